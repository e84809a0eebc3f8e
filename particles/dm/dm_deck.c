/* SPDX-License-Identifier: MIT */
/* dm_deck.c — the deck reader of the problem type `discrete_model` (docs/input-dm.md): every
 * key is checked and located (FILE:LINE:COL) before anything runs. */
#include "dm_problem_impl.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const face_bc_names[] = {"free", "wall", "symmetry", "fixed", "periodic", NULL};
static const char *const face_keys[6] = {"x_lo", "x_hi", "y_lo", "y_hi", "z_lo", "z_hi"};
static const char *const profile_names[] = {
    "none", "rod_triangle", "rod_sine", "contact_harmonic", "random_velocity", NULL};

static const char *const response_names[] = {"linear_elastic", "eos", NULL};
static const char *const yield_names[] = {"none", "elastic_plastic", "steinberg_guinan",
                                          "johnson_cook", NULL};

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
    if (dk_get(it, "velocity")) { /* a body's initial x velocity (the flyer problem) */
      ly->has_u0 = 1;
      dk_read_double(e, doc, it, "velocity", MS_DIM_VELOCITY, true, 0, -1e3, 1e3, &ly->u0);
      if (ly->response != RESP_EOS)
        dk_error(e, doc, dk_get(it, "velocity"),
                 "discrete_model.layers: 'velocity' (a body's initial velocity) needs response: "
                 "eos");
    }
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
    dm_sg_read(e, doc, it, ly->yield, ly->eos, &ly->sg); /* strength_set / strength keys */
    dm_frac_read(e, doc, it, "discrete_model.layers[]", &ly->frac); /* fracture: {...} */
    if (ly->frac.model != DM_FRACTURE_NONE && ly->response != RESP_EOS)
      dk_error(e, doc, dk_get(it, "fracture"),
               "discrete_model.layers: 'fracture' needs response: eos");
    if (ly->yield != DM_YIELD_NONE) {
      if (ly->response != RESP_EOS)
        dk_error(e, doc, it, "discrete_model.layers: 'yield' needs response: eos");
      if (ly->eos && eos_get_kind(ly->eos) == EOS_IDEAL_GAS)
        dk_error(e, doc, it,
                 "discrete_model.layers: a yield model on an ideal gas (material '%s') has no "
                 "meaning",
                 ly->name);
      if (ly->yield == DM_YIELD_STEINBERG_GUINAN) ly->G = ly->sg.G0, ly->Y0 = ly->sg.Y0;
      else if (ly->yield == DM_YIELD_JOHNSON_COOK) ly->G = ly->sg.G0, ly->Y0 = ly->sg.jA;
      else if (!(ly->G > 0))
        dk_error(e, doc, it,
                 "discrete_model.layers: yield: elastic_plastic needs the material's "
                 "shear_modulus > 0 (GPa), got %g",
                 ly->G);
      if (ly->yield >= DM_YIELD_STEINBERG_GUINAN) {
        if (dk_get(it, "yield_stress"))
          dk_error(e, doc, dk_get(it, "yield_stress"), "%s",
                   ly->yield == DM_YIELD_STEINBERG_GUINAN
                       ? "discrete_model.layers: with steinberg_guinan give Y0 as "
                         "strength.yield_stress"
                       : "discrete_model.layers: 'yield_stress' needs yield: elastic_plastic");
      } else if (!dk_get(it, "yield_stress"))
        dk_error(e, doc, it, "discrete_model.layers: yield: elastic_plastic needs 'yield_stress'");
      else dk_read_positive(e, doc, it, "yield_stress", MS_DIM_PRESSURE, true, 0, &ly->Y0);
    } else if (dk_get(it, "yield_stress")) {
      dk_error(e, doc, it, "discrete_model.layers: 'yield_stress' needs yield: elastic_plastic");
    }
  }
}

/* domain: lo, hi (whole numbers of spacings), then the memory estimate (when the deck has no
 * error so far: nerr0 errors before this section was read). Returns the node (or NULL). */
static const dk_node *read_domain(dm_problem *p, dk_doc *doc, const dk_node *sec, size_t nerr0,
                                  dk_errors *e) {
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
  return dom;
}

