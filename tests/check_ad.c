/* check_ad.c - Check suite for reverse-mode differentiation (gen/ad.c).
 *
 *   - every operator and function, composed with inputs, against central
 *     differences at NPOINTS random points inside its domain;
 *   - a Rosenbrock-like function with shared subexpressions against its
 *     hand-derived gradient and central differences;
 *   - the dot-product test of one seeded reverse sweep: <J u, w> = <u, J'w>
 *     for a vector function built from all the operations;
 *   - the four models of the paper, parsed from models/, analysed and
 *     differentiated as hbvmgen does: U, g, grad U and the sparse Jacobian
 *     of g against hand-derived formulas, and their structural zeros.
 * A finite-difference error is |ad - fd| / max(1, |fd|) with step
 * h = 1e-5 max(1, |x|); with HBVMGEN_TEST_VERBOSE set in the environment
 * the worst one of each expression is printed.
 * The suite is exposed as ad_suite(); the project's runner calls it. */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

Suite *ad_suite(void);

#define SEED 20240601u
#define NPOINTS 20
#define FD_TOL 1e-7
#define HAND_TOL 1e-12
#define DOT_TOL 1e-12
#define MAXN 9
#define NCASES(t) ((int)(sizeof(t) / sizeof((t)[0])))

/* ---- helpers ---- */

/* Uniform number in [lo, hi) from the C library's generator (seeded by
 * each test, so results do not depend on test order). */
static double uniform(double lo, double hi)
{
  return lo + (hi - lo) * (rand() / (RAND_MAX + 1.0));
}

/* Checked teardown: release the arena after every test. */
static void teardown(void)
{
  arena_free_all();
}

/* True when a node with operation op (and, for inputs, slot idx) is
 * reachable from root. */
static int reaches(const Dag *d, int root, Op op, int idx)
{
  unsigned char *mark = calloc((size_t)d->n, 1);
  int found = 0;
  ck_assert_ptr_nonnull(mark);
  dag_reach(d, &root, 1, mark);
  for (int id = 0; id < d->n; id++)
    found |= mark[id] && d->nodes[id].op == op && (op != OP_INPUT || d->nodes[id].idx == idx);
  free(mark);
  return found;
}

/* The largest error of the gradient nodes grad[0..n-1] of root against
 * central differences of root at x. The step actually taken, xp - xm, is
 * used so that rounding of x +- h does not count as an error. */
static double fd_error(const Dag *d, int root, const int *grad, int n, const double *x)
{
  double xs[MAXN], g[MAXN], worst = 0;
  memcpy(xs, x, (size_t)n * sizeof *xs);
  dag_eval_many(d, grad, n, x, NULL, g);
  for (int i = 0; i < n; i++) {
    double h = 1e-5 * fmax(1, fabs(x[i])), xp = x[i] + h, xm = x[i] - h, fp, fm;
    xs[i] = xp;
    fp = dag_eval(d, root, xs, NULL);
    xs[i] = xm;
    fm = dag_eval(d, root, xs, NULL);
    xs[i] = x[i];
    double fd = (fp - fm) / (xp - xm), err = fabs(g[i] - fd) / fmax(1, fabs(fd));
    ck_assert_msg(isfinite(g[i]) && isfinite(fd), "input %d: ad %g, fd %g", i, g[i], fd);
    worst = fmax(worst, err);
  }
  return worst;
}

/* Differentiate root with respect to inputs 0..n-1 and compare with central
 * differences at NPOINTS random points of [lo, hi]^n. Inputs that root does
 * not use must get the structural zero. Returns the worst error. */
static double check_fd(Dag *d, int root, int n, double lo, double hi, const char *what)
{
  int grad[MAXN];
  double x[MAXN], worst = 0;
  ck_assert_int_le(n, MAXN);
  ad_gradient(d, root, n, grad);
  for (int i = 0; i < n; i++)
    if (!reaches(d, root, OP_INPUT, i))
      ck_assert_msg(dag_is_zero(d, grad[i]), "%s: d/dx%d is not the zero node", what, i);
  srand(SEED);
  for (int pt = 0; pt < NPOINTS; pt++) {
    for (int i = 0; i < n; i++)
      x[i] = uniform(lo, hi);
    double err = fd_error(d, root, grad, n, x);
    ck_assert_msg(err <= FD_TOL, "%s: gradient off by %.3e at point %d", what, err, pt);
    worst = fmax(worst, err);
  }
  if (getenv("HBVMGEN_TEST_VERBOSE"))
    printf("ad: %-24s worst finite-difference error %.2e\n", what, worst);
  return worst;
}

