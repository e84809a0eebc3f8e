/* SPDX-License-Identifier: MIT */
/* eos.h — equations of state, materials, Hugoniots and mixtures (docs/design.md §3).
 *
 * Internal units (docs/design.md §2): ρ g/cm³, e kJ/g, P GPa, c km/s.
 * An EOS is an opaque object with a small table of operations (eos/eos_impl.h); the grid calls
 * the array form over whole material regions, the particles ask for the cold curve once at
 * set-up to tabulate their pair potentials.
 */
#ifndef MSCALE_EOS_H
#define MSCALE_EOS_H

#include "core.h"

typedef enum eos_kind {
  EOS_MG_COLD,       /* Mie–Grüneisen, cold-curve form: rho0, c0, n, gamma0 */
  EOS_MG_LINEAR,     /* Mie–Grüneisen, linear Us–up reference Hugoniot: rho0, c0, s, gamma0 */
  EOS_IDEAL_GAS,     /* gamma, reference (ambient) rho0 and p0 */
  EOS_TABLE_COLD,    /* tabulated cold curve (delta, rho, eps_x, P_x) + Grüneisen gamma */
  EOS_TABLE_FULL,    /* full table P(rho, e), c(rho, e) on a rectangular (rho, e) grid */
  EOS_LINEAR_ELASTIC /* small-strain elastic solid for the paper-000 tests: rho0, K (bulk modulus) */
} eos_kind;

typedef struct eos eos_t;

/* Constructors return NULL for impossible parameters (ρ0 ≤ 0, c0 ≤ 0, n ≤ 1, Γ0 < 0, s < 0,
 * γ ≤ 1, K ≤ 0; the deck reader reports these with their location first). Table readers record
 * every problem of the file in *e as FILE:LINE:COL and return NULL.
 * gamma_rho_const: if true, Γρ = Γ0ρ0 (Γ = Γ0 ρ0/ρ); otherwise Γ is constant. */
eos_t *eos_create_mg_cold(double rho0, double c0, double n, double gamma0, bool gamma_rho_const);
eos_t *eos_create_mg_linear(double rho0, double c0, double s, double gamma0);
/* Ideal gas P = (γ−1)ρe. rho0 is the reference (ambient) density; the reference pressure is
 * p0 (eos_create_ideal_gas: 1 atm = 1.01325e-4 GPa), so eos_c0 = sqrt(γ p0/ρ0). */
eos_t *eos_create_ideal_gas(double gamma, double rho0);
eos_t *eos_create_ideal_gas_ref(double gamma, double rho0, double p0);
/* Small-strain elastic solid (docs/eos.md): P = K(1 − ρ0/ρ), independent of e; its cold
 * energy ε_x = K(1 − 1/δ)²/(2ρ0) is the strain energy ½Kθ² per unit mass, θ = 1 − 1/δ. */
eos_t *eos_create_linear_elastic(double rho0, double bulk_modulus);
/* Tabulated cold curve from a file in the Table-1 format (docs/eos.md); gamma as for MG. */
eos_t *eos_create_table_cold(const char *path, double gamma0, bool gamma_rho_const, dk_errors *e);
/* Full (rho, e) table from text or HDF5 (by extension .h5 / .hdf5); format in docs/eos.md.
 * Bilinear interpolation of P and c²; NaN outside the table. */
eos_t *eos_create_table_full(const char *path, dk_errors *e);
/* Write a full table (EOS_TABLE_FULL) as text or HDF5 (by extension). */
ms_status eos_table_write(const eos_t *table, const char *path);
/* Build a full table by sampling another EOS on a uniform grid (exact nodal c² from the
 * source). NULL if a node is outside the source's domain or has c² ≤ 0 (docs/eos.md §6). */
eos_t *eos_create_table_from(const eos_t *src, double rho_min, double rho_max, size_t nrho,
                             double e_min, double e_max, size_t ne);
void eos_destroy(eos_t **eos); /* null-safe; sets *eos = NULL */

eos_kind eos_get_kind(const eos_t *eos);
const char *eos_kind_name(eos_kind k);
double eos_rho0(const eos_t *eos); /* reference density (g/cm³) */
double eos_c0(const eos_t *eos);   /* reference sound speed c(rho0, e0) (km/s) */
/* Reference specific internal energy e0 (kJ/g): 0 for condensed matter (the cold curve's zero),
 * p0/((γ−1)ρ0) for an ideal gas. The reference state (rho0, e0) is the default initial state of
 * Hugoniots and of mixture components. */
double eos_e0(const eos_t *eos);
bool eos_has_cold_curve(const eos_t *eos);
/* Range of δ where the cold curve is defined: the table's or tabulated isentrope's range, or
 * (0, INFINITY) for analytic curves (δ = 0 itself excluded). Returns false (and NaNs) if the
 * EOS has no cold curve. */
bool eos_cold_range(const eos_t *eos, double *delta_min, double *delta_max);

/* Single-state queries. */
double eos_pressure(const eos_t *eos, double rho, double e);
double eos_sound_speed(const eos_t *eos, double rho, double e);
/* Cold curve: P_x(δ) and ε_x(δ), δ = ρ/ρ0 (docs/design.md §3). NaN if the EOS has none. */
double eos_cold_pressure(const eos_t *eos, double delta);
double eos_cold_energy(const eos_t *eos, double delta);
/* Temperature (K) with a constant specific heat cv set by eos_set_heat_capacity (deck key
 * `cv`): T = (e − ε_x(δ))/cv above the 0 K cold curve, T = e/cv for an ideal gas. NaN if no cv
 * was given, outside the domain, or where the EOS has no cold curve. */
