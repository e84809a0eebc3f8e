/* SPDX-License-Identifier: MIT */
/* neighbour.c — link cells and Verlet half lists with a skin (layout in cd_impl.h).
 *
 * A list built at time t_b holds every pair closer than r_list = R_c + skin. It stays valid
 * while no pair that was farther than r_list at t_b can have come within R_c: a pair closes
 * in by |Δ_i − Δ_j| at most (Δ the displacements since t_b), so the list holds while that is
 * below the skin for every pair. cd_neigh_holds tests it (cd_impl.h): every |Δ| within skin/2
 * (the usual test), or every Δ within skin/2 of one common vector, the centre of their
 * bounding box — a slab moving as a whole (a shocked region, a flying fragment) costs no
 * rebuild until its particles move relative to the rest.
 */
#include "cd_impl.h"
#include "neighbour_select.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

ms_status cd_neigh_create(const cd_neigh_params *par, cd_neigh **out) {
  *out = NULL;
  if (!(par->rlist > par->skin) || !(par->skin >= 0)) return MS_ERR_INPUT;
  const size_t cap = par->cap;
  const double rlist = par->rlist, skin = par->skin;
  cd_neigh *nl = ms_calloc(1, sizeof *nl);
  nl->rlist = rlist;
  nl->skin = skin;
  nl->sorted = ms_calloc(cap + 8, sizeof *nl->sorted); /* + 7: AVX2 select_range reads 8 */
  nl->cell_of = ms_calloc(cap + 1, sizeof *nl->cell_of);
  nl->first = ms_calloc(cap + 1, sizeof *nl->first);
  nl->nplain = ms_calloc(cap + 1, sizeof *nl->nplain);
  nl->nimg = ms_calloc(cap + 1, sizeof *nl->nimg);
  nl->xb = ms_calloc(cap + 1, sizeof *nl->xb);
  nl->yb = ms_calloc(cap + 1, sizeof *nl->yb);
  nl->zb = ms_calloc(cap + 1, sizeof *nl->zb);
  /* one block of 3 (cap + 1) floats (+ 16 each so that ys, zs stay 64-byte aligned): also the
   * renumbering scratch, which needs 8 bytes per particle */
  const size_t stride = (cap + 1 + 15) / 16 * 16;
  nl->xs = ms_aligned_alloc(3 * stride + 8, sizeof *nl->xs); /* + 8: the same, past zs */
  nl->ys = nl->xs + stride;
  nl->zs = nl->ys + stride;
#if defined(CD_SELECT_AVX2)
  if (!compress_lut[255][7]) fill_compress_lut();
#endif
  *out = nl;
  return MS_OK;
}

static void cd_neigh_free(cd_neigh *nl) {
  if (!nl) return;
  for (int l = 0; l < nl->layers_cap; l++) free(nl->buf[l]);
  free(nl->buf);
  free(nl->buf_cap);
  free(nl->buf_len);
  free(nl->layer_start);
  free(nl->phase_layer);
  free(nl->cell_start);
  free(nl->sorted);
  free(nl->cell_of);
  free(nl->first);
  free(nl->nplain);
  free(nl->nimg);
  free(nl->xb);
  free(nl->yb);
  free(nl->zb);
  free(nl->xs);
  free(nl);
}

void cd_neigh_destroy(cd_neigh **nl) {
  if (!nl) return;
  cd_neigh_free(*nl);
  *nl = NULL;
}

size_t cd_neigh_bytes(const cd_neigh *nl) {
  size_t n = nl->n;
  size_t b = n * (2 * sizeof(int32_t) + sizeof(uint32_t) + 2 * sizeof(uint16_t) +
                  3 * sizeof(float) + 3 * sizeof(float));
  b += (nl->ncells + 1) * sizeof(int32_t);
  for (int l = 0; l < nl->nlayer; l++) b += nl->buf_cap[l] * sizeof(int32_t);
  return b;
}

size_t cd_neigh_pairs(const cd_neigh *nl) {
  size_t np = 0;
  for (int l = 0; l < nl->nlayer; l++)
    for (int32_t q = nl->layer_start[l]; q < nl->layer_start[l + 1]; q++)
      np += (size_t)nl->nplain[q] + nl->nimg[q];
  return nl->full ? np / 2 : np;
}

/* Of particles [0, n): {max|Δ|², max Δx, max Δy, max Δz, −min Δx, −min Δy, −min Δz}, Δ the
 * displacement since the last build; all INFINITY if some position is not finite. */
