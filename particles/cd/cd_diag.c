/* SPDX-License-Identifier: MIT */
/* cd_diag.c — binned profiles, shock-front tracking and HDF5/XDMF particle snapshots.
 *
 * Profile stress (compression positive, i.e. the pressure tensor; Cauchy stress = −P):
 *   P_ab(bin) = (1/V_bin) Σ_{i in bin} [ m_i (v_i − v̄)_a (v_i − v̄)_b + W_i,ab ],
 * W_i = ½ Σ_j f(r) r_a r_b / r the particle's share of the pair virial, v̄ the bin's mean
 * velocity; σ_u is the von Mises intensity of P (docs/design.md §5.1). Driven (piston) particles are
 * left out of profiles.
 */
#include "cd_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const cd_profile_columns[CD_PROFILE_NCOL] = {
    "x", "count", "rho", "vx", "vy", "vz", "Pxx", "Pyy", "Pzz", "Pxy", "Pyz", "Pzx", "sigma_u"};

static double *particle_virials(cd_sim *s) {
  if (!s->pw) s->pw = ms_aligned_alloc(6 * s->p->cap, sizeof(double));
  cd_sim_particle_virial(s, s->pw);
  return s->pw;
}

void cd_profile(cd_sim *s, int axis, double lo, double hi, int nbin, double area, double *out) {
  const ptl_state *p = s->p;
  const double *w = particle_virials(s);
  const double *xa = axis == 0 ? p->x : (axis == 1 ? p->y : p->z);
  const double *v[3] = {p->vx, p->vy, p->vz};
  const double width = (hi - lo) / nbin, vol = width * area;
  memset(out, 0, (size_t)nbin * CD_PROFILE_NCOL * sizeof *out);
  double *mass = ms_calloc((size_t)nbin, sizeof *mass);
  for (size_t i = 0; i < p->nlocal; i++) {
    if (p->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) continue;
    int k = (int)floor((xa[i] - lo) / width);
    if (k < 0 || k >= nbin) continue;
    double *row = out + (size_t)k * CD_PROFILE_NCOL;
    row[1] += 1.0;
    mass[k] += p->mass[i];
    for (int c = 0; c < 3; c++) row[3 + c] += p->mass[i] * v[c][i];
  }
  if (s->dd) { /* MPI: every rank's owned particles */
    par_sum_doubles(out, (size_t)nbin * CD_PROFILE_NCOL);
    par_sum_doubles(mass, (size_t)nbin);
  }
  for (int k = 0; k < nbin; k++) {
    double *row = out + (size_t)k * CD_PROFILE_NCOL;
    row[0] = lo + (k + 0.5) * width;
    row[2] = mass[k] / vol;
    for (int c = 0; c < 3; c++) row[3 + c] = mass[k] > 0 ? row[3 + c] / mass[k] : 0.0;
  }
  static const int ia[6] = {0, 1, 2, 0, 1, 2}, ib[6] = {0, 1, 2, 1, 2, 0};
  double *acc = ms_calloc(6 * (size_t)nbin, sizeof *acc); /* stress sums per bin */
  for (size_t i = 0; i < p->nlocal; i++) {
    if (p->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) continue;
    int k = (int)floor((xa[i] - lo) / width);
    if (k < 0 || k >= nbin) continue;
    const double *row = out + (size_t)k * CD_PROFILE_NCOL;
    double dv[3];
    for (int c = 0; c < 3; c++) dv[c] = v[c][i] - row[3 + c];
    for (int c = 0; c < 6; c++) acc[6 * k + c] += p->mass[i] * dv[ia[c]] * dv[ib[c]] + w[6 * i + c];
  }
  if (s->dd) par_sum_doubles(acc, 6 * (size_t)nbin);
  for (int k = 0; k < nbin; k++) {
    double *row = out + (size_t)k * CD_PROFILE_NCOL;
    for (int c = 0; c < 6; c++) row[6 + c] = acc[6 * k + c] / vol;
    row[12] = cd_von_mises(row + 6);
  }
  free(mass);
  free(acc);
}

double cd_front_position(const double *profile, int nbin, int axis, double u_ref, double frac) {
  const double thr = frac * u_ref;
  double zprev = NAN, vprev = NAN;
  for (int k = 0; k < nbin; k++) {
    const double *row = profile + (size_t)k * CD_PROFILE_NCOL;
    if (row[1] <= 0) continue;
    double z = row[0], v = row[3 + axis];
    if (isfinite(vprev) && v < thr && thr <= vprev)
      return zprev + (thr - vprev) * (z - zprev) / (v - vprev);
    zprev = z;
    vprev = v;
  }
  return NAN;
}

const char *cd_sim_error(const cd_sim *s) { return s->err; }

/* The guard's screening pass: true when no owned particle can fail it (all of x, v finite,
 * |v| Δt <= step_max, no wall axis to check). One parallel, vectorised pass; only when it
 * fails does cd_sim_guard scan particle by particle for the one to name. */
