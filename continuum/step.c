/* SPDX-License-Identifier: MIT */
/* step.c — one time step of the 1D Lagrangian cross scheme (docs/design.md §4), as phase functions
 * named verb + quantity + where (LULESH style): cont_calc_predicted_velocity_for_nodes,
 * cont_calc_half_step_for_cells, cont_calc_velocity_and_position_for_nodes,
 * cont_calc_energy_and_density_for_cells, cont_eval_eos_for_cells,
 * cont_calc_q_and_time_constraint_for_cells.
 *
 * Staggered grid: node j has x_j, u_j and mass M_j = ½(m_{j−1} + m_j); cell i lies between
 * nodes i and i+1 and has mass m_i, volume V_i, ρ_i, e_i, p_i, q_i, c_i. Face area A(x) = x^k,
 * k = 0, 1, 2 (planar, per radian, per steradian) so that V_i = (x_{i+1}^{k+1} − x_i^{k+1})/(k+1).
 *
 * One step tⁿ → tⁿ⁺¹ = tⁿ + Δt (predictor–corrector, cf. Caramana, Burton, Shashkov & Whalen 1998):
 *
 *   predictor   F_j  = A(x_jⁿ) [(p+q)ⁿ_{j−1} − (p+q)ⁿ_j]
 *               u*_j = u_jⁿ + Δt F_j / M_j,   û_j = ½(u_jⁿ + u*_j),   x* = xⁿ + Δt û
 *               half-step cells at x^{n+½} = xⁿ + ½Δt û:
 *               e^{n+½} = eⁿ − (pⁿ + q̂) ½Δt (Ā û)_{i+1,i} / m,   p^{n+½} = P(ρ^{n+½}, e^{n+½}),
 *               q̂ = q^{n+½} from û
 *   corrector   Ā_j  = mean-value face area between x_jⁿ and x*_j   ((x*^{k+1} − xⁿ^{k+1})/((k+1)(x* − xⁿ)))
 *               F_j  = Ā_j [(p+q)^{n+½}_{j−1} − (p+q)^{n+½}_j]
 *               u_jⁿ⁺¹ = u_jⁿ + Δt F_j / M_j,   ū_j = ½(u_jⁿ + u_jⁿ⁺¹),   x_jⁿ⁺¹ = x_jⁿ + Δt ū_j
 *               e_iⁿ⁺¹ = e_iⁿ − Δt (p+q)^{n+½}_i (Ā_{i+1} ū_{i+1} − Ā_i ū_i) / m_i
 *               then ρⁿ⁺¹ = m/V(xⁿ⁺¹), pⁿ⁺¹, cⁿ⁺¹ from the EOS, qⁿ⁺¹ from uⁿ⁺¹.
 *
 * Why it conserves energy exactly: Σ_j ½M_j(u_jⁿ⁺¹² − u_jⁿ²) = Σ_j M_j(u_jⁿ⁺¹ − u_jⁿ)ū_j = Δt Σ_j F_j ū_j,
 * and summation by parts turns Σ_j F_j ū_j into −Σ_i (p+q)_i(Ā_{i+1}ū_{i+1} − Ā_iū_i) plus the
 * boundary terms, which is minus the internal-energy change: only the boundary work is left
 * (it is accumulated in g->work). In planar geometry the same sum gives momentum conservation.
 *
 * The step is cache-blocked: the grid is swept in chunks, each phase running one index behind
 * the phase it depends on, so a chunk's arrays stay in L1/L2 (docs/continuum.md). All state
 * updates are in place; the predictor quantities live in chunk-sized windows (cont_impl.h),
 * so each step streams only the state arrays through main memory.
 */
#include "cont_impl.h"

#include <float.h>
#include <math.h>
#include <stdio.h>

static inline double face_area(double x, int k) {
  switch (k) {
  case 0:
    return 1.0;
  case 1:
    return x;
  default:
    return x * x;
  }
}

/* Mean-value area between positions a and b: (b^{k+1} − a^{k+1}) / ((k+1)(b − a)). */
static inline double mean_area(double a, double b, int k) {
  switch (k) {
  case 0:
    return 1.0;
  case 1:
    return 0.5 * (a + b);
  default:
    return (a * a + a * b + b * b) * (1.0 / 3.0);
  }
}

