/* check_files.c - Check suite for what the generator does to the file
 * system and for the costs of its front end (issue 13, items 2-4 and 9):
 *
 *   output     each scenario in its own temporary directory: -o DIR is
 *              created (mkdir -p); a symlink planted at a temporary's old
 *              fixed name is never followed; when NAME.c cannot be replaced
 *              (it is a directory) the NAME.h already moved into place is
 *              put back; past `ulimit -f` nothing is changed; an -o path
 *              longer than the system allows is refused, not truncated;
 *              concurrent runs into one directory never leave a mismatched
 *              NAME.h/NAME.c pair. No temporary is ever left behind, and no
 *              message names one.
 *   cost       diagnostics cost the size of the input, not its size times
 *              the number of messages (counted in bytes read, not seconds),
 *              10^5 unused definitions print 20 warnings and a count, and
 *              a NAME.c of 4 MB or more gets a note with its size.
 *   driver     -T shorter than |h| still takes one step, as --help says.
 *
 * The suite is files_suite(); the project's runner (check_main.c) adds it.
 * It runs from tests/, like the others. */
#define _POSIX_C_SOURCE 200809L

#include <check.h>
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "hbvmgen.h"
#include "hbvmrt_internal.h"

Suite *files_suite(void);

#define GENERATOR "../gen/hbvmgen"
#define PENDULUM "../models/pendulum.ham"
#define CONICAL "../models/conical.ham"
#define TIMEOUT 20

/* ---- helpers ---- */

static char root[64];  /* this test's temporary directory */

static void make_root(void)
{
  strcpy(root, "/tmp/hbvmgen-files-XXXXXX");
  ck_assert_msg(mkdtemp(root) != NULL, "cannot create a temporary directory");
}

static void remove_tree(const char *path)
{
  struct stat st;
  if (lstat(path, &st))
    return;
  if (S_ISDIR(st.st_mode)) {
    DIR *d = opendir(path);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL) {
      if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
        continue;
      char *sub = malloc(strlen(path) + strlen(e->d_name) + 2);
      sprintf(sub, "%s/%s", path, e->d_name);
      remove_tree(sub);
      free(sub);
    }
    if (d)
      closedir(d);
    rmdir(path);
  } else {
    unlink(path);
  }
}

static void teardown(void)
{
  if (root[0])
    remove_tree(root);
  root[0] = '\0';
}

static void put(const char *path, const char *text)
{
  FILE *f = fopen(path, "w");
  ck_assert_msg(f && fputs(text, f) >= 0 && fclose(f) == 0, "cannot write %s", path);
}

/* The whole file (NUL-terminated, to free), or NULL. */
static char *get(const char *path)
{
  FILE *f = fopen(path, "rb");
  if (!f)
    return NULL;
  size_t cap = 1 << 16, n = 0, got;
  char *s = malloc(cap + 1);
  while (s && (got = fread(s + n, 1, cap - n, f)) > 0)
    if ((n += got) == cap)
      s = realloc(s, (cap *= 2) + 1);
  fclose(f);
  ck_assert_msg(s != NULL, "out of memory");
  s[n] = '\0';
  return s;
}

/* The names in dir, "." and ".." aside, sorted and joined by spaces. */
static void entries(const char *dir, char *out, size_t size)
{
  char *names[64];
  int n = 0;
  DIR *d = opendir(dir);
  ck_assert_msg(d != NULL, "cannot open %s", dir);
  struct dirent *e;
  while ((e = readdir(d)) != NULL && n < 64)
    if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
      names[n++] = strdup(e->d_name);
  closedir(d);
  for (int i = 0; i < n; i++) /* insertion sort: a handful of names */
    for (int j = i; j > 0 && strcmp(names[j - 1], names[j]) > 0; j--) {
      char *t = names[j];
      names[j] = names[j - 1];
      names[j - 1] = t;
    }
  out[0] = '\0';
  for (int i = 0; i < n; i++) {
    snprintf(out + strlen(out), size - strlen(out), "%s%s", i ? " " : "", names[i]);
    free(names[i]);
  }
}

/* Run the generator with args (NULL-terminated), stderr into root/stderr,
 * with a file-size limit when fsize > 0. Returns the exit status, -1 when
 * killed; *err receives stderr (to free) when err is not NULL. */
