/* SPDX-License-Identifier: MIT */
/* grid2d_setup.c — set-up and teardown of the 2D grid (node masses, boundary normals, the
 * first state and time step), its tag lines, and what callers read of it (cont2d.h). The
 * scheme itself: grid2d.c.
 */
#include "grid2d_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *xcalloc(size_t n, size_t sz) { return calloc(n ? n : 1, sz); }

void c2d_setup_defaults(c2d_setup *s) {
  memset(s, 0, sizeof *s);
  s->geometry = C2D_XY;
  s->q1 = 0.5;
  s->q2 = 1.0;
  s->q_gamma = 5.0 / 3.0;
  s->use_limiter = true;
  s->hg_coef = 0.0;
  s->cfl = 0.5;
  s->dv_max = 0.1;
  s->dt_max = INFINITY;
  s->dt_min = 1e-12;
  s->dt_growth = 1.1;
}

/* Zones: densities, energies, materials, corner and zone masses, node masses, the EOS runs;
 * a tangled zone or one without ρ > 0 and an EOS is reported in err (false). */
static bool init_zones(c2d_grid *g, const c2d_setup *s, char *err, size_t errlen) {
  const size_t nz = g->nz;
  for (size_t z = 0; z < nz; ++z) {
    double X[4], Y[4];
    gather(g, z, g->x, g->y, X, Y);
    double a = quad_area(X, Y);
    double xc = 0.25 * (X[0] + X[1] + X[2] + X[3]), yc = 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]);
    bool ok = a > 0.0;
    for (int k = 0; k < 4 && ok; ++k) {
      double CX[4], CY[4];
      corner_quad(X, Y, xc, yc, k, CX, CY);
      if (!(quad_area(CX, CY) > 0.0)) ok = false;
    }
    if (!ok) {
      snprintf(err, errlen,
               "2D grid: zone %zu (i = %zu, j = %zu, near x = %.6g, y = %.6g) is tangled or "
               "inverted (area %.6g, or a corner of non-positive area)",
               z, z % g->ni, z / g->ni, xc, yc, a);
      return false;
    }
    if (!(s->rho[z] > 0.0) || !s->eos[z]) {
      snprintf(err, errlen, "2D grid: zone %zu needs ρ > 0 and an EOS", z);
      return false;
    }
    g->rho[z] = s->rho[z];
    g->e[z] = s->e[z];
    g->material[z] = s->material ? s->material[z] : 0;
    double mz = 0.0;
    for (int k = 0; k < 4; ++k) {
      double CX[4], CY[4];
      corner_quad(X, Y, xc, yc, k, CX, CY);
      g->mc[4 * z + k] = s->rho[z] * poly_volume(g->geo, CX, CY);
      mz += g->mc[4 * z + k];
    }
    g->m[z] = mz;
    size_t nd[4];
    zone_nodes(g, z, nd);
    if (g->geo == C2D_RZ && !g->area_weighted) {
      /* r–z control-volume form: node masses lumped with the bilinear shape functions,
       * M_p += ρ0 ∫_z N_p r dA (2 × 2 Gauss points, exact for this integrand), the partition
       * that matches the force P ∂V/∂x_p: a flow along z stays uniform across r (the median
       * corner masses make the axis nodes 4/3 too light for their force — axis jetting). */
      double mf[4], maf[4];
      c2d_fe_lumped(X, Y, mf, maf);
      /* scale so that Σ_p M_p = Σ_z m_z exactly (the quadrature is exact up to round-off) */
      double sm = mf[0] + mf[1] + mf[2] + mf[3];
      for (int k = 0; k < 4; ++k) g->M[nd[k]] += mz * mf[k] / sm;
    } else {
      for (int k = 0; k < 4; ++k) g->M[nd[k]] += g->mc[4 * z + k];
    }
    if (g->nruns == 0 || g->runs[g->nruns - 1].eos != s->eos[z]) {
      g->runs[g->nruns].first = z;
      g->runs[g->nruns].eos = s->eos[z];
      g->runs[g->nruns].n = 0;
      g->nruns++;
    }
    g->runs[g->nruns - 1].n++;
  }
  return true;
}