static inline double volume_between(double xl, double xr, int k) {
  switch (k) {
  case 0:
    return xr - xl;
  case 1:
    return 0.5 * (xr - xl) * (xr + xl);
  default:
    return (xr - xl) * (xr * xr + xr * xl + xl * xl) * (1.0 / 3.0);
  }
}

double cont_cell_volume(const cont_grid *g, double xl, double xr) {
  return volume_between(xl, xr, g->area_power);
}

/* Outside pressure acting on a boundary node (wall and piston nodes are velocity-prescribed, so
 * their value does not matter). */
static double boundary_pressure(const cont_bc *bc, double t) {
  return bc->kind == CONT_BC_PRESSURE ? cont_fn_eval(&bc->fn, t) : 0.0;
}

/* Prescribed velocity of a boundary node at time t, or NAN if the node moves freely. */
static double boundary_velocity(const cont_bc *bc, double t) {
  switch (bc->kind) {
  case CONT_BC_WALL:
    return 0.0;
  case CONT_BC_PISTON:
    return cont_fn_eval(&bc->fn, t);
  default:
    return NAN;
  }
}

/* Viscosity q = ρ|Δu|(q_quad|Δu| + q_lin c) in compression (Δu = u_{i+1} − u_i < 0), else 0. */
void cont_calc_q_for_cells(const cont_grid *g, size_t lo, size_t hi, const double *rho,
                           const double *u, const double *c, double *q) {
  const double cq = g->q_quad, cl = g->q_lin;
  for (size_t i = lo; i < hi; ++i) {
    double du = u[i + 1] - u[i];
    double adu = du < 0.0 ? -du : 0.0;
    q[i] = rho[i] * adu * (cq * adu + cl * c[i]);
  }
}

/* Pressure (and sound speed if c != NULL) of cells [lo, hi), region by region. */
void cont_eval_eos_for_cells(cont_grid *g, size_t lo, size_t hi, const double *rho, const double *e,
                             double *p, double *c, size_t *bad, ms_status *st) {
  for (size_t r = 0; r < g->nregions; ++r) {
    const cont_region *reg = &g->regions[r];
    size_t a = reg->first > lo ? reg->first : lo;
    size_t b = reg->first + reg->n < hi ? reg->first + reg->n : hi;
    if (a >= b) continue;
    size_t ibad = 0;
    ms_status s = eos_eval(reg->eos, b - a, rho + a, e + a, p + a, c ? c + a : NULL, &ibad);
    if (s != MS_OK && *st == MS_OK) {
      *st = s;
      *bad = a + ibad;
    }
  }
}

/* Courant limit with the viscosity's signal speed: Δt_i = cfl Δx / (Q + sqrt(Q² + c²)),
 * Q = q_lin c + 2 q_quad |Δu| in compression (Benson 1991 form). Used at set-up; the step
 * computes the same formula inside cont_calc_q_and_time_constraint_for_cells. */
double cont_calc_time_constraint(const cont_grid *g, size_t lo, size_t hi) {
  const double *restrict x = g->x, *restrict u = g->u, *restrict c = g->c;
  const double cq2 = 2.0 * g->q_quad, cl = g->q_lin;
  double inv_dt_max = 0.0; /* max of 1/Δt avoids a division per cell */
  for (size_t i = lo; i < hi; ++i) {
    double du = u[i + 1] - u[i];
    double adu = du < 0.0 ? -du : 0.0;
    double qs = adu > 0.0 ? cl * c[i] + cq2 * adu : 0.0;
    double inv = (qs + sqrt(qs * qs + c[i] * c[i])) / (x[i + 1] - x[i]);
    inv_dt_max = inv > inv_dt_max ? inv : inv_dt_max;
  }
  return inv_dt_max > 0.0 ? g->cfl / inv_dt_max : INFINITY;
}

static ms_status fail(cont_grid *g, size_t cell, const char *what, double value) {
  snprintf(g->err, sizeof g->err,
           "unstable at step %ld, t = %.9g %s: %s in cell %zu (layer %d, x = %.6g cm) = %.6g",
           g->step + 1, ms_out_time(g->t), ms_out_time_label(), what, cell, g->layer[cell],
           0.5 * (g->x[cell] + g->x[cell + 1]), value);
  return MS_ERR_UNSTABLE;
}

