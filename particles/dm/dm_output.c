/* SPDX-License-Identifier: MIT */
/* dm_output.c — the files of the discrete-model problem: profiles (CSV), particle snapshots
 * (HDF5 + XDMF through ptl_write_snapshot), the sphere's radial profile, the probe and energy
 * histories and the run summary; and the report of an unstable step. */
#include "dm_problem_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void dmp_write_profile(const ms_ctx *ctx, const dm_problem *p, dm_model *m, size_t nreal, double t,
                       int index) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  const dm_state *s = m->s;
  char name[64];
  snprintf(name, sizeof name, "dm_profile_%03d.csv", index);
  char *path = ms_out_path(ctx, name);
  ms_afile af;
  if (ms_afile_open(&af, path) != MS_OK) {
    free(path);
    return;
  }
  double *S = malloc(9 * s->n * sizeof(double));
  dm_cauchy_stress(m, S);
  const char *names[] = {"x",   "y",   "z",   "w_x",      "w_y",       "w_z",
                         "u_x", "u_y", "u_z", "sigma_xx", "cauchy_xx", "exact"};
  const char *units[] = {"cm",   "cm",   "cm",   "cm",  "cm",  "cm",
                         "km/s", "km/s", "km/s", "GPa", "GPa", "GPa or cm"};
  char title[160];
  snprintf(title, sizeof title,
           "discrete model profile at t = %.9g %s; exact = sigma_xx (contact) or w_x (rod) "
           "where known, else 0",
           ms_out_time(t), ms_out_time_label());
  ms_csv_header(af.f, title, 12, names, units);
  for (size_t i = 0; i < nreal; ++i) {
    const double *X = &s->X[3 * i];
    if (p->dim == 3 && fabs(X[2] - (p->lo[2] + 0.5 * p->h)) > 1e-9 * p->h) continue;
    double ex = 0.0;
    const dm_layer *l0 = &p->layers[0];
    if (p->profile == PROF_CONTACT && p->nlayers >= 2) {
      const dm_layer *l1 = &p->layers[1];
      ex = dm_exact_contact_stress(X[0], t, p->length, p->amplitude, l0->rho, l0->K + 4 * l0->G / 3,
                                   l1->rho, l1->K + 4 * l1->G / 3);
    } else if (p->profile == PROF_ROD_TRIANGLE) {
      ex = dm_exact_rod_triangle(X[0], t, p->length, p->amplitude, dmp_wave_speed(p), 0);
    } else if (p->profile == PROF_ROD_SINE) {
      double c = dmp_wave_speed(p), L = p->length;
      ex = p->amplitude * L * sin(p->mode * M_PI * X[0] / (2 * L)) *
           cos(p->mode * M_PI * c * t / (2 * L));
    }
    double row[12] = {X[0],
                      X[1],
                      X[2],
                      s->w[3 * i],
                      s->w[3 * i + 1],
                      s->w[3 * i + 2],
                      s->u[3 * i],
                      s->u[3 * i + 1],
                      s->u[3 * i + 2],
                      m->sigma[9 * i],
                      S[9 * i],
                      ex};
    ms_csv_row(af.f, 12, row);
  }
  free(S);
  ms_afile_commit(&af);
  free(path);
}

/* The material table of the snapshots: the layers' names in layer order ("cu,cu,pb"; the
 * index of a particle's layer is its particles/material) into names[size]. */
void dmp_material_table(const dm_problem *p, char *names, size_t size) {
  names[0] = 0;
  for (size_t k = 0; k < p->nlayers; ++k)
    ptl_material_table_add(names, size, p->layers[k].name ? p->layers[k].name : "");
}

ptl_snapshot dmp_snapshot_of(size_t n, const double *X, const double *w, const double *u,
                             const double *mass, double t, double *xv) {
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      xv[a * n + i] = X[3 * i + a] + w[3 * i + a];
      xv[(3 + a) * n + i] = u[3 * i + a];
    }
  const double *const xc[3] = {xv, xv + n, xv + 2 * n};
  const double *const vc[3] = {xv + 3 * n, xv + 4 * n, xv + 5 * n};
  return ptl_snapshot_of(n, xc, vc, mass, t, false);
}

ms_status dmp_snapshot_write(const ms_ctx *ctx, const char *name, const ptl_snapshot *snap,
                             const char *who) {
  char *path = ms_out_path(ctx, name);
  const ms_status st = ptl_write_snapshot(path, snap);
  if (st != MS_OK) ms_log(ctx, MS_LOG_WARN, "%s: could not write %s", who, path);
  free(path);
  return st;
}

