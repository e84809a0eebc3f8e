/* SPDX-License-Identifier: MIT */
/* cd_mpi.c — strong scaling of cluster dynamics over MPI ranks (docs/mpi.md, benchmarks.md):
 * problem A (256,000 particles, periodic bulk) or B (320,000, piston) of the LAMMPS anchor,
 * built by bench/cd_lammps's set-up, run on as many ranks as mpirun gives (1 rank: the serial
 * code path, no decomposition).
 *
 *   OMP_NUM_THREADS=1 mpirun -np 1 cd_mpi_bench A [--steps N] [--partition auto|metis|slab]
 *   OMP_NUM_THREADS=1 mpirun -np 2 cd_mpi_bench A ...
 * Prints the loop wall time (slowest rank), CPU time per rank and summed, particle-steps/s,
 * the decomposition (cells, owned, ghosts, edge cut, load), exchange time and volume, per rank
 * the owned/ghost/list-entry counts, force time, CPU outside MPI and peak RSS, and the final
 * energies (which must agree with the 1-rank run to round-off). Efficiency = T1 / (P·T_P) from
 * two such runs (run_scaling.sh interleaves them). */
#include "cd_lammps_setup.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Peak resident memory of this process (VmHWM of /proc/self/status), MB; NaN if unknown. */
static double peak_rss_mb(void) {
  FILE *f = fopen("/proc/self/status", "r");
  char line[256];
  double kb = NAN;
  while (f && fgets(line, sizeof line, f))
    if (!strncmp(line, "VmHWM:", 6)) kb = atof(line + 6);
  if (f) fclose(f);
  return kb / 1024.0;
}

