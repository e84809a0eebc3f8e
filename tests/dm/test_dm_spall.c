/* SPDX-License-Identifier: MIT */
/* test_dm_spall.c — spall of an Al target hit by a thinner Al flyer in the finite-deformation
 * discrete model with the tensile cut-off of particles/dm/dm_fracture.c (docs/particles-dm.md
 * "Fracture", docs/validation.md "Spall"), 1D chain, at two resolutions:
 *  a. the pull-back of the free-surface velocity gives back the deck's σ_s through the acoustic
 *     formula σ = ½ ρ0 c0 Δu within 10 %, the minimum corrected for the viscous rounding of the
 *     spall pulse's front (below; Kanel's correction for the pulse's faster front,
 *     δ = h_s (1/c_b − 1/c_l) |du/dt|, vanishes here: no strength, c_l = c_b [Kanel2010]);
 *  b. the spall plane (the particles that fail first) lies within 3 spacings of the point where
 *     the two release waves, interacting, first bring the tension to σ_s: computed here by the
 *     method of characteristics on the release isentrope (below);
 *  c. K + U + E_hg + broken stays constant (1e-6 of the impact energy) and the target separates.
 * DM_SPALL_PRINT=1 prints the numbers. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "dm.h"

static int print_on(void) { return getenv("DM_SPALL_PRINT") != NULL; }

/* ---- the release isentrope through the shocked state, into tension ----
 * On it de/dρ = p/ρ² and φ(ρ) = ∫ c dρ/ρ; the Riemann invariants of 1D isentropic flow are
 * r = u + φ on C+ (dX/dt = a) and s = u − φ on C− (dX/dt = −a), a = ρc/ρ0 the Lagrangian sound
 * speed ([Courant-Friedrichs] ch. III). Tabulated from ρ1 down to ρ_min (p well below −σ_s). */
#define NIS 20000
typedef struct isentrope {
  double rho[NIS], phi[NIS], p[NIS], a[NIS];
  int n;
} isentrope;

static void isentrope_build(const eos_t *eos, double rho1, double e1, double p_stop,
                            isentrope *is) {
  const double rho0 = eos_rho0(eos), drho = (rho1 - 0.8 * rho0) / (NIS - 1);
  double rho = rho1, e = e1, phi = 0.0;
  is->n = 0;
  for (int k = 0; k < NIS; ++k) {
    const double p = eos_pressure(eos, rho, e), c = eos_sound_speed(eos, rho, e);
    assert_true(isfinite(p) && isfinite(c));
    is->rho[k] = rho, is->phi[k] = phi, is->p[k] = p, is->a[k] = rho * c / rho0, is->n = k + 1;
    if (p < p_stop) break;
    double ke[4], kf[4]; /* RK4 in ρ (step −drho) for de/dρ = p/ρ², dφ/dρ = c/ρ */
    for (int s = 0; s < 4; ++s) {
      const double fr = s == 0 ? 0 : s == 3 ? 1.0 : 0.5;
      const double rr = rho - fr * drho, ee = e - (s == 0 ? 0 : fr * drho * ke[s - 1]);
      ke[s] = eos_pressure(eos, rr, ee) / (rr * rr);
      kf[s] = eos_sound_speed(eos, rr, ee) / rr;
    }
    e -= drho * (ke[0] + 2 * ke[1] + 2 * ke[2] + ke[3]) / 6.0;
    phi -= drho * (kf[0] + 2 * kf[1] + 2 * kf[2] + kf[3]) / 6.0;
    rho -= drho;
  }
  assert_true(is->p[is->n - 1] < p_stop); /* the table reaches the tension asked for */
}

/* p and a at φ (φ decreasing along the table); beyond its end: p = −INFINITY */
static void isentrope_at(const isentrope *is, double phi, double *p, double *a) {
  if (phi >= is->phi[0]) {
    *p = is->p[0], *a = is->a[0];
    return;
  }
  if (phi <= is->phi[is->n - 1]) {
    *p = -INFINITY, *a = is->a[is->n - 1];
    return;
  }
  int lo = 0, hi = is->n - 1; /* phi[lo] > phi > phi[hi] */
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    if (is->phi[mid] > phi) lo = mid;
    else hi = mid;
  }
  const double w = (phi - is->phi[lo]) / (is->phi[hi] - is->phi[lo]);
  *p = is->p[lo] + w * (is->p[hi] - is->p[lo]), *a = is->a[lo] + w * (is->a[hi] - is->a[lo]);
}

