/* main.c - the hbvmgen command line (docs/hbvmgen.1, docs/api.md).
 *
 * Reads the model, runs the passes in order (parse, analyse, differentiate,
 * choose k, build the step, emit) and writes NAME.h, NAME.c and optionally
 * NAME_main.c. Files are written under temporary names and renamed only
 * when everything succeeded, so an error never leaves a partial output
 * (see "writing the output" below). */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE /* flock */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "hbvmgen.h"
#include "roll.h"

#define MAX_MODEL_BYTES (64L << 20)
#define MAX_S 20
#define MAX_K 200
#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

#define STR_(x) #x
#define STR(x) STR_(x)

static const char usage[] =
    "usage: hbvmgen [options] MODEL.ham\n"
    "\n"
    "Generate a C solver (HBVM(k,s), line-integral method) for the constrained\n"
    "Hamiltonian system described in MODEL.ham.\n"
    "\n"
    "options:\n"
    "  -s S          degree of the polynomial approximation, 1 <= S <= 20 (default 2)\n"
    "  -k K|auto     Gauss-Legendre nodes, S <= K <= 200 (default auto: the smallest k that\n"
    "                conserves H and g exactly for polynomial models; s where the step\n"
    "                rescales p (--energy rescale, poly family); 2s+12 otherwise)\n"
    "  --energy E    auto, rescale or quadrature: how a model without constraints keeps\n"
    "                H at round-off. rescale: the end of each step rescales p to the\n"
    "                run's energy (k = s suffices); quadrature: k exact for H, or 2s+12\n"
    "                nodes where U is not a polynomial. auto (default): rescale where M\n"
    "                depends on q, or where U is not a polynomial and neither -k, --batch\n"
    "                nor --wide-step is given; quadrature otherwise (docs/method-const.md)\n"
    "  -o DIR        where NAME.c and NAME.h are written (default .: the current directory)\n"
    "  -n NAME       C prefix of every emitted symbol (default: the model file's base name)\n"
    "  --multiplier F  const or poly: how the Lagrange multiplier varies over a step.\n"
    "                const: constant, the paper's method, order 2 with constraints\n"
    "                (2s where the true multiplier is constant); poly: a polynomial of\n"
    "                degree s-1, then p projected onto the hidden constraint and rescaled\n"
    "                to the energy: order 2s. Default: poly for s >= 2 with constraints,\n"
    "                and always where M depends on q (const is refused there)\n"
    "  --iteration I auto, fixed or newton: how the step's equations are solved. fixed:\n"
    "                fixed-point sweeps, which converge while h omega < ~3 (omega the\n"
    "                fastest frequency of the linearised model); newton: simplified Newton\n"
    "                with the Hessian of U (+ lambda' g), for stiff models and long steps;\n"
    "                auto (default): fixed's code for a model that is not stiff at q0\n"
    "                (omega_fast / omega_slow < 75; rolled by auto from m = 512: the widest\n"
    "                gap between its frequencies < 75), else sweeps that hand over to Newton\n"
    "                where they are slow (--check says which). Newton: in both multiplier\n"
    "                families and with --batch (each lane the scalar step in turn), and\n"
    "                rolled (--rolled) where the Hessian of U (+ lambda' g) is a band;\n"
    "                not with --wide-step (docs/method-newton.md)\n";

/* (the rest of the usage, apart: a C99 compiler need not take a string over 4095 bytes) */
static const char usage_more[] =
    "  --main        also emit NAME_main.c, a standalone driver (link runtime/libhbvmrt.a)\n"
    "  --check       parse and analyse only; print m, nu, degrees and the chosen k, and the\n"
    "                size of the code it would write (nothing is written)\n"
    "  --real T      float or double (default): the type of the state, constants and\n"
    "                arithmetic of the generated code (float: for FPUs without double)\n"
    "  --plain-sum   update q, p, t by plain addition instead of compensated (Kahan)\n"
    "                summation: only to measure what compensation buys\n"
    "  --wide-step   iterate and update in the next wider type (long double, 80-bit on\n"
    "                x86-64, for double; double for float), from the compensated state,\n"
    "                rounding once into q, p: for runs of millions of steps, where the\n"
    "                round-off of a double step has a small bias that makes |H - H0|\n"
    "                drift (bench/README.md); 4-5x the step time, and no gain where\n"
    "                long double is double\n"
    "  --batch W     also emit NAME_batch_step: W trajectories (1 <= W <= 64) stepped\n"
    "                together in struct-of-arrays lanes that the compiler vectorises,\n"
    "                each lane bitwise equal to NAME_step, and NAME_batch_step_adaptive,\n"
    "                whose lanes share an error-controlled h (not with --wide-step; with\n"
    "                Newton, or M(q) and constraints, the lanes take the scalar step one\n"
    "                after another)\n"
    "  --mass-loop N  compute M^-1 v for a dense constant M as a loop over a table of\n"
    "                M^-1 when it takes N or more multiplications, straight-line code\n"
    "                below (default " STR(MASS_LOOP_DEFAULT) ": the measured crossover, docs/embedding.md)\n"
    "  --stage-loop N  print the k stages of the step as one loop over the stages (the\n"
    "                model's derivatives once, inside it) when their straight-line code\n"
    "                would take N or more operations (default " STR(STAGE_LOOP_DEFAULT) ", docs/embedding.md)\n"
    "  --rolled auto|on|off  print the model's index as loops (the rolled form,\n"
    "                docs/rolled.md): one loop body per run of uniform terms of U, g\n"
    "                and their derivatives, and the banded multiplier system as a loop\n"
    "                (both multiplier families, float, adaptive steps, dense output,\n"
    "                events and --batch, whose lanes run the rolled kernels one by one;\n"
    "                --iteration newton, the Newton matrix (with constraints and the\n"
    "                multiplier's rows) factored over its band);\n"
    "                auto (default) rolls a large model the form covers, on insists\n"
    "                (an error says what it does not cover yet), off never rolls\n"
    "  -h, --help    this text\n"
    "  --version     the version\n";

