/* SPDX-License-Identifier: MIT */
/* libFuzzer harness: the HDF5 readers (ms_h5_open_read, ms_h5_exists, ms_h5_read_doubles) and
 * the HDF5 form of the full EOS table (eos_create_table_full on a .h5 file).
 *
 * Two builds of this file:
 *  - fuzz_h5 (structured): the input is a small program that builds a *valid* HDF5 file with a
 *    wrong or odd layout — datasets or groups under the names the readers look for, float64,
 *    float32, int or string types, rank 0..3, empty or mismatched dimensions, NaN/Inf values,
 *    chunked datasets with huge declared sizes and no data. This exercises our code, not the
 *    HDF5 library's parser.
 *  - fuzz_h5_raw (-DFUZZ_H5_RAW): the input bytes are the file itself (seed: a valid table).
 *    Crashes inside libhdf5 found this way are HDF5 bugs, documented in docs/reliability.md.
 * Oracles: no sanitizer report; every reader failure comes with a message naming the file;
 * successful reads return 1D/2D data of the sizes reported. */
#include "eos.h"
#include "fuzz_util.h"

#include <hdf5.h>
#include <math.h>

static const char *const names[] = {"rho", "e", "P", "c", "rho0", "coords", "g/x", "/g/y/z"};
enum { NNAMES = sizeof names / sizeof *names };

typedef struct cursor {
  const uint8_t *p;
  size_t n;
} cursor;

static unsigned take(cursor *c) {
  if (!c->n) return 0;
  c->n--;
  return *c->p++;
}

#ifndef FUZZ_H5_RAW
static double value_from(unsigned b) {
  switch (b % 16) {
  case 0:
    return NAN;
  case 1:
    return INFINITY;
  case 2:
    return -1.0;
  case 3:
    return 0.0;
  default:
    return (double)(b / 16 + 1) * 0.5 * (b % 16);
  }
}

static void build_file(const char *path, cursor *c) {
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (f < 0) abort();
  hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  unsigned nobj = take(c) % 7;
  for (unsigned k = 0; k < nobj; k++) {
    unsigned op = take(c);
    const char *name = names[op % NNAMES];
    if ((op >> 4) % 8 == 0) { /* a group where a dataset is expected */
      hid_t g = H5Gcreate2(f, name, lcpl, H5P_DEFAULT, H5P_DEFAULT);
      if (g >= 0) H5Gclose(g);
      continue;
    }
    unsigned shape = take(c);
    int rank = shape % 4;
    hsize_t dims[3] = {take(c) % 9, take(c) % 9, take(c) % 4};
    unsigned tsel = take(c) % 8;
    hid_t ftype = tsel < 4    ? H5T_IEEE_F64LE
                  : tsel == 4 ? H5T_IEEE_F32BE
                  : tsel == 5 ? H5T_STD_I32LE
                              : -1;
    hid_t strtype = -1;
    if (ftype < 0) {
      strtype = H5Tcopy(H5T_C_S1);
      H5Tset_size(strtype, 8);
      ftype = strtype;
    }
    hid_t dcpl = H5P_DEFAULT, space;
    bool huge = (shape >> 2) % 8 == 0 && rank > 0;
    if (huge) { /* chunked, huge declared extent, nothing written */
      hsize_t big[3] = {(hsize_t)1 << (20 + take(c) % 24), 3, 2}, chunk[3] = {4, 1, 1};
      space = H5Screate_simple(rank, big, NULL);
      dcpl = H5Pcreate(H5P_DATASET_CREATE);
      H5Pset_chunk(dcpl, rank, chunk);
    } else {
      space = rank ? H5Screate_simple(rank, dims, NULL) : H5Screate(H5S_SCALAR);
    }
    hid_t ds = H5Dcreate2(f, name, ftype, space, lcpl, dcpl, H5P_DEFAULT);
    if (ds >= 0 && !huge && ftype != strtype) {
      hsize_t count = rank ? dims[0] * (rank > 1 ? dims[1] : 1) * (rank > 2 ? dims[2] : 1) : 1;
      double buf[9 * 9 * 4];
      for (hsize_t i = 0; i < count; i++) buf[i] = value_from(take(c));
      H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    }
    if (ds >= 0) H5Dclose(ds);
    if (dcpl != H5P_DEFAULT) H5Pclose(dcpl);
    H5Sclose(space);
    if (strtype >= 0) H5Tclose(strtype);
  }
  H5Pclose(lcpl);
  H5Fclose(f);
}
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size > 1 << 16) return 0;
  const char *path = fuzz_scratch_path(".h5");
  cursor c = {data, size};
#ifdef FUZZ_H5_RAW
  fuzz_write_file(path, data, size);
#else
  build_file(path, &c);
#endif
  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *h = ms_h5_open_read(path, &e);
  if (!h && !e.n) {
    fprintf(stderr, "fuzz oracle: open failed without a message\n");
    abort();
  }
  if (h) {
    for (int i = 0; i < NNAMES; i++) {
      double *v = NULL;
      size_t n0, n1;
      size_t before = e.n;
      bool exists = ms_h5_exists(h, names[i]);
      ms_status s = ms_h5_read_doubles(h, names[i], &v, &n0, &n1, &e);
      if (s == MS_OK) {
        if (!exists || !v || e.n != before) { /* n1 may be 0: a [n][0] dataset is empty */
          fprintf(stderr, "fuzz oracle: '%s' read but exists=%d, n1=%zu, %zu new errors\n",
                  names[i], exists, n1, e.n - before);
          abort();
        }
        volatile double sum = 0;
        for (size_t k = 0; k < n0 * n1; k++) sum += v[k]; /* ASan checks the size */
        (void)sum;
      } else if (e.n == before || v) {
        fprintf(stderr, "fuzz oracle: reading '%s' failed without a message\n", names[i]);
        abort();
      }
      free(v);
    }
    ms_h5_close_read(h);
  }
  fuzz_check_errors(&e, path);
  dk_errors_free(&e);

  dk_errors_init(&e);
  eos_t *eos = eos_create_table_full(path, &e);
  if (!eos == !e.n) { /* accepted without errors or rejected with some */
    fprintf(stderr, "fuzz oracle: table %s with %zu errors\n", eos ? "accepted" : "rejected", e.n);
    dk_errors_print(&e, stderr);
    abort();
  }
  fuzz_check_errors(&e, path);
  if (eos) {
    double rho0 = eos_rho0(eos);
    (void)eos_pressure(eos, rho0, 0.5);
    (void)eos_sound_speed(eos, rho0 * 1.01, 0.1);
    (void)eos_pressure(eos, NAN, 0.0);
  }
  eos_destroy(&eos);
  dk_errors_free(&e);
  (void)take;
  (void)c;
  return 0;
}
