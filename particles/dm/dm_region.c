/* SPDX-License-Identifier: MIT */
/* dm_region.c — the finite-deformation discrete model (dm_finite.c) as a particle region of the
 * coupled problem (ptl_region.h, docs/input-coupled.md "particles", docs/particles-dm.md
 * "The discrete model as the coupled problem's particle region"): the deck section, a
 * simple-square (2D plane strain) or simple-cubic (3D) slab cut by the surface profile, the
 * piston layers (DM_PRESCRIBED) and the surface layer, and the interface's calls on a dm_fin.
 *
 * The coupling sees a ptl_state mirror of the model (x = X + w, v = u, f, mass, gid, flags),
 * refreshed after every step; velocities it changes between steps (drag kicks) are copied back
 * into the model's u before the next one. The coupled loop steps with the fixed geometry.dt:
 * it is chosen at create as dt_margin × the model's own limit at the initial state (the
 * Courant limit of dm_fin, docs/particles-dm.md "Time step"); where the model's limit at the
 * current state falls below it, region_step sub-cycles (MS_ERR_UNSTABLE beyond
 * DM_REGION_MAX_SUBSTEPS sub-steps).
 * Fracture (dm_fracture.c) breaks bonds; the fragments are the components of the unbroken ones
 * (region_links). Not yet: random surfaces. */
#include "dm_columns.h"
#include "dm_impl.h"
#include "ptl_region_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { SURF_FLAT = 0, SURF_SINE };
/* most model sub-steps per coupled step (region_step): beyond, the limit has collapsed */
enum { DM_REGION_MAX_SUBSTEPS = 64 };
static const char *const surface_names[] = {"flat", "sine", NULL};
static const char *const response_names[] = {"eos", "linear_elastic", NULL};
static const char *const yield_names[] = {"none", "elastic_plastic", "steinberg_guinan",
                                          "johnson_cook", NULL};

typedef struct dm_region_params {
  ptl_region_params base;
  double h; /* spacing (deck: r0), cm */
  long dim; /* 2 or 3 */
  double width, width_z, horizon;
  long piston_layers;
  int yield;
  double G, Y0;
  dm_sg sg;         /* steinberg_guinan: strength_set and/or strength {...} (dm_strength.c) */
  dm_fracture frac; /* fracture: {...} (dm_fracture.c) */
  double cq, cl, courant, hourglass, dt_margin, cond_max, contact;
  double ref_threshold; /* reference_update.threshold (0: none) */
  int surface;
  double surf_depth, surf_wavelength;
  const dk_node *at, *at_r0;
} dm_region_params;

/* A constant-or-piecewise-linear piston u(t)·dir on the region's clock, with the running
 * integral at its samples so that a step's mean velocity is exact. */
typedef struct piston {
  size_t n, cap, k; /* samples, capacity, cursor (segment of the last lookup) */
  double *t, *u, *cum;
  double dir[3];
} piston;

typedef struct dm_region {
  ptl_region base;
  dm_state s;
  dm_model *m;
  dm_fin *f;
  dm_fin_material mat;
  uint8_t *imat;
  ptl_state *ps;
  size_t *link_start; /* [n + 1], link_nbr [bonds]: the unbroken bonds (region_links) */
  int32_t *link_nbr;
  ptl_region_geometry geo;
  double t, dt, dt0_limit;
  double ref_threshold; /* > 0: per-family reference updates (region_rebase) */
  piston pis;
  dm_columns *cols; /* the piston by columns (set_piston_columns); NULL: pis */
  int rank, nranks; /* replicated on MPI ranks: rank 0 owns the particles (region_distribute) */
  char err[512];
} dm_region;

/* ---------------------------------------------------------------------------------------- */
/* The deck section                                                                           */

static void read_surface(dm_region_params *p, dk_doc *doc, const dk_node *S, dk_errors *e) {
  dk_read_enum(e, doc, S, "profile", false, 0, surface_names, &p->surface);
  const bool need = p->surface != SURF_FLAT;
  const dk_node *amplitude_node = dk_get(S, "amplitude");
  if (amplitude_node) { /* a0 = depth/2, as cd_region.c */
    if (dk_get(S, "depth"))
      dk_error(e, doc, amplitude_node,
               "particles.surface: give depth (peak to valley) or amplitude (half of it), "
               "not both");
    double amplitude = 0.0;
    dk_read_double(e, doc, S, "amplitude", MS_DIM_LENGTH, need, 0.0, 0.0, INFINITY, &amplitude);
    p->surf_depth = 2.0 * amplitude;
  } else {
    dk_read_double(e, doc, S, "depth", MS_DIM_LENGTH, need, 0.0, 0.0, INFINITY, &p->surf_depth);
  }
  dk_read_double(e, doc, S, "wavelength", MS_DIM_LENGTH, need, 0.0, 0.0, INFINITY,
                 &p->surf_wavelength);
  if (need && !(p->surf_wavelength > 0))
    dk_error(e, doc, S, "particles.surface: wavelength must be > 0 for a sine surface");
}

/* Checkpoints of the coupled run are not implemented for this model: refuse the deck's
 * time.checkpoint_every / checkpoint_time (nonzero) where they stand, if the section is the
 * coupled problem's (root → coupled → particles). */
