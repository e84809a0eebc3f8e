/* SPDX-License-Identifier: MIT */
/* cd_partition_cells (particles/cd_partition.c): slab balance on known weights, METIS against
 * slabs, determinism, the periodic wrap of the 26-neighbour stencil, and the reported
 * imbalance / edge cut / halo cells against a brute-force count over all cell pairs. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "cd.h"

static int64_t ncells(const int n[3]) { return (int64_t)n[0] * n[1] * n[2]; }

/* Brute force over all cell pairs: adjacent when every axis index differs by at most 1
 * (circularly on periodic axes) and the cells differ. */
static bool adjacent(const int n[3], const bool per[3], int64_t a, int64_t b) {
  if (a == b) return false;
  int64_t ia[3] = {a % n[0], a / n[0] % n[1], a / n[0] / n[1]};
  int64_t ib[3] = {b % n[0], b / n[0] % n[1], b / n[0] / n[1]};
  for (int k = 0; k < 3; ++k) {
    int64_t d = llabs(ia[k] - ib[k]);
    if (per[k] && n[k] - d < d) d = n[k] - d;
    if (d > 1) return false;
  }
  return true;
}

/* Brute-force figures; halo[p] and nbrs[p] (distinct adjacent parts) per part. The load is
 * max_p (weight of p + 0.25 × weight of p's halo cells) / mean (ptl.h). */
static void brute_stats(const int n[3], const bool per[3], const int64_t *w, int nparts,
                        const int32_t *owner, cd_partition_stats *st, long *halo, int *nbrs) {
  int64_t nv = ncells(n);
  double *pw = calloc((size_t)nparts, sizeof(double)), tot = 0, mx = 0;
  for (int64_t c = 0; c < nv; ++c) {
    pw[owner[c]] += (double)w[c];
    tot += (double)w[c];
  }
  for (int p = 0; p < nparts; ++p) mx = fmax(mx, pw[p]);
  st->imbalance = mx / (tot / nparts);
  st->edge_cut = 0;
  for (int64_t a = 0; a < nv; ++a)
    for (int64_t b = a + 1; b < nv; ++b)
      if (owner[a] != owner[b] && adjacent(n, per, a, b)) st->edge_cut++;
  st->halo_cells = 0;
  st->load = 0;
  for (int p = 0; p < nparts; ++p) {
    halo[p] = 0;
    nbrs[p] = 0;
    double hw = 0;
    for (int64_t c = 0; c < nv; ++c) {
      if (owner[c] == p) continue;
      bool near = false;
      for (int64_t b = 0; b < nv && !near; ++b) near = owner[b] == p && adjacent(n, per, c, b);
      halo[p] += near;
      hw += near ? (double)w[c] : 0.0;
    }
    st->load = fmax(st->load, (pw[p] + 0.25 * hw) / (tot / nparts));
    st->halo_cells += halo[p];
    for (int q = 0; q < nparts; ++q) {
      bool touch = false;
      for (int64_t a = 0; a < nv && !touch && q != p; ++a)
        for (int64_t b = 0; b < nv && !touch && owner[a] == p; ++b)
          touch = owner[b] == q && adjacent(n, per, a, b);
      nbrs[p] += touch;
    }
  }
  free(pw);
}

/* Slabs on known plane weights: along x, planes weigh 6,1,1,1,1,1,1,4 (each plane 2×3 cells,
 * the plane weight on its first cell): 2 parts split 8 | 8 after plane 2; 4 parts put each
 * plane in the part holding the midpoint of its weight. */
