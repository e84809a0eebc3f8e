/* SPDX-License-Identifier: MIT */
/* dm_impact_checkpoint.c — checkpoints and restart of the deck problem type `impact`
 * (docs/input-impact.md "Checkpoints, restart and MPI ranks"). OUTDIR/impact_checkpoint.h5
 * (core/checkpoint.c: written as .part and renamed, stamped with the deck's hash) holds
 *  - /dm_fin: the finite-deformation model through dm_fin_checkpoint.c, the code of the
 *    discrete_model problem's and the coupled region's checkpoints (every array a step reads:
 *    w, u, e, ρ, p, q, J, ε_p, E_hg, F, s, V P A⁻¹, σ, the forces, the wall's and contact's
 *    external force and its accumulated work, the failed particles, broken bonds and their
 *    contact state, the step counter and the next step's length);
 *  - /impact/X, /impact/volume: the reference configuration, which a reference update moves
 *    (X ← x, V ← J V): a restart rebuilds the families on it, as the update did (the same
 *    dm_model_create on the same bits gives the same families, A⁻¹ and bond-penalty κ);
 *    with symmetry planes the real particles' rows only (everything in the file is the real
 *    particles'): the update changes which lie within a horizon of a plane, so a restart
 *    rebuilds the mirror ghosts on the checkpoint's reference (dm_sym_ghosts) and fills their
 *    rows from their partners (dm_sym_sync);
 *  - /impact/families (families: keep or merge, either scope): the bond lists, each family's
 *    own bond vectors (per-family references), A⁻¹, cond and κ of every row as they are
 *    (dm_family_checkpoint.c; kept or merged families are not a function of X), and the count
 *    of family updates;
 *  - /impact/history: the rows of impact_history.csv so far, with the run's scalars as its
 *    attributes: time, the history's stride (energy_every, doubled when thinned), snapshots
 *    written, the next checkpoint time, the wall's and the contact's stored energy and contact
 *    counts of the last force evaluation, and the summary's running extrema (energy balance,
 *    momentum, J, stretch), reference updates and the energy they released.
 * A checkpoint changes nothing of the run (no list is rebuilt, nothing recomputed), so a run
 * continued from any checkpoint ends with the bytes of the uninterrupted run, and a checkpoint
 * can be written wherever an interrupt arrives. The run is replicated on MPI ranks
 * (dm_impact_run.h): rank 0's rows are the whole state, so a checkpoint restarts on any rank
 * count. */
#include "dm_impact_run.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DMI_CHECKPOINT_FORMAT "mscale impact checkpoint 1"
#define DMI_FAMILIES          "/impact/families"

bool dmi_checkpoint_due(dmi_run *r) {
  const dm_impact *p = r->p;
  const long step = r->f->step;
  if (step <= r->step0) return false; /* the state the run started from is on disk already */
  if (p->checkpoint_every > 0) return step % p->checkpoint_every == 0;
  if (!(p->checkpoint_time > 0) || r->t < r->ckpt_next * (1 - 1e-12)) return false;
  r->ckpt_next = (floor(r->t / p->checkpoint_time * (1 + 1e-12)) + 1) * p->checkpoint_time;
  return true;
}

/* The run's scalars (attributes of /impact/history), in one list for writing and reading. */
enum { NSCALAR = 18 };
static void scalars(dmi_run *r, double *v[NSCALAR], const char *name[NSCALAR], double buf[5]) {
  dm_impact_summary *s = &r->p->sum;
  static const char *const nm[NSCALAR] = {
      "t",           "energy_every",  "next_snapshot",  "next_checkpoint_time",
      "wall_energy", "wall_contacts", "contact_energy", "body_contacts",
      "energy_err",  "wall_err",      "p_total",        "p_transverse",
      "p_normal",    "J_min",         "J_max",          "stretch_max",
      "ref_updates", "released"};
  double *const p[NSCALAR] = {&r->t,
                              &buf[0],
                              &buf[1],
                              &r->ckpt_next,
                              &r->wl->stored,
                              &buf[2],
                              &r->wl->ct->stored,
                              &buf[3],
                              &s->energy_err,
                              &s->wall_err,
                              &s->p_total,
                              &s->p_transverse,
                              &s->p_normal,
                              &s->J_min,
                              &s->J_max,
                              &s->stretch_max,
                              &buf[4],
                              &s->released};
  memcpy(v, p, sizeof p);
  memcpy(name, nm, sizeof nm);
}

