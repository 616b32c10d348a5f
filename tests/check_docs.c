/* check_docs.c - what the documentation promises, run as a user would.
 *
 *   - the embedding examples of docs/embedding.md (docs/examples/embed.c
 *     and embed.cpp) are compiled with gcc and g++ against a pendulum
 *     generated into a temporary directory, run, and their printed state
 *     compared with an independent RK4 solution of the pendulum and with
 *     the lines docs/embedding.md shows after ./embed and ./embed_cpp, and
 *     docs/embedding.md shows both files verbatim;
 *   - `make install PREFIX=TMP` installs what docs/hbvmgen.1 lists, and the
 *     C example and a standalone driver build with `pkg-config --cflags
 *     --libs hbvmrt` (PKG_CONFIG_PATH=TMP/lib/pkgconfig) and nothing else
 *     but the generated directory; the driver's CSV header names the
 *     model's columns; DESTDIR stages without changing the prefix;
 *   - the man page and docs/api.md document every option of `hbvmgen
 *     --help`, and --help every option of the man page;
 *   - what docs/rolled.md says `--rolled on` refuses is refused, and what
 *     it, --help and the man page say the rolled form covers (--batch) is
 *     rolled;
 *   - no source comment cites a section of the retired SPEC (docs/ is the
 *     contract), --check's output names no source file of the generator,
 *     and every relative link of README.md and of the pages in docs/ names
 *     a file that exists;
 *   - the stack bound of docs/api.md holds for the committed solvers at -O0
 *     and -O2 (gcc -fstack-usage).
 * Under the sanitizers (HBVM_SANITIZED) the installed runtime is
 * instrumented, so the programs linked with it get -fsanitize too.
 * The suite is exposed as docs_suite(); the project's runner calls it. */
#define _POSIX_C_SOURCE 200809L   /* mkdtemp, popen */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "generate.h"
#include "hbvmrt.h"

Suite *docs_suite(void);

#define SAN_FLAGS "-fsanitize=address,undefined -fno-omit-frame-pointer"

static int sanitized(void)
{
  const char *s = getenv("HBVM_SANITIZED");
  return s && *s;
}

/* Run a shell command from tests/; returns its exit status, or -1. */
static int sh(const char *cmd)
{
  int rc = system(cmd);
  if (rc == -1 || !WIFEXITED(rc))
    return -1;
  return WEXITSTATUS(rc);
}

/* The first line a command prints on stdout, into out (size bytes). */
static void first_line(const char *cmd, char *out, size_t size)
{
  FILE *p = popen(cmd, "r");
  ck_assert_msg(p != NULL, "cannot run %s", cmd);
  if (!fgets(out, (int)size, p))
    out[0] = '\0';
  while (fgetc(p) != EOF) {
  }
  ck_assert_msg(pclose(p) == 0, "%s failed", cmd);
  out[strcspn(out, "\n")] = '\0';
}

static char *fresh_dir(char *tmpl)
{
  ck_assert_msg(mkdtemp(tmpl) != NULL, "cannot create a temporary directory");
  return tmpl;
}

static void remove_dir(const char *dir)
{
  char cmd[512];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  ck_assert_int_eq(sh(cmd), 0);
}

/* The pendulum of models/pendulum.ham at t = 10 by classical RK4 on the
 * angle (theta'' = -sin theta, theta(0) = 0, theta'(0) = 1), h = 1e-4:
 * x = sin theta, y = -cos theta, accurate to about 1e-13. */
static void pendulum_reference(double *x, double *y)
{
  double th = 0, w = 1, h = 1e-4;
  for (int i = 0; i < 100000; i++) {
    double k1t = w, k1w = -sin(th);
    double k2t = w + h / 2 * k1w, k2w = -sin(th + h / 2 * k1t);
    double k3t = w + h / 2 * k2w, k3w = -sin(th + h / 2 * k2t);
    double k4t = w + h * k3w, k4w = -sin(th + h * k3t);
    th += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
    w += h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w);
  }
  *x = sin(th);
  *y = -cos(th);
}

