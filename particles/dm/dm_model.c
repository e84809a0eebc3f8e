/* SPDX-License-Identifier: MIT */
/* dm_model.c — strain, stress, energy and the exact Hamiltonian force of the discrete model
 * ([Sofronov] §1 with the correction of docs/design.md §5.2).
 *
 * Energy: H_el = Σ_i V_i U_i(E_i), C_i = Σ_k Δw_ik ⊗ g_ik with Δw_ik = w_k − w_i and
 * g_ik = A_i⁻¹ξ_ik, so ∂H/∂w_k (from particle i's term) = V_i σ_i g_ik and
 * ∂H/∂w_i = −Σ_k V_i σ_i g_ik: every bond adds f = V_i σ_i g_ik = P_i ξ_ik to F_i and −f to F_k.
 * Families are symmetric (k ∈ N_i ⇔ i ∈ N_k, with ξ_ki = −ξ_ik), so the force can be gathered
 * per particle without scatter or atomics:  F_i = Σ_{k∈N_i} (P_i + P_k) ξ_ik.
 *
 * Optional hourglass stabilisation (off by default; docs/particles-dm.md): the energy
 *   H_s = Σ_i (κ_i/2) Σ_k |z_ik|²,  z_ik = Δw_ik − C_i ξ_ik  (least-squares residual),
 *   κ_i = c_s G_i V_i / tr A_i,
 * penalises exactly the part of Δw no linear field explains. Because Σ_k z_ik⊗ξ_ik = 0 (normal
 * equations), ∂(½|z|²)/∂Δw = z and the force stays pairwise:
 *   F_i = Σ_k [(Q_i + Q_k) ξ_ik + (κ_i + κ_k) Δw_ik],  Q_i = P_i − κ_i C_i.
 * It vanishes for every linear displacement field, so it changes neither the long-wave
 * elasticity nor the conservation of P and J.
 */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void dm_state_alloc(dm_state *s, size_t n, int dim) {
  memset(s, 0, sizeof *s);
  s->n = n;
  s->dim = dim;
  size_t m = n ? n : 1;
  /* one double of padding: 4-lane loads of the last particle's vector (dm_finite.c) */
  s->X = ms_aligned_alloc(3 * m + 1, sizeof(double));
  s->w = ms_aligned_alloc(3 * m + 1, sizeof(double));
  s->u = ms_aligned_alloc(3 * m + 1, sizeof(double));
  s->mass = ms_aligned_alloc(m, sizeof(double));
  s->vol = ms_aligned_alloc(m, sizeof(double));
  s->K = ms_aligned_alloc(m, sizeof(double));
  s->G = ms_aligned_alloc(m, sizeof(double));
  s->bc = ms_calloc(m, 1);
  s->partner = ms_calloc(m, sizeof(uint32_t));
  s->msign = ms_calloc(3 * m, sizeof(int8_t));
}

void dm_state_free(dm_state *s) {
  if (!s) return;
  free(s->X);
  free(s->w);
  free(s->u);
  free(s->mass);
  free(s->vol);
  free(s->K);
  free(s->G);
  free(s->bc);
  free(s->partner);
  free(s->msign);
  memset(s, 0, sizeof *s);
}

void dm_alloc_work(dm_model *m, size_t n) {
  const size_t na = n ? n : 1;
  m->Ainv = ms_aligned_alloc(9 * na, sizeof(double));
  m->cond = ms_aligned_alloc(na, sizeof(double));
  m->kappa = ms_aligned_alloc(na, sizeof(double));
  m->C = ms_aligned_alloc(9 * na, sizeof(double));
  m->sigma = ms_aligned_alloc(9 * na, sizeof(double));
  m->Q = ms_aligned_alloc(9 * na + 1, sizeof(double)); /* +1: 4-lane loads (dm_finite.c) */
  m->energy = ms_aligned_alloc(na, sizeof(double));
}

