/* hbvmgen.h - the one shared header of the generator.
 *
 * A model travels through the generator in this order, one file per pass:
 *   lexer.l, parser.y   text -> syntax tree (Ast, Stmt)
 *   ast.c               names, shapes, semantic errors; lowers to the DAG (Model)
 *   dag.c               hash-consed expression DAG: CSE, folding, degrees
 *   ad.c                reverse-mode gradients and Jacobians on the DAG
 *   mass.c              the mass matrix: SPD check and structure of M^-1 (in the DAG with params)
 *   model.c             gradient of U, Jacobian of g, checks of q0 and p0
 *   switch.c            the switching functions: where U or g is not smooth
 *   method.c            HBVM(k,s) constants and the choice of k
 *   step.c              the step of the method, built as one more DAG (step.h):
 *     step_const.c      the multiplier family of the paper (constant over a step)
 *     step_poly.c       the order-2s family (polynomial multiplier, projection)
 *     lu.c              linear systems of DAG nodes, factored at generation time
 *   emit_kernel.c       C text of the kernels: straight-line code from the DAG (emit.h)
 *   emit_solver.c       C text of NAME.h / NAME.c around them (emit.h lists its files:
 *                       the API, the step's blocks, the error control, the prediction)
 *   emit_batch.c        --batch W: the same step over W lanes in struct-of-arrays form
 *   emit_main.c         C text of NAME_main.c, the standalone driver
 *   main.c              the command line
 * util.c holds the arena, growable arrays, the fatal-error path and the
 * diagnostics every pass uses. */
#ifndef HBVMGEN_H
#define HBVMGEN_H

#include <stddef.h>
#include <stdio.h>

#define HBVMGEN_VERSION "0.1.0"

/* ---- util.c: arena, growable arrays, dying, diagnostics ---- */

typedef struct {
  int line, col;
} Loc;

void *arena_alloc(size_t size);          /* zeroed; dies cleanly on exhaustion */
int *step_nodes(int n);                  /* n node ids (at least 1), zeroed, for step*.c and lu.c */
char *arena_strndup(const char *s, size_t n);
void arena_free_all(void);

/* The one growable array: v, n in use, cap allocated, in the arena. */
void *vec_reserve(void *v, int n, int *cap, long need, size_t elem);
#define VEC_RESERVE(v, n, cap, need) ((v) = vec_reserve((v), (n), &(cap), (need), sizeof *(v)))

typedef struct {
  int *v;
  int n, cap;
} IntVec;
void intvec_push(IntVec *vec, int x);

void *xmalloc(size_t size);              /* malloc, calloc, realloc that die cleanly */
void *xcalloc(size_t n, size_t size);
void *xrealloc(void *p, size_t size);

/* The generator's one exit path on a failure: an error (at loc when it has a
 * line), "out of memory", or an internal error (abort). */
void fatal_at(Loc loc, const char *fmt, ...);
void out_of_memory(void);
void internal_error(const char *fmt, ...);
#define ASSERT(c) ((c) ? (void)0 : internal_error("%s:%d: %s", __FILE__, __LINE__, #c))

const char *c_name_problem(const char *name); /* why name cannot be a C identifier here, or NULL */

void diag_begin(const char *file, const char *src, size_t len);
void error_at(Loc loc, const char *fmt, ...);
void warning_at(Loc loc, const char *fmt, ...);
void note_at(Loc loc, const char *fmt, ...); /* context of the error before it */
void diag_end(void);                     /* prints the counts of warnings not shown */
int diag_error_count(void);
int diag_too_many(void);                 /* true once the error cap is hit */
long diag_scanned(void);                 /* bytes read to index lines (for tests) */

/* ---- parser.y / lexer.l: the syntax tree ---- */

typedef enum {
  A_NUM,      /* num */
  A_NAME,     /* name */
  A_INDEX,    /* name[a] */
  A_NEG,      /* -a */
  A_BIN,      /* a op b, op one of + - * / ^ */
  A_CALL,     /* name(args), args a list via next: a function, or one of 'def' */
  A_SUM,      /* sum(name in a..b, c), or sum(name in a, c) over the list a (b NULL) */
  A_LIST,     /* [args] */
  A_FOR,      /* [c for name in a..b], or [c for name in a] over the list a (b NULL) */
  A_IDENTITY, /* identity */
  A_DIAG      /* diag(args) */
} AstKind;