/* Run an embedding example and check what it prints: t = 10, the
 * position within 1e-7 of the reference (HBVM(2,2), h = 0.01, order 4),
 * H and g conserved at round-off. */
static void check_example_output(const char *program)
{
  char line[256];
  double t, x, y, dH, g, xr, yr;
  first_line(program, line, sizeof line);
  ck_assert_msg(sscanf(line, "t=%lf x=%lf y=%lf dH=%lf g=%lf", &t, &x, &y, &dH, &g) == 5, "%s printed '%s'",
                program, line);
  pendulum_reference(&xr, &yr);
  ck_assert_msg(fabs(t - 10) < 1e-9, "%s: t = %g", program, t);
  ck_assert_msg(fabs(x - xr) < 1e-7 && fabs(y - yr) < 1e-7, "%s: (x, y) = (%.9f, %.9f), reference (%.9f, %.9f)",
                program, x, y, xr, yr);
  ck_assert_msg(dH <= 1e-13 && g <= 1e-13, "%s: |H - H0| = %g, |g| = %g", program, dH, g);
}

/* The whole of a file, malloc'd. */
static char *slurp(const char *path)
{
  FILE *f = fopen(path, "rb");
  ck_assert_msg(f != NULL, "cannot read %s", path);
  char *buf = calloc(1, 1 << 17);
  ck_assert_ptr_nonnull(buf);
  size_t n = fread(buf, 1, (1 << 17) - 1, f);
  ck_assert_msg(n < (1 << 17) - 1, "%s is too large", path);
  fclose(f);
  return buf;
}

/* What program prints, exactly as docs/embedding.md shows it on the
 * indented line after "    ./NAME" (NAME the program's base name). */
static void check_shown_output(const char *program)
{
  char line[256], shown[256], cmd[64];
  first_line(program, line, sizeof line);
  char *doc = slurp("../docs/embedding.md");
  snprintf(cmd, sizeof cmd, "    ./%s\n    ", strrchr(program, '/') + 1);
  const char *at = strstr(doc, cmd);
  ck_assert_msg(at != NULL, "docs/embedding.md does not show what ./%s prints", strrchr(program, '/') + 1);
  at += strlen(cmd);
  size_t n = strcspn(at, "\n");
  ck_assert_uint_lt(n, sizeof shown);
  memcpy(shown, at, n);
  shown[n] = '\0';
  ck_assert_msg(!strcmp(line, shown), "docs/embedding.md shows '%s', %s prints '%s'", shown, program, line);
  free(doc);
}

START_TEST(embedding_examples_c_and_cpp)
{
  char tmpl[] = "/tmp/hbvm-docs-XXXXXX", cmd[1024];
  const char *d = fresh_dir(tmpl);
  snprintf(cmd, sizeof cmd, "../gen/hbvmgen -o %s ../models/pendulum.ham", d);
  ck_assert_int_eq(sh(cmd), 0);
  snprintf(cmd, sizeof cmd,
           "gcc -O2 -std=c99 -Wall -Wextra -pedantic -Werror -I%s ../docs/examples/embed.c %s/pendulum.c -lm "
           "-o %s/embed", d, d, d);
  ck_assert_msg(sh(cmd) == 0, "the C example does not build: %s", cmd);
  snprintf(cmd, sizeof cmd,
           "gcc -O2 -std=c99 -Wall -Wextra -pedantic -Werror -c %s/pendulum.c -o %s/pendulum.o && "
           "g++ -O2 -Wall -Wextra -pedantic -Werror -I%s ../docs/examples/embed.cpp %s/pendulum.o -lm -o %s/embed_cpp",
           d, d, d, d, d);
  ck_assert_msg(sh(cmd) == 0, "the C++ example does not build: %s", cmd);
  snprintf(cmd, sizeof cmd, "%s/embed", d);
  check_example_output(cmd);
  check_shown_output(cmd);
  snprintf(cmd, sizeof cmd, "%s/embed_cpp", d);
  check_example_output(cmd);
  check_shown_output(cmd);
  remove_dir(d);
}
END_TEST

