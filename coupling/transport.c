/* SPDX-License-Identifier: MIT */
/* Transport of detached fragments as point masses through the gas to a detector plane
 * (docs/design.md §6). Each fragment obeys
 *   dx/dt = v,   dv/dt = F_drag(x, v, t)/m,
 * which is stiff for micron-size fragments (τ = ρ_p d²/(18 μ) ≪ the flight time), so it is
 * integrated with CVODE's BDF method and a dense 6×6 Newton solve. Every fragment has its own
 * CVODE memory, kept between advance calls: its error control does not depend on the other
 * fragments, and a coupling loop may advance in short windows without restarting BDF.
 * Arrival is a CVODE root, n·x − x_det = 0 crossed upwards. */
#include "cpl_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

typedef struct flight_rec {
  cpl_flight fl;
  struct cpl_transport *tr;
  void *cvode;
  N_Vector y;
  SUNMatrix A;
  SUNLinearSolver LS;
  bool started; /* CVODE set up (lazily, on the first advance) */
} flight_rec;

struct cpl_transport {
  cpl_transport_opts o;
  cpl_gas_fn gas;
  void *gas_user;
  cpl_gas_return_fn ret;
  void *ret_user;
  SUNContext sunctx;
  size_t n, cap;
  flight_rec **rec;
  char err[256];
};

void cpl_transport_opts_default(cpl_transport_opts *o) {
  memset(o, 0, sizeof *o);
  o->law = CPL_DRAG_SCHILLER_NAUMANN;
  o->rho_p = 1.0;
  o->det_normal[0] = 1.0;
  o->det_x = INFINITY;
  o->rtol = 1e-8;
  o->atol_x = 1e-10;
  o->atol_v = 1e-10;
  o->max_steps = 100000;
}

ms_status cpl_transport_create(const cpl_transport_params *p, cpl_transport **out) {
  *out = NULL;
  if (!p->opts || !p->gas) return MS_ERR_INPUT;
  const cpl_transport_opts *o = p->opts;
  cpl_gas_fn gas = p->gas;
  void *gas_user = p->gas_user;
  cpl_transport *tr = ms_calloc(1, sizeof *tr);
  tr->o = *o;
  if (!(tr->o.rtol > 0)) tr->o.rtol = 1e-8;
  if (!(tr->o.atol_x > 0)) tr->o.atol_x = 1e-10;
  if (!(tr->o.atol_v > 0)) tr->o.atol_v = 1e-10;
  if (tr->o.max_steps <= 0) tr->o.max_steps = 100000;
  double nn = sqrt(o->det_normal[0] * o->det_normal[0] + o->det_normal[1] * o->det_normal[1] +
                   o->det_normal[2] * o->det_normal[2]);
  if (!(nn > 0)) {
    tr->o.det_normal[0] = 1;
    tr->o.det_normal[1] = tr->o.det_normal[2] = 0;
  } else {
    for (int a = 0; a < 3; a++) tr->o.det_normal[a] = o->det_normal[a] / nn;
  }
  tr->gas = gas;
  tr->gas_user = gas_user;
  if (SUNContext_Create(NULL, &tr->sunctx) != 0) {
    free(tr);
    return MS_ERR_SOLVER;
  }
  *out = tr;
  return MS_OK;
}

static void rec_free(flight_rec *r) {
  if (!r) return;
  if (r->cvode) CVodeFree(&r->cvode);
  if (r->LS) SUNLinSolFree(r->LS);
  if (r->A) SUNMatDestroy(r->A);
  if (r->y) N_VDestroy(r->y);
  free(r);
}

static void cpl_transport_free(cpl_transport *tr) {
  if (!tr) return;
  for (size_t i = 0; i < tr->n; i++) rec_free(tr->rec[i]);
  free(tr->rec);
  SUNContext_Free(&tr->sunctx);
  free(tr);
}

void cpl_transport_destroy(cpl_transport **tr) {
  if (!tr) return;
  cpl_transport_free(*tr);
  *tr = NULL;
}

void cpl_transport_set_return(cpl_transport *tr, cpl_gas_return_fn fn, void *user) {
  tr->ret = fn;
  tr->ret_user = user;
}

static double normal_dist(const cpl_transport *tr, const double x[3]) {
  const double *n = tr->o.det_normal;
  return n[0] * x[0] + n[1] * x[1] + n[2] * x[2] - tr->o.det_x;
}

