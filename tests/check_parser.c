/* check_parser.c - Check suite for the front end (gen/lexer.l, parser.y,
 * ast.c, mass.c) and the command line (gen/main.c).
 *
 * Small models, one per statement form of docs/language.md, go through the
 * front end in-process (diag_begin, parse_model, analyse,
 * model_differentiate); each test asserts what the analysed Model holds:
 * m, nu, degrees, the kind of M and its inverse, q0 and p0, and the values
 * of U and g at a point (dag_eval). Table-driven cases cover the twenty
 * functions, operator precedence and number formats.
 * The command line is run as ../gen/hbvmgen (the suite runs from tests/):
 * the first line of --check on each model in models/ for s = 1, 2, 3,
 * --help, --version and bad options; models/solar.ham (def, double sums
 * and comprehensions) and tests/models/solar_plain.ham (the same written
 * out) generate the same C.
 * The suite is exposed as parser_suite(); the project's runner calls it. */
#define _POSIX_C_SOURCE 200809L   /* popen, pclose, dup */

#include <check.h>
#include <ctype.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "generate.h"
#include "hbvmgen.h"

// P_j(x) = sqrt(2j+1) L_j(2x-1), by the recurrence (the test's own).
static double shifted_legendre(int j, double x) {
  double t = 2 * x - 1, prev = 0, cur = 1;
  for (int n = 0; n < j; n++) {
    double next = n == 0 ? t : ((2 * n + 1) * t * cur - n * prev) / (n + 1);
    prev = cur;
    cur = next;
  }
  return sqrt(2.0 * j + 1) * cur;
}

// The warm start's E_ji(r) = sum_d E[(j*s+i)*s+d] r^d = int_0^1 P_j(x)
// P_i(1 + r x) dx: its zero coefficients exactly 0 (d < j or d > i), the
// diagonal exactly r^j, so that a same-size start copies gamma_j, and at
// r = 1/2 the integral by the method's own Gauss nodes (exact for this
// degree) within the quadrature's round-off, 64 ulps of the sum of its
// terms' magnitudes (they cancel: E_45(1/2) = 0.93 for s = 7 from terms
// of magnitudes summing to 173).
START_TEST(test_warm_start_table)
{
  for (int s = 1; s <= 12; s++) {
    Method *me = method_new(s, s, MULT_POLY);
    double r = 0.5;
    for (int j = 0; j < s; j++)
      for (int i = 0; i < s; i++) {
        const double *c = me->E + (j * s + i) * s;
        double horner = 0, quad = 0, mass = 0;
        for (int d = s - 1; d >= 0; d--) {
          if (d < j || d > i) ck_assert_msg(c[d] == 0, "s=%d E[%d][%d][%d] = %g", s, j, i, d, c[d]);
          horner = horner * r + c[d];
        }
        if (i == j) ck_assert_msg(c[j] == 1, "s=%d E[%d][%d][%d] = %.17g", s, j, j, j, c[j]);
        for (int l = 0; l < s; l++) {
          double term = me->b[l] * shifted_legendre(j, me->c[l]) * shifted_legendre(i, 1 + r * me->c[l]);
          quad += term;
          mass += fabs(term);
        }
        ck_assert_msg(fabs(horner - quad) <= 64 * DBL_EPSILON * mass, "s=%d E_%d%d(1/2) %.17g, quadrature %.17g", s, j,
                      i, horner, quad);
      }
    arena_free_all();
  }
}
END_TEST

// The two-step start's E2 (long double, rounded once): E2[0][0] and
// E2[0][s] against their exact values (rationals, from exact polynomial
// arithmetic): exact up to s = 3, within 2 ulps at s = 4 and 1e-12 at
// s = 6, where the solve in long double loses digits to the table's size
// (the double solve before: 1 ulp off at s = 2, 2e-13 at s = 4, 4e-11 at
// s = 6); and a constant
// polynomial goes on unchanged: E2[j][0] + E2[j][s] = [j == 0] for s <= 10.
START_TEST(test_two_step_table)
{
  static const struct {
    int s;
    double e0, es, tol;
  } exact[] = {{1, 2, -1, 0}, {2, -5.5, 6.5, 0}, {3, 69.5, -68.5, 0}, {4, -910.1875, 911.1875, 5e-16},
               {6, -227983.26953125, 227984.26953125, 1e-12}};
  for (size_t c = 0; c < sizeof exact / sizeof exact[0]; c++) {
    int s = exact[c].s;
    Method *me = method_new(s, s, MULT_POLY);
    double e0 = me->E2[0], es = me->E2[s], tol = exact[c].tol * fabs(exact[c].e0);
    ck_assert_msg(fabs(e0 - exact[c].e0) <= tol && fabs(es - exact[c].es) <= tol, "s=%d E2[0][0] %.17g E2[0][s] %.17g",
                  s, e0, es);
    arena_free_all();
  }
  for (int s = 1; s <= 10; s++) {
    Method *me = method_new(s, s, MULT_POLY);
    for (int j = 0; j < s; j++)
      ck_assert_msg(me->E2[j * 2 * s] + me->E2[j * 2 * s + s] == (j == 0), "s=%d row %d: %.17g + %.17g", s, j,
                    me->E2[j * 2 * s], me->E2[j * 2 * s + s]);
    arena_free_all();
  }
}
END_TEST

Suite *parser_suite(void);

#define GENERATOR "../gen/hbvmgen"
#define PI 3.14159265358979323846
#define TOL 1e-14
#define NCASES(t) ((int)(sizeof(t) / sizeof((t)[0])))

/* ---- the front end in-process ---- */

/* Parse and analyse src, which must be a valid model, and differentiate
 * it. The model lives in the arena, freed after each test. */
static Model *load(const char *src)
{
  size_t len = strlen(src);
  diag_begin("test.ham", src, len);
  Stmt *prog = parse_model(src, len);
  ck_assert_msg(diag_error_count() == 0, "syntax error in:\n%s", src);
  Model *mod = analyse("test.ham", prog);
  ck_assert_msg(mod != NULL, "analysis failed for:\n%s", src);
  model_differentiate(mod);
  return mod;
}

/* Whether src is refused (syntax or analysis errors); the messages, which
 * the golden files of check_errors.c test, are discarded. */
static int refused(const char *src)
{
  size_t len = strlen(src);
  fflush(stderr);
  int saved = dup(2), null = open("/dev/null", O_WRONLY);
  ck_assert_msg(saved >= 0 && null >= 0 && dup2(null, 2) == 2, "cannot silence stderr");
  close(null);
  diag_begin("test.ham", src, len);
  Stmt *prog = parse_model(src, len);
  int bad = diag_error_count() > 0 || analyse("test.ham", prog) == NULL;
  fflush(stderr);
  dup2(saved, 2);
  close(saved);
  return bad;
}

/* Each of the n models of bad is refused. */
static void assert_refused(const char *const *bad, int n)
{
  for (int i = 0; i < n; i++)
    ck_assert_msg(refused(bad[i]), "accepted:\n%s", bad[i]);
}

