/* SPDX-License-Identifier: MIT */
/* Fragments: bonds |r_i − r_k| ≤ b·a ([Davydov] §4.2, docs/design.md §6), connected components by
 * union–find, per-fragment statistics. docs/coupling.md describes the algorithm. */
#define _GNU_SOURCE /* qsort_r */
#include "cpl_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------- */
/* Union–find                                                                                */

void cpl_uf_init(cpl_uf *uf, size_t n) {
  if (uf->n < n || !uf->parent) {
    free(uf->parent);
    free(uf->size);
    uf->parent = ms_calloc(n ? n : 1, sizeof *uf->parent);
    uf->size = ms_calloc(n ? n : 1, sizeof *uf->size);
  }
  uf->n = n;
  for (size_t i = 0; i < n; i++) {
    uf->parent[i] = i;
    uf->size[i] = 1;
  }
}

void cpl_uf_free(cpl_uf *uf) {
  free(uf->parent);
  free(uf->size);
  memset(uf, 0, sizeof *uf);
}

size_t cpl_uf_find(cpl_uf *uf, size_t i) {
  size_t root = i;
  while (uf->parent[root] != root) root = uf->parent[root];
  /* path compression: every node on the path points at the root */
  while (uf->parent[i] != root) {
    size_t next = uf->parent[i];
    uf->parent[i] = root;
    i = next;
  }
  return root;
}

bool cpl_uf_union(cpl_uf *uf, size_t i, size_t k) {
  size_t a = cpl_uf_find(uf, i), b = cpl_uf_find(uf, k);
  if (a == b) return false;
  /* union by size keeps the trees O(log n) deep even before compression */
  if (uf->size[a] < uf->size[b]) {
    size_t t = a;
    a = b;
    b = t;
  }
  uf->parent[b] = a;
  uf->size[a] += uf->size[b];
  return true;
}

/* ---------------------------------------------------------------------------------------- */
/* Storage                                                                                   */

void cpl_fragments_init(cpl_fragments *f) { memset(f, 0, sizeof *f); }

static void free_fragment_arrays(cpl_fragments *f) {
  free(f->first);
  free(f->count);
  free(f->mass);
  free(f->diameter);
  free(f->cx);
  free(f->cy);
  free(f->cz);
  free(f->vx);
  free(f->vy);
  free(f->vz);
  free(f->rg);
  free(f->work);
}

void cpl_fragments_free(cpl_fragments *f) {
  if (!f) return;
  free(f->id);
  free_fragment_arrays(f);
  free(f->cell_of);
  free(f->cell_start);
  free(f->cell_items);
  free(f->key);
  cpl_uf_free(&f->uf);
  memset(f, 0, sizeof *f);
}

static void reserve_particles(cpl_fragments *f, size_t n) {
  if (f->cap_particles >= n && f->id) return;
  size_t cap = n ? n : 1;
  free(f->id);
  free(f->cell_of);
  free(f->cell_items);
  free(f->key);
  f->id = ms_calloc(cap, sizeof *f->id);
  f->key = ms_calloc(cap, sizeof *f->key);
  f->cell_of = ms_calloc(cap, sizeof *f->cell_of);
  f->cell_items = ms_calloc(cap, sizeof *f->cell_items);
  f->cap_particles = cap;
}

static void reserve_fragments(cpl_fragments *f, size_t n) {
  if (f->cap_fragments >= n && f->count) return;
  size_t cap = n ? n : 1;
  free_fragment_arrays(f);
  f->first = ms_calloc(cap, sizeof *f->first);
  f->count = ms_calloc(cap, sizeof *f->count);
  f->mass = ms_calloc(cap, sizeof *f->mass);
  f->diameter = ms_calloc(cap, sizeof *f->diameter);
  f->cx = ms_calloc(cap, sizeof *f->cx);
  f->cy = ms_calloc(cap, sizeof *f->cy);
  f->cz = ms_calloc(cap, sizeof *f->cz);
  f->vx = ms_calloc(cap, sizeof *f->vx);
  f->vy = ms_calloc(cap, sizeof *f->vy);
  f->vz = ms_calloc(cap, sizeof *f->vz);
  f->rg = ms_calloc(cap, sizeof *f->rg);
  f->work = ms_calloc(cap * CPL_WORK_COLS, sizeof *f->work);
  f->cap_fragments = cap;
}