/* Velocity constraint of node j at time t (boundary condition or coupling), or NAN. */
static inline double node_constraint(const cont_grid *g, size_t j, double t) {
  double v = g->ext_velocity[j];
  if (!isnan(v)) return v;
  if (j == 0) return boundary_velocity(&g->left, t);
  if (j == g->ncells) return boundary_velocity(&g->right, t);
  return NAN;
}

/* Nodes that need the slow path: the two boundary nodes, and every node while coupling hooks
 * are active. */
static inline bool node_is_special(const cont_grid *g, size_t j) {
  return j == 0 || j == g->ncells || g->any_ext;
}

/* Window position of global index j (cont_impl.h). */
static inline size_t wi(const cont_grid *g, size_t j) { return j + CONT_HALO - g->win_origin; }

/* Predictor for one node from g->force[j]: û = ½(uⁿ + u*) and the mean-value area Ā between
 * xⁿ and x*. */
static inline void predict_node(cont_grid *g, size_t j, double dt, double t_new) {
  double us = g->u[j] + dt * g->force[j] * g->inv_mass[j];
  if (node_is_special(g, j)) {
    double v = node_constraint(g, j, t_new);
    if (!isnan(v)) us = v;
  }
  double um = 0.5 * (g->u[j] + us);
  g->u_pred_mean[wi(g, j)] = um;
  g->area_mid[wi(g, j)] = mean_area(g->x[j], g->x[j] + dt * um, g->area_power);
}

/* Corrector for a boundary/coupled node from g->force[j]: constraint, reaction force and the
 * work done on the grid by everything outside it (outside pressure, external traction,
 * constraint). */
static inline void correct_special_node(cont_grid *g, size_t j, double dt, double t_new,
                                        double p_left, double p_right, double *work,
                                        double *impulse) {
  double u_old = g->u[j], a = g->area_mid[wi(g, j)], f = g->force[j];
  double un = u_old + dt * f * g->inv_mass[j];
  double v = node_constraint(g, j, t_new);
  double react = 0.0;
  if (!isnan(v)) {
    react = (v - u_old) / (dt * g->inv_mass[j]) - f; /* M Δu/Δt minus the applied force */
    un = v;
  }
  g->reaction[j] = a > 0.0 ? react / a : 0.0;
  double ub = 0.5 * (u_old + un);
  double outside = react + a * g->ext_traction[j];
  if (j == 0) outside += a * p_left;
  if (j == g->ncells) outside -= a * p_right;
  *work += dt * outside * ub;
  *impulse += dt * outside;
  g->u_mean[wi(g, j)] = ub;
  g->x[j] += dt * ub;
  g->u[j] = un;
}

/* Slow-path force on node j (coupling hooks active): (p+q) on its left and right (the outside
 * pressure at the ends), its face area, plus the external traction. */
static inline double special_force(const cont_grid *g, size_t j, double pq_left, double pq_right,
                                   double area) {
  return area * (pq_left - pq_right + g->ext_traction[j]);
}

/* State shared by the phases of one step. */
typedef struct step_ctx {
  cont_grid *g;
  double dt, t1;             /* step and new time */
  double pL0, pR0, pLh, pRh; /* outside pressures at tⁿ and t^{n+½} */
  size_t o;                  /* window index = global index + o (mod 2^64; cont_impl.h) */
  double work, impulse;      /* delivered by the outside during this step */
} step_ctx;

/* N1 — predictor for nodes [lo, hi): F = A(xⁿ)[(p+q)ⁿ_{j−1} − (p+q)ⁿ_j], û = uⁿ + ½Δt F/M,
 * Ā between xⁿ and xⁿ + Δt û. Reads p, q straight from the cells (cells ≥ lo − 1 still hold
 * time level n). Boundary and coupled nodes go through predict_node. */