static void test_slab_known_weights(void **state) {
  (void)state;
  const int n[3] = {8, 2, 3};
  const bool per[3] = {false, false, false};
  const int64_t plane_w[8] = {6, 1, 1, 1, 1, 1, 1, 4};
  int64_t w[48] = {0};
  for (int x = 0; x < 8; ++x) w[x] = plane_w[x];
  int32_t owner[48];
  cd_partition_stats st;
  assert_int_equal(cd_partition_cells(n, per, w, 2, CD_PART_SLAB, 0, owner, &st), MS_OK);
  for (int64_t c = 0; c < 48; ++c) assert_int_equal(owner[c], c % 8 < 3 ? 0 : 1);
  assert_true(st.imbalance == 1.0); /* 8 | 8 exactly */
  /* 4 parts, quarter marks at 4, 8, 12: midpoints 3, 6.5, 7.5, 8.5, 9.5, 10.5, 11.5, 14 →
   * parts 0,1,1,2,2,2,2,3 (weights 6, 2, 4, 4) */
  const int32_t expect4[8] = {0, 1, 1, 2, 2, 2, 2, 3};
  assert_int_equal(cd_partition_cells(n, per, w, 4, CD_PART_SLAB, 0, owner, &st), MS_OK);
  for (int64_t c = 0; c < 48; ++c) assert_int_equal(owner[c], expect4[c % 8]);
  assert_true(fabs(st.imbalance - 6.0 / 4.0) < 1e-15); /* part 0 = plane 0 (6) of mean 4 */
  /* along z (3 planes of 16 cells), uniform weights: one plane per part */
  int64_t u[48];
  for (int c = 0; c < 48; ++c) u[c] = 5;
  assert_int_equal(cd_partition_cells(n, per, u, 3, CD_PART_SLAB, 2, owner, &st), MS_OK);
  for (int64_t c = 0; c < 48; ++c) assert_int_equal(owner[c], c / 16);
  assert_true(st.imbalance == 1.0);
  cd_partition_stats bf;
  long halo[5];
  int nbrs[5];
  brute_stats(n, per, u, 3, owner, &bf, halo, nbrs);
  assert_int_equal(st.edge_cut, bf.edge_cut);
  assert_int_equal(st.halo_cells, bf.halo_cells);
  assert_int_equal(st.halo_cells, 4 * 16); /* the middle part sees both neighbours' planes */
}

/* Planes that do not divide evenly: 5 uniform planes of 4×3 cells along x on 2 parts are cut
 * inside the middle plane, after its first 6 cells in (y, z) row order: 30 | 30 cells. */
static void test_slab_cut_inside_plane(void **state) {
  (void)state;
  const int n[3] = {5, 4, 3};
  const bool per[3] = {true, false, false};
  int64_t w[60];
  for (int c = 0; c < 60; ++c) w[c] = 7;
  int32_t owner[60];
  cd_partition_stats st;
  assert_int_equal(cd_partition_cells(n, per, w, 2, CD_PART_SLAB, 0, owner, &st), MS_OK);
  for (int64_t c = 0; c < 60; ++c) {
    const int64_t x = c % 5, y = c / 5 % 4; /* z order inside a y row: rows y = 0, 1 first */
    assert_int_equal(owner[c], x < 2 || (x == 2 && y < 2) ? 0 : 1);
  }
  assert_true(st.imbalance == 1.0); /* whole planes would give 36 | 24: 1.2 */
  assert_true(st.method == CD_PART_SLAB && isnan(st.rejected_load));
}

/* auto keeps the map of lower load: on a uniform 16³ block, slabs for 2 parts (one cut plane
 * each side; METIS is no flatter and a little less even) and METIS for 8 parts (2-plane slabs
 * have halos as large as themselves: load (2 + 0.25·2)/2 = 1.25, METIS's 8³ corner blocks
 * ~(512 + 0.25·217)/512 = 1.11); the map returned is the chosen method's own, and the other's
 * load is reported. */
