/* SPDX-License-Identifier: MIT */
/* output.c — profiles (HDF5 + XDMF + CSV) and tagged-node histories (CSV + HDF5). All files
 * go through the atomic writers of core, so an interrupted run leaves no truncated file. */
#include "cont_run.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char *stem_name(const char *stem, const char *ext) {
  size_t n = strlen(stem) + strlen(ext) + 1;
  char *s = ms_calloc(n, 1);
  snprintf(s, n, "%s%s", stem, ext);
  return s;
}

const char *cont_mass_unit(cont_geometry geometry) {
  return geometry == CONT_PLANAR ? "g/cm^2" : geometry == CONT_CYLINDRICAL ? "g/(cm*rad)" : "g/sr";
}

const char *cont_energy_unit(cont_geometry geometry) {
  return geometry == CONT_PLANAR        ? "kJ/cm^2"
         : geometry == CONT_CYLINDRICAL ? "kJ/(cm*rad)"
                                        : "kJ/sr";
}

ms_status cont_write_profile(const ms_ctx *ctx, const cont_grid *g, const char *stem) {
  size_t N = g->ncells, Nn = g->nnodes;
  char *h5_name = stem_name(stem, ".h5"), *xmf_name = stem_name(stem, ".xmf"),
       *csv_name = stem_name(stem, ".csv");
  char *h5_path = ms_out_path(ctx, h5_name), *xmf_path = ms_out_path(ctx, xmf_name),
       *csv_path = ms_out_path(ctx, csv_name);
  ms_status s = MS_OK;

  double *xyz = ms_calloc(3 * Nn, sizeof(double));
  double *xc = ms_calloc(N, sizeof(double)), *uc = ms_calloc(N, sizeof(double)),
         *mat = ms_calloc(N, sizeof(double));
  for (size_t j = 0; j < Nn; ++j) xyz[3 * j] = g->x[j];
  for (size_t i = 0; i < N; ++i) {
    xc[i] = 0.5 * (g->x[i] + g->x[i + 1]);
    uc[i] = 0.5 * (g->u[i] + g->u[i + 1]);
    mat[i] = g->material[i];
  }

  ms_h5 *h = ms_h5_create(h5_path);
  if (!h) {
    s = MS_ERR_IO;
  } else {
    const char *L = ms_unit_label(MS_DIM_LENGTH), *V = ms_unit_label(MS_DIM_VELOCITY),
               *D = ms_unit_label(MS_DIM_DENSITY), *E = ms_unit_label(MS_DIM_SPEC_ENERGY),
               *P = ms_unit_label(MS_DIM_PRESSURE);
    struct {
      const char *name;
      size_t n0, n1;
      const double *d;
      const char *u;
    } ds[] = {{"nodes/xyz", Nn, 3, xyz, L},
              {"nodes/x", Nn, 1, g->x, L},
              {"nodes/u", Nn, 1, g->u, V},
              {"cells/x", N, 1, xc, L},
              {"cells/rho", N, 1, g->rho, D},
              {"cells/e", N, 1, g->e, E},
              {"cells/p", N, 1, g->p, P},
              {"cells/q", N, 1, g->q, P},
              {"cells/c", N, 1, g->c, V},
              {"cells/mass", N, 1, g->mass, cont_mass_unit(g->geometry)},
              {"cells/material", N, 1, mat, "1"}}; /* float: the XDMF sidecar reads it as one */
    for (size_t k = 0; k < sizeof ds / sizeof ds[0] && s == MS_OK; ++k)
      s = ms_h5_write_doubles(h, ds[k].name, ds[k].n0, ds[k].n1, ds[k].d, ds[k].u);
    if (s == MS_OK) s = ms_h5_attr_double(h, "/", "time", ms_out_time(g->t));
    if (s == MS_OK) s = ms_h5_attr_int(h, "/", "step", g->step);
    if (s == MS_OK) s = ms_h5_attr_string(h, "/", "time_units", ms_out_time_label());
    if (s == MS_OK) {
      static const char *const geo[] = {"planar", "cylindrical", "spherical"};
      s = ms_h5_attr_string(h, "/", "geometry", geo[g->geometry]);
    }
    if (s == MS_OK) s = ms_h5_close(h);
    else ms_h5_abort(h);
  }
  if (s == MS_OK) {
    const ms_xdmf_attr attr[] = {{"u", "nodes/u", 1, false},
                                 {"rho", "cells/rho", 1, true},
                                 {"e", "cells/e", 1, true},
                                 {"p", "cells/p", 1, true},
                                 {"q", "cells/q", 1, true},
                                 {"c", "cells/c", 1, true},
                                 {"material", "cells/material", 1, true}};
    s = ms_xdmf_write_points(xmf_path, h5_name, "nodes/xyz", Nn, 3, ms_out_time(g->t),
                             sizeof attr / sizeof attr[0], attr);
    /* the run's profiles as one time series for ParaView (profile_final sorts last) */
    const char *slash = strrchr(xmf_path, '/');
    char *dir = slash ? ms_strdup(xmf_path) : ms_strdup(".");
    if (slash) dir[slash - xmf_path] = '\0';
    if (s == MS_OK) s = ms_xdmf_write_series(dir, "profile_", "profiles.xmf");
    free(dir);
  }
  if (s == MS_OK) {
    ms_afile af;
    s = ms_afile_open(&af, csv_path);
    if (s == MS_OK) {
      const char *names[] = {"cell", "x", "rho", "u", "e", "p", "q", "c", "material"};
      const char *units[] = {"1",
                             ms_unit_label(MS_DIM_LENGTH),
                             ms_unit_label(MS_DIM_DENSITY),
                             ms_unit_label(MS_DIM_VELOCITY),
                             ms_unit_label(MS_DIM_SPEC_ENERGY),
                             ms_unit_label(MS_DIM_PRESSURE),
                             ms_unit_label(MS_DIM_PRESSURE),
                             ms_unit_label(MS_DIM_VELOCITY),
                             "1"};
      char title[128];
      snprintf(title, sizeof title, "continuum profile at t = %.9g %s (cell centres)",
               ms_out_time(g->t), ms_out_time_label());
      ms_csv_header(af.f, title, 9, names, units);
      for (size_t i = 0; i < N; ++i) {
        double row[9] = {(double)i, xc[i],   g->rho[i], uc[i], g->e[i],
                         g->p[i],   g->q[i], g->c[i],   mat[i]};
        ms_csv_row(af.f, 9, row);
      }
      s = ms_afile_commit(&af);
    }
  }
  free(xyz);
  free(xc);
  free(uc);
  free(mat);
  free(h5_name);
  free(xmf_name);
  free(csv_name);
  free(h5_path);
  free(xmf_path);
  free(csv_path);
  return s;
}

