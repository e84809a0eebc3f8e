/* SPDX-License-Identifier: MIT */
/* The per-family reference update (dm_fin_rebase_local, particles/dm/dm_fin_local.c) in a
 * periodic box (docs/particles-dm.md "Reference update"): the bonds across the periodic
 * boundary keep their image, so an update takes their minimum-image vector as the new
 * reference and the gather their reverse bonds' with the opposite image. Patch test across the
 * boundary (an affine deformation after an update is reproduced exactly, no penalty force),
 * energy to round-off and momentum exact over steps with updates, merge refused. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "dm.h"
#include "test_util.h"

enum { N1 = 6 };
static const double H = 0.1;

typedef struct block {
  eos_t *eos;
  dm_state s;
  dm_fin_material mat;
  uint8_t *imat;
  dm_fin *f;
  ms_ctx ctx;
} block;

/* An Al block of N1³ particles, periodic along y (box N1 h = 4 horizons), elastic (Y0 high),
 * with w = E X + zero-mean pseudo-random noise (amplitude `noise` h) and bond penalty c_s. E's
 * y column must be 0: a periodic displacement cannot depend on y. */
static void block_make(block *b, const double E[9], double noise, double cs) {
  assert_true(E[1] == 0 && E[4] == 0 && E[7] == 0);
  b->eos = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  dm_state_alloc(&b->s, (size_t)(N1 * N1 * N1), 3);
  unsigned r = 4242u;
  for (int k = 0, i = 0; k < N1; ++k)
    for (int j = 0; j < N1; ++j)
      for (int l = 0; l < N1; ++l, ++i) {
        const double X[3] = {(l + 0.5) * H, (j + 0.5) * H, (k + 0.5) * H};
        for (int a = 0; a < 3; ++a) {
          r = r * 1103515245u + 12345u;
          const double d = ((double)((r >> 8) & 0xffff) / 65535.0 - 0.5) * noise * H;
          b->s.X[3 * i + a] = X[a];
          b->s.w[3 * i + a] = E[3 * a] * X[0] + E[3 * a + 2] * X[2] + d;
        }
        b->s.mass[i] = 2.703 * H * H * H, b->s.vol[i] = H * H * H;
        b->s.K[i] = 77, b->s.G[i] = 27.6;
      }
  ms_ctx_init_serial(&b->ctx);
  b->ctx.verbosity = MS_LOG_ERROR;
  dm_model *m = NULL;
  const dm_options opt = {.horizon = 1.5 * H, .cond_max = 1e8, .box = {0, N1 * H, 0}};
  assert_int_equal(
      dm_model_create(&(dm_model_params){.state = &b->s, .opt = opt, .ctx = &b->ctx}, &m), MS_OK);
  b->mat = (dm_fin_material){.eos = b->eos, .yield = DM_YIELD_ELASTIC_PLASTIC, .G = 27.6, .Y0 = 10};
  b->imat = calloc(b->s.n, 1);
  dm_fin_params par = {.cq = 2, .cl = 0.5, .courant = 0.4, .hourglass = cs, .ell = H};
  assert_int_equal(
      dm_fin_create(&(dm_fin_setup){.m = m, .mat = &b->mat, .imat = b->imat, .par = par}, &b->f),
      MS_OK);
}

static void block_free(block *b) {
  dm_model *m = b->f->m;
  dm_fin_destroy(&b->f);
  dm_model_destroy(&m);
  free(b->imat);
  dm_state_free(&b->s);
  eos_destroy(&b->eos);
  ms_ctx_close(&b->ctx);
}

/* x ← (I + E2) x from the current configuration (E2's y column 0: periodic), refreshed. */
static void affine_increment(block *b, const double E2[9]) {
  dm_state *s = &b->s;
  for (size_t i = 0; i < s->n; ++i) {
    double x[3];
    for (int a = 0; a < 3; ++a) x[a] = s->X[3 * i + a] + s->w[3 * i + a];
    for (int a = 0; a < 3; ++a)
      s->w[3 * i + a] = x[a] + E2[3 * a] * x[0] + E2[3 * a + 2] * x[2] - s->X[3 * i + a];
  }
  assert_int_equal(dm_fin_refresh(b->f), MS_OK);
}

/* Does some bond of the model cross the periodic boundary (image ≠ 13)? */
static size_t crossing_bonds(const dm_model *m) {
  size_t c = 0;
  for (size_t b = 0; b < m->nbonds; ++b) c += m->img[b] != 13;
  return c;
}

/* Patch test across the periodic boundary: a 5 % stretch along x with shear (every family
 * updated at threshold 1 %), then a further affine increment from the new references: exact on
 * every family, those with bonds across the boundary included, so the bond penalty's force
 * f(c_s = 1) − f(c_s = 0) stays at round-off (1e-12 of the boundary forces, as
 * test_dm_rebase's patch tests). With the bonds' image dropped in the gather (ΔX = X_k − X_i
 * there) the penalty force is 44 |f| (measured); with the update's new vectors taken without
 * the image the update is refused (the families across the boundary degenerate): the test can
 * fail. */