ms_status dmi_checkpoint_write(dmi_run *r) {
  const ms_ctx *ctx = r->ctx;
  const bool owner = ctx->rank == 0; /* replicated: rank 0's rows are the whole state */
  const dm_state *s = r->f->m->s;
  ms_h5 *h = ms_ckpt_create(ctx, DMI_CHECKPOINT_NAME, DMI_CHECKPOINT_FORMAT, r->p->deck_hash);
  if (!h) return par_agree_status(MS_ERR_IO);
  ms_status st = dm_fin_checkpoint_write(r->f, s, h, "/dm_fin", owner);
  /* the real particles' rows (with symmetry planes the mirror ghosts follow them: rebuilt on
   * restart, their number changes with reference updates) */
  const size_t n = owner ? r->f->n : 0;
  if (st == MS_OK) st = ms_h5_write_doubles_dist(h, "/impact/X", n, 3, s->X, "cm");
  if (st == MS_OK) st = ms_h5_write_doubles_dist(h, "/impact/volume", n, 1, s->vol, "cm^3");
  if (st == MS_OK && r->p->ref_keep) /* kept, merged or per-family: the families as they are */
    st = dm_families_checkpoint_write(r->f->m, h, DMI_FAMILIES, owner);
  if (st == MS_OK && r->p->ref_keep)
    st =
        ms_h5_attr_double(h, DMI_FAMILIES "/sizes", "family_updates", (double)r->p->family_updates);
  if (st == MS_OK) /* at least the row of step 0 (recorded before any checkpoint) */
    st = ms_h5_write_doubles_dist(h, "/impact/history", owner ? r->nh : 0, r->ncol, r->hist,
                                  "impact_history.csv");
  double *v[NSCALAR],
      buf[5] = {(double)r->p->energy_every, (double)r->next_out, (double)r->wl->in_contact,
                (double)r->wl->ct->in_contact, (double)r->p->sum.ref_updates};
  const char *name[NSCALAR];
  scalars(r, v, name, buf);
  for (int k = 0; k < NSCALAR && st == MS_OK; ++k)
    st = ms_h5_attr_double(h, "/impact/history", name[k], *v[k]);
  return ms_ckpt_commit(ctx, h, st, DMI_CHECKPOINT_NAME, r->f->step);
}

/* The reference configuration of the checkpoint (its real particles); the families rebuilt on
 * it when a reference update had moved it, as dm_refamily.c's update did: with symmetry planes
 * the mirror ghosts of the new reference first (dm_sym_ghosts: which particles lie within a
 * horizon of a plane has changed), then dm_model_create on the same X and V, the ghosts' rows
 * (dm_sym_resize), κ. Kept, merged or per-family families (reference_update.families: keep,
 * merge) are not a function of X: read as they are (dm_family_checkpoint.c), on the ghost set
 * of the set-up, which such updates never change (dm_refamily.c, dm_fin_local.c). */
