/* SPDX-License-Identifier: MIT */
/* The Taylor anvil test at CI resolution (docs/validation.md, "Taylor anvil test"): the shipped
 * deck inputs/dm-taylor-cu-wg-coarse.yaml — the OFHC copper rod of [WilkinsGuinan1973]
 * (L0 = 23.47 mm, D0 = 7.62 mm, 210 m/s onto a rigid anvil), Johnson–Cook copper, the
 * finite-deformation discrete model in full 3D at h = R0/6 — run through the `impact` problem,
 * with per-family reference updates that keep and merge the families (each family against its
 * own 1 % bond-stretch trigger; docs/particles-dm.md "Reference update", "Per-family
 * references"), its final length, footprint and profile above the foot compared with the measured ones
 * ([Zelepugin2023], test 1: L_f = 14.80 mm, largest radius 8.40 mm), and its energy and momentum
 * balance checked.
 * DM_TAYLOR_PRINT=1 prints the numbers. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "dm.h"
#include "test_util.h"

/* measured ([Zelepugin2023] test 1, from [WilkinsGuinan1973]), mm */
static const double exp_length = 14.7964, exp_footprint = 2 * 8.3965;
/* measured radius at 0.2, 0.5, 2/3 of the final length from the face (DM_TAYLOR_PROFILE_F) */
static const double exp_radius[DM_TAYLOR_PROFILE_N] = {5.347, 4.400, 4.111};

static void test_taylor_cu_coarse(void **state) {
  (void)state;
  const char *src = getenv("MSCALE_SOURCE_DIR");
  assert_non_null(src);
  char path[4096];
  snprintf(path, sizeof path, "%s/inputs/dm-taylor-cu-wg-coarse.yaml", src);
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load(path, &e);
  assert_non_null(doc);
  dk_read_units(doc, &e);
  dk_get(dk_root(doc), "problem");
  eos_materials *mats = eos_materials_read(doc, &e);
  dm_impact *p = dm_impact_problem_read(doc, dk_get(dk_root(doc), "impact"), mats, &e);
  dk_report_unused(&e, doc);
  dk_errors_print(&e, stderr);
  assert_non_null(p);
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = getenv("DM_TAYLOR_PRINT") ? MS_LOG_INFO : MS_LOG_ERROR;
  assert_int_equal(dm_impact_problem_run(&ctx, p), MS_OK);
  ms_ctx_close(&ctx);
  const dm_impact_summary *s = dm_impact_get_summary(p);
  const double L = 10 * s->length, D = 10 * s->footprint;
  printf("Taylor Cu (Wilkins-Guinan, 210 m/s), h = R0/6: %zu particles, %ld steps; L %.3f mm "
         "(experiment %.2f, %+.2f %%), D %.3f mm (experiment %.2f, %+.2f %%); balance %.3g, "
         "wall %.3g, E_hg/E0 %.3g, transverse momentum %.3g, final normal momentum %.3g\n",
         s->particles, s->steps, L, exp_length, 100 * (L / exp_length - 1), D, exp_footprint,
         100 * (D / exp_footprint - 1), s->energy_err, s->wall_err, s->hg_ratio, s->p_transverse,
         s->p_normal);
  /* K + U + E_hg − W_wall = E0 holds per half kick (dm_finite.c, and with per-family
   * references dm_fin_local.c): round-off over ~3000 steps (measured 3.7e-14) */
  assert_true(s->energy_err < 1e-11);
  /* frictionless wall and pairwise internal forces: no momentum along the wall */
  assert_true(s->p_transverse < 1e-12);
  /* the rod has stopped on the wall: what is left of its momentum is the elastic rebound */
  assert_true(fabs(s->p_normal) < 0.1);
  /* LOOSE BOUNDS (the criterion of the full-size run, docs/validation.md, is 5 % and 10 %).
   * Length: the 5 % of the criterion holds already at h = R0/6 (measured +3.8 %; +2.5 % at
   * R0/12).
   * Footprint: not met at this resolution (docs/validation.md). The measured largest radius
   * (8.40 mm) is a lip at the impact face — the measured outline falls to 5.60 mm within 1.75 mm
   * of the face, less than three particle layers of h = 0.635 mm here. With the deck's
   * per-family reference updates (families merged, each family's penalty mismatch restarted
   * every 1 % of its own bond strain) the foot forms a flared lip: measured −14.3 % here,
   * −11.2 % at R0/9 and −9.7 % at R0/12 (the same deck). 18 % admits the coarse lattice's
   * deficit with 3.8 points (0.6 mm, one spacing) for compiler and platform round-off in a run
   * of 2800 steps with ~2000 update steps, and fails the total-Lagrangian penalty without
   * updates (−35.1 %, shown failing) and the global update that keeps the families (−22.3 %). */
#define CI_LENGTH_TOL    0.05
#define CI_FOOTPRINT_TOL 0.18
  assert_true(fabs(L / exp_length - 1) < CI_LENGTH_TOL);
  assert_true(fabs(D / exp_footprint - 1) < CI_FOOTPRINT_TOL);
  /* Profile above the foot (0.2, 0.5, 2/3 of L_f): the model's surface radius there is known
   * only to within half a spacing radially (the outer particles stand h/2 inside the surface,
   * which is taken to stretch with them), so h/2 = 0.3175 mm is the resolution of the
   * comparison; measured +0.14, +0.00, −0.09 mm here. The
   * total-Lagrangian penalty without updates gives +0.53 mm at 0.5 L_f (the upper rod too wide:
   * the penalty spreads the foot's deformation up the rod), and halving Johnson–Cook's hardening
   * B +0.88 mm at 0.2 L_f: both fail. */
  for (int k = 0; k < DM_TAYLOR_PROFILE_N; ++k) {
    const double dr = 10 * s->radius_at[k] - exp_radius[k];
    printf("  radius at %.3f L_f: %.3f mm (experiment %.3f, %+.3f mm)\n",
           (double[])DM_TAYLOR_PROFILE_F[k], 10 * s->radius_at[k], exp_radius[k], dr);
    assert_true(fabs(dr) < 0.3175);
  }
  dm_impact_problem_destroy(&p);
  eos_materials_destroy(&mats);
  dk_free(doc);
  dk_errors_free(&e);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_taylor_cu_coarse)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
