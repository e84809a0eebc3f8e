/* SPDX-License-Identifier: MIT */
/* Hamiltonian discrete model (docs/design.md §5.2): force = −∇H, conservation laws, bounded energy,
 * linear-field exactness, detection of singular shape matrices, thread-count independence. */
#include <math.h>
#include <omp.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "dm.h"

/* dm_model_create with the model as the result: NULL exactly when the status (in *st, if not
 * NULL) is not MS_OK; bad (if not NULL) receives the first singular particle. */
static dm_model *model_of(dm_state *s, const dm_options *opt, const ms_ctx *ctx, ms_status *st,
                          size_t *bad) {
  dm_model *m = NULL;
  const ms_status status = dm_model_create(
      &(dm_model_params){.state = s, .opt = *opt, .ctx = ctx, .first_bad = bad}, &m);
  assert_true((status == MS_OK) == (m != NULL));
  if (st) *st = status;
  return m;
}

static uint64_t rng_k; /* outputs drawn so far from the generator started from seed 12345 */
static double urand(void) { return ptl_splitmix64_uniform(12345, rng_k++); } /* [0, 1) */

/* Simple-cubic block nx×ny×nz (spacing h) in `dim` dimensions, reference positions perturbed by
 * up to ±jitter·h, random moduli (so that interfaces between unlike particles are exercised). */
static void make_block(dm_state *s, int dim, int nx, int ny, int nz, double h, double jitter) {
  size_t n = (size_t)nx * ny * nz;
  dm_state_alloc(s, n, dim);
  size_t i = 0;
  for (int c = 0; c < nz; ++c)
    for (int b = 0; b < ny; ++b)
      for (int a = 0; a < nx; ++a, ++i) {
        int idx[3] = {a, b, c};
        for (int d = 0; d < dim; ++d) s->X[3 * i + d] = (idx[d] + jitter * (2 * urand() - 1)) * h;
        s->vol[i] = pow(h, dim);
        s->mass[i] = (2.0 + 6.0 * urand()) * s->vol[i];
        s->K[i] = 50.0 + 100.0 * urand();
        s->G[i] = 20.0 + 60.0 * urand();
      }
}

static void random_field(dm_state *s, double *v, double amp) {
  for (size_t i = 0; i < s->n; ++i)
    for (int d = 0; d < s->dim; ++d) v[3 * i + d] = amp * (2 * urand() - 1);
}

/* F = −∂H/∂w by central differences. H is exactly quadratic in w, so the difference quotient
 * has no truncation error; what remains is round-off ~ 1e-16·H/δ, far below the 1e-6 relative
 * bound of the issue (which therefore tests the force formula, e.g. the dropped k-terms of the
 * printed eq. (6) give O(1) errors). */
static void check_fd(int dim, int nx, int ny, int nz, double hourglass) {
  dm_state s;
  const double h = 0.1;
  make_block(&s, dim, nx, ny, nz, h, 0.15);
  random_field(&s, s.w, 1e-3 * h);
  dm_options opt = {.horizon = 2.2 * h, .hourglass = hourglass};
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ms_status st;
  dm_model *m = model_of(&s, &opt, &ctx, &st, NULL);
  assert_non_null(m);
  double *F = calloc(3 * s.n, sizeof(double));
  dm_forces(m, s.w, F);
  double fbig = 0.0, errmax = 0.0;
  for (size_t i = 0; i < s.n; ++i)
    for (int a = 0; a < dim; ++a) fbig = fmax(fbig, fabs(F[3 * i + a]));
  const double delta = 1e-4 * h;
  for (size_t i = 0; i < s.n; ++i)
    for (int a = 0; a < dim; ++a) {
      double w0 = s.w[3 * i + a];
      s.w[3 * i + a] = w0 + delta;
      double Hp = dm_potential_energy(m, s.w);
      s.w[3 * i + a] = w0 - delta;
      double Hm = dm_potential_energy(m, s.w);
      s.w[3 * i + a] = w0;
      double fd = -(Hp - Hm) / (2 * delta);
      errmax = fmax(errmax, fabs(fd - F[3 * i + a]));
    }
  printf("dim %d, %zu particles, %zu bonds, hourglass %g: max|F_fd - F|/max|F| = %.2e\n", dim, s.n,
         m->nbonds, hourglass, errmax / fbig);
  assert_true(fbig > 0.0);
  assert_true(errmax / fbig < 1e-6);
  free(F);
  dm_model_destroy(&m);
  dm_state_free(&s);
  ms_ctx_close(&ctx);
}

