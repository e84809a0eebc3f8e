/* SPDX-License-Identifier: MIT */
/* eos_table_full.c — a full EOS P(ρ, e) on a rectangular (ρ, e) grid (docs/eos.md).
 *
 * Interpolation is bilinear in (ρ, e) for P and for c² (given in the file, or from centred
 * differences of P at the nodes: c² = ∂P/∂ρ|_e + (P/ρ²)∂P/∂e|_ρ). Bilinear interpolation is
 * monotone: if the nodal P increase with ρ at every e (checked on reading), so does the
 * interpolant, and its error is O(h²) where P is smooth. Queries outside the grid return NaN
 * (eos_eval reports them as MS_ERR_UNSTABLE); there is no extrapolation. */
#include "eos_impl.h"

#include <stdlib.h>
#include <string.h>

typedef struct table_full {
  size_t nr, ne;
  double *rho, *e; /* axes, strictly increasing */
  double *P, *c2;  /* [nr][ne] */
} table_full;

/* Index i with x[i] <= v <= x[i+1]; false outside [x0, x_{n-1}]. */
static bool locate(const double *x, size_t n, double v, size_t *i, double *t) {
  if (!(v >= x[0] && v <= x[n - 1])) return false;
  size_t lo = 0, hi = n - 1;
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (x[mid] <= v) lo = mid;
    else hi = mid;
  }
  *i = lo;
  *t = (v - x[lo]) / (x[hi] - x[lo]);
  return true;
}

static double bilinear(const table_full *t, const double *f, double rho, double e) {
  size_t i, j;
  double a, b;
  if (!locate(t->rho, t->nr, rho, &i, &a) || !locate(t->e, t->ne, e, &j, &b)) return NAN;
  const double *r0 = f + i * t->ne, *r1 = r0 + t->ne;
  return (1 - a) * ((1 - b) * r0[j] + b * r0[j + 1]) + a * ((1 - b) * r1[j] + b * r1[j + 1]);
}

static double tf_pressure(const eos_t *eos, double rho, double e) {
  const table_full *t = eos->data;
  return bilinear(t, t->P, rho, e);
}

static double tf_c2(const eos_t *eos, double rho, double e) {
  const table_full *t = eos->data;
  return bilinear(t, t->c2, rho, e);
}

/* Fused: one cell lookup for P and c². */
static void tf_eval(const eos_t *eos, double rho, double e, double *p, double *c2) {
  const table_full *t = eos->data;
  size_t i, j;
  double a, b;
  if (!locate(t->rho, t->nr, rho, &i, &a) || !locate(t->e, t->ne, e, &j, &b)) {
    *p = *c2 = NAN;
    return;
  }
  size_t k0 = i * t->ne + j, k1 = k0 + t->ne;
  double w00 = (1 - a) * (1 - b), w01 = (1 - a) * b, w10 = a * (1 - b), w11 = a * b;
  *p = w00 * t->P[k0] + w01 * t->P[k0 + 1] + w10 * t->P[k1] + w11 * t->P[k1 + 1];
  *c2 = w00 * t->c2[k0] + w01 * t->c2[k0 + 1] + w10 * t->c2[k1] + w11 * t->c2[k1 + 1];
}

static void tf_free(eos_t *eos) {
  table_full *t = eos->data;
  if (!t) return;
  free(t->rho), free(t->e), free(t->P), free(t->c2);
}

static const eos_ops table_full_ops = {
    tf_pressure, tf_c2, eos_isentrope_cold_pressure, eos_isentrope_cold_energy, NULL, tf_free,
    tf_eval,     NULL};

/* Nodal c² from centred differences of P (one-sided, first order, on the edges). */
static void nodal_c2_from_p(table_full *t) {
  size_t nr = t->nr, ne = t->ne;
  for (size_t i = 0; i < nr; ++i)
    for (size_t j = 0; j < ne; ++j) {
      size_t im = i > 0 ? i - 1 : i, ip = i + 1 < nr ? i + 1 : i;
      size_t jm = j > 0 ? j - 1 : j, jp = j + 1 < ne ? j + 1 : j;
      double dpdr = (t->P[ip * ne + j] - t->P[im * ne + j]) / (t->rho[ip] - t->rho[im]);
      double dpde = (t->P[i * ne + jp] - t->P[i * ne + jm]) / (t->e[jp] - t->e[jm]);
      double p = t->P[i * ne + j], r = t->rho[i];
      t->c2[i * ne + j] = dpdr + p / (r * r) * dpde;
    }
}

/* Finish a table: checks, EOS object, reference sound speed and cold curve (isentrope through
 * (ρ0, 0), when that state lies in the table). Takes ownership of `t`'s arrays. `where` names
 * the source for messages; line[] (optional) maps node index -> file line. */
