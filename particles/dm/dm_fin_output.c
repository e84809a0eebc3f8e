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
static double kinematics(const dm_model *m, const double *w, const uint8_t *failed, size_t i,
                         double F[9]) {
  double C[9];
  dm_fin_displacement_gradient(m, w, failed, i, C);
  double zz = 0, xx = 0;
  for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
    const size_t k = m->nbr[b];
    if (failed && failed[k]) continue; /* a broken bond */
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
  double *pres = buf + 6 * n, *J = buf + 7 * n, *rho = buf + 8 * n;
  double *ehs = buf + 9 * n, *hg = buf + 10 * n;
  int64_t *mat = ms_calloc(n + 1, sizeof *mat);
  for (size_t i = 0; i < n; ++i) {
    double F[9];
    hg[i] = kinematics(r->m, fl->w, r->f ? r->f->failed : NULL, i, F);
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
  char names[4096]; /* the index table of particles/material */
  dmp_material_table(p, names, sizeof names);
  ptl_snapshot snap = dmp_snapshot_of(n, s->X, fl->w, fl->u, s->mass, t, buf); /* x, v columns */
  ptl_snapshot_contents(&snap, sizeof data / sizeof data[0], data, sizeof xdmf / sizeof xdmf[0],
                        xdmf, names, step);
  ptl_snapshot_attr_add(&snap, "r0", p->h);
  for (int a = 0; a < p->dim; ++a)
    if (p->face[2 * a] == FACE_PERIODIC)
      ptl_snapshot_period_add(&snap, a, p->hi[a] - p->lo[a], p->lo[a]);
  const ms_status st = dmp_snapshot_write(ctx, name, &snap, "discrete model");
  free(buf);
  free(mat);
  return st;
}

void dmp_backup_alloc(dmp_backup *b, size_t n, unsigned keep) {
  const size_t m = n ? n : 1;
  *b = (dmp_backup){.w = ms_calloc(3 * m + 1, sizeof(double)),
                    .u = ms_calloc(3 * m, sizeof(double)),
                    .e = ms_calloc(m, sizeof(double)),
                    .eps_p = ms_calloc(m, sizeof(double)),
                    .p = ms_calloc(m, sizeof(double)),
                    .ehg = keep & DMP_KEEP_EHG ? ms_calloc(m, sizeof(double)) : NULL,
                    .q = keep & DMP_KEEP_Q ? ms_calloc(m, sizeof(double)) : NULL,
                    .sigma_u = keep & DMP_KEEP_SIGMA_U ? ms_calloc(m, sizeof(double)) : NULL,
                    .rho = keep & DMP_KEEP_RHO ? ms_calloc(m, sizeof(double)) : NULL,
                    .J = keep & DMP_KEEP_J ? ms_calloc(m, sizeof(double)) : NULL,
                    .n = n};
}

void dmp_backup_free(dmp_backup *b) {
  free(b->w), free(b->u), free(b->e), free(b->eps_p), free(b->p);
  free(b->ehg), free(b->q), free(b->sigma_u), free(b->rho), free(b->J);
  memset(b, 0, sizeof *b);
}

static void copy_kept(double *to, const double *from, size_t n) {
  if (to) memcpy(to, from, n * sizeof(double));
}

void dmp_backup_take(dmp_backup *b, const dm_fin *f, double t) {
  const size_t n = b->n;
  copy_kept(b->w, f->m->s->w, 3 * n), copy_kept(b->u, f->m->s->u, 3 * n);
  copy_kept(b->e, f->e, n), copy_kept(b->eps_p, f->eps_p, n), copy_kept(b->p, f->p, n);
  copy_kept(b->ehg, f->ehg, n), copy_kept(b->q, f->q, n);
  copy_kept(b->rho, f->rho, n), copy_kept(b->J, f->J, n);
  if (b->sigma_u) dmf_sigma_u(f, b->sigma_u);
  b->t = t, b->step = f->step, b->valid = true;
}

void dmf_report_unstable(dmf_run *r, size_t particle, const char *what, double value, double t) {
  const dmp_backup *b = &r->bk;
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