static c2d_grid *grid_make(const c2d_setup *s, char *err, size_t errlen) {
  if (s->ni < 1 || s->nj < 1 || !s->x || !s->y || !s->rho || !s->e || !s->eos) {
    snprintf(err, errlen, "2D grid: need ni, nj ≥ 1 and node positions, ρ, e and an EOS per zone");
    return NULL;
  }
  if (!(s->cfl > 0.0 && s->cfl < 1.0) || !(s->dt_growth > 1.0) || s->q1 < 0 || s->q2 < 0 ||
      s->hg_coef < 0) {
    snprintf(err, errlen, "2D grid: need 0 < cfl < 1, dt_growth > 1, q1, q2, hg ≥ 0");
    return NULL;
  }
  c2d_grid *g = xcalloc(1, sizeof *g);
  g->geo = s->geometry;
  g->ni = s->ni;
  g->nj = s->nj;
  g->nn = (s->ni + 1) * (s->nj + 1);
  g->nz = s->ni * s->nj;
  size_t nn = g->nn, nz = g->nz;
  double **na[] = {&g->x, &g->y, &g->u, &g->v, &g->M, &g->xh, &g->yh, &g->uh, &g->vh};
  for (size_t k = 0; k < sizeof na / sizeof na[0]; ++k) *na[k] = xcalloc(nn, sizeof(double));
  g->rx0 = xcalloc(2 * nn, sizeof(double));
  g->ex = xcalloc(nn, sizeof(double));
  g->ey = xcalloc(nn, sizeof(double));
  double **za[] = {&g->m, &g->rho, &g->e, &g->p, &g->c, &g->vol, &g->rhoh, &g->ph, &g->ch};
  for (size_t k = 0; k < sizeof za / sizeof za[0]; ++k) *za[k] = xcalloc(nz, sizeof(double));
  g->mc = xcalloc(4 * nz, sizeof(double));
  g->material = xcalloc(nz, sizeof(int));
  g->runs = xcalloc(nz, sizeof(c2d_run));
  g->nthreads = 1;
  c2d_scratch_alloc(g);
  memcpy(g->x, s->x, nn * sizeof(double));
  memcpy(g->y, s->y, nn * sizeof(double));
  if (s->u) memcpy(g->u, s->u, nn * sizeof(double));
  if (s->v) memcpy(g->v, s->v, nn * sizeof(double));
  g->q1 = s->q1;
  g->q2 = s->q2;
  g->zeta = 0.25 * (s->q_gamma + 1.0);
  g->limiter = s->use_limiter;
  g->area_weighted = s->geometry == C2D_RZ && s->rz_area_weighted;
  g->hg = s->hg_coef;
  g->cfl = s->cfl;
  g->dv_max = s->dv_max > 0 ? s->dv_max : 0.1;
  g->dt_max = s->dt_max > 0 ? s->dt_max : INFINITY;
  g->dt_min = s->dt_min;
  g->dt_growth = s->dt_growth;
  const double side_normal[4][2] = {{1, 0}, {1, 0}, {0, 1}, {0, 1}};
  for (int k = 0; k < 4; ++k) {
    g->bc[k] = s->bc[k];
    if (g->bc[k].kind == C2D_BC_PRESSURE) g->has_pressure = true;
    cont_fn_copy(&g->bc[k].fn, &s->bc[k].fn);
    if (g->bc[k].kind == C2D_BC_WALL && g->bc[k].normal[0] == 0.0 && g->bc[k].normal[1] == 0.0) {
      g->bc[k].normal[0] = side_normal[k][0];
      g->bc[k].normal[1] = side_normal[k][1];
    }
    double nl = hypot(g->bc[k].normal[0], g->bc[k].normal[1]);
    if (nl > 0) {
      g->bc[k].normal[0] /= nl;
      g->bc[k].normal[1] /= nl;
    }
  }
  for (size_t n = 0; n < nn; ++n) {
    double r = hypot(g->x[n], g->y[n]);
    if (r > 0) {
      g->rx0[2 * n] = g->x[n] / r;
      g->rx0[2 * n + 1] = g->y[n] / r;
    }
    if (g->geo == C2D_RZ && g->x[n] < 0.0) {
      snprintf(err, errlen, "r–z grid: node %zu (i = %zu, j = %zu) has r = %.6g < 0", n,
               n % (g->ni + 1), n / (g->ni + 1), g->x[n]);
      c2d_grid_destroy(&g);
      return NULL;
    }
  }
  /* Zones: masses from the corner volumes; tangled zones are reported. */
  if (!init_zones(g, s, err, errlen)) {
    c2d_grid_destroy(&g);
    return NULL;
  }
  for (size_t n = 0; n < nn; ++n) {
    if (!(g->M[n] > 0.0)) {
      /* Degenerate r = 0 nodes of an r–z polar centre carry no mass; they must be fixed. */
      g->M[n] = 0.0;
    }
  }
  if (c2d_zone_state(g, g->x, g->y, g->e, g->vol, g->rho, g->p, g->c) != MS_OK) {
    snprintf(err, errlen, "2D grid at set-up: %s", g->err);
    c2d_grid_destroy(&g);
    return NULL;
  }
  for (size_t n = 0; n < nn; ++n) c2d_apply_bc(g, n, 0.0, &g->u[n], &g->v[n]);
  double dt = c2d_stable_dt(g);
  g->dt_next = s->dt_initial > 0 ? s->dt_initial : 0.1 * dt;
  if (!isfinite(g->dt_next)) g->dt_next = g->dt_max < INFINITY ? g->dt_max : 1e-6;
  return g;
}