/* The first point (X, t) where the interaction of the two centred release fans reaches
 * p = −σ_s. Flyer [−df, 0], target [0, dt], impact at t = 0, shocks at Lagrangian speed Us.
 * Fan A (C+ fan) is centred at (−df, df/Us): on it s = u1 − φ1 and its C+ characteristic j
 * (φ_j from φ1 = 0 down to φ_r, p(φ_r) = 0) is straight until it meets fan B; fan B (C− fan)
 * is centred at (dt, dt/Us) with r = u1 + φ1. Where they cross, C+ j keeps r_j = u1 − φ1 +
 * 2φ_j and C− k keeps s_k = u1 + φ1 − 2φ_k, so φ = φ_j + φ_k − φ1 (tension) and the point
 * follows from the two neighbours by the second-order characteristic step (trapezoidal
 * slopes). N characteristics per fan. */
typedef struct moc_point {
  double X, t, a;
} moc_point;

static void spall_point(const isentrope *is, double Us, double df, double dt, double sigma_s, int N,
                        double *X_sp, double *t_sp, double *dphi_A) {
  /* φ_r: where p = 0 on the isentrope */
  double phi_r = NAN;
  for (int k = 1; k < is->n; ++k)
    if (is->p[k] <= 0) {
      const double w = is->p[k - 1] / (is->p[k - 1] - is->p[k]);
      phi_r = is->phi[k - 1] + w * (is->phi[k] - is->phi[k - 1]);
      break;
    }
  assert_true(isfinite(phi_r));
  const double phi1 = is->phi[0];
  moc_point *prev = calloc((size_t)N + 1, sizeof *prev), *cur = calloc((size_t)N + 1, sizeof *cur);
  const double tA = df / Us, tB = dt / Us;
  double phi_ch[N + 1], a_ch[N + 1];
  for (int j = 0; j <= N; ++j) {
    double p;
    phi_ch[j] = phi1 + (phi_r - phi1) * j / N;
    isentrope_at(is, phi_ch[j], &p, &a_ch[j]);
  }
  *t_sp = INFINITY, *X_sp = NAN;
  for (int k = 0; k <= N; ++k) {   /* C− characteristic k of fan B */
    for (int j = 0; j <= N; ++j) { /* C+ characteristic j of fan A */
      double p, aR;
      isentrope_at(is, phi_ch[j] + phi_ch[k] - phi1, &p, &aR);
      /* C+ from P: fan A's centre (k = 0: straight, slope a_j) or point (j, k−1) */
      const double XP = k == 0 ? -df : prev[j].X, tP = k == 0 ? tA : prev[j].t;
      const double lp = k == 0 ? a_ch[j] : 0.5 * (prev[j].a + aR);
      /* C− from Q: fan B's centre (j = 0: straight, slope a_k) or point (j−1, k) */
      const double XQ = j == 0 ? dt : cur[j - 1].X, tQ = j == 0 ? tB : cur[j - 1].t;
      const double lm = j == 0 ? a_ch[k] : 0.5 * (cur[j - 1].a + aR);
      const double t = (XQ - XP + lp * tP + lm * tQ) / (lp + lm);
      cur[j] = (moc_point){XP + lp * (t - tP), t, aR};
      if (p <= -sigma_s && t < *t_sp) *t_sp = t, *X_sp = cur[j].X, *dphi_A = phi1 - phi_ch[j];
    }
    moc_point *sw = prev;
    prev = cur, cur = sw;
  }
  free(prev), free(cur);
}

/* ---- the free-surface history ----
 * u_max: the plateau (mean over the middle half between its first crossing of 99 % of the
 * maximum and the start of the pull-back); u_min: the first minimum after it (the running
 * minimum until the velocity has risen again by a quarter of the dip). */
static void pullback(const double *hist, size_t n, double *umax, double *umin) {
  double top = 0;
  for (size_t r = 0; r < n; ++r) top = fmax(top, hist[2 * r + 1]);
  size_t r0 = 0;
  while (r0 < n && hist[2 * r0 + 1] < 0.99 * top) ++r0;
  size_t r1 = r0; /* the pull-back starts: 2 % below the plateau */
  while (r1 < n && hist[2 * r1 + 1] > 0.98 * top) ++r1;
  double s = 0;
  size_t c = 0;
  for (size_t r = r0 + (r1 - r0) / 4; r < r1 - (r1 - r0) / 4; ++r) s += hist[2 * r + 1], ++c;
  *umax = s / (double)c;
  double m = INFINITY;
  for (size_t r = r1; r < n; ++r) {
    m = fmin(m, hist[2 * r + 1]);
    if (hist[2 * r + 1] > m + 0.25 * (*umax - m)) break;
  }
  *umin = m;
}

