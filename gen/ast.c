/* ast.c - semantic analysis: from statements to a Model.
 *
 * Statements are taken in file order, so a name must be defined before it
 * is used. Each expression is lowered straight into the DAG: names become
 * coordinates (input slots), constants, shared subexpressions or
 * parameters; index variables of `sum` and `for` are integers substituted
 * as constants while their body is lowered, so arrays, sums and
 * comprehensions are fully expanded. A function of `def` is expanded the
 * same way at each call: its body is lowered with each parameter naming the
 * argument's node, in the scope of the `def` (the names defined before it),
 * and hash-consing in the DAG shares what two calls have in common. M, q0 and p0 depend on the final
 * number of coordinates and are lowered after the last statement (still
 * seeing only the names defined before them). So are the events, whose
 * expressions may also use the momenta p[1] .. p[m] (DAG inputs m .. 2m-1,
 * which only they use).
 *
 * Every lowering function returns a node id, or -1 after reporting an
 * error; analysis goes on with the next statement so several errors can be
 * reported in one run. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

#define MAX_COORDS 100000
#define MAX_CONSTRAINTS 4096  /* the step factors a dense nu x nu system at worst */
#define MAX_PARAMS 10000
#ifndef MAX_WORK            /* (the fuzz harness builds with a smaller limit) */
#define MAX_WORK 20000000L   /* terms expanded by sum/for over the whole model */
#endif
#define MAX_INDEX 1000000000L
#define MAX_EVENTS 1000
#define MAX_CALL_NOTES 4 /* "in this call of" notes after one error, innermost first */

typedef enum { SYM_COORD, SYM_ARRAY, SYM_VALUE, SYM_VALUES, SYM_PARAM, SYM_INDEX, SYM_FUNC, SYM_ARG } SymKind;

typedef struct Sym Sym;
struct Sym {
  SymKind kind;
  const char *name;
  Loc loc;
  int stmt;      /* statement that defines it (file order) */
  int base;      /* COORD, ARRAY: first input slot; PARAM: parameter number */
  int size;      /* ARRAY, VALUES */
  int node;      /* VALUE, ARG (a parameter of a function of def, during a call) */
  int *nodes;    /* VALUES: size nodes, the array defined by name = [...] */
  long ival;     /* INDEX */
  const Stmt *def; /* FUNC: its statement */
  int busy;      /* FUNC: its body is being expanded */
  int broken;    /* FUNC: an error was reported in its body (once) */
  int used;
  Sym *shadowed; /* a name this one hides while it is defined (see define) */
  Sym *next;     /* hash chain */
};

typedef struct {
  Model *mod;
  Dag *d;
  Sym **buckets;   /* hash chains of the names, grown with their number */
  int nbuckets, nsyms;
  int stmt;        /* index of the statement being analysed */
  long work;
  IntVec g, g_line, g_col;
  const char **names; /* coordinate names */
  int nnamed, ncap;
  Stmt *mass, *q0, *p0, *pot;
  int mass_stmt, q0_stmt, p0_stmt;
  Param *params;
  int nparams, pcap;
  const Stmt *prog;  /* all statements, to find a name defined too late */
  IntVec events;     /* the event statements, by number */
  int momenta;       /* lowering an event: p[i] is momentum i */
  int call_depth;    /* summed depths of the bodies of the calls being expanded */
  int noted_error, notes; /* the error the last "in this call" notes follow, and their number */
  const Ast *ranging; /* the iterator whose range or list is being lowered (see unbound_index) */
  Sym *free_syms;    /* undefined names, reused by define (loops and calls define many) */
  struct Memo **memo; /* the calls expanded, by function and argument nodes (see find_call) */
  int nmemo, memocap;
} Ctx;

/* A call of a function of def already expanded: f with these argument
 * nodes (and the meaning of p, as in an event or not) gives node. */
typedef struct Memo {
  const Sym *f;
  int momenta, node, nargs;
  int *args;
  struct Memo *next;
} Memo;

// Give n the depth one more than its deepest child. The first node deeper
// than MAX_AST_DEPTH is an error (the parser goes on, nothing is lowered),
// so the recursive lowering below cannot overflow the stack.
static void set_depth(Ast *n, int child_depth) {
  if (child_depth + 1 <= n->depth) return;
  n->depth = child_depth + 1;
  if (n->depth == MAX_AST_DEPTH + 1)
    error_at(n->loc, "expression nested too deeply (more than %d levels)", MAX_AST_DEPTH);
}

// A new syntax tree node with up to three children.
Ast *ast_new(AstKind kind, Loc loc, Ast *a, Ast *b, Ast *c) {
  Ast *n = arena_alloc(sizeof *n);
  n->kind = kind;
  n->loc = loc;
  n->a = a;
  n->b = b;
  n->c = c;
  int depth = 0;
  const Ast *kids[3] = {a, b, c};
  for (int i = 0; i < 3; i++)
    if (kids[i] && kids[i]->depth > depth) depth = kids[i]->depth;
  set_depth(n, depth);
  return n;
}

// Attach an argument list to n, which becomes deeper than its deepest argument.
void ast_set_args(Ast *n, Ast *args) {
  n->args = args;
  int depth = 0;
  for (const Ast *a = args; a; a = a->next)
    if (a->depth > depth) depth = a->depth;
  set_depth(n, depth);
}

static unsigned hash_name(const Ctx *cx, const char *s) {
  unsigned h = 2166136261u;
  for (; *s; s++) h = (h ^ (unsigned char)*s) * 16777619u;
  return h & (unsigned)(cx->nbuckets - 1);
}

// Double the hash table when it holds twice as many names as chains.
static void grow_table(Ctx *cx) {
  Sym **old = cx->buckets;
  int nold = cx->nbuckets;
  cx->nbuckets = nold ? 2 * nold : 256;
  cx->buckets = arena_alloc((size_t)cx->nbuckets * sizeof *cx->buckets);
  for (int b = 0; b < nold; b++)
    for (Sym *s = old[b], *next; s; s = next) {
      next = s->next;
      unsigned h = hash_name(cx, s->name);
      s->next = cx->buckets[h];
      cx->buckets[h] = s;
    }
}

static Sym *lookup(Ctx *cx, const char *name) {
  for (Sym *s = cx->buckets[hash_name(cx, name)]; s; s = s->next)
    if (!strcmp(s->name, name)) return s;
  return NULL;
}

static const char *sym_kind_name(const Ctx *cx, const Sym *s) {
  switch (s->kind) {
  case SYM_COORD: return "a coordinate";
  case SYM_ARRAY: return "an array of coordinates";
  case SYM_VALUE: return cx->d->nodes[s->node].op == OP_CONST ? "a constant" : "a named subexpression";
  case SYM_VALUES: return "an array of values";
  case SYM_PARAM: return "a parameter";
  case SYM_INDEX: return "an index variable";
  case SYM_FUNC: return "a function";
  case SYM_ARG: return "a parameter of a function";
  }
  return "a name";
}

static void unlink_sym(Ctx *cx, Sym *sym) {
  Sym **p = &cx->buckets[hash_name(cx, sym->name)];
  while (*p != sym) p = &(*p)->next;
  *p = sym->next;
  cx->nsyms--;
}

