/* SPDX-License-Identifier: MIT */
/* grid2d_step.c — the time step of the 2D grid (c2d_grid_step; the corner forces and the zone
 * state: grid2d.c). docs/continuum2d.md §6 (layout, speed) and §7 (threads).
 *
 * Step tⁿ → tⁿ⁺¹ (predictor–corrector of [CBSW98], as the 1D scheme, continuum/step.c):
 *   predictor  Fⁿ from (xⁿ, uⁿ, pⁿ); u* = uⁿ + Δt Fⁿ/M (boundary conditions at tⁿ⁺¹);
 *              û = ½(uⁿ + u*); x^{n+½} = xⁿ + ½Δt û; e^{n+½} = eⁿ − ½Δt Σ_c r̃ f_cⁿ·û / m_z;
 *              ρ^{n+½}, p^{n+½}
 *   corrector  F from (x^{n+½}, û, p^{n+½}); uⁿ⁺¹ = uⁿ + Δt F/M (BCs); ū = ½(uⁿ + uⁿ⁺¹);
 *              xⁿ⁺¹ = xⁿ + Δt ū; eⁿ⁺¹ = eⁿ − Δt Σ_c r̃ f_c·ū / m_z; ρⁿ⁺¹, pⁿ⁺¹, cⁿ⁺¹.
 * Σ ½M(uⁿ⁺¹² − uⁿ²) = Σ M(uⁿ⁺¹ − uⁿ)·ū = Δt Σ_p r̃_p Σ_c f_c·ū = −Σ m_z(eⁿ⁺¹ − eⁿ) for every
 * free node; at a constrained node the difference is the boundary's work (g->work).
 *
 * Layout: each half step is one sweep over the zone rows j = 0, 1, …: the corner forces of
 * zone row j; then node row j (gathers its corners from zone rows j − 1 and j, accelerates,
 * applies the boundary conditions, moves); then zone row j − 1 (its work Σ r̃ f·ū with the
 * forces it made, its energy, volume, density and EOS, and in the corrector its Courant limit).
 * Corner forces, ū and r̃ live in two-row rings, so they stay in cache and never go to memory;
 * the inputs of a sweep's forces are never written during it (the predictor writes x^{n+½},
 * û; the corrector xⁿ⁺¹, uⁿ⁺¹, with ū only in the rings), so the limiter may read nodes two
 * rows away.
 *
 * Threads: each takes a band of zone rows. It first makes the forces of its band's last zone
 * row (which the next band's first node row needs), then sweeps its band, then, after a
 * barrier, finishes its last zone row with the next band's first node row. Every zone and node
 * does the same arithmetic in the same order whatever band it is in, and the boundary work is
 * summed serially in node order, so results do not depend on the number of threads.
 */
#include "grid2d_impl.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

/* One sweep: what its forces see, where its node update starts (bx, bu: xⁿ, uⁿ) and writes
 * (ox, ou: x^{n+½}, û in the predictor; xⁿ⁺¹, uⁿ⁺¹ in place in the corrector), the zone state
 * it writes. */
typedef struct sweep {
  bool corr;
  double dt, t1;
  c2d_fstate in;
  double *ox, *oy, *ou, *ov;
  double *orho, *op, *oc;
} sweep;

/* What a thread's sweep found (reduced serially afterwards); padded against false sharing. */
typedef struct sweep_out {
  size_t inv_z, eos_z, nan_z;
  double inv_val, eos_val, dt, dvr;
  char pad[8];
} sweep_out;

/* A node row's ū, v̄ and r̃ (1 unless rz_area_weighted). */
typedef struct nrow {
  double *u, *v, *r;
} nrow;

static void scratch_release(c2d_scratch *s) { free(s->fc[0]); /* one block per thread */ }

void c2d_scratch_free(c2d_grid *g) {
  for (int t = 0; t < g->nscratch; ++t) scratch_release(&g->scr[t]);
  free(g->scr);
  g->scr = NULL;
  g->nscratch = 0;
}