/* docs/embedding.md shows the example files verbatim. */
START_TEST(embedding_doc_shows_the_examples)
{
  static const char *const files[] = {"../docs/examples/embed.c", "../docs/examples/embed.cpp"};
  char *doc = slurp("../docs/embedding.md");
  for (size_t i = 0; i < 2; i++) {
    char *src = slurp(files[i]);
    ck_assert_msg(strstr(doc, src) != NULL, "docs/embedding.md does not show %s as it is", files[i]);
    free(src);
  }
  free(doc);
}
END_TEST

/* make install from the top of the tree, as this run was built. */
static void make_install(const char *vars)
{
  char cmd[1024];
  snprintf(cmd, sizeof cmd,
           "cd .. && env -u MAKEFLAGS -u MAKELEVEL -u MFLAGS make -s install %s SANITIZE=%s >/dev/null", vars,
           sanitized() ? "1" : "");
  ck_assert_msg(sh(cmd) == 0, "make install failed: %s", cmd);
}

START_TEST(install_and_pkg_config)
{
  static const char *const installed[] = {"bin/hbvmgen", "lib/libhbvmrt.a", "include/hbvmrt.h",
                                          "share/man/man1/hbvmgen.1", "lib/pkgconfig/hbvmrt.pc"};
  char tmpl[] = "/tmp/hbvm-prefix-XXXXXX", cmd[2048], vars[512], line[256];
  const char *d = fresh_dir(tmpl);
  snprintf(vars, sizeof vars, "PREFIX=%s", d);
  make_install(vars);
  for (size_t i = 0; i < sizeof installed / sizeof installed[0]; i++) {
    snprintf(cmd, sizeof cmd, "test -f %s/%s", d, installed[i]);
    ck_assert_msg(sh(cmd) == 0, "make install did not install %s", installed[i]);
  }
  /* the installed generator, then the example and a driver from pkg-config's flags alone */
  const char *pc = "PKG_CONFIG_PATH=%s/lib/pkgconfig; export PKG_CONFIG_PATH; ";
  char env[256];
  snprintf(env, sizeof env, pc, d);
  snprintf(cmd, sizeof cmd, "mkdir %s/out && %s/bin/hbvmgen --main -o %s/out ../models/pendulum.ham", d, d, d);
  ck_assert_int_eq(sh(cmd), 0);
  snprintf(cmd, sizeof cmd,
           "%s cc -O2 -std=c99 -I%s/out ../docs/examples/embed.c %s/out/pendulum.c $(pkg-config --cflags --libs hbvmrt) "
           "-o %s/embed && "
           "cc -O2 -std=c99 %s -I%s/out %s/out/pendulum.c %s/out/pendulum_main.c $(pkg-config --cflags --libs hbvmrt) "
           "-o %s/pendulum",
           env, d, d, d, sanitized() ? SAN_FLAGS : "", d, d, d, d);
  ck_assert_msg(sh(cmd) == 0, "building with pkg-config failed: %s", cmd);
  /* pkg-config links the shared runtime, which the loader finds in PREFIX/lib */
  snprintf(cmd, sizeof cmd, "LD_LIBRARY_PATH=%s/lib %s/embed", d, d);
  check_example_output(cmd);
  snprintf(cmd, sizeof cmd, "LD_LIBRARY_PATH=%s/lib %s/pendulum -h 0.1 -N 2 --quiet --csv - 2>/dev/null", d, d);
  first_line(cmd, line, sizeof line);
  ck_assert_str_eq(line, "t,x,y,p_x,p_y,lambda_1,H,g_1,hc_1");
  /* DESTDIR stages the same files; the .pc keeps the real prefix */
  snprintf(vars, sizeof vars, "DESTDIR=%s/stage PREFIX=/opt/hbvm", d);
  make_install(vars);
  snprintf(cmd, sizeof cmd, "grep -qx 'prefix=/opt/hbvm' %s/stage/opt/hbvm/lib/pkgconfig/hbvmrt.pc", d);
  ck_assert_msg(sh(cmd) == 0, "DESTDIR install: hbvmrt.pc does not name the prefix /opt/hbvm");
  remove_dir(d);
}
END_TEST