static void displacement_extent(const cd_neigh *nl, const ptl_state *p, long n, double ext[7]) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  const float *restrict xb = nl->xb, *restrict yb = nl->yb, *restrict zb = nl->zb;
  double d2max = 0.0, hx = -INFINITY, hy = -INFINITY, hz = -INFINITY;
  double lx = -INFINITY, ly = -INFINITY, lz = -INFINITY; /* −min, so that all seven are maxima */
  int nan_seen = 0;                                      /* the maxima skip NaN */
#pragma omp parallel for simd schedule(static)                                                     \
    reduction(max                                                                                  \
              : d2max, hx, hy, hz, lx, ly, lz, nan_seen) if (CD_PAR(n))
  for (long i = 0; i < n; i++) {
    const double dx = x[i] - xb[i], dy = y[i] - yb[i], dz = z[i] - zb[i];
    cd_extent_update(dx, dy, dz, &d2max, &hx, &hy, &hz, &lx, &ly, &lz, &nan_seen);
  }
  cd_extents_finish(ext, d2max, hx, hy, hz, lx, ly, lz, nan_seen);
}

/* max |Δ − c|² over particles [0, n), c fixed */
static double spread2(const cd_neigh *nl, const ptl_state *p, long n, const double c[3]) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  const float *restrict xb = nl->xb, *restrict yb = nl->yb, *restrict zb = nl->zb;
  const double cx = c[0], cy = c[1], cz = c[2];
  double m2 = 0.0;
#pragma omp parallel for simd schedule(static) reduction(max : m2) if (CD_PAR(n))
  for (long i = 0; i < n; i++) {
    const double dx = x[i] - xb[i] - cx, dy = y[i] - yb[i] - cy, dz = z[i] - zb[i] - cz;
    const double d2 = dx * dx + dy * dy + dz * dz;
    m2 = d2 > m2 ? d2 : m2;
  }
  return m2;
}

bool cd_neigh_holds(const cd_neigh *nl, const ptl_state *p, long n, double bound, double reach,
                    bool dd, const double *known_ext) {
  const double margin = nl->xb_err + reach; /* NaN reach: no margin is left */
  if (bound < 0.5 * nl->skin - margin) return true;
  double ext[8];
  if (known_ext) memcpy(ext, known_ext, 7 * sizeof *ext);
  else displacement_extent(nl, p, n, ext);
  ext[7] = margin < INFINITY ? margin : INFINITY;
  if (dd) par_max_doubles(ext, 8); /* the RKN reach differs between ranks */
  const double half = 0.5 * nl->skin - ext[7];
  if (!(half > 0.0)) return false;
  const double h2 = half * half;
  if (ext[0] <= h2) return true; /* every |Δ| within skin/2 */
  double c[3], box2 = 0.0, wmax = 0.0;
  for (int a = 0; a < 3; a++) {
    const double w = 0.5 * (ext[1 + a] + ext[4 + a]);
    c[a] = 0.5 * (ext[1 + a] - ext[4 + a]);
    box2 += w * w;
    wmax = w > wmax ? w : wmax;
  }
  if (box2 <= h2) return true;       /* the whole bounding box within skin/2 of its centre */
  if (!(wmax <= half)) return false; /* some |Δ − c| > skin/2 for every c */
  double m2 = spread2(nl, p, n, c);  /* the distance to the centre itself: a second pass */
  if (dd) m2 = par_max_double(m2);
  return m2 <= h2;
}

static bool is_partner(const int32_t *partners, int32_t i, int32_t j) {
  const int32_t *pi = partners + (size_t)i * CD_MAX_PARTNERS;
  for (int k = 0; k < CD_MAX_PARTNERS; k++)
    if (pi[k] == j) return true;
  return false;
}

/* Build the lists of one layer into its buffer; returns the entries needed (the buffer was
 * large enough iff the result is <= its capacity). */
/* candidates inside r_list per particle: far above any packing (fcc: 12 within 1.3 r0 even
 * at δ = 2 with the second shell; 50 would mean near-overlapping particles) */
#define CD_MAX_CAND 510

/* One range of a cell's stencil: sorted positions q0 .. q1 − 1 with their image code; `same`
 * ranges (same layer, or no colouring) keep only q > p (cd_impl.h). */
typedef struct stencil_range {
  int32_t q0, q1;
  int code;
  bool same;
} stencil_range;

/* Image code of the shift (s0, s1, s2) along the axes ax[0..2]: 13 is no image. */
static inline int stencil_code(const int ax[3], int s0, int s1, int s2) {
  int sh[3];
  sh[ax[0]] = s0;
  sh[ax[1]] = s1;
  sh[ax[2]] = s2;
  return (sh[0] + 1) + 3 * (sh[1] + 1) + 9 * (sh[2] + 1);
}

