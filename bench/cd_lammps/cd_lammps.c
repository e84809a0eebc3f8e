/* SPDX-License-Identifier: MIT */
/* cd_lammps.c — problems A (bulk) and B (piston) of the LAMMPS anchor, reproduced exactly
 * (cd_lammps.md: same particles and order, splitmix64 velocities, potential, R_c = 1.2 r0 hard
 * cutoff, skin 0.1 r0, Δt = 0.02 r0/c0, steps), timed like LAMMPS's "Loop time".
 *
 *   OMP_NUM_THREADS=1 cd_lammps_bench A            # 1000 steps, 256,000 particles
 *   OMP_NUM_THREADS=2 cd_lammps_bench B [--diag]   # 2000 steps, 320,000 particles
 *   options: --steps N, --diag (B: z-profiles every 100 steps, shock speed D by front tracking)
 * Prints particle-steps/s = N·steps/(loop wall time), rebuilds, bytes/particle, energies.
 */
#include "cd_lammps_setup.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int main(int argc, char **argv) {
  if (argc < 2 || (strcmp(argv[1], "A") && strcmp(argv[1], "B"))) {
    fprintf(stderr, "usage: %s A|B [--steps N] [--diag]\n", argv[0]);
    return 2;
  }
  const bool probB = argv[1][0] == 'B';
  long steps = probB ? 2000 : 1000;
  bool diag = false;
  for (int k = 2; k < argc; k++) {
    if (!strcmp(argv[k], "--steps") && k + 1 < argc) steps = atol(argv[++k]);
    else if (!strcmp(argv[k], "--diag")) diag = true;
  }
  eos_t *eos = eos_create_mg_cold(RHO0, C0, NEXP, 2.0, true);
  int nx = 0;
  cd_sim *s = cd_lammps_setup(probB, eos, &nx);
  const size_t n = cd_sim_particles(s)->n;
  const double a = sqrt(2.0) * R0;
  double tw0 = ms_wall_time();
  if (cd_sim_init(s) != MS_OK) {
    fprintf(stderr, "init failed\n");
    return 1;
  }
  double setup = ms_wall_time() - tw0;
  cd_energy e0, e1;
  cd_sim_energy(s, &e0);
  printf("problem %s: N = %zu, steps = %ld, threads = %d, setup %.3f s\n", argv[1], n, steps,
         omp_get_max_threads(), setup);
  printf("step 0: KE %.12g PE %.12g total %.12g\n", e0.kinetic, e0.potential, e0.total);
  const int nbin = 262;
  const double zlo = -0.25 * a, zhi = zlo + nbin * a;
  double *prof = diag ? ms_calloc((size_t)nbin * CD_PROFILE_NCOL, sizeof *prof) : NULL;
  double tfr[64], zfr[64], zfr1[64];
  int nfr = 0;
  double loop = 0.0, t0 = ms_wall_time();
  clock_t cpu0 = clock();
  for (long k = 1; k <= steps; k++) {
    if (cd_sim_step(s) != MS_OK) {
      fprintf(stderr, "unstable at step %ld\n", k);
      return 1;
    }
    if (diag && k % 100 == 0) {
      loop += ms_wall_time() - t0;
      cd_profile(s, 2, zlo, zhi, nbin, (nx * a) * (nx * a), prof);
      if (nfr < 64) {
        tfr[nfr] = cd_sim_time(s);
        zfr1[nfr] = cd_front_position(prof, nbin, 2, UP, 0.1);
        zfr[nfr++] = cd_front_position(prof, nbin, 2, UP, 0.5);
      }
      cd_energy e;
      cd_sim_energy(s, &e);
      printf("step %ld t %.6e front %.6e KE %.10g PE %.10g broken %.6g Wp %.10g total %.10g\n", k,
             cd_sim_time(s), zfr[nfr - 1], e.kinetic, e.potential, e.broken, e.piston_work,
             e.total);
      t0 = ms_wall_time();
    }
  }
  loop += ms_wall_time() - t0;
  double cpu = (double)(clock() - cpu0) / CLOCKS_PER_SEC;
  cd_sim_energy(s, &e1);
  printf("step %ld: KE %.17g PE %.17g total %.17g (broken %.6g, piston work %.6g)\n", steps,
         e1.kinetic, e1.potential, e1.total, e1.broken, e1.piston_work);
  double w_force, w_neigh;
  cd_sim_wall_times(s, &w_force, &w_neigh);
  printf("loop time %.3f s (force %.3f, neighbour %.3f), rebuilds %ld, pairs %zu\n", loop, w_force,
         w_neigh, cd_sim_rebuilds(s), cd_sim_pairs(s));
  printf("process CPU time in the loop %.3f s (all threads)\n", cpu);
  printf("bytes/particle %.1f\n", (double)cd_sim_bytes(s) / (double)n);
  printf("particle-steps/s %.4g\n", (double)n * (double)steps / loop);
  if (diag && nfr > 2) {
    /* least-squares slopes of z_f(t) as analyze_shock.py: fronts where the bin-mean vz falls
     * below 0.1u and 0.5u, fits over t >= T/4 and t >= T/2 */
    const double *zz[2] = {zfr1, zfr};
    const double fr[2] = {0.1, 0.5}, from[2] = {0.25, 0.5};
    for (int a2 = 0; a2 < 2; a2++)
      for (int b2 = 0; b2 < 2; b2++) {
        double sx = 0, sy = 0, sxx = 0, sxy = 0;
        int m = 0;
        for (int k = 0; k < nfr; k++)
          if (tfr[k] >= from[b2] * tfr[nfr - 1] * (1 - 1e-12) && isfinite(zz[a2][k])) {
            sx += tfr[k];
            sy += zz[a2][k];
            sxx += tfr[k] * tfr[k];
            sxy += tfr[k] * zz[a2][k];
            m++;
          }
        double D = (m * sxy - sx * sy) / (m * sxx - sx * sx);
        printf("shock speed D = %.4f km/s (front at vz = %.1f u, fit t >= %.2f T, %d frames)\n", D,
               fr[a2], from[b2], m);
      }
    printf("t [10us]     zf(0.1u) [cm]  zf(0.5u) [cm]\n");
    for (int k = 0; k < nfr; k++) printf("%.4e %.5e %.5e\n", tfr[k], zfr1[k], zfr[k]);
  }
  free(prof);
  cd_sim_destroy(&s);
  eos_destroy(&eos);
  return 0;
}
