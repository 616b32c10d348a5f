/* check_ensemble.c - the ensemble runner (runtime/ensemble.c): the summary
 * file of --ensemble and --sweep is byte for byte the same for the scalar
 * step and --batch W (W = 1, 3, 4), on 1 and 2 OpenMP threads (also with a
 * mass matrix M(q): models/double_pendulum_angles.ham, and with Newton: the
 * stiff bob), and on 1 and 2 MPI
 * ranks (mpirun -np 2 on loopback; skipped, saying so, without MPI);
 * a trajectory ends where a single run ends (-T hit exactly, --tol); a
 * rolled model (--rolled on, docs/rolled.md) gives the same summary with
 * --batch W as without, on 2 threads and 2 MPI ranks, and the straight-line
 * form's rows to the reordering of sums. */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "generate.h"

static char dir[] = "/tmp/hbvm-ens-XXXXXX";

static int sh(const char *cmd)
{
  int rc = system(cmd);
  return rc == -1 || !WIFEXITED(rc) ? -1 : WEXITSTATUS(rc);
}

/* Generate NAME from model with flags; build its driver with cc against
 * runtime/libhbvmrt_omp.a (-fopenmp), or with mpicc against the runtime
 * compiled for MPI. */
static void build(const char *name, const char *model, const char *flags, int mpi)
{
  char cmd[2048];
  const char *san = getenv("HBVM_SANITIZED") && *getenv("HBVM_SANITIZED") && !mpi
                        ? "-fsanitize=address,undefined -fno-omit-frame-pointer" : "";
  snprintf(cmd, sizeof cmd,
           "../gen/hbvmgen %s --main -n %s -o %s %s 2>/dev/null && %s -O2 -std=c99 -Wall -Wextra -pedantic -Werror "
           "-fopenmp %s -I../runtime -I%s %s/%s.c %s/%s_main.c %s -lm -o %s/%s",
           flags, name, dir, model, mpi ? "mpicc -DHBVMRT_MPI" : "cc", san, dir, dir, name, dir, name,
           mpi ? "../runtime/*.c" : "../runtime/libhbvmrt_omp.a", dir, name);
  ck_assert_msg(sh(cmd) == 0, "cannot build: %s", cmd);
}

/* Run dir/name with args, the summary into dir/out; returns the file. */
static char *run(const char *launch, const char *name, const char *args, const char *out, int status)
{
  char cmd[2048], path[256];
  snprintf(path, sizeof path, "%s/%s", dir, out);
  snprintf(cmd, sizeof cmd, "%s %s/%s %s --csv %s 2>%s/err.txt", launch, dir, name, args, path, dir);
  int rc = sh(cmd);
  ck_assert_msg(rc == status, "%s: exit status %d, expected %d", cmd, rc, status);
  char *text = read_text(path);
  ck_assert_ptr_nonnull(text);
  return text;
}

/* The pendulum from rest at 8 angles, a row with momenta that no step of
 * h = 0.1 or its halves converges from (status 1), one off the constraint
 * (-1), and one whose steps of 0.1 fail but their halves, 256 times
 * smaller, do (a batch lane that leaves for the scalar path). */
static const char rows[] =
    "x, y, p_x, p_y\n"
    "0.1, -0.99498743710661997, 0, 0\n0.2, -0.9797958971132712, 0, 0\n0.3, -0.95393920141694566, 0, 0\n"
    "0.4, -0.91651513899116799, 0, 0\n0.5, -0.8660254037844386, 0, 0\n0.6, -0.8, 0, 0\n"
    "# a comment line\n"
    "0, -1, 1e7, 0\n0.7, -0.71414284285428498, 0, 0\n0, -1.5, 0, 0\n0.8, -0.6, 0, 0\n0, -1, 3000, 0\n";

/* Whether trajectory traj's row of the summary text ends with tail (its
 * input columns: issue 31 item 8). */
static int row_ends_with(const char *text, int traj, const char *tail)
{
  char key[32];
  snprintf(key, sizeof key, "\n%d,", traj);
  const char *row = strstr(text, key), *end = row ? strchr(row + 1, '\n') : NULL;
  size_t n = strlen(tail);
  return end && (size_t)(end - row) > n && !strncmp(end - n, tail, n);
}

