/* SPDX-License-Identifier: MIT */
/* Dusting check ([Davydov] §3, Figs. 18–20): a plane shock (piston u = 2 km/s, R_c = 1.1 r0)
 * reaches the smooth free surface of an aluminium slab with a periodic cross-section of two
 * lattice periods. Without damping, the anharmonic lattice throws single clusters off the
 * surface; with the relative-velocity damping Γ = c0/(50 a) (eq. 6) the spurious detached mass
 * drops by at least 10× and the free-surface velocity stays within 2 % of 2·up.
 * Detached = not in the largest connected component of the bond graph (pairs closer than
 * 1.5 r0, union–find over the Verlet lists). */
#include <math.h>
#include <omp.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "cd_impl.h"

#define R0 5.0e-4
#define C0 5.35

static int32_t find(int32_t *par, int32_t i) {
  while (par[i] != i) {
    par[i] = par[par[i]];
    i = par[i];
  }
  return i;
}

/* largest component's size and its mean vz within 10 r0 of its far end */
static size_t detached(const cd_sim *s, double *v_surface) {
  const ptl_state *p = s->p;
  const cd_neigh *nl = s->nl;
  const size_t n = p->n;
  int32_t *par = malloc(n * sizeof *par);
  size_t *size = calloc(n, sizeof *size);
  for (size_t i = 0; i < n; i++) par[i] = (int32_t)i;
  const double b2 = 1.5 * 1.5 * R0 * R0;
  for (int l = 0; l < nl->nlayer; l++)
    for (int32_t pos = nl->layer_start[l]; pos < nl->layer_start[l + 1]; pos++) {
      int32_t i = nl->sorted[pos];
      const int32_t *lst = nl->buf[l] + nl->first[pos];
      int np = nl->nplain[pos], ni = nl->nimg[pos];
      for (int k = 0; k < np + ni; k++) {
        const double *sh;
        int32_t j = *cd_nb_entry(nl, lst, np, k, &sh) & CD_NB_INDEX;
        double dx = p->x[i] - p->x[j] - sh[0], dy = p->y[i] - p->y[j] - sh[1],
               dz = p->z[i] - p->z[j] - sh[2];
        if (dx * dx + dy * dy + dz * dz < b2) {
          int32_t a = find(par, i), c = find(par, j);
          if (a != c) par[a < c ? c : a] = a < c ? a : c;
        }
      }
    }
  size_t best = 0;
  int32_t broot = 0;
  for (size_t i = 0; i < n; i++) {
    int32_t r = find(par, (int32_t)i);
    if (++size[r] > best) {
      best = size[r];
      broot = r;
    }
  }
  double zmax = -INFINITY;
  for (size_t i = 0; i < n; i++)
    if (find(par, (int32_t)i) == broot && p->z[i] > zmax) zmax = p->z[i];
  double vs = 0;
  int cnt = 0;
  for (size_t i = 0; i < n; i++)
    if (find(par, (int32_t)i) == broot && p->z[i] > zmax - 10 * R0) {
      vs += p->vz[i];
      cnt++;
    }
  *v_surface = vs / cnt;
  free(par);
  free(size);
  return n - best;
}

static size_t run(double J, cd_cutoff_mode mode, int nz, double *vfs) {
  eos_t *eos = eos_create_mg_cold(2.71, C0, 4.0, 2.0, true);
  const int nx = 2;
  const double a = sqrt(2.0) * R0, m = eos_rho0(eos) * cd_cluster_volume(CD_LATTICE_FCC, R0, 0);
  ptl_state *p = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = (size_t)4 * nx * nx * nz, .dim = 3}, &p),
          "ptl_state_create");
  double sh[3] = {0.25, 0.25, 0.0}, o[3] = {0, 0, 0};
  cd_lattice_fcc(p, nx, nx, nz, sh, o, R0, m, 0);
  const size_t npist = (size_t)4 * nx * nx * 2;
  for (size_t i = 0; i < npist; i++) p->flags[i] = PTL_DRIVEN;
  for (size_t i = npist; i < p->n; i++) {
    p->vx[i] = 0.01 * (2 * ptl_splitmix64_uniform(3, 3 * i) - 1);
    p->vy[i] = 0.01 * (2 * ptl_splitmix64_uniform(3, 3 * i + 1) - 1);
  }
  cd_box box = {.hi = {nx * a, nx * a, nz * a}, .bc = {CD_BC_PERIODIC, CD_BC_PERIODIC, CD_BC_FREE}};
  cd_config cfg = {.r0 = R0,
                   .skin = 0.1 * R0,
                   .dt = 0.02 * R0 / C0,
                   .cutoff = mode,
                   .damping_gamma = J > 0 ? C0 / (J * R0) : 0.0,
                   .sort_every = 8,
                   .lattice = CD_LATTICE_FCC};
  cd_sim *s = NULL;
  ms_must(cd_sim_create(&(cd_sim_params){.particles = p, .box = &box, .cfg = &cfg, .nmat = 1}, &s),
          "cd_sim_create");
  cd_pair_table *t = calloc(1, sizeof *t);
  assert_int_equal(
      cd_pair_table_build(t, eos, eos, CD_LATTICE_FCC, R0, 0, 1.1 * R0, 0.5 * R0, 1.0, 0), MS_OK);
  cd_sim_set_pair(s, 0, 0, t);
  double th[1] = {0}, uh[1] = {2.0}, dir[3] = {0, 0, 1};
  cd_history h = {1, th, uh};
  cd_sim_set_piston(s, &h, dir);
  assert_int_equal(cd_sim_init(s), MS_OK);
  /* shock transit (D ~ 8.4 km/s) plus as long again for the release to form */
  const long nsteps = (long)(1.6 * nz * a / 8.4 / cfg.dt);
  for (long k = 0; k < nsteps; k++) assert_int_equal(cd_sim_step(s), MS_OK);
  size_t nd = detached(s, vfs);
  cd_energy e;
  cd_sim_energy(s, &e);
  printf("J = %g (%s): %zu of %zu clusters detached, free-surface velocity %.4f km/s, dissipated "
         "%.3g of piston work %.3g\n",
         J, mode == CD_CUTOFF_PLAIN ? "plain" : "bonded", nd, p->n, *vfs, e.dissipated,
         e.piston_work);
  cd_sim_destroy(&s);
  eos_destroy(&eos);
  return nd;
}

static void test_dusting(void **state) {
  (void)state;
  const int nz = 150;
  for (int mode = CD_CUTOFF_PLAIN; mode <= CD_CUTOFF_BONDED; mode++) {
    double v0, v1;
    size_t d0 = run(0.0, (cd_cutoff_mode)mode, nz, &v0),
           d1 = run(50.0, (cd_cutoff_mode)mode, nz, &v1);
    /* without damping some clusters fly off (4 of 2400 in both modes at this size); damping
     * must cut the detached mass at least tenfold (here: to none) */
    assert_true(d0 > 0);
    assert_true(10 * d1 <= d0);
    /* free surface: u_fs = 2 up for a shock this weak (the release reverses the particle
     * velocity jump); 2 % as the issue asks (measured 0.6 %) */
    assert_true(fabs(v1 - 4.0) < 0.02 * 4.0);
  }
}

int main(void) {
  /* one thread: results do not depend on the thread count (test_cd_dynamics), and ctest -j
   * runs several of these at once, where OpenMP barriers of oversubscribed threads stall */
  omp_set_num_threads(1);
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_dusting)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
