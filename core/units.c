/* SPDX-License-Identifier: MIT */
/* Units (docs/design.md §2). Internal system g, cm, 10 µs; decks may be written in SI. */
#include "core.h"

#include <string.h>

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

/* Output units (docs/output.md, "Units"): times are written in µs, not in the internal 10 µs,
 * so that a reader needs no conversion. Each internal unit that holds the time is spelt here
 * with its output spelling and the factor from internal to output values. */
static const struct {
  const char *internal, *output;
  double factor;
} time_bearing[] = {
    {"10us", "us", 10.0},
    {"10 us", "us", 10.0},
    {"GPa*10us", "GPa*us", 10.0},
};

const char *ms_out_unit(const char *internal, double *factor) {
  for (size_t i = 0; i < sizeof time_bearing / sizeof time_bearing[0]; i++)
    if (!strcmp(internal, time_bearing[i].internal)) {
      if (factor) *factor = time_bearing[i].factor;
      return time_bearing[i].output;
    }
  if (factor) *factor = 1.0;
  return internal;
}

double ms_out_unit_factor(const char *output) {
  for (size_t i = 0; i < sizeof time_bearing / sizeof time_bearing[0]; i++)
    if (!strcmp(output, time_bearing[i].output)) return time_bearing[i].factor;
  return 1.0;
}

double ms_out_time(double t) { return 10.0 * t; }

const char *ms_out_time_label(void) { return "us"; }
