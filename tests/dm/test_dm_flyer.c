/* SPDX-License-Identifier: MIT */
/* test_dm_flyer.c — the flyer-plate problem of the finite-deformation discrete model
 * (particles/dm/dm_flyer.c, docs/particles-dm.md "Flyer onto a target"), yield none:
 *  a. the same flyer-plate problem run by the 1D Lagrangian grid (continuum) and by the
 *     particles: free-surface velocity plateau within 0.5 %, arrival time within 1 %;
 *  b. release into vacuum: the free-surface velocity within 1 % of the exact solution for the
 *     EOS (shocked state from the Hugoniot, release isentrope to p = 0, u_fs = u1 + ∫ c dρ/ρ),
 *     and the centred rarefaction fan's velocity profile in L1;
 *  c. K + U + E_hg conserved to 1e-6 of the initial kinetic energy over the impact.
 * Set DM_FLYER_PRINT=1 for the numbers (docs/validation.md). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cont.h"
#include "dm.h"

static int print_on(void) { return getenv("DM_FLYER_PRINT") != NULL; }

/* The deck's default viscosity and bond penalty (docs/input-dm.md), the same for every case. */
static dm_fin_params default_par(double h) {
  return (dm_fin_params){.cq = 2.0, .cl = 0.5, .courant = 0.4, .hourglass = 1.0, .ell = h};
}

/* ---- the exact release of a uniformly shocked state into vacuum ----
 * Behind a steady shock the state (ρ1, e1, u1) is uniform and isentropic, so its release at the
 * free surface is a centred simple wave: on the isentrope de/dρ = p/ρ² the C+ invariant
 * u + ∫ c dρ/ρ is constant, so u(ρ) = u1 + ∫_ρ^ρ1 c/ρ' dρ' and the free surface moves at
 * u(ρ_r), p(ρ_r, e_r) = 0. In the reference coordinate X the fan's characteristics leave
 * (X_fs, t_b) with dX/dt = −ρ c/ρ0 ([Courant-Friedrichs] ch. III). */
#define NIS 4000
typedef struct release {
  double rho[NIS + 1], u[NIS + 1], cl[NIS + 1]; /* along the isentrope, ρ1 down to ρ_r */
  int n;
  double u1, ufs;
} release;

static void release_solve(const eos_t *eos, double rho1, double e1, double u1, release *r) {
  const double rho0 = eos_rho0(eos);
  /* ρ from ρ1 down to below ρ0 (p = 0 is crossed between: the shocked state is hot) */
  const double drho = (rho1 - 0.9 * rho0) / NIS;
  double rho = rho1, e = e1, I = 0.0;
  r->u1 = u1, r->n = 0;
  for (int k = 0; k <= NIS; ++k) {
    const double p = eos_pressure(eos, rho, e), c = eos_sound_speed(eos, rho, e);
    r->rho[k] = rho, r->u[k] = u1 + I, r->cl[k] = rho * c / rho0, r->n = k + 1;
    if (p <= 0) break;
    /* RK4 in ρ (step −drho) for de/dρ = p/ρ² and dI/dρ = −c/ρ */
    double ke[4], ki[4], rr = rho, ee = e;
    for (int s = 0; s < 4; ++s) {
      const double fr = s == 0 ? 0 : s == 3 ? 1.0 : 0.5;
      rr = rho - fr * drho;
      ee = e + (s == 0 ? 0 : -fr * drho * ke[s - 1]);
      ke[s] = eos_pressure(eos, rr, ee) / (rr * rr);
      ki[s] = eos_sound_speed(eos, rr, ee) / rr;
    }
    e -= drho * (ke[0] + 2 * ke[1] + 2 * ke[2] + ke[3]) / 6.0;
    I += drho * (ki[0] + 2 * ki[1] + 2 * ki[2] + ki[3]) / 6.0;
    rho -= drho;
  }
  assert_true(r->n >= 2 && r->n <= NIS); /* p = 0 was crossed */
  r->ufs = r->u[r->n - 1]; /* at the first ρ with p ≤ 0: within one step drho of ρ_r */
}