/* Append a range to the stencil, merged with the previous one when contiguous with it. Empty
 * ranges, and `same` ranges wholly before the cell's first position `cell_q0` (no particle of
 * the cell takes them), are dropped: the candidates each particle sees are unchanged. */
static inline void add_range(stencil_range *st, int *nst, int32_t q0, int32_t q1, int code,
                             bool same, int32_t cell_q0) {
  if (q0 == q1 || (same && q1 <= cell_q0)) return;
  stencil_range *last = *nst > 0 ? st + *nst - 1 : NULL;
  if (last && last->q1 == q0 && last->code == code && last->same == same) last->q1 = q1;
  else st[(*nst)++] = (stencil_range){q0, q1, code, same};
}

/* Full lists: store the group of `nlane` positions from g0 (their counts already in nplain,
 * nimg) in the layout of cd_impl.h; returns the new length (entries are written only while
 * they fit in cap; padding entries of shorter lists are 0, never read). */
static size_t flush_group(cd_neigh *nl, int32_t *buf, size_t cap, size_t len, int32_t g0, int nlane,
                          int32_t gcand[][CD_MAX_CAND + 16], int32_t gimg[][CD_MAX_CAND + 2]) {
  int kmax = 0;
  for (int l = 0; l < nlane; l++) kmax = nl->nplain[g0 + l] > kmax ? nl->nplain[g0 + l] : kmax;
  if (len + (size_t)CD_GROUP * kmax <= cap)
    for (int k = 0; k < kmax; k++)
      for (int l = 0; l < CD_GROUP; l++)
        buf[len + (size_t)CD_GROUP * k + l] = l < nlane && k < nl->nplain[g0 + l] ? gcand[l][k] : 0;
  len += (size_t)CD_GROUP * kmax;
  for (int l = 0; l < nlane; l++) {
    const size_t m = 2 * (size_t)nl->nimg[g0 + l];
    if (len + m <= cap) memcpy(buf + len, gimg[l], m * sizeof *buf);
    nl->first[g0 + l] = (uint32_t)len;
    len += m;
  }
  return len;
}

/* The stencil of cell c (its layer's cell, axes ax): the ranges of sorted positions of its
 * 3 x 3 x 3 neighbour cells with their image codes, in the order the lists are built; returns
 * their number (at most 27). */
static int cell_stencil(const cd_neigh *nl, const bool per[3], const int ax[3], int32_t c,
                        stencil_range st[27]) {
  const int n0 = nl->ncell[ax[0]], n1 = nl->ncell[ax[1]], n2 = nl->ncell[ax[2]];
  const int32_t *cs = nl->cell_start;
  const int k[3] = {c / (n1 * n2), (c / n2) % n1, c % n2};
  int nst = 0;
  for (int o0 = -1; o0 <= 1; o0++) {
    int m0 = k[0] + o0, s0 = 0;
    if (m0 < 0) {
      if (!per[0]) continue;
      m0 += n0;
      s0 = -1;
    }
    if (m0 >= n0) {
      if (!per[0]) continue;
      m0 -= n0;
      s0 = 1;
    }
    bool same_layer = (m0 == k[0]) && (s0 == 0 || n0 == 1);
    bool next_layer = false;
    if (nl->colour) {
      int nxt = k[0] + 1;
      if (nxt == n0) nxt = per[0] ? 0 : -1;
      next_layer = (m0 == nxt) && !same_layer;
      if (!same_layer && !next_layer && !nl->full) continue;
    }
    for (int o1 = -1; o1 <= 1; o1++) {
      int m1 = k[1] + o1, s1 = 0;
      if (m1 < 0) {
        if (!per[1]) continue;
        m1 += n1;
        s1 = -1;
      }
      if (m1 >= n1) {
        if (!per[1]) continue;
        m1 -= n1;
        s1 = 1;
      }
      const bool same = !next_layer && !nl->full; /* full lists keep q < p too */
      const int32_t row = (m0 * n1 + m1) * n2;
      if (k[2] >= 1 && k[2] + 1 < n2) { /* the row's three cells are contiguous: one range */
        add_range(st, &nst, cs[row + k[2] - 1], cs[row + k[2] + 2], stencil_code(ax, s0, s1, 0),
                  same, cs[c]);
        continue;
      }
      for (int o2 = -1; o2 <= 1; o2++) {
        int m2 = k[2] + o2, s2 = 0;
        if (m2 < 0) {
          if (!per[2]) continue;
          m2 += n2;
          s2 = -1;
        }
        if (m2 >= n2) {
          if (!per[2]) continue;
          m2 -= n2;
          s2 = 1;
        }
        add_range(st, &nst, cs[row + m2], cs[row + m2 + 1], stencil_code(ax, s0, s1, s2), same,
                  cs[c]);
      }
    }
  }
  return nst;
}

