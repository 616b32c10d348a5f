/* check_dag.c - Check suite for the expression DAG (gen/dag.c) and the
 * choice of k (method_auto_k in gen/method.c).
 *
 * Expressions are written in reverse Polish notation and built by rpn()
 * through the public dag_* calls, so every case is one line of a table:
 *   - common subexpressions: node counts and node identity, also after the
 *     node array and the hash table have grown;
 *   - constant folding, which must never create a NaN, an infinity or -0.0
 *     constant, and the algebraic simplifications;
 *   - the polynomial degree of each node;
 *   - method_auto_k on polynomial and non-polynomial degrees;
 *   - dag_eval, dag_eval_many and dag_subst against C evaluation;
 *   - dag_positive (bounds.c), and the M(q) pivot it leaves unguarded.
 * The suite is exposed as dag_suite(); the project's runner calls it. */
#define _POSIX_C_SOURCE 200809L /* popen */
#include <check.h>
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

Suite *dag_suite(void);

#define SEED 20240601u
#define NPOINTS 20
#define NCASES(t) ((int)(sizeof(t) / sizeof((t)[0])))

/* ---- helpers ---- */

/* Uniform number in [lo, hi) from the C library's generator (seeded by
 * each test that uses it, so results do not depend on test order). */
static double uniform(double lo, double hi)
{
  return lo + (hi - lo) * (rand() / (RAND_MAX + 1.0));
}

/* The operation named by an RPN token: + - * / ^ ~ (negation), or an
 * operation's name in any case (sin, atan2, pow, abs...); OP_COUNT if the
 * token names none. */
static Op rpn_op(const char *tok)
{
  static const char sym[] = "+-*/^~";
  static const Op symop[] = {OP_ADD, OP_SUB, OP_MUL, OP_DIV, OP_POW, OP_NEG};
  const char *c = tok[0] && !tok[1] ? strchr(sym, tok[0]) : NULL;
  if (c)
    return symop[c - sym];
  for (int op = OP_ADD; op < OP_COUNT; op++) {
    const char *name = op_name((Op)op);
    size_t i = 0;
    while (name[i] && tok[i] && toupper((unsigned char)tok[i]) == name[i])
      i++;
    if (!name[i] && !tok[i])
      return (Op)op;
  }
  return OP_COUNT;
}

/* Build the expression src, written in reverse Polish notation with tokens
 * separated by blanks: x y z are inputs 0..2, p q parameters 0..1, numbers
 * constants, the rest operations (see rpn_op). Fails the test on a
 * malformed expression. */
static int rpn(Dag *d, const char *src)
{
  int stack[32], top = 0;
  const char *s = src;
  for (;;) {
    char tok[32], *end;
    s += strspn(s, " ");
    size_t n = strcspn(s, " ");
    if (!n)
      break;
    ck_assert_msg(n < sizeof tok && top < 32, "bad rpn '%s'", src);
    memcpy(tok, s, n);
    tok[n] = 0;
    s += n;
    double v = strtod(tok, &end);
    Op op = rpn_op(tok);
    if (!*end)
      stack[top++] = dag_const(d, v);
    else if (n == 1 && strchr("xyz", tok[0]))
      stack[top++] = dag_input(d, tok[0] - 'x');
    else if (n == 1 && strchr("pq", tok[0]))
      stack[top++] = dag_param(d, tok[0] - 'p');
    else {
      ck_assert_msg(op < OP_COUNT && op_arity(op) <= top, "bad token '%s' in '%s'", tok, src);
      int arity = op_arity(op);
      top -= arity;
      stack[top] = dag_op(d, op, stack[top], arity == 2 ? stack[top + 1] : -1);
      top++;
    }
  }
  ck_assert_msg(top == 1, "rpn '%s' leaves %d values", src, top);
  return stack[0];
}

/* Number of nodes of the DAG with operation op. */
static int count_op(const Dag *d, Op op)
{
  int k = 0;
  for (int id = 0; id < d->n; id++)
    k += d->nodes[id].op == op;
  return k;
}