static eos_t *finish_table(table_full *t, double rho0, const char *where, const int *line,
                           dk_errors *e) {
  size_t nerr0 = e ? e->n : 0, nr = t->nr, ne = t->ne;
  bool ok = true;
  for (size_t i = 0; i < nr && ok; ++i)
    for (size_t j = 0; j < ne; ++j) {
      int ln = line ? line[i * ne + j] : 0;
      if (i > 0 && t->P[i * ne + j] < t->P[(i - 1) * ne + j]) {
        if (e)
          dk_error_at(e, where, ln, 1,
                      "P is not monotone in rho: P(rho=%g, e=%g) = %g < P(rho=%g) = %g; tables "
                      "must have dP/drho >= 0",
                      t->rho[i], t->e[j], t->P[i * ne + j], t->rho[i - 1], t->P[(i - 1) * ne + j]);
        ok = false;
        break;
      }
      if (!(t->c2[i * ne + j] > 0.0)) {
        if (e)
          dk_error_at(e, where, ln, 1, "sound speed squared c^2 = %g <= 0 at rho = %g, e = %g",
                      t->c2[i * ne + j], t->rho[i], t->e[j]);
        ok = false;
        break;
      }
    }
  if (!ok || (e && e->n != nerr0)) {
    free(t->rho), free(t->e), free(t->P), free(t->c2);
    return NULL;
  }
  eos_t *eos = eos_alloc(EOS_TABLE_FULL, &table_full_ops, rho0, t, sizeof *t);
  double c2 = tf_c2(eos, rho0, 0.0);
  eos->c0 = c2 > 0.0 ? sqrt(c2) : NAN;
  if (isnan(tf_pressure(eos, rho0, 0.0)) ||
      eos_build_isentrope_cold(eos, t->rho[0] / rho0, t->rho[nr - 1] / rho0, 4000) != MS_OK)
    eos->delta_min = eos->delta_max = NAN; /* no cold curve */
  return eos;
}

eos_t *eos_create_table_from(const eos_t *src, double rho_min, double rho_max, size_t nrho,
                             double e_min, double e_max, size_t ne) {
  if (!src || nrho < 2 || ne < 2 || !(rho_min > 0.0) || !(rho_max > rho_min) || !(e_max > e_min))
    return NULL;
  table_full t = {nrho,
                  ne,
                  ms_calloc(nrho, sizeof(double)),
                  ms_calloc(ne, sizeof(double)),
                  ms_calloc(nrho * ne, sizeof(double)),
                  ms_calloc(nrho * ne, sizeof(double))};
  for (size_t i = 0; i < nrho; ++i)
    t.rho[i] = rho_min + (rho_max - rho_min) * (double)i / (double)(nrho - 1);
  for (size_t j = 0; j < ne; ++j) t.e[j] = e_min + (e_max - e_min) * (double)j / (double)(ne - 1);
  bool ok = true;
  for (size_t i = 0; i < nrho && ok; ++i)
    for (size_t j = 0; j < ne; ++j) {
      t.P[i * ne + j] = eos_pressure(src, t.rho[i], t.e[j]);
      t.c2[i * ne + j] = src->ops->sound_speed2(src, t.rho[i], t.e[j]);
      if (!isfinite(t.P[i * ne + j]) || !isfinite(t.c2[i * ne + j])) ok = false;
    }
  if (!ok) {
    free(t.rho), free(t.e), free(t.P), free(t.c2);
    return NULL;
  }
  return finish_table(&t, src->rho0, "<sampled table>", NULL, NULL);
}

/* ------------------------------------------------------------------------------------------ */
/* Text format: "# rho0: <g/cm^3>" metadata, optional header line, then rows `rho e P [c]`,
 * grouped by rho (rho increasing), e increasing within each group, the same e values in every
 * group. */

