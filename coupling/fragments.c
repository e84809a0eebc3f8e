/* Fragments: bonds |r_i − r_k| ≤ b·a (paper 002 §4.2, DESIGN.md §6), connected components by
 * union–find, per-fragment statistics. docs/coupling.md describes the algorithm. */
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
  while (uf->parent[root] != root)
    root = uf->parent[root];
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
  if (a == b)
    return false;
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
  if (!f)
    return;
  free(f->id);
  free_fragment_arrays(f);
  free(f->cell_of);
  free(f->cell_start);
  free(f->cell_items);
  cpl_uf_free(&f->uf);
  memset(f, 0, sizeof *f);
}

static void reserve_particles(cpl_fragments *f, size_t n) {
  if (f->cap_particles >= n && f->id)
    return;
  size_t cap = n ? n : 1;
  free(f->id);
  free(f->cell_of);
  free(f->cell_items);
  f->id = ms_calloc(cap, sizeof *f->id);
  f->cell_of = ms_calloc(cap, sizeof *f->cell_of);
  f->cell_items = ms_calloc(cap, sizeof *f->cell_items);
  f->cap_particles = cap;
}

static void reserve_fragments(cpl_fragments *f, size_t n) {
  if (f->cap_fragments >= n && f->count)
    return;
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

static ms_status check_input(const cpl_particles *p, const cpl_fragment_opts *o) {
  if (!p || !o || (p->n && (!p->x || !p->y || !p->mass)))
    return MS_ERR_INPUT;
  if (!(o->bond > 0) || !(o->spacing > 0) || !isfinite(o->bond * o->spacing))
    return MS_ERR_INPUT;
  double L = o->bond * o->spacing;
  for (int k = 0; k < 3; k++) {
    double P = o->box.period[k];
    if (P < 0 || !isfinite(P) || !isfinite(o->box.lo[k]))
      return MS_ERR_INPUT;
    /* minimum image is only unambiguous if a bond is shorter than half a period */
    if (P > 0 && !(2 * L < P))
      return MS_ERR_INPUT;
  }
  for (size_t i = 0; i < p->n; i++) {
    if (p->skip && p->skip[i])
      continue;
    if (!isfinite(p->x[i]) || !isfinite(p->y[i]) || !isfinite(coord(p->z, i)) ||
        !isfinite(p->mass[i]) || p->mass[i] < 0)
      return MS_ERR_INPUT;
  }
  return MS_OK;
}

/* Component of a separation vector along axis k reduced to the minimum image. */
static inline double min_image(double d, double period) {
  if (period > 0)
    d -= period * nearbyint(d / period);
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

/* Fragment ids from the union–find roots, numbered by smallest particle index. */
static void label_from_roots(cpl_fragments *f, const cpl_particles *p) {
  size_t n = p->n;
  /* root -> id: reuse cell_of as the map (values (size_t)-1 = unassigned) */
  size_t *root_id = f->cell_of;
  for (size_t i = 0; i < n; i++)
    root_id[i] = (size_t)-1;
  size_t nfrag = 0;
  for (size_t i = 0; i < n; i++) {
    if (p->skip && p->skip[i]) {
      f->id[i] = -1;
      continue;
    }
    size_t r = cpl_uf_find(&f->uf, i);
    if (root_id[r] == (size_t)-1)
      root_id[r] = nfrag++;
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
    if (p->skip && p->skip[i])
      continue;
    active++;
    for (int k = 0; k < 3; k++) {
      double v = coord(pos[k], i);
      if (v < bmin[k])
        bmin[k] = v;
      if (v > bmax[k])
        bmax[k] = v;
    }
  }
  if (!active)
    for (int k = 0; k < 3; k++)
      bmin[k] = bmax[k] = 0;
  /* cell width w ≥ L; grow w until the cell count is at most ~2 per active particle */
  double w = L;
  size_t cap = 2 * (active ? active : 1) + 64;
  for (;;) {
    double total = 1;
    for (int k = 0; k < 3; k++) {
      double P = o->box.period[k];
      double ext = P > 0 ? P : bmax[k] - bmin[k];
      double nk = floor(ext / w);
      if (nk < 1)
        nk = 1;
      total *= nk;
    }
    if (total <= (double)cap)
      break;
    w *= 1.5;
  }
  size_t ncell = 1;
  for (int k = 0; k < 3; k++) {
    double P = o->box.period[k];
    g->periodic[k] = P > 0;
    double ext = P > 0 ? P : bmax[k] - bmin[k];
    size_t nk = (size_t)floor(ext / w);
    if (nk < 1)
      nk = 1;
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
        if (s < 0)
          s += nk;
      }
      if (!(s >= 0))
        s = 0;
      if (s >= nk)
        s = nk - 1; /* the last cell takes the upper edge (and the remainder) */
      c[k] = (size_t)s;
    }
    size_t cell = (c[2] * g->nc[1] + c[1]) * g->nc[0] + c[0];
    f->cell_of[i] = cell;
    f->cell_start[cell + 1]++;
  }
  for (size_t c = 0; c < ncell; c++)
    f->cell_start[c + 1] += f->cell_start[c];
  return ncell;
}

