/* SPDX-License-Identifier: MIT */
/* coupled_grid.c — the coupled problem's adapter over the grid (cont.h): the gas state the
 * fragments feel, the momentum and energy they return to it, the tag histories shared over the
 * ranks, and the check that the replicated grids stayed equal. */
#include "coupled_impl.h"

#include <stdlib.h>
#include <string.h>

/* Linear interpolation in a sampled history (constant beyond the ends). */
double cpl_interp(size_t n, const double *t, const double *v, double x) {
  if (!n) return 0.0;
  if (x <= t[0]) return v[0];
  if (x >= t[n - 1]) return v[n - 1];
  size_t lo = 0, hi = n - 1;
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (t[mid] <= x) lo = mid;
    else hi = mid;
  }
  return v[lo] + (v[hi] - v[lo]) * (x - t[lo]) / (t[hi] - t[lo]);
}

gas_ctx cpl_gas_of(const cpl_problem *p, cont_grid *g, double offset, double area) {
  return (gas_ctx){.g = g,
                   .gas_layer = p->gas_layer,
                   .mu = p->mats->m[p->gas_mat].viscosity,
                   .offset = offset,
                   .area = area,
                   .st = MS_OK};
}

/* The gas at x receives momentum −dp (along the grid axis: the 1D gas has no transverse
 * momentum, so dp[1], dp[2] are not represented) and energy −de (all of it, transverse motion
 * included: energy is conserved exactly), per cm² of the particle region's cross-section.
 * Outside the gas layer nothing is returned (nor was drag applied there). */
void cpl_gas_deposit(void *user, const double x[3], double t0, double t1, const double dp[3],
                     double de) {
  (void)t0;
  (void)t1;
  gas_ctx *c = user;
  cont_sample s;
  if (c->st != MS_OK || !cont_grid_sample(c->g, x[0] - c->offset, &s) || s.layer != c->gas_layer)
    return;
  if (c->cell_src) {
    c->cell_src[2 * s.cell] -= dp[0] / c->area;
    c->cell_src[2 * s.cell + 1] -= de / c->area;
    return;
  }
  ms_status st = cont_grid_add_cell_source(c->g, s.cell, -dp[0] / c->area, -de / c->area);
  if (st != MS_OK) {
    c->st = st;
    return;
  }
  c->returned_p -= dp[0];
  c->returned_e -= de;
  if (c->log) cpl_gaslog_source(c->log, s.cell, -dp[0] / c->area, -de / c->area);
}

bool cpl_grid_gas(void *user, const double x[3], double t, cpl_gas *out) {
  (void)t;
  const gas_ctx *c = user;
  cont_sample s;
  if (!cont_grid_sample(c->g, x[0] - c->offset, &s) || s.layer != c->gas_layer) return false;
  out->rho = s.rho;
  out->u[0] = s.u;
  out->u[1] = out->u[2] = 0;
  out->p = s.p;
  out->mu = c->mu;
  return true;
}

/* MPI: the ranks' drag-kick sources, summed over the ranks in rank order (the same bits on every
 * rank), enter every rank's copy of the grid identically (cell order; serially they enter
 * particle by particle: the same sums to round-off, since a cell source is additive). */
void cpl_gas_return_sum(gas_ctx *c) {
  const size_t ncell = cont_grid_ncells(c->g);
  double *src = c->cell_src;
  par_sum_doubles_ordered(src, 2 * ncell);
  c->cell_src = NULL;
  for (size_t k = 0; k < ncell && c->st == MS_OK; k++) {
    if (src[2 * k] == 0 && src[2 * k + 1] == 0) continue;
    c->st = cont_grid_add_cell_source(c->g, k, src[2 * k], src[2 * k + 1]);
    if (c->st == MS_OK) {
      c->returned_p += src[2 * k] * c->area;
      c->returned_e += src[2 * k + 1] * c->area;
      if (c->log) /* every rank logs the same sums: a restart replays them bit for bit */
        cpl_gaslog_source(c->log, k, src[2 * k], src[2 * k + 1]);
    }
  }
  memset(src, 0, 2 * ncell * sizeof *src);
  c->cell_src = src;
}

/* MPI: the grids are replicated, every rank advancing its copy with the same operands (what
 * the ranks contribute enters through fixed-order sums or broadcasts). Guard: a digest of every
 * copy's node and cell arrays, compared over the ranks at the end of the run; a difference is an
 * internal error (MS_ERR_INTERNAL on every rank). Serial: nothing to compare. */
ms_status cpl_check_replicated(const ms_ctx *ctx, const cont_grid *g1, const cont_grid *g2) {
  if (ctx->size < 2) return MS_OK;
  uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a offset basis */
  const cont_grid *grids[2] = {g1, g2};
  for (int k = 0; k < 2; k++) {
    if (!grids[k]) continue;
    cont_view v = cont_grid_view(grids[k]);
    h = dk_hash_doubles(h, v.x, v.nnodes);
    h = dk_hash_doubles(h, v.u, v.nnodes);
    h = dk_hash_doubles(h, v.rho, v.ncells);
    h = dk_hash_doubles(h, v.e, v.ncells);
    h = dk_hash_doubles(h, v.p, v.ncells);
  }
  const int64_t mine = (int64_t)h, top = par_max_int64(mine);
  if (par_max_int(mine != top) == 0) {
    ms_log(ctx, MS_LOG_INFO, "coupled: the replicated grid is bitwise identical on all %d ranks",
           ctx->size);
    return MS_OK;
  }
  ms_log(ctx, MS_LOG_ERROR, "coupled: the replicated grid differs between the ranks (rank %d)",
         ctx->rank);
  return MS_ERR_INTERNAL;
}

/* Under MPI rank 0 ran the grid (cont_problem_run); the tag history h (t, x, u, p_right) goes to
 * every rank, into *buf (the caller frees it). Serial: nothing to do. */
void cpl_share_history(const ms_ctx *ctx, cont_history *h, double **buf) {
  *buf = NULL;
  if (ctx->size < 2) return;
  double nd = (double)h->n;
  par_bcast_doubles(&nd, 1, 0);
  const size_t n = (size_t)nd;
  double *b = ms_calloc(4 * n + 1, sizeof *b);
  if (ctx->rank == 0) {
    memcpy(b, h->t, n * sizeof *b);
    memcpy(b + n, h->x, n * sizeof *b);
    memcpy(b + 2 * n, h->u, n * sizeof *b);
    memcpy(b + 3 * n, h->p_right, n * sizeof *b);
  }
  par_bcast_doubles(b, 4 * n, 0);
  h->n = n, h->t = b, h->x = b + n, h->u = b + 2 * n, h->p_right = b + 3 * n;
  *buf = b;
}
