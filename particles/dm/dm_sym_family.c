/* SPDX-License-Identifier: MIT */
/* dm_sym_family.c — symmetry planes with families that reference updates keep or merge
 * (docs/particles-dm.md "Symmetry planes", "Per-family references"). dm_symmetry.c's quarter
 * equals the full body because every real family is the full body's, built within the horizon
 * of a mirror-symmetric configuration. Kept and merged families are not built from positions, so
 * the quarter keeps them the full body's by construction:
 *  - the ghost set is the set-up's and never changes (the kept lists index it); an update
 *    whose current configuration brings a real particle within the horizon of a plane where its
 *    mirror image has no ghost is refused (dm_sym_uncovered: the neighbour search would miss the
 *    bonds across the plane);
 *  - the bonds a merge adds are closed under the reflections (dm_sym_close_pairs): family i
 *    gaining ghost g = M p (M the reflections of g, p its partner) is, in the full body, also
 *    family p gaining M i, which the quarter finds by mapping every new pair (a, b) to (M a, M b)
 *    for every product M of the planes' reflections and keeping the directions whose first
 *    particle is real;
 *  - per-family references: the gather reads each bond's reverse vector ξ_rev, which for a bond
 *    i → g is a bond of the ghost's family. The ghosts get rows holding exactly those reverse
 *    bonds (dm_sym_ghost_rows), with the full body's vectors ξ_{g→i} = M ξ_{p→M i}
 *    (dm_sym_ghost_xref: M a diagonal of ±1, so exact copies), refreshed at every update; their
 *    Q and κ are their partners' (dm_sym_sync), so every real particle's force is the full
 *    body's by the same bond sums in another order. The ghosts' rows are never stepped (the
 *    passes run over the real particles). */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The reflections of ghost g as a mask of the planes. */
static unsigned ghost_mask(const dm_fin *f, const dm_state *s, size_t g) {
  unsigned m = 0;
  for (int j = 0; j < f->sym.n; ++j)
    if (s->msign[3 * g + f->sym.axis[j]] < 0) m |= 1u << j;
  return m;
}

void dm_sym_map_build(const dm_fin *f, dm_sym_map *mp) {
  const dm_state *s = f->m->s;
  const size_t nr = f->n;
  mp->nreal = nr, mp->nmask = 1u << f->sym.n;
  mp->ghost = ms_calloc(nr * mp->nmask + 1, sizeof(uint32_t));
  mp->off = ms_calloc(nr + 1, 1);
  for (size_t q = 0; q < nr * mp->nmask; ++q) mp->ghost[q] = UINT32_MAX;
  for (size_t i = 0; i < nr; ++i)
    for (int j = 0; j < f->sym.n; ++j) /* dm_sym_ghosts put the on-plane ones exactly on it */
      if (s->X[3 * i + f->sym.axis[j]] != f->sym.pos[j]) mp->off[i] |= (uint8_t)(1u << j);
  for (size_t g = nr; g < s->n; ++g)
    mp->ghost[(size_t)s->partner[g] * mp->nmask + ghost_mask(f, s, g)] = (uint32_t)g;
}

void dm_sym_map_free(dm_sym_map *mp) {
  free(mp->ghost), free(mp->off);
  mp->ghost = NULL, mp->off = NULL;
}

size_t dm_sym_image(const dm_fin *f, const dm_sym_map *mp, size_t k, unsigned mask) {
  const dm_state *s = f->m->s;
  const size_t r = k < mp->nreal ? k : s->partner[k];
  const unsigned mk = k < mp->nreal ? 0u : ghost_mask(f, s, k);
  const unsigned t = (mk ^ mask) & mp->off[r];
  if (!t) return r;
  const uint32_t g = mp->ghost[r * mp->nmask + t];
  return g == UINT32_MAX ? SIZE_MAX : g;
}

/* Is a real particle within `reach` of the point y (current positions; cl: the real particles'
 * cell list, cells of size reach)? */
