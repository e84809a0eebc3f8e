/* SPDX-License-Identifier: MIT */
/* grid.c — building the grid from layers, its accessors, the energy budget and coupling hooks. */
#include "cont_impl.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void cont_setup_defaults(cont_setup *s) {
  memset(s, 0, sizeof *s);
  s->geometry = CONT_PLANAR;
  s->left.kind = CONT_BC_WALL;
  s->right.kind = CONT_BC_WALL;
  s->q_quad = 1.0;
  s->q_lin = 0.2;
  s->cfl = 0.5;
  s->dt_max = INFINITY;
  s->dt_min = 1e-12;
  s->dt_growth = 1.1;
}

size_t cont_setup_layer_first_node(const cont_setup *s, size_t layer) {
  size_t n = 0;
  for (size_t k = 0; k < layer && k < s->nlayers; ++k) n += (size_t)s->layers[k].ncells;
  return n;
}

/* ------------------------------------------------------------------------------------------ */
/* Time functions                                                                              */

double cont_fn_eval(const cont_fn *f, double t) {
  switch (f->kind) {
  case CONT_FN_CONST:
    return f->value;
  case CONT_FN_TABLE: {
    if (f->n == 0) return 0.0;
    if (t <= f->t[0]) return f->v[0];
    if (t >= f->t[f->n - 1]) return f->v[f->n - 1];
    size_t lo = 0, hi = f->n - 1; /* t[lo] <= t < t[hi] */
    while (hi - lo > 1) {
      size_t mid = (lo + hi) / 2;
      if (f->t[mid] <= t) lo = mid;
      else hi = mid;
    }
    double w = (t - f->t[lo]) / (f->t[hi] - f->t[lo]);
    return f->v[lo] + w * (f->v[hi] - f->v[lo]);
  }
  case CONT_FN_TRAPEZOID: {
    double s = t - f->t0;
    if (s <= 0.0) return 0.0;
    if (s < f->rise) return f->value * s / f->rise;
    s -= f->rise;
    if (s <= f->hold) return f->value;
    s -= f->hold;
    if (s < f->fall) return f->value * (1.0 - s / f->fall);
    return 0.0;
  }
  case CONT_FN_EXP_DECAY: {
    double s = t - f->t0;
    if (s <= 0.0) return 0.0;
    double ramp = (f->rise > 0.0 && s < f->rise) ? s / f->rise : 1.0;
    return ramp * f->value * exp(-s / f->tau);
  }
  }
  return 0.0;
}

void cont_fn_free(cont_fn *f) {
  if (!f) return;
  free(f->t);
  free(f->v);
  f->t = f->v = NULL;
  f->n = 0;
}

void cont_fn_copy(cont_fn *dst, const cont_fn *src) {
  *dst = *src;
  if (src->kind == CONT_FN_TABLE && src->n > 0) {
    dst->t = ms_calloc(src->n, sizeof(double));
    dst->v = ms_calloc(src->n, sizeof(double));
    memcpy(dst->t, src->t, src->n * sizeof(double));
    memcpy(dst->v, src->v, src->n * sizeof(double));
  } else {
    dst->t = dst->v = NULL;
    dst->n = 0;
  }
}

/* ------------------------------------------------------------------------------------------ */
/* Initial state                                                                               */

bool cont_energy_from_pressure(const eos_t *eos, double rho, double p, double *e) {
  /* p(ρ, e) is increasing in e for every EOS we have (Γ > 0): bracket, then bisect/secant. */
  double lo = 0.0, hi = 1.0;
  double flo = eos_pressure(eos, rho, lo) - p;
  if (!isfinite(flo)) return false;
  if (flo > 0.0) { /* root at negative e (cold compressed material under low pressure) */
    hi = lo;
    double step = 1.0;
    for (int k = 0; k < 200 && flo > 0.0; ++k, step *= 2.0) {
      hi = lo;
      lo -= step;
      flo = eos_pressure(eos, rho, lo) - p;
      if (!isfinite(flo)) return false;
    }
  } else {
    double fhi = eos_pressure(eos, rho, hi) - p;
    for (int k = 0; k < 200 && fhi < 0.0; ++k) {
      lo = hi;
      hi *= 2.0;
      fhi = eos_pressure(eos, rho, hi) - p;
      if (!isfinite(fhi)) return false;
    }
    if (fhi < 0.0) return false;
  }
  if (eos_pressure(eos, rho, lo) - p > 0.0 || eos_pressure(eos, rho, hi) - p < 0.0) return false;
  for (int it = 0; it < 200; ++it) {
    double mid = 0.5 * (lo + hi);
    if (mid == lo || mid == hi) break;
    if (eos_pressure(eos, rho, mid) - p < 0.0) lo = mid;
    else hi = mid;
  }
  *e = 0.5 * (lo + hi);
  return true;
}

