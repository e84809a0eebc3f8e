/* SPDX-License-Identifier: MIT */
/* dm_impact_deck.c — the deck reader of the problem type `impact` (docs/input-impact.md): every
 * key checked and located (FILE:LINE:COL) before anything runs, including the set-up errors a
 * run could only find later: a body outside the box, bodies that overlap or come within the
 * horizon of each other (they would be bonded), a body across the wall, an initial velocity
 * whose approach to the wall violates the first step's time-step limit, and an impact between
 * bodies that the contact's penalty cannot hold. */
#include "dm_impact_impl.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const shape_names[] = {"cylinder", "sphere", "box", NULL};
static const char *const axis_names[] = {"x", "y", "z", NULL};
static const char *const side_names[] = {"lo", "hi", NULL};
static const char *const yield_names[] = {"none", "elastic_plastic", "steinberg_guinan",
                                          "johnson_cook", NULL};

bool dmi_inside(const dmi_body *b, const double x[3]) {
  double d[3];
  for (int a = 0; a < 3; ++a) d[a] = x[a] - b->center[a];
  if (b->shape == DMI_SPHERE)
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < b->radius * b->radius;
  if (b->shape == DMI_BOX)
    return fabs(d[0]) < 0.5 * b->size[0] && fabs(d[1]) < 0.5 * b->size[1] &&
           fabs(d[2]) < 0.5 * b->size[2];
  const int a = b->axis, p = (a + 1) % 3, q = (a + 2) % 3;
  return fabs(d[a]) < 0.5 * b->length && d[p] * d[p] + d[q] * d[q] < b->radius * b->radius;
}

size_t dmi_body_sites(const dmi_body *b, double h, double *X) {
  long n[3]; /* sites per axis, centred on the body's centre */
  if (b->shape == DMI_BOX)
    for (int a = 0; a < 3; ++a) n[a] = lround(b->size[a] / h);
  else {
    const long nr = 2 * (long)ceil(b->radius / h);
    n[0] = n[1] = n[2] = nr;
    if (b->shape == DMI_CYLINDER) n[b->axis] = lround(b->length / h);
  }
  size_t cnt = 0;
  for (long k = 0; k < n[2]; ++k)
    for (long j = 0; j < n[1]; ++j)
      for (long i = 0; i < n[0]; ++i) {
        const long idx[3] = {i, j, k};
        double x[3], r2 = 0;
        for (int a = 0; a < 3; ++a) {
          x[a] = b->center[a] + (idx[a] + 0.5 - 0.5 * n[a]) * h;
          if (b->shape == DMI_SPHERE || (b->shape == DMI_CYLINDER && a != b->axis))
            r2 += (x[a] - b->center[a]) * (x[a] - b->center[a]);
        }
        if (b->shape != DMI_BOX && r2 >= b->radius * b->radius) continue;
        if (X) memcpy(&X[3 * cnt], x, sizeof x);
        ++cnt;
      }
  return cnt;
}

void dmi_body_speeds(const dmi_body *b, double *cL, double *c) {
  const double rho0 = eos_rho0(b->mat.eos);
  const double c0 = eos_sound_speed(b->mat.eos, rho0, eos_e0(b->mat.eos));
  const double G = b->mat.yield != DM_YIELD_NONE ? b->mat.G : 0.0;
  *c = c0, *cL = sqrt(c0 * c0 + 4.0 * G / (3.0 * rho0));
}

/* A list of exactly three numbers (with units) into out; false (error recorded) otherwise. */
static bool read_vec3(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                      bool required, double out[3], const char *what) {
  if (!dk_get(map, key) && !required) return true;
  double *v = NULL;
  size_t nv = 0;
  bool ok = dk_read_double_list(e, doc, map, key, dim, true, &v, &nv);
  if (ok && nv != 3) {
    dk_error(e, doc, dk_get(map, key), "%s.%s: needs 3 values (x, y, z), got %zu", what, key, nv);
    ok = false;
  }
  if (ok) memcpy(out, v, 3 * sizeof(double));
  free(v);
  return ok;
}

