/* SPDX-License-Identifier: MIT */
/* Analytic EOS kinds and the tabulated cold curve of [Davydov] (docs/eos.md):
 * Table 1 of [Davydov] reproduced, f = −dE/dr, ε_x vs ∫P_x, sound speed vs the isentrope. */
#include <math.h>

#include "eos_impl.h"
#include "eos_test_util.h"

/* ---- Table 1 of [Davydov] ---------------------------------------------------------------- */

/* The printed E(r) [J] and f(r) [N] columns for r/r0 = 0.75 ... 1.30 (r0 = 5 µm). */
static const double table1_r[] = {0.75, 0.8, 0.85, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2, 1.25, 1.3};
static const double table1_E[] = {8.304E-07, 4.332E-07, 1.969E-07, 7.249E-08, 1.513E-08, 0,
                                  1.053E-08, 3.583E-08, 7.042E-08, 1.117E-07, 1.585E-07, 2.102E-07};
static const double table1_f[] = {1.936E+00,  1.253E+00,  6.796E-01,  3.437E-01,
                                  1.317E-01,  0,          -7.678E-02, -1.222E-01,
                                  -1.529E-01, -1.766E-01, -1.971E-01, -2.163E-01};

static eos_t *load_al_osa(void) {
  char path[1024];
  eos_test_source_path(path, sizeof path, "eos/data/al_osa_cold.txt");
  dk_errors e;
  dk_errors_init(&e);
  eos_t *eos = eos_create_table_cold(path, 2.0, false, &e);
  if (!eos) eos_test_dump(&e);
  assert_non_null(eos);
  dk_errors_free(&e);
  return eos;
}

/* Pair potential of docs/design.md §5.1 in SI: E(r) = (√2 ρ0 r0³/12) ε_x((r0/r)³),
 * f(r) = (√2/4) r² P_x((r0/r)³); ρ0 kg/m³, ε_x J/kg (= 1e6 kJ/g... 1 kJ/g = 1e6 J/kg),
 * P_x Pa (1 GPa = 1e9 Pa). */
static double pair_energy_si(const eos_t *eos, double r, double r0) {
  double rho0 = eos_rho0(eos) * 1e3;
  return sqrt(2.0) * rho0 * r0 * r0 * r0 / 12.0 * eos_cold_energy(eos, pow(r0 / r, 3)) * 1e6;
}
static double pair_force_si(const eos_t *eos, double r, double r0) {
  return sqrt(2.0) / 4.0 * r * r * eos_cold_pressure(eos, pow(r0 / r, 3)) * 1e9;
}

/* Half a unit in the last printed place of a 4-significant-digit number. */
static double half_ulp4(double printed) {
  return printed == 0.0 ? 1e-30 : 0.5 * pow(10.0, floor(log10(fabs(printed))) - 3);
}

static void test_table1_reproduced(void **state) {
  (void)state;
  eos_t *al = load_al_osa();
  assert_true(fabs(eos_rho0(al) - 2.71) < 1e-15);
  const double r0 = 5e-6;
  for (size_t i = 0; i < sizeof table1_r / sizeof table1_r[0]; ++i) {
    double r = table1_r[i] * r0;
    double E = pair_energy_si(al, r, r0), f = pair_force_si(al, r, r0);
    /* "to the printed digits": within half a unit of the 4th significant digit (the worst row
     * is 0.48 of it); at r = r0 both are 0 to round-off. */
    double tolE = half_ulp4(table1_E[i]), tolf = half_ulp4(table1_f[i]);
    if (table1_E[i] == 0.0) tolE = 1e-20, tolf = 1e-12;
    if (fabs(E - table1_E[i]) > tolE || fabs(f - table1_f[i]) > tolf)
      fail_msg("r/r0 = %g: E = %.6e (printed %.3e), f = %.6e (printed %.3e)", table1_r[i], E,
               table1_E[i], f, table1_f[i]);
  }
  eos_destroy(&al);
}

