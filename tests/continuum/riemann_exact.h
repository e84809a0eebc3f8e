/* SPDX-License-Identifier: MIT */
/* riemann_exact.h — exact solution of the Riemann problem for an ideal gas (Toro, "Riemann
 * Solvers and Numerical Methods for Fluid Dynamics", ch. 4), written for the continuum tests. */
#ifndef CONT_TEST_RIEMANN_EXACT_H
#define CONT_TEST_RIEMANN_EXACT_H

#include <math.h>

typedef struct riemann_state {
  double rho, u, p;
} riemann_state;

/* Pressure function f_K(p) and its derivative for one side (Toro eq. 4.6–4.7). */
static void riemann_f(double p, const riemann_state *K, double g, double *f, double *df) {
  double c = sqrt(g * K->p / K->rho);
  if (p > K->p) { /* shock */
    double A = 2.0 / ((g + 1.0) * K->rho), B = (g - 1.0) / (g + 1.0) * K->p;
    double s = sqrt(A / (p + B));
    *f = (p - K->p) * s;
    *df = s * (1.0 - 0.5 * (p - K->p) / (B + p));
  } else { /* rarefaction */
    double pr = p / K->p;
    *f = 2.0 * c / (g - 1.0) * (pow(pr, (g - 1.0) / (2.0 * g)) - 1.0);
    *df = 1.0 / (K->rho * c) * pow(pr, -(g + 1.0) / (2.0 * g));
  }
}

/* Star-region pressure and velocity (Newton iteration from the two-rarefaction guess). */
static void riemann_star(const riemann_state *L, const riemann_state *R, double g, double *ps,
                         double *us) {
  double cL = sqrt(g * L->p / L->rho), cR = sqrt(g * R->p / R->rho);
  double z = (g - 1.0) / (2.0 * g);
  double p =
      pow((cL + cR - 0.5 * (g - 1.0) * (R->u - L->u)) / (cL / pow(L->p, z) + cR / pow(R->p, z)),
          1.0 / z);
  for (int it = 0; it < 100; ++it) {
    double fL, dL, fR, dR;
    riemann_f(p, L, g, &fL, &dL);
    riemann_f(p, R, g, &fR, &dR);
    double dp = (fL + fR + R->u - L->u) / (dL + dR);
    p -= dp;
    if (p < 1e-14) p = 1e-14;
    if (fabs(dp) < 1e-15 * p) break;
  }
  double fL, dL, fR, dR;
  riemann_f(p, L, g, &fL, &dL);
  riemann_f(p, R, g, &fR, &dR);
  *ps = p;
  *us = 0.5 * (L->u + R->u) + 0.5 * (fR - fL);
}

/* Solution at similarity coordinate s = (x − x0)/t (Toro §4.5 sampling). */
static riemann_state riemann_sample(const riemann_state *L, const riemann_state *R, double g,
                                    double ps, double us, double s) {
  riemann_state w;
  double gm = (g - 1.0) / (g + 1.0);
  if (s <= us) { /* left of the contact */
    double cL = sqrt(g * L->p / L->rho);
    if (ps > L->p) {
      double SL = L->u - cL * sqrt((g + 1.0) / (2.0 * g) * ps / L->p + (g - 1.0) / (2.0 * g));
      if (s <= SL) return *L;
      w.rho = L->rho * (ps / L->p + gm) / (gm * ps / L->p + 1.0);
      w.u = us;
      w.p = ps;
      return w;
    }
    double cs = cL * pow(ps / L->p, (g - 1.0) / (2.0 * g));
    double SH = L->u - cL, ST = us - cs;
    if (s <= SH) return *L;
    if (s >= ST) {
      w.rho = L->rho * pow(ps / L->p, 1.0 / g);
      w.u = us;
      w.p = ps;
      return w;
    }
    double f = 2.0 / (g + 1.0) + gm / cL * (L->u - s);
    w.rho = L->rho * pow(f, 2.0 / (g - 1.0));
    w.u = 2.0 / (g + 1.0) * (cL + 0.5 * (g - 1.0) * L->u + s);
    w.p = L->p * pow(f, 2.0 * g / (g - 1.0));
    return w;
  }
  double cR = sqrt(g * R->p / R->rho);
  if (ps > R->p) {
    double SR = R->u + cR * sqrt((g + 1.0) / (2.0 * g) * ps / R->p + (g - 1.0) / (2.0 * g));
    if (s >= SR) return *R;
    w.rho = R->rho * (ps / R->p + gm) / (gm * ps / R->p + 1.0);
    w.u = us;
    w.p = ps;
    return w;
  }
  double cs = cR * pow(ps / R->p, (g - 1.0) / (2.0 * g));
  double SH = R->u + cR, ST = us + cs;
  if (s >= SH) return *R;
  if (s <= ST) {
    w.rho = R->rho * pow(ps / R->p, 1.0 / g);
    w.u = us;
    w.p = ps;
    return w;
  }
  double f = 2.0 / (g + 1.0) - gm / cR * (R->u - s);
  w.rho = R->rho * pow(f, 2.0 / (g - 1.0));
  w.u = 2.0 / (g + 1.0) * (-cR + 0.5 * (g - 1.0) * R->u + s);
  w.p = R->p * pow(f, 2.0 * g / (g - 1.0));
  return w;
}

#endif