/* material, yield and strength keys of one body (the layer keys of docs/input-dm.md). */
static void read_body_material(dmi_body *b, dk_doc *doc, const dk_node *it,
                               const eos_materials *mats, dk_errors *e) {
  const eos_material *m = NULL;
  if (dk_read_string(e, doc, it, "material", true, NULL, &b->material) && mats)
    m = eos_materials_find(mats, b->material, e, doc, it);
  dk_read_enum(e, doc, it, "yield", false, DM_YIELD_NONE, yield_names, &b->mat.yield);
  if (m && !m->eos)
    dk_error(e, doc, it, "impact.bodies: material '%s' needs an 'eos:' entry", b->material);
  const eos_t *eos = m ? m->eos : NULL;
  if (eos) {
    const double r0 = eos_rho0(eos), c0 = eos_sound_speed(eos, r0, eos_e0(eos));
    if (!(c0 > 0) || !isfinite(c0)) {
      dk_error(e, doc, it, "impact.bodies: material '%s' has no sound speed at rho0", m->name);
      eos = NULL;
    }
  }
  b->mat.eos = eos;
  b->mat.G = m ? m->shear_modulus : 0.0;
  b->mat.sg = &b->sg;
  dm_sg_read(e, doc, it, b->mat.yield, eos, &b->sg);
  if (b->mat.yield == DM_YIELD_STEINBERG_GUINAN) b->mat.G = b->sg.G0, b->mat.Y0 = b->sg.Y0;
  else if (b->mat.yield == DM_YIELD_JOHNSON_COOK) b->mat.G = b->sg.G0, b->mat.Y0 = b->sg.jA;
  if (b->mat.yield == DM_YIELD_ELASTIC_PLASTIC) {
    dk_read_positive(e, doc, it, "yield_stress", MS_DIM_PRESSURE, true, 0, &b->mat.Y0);
    if (m && !(b->mat.G > 0))
      dk_error(e, doc, it,
               "impact.bodies: yield: elastic_plastic needs the material's shear_modulus > 0");
  } else if (dk_get(it, "yield_stress"))
    dk_error(e, doc, dk_get(it, "yield_stress"),
             "impact.bodies: 'yield_stress' needs yield: elastic_plastic");
  dm_frac_read(e, doc, it, "impact.bodies[]", &b->mat.frac);
  if (eos && b->mat.yield != DM_YIELD_NONE && eos_get_kind(eos) == EOS_IDEAL_GAS)
    dk_error(e, doc, it, "impact.bodies: a yield model on an ideal gas has no meaning");
}

/* shape, size, centre and velocity of one body. */
static void read_body_shape(dmi_body *b, dk_doc *doc, const dk_node *it, dk_errors *e) {
  dk_read_enum(e, doc, it, "shape", true, DMI_CYLINDER, shape_names, &b->shape);
  read_vec3(e, doc, it, "center", MS_DIM_LENGTH, true, b->center, "impact.bodies");
  read_vec3(e, doc, it, "velocity", MS_DIM_VELOCITY, false, b->velocity, "impact.bodies");
  if (b->shape == DMI_BOX)
    read_vec3(e, doc, it, "size", MS_DIM_LENGTH, true, b->size, "impact.bodies");
  else dk_read_positive(e, doc, it, "radius", MS_DIM_LENGTH, true, 0, &b->radius);
  if (b->shape == DMI_CYLINDER) {
    dk_read_positive(e, doc, it, "length", MS_DIM_LENGTH, true, 0, &b->length);
    dk_read_enum(e, doc, it, "axis", false, 2, axis_names, &b->axis);
  }
  if (b->shape == DMI_BOX)
    for (int a = 0; a < 3; ++a)
      if (!(b->size[a] > 0))
        dk_error(e, doc, dk_get(it, "size"), "impact.bodies.size: must be > 0");
  for (int a = 0; a < 3; ++a)
    if (!(fabs(b->velocity[a]) <= 1e3))
      dk_error(e, doc, dk_get(it, "velocity"), "impact.bodies.velocity: |v| must be <= 1000 km/s");
}