MS_KERNEL_CLONES CD_KERNEL_FLATTEN static size_t build_layer(cd_neigh *nl, const ptl_state *p,
                                                             const cd_box *box, int layer,
                                                             const int ax[3],
                                                             const int32_t *partners, float rl2) {
  const int n1 = nl->ncell[ax[1]], n2 = nl->ncell[ax[2]];
  const bool per[3] = {box->bc[ax[0]] == CD_BC_PERIODIC, box->bc[ax[1]] == CD_BC_PERIODIC,
                       box->bc[ax[2]] == CD_BC_PERIODIC};
  const int32_t nloc = (int32_t)p->nlocal;
  int32_t *buf = nl->buf[layer];
  size_t cap = nl->buf_cap[layer], len = 0;
  int32_t cand[CD_MAX_CAND + 16], img[CD_MAX_CAND + 2]; /* one particle's candidates */
  int32_t imgj[CD_MAX_CAND / 2 + 16];
  /* full lists: the lists of the current group (cd_impl.h) */
  int32_t gcand[CD_GROUP][CD_MAX_CAND + 16], gimg[CD_GROUP][CD_MAX_CAND + 2];
  const int32_t ls = nl->layer_start[layer], le = nl->layer_start[layer + 1];
  /* the stencil of one cell: ranges of sorted positions with their image code; `same` ranges
   * (same layer, or no colouring) keep only q > p (cd_impl.h) */
  stencil_range st[27];
  const int32_t c_begin = (int32_t)layer * n1 * n2, c_end = c_begin + n1 * n2;
  for (int32_t c = c_begin; c < c_end; c++) {
    if (nl->cell_start[c] == nl->cell_start[c + 1]) continue;
    const int nst = cell_stencil(nl, per, ax, c, st);
    for (int32_t pos = nl->cell_start[c]; pos < nl->cell_start[c + 1]; pos++) {
      const int32_t i = nl->sorted[pos];
      const float xi = nl->xs[pos], yi = nl->ys[pos], zi = nl->zs[pos];
      const size_t start = len;
      int nimg = 0, nc = 0;
      for (int e = 0; e < nst; e++) {
        int32_t q0 = st[e].q0, q1 = st[e].q1;
        if (st[e].same && q0 <= pos) q0 = pos + 1;
        if (st[e].code == 13) {
          /* branchless: store every candidate, advance only for those inside r_list */
          if (q1 - q0 > CD_MAX_CAND - nc) {
            q1 = q0 + (CD_MAX_CAND - nc);
            nl->overfull = true;
          }
          if (q0 <= pos && pos < q1) { /* full lists: the range around the particle itself */
            nc += select_range(nl, q0, pos, NULL, xi, yi, zi, rl2, cand + nc);
            q0 = pos + 1;
          }
          nc += select_range(nl, q0, q1, NULL, xi, yi, zi, rl2, cand + nc);
        } else {
          const float sv[3] = {(float)nl->shift[st[e].code][0], (float)nl->shift[st[e].code][1],
                               (float)nl->shift[st[e].code][2]};
          if (q1 - q0 > CD_MAX_CAND / 2 - nimg) {
            q1 = q0 + (CD_MAX_CAND / 2 - nimg);
            nl->overfull = true;
          }
          const int m = select_range(nl, q0, q1, sv, xi, yi, zi, rl2, imgj);
          for (int q = 0; q < m; q++, nimg++) {
            img[2 * nimg] = imgj[q];
            img[2 * nimg + 1] = st[e].code;
          }
        }
      }
      if (i >= nloc && nl->full) { /* full lists: an owned particle's row holds its ghosts */
        nc = nimg = 0;
      } else if (i >= nloc) { /* a ghost lists owned particles only: no ghost-ghost pairs */
        int m = 0;
        for (int q = 0; q < nc; q++)
          if (cand[q] < nloc) cand[m++] = cand[q];
        nc = m;
        m = 0;
        for (int q = 0; q < nimg; q++)
          if (img[2 * q] < nloc) {
            img[2 * m] = img[2 * q];
            img[2 * m + 1] = img[2 * q + 1];
            m++;
          }
        nimg = m;
      }
      if (partners) {
        for (int q = 0; q < nc; q++)
          if (is_partner(partners, i, cand[q])) cand[q] |= CD_NB_BONDED;
        for (int q = 0; q < nimg; q++)
          if (is_partner(partners, i, img[2 * q])) img[2 * q] |= CD_NB_BONDED;
      }
      nl->nplain[pos] = (uint16_t)nc;
      nl->nimg[pos] = (uint16_t)nimg;
      if (nl->full) { /* staged until its group of CD_GROUP positions is complete */
        const int lane = (pos - ls) % CD_GROUP;
        memcpy(gcand[lane], cand, (size_t)nc * sizeof *cand);
        memcpy(gimg[lane], img, 2 * (size_t)nimg * sizeof *img);
        if (lane == CD_GROUP - 1 || pos == le - 1)
          len = flush_group(nl, buf, cap, len, pos - lane, lane + 1, gcand, gimg);
        continue;
      }
      if (len + (size_t)nc + 2 * (size_t)nimg <= cap) {
        memcpy(buf + len, cand, (size_t)nc * sizeof *cand);
        memcpy(buf + len + nc, img, 2 * (size_t)nimg * sizeof *img);
      }
      len += (size_t)nc + 2 * (size_t)nimg;
      nl->first[pos] = (uint32_t)start;
    }
  }
  nl->buf_len[layer] = len;
  return len;
}

