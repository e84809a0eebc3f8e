/* SPDX-License-Identifier: MIT */
/* test_dm_contact.c — the short-range contact of the finite-deformation discrete model between
 * particles not in each other's family (particles/dm/dm_contact.c, docs/particles-dm.md
 * "Contact"):
 *  a. a pair within the contact distance is pushed apart: two 1D blocks whose facing particles
 *     (different families) sit at 0.3 h, at rest: the force on each is the pair law's
 *     κ_ik d_c g(r/d_c) (dm_pair_law, evaluated here), equal and opposite, and the pair
 *     separates beyond d_c;
 *  b. two intact 2D blocks (periodic in y) thrown at each other rebound: K + U + E_hg + contact
 *     is conserved to round-off at every step, momentum to round-off, the blocks' velocities are
 *     reversed, no pair comes closer than half the contact distance, and the contact's energy
 *     after the separation (the spring's booked work, 0 for an exact integration) falls with the
 *     step; without the contact (contact_distance 0) they pass into each other;
 *  c. the cell list's walk (particles/dm/dm_cells.h), which the contact passes share, finds from
 *     each particle every other one closer than the cell size exactly once, against all pairs
 *     by brute force. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "dm_impl.h"
#include "dm_test.h"

/* Two blocks of nx × ny particles (spacing h; Al, no strength), block B shifted by gap h beyond
 * A along x in the reference (so no bond crosses: gap > horizon 1.5 h), then moved by shift h
 * (w) and given velocities ±v along x. Periodic in y for ny > 1. */
typedef dm_fin_body blocks;

static ms_status blocks_build(blocks *b, int dim, long nx, long ny, double gap, double shift,
                              double v, const dm_fin_params *par) {
  const double h = par->ell;
  dm_fin_body_alloc(b, dim, (size_t)(2 * nx * ny), nx, ny, h, &(dm_fin_material){0});
  for (long blk = 0; blk < 2; ++blk)
    for (long iy = 0; iy < ny; ++iy)
      for (long ix = 0; ix < nx; ++ix) {
        const size_t i = (size_t)((blk * ny + iy) * nx + ix);
        b->s.X[3 * i] = (ix + 0.5 + blk * (nx - 1 + gap)) * h;
        b->s.X[3 * i + 1] = dim > 1 ? (iy + 0.5) * h : 0.0;
        b->s.w[3 * i] = blk ? -shift * h : 0.0;
        b->s.u[3 * i] = blk ? -v : v;
      }
  return dm_fin_body_finish(b, par);
}

/* the smallest distance between a particle of A and one of B (current positions) */
static double blocks_gap(const blocks *b) {
  const size_t nb = (size_t)(b->nx * b->ny);
  double rmin = INFINITY;
  for (size_t i = 0; i < nb; ++i)
    for (size_t k = nb; k < 2 * nb; ++k) {
      double r2 = 0;
      for (int a = 0; a < 3; ++a) {
        double d =
            (b->s.X[3 * k + a] + b->s.w[3 * k + a]) - (b->s.X[3 * i + a] + b->s.w[3 * i + a]);
        if (a == 1 && b->ny > 1) d -= b->ny * b->h * nearbyint(d / (b->ny * b->h));
        r2 += d * d;
      }
      rmin = fmin(rmin, sqrt(r2));
    }
  return rmin;
}

