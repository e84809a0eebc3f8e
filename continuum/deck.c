/* SPDX-License-Identifier: MIT */
/* deck.c — the `continuum:` deck section (docs/input-continuum.md) → cont_setup + run options.
 * Every problem is recorded with FILE:LINE:COL; reading continues after an error so that
 * `mscale check` reports all of them. */
#include "cont_run.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const geometry_names[] = {"planar", "cylindrical", "spherical", NULL};
static const char *const bc_names[] = {"wall", "free", "piston", "pressure", NULL};
static const char *const grade_names[] = {"none", "left", "right", "both", NULL};
static const char *const pulse_names[] = {"trapezoid", "exponential", NULL};
static const char *const xt_names[] = {"density", "pressure", NULL};

/* Read a history table [[t, v], ...] or a file; checks that t increases strictly. */
static bool read_history_table(dk_errors *e, dk_doc *doc, const dk_node *bcmap, ms_dim vdim,
                               cont_fn *fn) {
  const dk_node *tab = dk_get(bcmap, "table");
  const dk_node *file = dk_get(bcmap, "file");
  ms_unit_system sys = dk_units(doc);
  double tconv = ms_unit_to_internal(sys, MS_DIM_TIME), vconv = ms_unit_to_internal(sys, vdim);
  fn->kind = CONT_FN_TABLE;
  if (tab) {
    if (!dk_expect_seq(e, doc, tab, "table")) return false;
    size_t n = dk_seq_len(tab);
    if (n == 0) {
      dk_error(e, doc, tab, "table: needs at least one [t, value] row");
      return false;
    }
    fn->t = ms_calloc(n, sizeof(double));
    fn->v = ms_calloc(n, sizeof(double));
    fn->n = n;
    bool ok = true;
    for (size_t k = 0; k < n; ++k) {
      const dk_node *row = dk_seq_at(tab, k);
      if (dk_node_kind(row) != DK_SEQ || dk_seq_len(row) != 2) {
        dk_error(e, doc, row, "table row %zu: expected [t, value]", k);
        ok = false;
        continue;
      }
      ok = dk_node_double(e, doc, dk_seq_at(row, 0), "table time", MS_DIM_TIME, &fn->t[k]) && ok;
      ok = dk_node_double(e, doc, dk_seq_at(row, 1), "table value", vdim, &fn->v[k]) && ok;
      if (ok && k > 0 && !(fn->t[k] > fn->t[k - 1])) {
        dk_error(e, doc, row, "table row %zu: time %g does not increase (previous %g)", k, fn->t[k],
                 fn->t[k - 1]);
        ok = false;
      }
    }
    return ok;
  }
  const char *path = dk_scalar(file);
  if (!path) {
    dk_error(e, doc, file, "file: expected a file name");
    return false;
  }
  char *full = dk_resolve_path(doc, path);
  double *data = NULL;
  size_t nrow = 0, ncol = 0;
  ms_status s = ms_read_table(full, 2, &data, &nrow, &ncol, e);
  if (s != MS_OK) {
    dk_error(e, doc, file, "file '%s': cannot be read as a table of (t, value)", full);
    free(full);
    return false;
  }
  bool ok = nrow > 0;
  if (!ok) dk_error(e, doc, file, "history file '%s' has no rows", full);
  fn->t = ms_calloc(nrow ? nrow : 1, sizeof(double));
  fn->v = ms_calloc(nrow ? nrow : 1, sizeof(double));
  fn->n = nrow;
  tconv = ms_table_time_factor(full, 0, tconv); /* the file's own "# units:" line first */
  for (size_t k = 0; k < nrow && ok; ++k) {
    fn->t[k] = data[k * ncol] * tconv;
    fn->v[k] = data[k * ncol + 1] * vconv;
    if (k > 0 && !(fn->t[k] > fn->t[k - 1])) {
      dk_error(e, doc, file,
               "history file '%s' is not monotone in time: data row %zu has t = %g after %g", full,
               k + 1, data[k * ncol], data[(k - 1) * ncol]);
      ok = false;
    }
  }
  free(data);
  free(full);
  return ok;
}

