/* SPDX-License-Identifier: MIT */
/* dm_par.c — the discrete model on MPI ranks (docs/mpi.md).
 *
 * The bond graph of the Hamiltonian model is fixed, so it is partitioned once, at set-up, with
 * METIS (k-way, vertex weight = bonds of the particle, edge weight = bonds between the two):
 * minimising the edge cut minimises the ghost traffic. Mirror ghosts (DM_MIRROR, w = S w_p)
 * are contracted into their real partner before partitioning, so a mirror and its partner are
 * always on the same rank and the constraint stays local.
 *
 * Each rank holds a local model: its owned particles (ascending global index) followed by the
 * ghosts — off-rank members of owned particles' families — grouped by owner rank, ascending
 * global index inside a group. Owned particles keep their families in the global bond order;
 * ghosts have empty families. A force evaluation is
 *   1. w of ghosts from their owners (exchange 3 doubles per ghost; in the constraint hook,
 *      which rkn_step calls right before every acceleration),
 *   2. C, σ, Q of owned particles (their families are complete on the rank),
 *   3. Q of ghosts from their owners (9 doubles per ghost),
 *   4. F_i = Σ_k (Q_i + Q_k) ξ_ik for owned particles.
 * Every owned value is computed by the same code from the same operands in the same order as
 * on one rank, so displacements and velocities are bitwise independent of the rank count.
 * Global sums (energies) are made order-independent too: every rank writes its particles'
 * terms into a zeroed array indexed by global particle, one element-wise MPI sum fills it (each
 * element has exactly one nonzero term, so that sum is exact), and every rank adds the array
 * up in global order. O(N) per diagnostic call, done every energy_every steps only.
 */
#define _GNU_SOURCE /* qsort_r */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


struct dm_dist {
  int rank, size;
  dm_model *gm; /* the global model (replicated set-up; not owned) */
  size_t n_global;
  dm_state ls;  /* local particles: owned, then ghosts */
  dm_model *lm; /* local model (families of owned particles in local indices) */
  size_t n_owned, n_ghost;
  uint32_t *gid;      /* [n_local] global index */
  uint32_t *local_of; /* [n_global] local index, UINT32_MAX if not on this rank */
  int32_t *part;      /* [n_global] owner rank */
  int *scount, *sdispl, *rcount, *rdispl; /* per rank, in particles */
  int *sc_d, *sd_d, *rc_d, *rd_d;         /* the same in doubles (set per exchange width) */
  uint32_t *send_idx; /* local indices of owned particles sent, grouped by destination */
  size_t nsend;
  double *sbuf, *rbuf; /* 9 doubles per sent / received particle */
  double *gbuf;        /* [4][n_global] ordered-reduction scratch */
  double *tbuf;        /* [4][n_owned] per-particle terms of those reductions */
  dm_dist_stats stats;
};

/* ---- partition ------------------------------------------------------------------------- */

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* Vertex of particle i in the contracted graph (mirror ghosts → their partner). */
static uint32_t vertex_particle(const dm_state *s, size_t i) {
  return s->bc[i] == DM_MIRROR ? s->partner[i] : (uint32_t)i;
}

/* Cut bonds and weight imbalance of a particle partition. */
static void partition_quality(const dm_model *m, const int32_t *part, int nparts,
                              const int32_t *wvert, long *cut, double *imbalance) {
  long c = 0;
  for (size_t i = 0; i < m->s->n; ++i)
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b)
      if (part[i] != part[m->nbr[b]]) ++c;
  *cut = c / 2;
  double *w = ms_calloc((size_t)nparts, sizeof(double)), tot = 0, mx = 0;
  for (size_t i = 0; i < m->s->n; ++i) {
    w[part[i]] += (double)wvert[i];
    tot += (double)wvert[i];
  }
  for (int r = 0; r < nparts; ++r) mx = fmax(mx, w[r]);
  *imbalance = tot > 0 ? mx / (tot / nparts) : 1.0;
  free(w);
}

static int cmp_slab(const void *a, const void *b, void *xs) {
  const double *x = xs;
  uint32_t i = *(const uint32_t *)a, k = *(const uint32_t *)b;
  if (x[3 * i] != x[3 * k]) return x[3 * i] < x[3 * k] ? -1 : 1;
  return i < k ? -1 : i > k;
}

/* The plain slab decomposition along x (equal bond weight per slab, mirrors with their
 * partners), for the comparison in the log. */