static ms_status read_reference(dmi_run *r, ms_h5r *h, dk_errors *e) {
  dm_fin *f = r->f;
  dm_state *s = f->m->s;
  const size_t n = f->n;
  double *X = ms_calloc(3 * n + 1, sizeof *X), *V = ms_calloc(n + 1, sizeof *V);
  size_t nr = 0;
  ms_status st = dm_ckpt_read_rows(h, "/impact/X", 3, n, true, X, &nr, e);
  if (st == MS_OK) st = dm_ckpt_read_rows(h, "/impact/volume", 1, n, true, V, &nr, e);
  const bool moved =
      st == MS_OK && (memcmp(X, s->X, 3 * n * sizeof *X) || memcmp(V, s->vol, n * sizeof *V));
  if (st == MS_OK && r->p->ref_keep) { /* kept, merged or per-family: stored, not rebuilt */
    double nfam = 0;
    st = dm_families_checkpoint_read(f->m, h, DMI_FAMILIES, e);
    if (st == MS_OK)
      st = ms_h5_read_attr_double(h, DMI_FAMILIES "/sizes", "family_updates", &nfam, e);
    if (st == MS_OK) {
      memcpy(s->X, X, 3 * n * sizeof *X), memcpy(s->vol, V, n * sizeof *V);
      if (f->sym.n)
        dm_sym_reference(s, n, &f->sym); /* the ghosts' X and V of the moved reference */
      r->p->family_updates = (long)nfam;
    }
  } else if (moved) {
    memcpy(s->X, X, 3 * n * sizeof *X), memcpy(s->vol, V, n * sizeof *V);
    if (f->sym.n) dm_sym_ghosts(s, n, &f->sym, f->m->opt.horizon, f->par.ell);
    dm_model *m = NULL;
    st = dm_model_create(&(dm_model_params){.state = s, .opt = f->m->opt, .ctx = r->ctx}, &m);
    if (st == MS_OK) {
      dm_model *old = f->m;
      f->m = m;
      dm_model_destroy(&old);
      if (f->sym.n) dm_sym_resize(f, f->imat_all); /* v̄, v_close, materials of the ghosts */
      dm_fin_bond_penalty(f);
    } else {
      dk_error_at(e, "checkpoint", 0, 0,
                  "the families of the checkpoint's reference configuration cannot be built");
      st = MS_ERR_INPUT;
    }
  }
  free(X), free(V);
  return st;
}

static ms_status read_run(dmi_run *r, ms_h5r *h, dk_errors *e) {
  ms_status st =
      dm_ckpt_read_rows(h, "/impact/history", r->ncol, r->nhmax, false, r->hist, &r->nh, e);
  double *v[NSCALAR], buf[5] = {0, 0, 0, 0, 0};
  const char *name[NSCALAR];
  scalars(r, v, name, buf);
  for (int k = 0; k < NSCALAR && st == MS_OK; ++k)
    st = ms_h5_read_attr_double(h, "/impact/history", name[k], v[k], e);
  if (st == MS_OK && (buf[0] < 1 || buf[1] < 0 || buf[1] > (double)r->p->nparticle_times + 1)) {
    dk_error_at(e, "checkpoint", 0, 0,
                "'/impact/history': energy_every %g or next_snapshot %g "
                "out of range for this deck",
                buf[0], buf[1]);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) {
    r->p->energy_every = (long)buf[0], r->next_out = (size_t)buf[1];
    r->wl->in_contact = (long)buf[2], r->wl->ct->in_contact = (long)buf[3];
    r->p->sum.ref_updates = (long)buf[4];
  }
  return st;
}

ms_status dmi_restart(dmi_run *r) {
  const ms_ctx *ctx = r->ctx;
  dk_errors e;
  dk_errors_init(&e);
  ms_status st = MS_ERR_INPUT;
  ms_h5r *h = ms_ckpt_open(ctx->restart, DMI_CHECKPOINT_FORMAT, r->p->deck_hash, &e);
  if (h) {
    st = read_reference(r, h, &e);
    if (st == MS_OK) st = dm_fin_checkpoint_read(r->f, r->f->m->s, h, "/dm_fin", &e);
    if (st == MS_OK) st = read_run(r, h, &e);
    ms_h5_close_read(h);
  }
  st = par_agree_status(st);
  if (st != MS_OK) {
    if (ctx->rank == 0) dk_errors_print(&e, stderr);
    ms_log(ctx, MS_LOG_ERROR, "impact: cannot restart from %s", ctx->restart);
    st = MS_ERR_INPUT;
  } else {
    r->step0 = r->f->step;
    ms_log(ctx, MS_LOG_INFO, "impact: restarted from %s at step %ld (t = %.9g %s)", ctx->restart,
           r->step0, ms_out_time(r->t), ms_out_time_label());
  }
  dk_errors_free(&e);
  return st;
}
