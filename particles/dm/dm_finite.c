/* SPDX-License-Identifier: MIT */
/* dm_finite.c — the discrete model at finite deformation (docs/particles-dm.md, "Finite
 * deformation"): least-squares F over the reference family, pressure from the material's EOS,
 * a hypoelastic (Jaumann) deviator with J2 radial return, a bulk viscosity, the first
 * Piola–Kirchhoff stress in the bond gather of dm_model.c, and a kick–drift–kick integrator
 * whose internal-energy update uses the time-centred velocity of each half kick, so that
 * kinetic + internal + bond-penalty energy − driven work is conserved to round-off.
 *
 * Energy identity (families symmetric, Q_i = V_i P_i A_i⁻¹ − κ_i C_i, z_ik = Δw_ik − C_i ξ_ik):
 *   Σ_i f_i·ū_i = −Σ_i [V_i P_i : Ḟ_i(ū) + κ_i Σ_k z_ik·Δū_ik]   for any velocity field ū,
 * so a half kick Δu_i = (dt/2) f_i/m_i with m_i Δe_i = (dt/2) V_i P_i : Ḟ_i(ū), ū = (u⁻ + u⁺)/2,
 * ΔE_hg,i = (dt/2) κ_i Σ_k z_ik·Δū_ik changes Σ m|u|²/2 + Σ m e + E_hg by exactly the work
 * −(dt/2) Σ_driven f_i·u_i of the driven particles.
 */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double det3(const double *a) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
         a[2] * (a[3] * a[7] - a[4] * a[6]);
}

static void inv3(const double *a, double det, double *r) {
  const double id = 1.0 / det;
  r[0] = (a[4] * a[8] - a[5] * a[7]) * id;
  r[1] = (a[2] * a[7] - a[1] * a[8]) * id;
  r[2] = (a[1] * a[5] - a[2] * a[4]) * id;
  r[3] = (a[5] * a[6] - a[3] * a[8]) * id;
  r[4] = (a[0] * a[8] - a[2] * a[6]) * id;
  r[5] = (a[2] * a[3] - a[0] * a[5]) * id;
  r[6] = (a[3] * a[7] - a[4] * a[6]) * id;
  r[7] = (a[1] * a[6] - a[0] * a[7]) * id;
  r[8] = (a[0] * a[4] - a[1] * a[3]) * id;
}

static int is_driven(uint8_t bc) { return bc == DM_PRESCRIBED || bc == DM_FIXED; }

/* Strain, stress and Q of particle i at the current w, with rates from u; advances the deviator
 * by dt. Returns the particle's stable time step, or −1 (bad state, recorded in *what). */