/* The options of `hbvmgen --help`: each word starting with '-' on a line
 * that starts with "  -", into opts (at most max); returns their number. */
static int help_options(char opts[][32], int max)
{
  FILE *help = popen("../gen/hbvmgen --help", "r");
  ck_assert_ptr_nonnull(help);
  char line[512];
  int n = 0;
  while (fgets(line, sizeof line, help)) {
    if (strncmp(line, "  -", 3))
      continue;
    for (char *w = strtok(line, " ,|\n"); w && w[0] == '-' && n < max; w = strtok(NULL, " ,|\n"))
      snprintf(opts[n++], 32, "%s", w);
  }
  ck_assert_int_eq(pclose(help), 0);
  return n;
}

/* Every option `hbvmgen --help` lists appears in the man page, spelt as
 * roff spells it (\- for each dash), and in docs/api.md ("The generator's
 * options", in backquotes). */
START_TEST(man_page_and_api_cover_help)
{
  char opts[64][32];
  int n = help_options(opts, 64);
  char *page = slurp("../docs/hbvmgen.1"), *api = slurp("../docs/api.md");
  for (int i = 0; i < n; i++) {
    char roff[128], quoted[64];
    size_t k = 0;
    for (const char *c = opts[i]; *c && k + 3 < sizeof roff; c++) {
      if (*c == '-')
        roff[k++] = '\\';
      roff[k++] = *c;
    }
    roff[k] = '\0';
    ck_assert_msg(strstr(page, roff) != NULL, "docs/hbvmgen.1 does not document %s", opts[i]);
    quoted[0] = '`';
    strcpy(quoted + 1, opts[i]);
    ck_assert_msg(strstr(api, quoted) != NULL, "docs/api.md does not document %s", opts[i]);
  }
  ck_assert_int_ge(n, 12);
  free(page);
  free(api);
}
END_TEST

/* Every option the man page documents (the words starting with \- on the
 * line after each .TP of its OPTIONS section) is an option of --help. */
START_TEST(help_covers_man_page)
{
  char opts[64][32], *page = slurp("../docs/hbvmgen.1");
  int nhelp = help_options(opts, 64), documented = 0;
  const char *sec = strstr(page, "\n.SH OPTIONS\n"), *end = sec ? strstr(sec + 1, "\n.SH ") : NULL;
  ck_assert_msg(sec && end, "docs/hbvmgen.1 has no OPTIONS section");
  for (const char *tp = strstr(sec, "\n.TP\n"); tp && tp < end; tp = strstr(tp + 1, "\n.TP\n")) {
    char line[256];
    const char *at = tp + 5;
    size_t len = strcspn(at, "\n");
    snprintf(line, sizeof line, "%.*s", (int)(len < sizeof line ? len : sizeof line - 1), at);
    for (char *w = strtok(line, " \","); w; w = strtok(NULL, " \",")) {
      if (strncmp(w, "\\-", 2))
        continue;
      char opt[32];
      size_t k = 0;
      for (const char *c = w; *c && k + 1 < sizeof opt; c++)
        if (*c != '\\')
          opt[k++] = *c;
      opt[k] = '\0';
      int found = 0;
      for (int i = 0; i < nhelp; i++)
        found |= !strcmp(opts[i], opt);
      ck_assert_msg(found, "docs/hbvmgen.1 documents %s, which hbvmgen --help does not list", opt);
      documented++;
    }
  }
  ck_assert_int_ge(documented, 12);
  free(page);
}
END_TEST