/* The value of node at coordinates q, parameters at their defaults. */
static double eval(const Model *mod, int node, const double *q)
{
  double prm[64] = {0};
  ck_assert_int_le(mod->nparams, 64);
  for (int i = 0; i < mod->nparams; i++)
    prm[i] = mod->params[i].value;
  return dag_eval(mod->dag, node, q, prm);
}

/* Assert |got - want| <= TOL * max(1, |want|), naming what is compared. */
static void assert_close(double got, double want, const char *what)
{
  ck_assert_msg(fabs(got - want) <= TOL * fmax(1, fabs(want)), "%s = %.17g, want %.17g", what, got, want);
}

/* Assert n values of got against want, named what[i]. */
static void assert_values(const double *got, const double *want, int n, const char *what)
{
  for (int i = 0; i < n; i++) {
    char name[64];
    snprintf(name, sizeof name, "%s[%d]", what, i);
    assert_close(got[i], want[i], name);
  }
}

static void teardown(void)
{
  arena_free_all();
}

/* ---- statements ---- */

START_TEST(test_scalar_variables)
{
  Model *mod = load("variables x, y\nvariables z\nU = x + 2*y + 3*z\n");
  ck_assert_int_eq(mod->m, 3);
  ck_assert_int_eq(mod->nu, 0);
  ck_assert_int_eq(mod->degg, 0);
  static const char *const names[] = {"x", "y", "z"};
  for (int i = 0; i < 3; i++)
    ck_assert_str_eq(mod->coord_names[i], names[i]);
  const double q[] = {1, 10, 100};
  assert_close(eval(mod, mod->U, q), 321, "U");
  ck_assert_int_eq(mod->degU, 1);
}
END_TEST

/* Arrays expand in index order, sizes are constant expressions, and
 * several variables statements append. */
START_TEST(test_array_variables)
{
  Model *mod = load("n = 2\nvariables a[n + 1], b\nvariables c[n]\nU = sum(i in 1..3, i * a[i]) + 10*b + 100*c[2]\n");
  ck_assert_int_eq(mod->m, 6);
  static const char *const names[] = {"a[1]", "a[2]", "a[3]", "b", "c[1]", "c[2]"};
  for (int i = 0; i < 6; i++)
    ck_assert_str_eq(mod->coord_names[i], names[i]);
  const double q[] = {1, 2, 3, 4, 5, 6};
  assert_close(eval(mod, mod->U, q), 1 + 4 + 9 + 40 + 600, "U");
}
END_TEST

/* A definition folding to a number is a constant; otherwise a named
 * subexpression of q, shared wherever it is used. */
START_TEST(test_definitions)
{
  Model *mod = load("variables x, y\nk = 2^3 - 1\nr = sqrt(x^2 + y^2)\nU = k * r + r^2\n");
  const double q[] = {3, 4};
  assert_close(eval(mod, mod->U, q), 7 * 5 + 25, "U");
  ck_assert_int_eq(mod->degU, DEG_NONPOLY);
  const double grad[] = {7 * 3 / 5.0 + 6, 7 * 4 / 5.0 + 8};
  for (int i = 0; i < 2; i++)
    assert_close(eval(mod, mod->gradU[i], q), grad[i], "dU/dq");
}
END_TEST

/* A param is a run-time value: it stays a parameter in U and g, and
 * counts as a constant in degrees. */
START_TEST(test_param)
{
  Model *mod = load("param k = 2.5\nparam L = 2\nvariables x, y\nU = k * x^2\ng = x^2 + y^2 - L^2\n");
  ck_assert_int_eq(mod->nparams, 2);
  ck_assert_str_eq(mod->params[0].name, "k");
  ck_assert_str_eq(mod->params[1].name, "L");
  assert_close(mod->params[0].value, 2.5, "k");
  assert_close(mod->params[1].value, 2, "L");
  const double q[] = {2, 1};
  assert_close(eval(mod, mod->U, q), 10, "U");
  assert_close(eval(mod, mod->g[0], q), 1, "g");
  const double prm[] = {1, 3};
  assert_close(dag_eval(mod->dag, mod->g[0], q, prm), 5 - 9, "g with L = 3");
  ck_assert_int_eq(mod->degU, 2);
  ck_assert_int_eq(mod->degg, 2);
}
END_TEST

/* Every form of M, classified by what it is, with diag(M^-1). */
static const struct {
  const char *mass;
  MassKind kind;
  double minv_diag[2];
} mass_cases[] = {
    {"", MASS_IDENTITY, {1, 1}},
    {"M = identity", MASS_IDENTITY, {1, 1}},
    {"M = 4", MASS_SCALAR, {0.25, 0.25}},
    {"M = diag(2, 2)", MASS_SCALAR, {0.5, 0.5}},
    {"M = diag(1, 2)", MASS_DIAG, {1, 0.5}},
    {"M = [[1, 0], [0, 1]]", MASS_IDENTITY, {1, 1}},
    {"M = [[2, 0], [0, 4]]", MASS_DIAG, {0.5, 0.25}},
    {"c = 3\nM = [[2, 1], [1, c - 1]]", MASS_DENSE, {2 / 3.0, 2 / 3.0}},
};

START_TEST(test_mass)
{
  char src[256];
  snprintf(src, sizeof src, "variables x, y\n%s\nU = x*y\n", mass_cases[_i].mass);
  Model *mod = load(src);
  ck_assert_msg(mod->mass == mass_cases[_i].kind, "'%s': mass kind %d, want %d", mass_cases[_i].mass, mod->mass,
                mass_cases[_i].kind);
  assert_values(mod->minv_diag, mass_cases[_i].minv_diag, 2, "diag(M^-1)");
  if (mod->mass == MASS_DENSE) {
    const double minv[] = {2 / 3.0, -1 / 3.0, -1 / 3.0, 2 / 3.0};
    assert_values(mod->minv, minv, 4, "M^-1");
  }
}
END_TEST

/* M with params: M^-1 v from the DAG (mass.c's L D L' factors, or 1/m_ii)
 * times M is v at any params; a constant M stays constants; params making M
 * singular or indefinite give NaN, never a finite wrong value. */
static void minv_columns(Model *mod, const double *prm, double *inv)
{
  int m = mod->m, v[3] = {0}, out[3] = {0};
  for (int i = 0; i < m; i++) v[i] = dag_input(mod->dag, i);
  minv_apply(mod, mod->dag, v, out);
  for (int j = 0; j < m; j++) {
    double e[3] = {0, 0, 0};
    e[j] = 1;
    for (int i = 0; i < m; i++) inv[i * m + j] = dag_eval(mod->dag, out[i], e, prm);
  }
}

