/* fuzz_runtime.c - libFuzzer harness over the driver library's parsers.
 *
 * An input is an option line, then (after its first newline) the text of
 * a CSV file:
 *
 *   --sweep k=0:1:5 -T 2 --tol 1e-8
 *   x, p_x, k
 *   1, 0, 0.5
 *
 * The CSV text is written to a temporary file, which hbvmrt_table_read
 * reads (runtime/table.c, --ensemble FILE) whenever it is not empty. The
 * option line is split into argv words at blanks (and NUL bytes); the word
 * "@" stands for the temporary file, so "--ensemble @" reads it through
 * the ensemble's column lookup. With --ensemble or --sweep the words go
 * through the ensemble's preamble (runtime/ensemble.c prepare: own_options,
 * hbvmrt_parse_args, the --sweep NAME=A:B:N parser or the table and its
 * columns), else through hbvmrt_parse_args alone. Nothing is run: prepare
 * and hbvmrt_parse_args read and check, they never step or write a file.
 *
 * Two fake models (no solver is needed: their functions are never stepped):
 * "fz", with every field of a current driver (m = 2 coordinates x and
 * th[2], a constraint, params k and p_x, events hit and top, dense output
 * and error control), for inputs of even length; "old", a driver of
 * hbvmgen 0.1 (m = 1, no names, params, events or error control: the
 * options that need them are refused), for odd lengths.
 *
 * A '/' in a word becomes '_', so an input names no file outside the
 * working directory (a FIFO or /dev/zero there would hang the reader, a
 * directory is fine: reading it fails with EISDIR and is reported). The
 * ensemble's trajectory limit is 10^5 in this build (-DHBVMRT_MAX_TRAJ),
 * so `--sweep k=0:1:1e7` stays fast under the sanitizers.
 *
 * Build and run: tests/fuzz/run_runtime.sh [SECONDS]. */
#include "ensemble.c"   /* its static prepare and ens_free; first, for its _POSIX_C_SOURCE */

#include <float.h>
#include <stddef.h>
#include <stdint.h>
#include <unistd.h>

#define FUZZ_MAX_WORDS 64

/* ---- the fake models ---- */

typedef struct {
  double t, q[2], p[2], lambda[1];
} FzState;

typedef struct {
  double k, p_x;
} FzParams;

static const double fz_q0[2] = {1.0, 0.0}, fz_p0[2] = {0.0, 1.0};
static const char *const fz_names[2] = {"x", "th[2]"};
static const hbvmrt_param fz_params[2] = {{"k", offsetof(FzParams, k)}, {"p_x", offsetof(FzParams, p_x)}};
static const char *const fz_event_names[2] = {"hit", "top"};
static const int fz_event_dirs[2] = {0, 1};

static void fz_init_params(void *x, const double *q0, const double *p0, const void *prm)
{
  FzState *s = x;

  (void)prm;
  memset(s, 0, sizeof *s);
  memcpy(s->q, q0 ? q0 : fz_q0, sizeof s->q);
  memcpy(s->p, p0 ? p0 : fz_p0, sizeof s->p);
}

static void fz_init(void *x, const double *q0, const double *p0)
{
  fz_init_params(x, q0, p0, NULL);
}

static void fz_params_default(void *prm)
{
  FzParams *pr = prm;

  pr->k = 1.5;
  pr->p_x = -2.0;
}

/* the steps, projection, dense output: never called by the parsers */
static int fz_step(void *x, double h, const void *prm, hbvmrt_stats *st)
{
  (void)x, (void)h, (void)prm, (void)st;
  abort();
}

static int fz_step_adaptive(void *x, double *h, double tol, const void *prm, hbvmrt_stats *st)
{
  (void)tol;
  return fz_step(x, *h, prm, st);
}

static int fz_project(void *x, const void *prm, double *dq, double *dp)
{
  (void)x, (void)prm, (void)dq, (void)dp;
  abort();
}

static void fz_dense(const void *x, double theta, void *y)
{
  (void)x, (void)theta, (void)y;
  abort();
}

static const char *fz_strerror(int code)
{
  (void)code;
  return "fake";
}

static double fz_energy(const void *x, const void *prm)
{
  (void)x, (void)prm;
  return 0;
}

/* g, hc and the event values: nu = 1 and nevents = 2 zeros */
static void fz_zeros(const void *x, const void *prm, double *v)
{
  (void)x, (void)prm;
  v[0] = 0;
}

static void fz_events(const void *x, const void *prm, double *v)
{
  (void)x, (void)prm;
  v[0] = v[1] = 0;
}

