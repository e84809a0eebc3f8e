/* SPDX-License-Identifier: MIT */
/* bench_dm_peri — particle-steps per second of the Hamiltonian discrete model on the benchmark
 * of bench/problems/dm_lammps.md (simple cubic 50³, horizon 3.015 h, Verlet, 300 steps).
 *
 *   bench_dm_peri [DECK]      (default DECK: bench/dm_peri/dm_peri.yaml; fewer steps: copy the
 *                             deck and edit `steps:`)
 *
 * Runs the deck through the `discrete_model` problem and prints one line
 *   dm_peri particles=... bonds=... steps=... threads=... loop_s=... particle_steps_per_s=...
 * The timed loop excludes set-up (families, A⁻¹, stability estimate). Threads: OMP_NUM_THREADS.
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dm.h"

int main(int argc, char **argv) {
  const char *deck = MSCALE_DM_PERI_DECK;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--help")) {
      printf("usage: bench_dm_peri [DECK]\n");
      return 0;
    } else deck = argv[i];
  }
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load(deck, &e);
  if (!doc) {
    dk_errors_print(&e, stderr);
    return 2;
  }
  dk_read_units(doc, &e);
  dk_get(dk_root(doc), "problem");
  eos_materials *mats = eos_materials_read(doc, &e);
  const dk_node *sec = dk_get(dk_root(doc), "discrete_model");
  dm_problem *p = sec ? dm_problem_read(doc, sec, mats, &e) : NULL;
  if (e.n || !p) {
    dk_errors_print(&e, stderr);
    return 2;
  }
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ms_status st = dm_problem_run(&ctx, p);
  const dm_run_summary *s = dm_problem_summary(p);
  printf("dm_peri particles=%zu bonds=%zu steps=%ld threads=%d loop_s=%.3f loop_cpu_s=%.3f "
         "particle_steps_per_s=%.4g particle_steps_per_cpu_s=%.4g\n",
         s->real_particles, s->bonds, s->steps, omp_get_max_threads(), s->wall_s, s->cpu_s,
         s->particle_steps_per_s,
         s->cpu_s > 0 ? (double)s->real_particles * s->steps / s->cpu_s : 0.0);
  dm_problem_destroy(&p);
  eos_materials_destroy(&mats);
  dk_free(doc);
  dk_errors_free(&e);
  ms_ctx_close(&ctx);
  return st == MS_OK ? 0 : 1;
}