static void test_auto_choice(void **state) {
  (void)state;
  const int n[3] = {16, 16, 16};
  const bool per[3] = {false, false, false};
  const int64_t nv = ncells(n);
  int64_t *w = malloc((size_t)nv * sizeof *w);
  for (int64_t c = 0; c < nv; ++c) w[c] = 64;
  int32_t *oa = malloc((size_t)nv * sizeof *oa), *ob = malloc((size_t)nv * sizeof *ob);
  const int parts[2] = {2, 8};
  const cd_partition_method expect[2] = {CD_PART_SLAB, CD_PART_METIS};
  for (int k = 0; k < 2; ++k) {
    cd_partition_stats sa, sb, sother;
    assert_int_equal(cd_partition_cells(n, per, w, parts[k], CD_PART_AUTO, 2, oa, &sa), MS_OK);
    printf("16^3, %d parts: auto took %s, load %.4f (other %.4f)\n", parts[k],
           sa.method == CD_PART_SLAB ? "slab" : "metis", sa.load, sa.rejected_load);
    assert_int_equal(sa.method, expect[k]);
    assert_int_equal(cd_partition_cells(n, per, w, parts[k], expect[k], 2, ob, &sb), MS_OK);
    assert_memory_equal(oa, ob, (size_t)nv * sizeof *oa);
    assert_true(sa.load == sb.load && sa.load <= sa.rejected_load);
    assert_int_equal(cd_partition_cells(n, per, w, parts[k],
                                        expect[k] == CD_PART_SLAB ? CD_PART_METIS : CD_PART_SLAB, 2,
                                        ob, &sother),
                     MS_OK);
    assert_true(sother.load == sa.rejected_load);
    cd_partition_stats ev;
    assert_int_equal(cd_partition_evaluate(n, per, w, parts[k], oa, &ev), MS_OK);
    assert_true(ev.load == sa.load && ev.edge_cut == sa.edge_cut && ev.imbalance == sa.imbalance);
  }
  cd_partition_stats s8;
  assert_int_equal(cd_partition_cells(n, per, w, 8, CD_PART_SLAB, 2, ob, &s8), MS_OK);
  assert_true(fabs(s8.load - 1.25) < 1e-15); /* an inner slab: 2 planes + 2 halo planes */
  oa[0] = 8;                                 /* an owner outside [0, parts) */
  cd_partition_stats ev;
  assert_int_equal(cd_partition_evaluate(n, per, w, 8, oa, &ev), MS_ERR_INPUT);
  free(w);
  free(oa);
  free(ob);
}

/* On a uniform 16³ block, METIS cuts no more edges than slabs for 4..16 parts (slabs cut
 * (P−1) full planes, METIS near-cubic blocks) and stays balanced (METIS's default 3 %
 * tolerance, plus one cell of granularity: a cell is 1/256 of a part at 16 parts). */
static void test_metis_beats_slabs(void **state) {
  (void)state;
  const int n[3] = {16, 16, 16};
  const bool per[3] = {false, false, false};
  int64_t nv = ncells(n);
  int64_t *w = malloc((size_t)nv * sizeof *w);
  for (int64_t c = 0; c < nv; ++c) w[c] = 10;
  int32_t *om = malloc((size_t)nv * sizeof *om), *os = malloc((size_t)nv * sizeof *os);
  const int parts[] = {4, 8, 16};
  for (size_t k = 0; k < 3; ++k) {
    cd_partition_stats sm, ss;
    assert_int_equal(cd_partition_cells(n, per, w, parts[k], CD_PART_METIS, 0, om, &sm), MS_OK);
    assert_int_equal(cd_partition_cells(n, per, w, parts[k], CD_PART_SLAB, 0, os, &ss), MS_OK);
    printf("16^3, %2d parts: METIS cut %ld halo %ld imbalance %.4f | slab cut %ld halo %ld "
           "imbalance %.4f\n",
           parts[k], sm.edge_cut, sm.halo_cells, sm.imbalance, ss.edge_cut, ss.halo_cells,
           ss.imbalance);
    assert_true(sm.edge_cut <= ss.edge_cut);
    assert_true(sm.imbalance < 1.04);
    assert_true(ss.imbalance == 1.0); /* 16 planes split evenly */
    for (int64_t c = 0; c < nv; ++c) assert_true(om[c] >= 0 && om[c] < parts[k]);
  }
  free(w);
  free(om);
  free(os);
}

/* Two calls with the same input give the same map (every rank computes it independently). */
static void test_determinism(void **state) {
  (void)state;
  const int n[3] = {12, 9, 7};
  const bool per[3] = {true, false, true};
  int64_t nv = ncells(n);
  int64_t *w = malloc((size_t)nv * sizeof *w);
  for (int64_t c = 0; c < nv; ++c) w[c] = (int64_t)(100 * ptl_splitmix64_uniform(7, (uint64_t)c));
  int32_t *a = malloc((size_t)nv * sizeof *a), *b = malloc((size_t)nv * sizeof *b);
  for (int rep = 0; rep < 2; ++rep) {
    cd_partition_method m = rep ? CD_PART_METIS : CD_PART_SLAB;
    assert_int_equal(cd_partition_cells(n, per, w, 5, m, 1, a, NULL), MS_OK);
    assert_int_equal(cd_partition_cells(n, per, w, 5, m, 1, b, NULL), MS_OK);
    assert_memory_equal(a, b, (size_t)nv * sizeof *a);
  }
  free(w);
  free(a);
  free(b);
}