typedef struct {
  const char *model, *outdir, *name;
  int s, k; /* k = 0: auto */
  int emit_main, check_only;
  int single, plain_sum, wide_step;
  int multiplier; /* -1: default for s and the model; else a MultFamily */
  int batch;      /* --batch W, 0 without */
  long mass_loop; /* --mass-loop N, 0 for the default */
  long stage_loop; /* --stage-loop N, 0 for the default */
  int iteration;   /* --iteration: an IterKind */
  int rolled;      /* --rolled: ROLL_AUTO, ROLL_ON or ROLL_OFF */
  int energy;      /* --energy: an EnergyKind */
} Options;

/* --energy: how a model without constraints keeps H (resolve_energy) */
typedef enum { ENERGY_AUTO, ENERGY_RESCALE, ENERGY_QUADRATURE } EnergyKind;

static int fail(const char *fmt, const char *arg) {
  fprintf(stderr, "hbvmgen: error: ");
  fprintf(stderr, fmt, arg);
  fprintf(stderr, "\n");
  return 1;
}

static int parse_count(const char *s, int lo, int hi, int *out) {
  char *end;
  errno = 0;
  long v = strtol(s, &end, 10);
  if (!*s || *end || errno || v < lo || v > hi) return -1;
  *out = (int)v;
  return 0;
}

// Whether name cannot prefix the emitted symbols (said why, with the model
// file it comes from when it was not given with -n).
static int bad_name(const char *name, const char *file) {
  int ok = ((name[0] | 32) >= 'a' && (name[0] | 32) <= 'z') || name[0] == '_';
  for (const char *p = name; *p; p++)
    ok &= *p == '_' || (*p >= '0' && *p <= '9') || ((*p | 32) >= 'a' && (*p | 32) <= 'z');
  const char *why = !ok ? "is not a C identifier"
                    : name[0] == '_' ? "starts with '_' (such names are reserved in C)"
                    : !strcmp(name, "hbvmrt") || !strncmp(name, "hbvmrt_", 7) ? "is the prefix of the driver library"
                    : c_name_problem(name) ? c_name_problem(name) : NULL;
  if (!why) return 0;
  if (file)
    fprintf(stderr, "hbvmgen: error: the file name '%s' gives the C prefix '%s', which %s%s; pass -n NAME\n", file, name,
            ok && name[0] != '_' && strncmp(name, "hbvmrt", 6) ? "is " : "", why);
  else
    fprintf(stderr, "hbvmgen: error: -n needs a C prefix, but '%s' %s%s\n", name,
            ok && name[0] != '_' && strncmp(name, "hbvmrt", 6) ? "is " : "", why);
  return 1;
}

// Parse argv into o. Returns -1 to exit 0 (help, version), 1 on a usage
// error (already reported), 0 to go on.
static int parse_args(int argc, char **argv, Options *o) {
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int has_value = i + 1 < argc;
    if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
      fputs(usage, stdout);
      fputs(usage_more, stdout);
      return -1;
    } else if (!strcmp(a, "--version")) {
      printf("hbvmgen %s\n", HBVMGEN_VERSION);
      return -1;
    } else if (!strcmp(a, "--main")) {
      o->emit_main = 1;
    } else if (!strcmp(a, "--check")) {
      o->check_only = 1;
    } else if (!strcmp(a, "--plain-sum")) {
      o->plain_sum = 1;
    } else if (!strcmp(a, "--wide-step")) {
      o->wide_step = 1;
    } else if (!strcmp(a, "--multiplier")) {
      if (!has_value) return fail("option %s needs a value", a);
      const char *v = argv[++i];
      if (strcmp(v, "const") && strcmp(v, "poly")) return fail("--multiplier needs 'const' or 'poly', got '%s'", v);
      o->multiplier = !strcmp(v, "poly") ? MULT_POLY : MULT_CONST;
    } else if (!strcmp(a, "--iteration")) {
      if (!has_value) return fail("option %s needs a value", a);
      const char *v = argv[++i];
      if (strcmp(v, "fixed") && strcmp(v, "newton") && strcmp(v, "auto"))
        return fail("--iteration needs 'auto', 'fixed' or 'newton', got '%s'", v);
      o->iteration = !strcmp(v, "newton") ? ITER_NEWTON : !strcmp(v, "auto") ? ITER_AUTO : ITER_FIXED;
    } else if (!strcmp(a, "--energy")) {
      if (!has_value) return fail("option %s needs a value", a);
      const char *v = argv[++i];
      if (strcmp(v, "auto") && strcmp(v, "rescale") && strcmp(v, "quadrature"))
        return fail("--energy needs 'auto', 'rescale' or 'quadrature', got '%s'", v);
      o->energy = !strcmp(v, "rescale") ? ENERGY_RESCALE : !strcmp(v, "quadrature") ? ENERGY_QUADRATURE : ENERGY_AUTO;
    } else if (!strcmp(a, "--rolled")) {
      if (!has_value) return fail("option %s needs a value", a);
      const char *v = argv[++i];
      if (strcmp(v, "auto") && strcmp(v, "on") && strcmp(v, "off")) return fail("--rolled needs 'auto', 'on' or 'off', got '%s'", v);
      o->rolled = !strcmp(v, "on") ? ROLL_ON : !strcmp(v, "off") ? ROLL_OFF : ROLL_AUTO;
    } else if (!strcmp(a, "--real")) {
      if (!has_value) return fail("option %s needs a value", a);
      const char *v = argv[++i];
      if (strcmp(v, "float") && strcmp(v, "double")) return fail("--real needs 'float' or 'double', got '%s'", v);
      o->single = !strcmp(v, "float");
    } else if (!strcmp(a, "--mass-loop") || !strcmp(a, "--stage-loop")) {
      if (!has_value) return fail("option %s needs a value", a);
      int n;
      if (parse_count(argv[++i], 1, 1 << 30, &n)) {
        fprintf(stderr, "hbvmgen: error: %s needs an integer from 1 to 2^30, got '%s'\n", a, argv[i]);
        return 1;
      }
      *(a[2] == 'm' ? &o->mass_loop : &o->stage_loop) = n;
    } else if (!strcmp(a, "--batch")) {
      if (!has_value) return fail("option %s needs a value", a);
      if (parse_count(argv[++i], 1, 64, &o->batch)) return fail("--batch needs an integer from 1 to 64, got '%s'", argv[i]);
    } else if (!strcmp(a, "-s") || !strcmp(a, "-k") || !strcmp(a, "-o") || !strcmp(a, "-n")) {
      if (!has_value) return fail("option %s needs a value", a);
      const char *v = argv[++i];
      if (a[1] == 's' && parse_count(v, 1, MAX_S, &o->s)) return fail("-s needs an integer from 1 to 20, got '%s'", v);
      if (a[1] == 'k' && strcmp(v, "auto") && parse_count(v, 1, MAX_K, &o->k))
        return fail("-k needs 'auto' or an integer from 1 to 200, got '%s'", v);
      if (a[1] == 'k' && !strcmp(v, "auto")) o->k = 0;
      if (a[1] == 'o') o->outdir = v;
      if (a[1] == 'n') o->name = v;
    } else if (a[0] == '-' && a[1]) {
      return fail("unknown option '%s' (see hbvmgen --help)", a);
    } else if (o->model) {
      return fail("more than one model file given ('%s')", a);
    } else {
      o->model = a;
    }
  }
  if (!o->model) return fail("%s", "no model file given (see hbvmgen --help)");
  if (o->k && o->k < o->s) {
    char buf[64];
    snprintf(buf, sizeof buf, "k=%d < s=%d", o->k, o->s);
    return fail("-k must be at least -s (%s)", buf);
  }
  if (o->batch && o->wide_step) return fail("%s", "--batch cannot be used with --wide-step (long double does not vectorise)");
  if (o->energy == ENERGY_RESCALE && (o->batch || o->wide_step))
    return fail("--energy rescale cannot be used with %s (not yet: its step has no rescale)",
                o->batch ? "--batch" : "--wide-step");
  if (o->iteration == ITER_NEWTON && o->wide_step)
    return fail("%s", "--iteration newton cannot be used with --wide-step (not yet)");
  if (o->iteration == ITER_NEWTON && o->s > NEWTON_MAX_S) {
    char buf[64];
    snprintf(buf, sizeof buf, "s=%d > %d", o->s, NEWTON_MAX_S);
    return fail("--iteration newton needs a smaller -s (%s)", buf);
  }
  if (o->name && bad_name(o->name, NULL)) return 1;
  return 0;
}

