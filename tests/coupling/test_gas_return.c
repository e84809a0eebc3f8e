/* SPDX-License-Identifier: MIT */
/* Momentum and energy returned to the gas (docs/coupling.md §4): the continuum cell source
 * cont_grid_add_cell_source on its own, then lead fragments flying through an air column with
 * the transport handing −dp and −de of every CVODE step to the gas cell they are in. The
 * fragments, the gas and the walls together must conserve momentum and energy; without the
 * return they do not (the control case shows the test can fail).
 * Units: g, cm, 10 µs (air ρ = 1.2e-3 g/cm³, μ = 1.8e-9 g/(cm·10 µs); Pb 11.34 g/cm³). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
/* cmocka needs the headers above */
#include <cmocka.h>

#include "cont.h"
#include "cpl.h"
#include "cpl_test.h"

#define PI 3.14159265358979323846
static const double RHO_AIR = 1.2e-3, P_AIR = 1.01325e-4, MU_AIR = 1.8e-9, RHO_PB = 11.34;

/* An air column [0, L] between walls, n cells, at rest. */
static cont_grid *air_column(eos_t *air, double L, long n) {
  cont_layer_spec layer = {.name = "air",
                           .eos = air,
                           .thickness = L,
                           .rho = RHO_AIR,
                           .e = P_AIR / (0.4 * RHO_AIR),
                           .ncells = n};
  cont_setup s;
  cont_setup_defaults(&s);
  s.layers = &layer;
  s.nlayers = 1;
  s.left.kind = CONT_BC_WALL;
  s.right.kind = CONT_BC_WALL;
  char msg[256];
  cont_grid *g = NULL;
  cont_grid_create(&s, &g, msg, sizeof msg);
  assert_non_null(g);
  return g;
}

static void test_cell_source(void **state) {
  (void)state;
  eos_t *air = eos_create_ideal_gas(1.4, RHO_AIR);
  cont_grid *g = air_column(air, 1.0, 10);
  cont_balance b0 = cont_grid_balance(g);
  const double dp = 2e-5, de = 3e-5; /* per cm²: g·km/s and kJ */
  assert_int_equal(cont_grid_add_cell_source(g, 4, dp, de), MS_OK);
  cont_balance b1 = cont_grid_balance(g);
  cont_view v = cont_grid_view(g);
  /* both nodes of the cell move together; nothing else moves */
  assert_true(v.u[4] > 0 && v.u[4] == v.u[5]);
  for (size_t j = 0; j < v.nnodes; j++)
    if (j != 4 && j != 5) assert_true(v.u[j] == 0.0);
  /* the sums receive exactly dp and de (round-off of a few additions) */
  assert_double_equal(b1.momentum - b0.momentum, dp, 1e-15);
  assert_double_equal(b1.internal + b1.kinetic - b0.internal - b0.kinetic, de, 1e-15);
  assert_double_equal(b1.source_momentum, dp, 0);
  assert_double_equal(b1.source_energy, de, 0);
  assert_double_equal(b1.work - b0.work, de, 0);
  /* the heat went into the cell and its pressure follows the EOS: p = (γ − 1) ρ e */
  assert_double_equal(v.p[4], 0.4 * v.rho[4] * v.e[4], 1e-15 * v.p[4]);
  assert_true(v.e[4] > v.e[3]);
  /* more energy taken than the cell has: refused, grid unchanged */
  double e4 = v.e[4];
  assert_int_equal(cont_grid_add_cell_source(g, 4, 0.0, -1.0), MS_ERR_UNSTABLE);
  assert_true(cont_grid_view(g).e[4] == e4);
  assert_int_equal(cont_grid_add_cell_source(g, 10, 0.0, 0.0), MS_ERR_UNSTABLE);
  cont_grid_destroy(&g);
  eos_destroy(&air);
}

/* ---- fragments in an air column ---------------------------------------------------------- */

typedef struct column {
  cont_grid *g;
  double area; /* cross-section the fragments stand for, cm² */
  ms_status st;
} column;

static bool column_gas(void *user, const double x[3], double t, cpl_gas *out) {
  (void)t;
  const column *c = user;
  cont_sample s;
  if (!cont_grid_sample(c->g, x[0], &s)) return false;
  out->rho = s.rho;
  out->u[0] = s.u;
  out->u[1] = out->u[2] = 0;
  out->p = s.p;
  out->mu = MU_AIR;
  return true;
}

static void column_deposit(void *user, const double x[3], double t0, double t1, const double dp[3],
                           double de) {
  (void)t0;
  (void)t1;
  column *c = user;
  cont_sample s;
  if (c->st == MS_OK && cont_grid_sample(c->g, x[0], &s))
    c->st = cont_grid_add_cell_source(c->g, s.cell, -dp[0] / c->area, -de / c->area);
}

typedef struct totals {
  double p, e;             /* fragments + gas − what the walls delivered */
  double frag_p, gas_heat; /* fragments' momentum; gas internal energy (× area) */
} totals;

