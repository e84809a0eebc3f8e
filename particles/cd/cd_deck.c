/* SPDX-License-Identifier: MIT */
/* cd_deck.c — the `cluster_dynamics` section of a deck (docs/input-cd.md): read and check it
 * into a cd_problem, one sub-reader per part (box, regions, interfaces, piston, thermal, output,
 * relax, mpi), and the geometry of its regions.
 *
 * Every problem in the section is recorded as a deck error (FILE:LINE:COL), never the first
 * only: overlapping regions of different materials, fewer than 2 lattice periods across a
 * periodic dimension, R_c not above the nearest-neighbour distance, a piston history whose
 * time does not increase.
 */
#include "cd_problem_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const shape_names[] = {"box", "sphere", "cylinder", "halfspace", NULL};
static const char *const surface_names[] = {"flat", "sine", "random", NULL};
static const char *const bc_names[] = {"free", "periodic", "wall", NULL};
const char *const cd_mode_names[] = {"plain", "bonded", "shifted", NULL};
const char *const cd_partition_names[] = {"slab", "metis", "auto", NULL};

static int material_index(cd_problem *p, const eos_materials *mats, dk_doc *doc, const dk_node *at,
                          const char *name, dk_errors *e) {
  for (int k = 0; k < p->nmat; k++)
    if (strcmp(p->mat[k]->name, name) == 0) return k;
  const eos_material *m = eos_materials_find(mats, name, e, doc, at);
  if (!m) return -1;
  if (p->nmat == CD_MAX_MATERIALS) {
    dk_error(e, doc, at, "at most %d materials in one cluster-dynamics run", CD_MAX_MATERIALS);
    return -1;
  }
  if (!eos_has_cold_curve(m->eos)) {
    dk_error(e, doc, at,
             "material '%s' has no cold curve (its EOS is %s): cluster dynamics "
             "needs P_x(delta) and eps_x(delta)",
             name, eos_kind_name(eos_get_kind(m->eos)));
    return -1;
  }
  p->mat[p->nmat] = m;
  return p->nmat++;
}

static bool read_vec(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, int dim,
                     ms_dim unit, bool required, const double *def, double out[3]) {
  double *v = NULL;
  size_t n = 0;
  const dk_node *node = dk_get(map, key);
  if (!node) {
    if (required) {
      dk_error(e, doc, map, "missing '%s' (a list of %d numbers)", key, dim);
      return false;
    }
    for (int a = 0; a < 3; a++) out[a] = def ? def[a] : 0.0;
    return true;
  }
  if (!dk_read_double_list(e, doc, map, key, unit, true, &v, &n)) return false;
  bool ok = (int)n == dim;
  if (!ok)
    dk_error(e, doc, node, "'%s' needs %d components (dimension %d), got %zu", key, dim, dim, n);
  for (int a = 0; a < 3; a++) out[a] = ok && a < dim ? v[a] : (def ? def[a] : 0.0);
  free(v);
  return ok;
}