// The C prefix from the model's file name: its base name without .ham,
// with characters that cannot appear in a C identifier replaced by '_'.
static const char *default_name(const char *path) {
  const char *base = strrchr(path, '/');
  base = base ? base + 1 : path;
  size_t n = strlen(base);
  if (n > 4 && !strcmp(base + n - 4, ".ham")) n -= 4;
  char *name = arena_alloc(n + 6);
  size_t j = 0;
  if (n == 0) strcpy(name, "model"), j = 5;
  else if (base[0] >= '0' && base[0] <= '9') name[j++] = 'm';
  for (size_t i = 0; i < n; i++) {
    char c = base[i];
    int ok = c == '_' || (c >= '0' && c <= '9') || ((c | 32) >= 'a' && (c | 32) <= 'z');
    name[j++] = ok ? c : '_';
  }
  return name;
}

// Say so when the prefix default_name made of the file name at path is not
// its base name as written (my-model.ham gives my_model, 2d.ham m2d).
static void note_renamed(const char *path, const char *name) {
  const char *base = strrchr(path, '/');
  base = base ? base + 1 : path;
  size_t n = strlen(base);
  if (n > 4 && !strcmp(base + n - 4, ".ham")) n -= 4;
  if (strlen(name) != n || strncmp(base, name, n))
    fprintf(stderr, "hbvmgen: note: the emitted symbols of '%s' take the prefix '%s': '%.*s' is not a C identifier "
            "(-n NAME chooses another)\n", path, name, (int)n, base);
}

static char *read_file(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "hbvmgen: error: cannot open '%s': %s\n", path, strerror(errno));
    return NULL;
  }
  char *buf = NULL;
  size_t n = 0, cap = 0;
  for (;;) {
    if (n == cap) {
      cap = cap ? 2 * cap : 65536;
      if ((long)cap > MAX_MODEL_BYTES + 65536) {
        fprintf(stderr, "hbvmgen: error: '%s' is larger than %ld MiB\n", path, MAX_MODEL_BYTES >> 20);
        free(buf);
        fclose(f);
        return NULL;
      }
      buf = xrealloc(buf, cap);
    }
    size_t got = fread(buf + n, 1, cap - n, f);
    n += got;
    if (got == 0) break;
  }
  int err = ferror(f);
  fclose(f);
  if (err) {
    fprintf(stderr, "hbvmgen: error: cannot read '%s'\n", path);
    free(buf);
    return NULL;
  }
  *len = n;
  return buf;
}

static const char *deg_str(int deg, char *buf) {
  if (deg == DEG_NONPOLY) return "nonpoly";
  snprintf(buf, 16, "%d", deg);
  return buf;
}

static const char *mass_str(MassKind k) {
  switch (k) {
  case MASS_IDENTITY: return "identity";
  case MASS_SCALAR: return "scalar multiple of the identity";
  case MASS_DIAG: return "diagonal";
  case MASS_DENSE: return "dense (products with its precomputed inverse)";
  }
  return "?";
}

