/* SPDX-License-Identifier: MIT */
/* Set-up shared by the cluster-dynamics MPI tests (test_cd_mpi.c, test_frag_cd_mpi.c): every rank
 * generates the same system; the distributed run keeps this rank's contiguous block of it
 * (cd_sim_init then migrates the particles to the owners of their coarse cells), the in-process
 * serial reference keeps all of it. */
#ifndef MSCALE_CD_MPI_TEST_H
#define MSCALE_CD_MPI_TEST_H

#include <stdlib.h>

#include "mpi_check.h"
#include "cd.h"

/* The simulation of p (this rank's block of it if distributed) in box with cfg, one material:
 * eos's fcc pair table with R_c = 1.2 r0. Set the piston, if any, then call cd_test_init. */
static cd_sim *cd_test_create(ptl_state *p, const cd_box *box, const cd_config *cfg,
                              const eos_t *eos, bool distributed) {
  if (distributed) {
    const size_t r = (size_t)par_rank(), P = (size_t)par_size();
    ptl_state_keep_range(p, p->n * r / P, p->n * (r + 1) / P);
  }
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = box, .cfg = cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = calloc(1, sizeof *t);
  const double r0 = cfg->r0;
  if (!t ||
      cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, r0, 0, 1.2 * r0, 0.5 * r0, 1.0, 0) != MS_OK)
    abort();
  cd_sim_set_pair(s, 0, 0, t);
  return s;
}

/* The decomposition (mc; NULL for the serial reference) and the set-up (cd_sim_init). */
static void cd_test_init(cd_sim *s, const cd_mpi_config *mc) {
  if (mc) cd_sim_set_mpi(s, mc);
  CHECK(cd_sim_init(s) == MS_OK, "init");
}

#endif