/* a. */
static void test_pair_pushed_apart(void **state) {
  (void)state;
  const double h = 0.001, dc = 0.5;
  dm_fin_params par = {
      .cq = 2.0, .cl = 0.5, .courant = 0.4, .hourglass = 1.0, .ell = h, .contact = dc};
  blocks b;
  /* reference gap 2 h (no bond across), moved 1.7 h closer: the facing pair at 0.3 h */
  assert_int_equal(blocks_build(&b, 1, 3, 1, 2.0, 1.7, 0.0, &par), MS_OK);
  const size_t ia = 2, ib = 3; /* the facing particles */
  const double r = (b.s.X[3 * ib] + b.s.w[3 * ib]) - (b.s.X[3 * ia] + b.s.w[3 * ia]);
  assert_true(fabs(r - 0.3 * h) < 1e-12 * h);
  double g, s;
  dm_pair_law(b.f, ia, r / (dc * h), &g, &s);
  /* κ_ik = κc_a + κc_b, κc = K d² V / Σ|ξ|² with d = 1, the end particle's family one bond h */
  const double K = 2.703 * 5.35 * 5.35, kap = 2.0 * K * h / (h * h);
  const double fexp = kap * dc * h * g; /* the pair law's push, > 0 */
  assert_true(fexp > 0);
  /* at rest the bond forces are 0, so frc is the contact's alone: to round-off of the pair law */
  assert_true(fabs(-b.f->frc[3 * ia] - fexp) < 1e-12 * fexp);
  assert_true(b.f->frc[3 * ib] == -b.f->frc[3 * ia]); /* equal and opposite, bit for bit */
  for (long step = 0; step < 2000 && b.f->sr->touching; ++step)
    assert_int_equal(dm_fin_step(b.f), MS_OK);
  const double r1 = (b.s.X[3 * ib] + b.s.w[3 * ib]) - (b.s.X[3 * ia] + b.s.w[3 * ia]);
  assert_true(r1 >= dc * h);                           /* pushed out of the contact */
  assert_true(b.s.u[3 * ia] < 0 && b.s.u[3 * ib] > 0); /* and moving apart */
  dm_fin_body_free(&b);
}

/* b. Returns the contact energy left after the separation over K0; *rmin the closest approach
 * over h. */
static double rebound(double courant, double contact, double *rmin, int *passed) {
  const double h = 0.001, v = 0.1;
  dm_fin_params par = {
      .cq = 0.0, .cl = 0.0, .courant = courant, .hourglass = 1.0, .ell = h, .contact = contact};
  blocks b;
  assert_int_equal(blocks_build(&b, 2, 6, 5, 3.0, 0.0, v, &par), MS_OK);
  const size_t nb = (size_t)(b.nx * b.ny);
  double K0;
  dm_fin_energies(b.f, &K0, NULL, NULL);
  const double E0 = dm_fin_body_energy(&b), m = b.s.mass[0];
  double dE = 0, dP = 0;
  *rmin = INFINITY, *passed = 0;
  int met = 0, apart = 0;
  ms_status st = MS_OK;
  for (long step = 0; step < 100000 && st == MS_OK; ++step) {
    st = dm_fin_step(b.f);
    if (st != MS_OK) break;
    dE = fmax(dE, fabs(dm_fin_body_energy(&b) - E0));
    double P = 0, uA = 0, uB = 0;
    for (size_t i = 0; i < 2 * nb; ++i) P += m * b.s.u[3 * i];
    for (size_t i = 0; i < nb; ++i) uA += b.s.u[3 * i] / nb, uB += b.s.u[3 * (i + nb)] / nb;
    dP = fmax(dP, fabs(P));
    const double gap = blocks_gap(&b);
    *rmin = fmin(*rmin, gap / h);
    if (gap < 0.5 * contact * h) met = 1;
    /* A's mean x beyond B's: they passed into each other */
    double xA = 0, xB = 0;
    for (size_t i = 0; i < nb; ++i)
      xA += (b.s.X[3 * i] + b.s.w[3 * i]) / nb,
          xB += (b.s.X[3 * (i + nb)] + b.s.w[3 * (i + nb)]) / nb;
    if (xB - xA < 0.5 * b.nx * h) *passed = 1;
    if (uA < 0 && uB > 0 && gap > contact * h + 0.5 * h) apart = 1; /* rebounded, apart */
    if (*passed || apart) break;
  }
  double E_c = dm_fin_contact_energy(b.f);
  if (contact > 0) {
    assert_int_equal(st, MS_OK);
    /* the identity K + U + E_hg + contact − W: each half kick's work booked with its v̄, so
     * round-off only (~1e3 steps of sums of O(K0) terms: 1e-12 K0 leaves 10x margin) */
    assert_true(dE < 1e-12 * K0);
    /* central, equal and opposite (bit for bit) pair forces: Σ m u stays 0 up to the
     * summation's round-off */
    assert_true(dP < 1e-12 * m * v * (double)nb);
    assert_false(met); /* never closer than half the contact distance */
    assert_false(*passed);
    assert_true(apart); /* the blocks' mean velocities reversed, every pair beyond d_c */
  }
  if (getenv("DM_CONTACT_PRINT"))
    printf("rebound courant %.2f contact %.2f: closest %.3f h, contact energy left %.2e K0, "
           "balance %.1e K0, passed %d\n",
           courant, contact, *rmin, E_c / K0, dE / K0, *passed);
  dm_fin_body_free(&b);
  return E_c / K0;
}