static double stress_one(dm_fin *f, size_t i, double dt, const char **what, double *val) {
  dm_model *m = f->m;
  const dm_state *st = m->s;
  const double *w = st->w, *u = st->u, *Ai = &m->Ainv[9 * i];
  double C[9] = {0}, Fd[9] = {0};
  for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
    const size_t k = m->nbr[b];
    double xi[3], g[3];
    dm_bond_vector(m, i, b, xi);
    for (int a = 0; a < 3; ++a)
      g[a] = Ai[3 * a] * xi[0] + Ai[3 * a + 1] * xi[1] + Ai[3 * a + 2] * xi[2];
    for (int a = 0; a < 3; ++a) {
      const double dw = w[3 * k + a] - w[3 * i + a], dv = u[3 * k + a] - u[3 * i + a];
      for (int c = 0; c < 3; ++c) C[3 * a + c] += dw * g[c], Fd[3 * a + c] += dv * g[c];
    }
  }
  double *F = &f->F[9 * i];
  for (int a = 0; a < 9; ++a) F[a] = C[a];
  F[0] += 1.0, F[4] += 1.0, F[8] += 1.0;
  const double J = det3(F);
  f->J[i] = J;
  if (!(J > 0) || !isfinite(J)) {
    *what = "J = det F", *val = J;
    return -1.0;
  }
  double Fi[9], L[9];
  inv3(F, J, Fi);
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      L[3 * a + c] = Fd[3 * a] * Fi[c] + Fd[3 * a + 1] * Fi[3 + c] + Fd[3 * a + 2] * Fi[6 + c];
  const double trD = L[0] + L[4] + L[8];
  const dm_fin_material *mt = &f->mat[f->imat[i]];
  const double rho0 = st->mass[i] / st->vol[i], rho = rho0 / J;
  const bool open = dm_frac_open(f, i, J); /* an open crack: no EOS (dm_fracture.c) */
  const double p = open ? 0.0 : eos_pressure(mt->eos, rho, f->e[i]);
  const double c = open ? eos_c0(mt->eos) : eos_sound_speed(mt->eos, rho, f->e[i]);
  if (!isfinite(p) || !isfinite(c)) {
    *what = "pressure p(rho, e)", *val = p;
    return -1.0;
  }
  const double ell = f->par.ell * pow(J, 1.0 / f->dim);
  const double q =
      trD < 0 && !open ? rho * ell * (f->par.cq * ell * -trD + f->par.cl * c) * -trD : 0.0;
  double *s = &f->s[9 * i];
  const int strength = mt->yield != DM_YIELD_NONE;
  double G = mt->G, Y = mt->Y0; /* elastic_plastic: constants */
  /* steinberg_guinan G(p, T), Y(ε_p, p, T); johnson_cook Y(ε_p, ε̇, T); not for a failed
   * particle (no deviator; an open one's density may be beyond the cold curve) */
  if (mt->yield >= DM_YIELD_STEINBERG_GUINAN && !dm_frac_failed(f, i)) {
    const double T = dm_sg_temperature(mt->sg, mt->eos, rho, f->e[i]);
    if (!isfinite(T)) {
      *what = "temperature T (no cold curve at this density)", *val = rho;
      return -1.0;
    }
    if (mt->yield == DM_YIELD_JOHNSON_COOK) { /* rate: √(2/3 D′:D′) of this step's L */
      double dd = 0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) dd += 0.25 * pow(L[3 * a + b] + L[3 * b + a], 2);
      const double rate = sqrt(2.0 / 3.0 * fmax(dd - trD * trD / 3.0, 0.0));
      G = mt->sg->G0, Y = dm_jc_yield(mt->sg, f->eps_p[i], rate, T);
    } else dm_sg_moduli(mt->sg, rho / eos_rho0(mt->eos), p, T, f->eps_p[i], &G, &Y);
  }
  if (strength && dt > 0 && !dm_frac_failed(f, i)) {
    /* Jaumann: ṡ = 2G D′ + W s − s W (D = sym L, W = skew L) */
    double D[9], W[9], ds[9];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        D[3 * a + b] = 0.5 * (L[3 * a + b] + L[3 * b + a]);
        W[3 * a + b] = 0.5 * (L[3 * a + b] - L[3 * b + a]);
      }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double ws = 0;
        for (int c2 = 0; c2 < 3; ++c2)
          ws += W[3 * a + c2] * s[3 * c2 + b] - s[3 * a + c2] * W[3 * c2 + b];
        ds[3 * a + b] = 2.0 * G * (D[3 * a + b] - (a == b ? trD / 3.0 : 0.0)) + ws;
      }
    for (int a = 0; a < 9; ++a) s[a] += dt * ds[a];
    const double tr = (s[0] + s[4] + s[8]) / 3.0; /* keep s traceless against round-off */
    s[0] -= tr, s[4] -= tr, s[8] -= tr;
    double ss = 0;
    for (int a = 0; a < 9; ++a) ss += s[a] * s[a];
    const double seq = sqrt(1.5 * ss);
    if (seq > Y && G > 0) { /* J2 radial return */
      const double r = Y / seq;
      for (int a = 0; a < 9; ++a) s[a] *= r;
      f->eps_p[i] += (seq - Y) / (3.0 * G);
    } else if (seq > Y) /* molten (steinberg_guinan above T_m): no deviator */
      for (int a = 0; a < 9; ++a) s[a] = 0.0;
  }
  double *sg = &f->sig[9 * i];
  for (int a = 0; a < 9; ++a) sg[a] = s[a];
  sg[0] -= p + q, sg[4] -= p + q, sg[8] -= p + q;
  dm_frac_stress(f, i, mt, J, sg, s); /* failure test; a failed particle's cut-off */
  double P[9];                        /* P = J σ F⁻ᵀ */
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      P[3 * a + b] = J * (sg[3 * a] * Fi[3 * b] + sg[3 * a + 1] * Fi[3 * b + 1] +
                          sg[3 * a + 2] * Fi[3 * b + 2]);
  double *QP = &f->QP[9 * i], *Q = &m->Q[9 * i];
  const double V = st->vol[i], kap = m->kappa[i];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      QP[3 * a + b] = V * (P[3 * a] * Ai[b] + P[3 * a + 1] * Ai[3 + b] + P[3 * a + 2] * Ai[6 + b]);
      Q[3 * a + b] = QP[3 * a + b] - kap * C[3 * a + b];
    }
  f->rho[i] = rho, f->p[i] = p, f->q[i] = q;
  const double cL = sqrt(c * c + (strength ? 4.0 * G / (3.0 * rho) : 0.0));
  /* ν_q / ℓ; the quadratic term only where q acts (compression, not open): elsewhere it would
   * only shrink the step — without bound in a stretching jet tip or a broken particle, whose
   * |tr D| from a scattered family is large (docs/particles-dm.md "Time step") */
  const double nu_l = (q > 0 ? f->par.cq * ell * -trD : 0.0) + f->par.cl * c;
  return f->par.courant * ell / (cL + 2.0 * nu_l);
}

