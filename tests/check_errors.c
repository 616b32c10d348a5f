/* check_errors.c - Check suite for bad input (docs/language.md, "Errors and warnings").
 *
 * Every case runs the generator itself, ../gen/hbvmgen (the suite runs from
 * tests/), in a child with its own temporary output directory, stdout and
 * stderr in files, and an alarm that kills it if it hangs:
 *   - golden files: each err/NAME.ham must print exactly err/NAME.err on
 *     stderr. A model with an error exits 1 and writes nothing; a model
 *     with warnings only exits 0 and writes its solver;
 *   - robustness: inputs built here at run time, too large or too odd to
 *     commit (10^5-deep brackets, 10^4-term operator chains, 1 MB names,
 *     numbers, lines and comments, random and NUL bytes, an empty file,
 *     mutated models) must give an error on stderr, exit 1 and write nothing; never
 *     crash or hang.
 * The suite is exposed as errors_suite(); the project's runner calls it. */
#define _POSIX_C_SOURCE 200809L   /* mkdtemp, fork, fileno */

#include <check.h>
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

Suite *errors_suite(void);

#define GENERATOR "../gen/hbvmgen"
#define GOLDEN_DIR "err"
#define TIMEOUT 20                /* seconds a single run may take */
#define MIN_GOLDEN 30
#define MB (1 << 20)
#define SEED 20240611u

/* ---- running the generator ---- */

/* A run of the generator in its own temporary directory dir:
 * dir/model.ham is the input (or a golden file), dir/out the -o directory,
 * dir/stdout and dir/stderr what it printed. */
typedef struct {
  char dir[64];
  char out[96], model[96], stdout_path[96], stderr_path[96];
  int status;                     /* exit status; -1 killed by a signal */
  int signal;                     /* the signal (SIGALRM: timed out) */
  char *err;                      /* stderr, NUL-terminated */
  size_t errlen;
} Run;

/* Read a whole file; *len receives its length. The buffer is
 * NUL-terminated for convenience and must be freed. NULL if unreadable. */
static char *slurp(const char *path, size_t *len)
{
  FILE *f = fopen(path, "rb");
  if (!f)
    return NULL;
  size_t cap = 4096, n = 0;
  char *buf = malloc(cap + 1);
  size_t got;
  while (buf && (got = fread(buf + n, 1, cap - n, f)) > 0) {
    n += got;
    if (n == cap) {
      char *bigger = realloc(buf, 2 * cap + 1);
      if (!bigger)
        free(buf);
      buf = bigger;
      cap *= 2;
    }
  }
  fclose(f);
  ck_assert_msg(buf != NULL, "out of memory reading %s", path);
  buf[n] = '\0';
  if (len)
    *len = n;
  return buf;
}

/* Write len bytes to path, failing the test if that is impossible. */
static void spit(const char *path, const char *data, size_t len)
{
  FILE *f = fopen(path, "wb");
  ck_assert_msg(f != NULL, "cannot create %s", path);
  ck_assert_msg(fwrite(data, 1, len, f) == len && fclose(f) == 0, "cannot write %s", path);
}

/* Make a fresh run directory with an empty output directory in it. */
static void run_init(Run *r)
{
  memset(r, 0, sizeof *r);
  strcpy(r->dir, "/tmp/hbvmgen-errors-XXXXXX");
  ck_assert_msg(mkdtemp(r->dir) != NULL, "cannot create a temporary directory");
  snprintf(r->out, sizeof r->out, "%s/out", r->dir);
  snprintf(r->model, sizeof r->model, "%s/model.ham", r->dir);
  snprintf(r->stdout_path, sizeof r->stdout_path, "%s/stdout", r->dir);
  snprintf(r->stderr_path, sizeof r->stderr_path, "%s/stderr", r->dir);
  ck_assert_msg(mkdir(r->out, 0700) == 0, "cannot create %s", r->out);
}

/* Remove a directory tree (the run directory: files and one level of
 * subdirectories). */
static void remove_tree(const char *path)
{
  DIR *d = opendir(path);
  if (!d) {
    remove(path);
    return;
  }
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
      continue;
    char sub[512];
    snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
    remove_tree(sub);
  }
  closedir(d);
  rmdir(path);
}

static void run_done(Run *r)
{
  free(r->err);
  remove_tree(r->dir);
}

/* The options a model asks for on its first line, "# flags: --real float",
 * split into argv (at most 8, into buf); returns their number. */
