/* SPDX-License-Identifier: MIT */
/* fragments_dist.c — fragments of particles distributed over MPI ranks (docs/mpi.md
 * "Fragments on MPI ranks"). MPI only through core's par_* wrappers.
 *
 *  1. Local union–find over the rank's owned particles and ghost copies (every bond with both
 *     ends on the rank, found by the serial cell-list search).
 *  2. Label = smallest gid of the local component; the labels of ghost copies go to the ghosts'
 *     owners and the owners' labels come back, each side keeping the minimum, until an
 *     all-reduce says no label changed: then every particle's label is the smallest gid of its
 *     global fragment (min-label propagation over the graph "local components + ghost ↔
 *     original"; rounds ≈ the number of rank boundaries a fragment's smallest gid must cross).
 *  3. The statistics passes of the serial code (cpl_acc1_add, …) run on owned particles into
 *     one record per (rank, fragment); records go to the rank owning the label — labels are cut
 *     into P contiguous gid ranges, so rank r's fragments come before rank r+1's in the serial
 *     order and global ids are a prefix sum — which merges them (in source-rank order) and sends
 *     back what the next pass needs (reference point, centre offset), then the global id.
 *  4. The table is gathered on every rank (rows in rank order = the serial order).
 * Per call: O(local particles) work plus messages proportional to ghosts and to local fragments;
 * the replicated table is O(fragments) on every rank (what drag, ejecta selection and the CSV
 * writers use). Scratch is allocated per call (fragment searches run at output intervals). */
#include "cpl_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A personalised exchange pattern in records: counts and displacements per rank, forward
 * (send → recv) or back (the replies, recv → send layout). */
typedef struct plan {
  int P;
  int *sc, *sd, *rc, *rd; /* records */
  size_t ns, nr;
  int *w4; /* [4][P] the same scaled to a record width */
} plan;

static void plan_init(plan *x, int P, const int *send_counts) {
  x->P = P;
  x->sc = ms_calloc((size_t)P, sizeof(int));
  x->sd = ms_calloc((size_t)P, sizeof(int));
  x->rc = ms_calloc((size_t)P, sizeof(int));
  x->rd = ms_calloc((size_t)P, sizeof(int));
  x->w4 = ms_calloc(4 * (size_t)P, sizeof(int));
  memcpy(x->sc, send_counts, (size_t)P * sizeof(int));
  par_alltoall_ints(x->sc, x->rc);
  x->ns = x->nr = 0;
  for (int r = 0; r < P; ++r) {
    x->sd[r] = (int)x->ns;
    x->rd[r] = (int)x->nr;
    x->ns += (size_t)x->sc[r];
    x->nr += (size_t)x->rc[r];
  }
}

static void plan_free(plan *x) {
  free(x->sc);
  free(x->sd);
  free(x->rc);
  free(x->rd);
  free(x->w4);
}

/* Counts and displacements of `width` elements per record, in the direction asked. */
static int *plan_scaled(const plan *x, int width, bool back) {
  int *w = x->w4, P = x->P;
  const int *sc = back ? x->rc : x->sc, *sd = back ? x->rd : x->sd;
  const int *rc = back ? x->sc : x->rc, *rd = back ? x->sd : x->rd;
  for (int r = 0; r < P; ++r) {
    w[r] = sc[r] * width;
    w[P + r] = sd[r] * width;
    w[2 * P + r] = rc[r] * width;
    w[3 * P + r] = rd[r] * width;
  }
  return w;
}

static void plan_doubles(const plan *x, int width, bool back, const double *send, double *recv) {
  int *w = plan_scaled(x, width, back), P = x->P;
  par_alltoallv_doubles(send, w, w + P, recv, w + 2 * P, w + 3 * P);
}

static void plan_int64(const plan *x, bool back, const int64_t *send, int64_t *recv) {
  int *w = plan_scaled(x, 1, back), P = x->P;
  par_alltoallv_int64(send, w, w + P, recv, w + 2 * P, w + 3 * P);
}

static int cmp_i64(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return x < y ? -1 : x > y;
}

/* (key, position) pairs sorted by key, then position. */
typedef struct keyed {
  int64_t key;
  size_t pos;
} keyed;

static int cmp_keyed(const void *a, const void *b) {
  const keyed *x = a, *y = b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->pos < y->pos ? -1 : x->pos > y->pos;
}

