/* SPDX-License-Identifier: MIT */
/* cd_par.c — cluster dynamics on MPI ranks: coarse-cell ownership, migration, ghosts
 * (docs/mpi.md, "Cluster dynamics on MPI ranks").
 *
 * The box is cut into coarse cells at least r_list = R_c + skin wide, so every pair that the
 * neighbour lists can hold joins particles of the same or of adjacent (26-stencil) cells. Each
 * cell belongs to one rank (cd_partition_cells on the all-reduced particle counts: every rank
 * computes the same owner map). At every list build the particles move to the owner of their
 * cell (migration), and each owned particle in a cell adjacent to another rank's cell is sent
 * there as a ghost. Between builds no pair closes in by more than the skin (the rebuild test of
 * neighbour.c), so the ghosts of the build cover every pair that can come within R_c before the
 * next one; their positions and velocities are refreshed before every force evaluation. Ghosts
 * keep their wrapped coordinates: the local list builder finds periodic images exactly as in a
 * serial run.
 *
 * Message layout: a full particle record is CD_REC doubles (x, y, z, vx, vy, vz, mass, gid, mat,
 * flags; + CD_MAX_PARTNERS partner gids in bonded mode); gids are exact in a double below 2^53.
 */
#include "cd_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { CD_REC = 10 };

struct cd_dd {
  int rank, size;
  /* coarse grid */
  int nc[3];
  double lo[3], len[3], inv_w[3];
  bool per[3];
  size_t ncells;
  int32_t *owner, *owner_new; /* [ncells] */
  long map_version;           /* bumped whenever `owner` changes */
  /* per cell of this rank: the other ranks owning a cell of its 26-stencil (foreign_ranks),
   * halo_rank[halo_start[c] .. halo_start[c+1]); empty for other ranks' cells. Rebuilt when the
   * map changed (halo_version != map_version), so a list build looks ranks up instead of
   * scanning 26 neighbours per cell twice (11 % of a rank's time in bench/cd_mpi B) */
  int32_t *halo_start;
  int *halo_rank;
  size_t halo_cap;
  long halo_version;
  int64_t *weight; /* [ncells] scratch */
  int slab_axis;
  /* per rank: migration counts and displacements (doubles) */
  int *mcnt_s, *mcnt_r, *mdsp_s, *mdsp_r;
  /* ghost neighbours: ranks, counts and displacements per neighbour (particles, then doubles) */
  int nnbr;
  int *nbr, *gcnt_s, *gcnt_r, *gdsp_s, *gdsp_r, *xcnt_s, *xcnt_r, *xdsp_s, *xdsp_r;
  int32_t *send_idx; /* owned particles sent, grouped by neighbour */
  size_t nsend, send_cap;
  double *sbuf, *rbuf;
  size_t sbuf_cap, rbuf_cap;
  int32_t *cell;    /* [cap] coarse cell of each owned particle */
  int32_t *perm;    /* [cap] sort scratch */
  double *tmp;      /* [cap] sort scratch */
  int64_t *pgid;    /* bonded: [cap][CD_MAX_PARTNERS] partner gids */
  int32_t *gid_map; /* bonded: gid -> local index, [ngid] (−1 elsewhere) */
  size_t ngid;      /* gids are creation indices, below the global count */
  long builds_since;
  bool replicated; /* until the first migration: every rank holds every particle */
  cd_mpi_stats st;
};

static void grow(double **buf, size_t *cap, size_t need) {
  if (need <= *cap) return;
  free(*buf);
  *cap = need + need / 4 + 64;
  *buf = ms_aligned_alloc(*cap, sizeof(double));
}

static int wrap_index(int k, int n) { return k < 0 ? k + n : (k >= n ? k - n : k); }

static int32_t cell_of(const cd_dd *d, double x, double y, double z) {
  const double r[3] = {x, y, z};
  int k[3];
  for (int a = 0; a < 3; a++) {
    const double u = (r[a] - d->lo[a]) * d->inv_w[a];
    /* outside (or NaN: the run stops at the next check) -> an end cell */
    k[a] = u >= 0 && u < d->nc[a] ? (int)u : (u >= d->nc[a] ? d->nc[a] - 1 : 0);
  }
  return k[0] + d->nc[0] * (k[1] + d->nc[1] * k[2]);
}

