/* SPDX-License-Identifier: MIT */
/* jets.c — one Richtmyer–Meshkov jet case on the discrete model's particle region (jets.h).
 *
 * Geometry (particles/dm/dm_region.c): a simple-square lattice of spacing h from the drive face
 * x = 0 to the groove peaks x_top, one groove wavelength λ = ncol h wide (periodic), the sine
 * profile x_top − h0 (1 − cos k y) cutting it: peaks at y = 0, valleys at y = λ/2. The first two
 * layers are the piston, driven at a constant u_p. At a free surface (Atwood number −1) the
 * groove inverts after breakout and the valley grows into a spike (jet), the peak into a bubble.
 *
 * Measured from the particles (no fragments, no bonds broken):
 *   x_valley, x_peak  the mean x of the surface particles of the two columns either side of
 *            the valley and of the peak centre: after the inversion the spike's leading
 *            particles on its axis, and the bubble (the trace's x_bubble);
 *   η        (x_valley − x_peak)/2: −a0⁺ once the shock has passed, through 0 at the inversion,
 *            then the spike–bubble amplitude (its second harmonic cancels);
 *   x_spike  the largest x of the particles that started in the valley half |y − λ/2| < λ/4
 *            (the foremost particle, on or off the axis);
 *   x_fs, u_fs  the flat strip's free-surface position and velocity (the same drive and depth,
 *            5 columns): the bulk free surface the spike is measured against.
 * Over the fit window [t_b + fit_from λ/U_s, t_b + fit_to λ/U_s], t_b the flat strip's
 * breakout, the least-squares slopes of x_valley − x_fs (v_spike, the spike tip's velocity
 * over the free surface), of x_spike − x_fs (v_spike_max) and of η (v_eta) are compared with
 * Richtmyer's impulsive estimate k a0⁺ Δu [Richtmyer1960], a0⁺ = a0 (1 − u_p/U_s) and Δu the
 * flat surface's mean velocity over the window, as [Buttler2012] apply it to metals; a0 is the
 * cut lattice's amplitude (classify). The jet's tip is also measured by leading mass and by
 * cluster (jets_tip.c), every step, as absolute slopes over the window (fit_window). */
#include "jets.h"

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

double jets_slope(const double *t, const double *y, long n) {
  double st = 0, sy = 0;
  for (long i = 0; i < n; i++) st += t[i], sy += y[i];
  st /= (double)n, sy /= (double)n;
  double num = 0, den = 0;
  for (long i = 0; i < n; i++) num += (t[i] - st) * (y[i] - sy), den += (t[i] - st) * (t[i] - st);
  return den > 0 ? num / den : NAN;
}

/* The region from a `particles:` section written as the coupled deck would give it, without the
 * short-range contact (contact_distance 0; dm_contact.c): the sweep of docs/validation.md
 * "Microjets" was measured without it, and it measures the early growth of intact material,
 * before a groove's flanks converge (with it test_dm_jets took over its 300 s). */
