/* SPDX-License-Identifier: MIT */
/* jets_tip.c — the jet's leading-mass fronts and its clusters (jets_tip.h). */
#include "jets_tip.h"

#include <math.h>
#include <stdlib.h>

const double jets_tip_frac[JETS_TIP_NFRAC] = {0.01, 0.1, 0.5};
const double jets_tip_link = 1.5;

struct jets_tip {
  size_t cap;         /* valley-half particles: the most the jet can hold */
  size_t *idx;        /* the jet's particles, sorted by x descending */
  long *parent, *cnt; /* union–find over positions in idx */
  double m_groove, h;
};

jets_tip *jets_tip_create(const ptl_state *ps, const uint8_t *role, double m_groove, double h) {
  jets_tip *t = calloc(1, sizeof *t);
  if (!t) return NULL;
  for (size_t i = 0; i < ps->n; i++) t->cap += role[i] & 1;
  t->idx = malloc((t->cap + 1) * sizeof *t->idx);
  t->parent = malloc((t->cap + 1) * sizeof *t->parent);
  t->cnt = malloc((t->cap + 1) * sizeof *t->cnt);
  t->m_groove = m_groove, t->h = h;
  if (!t->idx || !t->parent || !t->cnt) jets_tip_destroy(&t);
  return t;
}

void jets_tip_destroy(jets_tip **t) {
  if (!*t) return;
  free((*t)->idx), free((*t)->parent), free((*t)->cnt), free(*t);
  *t = NULL;
}

static const double *sort_x; /* qsort has no context argument in C11 */
static int by_x_desc(const void *a, const void *b) {
  const double xa = sort_x[*(const size_t *)a], xb = sort_x[*(const size_t *)b];
  return (xa < xb) - (xa > xb);
}

static long find(long *parent, long a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}

/* Clusters of the sorted jet: pairs within link·h, scanning forward in x only as far as link·h. */
static void clusters(jets_tip *t, const ptl_state *ps, long n, jets_tip_sample *out) {
  const double L = jets_tip_link * t->h, L2 = L * L;
  for (long a = 0; a < n; a++) t->parent[a] = a, t->cnt[a] = 0;
  for (long a = 0; a < n; a++) {
    const size_t i = t->idx[a];
    for (long b = a + 1; b < n && ps->x[i] - ps->x[t->idx[b]] <= L; b++) {
      const size_t k = t->idx[b];
      const double dx = ps->x[i] - ps->x[k], dy = ps->y[i] - ps->y[k];
      if (dx * dx + dy * dy > L2) continue;
      const long ra = find(t->parent, a), rb = find(t->parent, b);
      if (ra != rb) t->parent[ra > rb ? ra : rb] = ra < rb ? ra : rb;
    }
  }
  long big = 0;
  out->n_clusters = 0;
  for (long a = 0; a < n; a++) {
    const long r = find(t->parent, a);
    out->n_clusters += r == a;
    if (++t->cnt[r] > t->cnt[big]) big = r;
  }
  out->tip_cluster = t->cnt[find(t->parent, 0)];
  long a = 0; /* the first (foremost) member of the largest cluster */
  while (find(t->parent, a) != big) a++;
  out->n_ahead = a;
  out->x_main = ps->x[t->idx[a]], out->v_main = ps->vx[t->idx[a]];
}

void jets_tip_measure(jets_tip *t, const ptl_state *ps, const uint8_t *role, double x_fs,
                      double lambda, jets_tip_sample *out) {
  /* the candidates for the leading masses reach λ/4 behind the surface: the valley half holds
   * λ²/8 there, ≫ the largest leading mass 0.5 h0 λ = (k h0/4π) λ² at k h0 ≤ 1.5 */
  const double x_lo = x_fs - 0.25 * lambda;
  long n = 0, nj = 0;
  double m = 0;
  for (size_t i = 0; i < ps->n; i++)
    if ((role[i] & 1) && ps->x[i] > x_lo) {
      t->idx[n++] = i;
      if (ps->x[i] > x_fs) m += ps->mass[i], nj++;
    }
  out->n_jet = nj, out->m_jet = m / t->m_groove;
  for (int j = 0; j < JETS_TIP_NFRAC; j++) out->x_m[j] = out->v_m[j] = NAN;
  out->x_main = out->v_main = NAN;
  out->n_clusters = out->n_ahead = out->tip_cluster = 0;
  if (n == 0) return;
  sort_x = ps->x;
  qsort(t->idx, (size_t)n, sizeof *t->idx, by_x_desc);
  double cm = 0, cmv = 0;
  int j = 0;
  for (long a = 0; a < n && j < JETS_TIP_NFRAC; a++) {
    const size_t i = t->idx[a];
    cm += ps->mass[i], cmv += ps->mass[i] * ps->vx[i];
    while (j < JETS_TIP_NFRAC && cm >= jets_tip_frac[j] * t->m_groove - 1e-9 * ps->mass[i]) {
      out->x_m[j] = ps->x[i], out->v_m[j] = cmv / cm;
      j++;
    }
  }
  if (nj > 0) clusters(t, ps, nj, out); /* the jet: the first nj of the sorted candidates */
}
