/* SPDX-License-Identifier: MIT */
/* cd_lammps_setup.c — the LAMMPS anchor's problems as a cd_sim (cd_lammps_setup.h). */
#include "cd_lammps_setup.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

cd_sim *cd_lammps_setup(bool probB, const eos_t *eos, int *nx_out) {
  const double a = sqrt(2.0) * R0, rc = 1.2 * R0, skin = 0.1 * R0, dt = 0.02 * R0 / C0;
  const double mass = RHO0 * R0 * R0 * R0 / sqrt(2.0);
  const int nx = probB ? 20 : 40, nz = probB ? 200 : 40;
  const size_t n = (size_t)4 * nx * nx * nz;
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = n, .dim = 3}, &p), "ptl_state_create");
  double shift[3] = {0.25, 0.25, probB ? 0.0 : 0.25}, origin[3] = {0, 0, 0};
  cd_lattice_fcc(p, nx, nx, nz, shift, origin, R0, mass, 0);
  /* v[i][c] = VAMP(2u_{3i+c} − 1), mean over mobile particles subtracted; piston at +UP z */
  const size_t npiston = probB ? (size_t)4 * nx * nx * 2 : 0;
  double mean[3] = {0, 0, 0};
  double *v[3] = {p->vx, p->vy, p->vz};
  for (size_t i = 0; i < n; i++)
    for (int c = 0; c < 3; c++) {
      v[c][i] = VAMP * (2.0 * ptl_splitmix64_uniform(SEED, 3 * i + c) - 1.0);
      if (i >= npiston) mean[c] += v[c][i];
    }
  for (size_t i = 0; i < n; i++)
    for (int c = 0; c < 3; c++) v[c][i] -= mean[c] / (double)(n - npiston);
  for (size_t i = 0; i < npiston; i++) { /* iz < 2: the first 2·4·nx² particles */
    p->flags[i] = PTL_DRIVEN;
    p->vx[i] = p->vy[i] = 0.0;
    p->vz[i] = UP;
  }
  cd_box box = {.lo = {0, 0, 0},
                .hi = {nx * a, nx * a, nz * a},
                .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, probB ? CD_BC_FREE : CD_BC_PERIODIC}};
  cd_config cfg = {
      .r0 = R0, .skin = skin, .dt = dt, .cutoff = CD_CUTOFF_PLAIN, .lattice = CD_LATTICE_FCC};
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = &box, .cfg = &cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = ms_calloc(1, sizeof *t);
  if (cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0.0, rc, 0.5 * R0, 1.0, 0) != MS_OK) {
    fprintf(stderr, "table failed\n");
    exit(1);
  }
  cd_sim_set_pair(s, 0, 0, t);
  if (probB) {
    double tt[1] = {0.0}, uu[1] = {UP}, dir[3] = {0, 0, 1};
    cd_history h = {1, tt, uu};
    cd_sim_set_piston(s, &h, dir);
  }
  if (nx_out) *nx_out = nx;
  return s;
}
