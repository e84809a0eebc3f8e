/* SPDX-License-Identifier: MIT */
/* Fragments: union–find over the cell-list pair search against a brute-force component search
 * (O(n²) adjacency + breadth-first search) on random point sets and constructed cases.
 * The partitions must be identical (same fragment id for every particle: both number fragments
 * by their smallest particle index), hence also the spectra. Tie distances cannot differ
 * between the two: the reference evaluates the same expression (min-image components, squared
 * distance ≤ (b·a)²) in the same floating-point operations. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
/* cmocka needs the headers above */
#include <cmocka.h>

#include "cpl_test.h"
#include "ptl.h"
#include "frag_points.h"

/* ---- helpers ---------------------------------------------------------------------------- */

/* splitmix64 → [0, 1): the outputs of ptl's generator started from the seed rng_seed set */
static uint64_t rng_seed_, rng_k;
static void rng_seed(uint64_t seed) {
  rng_seed_ = seed;
  rng_k = 0;
}
static double urand(void) { return ptl_splitmix64_uniform(rng_seed_, rng_k++); }

typedef frag_points cloud;

static cpl_particles view(const cloud *c, bool use_skip, bool use_z) {
  return frag_points_view(c, use_skip, use_z, false);
}

/* Reference labelling: O(n²) adjacency matrix, BFS from the smallest unvisited index. */
static size_t brute_force(const cpl_particles *p, const cpl_fragment_opts *o, int64_t *id) {
  size_t n = p->n;
  double L = o->bond * o->spacing, L2 = L * L;
  uint8_t *adj = calloc(n * n + 1, 1);
  for (size_t i = 0; i < n; i++)
    for (size_t k = i + 1; k < n; k++) {
      if (p->skip && (p->skip[i] || p->skip[k])) continue;
      double dx = frag_min_image(p->x[k] - p->x[i], o->box.period[0]);
      double dy = frag_min_image(p->y[k] - p->y[i], o->box.period[1]);
      double dz = frag_min_image((p->z ? p->z[k] : 0.0) - (p->z ? p->z[i] : 0.0), o->box.period[2]);
      if (dx * dx + dy * dy + dz * dz <= L2) adj[i * n + k] = adj[k * n + i] = 1;
    }
  size_t *queue = calloc(n + 1, sizeof *queue);
  for (size_t i = 0; i < n; i++) id[i] = -1;
  size_t nfrag = 0;
  for (size_t s = 0; s < n; s++) {
    if (id[s] >= 0 || (p->skip && p->skip[s])) continue;
    size_t head = 0, tail = 0;
    queue[tail++] = s;
    id[s] = (int64_t)nfrag;
    while (head < tail) {
      size_t i = queue[head++];
      for (size_t k = 0; k < n; k++)
        if (adj[i * n + k] && id[k] < 0) {
          id[k] = (int64_t)nfrag;
          queue[tail++] = k;
        }
    }
    nfrag++;
  }
  free(adj);
  free(queue);
  return nfrag;
}

