/* grid2d.c — the 2D staggered Lagrangian quad grid with the compatible discretisation
 * ([CBSW98], docs/continuum2d.md). Public API in cont2d.h.
 *
 * Corner forces of zone z on its node p (k = 0..3 counter-clockwise), V the zone's area (x–y)
 * or per-radian volume ∫ r dA (r–z):
 *   pressure      f_k = P_z ∂V_z/∂x_k   (x–y: P_z · ½(y_{k+1} − y_{k−1}, x_{k−1} − x_{k+1}))
 *   sub-zonal     f_k += Σ_c δp_c ∂V_c/∂x_k, δp_c = hg c_z² (ρ_c − ρ_z)  ([CS98]; V_c the corner
 *                 quad node – edge midpoint – centre – edge midpoint, ρ_c = m_c/V_c)
 *   viscosity     edge (k, k+1) in compression (Δu·Δx < 0): f_k += q |S| Δu/|Δu|,
 *                 f_{k+1} −= q |S| Δu/|Δu|, S the median from the zone centre to the edge
 *                 midpoint, q = ρ(1−ψ)|Δu|(q2 ζ|Δu| + sqrt(q2²ζ²|Δu|² + q1²c²)) ([CSW98]);
 *                 r–z: times the radius of node k's lumped mass in the zone
 * r–z (control-volume form, docs/continuum2d.md §1–2): node masses lumped with the bilinear
 * shape functions, M_p = Σ_z ρ0 ∫ N_p r dA, which matches P ∂V/∂x (a flow along z stays uniform
 * across r). Option rz_area_weighted: f multiplied by r̃_p = M_p / Σ_c ρ_z A_c on planar
 * gradients (r̃ = 1 otherwise).
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
 * Threads: zones compute their four corner forces into fc[]; nodes gather the (up to) four
 * corners that touch them in a fixed order — no scatter, so results do not depend on the
 * number of threads.
 */
#include "cont2d.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

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

static void *xcalloc(size_t n, size_t sz) { return calloc(n ? n : 1, sz); }

void c2d_setup_defaults(c2d_setup *s) {
  memset(s, 0, sizeof *s);
  s->geometry = C2D_XY;
  s->q1 = 0.5;
  s->q2 = 1.0;
  s->q_gamma = 5.0 / 3.0;
  s->use_limiter = true;
  s->hg_coef = 0.0;
  s->cfl = 0.5;
  s->dv_max = 0.1;
  s->dt_max = INFINITY;
  s->dt_min = 1e-12;
  s->dt_growth = 1.1;
}