static void test_force_is_minus_grad_H(void **state) {
  (void)state;
  check_fd(3, 5, 4, 4, 0.0);
  check_fd(3, 5, 4, 4, 0.5);
  check_fd(2, 7, 6, 1, 0.0);
  check_fd(1, 12, 1, 1, 0.0);
  check_fd(1, 12, 1, 1, 1.0);
}

/* The model reproduces any linear displacement field exactly ([Sofronov] §1, after eq. 2) —
 * on every particle, including the boundary ones with one-sided families — and the forces of
 * a homogeneous strain vanish on interior particles. */
static void test_linear_field_exact(void **state) {
  (void)state;
  dm_state s;
  make_block(&s, 3, 6, 6, 6, 1.0, 0.2);
  const double Cb[9] = {1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, -4e-4, 3e-4, 7e-4};
  for (size_t i = 0; i < s.n; ++i)
    for (int a = 0; a < 3; ++a)
      s.w[3 * i + a] =
          Cb[3 * a] * s.X[3 * i] + Cb[3 * a + 1] * s.X[3 * i + 1] + Cb[3 * a + 2] * s.X[3 * i + 2];
  dm_options opt = {.horizon = 1.8, .hourglass = 1.0};
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  dm_model *m = model_of(&s, &opt, &ctx, NULL, NULL);
  assert_non_null(m);
  double *F = calloc(3 * s.n, sizeof(double));
  dm_forces(m, s.w, F);
  double err = 0;
  for (size_t i = 0; i < s.n; ++i)
    for (int c = 0; c < 9; ++c) err = fmax(err, fabs(m->C[9 * i + c] - Cb[c]));
  /* round-off relative to |C| ~ 1e-3 */
  assert_true(err < 1e-15);
  /* hourglass indicator: exactly 0 for a linear field (up to round-off) */
  double dwn, hg = dm_hourglass_norm(m, s.w, &dwn);
  assert_true(dwn > 0 && hg / dwn < 1e-12);
  free(F);
  dm_model_destroy(&m);
  dm_state_free(&s);
  ms_ctx_close(&ctx);
}

/* Linear momentum Σ m u and reference angular momentum J = Σ X × m u are exact invariants
 * (pairwise antisymmetric bond forces; Σ_k ξ_ik × σ_i A_i⁻¹ ξ_ik = ε:σ_i = 0). Checked over
 * 2000 steps of every scheme from random w and u; tolerance 1e-12 relative to Σ m|u| (Σ m|u||X|),
 * i.e. accumulated round-off. The current-configuration angular momentum Σ (X + w) × m u is
 * conserved only to O(strain) by the small-strain model (docs/particles-dm.md). */