static void set_err(char *err, size_t errlen, const char *fmt, ...) {
  if (!err || errlen == 0) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
}

/* Cell sizes of a layer: uniform, or a geometric series with ratio r whose smallest cell sits at
 * the graded end(s): sizes ∝ r^k counted from that end. */
void cont_layer_sizes(const cont_layer_spec *L, double *dx) {
  size_t n = (size_t)L->ncells;
  double r = L->grade_ratio > 1.0 ? L->grade_ratio : 1.0;
  if (L->grade_side == CONT_GRADE_NONE || r == 1.0) {
    for (size_t k = 0; k < n; ++k) dx[k] = L->thickness / (double)n;
    return;
  }
  double sum = 0.0;
  for (size_t k = 0; k < n; ++k) {
    double from_end;
    switch (L->grade_side) {
    case CONT_GRADE_LEFT:
      from_end = (double)k;
      break;
    case CONT_GRADE_RIGHT:
      from_end = (double)(n - 1 - k);
      break;
    default: { /* both ends fine, coarsest in the middle */
      double a = (double)k, b = (double)(n - 1 - k);
      from_end = a < b ? a : b;
    }
    }
    dx[k] = pow(r, from_end);
    sum += dx[k];
  }
  for (size_t k = 0; k < n; ++k) dx[k] *= L->thickness / sum;
}

static double *alloc_doubles(size_t n) { return ms_aligned_alloc(n, sizeof(double)); }

/* The set-up's own consistency; the cell count, or 0 with *err set. */
static size_t setup_cells(const cont_setup *s, char *err, size_t errlen) {
  if (s->nlayers == 0) {
    set_err(err, errlen, "no layers");
    return 0;
  }
  if (!(s->cfl > 0.0 && s->cfl < 1.0)) {
    set_err(err, errlen, "cfl = %g must lie in (0, 1)", s->cfl);
    return 0;
  }
  if (s->geometry != CONT_PLANAR && s->x_left < 0.0) {
    set_err(err, errlen, "x_left = %g < 0 in curvilinear geometry", s->x_left);
    return 0;
  }
  size_t ncells = 0;
  for (size_t k = 0; k < s->nlayers; ++k) {
    const cont_layer_spec *L = &s->layers[k];
    if (L->ncells <= 0 || !(L->thickness > 0.0) || !(L->rho > 0.0) || !L->eos) {
      set_err(err, errlen, "layer %zu (%s): needs cells > 0, thickness > 0, density > 0, an EOS", k,
              L->name ? L->name : "?");
      return 0;
    }
    ncells += (size_t)L->ncells;
  }
  return ncells;
}

/* grid_alloc's arrays per cell: 7 node and 7 cell arrays of doubles, 2 of ints (the CONT_WINDOW
 * arrays do not grow with the grid). */
size_t cont_grid_bytes_per_cell(void) { return 14 * sizeof(double) + 2 * sizeof(int); }

/* The grid's arrays, sized once for ncells cells. */
static cont_grid *grid_alloc(const cont_setup *s, size_t ncells) {
  cont_grid *g = ms_calloc(1, sizeof *g);
  g->geometry = s->geometry;
  g->area_power = (int)s->geometry;
  g->ncells = ncells;
  g->nnodes = ncells + 1;
  size_t N = ncells, Nn = ncells + 1;
  g->x = alloc_doubles(Nn);
  g->u = alloc_doubles(Nn);
  g->inv_mass = alloc_doubles(Nn);
  g->u_pred_mean = alloc_doubles(CONT_WINDOW);
  g->area_mid = alloc_doubles(CONT_WINDOW);
  g->u_mean = alloc_doubles(CONT_WINDOW);
  g->ext_traction = alloc_doubles(Nn);
  g->ext_velocity = alloc_doubles(Nn);
  g->reaction = alloc_doubles(Nn);
  g->force = alloc_doubles(Nn);
  g->mass = alloc_doubles(N);
  g->inv_cell_mass = alloc_doubles(N);
  g->rho = alloc_doubles(N);
  g->e = alloc_doubles(N);
  g->p = alloc_doubles(N);
  g->q = alloc_doubles(N);
  g->c = alloc_doubles(N);
  g->rho_half = alloc_doubles(CONT_WINDOW);
  g->e_half = alloc_doubles(CONT_WINDOW);
  g->p_half = alloc_doubles(CONT_WINDOW);
  g->q_half = alloc_doubles(CONT_WINDOW);
  g->material = ms_calloc(N, sizeof(int));
  g->layer = ms_calloc(N, sizeof(int));
  g->nregions = s->nlayers;
  g->regions = ms_calloc(s->nlayers, sizeof(cont_region));
  for (size_t j = 0; j < Nn; ++j) g->ext_velocity[j] = NAN;
  g->land_time = NAN;
  return g;
}

