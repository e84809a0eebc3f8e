/* SPDX-License-Identifier: MIT */
/* Symplectic RKN integrators: coefficient conditions, measured convergence order, bounded
 * energy error (docs/design.md §5.2, [Sofronov] §2). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "ptl.h"

/* Nonlinear test problem (a linear one could hide order defects): two coupled anharmonic
 * oscillators, a = −∂V/∂q with V = ½q0² + ½q1² + ¼q0⁴ + ½ q0² q1 (smooth, bounded orbits for the
 * small initial data used). */
static ms_status anharmonic(void *user, double t, const double *q, double *a) {
  (void)user;
  (void)t;
  a[0] = -q[0] - q[0] * q[0] * q[0] - q[0] * q[1];
  a[1] = -q[1] - 0.5 * q[0] * q[0];
  return MS_OK;
}

static double anharmonic_energy(const double *q, const double *u) {
  return 0.5 * (u[0] * u[0] + u[1] * u[1]) + 0.5 * (q[0] * q[0] + q[1] * q[1]) +
         0.25 * q[0] * q[0] * q[0] * q[0] + 0.5 * q[0] * q[0] * q[1];
}

static void integrate(rkn_kind kind, double dt, double T, double q[2], double u[2]) {
  rkn_integrator *ig = NULL;
  ms_must(rkn_create(&(rkn_params){.kind = kind, .ndof = 2}, &ig), "rkn_create");
  q[0] = 0.6, q[1] = -0.3, u[0] = 0.0, u[1] = 0.4;
  long n = lround(T / dt);
  for (long s = 0; s < n; ++s)
    assert_int_equal(rkn_step(ig, s * dt, dt, q, u, anharmonic, NULL, NULL), MS_OK);
  rkn_destroy(&ig);
}

/* Order conditions of RKN methods up to order 4 with b = γ, c = α, a_lk = γ_k(α_l − α_k)
 * ([Sofronov] §2; the β conditions follow from β = γ(1 − α) for symplectic schemes):
 * Σb = 1, Σbc = ½, Σbc² = ⅓, Σbc³ = ¼, Σ b_l a_lk = 1/6, Σ b_l c_l a_lk = 1/8,
 * Σ b_l a_lk c_k = 1/24. Residuals are pure round-off of O(1) sums: < 1e-14. */
static void test_coefficients(void **state) {
  (void)state;
  for (int k = 0; k < RKN_KIND_COUNT; ++k) {
    const rkn_scheme *s = rkn_scheme_get((rkn_kind)k);
    assert_non_null(s);
    assert_string_equal(s->name, rkn_scheme_names[k]);
    double sg = 0, sga = 0, sga2 = 0, sga3 = 0, sba = 0, sbca = 0, sbac = 0;
    for (int l = 0; l < s->stages; ++l) {
      double g = s->gamma[l], a = s->alpha[l];
      sg += g, sga += g * a, sga2 += g * a * a, sga3 += g * a * a * a;
      for (int m = 0; m < l; ++m) {
        double alm = s->gamma[m] * (a - s->alpha[m]);
        sba += g * alm, sbca += g * a * alm, sbac += g * alm * s->alpha[m];
      }
    }
    assert_true(fabs(sg - 1.0) < 1e-14);
    assert_true(fabs(sga - 0.5) < 1e-14);
    if (s->order >= 4) {
      assert_true(fabs(sga2 - 1.0 / 3.0) < 1e-14);
      assert_true(fabs(sga3 - 0.25) < 1e-14);
      assert_true(fabs(sba - 1.0 / 6.0) < 1e-14);
      assert_true(fabs(sbca - 1.0 / 8.0) < 1e-14);
      assert_true(fabs(sbac - 1.0 / 24.0) < 1e-14);
    }
  }
}

/* Measured order: errors at T = 10 against a reference (RKN4, dt = 1/2048) for dt halved
 * from 0.2 (4th order) or 0.05 (Verlet); the order is the least-squares slope of log error vs
 * log dt. The issue asks for the expected order ± 0.2. */
static void test_convergence_order(void **state) {
  (void)state;
  const double T = 10.0;
  double qref[2], uref[2];
  integrate(RKN_RKN4, 1.0 / 2048.0, T, qref, uref);
  for (int k = 0; k < RKN_KIND_COUNT; ++k) {
    const rkn_scheme *s = rkn_scheme_get((rkn_kind)k);
    double dt0 = s->order == 2 ? 0.05 : 0.2;
    double lx[4], ly[4];
    for (int j = 0; j < 4; ++j) {
      double dt = dt0 / pow(2.0, j), q[2], u[2];
      integrate((rkn_kind)k, dt, T, q, u);
      double err =
          hypot(hypot(q[0] - qref[0], q[1] - qref[1]), hypot(u[0] - uref[0], u[1] - uref[1]));
      lx[j] = log(dt);
      ly[j] = log(err);
    }
    double mx = 0, my = 0;
    for (int j = 0; j < 4; ++j) mx += lx[j] / 4, my += ly[j] / 4;
    double sxy = 0, sxx = 0;
    for (int j = 0; j < 4; ++j)
      sxy += (lx[j] - mx) * (ly[j] - my), sxx += (lx[j] - mx) * (lx[j] - mx);
    double order = sxy / sxx;
    printf("%-15s measured order %.3f (expected %d)\n", s->name, order, s->order);
    assert_true(fabs(order - s->order) < 0.2);
  }
}

/* Symplectic: the energy error oscillates but does not drift over 1e5 steps. The error stays
 * below a bound of the size of its first-period maximum (×2 for margin), and the mean over the
 * last tenth differs from the mean over the first tenth by less than 10 % of that bound — a
 * drifting (non-symplectic) scheme such as explicit Euler or RK2 fails both. */
static void test_energy_bounded(void **state) {
  (void)state;
  for (int k = 0; k < RKN_KIND_COUNT; ++k) {
    rkn_integrator *ig = NULL;
    ms_must(rkn_create(&(rkn_params){.kind = (rkn_kind)k, .ndof = 2}, &ig), "rkn_create");
    double q[2] = {0.6, -0.3}, u[2] = {0.0, 0.4};
    double E0 = anharmonic_energy(q, u), dt = 0.1;
    long nsteps = 100000, tenth = nsteps / 10;
    double max_first = 0, max_all = 0, mean_first = 0, mean_last = 0;
    for (long s = 0; s < nsteps; ++s) {
      rkn_step(ig, s * dt, dt, q, u, anharmonic, NULL, NULL);
      double err = anharmonic_energy(q, u) - E0;
      if (s < 100) max_first = fmax(max_first, fabs(err));
      max_all = fmax(max_all, fabs(err));
      if (s < tenth) mean_first += err / tenth;
      if (s >= nsteps - tenth) mean_last += err / tenth;
    }
    printf("%-15s |dE| first 10 periods' max %.3e, overall max %.3e, drift of the mean %.3e\n",
           rkn_scheme_get((rkn_kind)k)->name, max_first, max_all, mean_last - mean_first);
    assert_true(max_all < 2.0 * max_first);
    assert_true(fabs(mean_last - mean_first) < 0.1 * 2.0 * max_first);
    rkn_destroy(&ig);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_coefficients),
      cmocka_unit_test(test_convergence_order),
      cmocka_unit_test(test_energy_bounded),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
