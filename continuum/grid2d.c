/* SPDX-License-Identifier: MIT */
/* grid2d.c — the 2D staggered Lagrangian quad grid with the compatible discretisation
 * ([CBSW98], docs/continuum2d.md): the corner forces, the boundary conditions and the zone
 * state. Public API in cont2d.h; set-up, tag lines and queries: grid2d_setup.c.
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
 * The time step (predictor–corrector, threads): grid2d_step.c.
 */
#include "grid2d_impl.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* Velocity gradients g = Δu/l of the edges i → i + st, i < n, with ic = 1/|g|² (g and ic 0 on
 * a degenerate or motionless edge). Restrict parameters: the loop vectorizes. */
MS_KERNEL_CLONES static void edge_grads(const double *restrict x, const double *restrict y,
                                        const double *restrict u, const double *restrict v,
                                        size_t st, size_t n, double *restrict egx,
                                        double *restrict egy, double *restrict eic) {
  for (size_t i = 0; i < n; ++i) {
    double dx = x[i + st] - x[i], dy = y[i + st] - y[i], l = sqrt(dx * dx + dy * dy);
    double il = l > 0.0 ? 1.0 / l : 0.0;
    double gx = (u[i + st] - u[i]) * il, gy = (v[i + st] - v[i]) * il, n2 = gx * gx + gy * gy;
    egx[i] = gx;
    egy[i] = gy;
    eic[i] = n2 > 0.0 ? 1.0 / n2 : 0.0;
  }
}

static void edge_row(const c2d_fstate *s, size_t a0, size_t st, size_t n, const c2d_erow *e) {
  edge_grads(s->x + a0, s->y + a0, s->u + a0, s->v + a0, st, n, e->gx, e->gy, e->ic);
}

/* The edges along node row n, (i, n) → (i+1, n), i < ni. */
void c2d_edge_hrow(const c2d_grid *g, const c2d_fstate *s, size_t n, c2d_erow *e) {
  edge_row(s, (g->ni + 1) * n, 1, g->ni, e);
}

/* The edges across zone row j, (i, j) → (i, j+1), i ≤ ni. */
void c2d_edge_vrow(const c2d_grid *g, const c2d_fstate *s, size_t j, c2d_erow *e) {
  edge_row(s, (g->ni + 1) * j, g->ni + 1, g->ni + 1, e);
}

/* CSW98 limiter ψ of edge c of row ec from its neighbours along the same logical line, edge l of
 * row el (present if hl) and edge r of row er (present if hr): the ratios
 * r = (g_nb · g_c)/|g_c|² (the orientation of the line cancels); a missing neighbour at the mesh
 * boundary takes the other's ratio (both missing: ψ = 0). Branch-free: an absent neighbour's
 * index must still be valid. The flags hl, hr are doubles (1 present, 0 absent): selects on a
 * double comparison vectorize, on a bool they do not (GCC 12). */
static inline double psi_of(double gx, double gy, double ic, double lgx, double lgy, double hl,
                            double rgx, double rgy, double hr) {
  double rl = hl > 0.0 ? (lgx * gx + lgy * gy) * ic : 0.0;
  double rr = hr > 0.0 ? (rgx * gx + rgy * gy) * ic : 0.0;
  rl = hl > 0.0 ? rl : rr;
  rr = hr > 0.0 ? rr : rl;
  double psi = 0.5 * (rl + rr);
  psi = 2.0 * rl < psi ? 2.0 * rl : psi;
  psi = 2.0 * rr < psi ? 2.0 * rr : psi;
  psi = psi > 1.0 ? 1.0 : psi;
  return psi > 0.0 ? psi : 0.0;
}

