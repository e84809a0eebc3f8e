/* SPDX-License-Identifier: MIT */
/* tags.c — tagged nodes: x(t), u(t) of a node and p, ρ of its two cells at every step.
 *
 * The predictor–corrector step leaves positions, velocities and cell states at the same time
 * level tⁿ, so a history row (tⁿ, xⁿ, uⁿ, pⁿ, ρⁿ) is consistent as recorded: no half-step
 * re-centring is needed when the coupling uses x(t) and u(t) to drive a piston (x(t) is then the
 * trapezoidal integral of u(t), exactly as the grid moved the node). Storage grows by doubling,
 * so a step allocates only O(log steps) times over a run.
 */
#include "cont_impl.h"

#include <math.h>
#include <string.h>

static void tag_reserve(cont_tag *tg, size_t need) {
  if (need <= tg->cap) return;
  size_t cap = tg->cap ? tg->cap : 1024;
  while (cap < need) cap *= 2;
  double **cols[] = {&tg->t,        &tg->x,       &tg->u,        &tg->p_left,
                     &tg->rho_left, &tg->p_right, &tg->rho_right};
  for (size_t k = 0; k < sizeof cols / sizeof cols[0]; ++k)
    *cols[k] = ms_realloc(*cols[k], cap, sizeof(double));
  tg->cap = cap;
}

static void tag_record(const cont_grid *g, cont_tag *tg) {
  tag_reserve(tg, tg->n + 1);
  size_t j = tg->node, n = tg->n;
  tg->t[n] = g->t;
  tg->x[n] = g->x[j];
  tg->u[n] = g->u[j];
  tg->p_left[n] = j > 0 ? g->p[j - 1] : NAN;
  tg->rho_left[n] = j > 0 ? g->rho[j - 1] : NAN;
  tg->p_right[n] = j < g->ncells ? g->p[j] : NAN;
  tg->rho_right[n] = j < g->ncells ? g->rho[j] : NAN;
  tg->n = n + 1;
}

void cont_record_tags(cont_grid *g) {
  for (size_t k = 0; k < g->ntags; ++k) tag_record(g, &g->tags[k]);
}

size_t cont_grid_ntags(const cont_grid *g) { return g->ntags; }

size_t cont_grid_add_tag(cont_grid *g, const char *name, size_t node) {
  if (g->ntags == g->tag_cap) {
    g->tag_cap = g->tag_cap ? 2 * g->tag_cap : 4;
    g->tags = ms_realloc(g->tags, g->tag_cap, sizeof(cont_tag));
  }
  cont_tag *tg = &g->tags[g->ntags];
  memset(tg, 0, sizeof *tg);
  tg->name = ms_strdup(name ? name : "tag");
  tg->node = node < g->nnodes ? node : g->nnodes - 1;
  tag_record(g, tg);
  return g->ntags++;
}

cont_history cont_grid_history(const cont_grid *g, size_t tag) {
  cont_history h = {0};
  if (tag >= g->ntags) return h;
  const cont_tag *tg = &g->tags[tag];
  h.name = tg->name;
  h.node = tg->node;
  h.n = tg->n;
  h.t = tg->t;
  h.x = tg->x;
  h.u = tg->u;
  h.p_left = tg->p_left;
  h.rho_left = tg->rho_left;
  h.p_right = tg->p_right;
  h.rho_right = tg->rho_right;
  return h;
}

void cont_history_at(const cont_history *h, double t, double *x, double *u) {
  if (h->n == 0) {
    *x = *u = NAN;
    return;
  }
  if (t <= h->t[0] || h->n == 1) {
    *x = h->x[0];
    *u = h->u[0];
    return;
  }
  if (t >= h->t[h->n - 1]) {
    *x = h->x[h->n - 1];
    *u = h->u[h->n - 1];
    return;
  }
  size_t lo = 0, hi = h->n - 1; /* t[lo] <= t < t[hi] */
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (h->t[mid] <= t) lo = mid;
    else hi = mid;
  }
  double dt = t - h->t[lo], w = dt / (h->t[hi] - h->t[lo]);
  double ut = h->u[lo] + w * (h->u[hi] - h->u[lo]);
  *u = ut;
  *x = h->x[lo] + 0.5 * dt * (h->u[lo] + ut);
}
