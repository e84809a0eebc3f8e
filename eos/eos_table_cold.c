/* SPDX-License-Identifier: MIT */
/* eos_table_cold.c — tabulated cold curve in the format of Table 1 of [Davydov] (docs/eos.md):
 * columns delta, rho [g/cm³], eps_x [kJ/g], P_x [GPa]; Mie–Grüneisen thermal part around it.
 *
 * Interpolation: ε_x(δ) is the cubic Hermite interpolant of the tabulated ε_x with nodal slopes
 * dε_x/dδ = P_x/(ρ0 δ²) (the definition ε_x = ∫ P_x/(ρ0 δ²) dδ, docs/design.md §3), and
 * P_x(δ) = ρ0 δ² ε_x'(δ). Both columns are reproduced exactly at the nodes and the pair is
 * thermodynamically consistent everywhere, so cluster forces f = −dE/dr are exact derivatives
 * of the potentials. The reader checks that the interpolated P_x is monotone. */
#include "eos_impl.h"

#include <stdlib.h>
#include <string.h>

typedef struct table_cold {
  eos_hermite eps; /* ε_x(δ) */
  eos_gruneisen g;
} table_cold;

static double tc_cold_energy(const eos_t *eos, double delta) {
  const table_cold *t = eos->data;
  double y;
  eos_hermite_eval(&t->eps, delta, &y, NULL, NULL);
  return y;
}

static double tc_cold_pressure(const eos_t *eos, double delta) {
  const table_cold *t = eos->data;
  double dy;
  if (!eos_hermite_eval(&t->eps, delta, NULL, &dy, NULL)) return NAN;
  return eos->rho0 * delta * delta * dy;
}

static double tc_pressure(const eos_t *eos, double rho, double e) {
  const table_cold *t = eos->data;
  double delta = rho / eos->rho0, y, dy;
  if (!eos_hermite_eval(&t->eps, delta, &y, &dy, NULL)) return NAN;
  return eos_mg_pressure_from_cold(&t->g, rho, e, eos->rho0 * delta * delta * dy, y);
}

static double tc_c2(const eos_t *eos, double rho, double e) {
  const table_cold *t = eos->data;
  double delta = rho / eos->rho0, y, dy, d2y;
  if (!eos_hermite_eval(&t->eps, delta, &y, &dy, &d2y)) return NAN;
  double dpx = eos->rho0 * (2.0 * delta * dy + delta * delta * d2y); /* dP_x/dδ */
  return eos_mg_c2_from_cold(&t->g, eos->rho0, rho, e, dpx, y);
}

static void tc_eval(const eos_t *eos, double rho, double e, double *p, double *c2) {
  const table_cold *t = eos->data;
  double delta = rho / eos->rho0, y, dy, d2y;
  if (!eos_hermite_eval(&t->eps, delta, &y, &dy, &d2y)) {
    *p = *c2 = NAN;
    return;
  }
  *p = eos_mg_pressure_from_cold(&t->g, rho, e, eos->rho0 * delta * delta * dy, y);
  double dpx = eos->rho0 * (2.0 * delta * dy + delta * delta * d2y);
  *c2 = eos_mg_c2_from_cold(&t->g, eos->rho0, rho, e, dpx, y);
}

static void tc_free(eos_t *eos) {
  table_cold *t = eos->data;
  if (t) eos_hermite_free(&t->eps);
}

static const eos_ops table_cold_ops = {tc_pressure, tc_c2,   tc_cold_pressure, tc_cold_energy,
                                       NULL,        tc_free, tc_eval,          NULL};

/* Relative mismatch allowed between the delta column and rho/rho0: Table 1 prints δ with
 * three decimals (rounding error ≤ 5e-4 at δ ≥ 0.455, i.e. ≤ 1.1e-3 relative). */
#define DELTA_REL_TOL 2e-3