/* The data file holds the printed columns exactly; the EOS reproduces them at the nodes. */
static void test_table1_nodes(void **state) {
  (void)state;
  eos_t *al = load_al_osa();
  static const double rho[] = {6.423704, 5.292969, 4.412782, 3.717421, 3.160811, 2.71,
                               2.341,    2.036063, 1.781869, 1.568287, 1.38752,  1.2335};
  static const double eps[] = {20.801,  10.8512, 4.93168, 1.81569, 0.3791,  0,
                               0.26366, 0.89746, 1.76385, 2.79802, 3.96943, 5.26428};
  static const double px[] = {389.39,  221.446, 106.423, 48.0046, 16.5038, 0,
                              -7.8793, -11.425, -13.079, -13.878, -14.275, -14.478};
  for (size_t i = 0; i < 12; ++i) {
    double d = rho[i] / 2.71;
    /* Hermite interpolation is exact at nodes up to round-off (1e-12 relative). */
    assert_true(fabs(eos_cold_energy(al, d) - eps[i]) <= 1e-12 * (1 + fabs(eps[i])));
    assert_true(fabs(eos_cold_pressure(al, d) - px[i]) <= 1e-12 * (1 + fabs(px[i])));
  }
  /* Outside the table: NaN, never an extrapolated value. */
  assert_true(isnan(eos_cold_energy(al, 0.4)));
  assert_true(isnan(eos_cold_pressure(al, 2.5)));
  assert_true(isnan(eos_pressure(al, 2.71 * 2.5, 1.0)));
  double dmin, dmax;
  assert_true(eos_cold_range(al, &dmin, &dmax));
  assert_true(fabs(dmin - 1.2335 / 2.71) < 1e-15 && fabs(dmax - 6.423704 / 2.71) < 1e-15);
  eos_destroy(&al);
}

/* f = −dE/dr: central differences of E(r) at points between table nodes (E is C¹ and piecewise
 * smooth, so away from nodes the error is O(h²) ≈ 1e-10 relative for h = 1e-5 r0; 1e-6 leaves
 * room for round-off in E ~ 1e-7 J differences). */
static void check_force_is_minus_dE(const eos_t *eos, double r0, double rlo, double rhi) {
  double fscale =
      fmax(fabs(pair_force_si(eos, rlo * r0, r0)), fabs(pair_force_si(eos, rhi * r0, r0)));
  for (int k = 0; k < 200; ++k) {
    double x = rlo + (rhi - rlo) * (k + 0.37) / 200.0, r = x * r0, h = 1e-5 * r0;
    double dE = (pair_energy_si(eos, r + h, r0) - pair_energy_si(eos, r - h, r0)) / (2 * h);
    double f = pair_force_si(eos, r, r0);
    if (fabs(f + dE) > 1e-6 * fscale) fail_msg("r/r0 = %g: f = %.10e, -dE/dr = %.10e", x, f, -dE);
  }
}

static void test_force_is_minus_dE_dr(void **state) {
  (void)state;
  eos_t *al = load_al_osa();
  check_force_is_minus_dE(al, 5e-6, 0.7501, 1.2999);
  eos_t *pb = eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, false);
  check_force_is_minus_dE(pb, 5e-6, 0.7, 1.3);
  eos_destroy(&pb);
  eos_destroy(&al);
}

/* ---- Mie–Grüneisen cold form --------------------------------------------------------------- */

/* Composite Simpson of P_x/(ρ0 d²) from 1 to δ (4000 panels: error ~1e-14 relative). */
static double integrate_cold_energy(const eos_t *eos, double delta) {
  const int n = 4000;
  double h = (delta - 1.0) / n, sum = 0.0, rho0 = eos_rho0(eos);
  for (int i = 0; i <= n; ++i) {
    double d = 1.0 + i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    sum += w * eos_cold_pressure(eos, d) / (rho0 * d * d);
  }
  return sum * h / 3.0;
}

static void test_mg_cold_energy_is_integral(void **state) {
  (void)state;
  /* [Davydov] parameters: Pb, B4C, h-BN (docs/design.md §3). */
  const double par[3][3] = {{11.34, 1.972, 3.0}, {2.51, 9.06, 3.13}, {2.29, 3.19, 10.41}};
  const double deltas[] = {0.6, 0.8, 0.95, 1.05, 1.3, 1.7, 2.2};
  for (int m = 0; m < 3; ++m) {
    eos_t *eos = eos_create_mg_cold(par[m][0], par[m][1], par[m][2], 1.5, false);
    assert_non_null(eos);
    assert_true(eos_cold_energy(eos, 1.0) == 0.0 && fabs(eos_cold_pressure(eos, 1.0)) < 1e-15);
    for (size_t k = 0; k < sizeof deltas / sizeof deltas[0]; ++k) {
      double exact = eos_cold_energy(eos, deltas[k]), num = integrate_cold_energy(eos, deltas[k]);
      /* Simpson with 4000 panels: truncation < 1e-12 relative even for n = 10.41 at δ = 2.2. */
      if (fabs(exact - num) > 1e-10 * fabs(exact))
        fail_msg("material %d, delta %g: eps_x = %.15g, integral = %.15g", m, deltas[k], exact,
                 num);
    }
    eos_destroy(&eos);
  }
}