/* Zone nodes, counter-clockwise. */
static inline void zone_nodes(const c2d_grid *g, size_t z, size_t nd[4]) {
  size_t i = z % g->ni, j = z / g->ni, w = g->ni + 1;
  nd[0] = i + w * j;
  nd[1] = nd[0] + 1;
  nd[2] = nd[1] + w;
  nd[3] = nd[0] + w;
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

/* ∂V/∂x_k of a 4-vertex polygon: planar area ½(y_{k+1} − y_{k−1}, x_{k−1} − x_{k+1}); in r–z the
 * per-radian volume V = (1/6) Σ (r_k + r_{k+1})(r_k z_{k+1} − r_{k+1} z_k) differentiated. */
static inline void poly_grad(c2d_geometry geo, const double X[4], const double Y[4], double gx[4],
                             double gy[4]) {
  for (int k = 0; k < 4; ++k) {
    int kn = (k + 1) & 3, kp = (k + 3) & 3;
    if (geo == C2D_RZ) {
      gx[k] = ((X[kp] * Y[k] - X[k] * Y[kp]) - (X[kp] + X[k]) * Y[kp] +
               (X[k] * Y[kn] - X[kn] * Y[k]) + (X[k] + X[kn]) * Y[kn]) /
              6.0;
      gy[k] = ((X[kp] + X[k]) * X[kp] - (X[k] + X[kn]) * X[kn]) / 6.0;
    } else {
      gx[k] = 0.5 * (Y[kn] - Y[kp]);
      gy[k] = 0.5 * (X[kp] - X[kn]);
    }
  }
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

static void gather(const c2d_grid *g, size_t z, const double *ax, const double *ay, double X[4],
                   double Y[4]) {
  size_t nd[4];
  zone_nodes(g, z, nd);
  for (int k = 0; k < 4; ++k) {
    X[k] = ax[nd[k]];
    Y[k] = ay[nd[k]];
  }
}

/* Normalised velocity gradient along the node pair a → b (0 if the pair is degenerate). */
static inline void edge_grad(const c2d_grid *g, const double *px, const double *py,
                             const double *pu, const double *pv, size_t a, size_t b, double gr[2]) {
  double dx = px[b] - px[a], dy = py[b] - py[a], l = sqrt(dx * dx + dy * dy);
  (void)g;
  if (l <= 0.0) {
    gr[0] = gr[1] = 0.0;
    return;
  }
  gr[0] = (pu[b] - pu[a]) / l;
  gr[1] = (pv[b] - pv[a]) / l;
}

/* CSW98 limiter ψ for the zone edge from logical node (ia, ja) to (ib, jb) (neighbours along
 * the same logical line; a missing neighbour at the mesh boundary takes the other's ratio). */
static double edge_limiter(const c2d_grid *g, const double *px, const double *py, const double *pu,
                           const double *pv, long ia, long ja, long ib, long jb) {
  long di = ib - ia, dj = jb - ja, w = (long)g->ni + 1;
  double gc[2], gl[2], gr[2];
  edge_grad(g, px, py, pu, pv, (size_t)(ia + w * ja), (size_t)(ib + w * jb), gc);
  double n2 = gc[0] * gc[0] + gc[1] * gc[1];
  if (n2 <= 0.0) return 0.0;
  long il = ia - di, jl = ja - dj, ir = ib + di, jr = jb + dj;
  bool hl = il >= 0 && jl >= 0 && il <= (long)g->ni && jl <= (long)g->nj;
  bool hr = ir >= 0 && jr >= 0 && ir <= (long)g->ni && jr <= (long)g->nj;
  double rl = 0.0, rr = 0.0;
  if (hl) {
    edge_grad(g, px, py, pu, pv, (size_t)(il + w * jl), (size_t)(ia + w * ja), gl);
    rl = (gl[0] * gc[0] + gl[1] * gc[1]) / n2;
  }
  if (hr) {
    edge_grad(g, px, py, pu, pv, (size_t)(ib + w * jb), (size_t)(ir + w * jr), gr);
    rr = (gr[0] * gc[0] + gr[1] * gc[1]) / n2;
  }
  if (!hl && !hr) return 0.0;
  if (!hl) rl = rr;
  if (!hr) rr = rl;
  double psi = 0.5 * (rl + rr);
  if (2.0 * rl < psi) psi = 2.0 * rl;
  if (2.0 * rr < psi) psi = 2.0 * rr;
  if (psi > 1.0) psi = 1.0;
  return psi > 0.0 ? psi : 0.0;
}

/* Bilinear shape-function integrals over a quad (2 × 2 Gauss points, exact here):
 * mr[k] = ∫ N_k r dA and ma[k] = ∫ N_k dA (r = X). */
static void fe_lumped(const double X[4], const double Y[4], double mr[4], double ma[4]) {
  const double gp[2] = {-0.57735026918962576, 0.57735026918962576};
  for (int k = 0; k < 4; ++k) mr[k] = ma[k] = 0.0;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      double xi = gp[a], et = gp[b];
      double N[4] = {0.25 * (1 - xi) * (1 - et), 0.25 * (1 + xi) * (1 - et),
                     0.25 * (1 + xi) * (1 + et), 0.25 * (1 - xi) * (1 + et)};
      double dxi[4] = {-0.25 * (1 - et), 0.25 * (1 - et), 0.25 * (1 + et), -0.25 * (1 + et)};
      double det[4] = {-0.25 * (1 - xi), -0.25 * (1 + xi), 0.25 * (1 + xi), 0.25 * (1 - xi)};
      double r = 0, xx = 0, xe = 0, yx = 0, ye = 0;
      for (int q = 0; q < 4; ++q) {
        r += N[q] * X[q];
        xx += dxi[q] * X[q];
        xe += det[q] * X[q];
        yx += dxi[q] * Y[q];
        ye += det[q] * Y[q];
      }
      double J = xx * ye - xe * yx;
      for (int q = 0; q < 4; ++q) {
        mr[q] += N[q] * r * J;
        ma[q] += N[q] * J;
      }
    }
}

static void fe_radii(const double X[4], const double Y[4], double rb[4]) {
  double mr[4], ma[4];
  fe_lumped(X, Y, mr, ma);
  for (int k = 0; k < 4; ++k) rb[k] = ma[k] > 0 ? mr[k] / ma[k] : 0.0;
}

/* Zone pass: planar corner forces (pressure pz, sub-zonal pressure, edge viscosity) at positions
 * (px, py) and velocities (pu, pv); densities rz, sound speeds cz. */
static void zone_forces(c2d_grid *g, const double *px, const double *py, const double *pu,
                        const double *pv, const double *pz, const double *rz, const double *cz) {
  const long ni = (long)g->ni;
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static)
#endif
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4], U[4], V[4];
    gather(g, z, px, py, X, Y);
    gather(g, z, pu, pv, U, V);
    double *f = g->fc + 8 * z;
    const double P = pz[z];
    double gvx[4], gvy[4];
    const c2d_geometry fg = g->area_weighted ? C2D_XY : g->geo; /* geometry of the gradients */
    poly_grad(fg, X, Y, gvx, gvy);
    size_t nd[4];
    zone_nodes(g, z, nd);
    if (g->geo == C2D_RZ)
      for (int k = 0; k < 4; ++k) {
        double CX[4], CY[4];
        corner_quad(X, Y, 0.25 * (X[0] + X[1] + X[2] + X[3]), 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]), k,
                    CX, CY);
        g->ma[4 * z + k] = rz[z] * quad_area(CX, CY);
      }
    for (int k = 0; k < 4; ++k) {
      f[2 * k] = P * gvx[k];
      f[2 * k + 1] = P * gvy[k];
    }
    double ex[8] = {0, 0, 0, 0, 0, 0, 0, 0}; /* sub-zonal pressure and viscosity */
    double xc = 0.25 * (X[0] + X[1] + X[2] + X[3]), yc = 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]);
    {
      double dpc[4];
      if (g->hg > 0.0) {
        for (int k = 0; k < 4; ++k) {
          double CX[4], CY[4];
          corner_quad(X, Y, xc, yc, k, CX, CY);
          double vc = poly_volume(g->geo, CX, CY);
          dpc[k] = vc > 0.0 ? g->hg * cz[z] * cz[z] * (g->mc[4 * z + k] / vc - rz[z]) : 0.0;
        }
        /* f_q += Σ_c δp_c ∂V_c/∂x_q through the corner vertices (node, midpoints, centre). */
        for (int k = 0; k < 4; ++k) {
          double CX[4], CY[4];
          corner_quad(X, Y, xc, yc, k, CX, CY);
          double gx[4], gy[4];
          poly_grad(fg, CX, CY, gx, gy);
          for (int a = 0; a < 4; ++a) {
            gx[a] *= dpc[k];
            gy[a] *= dpc[k];
          }
          int kn = (k + 1) & 3, kp = (k + 3) & 3;
          ex[2 * k] += gx[0] + 0.5 * (gx[1] + gx[3]);
          ex[2 * k + 1] += gy[0] + 0.5 * (gy[1] + gy[3]);
          ex[2 * kn] += 0.5 * gx[1];
          ex[2 * kn + 1] += 0.5 * gy[1];
          ex[2 * kp] += 0.5 * gx[3];
          ex[2 * kp + 1] += 0.5 * gy[3];
          for (int q = 0; q < 4; ++q) {
            ex[2 * q] += 0.25 * gx[2];
            ex[2 * q + 1] += 0.25 * gy[2];
          }
        }
      }
    }
    /* Edge viscosity, compression only. */
    long i = (long)z % ni, j = (long)z / ni;
    const long li[4] = {i, i + 1, i + 1, i}, lj[4] = {j, j, j + 1, j + 1};
    double dumax = 0.0, vx[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      int kn = (k + 1) & 3;
      double du = U[kn] - U[k], dv = V[kn] - V[k];
      double dx = X[kn] - X[k], dy = Y[kn] - Y[k];
      if (du * dx + dv * dy >= 0.0) continue;
      double adu = sqrt(du * du + dv * dv);
      if (!(adu > 1e-150)) continue; /* |Δu|² underflows: no viscosity (and no 0/0 below) */
      if (adu > dumax) dumax = adu;
      double psi = g->limiter ? edge_limiter(g, px, py, pu, pv, li[k], lj[k], li[kn], lj[kn]) : 0.0;
      double a = g->q2 * g->zeta * adu;
      double q = rz[z] * (1.0 - psi) * adu * (a + sqrt(a * a + g->q1 * g->q1 * cz[z] * cz[z]));
      double sx = 0.5 * (X[k] + X[kn]) - xc, sy = 0.5 * (Y[k] + Y[kn]) - yc;
      /* the median's surface: length |S| (planar), |S| × the radius of its midpoint (r–z) */
      double sa = sqrt(sx * sx + sy * sy);
      double s = q * sa / adu;
      vx[2 * k] += s * du;
      vx[2 * k + 1] += s * dv;
      vx[2 * kn] -= s * du;
      vx[2 * kn + 1] -= s * dv;
    }
    if (fg == C2D_RZ) {
      /* r–z: the planar viscous corner force times r̄_c = ∫N_k r dA / ∫N_k dA, the radius of
       * node k's lumped mass in this zone, so that q accelerates the nodes consistently with
       * their masses (a flow along z stays uniform across r). */
      double rb[4];
      fe_radii(X, Y, rb);
      for (int k = 0; k < 4; ++k) {
        vx[2 * k] *= rb[k];
        vx[2 * k + 1] *= rb[k];
      }
    }
    for (int k = 0; k < 8; ++k) ex[k] += vx[k];
    g->dumax[z] = dumax;
    for (int k = 0; k < 8; ++k) f[k] += ex[k];
  }
}

