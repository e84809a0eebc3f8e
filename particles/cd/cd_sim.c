/* SPDX-License-Identifier: MIT */
/* cd_sim.c — the cluster-dynamics run: set-up, time step, piston, walls. The energy balance,
 * the virial stress and the relaxation stage are cd_relax.c's.
 *
 * Every force evaluation of a run goes through cd_step_forces (the one place for per-evaluation
 * hooks). One velocity-Verlet step (the default; then the damping sub-step; particles-cd.md):
 *   1. v ← v + (Δt/2) f/m, x ← x + Δt v for integrated particles (fused, with the largest
 *      speed, which bounds the displacements since the last list build); driven (piston)
 *      particles move by ∫u dt;
 *   2. walls reflect particles specularly;
 *   3. the lists are rebuilt unless the rebuild test of neighbour.c passes (every particle
 *      within skin/2 of its build position, or of it plus one common displacement);
 *   4. forces f(x^{n+1});
 *   5. v ← v + (Δt/2) f/m;
 *   6. if Γ > 0: relative-velocity damping v_i −= Δt Γ Σ_k (μ_ik/m_i)(v_i − v_k), its exact
 *      kinetic-energy change booked as dissipated energy.
 * Piston work: W += ½(F_old + F_new)·dir·Δs with F the force of the particles on the piston and
 * Δs the piston displacement in the step (trapezoid rule, consistent with Verlet).
 *
 * RKN steps (position Verlet, SIA4, RKN4, RKN4 conjugate; docs/design.md §5.2) go through
 * rkn_step_soa on x, y, z in place (rkn_step_cd): the lists are checked and rebuilt only at step
 * boundaries, with the skin test widened by a bound on how far the stage positions reach from
 * x^n; driven particles sit at x_p(t_l) = x_p(t_n) + ∫u dt at every stage; piston work is the
 * scheme's own quadrature W += Δt Σ γ_l F_l·dir u(t_l); walls and damping act after the step.
 */
#include "cd_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const cd_integrator_names[] = {
    "velocity_verlet", "position_verlet", "sia4", "rkn4", "rkn4_conjugate", NULL};
static const rkn_kind rkn_of[CD_INT_COUNT] = {RKN_VERLET, RKN_VERLET, RKN_SIA4, RKN_RKN4,
                                              RKN_RKN4_CONJ};

/* ---- piston history ---- */
double cd_history_eval(const cd_history *h, double t) {
  if (h->n == 0) return 0.0;
  if (t <= h->t[0]) return h->u[0];
  if (t >= h->t[h->n - 1]) return h->u[h->n - 1];
  size_t lo = 0, hi = h->n - 1;
  while (hi - lo > 1) {
    size_t mid = (lo + hi) / 2;
    if (h->t[mid] <= t) lo = mid;
    else hi = mid;
  }
  double w = (t - h->t[lo]) / (h->t[hi] - h->t[lo]);
  return h->u[lo] + w * (h->u[hi] - h->u[lo]);
}

/* ∫ of the piecewise-linear history: sum of trapezoids over the breakpoints inside [t0, t1]. */
double cd_history_integral(const cd_history *h, double t0, double t1) {
  if (h->n == 0) return 0.0;
  double acc = 0.0, ta = t0, ua = cd_history_eval(h, t0);
  for (size_t k = 0; k < h->n; k++) {
    if (h->t[k] <= t0) continue;
    if (h->t[k] >= t1) break;
    acc += 0.5 * (ua + h->u[k]) * (h->t[k] - ta);
    ta = h->t[k];
    ua = h->u[k];
  }
  return acc + 0.5 * (ua + cd_history_eval(h, t1)) * (t1 - ta);
}

void cd_history_free(cd_history *h) {
  if (!h) return;
  free(h->t);
  free(h->u);
  h->t = h->u = NULL;
  h->n = 0;
}