ms_status dm_model_create(const dm_model_params *par, dm_model **out) {
  *out = NULL;
  dm_state *s = par->state;
  const dm_options *opt = &par->opt;
  const ms_ctx *ctx = par->ctx;
  if (!s || s->n == 0 || s->dim < 1 || s->dim > 3 || !(opt->horizon > 0.0)) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model: needs particles, dim 1..3 and a horizon > 0");
    return MS_ERR_INPUT;
  }
  if (s->n > UINT32_MAX) {
    ms_log(ctx, MS_LOG_ERROR, "discrete model: more than 2^32 particles");
    return MS_ERR_INPUT;
  }
  for (size_t i = 0; i < s->n; ++i) {
    if (!(s->mass[i] > 0) || !(s->vol[i] > 0) || !(s->K[i] > 0) || !(s->G[i] >= 0)) {
      ms_log(ctx, MS_LOG_ERROR,
             "discrete model: particle %zu at (%g, %g, %g) needs mass, volume, K > 0 and G >= 0", i,
             s->X[3 * i], s->X[3 * i + 1], s->X[3 * i + 2]);
      return MS_ERR_INPUT;
    }
    if (s->bc[i] == DM_MIRROR && (s->partner[i] >= s->n || s->bc[s->partner[i]] == DM_MIRROR)) {
      ms_log(ctx, MS_LOG_ERROR, "discrete model: mirror ghost %zu has no real partner", i);
      return MS_ERR_INPUT;
    }
    for (int a = 0; a < 3; ++a) {
      if (opt->box[a] > 0 && (s->X[3 * i + a] < 0 || s->X[3 * i + a] >= opt->box[a])) {
        ms_log(ctx, MS_LOG_ERROR, "discrete model: particle %zu outside the periodic box", i);
        return MS_ERR_INPUT;
      }
      if (a >= s->dim && (s->X[3 * i + a] != 0.0 || s->w[3 * i + a] != 0.0)) {
        ms_log(ctx, MS_LOG_ERROR,
               "discrete model: particle %zu has a nonzero component %d in a %dD model", i, a,
               s->dim);
        return MS_ERR_INPUT;
      }
    }
  }
  dm_model *m = ms_calloc(1, sizeof *m);
  m->s = s;
  m->opt = *opt;
  if (m->opt.cond_max <= 0) m->opt.cond_max = 1e8;
  size_t n = s->n;
  dm_alloc_work(m, n);
  ms_status st = dm_build_families(m, ctx);
  if (st == MS_OK) st = dm_build_shape(m, ctx, par->first_bad);
  if (st != MS_OK) {
    dm_model_destroy(&m);
    return st;
  }
  for (size_t i = 0; i < n; ++i)
    if (s->bc[i] == DM_FIXED) s->u[3 * i] = s->u[3 * i + 1] = s->u[3 * i + 2] = 0.0;
  *out = m;
  return MS_OK;
}

void dm_model_destroy(dm_model **mp) {
  if (!mp || !*mp) return;
  dm_model *m = *mp;
  free(m->start);
  free(m->nbr);
  free(m->img);
  free(m->Ainv);
  free(m->cond);
  free(m->kappa);
  free(m->C);
  free(m->sigma);
  free(m->Q);
  free(m->energy);
  free(m->xref);
  free(m->rev);
  free(m);
  *mp = NULL;
}