void c2d_scratch_alloc(c2d_grid *g) {
  if (g->nscratch >= g->nthreads) return;
  c2d_scratch_free(g);
  const size_t ni = g->ni, w = ni + 1;
  const size_t per = 3 * (8 * ni + 4 * ni) + 9 * w + 2 * ni + 15 * (w + 2);
  g->scr = calloc((size_t)g->nthreads, sizeof *g->scr);
  if (!g->scr) abort();
  for (int t = 0; t < g->nthreads; ++t) {
    c2d_scratch *s = &g->scr[t];
    double *b = calloc(per, sizeof(double));
    if (!b) abort();
    double **rows[] = {&s->fc[0], &s->fc[1], &s->fcb};
    for (int k = 0; k < 3; ++k, b += 8 * ni) *rows[k] = b;
    double **mrows[] = {&s->ma[0], &s->ma[1], &s->mab};
    for (int k = 0; k < 3; ++k, b += 4 * ni) *mrows[k] = b;
    double **nrows[] = {&s->ub[0], &s->ub[1], &s->ubb,   &s->vb[0], &s->vb[1],
                        &s->vbb,   &s->rf[0], &s->rf[1], &s->rfb};
    for (int k = 0; k < 9; ++k, b += w) *nrows[k] = b;
    s->erow = b; /* 2 ni: energies, then the predictor's volumes */
    b += 2 * ni;
    c2d_erow *er[5] = {&s->eh[0], &s->eh[1], &s->ev[0], &s->ev[1], &s->ev[2]};
    for (int k = 0; k < 5; ++k) { /* each with a zero pad before and after */
      er[k]->gx = b + 1;
      er[k]->gy = b + w + 3;
      er[k]->ic = b + 2 * w + 5;
      b += 3 * (w + 2);
    }
  }
  if (!g->wside) {
    g->wside = calloc(2 * (g->ni + 1) + 2 * (g->nj + 1), sizeof(double));
    if (!g->wside) abort();
  }
  g->nscratch = g->nthreads;
}

/* Index in g->wside of side node (i, j) (row 0, row nj, then columns 0 and ni of the rows
 * between). */
static inline size_t wside_index(const c2d_grid *g, size_t i, size_t j) {
  const size_t w = g->ni + 1;
  if (j == 0) return i;
  if (j == g->nj) return w + i;
  return 2 * w + (i == 0 ? j : g->nj + 1 + j);
}

/* Node (i, j) = n: acceleration from its gathered corner forces (sx, sy; area masses sa), the
 * update of the sweep, and its ū, v̄, r̃ into the row slot. */
static inline __attribute__((always_inline)) void node_update(c2d_grid *g, const sweep *sw,
                                                              size_t i, size_t j, double sx,
                                                              double sy, double sa,
                                                              const nrow *nr) {
  const size_t n = i + (g->ni + 1) * j;
  const bool side = i == 0 || j == 0 || i == g->ni || j == g->nj;
  const double M = g->M[n], r = g->area_weighted ? M / sa : 1.0, dt = sw->dt;
  double ax = 0.0, ay = 0.0;
  if (M > 0.0) {
    const double ex = side && g->has_pressure ? g->ex[n] : 0.0;
    const double ey = side && g->has_pressure ? g->ey[n] : 0.0;
    ax = (r * sx + ex) / M;
    ay = (r * sy + ey) / M;
  }
  const double u0 = g->u[n], v0 = g->v[n];
  double u1 = u0 + dt * ax, v1 = v0 + dt * ay;
  const bool con = side && c2d_apply_bc_ij(g, i, j, n, sw->t1, &u1, &v1);
  const double ub = 0.5 * (u0 + u1), vb = 0.5 * (v0 + v1);
  if (!sw->corr) {
    sw->ou[n] = ub;
    sw->ov[n] = vb;
    sw->ox[n] = g->x[n] + 0.5 * dt * ub;
    sw->oy[n] = g->y[n] + 0.5 * dt * vb;
  } else {
    /* Reaction work at constrained nodes: ΔKE minus the work of the grid's own forces. */
    if (side)
      g->wside[wside_index(g, i, j)] =
          con ? M * ((u1 - u0) * ub + (v1 - v0) * vb) - dt * r * (sx * ub + sy * vb) : 0.0;
    g->u[n] = u1;
    g->v[n] = v1;
    g->x[n] += dt * ub;
    g->y[n] += dt * vb;
  }
  nr->u[i] = ub;
  nr->v[i] = vb;
  nr->r[i] = r;
}