ms_status cd_history_read(cd_history *h, const char *path, bool si, dk_errors *e) {
  double *data = NULL;
  size_t nrow = 0, ncol = 0;
  *h = (cd_history){0};
  ms_status st = ms_read_table(path, 2, &data, &nrow, &ncol, e);
  if (st != MS_OK) return st;
  if (nrow < 1) {
    dk_error_at(e, path, 1, 1, "piston history: no rows (need columns t, u)");
    free(data);
    return MS_ERR_INPUT;
  }
  double ft =
      ms_table_time_factor(path, 0, si ? ms_unit_to_internal(MS_UNITS_SI, MS_DIM_TIME) : 1.0);
  double fu = si ? ms_unit_to_internal(MS_UNITS_SI, MS_DIM_VELOCITY) : 1.0;
  h->n = nrow;
  h->t = ms_calloc(nrow, sizeof *h->t);
  h->u = ms_calloc(nrow, sizeof *h->u);
  /* ms_read_table does not return the file line of a data row (comments and a header line may
   * precede it), so row errors name the file and the data row. */
  for (size_t k = 0; k < nrow; k++) {
    h->t[k] = data[k * ncol] * ft;
    h->u[k] = data[k * ncol + 1] * fu;
    if (!isfinite(h->t[k]) || !isfinite(h->u[k])) {
      dk_error_at(e, path, 0, 0, "piston history: data row %zu is not finite", k + 1);
      st = MS_ERR_INPUT;
    } else if (k > 0 && !(h->t[k] > h->t[k - 1])) {
      dk_error_at(e, path, 0, 0,
                  "piston history: time does not increase at data row %zu (t = %g after %g): a "
                  "jump in time; give u(t) as a function with strictly increasing t",
                  k + 1, data[k * ncol], data[(k - 1) * ncol]);
      st = MS_ERR_INPUT;
    }
  }
  free(data);
  if (st != MS_OK) cd_history_free(h);
  return st;
}

/* ---- set-up ---- */
ms_status cd_sim_create(const cd_sim_params *p, cd_sim **out) {
  *out = NULL;
  if (!p->particles || !p->box || !p->cfg || p->nmat < 1 || p->nmat > CD_MAX_MATERIALS)
    return MS_ERR_INPUT;
  cd_sim *s = ms_calloc(1, sizeof *s);
  s->p = p->particles;
  s->box = *p->box;
  s->cfg = *p->cfg;
  s->nmat = p->nmat;
  s->material_names = p->material_names ? ms_strdup(p->material_names) : NULL;
  *out = s;
  return MS_OK;
}

void cd_sim_set_pair(cd_sim *s, int a, int b, cd_pair_table *t) {
  if (s->pair[a][b] && s->pair[a][b] != t) {
    cd_pair_table *old = s->pair[a][b];
    s->pair[a][b] = s->pair[b][a] = NULL;
    cd_pair_table_free(old);
    free(old);
  }
  if (s->cfg.cutoff == CD_CUTOFF_SHIFTED) cd_pair_table_shift_energy(t);
  s->pair[a][b] = s->pair[b][a] = t;
}

void cd_sim_set_piston(cd_sim *s, const cd_history *h, const double dir[3]) {
  cd_history_free(&s->piston);
  s->piston.n = h->n;
  s->piston.t = ms_calloc(h->n ? h->n : 1, sizeof(double));
  s->piston.u = ms_calloc(h->n ? h->n : 1, sizeof(double));
  memcpy(s->piston.t, h->t, h->n * sizeof(double));
  memcpy(s->piston.u, h->u, h->n * sizeof(double));
  double nrm = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  for (int a = 0; a < 3; a++) s->piston_dir[a] = nrm > 0 ? dir[a] / nrm : 0.0;
}

void cd_sim_set_material_names(cd_sim *s, const char *names) {
  free(s->material_names);
  s->material_names = names ? ms_strdup(names) : NULL;
}

static void cd_sim_free(cd_sim *s) {
  if (!s) return;
  free(s->material_names);
  for (int a = 0; a < CD_MAX_MATERIALS; a++)
    for (int b = a; b < CD_MAX_MATERIALS; b++)
      if (s->pair[a][b]) {
        cd_pair_table_free(s->pair[a][b]);
        free(s->pair[a][b]);
      }
  cd_neigh_destroy(&s->nl);
  cd_dd_free(s->dd);
  cd_history_free(&s->piston);
  free(s->driven);
  free(s->scratch);
  free(s->partners);
  free(s->sums);
  free(s->pw);
  rkn_destroy(&s->rkn);
  free(s->driven_x0);
  ptl_state_destroy(&s->p);
  free(s);
}

void cd_sim_destroy(cd_sim **s) {
  if (!s) return;
  cd_sim_free(*s);
  *s = NULL;
}

static void ensure_sums(cd_sim *s) {
  if (s->sums_cap < s->nl->layers_cap) {
    free(s->sums);
    s->sums_cap = s->nl->layers_cap;
    s->sums = ms_aligned_alloc((size_t)s->sums_cap, sizeof(cd_layer_sums));
  }
}

/* Under MPI (s->dd) every build first moves particles to their owners and refreshes the
 * ghosts (cd_par.c), which also sorts the owned particles into cell order (no renumbering). */