/* All stresses and the forces; sets dt_next. */
static ms_status forces(dm_fin *f, double dt) {
  const long n = (long)f->n;
  double dtmin = INFINITY;
  long bad = n, imin = 0;
#pragma omp parallel if (n > 4096)
  { /* the smallest step and its particle (the smallest index of ties: thread-count independent) */
    double tdt = INFINITY;
    long tbad = n, ti = n;
#pragma omp for schedule(static) nowait
    for (long i = 0; i < n; ++i) {
      const char *what = NULL;
      double val = 0;
      double d = stress_one(f, (size_t)i, dt, &what, &val);
      if (d < 0) {
        if (i < tbad) tbad = i;
      } else if (d < tdt) tdt = d, ti = i;
    }
#pragma omp critical(dm_fin_forces_min)
    {
      if (tbad < bad) bad = tbad;
      if (tdt < dtmin || (tdt == dtmin && ti < imin)) dtmin = tdt, imin = ti;
    }
  }
  if (bad < n) { /* redo the first bad particle serially for the report (no deviator step) */
    const char *what = "state";
    double val = 0;
    stress_one(f, (size_t)bad, 0.0, &what, &val);
    f->bad = (size_t)bad, f->bad_what = what, f->bad_value = val;
    return MS_ERR_UNSTABLE;
  }
  dm_gather_pass(f->m, f->m->s->w, f->frc, f->n);
  if (f->ext) { /* an external force (the rigid wall of dm_impact.c) */
    const double dext = f->ext(f->ext_user, f, f->fext);
    for (size_t j = 0; j < 3 * f->n; ++j) f->frc[j] += f->fext[j];
    if (dext < dtmin) dtmin = dext;
  }
  for (long i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      if (!isfinite(f->frc[3 * i + a])) {
        f->bad = (size_t)i, f->bad_what = "force", f->bad_value = f->frc[3 * i + a];
        return MS_ERR_UNSTABLE;
      }
  f->dt_next = dtmin, f->dt_particle = (size_t)imin;
  return MS_OK;
}

ms_status dm_fin_refresh(dm_fin *f) { return forces(f, 0.0); }

/* Half kick of length h = dt/2 with the current forces, and the matching energy updates. */
static ms_status half_kick(dm_fin *f, double h) {
  dm_model *m = f->m;
  dm_state *st = m->s;
  const long n = (long)f->n;
  double dW = 0.0, dWe = 0.0;
  for (long i = 0; i < n; ++i) {
    double *u = &st->u[3 * i], *vb = &f->vbar[3 * i];
    if (is_driven(st->bc[i])) {
      for (int a = 0; a < 3; ++a) vb[a] = u[a];
      dW -= h * (f->frc[3 * i] * u[0] + f->frc[3 * i + 1] * u[1] + f->frc[3 * i + 2] * u[2]);
      continue;
    }
    const double im = h / st->mass[i];
    for (int a = 0; a < f->dim; ++a) {
      const double u1 = u[a] + im * f->frc[3 * i + a];
      vb[a] = 0.5 * (u[a] + u1);
      u[a] = u1;
      if (f->ext) dWe += h * f->fext[3 * i + a] * vb[a]; /* its share of Σ m Δ|u|²/2 */
    }
  }
  f->work += dW, f->ext_work += dWe;
  long bad = n;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > 4096)
  for (long i = 0; i < n; ++i) {
    const double *QP = &f->QP[9 * i], *C = &f->F[9 * i], *w = st->w, *vb = f->vbar;
    double pw = 0.0, ph = 0.0;
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      const size_t k = m->nbr[b];
      double xi[3];
      dm_bond_vector(m, (size_t)i, b, xi);
      for (int a = 0; a < 3; ++a) {
        const double dv = vb[3 * k + a] - vb[3 * i + a];
        const double qx = QP[3 * a] * xi[0] + QP[3 * a + 1] * xi[1] + QP[3 * a + 2] * xi[2];
        /* z = Δw − (F − I) ξ */
        const double z = w[3 * k + a] - w[3 * i + a] -
                         (C[3 * a] * xi[0] + C[3 * a + 1] * xi[1] + C[3 * a + 2] * xi[2] - xi[a]);
        pw += dv * qx, ph += dv * z;
      }
    }
    f->e[i] += h * pw / st->mass[i];
    f->ehg[i] += h * m->kappa[i] * ph;
    if (!isfinite(f->e[i]) && i < bad) bad = i;
  }
  if (bad < n) {
    f->bad = (size_t)bad, f->bad_what = "specific internal energy e", f->bad_value = f->e[bad];
    return MS_ERR_UNSTABLE;
  }
  return MS_OK;
}

