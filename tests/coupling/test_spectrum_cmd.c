/* SPDX-License-Identifier: MIT */
/* `mscale spectrum SNAPSHOT.h5`: app/cmd_spectrum.c called in-process on snapshots written
 * with core's HDF5 writer in the layout of docs/coupling.md (the one cd_write_snapshot uses).
 * A good snapshot gives exactly the library's spectrum with the header `g,count,mass`; bad
 * snapshots (missing dataset, wrong shape, NaN, no lattice spacing) exit 2 with a message that
 * names the file and the problem; bad usage exits 2; --help exits 0. */
#include <fcntl.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
/* cmocka needs the headers above */
#include <cmocka.h>

#include "cpl.h"

int cmd_spectrum(int argc, char **argv);

/* The front end's helper (app/main.c), which this test does not link. */
int app_wants_help(int argc, char **argv);
int app_wants_help(int argc, char **argv) {
  for (int i = 1; i < argc; i++)
    if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return 1;
  return 0;
}

/* Temporary file names unique to this process (Release and sanitizer runs may overlap). */
static const char *tmp_name(const char *stem) {
  static char buf[8][256];
  static int next = 0;
  char *b = buf[next++ % 8];
  snprintf(b, sizeof buf[0], "/tmp/mscale_test_%ld_%s", (long)getpid(), stem);
  return b;
}

static char *read_all(const char *path) {
  FILE *f = fopen(path, "r");
  if (!f) return calloc(1, 1);
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  rewind(f);
  char *s = calloc((size_t)n + 1, 1);
  size_t got = fread(s, 1, (size_t)n, f);
  s[got] = 0;
  fclose(f);
  return s;
}

