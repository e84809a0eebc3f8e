/* SPDX-License-Identifier: MIT */
/* Distributed fragments (coupling/fragments_dist.c) against the serial finder: every rank builds
 * the same global particle sets, the serial cpl_fragments_find on all of them (gid = global
 * index) is the reference, then each rank keeps its share — by x slabs with ghosts exactly the
 * particles within b·a of its own, and by a METIS map of coarse cells (cd_partition_cells)
 * with the whole adjacent cell layer as ghosts — stored in a shuffled order, ghosts on periodic
 * axes shifted by a period. cpl_fragments_find_dist must give every owned particle the
 * reference fragment id, the same table (count, smallest gid exactly; mass, centre, velocity,
 * radius of gyration, diameter to 1e-12 relative: the same sums in another order) and the same
 * spectrum. Sets: random points (open and periodic, some particles skipped), a serpentine
 * chain crossing every rank boundary many times with shuffled gids, rings, a chain closed
 * through a periodic boundary. Bad input must fail on every rank. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cpl.h"
#include "cd.h"
#include "frag_points.h"
#include "mpi_check.h"

static ms_ctx ctx;
static const double PI = 3.14159265358979323846;

/* ---- global particle sets (identical on every rank) ---- */
typedef struct gset {
  const char *name;
  frag_points p; /* gid = global index until a set shuffles them */
  cpl_fragment_opts o;
  double lo[3], ext[3]; /* region for the decompositions */
} gset;

static uint64_t rng_k;
static double urand(void) { return ptl_splitmix64_uniform(2026, rng_k++); }

/* n points at the origin with random velocities and masses */
static void gset_alloc(gset *g, const char *name, size_t n) {
  memset(g, 0, sizeof *g);
  g->name = name;
  frag_points_alloc(&g->p, n);
  for (size_t i = 0; i < n; ++i) {
    g->p.vx[i] = urand() - 0.5;
    g->p.vy[i] = urand() - 0.5;
    g->p.vz[i] = urand() - 0.5;
    g->p.m[i] = 0.5 + urand();
  }
}

/* Random points in a box of side `side` (bond 0.85: clusters of all sizes below percolation);
 * periodic in x and y if `periodic`; 3 % skipped. */
static void make_random(gset *g, bool periodic) {
  const double side = 10.0;
  gset_alloc(g, periodic ? "random periodic" : "random open", 1400);
  g->o = (cpl_fragment_opts){.bond = 0.85, .spacing = 1.0, .rho0 = 2.7};
  for (size_t i = 0; i < g->p.n; ++i) {
    g->p.x[i] = side * urand();
    g->p.y[i] = side * urand();
    g->p.z[i] = side * urand();
    g->p.skip[i] = urand() < 0.03;
  }
  for (int a = 0; a < 3; ++a) {
    g->lo[a] = 0;
    g->ext[a] = side;
    if (periodic && a < 2) g->o.box.period[a] = side;
  }
}

/* Open box: a serpentine chain (8 runs along x joined by short steps in y, spacing 0.9 b·a),
 * 6 rings in the x–y plane of different radii, 200 isolated points far apart in z. The chain's
 * and rings' gids are a random permutation, so the smallest gid of a fragment sits anywhere. */