eos_t *eos_create_table_cold(const char *path, double gamma0, bool gamma_rho_const, dk_errors *e) {
  size_t nerr0 = e->n;
  if (!(gamma0 >= 0.0)) {
    dk_error_at(e, path, 0, 0, "Grüneisen coefficient must be >= 0 (found %g)", gamma0);
    return NULL;
  }
  eos_text_table tt;
  if (eos_text_read(path, 4, 4, &tt, e) != MS_OK) return NULL;
  size_t n = tt.nrow;
  const double *v = tt.v;
#define D(i)   v[4 * (i) + 0]
#define RHO(i) v[4 * (i) + 1]
#define EPS(i) v[4 * (i) + 2]
#define PX(i)  v[4 * (i) + 3]
  if (n < 3) {
    dk_error_at(e, path, tt.last_line, 0, "a cold-curve table needs at least 3 rows (found %zu)",
                n);
    eos_text_free(&tt);
    return NULL;
  }
  for (size_t i = 0; i < n; ++i) {
    if (!(D(i) > 0.0)) dk_error_at(e, path, tt.line[i], 1, "delta must be > 0 (found %g)", D(i));
    if (!(RHO(i) > 0.0)) dk_error_at(e, path, tt.line[i], 1, "rho must be > 0 (found %g)", RHO(i));
  }
  /* Order: strictly monotone in delta, either direction (Table 1 lists δ decreasing). */
  bool increasing = D(1) > D(0);
  for (size_t i = 1; i < n; ++i) {
    bool ok = increasing ? D(i) > D(i - 1) : D(i) < D(i - 1);
    if (!ok)
      dk_error_at(e, path, tt.line[i], 1,
                  "delta column is not strictly monotone: %g follows %g (line %d); rows must be "
                  "sorted by delta",
                  D(i), D(i - 1), tt.line[i - 1]);
  }
  /* Reference row δ = 1 gives ρ0 (or the "# rho0:" metadata). */
  size_t iref = n;
  for (size_t i = 0; i < n; ++i)
    if (D(i) == 1.0) iref = i;
  double rho0 = NAN;
  const char *meta = eos_text_meta(&tt, "rho0");
  if (meta) {
    char *end;
    rho0 = strtod(meta, &end);
    if (end == meta || !(rho0 > 0.0)) {
      dk_error_at(e, path, 0, 0, "metadata 'rho0: %s' is not a positive number", meta);
      rho0 = NAN;
    }
  }
  if (iref == n) {
    dk_error_at(e, path, tt.last_line, 0,
                "the table has no reference row with delta = 1 (where eps_x = 0)");
  } else {
    if (isnan(rho0)) rho0 = RHO(iref);
    double escale = 0.0;
    for (size_t i = 0; i < n; ++i) escale = fmax(escale, fabs(EPS(i)));
    if (fabs(EPS(iref)) > 1e-12 * escale)
      dk_error_at(e, path, tt.line[iref], 1, "eps_x must be 0 at delta = 1 (found %g)", EPS(iref));
  }
  if (e->n == nerr0) {
    for (size_t i = 0; i < n; ++i) {
      double dr = RHO(i) / rho0;
      if (fabs(dr / D(i) - 1.0) > DELTA_REL_TOL)
        dk_error_at(e, path, tt.line[i], 1,
                    "rho/rho0 = %.6g does not match delta = %g (rho0 = %g g/cm^3)", dr, D(i), rho0);
    }
  }
  /* P_x must increase with compression (∂P_x/∂δ > 0: a real cold sound speed). */
  for (size_t i = 1; i < n && e->n == nerr0; ++i) {
    bool ok = (D(i) > D(i - 1)) == (PX(i) > PX(i - 1));
    if (!ok)
      dk_error_at(e, path, tt.line[i], 1,
                  "P_x is not monotone in delta: P_x = %g at delta = %g (line %d) but %g at delta "
                  "= %g",
                  PX(i - 1), D(i - 1), tt.line[i - 1], PX(i), D(i));
  }
  if (e->n != nerr0) {
    eos_text_free(&tt);
    return NULL;
  }
  /* Nodes in increasing δ, using ρ/ρ0 (more digits than the printed δ). */
  table_cold tc = {{0}, {gamma0, rho0, gamma_rho_const}};
  eos_hermite *h = &tc.eps;
  h->n = n;
  h->x = ms_calloc(n, sizeof *h->x);
  h->y = ms_calloc(n, sizeof *h->y);
  h->dy = ms_calloc(n, sizeof *h->dy);
  int *line = ms_calloc(n, sizeof *line);
  for (size_t k = 0; k < n; ++k) {
    size_t i = increasing ? k : n - 1 - k;
    double delta = RHO(i) / rho0;
    h->x[k] = delta;
    h->y[k] = EPS(i);
    h->dy[k] = PX(i) / (rho0 * delta * delta);
    line[k] = tt.line[i];
  }
  /* Monotonicity of the interpolated P_x (inconsistent ε_x and P_x columns would overshoot). */
  for (size_t k = 0; k + 1 < n && e->n == nerr0; ++k) {
    double prev = PX(increasing ? k : n - 1 - k);
    for (int j = 1; j <= 64; ++j) {
      double x = h->x[k] + (h->x[k + 1] - h->x[k]) * j / 64.0, dy;
      eos_hermite_eval(h, x, NULL, &dy, NULL);
      double p = rho0 * x * x * dy;
      if (!(p > prev)) {
        dk_error_at(e, path, line[k + 1], 1,
                    "eps_x and P_x are inconsistent between lines %d and %d: the interpolated "
                    "P_x (cubic Hermite in eps_x with slopes P_x/(rho0 delta^2)) is not monotone "
                    "near delta = %.4g",
                    line[k], line[k + 1], x);
        break;
      }
      prev = p;
    }
  }
  free(line);
  eos_text_free(&tt);
#undef D
#undef RHO
#undef EPS
#undef PX
  if (e->n != nerr0) {
    eos_hermite_free(h);
    return NULL;
  }
  eos_t *eos = eos_alloc(EOS_TABLE_COLD, &table_cold_ops, rho0, &tc, sizeof tc);
  eos->delta_min = h->x[0];
  eos->delta_max = h->x[n - 1];
  eos->c0 = sqrt(tc_c2(eos, rho0, 0.0));
  return eos;
}