/* Ranks other than this one owning a cell of the 26-stencil of cell c (ascending, distinct). */
static int foreign_ranks(const cd_dd *d, int32_t c, int *out) {
  const int k[3] = {(int)(c % d->nc[0]), (int)((c / d->nc[0]) % d->nc[1]),
                    (int)(c / ((size_t)d->nc[0] * d->nc[1]))};
  int n = 0;
  for (int o = 0; o < 27; o++) {
    if (o == 13) continue;
    int m[3] = {k[0] + o % 3 - 1, k[1] + (o / 3) % 3 - 1, k[2] + o / 9 - 1};
    bool ok = true;
    for (int a = 0; a < 3 && ok; a++) {
      if (m[a] >= 0 && m[a] < d->nc[a]) continue;
      if (d->per[a]) m[a] = wrap_index(m[a], d->nc[a]);
      else ok = false;
    }
    if (!ok) continue;
    int r = d->owner[m[0] + d->nc[0] * (m[1] + (size_t)d->nc[1] * m[2])];
    if (r == d->rank) continue;
    int q = 0;
    while (q < n && out[q] < r) q++;
    if (q < n && out[q] == r) continue;
    memmove(out + q + 1, out + q, (size_t)(n - q) * sizeof *out);
    out[q] = r;
    n++;
  }
  return n;
}

/* The halo table of this rank's cells (struct cd_dd) for the owner map in use. */
static void update_halo(cd_dd *d) {
  if (d->halo_start && d->halo_version == d->map_version) return;
  free(d->halo_start);
  d->halo_start = ms_calloc(d->ncells + 1, sizeof *d->halo_start);
  size_t n = 0;
  int ranks[26];
  for (size_t c = 0; c < d->ncells; c++) {
    const int nr = d->owner[c] == d->rank ? foreign_ranks(d, (int32_t)c, ranks) : 0;
    if (nr == 0) {
      d->halo_start[c + 1] = (int32_t)n;
      continue;
    }
    if (n + (size_t)nr > d->halo_cap) {
      d->halo_cap = 2 * (n + (size_t)nr) + 64;
      d->halo_rank = ms_realloc(d->halo_rank, d->halo_cap, sizeof *d->halo_rank);
    }
    memcpy(d->halo_rank + n, ranks, (size_t)nr * sizeof *ranks);
    n += (size_t)nr;
    d->halo_start[c + 1] = (int32_t)n;
  }
  d->halo_version = d->map_version;
}

/* Periodic axes: positions into [lo, hi), as the list builder does (idempotent there). */
static void wrap_positions(const cd_sim *s, size_t n) {
  double *pos[3] = {s->p->x, s->p->y, s->p->z};
  for (int a = 0; a < 3; a++) {
    if (s->box.bc[a] != CD_BC_PERIODIC) continue;
    const double la = s->box.lo[a], len = s->box.hi[a] - s->box.lo[a];
    double *xa = pos[a];
    for (size_t i = 0; i < n; i++) {
      double w = xa[i] - la;
      if (w < 0.0 || w >= len) xa[i] -= len * floor(w / len);
      if (xa[i] >= la + len) xa[i] -= len;
    }
  }
}

/* Coarse grid: wall and periodic axes span the box; free axes the box given to the run if it
 * has an extent there, else the particles' extent now. Particles outside a free axis' range
 * fall into its end cells (which then are wider than r_list: still correct, since only
 * adjacency matters). */