static void slab_partition(const dm_model *m, int nparts, const int32_t *wvert, int32_t *part) {
  const dm_state *s = m->s;
  uint32_t *ord = ms_calloc(s->n ? s->n : 1, sizeof(uint32_t));
  double *wv = ms_calloc(s->n ? s->n : 1, sizeof(double)); /* mirrors weigh on their partner */
  size_t nv = 0;
  double tot = 0;
  for (size_t i = 0; i < s->n; ++i) {
    wv[vertex_particle(s, i)] += (double)wvert[i];
    tot += (double)wvert[i];
    if (s->bc[i] != DM_MIRROR) ord[nv++] = (uint32_t)i;
  }
  /* order by (x, index) */
  qsort_r(ord, nv, sizeof(uint32_t), cmp_slab, (void *)s->X);
  double acc = 0;
  for (size_t v = 0; v < nv; ++v) {
    int r = (int)(acc / tot * nparts);
    part[ord[v]] = r < nparts ? r : nparts - 1;
    acc += wv[ord[v]];
  }
  for (size_t i = 0; i < s->n; ++i)
    if (s->bc[i] == DM_MIRROR) part[i] = part[s->partner[i]];
  free(ord);
  free(wv);
}

/* METIS k-way partition of the contracted bond graph into nparts; part[] for every particle.
 * wpart[i]: the particle's work weight (its bonds), summed over contracted mirrors. */
static ms_status metis_partition(const dm_model *m, int nparts, int32_t *wvert, int32_t *part,
                                 const ms_ctx *ctx) {
  const dm_state *s = m->s;
  const size_t n = s->n;
  /* vertices: non-mirror particles, numbered in index order */
  int32_t *vid = ms_calloc(n, sizeof(int32_t));
  int32_t nv = 0;
  for (size_t i = 0; i < n; ++i) vid[i] = s->bc[i] == DM_MIRROR ? -1 : nv++;
  int32_t *vwgt = ms_calloc((size_t)nv, sizeof(int32_t));
  for (size_t i = 0; i < n; ++i) vwgt[vid[vertex_particle(s, i)]] += wvert[i];
  for (int32_t v = 0; v < nv; ++v)
    if (vwgt[v] < 1) vwgt[v] = 1;
  /* directed edges (v << 32 | u), v != u, then merged into weights */
  uint64_t *e = ms_calloc(m->nbonds ? m->nbonds : 1, sizeof(uint64_t));
  size_t ne = 0;
  for (size_t i = 0; i < n; ++i) {
    uint64_t v = (uint64_t)vid[vertex_particle(s, i)];
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      uint64_t u = (uint64_t)vid[vertex_particle(s, m->nbr[b])];
      if (u != v) e[ne++] = v << 32 | u;
    }
  }
  qsort(e, ne, sizeof(uint64_t), cmp_u64);
  int32_t *xadj = ms_calloc((size_t)nv + 1, sizeof(int32_t));
  int32_t *adj = ms_calloc(ne ? ne : 1, sizeof(int32_t)),
          *adjw = ms_calloc(ne ? ne : 1, sizeof(int32_t));
  size_t na = 0;
  for (size_t k = 0; k < ne;) {
    size_t j = k;
    while (j < ne && e[j] == e[k]) ++j;
    int32_t v = (int32_t)(e[k] >> 32);
    adj[na] = (int32_t)(e[k] & 0xffffffffu);
    adjw[na++] = (int32_t)(j - k);
    xadj[v + 1]++;
    k = j;
  }
  for (int32_t v = 0; v < nv; ++v) xadj[v + 1] += xadj[v];
  int32_t *vpart = ms_calloc((size_t)nv ? (size_t)nv : 1, sizeof(int32_t));
  int rc = 0;
  ms_status st = MS_OK;
  if (nparts > 1 && nv > 0) /* at most 1 % above the mean weight (METIS's default: 3 %) */
    st = ptl_partition_kway(nv, xadj, adj, vwgt, adjw, nparts, 10, vpart, &rc);
  if (st != MS_OK)
    ms_log(ctx, MS_LOG_ERROR, "discrete model: METIS partitioning failed (code %d)", rc);
  for (size_t i = 0; i < n; ++i) part[i] = (int32_t)vpart[vid[vertex_particle(s, i)]];
  free(vid);
  free(vwgt);
  free(e);
  free(xadj);
  free(adj);
  free(adjw);
  free(vpart);
  return st;
}

/* ---- local model ------------------------------------------------------------------------ */