START_TEST(test_mass_params)
{
  Model *mod = load("variables x, y, z\nparam a = 2\nparam c = 0.5\n"
                    "M = [[a, c, 0], [c, 1 + a, c / 2], [0, c / 2, a * a]]\nU = x*y*z\n");
  ck_assert(mod->minv_node && mod->mass_L);
  ck_assert_int_eq(mod->mass, MASS_DENSE); /* at the defaults */
  static const double prms[][2] = {{2, 0.5}, {1, 0}, {5, -1.5}, {0.3, 0.2}};
  for (int t = 0; t < NCASES(prms); t++) {
    double a = prms[t][0], c = prms[t][1], inv[9];
    const double M[9] = {a, c, 0, c, 1 + a, c / 2, 0, c / 2, a * a};
    minv_columns(mod, prms[t], inv);
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) {
        double mi = 0;
        for (int k = 0; k < 3; k++) mi += M[i * 3 + k] * inv[k * 3 + j];
        ck_assert_msg(fabs(mi - (i == j)) <= 1e-14, "a=%g c=%g: (M M^-1)[%d][%d] = %.17g", a, c, i, j, mi);
      }
  }
  const double indefinite[] = {1, 2}, singular[] = {0, 0};
  double inv[9];
  minv_columns(mod, indefinite, inv);
  ck_assert_msg(isnan(inv[8]), "an indefinite M gives M^-1 = %g, want NaN", inv[8]);
  minv_columns(mod, singular, inv);
  ck_assert_msg(!isfinite(inv[0]), "a singular M gives M^-1 = %g, want non-finite", inv[0]);

  mod = load("variables x, y\nparam m1 = 2\nM = diag(m1, 1)\nU = x*y\n");
  ck_assert(mod->minv_node && !mod->mass_L);
  ck_assert_int_eq(mod->mass, MASS_DIAG);
  for (double m1 = -1; m1 <= 3; m1 += 0.5) {
    double d[4];
    minv_columns(mod, &m1, d);
    if (m1 > 0) ck_assert_msg(d[0] == 1 / m1 && d[3] == 1 && d[1] == 0, "m1=%g: M^-1 = diag(%g, %g)", m1, d[0], d[3]);
    else ck_assert_msg(isnan(d[0]), "m1=%g: M^-1[0][0] = %g, want NaN", m1, d[0]);
  }
  mod = load("variables x, y\nparam k = 3\nM = diag(2, 1)\nU = k*x*y\n");
  ck_assert(!mod->minv_node); /* constant: baked in as before */
}
END_TEST

START_TEST(test_potential_default)
{
  Model *mod = load("variables x\n");
  const double q[] = {5};
  assert_close(eval(mod, mod->U, q), 0, "U");
  ck_assert_int_eq(mod->degU, 0);
  ck_assert_int_eq(mod->nu, 0);
  assert_close(eval(mod, mod->gradU[0], q), 0, "dU/dx");
}
END_TEST

/* g as a scalar, a list, a nested list and a comprehension; several g
 * statements append in order. */
START_TEST(test_constraints)
{
  Model *mod = load("variables x[7]\n" /* no more constraints than coordinates */
                    "g = x[1] - 1\n"
                    "g = [x[2] - 2, [x[3] - 3, [x[1] * x[2]]]]\n"
                    "g = [i * x[i]^2 for i in 1..3]\n");
  ck_assert_int_eq(mod->nu, 7);
  const double q[] = {1, 2, 3, 0, 0, 0, 0};
  const double want[] = {0, 0, 0, 2, 1, 8, 27};
  for (int a = 0; a < 7; a++)
    assert_close(eval(mod, mod->g[a], q), want[a], "g");
  ck_assert_int_eq(mod->degg, 2);
  ck_assert_int_eq(mod->g_loc[0].line, 2);
  ck_assert_int_eq(mod->g_loc[4].line, 4);
  ck_assert_int_eq(mod->jac[0].n, 1);   /* x[1] - 1 depends on x[1] only */
  ck_assert_int_eq(mod->jac[3].n, 2);
}
END_TEST

/* sum with index arithmetic in indices, bounds and bodies; nested sums. */
START_TEST(test_sum_and_indexing)
{
  Model *mod = load("variables x[4]\n"
                    "n = 4\n"
                    "U = sum(i in 1..n - 1, x[i] * x[i + 1]) + sum(i in 1..2, sum(j in i..2, x[2*j - 1] * (i + j)))\n");
  const double q[] = {1, 2, 3, 4};
  /* 1*2 + 2*3 + 3*4; i=1: j=1 x1*2, j=2 x3*3; i=2: j=2 x3*4 */
  assert_close(eval(mod, mod->U, q), 20 + 2 + 9 + 12, "U");
  ck_assert_int_eq(mod->degU, 2);
}
END_TEST

/* The twenty functions against the C library at (x, y) = (0.3, 0.7). */
static double fn_abs(double x, double y) { return fabs(x - y); }
static double fn_sin(double x, double y) { (void)y; return sin(x); }
static double fn_cos(double x, double y) { (void)y; return cos(x); }
static double fn_tan(double x, double y) { (void)y; return tan(x); }
static double fn_asin(double x, double y) { (void)y; return asin(x); }
static double fn_acos(double x, double y) { (void)y; return acos(x); }
static double fn_atan(double x, double y) { (void)y; return atan(x); }
static double fn_sinh(double x, double y) { (void)y; return sinh(x); }
static double fn_cosh(double x, double y) { (void)y; return cosh(x); }
static double fn_tanh(double x, double y) { (void)y; return tanh(x); }
static double fn_exp(double x, double y) { (void)y; return exp(x); }
static double fn_log(double x, double y) { (void)y; return log(x); }
static double fn_sqrt(double x, double y) { (void)y; return sqrt(x); }
static double fn_sign(double x, double y) { return (x - y > 0) - (x - y < 0); }
static double fn_floor(double x, double y) { return floor(y / x); }
static double fn_mod(double x, double y) { return (x - y) - x * floor((x - y) / x); }

static const struct {
  const char *expr;
  double (*f)(double, double);
} function_cases[] = {
    {"sin(x)", fn_sin},   {"cos(x)", fn_cos},     {"tan(x)", fn_tan},   {"asin(x)", fn_asin}, {"acos(x)", fn_acos},
    {"atan(x)", fn_atan}, {"atan2(x, y)", atan2}, {"sinh(x)", fn_sinh}, {"cosh(x)", fn_cosh}, {"tanh(x)", fn_tanh},
    {"exp(x)", fn_exp},   {"log(x)", fn_log},     {"sqrt(x)", fn_sqrt}, {"pow(x, y)", pow},   {"abs(x - y)", fn_abs},
    {"sign(x - y)", fn_sign}, {"min(x, y)", fmin}, {"max(x, y)", fmax}, {"floor(y / x)", fn_floor},
    {"mod(x - y, x)", fn_mod},
};

START_TEST(test_functions)
{
  char src[128];
  snprintf(src, sizeof src, "variables x, y\nU = %s\n", function_cases[_i].expr);
  Model *mod = load(src);
  const double q[] = {0.3, 0.7};
  assert_close(eval(mod, mod->U, q), function_cases[_i].f(0.3, 0.7), function_cases[_i].expr);
  ck_assert_int_eq(mod->degU, DEG_NONPOLY);
}
END_TEST

/* expr with the names x and y (not the letters of exp) replaced by the
 * numbers 0.3 and 0.7, into out (size bytes). */