/* Node pass: gather the corner forces touching each node (fixed order), radius factor. */
static void node_gather(c2d_grid *g) {
  const size_t ni = g->ni, nj = g->nj, w = ni + 1;
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static)
#endif
  for (size_t n = 0; n < g->nn; ++n) {
    size_t i = n % w, j = n / w;
    double sx = 0.0, sy = 0.0, sa = 0.0;
    /* zone (i, j) corner 0, (i−1, j) corner 1, (i−1, j−1) corner 2, (i, j−1) corner 3 */
    if (i < ni && j < nj) {
      size_t z = i + ni * j;
      sx += g->fc[8 * z];
      sy += g->fc[8 * z + 1];
      sa += g->ma[4 * z];
    }
    if (i > 0 && j < nj) {
      size_t z = i - 1 + ni * j;
      sx += g->fc[8 * z + 2];
      sy += g->fc[8 * z + 3];
      sa += g->ma[4 * z + 1];
    }
    if (i > 0 && j > 0) {
      size_t z = i - 1 + ni * (j - 1);
      sx += g->fc[8 * z + 4];
      sy += g->fc[8 * z + 5];
      sa += g->ma[4 * z + 2];
    }
    if (i < ni && j > 0) {
      size_t z = i + ni * (j - 1);
      sx += g->fc[8 * z + 6];
      sy += g->fc[8 * z + 7];
      sa += g->ma[4 * z + 3];
    }
    g->fx[n] = sx;
    g->fy[n] = sy;
    g->rf[n] = g->area_weighted ? g->M[n] / sa : 1.0;
  }
}

/* Outside pressure p(t) on the edges of C2D_BC_PRESSURE sides at positions (px, py): edge a → b
 * (counter-clockwise in its zone, outward normal ∝ (y_b − y_a, x_a − x_b)) pushes its nodes with
 * −p n ∫ N r ds: L/2 each in x–y, L(2r_a + r_b)/6 in r–z (the boundary part of ∂V/∂x, so a
 * matching outside pressure is in exact equilibrium). Serial: boundary nodes only. */