/* Index of key in the sorted array a[0..n), or −1. */
static long find_sorted(const int64_t *a, size_t n, int64_t key) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (a[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  return lo < n && a[lo] == key ? (long)lo : -1;
}

static inline bool skipped(const cpl_particles *p, size_t i) { return p->skip && p->skip[i]; }

/* Local checks: ghosts' owners, gids below 2^53 (they travel as doubles in the records). */
static ms_status check_dist(const cpl_particles *p, size_t n_owned, const int32_t *ghost_owner,
                            const cpl_fragment_opts *o, const ms_ctx *ctx) {
  if (!p || !o || !ctx || n_owned > p->n || !p->gid || (p->n > n_owned && !ghost_owner))
    return MS_ERR_INPUT;
  for (size_t i = 0; i < p->n; ++i)
    if (p->gid[i] < 0 || p->gid[i] >= (INT64_C(1) << 53)) return MS_ERR_INPUT;
  for (size_t j = 0; j < p->n - n_owned; ++j)
    if (ghost_owner[j] < 0 || ghost_owner[j] >= ctx->size || ghost_owner[j] == ctx->rank)
      return MS_ERR_INPUT;
  return MS_OK;
}

/* 2. Labels, indexed by root (lab[n]): the smallest gid of each local component, then the
 * min-label propagation with the ghosts' owners until no label changes (rounds counted).
 * cnt: P ints of scratch. Collective. */
static ms_status global_labels(const cpl_particles *p, size_t n_owned, const int32_t *ghost_owner,
                               int P, cpl_uf *uf, int *cnt, int64_t *lab, int *rounds) {
  const size_t n = p->n, ng = n - n_owned;
  ms_status st = MS_OK;
  for (size_t i = 0; i < n; ++i) lab[i] = INT64_MAX;
  for (size_t i = 0; i < n; ++i) {
    if (skipped(p, i)) continue;
    size_t r = cpl_uf_find(uf, i);
    if (p->gid[i] < lab[r]) lab[r] = p->gid[i];
  }
  /* active ghosts grouped by owner (stable), their gids to the owners */
  for (size_t j = 0; j < ng; ++j)
    if (!skipped(p, n_owned + j)) cnt[ghost_owner[j]]++;
  plan gp;
  plan_init(&gp, P, cnt);
  size_t *gl = ms_calloc(gp.ns + 1, sizeof *gl); /* local index of each sent ghost */
  {
    int *cur = ms_calloc((size_t)P, sizeof(int));
    for (size_t j = 0; j < ng; ++j)
      if (!skipped(p, n_owned + j)) {
        int r = ghost_owner[j];
        gl[(size_t)gp.sd[r] + (size_t)cur[r]++] = n_owned + j;
      }
    free(cur);
  }
  int64_t *sl = ms_calloc(gp.ns + 1, sizeof *sl), *rl = ms_calloc(gp.nr + 1, sizeof *rl);
  for (size_t q = 0; q < gp.ns; ++q) sl[q] = p->gid[gl[q]];
  plan_int64(&gp, false, sl, rl);
  /* the owned particle behind each request: owned gids sorted, binary search */
  size_t *req = ms_calloc(gp.nr + 1, sizeof *req);
  {
    keyed *own = ms_calloc(n_owned + 1, sizeof *own);
    int64_t *keys = ms_calloc(n_owned + 1, sizeof *keys);
    for (size_t i = 0; i < n_owned; ++i) own[i] = (keyed){p->gid[i], i};
    qsort(own, n_owned, sizeof *own, cmp_keyed);
    for (size_t i = 0; i < n_owned; ++i) {
      keys[i] = own[i].key;
      if (i > 0 && keys[i] == keys[i - 1]) st = MS_ERR_INPUT; /* duplicate gid */
    }
    for (size_t q = 0; q < gp.nr; ++q) {
      long k = find_sorted(keys, n_owned, rl[q]);
      /* a ghost of a particle its owner does not have, or skips, would add false bonds */
      if (k < 0 || skipped(p, own[k].pos)) {
        st = MS_ERR_INPUT;
        req[q] = 0;
      } else {
        req[q] = own[k].pos;
      }
    }
    free(own);
    free(keys);
  }
  st = par_agree_status(st);
  while (st == MS_OK) {
    ++*rounds;
    int changed = 0;
    for (size_t q = 0; q < gp.ns; ++q) sl[q] = lab[cpl_uf_find(uf, gl[q])];
    plan_int64(&gp, false, sl, rl);
    for (size_t q = 0; q < gp.nr; ++q) {
      size_t r = cpl_uf_find(uf, req[q]);
      if (rl[q] < lab[r]) lab[r] = rl[q], changed = 1;
    }
    for (size_t q = 0; q < gp.nr; ++q) rl[q] = lab[cpl_uf_find(uf, req[q])];
    plan_int64(&gp, true, rl, sl);
    for (size_t q = 0; q < gp.ns; ++q) {
      size_t r = cpl_uf_find(uf, gl[q]);
      if (sl[q] < lab[r]) lab[r] = sl[q], changed = 1;
    }
    if (!par_max_int(changed)) break;
  }
  plan_free(&gp);
  free(gl);
  free(sl);
  free(rl);
  free(req);
  return st;
}

/* A fragment's row on its label owner and in the gathered table: [acc1 | centre(3) | acc3]. */
enum { ROW = CPL_ACC1 + 4, R_C = CPL_ACC1, R_ACC3 = CPL_ACC1 + 3 };

/* 4. The table on every rank: the owners' rows (nF here, nper[r] on rank r, total in all)
 * gathered in rank order. Collective. */
static void gather_table(cpl_fragments *f, const double *row, size_t nF, const long *nper,
                         long total, int P, const cpl_fragment_opts *o) {
  int *gc = ms_calloc((size_t)P, sizeof(int)), *gd = ms_calloc((size_t)P, sizeof(int));
  for (int r = 0, at = 0; r < P; ++r) {
    gc[r] = (int)nper[r] * ROW;
    gd[r] = at;
    at += gc[r];
  }
  double *all = ms_calloc((size_t)total * ROW + 1, sizeof *all);
  par_allgatherv_doubles(row, (int)nF * ROW, all, gc, gd);
  f->n = (size_t)total;
  cpl_fragments_reserve(f, f->n);
  for (size_t k = 0; k < f->n; ++k) {
    const double *rk = all + k * ROW;
    cpl_fragment_set(f, k, rk, rk + R_C, rk[R_ACC3], o->rho0);
  }
  free(gc);
  free(gd);
  free(all);
}

ms_status cpl_fragments_find_dist(cpl_fragments *f, const cpl_particles *p, size_t n_owned,
                                  const int32_t *ghost_owner, const cpl_fragment_opts *o,
                                  const ms_ctx *ctx) {
  ms_status st = check_dist(p, n_owned, ghost_owner, o, ctx);
  if (st == MS_OK) st = cpl_fragments_bond_search(f, p, o, n_owned);
  st = par_agree_status(st);
  if (st != MS_OK) return st;
  const int P = ctx->size;
  const size_t n = p->n;
  cpl_uf *uf = &f->uf;

  /* ---- 2. labels: smallest gid of the global fragment, indexed by root ---- */
  int64_t *lab = ms_calloc(n ? n : 1, sizeof *lab);
  int *cnt = ms_calloc((size_t)P, sizeof(int));
  int rounds = 0;
  st = global_labels(p, n_owned, ghost_owner, P, uf, cnt, lab, &rounds);
  if (st != MS_OK) {
    free(lab);
    free(cnt);
    return st;
  }

  /* ---- 3. local fragments: distinct labels of owned particles, ascending ---- */
  int64_t *L = ms_calloc(n_owned + 1, sizeof *L);
  size_t nl = 0;
  for (size_t i = 0; i < n_owned; ++i)
    if (!skipped(p, i)) L[nl++] = lab[cpl_uf_find(uf, i)];
  qsort(L, nl, sizeof *L, cmp_i64);
  size_t u = 0;
  for (size_t k = 0; k < nl; ++k)
    if (u == 0 || L[k] != L[u - 1]) L[u++] = L[k];
  nl = u;
  int64_t *lid = f->id; /* local fragment of each owned particle (global id at the end) */
  for (size_t i = 0; i < n_owned; ++i)
    lid[i] = skipped(p, i) ? -1 : find_sorted(L, nl, lab[cpl_uf_find(uf, i)]);
  free(lab);
  /* label owners: P contiguous gid ranges (monotone in the label, so L is grouped by owner) */
  int64_t gmax = -1;
  for (size_t i = 0; i < n_owned; ++i) gmax = p->gid[i] > gmax ? p->gid[i] : gmax;
  const double G = (double)par_max_int64(gmax) + 1;
  memset(cnt, 0, (size_t)P * sizeof(int));
  for (size_t k = 0; k < nl; ++k) {
    int r = (int)floor((double)L[k] / G * P);
    cnt[r < P ? r : P - 1]++;
  }
  plan fp;
  plan_init(&fp, P, cnt);
  free(cnt);

  /* pass 1 records [label | acc1] to the label owners */
  const int W1 = 1 + CPL_ACC1;
  double *acc1 = ms_calloc(nl * CPL_ACC1 + 1, sizeof *acc1);
  cpl_acc1_clear(acc1, nl);
  cpl_acc1_add(acc1, lid, n_owned, p, &o->box);
  double *sbuf = ms_calloc(nl * W1 + 1, sizeof *sbuf);
  double *rbuf = ms_calloc(fp.nr * W1 + 1, sizeof *rbuf);
  for (size_t k = 0; k < nl; ++k) {
    sbuf[k * W1] = (double)L[k];
    memcpy(sbuf + k * W1 + 1, acc1 + k * CPL_ACC1, CPL_ACC1 * sizeof *acc1);
  }
  plan_doubles(&fp, W1, false, sbuf, rbuf);
  /* the owner's fragments: received records sorted by (label, arrival = source rank order) */
  keyed *ord = ms_calloc(fp.nr + 1, sizeof *ord);
  for (size_t q = 0; q < fp.nr; ++q) ord[q] = (keyed){(int64_t)rbuf[q * W1], q};
  qsort(ord, fp.nr, sizeof *ord, cmp_keyed);
  size_t *frag_of = ms_calloc(fp.nr + 1, sizeof *frag_of); /* record → owner's fragment */
  size_t nF = 0;
  for (size_t a = 0; a < fp.nr; ++a) {
    if (a == 0 || ord[a].key != ord[a - 1].key) ++nF;
    frag_of[ord[a].pos] = nF - 1;
  }
  /* owner's rows: [acc1 | centre(3) | acc3] (ROW), the layout gathered at the end */
  double *row = ms_calloc(nF * ROW + 1, sizeof *row);
  double *ref = ms_calloc(3 * nF + 1, sizeof *ref), *off = ms_calloc(3 * nF + 1, sizeof *off);
  double *sum3 = ms_calloc(3 * nF + 1, sizeof *sum3);
  for (size_t k = 0; k < nF; ++k) cpl_acc1_clear(row + k * ROW, 1);
  for (size_t a = 0; a < fp.nr; ++a) { /* merged in (label, source rank) order */
    size_t q = ord[a].pos;
    cpl_acc1_merge(row + frag_of[q] * ROW, rbuf + q * W1 + 1);
  }
  for (size_t k = 0; k < nF; ++k) cpl_ref_point(row + k * ROW, &o->box, ref + 3 * k);
  /* reference points back; pass 2 */
  double *rep = ms_calloc(3 * fp.nr + 1, sizeof *rep);
  double *lref = ms_calloc(3 * nl + 1, sizeof *lref), *loff = ms_calloc(3 * nl + 1, sizeof *loff);
  double *lsum = ms_calloc(3 * nl + 1, sizeof *lsum);
  for (size_t q = 0; q < fp.nr; ++q) memcpy(rep + 3 * q, ref + 3 * frag_of[q], 3 * sizeof *rep);
  plan_doubles(&fp, 3, true, rep, lref);
  cpl_acc2_add(lsum, lid, n_owned, p, &o->box, lref);
  plan_doubles(&fp, 3, false, lsum, rbuf);
  for (size_t a = 0; a < fp.nr; ++a) {
    size_t q = ord[a].pos, k = frag_of[q];
    for (int d = 0; d < 3; ++d) sum3[3 * k + d] += rbuf[3 * q + d];
  }
  for (size_t k = 0; k < nF; ++k)
    cpl_centre(row[k * ROW + CPL_ACC1_MASS], ref + 3 * k, sum3 + 3 * k, &o->box, off + 3 * k,
               row + k * ROW + R_C);
  /* centre offsets back; pass 3 */
  for (size_t q = 0; q < fp.nr; ++q) memcpy(rep + 3 * q, off + 3 * frag_of[q], 3 * sizeof *rep);
  plan_doubles(&fp, 3, true, rep, loff);
  memset(lsum, 0, 3 * nl * sizeof *lsum);
  cpl_acc3_add(lsum, lid, n_owned, p, &o->box, lref, loff);
  plan_doubles(&fp, 1, false, lsum, rbuf);
  for (size_t a = 0; a < fp.nr; ++a) {
    size_t q = ord[a].pos;
    row[frag_of[q] * ROW + R_ACC3] += rbuf[q];
  }

  /* ---- global ids: rank r's fragments follow those of ranks < r ---- */
  long *nper = ms_calloc((size_t)P, sizeof(long));
  par_allgather_long((long)nF, nper);
  long offset = 0, total = 0;
  for (int r = 0; r < P; ++r) {
    if (r < ctx->rank) offset += nper[r];
    total += nper[r];
  }
  for (size_t q = 0; q < fp.nr; ++q) rep[q] = (double)(offset + (long)frag_of[q]);
  plan_doubles(&fp, 1, true, rep, lsum);
  for (size_t i = 0; i < n_owned; ++i)
    if (lid[i] >= 0) lid[i] = (int64_t)lsum[lid[i]];
  f->n_particles = n_owned;

  /* ---- 4. the table on every rank ---- */
  gather_table(f, row, nF, nper, total, P, o);
  f->rounds = rounds;

  plan_free(&fp);
  free(L);
  free(acc1);
  free(sbuf);
  free(rbuf);
  free(ord);
  free(frag_of);
  free(row);
  free(ref);
  free(off);
  free(sum3);
  free(rep);
  free(lref);
  free(loff);
  free(lsum);
  free(nper);
  return MS_OK;
}
