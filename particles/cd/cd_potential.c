/* SPDX-License-Identifier: MIT */
/* cd_potential.c — pair potentials from an EOS cold curve ([Davydov] eqs. 1–2, docs/design.md §5.1).
 *
 * fcc (12 neighbours, 6 bonds per particle, volume per particle r0³/√2):
 *   $E(r) = \frac{\sqrt2 \rho_0 r_0^3}{12}\,\varepsilon_x(\delta)$, $\delta = (r_0/r)^3$,
 *   $f(r) = -E'(r) = \frac{\sqrt2}{4} r^2 P_x(\delta)$   (f > 0 repulsive).
 * 2D triangular lattice (6 neighbours, 3 bonds per particle, area (√3/2) r0², thickness h):
 *   m = ρ0 (√3/2) r0² h, $E(r) = \frac{m}{3}\varepsilon_x(\delta)$, $\delta = (r_0/r)^2$,
 *   $f(r) = -E'(r) = \frac{r h}{\sqrt3} P_x(\delta)$,
 * derived in docs/particles-cd.md: dE/dr = (m/3) ε_x'(δ) dδ/dr with ε_x' = P_x/(ρ0 δ²) and
 * dδ/dr = −2δ/r; a uniformly strained lattice then has virial pressure exactly P_x(δ).
 *
 * Tabulation: cubic Hermite interpolation of E in s = r² on a uniform s-grid, with the exact
 * values E(s_k) and slopes dE/ds = −f/(2r) at the nodes. The force used by the kernels is
 * F/r = −2 dE/ds of the same cubic (a quadratic in t), so energy and force are exactly
 * consistent and no square root is needed. r0² is a node, where E = F = 0 exactly.
 * With the default 4096 intervals on [(0.5 r0)², R_c²] the force agrees with the formula to
 * ~1e-10 of max|f| (tests/cd/test_cd_potential.c).
 */
#include "cd_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double cd_cluster_volume(cd_lattice lat, double r0, double thickness) {
  if (lat == CD_LATTICE_TRI2D) return 0.5 * sqrt(3.0) * r0 * r0 * thickness;
  return r0 * r0 * r0 / sqrt(2.0);
}

double cd_particle_bytes(cd_lattice lat, double reach) {
  /* lattice sites within `reach` r0 of a site: sphere or disc × sites per r0^dim
   * (fcc √2, triangular 2/√3), 8 B per neighbour-list entry */
  double entries = lat == CD_LATTICE_FCC ? 4.0 / 3.0 * M_PI * pow(reach, 3) * sqrt(2.0)
                                         : M_PI * reach * reach * 2.0 / sqrt(3.0);
  return 300.0 + 8.0 * entries;
}

static double lattice_delta(cd_lattice lat, double r0, double r) {
  double q = r0 / r;
  return lat == CD_LATTICE_TRI2D ? q * q : q * q * q;
}

double cd_pair_energy_exact(const eos_t *eos, cd_lattice lat, double r0, double thickness,
                            double r) {
  double m = eos_rho0(eos) * cd_cluster_volume(lat, r0, thickness);
  double bonds = lat == CD_LATTICE_TRI2D ? 3.0 : 6.0; /* bonds per particle */
  return m / bonds * eos_cold_energy(eos, lattice_delta(lat, r0, r));
}

double cd_pair_force_exact(const eos_t *eos, cd_lattice lat, double r0, double thickness,
                           double r) {
  double px = eos_cold_pressure(eos, lattice_delta(lat, r0, r));
  if (lat == CD_LATTICE_TRI2D) return r * thickness * px / sqrt(3.0);
  return sqrt(2.0) / 4.0 * r * r * px;
}

