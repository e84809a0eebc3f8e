/* SPDX-License-Identifier: MIT */
/* grid2d_deck.c — the `grid2d` deck problem: read the section, build the 2D grid, run it with
 * HDF5 + XDMF snapshots (docs/continuum2d.md §8). */
#include "grid2d_deck_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct c2d_problem {
  c2d_grid *grid;
  double t_end;
  long nsnap;
};

static const double PI = 3.14159265358979323846;

/* A two-number range `key: [a, b]`. */
static bool read_range(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                       bool required, double def0, double def1, double out[2]) {
  out[0] = def0;
  out[1] = def1;
  if (!dk_get(map, key)) {
    if (required) dk_error(e, doc, map, "%s: required ([from, to])", key);
    return !required;
  }
  double *v = NULL;
  size_t n = 0;
  if (!dk_read_double_list(e, doc, map, key, dim, true, &v, &n)) return false;
  bool ok = n == 2;
  if (ok) {
    out[0] = v[0];
    out[1] = v[1];
  } else dk_error(e, doc, dk_get(map, key), "%s: expected [from, to]", key);
  free(v);
  return ok;
}

/* `key: number` (a constant) or `key: {value | table | file | pulse}` (a history, as in the 1D
 * deck: docs/input-continuum.md). */
static void read_history(dk_errors *e, dk_doc *doc, const dk_node *bc, const char *side,
                         const char *key, ms_dim dim, cont_fn *fn) {
  memset(fn, 0, sizeof *fn);
  const dk_node *h = dk_get(bc, key);
  if (h && dk_node_kind(h) == DK_MAP) {
    char what[64];
    snprintf(what, sizeof what, "%s.%s", side, key);
    cont_fn_read(e, doc, h, what, dim, fn);
    return;
  }
  fn->kind = CONT_FN_CONST;
  dk_read_double(e, doc, bc, key, dim, true, 0, -INFINITY, INFINITY, &fn->value);
}

static void read_bc(dk_errors *e, dk_doc *doc, const dk_node *bcs, const char *key, c2d_bc *bc) {
  memset(bc, 0, sizeof *bc);
  const dk_node *n = bcs ? dk_get(bcs, key) : NULL;
  if (!n) return; /* free */
  if (!dk_expect_map(e, doc, n, key)) return;
  static const char *const kinds[] = {"free", "wall", "piston", "fixed", "pressure", NULL};
  int k = 0;
  dk_read_enum(e, doc, n, "type", true, 0, kinds, &k);
  bc->kind = (c2d_bc_kind)k;
  double nv[2] = {0, 0};
  if (bc->kind == C2D_BC_WALL) read_range(e, doc, n, "normal", MS_DIM_NONE, false, 0, 0, nv);
  bc->normal[0] = nv[0];
  bc->normal[1] = nv[1];
  if (bc->kind == C2D_BC_PRESSURE)
    read_history(e, doc, n, key, "pressure", MS_DIM_PRESSURE, &bc->fn);
  if (bc->kind == C2D_BC_PISTON) {
    double dir[2] = {1, 0};
    read_history(e, doc, n, key, "velocity", MS_DIM_VELOCITY, &bc->fn);
    dk_read_bool(e, doc, n, "radial", false, false, &bc->radial);
    read_range(e, doc, n, "direction", MS_DIM_NONE, false, 1, 0, dir);
    double l = hypot(dir[0], dir[1]);
    if (!(l > 0)) {
      dk_error(e, doc, n, "%s: direction must be a non-zero vector", key);
      l = 1;
    }
    bc->dir[0] = dir[0] / l;
    bc->dir[1] = dir[1] / l;
  }
}