/* Pass 1 for particle i: C_i, σ_i, Q_i and the particle's energy. */
static inline void strain_stress(dm_model *restrict m, const double *restrict w, size_t i) {
  const dm_state *s = m->s;
  const double *restrict X = s->X;
  const double xi0 = X[3 * i], yi0 = X[3 * i + 1], zi0 = X[3 * i + 2];
  const double wx = w[3 * i], wy = w[3 * i + 1], wz = w[3 * i + 2];
  double b00 = 0, b01 = 0, b02 = 0, b10 = 0, b11 = 0, b12 = 0, b20 = 0, b21 = 0, b22 = 0;
  double dw2 = 0;
  const size_t e = m->start[i + 1];
  for (size_t b = m->start[i]; b < e; ++b) {
    const size_t k = m->nbr[b];
    const double *sh = m->shift[m->img[b]];
    const double x = X[3 * k] + sh[0] - xi0, y = X[3 * k + 1] + sh[1] - yi0,
                 z = X[3 * k + 2] + sh[2] - zi0;
    const double dx = w[3 * k] - wx, dy = w[3 * k + 1] - wy, dz = w[3 * k + 2] - wz;
    /* Bᵀ_ab = Σ Δw_a ξ_b */
    b00 += dx * x, b01 += dx * y, b02 += dx * z;
    b10 += dy * x, b11 += dy * y, b12 += dy * z;
    b20 += dz * x, b21 += dz * y, b22 += dz * z;
    dw2 += dx * dx + dy * dy + dz * dz;
  }
  const double Bt[9] = {b00, b01, b02, b10, b11, b12, b20, b21, b22};
  const double *Ai = &m->Ainv[9 * i];
  double *C = &m->C[9 * i];
  const int dim = s->dim;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      C[3 * a + c] =
          a < dim ? Bt[3 * a] * Ai[c] + Bt[3 * a + 1] * Ai[3 + c] + Bt[3 * a + 2] * Ai[6 + c] : 0.0;
  /* E = sym C; σ = λ tr E I + 2G E ([Sofronov] eq. 3 and the formula after it) */
  const double G = s->G[i], lam = s->K[i] - 2.0 * G / 3.0, V = s->vol[i];
  const double tr = C[0] + C[4] + C[8];
  double *sg = &m->sigma[9 * i];
  double U2 = 0.0, CB = 0.0;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c) {
      double E = 0.5 * (C[3 * a + c] + C[3 * c + a]);
      double sv = 2.0 * G * E + (a == c ? lam * tr : 0.0);
      sg[3 * a + c] = sv;
      U2 += sv * E;
      CB += C[3 * a + c] * Bt[3 * a + c];
    }
  const double kap = m->kappa[i];
  /* Σ_k |z_ik|² = Σ|Δw|² − C:Bᵀ (since C A = Bᵀ) */
  m->energy[i] = 0.5 * V * U2 + (kap > 0 ? 0.5 * kap * (dw2 - CB) : 0.0);
  double *Q = &m->Q[9 * i];
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      Q[3 * a + c] =
          V * (sg[3 * a] * Ai[c] + sg[3 * a + 1] * Ai[3 + c] + sg[3 * a + 2] * Ai[6 + c]) -
          kap * C[3 * a + c];
}

