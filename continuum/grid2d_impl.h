/* SPDX-License-Identifier: MIT */
/* grid2d_impl.h — private to the 2D grid (grid2d.c, the scheme's kernels; grid2d_step.c, the
 * time step; grid2d_setup.c, set-up and queries): the grid's state, the zone geometry they use,
 * and the kernels they share. Not for use outside continuum/.
 */
#ifndef MSCALE_GRID2D_IMPL_H
#define MSCALE_GRID2D_IMPL_H

#include "cont2d.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

/* The zone- and node-row kernels are dispatched at run time in a portable build
 * (MS_KERNEL_CLONES, core.h). The build is C11 without contraction (no FMA), so a clone
 * changes the vector width only: the row sums of the energy kernel may round differently from
 * one CPU to another, never from one thread count to another. */

typedef struct c2d_tagline {
  char *name;
  size_t nnodes, *node;
  size_t n, cap;
  double *t, *x, *y, *u, *v;
} c2d_tagline;

typedef struct c2d_run {
  size_t first, n;
  const eos_t *eos;
} c2d_run;

/* Velocity gradients of a row of edges: g = Δu/l along the edge, ic = 1/|g|². */
typedef struct c2d_erow {
  double *gx, *gy, *ic;
} c2d_erow;

/* Per-thread scratch of the time step's sweeps (grid2d_step.c): corner forces and r–z corner
 * area masses of two zone rows (a ring) and of the band's last zone row (read by the next
 * band); ū, v̄ and r̃ of two node rows and of the band's first node row (read by the previous
 * band); the energies of one zone row for its EOS call; the limiter's edge rows. */
typedef struct c2d_scratch {
  double *fc[2], *ma[2], *fcb, *mab;
  double *ub[2], *vb[2], *rf[2], *ubb, *vbb, *rfb;
  double *erow;
  c2d_erow eh[2],
      ev[3]; /* limiter edge rows: along node rows (n mod 2), across zone rows (mod 3) */
} c2d_scratch;

struct c2d_grid {
  c2d_geometry geo;
  size_t ni, nj, nn, nz;
  /* nodes */
  double *x, *y, *u, *v, *M;
  double *xh, *yh, *uh, *vh; /* half-step positions, û */
  double *ex, *ey;           /* outside-pressure force on boundary nodes */
  bool has_pressure;
  double *rx0;   /* radial piston: unit direction at t = 0 (x, y interleaved) */
  double *wside; /* boundary work of the side nodes in the last corrector (2(ni+1) + 2(nj+1)) */
  /* zones */
  double *m, *rho, *e, *p, *c, *vol, *rhoh, *ph, *ch;
  double *mc; /* 4 per zone: corner masses */
  int *material;
  size_t nruns;
  c2d_run *runs;
  c2d_bc bc[4];
  double q1, q2, zeta, hg;
  bool limiter, area_weighted;
  double cfl, dv_max, dt_max, dt_min, dt_growth, dt_next;
  double t, work;
  long step;
  size_t ntags, tag_cap;
  c2d_tagline *tags;
  int nthreads, nscratch;
  c2d_scratch *scr; /* nscratch ≥ nthreads */
  char err[512];
};

/* What a force pass sees: node positions and velocities, zone pressure, density, sound speed. */
typedef struct c2d_fstate {
  const double *x, *y, *u, *v, *p, *rho, *c;
} c2d_fstate;

/* Zone nodes, counter-clockwise. */
static inline void zone_nodes(const c2d_grid *g, size_t z, size_t nd[4]) {
  size_t i = z % g->ni, j = z / g->ni, w = g->ni + 1;
  nd[0] = i + w * j;
  nd[1] = nd[0] + 1;
  nd[2] = nd[1] + w;
  nd[3] = nd[0] + w;
}

