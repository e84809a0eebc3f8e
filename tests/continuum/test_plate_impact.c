/* SPDX-License-Identifier: MIT */
/* Symmetric plate impact, Al on Al at 2 km/s, Mie–Grüneisen Us–up EOS (issue 3): particle
 * velocity v/2 behind both shocks, shock pressure and speed within 1 % of the Hugoniot tool
 * (eos_hugoniot), and the tagged contact node's history consistent with the grid. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "cont.h"

static const double rho0 = 2.703, v_imp = 2.0;

/* Position of the half-pressure point of the shock in the target (x > x_contact), by linear
 * interpolation between cell centres, scanning from the right (undisturbed) side. */
static double shock_position(const cont_view *v, double p_half) {
  for (size_t i = v->ncells - 1; i > 0; --i) {
    if (v->p[i - 1] >= p_half && v->p[i] < p_half) {
      double xa = 0.5 * (v->x[i - 1] + v->x[i]), xb = 0.5 * (v->x[i] + v->x[i + 1]);
      return xa + (p_half - v->p[i - 1]) / (v->p[i] - v->p[i - 1]) * (xb - xa);
    }
  }
  return NAN;
}

static void test_symmetric_al_impact(void **state) {
  eos_t *al = eos_create_mg_linear(rho0, 5.35, 1.34, 2.0);
  assert_non_null(al);
  eos_hugoniot_point h;
  double up = 0.5 * v_imp;
  assert_int_equal(eos_hugoniot(al, rho0, 0.0, 1, &up, &h), MS_OK);
  /* the linear Us–up Hugoniot: Us = c0 + s up, P = ρ0 Us up */
  assert_true(fabs(h.us - (5.35 + 1.34 * up)) < 1e-6 * h.us);

  cont_layer_spec layers[2] = {
      {.name = "impactor", .eos = al, .thickness = 0.5, .rho = rho0, .u = v_imp, .ncells = 500},
      {.name = "target", .eos = al, .thickness = 1.0, .rho = rho0, .ncells = 1000}};
  cont_tag_spec tag = {.name = "contact", .node = 500};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = layers;
  s.nlayers = 2;
  s.left.kind = CONT_BC_FREE;
  s.right.kind = CONT_BC_FREE;
  s.ntags = 1;
  s.tags = &tag;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);

  /* Shocks travel ~6.7 km/s: at t = 0.06 (0.6 µs) the target shock is 0.4 cm in, the impactor
   * shock 0.4 cm back, both clear of the free surfaces (0.5 and 1.0 cm away). */
  const double t1 = 0.03, t2 = 0.06;
  assert_int_equal(cont_grid_run_to(g, t1), MS_OK);
  cont_view v = cont_grid_view(g);
  double xs1 = shock_position(&v, 0.5 * h.p);
  assert_int_equal(cont_grid_run_to(g, t2), MS_OK);
  v = cont_grid_view(g);
  double xs2 = shock_position(&v, 0.5 * h.p);
  double us = (xs2 - xs1) / (t2 - t1); /* target at rest: lab speed = shock speed */

  /* Plateau between the contact and the shock, away from both by 20 % of the distance. */
  double xc = v.x[500];
  double pm = 0, um = 0, rm = 0;
  size_t n = 0;
  for (size_t i = 500; i < v.ncells; ++i) {
    double x = 0.5 * (v.x[i] + v.x[i + 1]);
    if (x > xc + 0.2 * (xs2 - xc) && x < xc + 0.8 * (xs2 - xc)) {
      pm += v.p[i];
      um += 0.5 * (v.u[i] + v.u[i + 1]);
      rm += v.rho[i];
      ++n;
    }
  }
  pm /= (double)n;
  um /= (double)n;
  rm /= (double)n;
  printf("plate impact Al/Al %.1f km/s: u = %.6f (exact %.6f), P = %.4f GPa (Hugoniot %.4f, "
         "%+.3f %%), Us = %.4f km/s (Hugoniot %.4f, %+.3f %%), rho = %.4f (Hugoniot %.4f)\n",
         v_imp, um, up, pm, h.p, 100 * (pm / h.p - 1), us, h.us, 100 * (us / h.us - 1), rm, h.rho);
  /* Symmetry makes the contact move at exactly v/2; round-off in the lab frame (u = 2 vs 0 is
   * not bit-symmetric) allows ~1e-13 after 10³ steps; the plateau mean carries the small
   * post-shock ringing, 1e-3 of up. */
  cont_history hist = cont_grid_history(g, 0);
  assert_true(hist.n == (size_t)cont_grid_steps(g) + 1);
  double worst = 0;
  for (size_t k = 1; k < hist.n; ++k) worst = fmax(worst, fabs(hist.u[k] - up));
  printf("plate impact: contact velocity max |u - v/2| over %zu steps = %.2e\n", hist.n, worst);
  assert_true(worst < 1e-10);
  assert_true(fabs(um - up) < 1e-3 * up);
  /* Issue 3: P and Us within 1 % of the Hugoniot. */
  assert_true(fabs(pm / h.p - 1.0) < 0.01);
  assert_true(fabs(us / h.us - 1.0) < 0.01);
  assert_true(fabs(rm / h.rho - 1.0) < 0.01);

  /* The history's last row is the grid's current state (same time level), and x(t) is the
   * trapezoidal integral of u(t) — exactly how the grid moves the node. */
  size_t last = hist.n - 1;
  assert_true(hist.t[last] == cont_grid_time(g));
  assert_true(hist.x[last] == v.x[500] && hist.u[last] == v.u[500]);
  assert_true(hist.p_left[last] == v.p[499] && hist.rho_right[last] == v.rho[500]);
  double xint = hist.x[0];
  for (size_t k = 1; k < hist.n; ++k)
    xint += 0.5 * (hist.t[k] - hist.t[k - 1]) * (hist.u[k] + hist.u[k - 1]);
  /* round-off of 10³ additions; the landing steps at t1, t2 use exact times */
  assert_true(fabs(xint - hist.x[last]) < 1e-12);

  /* Interpolation for a particle piston: at the recorded times it returns the rows; between
   * rows u is linear (1e-14: round-off of u ~ 1). */
  for (size_t k = 0; k + 1 < hist.n; k += 97) {
    double xk, uk, xm, um2;
    cont_history_at(&hist, hist.t[k], &xk, &uk);
    assert_true(xk == hist.x[k] && uk == hist.u[k]);
    cont_history_at(&hist, 0.5 * (hist.t[k] + hist.t[k + 1]), &xm, &um2);
    assert_true(fabs(um2 - 0.5 * (hist.u[k] + hist.u[k + 1])) < 1e-14);
    /* the contact moves forward (u ≈ 1 > 0): the midpoint lies between the rows */
    assert_true(xm > hist.x[k] && xm < hist.x[k + 1]);
  }
  /* Sampling the state at a position inside the shocked target. */
  cont_sample smp;
  assert_true(cont_grid_sample(g, xc + 0.5 * (xs2 - xc), &smp));
  assert_true(fabs(smp.u - up) < 1e-2 && fabs(smp.p / h.p - 1) < 0.02 && smp.layer == 1);
  assert_false(cont_grid_sample(g, v.x[v.ncells] + 1.0, &smp));

  cont_grid_destroy(&g);
  eos_destroy(&al);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_symmetric_al_impact)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