static void test_blocks_rebound(void **state) {
  (void)state;
  double r1, r2, r0;
  int p1, p2, p0;
  const double e1 = rebound(0.4, 0.5, &r1, &p1), e2 = rebound(0.1, 0.5, &r2, &p2);
  /* the contact's booked energy after the separation (0 for an exact integration) is the
   * time discretisation's error of the face particles' motion, which the face's lattice springs
   * (ω dt ≈ 0.8 at courant 0.4) and the contact share: measured −5.6 % of K0 at courant 0.4,
   * 1.8 % at 0.1 (its sign alternates with the phase of the separation); asserted: below 10 %
   * at the default courant and falling with the step (at least halved over a 4x smaller step;
   * the booked balance above is exact whatever the step) */
  assert_true(fabs(e2) < fabs(e1) / 2.0);
  assert_true(fabs(e1) < 0.1);
  /* without the contact the blocks pass into each other */
  (void)rebound(0.4, 0.0, &r0, &p0);
  assert_true(p0 || r0 < 0.1);
}

/* c. The walk from every particle over 400 random ones in a box of 6 × 5 × 4 cells, in 1D, 2D
 * and 3D, periodic along the dimension's axes (minimum image; the wrap across each face) or not,
 * packed (one bucket per cell) or with 8 particles 10⁴ cells away (hashed buckets): every pair
 * closer than the cell size is visited exactly once from each side. Exact: integer counts. */
static void test_cell_walk(void **state) {
  (void)state;
  const size_t n = 400;
  const double box[3] = {6, 5, 4}; /* cell size 1 */
  double *X = calloc(3 * n, sizeof *X), *w = calloc(3 * n, sizeof *w);
  uint8_t *seen = calloc(n * n, 1);
  uint64_t rng = 12345;
  for (int dim = 1; dim <= 3; ++dim)
    for (int periodic = 0; periodic < 2; ++periodic)
      for (int far = 0; far < 2 - periodic; ++far) {
        for (size_t i = 0; i < 3 * n; ++i) {
          rng = rng * 6364136223846793005u + 1442695040888963407u; /* 64-bit LCG: any spread */
          const int a = (int)(i % 3);
          X[i] = a < dim ? box[a] * (double)(rng >> 11) / 9007199254740992.0 : 0.0;
          if (far && i < 24 && a < dim) X[i] += 1e4;
        }
        dm_cells c;
        assert_int_equal(dm_cells_init(&c, n, dim, 1.0, NULL, periodic ? box : NULL), MS_OK);
        dm_cells_build(&c, X, w);
        assert_int_equal(c.dense, !far);
        memset(seen, 0, n * n);
        size_t pairs = 0;
        for (size_t i = 0; i < n; ++i)
          for (int q = 0; q < c.nnear; ++q) {
            long cell[3];
            dm_cells_near(&c, &c.cidx[3 * i], q, cell);
            for (long j = dm_cells_list(&c, cell); j >= 0; j = c.next[j])
              if ((size_t)j != i && dm_cells_holds(&c, j, cell)) ++seen[i * n + (size_t)j];
          }
        for (size_t i = 0; i < n; ++i)
          for (size_t j = 0; j < n; ++j) {
            double r2 = 0;
            for (int a = 0; a < 3; ++a) {
              double y = X[3 * j + a] - X[3 * i + a];
              if (periodic && a < dim) y -= box[a] * nearbyint(y / box[a]);
              r2 += y * y;
            }
            if (i != j && r2 < 1.0) {
              assert_int_equal(seen[i * n + j], 1);
              ++pairs;
            } else {
              assert_true(seen[i * n + j] <= 1);
            }
          }
        printf("cell walk, %dD, %s, %s: %zu pairs within the cell size, each seen once\n", dim,
               periodic ? "periodic" : "not periodic", far ? "hashed" : "dense", pairs);
        assert_true(pairs > n / 2);
        dm_cells_free(&c);
      }
  free(X), free(w), free(seen);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pair_pushed_apart),
      cmocka_unit_test(test_blocks_rebound),
      cmocka_unit_test(test_cell_walk),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