/* The same for zone (i, j), without dividing its index. */
static inline void zone_nodes_ij(const c2d_grid *g, size_t i, size_t j, size_t nd[4]) {
  const size_t w = g->ni + 1;
  nd[0] = i + w * j;
  nd[1] = nd[0] + 1;
  nd[2] = nd[1] + w;
  nd[3] = nd[0] + w;
}

static inline void gather_nd(const size_t nd[4], const double *ax, const double *ay, double X[4],
                             double Y[4]) {
  for (int k = 0; k < 4; ++k) {
    X[k] = ax[nd[k]];
    Y[k] = ay[nd[k]];
  }
}

static inline double quad_area(const double X[4], const double Y[4]) {
  return 0.5 * ((X[0] - X[2]) * (Y[1] - Y[3]) - (X[1] - X[3]) * (Y[0] - Y[2]));
}

/* ∫ r dA over a polygon (per radian): (1/6) Σ (r_k + r_{k+1})(r_k z_{k+1} − r_{k+1} z_k). */
static inline double quad_rvol(const double X[4], const double Y[4]) {
  double s = 0.0;
  for (int k = 0; k < 4; ++k) {
    int l = (k + 1) & 3;
    s += (X[k] + X[l]) * (X[k] * Y[l] - X[l] * Y[k]);
  }
  return s / 6.0;
}

static inline double poly_volume(c2d_geometry geo, const double X[4], const double Y[4]) {
  return geo == C2D_RZ ? quad_rvol(X, Y) : quad_area(X, Y);
}
/* Corner quad of corner k: node, midpoint to next, centre, midpoint from previous. */
static inline void corner_quad(const double X[4], const double Y[4], double xc, double yc, int k,
                               double CX[4], double CY[4]) {
  int kn = (k + 1) & 3, kp = (k + 3) & 3;
  CX[0] = X[k];
  CY[0] = Y[k];
  CX[1] = 0.5 * (X[k] + X[kn]);
  CY[1] = 0.5 * (Y[k] + Y[kn]);
  CX[2] = xc;
  CY[2] = yc;
  CX[3] = 0.5 * (X[k] + X[kp]);
  CY[3] = 0.5 * (Y[k] + Y[kp]);
}

static inline void gather(const c2d_grid *g, size_t z, const double *ax, const double *ay,
                          double X[4], double Y[4]) {
  size_t nd[4];
  zone_nodes(g, z, nd);
  for (int k = 0; k < 4; ++k) {
    X[k] = ax[nd[k]];
    Y[k] = ay[nd[k]];
  }
}

/* Courant limit of one zone (corners X, Y, velocities U, V, sound speed c): cfl L / σ, L the
 * smaller of the shortest edge and twice the area over the longest diagonal, σ = q_s +
 * sqrt(q_s² + c²) with q_s = 2 q2 ζ |Δu|max over the compressive edges. */
static inline double c2d_zone_dt(const c2d_grid *g, const double X[4], const double Y[4],
                                 const double U[4], const double V[4], double c) {
  double l2 = INFINITY;
  for (int k = 0; k < 4; ++k) {
    int kn = (k + 1) & 3;
    double dx = X[kn] - X[k], dy = Y[kn] - Y[k], e2 = dx * dx + dy * dy;
    l2 = e2 > 0.0 && e2 < l2 ? e2 : l2;
  }
  double a1 = X[2] - X[0], b1 = Y[2] - Y[0], a2 = X[3] - X[1], b2 = Y[3] - Y[1];
  const double d1 = a1 * a1 + b1 * b1, d2 = a2 * a2 + b2 * b2;
  const double dd = d1 > d2 ? d1 : d2; /* longest diagonal² */
  double h = 2.0 * quad_area(X, Y) / sqrt(dd);
  double L = sqrt(l2);
  if (h < L) L = h;
  double du2 = 0.0; /* the largest compressive |Δu|²: one sqrt (sqrt is monotonic) */
  for (int k = 0; k < 4; ++k) {
    int kn = (k + 1) & 3;
    double du = U[kn] - U[k], dv = V[kn] - V[k], a2 = du * du + dv * dv;
    du2 = du * (X[kn] - X[k]) + dv * (Y[kn] - Y[k]) < 0.0 && a2 > du2 ? a2 : du2;
  }
  const double dumax = sqrt(du2);
  double qs = 2.0 * g->q2 * g->zeta * dumax;
  double sig = qs + sqrt(qs * qs + c * c);
  return sig > 0.0 ? g->cfl * L / sig : INFINITY;
}