/* True when |got - want| <= tol max(1, |want|). */
static int close_to(double got, double want, double tol)
{
  return fabs(got - want) <= tol * fmax(1, fabs(want));
}

/* ---- every operation ---- */

enum { B_NONE, B_CONST, B_VAR };

/* One operation applied to operands built from two inputs xa, xb in
 * [-1, 1]: a = amid + arad xa xb, and b = bmid (B_CONST) or
 * b = bmid + brad (xa - xb) / 2 (B_VAR), so a and b stay in
 * [mid - rad, mid + rad], chosen away from singularities and branch cuts. */
typedef struct {
  const char *name;
  Op op;
  double amid, arad;
  int bkind;
  double bmid, brad;
} OpCase;

static const OpCase op_cases[] = {
    {"+", OP_ADD, 0, 1, B_VAR, 0, 1},
    {"-", OP_SUB, 0, 1, B_VAR, 0, 1},
    {"*", OP_MUL, 0.5, 1, B_VAR, 0, 1},
    {"/", OP_DIV, 0, 1, B_VAR, 1.25, 0.75},
    {"unary -", OP_NEG, 0.3, 1, B_NONE, 0, 0},
    {"^2", OP_POW, 1.25, 0.75, B_CONST, 2, 0},
    {"^3, negative base", OP_POW, -1.25, 0.75, B_CONST, 3, 0},
    {"^2.5", OP_POW, 1.25, 0.75, B_CONST, 2.5, 0},
    {"^-1", OP_POW, 1.25, 0.75, B_CONST, -1, 0},
    {"^-1.5", OP_POW, 1.25, 0.75, B_CONST, -1.5, 0},
    {"^ variable (pow)", OP_POW, 1.25, 0.75, B_VAR, 0, 2},
    {"sin", OP_SIN, 0, 3, B_NONE, 0, 0},
    {"cos", OP_COS, 0, 3, B_NONE, 0, 0},
    {"tan", OP_TAN, 0, 1.2, B_NONE, 0, 0},
    {"asin", OP_ASIN, 0, 0.85, B_NONE, 0, 0},
    {"acos", OP_ACOS, 0, 0.85, B_NONE, 0, 0},
    {"atan", OP_ATAN, 0, 3, B_NONE, 0, 0},
    {"atan2, x > 0", OP_ATAN2, 0, 1, B_VAR, 0.65, 0.35},
    {"atan2, x < 0", OP_ATAN2, 0.6, 0.4, B_VAR, -0.65, 0.35},
    {"sinh", OP_SINH, 0, 2, B_NONE, 0, 0},
    {"cosh", OP_COSH, 0, 2, B_NONE, 0, 0},
    {"tanh", OP_TANH, 0, 2, B_NONE, 0, 0},
    {"exp", OP_EXP, 0, 2, B_NONE, 0, 0},
    {"log", OP_LOG, 1.6, 1.4, B_NONE, 0, 0},
    {"sqrt", OP_SQRT, 1.6, 1.4, B_NONE, 0, 0},
    {"abs, a > 0", OP_ABS, 0.6, 0.4, B_NONE, 0, 0},
    {"abs, a < 0", OP_ABS, -0.6, 0.4, B_NONE, 0, 0},
    {"min, a < b", OP_MIN, -0.6, 0.4, B_VAR, 0.65, 0.35},
    {"min, a > b", OP_MIN, 0.6, 0.4, B_VAR, -0.65, 0.35},
    {"max, a < b", OP_MAX, -0.6, 0.4, B_VAR, 0.65, 0.35},
    {"max, a > b", OP_MAX, 0.6, 0.4, B_VAR, -0.65, 0.35},
    {"sign, a > 0", OP_SIGN, 0.6, 0.4, B_NONE, 0, 0},
};