/* HDF5 snapshot of the real particles with an XDMF sidecar (ParaView), by ptl_write_snapshot,
 * in the layout every particle problem shares (docs/output.md, "Particle snapshots"): current
 * positions X + w (particles/x), velocity u (particles/v), mass, the layer's material index
 * (particles/material, names in material_names), the vertex ids and the particles.xmf series;
 * then the model's fields: reference positions, w, |u|, Cauchy stress (9 components) and its
 * pressure −tr Σ/3, von Mises intensity and Σ_xx; attributes time, step. */
void dmp_write_snapshot(const ms_ctx *ctx, const dm_problem *p, dm_model *m, size_t nreal, double t,
                        long step, const char *name) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  const dm_state *s = m->s;
  double *S = malloc(9 * s->n * sizeof(double));
  double *xv = malloc((6 * nreal + 1) * sizeof(double)), *sc = malloc(4 * nreal * sizeof(double));
  int64_t *mat = ms_calloc(nreal + 1, sizeof *mat);
  dm_cauchy_stress(m, S);
  double *speed = sc, *pres = sc + nreal, *vm = sc + 2 * nreal, *sxx = sc + 3 * nreal;
  for (size_t i = 0; i < nreal; ++i) {
    const double *u = &s->u[3 * i], *T = &S[9 * i];
    mat[i] = dmp_layer_at(p, s->X[3 * i]) - p->layers;
    speed[i] = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    pres[i] = -(T[0] + T[4] + T[8]) / 3.0;
    double s12 = 0.5 * (T[1] + T[3]), s23 = 0.5 * (T[5] + T[7]), s31 = 0.5 * (T[2] + T[6]);
    vm[i] = sqrt(0.5 * ((T[0] - T[4]) * (T[0] - T[4]) + (T[4] - T[8]) * (T[4] - T[8]) +
                        (T[8] - T[0]) * (T[8] - T[0]) + 6.0 * (s12 * s12 + s23 * s23 + s31 * s31)));
    sxx[i] = T[0];
  }
  const ptl_snapshot_data data[] = {
      {"particles/material", NULL, mat, 1, NULL},  {"particles/X", s->X, NULL, 3, "cm"},
      {"particles/w", s->w, NULL, 3, "cm"},        {"particles/speed", speed, NULL, 1, "km/s"},
      {"particles/cauchy", S, NULL, 9, "GPa"},     {"particles/pressure", pres, NULL, 1, "GPa"},
      {"particles/von_mises", vm, NULL, 1, "GPa"}, {"particles/sigma_xx", sxx, NULL, 1, "GPa"}};
  const ms_xdmf_attr xdmf[] = {
      {"velocity", "particles/v", 3, false},        {"mass", "particles/mass", 1, false},
      {"displacement", "particles/w", 3, false},    {"speed", "particles/speed", 1, false},
      {"pressure", "particles/pressure", 1, false}, {"von_mises", "particles/von_mises", 1, false},
      {"sigma_xx", "particles/sigma_xx", 1, false}};
  char names[4096];
  dmp_material_table(p, names, sizeof names);
  ptl_snapshot snap = dmp_snapshot_of(nreal, s->X, s->w, s->u, s->mass, t, xv);
  ptl_snapshot_contents(&snap, sizeof data / sizeof data[0], data, sizeof xdmf / sizeof xdmf[0],
                        xdmf, names, step);
  dmp_snapshot_write(ctx, name, &snap, "discrete model");
  free(S);
  free(xv);
  free(sc);
  free(mat);
}

void dmp_write_sphere_radial(const ms_ctx *ctx, const dm_problem *p, const dm_state *s,
                             size_t nreal, double t) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  char *path = ms_out_path(ctx, "dm_sphere_radial.csv");
  ms_afile af;
  if (ms_afile_open(&af, path) != MS_OK) {
    free(path);
    return;
  }
  const char *names[] = {"r", "w_r", "u_r", "w_exact", "u_exact"};
  const char *units[] = {"cm", "cm", "km/s", "cm", "km/s"};
  char title[128];
  snprintf(title, sizeof title, "spherical wave, all free particles, t = %.9g %s", ms_out_time(t),
           ms_out_time_label());
  ms_csv_header(af.f, title, 5, names, units);
  const double cl = dmp_wave_speed(p);
  size_t stride = nreal > 400000 ? nreal / 400000 + 1 : 1; /* keep the file < ~40 MB */
  for (size_t i = 0; i < nreal; i += stride) {
    if (s->bc[i] != DM_FREE) continue;
    const double *X = &s->X[3 * i];
    double r = sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
    double wr = (s->w[3 * i] * X[0] + s->w[3 * i + 1] * X[1] + s->w[3 * i + 2] * X[2]) / r;
    double ur = (s->u[3 * i] * X[0] + s->u[3 * i + 1] * X[1] + s->u[3 * i + 2] * X[2]) / r;
    double we, ue;
    dm_exact_sphere(r, t, p->src_r0, p->src_w0, p->src_period, cl, &we, &ue);
    double row[5] = {r, wr, ur, we, ue};
    ms_csv_row(af.f, 5, row);
  }
  ms_afile_commit(&af);
  free(path);
}