ms_status cont_write_histories(const ms_ctx *ctx, const cont_grid *g, long stride) {
  if (g->ntags == 0) return MS_OK;
  if (stride < 1) stride = 1;
  ms_status s = MS_OK;
  const char *names[] = {"t", "x", "u", "p_left", "rho_left", "p_right", "rho_right"};
  const char *units[] = {ms_unit_label(MS_DIM_TIME),     ms_unit_label(MS_DIM_LENGTH),
                         ms_unit_label(MS_DIM_VELOCITY), ms_unit_label(MS_DIM_PRESSURE),
                         ms_unit_label(MS_DIM_DENSITY),  ms_unit_label(MS_DIM_PRESSURE),
                         ms_unit_label(MS_DIM_DENSITY)};
  char *h5_path = ms_out_path(ctx, "history.h5");
  ms_h5 *h = ms_h5_create(h5_path);
  free(h5_path);
  if (!h) return MS_ERR_IO;
  for (size_t k = 0; k < g->ntags && s == MS_OK; ++k) {
    cont_history hs = cont_grid_history(g, k);
    /* rows kept: every stride-th, and always the last */
    size_t nkeep = hs.n == 0 ? 0 : (hs.n - 1) / (size_t)stride + 1;
    bool last_extra = hs.n > 0 && (hs.n - 1) % (size_t)stride != 0;
    size_t nrow = nkeep + (last_extra ? 1 : 0);
    const double *cols[] = {hs.t, hs.x, hs.u, hs.p_left, hs.rho_left, hs.p_right, hs.rho_right};
    /* a boundary node has a cell on one side only: the other side's columns are left out rather
     * than written as NaN */
    size_t keep[7], ncol = 0;
    for (size_t c = 0; c < 7; ++c)
      if (!((c == 3 || c == 4) && hs.node == 0) && !((c == 5 || c == 6) && hs.node == g->ncells))
        keep[ncol++] = c;
    double *buf = ms_calloc(nrow ? nrow : 1, sizeof(double));
    for (size_t k = 0; k < ncol && s == MS_OK; ++k) {
      const size_t c = keep[k];
      for (size_t r = 0; r < nkeep; ++r) buf[r] = cols[c][r * (size_t)stride];
      if (last_extra) buf[nrow - 1] = cols[c][hs.n - 1];
      char ds[256];
      snprintf(ds, sizeof ds, "%s/%s", hs.name, names[c]);
      double to_out; /* the time column in the output unit (docs/output.md, "Units") */
      const char *unit = ms_out_unit(units[c], &to_out);
      for (size_t r = 0; r < nrow; ++r) buf[r] *= to_out;
      s = ms_h5_write_doubles(h, ds, nrow, 1, buf, unit);
    }
    free(buf);
    if (s == MS_OK) {
      char grp[256];
      snprintf(grp, sizeof grp, "/%s", hs.name);
      s = ms_h5_attr_int(h, grp, "node", (int64_t)hs.node);
    }
    /* CSV */
    char fname[300];
    snprintf(fname, sizeof fname, "history_%s.csv", hs.name);
    char *path = ms_out_path(ctx, fname);
    ms_afile af;
    if (s == MS_OK) s = ms_afile_open(&af, path);
    free(path);
    if (s == MS_OK) {
      char title[300];
      snprintf(title, sizeof title,
               "continuum history of tagged node '%s' (node %zu); x, u and cell states at the "
               "same time level",
               hs.name, hs.node);
      const char *knames[7], *kunits[7];
      for (size_t k = 0; k < ncol; ++k) knames[k] = names[keep[k]], kunits[k] = units[keep[k]];
      ms_csv_header(af.f, title, ncol, knames, kunits);
      for (size_t r = 0; r < hs.n; ++r) {
        if (r % (size_t)stride != 0 && r != hs.n - 1) continue;
        double row[7];
        for (size_t k = 0; k < ncol; ++k) row[k] = cols[keep[k]][r];
        ms_csv_row(af.f, ncol, row);
      }
      s = ms_afile_commit(&af);
    }
  }
  if (s == MS_OK) s = ms_h5_close(h);
  else ms_h5_abort(h);
  return s;
}