/* Build the operation of case c on inputs xa, xb (see OpCase). */
static int build_case(Dag *d, const OpCase *c, int xa, int xb)
{
  int a = dag_add(d, dag_const(d, c->amid), dag_mul(d, dag_const(d, c->arad), dag_mul(d, xa, xb)));
  int b = -1;
  if (c->bkind == B_CONST)
    b = dag_const(d, c->bmid);
  else if (c->bkind == B_VAR)
    b = dag_add(d, dag_const(d, c->bmid), dag_mul(d, dag_const(d, c->brad / 2), dag_sub(d, xa, xb)));
  return dag_op(d, c->op, a, b);
}

/* f = F + z F with F the case's operation on x, y, so F has two users; a
 * fourth input is unused and must get a structural zero. */
START_TEST(test_op_gradient)
{
  const OpCase *c = &op_cases[_i];
  Dag *d = dag_new();
  int f = build_case(d, c, dag_input(d, 0), dag_input(d, 1));
  int root = dag_add(d, f, dag_mul(d, dag_input(d, 2), f));
  ck_assert_msg(reaches(d, root, c->op, -1), "%s was simplified away", c->name);
  check_fd(d, root, 4, -1, 1, c->name);
}
END_TEST

/* At a kink the sweep takes the documented subgradient (ad.c): d abs = 0
 * and d sign = 0 at 0; min and max give half to each operand at a tie. */
START_TEST(test_subgradients_at_ties)
{
  static const struct {
    Op op;
    double x, y, dx, dy;
  } cases[] = {
      {OP_ABS, 0, 0, 0, 0},      {OP_SIGN, 0, 0, 0, 0},      {OP_MIN, 1.5, 1.5, 0.5, 0.5},
      {OP_MAX, -2, -2, 0.5, 0.5}, {OP_MIN, 1, 2, 1, 0},       {OP_MAX, 1, 2, 0, 1},
  };
  for (int i = 0; i < NCASES(cases); i++) {
    Dag *d = dag_new();
    int x = dag_input(d, 0), y = dag_input(d, 1), grad[2];
    int f = dag_op(d, cases[i].op, x, op_arity(cases[i].op) == 2 ? y : -1);
    ad_gradient(d, f, 2, grad);
    double q[2] = {cases[i].x, cases[i].y};
    double dx = dag_eval(d, grad[0], q, NULL), dy = dag_eval(d, grad[1], q, NULL);
    ck_assert_msg(dx == cases[i].dx && dy == cases[i].dy, "%s at (%g, %g): gradient (%g, %g), want (%g, %g)",
                  op_name(cases[i].op), q[0], q[1], dx, dy, cases[i].dx, cases[i].dy);
  }
}
END_TEST

/* ---- a composite with shared subexpressions ---- */

#define NROS 6

/* Build f = sum_i 100 (x[i+1] - t_i)^2 + (1 - x[i])^2 + s sin(s), with
 * t_i = x[i]^2 and s = sum_i t_i sharing the squares. */
static int rosen_build(Dag *d)
{
  int t[NROS], one = dag_const(d, 1), s = dag_const(d, 0), f = dag_const(d, 0);
  for (int i = 0; i < NROS; i++) {
    t[i] = dag_mul(d, dag_input(d, i), dag_input(d, i));
    s = dag_add(d, s, t[i]);
  }
  for (int i = 0; i + 1 < NROS; i++) {
    int r = dag_sub(d, dag_input(d, i + 1), t[i]), o = dag_sub(d, one, dag_input(d, i));
    f = dag_add(d, f, dag_add(d, dag_mul(d, dag_const(d, 100), dag_mul(d, r, r)), dag_mul(d, o, o)));
  }
  return dag_add(d, f, dag_mul(d, s, dag_op(d, OP_SIN, s, -1)));
}

/* The hand-derived gradient of rosen_build's function. */
static void rosen_grad(const double *x, double *g)
{
  double s = 0;
  for (int i = 0; i < NROS; i++)
    s += x[i] * x[i];
  for (int i = 0; i < NROS; i++) {
    g[i] = 2 * x[i] * (sin(s) + s * cos(s));
    if (i + 1 < NROS)
      g[i] += -400 * x[i] * (x[i + 1] - x[i] * x[i]) - 2 * (1 - x[i]);
    if (i > 0)
      g[i] += 200 * (x[i] - x[i - 1] * x[i - 1]);
  }
}