typedef struct Ast Ast;
struct Ast {
  AstKind kind;
  Loc loc;
  int op;            /* A_BIN: '+', '-', '*', '/', '^'; A_SUM, A_FOR: ',' for an inner iterator */
  double num;        /* A_NUM */
  const char *name;  /* A_NAME, A_INDEX, A_CALL, A_SUM, A_FOR */
  Loc name_loc;      /* A_SUM, A_FOR: where the index variable is named */
  Ast *a, *b, *c;    /* operands, range bounds, body */
  Ast *args;         /* A_CALL, A_LIST, A_DIAG: first of a list linked by next */
  Ast *next;
  int depth;         /* nesting depth, bounded by MAX_AST_DEPTH */
};

typedef enum { S_VARIABLES, S_DEF, S_PARAM, S_MASS, S_POTENTIAL, S_CONSTRAINTS, S_Q0, S_P0, S_EVENT, S_FUNC } StmtKind;

typedef struct Decl Decl;
struct Decl {          /* one name of a variables statement */
  const char *name;
  Loc loc;
  Ast *size;           /* NULL for a scalar */
  Decl *next;
};

typedef struct Stmt Stmt;
struct Stmt {
  StmtKind kind;
  Loc loc;
  const char *name;    /* S_DEF, S_PARAM, S_EVENT, S_FUNC */
  Loc name_loc;
  Ast *expr;
  int dir;             /* S_EVENT: the sign changes that count, 0 both, 1 rising, -1 falling */
  Decl *decls;         /* S_VARIABLES; S_FUNC: its parameters */
  Stmt *next;
};

#define MAX_AST_DEPTH 5000
#define MAX_NESTING 1000

Ast *ast_new(AstKind kind, Loc loc, Ast *a, Ast *b, Ast *c);
void ast_set_args(Ast *n, Ast *args);
Stmt *parse_model(const char *src, size_t len);   /* NULL for no statements; check diag_error_count() */

/* ---- dag.c: the expression DAG ---- */

/* X-macro of operations: name, arity, C function (NULL for operators).
 * The emitter prints an op with a C function as that function with the
 * real type's suffix (fmin, fminf, fminl); the others it prints itself. */
#define OPS(X)                   \
  X(CONST, 0, NULL)              \
  X(INPUT, 0, NULL)              \
  X(PARAM, 0, NULL)              \
  X(ADD, 2, NULL)                \
  X(SUB, 2, NULL)                \
  X(MUL, 2, NULL)                \
  X(DIV, 2, NULL)                \
  X(NEG, 1, NULL)                \
  X(POW, 2, "pow")               \
  X(SIN, 1, "sin")               \
  X(COS, 1, "cos")               \
  X(TAN, 1, "tan")               \
  X(ASIN, 1, "asin")             \
  X(ACOS, 1, "acos")             \
  X(ATAN, 1, "atan")             \
  X(ATAN2, 2, "atan2")           \
  X(SINH, 1, "sinh")             \
  X(COSH, 1, "cosh")             \
  X(TANH, 1, "tanh")             \
  X(EXP, 1, "exp")               \
  X(LOG, 1, "log")               \
  X(SQRT, 1, "sqrt")             \
  X(ABS, 1, "fabs")              \
  X(SIGN, 1, NULL)               \
  X(MIN, 2, "fmin")              \
  X(MAX, 2, "fmax")              \
  X(FLOOR, 1, "floor")           \
  X(VEC, 2, NULL)                \
  X(TROW, 1, NULL)               \
  X(SSUM, 1, NULL)

typedef enum {
#define X(name, arity, cfun) OP_##name,
  OPS(X)
#undef X
  OP_COUNT
} Op;

int op_arity(Op op);
const char *op_cfun(Op op);
const char *op_name(Op op);

/* OP_VEC and OP_TROW (dag_vector, dag_table_row) are a product with a
 * constant table that stays a loop in the emitted code instead of m^2
 * operations: VEC nodes chain the entries of a vector (a = entry j, b = the
 * chain of entries 0..j-1 or -1, idx = j) and are never printed by
 * themselves; TROW (a = the last VEC of a chain, idx = row, val = table
 * number) is sum_j T[row][j] v_j, summed in order of j from j = 0. */

/* OP_SSUM (dag_stage_sum) is one sum over the k stages of HBVM that stays a
 * loop in the emitted code: sum_l W[l][j] f_r(Q_l), f_r a model node over
 * the coordinates (inputs 0..m-1) and Q_l = q0 + h sum_j Ihat[l][j] gamma_j
 * the stage point. a = the node of h (so it is an operation), idx = j *
 * nroots + r, val = the loop's number (DagLoop). */