START_TEST(test_independent_of_w_and_threads)
{
  static const char *const flags[] = {"-s 2", "-s 2 --batch 1", "-s 2 --batch 3", "-s 2 --batch 4"};
  char path[256], name[32], *ref = NULL;
  snprintf(path, sizeof path, "%s/rows.csv", dir);
  FILE *f = fopen(path, "w");
  ck_assert_ptr_nonnull(f);
  fputs(rows, f);
  fclose(f);
  for (int i = 0; i < 4; i++) {
    snprintf(name, sizeof name, "pend%d", i);
    build(name, "../models/pendulum.ham", flags[i], 0);
    for (int t = 1; t <= 2; t++) {
      char args[512];
      snprintf(args, sizeof args, "--ensemble %s -h 0.1 -N 100 --threads %d", path, t);
      char *got = run("", name, args, "ens.csv", 2); /* a trajectory failed */
      if (!ref) {
        ref = got;
        ck_assert_ptr_nonnull(strstr(ref, "traj,status,steps,t,x,y,p_x,p_y,lambda_1,H,max_dH,max_g,max_hc,"));
        ck_assert_ptr_nonnull(strstr(ref, "\n7,1,0,0,0,-1,10000000,0,")); /* ENOCONV at the first step */
        ck_assert_ptr_nonnull(strstr(ref, "\n11,0,25600,")); /* 100 steps of 0.1 in halves of halves */
        ck_assert_ptr_nonnull(strstr(ref, "\n9,-1,0,0,0,-1.5,0,0,")); /* off the constraint: not run */
        ck_assert_ptr_nonnull(strstr(ref, "\n10,0,100,"));
        /* each row ends with the input's values, named apart from the final state */
        ck_assert_ptr_nonnull(strstr(ref, ",iters_mean,iters_max,x(0),y(0),p_x(0),p_y(0)\n"));
        ck_assert_msg(row_ends_with(ref, 7, ",0,-1,10000000,0"), "%s", ref);
        ck_assert_msg(row_ends_with(ref, 9, ",0,-1.5,0,0"), "%s", ref);
        /* the summary line counts the trajectories whose steps were retried as
         * halves (7, which fails even so, and 11), as a single run says it */
        snprintf(path, sizeof path, "%s/err.txt", dir);
        char *err = read_text(path);
        ck_assert_ptr_nonnull(err);
        ck_assert_msg(strstr(err, "trajectories=11 ok=9 failed=2 halved=2 steps=100 "), "summary: %s", err);
        free(err);
        snprintf(path, sizeof path, "%s/rows.csv", dir);
        continue;
      }
      ck_assert_msg(!strcmp(got, ref), "%s with %d threads: the summary differs", flags[i], t);
      free(got);
    }
  }
  free(ref);
}
END_TEST

/* The launcher of the runs on 2 MPI ranks (loopback). */
static const char mpirun[] = "OMPI_MCA_btl=self,vader OMPI_MCA_plm_rsh_agent=false timeout 120 mpirun --allow-run-as-root "
                             "--oversubscribe -np 2";

/* Whether MPI is installed; says so on stderr when it is not. */
static int have_mpi(void)
{
  if (sh("command -v mpicc >/dev/null && command -v mpirun >/dev/null") == 0) return 1;
  fprintf(stderr, "check_ensemble: MPI is not installed (scripts/deps.sh mpi): the test on 2 ranks is skipped\n");
  return 0;
}

START_TEST(test_sweep_and_mpi)
{
  char *one, *got;
  build("mp", "models/mass_param.ham", "-s 2", 0);
  build("mpb", "models/mass_param.ham", "-s 2 --batch 4", 0);
  one = run("", "mp", "--sweep m1=1:3:11 -h 0.05 -N 200 --threads 1", "s1.csv", 0);
  ck_assert_ptr_nonnull(strstr(one, "\n11,0,200,10,"));
  ck_assert_ptr_nonnull(strstr(one, ",iters_mean,iters_max,m1\n")); /* the swept param, by row */
  ck_assert_msg(row_ends_with(one, 1, ",1") && row_ends_with(one, 2, ",1.2") && row_ends_with(one, 11, ",3"), "%s",
                one);
  got = run("", "mpb", "--sweep m1=1:3:11 -h 0.05 -N 200 --threads 2", "s2.csv", 0);
  ck_assert_msg(!strcmp(got, one), "--sweep with --batch 4 on 2 threads differs");
  free(got);
  if (!have_mpi()) {
    free(one);
    return;
  }
  build("mpm", "models/mass_param.ham", "-s 2 --batch 4", 1);
  build("mps", "models/mass_param.ham", "-s 2", 1);
  got = run(mpirun, "mpm", "--sweep m1=1:3:11 -h 0.05 -N 200 --threads 1", "s3.csv", 0);
  ck_assert_msg(!strcmp(got, one), "--sweep with --batch 4 on 2 MPI ranks differs");
  free(got);
  got = run(mpirun, "mps", "--sweep m1=1:3:11 -h 0.05 -N 200 --threads 2", "s4.csv", 0);
  ck_assert_msg(!strcmp(got, one), "--sweep, scalar, on 2 MPI ranks of 2 threads differs");
  free(got);
  free(one);
}
END_TEST