ms_status cd_rebuild_lists(cd_sim *s, bool reorder) {
  double t0 = ms_wall_time();
  ms_status st = MS_OK;
  if (s->dd) {
    st = cd_dd_redistribute(s);
    reorder = false;
  }
  if (st == MS_OK) st = cd_neigh_build(s->nl, s->p, &s->box, s->partners, reorder);
  if (s->dd) { /* the serial run's float-rounding margin (rebuild test, neighbour.c) */
    st = par_agree_status(st);
    s->nl->xb_err = par_max_double(s->nl->xb_err);
  }
  s->wall_time_neigh += ms_wall_time() - t0;
  s->disp_bound = 0.0;
  if (st == MS_ERR_UNSTABLE && !s->err[0]) { /* the list build's diagnostic (neighbour.c) */
    const cd_neigh *nl = s->nl;
    snprintf(s->err, sizeof s->err,
             "unstable at step %ld, t = %.9g %s: a particle has too many list candidates in "
             "its link cells: particles piled on top of each other, or the particles spread "
             "so far that the cell grid (at most %d n + 64 cells over their extent: %d x %d x "
             "%d cells of %.3g x %.3g x %.3g cm) is too coarse",
             s->step, ms_out_time(s->t), ms_out_time_label(), nl->cell_factor, nl->ncell[0],
             nl->ncell[1], nl->ncell[2], 1.0 / nl->cell_inv_w[0], 1.0 / nl->cell_inv_w[1],
             1.0 / nl->cell_inv_w[2]);
  }
  if (st != MS_OK) return st;
  ensure_sums(s);
  if ((reorder || s->dd) && s->driven) { /* indices changed: refresh the driven list */
    size_t k = 0;
    for (size_t i = 0; i < s->p->nlocal; i++)
      if (s->p->flags[i] & PTL_DRIVEN) s->driven[k++] = (int32_t)i;
    s->n_driven = k;
  }
  return MS_OK;
}

/* The fit kernel (cd_force.c) on full lists serves runs whose every force evaluation in a time
 * step is the forces-only one: one material with a fitted table, plain cutoff, no damping
 * (its sub-step walks half lists). It pays only with AVX-512 (eight pairs per instruction; a
 * scalar full list computes every pair twice). Under MPI an owned particle's full list holds
 * its ghost neighbours too, so its force is complete, and a ghost's list is empty (its force is
 * its owner's business; the diagnostics take an owned–ghost pair from the owned side). */
static bool fit_path(const cd_sim *s) {
#if CD_X86_DISPATCH || defined(__AVX512F__)
  return cd_simd_level_ == CD_SIMD_AVX512 && s->nmat == 1 && s->pair[0][0]->fit_ok &&
         cd_pairs_by_distance(s->cfg.cutoff) && !(s->cfg.damping_gamma > 0.0) &&
         !getenv("MSCALE_CD_NO_FIT");
#else
  return false;
#endif
}

/* A full list takes about twice as long to build as a half list (every pair is found from
 * both sides) and saves 6 % (quiet core) to 15 % (loaded) of a time step: it pays when the
 * list lives at least this many steps. Measured on the piston problem (docs/benchmarks.md,
 * round 8): a full build costs ~37 ms more than a half one and saves ~2.3 ms per step, even
 * at 16 steps; its lists live 6–10 steps, where half lists are faster. */
enum { CD_FULL_MIN_STEPS = 16 };

static ms_status rebuild(cd_sim *s) {
  if (s->nl->nbuild > 0) /* by the age of the list being replaced */
    s->nl->full = fit_path(s) && s->step - s->last_build_step >= CD_FULL_MIN_STEPS;
  s->last_build_step = s->step;
  int every = s->cfg.sort_every > 0 ? s->cfg.sort_every : 8; /* default: every 8th build */
  return cd_rebuild_lists(s, s->nl->nbuild % every == 0);
}

static double driven_force(const cd_sim *s) {
  double f = 0.0;
  for (size_t k = 0; k < s->n_driven; k++) {
    int32_t i = s->driven[k];
    f += s->p->fx[i] * s->piston_dir[0] + s->p->fy[i] * s->piston_dir[1] +
         s->p->fz[i] * s->piston_dir[2];
  }
  return f;
}

/* Forces for the time step; in bonded mode also books broken bonds. */
void cd_step_forces(cd_sim *s) {
  if (s->dd) cd_dd_refresh(s, CD_REFRESH_X);
  double t0 = ms_wall_time();
  if (s->cfg.cutoff == CD_CUTOFF_BONDED) {
    cd_compute_forces(s, s->sums, NULL, true);
    for (int l = 0; l < s->nl->nlayer; l++) {
      s->broken_bonded += s->sums[l].broken;
      s->n_broken_bonds += s->sums[l].nbroken;
    }
  } else {
    cd_compute_forces(s, NULL, NULL, true);
  }
  s->wall_time_force += ms_wall_time() - t0;
}