static void make_grid(cd_sim *s) {
  cd_dd *d = s->dd;
  const double rlist = s->rc_max + s->cfg.skin;
  const double *pos[3] = {s->p->x, s->p->y, s->p->z};
  for (int a = 0; a < 3; a++) {
    double lo = s->box.lo[a], hi = s->box.hi[a];
    d->per[a] = s->box.bc[a] == CD_BC_PERIODIC;
    if (s->box.bc[a] == CD_BC_FREE && !(hi > lo)) {
      double mn = INFINITY, mx = -INFINITY;
      for (size_t i = 0; i < s->p->nlocal; i++) {
        mn = fmin(mn, pos[a][i]);
        mx = fmax(mx, pos[a][i]);
      }
      lo = par_min_double(mn);
      hi = par_max_double(mx);
      if (!(hi >= lo)) lo = hi = 0.0;
    }
    d->lo[a] = lo;
    d->len[a] = hi - lo;
    d->nc[a] = (int)fmin(floor(d->len[a] / rlist), 1 << 20);
    if (d->nc[a] < 1) d->nc[a] = 1;
  }
  /* at most ~4 million cells (the owner map is replicated on every rank) */
  while ((double)d->nc[0] * d->nc[1] * d->nc[2] > 4.0e6) {
    int big = 0;
    for (int a = 1; a < 3; a++)
      if (d->nc[a] > d->nc[big]) big = a;
    d->nc[big] = (d->nc[big] + 1) / 2;
  }
  for (int a = 0; a < 3; a++) d->inv_w[a] = d->len[a] > 0 ? d->nc[a] / d->len[a] : 0.0;
  d->slab_axis = 2;
  if (d->nc[1] > d->nc[d->slab_axis]) d->slab_axis = 1;
  if (d->nc[0] > d->nc[d->slab_axis]) d->slab_axis = 0;
  size_t ncells = (size_t)d->nc[0] * d->nc[1] * d->nc[2];
  if (ncells != d->ncells) {
    free(d->owner);
    free(d->owner_new);
    free(d->weight);
    d->ncells = ncells;
    d->owner = ms_calloc(ncells, sizeof *d->owner);
    d->map_version++; /* the halo table is sized by the grid */
    d->owner_new = ms_calloc(ncells, sizeof *d->owner_new);
    d->weight = ms_calloc(ncells, sizeof *d->weight);
  }
  for (int a = 0; a < 3; a++) d->st.ncell[a] = d->nc[a];
}

/* Owner map from the all-reduced particle counts of the cells (the same on every rank). The
 * partitioner weighs a cell weight + 1; counts are scaled by 64 so that empty cells (a free
 * axis' room for ejecta) weigh next to nothing. With `only_if_better`, the new map replaces
 * the old one only when it lowers the load (cd_partition_stats: owned + ghost cost, max over
 * ranks) by more than 1 %. Returns whether it did. */
static bool partition(cd_sim *s, bool only_if_better, ms_status *status) {
  cd_dd *d = s->dd;
  const ptl_state *p = s->p;
  memset(d->weight, 0, d->ncells * sizeof *d->weight);
  for (size_t i = 0; i < p->nlocal; i++)
    if (!(p->flags[i] & PTL_REMOVED)) d->weight[cell_of(d, p->x[i], p->y[i], p->z[i])] += 64;
  if (!d->replicated) par_sum_int64s(d->weight, d->ncells);
  cd_partition_stats ps, old;
  ms_status st = cd_partition_cells(d->nc, d->per, d->weight, d->size, s->mpi.partition,
                                    d->slab_axis, d->owner_new, &ps);
  if (st == MS_OK && only_if_better)
    st = cd_partition_evaluate(d->nc, d->per, d->weight, d->size, d->owner, &old);
  *status = par_agree_status(st);
  d->builds_since = 0;
  if (*status != MS_OK) return false;
  if (only_if_better && !(ps.load < old.load * 0.99)) return false;
  int32_t *t = d->owner;
  d->owner = d->owner_new;
  d->owner_new = t;
  d->map_version++;
  d->st.partition = ps;
  d->st.partitions++;
  return true;
}