static inline __attribute__((always_inline)) void
cont_calc_predicted_velocity_for_nodes(step_ctx *sc, size_t lo, size_t hi, const int k) {
  cont_grid *g = sc->g;
  const size_t N = g->ncells, o = sc->o;
  const double dt = sc->dt;
  const double *restrict x = g->x, *restrict u = g->u, *restrict im = g->inv_mass,
                         *restrict p = g->p, *restrict q = g->q;
  double *restrict upm = g->u_pred_mean, *restrict am = g->area_mid;
  if (g->any_ext) {
    for (size_t j = lo; j < hi; ++j) {
      double pl = j > 0 ? p[j - 1] + q[j - 1] : sc->pL0, pr = j < N ? p[j] + q[j] : sc->pR0;
      g->force[j] = special_force(g, j, pl, pr, face_area(x[j], k));
      predict_node(g, j, dt, sc->t1);
    }
    return;
  }
  size_t a = lo > 0 ? lo : 1, b = hi < N ? hi : N;
#pragma omp simd
  for (size_t j = a; j < b; ++j) {
    double f = face_area(x[j], k) * ((p[j - 1] + q[j - 1]) - (p[j] + q[j]));
    double um = u[j] + 0.5 * dt * f * im[j]; /* ½(uⁿ + u*) */
    upm[j + o] = um;
    if (k != 0) am[j + o] = mean_area(x[j], x[j] + dt * um, k);
  }
  if (lo == 0) {
    g->force[0] = face_area(x[0], k) * (sc->pL0 - (p[0] + q[0]));
    predict_node(g, 0, dt, sc->t1);
  }
  if (hi == N + 1) {
    g->force[N] = face_area(x[N], k) * ((p[N - 1] + q[N - 1]) - sc->pR0);
    predict_node(g, N, dt, sc->t1);
  }
}

/* C1 + C2 — half-step cells [lo, hi): ρ^{n+½} at xⁿ + ½Δt û, e^{n+½}, p^{n+½} from the EOS and
 * (p+q)^{n+½} into the q_half window. The first half step's work uses pⁿ and the viscosity q̂ of
 * the predicted velocities û, with ΔV in the same face-area × velocity form as the corrector,
 * so q·ΔV ≤ 0 (q from another velocity field, or V^{n+½} − Vⁿ whose rounding can disagree in
 * sign with Δû, could let q do negative work and drive a cold gas to e < 0). */
static inline __attribute__((always_inline)) ms_status
cont_calc_half_step_for_cells(step_ctx *sc, size_t lo, size_t hi, const int k) {
  cont_grid *g = sc->g;
  const size_t o = sc->o;
  const double dt = sc->dt, cq = g->q_quad, cl = g->q_lin;
  const double *restrict x = g->x, *restrict m = g->mass, *restrict im_c = g->inv_cell_mass,
                         *restrict rho = g->rho, *restrict e = g->e, *restrict p = g->p,
                         *restrict c = g->c, *restrict upm = g->u_pred_mean,
                         *restrict am = g->area_mid;
  double *restrict rh = g->rho_half, *restrict eh = g->e_half, *restrict ph = g->p_half,
                   *restrict qh = g->q_half;
  int neg = 0;
#pragma omp simd reduction(| : neg)
  for (size_t i = lo; i < hi; ++i) {
    double ul = upm[i + o], ur = upm[i + 1 + o];
    double vh = volume_between(x[i] + 0.5 * dt * ul, x[i + 1] + 0.5 * dt * ur, k);
    neg |= !(vh > 0.0);
    rh[i + o] = m[i] / vh;
    double du = ur - ul;
    double adu = du < 0.0 ? -du : 0.0;
    double qhat = rho[i] * adu * (cq * adu + cl * c[i]);
    double dv = k == 0 ? 0.5 * dt * du : 0.5 * dt * (am[i + 1 + o] * ur - am[i + o] * ul);
    eh[i + o] = e[i] - (p[i] + qhat) * dv * im_c[i];
  }
  if (neg) {
    for (size_t i = lo; i < hi; ++i) {
      double vh =
          volume_between(x[i] + 0.5 * dt * upm[i + o], x[i + 1] + 0.5 * dt * upm[i + 1 + o], k);
      if (!(vh > 0.0)) return fail(g, i, "volume (predictor)", vh);
    }
  }
  /* the EOS works on window slices: cell i ↔ window entry i + o */
  for (size_t r = 0; r < g->nregions; ++r) {
    const cont_region *reg = &g->regions[r];
    size_t a = reg->first > lo ? reg->first : lo;
    size_t b = reg->first + reg->n < hi ? reg->first + reg->n : hi;
    if (a >= b) continue;
    size_t ibad = 0;
    if (eos_eval(reg->eos, b - a, rh + (a + o), eh + (a + o), ph + (a + o), NULL, &ibad) != MS_OK)
      return fail(g, a + ibad, "EOS state (predictor density)", rh[a + ibad + o]);
  }
#pragma omp simd
  for (size_t i = lo; i < hi; ++i) {
    double du = upm[i + 1 + o] - upm[i + o];
    double adu = du < 0.0 ? -du : 0.0;
    qh[i + o] = ph[i + o] + rh[i + o] * adu * (cq * adu + cl * c[i]);
  }
  return MS_OK;
}

