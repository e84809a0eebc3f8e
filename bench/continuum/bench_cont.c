/* SPDX-License-Identifier: MIT */
/* bench_cont — cell-steps per second of the continuum step on a large planar Mie–Grüneisen
 * problem (issue 3: 10⁶ cells, aim ≥ 1e8 cell-steps/s on one core).
 *
 *   build/bench/continuum/bench_cont [CELLS] [STEPS] [mg|gas]   (defaults 1000000 200 mg)
 *
 * `gas` replaces the Mie–Grüneisen EOS by an ideal gas (same density, e = 1 kJ/g) to separate
 * the cost of the scheme from the cost of the EOS evaluation.
 *
 * Problem: an Al flyer (u = 2 km/s) on an Al target, linear Us–up EOS, free surfaces, so shocks
 * are present and the viscosity/EOS work is representative. Prints the set-up time, the time
 * per step, cell-steps/s (wall and CPU time), and the energy drift as a check that the run was sane. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cont.h"

int main(int argc, char **argv) {
  long cells = argc > 1 ? atol(argv[1]) : 1000000;
  long steps = argc > 2 ? atol(argv[2]) : 200;
  if (cells < 2 || steps < 1) {
    fprintf(stderr, "usage: bench_cont [CELLS >= 2] [STEPS >= 1]\n");
    return 2;
  }
  bool gas = argc > 3 && !strcmp(argv[3], "gas");
  eos_t *al = gas ? eos_create_ideal_gas(1.4, 2.703) : eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  cont_layer_spec layers[2] = {{.name = "flyer",
                                .eos = al,
                                .thickness = 1.0,
                                .rho = 2.703,
                                .u = 2.0,
                                .e = gas ? 1.0 : 0.0,
                                .ncells = cells / 2},
                               {.name = "target",
                                .eos = al,
                                .thickness = 1.0,
                                .rho = 2.703,
                                .e = gas ? 1.0 : 0.0,
                                .ncells = cells - cells / 2}};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = layers;
  s.nlayers = 2;
  s.left.kind = CONT_BC_FREE;
  s.right.kind = CONT_BC_FREE;
  double w0 = ms_wall_time();
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  if (!g) {
    fprintf(stderr, "bench_cont: %s\n", msg);
    return 1;
  }
  double w1 = ms_wall_time();
  cont_balance b0 = cont_grid_balance(g);
  /* warm-up: a few steps so the time step has grown and the shock has formed */
  for (int k = 0; k < 10; ++k) cont_grid_step(g, INFINITY);
  double w2 = ms_wall_time();
  clock_t c2 = clock();
  for (long k = 0; k < steps; ++k) {
    if (cont_grid_step(g, INFINITY) != MS_OK) {
      fprintf(stderr, "bench_cont: %s\n", cont_grid_error(g));
      return 1;
    }
  }
  double w3 = ms_wall_time();
  clock_t c3 = clock();
  double cpu = (double)(c3 - c2) / CLOCKS_PER_SEC;
  cont_balance b = cont_grid_balance(g);
  double rate = (double)cells * (double)steps / (w3 - w2);
  printf("bench_cont: %ld cells, %ld steps (after 10 warm-up), %s EOS, set-up %.3f s\n", cells,
         steps, gas ? "ideal-gas" : "Mie-Grueneisen Us-up", w1 - w0);
  printf("bench_cont: %.3f ms/step, %.3e cell-steps/s, %.2f ns per cell-step\n",
         1e3 * (w3 - w2) / (double)steps, rate, 1e9 / rate);
  /* CPU time is what the process got; on a shared machine wall time also counts waiting */
  printf("bench_cont: CPU time %.3f s for %.3f s wall: %.3e cell-steps per CPU-second, %.2f ns\n",
         cpu, w3 - w2, (double)cells * (double)steps / cpu, 1e9 * cpu / ((double)cells * steps));
  printf("bench_cont: energy drift %.2e (relative), t = %.4g\n",
         (b.internal + b.kinetic - b.work - b0.internal - b0.kinetic) / (b0.internal + b0.kinetic),
         cont_grid_time(g));
  cont_grid_destroy(&g);
  eos_destroy(&al);
  return 0;
}