/* E and dE/ds of the mixed potential at s (before tabulation). */
static void mixed_e_des(const eos_t *a, const eos_t *b, cd_lattice lat, double r0, double h,
                        double attraction, double s, double *e, double *des) {
  double r = sqrt(s);
  double ea = cd_pair_energy_exact(a, lat, r0, h, r);
  double fa = cd_pair_force_exact(a, lat, r0, h, r);
  if (b != a) {
    ea = 0.5 * (ea + cd_pair_energy_exact(b, lat, r0, h, r));
    fa = 0.5 * (fa + cd_pair_force_exact(b, lat, r0, h, r));
    /* Beyond r0 the mixed pair is attractive; scaling E there by `attraction` keeps E and
     * f continuous at r0 (both vanish there). */
    if (r > r0) {
      ea *= attraction;
      fa *= attraction;
    }
  }
  *e = ea;
  *des = -fa / (2.0 * r);
}

/* ---- Fit: F/r as 16 polynomials in s, for the forces-only fast path (cd_force.c) ----
 *
 * The table's F/r is a quadratic per 1/4096 of the s range, so a vectorised kernel would have
 * to gather three coefficients per pair from 128 KB; the fit's coefficients fit in registers.
 * Segment k is the set of doubles sharing the bits above CD_FIT_SHIFT (exponent and the top
 * three mantissa bits: 8 segments per octave, each 1/8–1/16 of its s wide), so the index is one
 * shift and the segment centre c_k one bit operation, and the 16 segments below R_c² (two
 * octaves: R_c/2 .. R_c) are told apart by k mod 16 (a register permute). On each segment,
 * Chebyshev interpolation of the exact F/r = −2 dE/ds (mixed_e_des) at deg + 1 nodes, rewritten
 * as monomials in t = s − c_k; the lowest degree whose error on a dense grid is below
 * 1e-12 of max|F/r| on the fitted range is kept (degree 9 for the benchmark's aluminium,
 * error 4e-13). The fit must also agree with the table's F/r to 1e-9 of max|F/r| over
 * [s_lo, R_c²] (the table's own accuracy: test_cd_potential); otherwise fit_ok stays false. */

static uint64_t dbits(double x) {
  uint64_t b;
  memcpy(&b, &x, sizeof b);
  return b;
}

static double bitsd(uint64_t b) {
  double x;
  memcpy(&x, &b, sizeof x);
  return x;
}

/* The table's F/r at s < rc2 (the kernels' arithmetic, cd_force.c). */
static double table_fr(const cd_pair_table *t, double s) {
  const double *c = t->fcoef;
  if (s < t->s_lo) return fma((s - t->s_lo) * t->inv_h, c[1], c[0]);
  double u = (s - t->s_lo) * t->inv_h;
  int m = (int)u;
  double w = u - m;
  c += 4 * m;
  return fma(w, fma(w, c[2], c[1]), c[0]);
}

static double exact_fr(const eos_t *a, const eos_t *b, cd_lattice lat, double r0, double h,
                       double attraction, double s) {
  double e, des;
  mixed_e_des(a, b, lat, r0, h, attraction, s, &e, &des);
  return -2.0 * des;
}

/* Interpolate F/r on [lo, hi] at deg + 1 Chebyshev nodes; monomial coefficients in t = s − c
 * into m[0..deg] (long double: the basis change loses a few digits otherwise). */