static void test_periodic_patch(void **state) {
  (void)state;
  static const double E1[9] = {0.05, 0, 0, 0.03, 0, 0, 0.02, 0, 0.01};
  static const double E2[9] = {-0.04, 0, 0.02, 0.01, 0, -0.03, 0.02, 0, 0.03};
  block b1, b0;
  block_make(&b1, E1, 0.0, 1.0), block_make(&b0, E1, 0.0, 0.0);
  block *bb[2] = {&b1, &b0};
  for (int q = 0; q < 2; ++q) {
    dm_refamily_report rep;
    assert_int_equal(dm_fin_rebase_local(bb[q]->f, &bb[q]->ctx, 0.01, false, &rep), MS_OK);
    assert_true(rep.families == bb[q]->s.n);
    affine_increment(bb[q], E2);
  }
  const size_t nc = crossing_bonds(b1.f->m);
  double d = 0, scale = 0;
  for (size_t j = 0; j < 3 * b1.s.n; ++j)
    d = fmax(d, fabs(b1.f->frc[j] - b0.f->frc[j])), scale = fmax(scale, fabs(b0.f->frc[j]));
  printf("periodic patch test: %zu of %zu bonds across the boundary; |f_penalty| %.3g, |f| "
         "%.3g\n",
         nc, b1.f->m->nbonds, d, scale);
  assert_true(nc > 0 && scale > 0 && d < 1e-12 * scale);
  /* every updated family's F is I + E2 (exact affine: round-off 1e-13 of O(1) entries) */
  for (size_t i = 0; i < b1.s.n; ++i)
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c)
        assert_true(fabs(b1.f->F[9 * i + 3 * a + c] - ((a == c) + E2[3 * a + c])) < 1e-13);
  block_free(&b1), block_free(&b0);
}

/* Dynamics in the periodic box (random velocities 0.02 km/s on the block with noise 0.02 h,
 * threshold 1 %, families kept; as test_dm_rebase's test_local_dynamics): K + U + E_hg stays
 * at E0 to 1e-13 of |K| + |U| + |E_hg| (round-off of 216 terms over 60 steps; 1e-15 measured),
 * Σ m u to 1e-15 of Σ m|u| (equal and opposite bond forces, across the boundary too: 1e-17
 * measured). Shown to fail: the released penalty energy not booked as heat (|dE| = 0.8 of the
 * sum), the reverse bond's ΔX taken as −ΔX_b in the gather (|dP| 1.4e-13 of Σ m|u|: X_k + s −
 * X_i is not bit for bit −(X_i − s − X_k)). A merge in a periodic box is refused
 * (MS_ERR_INTERNAL: the new pairs' images are not built). */
static void test_periodic_dynamics(void **state) {
  (void)state;
  block b;
  const double zero[9] = {0};
  block_make(&b, zero, 0.02, 1.0);
  unsigned r = 777u;
  for (size_t j = 0; j < 3 * b.s.n; ++j) {
    r = r * 1103515245u + 12345u;
    b.s.u[j] = 0.02 * ((double)((r >> 8) & 0xffff) / 65535.0 - 0.5);
  }
  assert_int_equal(dm_fin_refresh(b.f), MS_OK);
  const size_t n = b.s.n;
  double K, U, Hg, P0[3] = {0}, mu = 0;
  dm_fin_energies(b.f, &K, &U, &Hg);
  const double E0 = K + U + Hg;
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      P0[a] += b.s.mass[i] * b.s.u[3 * i + a], mu += b.s.mass[i] * fabs(b.s.u[3 * i + a]);
  double dE = 0, Es = 0, released = 0;
  size_t updates = 0, steps_with = 0;
  dm_refamily_report rep;
  for (int step = 0; step < 60; ++step) {
    assert_int_equal(dm_fin_step(b.f), MS_OK);
    assert_int_equal(dm_fin_rebase_local(b.f, &b.ctx, 0.01, false, &rep), MS_OK);
    updates += rep.families, steps_with += rep.families > 0, released += rep.released;
    dm_fin_energies(b.f, &K, &U, &Hg);
    dE = fmax(dE, fabs(K + U + Hg - E0)), Es = fmax(Es, fabs(K) + fabs(U) + fabs(Hg));
  }
  double P[3] = {0}, dP = 0;
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) P[a] += b.s.mass[i] * b.s.u[3 * i + a];
  for (int a = 0; a < 3; ++a) dP = fmax(dP, fabs(P[a] - P0[a]));
  printf("periodic per-family dynamics: %zu family updates at %zu of 60 steps, released %.3g; "
         "|dE| %.3g of %.3g, |dP| %.3g of %.3g\n",
         updates, steps_with, released, dE, Es, dP, mu);
  assert_true(steps_with > 1 && released > 0);
  assert_true(dE < 1e-13 * Es);
  assert_true(dP < 1e-15 * mu);
  assert_int_equal(dm_fin_rebase_local(b.f, &b.ctx, 0.001, true, &rep), MS_ERR_INTERNAL);
  block_free(&b);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_periodic_patch),
      cmocka_unit_test(test_periodic_dynamics),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