/* True when node id is a constant that folding must never produce: NaN, an
 * infinity or -0.0. */
static int bad_const(const Dag *d, int id)
{
  const Node *n = &d->nodes[id];
  return n->op == OP_CONST && (!isfinite(n->val) || (n->val == 0 && signbit(n->val)));
}

/* Checked teardown: release the arena after every test. */
static void teardown(void)
{
  arena_free_all();
}

/* ---- common subexpressions ---- */

/* Pairs of expressions that must (or must not) be the same node. */
static const struct {
  const char *a, *b;
  int same;
} same_cases[] = {
    {"x y *", "y x *", 1},         {"x y +", "y x +", 1},
    {"x sin", "x sin", 1},         {"x y * z +", "z y x * +", 1},
    {"x 2 ^ y exp *", "y exp x 2 ^ *", 1},
    {"x y -", "y x -", 0},         {"x y /", "y x /", 0},
    {"x y ^", "y x ^", 0},         {"x y atan2", "y x atan2", 0},
    {"x sin", "x cos", 0},         {"x p *", "x q *", 0},
};

START_TEST(test_cse_identity)
{
  Dag *d = dag_new();
  for (int i = 0; i < NCASES(same_cases); i++) {
    int a = rpn(d, same_cases[i].a), b = rpn(d, same_cases[i].b);
    ck_assert_msg((a == b) == same_cases[i].same, "'%s' vs '%s': nodes %d and %d", same_cases[i].a,
                  same_cases[i].b, a, b);
  }
}
END_TEST

/* Expressions and how many nodes of one operation they may create. */
static const struct {
  const char *e;
  Op op;
  int count, nodes; /* nodes: total size of the DAG (which starts with the constant 0), 0 to skip */
} count_cases[] = {
    {"x y * x y * +", OP_MUL, 1, 5},
    {"x y * y x * +", OP_MUL, 1, 5},
    {"x sin x sin *", OP_SIN, 1, 4},
    {"x sin y cos * x sin y cos * -", OP_SIN, 1, 0},
    {"x y + sqrt x y + sqrt / y x + sqrt +", OP_SQRT, 1, 0},
    {"x y + sqrt x y + sqrt / y x + sqrt +", OP_ADD, 2, 0},
};

START_TEST(test_cse_counts)
{
  for (int i = 0; i < NCASES(count_cases); i++) {
    Dag *d = dag_new();
    rpn(d, count_cases[i].e);
    ck_assert_msg(count_op(d, count_cases[i].op) == count_cases[i].count, "'%s': %d %s nodes, want %d",
                  count_cases[i].e, count_op(d, count_cases[i].op), op_name(count_cases[i].op),
                  count_cases[i].count);
    if (count_cases[i].nodes)
      ck_assert_int_eq(d->n, count_cases[i].nodes);
  }
}
END_TEST

/* Build a chain of NCHAIN distinct nodes, t = t * x + i; returns the last. */
#define NCHAIN 6000
static int chain(Dag *d)
{
  int t = dag_input(d, 0);
  for (int i = 1; i <= NCHAIN; i++)
    t = dag_add(d, dag_mul(d, t, dag_input(d, 0)), dag_const(d, i));
  return t;
}

/* Sharing survives the growth of the node array and of the hash table. */
START_TEST(test_cse_growth)
{
  Dag *d = dag_new();
  int last = chain(d), n = d->n;
  ck_assert_int_gt(n, 3 * NCHAIN);
  ck_assert_int_eq(chain(d), last);
  ck_assert_int_eq(d->n, n);
}
END_TEST

/* ---- folding and simplification ---- */