static ms_status build(const jets_case *c, double width, bool grooved, double depth, double us,
                       double t_end, ptl_region **out, ptl_region_params **pp_out,
                       dk_doc **doc_out) {
  char text[1024];
  const double lambda = (double)c->ncol * c->h, h0 = c->kh0 * lambda / (2 * M_PI);
  int len = snprintf(text, sizeof text,
                     "particles:\n  r0: %.17g\n  width: %.17g\n  dt_margin: %.17g\n"
                     "  contact_distance: 0\n",
                     c->h, width, c->dt_margin);
  if (c->Y > 0)
    len += snprintf(text + len, sizeof text - (size_t)len,
                    "  yield: elastic_plastic\n  shear_modulus: %.17g\n  yield_stress: %.17g\n",
                    c->G, c->Y);
  else if (c->strength_set)
    len += snprintf(text + len, sizeof text - (size_t)len,
                    "  yield: steinberg_guinan\n  strength_set: %s\n", c->strength_set);
  if (c->visc_linear > 0)
    len += snprintf(text + len, sizeof text - (size_t)len, "  viscosity: {linear: %.17g}\n",
                    c->visc_linear);
  if (c->spall_strength > 0)
    len += snprintf(text + len, sizeof text - (size_t)len,
                    "  fracture: {model: mean_stress, spall_strength: %.17g}\n", c->spall_strength);
  if (c->hourglass > 0)
    len += snprintf(text + len, sizeof text - (size_t)len, "  hourglass: %.17g\n", c->hourglass);
  if (c->ref_threshold > 0)
    len += snprintf(text + len, sizeof text - (size_t)len,
                    "  reference_update: {threshold: %.17g}\n", c->ref_threshold);
  if (grooved)
    snprintf(text + len, sizeof text - (size_t)len,
             "  surface: {profile: sine, depth: %.17g, wavelength: %.17g}\n", 2 * h0, lambda);
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, "jets.yaml", &e);
  ptl_region_params *pp = NULL;
  if (doc)
    pp = ptl_region_params_read(ptl_region_model_find("discrete_model"), doc,
                                dk_get(dk_root(doc), "particles"), &e);
  if (e.n || !pp) {
    dk_errors_print(&e, stderr);
    dk_errors_free(&e);
    ptl_region_params_destroy(&pp);
    dk_free(doc);
    return MS_ERR_INPUT;
  }
  dk_errors_free(&e);
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.verbosity = MS_LOG_WARN;
  ms_status st = ptl_region_create(pp, &ctx, c->eos, 0.0, depth, out);
  ms_ctx_close(&ctx);
  if (st != MS_OK) {
    ptl_region_params_destroy(&pp);
    dk_free(doc);
    return st;
  }
  /* the drive: held at u_p, or u_p exp(−t/τ) sampled at 257 points over the run (piecewise
   * linear between them: relative error (Δt/τ)²/8 < 1e-4 for τ ≥ t_end/25) */
  enum { NDRIVE = 257 };
  double t[NDRIVE], u[NDRIVE];
  const double dir[3] = {1, 0, 0}, tau = c->decay * (double)c->ncol * c->h / us;
  const size_t nd = c->decay > 0 ? NDRIVE : 1;
  for (size_t k = 0; k < nd; k++) {
    t[k] = nd > 1 ? t_end * (double)k / (double)(nd - 1) : 0.0;
    u[k] = c->decay > 0 ? c->up * exp(-t[k] / tau) : c->up;
  }
  ptl_region_set_piston(*out, nd, t, u, dir);
  *pp_out = pp;
  *doc_out = doc;
  return ptl_region_init(*out);
}

static void release(ptl_region **r, ptl_region_params **pp, dk_doc **doc) {
  ptl_region_destroy(r);
  ptl_region_params_destroy(pp);
  dk_free(*doc);
  *doc = NULL;
}

/* The flat strip: its surface position and velocity at every step. */
static ms_status run_flat(const jets_case *c, double depth, double t_end, long nsteps, double *x_fs,
                          double *u_fs, double *dt, jets_result *r) {
  ptl_region *reg = NULL;
  ptl_region_params *pp = NULL;
  dk_doc *doc = NULL;
  /* 5 columns: the least width for horizon 1.5 (3 horizons = 4.5 h) */
  ms_status st = build(c, 5 * c->h, false, depth, r->us, t_end, &reg, &pp, &doc);
  if (st != MS_OK) return st;
  *dt = ptl_region_get_geometry(reg).dt;
  const ptl_state *ps = ptl_region_state(reg);
  r->t_break = NAN;
  for (long k = 0; k < nsteps && st == MS_OK; k++) {
    st = ptl_region_step(reg);
    double sx = 0;
    long ns = 0;
    for (size_t i = 0; i < ps->n; i++)
      if (ps->flags[i] & PTL_SURFACE) sx += ps->x[i], ns++;
    x_fs[k] = sx / (double)ns;
    u_fs[k] = ptl_region_free_surface_velocity(reg);
    if (isnan(r->t_break) && u_fs[k] >= c->up) r->t_break = (double)(k + 1) * *dt;
  }
  if (c->decay > 0) { /* the half-rise to the surface's largest velocity (that of breakout) */
    double umax = 0;
    for (long k = 0; k < nsteps; k++) umax = fmax(umax, u_fs[k]);
    r->t_break = NAN;
    for (long k = 0; k < nsteps && isnan(r->t_break); k++)
      if (u_fs[k] >= 0.5 * umax) r->t_break = (double)(k + 1) * *dt;
  }
  if (st != MS_OK) snprintf(r->err, sizeof r->err, "flat strip: %s", ptl_region_error(reg));
  release(&reg, &pp, &doc);
  return st;
}

