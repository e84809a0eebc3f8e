/* SPDX-License-Identifier: MIT */
/* grid2d.c — the 2D staggered Lagrangian quad grid with the compatible discretisation
 * ([CBSW98], docs/continuum2d.md): the corner forces, the boundary conditions, the zone update
 * and the time step. Public API in cont2d.h; set-up, tag lines and queries: grid2d_setup.c.
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
#include "grid2d_impl.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

/* The share of the calling thread of [0, count) items of a row-major (width) index space, as
 * schedule(static) would give it (contiguous, in thread order), and the (i, j) of its first item;
 * the loops then step i, j without dividing every index. */
static inline void thread_share(size_t count, size_t width, size_t lo_hi[2], size_t *i, size_t *j) {
#ifdef _OPENMP
  const size_t nt = (size_t)omp_get_num_threads(), t = (size_t)omp_get_thread_num();
#else
  const size_t nt = 1, t = 0;
#endif
  const size_t q = count / nt, r = count % nt;
  lo_hi[0] = t * q + (t < r ? t : r);
  lo_hi[1] = lo_hi[0] + q + (t < r ? 1 : 0);
  *i = lo_hi[0] % width;
  *j = lo_hi[0] / width;
}
/* for (i, j) over the calling thread's share (thread_share) of count items, width per row;
 * the body sees i and j (and q_, the linear index). */
#define FOR_SHARE(count, width)                                                                    \
  for (size_t q_ = 0, lh_[2], i = 0, j = 0; q_ == 0; q_ = 1)                                       \
    for (thread_share((count), (width), lh_, &i, &j), q_ = lh_[0]; q_ < lh_[1];                    \
         ++q_, i = i + 1 == (width) ? 0 : i + 1, j += i == 0)

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
void c2d_fe_lumped(const double X[4], const double Y[4], double mr[4], double ma[4]) {
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
  c2d_fe_lumped(X, Y, mr, ma);
  for (int k = 0; k < 4; ++k) rb[k] = ma[k] > 0 ? mr[k] / ma[k] : 0.0;
}

/* The corner forces of zone z = (i, j) (c2d_zone_forces). The zone loops run over rows and
 * columns so that no zone divides its index (the divisions were a visible share of the pass). */