/* Node positions of mesh `type` (rect with its skew, polar, Saltzman). */
static void mesh_nodes(int type, long ni, long nj, const double xr[2], const double yr[2],
                       const double rr[2], const double th[2], double skew, double *x, double *y) {
  if (type == 0) {
    c2d_mesh_rect((size_t)ni, (size_t)nj, xr[0], xr[1], yr[0], yr[1], x, y);
    if (skew != 0.0)
      for (long j = 0; j <= nj; ++j)
        for (long i = 0; i <= ni; ++i)
          x[i + (ni + 1) * j] += skew * (double)(nj - j) * (yr[1] - yr[0]) / (double)nj *
                                 sin(PI * (double)i / (double)ni);
  } else if (type == 1) {
    c2d_mesh_polar((size_t)ni, (size_t)nj, rr[0], rr[1], th[0] * PI / 180, th[1] * PI / 180, x, y);
  } else {
    c2d_mesh_saltzman((size_t)ni, (size_t)nj, x, y);
  }
}

/* Regions: zones whose centre lies in the box `x`, `y` (and the ring `radius` about the
 * origin) get their own state and material, by default the section's (d; with blocks and no
 * section material or density, the region must give them). Later regions win; zreg[z] = the region of zone z (or -1). `energy_total` (a total
 * energy E spread with uniform e over the region's mass, e.g. a Sedov deposit) is kept in
 * etot[r] (NAN otherwise) and applied once the grid knows its zone masses. */
static void read_regions(dk_errors *e, dk_doc *doc, const dk_node *regs, const eos_materials *mats,
                         const c2d_deck_defaults *d, long ni, size_t nz, const double *x,
                         const double *y, double *rho, double *en, const eos_t **eos, int *mid,
                         int *zreg, double *etot) {
  for (size_t r = 0; r < dk_seq_len(regs); ++r) {
    const dk_node *rg = dk_seq_at(regs, r);
    etot[r] = NAN;
    if (!dk_expect_map(e, doc, rg, "region")) continue;
    double bx[2], by[2], br[2], rr0 = d->rho, er = NAN, pr = NAN;
    read_range(e, doc, rg, "x", MS_DIM_LENGTH, false, -INFINITY, INFINITY, bx);
    read_range(e, doc, rg, "y", MS_DIM_LENGTH, false, -INFINITY, INFINITY, by);
    read_range(e, doc, rg, "radius", MS_DIM_LENGTH, false, 0, INFINITY, br);
    dk_read_positive(e, doc, rg, "density", MS_DIM_DENSITY, isnan(d->rho), d->rho, &rr0);
    const char *rm = d->mat ? d->mat->name : NULL;
    dk_read_string(e, doc, rg, "material", !d->mat, rm, &rm);
    const eos_material *m2 = rm ? eos_materials_find(mats, rm, e, doc, rg) : NULL;
    const int nstate =
        !!dk_get(rg, "pressure") + !!dk_get(rg, "energy") + !!dk_get(rg, "energy_total");
    if (nstate > 1)
      dk_error(e, doc, rg, "region %zu: give at most one of pressure, energy, energy_total", r);
    if (dk_get(rg, "pressure"))
      dk_read_double(e, doc, rg, "pressure", MS_DIM_PRESSURE, true, 0, -INFINITY, INFINITY, &pr);
    if (dk_get(rg, "energy"))
      dk_read_double(e, doc, rg, "energy", MS_DIM_SPEC_ENERGY, true, 0, -INFINITY, INFINITY, &er);
    if (dk_get(rg, "energy_total"))
      dk_read_positive(e, doc, rg, "energy_total", MS_DIM_ENERGY, true, 1, &etot[r]);
    if (!m2 || isnan(rr0)) continue;
    if (!isnan(pr) && !cont_energy_from_pressure(m2->eos, rr0, pr, &er)) {
      dk_error(e, doc, rg, "region %zu: no energy gives pressure %g at density %g", r, pr, rr0);
      continue;
    }
    if (isnan(er)) er = d->e;
    for (size_t z = 0; z < nz; ++z) {
      size_t i = z % (size_t)ni, j = z / (size_t)ni, a = i + (size_t)(ni + 1) * j, w = ni + 1;
      double xc = 0.25 * (x[a] + x[a + 1] + x[a + w] + x[a + w + 1]);
      double yc = 0.25 * (y[a] + y[a + 1] + y[a + w] + y[a + w + 1]), rc = hypot(xc, yc);
      if (xc >= bx[0] && xc <= bx[1] && yc >= by[0] && yc <= by[1] && rc >= br[0] && rc <= br[1]) {
        rho[z] = rr0;
        en[z] = er;
        eos[z] = m2->eos;
        mid[z] = (int)(m2 - mats->m);
        zreg[z] = (int)r;
      }
    }
  }
}