static void read_region(cd_problem *p, const eos_materials *mats, dk_doc *doc, const dk_node *rn,
                        dk_errors *e) {
  if (!dk_expect_map(e, doc, rn, "region")) return;
  if (p->nreg == CD_MAX_REGIONS) {
    dk_error(e, doc, rn, "at most %d regions", CD_MAX_REGIONS);
    return;
  }
  cd_deck_region *r = &p->reg[p->nreg];
  memset(r, 0, sizeof *r);
  r->node = rn;
  const char *mname = NULL;
  if (dk_read_string(e, doc, rn, "material", true, NULL, &mname))
    r->mat = material_index(p, mats, doc, dk_get(rn, "material"), mname, e);
  else r->mat = -1;
  int shape = 0;
  dk_read_enum(e, doc, rn, "shape", false, SHAPE_BOX, shape_names, &shape);
  r->shape = (region_shape)shape;
  const int d = p->dim;
  switch (r->shape) {
  case SHAPE_BOX:
    read_vec(e, doc, rn, "lo", d, MS_DIM_LENGTH, true, NULL, r->lo);
    read_vec(e, doc, rn, "hi", d, MS_DIM_LENGTH, true, NULL, r->hi);
    for (int a = 0; a < d; a++)
      if (!(r->hi[a] > r->lo[a]))
        dk_error(e, doc, rn, "box region: hi must exceed lo on every axis");
    break;
  case SHAPE_SPHERE:
    read_vec(e, doc, rn, "center", d, MS_DIM_LENGTH, true, NULL, r->center);
    dk_read_positive(e, doc, rn, "radius", MS_DIM_LENGTH, true, 0, &r->radius);
    break;
  case SHAPE_CYLINDER: {
    long ax = 2;
    read_vec(e, doc, rn, "center", d, MS_DIM_LENGTH, true, NULL, r->center);
    dk_read_positive(e, doc, rn, "radius", MS_DIM_LENGTH, true, 0, &r->radius);
    dk_read_int(e, doc, rn, "axis", false, d == 2 ? 2 : 2, 0, 2, &ax);
    r->axis = (int)ax;
    read_vec(e, doc, rn, "lo", d, MS_DIM_LENGTH, false,
             (double[3]){-INFINITY, -INFINITY, -INFINITY}, r->lo);
    read_vec(e, doc, rn, "hi", d, MS_DIM_LENGTH, false, (double[3]){INFINITY, INFINITY, INFINITY},
             r->hi);
    break;
  }
  case SHAPE_HALFSPACE: {
    long ax = 0;
    dk_read_int(e, doc, rn, "axis", false, 0, 0, d - 1, &ax);
    r->axis = (int)ax;
    dk_read_double(e, doc, rn, "below", MS_DIM_LENGTH, true, 0, -INFINITY, INFINITY, &r->plane);
    break;
  }
  }
  read_vec(e, doc, rn, "velocity", d, MS_DIM_VELOCITY, false, NULL, r->velocity);
  dk_read_bool(e, doc, rn, "piston", false, false, &r->piston);
  dk_read_bool(e, doc, rn, "matrix", false, false, &r->matrix);
  const dk_node *sn = dk_get(rn, "surface");
  if (sn && dk_expect_map(e, doc, sn, "surface")) {
    int sk = 0;
    long ax = d - 1, along = 0, seed = 1;
    dk_read_enum(e, doc, sn, "profile", true, SURF_FLAT, surface_names, &sk);
    dk_read_int(e, doc, sn, "axis", false, d - 1, 0, d - 1, &ax);
    dk_read_int(e, doc, sn, "along", false, 0, 0, d - 1, &along);
    dk_read_double(e, doc, sn, "amplitude", MS_DIM_LENGTH, true, 0, 0, INFINITY, &r->amplitude);
    dk_read_positive(e, doc, sn, "wavelength", MS_DIM_LENGTH, true, 0, &r->wavelength);
    dk_read_int(e, doc, sn, "seed", false, 1, 0, 1L << 40, &seed);
    if (r->shape != SHAPE_BOX) dk_error(e, doc, sn, "a surface profile applies to box regions");
    if (ax == along) dk_error(e, doc, sn, "surface: 'along' must differ from 'axis'");
    r->surface = (surface_kind)sk;
    r->surface_axis = (int)ax;
    r->surface_along = (int)along;
    r->seed = (uint64_t)seed;
  }
  const dk_node *gn = dk_get(rn, "polycrystal");
  if (gn && dk_expect_map(e, doc, gn, "polycrystal")) {
    long ng = 10, seed = 1;
    dk_read_int(e, doc, gn, "grains", true, 10, 1, 100000, &ng);
    dk_read_int(e, doc, gn, "seed", false, 1, 0, 1L << 40, &seed);
    dk_read_bool(e, doc, gn, "rotate", false, true, &r->rotate);
    dk_read_double(e, doc, gn, "min_distance", MS_DIM_NONE, false, 0.8, 0.1, 1.0, &r->dmin);
    r->ngrains = (int)ng;
    r->grain_seed = (uint64_t)seed;
    if (r->shape == SHAPE_HALFSPACE)
      dk_error(e, doc, gn, "a polycrystal fills a box, sphere or cylinder region");
    const dk_node *ml = dk_get(gn, "materials");
    if (ml && dk_expect_seq(e, doc, ml, "polycrystal materials")) {
      double *fr = NULL;
      size_t nf = 0;
      dk_read_double_list(e, doc, gn, "fractions", MS_DIM_NONE, true, &fr, &nf);
      if (nf != dk_seq_len(ml) || nf > CD_MAX_MATERIALS)
        dk_error(e, doc, gn, "polycrystal: 'fractions' needs one number per material");
      double sum = 0;
      for (size_t k = 0; k < nf && k < dk_seq_len(ml) && k < CD_MAX_MATERIALS; k++) {
        const char *nm = dk_scalar(dk_seq_at(ml, k));
        r->gmat[k] = nm ? material_index(p, mats, doc, dk_seq_at(ml, k), nm, e) : -1;
        r->gfrac[k] = fr[k];
        sum += fr[k];
        r->ngmat = (int)k + 1;
      }
      if (nf && fabs(sum - 1.0) > 1e-6)
        dk_error(e, doc, gn, "polycrystal: fractions must sum to 1 (%g)", sum);
      free(fr);
    }
  }
  p->nreg++;
}

