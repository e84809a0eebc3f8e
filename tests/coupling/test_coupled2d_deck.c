/* SPDX-License-Identifier: MIT */
/* The deck problem coupled2d end to end (docs/coupling.md §5a, issue 24): the shipped deck
 * inputs/coupled2d-flyer.yaml (the finite flyer of test_drive2d) is run through `mscale run`, and
 * free_surface_columns.csv is checked as test_drive2d checks its in-process run: at every
 * column (x = 0 … 1, every 0.05) the particles' free-surface plateau after breakout within 1 % of
 * the grid's (the same window, breakout and half-rise shift: cpl_free_surface_check and
 * cpl_test_mean_over). Measured: ≤ 0.37 %, as test_drive2d. Also: the run's particle snapshots
 * exist.
 * Usage: test_coupled2d_deck MSCALE DECK [--set PATH=VALUE]... (extra arguments go to `mscale
 * run`: `--set coupled2d.drive.lateral=false` must fail, −3.1 % at x = 1). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "cpl.h"
#include "cpl_test.h"

static int g_argc;
static char **g_argv;

enum { MAXCOL = 64, MAXREC = 8000, LINE = 1 << 16 };

/* The CSV: t (µs) and per column u_grid, u_particles (km/s); an empty field (no surface particle
 * there) reads as NaN. Returns the rows; *ncol the columns (pairs). */
static size_t read_csv(const char *path, double *t, double *ug, double *up, size_t *ncol) {
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  char *line = malloc(LINE);
  size_t n = 0;
  *ncol = 0;
  while (fgets(line, LINE, f)) {
    if (line[0] == '#') continue;
    if (line[0] == 't') { /* the column names */
      for (const char *c = line; *c; c++) *ncol += *c == ',';
      *ncol /= 2;
      assert_true(*ncol > 0 && *ncol <= MAXCOL);
      continue;
    }
    assert_true(n < MAXREC);
    char *c = line;
    t[n] = 0.1 * strtod(c, &c); /* µs → 10 µs, the internal unit of the windows below */
    for (size_t m = 0; m < *ncol; m++) {
      for (int k = 0; k < 2; k++) {
        assert_true(*c == ',');
        c++;
        char *end = c;
        const double v = strtod(c, &end);
        (k ? up : ug)[m * MAXREC + n] = end == c ? NAN : v;
        c = end;
      }
    }
    n++;
  }
  free(line);
  fclose(f);
  return n;
}

static void test_deck(void **state) {
  (void)state;
  assert_true(g_argc >= 3);
  char dir[] = "/tmp/mscale_test_coupled2d_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char cmd[4096];
  int len =
      snprintf(cmd, sizeof cmd, "'%s' run '%s' -o '%s/out' --quiet", g_argv[1], g_argv[2], dir);
  for (int k = 3; k < g_argc; k++)
    len += snprintf(cmd + len, sizeof cmd - (size_t)len, " '%s'", g_argv[k]);
  len += snprintf(cmd + len, sizeof cmd - (size_t)len, " > '%s/run.txt' 2>&1", dir);
  printf("%s\n", cmd);
  assert_int_equal(system(cmd), 0);
  char path[512];
  snprintf(path, sizeof path, "%s/out/particles_0004.h5", dir);
  FILE *snap = fopen(path, "rb");
  assert_non_null(snap);
  fclose(snap);
  snprintf(path, sizeof path, "%s/out/particles.xmf", dir);
  assert_non_null(snap = fopen(path, "rb"));
  fclose(snap);
  double *t = calloc(MAXREC, sizeof *t), *ug = calloc(MAXREC * MAXCOL, sizeof *ug),
         *up = calloc(MAXREC * MAXCOL, sizeof *up);
  size_t ncol = 0;
  snprintf(path, sizeof path, "%s/out/free_surface_columns.csv", dir);
  const size_t n = read_csv(path, t, ug, up, &ncol);
  printf("%zu rows, %zu columns\n", n, ncol);
  assert_int_equal(ncol, 21); /* x = 0 … 1 every 0.05 (output.column_every 4, column_upto 1) */
  /* test_drive2d's plateau: the means over [t_b + w/2, t_b + w], w = 0.018, the particles'
   * window shifted by their half-rise offset (the reasons are given there) */
  const double win = 0.018;
  double worst = 0;
  size_t worst_c = 0;
  for (size_t c = 0; c < ncol; c++) {
    cpl_fs_check chk;
    double pg, pp;
    cpl_test_plateaus(n, t, &ug[c * MAXREC], &up[c * MAXREC], win, &chk, &pg, &pp);
    const double rel = pp / pg - 1;
    printf("column %zu: breakout %.4f, plateau grid %.4f, particles %.4f km/s (%+.2f %%)\n", c,
           chk.t_break, pg, pp, 100 * rel);
    if (!(fabs(rel) <= worst)) worst = fabs(rel), worst_c = c;
  }
  printf("coupled2d deck: worst plateau difference %.3f %% at column %zu\n", 100 * worst, worst_c);
  /* 1 %: test_drive2d's criterion (the 1D drive check of test_cpl_dm, column by column) */
  assert_true(worst < 0.01);
  free(t), free(ug), free(up);
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  assert_int_equal(system(cmd), 0);
}

int main(int argc, char **argv) {
  g_argc = argc, g_argv = argv;
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_deck)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