/* Full lists are valid only while fit_path holds; cd_sim_relax changes the damping and the
 * cutoff mode between builds: half lists then, built at once. */
ms_status cd_half_lists_unless_fit(cd_sim *s) {
  if (!s->nl->full || fit_path(s)) return MS_OK;
  s->nl->full = false;
  s->last_build_step = s->step;
  ms_status st = cd_rebuild_lists(s, false);
  if (st == MS_OK) cd_step_forces(s);
  return st;
}

/* Pairs inside R_c at the start, for the broken-pair energy of the plain cutoff. */
void cd_count_inside0(cd_sim *s) {
  cd_compute_forces(s, s->sums, NULL, false);
  memset(s->n_inside0, 0, sizeof s->n_inside0);
  for (int l = 0; l < s->nl->nlayer; l++)
    for (int k = 0; k < CD_MAX_MATERIALS * CD_MAX_MATERIALS; k++)
      s->n_inside0[k / CD_MAX_MATERIALS][k % CD_MAX_MATERIALS] += s->sums[l].inside[k];
  if (s->dd) par_sum_int64s(&s->n_inside0[0][0], CD_MAX_MATERIALS * CD_MAX_MATERIALS);
  s->have_inside0 = true;
}

/* Bonded mode: the partners are every pair closer than its R_c now (from the current lists,
 * which must be built). */
ms_status cd_form_partners(cd_sim *s) {
  const ptl_state *p = s->p;
  for (size_t k = 0; k < p->cap * CD_MAX_PARTNERS; k++) s->partners[k] = -1;
  const cd_neigh *nl = s->nl;
  for (int l = 0; l < nl->nlayer; l++)
    for (int32_t pos = nl->layer_start[l]; pos < nl->layer_start[l + 1]; pos++) {
      int32_t i = nl->sorted[pos];
      const int32_t *lst = nl->buf[l] + nl->first[pos];
      int np = nl->nplain[pos], ni = nl->nimg[pos];
      for (int k = 0; k < np + ni; k++) {
        const double *sh;
        int32_t j = *cd_nb_entry(nl, lst, np, k, &sh) & CD_NB_INDEX;
        double dx = p->x[i] - p->x[j] - sh[0], dy = p->y[i] - p->y[j] - sh[1],
               dz = p->z[i] - p->z[j] - sh[2];
        if (dx * dx + dy * dy + dz * dz >= s->pair[p->mat[i]][p->mat[j]]->rc2) continue;
        int32_t *pi = s->partners + (size_t)i * CD_MAX_PARTNERS;
        int32_t *pj = s->partners + (size_t)j * CD_MAX_PARTNERS;
        int ki = 0, kj = 0;
        while (ki < CD_MAX_PARTNERS && pi[ki] >= 0) ki++;
        while (kj < CD_MAX_PARTNERS && pj[kj] >= 0) kj++;
        if (ki == CD_MAX_PARTNERS || kj == CD_MAX_PARTNERS) return MS_ERR_INPUT;
        pi[ki] = j;
        pj[kj] = i;
      }
    }
  return rebuild(s); /* the lists take the bonded flags */
}