// --check's lines on the switching functions (none for a smooth model):
// their number, then each one's function, kind and value at q0 (default params).
static void print_switches(const Model *mod, const char *name) {
  if (!mod->nswitch) return;
  double *prm = xmalloc((size_t)(mod->nparams + 1) * sizeof *prm), *v = xmalloc((size_t)mod->nswitch * sizeof *v);
  for (int i = 0; i < mod->nparams; i++) prm[i] = mod->params[i].value;
  dag_eval_many(mod->dag, mod->switch_nodes, mod->nswitch, mod->q0, prm, v);
  printf("switching functions: %d (%s_switch): %s not smooth where they change sign; the driver ends a step on "
         "each such point and restarts there (--no-switch: off)\n", mod->nswitch, name,
         mod->switch_in_U ? "U" : "g");
  for (int i = 0; i < mod->nswitch; i++)
    printf("switch %d: %s, %s, %.6g at q0\n", i + 1, mod->switch_what[i],
           mod->switch_kinds[i] == SWITCH_INTEGER ? "jumps where it crosses an integer" : "kink or jump at 0",
           v[i] == 0 ? 0.0 : v[i]); /* (no -0) */
  free(prm);
  free(v);
}

static void print_check(const Model *mod, const Options *o, int k, const char *why, MultFamily fam,
                        const char *iter_why, int rescale) {
  char a[16], b[16];
  printf("model %s: m=%d nu=%d deg(U)=%s deg(g)=%s k=%d s=%d\n", o->name, mod->m, mod->nu, deg_str(mod->degU, a),
         deg_str(mod->degg, b), k, o->s);
  printf("k: %s\n", o->k ? "given with -k" : why);
  if (!mod->nu)
    printf("multiplier: none (no constraints): order %d\n", 2 * o->s);
  else if (fam == MULT_POLY)
    printf("multiplier: poly (degree %d, projection and energy rescale): order %d in q, p and lambda\n", o->s - 1,
           o->s >= 2 ? 2 * o->s : 2);
  else if (o->s >= 2) /* measured: docs/api.md, "The local error estimate" */
    printf("multiplier: const (the paper's method): order 2 in p (across the hidden constraint), 4 in q, 1 in lambda "
           "(%d where the true multiplier is constant)\n", 2 * o->s);
  else
    printf("multiplier: const (the paper's method): order 2 in q and p, 1 in lambda\n");
  if (o->iteration == ITER_NEWTON)
    printf("iteration: newton (simplified Newton, the Newton matrix factored and kept across steps while it contracts "
           "fast, docs/method-newton.md)\n");
  else
    printf("iteration: %s\n", iter_why);
  if (mod->mass_q) mass_q_report(stdout, mod);
  else if (!mod->minv_node) printf("M: constant, %s\n", mass_str(mod->mass));
  else
    printf("M: with params (constant in q): %s, computed from them in every kernel call\n",
           mod->mass_L ? "dense, M^-1 v by its L D L' factors" : "diagonal, M^-1 = 1/M_ii");
  long nnz = 0;
  for (int a2 = 0; a2 < mod->nu; a2++) nnz += mod->jac[a2].n;
  if (mod->nu)
    printf("Jacobian of g: %ld structural nonzeros of %ld (%.0f%%)\n", nnz, (long)mod->m * mod->nu,
           100.0 * nnz / ((double)mod->m * mod->nu));
  int ngrad = 0;
  for (int i = 0; i < mod->m; i++) ngrad += !dag_is_zero(mod->dag, mod->gradU[i]);
  printf("grad U: %d nonzero entries of %d\n", ngrad, mod->m);
  for (int i = 0; i < mod->nparams; i++) printf("param %s = %.17g\n", mod->params[i].name, mod->params[i].value);
  print_switches(mod, o->name);
  method_advise(stdout, mod, o->s, k, fam, rescale);
}

/* ---- writing the output ----
 *
 * Each file is first written to a temporary DIR/.NAME.h.XXXXXX created by
 * mkstemp (exclusively, with an unpredictable name: a planted symlink is
 * never followed). Only when all are complete are they renamed into place,
 * under an exclusive lock on DIR so that two runs cannot interleave; an
 * existing file is first moved to a backup, and if any rename fails, the
 * files already replaced are put back, so DIR holds either the old set or
 * the new one, never a mix. Every temporary is registered and removed on
 * every exit path (atexit covers the fatal ones). Messages name the user's
 * paths, never a temporary. */

enum { H, C, MAIN, NFILES };

static char *tmp_path[2 * NFILES]; /* temporaries and backups to remove at exit */

static void remove_temporaries(void) {
  for (int i = 0; i < 2 * NFILES; i++)
    if (tmp_path[i]) {
      unlink(tmp_path[i]);
      free(tmp_path[i]);
      tmp_path[i] = NULL;
    }
}

// Keep path (a temporary that is no longer ours to remove).
static void forget(int slot) {
  free(tmp_path[slot]);
  tmp_path[slot] = NULL;
}

// DIR/NAME+suffix, or NULL after an error naming it when it (or its
// temporary, 8 bytes longer) would be longer than the system allows.
static char *output_path(const char *dir, const char *name, const char *suffix) {
  size_t n = strlen(dir) + 1 + strlen(name) + strlen(suffix);
  char *p = xmalloc(n + 1);
  snprintf(p, n + 1, "%s/%s%s", dir, name, suffix);
  if (n + 8 >= PATH_MAX) {
    fprintf(stderr, "hbvmgen: error: cannot write '%s': the path is too long (%zu bytes, at most %d)\n", p, n,
            PATH_MAX - 9);
    free(p);
    return NULL;
  }
  return p;
}

// mkdir -p dir. Returns 0, or 1 after an error naming dir.
static int make_dir(const char *dir) {
  char *path = xmalloc(strlen(dir) + 1);
  strcpy(path, dir);
  int rc = 0;
  for (char *p = path + (path[0] == '/');; p++) {
    if (*p != '/' && *p) continue;
    char saved = *p;
    *p = '\0';
    if (mkdir(path, 0777) && errno != EEXIST) {
      fprintf(stderr, "hbvmgen: error: cannot create the output directory '%s'%s%s%s: %s\n", dir,
              saved ? " ('" : "", saved ? path : "", saved ? "')" : "", strerror(errno));
      rc = 1;
      break;
    }
    *p = saved;
    if (!saved) break;
  }
  struct stat st;
  if (!rc && stat(dir, &st)) {
    fprintf(stderr, "hbvmgen: error: cannot use the output directory '%s': %s\n", dir, strerror(errno));
    rc = 1;
  } else if (!rc && !S_ISDIR(st.st_mode)) {
    fprintf(stderr, "hbvmgen: error: the output directory '%s' is not a directory\n", dir);
    rc = 1;
  }
  free(path);
  return rc;
}