static void substitute(const char *expr, char *out, size_t size)
{
  size_t n = 0;
  for (const char *c = expr; *c && n + 4 < size; c++) {
    int alone = (*c == 'x' || *c == 'y') && (c == expr || !isalnum((unsigned char)c[-1])) &&
                !isalnum((unsigned char)c[1]);
    if (alone)
      n += (size_t)sprintf(out + n, "%s", *c == 'x' ? "0.3" : "0.7");
    else
      out[n++] = *c;
  }
  out[n] = '\0';
}

/* Every function folds to the same number on constant arguments (q0). */
START_TEST(test_functions_fold)
{
  char expr[128], src[256];
  substitute(function_cases[_i].expr, expr, sizeof expr);
  snprintf(src, sizeof src, "variables x, y\nq0 = [%s, 0]\nU = x + y\n", expr);
  Model *mod = load(src);
  assert_close(mod->q0[0], function_cases[_i].f(0.3, 0.7), expr);
}
END_TEST

/* name = [...] defines an array of values (constants or expressions),
 * flattened like g; name[i] takes a constant index or a sum/for index
 * variable, and constant entries work wherever constants are required. */
START_TEST(test_value_arrays)
{
  Model *mod = load("variables x[3]\n"
                    "mass = [1, 2, 0.5]\n"
                    "k = [[10 * i for i in 1..2], 30]\n"
                    "d = [x[i + 1] - x[i] for i in 1..2]\n"
                    "M = diag(mass[1], mass[2], mass[3])\n"
                    "U = sum(i in 1..3, k[i] * x[i]^2) + d[2]^2\n"
                    "g = sum(i in 1..2, mass[i + 1] * x[i]) - 1\n"
                    "q0 = [mass[3], 0, k[1]]\n");
  const double q[] = {1, 2, 5}, minv[] = {1, 0.5, 2}, q0[] = {0.5, 0, 10};
  assert_close(eval(mod, mod->U, q), 10 + 20 * 4 + 30 * 25 + 9, "U");
  assert_close(eval(mod, mod->g[0], q), 2 * 1 + 0.5 * 2 - 1, "g");
  assert_values(mod->minv_diag, minv, 3, "diag M^-1");
  assert_values(mod->q0, q0, 3, "q0");
  ck_assert_int_eq(mod->degU, 2);
  ck_assert_int_eq(mod->degg, 1);
  ck_assert(refused("variables x\na = [1, 2]\nU = a[3] * x\n"));
  ck_assert(refused("variables x\na = [1, 2]\nU = a * x\n"));
  ck_assert(refused("variables x\na = [1, 2]\nU = a[x] * x\n"));
  ck_assert(refused("variables x\na = []\nU = x\n"));
}
END_TEST

/* U(x, y) and its gradient at a point. */
typedef struct {
  double q[2], U, dx, dy;
} Point;

static void assert_points(const Model *mod, const Point *pts, int n)
{
  for (int i = 0; i < n; i++) {
    assert_close(eval(mod, mod->U, pts[i].q), pts[i].U, "U");
    assert_close(eval(mod, mod->gradU[0], pts[i].q), pts[i].dx, "dU/dx");
    assert_close(eval(mod, mod->gradU[1], pts[i].q), pts[i].dy, "dU/dy");
  }
}

/* min, max and sign: values on both sides and at a tie, derivatives the
 * subgradients of ad.c (half to each operand of min/max at a tie). */
START_TEST(test_min_max_sign)
{
  Model *mod = load("variables x, y\nU = 3 * min(x, y) + 5 * max(x, 2*y) + 7 * sign(x) * x\n");
  static const Point pts[] = {
      {{1, 2}, 3 * 1 + 5 * 4 + 7, 3 + 7, 10},
      {{3, 1}, 3 * 1 + 5 * 3 + 21, 5 + 7, 3},
      {{2, 1}, 3 * 1 + 5 * 2 + 14, 2.5 + 7, 3 + 5},    /* tie of max: half each */
      {{-1, -1}, -3 - 5 - 7 * -1, 1.5 + 5 - 7, 1.5},   /* tie of min: half each */
      {{0, 1}, 0 + 10 + 0, 3 + 0, 10},                 /* sign(0) = 0, d sign = 0 */
  };
  assert_points(mod, pts, NCASES(pts));
  ck_assert_int_eq(mod->degU, DEG_NONPOLY);
  ck_assert(refused("variables x\nU = min(x)\n"));
  ck_assert(refused("variables x\nU = sign(x, 1)\n"));
}
END_TEST

/* floor and mod: values on both sides of a jump and at one, the sign of
 * mod that of its divisor (as Python's %), derivatives floor' = 0 and
 * mod(x, y) = x - y floor(x / y): d/dx 1, d/dy -floor(x / y). */
START_TEST(test_floor_mod)
{
  Model *mod = load("variables x, y\nU = floor(x) + 10 * mod(x, y)\n");
  static const Point pts[] = {
      {{2.5, 2}, 2 + 10 * 0.5, 10, -10},
      {{-0.5, 2}, -1 + 10 * 1.5, 10, 10},   /* floor(-0.5) = -1, mod(-0.5, 2) = 1.5 */
      {{3, 2}, 3 + 10 * 1, 10, -10},        /* at a jump: the right-hand value */
      {{2.5, -2}, 2 + 10 * -1.5, 10, 20},   /* mod(2.5, -2) = -1.5 */
  };
  assert_points(mod, pts, NCASES(pts));
  ck_assert_int_eq(mod->degU, DEG_NONPOLY);
  mod = load("variables x\nq0 = [mod(7, 3) + 10 * mod(-7, 3) + 100 * floor(-2.5)]\n");
  assert_close(mod->q0[0], 1 + 10 * 2 - 300, "q0");
  static const char *const bad[] = {"variables x\nU = floor(x, 1)\n", "variables x\nU = mod(x)\n",
                                     "variables x\nU = mod(x, 0)\n"};
  assert_refused(bad, NCASES(bad));
}
END_TEST

/* Double comprehensions and sums over several index variables (the inner
 * range may use the outer variable), and index variables that run over a
 * list, written out or named: each expands in the order written. */