/* Node flags: whether a node depends on a coordinate. */
enum { DEP_INPUT = 1 };

#define DEG_NONPOLY (-1)

typedef struct {
  unsigned char op;
  unsigned char flags; /* DEP_* */
  int a, b;            /* children, -1 when absent */
  int idx;             /* OP_INPUT: input slot; OP_PARAM: parameter number */
  int deg;             /* polynomial degree in the inputs, DEG_NONPOLY otherwise */
  double val;          /* OP_CONST */
} Node;

/* Nodes are numbered in creation order, so children always have smaller ids
 * and every pass over the DAG is a loop over ids, never a recursion. */
/* A constant table of the DAG (dag_table): rows x cols, row-major. */
typedef struct {
  const char *name;    /* its C name after the prefix */
  const double *v;
  int rows, cols;
} DagTable;

/* A loop over the stages (dag_loop): roots f_r over the coordinates, and
 * what a stage point is made of. */
typedef struct {
  const int *roots;    /* nroots model nodes */
  int nroots;
  int m, k, s;
  const double *W;     /* k x s: the weights of the sums */
  const double *Ihat;  /* k x s: Q_l = q0 + h sum_j Ihat[l][j] gamma_j */
  const int *q0, *gam; /* input nodes: m of q0, s*m of gamma (j*m + i) */
  int h;               /* the input node of h */
} DagLoop;

typedef struct {
  Node *nodes;
  int n, cap;
  int *table;          /* open-addressing hash of node ids, -1 empty */
  int zero;            /* the constant 0 */
  int tcap;
  Loc where;           /* what is being built, where the node limit is reported */
  const char *where_note; /* what the limit message adds there (NULL: a statement) */
  long work;           /* nodes visited by dag_subst and ad_gradient: a cost to test, not time */
  IntVec marks;        /* section labels for the emitter: (first id, label index) */
  const char **labels;
  int nlabels, labcap;
  /* ad.c: scratch of reverse sweeps, so that one costs the size of the
   * subgraph it visits, not of the whole DAG: per node id an adjoint, valid
   * where its stamp is the sweep's epoch; the ids visited */
  int *sweep_stamp, *sweep_adj;
  int sweep_cap, sweep_epoch;
  IntVec sweep_ids;
  DagTable *tables;    /* the constant tables TROW nodes read */
  int ntables, tabcap;
  DagLoop *loops;      /* the stage loops SSUM nodes read */
  int nloops, loopcap;
} Dag;

#ifndef MAX_NODES /* (the fuzz harness builds with smaller limits, tests/fuzz/run.sh) */
#define MAX_NODES 4000000
#endif

Dag *dag_new(void);
int dag_const(Dag *d, double v);
int dag_input(Dag *d, int slot);
int dag_param(Dag *d, int idx);
int dag_op(Dag *d, Op op, int a, int b);  /* folds and simplifies; b = -1 for unary */
int dag_add(Dag *d, int a, int b);
int dag_sub(Dag *d, int a, int b);
int dag_mul(Dag *d, int a, int b);
int dag_div(Dag *d, int a, int b);
int dag_neg(Dag *d, int a);
int dag_table(Dag *d, const char *name, const double *v, int rows, int cols); /* its number */
int dag_vector(Dag *d, const int *v, int n);          /* the chain of v[0..n-1], n >= 1 */
int dag_table_row(Dag *d, int table, int row, int vec); /* sum_j T[row][j] v_j */
int dag_vector_len(const Dag *d, int vec);
void dag_vector_entries(const Dag *d, int vec, int *out); /* the dag_vector_len entries of the chain */
int dag_loop(Dag *d, const DagLoop *loop);           /* its number */
int dag_stage_sum(Dag *d, int loop, int j, int r);    /* sum_l W[l][j] f_r(Q_l) */
int dag_is_const(const Dag *d, int n, double v);
int dag_is_zero(const Dag *d, int n);
void dag_section(Dag *d, const char *label);
double op_apply(Op op, double a, double b);
void dag_reach(const Dag *d, const int *roots, int nroots, unsigned char *mark);
long dag_count_ops(const Dag *d, const int *roots, int nroots); /* nodes with an operand */
double dag_eval(const Dag *d, int root, const double *inputs, const double *params);
int dag_positive(const Dag *d, int x); /* bounds.c: x > 0 (or NaN) for all inputs and params */
void dag_eval_many(const Dag *d, const int *roots, int nroots, const double *inputs, const double *params,
                   double *out);
