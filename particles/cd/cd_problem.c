/* SPDX-License-Identifier: MIT */
/* cd_problem.c — the `cluster_dynamics` deck problem (docs/input-cd.md): read and check the
 * section, fill the regions with a lattice, run, and write energy balance, profiles, front
 * positions and HDF5/XDMF snapshots into the output directory.
 *
 * Every problem in the section is recorded as a deck error (FILE:LINE:COL), never the first
 * only: overlapping regions of different materials, fewer than 2 lattice periods across a
 * periodic dimension, R_c not above the nearest-neighbour distance, a piston history whose
 * time does not increase.
 */
#include "cd_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { CD_MAX_REGIONS = 32 };
typedef enum { SHAPE_BOX = 0, SHAPE_SPHERE, SHAPE_CYLINDER, SHAPE_HALFSPACE } region_shape;
static const char *const shape_names[] = {"box", "sphere", "cylinder", "halfspace", NULL};

/* Largest lattice a deck may ask for: particle indices are int32_t. */
#define CD_MAX_LATTICE_SITES 2.0e9
typedef enum { SURF_FLAT = 0, SURF_SINE, SURF_RANDOM } surface_kind;
static const char *const surface_names[] = {"flat", "sine", "random", NULL};
static const char *const bc_names[] = {"free", "periodic", "wall", NULL};
static const char *const mode_names[] = {"plain", "bonded", NULL};
static const char *const partition_names[] = {"slab", "metis", "auto",
                                              NULL}; /* cd_partition_method */

typedef struct cd_region {
  int mat; /* index into the problem's material list */
  region_shape shape;
  double lo[3], hi[3];      /* box */
  double center[3], radius; /* sphere, cylinder (axis `axis`) */
  int axis;                 /* cylinder axis; halfspace normal axis */
  double plane;             /* halfspace: x_axis < plane */
  double velocity[3];
  bool piston;
  bool matrix; /* fills only the sites no other region takes (no overlap check) */
  int ngrains; /* polycrystal / grain structure (box regions; 0 = single crystal) */
  uint64_t grain_seed;
  bool rotate; /* random lattice orientation per grain */
  double dmin; /* overlap removal distance / r0 */
  int ngmat;   /* grain materials (0: the region's material) */
  int gmat[CD_MAX_MATERIALS];
  double gfrac[CD_MAX_MATERIALS];
  surface_kind surface; /* box: profile of the hi face along `surface_axis` */
  int surface_axis, surface_along;
  double amplitude, wavelength;
  uint64_t seed;
  const dk_node *node;
} cd_region;

struct cd_problem {
  int dim;
  cd_lattice lattice;
  double r0, thickness, rc, skin, courant, dt, t_end, r_min, damping_j, attraction_default;
  int table_intervals;
  cd_cutoff_mode mode;
  cd_integrator integrator;
  cd_box box;
  double origin[3];
  int nmat;
  const eos_material *mat[CD_MAX_MATERIALS];
  double rc_pair[CD_MAX_MATERIALS][CD_MAX_MATERIALS],
      attraction[CD_MAX_MATERIALS][CD_MAX_MATERIALS];
  int nreg;
  cd_region reg[CD_MAX_REGIONS];
  cd_history piston;
  double piston_dir[3];
  double thermal_amp;
  uint64_t thermal_seed;
  int out_every, profile_axis, profile_bins, snapshots;
  cd_mpi_config mpi;      /* decomposition on MPI ranks (docs/input-cd.md "mpi") */
  double front_u;         /* reference velocity for front tracking (piston velocity by default) */
  long checkpoint_every;  /* steps between checkpoints (0: none) */
  double checkpoint_time; /* or simulated time between them (rounded to whole steps) */
  uint64_t deck_hash;     /* resolved deck (t_end left out) and piston history */
  bool relax_on;          /* `relax:` given: cd_sim_relax before the piston starts */
  cd_relax_config relax;  /* times in 10 us; Γ, tau, modulus set at run time from c0 */
  double relax_j, relax_tau; /* damping J (0: none); box tau in r0/c0 */
};

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
  cd_region *r = &p->reg[p->nreg];
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
    if (r->shape != SHAPE_BOX) dk_error(e, doc, gn, "a polycrystal fills a box region");
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

/* seeds and materials of a region's grains (the seeds are those of cd_polycrystal) */
static void grain_seed(const cd_region *r, int dim, int g, double x[3]) {
  for (int a = 0; a < 3; a++)
    x[a] = a < dim ? r->lo[a] + (r->hi[a] - r->lo[a]) *
                                    ptl_splitmix64_uniform(r->grain_seed, 3 * (uint64_t)g + a)
                   : 0.0;
}
static int grain_material(const cd_region *r, int g) {
  if (r->ngmat == 0) return r->mat;
  double u = ptl_splitmix64_uniform(r->grain_seed ^ 0x5bd1e995u, (uint64_t)g), acc = 0;
  for (int k = 0; k < r->ngmat; k++) {
    acc += r->gfrac[k];
    if (u < acc) return r->gmat[k];
  }
  return r->gmat[r->ngmat - 1];
}
static int nearest_grain(const cd_region *r, int dim, const double x[3]) {
  int best = 0;
  double bd = INFINITY;
  for (int g = 0; g < r->ngrains; g++) {
    double s[3], d2 = 0;
    grain_seed(r, dim, g, s);
    for (int a = 0; a < dim; a++) d2 += (x[a] - s[a]) * (x[a] - s[a]);
    if (d2 < bd) {
      bd = d2;
      best = g;
    }
  }
  return best;
}