static int model_flags(const char *model, char *buf, size_t size, char **argv)
{
  FILE *f = fopen(model, "r");
  int n = 0;
  if (!f)
    return 0;
  if (fgets(buf, (int)size, f) && !strncmp(buf, "# flags: ", 9))
    for (char *t = strtok(buf + 9, " \r\n"); t && n < 8; t = strtok(NULL, " \r\n"))
      argv[n++] = t;
  fclose(f);
  return n;
}

/* Run the generator as `hbvmgen [flags] -o OUT model` in a child whose
 * stdout and stderr go to files, killed by SIGALRM after TIMEOUT seconds
 * (the alarm survives exec). Fills r->status, r->signal and r->err. */
static void run_generator(Run *r, const char *model)
{
  char flagbuf[256], *argv[13] = {GENERATOR};
  int argc = 1 + model_flags(model, flagbuf, sizeof flagbuf, argv + 1);
  argv[argc++] = "-o";
  argv[argc++] = r->out;
  argv[argc++] = (char *)model;
  argv[argc] = NULL;
  fflush(NULL);
  pid_t pid = fork();
  ck_assert_msg(pid >= 0, "fork failed");
  if (pid == 0) {
    int out = open(r->stdout_path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    int err = open(r->stderr_path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (out < 0 || err < 0 || dup2(out, 1) < 0 || dup2(err, 2) < 0)
      _exit(127);
    alarm(TIMEOUT);
    execv(GENERATOR, argv);
    _exit(127);
  }
  int status;
  ck_assert_msg(waitpid(pid, &status, 0) == pid, "waitpid failed");
  r->status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r->signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  ck_assert_msg(r->status != 127, "cannot run %s from tests/ (build it with make all)", GENERATOR);
  free(r->err);
  r->err = slurp(r->stderr_path, &r->errlen);
  ck_assert_msg(r->err != NULL, "no stderr file");
}

/* Number of entries in a directory, "." and ".." aside. */
static int count_entries(const char *path)
{
  DIR *d = opendir(path);
  ck_assert_msg(d != NULL, "cannot open %s", path);
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d)) != NULL)
    n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
  closedir(d);
  return n;
}

/* ---- golden files ---- */

/* The first line of s, for messages (at most 200 bytes, into buf). */
static const char *first_line(const char *s, char *buf, size_t size)
{
  size_t n = strcspn(s, "\n");
  if (n >= size)
    n = size - 1;
  memcpy(buf, s, n);
  buf[n] = '\0';
  return buf;
}

/* Describe where got differs from want: the 1-based line and both
 * versions of it. */
static void describe_difference(const char *want, size_t wlen, const char *got, size_t glen, char *msg,
                                size_t size)
{
  size_t i = 0, line = 1, start = 0;
  while (i < wlen && i < glen && want[i] == got[i]) {
    if (want[i] == '\n') {
      line++;
      start = i + 1;
    }
    i++;
  }
  char a[201], b[201];
  snprintf(msg, size, "line %zu:\n      want: %s\n      got:  %s", line,
           start < wlen ? first_line(want + start, a, sizeof a) : "(end of output)",
           start < glen ? first_line(got + start, b, sizeof b) : "(end of output)");
}

/* Check err/NAME.ham against err/NAME.err; append a report to failures
 * (size bytes) and return 1 when it does not match. The expected exit
 * status is 1 when the .err file holds an error, 0 when only warnings. */
static int check_golden(const char *name, char *failures, size_t size)
{
  char model[300], expect_path[300], why[700] = "";
  snprintf(model, sizeof model, GOLDEN_DIR "/%s.ham", name);
  snprintf(expect_path, sizeof expect_path, GOLDEN_DIR "/%s.err", name);
  size_t wlen;
  char *want = slurp(expect_path, &wlen);
  if (!want) {
    snprintf(failures + strlen(failures), size - strlen(failures), "  %s: no %s\n", model, expect_path);
    return 1;
  }
  int error = strstr(want, ": error: ") != NULL;
  Run r;
  run_init(&r);
  run_generator(&r, model);
  int files = count_entries(r.out);
  if (r.signal)
    snprintf(why, sizeof why, "killed by signal %d%s", r.signal, r.signal == SIGALRM ? " (timed out)" : "");
  else if (r.status != !!error)
    snprintf(why, sizeof why, "exit status %d, want %d", r.status, !!error);
  else if (error && files)
    snprintf(why, sizeof why, "%d file(s) written despite the error", files);
  else if (!error && files < 2)
    snprintf(why, sizeof why, "warnings only, but the solver was not written");
  else if (r.errlen != wlen || memcmp(r.err, want, wlen))
    describe_difference(want, wlen, r.err, r.errlen, why, sizeof why);
  if (*why)
    snprintf(failures + strlen(failures), size - strlen(failures), "  %s: %s\n", model, why);
  free(want);
  run_done(&r);
  return *why != '\0';
}