static void link_sym(Ctx *cx, Sym *s) {
  if (++cx->nsyms > 2 * cx->nbuckets) grow_table(cx);
  unsigned h = hash_name(cx, s->name);
  s->next = cx->buckets[h];
  cx->buckets[h] = s;
}

// Define a new name, or report that it exists (returns NULL then). A name
// the statement being analysed cannot see (defined by a later statement, or
// an index variable of the caller of a function being expanded) is hidden
// while the new one, an index variable or a parameter, is defined.
static Sym *define(Ctx *cx, const char *name, Loc loc, SymKind kind) {
  if (!strcmp(name, "pi")) {
    error_at(loc, "'pi' is the constant 3.14159... and cannot be redefined");
    return NULL;
  }
  Sym *old = lookup(cx, name);
  int hide = old && old->stmt > cx->stmt;
  if (old && !hide) {
    error_at(loc, "'%s' is defined twice (first as %s at line %d, column %d)", name, sym_kind_name(cx, old),
             old->loc.line, old->loc.col);
    return NULL;
  }
  const char *problem = kind == SYM_VALUE || kind == SYM_PARAM ? c_name_problem(name) : NULL;
  if (problem) {
    error_at(loc, "'%s' cannot name a %s: it is %s, which the generated C cannot use", name,
             kind == SYM_PARAM ? "param" : "definition", problem);
    return NULL;
  }
  Sym *s = cx->free_syms;
  if (s) {
    cx->free_syms = s->next;
    memset(s, 0, sizeof *s);
  } else {
    s = arena_alloc(sizeof *s);
  }
  s->kind = kind;
  s->name = name;
  s->loc = loc;
  s->stmt = cx->stmt;
  if (hide) {
    unlink_sym(cx, old);
    s->shadowed = old;
  }
  link_sym(cx, s);
  return s;
}

// Remove a name defined for a while (an index variable, a parameter), and
// bring back the name it hid; its Sym is kept for the next define.
static void undefine(Ctx *cx, Sym *sym) {
  unlink_sym(cx, sym);
  if (sym->shadowed) link_sym(cx, sym->shadowed);
  sym->next = cx->free_syms;
  cx->free_syms = sym;
}

static int lower(Ctx *cx, const Ast *e);

// What a node that is not constant depends on, for messages.
static const char *dependence(const Node *nd) { return nd->flags & DEP_INPUT ? "a coordinate" : "a parameter"; }

// Require node n, the value of what at loc, to be a constant integer.
static int const_int(Ctx *cx, int n, Loc loc, const char *what, long *out) {
  const Node *nd = &cx->d->nodes[n];
  if (nd->op != OP_CONST) {
    error_at(loc, "%s must be a constant integer, but it depends on %s", what, dependence(nd));
    return -1;
  }
  if (nd->val != floor(nd->val)) {
    error_at(loc, "%s must be an integer, got %.17g", what, nd->val);
    return -1;
  }
  if (fabs(nd->val) > MAX_INDEX) {
    error_at(loc, "%s is %.17g, beyond the largest allowed magnitude, %ld", what, nd->val, MAX_INDEX);
    return -1;
  }
  *out = (long)nd->val;
  return 0;
}

// Lower e and require a constant integer (sizes, indices, ranges).
static int lower_int(Ctx *cx, const Ast *e, const char *what, long *out) {
  int n = lower(cx, e);
  return n < 0 ? -1 : const_int(cx, n, e->loc, what, out);
}

// Where statement st defines name (a definition, param or coordinate), or NULL.
static const Loc *defines(const Stmt *st, const char *name) {
  if ((st->kind == S_DEF || st->kind == S_PARAM || st->kind == S_FUNC) && !strcmp(st->name, name)) return &st->name_loc;
  if (st->kind == S_VARIABLES)
    for (const Decl *dc = st->decls; dc; dc = dc->next)
      if (!strcmp(dc->name, name)) return &dc->loc;
  return NULL;
}

// Report name, when it is the index variable of the iterator whose range is
// being lowered or of one inside it in the same sum or comprehension (`j in
// j + 1..N`, `sum(j in i + 1..N, i in 1..N, e)`): its value is not known
// yet. Returns whether it reported.
static int unbound_index(Ctx *cx, const char *name, Loc loc) {
  for (const Ast *it = cx->ranging; it && (it == cx->ranging || it->op == ','); it = it->c) {
    if (it->kind != cx->ranging->kind) break;
    if (strcmp(it->name, name)) continue;
    if (it == cx->ranging)
      error_at(loc, "index variable '%s' is used in its own range: a bound may use only the index variables before it",
               name);
    else
      error_at(loc, "index variable '%s' is used in a range before it is bound: index variables are bound left to "
               "right, so write '%s in ...' first (line %d, column %d)", name, name, it->name_loc.line,
               it->name_loc.col);
    return 1;
  }
  return 0;
}

// Find the symbol a name refers to in the statement being analysed, or
// report why there is none: a name defined by this statement is used in
// its own definition, one defined by a later statement before its
// definition; any other is unknown.
static Sym *resolve(Ctx *cx, const char *name, Loc loc) {
  Sym *s = lookup(cx, name);
  if (s && s->stmt <= cx->stmt) return s;
  const Loc *later = s && s->kind != SYM_INDEX ? &s->loc : NULL; /* not a caller's index variable */
  int i = 0;
  for (const Stmt *st = cx->prog; st && !later; st = st->next, i++)
    if (i >= cx->stmt && (later = defines(st, name)) != NULL && i == cx->stmt) {
      error_at(loc, "'%s' is used in its own definition", name);
      return NULL;
    }
  if (later)
    error_at(loc, "'%s' is used before its definition (line %d, column %d)", name, later->line, later->col);
  else if (!unbound_index(cx, name, loc))
    error_at(loc, "unknown name '%s'", name);
  return NULL;
}

// Whether name is the momenta of an event expression: p, unless the model
// gives p a meaning of its own.
static int is_momenta(Ctx *cx, const char *name) { return cx->momenta && !strcmp(name, "p") && !lookup(cx, name); }

// Resolve a plain name in an expression.
static int lower_name(Ctx *cx, const Ast *e) {
  if (!strcmp(e->name, "pi")) return dag_const(cx->d, 3.14159265358979323846);
  if (is_momenta(cx, e->name)) {
    error_at(e->loc, "'p' is the array of the %d momenta in an event: index it, as in p[1]", cx->mod->m);
    return -1;
  }
  Sym *s = resolve(cx, e->name, e->loc);
  if (!s) return -1;
  s->used = 1;
  switch (s->kind) {
  case SYM_COORD: return dag_input(cx->d, s->base);
  case SYM_ARRAY:
    error_at(e->loc, "'%s' is an array of %d coordinates: index it, as in %s[1]", e->name, s->size, e->name);
    return -1;
  case SYM_VALUE: return s->node;
  case SYM_VALUES:
    if (s->size == 0) return -1;
    error_at(e->loc, "'%s' is an array of %d values: index it, as in %s[1]", e->name, s->size, e->name);
    return -1;
  case SYM_PARAM: return dag_param(cx->d, s->base);
  case SYM_INDEX: return dag_const(cx->d, (double)s->ival);
  case SYM_ARG: return s->node;
  case SYM_FUNC:
    error_at(e->loc, "'%s' is a function: call it, as in %s(...)", e->name, e->name);
    return -1;
  }
  return -1;
}