static inline double edge_psi(const c2d_erow *ec, ptrdiff_t c, const c2d_erow *el, ptrdiff_t l,
                              bool hl, const c2d_erow *er, ptrdiff_t r, bool hr) {
  return psi_of(ec->gx[c], ec->gy[c], ec->ic[c], el->gx[l], el->gy[l], hl, er->gx[r], er->gy[r],
                hr);
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

/* The edge viscosity of one zone edge ([CSW98]): Δu = (du, dv) and Δx = (dx, dy) along it, S =
 * (sx, sy) the median from the zone centre to its midpoint, ψ its limiter, ρ and qq = q1²c² the
 * zone's. Returns q|S|/|Δu| (the force on the edge's nodes is ± that times Δu), 0 unless the
 * edge compresses (and |Δu|² has not underflowed). q/|Δu| is formed without the |Δu| that
 * cancels. */
static inline double edge_q(double du, double dv, double dx, double dy, double sx, double sy,
                            double psi, double rho, double qq, double q2z) {
  double adu = sqrt(du * du + dv * dv);
  double a = q2z * adu;
  double qa = rho * (1.0 - psi) * (a + sqrt(a * a + qq)) * sqrt(sx * sx + sy * sy);
  return du * dx + dv * dy < 0.0 && adu > 1e-150 ? qa : 0.0;
}

/* The corner forces of zone (i0, j0) into f[8] (x, y per corner) and, in r–z, its corner area
 * masses ρ_z A_c into ma[4], from the state s (lim: the limiter's edge rows, NULL: no
 * limiter). */
static inline __attribute__((always_inline)) void
zone_force(const c2d_grid *g, size_t i0, size_t j0, const c2d_fstate *s, const c2d_elim *lim,
           double *restrict fc, double *restrict ma, const bool rz_geo, const bool hg_on) {
  const size_t z = i0 + g->ni * j0, ni = g->ni;
  double f[8];
  const double *px = s->x, *py = s->y, *rz = s->rho, *cz = s->c;
  size_t nd[4];
  zone_nodes_ij(g, i0, j0, nd);
  double X[4], Y[4], U[4], V[4];
  gather_nd(nd, px, py, X, Y);
  gather_nd(nd, s->u, s->v, U, V);
  {
    const double P = s->p[z];
    double gvx[4], gvy[4];
    const c2d_geometry geo = rz_geo ? C2D_RZ : C2D_XY;
    const c2d_geometry fg = g->area_weighted ? C2D_XY : geo; /* geometry of the gradients */
    poly_grad(fg, X, Y, gvx, gvy);
    if (rz_geo)
      for (int k = 0; k < 4; ++k) {
        double CX[4], CY[4];
        corner_quad(X, Y, 0.25 * (X[0] + X[1] + X[2] + X[3]), 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]), k,
                    CX, CY);
        ma[k * ni + i0] = rz[z] * quad_area(CX, CY);
      }
    for (int k = 0; k < 4; ++k) {
      f[2 * k] = P * gvx[k];
      f[2 * k + 1] = P * gvy[k];
    }
    double ex[8] = {0, 0, 0, 0, 0, 0, 0, 0}; /* sub-zonal pressure and viscosity */
    double xc = 0.25 * (X[0] + X[1] + X[2] + X[3]), yc = 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]);
    {
      double dpc[4];
      if (hg_on) {
        for (int k = 0; k < 4; ++k) {
          double CX[4], CY[4];
          corner_quad(X, Y, xc, yc, k, CX, CY);
          double vc = poly_volume(geo, CX, CY);
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
    /* Edge viscosity, compression only; the four edges without branches (whether an edge
     * compresses is data, not predictable). ψ from the edge rows (k = 0: along node row j0,
     * 1: the right edge across zone row j0, 2: along node row j0 + 1, 3: the left edge). */
    double psi[4] = {0, 0, 0, 0};
    if (lim) {
      /* il, ir: valid indices even at the row's ends (the edge rows have a pad before and after) */
      const ptrdiff_t i = (ptrdiff_t)i0, il = i - 1, ir = i + 1;
      const bool hl = i0 > 0, hr = i0 + 1 < ni, hb = lim->vm != NULL, ht = lim->vp != NULL;
      const c2d_erow *vm = hb ? lim->vm : lim->v0, *vp = ht ? lim->vp : lim->v0;
      psi[0] = edge_psi(lim->hlo, i, lim->hlo, il, hl, lim->hlo, ir, hr);
      psi[1] = edge_psi(lim->v0, i + 1, vm, i + 1, hb, vp, i + 1, ht);
      psi[2] = edge_psi(lim->hhi, i, lim->hhi, il, hl, lim->hhi, ir, hr);
      psi[3] = edge_psi(lim->v0, i, vm, i, hb, vp, i, ht);
    }
    const double qq = g->q1 * g->q1 * cz[z] * cz[z], q2z = g->q2 * g->zeta;
    double vx[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      int kn = (k + 1) & 3;
      double du = U[kn] - U[k], dv = V[kn] - V[k];
      double dx = X[kn] - X[k], dy = Y[kn] - Y[k];
      double sx = 0.5 * (X[k] + X[kn]) - xc, sy = 0.5 * (Y[k] + Y[kn]) - yc;
      double sq = edge_q(du, dv, dx, dy, sx, sy, psi[k], rz[z], qq, q2z);
      vx[2 * k] += sq * du;
      vx[2 * k + 1] += sq * dv;
      vx[2 * kn] -= sq * du;
      vx[2 * kn + 1] -= sq * dv;
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
    for (int k = 0; k < 8; ++k) fc[k * ni + i0] = f[k] + ex[k];
  }
}

/* zone_force for x–y without sub-zonal pressure, over a whole zone row, its arrays as restrict
 * parameters so that the compiler vectorizes the loop across zones: node rows j (a) and j + 1
 * (b); zone P, ρ, c; the limiter's edge rows (hlo, hhi along node rows j, j + 1 with pads at
 * either end; v0 across zone row j, vm and vp across rows j ∓ 1, present if hb, ht = 1; lon = 0:
 * no limiter, ψ = 0). The same arithmetic as zone_force. Flags are doubles: see psi_of. */
MS_KERNEL_CLONES static __attribute__((noinline)) void
force_row_xy_k(ptrdiff_t ni, const double *restrict xa, const double *restrict xb,
               const double *restrict ya, const double *restrict yb, const double *restrict ua,
               const double *restrict ub, const double *restrict va, const double *restrict vb,
               const double *restrict P, const double *restrict R, const double *restrict C,
               double q1, double q2z, double lon, const double *restrict hlx,
               const double *restrict hly, const double *restrict hlc, const double *restrict hhx,
               const double *restrict hhy, const double *restrict hhc, const double *restrict v0x,
               const double *restrict v0y, const double *restrict v0c, const double *restrict vmx,
               const double *restrict vmy, const double *restrict vpx, const double *restrict vpy,
               double hb, double ht, double *restrict f0, double *restrict f1, double *restrict f2,
               double *restrict f3, double *restrict f4, double *restrict f5, double *restrict f6,
               double *restrict f7) {
  for (ptrdiff_t i = 0; i < ni; ++i) {
    const double X[4] = {xa[i], xa[i + 1], xb[i + 1], xb[i]},
                 Y[4] = {ya[i], ya[i + 1], yb[i + 1], yb[i]};
    const double U[4] = {ua[i], ua[i + 1], ub[i + 1], ub[i]},
                 V[4] = {va[i], va[i + 1], vb[i + 1], vb[i]};
    double f[8];
    for (int k = 0; k < 4; ++k) {
      int kn = (k + 1) & 3, kp = (k + 3) & 3;
      f[2 * k] = P[i] * (0.5 * (Y[kn] - Y[kp]));
      f[2 * k + 1] = P[i] * (0.5 * (X[kp] - X[kn]));
    }
    double psi[4];
    {
      const double hl = i > 0 ? lon : 0.0, hr = i + 1 < ni ? lon : 0.0;
      psi[0] =
          psi_of(hlx[i], hly[i], hlc[i], hlx[i - 1], hly[i - 1], hl, hlx[i + 1], hly[i + 1], hr);
      psi[1] = psi_of(v0x[i + 1], v0y[i + 1], v0c[i + 1], vmx[i + 1], vmy[i + 1], hb, vpx[i + 1],
                      vpy[i + 1], ht);
      psi[2] =
          psi_of(hhx[i], hhy[i], hhc[i], hhx[i - 1], hhy[i - 1], hl, hhx[i + 1], hhy[i + 1], hr);
      psi[3] = psi_of(v0x[i], v0y[i], v0c[i], vmx[i], vmy[i], hb, vpx[i], vpy[i], ht);
    }
    const double xc = 0.25 * (X[0] + X[1] + X[2] + X[3]), yc = 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]);
    const double qq = q1 * q1 * C[i] * C[i];
    double vx[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      int kn = (k + 1) & 3;
      double du = U[kn] - U[k], dv = V[kn] - V[k];
      double sx = 0.5 * (X[k] + X[kn]) - xc, sy = 0.5 * (Y[k] + Y[kn]) - yc;
      double sq = edge_q(du, dv, X[kn] - X[k], Y[kn] - Y[k], sx, sy, psi[k], R[i], qq, q2z);
      vx[2 * k] += sq * du;
      vx[2 * k + 1] += sq * dv;
      vx[2 * kn] -= sq * du;
      vx[2 * kn + 1] -= sq * dv;
    }
    /* eight restrict outputs: one array with offsets k ni would not vectorize */
    f0[i] = f[0] + vx[0];
    f1[i] = f[1] + vx[1];
    f2[i] = f[2] + vx[2];
    f3[i] = f[3] + vx[3];
    f4[i] = f[4] + vx[4];
    f5[i] = f[5] + vx[5];
    f6[i] = f[6] + vx[6];
    f7[i] = f[7] + vx[7];
  }
}