static int compare_names(const void *a, const void *b)
{
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The NAME of every err/NAME.ham, sorted; *n receives their number. */
static char **golden_names(int *n)
{
  DIR *d = opendir(GOLDEN_DIR);
  ck_assert_msg(d != NULL, "cannot open tests/" GOLDEN_DIR " (the suite runs from tests/)");
  int cap = 16;
  char **names = malloc((size_t)cap * sizeof *names);
  *n = 0;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    size_t len = strlen(e->d_name);
    if (len <= 4 || strcmp(e->d_name + len - 4, ".ham"))
      continue;
    if (*n == cap)
      names = realloc(names, (size_t)(cap *= 2) * sizeof *names);
    ck_assert_msg(names != NULL, "out of memory");
    names[*n] = malloc(len - 3);
    memcpy(names[*n], e->d_name, len - 4);
    names[(*n)++][len - 4] = '\0';
  }
  closedir(d);
  qsort(names, (size_t)*n, sizeof *names, compare_names);
  return names;
}

START_TEST(test_golden)
{
  int n, failed = 0;
  char **names = golden_names(&n);
  size_t size = 64 * 1024;
  char *failures = calloc(size, 1);
  ck_assert_msg(failures != NULL, "out of memory");
  for (int i = 0; i < n; i++) {
    failed += check_golden(names[i], failures, size);
    free(names[i]);
  }
  free(names);
  ck_assert_msg(n >= MIN_GOLDEN, "only %d golden files in tests/" GOLDEN_DIR, n);
  ck_assert_msg(failed == 0, "%d of %d golden files do not match:\n%s", failed, n, failures);
  free(failures);
}
END_TEST

/* ---- robustness: inputs built at run time ---- */

/* A growable byte buffer for building models. */
typedef struct {
  char *s;
  size_t n, cap;
} Buf;

static void buf_add(Buf *b, const void *data, size_t len)
{
  if (b->n + len > b->cap) {
    size_t cap = b->cap ? b->cap : 4096;
    while (cap < b->n + len)
      cap *= 2;
    b->s = realloc(b->s, cap);
    ck_assert_msg(b->s != NULL, "out of memory");
    b->cap = cap;
  }
  memcpy(b->s + b->n, data, len);
  b->n += len;
}

static void buf_str(Buf *b, const char *s)
{
  buf_add(b, s, strlen(s));
}

static void buf_repeat(Buf *b, const char *s, long times)
{
  for (long i = 0; i < times; i++)
    buf_str(b, s);
}

/* Run the generator on the model in b (then freed) and require a failure
 * done right: exit status 1, no signal, an error on stderr whose text
 * contains want (when not NULL), no internal error, nothing written. */
static void expect_rejected(Buf *b, const char *what, const char *want)
{
  Run r;
  run_init(&r);
  spit(r.model, b->s ? b->s : "", b->n);
  free(b->s);
  memset(b, 0, sizeof *b);
  run_generator(&r, r.model);
  char line[201];
  ck_assert_msg(!r.signal, "%s: killed by signal %d%s", what, r.signal, r.signal == SIGALRM ? " (hang)" : "");
  ck_assert_msg(r.status == 1, "%s: exit status %d, want 1", what, r.status);
  ck_assert_msg(strstr(r.err, ": error: ") != NULL, "%s: no error on stderr: %s", what,
                first_line(r.err, line, sizeof line));
  ck_assert_msg(strstr(r.err, "internal error") == NULL, "%s: %s", what, first_line(r.err, line, sizeof line));
  ck_assert_msg(want == NULL || strstr(r.err, want) != NULL, "%s: want '%s' on stderr, got: %s", what, want,
                first_line(r.err, line, sizeof line));
  ck_assert_msg(count_entries(r.out) == 0, "%s: files written despite the error", what);
  run_done(&r);
}

START_TEST(test_deep_brackets)
{
  Buf b = {0};
  buf_str(&b, "variables x\nU = ");
  buf_repeat(&b, "(", 100000);
  buf_str(&b, "x");
  buf_repeat(&b, ")", 100000);
  expect_rejected(&b, "10^5-deep parentheses", "model.ham:2:1005: error: brackets nested more than 1000 deep");
  buf_str(&b, "variables x\ng = ");
  buf_repeat(&b, "[", 100000);
  expect_rejected(&b, "10^5 open brackets", "brackets nested more than 1000 deep");
}
END_TEST