ms_status dm_fin_step(dm_fin *f) {
  dm_state *st = f->m->s;
  const double dt = f->dt_next;
  ms_status r = half_kick(f, 0.5 * dt);
  if (r != MS_OK) return r;
  for (size_t i = 0; i < 3 * f->n; ++i) st->w[i] += dt * st->u[i];
  r = forces(f, dt);
  if (r != MS_OK) return r;
  r = half_kick(f, 0.5 * dt);
  ++f->step;
  return r;
}

void dm_fs_history_init(dm_fs_history *h, size_t cap) {
  *h = (dm_fs_history){.rows = ms_calloc(2 * cap, sizeof(double)), .cap = cap, .stride = 1};
}

void dm_fs_history_record(dm_fs_history *h, long step, double t, const dm_state *s, long nx,
                          long nyz) {
  if (step % h->stride != 0) return;
  if (h->n == h->cap) {
    for (size_t r = 0; r < h->n / 2; ++r)
      memmove(&h->rows[2 * r], &h->rows[4 * r], 2 * sizeof(double));
    h->n /= 2, h->stride *= 2;
    if (step % h->stride != 0) return;
  }
  double ux = 0;
  for (long j = 0; j < nyz; ++j) ux += s->u[3 * (size_t)(j * nx + nx - 1)];
  h->rows[2 * h->n] = t, h->rows[2 * h->n + 1] = ux / (double)nyz;
  ++h->n;
}

