/* SPDX-License-Identifier: MIT */
/* dm_exact.c — exact reference solutions of [Sofronov] §5 (units g, cm, 10 µs). */
#include "dm.h"

#include <math.h>

/* Odd, 4L-periodic extension of the triangle εx (0<x<L), ε(2L−x) (L<x<2L): fixed ends at 0
 * and 2L make the displacement odd about both. */
static double triangle_ext(double y, double L, double eps) {
  double P = 4.0 * L;
  y = fmod(y + L, P);
  if (y < 0) y += P;
  y -= L; /* y in [−L, 3L) */
  return y <= L ? eps * y : eps * (2.0 * L - y);
}

double dm_exact_rod_triangle(double x, double t, double L, double eps, double c, int nterms) {
  if (nterms <= 0) /* d'Alembert: w = ½[W(x − ct) + W(x + ct)], exact, no truncation */
    return 0.5 * (triangle_ext(x - c * t, L, eps) + triangle_ext(x + c * t, L, eps));
  /* [Sofronov] §5.1 series: w = 8εL/π² Σ (−1)ⁿ/(2n+1)² sin((2n+1)πx/2L) cos((2n+1)πct/2L) */
  double sum = 0.0;
  for (int n = nterms - 1; n >= 0; --n) {
    double m = 2.0 * n + 1.0;
    sum += (n % 2 ? -1.0 : 1.0) / (m * m) * sin(m * M_PI * x / (2.0 * L)) *
           cos(m * M_PI * c * t / (2.0 * L));
  }
  return 8.0 * eps * L / (M_PI * M_PI) * sum;
}

double dm_exact_rod_sine(double x, double t, double L, double eps, double c) {
  return eps * L * sin(M_PI * x / (2.0 * L)) * cos(M_PI * c * t / (2.0 * L));
}

/* Initial stress of §5.2: σ0(y) = E1 ε k cos(k y), k = 8π/L (w = ε sin(k y), extended oddly
 * about x = 0 by the fixed end, so the same formula holds for y < 0). */
double dm_exact_contact_stress(double x, double t, double L, double eps, double rho1, double E1,
                               double rho2, double E2) {
  const double k = 8.0 * M_PI / L;
  const double c1 = sqrt(E1 / rho1), c2 = sqrt(E2 / rho2);
  const double Z1 = rho1 * c1, Z2 = rho2 * c2;
  const double refl = (Z2 - Z1) / (Z1 + Z2), trans = 2.0 * Z2 / (Z1 + Z2);
  const double S = E1 * eps * k;
#define SIGMA0(y) (S * cos(k * (y)))
  if (x < L) {
    double right = 0.5 * SIGMA0(x - c1 * t); /* right-going half of the initial data */
    double y = x + c1 * t;                   /* where the left-going part started */
    double left = y < L ? 0.5 * SIGMA0(y)
                        /* reflected at the contact: the incident half that reached x = L at
                         * time t − (L − x)/c1 started at 2L − x − c1 t */
                        : refl * 0.5 * SIGMA0(2.0 * L - y);
    return right + left;
  }
  double tau = t - (x - L) / c2; /* time the transmitted signal left the contact */
  if (tau < 0) return 0.0;
  return trans * 0.5 * SIGMA0(L - c1 * tau);
#undef SIGMA0
}

/* [Sofronov] §5.3: Φ(τ) and its derivatives for f(t) = w0(1 − cos ωt), α = ωr0/C. */
void dm_exact_sphere(double r, double t, double r0, double w0, double period, double cl, double *w,
                     double *u) {
  const double om = 2.0 * M_PI / period, al = om * r0 / cl;
  const double tau = t - (r - r0) / cl;
  if (tau < 0) {
    *w = 0.0;
    *u = 0.0;
    return;
  }
  const double ex = exp(-cl * tau / r0), co = cos(om * tau), si = sin(om * tau);
  const double a2 = al * al, d = 1.0 + a2;
  const double phi = -r0 * r0 * w0 / d * (d - a2 * ex - co - al * si);
  const double phi1 = -r0 * w0 * cl / d * (a2 * ex + al * si - a2 * co);
  const double phi2 = -w0 * cl * cl / d * (-a2 * ex + a2 * co + al * a2 * si);
  *w = -(phi + r / cl * phi1) / (r * r);
  *u = -(phi1 + r / cl * phi2) / (r * r);
}