/* Chains of 10^4 operators without brackets: right-associative ^ and
 * unary minus fill the parser's stack, left-associative + makes a deep
 * tree; each is an error, never a stack overflow. */
START_TEST(test_deep_chains)
{
  static const struct {
    const char *first, *link, *what;
  } chains[] = {
      {"x", "^x", "x^x^...^x"},
      {"x", "+x", "x+x+...+x"},
      {"x", "*sin(x)", "x*sin(x)*...*sin(x)"},
      {"-", "-", "------x"},
  };
  for (size_t i = 0; i < sizeof chains / sizeof chains[0]; i++) {
    Buf b = {0};
    buf_str(&b, "variables x\nU = ");
    buf_str(&b, chains[i].first);
    buf_repeat(&b, chains[i].link, 10000);
    if (chains[i].first[0] == '-')
      buf_str(&b, "x");
    buf_str(&b, "\n");
    expect_rejected(&b, chains[i].what, "error: expression nested too deeply");
  }
}
END_TEST

/* A model of 40 KB whose statements are small but whose step is not: a
 * chain of 25 links coupled by a dense M, at s = 8 the poly family's
 * multiplier system of 200 coefficients. The node limit is then reached
 * while the step is built, and is reported at the constraints with what
 * to do, not without a place (issue 13, item 8). */
START_TEST(test_step_node_limit)
{
  enum { LINKS = 25, COORDS = 2 * LINKS };
  Buf b = {0};
  char num[64];
  buf_str(&b, "# flags: -s 8\nN = 25\nvariables x[N], y[N]\nM = [");
  for (int i = 0; i < COORDS; i++) {
    buf_str(&b, i ? ",\n [" : "[");
    for (int j = 0; j < COORDS; j++) {
      snprintf(num, sizeof num, "%s%.17g", j ? ", " : "", i == j ? 3.0 : ldexp(1.0, -abs(i - j)));
      buf_str(&b, num);
    }
    buf_str(&b, "]");
  }
  buf_str(&b, "]\nU = sum(i in 1..N, y[i])\n"
              "g = [x[1]^2 + y[1]^2 - 1, [(x[i] - x[i-1])^2 + (y[i] - y[i-1])^2 - 1 for i in 2..N]]\n"
              "q0 = [[i for i in 1..N], [0 for i in 1..N]]\np0 = [0 for i in 1..2*N]\n");
  expect_rejected(&b, "a step over the node limit",
                  "model.ham:55:22: error: the model needs more than 4000000 expression nodes "
                  "(the limit was reached building the step for these equations: pass --multiplier const");
}
END_TEST

START_TEST(test_huge_tokens)
{
  Buf b = {0};
  buf_str(&b, "variables ");
  buf_repeat(&b, "a", MB);
  buf_str(&b, "\n");
  expect_rejected(&b, "1 MB name", "is too long: 1048576 characters");
  buf_str(&b, "variables x\nU = ");
  buf_repeat(&b, "7", MB);
  buf_str(&b, " * x\n");
  expect_rejected(&b, "1 MB number", "error: number out of range");
  buf_str(&b, "variables x\nU = x");
  buf_repeat(&b, " ", MB);
  buf_str(&b, "@ 2\n");
  expect_rejected(&b, "1 MB line", "model.ham:2:1048582: error: unexpected character '@'");
  buf_str(&b, "variables x\nU = x\n");
  buf_repeat(&b, "@", MB);
  expect_rejected(&b, "1 MB of bad characters", "note: too many errors, stopping");
  buf_str(&b, "# ");
  buf_repeat(&b, "\xc3\xa9", MB / 2);
  buf_str(&b, "\nvariables x\nU = y\n");
  expect_rejected(&b, "1 MB comment", "model.ham:3:5: error: unknown name 'y'");
}
END_TEST

/* Functions of def cannot recurse deeper than expressions may nest: a
 * chain of 3000, each calling the one before, is refused. (Exponential
 * expansion, functions calling the one before twice, is test_def_functions
 * in check_parser.c: expanded once per distinct arguments.) */
START_TEST(test_def_expansion_bounded)
{
  Buf b = {0};
  char line[96];
  buf_str(&b, "variables x\ndef f1(a) = a + 1\n");
  for (int i = 2; i <= 3000; i++) {
    snprintf(line, sizeof line, "def f%d(a) = f%d(a) + 1\n", i, i - 1);
    buf_str(&b, line);
  }
  buf_str(&b, "U = f3000(x)\n");
  expect_rejected(&b, "3000 nested calls", "error: calls of functions nested too deeply");
}
END_TEST

/* A small deterministic generator (xorshift32), independent of the C
 * library so the inputs are the same everywhere. */