/* Periodic axes wrap: a ring of 4 cells in two slabs is cut twice (once open); a periodic axis
 * of 2 cells joins them once, not twice; a fully periodic 3³ grid is the complete graph on 27
 * cells (each cell's 26 offsets are 26 distinct cells). */
static void test_periodic_wrap(void **state) {
  (void)state;
  int32_t owner[27];
  int64_t w[27];
  for (int c = 0; c < 27; ++c) w[c] = 1;
  cd_partition_stats st;
  const int ring[3] = {4, 1, 1};
  const bool open[3] = {false, false, false}, px[3] = {true, false, false};
  assert_int_equal(cd_partition_cells(ring, px, w, 2, CD_PART_SLAB, 0, owner, &st), MS_OK);
  assert_int_equal(st.edge_cut, 2);
  assert_int_equal(st.halo_cells, 4);
  const int ring8[3] = {8, 1, 1};
  long halo[4];
  int nbrs[4];
  for (int per = 0; per < 2; ++per) { /* 4 slabs of 2 cells: ends have 1 neighbour unless wrapped */
    assert_int_equal(cd_partition_cells(ring8, per ? px : open, w, 4, CD_PART_SLAB, 0, owner, NULL),
                     MS_OK);
    cd_partition_halo(ring8, per ? px : open, owner, 4, halo, nbrs);
    for (int p = 0; p < 4; ++p) {
      bool end = !per && (p == 0 || p == 3);
      assert_int_equal(nbrs[p], end ? 1 : 2);
      assert_int_equal(halo[p], end ? 1 : 2);
    }
  }
  assert_int_equal(cd_partition_cells(ring, open, w, 2, CD_PART_SLAB, 0, owner, &st), MS_OK);
  assert_int_equal(st.edge_cut, 1);
  assert_int_equal(st.halo_cells, 2);
  const int two[3] = {2, 1, 1};
  assert_int_equal(cd_partition_cells(two, px, w, 2, CD_PART_METIS, 0, owner, &st), MS_OK);
  assert_int_equal(st.edge_cut, 1);
  assert_int_equal(st.halo_cells, 2);
  const int cube[3] = {3, 3, 3};
  const bool all[3] = {true, true, true};
  assert_int_equal(cd_partition_cells(cube, all, w, 27, CD_PART_METIS, 0, owner, &st), MS_OK);
  for (int c = 0; c < 27; ++c) assert_int_equal(owner[c], c); /* nparts ≥ cells: identity */
  assert_int_equal(st.edge_cut, 27 * 26 / 2);
  assert_int_equal(st.halo_cells, 27 * 26);
  assert_int_equal(cd_partition_cells(cube, open, w, 27, CD_PART_METIS, 0, owner, &st), MS_OK);
  /* open 3³: 8 corners × 7 + 12 edges × 11 + 6 faces × 17 + 1 centre × 26 neighbours, / 2 */
  assert_int_equal(st.edge_cut, (8 * 7 + 12 * 11 + 6 * 17 + 26) / 2);
}

/* The reported figures and the per-part halo / neighbour-part counts (cd_partition_halo) equal a
 * brute-force count over all cell pairs, for every method, several part counts and mixed
 * periodic/open axes (including a periodic axis of 2 cells). */