/* A history in map m: exactly one of value, table, file, pulse (docs/input-continuum.md);
 * `what` names it in messages. Shared by the 1D and 2D decks. */
bool cont_fn_read(dk_errors *e, dk_doc *doc, const dk_node *m, const char *what, ms_dim vdim,
                  cont_fn *fn) {
  memset(fn, 0, sizeof *fn);
  const dk_node *val = dk_get(m, "value"), *tab = dk_get(m, "table"), *file = dk_get(m, "file"),
                *pulse = dk_get(m, "pulse");
  int given = !!val + !!tab + !!file + !!pulse;
  if (given != 1) {
    dk_error(e, doc, m, "%s: give exactly one of value, table, file, pulse", what);
    return false;
  }
  if (val) {
    fn->kind = CONT_FN_CONST;
    return dk_node_double(e, doc, val, "value", vdim, &fn->value);
  }
  if (tab || file) return read_history_table(e, doc, m, vdim, fn);
  if (!dk_expect_map(e, doc, pulse, "pulse")) return false;
  size_t n0 = e->n;
  int shape = 0;
  dk_read_enum(e, doc, pulse, "shape", false, 0, pulse_names, &shape);
  dk_read_double(e, doc, pulse, "amplitude", vdim, true, 0, -INFINITY, INFINITY, &fn->value);
  dk_read_double(e, doc, pulse, "start", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &fn->t0);
  if (shape == 0) {
    fn->kind = CONT_FN_TRAPEZOID;
    dk_read_double(e, doc, pulse, "rise", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &fn->rise);
    dk_read_double(e, doc, pulse, "hold", MS_DIM_TIME, true, 0.0, 0.0, INFINITY, &fn->hold);
    dk_read_double(e, doc, pulse, "fall", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &fn->fall);
  } else {
    fn->kind = CONT_FN_EXP_DECAY;
    dk_read_double(e, doc, pulse, "rise", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &fn->rise);
    dk_read_positive(e, doc, pulse, "decay", MS_DIM_TIME, true, 1.0, &fn->tau);
  }
  return e->n == n0;
}

/* A boundary: {type: wall|free|piston|pressure, value | table | file | pulse}. */
static void read_bc(dk_errors *e, dk_doc *doc, const dk_node *sec, const char *key, cont_bc *bc) {
  const dk_node *m = dk_get(sec, key);
  bc->kind = CONT_BC_WALL;
  memset(&bc->fn, 0, sizeof bc->fn);
  if (!m) {
    /* default written back so the resolved deck shows it */
    return;
  }
  if (!dk_expect_map(e, doc, m, key)) return;
  int kind = 0;
  if (!dk_read_enum(e, doc, m, "type", true, 0, bc_names, &kind)) return;
  bc->kind = (cont_bc_kind)kind;
  if (bc->kind == CONT_BC_WALL || bc->kind == CONT_BC_FREE) return;
  char what[64];
  snprintf(what, sizeof what, "%s boundary", key);
  cont_fn_read(e, doc, m, what, bc->kind == CONT_BC_PISTON ? MS_DIM_VELOCITY : MS_DIM_PRESSURE,
               &bc->fn);
}