/* N2 — corrector for nodes [lo, hi): F = Ā[(p+q)^{n+½}_{j−1} − (p+q)^{n+½}_j],
 * uⁿ⁺¹ = uⁿ + Δt F/M, ū = ½(uⁿ + uⁿ⁺¹), xⁿ⁺¹ = xⁿ + Δt ū (planar areas are 1, never stored). */
static inline __attribute__((always_inline)) void
cont_calc_velocity_and_position_for_nodes(step_ctx *sc, size_t lo, size_t hi, const int k) {
  cont_grid *g = sc->g;
  const size_t N = g->ncells, o = sc->o;
  const double dt = sc->dt;
  double *restrict x = g->x, *restrict u = g->u, *restrict ubar = g->u_mean;
  const double *restrict im = g->inv_mass, *restrict am = g->area_mid, *restrict qh = g->q_half;
  if (g->any_ext) {
    for (size_t j = lo; j < hi; ++j) {
      double pl = j > 0 ? qh[j - 1 + o] : sc->pLh, pr = j < N ? qh[j + o] : sc->pRh;
      g->force[j] = special_force(g, j, pl, pr, am[j + o]);
      correct_special_node(g, j, dt, sc->t1, sc->pLh, sc->pRh, &sc->work, &sc->impulse);
    }
    return;
  }
  size_t a = lo > 0 ? lo : 1, b = hi < N ? hi : N;
#pragma omp simd
  for (size_t j = a; j < b; ++j) {
    double f = (k == 0 ? 1.0 : am[j + o]) * (qh[j - 1 + o] - qh[j + o]);
    double un = u[j] + dt * f * im[j];
    double ub = 0.5 * (u[j] + un);
    ubar[j + o] = ub;
    x[j] += dt * ub;
    u[j] = un;
  }
  if (lo == 0) {
    g->force[0] = am[0 + o] * (sc->pLh - qh[0 + o]);
    correct_special_node(g, 0, dt, sc->t1, sc->pLh, sc->pRh, &sc->work, &sc->impulse);
  }
  if (hi == N + 1) {
    g->force[N] = am[N + o] * (qh[N - 1 + o] - sc->pRh);
    correct_special_node(g, N, dt, sc->t1, sc->pLh, sc->pRh, &sc->work, &sc->impulse);
  }
}

/* C3 — cells [lo, hi): the conservative work term
 * eⁿ⁺¹ = eⁿ − Δt (p+q)^{n+½} (Ā_{i+1} ū_{i+1} − Ā_i ū_i)/m, and ρⁿ⁺¹ = m / V(xⁿ⁺¹). */
static inline __attribute__((always_inline)) ms_status
cont_calc_energy_and_density_for_cells(step_ctx *sc, size_t lo, size_t hi, const int k) {
  cont_grid *g = sc->g;
  const size_t o = sc->o;
  const double dt = sc->dt;
  const double *restrict x = g->x, *restrict m = g->mass, *restrict im_c = g->inv_cell_mass,
                         *restrict ubar = g->u_mean, *restrict am = g->area_mid,
                         *restrict qh = g->q_half;
  double *restrict e = g->e, *restrict rho = g->rho;
  int bad = 0;
#pragma omp simd reduction(| : bad)
  for (size_t i = lo; i < hi; ++i) {
    double ul = ubar[i + o], ur = ubar[i + 1 + o];
    double wrk = k == 0 ? qh[i + o] * (ur - ul) : qh[i + o] * (am[i + 1 + o] * ur - am[i + o] * ul);
    e[i] -= dt * wrk * im_c[i];
    double v = volume_between(x[i], x[i + 1], k);
    rho[i] = m[i] / v;
    bad |= !(v > 0.0) | !(fabs(e[i]) <= DBL_MAX);
  }
  if (bad) {
    for (size_t i = lo; i < hi; ++i) {
      double v = volume_between(x[i], x[i + 1], k);
      if (!(v > 0.0)) return fail(g, i, "volume", v);
      if (!(fabs(e[i]) <= DBL_MAX)) return fail(g, i, "specific internal energy", e[i]);
    }
  }
  return MS_OK;
}

