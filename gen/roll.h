/* roll.h - the rolled form of a large model (roll.c, emit_rolled.c).
 *
 * roll.c finds the repetition a model's index makes (variables x[N], sums
 * and comprehensions over i) in its derivatives: runs of items that are the
 * same expression up to a shift of the index. emit_rolled.c prints each run
 * once, as a loop over arrays, and the step's kernels around them as loops
 * (the banded multiplier system included). docs/rolled.md is the design. */
#ifndef ROLL_H
#define ROLL_H

#include "hbvmgen.h"

/* --rolled: EmitOptions.rolled */
enum { ROLL_OFF, ROLL_ON, ROLL_AUTO };

/* A family with more runs than this is not uniform in its index: not rolled. */
#define ROLL_MAX_RUNS 64
/* grad U in more runs than this: try U's terms as pair runs (roll_pair.c),
 * taken when they are fewer runs. */
#define ROLL_PAIR_TRY_RUNS 8
/* --rolled auto rolls a model whose straight-line sweep has at least this many
 * operations (docs/rolled.md, "Crossover": measured on the chain). */
#define ROLL_AUTO_OPS 4000
/* ... and whose derivatives it shortens this many times at least (items per run). */
#define ROLL_AUTO_COMPRESSION 8
/* A pair sum (roll_pair.c) is rolled by --rolled auto from this many items
 * on, in runs of ROLL_AUTO_COMPRESSION items or more on average, whatever
 * its sweep's operations (which the stage loop keeps from growing with the
 * pairs): docs/rolled.md, "Pair sums". The cluster of 8 diatomics has 30
 * (28 pairs of molecules, 2 of its trap), the cluster of 4 7; the rolled
 * cluster's step took 0.89-0.99 times the straight-line one's at N = 4-16
 * (alternated timings) and 1.2-1.3 times its instructions. */
#define ROLL_AUTO_PAIR_ITEMS 24
/* ... and is looked for (the model analysed) below ROLL_AUTO_OPS from this
 * many coordinates on (the cluster of 8), so that small models are not. */
#define ROLL_AUTO_PAIR_M 48
/* From this many coordinates on, --rolled auto decides without building the
 * straight-line step (whose dense nu x nu node matrices cost O(nu^2) time
 * and memory: 1.7 GB at the chain of 4000) and so without counting its
 * operations: a model of this size the rolled form covers, whose
 * derivatives it shortens ROLL_AUTO_COMPRESSION times, is rolled. (A sweep
 * under ROLL_AUTO_OPS operations would need fewer than 8 a coordinate.) */
#define ROLL_LEAN_M 512

/* One maximal run of items that are the same expression up to a shift of
 * the index: item u (u0 <= u < u0 + n) has the base index b0 + stride (u -
 * u0), and its expression is body[] (in post-order, the root last) with
 * each input at its offset from the base. */
typedef struct RollRun {
  int u0, n;
  int b0, stride;
  int *body, nbody;
} RollRun;

typedef struct {
  int nitems;
  RollRun *runs;
  int nruns;
  int zero;           /* every item is the constant 0 */
} RollFamily;

/* A family of derivative entries split for the step's Legendre projections:
 * the items affine in q are projected in closed form, as step.c does,
 * sum_l b_l P_j(c_l) f(Q_l) = delta_j0 f(q0) + f_lin(h (X gamma)_j), and only
 * the others (curved) are evaluated at the k stages. Each family has all the
 * items, 0 where an item belongs to another. */
typedef struct {
  RollFamily affine;  /* f, affine items */
  RollFamily lin;     /* f_lin(v) = sum_i df/dq_i v_i, v the second array, affine items */
  RollFamily curved;  /* f, the other items */
} RollSplit;

/* A pair sum of U rolled (roll_pair.c, docs/rolled.md "Pair sums"): a run
 * of items, each p consecutive terms of U, that is one double loop, b = B0,
 * B0 + SB, .. B1 and for each b c = b + D, b + D + SC, .. CE. body[] (post-
 * order, nbody places) is the first item's value and gradient; an input at
 * place k is q[b + off[k]] (base[k] = 0) or q[c + off[k]] (base[k] = 1); the
 * item's value is at place value, its gradient entry e at gplace[e], added
 * to grad U at b + goff[e] or c + goff[e] (gbase[e]). */