/* ---------------------------------------------------------------------------------------- */
/* Input checks and geometry                                                                 */

static inline double coord(const double *a, size_t i) { return a ? a[i] : 0.0; }

/* Masses are checked for particles [0, n_mass) only (ghost copies of a distributed search
 * carry positions only). */
static ms_status check_input(const cpl_particles *p, const cpl_fragment_opts *o, size_t n_mass) {
  if (!p || !o || (p->n && (!p->x || !p->y || !p->mass))) return MS_ERR_INPUT;
  if (!(o->bond > 0) || !(o->spacing > 0) || !isfinite(o->bond * o->spacing)) return MS_ERR_INPUT;
  double L = o->bond * o->spacing;
  for (int k = 0; k < 3; k++) {
    double P = o->box.period[k];
    if (P < 0 || !isfinite(P) || !isfinite(o->box.lo[k])) return MS_ERR_INPUT;
    /* minimum image is only unambiguous if a bond is shorter than half a period */
    if (P > 0 && !(2 * L < P)) return MS_ERR_INPUT;
  }
  for (size_t i = 0; i < p->n; i++) {
    if (p->skip && p->skip[i]) continue;
    if (!isfinite(p->x[i]) || !isfinite(p->y[i]) || !isfinite(coord(p->z, i))) return MS_ERR_INPUT;
    if (i < n_mass && (!isfinite(p->mass[i]) || p->mass[i] < 0)) return MS_ERR_INPUT;
    if (p->gid && p->gid[i] < 0) return MS_ERR_INPUT;
  }
  return MS_OK;
}

/* Component of a separation vector along axis k reduced to the minimum image. */
static inline double min_image(double d, double period) {
  if (period > 0) d -= period * nearbyint(d / period);
  return d;
}

static inline bool bonded(const cpl_particles *p, const cpl_box *box, double L2, size_t i,
                          size_t k) {
  double dx = min_image(p->x[k] - p->x[i], box->period[0]);
  double dy = min_image(p->y[k] - p->y[i], box->period[1]);
  double dz = min_image(coord(p->z, k) - coord(p->z, i), box->period[2]);
  return dx * dx + dy * dy + dz * dz <= L2;
}

/* ---------------------------------------------------------------------------------------- */
/* Labelling                                                                                  */

static int cmp_root_key(const void *a, const void *b, void *keyv) {
  const int64_t *key = keyv;
  int64_t x = key[*(const size_t *)a], y = key[*(const size_t *)b];
  return x < y ? -1 : x > y;
}

/* Fragment ids from the union–find roots, numbered by smallest particle index, or by smallest
 * gid when the view has gids (then f->key[root] holds that gid). */
static void label_from_roots(cpl_fragments *f, const cpl_particles *p) {
  size_t n = p->n;
  /* root -> id: reuse cell_of as the map (values (size_t)-1 = unassigned) */
  size_t *root_id = f->cell_of;
  for (size_t i = 0; i < n; i++) root_id[i] = (size_t)-1;
  size_t nfrag = 0;
  if (p->gid) {
    /* roots in order of their smallest gid: cell_items lists the roots, then is sorted */
    for (size_t i = 0; i < n; i++) {
      if (p->skip && p->skip[i]) continue;
      size_t r = cpl_uf_find(&f->uf, i);
      if (root_id[r] == (size_t)-1) {
        root_id[r] = 0;
        f->key[r] = p->gid[i];
        f->cell_items[nfrag++] = r;
      } else if (p->gid[i] < f->key[r]) {
        f->key[r] = p->gid[i];
      }
    }
    qsort_r(f->cell_items, nfrag, sizeof *f->cell_items, cmp_root_key, f->key);
    for (size_t k = 0; k < nfrag; k++) root_id[f->cell_items[k]] = k;
  }
  for (size_t i = 0; i < n; i++) {
    if (p->skip && p->skip[i]) {
      f->id[i] = -1;
      continue;
    }
    size_t r = cpl_uf_find(&f->uf, i);
    if (root_id[r] == (size_t)-1) root_id[r] = nfrag++;
    f->id[i] = (int64_t)root_id[r];
  }
  f->n_particles = n;
  f->n = nfrag;
}