/* C5 — cells [lo, hi): qⁿ⁺¹ (formula of cont_calc_q_for_cells), the finiteness checks and the
 * Courant constraint (formula of cont_calc_time_constraint) in one pass; *dt_constraint is
 * lowered to this range's limit. */
static inline __attribute__((always_inline)) ms_status
cont_calc_q_and_time_constraint_for_cells(step_ctx *sc, size_t lo, size_t hi,
                                          double *dt_constraint) {
  cont_grid *g = sc->g;
  const double cq = g->q_quad, cl = g->q_lin, cq2 = 2.0 * g->q_quad;
  const double *restrict x = g->x, *restrict u = g->u, *restrict rho = g->rho, *restrict p = g->p,
                         *restrict c = g->c;
  double *restrict q = g->q;
  int bad = 0;
  double inv_dt_max = 0.0; /* max of 1/Δt: one division per cell, no reciprocal of the result */
#pragma omp simd reduction(| : bad) reduction(max : inv_dt_max)
  for (size_t i = lo; i < hi; ++i) {
    double du = u[i + 1] - u[i];
    double adu = du < 0.0 ? -du : 0.0;
    q[i] = rho[i] * adu * (cq * adu + cl * c[i]);
    bad |= !(fabs(p[i]) <= DBL_MAX) | !(c[i] >= 0.0);
    double qs = adu > 0.0 ? cl * c[i] + cq2 * adu : 0.0;
    double inv = (qs + sqrt(qs * qs + c[i] * c[i])) / (x[i + 1] - x[i]);
    inv_dt_max = inv > inv_dt_max ? inv : inv_dt_max;
  }
  if (bad) {
    for (size_t i = lo; i < hi; ++i) {
      if (!(fabs(p[i]) <= DBL_MAX)) return fail(g, i, "pressure", p[i]);
      if (!(c[i] >= 0.0)) return fail(g, i, "sound speed", c[i]);
    }
  }
  double dtc = inv_dt_max > 0.0 ? g->cfl / inv_dt_max : INFINITY;
  if (dtc < *dt_constraint) *dt_constraint = dtc;
  return MS_OK;
}

/* One step. The body is inlined three times with the face-area power k as a constant (planar,
 * cylindrical, spherical), so the geometry switches fold away and the loops vectorize.
 *
 * Chunk ordering. Each chunk advances four frontiers, each phase one index behind the phase
 * it reads from: N1 [fN1, nN1); C1+C2 [fC1, nC1) with nC1 = nN1 − 1; N2 [fN2, nN2) with
 * nN2 = nC1; C3–C5 [fC3, nC3) with nC3 = nN2 − 1 (all extended to the ends in the last chunk).
 * State is updated in place: a phase overwrites index i only after every phase that reads the
 * old value at i has passed it (C3–C5 rewrite e, ρ, p, q, c of cells < nN1 − 2, which N1 and C1
 * have finished; N2 moves nodes < nN1 − 1, which C1 has finished). The windows hold global
 * indices [fN1 − CONT_HALO, fN1 + CONT_CHUNK + CONT_HALO); the oldest entries read are at
 * fN1 − 2. */