static void read_layer(dk_errors *e, dk_doc *doc, const dk_node *L, size_t k,
                       const eos_materials *mats, double *x_end, bool *x_known,
                       cont_layer_spec *spec) {
  memset(spec, 0, sizeof *spec);
  spec->grade_ratio = 1.0;
  if (!dk_expect_map(e, doc, L, "layer")) return;
  const char *mname = NULL;
  dk_read_string(e, doc, L, "material", true, NULL, &mname);
  const eos_material *mat = NULL;
  if (mname && mats) mat = eos_materials_find(mats, mname, e, doc, dk_get(L, "material"));
  if (mat) {
    spec->eos = mat->eos;
    spec->material = (int)(mat - mats->m);
  }
  const char *name = NULL;
  dk_read_string(e, doc, L, "name", false, mname ? mname : "layer", &name);
  spec->name = name;

  /* Extent: thickness, or from/to. Layers must tile the line without gaps or overlaps. */
  const dk_node *from_n = dk_get(L, "from"), *to_n = dk_get(L, "to"),
                *th_n = dk_get(L, "thickness");
  double from = *x_end, to = NAN, th = NAN;
  if (from_n) dk_node_double(e, doc, from_n, "from", MS_DIM_LENGTH, &from);
  if (to_n) dk_node_double(e, doc, to_n, "to", MS_DIM_LENGTH, &to);
  if (th_n) dk_node_double(e, doc, th_n, "thickness", MS_DIM_LENGTH, &th);
  if (th_n && to_n) {
    dk_error(e, doc, L, "layer %zu (%s): give thickness or from/to, not both", k, name);
  } else if (!th_n && !to_n) {
    dk_error(e, doc, L, "layer %zu (%s): missing 'thickness' (cm) or 'to' (cm)", k, name);
  } else {
    if (to_n) th = to - from;
    if (!(th > 0.0))
      dk_error(e, doc, th_n ? th_n : to_n, "layer %zu (%s): thickness %g must be > 0", k, name, th);
  }
  if (from_n && *x_known) {
    double tol = 1e-9 * (fabs(*x_end) + fabs(th > 0 ? th : 0) + 1e-30);
    if (from < *x_end - tol)
      dk_error(e, doc, from_n, "layer %zu (%s) overlaps the previous layer: from = %g < %g", k,
               name, from, *x_end);
    else if (from > *x_end + tol)
      dk_error(e, doc, from_n,
               "layer %zu (%s) leaves a gap after the previous layer: from = %g > %g", k, name,
               from, *x_end);
  }
  if (from_n && !*x_known) *x_end = from; /* first layer sets x_left */
  *x_known = true;
  spec->thickness = th;
  if (th > 0.0) *x_end = (from_n ? from : *x_end) + th;

  /* Resolution: cells, or cell_size. */
  const dk_node *cells_n = dk_get(L, "cells"), *size_n = dk_get(L, "cell_size");
  if (cells_n && size_n) {
    dk_error(e, doc, L, "layer %zu (%s): give cells or cell_size, not both", k, name);
  } else if (cells_n) {
    long nc = 0;
    if (dk_read_int(e, doc, L, "cells", true, 0, 0, 100000000, &nc)) {
      if (nc < 1)
        dk_error(e, doc, cells_n, "layer %zu (%s): cells = %ld, a layer needs at least one cell", k,
                 name, nc);
      spec->ncells = nc;
    }
  } else if (size_n) {
    double h = 0;
    if (dk_read_positive(e, doc, L, "cell_size", MS_DIM_LENGTH, true, 0, &h) && th > 0.0) {
      double n = floor(th / h + 0.5);
      if (!(n <= 1e8)) /* the same limit as `cells:` */
        dk_error(e, doc, size_n,
                 "layer %zu (%s): cell_size %g cm gives %.3g cells in %g cm; at "
                 "most 1e8 cells per layer",
                 k, name, h, n, th);
      else spec->ncells = n < 1 ? 1 : (long)n;
    }
  } else {
    dk_error(e, doc, L, "layer %zu (%s): missing 'cells' (count) or 'cell_size' (cm)", k, name);
  }

  double rho0 = spec->eos ? eos_rho0(spec->eos) : 1.0;
  dk_read_positive(e, doc, L, "density", MS_DIM_DENSITY, false, rho0, &spec->rho);
  dk_read_double(e, doc, L, "velocity", MS_DIM_VELOCITY, false, 0.0, -INFINITY, INFINITY, &spec->u);
  if (dk_get(L, "pressure") && dk_get(L, "energy")) {
    dk_error(e, doc, L, "layer %zu (%s): give energy or pressure, not both", k, name);
  } else if (dk_get(L, "pressure")) {
    spec->e_from_p = true;
    dk_read_double(e, doc, L, "pressure", MS_DIM_PRESSURE, true, 0, -INFINITY, INFINITY, &spec->p);
  } else {
    dk_read_double(e, doc, L, "energy", MS_DIM_SPEC_ENERGY, false, 0.0, -INFINITY, INFINITY,
                   &spec->e);
  }
  const dk_node *gr = dk_get(L, "grading");
  if (gr && dk_expect_map(e, doc, gr, "grading")) {
    int side = 0;
    dk_read_double(e, doc, gr, "ratio", MS_DIM_NONE, true, 1.0, 1.0, 2.0, &spec->grade_ratio);
    dk_read_enum(e, doc, gr, "toward", true, 0, grade_names, &side);
    spec->grade_side = (cont_grade_side)side;
  }
}