START_TEST(test_fold_values)
{
  const struct {
    const char *e;
    double v;
  } cases[] = {
      {"2 3 * 1 +", 7},
      {"2 sin", sin(2)},
      {"4 sqrt 3 ^", 8},
      {"1 2 atan2 3 / 0.5 exp -", atan2(1, 2) / 3 - exp(0.5)},
      {"1 3 / ~ 2 pow", pow(-1.0 / 3, 2)},
      {"-1 abs 0.5 acos +", 1 + acos(0.5)},
      {"0 -1 *", 0},
      {"0 ~", 0},
      {"0 -1 /", 0},
  };
  Dag *d = dag_new();
  for (int i = 0; i < NCASES(cases); i++) {
    int id = rpn(d, cases[i].e);
    ck_assert_msg(d->nodes[id].op == OP_CONST, "'%s' not folded", cases[i].e);
    ck_assert_msg(d->nodes[id].val == cases[i].v && !signbit(d->nodes[id].val) == !signbit(cases[i].v),
                  "'%s' folds to %.17g, want %.17g", cases[i].e, d->nodes[id].val, cases[i].v);
  }
  ck_assert_int_eq(count_op(d, OP_CONST), d->n);
  ck_assert_int_eq(dag_const(d, -0.0), dag_const(d, 0.0));
  ck_assert(!signbit(d->nodes[dag_const(d, -0.0)].val));
}
END_TEST

/* Operations on constants whose value is NaN, an infinity or -0.0. */
static const struct {
  Op op;
  double a, b;
} nonfinite_cases[] = {
    {OP_DIV, 1, 0},      {OP_DIV, -1, 0},      {OP_DIV, 0, 0},       {OP_LOG, 0, 0},
    {OP_LOG, -1, 0},     {OP_SQRT, -1, 0},     {OP_POW, 0, -1},      {OP_POW, -8, 0.5},
    {OP_ASIN, 2, 0},     {OP_ACOS, -3, 0},     {OP_EXP, 1000, 0},    {OP_COSH, -1000, 0},
    {OP_MUL, 1e300, 1e300}, {OP_SUB, -1e308, 1e308}, {OP_MUL, -1e-200, 1e-200},
    {OP_MUL, 0, -1},     {OP_MUL, -2, 0},      {OP_NEG, 0, 0},       {OP_DIV, 0, -5},
    {OP_SIN, 0, 0},      {OP_TANH, 0, 0},      {OP_ATAN, 0, 0},      {OP_ASIN, 0, 0},
};

/* No case folds to a bad constant: either the node is left for run time,
 * where it evaluates as C does, or it is a constant equal to the C value
 * (+0 for the signed zeros). */
START_TEST(test_fold_nonfinite)
{
  Dag *d = dag_new();
  for (int i = 0; i < NCASES(nonfinite_cases); i++) {
    Op op = nonfinite_cases[i].op;
    double a = nonfinite_cases[i].a, b = nonfinite_cases[i].b, c = op_apply(op, a, b);
    int id = dag_op(d, op, dag_const(d, a), op_arity(op) == 2 ? dag_const(d, b) : -1);
    double v = dag_eval(d, id, NULL, NULL);
    ck_assert_msg(!bad_const(d, id), "%s(%g, %g) folded to %g", op_name(op), a, b, d->nodes[id].val);
    if (d->nodes[id].op == OP_CONST)
      ck_assert_msg(v == c, "%s(%g, %g) = %g, want %g", op_name(op), a, b, v, c);
    else
      ck_assert_msg(!isfinite(c) || (c == 0 && signbit(c)), "%s(%g, %g) = %g not folded", op_name(op), a, b, c);
    if (!isfinite(c))
      ck_assert_msg(d->nodes[id].op != OP_CONST && (v == c || (isnan(v) && isnan(c))),
                    "%s(%g, %g) evaluates to %g, want %g", op_name(op), a, b, v, c);
  }
  for (int id = 0; id < d->n; id++)
    ck_assert_msg(!bad_const(d, id), "node %d is the constant %g", id, d->nodes[id].val);
}
END_TEST

