/* SPDX-License-Identifier: MIT */
/* cd_checkpoint.c — the cluster-dynamics state in a checkpoint file (docs/mpi.md).
 *
 * Group /cd of a checkpoint (core/checkpoint.c makes the file):
 *   position, velocity [N][3]; mass [N]; gid, material, flags [N] (int64); partners [N·16]
 *   (int64 gids, −1 = none or broken; bonded cutoff only); segments [ranks] (particles each
 *   rank wrote, in rank order); inside0 [64] (pairs inside R_c at the start, plain cutoff);
 *   attributes particles, step, t, dissipated, piston_work, broken_bonded, n_broken_bonds,
 *   nbuild (list builds so far, which sets the renumbering schedule).
 * Every rank writes its own particles as one segment (offsets by exclusive scan), so the file
 * does not depend on the decomposition. Bonded partners are stored as gids: indices change
 * with every renumbering and with the rank count, gids never do.
 *
 * Bitwise continuation: the run calls cd_sim_refresh right before each checkpoint and the
 * restart does the same thing in cd_sim_init, so both continue from the same particle order,
 * lists and forces; velocities and positions are stored exactly (IEEE doubles). Under MPI the
 * owner map of the coarse cells (/cd/owner) is stored too and reused by a restart on the same
 * rank count. */
#include "cd_impl.h"

#include <stdlib.h>
#include <string.h>

struct cd_restart {
  ptl_state *p;
  int64_t *partner_gid; /* [n][CD_MAX_PARTNERS] or NULL */
  int32_t *owner;       /* MPI, same rank count: coarse-cell owner map (NULL otherwise) */
  size_t owner_cells;
  double builds_since;
  double step, t, dissipated, piston_work, broken_bonded, n_broken_bonds, nbuild;
  double inside0[CD_MAX_MATERIALS * CD_MAX_MATERIALS];
};

/* Particles this rank writes: with the distributed model (cd_par.c) its owned ones
 * [0, p->nlocal); a serial run's are all of them (written by rank 0 alone when the same serial
 * run is made on several ranks). */
static size_t owned_count(const ms_ctx *ctx, const cd_sim *s) {
  return s->dd ? s->p->nlocal : (ctx->rank == 0 ? s->p->n : 0);
}

static const char *const attr_names[] = {
    "step", "t", "dissipated", "piston_work", "broken_bonded", "n_broken_bonds", "nbuild"};
enum { N_ATTR = sizeof attr_names / sizeof *attr_names };