/* Compare the union–find result with the reference: partition, spectrum, fragment masses. */
static void check_against_brute_force(const cpl_particles *p, const cpl_fragment_opts *o) {
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(cpl_fragments_find(&f, p, o), MS_OK);
  int64_t *ref = calloc(p->n + 1, sizeof *ref);
  size_t nref = brute_force(p, o, ref);
  assert_int_equal(f.n, nref);
  for (size_t i = 0; i < p->n; i++) assert_int_equal(f.id[i], ref[i]); /* identical partition */
  /* spectrum from the reference labels */
  int64_t *cnt = calloc(nref + 1, sizeof *cnt);
  double *mass = calloc(nref + 1, sizeof *mass);
  for (size_t i = 0; i < p->n; i++)
    if (ref[i] >= 0) {
      cnt[ref[i]]++;
      mass[ref[i]] += p->mass[i];
    }
  for (size_t k = 0; k < nref; k++) {
    assert_int_equal(f.count[k], cnt[k]);
    /* same particles summed in the same (index) order: identical to the last bit */
    assert_true(f.mass[k] == mass[k]);
  }
  cpl_spectrum s;
  cpl_spectrum_build(&f, &s);
  int64_t total = 0;
  for (size_t r = 0; r < s.n; r++) {
    int64_t c = 0;
    for (size_t k = 0; k < nref; k++) c += cnt[k] == s.g[r];
    assert_int_equal(s.count[r], c);
    total += s.g[r] * s.count[r];
    if (r) assert_true(s.g[r] > s.g[r - 1]);
  }
  size_t active = 0;
  for (size_t i = 0; i < p->n; i++) active += !(p->skip && p->skip[i]);
  assert_int_equal(total, (int64_t)active);
  cpl_spectrum_free(&s);

  /* the CSR entry point with an over-complete candidate list (all pairs within 1.5 b·a, both
   * directions) gives the same partition */
  size_t n = p->n;
  size_t *start = calloc(n + 1, sizeof *start);
  size_t cap = 16, m = 0;
  int32_t *nbr = malloc(cap * sizeof *nbr);
  double R = 1.5 * o->bond * o->spacing;
  for (size_t i = 0; i < n; i++) {
    start[i] = m;
    for (size_t k = 0; k < n; k++) {
      if (k == i) continue;
      double dx = frag_min_image(p->x[k] - p->x[i], o->box.period[0]);
      double dy = frag_min_image(p->y[k] - p->y[i], o->box.period[1]);
      double dz = frag_min_image((p->z ? p->z[k] : 0.0) - (p->z ? p->z[i] : 0.0), o->box.period[2]);
      if (dx * dx + dy * dy + dz * dz <= R * R) {
        if (m == cap) nbr = realloc(nbr, (cap *= 2) * sizeof *nbr);
        nbr[m++] = (int32_t)k;
      }
    }
  }
  start[n] = m;
  cpl_fragments g;
  cpl_fragments_init(&g);
  assert_int_equal(cpl_fragments_find_csr(&g, p, o, start, nbr), MS_OK);
  assert_int_equal(g.n, nref);
  for (size_t i = 0; i < n; i++) assert_int_equal(g.id[i], ref[i]);
  cpl_fragments_free(&g);
  free(start);
  free(nbr);
  free(cnt);
  free(mass);
  free(ref);
  cpl_fragments_free(&f);
}

static cpl_fragment_opts opts(double bond, double a) {
  cpl_fragment_opts o;
  memset(&o, 0, sizeof o);
  o.bond = bond;
  o.spacing = a;
  o.rho0 = 2.7;
  return o;
}

/* ---- union–find itself ------------------------------------------------------------------- */

/* Random unions against naive relabelling (every element carries its set label). */
static void test_union_find(void **state) {
  (void)state;
  rng_seed(7);
  size_t n = 500;
  cpl_uf uf;
  memset(&uf, 0, sizeof uf);
  cpl_uf_init(&uf, n);
  size_t *label = malloc(n * sizeof *label);
  for (size_t i = 0; i < n; i++) label[i] = i;
  for (int step = 0; step < 400; step++) {
    size_t a = (size_t)(urand() * n), b = (size_t)(urand() * n);
    bool merged = cpl_uf_union(&uf, a, b);
    assert_int_equal(merged, label[a] != label[b]);
    if (label[a] != label[b]) {
      size_t from = label[b], to = label[a];
      for (size_t i = 0; i < n; i++)
        if (label[i] == from) label[i] = to;
    }
    if (step % 50 == 0)
      for (size_t i = 0; i < n; i++)
        for (size_t k = i; k < n; k += 37)
          assert_int_equal(cpl_uf_find(&uf, i) == cpl_uf_find(&uf, k), label[i] == label[k]);
  }
  /* set sizes at the roots match the label counts */
  for (size_t i = 0; i < n; i++) {
    size_t c = 0;
    for (size_t k = 0; k < n; k++) c += label[k] == label[i];
    assert_int_equal(uf.size[cpl_uf_find(&uf, i)], c);
  }
  free(label);
  cpl_uf_free(&uf);
}

/* ---- random point sets -------------------------------------------------------------------- */

/* Uniform random points at unit mean spacing; bond lengths below, near and above the
 * percolation range, so the spectra go from all singletons to one giant fragment. */
static void test_random_sets(void **state) {
  (void)state;
  const size_t sizes[] = {0, 1, 2, 37, 400, 2500};
  const double bonds[] = {0.3, 0.7, 0.9, 1.1, 1.6};
  for (int dim = 2; dim <= 3; dim++)
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; si++)
      for (size_t bi = 0; bi < sizeof bonds / sizeof *bonds; bi++) {
        size_t n = sizes[si];
        if (n > 1000 && bi % 2) continue; /* keep the O(n²) reference within seconds */
        rng_seed(1000 * dim + 10 * si + bi);
        cloud c;
        frag_points_alloc(&c, n);
        double side = dim == 3 ? cbrt((double)n) : sqrt((double)n);
        for (size_t i = 0; i < n; i++) {
          c.x[i] = side * urand();
          c.y[i] = side * urand();
          c.z[i] = dim == 3 ? side * urand() : 0.0;
          c.m[i] = 1 + urand();
          c.skip[i] = urand() < 0.05;
        }
        cpl_particles p = view(&c, bi % 2 == 1, dim == 3);
        check_against_brute_force(&p, &(cpl_fragment_opts){.bond = bonds[bi], .spacing = 1.0});
        /* the same with a lattice spacing ≠ 1 (only b·a matters) */
        cpl_fragment_opts o = opts(bonds[bi] / 0.25, 0.25);
        check_against_brute_force(&p, &o);
        frag_points_free(&c);
      }
}

