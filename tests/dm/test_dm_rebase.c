/* SPDX-License-Identifier: MIT */
/* The reference update that keeps the families (dm_fin_rebase, particles/dm/dm_refamily.c,
 * docs/particles-dm.md "Reference update"): the affine patch test of the bond penalty (a
 * uniform deformation gives no stabilisation force, before and after the update, with the
 * families kept or merged); the update moves exactly the penalty's stored energy into heat
 * (K + U + E_hg unchanged) and restarts the mismatch z from 0; merged families stay symmetric
 * and gain a particle that has come within the horizon. */
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

/* An Al block of N1³ particles (elastic-plastic, Y0 high enough to stay elastic) with
 * displacement w = E X + a zero-mean pseudo-random part of amplitude `noise` h, bond penalty
 * c_s. */
static void block_make(block *b, const double E[9], double noise, double cs) {
  b->eos = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  dm_state_alloc(&b->s, (size_t)(N1 * N1 * N1), 3);
  unsigned r = 12345u;
  for (int k = 0, i = 0; k < N1; ++k)
    for (int j = 0; j < N1; ++j)
      for (int l = 0; l < N1; ++l, ++i) {
        const double X[3] = {(l + 0.5) * H, (j + 0.5) * H, (k + 0.5) * H};
        for (int a = 0; a < 3; ++a) {
          r = r * 1103515245u + 12345u;
          const double d = ((double)((r >> 8) & 0xffff) / 65535.0 - 0.5) * noise * H;
          b->s.X[3 * i + a] = X[a];
          b->s.w[3 * i + a] = E[3 * a] * X[0] + E[3 * a + 1] * X[1] + E[3 * a + 2] * X[2] + d;
        }
        b->s.mass[i] = 2.703 * H * H * H, b->s.vol[i] = H * H * H;
        b->s.K[i] = 77, b->s.G[i] = 27.6;
      }
  ms_ctx_init_serial(&b->ctx);
  b->ctx.verbosity = MS_LOG_ERROR;
  dm_model *m = NULL;
  assert_int_equal(dm_model_create(&(dm_model_params){.state = &b->s,
                                                      .opt = {.horizon = 1.5 * H, .cond_max = 1e8},
                                                      .ctx = &b->ctx},
                                   &m),
                   MS_OK);
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

static const double E_affine[9] = {-0.2, 0.03, 0, 0, 0.1, 0, 0.02, 0, 0.05};

/* The largest |f(c_s = 1) − f(c_s = 0)| over all particles, boundary ones included: the bond
 * penalty's force, after an update of kind `kind` (0: none, 1: families kept, 2: merged). */
static double penalty_force(const double E[9], double noise, int kind, double *scale) {
  block b1, b0;
  block_make(&b1, E, noise, 1.0), block_make(&b0, E, noise, 0.0);
  dm_refamily_report rep;
  if (kind) { /* update, then a second affine deformation from the new reference */
    static const double E2[9] = {0.04, 0, -0.03, 0.02, -0.05, 0, 0, 0.01, 0.03};
    block *bb[2] = {&b1, &b0};
    for (int q = 0; q < 2; ++q) {
      dm_state *s = &bb[q]->s;
      assert_int_equal(dm_fin_rebase(bb[q]->f, &bb[q]->ctx, kind == 2, &rep), MS_OK);
      for (size_t i = 0; i < s->n; ++i)
        for (int a = 0; a < 3; ++a)
          s->w[3 * i + a] = E2[3 * a] * s->X[3 * i] + E2[3 * a + 1] * s->X[3 * i + 1] +
                            E2[3 * a + 2] * s->X[3 * i + 2];
      assert_int_equal(dm_fin_refresh(bb[q]->f), MS_OK);
    }
  }
  double d = 0, fbig = 0;
  for (size_t j = 0; j < 3 * b1.s.n; ++j) {
    d = fmax(d, fabs(b1.f->frc[j] - b0.f->frc[j]));
    fbig = fmax(fbig, fabs(b0.f->frc[j]));
  }
  *scale = fbig;
  block_free(&b1), block_free(&b0);
  return d;
}

/* Patch test: for the affine field the least-squares F is exact on every family, z = 0 and the
 * penalty adds no force — relative to the stress forces of the boundary particles (|f| ~ p h²),
 * 1e-12 is round-off of sums of ~20 bonds; the same after an update with the families kept or
 * merged and a second affine deformation from the new reference (A⁻¹ of the updated families:
 * with the old A⁻¹ kept the penalty force is 5e-2 of |f|, measured). A non-affine field (noise 0.05 h) does get a
 * penalty force: the test can fail. */
static void test_patch(void **state) {
  (void)state;
  for (int kind = 0; kind < 3; ++kind) {
    double scale, d = penalty_force(E_affine, 0.0, kind, &scale);
    printf("patch test, update %d: |f_penalty| %.3g, |f| %.3g\n", kind, d, scale);
    assert_true(scale > 0 && d < 1e-12 * scale);
  }
  double scale, d = penalty_force(E_affine, 0.05, 0, &scale);
  printf("non-affine: |f_penalty| %.3g, |f| %.3g\n", d, scale);
  assert_true(d > 1e-3 * scale);
}

/* The update of a non-affine state reached by the dynamics (random velocities of 0.01 km/s on
 * the affinely deformed block, 40 steps, so that E_hg is the penalty's work): the update moves
 * the stored energy Σ κ|z|²/2 (rep.released > 0) into e, so K + U + E_hg is unchanged to
 * round-off (1e-13 of U: sums of 216 terms) and E_hg drops by exactly rep.released, to the
 * penalty's time-discretisation residual (|E_hg| after it below 5 % of E_hg before: measured
 * in the printout); a second update releases nothing (z = 0 at the new reference: below 1e-12
 * of the first, round-off of F ξ against x_k − x_i). ρ of each particle is continuous
 * (V ← J V) and F = I after it (bond stretch 1). */
static void test_energy_to_heat(void **state) {
  (void)state;
  for (int merge = 0; merge < 2; ++merge) {
    block b;
    block_make(&b, E_affine, 0.0, 1.0);
    unsigned r = 777u;
    for (size_t j = 0; j < 3 * b.s.n; ++j) {
      r = r * 1103515245u + 12345u;
      b.s.u[j] = 0.02 * ((double)((r >> 8) & 0xffff) / 65535.0 - 0.5);
    }
    assert_int_equal(dm_fin_refresh(b.f), MS_OK);
    for (int step = 0; step < 40; ++step) assert_int_equal(dm_fin_step(b.f), MS_OK);
    double K0, U0, H0, K1, U1, H1;
    dm_fin_energies(b.f, &K0, &U0, &H0);
    double *rho = calloc(b.s.n, sizeof(double));
    for (size_t i = 0; i < b.s.n; ++i) rho[i] = b.f->rho[i];
    dm_refamily_report rep;
    assert_int_equal(dm_fin_rebase(b.f, &b.ctx, merge, &rep), MS_OK);
    dm_fin_energies(b.f, &K1, &U1, &H1);
    printf("update (merge %d): released %.6g kJ, U %.9g -> %.9g, E_hg %.6g -> %.6g, bonds %zu\n",
           merge, rep.released, U0, U1, H0, H1, rep.bonds);
    assert_true(rep.released > 0 && H0 > 0);
    assert_true(fabs((K1 + U1 + H1) - (K0 + U0 + H0)) < 1e-13 * fabs(U0));
    assert_true(fabs((H0 - H1) - rep.released) < 1e-12 * rep.released);
    assert_true(fabs(H1) < 0.05 * H0);
    for (size_t i = 0; i < b.s.n; ++i) assert_true(fabs(b.f->rho[i] / rho[i] - 1) < 1e-12);
    assert_true(fabs(dm_fin_max_stretch(b.f, NULL) - 1.0) < 1e-14);
    dm_refamily_report rep2;
    assert_int_equal(dm_fin_rebase(b.f, &b.ctx, merge, &rep2), MS_OK);
    assert_true(rep2.released < 1e-12 * rep.released);
    free(rho);
    block_free(&b);
  }
}

/* Merged families: a corner particle pushed 0.3 h diagonally into the block comes within the
 * horizon (1.5 h) of particles that were not its neighbours (the one at (1.5, 1.5, 1.5) h:
 * √3 h before, 1.21 h now); after the merge it has them, the
 * old ones too, and every bond i → k has its partner k → i. */
static void test_merge_symmetric(void **state) {
  (void)state;
  const double zero[9] = {0};
  block b;
  block_make(&b, zero, 0.0, 1.0);
  const size_t c = 0; /* corner (0.5, 0.5, 0.5) h */
  for (int a = 0; a < 3; ++a) b.s.w[3 * c + a] = 0.3 * H;
  assert_int_equal(dm_fin_refresh(b.f), MS_OK);
  const dm_model *m = b.f->m;
  const size_t before = m->start[c + 1] - m->start[c];
  dm_refamily_report rep;
  assert_int_equal(dm_fin_rebase(b.f, &b.ctx, true, &rep), MS_OK);
  m = b.f->m;
  const size_t after = m->start[c + 1] - m->start[c];
  printf("merge: corner family %zu -> %zu bonds, %zu bonds in all\n", before, after, m->nbonds);
  assert_true(after > before);
  const size_t far = (size_t)((N1 + 1) * N1 + 1); /* (1.5, 1.5, 1.5) h */
  bool found = false;
  for (size_t q = m->start[c]; q < m->start[c + 1]; ++q) found |= m->nbr[q] == far;
  assert_true(found);
  for (size_t i = 0; i < b.s.n; ++i)
    for (size_t q = m->start[i]; q < m->start[i + 1]; ++q) {
      const size_t k = m->nbr[q];
      bool back = false;
      for (size_t r = m->start[k]; r < m->start[k + 1]; ++r) back |= m->nbr[r] == i;
      assert_true(back);
    }
  block_free(&b);
}

/* A refused update (a new shape matrix above cond_max: here cond_max lowered to 3 before an
 * update of a block compressed to half along x, cond F A Fᵀ ≈ 4 in the interior) restores the
 * old reference, volumes and families — also the merged ones — and moves no energy. */
static void test_refused(void **state) {
  (void)state;
  const double E[9] = {-0.5, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int merge = 0; merge < 2; ++merge) {
    block b;
    block_make(&b, E, 0.01, 1.0);
    dm_model *m = b.f->m;
    const size_t nb = m->nbonds, n = b.s.n;
    double *X = malloc(3 * n * sizeof(double)), *w = malloc(3 * n * sizeof(double));
    memcpy(X, b.s.X, 3 * n * sizeof(double)), memcpy(w, b.s.w, 3 * n * sizeof(double));
    const double e5 = b.f->e[5], V5 = b.s.vol[5];
    m->opt.cond_max = 3.0;
    dm_refamily_report rep;
    assert_int_equal(dm_fin_rebase(b.f, &b.ctx, merge, &rep), MS_ERR_UNSTABLE);
    assert_true(rep.bad < n);
    assert_true(b.f->m == m && m->nbonds == nb);
    assert_memory_equal(X, b.s.X, 3 * n * sizeof(double));
    assert_memory_equal(w, b.s.w, 3 * n * sizeof(double));
    assert_true(b.f->e[5] == e5 && b.s.vol[5] == V5);
    free(X), free(w);
    block_free(&b);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_patch),
      cmocka_unit_test(test_energy_to_heat),
      cmocka_unit_test(test_merge_symmetric),
      cmocka_unit_test(test_refused),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
