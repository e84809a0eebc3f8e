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
#include "dm_vec.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

MS_KERNEL_INLINE static inline void inv3(const double *a, double det, double *r) {
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

/* The bond moments of particle i, each Σ_k Δa_ik ⊗ ξ_ik (row a, column b: Σ Δa_a ξ_b), so that
 * per-bond products with A⁻¹, P or C become one 3×3 product per particle afterwards (C =
 * (Σ Δw ⊗ ξ) A⁻¹, since g_ik = A⁻¹ξ_ik and A symmetric). Bw: of the displacement after a drift
 * by dt (w + dt u, formed here so the drift itself can follow the pass); Bu: of u. kick: Bv of
 * a half kick's mean velocity vb and sv = Σ_k Δv̄_ik·Δw_ik (w before the drift); close: the same,
 * Bc and sc, of vc. Column c of each moment is one 4-lane vector over the components of Δa
 * (lane 3 unused), updated per bond by ξ_c (broadcast) times Δa: three multiply-adds per moment,
 * no lane shuffles in the loop, independent accumulators. The flags are constants at each call
 * site, so each use compiles to its own loop; Bc and sc get the same bits in each. */
MS_KERNEL_INLINE static inline void
bond_moments(const dm_model *restrict m, size_t i, const double *restrict w,
             const double *restrict u, const double *restrict vb, const double *restrict vc,
             const uint8_t *restrict failed, double dt, bool stress, bool kick, bool close,
             moments *restrict M) {
  if (m->xref) { /* per-family references (dm_fin_local.c; refused with fracture) */
    dm_fin_local_moments(m, i, w, u, vb, vc, dt, stress, kick, close, M);
    return;
  }
  const double *restrict X = m->s->X;
  const v4d zero = {0}, xi0 = ld4(&X[3 * i]), wi = ld4(&w[3 * i]);
  const v4d ui = stress ? ld4(&u[3 * i]) : zero;
  const v4d vi = kick ? ld4(&vb[3 * i]) : zero, ci = close ? ld4(&vc[3 * i]) : zero;
  const v4d wn = wi + dt * ui;
  v4d aw0 = zero, aw1 = zero, aw2 = zero, au0 = zero, au1 = zero, au2 = zero;
  v4d av0 = zero, av1 = zero, av2 = zero, s4 = zero;
  v4d ac0 = zero, ac1 = zero, ac2 = zero, c4 = zero;
  const size_t e = m->start[i + 1];
  for (size_t b = m->start[i]; b < e; ++b) {
    const size_t k = m->nbr[b];
    if (failed && failed[k]) continue; /* a broken bond (dm_fracture.c) */
    const v4d xi = ld4(&X[3 * k]) + ld4(m->shift4[m->img[b]]) - xi0; /* (X_k + shift) − X_i */
    const v4d x = bc4(xi[0]), y = bc4(xi[1]), z = bc4(xi[2]);
    const v4d wk = ld4(&w[3 * k]);
    if (stress) {
      const v4d uk = ld4(&u[3 * k]), dw = wk + dt * uk - wn, du = uk - ui;
      aw0 += dw * x, aw1 += dw * y, aw2 += dw * z;
      au0 += du * x, au1 += du * y, au2 += du * z;
    }
    if (kick) {
      const v4d dv = ld4(&vb[3 * k]) - vi;
      av0 += dv * x, av1 += dv * y, av2 += dv * z;
      s4 += dv * (wk - wi);
    }
    if (close) {
      const v4d dc = ld4(&vc[3 * k]) - ci;
      ac0 += dc * x, ac1 += dc * y, ac2 += dc * z;
      c4 += dc * (wk - wi);
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (stress) {
      M->Bw[3 * a] = aw0[a], M->Bw[3 * a + 1] = aw1[a], M->Bw[3 * a + 2] = aw2[a];
      M->Bu[3 * a] = au0[a], M->Bu[3 * a + 1] = au1[a], M->Bu[3 * a + 2] = au2[a];
    }
    if (kick) M->Bv[3 * a] = av0[a], M->Bv[3 * a + 1] = av1[a], M->Bv[3 * a + 2] = av2[a];
    if (close) M->Bc[3 * a] = ac0[a], M->Bc[3 * a + 1] = ac1[a], M->Bc[3 * a + 2] = ac2[a];
  }
  if (kick) M->sv = s4[0] + s4[1] + s4[2];
  if (close) M->sc = c4[0] + c4[1] + c4[2];
}

/* r = B A (3×3, row-major) */
MS_KERNEL_INLINE static inline void mul33(const double *restrict B, const double *restrict A,
                                          double *restrict r) {
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      r[3 * a + c] = B[3 * a] * A[c] + B[3 * a + 1] * A[3 + c] + B[3 * a + 2] * A[6 + c];
}

MS_KERNEL_CLONES void dm_fin_displacement_gradient(const dm_model *m, const double *w,
                                                   const uint8_t *failed, size_t i, double C[9]) {
  moments M; /* u = w with dt = 0: Bw is Σ Δw ⊗ ξ exactly (Bu unused) */
  bond_moments(m, i, w, w, NULL, NULL, failed, 0.0, true, false, false, &M);
  mul33(M.Bw, &m->Ainv[9 * i], C);
}

/* The energy increments of a half kick of length h for particle i from its moments (Bv, sv)
 * and the Q_P and F of the last force evaluation: Σ_k Δv̄·(Q_P ξ) = Q_P : Bv and
 * Σ_k Δv̄·z = sv − (F − I) : Bv (z = Δw − (F − I) ξ). Returns false if e is not finite. */
MS_KERNEL_INLINE static inline bool kick_energy(dm_fin *f, size_t i, double h, const double *Bv,
                                                double sv) {
  const double *QP = &f->QP[9 * i], *F = &f->F[9 * i];
  double pw = 0.0, ph = sv + Bv[0] + Bv[4] + Bv[8];
  for (int a = 0; a < 9; ++a) pw += QP[a] * Bv[a], ph -= F[a] * Bv[a];
  f->e[i] += h * pw / f->m->s->mass[i];
  f->ehg[i] += h * f->m->kappa[i] * ph;
  return isfinite(f->e[i]);
}

/* Strain, stress and Q of particle i at w + dt u (the drift of this step, done after the pass),
 * with rates from u; advances the deviator by dt. With h > 0 first the energy increments of the
 * pending closing half kick of the last step (f->pending; then e and e_hg also into keep_e,
 * keep_ehg) and of the half kick just made (its v̄ in f->vbar); *bad_e set if e is not finite.
 * Returns the particle's stable time step, or −1 (bad state, recorded in *what). */
MS_KERNEL_CLONES static double stress_one(dm_fin *f, size_t i, double dt, double h, bool *bad_e,
                                          const char **what, double *val) {
  if (dm_frac_failed(f, i)) return dm_frac_failed_step(f, i); /* no F, no EOS (dm_fracture.c) */
  dm_model *m = f->m;
  const dm_state *st = m->s;
  const double *Ai = &m->Ainv[9 * i];
  double C[9], Fd[9];
  moments M;
  const uint8_t *fl = f->failed; /* its bonds to failed particles are broken (dm_fracture.c) */
  if (h > 0 && f->pending) {
    bond_moments(m, i, st->w, st->u, f->vbar, f->vclose, fl, dt, true, true, true, &M);
    if (!kick_energy(f, i, f->h_close, M.Bc, M.sc)) *bad_e = true;
    if (f->keep_e) f->keep_e[i] = f->e[i], f->keep_ehg[i] = f->ehg[i];
    if (!kick_energy(f, i, h, M.Bv, M.sv)) *bad_e = true;
  } else if (h > 0) {
    bond_moments(m, i, st->w, st->u, f->vbar, NULL, fl, dt, true, true, false, &M);
    if (!kick_energy(f, i, h, M.Bv, M.sv)) *bad_e = true;
  } else bond_moments(m, i, st->w, st->u, NULL, NULL, fl, dt, true, false, false, &M);
  mul33(M.Bw, Ai, C), mul33(M.Bu, Ai, Fd);
  double *F = &f->F[9 * i];
  for (int a = 0; a < 9; ++a) F[a] = C[a];
  F[0] += 1.0, F[4] += 1.0, F[8] += 1.0;
  const double J = dm_det3(F), J_prev = f->J[i];
  f->J[i] = J;
  const dm_fin_material *mt = &f->mat[f->imat[i]];
  const double rho0 = st->mass[i] / st->vol[i];
  /* a particle that has lost family members and whose F leaves the material's range fails
   * (dm_frac_degenerate); anywhere else the run stops */
  if ((!(J > 0) || !isfinite(J)) && dm_frac_degenerate(f, i, J_prev))
    return dm_frac_failed_step(f, i);
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
  const double p = eos_pressure(mt->eos, rho0 / J, f->e[i]);
  const double c = eos_sound_speed(mt->eos, rho0 / J, f->e[i]);
  if ((!isfinite(p) || !isfinite(c)) && dm_frac_degenerate(f, i, J_prev))
    return dm_frac_failed_step(f, i);
  if (!isfinite(p) || !isfinite(c)) {
    *what = "pressure p(rho, e)", *val = p;
    return -1.0;
  }
  const double rho = rho0 / J, ell = f->par.ell * pow(J, 1.0 / f->dim);
  const double q = trD < 0 ? rho * ell * (f->par.cq * ell * -trD + f->par.cl * c) * -trD : 0.0;
  double *s = &f->s[9 * i];
  const int strength = mt->yield != DM_YIELD_NONE;
  double G = mt->G, Y = mt->Y0; /* elastic_plastic: constants */
  /* steinberg_guinan G(p, T), Y(ε_p, p, T); johnson_cook Y(ε_p, ε̇, T) */
  if (mt->yield >= DM_YIELD_STEINBERG_GUINAN) {
    const double T = dm_sg_temperature(mt->sg, mt->eos, rho, f->e[i]);
    if (!isfinite(T) && mt->frac.model != DM_FRACTURE_NONE && rho < eos_rho0(mt->eos)) {
      Y = 0.0; /* stretched beyond the cold curve (below ~0.63 ρ0 for Al): far beyond the spall
                * strength, it fails in this pass (dm_frac_stress); no strength meanwhile */
    } else if (!isfinite(T) && dm_frac_degenerate(f, i, J_prev)) {
      return dm_frac_failed_step(f, i);
    } else if (!isfinite(T)) {
      *what = "temperature T (no cold curve at this density)", *val = rho;
      return -1.0;
    }
    if (!isfinite(T)) {
      /* Y = 0 above */
    } else if (mt->yield == DM_YIELD_JOHNSON_COOK) { /* rate: √(2/3 D′:D′) of this step's L */
      double dd = 0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) dd += 0.25 * pow(L[3 * a + b] + L[3 * b + a], 2);
      const double rate = sqrt(2.0 / 3.0 * fmax(dd - trD * trD / 3.0, 0.0));
      G = mt->sg->G0, Y = dm_jc_yield(mt->sg, f->eps_p[i], rate, T);
    } else dm_sg_moduli(mt->sg, rho / eos_rho0(mt->eos), p, T, f->eps_p[i], &G, &Y);
  }
  if (strength && dt > 0) {
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
      Q[3 * b + a] = QP[3 * a + b] - kap * C[3 * a + b]; /* transposed: gather_one */
    }
  f->rho[i] = rho, f->p[i] = p, f->q[i] = q;
  const double cL = sqrt(c * c + (strength ? 4.0 * G / (3.0 * rho) : 0.0));
  /* ν_q / ℓ; the quadratic term only where q acts (compression, not open): elsewhere it would
   * only shrink the step — without bound in a stretching jet tip or a broken particle, whose
   * |tr D| from a scattered family is large (docs/particles-dm.md "Time step") */
  const double nu_l = (q > 0 ? f->par.cq * ell * -trD : 0.0) + f->par.cl * c;
  return f->par.courant * ell / (cL + 2.0 * nu_l);
}

/* The force on particle i, F_i = Σ_k [(Q_i + Q_k) ξ_ik + (κ_i + κ_k) Δw_ik] (dm_model.c's
 * gather_force, the same sum) = Q_i Σ_k ξ_ik + Σ_k [Q_k ξ_ik + (κ_i + κ_k) Δw_ik]. m->Q holds
 * each Q transposed (stress_one), so Q_k ξ is Σ_c ξ_c (column c of Q_k): three broadcasts times
 * contiguous 4-lane loads (lane 3 unused), no lane shuffles in the loop. The sum runs over the
 * unbroken bonds (failed: NULL or both ends intact, dm_fracture.c), the same set from both ends,
 * so the pair terms stay equal and opposite; a failed particle gets no bond force. */
MS_KERNEL_CLONES static void gather_one(const dm_model *restrict m, const double *restrict w,
                                        const uint8_t *restrict failed, size_t i,
                                        double *restrict F) {
  if (m->xref) { /* per-family references (dm_fin_local.c; refused with fracture) */
    dm_fin_local_gather(m, w, i, F);
    return;
  }
  const double *restrict X = m->s->X, *restrict QT = m->Q, *restrict kap = m->kappa;
  const double ki = kap[i];
  if (failed && failed[i]) {
    F[3 * i] = F[3 * i + 1] = F[3 * i + 2] = 0.0;
    return;
  }
  const v4d zero = {0}, wi = ld4(&w[3 * i]), xi0 = ld4(&X[3 * i]);
  v4d r0 = zero, r1 = zero, r2 = zero, fw = zero;
  v4d sxi = zero; /* Σ_k ξ_ik */
  const size_t e = m->start[i + 1];
  for (size_t b = m->start[i]; b < e; ++b) {
    const size_t k = m->nbr[b];
    if (failed && failed[k]) continue;
    const v4d xi = ld4(&X[3 * k]) + ld4(m->shift4[m->img[b]]) - xi0; /* (X_k + shift) − X_i */
    const double x = xi[0], y = xi[1], z = xi[2];
    const double *q = &QT[9 * k];
    r0 += bc4(x) * ld4(q), r1 += bc4(y) * ld4(q + 3), r2 += bc4(z) * ld4(q + 6);
    fw += bc4(ki + kap[k]) * (ld4(&w[3 * k]) - wi);
    sxi += xi;
  }
  const double *qi = &QT[9 * i]; /* Q_i ξ-sum: row a of Q_i is qi[a], qi[3 + a], qi[6 + a] */
  for (int a = 0; a < 3; ++a)
    F[3 * i + a] =
        r0[a] + r1[a] + r2[a] + fw[a] + qi[a] * sxi[0] + qi[3 + a] * sxi[1] + qi[6 + a] * sxi[2];
}

/* w += dt u over n doubles: cloned like the stress pass, which forms the same w + dt u. */
MS_KERNEL_CLONES static void drift(double *restrict w, const double *restrict u, double dt,
                                   size_t n) {
  for (size_t j = 0; j < n; ++j) w[j] += dt * u[j];
}

/* The pending closing half kick's energies of particle i (dm_fin_flush); false if e is not
 * finite. */
MS_KERNEL_CLONES static bool flush_one(dm_fin *f, size_t i) {
  if (dm_frac_failed(f, i)) return true; /* no bond force: no work (as in the stress pass) */
  moments M;
  bond_moments(f->m, i, f->m->s->w, NULL, NULL, f->vclose, f->failed, 0.0, false, false, true, &M);
  return kick_energy(f, i, f->h_close, M.Bc, M.sc);
}

static ms_status bad_energy(dm_fin *f, long i) {
  f->bad = (size_t)i, f->bad_what = "specific internal energy e", f->bad_value = f->e[i];
  return MS_ERR_UNSTABLE;
}

/* All stresses and the forces; sets dt_next. With dt > 0 (a step): first the energy increments
 * of the half kick of length h just made, then the stress at w + dt u, then the drift
 * w += dt u itself (one pass over the bonds for both; stress_one). */
static ms_status forces(dm_fin *f, double dt, double h) {
  const long n = (long)f->n;
  if (f->sym.n) dm_sym_sync(f); /* the ghosts' w, u of a state set from outside */
  double dtmin = INFINITY;
  long bad = n, bad_e = n, imin = 0;
#pragma omp parallel if (n > 4096)
  { /* the smallest step and its particle (the smallest index of ties: thread-count independent) */
    double tdt = INFINITY;
    long tbad = n, tbad_e = n, ti = n;
#pragma omp for schedule(static) nowait
    for (long i = 0; i < n; ++i) {
      const char *what = NULL;
      double val = 0;
      bool be = false;
      double d = stress_one(f, (size_t)i, dt, h, &be, &what, &val);
      if (be && i < tbad_e) tbad_e = i;
      if (d < 0) {
        if (i < tbad) tbad = i;
      } else if (d < tdt) tdt = d, ti = i;
    }
#pragma omp critical(dm_fin_forces_min)
    {
      if (tbad < bad) bad = tbad;
      if (tbad_e < bad_e) bad_e = tbad_e;
      if (tdt < dtmin || (tdt == dtmin && ti < imin)) dtmin = tdt, imin = ti;
    }
  }
  if (h > 0) f->pending = false;              /* the stress pass added them */
  if (bad_e < n) return bad_energy(f, bad_e); /* the kick failed: no drift */
  dm_state *st = f->m->s;
  if (dt > 0) drift(st->w, st->u, dt, 3 * f->n);
  if (f->sym.n) dm_sym_sync(f); /* the ghosts' w, Q, κ, failed for the gather */
  /* this pass's failures break their bonds before the gather (the ghosts' w are current) */
  if (dm_frac_commit(f) && f->sym.n) dm_sym_sync(f);
  if (bad < n) { /* redo the first bad particle serially for the report (no deviator step) */
    const char *what = "state";
    double val = 0;
    bool be = false;
    stress_one(f, (size_t)bad, 0.0, 0.0, &be, &what, &val);
    f->bad = (size_t)bad, f->bad_what = what, f->bad_value = val;
    return MS_ERR_UNSTABLE;
  }
#pragma omp parallel for schedule(static) if (n > 4096)
  for (long i = 0; i < n; ++i) gather_one(f->m, st->w, f->failed, (size_t)i, f->frc);
  if (f->failed && dm_frac_contact(f, &dtmin, &imin) != MS_OK) return MS_ERR_UNSTABLE;
  if (f->sr && dm_contact_force(f, &dtmin, &imin) != MS_OK) return MS_ERR_UNSTABLE;
  if (f->ext) { /* an external force (the rigid wall of dm_impact.c) */
    const double dext = f->ext(f->ext_user, f, f->fext);
    for (size_t j = 0; j < 3 * f->n; ++j) f->frc[j] += f->fext[j];
    if (dext < dtmin) dtmin = dext;
  }
  for (size_t j = 0; j < f->nonplane; ++j) f->frc[f->onplane[j]] = 0.0; /* held on its plane */
  for (long i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      if (!isfinite(f->frc[3 * i + a])) {
        f->bad = (size_t)i, f->bad_what = "force", f->bad_value = f->frc[3 * i + a];
        return MS_ERR_UNSTABLE;
      }
  f->dt_next = dtmin, f->dt_particle = (size_t)imin;
  return MS_OK;
}

ms_status dm_fin_refresh(dm_fin *f) {
  const ms_status r = dm_fin_flush(f); /* at the QP and F it is about to replace */
  return r != MS_OK ? r : forces(f, 0.0, 0.0);
}

/* The velocity part of a half kick of length h = dt/2 with the current forces: u, its mean v̄
 * over the kick (into vbar [n][3]), and the work of the driven particles and of the external
 * force. */
static void kick_velocities(dm_fin *f, double h, double *vbar) {
  dm_state *st = f->m->s;
  const long n = (long)f->n;
  double dW = 0.0, dWe = 0.0;
  for (long i = 0; i < n; ++i) {
    double *u = &st->u[3 * i], *vb = &vbar[3 * i];
    const double hw = h * dm_fin_fold(f, (size_t)i); /* full-body sums (symmetry planes) */
    if (is_driven(st->bc[i])) {
      for (int a = 0; a < 3; ++a) vb[a] = u[a];
      dW -= hw * (f->frc[3 * i] * u[0] + f->frc[3 * i + 1] * u[1] + f->frc[3 * i + 2] * u[2]);
      continue;
    }
    const double im = h / st->mass[i];
    for (int a = 0; a < f->dim; ++a) {
      const double u1 = u[a] + im * f->frc[3 * i + a];
      vb[a] = 0.5 * (u[a] + u1);
      u[a] = u1;
      if (f->ext) dWe += hw * f->fext[3 * i + a] * vb[a]; /* its share of Σ m Δ|u|²/2 */
    }
  }
  f->work += dW, f->ext_work += dWe;
  if (f->sym.n) dm_sym_sync(f); /* the ghosts' u and v̄ */
}

ms_status dm_fin_flush(dm_fin *f) {
  if (!f->pending) return MS_OK;
  const long n = (long)f->n;
  long bad = n;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > 4096)
  for (long i = 0; i < n; ++i)
    if (!flush_one(f, (size_t)i) && i < bad) bad = i;
  f->pending = false;
  return bad < n ? bad_energy(f, bad) : MS_OK;
}

/* Kick (u; e in the stress pass, with the last step's pending closing kick) – drift (after the
 * stress pass) – forces – kick (u; e pending). */
ms_status dm_fin_advance(dm_fin *f) {
  const double dt = f->dt_next;
  if (f->failed && f->keep_e && f->pending) /* the stress pass skips failed particles: their e is */
    for (size_t i = 0; i < f->n; ++i)       /* complete now (their pending increments are 0) */
      if (f->failed[i]) f->keep_e[i] = f->e[i], f->keep_ehg[i] = f->ehg[i];
  kick_velocities(f, 0.5 * dt, f->vbar);
  dm_frac_contact_work(f, 0.5 * dt, f->vbar);
  dm_contact_work(f, 0.5 * dt, f->vbar);
  ms_status r = forces(f, dt, 0.5 * dt);
  if (r != MS_OK) return r;
  kick_velocities(f, 0.5 * dt, f->vclose);
  dm_frac_contact_work(f, 0.5 * dt, f->vclose);
  dm_contact_work(f, 0.5 * dt, f->vclose);
  f->h_close = 0.5 * dt, f->pending = true;
  ++f->step;
  return MS_OK;
}

ms_status dm_fin_step(dm_fin *f) {
  const ms_status r = dm_fin_advance(f);
  return r != MS_OK ? r : dm_fin_flush(f);
}

void dm_fs_history_init(dm_fs_history *h, size_t cap) {
  *h = (dm_fs_history){.rows = ms_calloc(2 * cap, sizeof(double)), .cap = cap, .stride = 1};
}

void dm_fs_history_record(dm_fs_history *h, long step, double t, const dm_state *s, long nx,
                          long nyz) {
  if (step % h->stride != 0) return;
  if (h->n == h->cap) {
    h->n = dm_rows_thin(h->rows, h->n, 2), h->stride *= 2;
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
    const double *u = &st->u[3 * i], wt = dm_fin_fold(f, i);
    if (!is_driven(st->bc[i]))
      K += wt * 0.5 * st->mass[i] * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    U += wt * st->mass[i] * f->e[i];
    H += wt * f->ehg[i];
  }
  if (kinetic) *kinetic = K;
  if (internal) *internal = U;
  if (hourglass) *hourglass = H;
}

double dm_fin_kappa(const dm_fin *f, size_t i, double trA) {
  /* bond penalty κ_i = c_s M_i V_i / tr A_i, M = ρ0 c0² + 4G/3 (reference P-wave modulus) */
  const dm_fin_material *mt = &f->mat[f->imat[i]];
  const double cs = f->par.hourglass;
  const double rho0 = eos_rho0(mt->eos), c0 = eos_sound_speed(mt->eos, rho0, eos_e0(mt->eos));
  const double M = rho0 * c0 * c0 + (mt->yield != DM_YIELD_NONE ? 4.0 * mt->G / 3.0 : 0.0);
  return cs > 0 && trA > 0 ? cs * M * f->m->s->vol[i] / trA : 0.0;
}

void dm_fin_bond_penalty(dm_fin *f) {
  dm_model *m = f->m;
  m->opt.hourglass = f->par.hourglass;
  for (size_t i = 0; i < f->n; ++i) {
    double trA = 0;
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      double xi[3], dw[3];
      if (m->xref) dm_fin_local_bond(m, m->s->w, i, b, xi, dw);
      else dm_bond_vector(m, i, b, xi);
      trA += xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
    }
    m->kappa[i] = dm_fin_kappa(f, i, trA);
  }
}