START_TEST(test_iterators)
{
  Model *mod = load("variables x[7]\n"
                    "pick = [3, 1]\n"
                    "g = [x[i] - 10 * j for i in 1..2 for j in i..2]\n"
                    "g = [x[b] for b in [3, 1]]\n"
                    "g = [x[b] + c for b in pick for c in [5]]\n"
                    "U = sum(i in 1..2, j in i + 1..3, x[i] * x[j]) + sum(b in [1, 3], 100 * x[b])\n"
                    "q0 = [1 for i in 1..7]\n");
  const double q[] = {1, 2, 3, 0, 0, 0, 0};
  const double want[] = {1 - 10, 1 - 20, 2 - 20, 3, 1, 3 + 5, 1 + 5};
  ck_assert_int_eq(mod->nu, 7);
  for (int a = 0; a < 7; a++)
    assert_close(eval(mod, mod->g[a], q), want[a], "g");
  assert_close(eval(mod, mod->U, q), 2 + 3 + 6 + 100 * (1 + 3), "U");
  mod = load("variables x, y\nU = sum(b in [], x) + x\ng = [x - y * i * j for i in [1, 2] for j in [i]]\nq0 = [1, 1]\n");
  ck_assert_int_eq(mod->nu, 2);
  /* a pair sum over i < j (the last inner range empty) and its pairs as a
   * double comprehension: sum_{i<j} i j = (15^2 - 55) / 2 at q = 1..5 */
  mod = load("variables x[5]\npairs = [10 * i + j for i in 1..5 for j in i + 1..5]\n"
             "U = sum(i in 1..5, j in i + 1..5, x[i] * x[j]) + 1000 * pairs[10]\n");
  const double q5[] = {1, 2, 3, 4, 5};
  assert_close(eval(mod, mod->U, q5), 85 + 1000 * 45, "pair sum");
  static const char *const bad[] = {"variables x\nU = sum(b in [1, x], x)\n", "variables x\nU = sum(b in [1.5], x)\n",
                                     "variables x\nU = sum(b in 2, x)\n",
                                     "variables x\ng = [x for i in 1..2 for i in 1..2]\n",
                                     /* bounds of a pair sum: an index bound later, its own, a param */
                                     "variables x[3]\nU = sum(j in i + 1..3, i in 1..2, x[i] * x[j])\n",
                                     "variables x[3]\nU = sum(i in 1..2, j in j + 1..3, x[i] * x[j])\n",
                                     "variables x[3]\nparam k = 1\nU = sum(i in 1..2, j in i + k..3, x[i] * x[j])\n",
                                     "variables x[3]\nU = sum(i in 1..2, j in i + 0.5..3, x[i] * x[j])\n"};
  assert_refused(bad, NCASES(bad));
}
END_TEST

/* Functions of def: expanded at each call with the parameters bound to the
 * arguments (usable as indices when constant integers), in the scope of
 * the def: a caller's index variable of the same name, or a name defined
 * after the def, is hidden, not clashed with. Calls with equal arguments
 * share their nodes. */
START_TEST(test_def_functions)
{
  Model *mod = load("variables x[3]\n"
                    "def d(i, j) = x[i] - x[j]\n"
                    "def r2(i, j) = d(i, j)^2 + sum(k in 1..1, 0 * x[k])\n"
                    "U = sum(k in 1..2, j in k + 1..3, r2(k, j)) + r2(1, 2)\n"
                    "j = 4\n"
                    "g = d(3, 1) * j - 8\n");
  const double q[] = {1, 2, 4};
  assert_close(eval(mod, mod->U, q), 1 + 9 + 4 + 1, "U");
  assert_close(eval(mod, mod->g[0], q), 3 * 4 - 8, "g");
  Model *twice = load("variables x, y\ndef f(a) = sin(a) * a\nU = f(x + y) + f(x + y)\n");
  int n_twice = twice->dag->n;
  Model *once = load("variables x, y\nU = sin(x + y) * (x + y) + sin(x + y) * (x + y)\n");
  ck_assert_int_eq(n_twice, once->dag->n);
  /* 40 functions each calling the one before twice: 2^39 calls of f1 written
   * out, expanded once per distinct arguments (a few hundred nodes) */
  char src[4096] = "variables x\ndef f1(a) = a\n";
  for (int i = 2; i <= 40; i++)
    snprintf(src + strlen(src), sizeof src - strlen(src), "def f%d(a) = f%d(a) + f%d(a)\n", i, i - 1, i - 1);
  strcat(src, "U = f40(x)\n");
  Model *chain = load(src);
  const double one[] = {1};
  assert_close(eval(chain, chain->U, one), ldexp(1, 39), "U of the doubling chain");
  ck_assert_int_lt(chain->dag->n, 1000);
  static const char *const bad[] = {
      "variables x\ndef f(a) = a\nU = f(x, x)\n",        /* arity */
      "variables x\ndef f(a) = f(a)\nU = f(x)\n",        /* recursion */
      "variables x\ndef f(x) = x\nU = f(x)\n",           /* a parameter named as a coordinate */
      "variables x\ndef f(a, a) = a\nU = f(x, x)\n",     /* twice */
      "variables x\nU = f(x)\ndef f(a) = a\n",           /* used before its def */
      "variables x\ndef f(a) = a * y\ny = 2\nU = f(x)\n", /* the body sees only earlier names */
      "variables x\ndef f(a) = a\nU = f\n",              /* not called */
      "variables x\nU = x(1)\n",                         /* not a function */
  };
  assert_refused(bad, NCASES(bad));
}
END_TEST

/* q0 and p0 as lists with nested lists and comprehensions; without them
 * the initial values are zero. */
START_TEST(test_initial_values)
{
  Model *mod = load("variables x[2], y\nq0 = [[i / 2 for i in 1..2], 3]\np0 = [0, [1, [2]]]\n");
  const double q0[] = {0.5, 1, 3}, p0[] = {0, 1, 2};
  assert_values(mod->q0, q0, 3, "q0");
  assert_values(mod->p0, p0, 3, "p0");
  mod = load("variables x, y\n");
  const double zero[] = {0, 0};
  assert_values(mod->q0, zero, 2, "default q0");
  assert_values(mod->p0, zero, 2, "default p0");
}
END_TEST

/* Comments, optional semicolons, statements on one line, any order;
 * non-ASCII text in comments. */
START_TEST(test_layout)
{
  Model *mod = load("# a comment \xc3\xa9\xe2\x82\xac\n"
                    ";; variables x; # trailing comment\n"
                    "U = x^2;  q0 = [3, 5]   p0 = [1, 0];\n"
                    "\t\r\n"
                    "variables y g = y - x # no newline at the end");
  ck_assert_int_eq(mod->m, 2);
  ck_assert_int_eq(mod->nu, 1);
  const double q[] = {3, 5};
  assert_close(eval(mod, mod->U, q), 9, "U");
  assert_close(eval(mod, mod->g[0], q), 2, "g");
  assert_close(mod->q0[0], 3, "q0");
  assert_close(mod->p0[0], 1, "p0");
}
END_TEST

/* Every number format of docs/language.md. */
START_TEST(test_numbers)
{
  Model *mod = load("variables x[6]\nq0 = [12, 1.5, .5, 2e-3, 1.0E+10, 0.25e1]\n");
  const double want[] = {12, 1.5, 0.5, 2e-3, 1.0E+10, 2.5};
  ck_assert_int_eq(mod->m, 6);
  for (int i = 0; i < 6; i++)
    ck_assert_msg(mod->q0[i] == want[i], "number %d: %.17g, want %.17g", i, mod->q0[i], want[i]);
}
END_TEST

/* Precedence and associativity: '^' is right-associative and binds
 * tighter than unary minus; the others are left-associative. Each
 * expression is evaluated at x = 3. */