static void fit_segment(const eos_t *a, const eos_t *b, cd_lattice lat, double r0, double h,
                        double attraction, double lo, double hi, double c, int deg, double *m) {
  const int nn = deg + 1;
  long double f[CD_FIT_MAXDEG + 1], ch[CD_FIT_MAXDEG + 1];
  const long double mid = 0.5L * ((long double)lo + hi), half = 0.5L * ((long double)hi - lo);
  for (int j = 0; j < nn; j++) {
    long double u = cosl(3.14159265358979323846264338327950288L * (j + 0.5L) / nn);
    f[j] = exact_fr(a, b, lat, r0, h, attraction, (double)(mid + half * u));
  }
  for (int i = 0; i < nn; i++) { /* ch_i = (2/N) Σ_j f_j T_i(u_j), ch_0 halved */
    long double acc = 0.0L;
    for (int j = 0; j < nn; j++)
      acc += f[j] * cosl(3.14159265358979323846264338327950288L * i * (j + 0.5L) / nn);
    ch[i] = (i == 0 ? 1.0L : 2.0L) * acc / nn;
  }
  /* Σ ch_i T_i(u) with u = α t + β (α = 1/half, β = (c − mid)/half), as a polynomial in t:
   * T_0 = 1, T_1 = u, T_{i+1} = 2u T_i − T_{i−1} */
  const long double al = 1.0L / half, be = ((long double)c - mid) / half;
  long double tm[CD_FIT_MAXDEG + 2] = {1.0L}, tc[CD_FIT_MAXDEG + 2] = {0}, tn[CD_FIT_MAXDEG + 2];
  long double acc[CD_FIT_MAXDEG + 1] = {0};
  tc[0] = be; /* T_1 = β + α t */
  tc[1] = al;
  acc[0] = ch[0];
  for (int i = 1; i < nn; i++) {
    for (int p = 0; p <= i; p++) acc[p] += ch[i] * tc[p];
    if (i + 1 < nn) { /* tn = 2(β + α t) tc − tm */
      for (int p = 0; p <= i + 1; p++)
        tn[p] = 2.0L * (be * (p <= i ? tc[p] : 0.0L) + (p > 0 ? al * tc[p - 1] : 0.0L)) -
                (p <= i - 1 ? tm[p] : 0.0L);
      for (int p = 0; p <= i + 1; p++) {
        tm[p] = p <= i ? tc[p] : 0.0L;
        tc[p] = tn[p];
      }
    }
  }
  for (int p = 0; p <= deg; p++) m[p] = (double)acc[p];
}

static void pair_fit_build(cd_pair_table *t, const eos_t *a, const eos_t *b, cd_lattice lat,
                           double r0, double h, double attraction) {
  t->fit_ok = false;
  const uint64_t sh = CD_FIT_SHIFT;
  uint64_t khi = dbits(t->rc2) >> sh;
  if ((dbits(t->rc2) & ((UINT64_C(1) << sh) - 1)) == 0) khi--; /* s < rc2 never reaches it */
  uint64_t klo = dbits(t->s_lo) >> sh;
  if (khi - klo >= CD_FIT_NSEG) klo = khi - (CD_FIT_NSEG - 1);
  const double slo = fmax(bitsd(klo << sh), t->s_lo);
  /* error scale: max |F/r| over the fitted range and over the table */
  double fmax_fit = 0.0, fmax_tab = 0.0;
  for (int k = 0; k <= 4096; k++) {
    const double s = t->s_lo + (t->rc2 - t->s_lo) * k / 4096.0;
    const double fr = fabs(table_fr(t, fmin(s, nextafter(t->rc2, 0.0))));
    fmax_tab = fmax(fmax_tab, fr);
    if (s >= slo) fmax_fit = fmax(fmax_fit, fabs(exact_fr(a, b, lat, r0, h, attraction, s)));
  }
  fmax_fit = fmax(fmax_fit, fabs(exact_fr(a, b, lat, r0, h, attraction, slo)));
  if (!(fmax_fit > 0.0) || !isfinite(fmax_fit)) return;
  enum { NCHECK = 256 }; /* dense grid per segment, ends included */
  for (int deg = 4; deg <= CD_FIT_MAXDEG; deg++) {
    double worst = 0.0, worst_tab = 0.0;
    t->fit_deg = deg;
    for (uint64_t k = klo; k <= khi; k++) {
      const double lo = fmax(bitsd(k << sh), slo), hi = fmin(bitsd((k + 1) << sh), t->rc2);
      const double c = bitsd((k << sh) | (UINT64_C(1) << (sh - 1)));
      double m[CD_FIT_MAXDEG + 1];
      fit_segment(a, b, lat, r0, h, attraction, lo, hi, c, deg, m);
      for (int p = 0; p <= CD_FIT_MAXDEG; p++)
        t->fit_coef[p][k % CD_FIT_NSEG] = p <= deg ? m[p] : 0.0;
      for (int q = 0; q <= NCHECK; q++) {
        const double s = q == NCHECK ? nextafter(hi, 0.0) : lo + (hi - lo) * q / NCHECK;
        const double fit = cd_pair_fit_eval(t, s), ex = exact_fr(a, b, lat, r0, h, attraction, s);
        const double tab = table_fr(t, s);
        if (!isfinite(fit)) worst = INFINITY;
        worst = fmax(worst, fabs(fit - ex));
        worst_tab = fmax(worst_tab, fabs(fit - tab));
      }
    }
    if (worst <= 1e-12 * fmax_fit) {
      t->fit_slo = slo;
      t->fit_ok = worst_tab <= 1e-9 * fmax_tab;
      return;
    }
  }
}

