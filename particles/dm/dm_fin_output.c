/* SPDX-License-Identifier: MIT */
/* dm_fin_output.c — particle snapshots of the discrete-model problem with response: eos
 * (HDF5 + XDMF through ptl_write_snapshot, docs/output.md) and the last good state that a failed
 * step leaves to show: a step that meets J ≤ 0 or a non-finite energy, pressure or force has
 * already changed the arrays, so the state at its start is copied before every step (w, u, e,
 * E_hg, ε_p, p, q, σ_u: 96 B per particle; J is recomputed from w). p is copied, not recomputed:
 * the model's p is the one of its last stress evaluation, at the e of the step's middle. */
#include "dm_fin_run.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void dmf_sigma_u(const dm_fin *f, double *out) {
  for (size_t i = 0; i < f->n; ++i) {
    const double *sd = &f->s[9 * i];
    double ss = 0;
    for (int a = 0; a < 9; ++a) ss += sd[a] * sd[a];
    out[i] = sqrt(1.5 * ss);
  }
}

dmf_fields dmf_live_fields(dmf_run *r) {
  const dm_fin *f = r->f;
  dmf_sigma_u(f, r->sigma_u);
  return (dmf_fields){.w = r->s.w,
                      .u = r->s.u,
                      .e = f->e,
                      .ehg = f->ehg,
                      .eps_p = f->eps_p,
                      .q = f->q,
                      .sigma_u = r->sigma_u,
                      .p = f->p,
                      .J = f->J};
}

/* F_i of displacements w (the least-squares fit of dm_finite.c, its own arithmetic: a state's J
 * is the same bits here)
 * and the family's non-affine part: √(Σ_k |Δw_ik − (F − I)ξ_ik|² / Σ_k |ξ_ik|²), the bond
 * stretch the fit cannot represent — the zero-energy (hourglass) modes the bond penalty acts
 * on (docs/particles-dm.md "Finite deformation"); 0 under any uniform deformation. */
static double kinematics(const dm_model *m, const double *w, size_t i, double F[9]) {
  double C[9];
  dm_fin_displacement_gradient(m, w, i, C);
  double zz = 0, xx = 0;
  for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
    const size_t k = m->nbr[b];
    double xi[3], dw[3];
    if (m->xref) /* per-family references (dm_fin_local.c) */
      dm_fin_local_bond(m, w, i, b, xi, dw);
    else {
      dm_bond_vector(m, i, b, xi);
      for (int a = 0; a < 3; ++a) dw[a] = w[3 * k + a] - w[3 * i + a];
    }
    for (int a = 0; a < 3; ++a) {
      const double z = dw[a] - (C[3 * a] * xi[0] + C[3 * a + 1] * xi[1] + C[3 * a + 2] * xi[2]);
      zz += z * z, xx += xi[a] * xi[a];
    }
  }
  for (int a = 0; a < 9; ++a) F[a] = C[a];
  F[0] += 1.0, F[4] += 1.0, F[8] += 1.0;
  return xx > 0 ? sqrt(zz / xx) : 0.0;
}

