/* SPDX-License-Identifier: MIT */
/* cd_partition.c — partition of the cluster-dynamics coarse-cell grid over MPI ranks
 * (docs/mpi.md "Partitioning the cluster-dynamics region").
 *
 * The particle region is covered by a grid of coarse cells, each weighted by its particle
 * count. A part (rank) owns whole cells; its ghosts are the particles of the cells adjacent to
 * it, so the communication of a step is proportional to the halo cells and the edges of the
 * 26-neighbour cell graph cut by the partition. Methods:
 *   - slabs: the cells in plane-major order along one axis, cut where the cumulative weight
 *     crosses k·W/nparts (a cell goes to the part holding the midpoint of its weight), so a cut
 *     may fall inside a plane;
 *   - METIS k-way on the 26-neighbour graph, vertex weight = weight + 1 (no cell weighs 0),
 *     unit edge weights, fixed seed. Callers pass particle counts scaled up (cd_par.c: 64 per
 *     particle) so that an empty cell weighs next to nothing: with unscaled counts the many
 *     empty cells around ejecta weighed as much as particles and the particle imbalance of the
 *     default deck's late snapshot was 1.36–1.48 instead of 1.01–1.12 (docs/benchmarks.md).
 *   - auto: both, keeping the map of the lower load (max over parts of the owned weight plus
 *     CD_PART_GHOST_COST × the weight of its halo cells): slabs on a uniform block (no halo
 *     beyond the cut planes), METIS when the particles are unevenly spread (ejecta).
 * All are pure functions of their input, so every rank computes the same map without a
 * broadcast (METIS is deterministic for a fixed seed and input on one build).
 */
#include "cd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The distinct neighbours of cell (ix, iy, iz) in the 26-neighbour stencil, periodic axes
 * wrapped, the cell itself excluded (a periodic axis of 1 or 2 cells maps several offsets onto
 * the same cell). Returns the count (≤ 26), neighbours in stencil order. */
static int cell_neighbours(const int ncell[3], const bool periodic[3], int ix, int iy, int iz,
                           int64_t *out) {
  const int64_t self = ix + (int64_t)ncell[0] * (iy + (int64_t)ncell[1] * iz);
  int n = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        int q[3] = {ix + dx, iy + dy, iz + dz};
        bool ok = true;
        for (int a = 0; a < 3 && ok; ++a) {
          if (q[a] >= 0 && q[a] < ncell[a]) continue;
          if (!periodic[a]) ok = false;
          else q[a] = (q[a] + ncell[a]) % ncell[a];
        }
        if (!ok) continue;
        int64_t c = q[0] + (int64_t)ncell[0] * (q[1] + (int64_t)ncell[1] * q[2]);
        if (c == self) continue;
        bool seen = false;
        for (int m = 0; m < n && !seen; ++m) seen = out[m] == c;
        if (!seen) out[n++] = c;
      }
  return n;
}

/* The 26-neighbour graph in CSR form (METIS's xadj/adjncy). */
typedef struct cell_graph {
  int32_t nv;
  int32_t *xadj, *adj;
} cell_graph;

static void graph_build(const int ncell[3], const bool periodic[3], cell_graph *g) {
  const int64_t nv = (int64_t)ncell[0] * ncell[1] * ncell[2];
  g->nv = (int32_t)nv;
  g->xadj = ms_calloc((size_t)nv + 1, sizeof(int32_t));
  g->adj = ms_calloc((size_t)nv * 26 + 1, sizeof(int32_t));
  int64_t nb[26];
  size_t na = 0;
  for (int iz = 0; iz < ncell[2]; ++iz)
    for (int iy = 0; iy < ncell[1]; ++iy)
      for (int ix = 0; ix < ncell[0]; ++ix) {
        int64_t c = ix + (int64_t)ncell[0] * (iy + (int64_t)ncell[1] * iz);
        int k = cell_neighbours(ncell, periodic, ix, iy, iz, nb);
        for (int m = 0; m < k; ++m) g->adj[na++] = (int32_t)nb[m];
        g->xadj[c + 1] = (int32_t)na;
      }
}

