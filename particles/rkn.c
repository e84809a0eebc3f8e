/* SPDX-License-Identifier: MIT */
/* rkn.c — explicit symplectic Runge–Kutta–Nyström integrators (docs/design.md §5.2, [Sofronov] §2).
 *
 * Coefficients: Verlet α = ½, γ = 1. SIA4 (Candy & Rozmus 1991) as printed in [Sofronov].
 * RKN4 and its conjugate: the printed coefficients are garbled; docs/design.md §5.2 gives
 * α = ((3±√3)/6, (3∓√3)/6, (3±√3)/6), γ = ((3∓2√3)/12, ½, (3±2√3)/12), which satisfy every
 * 4th-order RKN condition (checked numerically in tests/ptl/test_rkn_order.c).
 */
#include "ptl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const rkn_scheme_names[] = {"verlet", "sia4", "rkn4", "rkn4_conjugate", NULL};

static rkn_scheme schemes[RKN_KIND_COUNT];
static int schemes_ready = 0;

static void schemes_init(void) {
  /* Built at run time because the coefficients contain cube and square roots. */
  const double c1 = cbrt(2.0), c2 = cbrt(4.0), s3 = sqrt(3.0);
  schemes[RKN_VERLET] = (rkn_scheme){RKN_VERLET, "verlet", 1, 2, {0.5, 0, 0}, {1.0, 0, 0}};
  double g1 = c1 / 3.0 + c2 / 6.0 + 2.0 / 3.0;
  schemes[RKN_SIA4] =
      (rkn_scheme){RKN_SIA4,
                   "sia4",
                   3,
                   4,
                   {c1 / 6.0 + c2 / 12.0 + 1.0 / 3.0, 0.5, 2.0 / 3.0 - c1 / 6.0 - c2 / 12.0},
                   {g1, -1.0 / 3.0 - 2.0 * c1 / 3.0 - c2 / 3.0, g1}};
  schemes[RKN_RKN4] = (rkn_scheme){RKN_RKN4,
                                   "rkn4",
                                   3,
                                   4,
                                   {(3 + s3) / 6, (3 - s3) / 6, (3 + s3) / 6},
                                   {(3 - 2 * s3) / 12, 0.5, (3 + 2 * s3) / 12}};
  schemes[RKN_RKN4_CONJ] = (rkn_scheme){RKN_RKN4_CONJ,
                                        "rkn4_conjugate",
                                        3,
                                        4,
                                        {(3 - s3) / 6, (3 + s3) / 6, (3 - s3) / 6},
                                        {(3 + 2 * s3) / 12, 0.5, (3 - 2 * s3) / 12}};
  schemes_ready = 1;
}

const rkn_scheme *rkn_scheme_get(rkn_kind kind) {
  if ((int)kind < 0 || kind >= RKN_KIND_COUNT) return NULL;
#pragma omp critical(rkn_schemes_init)
  if (!schemes_ready) schemes_init();
  return &schemes[kind];
}

struct rkn_integrator {
  rkn_scheme s;
  size_t ndof, cap; /* dofs in use / allocated */
  double *q;        /* stage positions */
  double *acc[3];   /* stage accelerations a(q_l) */
};

ms_status rkn_create(const rkn_params *p, rkn_integrator **out) {
  *out = NULL;
  const rkn_scheme *s = rkn_scheme_get(p->kind);
  const size_t ndof = p->ndof;
  if (!s || ndof == 0) return MS_ERR_INPUT;
  rkn_integrator *ig = ms_calloc(1, sizeof *ig);
  ig->s = *s;
  ig->ndof = ig->cap = ndof;
  ig->q = ms_aligned_alloc(ndof, sizeof(double));
  for (int l = 0; l < s->stages; ++l) ig->acc[l] = ms_aligned_alloc(ndof, sizeof(double));
  *out = ig;
  return MS_OK;
}

static void rkn_release(rkn_integrator *ig) {
  if (!ig) return;
  free(ig->q);
  for (int l = 0; l < 3; ++l) free(ig->acc[l]);
  free(ig);
}

void rkn_destroy(rkn_integrator **ig) {
  if (!ig) return;
  rkn_release(*ig);
  *ig = NULL;
}

const rkn_scheme *rkn_integrator_scheme(const rkn_integrator *ig) { return &ig->s; }

ms_status rkn_resize(rkn_integrator *ig, size_t ndof) {
  if (ndof > ig->cap) return MS_ERR_INPUT;
  ig->ndof = ndof;
  return MS_OK;
}

/* q = r + Δt α_l u + Δt² Σ_{k<l} γ_k (α_l − α_k) a_k over n entries (a_k = acc[k] + off). */
static void form_stage(const rkn_scheme *s, int l, double dt, long n, const double *r,
                       const double *u, double *const acc[3], size_t off, double *q) {
  const double alpha = s->alpha[l], dt2 = dt * dt;
  double c[3] = {0, 0, 0};
  for (int k = 0; k < l; ++k) c[k] = dt2 * s->gamma[k] * (s->alpha[l] - s->alpha[k]);
  const double *a0 = acc[0] + off, *a1 = l > 1 ? acc[1] + off : NULL;
#pragma omp parallel for schedule(static) if (n > 20000)
  for (long i = 0; i < n; ++i) {
    double v = r[i] + dt * alpha * u[i];
    if (l > 0) v += c[0] * a0[i];
    if (l > 1) v += c[1] * a1[i];
    q[i] = v;
  }
}

