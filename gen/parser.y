/* parser.y - the grammar of the .ham model language (docs/language.md).
 *
 * A pure, reentrant LALR(1) parser with locations. It builds a list of
 * statements whose expressions are syntax trees; all meaning (names,
 * shapes, constants) is given later by ast.c. Statements need no separator;
 * after a syntax error the parser skips to where a statement can start.
 * Syntax errors name the unexpected token (with its text for names and
 * numbers), the expected ones when there are few, and the bracket left
 * open when its closer would fit; a reserved word where a name belongs is
 * its own error. Nesting is bounded: the lexer refuses deeper brackets than
 * MAX_NESTING and ast_new refuses trees deeper than MAX_AST_DEPTH, so no
 * later pass can overflow the C stack. */

%define api.pure full
%define parse.error custom
%define parse.lac full
%locations
%expect 0
%param {yyscan_t scanner}
%parse-param {ParseState *ps}

%code requires {
#include "hbvmgen.h"
#ifndef YY_TYPEDEF_YY_SCANNER_T
#define YY_TYPEDEF_YY_SCANNER_T
typedef void *yyscan_t;
#endif
typedef struct {
  Stmt *first, *last;  /* statements in file order */
  int fatal;           /* the lexer gave up (nesting too deep, too many errors) */
  Loc end;             /* just after the last token: where end of file is reported */
  const char *text;    /* text of the last name or number read (for messages) */
  int after_name;      /* the token before the current one was that name ... */
  Loc name_loc;        /* ... which is here */
  const char *prev_text; /* the name or number read before text, and where */
  Loc prev_loc;
  int is_name;         /* the current token is a name */
  int event_line;      /* the line of the last 'event' read (0: none) */
  long tokens;         /* tokens read, bounded by MAX_TOKENS */
  int depth;           /* open brackets, counted by the lexer ... */
  int pop;             /* ... which closes one when it reads the next token */
  Loc open[MAX_NESTING];       /* where each open bracket is */
  char open_char[MAX_NESTING]; /* and which one: '(' or '[' */
} ParseState;
}

%code provides {
int yylex(YYSTYPE *lval, YYLTYPE *lloc, yyscan_t scanner);
}

%code {
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "lexer.h"

static Loc loc_of(YYLTYPE l) {
  Loc loc = {l.first_line, l.first_column};
  return loc;
}

// Bison's own errors; only "memory exhausted" (the parser stack is full)
// can arrive here, syntax errors go to yyreport_syntax_error.
static void yyerror(YYLTYPE *l, yyscan_t scanner, ParseState *ps, const char *msg) {
  (void)scanner;
  if (ps->fatal || diag_too_many()) return;
  if (!strcmp(msg, "memory exhausted"))
    error_at(loc_of(*l), "expression nested too deeply");
  else
    error_at(loc_of(*l), "%s", msg);
}

static void reserved_name(YYLTYPE l, const char *word) {
  error_at(loc_of(l), "'%s' is a reserved word and cannot be used as a name", word);
}

static void add_stmt(ParseState *ps, StmtKind kind, YYLTYPE l, Ast *expr) {
  Stmt *s = arena_alloc(sizeof *s);
  s->kind = kind;
  s->loc = loc_of(l);
  s->expr = expr;
  if (ps->last) ps->last->next = s; else ps->first = s;
  ps->last = s;
}

static Ast *leaf_name(AstKind kind, YYLTYPE l, const char *name) {
  Ast *n = ast_new(kind, loc_of(l), NULL, NULL, NULL);
  n->name = name;
  return n;
}

static Decl *decl_reverse(Decl *list) {
  Decl *prev = NULL;
  while (list) {
    Decl *next = list->next;
    list->next = prev;
    prev = list;
    list = next;
  }
  return prev;
}

/* The sums or comprehensions of iterators (linked by next, innermost first,
 * each an A_FOR with its name, range or list in a and b, and no body yet)
 * around body: [e for i in A for j in B] is [[e for j in B] for i in A],
 * sum(i in A, j in B, e) is sum(i in A, sum(j in B, e)). Each node is at
 * its iterator, the outermost at loc. */
static Ast *nest(AstKind kind, Loc loc, Ast *iters, Ast *body) {
  for (Ast *it = iters; it; it = it->next) {
    body = ast_new(kind, it->next ? it->loc : loc, it->a, it->b, body);
    body->name = it->name;
    body->name_loc = it->name_loc;
    body->op = it->next ? ',' : 0; /* an inner iterator, not a sum or list of its own */
  }
  return body;
}

static Ast *iterator(YYLTYPE l, YYLTYPE at, const char *name, Ast *from, Ast *to) {
  Ast *n = ast_new(A_FOR, loc_of(at), from, to, NULL);
  n->name = name;
  n->name_loc = loc_of(l);
  return n;
}

/* Reverse a list linked by next. */
static Ast *list_reverse(Ast *list) {
  Ast *prev = NULL;
  while (list) {
    Ast *next = list->next;
    list->next = prev;
    prev = list;
    list = next;
  }
  return prev;
}
}