static ptl_region_params *region_read(dk_doc *doc, const dk_node *P, dk_errors *e) {
  const size_t nerr0 = e->n;
  dm_region_params *p = ms_calloc(1, sizeof *p);
  p->at = P;
  p->at_r0 = dk_get(P, "r0");
  dk_read_positive(e, doc, P, "r0", MS_DIM_LENGTH, true, 0, &p->h);
  dk_read_int(e, doc, P, "dimension", false, 2, 2, 3, &p->dim);
  dk_read_positive(e, doc, P, "width", MS_DIM_LENGTH, true, 0, &p->width);
  /* the DM's own defaults (docs/input-dm.md): horizon 1.5 spacings, courant 0.4, bond
   * penalty c_s = 1, viscosity C_q = 2, C_l = 0.5 */
  dk_read_double(e, doc, P, "horizon", MS_DIM_NONE, false, 1.5, 1.0, 10.0, &p->horizon);
  if (p->dim == 3)
    dk_read_double(e, doc, P, "width_z", MS_DIM_LENGTH, false, ceil(3.0 * p->horizon + 1e-9) * p->h,
                   0.0, INFINITY, &p->width_z);
  dk_read_int(e, doc, P, "piston_layers", false, 2, 1, 100, &p->piston_layers);
  int response = 0;
  const dk_node *at_resp = dk_get(P, "response");
  dk_read_enum(e, doc, P, "response", false, 0, response_names, &response);
  if (response != 0)
    dk_error(e, doc, at_resp,
             "particles.response: the coupled problem's discrete model takes response: eos only "
             "(the sample's pressure from the grid material's EOS)");
  dk_read_enum(e, doc, P, "yield", false, DM_YIELD_NONE, yield_names, &p->yield);
  if (p->yield == DM_YIELD_ELASTIC_PLASTIC) {
    /* ptl_region_create receives the sample's EOS only, so G is a key of this section */
    dk_read_positive(e, doc, P, "shear_modulus", MS_DIM_PRESSURE, true, 0, &p->G);
    dk_read_positive(e, doc, P, "yield_stress", MS_DIM_PRESSURE, true, 0, &p->Y0);
  } else {
    /* none: no keys; steinberg_guinan: G0 and Y0 from strength_set / strength {...} */
    static const char *const only_ep[] = {"shear_modulus", "yield_stress"};
    for (int k = 0; k < 2; k++)
      if (dk_get(P, only_ep[k]))
        dk_error(e, doc, dk_get(P, only_ep[k]), "particles.%s needs yield: elastic_plastic",
                 only_ep[k]);
  }
  /* the sample's EOS is not known here: its cold curve (the temperature) is checked at create */
  dm_sg_read(e, doc, P, p->yield, NULL, &p->sg);
  if (p->yield == DM_YIELD_STEINBERG_GUINAN) p->G = p->sg.G0, p->Y0 = p->sg.Y0;
  if (p->yield == DM_YIELD_JOHNSON_COOK) p->G = p->sg.G0, p->Y0 = p->sg.jA;
  dm_frac_read(e, doc, P, "particles", &p->frac);
  p->cq = 2.0, p->cl = 0.5;
  const dk_node *V = dk_get(P, "viscosity");
  if (V && dk_expect_map(e, doc, V, "particles.viscosity")) {
    dk_read_double(e, doc, V, "quadratic", MS_DIM_NONE, false, 2.0, 0.0, 100.0, &p->cq);
    dk_read_double(e, doc, V, "linear", MS_DIM_NONE, false, 0.5, 0.0, 100.0, &p->cl);
  }
  dk_read_double(e, doc, P, "courant", MS_DIM_NONE, false, 0.4, 1e-6, 1.0, &p->courant);
  dk_read_double(e, doc, P, "hourglass", MS_DIM_NONE, false, 1.0, 0.0, 100.0, &p->hourglass);
  dk_read_double(e, doc, P, "dt_margin", MS_DIM_NONE, false, 0.5, 1e-3, 1.0, &p->dt_margin);
  dk_read_double(e, doc, P, "cond_max", MS_DIM_NONE, false, 1e8, 1.0, 1e16, &p->cond_max);
  dk_read_double(e, doc, P, "contact_distance", MS_DIM_NONE, false, DM_CONTACT_DEFAULT, 0.0,
                 DM_CONTACT_MAX, &p->contact); /* dm_contact.c */
  /* reference_update: {threshold}: the impact problem's per-family update, families kept
   * (dm_fin_rebase_local; docs/input-coupled.md) */
  const dk_node *RU = dk_get(P, "reference_update");
  if (RU && dk_expect_map(e, doc, RU, "particles.reference_update")) {
    dk_read_double(e, doc, RU, "threshold", MS_DIM_NONE, true, 0, 1e-3, 10.0, &p->ref_threshold);
    if (p->frac.model || p->contact > 0)
      dk_error(e, doc, RU,
               "particles.reference_update needs contact_distance: 0 and no fracture (their "
               "per-bond state belongs to one shared reference)");
  }
  /* its cells: at least 3 seeing distances (d_c + h/2) across a periodic width */
  const double see = (p->contact + 0.5) * p->h;
  if (p->contact > 0 && p->h > 0 &&
      ((p->width > 0 && p->width < 3.0 * see * (1 + 1e-9)) ||
       (p->dim == 3 && p->width_z < 3.0 * see * (1 + 1e-9))))
    dk_error(e, doc, dk_get(P, "contact_distance") ? dk_get(P, "contact_distance") : P,
             "particles.contact_distance: the periodic width must hold 3 seeing distances "
             "(d_c + r0/2 = %g cm): give a smaller contact_distance or a wider region",
             see);
  const dk_node *S = dk_get(P, "surface");
  p->surface = SURF_FLAT;
  if (S && dk_expect_map(e, doc, S, "particles.surface")) read_surface(p, doc, S, e);
  /* periodic axes need a box of at least 3 horizons (docs/particles-dm.md "Boundaries") */
  if (p->h > 0 && p->width > 0 && p->width < 3.0 * p->horizon * p->h * (1 - 1e-9))
    dk_error(e, doc, dk_get(P, "width"),
             "particles.width (%g cm) must be at least 3 horizons (3 x %g x r0 = %g cm): the "
             "periodic families wrap",
             p->width, p->horizon, 3.0 * p->horizon * p->h);
  if (p->dim == 3 && p->h > 0 && p->width_z < 3.0 * p->horizon * p->h * (1 - 1e-9))
    dk_error(e, doc, dk_get(P, "width_z") ? dk_get(P, "width_z") : P,
             "particles.width_z (%g cm) must be at least 3 horizons (%g cm)", p->width_z,
             3.0 * p->horizon * p->h);
  if (p->surface != SURF_FLAT && p->surf_wavelength > 0 && p->width > 0 &&
      p->surf_wavelength > p->width * (1 + 1e-9))
    dk_error(e, doc, dk_get(P, "width"),
             "particles.width (%g cm) must hold at least one surface wavelength (%g cm)", p->width,
             p->surf_wavelength);
  if (e->n != nerr0) {
    free(p);
    return NULL;
  }
  return &p->base;
}

