/* SPDX-License-Identifier: MIT */
/* dm_strength.c — the Steinberg–Guinan strength model for the finite-deformation discrete model
 * (docs/particles-dm.md, "Strength: Steinberg–Guinan"; [SCG1980] for the model, [Steinberg1996]
 * for the parameter sets): shear modulus and yield stress of a particle from its density,
 * pressure, temperature and plastic strain, and zero above the melt curve. dm_finite.c evaluates
 * them per particle in every stress pass; nothing here allocates.
 */
#include "dm_impl.h"

#include <math.h>
#include <string.h>

/* Built-in sets: Steinberg's compilation [Steinberg1996] as transcribed in the Uintah MPM
 * material files (docs/references.md); A = G'_P/G0 in Mbar⁻¹ and B = −G'_T/G0 in K⁻¹ as that
 * table gives them, c_v in J/(kg·K). G'_P = A G0 / 100 GPa, G'_T = −B G0. */
typedef struct sg_row {
  const char *name;
  double G0, A, B, Y0, Ymax, beta, n, Tm0, gamma0, a, cv;
} sg_row;
static const sg_row sg_table[] = {
    {"Al6061_T6", 27.6, 6.52, 6.16e-4, 0.29, 0.68, 125.0, 0.10, 1220.0, 1.97, 1.5, 885.0},
    {"Cu_OFHC", 47.7, 2.83, 3.77e-4, 0.12, 0.64, 36.0, 0.45, 1790.0, 2.02, 1.5, 383.0},
    {"Pb", 8.6, 11.63, 1.16e-3, 0.008, 0.10, 110.0, 0.52, 760.0, 2.74, 2.20, 124.0},
    {"Sn", 17.9, 8.66, 2.12e-3, 0.16, 0.22, 2000.0, 0.06, 656.6, 2.27, 1.7, 220.0},
};
enum { SG_NSETS = sizeof sg_table / sizeof sg_table[0] };

bool dm_sg_set(const char *name, dm_sg *out) {
  for (int k = 0; name && k < SG_NSETS; ++k) {
    const sg_row *r = &sg_table[k];
    if (strcmp(name, r->name)) continue;
    *out = (dm_sg){.G0 = r->G0,
                   .dGdP = r->A * r->G0 / 100.0, /* Mbar⁻¹ → GPa⁻¹ */
                   .dGdT = -r->B * r->G0,
                   .Y0 = r->Y0,
                   .Ymax = r->Ymax,
                   .beta = r->beta,
                   .n = r->n,
                   .eps_i = 0.0,
                   .Tm0 = r->Tm0,
                   .gamma0 = r->gamma0,
                   .a = r->a,
                   .cv = r->cv * 1e-6, /* J/(kg·K) → kJ/(g·K) */
                   .T0 = 300.0};
    return true;
  }
  return false;
}

const char *dm_sg_set_names(void) { return "Al6061_T6, Cu_OFHC, Pb, Sn"; }

/* [SCG1980] eq. (5): the Lindemann law with Γ = Γ0 − a(1 − 1/η) integrated */
double dm_sg_melt_temperature(const dm_sg *sg, double eta) {
  return sg->Tm0 * exp(2.0 * sg->a * (1.0 - 1.0 / eta)) *
         pow(eta, 2.0 * (sg->gamma0 - sg->a - 1.0 / 3.0));
}

double dm_sg_temperature(const dm_sg *sg, const eos_t *eos, double rho, double e) {
  const double ex = eos_cold_energy(eos, rho / eos_rho0(eos));
  return sg->T0 + (e - ex) / sg->cv;
}

/* [SCG1980] eqs. (1)–(2): Y'_P/Y0 = G'_P/G0 and Y'_T/Y0 = G'_T/G0, i.e. Y = Y0 f(ε_p) G/G0 */
void dm_sg_moduli(const dm_sg *sg, double eta, double p, double T, double eps_p, double *G,
                  double *Y) {
  if (!(T < dm_sg_melt_temperature(sg, eta))) { /* molten (or NaN): no strength */
    *G = 0.0, *Y = 0.0;
    return;
  }
  const double g = sg->G0 + sg->dGdP * p / cbrt(eta) + sg->dGdT * (T - sg->T0);
  *G = g > 0 ? g : 0.0;
  const double f = sg->Y0 * pow(1.0 + sg->beta * (eps_p + sg->eps_i), sg->n);
  *Y = (f < sg->Ymax ? f : sg->Ymax) * *G / sg->G0;
}

/* ---- Johnson–Cook [JohnsonCook1983] ---- */

/* OFHC copper of [JohnsonCook1983]: A 90 MPa, B 292 MPa, n 0.31, C 0.025, m 1.09, T_melt 1356 K. G0 and c_v
 * (for T(ρ, e)) are not JC constants: G0 47.7 GPa and c_v 383 J/(kg·K) of the Cu_OFHC set of
 * [Steinberg1996] above; T_room = 300 K, the temperature route's reference (T* = 0 at (ρ0, e0)). */
