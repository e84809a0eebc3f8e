/* SPDX-License-Identifier: MIT */
/* Richtmyer–Meshkov microjets of the finite-deformation discrete model, the coupled problem's
 * particle region `discrete_model` driven through particles/ptl_region.h (bench/dm_jets/jets.c
 * runs the cases; docs/validation.md "Microjets" has the full sweep and its command).
 *
 * Lead, inputs/eos-materials.yaml's `pb` (cold-curve Mie–Grüneisen), yield: none, a constant
 * 0.8 km/s piston: 26.2 GPa, U_s = 2.887 km/s (`mscale hugoniot inputs/eos-materials.yaml
 * --material pb --up 0.8`). A sine groove of wavelength λ = 64 or 128 h (h = 1 µm) on the
 * free surface, one wavelength wide and periodic, slab depth 1.5 λ:
 *   - k h0 = 0.1 (λ = 128 h): the amplitude's growth rate over [t_b + λ/U_s, t_b + 3 λ/U_s]
 *     (the slope of (x_valley − x_peak)/2) is Richtmyer's impulsive k a0 (1 − u_p/U_s) Δu
 *     [Richtmyer1960; Buttler2012] within 10 %, and the spike tip runs ahead of it by the
 *     second harmonic of the weakly nonlinear theory [VelikovichDimonte1996; ZhangSohn1997]:
 *     the spike's velocity over the free surface is η̇ (1 + k η) within 10 %;
 *   - k h0 = 0.5 with strength (elastic–perfectly plastic, G = 8.6 GPa): the growth η_max − η_b
 *     is arrested at Y = 1 and 2 GPa, and halves when Y doubles (∝ 1/Y, [Piriz2008;
 *     Dimonte2011]) to within a log–log slope of −1 ± 0.25. Why these two: below 1 GPa the
 *     arrested k (η_max − η_b) exceeds 1 (nonlinear, not strength-limited; the sweep's slope
 *     flattens to −0.5), at 4 GPa η_max − η_b is 1.6 spacings (unresolved). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "jets.h"

static eos_materials *mats;
static dk_doc *doc;
static const eos_t *pb;

static int setup(void **state) {
  (void)state;
  const char *src = getenv("MSCALE_SOURCE_DIR");
  char path[1024];
  snprintf(path, sizeof path, "%s/inputs/eos-materials.yaml", src ? src : ".");
  dk_errors e;
  dk_errors_init(&e);
  doc = dk_load(path, &e);
  mats = doc ? eos_materials_read(doc, &e) : NULL;
  const eos_material *m = mats ? eos_materials_find(mats, "pb", &e, doc, NULL) : NULL;
  if (e.n) dk_errors_print(&e, stderr);
  dk_errors_free(&e);
  pb = m ? m->eos : NULL;
  return pb ? 0 : -1;
}

static int teardown(void **state) {
  (void)state;
  eos_materials_destroy(&mats);
  dk_free(doc);
  return 0;
}

/* The coarse resolution of the sweep (bench_dm_jets defaults): λ = 64 h, depth 1.5 λ, run to
 * 3 λ/U_s after breakout (before the release reflected at the piston returns to the surface,
 * ≈ 3.1 λ/U_s here), dt_margin 0.35 (the sweep's; the region's default 0.5 gives the same
 * spike velocities to 1e-4 km/s at k h0 = 0.1 and 1.5, measured). */
static jets_case coarse(double kh0) {
  return (jets_case){.eos = pb,
                     .up = 0.8,
                     .h = 1e-4,
                     .ncol = 64,
                     .kh0 = kh0,
                     .depth_wl = 1.5,
                     .obs_wl = 3.0,
                     .fit_from = 1.0,
                     .fit_to = 3.0,
                     .dt_margin = 0.35,
                     .G = 8.6};
}

/* k h0 = 0.1 at λ = 128 h. The impulsive model is a linear theory: what it predicts is the
 * growth of the fundamental, measured by η = (x_valley − x_peak)/2, in which the second
 * harmonic of the weakly nonlinear profile cancels. The spike's leading particles run ahead of
 * it: by the end of the window k η ≈ 0.6, and at a free surface (|A| = 1) the spike speeds up
 * and the bubble slows down as the profile steepens (docs/validation.md "Microjets"). */