static void boundary_pressure(c2d_grid *g, const double *px, const double *py, double t) {
  if (!g->has_pressure) return;
  const size_t ni = g->ni, nj = g->nj, w = ni + 1;
  for (int s = 0; s < 4; ++s) {
    size_t ne = s < 2 ? nj : ni;
    for (size_t k = 0; k <= ne; ++k) {
      size_t n = s == 0 ? w * k : s == 1 ? ni + w * k : s == 2 ? k : k + w * nj;
      g->ex[n] = g->ey[n] = 0.0;
    }
  }
  for (int s = 0; s < 4; ++s) {
    if (g->bc[s].kind != C2D_BC_PRESSURE) continue;
    double p = cont_fn_eval(&g->bc[s].fn, t);
    size_t ne = s < 2 ? nj : ni;
    for (size_t k = 0; k < ne; ++k) {
      size_t a, b;
      if (s == 0) { /* ILO: (0, k+1) → (0, k) */
        a = w * (k + 1);
        b = w * k;
      } else if (s == 1) { /* IHI: (ni, k) → (ni, k+1) */
        a = ni + w * k;
        b = ni + w * (k + 1);
      } else if (s == 2) { /* JLO: (k, 0) → (k+1, 0) */
        a = k;
        b = k + 1;
      } else { /* JHI: (k+1, nj) → (k, nj) */
        a = k + 1 + w * nj;
        b = k + w * nj;
      }
      double nx = py[b] - py[a], ny = px[a] - px[b]; /* outward normal × L */
      double wa = 0.5, wb = 0.5;
      if (g->geo == C2D_RZ) {
        wa = (2.0 * px[a] + px[b]) / 6.0;
        wb = (px[a] + 2.0 * px[b]) / 6.0;
      }
      g->ex[a] -= p * nx * wa;
      g->ey[a] -= p * ny * wa;
      g->ex[b] -= p * nx * wb;
      g->ey[b] -= p * ny * wb;
    }
  }
}

/* Boundary conditions of node n at time t on the velocity (u, v). Returns true if the node is
 * constrained (its reaction does work). */
static bool apply_bc(const c2d_grid *g, size_t n, double t, double *u, double *v) {
  size_t w = g->ni + 1, i = n % w, j = n / w;
  bool on[4] = {i == 0, i == g->ni, j == 0, j == g->nj};
  bool con = false;
  for (int s = 0; s < 4; ++s) {
    if (!on[s] || g->bc[s].kind != C2D_BC_PISTON) continue;
    double sp = cont_fn_eval(&g->bc[s].fn, t);
    if (g->bc[s].radial) {
      *u = sp * g->rx0[2 * n];
      *v = sp * g->rx0[2 * n + 1];
    } else {
      *u = sp * g->bc[s].dir[0];
      *v = sp * g->bc[s].dir[1];
    }
    con = true;
  }
  for (int s = 0; s < 4; ++s) {
    if (!on[s]) continue;
    if (g->bc[s].kind == C2D_BC_WALL) {
      double nx = g->bc[s].normal[0], ny = g->bc[s].normal[1], un = *u * nx + *v * ny;
      *u -= un * nx;
      *v -= un * ny;
      con = true;
    } else if (g->bc[s].kind == C2D_BC_FIXED) {
      *u = *v = 0.0;
      con = true;
    } else if (g->bc[s].kind == C2D_BC_PRESSURE) {
      con = true; /* the outside pressure does work (booked like a reaction) */
    }
  }
  return con;
}

static ms_status fail_zone(c2d_grid *g, size_t z, const char *what, double value) {
  size_t nd[4];
  zone_nodes(g, z, nd);
  snprintf(g->err, sizeof g->err,
           "step %ld, t = %.9g: %s in zone %zu (i = %zu, j = %zu, near x = %.6g, y = %.6g) = %.6g",
           g->step + 1, g->t, what, z, z % g->ni, z / g->ni, g->x[nd[0]], g->y[nd[0]], value);
  return MS_ERR_UNSTABLE;
}

/* Volumes, densities at positions (px, py); the EOS for (rho, e) → (p, c). */
static ms_status zone_state(c2d_grid *g, const double *px, const double *py, const double *e,
                            double *vol, double *rho, double *p, double *c) {
  size_t bad_zone = (size_t)-1;
  double bad_val = 0.0;
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static)
#endif
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4];
    gather(g, z, px, py, X, Y);
    double a = quad_area(X, Y);
    double vz = g->geo == C2D_RZ ? quad_rvol(X, Y) : a;
    vol[z] = vz;
    rho[z] = g->m[z] / vz;
    if (!(a > 0.0) || !(vz > 0.0)) {
#ifdef _OPENMP
#pragma omp critical
#endif
      if (z < bad_zone) {
        bad_zone = z;
        bad_val = a;
      }
    }
  }
  if (bad_zone != (size_t)-1) return fail_zone(g, bad_zone, "inverted (area ≤ 0)", bad_val);
  for (size_t r = 0; r < g->nruns; ++r) {
    const c2d_run *run = &g->runs[r];
    size_t bad = 0;
    if (eos_eval(run->eos, run->n, rho + run->first, e + run->first, p + run->first, c + run->first,
                 &bad) != MS_OK) {
      size_t z = run->first + bad;
      return fail_zone(g, z, "EOS outside its domain (specific internal energy)", e[z]);
    }
  }
  return MS_OK;
}