void dm_fin_energies(const dm_fin *f, double *kinetic, double *internal, double *hourglass) {
  const dm_state *st = f->m->s;
  double K = 0, U = 0, H = 0;
  for (size_t i = 0; i < f->n; ++i) {
    const double *u = &st->u[3 * i];
    if (!is_driven(st->bc[i])) K += 0.5 * st->mass[i] * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    U += st->mass[i] * f->e[i];
    H += f->ehg[i];
  }
  if (kinetic) *kinetic = K;
  if (internal) *internal = U;
  if (hourglass) *hourglass = H;
}

void dm_fin_bond_penalty(dm_fin *f) {
  /* bond penalty κ_i = c_s M_i V_i / tr A_i, M = ρ0 c0² + 4G/3 (reference P-wave modulus) */
  dm_model *m = f->m;
  const dm_state *st = m->s;
  const double cs = f->par.hourglass;
  m->opt.hourglass = cs;
  for (size_t i = 0; i < f->n; ++i) {
    const dm_fin_material *mt = &f->mat[f->imat[i]];
    const double rho0 = eos_rho0(mt->eos), c0 = eos_sound_speed(mt->eos, rho0, eos_e0(mt->eos));
    const double M = rho0 * c0 * c0 + (mt->yield != DM_YIELD_NONE ? 4.0 * mt->G / 3.0 : 0.0);
    double trA = 0;
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      double xi[3];
      dm_bond_vector(m, i, b, xi);
      trA += xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
    }
    m->kappa[i] = cs > 0 && trA > 0 ? cs * M * st->vol[i] / trA : 0.0;
  }
}

ms_status dm_fin_set_external(dm_fin *f, dm_fin_ext_fn fn, void *user) {
  f->ext = fn, f->ext_user = user;
  if (fn && !f->fext) f->fext = ms_calloc(3 * (f->n ? f->n : 1), sizeof(double));
  return forces(f, 0.0);
}

void dm_fin_destroy(dm_fin **fp) {
  if (!fp || !*fp) return;
  dm_fin *f = *fp;
  free(f->e), free(f->rho), free(f->p), free(f->q), free(f->J), free(f->eps_p), free(f->ehg);
  free(f->F), free(f->s), free(f->QP), free(f->sig), free(f->frc), free(f->vbar);
  dm_frac_free(f);
  free(f->fext);
  free(f);
  *fp = NULL;
}

