/* SPDX-License-Identifier: MIT */
/* The `impact` problem (particles/dm/dm_impact*.c) and the reference-configuration update
 * (particles/dm/dm_refamily.c): located deck errors; an elastic box bouncing off the rigid
 * wall (energy balance to round-off with the wall's work, frictionless wall, rebound); the
 * reference update of an affinely deformed block (density, pressure and stress unchanged,
 * families rebuilt) and its refusal of a degenerate family (state restored, particle named). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "dm_test.h"
#include "test_util.h"

static const char *materials =
    "problem: impact\n"
    "materials:\n"
    "  - name: al\n"
    "    eos: {type: mg_linear, rho0: 2.703, c0: 5.35, s: 1.34, gamma0: 2.0}\n"
    "    shear_modulus: 27.6\n";

typedef struct loaded {
  dk_doc *doc;
  eos_materials *mats;
  dm_impact *p;
  dk_errors e;
} loaded;

static void load(loaded *L, const char *section) {
  char text[4096];
  snprintf(text, sizeof text, "%s%s", materials, section);
  L->doc = dm_test_deck(text, "deck.yaml", &L->mats, &L->e);
  L->p = dm_impact_problem_read(L->doc, dk_get(dk_root(L->doc), "impact"), L->mats, &L->e);
  dk_report_unused(&L->e, L->doc);
}

static void unload(loaded *L) {
  dm_impact_problem_destroy(&L->p);
  dm_test_deck_free(L->doc, &L->mats, &L->e);
}

/* The deck errors the issue names, each located at its body (line of the list item). */
static void test_placement_errors(void **state) {
  (void)state;
  loaded L;
  load(&L, "impact:\n"
           "  spacing: 0.1\n"
           "  domain: {lo: [-1, -1, 0], hi: [1, 1, 2]}\n"
           "  bodies:\n"
           "    - {shape: box, material: al, center: [0, 0, 0.5], size: [0.6, 0.6, 0.6]}\n"
           "    - {shape: sphere, material: al, center: [0, 0, 0.9], radius: 0.3}\n" /* overlap */
           "    - {shape: sphere, material: al, center: [0, 0, 1.9], radius: 0.3}\n" /* outside */
           "    - {shape: box, material: al, center: [0.42, 0, 0.5], size: [0.2, 0.2, 0.2],\n"
           "       velocity: [0, 0, -5]}\n"      /* too fast for the first step, and too close */
           "  wall: {axis: z, position: 0.25}\n" /* body 0 crosses it */
           "  t_end: 1\n");
  assert_null(L.p);
  dk_errors_print(&L.e, stderr);
  assert_true(has_error(&L.e, "deck.yaml:11:7: impact.bodies[1]: overlaps bodies[0]"));
  assert_true(has_error(&L.e, "deck.yaml:12:7: impact.bodies[2]: the body is not inside"));
  assert_true(has_error(&L.e, "deck.yaml:10:7: impact.bodies[0]: the body crosses the wall"));
  assert_true(has_error(&L.e, "deck.yaml:14:18: impact.bodies[3].velocity") &&
              has_error(&L.e, "first step"));
  assert_true(has_error(&L.e, "deck.yaml:13:7: impact.bodies[3]: comes within the horizon"));
  unload(&L);
}

/* Two bodies whose impact the contact penalty cannot hold (docs/input-impact.md): the acoustic
 * pressure of Al on Al at 6.7 km/s, 48 GPa, against c_c M = 0.1 · 77 GPa: located at the
 * velocity of the second body. */
static void test_contact_too_soft(void **state) {
  (void)state;
  loaded L;
  load(&L, "impact:\n"
           "  spacing: 0.1\n"
           "  domain: {lo: [-1, -1, -1], hi: [1, 1, 2]}\n"
           "  contact: {stiffness: 0.1}\n"
           "  bodies:\n"
           "    - {shape: box, material: al, center: [0, 0, 0], size: [1.0, 1.0, 0.2]}\n"
           "    - {shape: sphere, material: al, center: [0, 0, 0.6], radius: 0.25,\n"
           "       velocity: [0, 0, -6.7]}\n"
           "  t_end: 1\n");
  assert_null(L.p);
  dk_errors_print(&L.e, stderr);
  assert_true(has_error(&L.e, "deck.yaml:13:18: impact.bodies[1].velocity") &&
              has_error(&L.e, "impact.contact.stiffness"));
  unload(&L);
}