/* Exact u at reference X, time t, fan centred at (Xfs, tb). */
static double release_u(const release *r, double X, double Xfs, double t, double tb) {
  if (t <= tb) return r->u1;
  const double xi = -(X - Xfs) / (t - tb); /* = ρ c/ρ0 on the characteristic through X */
  if (xi >= r->cl[0]) return r->u1;
  for (int k = 1; k < r->n; ++k)
    if (xi >= r->cl[k]) {
      const double w = (xi - r->cl[k]) / (r->cl[k - 1] - r->cl[k]);
      return r->u[k] + w * (r->u[k - 1] - r->u[k]);
    }
  return r->ufs;
}

/* ---- histories ---- */
/* First time the history crosses level (linear interpolation), or NaN. */
static double crossing(const double *hist, size_t n, double level) {
  for (size_t r = 1; r < n; ++r)
    if (hist[2 * r + 1] >= level && hist[2 * r - 1] < level) {
      const double w = (level - hist[2 * r - 1]) / (hist[2 * r + 1] - hist[2 * r - 1]);
      return hist[2 * r - 2] + w * (hist[2 * r] - hist[2 * r - 2]);
    }
  return NAN;
}
/* Time average of u over [ta, tb] (trapezoids over the recorded rows inside). */
static double window_mean(const double *hist, size_t n, double ta, double tb) {
  double s = 0, T = 0;
  for (size_t r = 1; r < n; ++r) {
    const double t0 = hist[2 * r - 2], t1 = hist[2 * r];
    if (t0 < ta || t1 > tb) continue;
    s += 0.5 * (hist[2 * r - 1] + hist[2 * r + 1]) * (t1 - t0), T += t1 - t0;
  }
  return T > 0 ? s / T : NAN;
}

/* The grid's run of the same problem: the last node's velocity every dt_s up to t_end. */
static size_t grid_history(const eos_t *ef, const eos_t *et, double Lf, double Lt, double v,
                           long cf, long ct, double t_end, double *hist, size_t nmax) {
  cont_layer_spec layers[2] = {
      {.name = "flyer", .eos = ef, .thickness = Lf, .rho = eos_rho0(ef), .u = v, .ncells = cf},
      {.name = "target", .eos = et, .thickness = Lt, .rho = eos_rho0(et), .ncells = ct}};
  cont_setup s;
  cont_setup_defaults(&s); /* the grid's own default viscosity (q_quad 1, q_lin 0.2) */
  s.layers = layers, s.nlayers = 2;
  s.left.kind = CONT_BC_FREE, s.right.kind = CONT_BC_FREE;
  char msg[256];
  cont_grid *g = NULL;
  assert_int_equal(cont_grid_create(&s, &g, msg, sizeof msg), MS_OK);
  size_t n = 0;
  for (; n < nmax; ++n) {
    const double t = t_end * (double)n / (double)(nmax - 1);
    if (n > 0) assert_int_equal(cont_grid_run_to(g, t), MS_OK);
    cont_view vw = cont_grid_view(g);
    hist[2 * n] = t, hist[2 * n + 1] = vw.u[vw.nnodes - 1];
  }
  cont_grid_destroy(&g);
  return n;
}

typedef struct fcase {
  const char *name;
  eos_t *eos;
  double v; /* impact speed (km/s) */
} fcase;

/* The flyer spec of these tests: fc's material for flyer and target, the flyer at fc->v onto
 * the target at rest, horizon 1.5, default_par; nlat periodic rows (and columns in 3D). */
static dm_flyer_spec flyer_spec(const fcase *fc, int dim, long nf, long nt, long nlat, double h,
                                double t_end, size_t nhist) {
  return (dm_flyer_spec){.dim = dim,
                         .nflyer = nf,
                         .ntarget = nt,
                         .ny = nlat,
                         .nz = nlat,
                         .h = h,
                         .horizon = 1.5,
                         .mat = {{.eos = fc->eos}, {.eos = fc->eos}},
                         .u = {fc->v, 0.0},
                         .par = default_par(h),
                         .t_end = t_end,
                         .nhist = nhist};
}