// Lower name[i], of coordinates or of values: i must fold to an integer
// within the array's bounds.
static int lower_index(Ctx *cx, const Ast *e) {
  if (is_momenta(cx, e->name)) {
    long i;
    if (lower_int(cx, e->a, "an index", &i) < 0) return -1;
    if (i < 1 || i > cx->mod->m) {
      error_at(e->a->loc, "index %ld out of range: the momenta 'p' have indices 1..%d", i, cx->mod->m);
      return -1;
    }
    return dag_input(cx->d, cx->mod->m + (int)i - 1);
  }
  Sym *s = resolve(cx, e->name, e->loc);
  if (!s) return -1;
  if (s->kind != SYM_ARRAY && s->kind != SYM_VALUES) {
    error_at(e->loc, "'%s' is %s, not an array, and cannot be indexed", e->name, sym_kind_name(cx, s));
    return -1;
  }
  long i;
  if (s->kind == SYM_VALUES && s->size == 0) return -1;
  if (lower_int(cx, e->a, "an index", &i) < 0) return -1;
  if (i < 1 || i > s->size) {
    error_at(e->a->loc, "index %ld out of range: '%s' has indices 1..%d", i, e->name, s->size);
    return -1;
  }
  s->used = 1;
  return s->kind == SYM_VALUES ? s->nodes[i - 1] : dag_input(cx->d, s->base + (int)i - 1);
}

// Print a constant operand for a message; of an operator, in parentheses
// when negative.
static void operand(char *buf, size_t size, double v, int func) {
  snprintf(buf, size, v < 0 && !func ? "(%.6g)" : "%.6g", v);
}

// Build op(a, b) from lowered operands; a constant result that is not a
// finite number is an error at loc (x/0, sqrt(-1), log(0), 1e308*10, ...)
// that shows the operation with its operands. what is the function's name,
// or the operator itself ("^") for a binary operator.
static int build(Ctx *cx, Op op, int a, int b, Loc loc, const char *what) {
  const Node *na = &cx->d->nodes[a], *nb = b >= 0 ? &cx->d->nodes[b] : NULL;
  if (na->op == OP_CONST && (!nb || nb->op == OP_CONST)) {
    double v = op_apply(op, na->val, nb ? nb->val : 0);
    if (!isfinite(v) && !(op == OP_DIV && nb->val == 0)) {
      int func = strlen(what) > 1;
      char x[40], y[40] = "";
      operand(x, sizeof x, na->val, func);
      if (nb) operand(y, sizeof y, nb->val, func);
      const char *why = isinf(v) ? "is infinite" : func ? "is not a number: the argument is outside the domain"
                                                        : "is not a number";
      if (func)
        error_at(loc, "%s(%s%s%s) %s", what, x, nb ? ", " : "", y, why);
      else
        error_at(loc, "%s %s %s %s", x, what, y, why);
      return -1;
    }
  }
  if (op == OP_DIV && nb && nb->op == OP_CONST && nb->val == 0) {
    error_at(loc, "division by zero");
    return -1;
  }
  return dag_op(cx->d, op, a, b);
}

static const struct {
  const char *name;
  Op op;
} functions[] = {
    {"sin", OP_SIN},   {"cos", OP_COS},   {"tan", OP_TAN},     {"asin", OP_ASIN}, {"acos", OP_ACOS},
    {"atan", OP_ATAN}, {"atan2", OP_ATAN2}, {"sinh", OP_SINH}, {"cosh", OP_COSH}, {"tanh", OP_TANH},
    {"exp", OP_EXP},   {"log", OP_LOG},   {"sqrt", OP_SQRT},   {"pow", OP_POW},   {"abs", OP_ABS},
    {"sign", OP_SIGN}, {"min", OP_MIN},   {"max", OP_MAX},     {"floor", OP_FLOOR},
};

/* ---- lists: g, q0, p0, diag(...), what an index variable runs over ---- */

typedef struct {
  IntVec nodes, lines, cols;
} List;

static int flatten(Ctx *cx, const Ast *e, List *out);

#define FUNCTION_NAMES \
  "sin cos tan asin acos atan atan2 sinh cosh tanh exp log sqrt pow abs sign min max floor mod"

// The number of arguments of a call, checked against arity (reported).
static int check_arity(const Ast *e, int arity) {
  int nargs = 0;
  for (const Ast *a = e->args; a; a = a->next) nargs++;
  if (nargs == arity) return 0;
  error_at(e->loc, "'%s' takes %d argument%s, got %d", e->name, arity, arity == 1 ? "" : "s", nargs);
  return -1;
}

// mod(x, y) = x - y floor(x / y), which has the sign of y (as Python's %),
// built from those operations: its derivatives are 1 and -floor(x / y).
static int build_mod(Ctx *cx, int x, int y, Loc loc) {
  if (dag_is_zero(cx->d, y)) {
    error_at(loc, "mod(a, b) with b = 0: the remainder of a division by zero");
    return -1;
  }
  int q = build(cx, OP_DIV, x, y, loc, "/");
  if (q < 0) return -1;
  int fl = build(cx, OP_FLOOR, q, -1, loc, "floor");
  int prod = fl < 0 ? -1 : build(cx, OP_MUL, y, fl, loc, "*");
  return prod < 0 ? -1 : build(cx, OP_SUB, x, prod, loc, "-");
}

static int lower_user_call(Ctx *cx, const Ast *e, Sym *f);

// A call: of a function of the language, or of one defined with 'def'.
static int lower_call(Ctx *cx, const Ast *e) {
  Op op = OP_COUNT;
  for (size_t i = 0; i < sizeof functions / sizeof functions[0]; i++)
    if (!strcmp(functions[i].name, e->name)) op = functions[i].op;
  int is_mod = !strcmp(e->name, "mod");
  if (op == OP_COUNT && !is_mod) {
    Sym *f = lookup(cx, e->name);
    if (f && f->stmt <= cx->stmt && f->kind == SYM_FUNC) return lower_user_call(cx, e, f);
    if (f && f->stmt <= cx->stmt)
      error_at(e->loc, "'%s' is %s, not a function", e->name, sym_kind_name(cx, f));
    else
      error_at(e->loc, "'%.40s' is not a function (the functions are " FUNCTION_NAMES ", and those of 'def')",
               e->name);
    return -1;
  }
  int arity = is_mod ? 2 : op_arity(op);
  if (check_arity(e, arity) < 0) return -1;
  int x = lower(cx, e->args);
  int y = arity == 2 ? lower(cx, e->args->next) : -1;
  if (x < 0 || (arity == 2 && y < 0)) return -1;
  return is_mod ? build_mod(cx, x, y, e->loc) : build(cx, op, x, y, e->loc, e->name);
}