/* Height of a box region's profiled hi face at coordinate s along the surface. Random: a sum of
 * 8 sine modes with wavelengths λ/1..λ/8, amplitudes ∝ 1/k and random phases, scaled to the
 * given peak amplitude (a smooth random roughness). */
static double surface_height(const cd_deck_region *r, double s) {
  const double two_pi = 6.283185307179586;
  if (r->surface == SURF_SINE) return r->amplitude * sin(two_pi * s / r->wavelength);
  if (r->surface == SURF_RANDOM) {
    double h = 0, norm = 0;
    for (int k = 1; k <= 8; k++) {
      double ph = two_pi * ptl_splitmix64_uniform(r->seed, (uint64_t)k);
      h += sin(two_pi * k * s / r->wavelength + ph) / k;
      norm += 1.0 / k;
    }
    return r->amplitude * h / norm;
  }
  return 0.0;
}

bool cd_deck_region_contains(const cd_deck_region *r, const double x[3], int dim) {
  switch (r->shape) {
  case SHAPE_BOX:
    for (int a = 0; a < dim; a++) {
      double hi = r->hi[a];
      if (r->surface != SURF_FLAT && a == r->surface_axis)
        hi += surface_height(r, x[r->surface_along]);
      if (x[a] < r->lo[a] || x[a] >= hi) return false;
    }
    return true;
  case SHAPE_SPHERE: {
    double d2 = 0;
    for (int a = 0; a < dim; a++) d2 += (x[a] - r->center[a]) * (x[a] - r->center[a]);
    return d2 < r->radius * r->radius;
  }
  case SHAPE_CYLINDER: {
    double d2 = 0;
    for (int a = 0; a < dim; a++) {
      if (a == r->axis) {
        if (x[a] < r->lo[a] || x[a] >= r->hi[a]) return false;
        continue;
      }
      d2 += (x[a] - r->center[a]) * (x[a] - r->center[a]);
    }
    return d2 < r->radius * r->radius;
  }
  case SHAPE_HALFSPACE:
    return x[r->axis] < r->plane;
  }
  return false;
}

/* The region's bounding box, clipped to the problem's box if `clip` (a polycrystal's grain
 * seeds lie in the clipped one); a cylinder without lo/hi along its axis spans the box there. */
void cd_deck_region_bounds(const cd_problem *p, const cd_deck_region *r, bool clip, double lo[3],
                           double hi[3]) {
  for (int a = 0; a < 3; a++) {
    double l = p->box.lo[a], h = p->box.hi[a];
    switch (r->shape) {
    case SHAPE_BOX:
      l = r->lo[a], h = r->hi[a];
      break;
    case SHAPE_SPHERE:
      l = r->center[a] - r->radius, h = r->center[a] + r->radius;
      break;
    case SHAPE_CYLINDER:
      if (a == r->axis) l = r->lo[a], h = r->hi[a];
      else l = r->center[a] - r->radius, h = r->center[a] + r->radius;
      break;
    case SHAPE_HALFSPACE:
      if (a == r->axis) h = r->plane;
      break;
    }
    lo[a] = a >= p->dim ? 0.0 : clip ? fmax(l, p->box.lo[a]) : l;
    hi[a] = a >= p->dim ? 0.0 : clip ? fmin(h, p->box.hi[a]) : h;
  }
}

/* lattice period along each axis: fcc cubic constant a = √2 r0; triangular r0 × √3 r0 */
void cd_deck_lattice_period(const cd_problem *p, double per[3]) {
  if (p->lattice == CD_LATTICE_FCC) {
    per[0] = per[1] = per[2] = sqrt(2.0) * p->r0;
  } else {
    per[0] = p->r0;
    per[1] = sqrt(3.0) * p->r0;
    per[2] = 1.0;
  }
}

/* Length, area or volume (dim 1..3 axes) of region r inside the box: an upper bound of the space
 * its lattice sites fill (a surface profile counts at its peaks, overlaps count twice). */