START_TEST(test_rosenbrock)
{
  Dag *d = dag_new();
  int root = rosen_build(d), grad[NROS], again[NROS];
  double x[NROS], g[NROS], want[NROS];
  ad_gradient(d, root, NROS, grad);
  int n = d->n;
  ad_gradient(d, root, NROS, again);
  ck_assert_int_eq(d->n, n); /* a second sweep finds every node it needs */
  ck_assert_mem_eq(grad, again, sizeof grad);
  ck_assert_int_eq(rosen_build(d), root);
  srand(SEED);
  for (int pt = 0; pt < NPOINTS; pt++) {
    for (int i = 0; i < NROS; i++)
      x[i] = uniform(-1.5, 1.5);
    dag_eval_many(d, grad, NROS, x, NULL, g);
    rosen_grad(x, want);
    for (int i = 0; i < NROS; i++)
      ck_assert_msg(close_to(g[i], want[i], HAND_TOL), "d/dx%d: ad %.17g, hand %.17g", i, g[i], want[i]);
  }
  check_fd(d, root, NROS, -1.5, 1.5, "rosenbrock");
}
END_TEST

/* ---- dot-product test of one seeded reverse sweep ---- */

#define NDOT 5
#define PDOT 4

/* f: R^NDOT -> R^PDOT, output r the sum of the cases c = r mod PDOT of
 * op_cases on two different inputs, so the outputs share inputs and
 * subexpressions. */
static void dot_build(Dag *d, int *roots)
{
  for (int r = 0; r < PDOT; r++)
    roots[r] = dag_const(d, 0);
  for (int c = 0; c < NCASES(op_cases); c++) {
    int r = c % PDOT, xa = dag_input(d, c % NDOT), xb = dag_input(d, (c + 1 + r) % NDOT);
    roots[r] = dag_add(d, roots[r], build_case(d, &op_cases[c], xa, xb));
  }
}

/* J u from per-output gradients, J'w from one ad_reverse seeded with the
 * constants w; <J u, w> = <u, J'w> to DOT_TOL relative to the sum of the
 * magnitudes of the products. Seeds NULL must give the column sums of J. */
START_TEST(test_dot_product)
{
  Dag *d = dag_new();
  int roots[PDOT], G[PDOT][NDOT], seeds[PDOT], jtw[NDOT];
  double x[NDOT], J[PDOT][NDOT], u[NDOT], w[PDOT], v[NDOT];
  dot_build(d, roots);
  for (int r = 0; r < PDOT; r++)
    ad_gradient(d, roots[r], NDOT, G[r]);
  srand(SEED);
  for (int pt = 0; pt < 5; pt++) {
    for (int i = 0; i < NDOT; i++)
      x[i] = uniform(-1, 1);
    for (int r = 0; r < PDOT; r++)
      dag_eval_many(d, G[r], NDOT, x, NULL, J[r]);
    ad_reverse(d, roots, NULL, PDOT, NDOT, jtw);
    dag_eval_many(d, jtw, NDOT, x, NULL, v);
    for (int i = 0; i < NDOT; i++) {
      double sum = 0;
      for (int r = 0; r < PDOT; r++)
        sum += J[r][i];
      ck_assert_msg(close_to(v[i], sum, DOT_TOL), "seeds NULL: %.17g, column sum %.17g", v[i], sum);
    }
    for (int trial = 0; trial < 4; trial++) {
      double lhs = 0, rhs = 0, scale = 0;
      for (int i = 0; i < NDOT; i++)
        u[i] = uniform(-1, 1);
      for (int r = 0; r < PDOT; r++) {
        w[r] = uniform(-1, 1);
        seeds[r] = dag_const(d, w[r]);
      }
      ad_reverse(d, roots, seeds, PDOT, NDOT, jtw);
      dag_eval_many(d, jtw, NDOT, x, NULL, v);
      for (int r = 0; r < PDOT; r++)
        for (int i = 0; i < NDOT; i++) {
          lhs += J[r][i] * u[i] * w[r];
          scale += fabs(J[r][i] * u[i] * w[r]);
        }
      for (int i = 0; i < NDOT; i++) {
        rhs += u[i] * v[i];
        scale += fabs(u[i] * v[i]);
      }
      ck_assert_msg(fabs(lhs - rhs) <= DOT_TOL * scale, "<Ju,w> = %.17g, <u,J'w> = %.17g", lhs, rhs);
    }
  }
}
END_TEST