double cd_pair_fit_eval(const cd_pair_table *t, double s) { return cd_fit_eval(t, s); }

ms_status cd_pair_table_build(cd_pair_table *t, const eos_t *a, const eos_t *b, cd_lattice lat,
                              double r0, double thickness, double rc, double r_min,
                              double attraction, int nint) {
  *t = (cd_pair_table){0};
  if (!a || !b || !eos_has_cold_curve(a) || !eos_has_cold_curve(b)) return MS_ERR_INPUT;
  if (!(rc > r0) || !(r_min > 0) || !(r_min < r0)) return MS_ERR_INPUT;
  if (nint <= 0) nint = 4096;
  /* Clamp r_min to the cold curves' δ range. */
  const eos_t *ab[2] = {a, b};
  for (int k = 0; k < 2; k++) {
    double dmin, dmax;
    if (eos_cold_range(ab[k], &dmin, &dmax)) {
      if (isfinite(dmax) && dmax > 1.0) {
        double rmin_k = lat == CD_LATTICE_TRI2D ? r0 / sqrt(dmax) : r0 / cbrt(dmax);
        if (r_min < rmin_k) r_min = rmin_k * (1.0 + 1e-12);
      }
      if (isfinite(dmin) && dmin > 0.0) {
        double rmax_k = lat == CD_LATTICE_TRI2D ? r0 / sqrt(dmin) : r0 / cbrt(dmin);
        if (rc > rmax_k * (1.0 - 1e-12)) return MS_ERR_INPUT; /* cold curve does not reach R_c */
      }
    }
  }
  double s0 = r0 * r0, shi = rc * rc, slo_want = r_min * r_min;
  /* uniform grid with r0² on a node: h = (R_c² − r0²)/m_hi, s_lo = r0² − m_lo h */
  double frac_hi = (shi - s0) / (shi - slo_want);
  int m_hi = (int)ceil(frac_hi * nint);
  if (m_hi < 1) m_hi = 1;
  double hs = (shi - s0) / m_hi;
  int m_lo = (int)floor((s0 - slo_want) / hs); /* s_lo >= r_min² stays in the EOS range */
  t->nint = m_lo + m_hi;
  t->h = hs;
  t->inv_h = 1.0 / hs;
  t->s_lo = s0 - m_lo * hs;
  t->rc = rc;
  t->rc2 = shi;
  t->r0 = r0;
  /* one spare interval on top: the last cubic re-centred at t = 1 (lookups of s rounding onto
   * rc² land there and see the same polynomial) */
  t->fcoef = ms_aligned_alloc((size_t)(t->nint + 1) * 4, sizeof(double));
  t->ecoef = ms_aligned_alloc((size_t)(t->nint + 1) * 4, sizeof(double));
  double e_prev = 0, d_prev = 0;
  for (int k = 0; k <= t->nint; k++) {
    double s = k == m_lo ? s0 : (k == t->nint ? shi : t->s_lo + k * hs);
    double e, des;
    mixed_e_des(a, b, lat, r0, thickness, attraction, s, &e, &des);
    if (k == m_lo) e = des = 0.0; /* exact at rest: ε_x(1) = P_x(1) = 0 */
    if (!isfinite(e) || !isfinite(des)) {
      cd_pair_table_free(t);
      return MS_ERR_INPUT;
    }
    des *= hs; /* slope per unit t */
    if (k > 0) {
      /* Hermite cubic on t in [0,1]: E = e0 + t(m0 + t(c2 + t c3)) */
      double e0 = e_prev, m0 = d_prev, e1 = e, m1 = des;
      double c2 = 3.0 * (e1 - e0) - 2.0 * m0 - m1;
      double c3 = 2.0 * (e0 - e1) + m0 + m1;
      double *ec = t->ecoef + 4 * (k - 1), *fc = t->fcoef + 4 * (k - 1);
      ec[0] = e0;
      ec[1] = m0;
      ec[2] = c2;
      ec[3] = c3;
      /* F/r = −2 dE/ds = −(2/h) dE/dt = −(2/h)(m0 + 2 c2 t + 3 c3 t²) */
      double g = -2.0 / hs;
      fc[0] = g * m0;
      fc[1] = g * 2.0 * c2;
      fc[2] = g * 3.0 * c3;
      fc[3] = 0.0;
    }
    e_prev = e;
    d_prev = des;
  }
  t->e_rc = e_prev;
  {
    const double *e = t->ecoef + 4 * (t->nint - 1), *f = t->fcoef + 4 * (t->nint - 1);
    double *E = t->ecoef + 4 * t->nint, *F = t->fcoef + 4 * t->nint;
    E[0] = e[0] + e[1] + e[2] + e[3];
    E[1] = e[1] + 2.0 * e[2] + 3.0 * e[3];
    E[2] = e[2] + 3.0 * e[3];
    E[3] = e[3];
    F[0] = f[0] + f[1] + f[2];
    F[1] = f[1] + 2.0 * f[2];
    F[2] = f[2];
    F[3] = 0.0;
  }
  pair_fit_build(t, a, b, lat, r0, thickness, attraction);
  return MS_OK;
}