// Bind the parameters of function f to the nodes vals, each hiding a name
// the function cannot see (see define). Returns the number bound; fewer
// than the parameters after an error.
static int bind_params(Ctx *cx, const Sym *f, const int *vals, Sym **bound) {
  int n = 0;
  for (const Decl *p = f->def->decls; p; p = p->next, n++) {
    if (!(bound[n] = define(cx, p->name, p->loc, SYM_ARG))) break;
    bound[n]->node = vals[n];
    bound[n]->used = 1;
  }
  return n;
}

// A call of function f of 'def': the arguments lowered here, then its body
// where f was defined, seeing the names defined before it and its
// parameters, each the node of its argument; once per distinct arguments
// (find_call). An error in the body is
// reported once, with a note at the call (at the first MAX_CALL_NOTES calls
// of a nest of them); a call costs one term of
// MAX_WORK, so that functions calling others twice cannot expand
// exponentially, and the bodies of the calls being expanded are at most
// MAX_AST_DEPTH deep together, which bounds the recursion of lower.
static unsigned hash_call(const Sym *f, int momenta, const int *args, int n, int cap) {
  unsigned h = (unsigned)(size_t)f * 2654435761u ^ (unsigned)momenta;
  for (int i = 0; i < n; i++) h = (h ^ (unsigned)args[i]) * 16777619u;
  return h & (unsigned)(cap - 1);
}

// The slot of the call of f with the argument nodes args (n of them) in the
// calls already expanded: *slot is its entry, or NULL where a new one goes.
// A body's value depends on nothing else (it sees only what was defined
// before it, and its parameters), so a call is expanded once per distinct
// arguments: f(a) = g(a) + g(a) costs one expansion of g, and functions
// that call others twice expand in linear, not exponential, time.
static Memo **find_call(Ctx *cx, const Sym *f, const int *args, int n) {
  if (cx->nmemo >= cx->memocap) { /* grow (and create) the table, rehashing */
    int cap = cx->memocap ? 2 * cx->memocap : 256;
    Memo **t = arena_alloc((size_t)cap * sizeof *t);
    for (int b = 0; b < cx->memocap; b++)
      for (Memo *m = cx->memo[b], *next; m; m = next) {
        next = m->next;
        unsigned h = hash_call(m->f, m->momenta, m->args, m->nargs, cap);
        m->next = t[h];
        t[h] = m;
      }
    cx->memo = t;
    cx->memocap = cap;
  }
  Memo **slot = &cx->memo[hash_call(f, cx->momenta, args, n, cx->memocap)];
  for (; *slot; slot = &(*slot)->next)
    if ((*slot)->f == f && (*slot)->momenta == cx->momenta && !memcmp((*slot)->args, args, (size_t)n * sizeof *args))
      break;
  return slot;
}

static int lower_user_call(Ctx *cx, const Ast *e, Sym *f) {
  int nparams = 0;
  for (const Decl *p = f->def->decls; p; p = p->next) nparams++;
  if (f->busy) {
    error_at(e->loc, "'%s' is used in its own definition", e->name);
    return -1;
  }
  if (check_arity(e, nparams) < 0) return -1;
  /* on the heap: a call in a loop must not fill the arena */
  int *vals = xmalloc((size_t)nparams * sizeof *vals), i = 0, ok = 1;
  for (const Ast *a = e->args; a && ok; a = a->next) ok = (vals[i++] = lower(cx, a)) >= 0;
  if (ok && !f->broken && (cx->work >= MAX_WORK || cx->call_depth + f->def->expr->depth > MAX_AST_DEPTH)) {
    error_at(e->loc, cx->work >= MAX_WORK ? "too many terms: sums, lists and calls may expand to at most %ld in all"
                                          : "calls of functions nested too deeply (more than %ld levels in all)",
             cx->work >= MAX_WORK ? MAX_WORK : (long)MAX_AST_DEPTH);
    ok = 0;
  }
  Memo **slot = ok && !f->broken ? find_call(cx, f, vals, nparams) : NULL;
  if (!slot || *slot) {
    free(vals);
    return slot ? (cx->work++, (*slot)->node) : -1;
  }
  cx->work++;
  f->used = 1;
  int caller = cx->stmt, errors = diag_error_count(), node = -1;
  const Ast *ranging = cx->ranging; /* the body does not see the caller's iterators */
  cx->stmt = f->stmt;
  cx->ranging = NULL;
  Sym **bound = xmalloc((size_t)nparams * sizeof *bound);
  int nbound = bind_params(cx, f, vals, bound);
  if (nbound == nparams) {
    f->busy = 1;
    cx->call_depth += f->def->expr->depth;
    node = lower(cx, f->def->expr);
    cx->call_depth -= f->def->expr->depth;
    f->busy = 0;
  }
  while (nbound > 0) undefine(cx, bound[--nbound]);
  free(bound);
  cx->stmt = caller;
  cx->ranging = ranging;
  if (node >= 0) { /* remembered (its arguments into the arena: once per distinct call) */
    Memo *m = arena_alloc(sizeof *m);
    *m = (Memo){f, cx->momenta, node, nparams, arena_alloc((size_t)nparams * sizeof(int) + 1), NULL};
    memcpy(m->args, vals, (size_t)nparams * sizeof(int));
    *find_call(cx, f, vals, nparams) = m;
    cx->nmemo++;
  }
  free(vals);
  if (node < 0 && diag_error_count() > errors) {
    if (cx->noted_error != diag_error_count()) cx->noted_error = diag_error_count(), cx->notes = 0;
    if (cx->notes++ < MAX_CALL_NOTES) note_at(e->loc, "in this call of '%s'", e->name);
    f->broken = 1;
  }
  return node;
}

// Run body once for each value of index variable at->name (a new one) over
// a range a..b (at->a, at->b) or a list (at->a, at->b NULL), calling
// fn(cx, body, acc) which returns <0 on error.
typedef int (*RangeFn)(Ctx *cx, const Ast *body, void *acc);

/* The values of a list an index variable runs over, on the heap (a list
 * after 'in' is taken again at each iteration of the loops around it, so
 * it must not stay in the arena). */
typedef struct {
  long *v;
  int n, cap;
} Longs;

static int iterated_list(Ctx *cx, const Ast *e, Longs *out);

static int for_range(Ctx *cx, const Ast *at, const Ast *body, RangeFn fn, void *acc) {
  long lo = 0, hi = -1;
  Longs vals = {NULL, 0, 0};
  int rc = 0;
  const Ast *outer = cx->ranging;
  cx->ranging = at;
  if (!at->b) {
    rc = iterated_list(cx, at->a, &vals);
    hi = vals.n - 1;
  } else if (lower_int(cx, at->a, "a range bound", &lo) < 0 || lower_int(cx, at->b, "a range bound", &hi) < 0) {
    rc = -1;
  }
  cx->ranging = outer;
  if (rc == 0 && hi - lo + 1 > MAX_WORK - cx->work) {
    error_at(at->loc, "range %ld..%ld has too many terms: sums and lists may expand to at most %ld terms in all", lo,
             hi, MAX_WORK);
    rc = -1;
  }
  Sym *iv = rc < 0 ? NULL : define(cx, at->name, at->name_loc, SYM_INDEX);
  if (iv) {
    iv->used = 1;
    for (long i = lo; i <= hi && rc >= 0; i++) {
      cx->work++;
      iv->ival = at->b ? i : vals.v[i];
      rc = fn(cx, body, acc);
    }
    undefine(cx, iv);
  }
  free(vals.v);
  return iv ? rc : -1;
}

