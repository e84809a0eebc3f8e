/* test_dm_hugoniot.c — the finite-deformation discrete model (particles/dm/dm_finite.c) against
 * the EOS library's Hugoniot: a piston driving a planar shock into Al (mg_linear) and Pb
 * (mg_cold), yield none; and the discrete energy balance with viscosity and plasticity on
 * (docs/particles-dm.md, docs/validation.md). Set DM_HUGONIOT_PRINT=1 for the table. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>

#include "dm.h"

/* Default viscosity and bond-penalty coefficients of the deck (docs/input-dm.md): one set for
 * every run, not tuned per case. */
static dm_fin_params default_par(double h) {
  return (dm_fin_params){.cq = 2.0, .cl = 0.5, .courant = 0.4, .hourglass = 1.0, .ell = h};
}

typedef struct hcase {
  const char *name;
  eos_t *eos;
} hcase;

static void run_case(const hcase *hc, int dim, long nx, long nlat, double up, double tol,
                     int print) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  const double rho0 = eos_rho0(hc->eos), e0 = eos_e0(hc->eos);
  eos_hugoniot_point ref;
  assert_int_equal(eos_hugoniot(hc->eos, rho0, e0, 1, &up, &ref), MS_OK);
  const double h = 0.01; /* cm: the result is scale-free (no length in the model but h) */
  dm_piston_spec sp = {.dim = dim,
                       .nx = nx,
                       .ny = nlat,
                       .nz = nlat,
                       .npiston = 2,
                       .h = h,
                       .horizon = 1.5,
                       .mat = {.eos = hc->eos, .yield = DM_YIELD_NONE},
                       .par = default_par(h),
                       .up = up,
                       .nsamples = 20};
  /* run until the front (lab speed D) has crossed 75 % of the slab: sizing only */
  sp.t_end = 0.75 * (nx - sp.npiston) * h / ref.us;
  dm_piston_result r;
  assert_int_equal(dm_piston_run(&sp, &ctx, &r), MS_OK);
  const double eD = r.D / ref.us - 1, eP = r.P / (ref.p - eos_pressure(hc->eos, rho0, e0)) - 1,
               er = r.rho / ref.rho - 1;
  if (print)
    printf("%s dim %d nx %ld up %5.2f: D %.5f (ref %.5f, %+.3f %%) P %.5f (ref %.5f, %+.3f %%) "
           "rho %.5f (ref %.5f, %+.3f %%) overshoot %.3f energy %.2e hg/W %.2e steps %ld\n",
           hc->name, dim, nx, up, r.D, ref.us, 100 * eD, r.P, ref.p, 100 * eP, r.rho, ref.rho,
           100 * er, r.sxx_max / r.P, r.energy_err, r.hg_ratio, r.steps);
  free(r.profile);
  ms_ctx_close(&ctx);
  assert_true(fabs(eD) < tol);
  assert_true(fabs(eP) < tol);
  assert_true(fabs(er) < tol);
  /* the balance is exact up to round-off: 1e-6 of the work leaves ~1e10 ulp of room */
  assert_true(r.energy_err < 1e-6);
}

static int print_on(void) { return getenv("DM_HUGONIOT_PRINT") != NULL; }

static const double ups[] = {0.1, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0};

static void test_al_1d(void **state) {
  (void)state;
  hcase hc = {"Al", eos_create_mg_linear(2.703, 5.35, 1.34, 2.0)};
  /* 1 %: the criterion for D, P and rho behind the front */
  for (size_t j = 0; j < sizeof ups / sizeof *ups; ++j)
    run_case(&hc, 1, 400, 1, ups[j], 0.01, print_on());
  eos_destroy(hc.eos);
}

static void test_pb_1d(void **state) {
  (void)state;
  hcase hc = {"Pb", eos_create_mg_cold(11.34, 1.972, 3.0, 2.0, false)};
  for (size_t j = 0; j < sizeof ups / sizeof *ups; ++j)
    run_case(&hc, 1, 400, 1, ups[j], 0.01, print_on());
  eos_destroy(hc.eos);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_al_1d),
      cmocka_unit_test(test_pb_1d),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