ms_status cd_sim_init(cd_sim *s) {
  ptl_state *p = s->p;
  s->rc_max = 0.0;
  for (int a = 0; a < s->nmat; a++)
    for (int b = 0; b < s->nmat; b++) {
      if (!s->pair[a][b]) return MS_ERR_INPUT;
      if (s->pair[a][b]->rc > s->rc_max) s->rc_max = s->pair[a][b]->rc;
    }
  if (p->dim == 2)
    for (size_t i = 0; i < p->n; i++) p->z[i] = p->vz[i] = 0.0;
  if (s->mpi_on && par_size() > 1) {
    ms_status st = cd_dd_create(s); /* grows p to the global count */
    if (st != MS_OK) return st;
  }
  ms_must(
      cd_neigh_create(
          &(cd_neigh_params){.cap = p->cap, .rlist = s->rc_max + s->cfg.skin, .skin = s->cfg.skin},
          &s->nl),
      "cd_neigh_create");
  s->nl->full = fit_path(s);
  ms_status st = rebuild(s);
  if (st != MS_OK) return st;
  if (s->cfg.cutoff == CD_CUTOFF_BONDED && !s->partners) { /* a restart brings its own */
    s->partners = ms_aligned_alloc(p->cap * CD_MAX_PARTNERS, sizeof(int32_t));
    st = cd_form_partners(s);
    if (st != MS_OK) return st;
  }
  if (s->cfg.damping_gamma > 0.0) s->scratch = ms_aligned_alloc(3 * p->cap, sizeof(double));
  s->n_driven = 0;
  for (size_t i = 0; i < p->nlocal; i++)
    if (p->flags[i] & PTL_DRIVEN) s->n_driven++;
  /* under MPI the owned driven particles change with migration: room for all */
  s->driven = ms_calloc((s->dd ? p->cap : s->n_driven) + 1, sizeof *s->driven);
  for (size_t i = 0, k = 0; i < p->nlocal; i++)
    if (p->flags[i] & PTL_DRIVEN) s->driven[k++] = (int32_t)i;
  if (s->cfg.integrator != CD_INT_VELOCITY_VERLET) {
    if ((int)s->cfg.integrator < 0 || s->cfg.integrator >= CD_INT_COUNT) return MS_ERR_INPUT;
    /* MPI: room for every particle (the owned count changes with migration; rkn_resize) */
    const size_t cap = s->dd ? p->cap : p->n;
    ms_must(rkn_create(&(rkn_params){.kind = rkn_of[s->cfg.integrator], .ndof = 3 * cap}, &s->rkn),
            "rkn_create");
    s->driven_x0 = ms_calloc(3 * (s->dd ? cap : s->n_driven) + 1, sizeof *s->driven_x0);
    /* q_l − x^n = Δt α_l u + Δt² Σ_{k<l} γ_k(α_l − α_k) a_k: reach coefficients */
    const rkn_scheme *sc = rkn_integrator_scheme(s->rkn);
    s->rkn_reach[0] = s->rkn_reach[1] = 0.0;
    for (int l = 0; l < sc->stages; l++) {
      double c1 = 0.0;
      for (int k = 0; k < l; k++) c1 += fabs(sc->gamma[k] * (sc->alpha[l] - sc->alpha[k]));
      s->rkn_reach[0] = fmax(s->rkn_reach[0], fabs(sc->alpha[l]));
      s->rkn_reach[1] = fmax(s->rkn_reach[1], c1);
    }
  }
  if (!s->have_inside0) cd_count_inside0(s);
  cd_step_forces(s);
  return MS_OK;
}

/* What a restart does after reading a checkpoint (lists built with renumbering, then forces),
 * done by the run at each checkpoint too: both continue from identical lists, particle order
 * and force summation order (docs/mpi.md). The renumbering is a stable sort into cell order,
 * so repeating it on the checkpoint's order leaves that order unchanged. */
ms_status cd_sim_refresh(cd_sim *s) {
  s->nl->full = fit_path(s); /* both runs continue from the same list kind */
  s->last_build_step = s->step;
  ms_status st = cd_rebuild_lists(s, true);
  if (st == MS_OK) cd_step_forces(s);
  return st;
}

ms_status cd_sim_affine(cd_sim *s, const double lambda[3]) {
  ptl_state *p = s->p;
  double *xa[3] = {p->x, p->y, p->z};
  for (int a = 0; a < 3; a++) {
    double lo = s->box.lo[a];
    for (size_t i = 0; i < p->n; i++) xa[a][i] = lo + lambda[a] * (xa[a][i] - lo);
    s->box.hi[a] = lo + lambda[a] * (s->box.hi[a] - lo);
  }
  if (s->dd) cd_dd_regrid(s);
  ms_status st = rebuild(s);
  if (st != MS_OK) return st;
  cd_step_forces(s);
  return MS_OK;
}

/* ---- time step ---- */

/* Specular walls: particles beyond a wall are mirrored back with the normal velocity reversed. */
static void reflect_walls(cd_sim *s) {
  ptl_state *p = s->p;
  const long n = (long)p->nlocal;
  double *xs[3] = {p->x, p->y, p->z}, *vs[3] = {p->vx, p->vy, p->vz};
  for (int a = 0; a < 3; a++) {
    if (s->box.bc[a] != CD_BC_WALL) continue;
    double *xa = xs[a], *va = vs[a];
    const double lo = s->box.lo[a], hi = s->box.hi[a];
    for (long i = 0; i < n; i++) {
      if (p->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) continue;
      if (xa[i] < lo) {
        xa[i] = 2.0 * lo - xa[i];
        va[i] = -va[i];
      }
      if (xa[i] > hi) {
        xa[i] = 2.0 * hi - xa[i];
        va[i] = -va[i];
      }
    }
  }
}