/* The gathered force (sx, sy), area mass sa and acceleration of interior node i of a row
 * (node_update's arithmetic; aw > 0: r̃ = M/sa, else 1): corners in node_row's order. */
#define NODE_INTERIOR_ACCEL                                                                        \
  double sx = 0.0, sy = 0.0, sa = 0.0;                                                             \
  sx += fb0[i];                                                                                    \
  sy += fb1[i];                                                                                    \
  sa += mb0[i];                                                                                    \
  sx += fb2[i - 1];                                                                                \
  sy += fb3[i - 1];                                                                                \
  sa += mb1[i - 1];                                                                                \
  sx += fa4[i - 1];                                                                                \
  sy += fa5[i - 1];                                                                                \
  sa += ma2[i - 1];                                                                                \
  sx += fa6[i];                                                                                    \
  sy += fa7[i];                                                                                    \
  sa += ma3[i];                                                                                    \
  const double Mi = M[i], r = aw > 0.0 ? Mi / sa : 1.0;                                            \
  const double ax = Mi > 0.0 ? (r * sx + 0.0) / Mi : 0.0, ay = Mi > 0.0 ? (r * sy + 0.0) / Mi : 0.0;
#define NODE_INTERIOR_ARGS                                                                         \
  ptrdiff_t ni, double dt, double aw, const double *restrict fb0, const double *restrict fb1,      \
      const double *restrict fb2, const double *restrict fb3, const double *restrict fa4,          \
      const double *restrict fa5, const double *restrict fa6, const double *restrict fa7,          \
      const double *restrict mb0, const double *restrict mb1, const double *restrict ma2,          \
      const double *restrict ma3, const double *restrict M, double *restrict nu,                   \
      double *restrict nv, double *restrict nr

/* Nodes i = 1 .. ni − 1 of an interior node row (four corners, no boundary condition), predictor:
 * û into ou, ov, x^{n+½} into ox, oy (from u, v, x, y). Restrict arrays: vectorizes. */
MS_KERNEL_CLONES static void
node_interior_pred_k(NODE_INTERIOR_ARGS, const double *restrict u, const double *restrict v,
                     const double *restrict x, const double *restrict y, double *restrict ou,
                     double *restrict ov, double *restrict ox, double *restrict oy) {
  for (ptrdiff_t i = 1; i < ni; ++i) {
    NODE_INTERIOR_ACCEL
    const double u1 = u[i] + dt * ax, v1 = v[i] + dt * ay;
    const double ub = 0.5 * (u[i] + u1), vb = 0.5 * (v[i] + v1);
    ou[i] = ub;
    ov[i] = vb;
    ox[i] = x[i] + 0.5 * dt * ub;
    oy[i] = y[i] + 0.5 * dt * vb;
    nu[i] = ub;
    nv[i] = vb;
    nr[i] = r;
  }
}

/* The same, corrector: uⁿ⁺¹ and xⁿ⁺¹ in place. */
MS_KERNEL_CLONES static void node_interior_corr_k(NODE_INTERIOR_ARGS, double *restrict u,
                                                  double *restrict v, double *restrict x,
                                                  double *restrict y) {
  for (ptrdiff_t i = 1; i < ni; ++i) {
    NODE_INTERIOR_ACCEL
    const double u0 = u[i], v0 = v[i], u1 = u0 + dt * ax, v1 = v0 + dt * ay;
    const double ub = 0.5 * (u0 + u1), vb = 0.5 * (v0 + v1);
    u[i] = u1;
    v[i] = v1;
    x[i] += dt * ub;
    y[i] += dt * vb;
    nu[i] = ub;
    nv[i] = vb;
    nr[i] = r;
  }
}

/* Node row j: gathers the corners that touch each node in a fixed order — zone (i, j) corner
 * 0, (i−1, j) corner 1, (i−1, j−1) corner 2, (i, j−1) corner 3 — from the forces fa (ma_a) of
 * zone row j − 1 and fb (ma_b) of zone row j (NULL: no such row), then updates it. The interior
 * nodes of an interior row go through the vectorized kernels (the same arithmetic). */
