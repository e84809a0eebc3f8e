/* SPDX-License-Identifier: MIT */
/* Zone-steps per second of the 2D grid (issue 24): an aluminium block (Mie–Grüneisen, the
 * repository's `al`, docs/design.md §3) of N × N zones hit by a 1 km/s piston, walls elsewhere,
 * K steps. Usage: c2d_speed [N=1000] [K=20] [threads=1] [limiter=1]. Not a test: prints one line,
 * the loop's wall time and its process CPU time (all threads; the figure to quote on a loaded
 * machine, docs/benchmarks.md "How to measure"). */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "c2d_test.h"

int main(int argc, char **argv) {
  size_t n = argc > 1 ? (size_t)atol(argv[1]) : 1000;
  long k = argc > 2 ? atol(argv[2]) : 20;
  int th = argc > 3 ? atoi(argv[3]) : 1;
  eos_t *al = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  c2d_fixture f;
  fixture_init(&f, n, n, al);
  c2d_mesh_rect(n, n, 0.0, 1.0, 0.0, 1.0, f.x, f.y);
  for (size_t z = 0; z < n * n; ++z) {
    f.rho[z] = 2.703;
    f.e[z] = 0.0;
  }
  c2d_setup s;
  c2d_setup_defaults(&s);
  fixture_setup(&f, &s);
  if (argc > 4) s.use_limiter = atoi(argv[4]) != 0; /* 4th argument: limiter on/off */
  s.bc[C2D_ILO].kind = C2D_BC_PISTON;
  s.bc[C2D_ILO].dir[0] = 1.0;
  s.bc[C2D_ILO].fn.kind = CONT_FN_CONST;
  s.bc[C2D_ILO].fn.value = 1.0;
  s.bc[C2D_IHI].kind = s.bc[C2D_JLO].kind = s.bc[C2D_JHI].kind = C2D_BC_WALL;
  char msg[256];
  c2d_grid *g = NULL;
  c2d_grid_create(&s, &g, msg, sizeof msg);
  if (!g) {
    fprintf(stderr, "%s\n", msg);
    return 1;
  }
  c2d_grid_set_threads(g, th);
  c2d_grid_step(g, INFINITY); /* warm-up */
  double t0 = ms_wall_time();
  const clock_t c0 = clock();
  for (long i = 0; i < k; ++i)
    if (c2d_grid_step(g, INFINITY) != MS_OK) {
      fprintf(stderr, "%s\n", c2d_grid_error(g));
      return 1;
    }
  double w = ms_wall_time() - t0, cpu = (double)(clock() - c0) / CLOCKS_PER_SEC;
  printf("c2d_speed: %zu x %zu zones, %ld steps, %d thread(s): %.3f s, %.3e zone-steps/s; "
         "%.3f s CPU, %.3e zone-steps per CPU-s\n",
         n, n, k, th, w, (double)(n * n) * (double)k / w, cpu, (double)(n * n) * (double)k / cpu);
  c2d_grid_destroy(&g);
  fixture_free(&f);
  eos_destroy(&al);
  return 0;
}