static void make_chains(gset *g) {
  const double L = 1.0, step = 0.9 * L, side = 40.0;
  size_t nrun = (size_t)(side / step), nchain = 8 * nrun + 7 * 3;
  size_t nring = 0;
  const double radii[6] = {3, 5, 7, 9, 12, 15};
  for (int k = 0; k < 6; ++k) nring += (size_t)ceil(2 * PI * radii[k] / step);
  gset_alloc(g, "chains and rings", nchain + nring + 200);
  g->o = (cpl_fragment_opts){.bond = 1.0, .spacing = L, .rho0 = 1.0};
  size_t i = 0;
  double y = 0;
  for (int run = 0; run < 8; ++run) {
    for (size_t k = 0; k < nrun; ++k, ++i) {
      /* each run starts where the last ended */
      g->p.x[i] = (double)(run % 2 ? nrun - 1 - k : k) * step;
      g->p.y[i] = y;
      g->p.z[i] = 0;
    }
    if (run < 7)
      for (int k = 1; k <= 3; ++k, ++i) { /* three steps up at the turn */
        g->p.x[i] = g->p.x[i - 1];
        g->p.y[i] = y + k * step;
      }
    y += 4 * step;
  }
  for (int r = 0; r < 6; ++r) {
    size_t nk = (size_t)ceil(2 * PI * radii[r] / step);
    for (size_t k = 0; k < nk; ++k, ++i) { /* chord 2R sin(π/nk) ≤ step */
      double th = 2 * PI * (double)k / (double)nk;
      g->p.x[i] = side / 2 + radii[r] * cos(th);
      g->p.y[i] = side / 2 + radii[r] * sin(th);
      g->p.z[i] = 5.0 + 3.0 * r;
    }
  }
  for (size_t k = 0; k < 200; ++k, ++i) { /* a grid of isolated points, 2 apart */
    g->p.x[i] = 2.0 * (double)(k % 20);
    g->p.y[i] = 2.0 * (double)(k / 20 % 10);
    g->p.z[i] = 30.0;
  }
  /* shuffled gids (Fisher–Yates) */
  for (size_t k = g->p.n - 1; k > 0; --k) {
    size_t j = (size_t)(urand() * (double)(k + 1));
    int64_t t = g->p.gid[k];
    g->p.gid[k] = g->p.gid[j];
    g->p.gid[j] = t;
  }
  for (int a = 0; a < 3; ++a) {
    g->lo[a] = -1;
    g->ext[a] = side + 2;
  }
}

/* A chain along x closed through the periodic boundary (one ring through the whole period)
 * with a blob of 60 particles on it near x = 5 (a fragment spanning a period evenly has no
 * defined centre: the circular mean of its positions is round-off; the blob defines it), a
 * second open chain beside it, and clusters spread over the box. Periodic in x. */
static void make_periodic_ring(gset *g) {
  const double side = 30.0, step = 0.75;
  size_t nr = (size_t)(side / step);
  gset_alloc(g, "periodic ring", 2 * nr + 300);
  g->o = (cpl_fragment_opts){.bond = 1.0, .spacing = 1.0, .rho0 = 1.0};
  g->o.box.period[0] = side;
  size_t i = 0;
  for (size_t k = 0; k < nr; ++k, ++i) { /* closes: last to first is step through the wrap */
    g->p.x[i] = (double)k * step;
    g->p.y[i] = 2;
    g->p.z[i] = 2;
  }
  for (size_t k = 0; k + 1 < nr; ++k, ++i) { /* gap of 2 steps at the wrap: not closed */
    g->p.x[i] = 0.5 * step + (double)k * step;
    g->p.y[i] = 6;
    g->p.z[i] = 2;
  }
  for (size_t k = 0; k < 60; ++k, ++i) { /* within 0.8 of (5, 2, 2): bonded to the ring */
    double r = 0.8 * cbrt(urand()), th = acos(2 * urand() - 1), ph = 2 * PI * urand();
    g->p.x[i] = 5 + r * sin(th) * cos(ph);
    g->p.y[i] = 2 + r * sin(th) * sin(ph);
    g->p.z[i] = 2 + r * cos(th);
  }
  for (; i < g->p.n; ++i) {
    g->p.x[i] = side * urand();
    g->p.y[i] = 10 + 8 * urand();
    g->p.z[i] = 8 * urand();
  }
  for (size_t k = g->p.n - 1; k > 0; --k) {
    size_t j = (size_t)(urand() * (double)(k + 1));
    int64_t t = g->p.gid[k];
    g->p.gid[k] = g->p.gid[j];
    g->p.gid[j] = t;
  }
  g->lo[0] = 0, g->ext[0] = side;
  g->lo[1] = 0, g->ext[1] = 20;
  g->lo[2] = 0, g->ext[2] = 10;
}

/* ---- decompositions ---- */

