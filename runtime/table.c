/* table.c - a CSV table of numbers read from a file (--ensemble FILE).
 *
 * The file is a header of column names and then one row of finite numbers
 * per line, separated by commas, blanks (spaces, tabs) around them allowed.
 * Lines end with \n, \r\n or a lone \r (old Mac files; they once read as a
 * single line, every row dropped); blank lines and lines starting with #
 * are skipped; a UTF-8 byte order mark at the start is skipped. Anything
 * else is an error naming the file, the line and the column (bytes from 1):
 * a NUL byte, an empty or repeated column name, a field that is not a finite
 * number, a row with too few or too many fields, a header without rows (no
 * trajectories), or more rows than asked for. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmrt_internal.h"

/* The whole file into a buffer of *len bytes (one more: a NUL); NULL after
 * reporting. */
static char *slurp(const hbvmrt_model *md, const char *path, size_t *len)
{
  FILE *f = fopen(path, "rb");
  size_t cap = 4096, n;
  char *buf = NULL, *more;

  *len = 0;
  if (!f) {
    hbvmrt_error(md, "cannot open '%s': %s", path, strerror(errno));
    return NULL;
  }
  for (;;) {
    if (!(more = realloc(buf, cap + 1))) {
      hbvmrt_error(md, "out of memory reading '%s'", path);
      break;
    }
    buf = more;
    n = fread(buf + *len, 1, cap - *len, f);
    *len += n;
    if (*len < cap)
      break;
    cap *= 2;
  }
  if (more && ferror(f)) {
    hbvmrt_error(md, "cannot read '%s': %s", path, strerror(errno ? errno : EIO));
    more = NULL;
  }
  fclose(f);
  if (!more) {
    free(buf);
    return NULL;
  }
  buf[*len] = '\0';
  return buf;
}

/* "NAME: error: PATH:LINE:COL: message" on stderr. */
static void table_error(const hbvmrt_model *md, const char *path, long line, long col, const char *fmt, ...)
  HBVMRT_PRINTF(5, 6);

static void table_error(const hbvmrt_model *md, const char *path, long line, long col, const char *fmt, ...)
{
  va_list ap;

  fprintf(stderr, "%s: error: %s:%ld:%ld: ", md->name, path, line, col);
  va_start(ap, fmt);
  vfprintf(stderr, fmt, ap);
  va_end(ap);
  fputc('\n', stderr);
}

static int blank(char c)
{
  return c == ' ' || c == '\t';
}

/* The header line s (NUL-terminated, line number ln) into tb's names. */
static int read_header(const hbvmrt_model *md, const char *path, long ln, char *s, hbvmrt_table *tb)
{
  int n = 1, c, k;
  char *p;

  for (p = s; *p; p++)
    n += *p == ',';
  tb->ncol = n;
  tb->names = calloc((size_t)n, sizeof *tb->names);
  tb->name_col = calloc((size_t)n, sizeof *tb->name_col);
  if (!tb->names || !tb->name_col) {
    hbvmrt_error(md, "out of memory");
    return -1;
  }
  for (c = 0, p = s; c < n; c++) {
    char *end = p + strcspn(p, ","), *b = p, *e = end, *next = *end ? end + 1 : end;
    while (blank(*b))
      b++;
    while (e > b && blank(e[-1]))
      e--;
    tb->name_col[c] = (int)(b - s) + 1;
    if (e == b) {
      table_error(md, path, ln, (long)(b - s) + 1, "column %d has no name", c + 1);
      return -1;
    }
    *e = '\0';
    tb->names[c] = b;
    for (k = 0; k < c; k++)
      if (!strcmp(tb->names[k], b)) {
        table_error(md, path, ln, (long)(b - s) + 1, "column '%s' given twice (first at column %d)", b, tb->name_col[k]);
        return -1;
      }
    p = next;
  }
  return 0;
}