static void test_linear_growth(void **state) {
  (void)state;
  jets_case c = coarse(0.1);
  c.ncol = 128;
  jets_result r;
  assert_int_equal(jets_run(&c, &r, NULL, 1), MS_OK);
  printf("kh0 0.1, lambda 128 h: a0/h0 %.3f, du %.4f km/s, k a0+ du %.4f km/s; amplitude rate "
         "%.4f (%+.1f %%); spike tip - u_fs %.4f (%+.1f %%; peak %.4f, late %.4f)\n",
         r.a0 / r.h0, r.du, r.v_lin, r.v_eta, 100 * (r.v_eta / r.v_lin - 1), r.v_spike,
         100 * (r.v_spike / r.v_lin - 1), r.v_spike_peak, r.v_spike_late);
  assert_int_equal(r.status, 0);
  /* the flat surface's jump: 2 u_p up to the release isentrope's difference from the
   * Hugoniot (measured 1.6201 = 2 u_p + 1.3 %) */
  assert_true(fabs(r.du / (2 * c.up) - 1) < 0.03);
  /* 10 %: the bound for k h0 ≤ 0.2 (measured −4.2 % here, +1.1 % at λ = 256 h; −16 %
   * at 64 h, where a0 ≈ h: not resolved). The slope averages the ringing of the compressible
   * start-up over the window's two λ/U_s; a0 is the cut lattice's fundamental (1.04 h0) */
  assert_true(fabs(r.v_eta / r.v_lin - 1) < 0.10);
  /* the spike leads the amplitude (measured +29 % over k a0+ du, +34 % over the amplitude's
   * rate): a model without the nonlinear asymmetry (or with the jets held back) fails this */
  assert_true(r.v_spike > 1.1 * r.v_eta);
  /* ... and by as much as the weakly nonlinear theory of a free surface says: to second order
   * [VelikovichDimonte1996; ZhangSohn1997] the spike sits at η + (k/2)(η² − η_b²) from the mean
   * surface (velocity η̇ (1 + k η)), η the measured amplitude. Over the window k η runs from
   * 0.18 to 0.69. 10 %: the bound on the spike; the theory's next order is O((k η)²)
   * of η̇ (measured −6.6 % here; −3.9 % at λ = 256 h, −14 % at 64 h, where the amplitude itself
   * is 16 % slow). Seen to fail with the second harmonic's sign flipped in jets.c (η̇ (1 − k η):
   * the spike 2.4× the prediction, measured) and without it (η̇ alone: 1.34×). */
  printf("second order: spike %.4f km/s vs eta'(1 + k eta) %.4f (%+.1f %%); bubble %.4f vs "
         "-eta'(1 - k eta) %.4f; k eta %.3f -> %.3f over the window\n",
         r.v_spike, r.v_spike_nl, 100 * (r.v_spike / r.v_spike_nl - 1), r.v_bubble, r.v_bubble_nl,
         r.keta_fit0, r.keta_fit1);
  assert_true(fabs(r.v_spike / r.v_spike_nl - 1) < 0.10);
}

static void test_strength_arrests_growth(void **state) {
  (void)state;
  const double Y[2] = {1.0, 2.0};
  double deta[2];
  for (int i = 0; i < 2; i++) {
    jets_case c = coarse(0.5);
    c.Y = Y[i];
    jets_result r;
    assert_int_equal(jets_run(&c, &r, NULL, 1), MS_OK);
    printf("Y %.1f GPa: eta_b %.3g cm, deta_max %.4g cm (k deta %.4f) at %.4g after breakout "
           "(run %.4g), %s\n",
           Y[i], r.eta_b, r.deta_max, r.k * r.deta_max, r.t_eta_max, r.t_end - r.t_break,
           r.arrested ? "arrested" : "still growing");
    assert_int_equal(r.status, 0);
    assert_true(r.arrested);
    /* well below the strength-free growth over the same time (v_lin (t_end − t_b)) */
    assert_true(r.deta_max < 0.5 * r.v_lin * (r.t_end - r.t_break));
    deta[i] = r.deta_max;
  }
  /* η_max − η_b ∝ ρ η̇0²/(k Y) in the strength-limited regime: slope −1 ± 0.25 (the issue's
   * bound) between Y and 2Y */
  const double slope = log(deta[1] / deta[0]) / log(Y[1] / Y[0]);
  printf("log-log slope of the arrested growth vs Y: %.3f\n", slope);
  assert_true(fabs(slope + 1) < 0.25);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_linear_growth),
                                     cmocka_unit_test(test_strength_arrests_growth)};
  return cmocka_run_group_tests(tests, setup, teardown);
}