%union {
  double num;
  const char *str;
  Ast *ast;
  Decl *decl;
}

%token <num> NUMBER "number"
%token <str> NAME "name"
%token <str> FUNC "function name"
%token <str> VARIABLES "'variables'" PARAM "'param'" KW_M "'M'" KW_U "'U'" KW_G "'g'"
%token <str> Q0 "'q0'" P0 "'p0'" IDENTITY "'identity'" DIAG "'diag'" SUM "'sum'"
%token <str> FOR "'for'" IN "'in'" EVENT "'event'" RISING "'rising'" FALLING "'falling'" DEF "'def'"
%token DOTDOT "'..'"

%type <ast> expr primary args arglist iter iters fors
%type <decl> decls decl params
%type <str> name reserved stmt_reserved
%type <num> direction

%left '+' '-'
%left '*' '/'
%precedence UMINUS
%right '^'
%token ';' '=' ',' '[' ']' '(' ')' /* numbered in this order, the order expected tokens are listed in */

%%

model
  : %empty
  | model stmt
  | model ';'
  | model error                 { ps->depth = ps->pop = 0; /* resynchronise on the next statement */ }
  ;

stmt
  : VARIABLES decls             { add_stmt(ps, S_VARIABLES, @1, NULL); ps->last->decls = decl_reverse($2); }
  | NAME '=' expr               { add_stmt(ps, S_DEF, @1, $3); ps->last->name = $1; ps->last->name_loc = loc_of(@1); }
  | PARAM name '=' expr         { add_stmt(ps, S_PARAM, @1, $4); ps->last->name = $2; ps->last->name_loc = loc_of(@2); }
  | KW_M '=' expr               { add_stmt(ps, S_MASS, @1, $3); }
  | KW_U '=' expr               { add_stmt(ps, S_POTENTIAL, @1, $3); }
  | KW_G '=' expr               { add_stmt(ps, S_CONSTRAINTS, @1, $3); }
  | Q0 '=' expr                 { add_stmt(ps, S_Q0, @1, $3); }
  | P0 '=' expr                 { add_stmt(ps, S_P0, @1, $3); }
  | EVENT name '=' expr direction
                                { add_stmt(ps, S_EVENT, @1, $4); ps->last->name = $2; ps->last->name_loc = loc_of(@2);
                                  ps->last->dir = (int)$5; }
  | DEF name '(' params ')' '=' expr
                                { add_stmt(ps, S_FUNC, @1, $7); ps->last->name = $2; ps->last->name_loc = loc_of(@2);
                                  ps->last->decls = decl_reverse($4); }
  | stmt_reserved '=' expr      { reserved_name(@1, $1); }
  ;

/* The parameters of a function of 'def', in reverse. */
params
  : name                        { $$ = arena_alloc(sizeof(Decl)); $$->name = $1; $$->loc = loc_of(@1); }
  | params ',' name             { $$ = arena_alloc(sizeof(Decl)); $$->name = $3; $$->loc = loc_of(@3); $$->next = $1; }
  ;

