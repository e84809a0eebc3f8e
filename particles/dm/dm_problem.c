/* dm_problem.c — the deck problem type `discrete_model` (docs/input-dm.md): builds a lattice of
 * particles in a box with per-face boundaries, material layers, initial data of [Sofronov] §5
 * or random velocities (benchmark), an optional spherical displacement source, integrates with
 * a symplectic RKN scheme and compares with the exact solutions where one exists.
 */
#include "dm_impl.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum face_bc { FACE_FREE = 0, FACE_WALL, FACE_SYMMETRY, FACE_FIXED, FACE_PERIODIC };
static const char *const face_bc_names[] = {"free", "wall", "symmetry", "fixed", "periodic", NULL};
static const char *const face_keys[6] = {"x_lo", "x_hi", "y_lo", "y_hi", "z_lo", "z_hi"};

enum profile {
  PROF_NONE = 0,
  PROF_ROD_TRIANGLE,
  PROF_ROD_SINE,
  PROF_CONTACT,
  PROF_RANDOM_VELOCITY
};
static const char *const profile_names[] = {
    "none", "rod_triangle", "rod_sine", "contact_harmonic", "random_velocity", NULL};

enum response { RESP_LINEAR = 0, RESP_EOS };
static const char *const response_names[] = {"linear_elastic", "eos", NULL};
static const char *const yield_names[] = {"none", "elastic_plastic", NULL};

typedef struct dm_layer {
  double x_max; /* particles with x < x_max (the last layer takes the rest) */
  double rho, K, G;
  const char *name;
  int response, yield; /* enum response, dm_yield */
  double Y0;           /* yield stress (GPa), elastic_plastic */
  const eos_t *eos;    /* the material's EOS (response eos) */
} dm_layer;

struct dm_problem {
  int dim;
  double h, lo[3], hi[3];
  long ncell[3];
  double horizon; /* in spacings */
  int face[6];
  size_t nlayers;
  dm_layer *layers;
  int profile;
  double amplitude, length;
  long mode; /* rod_sine: w = εL sin(mode·πx/2L) */
  long seed;
  int has_source;
  double src_r0, src_w0, src_period;
  int integrator;
  double dt, courant, t_end;
  long steps;
  double hourglass, cond_max;
  double *probes;
  size_t nprobes;
  long probe_every, energy_every;
  double *profile_times;
  size_t nprofile_times;
  double *snapshot_times;
  size_t nsnapshot_times;
  long checkpoint_every; /* steps between checkpoints (0: none) */
  int finite;            /* every layer has response: eos (dm_finite.c) */
  double cq, cl;         /* viscosity coefficients */
  int has_piston;
  double piston_u;    /* km/s along +x */
  long piston_layers; /* x layers of real particles driven */
  dm_run_summary sum;
  double *final_w, *final_u; /* global state at the end of the last run ([n][3]) */
  size_t final_n;
};

const dm_run_summary *dm_problem_summary(const dm_problem *p) { return &p->sum; }

size_t dm_problem_final_state(const dm_problem *p, const double **w, const double **u) {
  if (w) *w = p->final_w;
  if (u) *u = p->final_u;
  return p->final_n;
}

void dm_problem_free(dm_problem *p) {
  if (!p) return;
  free(p->layers);
  free(p->probes);
  free(p->profile_times);
  free(p->snapshot_times);
  free(p->final_w);
  free(p->final_u);
  free(p);
}

static void read_layers(dm_problem *p, dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                        dk_errors *e) {
  const dk_node *L = dk_get(sec, "layers");
  if (!L) {
    dk_error(e, doc, sec, "discrete_model: 'layers' (a list of materials by x range) is required");
    return;
  }
  if (!dk_expect_seq(e, doc, L, "discrete_model.layers")) return;
  p->nlayers = dk_seq_len(L);
  if (p->nlayers == 0) {
    dk_error(e, doc, L, "discrete_model.layers: needs at least one layer");
    return;
  }
  p->layers = ms_calloc(p->nlayers, sizeof *p->layers);
  for (size_t i = 0; i < p->nlayers; ++i) {
    const dk_node *it = dk_seq_at(L, i);
    dm_layer *ly = &p->layers[i];
    if (!dk_expect_map(e, doc, it, "discrete_model.layers[]")) continue;
    ly->x_max = INFINITY; /* absent: the rest of the domain (no default written back) */
    if (dk_get(it, "x_max"))
      dk_read_double(e, doc, it, "x_max", MS_DIM_LENGTH, true, 0, -INFINITY, INFINITY, &ly->x_max);
    const char *mname = NULL;
    if (dk_get(it, "material")) {
      dk_read_string(e, doc, it, "material", true, NULL, &mname);
      const eos_material *m = mname && mats ? eos_materials_find(mats, mname, e, doc, it) : NULL;
      if (m) {
        /* K = ρ0 c0² (c0: the EOS's bulk sound speed at ρ0), G = the material's shear_modulus */
        ly->rho = eos_rho0(m->eos);
        ly->K = ly->rho * eos_c0(m->eos) * eos_c0(m->eos);
        ly->G = m->shear_modulus;
        ly->name = m->name;
        if (!(ly->K > 0))
          dk_error(e, doc, it, "discrete_model.layers: material '%s' has no bulk modulus", mname);
      }
    } else {
      dk_read_positive(e, doc, it, "rho", MS_DIM_DENSITY, true, 0, &ly->rho);
      dk_read_positive(e, doc, it, "bulk_modulus", MS_DIM_PRESSURE, true, 0, &ly->K);
      dk_read_double(e, doc, it, "shear_modulus", MS_DIM_PRESSURE, true, 0, 0, INFINITY, &ly->G);
      ly->name = "direct";
    }
    dk_read_enum(e, doc, it, "response", false, RESP_LINEAR, response_names, &ly->response);
    dk_read_enum(e, doc, it, "yield", false, DM_YIELD_NONE, yield_names, &ly->yield);
    const eos_material *mm = mname && mats && ly->name && strcmp(ly->name, "direct")
                                 ? eos_materials_find(mats, mname, NULL, doc, it)
                                 : NULL;
    if (ly->response == RESP_EOS) {
      if (!mm || !mm->eos)
        dk_error(e, doc, it,
                 "discrete_model.layers: response: eos needs a material with an 'eos:' entry "
                 "(give 'material: NAME')");
      else {
        ly->eos = mm->eos;
        const double r0 = eos_rho0(mm->eos), c0 = eos_sound_speed(mm->eos, r0, eos_e0(mm->eos));
        if (!(c0 > 0) || !isfinite(c0))
          dk_error(e, doc, it, "discrete_model.layers: material '%s' has no sound speed at rho0",
                   mm->name);
      }
    }
    if (ly->yield != DM_YIELD_NONE) {
      if (ly->response != RESP_EOS)
        dk_error(e, doc, it, "discrete_model.layers: 'yield' needs response: eos");
      if (ly->eos && eos_get_kind(ly->eos) == EOS_IDEAL_GAS)
        dk_error(e, doc, it,
                 "discrete_model.layers: a yield model on an ideal gas (material '%s') has no "
                 "meaning",
                 ly->name);
      if (!(ly->G > 0))
        dk_error(e, doc, it,
                 "discrete_model.layers: yield: elastic_plastic needs the material's "
                 "shear_modulus > 0 (GPa), got %g",
                 ly->G);
      if (!dk_get(it, "yield_stress"))
        dk_error(e, doc, it, "discrete_model.layers: yield: elastic_plastic needs 'yield_stress'");
      else dk_read_positive(e, doc, it, "yield_stress", MS_DIM_PRESSURE, true, 0, &ly->Y0);
    } else if (dk_get(it, "yield_stress")) {
      dk_error(e, doc, it, "discrete_model.layers: 'yield_stress' needs yield: elastic_plastic");
    }
  }
}