/* Cell list over the particles: cells of size ≥ L (the bond length), enlarged if the bounding
 * box would need too many cells (ejecta spread far), so memory stays O(n). */
typedef struct cell_grid {
  size_t nc[3];
  double lo[3], inv_w[3];
  bool periodic[3];
} cell_grid;

static size_t build_cells(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o,
                          cell_grid *g) {
  double L = o->bond * o->spacing;
  double bmin[3] = {INFINITY, INFINITY, INFINITY}, bmax[3] = {-INFINITY, -INFINITY, -INFINITY};
  const double *pos[3] = {p->x, p->y, p->z};
  size_t active = 0;
  for (size_t i = 0; i < p->n; i++) {
    if (p->skip && p->skip[i]) continue;
    active++;
    for (int k = 0; k < 3; k++) {
      double v = coord(pos[k], i);
      if (v < bmin[k]) bmin[k] = v;
      if (v > bmax[k]) bmax[k] = v;
    }
  }
  if (!active)
    for (int k = 0; k < 3; k++) bmin[k] = bmax[k] = 0;
  /* cell width w ≥ L; grow w until the cell count is at most ~2 per active particle */
  double w = L;
  size_t cap = 2 * (active ? active : 1) + 64;
  for (;;) {
    double total = 1;
    for (int k = 0; k < 3; k++) {
      double P = o->box.period[k];
      double ext = P > 0 ? P : bmax[k] - bmin[k];
      double nk = floor(ext / w);
      if (nk < 1) nk = 1;
      total *= nk;
    }
    if (total <= (double)cap) break;
    w *= 1.5;
  }
  size_t ncell = 1;
  for (int k = 0; k < 3; k++) {
    double P = o->box.period[k];
    g->periodic[k] = P > 0;
    double ext = P > 0 ? P : bmax[k] - bmin[k];
    size_t nk = (size_t)floor(ext / w);
    if (nk < 1) nk = 1;
    g->nc[k] = nk;
    g->lo[k] = P > 0 ? o->box.lo[k] : bmin[k];
    /* periodic: cells tile the period exactly (width P/nk ≥ w ≥ L) */
    g->inv_w[k] = P > 0 ? nk / P : 1.0 / w;
    ncell *= nk;
  }
  if (f->cap_cells < ncell + 1 || !f->cell_start) {
    free(f->cell_start);
    f->cell_start = ms_calloc(ncell + 1, sizeof *f->cell_start);
    f->cap_cells = ncell + 1;
  }
  memset(f->cell_start, 0, (ncell + 1) * sizeof *f->cell_start);
  for (size_t i = 0; i < p->n; i++) {
    if (p->skip && p->skip[i]) {
      f->cell_of[i] = (size_t)-1;
      continue;
    }
    size_t c[3];
    for (int k = 0; k < 3; k++) {
      /* Reduce in floating point before converting: a far-away particle (x = 1e300 in a
       * damaged snapshot) must not overflow the integer conversion. */
      const double nk = (double)g->nc[k];
      double s = (coord(pos[k], i) - g->lo[k]) * g->inv_w[k];
      if (g->periodic[k]) {
        s = fmod(s, nk);
        if (s < 0) s += nk;
      }
      if (!(s >= 0)) s = 0;
      if (s >= nk) s = nk - 1; /* the last cell takes the upper edge (and the remainder) */
      c[k] = (size_t)s;
    }
    size_t cell = (c[2] * g->nc[1] + c[1]) * g->nc[0] + c[0];
    f->cell_of[i] = cell;
    f->cell_start[cell + 1]++;
  }
  for (size_t c = 0; c < ncell; c++) f->cell_start[c + 1] += f->cell_start[c];
  return ncell;
}