static double stable_dt(const c2d_grid *g) {
  double dt = INFINITY;
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static) reduction(min : dt)
#endif
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4];
    gather(g, z, g->x, g->y, X, Y);
    double l2 = INFINITY;
    for (int k = 0; k < 4; ++k) {
      int kn = (k + 1) & 3;
      double dx = X[kn] - X[k], dy = Y[kn] - Y[k], d2 = dx * dx + dy * dy;
      if (d2 > 0.0 && d2 < l2) l2 = d2;
    }
    double a1 = X[2] - X[0], b1 = Y[2] - Y[0], a2 = X[3] - X[1], b2 = Y[3] - Y[1];
    double dd = fmax(a1 * a1 + b1 * b1, a2 * a2 + b2 * b2); /* longest diagonal² */
    double h = 2.0 * quad_area(X, Y) / sqrt(dd);
    double L = sqrt(l2);
    if (h < L) L = h;
    double U[4], V[4], dumax = 0.0;
    gather(g, z, g->u, g->v, U, V);
    for (int k = 0; k < 4; ++k) {
      int kn = (k + 1) & 3;
      double du = U[kn] - U[k], dv = V[kn] - V[k];
      if (du * (X[kn] - X[k]) + dv * (Y[kn] - Y[k]) < 0.0) {
        double a = sqrt(du * du + dv * dv);
        dumax = a > dumax ? a : dumax;
      }
    }
    double qs = 2.0 * g->q2 * g->zeta * dumax;
    double sig = qs + sqrt(qs * qs + g->c[z] * g->c[z]);
    double dz = sig > 0.0 ? g->cfl * L / sig : INFINITY;
    if (dz < dt) dt = dz;
  }
  return dt;
}