void dag_subst(Dag *d, const int *roots, int nroots, const int *map, int nmap, int *out);

/* ---- ad.c: reverse-mode differentiation ---- */

/* Gradient of root with respect to inputs 0..n-1 as nodes: grad[i]. */
void ad_gradient(Dag *d, int root, int n, int *grad);
/* grad[i] = d(sum_r seeds[r] * roots[r]) / d(input i); seeds NULL: ones. */
void ad_reverse(Dag *d, const int *roots, const int *seeds, int nroots, int n, int *grad);

/* ---- the analysed model (ast.c, mass.c) ---- */

typedef enum { MASS_IDENTITY, MASS_SCALAR, MASS_DIAG, MASS_DENSE } MassKind;

typedef struct {
  const char *name;
  double value;
  Loc loc;
} Param;

/* One structurally nonzero entry of a gradient or Jacobian column. */
typedef struct {
  int coord, node;
} Entry;

typedef struct {
  Entry *e;
  int n;
} SparseVec;

/* ad.c: the structurally nonzero entries of the gradient of root with
 * respect to inputs 0..n-1, in input order; costs the size of root's
 * subgraph, not of the DAG or of n. */
void ad_gradient_sparse(Dag *d, int root, int n, SparseVec *out);

typedef struct {
  const char *file;
  int m, nu;
  const char **coord_names;   /* "x", "x[3]", ... for comments */
  Param *params;
  int nparams;
  Dag *dag;                   /* inputs 0..m-1 are the coordinates */
  int U;                      /* potential node */
  int *g;                     /* nu constraint nodes */
  Loc *g_loc;
  int *gradU;                 /* m nodes */
  SparseVec *jac;             /* nu columns: grad g_a, structural nonzeros only */
  MassKind mass;              /* what M is (at the default params when it has params) */
  double *minv;               /* m*m row-major inverse mass (dense only), else NULL */
  double *minv_diag;          /* m entries of diag(M^-1) */
  /* M with params (mass.c): M = L D L' as nodes of the params, NULL when M
   * is constant. minv_node: the m entries of D^-1 (NaN where a pivot is not
   * positive); mass_L: the m rows of L below the diagonal, NULL when M is
   * diagonal. minv, minv_diag and mass then hold M at the default params. */
  int *minv_node;
  SparseVec *mass_L;
  /* M(q), a mass matrix that depends on the coordinates (mass_q.c): its
   * m*m row-major entries as nodes of q (inputs 0..m-1) and params, NULL
   * when M does not depend on q (minv, minv_diag then hold M at q0); for the
   * step, in the model's space of q (inputs 0..m-1) and p (inputs m..2m-1):
   * v = M(q)^-1 p (m nodes) and the force grad_q T + grad U (m nodes), T =
   * p' v / 2, by closed form (mass_q_closed) or reverse-mode AD */
  int *mass_q;
  Loc mass_loc;
  int mass_q_closed;
  int *mq_v, *mq_force;
  /* with constraints, the point (m nodes: a kernel's q0 input) at which
   * minv_apply takes M(q)^-1 outside the stages; NULL otherwise */
  const int *mass_at;
  double *q0, *p0;            /* m each, at the default params */
  int *q0n, *p0n;             /* m nodes each: q0, p0 as functions of the params */
  Loc q0_loc, p0_loc, U_loc;  /* U_loc: the U statement, or line 0 */
  int degU, degg;             /* DEG_NONPOLY or degree; degg = 0 without constraints */
  long stage_loop;            /* stages whose straight-line code would take this many
                               * operations or more are a loop (--stage-loop) */
  long mass_loop;             /* a product M^-1 v of a dense constant M with this many
                               * multiplications or more is a loop over a table (--mass-loop) */
  /* events (ast.c): nodes of q (inputs 0..m-1), p (inputs m..2m-1) and params;
   * dirs 0 (any sign change), 1 (rising), -1 (falling) */
  int nevents;
  const char **event_names;
  int *event_nodes, *event_dirs;
  /* switching functions (switch.c): nodes of q and params where U or g is
   * not smooth, their kinds (SWITCH_*), the function that has each ("abs",
   * "min/max", ...), and whether U has one (else only g) */
  int nswitch;
  int *switch_nodes, *switch_kinds;
  const char **switch_what;
  int switch_in_U;
} Model;