/* Height of a box region's profiled hi face at coordinate s along the surface. Random: a sum of
 * 8 sine modes with wavelengths λ/1..λ/8, amplitudes ∝ 1/k and random phases, scaled to the
 * given peak amplitude (a smooth random roughness). */
static double surface_height(const cd_region *r, double s) {
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

static bool region_contains(const cd_region *r, const double x[3], int dim) {
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

/* lattice period along each axis: fcc cubic constant a = √2 r0; triangular r0 × √3 r0 */
static void lattice_period(const cd_problem *p, double per[3]) {
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
static double region_measure(const cd_problem *p, const cd_region *r) {
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

  /* box */
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
    lattice_period(p, per);
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
  /* The box bounds the lattice: particles are indexed with 32-bit integers (neighbour lists),
   * and the checks below walk every lattice cell, so refuse a box that holds more sites
   * before any count is converted to an integer. */
  bool box_too_big = false;
  if (bn && e->n == nerr0 && p->r0 > 0) {
    double per[3], sites = p->dim == 3 ? 4.0 : 2.0, widest = 0.0;
    int axis = 0;
    lattice_period(p, per);
    for (int a = 0; a < p->dim; a++) {
      double cells = ceil((p->box.hi[a] - p->box.lo[a]) / per[a]) + 1;
      sites *= cells;
      if (cells > widest) widest = cells, axis = a;
    }
    const dk_node *at = dk_seq_at(dk_get(bn, "hi"), (size_t)axis);
    box_too_big = !(sites <= CD_MAX_LATTICE_SITES);
    if (box_too_big)
      dk_error(e, doc, at ? at : bn,
               "box: holds about %.3g lattice sites at spacing %g cm (axis "
               "%d is the longest); at most %.3g are possible (particle indices are 32-bit)",
               sites, p->r0, axis, CD_MAX_LATTICE_SITES);
  }

  /* regions */
  const dk_node *rl = dk_get(sec, "regions");
  if (!rl) dk_error(e, doc, sec, "missing 'regions' (list of material regions)");
  else if (dk_expect_seq(e, doc, rl, "regions"))
    for (size_t k = 0; k < dk_seq_len(rl); k++) read_region(p, mats, doc, dk_seq_at(rl, k), e);

  /* interfaces (per material pair) */
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

  /* piston */
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

  p->mpi = (cd_mpi_config){.partition = CD_PART_AUTO,
                           .rebalance_threshold = 1.2,
                           .rebalance_interval = 10,
                           .replicated = true};
  const dk_node *mn = dk_get(sec, "mpi");
  if (mn && dk_expect_map(e, doc, mn, "mpi")) {
    int pm = CD_PART_AUTO;
    long iv = 10;
    dk_read_enum(e, doc, mn, "partition", false, CD_PART_AUTO, partition_names, &pm);
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

  /* refuse what cannot fit before anything is allocated (also said for a box of too many
   * sites: the estimate tells how far off the deck is) */
  if (e->n == nerr0 + box_too_big) memory_check(p, doc, sec, e);
  /* overlapping regions of different materials: some lattice site inside both */
  if (e->n == nerr0 && p->nreg > 1) {
    double per[3];
    lattice_period(p, per);
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
            double x[3] = {p->origin[0] + (ix + bs[0]) * per[0],
                           p->origin[1] + (iy + bs[1]) * per[1],
                           p->dim == 3 ? p->origin[2] + (iz + bs[2]) * per[2] : 0.0};
            int first = -1;
            for (int k = 0; k < p->nreg; k++) {
              /* a region whose material has errors of its own (mat < 0) is not compared */
              if (p->reg[k].matrix || p->reg[k].mat < 0 || !region_contains(&p->reg[k], x, p->dim))
                continue;
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
  }
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

/* Fill the regions: a site belongs to the first ordinary region containing it (overlaps of the
 * same material are fine), else to the first `matrix` region containing it. Polycrystal regions
 * with rotated grains claim their sites in the global lattice and are then filled by
 * cd_polycrystal (their residual porosity goes to the log). */
typedef struct site_list {
  size_t n, cap;
  double *x;
  int *reg, *mat;
} site_list;

static void site_add(site_list *l, const double x[3], int reg, int mat) {
  if (l->n == l->cap) {
    l->cap = l->cap ? 2 * l->cap : 4096;
    l->x = ms_realloc(l->x, 3 * l->cap, sizeof *l->x);
    l->reg = ms_realloc(l->reg, l->cap, sizeof *l->reg);
    l->mat = ms_realloc(l->mat, l->cap, sizeof *l->mat);
  }
  memcpy(l->x + 3 * l->n, x, 3 * sizeof *x);
  l->reg[l->n] = reg;
  l->mat[l->n++] = mat;
}

static int owner_region(const cd_problem *p, const double x[3]) {
  for (int kk = 0; kk < 2 * p->nreg; kk++) { /* ordinary regions, then matrices */
    const int k = kk % p->nreg;
    const cd_region *r = &p->reg[k];
    if (r->matrix == (kk >= p->nreg) && region_contains(r, x, p->dim)) return k;
  }
  return -1;
}

typedef struct owner_filter {
  const cd_problem *p;
  int reg;
} owner_filter;
static bool owned_by(void *user, const double x[3]) {
  const owner_filter *f = user;
  return owner_region(f->p, x) == f->reg;
}

static ptl_state *build_particles(const cd_problem *p, ms_ctx *ctx) {
  double per[3];
  lattice_period(p, per);
  long ncell[3] = {1, 1, 1};
  for (int a = 0; a < p->dim; a++)
    ncell[a] = (long)ceil((p->box.hi[a] - p->origin[a]) / per[a]) + 1;
  const int nb = p->dim == 3 ? 4 : 2;
  const double fcc[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const double tri[2][3] = {{0, 0, 0}, {0.5, 0.5, 0}};
  const double vol = cd_cluster_volume(p->lattice, p->r0, p->thickness);
  site_list l = {0};
  for (long iz = 0; iz < ncell[2]; iz++)
    for (long iy = 0; iy < ncell[1]; iy++)
      for (long ix = 0; ix < ncell[0]; ix++)
        for (int b = 0; b < nb; b++) {
          const double *bs = p->dim == 3 ? fcc[b] : tri[b];
          double x[3] = {p->origin[0] + (ix + bs[0]) * per[0], p->origin[1] + (iy + bs[1]) * per[1],
                         p->dim == 3 ? p->origin[2] + (iz + bs[2]) * per[2] : 0.0};
          bool inside = true;
          for (int a = 0; a < p->dim; a++)
            if (x[a] < p->box.lo[a] || x[a] >= p->box.hi[a]) inside = false;
          if (!inside) continue;
          int k = owner_region(p, x);
          if (k < 0) continue;
          const cd_region *r = &p->reg[k];
          if (r->ngrains > 0 && r->rotate) continue; /* filled below */
          int mat = r->ngrains > 0 ? grain_material(r, nearest_grain(r, p->dim, x)) : r->mat;
          site_add(&l, x, k, mat);
        }
  for (int k = 0; k < p->nreg; k++) {
    const cd_region *r = &p->reg[k];
    if (r->ngrains == 0 || !r->rotate) continue;
    double lo[3], hi[3], *xyz = NULL, por = 0;
    int32_t *grain = NULL;
    /* a profiled face reaches up to `amplitude` beyond hi: grains fill that box and the owner
     * filter cuts the profile; the sine and random profiles average zero over the periodic
     * extent, so the region's volume is that of the flat box (the porosity's reference) */
    double vbox = 1.0;
    for (int a = 0; a < 3; a++) {
      lo[a] = a < p->dim ? fmax(r->lo[a], p->box.lo[a]) : 0.0;
      hi[a] = a < p->dim ? fmin(r->hi[a], p->box.hi[a]) : 0.0;
      if (a < p->dim) vbox *= hi[a] - lo[a];
      if (r->surface != SURF_FLAT && a == r->surface_axis)
        hi[a] = fmin(r->hi[a] + r->amplitude, p->box.hi[a]);
    }
    /* grains wrap along a periodic axis that the region spans */
    bool per[3] = {false, false, false};
    for (int a = 0; a < p->dim; a++)
      per[a] =
          p->box.bc[a] == CD_BC_PERIODIC && r->lo[a] <= p->box.lo[a] && r->hi[a] >= p->box.hi[a];
    owner_filter f = {p, k};
    size_t n = cd_polycrystal(p->dim, p->r0, p->thickness, lo, hi, per, r->ngrains, r->grain_seed,
                              r->dmin, owned_by, &f, &xyz, &grain, &por);
    if (r->surface != SURF_FLAT)
      por = 1.0 - (double)n * vol / (p->dim == 2 ? vbox * p->thickness : vbox);
    for (size_t i = 0; i < n; i++) site_add(&l, xyz + 3 * i, k, grain_material(r, grain[i]));
    ms_log(ctx, MS_LOG_INFO,
           "cluster_dynamics: region %d: polycrystal of %d grains, %zu particles, "
           "residual porosity %.2f %%",
           k + 1, r->ngrains, n, 100.0 * por);
    free(xyz);
    free(grain);
  }
  ptl_state *s = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = l.n, .dim = p->dim}, &s), "ptl_state_create");
  for (size_t q = 0; q < l.n; q++) {
    const cd_region *r = &p->reg[l.reg[q]];
    const double *x = l.x + 3 * q;
    size_t i = ptl_state_add(s, x[0], x[1], x[2], eos_rho0(p->mat[l.mat[q]]->eos) * vol, l.mat[q]);
    s->vx[i] = r->velocity[0];
    s->vy[i] = r->velocity[1];
    s->vz[i] = r->velocity[2];
    if (r->piston) s->flags[i] |= PTL_DRIVEN;
  }
  free(l.x);
  free(l.reg);
  free(l.mat);
  return s;
}

static void write_energy_row(FILE *f, const cd_sim *s, const cd_energy *e, double vfs) {
  double row[11] = {s->t,           e->kinetic,     e->potential, e->dissipated,
                    e->broken,      e->piston_work, e->total,     e->momentum[0],
                    e->momentum[1], e->momentum[2], vfs};
  ms_csv_row(f, 11, row);
}

static void write_headers(FILE *fe, FILE *fp, FILE *ff) {
  static const char *const ecol[] = {"t",      "kinetic",     "potential",     "dissipated",
                                     "broken", "piston_work", "total",         "px",
                                     "py",     "pz",          "v_free_surface"};
  static const char *const eunit[] = {"10us",      "g(km/s)^2", "g(km/s)^2", "g(km/s)^2",
                                      "g(km/s)^2", "g(km/s)^2", "g(km/s)^2", "g km/s",
                                      "g km/s",    "g km/s",    "km/s"};
  ms_csv_header(fe,
                "cluster dynamics energy balance (total = kinetic + potential + dissipated "
                "+ broken - piston_work)",
                11, ecol, eunit);
  const char *pcol[CD_PROFILE_NCOL + 1] = {"t"};
  const char *punit[CD_PROFILE_NCOL + 1] = {"10us", "cm",  "-",   "g/cm^3", "km/s", "km/s", "km/s",
                                            "GPa",  "GPa", "GPa", "GPa",    "GPa",  "GPa",  "GPa"};
  for (int c = 0; c < CD_PROFILE_NCOL; c++) pcol[c + 1] = cd_profile_columns[c];
  ms_csv_header(fp, "cluster dynamics binned profiles (stress compression-positive)",
                CD_PROFILE_NCOL + 1, pcol, punit);
  static const char *const fcol[] = {"t", "front"}, *const funit[] = {"10us", "cm"};
  ms_csv_header(ff,
                "shock front: where the bin-mean velocity along the profile axis falls "
                "below half the front_velocity",
                2, fcol, funit);
}

/* ---- checkpoints (docs/mpi.md): OUTDIR/cd_checkpoint.h5 ---- */
#define CD_CHECKPOINT_FORMAT "mscale cluster_dynamics checkpoint 1"
enum { CD_NSTREAMS = 3, CD_MAX_FRONT = 4096 };
static const char *const stream_names[CD_NSTREAMS] = {
    "/outputs/cd_energy.csv", "/outputs/cd_profiles.csv", "/outputs/cd_front.csv"};

/* The state at the end of a step, before that step's outputs: the particles (after
 * cd_sim_refresh, which the restart repeats), the CSV text so far and the front samples. */
static ms_status write_checkpoint(ms_ctx *ctx, const cd_problem *p, cd_sim *s,
                                  ms_afile *const streams[CD_NSTREAMS], const double *front,
                                  int nf) {
  ms_status st = cd_sim_refresh(s);
  if (st != MS_OK) return st;
  ms_h5 *h = ms_ckpt_create(ctx, "cd_checkpoint.h5", CD_CHECKPOINT_FORMAT, p->deck_hash);
  if (!h) return MS_ERR_IO;
  st = cd_checkpoint_write(h, ctx, s);
  for (int k = 0; k < CD_NSTREAMS && st == MS_OK; k++)
    st = ms_ckpt_save_afile(ctx, h, stream_names[k], streams[k]);
  if (st == MS_OK)
    st = ms_h5_write_doubles_dist(h, "/outputs/front", ctx->rank == 0 ? (size_t)nf : 0, 2, front,
                                  "10us, cm");
  return ms_ckpt_commit(ctx, h, st, "cd_checkpoint.h5", s->step);
}

static ms_status restore_outputs(const ms_ctx *ctx, ms_h5r *h, ms_afile *const streams[CD_NSTREAMS],
                                 double *front, int *nf) {
  dk_errors e;
  dk_errors_init(&e);
  ms_status st = MS_OK;
  for (int k = 0; k < CD_NSTREAMS && st == MS_OK; k++)
    st = ms_ckpt_restore_afile(ctx, h, stream_names[k], streams[k], &e);
  double *v = NULL;
  size_t n = 0, ncol = 0;
  if (st == MS_OK)
    st = ms_h5_read_doubles_rows(h, "/outputs/front", 0, SIZE_MAX, &v, &n, &ncol, &e);
  if (st == MS_OK && (ncol != 2 || n > CD_MAX_FRONT)) {
    dk_error_at(&e, ctx->restart, 0, 0, "'/outputs/front' is not a table of at most %d (t, z) rows",
                CD_MAX_FRONT);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) {
    memcpy(front, v, 2 * n * sizeof *v);
    *nf = (int)n;
  }
  free(v);
  st = par_agree_status(st);
  if (st != MS_OK && ctx->rank == 0) dk_errors_print(&e, stderr);
  dk_errors_free(&e);
  return st;
}

/* Thermal velocities: amplitude·(2u − 1) per component, u the splitmix64 output of the
 * particle's gid (the same on any rank count), mean removed over the integrated particles
 * (`dist`: over every rank's share). */
static void add_thermal(const cd_problem *p, ptl_state *ps, bool dist) {
  double mean[4] = {0, 0, 0, 0}, *v[3] = {ps->vx, ps->vy, ps->vz}; /* Σ dv per axis, count */
  for (size_t i = 0; i < ps->nlocal; i++) {
    if (ps->flags[i] & PTL_DRIVEN) continue;
    for (int c = 0; c < p->dim; c++) {
      double dv =
          p->thermal_amp *
          (2.0 * ptl_splitmix64_uniform(p->thermal_seed, 3 * (uint64_t)ps->gid[i] + c) - 1.0);
      v[c][i] += dv;
      mean[c] += dv;
    }
    mean[3] += 1.0;
  }
  if (dist) par_sum_doubles(mean, 4);
  for (size_t i = 0; i < ps->nlocal; i++)
    if (!(ps->flags[i] & PTL_DRIVEN))
      for (int c = 0; c < p->dim; c++) v[c][i] -= mean[c] / (mean[3] > 0 ? mean[3] : 1.0);
}

/* The relaxation stage (`relax:`): damped dynamics with the box rescaled toward zero mean
 * normal stress, then at rest with the bonds of the relaxed packing; logged. */
static ms_status relax_sample(ms_ctx *ctx, const cd_problem *p, cd_sim *s, double c0max,
                              size_t nglobal) {
  cd_relax_config rc = p->relax;
  double rho0 = 0.0; /* stiffness scale of the box rescale: largest ρ0 times largest c0² */
  for (int k = 0; k < p->nmat; k++) rho0 = fmax(rho0, eos_rho0(p->mat[k]->eos));
  rc.damping_gamma = p->relax_j > 0 ? c0max / (p->relax_j * p->r0) : 0.0;
  rc.tau = p->relax_tau * p->r0 / c0max;
  rc.modulus = rho0 * c0max * c0max;
  cd_relax_result r;
  ms_status st = cd_sim_relax(s, &rc, &r);
  if (st != MS_OK) return st;
  const double vsolid = (double)nglobal * cd_cluster_volume(p->lattice, p->r0, p->thickness);
  ms_log(ctx, MS_LOG_INFO,
         "cluster_dynamics: relaxation: %ld steps; mean stress xx yy zz %.4g "
         "%.4g %.4g -> %.4g %.4g %.4g GPa; box stretch %.5f %.5f %.5f; density %.5g -> %.5g g/cm3, "
         "porosity (1 - N V_site/V) %.3f -> %.3f %%; energy released %.4g kJ/g (damping and quench "
         "%.4g); %ld bonds broken",
         r.steps, r.stress0[0], r.stress0[1], r.stress0[2], r.stress[0], r.stress[1], r.stress[2],
         r.lambda[0], r.lambda[1], r.lambda[2], r.mass / r.volume0, r.mass / r.volume,
         100.0 * (1.0 - vsolid / r.volume0), 100.0 * (1.0 - vsolid / r.volume), r.energy / r.mass,
         r.dissipated / r.mass, r.broken_bonds);
  if (p->thermal_amp > 0) add_thermal(p, s->p, s->dd != NULL);
  return MS_OK;
}

ms_status cd_problem_run(ms_ctx *ctx, cd_problem *p) {
  cd_restart *rs = NULL;
  ms_h5r *rh = NULL;
  ptl_state *ps = NULL;
  if (ctx->restart) {
    dk_errors e;
    dk_errors_init(&e);
    rh = ms_ckpt_open(ctx->restart, CD_CHECKPOINT_FORMAT, p->deck_hash, &e);
    if (rh) rs = cd_restart_read(rh, ctx, p->dim, p->mode == CD_CUTOFF_BONDED, &e);
    if (rs) ps = cd_restart_take_particles(rs);
    ms_status st = par_agree_status(rs ? MS_OK : MS_ERR_INPUT);
    if (st != MS_OK) {
      if (ctx->rank == 0) dk_errors_print(&e, stderr);
      ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: cannot restart from %s", ctx->restart);
    }
    dk_errors_free(&e);
    if (st != MS_OK) {
      ptl_state_destroy(&ps);
      cd_restart_destroy(&rs);
      ms_h5_close_read(rh);
      return st;
    }
  } else {
    ps = build_particles(p, ctx);
  }
  if (!ps || ps->n == 0) {
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: the regions contain no lattice site");
    ptl_state_destroy(&ps);
    return MS_ERR_INPUT;
  }
  /* thermal velocities; with a relaxation they are given after it (it ends at rest) */
  if (p->thermal_amp > 0 && !rs && !p->relax_on) add_thermal(p, ps, false);
  /* free-surface layer: particles within r0 of the farthest one along the piston direction */
  double dir[3] = {p->piston_dir[0], p->piston_dir[1], p->piston_dir[2]};
  int axis = p->profile_axis;
  if (p->piston.n && !rs) {
    double smax = -INFINITY;
    for (size_t i = 0; i < ps->n; i++) {
      double sx = ps->x[i] * dir[0] + ps->y[i] * dir[1] + ps->z[i] * dir[2];
      if (sx > smax) smax = sx;
    }
    for (size_t i = 0; i < ps->n; i++) {
      double sx = ps->x[i] * dir[0] + ps->y[i] * dir[1] + ps->z[i] * dir[2];
      if (sx > smax - p->r0 && !(ps->flags[i] & PTL_DRIVEN)) ps->flags[i] |= PTL_SURFACE;
    }
  }
  double c0max = 0;
  for (int k = 0; k < p->nmat; k++) c0max = fmax(c0max, eos_c0(p->mat[k]->eos));
  cd_config cfg = {.r0 = p->r0,
                   .skin = p->skin * p->r0,
                   .dt = p->dt > 0 ? p->dt : p->courant * p->r0 / c0max,
                   .cutoff = p->mode,
                   .damping_gamma = p->damping_j > 0 ? c0max / (p->damping_j * p->r0) : 0.0,
                   .sort_every = 8,
                   .lattice = p->lattice,
                   .thickness = p->thickness,
                   .integrator = p->integrator};
  const bool dist = ctx->size > 1;
  const size_t nglobal = ps->n;
  cd_sim *s = NULL;
  ms_must(cd_sim_create(
              &(cd_sim_params){.particles = ps, .box = &p->box, .cfg = &cfg, .nmat = p->nmat}, &s),
          "cd_sim_create");
  /* every rank built (or read) the whole set: cd_sim_init keeps what each rank's cells own */
  if (dist) cd_sim_set_mpi(s, &p->mpi);
  for (int a = 0; a < p->nmat; a++)
    for (int b = a; b < p->nmat; b++) {
      cd_pair_table *t = ms_calloc(1, sizeof *t);
      if (cd_pair_table_build(t, p->mat[a]->eos, p->mat[b]->eos, p->lattice, p->r0, p->thickness,
                              p->rc_pair[a][b] * p->r0, p->r_min * p->r0, p->attraction[a][b],
                              p->table_intervals) != MS_OK) {
        ms_log(ctx, MS_LOG_ERROR,
               "cluster_dynamics: cannot tabulate the pair potential of '%s'-'%s' "
               "on [r_min, R_c] (cold curve undefined there?)",
               p->mat[a]->name, p->mat[b]->name);
        free(t);
        cd_sim_destroy(&s);
        cd_restart_destroy(&rs);
        ms_h5_close_read(rh);
        return MS_ERR_INPUT;
      }
      cd_sim_set_pair(s, a, b, t);
    }
  if (p->piston.n) cd_sim_set_piston(s, &p->piston, dir);
  const long nsteps = (long)ceil(p->t_end / cfg.dt - 1e-9);
  ms_status st;
  if (rs) {
    dk_errors e;
    dk_errors_init(&e);
    st = cd_restart_step(rs) > nsteps ? MS_ERR_INPUT : cd_sim_init_restart(s, rs, &e);
    if (cd_restart_step(rs) > nsteps)
      dk_error_at(&e, ctx->restart, 0, 0,
                  "the checkpoint is at step %ld, beyond this deck's "
                  "end (step %ld)",
                  cd_restart_step(rs), nsteps);
    if (st != MS_OK && ctx->rank == 0) dk_errors_print(&e, stderr);
    dk_errors_free(&e);
  } else {
    st = cd_sim_init(s);
    if (st == MS_OK && p->relax_on) st = relax_sample(ctx, p, s, c0max, nglobal);
  }
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: set-up failed (%s)", ms_status_str(st));
    cd_sim_destroy(&s);
    cd_restart_destroy(&rs);
    ms_h5_close_read(rh);
    return st;
  }
  ms_log(ctx, MS_LOG_INFO,
         "cluster_dynamics: %zu particles, %d material(s), dt = %g, R_c = %g r0, "
         "%s cutoff, damping Gamma = %g, integrator %s, %zu bytes/particle",
         nglobal, p->nmat, cfg.dt, p->rc, mode_names[p->mode], cfg.damping_gamma,
         cd_integrator_names[p->integrator], cd_sim_bytes(s) / (ps->nlocal ? ps->nlocal : 1));
  const cd_mpi_stats *ms = cd_sim_mpi_stats(s);
  long rebalances_logged = 0;
  if (ms) {
    const cd_partition_stats *pst = &ms->partition;
    char alt[80] = ""; /* auto: the map it did not take */
    if (!isnan(pst->rejected_load))
      snprintf(alt, sizeof alt, " (auto; %s: load %.3f)",
               partition_names[pst->method == CD_PART_SLAB ? CD_PART_METIS : CD_PART_SLAB],
               pst->rejected_load);
    ms_log(ctx, MS_LOG_INFO,
           "cluster_dynamics on %d ranks: %dx%dx%d coarse cells, %s partition%s: "
           "edge cut %ld, imbalance %.3f, load %.3f; owned max %zu, ghosts %zu in all; "
           "rebalance above %g (checked every %d list builds)",
           ms->ranks, ms->ncell[0], ms->ncell[1], ms->ncell[2], partition_names[pst->method], alt,
           pst->edge_cut, ms->imbalance, pst->load, ms->max_owned, ms->total_ghosts,
           p->mpi.rebalance_threshold, p->mpi.rebalance_interval);
  }

  /* outputs */
  /* rank 0 writes the CSV files; every rank runs the same loop (the diagnostics are collective) */
  const bool root = ctx->rank == 0;
  ms_afile fe = {0}, fp = {0}, ff = {0};
  if (root) {
    char *path = ms_out_path(ctx, "cd_energy.csv");
    st = ms_afile_open(&fe, path);
    free(path);
    if (st == MS_OK) {
      path = ms_out_path(ctx, "cd_profiles.csv");
      st = ms_afile_open(&fp, path);
      free(path);
    }
    if (st == MS_OK) {
      path = ms_out_path(ctx, "cd_front.csv");
      st = ms_afile_open(&ff, path);
      free(path);
    }
  }
  if (dist) st = par_agree_status(st);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: cannot open output files");
    if (fe.f) ms_afile_abort(&fe);
    if (fp.f) ms_afile_abort(&fp);
    cd_sim_destroy(&s);
    cd_restart_destroy(&rs);
    ms_h5_close_read(rh);
    return st;
  }
  ms_afile *streams[CD_NSTREAMS] = {&fe, &fp, &ff};
  if (!rs && root) write_headers(fe.f, fp.f, ff.f); /* a restart writes back the text so far */

  double lo = p->box.lo[axis], hi = p->box.hi[axis];
  if (p->box.bc[axis] != CD_BC_PERIODIC) { /* free axis: the extent may grow; pad by 50 % */
    double L = hi - lo;
    hi += 0.5 * L;
  }
  double area = 1.0; /* of the box at the start (a relaxation may have rescaled it) */
  for (int a = 0; a < p->dim; a++)
    if (a != axis) area *= s->box.hi[a] - s->box.lo[a];
  if (p->dim == 2) area *= p->thickness;
  double *prof = ms_calloc((size_t)p->profile_bins * CD_PROFILE_NCOL, sizeof *prof);
  const long snap_every = p->snapshots > 0 ? (nsteps + p->snapshots - 1) / p->snapshots : 0;
  const long ckpt_every =
      p->checkpoint_every > 0
          ? p->checkpoint_every
          : (p->checkpoint_time > 0 ? lround(fmax(1.0, p->checkpoint_time / cfg.dt)) : 0);
  double front[2 * CD_MAX_FRONT]; /* (t, z) of the front fit */
  int nf = 0;
  long step0 = 0;
  if (rs) {
    step0 = cd_restart_step(rs);
    st = restore_outputs(ctx, rh, streams, front, &nf);
    cd_restart_destroy(&rs);
    ms_h5_close_read(rh);
    if (st == MS_OK)
      ms_log(ctx, MS_LOG_INFO, "cluster_dynamics: restarted from %s at step %ld (t = %.9g)",
             ctx->restart, step0, s->t);
  }
  ms_progress prog;
  ms_progress_start(&prog, ctx, "cluster_dynamics", s->t, nsteps * cfg.dt);
  for (long k = step0; k <= nsteps && st == MS_OK; k++) {
    if (k > step0) st = cd_sim_step(s);
    if (st != MS_OK) break;
    if (ms && ms->rebalances > rebalances_logged) {
      rebalances_logged = ms->rebalances;
      ms_log(ctx, MS_LOG_INFO,
             "cluster_dynamics: rebalance at step %ld: imbalance %.3f -> %.3f, "
             "edge cut %ld, %s map",
             ms->rebalance_step, ms->rebalance_before, ms->rebalance_after, ms->partition.edge_cut,
             partition_names[ms->partition.method]);
    }
    if (k > step0 && ckpt_every > 0 && k % ckpt_every == 0) {
      st = write_checkpoint(ctx, p, s, streams, front, nf);
      if (st != MS_OK) break;
    }
    bool out = k % p->out_every == 0 || k == nsteps;
    if (out) {
      cd_energy en;
      cd_sim_energy(s, &en);
      const double vfs = cd_free_surface_velocity(s, axis);
      if (root) write_energy_row(fe.f, s, &en, vfs);
      cd_profile(s, axis, lo, hi, p->profile_bins, area, prof);
      for (int b = 0; b < p->profile_bins; b++) {
        double row[CD_PROFILE_NCOL + 1];
        row[0] = s->t;
        memcpy(row + 1, prof + (size_t)b * CD_PROFILE_NCOL, CD_PROFILE_NCOL * sizeof(double));
        if (row[2] > 0 && root) ms_csv_row(fp.f, CD_PROFILE_NCOL + 1, row);
      }
      if (p->front_u > 0) {
        double z = cd_front_position(prof, p->profile_bins, axis, p->front_u, 0.5);
        double row[2] = {s->t, z};
        if (root && isfinite(z)) ms_csv_row(ff.f, 2, row); /* no row (never NaN) before a front */
        if (isfinite(z) && nf < CD_MAX_FRONT) {
          front[2 * nf] = s->t;
          front[2 * nf++ + 1] = z;
        }
      }
      ms_progress_update(&prog, s->t, k);
      if (ms && k % (10L * p->out_every) == 0)
        ms_log(ctx, MS_LOG_INFO,
               "cluster_dynamics: step %ld: owned max %zu (imbalance %.3f), "
               "ghosts %zu in all",
               k, ms->max_owned, ms->imbalance, ms->total_ghosts);
    }
    if (snap_every && (k % snap_every == 0 || k == nsteps)) {
      char name[64];
      snprintf(name, sizeof name, "cd_snap_%06ld.h5", k);
      char *sp = ms_out_path(ctx, name);
      if (cd_write_snapshot(s, sp) != MS_OK) st = MS_ERR_IO;
      free(sp);
    }
  }
  ms_progress_finish(&prog, s->t, s->step);
  if (st == MS_ERR_UNSTABLE) { /* the guard's finding, the state it found, the series so far */
    if (cd_sim_error(s)[0])    /* on the rank that found it */
      ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: %s", cd_sim_error(s));
    char *sp = ms_out_path(ctx, "cd_snap_unstable.h5");
    if (cd_write_snapshot(s, sp) == MS_OK)
      ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: final state written to cd_snap_unstable.h5");
    free(sp);
  }
  if (nf > 3) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int m = 0;
    for (int k = 0; k < nf; k++) {
      const double tk = front[2 * k], zk = front[2 * k + 1];
      if (tk >= 0.25 * front[2 * (nf - 1)]) {
        sx += tk;
        sy += zk;
        sxx += tk * tk;
        sxy += tk * zk;
        m++;
      }
    }
    if (m > 2)
      ms_log(ctx, MS_LOG_INFO,
             "cluster_dynamics: shock speed D = %.4f km/s (front fit over t >= T/4)",
             (m * sxy - sx * sy) / (m * sxx - sx * sx));
  }
  ms_log(ctx, MS_LOG_INFO,
         "cluster_dynamics: %ld steps, %ld list builds, %ld broken bonds, wall "
         "force %.2f s, lists %.2f s",
         s->step, cd_sim_rebuilds(s), dist ? par_sum_long(s->n_broken_bonds) : s->n_broken_bonds,
         s->wall_time_force, s->wall_time_neigh);
  if (ms) {
    const double xmax = par_max_double(ms->exchange_s), xmin = par_min_double(ms->exchange_s);
    const double recv = par_sum_double(ms->exchanged_doubles);
    ms_log(ctx, MS_LOG_INFO,
           "cluster_dynamics on %d ranks: %ld partitions (%ld rebalances), "
           "imbalance %.3f at the end; migration and ghost exchange %.3f-%.3f s per rank; %.4g "
           "doubles received in all; %ld bonds lost at migrations",
           ms->ranks, ms->partitions, ms->rebalances, ms->imbalance, xmin, xmax, recv,
           par_sum_long(ms->lost_bonds));
  }
  free(prof);
  if ((st == MS_OK || st == MS_ERR_UNSTABLE) && root) { /* unstable: keep the series so far */
    ms_status sc = ms_afile_commit(&fe);
    if (sc == MS_OK) sc = ms_afile_commit(&fp);
    else ms_afile_abort(&fp);
    if (sc == MS_OK) sc = ms_afile_commit(&ff);
    else ms_afile_abort(&ff);
    if (sc != MS_OK) ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: cannot write the CSV files");
    if (st == MS_OK) st = sc;
  } else if (st != MS_OK && st != MS_ERR_UNSTABLE) {
    ms_log(ctx, MS_LOG_ERROR, "cluster_dynamics: stopped at t = %g (%s)", s->t, ms_status_str(st));
    ms_afile_abort(&fe);
    ms_afile_abort(&fp);
    ms_afile_abort(&ff);
  }
  cd_sim_destroy(&s);
  return st;
}