static void read_bodies(dm_impact *p, dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                        dk_errors *e) {
  const dk_node *L = dk_get(sec, "bodies");
  if (!L) {
    dk_error(e, doc, sec, "impact: 'bodies' (a list of shapes with materials) is required");
    return;
  }
  if (!dk_expect_seq(e, doc, L, "impact.bodies")) return;
  p->nbodies = dk_seq_len(L);
  if (p->nbodies == 0 || p->nbodies > 255) {
    dk_error(e, doc, L, "impact.bodies: needs 1 to 255 bodies, got %zu", p->nbodies);
    p->nbodies = 0;
    return;
  }
  p->bodies = ms_calloc(p->nbodies, sizeof *p->bodies);
  for (size_t i = 0; i < p->nbodies; ++i) {
    const dk_node *it = dk_seq_at(L, i);
    if (!dk_expect_map(e, doc, it, "impact.bodies[]")) continue;
    read_body_shape(&p->bodies[i], doc, it, e);
    read_body_material(&p->bodies[i], doc, it, mats, e);
  }
}

static void read_wall(dm_impact *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *w = dk_get(sec, "wall");
  if (!w || !dk_expect_map(e, doc, w, "impact.wall")) return;
  p->has_wall = 1;
  int side = 0;
  dk_read_enum(e, doc, w, "axis", false, 2, axis_names, &p->wall_axis);
  dk_read_double(e, doc, w, "position", MS_DIM_LENGTH, true, 0, -INFINITY, INFINITY, &p->wall_pos);
  dk_read_enum(e, doc, w, "side", false, 0, side_names, &side);
  p->wall_side = side == 0 ? 1 : -1; /* lo: the wall is below the bodies */
  dk_read_positive(e, doc, w, "stiffness", MS_DIM_NONE, false, 1.0, &p->wall_stiffness);
  const int a = p->wall_axis;
  if (!(p->wall_pos >= p->lo[a] && p->wall_pos <= p->hi[a]))
    dk_error(e, doc, dk_get(w, "position"),
             "impact.wall.position: %g is outside the domain [%g, %g]", p->wall_pos, p->lo[a],
             p->hi[a]);
}

/* A body outside the box, across the wall, or too fast for the first step near the wall. */
static void check_body_placement(const dm_impact *p, dk_doc *doc, const dk_node *L, dk_errors *e) {
  const double h = p->h;
  for (size_t i = 0; i < p->nbodies; ++i) {
    const dmi_body *b = &p->bodies[i];
    const dk_node *it = dk_seq_at(L, i);
    const size_t n = dmi_body_sites(b, h, NULL);
    if (n == 0) {
      dk_error(e, doc, it, "impact.bodies[%zu]: no lattice site inside (smaller than the spacing)",
               i);
      continue;
    }
    double *X = ms_calloc(3 * n, sizeof(double)), gap = INFINITY;
    dmi_body_sites(b, h, X);
    int out = 0;
    for (size_t j = 0; j < n && !out; ++j)
      for (int a = 0; a < 3; ++a)
        if (X[3 * j + a] - 0.5 * h < p->lo[a] - 1e-9 * h ||
            X[3 * j + a] + 0.5 * h > p->hi[a] + 1e-9 * h)
          out = 1;
    if (p->has_wall)
      for (size_t j = 0; j < n; ++j)
        gap = fmin(gap, p->wall_side * (X[3 * j + p->wall_axis] - p->wall_pos) - 0.5 * h);
    free(X);
    if (out)
      dk_error(e, doc, it, "impact.bodies[%zu]: the body is not inside the domain [lo, hi]", i);
    if (p->has_wall && gap < -1e-9 * h)
      dk_error(e, doc, it,
               "impact.bodies[%zu]: the body crosses the wall plane (its particles must be half a "
               "spacing or more on the wall's %s side)",
               i, p->wall_side > 0 ? "+" : "-");
    if (!p->has_wall || !b->mat.eos) continue;
    /* the first step: dt1 = courant h/(c_L + 2 C_l c) (no velocity gradient yet); a particle
     * approaching the wall must move at most 0.1 h in it (docs/input-impact.md) */
    double cL, c;
    dmi_body_speeds(b, &cL, &c);
    const double dt1 = p->courant * h / (cL + 2.0 * p->cl * c);
    const double vn = -p->wall_side * b->velocity[p->wall_axis];
    if (vn * dt1 > 0.1 * h)
      dk_error(e, doc, dk_get(it, "velocity") ? dk_get(it, "velocity") : it,
               "impact.bodies[%zu].velocity: the approach speed %g km/s moves a particle %.3g "
               "spacings towards the wall in the first step (dt %g from c_L %g km/s), more than "
               "the contact's limit of 0.1 spacing per step: give a smaller courant or velocity",
               i, vn, vn * dt1 / h, dt1, cL);
  }
}