ms_status cd_dd_create(cd_sim *s) {
  cd_dd *d = ms_calloc(1, sizeof *d);
  s->dd = d;
  d->rank = par_rank();
  d->size = par_size();
  d->st.ranks = d->size;
  ptl_state *p = s->p;
  d->replicated = s->mpi.replicated;
  d->st.global = d->replicated ? p->nlocal : (size_t)par_sum_long((long)p->nlocal);
  ptl_state_reserve(p, d->st.global); /* a rank never holds a particle twice */
  const size_t cap = p->cap + 1;
  d->cell = ms_calloc(cap, sizeof *d->cell);
  d->perm = ms_calloc(cap, sizeof *d->perm);
  d->tmp = ms_calloc(cap, sizeof *d->tmp);
  const int P = d->size;
  int **arr[] = {&d->mcnt_s, &d->mcnt_r, &d->mdsp_s, &d->mdsp_r, &d->nbr,    &d->gcnt_s, &d->gcnt_r,
                 &d->gdsp_s, &d->gdsp_r, &d->xcnt_s, &d->xcnt_r, &d->xdsp_s, &d->xdsp_r};
  for (size_t k = 0; k < sizeof arr / sizeof *arr; k++)
    *arr[k] = ms_calloc((size_t)P + 1, sizeof(int));
  if (s->cfg.cutoff == CD_CUTOFF_BONDED) {
    d->pgid = ms_aligned_alloc(cap * CD_MAX_PARTNERS, sizeof *d->pgid);
    d->ngid = cap;
    d->gid_map = ms_calloc(cap, sizeof *d->gid_map);
    for (size_t k = 0; k < cap; k++) d->gid_map[k] = -1;
  }
  make_grid(s);
  ms_status st;
  partition(s, false, &st);
  if (st == MS_OK && s->mpi.owner && s->mpi.owner_cells == d->ncells) { /* restart */
    memcpy(d->owner, s->mpi.owner, d->ncells * sizeof *d->owner);
    d->map_version++;
    const cd_partition_method m = d->st.partition.method;
    st = par_agree_status(
        cd_partition_evaluate(d->nc, d->per, d->weight, d->size, d->owner, &d->st.partition));
    d->st.partition.method = m;
  }
  return st;
}

const int32_t *cd_dd_owner(const cd_dd *d, size_t *ncells, long *builds_since) {
  *ncells = d->ncells;
  *builds_since = d->builds_since;
  return d->owner;
}

void cd_dd_set_builds_since(cd_dd *d, long builds_since) { d->builds_since = builds_since; }

void cd_dd_free(cd_dd *d) {
  if (!d) return;
  void *arr[] = {d->owner,    d->owner_new, d->weight, d->halo_start, d->halo_rank, d->mcnt_s,
                 d->mcnt_r,   d->mdsp_s,    d->mdsp_r, d->nbr,        d->gcnt_s,    d->gcnt_r,
                 d->gdsp_s,   d->gdsp_r,    d->xcnt_s, d->xcnt_r,     d->xdsp_s,    d->xdsp_r,
                 d->send_idx, d->sbuf,      d->rbuf,   d->cell,       d->perm,      d->tmp,
                 d->pgid,     d->gid_map};
  for (size_t k = 0; k < sizeof arr / sizeof *arr; k++) free(arr[k]);
  free(d);
}

void cd_dd_regrid(cd_sim *s) {
  ms_status st;
  make_grid(s);
  partition(s, false, &st);
}

bool cd_dd_owns(const cd_dd *d, const double x[3]) {
  double r[3] = {x[0], x[1], x[2]};
  for (int a = 0; a < 3; a++)
    if (d->per[a] && d->len[a] > 0) r[a] -= d->len[a] * floor((r[a] - d->lo[a]) / d->len[a]);
  return d->owner[cell_of(d, r[0], r[1], r[2])] == d->rank;
}

const cd_mpi_stats *cd_dd_stats(const cd_dd *d) { return &d->st; }

/* ---- particle records ---- */

static int rec_len(const cd_sim *s) { return CD_REC + (s->dd->pgid ? CD_MAX_PARTNERS : 0); }

static void pack(const cd_sim *s, size_t i, double *r) {
  const ptl_state *p = s->p;
  r[0] = p->x[i], r[1] = p->y[i], r[2] = p->z[i];
  r[3] = p->vx[i], r[4] = p->vy[i], r[5] = p->vz[i];
  r[6] = p->mass[i];
  r[7] = (double)p->gid[i];
  r[8] = p->mat[i];
  r[9] = p->flags[i];
  if (s->dd->pgid)
    for (int k = 0; k < CD_MAX_PARTNERS; k++)
      r[CD_REC + k] = (double)s->dd->pgid[i * CD_MAX_PARTNERS + k];
}

static void unpack(cd_sim *s, size_t i, const double *r) {
  ptl_state *p = s->p;
  p->x[i] = r[0], p->y[i] = r[1], p->z[i] = r[2];
  p->vx[i] = r[3], p->vy[i] = r[4], p->vz[i] = r[5];
  p->fx[i] = p->fy[i] = p->fz[i] = 0.0;
  p->mass[i] = r[6];
  p->gid[i] = (int64_t)r[7];
  p->mat[i] = (uint8_t)r[8];
  p->flags[i] = (uint8_t)r[9];
  if (s->dd->pgid)
    for (int k = 0; k < CD_MAX_PARTNERS; k++)
      s->dd->pgid[i * CD_MAX_PARTNERS + k] = (int64_t)r[CD_REC + k];
}