static void test_momenta_conserved(void **state) {
  (void)state;
  for (int k = 0; k < RKN_KIND_COUNT; ++k) {
    dm_state s;
    make_block(&s, 3, 5, 5, 5, 0.1, 0.15);
    random_field(&s, s.w, 1e-4);
    random_field(&s, s.u, 1e-2);
    dm_options opt = {.horizon = 0.22, .hourglass = k == 1 ? 0.5 : 0.0};
    ms_ctx ctx;
    ms_ctx_init_serial(&ctx);
    dm_model *m = model_of(&s, &opt, &ctx, NULL, NULL);
    assert_non_null(m);
    double P0[3], J0[3], P[3], J[3];
    dm_momenta(&s, P0, J0);
    double pscale = 0, jscale = 0;
    for (size_t i = 0; i < s.n; ++i) {
      double um = s.mass[i] * sqrt(s.u[3 * i] * s.u[3 * i] + s.u[3 * i + 1] * s.u[3 * i + 1] +
                                   s.u[3 * i + 2] * s.u[3 * i + 2]);
      pscale += um;
      jscale += um * 0.5;
    }
    rkn_integrator *ig = NULL;
    ms_must(rkn_create(&(rkn_params){.kind = (rkn_kind)k, .ndof = 3 * s.n}, &ig), "rkn_create");
    const double dt = 2e-3; /* c ≈ 5, h = 0.1: well inside the stability limit */
    for (int step = 0; step < 2000; ++step)
      assert_int_equal(rkn_step(ig, step * dt, dt, s.w, s.u, dm_accel, dm_constrain, m), MS_OK);
    dm_momenta(&s, P, J);
    double dP = 0, dJ = 0;
    for (int a = 0; a < 3; ++a)
      dP = fmax(dP, fabs(P[a] - P0[a])), dJ = fmax(dJ, fabs(J[a] - J0[a]));
    printf("%-15s |dP|/sum m|u| = %.2e, |dJ|/scale = %.2e\n", rkn_scheme_get(k)->name, dP / pscale,
           dJ / jscale);
    assert_true(dP / pscale < 1e-12);
    assert_true(dJ / jscale < 1e-12);
    rkn_destroy(&ig);
    dm_model_destroy(&m);
    dm_state_free(&s);
    ms_ctx_close(&ctx);
  }
}

/* Bounded energy error over 1e5 Verlet steps of a free 4×4×4 block (random initial data): the
 * error oscillates (bounded by twice its maximum over the first 1000 steps) and its mean over
 * the last tenth of the run differs from the first tenth by < 10 % of that bound: no drift. */
static void test_energy_no_drift(void **state) {
  (void)state;
  dm_state s;
  make_block(&s, 3, 4, 4, 4, 0.1, 0.1);
  random_field(&s, s.w, 1e-4);
  random_field(&s, s.u, 1e-3);
  dm_options opt = {.horizon = 0.16};
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  dm_model *m = model_of(&s, &opt, &ctx, NULL, NULL);
  assert_non_null(m);
  rkn_integrator *ig = NULL;
  ms_must(rkn_create(&(rkn_params){.kind = RKN_VERLET, .ndof = 3 * s.n}, &ig), "rkn_create");
  double E0 = dm_kinetic_energy(&s) + dm_potential_energy(m, s.w);
  const double dt = 4e-3; /* ~ 1/5 of the Verlet limit for c_max ≈ 7, h = 0.1 */
  const long nsteps = 100000, tenth = nsteps / 10;
  double max_first = 0, max_all = 0, mean_first = 0, mean_last = 0;
  for (long step = 0; step < nsteps; ++step) {
    rkn_step(ig, step * dt, dt, s.w, s.u, dm_accel, dm_constrain, m);
    if (step % 10) continue; /* energy sampled every 10 steps: the test stays fast */
    double err = (dm_kinetic_energy(&s) + dm_potential_energy(m, s.w) - E0) / E0;
    if (step < 1000) max_first = fmax(max_first, fabs(err));
    max_all = fmax(max_all, fabs(err));
    if (step < tenth) mean_first += err / (tenth / 10);
    if (step >= nsteps - tenth) mean_last += err / (tenth / 10);
  }
  printf("energy: max rel error first 1000 steps %.3e, over 1e5 steps %.3e, drift of mean %.3e\n",
         max_first, max_all, mean_last - mean_first);
  assert_true(max_all < 2.0 * max_first);
  assert_true(fabs(mean_last - mean_first) < 0.2 * max_first);
  rkn_destroy(&ig);
  dm_model_destroy(&m);
  dm_state_free(&s);
  ms_ctx_close(&ctx);
}