dm_problem *dm_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                            dk_errors *e) {
  dm_problem *p = ms_calloc(1, sizeof *p);
  size_t nerr0 = e->n;
  long dim = 1;
  dk_read_int(e, doc, sec, "dimension", false, 1, 1, 3, &dim);
  p->dim = (int)dim;
  dk_read_positive(e, doc, sec, "spacing", MS_DIM_LENGTH, true, 0, &p->h);
  dk_read_double(e, doc, sec, "horizon", MS_DIM_NONE, false, 1.5, 1.0, 10.0, &p->horizon);
  const dk_node *dom = dk_get(sec, "domain");
  if (!dom) dk_error(e, doc, sec, "discrete_model: 'domain' with 'lo' and 'hi' lists is required");
  else if (dk_expect_map(e, doc, dom, "discrete_model.domain")) {
    double *lo = NULL, *hi = NULL;
    size_t nlo = 0, nhi = 0;
    bool ok = dk_read_double_list(e, doc, dom, "lo", MS_DIM_LENGTH, true, &lo, &nlo);
    ok = dk_read_double_list(e, doc, dom, "hi", MS_DIM_LENGTH, true, &hi, &nhi) && ok;
    if (ok && (nlo != (size_t)p->dim || nhi != (size_t)p->dim))
      dk_error(e, doc, dom, "discrete_model.domain: lo and hi need %d values (the dimension)",
               p->dim);
    else if (ok && p->h > 0) {
      for (int a = 0; a < p->dim; ++a) {
        p->lo[a] = lo[a], p->hi[a] = hi[a];
        double nc = (hi[a] - lo[a]) / p->h;
        p->ncell[a] = lround(nc);
        if (!(hi[a] > lo[a]) || fabs(nc - p->ncell[a]) > 1e-6 * fmax(1.0, nc))
          dk_error(e, doc, dom,
                   "discrete_model.domain: hi - lo along axis %d (%g) must be a positive whole "
                   "number of spacings (%g)",
                   a, hi[a] - lo[a], p->h);
      }
    }
    free(lo);
    free(hi);
  }
  for (int a = p->dim; a < 3; ++a) p->ncell[a] = 1;
  if (e->n ==
      nerr0) { /* refuse what cannot fit before anything is allocated (docs/reliability.md) */
    double n = (double)p->ncell[0] * (double)p->ncell[1] * (double)p->ncell[2];
    /* family members within the horizon δ (in spacings): 2δ, πδ², (4/3)πδ³ in 1, 2, 3 D */
    double d = p->horizon, members = p->dim == 1   ? 2 * d
                                     : p->dim == 2 ? M_PI * d * d
                                                   : 4.0 / 3.0 * M_PI * d * d * d;
    /* measured: ~290 MB for 125k particles with 122 members each (bench/dm_peri) */
    ms_mem_estimate m;
    ms_mem_init(&m);
    ms_mem_add(&m, dk_get(sec, "spacing"), "discrete_model particles", n, 400.0 + 16.0 * members);
    ms_mem_check(&m, ms_mem_limit(), 1, 1, e, doc);
    ms_mem_free(&m);
  }
  const dk_node *bnd = dk_get(sec, "boundaries");
  if (bnd && !dk_expect_map(e, doc, bnd, "discrete_model.boundaries")) bnd = NULL;
  for (int f = 0; f < 2 * p->dim; ++f) {
    if (bnd) dk_read_enum(e, doc, bnd, face_keys[f], false, FACE_FREE, face_bc_names, &p->face[f]);
    else p->face[f] = FACE_FREE;
  }
  for (int a = 0; a < p->dim; ++a) {
    int plo = p->face[2 * a] == FACE_PERIODIC, phi = p->face[2 * a + 1] == FACE_PERIODIC;
    if (plo != phi)
      dk_error(e, doc, bnd, "discrete_model.boundaries: axis %d is periodic on one face only", a);
    if (plo && fabs(p->lo[a]) > 0)
      dk_error(e, doc, dom, "discrete_model.domain: a periodic axis must start at lo = 0");
  }
  for (int f = 0; f < 2 * p->dim; ++f)
    if ((p->face[f] == FACE_WALL || p->face[f] == FACE_SYMMETRY) &&
        p->ncell[f / 2] < 2 * (long)ceil(p->horizon - 1e-9))
      dk_error(e, doc, bnd,
               "discrete_model.boundaries.%s: a mirror face needs at least 2 x horizon = %ld "
               "cells across the domain",
               face_keys[f], 2 * (long)ceil(p->horizon - 1e-9));
  read_layers(p, doc, sec, mats, e);

  const dk_node *ini = dk_get(sec, "initial");
  p->profile = PROF_NONE;
  p->mode = 1;
  if (ini && dk_expect_map(e, doc, ini, "discrete_model.initial")) {
    dk_read_enum(e, doc, ini, "profile", true, PROF_NONE, profile_names, &p->profile);
    if (p->profile == PROF_RANDOM_VELOCITY) {
      dk_read_positive(e, doc, ini, "amplitude", MS_DIM_VELOCITY, true, 0, &p->amplitude);
      dk_read_int(e, doc, ini, "seed", false, 12345, 0, LONG_MAX, &p->seed);
    } else if (p->profile != PROF_NONE) {
      dk_read_positive(e, doc, ini, "amplitude", MS_DIM_NONE, true, 0, &p->amplitude);
      dk_read_positive(e, doc, ini, "length", MS_DIM_LENGTH, true, 0, &p->length);
      if (p->profile == PROF_ROD_SINE)
        dk_read_int(e, doc, ini, "mode", false, 1, 1, 100000, &p->mode);
      if (p->dim != 1)
        dk_error(e, doc, ini, "discrete_model.initial: profile '%s' is a 1D (rod) problem",
                 profile_names[p->profile]);
      if (p->profile == PROF_CONTACT && p->nlayers < 2)
        dk_error(e, doc, ini, "discrete_model.initial: contact_harmonic needs two layers");
    }
  }
  const dk_node *src = dk_get(sec, "source");
  if (src && dk_expect_map(e, doc, src, "discrete_model.source")) {
    static const char *const src_types[] = {"sphere", NULL};
    int st = 0;
    dk_read_enum(e, doc, src, "type", true, 0, src_types, &st);
    p->has_source = 1;
    dk_read_positive(e, doc, src, "r0", MS_DIM_LENGTH, true, 0, &p->src_r0);
    dk_read_positive(e, doc, src, "w0", MS_DIM_LENGTH, true, 0, &p->src_w0);
    dk_read_positive(e, doc, src, "period", MS_DIM_TIME, true, 0, &p->src_period);
    if (p->dim != 3) dk_error(e, doc, src, "discrete_model.source: the sphere source is 3D");
  }

  dk_read_enum(e, doc, sec, "integrator", false, RKN_VERLET, rkn_scheme_names, &p->integrator);
  const int courant_given = dk_get(sec, "courant") != NULL;
  if (dk_get(sec, "dt")) dk_read_positive(e, doc, sec, "dt", MS_DIM_TIME, true, 0, &p->dt);
  else dk_read_positive(e, doc, sec, "courant", MS_DIM_NONE, false, 0.5, &p->courant);
  if (dk_get(sec, "steps")) dk_read_int(e, doc, sec, "steps", true, 0, 1, LONG_MAX, &p->steps);
  else dk_read_positive(e, doc, sec, "t_end", MS_DIM_TIME, true, 0, &p->t_end);
  /* response: eos on every layer or on none (docs/input-dm.md) */
  size_t neos = 0;
  for (size_t i = 0; i < p->nlayers; ++i) neos += p->layers[i].response == RESP_EOS;
  if (neos && neos != p->nlayers)
    dk_error(e, doc, dk_get(sec, "layers"),
             "discrete_model.layers: response: eos must be given on every layer or on none");
  p->finite = neos > 0 && neos == p->nlayers;
  /* the finite model's defaults: bond penalty on (c_s = 1), courant 0.4 (docs/input-dm.md) */
  dk_read_double(e, doc, sec, "hourglass", MS_DIM_NONE, false, p->finite ? 1.0 : 0.0, 0.0, 100.0,
                 &p->hourglass);
  if (p->finite && !courant_given) p->courant = 0.4;
  if (p->finite && dk_get(sec, "dt"))
    dk_error(e, doc, dk_get(sec, "dt"),
             "discrete_model.dt: response: eos takes its step from the sound speed (give courant)");
  p->cq = 2.0, p->cl = 0.5;
  const dk_node *vis = dk_get(sec, "viscosity");
  if (vis && dk_expect_map(e, doc, vis, "discrete_model.viscosity")) {
    if (!p->finite) dk_error(e, doc, vis, "discrete_model.viscosity: needs response: eos");
    dk_read_double(e, doc, vis, "quadratic", MS_DIM_NONE, false, 2.0, 0.0, 100.0, &p->cq);
    dk_read_double(e, doc, vis, "linear", MS_DIM_NONE, false, 0.5, 0.0, 100.0, &p->cl);
  }
  const dk_node *pis = dk_get(sec, "piston");
  if (pis && dk_expect_map(e, doc, pis, "discrete_model.piston")) {
    if (!p->finite) dk_error(e, doc, pis, "discrete_model.piston: needs response: eos");
    p->has_piston = 1;
    dk_read_double(e, doc, pis, "velocity", MS_DIM_VELOCITY, true, 0, -INFINITY, INFINITY,
                   &p->piston_u);
    dk_read_int(e, doc, pis, "layers", false, 2, 1, LONG_MAX, &p->piston_layers);
    if (p->piston_layers >= p->ncell[0])
      dk_error(e, doc, pis,
               "discrete_model.piston: layers (%ld) must be fewer than the %ld x cells",
               p->piston_layers, p->ncell[0]);
  }
  if (p->finite) {
    for (int f = 0; f < 2 * p->dim; ++f)
      if (p->face[f] == FACE_WALL || p->face[f] == FACE_SYMMETRY)
        dk_error(e, doc, bnd ? bnd : sec,
                 "discrete_model.boundaries.%s: response: eos takes free, fixed or periodic "
                 "faces (wall and symmetry ghosts are not implemented for it)",
                 face_keys[f]);
    if (p->profile != PROF_NONE && p->profile != PROF_RANDOM_VELOCITY)
      dk_error(e, doc, ini ? ini : sec,
               "discrete_model.initial: response: eos takes profile none or random_velocity");
    if (p->has_source) dk_error(e, doc, src, "discrete_model.source: not with response: eos");
  }
  dk_read_double(e, doc, sec, "cond_max", MS_DIM_NONE, false, 1e8, 1.0, 1e16, &p->cond_max);

  const dk_node *out = dk_get(sec, "output");
  p->probe_every = 1;
  p->energy_every = 100;
  if (out && dk_expect_map(e, doc, out, "discrete_model.output")) {
    if (dk_get(out, "probes"))
      dk_read_double_list(e, doc, out, "probes", MS_DIM_LENGTH, true, &p->probes, &p->nprobes);
    dk_read_int(e, doc, out, "probe_every", false, 1, 1, LONG_MAX, &p->probe_every);
    dk_read_int(e, doc, out, "energy_every", false, 100, 1, LONG_MAX, &p->energy_every);
    dk_read_int(e, doc, out, "checkpoint_every", false, 0, 0, LONG_MAX, &p->checkpoint_every);
    if (dk_get(out, "profile_times"))
      dk_read_double_list(e, doc, out, "profile_times", MS_DIM_TIME, true, &p->profile_times,
                          &p->nprofile_times);
    if (dk_get(out, "snapshot_times"))
      dk_read_double_list(e, doc, out, "snapshot_times", MS_DIM_TIME, true, &p->snapshot_times,
                          &p->nsnapshot_times);
  }
  if (p->finite && p->checkpoint_every > 0)
    dk_error(e, doc, out, "discrete_model.output.checkpoint_every: not with response: eos yet");
  if (e->n > nerr0) {
    dm_problem_free(p);
    return NULL;
  }
  return p;
}

/* ------------------------------------------------------------------------------------------ */
/* Set-up                                                                                      */

static const dm_layer *layer_at(const dm_problem *p, double x) {
  for (size_t i = 0; i + 1 < p->nlayers; ++i)
    if (x < p->layers[i].x_max) return &p->layers[i];
  return &p->layers[p->nlayers - 1];
}

/* Thickness (cells) of the particle layer added outside a face. */
static long face_layers(const dm_problem *p, int f) {
  long hz = (long)ceil(p->horizon - 1e-9);
  switch (p->face[f]) {
  case FACE_WALL:
  case FACE_SYMMETRY:
    return 2 * hz; /* ghosts next to the wall need complete families */
  case FACE_FIXED:
    return hz;
  default:
    return 0;
  }
}

/* Builds the particles: real ones first in lattice order (x fastest), then fixed layers and
 * mirror ghosts. */