/* Copy particle i to slot k (k <= i), partner gids included. */
static void move_particle(cd_sim *s, size_t i, size_t k) {
  if (i == k) return;
  ptl_state *p = s->p;
  double *arr[] = {p->x, p->y, p->z, p->vx, p->vy, p->vz, p->fx, p->fy, p->fz, p->mass};
  for (size_t a = 0; a < sizeof arr / sizeof *arr; a++) arr[a][k] = arr[a][i];
  p->gid[k] = p->gid[i];
  p->mat[k] = p->mat[i];
  p->flags[k] = p->flags[i];
  s->dd->cell[k] = s->dd->cell[i];
  if (s->dd->pgid)
    memcpy(s->dd->pgid + k * CD_MAX_PARTNERS, s->dd->pgid + i * CD_MAX_PARTNERS,
           CD_MAX_PARTNERS * sizeof *s->dd->pgid);
}

/* Sort key of a coarse cell: its index in the list builder's traversal order (neighbour.c:
 * layer-major along the axis with most cells, z on ties, then the other two in order). The
 * coarse cells of a periodic axis are the builder's link cells, so owned particles end up in
 * the order the force loops visit them, as the serial run's renumbering arranges. */
static int32_t traversal_key(const cd_dd *d, int32_t c) {
  const int k[3] = {(int)(c % d->nc[0]), (int)((c / d->nc[0]) % d->nc[1]),
                    (int)(c / ((size_t)d->nc[0] * d->nc[1]))};
  int ax[3] = {2, 0, 1};
  if (d->nc[1] > d->nc[ax[0]]) ax[0] = 1;
  if (d->nc[0] > d->nc[ax[0]]) ax[0] = 0;
  for (int a = 0, m = 1; a < 3; a++)
    if (a != ax[0]) ax[m++] = a;
  return (int32_t)(((size_t)k[ax[0]] * d->nc[ax[1]] + k[ax[1]]) * d->nc[ax[2]] + k[ax[2]]);
}

/* Owned particles into the builder's cell order (stable counting sort), for memory locality of
 * the lists built without renumbering; d->cell follows. */
static void sort_by_cell(cd_sim *s) {
  cd_dd *d = s->dd;
  ptl_state *p = s->p;
  const size_t n = p->nlocal;
  /* counting sort through the weight array (reused as cursors), keys held in tmp */
  int64_t *cur = d->weight;
  memset(cur, 0, d->ncells * sizeof *cur);
  int32_t *key = (int32_t *)(void *)d->tmp;
  for (size_t i = 0; i < n; i++) cur[key[i] = traversal_key(d, d->cell[i])]++;
  int64_t acc = 0;
  for (size_t c = 0; c < d->ncells; c++) {
    int64_t m = cur[c];
    cur[c] = acc;
    acc += m;
  }
  for (size_t i = 0; i < n; i++) d->perm[cur[key[i]]++] = (int32_t)i; /* perm[new] = old */
  double *arr[] = {p->x, p->y, p->z, p->vx, p->vy, p->vz, p->mass};
  for (size_t a = 0; a < sizeof arr / sizeof *arr; a++) {
    for (size_t q = 0; q < n; q++) d->tmp[q] = arr[a][d->perm[q]];
    memcpy(arr[a], d->tmp, n * sizeof(double));
  }
  int64_t *g = (int64_t *)(void *)d->tmp;
  for (size_t q = 0; q < n; q++) g[q] = p->gid[d->perm[q]];
  memcpy(p->gid, g, n * sizeof *g);
  uint8_t *b = (uint8_t *)(void *)d->tmp;
  for (size_t q = 0; q < n; q++) b[q] = p->mat[d->perm[q]];
  memcpy(p->mat, b, n);
  for (size_t q = 0; q < n; q++) b[q] = p->flags[d->perm[q]];
  memcpy(p->flags, b, n);
  int32_t *c = (int32_t *)(void *)d->tmp;
  for (size_t q = 0; q < n; q++) c[q] = d->cell[d->perm[q]];
  memcpy(d->cell, c, n * sizeof *c);
  if (d->pgid) { /* bonded mode: one column of partner gids at a time through tmp */
    int64_t *col = (int64_t *)(void *)d->tmp;
    for (int k = 0; k < CD_MAX_PARTNERS; k++) {
      for (size_t q = 0; q < n; q++) col[q] = d->pgid[(size_t)d->perm[q] * CD_MAX_PARTNERS + k];
      for (size_t q = 0; q < n; q++) d->pgid[q * CD_MAX_PARTNERS + k] = col[q];
    }
  }
  for (size_t i = 0; i < n; i++) p->fx[i] = p->fy[i] = p->fz[i] = 0.0;
}