bool dm_jc_set(const char *name, dm_sg *out) {
  if (!name || strcmp(name, "Cu_OFHC_JC")) return false;
  *out = (dm_sg){.G0 = 47.7,
                 .jA = 0.090,
                 .jB = 0.292,
                 .jn = 0.31,
                 .jC = 0.025,
                 .jm = 1.09,
                 .Tm0 = 1356.0,
                 .cv = 383.0 * 1e-6,
                 .T0 = 300.0};
  return true;
}

/* ε̇0 = 1/s in the code's time unit (10 µs, core/units.c): 1e-5 per unit */
#define JC_RATE0 1e-5

double dm_jc_yield(const dm_sg *sg, double eps_p, double rate, double T) {
  if (!(T == T)) return 0.0; /* unknown T: no strength (as steinberg_guinan) */
  double ts = (T - sg->T0) / (sg->Tm0 - sg->T0);
  ts = ts < 0 ? 0 : ts > 1 ? 1 : ts;
  const double r = rate / JC_RATE0 > 1.0 ? rate / JC_RATE0 : 1.0;
  const double h = sg->jA + sg->jB * (eps_p > 0 ? pow(eps_p, sg->jn) : 0.0);
  const double y = h * (1.0 + sg->jC * log(r)) * (1.0 - pow(ts, sg->jm));
  return y > 0 ? y : 0.0;
}

/* ---- deck ---- */

static void rd(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim, bool req,
               double lo, double *v) {
  if (map) dk_read_double(e, doc, map, key, dim, req, *v, lo, INFINITY, v);
}

static void rd_pos(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                   bool req, double *v) {
  if (map) dk_read_positive(e, doc, map, key, dim, req, *v, v);
}

static void cold_curve_check(dk_errors *e, dk_doc *doc, const dk_node *layer, const eos_t *eos,
                             const dm_sg *out, const char *model) {
  if (eos && out->cv > 0 && !isfinite(dm_sg_temperature(out, eos, eos_rho0(eos), eos_e0(eos))))
    dk_error(e, doc, layer,
             "discrete_model.layers: yield: %s takes the temperature from the EOS's cold curve, "
             "and this EOS (%s) has none",
             model, eos_kind_name(eos_get_kind(eos)));
}

/* yield: johnson_cook: `strength_set: Cu_OFHC_JC` and/or `johnson_cook: {A, B, n, C, m, T_melt,
 * T_room, shear_modulus, cv}` (keys override the set; all but T_room required without it). */
static void jc_read(dk_errors *e, dk_doc *doc, const dk_node *layer, const eos_t *eos, dm_sg *out) {
  const dk_node *set = dk_get(layer, "strength_set"), *map = dk_get(layer, "johnson_cook");
  if (dk_get(layer, "strength")) {
    dk_error(e, doc, dk_get(layer, "strength"),
             "discrete_model.layers: with yield: johnson_cook give the constants as "
             "'johnson_cook: {...}'");
    dk_mark_used(layer, "strength");
  }
  bool have = false;
  out->T0 = 300.0;
  if (set) {
    const char *nm = dk_scalar(set);
    if (!dm_jc_set(nm, out))
      dk_error(e, doc, set,
               "discrete_model.layers: unknown johnson_cook strength_set '%s' (known: Cu_OFHC_JC)",
               nm ? nm : "(not a name)");
    have = true;
  }
  if (map && !dk_expect_map(e, doc, map, "discrete_model.layers.johnson_cook")) {
    dk_mark_used(layer, "johnson_cook");
    return;
  }
  if (!have && !map) {
    dk_error(e, doc, layer,
             "discrete_model.layers: yield: johnson_cook needs 'strength_set: Cu_OFHC_JC' or "
             "'johnson_cook: {A, B, n, C, m, T_melt, T_room, shear_modulus, cv}'");
    return;
  }
  const bool req = !have;
  rd_pos(e, doc, map, "A", MS_DIM_PRESSURE, req, &out->jA);
  rd(e, doc, map, "B", MS_DIM_PRESSURE, req, 0.0, &out->jB);
  rd(e, doc, map, "n", MS_DIM_NONE, req, 0.0, &out->jn);
  rd(e, doc, map, "C", MS_DIM_NONE, req, 0.0, &out->jC);
  rd_pos(e, doc, map, "m", MS_DIM_NONE, req, &out->jm);
  rd_pos(e, doc, map, "T_melt", MS_DIM_TEMPERATURE, req, &out->Tm0);
  rd_pos(e, doc, map, "T_room", MS_DIM_TEMPERATURE, false, &out->T0);
  rd_pos(e, doc, map, "shear_modulus", MS_DIM_PRESSURE, req, &out->G0);
  rd_pos(e, doc, map, "cv", MS_DIM_SPEC_ENERGY, req, &out->cv); /* kJ/(g·K) */
  if (out->T0 > 0 && out->Tm0 > 0 && !(out->T0 < out->Tm0))
    dk_error(e, doc, map ? map : layer,
             "discrete_model.layers: johnson_cook: T_room = %g K is not below T_melt = %g K",
             out->T0, out->Tm0);
  cold_curve_check(e, doc, layer, eos, out, "johnson_cook");
}