/* energy_total of the regions: e = E / (the region's mass as the grid counts it: per radian in
 * r–z), so the grid's internal energy Σ m e holds E exactly; false (located error) for a region
 * with no zone. */
static bool apply_energy_totals(dk_errors *e, dk_doc *doc, const dk_node *regs, const c2d_grid *g,
                                const int *zreg, const double *etot, double *en) {
  c2d_view v = c2d_grid_view(g);
  bool ok = true;
  for (size_t r = 0; r < dk_seq_len(regs); ++r) {
    if (isnan(etot[r])) continue;
    double mass = 0;
    for (size_t z = 0; z < v.nzones; ++z)
      if (zreg[z] == (int)r) mass += v.mass[z];
    if (!(mass > 0)) {
      dk_error(e, doc, dk_seq_at(regs, r), "region %zu: energy_total: no zone centre lies in it",
               r);
      ok = false;
      continue;
    }
    for (size_t z = 0; z < v.nzones; ++z)
      if (zreg[z] == (int)r) en[z] = etot[r] / mass;
  }
  return ok;
}

/* Tag lines `tags: [{name, i | j}]` on the built grid. */
static void read_tags(dk_errors *e, dk_doc *doc, const dk_node *tags, long ni, long nj,
                      c2d_grid *g) {
  for (size_t k = 0; tags && k < dk_seq_len(tags); ++k) {
    const dk_node *tg = dk_seq_at(tags, k);
    if (!dk_expect_map(e, doc, tg, "tag")) continue;
    const char *tn = NULL;
    long ii = -1, jj = -1;
    dk_read_string(e, doc, tg, "name", true, NULL, &tn);
    if (dk_get(tg, "i")) dk_read_int(e, doc, tg, "i", true, 0, 0, ni, &ii);
    if (dk_get(tg, "j")) dk_read_int(e, doc, tg, "j", true, 0, 0, nj, &jj);
    if ((ii < 0) == (jj < 0)) {
      dk_error(e, doc, tg, "tag: give exactly one of i (a line i = const) or j");
      continue;
    }
    if (tn) c2d_grid_add_tag_line(g, tn, jj >= 0, (size_t)(jj >= 0 ? jj : ii));
  }
}

/* Viscosity, hourglass, r–z form, time, output and thread keys of the section. */
static void read_controls(dk_errors *e, dk_doc *doc, const dk_node *sec, c2d_setup *s,
                          double *t_end, long *nsnap, long *nthreads) {
  const dk_node *visc = dk_get(sec, "viscosity");
  if (visc && dk_expect_map(e, doc, visc, "viscosity")) {
    dk_read_double(e, doc, visc, "q1", MS_DIM_NONE, false, s->q1, 0, INFINITY, &s->q1);
    dk_read_double(e, doc, visc, "q2", MS_DIM_NONE, false, s->q2, 0, INFINITY, &s->q2);
    dk_read_double(e, doc, visc, "gamma", MS_DIM_NONE, false, s->q_gamma, 1, INFINITY, &s->q_gamma);
    dk_read_bool(e, doc, visc, "limiter", false, true, &s->use_limiter);
  }
  dk_read_double(e, doc, sec, "hourglass", MS_DIM_NONE, false, 0, 0, INFINITY, &s->hg_coef);
  dk_read_bool(e, doc, sec, "rz_area_weighted", false, false, &s->rz_area_weighted);
  const dk_node *tm = dk_get(sec, "time");
  if (!tm) dk_error(e, doc, sec, "grid2d: `time: {end: ...}` is required");
  if (tm && dk_expect_map(e, doc, tm, "time")) {
    dk_read_positive(e, doc, tm, "end", MS_DIM_TIME, true, 0, t_end);
    dk_read_double(e, doc, tm, "cfl", MS_DIM_NONE, false, s->cfl, 1e-6, 0.999, &s->cfl);
  }
  const dk_node *out = dk_get(sec, "output");
  if (out && dk_expect_map(e, doc, out, "output"))
    dk_read_int(e, doc, out, "snapshots", false, 10, 0, 100000, nsnap);
  dk_read_int(e, doc, sec, "threads", false, 1, 1, 1024, nthreads);
}

