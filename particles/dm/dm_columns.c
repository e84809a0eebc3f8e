/* SPDX-License-Identifier: MIT */
/* dm_columns.c — the discrete model region's piston by columns (dm_columns.h; docs/coupling.md
 * "Driving particles from a 2D node line"): per-column velocity histories on one time base,
 * their running integrals, and the driven particles' interpolation weights. */
#include "dm_columns.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The histories as nh = ncomp · ncol series on one time base: series j < ncol is column j's
 * velocity along the region's x, series ncol + j (ncomp = 2) its velocity along y. */
struct dm_columns {
  size_t ncol, ncomp, nh, n, k; /* columns, components, series, samples, cursor */
  double *y, *t, *u;            /* ncol; n; n × nh */
  double *cum;          /* n × nh: ∫ u from t[0] to t[k] (trapezoid: exact, u is linear) */
  double *mean;         /* nh: each series' mean over the step being driven */
  size_t np, *idx, *lo; /* prescribed particles: index, left column */
  double *w;            /* weight of column lo + 1 */
};

void dm_columns_destroy(dm_columns **pc) {
  if (!pc || !*pc) return;
  dm_columns *c = *pc;
  free(c->y), free(c->t), free(c->u), free(c->cum), free(c->mean);
  free(c->idx), free(c->lo), free(c->w);
  free(c);
  *pc = NULL;
}

static bool arrays_ok(size_t ncol, const double *ycol, size_t n, const double *t, const double *ux,
                      const double *uy) {
  if (!ncol || !n || !ycol || !t || !ux) return false;
  for (size_t c = 0; c < ncol; c++)
    if (!isfinite(ycol[c]) || (c && !(ycol[c] > ycol[c - 1]))) return false;
  for (size_t k = 0; k < n; k++)
    if (!isfinite(t[k]) || (k && !(t[k] > t[k - 1]))) return false;
  for (size_t k = 0; k < n * ncol; k++)
    if (!isfinite(ux[k]) || (uy && !isfinite(uy[k]))) return false;
  return true;
}

ms_status dm_columns_create(size_t ncol, const double *ycol, size_t n, const double *t,
                            const double *ux, const double *uy, const dm_state *s,
                            dm_columns **out) {
  *out = NULL;
  if (!arrays_ok(ncol, ycol, n, t, ux, uy)) return MS_ERR_INPUT;
  dm_columns *c = ms_calloc(1, sizeof *c);
  const size_t nh = (uy ? 2 : 1) * ncol;
  c->ncol = ncol, c->ncomp = uy ? 2 : 1, c->nh = nh, c->n = n;
  c->y = ms_calloc(ncol, sizeof *c->y), c->mean = ms_calloc(nh, sizeof *c->mean);
  c->t = ms_calloc(n, sizeof *c->t);
  c->u = ms_calloc(n * nh, sizeof *c->u), c->cum = ms_calloc(n * nh, sizeof *c->cum);
  memcpy(c->y, ycol, ncol * sizeof *ycol);
  memcpy(c->t, t, n * sizeof *t);
  for (size_t k = 0; k < n; k++) {
    memcpy(&c->u[k * nh], &ux[k * ncol], ncol * sizeof *ux);
    if (uy) memcpy(&c->u[k * nh + ncol], &uy[k * ncol], ncol * sizeof *uy);
  }
  const double *u = c->u;
  for (size_t k = 1; k < n; k++)
    for (size_t j = 0; j < nh; j++)
      c->cum[k * nh + j] = c->cum[(k - 1) * nh + j] +
                           0.5 * (u[k * nh + j] + u[(k - 1) * nh + j]) * (t[k] - t[k - 1]);
  for (size_t i = 0; i < s->n; i++) c->np += s->bc[i] == DM_PRESCRIBED;
  c->idx = ms_calloc(c->np + 1, sizeof *c->idx), c->lo = ms_calloc(c->np + 1, sizeof *c->lo);
  c->w = ms_calloc(c->np + 1, sizeof *c->w);
  size_t q = 0;
  for (size_t i = 0; i < s->n; i++) {
    if (s->bc[i] != DM_PRESCRIBED) continue;
    const double y = s->X[3 * i + 1];
    size_t lo = 0; /* ycol[lo] ≤ y < ycol[lo + 1] (binary search), clamped at the ends */
    size_t hi = ncol - 1;
    while (hi - lo > 1) {
      const size_t mid = (lo + hi) / 2;
      if (ycol[mid] <= y) lo = mid;
      else hi = mid;
    }
    double w = 0.0;
    if (ncol > 1) w = fmin(1.0, fmax(0.0, (y - ycol[lo]) / (ycol[lo + 1] - ycol[lo])));
    c->idx[q] = i, c->lo[q] = lo, c->w[q] = w, q++;
  }
  *out = c;
  return MS_OK;
}

/* sign · ∫ u_j from t[0] to time (u constant beyond the ends) added to mean[j] for every
 * series: the segment is found once (the cursor makes increasing times O(1)). */
static void antiderivative(dm_columns *c, double time, double sign) {
  const size_t nc = c->nh, last = c->n - 1;
  const double *t = c->t, *u = c->u, *cum = c->cum;
  if (c->n == 1 || time <= t[0]) {
    for (size_t j = 0; j < nc; j++) c->mean[j] += sign * u[j] * (time - t[0]);
    return;
  }
  if (time >= t[last]) {
    for (size_t j = 0; j < nc; j++)
      c->mean[j] += sign * (cum[last * nc + j] + u[last * nc + j] * (time - t[last]));
    return;
  }
  size_t k = c->k < last ? c->k : last - 1;
  while (k > 0 && time < t[k]) k--;
  while (k + 1 < last && time >= t[k + 1]) k++;
  c->k = k;
  const double dt = t[k + 1] - t[k], tau = time - t[k];
  for (size_t j = 0; j < nc; j++) {
    /* the single piston's arithmetic (dm_region.c, piston_antiderivative), operation for
     * operation: equal histories give bitwise equal runs */
    const double u0 = u[k * nc + j], slope = dt > 0 ? (u[(k + 1) * nc + j] - u0) / dt : 0.0;
    c->mean[j] += sign * (cum[k * nc + j] + u0 * tau + 0.5 * slope * tau * tau);
  }
}

void dm_columns_drive(dm_columns *c, double a, double b, dm_state *s) {
  memset(c->mean, 0, c->nh * sizeof *c->mean);
  antiderivative(c, a, -1.0);
  antiderivative(c, b, 1.0);
  for (size_t j = 0; j < c->nh; j++) c->mean[j] /= b - a;
  const size_t nc = c->ncol;
  for (size_t q = 0; q < c->np; q++) {
    const size_t lo = c->lo[q], hi = lo + 1 < nc ? lo + 1 : lo;
    const double w = c->w[q];
    double *ui = &s->u[3 * c->idx[q]];
    ui[0] = (1.0 - w) * c->mean[lo] + w * c->mean[hi];
    ui[1] = c->ncomp == 2 ? (1.0 - w) * c->mean[nc + lo] + w * c->mean[nc + hi] : 0.0;
    ui[2] = 0.0;
  }
}