c2d_grid *c2d_grid_create(const c2d_setup *s, char *err, size_t errlen) {
  if (s->ni < 1 || s->nj < 1 || !s->x || !s->y || !s->rho || !s->e || !s->eos) {
    snprintf(err, errlen, "2D grid: need ni, nj ≥ 1 and node positions, ρ, e and an EOS per zone");
    return NULL;
  }
  if (!(s->cfl > 0.0 && s->cfl < 1.0) || !(s->dt_growth > 1.0) || s->q1 < 0 || s->q2 < 0 ||
      s->hg_coef < 0) {
    snprintf(err, errlen, "2D grid: need 0 < cfl < 1, dt_growth > 1, q1, q2, hg ≥ 0");
    return NULL;
  }
  c2d_grid *g = xcalloc(1, sizeof *g);
  g->geo = s->geometry;
  g->ni = s->ni;
  g->nj = s->nj;
  g->nn = (s->ni + 1) * (s->nj + 1);
  g->nz = s->ni * s->nj;
  size_t nn = g->nn, nz = g->nz;
  double **na[] = {&g->x,  &g->y,  &g->u,  &g->v,  &g->M,  &g->xh,
                   &g->yh, &g->uh, &g->vh, &g->fx, &g->fy, &g->rf};
  for (size_t k = 0; k < sizeof na / sizeof na[0]; ++k) *na[k] = xcalloc(nn, sizeof(double));
  g->rx0 = xcalloc(2 * nn, sizeof(double));
  g->ex = xcalloc(nn, sizeof(double));
  g->ey = xcalloc(nn, sizeof(double));
  double **za[] = {&g->m,  &g->rho,  &g->e,  &g->p,  &g->c,       &g->vol,
                   &g->eh, &g->rhoh, &g->ph, &g->ch, &g->vol_old, &g->dumax};
  for (size_t k = 0; k < sizeof za / sizeof za[0]; ++k) *za[k] = xcalloc(nz, sizeof(double));
  g->mc = xcalloc(4 * nz, sizeof(double));
  g->ma = xcalloc(4 * nz, sizeof(double));
  g->fc = xcalloc(8 * nz, sizeof(double));
  g->material = xcalloc(nz, sizeof(int));
  g->runs = xcalloc(nz, sizeof(c2d_run));
  g->nthreads = 1;
  memcpy(g->x, s->x, nn * sizeof(double));
  memcpy(g->y, s->y, nn * sizeof(double));
  if (s->u) memcpy(g->u, s->u, nn * sizeof(double));
  if (s->v) memcpy(g->v, s->v, nn * sizeof(double));
  g->q1 = s->q1;
  g->q2 = s->q2;
  g->zeta = 0.25 * (s->q_gamma + 1.0);
  g->limiter = s->use_limiter;
  g->area_weighted = s->geometry == C2D_RZ && s->rz_area_weighted;
  g->hg = s->hg_coef;
  g->cfl = s->cfl;
  g->dv_max = s->dv_max > 0 ? s->dv_max : 0.1;
  g->dt_max = s->dt_max > 0 ? s->dt_max : INFINITY;
  g->dt_min = s->dt_min;
  g->dt_growth = s->dt_growth;
  const double side_normal[4][2] = {{1, 0}, {1, 0}, {0, 1}, {0, 1}};
  for (int k = 0; k < 4; ++k) {
    g->bc[k] = s->bc[k];
    if (g->bc[k].kind == C2D_BC_PRESSURE) g->has_pressure = true;
    cont_fn_copy(&g->bc[k].fn, &s->bc[k].fn);
    if (g->bc[k].kind == C2D_BC_WALL && g->bc[k].normal[0] == 0.0 && g->bc[k].normal[1] == 0.0) {
      g->bc[k].normal[0] = side_normal[k][0];
      g->bc[k].normal[1] = side_normal[k][1];
    }
    double nl = hypot(g->bc[k].normal[0], g->bc[k].normal[1]);
    if (nl > 0) {
      g->bc[k].normal[0] /= nl;
      g->bc[k].normal[1] /= nl;
    }
  }
  for (size_t n = 0; n < nn; ++n) {
    double r = hypot(g->x[n], g->y[n]);
    if (r > 0) {
      g->rx0[2 * n] = g->x[n] / r;
      g->rx0[2 * n + 1] = g->y[n] / r;
    }
    if (g->geo == C2D_RZ && g->x[n] < 0.0) {
      snprintf(err, errlen, "r–z grid: node %zu (i = %zu, j = %zu) has r = %.6g < 0", n,
               n % (g->ni + 1), n / (g->ni + 1), g->x[n]);
      c2d_grid_destroy(g);
      return NULL;
    }
  }
  /* Zones: masses from the corner volumes; tangled zones are reported. */
  for (size_t z = 0; z < nz; ++z) {
    double X[4], Y[4];
    gather(g, z, g->x, g->y, X, Y);
    double a = quad_area(X, Y);
    double xc = 0.25 * (X[0] + X[1] + X[2] + X[3]), yc = 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]);
    bool ok = a > 0.0;
    for (int k = 0; k < 4 && ok; ++k) {
      double CX[4], CY[4];
      corner_quad(X, Y, xc, yc, k, CX, CY);
      if (!(quad_area(CX, CY) > 0.0)) ok = false;
    }
    if (!ok) {
      snprintf(err, errlen,
               "2D grid: zone %zu (i = %zu, j = %zu, near x = %.6g, y = %.6g) is tangled or "
               "inverted (area %.6g, or a corner of non-positive area)",
               z, z % g->ni, z / g->ni, xc, yc, a);
      c2d_grid_destroy(g);
      return NULL;
    }
    if (!(s->rho[z] > 0.0) || !s->eos[z]) {
      snprintf(err, errlen, "2D grid: zone %zu needs ρ > 0 and an EOS", z);
      c2d_grid_destroy(g);
      return NULL;
    }
    g->rho[z] = s->rho[z];
    g->e[z] = s->e[z];
    g->material[z] = s->material ? s->material[z] : 0;
    double mz = 0.0;
    for (int k = 0; k < 4; ++k) {
      double CX[4], CY[4];
      corner_quad(X, Y, xc, yc, k, CX, CY);
      g->mc[4 * z + k] = s->rho[z] * poly_volume(g->geo, CX, CY);
      mz += g->mc[4 * z + k];
    }
    g->m[z] = mz;
    size_t nd[4];
    zone_nodes(g, z, nd);
    if (g->geo == C2D_RZ && !g->area_weighted) {
      /* r–z control-volume form: node masses lumped with the bilinear shape functions,
       * M_p += ρ0 ∫_z N_p r dA (2 × 2 Gauss points, exact for this integrand), the partition
       * that matches the force P ∂V/∂x_p: a flow along z stays uniform across r (the median
       * corner masses make the axis nodes 4/3 too light for their force — axis jetting). */
      double mf[4], maf[4];
      fe_lumped(X, Y, mf, maf);
      /* scale so that Σ_p M_p = Σ_z m_z exactly (the quadrature is exact up to round-off) */
      double sm = mf[0] + mf[1] + mf[2] + mf[3];
      for (int k = 0; k < 4; ++k) g->M[nd[k]] += mz * mf[k] / sm;
    } else {
      for (int k = 0; k < 4; ++k) g->M[nd[k]] += g->mc[4 * z + k];
    }
    if (g->nruns == 0 || g->runs[g->nruns - 1].eos != s->eos[z]) {
      g->runs[g->nruns].first = z;
      g->runs[g->nruns].eos = s->eos[z];
      g->runs[g->nruns].n = 0;
      g->nruns++;
    }
    g->runs[g->nruns - 1].n++;
  }
  for (size_t n = 0; n < nn; ++n) {
    if (!(g->M[n] > 0.0)) {
      /* Degenerate r = 0 nodes of an r–z polar centre carry no mass; they must be fixed. */
      g->M[n] = 0.0;
    }
  }
  if (zone_state(g, g->x, g->y, g->e, g->vol, g->rho, g->p, g->c) != MS_OK) {
    snprintf(err, errlen, "2D grid at set-up: %s", g->err);
    c2d_grid_destroy(g);
    return NULL;
  }
  for (size_t n = 0; n < nn; ++n) apply_bc(g, n, 0.0, &g->u[n], &g->v[n]);
  zone_forces(g, g->x, g->y, g->u, g->v, g->p, g->rho, g->c);
  double dt = stable_dt(g);
  g->dt_next = s->dt_initial > 0 ? s->dt_initial : 0.1 * dt;
  if (!isfinite(g->dt_next)) g->dt_next = g->dt_max < INFINITY ? g->dt_max : 1e-6;
  return g;
}

void c2d_grid_destroy(c2d_grid *g) {
  if (!g) return;
  double *arr[] = {g->x,    g->y,  g->u,   g->v,       g->M,   g->xh, g->yh, g->uh,   g->vh,  g->fx,
                   g->fy,   g->rf, g->rx0, g->m,       g->rho, g->e,  g->p,  g->c,    g->vol, g->eh,
                   g->rhoh, g->ph, g->ch,  g->vol_old, g->mc,  g->ma, g->fc, g->dumax};
  for (size_t k = 0; k < sizeof arr / sizeof arr[0]; ++k) free(arr[k]);
  for (int k = 0; k < 4; ++k) cont_fn_free(&g->bc[k].fn);
  free(g->ex);
  free(g->ey);
  for (size_t k = 0; k < g->ntags; ++k) {
    c2d_tagline *tl = &g->tags[k];
    free(tl->name);
    free(tl->node);
    free(tl->t);
    free(tl->x);
    free(tl->y);
    free(tl->u);
    free(tl->v);
  }
  free(g->tags);
  free(g->material);
  free(g->runs);
  free(g);
}