static inline __attribute__((always_inline)) void
zone_force(c2d_grid *g, size_t i0, size_t j0, const double *px, const double *py, const double *pu,
           const double *pv, const double *pz, const double *rz, const double *cz) {
  const size_t z = i0 + g->ni * j0;
  size_t nd[4];
  zone_nodes_ij(g, i0, j0, nd);
  double X[4], Y[4], U[4], V[4];
  gather_nd(nd, px, py, X, Y);
  gather_nd(nd, pu, pv, U, V);
  {
    double *f = g->fc + 8 * z;
    const double P = pz[z];
    double gvx[4], gvy[4];
    const c2d_geometry fg = g->area_weighted ? C2D_XY : g->geo; /* geometry of the gradients */
    poly_grad(fg, X, Y, gvx, gvy);
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
    const long i = (long)i0, j = (long)j0;
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

/* Zone pass: planar corner forces (pressure pz, sub-zonal pressure, edge viscosity) at positions
 * (px, py) and velocities (pu, pv); densities rz, sound speeds cz. */
void c2d_zone_forces(c2d_grid *g, const double *px, const double *py, const double *pu,
                     const double *pv, const double *pz, const double *rz, const double *cz) {
#ifdef _OPENMP
#pragma omp parallel num_threads(g->nthreads)
#endif
  FOR_SHARE(g->nz, g->ni) zone_force(g, i, j, px, py, pu, pv, pz, rz, cz);
}

/* Node pass: gather the corner forces touching each node (fixed order), radius factor. */
static void node_gather(c2d_grid *g) {
  const size_t ni = g->ni, nj = g->nj, w = ni + 1;
#ifdef _OPENMP
#pragma omp parallel num_threads(g->nthreads)
#endif
  FOR_SHARE(g->nn, (g->ni + 1)) {
    const size_t n = i + w * j;
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
static bool apply_bc_ij(const c2d_grid *g, size_t i, size_t j, size_t n, double t, double *u,
                        double *v) {
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

bool c2d_apply_bc(const c2d_grid *g, size_t n, double t, double *u, double *v) {
  const size_t w = g->ni + 1;
  return apply_bc_ij(g, n % w, n / w, n, t, u, v);
}

/* Only the nodes of the mesh's sides can be constrained (an interior node: nothing to do). */
static inline bool on_side(const c2d_grid *g, size_t i, size_t j) {
  return i == 0 || j == 0 || i == g->ni || j == g->nj;
}

static ms_status fail_zone(c2d_grid *g, size_t z, const char *what, double value) {
  size_t nd[4];
  zone_nodes(g, z, nd);
  snprintf(g->err, sizeof g->err,
           "step %ld, t = %.9g %s: %s in zone %zu (i = %zu, j = %zu, near x = %.6g, y = %.6g cm) "
           "= %.6g",
           g->step + 1, ms_out_time(g->t), ms_out_time_label(), what, z, z % g->ni, z / g->ni,
           g->x[nd[0]], g->y[nd[0]], value);
  return MS_ERR_UNSTABLE;
}

/* Volumes, densities at positions (px, py); the EOS for (rho, e) → (p, c). */
ms_status c2d_zone_state(c2d_grid *g, const double *px, const double *py, const double *e,
                         double *vol, double *rho, double *p, double *c) {
  size_t bad_zone = (size_t)-1;
  double bad_val = 0.0;
#ifdef _OPENMP
#pragma omp parallel num_threads(g->nthreads)
#endif
  FOR_SHARE(g->nz, g->ni) {
    const size_t z = i + g->ni * j;
    size_t nd[4];
    zone_nodes_ij(g, i, j, nd);
    double X[4], Y[4];
    gather_nd(nd, px, py, X, Y);
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

double c2d_stable_dt(const c2d_grid *g) {
  double dt = INFINITY;
#ifdef _OPENMP
#pragma omp parallel num_threads(g->nthreads) reduction(min : dt)
#endif
  FOR_SHARE(g->nz, g->ni) {
    const size_t z = i + g->ni * j;
    size_t nd[4];
    zone_nodes_ij(g, i, j, nd);
    double X[4], Y[4];
    gather_nd(nd, g->x, g->y, X, Y);
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
    gather_nd(nd, g->u, g->v, U, V);
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
static inline double zone_work(const c2d_grid *g, size_t i, size_t j, const double *wu,
                               const double *wv) {
  const size_t z = i + g->ni * j;
  size_t nd[4];
  zone_nodes_ij(g, i, j, nd);
  const double *f = g->fc + 8 * z;
  double s = 0.0;
  for (int k = 0; k < 4; ++k) {
    double r = g->rf[nd[k]];
    s += r * (f[2 * k] * wu[nd[k]] + f[2 * k + 1] * wv[nd[k]]);
  }
  return s;
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
  const double t1 = g->t + dt;
  const size_t nn = g->nn, nz = g->nz, ni = g->ni;
  /* Predictor. */
  c2d_zone_forces(g, g->x, g->y, g->u, g->v, g->p, g->rho, g->c);
  node_gather(g);
  boundary_pressure(g, g->x, g->y, g->t);
#ifdef _OPENMP
#pragma omp parallel num_threads(g->nthreads)
#endif
  FOR_SHARE(g->nn, (g->ni + 1)) {
    const size_t n = i + (ni + 1) * j;
    double ax, ay;
    node_accel(g, n, &ax, &ay);
    double us = g->u[n] + dt * ax, vs = g->v[n] + dt * ay;
    if (on_side(g, i, j)) apply_bc_ij(g, i, j, n, t1, &us, &vs);
    g->uh[n] = 0.5 * (g->u[n] + us);
    g->vh[n] = 0.5 * (g->v[n] + vs);
    g->xh[n] = g->x[n] + 0.5 * dt * g->uh[n];
    g->yh[n] = g->y[n] + 0.5 * dt * g->vh[n];
  }
#ifdef _OPENMP
#pragma omp parallel num_threads(g->nthreads)
#endif
  FOR_SHARE(g->nz, g->ni) {
    const size_t z = i + ni * j;
    g->eh[z] = g->e[z] - 0.5 * dt * zone_work(g, i, j, g->uh, g->vh) / g->m[z];
  }
  ms_status st = c2d_zone_state(g, g->xh, g->yh, g->eh, g->vol_old, g->rhoh, g->ph, g->ch);
  if (st != MS_OK) return st;
  /* Corrector. */
  c2d_zone_forces(g, g->xh, g->yh, g->uh, g->vh, g->ph, g->rhoh, g->ch);
  node_gather(g);
  boundary_pressure(g, g->xh, g->yh, g->t + 0.5 * dt);
  double work = 0.0;
#ifdef _OPENMP
#pragma omp parallel num_threads(g->nthreads)
#endif
  FOR_SHARE(g->nn, (g->ni + 1)) {
    const size_t n = i + (ni + 1) * j;
    double ax, ay;
    node_accel(g, n, &ax, &ay);
    double u1 = g->u[n] + dt * ax, v1 = g->v[n] + dt * ay;
    const bool con = on_side(g, i, j) && apply_bc_ij(g, i, j, n, t1, &u1, &v1);
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
#pragma omp parallel num_threads(g->nthreads)
#endif
  FOR_SHARE(g->nz, g->ni) {
    const size_t z = i + ni * j;
    g->vol_old[z] = g->vol[z];
    g->e[z] -= dt * zone_work(g, i, j, g->uh, g->vh) / g->m[z];
  }
  g->t = t1;
  st = c2d_zone_state(g, g->x, g->y, g->e, g->vol, g->rho, g->p, g->c);
  if (st != MS_OK) return st;
  g->step++;
  /* Next step: Courant (with the viscosity's compressive |Δu| at tⁿ⁺¹), volume change, growth. */
  double dtn = c2d_stable_dt(g);
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