/* Each expression simplifies to the node of the second one. */
static const struct {
  const char *e, *want;
} simplify_cases[] = {
    {"x 0 +", "x"},      {"0 x +", "x"},         {"x 0 -", "x"},         {"x 1 *", "x"},
    {"1 x *", "x"},      {"x 0 *", "0"},         {"0 x *", "0"},         {"x x -", "0"},
    {"x ~ ~", "x"},      {"x 1 ^", "x"},         {"x 0 ^", "1"},         {"x 1 /", "x"},
    {"x sin 0 *", "0"},  {"x y * y x * -", "0"}, {"x y + ~ ~", "y x +"}, {"x y + 1 ^", "x y +"},
    {"x sin 0 ^", "1"},  {"0 x ~ -", "x"},       {"x y ~ +", "x y -"},   {"x p * 1 *", "p x *"},
    /* powers of two float up products and common ones out of sums (exact) */
    {"0.5 x * 2 y * *", "x y *"},                {"0.5 x x * * x * 2 y * *", "x x * x * y *"},
    {"2 x * y *", "2 x y * *"},                  {"2 x * 2 y * +", "2 x y + *"},
    {"2 x * -2 y * +", "2 x y - *"},             {"4 x * y * 3 *", "12 x y * *"},
    {"2 x * 4 y * +", "4 y * 2 x * +"},          {"3 x * y *", "3 x * y *"},
    /* differences shared with their reverse, negations out of differences (exact) */
    {"x y - y x - +", "0"},                      {"x ~ y -", "x y + ~"},
};

START_TEST(test_simplify)
{
  Dag *d = dag_new();
  for (int i = 0; i < NCASES(simplify_cases); i++) {
    int want = rpn(d, simplify_cases[i].want);
    ck_assert_msg(rpn(d, simplify_cases[i].e) == want, "'%s' does not simplify to '%s'", simplify_cases[i].e,
                  simplify_cases[i].want);
  }
}
END_TEST

/* The power-of-two floating is exact: each expression evaluates bitwise as
 * the same arithmetic done in C in the written order, at random points. */
static double pow2_written(const double *v)
{
  double r2 = v[0] * v[0] + v[1] * v[1], s = sqrt(r2), inv = 1 / s, k = (0.5 * (inv * inv)) * inv;
  return 0.3 * ((k * (2 * v[0])) - (2 * v[1]) * (0.5 * v[2])) + 0.25 * ((2 * v[0]) * (2 * v[1]));
}

START_TEST(test_pow2_exact)
{
  Dag *d = dag_new();
  int e = rpn(d, "0.3 0.5 1 x x * y y * + sqrt / 2 ^ * 1 x x * y y * + sqrt / * 2 x * * 2 y * 0.5 z * * - * "
                 "0.25 2 x * 2 y * * * +");
  unsigned char *mark = calloc((size_t)d->n, 1);
  ck_assert_ptr_nonnull(mark);
  dag_reach(d, &e, 1, mark);
  for (int id = 0; id < d->n; id++) { /* the factors 2 and 1/2 all floated away */
    const Node *n = &d->nodes[id];
    int two = n->op == OP_MUL && (dag_is_const(d, n->a, 2) || dag_is_const(d, n->a, 0.5) ||
                                  dag_is_const(d, n->b, 2) || dag_is_const(d, n->b, 0.5));
    ck_assert_msg(!mark[id] || !two, "node %d is a product by 2 or 1/2", id);
  }
  free(mark);
  /* scales whose product leaves the normal range stay where they are */
  int big = dag_const(d, 0x1p1000), tiny = dag_const(d, 0x1p-1000), x = rpn(d, "x"), y = rpn(d, "y");
  int huge = dag_mul(d, dag_mul(d, big, x), dag_mul(d, big, y)), small = dag_mul(d, dag_mul(d, tiny, x), dag_mul(d, tiny, y));
  for (int id = 0; id < d->n; id++)
    ck_assert_msg(!bad_const(d, id) && !(d->nodes[id].op == OP_CONST && d->nodes[id].val != 0 &&
                                         fabs(d->nodes[id].val) < 0x1p-1000),
                  "node %d is the constant %g", id, d->nodes[id].val);
  double v[3] = {0.75, -1.5, 0};
  ck_assert(dag_eval(d, huge, v, NULL) == (0x1p1000 * 0.75) * (0x1p1000 * -1.5));
  ck_assert(dag_eval(d, small, v, NULL) == (0x1p-1000 * 0.75) * (0x1p-1000 * -1.5));
  srand(SEED);
  for (int pt = 0; pt < 1000; pt++) {
    double v[3] = {uniform(-3, 3), uniform(-3, 3), uniform(-3, 3)};
    double got = dag_eval(d, e, v, NULL), want = pow2_written(v);
    ck_assert_msg(got == want, "at (%g, %g, %g): %.17g, written order %.17g", v[0], v[1], v[2], got, want);
  }
}
END_TEST