/* Run the command with stdout and stderr captured into *out and *err. */
static int run(char **out, char **err, int argc, const char **argv) {
  static char po[256], pe[256];
  snprintf(po, sizeof po, "%s", tmp_name("spectrum.out"));
  snprintf(pe, sizeof pe, "%s", tmp_name("spectrum.err"));
  fflush(stdout);
  fflush(stderr);
  int so = dup(1), se = dup(2);
  int fo = open(po, O_WRONLY | O_CREAT | O_TRUNC, 0644),
      fe = open(pe, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  dup2(fo, 1);
  dup2(fe, 2);
  close(fo);
  close(fe);
  int rc = cmd_spectrum(argc, (char **)argv);
  fflush(stdout);
  fflush(stderr);
  dup2(so, 1);
  dup2(se, 2);
  close(so);
  close(se);
  *out = read_all(po);
  *err = read_all(pe);
  remove(po);
  remove(pe);
  return rc;
}

/* The test configuration: a 6×6 square block of spacing a (one fragment of 36), a chain of
 * 4, and 5 isolated particles — in the z = 0 plane, 3D coordinates. */
enum { NPART = 36 + 4 + 5 };
static const double A = 5e-4; /* 5 µm */

static void make_particles(double *xyz, double *vel, double *mass) {
  size_t i = 0;
  for (int r = 0; r < 6; r++)
    for (int c = 0; c < 6; c++, i++) {
      xyz[3 * i] = c * A;
      xyz[3 * i + 1] = r * A;
    }
  for (int k = 0; k < 4; k++, i++) {
    xyz[3 * i] = 20 * A + k * A;
    xyz[3 * i + 1] = 0;
  }
  for (int k = 0; k < 5; k++, i++) {
    xyz[3 * i] = 40 * A + 3 * k * A;
    xyz[3 * i + 1] = 10 * A;
  }
  for (size_t j = 0; j < NPART; j++) {
    xyz[3 * j + 2] = 0;
    vel[3 * j] = 0.01 * j;
    vel[3 * j + 1] = vel[3 * j + 2] = 0;
    mass[j] = 1e-9 * (1 + j % 3);
  }
}

typedef enum defect {
  GOOD = 0,
  NO_MASS,
  X_WRONG_SHAPE,
  NAN_POSITION,
  NO_SPACING,
  MASS_SHORT,
  NEGATIVE_MASS
} defect;

static void write_snapshot(const char *path, defect d) {
  double xyz[3 * NPART], vel[3 * NPART], mass[NPART];
  make_particles(xyz, vel, mass);
  if (d == NAN_POSITION) xyz[3 * 7 + 1] = NAN;
  if (d == NEGATIVE_MASS) mass[3] = -1;
  ms_h5 *h = ms_h5_create(path);
  assert_non_null(h);
  if (d == X_WRONG_SHAPE)
    assert_int_equal(ms_h5_write_doubles(h, "particles/x", 3 * NPART, 1, xyz, "cm"), MS_OK);
  else assert_int_equal(ms_h5_write_doubles(h, "particles/x", NPART, 3, xyz, "cm"), MS_OK);
  assert_int_equal(ms_h5_write_doubles(h, "particles/v", NPART, 3, vel, "km/s"), MS_OK);
  if (d != NO_MASS)
    assert_int_equal(
        ms_h5_write_doubles(h, "particles/mass", d == MASS_SHORT ? NPART - 1 : NPART, 1, mass, "g"),
        MS_OK);
  if (d != NO_SPACING) assert_int_equal(ms_h5_attr_double(h, "particles", "r0", A), MS_OK);
  assert_int_equal(ms_h5_attr_double(h, "particles", "time", 0.5), MS_OK);
  assert_int_equal(ms_h5_close(h), MS_OK);
}

/* The library's own answer for the same particles. */
static char *expected_rows(double bond) {
  double xyz[3 * NPART], vel[3 * NPART], mass[NPART], x[NPART], y[NPART], z[NPART];
  make_particles(xyz, vel, mass);
  for (int i = 0; i < NPART; i++) {
    x[i] = xyz[3 * i];
    y[i] = xyz[3 * i + 1];
    z[i] = xyz[3 * i + 2];
  }
  cpl_particles p = {NPART, x, y, z, NULL, NULL, NULL, mass, NULL, NULL};
  cpl_fragment_opts o = {.bond = bond, .spacing = A};
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  char *buf = NULL;
  size_t len = 0;
  FILE *m = open_memstream(&buf, &len);
  cpl_write_spectrum(m, &f, "x");
  fclose(m);
  cpl_fragments_free(&f);
  char *rows = strdup(strstr(buf, "g,count,mass\n"));
  free(buf);
  return rows;
}

static const char *body_of(const char *csv) {
  while (*csv == '#') csv = strchr(csv, '\n') + 1;
  return csv;
}

static void test_good_snapshot(void **state) {
  (void)state;
  char path[256], table_path[256];
  snprintf(path, sizeof path, "%s", tmp_name("good.h5"));
  snprintf(table_path, sizeof table_path, "%s", tmp_name("fragments.csv"));
  write_snapshot(path, GOOD);
  char *out, *err;
  const char *argv[] = {"spectrum", path};
  assert_int_equal(run(&out, &err, 2, argv), 0);
  /* b = 1.2 (default): block of 36, chain of 4, five singles (3a apart) */
  char *want = expected_rows(1.2);
  assert_string_equal(body_of(out), want);
  assert_non_null(strstr(out, "# units: g [clusters], count [fragments], mass [g]\n"));
  assert_non_null(strstr(body_of(out), "g,count,mass\n1,5,"));
  assert_non_null(strstr(body_of(out), "\n4,1,"));
  assert_non_null(strstr(body_of(out), "\n36,1,"));
  free(want);
  free(out);
  free(err);
  /* --bond 3.5: the singles (3a apart) join into one fragment of 5; the block, the chain and
   * the singles stay apart (≥ 4 a) */
  const char *argv2[] = {"spectrum", path, "--bond", "3.5", "--fragments", table_path};
  assert_int_equal(run(&out, &err, 6, argv2), 0);
  want = expected_rows(3.5);
  assert_string_equal(body_of(out), want);
  assert_non_null(strstr(body_of(out), "g,count,mass\n4,1,"));
  assert_non_null(strstr(body_of(out), "\n5,1,"));
  char *table = read_all(table_path);
  assert_non_null(strstr(table, "id,count,mass,d,x,y,z,vx,vy,vz,rg\n0,36,"));
  free(table);
  free(want);
  free(out);
  free(err);
  /* --spacing overrides the attribute: with a = 2 a0 and b = 1.2 the singles (3 a0 = 1.5 a)
   * are still apart, chain and block too (gap ≥ 15 a0) */
  const char *argv3[] = {"spectrum", path, "--spacing", "1e-3"};
  assert_int_equal(run(&out, &err, 4, argv3), 0);
  assert_non_null(strstr(out, "bond b*a = 1.2*0.001 cm"));
  free(out);
  free(err);
  remove(path);
  remove(table_path);
}

/* Each defect: exit 2, stderr names the file and the problem. */
static void test_bad_snapshots(void **state) {
  (void)state;
  static const struct {
    defect d;
    const char *needle;
  } cases[] = {
      {NO_MASS, "'/particles/mass' is missing"},
      {X_WRONG_SHAPE, "must have shape [n][3]"},
      {NAN_POSITION, "non-finite position (first: particle 7)"},
      {NO_SPACING, "no lattice spacing"},
      {MASS_SHORT, "'/particles/mass' has 44 entries"},
      {NEGATIVE_MASS, "not a positive number (first: particle 3)"},
  };
  char path[256];
  snprintf(path, sizeof path, "%s", tmp_name("bad.h5"));
  for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
    write_snapshot(path, cases[c].d);
    char *out, *err;
    const char *argv[] = {"spectrum", path};
    int rc = run(&out, &err, 2, argv);
    if (rc != 2 || !strstr(err, cases[c].needle) || !strstr(err, path))
      fail_msg("case %zu: rc %d, stderr: %s", c, rc, err);
    assert_string_equal(out, ""); /* nothing half-written on stdout */
    free(out);
    free(err);
  }
  remove(path);
  /* not an HDF5 file at all */
  FILE *f = fopen(path, "w");
  fputs("not hdf5\n", f);
  fclose(f);
  char *out, *err;
  const char *argv[] = {"spectrum", path};
  assert_int_equal(run(&out, &err, 2, argv), 2);
  assert_non_null(strstr(err, path));
  free(out);
  free(err);
  remove(path);
}