/* Bodies that overlap or come within the horizon of each other would be bonded together. */
static void check_body_pairs(const dm_impact *p, dk_doc *doc, const dk_node *L, dk_errors *e) {
  const double h = p->h, delta = p->horizon * h;
  for (size_t j = 1; j < p->nbodies; ++j) {
    const size_t nj = dmi_body_sites(&p->bodies[j], h, NULL);
    double *Xj = ms_calloc(3 * (nj ? nj : 1), sizeof(double));
    dmi_body_sites(&p->bodies[j], h, Xj);
    for (size_t i = 0; i < j; ++i) {
      const size_t ni = dmi_body_sites(&p->bodies[i], h, NULL);
      double *Xi = ms_calloc(3 * (ni ? ni : 1), sizeof(double));
      dmi_body_sites(&p->bodies[i], h, Xi);
      int overlap = 0, close = 0;
      for (size_t a = 0; a < nj && !overlap; ++a) overlap = dmi_inside(&p->bodies[i], &Xj[3 * a]);
      for (size_t b = 0; b < ni && !overlap; ++b) overlap = dmi_inside(&p->bodies[j], &Xi[3 * b]);
      for (size_t a = 0; a < nj && !overlap && !close; ++a)
        for (size_t b = 0; b < ni && !close; ++b) {
          double d2 = 0;
          for (int c = 0; c < 3; ++c) d2 += pow(Xj[3 * a + c] - Xi[3 * b + c], 2);
          close = d2 < delta * delta;
        }
      /* the contact's penalty must hold the impact (dm_impact_contact.c): the acoustic
       * impact pressure Z_i Z_j/(Z_i + Z_j) |Δv| (Z = ρ0 c0; a lower bound of the shock's, about
       * half of it for Al on Al at 6.7 km/s) may press the surfaces into each other by at most
       * 0.25 h, d/h = p / (c_c M) with M the harmonic mean of the P-wave moduli. (The time step
       * needs no check: the contact's own limit adapts it, docs/input-impact.md.) */
      double dv2 = 0, p_ac = 0, M_c = 0;
      for (int c = 0; c < 3; ++c)
        dv2 += pow(p->bodies[j].velocity[c] - p->bodies[i].velocity[c], 2);
      if (p->contact_stiffness > 0 && p->bodies[i].mat.eos && p->bodies[j].mat.eos) {
        double cL[2], c0[2], Z[2], Mb[2];
        const dmi_body *bb[2] = {&p->bodies[i], &p->bodies[j]};
        for (int q = 0; q < 2; ++q) {
          dmi_body_speeds(bb[q], &cL[q], &c0[q]);
          Z[q] = eos_rho0(bb[q]->mat.eos) * c0[q], Mb[q] = eos_rho0(bb[q]->mat.eos) * cL[q] * cL[q];
        }
        p_ac = Z[0] * Z[1] / (Z[0] + Z[1]) * sqrt(dv2);
        M_c = 2.0 * Mb[0] * Mb[1] / (Mb[0] + Mb[1]);
      }
      if (overlap)
        dk_error(e, doc, dk_seq_at(L, j), "impact.bodies[%zu]: overlaps bodies[%zu]", j, i);
      if (!overlap && M_c > 0 && p_ac > 0.25 * p->contact_stiffness * M_c)
        dk_error(e, doc,
                 dk_get(dk_seq_at(L, j), "velocity") ? dk_get(dk_seq_at(L, j), "velocity")
                                                     : dk_seq_at(L, j),
                 "impact.bodies[%zu].velocity: the impact on bodies[%zu] (acoustic pressure %g "
                 "GPa) would press the contact %.3g spacings deep, more than 0.25: give a larger "
                 "impact.contact.stiffness (now %g)",
                 j, i, p_ac, p_ac / (p->contact_stiffness * M_c), p->contact_stiffness);
      if (!overlap && close)
        dk_error(e, doc, dk_seq_at(L, j),
                 "impact.bodies[%zu]: comes within the horizon (%g cm) of bodies[%zu]: the two "
                 "would be bonded (the contact acts between unbonded bodies only); leave a gap",
                 j, delta, i);
      free(Xi);
    }
    free(Xj);
  }
}