static bool within(const gset *g, size_t i, size_t k, double L) {
  double dx = frag_min_image(g->p.x[k] - g->p.x[i], g->o.box.period[0]);
  double dy = frag_min_image(g->p.y[k] - g->p.y[i], g->o.box.period[1]);
  double dz = frag_min_image(g->p.z[k] - g->p.z[i], g->o.box.period[2]);
  return dx * dx + dy * dy + dz * dz <= L * L;
}

/* Coarse cells of width ≥ b·a over the region (periodic axes: over the period). */
typedef struct cells {
  int nc[3];
  bool per[3];
  size_t *of; /* cell of each particle */
} cells;

static void cells_build(const gset *g, cells *c) {
  double L = g->o.bond * g->o.spacing;
  for (int a = 0; a < 3; ++a) {
    c->nc[a] = (int)floor(g->ext[a] / L);
    if (c->nc[a] < 1) c->nc[a] = 1;
    c->per[a] = g->o.box.period[a] > 0;
  }
  c->of = ms_calloc(g->p.n, sizeof *c->of);
  const double *pos[3] = {g->p.x, g->p.y, g->p.z};
  for (size_t i = 0; i < g->p.n; ++i) {
    int q[3];
    for (int a = 0; a < 3; ++a) {
      double s = (pos[a][i] - g->lo[a]) / g->ext[a] * c->nc[a];
      if (c->per[a]) s -= c->nc[a] * floor(s / c->nc[a]);
      q[a] = (int)s;
      q[a] = q[a] < 0 ? 0 : q[a] >= c->nc[a] ? c->nc[a] - 1 : q[a];
    }
    c->of[i] = (size_t)q[0] + (size_t)c->nc[0] * ((size_t)q[1] + (size_t)c->nc[1] * (size_t)q[2]);
  }
}

/* Mark cell b and its 26 neighbours (periodic axes wrapped). */
static void mark_neighbourhood(const cells *c, size_t b, uint8_t *mark) {
  int ib[3] = {(int)(b % (size_t)c->nc[0]), (int)(b / (size_t)c->nc[0] % (size_t)c->nc[1]),
               (int)(b / (size_t)c->nc[0] / (size_t)c->nc[1])};
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        int q[3] = {ib[0] + dx, ib[1] + dy, ib[2] + dz};
        bool ok = true;
        for (int k = 0; k < 3; ++k) {
          if (q[k] >= 0 && q[k] < c->nc[k]) continue;
          if (c->per[k]) q[k] = (q[k] + c->nc[k]) % c->nc[k];
          else ok = false;
        }
        if (ok)
          mark[(size_t)q[0] + (size_t)c->nc[0] * ((size_t)q[1] + (size_t)c->nc[1] * (size_t)q[2])] =
              1;
      }
}

typedef enum { SLABS = 0, METIS_CELLS } decomp;

/* Owner of every particle, and whether particle i is a ghost on this rank. */
static void decompose(const gset *g, decomp how, int32_t *owner, uint8_t *ghost) {
  const int P = ctx.size, me = ctx.rank;
  double L = g->o.bond * g->o.spacing;
  memset(ghost, 0, g->p.n);
  if (how == SLABS) {
    for (size_t i = 0; i < g->p.n; ++i) {
      double s = (g->p.x[i] - g->lo[0]) / g->ext[0];
      if (g->o.box.period[0] > 0) s -= floor(s);
      int r = (int)(s * P);
      owner[i] = r < 0 ? 0 : r >= P ? P - 1 : r;
    }
    /* ghosts: exactly the particles within b·a of an owned one (the minimum the finder needs) */
    for (size_t k = 0; k < g->p.n; ++k) {
      if (owner[k] == me) continue;
      for (size_t i = 0; i < g->p.n && !ghost[k]; ++i)
        if (owner[i] == me && within(g, i, k, L)) ghost[k] = 1;
    }
    return;
  }
  cells c;
  cells_build(g, &c);
  size_t nv = (size_t)c.nc[0] * (size_t)c.nc[1] * (size_t)c.nc[2];
  int64_t *w = ms_calloc(nv, sizeof *w);
  int32_t *cown = ms_calloc(nv, sizeof *cown);
  for (size_t i = 0; i < g->p.n; ++i) w[c.of[i]]++;
  CHECK(cd_partition_cells(c.nc, c.per, w, P, CD_PART_METIS, 0, cown, NULL) == MS_OK, "METIS");
  for (size_t i = 0; i < g->p.n; ++i) owner[i] = cown[c.of[i]];
  /* ghosts: every particle of the cells adjacent to the rank's cells (a CD halo layer) */
  uint8_t *near = ms_calloc(nv, 1);
  for (size_t b = 0; b < nv; ++b)
    if (cown[b] == me) mark_neighbourhood(&c, b, near);
  for (size_t i = 0; i < g->p.n; ++i) ghost[i] = owner[i] != me && near[c.of[i]];
  free(w);
  free(cown);
  free(near);
  free(c.of);
}