// Add the term body to the sum *acc; the inner iterator of a sum over
// several, sum(i in A, j in B, e), adds its terms to the same sum, in the
// order of the pairs, as e(i1, j1) + e(i1, j2) + ... written out would.
static int sum_term(Ctx *cx, const Ast *body, void *acc) {
  int *sum = acc;
  if (body->kind == A_SUM && body->op == ',') return for_range(cx, body, body->c, sum_term, acc);
  int t = lower(cx, body);
  if (t < 0) return -1;
  *sum = dag_add(cx->d, *sum, t);
  return 0;
}

// Lower a scalar expression.
static int lower(Ctx *cx, const Ast *e) {
  switch (e->kind) {
  case A_NUM: return dag_const(cx->d, e->num);
  case A_NAME: return lower_name(cx, e);
  case A_INDEX: return lower_index(cx, e);
  case A_NEG: {
    int a = lower(cx, e->a);
    return a < 0 ? -1 : dag_neg(cx->d, a);
  }
  case A_BIN: {
    int a = lower(cx, e->a), b = a < 0 ? -1 : lower(cx, e->b);
    if (a < 0 || b < 0) return -1;
    static const char *names[] = {"+", "-", "*", "/", "^"};
    const char *ops = "+-*/^";
    static const Op bops[] = {OP_ADD, OP_SUB, OP_MUL, OP_DIV, OP_POW};
    int k = (int)(strchr(ops, e->op) - ops);
    return build(cx, bops[k], a, b, e->loc, names[k]);
  }
  case A_CALL: return lower_call(cx, e);
  case A_SUM: {
    int sum = dag_const(cx->d, 0);
    return for_range(cx, e, e->c, sum_term, &sum) < 0 ? -1 : sum;
  }
  case A_LIST:
  case A_FOR: error_at(e->loc, "a list is not allowed here: expected a single value"); return -1;
  case A_IDENTITY: error_at(e->loc, "'identity' is only allowed as 'M = identity'"); return -1;
  case A_DIAG: error_at(e->loc, "'diag' is only allowed as 'M = diag(...)'"); return -1;
  }
  return -1;
}

static int flatten_item(Ctx *cx, const Ast *body, void *acc) { return flatten(cx, body, acc); }

// Append the values of e to out: lists and comprehensions nest and flatten.
static int flatten(Ctx *cx, const Ast *e, List *out) {
  if (e->kind == A_LIST) {
    for (const Ast *a = e->args; a; a = a->next)
      if (flatten(cx, a, out) < 0) return -1;
    return 0;
  }
  if (e->kind == A_FOR) return for_range(cx, e, e->c, flatten_item, out);
  int n = lower(cx, e);
  if (n < 0) return -1;
  intvec_push(&out->nodes, n);
  intvec_push(&out->lines, e->loc.line);
  intvec_push(&out->cols, e->loc.col);
  return 0;
}

// Append v to the values of a list after 'in'.
static void longs_push(Longs *out, long v) {
  if (out->n == out->cap) {
    out->cap = out->cap ? 2 * out->cap : 16;
    out->v = xrealloc(out->v, (size_t)out->cap * sizeof *out->v);
  }
  out->v[out->n++] = v;
}

static const char list_value[] = "a value of the list after 'in'";

static int list_values(Ctx *cx, const Ast *e, Longs *out);

static int list_item(Ctx *cx, const Ast *body, void *acc) { return list_values(cx, body, acc); }

// Append the values of e, an element of a list after 'in', to out: lists
// and comprehensions nest and flatten, each value a constant integer.
static int list_values(Ctx *cx, const Ast *e, Longs *out) {
  if (e->kind == A_LIST) {
    for (const Ast *a = e->args; a; a = a->next)
      if (list_values(cx, a, out) < 0) return -1;
    return 0;
  }
  if (e->kind == A_FOR) return for_range(cx, e, e->c, list_item, out);
  long v;
  if (lower_int(cx, e, list_value, &v) < 0) return -1;
  longs_push(out, v);
  return 0;
}

// The values of what an index variable runs over, e: a list, or the name
// of an array of values.
static int iterated_list(Ctx *cx, const Ast *e, Longs *out) {
  if (e->kind == A_LIST || e->kind == A_FOR) return list_values(cx, e, out);
  Sym *s = e->kind == A_NAME ? lookup(cx, e->name) : NULL;
  if (s && s->kind == SYM_VALUES && s->stmt <= cx->stmt) {
    s->used = 1;
    long v;
    for (int i = 0; i < s->size; i++) {
      if (const_int(cx, s->nodes[i], e->loc, list_value, &v) < 0) return -1;
      longs_push(out, v);
    }
    return s->size ? 0 : -1; /* an array in error has no values, and its error is said */
  }
  error_at(e->loc, "an index variable runs over a range 'a..b' or a list '[...]', not over a single value");
  return -1;
}

// Flatten a list (q0, p0, diag entries, a row of M) into want nodes that
// depend on no coordinate, and on no param unless params_ok; what names the
// list, whole what it is part of.
static int *value_list(Ctx *cx, const Stmt *st, const char *what, const char *whole, int want, int params_ok) {
  List l = {{0}, {0}, {0}};
  if (flatten(cx, st->expr, &l) < 0) return NULL;
  for (int i = 0; i < l.nodes.n; i++) {
    const Node *nd = &cx->d->nodes[l.nodes.v[i]];
    if (nd->op != OP_CONST && (!params_ok || nd->flags & DEP_INPUT)) {
      Loc loc = {l.lines.v[i], l.cols.v[i]};
      if (params_ok) error_at(loc, "%s cannot depend on a coordinate (it may use params), but this value does", whole);
      else error_at(loc, "%s must be constant, but this value depends on %s", whole, dependence(nd));
      return NULL;
    }
  }
  if (l.nodes.n != want) {
    error_at(st->loc, "%s has %d value%s, expected %d (one per coordinate)", what, l.nodes.n,
             l.nodes.n == 1 ? "" : "s", want);
    return NULL;
  }
  return l.nodes.v;
}

/* ---- statements ---- */

// Name coordinate slot for comments in the emitted code: "x" or "x[3]".
static void name_coord(Ctx *cx, const char *name, long index) {
  VEC_RESERVE(cx->names, cx->nnamed, cx->ncap, cx->nnamed + 1);
  char buf[32] = "";
  if (index > 0) snprintf(buf, sizeof buf, "[%ld]", index);
  size_t len = strlen(name);
  char *full = arena_alloc(len + strlen(buf) + 1);
  memcpy(full, name, len);
  strcpy(full + len, buf);
  cx->names[cx->nnamed++] = full;
}