/* Two equal elastic Al boxes collide head on at ±0.1 km/s through the contact between bodies
 * (dm_impact_contact.c): central pair forces, so the momentum stays 0 to round-off (1e-12 of
 * the bodies' |m v|, measured in the log); K + U + E_hg − W_contact = E0 per half kick, the
 * balance to round-off (1e-12 E0); the contact's work against its stored energy is the
 * penalty's time discretisation, second order in ω Δt (measured 2.3e-2 E0 at ω Δt ≤ 0.8 and
 * 6.3e-3 at the contact's ω Δt ≤ courant = 0.4: ratio 3.7, about 4; bound 1e-2); and the
 * boxes separate again, each moving back (Σ over body 0 of m u_z < 0 at the end, > 50 % of its
 * initial momentum: an elastic bar rebounds whole, the boxes keep part in vibration). */
static void test_contact_rebound(void **state) {
  (void)state;
  loaded L;
  load(&L, "impact:\n"
           "  spacing: 0.05\n"
           "  domain: {lo: [-1, -1, -1], hi: [1, 1, 1]}\n"
           "  bodies:\n"
           "    - {shape: box, material: al, center: [0, 0, -0.2], size: [0.3, 0.3, 0.3],\n"
           "       yield: elastic_plastic, yield_stress: 10, velocity: [0, 0, 0.1]}\n"
           "    - {shape: box, material: al, center: [0, 0, 0.2], size: [0.3, 0.3, 0.3],\n"
           "       yield: elastic_plastic, yield_stress: 10, velocity: [0, 0, -0.1]}\n"
           "  t_end: 0.8\n"
           "  output: {energy_every: 1}\n");
  assert_non_null(L.p);
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = MS_LOG_INFO;
  assert_int_equal(dm_impact_problem_run(&ctx, L.p), MS_OK);
  ms_ctx_close(&ctx);
  const dm_impact_summary *s = dm_impact_get_summary(L.p);
  const double P1 = s->p0_body0, P1end = s->p_body0;
  printf("contact rebound: %ld steps, balance %.3g, contact %.3g, |P| %.3g, body 0: P %.4g -> "
         "%.4g\n",
         s->steps, s->energy_err, s->wall_err, s->p_total, P1, P1end);
  assert_true(s->energy_err < 1e-12);
  assert_true(s->wall_err < 1e-2);
  assert_true(s->p_total < 1e-12);
  assert_true(P1 > 0 && P1end < -0.5 * P1);
  unload(&L);
}

/* Shape and key errors are collected in one pass. */
static void test_key_errors(void **state) {
  (void)state;
  loaded L;
  load(&L, "impact:\n"
           "  spacing: 0.1\n"
           "  domain: {lo: [-1, -1], hi: [1, 1, 2]}\n" /* 2 values */
           "  bodies:\n"
           "    - {shape: cone, material: al, center: [0, 0, 0.5]}\n" /* unknown shape */
           "    - {shape: sphere, material: cu, center: [0, 0, 1], radius: 0.2}\n" /* unknown */
           "  wall: {axis: w, position: 0}\n" /* unknown axis */
           "  t_end: 1\n");
  assert_null(L.p);
  dk_errors_print(&L.e, stderr);
  assert_true(has_error(&L.e, "deck.yaml:8:16: impact.domain.lo: needs 3 values"));
  assert_true(has_error(&L.e, "deck.yaml:10:15: impact.bodies[0].shape") &&
              has_error(&L.e, "'cone'"));
  assert_true(has_error(&L.e, "deck.yaml:11:7: unknown material 'cu'"));
  assert_true(has_error(&L.e, "deck.yaml:12:16: impact.wall.axis"));
  unload(&L);
}

