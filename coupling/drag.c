/* SPDX-License-Identifier: MIT */
/* Gas drag on fragments (docs/design.md §6): Schiller–Naumann, as in the Logos multiphase paper
 * ([Logos]: C_D = 24/Re (1 + 0.15 Re^0.687) for Re < 1000, 0.44 above; τ_p = ρ_p d²/(18 μ)). */
#include "cpl_impl.h"

#include <math.h>

const char *const cpl_drag_law_names[] = {"schiller_naumann", "stokes", "none", NULL};

/* Re above which Schiller–Naumann uses the constant Newton-regime coefficient. */
#define SN_RE_NEWTON 1000.0

double cpl_drag_factor(cpl_drag_law law, double re) {
  switch (law) {
  case CPL_DRAG_STOKES:
    return 1.0;
  case CPL_DRAG_SCHILLER_NAUMANN:
    /* f = C_D Re/24: 1 + 0.15 Re^0.687 below Re = 1000, 0.44 Re/24 above */
    return re < SN_RE_NEWTON ? 1.0 + 0.15 * pow(re, 0.687) : 0.44 * re / 24.0;
  case CPL_DRAG_NONE:
  default:
    return 0.0;
  }
}

double cpl_drag_coefficient(cpl_drag_law law, double re) {
  if (law == CPL_DRAG_NONE) return 0.0;
  return 24.0 / re * cpl_drag_factor(law, re);
}

double cpl_reynolds(const cpl_gas *g, double d, const double v[3]) {
  double vr[3] = {g->u[0] - v[0], g->u[1] - v[1], g->u[2] - v[2]};
  double w = sqrt(vr[0] * vr[0] + vr[1] * vr[1] + vr[2] * vr[2]);
  return g->rho * w * d / g->mu;
}

void cpl_drag_force(cpl_drag_law law, const cpl_gas *g, double d, const double v[3], double F[3]) {
  F[0] = F[1] = F[2] = 0;
  if (law == CPL_DRAG_NONE || !(g->mu > 0) || !(g->rho > 0) || !(d > 0)) return;
  double re = cpl_reynolds(g, d, v);
  /* ½ ρ C_D (π d²/4)|v_r| v_r = 3π μ d (C_D Re/24) v_r: the same force, finite at v_r = 0 */
  double k = 3.0 * CPL_PI * g->mu * d * cpl_drag_factor(law, re);
  for (int a = 0; a < 3; a++) F[a] = k * (g->u[a] - v[a]);
}

double cpl_stokes_time(double rho_p, double d, double mu) { return rho_p * d * d / (18.0 * mu); }

void cpl_drag_fragments(cpl_drag_law law, cpl_fragments *f, const cpl_particles *p,
                        const cpl_ejecta_sel *sel, cpl_gas_fn gas, void *gas_user, double t,
                        double *fx, double *fy, double *fz) {
  if (law == CPL_DRAG_NONE || !f->n) return;
  /* fragment accelerations first (scratch columns 0..2 of f->work; no allocation per step) */
  size_t big = sel && sel->exclude_largest ? cpl_largest_fragment(f) : (size_t)-1;
  for (size_t k = 0; k < f->n; k++) {
    double *a = f->work + k * CPL_WORK_COLS;
    a[0] = a[1] = a[2] = 0;
    if (sel && !cpl_is_ejecta_with(f, k, sel, big)) continue;
    double x[3] = {f->cx[k], f->cy[k], f->cz[k]}, v[3] = {f->vx[k], f->vy[k], f->vz[k]};
    cpl_gas g;
    if (!(f->mass[k] > 0) || !gas(gas_user, x, t, &g)) continue;
    double F[3];
    cpl_drag_force(law, &g, f->diameter[k], v, F);
    for (int c = 0; c < 3; c++) a[c] = F[c] / f->mass[k];
  }
  /* particle i takes m_i/M of its fragment's force: a uniform acceleration, so drag changes
   * no relative motion inside the fragment and the fragment's total force is exact */
  for (size_t i = 0; i < p->n && i < f->n_particles; i++) {
    int64_t id = f->id[i];
    if (id < 0) continue;
    const double *a = f->work + (size_t)id * CPL_WORK_COLS;
    double m = p->mass[i];
    fx[i] += m * a[0];
    fy[i] += m * a[1];
    if (fz) fz[i] += m * a[2];
  }
}