/* The RK4 isentrope tabulation that gives the Us–up form and full tables their cold curves,
 * checked on the MG cold form where the isentrope through (ρ0, 0) is ε_x itself. RK4 with
 * step 5e-4 in δ and cubic Hermite between nodes: error ~1e-13 c0²; 1e-9 c0² is generous. */
static void test_isentrope_integrator(void **state) {
  (void)state;
  eos_t *eos = eos_create_mg_cold(2.51, 9.06, 3.13, 1.2, false);
  assert_int_equal(eos_build_isentrope_cold(eos, 0.6, 2.0, 2000), MS_OK);
  double c02 = 9.06 * 9.06;
  for (double d = 0.6; d <= 2.0; d += 0.0137) {
    double exact = eos_cold_energy(eos, d), tab = eos_isentrope_cold_energy(eos, d);
    if (fabs(exact - tab) > 1e-9 * c02) fail_msg("delta %g: %.15g vs %.15g", d, exact, tab);
    double pe = eos_cold_pressure(eos, d), pt = eos_isentrope_cold_pressure(eos, d);
    if (fabs(pe - pt) > 1e-8 * 2.51 * c02) fail_msg("delta %g: P %.15g vs %.15g", d, pe, pt);
  }
  eos_destroy(&eos);
}

/* Cold curves that are tabulated isentropes (Us–up form) are consistent: P_x = ρ0 δ² dε_x/dδ
 * (central differences, h = 1e-5: O(h²) error ≈ 1e-10, Hermite kinks between RK4 nodes
 * 5e-4 apart are smaller than 1e-7 relative). */
static void test_mg_linear_cold_curve(void **state) {
  (void)state;
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  assert_non_null(al);
  double dmin, dmax;
  assert_true(eos_cold_range(al, &dmin, &dmax));
  assert_true(dmin < 0.7 && dmax > 2.5);
  assert_true(fabs(eos_cold_energy(al, 1.0)) < 1e-15 && fabs(eos_cold_pressure(al, 1.0)) < 1e-12);
  for (double d = 0.7; d < 2.5; d += 0.0731) {
    double h = 1e-5;
    double de = (eos_cold_energy(al, d + h) - eos_cold_energy(al, d - h)) / (2 * h);
    double p = eos_cold_pressure(al, d), p_fd = 2.703 * d * d * de;
    if (fabs(p - p_fd) > 1e-6 * (fabs(p) + 1.0))
      fail_msg("delta %g: P_x %.12g, fd %.12g", d, p, p_fd);
  }
  /* The cold curve lies below the Hugoniot: e_H(ρ) ≥ ε_x at the same ρ (entropy rises). */
  for (double d = 1.05; d < 2.0; d += 0.1) {
    double eta = 1 - 1 / d, ph = 2.703 * 5.35 * 5.35 * eta / pow(1 - 1.34 * eta, 2);
    assert_true(ph * eta / (2 * 2.703) > eos_cold_energy(al, d));
  }
  /* Beyond the limiting compression s/(s−1) the Us–up form is undefined: NaN, not garbage. */
  assert_true(isnan(eos_pressure(al, 2.703 * 1.34 / 0.34 * 1.01, 1.0)));
  eos_destroy(&al);
}

/* Linear elastic: P = K(1 − ρ0/ρ), ε_x = Kθ²/(2ρ0), c² = Kρ0/ρ² (docs/eos.md). */
static void test_linear_elastic(void **state) {
  (void)state;
  const double rho0 = 7.85, K = 200.0 / 3.0; /* [Sofronov] rod: E = 200, ν = 0 */
  eos_t *s = eos_create_linear_elastic(rho0, K);
  assert_non_null(s);
  assert_true(fabs(eos_c0(s) - sqrt(K / rho0)) < 1e-14);
  for (double d = 0.98; d <= 1.02; d += 0.005) {
    double theta = 1 - 1 / d;
    assert_true(fabs(eos_pressure(s, rho0 * d, 3.0) - K * theta) < 1e-13);
    assert_true(fabs(eos_cold_energy(s, d) - integrate_cold_energy(s, d)) < 1e-14);
  }
  eos_destroy(&s);
}

/* ---- Sound speed against a finite-difference isentrope ------------------------------------- */

/* c² = dP/dρ along de = (P/ρ²) dρ: one RK4 step of the isentrope each way from (ρ, e) with
 * h = 1e-4 ρ, then a central difference: O(h²) ≈ 1e-8 relative, so tolerance 1e-6. */