static void region_params_destroy(ptl_region_params *pp) { free(pp); }
static const char *region_notes(const ptl_region_params *pp) {
  (void)pp;
  return "";
}

static void lattice_counts(const dm_region_params *p, double depth, long n[3]) {
  n[0] = (long)fmax((double)p->piston_layers + 2.0, nearbyint(depth / p->h));
  n[1] = (long)fmax(1.0, nearbyint(p->width / p->h));
  n[2] = p->dim == 3 ? (long)fmax(1.0, nearbyint(p->width_z / p->h)) : 1;
}

/* Check-time memory estimate (docs/reliability.md §4): the DM's families and work arrays
 * (dm_deck.c's measured 400 B + 16 B per family member), dm_fin's per-particle arrays
 * (7 scalars, 4 tensors, 2 vectors: 392 B), the ptl_state mirror (~100 B) and the coupling's
 * fragment and transport buffers (25 B). */
static ptl_region_estimate region_estimate(const ptl_region_params *pp, double depth) {
  const dm_region_params *p = (const dm_region_params *)pp;
  long n[3];
  lattice_counts(p, depth, n);
  const double d = p->horizon;
  const double members = p->dim == 2 ? M_PI * d * d : 4.0 / 3.0 * M_PI * d * d * d;
  ptl_region_estimate est = {(double)n[0] * (double)n[1] * (double)n[2],
                             400.0 + 16.0 * members + 392.0 + 100.0 + 25.0,
                             p->at_r0 ? p->at_r0 : p->at};
  return est;
}

/* ---------------------------------------------------------------------------------------- */
/* The piston                                                                                 */

static void piston_reserve(piston *q, size_t n) {
  if (n <= q->cap) return;
  q->t = realloc(q->t, n * sizeof *q->t);
  q->u = realloc(q->u, n * sizeof *q->u);
  q->cum = realloc(q->cum, n * sizeof *q->cum);
  if (!q->t || !q->u || !q->cum) {
    fprintf(stderr, "mscale: out of memory (piston history)\n");
    abort();
  }
  q->cap = n;
}

static void piston_integrate(piston *q) {
  q->k = 0;
  if (q->n) q->cum[0] = 0.0;
  for (size_t k = 1; k < q->n; k++)
    q->cum[k] = q->cum[k - 1] + 0.5 * (q->u[k] + q->u[k - 1]) * (q->t[k] - q->t[k - 1]);
}

/* ∫ u from t[0] to t (u constant beyond the ends). The cursor makes a run of increasing times
 * O(1) each. */
static double piston_antiderivative(piston *q, double t) {
  if (q->n == 0) return 0.0;
  if (q->n == 1 || t <= q->t[0]) return q->u[0] * (t - q->t[0]);
  const size_t last = q->n - 1;
  if (t >= q->t[last]) return q->cum[last] + q->u[last] * (t - q->t[last]);
  size_t k = q->k < last ? q->k : last - 1;
  while (k > 0 && t < q->t[k]) k--;
  while (k + 1 < last && t >= q->t[k + 1]) k++;
  q->k = k;
  const double dt = q->t[k + 1] - q->t[k], tau = t - q->t[k];
  const double slope = dt > 0 ? (q->u[k + 1] - q->u[k]) / dt : 0.0;
  return q->cum[k] + q->u[k] * tau + 0.5 * slope * tau * tau;
}

/* Mean piston velocity over [a, b]: the driven layer then moves by exactly the history's
 * displacement over the step (dm_fin drifts w by dt·u). */
static double piston_mean(piston *q, double a, double b) {
  return (piston_antiderivative(q, b) - piston_antiderivative(q, a)) / (b - a);
}

/* ---------------------------------------------------------------------------------------- */
/* Building the region                                                                        */

