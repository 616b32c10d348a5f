/* emit_choice.c - what the model, method and options choose for the step.
 *
 * Predicates, no output: the step's order, which parts of the local error
 * need an estimate of their own (the constant multiplier's, the
 * quadrature's), and whether the adaptive step's iteration stops at its
 * tolerance. The scalar step (emit_step.c and the files it calls) and the
 * batch step (emit_batch*.c) both ask them, so they sit below both: neither
 * emitter calls the other for them. */
#include "emit.h"

// The order of the step in q and p: 2s, but 2 for the constant multiplier
// with constraints (docs/api.md).
int step_order(const Emitter *e) {
  return e->mod->nu && e->st->kern[K_FACTOR].nout == 0 ? 2 : 2 * e->me->s;
}

// Whether the step's error has a part NAME_err_est does not see: the
// constant multiplier with constraints at s >= 2 (order 2, not 2s), whose
// error comes from the multiplier's change over the step (NAME_mult_err).
// At s = 1 both families have order 2 = 2s.
int mult_err_wanted(const Emitter *e) { return step_order(e) < 2 * e->me->s; }

// Whether NAME_step_adaptive's iteration stops at its tolerance rather than
// at round-off (NAME_itol): the polynomial family, whose end of step restores
// H (the rescale) and the hidden constraint (the projection) whatever the
// iteration left, and g with Newton steps (emit_end_poly); not under
// --wide-step, whose iteration is in the wider type.
int itol_wanted(const Emitter *e) { return e->st->kern[K_FACTOR].nout > 0 && !e->wide_step && emit_has_sweeps(e); }

// Whether the constant family's end of the step rescales p1 to the run's
// energy H0 (emit_mq_rescale): always with M(q), whose H no k integrates
// exactly, and with --energy rescale (the default for an unconstrained
// model whose U is not a polynomial, at -k auto: docs/method-const.md). The
// iteration may then stop at 2 ulps (the contraction test, emit_iterate.c).
int energy_rescale_wanted(const Emitter *e) { return e->mod->mass_q || e->me->energy_rescale; }

// Whether the end of the step restores H, whatever the last ulps of the
// iteration: the polynomial family's projection and rescale (its multiplier
// factor), or the constant family's rescale. The iteration's tests differ
// by it (emit_iterate.c: the contraction test, or the round-off test).
int step_end_restores_energy(const Emitter *e) { return e->st->kern[K_FACTOR].nout > 0 || energy_rescale_wanted(e); }

// Whether the step's error estimate must take the quadrature's part from
// the energy defect: k nodes do not integrate H exactly for this model (U or
// g not polynomial, or k below -k auto), and no rescale restores H (the
// constant family, or no constraints).
int energy_defect_wanted(const Emitter *e) {
  return !e->st->kern[K_FACTOR].nout &&
         !method_quadrature_exact(e->me->k, e->me->s, e->mod->degU, e->mod->degg);
}
