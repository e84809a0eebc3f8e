/* SPDX-License-Identifier: MIT */
/* eos.c — dispatch through the ops table, the common domain policy, and numerical helpers
 * shared by the EOS kinds (cubic Hermite curves, isentrope tabulation, Brent's method). */
#include "eos_impl.h"

#include <stdlib.h>
#include <string.h>

eos_t *eos_alloc(eos_kind kind, const eos_ops *ops, double rho0, const void *data, size_t size) {
  eos_t *eos = ms_calloc(1, sizeof *eos);
  eos->kind = kind;
  eos->ops = ops;
  eos->rho0 = rho0;
  eos->c0 = NAN;
  eos->delta_min = 0.0;
  eos->delta_max = INFINITY;
  if (size > 0) {
    eos->data = ms_calloc(1, size);
    memcpy(eos->data, data, size);
  }
  return eos;
}

static void eos_release(eos_t *eos) {
  if (!eos) return;
  if (eos->ops && eos->ops->free_data) eos->ops->free_data(eos);
  eos_hermite_free(&eos->isentrope);
  free(eos->data);
  free(eos);
}

void eos_destroy(eos_t **eos) {
  if (!eos) return;
  eos_release(*eos);
  *eos = NULL;
}

eos_kind eos_get_kind(const eos_t *eos) { return eos->kind; }

const char *eos_kind_name(eos_kind k) {
  switch (k) {
  case EOS_MG_COLD:
    return "mg_cold";
  case EOS_MG_LINEAR:
    return "mg_linear";
  case EOS_IDEAL_GAS:
    return "ideal_gas";
  case EOS_TABLE_COLD:
    return "table_cold";
  case EOS_TABLE_FULL:
    return "table_full";
  case EOS_LINEAR_ELASTIC:
    return "linear_elastic";
  }
  return "unknown";
}

double eos_rho0(const eos_t *eos) { return eos->rho0; }
double eos_c0(const eos_t *eos) { return eos->c0; }
double eos_e0(const eos_t *eos) { return eos->e0; }

bool eos_has_cold_curve(const eos_t *eos) {
  return eos->ops->cold_pressure != NULL && !isnan(eos->delta_min);
}

bool eos_cold_range(const eos_t *eos, double *delta_min, double *delta_max) {
  bool has = eos_has_cold_curve(eos);
  if (delta_min) *delta_min = has ? eos->delta_min : NAN;
  if (delta_max) *delta_max = has ? eos->delta_max : NAN;
  return has;
}

double eos_pressure(const eos_t *eos, double rho, double e) {
  if (!(rho > 0.0) || !isfinite(e)) return NAN;
  return eos->ops->pressure(eos, rho, e);
}

/* Sound speed with the floor of docs/eos.md: c ≥ EOS_C_FLOOR_FRACTION·c0 inside the domain. */
static double sound_speed_policy(const eos_t *eos, double c2) {
  if (isnan(c2)) return NAN;
  double floor = EOS_C_FLOOR_FRACTION * eos->c0;
  if (!(floor > 0.0)) floor = 1e-12; /* EOS without a reference speed: c stays positive */
  return c2 > floor * floor ? sqrt(c2) : floor;
}

double eos_sound_speed(const eos_t *eos, double rho, double e) {
  if (!(rho > 0.0) || !isfinite(e)) return NAN;
  return sound_speed_policy(eos, eos->ops->sound_speed2(eos, rho, e));
}

double eos_cold_pressure(const eos_t *eos, double delta) {
  if (!eos_has_cold_curve(eos) || !(delta > 0.0) ||
      !(delta >= eos->delta_min && delta <= eos->delta_max))
    return NAN;
  return eos->ops->cold_pressure(eos, delta);
}

double eos_cold_energy(const eos_t *eos, double delta) {
  if (!eos_has_cold_curve(eos) || !(delta > 0.0) ||
      !(delta >= eos->delta_min && delta <= eos->delta_max))
    return NAN;
  return eos->ops->cold_energy(eos, delta);
}