ms_status cd_checkpoint_write(ms_h5 *h, const ms_ctx *ctx, const cd_sim *s) {
  const ptl_state *p = s->p;
  const size_t n = owned_count(ctx, s);
  double *buf = ms_calloc(3 * n + 1, sizeof *buf);
  int64_t *ibuf = ms_calloc((s->partners ? CD_MAX_PARTNERS : 1) * n + 1, sizeof *ibuf);
  ms_status st = MS_OK;
  const double *xyz[2][3] = {{p->x, p->y, p->z}, {p->vx, p->vy, p->vz}};
  for (int k = 0; k < 2 && st == MS_OK; k++) {
    for (size_t i = 0; i < n; i++)
      for (int a = 0; a < 3; a++) buf[3 * i + a] = xyz[k][a][i];
    st = ms_h5_write_doubles_dist(h, k ? "/cd/velocity" : "/cd/position", n, 3, buf,
                                  k ? "km/s" : "cm");
  }
  if (st == MS_OK) st = ms_h5_write_doubles_dist(h, "/cd/mass", n, 1, p->mass, "g");
  if (st == MS_OK) st = ms_h5_write_ints_dist(h, "/cd/gid", n, p->gid);
  for (int k = 0; k < 2 && st == MS_OK; k++) {
    const uint8_t *src = k ? p->flags : p->mat;
    for (size_t i = 0; i < n; i++) ibuf[i] = src[i];
    st = ms_h5_write_ints_dist(h, k ? "/cd/flags" : "/cd/material", n, ibuf);
  }
  if (st == MS_OK && s->partners) {
    for (size_t q = 0; q < n * CD_MAX_PARTNERS; q++) {
      int32_t j = s->partners[q];
      ibuf[q] = j >= 0 ? p->gid[j] : -1;
    }
    st = ms_h5_write_ints_dist(h, "/cd/partners", n * CD_MAX_PARTNERS, ibuf);
  }
  double seg = (double)n, inside0[CD_MAX_MATERIALS * CD_MAX_MATERIALS];
  for (int k = 0; k < CD_MAX_MATERIALS * CD_MAX_MATERIALS; k++)
    inside0[k] = (double)s->n_inside0[k / CD_MAX_MATERIALS][k % CD_MAX_MATERIALS];
  if (st == MS_OK) st = ms_h5_write_doubles_dist(h, "/cd/segments", 1, 1, &seg, NULL);
  if (st == MS_OK)
    st = ms_h5_write_doubles_dist(h, "/cd/inside0", ctx->rank == 0 ? 64 : 0, 1, inside0, NULL);
  /* the balance accumulators are per-rank shares under MPI: the file holds their sums */
  double acc[4] = {s->dissipated, s->piston_work, s->broken_bonded, (double)s->n_broken_bonds};
  if (s->dd) par_sum_doubles(acc, 4);
  const double vals[N_ATTR] = {(double)s->step,      s->t, acc[0], acc[1], acc[2], acc[3],
                               (double)s->nl->nbuild};
  for (int k = 0; k < N_ATTR && st == MS_OK; k++)
    st = ms_h5_attr_double(h, "/cd", attr_names[k], vals[k]);
  if (st == MS_OK && s->dd) { /* the decomposition, for a restart on as many ranks */
    size_t ncells = 0;
    long since = 0;
    const int32_t *owner = cd_dd_owner(s->dd, &ncells, &since);
    const size_t mine = ctx->rank == 0 ? ncells : 0;
    int64_t *o = ms_calloc(mine + 1, sizeof *o);
    for (size_t c = 0; c < mine; c++) o[c] = owner[c];
    st = ms_h5_write_ints_dist(h, "/cd/owner", mine, o);
    free(o);
    if (st == MS_OK) st = ms_h5_attr_double(h, "/cd", "builds_since", (double)since);
  }
  if (st == MS_OK) st = ms_h5_attr_double(h, "/cd", "particles", par_sum_double(seg));
  free(buf);
  free(ibuf);
  return st;
}

/* Reads `name` rows [row0, row0 + nrow) with `ncol` values each into a malloc'd array. */
static ms_status read_d(ms_h5r *h, const char *name, size_t row0, size_t nrow, size_t ncol,
                        double **v, dk_errors *e) {
  size_t nr = 0, nc = 0;
  ms_status st = ms_h5_read_doubles_rows(h, name, row0, nrow, v, &nr, &nc, e);
  if (st == MS_OK && (nr != nrow || nc != ncol)) {
    dk_error_at(e, "checkpoint", 0, 0, "'%s' has rows of %zu values, expected %zu", name, nc, ncol);
    st = MS_ERR_INPUT;
  }
  return st;
}
static ms_status read_i(ms_h5r *h, const char *name, size_t row0, size_t nrow, int64_t **v,
                        dk_errors *e) {
  size_t nr = 0, nc = 0;
  ms_status st = ms_h5_read_ints_rows(h, name, row0, nrow, v, &nr, &nc, e);
  if (st == MS_OK && (nr != nrow || nc != 1)) {
    dk_error_at(e, "checkpoint", 0, 0, "'%s' is not a list of %zu integers", name, nrow);
    st = MS_ERR_INPUT;
  }
  return st;
}