static void graph_free(cell_graph *g) {
  free(g->xadj);
  free(g->adj);
}

/* Slabs along `axis`: the cells in plane-major order (the plane along `axis`, then the rows
 * along the lower other axis, then the higher one) cut into nparts contiguous runs by
 * cumulative weight; a cell goes to the part holding the midpoint of its weight (cuts at
 * k·W/nparts), an empty cell to the part of the cell before it. A cut therefore falls inside a
 * plane when the planes do not divide evenly: every part's weight is within one cell's weight
 * of W/nparts (43 whole planes on 2 parts gave 1.025) at the price of a step in the boundary
 * (one extra row of halo cells). Equal cell counts if every weight is 0. */
static void slab_partition(const int ncell[3], const int64_t *weight, int nparts, int axis,
                           int32_t *owner) {
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2; /* the other two axes, ascending */
  const int64_t stride[3] = {1, ncell[0], (int64_t)ncell[0] * ncell[1]};
  const int64_t nv = (int64_t)ncell[0] * ncell[1] * ncell[2];
  double total = 0;
  for (int64_t c = 0; c < nv; ++c) total += (double)weight[c];
  double acc = 0;
  int32_t last = 0;
  int64_t k = 0; /* position in plane-major order */
  for (int i0 = 0; i0 < ncell[axis]; ++i0)
    for (int i1 = 0; i1 < ncell[a1]; ++i1)
      for (int i2 = 0; i2 < ncell[a2]; ++i2, ++k) {
        const int64_t c = i0 * stride[axis] + i1 * stride[a1] + i2 * stride[a2];
        const double w = (double)weight[c];
        if (total > 0 && w == 0) {
          owner[c] = last;
          continue;
        }
        const double at = total > 0 ? (acc + 0.5 * w) / total : ((double)k + 0.5) / (double)nv;
        const int r = (int)(at * nparts);
        owner[c] = last = r < nparts ? r : nparts - 1;
        acc += w;
      }
}

static ms_status metis_partition(const cell_graph *g, const int64_t *weight, int nparts,
                                 int32_t *owner) {
  const int32_t nv = g->nv;
  if (nparts >= nv) { /* no balancing possible: one cell per part, the rest empty */
    for (int32_t c = 0; c < nv; ++c) owner[c] = c;
    return MS_OK;
  }
  /* vertex weights w + 1 in 32 bits; if their sum would overflow METIS's 32-bit index, the
   * weights are scaled down (rounded) so the total stays below 2^30 */
  double total = 0;
  for (int32_t c = 0; c < nv; ++c) total += (double)weight[c] + 1;
  const double limit = 1073741824.0; /* 2^30 */
  const double scale = total > limit ? (limit - (double)nv) / (total - (double)nv) : 1.0;
  int32_t *vwgt = ms_calloc((size_t)nv, sizeof *vwgt);
  for (int32_t c = 0; c < nv; ++c) vwgt[c] = (int32_t)llround((double)weight[c] * scale) + 1;
  const ms_status s = ptl_partition_kway(nv, g->xadj, g->adj, vwgt, NULL, nparts, 0, owner, NULL);
  free(vwgt);
  return s;
}

/* Cost of a ghost particle relative to an owned one in the load model (ptl.h): an owned fcc
 * particle inside r_list = 1.3 r0 carries 6 half-list entries and its integration; a ghost
 * adds ~1 list entry (the pairs across the cut, computed on both sides) and 3 doubles packed,
 * sent and received per force evaluation. bench/cd_mpi on 2 ranks: ~12.8k ghosts per rank
 * add 1.7 % list entries and ~1.5 % pack/copy time to 128k owned, i.e. ~0.25 each. */
#define CD_PART_GHOST_COST 0.25