ms_status dmf_write_snapshot(const dmf_run *r, const dmf_fields *fl, double t, long step,
                             const char *name) {
  const ms_ctx *ctx = &r->octx;
  if (!ctx->outdir || !ctx->outdir[0]) return MS_OK;
  const dm_problem *p = r->p;
  const dm_state *s = &r->s;
  const size_t n = r->nreal;
  /* columns: x y z, vx vy vz, p, J, rho, e_hourglass, hourglass */
  double *buf = ms_calloc(11 * n + 1, sizeof *buf);
  double *x = buf, *v = buf + 3 * n, *pres = buf + 6 * n, *J = buf + 7 * n, *rho = buf + 8 * n;
  double *ehs = buf + 9 * n, *hg = buf + 10 * n;
  int64_t *mat = ms_calloc(n + 1, sizeof *mat);
  for (size_t i = 0; i < n; ++i) {
    double F[9];
    hg[i] = kinematics(r->m, fl->w, i, F);
    for (int a = 0; a < 3; ++a) {
      x[a * n + i] = s->X[3 * i + a] + fl->w[3 * i + a];
      v[a * n + i] = fl->u[3 * i + a];
    }
    const double rho0 = s->mass[i] / s->vol[i];
    J[i] = fl->J ? fl->J[i] : dm_det3(F);
    rho[i] = rho0 / J[i];
    pres[i] = fl->p[i];
    ehs[i] = fl->ehg[i] / s->mass[i];
    mat[i] = r->imat[i];
  }
  const ptl_snapshot_data data[] = {{"particles/X", s->X, NULL, 3, "cm"},
                                    {"particles/w", fl->w, NULL, 3, "cm"},
                                    {"particles/pressure", pres, NULL, 1, "GPa"},
                                    {"particles/q", fl->q, NULL, 1, "GPa"},
                                    {"particles/density", rho, NULL, 1, "g/cm^3"},
                                    {"particles/energy", fl->e, NULL, 1, "kJ/g"},
                                    {"particles/von_mises", fl->sigma_u, NULL, 1, "GPa"},
                                    {"particles/eps_p", fl->eps_p, NULL, 1, "1"},
                                    {"particles/J", J, NULL, 1, "1"},
                                    {"particles/e_hourglass", ehs, NULL, 1, "kJ/g"},
                                    {"particles/hourglass", hg, NULL, 1, "1"},
                                    {"particles/material", NULL, mat, 1, NULL}};
  const ms_xdmf_attr xdmf[] = {{"velocity", "particles/v", 3, false},
                               {"displacement", "particles/w", 3, false},
                               {"pressure", "particles/pressure", 1, false},
                               {"q", "particles/q", 1, false},
                               {"density", "particles/density", 1, false},
                               {"energy", "particles/energy", 1, false},
                               {"von_mises", "particles/von_mises", 1, false},
                               {"eps_p", "particles/eps_p", 1, false},
                               {"J", "particles/J", 1, false},
                               {"e_hourglass", "particles/e_hourglass", 1, false},
                               {"hourglass", "particles/hourglass", 1, false}};
  const double *const xc[3] = {x, x + n, x + 2 * n}, *const vc[3] = {v, v + n, v + 2 * n};
  ptl_snapshot snap = ptl_snapshot_of(n, xc, vc, s->mass, t, false);
  char names[4096];
  dmp_material_table(p, names, sizeof names);
  snap.material_names = names; /* the index table of particles/material */
  snap.ndata = sizeof data / sizeof data[0];
  snap.data = data;
  snap.nxdmf = sizeof xdmf / sizeof xdmf[0];
  snap.xdmf = xdmf;
  ptl_snapshot_attr_add(&snap, "time", t);
  ptl_snapshot_attr_add(&snap, "step", (double)step);
  ptl_snapshot_attr_add(&snap, "r0", p->h);
  for (int a = 0; a < p->dim; ++a)
    if (p->face[2 * a] == FACE_PERIODIC)
      ptl_snapshot_period_add(&snap, a, p->hi[a] - p->lo[a], p->lo[a]);
  char *path = ms_out_path(ctx, name);
  const ms_status st = ptl_write_snapshot(path, &snap);
  if (st != MS_OK) ms_log(ctx, MS_LOG_WARN, "discrete model: could not write %s", path);
  free(path);
  free(buf);
  free(mat);
  return st;
}

void dmf_backup_alloc(dmf_run *r) {
  const size_t n = r->s.n ? r->s.n : 1;
  dmf_backup *b = &r->bk;
  /* w: +1 for dm_finite.c's 4-lane loads */
  b->w = ms_calloc(3 * n + 1, sizeof(double)), b->u = ms_calloc(3 * n, sizeof(double));
  b->e = ms_calloc(n, sizeof(double)), b->ehg = ms_calloc(n, sizeof(double));
  b->eps_p = ms_calloc(n, sizeof(double)), b->q = ms_calloc(n, sizeof(double));
  b->p = ms_calloc(n, sizeof(double)), b->sigma_u = ms_calloc(n, sizeof(double));
}

void dmf_backup_free(dmf_run *r) {
  dmf_backup *b = &r->bk;
  free(b->w), free(b->u), free(b->e), free(b->ehg), free(b->eps_p), free(b->q), free(b->p);
  free(b->sigma_u);
  memset(b, 0, sizeof *b);
}

void dmf_backup_take(dmf_run *r, double t) {
  const dm_fin *f = r->f;
  dmf_backup *b = &r->bk;
  const size_t n = r->s.n;
  memcpy(b->w, r->s.w, 3 * n * sizeof(double));
  memcpy(b->u, r->s.u, 3 * n * sizeof(double));
  memcpy(b->e, f->e, n * sizeof(double));
  memcpy(b->ehg, f->ehg, n * sizeof(double));
  memcpy(b->eps_p, f->eps_p, n * sizeof(double));
  memcpy(b->q, f->q, n * sizeof(double));
  memcpy(b->p, f->p, n * sizeof(double));
  dmf_sigma_u(f, b->sigma_u);
  b->t = t, b->step = f->step, b->valid = 1;
}

void dmf_report_unstable(dmf_run *r, size_t particle, const char *what, double value, double t) {
  const dmf_backup *b = &r->bk;
  const double *X = &r->s.X[3 * (particle < r->s.n ? particle : 0)];
  static const char name[] = PTL_SNAPSHOT_UNSTABLE;
  if (r->ctx->rank == 0) /* replicated: every rank found the same */
    ms_log(r->ctx, MS_LOG_ERROR,
           "discrete model (response eos): step %ld, t = %.9g %s: particle %zu (X = %g %g %g): "
           "%s = %g; the run stops, the last good state (step %ld, t = %.9g %s) is in %s",
           b->step + 1, ms_out_time(t), ms_out_time_label(), particle, X[0], X[1], X[2], what,
           value, b->step, ms_out_time(b->t), ms_out_time_label(), name);
  if (!b->valid) return;
  const dmf_fields fl = {.w = b->w,
                         .u = b->u,
                         .e = b->e,
                         .ehg = b->ehg,
                         .eps_p = b->eps_p,
                         .q = b->q,
                         .sigma_u = b->sigma_u,
                         .p = b->p};
  dmf_write_snapshot(r, &fl, b->t, b->step, name);
}
