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
#include <stdio.h>

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

/* ",PREFIXname" for each of the m coordinate names */
static void coords(FILE *f, const char *prefix, const char *const *name, int m)
{
  int i;

  for (i = 0; i < m; i++)
    fprintf(f, ",%s%s", prefix, name[i]);
}

int hbvmrt_csv_header(FILE *f, const hbvmrt_model *md)
{
  fputc('t', f);
  if (md->names) {
    coords(f, "", md->names, md->m);
    coords(f, "p_", md->names, md->m);
    names(f, "lambda_", md->nu);
    fputs(",H", f);
    names(f, "g_", md->nu);
    names(f, "hc_", md->nu);
    fputc('\n', f);
    return ferror(f) ? -1 : 0;
  }
  names(f, "q", md->m);
  names(f, "p", md->m);
  names(f, "lam", md->nu);
  fputs(",H", f);
  names(f, "g", md->nu);
  names(f, "hc", md->nu);
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