/* Height below the nominal surface of a sine groove profile (0 at the peaks, depth in the
 * valleys), the period fitted to the width as cd_region.c does. */
static double surface_drop(const dm_region_params *p, double width, double y) {
  if (p->surface == SURF_FLAT || !(p->surf_depth > 0)) return 0.0;
  const double lam = width / fmax(1.0, nearbyint(width / p->surf_wavelength));
  return 0.5 * p->surf_depth * (1 - cos(2 * M_PI * y / lam));
}

/* The mirror of the model in the coupling's particle state. */
static void sync_state(dm_region *r) {
  const dm_state *s = &r->s;
  ptl_state *ps = r->ps;
  const bool three = ps->dim == 3;
  for (size_t i = 0; i < s->n; i++) {
    const double *X = &s->X[3 * i], *w = &s->w[3 * i], *u = &s->u[3 * i], *f = &r->f->frc[3 * i];
    ps->x[i] = X[0] + w[0], ps->y[i] = X[1] + w[1];
    ps->vx[i] = u[0], ps->vy[i] = u[1];
    ps->fx[i] = f[0], ps->fy[i] = f[1];
    if (three) ps->z[i] = X[2] + w[2], ps->vz[i] = u[2], ps->fz[i] = f[2];
  }
}

static void region_free(dm_region *r) {
  dm_fin_destroy(&r->f);
  dm_model_destroy(&r->m);
  dm_state_free(&r->s);
  ptl_state_destroy(&r->ps);
  free(r->imat), free(r->link_start), free(r->link_nbr);
  free(r->pis.t), free(r->pis.u), free(r->pis.cum);
  dm_columns_destroy(&r->cols);
  free(r);
}