// A new empty file DIR/.NAME+suffix.XXXXXX beside final, registered in
// slot. Returns its descriptor, or -1 after an error naming final.
static int make_temporary(const char *dir, const char *name, const char *suffix, const char *final, int slot) {
  size_t n = strlen(dir) + strlen(name) + strlen(suffix) + 10;
  char *path = xmalloc(n);
  snprintf(path, n, "%s/.%s%s.XXXXXX", dir, name, suffix);
  int fd = mkstemp(path);
  if (fd < 0) {
    fprintf(stderr, "hbvmgen: error: cannot write '%s': %s\n", final, strerror(errno));
    free(path);
    return -1;
  }
  tmp_path[slot] = path;
  return fd;
}

// Move each of the n new files tmp_path[i] to final[i], backing up what was
// there; on a failure put everything back. Returns 0; 1 when nothing was
// changed; 2 when the old files could not all be restored (said how).
static int install(const char *dir, const char *name, char *const *final, const char *const *suffix, int n) {
  struct stat st;
  int dfd = open(dir, O_RDONLY);
  if (dfd >= 0) flock(dfd, LOCK_EX); /* serialises concurrent runs into dir */
  int placed = 0, rc = 0;
  char *bak[NFILES] = {NULL, NULL, NULL};
  for (; placed < n; placed++) {
    if (!lstat(final[placed], &st)) {
      if (S_ISDIR(st.st_mode)) {
        fprintf(stderr, "hbvmgen: error: cannot write '%s': it is a directory\n", final[placed]);
        rc = 1;
        break;
      }
      int fd = make_temporary(dir, name, suffix[placed], final[placed], NFILES + placed);
      if (fd < 0) {
        rc = 1;
        break;
      }
      close(fd);
      if (rename(final[placed], tmp_path[NFILES + placed])) {
        fprintf(stderr, "hbvmgen: error: cannot replace '%s': %s\n", final[placed], strerror(errno));
        rc = 1;
        break;
      }
      bak[placed] = tmp_path[NFILES + placed];
      tmp_path[NFILES + placed] = NULL; /* the user's file now: removed only once replaced */
    }
    if (rename(tmp_path[placed], final[placed])) {
      fprintf(stderr, "hbvmgen: error: cannot write '%s': %s\n", final[placed], strerror(errno));
      rc = 1;
      placed++; /* its backup, if any, is restored below */
      break;
    }
    forget(placed);
  }
  for (int i = placed - 1; rc && i >= 0; i--) { /* put back what was there, newest first */
    if (tmp_path[i] && !bak[i]) continue; /* never placed, nothing moved */
    if (bak[i] ? rename(bak[i], final[i]) : unlink(final[i])) {
      fprintf(stderr, "hbvmgen: error: cannot restore '%s'%s%s%s: %s\n", final[i],
              bak[i] ? " (the old file is kept as '" : "", bak[i] ? bak[i] : "", bak[i] ? "')" : "", strerror(errno));
      rc = 2;
    }
    free(bak[i]);
    bak[i] = NULL;
  }
  for (int i = 0; i < NFILES; i++)
    if (bak[i]) {
      unlink(bak[i]);
      free(bak[i]);
    }
  if (dfd >= 0) close(dfd); /* releases the lock */
  return rc;
}

// NAME.c from this size on gets a note: compiling it takes a while. Measured
// with gcc 12 -O2 on x86-64 (docs/embedding.md, "Large models"): chains of
// 100, 200, 400 and 1000 constrained coordinates, 1.8, 3.8, 7.9 and 19.7 MB of
// C, took 12, 30, 80 and 200 s and 0.34, 0.40, 0.44 and 3.2 GB.
#define LARGE_C_BYTES 4000000L /* 4 MB */
// From this size on NAME.c is refused (nothing is written): at 19.7 MB gcc
// took 200 s and 3.2 GB, and the 124 MB of variables x[100000] none finished.
#define MAX_C_BYTES 32000000L /* 32 MB */

// The note on a large NAME.c at path (nothing when it is smaller, or when it
// cannot be read back: it was just written).
static void note_large_output(const char *path) {
  struct stat sb;
  if (stat(path, &sb) || sb.st_size < LARGE_C_BYTES) return;
  fprintf(stderr,
          "hbvmgen: note: '%s' is %.1f MB of C: compilers take minutes and gigabytes on a file this size "
          "(gcc -O2: 30 s and 0.4 GB at 3.8 MB, 200 s and 3.2 GB at 19.7 MB; --stage-loop and --mass-loop "
          "shrink what they can, docs/embedding.md, \"Large models\"; a model uniform in its index is a few "
          "loops with --rolled, docs/rolled.md)\n",
          path, (double)sb.st_size / 1e6);
}

// What the emitter takes of the options.
static EmitOptions emit_options(const Options *o) {
  EmitOptions eo = {o->name, strrchr(o->model, '/') ? strrchr(o->model, '/') + 1 : o->model, o->single,
                    !o->plain_sum, o->wide_step, o->batch, o->rolled, NULL};
  return eo;
}

/* --iteration auto emits the straight-line Newton only up to this m: its
 * factorisation is unrolled (m^3 operations for a dense Hessian; tests/
 * check_lean.c's dense chain of m = 160 would have taken more than 4 MB of C).
 * Above, auto emits Newton where the rolled form's band loops take it
 * (rolled_newton_candidate; docs/rolled.md, "Newton"), and there the
 * frequencies must split: a long chain's omega_fast / omega_slow grows like
 * m whether it is stiff or not, so the ratio across the widest gap between
 * consecutive frequencies decides (the FPU chain of 500 pairs at omega =
 * 1000: 1e3 and more; a chain of equal soft springs: 2). */
