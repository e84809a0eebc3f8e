/* SPDX-License-Identifier: MIT */
/* The reference update that keeps the families (dm_fin_rebase, particles/dm/dm_refamily.c,
 * docs/particles-dm.md "Reference update"): the affine patch test of the bond penalty (a
 * uniform deformation gives no stabilisation force, before and after the update, with the
 * families kept or merged); the update moves exactly the penalty's stored energy into heat
 * (K + U + E_hg unchanged) and restarts the mismatch z from 0; merged families stay symmetric
 * and gain a particle that has come within the horizon. The per-family update
 * (dm_fin_rebase_local, particles/dm/dm_fin_local.c): its kernels reproduce the shared
 * reference's forces; the patch test after a partial update (families with different
 * references); energy to round-off and momentum exact over steps with updates; a merged
 * partner gains the bond with zero mismatch; a refused update changes nothing. The per-family
 * update in a periodic box: the bonds across the boundary keep their image, so an update takes
 * their minimum-image vector as the new reference and the gather their reverse bonds' with the
 * opposite image (the patch test across the boundary, energy and momentum over steps, merge
 * refused). */
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
 * displacement w = E X + a zero-mean pseudo-random part of amplitude `noise` h (generator
 * seeded with `seed`), bond penalty c_s, periodic along y with period box_y if box_y > 0 (then
 * E's y column must be 0: a periodic displacement cannot depend on y). */
static void block_make_in(block *b, const double E[9], double noise, double cs, unsigned seed,
                          double box_y) {
  if (box_y > 0) assert_true(E[1] == 0 && E[4] == 0 && E[7] == 0);
  b->eos = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  dm_state_alloc(&b->s, (size_t)(N1 * N1 * N1), 3);
  unsigned r = seed;
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
  const dm_options opt = {.horizon = 1.5 * H, .cond_max = 1e8, .box = {0, box_y, 0}};
  assert_int_equal(
      dm_model_create(&(dm_model_params){.state = &b->s, .opt = opt, .ctx = &b->ctx}, &m), MS_OK);
  b->mat = (dm_fin_material){.eos = b->eos, .yield = DM_YIELD_ELASTIC_PLASTIC, .G = 27.6, .Y0 = 10};
  b->imat = calloc(b->s.n, 1);
  dm_fin_params par = {.cq = 2, .cl = 0.5, .courant = 0.4, .hourglass = cs, .ell = H};
  assert_int_equal(
      dm_fin_create(&(dm_fin_setup){.m = m, .mat = &b->mat, .imat = b->imat, .par = par}, &b->f),
      MS_OK);
}

/* The block without a periodic box. */
static void block_make(block *b, const double E[9], double noise, double cs) {
  block_make_in(b, E, noise, cs, 12345u, 0.0);
}

/* Pseudo-random velocities of ±0.01 km/s on every component, the forces refreshed. */
static void random_velocities(block *b) {
  unsigned r = 777u;
  for (size_t j = 0; j < 3 * b->s.n; ++j) {
    r = r * 1103515245u + 12345u;
    b->s.u[j] = 0.02 * ((double)((r >> 8) & 0xffff) / 65535.0 - 0.5);
  }
  assert_int_equal(dm_fin_refresh(b->f), MS_OK);
}

/* Σ m u into P and, if mu is given, Σ m |u| into *mu. */
static void momentum(const block *b, double P[3], double *mu) {
  P[0] = P[1] = P[2] = 0;
  double s = 0;
  for (size_t i = 0; i < b->s.n; ++i)
    for (int a = 0; a < 3; ++a)
      P[a] += b->s.mass[i] * b->s.u[3 * i + a], s += b->s.mass[i] * fabs(b->s.u[3 * i + a]);
  if (mu) *mu = s;
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
    random_velocities(&b);
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

/* ---- per-family references (dm_fin_rebase_local) ---- */

/* max |a − b| over 3n components, and max |b| */
static double max_diff(const double *a, const double *b, size_t n3, double *scale) {
  double d = 0, big = 0;
  for (size_t j = 0; j < n3; ++j) d = fmax(d, fabs(a[j] - b[j])), big = fmax(big, fabs(b[j]));
  *scale = big;
  return d;
}

/* The per-family kernels (bond moments, gather with the reverse bonds' own vectors) on vectors
 * equal to the shared reference give the shared reference's forces: a non-affine state (noise
 * 0.05 h, so the penalty acts), switched to per-family vectors without an update
 * (dm_fin_local_init; an update call with threshold 10 passes nothing and keeps the shared
 * reference).
 * 1e-13 of the largest force is round-off of sums of ~20 bonds in another order; a sign error
 * in the reverse bonds' stress term Q_k ξ_rev gives 0.9 of |f|: the test can fail (an error
 * in their offsets ΔX − ξ, 0 here, fails test_local_patch and test_local_dynamics). */
static void test_local_kernels(void **state) {
  (void)state;
  block b;
  block_make(&b, E_affine, 0.05, 1.0);
  const size_t n3 = 3 * b.s.n;
  double *f0 = malloc(n3 * sizeof(double));
  memcpy(f0, b.f->frc, n3 * sizeof(double));
  dm_refamily_report rep;
  assert_int_equal(dm_fin_rebase_local(b.f, &b.ctx, 10.0, false, &rep), MS_OK);
  assert_true(rep.families == 0 && !b.f->m->xref); /* nothing passed: still shared */
  assert_int_equal(dm_fin_local_init(b.f), MS_OK);
  assert_true(b.f->m->xref && b.f->m->rev);
  assert_int_equal(dm_fin_refresh(b.f), MS_OK);
  double scale, d = max_diff(b.f->frc, f0, n3, &scale);
  printf("per-family kernels on the shared reference: |df| %.3g of |f| %.3g\n", d, scale);
  assert_true(scale > 0 && d < 1e-13 * scale);
  free(f0);
  block_free(&b);
}

/* Sets x ← (I + E2) x (an affine increment from the current configuration) and refreshes. */
static void affine_increment(block *b, const double E2[9]) {
  dm_state *s = &b->s;
  for (size_t i = 0; i < s->n; ++i) {
    double x[3];
    for (int a = 0; a < 3; ++a) x[a] = s->X[3 * i + a] + s->w[3 * i + a];
    for (int a = 0; a < 3; ++a)
      s->w[3 * i + a] =
          x[a] + E2[3 * a] * x[0] + E2[3 * a + 1] * x[1] + E2[3 * a + 2] * x[2] - s->X[3 * i + a];
  }
  assert_int_equal(dm_fin_refresh(b->f), MS_OK);
}

/* Patch test with mixed references: after an affine stretch only the families holding the
 * most stretched bond direction pass a threshold just below it (the others, on two edges of
 * the block, keep the lattice as reference); a further affine increment is then exact on every
 * family, updated or not, so the bond penalty (f(c_s = 1) − f(c_s = 0)) stays at round-off
 * (1e-12 of the boundary forces, as test_patch). With the reverse bonds' vectors taken from
 * the bond itself (−ξ_b, the shared reference's rule) the penalty force is 7e-2 of |f|
 * (measured): the test can fail. */
static void test_local_patch(void **state) {
  (void)state;
  static const double E2[9] = {0.04, 0, -0.03, 0.02, -0.05, 0, 0, 0.01, 0.03};
  block b1, b0;
  /* 5 % stretch along (1, −1, 0): the families of the two vertical edges x = y = 0 and
   * x = y = (N1 − 1) h have no bond along that line */
  static const double E1[9] = {0.025, -0.025, 0, -0.025, 0.025, 0, 0, 0, 0};
  block_make(&b1, E1, 0.0, 1.0), block_make(&b0, E1, 0.0, 0.0);
  const double lam = dm_fin_max_stretch(b1.f, NULL);
  block *bb[2] = {&b1, &b0};
  for (int q = 0; q < 2; ++q) {
    dm_refamily_report rep;
    assert_int_equal(dm_fin_rebase_local(bb[q]->f, &bb[q]->ctx, 0.999 * (lam - 1), false, &rep),
                     MS_OK);
    printf("partial update: %zu of %zu families\n", rep.families, bb[q]->s.n);
    assert_true(rep.families > 0 && rep.families < bb[q]->s.n);
    affine_increment(bb[q], E2);
  }
  double scale, d = max_diff(b1.f->frc, b0.f->frc, 3 * b1.s.n, &scale);
  printf("patch test, per-family update: |f_penalty| %.3g, |f| %.3g\n", d, scale);
  assert_true(scale > 0 && d < 1e-12 * scale);
  block_free(&b1), block_free(&b0);
}

/* Dynamics with per-family updates (random velocities 0.02 km/s on the block with noise,
 * threshold 1 %: families update at different steps, a part of them at a time; merge
 * on): K + U + E_hg stays at
 * E0 to 1e-13 of |K| + |U| + |E_hg| (they nearly cancel: E0 is 1e-3 of them; round-off of 216
 * terms over 60 steps, 1e-15 measured; nothing is driven), Σ m u is kept to
 * 1e-15 of Σ m|u| (each family's bond forces act in equal and opposite pairs), ρ of an updated
 * family is continuous (1e-12) and only the updated families change their volume. */
static void test_local_dynamics(void **state) {
  (void)state;
  block b;
  const double zero[9] = {0};
  block_make(&b, zero, 0.02, 1.0);
  random_velocities(&b);
  const size_t n = b.s.n;
  double K, U, Hg, P0[3], mu;
  dm_fin_energies(b.f, &K, &U, &Hg);
  const double E0 = K + U + Hg;
  momentum(&b, P0, &mu);
  double dE = 0, Es = 0;
  size_t updates = 0, steps_with = 0, most = 0;
  for (int step = 0; step < 60; ++step) {
    assert_int_equal(dm_fin_step(b.f), MS_OK);
    double *V = malloc(n * sizeof(double)), *rho = malloc(n * sizeof(double));
    memcpy(V, b.s.vol, n * sizeof(double)), memcpy(rho, b.f->rho, n * sizeof(double));
    dm_refamily_report rep;
    assert_int_equal(dm_fin_rebase_local(b.f, &b.ctx, 0.01, true, &rep), MS_OK);
    updates += rep.families, steps_with += rep.families > 0;
    most = rep.families > most ? rep.families : most;
    size_t moved = 0; /* exactly the updated families change V */
    for (size_t i = 0; i < n; ++i)
      if (b.s.vol[i] != V[i]) {
        ++moved;
        assert_true(fabs(b.f->rho[i] / rho[i] - 1) < 1e-12);
      }
    assert_true(moved == rep.families);
    free(V), free(rho);
    dm_fin_energies(b.f, &K, &U, &Hg);
    dE = fmax(dE, fabs(K + U + Hg - E0)), Es = fmax(Es, fabs(K) + fabs(U) + fabs(Hg));
  }
  double P[3], dP = 0;
  momentum(&b, P, NULL);
  for (int a = 0; a < 3; ++a) dP = fmax(dP, fabs(P[a] - P0[a]));
  printf("per-family dynamics: %zu family updates at %zu of 60 steps (at most %zu at once), "
         "|dE| %.3g of |K| + |U| + |E_hg| %.3g, |dP| %.3g of sum m|u| %.3g\n",
         updates, steps_with, most, dE, Es, dP, mu);
  assert_true(steps_with > 1 && most < n);
  assert_true(dE < 1e-13 * Es);
  assert_true(dP < 1e-15 * mu);
  block_free(&b);
}

/* Merge with per-family references: the corner pushed 0.3 h into the block (test_merge_symmetric)
 * after a small affine strain; its family and its neighbours' pass the threshold; it bonds the particle at (1.5, 1.5, 1.5) h, which
 * gains the bond back pulled through its own F (it did not pass: its F, J and stress stay, to
 * round-off 1e-12; with the bond's current vector instead of the pull-back it does not:
 * the test can fail), every bond's rev is its partner's bond back, and K + U + E_hg is unchanged
 * (1e-12 of the energy the update moved from E_hg into e: round-off). */
static void test_local_merge(void **state) {
  (void)state;
  /* a small affine strain first (bond stretch < 1.04), so that the partner's F is not I */
  static const double E[9] = {0.03, 0.01, 0, 0, -0.02, 0, 0, 0, 0.01};
  block b;
  block_make(&b, E, 0.0, 1.0);
  const size_t c = 0, far = (size_t)((N1 + 1) * N1 + 1);
  for (int a = 0; a < 3; ++a) b.s.w[3 * c + a] += 0.3 * H;
  assert_int_equal(dm_fin_refresh(b.f), MS_OK);
  double F[9], K0, U0, H0, K1, U1, H1;
  memcpy(F, &b.f->F[9 * far], sizeof F);
  const size_t before = b.f->m->start[far + 1] - b.f->m->start[far];
  dm_fin_energies(b.f, &K0, &U0, &H0);
  dm_refamily_report rep;
  assert_int_equal(dm_fin_rebase_local(b.f, &b.ctx, 0.1, true, &rep), MS_OK);
  const dm_model *m = b.f->m;
  dm_fin_energies(b.f, &K1, &U1, &H1);
  printf("per-family merge: %zu families updated, %zu gained bonds; far family %zu -> %zu\n",
         rep.families, rep.gained, before, m->start[far + 1] - m->start[far]);
  assert_true(rep.families >= 1 && rep.gained >= 1);
  assert_true(m->start[far + 1] - m->start[far] == before + 1);
  for (int a = 0; a < 9; ++a) assert_true(fabs(b.f->F[9 * far + a] - F[a]) < 1e-12);
  for (size_t i = 0; i < b.s.n; ++i)
    for (size_t q = m->start[i]; q < m->start[i + 1]; ++q)
      assert_true(m->nbr[m->rev[q]] == i && m->rev[m->rev[q]] == q);
  assert_true(rep.released > 0);
  assert_true(fabs((K1 + U1 + H1) - (K0 + U0 + H0)) < 1e-12 * rep.released);
  block_free(&b);
}

/* A refused per-family update (cond_max 3 under a compression to half along x, as test_refused)
 * changes nothing: volumes, energies, bonds. */
static void test_local_refused(void **state) {
  (void)state;
  const double E[9] = {-0.5, 0, 0, 0, 0, 0, 0, 0, 0};
  block b;
  block_make(&b, E, 0.01, 1.0);
  dm_model *m = b.f->m;
  const size_t nb = m->nbonds;
  const double e5 = b.f->e[5], V5 = b.s.vol[5];
  m->opt.cond_max = 3.0;
  dm_refamily_report rep;
  assert_int_equal(dm_fin_rebase_local(b.f, &b.ctx, 0.1, true, &rep), MS_ERR_UNSTABLE);
  assert_true(rep.bad < b.s.n && m->nbonds == nb);
  assert_true(b.f->e[5] == e5 && b.s.vol[5] == V5);
  block_free(&b);
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
  block_make_in(&b1, E1, 0.0, 1.0, 4242u, N1 * H), block_make_in(&b0, E1, 0.0, 0.0, 4242u, N1 * H);
  block *bb[2] = {&b1, &b0};
  for (int q = 0; q < 2; ++q) {
    dm_refamily_report rep;
    assert_int_equal(dm_fin_rebase_local(bb[q]->f, &bb[q]->ctx, 0.01, false, &rep), MS_OK);
    assert_true(rep.families == bb[q]->s.n);
    affine_increment(bb[q], E2);
  }
  const size_t nc = crossing_bonds(b1.f->m);
  double scale, d = max_diff(b1.f->frc, b0.f->frc, 3 * b1.s.n, &scale);
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
  block_make_in(&b, zero, 0.02, 1.0, 4242u, N1 * H);
  random_velocities(&b);
  double K, U, Hg, P0[3], mu;
  dm_fin_energies(b.f, &K, &U, &Hg);
  const double E0 = K + U + Hg;
  momentum(&b, P0, &mu);
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
  double P[3], dP = 0;
  momentum(&b, P, NULL);
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
      cmocka_unit_test(test_patch),
      cmocka_unit_test(test_energy_to_heat),
      cmocka_unit_test(test_merge_symmetric),
      cmocka_unit_test(test_refused),
      cmocka_unit_test(test_local_kernels),
      cmocka_unit_test(test_local_patch),
      cmocka_unit_test(test_local_dynamics),
      cmocka_unit_test(test_local_merge),
      cmocka_unit_test(test_local_refused),
      cmocka_unit_test(test_periodic_patch),
      cmocka_unit_test(test_periodic_dynamics),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