/* After the integrator: damping sub-step, clock, and the periodic NaN check. */
static ms_status end_step(cd_sim *s) {
  if (s->cfg.damping_gamma > 0.0) {
    /* the ghosts' velocities after the kick; after an RKN step their positions too (they hold
     * the last stage's) */
    if (s->dd) cd_dd_refresh(s, CD_REFRESH_V | (s->rkn ? CD_REFRESH_X : 0u));
    s->dissipated += cd_damping_step(s);
  }
  s->t += s->cfg.dt;
  s->step++;
  if (s->step % CD_GUARD_EVERY == 0) {
    int bad = cd_sim_guard(s) != MS_OK; /* the finding names a particle of this rank */
    if (s->dd) bad = par_max_int(bad);  /* every rank stops together */
    if (bad) return MS_ERR_UNSTABLE;
  }
  return MS_OK;
}

/* Signed piston displacement ∫_{t0}^{t1} u dt (t1 may precede t0: SIA4's last stage does). */
static double piston_shift(const cd_sim *s, double t0, double t1) {
  return t1 >= t0 ? cd_history_integral(&s->piston, t0, t1)
                  : -cd_history_integral(&s->piston, t1, t0);
}

/* RKN constraint: driven particles at their prescribed place (and velocity at the end). */
static void rkn_constrain_cd(void *user, double t, bool end) {
  cd_sim *s = user;
  ptl_state *p = s->p;
  const double d = piston_shift(s, s->t, t), u = end ? cd_history_eval(&s->piston, t) : 0.0;
  for (size_t k = 0; k < s->n_driven; k++) {
    const int32_t i = s->driven[k];
    const double *x0 = s->driven_x0 + 3 * k;
    p->x[i] = x0[0] + d * s->piston_dir[0];
    p->y[i] = x0[1] + d * s->piston_dir[1];
    p->z[i] = x0[2] + d * s->piston_dir[2];
    if (end) {
      p->vx[i] = u * s->piston_dir[0];
      p->vy[i] = u * s->piston_dir[1];
      p->vz[i] = u * s->piston_dir[2];
    }
  }
}

/* RKN acceleration at the stage positions (x, y, z hold q_l): a = f/m of integrated
 * particles, 0 for driven and removed ones; records the force on the piston. */
MS_KERNEL_CLONES static ms_status rkn_accel_cd(void *user, double t, double *const acc[]) {
  (void)t;
  cd_sim *s = user;
  ptl_state *p = s->p;
  const long n = (long)p->nlocal; /* MPI: ghosts get the stage positions in step_forces */
  cd_step_forces(s);
  if (s->stage < 3) s->stage_force[s->stage++] = driven_force(s);
  const double *restrict fx = p->fx, *restrict fy = p->fy, *restrict fz = p->fz;
  const double *restrict m = p->mass;
  const uint8_t *restrict fl = p->flags;
  double *restrict ax = acc[0], *restrict ay = acc[1], *restrict az = acc[2];
#pragma omp parallel for simd schedule(static) if (CD_PAR(n))
  for (long i = 0; i < n; i++) {
    const double c = fl[i] & (PTL_DRIVEN | PTL_REMOVED) ? 0.0 : 1.0 / m[i];
    ax[i] = c * fx[i];
    ay[i] = c * fy[i];
    az[i] = c * fz[i];
  }
  return MS_OK;
}

/* One RKN step. The stage positions reach at most Δt c0 max|v| + Δt² c1 max|a| from x^n
 * (rkn_reach; max|a| from the last forces, doubled for its change within the step), so the
 * lists are rebuilt before the step unless the rebuild test (neighbour.c) passes with that
 * reach added to the displacements so far. */