#define AUTO_NEWTON_MAX_M 32

static Step *build_step(Model *mod, Method *me, EmitOptions *eo);

// Whether auto's Newton counts on the rolled form: above AUTO_NEWTON_MAX_M
// (rolled_newton_candidate), where the straight-line factorisation would
// be unrolled.
static int newton_needs_roll(const Model *mod, const Method *me) {
  return me->iteration == ITER_AUTO && mod->m > AUTO_NEWTON_MAX_M;
}

// The fixed-point step where auto chose Newton for the rolled form and the
// form did not take the model, with a note.
static Step *fixed_after_all(Model *mod, Method *me, EmitOptions *eo) {
  fprintf(stderr, "hbvmgen: note: --iteration auto: the rolled form does not take this model's Newton matrix "
                  "(docs/rolled.md, \"What the rolled form covers\"): the step is the fixed-point one\n");
  me->iteration = ITER_FIXED;
  return build_step(mod, me, eo);
}

// The step to emit, with the form chosen (roll.h) into eo->roll: the
// rolled form's layout (step_build_layout) where roll_plan tries it first
// and roll_choose takes it, else the straight-line step. Where auto chose
// Newton for the rolled form (rolled_newton_candidate) and the form is not
// taken, me->iteration falls back to ITER_FIXED (fixed_after_all). NULL
// after an error.
static Step *build_step(Model *mod, Method *me, EmitOptions *eo) {
  if (roll_plan(mod, me, eo)) {
    Step *lay = step_build_layout(mod, me);
    if (!lay || roll_choose(mod, me, lay, 1, eo)) return NULL;
    if (eo->roll) return lay;
  }
  if (newton_needs_roll(mod, me)) return fixed_after_all(mod, me, eo); /* before the unrolled Newton is built */
  Step *st = step_build(mod, me);
  if (!st || roll_choose(mod, me, st, 0, eo)) return NULL;
  /* the poly family's rolled factor, and the Newton matrix's, are bands: their layout is
   * not the straight-line one */
  return eo->roll && ((me->family == MULT_POLY && mod->nu) || me->iteration != ITER_FIXED) ? step_build_layout(mod, me)
                                                                                            : st;
}

// --check's last line: the code the options would write, emitted into
// temporary files and thrown away: the size of NAME.c (and of NAME.h), and
// whether the k stages are straight-line code or one loop (--stage-loop).
// Returns 1 when the step cannot be emitted (the reason reported), else 0;
// without a temporary file the line says so and the status stays 0.
static int print_check_code(const Options *o, Model *mod, int k, MultFamily fam, IterKind iter, int rescale) {
  Method *me = method_new(k, o->s, fam);
  me->iteration = iter;
  me->energy_rescale = rescale;
  EmitOptions eo = emit_options(o);
  Step *st = build_step(mod, me, &eo);
  if (!st || emit_check(mod, st, &eo)) return 1;
  FILE *h = tmpfile(), *c = tmpfile();
  if (!h || !c || emit_solver(h, c, mod, me, st, &eo) != 0) /* the analysis stands; only the size is missing */
    printf("code: not measured (no temporary file: %s)\n", strerror(errno));
  else
    printf("code: %s.c %.2f MB, %s.h %ld bytes; the %d stages %s\n", o->name, (double)ftell(c) / 1e6, o->name,
           ftell(h), k, mod->dag->nloops ? "as one loop (--stage-loop)" : "in straight-line code");
  if (h) fclose(h);
  if (c) fclose(c);
  return 0;
}

// Emit the solver files; all or nothing.
static int write_outputs(const Options *o, Model *mod, Method *me) {
  const char *suffix[NFILES] = {".h", ".c", "_main.c"};
  char *final[NFILES] = {NULL, NULL, NULL};
  FILE *f[NFILES] = {NULL, NULL, NULL};
  EmitOptions eo = emit_options(o);
  Step *st = build_step(mod, me, &eo);
  if (!st || emit_check(mod, st, &eo)) return 1; /* nothing is written yet */
  int nfiles = o->emit_main ? 3 : 2, rc = make_dir(o->outdir);
  atexit(remove_temporaries);
  mode_t mask = umask(0);
  umask(mask);
  for (int i = 0; i < nfiles && !rc; i++) {
    int fd = -1;
    if (!(final[i] = output_path(o->outdir, o->name, suffix[i])) ||
        (fd = make_temporary(o->outdir, o->name, suffix[i], final[i], i)) < 0) {
      rc = 1;
    } else if (fchmod(fd, 0666 & ~mask) || !(f[i] = fdopen(fd, "w"))) {
      fprintf(stderr, "hbvmgen: error: cannot write '%s': %s\n", final[i], strerror(errno));
      close(fd);
      rc = 1;
    }
  }
  int emitted = rc ? 0 : emit_solver(f[H], f[C], mod, me, st, &eo) == 0;
  if (emitted && o->emit_main) emitted = emit_driver(f[MAIN], mod, me, &eo) == 0;
  long csize = f[C] ? ftell(f[C]) : 0;
  if (!rc && emitted && csize > MAX_C_BYTES) {
    fprintf(stderr,
            "hbvmgen: error: '%s' would be %.1f MB of C, above the %.0f MB no compiler handles in reasonable time "
            "(gcc -O2: 200 s and 3.2 GB at 19.7 MB); --stage-loop N and --mass-loop N roll the stages and M^-1 "
            "into loops where they can (docs/embedding.md, \"Large models\"), --rolled the model's index "
            "(docs/rolled.md)\n",
            final[C], (double)csize / 1e6, MAX_C_BYTES / 1e6);
    rc = 2; /* reported: no second message */
  }
  for (int i = 0; i < nfiles; i++) {
    if (!f[i]) continue;
    int bad = ferror(f[i]), err = errno;
    if (fclose(f[i])) bad = 1, err = errno;
    if (bad && !rc) {
      fprintf(stderr, "hbvmgen: error: cannot write '%s': %s\n", final[i], strerror(err));
      rc = 1;
    }
  }
  if (!rc && !emitted) {
    fprintf(stderr, "hbvmgen: error: cannot write the output\n");
    rc = 1;
  }
  if (!rc) rc = install(o->outdir, o->name, final, suffix, nfiles);
  if (!rc) note_large_output(final[C]);
  remove_temporaries();
  for (int i = 0; i < nfiles; i++) free(final[i]);
  if (rc == 1) fprintf(stderr, "hbvmgen: error: writing the output failed; no file in '%s' was changed\n", o->outdir);
  return rc != 0;
}