/* Acceleration of node n from the gathered planar force. */
static inline void node_accel(const c2d_grid *g, size_t n, double *ax, double *ay) {
  double M = g->M[n];
  if (!(M > 0.0)) {
    *ax = *ay = 0.0;
    return;
  }
  *ax = (g->rf[n] * g->fx[n] + g->ex[n]) / M;
  *ay = (g->rf[n] * g->fy[n] + g->ey[n]) / M;
}

/* Work rate −Σ_c r̃ f_c·w of zone z with node velocities (wu, wv). */
static inline double zone_work(const c2d_grid *g, size_t z, const double *wu, const double *wv) {
  size_t nd[4];
  zone_nodes(g, z, nd);
  const double *f = g->fc + 8 * z;
  double s = 0.0;
  for (int k = 0; k < 4; ++k) {
    double r = g->rf[nd[k]];
    s += r * (f[2 * k] * wu[nd[k]] + f[2 * k + 1] * wv[nd[k]]);
  }
  return s;
}

static void tag_record(const c2d_grid *g, c2d_tagline *tl) {
  if (tl->n + 1 > tl->cap) {
    size_t cap = tl->cap ? 2 * tl->cap : 256;
    tl->t = ms_realloc(tl->t, cap, sizeof(double));
    double **cols[] = {&tl->x, &tl->y, &tl->u, &tl->v};
    for (int c = 0; c < 4; ++c) *cols[c] = ms_realloc(*cols[c], cap * tl->nnodes, sizeof(double));
    tl->cap = cap;
  }
  size_t r = tl->n * tl->nnodes;
  tl->t[tl->n] = g->t;
  for (size_t k = 0; k < tl->nnodes; ++k) {
    size_t nd = tl->node[k];
    tl->x[r + k] = g->x[nd];
    tl->y[r + k] = g->y[nd];
    tl->u[r + k] = g->u[nd];
    tl->v[r + k] = g->v[nd];
  }
  tl->n++;
}

size_t c2d_grid_add_tag_line(c2d_grid *g, const char *name, bool along_i, size_t index) {
  if (g->ntags == g->tag_cap) {
    g->tag_cap = g->tag_cap ? 2 * g->tag_cap : 4;
    g->tags = ms_realloc(g->tags, g->tag_cap, sizeof(c2d_tagline));
  }
  c2d_tagline *tl = &g->tags[g->ntags];
  memset(tl, 0, sizeof *tl);
  tl->name = ms_strdup(name ? name : "line");
  size_t w = g->ni + 1;
  if (along_i) {
    if (index > g->nj) index = g->nj;
    tl->nnodes = g->ni + 1;
    tl->node = xcalloc(tl->nnodes, sizeof(size_t));
    for (size_t i = 0; i <= g->ni; ++i) tl->node[i] = i + w * index;
  } else {
    if (index > g->ni) index = g->ni;
    tl->nnodes = g->nj + 1;
    tl->node = xcalloc(tl->nnodes, sizeof(size_t));
    for (size_t j = 0; j <= g->nj; ++j) tl->node[j] = index + w * j;
  }
  tag_record(g, tl);
  return g->ntags++;
}

size_t c2d_grid_ntag_lines(const c2d_grid *g) { return g->ntags; }

c2d_line_history c2d_grid_line_history(const c2d_grid *g, size_t tag) {
  c2d_line_history h;
  memset(&h, 0, sizeof h);
  if (tag >= g->ntags) return h;
  const c2d_tagline *tl = &g->tags[tag];
  h.name = tl->name;
  h.nnodes = tl->nnodes;
  h.node = tl->node;
  h.n = tl->n;
  h.t = tl->t;
  h.x = tl->x;
  h.y = tl->y;
  h.u = tl->u;
  h.v = tl->v;
  return h;
}

ms_status c2d_grid_step(c2d_grid *g, double dt_limit) {
  double dt = g->dt_next;
  if (dt > dt_limit) dt = dt_limit;
  if (!(dt >= g->dt_min) && dt_limit >= g->dt_min) {
    snprintf(g->err, sizeof g->err, "step %ld, t = %.9g: time step %.3g below dt_min %.3g",
             g->step + 1, g->t, dt, g->dt_min);
    return MS_ERR_UNSTABLE;
  }
  const double t1 = g->t + dt;
  const size_t nn = g->nn, nz = g->nz;
  /* Predictor. */
  zone_forces(g, g->x, g->y, g->u, g->v, g->p, g->rho, g->c);
  node_gather(g);
  boundary_pressure(g, g->x, g->y, g->t);
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static)
#endif
  for (size_t n = 0; n < nn; ++n) {
    double ax, ay;
    node_accel(g, n, &ax, &ay);
    double us = g->u[n] + dt * ax, vs = g->v[n] + dt * ay;
    apply_bc(g, n, t1, &us, &vs);
    g->uh[n] = 0.5 * (g->u[n] + us);
    g->vh[n] = 0.5 * (g->v[n] + vs);
    g->xh[n] = g->x[n] + 0.5 * dt * g->uh[n];
    g->yh[n] = g->y[n] + 0.5 * dt * g->vh[n];
  }
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static)
#endif
  for (size_t z = 0; z < nz; ++z)
    g->eh[z] = g->e[z] - 0.5 * dt * zone_work(g, z, g->uh, g->vh) / g->m[z];
  ms_status st = zone_state(g, g->xh, g->yh, g->eh, g->vol_old, g->rhoh, g->ph, g->ch);
  if (st != MS_OK) return st;
  /* Corrector. */
  zone_forces(g, g->xh, g->yh, g->uh, g->vh, g->ph, g->rhoh, g->ch);
  node_gather(g);
  boundary_pressure(g, g->xh, g->yh, g->t + 0.5 * dt);
  double work = 0.0;
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static)
#endif
  for (size_t n = 0; n < nn; ++n) {
    double ax, ay;
    node_accel(g, n, &ax, &ay);
    double u1 = g->u[n] + dt * ax, v1 = g->v[n] + dt * ay;
    bool con = apply_bc(g, n, t1, &u1, &v1);
    double ub = 0.5 * (g->u[n] + u1), vb = 0.5 * (g->v[n] + v1);
    /* Reaction work at constrained nodes: ΔKE minus the work of the grid's own forces. */
    g->xh[n] = con ? g->M[n] * ((u1 - g->u[n]) * ub + (v1 - g->v[n]) * vb) -
                         dt * g->rf[n] * (g->fx[n] * ub + g->fy[n] * vb)
                   : 0.0;
    g->uh[n] = ub;
    g->vh[n] = vb;
    g->u[n] = u1;
    g->v[n] = v1;
    g->x[n] += dt * ub;
    g->y[n] += dt * vb;
  }
  for (size_t n = 0; n < nn; ++n) work += g->xh[n]; /* serial: thread-count independent */
  g->work += work;