/* Periodic boxes: random points in [lo, lo + P) per periodic axis, including boxes only 2–3
 * bond lengths wide, where the cell stencil wraps onto itself. */
static void test_random_periodic(void **state) {
  (void)state;
  const double bonds[] = {0.6, 0.95, 1.3};
  const double sides[] = {2.7, 4.1, 9.0};
  for (size_t si = 0; si < 3; si++)
    for (size_t bi = 0; bi < 3; bi++)
      for (int mask = 1; mask < 8; mask += 3) { /* periodic axes: x; x,y; x,y,z */
        double side = sides[si];
        if (2 * bonds[bi] >= side) continue;
        size_t n = (size_t)(side * side * side);
        rng_seed(99 + 7 * si + 3 * bi + (uint64_t)mask);
        cloud c;
        frag_points_alloc(&c, n);
        cpl_fragment_opts o = opts(bonds[bi], 1.0);
        int m = mask == 1 ? 1 : mask == 4 ? 3 : 7;
        for (int a = 0; a < 3; a++) {
          o.box.lo[a] = -1.5;
          o.box.period[a] = (m >> a) & 1 ? side : 0.0;
        }
        for (size_t i = 0; i < n; i++) {
          c.x[i] = -1.5 + side * urand();
          c.y[i] = -1.5 + side * urand();
          c.z[i] = -1.5 + side * urand();
          c.m[i] = 1.0;
        }
        cpl_particles p = view(&c, false, true);
        check_against_brute_force(&p, &o);
        frag_points_free(&c);
      }
}

/* Far-flung ejecta: a dense cluster plus particles 10⁶ bond lengths away — the cell grid must
 * coarsen (memory O(n)) and still find every bond. */
static void test_sparse_spread(void **state) {
  (void)state;
  rng_seed(5);
  cloud c;
  frag_points_alloc(&c, 600);
  for (size_t i = 0; i < c.n; i++) {
    double far = i % 50 == 0 ? 1e6 * (1 + urand()) : 0.0;
    c.x[i] = far + 6 * urand();
    c.y[i] = 6 * urand();
    c.z[i] = far * 0.5 + 6 * urand();
    c.m[i] = 1;
  }
  cpl_particles p = view(&c, false, true);
  cpl_fragment_opts o = opts(1.0, 1.0);
  check_against_brute_force(&p, &o);
  frag_points_free(&c);
}

/* ---- constructed cases ------------------------------------------------------------------- */

static size_t find_n(const cloud *c, cpl_fragment_opts o, cpl_fragments *f) {
  cpl_particles p = view(c, true, true);
  assert_int_equal(cpl_fragments_find(f, &p, &o), MS_OK);
  return f->n;
}

/* Chains with spacing a: one fragment at b = 1.01; a gap of 1.5a splits it in two at b < 1.5
 * and not at b > 1.5; at b = 0.99 every particle is alone. Order of particles is shuffled so
 * numbering by smallest index is exercised. */
static void test_chains(void **state) {
  (void)state;
  size_t n = 200;
  cloud c;
  frag_points_alloc(&c, n);
  double a = 3e-4; /* 3 µm */
  for (size_t i = 0; i < n; i++) {
    size_t pos = (i * 73) % n; /* a permutation of 0..n-1 (73 coprime with 200) */
    c.x[i] = a * pos + (pos >= 120 ? 0.5 * a : 0.0);
    c.m[i] = 1e-9;
  }
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(find_n(&c, opts(1.01, a), &f), 2);
  /* particle 0 sits at pos 0, in the first (120-particle) part: fragment 0 */
  assert_int_equal(f.count[0], 120);
  assert_int_equal(f.count[1], 80);
  assert_int_equal(f.first[0], 0);
  assert_int_equal(find_n(&c, opts(1.6, a), &f), 1);
  assert_int_equal(find_n(&c, opts(0.99, a), &f), n);
  for (size_t i = 0; i < n; i++) assert_int_equal(f.id[i], (int64_t)i);
  /* skipping the particle at pos 50 cuts the first part at 50 */
  for (size_t i = 0; i < n; i++) c.skip[i] = (i * 73) % n == 50;
  assert_int_equal(find_n(&c, opts(1.01, a), &f), 3);
  /* numbered by smallest index: index 0 (pos 0) → pos 0..49; index 1 (pos 73) → 51..119 */
  assert_int_equal(f.count[0], 50);
  assert_int_equal(f.count[1], 69);
  assert_int_equal(f.count[2], 80);
  cpl_fragments_free(&f);
  frag_points_free(&c);
}

