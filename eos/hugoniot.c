/* SPDX-License-Identifier: MIT */
/* hugoniot.c — Rankine–Hugoniot states for any EOS (docs/design.md §3) and the Kuropatenko mixture
 * rule ([Davydov] §1.2). docs/eos.md describes the method.
 *
 * For a piston (particle) velocity up, with t = up/Us = 1 − ρ0/ρ the jump conditions give
 *   ρ = ρ0/(1 − t),  P_R = P0 + ρ0 up²/t  (Rayleigh line),  e = e0 + up²/2 + P0 t/ρ0,
 * and the shock state is the root of F(t) = P_eos(ρ, e) − P_R(t) on 0 < t < 1. KINSOL solves
 * it (unknown w = Us − up > 0 as a constraint, Newton with line search); if KINSOL fails or
 * leaves the EOS's domain, a bracketing search from the weak-shock side (t → 0, F → −∞)
 * followed by Brent's method finds the first root. */
#include "eos_impl.h"

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <stdlib.h>

typedef struct hug_problem {
  const eos_t *eos;
  double rho0, e0, p0, up, pscale;
} hug_problem;

typedef struct hug_state {
  double rho, e, us, p_rayleigh;
} hug_state;

static hug_state state_from_t(const hug_problem *h, double t) {
  hug_state s;
  s.rho = h->rho0 / (1.0 - t);
  s.us = h->up / t;
  s.p_rayleigh = h->p0 + h->rho0 * h->up * h->up / t;
  s.e = h->e0 + 0.5 * h->up * h->up + h->p0 * t / h->rho0;
  return s;
}

static double residual_t(double t, void *user) {
  const hug_problem *h = user;
  if (!(t > 0.0 && t < 1.0)) return NAN;
  hug_state s = state_from_t(h, t);
  double p = eos_pressure(h->eos, s.rho, s.e);
  return (p - s.p_rayleigh) / h->pscale;
}

/* KINSOL residual in w = Us − up. */
static int kin_residual(N_Vector y, N_Vector f, void *user) {
  const hug_problem *h = user;
  double w = NV_Ith_S(y, 0);
  double r = w > 0.0 ? residual_t(h->up / (h->up + w), user) : NAN;
  NV_Ith_S(f, 0) = r;
  return isfinite(r) ? 0 : 1; /* recoverable: KINSOL shortens the step */
}

static void kin_silent(int code, const char *module, const char *function, char *msg, void *data) {
  (void)code, (void)module, (void)function, (void)msg, (void)data;
}

/* Search t upward (on a logit scale) from the weak-shock end for the first sign change of
 * f (f < 0 near t = 0), then Brent. Handles NaN (outside the EOS domain) by bisecting towards
 * the domain edge. Returns NaN if there is no root inside the domain. */
static double bracket_root(double (*f)(double, void *), void *user, double t_start) {
  double ta = t_start, fa = f(ta, user);
  for (int k = 0; k < 60 && !(fa < 0.0); ++k) {
    ta *= 0.1;
    fa = f(ta, user);
  }
  if (!(fa < 0.0)) return NAN;
  double z = log(ta / (1.0 - ta));
  for (int k = 0; k < 800; ++k) {
    double zb = z + 0.05, tb = 1.0 / (1.0 + exp(-zb)), fb = f(tb, user);
    if (tb >= 1.0) return NAN;
    if (isnan(fb)) {
      /* Domain edge between ta and tb: bisect on "defined", looking for a sign change. */
      double lo = ta, hi = tb;
      for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
        double mid = 0.5 * (lo + hi), fm = f(mid, user);
        if (isnan(fm)) {
          hi = mid;
        } else if (fm >= 0.0) {
          return eos_brent(f, user, ta, mid, fa, fm, 1e-15 * mid, 200);
        } else {
          lo = mid, ta = mid, fa = fm;
        }
      }
      return NAN;
    }
    if (fb >= 0.0) return eos_brent(f, user, ta, tb, fa, fb, 1e-15 * tb, 200);
    ta = tb, fa = fb, z = zb;
  }
  return NAN;
}

typedef struct kin_solver {
  SUNContext ctx;
  N_Vector y, scale, constraints;
  SUNMatrix J;
  SUNLinearSolver LS;
  void *mem;
} kin_solver;