static ms_status region_create(const ptl_region_params *pp, const ms_ctx *ctx, const eos_t *eos,
                               double x_drive, double depth, ptl_region **out) {
  const dm_region_params *p = (const dm_region_params *)pp;
  const int dim = (int)p->dim;
  const double h = p->h, rho0 = eos_rho0(eos), e0 = eos_e0(eos);
  const double c0 = eos_sound_speed(eos, rho0, e0);
  if (!(c0 > 0) || !isfinite(c0)) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: the sample's EOS has no sound speed at rho0");
    return MS_ERR_INPUT;
  }
  long n[3];
  lattice_counts(p, depth, n);
  const double width = (double)n[1] * h, width_z = dim == 3 ? (double)n[2] * h : 0.0;
  const double x_top = x_drive + (double)n[0] * h, vol = pow(h, dim), mass = rho0 * vol;
  dm_region *r = ms_calloc(1, sizeof *r);
  /* the lattice, cut by the profile: count first, then fill */
  size_t cnt = 0;
  long min_col = n[0];
  for (int pass = 0; pass < 2; pass++) {
    for (long iz = 0; iz < n[2]; iz++)
      for (long iy = 0; iy < n[1]; iy++) {
        const double y = (iy + 0.5) * h, z = dim == 3 ? (iz + 0.5) * h : 0.0;
        const double top = x_top - surface_drop(p, width, y);
        long col = 0;
        for (long ix = 0; ix < n[0]; ix++) {
          const double x = x_drive + (ix + 0.5) * h;
          if (x > top) break;
          col++;
          if (pass == 0) {
            cnt++;
            continue;
          }
          const size_t i = r->s.n++;
          double *X = &r->s.X[3 * i];
          X[0] = x, X[1] = y, X[2] = z;
          r->s.mass[i] = mass, r->s.vol[i] = vol;
          r->s.K[i] = rho0 * c0 * c0, r->s.G[i] = p->G;
          const bool driven = ix < p->piston_layers;
          r->s.bc[i] = driven ? DM_PRESCRIBED : DM_FREE;
          size_t j = ptl_state_add(r->ps, x, y, z, mass, 0);
          r->ps->gid[j] = (int64_t)j;
          if (driven) r->ps->flags[j] |= PTL_DRIVEN;
          else if (x > top - h) r->ps->flags[j] |= PTL_SURFACE;
        }
        if (col < min_col) min_col = col;
      }
    if (pass == 0) {
      if (min_col < p->piston_layers + 2) {
        ms_log(ctx, MS_LOG_ERROR,
               "coupled: particles: the surface profile (depth %g cm) leaves %ld layers in a "
               "column of the %ld-layer slab: it needs the piston's %ld and 2 more",
               p->surf_depth, min_col, n[0], p->piston_layers);
        free(r);
        return MS_ERR_INPUT;
      }
      dm_state_alloc(&r->s, cnt, dim);
      r->s.n = 0;
      ms_must(ptl_state_create(&(ptl_state_params){.cap = cnt, .dim = dim}, &r->ps),
              "ptl_state_create");
    }
  }
  dm_options opt = {.horizon = p->horizon * h, .cond_max = p->cond_max};
  opt.box[1] = width;
  if (dim == 3) opt.box[2] = width_z;
  size_t first_bad = (size_t)-1;
  ms_status st = dm_model_create(
      &(dm_model_params){.state = &r->s, .opt = opt, .ctx = ctx, .first_bad = &first_bad}, &r->m);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR,
           "coupled: particles: the discrete model's families cannot be built (a surface profile "
           "too steep for the horizon leaves particles with too few neighbours?)");
    region_free(r);
    return st;
  }
  r->mat =
      (dm_fin_material){.eos = eos, .yield = p->yield, .G = p->G, .Y0 = p->Y0, .frac = p->frac};
  if (p->yield >= DM_YIELD_STEINBERG_GUINAN) {
    r->mat.sg = &p->sg; /* the parameters outlive the region (the deck's) */
    if (!isfinite(dm_sg_temperature(&p->sg, eos, rho0, e0))) {
      ms_log(ctx, MS_LOG_ERROR,
             "coupled: particles: yield: %s takes the temperature from the EOS's "
             "cold curve, and the sample's EOS (%s) has none",
             yield_names[p->yield], eos_kind_name(eos_get_kind(eos)));
      region_free(r);
      return MS_ERR_INPUT;
    }
  }
  r->imat = ms_calloc(r->s.n, 1);
  const dm_fin_params par = {.cq = p->cq,
                             .cl = p->cl,
                             .courant = p->courant,
                             .hourglass = p->hourglass,
                             .ell = h,
                             .contact = p->contact};
  st =
      dm_fin_create(&(dm_fin_setup){.m = r->m, .mat = &r->mat, .imat = r->imat, .par = par}, &r->f);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "coupled: particles: the discrete model's initial state is invalid");
    region_free(r);
    return st;
  }
  /* the fixed step: a margin below the model's limit at rest, for the compression to come.
   * The limit courant·ℓ/(c_L + 2(C_q ℓ|tr D| + C_l c)) falls under compression as c grows, ℓ
   * shrinks and the front's |tr D| adds viscosity: for Al at u_p = 0.5 km/s (c ≈ 6.7 km/s,
   * ℓ/h ≈ 0.96 in 2D, |tr D| ≈ u_p/(5 h)) by ≈ 1.35, so dt_margin 0.5 leaves room up to
   * a 2 km/s piston without sub-cycling (docs/particles-dm.md); beyond, and in stretching jet
   * tips, region_step sub-cycles. */
  r->link_start = ms_calloc(r->s.n + 1, sizeof *r->link_start);
  r->link_nbr = ms_calloc(r->m->nbonds + 1, sizeof *r->link_nbr);
  r->dt0_limit = r->f->dt_next;
  r->ref_threshold = p->ref_threshold;
  r->dt = p->dt_margin * r->dt0_limit;
  r->pis.dir[0] = 1.0;
  piston_reserve(&r->pis, 2);
  r->pis.n = 1, r->pis.t[0] = 0.0, r->pis.u[0] = 0.0;
  piston_integrate(&r->pis);
  sync_state(r);
  r->geo = (ptl_region_geometry){.dim = dim,
                                 .spacing = h,
                                 .rho0 = rho0,
                                 .c0 = eos_c0(eos),
                                 .x_drive = x_drive,
                                 .x_top = x_top,
                                 .surface_depth = p->surface != SURF_FLAT ? p->surf_depth : 0.0,
                                 .period = {0.0, width, width_z},
                                 .area = dim == 3 ? width * width_z : width, /* 2D: 1 cm thick */
                                 .dt = r->dt,
                                 .particles = r->s.n};
  ms_log(ctx, MS_LOG_INFO,
         "coupled: particles: discrete model (response eos, yield %s), %dD simple %s lattice, "
         "h = %g cm, horizon %g h, %zu particles (%ld x %ld x %ld), %zu bonds, region %g..%g cm "
         "(grid: %g..%g), width %g cm, surface %s (depth %g cm); fixed dt = %g (%g x the limit "
         "%g at rest)",
         yield_names[p->yield], dim, dim == 3 ? "cubic" : "square", h, p->horizon, r->s.n, n[0],
         n[1], n[2], r->m->nbonds, x_drive, x_top, x_drive, x_drive + depth, width,
         surface_names[p->surface], p->surf_depth, r->dt, p->dt_margin, r->dt0_limit);
  *out = &r->base;
  return MS_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* The interface's calls                                                                      */

static dm_region *dmr(ptl_region *r) { return (dm_region *)r; }
static const dm_region *cdmr(const ptl_region *r) { return (const dm_region *)r; }

static void region_destroy(ptl_region *r) { region_free(dmr(r)); }
static ptl_region_geometry region_geometry(const ptl_region *r) { return cdmr(r)->geo; }
static ptl_state *region_state(ptl_region *r) { return dmr(r)->ps; }
static double region_time(const ptl_region *r) { return cdmr(r)->t; }

static void region_set_piston(ptl_region *rr, size_t n, const double *t, const double *u,
                              const double dir[3]) {
  piston *q = &dmr(rr)->pis;
  dm_columns_destroy(&dmr(rr)->cols);
  piston_reserve(q, n < 2 ? 2 : n);
  q->n = n;
  memcpy(q->t, t, n * sizeof *t);
  memcpy(q->u, u, n * sizeof *u);
  for (int a = 0; a < 3; a++) q->dir[a] = dir[a];
  piston_integrate(q);
}

static void region_hold_piston(ptl_region *rr, double u, double span) {
  dm_region *r = dmr(rr);
  piston *q = &r->pis; /* capacity ≥ 2 since create: nothing is allocated here */
  dm_columns_destroy(&r->cols);
  q->n = 2;
  q->t[0] = r->t, q->t[1] = r->t + span;
  q->u[0] = q->u[1] = u;
  piston_integrate(q);
}

