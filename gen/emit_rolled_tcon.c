/* emit_rolled_tcon.c - the loops over the coordinates that visit the
 * constraints on each (the table tcon of roll.c), printed without the table.
 *
 * The loops that assemble the multiplier system and spread the multipliers
 * back (emit_rolled.c) visit, for each coordinate i, the T constraints
 * tcon[T i + t] on it. On a model uniform in its index these are affine in
 * i over long stretches (the chain's x_i carries the links i and i + 1, but
 * its last coordinate only link i): the coordinates are cut into segments on
 * which each constraint slot t is absent or a = i + offset, and the loop is
 * printed once per segment, with the offsets and the absent slots known at
 * generation time. The loop body then has no table load and no branch per
 * constraint; it visits the same i and a in the same order as the table
 * loop, so its sums are the same, bit for bit. A model with more than
 * ROLL_MAX_RUNS segments keeps the table loop (one segment whose slots all
 * read the table). */
#include <stdio.h>
#include <stdlib.h>

#include "emit.h"
#include "roll.h"

// Whether coordinate i's slots match those of segment s (offsets from i).
static int seg_matches(const Roll *r, const TconSeg *s, int i) {
  for (int t = 0; t < r->T; t++) {
    int a = r->tcon[r->T * i + t];
    if (a < 0 ? s->off[t] != TCON_ABSENT : s->off[t] != a - i) return 0;
  }
  return 1;
}

// The segments of the coordinates 0..m-1 (see above), *n of them.
TconSeg *rolled_tcon_segments(const Roll *r, int *n) {
  int T = r->T, m = r->m;
  TconSeg *s = xmalloc((size_t)(m > 0 ? m : 1) * sizeof *s);
  int *off = xmalloc((size_t)(m * T > 0 ? m * T : 1) * sizeof *off);
  *n = 0;
  for (int i = 0; i < m; (*n)++) {
    TconSeg *g = &s[*n];
    g->i0 = i;
    g->off = off + *n * T;
    for (int t = 0; t < T; t++) g->off[t] = r->tcon[T * i + t] < 0 ? TCON_ABSENT : r->tcon[T * i + t] - i;
    while (i < m && seg_matches(r, g, i)) i++;
    g->i1 = i;
  }
  if (*n > ROLL_MAX_RUNS) { /* not uniform: the table, one loop */
    *n = 1;
    s[0].i1 = m;
    for (int t = 0; t < T; t++) s[0].off[t] = TCON_TABLE;
  }
  return s;
}

void rolled_tcon_free(TconSeg *s) {
  if (!s) return;
  free(s[0].off);
  free(s);
}

// The loop over a segment's coordinates i and the locals a0.. of its
// present slots (with pad, a table slot's absent constraint reads nu, where
// the caller keeps a 0).
void rolled_tcon_open(Emitter *e, const TconSeg *s, int pad) {
  int T = e->roll->T;
  if (s->i1 - s->i0 == 1) out(e, "  { /* coordinate %d */\n    const int i = %d;\n", s->i0, s->i0);
  else out(e, "  for (i = %d; i < %d; i++) { /* coordinates %d..%d */\n", s->i0, s->i1, s->i0, s->i1 - 1);
  for (int t = 0; t < T; t++) {
    int o = s->off[t];
    if (o == TCON_TABLE && pad)
      out(e, "    const int a%d = %s_tcon[%d * i + %d] < 0 ? %d : %s_tcon[%d * i + %d];\n", t, e->P, T, t, e->mod->nu, e->P, T, t);
    else if (o == TCON_TABLE) out(e, "    const int a%d = %s_tcon[%d * i + %d];\n", t, e->P, T, t);
    else if (o != TCON_ABSENT) out(e, o ? "    const int a%d = i %c %d;\n" : "    const int a%d = i;\n", t, o < 0 ? '-' : '+', abs(o));
  }
}

// The guard of slot t's code inside a segment: "" (present), the run-time
// test of a table slot (in a buffer valid until the next call), or NULL
// (absent: print nothing).
const char *rolled_tcon_guard(const TconSeg *s, int t) {
  static char buf[32];
  if (s->off[t] == TCON_ABSENT) return NULL;
  if (s->off[t] != TCON_TABLE) return "";
  snprintf(buf, sizeof buf, "if (a%d >= 0) ", t);
  return buf;
}