static bool real_near(const dm_cells *cl, const dm_state *s, const double y[3], double reach) {
  long c0[3];
  dm_cells_of(cl, y, c0);
  for (long dz = -cl->reach[2]; dz <= cl->reach[2]; ++dz)
    for (long dy = -cl->reach[1]; dy <= cl->reach[1]; ++dy)
      for (long dx = -cl->reach[0]; dx <= cl->reach[0]; ++dx) {
        long cn[3] = {c0[0] + dx, c0[1] + dy, c0[2] + dz};
        for (long j = cl->head[dm_cells_bucket(cl, cn)]; j >= 0; j = cl->next[j]) {
          const long *cj = &cl->cidx[3 * j]; /* the cell's own particles only */
          if (cj[0] != cn[0] || cj[1] != cn[1] || cj[2] != cn[2]) continue;
          double r2 = 0;
          for (int a = 0; a < 3; ++a) {
            const double d = s->X[3 * j + a] + s->w[3 * j + a] - y[a];
            r2 += d * d;
          }
          if (r2 < reach * reach) return true;
        }
      }
  return false;
}

size_t dm_sym_uncovered(const dm_fin *f, const dm_sym_map *mp, double reach) {
  const dm_state *s = f->m->s;
  /* a cheap bound first: the image of i under the planes of m lies at least
   * √Σ_{j∈m} (d_ij + dmin_j)² from every real particle (d: current distances to plane j; dmin_j:
   * the real particles' smallest); only where that is below reach, the real particles near the
   * image itself (a cell list, built once) */
  double dmin[3] = {INFINITY, INFINITY, INFINITY};
  for (size_t i = 0; i < mp->nreal; ++i)
    for (int j = 0; j < f->sym.n; ++j) {
      const int a = f->sym.axis[j];
      dmin[j] = fmin(dmin[j], s->X[3 * i + a] + s->w[3 * i + a] - f->sym.pos[j]);
    }
  dm_cells cl;
  bool built = false;
  size_t bad = SIZE_MAX;
  for (size_t i = 0; i < mp->nreal && bad == SIZE_MAX; ++i)
    for (unsigned m = 1; m < mp->nmask && bad == SIZE_MAX; ++m) {
      if ((m & mp->off[i]) != m || mp->ghost[i * mp->nmask + m] != UINT32_MAX) continue;
      double r2 = 0, y[3]; /* on a plane of m: its own image there; a ghost: covered */
      for (int a = 0; a < 3; ++a) y[a] = s->X[3 * i + a] + s->w[3 * i + a];
      for (int j = 0; j < f->sym.n; ++j) {
        const int a = f->sym.axis[j];
        const double d = y[a] - f->sym.pos[j] + fmax(dmin[j], 0.0);
        if (m >> j & 1u) r2 += d * d, y[a] = 2.0 * f->sym.pos[j] - y[a];
      }
      if (!(r2 < reach * reach)) continue;
      if (!built) {
        if (dm_cells_init(&cl, mp->nreal, f->dim, reach, NULL, NULL) != MS_OK) return i;
        dm_cells_build(&cl, s->X, s->w), built = true;
      }
      if (real_near(&cl, s, y, reach)) bad = i;
    }
  if (built) dm_cells_free(&cl);
  return bad;
}

