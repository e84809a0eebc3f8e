/* SPDX-License-Identifier: MIT */
/* Output and input helpers: atomic files, tables with FILE:LINE errors, HDF5 round trip. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include <hdf5.h>

#include "core.h"
#include "test_util.h"

static void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

/* An aborted write leaves neither the final file nor the temporary; a committed one replaces
 * the old content only at commit. */
static void test_atomic_file(void **state) {
  (void)state;
  const char *path = "/tmp/mscale_test_atomic.txt";
  write_file(path, "finished\n");
  ms_afile af;
  assert_int_equal(ms_afile_open(&af, path), MS_OK);
  fputs("partial", af.f);
  fflush(af.f);
  char buf[64] = "";
  FILE *f = fopen(path, "r");
  assert_non_null(fgets(buf, sizeof buf, f));
  fclose(f);
  assert_string_equal(buf, "finished\n"); /* still the old content while writing */
  ms_afile_abort(&af);
  assert_int_equal(access("/tmp/mscale_test_atomic.txt.part", F_OK), -1);
  assert_int_equal(ms_afile_open(&af, path), MS_OK);
  fputs("new\n", af.f);
  assert_int_equal(ms_afile_commit(&af), MS_OK);
  f = fopen(path, "r");
  assert_non_null(fgets(buf, sizeof buf, f));
  fclose(f);
  assert_string_equal(buf, "new\n");
  remove(path);
}

static void test_table_reader(void **state) {
  (void)state;
  const char *path = "/tmp/mscale_test_table.csv";
  dk_errors e;
  double *d;
  size_t nr, nc;
  write_file(path, "# comment\nt,u\n0, 1\n0.5 2\n1.0,3\n");
  dk_errors_init(&e);
  assert_int_equal(ms_read_table(path, 2, &d, &nr, &nc, &e), MS_OK);
  assert_int_equal(nr, 3);
  assert_int_equal(nc, 2);
  assert_true(d[4] == 1.0 && d[5] == 3.0);
  free(d);
  /* a truncated last row */
  write_file(path, "0 1\n0.5 2\n1.0\n");
  assert_int_equal(ms_read_table(path, 2, &d, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, "mscale_test_table.csv:3:1: expected 2 columns"));
  /* a word in the data */
  write_file(path, "0 1\n0.5 abc\n");
  assert_int_equal(ms_read_table(path, 2, &d, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, "mscale_test_table.csv:2:5: expected a number, found 'abc'"));
  /* NaN is not data */
  write_file(path, "0 1\n0.5 nan\n");
  assert_int_equal(ms_read_table(path, 2, &d, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, ":2:5: column 2 is not a finite number (nan)"));
  /* too few columns, empty file, missing file */
  write_file(path, "1\n2\n");
  assert_int_equal(ms_read_table(path, 2, &d, &nr, &nc, &e), MS_ERR_INPUT);
  write_file(path, "# nothing\n");
  assert_int_equal(ms_read_table(path, 2, &d, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, "no data rows"));
  assert_int_equal(ms_read_table("/nonexistent/x.csv", 2, &d, &nr, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, "/nonexistent/x.csv: cannot open"));
  dk_errors_free(&e);
  remove(path);
}

static void test_hdf5_round_trip(void **state) {
  (void)state;
  const char *path = "/tmp/mscale_test.h5";
  ms_h5 *h = ms_h5_create(path);
  assert_non_null(h);
  double x[6] = {1, 2, 3, 4, 5, 6};
  int64_t id[3] = {7, 8, 9};
  assert_int_equal(ms_h5_write_doubles(h, "/particles/x", 3, 2, x, "cm"), MS_OK);
  assert_int_equal(ms_h5_write_ints(h, "/particles/id", 3, id), MS_OK);
  assert_int_equal(ms_h5_attr_double(h, "/", "time", 0.25), MS_OK);
  assert_int_equal(access("/tmp/mscale_test.h5.part", F_OK), 0); /* not final before close */
  assert_int_equal(ms_h5_close(h), MS_OK);
  assert_int_equal(access("/tmp/mscale_test.h5.part", F_OK), -1);
  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *r = ms_h5_open_read(path, &e);
  assert_non_null(r);
  double *back;
  size_t n0, n1;
  assert_int_equal(ms_h5_read_doubles(r, "/particles/x", &back, &n0, &n1, &e), MS_OK);
  assert_int_equal(n0, 3);
  assert_int_equal(n1, 2);
  assert_memory_equal(back, x, sizeof x);
  free(back);
  assert_false(ms_h5_exists(r, "/nothing/here"));
  assert_int_equal(ms_h5_read_doubles(r, "/nothing/here", &back, &n0, &n1, &e), MS_ERR_INPUT);
  assert_int_equal(ms_h5_read_doubles(r, "/particles/id", &back, &n0, &n1, &e), MS_ERR_INPUT);
  ms_h5_close_read(r);
  /* the units attribute is there for h5py users */
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t ds = H5Dopen2(f, "/particles/x", H5P_DEFAULT);
  assert_true(H5Aexists(ds, "units") > 0);
  H5Dclose(ds);
  H5Fclose(f);
  /* a file that is not HDF5 */
  write_file("/tmp/mscale_test_not.h5", "hello");
  assert_null(ms_h5_open_read("/tmp/mscale_test_not.h5", &e));
  assert_true(has_error(&e, "not a readable HDF5 file"));
  dk_errors_free(&e);
  remove(path);
  remove("/tmp/mscale_test_not.h5");
}