/* Node positions and cell states, layer by layer; false with *err set. */
static bool place_layers(cont_grid *g, const cont_setup *s, char *err, size_t errlen) {
  size_t N = g->ncells;
  double *dx = ms_calloc(N, sizeof(double));
  size_t i0 = 0;
  double xpos = s->x_left;
  g->x[0] = xpos;
  for (size_t k = 0; k < s->nlayers; ++k) {
    const cont_layer_spec *L = &s->layers[k];
    size_t n = (size_t)L->ncells;
    cont_layer_sizes(L, dx + i0);
    double e0 = L->e;
    if (L->e_from_p && !cont_energy_from_pressure(L->eos, L->rho, L->p, &e0)) {
      set_err(err, errlen, "layer %zu (%s): no energy gives pressure %g at density %g", k,
              L->name ? L->name : "?", L->p, L->rho);
      free(dx);
      return false;
    }
    g->regions[k] = (cont_region){.first = i0, .n = n, .eos = L->eos, .material = L->material};
    for (size_t i = i0; i < i0 + n; ++i) {
      xpos += dx[i];
      g->x[i + 1] = xpos;
      g->rho[i] = L->rho;
      g->e[i] = e0;
      g->material[i] = L->material;
      g->layer[i] = (int)k;
    }
    i0 += n;
  }
  /* The last node lands on the exact layer end within round-off; the first on x_left. */
  free(dx);
  return true;
}

/* Cell masses and lumped node masses and velocities. A node inside a layer takes the layer's
 * velocity; a contact node the mass-weighted mean of its two cells (the initial momentum is then
 * exactly Σ m_i u_i). False with *err set. */
static bool node_masses(cont_grid *g, const cont_setup *s, char *err, size_t errlen) {
  size_t N = g->ncells, Nn = g->nnodes;
  double *node_mass = ms_calloc(Nn, sizeof(double));
  double *node_mom = ms_calloc(Nn, sizeof(double));
  for (size_t i = 0; i < N; ++i) {
    double v = cont_cell_volume(g, g->x[i], g->x[i + 1]);
    g->mass[i] = g->rho[i] * v;
    g->inv_cell_mass[i] = 1.0 / g->mass[i];
    double uc = s->layers[g->layer[i]].u;
    node_mass[i] += 0.5 * g->mass[i];
    node_mass[i + 1] += 0.5 * g->mass[i];
    node_mom[i] += 0.5 * g->mass[i] * uc;
    node_mom[i + 1] += 0.5 * g->mass[i] * uc;
  }
  for (size_t j = 0; j < Nn; ++j) {
    g->inv_mass[j] = 1.0 / node_mass[j];
    g->u[j] = node_mom[j] / node_mass[j];
  }
  free(node_mass);
  free(node_mom);
  for (size_t i = 0; i < N; ++i) {
    if (!(g->mass[i] > 0.0)) {
      set_err(err, errlen, "cell %zu has mass %g (layers too thin for their cell count?)", i,
              g->mass[i]);
      return false;
    }
  }
  return true;
}

