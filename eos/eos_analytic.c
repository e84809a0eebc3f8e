/* SPDX-License-Identifier: MIT */
/* eos_analytic.c — the analytic EOS kinds (docs/design.md §3, docs/eos.md):
 *   Mie–Grüneisen cold-curve form, Mie–Grüneisen linear Us–up form, ideal gas, linear elastic. */
#include "eos_impl.h"

/* ------------------------------------------------------------------------------------------ */
/* Mie–Grüneisen, cold-curve form ([Davydov] §1.2 parameters; docs/design.md §3):
 *   P_x(δ) = (ρ0c0²/n)(δⁿ − 1),  ε_x(δ) = (c0²/n)[δⁿ⁻¹/(n−1) + 1/δ − n/(n−1)],
 *   P = P_x + G(ρ)(e − ε_x). */

typedef struct mg_cold {
  double c0, n;
  eos_gruneisen g;
  int n1_int; /* n − 1 if it is a small integer (fast powers in eos_eval), else 0 */
} mg_cold;

static double mg_cold_px(const eos_t *eos, double delta) {
  const mg_cold *m = eos->data;
  return eos->rho0 * m->c0 * m->c0 / m->n * (pow(delta, m->n) - 1.0);
}

static double mg_cold_ex(const eos_t *eos, double delta) {
  const mg_cold *m = eos->data;
  double n = m->n;
  return m->c0 * m->c0 / n * (pow(delta, n - 1.0) / (n - 1.0) + 1.0 / delta - n / (n - 1.0));
}

static double mg_cold_pressure(const eos_t *eos, double rho, double e) {
  const mg_cold *m = eos->data;
  double delta = rho / eos->rho0;
  return eos_mg_pressure_from_cold(&m->g, rho, e, mg_cold_px(eos, delta), mg_cold_ex(eos, delta));
}

static double mg_cold_c2(const eos_t *eos, double rho, double e) {
  const mg_cold *m = eos->data;
  double delta = rho / eos->rho0;
  double dpx = eos->rho0 * m->c0 * m->c0 * pow(delta, m->n - 1.0); /* dP_x/dδ */
  return eos_mg_c2_from_cold(&m->g, eos->rho0, rho, e, dpx, mg_cold_ex(eos, delta));
}

/* δ^k: repeated multiplication for small integer k (Pb has n = 3), pow otherwise. */
static inline double power(double delta, double k, int k_int) {
  if (k_int <= 0) return pow(delta, k);
  double r = delta;
  for (int i = 1; i < k_int; ++i) r *= delta;
  return r;
}

/* Fused P and c² with one power δⁿ⁻¹. */
static void mg_cold_eval(const eos_t *eos, double rho, double e, double *p, double *c2) {
  const mg_cold *m = eos->data;
  double n = m->n, c02 = m->c0 * m->c0, delta = rho / eos->rho0;
  double dn1 = power(delta, n - 1.0, m->n1_int), dn = dn1 * delta;
  double px = eos->rho0 * c02 / n * (dn - 1.0);
  double ex = c02 / n * (dn1 / (n - 1.0) + 1.0 / delta - n / (n - 1.0));
  *p = eos_mg_pressure_from_cold(&m->g, rho, e, px, ex);
  *c2 = eos_mg_c2_from_cold(&m->g, eos->rho0, rho, e, eos->rho0 * c02 * dn1, ex);
}

static const eos_ops mg_cold_ops = {
    mg_cold_pressure, mg_cold_c2, mg_cold_px, mg_cold_ex, NULL, NULL, mg_cold_eval, NULL};

eos_t *eos_create_mg_cold(double rho0, double c0, double n, double gamma0, bool gamma_rho_const) {
  if (!(rho0 > 0.0) || !(c0 > 0.0) || !(n > 1.0) || !(gamma0 >= 0.0) || !isfinite(rho0) ||
      !isfinite(c0) || !isfinite(n) || !isfinite(gamma0))
    return NULL;
  mg_cold m = {c0, n, {gamma0, rho0, gamma_rho_const}, 0};
  if (n == floor(n) && n <= 17.0) m.n1_int = (int)n - 1;
  eos_t *eos = eos_alloc(EOS_MG_COLD, &mg_cold_ops, rho0, &m, sizeof m);
  eos->c0 = c0;
  eos->delta_min = 0.0; /* analytic for every δ > 0 */
  return eos;
}

/* ------------------------------------------------------------------------------------------ */
/* Mie–Grüneisen, linear Us–up form (docs/design.md §3): with η = 1 − ρ0/ρ,
 *   P_H = ρ0c0²η/(1 − sη)²,  e_H = P_H η/(2ρ0)  (Hugoniot from (ρ0, e = 0, P = 0)),
 *   P = P_H + Γ0ρ0 (e − e_H). Defined for 1 − sη > 0 (ρ below the limiting compression
 *   ρ0 s/(s − 1)); NaN beyond. The cold curve is the isentrope through (ρ0, 0). */