static inline __attribute__((always_inline)) ms_status step_impl(cont_grid *g, double dt_limit,
                                                                 const int k) {
  double dt = g->dt_next < dt_limit ? g->dt_next : dt_limit;
  if (!(dt >= g->dt_min) && !(dt_limit < g->dt_min && dt == dt_limit)) {
    snprintf(g->err, sizeof g->err,
             "unstable at step %ld, t = %.9g %s: time step %.3g below dt_min = %.3g %s",
             g->step + 1, ms_out_time(g->t), ms_out_time_label(), ms_out_time(dt),
             ms_out_time(g->dt_min), ms_out_time_label());
    return MS_ERR_UNSTABLE;
  }
  const size_t N = g->ncells, Nn = g->nnodes;
  const double t0 = g->t;
  step_ctx sc = {.g = g,
                 .dt = dt,
                 .t1 = t0 + dt,
                 .pL0 = boundary_pressure(&g->left, t0),
                 .pR0 = boundary_pressure(&g->right, t0),
                 .pLh = boundary_pressure(&g->left, t0 + 0.5 * dt),
                 .pRh = boundary_pressure(&g->right, t0 + 0.5 * dt)};
  double dt_constraint = INFINITY;
  size_t fN1 = 0, fC1 = 0, fN2 = 0, fC3 = 0; /* frontiers: everything below is done */
  ms_status st = MS_OK;
  size_t bad = 0;
  g->win_origin = 0;

  while (fC3 < N) {
    size_t nN1 = fN1 + CONT_CHUNK < Nn ? fN1 + CONT_CHUNK : Nn;
    size_t nC1 = nN1 == Nn ? N : nN1 - 1;
    size_t nN2 = nC1 == N ? Nn : nC1;
    size_t nC3 = nN2 == Nn ? N : nN2 - 1;
    /* slide the windows, keeping the last CONT_HALO entries (global [fN1 − HALO, fN1)) */
    if (fN1 > g->win_origin) {
      size_t shift = fN1 - g->win_origin;
      double *const win[] = {g->u_pred_mean, g->area_mid, g->u_mean, g->q_half};
      for (size_t w = 0; w < sizeof win / sizeof win[0]; ++w)
        for (size_t h = 0; h < CONT_HALO; ++h) win[w][h] = win[w][h + shift];
      g->win_origin = fN1;
    }
    sc.o = CONT_HALO - fN1;

    cont_calc_predicted_velocity_for_nodes(&sc, fN1, nN1, k);
    if ((st = cont_calc_half_step_for_cells(&sc, fC1, nC1, k)) != MS_OK) return st;
    cont_calc_velocity_and_position_for_nodes(&sc, fN2, nN2, k);
    if ((st = cont_calc_energy_and_density_for_cells(&sc, fC3, nC3, k)) != MS_OK) return st;
    cont_eval_eos_for_cells(g, fC3, nC3, g->rho, g->e, g->p, g->c, &bad, &st);
    if (st != MS_OK) return fail(g, bad, "EOS state (density)", g->rho[bad]);
    if ((st = cont_calc_q_and_time_constraint_for_cells(&sc, fC3, nC3, &dt_constraint)) != MS_OK)
      return st;

    fN1 = nN1;
    fC1 = nC1;
    fN2 = nN2;
    fC3 = nC3;
  }

  g->work += sc.work;
  g->impulse += sc.impulse;
  /* a step clipped to land on an output time ends exactly there (t0 + (T − t0) may miss T
   * by an ulp), so histories and profiles carry the requested time */
  g->t = (dt == dt_limit && !isnan(g->land_time)) ? g->land_time : sc.t1;
  g->dt_last = dt;
  g->step++;
  /* growth is limited relative to the last unclipped step, so landing on an output time does
   * not slow the run down afterwards */
  double base = dt < g->dt_next ? g->dt_next : dt;
  double dt_next = dt_constraint;
  if (dt_next > g->dt_growth * base) dt_next = g->dt_growth * base;
  if (dt_next > g->dt_max) dt_next = g->dt_max;
  g->dt_next = dt_next;
  cont_record_tags(g);
  return MS_OK;
}

ms_status cont_grid_step(cont_grid *g, double dt_limit) {
  ms_status s;
  switch (g->area_power) {
  case 0:
    s = step_impl(g, dt_limit, 0);
    break;
  case 1:
    s = step_impl(g, dt_limit, 1);
    break;
  default:
    s = step_impl(g, dt_limit, 2);
    break;
  }
  g->land_time = NAN; /* a landing target applies to one step only, failed or not */
  return s;
}

ms_status cont_grid_run_to(cont_grid *g, double t_end) {
  while (g->t < t_end) {
    double left = t_end - g->t;
    /* land exactly on t_end; avoid leaving a sliver step behind */
    double lim = left;
    if (g->dt_next < left && g->dt_next > 0.5 * left) lim = 0.5 * left;
    if (g->dt_next >= left) lim = left;
    if (lim == left) g->land_time = t_end;
    ms_status s = cont_grid_step(g, lim);
    if (s != MS_OK) return s;
  }
  return MS_OK;
}