static double isentrope_c2_fd(const eos_t *eos, double rho, double e) {
  double h = 1e-4 * rho, p[2];
  for (int s = 0; s < 2; ++s) {
    double dr = s ? h : -h, r = rho, en = e;
#define SLOPE(rr, ee) (eos_pressure(eos, rr, ee) / ((rr) * (rr)))
    double k1 = SLOPE(r, en), k2 = SLOPE(r + dr / 2, en + dr / 2 * k1);
    double k3 = SLOPE(r + dr / 2, en + dr / 2 * k2), k4 = SLOPE(r + dr, en + dr * k3);
#undef SLOPE
    p[s] = eos_pressure(eos, r + dr, en + dr / 6 * (k1 + 2 * k2 + 2 * k3 + k4));
  }
  return (p[1] - p[0]) / (2 * h);
}

static void check_sound_speed(const eos_t *eos, double rho, double e, const char *what) {
  double c = eos_sound_speed(eos, rho, e), c2fd = isentrope_c2_fd(eos, rho, e);
  assert_true(c > 0.0);
  if (!(fabs(c * c - c2fd) <= 1e-6 * c2fd))
    fail_msg("%s at rho = %g, e = %g: c^2 = %.12g, isentrope %.12g", what, rho, e, c * c, c2fd);
}

static void test_sound_speed_isentrope(void **state) {
  (void)state;
  eos_t *kinds[5];
  kinds[0] = eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, false);
  kinds[1] = eos_create_mg_cold(2.29, 3.19, 10.41, 1.5, true);
  kinds[2] = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  kinds[3] = eos_create_ideal_gas(1.4, 1.225e-3);
  kinds[4] = eos_create_linear_elastic(7.85, 200.0 / 3.0);
  const double states[][2] = {{0.9, 0.05}, {1.0, 0.0}, {1.0, 0.5}, {1.3, 1.0}, {1.8, 6.0}};
  for (int k = 0; k < 5; ++k) {
    assert_non_null(kinds[k]);
    double rho0 = eos_rho0(kinds[k]);
    for (size_t s = 0; s < sizeof states / sizeof states[0]; ++s) {
      double e = states[s][1];
      if (k == 3) e += 0.2; /* ideal gas: a state with P > 0 */
      check_sound_speed(kinds[k], rho0 * states[s][0], e, eos_kind_name(eos_get_kind(kinds[k])));
    }
  }
  /* Table cold curve between nodes (Hermite P_x' is smooth inside an interval). */
  eos_t *al = load_al_osa();
  check_sound_speed(al, 2.71 * 1.08, 0.3, "table_cold");
  check_sound_speed(al, 2.71 * 1.5, 2.0, "table_cold");
  check_sound_speed(al, 2.71 * 0.93, 0.5, "table_cold");
  /* c0 is the sound speed at the reference state. */
  assert_true(fabs(eos_sound_speed(kinds[0], 11.34, 0.0) - 1.972) < 1e-14);
  assert_true(fabs(eos_sound_speed(kinds[2], 2.703, 0.0) - 5.35) < 1e-14);
  /* Ideal gas: c0 = sqrt(γ p0/ρ0) at 1 atm, 1.225 kg/m³: 0.3403 km/s. */
  assert_true(fabs(eos_c0(kinds[3]) - 0.34029) < 1e-4);
  for (int k = 0; k < 5; ++k) eos_destroy(&kinds[k]);
  eos_destroy(&al);
}

/* eos_eval: the array form (fused P and c² where a kind has them) agrees with the scalar
 * functions to round-off (1e-13: powers computed differently), and flags states outside the
 * domain. */