/* The kinds of switching functions: a kink or jump where the value changes
 * sign (abs, sign, min, max), or where it crosses an integer (floor, mod). */
enum { SWITCH_SIGN = 0, SWITCH_INTEGER = 1 };
void model_switches(Model *mod);      /* switch.c: after model_differentiate */
void switch_warn(const Model *mod);   /* the generation-time warning (none when smooth) */

/* The default of Model.mass_loop, from the measurements in docs/embedding.md. */
#define MASS_LOOP_DEFAULT 512
#define STAGE_LOOP_DEFAULT 4000

Model *analyse(const char *file, Stmt *prog);      /* NULL when errors were reported */
int mass_setup(Model *mod, const double *dense, Loc loc); /* 0 ok, else error reported */
int mass_setup_diag(Model *mod, const double *diag, Loc loc); /* M = diag(diag[0..m-1]) */
/* M of nodes with params (m diagonal entries, or m*m row-major when dense):
 * M^-1 in the DAG; call before mass_setup* with M at the default params. */
int mass_setup_params(Model *mod, const int *entries, int dense, Loc loc);
void minv_apply(const Model *mod, Dag *d, const int *v, int *out); /* out = M^-1 v, nodes */
long mass_ldl(Dag *d, const int *a, int m, SparseVec *L, int *dinv, int bounded, Loc loc, const char *what);
void mass_ldl_solve(Dag *d, const SparseVec *L, const int *dinv, int m, const int *v, int *out);
/* mass_q.c: M(q) */
void mass_q_setup(Model *mod, const int *entries, int dense, Loc loc);
int mass_q_check(Model *mod, const double *prm);   /* M(q0) SPD: 0, or -1 after a located error */
void mass_q_kinetic(Model *mod);                   /* mod->mq_v, mod->mq_force */
void mass_q_inertial(const Model *mod, Dag *d, const int *q, const int *v, int *out); /* grad_q T + Mdot v */
void minv_apply_at(const Model *mod, Dag *d, const int *q, const int *v, int *out); /* M(q)^-1 v */
int mass_q_refuse(const Model *mod, int newton, int wide, int const_mult); /* 1 after an error */
void mass_q_report(FILE *f, const Model *mod);    /* --check: M's dependence and cost */
void model_differentiate(Model *mod);
void model_check_initial(const Model *mod);
/* stiffness.c: the frequencies of the linearisation at q0 */
typedef struct {
  double fast, slow;          /* the largest and the smallest nonzero frequency */
  double gap_below, gap_above; /* either side of the largest ratio between consecutive ones */
} Frequencies;
double model_stiffness(const Model *mod, Frequencies *f); /* fast / slow, 0: not estimated */
int model_stiffness_estimated(const Model *mod);          /* whether model_stiffness estimates */

/* ---- method.c: HBVM(k,s) constants and the choice of k ---- */

/* How the multiplier varies over a step: the method family. */
typedef enum {
  MULT_CONST, /* constant over the step: the paper's method, order 2 (step_const.c) */
  MULT_POLY   /* a polynomial of degree s-1, then projection and rescale: order 2s (step_poly.c) */
} MultFamily;

/* How the step's equations are solved (--iteration). */
typedef enum {
  ITER_FIXED, /* fixed-point sweeps: converge while h omega < ~3 */
  ITER_NEWTON, /* simplified Newton on gamma (step_newton.c, emit_newton.c) */
  ITER_AUTO    /* fixed-point sweeps, Newton where they converge slowly (emit_newton.c) */
} IterKind;
#define NEWTON_MAX_S 8 /* the largest s of --iteration newton (its eigenbasis is checked up to it) */

typedef struct {
  int k, s;
  MultFamily family;
  IterKind iteration;
  int energy_rescale; /* p1 rescaled to H0 at the end of a step (--energy rescale, emit_end.c) */
  double *c, *b;      /* k nodes and weights on [0,1] */
  double *Ihat;       /* k x s: integral_0^{c_l} P_j */
  double *W;          /* k x s: b_l P_j(c_l) */
  double *Phat;       /* k x s: P_j(c_l) */
  double *xi;         /* s+1 values xi_0..xi_s */
  double *E;          /* s x s x s: warm start, E[j][i] = sum_d E[(j*s+i)*s+d] r^d */
  double *E2;         /* s x 2s: warm start from two steps of the same size */
} Method;

int method_auto_k(int s, int degU, int degg, MultFamily fam, const char **why);
int method_quadrature_exact(int k, int s, int degU, int degg);
Method *method_new(int k, int s, MultFamily family);
void method_advise(FILE *f, const Model *mod, int s, int k, MultFamily fam, int rescale); /* --check's advice */

