/* util.c - the arena every pass allocates from, growable arrays, and
 * GCC-style diagnostics: "file:line:col: error: message", then the source
 * line and a caret under the column. */
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
    if (arena_total + bsize > ARENA_LIMIT || !(b = malloc(sizeof(Block) + bsize))) {
      fprintf(stderr, "hbvmgen: error: out of memory (model too large)\n");
      exit(1);
    }
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

char *arena_strndup(const char *s, size_t n) {
  char *p = arena_alloc(n + 1);
  memcpy(p, s, n);
  return p;
}

void arena_free_all(void) {
  while (arena_head) {
    Block *next = arena_head->next;
    free(arena_head);
    arena_head = next;
  }
  arena_total = 0;
}

// Append to an arena-backed vector, doubling its capacity when full.
void intvec_push(IntVec *vec, int x) {
  if (vec->n == vec->cap) {
    int cap = vec->cap ? 2 * vec->cap : 16;
    int *v = arena_alloc((size_t)cap * sizeof(int));
    if (vec->n) memcpy(v, vec->v, (size_t)vec->n * sizeof(int));
    vec->v = v;
    vec->cap = cap;
  }
  vec->v[vec->n++] = x;
}

/* ---- diagnostics ---- */

#define MAX_ERRORS 20
#define MAX_SHOWN_LINE 160

static const char *diag_file = "<input>";
static const char *diag_src;
static size_t diag_len;
static int nerrors;

void diag_begin(const char *file, const char *src, size_t len) {
  diag_file = file;
  diag_src = src;
  diag_len = len;
  nerrors = 0;
}

int diag_error_count(void) { return nerrors; }
int diag_too_many(void) { return nerrors >= MAX_ERRORS; }

// Print the source line of loc with a caret under its column. Long lines
// are shown as a window around the column; unprintable bytes as '?'.
static void show_line(Loc loc) {
  if (!diag_src || loc.line <= 0) return;
  size_t pos = 0;
  for (int line = 1; line < loc.line && pos < diag_len; pos++)
    if (diag_src[pos] == '\n') line++;
  size_t end = pos;
  while (end < diag_len && diag_src[end] != '\n') end++;
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

void warning_at(Loc loc, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  report("warning", loc, fmt, ap);
  va_end(ap);
}

void internal_error(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("hbvmgen: internal error: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
  abort();
}