/* Renumber the particles into cell order (memory order = traversal order, so the neighbours
 * of a particle sit next to it in memory). sorted[] becomes the identity. Removed particles
 * go last. */
static void reorder_particles(cd_neigh *nl, ptl_state *p, int32_t *partners, int32_t nsorted) {
  const size_t n = p->n;
  size_t k = (size_t)nsorted;
  for (size_t i = 0; i < n; i++)
    if (nl->cell_of[i] < 0) nl->sorted[k++] = (int32_t)i;
  const int32_t *perm = nl->sorted;
  double *tmp = (double *)(void *)nl->xs; /* xs/ys/zs are refilled after the renumbering */
  double *arr[] = {p->x, p->y, p->z, p->vx, p->vy, p->vz, p->fx, p->fy, p->fz, p->mass};
  for (size_t a = 0; a < sizeof arr / sizeof *arr; a++) {
    double *v = arr[a];
#pragma omp parallel for schedule(static) if (CD_PAR(n))
    for (long q = 0; q < (long)n; q++) tmp[q] = v[perm[q]];
    memcpy(v, tmp, n * sizeof *v);
  }
  int64_t *g = (int64_t *)(void *)nl->xs;
  for (size_t q = 0; q < n; q++) g[q] = p->gid[perm[q]];
  memcpy(p->gid, g, n * sizeof *g);
  uint8_t *b = (uint8_t *)(void *)nl->xs;
  for (size_t q = 0; q < n; q++) b[q] = p->mat[perm[q]];
  memcpy(p->mat, b, n);
  for (size_t q = 0; q < n; q++) b[q] = p->flags[perm[q]];
  memcpy(p->flags, b, n);
  int32_t *c = (int32_t *)(void *)nl->xs;
  for (size_t q = 0; q < n; q++) c[q] = nl->cell_of[perm[q]];
  memcpy(nl->cell_of, c, n * sizeof *c);
  if (partners) {
    uint32_t *inv = nl->first;
    for (size_t q = 0; q < n; q++) inv[perm[q]] = (uint32_t)q;
    int32_t *rows = ms_calloc(n * CD_MAX_PARTNERS, sizeof *rows); /* bonded mode only */
    for (size_t q = 0; q < n; q++)
      for (int m = 0; m < CD_MAX_PARTNERS; m++) {
        int32_t j = partners[(size_t)perm[q] * CD_MAX_PARTNERS + m];
        rows[q * CD_MAX_PARTNERS + m] = j >= 0 ? (int32_t)inv[j] : -1;
      }
    memcpy(partners, rows, n * CD_MAX_PARTNERS * sizeof *rows);
    free(rows);
  }
  for (size_t q = 0; q < n; q++) nl->sorted[q] = (int32_t)q;
}

/* The cell grid of a build: along a periodic axis the box (positions wrapped into it), else the
 * extent of the particles; about r_list wide cells, at most ~f n + 64 of them (f =
 * nl->cell_factor, 2 unless a build overflowed); the image
 * shifts. MS_ERR_INPUT: a periodic axis shorter than 2 r_list. */