static void node_row(c2d_grid *g, const sweep *sw, size_t j, const double *fa, const double *maa,
                     const double *fb, const double *mab, const nrow *nr) {
  const size_t ni = g->ni;
  const bool interior = fa && fb && ni > 1; /* then 0 < j < nj: no side node for 0 < i < ni */
  for (size_t i = 0; i <= ni; ++i) {
    if (interior && i == 1) {
      const size_t n0 = (ni + 1) * j;
      const ptrdiff_t n = (ptrdiff_t)ni;
      const double aw = g->area_weighted ? 1.0 : 0.0;
      if (sw->corr)
        node_interior_corr_k(n, sw->dt, aw, fb, fb + ni, fb + 2 * ni, fb + 3 * ni, fa + 4 * ni,
                             fa + 5 * ni, fa + 6 * ni, fa + 7 * ni, mab, mab + ni, maa + 2 * ni,
                             maa + 3 * ni, g->M + n0, nr->u, nr->v, nr->r, g->u + n0, g->v + n0,
                             g->x + n0, g->y + n0);
      else
        node_interior_pred_k(n, sw->dt, aw, fb, fb + ni, fb + 2 * ni, fb + 3 * ni, fa + 4 * ni,
                             fa + 5 * ni, fa + 6 * ni, fa + 7 * ni, mab, mab + ni, maa + 2 * ni,
                             maa + 3 * ni, g->M + n0, nr->u, nr->v, nr->r, g->u + n0, g->v + n0,
                             g->x + n0, g->y + n0, sw->ou + n0, sw->ov + n0, sw->ox + n0,
                             sw->oy + n0);
      i = ni - 1;
      continue;
    }
    double sx = 0.0, sy = 0.0, sa = 0.0;
    if (fb && i < ni) {
      sx += fb[i];
      sy += fb[ni + i];
      sa += mab[i];
    }
    if (fb && i > 0) {
      sx += fb[2 * ni + i - 1];
      sy += fb[3 * ni + i - 1];
      sa += mab[ni + i - 1];
    }
    if (fa && i > 0) {
      sx += fa[4 * ni + i - 1];
      sy += fa[5 * ni + i - 1];
      sa += maa[2 * ni + i - 1];
    }
    if (fa && i < ni) {
      sx += fa[6 * ni + i];
      sy += fa[7 * ni + i];
      sa += maa[3 * ni + i];
    }
    node_update(g, sw, i, j, sx, sy, sa, nr);
  }
}

/* e_out = e_in − hdt Σ_c r̃ f_c·ū / m over a zone row (hdt = ½Δt predictor, Δt corrector):
 * corner forces f0..f7 (SoA), ū, v̄, r̃ of the node rows below (l*) and above (h*). */
MS_KERNEL_CLONES static void
energy_row_k(ptrdiff_t ni, double hdt, const double *restrict f0, const double *restrict f1,
             const double *restrict f2, const double *restrict f3, const double *restrict f4,
             const double *restrict f5, const double *restrict f6, const double *restrict f7,
             const double *restrict lu, const double *restrict lv, const double *restrict lr,
             const double *restrict hu, const double *restrict hv, const double *restrict hr,
             const double *restrict e_in, const double *restrict m, double *restrict e_out) {
  for (ptrdiff_t i = 0; i < ni; ++i) {
    /* −Σ_c r̃ f_c·ū, corners k = 0..3 (nodes (i, j), (i+1, j), (i+1, j+1), (i, j+1)) */
    double s = 0.0;
    s += lr[i] * (f0[i] * lu[i] + f1[i] * lv[i]);
    s += lr[i + 1] * (f2[i] * lu[i + 1] + f3[i] * lv[i + 1]);
    s += hr[i + 1] * (f4[i] * hu[i + 1] + f5[i] * hv[i + 1]);
    s += hr[i] * (f6[i] * hu[i] + f7[i] * hv[i]);
    e_out[i] = e_in[i] - hdt * s / m[i];
  }
}

/* x–y zone volumes (areas) and densities of a row from node rows a, b. Plain loops over restrict
 * rows (they vectorize; `omp simd` reductions here did not, GCC 12), the reductions after. */
MS_KERNEL_CLONES static void area_row_k(ptrdiff_t ni, const double *restrict xa,
                                        const double *restrict xb, const double *restrict ya,
                                        const double *restrict yb, const double *restrict m,
                                        double *restrict vol, double *restrict rho) {
  for (ptrdiff_t i = 0; i < ni; ++i) {
    const double X[4] = {xa[i], xa[i + 1], xb[i + 1], xb[i]},
                 Y[4] = {ya[i], ya[i + 1], yb[i + 1], yb[i]};
    const double a = quad_area(X, Y);
    vol[i] = a;
    rho[i] = m[i] / a;
  }
}