MS_KERNEL_CLONES static ms_status rkn_step_cd(cd_sim *s) {
  ptl_state *p = s->p;
  const double dt = s->cfg.dt;
  const long n = (long)p->nlocal;
  const double *restrict vx = p->vx, *restrict vy = p->vy, *restrict vz = p->vz;
  const double *restrict fx = p->fx, *restrict fy = p->fy, *restrict fz = p->fz;
  const double *restrict m = p->mass;
  const uint8_t *restrict fl = p->flags;
  double vmax2 = 0.0, amax2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : vmax2, amax2) if (CD_PAR(n))
  for (long i = 0; i < n; i++) {
    const double v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
    const double a2 = fl[i] & (PTL_DRIVEN | PTL_REMOVED)
                          ? 0.0
                          : (fx[i] * fx[i] + fy[i] * fy[i] + fz[i] * fz[i]) / (m[i] * m[i]);
    vmax2 = v2 > vmax2 ? v2 : vmax2;
    amax2 = a2 > amax2 ? a2 : amax2;
  }
  const double reach =
      dt * s->rkn_reach[0] * sqrt(vmax2) + 2.0 * dt * dt * s->rkn_reach[1] * sqrt(amax2);
  if (!cd_neigh_holds(s->nl, p, n, INFINITY, reach, s->dd, NULL)) { /* MPI: all ranks agree */
    ms_status st = rebuild(s);
    if (st != MS_OK) return st;
  }
  for (size_t k = 0; k < s->n_driven; k++) {
    const int32_t i = s->driven[k];
    s->driven_x0[3 * k] = p->x[i];
    s->driven_x0[3 * k + 1] = p->y[i];
    s->driven_x0[3 * k + 2] = p->z[i];
  }
  s->stage = 0;
  if (s->dd) rkn_resize(s->rkn, 3 * p->nlocal); /* the owned count changes at a build */
  double *r[3] = {p->x, p->y, p->z}, *u[3] = {p->vx, p->vy, p->vz};
  ms_status st = rkn_step_soa(s->rkn, s->t, dt, 3, r, u, rkn_accel_cd, rkn_constrain_cd, s);
  if (st != MS_OK) return st;
  if (s->n_driven) {
    const rkn_scheme *sc = rkn_integrator_scheme(s->rkn);
    for (int l = 0; l < sc->stages; l++)
      s->piston_work -= dt * sc->gamma[l] * s->stage_force[l] *
                        cd_history_eval(&s->piston, s->t + sc->alpha[l] * dt);
  }
  reflect_walls(s);
  return end_step(s);
}

/* vv_step's fused loop, particle i: kick v by (Δt/2)·f/m, zero f, drift x by Δt·v; returns
 * the new |v|². */
static inline double kick_drift_zero(long i, double hdt, double dt, const double *restrict m,
                                     double *restrict x, double *restrict y, double *restrict z,
                                     double *restrict vx, double *restrict vy, double *restrict vz,
                                     double *restrict fx, double *restrict fy,
                                     double *restrict fz) {
  const double c = hdt / m[i];
  vx[i] += c * fx[i];
  vy[i] += c * fy[i];
  vz[i] += c * fz[i];
  fx[i] = fy[i] = fz[i] = 0.0;
  x[i] += dt * vx[i];
  y[i] += dt * vy[i];
  z[i] += dt * vz[i];
  return vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
}

