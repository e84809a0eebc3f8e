/* SPDX-License-Identifier: MIT */
/* Fragment spectra and the distributions ejecta experiments report (docs/design.md §6):
 * N(g), per-fragment table, cumulative N(≥m), mass/diameter histograms, ejected mass vs
 * velocity. Every table is a CSV with core's units header. */
#include "cpl_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------- */
/* Spectrum N(g)                                                                             */

void cpl_spectrum_build(const cpl_fragments *f, cpl_spectrum *s) {
  memset(s, 0, sizeof *s);
  int64_t gmax = 0;
  for (size_t k = 0; k < f->n; k++)
    if (f->count[k] > gmax) gmax = f->count[k];
  if (!f->n) return;
  /* dense histogram over g = 1..gmax, then compress to the g that occur */
  int64_t *cnt = ms_calloc((size_t)gmax + 1, sizeof *cnt);
  double *mass = ms_calloc((size_t)gmax + 1, sizeof *mass);
  for (size_t k = 0; k < f->n; k++) {
    cnt[f->count[k]]++;
    mass[f->count[k]] += f->mass[k];
  }
  size_t rows = 0;
  for (int64_t g = 1; g <= gmax; g++) rows += cnt[g] > 0;
  s->g = ms_calloc(rows, sizeof *s->g);
  s->count = ms_calloc(rows, sizeof *s->count);
  s->mass = ms_calloc(rows, sizeof *s->mass);
  for (int64_t g = 1; g <= gmax; g++)
    if (cnt[g] > 0) {
      s->g[s->n] = g;
      s->count[s->n] = cnt[g];
      s->mass[s->n] = mass[g];
      s->n++;
    }
  free(cnt);
  free(mass);
}

void cpl_spectrum_free(cpl_spectrum *s) {
  if (!s) return;
  free(s->g);
  free(s->count);
  free(s->mass);
  memset(s, 0, sizeof *s);
}

/* ---------------------------------------------------------------------------------------- */
/* Ejecta selection                                                                          */

void cpl_ejecta_sel_default(cpl_ejecta_sel *s) {
  s->normal[0] = 1;
  s->normal[1] = s->normal[2] = 0;
  s->plane = -INFINITY;
  s->exclude_largest = true;
}

size_t cpl_largest_fragment(const cpl_fragments *f) {
  size_t best = (size_t)-1;
  for (size_t k = 0; k < f->n; k++)
    if (best == (size_t)-1 || f->mass[k] > f->mass[best]) best = k;
  return best;
}

bool cpl_is_ejecta_with(const cpl_fragments *f, size_t k, const cpl_ejecta_sel *s, size_t largest) {
  if (s->exclude_largest && k == largest) return false;
  double r = s->normal[0] * f->cx[k] + s->normal[1] * f->cy[k] + s->normal[2] * f->cz[k];
  return r > s->plane;
}

bool cpl_is_ejecta(const cpl_fragments *f, size_t k, const cpl_ejecta_sel *s) {
  return cpl_is_ejecta_with(f, k, s, s->exclude_largest ? cpl_largest_fragment(f) : (size_t)-1);
}

double cpl_ejected_mass(const cpl_fragments *f, const cpl_ejecta_sel *s) {
  size_t big = s->exclude_largest ? cpl_largest_fragment(f) : (size_t)-1;
  double m = 0;
  for (size_t k = 0; k < f->n; k++)
    if (cpl_is_ejecta_with(f, k, s, big)) m += f->mass[k];
  return m;
}

/* ---------------------------------------------------------------------------------------- */
/* CSV writers                                                                               */

void cpl_write_spectrum(FILE *out, const cpl_fragments *f, const char *title) {
  static const char *const names[] = {"g", "count", "mass"};
  static const char *const units[] = {"clusters", "fragments", "g"};
  ms_csv_header(out, title ? title : "fragment spectrum N(g)", 3, names, units);
  cpl_spectrum s;
  cpl_spectrum_build(f, &s);
  for (size_t r = 0; r < s.n; r++)
    fprintf(out, "%lld,%lld,%.10g\n", (long long)s.g[r], (long long)s.count[r], s.mass[r]);
  cpl_spectrum_free(&s);
}

void cpl_write_fragment_table(FILE *out, const cpl_fragments *f, const char *title) {
  static const char *const names[] = {"id", "count", "mass", "d",  "x", "y",
                                      "z",  "vx",    "vy",   "vz", "rg"};
  static const char *const units[] = {"1",  "clusters", "g",    "cm",   "cm", "cm",
                                      "cm", "km/s",     "km/s", "km/s", "cm"};
  ms_csv_header(out, title ? title : "fragments (centre of mass, c.o.m. velocity)", 11, names,
                units);
  for (size_t k = 0; k < f->n; k++)
    fprintf(out, "%zu,%lld,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n", k,
            (long long)f->count[k], f->mass[k], f->diameter[k], f->cx[k], f->cy[k], f->cz[k],
            f->vx[k], f->vy[k], f->vz[k], f->rg[k]);
}