/* The piston by columns (ptl_region.h): the driven particles' weights by their reference y. */
static ms_status region_set_piston_columns(ptl_region *rr, size_t ncol, const double *ycol,
                                           size_t n, const double *t, const double *ux,
                                           const double *uy) {
  dm_region *r = dmr(rr);
  dm_columns *c = NULL;
  const ms_status st = dm_columns_create(ncol, ycol, n, t, ux, uy, &r->s, &c);
  if (st != MS_OK) return st;
  dm_columns_destroy(&r->cols);
  r->cols = c;
  return MS_OK;
}

static void region_set_dt(ptl_region *r, double dt) { dmr(r)->dt = dt; }

/* On MPI ranks the region is replicated: every rank steps all particles, bit for bit the same
 * (the step is deterministic and thread-count independent); rank 0 owns them for the coupling
 * (fragments, snapshots, the driven-layer force, checkpoints), the others show an empty view.
 * The coupling's velocity kicks (drag) reach the owner only, so region_step takes rank 0's
 * velocities first. Cost: the serial region's time on every rank (docs/particles-dm.md). */
static void region_distribute(ptl_region *rr, const ms_ctx *ctx) {
  dm_region *r = dmr(rr);
  r->rank = ctx->rank, r->nranks = ctx->size;
  if (r->rank > 0) r->ps->n = r->ps->nlocal = 0;
}

/* The forces at t = 0 were computed by dm_fin_create. */
static ms_status region_init(ptl_region *r) {
  sync_state(dmr(r));
  return MS_OK;
}

/* The particle view's velocities, which the coupling may have changed since the step (drag
 * kicks), back into the model's free particles (u is the model's array, not the region's). */
static void take_view_velocities(const dm_region *r) {
  const ptl_state *ps = r->ps;
  double *u = r->s.u;
  for (size_t i = 0; i < r->s.n; i++)
    if (r->s.bc[i] != DM_PRESCRIBED) {
      u[3 * i] = ps->vx[i], u[3 * i + 1] = ps->vy[i];
      if (ps->dim == 3) u[3 * i + 2] = ps->vz[i];
    }
}

/* After a model step: the families whose bonds stretched past 1 + threshold get their own
 * references (dm_fin_rebase_local); a refusal (a degenerate family) stops the run. */
static ms_status region_rebase(dm_region *r) {
  if (!(r->ref_threshold > 0)) return MS_OK;
  dm_refamily_report rep;
  const ms_status st = dm_fin_rebase_local(r->f, NULL, r->ref_threshold, false, &rep);
  if (st != MS_OK) {
    const size_t b = rep.bad < r->s.n ? rep.bad : 0;
    snprintf(r->err, sizeof r->err,
             "discrete model: model step %ld, t = %.9g: the reference update is refused: particle "
             "%zu (X = %g %g %g) would have a degenerate family",
             r->f->step, r->t, b, r->s.X[3 * b], r->s.X[3 * b + 1], r->s.X[3 * b + 2]);
  }
  return st;
}

static ms_status region_step(ptl_region *rr) {
  dm_region *r = dmr(rr);
  dm_state *s = &r->s;
  const ptl_state *ps = r->ps;
  const bool three = ps->dim == 3;
  const double dt = r->dt;
  /* velocities the coupling changed (drag kicks) back into the model; the driven layer moves
   * with the piston's mean velocity over the step */
  const double up = piston_mean(&r->pis, r->t, r->t + dt);
  if (r->nranks > 1) {
    par_bcast_doubles(r->ps->vx, s->n, 0);
    par_bcast_doubles(r->ps->vy, s->n, 0);
    if (three) par_bcast_doubles(r->ps->vz, s->n, 0);
  }
  take_view_velocities(r);
  if (r->cols) dm_columns_drive(r->cols, r->t, r->t + dt, s);
  else
    for (size_t i = 0; i < s->n; i++)
      if (s->bc[i] == DM_PRESCRIBED)
        for (int a = 0; a < 3; a++) s->u[3 * i + a] = a < s->dim ? up * r->pis.dir[a] : 0.0;
  /* Sub-cycling: the coupled loop's step dt is fixed (dt_margin × the limit at rest), but the
   * model's own limit falls under compression and in stretching jet tips. The rest of the step
   * is split into k equal sub-steps, k = ⌈rest / limit⌉, with the limit of the current state
   * (dm_fin's forces of the last sub-step; checkpointed as dt_next): each sub-step then obeys
   * the explicit stability condition at its start, as the grid's own step does, and the
   * coupled step, its outputs and its piston velocity are unchanged. Bounded by
   * DM_REGION_MAX_SUBSTEPS: a limit that keeps falling is an instability, reported. */
  double rest = dt;
  long nsub = 0;
  while (rest > 0.0) {
    const double limit = r->f->dt_next;
    const double k = ceil(rest / limit * (1.0 - 1e-12));
    if (!(k >= 1.0) || nsub + (long)k > DM_REGION_MAX_SUBSTEPS) {
      const size_t i = r->f->dt_particle; /* where the limit is smallest (dm_fin's forces) */
      snprintf(r->err, sizeof r->err,
               "discrete model: model step %ld, t = %.9g: the stable step %.6g would need more "
               "than %d sub-steps of the coupled step %.6g (limiting particle %zu at X = %g %g "
               "%g: rho = %g, p = %g GPa, q = %g GPa); the limit at rest was %.6g",
               r->f->step, r->t, limit, DM_REGION_MAX_SUBSTEPS, dt, i, s->X[3 * i], s->X[3 * i + 1],
               s->X[3 * i + 2], r->f->rho[i], r->f->p[i], r->f->q[i], r->dt0_limit);
      sync_state(r);
      return MS_ERR_UNSTABLE;
    }
    const double h = k > 1.0 ? rest / k : rest;
    r->f->dt_next = h;
    ms_status st = dm_fin_step(r->f);
    nsub++;
    rest = k > 1.0 ? rest - h : 0.0;
    if (st != MS_OK) {
      r->t += dt - rest;
      sync_state(r);
      const double *X = &s->X[3 * r->f->bad];
      snprintf(r->err, sizeof r->err,
               "discrete model: model step %ld, t = %.9g: particle %zu (X = %g %g %g): %s = %g",
               r->f->step, r->t, r->f->bad, X[0], X[1], X[2], r->f->bad_what, r->f->bad_value);
      return MS_ERR_UNSTABLE;
    }
    if ((st = region_rebase(r)) != MS_OK) {
      r->t += dt - rest;
      sync_state(r);
      return st;
    }
  }
  r->t += dt;
  sync_state(r);
  return MS_OK;
}