/* The first n fields of the last line of text, with their commas, into buf. */
static void last_fields(const char *text, int n, char *buf, size_t size)
{
  size_t len = strlen(text), i = 0;
  while (len > 0 && text[len - 1] == '\n') len--;
  const char *line = text + len;
  while (line > text && line[-1] != '\n') line--;
  for (int commas = 0; line + i < text + len && i + 1 < size && commas < n; i++) {
    buf[i] = line[i];
    commas += line[i] == ',';
  }
  buf[i] = 0;
}

/* A trajectory of an ensemble ends where a single run of the driver ends:
 * on T exactly with -T (the last step shortened: -h 0.3 -T 10 is 33 steps
 * of 0.3 and one of 0.1) and with --tol (adaptive steps, each trajectory its
 * own even with --batch), bitwise, for the scalar step and --batch 4. */
START_TEST(test_span_and_tol)
{
  static const char *const how[] = {"-h 0.3 -T 10", "--tol 1e-8 -T 10"};
  build("ps", "../models/pendulum.ham", "-s 2", 0);
  build("pb", "../models/pendulum.ham", "-s 2 --batch 4", 0);
  for (int i = 0; i < 2; i++) {
    char args[256], single[256], want[300];
    snprintf(args, sizeof args, "--sweep p_x=0.5:1:5 %s --threads 2", how[i]);
    char *ens = run("", "ps", args, "e1.csv", 0), *bat = run("", "pb", args, "e2.csv", 0);
    ck_assert_msg(!strcmp(ens, bat), "%s: --batch 4 differs from the scalar step", args);
    snprintf(args, sizeof args, "--p0 0.5,0 %s", how[i]);
    char *one = run("", "ps", args, "one.csv", 0);
    last_fields(one, 7, single, sizeof single); /* t,x,y,p_x,p_y,lambda_1,H, */
    ck_assert_msg(!strncmp(single, "10,", 3), "%s: the single run ends at %s", args, single);
    snprintf(want, sizeof want, "\n1,0,%s,%s", i ? "" : "34", single);
    if (i) { /* the adaptive run's number of steps is its own: find the row by its state */
      char *row = strstr(ens, "\n1,0,");
      ck_assert_ptr_nonnull(row);
      row = strchr(row + 5, ',');
      ck_assert_msg(row && !strncmp(row + 1, single, strlen(single)), "%s: trajectory 1 is not the single run's %s",
                    how[i], single);
    } else {
      ck_assert_msg(strstr(ens, want) != NULL, "%s: trajectory 1 is not the single run's %s", how[i], single);
    }
    free(ens), free(bat), free(one);
  }
}
END_TEST

/* Builds NAMEs (generated with flags) and NAMEb (flags --batch 4) and runs
 * both with each of the two argument lists how[i] (%s: the file rows_text,
 * if any, is written to): the summaries byte for byte the same, the exit
 * status status[i]. one[i] gets the scalar step's summary (free it). */