/* The per-family reference update's deck errors (docs/input-impact.md), each at its key:
 * scope: family with the rebuilding update, with the short-range contact, with a fracture
 * model; an unknown scope; any reference update with a fracture model. */
static void test_scope_errors(void **state) {
  (void)state;
  /* per case: the body's fracture model (or none), what follows t_end, the error */
  static const char *const frac = ",\n       fracture: {model: mean_stress, spall_strength: 1.2}";
  static const struct {
    const char *body_extra, *tail, *err;
  } cases[] = {
      {"", "  reference_update: {threshold: 0.05, scope: family}\n",
       "deck.yaml:12:46: impact.reference_update.scope: family needs families: keep or merge"},
      {"",
       "  reference_update: {threshold: 0.05, families: merge, scope: family}\n"
       "  contact_distance: 0.5\n",
       "deck.yaml:12:63: impact.reference_update.scope: family is not available with "
       "contact_distance"},
      {"", "  reference_update: {threshold: 0.05, families: keep, scope: every}\n",
       "deck.yaml:12:62: impact.reference_update.scope: expected one of: all, family"},
      /* with a fracture model: scope family, and any reference update (the global one
       * refused it only at run time) */
      {frac, "  reference_update: {threshold: 0.05, families: merge, scope: family}\n",
       "deck.yaml:13:63: impact.reference_update.scope: family is not available with fracture"},
      {frac, "  reference_update: {threshold: 0.05}\n",
       "deck.yaml:13:21: impact.reference_update is not available with fracture"},
  };
  for (size_t q = 0; q < sizeof cases / sizeof *cases; ++q) {
    char text[2048];
    snprintf(text, sizeof text,
             "impact:\n"
             "  spacing: 0.1\n"
             "  domain: {lo: [-1, -1, 0], hi: [1, 1, 2]}\n"
             "  bodies:\n"
             "    - {shape: box, material: al, center: [0, 0, 0.5], size: [0.4, 0.4, 0.4]%s}\n"
             "  t_end: 1\n%s",
             cases[q].body_extra, cases[q].tail);
    loaded L;
    load(&L, text);
    dk_errors_print(&L.e, stderr);
    assert_null(L.p);
    assert_true(has_error(&L.e, cases[q].err));
    unload(&L);
  }
}

/* An elastic Al box (Y0 = 10 GPa: no yield at 0.1 km/s) hits the wall and rebounds. The wall's
 * work enters the balance K + U + E_hg − W_wall = E0 exactly per half kick (dm_finite.c): the
 * bound 1e-12 E0 is round-off over ~1000 steps of sums of ~1e3 terms. The wall is
 * frictionless and the internal forces pairwise: the momentum along the wall stays 0 to
 * round-off (1e-12 of |P0|). After the contact (no particle beyond the contact plane) the
 * stored wall energy is 0 and −W_wall is the energy the penalty kept: its time discretisation
 * error, bounded here by 5e-3 E0 (measured max over the run 9.2e-4, courant 0.4). The box rebounds (P_z > 0) with
 * more than 70 % of its momentum (measured 0.84): an elastic bar would rebound whole; the box keeps part of the
 * energy in vibration and the bulk viscosity takes a little (measured in the log). */