static bool kin_create(kin_solver *k, hug_problem *h) {
  if (SUNContext_Create(NULL, &k->ctx) != 0) return false;
  k->y = N_VNew_Serial(1, k->ctx);
  k->scale = N_VNew_Serial(1, k->ctx);
  k->constraints = N_VNew_Serial(1, k->ctx);
  k->J = SUNDenseMatrix(1, 1, k->ctx);
  k->LS = SUNLinSol_Dense(k->y, k->J, k->ctx);
  k->mem = KINCreate(k->ctx);
  if (!k->y || !k->scale || !k->constraints || !k->J || !k->LS || !k->mem) return false;
  N_VConst(1.0, k->y);
  N_VConst(2.0, k->constraints); /* w > 0 */
  return KINInit(k->mem, kin_residual, k->y) == KIN_SUCCESS &&
         KINSetErrHandlerFn(k->mem, kin_silent, NULL) == KIN_SUCCESS &&
         KINSetUserData(k->mem, h) == KIN_SUCCESS &&
         KINSetLinearSolver(k->mem, k->LS, k->J) == KIN_SUCCESS &&
         KINSetConstraints(k->mem, k->constraints) == KIN_SUCCESS &&
         KINSetFuncNormTol(k->mem, 1e-14) == KIN_SUCCESS &&
         KINSetScaledStepTol(k->mem, 1e-16) == KIN_SUCCESS &&
         KINSetMaxSetupCalls(k->mem, 1) == KIN_SUCCESS && /* exact Newton */
         KINSetNumMaxIters(k->mem, 100) == KIN_SUCCESS;
}

static void kin_free(kin_solver *k) {
  if (k->mem) KINFree(&k->mem);
  if (k->LS) SUNLinSolFree(k->LS);
  if (k->J) SUNMatDestroy(k->J);
  if (k->y) N_VDestroy(k->y);
  if (k->scale) N_VDestroy(k->scale);
  if (k->constraints) N_VDestroy(k->constraints);
  if (k->ctx) SUNContext_Free(&k->ctx);
}

/* Reference sound speed at the initial state (a scale for guesses and residuals). */
static double initial_sound_speed(const eos_t *eos, double rho0, double e0) {
  double c = eos_sound_speed(eos, rho0, e0);
  if (!(c > 0.0) || !isfinite(c)) c = eos_c0(eos);
  return (c > 0.0 && isfinite(c)) ? c : 0.0;
}

ms_status eos_hugoniot(const eos_t *eos, double rho0, double e0, size_t n, const double *up,
                       eos_hugoniot_point *out) {
  double p0 = eos_pressure(eos, rho0, e0);
  if (!isfinite(p0)) return MS_ERR_INPUT;
  double cref = initial_sound_speed(eos, rho0, e0);
  hug_problem h = {eos, rho0, e0, p0, 0.0, 1.0};
  kin_solver k = {0};
  bool have_kin = kin_create(&k, &h);
  ms_status st = MS_OK;
  double ratio = NAN; /* w/up of the previous point: continuation guess */
  for (size_t i = 0; i < n; ++i) {
    eos_hugoniot_point *o = &out[i];
    o->up = up[i];
    o->us = o->p = o->rho = o->e = NAN;
    if (!(up[i] > 0.0) || !isfinite(up[i])) {
      st = MS_ERR_SOLVER;
      continue;
    }
    h.up = up[i];
    h.pscale = rho0 * up[i] * (up[i] + cref) + fabs(p0);
    double t = NAN;
    if (have_kin) {
      double w = isfinite(ratio) ? ratio * up[i] : cref + 0.5 * up[i];
      if (!(w > 0.0)) w = 0.5 * up[i];
      NV_Ith_S(k.y, 0) = w;
      N_VConst(1.0 / (cref + up[i]), k.scale);
      int flag = KINSol(k.mem, k.y, KIN_LINESEARCH, k.scale, k.scale);
      w = NV_Ith_S(k.y, 0);
      double tt = up[i] / (up[i] + w), r = residual_t(tt, &h);
      if (flag >= 0 && w > 0.0 && fabs(r) <= 1e-12) t = tt;
    }
    if (isnan(t)) t = bracket_root(residual_t, &h, 0.1 * up[i] / (up[i] + 10.0 * cref + up[i]));
    if (isnan(t)) {
      st = MS_ERR_SOLVER;
      continue;
    }
    hug_state s = state_from_t(&h, t);
    o->us = s.us;
    o->rho = s.rho;
    o->e = s.e;
    o->p = eos_pressure(eos, s.rho, s.e);
    ratio = (s.us - up[i]) / up[i];
  }
  kin_free(&k);
  return st;
}