static const hbvmrt_model fz = {
  "fz", 2, 1, 4, 2,
  sizeof(FzState), sizeof(FzParams),
  offsetof(FzState, t), offsetof(FzState, q), offsetof(FzState, p), offsetof(FzState, lambda),
  2, fz_params,
  fz_q0, fz_p0,
  fz_init, fz_params_default, fz_step, fz_strerror, fz_energy,
  fz_zeros, fz_zeros,
  fz_names,
  fz_init_params, fz_project, DBL_EPSILON,
  fz_step_adaptive,
  fz_dense, 2, fz_event_names, fz_event_dirs, fz_events,
  NULL
};

/* as a driver of hbvmgen 0.1, which ends at the field names */
static const hbvmrt_model old = {
  "old", 1, 0, 2, 2,
  sizeof(FzState), 0,
  offsetof(FzState, t), offsetof(FzState, q), offsetof(FzState, p), offsetof(FzState, lambda),
  0, NULL,
  fz_q0, fz_p0,
  fz_init, NULL, fz_step, fz_strerror, fz_energy,
  NULL, NULL,
  NULL,
  NULL, NULL, 0,
  NULL,
  NULL, 0, NULL, NULL, NULL,
  NULL
};

/* ---- the input ---- */

static char csv_path[] = "/tmp/fuzz_runtime_XXXXXX";

static void remove_csv(void)
{
  unlink(csv_path);
}

int LLVMFuzzerInitialize(int *argc, char ***argv);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
  int fd = mkstemp(csv_path);

  (void)argc, (void)argv;
  if (fd < 0) {
    perror("fuzz_runtime: mkstemp");
    abort();
  }
  close(fd);
  atexit(remove_csv);
  return 0;
}

/* The n bytes at text into the temporary file. */
static void write_csv(const char *text, size_t n)
{
  FILE *f = fopen(csv_path, "wb");

  if (!f || fwrite(text, 1, n, f) != n || fclose(f) != 0)
    abort();
}

/* The words of line[0..n) into argv[1..] (argv[0] the program), at most
 * FUZZ_MAX_WORDS; line is cut in place. Returns argc. */
static int split_words(char *line, size_t n, char **argv)
{
  int argc = 1;
  size_t i = 0;

  argv[0] = "fz";
  while (i < n && argc < FUZZ_MAX_WORDS) {
    size_t start;
    while (i < n && (line[i] == ' ' || line[i] == '\t' || line[i] == '\0'))
      i++;
    if (i == n)
      break;
    for (start = i; i < n && line[i] != ' ' && line[i] != '\t' && line[i] != '\0'; i++)
      if (line[i] == '/')
        line[i] = '_';
    line[i] = '\0';   /* the byte after the line is a NUL too */
    argv[argc++] = strcmp(line + start, "@") ? line + start : csv_path;
    i++;
  }
  argv[argc] = NULL;
  return argc;
}

/* The words as the driver would take them: the ensemble's preamble, or
 * the single run's options (then their params applied to a block). */
static void parse_options(const hbvmrt_model *md, int argc, char **argv)
{
  if (hbvmrt_ensemble_wanted(argc, argv)) {
    Ens e;
    char *rest[FUZZ_MAX_WORDS + 1];
    memset(&e, 0, sizeof e);
    e.md = md;
    e.nranks = 1;
    prepare(&e, argc, argv, rest);
    ens_free(&e);
  } else {
    hbvmrt_opts o;
    FzParams prm = {0, 0};
    if (hbvmrt_parse_args(md, argc, argv, &o) == HBVMRT_ARGS_RUN && md->params_size == sizeof prm)
      hbvmrt_apply_params(md, &o, &prm);
    hbvmrt_opts_free(&o);
  }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const hbvmrt_model *md = size % 2 ? &old : &fz;
  char *buf = malloc(size + 1), *argv[FUZZ_MAX_WORDS + 1];
  const char *nl;
  size_t nline;

  if (!buf)
    abort();
  memcpy(buf, data, size);
  buf[size] = '\0';
  nl = memchr(buf, '\n', size);
  nline = nl ? (size_t)(nl - buf) : size;
  write_csv(buf + nline + (nl != NULL), size - nline - (nl != NULL));
  if (nl && nline + 1 < size) {
    hbvmrt_table tb;
    hbvmrt_table_read(md, csv_path, HBVMRT_MAX_TRAJ, &tb);
    hbvmrt_table_free(&tb);
  }
  parse_options(md, split_words(buf, nline, argv), argv);
  free(buf);
  return 0;
}