/* ---- degrees ---- */

static const struct {
  const char *e;
  int deg;
} degree_cases[] = {
    {"2", 0},           {"p", 0},           {"x", 1},            {"x y *", 2},
    {"x 3 ^", 3},       {"x y + 2 ^", 2},   {"x 2 /", 1},        {"1 x /", DEG_NONPOLY},
    {"x sin", DEG_NONPOLY}, {"2 sin", 0},   {"p x 2 ^ *", 2},    {"x sqrt", DEG_NONPOLY},
    {"x 2.5 ^", DEG_NONPOLY}, {"p sin x *", 1}, {"x p /", 1},    {"x -1 ^", DEG_NONPOLY},
    {"x y 3 ^ * z -", 4}, {"x y ^", DEG_NONPOLY}, {"p 2.5 ^", 0}, {"x ~ 2 ^ y +", 2},
    {"x abs", DEG_NONPOLY}, {"x 2 ^ 3 ^", 6},  {"x sin 2 ^", DEG_NONPOLY},
};

START_TEST(test_degree)
{
  Dag *d = dag_new();
  for (int i = 0; i < NCASES(degree_cases); i++) {
    int id = rpn(d, degree_cases[i].e);
    ck_assert_msg(d->nodes[id].deg == degree_cases[i].deg, "deg('%s') = %d, want %d", degree_cases[i].e,
                  d->nodes[id].deg, degree_cases[i].deg);
  }
}
END_TEST

/* ---- method_auto_k ---- */

START_TEST(test_auto_k)
{
  static const struct {
    int s, degU, degg, k, kpoly; /* kpoly: with the polynomial multiplier's rescale */
  } cases[] = {
      {2, 1, 2, 2, 2},            {1, 4, 6, 3, 3},  {2, 4, 6, 6, 6},            {3, 4, 6, 9, 9},
      {2, 3, 0, 3, 3},            {1, 1, 0, 1, 1},  {1, DEG_NONPOLY, 2, 14, 1}, {4, DEG_NONPOLY, 2, 20, 4},
      {2, 2, DEG_NONPOLY, 16, 2}, {5, 4, 6, 15, 15}, {1, 3, 0, 2, 2},           {3, 3, 2, 5, 5},
      {5, 1, 3, 8, 8},            {2, DEG_NONPOLY, 6, 16, 6},
  };
  for (int i = 0; i < NCASES(cases); i++) {
    const char *why = NULL;
    int k = method_auto_k(cases[i].s, cases[i].degU, cases[i].degg, MULT_CONST, &why);
    ck_assert_msg(k == cases[i].k, "auto k(s=%d, degU=%d, degg=%d) = %d, want %d", cases[i].s, cases[i].degU,
                  cases[i].degg, k, cases[i].k);
    ck_assert_msg(why && *why, "no reason given for k=%d", k);
    k = method_auto_k(cases[i].s, cases[i].degU, cases[i].degg, MULT_POLY, &why);
    ck_assert_msg(k == cases[i].kpoly, "poly: auto k(s=%d, degU=%d, degg=%d) = %d, want %d", cases[i].s,
                  cases[i].degU, cases[i].degg, k, cases[i].kpoly);
  }
}
END_TEST

/* ---- evaluation and substitution ---- */

