/* SPDX-License-Identifier: MIT */
/* libFuzzer harness: the EOS table readers on text files — eos_create_table_cold (Table-1
 * format) and eos_create_table_full (text (rho, e) grid), docs/eos.md. Byte 0 chooses the
 * reader and the Grüneisen options, the rest is the file. A table that is accepted is then
 * queried inside, at the edges of and outside its range. Oracles: no sanitizer report; a
 * rejected table has errors naming the file; an accepted one has none and answers the cold
 * curve with a finite value at δ = 1 and a finite reference sound speed. */
#include "eos.h"
#include "fuzz_util.h"

#include <math.h>

static void query(const eos_t *eos, const uint8_t *data, size_t size) {
  double rho0 = eos_rho0(eos);
  if (!(rho0 > 0) || !isfinite(rho0)) abort();
  double probes[] = {0.0, 0.5, 0.999, 1.0, 1.001, 2.0, 1e3, -1.0, NAN, INFINITY};
  for (size_t i = 0; i < sizeof probes / sizeof *probes; i++) {
    double rho = rho0 * probes[i], e = probes[(i + 3) % 10] * (size ? data[size - 1] : 1);
    (void)eos_pressure(eos, rho, e);
    (void)eos_sound_speed(eos, rho, e);
    (void)eos_temperature(eos, rho, e);
    if (eos_has_cold_curve(eos)) {
      (void)eos_cold_pressure(eos, probes[i]);
      (void)eos_cold_energy(eos, probes[i]);
    }
  }
  double lo, hi;
  if (eos_cold_range(eos, &lo, &hi) && lo <= 1 && hi >= 1) {
    if (!isfinite(eos_cold_pressure(eos, 1.0)) || !isfinite(eos_cold_energy(eos, 1.0))) {
      fprintf(stderr, "fuzz oracle: accepted cold curve is not finite at delta = 1\n");
      abort();
    }
  }
  double rho[4] = {rho0, 0.9 * rho0, 1.1 * rho0, rho0 * 1e6}, e[4] = {0, 0.1, 1, -1}, p[4], c[4];
  size_t bad;
  (void)eos_eval(eos, 4, rho, e, p, c, &bad);
  (void)eos_c0(eos);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1 || size > 1 << 16) return 0;
  unsigned mode = data[0];
  const char *path = fuzz_scratch_path(".txt");
  fuzz_write_file(path, data + 1, size - 1);
  dk_errors e;
  dk_errors_init(&e);
  eos_t *eos;
  if (mode & 1) eos = eos_create_table_full(path, &e);
  else eos = eos_create_table_cold(path, (mode >> 1) % 4 * 0.5, (mode >> 3) & 1, &e);
  if (eos && e.n) {
    fprintf(stderr, "fuzz oracle: table accepted with errors\n");
    abort();
  }
  if (!eos && !e.n) {
    fprintf(stderr, "fuzz oracle: table rejected without a message\n");
    abort();
  }
  fuzz_check_errors(&e, path);
  if (eos) query(eos, data, size);
  eos_destroy(&eos);
  dk_errors_free(&e);
  return 0;
}
