/* SPDX-License-Identifier: MIT */
/* Cluster dynamics on MPI ranks (docs/mpi.md, "Cluster dynamics on MPI ranks"), run under
 * mpirun -np 1, 2, 3, 4. Each rank also runs every case serially in-process (no decomposition)
 * and the distributed run must reproduce it:
 *  - piston (plain cutoff): a piston drives a shock through an fcc bar (periodic x, y; free z);
 *    METIS partition, no rebalancing. Particle count, every particle's final position and
 *    velocity (gathered by gid), the energy balance terms, the piston work and the shock speed D
 *    from the front positions of the reduced profiles;
 *  - the same with slab partition and rebalance_threshold 1.05 checked at every list build: the
 *    shock compresses the bar, so the load moves and repartitions happen (asserted >= 1 on 2+
 *    ranks); the result still matches the serial run;
 *  - the piston case with the RKN4 integrator (ghosts refreshed at every stage position), 400 steps;
 *  - bonded mode with damping after an affine stretch (bonds break across rank borders, the
 *    damping needs ghost velocities, the coarse grid is remade for the new box): energies,
 *    dissipated and broken energy, broken-bond count.
 * Tolerances: the ranks sum each particle's pair forces in another order than the serial run
 * (ghost pairs, cell-sorted particles), so the runs differ by round-off (~1e-16 relative per
 * force) that the dynamics then amplifies. Measured (np 2-4, 600 steps): positions agree to
 * ~1e-12 r0, energies to ~1e-13 relative; the bounds below (1e-8 r0, 1e-9 relative) leave four
 * orders of magnitude for other machines while still failing for any missing pair, ghost or
 * double-counted energy (each would show at >= 1e-6). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cd_mpi_test.h"

static int my_rank = 0;

#define R0 5.0e-4
#define C0 5.35
#define UP 2.0

typedef enum { CASE_PISTON, CASE_REBALANCE, CASE_BONDED, CASE_RKN } case_kind;

typedef struct result {
  size_t n;      /* global particle count */
  double *x, *v; /* [n][3] by gid */
  cd_energy e;
  double D;    /* shock speed from the front positions (piston cases) */
  long broken; /* broken bonds (bonded case) */
  long rebalances;
  long rebuilds;
} result;

/* The system of each case, generated identically on every rank; `share` keeps this rank's
 * block of it (the distributed run), else the whole (the serial reference). */
static cd_sim *make_case(case_kind kind, const eos_t *eos, bool distributed) {
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  const bool piston = kind != CASE_BONDED;
  const int nx = piston ? 5 : 7, nz = piston ? 26 : 7;
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = (size_t)4 * nx * nx * nz, .dim = 3}, &p),
          "ptl_state_create");
  double sh[3] = {0.25, 0.25, piston ? 0.0 : 0.25}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, nx, nx, nz, sh, o, R0, m, 0);
  const double vamp = piston ? 0.02 : 0.5;
  const size_t npiston = piston ? (size_t)4 * nx * nx * 2 : 0; /* the first 2 cell layers */
  double mean[3] = {0, 0, 0}, *v[3] = {p->vx, p->vy, p->vz};
  for (size_t i = 0; i < p->n; i++)
    for (int c = 0; c < 3; c++) {
      v[c][i] = vamp * (2.0 * ptl_splitmix64_uniform(11, 3 * i + c) - 1.0);
      if (i >= npiston) mean[c] += v[c][i] / (double)(p->n - npiston);
    }
  for (size_t i = 0; i < p->n; i++)
    for (int c = 0; c < 3; c++) v[c][i] = i < npiston ? (c == 2 ? UP : 0.0) : v[c][i] - mean[c];
  for (size_t i = 0; i < npiston; i++) p->flags[i] = PTL_DRIVEN;
  cd_box box = {.lo = {0, 0, 0},
                .hi = {nx * a, nx * a, nz * a},
                .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, piston ? CD_BC_FREE : CD_BC_PERIODIC}};
  cd_config cfg = {.r0 = R0,
                   .skin = 0.1 * R0,
                   .dt = 0.02 * R0 / C0,
                   .cutoff = piston ? CD_CUTOFF_PLAIN : CD_CUTOFF_BONDED,
                   .damping_gamma = piston ? 0.0 : 0.05 * C0 / R0,
                   .lattice = CD_LATTICE_FCC,
                   .integrator = kind == CASE_RKN ? CD_INT_RKN4 : CD_INT_VELOCITY_VERLET};
  cd_sim *s = cd_test_create(p, &box, &cfg, eos, distributed);
  if (piston) {
    double tt[1] = {0.0}, uu[1] = {UP}, dir[3] = {0, 0, 1};
    cd_history h = {1, tt, uu};
    cd_sim_set_piston(s, &h, dir);
  }
  const cd_mpi_config mc = {.partition = kind == CASE_REBALANCE ? CD_PART_SLAB : CD_PART_METIS,
                            .rebalance_threshold = kind == CASE_REBALANCE ? 1.05 : 0.0,
                            .rebalance_interval = 1};
  cd_test_init(s, distributed ? &mc : NULL);
  if (kind == CASE_BONDED)
    CHECK(cd_sim_affine(s, (double[3]){1.15, 1.15, 1.15}) == MS_OK, "affine");
  return s;
}