ms_status dm_fin_create(const dm_fin_setup *setup, dm_fin **out) {
  *out = NULL;
  dm_model *m = setup->m;
  const dm_fin_material *mat = setup->mat;
  const uint8_t *imat = setup->imat;
  const dm_fin_params *par = &setup->par;
  dm_state *st = m->s;
  for (size_t i = 0; i < st->n; ++i)
    if (st->bc[i] == DM_MIRROR) return MS_ERR_INPUT;
  if (!(par->ell > 0) || !(par->courant > 0) || par->cq < 0 || par->cl < 0 || par->hourglass < 0)
    return MS_ERR_INPUT;
  for (size_t i = 0; i < st->n; ++i)
    if ((mat[imat[i]].yield >= DM_YIELD_STEINBERG_GUINAN && !mat[imat[i]].sg) ||
        (mat[imat[i]].frac.model != DM_FRACTURE_NONE && !(mat[imat[i]].frac.spall_strength > 0)))
      return MS_ERR_INPUT;
  dm_fin *f = ms_calloc(1, sizeof *f);
  size_t n = st->n, n1 = n ? n : 1;
  f->m = m, f->n = n, f->dim = st->dim, f->mat = mat, f->imat = imat, f->par = *par;
  f->e = ms_calloc(n1, sizeof(double)), f->rho = ms_calloc(n1, sizeof(double));
  f->p = ms_calloc(n1, sizeof(double)), f->q = ms_calloc(n1, sizeof(double));
  f->J = ms_calloc(n1, sizeof(double)), f->eps_p = ms_calloc(n1, sizeof(double));
  f->ehg = ms_calloc(n1, sizeof(double));
  f->F = ms_calloc(9 * n1, sizeof(double)), f->s = ms_calloc(9 * n1, sizeof(double));
  f->QP = ms_calloc(9 * n1, sizeof(double)), f->sig = ms_calloc(9 * n1, sizeof(double));
  f->frc = ms_calloc(3 * n1, sizeof(double)), f->vbar = ms_calloc(3 * n1, sizeof(double));
  dm_frac_alloc(f);
  dm_fin_bond_penalty(f);
  for (size_t i = 0; i < n; ++i) f->e[i] = eos_e0(mat[imat[i]].eos);
  const ms_status status = forces(f, 0.0);
  if (status != MS_OK) {
    dm_fin_destroy(&f);
    return status;
  }
  *out = f;
  return MS_OK;
}

/* ---- the piston problem ---- */