/* A tag: {name, node} | {name, x} | {name, layer, side}. */
static void read_tag(dk_errors *e, dk_doc *doc, const dk_node *T, size_t index, const cont_setup *s,
                     cont_tag_spec *tag) {
  char what[48];
  snprintf(what, sizeof what, "tags[%zu]", index);
  if (!dk_expect_map(e, doc, T, what)) return;
  const char *name = NULL;
  dk_read_string(e, doc, T, "name", true, NULL, &name);
  tag->name = name ? name : "tag";
  size_t ntotal = cont_setup_layer_first_node(s, s->nlayers);
  const dk_node *node_n = dk_get(T, "node"), *x_n = dk_get(T, "x"), *layer_n = dk_get(T, "layer");
  int given = !!node_n + !!x_n + !!layer_n;
  if (given != 1) {
    dk_error(e, doc, T, "tag '%s': give exactly one of node, x, layer (+ side)", tag->name);
    return;
  }
  if (node_n) {
    long v = 0;
    if (dk_read_int(e, doc, T, "node", true, 0, -(long)ntotal - 1, (long)ntotal, &v))
      tag->node = v < 0 ? (size_t)((long)ntotal + 1 + v) : (size_t)v;
  } else if (x_n) {
    double x = 0;
    if (!dk_node_double(e, doc, x_n, "x", MS_DIM_LENGTH, &x)) return;
    /* nearest node of the initial grid: walk the layers' uniform/graded cells */
    double xl = s->x_left, best = INFINITY;
    size_t node = 0, j = 0;
    for (size_t k = 0; k < s->nlayers; ++k) {
      const cont_layer_spec *L = &s->layers[k];
      size_t n = (size_t)L->ncells;
      double *dx = ms_calloc(n ? n : 1, sizeof(double));
      cont_layer_sizes(L, dx);
      for (size_t i = 0; i <= n; ++i) {
        if (i > 0) xl += dx[i - 1];
        double d = fabs(xl - x);
        if (d < best) {
          best = d;
          node = j + i;
        }
      }
      j += n;
      free(dx);
    }
    double x_right = xl;
    if (x < s->x_left || x > x_right)
      dk_error(e, doc, x_n, "tag '%s': x = %g is outside the grid [%g, %g]", tag->name, x,
               s->x_left, x_right);
    tag->node = node;
  } else {
    const char *lname = dk_scalar(layer_n);
    size_t found = s->nlayers;
    for (size_t k = 0; k < s->nlayers && lname; ++k)
      if (s->layers[k].name && !strcmp(s->layers[k].name, lname)) {
        found = k;
        break;
      }
    if (found == s->nlayers) {
      dk_error(e, doc, layer_n, "tag '%s': unknown layer '%s'", tag->name, lname ? lname : "?");
      return;
    }
    static const char *const sides[] = {"left", "right", NULL};
    int side = 1;
    dk_read_enum(e, doc, T, "side", false, 1, sides, &side);
    size_t first = cont_setup_layer_first_node(s, found);
    tag->node = side == 0 ? first : first + (size_t)s->layers[found].ncells;
  }
}