/* The expressions of eval_cases written directly in C (v: x y z, p: p q). */
static double c_e0(const double *v, const double *p) { (void)p; return v[0] * v[1] + sin(v[0]); }
static double c_e1(const double *v, const double *p) { (void)p; return atan2(v[1], v[2]) * exp(v[0]) - pow(v[0], 3); }
static double c_e2(const double *v, const double *p) { (void)p; return pow(v[0] / v[1], -v[2]); }
static double c_e3(const double *v, const double *p) { (void)p; return cosh(v[0]) / tanh(v[1]) + sqrt(v[0] * v[1]); }
static double c_e4(const double *v, const double *p) { return p[0] * pow(v[0], 2) + p[1] * v[1] - fabs(p[1] * v[2]); }
static double c_e5(const double *v, const double *p) { (void)p; return asin(v[0] / 3) + acos(v[1] / 3) + atan(v[2]) * tan(v[2] / 2); }
static double c_e6(const double *v, const double *p) { (void)p; return log(v[0]) * sinh(v[1]) - cos(v[0] - v[2]); }
static double c_e7(const double *v, const double *p) { (void)p; return -(v[0] * v[0] - 1) / (v[1] + v[2]); }

static const struct {
  const char *e;
  double (*c)(const double *v, const double *p);
} eval_cases[] = {
    {"x y * x sin +", c_e0},
    {"y z atan2 x exp * x 3 ^ -", c_e1},
    {"x y / z ~ pow", c_e2},
    {"x cosh y tanh / x y * sqrt +", c_e3},
    {"p x 2 ^ * q y * + q z * abs -", c_e4},
    {"x 3 / asin y 3 / acos + z atan z 2 / tan * +", c_e5},
    {"x log y sinh * x z - cos -", c_e6},
    {"x x * 1 - ~ y z + /", c_e7},
};

/* dag_eval and dag_eval_many agree with C at random points in [0.5, 2]^3. */
START_TEST(test_eval)
{
  enum { NE = NCASES(eval_cases) };
  const double prm[2] = {1.7, -0.3};
  int roots[NE];
  Dag *d = dag_new();
  for (int i = 0; i < NE; i++)
    roots[i] = rpn(d, eval_cases[i].e);
  srand(SEED);
  for (int pt = 0; pt < NPOINTS; pt++) {
    double v[3], many[NE];
    for (int j = 0; j < 3; j++)
      v[j] = uniform(0.5, 2);
    dag_eval_many(d, roots, NE, v, prm, many);
    for (int i = 0; i < NE; i++) {
      double c = eval_cases[i].c(v, prm), one = dag_eval(d, roots[i], v, prm);
      ck_assert_msg(fabs(one - c) <= 1e-14 * fmax(1, fabs(c)), "'%s' = %.17g, C gives %.17g", eval_cases[i].e, one, c);
      ck_assert_msg(many[i] == one, "'%s': dag_eval_many %.17g, dag_eval %.17g", eval_cases[i].e, many[i], one);
    }
  }
}
END_TEST

/* True when node root depends on input slot. */
static int uses_input(const Dag *d, int root, int slot)
{
  unsigned char *mark = calloc((size_t)d->n, 1);
  int found = 0;
  ck_assert_ptr_nonnull(mark);
  dag_reach(d, &root, 1, mark);
  for (int id = 0; id < d->n; id++)
    found |= mark[id] && d->nodes[id].op == OP_INPUT && d->nodes[id].idx == slot;
  free(mark);
  return found;
}

/* dag_subst: x -> y+1 in x^2 and x*y (only slot 0 mapped), the identity map,
 * and the swap x <-> y. */