#define FLOAT_POLY_MAX_S 7 /* the largest s of the poly family in float */

// Report that the degree of U or of a constraint needs k > MAX_K, at the
// statement (U) or list element (g) that has it.
static void report_degree(const Model *mod, int s, int k) {
  const char *why;
  int best = -1;
  if (mod->degU == DEG_NONPOLY || method_auto_k(s, mod->degU, 0, MULT_CONST, &why) <= MAX_K)
    for (int a = 0; a < mod->nu; a++)
      if (best < 0 || mod->dag->nodes[mod->g[a]].deg > mod->dag->nodes[mod->g[best]].deg) best = a;
  error_at(best < 0 ? mod->U_loc : mod->g_loc[best],
           "%s has degree %d: the quadrature exact for it needs k=%d > %d Gauss nodes; pass -k",
           best < 0 ? "U" : "this constraint", best < 0 ? mod->degU : mod->degg, k, MAX_K);
}

/* --iteration auto: a model is stiff where omega_fast / omega_slow of its
 * linearisation at q0 (stiffness.c) is at least this. The fixed-point sweep
 * converges while h omega_fast < ~3; a step that follows the slow motion
 * accurately has h omega_slow of about 0.04 (HBVM(k,2): a relative error of
 * order 1e-7 a period), so above 3 / 0.04 = 75 the sweep, not accuracy,
 * sets h. The paper's models are at most 56 (satellites), the stiff bob at
 * k = 1e4 is 107, the FPU chain 47 at omega = 50 and 945 at omega = 1000. */
#define STIFF_RATIO 75

// Whether auto may emit Newton on a model above AUTO_NEWTON_MAX_M: where
// --rolled auto tries the rolled form first (roll_plan: from ROLL_LEAN_M)
// and it covers Newton (no constraints, a constant diagonal M). build_step
// falls back to the fixed-point step where the form is not taken after all
// (a pair sum's full Hessian, a band over 16). Not below ROLL_LEAN_M, where
// --rolled auto decides on the straight-line step, and building that step
// with Newton is what must not happen (a dense Hessian of m = 120 exceeds
// the node limit); not with --rolled on, which makes a Newton matrix the
// form cannot take an error (as up to m = 32).
static int rolled_newton_candidate(const Options *o, const Model *mod) {
  return !mod->nu && !mod->mass_q && !mod->minv_node && mod->mass != MASS_DENSE && !o->wide_step &&
         o->s <= NEWTON_MAX_S && o->rolled == ROLL_AUTO && mod->m >= ROLL_LEAN_M;
}

// What --iteration resolves to: fixed and newton as given; auto (the
// default) ITER_AUTO (sweeps first, Newton where they are slow) for a stiff
// model where Newton can be emitted, else ITER_FIXED, today's code. why
// receives --check's line (after "iteration: ").
static IterKind resolve_iteration(const Options *o, const Model *mod, char *why, size_t n) {
  if (o->iteration == ITER_FIXED) {
    snprintf(why, n, "fixed (fixed-point sweeps, given with --iteration fixed)");
    return ITER_FIXED;
  }
  if (o->iteration == ITER_NEWTON) return ITER_NEWTON;
  Frequencies f;
  double r = model_stiffness(mod, &f);
  if (r > 0 && rolled_newton_candidate(o, mod)) { /* (m >= ROLL_LEAN_M > AUTO_NEWTON_MAX_M) */
    double gap = f.gap_above / f.gap_below;
    if (gap < STIFF_RATIO)
      snprintf(why, n, "auto: fixed (fixed-point sweeps; not stiff: the widest gap between the frequencies at q0 is "
               "%.3g / %.3g = %.3g < %d; omega_fast / omega_slow = %.3g, wide without a gap)",
               f.gap_above, f.gap_below, gap, STIFF_RATIO, r);
    else
      snprintf(why, n, "auto: sweeps, then newton where they contract slowly, in the rolled form's band loops (stiff: "
               "the frequencies at q0 split at %.3g / %.3g = %.3g >= %d; docs/rolled.md, \"Newton\")",
               f.gap_above, f.gap_below, gap, STIFF_RATIO);
    return gap < STIFF_RATIO ? ITER_FIXED : ITER_AUTO;
  }
  const char *no = mod->mass_q                ? "Newton does not handle an M that depends on q"
                   : o->wide_step              ? "Newton is not emitted with --wide-step"
                   : o->s > NEWTON_MAX_S       ? "Newton needs s <= " STR(NEWTON_MAX_S)
                   : mod->m > AUTO_NEWTON_MAX_M ? "auto emits Newton up to m = " STR(AUTO_NEWTON_MAX_M)
                                                  " (its factorisation is unrolled: --iteration newton), and above "
                                                  "on a model without constraints that --rolled auto rolls (m >= 512)"
                                               : NULL;
  if (r == 0)
    snprintf(why, n, "auto: fixed (fixed-point sweeps; stiffness not estimated: %s)",
             mod->mass_q ? "M depends on q" : mod->minv_node ? "M has params"
             : !model_stiffness_estimated(mod) ? "m > 200, or m > 1200 without constraints and with a diagonal M"
                                               : "no nonzero frequency at q0");
  else if (r < STIFF_RATIO)
    snprintf(why, n, "auto: fixed (fixed-point sweeps; not stiff: omega_fast / omega_slow = %.3g / %.3g = %.3g < %d "
             "at q0)", f.fast, f.slow, r, STIFF_RATIO);
  else if (no)
    snprintf(why, n, "auto: fixed (fixed-point sweeps, converging while h < ~3 / %.3g; stiff, omega_fast / omega_slow "
             "= %.3g >= %d at q0, but %s)", f.fast, r, STIFF_RATIO, no);
  else
    snprintf(why, n, "auto: sweeps, then newton where they contract slowly (stiff: omega_fast / omega_slow = %.3g / "
             "%.3g = %.3g >= %d at q0; docs/method-newton.md)", f.fast, f.slow, r, STIFF_RATIO);
  return r >= STIFF_RATIO && !no ? ITER_AUTO : ITER_FIXED;
}