/* The standalone driver's options (the words starting with '-' before the
 * text on the lines of its --help that start with "  -", of a bare model of one
 * coordinate) are each in the man page's STANDALONE DRIVER section, spelt
 * as roff spells them, and in docs/api.md in backquotes: --hmax, --atol,
 * --t0, --restart (issue 31, item 5) and the rest. */
START_TEST(driver_options_documented)
{
  static const double zero[1] = {0};
  hbvmrt_model md;
  char *argv[] = {"m", "--help", NULL}, *help, line[512];
  char *page = slurp("../docs/hbvmgen.1"), *api = slurp("../docs/api.md");
  const char *sec = strstr(page, "\n.SH STANDALONE DRIVER\n"), *end = sec ? strstr(sec + 1, "\n.SH ") : NULL;
  FILE *f = tmpfile();
  int out = dup(1), n = 0;
  memset(&md, 0, sizeof md);
  md.name = "m";
  md.m = 1;
  md.state_size = md.params_size = 8;
  md.q0 = md.p0 = zero;
  ck_assert(f && out >= 0 && sec && end);
  fflush(stdout);
  dup2(fileno(f), 1);
  int rc = hbvmrt_main(&md, 2, argv);
  fflush(stdout);
  dup2(out, 1);
  close(out);
  ck_assert_int_eq(rc, 0);
  rewind(f);
  while (fgets(line, sizeof line, f)) {
    char *gap;
    if (strncmp(line, "  -", 3))
      continue;
    if ((gap = strstr(line + 2, "  ")))  /* the options end where the text after them starts */
      *gap = '\0';
    for (char *w = strtok(line, " ,|\n"); w; w = strtok(NULL, " ,|\n")) {
      char roff[64], quoted[40];
      size_t k = 0;
      if (w[0] != '-')
        continue;
      for (const char *c = w; *c && k + 3 < sizeof roff; c++) {
        if (*c == '-')
          roff[k++] = '\\';
        roff[k++] = *c;
      }
      roff[k] = '\0';
      help = strstr(sec, roff);
      ck_assert_msg(help && help < end, "docs/hbvmgen.1 (STANDALONE DRIVER) does not document the driver's %s", w);
      snprintf(quoted, sizeof quoted, "`%s", w);
      ck_assert_msg(strstr(api, quoted), "docs/api.md does not document the driver's %s", w);
      n++;
    }
  }
  ck_assert_int_ge(n, 20);
  fclose(f);
  free(page);
  free(api);
}
END_TEST

/* Source comments point at docs/, not at the retired SPEC (its "section
 * N"), and what --check prints names no source file of the generator
 * (gen/NAME.c) where a user would look for an explanation. */
START_TEST(no_pointers_to_sources)
{
  char pattern[] = "SPEC_section";
  pattern[4] = ' '; /* not written out, so that this file does not match */
  char cmd[512];
  snprintf(cmd, sizeof cmd,
           "! grep -rn -e '%s' -e 'SPEC [0-9]' ../gen ../runtime ../tests ../scripts ../bench ../Makefile "
           "--include='*.[chly]' --include='*.sh' --include=Makefile >&2",
           pattern);
  ck_assert_msg(sh(cmd) == 0, "a source comment cites the SPEC instead of docs/ (listed above)");
  static const char *const runs[] = {"../models/satellites.ham", "-s 1 ../models/satellites.ham",
                                     "../models/kepler.ham", "../models/modified.ham"};
  for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
    snprintf(cmd, sizeof cmd, "../gen/hbvmgen --check %s 2>&1 | grep -E '(gen/|\\<)[a-z_]+\\.[chly]\\>' | "
             "grep -v -E '\\<[a-z_]+\\.[ch] [0-9.]+ (MB|bytes)' >&2", runs[i]);
    ck_assert_msg(sh(cmd) != 0, "hbvmgen --check %s names a source file (above)", runs[i]);
  }
}
END_TEST