START_TEST(test_subst)
{
  Dag *d = dag_new();
  int roots[3] = {rpn(d, "x 2 ^"), rpn(d, "x y *"), rpn(d, "y z -")}, out[3];
  int shift[1] = {rpn(d, "y 1 +")}, ident[3], swap[2] = {dag_input(d, 1), dag_input(d, 0)};
  dag_subst(d, roots, 3, shift, 1, out);
  ck_assert(!uses_input(d, out[0], 0) && !uses_input(d, out[1], 0));
  ck_assert_int_eq(out[2], roots[2]);
  srand(SEED);
  for (int pt = 0; pt < NPOINTS; pt++) {
    double v[3] = {uniform(-2, 2), uniform(-2, 2), uniform(-2, 2)}, y = v[1];
    ck_assert_double_eq_tol(dag_eval(d, out[0], v, NULL), (y + 1) * (y + 1), 1e-14 * fmax(1, (y + 1) * (y + 1)));
    ck_assert_double_eq_tol(dag_eval(d, out[1], v, NULL), (y + 1) * y, 1e-14 * fmax(1, fabs((y + 1) * y)));
  }
  for (int i = 0; i < 3; i++)
    ident[i] = dag_input(d, i);
  dag_subst(d, roots, 3, ident, 3, out);
  for (int i = 0; i < 3; i++)
    ck_assert_int_eq(out[i], roots[i]);
  dag_subst(d, roots, 3, swap, 2, out);
  ck_assert_int_eq(out[0], rpn(d, "y 2 ^"));
  ck_assert_int_eq(out[1], roots[1]);
  ck_assert_int_eq(out[2], rpn(d, "x z -"));
}
END_TEST

/* The nodes that stay loops in the emitted code evaluate to their sums:
 * a table row (TROW) to sum_j T[row][j] v_j, and a stage sum (SSUM) to
 * sum_l W[l][j] f(Q_l) at the stage points Q_l = q0 + h sum_j Ihat[l][j]
 * gamma_j; the same sums spelt out as nodes give the same values. */
START_TEST(test_loop_nodes)
{
  Dag *d = dag_new();
  static const double T[6] = {1, 2, 3, -4, 0.5, 0.25};
  int v[3] = {dag_input(d, 0), dag_input(d, 1), dag_const(d, 3)};
  int t = dag_table(d, "T", T, 2, 3), vec = dag_vector(d, v, 3);
  int r0 = dag_table_row(d, t, 0, vec), r1 = dag_table_row(d, t, 1, vec);
  double in[2] = {0.75, -2};
  ck_assert_double_eq(dag_eval(d, r0, in, NULL), 1 * 0.75 + 2 * -2.0 + 3 * 3.0);
  ck_assert_double_eq(dag_eval(d, r1, in, NULL), -4 * 0.75 + 0.5 * -2.0 + 0.25 * 3.0);
  ck_assert_int_eq(dag_table_row(d, t, 0, dag_vector(d, v, 3)), r0); /* shared */
  /* f(x) = x^3 of coordinate 0; q0, gamma_0, gamma_1, h in slots 1..4; k = 3, s = 2 */
  static const double W[6] = {0.25, -0.5, 0.5, 0, 0.25, 0.5}, Ih[6] = {0.1, -0.2, 0.5, 0, 0.9, 0.2};
  int x = dag_input(d, 0), f = dag_mul(d, x, dag_mul(d, x, x));
  int q0[1] = {dag_input(d, 1)}, gam[2] = {dag_input(d, 2), dag_input(d, 3)}, h = dag_input(d, 4);
  DagLoop lp = {&f, 1, 1, 3, 2, W, Ih, q0, gam, h};
  int loop = dag_loop(d, &lp);
  double at[5] = {0, 0.3, 1.5, -0.7, 0.1};
  for (int j = 0; j < 2; j++) {
    double want = 0;
    for (int l = 0; l < 3; l++) {
      double Q = at[1] + at[4] * (Ih[l * 2] * at[2] + Ih[l * 2 + 1] * at[3]);
      want += W[l * 2 + j] * (Q * (Q * Q));
    }
    ck_assert_double_eq_tol(dag_eval(d, dag_stage_sum(d, loop, j, 0), at, NULL), want, 1e-15);
  }
}
END_TEST