/* The edge rows the limiter of zone row j reads: along node rows j (hlo) and j + 1 (hhi), across
 * zone rows j − 1 (vm; NULL at j = 0), j (v0) and j + 1 (vp; NULL at j = nj − 1). */
typedef struct c2d_elim {
  const c2d_erow *hlo, *hhi, *vm, *v0, *vp;
} c2d_elim;

/* ---- grid2d.c: the scheme's kernels (the time step and set-up call them) ---- */
/* Bilinear shape-function integrals over a quad (2 × 2 Gauss points, exact here):
 * mr[k] = ∫ N_k r dA and ma[k] = ∫ N_k dA (r = X). */
void c2d_fe_lumped(const double X[4], const double Y[4], double mr[4], double ma[4]);
/* The corner forces of zone row j from the state s: fc[8 i + 2k (+1)] the x (y) force of zone
 * (i, j) on its corner k (pressure, sub-zonal pressure, edge viscosity), ma[4 i + k] its r–z
 * corner area masses ρ_z A_c. */
void c2d_force_row(const c2d_grid *g, size_t j, const c2d_fstate *s, const c2d_elim *lim,
                   double *restrict fc, double *restrict ma);
/* Edge rows of the limiter (c2d_elim) at the state s: along node row n (ni edges), across zone
 * row j (ni + 1 edges). */
void c2d_edge_hrow(const c2d_grid *g, const c2d_fstate *s, size_t n, c2d_erow *e);
void c2d_edge_vrow(const c2d_grid *g, const c2d_fstate *s, size_t j, c2d_erow *e);
/* Outside pressure p(t) on the C2D_BC_PRESSURE sides at positions (px, py) into ex, ey. */
void c2d_boundary_pressure(c2d_grid *g, const double *px, const double *py, double t);
/* Boundary conditions of node n = (i, j) at time t on the velocity (u, v). Returns true if the
 * node is constrained (its reaction does work). */
bool c2d_apply_bc_ij(const c2d_grid *g, size_t i, size_t j, size_t n, double t, double *u,
                     double *v);
bool c2d_apply_bc(const c2d_grid *g, size_t n, double t, double *u, double *v);
/* The EOS over zones [z0, z0 + n): (rho, e) → (p, c), arrays starting at zone z0. Returns the
 * first zone outside its EOS's domain, or (size_t)-1. */
size_t c2d_eos_zones(const c2d_grid *g, size_t z0, size_t n, const double *rho, const double *e,
                     double *p, double *c);
/* Records the run-time failure of zone z (what, value) in g->err; returns MS_ERR_UNSTABLE. */
ms_status c2d_fail_zone(c2d_grid *g, size_t z, const char *what, double value);
/* Volumes, densities at positions (px, py); the EOS for (rho, e) → (p, c) (set-up). */
ms_status c2d_zone_state(c2d_grid *g, const double *px, const double *py, const double *e,
                         double *vol, double *rho, double *p, double *c);
/* Courant limit over the zones (set-up). */
double c2d_stable_dt(const c2d_grid *g);

/* ---- grid2d_step.c ---- */
/* (Re)allocates the sweeps' per-thread scratch for g->nthreads threads. */
void c2d_scratch_alloc(c2d_grid *g);
void c2d_scratch_free(c2d_grid *g);

/* ---- grid2d_setup.c ---- */
/* Appends the current node positions and velocities to tag line tl's history. */
void c2d_tag_record(const c2d_grid *g, c2d_tagline *tl);

#endif /* MSCALE_GRID2D_IMPL_H */