/* Rings of N points on a circle: chord 2R sin(π/N); bonded when chord ≤ b·a. Several rings
 * in a plane, far apart, give N(g) = one row per ring size. Plus isolated particles. */
static void test_rings_and_isolated(void **state) {
  (void)state;
  const size_t sizes[] = {3, 7, 7, 40};
  size_t niso = 25, n = niso;
  for (size_t r = 0; r < 4; r++) n += sizes[r];
  cloud c;
  frag_points_alloc(&c, n);
  double a = 1.0;
  size_t i = 0;
  for (size_t r = 0; r < 4; r++) {
    size_t N = sizes[r];
    double R = a / (2 * sin(3.14159265358979323846 / N)); /* chord = a */
    for (size_t k = 0; k < N; k++, i++) {
      double th = 2 * 3.14159265358979323846 * k / N;
      c.x[i] = 100.0 * r + R * cos(th);
      c.y[i] = R * sin(th);
      c.z[i] = 0;
      c.m[i] = 2.0;
    }
  }
  for (size_t k = 0; k < niso; k++, i++) {
    c.x[i] = 1000 + 5.0 * k;
    c.y[i] = 50;
    c.m[i] = 1.0;
  }
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(find_n(&c, opts(1.001, a), &f), 4 + niso);
  cpl_spectrum s;
  cpl_spectrum_build(&f, &s);
  assert_int_equal(s.n, 4); /* g = 1, 3, 7, 40 */
  assert_int_equal(s.g[0], 1);
  assert_int_equal(s.count[0], (int64_t)niso);
  assert_true(s.mass[0] == (double)niso);
  assert_int_equal(s.g[1], 3);
  assert_int_equal(s.count[1], 1);
  assert_int_equal(s.g[2], 7);
  assert_int_equal(s.count[2], 2);
  assert_true(s.mass[2] == 28.0);
  assert_int_equal(s.g[3], 40);
  cpl_spectrum_free(&s);
  /* a ring's centre of mass is its centre; radius of gyration R (points on the circle):
   * round-off of a few ulps of the ring size */
  double R40 = a / (2 * sin(3.14159265358979323846 / 40));
  assert_double_equal(f.cx[3], 300.0, 1e-12 * 300);
  assert_double_equal(f.cy[3], 0.0, 1e-12 * R40);
  assert_double_equal(f.rg[3], R40, 1e-12 * R40);
  /* a ring broken below the chord length: all singletons */
  assert_int_equal(find_n(&c, opts(0.999, a), &f), n);
  cpl_fragments_free(&f);
  frag_points_free(&c);
}

/* Periodic wrap: a chain crossing the periodic boundary is one fragment only when the axis
 * is periodic; its centre of mass is computed across the boundary. */
static void test_periodic_wrap(void **state) {
  (void)state;
  cloud c;
  frag_points_alloc(&c, 6);
  double P = 10.0, lo = -2.0;
  /* three particles just below lo + P, three just above lo: a chain through the boundary */
  double xs[6] = {lo + P - 0.25, lo + 0.25, lo + P - 1.25, lo + 1.25, lo + P - 2.25, lo + 2.25};
  for (int i = 0; i < 6; i++) {
    c.x[i] = xs[i];
    c.y[i] = 0.5;
    c.m[i] = 1.0;
    c.vx[i] = i; /* c.o.m. velocity 2.5 */
  }
  cpl_fragments f;
  cpl_fragments_init(&f);
  cpl_fragment_opts o = opts(1.01, 1.0);
  assert_int_equal(find_n(&c, o, &f), 2); /* open: two chains of 3 */
  o.box.lo[0] = lo;
  o.box.period[0] = P;
  assert_int_equal(find_n(&c, o, &f), 1);
  assert_int_equal(f.count[0], 6);
  /* symmetric about the boundary: the centre is lo (≡ lo + P); distance via the minimum image,
   * tolerance: round-off of coordinates of size ~10 */
  double d = f.cx[0] - lo;
  d -= P * nearbyint(d / P);
  assert_true(fabs(d) < 1e-12);
  assert_true(f.cx[0] >= lo && f.cx[0] < lo + P);
  assert_double_equal(f.vx[0], 2.5, 1e-15);
  /* rg of points at ±0.25, ±1.25, ±2.25 about the centre: sqrt(mean of squares) */
  double rg = sqrt((0.0625 + 1.5625 + 5.0625) / 3.0);
  assert_double_equal(f.rg[0], rg, 1e-12);
  /* a bond longer than half the period is refused (minimum image would be ambiguous) */
  cpl_fragment_opts bad = o;
  bad.bond = 5.0;
  cpl_particles p = view(&c, false, true);
  assert_int_equal(cpl_fragments_find(&f, &p, &bad), MS_ERR_INPUT);
  cpl_fragments_free(&f);
  frag_points_free(&c);
}