/* Which particles make the spike and the bubble, from their positions at t = 0: role 1 = the
 * valley half |y − λ/2| < λ/4 (where the tip is looked for), role 2 | 4 = the surface particles
 * of the two columns either side of the valley centre, role 8 = those either side of the peak
 * centre (η); and the staircase's fundamental amplitude. */
static void classify(const ptl_state *ps, double lambda, double k, double h, uint8_t *role,
                     double *a0) {
  double c1 = 0;
  long ns = 0;
  for (size_t i = 0; i < ps->n; i++) {
    const double dy = fabs(ps->y[i] - 0.5 * lambda); /* 0 at the valley, λ/2 at the peaks */
    role[i] = 0;
    if (ps->flags[i] & PTL_DRIVEN) continue;
    if (dy < 0.25 * lambda) role[i] |= 1;
    if (ps->flags[i] & PTL_SURFACE) {
      if (dy < h) role[i] |= 4;                       /* the columns at λ/2 ± h/2 */
      if (dy > 0.5 * lambda - h) role[i] |= 8;        /* at ± h/2 around y = 0 (periodic) */
      c1 += (ps->x[i] + 0.5 * h) * cos(k * ps->y[i]); /* the body ends h/2 beyond the layer */
      ns++;
    }
  }
  *a0 = 2 * c1 / (double)ns; /* x_top − h0 (1 − cos ky): the cosine coefficient is h0 */
}

/* The weakly nonlinear impulsive theory of a free surface (Atwood number −1; [VelikovichDimonte1996;
 * ZhangSohn1997], derived for this case in docs/validation.md "Microjets"): incompressible,
 * irrotational, pressure-free surface, the first harmonic η cos ky with η̇ constant; to second
 * order the surface is η cos ky + (k/2)(η² − η_b²) cos 2ky, so the spike (on the valley's axis)
 * sits at η + (k/2)(η² − η_b²) and the bubble at −η + (k/2)(η² − η_b²) from the mean surface,
 * their velocities η̇ (1 ± k η). From the measured η, over [k0, k1): the predicted spike and
 * bubble positions (up to the constant −(k/2) η_b², which no slope sees). */
static void nl_prediction(const jets_result *r, const double *eta, double eta_b, long k0, long k1,
                          double *spike, double *bubble) {
  for (long k = k0; k < k1; k++) {
    const double h2 = 0.5 * r->k * (eta[k] * eta[k] - eta_b * eta_b);
    spike[k] = eta[k] + h2, bubble[k] = -eta[k] + h2;
  }
}

/* The histories of one grooved run, one entry per step (jets_run). */
typedef struct jets_hist {
  double *x_fs, *u_fs, *tt, *xs, *eta, *vt, *rel, *relb, *nl, *nlb, *xtip;
  double *x_m[JETS_TIP_NFRAC], *v_m[JETS_TIP_NFRAC], *x_main;
  jets_tip_sample last; /* at the fit window's end */
} jets_hist;

enum { JETS_NHIST = 12 + 2 * JETS_TIP_NFRAC };