ms_status dmp_write_series(const ms_ctx *ctx, const char *file, const char *title, size_t ncol,
                           const char *const *names, const char *const *units, const double *data,
                           size_t nrow) {
  if (!ctx->outdir || !ctx->outdir[0]) return MS_OK;
  char *path = ms_out_path(ctx, file);
  ms_afile af;
  ms_status st = ms_afile_open(&af, path);
  free(path);
  if (st != MS_OK) return st;
  ms_csv_header(af.f, title, ncol, names, units);
  for (size_t r = 0; r < nrow; ++r) ms_csv_row(af.f, ncol, &data[r * ncol]);
  return ms_afile_commit(&af);
}


/* Instability guard report (docs/reliability.md §5): step `step` failed (rkn_step met a
 * non-finite acceleration and left the state at the step's start, time t). Names the first
 * particle whose displacement, velocity or acceleration at that state is not finite (each rank
 * looks at the particles it owns: dm_dist_accel is the integrator's own, collective force
 * call), and rank 0 writes the gathered state (m->s) as particles_unstable.h5. */
void dmp_report_unstable(const ms_ctx *ctx, const ms_ctx *octx, const dm_problem *p, dm_model *m,
                         dm_dist *d, const dm_state *ls, size_t nreal, long step, double t) {
  const dm_state *s = m->s;
  double *acc = ms_calloc(3 * ls->n + 1, sizeof *acc);
  dm_dist_accel(d, t, ls->w, acc); /* its status is the finding itself */
  const double *field[3] = {ls->w, ls->u, acc};
  static const char *const fname[3] = {"displacement w", "velocity u", "acceleration"};
  char what[200] = "";
  for (int f = 0; f < 3 && !what[0]; f++)
    for (size_t i = 0; i < nreal && !what[0]; i++) {
      long l = dm_dist_local_index(d, i);
      for (int a = 0; l >= 0 && a < 3 && !what[0]; a++)
        if (!isfinite(field[f][3 * l + a]))
          snprintf(what, sizeof what, "particle %zu (at %g, %g, %g): non-finite %s_%c = %g", i,
                   s->X[3 * i], s->X[3 * i + 1], s->X[3 * i + 2], fname[f], "xyz"[a],
                   field[f][3 * l + a]);
    }
  free(acc);
  if (what[0] || ctx->rank == 0)
    ms_log(ctx, MS_LOG_ERROR, "discrete model: unstable at step %ld, t = %.9g %s: %s", step + 1,
           ms_out_time(t), ms_out_time_label(),
           what[0] ? what
                   : "non-finite acceleration in a stage of the step (the state at its "
                     "start is finite)");
  if (ctx->rank == 0) {
    dmp_write_snapshot(octx, p, m, nreal, t, step, PTL_SNAPSHOT_UNSTABLE);
    ms_log(ctx, MS_LOG_ERROR, "discrete model: final state written to " PTL_SNAPSHOT_UNSTABLE);
  }
}

