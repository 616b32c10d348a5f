/* restart.c - --restart FILE[:ROW]: a run's initial state from a row of the
 * CSV the driver wrote (--csv), checkpoint and restart (docs/api.md, "The
 * standalone driver").
 *
 * The file is read as a table (table.c: the header names the columns; every
 * field a finite number); the row's t, its coordinates (the header's names,
 * or q1.. in the numbered header of older drivers) and their momenta (p_x,
 * or p1..) become --t0, --q0 and --p0. The other columns (lambda, H, g, hc)
 * are not read: the step recomputes them. The compensation of the sums and
 * the warm start are not in the CSV, so a restarted run continues within
 * the round-off of one step of the run it continues, not bitwise. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hbvmrt_internal.h"

/* The column of tb named name, or -1. */
static int column(const hbvmrt_table *tb, const char *name)
{
  int c;

  for (c = 0; c < tb->ncol; c++)
    if (!strcmp(tb->names[c], name))
      return c;
  return -1;
}

/* The column of coordinate i's position (mom 0) or momentum (mom 1): x and
 * p_x, or q1 and p1 for a driver without names; -1 after reporting. */
static int coordinate_column(const hbvmrt_model *md, const hbvmrt_table *tb, const char *path, int i, int mom)
{
  char name[96];
  int c;

  if (md->names)
    snprintf(name, sizeof name, "%s%s", mom ? "p_" : "", md->names[i]);
  else
    snprintf(name, sizeof name, "%s%d", mom ? "p" : "q", i + 1);
  if ((c = column(tb, name)) < 0)
    hbvmrt_error(md, "--restart: '%s' has no column '%s' (a CSV of this driver's --csv has one)", path, name);
  return c;
}

/* FILE[:ROW] split: the path (malloc'd) and the row, 0 for the last; the
 * last ':' starts ROW only when digits follow it, so a path may hold ':'. */
static char *split(const char *val, long *row)
{
  const char *colon = strrchr(val, ':');
  size_t len = strlen(val);
  char *path;

  *row = 0;
  if (colon && colon[1] && strspn(colon + 1, "0123456789") == strlen(colon + 1)) {
    *row = strtol(colon + 1, NULL, 10);
    len = (size_t)(colon - val);
    if (*row < 1)
      *row = -1;
  }
  if ((path = malloc(len + 1))) {
    memcpy(path, val, len);
    path[len] = '\0';
  }
  return path;
}

int hbvmrt_restart(const hbvmrt_model *md, const char *val, hbvmrt_opts *o)
{
  hbvmrt_table tb;
  long row;
  char *path = split(val, &row);
  int i, c, ct, rc = -1;

  if (!path) {
    hbvmrt_error(md, "out of memory");
    return -1;
  }
  if (row < 0) {
    hbvmrt_error(md, "--restart: ROW must be >= 1 (got '%s')", val);
    free(path);
    return -1;
  }
  if (hbvmrt_table_read(md, path, HBVMRT_MAX_ROWS, &tb) != 0)
    goto out;
  if (row > tb.nrow) {
    hbvmrt_error(md, "--restart: '%s' has %ld rows, not %ld", path, tb.nrow, row);
    goto out;
  }
  if (row == 0)
    row = tb.nrow;
  if ((ct = column(&tb, "t")) < 0) {
    hbvmrt_error(md, "--restart: '%s' has no column 't' (a CSV of this driver's --csv has one)", path);
    goto out;
  }
  if ((!o->q0 && !(o->q0 = calloc((size_t)md->m + 1, sizeof *o->q0))) ||
      (!o->p0 && !(o->p0 = calloc((size_t)md->m + 1, sizeof *o->p0)))) {
    hbvmrt_error(md, "out of memory");
    goto out;
  }
  for (i = 0; i < md->m; i++) {
    if ((c = coordinate_column(md, &tb, path, i, 0)) < 0)
      goto out;
    o->q0[i] = tb.val[(row - 1) * tb.ncol + c];
    if ((c = coordinate_column(md, &tb, path, i, 1)) < 0)
      goto out;
    o->p0[i] = tb.val[(row - 1) * tb.ncol + c];
  }
  o->t0 = tb.val[(row - 1) * tb.ncol + ct];
  rc = 0;
out:
  hbvmrt_table_free(&tb);
  free(path);
  return rc;
}