/* The section's state, the defaults of the mesh blocks: material, density, energy (or pressure),
 * velocity and radial velocity. With blocks, material and density may come from every block. */
static bool read_defaults(dk_errors *e, dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                          bool blocks, c2d_deck_defaults *d) {
  memset(d, 0, sizeof *d);
  d->rho = NAN;
  const char *mname = NULL;
  if (!blocks || dk_get(sec, "material"))
    dk_read_string(e, doc, sec, "material", true, NULL, &mname);
  d->mat = mname ? eos_materials_find(mats, mname, e, doc, dk_get(sec, "material")) : NULL;
  if (!blocks || dk_get(sec, "density"))
    dk_read_positive(e, doc, sec, "density", MS_DIM_DENSITY, true, 1, &d->rho);
  double p0 = NAN;
  d->e = d->mat ? eos_e0(d->mat->eos) : 0;
  if (dk_get(sec, "pressure"))
    dk_read_double(e, doc, sec, "pressure", MS_DIM_PRESSURE, true, 0, -INFINITY, INFINITY, &p0);
  else
    dk_read_double(e, doc, sec, "energy", MS_DIM_SPEC_ENERGY, false, d->e, -INFINITY, INFINITY,
                   &d->e);
  read_range(e, doc, sec, "velocity", MS_DIM_VELOCITY, false, 0, 0, d->vel);
  dk_read_double(e, doc, sec, "radial_velocity", MS_DIM_VELOCITY, false, 0, -INFINITY, INFINITY,
                 &d->vrad);
  if (!isnan(p0) && d->mat && !isnan(d->rho) &&
      !cont_energy_from_pressure(d->mat->eos, d->rho, p0, &d->e)) {
    dk_error(e, doc, dk_get(sec, "pressure"), "pressure %g: no energy gives it at density %g", p0,
             d->rho);
    return false;
  }
  if (!isnan(p0) && (!d->mat || isnan(d->rho))) {
    dk_error(e, doc, dk_get(sec, "pressure"),
             "pressure: needs the section's material and density (give it in the blocks)");
    return false;
  }
  return d->mat || blocks;
}

/* The one mesh `mesh: {type: rect | polar | saltzman, ni, nj, ...}` filled with the section's
 * state. */
static bool read_single_mesh(dk_errors *e, dk_doc *doc, const dk_node *mesh,
                             const eos_materials *mats, const c2d_deck_defaults *d,
                             c2d_deck_mesh *m) {
  static const char *const types[] = {"rect", "polar", "saltzman", NULL};
  int type = 0;
  long ni = 0, nj = 0;
  bool ok = dk_read_enum(e, doc, mesh, "type", false, 0, types, &type);
  ok = dk_read_int(e, doc, mesh, "ni", true, 0, 1, 100000000, &ni) && ok;
  ok = dk_read_int(e, doc, mesh, "nj", true, 0, 1, 100000000, &nj) && ok;
  double xr[2] = {0, 0}, yr[2] = {0, 0}, rr[2] = {0, 0}, th[2] = {0, 0}, skew = 0;
  if (type == 0) {
    ok = read_range(e, doc, mesh, "x", MS_DIM_LENGTH, true, 0, 1, xr) && ok;
    ok = read_range(e, doc, mesh, "y", MS_DIM_LENGTH, true, 0, 1, yr) && ok;
    ok = dk_read_double(e, doc, mesh, "skew", MS_DIM_NONE, false, 0, -INFINITY, INFINITY, &skew) &&
         ok;
  } else if (type == 1) {
    ok = read_range(e, doc, mesh, "r", MS_DIM_LENGTH, true, 0, 1, rr) && ok;
    ok = read_range(e, doc, mesh, "theta", MS_DIM_NONE, true, 0, 90, th) && ok; /* degrees */
  }
  if (!ok || !d->mat) return false;
  c2d_deck_mesh_alloc(m, ni, nj);
  mesh_nodes(type, ni, nj, xr, yr, rr, th, skew, m->x, m->y);
  const size_t nn = (size_t)(ni + 1) * (size_t)(nj + 1), nz = (size_t)ni * (size_t)nj;
  for (size_t n = 0; n < nn; ++n) {
    double r = hypot(m->x[n], m->y[n]);
    m->u[n] = d->vel[0] + (r > 0 ? d->vrad * m->x[n] / r : 0);
    m->v[n] = d->vel[1] + (r > 0 ? d->vrad * m->y[n] / r : 0);
  }
  for (size_t z = 0; z < nz; ++z) {
    m->rho[z] = d->rho;
    m->en[z] = d->e;
    m->eos[z] = d->mat->eos;
    m->mid[z] = (int)(d->mat - mats->m);
  }
  return true;
}