static unsigned next_random(unsigned *state)
{
  unsigned x = *state;
  x ^= x << 13;
  x ^= x >> 17;
  x ^= x << 5;
  return *state = x;
}

START_TEST(test_random_bytes)
{
  unsigned state = SEED;
  for (int file = 0; file < 8; file++) {
    Buf b = {0};
    size_t len = 1 + next_random(&state) % (64 * 1024);
    for (size_t i = 0; i < len; i++) {
      char c = (char)(next_random(&state) & 0xff);
      buf_add(&b, &c, 1);
    }
    char what[64];
    snprintf(what, sizeof what, "random bytes, file %d", file);
    expect_rejected(&b, what, NULL);
  }
}
END_TEST

START_TEST(test_nul_bytes)
{
  Buf b = {0};
  buf_add(&b, "\0", 1);
  expect_rejected(&b, "one NUL byte", "model.ham:1:1: error: unexpected byte 0x00");
  static const char nuls[4096];
  buf_add(&b, nuls, sizeof nuls);
  expect_rejected(&b, "4096 NUL bytes", "note: too many errors, stopping");
  buf_str(&b, "variables x\nU = x");
  buf_add(&b, "\0", 1);
  buf_str(&b, "\n");
  expect_rejected(&b, "a NUL byte in a model", "model.ham:2:6: error: unexpected byte 0x00");
}
END_TEST

START_TEST(test_empty_file)
{
  Buf b = {0};
  expect_rejected(&b, "empty file", "model.ham:1:1: error: the model declares no coordinates");
  buf_str(&b, "\n\n   \n# just a comment\n");
  expect_rejected(&b, "blank file", "error: the model declares no coordinates");
}
END_TEST

/* Mutations of the committed models (bytes deleted, duplicated, replaced
 * by punctuation or by keywords): whatever the result, the generator must
 * exit 0 having written the solver, or 1 having written nothing. */
START_TEST(test_mutated_models)
{
  static const char *const models[] = {"../models/pendulum.ham", "../models/conical.ham",
                                       "../models/modified.ham", "../models/satellites.ham"};
  static const char *const inserts[] = {"(", ")", "[", "]", ",", "^", "..", "sum(i in 1..2, ", "for", "x[",
                                        "1e999", "/0", "pi", "\xff", "#", "\n", "diag(", "M = "};
  unsigned state = SEED;
  for (int k = 0; k < 40; k++) {
    const char *path = models[k % 4];
    size_t len;
    char *src = slurp(path, &len);
    ck_assert_msg(src != NULL, "cannot read %s", path);
    Buf b = {0};
    size_t at = next_random(&state) % len, cut = next_random(&state) % 4;
    const char *ins = inserts[next_random(&state) % (sizeof inserts / sizeof inserts[0])];
    buf_add(&b, src, at);
    buf_str(&b, ins);
    buf_add(&b, src + at + (at + cut <= len ? cut : 0), len - at - (at + cut <= len ? cut : 0));
    free(src);
    Run r;
    run_init(&r);
    spit(r.model, b.s, b.n);
    free(b.s);
    run_generator(&r, r.model);
    int files = count_entries(r.out);
    ck_assert_msg(!r.signal, "mutation %d of %s: killed by signal %d", k, path, r.signal);
    ck_assert_msg((r.status == 1 && files == 0) || (r.status == 0 && files >= 2),
                  "mutation %d of %s: exit status %d with %d file(s) written", k, path, r.status, files);
    ck_assert_msg(r.status == 0 || strstr(r.err, ": error: ") || strstr(r.err, "hbvmgen: error: "),
                  "mutation %d of %s: failed without an error message", k, path);
    run_done(&r);
  }
}
END_TEST

Suite *errors_suite(void)
{
  Suite *s = suite_create("errors");
  TCase *golden = tcase_create("golden");
  tcase_set_timeout(golden, 300);
  tcase_add_test(golden, test_golden);
  suite_add_tcase(s, golden);
  TCase *robust = tcase_create("robustness");
  tcase_set_timeout(robust, 300);
  tcase_add_test(robust, test_deep_brackets);
  tcase_add_test(robust, test_deep_chains);
  tcase_add_test(robust, test_huge_tokens);
  tcase_add_test(robust, test_def_expansion_bounded);
  tcase_add_test(robust, test_step_node_limit);
  tcase_add_test(robust, test_random_bytes);
  tcase_add_test(robust, test_nul_bytes);
  tcase_add_test(robust, test_empty_file);
  tcase_add_test(robust, test_mutated_models);
  suite_add_tcase(s, robust);
  return s;
}