static double region_measure(const cd_problem *p, const cd_deck_region *r) {
  double box = 1.0, inside = 1.0;
  for (int a = 0; a < p->dim; a++) box *= p->box.hi[a] - p->box.lo[a];
  switch (r->shape) {
  case SHAPE_BOX:
  case SHAPE_CYLINDER: /* the cylinder's extent along its axis; its disc below */
    for (int a = 0; a < p->dim; a++) {
      if (r->shape == SHAPE_CYLINDER && a != r->axis) continue;
      double hi = r->hi[a] + (r->surface != SURF_FLAT && a == r->surface_axis ? r->amplitude : 0);
      inside *= fmax(0.0, fmin(hi, p->box.hi[a]) - fmax(r->lo[a], p->box.lo[a]));
    }
    if (r->shape == SHAPE_CYLINDER) /* 2D: a disc (axis 2) or a strip 2r wide */
      inside = p->dim == 2 && r->axis == 2
                   ? M_PI * r->radius * r->radius
                   : inside * (p->dim == 3 ? M_PI * r->radius * r->radius : 2.0 * r->radius);
    break;
  case SHAPE_SPHERE:
    inside = p->dim == 3 ? 4.0 / 3.0 * M_PI * pow(r->radius, 3) : M_PI * r->radius * r->radius;
    break;
  case SHAPE_HALFSPACE: {
    int a = r->axis;
    inside = box * fmin(1.0, fmax(0.0, (r->plane - p->box.lo[a]) / (p->box.hi[a] - p->box.lo[a])));
    break;
  }
  }
  return fmin(inside, box);
}

/* Check-time memory estimate (docs/reliability.md §4): particles = the regions' space over the
 * space per lattice site, times cd_particle_bytes. */
static void memory_check(const cd_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  double space = 0.0;
  for (int k = 0; k < p->nreg; k++) space += region_measure(p, &p->reg[k]);
  double box = 1.0;
  for (int a = 0; a < p->dim; a++) box *= p->box.hi[a] - p->box.lo[a];
  double site =
      cd_cluster_volume(p->lattice, p->r0, p->thickness) / (p->dim == 2 ? p->thickness : 1.0);
  ms_mem_estimate m;
  ms_mem_init(&m);
  ms_mem_add(&m, dk_get(sec, "regions"), "cluster_dynamics particles", fmin(space, box) / site,
             cd_particle_bytes(p->lattice, p->rc + p->skin));
  ms_mem_check(&m, ms_mem_limit(), 1, 1, e, doc);
  ms_mem_free(&m);
}

/* box: bounds, boundary conditions and lattice origin; a periodic axis holds a whole number of
 * lattice periods, at least 2. Returns the section's node (NULL: none). */
static const dk_node *read_box(cd_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *bn = dk_get(sec, "box");
  if (!bn) dk_error(e, doc, sec, "missing 'box' (lo, hi, boundary)");
  else if (dk_expect_map(e, doc, bn, "box")) {
    read_vec(e, doc, bn, "lo", p->dim, MS_DIM_LENGTH, true, NULL, p->box.lo);
    read_vec(e, doc, bn, "hi", p->dim, MS_DIM_LENGTH, true, NULL, p->box.hi);
    const dk_node *bcn = dk_get(bn, "boundary");
    if (!bcn) dk_error(e, doc, bn, "missing 'boundary' (one of free|periodic|wall per axis)");
    else if (dk_expect_seq(e, doc, bcn, "boundary")) {
      if ((int)dk_seq_len(bcn) != p->dim)
        dk_error(e, doc, bcn, "'boundary' needs %d entries", p->dim);
      for (size_t a = 0; a < dk_seq_len(bcn) && a < 3; a++) {
        const char *v = dk_scalar(dk_seq_at(bcn, a));
        int k = -1;
        for (int c = 0; v && bc_names[c]; c++)
          if (!strcmp(v, bc_names[c])) k = c;
        if (k < 0)
          dk_error(e, doc, dk_seq_at(bcn, a), "boundary '%s': expected free, periodic or wall",
                   v ? v : "?");
        else p->box.bc[a] = (cd_bc)k;
      }
    }
    read_vec(e, doc, bn, "lattice_origin", p->dim, MS_DIM_LENGTH, false, p->box.lo, p->origin);
    for (int a = 0; a < p->dim; a++)
      if (!(p->box.hi[a] > p->box.lo[a]))
        dk_error(e, doc, bn, "box: hi must exceed lo on axis %d", a);
    /* periodic axes must hold a whole number of lattice periods, at least 2 */
    double per[3];
    cd_deck_lattice_period(p, per);
    for (int a = 0; a < p->dim && p->r0 > 0; a++) {
      if (p->box.bc[a] != CD_BC_PERIODIC) continue;
      double L = p->box.hi[a] - p->box.lo[a], q = L / per[a];
      if (fabs(q - round(q)) > 1e-6 * q)
        dk_error(e, doc, bn,
                 "periodic axis %d: length %g is not a whole number of lattice periods "
                 "(%g)",
                 a, L, per[a]);
      if (round(q) < 2)
        dk_error(e, doc, bn,
                 "periodic axis %d: fewer than 2 lattice periods (%.3g) across it: "
                 "a particle would interact with its own image",
                 a, q);
      else if (L < 2.0 * (p->rc + p->skin) * p->r0)
        dk_error(e, doc, bn, "periodic axis %d: length %g below 2 (R_c + skin) = %g", a, L,
                 2.0 * (p->rc + p->skin) * p->r0);
    }
  }
  if (p->dim == 2) {
    p->box.bc[2] = CD_BC_FREE;
    p->box.lo[2] = p->box.hi[2] = 0.0;
  }
  return bn;
}