static int generate(const char *const *args, long fsize, char **err)
{
  char errpath[128];
  snprintf(errpath, sizeof errpath, "%s/stderr", root);
  fflush(NULL);
  pid_t pid = fork();
  ck_assert_msg(pid >= 0, "fork failed");
  if (pid == 0) {
    int fd = open(errpath, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    int null = open("/dev/null", O_WRONLY);
    if (fd < 0 || null < 0 || dup2(fd, 2) < 0 || dup2(null, 1) < 0)
      _exit(127);
    if (fsize > 0) {
      struct rlimit rl = {(rlim_t)fsize, (rlim_t)fsize};
      setrlimit(RLIMIT_FSIZE, &rl);
    }
    alarm(TIMEOUT);
    char *argv[16];
    int n = 0;
    argv[n++] = (char *)GENERATOR;
    for (; args[n - 1] && n < 15; n++)
      argv[n] = (char *)args[n - 1];
    argv[n] = NULL;
    execv(GENERATOR, argv);
    _exit(127);
  }
  int status;
  ck_assert_msg(waitpid(pid, &status, 0) == pid, "waitpid failed");
  int rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  ck_assert_msg(rc != 127, "cannot run %s from tests/", GENERATOR);
  if (err) {
    *err = get(errpath);
    ck_assert_msg(*err != NULL, "no stderr");
  }
  unlink(errpath);
  return rc;
}

/* stderr of a failed run: an error naming want, and no hidden temporary. */
static void check_message(const char *err, const char *want)
{
  ck_assert_msg(strstr(err, "hbvmgen: error: ") != NULL, "no error message: %s", err);
  ck_assert_msg(strstr(err, want) != NULL, "want '%s' in: %s", want, err);
  ck_assert_msg(strstr(err, "/.") == NULL && strstr(err, "XXXXXX") == NULL, "a temporary is named: %s", err);
}

/* root/name, in buf (of PATH_SIZE bytes). */
#define PATH_SIZE 160
static const char *in_root(char *buf, const char *name)
{
  snprintf(buf, PATH_SIZE, "%s/%s", root, name);
  return buf;
}

/* A failed run: exit status 1 and an error naming want. */
static void expect_failure(const char *const *args, long fsize, const char *want)
{
  char *err;
  ck_assert_int_eq(generate(args, fsize, &err), 1);
  check_message(err, want);
  free(err);
}

static void assert_content(const char *path, const char *want)
{
  char *s = get(path);
  ck_assert_msg(s && !strcmp(s, want), "%s holds '%s', want '%s'", path, s ? s : "(nothing)", want);
  free(s);
}

static void assert_entries(const char *dir, const char *want)
{
  char list[1024];
  entries(dir, list, sizeof list);
  ck_assert_str_eq(list, want);
}

/* ---- output ---- */

START_TEST(test_output_dir_created)
{
  make_root();
  char dir[PATH_SIZE];
  const char *args[] = {"-o", in_root(dir, "a/b/c"), PENDULUM, NULL};
  ck_assert_int_eq(generate(args, 0, NULL), 0);
  assert_entries(dir, "pendulum.c pendulum.h");
  /* a file where the directory should be: refused, naming the user's path */
  char file[PATH_SIZE], want[PATH_SIZE + 32];
  put(in_root(file, "file"), "x");
  const char *args2[] = {"-o", file, PENDULUM, NULL};
  snprintf(want, sizeof want, "'%s' is not a directory", file);
  expect_failure(args2, 0, want);
}
END_TEST

START_TEST(test_planted_symlink)
{
  make_root();
  char victim[128], link1[160], link2[160];
  snprintf(victim, sizeof victim, "%s/victim", root);
  put(victim, "precious\n");
  /* the temporaries' names of old: a symlink there used to be written through */
  snprintf(link1, sizeof link1, "%s/.pendulum.h.tmp", root);
  snprintf(link2, sizeof link2, "%s/.pendulum.c.tmp", root);
  ck_assert_int_eq(symlink(victim, link1), 0);
  ck_assert_int_eq(symlink(victim, link2), 0);
  const char *args[] = {"-o", root, PENDULUM, NULL};
  ck_assert_int_eq(generate(args, 0, NULL), 0);
  assert_content(victim, "precious\n");
  assert_entries(root, ".pendulum.c.tmp .pendulum.h.tmp pendulum.c pendulum.h victim");
}
END_TEST

START_TEST(test_failed_rename_restores)
{
  make_root();
  char path[PATH_SIZE];
  put(in_root(path, "pendulum.h"), "old header\n");
  ck_assert_int_eq(mkdir(in_root(path, "pendulum.c"), 0700), 0); /* NAME.c cannot be replaced */
  const char *args[] = {"-o", root, PENDULUM, NULL};
  expect_failure(args, 0, "pendulum.c': it is a directory");
  assert_content(in_root(path, "pendulum.h"), "old header\n"); /* put back after it was replaced */
  assert_entries(root, "pendulum.c pendulum.h");
}
END_TEST

START_TEST(test_file_size_limit)
{
  make_root();
  char h[PATH_SIZE], c[PATH_SIZE];
  put(in_root(h, "conical.h"), "old header\n");
  put(in_root(c, "conical.c"), "old code\n");
  const char *args[] = {"-o", root, CONICAL, NULL};
  expect_failure(args, 8192, "conical.c': File too large"); /* ulimit -f: the .h fits, the .c is larger */
  assert_content(h, "old header\n");
  assert_content(c, "old code\n");
  assert_entries(root, "conical.c conical.h");
}
END_TEST

START_TEST(test_long_path)
{
  make_root();
  static char dir[6000];
  snprintf(dir, sizeof dir, "%s/", root);
  size_t n = strlen(dir);
  memset(dir + n, 'd', 5000);
  dir[n + 5000] = '\0';
  const char *args[] = {"-o", dir, PENDULUM, NULL};
  expect_failure(args, 0, "too long");
  assert_entries(root, "");
}
END_TEST

/* Two runs into one directory with one -n but different models: whichever
 * finishes last, NAME.h and NAME.c come from the same run. */
START_TEST(test_concurrent_runs)
{
  make_root();
  char h[PATH_SIZE], c[PATH_SIZE];
  in_root(h, "twin.h");
  in_root(c, "twin.c");
  for (int round = 0; round < 10; round++) {
    pid_t pids[2];
    for (int i = 0; i < 2; i++) {
      fflush(NULL);
      pids[i] = fork();
      ck_assert(pids[i] >= 0);
      if (pids[i] == 0) {
        int null = open("/dev/null", O_WRONLY);
        dup2(null, 1);
        dup2(null, 2);
        alarm(TIMEOUT);
        execl(GENERATOR, GENERATOR, "-o", root, "-n", "twin", i ? CONICAL : PENDULUM, (char *)NULL);
        _exit(127);
      }
    }
    for (int i = 0; i < 2; i++) {
      int status;
      ck_assert(waitpid(pids[i], &status, 0) == pids[i]);
      ck_assert_msg(WIFEXITED(status) && WEXITSTATUS(status) == 0, "round %d: run %d failed", round, i);
    }
    char *a = get(h), *b = get(c);
    ck_assert(a && b);
    int ha = strstr(a, "from pendulum.ham") != NULL, ca = strstr(b, "from pendulum.ham") != NULL;
    ck_assert_msg(ha == ca, "round %d: twin.h from %s, twin.c from %s", round, ha ? "pendulum" : "conical",
                  ca ? "pendulum" : "conical");
    free(a);
    free(b);
    assert_entries(root, "twin.c twin.h");
  }
}
END_TEST

/* ---- cost ---- */

/* 10^5 warnings, one per line: indexing the lines reads the input a
 * bounded number of times, however many messages there are (rescanning
 * from the start for each was quadratic: 58 s for 10^5). */
START_TEST(test_diagnostics_linear)
{
  enum { LINES = 100000 };
  size_t len = (size_t)LINES * 8;
  char *src = malloc(len + 1);
  ck_assert(src != NULL);
  for (int i = 0; i < LINES; i++)
    snprintf(src + (size_t)i * 8, 9, "a%06d%c", i, "\n\r"[i % 2]); /* LF and lone CR alike */
  int saved = dup(2), null = open("/dev/null", O_WRONLY);
  ck_assert(saved >= 0 && null >= 0);
  fflush(stderr);
  dup2(null, 2);
  diag_begin("big.ham", src, len);
  long before = diag_scanned();
  for (int i = 1; i <= LINES; i++)
    warning_at((Loc){i, 2}, "warning %d", i);
  for (int i = 1; i <= LINES; i += 1000)
    warning_at((Loc){i, 1}, "another kind, %d", i);
  diag_end();
  fflush(stderr);
  dup2(saved, 2);
  close(saved);
  close(null);
  long scanned = diag_scanned() - before;
  ck_assert_msg(scanned <= 2 * (long)len, "%ld bytes read for %zu bytes of input", scanned, len);
  free(src);
}
END_TEST

/* 10^5 unused definitions: the generator prints 20 warnings and one count. */
START_TEST(test_many_warnings_capped)
{
  make_root();
  char model[PATH_SIZE], out[PATH_SIZE];
  FILE *f = fopen(in_root(model, "many.ham"), "w");
  ck_assert(f != NULL);
  fputs("variables x\nU = x^2\n", f);
  for (int i = 0; i < 100000; i++)
    fprintf(f, "d%d = %d\n", i, i);
  ck_assert(fclose(f) == 0);
  char *err;
  const char *args[] = {"-o", in_root(out, "out"), model, NULL};
  ck_assert_int_eq(generate(args, 0, &err), 0);
  int warnings = 0;
  for (const char *p = err; (p = strstr(p, ": warning: ")) != NULL; p++)
    warnings++;
  ck_assert_int_eq(warnings, 20);
  ck_assert_msg(strstr(err, "note: 99980 more warnings like \"definition 'd19' is never used\" were not shown"),
                "no count of the warnings not shown: %s", err);
  ck_assert_msg(strlen(err) < 4096, "%zu bytes of warnings", strlen(err));
  free(err);
}
END_TEST

/* A NAME.c of 4 MB or more gets a note with its size (gcc needs minutes and
 * gigabytes for it); a small one none. 400 coordinates in a chain of 399
 * constraints give 7.9 MB of straight-line C in about 0.2 s. */
START_TEST(test_large_output_note)
{
  make_root();
  char model[PATH_SIZE], out[PATH_SIZE], *err;
  FILE *f = fopen(in_root(model, "chain.ham"), "w");
  ck_assert(f != NULL);
  fputs("variables x[400]\nU = sum(i in 1..400, x[i]^4)\ng = [x[i]^2 + x[i+1]^2 - 1 for i in 1..399]\n", f);
  ck_assert(fclose(f) == 0);
  /* straight-line code: --rolled auto rolls this chain (a few KB of C) since the
   * poly family has a rolled form */
  const char *args[] = {"-o", in_root(out, "out"), "--rolled", "off", model, NULL};
  ck_assert_int_eq(generate(args, 0, &err), 0);
  const char *note = strstr(err, "hbvmgen: note: '");
  ck_assert_msg(note && strstr(note, "/out/chain.c' is ") && strstr(note, " MB of C: compilers take minutes"),
                "no note on the size of chain.c: %.300s", err);
  double mb = atof(strstr(note, "' is ") + 5);
  ck_assert_msg(mb > 4 && mb < 20, "chain.c said to be %g MB", mb);
  free(err);
  const char *small[] = {"-o", out, PENDULUM, NULL};
  ck_assert_int_eq(generate(small, 0, &err), 0);
  ck_assert_msg(!strstr(err, "MB of C"), "a note on a small file: %s", err);
  free(err);
}
END_TEST

/* ---- driver ---- */

static const hbvmrt_model fake = {.name = "fake", .m = 1, .k = 1, .s = 1};

/* N = ceil(T/|h|): a span shorter than one step is one step, not none. */
START_TEST(test_driver_short_span)
{
  static const struct {
    const char *h, *T;
    long n;
  } cases[] = {{"0.1", "1e-300", 1}, {"-0.1", "1e-300", 1}, {"0.1", "0", 0}, {"0.1", "0.05", 1},
               {"0.1", "1", 10},     {"1e300", "1", 1}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char *argv[] = {"fake", "-h", (char *)cases[i].h, "-T", (char *)cases[i].T, NULL};
    hbvmrt_opts o;
    int rc = hbvmrt_parse_args(&fake, 5, argv, &o);
    ck_assert_int_eq(rc, HBVMRT_ARGS_RUN);
    ck_assert_msg(o.nsteps == cases[i].n, "-h %s -T %s: %ld steps, want %ld", cases[i].h, cases[i].T, o.nsteps,
                  cases[i].n);
    hbvmrt_opts_free(&o);
  }
}
END_TEST

/* A test case of s that cleans up root after each test. */
static TCase *tcase_in(Suite *s, const char *name)
{
  TCase *tc = tcase_create(name);
  tcase_add_checked_fixture(tc, NULL, teardown);
  tcase_set_timeout(tc, 120);
  suite_add_tcase(s, tc);
  return tc;
}

Suite *files_suite(void)
{
  Suite *s = suite_create("files");
  TCase *out = tcase_in(s, "output");
  tcase_add_test(out, test_output_dir_created);
  tcase_add_test(out, test_planted_symlink);
  tcase_add_test(out, test_failed_rename_restores);
  tcase_add_test(out, test_file_size_limit);
  tcase_add_test(out, test_long_path);
  tcase_add_test(out, test_concurrent_runs);
  TCase *cost = tcase_in(s, "cost");
  tcase_add_test(cost, test_diagnostics_linear);
  tcase_add_test(cost, test_many_warnings_capped);
  tcase_add_test(cost, test_large_output_note);
  tcase_add_test(tcase_in(s, "driver"), test_driver_short_span);
  return s;
}