/* The minimum as the intersection of straight-line fits to the decline before it (from 30 to
 * 80 % of the dip) and to the spall pulse's rise after it (from 25 to 75 % of the dip): the
 * minimum a sharp spall front would give. */
static double fit_line(const double *hist, size_t a, size_t b, double *slope) {
  double st = 0, su = 0, stt = 0, stu = 0, n = 0;
  for (size_t r = a; r <= b; ++r) {
    const double t = hist[2 * r], u = hist[2 * r + 1];
    st += t, su += u, stt += t * t, stu += t * u, n += 1;
  }
  *slope = (n * stu - st * su) / (n * stt - st * st);
  return (su - *slope * st) / n;
}
static double pullback_tangents(const double *hist, size_t n, double umax, double umin) {
  const double du = umax - umin;
  size_t rmin = 0;
  for (size_t r = 0; r < n; ++r) /* the first minimum: the first row at umin */
    if (hist[2 * r + 1] == umin) {
      rmin = r;
      break;
    }
  size_t a = rmin, b = rmin;
  while (a > 0 && hist[2 * a + 1] < umax - 0.3 * du) --a;
  while (b > 0 && hist[2 * b + 1] < umax - 0.8 * du) --b;
  size_t c = rmin, d = rmin;
  while (c + 1 < n && hist[2 * c + 1] < umin + 0.25 * du) ++c;
  while (d + 1 < n && hist[2 * d + 1] < umin + 0.75 * du) ++d;
  if (b <= a + 1 || d <= c + 1) return umin;
  double k1, k2;
  const double c1 = fit_line(hist, a, b, &k1), c2 = fit_line(hist, c, d, &k2);
  const double t = (c2 - c1) / (k1 - k2);
  return c1 + k1 * t;
}

typedef struct spall_out {
  double sigma_est, sigma_tan, X_fail, X_sp, h, energy_err;
} spall_out;

/* Al 6061-T6 flyer of df at v onto dt of the same (mg_linear 2.703, 5.35, 1.34, Γ0 2: the
 * shipped Al, inputs/continuum-plate-impact.yaml), yield none, σ_s of the deck. */
static spall_out spall_run(double h, double v, double df, double dt, double sigma_s) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  eos_t *eos = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  const double rho0 = eos_rho0(eos), c0 = eos_c0(eos), u1 = 0.5 * v;
  eos_hugoniot_point hp;
  assert_int_equal(eos_hugoniot(eos, rho0, eos_e0(eos), 1, &u1, &hp), MS_OK);
  dm_fin_material mat = {.eos = eos,
                         .frac = {.model = DM_FRACTURE_MEAN_STRESS, .spall_strength = sigma_s}};
  /* the pull-back is over once the spall signal has crossed the scab twice */
  const double t_end = (df + dt) / hp.us + 4.0 * df / c0;
  dm_flyer_spec sp = {.dim = 1,
                      .nflyer = lround(df / h),
                      .ntarget = lround(dt / h),
                      .ny = 1,
                      .nz = 1,
                      .h = h,
                      .horizon = 1.5,
                      .mat = {mat, mat},
                      .u = {v, 0.0},
                      .par = {.cq = 2.0, .cl = 0.5, .courant = 0.4, .hourglass = 1.0, .ell = h},
                      .t_end = t_end,
                      .nhist = 20000};
  dm_flyer_result r;
  assert_int_equal(dm_flyer_run(&sp, &ctx, &r), MS_OK);
  isentrope is;
  isentrope_build(eos, hp.rho, hp.e, -2.0 * sigma_s, &is);
  spall_out o = {.h = h, .X_fail = r.X_fail - df, .energy_err = r.energy_err};
  double t_sp, dphi_A = NAN;
  spall_point(&is, hp.us, df, dt, sigma_s, 1000, &o.X_sp, &t_sp, &dphi_A);
  double umax, umin;
  pullback(r.hist, r.nhist, &umax, &umin);
  o.sigma_est = 0.5 * rho0 * c0 * (umax - umin);
  const double umin_t = pullback_tangents(r.hist, r.nhist, umax, umin);
  o.sigma_tan = 0.5 * rho0 * c0 * (umax - umin_t);
  if (print_on())
    printf("  tangents: u_min %.5f -> ½ρ0c0Δu %.4f GPa (%+.2f %%)\n", umin_t,
           0.5 * rho0 * c0 * (umax - umin_t),
           100 * (0.5 * rho0 * c0 * (umax - umin_t) / sigma_s - 1));
  /* the target separated: a fully failed layer between the spall plane and the free surface */
  long full = 0;
  for (long ix = 0; ix < sp.nflyer + sp.ntarget; ++ix) full += r.failed_layer[ix] == 1.0;
  if (print_on())
    printf("  characteristics: u_fs drop 2 (phi1 - phi_j) = %.5f km/s -> %.4f GPa\n", 2 * dphi_A,
           rho0 * c0 * dphi_A);
  if (print_on())
    printf("spall h %.5f cm (%ld + %ld particles), v %.2f km/s, p_H %.3f GPa: u_fs max %.5f "
           "min %.5f, ½ρ0c0Δu %.4f GPa vs σ_s %.4f (%+.2f %%); first failure at X %.5f cm "
           "(t %.5f), characteristics %.5f cm (t %.5f): %+.2f spacings; %zu failed, broken "
           "%.3e kJ, energy %.1e of K0, %ld steps\n",
           h, sp.nflyer, sp.ntarget, v, hp.p, umax, umin, o.sigma_est, sigma_s,
           100 * (o.sigma_est / sigma_s - 1), o.X_fail, r.t_fail, o.X_sp, t_sp,
           (o.X_fail - o.X_sp) / h, r.nfailed, r.broken, r.energy_err, r.steps);
  if (getenv("DM_SPALL_HISTORY"))
    for (size_t k = 0; k < r.nhist; ++k) printf("%.6f %.6f\n", r.hist[2 * k], r.hist[2 * k + 1]);
  assert_true(full >= 1);
  free(r.hist), free(r.profile), free(r.failed_layer);
  eos_destroy(&eos);
  ms_ctx_close(&ctx);
  return o;
}