// dag_count_ops counts each shared operation once, and no input or
// constant: (x + y) (x + y) - 3 x is an add, a product, a product by 3 and
// a difference.
START_TEST(test_count_ops)
{
  Dag *d = dag_new();
  int e = rpn(d, "x y + x y + * 3 x * -"), sum = rpn(d, "x y +");
  ck_assert_int_eq(dag_count_ops(d, &e, 1), 4);
  ck_assert_int_eq(dag_count_ops(d, &sum, 1), 1);
  int both[2] = {e, sum}, leaf = dag_input(d, 0);
  ck_assert_int_eq(dag_count_ops(d, both, 2), 4);
  ck_assert_int_eq(dag_count_ops(d, &leaf, 1), 0);
}
END_TEST

// dag_positive (bounds.c) proves positivity by interval arithmetic: the
// second pivot of the double pendulum in angles' M(q), 1 - cos(x - y)^2 / 2,
// is in [0.5, 1]; where the bounds reach 0 (1 - cos^2, sin^2), a param or an
// operation it does not bound (a quotient), or only the rounding margin
// (1e-12 + sin^2 of an input), it proves nothing.
START_TEST(test_positive)
{
  static const struct {
    const char *e;
    int positive;
  } c[] = {{"1 0.5 x y - cos x y - cos * * -", 1}, {"2 x cos +", 1}, {"x x * 1 +", 1}, {"x cos exp", 1},
           {"3 x sin y cos * -", 1},             {"x sqrt 1 +", 1}, {"x cos 2 ~ * 3 +", 1},
           {"1 x cos x cos * -", 0},             {"x sin x sin *", 0}, {"p", 0}, {"p p * 1 +", 1},
           {"1 x /", 0},                         {"x", 0},          {"1e-12 x sin x sin * +", 0},
           {"1 x cos y cos * -", 0},             {"-1", 0}};
  for (int i = 0; i < NCASES(c); i++) {
    Dag *d = dag_new();
    ck_assert_msg(dag_positive(d, rpn(d, c[i].e)) == c[i].positive, "'%s': positive %d expected", c[i].e,
                  c[i].positive);
  }
}
END_TEST

// End to end: the double pendulum in angles' M(q) factors without the
// guard of its second pivot (--check: 13 operations a stage for M(q)^-1 p,
// 16 with the guard's sqrt, division and product), while the spherical
// pendulum's sin(th)^2, which can be 0, keeps it (7).
START_TEST(test_positive_pivot_unguarded)
{
  static const struct {
    const char *model, *want;
  } c[] = {{"../models/double_pendulum_angles.ham", "a stage takes 13 operations for M(q)^-1 p"},
           {"../models/spherical_pendulum.ham", "a stage takes 7 operations for M(q)^-1 p"}};
  for (int i = 0; i < NCASES(c); i++) {
    char cmd[256], line[512];
    int found = 0;
    snprintf(cmd, sizeof cmd, "../gen/hbvmgen --check %s", c[i].model);
    FILE *f = popen(cmd, "r");
    ck_assert_ptr_nonnull(f);
    while (fgets(line, sizeof line, f)) found |= strstr(line, c[i].want) != NULL;
    ck_assert_int_eq(pclose(f), 0);
    ck_assert_msg(found, "%s: no '%s'", c[i].model, c[i].want);
  }
}
END_TEST

Suite *dag_suite(void)
{
  Suite *s = suite_create("dag");
  TCase *tc = tcase_create("dag");
  tcase_add_checked_fixture(tc, NULL, teardown);
  tcase_add_test(tc, test_cse_identity);
  tcase_add_test(tc, test_loop_nodes);
  tcase_add_test(tc, test_cse_counts);
  tcase_add_test(tc, test_cse_growth);
  tcase_add_test(tc, test_fold_values);
  tcase_add_test(tc, test_fold_nonfinite);
  tcase_add_test(tc, test_simplify);
  tcase_add_test(tc, test_pow2_exact);
  tcase_add_test(tc, test_degree);
  tcase_add_test(tc, test_auto_k);
  tcase_add_test(tc, test_eval);
  tcase_add_test(tc, test_subst);
  tcase_add_test(tc, test_count_ops);
  tcase_add_test(tc, test_positive);
  tcase_add_test(tc, test_positive_pivot_unguarded);
  suite_add_tcase(s, tc);
  return s;
}