/* One row s (line ln) into row r of tb's values, room for it already made. */
static int read_row(const hbvmrt_model *md, const char *path, long ln, const char *s, hbvmrt_table *tb, long r)
{
  const char *p = s;
  int c;

  for (c = 0; c < tb->ncol; c++) {
    char *end;
    double v;
    while (blank(*p))
      p++;
    if (*p == '\0') {
      table_error(md, path, ln, (long)(p - s) + 1, "expected %d numbers, got %d", tb->ncol, c);
      return -1;
    }
    v = strtod(p, &end);
    if (end == p || !isfinite(v) || (*end && *end != ',' && !blank(*end))) {
      size_t len = strcspn(p, ",");
      while (len > 0 && blank(p[len - 1]))
        len--;
      if (len == 0)
        table_error(md, path, ln, (long)(p - s) + 1, "an empty field (expected %d numbers)", tb->ncol);
      else
        table_error(md, path, ln, (long)(p - s) + 1, "'%.*s' is not a finite number", (int)len, p);
      return -1;
    }
    for (p = end; blank(*p); p++)
      ;
    if (c + 1 < tb->ncol && *p != ',') {
      if (*p)
        table_error(md, path, ln, (long)(p - s) + 1, "expected a comma");
      else
        table_error(md, path, ln, (long)(p - s) + 1, "expected %d numbers, got %d", tb->ncol, c + 1);
      return -1;
    }
    if (c + 1 == tb->ncol && *p) {
      table_error(md, path, ln, (long)(p - s) + 1, "expected %d numbers, got more", tb->ncol);
      return -1;
    }
    tb->val[r * tb->ncol + c] = v;
    p += *p == ',';
  }
  return 0;
}

int hbvmrt_table_read(const hbvmrt_model *md, const char *path, long max_rows, hbvmrt_table *tb)
{
  size_t len;
  char *p, *end;
  long ln = 0, rcap = 0;

  memset(tb, 0, sizeof *tb);
  if (!(tb->text = slurp(md, path, &len)))
    return -1;
  p = tb->text;
  end = p + len;
  if (len >= 3 && !memcmp(p, "\xEF\xBB\xBF", 3))
    p += 3;
  while (p < end) {
    char *eol = p + strcspn(p, "\r\n");
    ln++;
    if (eol < end && *eol == '\0') {   /* strcspn stopped at a NUL inside the file */
      table_error(md, path, ln, (long)(eol - p) + 1, "a NUL byte");
      return -1;
    }
    if (*eol == '\r' && eol[1] == '\n')
      *eol++ = '\0';
    *eol = '\0';
    if (p[strspn(p, " \t")] == '\0' || *p == '#') {
      p = eol + 1;
      continue;
    }
    if (!tb->names) {
      if (read_header(md, path, ln, p, tb) != 0)
        return -1;
      tb->header_line = ln;
    } else {
      if (tb->nrow >= max_rows) {
        table_error(md, path, ln, 1, "more than %ld trajectories", max_rows);
        return -1;
      }
      if (tb->nrow == rcap) {
        double *v;
        rcap = rcap ? 2 * rcap : 64;
        if (!(v = realloc(tb->val, (size_t)rcap * (size_t)tb->ncol * sizeof *v))) {
          hbvmrt_error(md, "out of memory");
          return -1;
        }
        tb->val = v;
      }
      if (read_row(md, path, ln, p, tb, tb->nrow) != 0)
        return -1;
      tb->nrow++;
    }
    p = eol + 1;
  }
  if (!tb->names) {
    hbvmrt_error(md, "%s: no header line (column names)", path);
    return -1;
  }
  if (tb->nrow == 0) {
    hbvmrt_error(md, "%s: no trajectories: the header (line %ld) and no rows", path, tb->header_line);
    return -1;
  }
  return 0;
}

void hbvmrt_table_free(hbvmrt_table *tb)
{
  free(tb->text);
  free(tb->names);
  free(tb->name_col);
  free(tb->val);
  memset(tb, 0, sizeof *tb);
}