static void search_cells(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o,
                         const cell_grid *g, size_t ncell) {
  /* counting sort, stable (particles of a cell in ascending index order): start[c] runs as a
   * cursor to the end of cell c, then the array is shifted back by one cell */
  size_t *start = f->cell_start;
  for (size_t i = 0; i < p->n; i++) {
    size_t c = f->cell_of[i];
    if (c == (size_t)-1) continue;
    f->cell_items[start[c]++] = i;
  }
  for (size_t c = ncell; c > 0; c--) start[c] = start[c - 1];
  start[0] = 0;

  double L = o->bond * o->spacing, L2 = L * L;
  long nb = 0;
  for (size_t cz = 0; cz < g->nc[2]; cz++)
    for (size_t cy = 0; cy < g->nc[1]; cy++)
      for (size_t cx = 0; cx < g->nc[0]; cx++) {
        size_t c = (cz * g->nc[1] + cy) * g->nc[0] + cx;
        if (start[c] == start[c + 1]) continue;
        /* the distinct neighbour cells (a periodic axis with < 3 cells repeats indices) */
        size_t nbr[27];
        int nn = 0;
        for (int dz = -1; dz <= 1; dz++)
          for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
              long q[3] = {(long)cx + dx, (long)cy + dy, (long)cz + dz};
              bool ok = true;
              for (int k = 0; k < 3; k++) {
                long nk = (long)g->nc[k];
                if (q[k] < 0 || q[k] >= nk) {
                  if (!g->periodic[k]) {
                    ok = false;
                    break;
                  }
                  q[k] = (q[k] % nk + nk) % nk;
                }
              }
              if (!ok) continue;
              size_t cn = ((size_t)q[2] * g->nc[1] + (size_t)q[1]) * g->nc[0] + (size_t)q[0];
              bool seen = false;
              for (int m = 0; m < nn; m++)
                if (nbr[m] == cn) seen = true;
              if (!seen) nbr[nn++] = cn;
            }
        for (size_t a = start[c]; a < start[c + 1]; a++) {
          size_t i = f->cell_items[a];
          for (int m = 0; m < nn; m++) {
            size_t cn = nbr[m];
            for (size_t b = start[cn]; b < start[cn + 1]; b++) {
              size_t k = f->cell_items[b];
              if (k <= i) continue; /* each unordered pair once */
              if (bonded(p, &o->box, L2, i, k)) {
                nb++;
                cpl_uf_union(&f->uf, i, k);
              }
            }
          }
        }
      }
  f->n_bonds = nb;
}

/* Union of the model's links (o->link_start/link_nbr) between particles that are not skipped. */
static void link_search(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o) {
  long nb = 0;
  for (size_t i = 0; i < p->n; i++) {
    if (p->skip && p->skip[i]) continue;
    for (size_t b = o->link_start[i]; b < o->link_start[i + 1]; b++) {
      const int32_t k = o->link_nbr[b];
      if (k < 0 || (size_t)k >= p->n || (size_t)k == i || (p->skip && p->skip[k])) continue;
      nb++;
      cpl_uf_union(&f->uf, i, (size_t)k);
    }
  }
  f->n_bonds = nb; /* a pair listed both ways counts twice */
}

ms_status cpl_fragments_bond_search(cpl_fragments *f, const cpl_particles *p,
                                    const cpl_fragment_opts *o, size_t n_mass) {
  ms_status s = check_input(p, o, n_mass);
  if (s != MS_OK) return s;
  reserve_particles(f, p->n);
  if (o->link_start && o->link_nbr) { /* the model's connectivity instead of distances */
    cpl_uf_init(&f->uf, p->n);
    link_search(f, p, o);
    return MS_OK;
  }
  cell_grid g;
  size_t ncell = build_cells(f, p, o, &g);
  cpl_uf_init(&f->uf, p->n);
  search_cells(f, p, o, &g, ncell);
  return MS_OK;
}

ms_status cpl_fragments_find(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o) {
  ms_status s = cpl_fragments_bond_search(f, p, o, p ? p->n : 0);
  if (s != MS_OK) return s;
  label_from_roots(f, p);
  cpl_fragments_stats(f, p, o);
  return MS_OK;
}