void dm_sg_read(dk_errors *e, dk_doc *doc, const dk_node *layer, int yield, const eos_t *eos,
                dm_sg *out) {
  const dk_node *set = dk_get(layer, "strength_set"), *map = dk_get(layer, "strength");
  memset(out, 0, sizeof *out);
  if (yield == DM_YIELD_JOHNSON_COOK) {
    jc_read(e, doc, layer, eos, out);
    return;
  }
  if (dk_get(layer, "johnson_cook")) {
    dk_error(e, doc, dk_get(layer, "johnson_cook"),
             "discrete_model.layers: 'johnson_cook' needs yield: johnson_cook");
    dk_mark_used(layer, "johnson_cook");
  }
  if (yield != DM_YIELD_STEINBERG_GUINAN) {
    if (set)
      dk_error(e, doc, set,
               "discrete_model.layers: 'strength_set' needs yield: "
               "steinberg_guinan");
    if (map)
      dk_error(e, doc, map,
               "discrete_model.layers: 'strength' needs yield: "
               "steinberg_guinan");
    if (map) dk_mark_used(layer, "strength");
    return;
  }
  bool have = false;
  out->T0 = 300.0;
  if (set) {
    const char *nm = dk_scalar(set);
    if (!dm_sg_set(nm, out))
      dk_error(e, doc, set, "discrete_model.layers: unknown strength_set '%s' (known: %s)",
               nm ? nm : "(not a name)", dm_sg_set_names());
    have = true; /* reported; do not also report every key of `strength` as missing */
  }
  if (map && !dk_expect_map(e, doc, map, "discrete_model.layers.strength")) {
    dk_mark_used(layer, "strength");
    return;
  }
  if (!have && !map) {
    dk_error(e, doc, layer,
             "discrete_model.layers: yield: steinberg_guinan needs 'strength_set: NAME' (known: "
             "%s) or 'strength: {shear_modulus, dG_dP, dG_dT, yield_stress, yield_max, beta, n, "
             "melt_temperature, gamma0, a, cv}'",
             dm_sg_set_names());
    return;
  }
  const bool req = !have; /* keys of `strength` override the set's values */
  rd_pos(e, doc, map, "shear_modulus", MS_DIM_PRESSURE, req, &out->G0);
  rd(e, doc, map, "dG_dP", MS_DIM_NONE, req, -INFINITY, &out->dGdP);
  rd(e, doc, map, "dG_dT", MS_DIM_PRESSURE, req, -INFINITY, &out->dGdT); /* GPa/K */
  rd_pos(e, doc, map, "yield_stress", MS_DIM_PRESSURE, req, &out->Y0);
  rd_pos(e, doc, map, "yield_max", MS_DIM_PRESSURE, req, &out->Ymax);
  rd(e, doc, map, "beta", MS_DIM_NONE, req, 0.0, &out->beta);
  rd(e, doc, map, "n", MS_DIM_NONE, req, 0.0, &out->n);
  rd(e, doc, map, "eps_i", MS_DIM_NONE, false, 0.0, &out->eps_i);
  rd_pos(e, doc, map, "melt_temperature", MS_DIM_TEMPERATURE, req, &out->Tm0);
  rd(e, doc, map, "gamma0", MS_DIM_NONE, req, 0.0, &out->gamma0);
  rd(e, doc, map, "a", MS_DIM_NONE, req, 0.0, &out->a);
  rd_pos(e, doc, map, "cv", MS_DIM_SPEC_ENERGY, req, &out->cv); /* kJ/(g·K) */
  rd_pos(e, doc, map, "T0", MS_DIM_TEMPERATURE, false, &out->T0);
  if (out->Ymax > 0 && out->Y0 > 0 && out->Ymax < out->Y0)
    dk_error(e, doc, map ? map : layer,
             "discrete_model.layers: steinberg_guinan: yield_max (%g GPa) below yield_stress "
             "(%g GPa)",
             out->Ymax, out->Y0);
  if (out->G0 > 0 && out->T0 > 0 && out->Tm0 > 0 && !(out->T0 < out->Tm0))
    dk_error(e, doc, map ? map : layer,
             "discrete_model.layers: steinberg_guinan: T0 = %g K is not below the melt "
             "temperature %g K: no strength at the reference state",
             out->T0, out->Tm0);
  cold_curve_check(e, doc, layer, eos, out, "steinberg_guinan");
}