#ifdef _OPENMP
#pragma omp parallel for num_threads(g->nthreads) schedule(static)
#endif
  for (size_t z = 0; z < nz; ++z) {
    g->vol_old[z] = g->vol[z];
    g->e[z] -= dt * zone_work(g, z, g->uh, g->vh) / g->m[z];
  }
  g->t = t1;
  st = zone_state(g, g->x, g->y, g->e, g->vol, g->rho, g->p, g->c);
  if (st != MS_OK) return st;
  g->step++;
  /* Next step: Courant (with the viscosity's compressive |Δu| at tⁿ⁺¹), volume change, growth. */
  double dtn = stable_dt(g);
  double dvr = 0.0;
  for (size_t z = 0; z < nz; ++z) {
    double r = fabs(g->vol[z] - g->vol_old[z]) / g->vol[z];
    if (r > dvr) dvr = r;
  }
  if (dvr > 0) {
    double dv = g->dv_max / dvr * dt;
    if (dv < dtn) dtn = dv;
  }
  if (dtn > g->dt_growth * dt) dtn = g->dt_growth * dt;
  if (dtn > g->dt_max) dtn = g->dt_max;
  g->dt_next = dtn;
  for (size_t z = 0; z < nz; ++z)
    if (!isfinite(g->e[z]) || !isfinite(g->p[z]))
      return fail_zone(g, z, "non-finite energy or pressure", g->e[z]);
  for (size_t k = 0; k < g->ntags; ++k) tag_record(g, &g->tags[k]);
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

const char *c2d_grid_error(const c2d_grid *g) { return g->err; }
double c2d_grid_time(const c2d_grid *g) { return g->t; }
long c2d_grid_steps(const c2d_grid *g) { return g->step; }
void c2d_grid_set_threads(c2d_grid *g, int nthreads) { g->nthreads = nthreads > 0 ? nthreads : 1; }

c2d_view c2d_grid_view(const c2d_grid *g) {
  c2d_view v = {g->ni, g->nj,  g->nn, g->nz, g->x, g->y, g->u,   g->v,
                g->M,  g->rho, g->e,  g->p,  g->c, g->m, g->vol, g->material};
  return v;
}

c2d_balance c2d_grid_balance(const c2d_grid *g) {
  c2d_balance b = {0, 0, g->work};
  for (size_t z = 0; z < g->nz; ++z) b.internal += g->m[z] * g->e[z];
  for (size_t n = 0; n < g->nn; ++n)
    b.kinetic += 0.5 * g->M[n] * (g->u[n] * g->u[n] + g->v[n] * g->v[n]);
  return b;
}

void c2d_grid_hourglass(const c2d_grid *g, double *hg_rms, double *rho_spread) {
  double s = 0.0, ms = 0.0, spread = 0.0;
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4];
    gather(g, z, g->x, g->y, X, Y);
    double a = quad_area(X, Y);
    double hx = X[0] - X[1] + X[2] - X[3], hy = Y[0] - Y[1] + Y[2] - Y[3];
    s += g->m[z] * (hx * hx + hy * hy) / a;
    ms += g->m[z];
    double xc = 0.25 * (X[0] + X[1] + X[2] + X[3]), yc = 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]);
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 4; ++k) {
      double CX[4], CY[4];
      corner_quad(X, Y, xc, yc, k, CX, CY);
      double rc = g->mc[4 * z + k] / poly_volume(g->geo, CX, CY);
      lo = rc < lo ? rc : lo;
      hi = rc > hi ? rc : hi;
    }
    double sp = (hi - lo) / g->rho[z];
    if (sp > spread) spread = sp;
  }
  *hg_rms = sqrt(s / ms);
  *rho_spread = spread;
}

double c2d_grid_min_area(const c2d_grid *g, size_t *zone) {
  double amin = INFINITY;
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4];
    gather(g, z, g->x, g->y, X, Y);
    double a = quad_area(X, Y);
    if (a < amin) {
      amin = a;
      if (zone) *zone = z;
    }
  }
  return amin;
}