/* A planar sheet of particles in a 3D model has singular A_i: set-up must refuse it and name
 * a particle; so must an isolated particle in 1D. */
static void test_singular_shape_detected(void **state) {
  (void)state;
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = MS_LOG_ERROR;
  dm_state s;
  make_block(&s, 3, 4, 4, 1, 1.0, 0.0);
  dm_options opt = {.horizon = 1.5};
  ms_status st = MS_OK;
  size_t bad = (size_t)-1;
  assert_null(model_of(&s, &opt, &ctx, &st, &bad));
  assert_int_equal(st, MS_ERR_INPUT);
  assert_true(bad < s.n);
  dm_state_free(&s);
  /* Nearly coplanar: one layer displaced by 1e-6 h out of plane -> condition number ~1e12 */
  make_block(&s, 3, 4, 4, 2, 1.0, 0.0);
  for (size_t i = 16; i < 32; ++i) s.X[3 * i + 2] = 1e-6;
  assert_null(model_of(&s, &opt, &ctx, &st, &bad));
  assert_int_equal(st, MS_ERR_INPUT);
  dm_state_free(&s);
  /* 1D: two particles farther apart than the horizon */
  dm_state_alloc(&s, 2, 1);
  s.X[3] = 2.0;
  for (int i = 0; i < 2; ++i) s.mass[i] = s.vol[i] = s.K[i] = s.G[i] = 1.0;
  assert_null(model_of(&s, &opt, &ctx, &st, &bad));
  assert_int_equal(bad, 0);
  dm_state_free(&s);
  /* and a well-posed block is accepted */
  make_block(&s, 3, 3, 3, 3, 1.0, 0.1);
  dm_model *m = model_of(&s, &opt, &ctx, &st, NULL);
  assert_non_null(m);
  assert_int_equal(st, MS_OK);
  dm_model_destroy(&m);
  assert_null(m);       /* destroy clears the pointer */
  dm_model_destroy(&m); /* and is null-safe */
  dm_model_destroy(NULL);
  dm_state_free(&s);
  ms_ctx_close(&ctx);
}

/* Periodic families: a uniform sc lattice in a periodic box has the full 18-neighbour family
 * (horizon 1.5 h) on every particle, and a periodic linear-in-sine field gives equal forces
 * to particles with the same x. Also: forces are bitwise identical on 1 and 2 threads. */
static void test_periodic_and_threads(void **state) {
  (void)state;
  dm_state s;
  const int nc = 6;
  const double h = 0.5;
  make_block(&s, 3, nc, nc, nc, h, 0.0);
  for (size_t i = 0; i < s.n; ++i) {
    for (int a = 0; a < 3; ++a) s.X[3 * i + a] += 0.5 * h;
    s.K[i] = 100, s.G[i] = 50;
    s.w[3 * i] = 1e-3 * sin(2 * M_PI * s.X[3 * i] / (nc * h));
  }
  dm_options opt = {.horizon = 1.5 * h, .box = {nc * h, nc * h, nc * h}};
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  dm_model *m = model_of(&s, &opt, &ctx, NULL, NULL);
  assert_non_null(m);
  for (size_t i = 0; i < s.n; ++i) assert_int_equal(m->start[i + 1] - m->start[i], 18);
  double *F1 = calloc(3 * s.n, sizeof(double)), *F2 = calloc(3 * s.n, sizeof(double));
  omp_set_num_threads(1);
  dm_forces(m, s.w, F1);
  omp_set_num_threads(2);
  dm_forces(m, s.w, F2);
  assert_memory_equal(F1, F2, 3 * s.n * sizeof(double));
  for (size_t i = 0; i < s.n; ++i) {
    size_t j = i % nc; /* same x column, first row */
    assert_true(fabs(F1[3 * i] - F1[3 * j]) < 1e-12 * fabs(F1[3 * 1]) + 1e-300);
    assert_true(fabs(F1[3 * i + 1]) < 1e-12 * fabs(F1[3 * 1]) + 1e-300);
  }
  free(F1);
  free(F2);
  dm_model_destroy(&m);
  dm_state_free(&s);
  ms_ctx_close(&ctx);
}