cd_restart *cd_restart_read(ms_h5r *h, const ms_ctx *ctx, int dim, bool bonded, dk_errors *e) {
  cd_restart *r = ms_calloc(1, sizeof *r);
  double total = 0, ranks = 0, *dseg = NULL, *pos = NULL, *vel = NULL, *mass = NULL, *in0 = NULL;
  int64_t *gid = NULL, *mat = NULL, *flags = NULL;
  double *vals[N_ATTR] = {
      &r->step,           &r->t,     &r->dissipated, &r->piston_work, &r->broken_bonded,
      &r->n_broken_bonds, &r->nbuild};
  ms_status st = ms_h5_read_attr_double(h, "/cd", "particles", &total, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/", "ranks", &ranks, e);
  for (int k = 0; k < N_ATTR && st == MS_OK; k++)
    st = ms_h5_read_attr_double(h, "/cd", attr_names[k], vals[k], e);
  if (st == MS_OK && !(total >= 1 && total < 4e9 && ranks >= 1 && ranks < 1e7 && r->step >= 0)) {
    dk_error_at(e, "checkpoint", 0, 0, "implausible header: %g particles on %g ranks, step %g",
                total, ranks, r->step);
    st = MS_ERR_INPUT;
  }
  /* Every rank reads every row, as the set-up generates the whole lattice on every rank;
   * cd_sim_init then keeps the particles this rank's cells own (on the same rank count, with
   * the checkpoint's owner map: exactly the segment it wrote, in its order). Reading only the
   * own segment (row0 = Σ segments of lower ranks) would need a set-up that starts from
   * disjoint shares with the partners of other ranks as gids. */
  const size_t row0 = 0, nrow = (size_t)total;
  if (st == MS_OK) st = read_d(h, "/cd/segments", 0, (size_t)ranks, 1, &dseg, e);
  if (st == MS_OK) {
    double sum = 0;
    for (size_t k = 0; k < (size_t)ranks; k++) sum += dseg[k];
    if (sum != total) {
      dk_error_at(e, "checkpoint", 0, 0, "segments hold %g particles, the header says %g", sum,
                  total);
      st = MS_ERR_INPUT;
    }
  }
  if (st == MS_OK) st = read_d(h, "/cd/position", row0, nrow, 3, &pos, e);
  if (st == MS_OK) st = read_d(h, "/cd/velocity", row0, nrow, 3, &vel, e);
  if (st == MS_OK) st = read_d(h, "/cd/mass", row0, nrow, 1, &mass, e);
  if (st == MS_OK) st = read_i(h, "/cd/gid", row0, nrow, &gid, e);
  if (st == MS_OK) st = read_i(h, "/cd/material", row0, nrow, &mat, e);
  if (st == MS_OK) st = read_i(h, "/cd/flags", row0, nrow, &flags, e);
  if (st == MS_OK) st = read_d(h, "/cd/inside0", 0, 64, 1, &in0, e);
  if (st == MS_OK && bonded)
    st = read_i(h, "/cd/partners", row0 * CD_MAX_PARTNERS, nrow * CD_MAX_PARTNERS, &r->partner_gid,
                e);
  /* same rank count: the owner map, so every rank gets its old particles back in their order */
  if (st == MS_OK && (int)ranks == ctx->size && ctx->size > 1 && ms_h5_exists(h, "/cd/owner")) {
    int64_t *o = NULL;
    size_t nc = 0, ncol = 0;
    st = ms_h5_read_ints_rows(h, "/cd/owner", 0, SIZE_MAX, &o, &nc, &ncol, e);
    if (st == MS_OK) st = ms_h5_read_attr_double(h, "/cd", "builds_since", &r->builds_since, e);
    if (st == MS_OK) {
      r->owner = ms_calloc(nc + 1, sizeof *r->owner);
      r->owner_cells = nc;
      for (size_t c = 0; c < nc && st == MS_OK; c++) {
        if (o[c] < 0 || o[c] >= ctx->size) {
          dk_error_at(e, "checkpoint", 0, 0, "'/cd/owner' names rank %lld", (long long)o[c]);
          st = MS_ERR_INPUT;
        }
        r->owner[c] = (int32_t)o[c];
      }
    }
    free(o);
  }
  if (st == MS_OK) {
    ms_must(ptl_state_create(&(ptl_state_params){.cap = nrow, .dim = dim}, &r->p),
            "ptl_state_create");
    r->p->n = r->p->nlocal = nrow;
    for (size_t i = 0; i < nrow; i++) {
      r->p->x[i] = pos[3 * i], r->p->y[i] = pos[3 * i + 1], r->p->z[i] = pos[3 * i + 2];
      r->p->vx[i] = vel[3 * i], r->p->vy[i] = vel[3 * i + 1], r->p->vz[i] = vel[3 * i + 2];
      r->p->fx[i] = r->p->fy[i] = r->p->fz[i] = 0.0;
      r->p->mass[i] = mass[i];
      r->p->gid[i] = gid[i];
      r->p->mat[i] = (uint8_t)mat[i];
      r->p->flags[i] = (uint8_t)flags[i];
      if (gid[i] < 0 || gid[i] >= (int64_t)total || mat[i] < 0 || mat[i] >= CD_MAX_MATERIALS ||
          flags[i] < 0 || flags[i] > 255 || !(mass[i] > 0)) {
        dk_error_at(e, "checkpoint", 0, 0,
                    "particle row %zu is damaged (gid %lld, material "
                    "%lld, mass %g)",
                    row0 + i, (long long)gid[i], (long long)mat[i], mass[i]);
        st = MS_ERR_INPUT;
        break;
      }
    }
    memcpy(r->inside0, in0, sizeof r->inside0);
  }
  free(dseg), free(pos), free(vel), free(mass), free(in0), free(gid), free(mat), free(flags);
  if (st != MS_OK) {
    cd_restart_destroy(&r);
    return NULL;
  }
  return r;
}

ptl_state *cd_restart_take_particles(cd_restart *r) {
  ptl_state *p = r->p;
  r->p = NULL;
  return p;
}

double cd_restart_time(const cd_restart *r) { return r->t; }
long cd_restart_step(const cd_restart *r) { return (long)r->step; }

ms_status cd_sim_init_restart(cd_sim *s, const cd_restart *r, dk_errors *e) {
  ptl_state *p = s->p;
  if (r->partner_gid) { /* gids back to this rank's indices */
    int64_t gmax = -1;
    for (size_t i = 0; i < p->n; i++) gmax = p->gid[i] > gmax ? p->gid[i] : gmax;
    int32_t *index_of = ms_calloc((size_t)gmax + 1, sizeof *index_of);
    for (int64_t g = 0; g <= gmax; g++) index_of[g] = -1;
    for (size_t i = 0; i < p->n; i++) index_of[p->gid[i]] = (int32_t)i;
    s->partners = ms_aligned_alloc(p->cap * CD_MAX_PARTNERS, sizeof(int32_t));
    for (size_t q = 0; q < p->n * CD_MAX_PARTNERS; q++) {
      int64_t g = r->partner_gid[q];
      s->partners[q] = g >= 0 && g <= gmax ? index_of[g] : -1;
      if (g >= 0 && s->partners[q] < 0) {
        dk_error_at(e, "checkpoint", 0, 0,
                    "a bonded partner (gid %lld) of particle %lld is "
                    "missing",
                    (long long)g, (long long)p->gid[q / CD_MAX_PARTNERS]);
        free(index_of);
        return MS_ERR_INPUT;
      }
    }
    free(index_of);
  }
  for (int k = 0; k < CD_MAX_MATERIALS * CD_MAX_MATERIALS; k++)
    s->n_inside0[k / CD_MAX_MATERIALS][k % CD_MAX_MATERIALS] = (long)r->inside0[k];
  s->have_inside0 = true;
  s->t = r->t;
  s->step = (long)r->step;
  s->dissipated = r->dissipated;
  s->piston_work = r->piston_work;
  s->broken_bonded = r->broken_bonded;
  s->n_broken_bonds = (long)r->n_broken_bonds;
  if (s->mpi_on && par_size() > 1 && par_rank() != 0) /* MPI: the sums live on rank 0 */
    s->dissipated = s->piston_work = s->broken_bonded = 0, s->n_broken_bonds = 0;
  if (r->owner) s->mpi.owner = r->owner, s->mpi.owner_cells = r->owner_cells;
  ms_status st = cd_sim_init(s); /* renumbers (a no-op on this order), lists, forces */
  s->mpi.owner = NULL;
  if (st == MS_OK) s->nl->nbuild = (long)r->nbuild;
  if (st == MS_OK && s->dd && r->owner) cd_dd_set_builds_since(s->dd, (long)r->builds_since);
  return st;
}

static void cd_restart_free(cd_restart *r) {
  if (!r) return;
  ptl_state_destroy(&r->p);
  free(r->partner_gid);
  free(r->owner);
  free(r);
}

void cd_restart_destroy(cd_restart **r) {
  if (!r) return;
  cd_restart_free(*r);
  *r = NULL;
}