static double *hist_alloc(jets_hist *h, long nsteps) {
  double *buf = malloc(JETS_NHIST * (size_t)nsteps * sizeof *buf);
  if (!buf) return NULL;
  double **a[JETS_NHIST] = {&h->x_fs, &h->u_fs, &h->tt, &h->xs,  &h->eta,  &h->vt,
                            &h->rel,  &h->relb, &h->nl, &h->nlb, &h->xtip, &h->x_main};
  for (int j = 0; j < JETS_TIP_NFRAC; j++) a[12 + 2 * j] = &h->x_m[j], a[13 + 2 * j] = &h->v_m[j];
  for (int j = 0; j < JETS_NHIST; j++) *a[j] = buf + (size_t)j * (size_t)nsteps;
  return buf;
}

static double mean(const double *y, long n) {
  double s = 0;
  for (long k = 0; k < n; k++) s += y[k];
  return s / (double)n;
}

/* The fits over the window [k0, k1) (kb: breakout; n steps run). */
static void fit_window(const jets_case *c, const jets_hist *h, long kb, long k0, long k1, long n,
                       jets_result *r) {
  const long nfit = k1 - k0;
  r->v_lin = r->v_spike = r->v_tip = r->v_eta = r->du = r->v_spike_peak = r->v_spike_late =
      r->v_spike_max = r->v_bubble = r->v_spike_nl = r->v_bubble_nl = r->keta_fit0 = r->keta_fit1 =
          r->deta_end = r->v_tip_slope = r->v_main = r->u_fs_b = r->m_jet_end = NAN;
  for (int j = 0; j < JETS_TIP_NFRAC; j++) r->v_front[j] = r->v_lead[j] = NAN;
  if (nfit >= 10) {
    const double *tt = h->tt + k0;
    r->du = mean(h->u_fs + k0, nfit);
    r->u_fs_b = h->u_fs[k0];
    r->v_tip = mean(h->vt + k0, nfit);
    r->v_spike = jets_slope(tt, h->rel + k0, nfit);
    r->v_spike_max = jets_slope(tt, h->xs + k0, nfit);
    r->v_eta = jets_slope(tt, h->eta + k0, nfit);
    r->v_lin = r->k * r->a0 * (1 - c->up / r->us) * r->du;
    nl_prediction(r, h->eta, kb < n ? h->eta[kb] : h->eta[0], k0, k1, h->nl, h->nlb);
    r->v_bubble = jets_slope(tt, h->relb + k0, nfit);
    r->v_spike_nl = jets_slope(tt, h->nl + k0, nfit);
    r->v_bubble_nl = jets_slope(tt, h->nlb + k0, nfit);
    r->keta_fit0 = r->k * h->eta[k0], r->keta_fit1 = r->k * h->eta[k1 - 1];
    r->deta_end = h->eta[k1 - 1] - (kb < n ? h->eta[kb] : h->eta[0]);
    r->v_tip_slope = jets_slope(tt, h->xtip + k0, nfit);
    r->v_main = jets_slope(tt, h->x_main + k0, nfit);
    for (int j = 0; j < JETS_TIP_NFRAC; j++) {
      r->v_front[j] = jets_slope(tt, h->x_m[j] + k0, nfit); /* NAN while the jet is lighter */
      r->v_lead[j] = mean(h->v_m[j] + k0, nfit);
    }
    r->m_jet_end = h->last.m_jet, r->n_jet_end = h->last.n_jet;
    r->n_clusters_end = h->last.n_clusters, r->n_ahead_end = h->last.n_ahead;
    r->tip_cluster_end = h->last.tip_cluster;
    /* the tip's history: the largest slope over a sliding λ/U_s after breakout, and the slope
     * over the last λ/U_s (a jet held by its neck decelerates) */
    const long w = (long)ceil(r->lambda / r->us / r->dt);
    r->v_spike_peak = -INFINITY;
    for (long k = kb; k + w <= k1; k += w / 8 + 1)
      r->v_spike_peak = fmax(r->v_spike_peak, jets_slope(h->tt + k, h->rel + k, w));
    if (k1 - w >= kb) r->v_spike_late = jets_slope(h->tt + k1 - w, h->rel + k1 - w, w);
  }
  if (kb < n) {
    r->eta_b = h->eta[kb];
    long kmax = kb;
    for (long k = kb; k < n; k++)
      if (h->eta[k] > h->eta[kmax]) kmax = k;
    r->deta_max = h->eta[kmax] - r->eta_b;
    r->t_eta_max = h->tt[kmax] - r->t_break;
    r->arrested = kmax < kb + (long)(0.9 * (double)(n - kb));
  }
  r->spike_len = n ? 2 * h->eta[n - 1] : 0;
}