static void force_row_xy(const c2d_grid *g, size_t j, const c2d_fstate *s, const c2d_elim *lim,
                         double *fc) {
  const size_t ni = g->ni, w = ni + 1, a = w * j, b = a + w, z = ni * j;
  /* without the limiter: all neighbours absent (ψ = 0), any valid edge row stands in */
  const c2d_erow *e0 = &g->scr[0].eh[0];
  const c2d_erow *hlo = lim ? lim->hlo : e0, *hhi = lim ? lim->hhi : e0, *v0 = lim ? lim->v0 : e0;
  const c2d_erow *vm = lim && lim->vm ? lim->vm : v0, *vp = lim && lim->vp ? lim->vp : v0;
  force_row_xy_k((ptrdiff_t)ni, s->x + a, s->x + b, s->y + a, s->y + b, s->u + a, s->u + b,
                 s->v + a, s->v + b, s->p + z, s->rho + z, s->c + z, g->q1, g->q2 * g->zeta,
                 lim ? 1.0 : 0.0, hlo->gx, hlo->gy, hlo->ic, hhi->gx, hhi->gy, hhi->ic, v0->gx,
                 v0->gy, v0->ic, vm->gx, vm->gy, vp->gx, vp->gy, lim && lim->vm ? 1.0 : 0.0,
                 lim && lim->vp ? 1.0 : 0.0, fc, fc + ni, fc + 2 * ni, fc + 3 * ni, fc + 4 * ni,
                 fc + 5 * ni, fc + 6 * ni, fc + 7 * ni);
}

