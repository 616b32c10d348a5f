/* util.c - the arena every pass allocates from, growable arrays, the
 * one way the generator dies (fatal, out_of_memory, internal_error), the
 * names the emitted C cannot use, and GCC-style diagnostics:
 * "file:line:col: error: message", then the source line and a caret under
 * the column. Lines end at LF, CRLF or a lone CR; their starts are indexed
 * once, so a diagnostic costs the length of its line, and a warning
 * repeated more than MAX_LIKE times is counted, not printed (diag_end
 * prints the count). */
#include <limits.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmgen.h"

/* ---- arena ---- */

typedef union {
  long double ld;
  void *p;
  long long ll;
} Align; /* C99 has no max_align_t */

typedef struct Block Block;
struct Block {
  Block *next;
  size_t used, size;
  Align data[];
};

static Block *arena_head;
static size_t arena_total;

#define ARENA_LIMIT ((size_t)8 << 30) /* a model needing more is refused */

// Allocate size zeroed bytes; exits with a clear message when memory runs out.
void *arena_alloc(size_t size) {
  size = (size + sizeof(Align) - 1) / sizeof(Align) * sizeof(Align);
  if (!arena_head || arena_head->size - arena_head->used < size) {
    size_t bsize = size > ((size_t)1 << 20) ? size : ((size_t)1 << 20);
    Block *b;
    if (arena_total + bsize > ARENA_LIMIT || !(b = malloc(sizeof(Block) + bsize))) out_of_memory();
    arena_total += bsize;
    b->next = arena_head;
    b->used = 0;
    b->size = bsize;
    arena_head = b;
  }
  void *p = (char *)arena_head->data + arena_head->used;
  arena_head->used += size;
  memset(p, 0, size);
  return p;
}

// An array of n node ids (at least 1) in the arena, zeroed: the step builders'
// (step*.c, lu.c) storage, here so that lu.c need not call up into step.c.
int *step_nodes(int n) { return arena_alloc((size_t)(n > 0 ? n : 1) * sizeof(int)); }

char *arena_strndup(const char *s, size_t n) {
  char *p = arena_alloc(n + 1);
  memcpy(p, s, n);
  return p;
}

static void forget_lines(void);

void arena_free_all(void) {
  forget_lines(); /* the line index lives in the arena */
  while (arena_head) {
    Block *next = arena_head->next;
    free(arena_head);
    arena_head = next;
  }
  arena_total = 0;
}

// The one growable array: make room in the arena array v (n elements of
// size elem in use, *cap allocated) for at least need elements, doubling
// its capacity and copying what is there. Returns the (maybe moved) array.
void *vec_reserve(void *v, int n, int *cap, long need, size_t elem) {
  if (need <= *cap) return v;
  long c = *cap ? *cap : 16;
  while (c < need) c *= 2;
  if (c > INT_MAX) out_of_memory();
  void *nv = arena_alloc((size_t)c * elem);
  if (n) memcpy(nv, v, (size_t)n * elem);
  *cap = (int)c;
  return nv;
}

void intvec_push(IntVec *vec, int x) {
  VEC_RESERVE(vec->v, vec->n, vec->cap, vec->n + 1);
  vec->v[vec->n++] = x;
}

void *xmalloc(size_t size) {
  void *p = malloc(size ? size : 1);
  if (!p) out_of_memory();
  return p;
}

void *xcalloc(size_t n, size_t size) {
  void *p = calloc(n ? n : 1, size ? size : 1);
  if (!p) out_of_memory();
  return p;
}

void *xrealloc(void *p, size_t size) {
  void *q = realloc(p, size ? size : 1);
  if (!q) out_of_memory();
  return q;
}

/* ---- names the emitted C cannot use ---- */

/* Keywords of C99, C11, C23 and C++ (the headers are included from C++
 * too), and what <math.h> and <stddef.h> define as macros. */
static const char *const c_keywords[] = {
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum", "extern",
    "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return", "short", "signed",
    "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void", "volatile", "while",
    /* C23 */
    "alignas", "alignof", "bool", "constexpr", "false", "nullptr", "static_assert", "thread_local", "true",
    "typeof", "typeof_unqual", NULL};