void cd_pair_table_free(cd_pair_table *t) {
  if (!t) return;
  free(t->fcoef);
  free(t->ecoef);
  t->fcoef = t->ecoef = NULL;
}

/* The shifted potential E(r) − E(R_c) ([AllenTildesley1987], p. 145): a constant off every
 * cubic's e0 (the spare interval's too, and the below-s_lo continuation reads interval 0's), so
 * E is continuous at R_c to the cubic's rounding; F/r and the fit are not touched. */
void cd_pair_table_shift_energy(cd_pair_table *t) {
  if (t->e_shift != 0.0 || t->e_rc == 0.0) return;
  for (int k = 0; k <= t->nint; k++) t->ecoef[4 * k] -= t->e_rc;
  t->e_shift = t->e_rc;
  t->e_rc = 0.0;
}

/* Below s_lo (r < r_min, outside the table) the first interval continues as its Taylor
 * polynomial at s_lo cut after the quadratic term of E: E = e0 + e1 w + e2 w², F/r = f0 + f1 w
 * (w = (s − s_lo)/h < 0), so F/r keeps growing linearly as s falls and E stays consistent
 * (a safety net: r_min defaults to 0.5 r0, i.e. δ = 8; a tabulated cold curve may end sooner,
 * Table 1 of [Davydov] at 0.75 r0). */
double cd_pair_table_energy(const cd_pair_table *t, double r) {
  double s = r * r;
  if (s >= t->rc2) return 0.0;
  const double *c = t->ecoef;
  if (s < t->s_lo) {
    double w = (s - t->s_lo) * t->inv_h;
    return fma(w, fma(w, c[2], c[1]), c[0]);
  }
  double u = (s - t->s_lo) * t->inv_h;
  int m = (int)u;
  double w = u - m;
  c += 4 * m;
  return fma(w, fma(w, fma(w, c[3], c[2]), c[1]), c[0]);
}

double cd_pair_table_force(const cd_pair_table *t, double r) {
  double s = r * r;
  return s >= t->rc2 ? 0.0 : r * table_fr(t, s);
}