/* The same in the corrector: also the relative volume change dv (vol holds the old volumes). */
MS_KERNEL_CLONES static void area_row_dv_k(ptrdiff_t ni, const double *restrict xa,
                                           const double *restrict xb, const double *restrict ya,
                                           const double *restrict yb, const double *restrict m,
                                           double *restrict vol, double *restrict rho,
                                           double *restrict dv) {
  for (ptrdiff_t i = 0; i < ni; ++i) {
    const double X[4] = {xa[i], xa[i + 1], xb[i + 1], xb[i]},
                 Y[4] = {ya[i], ya[i + 1], yb[i + 1], yb[i]};
    const double a = quad_area(X, Y);
    dv[i] = fabs(a - vol[i]) / a; /* volume change over the step */
    vol[i] = a;
    rho[i] = m[i] / a;
  }
}

/* Courant limits of a zone row at the new state (c2d_zone_dt) into dz. */
MS_KERNEL_CLONES static void dt_row_k(const c2d_grid *g, ptrdiff_t ni, const double *restrict xa,
                                      const double *restrict xb, const double *restrict ya,
                                      const double *restrict yb, const double *restrict ua,
                                      const double *restrict ub, const double *restrict va,
                                      const double *restrict vb, const double *restrict c,
                                      double *restrict dz) {
  for (ptrdiff_t i = 0; i < ni; ++i) {
    const double X[4] = {xa[i], xa[i + 1], xb[i + 1], xb[i]},
                 Y[4] = {ya[i], ya[i + 1], yb[i + 1], yb[i]};
    const double U[4] = {ua[i], ua[i + 1], ub[i + 1], ub[i]},
                 V[4] = {va[i], va[i + 1], vb[i + 1], vb[i]};
    dz[i] = c2d_zone_dt(g, X, Y, U, V, c[i]);
  }
}

/* Zone row j after its nodes moved: the work of its corner forces f with ū of node rows j (lo)
 * and j + 1 (hi), the energy, volume and density, the EOS; in the corrector also the Courant
 * limit, the volume change and the finiteness check. Failures go to o (lowest zone). */