/* Symmetric impact: flyer Lf = 2 Lt so that the flyer's rear release reaches the free surface
 * only after ≈ 4 t_a (t_a = Lt/D the breakout): the plateau window [1.2 t_a, 2.5 t_a] lies
 * between the arrival's rise and that release, for both materials. */
static void flyer_case(const fcase *fc, int dim, long nlat) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  const double h = 0.0025, Lt = 0.2, Lf = 0.4;
  const long nt = lround(Lt / h), nf = lround(Lf / h);
  const double rho0 = eos_rho0(fc->eos), e0 = eos_e0(fc->eos), u1 = 0.5 * fc->v;
  eos_hugoniot_point hp;
  assert_int_equal(eos_hugoniot(fc->eos, rho0, e0, 1, &u1, &hp), MS_OK);
  release rl;
  release_solve(fc->eos, hp.rho, hp.e, u1, &rl);
  const double ta_ex = Lt / hp.us, t_end = 2.6 * ta_ex;

  dm_flyer_spec sp = flyer_spec(fc, dim, nf, nt, nlat, h, t_end, 20000);
  dm_flyer_result r;
  assert_int_equal(dm_flyer_run(&sp, &ctx, &r), MS_OK);
  const size_t ng = 2000;
  double *gh = malloc(2 * ng * sizeof *gh);
  grid_history(fc->eos, fc->eos, Lf, Lt, fc->v, nf, nt, t_end, gh, ng);

  /* arrival: the half-way crossing of the exact free-surface velocity, for both */
  const double ta_p = crossing(r.hist, r.nhist, 0.5 * rl.ufs);
  const double ta_g = crossing(gh, ng, 0.5 * rl.ufs);
  const double up_p = window_mean(r.hist, r.nhist, 1.2 * ta_ex, 2.5 * ta_ex);
  const double up_g = window_mean(gh, ng, 1.2 * ta_ex, 2.5 * ta_ex);
  if (print_on())
    printf("%s %dD v %.2f: u_fs particles %.5f grid %.5f exact %.5f (%+.3f %% vs grid, %+.3f %% vs "
           "exact); arrival particles %.6f grid %.6f (%+.3f %%), Lt/D %.6f; energy %.2e of K0, "
           "E_hg/K0 %.2e, %ld steps\n",
           fc->name, dim, fc->v, up_p, up_g, rl.ufs, 100 * (up_p / up_g - 1),
           100 * (up_p / rl.ufs - 1), ta_p, ta_g, 100 * (ta_p / ta_g - 1), ta_ex, r.energy_err,
           r.hg_ratio, r.steps);
  /* a. the criteria: plateau 0.5 %, arrival 1 % */
  assert_true(fabs(up_p / up_g - 1) < 5e-3);
  assert_true(fabs(ta_p / ta_g - 1) < 1e-2);
  /* b. the exact release: 1 % */
  assert_true(fabs(up_p / rl.ufs - 1) < 1e-2);
  /* c. energy: KDK with the time-centred energy update conserves K + U + E_hg to round-off
   * (≈ 1e-12 per step relative; ~1e4 steps): 1e-6 of K0 leaves 1e2 of margin */
  assert_true(r.energy_err < 1e-6);
  /* zero-energy modes: the bond-penalty energy stays at the level of the piston runs
   * (E_hg/W ≤ 4.5e-4, docs/validation.md); 1e-3 of K0 bounds a mode that is not growing */
  assert_true(r.hg_ratio >= 0 && r.hg_ratio < 1e-3);
  free(r.hist), free(r.profile), free(gh);
  ms_ctx_close(&ctx);
}

/* b. The rarefaction fan's velocity profile: the target at t = 1.5 t_b, after the breakout
 * t_b = Lt/D (exact), fan centred at the free surface X_fs = Lt + Lf. Measure: relative L1
 * ∫|u − u_ex| dX / ((u_fs − u1) W) over the target, W = ρ1 c1 (t − t_b)/ρ0 the fan's width. */