/* Which sign changes of an event count: both (0), rising (1), falling (-1). */
direction
  : %empty                      { $$ = 0; }
  | RISING                      { $$ = 1; }
  | FALLING                     { $$ = -1; }
  ;

/* Where a name is wanted, a reserved word is an error, not a syntax error. */
name
  : NAME
  | reserved                    { reserved_name(@1, $1); }
  ;

reserved
  : stmt_reserved | VARIABLES | PARAM | KW_M | KW_U | KW_G | Q0 | P0 | EVENT | RISING | FALLING | DEF
  ;

/* The reserved words that cannot start a statement. */
stmt_reserved
  : IDENTITY | DIAG | SUM | FOR | IN | FUNC
  ;

decls
  : decl                        { $$ = $1; }
  | decls ',' decl              { $3->next = $1; $$ = $3; }
  ;

decl
  : name                        { $$ = arena_alloc(sizeof(Decl)); $$->name = $1; $$->loc = loc_of(@1); }
  | name '[' expr ']'           { $$ = arena_alloc(sizeof(Decl)); $$->name = $1; $$->loc = loc_of(@1); $$->size = $3; }
  ;

expr
  : primary
  | expr '+' expr               { $$ = ast_new(A_BIN, loc_of(@2), $1, $3, NULL); $$->op = '+'; }
  | expr '-' expr               { $$ = ast_new(A_BIN, loc_of(@2), $1, $3, NULL); $$->op = '-'; }
  | expr '*' expr               { $$ = ast_new(A_BIN, loc_of(@2), $1, $3, NULL); $$->op = '*'; }
  | expr '/' expr               { $$ = ast_new(A_BIN, loc_of(@2), $1, $3, NULL); $$->op = '/'; }
  | expr '^' expr               { $$ = ast_new(A_BIN, loc_of(@2), $1, $3, NULL); $$->op = '^'; }
  | '-' expr %prec UMINUS       { $$ = ast_new(A_NEG, loc_of(@1), $2, NULL, NULL); }
  | '+' expr %prec UMINUS       { $$ = $2; }
  ;

primary
  : NUMBER                      { $$ = ast_new(A_NUM, loc_of(@1), NULL, NULL, NULL); $$->num = $1; }
  | NAME                        { $$ = leaf_name(A_NAME, @1, $1); }
  | NAME '[' expr ']'           { $$ = ast_new(A_INDEX, loc_of(@1), $3, NULL, NULL); $$->name = $1; }
  | '(' expr ')'                { $$ = $2; }
  | FUNC '(' args ')'           { $$ = leaf_name(A_CALL, @1, $1); ast_set_args($$, $3); }
  | NAME '(' args ')'           { $$ = leaf_name(A_CALL, @1, $1); ast_set_args($$, $3); }
  | SUM '(' iters ',' expr ')'  { $$ = nest(A_SUM, loc_of(@1), $3, $5); }
  | '[' args ']'                { $$ = ast_new(A_LIST, loc_of(@1), NULL, NULL, NULL); ast_set_args($$, $2); }
  | '[' expr fors ']'           { $$ = nest(A_FOR, loc_of(@1), $3, $2); }
  | IDENTITY                    { $$ = ast_new(A_IDENTITY, loc_of(@1), NULL, NULL, NULL); }
  | DIAG '(' args ')'           { $$ = ast_new(A_DIAG, loc_of(@1), NULL, NULL, NULL); ast_set_args($$, $3); }
  ;

/* What an index variable runs over: a range of integers, or a list. */
iter
  : name IN expr DOTDOT expr    { $$ = iterator(@1, @1, $1, $3, $5); }
  | name IN expr                { $$ = iterator(@1, @1, $1, $3, NULL); }
  ;

/* The iterators of a sum, and the 'for' clauses of a comprehension, in reverse. */
iters
  : iter
  | iters ',' iter              { $3->next = $1; $$ = $3; }
  ;

fors
  : FOR iter                    { $$ = $2; $$->loc = loc_of(@1); }
  | fors FOR iter               { $3->loc = loc_of(@2); $3->next = $1; $$ = $3; }
  ;