typedef struct mg_linear {
  double c0, s, gamma0;
} mg_linear;

static bool mg_linear_ref(const eos_t *eos, double rho, double *ph, double *eh, double *dph,
                          double *deh) {
  const mg_linear *m = eos->data;
  double rho0 = eos->rho0, eta = 1.0 - rho0 / rho, den = 1.0 - m->s * eta;
  if (!(den > 0.0)) return false;
  double k = rho0 * m->c0 * m->c0;
  *ph = k * eta / (den * den);
  *eh = *ph * eta / (2.0 * rho0);
  double dph_deta = k * (1.0 + m->s * eta) / (den * den * den);
  double deta_drho = rho0 / (rho * rho);
  *dph = dph_deta * deta_drho;                              /* dP_H/dρ */
  *deh = (dph_deta * eta + *ph) / (2.0 * rho0) * deta_drho; /* de_H/dρ */
  return true;
}

static double mg_linear_pressure(const eos_t *eos, double rho, double e) {
  const mg_linear *m = eos->data;
  double ph, eh, dph, deh;
  if (!mg_linear_ref(eos, rho, &ph, &eh, &dph, &deh)) return NAN;
  return ph + m->gamma0 * eos->rho0 * (e - eh);
}

/* ∂P/∂ρ|_e = P_H' − G e_H', ∂P/∂e|_ρ = G = Γ0ρ0. */
static double mg_linear_c2(const eos_t *eos, double rho, double e) {
  const mg_linear *m = eos->data;
  double ph, eh, dph, deh;
  if (!mg_linear_ref(eos, rho, &ph, &eh, &dph, &deh)) return NAN;
  double G = m->gamma0 * eos->rho0, p = ph + G * (e - eh);
  return dph - G * deh + p / (rho * rho) * G;
}

static void mg_linear_eval(const eos_t *eos, double rho, double e, double *p, double *c2) {
  const mg_linear *m = eos->data;
  double ph, eh, dph, deh;
  if (!mg_linear_ref(eos, rho, &ph, &eh, &dph, &deh)) {
    *p = *c2 = NAN;
    return;
  }
  double G = m->gamma0 * eos->rho0;
  *p = ph + G * (e - eh);
  *c2 = dph - G * deh + *p / (rho * rho) * G;
}

/* Array form of mg_linear_eval: the same expressions in the same order (bitwise equal, the
 * build does not contract to FMA), with the domain test as a select so the loop vectorizes.
 * Dispatched at run time in a portable build (MS_KERNEL_CLONES, core.h): the 2D grid's EOS. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__AVX512F__)
__attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#endif
static void
mg_linear_eval_array(const eos_t *eos, size_t n, const double *restrict rho,
                     const double *restrict e, double *restrict p, double *restrict c2) {
  const mg_linear *m = eos->data;
  const double rho0 = eos->rho0, s = m->s, k = rho0 * m->c0 * m->c0, G = m->gamma0 * rho0;
  for (size_t i = 0; i < n; ++i) {
    double r = rho[i], eta = 1.0 - rho0 / r, den = 1.0 - s * eta;
    double ph = k * eta / (den * den), eh = ph * eta / (2.0 * rho0);
    double pi = ph + G * (e[i] - eh);
    p[i] = den > 0.0 ? pi : NAN;
    if (c2) {
      double dph_deta = k * (1.0 + s * eta) / (den * den * den);
      double deta_drho = rho0 / (r * r);
      double dph = dph_deta * deta_drho, deh = (dph_deta * eta + ph) / (2.0 * rho0) * deta_drho;
      double ci = dph - G * deh + pi / (r * r) * G;
      c2[i] = den > 0.0 ? ci : NAN;
    }
  }
}

static const eos_ops mg_linear_ops = {mg_linear_pressure,
                                      mg_linear_c2,
                                      eos_isentrope_cold_pressure,
                                      eos_isentrope_cold_energy,
                                      NULL,
                                      NULL,
                                      mg_linear_eval,
                                      mg_linear_eval_array};

/* Range of the tabulated isentrope (docs/eos.md): compression up to 3 or 95 % of the limiting
 * compression s/(s−1); tension down to 10 % above the spinodal δ = s/(s+1) of the reference
 * curve (where ∂P_H/∂ρ = 0), and not below 0.5. */
eos_t *eos_create_mg_linear(double rho0, double c0, double s, double gamma0) {
  if (!(rho0 > 0.0) || !(c0 > 0.0) || !(s >= 0.0) || !(gamma0 >= 0.0) || !isfinite(rho0) ||
      !isfinite(c0) || !isfinite(s) || !isfinite(gamma0))
    return NULL;
  mg_linear m = {c0, s, gamma0};
  eos_t *eos = eos_alloc(EOS_MG_LINEAR, &mg_linear_ops, rho0, &m, sizeof m);
  eos->c0 = c0;
  double dmax = 3.0, dmin = 0.5;
  if (s > 1.0) dmax = fmin(dmax, 0.95 * s / (s - 1.0));
  if (s > 0.0) dmin = fmax(dmin, 1.1 * s / (s + 1.0));
  if (eos_build_isentrope_cold(eos, dmin, dmax, 2000) != MS_OK) {
    eos_destroy(&eos);
    return NULL;
  }
  return eos;
}