int main(int argc, char **argv) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  if (par_init(&argc, &argv, &ctx) != MS_OK) return 1;
  if (argc < 2 || (strcmp(argv[1], "A") && strcmp(argv[1], "B"))) {
    if (ctx.rank == 0)
      fprintf(stderr, "usage: %s A|B [--steps N] [--partition auto|metis|slab]\n", argv[0]);
    par_finalize();
    return 2;
  }
  const bool probB = argv[1][0] == 'B';
  long steps = probB ? 2000 : 1000;
  cd_partition_method method = CD_PART_AUTO; /* the decks' default */
  for (int k = 2; k < argc; k++) {
    if (!strcmp(argv[k], "--steps") && k + 1 < argc) steps = atol(argv[++k]);
    else if (!strcmp(argv[k], "--partition") && k + 1 < argc) {
      k++;
      method = !strcmp(argv[k], "slab")   ? CD_PART_SLAB
               : !strcmp(argv[k], "auto") ? CD_PART_AUTO
                                          : CD_PART_METIS;
    }
  }
  eos_t *eos = eos_create_mg_cold(RHO0, C0, NEXP, 2.0, true);
  cd_sim *s = cd_lammps_setup(probB, eos, NULL);
  const size_t n = cd_sim_particles(s)->n;
  if (ctx.size > 1) {
    cd_mpi_config mc = {.partition = method,
                        .rebalance_threshold = 1.2,
                        .rebalance_interval = 10,
                        .replicated = true};
    cd_sim_set_mpi(s, &mc);
  }
  double tw0 = ms_wall_time();
  if (cd_sim_init(s) != MS_OK) {
    fprintf(stderr, "init failed\n");
    return 1;
  }
  const double setup = par_max_double(ms_wall_time() - tw0);
  cd_energy e0, e1;
  cd_sim_energy(s, &e0);
  par_barrier();
  double mw0, mc0, mw1, mc1;
  par_comm_time(&mw0, &mc0);
  const double t0 = ms_wall_time();
  const clock_t c0 = clock();
  for (long k = 1; k <= steps; k++)
    if (cd_sim_step(s) != MS_OK) {
      fprintf(stderr, "unstable at step %ld\n", k);
      return 1;
    }
  const double wall = ms_wall_time() - t0, cpu = (double)(clock() - c0) / CLOCKS_PER_SEC;
  par_comm_time(&mw1, &mc1);
  /* CPU outside MPI calls: the work of the rank, without its spinning in waits */
  const double work = cpu - (mc1 - mc0), work_max = par_max_double(work);
  const double comm_wall_max = par_max_double(mw1 - mw0);
  const double wall_max = par_max_double(wall), cpu_sum = par_sum_double(cpu);
  const double cpu_max = par_max_double(cpu);
  cd_sim_energy(s, &e1);
  const cd_mpi_stats *ms = cd_sim_mpi_stats(s);
  double xs = ms ? ms->exchange_s : 0.0, xd = ms ? ms->exchanged_doubles : 0.0;
  const double xs_max = par_max_double(xs), xd_sum = par_sum_double(xd);
  double w_force, w_neigh;
  cd_sim_wall_times(s, &w_force, &w_neigh);
  const double fw = par_max_double(w_force), nw = par_max_double(w_neigh);
  const double pairs = (double)cd_sim_pairs(s);
  const double pairs_max = par_max_double(pairs), pairs_sum = par_sum_double(pairs);
  /* per rank: owned, ghosts, list entries, force wall, CPU outside MPI (where the time goes),
   * peak resident memory, wall inside MPI calls and in ghost refreshes + migrations */
  enum { NPR = 8 };
  double mine[NPR] = {(double)cd_sim_particles(s)->nlocal,
                      (double)(cd_sim_particles(s)->n - cd_sim_particles(s)->nlocal),
                      pairs,
                      w_force,
                      work,
                      peak_rss_mb(),
                      mw1 - mw0,
                      xs};
  double *all = ms_calloc((size_t)NPR * ctx.size, sizeof *all);
  int *cnt = ms_calloc((size_t)ctx.size, sizeof *cnt),
      *dsp = ms_calloc((size_t)ctx.size, sizeof *dsp);
  for (int r = 0; r < ctx.size; r++) cnt[r] = NPR, dsp[r] = NPR * r;
  par_allgatherv_doubles(mine, NPR, all, cnt, dsp);
  if (ctx.rank == 0) {
    for (int r = 0; r < ctx.size; r++) {
      const double *a = all + NPR * r;
      printf("rank %d: owned %.0f, ghosts %.0f, list entries %.0f, force %.3f s (%.2f ns per "
             "entry-step), CPU outside MPI %.3f s, wall in MPI %.3f s (ghosts %.3f s), peak RSS "
             "%.1f MB\n",
             r, a[0], a[1], a[2], a[3], 1e9 * a[3] / (a[2] * (double)steps), a[4], a[6], a[7],
             a[5]);
    }
    printf("problem %s on %d rank(s): N = %zu, steps = %ld, setup %.3f s\n", argv[1], ctx.size, n,
           steps, setup);
    if (ms)
      printf("decomposition: %dx%dx%d coarse cells, %s%s, owned max %zu, ghosts %zu in all "
             "(%.2f %% of N), edge cut %ld, imbalance %.4f, load %.4f (other map %.4f), "
             "rebalances %ld\n",
             ms->ncell[0], ms->ncell[1], ms->ncell[2],
             ms->partition.method == CD_PART_METIS ? "metis" : "slab",
             method == CD_PART_AUTO ? " (auto)" : "", ms->max_owned, ms->total_ghosts,
             100.0 * ms->total_ghosts / n, ms->partition.edge_cut, ms->imbalance,
             ms->partition.load, ms->partition.rejected_load, ms->rebalances);
    printf("loop wall %.3f s (slowest rank; force %.3f, lists+migration %.3f, exchange %.3f), "
           "rebuilds %ld\n",
           wall_max, fw, nw, xs_max, cd_sim_rebuilds(s));
    printf("loop CPU %.3f s summed over ranks (max rank %.3f); CPU outside MPI calls: max rank "
           "%.3f s; wall inside MPI calls: max rank %.3f s\n",
           cpu_sum, cpu_max, work_max, comm_wall_max);
    printf("list entries: max rank %.0f, all ranks %.0f\n", pairs_max, pairs_sum);
    printf("exchanged %.4g doubles in all (%.3g per particle-step)\n", xd_sum,
           xd_sum / ((double)n * steps));
    printf("particle-steps/s %.4g (wall), %.4g per CPU-second\n", (double)n * steps / wall_max,
           (double)n * steps / cpu_sum);
    printf("SCALING ranks %d wall %.4f cpu_work_max %.4f cpu_sum %.4f\n", ctx.size, wall_max,
           work_max, cpu_sum);
    printf("energies: step 0 total %.15g; step %ld KE %.15g PE %.15g total %.15g\n", e0.total,
           steps, e1.kinetic, e1.potential, e1.total);
  }
  free(all);
  free(cnt);
  free(dsp);
  cd_sim_destroy(&s);
  eos_destroy(&eos);
  par_finalize();
  return 0;
}