static const char *const cxx_keywords[] = {
    "and", "and_eq", "asm", "bitand", "bitor", "catch", "char8_t", "char16_t", "char32_t", "class", "compl",
    "concept", "consteval", "constinit", "const_cast", "co_await", "co_return", "co_yield", "decltype", "delete",
    "dynamic_cast", "explicit", "export", "friend", "mutable", "namespace", "new", "noexcept", "not", "not_eq",
    "operator", "or", "or_eq", "private", "protected", "public", "reinterpret_cast", "requires", "static_cast",
    "template", "this", "throw", "try", "typeid", "typename", "using", "virtual", "wchar_t", "xor", "xor_eq", NULL};
static const char *const c_macros[] = {
    "NAN", "INFINITY", "HUGE_VAL", "HUGE_VALF", "HUGE_VALL", "MATH_ERRNO", "MATH_ERREXCEPT", "math_errhandling",
    "fpclassify", "isfinite", "isinf", "isnan", "isnormal", "signbit", "isgreater", "isgreaterequal", "isless",
    "islessequal", "islessgreater", "isunordered", "iszero", "issubnormal", "iscanonical", "issignaling",
    "NULL", "offsetof", "errno", NULL};

static int in_list(const char *name, const char *const *list) {
  for (; *list; list++)
    if (!strcmp(name, *list)) return 1;
  return 0;
}

// Why name cannot be an identifier of the emitted C (a keyword of C or
// C++, a macro of <math.h> or <stddef.h>, or reserved to the
// implementation), or NULL when it can.
const char *c_name_problem(const char *name) {
  if (in_list(name, c_keywords)) return "a C keyword";
  if (in_list(name, cxx_keywords)) return "a C++ keyword";
  if (in_list(name, c_macros) || !strncmp(name, "FP_", 3) ||
      (!strncmp(name, "M_", 2) && ((name[2] >= 'A' && name[2] <= 'Z') || (name[2] >= '0' && name[2] <= '9'))))
    return "a macro of <math.h> or <stddef.h>";
  if (name[0] == '_' && (name[1] == '\0' || name[1] == '_' || (name[1] >= 'A' && name[1] <= 'Z')))
    return "reserved in C (a leading underscore followed by an uppercase letter or another underscore)";
  return NULL;
}

/* ---- dying ---- */

static void show_line(Loc loc);
static const char *diag_file = "<input>";