static ms_status grid_extent(cd_neigh *nl, ptl_state *p, const cd_box *box, double L[3],
                             double lo[3], int nc[3]) {
  const size_t n = p->n;
  double *pos[3] = {p->x, p->y, p->z};
  for (int a = 0; a < 3; a++) {
    if (box->bc[a] == CD_BC_PERIODIC) {
      lo[a] = box->lo[a];
      L[a] = box->hi[a] - box->lo[a];
      if (!(L[a] >= 2.0 * nl->rlist)) return MS_ERR_INPUT;
      double *xa = pos[a];
      double la = lo[a], len = L[a];
#pragma omp parallel for schedule(static) if (CD_PAR(n))
      for (long i = 0; i < (long)n; i++) {
        double w = xa[i] - la;
        if (w < 0.0 || w >= len) xa[i] -= len * floor(w / len);
        if (xa[i] >= la + len) xa[i] -= len; /* round-off of the line above */
      }
      nc[a] = (int)floor(L[a] / nl->rlist);
      if (nc[a] < 1) nc[a] = 1;
    } else {
      double mn = INFINITY, mx = -INFINITY;
      const double *xa = pos[a];
#pragma omp parallel for schedule(static) reduction(min : mn) reduction(max : mx) if (CD_PAR(n))
      for (long i = 0; i < (long)n; i++) {
        if (p->flags[i] & PTL_REMOVED) continue;
        if (xa[i] < mn) mn = xa[i];
        if (xa[i] > mx) mx = xa[i];
      }
      if (!(mx >= mn)) mn = mx = 0.0;
      lo[a] = mn;
      L[a] = mx - mn;
      nc[a] = (int)floor(L[a] / nl->rlist);
      if (nc[a] < 1) nc[a] = 1;
    }
  }
  /* Cap the cell count (a few far-flung particles must not create millions of empty cells);
   * cd_neigh_build raises the factor when the capped cells hold too many particles. */
  const double factor = nl->cell_factor > 0 ? nl->cell_factor : 2;
  for (;;) {
    double tot = (double)nc[0] * nc[1] * nc[2];
    if (tot <= factor * (double)n + 64.0) break;
    int big = 0;
    for (int a = 1; a < 3; a++)
      if (nc[a] > nc[big]) big = a;
    nc[big] = (nc[big] + 1) / 2;
  }
  for (int a = 0; a < 3; a++) {
    nl->ncell[a] = nc[a];
    nl->cell_lo[a] = lo[a];
    double w = L[a] / nc[a];
    if (w < nl->rlist) w = nl->rlist;
    nl->cell_inv_w[a] = 1.0 / w;
  }
  for (int c = 0; c < 27; c++) {
    int s[3] = {c % 3 - 1, (c / 3) % 3 - 1, c / 9 - 1};
    for (int a = 0; a < 3; a++) nl->shift[c][a] = s[a] * L[a];
  }
  return MS_OK;
}

/* The cell starts of ncells cells and the per-layer buffers of n0 layers (grown, never
 * shrunk). */
static void grid_storage(cd_neigh *nl, size_t ncells, int n0) {
  if (ncells + 1 > nl->cells_cap) {
    free(nl->cell_start);
    nl->cells_cap = ncells + 1 + ncells / 4;
    nl->cell_start = ms_calloc(nl->cells_cap, sizeof *nl->cell_start);
  }
  nl->ncells = ncells;
  if (n0 + 1 > nl->layers_cap) {
    int old = nl->layers_cap, cap = n0 + 1 + n0 / 4;
    nl->buf = ms_realloc(nl->buf, (size_t)cap, sizeof *nl->buf);
    nl->buf_cap = ms_realloc(nl->buf_cap, (size_t)cap, sizeof *nl->buf_cap);
    nl->buf_len = ms_realloc(nl->buf_len, (size_t)cap, sizeof *nl->buf_len);
    nl->layer_start = ms_realloc(nl->layer_start, (size_t)cap + 1, sizeof *nl->layer_start);
    nl->phase_layer = ms_realloc(nl->phase_layer, (size_t)cap, sizeof *nl->phase_layer);
    for (int l = old; l < cap; l++) {
      nl->buf[l] = NULL;
      nl->buf_cap[l] = 0;
      nl->buf_len[l] = 0;
    }
    nl->layers_cap = cap;
  }
  nl->nlayer = n0;
}

