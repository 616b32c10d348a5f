/* parser.y - the grammar of the .ham model language (SPEC section 1).
 *
 * A pure, reentrant LALR(1) parser with locations. It builds a list of
 * statements whose expressions are syntax trees; all meaning (names,
 * shapes, constants) is given later by ast.c. Statements need no separator;
 * after a syntax error the parser skips to where a statement can start.
 * Nesting is bounded: the lexer refuses deeper brackets than MAX_NESTING and
 * ast_new refuses trees deeper than MAX_AST_DEPTH, so no later pass can
 * overflow the C stack. */

%define api.pure full
%define parse.error detailed
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
  int depth;           /* open brackets, counted by the lexer */
  int fatal;           /* the lexer gave up (nesting too deep, too many errors) */
} ParseState;
}

%code provides {
int yylex(YYSTYPE *lval, YYLTYPE *lloc, yyscan_t scanner);
}

%code {
#include "lexer.h"

static Loc loc_of(YYLTYPE l) {
  Loc loc = {l.first_line, l.first_column};
  return loc;
}

static void yyerror(YYLTYPE *l, yyscan_t scanner, ParseState *ps, const char *msg) {
  (void)scanner;
  if (ps->fatal || diag_too_many()) return;
  if (!strcmp(msg, "memory exhausted"))
    error_at(loc_of(*l), "expression too deeply nested");
  else
    error_at(loc_of(*l), "%s", msg);
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
%token VARIABLES "'variables'" PARAM "'param'" KW_M "'M'" KW_U "'U'" KW_G "'g'"
%token Q0 "'q0'" P0 "'p0'" IDENTITY "'identity'" DIAG "'diag'" SUM "'sum'"
%token FOR "'for'" IN "'in'" DOTDOT "'..'"

%type <ast> expr primary args arglist
%type <decl> decls decl

%left '+' '-'
%left '*' '/'
%precedence UMINUS
%right '^'

%%

model
  : %empty
  | model stmt
  | model ';'
  | model error                 { /* resynchronise on the next statement */ }
  ;

stmt
  : VARIABLES decls             { add_stmt(ps, S_VARIABLES, @1, NULL); ps->last->decls = decl_reverse($2); }
  | NAME '=' expr               { add_stmt(ps, S_DEF, @1, $3); ps->last->name = $1; ps->last->name_loc = loc_of(@1); }
  | PARAM NAME '=' expr         { add_stmt(ps, S_PARAM, @1, $4); ps->last->name = $2; ps->last->name_loc = loc_of(@2); }
  | KW_M '=' expr               { add_stmt(ps, S_MASS, @1, $3); }
  | KW_U '=' expr               { add_stmt(ps, S_POTENTIAL, @1, $3); }
  | KW_G '=' expr               { add_stmt(ps, S_CONSTRAINTS, @1, $3); }
  | Q0 '=' expr                 { add_stmt(ps, S_Q0, @1, $3); }
  | P0 '=' expr                 { add_stmt(ps, S_P0, @1, $3); }
  | FUNC '=' expr               { error_at(loc_of(@1), "'%s' is a reserved function name and cannot be defined", $1); }
  ;

decls
  : decl                        { $$ = $1; }
  | decls ',' decl              { $3->next = $1; $$ = $3; }
  ;

decl
  : NAME                        { $$ = arena_alloc(sizeof(Decl)); $$->name = $1; $$->loc = loc_of(@1); }
  | NAME '[' expr ']'           { $$ = arena_alloc(sizeof(Decl)); $$->name = $1; $$->loc = loc_of(@1); $$->size = $3; }
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
  | SUM '(' NAME IN expr DOTDOT expr ',' expr ')'
                                { $$ = ast_new(A_SUM, loc_of(@1), $5, $7, $9); $$->name = $3; }
  | '[' args ']'                { $$ = ast_new(A_LIST, loc_of(@1), NULL, NULL, NULL); ast_set_args($$, $2); }
  | '[' expr FOR NAME IN expr DOTDOT expr ']'
                                { $$ = ast_new(A_FOR, loc_of(@1), $6, $8, $2); $$->name = $4; }
  | IDENTITY                    { $$ = ast_new(A_IDENTITY, loc_of(@1), NULL, NULL, NULL); }
  | DIAG '(' args ')'           { $$ = ast_new(A_DIAG, loc_of(@1), NULL, NULL, NULL); ast_set_args($$, $3); }
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

/* Parse src (len bytes, may contain NUL) into a statement list. Syntax
 * errors are reported and parsing goes on where it can; the caller checks
 * diag_error_count(). */
Stmt *parse_model(const char *src, size_t len) {
  yyscan_t scanner;
  ParseState ps = {NULL, NULL, 0, 0};
  if (yylex_init_extra(&ps, &scanner)) internal_error("cannot start the lexer");
  YY_BUFFER_STATE buf = yy_scan_bytes(src, (int)len, scanner);
  yyset_lineno(1, scanner);
  yyset_column(1, scanner);
  yyparse(scanner, &ps);
  yy_delete_buffer(buf, scanner);
  yylex_destroy(scanner);
  return ps.first;
}