/* What checkpoints need (core/checkpoint.c): row ranges, int64 rows, bytes, string attributes,
 * empty datasets (nothing recorded yet), the deck hash. */
static void test_hdf5_checkpoint_helpers(void **state) {
  (void)state;
  const char *path = "/tmp/mscale_test_ckpt.h5";
  ms_h5 *h = ms_h5_create_collective(path); /* no MPI running: an ordinary file */
  assert_non_null(h);
  double x[8] = {0, 1, 10, 11, 20, 21, 30, 31};
  int64_t g[4] = {-1, 5, 1LL << 40, 7};
  assert_int_equal(ms_h5_write_doubles_dist(h, "/a/x", 4, 2, x, "cm"), MS_OK);
  assert_int_equal(ms_h5_write_doubles_dist(h, "/a/empty", 0, 2, x, NULL), MS_OK);
  assert_int_equal(ms_h5_write_ints_dist(h, "/a/g", 4, g), MS_OK);
  assert_int_equal(ms_h5_write_bytes_dist(h, "/a/text", 5, "a,b\n1"), MS_OK);
  assert_int_equal(ms_h5_attr_string(h, "/", "deck_hash", "00ff"), MS_OK);
  assert_int_equal(ms_h5_close(h), MS_OK);
  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *r = ms_h5_open_read(path, &e);
  assert_non_null(r);
  double *v = NULL;
  size_t n = 0, nc = 0;
  assert_int_equal(ms_h5_read_doubles_rows(r, "/a/x", 1, 2, &v, &n, &nc, &e), MS_OK);
  assert_int_equal(n, 2);
  assert_int_equal(nc, 2);
  assert_memory_equal(v, x + 2, 4 * sizeof *v); /* rows 1 and 2 exactly */
  free(v);
  assert_int_equal(ms_h5_read_doubles_rows(r, "/a/empty", 0, SIZE_MAX, &v, &n, &nc, &e), MS_OK);
  assert_int_equal(n, 0);
  free(v);
  assert_int_equal(ms_h5_read_doubles_rows(r, "/a/x", 3, 2, &v, &n, &nc, &e), MS_ERR_INPUT);
  assert_true(has_error(&e, "has 4 rows, rows 3..5 were asked for"));
  int64_t *gi = NULL;
  assert_int_equal(ms_h5_read_ints_rows(r, "/a/g", 0, SIZE_MAX, &gi, &n, &nc, &e), MS_OK);
  assert_int_equal(n, 4);
  assert_memory_equal(gi, g, sizeof g);
  free(gi);
  assert_int_equal(ms_h5_read_ints_rows(r, "/a/x", 0, SIZE_MAX, &gi, &n, &nc, &e), MS_ERR_INPUT);
  char *text = NULL;
  assert_int_equal(ms_h5_read_bytes(r, "/a/text", &text, &n, &e), MS_OK);
  assert_int_equal(n, 5);
  assert_string_equal(text, "a,b\n1");
  free(text);
  assert_int_equal(ms_h5_read_attr_string(r, "/", "deck_hash", &text, &e), MS_OK);
  assert_string_equal(text, "00ff");
  free(text);
  assert_int_equal(ms_h5_read_attr_string(r, "/", "absent", &text, &e), MS_ERR_INPUT);
  ms_h5_close_read(r);
  remove(path);
  /* the deck hash: defaults and skipped keys */
  dk_doc *a = dk_load_string("p: {x: 1, t_end: 2}\n", "a.yaml", &e);
  dk_doc *b = dk_load_string("p: {x: 1, t_end: 3}\n", "b.yaml", &e);
  dk_doc *c = dk_load_string("p: {x: 2, t_end: 2}\n", "c.yaml", &e);
  const char *const skip[] = {"p.t_end", NULL};
  assert_true(dk_hash(a, NULL) != dk_hash(b, NULL));
  assert_true(dk_hash(a, skip) == dk_hash(b, skip));
  assert_true(dk_hash(a, skip) != dk_hash(c, skip));
  dk_free(a), dk_free(b), dk_free(c);
  dk_errors_free(&e);
}