/* Every relative link [text](path) of README.md and of the pages in docs/
 * names a file that exists (from the linking file's directory). */
START_TEST(relative_links_resolve)
{
  const char *cmd =
      "cd .. && for f in README.md docs/*.md; do d=$(dirname \"$f\"); "
      "grep -o '](\\([^)#:]*\\)' \"$f\" | sed 's/^](//' | while read -r t; do "
      "[ -e \"$d/$t\" ] || { echo \"$f: no $t\" >&2; echo x; }; done; done | grep -q x";
  ck_assert_msg(sh(cmd) != 0, "README.md or docs/ link to a file that does not exist (listed above)");
}
END_TEST

/* The largest number of temporaries ("const double tN") of one function
 * of a generated source, and the sizes the bound of docs/api.md needs. */
static int max_temporaries(const char *path)
{
  FILE *f = fopen(path, "r");
  ck_assert_msg(f != NULL, "cannot read %s", path);
  char line[4096];
  int n = 0, best = 0;
  while (fgets(line, sizeof line, f)) {
    const char *c = line + strspn(line, " "); /* the fused step's sweep is indented deeper */
    if (c > line && !strncmp(c, "const double t", 14))
      n++;
    if (line[0] == '}') {
      if (n > best)
        best = n;
      n = 0;
    }
  }
  fclose(f);
  return best;
}

/* Sum of the step's frame and of the largest other frame, from gcc's
 * -fstack-usage file of the solver compiled at opt. */
static long stack_used(const char *dir, const char *solver, const char *opt)
{
  char cmd[2048], su[512], line[1024], here[1024];
  ck_assert_ptr_nonnull(getcwd(here, sizeof here));
  snprintf(cmd, sizeof cmd, "cd %s && gcc %s -std=c99 -fstack-usage -c %s/../generated/%s.c -o %s.o", dir, opt,
           here, solver, solver);
  ck_assert_msg(sh(cmd) == 0, "%s", cmd);
  snprintf(su, sizeof su, "%s/%s.su", dir, solver);
  FILE *f = fopen(su, "r");
  ck_assert_msg(f != NULL, "no %s", su);
  long step = 0, other = 0;
  while (fgets(line, sizeof line, f)) {
    char *tab = strchr(line, '\t');
    ck_assert_ptr_nonnull(tab);
    long bytes = strtol(tab + 1, NULL, 10);
    *tab = '\0';
    size_t len = strlen(line);
    if (len > 5 && !strcmp(line + len - 5, "_step"))
      step = bytes;
    else if (bytes > other)
      other = bytes;
  }
  fclose(f);
  ck_assert_int_gt(step, 0);
  return step + other;
}

START_TEST(stack_bound_holds)
{
  static const struct {
    const char *solver;
    int m, nu, s;
  } cases[] = {{"pendulum_k2s2", 2, 1, 2}, {"satellites_k6s3", 9, 3, 3}, {"kepler_k16s2", 2, 0, 2}};
  static const char *const opts[] = {"-O0", "-O2"};
  char tmpl[] = "/tmp/hbvm-stack-XXXXXX", path[512];
  const char *d = fresh_dir(tmpl);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    snprintf(path, sizeof path, "../generated/%s.c", cases[i].solver);
    long T = max_temporaries(path), s = cases[i].s, m = cases[i].m, nu = cases[i].nu;
    long bound = 8 * (2 * T + 3 * s * m + 2 * m + 7 * nu + 2) + 256;
    for (size_t k = 0; k < 2; k++) {
      long used = stack_used(d, cases[i].solver, opts[k]);
      ck_assert_msg(used <= bound, "%s at %s: %ld bytes of stack, the documented bound is %ld", cases[i].solver,
                    opts[k], used, bound);
    }
  }
  remove_dir(d);
}
END_TEST