static void zone_row(c2d_grid *g, const sweep *sw, size_t j, const double *f, const nrow *lo,
                     const nrow *hi, double *erow, sweep_out *o) {
  const size_t ni = g->ni, w = ni + 1, z0 = ni * j, n0 = w * j;
  const ptrdiff_t n = (ptrdiff_t)ni;
  const double dt = sw->dt, *px = sw->ox, *py = sw->oy;
  /* e^{n+½} (predictor) or eⁿ⁺¹ (corrector, then copied to e) into the row scratch */
  energy_row_k(n, sw->corr ? dt : 0.5 * dt, f, f + ni, f + 2 * ni, f + 3 * ni, f + 4 * ni,
               f + 5 * ni, f + 6 * ni, f + 7 * ni, lo->u, lo->v, lo->r, hi->u, hi->v, hi->r,
               g->e + z0, g->m + z0, erow);
  double *en = erow;
  if (sw->corr) {
    memcpy(g->e + z0, erow, ni * sizeof(double));
    en = g->e + z0;
  }
  double *vol = sw->corr ? g->vol + z0 : erow + ni; /* the predictor keeps no volumes */
  long bad = 0;
  if (g->geo == C2D_XY) {
    if (sw->corr) {
      double *dv = erow + ni; /* the corrector's free scratch half */
      area_row_dv_k(n, px + n0, px + n0 + w, py + n0, py + n0 + w, g->m + z0, vol, sw->orho + z0,
                    dv);
      for (size_t i = 0; i < ni; ++i) o->dvr = dv[i] > o->dvr ? dv[i] : o->dvr;
    } else area_row_k(n, px + n0, px + n0 + w, py + n0, py + n0 + w, g->m + z0, vol, sw->orho + z0);
    for (size_t i = 0; i < ni; ++i) bad += !(vol[i] > 0.0);
  } else
    for (size_t i = 0; i < ni; ++i) {
      const size_t z = z0 + i, nd[4] = {n0 + i, n0 + i + 1, n0 + w + i + 1, n0 + w + i};
      double X[4], Y[4];
      gather_nd(nd, px, py, X, Y);
      const double a = quad_area(X, Y), vz = quad_rvol(X, Y);
      if (sw->corr) {
        const double r = fabs(vz - vol[i]) / vz; /* volume change over the step */
        if (r > o->dvr) o->dvr = r;
      }
      vol[i] = vz;
      sw->orho[z] = g->m[z] / vz;
      bad += !(a > 0.0) || !(vz > 0.0);
    }
  if (bad)
    for (size_t i = 0; i < ni; ++i) { /* the first one, as the diagnostic */
      const size_t z = z0 + i, nd[4] = {n0 + i, n0 + i + 1, n0 + w + i + 1, n0 + w + i};
      double X[4], Y[4];
      gather_nd(nd, px, py, X, Y);
      const double a = quad_area(X, Y);
      const double vz = g->geo == C2D_RZ ? quad_rvol(X, Y) : a;
      if ((!(a > 0.0) || !(vz > 0.0)) && z < o->inv_z) {
        o->inv_z = z;
        o->inv_val = a;
        break;
      }
    }
  const size_t badz = c2d_eos_zones(g, z0, ni, sw->orho + z0, en, sw->op + z0, sw->oc + z0);
  if (badz != SIZE_MAX && badz < o->eos_z) {
    o->eos_z = badz;
    o->eos_val = en[badz - z0];
  }
  if (!sw->corr) return;
  double *dz = erow; /* eⁿ⁺¹ is in e by now */
  dt_row_k(g, n, g->x + n0, g->x + n0 + w, g->y + n0, g->y + n0 + w, g->u + n0, g->u + n0 + w,
           g->v + n0, g->v + n0 + w, g->c + z0, dz);
  for (size_t i = 0; i < ni; ++i) {
    if (dz[i] < o->dt) o->dt = dz[i];
    if ((!isfinite(g->e[z0 + i]) || !isfinite(g->p[z0 + i])) && z0 + i < o->nan_z)
      o->nan_z = z0 + i;
  }
}

/* The corner forces of zone row j (c2d_force_row) into fc, ma; with the limiter, first the edge
 * rows it reads that the thread's rings do not hold yet (rows are visited in increasing order
 * within a phase; *hdone, *vdone: the last node and zone row computed, −1 at a phase's start). */
static void sweep_forces(const c2d_grid *g, const sweep *sw, c2d_scratch *me, size_t j, double *fc,
                         double *ma, long *hdone, long *vdone) {
  const long nj = (long)g->nj, lj = (long)j;
  if (!g->limiter) {
    c2d_force_row(g, j, &sw->in, NULL, fc, ma);
    return;
  }
  for (long n = *hdone + 1 > lj ? *hdone + 1 : lj; n <= lj + 1; ++n)
    c2d_edge_hrow(g, &sw->in, (size_t)n, &me->eh[n & 1]);
  *hdone = lj + 1;
  const long vlo = lj > 0 ? lj - 1 : 0, vhi = lj + 1 < nj ? lj + 1 : nj - 1;
  for (long m = *vdone + 1 > vlo ? *vdone + 1 : vlo; m <= vhi; ++m)
    c2d_edge_vrow(g, &sw->in, (size_t)m, &me->ev[m % 3]);
  *vdone = vhi;
  const c2d_elim lim = {&me->eh[j & 1], &me->eh[(j + 1) & 1], lj > 0 ? &me->ev[(j - 1) % 3] : NULL,
                        &me->ev[j % 3], lj + 1 < nj ? &me->ev[(j + 1) % 3] : NULL};
  c2d_force_row(g, j, &sw->in, &lim, fc, ma);
}

/* Thread t of nt: its band [j0, j1) of zone rows (the first nb = min(nt, nj) threads). */
static bool band_of(size_t nj, int nt, int t, size_t *j0, size_t *j1) {
  const size_t nb = (size_t)nt < nj ? (size_t)nt : nj, ut = (size_t)t;
  if (ut >= nb) return false;
  const size_t q = nj / nb, r = nj % nb;
  *j0 = ut * q + (ut < r ? ut : r);
  *j1 = *j0 + q + (ut < r ? 1 : 0);
  return true;
}