static result run_case(case_kind kind, const eos_t *eos, bool distributed, long steps) {
  cd_sim *s = make_case(kind, eos, distributed);
  result res = {0};
  const cd_mpi_stats *ms = cd_sim_mpi_stats(s);
  if (distributed && ms) /* right after the set-up every owned particle lies in an owned cell */
    for (size_t i = 0; i < cd_sim_particles(s)->nlocal; i++) {
      double x[3] = {cd_sim_particles(s)->x[i], cd_sim_particles(s)->y[i],
                     cd_sim_particles(s)->z[i]};
      if (!cd_sim_owns_position(s, x)) {
        CHECK(false, "owned particle %zu (gid %ld) outside the rank's cells", i,
              (long)cd_sim_particles(s)->gid[i]);
        break;
      }
    }
  const double a = sqrt(2.0) * R0;
  const int nbin = 40;
  double *prof = calloc((size_t)nbin * CD_PROFILE_NCOL, sizeof *prof);
  double tf[64], zf[64];
  int nf = 0;
  for (long k = 1; k <= steps; k++) {
    if (cd_sim_step(s) != MS_OK) {
      CHECK(false, "step %ld failed", k);
      break;
    }
    if (kind != CASE_BONDED && k % 50 == 0) {
      cd_profile(s, 2, -0.25 * a, (nbin - 0.25) * a, nbin, 25.0 * a * a, prof);
      double z = cd_front_position(prof, nbin, 2, UP, 0.5);
      if (isfinite(z) && nf < 64) tf[nf] = cd_sim_time(s), zf[nf++] = z;
    }
  }
  cd_sim_energy(s, &res.e);
  /* D: least-squares slope of the front positions over the second half of the run */
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (int k = nf / 2; k < nf; k++, m++)
    sx += tf[k], sy += zf[k], sxx += tf[k] * tf[k], sxy += tf[k] * zf[k];
  res.D = m > 2 ? (m * sxy - sx * sy) / (m * sxx - sx * sx) : NAN;
  /* global state by gid: each owned particle contributes once, the sum over ranks fills it */
  const ptl_state *p = cd_sim_particles(s);
  long nown = (long)p->nlocal;
  res.n = (size_t)(distributed ? par_sum_long(nown) : nown);
  res.x = calloc(3 * res.n + 1, sizeof(double));
  res.v = calloc(3 * res.n + 1, sizeof(double));
  double *count = calloc(res.n + 1, sizeof(double));
  for (size_t i = 0; i < p->nlocal; i++) {
    size_t g = (size_t)p->gid[i];
    if (g >= res.n) continue;
    res.x[3 * g] = p->x[i], res.x[3 * g + 1] = p->y[i], res.x[3 * g + 2] = p->z[i];
    res.v[3 * g] = p->vx[i], res.v[3 * g + 1] = p->vy[i], res.v[3 * g + 2] = p->vz[i];
    count[g] += 1.0;
  }
  if (distributed) {
    par_sum_doubles(res.x, 3 * res.n);
    par_sum_doubles(res.v, 3 * res.n);
    par_sum_doubles(count, res.n);
  }
  size_t bad = 0;
  for (size_t g = 0; g < res.n; g++) bad += count[g] != 1.0;
  CHECK(bad == 0, "%zu gids not owned by exactly one rank", bad);
  res.broken = distributed ? par_sum_long(cd_sim_broken_bonds(s)) : cd_sim_broken_bonds(s);
  res.rebalances = ms ? ms->rebalances : 0;
  res.rebuilds = cd_sim_rebuilds(s);
  if (distributed && ms && my_rank == 0)
    printf("  %d ranks: coarse cells %dx%dx%d, owned max %zu of %zu, ghosts %zu in all, imbalance "
           "%.3f, edge cut %ld, partitions %ld, rebalances %ld, lost bonds %ld\n",
           ms->ranks, ms->ncell[0], ms->ncell[1], ms->ncell[2], ms->max_owned, ms->global,
           ms->total_ghosts, ms->imbalance, ms->partition.edge_cut, ms->partitions, ms->rebalances,
           ms->lost_bonds);
  free(count);
  free(prof);
  cd_sim_destroy(&s);
  return res;
}