/* ---- one comparison ---- */
static bool close_rel(double a, double b, double scale) {
  return fabs(a - b) <= 1e-12 * fmax(fabs(b), scale) || (isnan(a) && isnan(b));
}

static void run_case(const gset *g, decomp how) {
  const int me = ctx.rank;
  const char *dname = how == SLABS ? "x slabs" : "METIS cells";
  /* serial reference on all particles */
  cpl_particles pg = frag_points_view(&g->p, true, true, true);
  cpl_fragments ref;
  cpl_fragments_init(&ref);
  CHECK(cpl_fragments_find(&ref, &pg, &g->o) == MS_OK, "serial");

  int32_t *owner = ms_calloc(g->p.n, sizeof *owner);
  uint8_t *ghost = ms_calloc(g->p.n, 1);
  decompose(g, how, owner, ghost);
  /* local arrays: owned in a shuffled order, then ghosts (periodic axes shifted by a period) */
  size_t no = 0, ngh = 0;
  for (size_t i = 0; i < g->p.n; ++i) no += owner[i] == me, ngh += ghost[i];
  size_t nl = no + ngh;
  size_t *src = ms_calloc(nl + 1, sizeof *src);
  size_t a = 0, b = no;
  for (size_t i = 0; i < g->p.n; ++i) {
    if (owner[i] == me) src[a++] = i;
    else if (ghost[i]) src[b++] = i;
  }
  for (size_t k = no > 0 ? no - 1 : 0; k > 0; --k) { /* the same shuffle on every rank count */
    size_t j = (size_t)(ptl_splitmix64_uniform(77, src[k]) * (double)(k + 1)), t = src[k];
    src[k] = src[j];
    src[j] = t;
  }
  frag_points loc; /* this rank's arrays */
  frag_points_alloc(&loc, nl);
  double *x = loc.x, *y = loc.y, *z = loc.z, *vx = loc.vx, *vy = loc.vy, *vz = loc.vz, *m = loc.m;
  uint8_t *skip = loc.skip;
  int64_t *gid = loc.gid;
  int32_t *gown = ms_calloc(ngh + 1, sizeof *gown);
  for (size_t l = 0; l < nl; ++l) {
    size_t i = src[l];
    x[l] = g->p.x[i], y[l] = g->p.y[i], z[l] = g->p.z[i];
    if (l >= no) { /* ghosts: positions only; an image position on periodic axes */
      const double *per = g->o.box.period;
      x[l] += per[0] * (x[l] < g->lo[0] + 0.5 * per[0] ? 1 : -1);
      y[l] += per[1] * (y[l] < g->lo[1] + 0.5 * per[1] ? 1 : -1);
      vx[l] = vy[l] = vz[l] = m[l] = NAN; /* must not be read */
      gown[l - no] = owner[i];
    } else {
      vx[l] = g->p.vx[i], vy[l] = g->p.vy[i], vz[l] = g->p.vz[i], m[l] = g->p.m[i];
    }
    skip[l] = g->p.skip[i];
    gid[l] = g->p.gid[i];
  }
  cpl_particles pl = frag_points_view(&loc, true, true, true);
  cpl_fragments f;
  cpl_fragments_init(&f);
  ms_status st = cpl_fragments_find_dist(&f, &pl, no, gown, &g->o, &ctx);
  CHECK(st == MS_OK, "%s / %s: status %d", g->name, dname, (int)st);
  if (st == MS_OK) {
    if (me == 0)
      printf("%-18s %-12s np %d: %zu particles, %zu fragments, %d label rounds\n", g->name, dname,
             ctx.size, g->p.n, f.n, f.rounds);
    CHECK(f.n == ref.n && f.n_particles == no, "%s / %s: %zu fragments, serial %zu", g->name, dname,
          f.n, ref.n);
    /* ids: the reference labels the global particle index (gid is a permutation of it there) */
    for (size_t l = 0; l < no; ++l)
      CHECK(f.id[l] == ref.id[src[l]], "%s / %s: particle gid %lld: id %lld, serial %lld", g->name,
            dname, (long long)gid[l], (long long)f.id[l], (long long)ref.id[src[l]]);
    double side = fmax(g->ext[0], fmax(g->ext[1], g->ext[2]));
    for (size_t k = 0; k < f.n && f.n == ref.n; ++k) {
      CHECK(f.count[k] == ref.count[k] && f.first[k] == ref.first[k], "%s: fragment %zu count",
            g->name, k);
      bool ok = close_rel(f.mass[k], ref.mass[k], 0) && close_rel(f.cx[k], ref.cx[k], side) &&
                close_rel(f.cy[k], ref.cy[k], side) && close_rel(f.cz[k], ref.cz[k], side) &&
                close_rel(f.vx[k], ref.vx[k], 1) && close_rel(f.vy[k], ref.vy[k], 1) &&
                close_rel(f.vz[k], ref.vz[k], 1) && close_rel(f.rg[k], ref.rg[k], side) &&
                close_rel(f.diameter[k], ref.diameter[k], 0);
      CHECK(ok,
            "%s / %s: fragment %zu table differs (mass %.17g/%.17g cx %.17g/%.17g rg %.17g/%.17g)",
            g->name, dname, k, f.mass[k], ref.mass[k], f.cx[k], ref.cx[k], f.rg[k], ref.rg[k]);
    }
    cpl_spectrum s1 = {0}, s2 = {0};
    cpl_spectrum_build(&f, &s1);
    cpl_spectrum_build(&ref, &s2);
    CHECK(s1.n == s2.n, "%s: spectrum rows", g->name);
    for (size_t k = 0; k < s1.n && s1.n == s2.n; ++k)
      CHECK(s1.g[k] == s2.g[k] && s1.count[k] == s2.count[k] &&
                close_rel(s1.mass[k], s2.mass[k], 0),
            "%s: spectrum row %zu", g->name, k);
    cpl_spectrum_free(&s1);
    cpl_spectrum_free(&s2);
  }
  /* bad input fails on every rank: one rank names a ghost's owner wrongly (itself) */
  if (ctx.size > 1) {
    int32_t *bad = ms_calloc(ngh + 1, sizeof *bad);
    memcpy(bad, gown, ngh * sizeof *bad);
    if (me == ctx.size - 1 && ngh > 0) bad[0] = me;
    bool any = par_max_int(me == ctx.size - 1 && ngh > 0) != 0;
    st = cpl_fragments_find_dist(&f, &pl, no, bad, &g->o, &ctx);
    CHECK(!any || st == MS_ERR_INPUT, "%s: a bad ghost owner must fail everywhere", g->name);
    free(bad);
  }
  cpl_fragments_free(&f);
  cpl_fragments_free(&ref);
  free(owner);
  free(ghost);
  free(src);
  frag_points_free(&loc);
  free(gown);
}

int main(int argc, char **argv) {
  ms_ctx_init_serial(&ctx);
  if (par_init(&argc, &argv, &ctx)) return 1;
  gset sets[4];
  make_random(&sets[0], false);
  make_random(&sets[1], true);
  make_chains(&sets[2]);
  make_periodic_ring(&sets[3]);
  for (int s = 0; s < 4; ++s) {
    run_case(&sets[s], SLABS);
    run_case(&sets[s], METIS_CELLS);
    frag_points_free(&sets[s].p);
  }
  int total = (int)par_sum_long(failures);
  if (ctx.rank == 0)
    printf("%s: %d failure(s) on %d rank(s)\n", total ? "FAILED" : "passed", total, ctx.size);
  par_finalize();
  return total ? 1 : 0;
}