size_t cpl_transport_add(cpl_transport *tr, double mass, const double x[3], const double v[3],
                         double t0) {
  if (tr->n == tr->cap) {
    tr->cap = tr->cap ? 2 * tr->cap : 64;
    tr->rec = ms_realloc(tr->rec, tr->cap, sizeof *tr->rec);
  }
  flight_rec *r = ms_calloc(1, sizeof *r);
  r->tr = tr;
  cpl_flight *f = &r->fl;
  f->mass = mass;
  f->diameter = cbrt(6.0 * mass / (CPL_PI * tr->o.rho_p));
  f->t = t0;
  for (int a = 0; a < 3; a++) {
    f->x[a] = x[a];
    f->v[a] = v[a];
    f->v_arrival[a] = NAN;
  }
  f->t_arrival = NAN;
  f->state = CPL_FLYING;
  if (normal_dist(tr, x) >= 0) { /* already beyond the detector */
    f->state = CPL_ARRIVED;
    f->t_arrival = t0;
    for (int a = 0; a < 3; a++) f->v_arrival[a] = v[a];
  }
  tr->rec[tr->n] = r;
  return tr->n++;
}

size_t cpl_transport_add_fragments(cpl_transport *tr, const cpl_fragments *f,
                                   const cpl_ejecta_sel *sel, double t0) {
  size_t big = sel && sel->exclude_largest ? cpl_largest_fragment(f) : (size_t)-1;
  size_t added = 0;
  for (size_t k = 0; k < f->n; k++) {
    if (sel && !cpl_is_ejecta_with(f, k, sel, big)) continue;
    double x[3] = {f->cx[k], f->cy[k], f->cz[k]}, v[3] = {f->vx[k], f->vy[k], f->vz[k]};
    cpl_transport_add(tr, f->mass[k], x, v, t0);
    added++;
  }
  return added;
}

/* CVODE right-hand side: y = (x, v). */
static int flight_rhs(realtype t, N_Vector y, N_Vector ydot, void *user) {
  flight_rec *r = user;
  const cpl_transport *tr = r->tr;
  const double *Y = N_VGetArrayPointer(y);
  double *D = N_VGetArrayPointer(ydot);
  double F[3] = {0, 0, 0};
  cpl_gas g;
  if (tr->gas && tr->gas(tr->gas_user, Y, t, &g))
    cpl_drag_force(tr->o.law, &g, r->fl.diameter, Y + 3, F);
  for (int a = 0; a < 3; a++) {
    D[a] = Y[3 + a];
    D[3 + a] = F[a] / r->fl.mass;
  }
  for (int a = 0; a < 6; a++)
    if (!isfinite(D[a])) return 1; /* recoverable: CVODE retries with a smaller step */
  return 0;
}

static int flight_root(realtype t, N_Vector y, realtype *g, void *user) {
  flight_rec *r = user;
  g[0] = normal_dist(r->tr, N_VGetArrayPointer(y));
  return 0;
}

static bool flight_start(cpl_transport *tr, flight_rec *r) {
  cpl_flight *f = &r->fl;
  r->y = N_VNew_Serial(6, tr->sunctx);
  if (!r->y) return false;
  double *Y = N_VGetArrayPointer(r->y);
  for (int a = 0; a < 3; a++) {
    Y[a] = f->x[a];
    Y[3 + a] = f->v[a];
  }
  r->cvode = CVodeCreate(CV_BDF, tr->sunctx);
  if (!r->cvode) return false;
  N_Vector atol = N_VNew_Serial(6, tr->sunctx);
  double *A = N_VGetArrayPointer(atol);
  for (int a = 0; a < 3; a++) {
    A[a] = tr->o.atol_x;
    A[3 + a] = tr->o.atol_v;
  }
  int rootdir = 1; /* only crossings towards the detector side */
  bool ok = CVodeInit(r->cvode, flight_rhs, f->t, r->y) == CV_SUCCESS &&
            CVodeSVtolerances(r->cvode, tr->o.rtol, atol) == CV_SUCCESS &&
            CVodeSetUserData(r->cvode, r) == CV_SUCCESS &&
            CVodeSetMaxNumSteps(r->cvode, tr->o.max_steps) == CV_SUCCESS &&
            CVodeRootInit(r->cvode, 1, flight_root) == CV_SUCCESS &&
            CVodeSetRootDirection(r->cvode, &rootdir) == CV_SUCCESS;
  N_VDestroy(atol);
  if (!ok) return false;
  r->A = SUNDenseMatrix(6, 6, tr->sunctx);
  r->LS = SUNLinSol_Dense(r->y, r->A, tr->sunctx);
  if (!r->A || !r->LS || CVodeSetLinearSolver(r->cvode, r->LS, r->A) != CV_SUCCESS) return false;
  r->started = true;
  return true;
}