static void build_particles(dm_problem *p, dm_state *s) {
  long ext_lo[3] = {0, 0, 0}, ext_hi[3] = {0, 0, 0};
  size_t nreal = 1, ntot = 1;
  for (int a = 0; a < 3; ++a) {
    if (a < p->dim) ext_lo[a] = face_layers(p, 2 * a), ext_hi[a] = face_layers(p, 2 * a + 1);
    nreal *= (size_t)p->ncell[a];
    ntot *= (size_t)(p->ncell[a] + ext_lo[a] + ext_hi[a]);
  }
  /* Arrays sized for the whole extended lattice; outside particles are kept only when no
   * face they lie beyond is free. */
  dm_state_alloc(s, ntot, p->dim);
  size_t next = nreal;
  for (long k = -ext_lo[2]; k < p->ncell[2] + ext_hi[2]; ++k)
    for (long j = -ext_lo[1]; j < p->ncell[1] + ext_hi[1]; ++j)
      for (long i = -ext_lo[0]; i < p->ncell[0] + ext_hi[0]; ++i) {
        long idx[3] = {i, j, k}, mir[3] = {i, j, k};
        int outside = 0, skip = 0, fixed = 0;
        int8_t sign[3] = {1, 1, 1};
        for (int a = 0; a < p->dim; ++a) {
          int f = -1;
          if (idx[a] < 0) f = 2 * a, mir[a] = -1 - idx[a];
          if (idx[a] >= p->ncell[a]) f = 2 * a + 1, mir[a] = 2 * p->ncell[a] - 1 - idx[a];
          if (f < 0) continue;
          outside = 1;
          if (p->face[f] == FACE_FIXED) fixed = 1;
          else if (p->face[f] == FACE_WALL)
            for (int c = 0; c < 3; ++c) sign[c] = (int8_t)-sign[c];
          else if (p->face[f] == FACE_SYMMETRY) sign[a] = (int8_t)-sign[a];
          else skip = 1;
        }
        if (skip) continue;
        size_t id;
        if (!outside) {
          id = (size_t)i + (size_t)p->ncell[0] * ((size_t)j + (size_t)p->ncell[1] * (size_t)k);
        } else {
          id = next++;
          if (fixed) {
            s->bc[id] = DM_FIXED;
          } else {
            s->bc[id] = DM_MIRROR;
            s->partner[id] = (uint32_t)((size_t)mir[0] + (size_t)p->ncell[0] *
                                                             ((size_t)mir[1] + (size_t)p->ncell[1] *
                                                                                   (size_t)mir[2]));
            for (int c = 0; c < 3; ++c) s->msign[3 * id + c] = c < p->dim ? sign[c] : 1;
          }
        }
        for (int a = 0; a < p->dim; ++a) s->X[3 * id + a] = p->lo[a] + (idx[a] + 0.5) * p->h;
        /* material: by x of the particle (of its mirror partner for ghosts) */
        double xm = p->lo[0] + (mir[0] + 0.5) * p->h;
        const dm_layer *ly = layer_at(p, outside && !fixed ? xm : s->X[3 * id]);
        s->vol[id] = pow(p->h, p->dim);
        s->mass[id] = ly->rho * s->vol[id];
        s->K[id] = ly->K;
        s->G[id] = ly->G;
      }
  s->n = next; /* arrays are longer than needed when faces are free: harmless */
}

static double rod_wave_speed(const dm_problem *p) {
  const dm_layer *l = &p->layers[0];
  return sqrt((l->K + 4.0 * l->G / 3.0) / l->rho);
}

static void set_initial(dm_problem *p, dm_state *s, size_t nreal) {
  const double L = p->length, eps = p->amplitude;
  uint64_t rng_k = 0; /* the next output of the generator started from p->seed */
  for (size_t i = 0; i < nreal; ++i) {
    double x = s->X[3 * i];
    switch (p->profile) {
    case PROF_ROD_TRIANGLE:
      s->w[3 * i] = dm_exact_rod_triangle(x, 0.0, L, eps, 1.0, 0);
      break;
    case PROF_ROD_SINE:
      s->w[3 * i] = eps * L * sin(p->mode * M_PI * x / (2.0 * L));
      break;
    case PROF_CONTACT:
      s->w[3 * i] = x < L ? eps * sin(8.0 * M_PI * x / L) : 0.0;
      break;
    case PROF_RANDOM_VELOCITY: /* as bench/lammps/gen_inputs.py: u = A(2ξ − 1), ξ the (3i+c)-th */
      for (int c = 0; c < 3; ++c)
        s->u[3 * i + c] =
            p->amplitude * (2.0 * ptl_splitmix64_uniform((uint64_t)p->seed, rng_k++) - 1.0);
      break;
    default:
      break;
    }
  }
  if (p->profile == PROF_RANDOM_VELOCITY) {
    double mean[3] = {0, 0, 0};
    for (size_t i = 0; i < nreal; ++i)
      for (int c = 0; c < 3; ++c) mean[c] += s->u[3 * i + c] / (double)nreal;
    for (size_t i = 0; i < nreal; ++i)
      for (int c = 0; c < 3; ++c) s->u[3 * i + c] = c < p->dim ? s->u[3 * i + c] - mean[c] : 0.0;
  }
}

static void sphere_prescribe(void *user, size_t i, const double X[3], double t, double w[3]) {
  (void)i;
  const dm_problem *p = user;
  const dm_layer *l = &p->layers[0];
  double cl = sqrt((l->K + 4.0 * l->G / 3.0) / l->rho);
  double r = sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]), wr, ur;
  dm_exact_sphere(r, t, p->src_r0, p->src_w0, p->src_period, cl, &wr, &ur);
  for (int a = 0; a < 3; ++a) w[a] = X[a] / r * wr;
}

/* Largest eigenvalue of the symmetric tridiagonal matrix (α, β) by Sturm-sequence bisection. */
static double tridiag_max_eig(const double *al, const double *be, int k) {
  double lo = INFINITY, hi = -INFINITY;
  for (int j = 0; j < k; ++j) { /* Gershgorin interval */
    double r = (j > 0 ? fabs(be[j - 1]) : 0) + (j + 1 < k ? fabs(be[j]) : 0);
    lo = fmin(lo, al[j] - r);
    hi = fmax(hi, al[j] + r);
  }
  for (int it = 0; it < 200 && hi - lo > 1e-14 * fabs(hi); ++it) {
    double x = 0.5 * (lo + hi), d = 1.0;
    int above = 0; /* eigenvalues > x = sign changes... count of negative pivots of T − xI */
    for (int j = 0; j < k; ++j) {
      d = al[j] - x - (j > 0 ? be[j - 1] * be[j - 1] / d : 0.0);
      if (d == 0.0) d = 1e-300;
      if (d < 0) ++above;
    }
    if (above == k) /* every eigenvalue below x */
      hi = x;
    else lo = x;
  }
  return hi;
}

/* ω_max of the free particles: Lanczos on M⁻¹K (self-adjoint in the mass inner product) with
 * ghosts following their partners and fixed/prescribed particles held at 0. 40 iterations give
 * the top of the spectrum to well under 1 % on the lattices used here (it converges from
 * below; the run refuses ω_max Δt > 0.99 × the scheme's stability limit).
 * Runs on the distributed model (dot products in global particle order: the same bits on any
 * rank count). */
static double omega_max(dm_dist *d, const dm_state *gs) {
  const int kmax = 40;
  dm_state *s = dm_dist_state(d);
  dm_model *lm = dm_dist_model(d);
  const size_t n = s->n ? s->n : 1; /* local particles (owned + ghosts) */
  double *q = calloc(3 * n, sizeof(double)), *qp = calloc(3 * n, sizeof(double));
  double *z = calloc(3 * n, sizeof(double)), *work = calloc(3 * n, sizeof(double));
  double al[64], be[64];
  { /* the start vector in global particle order, the same for every rank count */
    double *g = calloc(3 * gs->n, sizeof(double));
    uint64_t rng_k = 0; /* the generator started from seed 7 */
    for (size_t i = 0; i < gs->n; ++i)
      for (int c = 0; c < 3; ++c)
        g[3 * i + c] = (gs->bc[i] == DM_FREE && c < gs->dim)
                           ? 2.0 * ptl_splitmix64_uniform(7, rng_k++) - 1.0
                           : 0.0;
    dm_dist_scatter(d, g, 3, q);
    free(g);
  }
  double nrm = sqrt(dm_dist_mass_dot(d, q, q));
  for (size_t i = 0; i < 3 * n; ++i) q[i] /= nrm;
  dm_prescribe_fn saved = lm->prescribe;
  lm->prescribe = NULL;
  int k = 0;
  double beta_prev = 0.0;
  for (; k < kmax && nrm > 0; ++k) {
    memcpy(work, q, 3 * n * sizeof(double));
    dm_dist_constrain(d, 0.0, work, NULL); /* ghosts mirror their partners; ghost values */
    dm_dist_accel(d, 0.0, work, z);        /* z = −M⁻¹K q on free particles, 0 elsewhere */
    for (size_t i = 0; i < 3 * n; ++i) z[i] = -z[i];
    double a = dm_dist_mass_dot(d, q, z);
    al[k] = a;
    for (size_t i = 0; i < 3 * n; ++i) z[i] -= a * q[i] + beta_prev * qp[i];
    double b = sqrt(dm_dist_mass_dot(d, z, z));
    be[k] = b;
    if (!(b > 1e-12 * fabs(a))) {
      ++k;
      break;
    }
    for (size_t i = 0; i < 3 * n; ++i) qp[i] = q[i], q[i] = z[i] / b;
    beta_prev = b;
  }
  lm->prescribe = saved;
  double lam = k > 0 ? tridiag_max_eig(al, be, k) : 0.0;
  free(q);
  free(qp);
  free(z);
  free(work);
  return sqrt(fmax(lam, 0.0));
}

/* ------------------------------------------------------------------------------------------ */
/* Run                                                                                         */

typedef struct probe_rec {
  size_t particle;
  double x;
} probe_rec;