ms_status dm_fin_set_external(dm_fin *f, dm_fin_ext_fn fn, void *user) {
  const ms_status r = dm_fin_flush(f); /* at the QP and F it is about to replace */
  if (r != MS_OK) return r;
  f->ext = fn, f->ext_user = user;
  if (fn && !f->fext) f->fext = ms_calloc(3 * (f->n ? f->n : 1), sizeof(double));
  return forces(f, 0.0, 0.0);
}

void dm_fin_destroy(dm_fin **fp) {
  if (!fp || !*fp) return;
  dm_fin *f = *fp;
  free(f->e), free(f->rho), free(f->p), free(f->q), free(f->J), free(f->eps_p), free(f->ehg);
  free(f->F), free(f->s), free(f->QP), free(f->sig), free(f->frc), free(f->vbar), free(f->vclose);
  dm_frac_free(f);
  dm_contact_free(f);
  dm_sym_free(f);
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
  size_t nreal = 0; /* the real particles, then only mirror ghosts (with symmetry planes) */
  while (nreal < st->n && st->bc[nreal] != DM_MIRROR) ++nreal;
  for (size_t i = nreal; i < st->n; ++i)
    if (st->bc[i] != DM_MIRROR || setup->sym.n == 0 || !m->opt.ghost_rows) return MS_ERR_INPUT;
  /* the short-range contact sees only the real particles' cell list: with symmetry planes it
   * would miss the pairs across a plane (the impact deck refuses the two together, dm_impact_sym.c) */
  if (!(par->ell > 0) || !(par->courant > 0) || par->cq < 0 || par->cl < 0 || par->hourglass < 0 ||
      !(par->contact >= 0 && par->contact < 1) || (setup->sym.n && par->contact > 0))
    return MS_ERR_INPUT;
  for (size_t i = 0; i < nreal; ++i)
    if ((mat[imat[i]].yield >= DM_YIELD_STEINBERG_GUINAN && !mat[imat[i]].sg) ||
        (mat[imat[i]].frac.model != DM_FRACTURE_NONE && !(mat[imat[i]].frac.spall_strength > 0)))
      return MS_ERR_INPUT;
  dm_fin *f = ms_calloc(1, sizeof *f);
  size_t n = nreal, n1 = n ? n : 1;
  f->m = m, f->n = n, f->nall = st->n, f->dim = st->dim, f->mat = mat, f->imat = imat;
  f->par = *par;
  f->e = ms_calloc(n1, sizeof(double)), f->rho = ms_calloc(n1, sizeof(double));
  f->p = ms_calloc(n1, sizeof(double)), f->q = ms_calloc(n1, sizeof(double));
  f->J = ms_calloc(n1, sizeof(double)), f->eps_p = ms_calloc(n1, sizeof(double));
  f->ehg = ms_calloc(n1, sizeof(double));
  f->F = ms_calloc(9 * n1, sizeof(double)), f->s = ms_calloc(9 * n1, sizeof(double));
  f->QP = ms_calloc(9 * n1, sizeof(double)), f->sig = ms_calloc(9 * n1, sizeof(double));
  f->frc = ms_calloc(3 * n1, sizeof(double)),
  f->vbar = ms_calloc(3 * n1 + 1, sizeof(double)); /* +1: ld4 */
  f->vclose = ms_calloc(3 * n1 + 1, sizeof(double));
  if (setup->sym.n && dm_sym_init(f, &setup->sym, imat) != MS_OK) {
    dm_fin_destroy(&f);
    return MS_ERR_INPUT;
  }
  dm_frac_alloc(f);
  if (dm_contact_alloc(f) != MS_OK) {
    dm_fin_destroy(&f);
    return MS_ERR_INPUT;
  }
  dm_fin_bond_penalty(f);
  for (size_t i = 0; i < n; ++i) f->e[i] = eos_e0(mat[imat[i]].eos);
  const ms_status status = forces(f, 0.0, 0.0);
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
  const double h = sp->h;
  dm_state s;
  dm_state_alloc(&s, n, dim);
  uint8_t *imat = ms_calloc(n, 1);
  dm_slab_place(&s, dim, nx, ny, nz, h, &sp->mat, imat);
  for (size_t i = 0; i < n; ++i)
    if ((long)(i % (size_t)nx) < sp->npiston) s.bc[i] = DM_PRESCRIBED, s.u[3 * i] = sp->up;
  dm_model *m;
  dm_fin *f;
  ms_status st = dm_slab_create(&s, ny, nz, h, sp->horizon, &sp->mat, imat, &sp->par, ctx, &m, &f);
  if (st != MS_OK) return res->status = st;
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
    dm_slab_layers(f, &s, nx, ny * nz, lay);
    for (long ix = 0; ix < nx; ++ix) { /* then the mean ε_p */
      for (long j = 0; j < ny * nz; ++j) lay[8 * nx + ix] += f->eps_p[(size_t)(j * nx + ix)];
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