static double rel(double a, double b, double scale) { return fabs(a - b) / scale; }

static void compare(const char *name, case_kind kind, const eos_t *eos, long steps) {
  result ser = run_case(kind, eos, false, steps);
  result dis = run_case(kind, eos, true, steps);
  CHECK(dis.n == ser.n, "%s: %zu particles, serial %zu", name, dis.n, ser.n);
  double dx = 0, dv = 0, vmax = 0;
  for (size_t k = 0; k < 3 * ser.n && dis.n == ser.n; k++) {
    dx = fmax(dx, fabs(dis.x[k] - ser.x[k]));
    dv = fmax(dv, fabs(dis.v[k] - ser.v[k]));
    vmax = fmax(vmax, fabs(ser.v[k]));
  }
  const double scale = fabs(ser.e.kinetic) + fabs(ser.e.potential);
  const double de[6] = {rel(dis.e.kinetic, ser.e.kinetic, scale),
                        rel(dis.e.potential, ser.e.potential, scale),
                        rel(dis.e.total, ser.e.total, scale),
                        rel(dis.e.piston_work, ser.e.piston_work, scale),
                        rel(dis.e.dissipated, ser.e.dissipated, scale),
                        rel(dis.e.broken, ser.e.broken, scale)};
  double demax = 0;
  for (int k = 0; k < 6; k++) demax = fmax(demax, de[k]);
  if (my_rank == 0)
    printf("%s: N %zu, %ld builds; max |dx| %.3g r0, max |dv| %.3g of max |v|, energies %.3g "
           "relative; D %.6f vs %.6f km/s; broken bonds %ld vs %ld; rebalances %ld\n",
           name, ser.n, dis.rebuilds, dx / R0, dv / vmax, demax, dis.D, ser.D, dis.broken,
           ser.broken, dis.rebalances);
  CHECK(dx < 1e-8 * R0, "%s: positions differ by %g r0", name, dx / R0);
  CHECK(dv < 1e-8 * vmax, "%s: velocities differ by %g of max |v|", name, dv / vmax);
  CHECK(demax < 1e-9, "%s: energies differ by %g relative", name, demax);
  for (int k = 0; k < 3; k++)
    CHECK(fabs(dis.e.momentum[k] - ser.e.momentum[k]) <= 1e-9 * scale / C0 + 1e-300,
          "%s: momentum %d: %g vs %g", name, k, dis.e.momentum[k], ser.e.momentum[k]);
  if (kind != CASE_BONDED) {
    CHECK(isfinite(ser.D) && ser.D > 6.0 && ser.D < 10.0, "%s: serial D = %g km/s", name, ser.D);
    CHECK(fabs(dis.D - ser.D) < 1e-6 * ser.D, "%s: D %.9f vs serial %.9f", name, dis.D, ser.D);
  } else {
    CHECK(ser.broken > 0, "%s: no bond broke (the case tests nothing)", name);
    CHECK(dis.broken == ser.broken, "%s: %ld broken bonds, serial %ld", name, dis.broken,
          ser.broken);
  }
  if (kind == CASE_REBALANCE && par_size() > 1)
    CHECK(dis.rebalances >= 1, "%s: no rebalance happened", name);
  free(ser.x), free(ser.v), free(dis.x), free(dis.v);
}

int main(int argc, char **argv) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  if (par_init(&argc, &argv, &ctx)) return 1;
  my_rank = ctx.rank;
  eos_t *eos = eos_create_mg_cold(2.71, C0, 4.0, 2.0, true);
  compare("piston (METIS)", CASE_PISTON, eos, 1000);
  compare("piston (slab, rebalance 1.05)", CASE_REBALANCE, eos, 1000);
  compare("bonded + damping", CASE_BONDED, eos, 300);
  compare("piston, RKN4", CASE_RKN, eos, 400);
  eos_destroy(&eos);
  int all = (int)par_sum_long(failures);
  if (my_rank == 0)
    printf("%s (%d failures over %d ranks)\n", all ? "FAILED" : "OK", all, ctx.size);
  ms_ctx_close(&ctx);
  par_finalize();
  return all ? 1 : 0;
}