static void write_profile(const ms_ctx *ctx, const dm_problem *p, dm_model *m, size_t nreal,
                          double t, int index) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  const dm_state *s = m->s;
  char name[64];
  snprintf(name, sizeof name, "dm_profile_%03d.csv", index);
  char *path = ms_out_path(ctx, name);
  ms_afile af;
  if (ms_afile_open(&af, path) != MS_OK) {
    free(path);
    return;
  }
  double *S = malloc(9 * s->n * sizeof(double));
  dm_cauchy_stress(m, S);
  const char *names[] = {"x",   "y",   "z",   "w_x",      "w_y",       "w_z",
                         "u_x", "u_y", "u_z", "sigma_xx", "cauchy_xx", "exact"};
  const char *units[] = {"cm",   "cm",   "cm",   "cm",  "cm",  "cm",
                         "km/s", "km/s", "km/s", "GPa", "GPa", "GPa or cm"};
  char title[160];
  snprintf(title, sizeof title,
           "discrete model profile at t = %.9g (10 us); exact = sigma_xx (contact) or w_x (rod) "
           "where known, else 0",
           t);
  ms_csv_header(af.f, title, 12, names, units);
  for (size_t i = 0; i < nreal; ++i) {
    const double *X = &s->X[3 * i];
    if (p->dim == 3 && fabs(X[2] - (p->lo[2] + 0.5 * p->h)) > 1e-9 * p->h) continue;
    double ex = 0.0;
    const dm_layer *l0 = &p->layers[0];
    if (p->profile == PROF_CONTACT && p->nlayers >= 2) {
      const dm_layer *l1 = &p->layers[1];
      ex = dm_exact_contact_stress(X[0], t, p->length, p->amplitude, l0->rho, l0->K + 4 * l0->G / 3,
                                   l1->rho, l1->K + 4 * l1->G / 3);
    } else if (p->profile == PROF_ROD_TRIANGLE) {
      ex = dm_exact_rod_triangle(X[0], t, p->length, p->amplitude, rod_wave_speed(p), 0);
    } else if (p->profile == PROF_ROD_SINE) {
      double c = rod_wave_speed(p), L = p->length;
      ex = p->amplitude * L * sin(p->mode * M_PI * X[0] / (2 * L)) *
           cos(p->mode * M_PI * c * t / (2 * L));
    }
    double row[12] = {X[0],
                      X[1],
                      X[2],
                      s->w[3 * i],
                      s->w[3 * i + 1],
                      s->w[3 * i + 2],
                      s->u[3 * i],
                      s->u[3 * i + 1],
                      s->u[3 * i + 2],
                      m->sigma[9 * i],
                      S[9 * i],
                      ex};
    ms_csv_row(af.f, 12, row);
  }
  free(S);
  ms_afile_commit(&af);
  free(path);
}

/* HDF5 snapshot of the real particles with an XDMF sidecar (ParaView): current positions
 * X + w, reference positions, w, u, |u|, Cauchy stress (9 components) and its pressure
 * −tr Σ/3, von Mises intensity and Σ_xx. */
static void write_snapshot(const ms_ctx *ctx, dm_model *m, size_t nreal, double t, long step,
                           const char *name) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  const dm_state *s = m->s;
  char *path = ms_out_path(ctx, name);
  double *S = malloc(9 * s->n * sizeof(double));
  double *x = malloc(3 * nreal * sizeof(double)), *sc = malloc(4 * nreal * sizeof(double));
  dm_cauchy_stress(m, S);
  double *speed = sc, *pres = sc + nreal, *vm = sc + 2 * nreal, *sxx = sc + 3 * nreal;
  for (size_t i = 0; i < nreal; ++i) {
    const double *u = &s->u[3 * i], *T = &S[9 * i];
    for (int a = 0; a < 3; ++a) x[3 * i + a] = s->X[3 * i + a] + s->w[3 * i + a];
    speed[i] = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    pres[i] = -(T[0] + T[4] + T[8]) / 3.0;
    double s12 = 0.5 * (T[1] + T[3]), s23 = 0.5 * (T[5] + T[7]), s31 = 0.5 * (T[2] + T[6]);
    vm[i] = sqrt(0.5 * ((T[0] - T[4]) * (T[0] - T[4]) + (T[4] - T[8]) * (T[4] - T[8]) +
                        (T[8] - T[0]) * (T[8] - T[0]) + 6.0 * (s12 * s12 + s23 * s23 + s31 * s31)));
    sxx[i] = T[0];
  }
  ms_status st = MS_ERR_IO;
  ms_h5 *h = ms_h5_create(path);
  if (h) {
    st = ms_h5_write_doubles(h, "particles/x", nreal, 3, x, "cm");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/X", nreal, 3, s->X, "cm");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/w", nreal, 3, s->w, "cm");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/u", nreal, 3, s->u, "km/s");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/speed", nreal, 1, speed, "km/s");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/cauchy", nreal, 9, S, "GPa");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/pressure", nreal, 1, pres, "GPa");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/von_mises", nreal, 1, vm, "GPa");
    if (st == MS_OK) st = ms_h5_write_doubles(h, "particles/sigma_xx", nreal, 1, sxx, "GPa");
    if (st == MS_OK) st = ms_h5_attr_double(h, "particles", "time", t);
    if (st == MS_OK) st = ms_h5_attr_double(h, "particles", "step", (double)step);
    if (st == MS_OK) st = ms_h5_close(h);
    else ms_h5_abort(h);
  }
  if (st == MS_OK) {
    ms_xdmf_attr attr[] = {{"displacement", "particles/w", 3, false},
                           {"velocity", "particles/u", 3, false},
                           {"speed", "particles/speed", 1, false},
                           {"pressure", "particles/pressure", 1, false},
                           {"von_mises", "particles/von_mises", 1, false},
                           {"sigma_xx", "particles/sigma_xx", 1, false}};
    char xname[64]; /* the sidecar: NAME.h5 -> NAME.xmf */
    snprintf(xname, sizeof xname, "%.*s.xmf", (int)strcspn(name, "."), name);
    char *xmf = ms_out_path(ctx, xname);
    st = ms_xdmf_write_points(xmf, name, "particles/x", nreal, 3, t, 6, attr);
    free(xmf);
  }
  if (st != MS_OK) ms_log(ctx, MS_LOG_WARN, "discrete model: could not write %s", path);
  free(path);
  free(S);
  free(x);
  free(sc);
}

static void write_sphere_radial(const ms_ctx *ctx, const dm_problem *p, const dm_state *s,
                                size_t nreal, double t) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  char *path = ms_out_path(ctx, "dm_sphere_radial.csv");
  ms_afile af;
  if (ms_afile_open(&af, path) != MS_OK) {
    free(path);
    return;
  }
  const char *names[] = {"r", "w_r", "u_r", "w_exact", "u_exact"};
  const char *units[] = {"cm", "cm", "km/s", "cm", "km/s"};
  char title[128];
  snprintf(title, sizeof title, "spherical wave, all free particles, t = %.9g (10 us)", t);
  ms_csv_header(af.f, title, 5, names, units);
  const dm_layer *l = &p->layers[0];
  double cl = sqrt((l->K + 4.0 * l->G / 3.0) / l->rho);
  size_t stride = nreal > 400000 ? nreal / 400000 + 1 : 1; /* keep the file < ~40 MB */
  for (size_t i = 0; i < nreal; i += stride) {
    if (s->bc[i] != DM_FREE) continue;
    const double *X = &s->X[3 * i];
    double r = sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
    double wr = (s->w[3 * i] * X[0] + s->w[3 * i + 1] * X[1] + s->w[3 * i + 2] * X[2]) / r;
    double ur = (s->u[3 * i] * X[0] + s->u[3 * i + 1] * X[1] + s->u[3 * i + 2] * X[2]) / r;
    double we, ue;
    dm_exact_sphere(r, t, p->src_r0, p->src_w0, p->src_period, cl, &we, &ue);
    double row[5] = {r, wr, ur, we, ue};
    ms_csv_row(af.f, 5, row);
  }
  ms_afile_commit(&af);
  free(path);
}

static ms_status write_series(const ms_ctx *ctx, const char *file, const char *title, size_t ncol,
                              const char *const *names, const char *const *units,
                              const double *data, size_t nrow) {
  if (!ctx->outdir || !ctx->outdir[0]) return MS_OK;
  char *path = ms_out_path(ctx, file);
  ms_afile af;
  ms_status st = ms_afile_open(&af, path);
  free(path);
  if (st != MS_OK) return st;
  ms_csv_header(af.f, title, ncol, names, units);
  for (size_t r = 0; r < nrow; ++r) ms_csv_row(af.f, ncol, &data[r * ncol]);
  return ms_afile_commit(&af);
}

/* Exact rod displacement at the probe. */
static double rod_exact(const dm_problem *p, double x, double t) {
  const double c = rod_wave_speed(p), L = p->length;
  if (p->profile == PROF_ROD_TRIANGLE) return dm_exact_rod_triangle(x, t, L, p->amplitude, c, 0);
  return p->amplitude * L * sin(p->mode * M_PI * x / (2 * L)) *
         cos(p->mode * M_PI * c * t / (2 * L));
}

/* Residual of the fit w(t) ≈ A·w_exact(t − s) over the window for a given lag s (A optimal);
 * returns the residual and A. */
static double lag_fit(const dm_problem *p, const double *hist, size_t first, size_t nrec, double x,
                      double sh, double *A) {
  double ww = 0, we = 0, ee = 0;
  for (size_t r = first; r < nrec; ++r) {
    double w = hist[2 * r + 1], ex = rod_exact(p, x, hist[2 * r] - sh);
    ww += w * w, we += w * ex, ee += ex * ex;
  }
  *A = ee > 0 ? we / ee : 0.0;
  return ww - (ee > 0 ? we * we / ee : 0.0);
}

/* Rod, over the last 10 L/c of the probe history:
 *   amplitude error = A − 1 and phase error = s (units of L/c; > 0: the computed wave lags)
 *   from the least-squares fit w(t) ≈ A·w_exact(t − s), which measures loss or gain of
 *   amplitude (the cross scheme's ~5× loss at 200 cells) independently of the dispersive
 *   ringing near the kinks of the triangle wave;
 *   peak error = (max|w| − max|w_exact|)/max|w_exact|, which includes that ringing;
 *   rms error = rms(w − w_exact)/max|w_exact| without any fit. */