static int cmp_ghost(const void *a, const void *b, void *partv) {
  const int32_t *part = partv;
  uint32_t i = *(const uint32_t *)a, k = *(const uint32_t *)b;
  if (part[i] != part[k]) return part[i] < part[k] ? -1 : 1;
  return i < k ? -1 : i > k;
}

static void copy_particle(dm_dist *d, size_t l, size_t g) {
  const dm_state *s = d->gm->s;
  dm_state *t = &d->ls;
  for (int a = 0; a < 3; ++a) {
    t->X[3 * l + a] = s->X[3 * g + a];
    t->w[3 * l + a] = s->w[3 * g + a];
    t->u[3 * l + a] = s->u[3 * g + a];
    t->msign[3 * l + a] = s->msign[3 * g + a];
  }
  t->mass[l] = s->mass[g];
  t->vol[l] = s->vol[g];
  t->K[l] = s->K[g];
  t->G[l] = s->G[g];
  t->bc[l] = s->bc[g];
  const dm_model *m = d->gm;
  dm_model *lm = d->lm;
  memcpy(&lm->Ainv[9 * l], &m->Ainv[9 * g], 9 * sizeof(double));
  lm->cond[l] = m->cond[g];
  lm->kappa[l] = m->kappa[g];
}

static void build_local(dm_dist *d) {
  const dm_model *m = d->gm;
  const dm_state *s = m->s;
  const size_t n = s->n;
  const int me = d->rank;
  d->local_of = ms_calloc(n ? n : 1, sizeof(uint32_t));
  for (size_t i = 0; i < n; ++i) d->local_of[i] = UINT32_MAX;
  size_t nown = 0;
  for (size_t i = 0; i < n; ++i)
    if (d->part[i] == me) d->local_of[i] = (uint32_t)nown++;
  /* ghosts: off-rank family members of owned particles */
  uint32_t *ghosts = ms_calloc(n ? n : 1, sizeof(uint32_t));
  size_t ng = 0;
  uint8_t *seen = ms_calloc(n ? n : 1, 1);
  size_t lbonds = 0;
  for (size_t i = 0; i < n; ++i) {
    if (d->part[i] != me) continue;
    lbonds += m->start[i + 1] - m->start[i];
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      uint32_t k = m->nbr[b];
      if (d->part[k] != me && !seen[k]) seen[k] = 1, ghosts[ng++] = k;
    }
  }
  qsort_r(ghosts, ng, sizeof(uint32_t), cmp_ghost, d->part);
  for (size_t g = 0; g < ng; ++g) d->local_of[ghosts[g]] = (uint32_t)(nown + g);
  d->n_owned = nown;
  d->n_ghost = ng;
  size_t nl = nown + ng;
  d->gid = ms_calloc(nl ? nl : 1, sizeof(uint32_t));
  for (size_t i = 0; i < n; ++i)
    if (d->local_of[i] != UINT32_MAX) d->gid[d->local_of[i]] = (uint32_t)i;

  dm_state_alloc(&d->ls, nl, s->dim);
  dm_model *lm = ms_calloc(1, sizeof *lm);
  d->lm = lm;
  lm->s = &d->ls;
  lm->opt = m->opt;
  memcpy(lm->shift, m->shift, sizeof lm->shift);
  dm_alloc_work(lm, nl);
  lm->start = ms_calloc(nl + 1, sizeof(size_t));
  lm->nbr = ms_calloc(lbonds ? lbonds : 1, sizeof(uint32_t));
  lm->img = ms_calloc(lbonds ? lbonds : 1, sizeof(uint8_t));
  lm->nbonds = lbonds;
  lm->prescribe = m->prescribe;
  lm->prescribe_user = m->prescribe_user;
  size_t b2 = 0;
  for (size_t l = 0; l < nl; ++l) {
    size_t g = d->gid[l];
    copy_particle(d, l, g);
    if (l < nown) {
      /* the global bond order (ascending global index) is kept: identical sums */
      for (size_t b = m->start[g]; b < m->start[g + 1]; ++b) {
        lm->nbr[b2] = d->local_of[m->nbr[b]];
        lm->img[b2++] = m->img[b];
      }
      if (s->bc[g] == DM_MIRROR) d->ls.partner[l] = d->local_of[s->partner[g]]; /* owned too */
    } else {
      d->ls.bc[l] = DM_FIXED; /* ghosts: values come from their owners, never integrated */
    }
    lm->start[l + 1] = b2;
  }
  free(seen);
  free(ghosts);

  /* send lists: owned particle i goes to every rank q != me owning a member of its family
   * (that rank holds i as a ghost), in ascending global index per destination — the order
   * in which q stores its ghosts from this rank. */
  const int P = d->size;
  d->scount = ms_calloc((size_t)P, sizeof(int));
  d->sdispl = ms_calloc((size_t)P, sizeof(int));
  d->rcount = ms_calloc((size_t)P, sizeof(int));
  d->rdispl = ms_calloc((size_t)P, sizeof(int));
  d->sc_d = ms_calloc((size_t)P, sizeof(int));
  d->sd_d = ms_calloc((size_t)P, sizeof(int));
  d->rc_d = ms_calloc((size_t)P, sizeof(int));
  d->rd_d = ms_calloc((size_t)P, sizeof(int));
  uint8_t *mark = ms_calloc((size_t)P, 1);
  for (int pass = 0; pass < 2; ++pass) {
    size_t *fill = ms_calloc((size_t)P, sizeof(size_t));
    for (size_t l = 0; l < nown; ++l) {
      size_t g = d->gid[l];
      memset(mark, 0, (size_t)P);
      for (size_t b = m->start[g]; b < m->start[g + 1]; ++b) {
        int q = d->part[m->nbr[b]];
        if (q == me || mark[q]) continue;
        mark[q] = 1;
        if (pass == 0) d->scount[q]++;
        else d->send_idx[(size_t)d->sdispl[q] + fill[q]++] = (uint32_t)l;
      }
    }
    free(fill);
    if (pass == 0) {
      d->nsend = 0;
      for (int q = 0; q < P; ++q) d->sdispl[q] = (int)d->nsend, d->nsend += (size_t)d->scount[q];
      d->send_idx = ms_calloc(d->nsend ? d->nsend : 1, sizeof(uint32_t));
    }
  }
  free(mark);
  for (size_t g = 0; g < ng; ++g) d->rcount[d->part[d->gid[nown + g]]]++;
  for (int q = 1; q < P; ++q) d->rdispl[q] = d->rdispl[q - 1] + d->rcount[q - 1];
  d->sbuf = ms_calloc(9 * (d->nsend ? d->nsend : 1), sizeof(double));
  d->rbuf = ms_calloc(9 * (ng ? ng : 1), sizeof(double));
  d->gbuf = ms_calloc(4 * (n ? n : 1), sizeof(double));
  d->tbuf = ms_calloc(4 * (nown ? nown : 1), sizeof(double));
}