/* Imbalance, edge cut, halo cells and load of a map (definitions in ptl.h). */
static void partition_stats(const cell_graph *g, const int64_t *weight, int nparts,
                            const int32_t *owner, cd_partition_stats *st) {
  double *pw = ms_calloc(2 * (size_t)nparts, sizeof(double)), *hw = pw + nparts;
  double total = 0, wmax = 0, lmax = 0;
  long cut = 0, halo = 0;
  for (int32_t c = 0; c < g->nv; ++c) {
    pw[owner[c]] += (double)weight[c];
    total += (double)weight[c];
    /* cell c is a halo cell of every other part owning one of its neighbours */
    int32_t seen[26];
    int ns = 0;
    for (int32_t e = g->xadj[c]; e < g->xadj[c + 1]; ++e) {
      int32_t q = owner[g->adj[e]];
      if (q == owner[c]) continue;
      ++cut;
      bool dup = false;
      for (int m = 0; m < ns && !dup; ++m) dup = seen[m] == q;
      if (!dup) seen[ns++] = q;
    }
    halo += ns;
    for (int m = 0; m < ns; ++m) hw[seen[m]] += (double)weight[c];
  }
  for (int r = 0; r < nparts; ++r) {
    wmax = fmax(wmax, pw[r]);
    lmax = fmax(lmax, pw[r] + CD_PART_GHOST_COST * hw[r]);
  }
  st->imbalance = total > 0 ? wmax / (total / nparts) : 1.0;
  st->load = total > 0 ? lmax / (total / nparts) : 1.0;
  st->edge_cut = cut / 2; /* every cut edge was seen from both ends */
  st->halo_cells = halo;
  free(pw);
}

static ms_status check_grid(const int ncell[3], const bool periodic[3], const int64_t *weight,
                            int nparts, const int32_t *owner) {
  if (!ncell || !periodic || !weight || !owner || nparts < 1) return MS_ERR_INPUT;
  double nv = 1;
  for (int a = 0; a < 3; ++a) {
    if (ncell[a] < 1) return MS_ERR_INPUT;
    nv *= ncell[a];
  }
  /* METIS indexes the 26 nv adjacency entries with a 32-bit index (ptl_partition_kway) */
  if (nv * 26 > 2147483647.0) return MS_ERR_INPUT;
  for (int64_t c = 0; c < (int64_t)nv; ++c)
    if (weight[c] < 0) return MS_ERR_INPUT;
  return MS_OK;
}

ms_status cd_partition_cells(const int ncell[3], const bool periodic[3], const int64_t *weight,
                             int nparts, cd_partition_method method, int slab_axis, int32_t *owner,
                             cd_partition_stats *stats) {
  if (check_grid(ncell, periodic, weight, nparts, owner) != MS_OK || slab_axis < 0 ||
      slab_axis > 2 ||
      (method != CD_PART_SLAB && method != CD_PART_METIS && method != CD_PART_AUTO))
    return MS_ERR_INPUT;
  const size_t nv = (size_t)ncell[0] * ncell[1] * ncell[2];
  cell_graph g = {0};
  const bool need_graph = stats || (method != CD_PART_SLAB && nparts > 1);
  if (need_graph) graph_build(ncell, periodic, &g);
  ms_status s = MS_OK;
  cd_partition_stats st = {.method = method == CD_PART_METIS ? CD_PART_METIS : CD_PART_SLAB,
                           .rejected_load = NAN};
  if (nparts == 1) {
    memset(owner, 0, nv * sizeof *owner);
  } else if (method == CD_PART_SLAB) {
    slab_partition(ncell, weight, nparts, slab_axis, owner);
  } else if (method == CD_PART_METIS) {
    s = metis_partition(&g, weight, nparts, owner);
  } else { /* both; the METIS map replaces the slabs if its load is lower */
    int32_t *alt = ms_calloc(nv, sizeof *alt);
    cd_partition_stats ss, sm;
    slab_partition(ncell, weight, nparts, slab_axis, owner);
    partition_stats(&g, weight, nparts, owner, &ss);
    s = metis_partition(&g, weight, nparts, alt);
    if (s == MS_OK) {
      partition_stats(&g, weight, nparts, alt, &sm);
      st.rejected_load = ss.load;
      if (sm.load < ss.load) {
        memcpy(owner, alt, nv * sizeof *owner);
        st.method = CD_PART_METIS;
      } else {
        st.rejected_load = sm.load;
      }
    }
    free(alt);
  }
  if (s == MS_OK && stats) {
    partition_stats(&g, weight, nparts, owner, &st);
    *stats = st;
  }
  if (need_graph) graph_free(&g);
  return s;
}