/* Builds the grid of the mesh m (located errors at `at`: the mesh entry), the regions' energy
 * deposits applied; NULL on error. */
static c2d_grid *build_grid(dk_errors *e, dk_doc *doc, const dk_node *at, const dk_node *regs,
                            c2d_setup *s, c2d_deck_mesh *m, const int *zreg, const double *etot,
                            bool has_etot) {
  s->ni = (size_t)m->ni;
  s->nj = (size_t)m->nj;
  s->x = m->x;
  s->y = m->y;
  s->u = m->u;
  s->v = m->v;
  s->rho = m->rho;
  s->e = m->en;
  s->eos = m->eos;
  s->material = m->mid;
  char msg[512];
  c2d_grid *g = NULL;
  c2d_grid_create(s, &g, msg, sizeof msg);
  if (!g) dk_error(e, doc, at, "%s", msg); /* tangled/inverted zone, r < 0: at the mesh */
  if (g && has_etot) { /* the zone masses are the grid's: build it again with the deposit */
    const bool dep = apply_energy_totals(e, doc, regs, g, zreg, etot, m->en);
    c2d_grid_destroy(&g);
    if (dep && c2d_grid_create(s, &g, msg, sizeof msg) != MS_OK)
      dk_error(e, doc, regs, "regions: energy_total: %s", msg);
  }
  return g;
}

