/* main.c - the hbvmgen command line (SPEC section 2).
 *
 * Reads the model, runs the passes in order (parse, analyse, differentiate,
 * choose k, build the step, emit) and writes NAME.h, NAME.c and optionally
 * NAME_main.c. Files are written under temporary names and renamed only
 * when everything succeeded, so an error never leaves a partial output. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

#define MAX_MODEL_BYTES (64L << 20)
#define MAX_S 20
#define MAX_K 200

static const char usage[] =
    "usage: hbvmgen [options] MODEL.ham\n"
    "\n"
    "Generate a C solver (HBVM(k,s), line-integral method) for the constrained\n"
    "Hamiltonian system described in MODEL.ham.\n"
    "\n"
    "options:\n"
    "  -s S          degree of the polynomial approximation, 1 <= S <= 20 (default 2)\n"
    "  -k K|auto     Gauss-Legendre nodes, S <= K <= 200 (default auto: the smallest k that\n"
    "                conserves H and g exactly for polynomial models; 2s+12 otherwise)\n"
    "  -o DIR        where NAME.c and NAME.h are written (default generated)\n"
    "  -n NAME       C prefix of every emitted symbol (default: the model file's base name)\n"
    "  --multiplier F  const or poly: how the Lagrange multiplier varies over a step.\n"
    "                const: constant, the paper's method, order 2 with constraints\n"
    "                (2s where the true multiplier is constant); poly: a polynomial of\n"
    "                degree s-1, then p projected onto the hidden constraint and rescaled\n"
    "                to the energy: order 2s. Default: poly for s >= 2 with constraints\n"
    "  --main        also emit NAME_main.c, a standalone driver (link runtime/libhbvmrt.a)\n"
    "  --check       parse and analyse only; print m, nu, degrees and the chosen k\n"
    "  --real T      float or double (default): the type of the state, constants and\n"
    "                arithmetic of the generated code (float: for FPUs without double)\n"
    "  --plain-sum   update q, p, t by plain addition instead of compensated (Kahan)\n"
    "                summation: only to measure what compensation buys\n"
    "  --wide-step   iterate and update in the next wider type (long double, 80-bit on\n"
    "                x86-64, for double; double for float), from the compensated state,\n"
    "                rounding once into q, p: for runs of millions of steps, where the\n"
    "                round-off of a double step has a small bias that makes |H - H0|\n"
    "                drift (bench/README.md); 4-5x the step time, and no gain where\n"
    "                long double is double\n"    "  -h, --help    this text\n"
    "  --version     the version\n";

typedef struct {
  const char *model, *outdir, *name;
  int s, k; /* k = 0: auto */
  int emit_main, check_only;
  int single, plain_sum, wide_step;
  int multiplier; /* -1: default for s and the model; else a MultFamily */
} Options;

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

// Parse argv into o. Returns -1 to exit 0 (help, version), 1 on a usage
// error (already reported), 0 to go on.
static int parse_args(int argc, char **argv, Options *o) {
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i];
    int has_value = i + 1 < argc;
    if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
      fputs(usage, stdout);
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
    } else if (!strcmp(a, "--real")) {
      if (!has_value) return fail("option %s needs a value", a);
      const char *v = argv[++i];
      if (strcmp(v, "float") && strcmp(v, "double")) return fail("--real needs 'float' or 'double', got '%s'", v);
      o->single = !strcmp(v, "float");
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
  if (o->single && o->emit_main) return fail("%s", "--main needs double precision (the driver's CSV is in double)");
  if (o->k && o->k < o->s) {
    char buf[64];
    snprintf(buf, sizeof buf, "k=%d < s=%d", o->k, o->s);
    return fail("-k must be at least -s (%s)", buf);
  }
  if (o->name) {
    int ok = o->name[0] == '_' || ((o->name[0] | 32) >= 'a' && (o->name[0] | 32) <= 'z');
    for (const char *p = o->name; *p; p++)
      ok &= *p == '_' || (*p >= '0' && *p <= '9') || ((*p | 32) >= 'a' && (*p | 32) <= 'z');
    if (!ok) return fail("-n needs a C identifier, got '%s'", o->name);
  }
  return 0;
}