// The one way out of the generator before its normal end: the message,
// located when loc has a line, then exit status 1 (or abort for an
// internal error, so that a bug leaves a core and a sanitizer trace).
static void die(int internal, Loc loc, const char *fmt, va_list ap) {
  fflush(stdout);
  if (internal) fputs("hbvmgen: internal error: ", stderr);
  else if (loc.line > 0) fprintf(stderr, "%s:%d:%d: error: ", diag_file, loc.line, loc.col);
  else fputs("hbvmgen: error: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  if (!internal) show_line(loc);
  fflush(stderr);
  if (internal) abort();
  exit(1);
}

void fatal_at(Loc loc, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  die(0, loc, fmt, ap);
  va_end(ap);
}

void out_of_memory(void) { fatal_at((Loc){0, 0}, "out of memory (model too large)"); }

void internal_error(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  die(1, (Loc){0, 0}, fmt, ap);
  va_end(ap);
}

/* ---- diagnostics ---- */

#define MAX_ERRORS 20
#define MAX_LIKE 20        /* warnings of one kind printed; the rest counted */
#define MAX_KINDS 64
#define MAX_SHOWN_LINE 160

static const char *diag_src;
static size_t diag_len;
static int nerrors;
static size_t *line_start; /* line_start[i]: offset of line i+1, once indexed (arena) */
static int nlines;
static long scanned;       /* bytes looked at to index lines (tests: linear) */
static struct {
  const char *fmt;         /* a kind of warning is its message's format */
  long count;
  char last[128];          /* the last one printed */
} kinds[MAX_KINDS];
static int nkinds;

void diag_begin(const char *file, const char *src, size_t len) {
  diag_file = file;
  diag_src = src;
  diag_len = len;
  nerrors = 0;
  forget_lines();
  nkinds = 0;
}

static void forget_lines(void) {
  line_start = NULL;
  nlines = 0;
}

int diag_error_count(void) { return nerrors; }
int diag_too_many(void) { return nerrors >= MAX_ERRORS; }
long diag_scanned(void) { return scanned; }

// Index the starts of the source's lines, once: a line ends at LF, CRLF or CR.
static void index_lines(void) {
  long cap = 1;
  for (size_t i = 0; i < diag_len; i++) cap += diag_src[i] == '\n' || diag_src[i] == '\r';
  scanned += (long)diag_len;
  line_start = arena_alloc((size_t)cap * sizeof *line_start);
  line_start[nlines++] = 0;
  for (size_t i = 0; i < diag_len; i++) {
    scanned++;
    if (diag_src[i] == '\r' && i + 1 < diag_len && diag_src[i + 1] == '\n') continue;
    if (diag_src[i] == '\n' || diag_src[i] == '\r') line_start[nlines++] = i + 1;
  }
}

// Print the source line of loc with a caret under its column. Long lines
// are shown as a window around the column; unprintable bytes as '?'.
static void show_line(Loc loc) {
  if (!diag_src || loc.line <= 0) return;
  if (!line_start) index_lines();
  if (loc.line > nlines) return;
  size_t pos = line_start[loc.line - 1], end = pos;
  while (end < diag_len && diag_src[end] != '\n' && diag_src[end] != '\r') end++;
  size_t col = loc.col > 0 ? (size_t)loc.col - 1 : 0;
  size_t from = 0;
  if (col > MAX_SHOWN_LINE / 2) from = col - MAX_SHOWN_LINE / 2;
  size_t to = end - pos;
  if (to > from + MAX_SHOWN_LINE) to = from + MAX_SHOWN_LINE;
  if (from > to || (from == to && col == 0)) return; /* no text to show */
  fputs("    ", stderr);
  for (size_t i = from; i < to; i++) {
    unsigned char ch = (unsigned char)diag_src[pos + i];
    fputc(ch == '\t' || (ch >= 32 && ch < 127) ? ch : '?', stderr);
  }
  fputs("\n    ", stderr);
  for (size_t i = from; i < col && i < to; i++) fputc(diag_src[pos + i] == '\t' ? '\t' : ' ', stderr);
  fputs("^\n", stderr);
}

static void report(const char *kind, Loc loc, const char *fmt, va_list ap) {
  if (loc.line > 0)
    fprintf(stderr, "%s:%d:%d: %s: ", diag_file, loc.line, loc.col, kind);
  else
    fprintf(stderr, "%s: %s: ", diag_file, kind);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  show_line(loc);
}

// Report an error at loc. After MAX_ERRORS, one last line says the rest were
// suppressed, and further errors are counted but not printed.
void error_at(Loc loc, const char *fmt, ...) {
  va_list ap;
  nerrors++;
  if (nerrors > MAX_ERRORS) return;
  va_start(ap, fmt);
  report("error", loc, fmt, ap);
  va_end(ap);
  if (nerrors == MAX_ERRORS) fprintf(stderr, "%s: note: too many errors, stopping\n", diag_file);
}

// Say where the error just reported arose (a call of a function of 'def'),
// unless that error was not shown.
void note_at(Loc loc, const char *fmt, ...) {
  va_list ap;
  if (nerrors >= MAX_ERRORS) return;
  va_start(ap, fmt);
  report("note", loc, fmt, ap);
  va_end(ap);
}

// Report a warning at loc; beyond MAX_LIKE of one kind (one format), only count it.
void warning_at(Loc loc, const char *fmt, ...) {
  va_list ap;
  int k = 0;
  while (k < nkinds && kinds[k].fmt != fmt) k++;
  if (k == nkinds && nkinds < MAX_KINDS) {
    kinds[k].fmt = fmt;
    kinds[k].count = 0;
    nkinds++;
  }
  if (k < nkinds && ++kinds[k].count > MAX_LIKE) return;
  va_start(ap, fmt);
  report("warning", loc, fmt, ap);
  va_end(ap);
  if (k < nkinds) {
    va_start(ap, fmt);
    vsnprintf(kinds[k].last, sizeof kinds[k].last, fmt, ap);
    va_end(ap);
  }
}

// Say how many warnings of each kind were counted but not printed.
void diag_end(void) {
  for (int k = 0; k < nkinds; k++)
    if (kinds[k].count > MAX_LIKE)
      fprintf(stderr, "%s: note: %ld more warnings like \"%s\" were not shown\n", diag_file,
              kinds[k].count - MAX_LIKE, kinds[k].last);
  nkinds = 0;
}