/* Per-fragment statistics against direct sums over the reference partition (open box). */
static void test_statistics(void **state) {
  (void)state;
  rng_seed(31);
  size_t n = 300;
  cloud c;
  frag_points_alloc(&c, n);
  for (size_t i = 0; i < n; i++) {
    c.x[i] = 8 * urand();
    c.y[i] = 8 * urand();
    c.z[i] = 3 * urand();
    c.vx[i] = urand() - 0.5;
    c.vy[i] = 2 * urand();
    c.vz[i] = -urand();
    c.m[i] = 0.5 + urand();
  }
  cpl_particles p = view(&c, false, true);
  cpl_fragment_opts o = opts(1.0, 1.0);
  o.rho0 = 11.34;
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  for (size_t k = 0; k < f.n; k++) {
    double M = 0, r[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
      if (f.id[i] == (int64_t)k) {
        M += c.m[i];
        r[0] += c.m[i] * c.x[i];
        r[1] += c.m[i] * c.y[i];
        r[2] += c.m[i] * c.z[i];
        v[0] += c.m[i] * c.vx[i];
        v[1] += c.m[i] * c.vy[i];
        v[2] += c.m[i] * c.vz[i];
      }
    for (int a = 0; a < 3; a++) {
      r[a] /= M;
      v[a] /= M;
    }
    double I = 0;
    for (size_t i = 0; i < n; i++)
      if (f.id[i] == (int64_t)k)
        I += c.m[i] * ((c.x[i] - r[0]) * (c.x[i] - r[0]) + (c.y[i] - r[1]) * (c.y[i] - r[1]) +
                       (c.z[i] - r[2]) * (c.z[i] - r[2]));
    /* the library sums relative to the first particle: different rounding, ~1e-15 relative */
    assert_double_equal(f.cx[k], r[0], 1e-13);
    assert_double_equal(f.cy[k], r[1], 1e-13);
    assert_double_equal(f.cz[k], r[2], 1e-13);
    assert_double_equal(f.vx[k], v[0], 1e-13);
    assert_double_equal(f.vy[k], v[1], 1e-13);
    assert_double_equal(f.vz[k], v[2], 1e-13);
    assert_double_equal(f.rg[k], sqrt(I / M), 1e-12);
    /* equivalent diameter: the sphere of density ρ0 with the fragment's mass */
    double d = f.diameter[k];
    assert_double_equal(3.14159265358979323846 / 6 * d * d * d * o.rho0, M, 1e-14 * M);
  }
  cpl_fragments_free(&f);
  frag_points_free(&c);
}

/* Numbering by gid: the same cloud stored in a shuffled order with gid = original index gives
 * the same fragment of every particle and the same table (rows in the same order, sums to
 * round-off) as the unshuffled cloud numbered by index. Open and periodic axes. */
static void test_gid_numbering(void **state) {
  (void)state;
  for (int per = 0; per < 2; per++) {
    const size_t n = 600;
    const double side = 9.0;
    rng_seed(4242 + (uint64_t)per);
    cloud c, s;
    frag_points_alloc(&c, n);
    frag_points_alloc(&s, n);
    cpl_fragment_opts o = opts(0.8, 1.0); /* ~1.8 bonds per particle: below percolation */
    o.rho0 = 2.0;
    for (int a = 0; a < 3 && per; a++) o.box.period[a] = a < 2 ? side : 0.0;
    for (size_t i = 0; i < n; i++) {
      c.x[i] = side * urand();
      c.y[i] = side * urand();
      c.z[i] = side * urand();
      c.vx[i] = urand() - 0.5;
      c.vy[i] = urand() - 0.5;
      c.vz[i] = urand() - 0.5;
      c.m[i] = 0.5 + urand();
      c.skip[i] = urand() < 0.05;
    }
    size_t *perm = calloc(n, sizeof *perm); /* Fisher–Yates */
    int64_t *gid = calloc(n, sizeof *gid);
    for (size_t i = 0; i < n; i++) perm[i] = i;
    for (size_t i = n - 1; i > 0; i--) {
      size_t j = (size_t)(urand() * (double)(i + 1)), t = perm[i];
      perm[i] = perm[j];
      perm[j] = t;
    }
    for (size_t j = 0; j < n; j++) {
      size_t i = perm[j];
      s.x[j] = c.x[i], s.y[j] = c.y[i], s.z[j] = c.z[i];
      s.vx[j] = c.vx[i], s.vy[j] = c.vy[i], s.vz[j] = c.vz[i];
      s.m[j] = c.m[i], s.skip[j] = c.skip[i];
      gid[j] = (int64_t)i;
    }
    cpl_particles pc = view(&c, true, true), ps = view(&s, true, true);
    ps.gid = gid;
    cpl_fragments f, g;
    cpl_fragments_init(&f);
    cpl_fragments_init(&g);
    assert_int_equal(cpl_fragments_find(&f, &pc, &o), MS_OK);
    assert_int_equal(cpl_fragments_find(&g, &ps, &o), MS_OK);
    printf("gid numbering (%s): %zu fragments of %zu particles\n", per ? "periodic" : "open", f.n,
           n);
    assert_true(f.n > 20 && f.n < n / 2); /* a mix of clusters, not all singletons */
    assert_int_equal(g.n, f.n);
    for (size_t j = 0; j < n; j++) assert_int_equal(g.id[j], f.id[perm[j]]);
    /* sums in another order: round-off of a few ulps of the largest term */
    for (size_t k = 0; k < f.n; k++) {
      assert_int_equal(g.count[k], f.count[k]);
      assert_int_equal(g.first[k], f.first[k]);
      assert_double_equal(g.mass[k], f.mass[k], 1e-13 * f.mass[k]);
      assert_double_equal(g.cx[k], f.cx[k], 1e-12 * side);
      assert_double_equal(g.cy[k], f.cy[k], 1e-12 * side);
      assert_double_equal(g.cz[k], f.cz[k], 1e-12 * side);
      assert_double_equal(g.vx[k], f.vx[k], 1e-12);
      assert_double_equal(g.rg[k], f.rg[k], 1e-12 * side);
      assert_double_equal(g.diameter[k], f.diameter[k], 1e-13 * f.diameter[k]);
    }
    cpl_fragments_free(&f);
    cpl_fragments_free(&g);
    free(perm);
    free(gid);
    frag_points_free(&c);
    frag_points_free(&s);
  }
}

/* Bad input: non-finite positions, bad options. */
static void test_bad_input(void **state) {
  (void)state;
  cloud c;
  frag_points_alloc(&c, 3);
  for (int i = 0; i < 3; i++) c.m[i] = 1;
  c.x[1] = NAN;
  cpl_particles p = view(&c, false, true);
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(cpl_fragments_find(&f, &p, &(cpl_fragment_opts){.bond = 1, .spacing = 1}),
                   MS_ERR_INPUT);
  c.skip[1] = 1; /* a skipped particle may hold anything */
  p = view(&c, true, true);
  assert_int_equal(cpl_fragments_find(&f, &p, &(cpl_fragment_opts){.bond = 1, .spacing = 1}),
                   MS_OK);
  assert_int_equal(f.id[1], -1);
  assert_int_equal(cpl_fragments_find(&f, &p, &(cpl_fragment_opts){.bond = 0, .spacing = 1}),
                   MS_ERR_INPUT);
  cpl_fragments_free(&f);
  frag_points_free(&c);
}

/* ---- outputs ------------------------------------------------------------------------------ */

static char *slurp(FILE *f) {
  fflush(f);
  long len = ftell(f);
  rewind(f);
  char *s = calloc((size_t)len + 1, 1);
  assert_int_equal(fread(s, 1, (size_t)len, f), (size_t)len);
  return s;
}

/* The CSV files: header exactly `g,count,mass` after '#' comment lines with units; the rows
 * reproduce the spectrum; cumulative, histogram and ejecta tables add up to the totals. */
static void test_csv_outputs(void **state) {
  (void)state;
  cloud c;
  frag_points_alloc(&c, 10);
  /* fragments: {0,1,2} at x≈0 (bulk, at rest), {3,4} at x≈10, singles 5..9 further out */
  double xs[10] = {0, 1, 2, 10, 11, 20, 30, 40, 50, 60};
  for (int i = 0; i < 10; i++) {
    c.x[i] = xs[i];
    c.m[i] = 1.0;
    c.vx[i] = xs[i] / 10; /* faster further out */
  }
  cpl_particles p = view(&c, false, true);
  cpl_fragment_opts o = opts(1.05, 1.0);
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  assert_int_equal(f.n, 7);

  FILE *t = tmpfile();
  cpl_write_spectrum(t, &f, NULL);
  char *s = slurp(t);
  fclose(t);
  const char *body = s;
  while (*body == '#') body = strchr(body, '\n') + 1; /* skip comment lines */
  assert_non_null(strstr(s, "# units: g [clusters], count [fragments], mass [g]"));
  assert_string_equal(body, "g,count,mass\n1,5,5\n2,1,2\n3,1,3\n");
  free(s);

  t = tmpfile();
  cpl_write_cumulative(t, &f, NULL);
  s = slurp(t);
  fclose(t);
  assert_non_null(strstr(s, "mass,N_ge,M_ge\n3,1,3\n2,2,5\n1,7,10\n"));
  free(s);

  /* ejecta: all but the largest fragment; cumulative mass by velocity, fastest first */
  cpl_ejecta_sel sel;
  cpl_ejecta_sel_default(&sel);
  assert_double_equal(cpl_ejected_mass(&f, &sel), 7.0, 0);
  t = tmpfile();
  cpl_write_ejecta_velocity(t, &f, &sel, NULL);
  s = slurp(t);
  fclose(t);
  assert_non_null(strstr(s, "v,M_ge\n6,1\n5,2\n4,3\n3,4\n2,5\n1.05,7\n"));
  free(s);
  sel.plane = 25; /* only fragments beyond x = 25 */
  assert_double_equal(cpl_ejected_mass(&f, &sel), 4.0, 0);

  t = tmpfile();
  cpl_write_histogram(t, &f, CPL_HIST_MASS, 3, NULL);
  s = slurp(t);
  fclose(t);
  /* bins over [1, 3] in log: the counts add to 7 fragments and the masses to 10 g */
  double sumc = 0, summ = 0;
  const char *line = strstr(s, "lo,hi,count,mass\n");
  assert_non_null(line);
  line = strchr(line, '\n') + 1;
  for (int b = 0; b < 3; b++) {
    double lo, hi, cn, ms;
    assert_int_equal(sscanf(line, "%lg,%lg,%lg,%lg", &lo, &hi, &cn, &ms), 4);
    sumc += cn;
    summ += ms;
    line = strchr(line, '\n') + 1;
  }
  assert_double_equal(sumc, 7, 0);
  assert_double_equal(summ, 10, 0);
  free(s);

  t = tmpfile();
  cpl_write_fragment_table(t, &f, NULL);
  s = slurp(t);
  fclose(t);
  assert_non_null(strstr(s, "id,count,mass,d,x,y,z,vx,vy,vz,rg\n0,3,3,"));
  free(s);
  cpl_fragments_free(&f);
  frag_points_free(&c);
}

/* The jets / spall layers / debris split (cpl_ejecta_classify, docs/coupling.md §9 "The split")
 * on a built configuration whose answer is known by construction: a square lattice a = 1,
 * periodic width 10 (10 lateral bins), unit masses, drive axis x:
 *   x = 0.5      one lone particle at the piston (a failed particle: not the bulk, debris);
 *   x = 2..4     the bulk plate, 3 rows × 10 (the deepest full-width fragment);
 *   x = 6        a 2-particle piece below the layer (debris);
 *   x = 8, 9     a spalled layer, 2 rows × 10, with a jet of 3 particles rooted in it at
 *                y = 4.5, x = 10..12 (level = the median front 9 + one spacing: the particles
 *                at 11 and 12 are jets, the other 21 layer);
 *   x = 15       a detached jet tip, 1 particle, vx = 3 (everything else vx = 1).
 * Masses are sums of unit masses (exact). Then the same without the plates: no full-width
 * fragment, no bulk, every particle debris. */
static void test_ejecta_split(void **state) {
  (void)state;
  frag_points c;
  frag_points_alloc(&c, 1 + 30 + 2 + 23 + 1);
  size_t n = 0;
#define PUT(px, py, pv) (c.x[n] = (px), c.y[n] = (py), c.vx[n] = (pv), c.m[n] = 1.0, n++)
  PUT(0.5, 0.5, 1.0);
  for (int row = 2; row <= 4; row++)
    for (int j = 0; j < 10; j++) PUT(row, j + 0.5, 1.0);
  PUT(6.0, 2.5, 1.0);
  PUT(6.0, 3.5, 1.0);
  for (int row = 8; row <= 9; row++)
    for (int j = 0; j < 10; j++) PUT(row, j + 0.5, 1.0);
  for (int row = 10; row <= 12; row++) PUT(row, 4.5, 1.0);
  PUT(15.0, 4.5, 3.0);
#undef PUT
  assert_int_equal(n, c.n);
  cpl_fragments f;
  cpl_fragments_init(&f);
  cpl_fragment_opts o = opts(1.01, 1.0);
  o.box.period[1] = 10.0;
  cpl_particles p = view(&c, false, false);
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  assert_int_equal(f.n, 5);
  cpl_split_opts so;
  cpl_split_opts_default(&so, &o, 2.0);
  cpl_ejecta_classes k;
  cpl_ejecta_classify(&f, &p, &so, NULL, &k);
  assert_int_equal(f.count[k.bulk], 30);
  assert_double_equal(k.m_bulk, 30.0, 0.0);
  assert_double_equal(k.level, 10.0, 0.0);
  assert_double_equal(k.m_jet, 3.0, 0.0);
  assert_double_equal(k.m_layer, 21.0, 0.0);
  assert_double_equal(k.m_debris, 3.0, 0.0);
  assert_int_equal(k.n_layer, 1);
  assert_int_equal(k.n_jet, 1);
  assert_int_equal(k.n_debris, 2);
  assert_double_equal(k.m_fast, 1.0, 0.0); /* the tip alone is faster than v_fast = 2 */
  assert_int_equal(k.n_fast, 1);
  assert_double_equal(k.v_max, 3.0, 0.0);
  /* the lone particle 7 spacings below the plate (more than reach = 2): a failed zone beneath
   * it, so the plate has come off the piston: no bulk, the plate is a layer */
  c.x[0] = -5.0;
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  cpl_ejecta_classify(&f, &p, &so, NULL, &k);
  assert_true(k.bulk == SIZE_MAX);
  assert_double_equal(k.level, 10.0, 0.0);
  assert_double_equal(k.m_layer, 51.0, 0.0);
  assert_int_equal(k.n_layer, 2);
  assert_double_equal(k.m_jet, 3.0, 0.0);
  c.x[0] = 0.5;
  /* a torn layer (one of its 10 bins emptied: 9 of 10 = 90 %) is still full-width; two emptied
   * bins make it a piece: the level falls to the bulk's front 4 + 1, and every detached particle
   * beyond it — the torn layer, its jet, the tip and the piece at x = 6 — is ahead */
  for (size_t i = 0; i < c.n; i++)
    if ((c.x[i] == 8.0 || c.x[i] == 9.0) && c.y[i] == 0.5) c.x[i] = 30.0 + c.x[i];
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  cpl_ejecta_classify(&f, &p, &so, NULL, &k);
  assert_int_equal(k.n_layer, 1);
  assert_double_equal(k.m_layer, 19.0, 0.0);
  for (size_t i = 0; i < c.n; i++)
    if ((c.x[i] == 8.0 || c.x[i] == 9.0) && c.y[i] == 1.5) c.x[i] = 50.0 + c.x[i];
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  cpl_ejecta_classify(&f, &p, &so, NULL, &k);
  assert_int_equal(k.n_layer, 0);
  assert_double_equal(k.level, 5.0, 0.0);
  assert_double_equal(k.m_layer, 0.0, 0.0);
  assert_double_equal(k.m_bulk, 30.0, 0.0);
  assert_double_equal(k.m_jet, 26.0, 0.0);
  assert_double_equal(k.m_debris, 1.0, 0.0); /* the lone particle at the piston */
  /* no full-width fragment at all: no bulk, no level, everything debris */
  c.n = 3; /* the lone particle and the piece, moved to indices 1, 2 */
  c.x[1] = 6.0, c.y[1] = 2.5, c.x[2] = 6.0, c.y[2] = 3.5;
  p = view(&c, false, false);
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  cpl_ejecta_classify(&f, &p, &so, NULL, &k);
  assert_true(k.bulk == SIZE_MAX && isnan(k.level));
  assert_double_equal(k.m_debris, 3.0, 0.0);
  assert_double_equal(k.m_jet + k.m_layer + k.m_bulk, 0.0, 0.0);
  cpl_fragments_free(&f);
  c.n = 57;
  frag_points_free(&c);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_union_find),      cmocka_unit_test(test_random_sets),
      cmocka_unit_test(test_random_periodic), cmocka_unit_test(test_sparse_spread),
      cmocka_unit_test(test_chains),          cmocka_unit_test(test_rings_and_isolated),
      cmocka_unit_test(test_periodic_wrap),   cmocka_unit_test(test_statistics),
      cmocka_unit_test(test_bad_input),       cmocka_unit_test(test_csv_outputs),
      cmocka_unit_test(test_gid_numbering),   cmocka_unit_test(test_ejecta_split),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