/* Colouring (cd_impl.h): the phases of layers that may be built and used in parallel. */
static void set_colouring(cd_neigh *nl, int n0, bool per0) {
  nl->colour = n0 >= 4;
  if (nl->colour) {
    int k = 0;
    nl->phase_start[0] = 0;
    int last_alone = per0 && (n0 % 2 == 1);
    for (int l = 0; l < n0; l += 2)
      if (!(last_alone && l == n0 - 1)) nl->phase_layer[k++] = l;
    nl->phase_start[1] = k;
    for (int l = 1; l < n0; l += 2) nl->phase_layer[k++] = l;
    nl->phase_start[2] = k;
    if (last_alone) nl->phase_layer[k++] = n0 - 1;
    nl->phase_start[3] = k;
    nl->nphase = last_alone ? 3 : 2;
  } else {
    for (int l = 0; l < n0; l++) nl->phase_layer[l] = l;
    nl->phase_start[0] = 0;
    nl->phase_start[1] = n0;
    nl->nphase = 1;
  }
}

static ms_status neigh_build_once(cd_neigh *nl, ptl_state *p, const cd_box *box, int32_t *partners,
                                  bool reorder);

/* A build; when a capped cell grid is too coarse (a debris cloud spread far: some particle's
 * cell rows hold more than CD_MAX_CAND candidates), the cap is raised fourfold, up to 128 n
 * cells, and the build redone (the lists are then complete); the raised cap stays for later
 * builds. A run whose grid never overflows builds exactly as with the cap 2 n + 64. */
ms_status cd_neigh_build(cd_neigh *nl, ptl_state *p, const cd_box *box, int32_t *partners,
                         bool reorder) {
  if (nl->cell_factor <= 0) nl->cell_factor = 2;
  ms_status st = neigh_build_once(nl, p, box, partners, reorder);
  while (st == MS_ERR_UNSTABLE && nl->overfull && nl->cell_factor < 128) {
    nl->cell_factor *= 4;
    nl->nbuild--; /* the same build, redone */
    st = neigh_build_once(nl, p, box, partners, false);
  }
  return st;
}