c2d_problem *c2d_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                              dk_errors *e) {
  size_t nerr0 = e->n;
  if (!sec || !dk_expect_map(e, doc, sec, "grid2d")) return NULL;
  c2d_setup s;
  c2d_setup_defaults(&s);
  static const char *const geos[] = {"xy", "rz", NULL};
  int geo = 0;
  dk_read_enum(e, doc, sec, "geometry", false, 0, geos, &geo);
  s.geometry = (c2d_geometry)geo;
  const dk_node *mesh = dk_get(sec, "mesh");
  if (!mesh) {
    dk_error(e, doc, sec, "grid2d: `mesh` is required");
    return NULL;
  }
  if (!dk_expect_map(e, doc, mesh, "mesh")) return NULL;
  const dk_node *blocks = dk_get(mesh, "blocks");
  if (blocks)
    for (size_t k = 0; k < dk_map_len(mesh); ++k)
      if (strcmp(dk_map_key(mesh, k), "blocks") != 0)
        dk_error(e, doc, dk_map_value(mesh, k),
                 "mesh: %s: not with `blocks` (each block has its own ranges and type)",
                 dk_map_key(mesh, k));
  c2d_deck_defaults d;
  bool ok = read_defaults(e, doc, sec, mats, blocks != NULL, &d);
  const dk_node *bcs = dk_get(sec, "boundaries");
  if (bcs) dk_expect_map(e, doc, bcs, "boundaries");
  const char *const sides[4] = {"ilo", "ihi", "jlo", "jhi"};
  for (int k = 0; k < 4; ++k) read_bc(e, doc, bcs, sides[k], &s.bc[k]);
  double t_end = 0;
  long nsnap = 10, nthreads = 1;
  read_controls(e, doc, sec, &s, &t_end, &nsnap, &nthreads);
  const dk_node *tags = dk_get(sec, "tags");
  if (tags) dk_expect_seq(e, doc, tags, "tags");
  c2d_deck_mesh m = {0};
  ok = (blocks ? c2d_blocks_build(e, doc, blocks, mats, s.geometry, &d, &m)
               : read_single_mesh(e, doc, mesh, mats, &d, &m)) &&
       ok;
  const dk_node *regs = dk_get(sec, "regions");
  c2d_problem *p = NULL;
  if (ok && e->n == nerr0) {
    /* Regions: rectangles (zone centres) with their own state and material. */
    const size_t nz = (size_t)m.ni * (size_t)m.nj;
    int *zreg = malloc(nz * sizeof *zreg);
    for (size_t z = 0; z < nz; ++z) zreg[z] = -1;
    double *etot = calloc(regs ? dk_seq_len(regs) + 1 : 1, sizeof *etot);
    bool has_etot = false;
    if (regs && dk_expect_seq(e, doc, regs, "regions")) {
      read_regions(e, doc, regs, mats, &d, m.ni, nz, m.x, m.y, m.rho, m.en, m.eos, m.mid, zreg,
                   etot);
      for (size_t r = 0; r < dk_seq_len(regs); ++r) has_etot |= !isnan(etot[r]);
    }
    c2d_grid *g =
        e->n == nerr0 ? build_grid(e, doc, mesh, regs, &s, &m, zreg, etot, has_etot) : NULL;
    if (g) {
      read_tags(e, doc, tags, m.ni, m.nj, g);
      c2d_grid_set_threads(g, (int)nthreads);
      p = calloc(1, sizeof *p);
      p->grid = g;
      p->t_end = t_end;
      p->nsnap = nsnap;
    }
    free(zreg);
    free(etot);
  }
  /* not read because of the errors above: not "unknown keys" either */
  dk_mark_used(sec, "regions");
  dk_mark_used(sec, "tags");
  for (int k = 0; k < 4; ++k) cont_fn_free(&s.bc[k].fn);
  c2d_deck_mesh_free(&m);
  return p;
}

static void c2d_problem_free(c2d_problem *p) {
  if (!p) return;
  c2d_grid_destroy(&p->grid);
  free(p);
}

void c2d_problem_destroy(c2d_problem **p) {
  if (!p) return;
  c2d_problem_free(*p);
  *p = NULL;
}

c2d_grid *c2d_problem_grid(c2d_problem *p) { return p ? p->grid : NULL; }

/* One snapshot grid2d_NNNN.h5: node coordinates (nn × 2) and velocities, zone fields. */
static ms_status write_snapshot(const ms_ctx *ctx, const c2d_grid *g, long k) {
  c2d_view v = c2d_grid_view(g);
  char name[64];
  snprintf(name, sizeof name, "grid2d_%04ld.h5", k);
  char *path = ms_out_path(ctx, name);
  ms_h5 *h = ms_h5_create(path);
  free(path);
  if (!h) return MS_ERR_IO;
  double *buf = malloc(3 * v.nnodes * sizeof(double));
  for (size_t n = 0; n < v.nnodes; ++n) {
    buf[2 * n] = v.x[n];
    buf[2 * n + 1] = v.y[n];
  }
  ms_status s = ms_h5_write_doubles(h, "coords", v.nnodes, 2, buf, "cm");
  /* node velocity components as (nj+1) × (ni+1) scalars (the structured-mesh node layout) */
  if (!s) s = ms_h5_write_doubles(h, "u", v.nj + 1, v.ni + 1, v.u, "km/s");
  if (!s) s = ms_h5_write_doubles(h, "v", v.nj + 1, v.ni + 1, v.v, "km/s");
  free(buf);
  if (!s) s = ms_h5_write_doubles(h, "density", v.nj, v.ni, v.rho, "g/cm3");
  if (!s) s = ms_h5_write_doubles(h, "pressure", v.nj, v.ni, v.p, "GPa");
  if (!s) s = ms_h5_write_doubles(h, "energy", v.nj, v.ni, v.e, "kJ/g");
  if (!s) s = ms_h5_attr_double(h, "/", "time", ms_out_time(c2d_grid_time(g)));
  if (s) {
    ms_h5_abort(h);
    return s;
  }
  return ms_h5_close(h);
}