static const char *region_error(const ptl_region *r) { return cdmr(r)->err; }

/* Σ f_x on the driven layer: dm_fin's gather computes every particle's force, the driven ones'
 * included (their reaction, which also enters the piston work). */
static double region_driven_force(const ptl_region *rr) {
  const dm_region *r = cdmr(rr);
  double f = 0;
  if (r->rank > 0) return 0.0; /* the drivers sum it over ranks; the owner's is the whole */
  for (size_t i = 0; i < r->s.n; i++)
    if (r->s.bc[i] == DM_PRESCRIBED) f += r->f->frc[3 * i];
  return f;
}

static double region_free_surface_velocity(const ptl_region *rr) {
  const dm_region *r = cdmr(rr);
  double sum = 0;
  size_t cnt = 0;
  for (size_t i = 0; i < r->s.n; i++)
    if (r->ps->flags[i] & PTL_SURFACE) sum += r->s.u[3 * i], cnt++;
  return cnt ? sum / (double)cnt : 0.0;
}

/* kinetic (free particles), potential = internal Σ m e + bond-penalty energy + the contact
 * energy of failed particles, broken (the penalty energy of failed particles, dm_fracture.c),
 * piston work W; total = K + potential + broken − W,
 * conserved to round-off by dm_fin (docs/particles-dm.md "Energy identity") except for what the
 * coupling's kicks add. */
static void region_energy(ptl_region *rr, ptl_region_energy *out) {
  const dm_region *r = dmr(rr);
  double K, U, H;
  dm_fin_energies(r->f, &K, &U, &H);
  memset(out, 0, sizeof *out);
  out->kinetic = K;
  out->potential = U + H + dm_fin_contact_energy(r->f); /* contact: failed particles' springs */
  out->piston_work = r->f->work;
  out->broken = dm_fin_broken_energy(r->f);
  out->total = K + U + H + dm_fin_contact_energy(r->f) + out->broken - r->f->work;
  for (size_t i = 0; i < r->s.n; i++)
    if (r->s.bc[i] == DM_FREE)
      for (int a = 0; a < 3; a++) out->momentum[a] += r->s.mass[i] * r->s.u[3 * i + a];
}

/* Failures by cause (dm_fracture.c's counters); false without a fracture model. */
static bool region_failures(const ptl_region *rr, long count[3]) {
  const dm_fin *f = cdmr(rr)->f;
  if (!f->failed) return false;
  count[0] = f->nfail_stress, count[1] = f->nfail_isolated, count[2] = f->nfail_degenerate;
  return true;
}

/* The fragments' connectivity: every bond of the families but the broken ones (both particles
 * failed, dm_fracture.c), so a slab is one fragment until it breaks, however far its spike
 * tips stretch. Particle i of the model is particle i of the view (on ranks > 0 the view is
 * empty and nothing is read). */
static bool region_links(ptl_region *rr, const size_t **start, const int32_t **nbr) {
  dm_region *r = dmr(rr);
  const dm_model *m = r->m;
  size_t q = 0;
  for (size_t i = 0; i < r->s.n; i++) {
    r->link_start[i] = q;
    for (size_t b = m->start[i]; b < m->start[i + 1]; b++)
      if (!dm_fin_bond_broken(r->f, i, m->nbr[b])) r->link_nbr[q++] = (int32_t)m->nbr[b];
  }
  r->link_start[r->s.n] = q;
  *start = r->link_start, *nbr = r->link_nbr;
  return true;
}

static void region_refresh_ghosts(ptl_region *r) { (void)r; } /* serial: no ghosts */
static void region_ghost_owners(const ptl_region *r, int32_t *owner) {
  (void)r;
  (void)owner;
}