static eos_t *read_text(const char *path, dk_errors *e) {
  size_t nerr0 = e->n;
  eos_text_table tt;
  if (eos_text_read(path, 3, 4, &tt, e) != MS_OK) return NULL;
  const char *meta = eos_text_meta(&tt, "rho0");
  double rho0 = NAN;
  if (!meta) {
    dk_error_at(e, path, 1, 1, "missing reference density metadata line '# rho0: <g/cm^3>'");
  } else {
    char *end;
    rho0 = strtod(meta, &end);
    if (end == meta || !(rho0 > 0.0) || !isfinite(rho0))
      dk_error_at(e, path, 1, 1, "metadata 'rho0: %s' is not a positive number", meta);
  }
  size_t n = tt.nrow, nc = tt.ncol;
  const double *v = tt.v;
  /* Grid shape from the first group: ne = rows until rho changes. */
  size_t ne = 1;
  while (ne < n && v[ne * nc] == v[0]) ++ne;
  if (n % ne != 0 || ne < 2 || n / ne < 2) {
    dk_error_at(e, path, tt.line[n - 1], 1,
                "not a rectangular (rho, e) grid: %zu rows, %zu e values in the first rho group "
                "(need at least 2 x 2 and rows = n_rho * n_e; truncated table?)",
                n, ne);
    eos_text_free(&tt);
    return NULL;
  }
  size_t nr = n / ne;
  table_full t = {nr,
                  ne,
                  ms_calloc(nr, sizeof(double)),
                  ms_calloc(ne, sizeof(double)),
                  ms_calloc(n, sizeof(double)),
                  ms_calloc(n, sizeof(double))};
  for (size_t j = 0; j < ne; ++j) {
    t.e[j] = v[j * nc + 1];
    if (j > 0 && !(t.e[j] > t.e[j - 1]))
      dk_error_at(e, path, tt.line[j], 1, "e must increase within a rho group: %g follows %g",
                  t.e[j], t.e[j - 1]);
  }
  for (size_t i = 0; i < nr && e->n - nerr0 < 10; ++i) {
    t.rho[i] = v[i * ne * nc];
    if (!(t.rho[i] > 0.0))
      dk_error_at(e, path, tt.line[i * ne], 1, "rho must be > 0 (found %g)", t.rho[i]);
    if (i > 0 && !(t.rho[i] > t.rho[i - 1]))
      dk_error_at(e, path, tt.line[i * ne], 1,
                  "rho groups must be in increasing rho: %g follows %g", t.rho[i], t.rho[i - 1]);
    for (size_t j = 0; j < ne; ++j) {
      size_t r = i * ne + j;
      if (v[r * nc] != t.rho[i])
        dk_error_at(e, path, tt.line[r], 1,
                    "expected rho = %g (row %zu of a group of %zu e values), found %g", t.rho[i],
                    j + 1, ne, v[r * nc]);
      else if (v[r * nc + 1] != t.e[j])
        dk_error_at(e, path, tt.line[r], 1,
                    "expected e = %g (the same e values in every rho group), found %g", t.e[j],
                    v[r * nc + 1]);
      t.P[r] = v[r * nc + 2];
      if (nc == 4) {
        if (!(v[r * nc + 3] > 0.0))
          dk_error_at(e, path, tt.line[r], 1, "sound speed must be > 0 (found %g)", v[r * nc + 3]);
        t.c2[r] = v[r * nc + 3] * v[r * nc + 3];
      }
    }
  }
  if (e->n != nerr0) {
    free(t.rho), free(t.e), free(t.P), free(t.c2);
    eos_text_free(&tt);
    return NULL;
  }
  if (nc == 3) nodal_c2_from_p(&t);
  eos_t *eos = finish_table(&t, rho0, path, tt.line, e);
  eos_text_free(&tt);
  return eos;
}

/* HDF5 format: datasets rho [n_rho], e [n_e], P [n_rho][n_e], optional c [n_rho][n_e], and
 * rho0 [1]; internal units (attributes "units" are informative). */