double eos_temperature(const eos_t *eos, double rho, double e);
ms_status eos_set_heat_capacity(eos_t *eos, double cv); /* kJ/(g·K), > 0 */

/* Array form for the grid's hot loop: p[i], c[i] (c may be NULL) for i < n; the same values as
 * eos_pressure/eos_sound_speed (c ≥ 1e-3 c0 where P is defined, docs/eos.md §7).
 * Returns MS_ERR_UNSTABLE at the first state outside the EOS's domain (its index in *bad). */
ms_status eos_eval(const eos_t *eos, size_t n, const double *rho, const double *e, double *p,
                   double *c, size_t *bad);

/* ------------------------------------------------------------------------------------------ */
/* Materials: the `materials:` list of a deck.                                                  */

typedef struct eos_material {
  char *name;
  eos_t *eos;
  /* Optional data used by other modules (0 if not given). */
  double shear_modulus; /* G, GPa (particle models, strength) */
  double viscosity;     /* dynamic viscosity μ, g/(cm·10µs) (gas drag on ejecta) */
  int line, col;        /* where the entry starts in the deck */
} eos_material;

/* A deck-defined mixture (top-level `mixtures:`) for the Kuropatenko rule. */
typedef struct eos_mixture {
  char *name;
  size_t ncomp;
  size_t *comp;  /* indices into eos_materials.m */
  double *alpha; /* volume fractions, sum 1 */
} eos_mixture;

typedef struct eos_materials {
  size_t n;
  eos_material *m;
  size_t nmix;
  eos_mixture *mix;
  /* Names of entries that had errors (left out of m[]); eos_materials_find does not report
   * them again as unknown. */
  size_t nbroken;
  char **broken;
} eos_materials;

/* Read `materials:` (and the optional `mixtures:`) from the deck root; every problem goes to *e.
 * Keys the reader does not know inside these sections are reported here (with the list of
 * accepted keys) and marked used, so dk_report_unused does not repeat them. Returns NULL only
 * if the section is absent or not a list (error recorded); otherwise entries with errors are
 * left out (e->n tells whether anything went wrong). */
eos_materials *eos_materials_read(dk_doc *doc, dk_errors *e);
/* Look a material up by name; records "unknown material 'x' (known: a, b)" at `where`. */
const eos_material *eos_materials_find(const eos_materials *mats, const char *name, dk_errors *e,
                                       const dk_doc *doc, const dk_node *where);
const eos_mixture *eos_mixtures_find(const eos_materials *mats, const char *name);
void eos_materials_destroy(eos_materials **mats); /* null-safe; sets *mats = NULL */

/* ------------------------------------------------------------------------------------------ */
/* Hugoniot (Rankine–Hugoniot jump conditions from an initial state rho0, e0, p0).             */

typedef struct eos_hugoniot_point {
  double up, us, p, rho, e;
} eos_hugoniot_point;

/* Solve the jump conditions for each particle velocity up[i] > 0 (KINSOL, safeguarded by a
 * bracketing fallback; docs/eos.md §8). Points without a solution inside the EOS's domain get
 * NaN in out[i] (except up) and the call returns MS_ERR_SOLVER; MS_ERR_INPUT if (rho0, e0) is
 * outside the domain. */
ms_status eos_hugoniot(const eos_t *eos, double rho0, double e0, size_t n, const double *up,
                       eos_hugoniot_point *out);
/* The Hugoniot state at a given shock pressure p > P0 (bracketing + Brent). */
ms_status eos_hugoniot_at_pressure(const eos_t *eos, double rho0, double e0, double p,
                                   eos_hugoniot_point *out);

/* Kuropatenko mixture rule ([Davydov] §1.2, docs/eos.md §9): 1/(D − u) = Σ α_i/(D_i − u_i),
 * with equal pressure in every component. Given the mixture particle velocity u (the
 * components' u_i follow from pressure equilibrium), returns D and p. alpha = volume
 * fractions (sum 1); MS_ERR_INPUT if they are not. */
ms_status eos_kuropatenko(size_t ncomp, const eos_t *const *comp, const double *alpha, double u,
                          double *D, double *p);
/* The same at a given pressure: each component's Hugoniot at p (from its reference state
 * ρ0_i = eos_rho0, e0_i = eos_e0) gives D_i − u_i; D − u = 1/Σ α_i/(D_i − u_i) and
 * p − P0 = ρ0 D u with ρ0 = Σ α_i ρ0_i, P0 = Σ α_i P0_i.
 * Fills the mixture state (up = u, us = D, p, rho = ρ0 D/(D − u), e − e0 from the energy jump). */
ms_status eos_kuropatenko_at_pressure(size_t ncomp, const eos_t *const *comp, const double *alpha,
                                      double p, eos_hugoniot_point *out);
/* Mixture Hugoniot for a list of u (wraps eos_kuropatenko). */
ms_status eos_kuropatenko_hugoniot(size_t ncomp, const eos_t *const *comp, const double *alpha,
                                   size_t n, const double *up, eos_hugoniot_point *out);

#endif /* MSCALE_EOS_H */