/* r_out = r + Δt u + Δt² Σ β_l a_l;  u += Δt Σ γ_l a_l  (β_l = γ_l (1 − α_l)); r_out may be r. */
static void finish_step(const rkn_scheme *s, double dt, long n, const double *r, double *u,
                        double *const acc[3], size_t off, double *r_out) {
  double b[3] = {0, 0, 0}, g[3] = {0, 0, 0};
  for (int l = 0; l < s->stages; ++l) {
    b[l] = dt * dt * s->gamma[l] * (1.0 - s->alpha[l]);
    g[l] = dt * s->gamma[l];
  }
  const int m = s->stages;
  const double *a0 = acc[0] + off, *a1 = m > 1 ? acc[1] + off : NULL,
               *a2 = m > 1 ? acc[2] + off : NULL;
#pragma omp parallel for schedule(static) if (n > 20000)
  for (long i = 0; i < n; ++i) {
    double dr = b[0] * a0[i], du = g[0] * a0[i];
    if (m > 1) {
      dr += b[1] * a1[i] + b[2] * a2[i];
      du += g[1] * a1[i] + g[2] * a2[i];
    }
    r_out[i] = r[i] + dt * u[i] + dr;
    u[i] += du;
  }
}

ms_status rkn_step(rkn_integrator *ig, double t, double dt, double *r, double *u,
                   rkn_accel_fn accel, rkn_constrain_fn constrain, void *user) {
  const rkn_scheme *s = &ig->s;
  const long n = (long)ig->ndof;
  for (int l = 0; l < s->stages; ++l) {
    form_stage(s, l, dt, n, r, u, ig->acc, 0, ig->q);
    double tl = t + s->alpha[l] * dt;
    if (constrain) constrain(user, tl, ig->q, NULL);
    ms_status st = accel(user, tl, ig->q, ig->acc[l]);
    if (st != MS_OK) return st;
  }
  finish_step(s, dt, n, r, u, ig->acc, 0, r);
  if (constrain) constrain(user, t + dt, r, u);
  return MS_OK;
}

/* Structure-of-arrays form: component c lives at offset c·n of the flat buffers; ig->q keeps
 * r^n while the stage positions are formed in place in r. */
ms_status rkn_step_soa(rkn_integrator *ig, double t, double dt, int ncomp, double *const r[],
                       double *const u[], rkn_accel_soa_fn accel, rkn_constrain_soa_fn constrain,
                       void *user) {
  const rkn_scheme *s = &ig->s;
  if (ncomp < 1 || ncomp > RKN_MAX_COMPONENTS || ig->ndof % (size_t)ncomp) return MS_ERR_INPUT;
  const size_t n = ig->ndof / (size_t)ncomp;
  for (int c = 0; c < ncomp; ++c) memcpy(ig->q + c * n, r[c], n * sizeof(double));
  double *acc[RKN_MAX_COMPONENTS];
  for (int l = 0; l < s->stages; ++l) {
    for (int c = 0; c < ncomp; ++c) {
      form_stage(s, l, dt, (long)n, ig->q + c * n, u[c], ig->acc, c * n, r[c]);
      acc[c] = ig->acc[l] + c * n;
    }
    double tl = t + s->alpha[l] * dt;
    if (constrain) constrain(user, tl, false);
    ms_status st = accel(user, tl, acc);
    if (st != MS_OK) return st;
  }
  for (int c = 0; c < ncomp; ++c)
    finish_step(s, dt, (long)n, ig->q + c * n, u[c], ig->acc, c * n, r[c]);
  if (constrain) constrain(user, t + dt, true);
  return MS_OK;
}

/* |tr M(z)| of the amplification matrix of one step with ω = 1, Δt = z. */
static double trace_amplification(const rkn_scheme *s, double z) {
  double tr = 0.0;
  for (int col = 0; col < 2; ++col) {
    double r = col == 0, u = col == 1, acc[3];
    for (int l = 0; l < s->stages; ++l) {
      double q = r + z * s->alpha[l] * u;
      for (int k = 0; k < l; ++k) q += z * z * s->gamma[k] * (s->alpha[l] - s->alpha[k]) * acc[k];
      acc[l] = -q;
    }
    double r1 = r + z * u, u1 = u;
    for (int l = 0; l < s->stages; ++l) {
      r1 += z * z * s->gamma[l] * (1.0 - s->alpha[l]) * acc[l];
      u1 += z * s->gamma[l] * acc[l];
    }
    tr += col == 0 ? r1 : u1;
  }
  return fabs(tr);
}

double rkn_stability_limit(rkn_kind kind) {
  const rkn_scheme *s = rkn_scheme_get(kind);
  if (!s) return 0.0;
  double z = 0.0, step = 1e-3;
  while (z < 10.0 && trace_amplification(s, z + step) < 2.0) z += step;
  double lo = z, hi = z + step; /* bisect the first crossing of |tr| = 2 */
  for (int it = 0; it < 60; ++it) {
    double mid = 0.5 * (lo + hi);
    if (trace_amplification(s, mid) < 2.0) lo = mid;
    else hi = mid;
  }
  return lo;
}