static int cmp_u64(const void *a, const void *b) {
  const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

size_t dm_sym_close_pairs(const dm_fin *f, const dm_sym_map *mp, uint64_t **pairs, size_t np,
                          size_t *missing) {
  const uint64_t *pr = *pairs;
  uint64_t *out = ms_calloc(2 * np * mp->nmask + 1, sizeof *out);
  size_t no = 0;
  *missing = SIZE_MAX;
  for (size_t q = 0; q < np; ++q) {
    const size_t a = (size_t)(pr[q] >> 32), b = (size_t)(pr[q] & 0xffffffffu);
    if (a >= mp->nreal) continue; /* its real end's direction is in the list too */
    for (unsigned m = 0; m < mp->nmask; ++m) {
      const size_t ia = dm_sym_image(f, mp, a, m), ib = dm_sym_image(f, mp, b, m);
      if (ia < mp->nreal && ib == SIZE_MAX && *missing == SIZE_MAX) *missing = ia;
      if (ib < mp->nreal && ia == SIZE_MAX && *missing == SIZE_MAX) *missing = ib;
      if (ia == SIZE_MAX || ib == SIZE_MAX) continue;
      if (ia < mp->nreal) out[no++] = (uint64_t)ia << 32 | ib;
      if (ib < mp->nreal) out[no++] = (uint64_t)ib << 32 | ia;
    }
  }
  qsort(out, no, sizeof *out, cmp_u64);
  size_t u = 0;
  for (size_t q = 0; q < no; ++q)
    if (u == 0 || out[q] != out[u - 1]) out[u++] = out[q];
  free(*pairs);
  *pairs = out;
  return u;
}

void dm_sym_ghost_rows(size_t n, size_t nreal, size_t **start, uint32_t **nbr, size_t **from,
                       size_t *nbonds) {
  const size_t *st = *start;
  const uint32_t *nb = *nbr;
  size_t *cnt = ms_calloc(n + 1, sizeof(size_t));
  for (size_t i = 0; i < nreal; ++i)
    for (size_t b = st[i]; b < st[i + 1]; ++b)
      if (nb[b] >= nreal) cnt[nb[b]]++;
  size_t *s2 = ms_calloc(n + 1, sizeof(size_t));
  for (size_t i = 0; i < nreal; ++i) s2[i + 1] = s2[i] + (st[i + 1] - st[i]);
  for (size_t g = nreal; g < n; ++g) s2[g + 1] = s2[g] + cnt[g];
  uint32_t *n2 = ms_calloc(s2[n] + 1, sizeof(uint32_t));
  size_t *f2 = ms_calloc(s2[n] + 1, sizeof(size_t));
  memcpy(n2, nb, s2[nreal] * sizeof(uint32_t));
  for (size_t c = 0; c < s2[nreal]; ++c) f2[c] = *from ? (*from)[c] : c;
  for (size_t g = nreal; g < n; ++g) cnt[g] = s2[g];
  for (size_t i = 0; i < nreal; ++i) /* in the order of i: each ghost row sorted */
    for (size_t b = st[i]; b < st[i + 1]; ++b)
      if (nb[b] >= nreal) {
        const size_t c = cnt[nb[b]]++;
        n2[c] = (uint32_t)i, f2[c] = SIZE_MAX;
      }
  free(cnt), free(*start), free(*nbr), free(*from);
  *start = s2, *nbr = n2, *from = f2, *nbonds = s2[n];
}

/* The bond p → j in p's sorted row, or SIZE_MAX. */
static size_t find_bond(const size_t *start, const uint32_t *nbr, size_t p, size_t j) {
  size_t lo = start[p], hi = start[p + 1];
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (nbr[mid] < j) lo = mid + 1;
    else hi = mid;
  }
  return lo < start[p + 1] && nbr[lo] == j ? lo : SIZE_MAX;
}

ms_status dm_sym_ghost_xref(const dm_fin *f, const dm_sym_map *mp, const size_t *start,
                            const uint32_t *nbr, double *xref) {
  const dm_state *s = f->m->s;
  long bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad) if (s->n - mp->nreal > 4096)
  for (long gl = (long)mp->nreal; gl < (long)s->n; ++gl) {
    const size_t g = (size_t)gl, p = s->partner[g];
    const unsigned mg = ghost_mask(f, s, g);
    const int8_t *sg = &s->msign[3 * g];
    for (size_t c = start[g]; c < start[g + 1]; ++c) {
      const size_t j = dm_sym_image(f, mp, nbr[c], mg); /* ξ_{g→i} = M ξ_{p→M i} */
      const size_t b = j == SIZE_MAX ? SIZE_MAX : find_bond(start, nbr, p, j);
      if (b == SIZE_MAX) {
        ++bad;
        continue;
      }
      for (int a = 0; a < 3; ++a) xref[3 * c + a] = sg[a] * xref[3 * b + a];
    }
  }
  return bad ? MS_ERR_INTERNAL : MS_OK;
}