/* Convergence order of each RKN scheme on the discrete model itself: a free 1D chain (60
 * particles, h = 0.05, c = 5.05) with a smooth Gaussian displacement, integrated to t = 0.2 with
 * dt halved from ω_max dt = 0.4; errors in w against RKN4 at a 64× smaller step. Slope of
 * log error vs log dt: expected 2 (Verlet) and 4, ± 0.2. */
static void integrate_chain(rkn_kind kind, double dt, double T, double *w_out) {
  dm_state s;
  const int n = 60;
  const double h = 0.05;
  dm_state_alloc(&s, n, 1);
  for (int i = 0; i < n; ++i) {
    s.X[3 * i] = (i + 0.5) * h;
    s.vol[i] = h, s.mass[i] = 7.85 * h, s.K[i] = 200.0 / 3.0, s.G[i] = 100.0;
    double y = (s.X[3 * i] - 1.5) / 0.3;
    s.w[3 * i] = 1e-3 * exp(-y * y);
  }
  dm_options opt = {.horizon = 1.5 * h};
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  dm_model *m = model_of(&s, &opt, &ctx, NULL, NULL);
  rkn_integrator *ig = NULL;
  ms_must(rkn_create(&(rkn_params){.kind = kind, .ndof = 3 * n}, &ig), "rkn_create");
  long steps = lround(T / dt);
  for (long k = 0; k < steps; ++k) rkn_step(ig, k * dt, dt, s.w, s.u, dm_accel, dm_constrain, m);
  for (int i = 0; i < n; ++i) w_out[i] = s.w[3 * i];
  rkn_destroy(&ig);
  dm_model_destroy(&m);
  dm_state_free(&s);
  ms_ctx_close(&ctx);
}

static void test_rkn_order_on_dm(void **state) {
  (void)state;
  const double T = 0.2, c = sqrt(200.0 / 7.85), dt0 = 0.4 * 0.05 / c;
  double ref[60], w[60];
  integrate_chain(RKN_RKN4, dt0 / 64 * (T / dt0) / ceil(T / dt0), T, ref);
  for (int k = 0; k < RKN_KIND_COUNT; ++k) {
    double lx[4], ly[4];
    for (int j = 0; j < 4; ++j) {
      double dt = T / (ceil(T / dt0) * pow(2.0, j)), err = 0;
      integrate_chain((rkn_kind)k, dt, T, w);
      for (int i = 0; i < 60; ++i) err = fmax(err, fabs(w[i] - ref[i]));
      lx[j] = log(dt), ly[j] = log(err);
    }
    double mx = 0, my = 0, sxy = 0, sxx = 0;
    for (int j = 0; j < 4; ++j) mx += lx[j] / 4, my += ly[j] / 4;
    for (int j = 0; j < 4; ++j)
      sxy += (lx[j] - mx) * (ly[j] - my), sxx += (lx[j] - mx) * (lx[j] - mx);
    const rkn_scheme *sc = rkn_scheme_get((rkn_kind)k);
    printf("DM chain: %-15s measured order %.3f (expected %d)\n", sc->name, sxy / sxx, sc->order);
    assert_true(fabs(sxy / sxx - sc->order) < 0.2);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_force_is_minus_grad_H),   cmocka_unit_test(test_linear_field_exact),
      cmocka_unit_test(test_momenta_conserved),       cmocka_unit_test(test_energy_no_drift),
      cmocka_unit_test(test_singular_shape_detected), cmocka_unit_test(test_periodic_and_threads),
      cmocka_unit_test(test_rkn_order_on_dm),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