/* Every owned particle to the owner of its cell (a replicated set: each rank keeps its own). */
static void migrate(cd_sim *s) {
  cd_dd *d = s->dd;
  ptl_state *p = s->p;
  const int P = d->size, L = rec_len(s);
  size_t n = p->nlocal;
  for (size_t i = 0; i < n; i++) d->cell[i] = cell_of(d, p->x[i], p->y[i], p->z[i]);
  if (d->replicated) {
    size_t keep = 0;
    for (size_t i = 0; i < n; i++)
      if (d->owner[d->cell[i]] == d->rank) move_particle(s, i, keep++);
    p->nlocal = p->n = keep;
    d->replicated = false;
    return;
  }
  memset(d->mcnt_s, 0, (size_t)P * sizeof(int));
  for (size_t i = 0; i < n; i++) {
    int r = d->owner[d->cell[i]];
    if (r != d->rank) d->mcnt_s[r] += L;
  }
  size_t nsend = 0;
  for (int r = 0; r < P; r++) {
    d->mdsp_s[r] = (int)nsend;
    nsend += (size_t)d->mcnt_s[r];
  }
  grow(&d->sbuf, &d->sbuf_cap, nsend + 1);
  int *cur = d->xcnt_s; /* scratch cursors */
  memcpy(cur, d->mdsp_s, (size_t)P * sizeof(int));
  size_t keep = 0;
  for (size_t i = 0; i < n; i++) {
    int r = d->owner[d->cell[i]];
    if (r != d->rank) {
      pack(s, i, d->sbuf + cur[r]);
      cur[r] += L;
    } else {
      move_particle(s, i, keep++);
    }
  }
  par_alltoall_ints(d->mcnt_s, d->mcnt_r);
  size_t nrecv = 0;
  for (int r = 0; r < P; r++) {
    d->mdsp_r[r] = (int)nrecv;
    nrecv += (size_t)d->mcnt_r[r];
  }
  grow(&d->rbuf, &d->rbuf_cap, nrecv + 1);
  par_alltoallv_doubles(d->sbuf, d->mcnt_s, d->mdsp_s, d->rbuf, d->mcnt_r, d->mdsp_r);
  d->st.exchanged_doubles += (double)nrecv;
  const size_t nin = nrecv / (size_t)L;
  for (size_t q = 0; q < nin; q++) {
    size_t i = keep + q;
    unpack(s, i, d->rbuf + q * (size_t)L);
    d->cell[i] = cell_of(d, p->x[i], p->y[i], p->z[i]);
  }
  p->nlocal = p->n = keep + nin;
}