static void rod_analysis(dm_problem *p, const double *hist, size_t nrec, double xprobe) {
  const double c = rod_wave_speed(p), L = p->length, t0 = p->sum.t_end - 10.0 * L / c;
  double amax = 0, emax = 0, se = 0;
  size_t cnt = 0, first = nrec;
  for (size_t r = 0; r < nrec; ++r) {
    double t = hist[2 * r];
    if (t < t0 - 1e-12) continue;
    if (first == nrec) first = r;
    double ex = rod_exact(p, xprobe, t);
    amax = fmax(amax, fabs(hist[2 * r + 1]));
    emax = fmax(emax, fabs(ex));
    se += (hist[2 * r + 1] - ex) * (hist[2 * r + 1] - ex);
    ++cnt;
  }
  if (!cnt || !(emax > 0)) return;
  p->sum.peak_err = (amax - emax) / emax;
  p->sum.rms_err = sqrt(se / cnt) / emax;
  /* lag: coarse scan of |s| ≤ L/c, then golden-section refinement */
  double best = 0, bestv = INFINITY, A;
  const double smax = L / c;
  const int ncoarse = 400;
  for (int k = -ncoarse; k <= ncoarse; ++k) {
    double sh = smax * k / ncoarse, v = lag_fit(p, hist, first, nrec, xprobe, sh, &A);
    if (v < bestv) bestv = v, best = sh;
  }
  double a = best - smax / ncoarse, b = best + smax / ncoarse;
  for (int it = 0; it < 50; ++it) {
    double m1 = a + 0.381966 * (b - a), m2 = a + 0.618034 * (b - a);
    if (lag_fit(p, hist, first, nrec, xprobe, m1, &A) <
        lag_fit(p, hist, first, nrec, xprobe, m2, &A))
      b = m2;
    else a = m1;
  }
  double sh = 0.5 * (a + b);
  lag_fit(p, hist, first, nrec, xprobe, sh, &A);
  p->sum.amp_err = A - 1.0;
  p->sum.phase_err = sh * c / L;
}

/* Instability guard report (docs/reliability.md §5): step `step` failed (rkn_step met a
 * non-finite acceleration and left the state at the step's start, time t). Names the first
 * particle whose displacement, velocity or acceleration at that state is not finite (each rank
 * looks at the particles it owns: dm_dist_accel is the integrator's own, collective force
 * call), and rank 0 writes the gathered state (m->s) as dm_snapshot_unstable.h5. */
static void report_unstable(const ms_ctx *ctx, const ms_ctx *octx, dm_model *m, dm_dist *d,
                            const dm_state *ls, size_t nreal, long step, double t) {
  const dm_state *s = m->s;
  double *acc = ms_calloc(3 * ls->n + 1, sizeof *acc);
  dm_dist_accel(d, t, ls->w, acc); /* its status is the finding itself */
  const double *field[3] = {ls->w, ls->u, acc};
  static const char *const fname[3] = {"displacement w", "velocity u", "acceleration"};
  char what[200] = "";
  for (int f = 0; f < 3 && !what[0]; f++)
    for (size_t i = 0; i < nreal && !what[0]; i++) {
      long l = dm_dist_local_index(d, i);
      for (int a = 0; l >= 0 && a < 3 && !what[0]; a++)
        if (!isfinite(field[f][3 * l + a]))
          snprintf(what, sizeof what, "particle %zu (at %g, %g, %g): non-finite %s_%c = %g", i,
                   s->X[3 * i], s->X[3 * i + 1], s->X[3 * i + 2], fname[f], "xyz"[a],
                   field[f][3 * l + a]);
    }
  free(acc);
  if (what[0] || ctx->rank == 0)
    ms_log(ctx, MS_LOG_ERROR, "discrete model: unstable at step %ld, t = %.9g: %s", step + 1, t,
           what[0] ? what
                   : "non-finite acceleration in a stage of the step (the state at its "
                     "start is finite)");
  if (ctx->rank == 0) {
    write_snapshot(octx, m, nreal, t, step, "dm_snapshot_unstable.h5");
    ms_log(ctx, MS_LOG_ERROR, "discrete model: final state written to dm_snapshot_unstable.h5");
  }
}

static void contact_analysis(dm_problem *p, const dm_model *m, size_t nreal, double t) {
  const dm_layer *l0 = &p->layers[0], *l1 = &p->layers[1];
  double smax = 0, s1 = 0, s2 = 0, sinf = 0;
  for (size_t i = 0; i < nreal; ++i) {
    double x = m->s->X[3 * i];
    double ex = dm_exact_contact_stress(x, t, p->length, p->amplitude, l0->rho,
                                        l0->K + 4 * l0->G / 3, l1->rho, l1->K + 4 * l1->G / 3);
    double d = m->sigma[9 * i] - ex;
    smax = fmax(smax, fabs(ex));
    s1 += fabs(d);
    s2 += d * d;
    sinf = fmax(sinf, fabs(d));
  }
  p->sum.err_l1 = s1 / nreal / smax;
  p->sum.err_l2 = sqrt(s2 / nreal) / smax;
  p->sum.err_max = sinf / smax;
}

static void sphere_analysis(dm_problem *p, const dm_state *s, size_t nreal, double t) {
  const dm_layer *l = &p->layers[0];
  double cl = sqrt((l->K + 4.0 * l->G / 3.0) / l->rho);
  double s1 = 0, s2 = 0, sinf = 0, su = 0, wmax = 0;
  size_t cnt = 0;
  for (size_t i = 0; i < nreal; ++i) {
    if (s->bc[i] != DM_FREE) continue;
    const double *X = &s->X[3 * i];
    double r = sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
    if (r > p->src_r0 + cl * t) continue; /* ahead of the front: both zero */
    double wr = (s->w[3 * i] * X[0] + s->w[3 * i + 1] * X[1] + s->w[3 * i + 2] * X[2]) / r;
    double ur = (s->u[3 * i] * X[0] + s->u[3 * i + 1] * X[1] + s->u[3 * i + 2] * X[2]) / r;
    double we, ue;
    dm_exact_sphere(r, t, p->src_r0, p->src_w0, p->src_period, cl, &we, &ue);
    wmax = fmax(wmax, fabs(we));
    s1 += fabs(wr - we);
    s2 += (wr - we) * (wr - we);
    sinf = fmax(sinf, fabs(wr - we));
    su += (ur - ue) * (ur - ue);
    ++cnt;
  }
  if (!cnt) return;
  double u0 = p->src_w0 * 2.0 * M_PI / p->src_period;
  p->sum.err_l1 = s1 / cnt / wmax;
  p->sum.err_l2 = sqrt(s2 / cnt) / wmax;
  p->sum.err_max = sinf / wmax;
  p->sum.err_u_l2 = sqrt(su / cnt) / u0;
}

/* ------------------------------------------------------------------------------------------ */
/* Checkpoint / restart (docs/mpi.md)                                                          */

/* What a run needs to continue bit for bit: the global state in particle order (the same file
 * for every rank count) and the diagnostics recorded so far. */
typedef struct dm_checkpoint_data {
  long step;
  double E0, dw_scale, energy_err_max;
  double *hist, *ehist; /* the run's arrays (not owned) */
  size_t pcols, nrec, nerec, nrec_max, nerec_max;
} dm_checkpoint_data;

/* OUTDIR/dm_checkpoint.h5, written as dm_checkpoint.h5.part and renamed when complete
 * (ms_h5_close): a crash while writing leaves the previous checkpoint intact. Rank 0 only. */
static ms_status write_checkpoint(const ms_ctx *ctx, const dm_state *s, double dt, int ranks,
                                  const dm_checkpoint_data *ck) {
  if (!ctx->outdir || !ctx->outdir[0]) return MS_OK;
  char *path = ms_out_path(ctx, "dm_checkpoint.h5");
  ms_h5 *h = ms_h5_create(path);
  ms_status st = h ? MS_OK : MS_ERR_IO;
  if (st == MS_OK) st = ms_h5_write_doubles(h, "/state/w", s->n, 3, s->w, "cm");
  if (st == MS_OK) st = ms_h5_write_doubles(h, "/state/u", s->n, 3, s->u, "km/s");
  if (st == MS_OK && ck->nrec > 0)
    st = ms_h5_write_doubles(h, "/history/probes", ck->nrec, ck->pcols, ck->hist, "10 us, cm");
  if (st == MS_OK && ck->nerec > 0)
    st = ms_h5_write_doubles(h, "/history/energy", ck->nerec, 5, ck->ehist, "10 us, kJ");
  const char *names[] = {"step", "dt", "particles", "E0", "dw_scale", "energy_err_max", "ranks"};
  double vals[] = {(double)ck->step,   dt,           (double)s->n, ck->E0, ck->dw_scale,
                   ck->energy_err_max, (double)ranks};
  for (int k = 0; k < 7 && st == MS_OK; ++k) st = ms_h5_attr_double(h, "/", names[k], vals[k]);
  if (st == MS_OK) st = ms_h5_attr_string(h, "/", "format", "mscale discrete_model checkpoint 1");
  if (h) {
    if (st == MS_OK) st = ms_h5_close(h);
    else ms_h5_abort(h);
  }
  if (st == MS_OK)
    ms_log(ctx, MS_LOG_INFO, "discrete model: checkpoint at step %ld written to %s", ck->step,
           path);
  else ms_log(ctx, MS_LOG_ERROR, "discrete model: cannot write the checkpoint %s", path);
  free(path);
  return st;
}

static ms_status read_rows(ms_h5r *h, const char *name, size_t ncol, size_t nmax, double *dst,
                           size_t *nrow, dk_errors *e) {
  *nrow = 0;
  if (!ms_h5_exists(h, name)) return MS_OK;
  double *v = NULL;
  size_t n0 = 0, n1 = 0;
  ms_status st = ms_h5_read_doubles(h, name, &v, &n0, &n1, e);
  if (st == MS_OK && (n1 != ncol || n0 > nmax)) {
    dk_error_at(e, "checkpoint", 0, 0, "'%s' has %zu x %zu values, expected at most %zu x %zu",
                name, n0, n1, nmax, ncol);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) memcpy(dst, v, n0 * ncol * sizeof(double)), *nrow = n0;
  free(v);
  return st;
}

/* Every rank reads the checkpoint into the global state s; the deck must describe the same
 * particles and time step (the restart continues the same run). */