static const struct {
  const char *expr;
  double value;
} precedence_cases[] = {
    {"-x^2", -9},         {"(-x)^2", 9},         {"2^3^2", 512},        {"(2^3)^2", 64},   {"x^2^-1", 1.7320508075688772},
    {"-2^2 * x", -12},    {"2 * 3 + 4 * x", 18}, {"2 + 3 * x", 11},     {"24 / x / 2", 4}, {"10 - x - 2", 5},
    {"-x - -x", 0},       {"+x", 3},             {"2 * -x", -6},        {"x^-1", 1 / 3.0}, {"pi * x", 3 * PI},
    {"(x + 1) * (x - 1)", 8},
};

START_TEST(test_precedence)
{
  char src[128];
  snprintf(src, sizeof src, "variables x\nU = %s\n", precedence_cases[_i].expr);
  Model *mod = load(src);
  const double q[] = {3};
  assert_close(eval(mod, mod->U, q), precedence_cases[_i].value, precedence_cases[_i].expr);
}
END_TEST

START_TEST(test_pi)
{
  Model *mod = load("variables x\nq0 = [pi / 4]\nU = pi * x\n");
  assert_close(mod->q0[0], PI / 4, "q0");
  const double q[] = {2};
  assert_close(eval(mod, mod->U, q), 2 * PI, "U");
}
END_TEST

/* Polynomial degrees of U and of the largest constraint. */
static const struct {
  const char *body;
  int degU, degg;
} degree_cases[] = {
    {"U = y", 1, 0},
    {"U = x^2 * y^2 + 1\ng = x - 1", 4, 1},
    {"g = [x^2 + y^2 - 1, x^3 * y^3]", 0, 6},
    {"U = sin(x)\ng = x*y", DEG_NONPOLY, 2},
    {"U = x^2.5", DEG_NONPOLY, 0},
    {"U = x / 2 + y^2 / pi", 2, 0},
    {"g = [x - 1, 1 / y]", 0, DEG_NONPOLY},
    {"U = sum(i in 1..4, x^i)", 4, 0},
};

START_TEST(test_degrees)
{
  char src[128];
  snprintf(src, sizeof src, "variables x, y\n%s\n", degree_cases[_i].body);
  Model *mod = load(src);
  ck_assert_msg(mod->degU == degree_cases[_i].degU && mod->degg == degree_cases[_i].degg,
                "'%s': deg(U)=%d deg(g)=%d, want %d %d", degree_cases[_i].body, mod->degU, mod->degg,
                degree_cases[_i].degU, degree_cases[_i].degg);
}
END_TEST

/* The gradient of U and the Jacobian of g from model_differentiate. */
START_TEST(test_derivatives)
{
  Model *mod = load("variables x, y, z\nU = x^2 * y + sin(z)\ng = [x*y - 1, z^2]\n");
  const double q[] = {2, 3, 0.5};
  const double grad[] = {12, 4, cos(0.5)};
  for (int i = 0; i < 3; i++)
    assert_close(eval(mod, mod->gradU[i], q), grad[i], "grad U");
  ck_assert_int_eq(mod->jac[0].n, 2);
  ck_assert_int_eq(mod->jac[1].n, 1);
  ck_assert_int_eq(mod->jac[1].e[0].coord, 2);
  assert_close(eval(mod, mod->jac[1].e[0].node, q), 1, "dg2/dz");
}
END_TEST

/* A few refusals in-process: the front end reports and returns NULL. */
START_TEST(test_refused)
{
  static const char *const bad[] = {
      "variables x\nU = y\n", "variables x[2]\nU = x[3]\n", "variables x\nM = [[1, 2], [3, 4]]\n",
      "variables x\nU = (x\n", "", "variables x\nq0 = [1, 2]\n",
  };
  assert_refused(bad, NCASES(bad));
}
END_TEST

/* ---- the command line ---- */

/* Run `GENERATOR args` through the shell; return its exit status and its
 * stdout (stderr too when merge) in out (size bytes). */
static int run_cli(const char *args, int merge, char *out, size_t size)
{
  char cmd[512];
  snprintf(cmd, sizeof cmd, "%s %s %s", GENERATOR, args, merge ? "2>&1" : "2>/dev/null");
  FILE *p = popen(cmd, "r");
  ck_assert_msg(p != NULL, "cannot run %s", cmd);
  size_t n = fread(out, 1, size - 1, p);
  out[n] = '\0';
  int status = pclose(p);
  ck_assert_msg(WIFEXITED(status), "%s: killed", cmd);
  ck_assert_msg(WEXITSTATUS(status) != 127, "cannot run %s (build it with make all)", GENERATOR);
  return WEXITSTATUS(status);
}

/* The first line of --check for each model and s (k auto). */
static const struct {
  const char *model;
  int s;
  const char *line;
} check_cases[] = {
    {"pendulum", 2, "model pendulum: m=2 nu=1 deg(U)=1 deg(g)=2 k=2 s=2"},
    {"pendulum", 1, "model pendulum: m=2 nu=1 deg(U)=1 deg(g)=2 k=1 s=1"},
    {"pendulum", 3, "model pendulum: m=2 nu=1 deg(U)=1 deg(g)=2 k=3 s=3"},
    {"conical", 2, "model conical: m=3 nu=1 deg(U)=1 deg(g)=2 k=2 s=2"},
    {"conical", 1, "model conical: m=3 nu=1 deg(U)=1 deg(g)=2 k=1 s=1"},
    {"conical", 3, "model conical: m=3 nu=1 deg(U)=1 deg(g)=2 k=3 s=3"},
    {"modified", 2, "model modified: m=3 nu=1 deg(U)=4 deg(g)=6 k=6 s=2"},
    {"modified", 1, "model modified: m=3 nu=1 deg(U)=4 deg(g)=6 k=3 s=1"},
    {"modified", 3, "model modified: m=3 nu=1 deg(U)=4 deg(g)=6 k=9 s=3"},
    {"satellites", 2, "model satellites: m=9 nu=3 deg(U)=nonpoly deg(g)=2 k=2 s=2"}, /* poly: k = s */
    {"satellites", 1, "model satellites: m=9 nu=3 deg(U)=nonpoly deg(g)=2 k=14 s=1"},
    {"satellites", 3, "model satellites: m=9 nu=3 deg(U)=nonpoly deg(g)=2 k=3 s=3"},
};

START_TEST(test_check_models)
{
  char args[128], out[4096];
  snprintf(args, sizeof args, "--check -s %d ../models/%s.ham", check_cases[_i].s, check_cases[_i].model);
  ck_assert_int_eq(run_cli(args, 0, out, sizeof out), 0);
  out[strcspn(out, "\n")] = '\0';
  ck_assert_str_eq(out, check_cases[_i].line);
}
END_TEST

/* -k given explicitly, and -n renaming the model. */
START_TEST(test_check_options)
{
  char out[4096];
  ck_assert_int_eq(run_cli("--check -k 4 -n pend ../models/pendulum.ham", 0, out, sizeof out), 0);
  out[strcspn(out, "\n")] = '\0';
  ck_assert_str_eq(out, "model pend: m=2 nu=1 deg(U)=1 deg(g)=2 k=4 s=2");
  ck_assert_int_eq(run_cli("-k auto -s 3 --check ../models/modified.ham", 0, out, sizeof out), 0);
  ck_assert_msg(strstr(out, " k=9 s=3\n") != NULL, "-k auto: %s", out);
}
END_TEST