/* grid2d.xmf: a temporal collection of 2DSMesh grids (nodes i fastest, as the grid), one per
 * snapshot; rewritten after every snapshot so a stopped run can still be opened. */
static ms_status write_xmf(const ms_ctx *ctx, const c2d_grid *g, long nk, const double *times) {
  c2d_view v = c2d_grid_view(g);
  char *path = ms_out_path(ctx, "grid2d.xmf");
  ms_afile af;
  ms_status s = ms_afile_open(&af, path);
  free(path);
  if (s) return s;
  FILE *f = af.f;
  fprintf(f, "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
             "  <Grid Name=\"grid2d\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
  static const char *const fields[3] = {"density", "pressure", "energy"};
  for (long k = 0; k < nk; ++k) {
    char h5[64];
    snprintf(h5, sizeof h5, "grid2d_%04ld.h5", k);
    fprintf(f, "   <Grid Name=\"t%ld\" GridType=\"Uniform\">\n    <Time Value=\"%.17g\"/>\n", k,
            times[k]);
    fprintf(f, "    <Topology TopologyType=\"2DSMesh\" Dimensions=\"%zu %zu\"/>\n", v.nj + 1,
            v.ni + 1);
    fprintf(f,
            "    <Geometry GeometryType=\"XY\">\n     <DataItem Dimensions=\"%zu 2\" "
            "NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/coords</DataItem>\n"
            "    </Geometry>\n",
            v.nnodes, h5);
    for (int q = 0; q < 2; ++q)
      fprintf(f,
              "    <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Node\">\n"
              "     <DataItem Dimensions=\"%zu %zu\" NumberType=\"Float\" Precision=\"8\" "
              "Format=\"HDF\">%s:/%s</DataItem>\n    </Attribute>\n",
              q ? "v" : "u", v.nj + 1, v.ni + 1, h5, q ? "v" : "u");
    for (int q = 0; q < 3; ++q)
      fprintf(f,
              "    <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
              "     <DataItem Dimensions=\"%zu %zu\" NumberType=\"Float\" Precision=\"8\" "
              "Format=\"HDF\">%s:/%s</DataItem>\n    </Attribute>\n",
              fields[q], v.nj, v.ni, h5, fields[q]);
    fprintf(f, "   </Grid>\n");
  }
  fprintf(f, "  </Grid>\n </Domain>\n</Xdmf>\n");
  return ms_afile_commit(&af);
}

/* grid2d_energy.csv: the energy budget at t = 0 and at every snapshot time. */
static ms_status write_energy_csv(const ms_ctx *ctx, const double *rows, long n) {
  char *path = ms_out_path(ctx, "grid2d_energy.csv");
  ms_afile af;
  ms_status s = ms_afile_open(&af, path);
  free(path);
  if (s) return s;
  const char *const names[] = {"t", "step", "internal", "kinetic", "boundary_work", "balance"};
  const char *const units[] = {ms_unit_label(MS_DIM_TIME),   "1",
                               ms_unit_label(MS_DIM_ENERGY), ms_unit_label(MS_DIM_ENERGY),
                               ms_unit_label(MS_DIM_ENERGY), "1"};
  ms_csv_header(af.f,
                "2D grid energy budget (per radian in r-z, per unit depth in x-y); balance = "
                "(internal + kinetic - boundary_work - E0) / E0",
                6, names, units);
  for (long k = 0; k < n; ++k) ms_csv_row(af.f, 6, &rows[6 * k]);
  return ms_afile_commit(&af);
}

static void energy_row(const c2d_grid *g, double e0, double *row) {
  c2d_balance b = c2d_grid_balance(g);
  row[0] = c2d_grid_time(g), row[1] = (double)c2d_grid_steps(g);
  row[2] = b.internal, row[3] = b.kinetic, row[4] = b.work;
  row[5] = (b.internal + b.kinetic - b.work - e0) / fmax(fabs(e0), b.internal + b.kinetic);
}

ms_status c2d_problem_run(ms_ctx *ctx, c2d_problem *p) {
  if (ctx->rank != 0) return par_agree_status(MS_OK); /* the grid runs on rank 0 */
  c2d_grid *g = p->grid;
  c2d_view v = c2d_grid_view(g);
  c2d_balance b0 = c2d_grid_balance(g);
  double e0 = b0.internal + b0.kinetic;
  ms_log(ctx, MS_LOG_INFO, "grid2d: %zu x %zu zones, t_end = %g %s", v.ni, v.nj,
         ms_out_time(p->t_end), ms_out_time_label());
  bool out = ctx->outdir && ctx->outdir[0];
  long nk = 0, nmax = p->nsnap + 2;
  double *times = calloc((size_t)nmax, sizeof(double));
  double *erows = calloc(6 * (size_t)nmax, sizeof(double));
  long ne = 0;
  energy_row(g, e0, &erows[6 * ne++]);
  ms_status s = MS_OK;
  if (out) {
    s = write_snapshot(ctx, g, nk);
    times[nk++] = 0.0;
    if (!s) s = write_xmf(ctx, g, nk, times);
  }
  ms_progress pr;
  ms_progress_start(&pr, ctx, "grid2d", 0.0, p->t_end);
  for (long k = 1; k <= (p->nsnap > 0 ? p->nsnap : 1) && !s; ++k) {
    double tk = p->t_end * (double)k / (double)(p->nsnap > 0 ? p->nsnap : 1);
    ms_status st = c2d_grid_run_to(g, tk);
    ms_progress_update(&pr, c2d_grid_time(g), c2d_grid_steps(g));
    if (out && (p->nsnap > 0 || st != MS_OK) && nk < nmax) {
      ms_status sw = write_snapshot(ctx, g, nk);
      times[nk++] = ms_out_time(c2d_grid_time(g)); /* the sidecars' times, us */
      if (!sw) sw = write_xmf(ctx, g, nk, times);
      if (sw && !st) st = sw;
    }
    double *row = &erows[6 * (ne < nmax ? ne++ : ne - 1)];
    energy_row(g, e0, row);
    ms_log(ctx, MS_LOG_INFO,
           "grid2d: t = %.6g %s, step %ld: internal %.9g, kinetic %.9g, boundary work %.9g %s, "
           "energy error %.3e (relative)",
           ms_out_time(row[0]), ms_out_time_label(), c2d_grid_steps(g), row[2], row[3], row[4],
           ms_unit_label(MS_DIM_ENERGY), fabs(row[5]));
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "grid2d: %s (last snapshot written at t = %.9g %s)",
             c2d_grid_error(g), ms_out_time(c2d_grid_time(g)), ms_out_time_label());
      s = st;
    }
  }
  ms_progress_finish(&pr, c2d_grid_time(g), c2d_grid_steps(g));
  for (size_t k = 0; out && k < c2d_grid_ntag_lines(g); ++k) {
    c2d_line_history h = c2d_grid_line_history(g, k);
    char name[256];
    snprintf(name, sizeof name, "tag_%s.h5", h.name);
    char *path = ms_out_path(ctx, name);
    ms_h5 *f = ms_h5_create(path);
    free(path);
    ms_status sw = f ? MS_OK : MS_ERR_IO;
    if (!sw) sw = ms_h5_write_times(f, "t", h.n, h.t);
    if (!sw) sw = ms_h5_write_doubles(f, "x", h.n, h.nnodes, h.x, "cm");
    if (!sw) sw = ms_h5_write_doubles(f, "y", h.n, h.nnodes, h.y, "cm");
    if (!sw) sw = ms_h5_write_doubles(f, "u", h.n, h.nnodes, h.u, "km/s");
    if (!sw) sw = ms_h5_write_doubles(f, "v", h.n, h.nnodes, h.v, "km/s");
    if (f) sw = sw ? (ms_h5_abort(f), sw) : ms_h5_close(f);
    if (sw && !s) s = sw;
  }
  if (out) {
    const ms_status sw = write_energy_csv(ctx, erows, ne);
    if (sw && !s) s = sw;
  }
  free(times);
  free(erows);
  return par_agree_status(s);
}
