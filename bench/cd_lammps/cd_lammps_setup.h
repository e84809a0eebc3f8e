/* SPDX-License-Identifier: MIT */
/* cd_lammps_setup.h — problems A (bulk) and B (piston) of the LAMMPS anchor
 * (bench/problems/cd_lammps.md) as a cd_sim, shared by bench/cd_lammps and bench/cd_mpi. */
#ifndef CD_LAMMPS_SETUP_H
#define CD_LAMMPS_SETUP_H

#include "cd.h"

/* constants of gen_inputs.py */
#define RHO0 2.71
#define C0   5.35
#define NEXP 4.0
#define R0   5.0e-4
#define SEED 12345ULL
#define VAMP 0.01
#define UP   2.0

/* The whole particle set of problem A (probB false: 40³ fcc cells, periodic) or B (20×20×200
 * cells, piston), same order and velocities as LAMMPS's, with table and piston set; not yet
 * initialised (cd_sim_init; cd_sim_set_mpi before it for an MPI run). *nx_out: cells across. */
cd_sim *cd_lammps_setup(bool probB, const eos_t *eos, int *nx_out);

#endif