/* Hand the momentum/energy change of one internal step to the gas. */
static void give_back(cpl_transport *tr, const flight_rec *r, double t0, const double x0[3],
                      const double v0[3]) {
  if (!tr->ret) return;
  const cpl_flight *f = &r->fl;
  double dp[3], xm[3], ke0 = 0, ke1 = 0;
  for (int a = 0; a < 3; a++) {
    dp[a] = f->mass * (f->v[a] - v0[a]);
    xm[a] = 0.5 * (x0[a] + f->x[a]);
    ke0 += v0[a] * v0[a];
    ke1 += f->v[a] * f->v[a];
  }
  tr->ret(tr->ret_user, xm, t0, f->t, dp, 0.5 * f->mass * (ke1 - ke0));
}

static ms_status advance_one(cpl_transport *tr, size_t i, double t_end) {
  flight_rec *r = tr->rec[i];
  cpl_flight *f = &r->fl;
  if (f->state != CPL_FLYING || f->t >= t_end) return MS_OK;
  if (!r->started && !flight_start(tr, r)) {
    f->state = CPL_FAILED;
    snprintf(tr->err, sizeof tr->err, "fragment %zu: cannot set up CVODE", i);
    return MS_ERR_SOLVER;
  }
  CVodeSetStopTime(r->cvode, t_end);
  double *Y = N_VGetArrayPointer(r->y);
  /* one internal step per call, so that momentum returned to the gas lands where it was lost */
  while (f->t < t_end) {
    double x0[3] = {f->x[0], f->x[1], f->x[2]}, v0[3] = {f->v[0], f->v[1], f->v[2]}, t0 = f->t;
    realtype tret = f->t;
    int flag = CVode(r->cvode, t_end, r->y, &tret, CV_ONE_STEP);
    if (flag < 0) {
      f->state = CPL_FAILED;
      snprintf(tr->err, sizeof tr->err, "fragment %zu: CVODE failed (flag %d) at t = %.6g", i, flag,
               f->t);
      return MS_ERR_SOLVER;
    }
    f->t = tret;
    for (int a = 0; a < 3; a++) {
      f->x[a] = Y[a];
      f->v[a] = Y[3 + a];
    }
    give_back(tr, r, t0, x0, v0);
    if (flag == CV_ROOT_RETURN) {
      f->state = CPL_ARRIVED;
      f->t_arrival = tret;
      for (int a = 0; a < 3; a++) f->v_arrival[a] = f->v[a];
      break;
    }
    if (flag == CV_TSTOP_RETURN) break;
  }
  long ns = 0;
  CVodeGetNumSteps(r->cvode, &ns);
  f->steps = ns;
  if (f->state == CPL_ARRIVED) {
    /* the fragment has left the run: release its solver memory */
    CVodeFree(&r->cvode);
    SUNLinSolFree(r->LS);
    SUNMatDestroy(r->A);
    N_VDestroy(r->y);
    r->cvode = NULL;
    r->LS = NULL;
    r->A = NULL;
    r->y = NULL;
  }
  return MS_OK;
}

ms_status cpl_transport_advance(cpl_transport *tr, double t_end) {
  ms_status worst = MS_OK;
  for (size_t i = 0; i < tr->n; i++) {
    ms_status s = advance_one(tr, i, t_end);
    if (s != MS_OK) worst = s;
  }
  return worst;
}

const char *cpl_transport_error(const cpl_transport *tr) { return tr->err; }
size_t cpl_transport_count(const cpl_transport *tr) { return tr->n; }
cpl_flight cpl_transport_get(const cpl_transport *tr, size_t i) { return tr->rec[i]->fl; }

void cpl_write_arrivals(FILE *out, const cpl_transport *tr, const char *title) {
  static const char *const names[] = {"id", "mass", "d", "t_arrival", "vx", "vy", "vz"};
  static const char *const units[] = {"1", "g", "cm", "10us", "km/s", "km/s", "km/s"};
  ms_csv_header(out, title ? title : "fragment arrivals at the detector plane", 7, names, units);
  for (size_t i = 0; i < tr->n; i++) {
    const cpl_flight *f = &tr->rec[i]->fl;
    if (f->state != CPL_ARRIVED) continue;
    fprintf(out, "%zu,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n", i, f->mass, f->diameter,
            ms_out_time(f->t_arrival), f->v_arrival[0], f->v_arrival[1], f->v_arrival[2]);
  }
}