static ms_status region_write_snapshot(ptl_region *rr, const char *path, const char *material) {
  dm_region *r = dmr(rr);
  if (r->rank > 0) return MS_OK; /* replicated: the owner writes */
  const ptl_state *ps = r->ps;
  const dm_fin *f = r->f;
  int64_t *mat = ms_calloc(r->s.n + 1, sizeof *mat); /* one material: 0 */
  /* fracture: the failed flags (1: failed; its p is the contact pressure, ρ and J held from the
   * failure, dm_fracture.c) */
  int64_t *failed = f->failed ? ms_calloc(r->s.n + 1, sizeof *failed) : NULL;
  for (size_t i = 0; failed && i < r->s.n; i++) failed[i] = f->failed[i];
  const ptl_snapshot_data data[] = {{"particles/material", NULL, mat, 1, NULL},
                                    {"particles/pressure", f->p, NULL, 1, "GPa"},
                                    {"particles/density", f->rho, NULL, 1, "g/cm^3"},
                                    {"particles/energy", f->e, NULL, 1, "kJ/g"},
                                    {"particles/J", f->J, NULL, 1, "1"},
                                    {"particles/gid", NULL, ps->gid, 1, NULL},
                                    {"particles/failed", NULL, failed, 1, NULL}};
  const ms_xdmf_attr xdmf[] = {{"velocity", "particles/v", 3, false},
                               {"pressure", "particles/pressure", 1, false},
                               {"density", "particles/density", 1, false},
                               {"mass", "particles/mass", 1, false}};
  ptl_snapshot snap = ptl_snapshot_of_state(ps, r->s.n, r->t, false);
  ptl_snapshot_contents(&snap, sizeof data / sizeof data[0] - (failed ? 0 : 1), data,
                        sizeof xdmf / sizeof xdmf[0], xdmf, material, f->step);
  ptl_snapshot_attr_add(&snap, "r0", r->geo.spacing);
  ptl_snapshot_period_add(&snap, 1, r->geo.period[1], 0.0);
  if (ps->dim == 3) ptl_snapshot_period_add(&snap, 2, r->geo.period[2], 0.0);
  const ms_status st = ptl_write_snapshot(path, &snap);
  free(mat), free(failed);
  return st;
}

static ms_status region_refresh(ptl_region *r) {
  (void)r;
  return MS_OK;
}

/* The model's state (dm_fin_checkpoint.c) and the region's clock; the particle view's
 * velocities replace u, since the coupling may have kicked them (drag) since the step. The
 * piston needs nothing: the drivers hold it again before every step. */
static ms_status region_checkpoint_write(const ptl_region *rr, ms_h5 *h, const ms_ctx *ctx) {
  const dm_region *r = cdmr(rr);
  if (r->ref_threshold > 0) /* the families' own references are not in /dm (not yet) */
    return ms_log(ctx, MS_LOG_ERROR, "coupled: particles: no checkpoint with reference_update"),
           MS_ERR_INPUT;
  const ptl_state *ps = r->ps;
  take_view_velocities(r); /* what the next step would take, so the checkpoint holds it */
  ms_status st = dm_fin_checkpoint_write(r->f, &r->s, h, "/dm", r->rank == 0);
  int64_t *flags = ms_calloc(r->s.n + 1, sizeof *flags);
  for (size_t i = 0; i < r->s.n; i++) flags[i] = ps->flags[i];
  if (st == MS_OK) st = ms_h5_write_ints_dist(h, "/dm/flags", r->rank == 0 ? r->s.n : 0, flags);
  free(flags);
  if (st == MS_OK) st = ms_h5_attr_double(h, "/dm/flags", "t", r->t);
  if (st == MS_OK) st = ms_h5_attr_double(h, "/dm/flags", "dt", r->dt);
  return st;
}

static ms_status region_restore(ptl_region *rr, ms_h5r *h, const ms_ctx *ctx, long *step,
                                dk_errors *e) {
  (void)ctx;
  dm_region *r = dmr(rr);
  ms_status st = dm_fin_checkpoint_read(r->f, &r->s, h, "/dm", e);
  int64_t *flags = NULL;
  size_t nr = 0, nc = 0;
  if (st == MS_OK) st = ms_h5_read_ints_rows(h, "/dm/flags", 0, SIZE_MAX, &flags, &nr, &nc, e);
  if (st == MS_OK && nr != r->s.n) {
    dk_error_at(e, "checkpoint", 0, 0, "'/dm/flags' has %zu particles, this region %zu", nr,
                r->s.n);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK)
    for (size_t i = 0; i < nr; i++) r->ps->flags[i] = (uint8_t)flags[i];
  free(flags);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/dm/flags", "t", &r->t, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, "/dm/flags", "dt", &r->dt, e);
  if (st != MS_OK) return st;
  r->geo.dt = r->dt;
  sync_state(r);
  *step = r->f->step;
  return MS_OK;
}

static const ptl_region_model dm_region_model = {
    .name = "discrete_model",
    .read = region_read,
    .params_destroy = region_params_destroy,
    .notes = region_notes,
    .estimate = region_estimate,
    .create = region_create,
    .destroy = region_destroy,
    .geometry = region_geometry,
    .state = region_state,
    .time = region_time,
    .set_piston = region_set_piston,
    .hold_piston = region_hold_piston,
    .set_piston_columns = region_set_piston_columns,
    .set_dt = region_set_dt,
    .distribute = region_distribute,
    .init = region_init,
    .step = region_step,
    .error = region_error,
    .driven_force = region_driven_force,
    .free_surface_velocity = region_free_surface_velocity,
    .energy = region_energy,
    .refresh_ghosts = region_refresh_ghosts,
    .ghost_owners = region_ghost_owners,
    .links = region_links,
    .failures = region_failures,
    .write_snapshot = region_write_snapshot,
    .refresh = region_refresh,
    .checkpoint_write = region_checkpoint_write,
    .restore = region_restore,
};

const ptl_region_model *dm_region_model_get(void) { return &dm_region_model; }
