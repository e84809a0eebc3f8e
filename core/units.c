/* SPDX-License-Identifier: MIT */
/* Units (docs/design.md §2). Internal system g, cm, 10 µs; decks may be written in SI. */
#include "core.h"

/* SI value × factor = internal value. */
static const double si_to_internal[MS_DIM_COUNT] = {
    [MS_DIM_NONE] = 1.0,         [MS_DIM_LENGTH] = 1e2, /* m -> cm */
    [MS_DIM_TIME] = 1e5,                                /* s -> 10 µs */
    [MS_DIM_MASS] = 1e3,                                /* kg -> g */
    [MS_DIM_DENSITY] = 1e-3,                            /* kg/m³ -> g/cm³ */
    [MS_DIM_VELOCITY] = 1e-3,                           /* m/s -> km/s */
    [MS_DIM_PRESSURE] = 1e-9,                           /* Pa -> GPa */
    [MS_DIM_SPEC_ENERGY] = 1e-6,                        /* J/kg -> kJ/g = (km/s)² */
    [MS_DIM_ENERGY] = 1e-3,                             /* J -> g·cm²/(10 µs)² = 1 kJ */
    [MS_DIM_VISCOSITY] = 1e-4,                          /* Pa·s = 10 g/(cm·s) -> g/(cm·10 µs) */
    [MS_DIM_TEMPERATURE] = 1.0,                         /* K */
};

static const char *const internal_label[MS_DIM_COUNT] = {
    [MS_DIM_NONE] = "1",         [MS_DIM_LENGTH] = "cm",
    [MS_DIM_TIME] = "10us",      [MS_DIM_MASS] = "g",
    [MS_DIM_DENSITY] = "g/cm^3", [MS_DIM_VELOCITY] = "km/s",
    [MS_DIM_PRESSURE] = "GPa",   [MS_DIM_SPEC_ENERGY] = "kJ/g",
    [MS_DIM_ENERGY] = "kJ",      [MS_DIM_VISCOSITY] = "g/(cm*10us)",
    [MS_DIM_TEMPERATURE] = "K",
};

double ms_unit_to_internal(ms_unit_system sys, ms_dim dim) {
  if (sys == MS_UNITS_INTERNAL || dim < 0 || dim >= MS_DIM_COUNT) return 1.0;
  return si_to_internal[dim];
}

const char *ms_unit_label(ms_dim dim) {
  if (dim < 0 || dim >= MS_DIM_COUNT) return "?";
  return internal_label[dim];
}