cont_problem *cont_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                                dk_errors *e) {
  size_t nerr0 = e->n;
  if (!sec) {
    dk_error(e, doc, NULL, "problem 'continuum' needs a 'continuum:' section");
    return NULL;
  }
  if (!dk_expect_map(e, doc, sec, "continuum")) return NULL;
  cont_problem *p = ms_calloc(1, sizeof *p);
  cont_setup *s = &p->setup;
  cont_setup_defaults(s);

  int geom = 0;
  dk_read_enum(e, doc, sec, "geometry", false, 0, geometry_names, &geom);
  s->geometry = (cont_geometry)geom;

  /* Layers. */
  const dk_node *layers = dk_get(sec, "layers");
  double x_end = 0.0;
  bool x_known = false;
  const dk_node *xl_n = dk_get(sec, "x_left");
  if (xl_n) {
    dk_read_double(e, doc, sec, "x_left", MS_DIM_LENGTH, false, 0.0, -INFINITY, INFINITY,
                   &s->x_left);
    x_end = s->x_left;
    x_known = true;
  }
  if (!layers) {
    dk_error(e, doc, sec, "continuum: missing 'layers' (a list, left to right)");
  } else if (dk_expect_seq(e, doc, layers, "layers")) {
    size_t n = dk_seq_len(layers);
    if (n == 0) dk_error(e, doc, layers, "layers: the list is empty");
    p->layers = ms_calloc(n ? n : 1, sizeof(cont_layer_spec));
    for (size_t k = 0; k < n; ++k) {
      read_layer(e, doc, dk_seq_at(layers, k), k, mats, &x_end, &x_known, &p->layers[k]);
      if (k == 0 && !xl_n) {
        /* x_left follows the first layer's `from` (or 0) */
        const dk_node *from_n = dk_get(dk_seq_at(layers, 0), "from");
        if (from_n) dk_node_double(e, doc, from_n, "from", MS_DIM_LENGTH, &s->x_left);
      }
    }
    s->layers = p->layers;
    s->nlayers = n;
  }
  if (s->geometry != CONT_PLANAR && s->x_left < 0.0)
    dk_error(e, doc, xl_n ? xl_n : sec, "x_left = %g: curvilinear grids need x_left >= 0",
             s->x_left);

  /* Boundaries. */
  read_bc(e, doc, sec, "left", &s->left);
  read_bc(e, doc, sec, "right", &s->right);
  if (s->geometry != CONT_PLANAR && s->x_left == 0.0 && s->left.kind != CONT_BC_WALL)
    dk_error(e, doc, dk_get(sec, "left") ? dk_get(sec, "left") : sec,
             "left boundary: at the axis/centre (x_left = 0) it must be a wall");

  /* Viscosity. */
  const dk_node *visc = dk_get(sec, "viscosity");
  if (visc && dk_expect_map(e, doc, visc, "viscosity")) {
    dk_read_double(e, doc, visc, "quadratic", MS_DIM_NONE, false, s->q_quad, 0.0, 10.0, &s->q_quad);
    dk_read_double(e, doc, visc, "linear", MS_DIM_NONE, false, s->q_lin, 0.0, 10.0, &s->q_lin);
  }

  /* Time control. */
  const dk_node *tm = dk_get(sec, "time");
  if (!tm) {
    dk_error(e, doc, sec, "continuum: missing 'time' (at least time.end)");
  } else if (dk_expect_map(e, doc, tm, "time")) {
    dk_read_positive(e, doc, tm, "end", MS_DIM_TIME, true, 0, &p->t_end);
    if (dk_read_double(e, doc, tm, "cfl", MS_DIM_NONE, false, s->cfl, 0.0, INFINITY, &s->cfl) &&
        !(s->cfl > 0.0 && s->cfl < 1.0))
      dk_error(e, doc, dk_get(tm, "cfl") ? dk_get(tm, "cfl") : tm,
               "time.cfl = %g: the CFL safety factor must satisfy 0 < cfl < 1", s->cfl);
    dk_read_double(e, doc, tm, "dt_initial", MS_DIM_TIME, false, 0.0, 0.0, INFINITY,
                   &s->dt_initial);
    double dtmax = 0.0;
    dk_read_double(e, doc, tm, "dt_max", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &dtmax);
    s->dt_max = dtmax > 0.0 ? dtmax : INFINITY;
    dk_read_positive(e, doc, tm, "dt_min", MS_DIM_TIME, false, s->dt_min, &s->dt_min);
    dk_read_double(e, doc, tm, "growth", MS_DIM_NONE, false, s->dt_growth, 1.0, 2.0, &s->dt_growth);
    long ms = 0;
    dk_read_int(e, doc, tm, "max_steps", false, 0, 0, (long)1e15, &ms);
    p->max_steps = ms;
  }

  /* Outputs. */
  const dk_node *out = dk_get(sec, "output");
  p->xt_frames = 200;
  p->history_stride = 1;
  if (out && dk_expect_map(e, doc, out, "output")) {
    dk_read_double_list(e, doc, out, "times", MS_DIM_TIME, false, &p->out_times, &p->n_out);
    for (size_t k = 0; k < p->n_out; ++k) {
      if (p->t_end > 0.0 && p->out_times[k] > p->t_end) {
        dk_error(e, doc, dk_get(out, "times"), "output.times entry %zu = %g is after time.end = %g",
                 k, p->out_times[k], p->t_end);
        break;
      }
      if (p->out_times[k] < 0.0 || (k > 0 && !(p->out_times[k] > p->out_times[k - 1]))) {
        dk_error(e, doc, dk_get(out, "times"),
                 "output.times must be >= 0 and increasing (entry %zu = %g)", k, p->out_times[k]);
        break;
      }
    }
    long v = 0;
    if (dk_read_int(e, doc, out, "history_stride", false, 1, 1, 1000000000, &v))
      p->history_stride = v;
    if (dk_read_int(e, doc, out, "xt_frames", false, 200, 0, 100000, &v)) p->xt_frames = v;
    int xq = 0;
    dk_read_enum(e, doc, out, "xt_quantity", false, 0, xt_names, &xq);
    p->xt_quantity = xq;
  }

  /* Tags (after layers: they refer to layer names and cell counts). */
  const dk_node *tags = dk_get(sec, "tags");
  if (tags && dk_expect_seq(e, doc, tags, "tags") && e->n == nerr0) {
    size_t n = dk_seq_len(tags);
    p->tags = ms_calloc(n ? n : 1, sizeof(cont_tag_spec));
    for (size_t k = 0; k < n; ++k) read_tag(e, doc, dk_seq_at(tags, k), k, s, &p->tags[k]);
    for (size_t k = 0; k < n; ++k)
      for (size_t j = 0; j < k; ++j)
        if (p->tags[j].name && p->tags[k].name && !strcmp(p->tags[j].name, p->tags[k].name))
          dk_error(e, doc, dk_seq_at(tags, k), "tag name '%s' used twice", p->tags[k].name);
    s->tags = p->tags;
    s->ntags = n;
  } else if (tags && dk_node_kind(tags) == DK_SEQ) {
    /* layers had errors, so tags cannot be resolved: mark their keys used, so they are not
     * also reported as unknown */
    static const char *const keys[] = {"name", "node", "x", "layer", "side"};
    for (size_t k = 0; k < dk_seq_len(tags); ++k)
      for (size_t j = 0; j < sizeof keys / sizeof keys[0]; ++j) dk_get(dk_seq_at(tags, k), keys[j]);
  }

  if (e->n != nerr0) {
    cont_problem_destroy(&p);
    return NULL;
  }
  char err[512] = "";
  cont_grid_create(s, &p->grid, err, sizeof err);
  if (!p->grid) {
    dk_error(e, doc, sec, "continuum: %s", err);
    cont_problem_destroy(&p);
    return NULL;
  }
  return p;
}

static void cont_problem_free(cont_problem *p) {
  if (!p) return;
  cont_grid_destroy(&p->grid);
  cont_fn_free(&p->setup.left.fn);
  cont_fn_free(&p->setup.right.fn);
  free(p->layers);
  free(p->tags);
  free(p->out_times);
  free(p);
}

void cont_problem_destroy(cont_problem **p) {
  if (!p) return;
  cont_problem_free(*p);
  *p = NULL;
}

cont_grid *cont_problem_grid(cont_problem *p) { return p ? p->grid : NULL; }