/* A snapshot with /particles/gid (as cluster dynamics writes, in rank order under MPI): stored
 * in reverse order with gid = the original index, it gives the same --fragments table as the
 * snapshot in the original order (fragments numbered by smallest gid, not by storage index);
 * without gids the reversed snapshot numbers them differently. A repeated gid exits 2. */
static void write_ordered(const char *path, bool reverse, bool with_gid, bool repeat_gid) {
  double xyz[3 * NPART], vel[3 * NPART], mass[NPART], x2[3 * NPART], v2[3 * NPART], m2[NPART];
  int64_t gid[NPART];
  make_particles(xyz, vel, mass);
  for (int j = 0; j < NPART; j++) {
    int i = reverse ? NPART - 1 - j : j;
    memcpy(x2 + 3 * j, xyz + 3 * i, 3 * sizeof(double));
    memcpy(v2 + 3 * j, vel + 3 * i, 3 * sizeof(double));
    m2[j] = mass[i];
    gid[j] = repeat_gid && j == 1 ? 7 : i + 100; /* ids need not start at 0 */
  }
  if (repeat_gid) gid[0] = 7;
  ms_h5 *h = ms_h5_create(path);
  assert_non_null(h);
  assert_int_equal(ms_h5_write_doubles(h, "particles/x", NPART, 3, x2, "cm"), MS_OK);
  assert_int_equal(ms_h5_write_doubles(h, "particles/v", NPART, 3, v2, "km/s"), MS_OK);
  assert_int_equal(ms_h5_write_doubles(h, "particles/mass", NPART, 1, m2, "g"), MS_OK);
  if (with_gid) assert_int_equal(ms_h5_write_ints(h, "particles/gid", NPART, gid), MS_OK);
  assert_int_equal(ms_h5_attr_double(h, "particles", "r0", A), MS_OK);
  assert_int_equal(ms_h5_close(h), MS_OK);
}

static char *table_of(const char *path, const char *table_path) {
  char *out, *err;
  const char *argv[] = {"spectrum", path, "--fragments", table_path};
  assert_int_equal(run(&out, &err, 4, argv), 0);
  free(out);
  free(err);
  char *t = read_all(table_path);
  remove(table_path);
  return t;
}

static void test_gid_order(void **state) {
  (void)state;
  char path[256], table_path[256];
  snprintf(path, sizeof path, "%s", tmp_name("gid.h5"));
  snprintf(table_path, sizeof table_path, "%s", tmp_name("gid.csv"));
  write_ordered(path, false, true, false);
  char *fwd = table_of(path, table_path);
  write_ordered(path, true, true, false);
  char *rev = table_of(path, table_path);
  write_ordered(path, true, false, false);
  char *rev_index = table_of(path, table_path);
  assert_non_null(strstr(fwd, "\n0,36,")); /* the block holds the smallest gid */
  assert_string_equal(rev, fwd);
  assert_non_null(strstr(rev_index, "\n0,1,")); /* by index: the last single comes first */
  assert_true(strcmp(rev_index, fwd) != 0);
  free(fwd);
  free(rev);
  free(rev_index);
  write_ordered(path, false, true, true);
  char *out, *err;
  const char *argv[] = {"spectrum", path};
  assert_int_equal(run(&out, &err, 2, argv), 2);
  assert_non_null(strstr(err, "'/particles/gid'"));
  assert_non_null(strstr(err, "distinct"));
  free(out);
  free(err);
  remove(path);
}