static ms_status neigh_build_once(cd_neigh *nl, ptl_state *p, const cd_box *box, int32_t *partners,
                                  bool reorder) {
  const size_t n = p->n;
  double *pos[3] = {p->x, p->y, p->z};
  double L[3] = {0, 0, 0}, lo[3] = {0, 0, 0};
  int nc[3];
  ms_status st = grid_extent(nl, p, box, L, lo, nc);
  if (st != MS_OK) return st;
  int ax[3] = {2, 0, 1}; /* slab axis: most cells, z on ties */
  if (nc[1] > nc[ax[0]]) ax[0] = 1;
  if (nc[0] > nc[ax[0]]) ax[0] = 0;
  for (int a = 0, k = 1; a < 3; a++)
    if (a != ax[0]) ax[k++] = a;
  nl->slab_axis = ax[0];
  const int n0 = nc[ax[0]], n1 = nc[ax[1]], n2 = nc[ax[2]];
  const size_t ncells = (size_t)n0 * n1 * n2;
  grid_storage(nl, ncells, n0);

  /* Bin: stable counting sort into cell order. */
  int32_t *cs = nl->cell_start;
  memset(cs, 0, (ncells + 1) * sizeof *cs);
  double inv[3] = {nl->cell_inv_w[ax[0]], nl->cell_inv_w[ax[1]], nl->cell_inv_w[ax[2]]};
  double l0[3] = {lo[ax[0]], lo[ax[1]], lo[ax[2]]};
  const double *pa0 = pos[ax[0]], *pa1 = pos[ax[1]], *pa2 = pos[ax[2]];
#pragma omp parallel for schedule(static) if (CD_PAR(n))
  for (long i = 0; i < (long)n; i++) {
    if (p->flags[i] & PTL_REMOVED) {
      nl->cell_of[i] = -1;
      continue;
    }
    int k0 = (int)((pa0[i] - l0[0]) * inv[0]);
    int k1 = (int)((pa1[i] - l0[1]) * inv[1]);
    int k2 = (int)((pa2[i] - l0[2]) * inv[2]);
    k0 = k0 < 0 ? 0 : (k0 >= n0 ? n0 - 1 : k0);
    k1 = k1 < 0 ? 0 : (k1 >= n1 ? n1 - 1 : k1);
    k2 = k2 < 0 ? 0 : (k2 >= n2 ? n2 - 1 : k2);
    nl->cell_of[i] = (k0 * n1 + k1) * n2 + k2;
  }
  for (size_t i = 0; i < n; i++)
    if (nl->cell_of[i] >= 0) cs[nl->cell_of[i] + 1]++;
  for (size_t c = 0; c < ncells; c++) cs[c + 1] += cs[c];
  {
    /* cs[c] serves as the running cursor of cell c, then is shifted back by one cell */
    for (size_t i = 0; i < n; i++) {
      int32_t c = nl->cell_of[i];
      if (c < 0) continue;
      nl->sorted[cs[c]++] = (int32_t)i;
    }
    for (size_t c = ncells; c > 0; c--) cs[c] = cs[c - 1];
    cs[0] = 0;
  }
  for (int l = 0; l <= n0; l++) nl->layer_start[l] = cs[(size_t)l * n1 * n2];
  /* with ghosts (MPI) the owned particles must stay in [0, nlocal): cd_par.c sorts them */
  if (reorder && p->nlocal == n) reorder_particles(nl, p, partners ? partners : NULL, cs[ncells]);
  /* positions in cell order, so that the candidate tests read them contiguously */
  const int32_t nsorted = cs[ncells];
#pragma omp parallel for schedule(static) if (CD_PAR(n))
  for (int32_t q = 0; q < nsorted; q++) {
    const int32_t i = nl->sorted[q];
    nl->xs[q] = (float)p->x[i];
    nl->ys[q] = (float)p->y[i];
    nl->zs[q] = (float)p->z[i];
  }

  /* Colouring (cd_impl.h). */
  const bool per0 = box->bc[ax[0]] == CD_BC_PERIODIC;
  set_colouring(nl, n0, per0);

  /* Lists, layer by layer; grow the buffers that were too small and redo those layers. */
  for (int l = 0; l < n0; l++) {
    size_t np = (size_t)(nl->layer_start[l + 1] - nl->layer_start[l]);
    size_t want = np * (nl->full ? 13 : 8) + 64; /* fcc: 6 (12) entries per particle */
    if (nl->buf_cap[l] < want / 2 || nl->buf[l] == NULL) {
      free(nl->buf[l]);
      nl->buf[l] = ms_calloc(want, sizeof(int32_t));
      nl->buf_cap[l] = want;
    }
  }
  /* r_list² for the float candidate test, widened by its rounding: per component of d, the
   * roundings of x_i, x_j (|x| <= amax), of the shift (<= L) and of the sums and the
   * difference are each at most 2^-24 of their size; d² has 3 more roundings. */
  double amax = 0.0, lmax = 0.0;
  for (int a = 0; a < 3; a++) {
    amax = fmax(amax, fmax(fabs(lo[a]), fabs(lo[a] + L[a])) + nl->rlist);
    lmax = fmax(lmax, L[a]);
  }
  const double ulp = 0x1.0p-24,
               derr = 1.7320508075688772 * ulp * (4 * amax + 3 * lmax + 2 * nl->rlist);
  const float rl2f =
      nextafterf((float)((nl->rlist + derr) * (nl->rlist + derr) * (1.0 + 8 * ulp)), INFINITY);
  int again;
  nl->overfull = false;
  do {
    again = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : again) if (CD_PAR(p->n))
    for (int l = 0; l < n0; l++) {
      size_t need = build_layer(nl, p, box, l, ax, partners, rl2f);
      if (need > nl->buf_cap[l]) again++;
    }
    if (again)
      for (int l = 0; l < n0; l++)
        if (nl->buf_len[l] > nl->buf_cap[l]) {
          size_t want = nl->buf_len[l] + nl->buf_len[l] / 4 + 64;
          free(nl->buf[l]);
          nl->buf[l] = ms_calloc(want, sizeof(int32_t));
          nl->buf_cap[l] = want;
        }
  } while (again);

  amax = 0.0;
#pragma omp parallel for schedule(static) reduction(max : amax) if (CD_PAR(n))
  for (long i = 0; i < (long)n; i++) {
    nl->xb[i] = (float)p->x[i];
    nl->yb[i] = (float)p->y[i];
    nl->zb[i] = (float)p->z[i];
    double ax = fabs(p->x[i]), ay = fabs(p->y[i]), az = fabs(p->z[i]);
    double m = ax > ay ? ax : ay;
    m = m > az ? m : az;
    amax = m > amax ? m : amax;
  }
  /* float rounding: |x − float(x)| <= 2^-24 |x| per component, so <= √3·2^-24·max|x| */
  nl->xb_err = 1.7320508075688772 * 0x1.0p-24 * amax * 1.01;
  nl->n = n;
  nl->nbuild++;
  return nl->overfull ? MS_ERR_UNSTABLE : MS_OK; /* particles piled on top of each other */
}