args
  : %empty                      { $$ = NULL; }
  | arglist                     { $$ = list_reverse($1); }
  ;

/* Built in reverse (newest first) so each append is O(1). */
arglist
  : expr                        { $$ = $1; }
  | arglist ',' expr            { $3->next = $1; $$ = $3; }
  ;

%%

/* Append to a message buffer of size MSG_SIZE, truncating quietly. */
#define MSG_SIZE 512
static void msg_add(char *msg, const char *fmt, ...) {
  size_t n = strlen(msg);
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg + n, MSG_SIZE - n, fmt, ap);
  va_end(ap);
}

/* Whether k is a reserved word (the grammar accepts them where a name is
 * wanted, only to report them as misused). */
static int is_reserved(yysymbol_kind_t k) {
  switch (k) {
  case YYSYMBOL_FUNC: case YYSYMBOL_VARIABLES: case YYSYMBOL_PARAM: case YYSYMBOL_KW_M: case YYSYMBOL_KW_U:
  case YYSYMBOL_KW_G: case YYSYMBOL_Q0: case YYSYMBOL_P0: case YYSYMBOL_IDENTITY: case YYSYMBOL_DIAG:
  case YYSYMBOL_SUM: case YYSYMBOL_FOR: case YYSYMBOL_IN: case YYSYMBOL_EVENT: case YYSYMBOL_RISING:
  case YYSYMBOL_FALLING: case YYSYMBOL_DEF: return 1;
  default: return 0;
  }
}

/* The tokens the parser could take instead of the unexpected one, as they
 * should be listed: where only a name fits (no statement could start
 * there), the reserved words are left out. Returns their number. */
static int expected_tokens(const yypcontext_t *ctx, yysymbol_kind_t *out) {
  yysymbol_kind_t all[YYNTOKENS];
  int n = yypcontext_expected_tokens(ctx, all, YYNTOKENS), name = 0, stmt = 0, k = 0;
  for (int i = 0; i < n; i++) {
    name |= all[i] == YYSYMBOL_NAME;
    stmt |= all[i] == YYSYMBOL_YYEOF;  /* the end of a statement: the next may start */
  }
  for (int i = 0; i < n; i++)
    if (!(name && !stmt && is_reserved(all[i]))) out[k++] = all[i];
  return k;
}

/* Whether token t is one of the characters in set. */
static int is_char(yysymbol_kind_t t, const char *set) {
  for (; *set; set++)
    if (t == YYTRANSLATE((unsigned char)*set)) return 1;
  return 0;
}

/* The expected tokens as they read best: the tokens that can start an
 * expression as "an expression", the five operators (and '[' of indexing,
 * '(' of a call with them) as "an operator", any other token by its name. Fills words,
 * returns their number. */
static int describe_expected(const yysymbol_kind_t *expected, int n, const char **words) {
  int expr = 0, nops = 0, k = 0;
  for (int i = 0; i < n; i++) {
    expr |= expected[i] == YYSYMBOL_NUMBER;
    nops += is_char(expected[i], "+-*/^");
  }
  if (expr) words[k++] = "an expression";
  if (nops == 5) words[k++] = "an operator";
  for (int i = 0; i < n; i++) {
    yysymbol_kind_t t = expected[i];
    int starts = t == YYSYMBOL_NUMBER || t == YYSYMBOL_NAME || t == YYSYMBOL_FUNC || t == YYSYMBOL_SUM ||
                 t == YYSYMBOL_IDENTITY || t == YYSYMBOL_DIAG || is_char(t, "+-([");
    if (!(expr && starts) && !(nops == 5 && is_char(t, "+-*/^[("))) words[k++] = yysymbol_name(t);
  }
  return k;
}

/* A syntax error: "syntax error, unexpected X", the text of X when it is a
 * name or a number, what was expected when it fits in four words, and,
 * when the innermost open bracket's closer is expected, where that
 * bracket was opened (the usual cause: a missing ')' or ']'). */