/* With a constant heat capacity the thermal energy above the 0 K curve is cv T: the cold curve
 * ε_x (the 0 K isotherm, which is also the T = 0 isentrope, so the tabulated isentropes of the
 * Us–up form and of tables qualify) gives T = (e − ε_x(δ))/cv; for an ideal gas T = e/cv. */
double eos_temperature(const eos_t *eos, double rho, double e) {
  if (!(rho > 0.0) || !(eos->cv > 0.0)) return NAN;
  if (eos->ops->temperature) return eos->ops->temperature(eos, rho, e);
  if (isnan(eos_pressure(eos, rho, e))) return NAN;
  return (e - eos_cold_energy(eos, rho / eos->rho0)) / eos->cv;
}

ms_status eos_set_heat_capacity(eos_t *eos, double cv) {
  if (!(cv > 0.0) || !isfinite(cv)) return MS_ERR_INPUT;
  eos->cv = cv;
  return MS_OK;
}

ms_status eos_eval(const eos_t *eos, size_t n, const double *rho, const double *e, double *p,
                   double *c, size_t *bad) {
  const eos_ops *ops = eos->ops;
  if (ops->eval_array) {
    /* one vectorized pass (c holds c² until the sound-speed policy is applied), then a scan
     * for the first state outside the domain */
    ops->eval_array(eos, n, rho, e, p, c);
    double floor = EOS_C_FLOOR_FRACTION * eos->c0;
    if (!(floor > 0.0)) floor = 1e-12;
    const double floor2 = floor * floor;
    if (c)
      for (size_t i = 0; i < n; ++i) {
        double c2 = c[i];
        c[i] = isnan(c2) ? NAN : c2 > floor2 ? sqrt(c2) : floor;
      }
    /* a branch-free count first (it vectorizes), the scan for the first bad state only then */
    size_t nbad = 0;
    for (size_t i = 0; i < n; ++i)
      nbad += !(rho[i] > 0.0) | !isfinite(e[i]) | isnan(p[i]) | (c != NULL && isnan(c[i]));
    if (nbad == 0) return MS_OK;
    for (size_t i = 0; i < n; ++i) {
      if (!(rho[i] > 0.0) || !isfinite(e[i]) || isnan(p[i]) || (c && isnan(c[i]))) {
        p[i] = NAN;
        if (bad) *bad = i;
        return MS_ERR_UNSTABLE;
      }
    }
    return MS_OK;
  }
  for (size_t i = 0; i < n; ++i) {
    double r = rho[i], ei = e[i], pi = NAN, c2 = NAN;
    if (r > 0.0 && isfinite(ei)) {
      if (c && ops->eval) {
        ops->eval(eos, r, ei, &pi, &c2);
      } else {
        pi = ops->pressure(eos, r, ei);
        if (c && !isnan(pi)) c2 = ops->sound_speed2(eos, r, ei);
      }
    }
    p[i] = pi;
    if (c) c[i] = isnan(pi) ? NAN : sound_speed_policy(eos, c2);
    if (isnan(pi) || (c && isnan(c[i]))) {
      if (bad) *bad = i;
      return MS_ERR_UNSTABLE;
    }
  }
  return MS_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Mie–Grüneisen around a cold curve.                                                          */

double eos_mg_pressure_from_cold(const eos_gruneisen *g, double rho, double e, double px,
                                 double ex) {
  return px + eos_gruneisen_G(g, rho) * (e - ex);
}

/* P = P_x(δ) + G(ρ)(e − ε_x(δ)) with dε_x/dρ = P_x/ρ² gives
 *   ∂P/∂ρ|_e = P_x'/ρ0 + G'(e − ε_x) − G P_x/ρ²,  ∂P/∂e|_ρ = G,
 *   c² = ∂P/∂ρ|_e + (P/ρ²)G = P_x'/ρ0 + (e − ε_x)(G' + G²/ρ²). */
double eos_mg_c2_from_cold(const eos_gruneisen *g, double rho0, double rho, double e, double dpx,
                           double ex) {
  double G = eos_gruneisen_G(g, rho);
  return dpx / rho0 + (e - ex) * (eos_gruneisen_dG(g) + G * G / (rho * rho));
}

/* ------------------------------------------------------------------------------------------ */
/* Cubic Hermite curves.                                                                       */

bool eos_hermite_eval(const eos_hermite *h, double x, double *y, double *dy, double *d2y) {
  size_t n = h->n;
  if (n < 2 || !(x >= h->x[0] && x <= h->x[n - 1])) {
    if (y) *y = NAN;
    if (dy) *dy = NAN;
    if (d2y) *d2y = NAN;
    return false;
  }
  size_t lo = 0, hi = n - 1; /* invariant x[lo] <= x <= x[hi] */
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (h->x[mid] <= x) lo = mid;
    else hi = mid;
  }
  double dx = h->x[hi] - h->x[lo], t = (x - h->x[lo]) / dx;
  double y0 = h->y[lo], y1 = h->y[hi], m0 = h->dy[lo] * dx, m1 = h->dy[hi] * dx;
  double t2 = t * t, t3 = t2 * t;
  if (y)
    *y = (2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * y1 +
         (t3 - t2) * m1;
  if (dy)
    *dy = ((6 * t2 - 6 * t) * y0 + (3 * t2 - 4 * t + 1) * m0 + (-6 * t2 + 6 * t) * y1 +
           (3 * t2 - 2 * t) * m1) /
          dx;
  if (d2y)
    *d2y =
        ((12 * t - 6) * y0 + (6 * t - 4) * m0 + (-12 * t + 6) * y1 + (6 * t - 2) * m1) / (dx * dx);
  return true;
}

void eos_hermite_free(eos_hermite *h) {
  free(h->x);
  free(h->y);
  free(h->dy);
  memset(h, 0, sizeof *h);
}

/* ------------------------------------------------------------------------------------------ */
/* The isentrope through (ρ0, 0) as cold curve: dε/dδ = P(ρ0δ, ε)/(ρ0δ²).                       */

static double isentrope_slope(const eos_t *eos, double delta, double eps) {
  double p = eos->ops->pressure(eos, eos->rho0 * delta, eps);
  return p / (eos->rho0 * delta * delta);
}

/* RK4 from δ = 1 towards `dend` in `nstep` steps; writes nodes (δ, ε, dε/dδ) into the arrays
 * (first node δ = 1). Returns the number of nodes written (stops where the EOS is undefined). */
static size_t integrate_isentrope(const eos_t *eos, double dend, size_t nstep, double *x, double *y,
                                  double *dy) {
  double h = (dend - 1.0) / (double)nstep, d = 1.0, eps = 0.0;
  double k1 = isentrope_slope(eos, d, eps);
  if (!isfinite(k1)) return 0;
  x[0] = d, y[0] = eps, dy[0] = k1;
  size_t m = 1;
  for (size_t i = 0; i < nstep; ++i) {
    double k2 = isentrope_slope(eos, d + 0.5 * h, eps + 0.5 * h * k1);
    double k3 = isentrope_slope(eos, d + 0.5 * h, eps + 0.5 * h * k2);
    double k4 = isentrope_slope(eos, d + h, eps + h * k3);
    double eps_new = eps + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    double d_new = 1.0 + (double)(i + 1) * h;
    double k_new = isentrope_slope(eos, d_new, eps_new);
    if (!isfinite(eps_new) || !isfinite(k_new)) break;
    d = d_new, eps = eps_new, k1 = k_new;
    x[m] = d, y[m] = eps, dy[m] = k1;
    ++m;
  }
  return m;
}

/* If the isentrope leaves the domain on one side right away (e.g. a table whose e range starts
 * at 0 while the isentrope dips below 0 near ρ0), the cold curve covers the other side only. */
ms_status eos_build_isentrope_cold(eos_t *eos, double dmin, double dmax, size_t nstep) {
  double *xs = ms_calloc(nstep + 1, sizeof *xs), *ys = ms_calloc(nstep + 1, sizeof *ys),
         *ds = ms_calloc(nstep + 1, sizeof *ds);
  double *xc = ms_calloc(nstep + 1, sizeof *xc), *yc = ms_calloc(nstep + 1, sizeof *yc),
         *dc = ms_calloc(nstep + 1, sizeof *dc);
  size_t ns = integrate_isentrope(eos, dmin, nstep, xs, ys, ds); /* tension side */
  size_t nc = integrate_isentrope(eos, dmax, nstep, xc, yc, dc); /* compression side */
  ms_status st = MS_OK;
  eos_hermite_free(&eos->isentrope);
  if (ns < 1 || nc < 1 || ns + nc < 3) {
    st = MS_ERR_INPUT; /* (ρ0, 0) is outside the domain, or nothing around it is inside */
    eos->delta_min = eos->delta_max = NAN;
  } else {
    eos_hermite *h = &eos->isentrope;
    h->n = ns + nc - 1;
    h->x = ms_calloc(h->n, sizeof *h->x);
    h->y = ms_calloc(h->n, sizeof *h->y);
    h->dy = ms_calloc(h->n, sizeof *h->dy);
    size_t k = 0;
    for (size_t i = ns; i-- > 1;) h->x[k] = xs[i], h->y[k] = ys[i], h->dy[k] = ds[i], ++k;
    for (size_t i = 0; i < nc; ++i) h->x[k] = xc[i], h->y[k] = yc[i], h->dy[k] = dc[i], ++k;
    eos->delta_min = h->x[0];
    eos->delta_max = h->x[h->n - 1];
  }
  free(xs), free(ys), free(ds), free(xc), free(yc), free(dc);
  return st;
}

double eos_isentrope_cold_energy(const eos_t *eos, double delta) {
  double y;
  eos_hermite_eval(&eos->isentrope, delta, &y, NULL, NULL);
  return y;
}

double eos_isentrope_cold_pressure(const eos_t *eos, double delta) {
  double y = eos_isentrope_cold_energy(eos, delta);
  return isnan(y) ? NAN : eos->ops->pressure(eos, eos->rho0 * delta, y);
}

/* ------------------------------------------------------------------------------------------ */
/* Brent's method (inverse quadratic interpolation safeguarded by bisection).                  */

double eos_brent(double (*f)(double x, void *user), void *user, double a, double b, double fa,
                 double fb, double xtol, int maxit) {
  if (isnan(fa) || isnan(fb) || (fa > 0) == (fb > 0)) {
    if (fa == 0.0) return a;
    if (fb == 0.0) return b;
    return NAN;
  }
  double c = a, fc = fa, d = b - a, e = d;
  for (int it = 0; it < maxit; ++it) {
    if ((fb > 0) == (fc > 0)) c = a, fc = fa, d = e = b - a;
    if (fabs(fc) < fabs(fb)) a = b, b = c, c = a, fa = fb, fb = fc, fc = fa;
    double tol = 2.0 * 2.2e-16 * fabs(b) + 0.5 * xtol, m = 0.5 * (c - b);
    if (fabs(m) <= tol || fb == 0.0) return b;
    if (fabs(e) >= tol && fabs(fa) > fabs(fb)) {
      double s = fb / fa, p, q;
      if (a == c) {
        p = 2.0 * m * s, q = 1.0 - s;
      } else {
        double r = fb / fc;
        q = fa / fc;
        p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0));
        q = (q - 1.0) * (r - 1.0) * (s - 1.0);
      }
      if (p > 0) q = -q;
      else p = -p;
      if (2.0 * p < fmin(3.0 * m * q - fabs(tol * q), fabs(e * q))) {
        e = d, d = p / q;
      } else {
        d = m, e = m;
      }
    } else {
      d = m, e = m;
    }
    a = b, fa = fb;
    b += fabs(d) > tol ? d : (m > 0 ? tol : -tol);
    fb = f(b, user);
    if (isnan(fb)) return NAN;
  }
  return b;
}