static void test_stats_brute_force(void **state) {
  (void)state;
  const int grids[2][3] = {{6, 5, 4}, {7, 2, 3}};
  const bool pers[2][3] = {{true, false, false}, {false, true, true}};
  for (int g = 0; g < 2; ++g) {
    const int *n = grids[g];
    int64_t nv = ncells(n);
    int64_t *w = malloc((size_t)nv * sizeof *w);
    for (int64_t c = 0; c < nv; ++c)
      w[c] = (int64_t)(50 * ptl_splitmix64_uniform(11 + (uint64_t)g, (uint64_t)c));
    int32_t *owner = malloc((size_t)nv * sizeof *owner);
    const int parts[] = {1, 2, 3, 5};
    for (int m = 0; m < 3; ++m)
      for (size_t k = 0; k < 4; ++k)
        for (int axis = 0; axis < 3; ++axis) {
          cd_partition_stats st, bf;
          const cd_partition_method meth =
              (cd_partition_method[]){CD_PART_SLAB, CD_PART_METIS, CD_PART_AUTO}[m];
          assert_int_equal(cd_partition_cells(n, pers[g], w, parts[k], meth, axis, owner, &st),
                           MS_OK);
          long halo[5], bhalo[5];
          int nbrs[5], bnbrs[5];
          brute_stats(n, pers[g], w, parts[k], owner, &bf, bhalo, bnbrs);
          cd_partition_halo(n, pers[g], owner, parts[k], halo, nbrs);
          for (int p = 0; p < parts[k]; ++p) {
            assert_int_equal(halo[p], bhalo[p]);
            assert_int_equal(nbrs[p], bnbrs[p]);
          }
          assert_int_equal(st.edge_cut, bf.edge_cut);
          assert_int_equal(st.halo_cells, bf.halo_cells);
          /* the same sum of the same integers (exact in double) divided the same way */
          assert_true(fabs(st.imbalance - bf.imbalance) <= 1e-14 * bf.imbalance);
          assert_true(fabs(st.load - bf.load) <= 1e-14 * bf.load); /* summed in another order */
          if (parts[k] == 1) assert_int_equal(st.edge_cut, 0);
          if (st.method ==
              CD_PART_SLAB) { /* slabs: parts non-decreasing in plane-major order, each within one
                         * cell weight of the mean (the midpoint rule) */
            const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
            const int64_t stride[3] = {1, n[0], (int64_t)n[0] * n[1]};
            double total = 0, wmax = 0, pw[5] = {0};
            int32_t prev = 0;
            for (int i0 = 0; i0 < n[axis]; ++i0)
              for (int i1 = 0; i1 < n[a1]; ++i1)
                for (int i2 = 0; i2 < n[a2]; ++i2) {
                  int64_t c = i0 * stride[axis] + i1 * stride[a1] + i2 * stride[a2];
                  assert_true(owner[c] >= prev);
                  prev = owner[c];
                  pw[owner[c]] += (double)w[c];
                  total += (double)w[c];
                  wmax = fmax(wmax, (double)w[c]);
                }
            for (int p = 0; p < parts[k]; ++p) assert_true(fabs(pw[p] - total / parts[k]) <= wmax);
          }
        }
    free(w);
    free(owner);
  }
}

static void test_bad_arguments(void **state) {
  (void)state;
  const int n[3] = {2, 2, 2}, zero[3] = {2, 0, 2};
  const bool per[3] = {false, false, false};
  int64_t w[8] = {1, 1, 1, 1, 1, 1, 1, 1};
  int32_t owner[8];
  assert_int_equal(cd_partition_cells(n, per, w, 0, CD_PART_SLAB, 0, owner, NULL), MS_ERR_INPUT);
  assert_int_equal(cd_partition_cells(n, per, w, 2, CD_PART_SLAB, 3, owner, NULL), MS_ERR_INPUT);
  assert_int_equal(cd_partition_cells(zero, per, w, 2, CD_PART_SLAB, 0, owner, NULL), MS_ERR_INPUT);
  w[3] = -1;
  assert_int_equal(cd_partition_cells(n, per, w, 2, CD_PART_METIS, 0, owner, NULL), MS_ERR_INPUT);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_slab_known_weights),    cmocka_unit_test(test_metis_beats_slabs),
      cmocka_unit_test(test_determinism),           cmocka_unit_test(test_periodic_wrap),
      cmocka_unit_test(test_stats_brute_force),     cmocka_unit_test(test_bad_arguments),
      cmocka_unit_test(test_slab_cut_inside_plane), cmocka_unit_test(test_auto_choice),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