ms_status cont_grid_create(const cont_setup *s, cont_grid **out, char *err, size_t errlen) {
  *out = NULL;
  size_t ncells = setup_cells(s, err, errlen);
  if (ncells == 0) return MS_ERR_INPUT;
  cont_grid *g = grid_alloc(s, ncells);
  size_t N = ncells, Nn = ncells + 1;
  if (!place_layers(g, s, err, errlen) || !node_masses(g, s, err, errlen)) {
    cont_grid_destroy(&g);
    return MS_ERR_INPUT;
  }

  cont_fn_copy(&g->left.fn, &s->left.fn);
  g->left.kind = s->left.kind;
  cont_fn_copy(&g->right.fn, &s->right.fn);
  g->right.kind = s->right.kind;
  /* Boundary nodes start at the prescribed velocity (wall 0, piston u(0)). */
  if (s->left.kind == CONT_BC_WALL) g->u[0] = 0.0;
  if (s->left.kind == CONT_BC_PISTON) g->u[0] = cont_fn_eval(&g->left.fn, 0.0);
  if (s->right.kind == CONT_BC_WALL) g->u[N] = 0.0;
  if (s->right.kind == CONT_BC_PISTON) g->u[N] = cont_fn_eval(&g->right.fn, 0.0);

  g->q_quad = s->q_quad;
  g->q_lin = s->q_lin;
  g->cfl = s->cfl;
  g->dt_max = s->dt_max > 0.0 ? s->dt_max : INFINITY;
  g->dt_min = s->dt_min;
  g->dt_growth = s->dt_growth > 1.0 ? s->dt_growth : 1.1;

  ms_status st = MS_OK;
  size_t bad = 0;
  cont_eval_eos_for_cells(g, 0, N, g->rho, g->e, g->p, g->c, &bad, &st);
  if (st != MS_OK) {
    set_err(err, errlen,
            "initial state of cell %zu (layer %d: rho = %g, e = %g) is outside its EOS", bad,
            g->layer[bad], g->rho[bad], g->e[bad]);
    cont_grid_destroy(&g);
    return MS_ERR_INPUT;
  }
  cont_calc_q_for_cells(g, 0, N, g->rho, g->u, g->c, g->q);
  double dtc = cont_calc_time_constraint(g, 0, N);
  g->dt_next = s->dt_initial > 0.0 ? s->dt_initial : 0.1 * dtc;
  if (g->dt_next > g->dt_max) g->dt_next = g->dt_max;
  if (!(g->dt_next > 0.0) || !isfinite(g->dt_next)) {
    /* nothing moves and no sound speed: any step is stable; fall back to dt_max or 1e-3 */
    g->dt_next = isfinite(g->dt_max) ? g->dt_max : 1e-3;
  }

  for (size_t k = 0; k < s->ntags; ++k) {
    if (s->tags[k].node >= Nn) {
      set_err(err, errlen, "tag '%s': node %zu outside 0..%zu", s->tags[k].name, s->tags[k].node,
              N);
      cont_grid_destroy(&g);
      return MS_ERR_INPUT;
    }
    cont_grid_add_tag(g, s->tags[k].name, s->tags[k].node);
  }
  *out = g;
  return MS_OK;
}

static void cont_grid_release(cont_grid *g) {
  if (!g) return;
  double **arrays[] = {&g->x,
                       &g->u,
                       &g->inv_mass,
                       &g->u_pred_mean,
                       &g->area_mid,
                       &g->u_mean,
                       &g->ext_traction,
                       &g->ext_velocity,
                       &g->reaction,
                       &g->force,
                       &g->mass,
                       &g->inv_cell_mass,
                       &g->rho,
                       &g->e,
                       &g->p,
                       &g->q,
                       &g->c,
                       &g->rho_half,
                       &g->e_half,
                       &g->p_half,
                       &g->q_half};
  for (size_t k = 0; k < sizeof arrays / sizeof arrays[0]; ++k) free(*arrays[k]);
  free(g->material);
  free(g->layer);
  free(g->regions);
  cont_fn_free(&g->left.fn);
  cont_fn_free(&g->right.fn);
  for (size_t k = 0; k < g->ntags; ++k) {
    cont_tag *tg = &g->tags[k];
    free(tg->name);
    free(tg->t);
    free(tg->x);
    free(tg->u);
    free(tg->p_left);
    free(tg->rho_left);
    free(tg->p_right);
    free(tg->rho_right);
  }
  free(g->tags);
  free(g);
}

void cont_grid_destroy(cont_grid **g) {
  if (!g) return;
  cont_grid_release(*g);
  *g = NULL;
}

/* ------------------------------------------------------------------------------------------ */
/* Accessors                                                                                   */

const char *cont_grid_error(const cont_grid *g) { return g->err; }
double cont_grid_time(const cont_grid *g) { return g->t; }
long cont_grid_steps(const cont_grid *g) { return g->step; }
double cont_grid_last_dt(const cont_grid *g) { return g->dt_last; }
size_t cont_grid_ncells(const cont_grid *g) { return g->ncells; }
cont_geometry cont_grid_geometry(const cont_grid *g) { return g->geometry; }

cont_view cont_grid_view(const cont_grid *g) {
  return (cont_view){.ncells = g->ncells,
                     .nnodes = g->nnodes,
                     .x = g->x,
                     .u = g->u,
                     .rho = g->rho,
                     .e = g->e,
                     .p = g->p,
                     .q = g->q,
                     .c = g->c,
                     .mass = g->mass,
                     .material = g->material,
                     .layer = g->layer};
}