/* Whether word occurs in the text from a to b. */
static int span_has(const char *a, const char *b, const char *word)
{
  size_t n = strlen(word);
  for (const char *p = a; p + n <= b; p++)
    if (!strncmp(p, word, n)) return 1;
  return 0;
}

/* The rolled form's coverage (docs/rolled.md, --help, docs/hbvmgen.1) is
 * the generator's: each option of rolled.md's bullet under "`--rolled on`
 * refuses" is refused with --rolled on on the chain of 8, and --batch,
 * which all three say is covered, is rolled. */
START_TEST(rolled_coverage_documented)
{
  char *doc = slurp("../docs/rolled.md"), *man = slurp("../docs/hbvmgen.1"), *chain = slurp("../models/chain8.ham");
  char flags[160], help[8192];
  ck_assert(doc && man && chain);
  const char *list = strstr(doc, "`--rolled on` refuses"), *q;
  ck_assert_ptr_nonnull(list);
  list = strstr(list, "\n- `");
  ck_assert_ptr_nonnull(list);
  const char *end = strchr(list + 1, '\n');
  int refused = 0;
  for (const char *p = strchr(list, '`'); p && p < end && (q = strchr(p + 1, '`')); p = strchr(q + 1, '`')) {
    snprintf(flags, sizeof flags, "-s 2 --rolled on %.*s", (int)(q - p - 1), p + 1);
    ck_assert_msg(!generate_source(chain, flags), "docs/rolled.md says --rolled on refuses %.*s; it did not",
                  (int)(q - p - 1), p + 1);
    refused++;
  }
  ck_assert_int_ge(refused, 1); /* (--wide-step; Newton with constraints is covered since the rolled saddle point) */
  char *b = generate_source(chain, "-s 2 --rolled on --batch 2");
  ck_assert_msg(b && strstr(b, "(rolled)"), "the rolled form does not cover --batch");
  free(b);
  ck_assert_msg(strstr(doc, "`--batch W`") && !span_has(list, end, "--batch"), "docs/rolled.md: --batch is covered");
  ck_assert_int_eq(generator_output("--help", help, sizeof help), 0);
  const char *entry = strstr(help, "--rolled auto|on|off"), *next = entry ? strstr(entry, "\n  -") : NULL;
  ck_assert_msg(entry && next && span_has(entry, next, "--batch"), "--help: --rolled covers --batch");
  const char *mentry = strstr(man, "\\-\\-rolled \" auto|on|off\""), *mnext = mentry ? strstr(mentry, ".TP") : NULL;
  ck_assert_msg(mentry && mnext && span_has(mentry, mnext, "\\-\\-batch"), "docs/hbvmgen.1: --rolled covers --batch");
  free(doc), free(man), free(chain);
}
END_TEST

Suite *docs_suite(void)
{
  Suite *s = suite_create("docs");
  TCase *tc = tcase_create("docs");
  tcase_set_tags(tc, "sanlong"); /* builds as a user does: sanitized in check-long */
  tcase_set_timeout(tc, 300);
  tcase_add_test(tc, embedding_examples_c_and_cpp);
  tcase_add_test(tc, embedding_doc_shows_the_examples);
  tcase_add_test(tc, install_and_pkg_config);
  tcase_add_test(tc, man_page_and_api_cover_help);
  tcase_add_test(tc, help_covers_man_page);
  tcase_add_test(tc, rolled_coverage_documented);
  tcase_add_test(tc, driver_options_documented);
  tcase_add_test(tc, no_pointers_to_sources);
  tcase_add_test(tc, relative_links_resolve);
  tcase_add_test(tc, stack_bound_holds);
  suite_add_tcase(s, tc);
  return s;
}