MS_KERNEL_CLONES static bool guard_screen(const cd_sim *s, double step_max) {
  const ptl_state *p = s->p;
  for (int a = 0; a < 3; a++)
    if (s->box.bc[a] == CD_BC_WALL) return false;
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  const double *restrict vx = p->vx, *restrict vy = p->vy, *restrict vz = p->vz;
  const uint8_t *restrict fl = p->flags;
  const long n = (long)p->nlocal;
  double worst = 0.0; /* max |v|² over kept particles; NaN/∞ anywhere makes it ∞ */
#pragma omp parallel for simd schedule(static) reduction(max : worst) if (CD_PAR(n))
  for (long i = 0; i < n; i++) {
    const double v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
    const double sum = x[i] + y[i] + z[i] + v2;
    /* sum − sum is 0 for finite sums, NaN for NaN or ±∞ in any term (or an overflow, which
     * only sends the check to the slow scan) */
    const double w = (fl[i] & PTL_REMOVED) ? 0.0 : (sum - sum == 0.0 ? v2 : INFINITY);
    worst = w > worst ? w : worst;
  }
  /* the margin keeps the screen on the safe side of the scan's sqrt rounding */
  return worst * s->cfg.dt * s->cfg.dt <= step_max * step_max * (1.0 - 1e-12);
}

ms_status cd_sim_guard(cd_sim *s) {
  const ptl_state *p = s->p;
  const double *q[6] = {p->x, p->y, p->z, p->vx, p->vy, p->vz};
  static const char *const name[6] = {"x", "y", "z", "vx", "vy", "vz"};
  const double step_max = 0.5 * s->cfg.r0;
  if (guard_screen(s, step_max)) return MS_OK;
  for (size_t i = 0; i < p->nlocal; i++) { /* owned particles (ghosts are another rank's) */
    if (p->flags[i] & PTL_REMOVED) continue;
    char what[200] = "";
    for (int c = 0; c < 6 && !what[0]; c++)
      if (!isfinite(q[c][i])) snprintf(what, sizeof what, "non-finite %s = %g", name[c], q[c][i]);
    double v = sqrt(p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i]);
    if (!what[0] && v * s->cfg.dt > step_max)
      snprintf(what, sizeof what,
               "speed |v| = %g km/s moves it %.3g r0 per step, more than 0.5 "
               "r0: the time step cannot follow it (reduce dt/courant or the drive)",
               v, v * s->cfg.dt / s->cfg.r0);
    for (int a = 0; a < 3 && !what[0]; a++)
      if (s->box.bc[a] == CD_BC_WALL && !(q[a][i] >= s->box.lo[a] && q[a][i] <= s->box.hi[a]))
        snprintf(what, sizeof what, "left the box through the wall: %s = %g outside [%g, %g]",
                 name[a], q[a][i], s->box.lo[a], s->box.hi[a]);
    if (what[0]) {
      snprintf(s->err, sizeof s->err,
               "unstable at step %ld, t = %.9g %s: particle %zu (%s"
               "at %g, %g, %g cm): %s",
               s->step, ms_out_time(s->t), ms_out_time_label(), i,
               p->flags[i] & PTL_DRIVEN ? "piston, " : "", p->x[i], p->y[i], p->z[i], what);
      return MS_ERR_UNSTABLE;
    }
  }
  return MS_OK;
}

ms_status cd_write_snapshot(cd_sim *s, const char *path) {
  const ptl_state *p = s->p;
  const size_t n = p->nlocal; /* MPI: each rank writes its owned particles (collective file) */
  const double *w = particle_virials(s);
  const double v0 = cd_cluster_volume(s->cfg.lattice, s->cfg.r0, s->cfg.thickness);
  double *su = ms_calloc(n + 1, sizeof *su), *pr = ms_calloc(n + 1, sizeof *pr);
  int64_t *mat = ms_calloc(n + 1, sizeof *mat);
  for (size_t i = 0; i < n; i++) {
    double t[6];
    for (int c = 0; c < 6; c++) t[c] = w[6 * i + c] / v0;
    su[i] = cd_von_mises(t);
    pr[i] = (s->p->dim == 2 ? (t[0] + t[1]) / 2.0 : (t[0] + t[1] + t[2]) / 3.0);
    mat[i] = p->mat[i];
  }
  const ptl_snapshot_data data[] = {{"particles/sigma_u", su, NULL, 1, "GPa"},
                                    {"particles/pressure", pr, NULL, 1, "GPa"},
                                    {"particles/material", NULL, mat, 1, NULL},
                                    {"particles/gid", NULL, p->gid, 1, NULL}};
  const ms_xdmf_attr xdmf[] = {{"velocity", "particles/v", 3, false},
                               {"sigma_u", "particles/sigma_u", 1, false},
                               {"pressure", "particles/pressure", 1, false},
                               {"mass", "particles/mass", 1, false}};
  ptl_snapshot snap = ptl_snapshot_of_state(p, n, s->t, s->dd != NULL);
  ptl_snapshot_contents(&snap, 4, data, 4, xdmf, s->material_names, s->step);
  ptl_snapshot_attr_add(&snap, "r0", s->cfg.r0);
  /* periodic axes as the coupling snapshots name them (`mscale spectrum` reads them) */
  for (int a = 0; a < s->p->dim; a++)
    if (s->box.bc[a] == CD_BC_PERIODIC)
      ptl_snapshot_period_add(&snap, a, s->box.hi[a] - s->box.lo[a], s->box.lo[a]);
  const ms_status st = ptl_write_snapshot(path, &snap);
  free(su);
  free(pr);
  free(mat);
  return st;
}