static void declare_variables(Ctx *cx, const Stmt *st) {
  Model *mod = cx->mod;
  for (const Decl *dc = st->decls; dc; dc = dc->next) {
    long size = 1;
    if (dc->size && lower_int(cx, dc->size, "an array size", &size) < 0) continue;
    if (dc->size && size < 1) {
      error_at(dc->size->loc, "an array size must be at least 1, got %ld", size);
      continue;
    }
    if (size > MAX_COORDS - mod->m) {
      error_at(dc->loc, "too many coordinates (at most %d)", MAX_COORDS);
      continue;
    }
    Sym *s = define(cx, dc->name, dc->loc, dc->size ? SYM_ARRAY : SYM_COORD);
    if (!s) continue;
    s->used = 1;
    s->base = mod->m;
    s->size = (int)size;
    mod->m += (int)size;
    for (long i = 0; i < size; i++) name_coord(cx, dc->name, dc->size ? i + 1 : 0);
  }
}

// name = [e1, e2, ...] or [e for i in a..b]: an array of values, each
// lowered once here (constants, or subexpressions of q and params).
static void define_values(Ctx *cx, const Stmt *st) {
  List l = {{0}, {0}, {0}};
  int ok = flatten(cx, st->expr, &l) == 0;
  if (ok && l.nodes.n == 0) {
    error_at(st->expr->loc, "the array '%s' has no values", st->name);
    ok = 0;
  }
  Sym *s = define(cx, st->name, st->name_loc, SYM_VALUES);
  if (!s) return;
  s->size = ok ? l.nodes.n : 0; /* 0: in error, its uses say nothing more */
  s->nodes = l.nodes.v;
}

static void define_value(Ctx *cx, const Stmt *st) {
  if (st->expr->kind == A_LIST || st->expr->kind == A_FOR) {
    define_values(cx, st);
    return;
  }
  int n = lower(cx, st->expr);
  Sym *s = define(cx, st->name, st->name_loc, SYM_VALUE);
  if (s) s->node = n < 0 ? dag_const(cx->d, 0) : n;
}

static void define_param(Ctx *cx, const Stmt *st) {
  int n = lower(cx, st->expr);
  if (n >= 0 && cx->d->nodes[n].op != OP_CONST) {
    error_at(st->expr->loc, "the default of param '%s' must be constant, but it depends on %s", st->name,
             dependence(&cx->d->nodes[n]));
    n = -1;
  }
  if (cx->nparams >= MAX_PARAMS) {
    error_at(st->loc, "too many parameters (at most %d)", MAX_PARAMS);
    return;
  }
  Sym *s = define(cx, st->name, st->name_loc, SYM_PARAM);
  if (!s) return;
  VEC_RESERVE(cx->params, cx->nparams, cx->pcap, cx->nparams + 1);
  s->base = cx->nparams;
  Param *p = &cx->params[cx->nparams++];
  p->name = st->name;
  p->loc = st->name_loc;
  p->value = n >= 0 ? cx->d->nodes[n].val : 0;
}

// def NAME(a, b, ...) = expr: a function, expanded at each call. Its
// parameters are checked here as names (distinct, none already defined),
// its body at each call.
static void define_function(Ctx *cx, const Stmt *st) {
  Sym *f = define(cx, st->name, st->name_loc, SYM_FUNC);
  int ok = 1, n = 0;
  for (const Decl *p = st->decls; p; p = p->next) n++;
  Sym **params = arena_alloc((size_t)n * sizeof *params);
  n = 0;
  for (const Decl *p = st->decls; p; p = p->next)
    if (!(params[n++] = define(cx, p->name, p->loc, SYM_ARG))) ok = 0;
  while (n > 0)
    if (params[--n]) undefine(cx, params[n]);
  if (!f) return;
  f->def = st;
  f->broken = !ok;
  f->used = !ok; /* no warning that it is unused on top of the error */
}

static int once(Stmt **slot, int *slot_stmt, Stmt *st, int stmt, const char *what) {
  if (*slot) {
    error_at(st->loc, "%s is defined twice (first at line %d, column %d)", what, (*slot)->loc.line, (*slot)->loc.col);
    return 0;
  }
  *slot = st;
  if (slot_stmt) *slot_stmt = stmt;
  return 1;
}

static void add_constraints(Ctx *cx, const Stmt *st) {
  List l = {{0}, {0}, {0}};
  if (flatten(cx, st->expr, &l) < 0) return;
  for (int i = 0; i < l.nodes.n; i++) {
    Loc loc = {l.lines.v[i], l.cols.v[i]};
    if (!(cx->d->nodes[l.nodes.v[i]].flags & DEP_INPUT)) {
      error_at(loc, "constraint %d does not depend on any coordinate", cx->g.n + 1);
      continue;
    }
    if (cx->g.n >= MAX_CONSTRAINTS) {
      error_at(loc, "too many constraints: this is constraint %d, at most %d are supported", cx->g.n + 1,
               MAX_CONSTRAINTS);
      return;
    }
    intvec_push(&cx->g, l.nodes.v[i]);
    intvec_push(&cx->g_line, loc.line);
    intvec_push(&cx->g_col, loc.col);
  }
}

// Flatten a list of entries of M (diag(...) or a row) into want nodes,
// expressions of constants, params and coordinates; a wrong count is an
// error at at, naming the list what.
static int *mass_list(Ctx *cx, const Ast *e, Loc at, const char *what, int want) {
  List l = {{0}, {0}, {0}};
  if (flatten(cx, e, &l) < 0) return NULL;
  if (l.nodes.n != want) {
    error_at(at, "%s has %d value%s, expected %d (one per coordinate)", what, l.nodes.n, l.nodes.n == 1 ? "" : "s",
             want);
    return NULL;
  }
  return l.nodes.v;
}

// The params' default values, to evaluate M at them (freed by the caller).
static double *param_values(const Ctx *cx) {
  double *prm = xmalloc((size_t)(cx->nparams + 1) * sizeof *prm);
  for (int i = 0; i < cx->nparams; i++) prm[i] = cx->params[i].value;
  return prm;
}

// M from its entries as nodes: m of the diagonal, or m*m row-major when
// dense. With params, M^-1 goes into the DAG (mass_setup_params); either
// way M's value (at the default params) is checked and classified by
// mass_setup or mass_setup_diag.
static void mass_from_nodes(Ctx *cx, const int *nodes, int dense, Loc loc) {
  Model *mod = cx->mod;
  int n = dense ? mod->m * mod->m : mod->m, params = 0, coords = 0;
  for (int i = 0; i < n; i++) params |= cx->d->nodes[nodes[i]].op != OP_CONST;
  for (int i = 0; i < n; i++) coords |= cx->d->nodes[nodes[i]].flags & DEP_INPUT;
  if (coords) { /* M(q): checked at q0 once q0 is known (mass_q_check) */
    mass_q_setup(mod, nodes, dense, loc);
    return;
  }
  if (params && mass_setup_params(mod, nodes, dense, loc) < 0) return;
  double *prm = param_values(cx), *v = xmalloc((size_t)n * sizeof *v);
  dag_eval_many(cx->d, nodes, n, NULL, prm, v);
  if (dense) mass_setup(mod, v, loc);
  else mass_setup_diag(mod, v, loc);
  free(prm);
  free(v);
}