static void same_with_batch(const char *name, const char *model, const char *flags, const char *rows_text,
                            const char *const how[2], const int status[2], char *one[2])
{
  char path[256], args[512], sname[64], bname[64], bflags[256];
  snprintf(path, sizeof path, "%s/%s.csv", dir, name);
  if (rows_text) {
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs(rows_text, f);
    fclose(f);
  }
  snprintf(sname, sizeof sname, "%ss", name);
  snprintf(bname, sizeof bname, "%sb", name);
  snprintf(bflags, sizeof bflags, "%s --batch 4", flags);
  build(sname, model, flags, 0);
  build(bname, model, bflags, 0);
  for (int i = 0; i < 2; i++) {
    snprintf(args, sizeof args, how[i], path);
    char *bat = run("", bname, args, "m2.csv", status[i]);
    one[i] = run("", sname, args, "m1.csv", status[i]);
    ck_assert_msg(!strcmp(one[i], bat), "%s %s: --batch 4 differs from the scalar step", flags, args);
    free(bat);
  }
}

/* M(q) (models/double_pendulum_angles.ham, k = s = 2): --ensemble with fixed
 * steps, where one trajectory's steps are retried as halves (a lane that
 * leaves the batch for the scalar path) and one fails, and --sweep with
 * adaptive steps: the summary of --batch 4 is the scalar step's, byte for
 * byte; the same for the four-bar in angles (M(q) and constraints, whose
 * lanes take the scalar step) swept over a mass and over gravity. */
START_TEST(test_mass_q)
{
  static const char mq_rows[] = "th1, th2, p_th1, p_th2\n0.5, -0.3, 0, 0\n1, 0.5, 0.2, 0\n2, -1, 0, 0.5\n"
                                "0.5, -0.3, 0, 100\n0.5, -0.3, 0, 1e7\n0.1, 0.1, 0, 0\n";
  static const char *const how[] = {"--ensemble %s -h 0.05 -N 200 --threads 2",
                                    "--sweep p_th2=0:3:7 --tol 1e-9 -T 5 --threads 2"};
  static const int status[] = {2, 0};
  char *one[2];
  same_with_batch("dp", "../models/double_pendulum_angles.ham", "-s 2", mq_rows, how, status, one);
  ck_assert_ptr_nonnull(strstr(one[0], "\n4,0,")); /* from p_th2 = 100: in halves */
  ck_assert_ptr_nonnull(strstr(one[0], "\n5,2,0,")); /* ENONFINITE at the first step */
  ck_assert_ptr_nonnull(strstr(one[0], "\n6,0,200,10,"));
  free(one[0]), free(one[1]);
  /* M(q) with constraints (the four-bar in angles): the lanes take the scalar step */
  static const char *const fb_how[] = {"--sweep m3=1:3:5 -h 0.05 -N 100 --threads 2",
                                       "--sweep grav=0.5:2:4 --tol 1e-9 -T 3 --threads 2"};
  static const int fb_status[] = {0, 0};
  same_with_batch("fb", "../models/fourbar_angles.ham", "-s 2", NULL, fb_how, fb_status, one);
  ck_assert_ptr_nonnull(strstr(one[0], "\n5,0,100,5,")); /* m3 = 3: 100 steps to t = 5 */
  ck_assert_ptr_nonnull(strstr(one[1], "\n4,0,")); /* grav = 2: adaptive, to T */
  free(one[0]), free(one[1]);
}
END_TEST

/* Newton (issue 27): the stiff bob swept over k = 1e4..1e6 (omega = 141..1414)
 * with fixed steps of 0.3 (h omega = 42..424), where the stiffer trajectories'
 * steps fail and are retried as halves (lanes that leave the batch), and with
 * adaptive steps: --batch 4 gives the scalar step's summary, byte for byte, in
 * the constant family under --iteration newton and in the poly family under
 * auto (which emits Newton for the stiff bob). */
START_TEST(test_newton)
{
  static const char *const how[] = {"--sweep k=1e4:1e6:7 -h 0.3 -N 20 --threads 2",
                                    "--sweep k=1e4:1e5:3 --tol 1e-6 -T 0.2 --threads 2"};
  static const int status[] = {0, 0};
  char *one[2];
  same_with_batch("bn", "../models/stiff_bob.ham", "-s 2 --iteration newton --multiplier const", NULL, how, status, one);
  ck_assert_ptr_nonnull(strstr(one[0], "\n1,0,20,6,")); /* k = 1e4: 20 steps of 0.3 */
  ck_assert_ptr_nonnull(strstr(one[0], "\n7,0,")); /* k = 1e6: in halves */
  ck_assert_ptr_null(strstr(one[0], "\n7,0,20,"));
  free(one[0]), free(one[1]);
  same_with_batch("ba", "../models/stiff_bob.ham", "-s 2", NULL, how, status, one);
  free(one[0]), free(one[1]);
}
END_TEST