/* Ghosts: each owned particle in a cell next to other ranks' cells goes to each of them. */
static void send_ghosts(cd_sim *s) {
  cd_dd *d = s->dd;
  ptl_state *p = s->p;
  const int P = d->size, L = rec_len(s);
  const size_t n = p->nlocal;
  update_halo(d);
  const int32_t *hs = d->halo_start;
  const int *hr = d->halo_rank;
  memset(d->mcnt_s, 0, (size_t)P * sizeof(int));
  for (size_t i = 0; i < n; i++) {
    if (p->flags[i] & PTL_REMOVED) continue;
    for (int32_t k = hs[d->cell[i]]; k < hs[d->cell[i] + 1]; k++) d->mcnt_s[hr[k]]++;
  }
  par_alltoall_ints(d->mcnt_s, d->mcnt_r);
  int *slot = d->mdsp_s; /* rank -> neighbour index */
  d->nnbr = 0;
  size_t ns = 0, nrg = 0;
  for (int r = 0; r < P; r++) {
    slot[r] = -1;
    if (r == d->rank || (d->mcnt_s[r] == 0 && d->mcnt_r[r] == 0)) continue;
    int k = d->nnbr++;
    slot[r] = k;
    d->nbr[k] = r;
    d->gcnt_s[k] = d->mcnt_s[r];
    d->gcnt_r[k] = d->mcnt_r[r];
    d->gdsp_s[k] = (int)ns;
    d->gdsp_r[k] = (int)nrg;
    ns += (size_t)d->gcnt_s[k];
    nrg += (size_t)d->gcnt_r[k];
  }
  if (n + nrg > p->cap) { /* cannot happen: a rank holds each particle at most once */
    fprintf(stderr, "cd_par: %zu owned + %zu ghosts exceed the capacity %zu\n", n, nrg, p->cap);
    abort();
  }
  if (ns + 1 > d->send_cap) { /* a particle may go to up to 26 ranks */
    free(d->send_idx);
    d->send_cap = ns + ns / 4 + 64;
    d->send_idx = ms_calloc(d->send_cap, sizeof *d->send_idx);
  }
  int *cur = d->xcnt_s;
  for (int k = 0; k < d->nnbr; k++) cur[k] = d->gdsp_s[k];
  for (size_t i = 0; i < n; i++) {
    if (p->flags[i] & PTL_REMOVED) continue;
    for (int32_t k = hs[d->cell[i]]; k < hs[d->cell[i] + 1]; k++)
      d->send_idx[cur[slot[hr[k]]]++] = (int32_t)i;
  }
  d->nsend = ns;
  grow(&d->sbuf, &d->sbuf_cap, ns * (size_t)L + 1);
  grow(&d->rbuf, &d->rbuf_cap, nrg * (size_t)L + 1);
  for (size_t q = 0; q < ns; q++) pack(s, (size_t)d->send_idx[q], d->sbuf + q * (size_t)L);
  for (int k = 0; k < d->nnbr; k++) {
    d->xcnt_s[k] = d->gcnt_s[k] * L;
    d->xdsp_s[k] = d->gdsp_s[k] * L;
    d->xcnt_r[k] = d->gcnt_r[k] * L;
    d->xdsp_r[k] = d->gdsp_r[k] * L;
  }
  par_exchange_doubles(d->nnbr, d->nbr, d->sbuf, d->xcnt_s, d->xdsp_s, d->rbuf, d->xcnt_r,
                       d->xdsp_r);
  d->st.exchanged_doubles += (double)(nrg * (size_t)L);
  for (size_t q = 0; q < nrg; q++) unpack(s, n + q, d->rbuf + q * (size_t)L);
  p->n = n + nrg;
  /* the refresh buffer: up to 6 doubles per particle sent (cd_dd_refresh) */
  grow(&d->sbuf, &d->sbuf_cap, 6 * ns + 1);
}

/* One message per array and neighbour: the owned values are gathered array by array into
 * sbuf (neighbour blocks in the order of send_idx), and the ghosts' values land directly in
 * their slots [nlocal + gdsp_r[k], ...) of the particle arrays (they arrived in that order at
 * the build), so nothing is unpacked. */
void cd_dd_refresh(cd_sim *s, unsigned what) {
  cd_dd *d = s->dd;
  ptl_state *p = s->p;
  const double t0 = ms_wall_time();
  double *arr[6];
  int na = 0;
  if (what & CD_REFRESH_X) arr[na++] = p->x, arr[na++] = p->y, arr[na++] = p->z;
  if (what & CD_REFRESH_V) arr[na++] = p->vx, arr[na++] = p->vy, arr[na++] = p->vz;
  const size_t ns = d->nsend, g0 = p->nlocal;
  const int32_t *restrict idx = d->send_idx;
  for (int a = 0; a < na; a++) {
    double *restrict buf = d->sbuf + (size_t)a * ns;
    const double *restrict src = arr[a];
    for (size_t q = 0; q < ns; q++) buf[q] = src[idx[q]];
    par_exchange_post(d->nnbr, d->nbr, buf, d->gcnt_s, d->gdsp_s, arr[a] + g0, d->gcnt_r, d->gdsp_r,
                      100 + a);
  }
  par_exchange_wait();
  if (what & CD_REFRESH_X)
    for (size_t i = g0; i < p->n; i++) p->fx[i] = p->fy[i] = p->fz[i] = 0.0;
  d->st.exchanged_doubles += (double)((p->n - g0) * (size_t)na);
  d->st.exchange_s += ms_wall_time() - t0;
}