/* Sort helper: indices by a key, descending (ties by index, so the output is deterministic). */
typedef struct keyed {
  double key;
  size_t k;
} keyed;

static int cmp_desc(const void *a, const void *b) {
  const keyed *x = a, *y = b;
  if (x->key > y->key) return -1;
  if (x->key < y->key) return 1;
  return (x->k > y->k) - (x->k < y->k);
}

void cpl_write_cumulative(FILE *out, const cpl_fragments *f, const char *title) {
  static const char *const names[] = {"mass", "N_ge", "M_ge"};
  static const char *const units[] = {"g", "fragments", "g"};
  ms_csv_header(out, title ? title : "cumulative N(>=m) and mass in fragments >= m", 3, names,
                units);
  if (!f->n) return;
  keyed *o = ms_calloc(f->n, sizeof *o);
  for (size_t k = 0; k < f->n; k++) o[k] = (keyed){f->mass[k], k};
  qsort(o, f->n, sizeof *o, cmp_desc);
  double msum = 0;
  for (size_t r = 0; r < f->n; r++) {
    msum += o[r].key;
    /* one row per distinct mass: the row carries everything at least this heavy */
    if (r + 1 < f->n && o[r + 1].key == o[r].key) continue;
    fprintf(out, "%.10g,%zu,%.10g\n", o[r].key, r + 1, msum);
  }
  free(o);
}

void cpl_write_histogram(FILE *out, const cpl_fragments *f, cpl_hist_of what, int nbins,
                         const char *title) {
  static const char *const names[] = {"lo", "hi", "count", "mass"};
  const char *unit = what == CPL_HIST_MASS ? "g" : "cm";
  const char *const units[] = {unit, unit, "fragments", "g"};
  ms_csv_header(out,
                title ? title
                      : (what == CPL_HIST_MASS ? "fragment mass distribution (log bins)"
                                               : "equivalent-diameter distribution (log bins)"),
                4, names, units);
  if (nbins < 1 || !f->n) return;
  const double *val = what == CPL_HIST_MASS ? f->mass : f->diameter;
  double lo = INFINITY, hi = -INFINITY;
  for (size_t k = 0; k < f->n; k++)
    if (isfinite(val[k]) && val[k] > 0) {
      if (val[k] < lo) lo = val[k];
      if (val[k] > hi) hi = val[k];
    }
  if (!(lo <= hi)) return;
  /* widen a degenerate range so every value falls inside one bin */
  double llo = log(lo), lhi = log(hi);
  if (lhi - llo < 1e-12) {
    llo -= 0.5;
    lhi += 0.5;
  }
  lhi += 1e-12 * (lhi - llo); /* the largest value lands in the last bin */
  double *cnt = ms_calloc((size_t)nbins, sizeof *cnt);
  double *mass = ms_calloc((size_t)nbins, sizeof *mass);
  for (size_t k = 0; k < f->n; k++) {
    if (!(isfinite(val[k]) && val[k] > 0)) continue;
    int b = (int)floor((log(val[k]) - llo) / (lhi - llo) * nbins);
    if (b < 0) b = 0;
    if (b >= nbins) b = nbins - 1;
    cnt[b] += 1;
    mass[b] += f->mass[k];
  }
  for (int b = 0; b < nbins; b++) {
    double row[4] = {exp(llo + (lhi - llo) * b / nbins), exp(llo + (lhi - llo) * (b + 1) / nbins),
                     cnt[b], mass[b]};
    ms_csv_row(out, 4, row);
  }
  free(cnt);
  free(mass);
}

void cpl_write_ejecta_velocity(FILE *out, const cpl_fragments *f, const cpl_ejecta_sel *s,
                               const char *title) {
  static const char *const names[] = {"v", "M_ge"};
  static const char *const units[] = {"km/s", "g"};
  ms_csv_header(out, title ? title : "cumulative ejected mass with normal velocity >= v", 2, names,
                units);
  size_t big = s->exclude_largest ? cpl_largest_fragment(f) : (size_t)-1;
  keyed *o = ms_calloc(f->n ? f->n : 1, sizeof *o);
  size_t m = 0;
  for (size_t k = 0; k < f->n; k++)
    if (cpl_is_ejecta_with(f, k, s, big))
      o[m++] =
          (keyed){s->normal[0] * f->vx[k] + s->normal[1] * f->vy[k] + s->normal[2] * f->vz[k], k};
  qsort(o, m, sizeof *o, cmp_desc);
  double msum = 0;
  for (size_t r = 0; r < m; r++) {
    msum += f->mass[o[r].k];
    if (r + 1 < m && o[r + 1].key == o[r].key) continue;
    fprintf(out, "%.10g,%.10g\n", o[r].key, msum);
  }
  free(o);
}