static void trace_head(FILE *trace, const jets_case *c, const jets_result *r) {
  fprintf(trace,
          "# jets trace: kh0 %g, lambda %g cm, up %g km/s, Y %g GPa, decay %g lambda/Us\n"
          "# units: t [10us], x_spike [cm], x_bubble [cm], x_fs [cm], eta [cm], v_tip [km/s], "
          "u_fs [km/s], x_valley [cm], m_jet [rho0 h0 lambda], x_m1/x_m10/x_m50 [cm], "
          "v_m1/v_m10/v_m50 [km/s], x_main [cm], v_main [km/s], n_jet/n_clusters/n_ahead/"
          "tip_cluster [particles]; leading masses 0.01/0.1/0.5 rho0 h0 lambda (h0 %g cm)\n"
          "t,x_spike,x_bubble,x_fs,eta,v_tip,u_fs,x_valley,m_jet,x_m1,x_m10,x_m50,v_m1,v_m10,"
          "v_m50,x_main,v_main,n_jet,n_clusters,n_ahead,tip_cluster\n",
          c->kh0, r->lambda, c->up, c->Y, c->decay, r->h0);
}

ms_status jets_run(const jets_case *c, jets_result *r, FILE *trace, long every) {
  memset(r, 0, sizeof *r);
  const double rho0 = eos_rho0(c->eos);
  eos_hugoniot_point hp;
  ms_status st = eos_hugoniot(c->eos, rho0, eos_e0(c->eos), 1, &c->up, &hp);
  if (st != MS_OK) return st;
  r->us = hp.us;
  r->lambda = (double)c->ncol * c->h;
  r->k = 2 * M_PI / r->lambda;
  r->h0 = c->kh0 / r->k;
  const double depth = nearbyint(c->depth_wl * (double)c->ncol) * c->h;
  /* the shock leaves the piston layers (2 h) and reaches the peaks after (depth − 2h)/U_s */
  const double t_end = (depth - 2 * c->h) / r->us + c->obs_wl * r->lambda / r->us;
  /* the region's fixed step (dt_margin × its Courant limit at rest, dm_region.c) comes with the
   * build; the flat strip's must be the grooved slab's (same h and material), checked below */
  ptl_region *reg = NULL;
  ptl_region_params *pp = NULL;
  dk_doc *doc = NULL;
  st = build(c, r->lambda, true, depth, r->us, t_end, &reg, &pp, &doc);
  if (st != MS_OK) return st;
  const ptl_region_geometry g = ptl_region_get_geometry(reg);
  r->dt = g.dt;
  r->particles = (long)g.particles;
  const long nsteps = (long)ceil(t_end / r->dt);
  jets_hist h = {0};
  double *buf = hist_alloc(&h, nsteps);
  double dt_flat = 0;
  st = buf ? run_flat(c, depth, t_end, nsteps, h.x_fs, h.u_fs, &dt_flat, r) : MS_ERR_NOMEM;
  if (st != MS_OK || fabs(dt_flat - r->dt) > 1e-12 * r->dt) {
    if (st == MS_OK) snprintf(r->err, sizeof r->err, "flat strip step %g != %g", dt_flat, r->dt);
    free(buf);
    release(&reg, &pp, &doc);
    return st == MS_OK ? MS_ERR_INPUT : st;
  }
  ptl_state *ps = ptl_region_state(reg);
  uint8_t *role = malloc(ps->n);
  classify(ps, r->lambda, r->k, c->h, role, &r->a0);
  /* ρ0 h0 λ in the particles' mass unit: a bulk particle's mass is ρ0 h² (× its z extent) */
  double m_p = 0;
  for (size_t i = 0; i < ps->n && m_p == 0; i++)
    if (!(ps->flags[i] & (PTL_DRIVEN | PTL_SURFACE))) m_p = ps->mass[i];
  jets_tip *tip = jets_tip_create(ps, role, m_p * r->h0 * r->lambda / (c->h * c->h), c->h);
  if (trace) trace_head(trace, c, r);
  const double t_fit = r->t_break + c->fit_from * r->lambda / r->us;
  const double t_fit_end = r->t_break + c->fit_to * r->lambda / r->us;
  ptl_region_energy e0, e1;
  ptl_region_energy_get(reg, &e0);
  long n = 0;
  for (long k = 0; k < nsteps; k++) {
    st = ptl_region_step(reg);
    if (st != MS_OK) {
      r->status = 1;
      snprintf(r->err, sizeof r->err, "%s", ptl_region_error(reg));
      break;
    }
    double x_sp = -INFINITY, v_sp = 0, x_va = 0, x_pk = 0;
    int n_va = 0, n_pk = 0;
    for (size_t i = 0; i < ps->n; i++) {
      if (!role[i]) continue;
      if ((role[i] & 1) && ps->x[i] > x_sp) x_sp = ps->x[i], v_sp = ps->vx[i];
      if (role[i] & 4) x_va += ps->x[i], n_va++;
      if (role[i] & 8) x_pk += ps->x[i], n_pk++;
    }
    const double x_bu = x_pk / n_pk;
    x_va /= n_va;
    h.tt[k] = (double)(k + 1) * r->dt;
    h.xs[k] = x_sp - h.x_fs[k], h.eta[k] = 0.5 * (x_va - x_bu), h.vt[k] = v_sp - h.u_fs[k];
    h.rel[k] = x_va - h.x_fs[k], h.relb[k] = x_bu - h.x_fs[k], h.xtip[k] = x_sp;
    jets_tip_sample ts;
    jets_tip_measure(tip, ps, role, h.x_fs[k], r->lambda, &ts);
    for (int j = 0; j < JETS_TIP_NFRAC; j++) h.x_m[j][k] = ts.x_m[j], h.v_m[j][k] = ts.v_m[j];
    h.x_main[k] = ts.x_main;
    if (h.tt[k] <= t_fit_end) h.last = ts;
    n = k + 1;
    if (trace && (k % every == 0 || k == nsteps - 1))
      fprintf(trace,
              "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%.9g,"
              "%.6g,%ld,%ld,%ld,%ld\n",
              h.tt[k], x_sp, x_bu, h.x_fs[k], h.eta[k], v_sp, h.u_fs[k], x_va, ts.m_jet, ts.x_m[0],
              ts.x_m[1], ts.x_m[2], ts.v_m[0], ts.v_m[1], ts.v_m[2], ts.x_main, ts.v_main, ts.n_jet,
              ts.n_clusters, ts.n_ahead, ts.tip_cluster);
  }
  r->steps = n;
  ptl_region_energy_get(reg, &e1);
  r->energy_err = fabs(e1.total - e0.total) / fmax(fabs(e1.piston_work), DBL_MIN);
  if (c->snapshot && ptl_region_write_snapshot(reg, c->snapshot, NULL) != MS_OK)
    fprintf(stderr, "jets: could not write %s\n", c->snapshot);
  r->t_end = n ? h.tt[n - 1] : 0;
  /* the fit window and the breakout amplitude */
  long k0 = 0, kb = 0, k1 = 0;
  while (k0 < n && h.tt[k0] < t_fit) k0++;
  while (kb < n && h.tt[kb] < r->t_break) kb++;
  while (k1 < n && h.tt[k1] <= t_fit_end) k1++;
  fit_window(c, &h, kb, k0, k1, n, r);
  jets_tip_destroy(&tip);
  free(role);
  free(buf);
  release(&reg, &pp, &doc);
  return MS_OK;
}