static void test_eval_array(void **state) {
  (void)state;
  eos_t *kinds[7] = {eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, false),
                     eos_create_mg_cold(2.29, 3.19, 10.41, 1.5, true),
                     eos_create_mg_linear(2.703, 5.35, 1.34, 2.0),
                     eos_create_ideal_gas(1.4, 1.225e-3),
                     eos_create_linear_elastic(7.85, 66.0),
                     load_al_osa(),
                     NULL};
  kinds[6] = eos_create_table_from(kinds[2], 2.5, 4.0, 31, 0.0, 3.0, 13);
  for (int k = 0; k < 7; ++k) {
    assert_non_null(kinds[k]);
    enum { N = 64 };
    double r[N], en[N], p[N], c[N];
    for (int i = 0; i < N; ++i) {
      r[i] = eos_rho0(kinds[k]) * (0.95 + 0.4 * i / N);
      en[i] = 0.05 + 2.0 * ((i * 13) % N) / N;
    }
    size_t bad = 99;
    assert_int_equal(eos_eval(kinds[k], N, r, en, p, c, &bad), MS_OK);
    for (int i = 0; i < N; ++i) {
      double ps = eos_pressure(kinds[k], r[i], en[i]), cs = eos_sound_speed(kinds[k], r[i], en[i]);
      if (fabs(p[i] - ps) > 1e-13 * (fabs(ps) + 1.0) || fabs(c[i] - cs) > 1e-13 * cs)
        fail_msg("%s: eval (%.17g, %.17g) vs scalar (%.17g, %.17g)",
                 eos_kind_name(eos_get_kind(kinds[k])), p[i], c[i], ps, cs);
    }
    eos_destroy(&kinds[k]);
  }

  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  double rho[4] = {2.703, 3.0, 3.5, 4.0}, e[4] = {0.0, 0.5, 1.0, 2.0}, p[4], c[4];
  size_t bad = 99;
  assert_int_equal(eos_eval(al, 4, rho, e, p, c, &bad), MS_OK);
  for (int i = 0; i < 4; ++i) {
    assert_true(p[i] == eos_pressure(al, rho[i], e[i]));
    assert_true(c[i] == eos_sound_speed(al, rho[i], e[i]));
  }
  rho[2] = 20.0; /* beyond the limiting compression ρ0 s/(s−1) = 10.65 */
  assert_int_equal(eos_eval(al, 4, rho, e, p, NULL, &bad), MS_ERR_UNSTABLE);
  assert_int_equal(bad, 2);
  rho[2] = -1.0;
  assert_int_equal(eos_eval(al, 4, rho, e, p, c, &bad), MS_ERR_UNSTABLE);
  assert_int_equal(bad, 2);
  eos_destroy(&al);
  /* Constructors refuse impossible parameters. */
  assert_null(eos_create_mg_cold(-1.0, 2.0, 3.0, 2.0, false));
  assert_null(eos_create_mg_cold(1.0, 2.0, 1.0, 2.0, false));
  assert_null(eos_create_mg_cold(1.0, 2.0, 3.0, -0.1, false));
  assert_null(eos_create_mg_linear(2.7, 5.35, -1.0, 2.0));
  assert_null(eos_create_ideal_gas(1.0, 1e-3));
  assert_null(eos_create_linear_elastic(7.85, 0.0));
}

/* Temperature with a constant specific heat: T = (e − ε_x)/cv, ideal gas T = e/cv. */
static void test_temperature(void **state) {
  (void)state;
  eos_t *pb = eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, false);
  assert_true(isnan(eos_temperature(pb, 11.34, 0.1)));          /* no cv given */
  assert_int_equal(eos_set_heat_capacity(pb, 0.129e-3), MS_OK); /* lead: 129 J/(kg K) */
  assert_int_equal(eos_set_heat_capacity(pb, -1.0), MS_ERR_INPUT);
  for (double d = 0.9; d < 1.5; d += 0.1) {
    double ex = eos_cold_energy(pb, d);
    assert_true(fabs(eos_temperature(pb, 11.34 * d, ex)) < 1e-9); /* on the cold curve: 0 K */
    assert_true(fabs(eos_temperature(pb, 11.34 * d, ex + 0.129e-3 * 300.0) - 300.0) < 1e-9);
  }
  eos_destroy(&pb);
  /* air: cv = 718 J/(kg K); at 1 atm, 1.225 kg/m³ the ideal-gas temperature is
   * p0/(ρ0 (γ−1) cv) = 288.1 K */
  eos_t *air = eos_create_ideal_gas(1.4, 1.225e-3);
  eos_set_heat_capacity(air, 0.718e-3);
  assert_true(fabs(eos_temperature(air, 1.225e-3, eos_e0(air)) - 288.1) < 0.1);
  assert_true(isnan(eos_temperature(air, 1.225e-3, -0.1)));
  eos_destroy(&air);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_table1_reproduced),
      cmocka_unit_test(test_table1_nodes),
      cmocka_unit_test(test_force_is_minus_dE_dr),
      cmocka_unit_test(test_mg_cold_energy_is_integral),
      cmocka_unit_test(test_isentrope_integrator),
      cmocka_unit_test(test_mg_linear_cold_curve),
      cmocka_unit_test(test_linear_elastic),
      cmocka_unit_test(test_sound_speed_isentrope),
      cmocka_unit_test(test_eval_array),
      cmocka_unit_test(test_temperature),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
