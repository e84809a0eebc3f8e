/* SPDX-License-Identifier: MIT */
/* eos_impl.h — private to eos/: the operations table behind eos_t and shared helpers.
 *
 * Every EOS kind fills an eos_ops table. The public functions in eos.c dispatch through it and
 * apply the common domain policy (docs/eos.md, "Domain and sound speed"):
 *   - pressure() returns NaN outside the EOS's domain (ρ ≤ 0, beyond a table, past the
 *     Us–up singularity, negative energy of an ideal gas);
 *   - sound_speed2() returns c² from c² = ∂P/∂ρ|_e + (P/ρ²) ∂P/∂e|_ρ (NaN outside the domain);
 *     eos_sound_speed floors it at (EOS_C_FLOOR_FRACTION · c0)² so the grid's time step stays
 *     finite in states below the cold curve;
 *   - cold_pressure()/cold_energy() return NaN outside the cold curve's range.
 */
#ifndef MSCALE_EOS_IMPL_H
#define MSCALE_EOS_IMPL_H

#include "eos.h"

#include <math.h>

/* c is never reported below this fraction of the reference sound speed (docs/eos.md). */
#define EOS_C_FLOOR_FRACTION 1.0e-3

typedef struct eos_ops {
  double (*pressure)(const eos_t *eos, double rho, double e);
  double (*sound_speed2)(const eos_t *eos, double rho, double e);
  double (*cold_pressure)(const eos_t *eos, double delta); /* NULL: no cold curve */
  double (*cold_energy)(const eos_t *eos, double delta);
  /* NULL: T = (e − ε_x(δ))/cv from the cold curve (eos_temperature) */
  double (*temperature)(const eos_t *eos, double rho, double e);
  void (*free_data)(eos_t *eos); /* NULL: nothing to free */
  /* Optional fused P and c² for eos_eval's loop (shares powers, table lookups); NULL: the two
   * calls above. Must give the same values as pressure() and sound_speed2(). */
  void (*eval)(const eos_t *eos, double rho, double e, double *p, double *c2);
  /* Optional array form of eval for the grid's hot loop (vectorizable, no calls per cell):
   * p[i] and, if c2 is not NULL, c2[i] for i < n, NaN outside the domain. Must give the same
   * values, bit for bit, as eval(). NULL: eos_eval loops over eval(). */
  void (*eval_array)(const eos_t *eos, size_t n, const double *rho, const double *e, double *p,
                     double *c2);
} eos_ops;

/* A cubic-Hermite tabulated curve y(x) with slopes y'(x) at the nodes; x strictly increasing.
 * Used for tabulated cold curves (ε_x(δ) with slopes P_x/(ρ0 δ²), so P_x = ρ0 δ² ε_x' holds
 * exactly: thermodynamic consistency by construction) and for isentropes integrated at set-up. */
typedef struct eos_hermite {
  size_t n;
  double *x, *y, *dy;
} eos_hermite;

/* Value, first and second derivative at x; returns false (and NaNs) outside [x0, x_{n-1}]. */
bool eos_hermite_eval(const eos_hermite *h, double x, double *y, double *dy, double *d2y);
void eos_hermite_free(eos_hermite *h);

/* Grüneisen factor G(ρ) = Γρ: constant Γ (G = Γρ) or Γρ = Γ0ρ0 (G constant). */
typedef struct eos_gruneisen {
  double gamma0, rho0;
  bool rho_gamma_const;
} eos_gruneisen;
static inline double eos_gruneisen_G(const eos_gruneisen *g, double rho) {
  return g->rho_gamma_const ? g->gamma0 * g->rho0 : g->gamma0 * rho;
}
static inline double eos_gruneisen_dG(const eos_gruneisen *g) {
  return g->rho_gamma_const ? 0.0 : g->gamma0;
}

/* Mie–Grüneisen around a cold curve (docs/design.md §3): P = P_x(δ) + G(ρ)(e − ε_x(δ)), and
 * c² = P_x'(δ)/ρ0 + (e − ε_x)(G' + G²/ρ²) (derivation in docs/eos.md). */
double eos_mg_pressure_from_cold(const eos_gruneisen *g, double rho, double e, double px,
                                 double ex);
double eos_mg_c2_from_cold(const eos_gruneisen *g, double rho0, double rho, double e, double dpx,
                           double ex);

struct eos {
  eos_kind kind;
  const eos_ops *ops;
  double rho0, c0, e0;
  double cv; /* specific heat kJ/(g·K) for eos_temperature; 0 = unknown */
  /* Cold curve range in δ (±inf if analytic everywhere; NaN if there is none). */
  double delta_min, delta_max;
  /* The isentrope through (ρ0, e = 0) used as the cold curve of EOSs that have no explicit one
   * (MG linear form, full tables); n == 0 if unused. */
  eos_hermite isentrope;
  void *data; /* kind-specific parameters, owned */
};

/* Allocate an eos with a copy of `data` (size bytes). */
eos_t *eos_alloc(eos_kind kind, const eos_ops *ops, double rho0, const void *data, size_t size);

/* Tabulate the isentrope through (ρ0, e = 0) on δ ∈ [dmin, dmax] (RK4, `nstep` steps each way
 * from δ = 1; stops early where the EOS leaves its domain) and make it the EOS's cold curve:
 * ε_x(δ) = isentrope energy, P_x(δ) = P(ρ0 δ, ε_x(δ)). */
ms_status eos_build_isentrope_cold(eos_t *eos, double dmin, double dmax, size_t nstep);
double eos_isentrope_cold_pressure(const eos_t *eos, double delta);
double eos_isentrope_cold_energy(const eos_t *eos, double delta);

/* ------------------------------------------------------------------------------------------ */
/* Plain numeric text tables with line numbers (eos/textfile.c).                               *
 * Format: '#' starts a comment; a comment of the form "# key: value" is metadata; the first    *
 * non-comment line may be a header of column names; values separated by blanks or commas;    *
 * every data row has the same number of columns.                                              */
typedef struct eos_text_table {
  size_t nrow, ncol;
  double *v; /* row-major [nrow][ncol] */
  int *line; /* file line of each row */
  char **meta_key, **meta_val;
  size_t nmeta;
  int last_line; /* number of lines in the file */
} eos_text_table;

ms_status eos_text_read(const char *path, size_t min_cols, size_t max_cols, eos_text_table *t,
                        dk_errors *e);
const char *eos_text_meta(const eos_text_table *t, const char *key);
void eos_text_free(eos_text_table *t);

/* Brent's method on [a, b] with f(a), f(b) of opposite sign; returns the root (NaN on failure). */
double eos_brent(double (*f)(double x, void *user), void *user, double a, double b, double fa,
                 double fb, double xtol, int maxit);

#endif /* MSCALE_EOS_IMPL_H */
