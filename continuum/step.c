/* step.c — one time step of the 1D Lagrangian cross scheme (DESIGN.md §4), as phase functions.
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
 *               e^{n+½} = eⁿ − (p+q)ⁿ (V^{n+½} − Vⁿ)/m,   p^{n+½} = P(ρ^{n+½}, e^{n+½}),
 *               q^{n+½} from û
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
 * the phase it depends on, so the ~20 arrays of a chunk stay in L1/L2 (docs/continuum.md). All
 * state updates are in place; only the predictor quantities live in scratch arrays.
 */
#include "cont_impl.h"

#include <float.h>
#include <math.h>
#include <stdio.h>

enum { CHUNK = 512 };

static inline double face_area(double x, int k) {
  switch (k) {
  case 0: return 1.0;
  case 1: return x;
  default: return x * x;
  }
}

/* Mean-value area between positions a and b: (b^{k+1} − a^{k+1}) / ((k+1)(b − a)). */
static inline double mean_area(double a, double b, int k) {
  switch (k) {
  case 0: return 1.0;
  case 1: return 0.5 * (a + b);
  default: return (a * a + a * b + b * b) * (1.0 / 3.0);
  }
}

static inline double volume_between(double xl, double xr, int k) {
  switch (k) {
  case 0: return xr - xl;
  case 1: return 0.5 * (xr - xl) * (xr + xl);
  default: return (xr - xl) * (xr * xr + xr * xl + xl * xl) * (1.0 / 3.0);
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
  case CONT_BC_WALL: return 0.0;
  case CONT_BC_PISTON: return cont_fn_eval(&bc->fn, t);
  default: return NAN;
  }
}

/* F_j = A_j [(p+q)_{j−1} − (p+q)_j] for nodes [lo, hi); boundary nodes see the outside pressure.
 * area == NULL means A(xpos_j). External tractions are added on the slow path. */