static ms_status read_checkpoint(const ms_ctx *ctx, const char *path, dm_state *s, long nsteps,
                                 double dt, dm_checkpoint_data *ck) {
  dk_errors e;
  dk_errors_init(&e);
  ms_status st = MS_ERR_INPUT;
  ms_h5r *h = ms_h5_open_read(path, &e);
  double step = 0, ck_dt = 0, np = 0, E0 = 0, dws = 0, emax = NAN;
  if (h) {
    st = MS_OK;
    if (ms_h5_read_attr_double(h, "/", "step", &step, &e) ||
        ms_h5_read_attr_double(h, "/", "dt", &ck_dt, &e) ||
        ms_h5_read_attr_double(h, "/", "particles", &np, &e) ||
        ms_h5_read_attr_double(h, "/", "E0", &E0, &e) ||
        ms_h5_read_attr_double(h, "/", "dw_scale", &dws, &e) ||
        ms_h5_read_attr_double(h, "/", "energy_err_max", &emax, &e))
      st = MS_ERR_INPUT;
    if (st == MS_OK && ((size_t)np != s->n || ck_dt != dt || step < 0 || step > nsteps)) {
      dk_error_at(&e, path, 0, 0,
                  "checkpoint of %zu particles, dt = %.17g at step %ld does not continue this "
                  "deck (%zu particles, dt = %.17g, %ld steps)",
                  (size_t)np, ck_dt, (long)step, s->n, dt, nsteps);
      st = MS_ERR_INPUT;
    }
    double *v = NULL;
    size_t n0 = 0, n1 = 0;
    for (int k = 0; k < 2 && st == MS_OK; ++k) {
      st = ms_h5_read_doubles(h, k ? "/state/u" : "/state/w", &v, &n0, &n1, &e);
      if (st == MS_OK && (n0 != s->n || n1 != 3)) st = MS_ERR_INPUT;
      if (st == MS_OK) memcpy(k ? s->u : s->w, v, 3 * s->n * sizeof(double));
      free(v);
      v = NULL;
    }
    if (st == MS_OK && ck->hist)
      st = read_rows(h, "/history/probes", ck->pcols, ck->nrec_max, ck->hist, &ck->nrec, &e);
    if (st == MS_OK)
      st = read_rows(h, "/history/energy", 5, ck->nerec_max, ck->ehist, &ck->nerec, &e);
    ms_h5_close_read(h);
  }
  if (st != MS_OK) {
    if (ctx->rank == 0) dk_errors_print(&e, stderr);
    ms_log(ctx, MS_LOG_ERROR, "discrete model: cannot restart from %s", path);
  }
  dk_errors_free(&e);
  ck->step = (long)step, ck->E0 = E0, ck->dw_scale = dws, ck->energy_err_max = emax;
  return st;
}

static double cpu_time(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------------------------------------ */
/* response: eos — the finite-deformation model (dm_finite.c), one rank                        */

/* Layer-averaged profile along x of the real particles (lattice order, x fastest). */
static void write_fin_profile(const ms_ctx *ctx, const dm_problem *p, const dm_fin *f, size_t nreal,
                              double t, int index, double *bins) {
  if (!ctx->outdir || !ctx->outdir[0]) return;
  const long nx = p->ncell[0];
  const int nc = 11;
  memset(bins, 0, (size_t)nx * nc * sizeof(double));
  const dm_state *s = f->m->s;
  for (size_t i = 0; i < nreal; ++i) {
    double *r = &bins[nc * (long)(i % (size_t)nx)];
    const double *sg = &f->sig[9 * i], *sd = &f->s[9 * i];
    double ss = 0;
    for (int a = 0; a < 9; ++a) ss += sd[a] * sd[a];
    double v[11] = {s->X[3 * i], s->X[3 * i] + s->w[3 * i],
                    s->u[3 * i], f->rho[i],
                    f->p[i],     f->q[i],
                    -sg[0],      f->e[i],
                    f->eps_p[i], sqrt(1.5 * ss),
                    f->J[i]};
    for (int c = 0; c < nc; ++c) r[c] += v[c];
  }
  const double per = (double)nreal / (double)nx;
  for (long j = 0; j < nx * nc; ++j) bins[j] /= per;
  char name[64];
  snprintf(name, sizeof name, "dm_fin_profile_%03d.csv", index);
  char title[160];
  snprintf(title, sizeof title,
           "discrete model (response eos) profile along x at t = %.9g (10 us), averaged over each "
           "x layer of particles",
           t);
  const char *nm[] = {"X", "x",     "u_x",     "rho", "p", "q", "minus_sigma_xx",
                      "e", "eps_p", "sigma_u", "J"};
  const char *un[] = {"cm", "cm", "km/s", "g/cm3", "GPa", "GPa", "GPa", "kJ/g", "1", "GPa", "1"};
  write_series(ctx, name, title, nc, nm, un, bins, (size_t)nx);
}

static ms_status run_finite(ms_ctx *ctx, dm_problem *p) {
  dm_run_summary *sum = &p->sum;
  if (ctx->size > 1) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model: response: eos runs on one rank (not distributed)");
    return MS_ERR_INPUT;
  }
  if (ctx->restart) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model: response: eos has no restart yet");
    return MS_ERR_INPUT;
  }
  dm_state s;
  build_particles(p, &s);
  const size_t nreal = (size_t)(p->ncell[0] * p->ncell[1] * p->ncell[2]);
  set_initial(p, &s, nreal);
  if (p->has_piston)
    for (size_t i = 0; i < nreal; ++i)
      if ((long)(i % (size_t)p->ncell[0]) < p->piston_layers) {
        s.bc[i] = DM_PRESCRIBED;
        s.u[3 * i] = p->piston_u, s.u[3 * i + 1] = s.u[3 * i + 2] = 0.0;
      }
  for (size_t i = nreal; i < s.n; ++i) s.u[3 * i] = s.u[3 * i + 1] = s.u[3 * i + 2] = 0.0;
  dm_options opt = {.horizon = p->horizon * p->h, .cond_max = p->cond_max, .hourglass = 0.0};
  for (int a = 0; a < p->dim; ++a)
    if (p->face[2 * a] == FACE_PERIODIC) opt.box[a] = p->hi[a] - p->lo[a];
  ms_status st;
  dm_model *m = dm_create(&s, &opt, ctx, &st, NULL);
  if (!m) {
    dm_state_free(&s);
    return st;
  }
  dm_fin_material *mat = ms_calloc(p->nlayers, sizeof *mat);
  for (size_t l = 0; l < p->nlayers; ++l)
    mat[l] = (dm_fin_material){.eos = p->layers[l].eos,
                               .yield = p->layers[l].yield,
                               .G = p->layers[l].G,
                               .Y0 = p->layers[l].Y0};
  uint8_t *imat = ms_calloc(s.n, 1);
  for (size_t i = 0; i < s.n; ++i) imat[i] = (uint8_t)(layer_at(p, s.X[3 * i]) - p->layers);
  dm_fin_params par = {
      .cq = p->cq, .cl = p->cl, .courant = p->courant, .hourglass = p->hourglass, .ell = p->h};
  dm_fin *f = dm_fin_create(m, mat, imat, &par, &st);
  if (!f) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model (response eos): the initial state is not valid");
    free(mat), free(imat), dm_destroy(m), dm_state_free(&s);
    return st;
  }
  sum->particles = s.n, sum->real_particles = nreal, sum->bonds = m->nbonds, sum->ranks = 1;
  ms_log(ctx, MS_LOG_INFO,
         "discrete model (response eos): %zu particles (%zu real), %zu bonds, dim %d, viscosity "
         "C_q %.3g C_l %.3g, bond penalty c_s %.3g, courant %.3g, first dt %.6g%s",
         s.n, nreal, m->nbonds, p->dim, p->cq, p->cl, p->hourglass, p->courant, f->dt_next,
         p->has_piston ? ", piston" : "");
  const long nx = p->ncell[0];
  double *bins = ms_calloc((size_t)nx * 11, sizeof(double));
  const size_t nemax = 4096;
  double *eh = ms_calloc(nemax * 7, sizeof(double));
  size_t ne = 0;
  char *done = ms_calloc(p->nprofile_times + 1, 1);
  double K, U, H;
  dm_fin_energies(f, &K, &U, &H);
  const double E0 = K + U + H;
  double t = 0.0, dEmax = 0.0, wall = 0.0;
  const double t_end = p->steps > 0 ? INFINITY : p->t_end;
  long every = p->energy_every;
  for (long step = 0;; ++step) {
    dm_fin_energies(f, &K, &U, &H);
    const double bal = K + U + H - f->work - E0;
    dEmax = fmax(dEmax, fabs(bal));
    const int last = (p->steps > 0 && step >= p->steps) || t >= t_end * (1 - 1e-12);
    if ((step % every == 0 || last) && ne < nemax) {
      double row[7] = {t, K, U, H, f->work, bal, 0};
      memcpy(&eh[7 * ne++], row, sizeof row);
    }
    for (size_t q = 0; q < p->nprofile_times; ++q)
      if (!done[q] && (t >= p->profile_times[q] * (1 - 1e-12) || last)) {
        write_fin_profile(ctx, p, f, nreal, t, (int)q, bins);
        done[q] = 1;
      }
    if (last) break;
    if (t + f->dt_next > t_end) f->dt_next = t_end - t;
    const double dt = f->dt_next, w0 = ms_wall_time();
    st = dm_fin_step(f);
    wall += ms_wall_time() - w0;
    t += dt;
    if (st != MS_OK) {
      const double *X = &s.X[3 * f->bad];
      ms_log(ctx, MS_LOG_ERROR,
             "discrete model (response eos): step %ld, t = %.9g: particle %zu (X = %g %g %g): %s "
             "= %g; the run stops (no output of this state)",
             f->step + 1, t, f->bad, X[0], X[1], X[2], f->bad_what, f->bad_value);
      break;
    }
  }
  sum->steps = f->step, sum->t_end = t, sum->wall_s = wall;
  sum->particle_steps_per_s = wall > 0 ? (double)nreal * f->step / wall : 0;
  sum->energy_err_max = f->work != 0 ? dEmax / fabs(f->work) : dEmax / fmax(fabs(E0), 1e-300);
  sum->hourglass_last = f->work != 0 ? H / fabs(f->work) : NAN;
  sum->kinetic_end = K, sum->potential_end = U;
  ms_log(ctx, MS_LOG_INFO,
         "discrete model (response eos): %ld steps to t = %.6g in %.3f s (%.4g particle-steps/s); "
         "energy balance max |K + U + E_hg - W - E0| = %.3g of the piston work %.6g kJ; "
         "bond-penalty energy / work = %.3g",
         f->step, t, wall, sum->particle_steps_per_s, sum->energy_err_max, f->work,
         sum->hourglass_last);
  {
    const char *nm[] = {"t",           "kinetic", "internal", "bond_penalty",
                        "piston_work", "balance", "unused"};
    const char *un[] = {"10 us", "kJ", "kJ", "kJ", "kJ", "kJ", "1"};
    /* rows of 7 written as 6 columns: compact them first */
    for (size_t r = 0; r < ne; ++r) memmove(&eh[6 * r], &eh[7 * r], 6 * sizeof(double));
    write_series(ctx, "dm_fin_energy.csv",
                 "energy history: balance = kinetic + internal + bond_penalty - piston_work - E0",
                 6, nm, un, eh, ne);
  }
  free(bins), free(eh), free(done), free(mat), free(imat);
  dm_fin_free(f);
  dm_destroy(m);
  dm_state_free(&s);
  return st;
}