static totals sum_up(const column *c, const cpl_transport *tr) {
  cont_balance b = cont_grid_balance(c->g);
  totals t = {0, 0, 0, b.internal * c->area};
  /* the walls' share of work/impulse is what is not the source's */
  t.p = c->area * (b.momentum - (b.impulse - b.source_momentum));
  t.e = c->area * (b.internal + b.kinetic - (b.work - b.source_energy));
  for (size_t i = 0; i < cpl_transport_count(tr); i++) {
    cpl_flight f = cpl_transport_get(tr, i);
    const double *v = f.state == CPL_ARRIVED ? f.v_arrival : f.v;
    t.p += f.mass * v[0];
    t.frag_p += f.mass * v[0];
    t.e += 0.5 * f.mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  }
  return t;
}

enum { NFRAG = 5 };
static const double FRAG_D[NFRAG] = {2e-4, 5e-4, 1e-3, 2e-3, 3e-3}; /* cm */
static const double FRAG_V[NFRAG] = {2.0, 1.8, 1.5, 1.2, 1.0};      /* km/s */
static double frag_mass(int k) { return RHO_PB * PI * pow(FRAG_D[k], 3) / 6; }

/* Five Pb fragments of 2–30 µm at 1–2 km/s cross a 4 cm air column towards a detector at
 * 3.5 cm; they stand for a 0.01 cm × 0.01 cm cross-section, so together they carry about half
 * the column's mass per cm² and visibly push and heat the gas. */
static totals fly(bool with_return, totals *start) {
  eos_t *air = eos_create_ideal_gas(1.4, RHO_AIR);
  column c = {air_column(air, 4.0, 400), 1e-4, MS_OK};
  cpl_transport_opts o;
  cpl_transport_opts_default(&o);
  o.law = CPL_DRAG_SCHILLER_NAUMANN;
  o.rho_p = RHO_PB;
  o.det_x = 3.5;
  cpl_transport *tr = NULL;
  ms_must(cpl_transport_create(
              &(cpl_transport_params){.opts = &o, .gas = column_gas, .gas_user = &c}, &tr),
          "cpl_transport_create");
  if (with_return) cpl_transport_set_return(tr, column_deposit, &c);
  for (int k = 0; k < NFRAG; k++) {
    double x0[3] = {0.3 + 0.05 * k, 0, 0}, v0[3] = {FRAG_V[k], 0, 0};
    cpl_transport_add(tr, frag_mass(k), x0, v0, 0.0);
  }
  *start = sum_up(&c, tr);
  const int windows = 200;
  for (int w = 1; w <= windows; w++) {
    double tw = 5.0 * w / windows; /* 50 µs */
    assert_int_equal(cont_grid_run_to(c.g, tw), MS_OK);
    assert_int_equal(cpl_transport_advance(tr, tw), MS_OK);
    assert_int_equal(c.st, MS_OK);
  }
  totals end = sum_up(&c, tr);
  size_t arrived = 0;
  for (size_t i = 0; i < cpl_transport_count(tr); i++)
    arrived += cpl_transport_get(tr, i).state == CPL_ARRIVED;
  printf("%s return: %zu of %d arrived; fragment momentum %.6g -> %.6g g*km/s, total momentum "
         "%.12g -> %.12g, total energy %.12g -> %.12g kJ, gas heat +%.4g kJ\n",
         with_return ? "with" : "without", arrived, (int)NFRAG, start->frag_p, end.frag_p, start->p,
         end.p, start->e, end.e, end.gas_heat - start->gas_heat);
  assert_true(arrived >= 3); /* the flight is long enough for drag to matter, short enough to end */
  cpl_transport_destroy(&tr);
  cont_grid_destroy(&c.g);
  eos_destroy(&air);
  return end;
}

static void test_fragments_in_gas(void **state) {
  (void)state;
  totals t0, t1 = fly(true, &t0);
  /* What the fragments lost (measured 4.2 % of their momentum, mostly by the small ones: a real
   * exchange, not a no-op) ... */
  double lost_p = t0.frag_p - t1.frag_p;
  assert_true(lost_p > 0.02 * t0.frag_p);
  /* ... the gas and the walls received: every internal CVODE step's Δp and ΔE go to a cell, so
   * the sums agree to round-off. 1e-9 of the exchanged momentum/energy: the grid's own
   * conservation is at ~1e-14 relative per step of the column's total energy (~1e3 times the
   * fragments' kinetic energy) over ~10⁴ steps. */
  assert_double_equal(t1.p, t0.p, 1e-9 * lost_p);
  double frag_ke0 = 0;
  for (int k = 0; k < NFRAG; k++) frag_ke0 += 0.5 * frag_mass(k) * FRAG_V[k] * FRAG_V[k];
  printf("balance: momentum %.2e of the exchanged momentum, energy %.2e of the fragments' "
         "initial kinetic energy\n",
         (t1.p - t0.p) / lost_p, (t1.e - t0.e) / frag_ke0);
  assert_double_equal(t1.e, t0.e, 1e-9 * frag_ke0);
  /* drag dissipates: the gas got hotter (its internal energy rose by part of the energy lost) */
  assert_true(t1.gas_heat > t0.gas_heat);

  /* Control: without the return the fragments still lose momentum but the gas receives none,
   * so the same balance misses by what they lost. */
  totals c0, c1 = fly(false, &c0);
  assert_true(fabs(c1.p - c0.p) > 0.5 * (c0.frag_p - c1.frag_p));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cell_source),
      cmocka_unit_test(test_fragments_in_gas),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