ms_status c2d_grid_create(const c2d_setup *s, c2d_grid **out, char *err, size_t errlen) {
  *out = grid_make(s, err, errlen);
  return *out ? MS_OK : MS_ERR_INPUT;
}

static void c2d_grid_release(c2d_grid *g) {
  if (!g) return;
  double *arr[] = {g->x,   g->y, g->u, g->v, g->M,   g->xh,   g->yh, g->uh, g->vh, g->rx0,  g->m,
                   g->rho, g->e, g->p, g->c, g->vol, g->rhoh, g->ph, g->ch, g->mc, g->wside};
  c2d_scratch_free(g);
  for (size_t k = 0; k < sizeof arr / sizeof arr[0]; ++k) free(arr[k]);
  for (int k = 0; k < 4; ++k) cont_fn_free(&g->bc[k].fn);
  free(g->ex);
  free(g->ey);
  for (size_t k = 0; k < g->ntags; ++k) {
    c2d_tagline *tl = &g->tags[k];
    free(tl->name);
    free(tl->node);
    free(tl->t);
    free(tl->x);
    free(tl->y);
    free(tl->u);
    free(tl->v);
  }
  free(g->tags);
  free(g->material);
  free(g->runs);
  free(g);
}

void c2d_grid_destroy(c2d_grid **g) {
  if (!g) return;
  c2d_grid_release(*g);
  *g = NULL;
}

void c2d_tag_record(const c2d_grid *g, c2d_tagline *tl) {
  if (tl->n + 1 > tl->cap) {
    size_t cap = tl->cap ? 2 * tl->cap : 256;
    tl->t = ms_realloc(tl->t, cap, sizeof(double));
    double **cols[] = {&tl->x, &tl->y, &tl->u, &tl->v};
    for (int c = 0; c < 4; ++c) *cols[c] = ms_realloc(*cols[c], cap * tl->nnodes, sizeof(double));
    tl->cap = cap;
  }
  size_t r = tl->n * tl->nnodes;
  tl->t[tl->n] = g->t;
  for (size_t k = 0; k < tl->nnodes; ++k) {
    size_t nd = tl->node[k];
    tl->x[r + k] = g->x[nd];
    tl->y[r + k] = g->y[nd];
    tl->u[r + k] = g->u[nd];
    tl->v[r + k] = g->v[nd];
  }
  tl->n++;
}