static double fan_case(const fcase *fc, double h) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  const double Lt = 0.2, Lf = 0.4;
  const long nt = lround(Lt / h), nf = lround(Lf / h);
  const double rho0 = eos_rho0(fc->eos), e0 = eos_e0(fc->eos), u1 = 0.5 * fc->v;
  eos_hugoniot_point hp;
  assert_int_equal(eos_hugoniot(fc->eos, rho0, e0, 1, &u1, &hp), MS_OK);
  release rl;
  release_solve(fc->eos, hp.rho, hp.e, u1, &rl);
  const double tb = Lt / hp.us, t = 1.5 * tb;
  dm_flyer_spec sp = flyer_spec(fc, 1, nf, nt, 1, h, t, 100);
  dm_flyer_result r;
  assert_int_equal(dm_flyer_run(&sp, &ctx, &r), MS_OK);
  const double Xfs = Lf + Lt, W = rl.cl[0] * (t - tb);
  double l1 = 0;
  for (long ix = nf; ix < nf + nt; ++ix) {
    const double X = r.profile[8 * ix];
    l1 += fabs(r.profile[8 * ix + 2] - release_u(&rl, X, Xfs, t, tb)) * h;
  }
  l1 /= (rl.ufs - u1) * W;
  if (print_on())
    printf("%s v %.2f h %.5f fan at t = 1.5 t_b: width %.4f cm (%.0f spacings), relative L1 "
           "%.4f = %.2f spacings / W\n",
           fc->name, fc->v, h, W, W / h, l1, l1 * W / h);
  if (getenv("DM_FLYER_PROFILE"))
    for (long ix = nf; ix < nf + nt; ++ix)
      printf("%.6f %.6f %.6f\n", r.profile[8 * ix], r.profile[8 * ix + 2],
             release_u(&rl, r.profile[8 * ix], Xfs, t, tb));
  /* a fan computed with a shock viscosity 2–4 spacings wide (docs/particles-dm.md) is smeared
   * and displaced by about that many spacings; a displacement δ costs δ/W in this measure */
  assert_true(l1 < 3.0 * h / W);
  free(r.hist), free(r.profile);
  ms_ctx_close(&ctx);
  return l1;
}

static fcase al_case(void) {
  /* Al: mg_linear (2.703, 5.35, 1.34, Γ0 2), inputs/continuum-plate-impact.yaml */
  return (fcase){"Al", eos_create_mg_linear(2.703, 5.35, 1.34, 2.0), 2.0};
}
static fcase pb_case(void) {
  /* Pb: mg_cold (11.34, 1.972, n 3, Γ0 2), the shipped decks (inputs/default.yaml) */
  return (fcase){"Pb", eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, false), 1.0};
}

/* one case on a dim-D lattice with ny periodic rows (and columns in 3D), its EOS released */
static void run_case(fcase c, int dim, long ny) {
  flyer_case(&c, dim, ny);
  eos_destroy(&c.eos);
}
static void test_al(void **state) {
  (void)state;
  run_case(al_case(), 1, 1);
}
static void test_pb(void **state) {
  (void)state;
  run_case(pb_case(), 1, 1);
}
/* The same planar problem on a 2D (5 periodic rows) and a 3D (5 × 5) lattice: the periodic
 * width must exceed 3 horizons */
static void test_al_2d(void **state) {
  (void)state;
  run_case(al_case(), 2, 5);
}
static void test_pb_3d(void **state) {
  (void)state;
  run_case(pb_case(), 3, 5);
}
/* The fan at h and h/2: each within 3 spacings / W, and the error first order in h (it falls by
 * at least 1.5 when h halves: the smearing is proportional to the spacing). */
static void fan_pair(const fcase *c) {
  const double l1a = fan_case(c, 0.0025), l1b = fan_case(c, 0.00125);
  assert_true(l1b < l1a / 1.5);
}
static void test_fan_al(void **state) {
  (void)state;
  fcase c = al_case();
  fan_pair(&c);
  eos_destroy(&c.eos);
}
static void test_fan_pb(void **state) {
  (void)state;
  fcase c = pb_case();
  fan_pair(&c);
  eos_destroy(&c.eos);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_al),     cmocka_unit_test(test_pb),
                                     cmocka_unit_test(test_al_2d),  cmocka_unit_test(test_pb_3d),
                                     cmocka_unit_test(test_fan_al), cmocka_unit_test(test_fan_pb)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