/* Node row n's slot: the band's first node row (t > 0) in the slot the previous band reads. */
static inline nrow node_slot(const c2d_grid *g, const c2d_scratch *s, bool first_of_band,
                             size_t n) {
  (void)g;
  nrow r = {first_of_band ? s->ubb : s->ub[n & 1], first_of_band ? s->vbb : s->vb[n & 1],
            first_of_band ? s->rfb : s->rf[n & 1]};
  return r;
}

static void sweep_thread(c2d_grid *g, const sweep *sw, int nt, int t, sweep_out *o) {
  const size_t nj = g->nj;
  size_t j0 = 0, j1 = 0;
  const bool active = band_of(nj, nt, t, &j0, &j1);
  const bool last = active && j1 == nj;
  c2d_scratch *S = g->scr, *me = &g->scr[t];
  o->inv_z = o->eos_z = o->nan_z = SIZE_MAX;
  o->inv_val = o->eos_val = 0.0;
  o->dt = INFINITY;
  o->dvr = 0.0;
  long hdone = -1, vdone = -1;
  if (active && !last) sweep_forces(g, sw, me, j1 - 1, me->fcb, me->mab, &hdone, &vdone);
  hdone = vdone = -1;
#ifdef _OPENMP
#pragma omp barrier
#endif
  if (active) {
    for (size_t z = j0; z < j1; ++z) {
      const bool mine_b = z == j1 - 1 && !last;
      double *fb = mine_b ? me->fcb : me->fc[z & 1], *mab = mine_b ? me->mab : me->ma[z & 1];
      if (!mine_b) sweep_forces(g, sw, me, z, fb, mab, &hdone, &vdone);
      const double *fa = NULL, *maa = NULL;
      if (z > j0) {
        fa = me->fc[(z - 1) & 1];
        maa = me->ma[(z - 1) & 1];
      } else if (t > 0) {
        fa = S[t - 1].fcb;
        maa = S[t - 1].mab;
      }
      const nrow nr = node_slot(g, me, z == j0 && t > 0, z);
      node_row(g, sw, z, fa, maa, fb, mab, &nr);
      if (z > j0) {
        const nrow lo = node_slot(g, me, z - 1 == j0 && t > 0, z - 1);
        zone_row(g, sw, z - 1, me->fc[(z - 1) & 1], &lo, &nr, me->erow, o);
      }
    }
    if (last) {
      const double *fa = me->fc[(nj - 1) & 1], *maa = me->ma[(nj - 1) & 1];
      const nrow nr = node_slot(g, me, false, nj);
      node_row(g, sw, nj, fa, maa, NULL, NULL, &nr);
      const nrow lo = node_slot(g, me, nj - 1 == j0 && t > 0, nj - 1);
      zone_row(g, sw, nj - 1, fa, &lo, &nr, me->erow, o);
    }
  }
#ifdef _OPENMP
#pragma omp barrier
#endif
  if (active && !last) {
    const nrow lo = node_slot(g, me, j1 - 1 == j0 && t > 0, j1 - 1);
    const nrow hi = node_slot(g, &S[t + 1], true, j1);
    zone_row(g, sw, j1 - 1, me->fcb, &lo, &hi, me->erow, o);
  }
}

/* Runs one sweep on g->nthreads threads; the lowest failing zones, the smallest Courant limit
 * and the largest volume change into *res. */
static void sweep_run(c2d_grid *g, const sweep *sw, sweep_out *res) {
  enum { max_threads = 256 }; /* a bound on the team size (more would not pay on one grid) */
  sweep_out outs[max_threads];
  int nt_used = 1;
  const int nt = g->nthreads < max_threads ? g->nthreads : max_threads;
#ifdef _OPENMP
#pragma omp parallel num_threads(nt)
  {
#pragma omp single
    nt_used = omp_get_num_threads();
    sweep_thread(g, sw, omp_get_num_threads(), omp_get_thread_num(), &outs[omp_get_thread_num()]);
  }
#else
  (void)nt;
  sweep_thread(g, sw, 1, 0, &outs[0]);
#endif
  *res = outs[0];
  for (int t = 1; t < nt_used; ++t) {
    const sweep_out *o = &outs[t];
    if (o->inv_z < res->inv_z) {
      res->inv_z = o->inv_z;
      res->inv_val = o->inv_val;
    }
    if (o->eos_z < res->eos_z) {
      res->eos_z = o->eos_z;
      res->eos_val = o->eos_val;
    }
    if (o->nan_z < res->nan_z) res->nan_z = o->nan_z;
    if (o->dt < res->dt) res->dt = o->dt;
    if (o->dvr > res->dvr) res->dvr = o->dvr;
  }
}