/* Pass 2 for particle i: F_i = Σ_k (Q_i + Q_k) ξ_ik [+ (κ_i + κ_k) Δw_ik]. */
static inline void gather_force(const dm_model *restrict m, const double *restrict w, size_t i,
                                double *restrict F, int stab) {
  const double *restrict X = m->s->X;
  const double *restrict Q = m->Q;
  const double xi0 = X[3 * i], yi0 = X[3 * i + 1], zi0 = X[3 * i + 2];
  double fx = 0, fy = 0, fz = 0;
  /* Σ_k Q_k ξ_ik accumulated in f; Q_i Σ_k ξ_ik added once at the end. */
  double sx = 0, sy = 0, sz = 0;
  const size_t e = m->start[i + 1];
  if (!stab) {
    for (size_t b = m->start[i]; b < e; ++b) {
      const size_t k = m->nbr[b];
      const double *sh = m->shift[m->img[b]];
      const double x = X[3 * k] + sh[0] - xi0, y = X[3 * k + 1] + sh[1] - yi0,
                   z = X[3 * k + 2] + sh[2] - zi0;
      const double *q = &Q[9 * k];
      fx += q[0] * x + q[1] * y + q[2] * z;
      fy += q[3] * x + q[4] * y + q[5] * z;
      fz += q[6] * x + q[7] * y + q[8] * z;
      sx += x, sy += y, sz += z;
    }
  } else {
    const double wx = w[3 * i], wy = w[3 * i + 1], wz = w[3 * i + 2], ki = m->kappa[i];
    for (size_t b = m->start[i]; b < e; ++b) {
      const size_t k = m->nbr[b];
      const double *sh = m->shift[m->img[b]];
      const double x = X[3 * k] + sh[0] - xi0, y = X[3 * k + 1] + sh[1] - yi0,
                   z = X[3 * k + 2] + sh[2] - zi0;
      const double *q = &Q[9 * k];
      const double kk = ki + m->kappa[k];
      fx += q[0] * x + q[1] * y + q[2] * z + kk * (w[3 * k] - wx);
      fy += q[3] * x + q[4] * y + q[5] * z + kk * (w[3 * k + 1] - wy);
      fz += q[6] * x + q[7] * y + q[8] * z + kk * (w[3 * k + 2] - wz);
      sx += x, sy += y, sz += z;
    }
  }
  const double *qi = &Q[9 * i];
  F[3 * i] = fx + qi[0] * sx + qi[1] * sy + qi[2] * sz;
  F[3 * i + 1] = fy + qi[3] * sx + qi[4] * sy + qi[5] * sz;
  F[3 * i + 2] = fz + qi[6] * sx + qi[7] * sy + qi[8] * sz;
}

void dm_forces(dm_model *m, const double *w, double *F) {
  const long n = (long)m->s->n;
  const int stab = m->opt.hourglass > 0;
#pragma omp parallel if (n > 16384)
  {
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) strain_stress(m, w, (size_t)i);
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) gather_force(m, w, (size_t)i, F, stab);
  }
}

/* The two passes of dm_forces over particles [0, n) only (the distributed model: owned
 * particles first, ghosts after them; dm_par.c exchanges Q between the passes). */
void dm_stress_pass(dm_model *m, const double *w, size_t n) {
#pragma omp parallel for schedule(static) if (n > 16384)
  for (long i = 0; i < (long)n; ++i) strain_stress(m, w, (size_t)i);
}

void dm_gather_pass(dm_model *m, const double *w, double *F, size_t n) {
  const int stab = m->opt.hourglass > 0;
#pragma omp parallel for schedule(static) if (n > 16384)
  for (long i = 0; i < (long)n; ++i) gather_force(m, w, (size_t)i, F, stab);
}

double dm_potential_energy(dm_model *m, const double *w) {
  const long n = (long)m->s->n;
#pragma omp parallel for schedule(static) if (n > 16384)
  for (long i = 0; i < n; ++i) strain_stress(m, w, (size_t)i);
  double sum = 0.0; /* serial: the same sum on any thread count */
  for (long i = 0; i < n; ++i)
    if (m->s->bc[i] != DM_MIRROR) sum += m->energy[i];
  return sum;
}

double dm_kinetic_energy(const dm_state *s) {
  double sum = 0.0;
  for (size_t i = 0; i < s->n; ++i) {
    if (s->bc[i] == DM_MIRROR) continue;
    const double *u = &s->u[3 * i];
    sum += 0.5 * s->mass[i] * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  }
  return sum;
}

void dm_momenta(const dm_state *s, double P[3], double J[3]) {
  for (int a = 0; a < 3; ++a) P[a] = J[a] = 0.0;
  for (size_t i = 0; i < s->n; ++i) {
    if (s->bc[i] == DM_MIRROR) continue;
    const double *u = &s->u[3 * i], *X = &s->X[3 * i];
    double m = s->mass[i];
    for (int a = 0; a < 3; ++a) P[a] += m * u[a];
    J[0] += m * (X[1] * u[2] - X[2] * u[1]);
    J[1] += m * (X[2] * u[0] - X[0] * u[2]);
    J[2] += m * (X[0] * u[1] - X[1] * u[0]);
  }
}