static void read_controls(dm_impact *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  dk_read_positive(e, doc, sec, "t_end", MS_DIM_TIME, true, 0, &p->t_end);
  dk_read_positive(e, doc, sec, "courant", MS_DIM_NONE, false, 0.4, &p->courant);
  if (p->courant > 1.0) dk_error(e, doc, dk_get(sec, "courant"), "impact.courant: at most 1");
  dk_read_double(e, doc, sec, "hourglass", MS_DIM_NONE, false, 1.0, 0.0, 100.0, &p->hourglass);
  dk_read_double(e, doc, sec, "cond_max", MS_DIM_NONE, false, 1e8, 1.0, 1e16, &p->cond_max);
  dk_read_double(
      e, doc, sec, "contact_distance", MS_DIM_NONE, false, 0.0, 0.0, DM_CONTACT_MAX,
      &p->contact_distance); /* dm_contact.c; off by default (cost, docs/input-impact.md) */
  p->cq = 2.0, p->cl = 0.5;
  const dk_node *vis = dk_get(sec, "viscosity");
  if (vis && dk_expect_map(e, doc, vis, "impact.viscosity")) {
    dk_read_double(e, doc, vis, "quadratic", MS_DIM_NONE, false, 2.0, 0.0, 100.0, &p->cq);
    dk_read_double(e, doc, vis, "linear", MS_DIM_NONE, false, 0.5, 0.0, 100.0, &p->cl);
  }
  p->contact_stiffness = 10.0; /* c_c: penetration < 0.1 h up to a contact stress M */
  const dk_node *ct = dk_get(sec, "contact");
  if (ct && dk_expect_map(e, doc, ct, "impact.contact"))
    dk_read_double(e, doc, ct, "stiffness", MS_DIM_NONE, false, 10.0, 0.0, 1000.0,
                   &p->contact_stiffness);
  const dk_node *ru = dk_get(sec, "reference_update");
  if (ru && dk_expect_map(e, doc, ru, "impact.reference_update")) {
    static const char *const family_names[] = {"rebuild", "keep", "merge", NULL};
    dk_read_double(e, doc, ru, "threshold", MS_DIM_NONE, true, 0, 1e-3, 10.0, &p->ref_threshold);
    dk_read_enum(e, doc, ru, "families", false, 0, family_names, &p->ref_keep);
    static const char *const scope_names[] = {"all", "family", NULL};
    const dk_node *sc = dk_get(ru, "scope");
    /* read only when given: the resolved deck, and so the checkpoints' deck hash, of a deck
     * without it stay those of before the key */
    if (sc) dk_read_enum(e, doc, ru, "scope", false, 0, scope_names, &p->ref_family);
    if (p->ref_family && !p->ref_keep)
      dk_error(e, doc, sc,
               "impact.reference_update.scope: family needs families: keep or merge (a rebuilt "
               "family is built on one reference shared by all)");
    if (p->ref_family && p->contact_distance > 0)
      dk_error(e, doc, sc,
               "impact.reference_update.scope: family is not available with contact_distance > 0 "
               "(the short-range contact's stiffness belongs to one shared reference)");
  }
  const dk_node *out = dk_get(sec, "output");
  p->energy_every = 20;
  if (out && dk_expect_map(e, doc, out, "impact.output")) {
    dk_read_int(e, doc, out, "energy_every", false, 20, 1, LONG_MAX, &p->energy_every);
    dk_read_checkpoint_interval(e, doc, out, "impact.output.", "steps", &p->checkpoint_every,
                                &p->checkpoint_time);
    if (dk_get(out, "particle_times"))
      dk_read_double_list(e, doc, out, "particle_times", MS_DIM_TIME, true, &p->particle_times,
                          &p->nparticle_times);
  }
}