typedef struct {
  int nitems;
  int B0, B1, SB, D, CE, SC;
  int *body, nbody;
  int *base, *off;
  int value;
  int ngrad, *gplace, *gbase, *goff;
} RollPairRun;

typedef struct {
  int period, nitems, nruns; /* period: the largest of the runs' */
  RollPairRun *runs;
} RollPairs;

/* roll_pair.c: the terms of U (node U, m coordinates) as pair runs, or NULL
 * when they make more than ROLL_MAX_RUNS runs (or cannot be printed). */
RollPairs *roll_pairs(Dag *d, int m, int U);

/* The analysis emit_rolled.c prints from. Inputs of the families' nodes:
 * slots 0..m-1 are q (the array q), m..2m-1 are the second array (v). */
typedef struct Roll {
  int m, nu, T, bw;   /* T: most constraints on one coordinate; bw: the half band of G' M^-1 G */
  int *tcon;          /* m*T: the t-th constraint on coordinate i (increasing), -1 */
  int identity;       /* M = I */
  RollFamily gradU;   /* items i: dU/dq_i */
  RollFamily *jac;    /* T families, items i: d g_tcon[i,t] / dq_i, 0 where tcon is -1 */
  RollFamily g;       /* items a: g_a */
  RollFamily U;       /* items: the terms of U, summed in order */
  RollFamily hvv;     /* items a: v' Hess(g_a)(q) v */
  RollSplit gradU_s;  /* gradU, split for the projections */
  RollSplit *jac_s;   /* T of them: jac, split */
  int curved;         /* some entry is curved: the stages are evaluated */
  int lin;            /* some affine entry is not constant: h (X gamma)_j is needed */
  RollPairs *pairs;   /* U as pair runs, grad U scattered from them (gradU, gradU_s unused), or NULL */
  /* --iteration newton, auto (roll_newton.c): Hess U, row i's t-th structural nonzero
   * (t < ht) in family hess[t], at column hcol; in the Newton matrix's band (half band
   * hb) row i is row hpos[i] (NULL: i), the entry at hoff[i ht + t] from the row's
   * start (-1: none) */
  int hb, ht, *hoff, *hpos;
  RollFamily *hess;
  /* with constraints (the constant family): row i's t-th entry is Hess U's, or
   * lambda_a's share of Hess g_a (hlam[i ht + t] = a, else -1); the Newton system
   * with the multiplier is one real band (roll_newton.c, "the saddle point"): kn
   * rows, khb each side, coordinate i's s unknowns from row krow[i], constraint
   * a's row kcon[a], and hoff the entry's offset in its row's band (-1: none) */
  int *hlam, *krow, *kcon, kn, khb;
} Roll;

/* Choosing the form from eo->rolled. roll_plan says which step to build
 * first: 1 the layout (step_build_layout: --rolled on, or auto on a model
 * of ROLL_LEAN_M coordinates or more, which the form covers), 0 the
 * straight-line step. roll_choose then decides on that step (layout 1 for
 * the layout) and sets eo->roll (NULL: straight-line; after a layout the
 * caller then builds the straight-line step and calls it again). Returns 1
 * after an error (--rolled on for a model or options the rolled form does
 * not cover), else 0. */
int roll_plan(const Model *mod, const Method *me, const EmitOptions *eo);
int roll_choose(Model *mod, const Method *me, const Step *st, int layout, EmitOptions *eo);
/* The n items nodes[] (base[u] their base indices, or NULL: the lowest
 * coordinate each reads) split into runs (roll.c). Returns 0, or -1 when an
 * item cannot be printed or there are more than ROLL_MAX_RUNS runs. */
int roll_family(Dag *d, int m, RollFamily *f, const int *nodes, const int *base, int n);
/* roll_newton.c: Hess U (with constraints Hess(U + lambda' g)) as band
 * families into r->hb, r->hess, for the rolled Newton kernels; -1 with *why
 * set where the rolled form cannot (a pair sum, a band too wide, a diagonal
 * not uniform in the index). */
int roll_hessian(Model *mod, const Method *me, Roll *r, const char **why);
/* Mark (dag_reach) the nodes the rolled kernels print of the model. */
void roll_reach(const struct Roll *r, const Dag *d, unsigned char *mark);
#endif