/* One velocity-Verlet step (the header comment). */
MS_KERNEL_CLONES static ms_status vv_step(cd_sim *s) {
  ptl_state *p = s->p;
  const double dt = s->cfg.dt, hdt = 0.5 * dt;
  long n = (long)p->nlocal; /* ghosts are refreshed from their owners; MPI: changes at a build */
  double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  double *restrict vx = p->vx, *restrict vy = p->vy, *restrict vz = p->vz;
  double *restrict fx = p->fx, *restrict fy = p->fy, *restrict fz = p->fz;
  const double *restrict m = p->mass;

  /* Driven particles: prescribed velocity for this step, zero force so the uniform loop below
   * moves them by Δt·(∫u dt/Δt). Removed particles have f = v = 0 and stay put. */
  double ds = 0.0, fold = 0.0, vp[3] = {0, 0, 0};
  /* MPI: a rank without driven particles at the start of the step may receive some at a build */
  const bool piston = s->n_driven > 0 || (s->dd && s->piston.n > 0);
  if (piston) {
    ds = cd_history_integral(&s->piston, s->t, s->t + dt);
    for (int a = 0; a < 3; a++) vp[a] = ds / dt * s->piston_dir[a];
    fold = driven_force(s);
    for (size_t k = 0; k < s->n_driven; k++) {
      int32_t i = s->driven[k];
      fx[i] = fy[i] = fz[i] = 0.0;
      vx[i] = vp[0];
      vy[i] = vp[1];
      vz[i] = vp[2];
    }
  }
  /* kick + drift + zero the forces, fused. The rebuild test (neighbour.c) needs the build
   * positions only once the cheap bound Σ Δt·max|v| on every displacement has reached skin/2;
   * before that the loop just tracks max|v|. */
  double vmax2 = 0.0;
  /* When this step may take the cheap bound past skin/2 (at up to twice the last step's
   * max|v|), the loop also takes the displacement extents the exact test then needs, saving it
   * a pass over x and the build positions (not with walls, which move particles after the
   * loop). Two loops: a test inside one keeps it from vectorising. */
  const bool walls =
      s->box.bc[0] == CD_BC_WALL || s->box.bc[1] == CD_BC_WALL || s->box.bc[2] == CD_BC_WALL;
  const bool track =
      !walls && s->disp_bound + 2.0 * dt * s->vmax_last >= 0.5 * s->cfg.skin - s->nl->xb_err;
  double d2max = 0.0, hx = -INFINITY, hy = -INFINITY, hz = -INFINITY;
  double lx = -INFINITY, ly = -INFINITY, lz = -INFINITY; /* −min, so that all are maxima */
  int nan_seen = 0;
  if (!track) {
#pragma omp parallel for simd schedule(static) reduction(max : vmax2) if (CD_PAR(n))
    for (long i = 0; i < n; i++) {
      const double v2 = kick_drift_zero(i, hdt, dt, m, x, y, z, vx, vy, vz, fx, fy, fz);
      vmax2 = v2 > vmax2 ? v2 : vmax2;
    }
  } else {
    const float *restrict xb = s->nl->xb, *restrict yb = s->nl->yb, *restrict zb = s->nl->zb;
#pragma omp parallel for simd schedule(static) if (CD_PAR(n))                                      \
    reduction(max                                                                                  \
              : vmax2, d2max, hx, hy, hz, lx, ly, lz, nan_seen)
    for (long i = 0; i < n; i++) {
      const double v2 = kick_drift_zero(i, hdt, dt, m, x, y, z, vx, vy, vz, fx, fy, fz);
      vmax2 = v2 > vmax2 ? v2 : vmax2;
      const double dx = x[i] - xb[i], dy = y[i] - yb[i], dz = z[i] - zb[i];
      cd_extent_update(dx, dy, dz, &d2max, &hx, &hy, &hz, &lx, &ly, &lz, &nan_seen);
    }
  }
  if (!(vmax2 < INFINITY)) vmax2 = INFINITY; /* NaN: the exact test, which rebuilds */
  if (s->dd) vmax2 = par_max_double(vmax2);  /* the serial run's bound on every rank */
  s->vmax_last = sqrt(vmax2);
  s->disp_bound += dt * s->vmax_last;
  reflect_walls(s);
  double ext[7];
  cd_extents_finish(ext, d2max, hx, hy, hz, lx, ly, lz, nan_seen);
  if (!cd_neigh_holds(s->nl, p, n, s->disp_bound, 0.0, s->dd, track ? ext : NULL)) {
    ms_status st = rebuild(s);
    if (st != MS_OK) return st;
    n = (long)p->nlocal;
  }
  s->forces_zeroed = true;
  /* the fit kernel does the closing kick itself, particle by particle (cd_force.c) */
  const bool kicked = s->nl->full;
  s->kick_hdt = kicked ? hdt : 0.0;
  cd_step_forces(s);
  s->kick_hdt = 0.0;
  if (!kicked) {
#pragma omp parallel for simd schedule(static) if (CD_PAR(n))
    for (long i = 0; i < n; i++) {
      const double c = hdt / m[i];
      vx[i] += c * fx[i];
      vy[i] += c * fy[i];
      vz[i] += c * fz[i];
    }
  }
  if (piston) {
    s->piston_work -= 0.5 * (fold + driven_force(s)) * ds;
    for (size_t k = 0; k < s->n_driven; k++) {
      int32_t i = s->driven[k];
      vx[i] = vp[0];
      vy[i] = vp[1];
      vz[i] = vp[2];
    }
  }
  return end_step(s);
}

ms_status cd_sim_step(cd_sim *s) { return s->rkn ? rkn_step_cd(s) : vv_step(s); }

long cd_sim_rebuilds(const cd_sim *s) { return s->nl ? s->nl->nbuild : 0; }
size_t cd_sim_pairs(const cd_sim *s) { return s->nl ? cd_neigh_pairs(s->nl) : 0; }
size_t cd_sim_bytes(const cd_sim *s) {
  size_t b = ptl_state_bytes(s->p) + (s->nl ? cd_neigh_bytes(s->nl) : 0);
  if (s->scratch) b += 3 * s->p->cap * sizeof(double);
  if (s->partners) b += s->p->cap * CD_MAX_PARTNERS * sizeof(int32_t);
  if (s->rkn) /* r^n and one acceleration per stage */
    b += (size_t)(1 + rkn_integrator_scheme(s->rkn)->stages) * 3 * s->p->n * sizeof(double);
  return b;
}

/* ---- MPI (cd_par.c) ---- */
void cd_sim_set_mpi(cd_sim *s, const cd_mpi_config *cfg) {
  s->mpi = *cfg;
  s->mpi_on = true;
}

const cd_mpi_stats *cd_sim_mpi_stats(const cd_sim *s) { return s->dd ? cd_dd_stats(s->dd) : NULL; }

bool cd_sim_owns_position(const cd_sim *s, const double x[3]) {
  return s->dd ? cd_dd_owns(s->dd, x) : true;
}

void cd_sim_refresh_ghosts(cd_sim *s) {
  if (s->dd) cd_dd_refresh(s, CD_REFRESH_X | CD_REFRESH_V);
}