static int yyreport_syntax_error(const yypcontext_t *ctx, yyscan_t scanner, ParseState *ps) {
  (void)scanner;
  if (ps->fatal || diag_too_many()) return 0;
  char msg[MSG_SIZE] = "";
  yysymbol_kind_t tok = yypcontext_token(ctx);
  /* a name after an event's expression, on its line (the unexpected token, or the one before): a
   * mistyped direction */
  int word = tok == YYSYMBOL_NAME || is_reserved(tok); /* the lexer's name_loc, text are this token's */
  Loc stray = word ? ps->prev_loc : ps->name_loc;
  if (ps->after_name && ps->last && ps->last->kind == S_EVENT && stray.line == ps->last->loc.line) {
    error_at(stray, "'%.40s' after the expression of event '%s': an event's direction is 'rising' or "
             "'falling' (or nothing: both)", word ? ps->prev_text : ps->text, ps->last->name);
    return 0;
  }
  yysymbol_kind_t expected[YYNTOKENS];
  int nexp = expected_tokens(ctx, expected);
  /* a comma in an event, as in a list: after its name (one event a statement) or
   * between its expression and its direction */
  const YYLTYPE *at_tok = yypcontext_location(ctx);
  if (is_char(tok, ",") && ps->depth == 0 && at_tok->first_line == ps->event_line) {
    int want_eq = 0;
    for (int i = 0; i < nexp; i++) want_eq |= expected[i] == YYTRANSLATE('=');
    error_at(loc_of(*at_tok), want_eq ? "',' after the name of an event: one event a statement ('event NAME = EXPR')"
                                      : "',' after the expression of an event: its direction follows with no comma "
                                        "('event NAME = EXPR falling')");
    return 0;
  }
  msg_add(msg, "syntax error, unexpected %s", yysymbol_name(tok));
  if (tok == YYSYMBOL_NAME || tok == YYSYMBOL_FUNC || tok == YYSYMBOL_NUMBER)
    msg_add(msg, " '%.40s%s'", ps->text, strlen(ps->text) > 40 ? "..." : "");
  if (is_char(tok, ")]") && ps->depth == 0) msg_add(msg, " (no bracket is open)");
  yysymbol_kind_t closer = YYSYMBOL_YYEMPTY;
  if (ps->depth > 0) closer = YYTRANSLATE(ps->open_char[ps->depth - 1] == '(' ? ')' : ']');
  int closes = 0;
  for (int i = 0; i < nexp; i++) closes |= expected[i] == closer;
  const char *words[YYNTOKENS + 2];
  int nwords = describe_expected(expected, nexp, words);
  if (nwords <= 4) {
    for (int i = 0; i < nwords; i++)
      msg_add(msg, "%s%s", i == 0 ? ", expecting " : i == nwords - 1 ? " or " : ", ", words[i]);
  } else if (closes) {
    msg_add(msg, ", expecting %s", yysymbol_name(closer));
  }
  if (closes) {
    Loc at = ps->open[ps->depth - 1];
    msg_add(msg, " (to close the '%c' at line %d, column %d)", ps->open_char[ps->depth - 1], at.line, at.col);
  }
  error_at(loc_of(*yypcontext_location(ctx)), "%s", msg);
  return 0;
}

/* Parse src (len bytes, may contain NUL) into a statement list, NULL when
 * there is none. Syntax errors are reported and parsing goes on where it
 * can; the caller checks diag_error_count(). */
Stmt *parse_model(const char *src, size_t len) {
  yyscan_t scanner;
  ParseState *ps = xcalloc(1, sizeof *ps);
  ps->end = (Loc){1, 1};
  if (yylex_init_extra(ps, &scanner)) internal_error("cannot start the lexer");
  YY_BUFFER_STATE buf = yy_scan_bytes(src, (int)len, scanner);
  yyset_lineno(1, scanner);
  yyset_column(1, scanner);
  yyparse(scanner, ps);
  yy_delete_buffer(buf, scanner);
  yylex_destroy(scanner);
  Stmt *first = ps->first;
  free(ps);
  return first;
}
