/* SPDX-License-Identifier: MIT */
/* grid2d_impl.h — private to the 2D grid (grid2d.c, the scheme; grid2d_setup.c, set-up and
 * queries): the grid's state, the zone geometry both use, and the scheme's passes that set-up
 * calls. Not for use outside continuum/.
 */
#ifndef MSCALE_GRID2D_IMPL_H
#define MSCALE_GRID2D_IMPL_H

#include "cont2d.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

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

struct c2d_grid {
  c2d_geometry geo;
  size_t ni, nj, nn, nz;
  /* nodes */
  double *x, *y, *u, *v, *M;
  double *xh, *yh, *uh, *vh; /* half-step positions, û */
  double *fx, *fy, *rf;      /* summed scaled corner force, radius factor r̃ */
  double *ex, *ey;           /* outside-pressure force on boundary nodes */
  bool has_pressure;
  double *rx0; /* radial piston: unit direction at t = 0 (x, y interleaved) */
  /* zones */
  double *m, *rho, *e, *p, *c, *vol, *eh, *rhoh, *ph, *ch, *vol_old;
  double *mc;    /* 4 per zone: corner masses */
  double *fc;    /* 8 per zone: corner forces (x, y), scaled by r̃ at the node */
  double *ma;    /* 4 per zone: ρ_z A_c (r–z area mass) */
  double *dumax; /* per zone: largest compressive |Δu| (time step) */
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
  int nthreads;
  char err[512];
};

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

/* ---- grid2d.c: the scheme's passes that set-up also calls ---- */
/* Bilinear shape-function integrals over a quad (2 × 2 Gauss points, exact here):
 * mr[k] = ∫ N_k r dA and ma[k] = ∫ N_k dA (r = X). */
void c2d_fe_lumped(const double X[4], const double Y[4], double mr[4], double ma[4]);
/* Zone pass: planar corner forces (pressure pz, sub-zonal pressure, edge viscosity) at positions
 * (px, py) and velocities (pu, pv); densities rz, sound speeds cz. */
void c2d_zone_forces(c2d_grid *g, const double *px, const double *py, const double *pu,
                     const double *pv, const double *pz, const double *rz, const double *cz);
/* Boundary conditions of node n at time t on the velocity (u, v). Returns true if the node is
 * constrained (its reaction does work). */
bool c2d_apply_bc(const c2d_grid *g, size_t n, double t, double *u, double *v);
/* Volumes, densities at positions (px, py); the EOS for (rho, e) → (p, c). */
ms_status c2d_zone_state(c2d_grid *g, const double *px, const double *py, const double *e,
                         double *vol, double *rho, double *p, double *c);
/* Courant limit over the zones (with the viscosity's compressive |Δu|). */
double c2d_stable_dt(const c2d_grid *g);

/* ---- grid2d_setup.c ---- */
/* Appends the current node positions and velocities to tag line tl's history. */
void c2d_tag_record(const c2d_grid *g, c2d_tagline *tl);

#endif /* MSCALE_GRID2D_IMPL_H */