size_t c2d_grid_add_tag_line(c2d_grid *g, const char *name, bool along_i, size_t index) {
  if (g->ntags == g->tag_cap) {
    g->tag_cap = g->tag_cap ? 2 * g->tag_cap : 4;
    g->tags = ms_realloc(g->tags, g->tag_cap, sizeof(c2d_tagline));
  }
  c2d_tagline *tl = &g->tags[g->ntags];
  memset(tl, 0, sizeof *tl);
  tl->name = ms_strdup(name ? name : "line");
  size_t w = g->ni + 1;
  if (along_i) {
    if (index > g->nj) index = g->nj;
    tl->nnodes = g->ni + 1;
    tl->node = xcalloc(tl->nnodes, sizeof(size_t));
    for (size_t i = 0; i <= g->ni; ++i) tl->node[i] = i + w * index;
  } else {
    if (index > g->ni) index = g->ni;
    tl->nnodes = g->nj + 1;
    tl->node = xcalloc(tl->nnodes, sizeof(size_t));
    for (size_t j = 0; j <= g->nj; ++j) tl->node[j] = index + w * j;
  }
  c2d_tag_record(g, tl);
  return g->ntags++;
}

size_t c2d_grid_ntag_lines(const c2d_grid *g) { return g->ntags; }

c2d_line_history c2d_grid_line_history(const c2d_grid *g, size_t tag) {
  c2d_line_history h;
  memset(&h, 0, sizeof h);
  if (tag >= g->ntags) return h;
  const c2d_tagline *tl = &g->tags[tag];
  h.name = tl->name;
  h.nnodes = tl->nnodes;
  h.node = tl->node;
  h.n = tl->n;
  h.t = tl->t;
  h.x = tl->x;
  h.y = tl->y;
  h.u = tl->u;
  h.v = tl->v;
  return h;
}

const char *c2d_grid_error(const c2d_grid *g) { return g->err; }
double c2d_grid_time(const c2d_grid *g) { return g->t; }
long c2d_grid_steps(const c2d_grid *g) { return g->step; }
void c2d_grid_set_threads(c2d_grid *g, int nthreads) {
  g->nthreads = nthreads > 0 ? nthreads : 1;
  c2d_scratch_alloc(g); /* the sweeps' per-thread rows (no allocation inside a time step) */
}

c2d_view c2d_grid_view(const c2d_grid *g) {
  c2d_view v = {g->ni, g->nj,  g->nn, g->nz, g->x, g->y, g->u,   g->v,
                g->M,  g->rho, g->e,  g->p,  g->c, g->m, g->vol, g->material};
  return v;
}

c2d_balance c2d_grid_balance(const c2d_grid *g) {
  c2d_balance b = {0, 0, g->work};
  for (size_t z = 0; z < g->nz; ++z) b.internal += g->m[z] * g->e[z];
  for (size_t n = 0; n < g->nn; ++n)
    b.kinetic += 0.5 * g->M[n] * (g->u[n] * g->u[n] + g->v[n] * g->v[n]);
  return b;
}

void c2d_grid_hourglass(const c2d_grid *g, double *hg_rms, double *rho_spread) {
  double s = 0.0, ms = 0.0, spread = 0.0;
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4];
    gather(g, z, g->x, g->y, X, Y);
    double a = quad_area(X, Y);
    double hx = X[0] - X[1] + X[2] - X[3], hy = Y[0] - Y[1] + Y[2] - Y[3];
    s += g->m[z] * (hx * hx + hy * hy) / a;
    ms += g->m[z];
    double xc = 0.25 * (X[0] + X[1] + X[2] + X[3]), yc = 0.25 * (Y[0] + Y[1] + Y[2] + Y[3]);
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 4; ++k) {
      double CX[4], CY[4];
      corner_quad(X, Y, xc, yc, k, CX, CY);
      double rc = g->mc[4 * z + k] / poly_volume(g->geo, CX, CY);
      lo = rc < lo ? rc : lo;
      hi = rc > hi ? rc : hi;
    }
    double sp = (hi - lo) / g->rho[z];
    if (sp > spread) spread = sp;
  }
  *hg_rms = sqrt(s / ms);
  *rho_spread = spread;
}

double c2d_grid_min_area(const c2d_grid *g, size_t *zone) {
  double amin = INFINITY;
  for (size_t z = 0; z < g->nz; ++z) {
    double X[4], Y[4];
    gather(g, z, g->x, g->y, X, Y);
    double a = quad_area(X, Y);
    if (a < amin) {
      amin = a;
      if (zone) *zone = z;
    }
  }
  return amin;
}