/* The box bounds the lattice: particles are indexed with 32-bit integers (neighbour lists),
 * and the checks below walk every lattice cell, so refuse a box that holds more sites
 * before any count is converted to an integer. True: too big (and said so). */
static bool box_too_big(const cd_problem *p, dk_doc *doc, const dk_node *bn, dk_errors *e) {
  double per[3], sites = p->dim == 3 ? 4.0 : 2.0, widest = 0.0;
  int axis = 0;
  cd_deck_lattice_period(p, per);
  for (int a = 0; a < p->dim; a++) {
    double cells = ceil((p->box.hi[a] - p->box.lo[a]) / per[a]) + 1;
    sites *= cells;
    if (cells > widest) widest = cells, axis = a;
  }
  const dk_node *at = dk_seq_at(dk_get(bn, "hi"), (size_t)axis);
  const bool big = !(sites <= CD_MAX_LATTICE_SITES);
  if (big)
    dk_error(e, doc, at ? at : bn,
             "box: holds about %.3g lattice sites at spacing %g cm (axis "
             "%d is the longest); at most %.3g are possible (particle indices are 32-bit)",
             sites, p->r0, axis, CD_MAX_LATTICE_SITES);
  return big;
}

/* interfaces: cutoff and attraction per material pair (default R_c and 1) */
static void read_interfaces(cd_problem *p, const eos_materials *mats, dk_doc *doc,
                            const dk_node *sec, dk_errors *e) {
  for (int a = 0; a < CD_MAX_MATERIALS; a++)
    for (int b = 0; b < CD_MAX_MATERIALS; b++) {
      p->rc_pair[a][b] = p->rc;
      p->attraction[a][b] = 1.0;
    }
  const dk_node *il = dk_get(sec, "interfaces");
  if (il && dk_expect_seq(e, doc, il, "interfaces"))
    for (size_t k = 0; k < dk_seq_len(il); k++) {
      const dk_node *in = dk_seq_at(il, k);
      if (!dk_expect_map(e, doc, in, "interface")) continue;
      const dk_node *mn = dk_get(in, "materials");
      int ia = -1, ib = -1;
      if (!mn || dk_node_kind(mn) != DK_SEQ || dk_seq_len(mn) != 2) {
        dk_error(e, doc, mn ? mn : in, "interface: 'materials' must list two material names");
      } else {
        const char *na = dk_scalar(dk_seq_at(mn, 0)), *nb = dk_scalar(dk_seq_at(mn, 1));
        if (na) ia = material_index(p, mats, doc, dk_seq_at(mn, 0), na, e);
        if (nb) ib = material_index(p, mats, doc, dk_seq_at(mn, 1), nb, e);
      }
      double rc = p->rc, att = 1.0;
      dk_read_double(e, doc, in, "cutoff", MS_DIM_NONE, false, p->rc, 1.0 + 1e-9, 3.0, &rc);
      dk_read_double(e, doc, in, "attraction", MS_DIM_NONE, false, 1.0, 0.0, 1.0, &att);
      if (ia >= 0 && ib >= 0) {
        p->rc_pair[ia][ib] = p->rc_pair[ib][ia] = rc;
        p->attraction[ia][ib] = p->attraction[ib][ia] = att;
      }
    }
}