// Lower M = ... into its m*m entries when written as [[...]], else into its
// diagonal, as nodes of constants and params; mass_from_nodes checks it
// and finds its structure.
static void lower_mass(Ctx *cx) {
  Model *mod = cx->mod;
  int m = mod->m;
  if (!cx->mass) {
    mass_setup(mod, NULL, (Loc){0, 0});
    return;
  }
  cx->stmt = cx->mass_stmt;
  cx->d->where = cx->mass->loc;
  const Ast *e = cx->mass->expr;
  if (e->kind == A_IDENTITY) {
    mass_setup(mod, NULL, e->loc);
    return;
  }
  if (e->kind == A_DIAG) {
    Ast list = *e;
    list.kind = A_LIST;
    int *dg = mass_list(cx, &list, cx->mass->loc, "diag(...) of M", m);
    if (dg) mass_from_nodes(cx, dg, 0, e->loc);
    return;
  }
  if (e->kind == A_LIST) {
    int rows = 0;
    for (const Ast *r = e->args; r; r = r->next) rows++;
    if (rows != m) {
      error_at(e->loc, "M has %d row%s, expected %d (one per coordinate)", rows, rows == 1 ? "" : "s", m);
      return;
    }
    /* every row read and checked before the m x m matrix is allocated */
    int **v = arena_alloc((size_t)m * sizeof *v);
    int i = 0;
    for (const Ast *r = e->args; r; r = r->next, i++) {
      v[i] = r->kind == A_LIST ? mass_list(cx, r, r->loc, "a row of M", m) : NULL;
      if (r->kind != A_LIST) error_at(r->loc, "M = [[...], ...] needs each row as a list");
      if (!v[i]) return;
    }
    int *dense = xmalloc((size_t)m * (size_t)m * sizeof *dense);
    for (i = 0; i < m; i++) memcpy(dense + (size_t)i * m, v[i], (size_t)m * sizeof *dense);
    mass_from_nodes(cx, dense, 1, e->loc);
    free(dense);
    return;
  }
  int n = lower(cx, e);
  if (n < 0) return;
  const Node *nd = &cx->d->nodes[n];
  int *dg = arena_alloc((size_t)m * sizeof *dg);
  for (int i = 0; i < m; i++) dg[i] = n;
  if (nd->flags & DEP_INPUT) { /* c(q) times the identity */
    mass_from_nodes(cx, dg, 0, e->loc);
    return;
  }
  double *prm = param_values(cx);
  double c = dag_eval(cx->d, n, NULL, prm);
  free(prm);
  if (!(c > 0)) {
    error_at(e->loc, "M = c (c times the identity) needs c > 0%s, got %g", nd->op == OP_CONST ? "" : " at the default params",
             c);
    return;
  }
  mass_from_nodes(cx, dg, 0, e->loc);
}

// q0 = [...] or p0 = [...]: m values that may use params (NAME_init_params
// evaluates them then) into *nodes, and their values at the default params;
// zeros when the statement is missing.
static double *initial_values(Ctx *cx, Stmt *st, int stmt, const char *what, Loc *loc, int **nodes) {
  int m = cx->mod->m;
  double *v = arena_alloc((size_t)m * sizeof(double)), *prm = arena_alloc((size_t)(cx->nparams + 1) * sizeof(double));
  *nodes = arena_alloc((size_t)m * sizeof(int));
  for (int i = 0; i < m; i++) (*nodes)[i] = cx->d->zero;
  if (!st) return v;
  cx->stmt = stmt;
  cx->d->where = *loc = st->loc;
  int *n = value_list(cx, st, what, what, m, 1);
  if (!n) return NULL;
  for (int i = 0; i < cx->nparams; i++) prm[i] = cx->params[i].value;
  memcpy(*nodes, n, (size_t)m * sizeof(int));
  dag_eval_many(cx->d, n, m, NULL, prm, v);
  return v;
}

// The events, after the last statement (the number of momenta is known):
// each a scalar expression of q, p and params with a name of its own that C
// can use, and that depends on q or p.
static void lower_events(Ctx *cx) {
  Model *mod = cx->mod;
  int n = cx->events.n;
  mod->event_names = arena_alloc((size_t)(n + 1) * sizeof *mod->event_names);
  mod->event_nodes = arena_alloc((size_t)(n + 1) * sizeof(int));
  mod->event_dirs = arena_alloc((size_t)(n + 1) * sizeof(int));
  const Stmt **seen = arena_alloc((size_t)(n + 1) * sizeof *seen);
  cx->momenta = 1;
  for (int k = 0; k < n; k++) {
    const Stmt *st = cx->prog;
    for (int i = 0; i < cx->events.v[k]; i++) st = st->next;
    seen[k] = st;
    cx->stmt = cx->events.v[k];
    const char *problem = c_name_problem(st->name);
    int dup = -1;
    for (int j = 0; j < k && dup < 0; j++)
      if (!strcmp(seen[j]->name, st->name)) dup = j;
    if (problem) error_at(st->name_loc, "'%s' cannot name an event: it is %s, which the generated C cannot use",
                          st->name, problem);
    else if (dup >= 0)
      error_at(st->name_loc, "event '%s' is defined twice (first at line %d, column %d)", st->name,
               seen[dup]->name_loc.line, seen[dup]->name_loc.col);
    int node = lower(cx, st->expr);
    if (node < 0 || problem || dup >= 0) continue;
    if (!(cx->d->nodes[node].flags & DEP_INPUT)) {
      error_at(st->expr->loc, "event '%s' does not depend on q or p: its sign never changes", st->name);
      continue;
    }
    if (mod->nevents >= MAX_EVENTS) {
      error_at(st->loc, "too many events: at most %d are supported", MAX_EVENTS);
      break;
    }
    mod->event_names[mod->nevents] = st->name;
    mod->event_nodes[mod->nevents] = node;
    mod->event_dirs[mod->nevents++] = st->dir;
  }
  cx->momenta = 0;
}

static int by_location(const void *a, const void *b) {
  const Sym *x = *(const Sym *const *)a, *y = *(const Sym *const *)b;
  return x->loc.line != y->loc.line ? (x->loc.line > y->loc.line) - (x->loc.line < y->loc.line)
                                    : (x->loc.col > y->loc.col) - (x->loc.col < y->loc.col);
}

// Warn about every definition and param never used, in file order.
static void warn_unused(Ctx *cx) {
  Sym **unused = arena_alloc((size_t)(cx->nsyms + 1) * sizeof *unused);
  int n = 0;
  for (int b = 0; b < cx->nbuckets; b++)
    for (Sym *s = cx->buckets[b]; s; s = s->next)
      if (!s->used && (s->kind == SYM_VALUE || s->kind == SYM_VALUES || s->kind == SYM_PARAM || s->kind == SYM_FUNC))
        unused[n++] = s;
  qsort(unused, (size_t)n, sizeof *unused, by_location);
  for (int i = 0; i < n; i++)
    warning_at(unused[i]->loc, "%s '%s' is never used",
               unused[i]->kind == SYM_PARAM ? "param" : unused[i]->kind == SYM_FUNC ? "function" : "definition",
               unused[i]->name);
}