/* Ghost values of a [n_local][width] array from their owners. */
static void exchange(dm_dist *d, double *v, int width) {
  if (d->size == 1) return;
  double t0 = ms_wall_time();
  for (size_t k = 0; k < d->nsend; ++k)
    memcpy(&d->sbuf[(size_t)width * k], &v[(size_t)width * d->send_idx[k]],
           (size_t)width * sizeof(double));
  for (int q = 0; q < d->size; ++q) {
    d->sc_d[q] = width * d->scount[q], d->sd_d[q] = width * d->sdispl[q];
    d->rc_d[q] = width * d->rcount[q], d->rd_d[q] = width * d->rdispl[q];
  }
  par_alltoallv_doubles(d->sbuf, d->sc_d, d->sd_d, d->rbuf, d->rc_d, d->rd_d);
  memcpy(&v[(size_t)width * d->n_owned], d->rbuf, (size_t)width * d->n_ghost * sizeof(double));
  d->stats.exchange_s += ms_wall_time() - t0;
  d->stats.exchanged_doubles += (double)width * (double)d->n_ghost;
}

ms_status dm_dist_create(const dm_dist_params *prm, dm_dist **out) {
  *out = NULL;
  dm_model *global = prm->global;
  const ms_ctx *ctx = prm->ctx;
  dm_dist *d = ms_calloc(1, sizeof *d);
  d->rank = ctx->rank;
  d->size = ctx->size > 0 ? ctx->size : 1;
  d->gm = global;
  const dm_state *s = global->s;
  const size_t n = s->n;
  d->n_global = n;
  d->part = ms_calloc(n ? n : 1, sizeof(int32_t));
  int32_t *wvert = ms_calloc(n ? n : 1, sizeof(int32_t));
  for (size_t i = 0; i < n; ++i) wvert[i] = (int32_t)(global->start[i + 1] - global->start[i]) + 1;
  ms_status st = MS_OK;
  double t0 = ms_wall_time();
  if (d->size > 1) {
    /* one rank partitions, everyone receives the same answer */
    if (d->rank == 0) st = metis_partition(global, d->size, wvert, d->part, ctx);
    st = par_agree_status(st);
    par_bcast_ints(d->part, n, 0);
  }
  d->stats.partition_s = ms_wall_time() - t0;
  partition_quality(global, d->part, d->size, wvert, &d->stats.edge_cut, &d->stats.imbalance);
  int32_t *slab = ms_calloc(n ? n : 1, sizeof(int32_t));
  slab_partition(global, d->size, wvert, slab);
  partition_quality(global, slab, d->size, wvert, &d->stats.edge_cut_slab,
                    &d->stats.imbalance_slab);
  free(slab);
  free(wvert);
  if (st != MS_OK) {
    dm_dist_destroy(&d);
    return st;
  }
  build_local(d);
  d->stats.owned = d->n_owned;
  d->stats.ghosts = d->n_ghost;
  /* par_* only with size > 1: a serial context inside an MPI program stays rank-local */
  const int par = d->size > 1;
  d->stats.max_owned = par ? (size_t)par_max_double((double)d->n_owned) : d->n_owned;
  d->stats.max_ghosts = par ? (size_t)par_max_double((double)d->n_ghost) : d->n_ghost;
  d->stats.total_ghosts = par ? (size_t)par_sum_long((long)d->n_ghost) : d->n_ghost;
  d->stats.bonds = global->nbonds / 2;
  *out = d;
  return MS_OK;
}