void cont_calc_force_for_nodes(cont_grid *g, size_t lo, size_t hi, const double *xpos,
                               const double *pq_cells, const double *area, double p_left,
                               double p_right, double *force_out) {
  const size_t ncells = g->ncells;
  const int k = g->area_power;
  /* interior nodes: vectorizable loop; the ends and coupling tractions after it */
  size_t a0 = lo > 0 ? lo : 1, b0 = hi < ncells ? hi : ncells;
  if (area) {
    for (size_t j = a0; j < b0; ++j) force_out[j] = area[j] * (pq_cells[j - 1] - pq_cells[j]);
  } else {
    for (size_t j = a0; j < b0; ++j)
      force_out[j] = face_area(xpos[j], k) * (pq_cells[j - 1] - pq_cells[j]);
  }
  for (size_t j = lo; j < hi; ++j) {
    if (j != 0 && j != ncells && !g->any_ext) {
      j = b0 - 1; /* skip the interior */
      continue;
    }
    double pl = j > 0 ? pq_cells[j - 1] : p_left;
    double pr = j < ncells ? pq_cells[j] : p_right;
    double a = area ? area[j] : face_area(xpos[j], k);
    force_out[j] = a * (pl - pr + g->ext_traction[j]);
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
void cont_eval_eos_for_cells(cont_grid *g, size_t lo, size_t hi, const double *rho,
                             const double *e, double *p, double *c, size_t *bad, ms_status *st) {
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
 * Q = q_lin c + 2 q_quad |Δu| in compression (Benson 1991 form). */
static inline double time_constraint(const cont_grid *g, size_t lo, size_t hi, int k) {
  const double *restrict x = g->x, *restrict u = g->u, *restrict c = g->c;
  const double cq2 = 2.0 * g->q_quad, cl = g->q_lin;
  double inv_dt_max = 0.0; /* max of 1/Δt avoids a division per cell */
  (void)k;
#pragma omp simd reduction(max : inv_dt_max)
  for (size_t i = lo; i < hi; ++i) {
    double dx = x[i + 1] - x[i];
    double du = u[i + 1] - u[i];
    double adu = du < 0.0 ? -du : 0.0;
    double qs = adu > 0.0 ? cl * c[i] + cq2 * adu : 0.0;
    double speed = qs + sqrt(qs * qs + c[i] * c[i]);
    double inv = speed / dx;
    inv_dt_max = inv > inv_dt_max ? inv : inv_dt_max;
  }
  return inv_dt_max > 0.0 ? g->cfl / inv_dt_max : INFINITY;
}

double cont_calc_time_constraint(const cont_grid *g, size_t lo, size_t hi) {
  return time_constraint(g, lo, hi, g->area_power);
}

static ms_status fail(cont_grid *g, size_t cell, const char *what, double value) {
  snprintf(g->err, sizeof g->err,
           "unstable at step %ld, t = %.9g: %s in cell %zu (layer %d, x = %.6g) = %.6g",
           g->step + 1, g->t, what, cell, g->layer[cell], 0.5 * (g->x[cell] + g->x[cell + 1]),
           value);
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

/* Predictor for one node: û = ½(uⁿ + u*) and the mean-value area Ā between xⁿ and x*. */
static inline void predict_node(cont_grid *g, size_t j, double dt, double t_new) {
  double us = g->u[j] + dt * g->force[j] * g->inv_mass[j];
  if (node_is_special(g, j)) {
    double v = node_constraint(g, j, t_new);
    if (!isnan(v)) us = v;
  }
  g->u_pred_mean[j] = 0.5 * (g->u[j] + us);
  g->area_mid[j] = mean_area(g->x[j], g->x[j] + dt * g->u_pred_mean[j], g->area_power);
}

/* Corrector for a boundary/coupled node: constraint, reaction force and the work done on the
 * grid by everything outside it (outside pressure, external traction, constraint). */
static inline void correct_special_node(cont_grid *g, size_t j, double dt, double t_new,
                                        double p_left, double p_right, double *work,
                                        double *impulse) {
  double u_old = g->u[j], a = g->area_mid[j], f = g->force[j];
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
  g->u_mean[j] = ub;
  g->x[j] += dt * ub;
  g->u[j] = un;
}

/* The step body is inlined three times with the face-area power k as a constant (planar,
 * cylindrical, spherical), so the geometry switches fold away and the loops vectorize. */
static inline __attribute__((always_inline)) ms_status step_impl(cont_grid *g, double dt_limit,
                                                                 const int k) {
  double dt = g->dt_next < dt_limit ? g->dt_next : dt_limit;
  if (!(dt >= g->dt_min) && !(dt_limit < g->dt_min && dt == dt_limit)) {
    snprintf(g->err, sizeof g->err,
             "unstable at step %ld, t = %.9g: time step %.3g below dt_min = %.3g", g->step + 1,
             g->t, dt, g->dt_min);
    return MS_ERR_UNSTABLE;
  }
  const size_t N = g->ncells, Nn = g->nnodes;
  const double t0 = g->t, t_half = t0 + 0.5 * dt, t1 = t0 + dt;
  const double pL0 = boundary_pressure(&g->left, t0), pR0 = boundary_pressure(&g->right, t0);
  const double pLh = boundary_pressure(&g->left, t_half), pRh = boundary_pressure(&g->right, t_half);

  /* distinct arrays: restrict lets the compiler vectorize without alias checks */
  double *restrict x = g->x, *restrict u = g->u;
  const double *restrict im = g->inv_mass;
  double *restrict upm = g->u_pred_mean, *restrict am = g->area_mid, *restrict ubar = g->u_mean;
  const double *restrict m = g->mass, *restrict im_c = g->inv_cell_mass;
  double *restrict vol = g->vol, *restrict rho = g->rho, *restrict e = g->e, *restrict p = g->p,
                     *restrict q = g->q, *restrict c = g->c;
  double *restrict rh = g->rho_half, *restrict eh = g->e_half, *restrict ph = g->p_half,
                     *restrict qh = g->q_half;

  double work = 0.0, impulse = 0.0, dt_constraint = INFINITY;
  size_t fN1 = 0, fC1 = 0, fN2 = 0, fC3 = 0; /* frontiers: everything below is done */
  ms_status st = MS_OK;
  size_t bad = 0;

  while (fC3 < N) {
    size_t nN1 = fN1 + CHUNK < Nn ? fN1 + CHUNK : Nn;
    size_t nC1 = nN1 == Nn ? N : nN1 - 1;
    size_t nN2 = nC1 == N ? Nn : nC1;
    size_t nC3 = nN2 == Nn ? N : nN2 - 1;

    /* (p+q)ⁿ into the q_half scratch for the predictor force: cells [fN1, nN1) (cell fN1−1
     * was formed in the previous chunk and C2 has not overwritten it yet). */
    for (size_t i = fN1; i < (nN1 < N ? nN1 : N); ++i) qh[i] = p[i] + q[i];
    /* N1: predictor velocities (forces from (p+q)ⁿ, areas at xⁿ). */
    cont_calc_force_for_nodes(g, fN1, nN1, x, qh, NULL, pL0, pR0, g->force);
    if (g->any_ext) {
      for (size_t j = fN1; j < nN1; ++j) predict_node(g, j, dt, t1);
    } else {
      size_t a = fN1 > 0 ? fN1 : 1, b = nN1 < N ? nN1 : N;
      const double *force = g->force;
      for (size_t j = a; j < b; ++j) {
        double us = u[j] + dt * force[j] * im[j];
        upm[j] = 0.5 * (u[j] + us);
        am[j] = mean_area(x[j], x[j] + dt * upm[j], k);
      }
      if (fN1 == 0) predict_node(g, 0, dt, t1);
      if (nN1 == Nn) predict_node(g, N, dt, t1);
    }

    /* C1: half-step cells. The work of the first half step uses pⁿ and the viscosity of the
     * predicted velocities û, so that q·ΔV ≤ 0 (q from a different velocity field could do
     * negative work and drive a cold gas to e < 0). */
    int neg = 0;
    {
      const double cq = g->q_quad, cl = g->q_lin;
#pragma omp simd reduction(| : neg)
      for (size_t i = fC1; i < nC1; ++i) {
        double xl = x[i] + 0.5 * dt * upm[i], xr = x[i + 1] + 0.5 * dt * upm[i + 1];
        double vh = volume_between(xl, xr, k);
        neg |= !(vh > 0.0);
        rh[i] = m[i] / vh;
        double du = upm[i + 1] - upm[i];
        double adu = du < 0.0 ? -du : 0.0;
        double qhat = rho[i] * adu * (cq * adu + cl * c[i]);
        /* ΔV in the same face-area × velocity form as the corrector (not V^{n+½} − Vⁿ, whose
         * rounding can disagree in sign with Δû and let q do negative work in a cold gas) */
        double dv = 0.5 * dt * (am[i + 1] * upm[i + 1] - am[i] * upm[i]);
        eh[i] = e[i] - (p[i] + qhat) * dv * im_c[i];
      }
    }
    if (neg) {
      for (size_t i = fC1; i < nC1; ++i) {
        double xl = x[i] + 0.5 * dt * upm[i], xr = x[i + 1] + 0.5 * dt * upm[i + 1];
        double vh = volume_between(xl, xr, k);
        if (!(vh > 0.0)) return fail(g, i, "volume (predictor)", vh);
      }
    }
    /* C2: half-step pressure and viscosity. qh held (p+q)ⁿ up to here; cells < nC1 are no
     * longer needed by N1 (it is ahead), so they are overwritten with q^{n+½} + p^{n+½}. */
    cont_eval_eos_for_cells(g, fC1, nC1, rh, eh, ph, NULL, &bad, &st);
    if (st != MS_OK) return fail(g, bad, "EOS state (predictor)", rh[bad]);
    {
      const double cq = g->q_quad, cl = g->q_lin;
      for (size_t i = fC1; i < nC1; ++i) {
        double du = upm[i + 1] - upm[i];
        double adu = du < 0.0 ? -du : 0.0;
        qh[i] = ph[i] + rh[i] * adu * (cq * adu + cl * c[i]);
      }
    }

    /* N2: corrector velocities and positions (forces from (p+q)^{n+½}, areas Ā). */
    cont_calc_force_for_nodes(g, fN2, nN2, x, qh, am, pLh, pRh, g->force);
    if (g->any_ext) {
      for (size_t j = fN2; j < nN2; ++j)
        correct_special_node(g, j, dt, t1, pLh, pRh, &work, &impulse);
    } else {
      size_t a = fN2 > 0 ? fN2 : 1, b = nN2 < N ? nN2 : N;
      const double *force = g->force;
      for (size_t j = a; j < b; ++j) {
        double un = u[j] + dt * force[j] * im[j];
        double ub = 0.5 * (u[j] + un);
        ubar[j] = ub;
        x[j] += dt * ub;
        u[j] = un;
      }
      if (fN2 == 0) correct_special_node(g, 0, dt, t1, pLh, pRh, &work, &impulse);
      if (nN2 == Nn) correct_special_node(g, N, dt, t1, pLh, pRh, &work, &impulse);
    }

    /* C3: energy, volume, density at tⁿ⁺¹. */
    int badc = 0;
#pragma omp simd reduction(| : badc)
    for (size_t i = fC3; i < nC3; ++i) {
      double wrk = qh[i] * (am[i + 1] * ubar[i + 1] - am[i] * ubar[i]);
      e[i] -= dt * wrk * im_c[i];
      double v = volume_between(x[i], x[i + 1], k);
      vol[i] = v;
      rho[i] = m[i] / v;
      badc |= !(v > 0.0) | !(fabs(e[i]) <= DBL_MAX);
    }
    if (badc) {
      for (size_t i = fC3; i < nC3; ++i) {
        if (!(vol[i] > 0.0)) return fail(g, i, "volume", vol[i]);
        if (!(fabs(e[i]) <= DBL_MAX)) return fail(g, i, "specific internal energy", e[i]);
      }
    }
    /* C4: EOS. */
    cont_eval_eos_for_cells(g, fC3, nC3, rho, e, p, c, &bad, &st);
    if (st != MS_OK) return fail(g, bad, "EOS state (density)", rho[bad]);
    /* C5: viscosity and the next step's constraint. */
    cont_calc_q_for_cells(g, fC3, nC3, rho, u, c, q);
    {
      int badp = 0;
#pragma omp simd reduction(| : badp)
      for (size_t i = fC3; i < nC3; ++i) badp |= !(fabs(p[i]) <= DBL_MAX) | !(c[i] >= 0.0);
      if (badp) {
        for (size_t i = fC3; i < nC3; ++i) {
          if (!(fabs(p[i]) <= DBL_MAX)) return fail(g, i, "pressure", p[i]);
          if (!(c[i] >= 0.0)) return fail(g, i, "sound speed", c[i]);
        }
      }
    }
    double dtc = time_constraint(g, fC3, nC3, k);
    if (dtc < dt_constraint) dt_constraint = dtc;

    fN1 = nN1;
    fC1 = nC1;
    fN2 = nN2;
    fC3 = nC3;
  }

  g->work += work;
  g->impulse += impulse;
  /* a step clipped to land on an output time ends exactly there (t0 + (T − t0) may miss T
   * by an ulp), so histories and profiles carry the requested time */
  g->t = (dt == dt_limit && !isnan(g->land_time)) ? g->land_time : t1;
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
  case 0: s = step_impl(g, dt_limit, 0); break;
  case 1: s = step_impl(g, dt_limit, 1); break;
  default: s = step_impl(g, dt_limit, 2); break;
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