/* ------------------------------------------------------------------------------------------ */
/* Ideal gas: P = (γ−1)ρe, c² = γ(γ−1)e = γP/ρ; domain e ≥ 0. Cold curve P_x = ε_x = 0. */

typedef struct ideal_gas {
  double gamma, p0;
} ideal_gas;

static double ideal_pressure(const eos_t *eos, double rho, double e) {
  const ideal_gas *g = eos->data;
  return e >= 0.0 ? (g->gamma - 1.0) * rho * e : NAN;
}

static double ideal_c2(const eos_t *eos, double rho, double e) {
  const ideal_gas *g = eos->data;
  return e >= 0.0 ? g->gamma * (g->gamma - 1.0) * e : NAN;
}

static double zero_cold(const eos_t *eos, double delta) { return 0.0; }

static double ideal_temperature(const eos_t *eos, double rho, double e) {
  return e >= 0.0 ? e / eos->cv : NAN;
}

static void ideal_eval_array(const eos_t *eos, size_t n, const double *restrict rho,
                             const double *restrict e, double *restrict p, double *restrict c2) {
  const ideal_gas *g = eos->data;
  const double gm1 = g->gamma - 1.0, ggm1 = g->gamma * (g->gamma - 1.0);
  for (size_t i = 0; i < n; ++i) p[i] = e[i] >= 0.0 ? gm1 * rho[i] * e[i] : NAN;
  if (c2)
    for (size_t i = 0; i < n; ++i) c2[i] = e[i] >= 0.0 ? ggm1 * e[i] : NAN;
}

static const eos_ops ideal_ops = {ideal_pressure,    ideal_c2, zero_cold, zero_cold,
                                  ideal_temperature, NULL,     NULL,      ideal_eval_array};

eos_t *eos_create_ideal_gas_ref(double gamma, double rho0, double p0) {
  if (!(gamma > 1.0) || !(rho0 > 0.0) || !(p0 >= 0.0) || !isfinite(gamma) || !isfinite(rho0) ||
      !isfinite(p0))
    return NULL;
  ideal_gas g = {gamma, p0};
  eos_t *eos = eos_alloc(EOS_IDEAL_GAS, &ideal_ops, rho0, &g, sizeof g);
  eos->c0 = sqrt(gamma * p0 / rho0);
  eos->e0 = p0 / ((gamma - 1.0) * rho0);
  eos->delta_min = 0.0;
  return eos;
}

eos_t *eos_create_ideal_gas(double gamma, double rho0) {
  return eos_create_ideal_gas_ref(gamma, rho0, 1.01325e-4); /* 1 atm in GPa */
}

/* ------------------------------------------------------------------------------------------ */
/* Linear elastic solid ([Sofronov] rod tests), docs/eos.md: volumetric strain θ = 1 − ρ0/ρ
 * (positive in compression; −tr E of the discrete model to first order),
 *   P = P_x = Kθ,  ε_x = ∫₁^δ P_x/(ρ0 d²) dd = Kθ²/(2ρ0),  c² = dP/dρ = Kρ0/ρ²;
 * no thermal pressure (Γ = 0), so P does not depend on e. */

typedef struct lin_elastic {
  double K;
} lin_elastic;

static double elastic_px(const eos_t *eos, double delta) {
  const lin_elastic *l = eos->data;
  return l->K * (1.0 - 1.0 / delta);
}

static double elastic_ex(const eos_t *eos, double delta) {
  const lin_elastic *l = eos->data;
  double theta = 1.0 - 1.0 / delta;
  return l->K * theta * theta / (2.0 * eos->rho0);
}

static double elastic_pressure(const eos_t *eos, double rho, double e) {
  return elastic_px(eos, rho / eos->rho0);
}

static double elastic_c2(const eos_t *eos, double rho, double e) {
  const lin_elastic *l = eos->data;
  return l->K * eos->rho0 / (rho * rho);
}

static const eos_ops elastic_ops = {
    elastic_pressure, elastic_c2, elastic_px, elastic_ex, NULL, NULL, NULL, NULL};

eos_t *eos_create_linear_elastic(double rho0, double bulk_modulus) {
  if (!(rho0 > 0.0) || !(bulk_modulus > 0.0) || !isfinite(rho0) || !isfinite(bulk_modulus))
    return NULL;
  lin_elastic l = {bulk_modulus};
  eos_t *eos = eos_alloc(EOS_LINEAR_ELASTIC, &elastic_ops, rho0, &l, sizeof l);
  eos->c0 = sqrt(bulk_modulus / rho0);
  eos->delta_min = 0.0;
  return eos;
}