/* ------------------------------------------------------------------------------------------ */
/* Hugoniot at a given pressure: with t = 1 − ρ0/ρ, e = e0 + ½(P + P0) t/ρ0 and the root of
 * G(t) = P_eos(ρ, e) − P (G(0) = P0 − P < 0). */

typedef struct hug_p_problem {
  const eos_t *eos;
  double rho0, e0, p0, p;
} hug_p_problem;

static double residual_p(double t, void *user) {
  const hug_p_problem *h = user;
  if (!(t > 0.0 && t < 1.0)) return NAN;
  double rho = h->rho0 / (1.0 - t), e = h->e0 + 0.5 * (h->p + h->p0) * t / h->rho0;
  return (eos_pressure(h->eos, rho, e) - h->p) / (fabs(h->p) + fabs(h->p0));
}

ms_status eos_hugoniot_at_pressure(const eos_t *eos, double rho0, double e0, double p,
                                   eos_hugoniot_point *out) {
  double p0 = eos_pressure(eos, rho0, e0);
  out->up = out->us = out->p = out->rho = out->e = NAN;
  if (!isfinite(p0) || !(p > p0)) return MS_ERR_INPUT;
  hug_p_problem h = {eos, rho0, e0, p0, p};
  double t = bracket_root(residual_p, &h, 1e-9);
  if (isnan(t)) return MS_ERR_SOLVER;
  double dp = p - p0;
  out->p = p;
  out->rho = rho0 / (1.0 - t);
  out->e = e0 + 0.5 * (p + p0) * t / rho0;
  out->up = sqrt(dp * t / rho0);
  out->us = sqrt(dp / (rho0 * t));
  return MS_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Kuropatenko rule ([Davydov] §1.2, docs/eos.md). Components start at their reference states
 * (ρ0_i, e0_i) = (eos_rho0, eos_e0) with pressures P0_i; the mixture starts at
 * ρ0 = Σ α_i ρ0_i, P0 = Σ α_i P0_i. */

static ms_status check_fractions(size_t ncomp, const eos_t *const *comp, const double *alpha) {
  if (ncomp == 0) return MS_ERR_INPUT;
  double sum = 0.0;
  for (size_t i = 0; i < ncomp; ++i) {
    if (!comp[i] || !(alpha[i] >= 0.0 && alpha[i] <= 1.0)) return MS_ERR_INPUT;
    sum += alpha[i];
  }
  return fabs(sum - 1.0) <= 1e-9 ? MS_OK : MS_ERR_INPUT;
}

static void mixture_reference(size_t ncomp, const eos_t *const *comp, const double *alpha,
                              double *rho0, double *p0) {
  *rho0 = *p0 = 0.0;
  for (size_t i = 0; i < ncomp; ++i) {
    *rho0 += alpha[i] * eos_rho0(comp[i]);
    *p0 += alpha[i] * eos_pressure(comp[i], eos_rho0(comp[i]), eos_e0(comp[i]));
  }
}

ms_status eos_kuropatenko_at_pressure(size_t ncomp, const eos_t *const *comp, const double *alpha,
                                      double p, eos_hugoniot_point *out) {
  out->up = out->us = out->p = out->rho = out->e = NAN;
  ms_status st = check_fractions(ncomp, comp, alpha);
  if (st != MS_OK) return st;
  double rho0, p0;
  mixture_reference(ncomp, comp, alpha, &rho0, &p0);
  if (!(p > p0)) return MS_ERR_INPUT;
  double sum = 0.0; /* Σ α_i/(D_i − u_i) */
  for (size_t i = 0; i < ncomp; ++i) {
    if (alpha[i] == 0.0) continue;
    eos_hugoniot_point hi;
    st = eos_hugoniot_at_pressure(comp[i], eos_rho0(comp[i]), eos_e0(comp[i]), p, &hi);
    if (st != MS_OK) return st;
    sum += alpha[i] / (hi.us - hi.up);
  }
  double W = 1.0 / sum, dp = p - p0;
  /* p − P0 = ρ0 D u with D = u + W  ->  u² + W u − dp/ρ0 = 0. */
  double u = 2.0 * dp / rho0 / (W + sqrt(W * W + 4.0 * dp / rho0));
  out->up = u;
  out->us = u + W;
  out->p = p;
  out->rho = rho0 * (u + W) / W;
  out->e = 0.5 * (p + p0) * (1.0 / rho0 - 1.0 / out->rho);
  return MS_OK;
}

typedef struct kur_problem {
  size_t ncomp;
  const eos_t *const *comp;
  const double *alpha;
  double u;
  ms_status st;
} kur_problem;

static double kur_residual(double p, void *user) {
  kur_problem *k = user;
  eos_hugoniot_point pt;
  ms_status st = eos_kuropatenko_at_pressure(k->ncomp, k->comp, k->alpha, p, &pt);
  if (st != MS_OK) {
    k->st = st;
    return NAN;
  }
  return pt.up - k->u;
}

static ms_status kuropatenko_point(size_t ncomp, const eos_t *const *comp, const double *alpha,
                                   double u, eos_hugoniot_point *out) {
  out->up = u;
  out->us = out->p = out->rho = out->e = NAN;
  ms_status st = check_fractions(ncomp, comp, alpha);
  if (st != MS_OK) return st;
  if (!(u > 0.0) || !isfinite(u)) return MS_ERR_INPUT;
  double rho0, p0, inv_c = 0.0;
  mixture_reference(ncomp, comp, alpha, &rho0, &p0);
  for (size_t i = 0; i < ncomp; ++i)
    if (alpha[i] > 0.0)
      inv_c += alpha[i] / eos_sound_speed(comp[i], eos_rho0(comp[i]), eos_e0(comp[i]));
  double c = 1.0 / inv_c; /* acoustic Kuropatenko speed, 1/C = Σ α_i/C_i */
  kur_problem k = {ncomp, comp, alpha, u, MS_OK};
  /* u_mix(p) increases from 0 at p = P0; expand the upper bracket until it passes u. */
  double plo = p0 + 1e-12 * rho0 * u * (c + u), flo = kur_residual(plo, &k);
  double phi = p0 + rho0 * u * (c + 2.0 * u), fhi = kur_residual(phi, &k);
  for (int i = 0; i < 60 && fhi < 0.0; ++i) {
    plo = phi, flo = fhi;
    phi = p0 + 2.0 * (phi - p0);
    fhi = kur_residual(phi, &k);
  }
  if (!(flo < 0.0) || !(fhi >= 0.0)) return k.st != MS_OK ? k.st : MS_ERR_SOLVER;
  double p = eos_brent(kur_residual, &k, plo, phi, flo, fhi, 1e-15 * phi, 200);
  if (isnan(p)) return k.st != MS_OK ? k.st : MS_ERR_SOLVER;
  return eos_kuropatenko_at_pressure(ncomp, comp, alpha, p, out);
}

ms_status eos_kuropatenko(size_t ncomp, const eos_t *const *comp, const double *alpha, double u,
                          double *D, double *p) {
  eos_hugoniot_point pt;
  ms_status st = kuropatenko_point(ncomp, comp, alpha, u, &pt);
  if (D) *D = pt.us;
  if (p) *p = pt.p;
  return st;
}

ms_status eos_kuropatenko_hugoniot(size_t ncomp, const eos_t *const *comp, const double *alpha,
                                   size_t n, const double *up, eos_hugoniot_point *out) {
  ms_status st = MS_OK;
  for (size_t i = 0; i < n; ++i) {
    ms_status s = kuropatenko_point(ncomp, comp, alpha, up[i], &out[i]);
    if (s != MS_OK && st == MS_OK) st = s;
  }
  return st;
}