// The C prefix from the model's file name: its base name without .ham,
// with characters that cannot appear in a C identifier replaced by '_'.
static const char *default_name(const char *path) {
  const char *base = strrchr(path, '/');
  base = base ? base + 1 : path;
  size_t n = strlen(base);
  if (n > 4 && !strcmp(base + n - 4, ".ham")) n -= 4;
  char *name = arena_alloc(n + 2);
  size_t j = 0;
  if (n == 0 || (base[0] >= '0' && base[0] <= '9')) name[j++] = '_';
  for (size_t i = 0; i < n; i++) {
    char c = base[i];
    int ok = c == '_' || (c >= '0' && c <= '9') || ((c | 32) >= 'a' && (c | 32) <= 'z');
    name[j++] = ok ? c : '_';
  }
  return name;
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
      char *nb = realloc(buf, cap);
      if (!nb) internal_error("out of memory reading the model");
      buf = nb;
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

static void print_check(const Model *mod, const Options *o, int k, const char *why, MultFamily fam) {
  char a[16], b[16];
  printf("model %s: m=%d nu=%d deg(U)=%s deg(g)=%s k=%d s=%d\n", o->name, mod->m, mod->nu, deg_str(mod->degU, a),
         deg_str(mod->degg, b), k, o->s);
  printf("k: %s\n", o->k ? "given with -k" : why);
  if (!mod->nu)
    printf("multiplier: none (no constraints): order %d\n", 2 * o->s);
  else if (fam == MULT_POLY)
    printf("multiplier: poly (degree %d, projection and energy rescale): order %d in q, p and lambda\n", o->s - 1,
           o->s >= 2 ? 2 * o->s : 2);
  else
    printf("multiplier: const (the paper's method): order 2 in q and p, 1 in lambda (%d where the true multiplier is "
           "constant)\n", 2 * o->s);
  printf("M: %s\n", mass_str(mod->mass));
  long nnz = 0;
  for (int a2 = 0; a2 < mod->nu; a2++) nnz += mod->jac[a2].n;
  if (mod->nu)
    printf("Jacobian of g: %ld structural nonzeros of %ld (%.0f%%)\n", nnz, (long)mod->m * mod->nu,
           100.0 * nnz / ((double)mod->m * mod->nu));
  int ngrad = 0;
  for (int i = 0; i < mod->m; i++) ngrad += !dag_is_zero(mod->dag, mod->gradU[i]);
  printf("grad U: %d nonzero entries of %d\n", ngrad, mod->m);
  for (int i = 0; i < mod->nparams; i++) printf("param %s = %.17g\n", mod->params[i].name, mod->params[i].value);
}

// Open DIR/NAME+suffix under a temporary name.
static FILE *open_tmp(const Options *o, const char *suffix, char *tmp, char *final, size_t size) {
  snprintf(final, size, "%s/%s%s", o->outdir, o->name, suffix);
  snprintf(tmp, size, "%s/.%s%s.tmp", o->outdir, o->name, suffix);
  FILE *f = fopen(tmp, "w");
  if (!f) fprintf(stderr, "hbvmgen: error: cannot write '%s': %s\n", tmp, strerror(errno));
  return f;
}

// Emit the solver files; all or nothing.
static int write_outputs(const Options *o, const Model *mod, const Method *me, const Step *st) {
  enum { H, C, MAIN, NFILES };
  const char *suffix[NFILES] = {".h", ".c", "_main.c"};
  char tmp[NFILES][4096], final[NFILES][4096];
  FILE *f[NFILES] = {NULL, NULL, NULL};
  int nfiles = o->emit_main ? 3 : 2, rc = 0;
  EmitOptions eo = {o->name, strrchr(o->model, '/') ? strrchr(o->model, '/') + 1 : o->model, o->single,
                    !o->plain_sum, o->wide_step};
  for (int i = 0; i < nfiles && !rc; i++)
    if (!(f[i] = open_tmp(o, suffix[i], tmp[i], final[i], sizeof tmp[i]))) rc = 1;
  if (!rc) rc = emit_solver(f[H], f[C], mod, me, st, &eo) != 0;
  if (!rc && o->emit_main) rc = emit_driver(f[MAIN], mod, me, &eo) != 0;
  for (int i = 0; i < nfiles; i++)
    if (f[i] && fclose(f[i])) rc = 1;
  for (int i = 0; i < nfiles; i++) {
    if (!f[i]) continue;
    if (rc) remove(tmp[i]);
    else if (rename(tmp[i], final[i])) {
      fprintf(stderr, "hbvmgen: error: cannot write '%s': %s\n", final[i], strerror(errno));
      rc = 1;
    }
  }
  if (rc) fprintf(stderr, "hbvmgen: error: writing the output failed; nothing was written\n");
  return rc;
}

int main(int argc, char **argv) {
  Options o = {NULL, "generated", NULL, 2, 0, 0, 0, 0, 0, 0, -1};
  int rc = parse_args(argc, argv, &o);
  if (rc) return rc < 0 ? 0 : rc;
  if (!o.name) o.name = default_name(o.model);
  size_t len;
  char *src = read_file(o.model, &len);
  if (!src) return 1;
  diag_begin(o.model, src, len);
  Stmt *prog = parse_model(src, len);
  Model *mod = diag_error_count() ? NULL : analyse(o.model, prog);
  if (!mod) {
    free(src);
    arena_free_all();
    return 1;
  }
  model_differentiate(mod);
  model_check_initial(mod);
  const char *why = "given with -k";
  int k = o.k ? o.k : method_auto_k(o.s, mod->degU, mod->degg, &why);
  MultFamily fam = o.multiplier >= 0 ? (MultFamily)o.multiplier : o.s >= 2 && mod->nu ? MULT_POLY : MULT_CONST;
  if (k > MAX_K) {
    fprintf(stderr, "hbvmgen: error: the degrees of U and g need k=%d > %d nodes; pass -k\n", k, MAX_K);
    rc = 1;
  } else if (o.check_only) {
    print_check(mod, &o, k, why, fam);
  } else {
    const Method *me = method_new(k, o.s, fam);
    Step *st = step_build(mod, me);
    rc = st ? write_outputs(&o, mod, me, st) : 1;
  }
  free(src);
  arena_free_all();
  return rc;
}