/* piston: direction and a constant velocity or a history u(t); and front_velocity */
static void read_piston(cd_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *pn = dk_get(sec, "piston");
  bool any_piston = false;
  for (int k = 0; k < p->nreg; k++) any_piston |= p->reg[k].piston;
  if (pn && dk_expect_map(e, doc, pn, "piston")) {
    read_vec(e, doc, pn, "direction", p->dim, MS_DIM_NONE, true, NULL, p->piston_dir);
    const dk_node *vn = dk_get(pn, "velocity"), *hn = dk_get(pn, "history");
    if ((vn != NULL) == (hn != NULL))
      dk_error(e, doc, pn,
               "piston: give exactly one of 'velocity' (constant) or 'history' (CSV t,u)");
    if (vn) {
      double u = 0;
      dk_read_double(e, doc, pn, "velocity", MS_DIM_VELOCITY, true, 0, -INFINITY, INFINITY, &u);
      p->piston.n = 1;
      p->piston.t = ms_calloc(1, sizeof(double));
      p->piston.u = ms_calloc(1, sizeof(double));
      p->piston.u[0] = u;
    } else if (hn) {
      const char *file = NULL;
      if (dk_read_string(e, doc, pn, "history", true, NULL, &file)) {
        char *path = dk_resolve_path(doc, file);
        if (cd_history_read(&p->piston, path, dk_units(doc) == MS_UNITS_SI, e) != MS_OK)
          dk_error(e, doc, hn,
                   "piston history '%s' rejected (see the message above: it needs "
                   "columns t, u with t strictly increasing)",
                   path);
        free(path);
      }
    }
    if (!any_piston) dk_error(e, doc, pn, "piston given but no region has 'piston: true'");
  } else if (any_piston) {
    dk_error(e, doc, sec, "a region has 'piston: true' but there is no 'piston:' section");
  }
  double fu = p->piston.n ? fabs(p->piston.u[p->piston.n - 1]) : 0.0;
  dk_read_double(e, doc, sec, "front_velocity", MS_DIM_VELOCITY, false, fu, 0, INFINITY,
                 &p->front_u);
}

/* thermal velocities and output (rows, profiles, snapshots, checkpoints) */
static void read_thermal_output(cd_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *tn = dk_get(sec, "thermal");
  if (tn && dk_expect_map(e, doc, tn, "thermal")) {
    long seed = 12345;
    dk_read_double(e, doc, tn, "amplitude", MS_DIM_VELOCITY, true, 0, 0, INFINITY, &p->thermal_amp);
    dk_read_int(e, doc, tn, "seed", false, 12345, 0, 1L << 40, &seed);
    p->thermal_seed = (uint64_t)seed;
  }

  long every = 100, axis = p->dim - 1, bins = 100, snaps = 0;
  const dk_node *on = dk_get(sec, "output");
  if (on && dk_expect_map(e, doc, on, "output")) {
    dk_read_int(e, doc, on, "every", false, 100, 1, 1L << 40, &every);
    dk_read_int(e, doc, on, "profile_axis", false, p->dim - 1, 0, p->dim - 1, &axis);
    dk_read_int(e, doc, on, "profile_bins", false, 100, 1, 1000000, &bins);
    dk_read_int(e, doc, on, "snapshots", false, 0, 0, 100000, &snaps);
  }
  if (on && dk_node_kind(on) == DK_MAP) {
    dk_read_checkpoint_interval(e, doc, on, "", "steps", &p->checkpoint_every, &p->checkpoint_time);
  }
  p->out_every = (int)every;
  p->profile_axis = (int)axis;
  p->profile_bins = (int)bins;
  p->snapshots = (int)snaps;
}

/* relax: the relaxation stage before the piston starts */
static void read_relax(cd_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *xn = dk_get(sec, "relax");
  if (xn && dk_expect_map(e, doc, xn, "relax")) {
    long every = 10;
    p->relax_on = true;
    dk_read_double(e, doc, xn, "time", MS_DIM_TIME, true, 0, 0, INFINITY, &p->relax.time);
    dk_read_double(e, doc, xn, "damping", MS_DIM_NONE, false, 5.0, 0.0, 1e6, &p->relax_j);
    dk_read_bool(e, doc, xn, "quench", false, true, &p->relax.quench);
    dk_read_bool(e, doc, xn, "box", false, true, &p->relax.box);
    dk_read_int(e, doc, xn, "box_every", false, 10, 1, 1L << 30, &every);
    dk_read_double(e, doc, xn, "tau", MS_DIM_NONE, false, 10.0, 1e-3, 1e9, &p->relax_tau);
    dk_read_double(e, doc, xn, "max_strain", MS_DIM_NONE, false, 1e-3, 1e-9, 0.1,
                   &p->relax.max_strain);
    dk_read_bool(e, doc, xn, "plain", false, true, &p->relax.plain);
    p->relax.box_every = (int)every;
    p->relax.rebond = true;
  }
}