/* The largest difference between the summaries a and b (the same header and
 * trajectories) in the columns t .. H of a row (its final state, multiplier
 * and energy); each row's trajectory, status and steps must be equal. The
 * other columns are round-off's maxima and iteration counts. */
static double rows_apart(const char *a, const char *b)
{
  const char *h = strstr(a, ",max_dH,");
  ck_assert_ptr_nonnull(h);
  int ncol = 0;
  for (const char *c = a; c < h; c++) ncol += *c == ',';
  double worst = 0;
  const char *ra = strchr(a, '\n'), *rb = strchr(b, '\n');
  for (; ra && rb && ra[1] && rb[1]; ra = strchr(ra + 1, '\n'), rb = strchr(rb + 1, '\n')) {
    char *pa = (char *)ra + 1, *pb = (char *)rb + 1;
    for (int k = 0; k <= ncol; k++) {
      double x = strtod(pa, &pa), y = strtod(pb, &pb);
      if (k < 3) ck_assert_msg(x == y, "column %d of a row: %g, %g", k + 1, x, y);
      else worst = fmax(worst, fabs(x - y));
      ck_assert(*pa == ',' && *pb == ',');
      pa++, pb++;
    }
  }
  ck_assert_msg(!ra == !rb, "not the same number of rows");
  return worst;
}

/* A rolled model (issue 29): the chain of 8 pendula rolled (--rolled on),
 * both multiplier families, swept over the last mass's initial momentum with
 * fixed and adaptive steps. The rolled batch lanes are the rolled step
 * bitwise, so --batch 4 (const) and 3 (poly) on 2 threads, and on 2 MPI
 * ranks, write the scalar run's summary byte for byte; the straight-line
 * form's rows agree to the reordering bound of docs/rolled.md with fixed
 * steps, and to the runs' error with --tol (below). */
START_TEST(test_rolled)
{
  static const char *const how[] = {"--sweep 'p_y[8]=0:0.5:7' -h 0.01 -N 200 --threads 2",
                                    "--sweep 'p_y[8]=0:0.5:7' --tol 1e-8 -T 2 --threads 2"};
  static const char *const fam[] = {"--multiplier const", ""};
  /* fixed steps: the reordering bound; --tol: the two forms choose their steps
   * from estimates that differ by round-off, so each is a run within its own
   * error, at most 30 tol (1 + max|q|) at T as the adaptive suite bounds it
   * (max|q| <= 8 on the chain): twice that apart */
  static const double bound[] = {1e-9, 60 * 1e-8 * 9};
  char flags[256];
  for (int f = 0; f < 2; f++) {
    snprintf(flags, sizeof flags, "-s 2 %s --rolled on", fam[f]);
    build("crs", "../models/chain8.ham", flags, 0);
    snprintf(flags, sizeof flags, "-s 2 %s --rolled on --batch %d", fam[f], f ? 3 : 4);
    build("crb", "../models/chain8.ham", flags, 0);
    snprintf(flags, sizeof flags, "-s 2 %s --rolled off", fam[f]);
    build("cst", "../models/chain8.ham", flags, 0);
    for (int i = 0; i < 2; i++) {
      char *one = run("", "crs", how[i], "r1.csv", 0), *bat = run("", "crb", how[i], "r2.csv", 0);
      char *str = run("", "cst", how[i], "r3.csv", 0);
      ck_assert_ptr_nonnull(strstr(one, "\n7,0,"));
      ck_assert_msg(!strcmp(one, bat), "%s %s: the rolled --batch differs from the rolled step", fam[f], how[i]);
      double d = rows_apart(one, str);
      printf("ensemble: chain 8 %s, %s: rolled vs straight-line rows within %.2g\n", f ? "poly" : "const", how[i], d);
      ck_assert_msg(d <= bound[i], "%s %s: rolled and straight-line rows differ by %g", fam[f], how[i], d);
      free(one), free(bat), free(str);
    }
    if (f == 0 && have_mpi()) { /* the rolled batch on 2 MPI ranks */
      build("crm", "../models/chain8.ham", "-s 2 --multiplier const --rolled on --batch 4", 1);
      char *one = run("", "crs", how[0], "r1.csv", 0), *got = run(mpirun, "crm", how[0], "r4.csv", 0);
      ck_assert_msg(!strcmp(one, got), "%s: the rolled --batch on 2 MPI ranks differs", how[0]);
      free(one), free(got);
    }
  }
}
END_TEST