dm_impact *dm_impact_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                                  dk_errors *e) {
  dm_impact *p = ms_calloc(1, sizeof *p);
  const size_t nerr0 = e->n;
  dk_read_positive(e, doc, sec, "spacing", MS_DIM_LENGTH, true, 0, &p->h);
  dk_read_double(e, doc, sec, "horizon", MS_DIM_NONE, false, 1.5, 1.0, 4.0, &p->horizon);
  const dk_node *dom = dk_get(sec, "domain");
  if (!dom)
    dk_error(e, doc, sec, "impact: 'domain' with 'lo' and 'hi' (3 values each) is required");
  else if (dk_expect_map(e, doc, dom, "impact.domain")) {
    bool ok = read_vec3(e, doc, dom, "lo", MS_DIM_LENGTH, true, p->lo, "impact.domain");
    ok = read_vec3(e, doc, dom, "hi", MS_DIM_LENGTH, true, p->hi, "impact.domain") && ok;
    for (int a = 0; ok && a < 3; ++a)
      if (!(p->hi[a] > p->lo[a])) {
        dk_error(e, doc, dom, "impact.domain: hi must exceed lo along every axis");
        break;
      }
  }
  read_controls(p, doc, sec, e);
  read_bodies(p, doc, sec, mats, e);
  /* fracture's per-bond contact state (dm_fracture.c) belongs to the families it was built on:
   * no reference update moves it (dm_fin_reference_update, dm_fin_rebase, dm_fin_rebase_local
   * refuse a model with fracture), so refuse the pair here, located, before the run */
  const dk_node *ru = dk_get(sec, "reference_update");
  for (size_t b = 0; p->ref_threshold > 0 && b < p->nbodies; ++b)
    if (p->bodies[b].mat.frac.model != DM_FRACTURE_NONE) {
      dk_error(e, doc, dk_get(ru, "scope") ? dk_get(ru, "scope") : ru,
               "impact.reference_update%s is not available with fracture (impact.bodies[%zu] has "
               "a fracture model: the broken bonds' contact belongs to the families it was built "
               "on)",
               p->ref_family ? ".scope: family" : "", b);
      break;
    }
  read_wall(p, doc, sec, e);
  dmi_sym_read(p, doc, sec, e);
  if (e->n == nerr0 && p->nbodies) { /* geometry checks need a valid deck so far */
    const dk_node *L = dk_get(sec, "bodies");
    size_t n = 0;
    for (size_t i = 0; i < p->nbodies; ++i) n += dmi_body_sites(&p->bodies[i], p->h, NULL);
    ms_mem_estimate mem; /* ~400 B + 16 B per bond and particle (dm_deck.c's estimate) */
    ms_mem_init(&mem);
    ms_mem_add(&mem, dk_get(sec, "spacing"), "impact particles", (double)n,
               400.0 + 16.0 * 4.0 / 3.0 * M_PI * pow(p->horizon, 3));
    ms_mem_check(&mem, ms_mem_limit(), 1, 1, e, doc);
    ms_mem_free(&mem);
    if (e->n == nerr0) {
      check_body_placement(p, doc, L, e);
      check_body_pairs(p, doc, L, e);
      dmi_sym_check(p, doc, sec, e);
    }
  }
  if (e->n > nerr0) {
    dm_impact_problem_destroy(&p);
    return NULL;
  }
  /* a restart may run to another end and change the cadence (a checkpoint changes nothing of
   * the run: dm_impact_checkpoint.c); anything else must be the deck that wrote it */
  static const char *const hash_skip[] = {"impact.t_end", "impact.output.checkpoint_every",
                                          "impact.output.checkpoint_time", NULL};
  p->deck_hash = dk_hash(doc, hash_skip);
  return p;
}

void dm_impact_problem_destroy(dm_impact **pp) {
  if (!pp || !*pp) return;
  free((*pp)->bodies);
  free((*pp)->particle_times);
  free(*pp);
  *pp = NULL;
}

const dm_impact_summary *dm_impact_get_summary(const dm_impact *p) { return &p->sum; }