/* boundaries: one of face_bc_names per face; returns the node (NULL if absent or not a map). */
static const dk_node *read_boundaries(dm_problem *p, dk_doc *doc, const dk_node *sec,
                                      const dk_node *dom, dk_errors *e) {
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
  return bnd;
}

/* initial: the profile of [Sofronov] §5 or random velocities; returns the node. */
static const dk_node *read_initial(dm_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
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
  return ini;
}

/* source: the spherical displacement source (3D); returns the node. */
static const dk_node *read_source(dm_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
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
  return src;
}

/* output: probes, histories, profile and snapshot times, checkpoints; returns the node. */
static const dk_node *read_output(dm_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
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
  return out;
}

/* response: eos (every layer or none) and what goes with it: the bond penalty's and the time
 * step's defaults, viscosity, piston, and the faces, profiles and source it does not take. */
static void read_response(dm_problem *p, dk_doc *doc, const dk_node *sec, int courant_given,
                          const dk_node *bnd, const dk_node *ini, const dk_node *src,
                          dk_errors *e) {
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
  if (!p->finite && dk_get(sec, "contact_distance"))
    dk_error(e, doc, dk_get(sec, "contact_distance"),
             "discrete_model.contact_distance: needs response: eos");
  /* off by default here: it costs 65 % on the finite benchmark (docs/benchmarks.md) */
  dk_read_double(e, doc, sec, "contact_distance", MS_DIM_NONE, false, 0.0, 0.0, DM_CONTACT_MAX,
                 &p->contact);
  for (int a = 0; a < p->dim && p->contact > 0; ++a) /* its cells: 3 seeing distances a box */
    if (p->face[2 * a] == FACE_PERIODIC &&
        p->hi[a] - p->lo[a] < 3.0 * (p->contact + 0.5) * p->h * (1 + 1e-9))
      dk_error(e, doc, dk_get(sec, "contact_distance"),
               "discrete_model.contact_distance: a periodic box must hold 3 seeing distances "
               "(d_c + spacing/2 = %g cm) along each periodic axis",
               (p->contact + 0.5) * p->h);
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
    if (p->has_source) dk_error(e, doc, src, "discrete_model.source: not with response: eos");
    for (size_t i = 0; i < p->nlayers; ++i)
      if (p->layers[i].has_u0 && p->profile == PROF_RANDOM_VELOCITY)
        dk_error(e, doc, ini ? ini : sec,
                 "discrete_model.initial: random_velocity and a layer 'velocity' exclude each "
                 "other (give one initial velocity)");
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
  const dk_node *dom = read_domain(p, doc, sec, nerr0, e);
  const dk_node *bnd = read_boundaries(p, doc, sec, dom, e);
  read_layers(p, doc, sec, mats, e);

  const dk_node *ini = read_initial(p, doc, sec, e);
  const dk_node *src = read_source(p, doc, sec, e);
  dk_read_enum(e, doc, sec, "integrator", false, RKN_VERLET, rkn_scheme_names, &p->integrator);
  const int courant_given = dk_get(sec, "courant") != NULL;
  if (dk_get(sec, "dt")) dk_read_positive(e, doc, sec, "dt", MS_DIM_TIME, true, 0, &p->dt);
  else dk_read_positive(e, doc, sec, "courant", MS_DIM_NONE, false, 0.5, &p->courant);
  if (dk_get(sec, "steps")) dk_read_int(e, doc, sec, "steps", true, 0, 1, LONG_MAX, &p->steps);
  else dk_read_positive(e, doc, sec, "t_end", MS_DIM_TIME, true, 0, &p->t_end);
  read_response(p, doc, sec, courant_given, bnd, ini, src, e);
  dk_read_double(e, doc, sec, "cond_max", MS_DIM_NONE, false, 1e8, 1.0, 1e16, &p->cond_max);

  read_output(p, doc, sec, e);
  if (e->n > nerr0) {
    dm_problem_destroy(&p);
    return NULL;
  }
  /* a response-eos restart may run to another end; anything else must be the deck that wrote
   * the checkpoint (dm_fin_restart.c) */
  static const char *const hash_skip[] = {"discrete_model.t_end", "discrete_model.steps", NULL};
  p->deck_hash = dk_hash(doc, hash_skip);
  return p;
}
