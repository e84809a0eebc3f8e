/* SPDX-License-Identifier: MIT */
/* Piston velocity from a tagged grid node's history, preserving the node's displacement
 * (the one-way drive of docs/design.md §6; formula in cpl.h and docs/coupling.md). */
#include "cpl_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void cpl_piston_free(cpl_piston *p) {
  if (!p) return;
  free(p->t);
  free(p->x);
  free(p->u);
  free(p->c);
  memset(p, 0, sizeof *p);
}

ms_status cpl_piston_build(cpl_piston *p, size_t n, const double *t, const double *x,
                           const double *u) {
  memset(p, 0, sizeof *p);
  if (n < 1 || !t || !x || !u) return MS_ERR_INPUT;
  for (size_t k = 0; k < n; k++) {
    if (!isfinite(t[k]) || !isfinite(x[k]) || !isfinite(u[k])) return MS_ERR_INPUT;
    if (k && !(t[k] > t[k - 1])) return MS_ERR_INPUT;
  }
  p->n = n;
  p->t = ms_calloc(n, sizeof *p->t);
  p->x = ms_calloc(n, sizeof *p->x);
  p->u = ms_calloc(n, sizeof *p->u);
  p->c = ms_calloc(n, sizeof *p->c);
  memcpy(p->t, t, n * sizeof *t);
  memcpy(p->x, x, n * sizeof *x);
  memcpy(p->u, u, n * sizeof *u);
  for (size_t k = 0; k + 1 < n; k++) {
    /* constant correction that makes ∫ over the interval equal the recorded displacement */
    p->c[k] = (x[k + 1] - x[k]) / (t[k + 1] - t[k]) - 0.5 * (u[k] + u[k + 1]);
    if (fabs(p->c[k]) > p->max_correction) p->max_correction = fabs(p->c[k]);
  }
  return MS_OK;
}

/* Interval k with t_k ≤ t < t_k+1 (binary search); n−1 past the end. */
static size_t interval(const cpl_piston *p, double t) {
  size_t lo = 0, hi = p->n - 1;
  if (t >= p->t[hi]) return hi;
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (p->t[mid] <= t) lo = mid;
    else hi = mid;
  }
  return lo;
}

double cpl_piston_velocity(const cpl_piston *p, double t) {
  if (!p->n) return 0.0;
  if (t <= p->t[0]) return p->u[0];
  size_t k = interval(p, t);
  if (k == p->n - 1) return p->u[k];
  double s = (t - p->t[k]) / (p->t[k + 1] - p->t[k]);
  return p->u[k] + (p->u[k + 1] - p->u[k]) * s + p->c[k];
}

double cpl_piston_displacement(const cpl_piston *p, double t) {
  if (!p->n) return 0.0;
  if (t <= p->t[0]) return p->u[0] * (t - p->t[0]); /* constant before the start */
  size_t k = interval(p, t);
  if (k == p->n - 1) return p->x[k] - p->x[0] + p->u[k] * (t - p->t[k]);
  double h = t - p->t[k], dt = p->t[k + 1] - p->t[k];
  /* exact integral of the linear-plus-constant velocity over [t_k, t] */
  double part = h * (p->u[k] + p->c[k]) + 0.5 * (p->u[k + 1] - p->u[k]) * h * h / dt;
  return p->x[k] - p->x[0] + part;
}

/* Free-surface comparison (docs/coupling.md §5): breakout where the grid's velocity first
 * exceeds 5 % of its maximum; plateaus = means over the second half of the window; arrival =
 * first crossing of half the plateau (linear interpolation between samples). */
static double half_crossing(size_t n, const double *t, const double *u, double level, double t0) {
  for (size_t k = 1; k < n; k++) {
    if (t[k] < t0 || !isfinite(u[k]) || !isfinite(u[k - 1])) continue;
    if (u[k - 1] < level && u[k] >= level)
      return t[k - 1] + (level - u[k - 1]) * (t[k] - t[k - 1]) / (u[k] - u[k - 1]);
    if (k == 1 && u[0] >= level) return t[0];
  }
  return NAN;
}

bool cpl_free_surface_check(size_t n, const double *t, const double *u_grid,
                            const double *u_particles, double window, cpl_fs_check *out) {
  memset(out, 0, sizeof *out);
  out->t_break = out->plateau_grid = out->plateau_particles = out->rel_diff = NAN;
  out->t_half_grid = out->t_half_particles = out->min_after = NAN;
  double umax = 0;
  for (size_t k = 0; k < n; k++)
    if (isfinite(u_grid[k])) umax = fmax(umax, fabs(u_grid[k]));
  if (!(umax > 0) || !(window > 0)) return false;
  size_t kb = 0;
  while (kb < n && !(fabs(u_grid[kb]) > 0.05 * umax)) kb++;
  if (kb == n) return false;
  out->t_break = t[kb];
  double sg = 0, sp = 0;
  size_t m = 0;
  for (size_t k = kb; k < n && t[k] <= out->t_break + window; k++)
    if (t[k] >= out->t_break + 0.5 * window && isfinite(u_particles[k])) {
      sg += u_grid[k];
      sp += u_particles[k];
      m++;
    }
  out->samples = m;
  if (!m) return false;
  /* after the window: the reflection of the release at the piston shows up here */
  for (size_t k = kb; k < n && t[k] <= out->t_break + 3 * window; k++)
    if (t[k] > out->t_break + window && isfinite(u_particles[k]))
      out->min_after =
          isnan(out->min_after) ? u_particles[k] : fmin(out->min_after, u_particles[k]);
  out->plateau_grid = sg / (double)m;
  out->plateau_particles = sp / (double)m;
  out->rel_diff = fabs(out->plateau_particles - out->plateau_grid) / fabs(out->plateau_grid);
  double t0 = out->t_break - window;
  out->t_half_grid = half_crossing(n, t, u_grid, 0.5 * out->plateau_grid, t0);
  out->t_half_particles = half_crossing(n, t, u_particles, 0.5 * out->plateau_particles, t0);
  return true;
}