/* The first failure of a sweep's zone state, in the order inverted zone, EOS domain. */
static ms_status state_failure(c2d_grid *g, const sweep_out *o) {
  if (o->inv_z != SIZE_MAX) return c2d_fail_zone(g, o->inv_z, "inverted (area ≤ 0)", o->inv_val);
  if (o->eos_z != SIZE_MAX)
    return c2d_fail_zone(g, o->eos_z, "EOS outside its domain (specific internal energy)",
                         o->eos_val);
  return MS_OK;
}

ms_status c2d_grid_step(c2d_grid *g, double dt_limit) {
  double dt = g->dt_next;
  if (dt > dt_limit) dt = dt_limit;
  if (!(dt >= g->dt_min) && dt_limit >= g->dt_min) {
    snprintf(g->err, sizeof g->err, "step %ld, t = %.9g %s: time step %.3g below dt_min %.3g %s",
             g->step + 1, ms_out_time(g->t), ms_out_time_label(), ms_out_time(dt),
             ms_out_time(g->dt_min), ms_out_time_label());
    return MS_ERR_UNSTABLE;
  }
  c2d_scratch_alloc(g);
  const double t1 = g->t + dt;
  sweep_out res;
  /* Predictor. */
  c2d_boundary_pressure(g, g->x, g->y, g->t);
  const sweep pred = {false,   dt,    t1,    {g->x, g->y, g->u, g->v, g->p, g->rho, g->c},
                      g->xh,   g->yh, g->uh, g->vh,
                      g->rhoh, g->ph, g->ch};
  sweep_run(g, &pred, &res);
  ms_status st = state_failure(g, &res);
  if (st != MS_OK) return st;
  /* Corrector. */
  c2d_boundary_pressure(g, g->xh, g->yh, g->t + 0.5 * dt);
  const sweep corr = {true,   dt,   t1,   {g->xh, g->yh, g->uh, g->vh, g->ph, g->rhoh, g->ch},
                      g->x,   g->y, g->u, g->v,
                      g->rho, g->p, g->c};
  sweep_run(g, &corr, &res);
  /* Boundary work, summed serially in node order (thread-count independent). */
  double work = 0.0;
  const size_t ni = g->ni, nj = g->nj;
  for (size_t j = 0; j <= nj; ++j) {
    if (j == 0 || j == nj)
      for (size_t i = 0; i <= ni; ++i) work += g->wside[wside_index(g, i, j)];
    else {
      work += g->wside[wside_index(g, 0, j)];
      work += g->wside[wside_index(g, ni, j)];
    }
  }
  g->work += work;
  g->t = t1;
  st = state_failure(g, &res);
  if (st != MS_OK) return st;
  g->step++;
  /* Next step: Courant (with the viscosity's compressive |Δu| at tⁿ⁺¹), volume change, growth. */
  double dtn = res.dt;
  if (res.dvr > 0) {
    double dv = g->dv_max / res.dvr * dt;
    if (dv < dtn) dtn = dv;
  }
  if (dtn > g->dt_growth * dt) dtn = g->dt_growth * dt;
  if (dtn > g->dt_max) dtn = g->dt_max;
  g->dt_next = dtn;
  if (res.nan_z != SIZE_MAX)
    return c2d_fail_zone(g, res.nan_z, "non-finite energy or pressure", g->e[res.nan_z]);
  for (size_t k = 0; k < g->ntags; ++k) c2d_tag_record(g, &g->tags[k]);
  return MS_OK;
}

ms_status c2d_grid_run_to(c2d_grid *g, double t_end) {
  while (g->t < t_end * (1.0 - 1e-14)) {
    double lim = t_end - g->t;
    /* Avoid a sliver step at the end. */
    if (g->dt_next < lim && g->dt_next > 0.5 * lim) lim = 0.5 * lim;
    ms_status st = c2d_grid_step(g, lim);
    if (st != MS_OK) return st;
  }
  return MS_OK;
}