START_TEST(test_errors)
{
  char cmd[512];
  build("pe", "../models/pendulum.ham", "-s 2 --batch 2", 0);
  static const char *const bad[] = {"--sweep z=0:1:3", "--sweep x=0:1", "--ensemble /nonexistent.csv",
                                    "--sweep x=0:1:3 --ensemble a.csv", "--sweep x=0:1:3 --threads 0",
                                    "--sweep x=0:1:3 --dt 0.1", "--sweep x=0:1:3 --every 2", "--sweep1"};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    snprintf(cmd, sizeof cmd, "%s/pe %s -N 1 2>/dev/null", dir, bad[i]);
    ck_assert_msg(sh(cmd) == 1, "%s: expected exit status 1", bad[i]);
  }
  /* a value that starts like --sweep (a CSV file named --sweep1) is no ensemble:
   * it was taken for one without its input, and the driver died of a NULL
   * (tests/fuzz/fuzz_runtime.c) */
  snprintf(cmd, sizeof cmd, "cd %s && ./pe -N 1 --csv --sweep1 2>/dev/null && test -s ./--sweep1", dir);
  ck_assert_msg(sh(cmd) == 0, "%s: expected a run writing the CSV --sweep1", cmd);
  /* --sweep N allocated 8 N bytes at once, N up to 1e9: now at most 1e7 */
  snprintf(cmd, sizeof cmd, "%s/pe --sweep x=0:1:10000001 -N 1 2>%s/err.txt", dir, dir);
  ck_assert_int_eq(sh(cmd), 1);
  snprintf(cmd, sizeof cmd, "%s/err.txt", dir);
  char *err = read_text(cmd);
  ck_assert_msg(err && strstr(err, "pe: error: --sweep: 10000001 trajectories, at most 10000000"), "%s", err);
  free(err);
}
END_TEST

/* The ensemble file in.csv of n bytes, run with -N 1 as --ensemble in.csv
 * (or --ensemble=in.csv when attached): the exit status, and the first line
 * of stderr in line (size bytes). */
static int run_input(const char *bytes, size_t n, int attached, char *line, size_t size)
{
  char cmd[1024], path[256];
  snprintf(path, sizeof path, "%s/in.csv", dir);
  FILE *f = fopen(path, "wb");
  ck_assert_ptr_nonnull(f);
  ck_assert_uint_eq(fwrite(bytes, 1, n, f), n);
  fclose(f);
  snprintf(cmd, sizeof cmd, "%s/pe --ensemble%s%s -N 1 --csv %s/out.csv 2>%s/err.txt", dir, attached ? "=" : " ", path,
           dir, dir);
  int rc = sh(cmd);
  snprintf(path, sizeof path, "%s/err.txt", dir);
  char *err = read_text(path);
  ck_assert_ptr_nonnull(err);
  snprintf(line, size, "%.*s", (int)strcspn(err, "\n"), err);
  free(err);
  return rc;
}

/* The ensemble file's malformed inputs, each an error naming the file, the
 * line and the column (status 1), and the line ends and marks that are
 * fine: CR alone (which dropped every row: trajectories=0, exit 0), CR LF,
 * a UTF-8 BOM (which made the first column unknown), --ensemble=F (which
 * was refused). A header alone, a repeated column, a NUL byte exited 0. */