/* Layer-averaged profile along x of the real particles (lattice order, x fastest). */
void dmp_write_fin_profile(const ms_ctx *ctx, const dm_problem *p, const dm_fin *f, size_t nreal,
                           double t, int index, double *bins) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  const long nx = p->ncell[0];
  const int nc = 11;
  memset(bins, 0, (size_t)nx * nc * sizeof(double));
  const dm_state *s = f->m->s;
  for (size_t i = 0; i < nreal; ++i) {
    double *r = &bins[nc * (long)(i % (size_t)nx)];
    const double *sg = &f->sig[9 * i], *sd = &f->s[9 * i];
    double ss = 0;
    for (int a = 0; a < 9; ++a) ss += sd[a] * sd[a];
    double v[11] = {s->X[3 * i], s->X[3 * i] + s->w[3 * i],
                    s->u[3 * i], f->rho[i],
                    f->p[i],     f->q[i],
                    -sg[0],      f->e[i],
                    f->eps_p[i], sqrt(1.5 * ss),
                    f->J[i]};
    for (int c = 0; c < nc; ++c) r[c] += v[c];
  }
  const double per = (double)nreal / (double)nx;
  for (long j = 0; j < nx * nc; ++j) bins[j] /= per;
  char name[64];
  snprintf(name, sizeof name, "dm_fin_profile_%03d.csv", index);
  char title[160];
  snprintf(title, sizeof title,
           "discrete model (response eos) profile along x at t = %.9g %s, averaged over each "
           "x layer of particles",
           ms_out_time(t), ms_out_time_label());
  const char *nm[] = {"X", "x",     "u_x",     "rho", "p", "q", "minus_sigma_xx",
                      "e", "eps_p", "sigma_u", "J"};
  const char *un[] = {"cm", "cm", "km/s", "g/cm3", "GPa", "GPa", "GPa", "kJ/g", "1", "GPa", "1"};
  dmp_write_series(ctx, name, title, nc, nm, un, bins, (size_t)nx);
}

void dmp_write_probes(const ms_ctx *ctx, const dm_problem *p, const probe_rec *pr,
                      const double *hist, size_t nrec) {
  const size_t pcols = 1 + p->nprobes;
  const char **nm = ms_calloc(pcols, sizeof(char *)), **un = ms_calloc(pcols, sizeof(char *));
  char(*lab)[32] = ms_calloc(pcols, sizeof *lab);
  nm[0] = "t", un[0] = "10 us";
  for (size_t q = 0; q < p->nprobes; ++q) {
    snprintf(lab[q + 1], 32, "w_x(%.6g)", pr[q].x);
    nm[q + 1] = lab[q + 1], un[q + 1] = "cm";
  }
  dmp_write_series(ctx, "dm_probes.csv", "displacement history at probe particles", pcols, nm, un,
                   hist, nrec);
  free(nm);
  free(un);
  free(lab);
}

void dmp_write_energy(const ms_ctx *ctx, const double *ehist, size_t nerec) {
  const char *nm[] = {"t", "kinetic", "potential", "total", "hourglass"};
  const char *un[] = {"10 us", "kJ", "kJ", "kJ", "1"};
  dmp_write_series(ctx, "dm_energy.csv", "energy (real particles) and zero-energy-mode indicator",
                   5, nm, un, ehist, nerec);
}

void dmp_write_summary(const ms_ctx *ctx, const dm_run_summary *sum) {
  const char *snm[] = {"particles",
                       "real_particles",
                       "bonds",
                       "steps",
                       "dt",
                       "t_end",
                       "omega_dt",
                       "wall_s",
                       "cpu_s",
                       "particle_steps_per_s",
                       "energy_err_max",
                       "hourglass_first",
                       "hourglass_max",
                       "hourglass_last",
                       "amp_err",
                       "phase_err_L_over_c",
                       "peak_err",
                       "rms_err",
                       "err_l1",
                       "err_l2",
                       "err_max",
                       "err_u_l2",
                       "kinetic_end",
                       "potential_end",
                       "ranks",
                       "edge_cut",
                       "edge_cut_slab",
                       "imbalance",
                       "imbalance_slab",
                       "restart_step"};
  const char *sun[] = {"1", "1", "1",  "1",  "10 us", "10 us", "1", "s", "s", "1/s",
                       "1", "1", "1",  "1",  "1",     "L/c",   "1", "1", "1", "1",
                       "1", "1", "kJ", "kJ", "1",     "1",     "1", "1", "1", "1"};
  double row[30] = {(double)sum->particles,
                    (double)sum->real_particles,
                    (double)sum->bonds,
                    (double)sum->steps,
                    sum->dt,
                    sum->t_end,
                    sum->omega_dt,
                    sum->wall_s,
                    sum->cpu_s,
                    sum->particle_steps_per_s,
                    sum->energy_err_max,
                    sum->hourglass_first,
                    sum->hourglass_max,
                    sum->hourglass_last,
                    sum->amp_err,
                    sum->phase_err,
                    sum->peak_err,
                    sum->rms_err,
                    sum->err_l1,
                    sum->err_l2,
                    sum->err_max,
                    sum->err_u_l2,
                    sum->kinetic_end,
                    sum->potential_end,
                    (double)sum->ranks,
                    (double)sum->edge_cut,
                    (double)sum->edge_cut_slab,
                    sum->imbalance,
                    sum->imbalance_slab,
                    (double)sum->restart_step};
  dmp_write_series(ctx, "dm_summary.csv", "discrete model run summary", 30, snm, sun, row, 1);
}
