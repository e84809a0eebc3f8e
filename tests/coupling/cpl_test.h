/* SPDX-License-Identifier: MIT */
/* Helpers shared by the coupling tests (include after <cmocka.h>). */
#ifndef MSCALE_CPL_TEST_H
#define MSCALE_CPL_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "cpl.h"

/* |a − b| ≤ tol, with both values in the failure message (this cmocka has no double asserts). */
#define assert_double_equal(a, b, tol) assert_close_at((a), (b), (tol), #a, __FILE__, __LINE__)
static inline void assert_close_at(double a, double b, double tol, const char *what,
                                   const char *file, int line) {
  if (!(fabs(a - b) <= tol)) {
    print_error("%s = %.17g, expected %.17g within %.3g (off by %.3g)\n", what, a, b, tol,
                fabs(a - b));
    _fail(file, line);
  }
}

/* Mean of the samples (t_k, u_k) over [a, b] (trapezoid on the samples inside, linear ends): the
 * plateau of the 2D line-drive checks (test_drive2d, test_coupled2d_deck). */
static inline double cpl_test_mean_over(size_t n, const double *t, const double *u, double a,
                                        double b) {
  double s = 0;
  for (size_t k = 1; k < n; k++) {
    const double lo = fmax(a, t[k - 1]), hi = fmin(b, t[k]);
    if (!(hi > lo)) continue;
    const double d = t[k] - t[k - 1], ul = u[k - 1] + (u[k] - u[k - 1]) * (lo - t[k - 1]) / d,
                 uh = u[k - 1] + (u[k] - u[k - 1]) * (hi - t[k - 1]) / d;
    s += 0.5 * (ul + uh) * (hi - lo);
  }
  return s / (b - a);
}

/* One column's free-surface plateaus (test_drive2d, test_coupled2d_deck): cpl_free_surface_check
 * of the grid's g and the particles' p sampled at t[n] with window w into chk, then the means
 * over [t_b + w/2, t_b + w], t_b the grid's breakout, the particles' window shifted by their
 * half-rise offset (test_drive2d gives the reasons), into *pg and *pp. */
static inline void cpl_test_plateaus(size_t n, const double *t, const double *g, const double *p,
                                     double w, cpl_fs_check *chk, double *pg, double *pp) {
  assert_true(cpl_free_surface_check(n, t, g, p, w, chk));
  const double shift = chk->t_half_particles - chk->t_half_grid;
  const double a = chk->t_break + 0.5 * w, b = chk->t_break + w;
  assert_true(b + fabs(shift) < t[n - 1]);
  *pg = cpl_test_mean_over(n, t, g, a, b), *pp = cpl_test_mean_over(n, t, p, a + shift, b + shift);
}

/* A `coupled` deck read from text (cpl_test_read: p is NULL and e holds the errors of a bad
 * deck), run in a temporary directory that must then hold `files` and is removed
 * (cpl_test_run_tmp), or both with no error allowed (cpl_test_run_deck); the problem stays for
 * its summary until cpl_test_run_free. */
typedef struct cpl_test_run {
  dk_errors e;
  dk_doc *doc;
  eos_materials *mats;
  cpl_problem *p;
} cpl_test_run;

static inline void cpl_test_read(cpl_test_run *r, const char *text, const char *name) {
  dk_errors_init(&r->e);
  r->doc = dk_load_string(text, name, &r->e);
  assert_non_null(r->doc);
  dk_read_units(r->doc, &r->e);
  r->mats = eos_materials_read(r->doc, &r->e);
  assert_non_null(r->mats);
  dk_get(dk_root(r->doc), "problem");
  r->p = cpl_problem_read(r->doc, dk_get(dk_root(r->doc), "coupled"), r->mats, &r->e);
  dk_report_unused(&r->e, r->doc);
}

/* Runs the read deck in a temporary directory, checks that `files` were written and, if given,
 * calls read(ctx, user) on the outputs before the directory is removed. */
static inline ms_status cpl_test_run_tmp_read(cpl_test_run *r, const char *const *files,
                                              size_t nfiles, void (*read)(const ms_ctx *, void *),
                                              void *user) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.quiet = true;
  ctx.verbosity = MS_LOG_WARN;
  char dir[] = "/tmp/mscale_test_cpl_XXXXXX";
  assert_non_null(mkdtemp(dir));
  assert_int_equal(ms_outdir_create(&ctx, dir, true), MS_OK);
  const ms_status st = cpl_problem_run(&ctx, r->p);
  for (size_t k = 0; k < nfiles && st == MS_OK; k++) {
    char *path = ms_out_path(&ctx, files[k]);
    if (access(path, R_OK)) fail_msg("missing output %s", path);
    free(path);
  }
  if (read && st == MS_OK) read(&ctx, user);
  ms_ctx_close(&ctx);
  char cmd[128];
  snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
  assert_int_equal(system(cmd), 0);
  return st;
}

static inline ms_status cpl_test_run_tmp(cpl_test_run *r, const char *const *files, size_t nfiles) {
  return cpl_test_run_tmp_read(r, files, nfiles, NULL, NULL);
}

static inline void cpl_test_run_deck(cpl_test_run *r, const char *text, const char *name,
                                     const char *const *files, size_t nfiles) {
  cpl_test_read(r, text, name);
  dk_errors_print(&r->e, stderr);
  assert_int_equal(r->e.n, 0);
  assert_int_equal(cpl_test_run_tmp(r, files, nfiles), MS_OK);
}

static inline void cpl_test_run_free(cpl_test_run *r) {
  cpl_problem_destroy(&r->p);
  eos_materials_destroy(&r->mats);
  dk_free(r->doc);
  dk_errors_free(&r->e);
}

#endif