/* Bonded mode: partner rows as gids before particles move, back to local indices after. */
static void partners_to_gids(cd_sim *s) {
  cd_dd *d = s->dd;
  const ptl_state *p = s->p;
  for (size_t i = 0; i < p->nlocal; i++)
    for (int k = 0; k < CD_MAX_PARTNERS; k++) {
      int32_t j = s->partners[i * CD_MAX_PARTNERS + k];
      d->pgid[i * CD_MAX_PARTNERS + k] = j >= 0 ? p->gid[j] : -1;
    }
}

static void partners_from_gids(cd_sim *s) {
  cd_dd *d = s->dd;
  const ptl_state *p = s->p;
  const int64_t ng = (int64_t)d->ngid;
  for (size_t i = 0; i < p->n; i++)
    if (p->gid[i] >= 0 && p->gid[i] < ng) d->gid_map[p->gid[i]] = (int32_t)i;
  long lost = 0;
  for (size_t i = 0; i < p->n; i++)
    for (int k = 0; k < CD_MAX_PARTNERS; k++) {
      int64_t g = d->pgid[i * CD_MAX_PARTNERS + k];
      int32_t j = g >= 0 && g < ng ? d->gid_map[g] : -1;
      /* an owned particle's intact bond is evaluated every step, so it breaks before the pair
       * leaves r_list: the partner is here (else `lost`, reported). Ghosts' rows may name
       * particles this rank does not hold (never needed: no ghost-ghost pairs). */
      if (g >= 0 && j < 0 && i < p->nlocal) lost++;
      s->partners[i * CD_MAX_PARTNERS + k] = j;
    }
  for (size_t i = 0; i < p->n; i++)
    if (p->gid[i] >= 0 && p->gid[i] < ng) d->gid_map[p->gid[i]] = -1;
  d->st.lost_bonds += lost;
}

ms_status cd_dd_redistribute(cd_sim *s) {
  cd_dd *d = s->dd;
  ptl_state *p = s->p;
  const double t0 = ms_wall_time();
  p->n = p->nlocal; /* drop the ghosts */
  wrap_positions(s, p->nlocal);
  if (s->partners) partners_to_gids(s);
  ms_status st = MS_OK;
  /* rebalance: the load is the owned particle count (the force work per particle is nearly
   * uniform in a dense body) */
  const double thr = s->mpi.rebalance_threshold;
  if (thr > 0 && !d->replicated &&
      ++d->builds_since >= (s->mpi.rebalance_interval > 0 ? s->mpi.rebalance_interval : 1)) {
    const double mean = (double)d->st.global / d->size;
    const double before = par_max_double((double)p->nlocal) / mean;
    if (before > thr && partition(s, true, &st)) {
      d->st.rebalances++;
      d->st.rebalance_step = s->step;
      d->st.rebalance_before = before;
      d->st.rebalance_after = d->st.partition.imbalance;
    }
  }
  migrate(s);
  sort_by_cell(s);
  send_ghosts(s);
  if (s->partners) partners_from_gids(s);
  d->st.owned = p->nlocal;
  d->st.ghosts = p->n - p->nlocal;
  d->st.max_owned = (size_t)par_max_double((double)p->nlocal);
  d->st.total_ghosts = (size_t)par_sum_long((long)(p->n - p->nlocal));
  d->st.imbalance = (double)d->st.max_owned * d->size / (double)d->st.global;
  d->st.exchange_s += ms_wall_time() - t0;
  return st;
}

void cd_sim_ghost_owners(const cd_sim *s, int32_t *owner) {
  const cd_dd *d = s->dd;
  if (!d) return;
  /* the ghosts of the last build arrived grouped by neighbour rank (send_ghosts) */
  for (int k = 0; k < d->nnbr; k++)
    for (int q = 0; q < d->gcnt_r[k]; q++) owner[d->gdsp_r[k] + q] = d->nbr[k];
}
