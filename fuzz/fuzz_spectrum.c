/* SPDX-License-Identifier: MIT */
/* libFuzzer harness: `mscale spectrum SNAPSHOT.h5` (app/cmd_spectrum.c: the snapshot reader,
 * attributes, the fragment search of coupling/ and the CSV writer).
 *
 * The input is a small program that builds a valid particle snapshot with odd content: n
 * particles (0..40), positions [n][2|3|4] with values from tiny to 1e300 and NaN, masses of
 * another length or sign, velocities, and the attributes r0, rho0, period_x/y/z, lo_x/y/z set
 * to fuzzed values (or left out). Oracles: no sanitizer report and exit code 0, 1 or 2. The
 * spectrum goes to /dev/null; run with -close_fd_mask=2 to silence the command's messages
 * (libFuzzer still prints crash reports). */
#include "fuzz_util.h"

#include <hdf5.h>
#include <math.h>

int cmd_spectrum(int argc, char **argv);

/* From app/main.c (not linked: it holds main()). */
int app_wants_help(int argc, char **argv) {
  for (int i = 1; i < argc; i++)
    if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return 1;
  return 0;
}

typedef struct cursor {
  const uint8_t *p;
  size_t n;
} cursor;

static unsigned take(cursor *c) {
  if (!c->n) return 0;
  c->n--;
  return *c->p++;
}

static double value_from(unsigned b) {
  static const double special[] = {NAN, INFINITY, -1.0, 0.0, 1e-300, 1e300, -1e300, 5e-324};
  if (b % 32 < 8) return special[b % 8];
  return (double)(b % 32 - 8) * 1e-3 * (b & 128 ? -1 : 1); /* a few lattice spacings apart */
}

static void attr(hid_t obj, const char *name, double v) {
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(obj, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  if (a >= 0) {
    H5Awrite(a, H5T_NATIVE_DOUBLE, &v);
    H5Aclose(a);
  }
  H5Sclose(space);
}

static void dataset(hid_t g, const char *name, hsize_t n0, hsize_t n1, cursor *c) {
  hsize_t dims[2] = {n0, n1};
  hid_t space = H5Screate_simple(n1 ? 2 : 1, dims, NULL);
  hid_t ds = H5Dcreate2(g, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  double buf[40 * 4];
  hsize_t count = n0 * (n1 ? n1 : 1);
  for (hsize_t i = 0; i < count; i++) buf[i] = value_from(take(c));
  if (ds >= 0) {
    H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    H5Dclose(ds);
  }
  H5Sclose(space);
}

static void build_snapshot(const char *path, cursor *c) {
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (f < 0) abort();
  hid_t g = H5Gcreate2(f, "particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  unsigned flags = take(c) | take(c) << 8;
  hsize_t n = take(c) % 41;
  hsize_t ncomp = 2 + take(c) % 3;
  dataset(g, "x", n, ncomp, c);
  if (!(flags & 1)) dataset(g, "mass", flags & 2 ? n : take(c) % 41, 0, c);
  if (flags & 4) dataset(g, "v", n, flags & 8 ? 3 : 2, c);
  static const char *const names[] = {"r0",       "rho0", "period_x", "period_y",
                                      "period_z", "lo_x", "lo_y",     "lo_z"};
  for (int k = 0; k < 8; k++)
    if (flags & (16u << k))
      attr(g, names[k], k == 0 && !(flags & 0x1000) ? 1e-3 : value_from(take(c)));
  H5Gclose(g);
  H5Fclose(f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static bool quiet;
  if (!quiet) quiet = freopen("/dev/null", "w", stdout) != NULL; /* the CSV */
  if (size > 4096) return 0;
  cursor c = {data, size};
  const char *path = fuzz_scratch_path(".h5");
  build_snapshot(path, &c);
  char *argv[] = {"spectrum", (char *)path, NULL};
  int rc = cmd_spectrum(2, argv);
  if (rc < 0 || rc > 2) abort();
  return 0;
}