/* --check's last line: the size of the code the options would write, and
 * whether the stages are one loop; nothing is written. */
START_TEST(test_check_code)
{
  char out[4096];
  ck_assert_int_eq(run_cli("--check -k 4 -n pend -o /nonexistent/dir ../models/pendulum.ham", 0, out, sizeof out), 0);
  const char *code = strstr(out, "\ncode: pend.c ");
  ck_assert_msg(code != NULL, "no code line: %s", out);
  double mb = atof(code + strlen("\ncode: pend.c "));
  ck_assert_msg(mb > 0.01 && mb < 1, "pend.c said to be %g MB", mb);
  ck_assert_msg(strstr(code, " bytes; the 4 stages in straight-line code\n"), "%s", code);
  ck_assert_int_eq(run_cli("--check -k 16 --stage-loop 1 ../models/kepler.ham", 0, out, sizeof out), 0);
  ck_assert_msg(strstr(out, "; the 16 stages as one loop (--stage-loop)\n"), "%s", out);
}
END_TEST

START_TEST(test_help)
{
  static const char *const options[] = {"-s S", "-k K", "auto", "-o DIR", "-n NAME", "--main", "--check", "-h",
                                        "--help", "--version"};
  char out[8192];
  for (int h = 0; h < 2; h++) {
    ck_assert_int_eq(run_cli(h ? "-h" : "--help", 0, out, sizeof out), 0);
    for (int i = 0; i < NCASES(options); i++)
      ck_assert_msg(strstr(out, options[i]) != NULL, "--help does not mention %s", options[i]);
  }
  ck_assert_int_eq(run_cli("--version", 0, out, sizeof out), 0);
  ck_assert_msg(!strncmp(out, "hbvmgen ", 8), "--version: %s", out);
}
END_TEST

/* src with every name of a temporary, a letter then digits (b12, t345),
 * replaced by one numbered in order of first appearance, so that two
 * sources compare equal when they differ only in how their temporaries are
 * numbered (malloc'd; src is freed). */
static char *renumber_temporaries(char *src)
{
  enum { MAXID = 1000000 };
  int *num[26] = {NULL}, next = 0;
  char *res = malloc(4 * strlen(src) + 1), *out = res; /* "b1" -> "T1000" at worst */
  ck_assert_ptr_nonnull(res);
  for (const char *c = src; *c;) {
    size_t digits = 0;
    int word = (c == src || !(isalnum((unsigned char)c[-1]) || c[-1] == '_')) && islower((unsigned char)c[0]);
    while (word && isdigit((unsigned char)c[1 + digits]))
      digits++;
    if (!digits || digits > 6 || isalnum((unsigned char)c[1 + digits]) || c[1 + digits] == '_') {
      *out++ = *c++;
      continue;
    }
    int **map = &num[c[0] - 'a'];
    if (!*map)
      ck_assert_ptr_nonnull(*map = calloc(MAXID, sizeof **map));
    long id = strtol(c + 1, NULL, 10);
    if (!(*map)[id])
      (*map)[id] = ++next;
    out += sprintf(out, "T%d", (*map)[id]);
    c += 1 + digits;
  }
  *out = '\0';
  for (int p = 0; p < 26; p++)
    free(num[p]);
  free(src);
  return res;
}

/* The new forms (def, sums over two index variables, double
 * comprehensions) expand exactly as the model written out by hand: the
 * outer solar system in both forms generates the same C but for the
 * numbering of its temporaries, so the same trajectories. */
START_TEST(test_sugar_same_code)
{
  char *sugar = read_text("../models/solar.ham"), *plain = read_text("../tests/models/solar_plain.ham");
  ck_assert_ptr_nonnull(sugar);
  ck_assert_ptr_nonnull(plain);
  ck_assert_msg(strstr(sugar, "def ") && strstr(sugar, " for c in 1..3]") && !strstr(plain, "def "),
                "the two models are not the two forms");
  /* (k = 18: at k = s, the default since --energy, both number alike) */
  char *a = generate_source(sugar, "-s 3 --energy quadrature"), *b = generate_source(plain, "-s 3 --energy quadrature");
  ck_assert_ptr_nonnull(a);
  ck_assert_ptr_nonnull(b);
  ck_assert_msg(strcmp(a, b) != 0, "the same numbering: the test would not see a difference");
  a = renumber_temporaries(a);
  b = renumber_temporaries(b);
  ck_assert_msg(strcmp(a, b) == 0, "models/solar.ham and tests/models/solar_plain.ham generate different code");
  free(sugar);
  free(plain);
  free(a);
  free(b);
}
END_TEST

/* --check's advice for each kind of model (method_advise): the (s, k)
 * measured best, whether the options given are those, what the constant
 * multiplier and a kink mean, and the step size limit of the iteration at
 * this s. A model with a kink is written into a temporary directory. */
START_TEST(test_check_advice)
{
  static const struct {
    const char *args, *want;
  } cases[] = {
      {"--check ../models/kepler.ham",
       "\nadvice: unconstrained and smooth: -s 6 -k auto (order 12; k = s, the end of the step rescales p); on the"},
      {"--check -s 6 ../models/solar.ham", "(order 12; k = s, the end of the step rescales p), as chosen;"},
      {"--check ../models/henon_heiles.ham", "\nadvice: unconstrained and smooth: -s 6 -k auto (order 12);"},
      {"--check ../models/pendulum.ham", "\nadvice: constrained and smooth: -s 4 -k auto --multiplier poly (order 8); "},
      {"--check -s 4 ../models/satellites.ham", " --multiplier poly (order 8), as chosen; "},
      {"--check --multiplier const ../models/pendulum.ham", "\nadvice: --multiplier const has order 2 in p with"},
      {"--check ../models/pendulum.ham", "stays below about 2.8 (docs/choosing.md, \"Stiffness\")\ncode: "},
      {"--check -s 9 ../models/kepler.ham", "stays below about 5.7 (docs/choosing.md"},
  };
  char out[8192], args[256], dir[] = "/tmp/hbvm-advice-XXXXXX";
  for (int i = 0; i < NCASES(cases); i++) {
    ck_assert_int_eq(run_cli(cases[i].args, 0, out, sizeof out), 0);
    ck_assert_msg(strstr(out, cases[i].want) != NULL, "%s: no '%s' in\n%s", cases[i].args, cases[i].want, out);
  }
  ck_assert_ptr_nonnull(mkdtemp(dir));
  snprintf(args, sizeof args, "%s/kink.ham", dir);
  FILE *f = fopen(args, "w");
  ck_assert_ptr_nonnull(f);
  fputs("variables x, y\nU = x^2 + max(y, 0)^2 + mod(x, 1)\n", f);
  fclose(f);
  snprintf(args, sizeof args, "--check %s/kink.ham", dir);
  ck_assert_int_eq(run_cli(args, 0, out, sizeof out), 0);
  ck_assert_msg(strstr(out, "\nadvice: U or g uses max, which has a kink or a jump: ") &&
                    !strstr(out, "advice: unconstrained and smooth") && !strstr(out, "advice: constrained and smooth"),
                "%s", out);
  /* the switching functions: max(y, 0) at y, and mod(x, 1) at floor(x)'s integer crossings */
  ck_assert_msg(strstr(out, "\nswitching functions: 2 (kink_switch): U not smooth") &&
                    strstr(out, "\nswitch 1: min/max, kink or jump at 0, ") &&
                    strstr(out, "\nswitch 2: floor, jumps where it crosses an integer, "),
                "%s", out);
  snprintf(args, sizeof args, "rm -r %s", dir);
  ck_assert_int_eq(system(args), 0);
}
END_TEST