ms_status cpl_fragments_find_csr(cpl_fragments *f, const cpl_particles *p,
                                 const cpl_fragment_opts *o, const size_t *start,
                                 const int32_t *nbr) {
  ms_status s = check_input(p, o, p ? p->n : 0);
  if (s != MS_OK) return s;
  if (p->n && (!start || !nbr)) return MS_ERR_INPUT;
  reserve_particles(f, p->n);
  cpl_uf_init(&f->uf, p->n);
  double L = o->bond * o->spacing, L2 = L * L;
  long nb = 0;
  for (size_t i = 0; i < p->n; i++) {
    if (p->skip && p->skip[i]) continue;
    for (size_t b = start[i]; b < start[i + 1]; b++) {
      int32_t k = nbr[b];
      if (k < 0 || (size_t)k >= p->n || (size_t)k == i) continue;
      if (p->skip && p->skip[k]) continue;
      if (bonded(p, &o->box, L2, i, (size_t)k)) {
        nb++;
        cpl_uf_union(&f->uf, i, (size_t)k);
      }
    }
  }
  f->n_bonds = nb; /* bonded list entries: a pair listed both ways counts twice */
  label_from_roots(f, p);
  cpl_fragments_stats(f, p, o);
  return MS_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Statistics, in three passes over the particles with per-fragment accumulators, so that a
 * distributed search can run each pass on its own particles and sum the accumulators across
 * ranks between the passes (coupling/fragments_dist.c). The frame of a fragment: positions
 * unwrapped (minimum image) around a reference point, the circular mean on periodic axes and
 * the particle with the smallest key (gid, or index) on open axes. */

void cpl_acc1_clear(double *acc, size_t nf) {
  memset(acc, 0, nf * CPL_ACC1 * sizeof *acc);
  for (size_t k = 0; k < nf; k++) acc[k * CPL_ACC1 + CPL_ACC1_KEY] = INFINITY;
}

void cpl_acc1_add(double *acc, const int64_t *id, size_t n, const cpl_particles *p,
                  const cpl_box *box) {
  const double *pos[3] = {p->x, p->y, p->z};
  const double *vel[3] = {p->vx, p->vy, p->vz};
  const double two_pi = 2 * CPL_PI;
  for (size_t i = 0; i < n; i++) {
    if (id[i] < 0) continue;
    double *a = acc + (size_t)id[i] * CPL_ACC1;
    double m = p->mass[i];
    a[CPL_ACC1_COUNT] += 1;
    a[CPL_ACC1_MASS] += m;
    for (int d = 0; d < 3; d++) {
      a[CPL_ACC1_MV + d] += m * coord(vel[d], i);
      double P = box->period[d];
      if (P > 0) {
        double th = two_pi * (coord(pos[d], i) - box->lo[d]) / P;
        /* unit weights: the reference point only needs to lie inside the fragment */
        a[CPL_ACC1_COS + d] += cos(th);
        a[CPL_ACC1_SIN + d] += sin(th);
      }
    }
    double key = p->gid ? (double)p->gid[i] : (double)i;
    if (key < a[CPL_ACC1_KEY]) {
      a[CPL_ACC1_KEY] = key;
      for (int d = 0; d < 3; d++) a[CPL_ACC1_REF + d] = coord(pos[d], i);
    }
  }
}

void cpl_acc1_merge(double *dst, const double *src) {
  for (int c = 0; c < CPL_ACC1_KEY; c++) dst[c] += src[c];
  if (src[CPL_ACC1_KEY] < dst[CPL_ACC1_KEY])
    for (int c = CPL_ACC1_KEY; c < CPL_ACC1; c++) dst[c] = src[c];
}

void cpl_ref_point(const double *acc1, const cpl_box *box, double ref[3]) {
  for (int d = 0; d < 3; d++) {
    double P = box->period[d];
    if (P > 0)
      ref[d] =
          box->lo[d] + P * atan2(acc1[CPL_ACC1_SIN + d], acc1[CPL_ACC1_COS + d]) / (2 * CPL_PI);
    else ref[d] = acc1[CPL_ACC1_REF + d];
  }
}

void cpl_acc2_add(double *acc2, const int64_t *id, size_t n, const cpl_particles *p,
                  const cpl_box *box, const double *ref) {
  const double *pos[3] = {p->x, p->y, p->z};
  for (size_t i = 0; i < n; i++) {
    if (id[i] < 0) continue;
    size_t k = (size_t)id[i];
    for (int d = 0; d < 3; d++)
      acc2[3 * k + d] += p->mass[i] * min_image(coord(pos[d], i) - ref[3 * k + d], box->period[d]);
  }
}

void cpl_centre(double mass, const double ref[3], const double acc2[3], const cpl_box *box,
                double off[3], double c[3]) {
  for (int d = 0; d < 3; d++) {
    /* offset of the centre from the reference (mean of unwrapped separations) */
    off[d] = mass > 0 ? acc2[d] / mass : 0.0;
    double x = ref[d] + off[d];
    double P = box->period[d];
    if (P > 0) {
      x = box->lo[d] + fmod(x - box->lo[d], P);
      if (x < box->lo[d]) x += P;
    }
    c[d] = x;
  }
}

void cpl_acc3_add(double *acc3, const int64_t *id, size_t n, const cpl_particles *p,
                  const cpl_box *box, const double *ref, const double *off) {
  const double *pos[3] = {p->x, p->y, p->z};
  for (size_t i = 0; i < n; i++) {
    if (id[i] < 0) continue;
    size_t k = (size_t)id[i];
    double r2 = 0;
    for (int d = 0; d < 3; d++) {
      double x = min_image(coord(pos[d], i) - ref[3 * k + d], box->period[d]) - off[3 * k + d];
      r2 += x * x;
    }
    acc3[k] += p->mass[i] * r2;
  }
}

void cpl_fragment_set(cpl_fragments *f, size_t k, const double *acc1, const double c[3],
                      double acc3, double rho0) {
  double M = acc1[CPL_ACC1_MASS], inv = M > 0 ? 1.0 / M : 0.0;
  f->first[k] = (int64_t)acc1[CPL_ACC1_KEY];
  f->count[k] = (int64_t)acc1[CPL_ACC1_COUNT];
  f->mass[k] = M;
  f->vx[k] = acc1[CPL_ACC1_MV] * inv;
  f->vy[k] = acc1[CPL_ACC1_MV + 1] * inv;
  f->vz[k] = acc1[CPL_ACC1_MV + 2] * inv;
  f->cx[k] = c[0];
  f->cy[k] = c[1];
  f->cz[k] = c[2];
  f->rg[k] = M > 0 ? sqrt(acc3 / M) : 0.0;
  f->diameter[k] = rho0 > 0 ? cbrt(6 * M / (CPL_PI * rho0)) : NAN;
}

void cpl_fragments_reserve(cpl_fragments *f, size_t nf) { reserve_fragments(f, nf); }

void cpl_fragments_stats(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o) {
  size_t nf = f->n;
  reserve_fragments(f, nf);
  /* f->work (CPL_WORK_COLS per fragment) as blocks: acc1 [nf][CPL_ACC1], ref, acc2, off [nf][3] */
  double *acc1 = f->work, *ref = acc1 + nf * CPL_ACC1, *acc2 = ref + 3 * nf, *off = acc2 + 3 * nf;
  double *acc3 = f->rg;
  cpl_acc1_clear(acc1, nf);
  memset(acc2, 0, 3 * nf * sizeof *acc2);
  memset(acc3, 0, nf * sizeof *acc3);
  cpl_acc1_add(acc1, f->id, p->n, p, &o->box);
  for (size_t k = 0; k < nf; k++) cpl_ref_point(acc1 + k * CPL_ACC1, &o->box, ref + 3 * k);
  cpl_acc2_add(acc2, f->id, p->n, p, &o->box, ref);
  for (size_t k = 0; k < nf; k++) {
    double centre[3];
    cpl_centre(acc1[k * CPL_ACC1 + CPL_ACC1_MASS], ref + 3 * k, acc2 + 3 * k, &o->box, off + 3 * k,
               centre);
    f->cx[k] = centre[0];
    f->cy[k] = centre[1];
    f->cz[k] = centre[2];
  }
  cpl_acc3_add(acc3, f->id, p->n, p, &o->box, ref, off);
  for (size_t k = 0; k < nf; k++) {
    const double centre[3] = {f->cx[k], f->cy[k], f->cz[k]};
    cpl_fragment_set(f, k, acc1 + k * CPL_ACC1, centre, acc3[k], o->rho0);
  }
}