static void test_elastic_rebound(void **state) {
  (void)state;
  loaded L;
  load(&L, "impact:\n"
           "  spacing: 0.05\n"
           "  domain: {lo: [-1, -1, 0], hi: [1, 1, 2]}\n"
           "  bodies:\n"
           "    - {shape: box, material: al, center: [0, 0, 0.2], size: [0.3, 0.3, 0.4],\n"
           "       yield: elastic_plastic, yield_stress: 10, velocity: [0, 0, -0.1]}\n"
           "  wall: {axis: z, position: 0}\n"
           "  t_end: 0.4\n"
           "  output: {energy_every: 1}\n");
  assert_non_null(L.p);
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = MS_LOG_INFO;
  assert_int_equal(dm_impact_problem_run(&ctx, L.p), MS_OK);
  ms_ctx_close(&ctx);
  const dm_impact_summary *s = dm_impact_get_summary(L.p);
  printf("rebound: %ld steps, balance %.3g, wall %.3g, transverse %.3g, normal %.4g, E_hg/E0 "
         "%.3g\n",
         s->steps, s->energy_err, s->wall_err, s->p_transverse, s->p_normal, s->hg_ratio);
  assert_true(s->energy_err < 1e-12);
  assert_true(s->p_transverse < 1e-12);
  assert_true(s->wall_err < 5e-3);
  assert_true(s->p_normal > 0.7 && s->p_normal <= 1.0);
  unload(&L);
}

/* A block of 6^3 particles deformed affinely (w = E X, E = diag(−0.2, 0.1, 0.05) plus a shear)
 * has the same F on every particle, boundary ones included (least squares is exact for affine
 * fields). The reference update then keeps ρ and p (V ← J V makes ρ = m/V the current density)
 * to round-off (1e-12 relative), rebuilds the families (F = I after it: the largest bond stretch
 * is 1) and keeps the forces zero in the interior. */