/* The corner forces of zone row j from the state s: fc[(2k (+1)) ni + i] the x (y) force of
 * zone (i, j) on its corner k, ma[k ni + i] its r–z corner area masses. The x–y row without
 * sub-zonal pressure (no calls in the loop) has loops of its own, which the compiler
 * vectorizes across the zones. */
void c2d_force_row(const c2d_grid *g, size_t j, const c2d_fstate *s, const c2d_elim *lim,
                   double *restrict fc, double *restrict ma) {
  const size_t ni = g->ni;
  const bool rz = g->geo == C2D_RZ, hg = g->hg > 0.0;
  if (!rz && !hg) force_row_xy(g, j, s, lim, fc);
  else
    for (size_t i = 0; i < ni; ++i) zone_force(g, i, j, s, lim, fc, ma, rz, hg);
}

/* Outside pressure p(t) on the edges of C2D_BC_PRESSURE sides at positions (px, py): edge a → b
 * (counter-clockwise in its zone, outward normal ∝ (y_b − y_a, x_a − x_b)) pushes its nodes with
 * −p n ∫ N r ds: L/2 each in x–y, L(2r_a + r_b)/6 in r–z (the boundary part of ∂V/∂x, so a
 * matching outside pressure is in exact equilibrium). Serial: boundary nodes only. */