static void search_cells(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o,
                         const cell_grid *g, size_t ncell) {
  /* counting sort, stable (particles of a cell in ascending index order): start[c] runs as a
   * cursor to the end of cell c, then the array is shifted back by one cell */
  size_t *start = f->cell_start;
  for (size_t i = 0; i < p->n; i++) {
    size_t c = f->cell_of[i];
    if (c == (size_t)-1)
      continue;
    f->cell_items[start[c]++] = i;
  }
  for (size_t c = ncell; c > 0; c--)
    start[c] = start[c - 1];
  start[0] = 0;

  double L = o->bond * o->spacing, L2 = L * L;
  long nb = 0;
  for (size_t cz = 0; cz < g->nc[2]; cz++)
    for (size_t cy = 0; cy < g->nc[1]; cy++)
      for (size_t cx = 0; cx < g->nc[0]; cx++) {
        size_t c = (cz * g->nc[1] + cy) * g->nc[0] + cx;
        if (start[c] == start[c + 1])
          continue;
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
              if (!ok)
                continue;
              size_t cn = ((size_t)q[2] * g->nc[1] + (size_t)q[1]) * g->nc[0] + (size_t)q[0];
              bool seen = false;
              for (int m = 0; m < nn; m++)
                if (nbr[m] == cn)
                  seen = true;
              if (!seen)
                nbr[nn++] = cn;
            }
        for (size_t a = start[c]; a < start[c + 1]; a++) {
          size_t i = f->cell_items[a];
          for (int m = 0; m < nn; m++) {
            size_t cn = nbr[m];
            for (size_t b = start[cn]; b < start[cn + 1]; b++) {
              size_t k = f->cell_items[b];
              if (k <= i)
                continue; /* each unordered pair once */
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

ms_status cpl_fragments_find(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o) {
  ms_status s = check_input(p, o);
  if (s != MS_OK)
    return s;
  reserve_particles(f, p->n);
  cell_grid g;
  size_t ncell = build_cells(f, p, o, &g);
  cpl_uf_init(&f->uf, p->n);
  search_cells(f, p, o, &g, ncell);
  label_from_roots(f, p);
  cpl_fragments_stats(f, p, o);
  return MS_OK;
}

ms_status cpl_fragments_find_csr(cpl_fragments *f, const cpl_particles *p,
                                 const cpl_fragment_opts *o, const size_t *start,
                                 const int32_t *nbr) {
  ms_status s = check_input(p, o);
  if (s != MS_OK)
    return s;
  if (p->n && (!start || !nbr))
    return MS_ERR_INPUT;
  reserve_particles(f, p->n);
  cpl_uf_init(&f->uf, p->n);
  double L = o->bond * o->spacing, L2 = L * L;
  long nb = 0;
  for (size_t i = 0; i < p->n; i++) {
    if (p->skip && p->skip[i])
      continue;
    for (size_t b = start[i]; b < start[i + 1]; b++) {
      int32_t k = nbr[b];
      if (k < 0 || (size_t)k >= p->n || (size_t)k == i)
        continue;
      if (p->skip && p->skip[k])
        continue;
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
/* Statistics                                                                                 */

void cpl_fragments_stats(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o) {
  size_t nf = f->n;
  reserve_fragments(f, nf);
  const double *pos[3] = {p->x, p->y, p->z};
  const double two_pi = 2 * CPL_PI;
  double *w = f->work; /* [nf][CPL_WORK_COLS]: cos/sin sums per periodic axis, reference, sums */
  memset(w, 0, nf * CPL_WORK_COLS * sizeof *w);
  for (size_t k = 0; k < nf; k++) {
    f->count[k] = 0;
    f->first[k] = -1;
    f->mass[k] = 0;
    f->vx[k] = f->vy[k] = f->vz[k] = 0;
    f->cx[k] = f->cy[k] = f->cz[k] = 0;
    f->rg[k] = 0;
  }
  /* pass 1: counts, masses, momentum, circular sums on periodic axes */
  for (size_t i = 0; i < p->n; i++) {
    int64_t id = f->id[i];
    if (id < 0)
      continue;
    size_t k = (size_t)id;
    double m = p->mass[i];
    if (f->first[k] < 0)
      f->first[k] = (int64_t)i;
    f->count[k]++;
    f->mass[k] += m;
    f->vx[k] += m * coord(p->vx, i);
    f->vy[k] += m * coord(p->vy, i);
    f->vz[k] += m * coord(p->vz, i);
    for (int a = 0; a < 3; a++) {
      double P = o->box.period[a];
      if (P > 0) {
        double th = two_pi * (coord(pos[a], i) - o->box.lo[a]) / P;
        /* unit weights: the reference point only needs to lie inside the fragment */
        w[k * CPL_WORK_COLS + 2 * a] += cos(th);
        w[k * CPL_WORK_COLS + 2 * a + 1] += sin(th);
      }
    }
  }
  /* reference point per periodic axis: circular mean (columns 0..2 reused) */
  for (size_t k = 0; k < nf; k++) {
    double M = f->mass[k];
    double inv = M > 0 ? 1.0 / M : 0.0;
    f->vx[k] *= inv;
    f->vy[k] *= inv;
    f->vz[k] *= inv;
    double ref[3] = {0, 0, 0};
    for (int a = 0; a < 3; a++) {
      double P = o->box.period[a];
      if (P > 0) {
        double th = atan2(w[k * CPL_WORK_COLS + 2 * a + 1], w[k * CPL_WORK_COLS + 2 * a]);
        ref[a] = o->box.lo[a] + P * th / two_pi;
      }
    }
    for (int a = 0; a < 3; a++)
      w[k * CPL_WORK_COLS + 6 + a] = ref[a];
    /* position sums (unwrapped) go to columns 0..2 */
    w[k * CPL_WORK_COLS + 0] = w[k * CPL_WORK_COLS + 1] = w[k * CPL_WORK_COLS + 2] = 0;
    /* also fall back to the first particle as the reference on open axes (round-off) */
    size_t i0 = (size_t)f->first[k];
    for (int a = 0; a < 3; a++)
      if (!(o->box.period[a] > 0))
        w[k * CPL_WORK_COLS + 6 + a] = coord(pos[a], i0);
  }
  /* pass 2: mass-weighted unwrapped positions relative to the reference */
  for (size_t i = 0; i < p->n; i++) {
    int64_t id = f->id[i];
    if (id < 0)
      continue;
    size_t k = (size_t)id;
    double m = p->mass[i];
    for (int a = 0; a < 3; a++) {
      double d = min_image(coord(pos[a], i) - w[k * CPL_WORK_COLS + 6 + a], o->box.period[a]);
      w[k * CPL_WORK_COLS + a] += m * d;
    }
  }
  double *c[3] = {f->cx, f->cy, f->cz};
  for (size_t k = 0; k < nf; k++) {
    double M = f->mass[k];
    for (int a = 0; a < 3; a++) {
      /* offset of the centre from the reference (mean of unwrapped separations) */
      double off = M > 0 ? w[k * CPL_WORK_COLS + a] / M : 0.0;
      w[k * CPL_WORK_COLS + 3 + a] = off; /* kept for pass 3 */
      double x = w[k * CPL_WORK_COLS + 6 + a] + off;
      double P = o->box.period[a];
      if (P > 0) {
        x = o->box.lo[a] + fmod(x - o->box.lo[a], P);
        if (x < o->box.lo[a])
          x += P;
      }
      c[a][k] = x;
    }
    f->diameter[k] = o->rho0 > 0 ? cbrt(6 * M / (CPL_PI * o->rho0)) : NAN;
  }
  /* pass 3: radius of gyration about the centre (in the same unwrapped frame) */
  for (size_t i = 0; i < p->n; i++) {
    int64_t id = f->id[i];
    if (id < 0)
      continue;
    size_t k = (size_t)id;
    double r2 = 0;
    for (int a = 0; a < 3; a++) {
      double d = min_image(coord(pos[a], i) - w[k * CPL_WORK_COLS + 6 + a], o->box.period[a]) -
                 w[k * CPL_WORK_COLS + 3 + a];
      r2 += d * d;
    }
    f->rg[k] += p->mass[i] * r2;
  }
  for (size_t k = 0; k < nf; k++)
    f->rg[k] = f->mass[k] > 0 ? sqrt(f->rg[k] / f->mass[k]) : 0.0;
}