/* mpi: the decomposition on MPI ranks */
static void read_mpi(cd_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  p->mpi = (cd_mpi_config){.partition = CD_PART_AUTO,
                           .rebalance_threshold = 1.2,
                           .rebalance_interval = 10,
                           .replicated = true};
  const dk_node *mn = dk_get(sec, "mpi");
  if (mn && dk_expect_map(e, doc, mn, "mpi")) {
    int pm = CD_PART_AUTO;
    long iv = 10;
    dk_read_enum(e, doc, mn, "partition", false, CD_PART_AUTO, cd_partition_names, &pm);
    dk_read_double(e, doc, mn, "rebalance_threshold", MS_DIM_NONE, false, 1.2, 0.0, 1e6,
                   &p->mpi.rebalance_threshold);
    dk_read_int(e, doc, mn, "rebalance_interval", false, 10, 1, 1L << 30, &iv);
    const dk_node *tn = dk_get(mn, "rebalance_threshold");
    if (tn && p->mpi.rebalance_threshold > 0 && p->mpi.rebalance_threshold < 1)
      dk_error(e, doc, tn,
               "rebalance_threshold %g: the imbalance max/mean is >= 1; give a value "
               ">= 1, or 0 for never",
               p->mpi.rebalance_threshold);
    p->mpi.partition = (cd_partition_method)pm;
    p->mpi.rebalance_interval = (int)iv;
  }
}

/* Overlapping regions of different materials (some lattice site inside both), and a region
 * that holds no lattice site inside the box (a body outside the box, or smaller than a site). */
