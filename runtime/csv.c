/* csv.c - the driver's CSV output.
 *
 * Header  t,x,y,p_x,p_y,lambda_1,H,g_1,hc_1: the model's coordinate names
 * (an array element as x[3]), p_ and the name for its momentum, then
 * lambda_a, H, g_a, hc_a for a = 1..nu (absent when nu = 0).  A model
 * description without names (md->names NULL: drivers from hbvmgen 0.1)
 * keeps the old header t,q1..qm,p1..pm,lam1..lamnu,H,g1..gnu,hc1..hcnu.
 * Then one row per written step with every value printed "%.17g", so a row
 * reads back to the same doubles.  Errors are
 * not reported here: the functions return -1 once the stream is in error and
 * the caller says what failed. */
#define _POSIX_C_SOURCE 200809L   /* SIGXFSZ */

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "hbvmrt_internal.h"

/* ",Xn" for n = 1..count */
static void names(FILE *f, const char *prefix, int count)
{
  int i;

  for (i = 1; i <= count; i++)
    fprintf(f, ",%s%d", prefix, i);
}

static void values(FILE *f, const double *v, int count)
{
  int i;

  for (i = 0; i < count; i++)
    fprintf(f, ",%.17g", v[i]);
}

/* the doubles at byte offset off of the state */
static const double *at(const void *x, size_t off)
{
  return (const double *)(const void *)((const char *)x + off);
}

/* ",PREFIXname" for each coordinate name, or ",PREFIXn" n = 1..m without names */
static void coords(FILE *f, const char *prefix, const hbvmrt_model *md)
{
  int i;

  if (!md->names) {
    names(f, prefix, md->m);
    return;
  }
  for (i = 0; i < md->m; i++)
    fprintf(f, ",%s%s", prefix, md->names[i]);
}

int hbvmrt_csv_header(FILE *f, const hbvmrt_model *md)
{
  /* prefixes of the q, p, lambda, g and hc columns: with names, numbered */
  static const char *const named[] = {"", "p_", "lambda_", "g_", "hc_"};
  static const char *const numbered[] = {"q", "p", "lam", "g", "hc"};
  const char *const *pre = md->names ? named : numbered;

  fputc('t', f);
  coords(f, pre[0], md);
  coords(f, pre[1], md);
  names(f, pre[2], md->nu);
  fputs(",H", f);
  names(f, pre[3], md->nu);
  names(f, pre[4], md->nu);
  fputc('\n', f);
  return ferror(f) ? -1 : 0;
}

/* One row for state x, with its energy H, constraints g and hidden
 * constraints hc (nu values each) computed by the caller. */
int hbvmrt_csv_row(FILE *f, const hbvmrt_model *md, const void *x, double H,
                   const double *g, const double *hc)
{
  fprintf(f, "%.17g", *at(x, md->off_t));
  values(f, at(x, md->off_q), md->m);
  values(f, at(x, md->off_p), md->m);
  values(f, at(x, md->off_lambda), md->nu);
  values(f, &H, 1);
  values(f, g, md->nu);
  values(f, hc, md->nu);
  fputc('\n', f);
  return ferror(f) ? -1 : 0;
}

/* The events CSV: event,t,x..,p_x.. (q1.., p1.. without names). */
int hbvmrt_csv_event_header(FILE *f, const hbvmrt_model *md)
{
  fputs("event,t", f);
  coords(f, md->names ? "" : "q", md);
  coords(f, md->names ? "p_" : "p", md);
  fputc('\n', f);
  return ferror(f) ? -1 : 0;
}

/* One event's row: its name, the time and q, p of the state x at it. */
int hbvmrt_csv_event_row(FILE *f, const hbvmrt_model *md, const char *name, const void *x)
{
  fprintf(f, "%s,%.17g", name, *at(x, md->off_t));
  values(f, at(x, md->off_q), md->m);
  values(f, at(x, md->off_p), md->m);
  fputc('\n', f);
  return ferror(f) ? -1 : 0;
}

/* An output file of the driver: path, or stdout for "-"; NULL (errno set)
 * when it cannot be opened. A write past the file size limit (ulimit -f)
 * then fails with EFBIG, reported as a full disk is, instead of the
 * SIGXFSZ that killed the process without a word. */
FILE *hbvmrt_out_open(const char *path)
{
#ifdef SIGXFSZ
  signal(SIGXFSZ, SIG_IGN);
#endif
  return strcmp(path, "-") == 0 ? stdout : fopen(path, "w");
}

/* Close it (stdout: flush); err, the errno of an earlier failed write or 0,
 * is kept, else that of the close. Returns the errno of the failure, or 0. */
int hbvmrt_out_close(FILE *f, int err)
{
  errno = 0;
  if (f == stdout ? fflush(stdout) != 0 || ferror(stdout) : fclose(f) != 0)
    err = err ? err : errno ? errno : EIO;
  return err;
}