// Refuse a scalar coordinate or a param whose name is also another column of
// the standalone driver's outputs, so that every column name says one thing:
// its CSV (t, the coordinates, p_ and a coordinate, lambda_a, H, g_a, hc_a for
// a = 1..nu), an ensemble's input (coordinates, p_..., params) and summary
// (traj, status, steps, ..., iters_max), the events CSV (event, a reserved
// word, and t). A param p_x beside a coordinate x could not be swept (--sweep
// p_x set the momentum), and coordinates x, p_x gave the header
// t,x,p_x,p_x,p_p_x,H. Array elements (x[3], p_x[3]) hold brackets and cannot
// clash; events and constraints give no column a name of theirs. Reported in
// file order.
static void check_column_names(Ctx *cx, int nu) {
  static const char summary[] = "in an ensemble's summary";
  static const char *const fixed[][2] = {{"t", "the time"},   {"H", "the energy"},     {"traj", summary},
                                         {"status", summary}, {"steps", summary},      {"max_dH", summary},
                                         {"max_g", summary},  {"max_hc", summary},     {"iters_mean", summary},
                                         {"iters_max", summary}};
  static const char *const numbered[][2] = {
      {"lambda_", "the multiplier of constraint"}, {"g_", "constraint"}, {"hc_", "the hidden constraint"}};
  Sym **named = arena_alloc((size_t)(cx->nsyms + 1) * sizeof *named);
  int n = 0;
  for (int b = 0; b < cx->nbuckets; b++)
    for (Sym *s = cx->buckets[b]; s; s = s->next)
      if (s->kind == SYM_COORD || s->kind == SYM_PARAM) named[n++] = s;
  qsort(named, (size_t)n, sizeof *named, by_location);
  for (int i = 0; i < n; i++) {
    const char *name = named[i]->name;
    char what[200] = "";
    for (size_t k = 0; k < sizeof fixed / sizeof fixed[0] && !*what; k++)
      if (!strcmp(name, fixed[k][0])) snprintf(what, sizeof what, "%s", fixed[k][1]);
    for (size_t k = 0; k < sizeof numbered / sizeof numbered[0] && !*what; k++) {
      size_t len = strlen(numbered[k][0]);
      const char *digits = name + len;
      if (strncmp(name, numbered[k][0], len) || digits[0] < '1' || digits[0] > '9' || strlen(digits) > 4 ||
          strspn(digits, "0123456789") != strlen(digits) || atoi(digits) > nu)
        continue;
      snprintf(what, sizeof what, "%s %s", numbered[k][1], digits);
    }
    const Sym *c = !*what && !strncmp(name, "p_", 2) ? lookup(cx, name + 2) : NULL;
    if (c && c->kind == SYM_COORD)
      snprintf(what, sizeof what, "the momentum of the coordinate '%s' of line %d, column %d", c->name, c->loc.line,
               c->loc.col);
    if (*what)
      error_at(named[i]->loc, "'%s' cannot name a %s: it is a column of the driver's output already (%s); rename it",
               name, named[i]->kind == SYM_PARAM ? "param" : "coordinate", what);
  }
}

// Analyse the statements of a model. Returns NULL if any error was reported.
Model *analyse(const char *file, Stmt *prog) {
  Ctx *cx = xcalloc(1, sizeof *cx);
  grow_table(cx);
  Model *mod = arena_alloc(sizeof *mod);
  mod->file = file;
  mod->mass_loop = MASS_LOOP_DEFAULT;
  mod->stage_loop = STAGE_LOOP_DEFAULT;
  cx->mod = mod;
  cx->d = mod->dag = dag_new();
  cx->prog = prog;
  mod->U = dag_const(cx->d, 0);
  int stmt = 0;
  for (Stmt *st = prog; st && !diag_too_many(); st = st->next, stmt++) {
    cx->stmt = stmt;
    cx->d->where = st->loc;
    switch (st->kind) {
    case S_VARIABLES: declare_variables(cx, st); break;
    case S_DEF: define_value(cx, st); break;
    case S_PARAM: define_param(cx, st); break;
    case S_POTENTIAL:
      if (once(&cx->pot, NULL, st, stmt, "U")) {
        int n = lower(cx, st->expr);
        if (n >= 0) mod->U = n;
        mod->U_loc = st->loc;
      }
      break;
    case S_CONSTRAINTS: add_constraints(cx, st); break;
    case S_MASS: once(&cx->mass, &cx->mass_stmt, st, stmt, "M"); break;
    case S_Q0: once(&cx->q0, &cx->q0_stmt, st, stmt, "q0"); break;
    case S_P0: once(&cx->p0, &cx->p0_stmt, st, stmt, "p0"); break;
    case S_EVENT: intvec_push(&cx->events, stmt); break;
    case S_FUNC: define_function(cx, st); break;
    }
  }
  if (mod->m == 0 && !diag_error_count()) error_at((Loc){1, 1}, "the model declares no coordinates: add 'variables x, ...'");
  if (mod->m > 0 && !diag_too_many()) {
    lower_mass(cx);
    mod->q0 = initial_values(cx, cx->q0, cx->q0_stmt, "q0", &mod->q0_loc, &mod->q0n);
    mod->p0 = initial_values(cx, cx->p0, cx->p0_stmt, "p0", &mod->p0_loc, &mod->p0n);
    if (mod->mass_q && mod->q0) {
      double *prm = param_values(cx);
      mass_q_check(mod, prm);
      free(prm);
    }
    lower_events(cx);
  }
  mod->nu = cx->g.n;
  mod->g = cx->g.v;
  mod->g_loc = arena_alloc((size_t)(mod->nu + 1) * sizeof(Loc));
  for (int a = 0; a < mod->nu; a++) mod->g_loc[a] = (Loc){cx->g_line.v[a], cx->g_col.v[a]};
  check_column_names(cx, mod->nu);
  if (mod->m > 0 && mod->nu > mod->m && !diag_error_count())
    error_at(mod->g_loc[mod->m], "more constraints than coordinates: constraint %d of %d, with %d coordinate%s (the "
             "constraints cannot be independent)", mod->m + 1, mod->nu, mod->m, mod->m == 1 ? "" : "s");
  mod->coord_names = cx->names;
  mod->params = cx->params;
  mod->nparams = cx->nparams;
  mod->degU = cx->d->nodes[mod->U].deg;
  if (mod->mass_q) mod->degU = DEG_NONPOLY; /* H's degree for the quadrature: T = p' M(q)^-1 p / 2 is rational in q */
  mod->degg = 0;
  for (int a = 0; a < mod->nu; a++) {
    int dg = cx->d->nodes[mod->g[a]].deg;
    if (dg == DEG_NONPOLY || mod->degg == DEG_NONPOLY) mod->degg = DEG_NONPOLY;
    else if (dg > mod->degg) mod->degg = dg;
  }
  if (!diag_error_count()) warn_unused(cx);
  free(cx);
  return diag_error_count() ? NULL : mod;
}