void dm_cauchy_stress(const dm_model *m, double *S) {
  const long n = (long)m->s->n;
#pragma omp parallel for schedule(static) if (n > 16384)
  for (long i = 0; i < n; ++i) {
    const double *C = &m->C[9 * i], *sg = &m->sigma[9 * i];
    double Fd[9]; /* I + Cᵀ */
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) Fd[3 * a + c] = (a == c) + C[3 * c + a];
    /* det(I + C) = det(I + Cᵀ) = V/V⁰ = ρ⁰/ρ */
    double J = Fd[0] * (Fd[4] * Fd[8] - Fd[5] * Fd[7]) - Fd[1] * (Fd[3] * Fd[8] - Fd[5] * Fd[6]) +
               Fd[2] * (Fd[3] * Fd[7] - Fd[4] * Fd[6]);
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c)
        S[9 * i + 3 * a + c] =
            (sg[3 * a] * Fd[c] + sg[3 * a + 1] * Fd[3 + c] + sg[3 * a + 2] * Fd[6 + c]) / J;
  }
}

double dm_hourglass_norm(const dm_model *m, const double *w, double *dw_norm) {
  double num = 0.0, den = 0.0;
  for (size_t i = 0; i < m->s->n; ++i) {
    if (m->s->bc[i] != DM_FREE) continue;
    const double *C = &m->C[9 * i];
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      size_t k = m->nbr[b];
      double xi[3];
      dm_bond_vector(m, i, b, xi);
      for (int a = 0; a < 3; ++a) {
        double dw = w[3 * k + a] - w[3 * i + a];
        double z = dw - (C[3 * a] * xi[0] + C[3 * a + 1] * xi[1] + C[3 * a + 2] * xi[2]);
        num += z * z;
        den += dw * dw;
      }
    }
  }
  if (dw_norm) *dw_norm = sqrt(den);
  return sqrt(num);
}

ms_status dm_accel(void *user, double t, const double *q, double *acc) {
  dm_model *m = user;
  const dm_state *s = m->s;
  dm_forces(m, q, acc);
  const long n = (long)s->n;
  const int dim = s->dim;
  int bad = 0;
#pragma omp parallel for schedule(static) reduction(| : bad) if (n > 16384)
  for (long i = 0; i < n; ++i) {
    double inv = s->bc[i] == DM_FREE ? 1.0 / s->mass[i] : 0.0;
    for (int a = 0; a < 3; ++a) {
      double v = a < dim ? acc[3 * i + a] * inv : 0.0;
      if (!isfinite(v)) bad = 1;
      acc[3 * i + a] = v;
    }
  }
  return bad ? MS_ERR_UNSTABLE : MS_OK;
}

void dm_constrain(void *user, double t, double *q, double *u) {
  dm_model *m = user;
  const dm_state *s = m->s;
  const double h = 1e-6 * (1.0 + fabs(t));
  for (size_t i = 0; i < s->n && m->prescribe; ++i) {
    if (s->bc[i] != DM_PRESCRIBED) continue;
    m->prescribe(m->prescribe_user, i, &s->X[3 * i], t, &q[3 * i]);
    if (u) { /* velocity of the prescribed motion, central difference */
      double wp[3], wm[3];
      m->prescribe(m->prescribe_user, i, &s->X[3 * i], t + h, wp);
      m->prescribe(m->prescribe_user, i, &s->X[3 * i], t - h, wm);
      for (int a = 0; a < 3; ++a) u[3 * i + a] = (wp[a] - wm[a]) / (2.0 * h);
    }
  }
  for (size_t i = 0; i < s->n; ++i) {
    if (s->bc[i] != DM_MIRROR) continue;
    size_t p = s->partner[i];
    for (int a = 0; a < 3; ++a) {
      q[3 * i + a] = s->msign[3 * i + a] * q[3 * p + a];
      if (u) u[3 * i + a] = s->msign[3 * i + a] * u[3 * p + a];
    }
  }
}