void dm_dist_destroy(dm_dist **dp) {
  if (!dp || !*dp) return;
  dm_dist *d = *dp;
  dm_model_destroy(&d->lm);
  dm_state_free(&d->ls);
  free(d->gid);
  free(d->local_of);
  free(d->part);
  free(d->scount);
  free(d->sdispl);
  free(d->rcount);
  free(d->rdispl);
  free(d->sc_d);
  free(d->sd_d);
  free(d->rc_d);
  free(d->rd_d);
  free(d->send_idx);
  free(d->sbuf);
  free(d->rbuf);
  free(d->gbuf);
  free(d->tbuf);
  free(d);
  *dp = NULL;
}

dm_state *dm_dist_state(dm_dist *d) { return &d->ls; }
dm_model *dm_dist_model(dm_dist *d) { return d->lm; }
size_t dm_dist_owned(const dm_dist *d) { return d->n_owned; }
const dm_dist_stats *dm_dist_get_stats(const dm_dist *d) { return &d->stats; }
long dm_dist_local_index(const dm_dist *d, size_t global) {
  uint32_t l = d->local_of[global];
  return l != UINT32_MAX && l < d->n_owned ? (long)l : -1;
}

/* ---- time stepping ---------------------------------------------------------------------- */

void dm_dist_constrain(void *user, double t, double *q, double *u) {
  dm_dist *d = user;
  dm_model *lm = d->lm;
  /* ghosts are DM_FIXED locally, so the serial constraint touches owned particles only
   * (a mirror's partner is always owned by the same rank) */
  dm_constrain(lm, t, q, u);
  exchange(d, q, 3);
}

ms_status dm_dist_accel(void *user, double t, const double *q, double *acc) {
  (void)t;
  dm_dist *d = user;
  dm_model *lm = d->lm;
  const dm_state *s = &d->ls;
  const size_t no = d->n_owned, nl = no + d->n_ghost;
  dm_stress_pass(lm, q, no);
  exchange(d, lm->Q, 9);
  dm_gather_pass(lm, q, acc, no);
  const int dim = s->dim;
  int bad = 0;
#pragma omp parallel for schedule(static) reduction(| : bad) if (no > 16384)
  for (long i = 0; i < (long)no; ++i) {
    double inv = s->bc[i] == DM_FREE ? 1.0 / s->mass[i] : 0.0;
    for (int a = 0; a < 3; ++a) {
      double v = a < dim ? acc[3 * i + a] * inv : 0.0;
      if (!isfinite(v)) bad = 1;
      acc[3 * i + a] = v;
    }
  }
  for (size_t i = 3 * no; i < 3 * nl; ++i) acc[i] = 0.0;
  if (d->size > 1) bad = par_max_int(bad); /* every rank stops together */
  return bad ? MS_ERR_UNSTABLE : MS_OK;
}

/* ---- ordered reductions and gathers ------------------------------------------------------ */

/* Sum of per-particle terms t[l] (owned) in global particle order, the same on every rank and
 * for every rank count. k arrays at once (k ≤ 4): out[j] = Σ_i t_j[i]. */