ms_status dm_problem_run(ms_ctx *ctx, dm_problem *p) {
  dm_run_summary *sum = &p->sum;
  if (p->finite) {
    *sum = (dm_run_summary){0};
    sum->amp_err = sum->phase_err = sum->rms_err = sum->peak_err = NAN;
    sum->err_l1 = sum->err_l2 = sum->err_max = sum->err_u_l2 = NAN;
    sum->hourglass_first = sum->hourglass_max = NAN;
    return run_finite(ctx, p);
  }
  const double nan = NAN;
  *sum = (dm_run_summary){0};
  sum->amp_err = sum->phase_err = sum->rms_err = sum->peak_err = nan;
  sum->err_l1 = sum->err_l2 = sum->err_max = sum->err_u_l2 = nan;
  sum->energy_err_max = sum->hourglass_first = sum->hourglass_max = sum->hourglass_last = nan;

  dm_state s;
  build_particles(p, &s);
  size_t nreal = (size_t)(p->ncell[0] * p->ncell[1] * p->ncell[2]);
  if (p->has_source)
    for (size_t i = 0; i < nreal; ++i) {
      const double *X = &s.X[3 * i];
      if (fmax(fabs(X[0]), fmax(fabs(X[1]), fabs(X[2]))) < p->src_r0) s.bc[i] = DM_PRESCRIBED;
    }
  for (size_t i = nreal; i < s.n; ++i) /* ghosts of source particles follow the source */
    if (s.bc[i] == DM_MIRROR && s.bc[s.partner[i]] == DM_PRESCRIBED) s.bc[i] = DM_PRESCRIBED;
  set_initial(p, &s, nreal);

  dm_options opt = {
      .horizon = p->horizon * p->h, .cond_max = p->cond_max, .hourglass = p->hourglass};
  for (int a = 0; a < p->dim; ++a)
    if (p->face[2 * a] == FACE_PERIODIC) opt.box[a] = p->hi[a] - p->lo[a];
  ms_status st;
  dm_model *m = dm_create(&s, &opt, ctx, &st, NULL);
  if (!m) {
    dm_state_free(&s);
    return st;
  }
  if (p->has_source) {
    m->prescribe = sphere_prescribe;
    m->prescribe_user = p;
  }
  sum->particles = s.n;
  sum->real_particles = nreal;
  sum->bonds = m->nbonds;
  dm_constrain(m, 0.0, s.w, s.u);

  /* Time step: given, or courant · h / c_max; checked against the scheme's stability limit. */
  double cmax = 0;
  for (size_t i = 0; i < nreal; ++i)
    cmax = fmax(cmax, sqrt((s.K[i] + 4.0 * s.G[i] / 3.0) * s.vol[i] / s.mass[i]));
  double dt = p->dt > 0 ? p->dt : p->courant * p->h / cmax;
  long nsteps = p->steps;
  if (nsteps <= 0) {
    nsteps = (long)ceil(p->t_end / dt - 1e-9);
    dt = p->t_end / nsteps;
  }
  /* MPI: partition the bond graph and build this rank's local model (docs/mpi.md). */
  dm_dist *d = dm_dist_create(m, ctx, &st);
  if (!d) {
    dm_destroy(m);
    dm_state_free(&s);
    return st;
  }
  const int par = ctx->size > 1;
  {
    const dm_dist_stats *ds = dm_dist_get_stats(d);
    sum->ranks = ctx->size;
    sum->edge_cut = ds->edge_cut, sum->edge_cut_slab = ds->edge_cut_slab;
    sum->imbalance = ds->imbalance, sum->imbalance_slab = ds->imbalance_slab;
    if (par)
      ms_log(ctx, MS_LOG_INFO,
             "discrete model on %d ranks: METIS edge cut %ld of %zu bonds (%.2f %%), imbalance "
             "%.4f; plain x slabs: edge cut %ld, imbalance %.4f; owned max %zu, ghosts max %zu "
             "(total %zu); partitioning %.3f s",
             ctx->size, ds->edge_cut, ds->bonds, 100.0 * ds->edge_cut / fmax(1.0, ds->bonds),
             ds->imbalance, ds->edge_cut_slab, ds->imbalance_slab, ds->max_owned, ds->max_ghosts,
             ds->total_ghosts, ds->partition_s);
  }
  double wmax = omega_max(d, &s), limit = rkn_stability_limit(p->integrator);
  dm_dist_release_global(d); /* the local model has all it needs: halve the memory */
  sum->dt = dt;
  sum->steps = nsteps;
  sum->t_end = nsteps * dt;
  sum->omega_dt = wmax * dt;
  ms_log(ctx, MS_LOG_INFO,
         "discrete model: %zu particles (%zu real), %zu bonds (%.1f per particle), dim %d, "
         "horizon %.3g h; %s, dt = %.6g (omega_max dt = %.4g, stability limit %.4g), %ld steps",
         s.n, nreal, m->nbonds, (double)m->nbonds / s.n, p->dim, p->horizon,
         rkn_scheme_names[p->integrator], dt, wmax * dt, limit, nsteps);
  if (wmax * dt > 0.99 * limit) {
    ms_log(ctx, MS_LOG_ERROR,
           "discrete model: time step %.6g too large: omega_max dt = %.4g exceeds 0.99 x the "
           "stability limit %.4g of %s (lower dt or courant)",
           dt, wmax * dt, limit, rkn_scheme_names[p->integrator]);
    dm_dist_free(d);
    dm_destroy(m);
    dm_state_free(&s);
    return MS_ERR_INPUT;
  }

  dm_state *ls = dm_dist_state(d);
  /* files: rank 0 writes them (every rank holds the gathered global state when it matters) */
  static char no_outdir[1] = "";
  ms_ctx octx = *ctx;
  if (ctx->rank != 0) octx.outdir = no_outdir;

  /* probes: nearest real particle to each x */
  probe_rec *pr = ms_calloc(p->nprobes ? p->nprobes : 1, sizeof *pr);
  for (size_t q = 0; q < p->nprobes; ++q) {
    double best = INFINITY;
    for (size_t i = 0; i < nreal; ++i) {
      double dd = fabs(s.X[3 * i] - p->probes[q]);
      for (int a = 1; a < p->dim; ++a) dd += fabs(s.X[3 * i + a] - (p->lo[a] + 0.5 * p->h));
      if (dd < best) best = dd, pr[q].particle = i, pr[q].x = s.X[3 * i];
    }
  }
  double *probe_val = ms_calloc(p->nprobes ? p->nprobes : 1, sizeof(double));
  size_t nrec_max = (size_t)(nsteps / p->probe_every) + 2, nrec = 0;
  size_t pcols = 1 + p->nprobes;
  double *hist = p->nprobes ? ms_calloc(nrec_max * pcols, sizeof(double)) : NULL;
  size_t nerec_max = (size_t)(nsteps / p->energy_every) + 2, nerec = 0;
  double *ehist = ms_calloc(nerec_max * 5, sizeof(double));
  long *prof_step = ms_calloc(p->nprofile_times ? p->nprofile_times : 1, sizeof(long));
  for (size_t q = 0; q < p->nprofile_times; ++q) prof_step[q] = lround(p->profile_times[q] / dt);
  long *snap_step = ms_calloc(p->nsnapshot_times ? p->nsnapshot_times : 1, sizeof(long));
  for (size_t q = 0; q < p->nsnapshot_times; ++q) snap_step[q] = lround(p->snapshot_times[q] / dt);

  rkn_integrator *ig = rkn_create(p->integrator, 3 * (ls->n ? ls->n : 1));
  dm_dist_diag dg;
  dm_dist_diagnostics(d, &dg);
  double E0 = dg.kinetic + dg.potential;
  double wall = 0.0, cpu = 0.0, dw_scale = 0.0;
  long step0 = 0;
  dm_checkpoint_data ck = {.hist = hist, .ehist = ehist, .pcols = pcols};
  if (ctx->restart) {
    ck.nrec_max = nrec_max, ck.nerec_max = nerec_max;
    st = read_checkpoint(ctx, ctx->restart, &s, nsteps, dt, &ck);
    if (par) st = par_agree_status(st);
    if (st == MS_OK) {
      dm_dist_scatter(d, s.w, 3, ls->w);
      dm_dist_scatter(d, s.u, 3, ls->u);
      step0 = ck.step, E0 = ck.E0, dw_scale = ck.dw_scale, nrec = ck.nrec, nerec = ck.nerec;
      sum->energy_err_max = ck.energy_err_max;
      sum->restart_step = step0;
      ms_log(ctx, MS_LOG_INFO, "discrete model: restarted from %s at step %ld (t = %.9g)",
             ctx->restart, step0, step0 * dt);
    }
  }
  ms_progress prog;
  ms_progress_start(&prog, ctx, "discrete model", step0 * dt, sum->t_end);
  long last_step = step0; /* the last step begun */
  for (long step = step0; step <= nsteps && st == MS_OK; ++step) {
    double t = step * dt;
    if (p->checkpoint_every > 0 && step > step0 && step % p->checkpoint_every == 0 &&
        step < nsteps) {
      /* the state at the top of this step, before anything of step `step` is recorded */
      dm_dist_gather(d, ls->w, 3, s.w);
      dm_dist_gather(d, ls->u, 3, s.u);
      ck.step = step, ck.E0 = E0, ck.dw_scale = dw_scale, ck.nrec = nrec, ck.nerec = nerec;
      ck.energy_err_max = sum->energy_err_max;
      ms_status cs = ctx->rank == 0 ? write_checkpoint(&octx, &s, dt, ctx->size, &ck) : MS_OK;
      if (par) cs = par_agree_status(cs);
      if (cs != MS_OK) {
        st = cs;
        break;
      }
    }
    if (hist && step % p->probe_every == 0 && nrec < nrec_max) {
      for (size_t q = 0; q < p->nprobes; ++q) {
        long l = dm_dist_local_index(d, pr[q].particle);
        probe_val[q] = l >= 0 ? ls->w[3 * l] : 0.0;
      }
      if (par) par_sum_doubles(probe_val, p->nprobes); /* one owner per probe: exact */
      hist[nrec * pcols] = t;
      for (size_t q = 0; q < p->nprobes; ++q) hist[nrec * pcols + 1 + q] = probe_val[q];
      ++nrec;
    }
    if ((step % p->energy_every == 0 || step == nsteps) && nerec < nerec_max) {
      dm_dist_diagnostics(d, &dg);
      double K = dg.kinetic, U = dg.potential;
      dw_scale = fmax(dw_scale, dg.dw_norm);
      double *row = &ehist[5 * nerec++];
      row[0] = t, row[1] = K, row[2] = U, row[3] = K + U, row[4] = dg.hourglass;
      if (E0 > 0 && !p->has_source) { /* a source does work: no conservation to check */
        double err = fabs(K + U - E0) / E0;
        sum->energy_err_max = isnan(sum->energy_err_max) ? err : fmax(sum->energy_err_max, err);
      }
      if (step == nsteps) sum->kinetic_end = K, sum->potential_end = U;
    }
    int gathered = 0;
    for (size_t q = 0; q < p->nprofile_times; ++q)
      if (prof_step[q] == step) {
        if (!gathered) {
          dm_dist_gather(d, ls->w, 3, s.w);
          dm_dist_gather(d, ls->u, 3, s.u);
          dm_dist_global_stress(d); /* stresses of the current state */
          gathered = 1;
        }
        write_profile(&octx, p, m, nreal, t, (int)q);
      }
    for (size_t q = 0; q < p->nsnapshot_times; ++q)
      if (snap_step[q] == step) {
        if (!gathered) {
          dm_dist_gather(d, ls->w, 3, s.w);
          dm_dist_gather(d, ls->u, 3, s.u);
          dm_dist_global_stress(d);
          gathered = 1;
        }
        char name[64];
        snprintf(name, sizeof name, "dm_snapshot_%03d.h5", (int)q);
        write_snapshot(&octx, m, nreal, t, step, name);
      }
    if (step == nsteps) break;
    last_step = step;
    double w0 = ms_wall_time(), c0 = cpu_time();
    st = rkn_step(ig, t, dt, ls->w, ls->u, dm_dist_accel, dm_dist_constrain, d);
    wall += ms_wall_time() - w0;
    cpu += cpu_time() - c0;
    ms_progress_update(&prog, t + dt, step + 1);
  }
  ms_progress_finish(&prog, sum->t_end, nsteps);
  /* the final state, on every rank, for the analyses */
  dm_dist_gather(d, ls->w, 3, s.w);
  dm_dist_gather(d, ls->u, 3, s.u);
  free(p->final_w);
  free(p->final_u);
  p->final_n = s.n;
  p->final_w = ms_calloc(3 * s.n, sizeof(double));
  p->final_u = ms_calloc(3 * s.n, sizeof(double));
  memcpy(p->final_w, s.w, 3 * s.n * sizeof(double));
  memcpy(p->final_u, s.u, 3 * s.n * sizeof(double));
  /* zero-energy-mode indicator: |z|(t) relative to the largest |Δw| of the run */
  for (size_t r = 0; r < nerec; ++r) {
    double hg = dw_scale > 0 ? ehist[5 * r + 4] / dw_scale : 0.0;
    ehist[5 * r + 4] = hg;
    if (r == 0) sum->hourglass_first = sum->hourglass_max = hg;
    sum->hourglass_max = fmax(sum->hourglass_max, hg);
    sum->hourglass_last = hg;
  }
  if (par) {
    const dm_dist_stats *ds = dm_dist_get_stats(d);
    double ex_max = par_max_double(ds->exchange_s), ex_min = par_min_double(ds->exchange_s);
    double vol = par_sum_double(ds->exchanged_doubles);
    ms_log(ctx, MS_LOG_INFO,
           "discrete model: ghost exchanges took %.3f-%.3f s per rank (of the step loop's %.3f s "
           "on the slowest rank); %.4g doubles received in all (%.3g per particle-step)",
           ex_min, ex_max, par_max_double(wall), vol,
           vol / fmax(1.0, (double)nreal * (double)(nsteps - step0)));
  }
  if (par) { /* the slowest rank sets the pace; CPU time of all ranks */
    wall = par_max_double(wall);
    cpu = par_sum_double(cpu);
  }
  sum->wall_s = wall;
  sum->cpu_s = cpu;
  long nrun = nsteps - step0;
  sum->particle_steps_per_s = wall > 0 ? (double)nreal * nrun / wall : 0;
  if (st == MS_ERR_UNSTABLE)
    report_unstable(ctx, &octx, m, d, ls, nreal, last_step, last_step * dt);

  /* analyses against the exact solutions */
  dm_dist_global_stress(d);
  if (st == MS_OK) {
    if ((p->profile == PROF_ROD_TRIANGLE || p->profile == PROF_ROD_SINE) && p->nprobes) {
      double *h1 = ms_calloc(2 * nrec, sizeof(double));
      for (size_t r = 0; r < nrec; ++r)
        h1[2 * r] = hist[r * pcols], h1[2 * r + 1] = hist[r * pcols + 1];
      rod_analysis(p, h1, nrec, pr[0].x);
      free(h1);
      ms_log(ctx, MS_LOG_INFO,
             "rod: probe x = %.6g, last 10 L/c: amplitude error %+.3f %% (least-squares fit), "
             "lag %+.5f L/c, peak error %+.3f %%, rms error %.3f %% of the amplitude",
             pr[0].x, 100 * sum->amp_err, sum->phase_err, 100 * sum->peak_err, 100 * sum->rms_err);
    }
    if (p->profile == PROF_CONTACT) {
      contact_analysis(p, m, nreal, sum->t_end);
      ms_log(ctx, MS_LOG_INFO,
             "contact: sigma_xx at t = %.6g vs exact: L1 %.4f, L2 %.4f, max %.4f (of max|sigma|)",
             sum->t_end, sum->err_l1, sum->err_l2, sum->err_max);
    }
    if (p->has_source) {
      sphere_analysis(p, &s, nreal, sum->t_end);
      write_sphere_radial(&octx, p, &s, nreal, sum->t_end);
      ms_log(ctx, MS_LOG_INFO,
             "sphere: radial w at t = %.6g vs exact: L1 %.4f, L2 %.4f, max %.4f (of max|w|); "
             "u: L2 %.4f of w0*omega",
             sum->t_end, sum->err_l1, sum->err_l2, sum->err_max, sum->err_u_l2);
    }
  }
  ms_log(ctx, MS_LOG_INFO,
         "discrete model: %ld steps in %.3f s (CPU %.3f s): %.4g particle-steps/s; "
         "max |dH|/H0 = %.3g; "
         "hourglass indicator first %.3g max %.3g last %.3g",
         nrun, wall, cpu, sum->particle_steps_per_s, sum->energy_err_max, sum->hourglass_first,
         sum->hourglass_max, sum->hourglass_last);

  if (hist) {
    const char **nm = ms_calloc(pcols, sizeof(char *)), **un = ms_calloc(pcols, sizeof(char *));
    char(*lab)[32] = ms_calloc(pcols, sizeof *lab);
    nm[0] = "t", un[0] = "10 us";
    for (size_t q = 0; q < p->nprobes; ++q) {
      snprintf(lab[q + 1], 32, "w_x(%.6g)", pr[q].x);
      nm[q + 1] = lab[q + 1], un[q + 1] = "cm";
    }
    write_series(&octx, "dm_probes.csv", "displacement history at probe particles", pcols, nm, un,
                 hist, nrec);
    free(nm);
    free(un);
    free(lab);
  }
  {
    const char *nm[] = {"t", "kinetic", "potential", "total", "hourglass"};
    const char *un[] = {"10 us", "kJ", "kJ", "kJ", "1"};
    write_series(&octx, "dm_energy.csv", "energy (real particles) and zero-energy-mode indicator",
                 5, nm, un, ehist, nerec);
    const char *snm[] = {"particles",
                         "real_particles",
                         "bonds",
                         "steps",
                         "dt",
                         "t_end",
                         "omega_dt",
                         "wall_s",
                         "cpu_s",
                         "particle_steps_per_s",
                         "energy_err_max",
                         "hourglass_first",
                         "hourglass_max",
                         "hourglass_last",
                         "amp_err",
                         "phase_err_L_over_c",
                         "peak_err",
                         "rms_err",
                         "err_l1",
                         "err_l2",
                         "err_max",
                         "err_u_l2",
                         "kinetic_end",
                         "potential_end",
                         "ranks",
                         "edge_cut",
                         "edge_cut_slab",
                         "imbalance",
                         "imbalance_slab",
                         "restart_step"};
    const char *sun[] = {"1", "1", "1",  "1",  "10 us", "10 us", "1", "s", "s", "1/s",
                         "1", "1", "1",  "1",  "1",     "L/c",   "1", "1", "1", "1",
                         "1", "1", "kJ", "kJ", "1",     "1",     "1", "1", "1", "1"};
    double row[30] = {(double)sum->particles,
                      (double)sum->real_particles,
                      (double)sum->bonds,
                      (double)sum->steps,
                      sum->dt,
                      sum->t_end,
                      sum->omega_dt,
                      sum->wall_s,
                      sum->cpu_s,
                      sum->particle_steps_per_s,
                      sum->energy_err_max,
                      sum->hourglass_first,
                      sum->hourglass_max,
                      sum->hourglass_last,
                      sum->amp_err,
                      sum->phase_err,
                      sum->peak_err,
                      sum->rms_err,
                      sum->err_l1,
                      sum->err_l2,
                      sum->err_max,
                      sum->err_u_l2,
                      sum->kinetic_end,
                      sum->potential_end,
                      (double)sum->ranks,
                      (double)sum->edge_cut,
                      (double)sum->edge_cut_slab,
                      sum->imbalance,
                      sum->imbalance_slab,
                      (double)sum->restart_step};
    write_series(&octx, "dm_summary.csv", "discrete model run summary", 30, snm, sun, row, 1);
  }
  free(hist);
  free(ehist);
  free(prof_step);
  free(snap_step);
  free(pr);
  free(probe_val);
  rkn_destroy(ig);
  dm_dist_free(d);
  dm_destroy(m);
  dm_state_free(&s);
  return st;
}