ms_status cd_partition_evaluate(const int ncell[3], const bool periodic[3], const int64_t *weight,
                                int nparts, const int32_t *owner, cd_partition_stats *stats) {
  if (check_grid(ncell, periodic, weight, nparts, owner) != MS_OK || !stats) return MS_ERR_INPUT;
  const size_t nv = (size_t)ncell[0] * ncell[1] * ncell[2];
  for (size_t c = 0; c < nv; ++c)
    if (owner[c] < 0 || owner[c] >= nparts) return MS_ERR_INPUT;
  cell_graph g = {0};
  graph_build(ncell, periodic, &g);
  *stats = (cd_partition_stats){.method = CD_PART_SLAB, .rejected_load = NAN};
  partition_stats(&g, weight, nparts, owner, stats);
  graph_free(&g);
  return MS_OK;
}

static int cmp_pair(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return x < y ? -1 : x > y;
}

/* Sorts and deduplicates pairs[0..n); returns the new count. */
static size_t unique_pairs(int64_t *pairs, size_t n) {
  qsort(pairs, n, sizeof *pairs, cmp_pair);
  size_t u = 0;
  for (size_t k = 0; k < n; ++k)
    if (u == 0 || pairs[k] != pairs[u - 1]) pairs[u++] = pairs[k];
  return u;
}

void cd_partition_halo(const int ncell[3], const bool periodic[3], const int32_t *owner, int nparts,
                       long *halo, int *neighbours) {
  if (halo) memset(halo, 0, (size_t)nparts * sizeof *halo);
  if (neighbours) memset(neighbours, 0, (size_t)nparts * sizeof *neighbours);
  /* adjacent part pairs (p << 32 | q), compacted whenever the buffer fills: their number is
   * O(parts × neighbours), far below the cell count */
  size_t cap = 1 << 16, np = 0;
  int64_t *pairs = ms_calloc(cap, sizeof *pairs);
  int64_t nb[26];
  for (int iz = 0; iz < ncell[2]; ++iz)
    for (int iy = 0; iy < ncell[1]; ++iy)
      for (int ix = 0; ix < ncell[0]; ++ix) {
        int64_t c = ix + (int64_t)ncell[0] * (iy + (int64_t)ncell[1] * iz);
        int k = cell_neighbours(ncell, periodic, ix, iy, iz, nb);
        int32_t seen[26];
        int ns = 0;
        for (int m = 0; m < k; ++m) {
          int32_t q = owner[nb[m]];
          bool dup = q == owner[c];
          for (int j = 0; j < ns && !dup; ++j) dup = seen[j] == q;
          if (!dup) seen[ns++] = q;
        }
        for (int j = 0; j < ns; ++j) {
          if (halo) ++halo[seen[j]]; /* c is a ghost cell of part seen[j] */
          if (np == cap) {
            np = unique_pairs(pairs, np);
            if (np > cap / 2) pairs = ms_realloc(pairs, cap *= 2, sizeof *pairs);
          }
          pairs[np++] = (int64_t)seen[j] << 32 | owner[c];
        }
      }
  np = unique_pairs(pairs, np);
  for (size_t k = 0; k < np && neighbours; ++k) ++neighbours[pairs[k] >> 32];
  free(pairs);
}