/* σ_s = 1.2 GPa (Al 6061-T6, docs/references.md [Kanel2010]). */
static const double sigma_al = 1.2;

/* b. The spall plane: a 1 mm flyer at 0.6 km/s (p_H ≈ 4.7 GPa) onto 2 mm, at h and h/2:
 * measured +0.70 and +1.4 spacings from the characteristics' point (the shock and the fans are
 * smeared over a few spacings by the viscosity); the 3 spacings. */
static void test_spall_plane(void **state) {
  (void)state;
  const double hs[2] = {0.001, 0.0005};
  for (int k = 0; k < 2; ++k) {
    const spall_out o = spall_run(hs[k], 0.6, 0.1, 0.2, sigma_al);
    assert_true(fabs(o.X_fail - o.X_sp) < 3.0 * o.h);
    /* c. the identity of dm_finite.c with the broken term: round-off (~1e-13 per step) */
    assert_true(o.energy_err < 1e-6);
  }
}

/* a. The pull-back: a thin flyer (0.5 mm at 0.25 km/s, p_H ≈ 1.9 GPa) on a thick target
 * (10 mm): the acoustic formula assumes that the tension at the spall plane rises gradually,
 * i.e. that the flyer's release fan is much wider there than the target's; with the 1 mm / 2 mm
 * case above the two fans meet with comparable widths, the tension peak is flat over ~20
 * spacings, all of it fails at once and the pull-back gives about half of σ_s
 * (docs/validation.md "Spall"). The correction used: the spall pulse here is a weak
 * compression (σ_s), spread by the linear viscosity over ~20 spacings, whose foot reaches the
 * free surface early and rounds the minimum off; its minimum is taken where straight-line fits
 * to the decline and to the pulse's rise meet (pullback_tangents: what a sharp front gives),
 * then σ = ½ ρ0 c0 Δu (Kanel's δ = 0 without strength). Measured at h and h/2: −2.5 % and
 * −5.1 % (−6.8 % at 2h); the plain minimum gives −10.8 % and −11.9 % (−16 % at 2h). The
 * characteristics predict +2.3 % (the release's nonlinearity) for a sharp cut-off. The
 * issue's 10 %. */
static void test_pullback(void **state) {
  (void)state;
  const double hs[2] = {0.001, 0.0005};
  for (int k = 0; k < 2; ++k) {
    const spall_out o = spall_run(hs[k], 0.25, 0.05, 1.0, sigma_al);
    assert_true(fabs(o.sigma_tan / sigma_al - 1) < 0.10);
    /* the plain minimum: bounded by the rounding above (measured ≤ 12 %) */
    assert_true(fabs(o.sigma_est / sigma_al - 1) < 0.15);
    assert_true(o.energy_err < 1e-6);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_spall_plane),
                                     cmocka_unit_test(test_pullback)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