/* ---- the paper's models ---- */

/* U, grad U, g and the dense Jacobian J (nu x m, row a = grad g_a) of a
 * model at q, derived by hand. */
typedef void HandFn(int m, const double *q, double *U, double *gU, double *g, double *J);

/* Pendulum (m = 2) and conical pendulum (m = 3): U = q_m, g = |q|^2 - 1. */
static void hand_sphere(int m, const double *q, double *U, double *gU, double *g, double *J)
{
  *U = q[m - 1];
  g[0] = -1;
  for (int i = 0; i < m; i++) {
    gU[i] = i == m - 1;
    g[0] += q[i] * q[i];
    J[i] = 2 * q[i];
  }
}

/* Modified pendulum: U = q3^4, g = q1^6 + q2^4 + q3^2 - 0.625. */
static void hand_modified(int m, const double *q, double *U, double *gU, double *g, double *J)
{
  (void)m;
  *U = pow(q[2], 4);
  gU[0] = gU[1] = 0;
  gU[2] = 4 * pow(q[2], 3);
  g[0] = pow(q[0], 6) + pow(q[1], 4) + q[2] * q[2] - 0.625;
  J[0] = 6 * pow(q[0], 5);
  J[1] = 4 * pow(q[1], 3);
  J[2] = 2 * q[2];
}

/* Three satellites q_i = q[3i..3i+2]: U = -sum 1/|q_i|, and for the tether
 * a between satellites i and j = i+1 mod 3, g_a = |q_i - q_j|^2 - 1. */
static void hand_satellites(int m, const double *q, double *U, double *gU, double *g, double *J)
{
  *U = 0;
  for (int i = 0; i < 3; i++) {
    const double *qi = q + 3 * i;
    double r = sqrt(qi[0] * qi[0] + qi[1] * qi[1] + qi[2] * qi[2]);
    int j = (i + 1) % 3;
    *U -= 1 / r;
    g[i] = -1;
    for (int k = 0; k < 3; k++) {
      double dk = qi[k] - q[3 * j + k];
      gU[3 * i + k] = qi[k] / (r * r * r);
      g[i] += dk * dk;
      J[i * m + 3 * i + k] = 2 * dk;
      J[i * m + 3 * j + k] = -2 * dk;
    }
  }
}

static const struct {
  const char *file;
  int m, nu, degU, degg;
  int grad_nnz, jac_nnz; /* structural nonzeros of grad U, of each Jacobian column */
  int unit_grad;         /* coordinate whose dU/dq is the constant node 1, or -1 */
  HandFn *hand;
} model_cases[] = {
    {"../models/pendulum.ham", 2, 1, 1, 2, 1, 2, 1, hand_sphere},
    {"../models/conical.ham", 3, 1, 1, 2, 1, 3, 2, hand_sphere},
    {"../models/modified.ham", 3, 1, 4, 6, 1, 3, -1, hand_modified},
    {"../models/satellites.ham", 9, 3, DEG_NONPOLY, 2, 9, 6, -1, hand_satellites},
};

/* Read, parse, analyse and differentiate the model at path as hbvmgen
 * does; *src receives the text, which must outlive the model. */
static Model *load_model(const char *path, char **src)
{
  FILE *f = fopen(path, "rb");
  ck_assert_msg(f != NULL, "cannot open %s", path);
  *src = malloc(1 << 16);
  ck_assert_ptr_nonnull(*src);
  size_t len = fread(*src, 1, 1 << 16, f);
  ck_assert_msg(!ferror(f) && feof(f), "cannot read %s (or larger than 64 KiB)", path);
  fclose(f);
  diag_begin(path, *src, len);
  Stmt *prog = parse_model(*src, len);
  ck_assert_msg(prog != NULL && diag_error_count() == 0, "%s does not parse", path);
  Model *mod = analyse(path, prog);
  ck_assert_msg(mod != NULL, "%s does not analyse", path);
  model_differentiate(mod);
  return mod;
}