static void test_reference_update_affine(void **state) {
  (void)state;
  const int n1 = 6;
  const double h = 0.1;
  eos_t *eos = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  dm_state s;
  dm_state_alloc(&s, (size_t)(n1 * n1 * n1), 3);
  const double E[9] = {-0.2, 0.03, 0, 0, 0.1, 0, 0, 0, 0.05};
  for (int k = 0, i = 0; k < n1; ++k)
    for (int j = 0; j < n1; ++j)
      for (int l = 0; l < n1; ++l, ++i) {
        const double X[3] = {(l + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h};
        for (int a = 0; a < 3; ++a) {
          s.X[3 * i + a] = X[a];
          s.w[3 * i + a] = E[3 * a] * X[0] + E[3 * a + 1] * X[1] + E[3 * a + 2] * X[2];
        }
        s.mass[i] = 2.703 * h * h * h, s.vol[i] = h * h * h, s.K[i] = 77, s.G[i] = 27.6;
      }
  dm_model *m = NULL;
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = MS_LOG_ERROR;
  assert_int_equal(dm_model_create(&(dm_model_params){.state = &s,
                                                      .opt = {.horizon = 1.5 * h, .cond_max = 1e8},
                                                      .ctx = &ctx},
                                   &m),
                   MS_OK);
  dm_fin_material mat = {.eos = eos, .yield = DM_YIELD_ELASTIC_PLASTIC, .G = 27.6, .Y0 = 0.3};
  uint8_t *imat = calloc(s.n, 1);
  dm_fin *f = NULL;
  dm_fin_params par = {.cq = 2, .cl = 0.5, .courant = 0.4, .hourglass = 1, .ell = h};
  assert_int_equal(
      dm_fin_create(&(dm_fin_setup){.m = m, .mat = &mat, .imat = imat, .par = par}, &f), MS_OK);
  const double J0 = f->J[0];
  double *rho = calloc(s.n, sizeof(double)), *p = calloc(s.n, sizeof(double));
  for (size_t i = 0; i < s.n; ++i) {
    rho[i] = f->rho[i], p[i] = f->p[i];
    assert_true(fabs(f->J[i] - J0) < 1e-12); /* affine: the same F everywhere */
  }
  assert_true(dm_fin_max_stretch(f, NULL) > 1.1);
  dm_refamily_report rep;
  assert_int_equal(dm_fin_reference_update(f, &ctx, &rep), MS_OK);
  assert_true(fabs(rep.jmin - J0) < 1e-12 && fabs(rep.jmax - J0) < 1e-12);
  assert_true(rep.released < 1e-20); /* affine: no bond mismatch, nothing stored */
  assert_true(fabs(dm_fin_max_stretch(f, NULL) - 1.0) < 1e-14);
  for (size_t i = 0; i < s.n; ++i) {
    assert_true(fabs(f->rho[i] / rho[i] - 1) < 1e-12);
    assert_true(fabs(f->p[i] - p[i]) < 1e-12 * fabs(p[i]));
    assert_true(fabs(f->J[i] - 1) < 1e-12);
    assert_true(fabs(s.w[3 * i]) == 0.0);
  }
  /* an interior particle's force is zero for a uniform stress (every bond pair cancels) */
  const size_t mid = (size_t)((2 * n1 + 2) * n1 + 2);
  for (int a = 0; a < 3; ++a) assert_true(fabs(f->frc[3 * mid + a]) < 1e-12 * fabs(p[mid]) * h * h);
  m = f->m;
  dm_fin_destroy(&f);
  dm_model_destroy(&m);
  free(imat), free(rho), free(p);
  dm_state_free(&s);
  eos_destroy(&eos);
  ms_ctx_close(&ctx);
}

/* A particle moved far from its neighbours would have no family after an update: the update is
 * refused (MS_ERR_UNSTABLE), the particle named and the state (X, w, V) restored. */
static void test_reference_update_degenerate(void **state) {
  (void)state;
  const int n1 = 5;
  const double h = 0.1;
  eos_t *eos = eos_create_mg_linear(2.703, 5.35, 1.34, 2.0);
  dm_state s;
  dm_state_alloc(&s, (size_t)(n1 * n1 * n1), 3);
  for (int k = 0, i = 0; k < n1; ++k)
    for (int j = 0; j < n1; ++j)
      for (int l = 0; l < n1; ++l, ++i) {
        s.X[3 * i] = (l + 0.5) * h, s.X[3 * i + 1] = (j + 0.5) * h, s.X[3 * i + 2] = (k + 0.5) * h;
        s.mass[i] = 2.703 * h * h * h, s.vol[i] = h * h * h, s.K[i] = 77, s.G[i] = 27.6;
      }
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = MS_LOG_ERROR;
  dm_model *m = NULL;
  assert_int_equal(dm_model_create(&(dm_model_params){.state = &s,
                                                      .opt = {.horizon = 1.5 * h, .cond_max = 1e8},
                                                      .ctx = &ctx},
                                   &m),
                   MS_OK);
  dm_fin_material mat = {.eos = eos, .yield = DM_YIELD_NONE};
  uint8_t *imat = calloc(s.n, 1);
  dm_fin *f = NULL;
  dm_fin_params par = {.cq = 2, .cl = 0.5, .courant = 0.4, .hourglass = 1, .ell = h};
  assert_int_equal(
      dm_fin_create(&(dm_fin_setup){.m = m, .mat = &mat, .imat = imat, .par = par}, &f), MS_OK);
  const size_t far = 0; /* a corner particle, moved 10 spacings away along −x: J stays > 0 */
  s.w[3 * far] = -10 * h;
  assert_int_equal(dm_fin_refresh(f), MS_OK);
  size_t at = 99;
  assert_true(dm_fin_max_stretch(f, &at) > 5 && at == far);
  dm_refamily_report rep;
  assert_int_equal(dm_fin_reference_update(f, &ctx, &rep), MS_ERR_UNSTABLE);
  assert_int_equal(rep.bad, far);
  assert_true(f->m == m);               /* the old families stay */
  assert_true(s.w[3 * far] == -10 * h); /* and the old state */
  assert_true(s.X[3 * far] == 0.5 * h && s.vol[far] == h * h * h);
  dm_fin_destroy(&f);
  dm_model_destroy(&m);
  free(imat);
  dm_state_free(&s);
  eos_destroy(&eos);
  ms_ctx_close(&ctx);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_placement_errors),
      cmocka_unit_test(test_key_errors),
      cmocka_unit_test(test_scope_errors),
      cmocka_unit_test(test_contact_too_soft),
      cmocka_unit_test(test_contact_rebound),
      cmocka_unit_test(test_elastic_rebound),
      cmocka_unit_test(test_reference_update_affine),
      cmocka_unit_test(test_reference_update_degenerate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