static void ordered_sums(dm_dist *d, int k, double *const *terms, double *out) {
  const size_t n = d->n_global;
  memset(d->gbuf, 0, (size_t)k * n * sizeof(double));
  for (int j = 0; j < k; ++j)
    for (size_t l = 0; l < d->n_owned; ++l) d->gbuf[(size_t)j * n + d->gid[l]] = terms[j][l];
  if (d->size > 1) par_sum_doubles(d->gbuf, (size_t)k * n);
  for (int j = 0; j < k; ++j) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += d->gbuf[(size_t)j * n + i];
    out[j] = sum;
  }
}

void dm_dist_diagnostics(dm_dist *d, dm_dist_diag *out) {
  dm_model *lm = d->lm;
  dm_state *s = &d->ls;
  const size_t no = d->n_owned;
  exchange(d, s->w, 3);
  dm_stress_pass(lm, s->w, no);
  double *kin = d->tbuf, *pot = kin + no, *hgz = kin + 2 * no, *hgw = kin + 3 * no;
  memset(kin, 0, 4 * no * sizeof(double));
  for (size_t i = 0; i < no; ++i) {
    if (s->bc[i] == DM_MIRROR) continue;
    const double *u = &s->u[3 * i];
    kin[i] = 0.5 * s->mass[i] * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    pot[i] = lm->energy[i];
    if (s->bc[i] != DM_FREE) continue;
    const double *C = &lm->C[9 * i];
    double zz = 0, ww = 0;
    for (size_t b = lm->start[i]; b < lm->start[i + 1]; ++b) {
      size_t k = lm->nbr[b];
      double xi[3];
      dm_bond_vector(lm, i, b, xi);
      for (int a = 0; a < 3; ++a) {
        double dw = s->w[3 * k + a] - s->w[3 * i + a];
        double z = dw - (C[3 * a] * xi[0] + C[3 * a + 1] * xi[1] + C[3 * a + 2] * xi[2]);
        zz += z * z;
        ww += dw * dw;
      }
    }
    hgz[i] = zz, hgw[i] = ww;
  }
  double *terms[4] = {kin, pot, hgz, hgw}, sums[4];
  ordered_sums(d, 4, terms, sums);
  out->kinetic = sums[0];
  out->potential = sums[1];
  out->hourglass = sqrt(sums[2]);
  out->dw_norm = sqrt(sums[3]);
}

void dm_dist_gather(dm_dist *d, const double *local, int width, double *global) {
  const size_t n = d->n_global;
  memset(global, 0, (size_t)width * n * sizeof(double));
  for (size_t l = 0; l < d->n_owned; ++l)
    memcpy(&global[(size_t)width * d->gid[l]], &local[(size_t)width * l],
           (size_t)width * sizeof(double));
  if (d->size > 1) par_sum_doubles(global, (size_t)width * n);
}

void dm_dist_scatter(dm_dist *d, const double *global, int width, double *local) {
  const size_t nl = d->n_owned + d->n_ghost;
  for (size_t l = 0; l < nl; ++l)
    memcpy(&local[(size_t)width * l], &global[(size_t)width * d->gid[l]],
           (size_t)width * sizeof(double));
}

double dm_dist_mass_dot(dm_dist *d, const double *x, const double *y) {
  const dm_state *s = &d->ls;
  double *t = d->tbuf, sum;
  for (size_t i = 0; i < d->n_owned; ++i)
    t[i] = s->bc[i] == DM_FREE ? s->mass[i] * (x[3 * i] * y[3 * i] + x[3 * i + 1] * y[3 * i + 1] +
                                               x[3 * i + 2] * y[3 * i + 2])
                               : 0.0;
  ordered_sums(d, 1, &t, &sum);
  return sum;
}

void dm_dist_global_stress(dm_dist *d) {
  dm_model *lm = d->lm;
  exchange(d, d->ls.w, 3);
  dm_stress_pass(lm, d->ls.w, d->n_owned);
  dm_dist_gather(d, lm->C, 9, d->gm->C);
  dm_dist_gather(d, lm->sigma, 9, d->gm->sigma);
}

void dm_dist_release_global(dm_dist *d) {
  dm_model *m = d->gm;
  free(m->start), m->start = NULL;
  free(m->nbr), m->nbr = NULL;
  free(m->img), m->img = NULL;
  free(m->Ainv), m->Ainv = NULL;
  free(m->cond), m->cond = NULL;
  free(m->kappa), m->kappa = NULL;
  free(m->Q), m->Q = NULL;
  free(m->energy), m->energy = NULL;
}