static void test_usage(void **state) {
  (void)state;
  char *out, *err;
  const char *help[] = {"spectrum", "--help"};
  assert_int_equal(run(&out, &err, 2, help), 0);
  assert_non_null(strstr(out, "Usage: mscale spectrum SNAPSHOT.h5"));
  free(out);
  free(err);
  const char *none[] = {"spectrum"};
  assert_int_equal(run(&out, &err, 1, none), 2);
  free(out);
  free(err);
  const char *badbond[] = {"spectrum", "x.h5", "--bond", "-1"};
  assert_int_equal(run(&out, &err, 4, badbond), 2);
  assert_non_null(strstr(err, "--bond"));
  free(out);
  free(err);
  const char *unknown[] = {"spectrum", "x.h5", "--bnod", "1"};
  assert_int_equal(run(&out, &err, 4, unknown), 2);
  assert_non_null(strstr(err, "--bnod"));
  free(out);
  free(err);
}

/* cpl_write_snapshot: the layout round-trips through `mscale spectrum` (same spectrum as the
 * library, periodic attributes honoured) and the fragment ids stored are the library's. */
static void test_snapshot_writer(void **state) {
  (void)state;
  double xyz[3 * NPART], vel[3 * NPART], mass[NPART], x[NPART], y[NPART], z[NPART];
  make_particles(xyz, vel, mass);
  for (int i = 0; i < NPART; i++) {
    x[i] = xyz[3 * i];
    y[i] = xyz[3 * i + 1];
    z[i] = xyz[3 * i + 2];
  }
  cpl_particles p = {NPART, x, y, z, NULL, NULL, NULL, mass, NULL, NULL};
  cpl_fragment_opts o = {.bond = 1.2, .spacing = A, .rho0 = 11.34};
  o.box.period[1] = 50 * A; /* y periodic, wide enough not to change anything */
  cpl_fragments f;
  cpl_fragments_init(&f);
  assert_int_equal(cpl_fragments_find(&f, &p, &o), MS_OK);
  char path[256];
  snprintf(path, sizeof path, "%s", tmp_name("writer.h5"));
  cpl_snapshot_info info = {.time = 0.25, .spacing = A, .rho0 = 11.34, .box = o.box};
  assert_int_equal(cpl_write_snapshot(path, &p, &f, &info), MS_OK);
  char *out, *err;
  const char *argv[] = {"spectrum", path};
  assert_int_equal(run(&out, &err, 2, argv), 0);
  char *want = expected_rows(1.2);
  assert_string_equal(body_of(out), want);
  free(want);
  free(out);
  free(err);
  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *h = ms_h5_open_read(path, &e);
  assert_non_null(h);
  double *ids = NULL, v = 0;
  size_t n0, n1;
  assert_int_equal(ms_h5_read_doubles(h, "/particles/fragment_id", &ids, &n0, &n1, &e), MS_OK);
  assert_int_equal(n0, NPART);
  for (size_t i = 0; i < NPART; i++) assert_true(ids[i] == (double)f.id[i]);
  assert_int_equal(ms_h5_read_attr_double(h, "/particles", "period_y", &v, &e), MS_OK);
  assert_true(v == 50 * A);
  assert_int_equal(ms_h5_read_attr_double(h, "/particles", "period_x", &v, NULL), MS_ERR_INPUT);
  free(ids);
  ms_h5_close_read(h);
  dk_errors_free(&e);
  cpl_fragments_free(&f);
  remove(path);
  size_t len = strlen(path);
  strcpy(path + len - 3, ".xmf");
  char *xmf = read_all(path);
  assert_non_null(strstr(xmf, "particles/fragment_id"));
  free(xmf);
  remove(path);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_good_snapshot), cmocka_unit_test(test_bad_snapshots),
      cmocka_unit_test(test_usage),         cmocka_unit_test(test_snapshot_writer),
      cmocka_unit_test(test_gid_order),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