/* Without -o the files go to the current directory (they went to
 * generated/, the directory of the committed solvers, before). */
START_TEST(test_default_output_dir)
{
  char here[1024], cmd[3072], dir[] = "/tmp/hbvm-cwd-XXXXXX";
  ck_assert_ptr_nonnull(getcwd(here, sizeof here));
  ck_assert_ptr_nonnull(mkdtemp(dir));
  snprintf(cmd, sizeof cmd, "cd %s && %s/%s %s/../models/pendulum.ham 2>/dev/null", dir, here, GENERATOR, here);
  ck_assert_int_eq(system(cmd), 0);
  snprintf(cmd, sizeof cmd, "test -f %s/pendulum.c && test -f %s/pendulum.h && test ! -e %s/generated", dir, dir, dir);
  ck_assert_msg(system(cmd) == 0, "hbvmgen without -o did not write pendulum.c and .h into the current directory");
  snprintf(cmd, sizeof cmd, "rm -r %s", dir);
  ck_assert_int_eq(system(cmd), 0);
}
END_TEST

/* Bad command lines exit 1 with "hbvmgen: error: ..." on stderr. */
static const char *const bad_options[] = {
    "--bogus ../models/pendulum.ham", "-s 0 ../models/pendulum.ham",   "-s x ../models/pendulum.ham",
    "-s 2.5 ../models/pendulum.ham",  "-s 21 ../models/pendulum.ham",  "-k 1 -s 2 ../models/pendulum.ham",
    "-k 0 ../models/pendulum.ham",    "-k many ../models/pendulum.ham", "-n 1abc ../models/pendulum.ham",
    "-n a-b ../models/pendulum.ham",  "../models/pendulum.ham -s",     "",
    "../models/pendulum.ham ../models/conical.ham", "no/such/model.ham",
    /* prefixes the emitted C cannot use: the runtime's, reserved, keywords */
    "-n hbvmrt ../models/pendulum.ham", "-n hbvmrt_x ../models/pendulum.ham", "-n _MATH ../models/pendulum.ham",
    "-n _ ../models/pendulum.ham",     "-n _x ../models/pendulum.ham",     "-n int ../models/pendulum.ham",
    "-n class ../models/pendulum.ham", "-n NAN ../models/pendulum.ham",
};

START_TEST(test_bad_options)
{
  char args[256], out[4096];
  snprintf(args, sizeof args, "--check %s", bad_options[_i]);
  ck_assert_msg(run_cli(args, 1, out, sizeof out) == 1, "'%s' did not exit 1: %s", args, out);
  ck_assert_msg(strstr(out, "hbvmgen: error: ") != NULL, "'%s': %s", args, out);
}
END_TEST

/* Building the step costs the size of the DAG, not its square: the work
 * counted by the DAG passes (Dag.work: nodes visited by dag_subst and
 * ad_gradient) for a chain of N sums of squares, with the constraint x[1]
 * = 1 as well, grows like N. Before, each affine derivative entry was
 * substituted by its own pass over the whole DAG (x[100000]: 57 s). */
START_TEST(test_step_build_linear)
{
  long work[2];
  for (int v = 0; v < 2; v++) {
    int n = v ? 4000 : 2000;
    char src[512];
    snprintf(src, sizeof src,
             "variables x[%d]\nU = sum(i in 1..%d, x[i]^2 * (1 + x[i]^2))\ng = x[1]^2 - 1\n"
             "q0 = [1 for i in 1..%d]\np0 = [0 for i in 1..%d]\n", n, n, n, n);
    Model *mod = load(src);
    mod->dag->work = 0;
    ck_assert_ptr_nonnull(step_build(mod, method_new(2, 2, MULT_POLY)));
    work[v] = mod->dag->work;
    arena_free_all();
  }
  ck_assert_msg(work[1] < 2.5 * work[0], "step building: %ld nodes visited for N = 2000, %ld for 4000", work[0],
                work[1]);
}
END_TEST

Suite *parser_suite(void)
{
  Suite *s = suite_create("parser");
  TCase *fe = tcase_create("front end");
  tcase_add_checked_fixture(fe, NULL, teardown);
  tcase_add_test(fe, test_scalar_variables);
  tcase_add_test(fe, test_array_variables);
  tcase_add_test(fe, test_definitions);
  tcase_add_test(fe, test_param);
  tcase_add_loop_test(fe, test_mass, 0, NCASES(mass_cases));
  tcase_add_test(fe, test_mass_params);
  tcase_add_test(fe, test_potential_default);
  tcase_add_test(fe, test_warm_start_table);
  tcase_add_test(fe, test_two_step_table);
  tcase_add_test(fe, test_constraints);
  tcase_add_test(fe, test_sum_and_indexing);
  tcase_add_loop_test(fe, test_functions, 0, NCASES(function_cases));
  tcase_add_loop_test(fe, test_functions_fold, 0, NCASES(function_cases));
  tcase_add_test(fe, test_value_arrays);
  tcase_add_test(fe, test_min_max_sign);
  tcase_add_test(fe, test_floor_mod);
  tcase_add_test(fe, test_iterators);
  tcase_add_test(fe, test_def_functions);
  tcase_add_test(fe, test_initial_values);
  tcase_add_test(fe, test_layout);
  tcase_add_test(fe, test_numbers);
  tcase_add_loop_test(fe, test_precedence, 0, NCASES(precedence_cases));
  tcase_add_test(fe, test_pi);
  tcase_add_loop_test(fe, test_degrees, 0, NCASES(degree_cases));
  tcase_add_test(fe, test_derivatives);
  tcase_add_test(fe, test_refused);
  tcase_add_test(fe, test_step_build_linear);
  suite_add_tcase(s, fe);
  TCase *cli = tcase_create("command line");
  tcase_set_timeout(cli, 60);
  tcase_add_loop_test(cli, test_check_models, 0, NCASES(check_cases));
  tcase_add_test(cli, test_check_options);
  tcase_add_test(cli, test_check_code);
  tcase_add_test(cli, test_help);
  tcase_add_test(cli, test_sugar_same_code);
  tcase_add_test(cli, test_check_advice);
  tcase_add_test(cli, test_default_output_dir);
  tcase_add_loop_test(cli, test_bad_options, 0, NCASES(bad_options));
  suite_add_tcase(s, cli);
  return s;
}