START_TEST(test_input_file)
{
#define ROW1 "0.6, -0.8, 0, 0"
#define ROW2 "0.8, -0.6, 0, 0"
  static const struct {
    const char *bytes;
    size_t n;
    const char *want; /* stderr's first line from "in.csv" on, or "" for success (2 trajectories) */
  } cases[] = {
      {"x,y,p_x,p_y\r" ROW1 "\r" ROW2 "\r", 0, ""},
      {"x,y,p_x,p_y\r\n" ROW1 "\r\n\r\n" ROW2, 0, ""},
      {"\xEF\xBB\xBFx,y,p_x,p_y\n" ROW1 "\n" ROW2 "\n", 0, ""},
      {"# no rows\nx,y,p_x,p_y\n\n", 0, "in.csv: no trajectories: the header (line 2) and no rows"},
      {"", 0, "in.csv: no header line (column names)"},
      {"x,y,x\n0,-1,0\n", 0, "in.csv:1:5: column 'x' given twice (first at column 1)"},
      {"x, y ,p_x,p_y\n" ROW1 "\n0.8, -0.6\0, 0, 0\n", 47, "in.csv:3:10: a NUL byte"},
      {"x,y,p_x,p_y\n" ROW1 "\n0.8,abc,0,0\n", 0, "in.csv:3:5: 'abc' is not a finite number"},
      {"x,y,p_x,p_y\n" ROW1 "\n0.8,-0.6,0\n", 0, "in.csv:3:11: expected 4 numbers, got 3"},
      {"x,y,p_x,p_y\n" ROW1 ",5\n", 0, "in.csv:2:16: expected 4 numbers, got more"},
      {"x,y,p_x,p_y\n" ROW1 "\n0.8,,0,0\n", 0, "in.csv:3:5: an empty field (expected 4 numbers)"},
      {"x,y,p_x,p_y\n0.6 0.1,-0.8,0,0\n", 0, "in.csv:2:5: expected a comma"},
      {"x,y,p_x,p_y\n0.6,nan,0,0\n", 0, "in.csv:2:5: 'nan' is not a finite number"},
      {"x,,p_x\n", 0, "in.csv:1:3: column 2 has no name"},
      {"x, zz\n1,2\n", 0, "in.csv:1:4: unknown column 'zz'"},
  };
  char line[1024], want[1100];
  build("pe", "../models/pendulum.ham", "-s 2 --batch 2", 0);
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    size_t n = cases[i].n ? cases[i].n : strlen(cases[i].bytes);
    int rc = run_input(cases[i].bytes, n, 0, line, sizeof line);
    if (!*cases[i].want) {
      ck_assert_msg(rc == 0 && strstr(line, "trajectories=2 ok=2 "), "case %zu: exit %d, %s", i, rc, line);
      continue;
    }
    snprintf(want, sizeof want, "pe: error: %s/%s", dir, cases[i].want);
    ck_assert_msg(rc == 1 && !strncmp(line, want, strlen(want)), "case %zu: exit %d, '%s', not '%s'", i, rc, line,
                  want);
  }
  ck_assert_int_eq(run_input(cases[0].bytes, strlen(cases[0].bytes), 1, line, sizeof line), 0);
  ck_assert_msg(strstr(line, "trajectories=2 ok=2 "), "%s", line);
#undef ROW1
#undef ROW2
}
END_TEST

static void setup(void)
{
  ck_assert_ptr_nonnull(mkdtemp(dir));
}

static void teardown(void)
{
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  if (sh(cmd) != 0)
    fprintf(stderr, "check_ensemble: could not remove %s\n", dir);
  strcpy(dir, "/tmp/hbvm-ens-XXXXXX");
}

Suite *ensemble_suite(void)
{
  Suite *s = suite_create("ensemble");
  TCase *widths = tcase_create("batch widths");
  tcase_set_tags(widths, "sanlong"); /* four batch solvers compiled: sanitized in check-long */
  tcase_add_checked_fixture(widths, setup, teardown);
  tcase_set_timeout(widths, 300);
  tcase_add_test(widths, test_independent_of_w_and_threads);
  suite_add_tcase(s, widths);
  TCase *models = tcase_create("models");
  tcase_set_tags(models, "sanlong"); /* M(q), rolled and Newton solvers compiled: sanitized in check-long */
  tcase_add_checked_fixture(models, setup, teardown);
  tcase_set_timeout(models, 300);
  tcase_add_test(models, test_mass_q);
  tcase_add_test(models, test_rolled);
  tcase_add_test(models, test_newton);
  suite_add_tcase(s, models);
  TCase *tc = tcase_create("ensemble");
  tcase_add_checked_fixture(tc, setup, teardown);
  tcase_set_timeout(tc, 300);
  tcase_add_test(tc, test_sweep_and_mpi);
  tcase_add_test(tc, test_span_and_tol);
  tcase_add_test(tc, test_errors);
  tcase_add_test(tc, test_input_file);
  suite_add_tcase(s, tc);
  return s;
}