static eos_t *read_h5(const char *path, dk_errors *e) {
  size_t nerr0 = e->n;
  ms_h5r *h = ms_h5_open_read(path, e);
  if (!h) {
    if (e->n == nerr0) dk_error_at(e, path, 0, 0, "cannot open HDF5 table");
    return NULL;
  }
  double *rho = NULL, *en = NULL, *P = NULL, *c = NULL, *rho0v = NULL;
  size_t nr = 0, ne = 0, a0, a1, b0, b1, k0, k1;
  bool ok = ms_h5_read_doubles(h, "rho", &rho, &nr, &a1, e) == MS_OK &&
            ms_h5_read_doubles(h, "e", &en, &ne, &b1, e) == MS_OK &&
            ms_h5_read_doubles(h, "P", &P, &a0, &b0, e) == MS_OK &&
            ms_h5_read_doubles(h, "rho0", &rho0v, &k0, &k1, e) == MS_OK;
  if (ok && (a1 != 1 || b1 != 1 || a0 != nr || b0 != ne || k0 * k1 != 1 || nr < 2 || ne < 2)) {
    dk_error_at(e, path, 0, 0,
                "inconsistent table shapes: rho [%zu], e [%zu], P [%zu][%zu], rho0 [%zu] "
                "(expected P [n_rho][n_e], n_rho, n_e >= 2, and a single rho0)",
                nr, ne, a0, b0, k0 * k1);
    ok = false;
  }
  if (ok && ms_h5_exists(h, "c")) {
    size_t c0n, c1n;
    if (ms_h5_read_doubles(h, "c", &c, &c0n, &c1n, e) != MS_OK) ok = false;
    else if (c0n != nr || c1n != ne) {
      dk_error_at(e, path, 0, 0, "dataset c has shape [%zu][%zu], expected [%zu][%zu]", c0n, c1n,
                  nr, ne);
      ok = false;
    }
  }
  ms_h5_close_read(h);
  double rho0 = ok ? rho0v[0] : NAN;
  if (ok && !(rho0 > 0.0)) {
    dk_error_at(e, path, 0, 0, "rho0 must be > 0 (found %g)", rho0);
    ok = false;
  }
  for (size_t i = 0; ok && i < nr; ++i)
    if (!(rho[i] > 0.0) || (i > 0 && !(rho[i] > rho[i - 1]))) {
      dk_error_at(e, path, 0, 0, "rho axis must be positive and strictly increasing (index %zu)",
                  i);
      ok = false;
    }
  for (size_t j = 1; ok && j < ne; ++j)
    if (!(en[j] > en[j - 1])) {
      dk_error_at(e, path, 0, 0, "e axis must be strictly increasing (index %zu)", j);
      ok = false;
    }
  for (size_t k = 0; ok && k < nr * ne; ++k)
    if (!isfinite(P[k]) || (c && !(c[k] > 0.0 && isfinite(c[k])))) {
      dk_error_at(e, path, 0, 0, "non-finite P or non-positive c at node %zu", k);
      ok = false;
    }
  free(rho0v);
  if (!ok) {
    free(rho), free(en), free(P), free(c);
    return NULL;
  }
  table_full t = {nr, ne, rho, en, P, ms_calloc(nr * ne, sizeof(double))};
  if (c) {
    for (size_t k = 0; k < nr * ne; ++k) t.c2[k] = c[k] * c[k];
    free(c);
  } else {
    nodal_c2_from_p(&t);
  }
  return finish_table(&t, rho0, path, NULL, e);
}

static bool is_h5_path(const char *path) {
  size_t n = strlen(path);
  return (n > 3 && strcmp(path + n - 3, ".h5") == 0) ||
         (n > 5 && strcmp(path + n - 5, ".hdf5") == 0);
}

eos_t *eos_create_table_full(const char *path, dk_errors *e) {
  return is_h5_path(path) ? read_h5(path, e) : read_text(path, e);
}

ms_status eos_table_write(const eos_t *eos, const char *path) {
  if (!eos || eos->kind != EOS_TABLE_FULL) return MS_ERR_INPUT;
  const table_full *t = eos->data;
  size_t nr = t->nr, ne = t->ne;
  double *c = ms_calloc(nr * ne, sizeof *c);
  for (size_t k = 0; k < nr * ne; ++k) c[k] = sqrt(t->c2[k]);
  ms_status st = MS_OK;
  if (is_h5_path(path)) {
    ms_h5 *h = ms_h5_create(path);
    if (!h) {
      free(c);
      return MS_ERR_IO;
    }
    if ((st = ms_h5_write_doubles(h, "rho", nr, 0, t->rho, "g/cm^3")) != MS_OK ||
        (st = ms_h5_write_doubles(h, "e", ne, 0, t->e, "kJ/g")) != MS_OK ||
        (st = ms_h5_write_doubles(h, "P", nr, ne, t->P, "GPa")) != MS_OK ||
        (st = ms_h5_write_doubles(h, "c", nr, ne, c, "km/s")) != MS_OK ||
        (st = ms_h5_write_doubles(h, "rho0", 1, 0, &eos->rho0, "g/cm^3")) != MS_OK) {
      ms_h5_abort(h);
    } else {
      st = ms_h5_close(h);
    }
  } else {
    ms_afile af;
    if ((st = ms_afile_open(&af, path)) == MS_OK) {
      fprintf(af.f, "# mscale full EOS table (docs/eos.md): rows grouped by rho, e increasing\n");
      fprintf(af.f, "# units: rho [g/cm^3], e [kJ/g], P [GPa], c [km/s]\n");
      fprintf(af.f, "# rho0: %.17g\n", eos->rho0);
      fprintf(af.f, "rho e P c\n");
      for (size_t i = 0; i < nr; ++i)
        for (size_t j = 0; j < ne; ++j)
          fprintf(af.f, "%.17g %.17g %.17g %.17g\n", t->rho[i], t->e[j], t->P[i * ne + j],
                  c[i * ne + j]);
      st = ms_afile_commit(&af);
    }
  }
  free(c);
  return st;
}