/* The model's sizes and degrees, the structure of grad U and of the
 * Jacobian, then U, g, grad U and J at random points against the hand
 * formulas (coordinates +-[0.2, 1.5], away from the satellites' 1/|q_i|). */
START_TEST(test_model)
{
  char *src;
  Model *mod = load_model(model_cases[_i].file, &src);
  const Dag *d = mod->dag;
  int m = mod->m, nu = mod->nu, nnz = 0;
  double prm[8] = {0}, q[MAXN], U, gU[MAXN], g[MAXN], J[MAXN * MAXN], val[MAXN], Jad[MAXN * MAXN];
  ck_assert_int_eq(m, model_cases[_i].m);
  ck_assert_int_eq(nu, model_cases[_i].nu);
  ck_assert_int_eq(mod->degU, model_cases[_i].degU);
  ck_assert_int_eq(mod->degg, model_cases[_i].degg);
  ck_assert_int_le(mod->nparams, 8);
  for (int i = 0; i < mod->nparams; i++)
    prm[i] = mod->params[i].value;
  for (int i = 0; i < m; i++)
    nnz += !dag_is_zero(d, mod->gradU[i]);
  ck_assert_int_eq(nnz, model_cases[_i].grad_nnz);
  if (model_cases[_i].unit_grad >= 0)
    ck_assert(dag_is_const(d, mod->gradU[model_cases[_i].unit_grad], 1));
  for (int a = 0; a < nu; a++) {
    ck_assert_int_eq(mod->jac[a].n, model_cases[_i].jac_nnz);
    for (int e = 0; e < mod->jac[a].n; e++)
      ck_assert(mod->jac[a].e[e].coord >= (e ? mod->jac[a].e[e - 1].coord + 1 : 0) && mod->jac[a].e[e].coord < m);
  }
  srand(SEED);
  for (int pt = 0; pt < NPOINTS; pt++) {
    for (int i = 0; i < m; i++)
      q[i] = (rand() % 2 ? 1 : -1) * uniform(0.2, 1.5);
    memset(J, 0, sizeof J);
    memset(Jad, 0, sizeof Jad);
    model_cases[_i].hand(m, q, &U, gU, g, J);
    ck_assert(close_to(dag_eval(d, mod->U, q, prm), U, HAND_TOL));
    dag_eval_many(d, mod->gradU, m, q, prm, val);
    for (int i = 0; i < m; i++)
      ck_assert_msg(close_to(val[i], gU[i], HAND_TOL), "dU/dq%d: %.17g, hand %.17g", i, val[i], gU[i]);
    dag_eval_many(d, mod->g, nu, q, prm, val);
    for (int a = 0; a < nu; a++) {
      ck_assert_msg(close_to(val[a], g[a], HAND_TOL), "g%d: %.17g, hand %.17g", a, val[a], g[a]);
      for (int e = 0; e < mod->jac[a].n; e++)
        Jad[a * m + mod->jac[a].e[e].coord] = dag_eval(d, mod->jac[a].e[e].node, q, prm);
    }
    for (int k = 0; k < nu * m; k++)
      ck_assert_msg(close_to(Jad[k], J[k], HAND_TOL), "dg%d/dq%d: %.17g, hand %.17g", k / m, k % m, Jad[k], J[k]);
  }
  free(src);
}
END_TEST

Suite *ad_suite(void)
{
  Suite *s = suite_create("ad");
  TCase *tc = tcase_create("ad");
  tcase_add_checked_fixture(tc, NULL, teardown);
  tcase_add_loop_test(tc, test_op_gradient, 0, NCASES(op_cases));
  tcase_add_test(tc, test_subgradients_at_ties);
  tcase_add_test(tc, test_rosenbrock);
  tcase_add_test(tc, test_dot_product);
  tcase_add_loop_test(tc, test_model, 0, NCASES(model_cases));
  suite_add_tcase(s, tc);
  return s;
}