void c2d_boundary_pressure(c2d_grid *g, const double *px, const double *py, double t) {
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
bool c2d_apply_bc_ij(const c2d_grid *g, size_t i, size_t j, size_t n, double t, double *u,
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
  return c2d_apply_bc_ij(g, n % w, n / w, n, t, u, v);
}

ms_status c2d_fail_zone(c2d_grid *g, size_t z, const char *what, double value) {
  size_t nd[4];
  zone_nodes(g, z, nd);
  snprintf(g->err, sizeof g->err,
           "step %ld, t = %.9g %s: %s in zone %zu (i = %zu, j = %zu, near x = %.6g, y = %.6g cm) "
           "= %.6g",
           g->step + 1, ms_out_time(g->t), ms_out_time_label(), what, z, z % g->ni, z / g->ni,
           g->x[nd[0]], g->y[nd[0]], value);
  return MS_ERR_UNSTABLE;
}

/* The EOS over zones [z0, z0 + n) (the material runs they cross): (rho, e) → (p, c), arrays
 * starting at zone z0. Returns the first zone outside its EOS's domain, or (size_t)-1. */
size_t c2d_eos_zones(const c2d_grid *g, size_t z0, size_t n, const double *rho, const double *e,
                     double *p, double *c) {
  size_t lo = 0, hi = g->nruns; /* the run holding z0: the last with first ≤ z0 */
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (g->runs[mid].first <= z0) lo = mid;
    else hi = mid;
  }
  const size_t zend = z0 + n;
  for (size_t r = lo, z = z0; r < g->nruns && z < zend; ++r) {
    const c2d_run *run = &g->runs[r];
    size_t rend = run->first + run->n < zend ? run->first + run->n : zend;
    if (rend <= z) continue;
    size_t bad = 0;
    const size_t o = z - z0;
    if (eos_eval(run->eos, rend - z, rho + o, e + o, p + o, c + o, &bad) != MS_OK) return z + bad;
    z = rend;
  }
  return (size_t)-1;
}

/* Volumes, densities at positions (px, py); the EOS for (rho, e) → (p, c). Set-up only (the
 * time step does this inside its sweeps, grid2d_step.c). */
ms_status c2d_zone_state(c2d_grid *g, const double *px, const double *py, const double *e,
                         double *vol, double *rho, double *p, double *c) {
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4];
    gather(g, z, px, py, X, Y);
    double a = quad_area(X, Y);
    double vz = g->geo == C2D_RZ ? quad_rvol(X, Y) : a;
    vol[z] = vz;
    rho[z] = g->m[z] / vz;
    if (!(a > 0.0) || !(vz > 0.0)) return c2d_fail_zone(g, z, "inverted (area ≤ 0)", a);
  }
  size_t bad = c2d_eos_zones(g, 0, g->nz, rho, e, p, c);
  if (bad != (size_t)-1)
    return c2d_fail_zone(g, bad, "EOS outside its domain (specific internal energy)", e[bad]);
  return MS_OK;
}

/* Courant limit over the zones (set-up; the time step takes it inside its corrector sweep). */
double c2d_stable_dt(const c2d_grid *g) {
  double dt = INFINITY;
  for (size_t z = 0; z < g->nz; ++z) {
    size_t nd[4];
    zone_nodes(g, z, nd);
    double X[4], Y[4], U[4], V[4];
    gather_nd(nd, g->x, g->y, X, Y);
    gather_nd(nd, g->u, g->v, U, V);
    double dz = c2d_zone_dt(g, X, Y, U, V, g->c[z]);
    if (dz < dt) dt = dz;
  }
  return dt;
}