// Whether the end of the step rescales p1 to the run's energy (--energy;
// Method.energy_rescale, emit_mq_rescale). Only without constraints (with
// them the poly family rescales and projects, the const family keeps the
// quadrature) and never with --batch or --wide-step. auto rescales where U
// is not a polynomial and -k is not given: k = s then keeps H at round-off
// at 1/3 of the 2s+12 nodes' cost (docs/method-const.md), while a given -k
// keeps the quadrature of its nodes, byte for byte as before --energy. M(q)
// always rescales (no k integrates its H). Returns 1 to rescale, 0 not, -1
// after an error.
static int resolve_energy(const Options *o, const Model *mod) {
  if (o->energy != ENERGY_AUTO && mod->nu) {
    fail("%s", "--energy applies to a model without constraints (with constraints the poly family rescales "
               "p, the const family keeps the quadrature)");
    return -1;
  }
  if (mod->mass_q && o->energy == ENERGY_QUADRATURE) {
    fail("%s", "--energy quadrature: M depends on q, and no k integrates its H exactly (the step rescales p)");
    return -1;
  }
  if (mod->nu || mod->mass_q || o->energy == ENERGY_QUADRATURE) return 0;
  if (o->energy == ENERGY_RESCALE) return 1;
  return mod->degU == DEG_NONPOLY && !o->k && !o->batch && !o->wide_step;
}

int main(int argc, char **argv) {
  Options o = {NULL, ".", NULL, 2, 0, 0, 0, 0, 0, 0, -1, 0, 0, 0, ITER_AUTO, ROLL_AUTO, ENERGY_AUTO};
  int rc = parse_args(argc, argv, &o);
  if (rc) return rc < 0 ? 0 : rc;
  if (!o.name) {
    if (bad_name(o.name = default_name(o.model), o.model)) return 1;
    note_renamed(o.model, o.name);
  }
  signal(SIGXFSZ, SIG_IGN); /* past ulimit -f, a write fails (and is reported) instead of killing us */
  size_t len;
  char *src = read_file(o.model, &len);
  if (!src) return 1;
  size_t bom = len >= 3 && !memcmp(src, "\xef\xbb\xbf", 3) ? 3 : 0; /* a UTF-8 byte-order mark */
  diag_begin(o.model, src + bom, len - bom);
  Stmt *prog = parse_model(src + bom, len - bom);
  Model *mod = diag_error_count() ? NULL : analyse(o.model, prog);
  if (!mod) {
    diag_end();
    free(src);
    arena_free_all();
    return 1;
  }
  if (o.mass_loop) mod->mass_loop = o.mass_loop;
  if (o.stage_loop) mod->stage_loop = o.stage_loop;
  model_differentiate(mod);
  model_switches(mod);
  model_check_initial(mod);
  switch_warn(mod);
  const char *why = "given with -k";
  /* the family changes nothing without constraints */
  MultFamily fam = !mod->nu ? MULT_CONST : o.multiplier >= 0 ? (MultFamily)o.multiplier : o.s >= 2 || mod->mass_q ? MULT_POLY : MULT_CONST;
  int rescale = resolve_energy(&o, mod);
  int k = o.k ? o.k : rescale > 0 ? o.s : method_auto_k(o.s, mod->degU, mod->degg, mod->mass_q ? MULT_POLY : fam, &why);
  if (mod->mass_q && !o.k) why = "M depends on q: k = s, the end of the step rescales p to keep H (docs/method-mq.md)";
  if (rescale > 0 && !o.k)
    why = o.energy == ENERGY_RESCALE ? "k = s, the end of the step rescales p to keep H (given with --energy rescale)"
                                     : "U is not a polynomial: k = s, the end of the step rescales p to keep H "
                                       "(--energy auto; --energy quadrature for k = 2s+12 without it, docs/method-const.md)";
  char iter_why[512];
  IterKind iter = resolve_iteration(&o, mod, iter_why, sizeof iter_why);
  if (rescale < 0) {
    rc = 1;
  } else if (mass_q_refuse(mod, o.iteration == ITER_NEWTON, o.wide_step, fam == MULT_CONST)) {
    rc = 1;
  } else if (k > MAX_K) {
    report_degree(mod, o.s, k);
    rc = 1;
  } else if (fam == MULT_POLY && o.single && o.s > FLOAT_POLY_MAX_S) {
    /* measured (issue 30): from s = 8 the iteration in float stalls above float's
     * round-off, and g(q1) of the pendulum reaches 500 ulps */
    error_at(mod->g_loc[0], "in float (--real float) the poly family's iteration reaches round-off only up to "
                            "s = %d, not s = %d: pass a smaller -s, --multiplier const or --real double",
             FLOAT_POLY_MAX_S, o.s);
    rc = 1;
  } else if (o.check_only) {
    print_check(mod, &o, k, why, fam, iter_why, rescale);
    rc = print_check_code(&o, mod, k, fam, iter, rescale);
  } else {
    Method *me = method_new(k, o.s, fam);
    me->iteration = iter;
    me->energy_rescale = rescale;
    rc = write_outputs(&o, mod, me);
  }
  diag_end();
  free(src);
  arena_free_all();
  return rc;
}