static char *slurp(const char *path) {
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  static char buf[4096];
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  buf[n] = 0;
  fclose(f);
  return buf;
}

/* Output units (docs/output.md, "Units"): a column declared in the internal 10 us is written in
 * us, header and values (x 10, one rounding: compared with %.10g's text); other columns are
 * untouched; after a checkpoint's text is copied back (ms_csv_resume) the rows go on in us; and
 * the table reader takes the file's time unit back to internal 10 us exactly for these values. */
static void test_output_time_unit(void **state) {
  (void)state;
  const char *path = "/tmp/mscale_test_units.csv";
  ms_afile af;
  assert_int_equal(ms_afile_open(&af, path), MS_OK);
  const char *names[] = {"t", "x", "J"}, *units[] = {"10us", "cm", "GPa*10us"};
  ms_csv_header(af.f, "a history at t = 1 us", 3, names, units);
  ms_csv_row(af.f, 3, (const double[]){0.25, 0.25, 2.0});
  assert_int_equal(ms_afile_commit(&af), MS_OK);
  assert_string_equal(slurp(path), "# a history at t = 1 us\n"
                                   "# units: t [us], x [cm], J [GPa*us]\n"
                                   "t,x,J\n"
                                   "2.5,0.25,20\n");
  /* a restarted run: the text so far copied back, then one more row */
  char text[4096];
  snprintf(text, sizeof text, "%s", slurp(path));
  assert_int_equal(ms_afile_open(&af, path), MS_OK);
  fputs(text, af.f);
  ms_csv_resume(af.f, text, strlen(text));
  ms_csv_row(af.f, 3, (const double[]){0.5, 1.0, 3.0});
  assert_int_equal(ms_afile_commit(&af), MS_OK);
  assert_non_null(strstr(slurp(path), "t,x,J\n2.5,0.25,20\n5,1,30\n"));
  /* a file without the header's registration: nothing converted */
  FILE *f = fopen(path, "w");
  ms_csv_row(f, 2, (const double[]){0.5, 1.0});
  fclose(f);
  assert_string_equal(slurp(path), "0.5,1\n");
  /* read back as a history: the units line names the time unit */
  write_file(path, "# units: t [us], u [km/s]\nt,u\n0,1\n2.5,2\n");
  assert_true(ms_table_time_factor(path, 0, 1.0) == 0.1);
  assert_true(ms_table_time_factor(path, 1, 7.0) == 7.0); /* not a time unit: the fallback */
  write_file(path, "# units: t [s], u [m/s]\nt,u\n0,1\n");
  assert_true(ms_table_time_factor(path, 0, 1.0) == 1e5);
  write_file(path, "# t [us] in a comment, not a units line\nt,u\n0,1\n");
  assert_true(ms_table_time_factor(path, 0, 1.0) == 1.0);
  assert_string_equal(ms_out_unit("10us", NULL), "us");
  assert_string_equal(ms_out_unit("km/s", NULL), "km/s");
  remove(path);
}

static void test_xdmf(void **state) {
  (void)state;
  const char *path = "/tmp/mscale_test.xmf";
  ms_xdmf_attr a[2] = {{"velocity", "/particles/v", 3, false}, {"rho", "/cells/rho", 1, true}};
  assert_int_equal(ms_xdmf_write_points(path, "snap.h5", "/particles/x", 4, 3, 1.5, 2, a), MS_OK);
  FILE *f = fopen(path, "r");
  char buf[8192];
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  buf[n] = 0;
  fclose(f);
  assert_non_null(strstr(buf, "TopologyType=\"Polyline\" NumberOfElements=\"3\""));
  assert_non_null(strstr(buf, "snap.h5:/particles/x"));
  assert_non_null(strstr(buf, "Attribute Name=\"rho\" AttributeType=\"Scalar\" Center=\"Cell\""));
  assert_non_null(strstr(buf, "<Time Value=\"1.5\"/>"));
  remove(path);
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_atomic_file),
                                     cmocka_unit_test(test_table_reader),
                                     cmocka_unit_test(test_hdf5_round_trip),
                                     cmocka_unit_test(test_hdf5_checkpoint_helpers),
                                     cmocka_unit_test(test_xdmf),
                                     cmocka_unit_test(test_output_time_unit)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