ms_status dm_piston_run(const dm_piston_spec *sp, const ms_ctx *ctx, dm_piston_result *res) {
  memset(res, 0, sizeof *res);
  const int dim = sp->dim;
  const long nx = sp->nx, ny = dim > 1 ? sp->ny : 1, nz = dim > 2 ? sp->nz : 1;
  const size_t n = (size_t)(nx * ny * nz);
  const double h = sp->h, rho0 = eos_rho0(sp->mat.eos), vol = pow(h, dim);
  dm_state s;
  dm_state_alloc(&s, n, dim);
  for (long iz = 0; iz < nz; ++iz)
    for (long iy = 0; iy < ny; ++iy)
      for (long ix = 0; ix < nx; ++ix) {
        size_t i = (size_t)((iz * ny + iy) * nx + ix);
        s.X[3 * i] = (ix + 0.5) * h;
        s.X[3 * i + 1] = dim > 1 ? (iy + 0.5) * h : 0.0;
        s.X[3 * i + 2] = dim > 2 ? (iz + 0.5) * h : 0.0;
        for (int a = 0; a < 3; ++a) s.w[3 * i + a] = s.u[3 * i + a] = 0.0;
        s.mass[i] = rho0 * vol, s.vol[i] = vol;
        s.K[i] = rho0 * pow(eos_c0(sp->mat.eos), 2), s.G[i] = sp->mat.G;
        s.bc[i] = ix < sp->npiston ? DM_PRESCRIBED : DM_FREE;
        if (ix < sp->npiston) s.u[3 * i] = sp->up;
      }
  dm_options opt = {.horizon = sp->horizon * h, .cond_max = 1e8, .hourglass = 0.0};
  if (dim > 1) opt.box[1] = ny * h;
  if (dim > 2) opt.box[2] = nz * h;
  dm_model *m = NULL;
  ms_status st = dm_model_create(&(dm_model_params){.state = &s, .opt = opt, .ctx = ctx}, &m);
  if (st != MS_OK) {
    dm_state_free(&s);
    return res->status = st;
  }
  uint8_t *imat = ms_calloc(n, 1);
  dm_fin *f = NULL;
  st = dm_fin_create(&(dm_fin_setup){.m = m, .mat = &sp->mat, .imat = imat, .par = sp->par}, &f);
  if (st != MS_OK) {
    free(imat), dm_model_destroy(&m), dm_state_free(&s);
    return res->status = st;
  }
  double K, U, H;
  dm_fin_energies(f, &K, &U, &H);
  const double E0 = K + U + H;
  const int ns = sp->nsamples > 1 ? sp->nsamples : 2;
  double *ts = ms_calloc((size_t)ns, sizeof(double)), *xs = ms_calloc((size_t)ns, sizeof(double));
  double *lay = ms_calloc((size_t)nx * 9, sizeof(double)); /* profile, then ε_p */
  int js = 0;
  double t = 0.0, dEmax = 0.0;
  while (t < sp->t_end && st == MS_OK) {
    if (t + f->dt_next > sp->t_end) f->dt_next = sp->t_end - t;
    t += f->dt_next;
    st = dm_fin_step(f);
    dm_fin_energies(f, &K, &U, &H);
    dEmax = fmax(dEmax, fabs(K + U + H - f->work - E0));
    const double tsj = 0.5 * sp->t_end * (1.0 + (double)(js + 1) / ns);
    if (st == MS_OK && js < ns && t >= tsj * (1 - 1e-12)) {
      /* front: the last layer (from the far end) whose mean u_x reaches up/2, interpolated */
      double prev = 0.0;
      xs[js] = NAN;
      for (long ix = nx - 1; ix >= 0; --ix) {
        double ux = 0;
        for (long j = 0; j < ny * nz; ++j) ux += s.u[3 * (size_t)(j * nx + ix)];
        ux /= (double)(ny * nz);
        if (ux >= 0.5 * sp->up) {
          const double fr = (ux - 0.5 * sp->up) / (ux - prev); /* 0 at this layer */
          xs[js] = (ix + 0.5 + fr) * h;
          break;
        }
        prev = ux;
      }
      ts[js++] = t;
    }
  }
  res->steps = f->step;
  if (st == MS_OK) {
    for (long ix = 0; ix < nx; ++ix) {
      double *r = &lay[8 * ix];
      for (long j = 0; j < ny * nz; ++j) {
        size_t i = (size_t)(j * nx + ix);
        r[0] += s.X[3 * i], r[1] += s.X[3 * i] + s.w[3 * i], r[2] += s.u[3 * i];
        r[3] += f->rho[i], r[4] += f->p[i], r[5] += f->q[i], r[6] += -f->sig[9 * i];
        r[7] += f->e[i];
        lay[8 * nx + ix] += f->eps_p[i];
      }
      for (int c = 0; c < 8; ++c) r[c] /= (double)(ny * nz);
      lay[8 * nx + ix] /= (double)(ny * nz);
    }
    /* D: least-squares slope of the front positions */
    double st_ = 0, sx = 0, stt = 0, stx = 0;
    for (int j = 0; j < js; ++j)
      st_ += ts[j], sx += xs[j], stt += ts[j] * ts[j], stx += ts[j] * xs[j];
    res->D = (js * stx - st_ * sx) / (js * stt - st_ * st_);
    const double Xp = sp->npiston * h, Xf = xs[js - 1];
    double a0 = Xp + 0.3 * (Xf - Xp), a1 = Xp + 0.8 * (Xf - Xp), cnt = 0;
    for (long ix = 0; ix < nx; ++ix) {
      const double *r = &lay[8 * ix];
      res->sxx_max = fmax(res->sxx_max, r[6]);
      if (r[0] < a0 || r[0] > a1) continue;
      res->P += r[6], res->rho += r[3], res->e += r[7], cnt += 1;
    }
    res->P /= cnt, res->rho /= cnt, res->e /= cnt;
    res->work = f->work;
    res->energy_err = dEmax / f->work;
    res->hg_ratio = H / f->work;
  } else {
    ms_log(ctx, MS_LOG_ERROR, "discrete model (finite): step %ld: particle %zu: %s = %g", f->step,
           f->bad, f->bad_what, f->bad_value);
  }
  res->profile = lay;
  res->eps_p = lay + 8 * nx;
  free(ts), free(xs), free(imat);
  dm_fin_destroy(&f);
  dm_model_destroy(&m);
  dm_state_free(&s);
  return res->status = st;
}