static void check_sites(const cd_problem *p, dk_doc *doc, dk_errors *e) {
  long sites[CD_MAX_REGIONS] = {0};
  double per[3];
  cd_deck_lattice_period(p, per);
  long ncell[3] = {1, 1, 1};
  for (int a = 0; a < p->dim; a++)
    ncell[a] = (long)ceil((p->box.hi[a] - p->origin[a]) / per[a]) + 1;
  bool reported[CD_MAX_REGIONS][CD_MAX_REGIONS] = {{false}};
  const double fcc[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const double tri[2][3] = {{0, 0, 0}, {0.5, 0.5, 0}};
  int nb = p->dim == 3 ? 4 : 2;
  for (long iz = 0; iz < ncell[2]; iz++)
    for (long iy = 0; iy < ncell[1]; iy++)
      for (long ix = 0; ix < ncell[0]; ix++)
        for (int b = 0; b < nb; b++) {
          const double *bs = p->dim == 3 ? fcc[b] : tri[b];
          double x[3] = {p->origin[0] + (ix + bs[0]) * per[0], p->origin[1] + (iy + bs[1]) * per[1],
                         p->dim == 3 ? p->origin[2] + (iz + bs[2]) * per[2] : 0.0};
          bool inside = true; /* the lattice fill keeps the sites inside the box only */
          for (int a = 0; a < p->dim; a++) inside &= x[a] >= p->box.lo[a] && x[a] < p->box.hi[a];
          int first = -1;
          for (int k = 0; k < p->nreg; k++) {
            /* a region whose material has errors of its own (mat < 0) is not compared */
            if (p->reg[k].matrix || p->reg[k].mat < 0 ||
                !cd_deck_region_contains(&p->reg[k], x, p->dim))
              continue;
            sites[k] += inside;
            if (first < 0) {
              first = k;
              continue;
            }
            if (p->reg[k].mat != p->reg[first].mat && !reported[first][k]) {
              reported[first][k] = true;
              dk_error(e, doc, p->reg[k].node,
                       "region %d (material '%s') overlaps region %d "
                       "(material '%s'), e.g. at (%g, %g, %g): regions of different materials "
                       "must not overlap",
                       k + 1, p->mat[p->reg[k].mat]->name, first + 1,
                       p->mat[p->reg[first].mat]->name, x[0], x[1], x[2]);
            }
          }
        }
  for (int k = 0; k < p->nreg; k++)
    if (!p->reg[k].matrix && p->reg[k].mat >= 0 && sites[k] == 0)
      dk_error(e, doc, p->reg[k].node,
               "region %d holds no lattice site inside the box (lo %g %g %g, hi %g %g %g): it "
               "lies outside the box or is smaller than one site (r0 = %g)",
               k + 1, p->box.lo[0], p->box.lo[1], p->box.lo[2], p->box.hi[0], p->box.hi[1],
               p->box.hi[2], p->r0);
}

/* A region velocity that would carry a particle half a cluster size in the first step: the
 * run's instability guard stops there (docs/reliability.md §6), so say it at the velocity. */
static void check_velocities(const cd_problem *p, dk_doc *doc, dk_errors *e) {
  double c0max = 0.0;
  for (int k = 0; k < p->nmat; k++) c0max = fmax(c0max, eos_c0(p->mat[k]->eos));
  const double dt = p->dt > 0 ? p->dt : p->courant * p->r0 / c0max;
  for (int k = 0; k < p->nreg; k++) {
    const double *v = p->reg[k].velocity;
    const double speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (c0max > 0 && speed * dt >= 0.5 * p->r0)
      dk_error(e, doc, dk_get(p->reg[k].node, "velocity"),
               "region %d: speed %g km/s moves a particle %.3g r0 in one time step (dt = %g): "
               "more than the 0.5 r0 per step the run allows; lower dt or courant",
               k + 1, speed, speed * dt / p->r0, dt);
  }
}

cd_problem *cd_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                            dk_errors *e) {
  size_t nerr0 = e->n;
  cd_problem *p = ms_calloc(1, sizeof *p);
  long dim = 3;
  dk_read_int(e, doc, sec, "dimension", false, 3, 2, 3, &dim);
  p->dim = (int)dim;
  p->lattice = dim == 2 ? CD_LATTICE_TRI2D : CD_LATTICE_FCC;
  const cd_model_defaults defaults = {"cluster_dynamics", 0.02, 0.0};
  cd_model_keys k;
  cd_model_keys_read(e, doc, sec, dim, &defaults, &k, NULL, 0);
  p->r0 = k.r0, p->thickness = k.thickness, p->rc = k.rc, p->mode = k.mode, p->skin = k.skin;
  p->courant = k.courant, p->dt = k.dt, p->r_min = k.r_min, p->damping_j = k.damping_j;
  p->table_intervals = k.table_intervals;
  dk_read_positive(e, doc, sec, "t_end", MS_DIM_TIME, true, 0, &p->t_end);
  int integ = CD_INT_VELOCITY_VERLET;
  dk_read_enum(e, doc, sec, "integrator", false, CD_INT_VELOCITY_VERLET, cd_integrator_names,
               &integ);
  p->integrator = (cd_integrator)integ;

  const dk_node *bn = read_box(p, doc, sec, e);
  const bool too_big = bn && e->n == nerr0 && p->r0 > 0 && box_too_big(p, doc, bn, e);
  const dk_node *rl = dk_get(sec, "regions");
  if (!rl) dk_error(e, doc, sec, "missing 'regions' (list of material regions)");
  else if (dk_expect_seq(e, doc, rl, "regions"))
    for (size_t k = 0; k < dk_seq_len(rl); k++) read_region(p, mats, doc, dk_seq_at(rl, k), e);
  read_interfaces(p, mats, doc, sec, e);
  read_piston(p, doc, sec, e);
  read_thermal_output(p, doc, sec, e);
  read_relax(p, doc, sec, e);
  read_mpi(p, doc, sec, e);

  /* refuse what cannot fit before anything is allocated (also said for a box of too many
   * sites: the estimate tells how far off the deck is) */
  if (e->n == nerr0 + too_big) memory_check(p, doc, sec, e);
  if (e->n == nerr0) check_sites(p, doc, e);
  if (e->n == nerr0) check_velocities(p, doc, e);
  if (e->n > nerr0) {
    cd_problem_destroy(&p);
    return NULL;
  }
  /* a restart may run to another t_end; anything else must be the deck that wrote it */
  static const char *const hash_skip[] = {"cluster_dynamics.t_end", NULL};
  p->deck_hash = dk_hash(doc, hash_skip);
  p->deck_hash = dk_hash_doubles(p->deck_hash, p->piston.t, p->piston.n);
  p->deck_hash = dk_hash_doubles(p->deck_hash, p->piston.u, p->piston.n);
  return p;
}

static void cd_problem_free(cd_problem *p) {
  if (!p) return;
  cd_history_free(&p->piston);
  free(p);
}

void cd_problem_destroy(cd_problem **p) {
  if (!p) return;
  cd_problem_free(*p);
  *p = NULL;
}