/* ---- step.c, step_const.c, step_poly.c, lu.c: the step as a DAG ---- */

/* The size macros of the generated solver a block's length is written in. */
typedef enum { SZ_SM, SZ_M, SZ_NU, SZ_SNU, SZ_ONE, SZ_COUNT } SizeSym;

/* A run of consecutive slots: one input of every kernel (the DAG inputs
 * first .. first+len-1, a C array argument or a scalar), or one result of
 * a kernel (out[first .. first+len-1]). */
typedef struct {
  const char *name;   /* the C name of an input; how templates name a result */
  SizeSym sym;        /* len = coef * (the value of sym), as the C text writes it */
  int coef;
  int first, len;
  int scalar;         /* input passed by value (h) */
  int narrow;         /* input in the solver's real type even in a wide kernel */
  int wrap;           /* the kernel signature breaks the line after it */
  int *nodes;         /* a result's DAG nodes, len of them */
} Slots;

/* The inputs every kernel takes, in signature order. */
enum { IN_Q0, IN_P0, IN_GAM, IN_H, IN_G0, IN_LAM, IN_PTH, IN_LU, IN_COUNT };

/* The kernels of a solver, in the order they are printed. */
typedef enum {
  K_SWEEP, K_FACTOR, K_MINV_P, K_ENERGY, K_G, K_HIDDEN, K_LAMBDA0, K_PROJECT,
  K_CONSISTENT, /* NAME_project: a Newton step onto g = 0, p projected onto the hidden constraint */
  K_INITIAL,    /* the model's q0, p0 as functions of the params (when they use any) */
  K_EVENTS,     /* the model's event functions at (q0, p0) (when it has events) */
  K_SWITCH,     /* the model's switching functions at q0 (when it has some) */
  K_NFACTOR,    /* --iteration newton: the Newton matrix, factored (step_newton.c) */
  K_NSOLVE,     /* --iteration newton: the correction for a residual */
  K_COUNT
} KernelId;

#define MAX_BLOCKS 12

/* A straight-line function of the generated solver: its results are
 * consecutive blocks of out[]. A kernel with no blocks is not emitted. */
typedef struct {
  const char *name;   /* the C name after the prefix */
  const char *what;   /* its comment */
  int wide;           /* computed one precision wider under --wide-step */
  Slots out[MAX_BLOCKS];
  int nout;
} Kernel;

typedef struct {
  int m, nu, s;
  Slots in[IN_COUNT];
  Kernel kern[K_COUNT];
  IntVec sec_owner;   /* per DAG section label: the kernels (1 << KernelId) built in it */
} Step;

Step *step_build(Model *mod, const Method *meth);
/* The step for the rolled form (roll.h): the layout of the kernels it prints
 * as loops, their results zeros (nothing of the straight-line step is built,
 * so the cost is linear in the model), and the kernels that stay
 * straight-line (events, switches, the params' q0 and p0) as step_build. */
Step *step_build_layout(Model *mod, const Method *meth);
/* The half band of the poly family's multiplier matrix in the rolled form
 * (unknowns a s + r): s (bw + 1) - 1 (step_poly.c). */
int poly_band(const Model *mod, int s);
/* The block of kernel k named name; NULL if there is none. */
const Slots *step_block(const Step *st, KernelId k, const char *name);
int kernel_size(const Kernel *k);   /* slots of out[] */

/* ---- emit_solver.c, emit_main.c (emit.h: the emitter's own files) ---- */

typedef struct {
  const char *name;     /* C prefix */
  const char *model_file;
  int single;           /* --real float */
  int compensated;      /* Kahan summation (off with --plain-sum) */
  int wide_step;        /* --wide-step: iterate and update one precision wider */
  int batch;            /* --batch W: also NAME_batch_step over W lanes (0: none) */
  int rolled;           /* --rolled: ROLL_OFF, ROLL_ON or ROLL_AUTO (roll.h) */
  const struct Roll *roll; /* the rolled form roll_choose chose, or NULL */
} EmitOptions;

int emit_check(const Model *mod, const Step *st, const EmitOptions *o); /* 1 after errors */
int emit_solver(FILE *h, FILE *c, const Model *mod, const Method *meth, const Step *st, const EmitOptions *o);
int emit_driver(FILE *f, const Model *mod, const Method *meth, const EmitOptions *o);

#endif