cont_balance cont_grid_balance(const cont_grid *g) {
  cont_balance b = {0};
  for (size_t i = 0; i < g->ncells; ++i) b.internal += g->mass[i] * g->e[i];
  for (size_t j = 0; j < g->nnodes; ++j) {
    double m = 1.0 / g->inv_mass[j];
    b.kinetic += 0.5 * m * g->u[j] * g->u[j];
    b.momentum += m * g->u[j];
  }
  b.work = g->work;
  b.impulse = g->impulse;
  b.source_energy = g->src_energy;
  b.source_momentum = g->src_momentum;
  return b;
}

/* ------------------------------------------------------------------------------------------ */
/* Coupling hooks                                                                              */

static void update_any_ext(cont_grid *g) {
  bool any = false;
  for (size_t j = 0; j < g->nnodes && !any; ++j)
    any = g->ext_traction[j] != 0.0 || !isnan(g->ext_velocity[j]);
  g->any_ext = any;
}

void cont_grid_set_node_force(cont_grid *g, size_t node, double traction) {
  if (node >= g->nnodes) return;
  g->ext_traction[node] = traction;
  if (traction != 0.0) g->any_ext = true;
  else update_any_ext(g);
}

void cont_grid_set_node_velocity(cont_grid *g, size_t node, double u) {
  if (node >= g->nnodes) return;
  g->ext_velocity[node] = u;
  if (!isnan(u)) g->any_ext = true;
  else update_any_ext(g);
}

double cont_grid_node_reaction(const cont_grid *g, size_t node) {
  return node < g->nnodes ? g->reaction[node] : NAN;
}

ms_status cont_grid_add_cell_source(cont_grid *g, size_t cell, double dp, double de) {
  if (cell >= g->ncells || !isfinite(dp) || !isfinite(de)) {
    snprintf(g->err, sizeof g->err, "cell source: cell %zu of %zu, dp = %g, de = %g", cell,
             g->ncells, dp, de);
    return MS_ERR_UNSTABLE;
  }
  const size_t j = cell;
  const double mL = 1.0 / g->inv_mass[j], mR = 1.0 / g->inv_mass[j + 1];
  const double du = dp / (mL + mR);
  /* kinetic energy the nodes gain: Σ M (u Δu + ½ Δu²) */
  const double dke = mL * du * (g->u[j] + 0.5 * du) + mR * du * (g->u[j + 1] + 0.5 * du);
  const double e_old = g->e[cell], p_old = g->p[cell], c_old = g->c[cell];
  const double e_new = e_old + (de - dke) * g->inv_cell_mass[cell];
  if (!(e_new >= 0.0)) {
    snprintf(g->err, sizeof g->err,
             "cell source: cell %zu would get e = %g (dp = %g, de = %g, kinetic %g)", cell, e_new,
             dp, de, dke);
    return MS_ERR_UNSTABLE;
  }
  g->e[cell] = e_new;
  size_t bad = 0;
  ms_status st = MS_OK;
  cont_eval_eos_for_cells(g, cell, cell + 1, g->rho, g->e, g->p, g->c, &bad, &st);
  if (st != MS_OK || !isfinite(g->p[cell])) {
    g->e[cell] = e_old;
    g->p[cell] = p_old;
    g->c[cell] = c_old;
    snprintf(g->err, sizeof g->err, "cell source: EOS failed in cell %zu at e = %g", cell, e_new);
    return MS_ERR_UNSTABLE;
  }
  g->u[j] += du;
  g->u[j + 1] += du;
  g->work += de;
  g->impulse += dp;
  g->src_energy += de;
  g->src_momentum += dp;
  return MS_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Sampling                                                                                    */

size_t cont_grid_nearest_node(const cont_grid *g, double x) {
  size_t lo = 0, hi = g->nnodes - 1;
  if (x <= g->x[0]) return 0;
  if (x >= g->x[hi]) return hi;
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (g->x[mid] <= x) lo = mid;
    else hi = mid;
  }
  return (x - g->x[lo] <= g->x[hi] - x) ? lo : hi;
}

bool cont_grid_sample(const cont_grid *g, double x, cont_sample *out) {
  size_t N = g->ncells;
  if (!(x >= g->x[0] && x <= g->x[N])) return false;
  size_t lo = 0, hi = N; /* x[lo] <= x <= x[hi] */
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (g->x[mid] <= x) lo = mid;
    else hi = mid;
  }
  size_t i = lo;
  double w = (x - g->x[i]) / (g->x[i + 1] - g->x[i]);
  out->cell = i;
  out->rho = g->rho[i];
  out->p = g->p[i];
  out->e = g->e[i];
  out->c = g->c[i];
  out->u = (1.0 - w) * g->u[i] + w * g->u[i + 1];
  out->material = g->material[i];
  out->layer = g->layer[i];
  return true;
}
