/* fuzz_frontend.c - libFuzzer harness over the generator's front end.
 *
 * Each input is a .ham model. It goes through the passes of gen/main.c:
 * diag_begin, parse_model, analyse, model_differentiate and
 * model_check_initial; for small models (few coordinates and constraints,
 * a small DAG) also method_auto_k, method_new, step_build and the emitters,
 * writing to /dev/null. The polynomial degree s (1..3) and the emitter's
 * options (--real float, --plain-sum) are taken from the input's length,
 * so all of them are exercised without changing the text.
 *
 * The generator ends the process with exit(1) when a model exceeds its
 * resource limits (arena size, MAX_NODES): that is its documented, clean
 * behaviour, not a bug. The harness is linked with
 *   -Wl,--wrap=exit,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free
 * so that such an exit inside the generator returns to the harness
 * (longjmp) instead of ending the fuzzer, and the heap blocks the generator
 * held at that moment (parser state, scratch arrays) are freed, so the
 * leak checker only reports real leaks. Anything else (a sanitizer report,
 * abort() from internal_error, a timeout) is a finding.
 *
 * Build and run: tests/fuzz/run.sh [SECONDS]. */
#include <setjmp.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "hbvmgen.h"

/* Limits of the models that also go through step_build and emission. */
#define FUZZ_MAX_M 8
#define FUZZ_MAX_NU 4
#define FUZZ_MAX_K 20        /* -k auto gives up to 2s + 12 = 18 for s <= 3 */
#define FUZZ_MAX_NODES 20000

/* ---- exit and heap interposition (see the comment at the top) ---- */

void __real_exit(int status) __attribute__((noreturn));
void *__real_malloc(size_t size);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t size);
void __real_free(void *p);

void __wrap_exit(int status) __attribute__((noreturn));
void *__wrap_malloc(size_t size);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t size);
void __wrap_free(void *p);

static jmp_buf escape;
static volatile int in_target;

/* The live heap blocks allocated while in_target: an open-addressing set
 * with tombstones. A full table stops tracking (an exit then leaks, which
 * the leak checker reports: no finding is hidden). */
#define LIVE_CAP (1 << 16)
#define TOMB ((void *)1)
static void *live[LIVE_CAP];
static size_t nlive_slots;

static size_t slot_of(const void *p) { return ((uintptr_t)p >> 4) * 2654435761u % LIVE_CAP; }

static void track(void *p) {
  if (!p || nlive_slots >= LIVE_CAP / 2) return;
  size_t i = slot_of(p);
  while (live[i] && live[i] != TOMB) i = (i + 1) % LIVE_CAP;
  if (!live[i]) nlive_slots++;
  live[i] = p;
}

static void untrack(void *p) {
  if (!p) return;
  for (size_t i = slot_of(p), n = 0; live[i] && n < LIVE_CAP; i = (i + 1) % LIVE_CAP, n++)
    if (live[i] == p) {
      live[i] = TOMB;
      return;
    }
}

/* Empty the set; free its blocks when release (after an exit). After a
 * normal run the blocks still held are leaks: they are left for the leak
 * checker to report. */
static void forget_all(int release) {
  if (!nlive_slots) return;
  for (size_t i = 0; i < LIVE_CAP; i++) {
    if (release && live[i] && live[i] != TOMB) __real_free(live[i]);
    live[i] = NULL;
  }
  nlive_slots = 0;
}

void __wrap_exit(int status) {
  if (in_target) longjmp(escape, 1);
  __real_exit(status);
}

void *__wrap_malloc(size_t size) {
  void *p = __real_malloc(size);
  if (in_target) track(p);
  return p;
}

void *__wrap_calloc(size_t n, size_t size) {
  void *p = __real_calloc(n, size);
  if (in_target) track(p);
  return p;
}

void *__wrap_realloc(void *p, size_t size) {
  void *q = __real_realloc(p, size);
  if (in_target && q) {
    untrack(p);
    track(q);
  }
  return q;
}

void __wrap_free(void *p) {
  if (in_target) untrack(p);
  __real_free(p);
}

/* ---- the passes ---- */

/* Build the step of a small analysed model and emit it to /dev/null, with
 * the options variant selects: bit 0 single precision (no driver then, as
 * gen/main.c requires), bit 1 plain summation, bit 2 the wide step. */
static void build_and_emit(Model *mod, int s, int variant) {
  static FILE *sink;
  const char *why;
  int k = method_auto_k(s, mod->degU, mod->degg, MULT_CONST, &why);
  if (mod->m > FUZZ_MAX_M || mod->nu > FUZZ_MAX_NU || k > FUZZ_MAX_K || mod->dag->n > FUZZ_MAX_NODES) return;
  const Method *me = method_new(k, s, MULT_CONST);
  Step *st = step_build(mod, me);
  if (!st) return;
  if (!sink && !(sink = fopen("/dev/null", "w"))) abort();
  int single = variant & 1;
  EmitOptions eo = {"fuzz", "fuzz.ham", single, !(variant & 2), (variant & 4) != 0};
  emit_solver(sink, sink, mod, me, st, &eo);
  if (!single) emit_driver(sink, mod, me, &eo);
}

/* One model: the passes of gen/main.c, then everything freed. */
static void run_model(const char *src, size_t len) {
  diag_begin("fuzz.ham", src, len);
  Stmt *prog = parse_model(src, len);
  Model *mod = diag_error_count() ? NULL : analyse("fuzz.ham", prog);
  if (!mod) return;
  model_differentiate(mod);
  model_check_initial(mod);
  build_and_emit(mod, 1 + (int)(len % 3), (int)(len / 3 % 8));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  int exited = 0;
  in_target = 1;
  if (!setjmp(escape)) run_model((const char *)data, size);
  else exited = 1;
  arena_free_all(); /* still in_target: the arena's blocks leave the set */
  in_target = 0;
  forget_all(exited);
  return 0;
}
