/* SPDX-License-Identifier: MIT */
/* dm_fracture.c — fracture of the finite-deformation discrete model (docs/particles-dm.md,
 * "Fracture"): an instantaneous tensile cut-off at the spall strength σ_s (the pmin / "spall"
 * model of hydrocodes: a cell whose tension reaches the threshold loses its strength
 * [Kanel2010], [Grady1988]), per particle, for good.
 *
 * A failed particle keeps its mass, momentum, family and internal energy, but no longer has a
 * stress of its own: no F over its family (whose members may have scattered), no EOS, no
 * deviator, no bond penalty (Q_i = 0, κ_i = 0; the penalty energy it held is booked as broken).
 * A bond is broken when either of its particles has failed: it leaves the intact one's F,
 * stress and force (dm_frac_commit rebuilds its shape matrix over its intact members, as LAMMPS
 * smd/tlsph leaves failed particles out of K and F [Ganzenmuller2015]); an intact particle left
 * with too few members, or whose F leaves its material's range, fails too (dm_frac_commit,
 * dm_frac_degenerate). Across a broken bond acts only a
 * compression-only central pair force, after the short-range contact forces of bond-based
 * peridynamics ([SillingAskari2005]; LAMMPS PERI, [Parks2008]), here across the broken bonds of
 * the families only (they act between any two nodes closer than a contact distance there):
 *   f_i = −κ_ik L_ik g(λ) y_ik/|y_ik|  while λ = |y_ik|/L_ik < 1, else 0,
 * y_ik = x_k − x_i, L_ik = min(|ξ_ik|, |y_ik| when the bond broke) (so the spring holds no
 * energy at the break: the elastic energy there is the particles' heat already),
 * κ_ik = κc_i + κc_k, κc_i = K d² V_i / Σ_k |ξ_ik|² (K = ρ0 c0² of the particle's material, d the
 * dimension): the lattice form of the bond-based micromodulus c = 18K/(π δ⁴) of
 * [SillingAskari2005], calibrated on the particle's own family so that a uniform compression of
 * a failed lattice stores K (tr ε)²/2 per volume at small strain; g(λ) (pair_law) follows the
 * material's EOS along e = e0, g = [p(ρ0 λ^−d) − p(ρ0)] λ^(d−1)/(K d) → 1 − λ, so that a
 * uniformly compressed failed lattice carries its EOS pressure (the linear spring alone lets a
 * failed region near a drive be crushed to half its spacing at 15–20 GPa). A dashpot η_ik ṙ
 * along the pair while it approaches in contact (η_ik = C_l √(κ_ik s √(m_i m_k)), s the spring's
 * current stiffness over κ, C_l the linear viscosity's coefficient: in a 1D chain at rest
 * η = C_l ρ0 c0 A, the q = C_l ρ c ℓ|tr D| of a
 * particle) damps the collisions; its work is the particles' heat. (Before issue 25's
 * follow-up a failed–intact bond was not broken: a failed neighbour drifting off dilated the
 * intact particle it hung on.) Fragments (dm_region.c) are the components of the unbroken bonds.
 *
 * Energy: pair forces are central and antisymmetric (momentum and angular momentum kept); the
 * springs derive from the potential Σ_pairs κ L² ∫_λ^1 g. The contact energy econ is booked as
 * the springs' work with each half kick's time-centred velocity, −h Σ_i fcon_i·ū_i, the dashpot's
 * as heat in e (half of each pair's to each particle), so K + U + E_hg + broken + contact − W =
 * const to round-off (the potential equals the booked energy up to velocity Verlet's O(dt²)).
 * The internal energy of a failed particle (its share of the elastic energy at the break
 * included) stays in U as heat; only the dashpot adds to it. */
#include "dm_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* κc_i = K d² V_i / Σ_k |ξ_ik|² (see the head) and the contact's stable step
 * dtcon_i = courant · 2/ω_i, ω_i² = 2 Σ_k (κc_i + κc_k)/m_i: Gershgorin's bound on the largest
 * eigenvalue of M⁻¹K of the contact springs (all bonds of the family counted, so the bound holds
 * whichever of them are broken and compressed); velocity Verlet is stable for ω dt < 2 (courant
 * 1 is the 1D chain's exact limit). */
static void contact_stiffness(dm_fin *f) {
  const dm_model *m = f->m;
  const dm_state *st = m->s;
  dm_pair_stiffness(f, f->kcon, 0.0);                                           /* dm_contact.c */
  for (size_t g = f->n; g < f->nall; ++g) f->kcon[g] = f->kcon[st->partner[g]]; /* ghosts */
  /* the dashpot (η = C_l √(κ √(m_i m_k)), damping ratio ζ = C_l/√2 for equal masses) lowers
   * the explicit limit to (2/ω)(√(1 + ζ²) − ζ) */
  const double zeta = f->par.cl / sqrt(2.0), damped = sqrt(1.0 + zeta * zeta) - zeta;
  for (size_t i = 0; i < f->n; ++i) {
    double sk = 0.0;
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) sk += f->kcon[i] + f->kcon[m->nbr[b]];
    f->dtcon[i] = sk > 0 ? f->par.courant * 2.0 * damped / sqrt(2.0 * sk / st->mass[i]) : INFINITY;
  }
}

void dm_frac_alloc(dm_fin *f) {
  bool any = false;
  for (size_t i = 0; i < f->n && !any; ++i) any = f->mat[f->imat[i]].frac.model != DM_FRACTURE_NONE;
  if (!any) return;
  const size_t n1 = f->n ? f->n : 1, na = f->nall > n1 ? f->nall : n1; /* na: with ghosts */
  f->failed = ms_calloc(na, 1);
  f->fresh = ms_calloc(n1, 1), f->cut = ms_calloc(n1, 1), f->fmark = ms_calloc(n1, 1);
  f->nintact = ms_calloc(n1, sizeof(uint32_t));
  f->fq = ms_calloc(2 * n1, sizeof(size_t)); /* the work list, then the round's marked list */
  for (size_t i = 0; i < f->n; ++i) f->nintact[i] = (uint32_t)(f->m->start[i + 1] - f->m->start[i]);
  f->broken = ms_calloc(n1, sizeof(double));
  f->kcon = ms_calloc(na, sizeof(double)), f->dtcon = ms_calloc(n1, sizeof(double));
  f->fcon = ms_calloc(3 * n1, sizeof(double)), f->econ = ms_calloc(n1, sizeof(double));
  f->nlcon = f->m->nbonds;
  f->lcon = ms_calloc(f->nlcon ? f->nlcon : 1, sizeof(double));
  f->gcon = ms_calloc(f->nlcon ? f->nlcon : 1, sizeof(double));
  f->dtclose = ms_calloc(n1, sizeof(double));
  for (size_t b = 0; b < f->nlcon; ++b) f->lcon[b] = -1.0; /* not broken yet */
  f->lam_end = ms_calloc(256, sizeof(double));
  contact_stiffness(f);
  dm_pair_ends(f, f->lam_end);
}

void dm_frac_free(dm_fin *f) {
  free(f->failed), free(f->broken), free(f->kcon), free(f->dtcon), free(f->fcon), free(f->econ);
  free(f->fresh), free(f->cut), free(f->fmark), free(f->nintact), free(f->fq);
  f->fresh = f->cut = f->fmark = NULL, f->nintact = NULL, f->fq = NULL;
  free(f->lcon), free(f->gcon), free(f->dtclose), free(f->lam_end);
  f->failed = NULL, f->broken = NULL;
  f->kcon = f->dtcon = f->fcon = f->econ = f->lcon = f->gcon = f->dtclose = NULL;
}

/* Largest eigenvalue of the symmetric a: the trigonometric form of the cubic's roots
 * ([Smith1961]): λ = q + 2p cos(φ), q = tr a/3, p² = tr((a − qI)²)/6,
 * cos 3φ = det((a − qI)/p)/2. */
double dm_frac_max_principal(const double *a) {
  const double p1 = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
  const double q = (a[0] + a[4] + a[8]) / 3.0;
  if (p1 <= 1e-30 * (a[0] * a[0] + a[4] * a[4] + a[8] * a[8])) /* diagonal */
    return fmax(a[0], fmax(a[4], a[8]));
  const double d0 = a[0] - q, d1 = a[4] - q, d2 = a[8] - q;
  const double p = sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1) / 6.0);
  const double b0 = d0 / p, b1 = a[1] / p, b2 = a[2] / p, b4 = d1 / p, b5 = a[5] / p, b8 = d2 / p;
  const double det = b0 * (b4 * b8 - b5 * b5) - b1 * (b1 * b8 - b5 * b2) + b2 * (b1 * b5 - b4 * b2);
  const double r = fmax(-1.0, fmin(1.0, 0.5 * det));
  return q + 2.0 * p * cos(acos(r) / 3.0);
}

void dm_frac_stress(dm_fin *f, size_t i, const dm_fin_material *mt, double J, double *sig,
                    double *s) {
  if (!f->failed) return;
  if (!f->failed[i]) {
    const dm_fracture *fr = &mt->frac;
    if (fr->model == DM_FRACTURE_NONE) return;
    /* a driven particle (a piston's prescribed or a fixed layer) never fails: its motion is
     * given, and in the coupled region it stands for the grid, which has no spall model — the
     * material fails above it, not in it (docs/particles-dm.md "Fracture") */
    const uint8_t bc = f->m->s->bc[i];
    if (bc == DM_PRESCRIBED || bc == DM_FIXED) return;
    const double tension = fr->model == DM_FRACTURE_PRINCIPAL_STRESS
                               ? dm_frac_max_principal(sig)
                               : (sig[0] + sig[4] + sig[8]) / 3.0;
    const bool strained = fr->failure_strain > 0 && J - 1.0 >= fr->failure_strain;
    if (!(tension >= fr->spall_strength) && !strained) return;
    f->fresh[i] = 1; /* failed from dm_frac_commit on, after this pass (no race on failed[]) */
    f->broken[i] += f->ehg[i]; /* the penalty's stored energy leaves E_hg: it is released */
    f->ehg[i] = 0.0;
    f->m->kappa[i] = 0.0;
  }
  /* failed: no stress of its own (from the next evaluation on dm_frac_failed_step); this
   * evaluation's gather already has its bonds broken */
  for (int a = 0; a < 9; ++a) s[a] = 0.0, sig[a] = 0.0;
}

double dm_frac_failed_step(dm_fin *f, size_t i) {
  double *Q = &f->m->Q[9 * i], *QP = &f->QP[9 * i], *sg = &f->sig[9 * i], *s = &f->s[9 * i];
  for (int a = 0; a < 9; ++a) Q[a] = QP[a] = sg[a] = s[a] = 0.0;
  f->q[i] = 0.0;
  /* all its bonds are broken: only the contact acts on it (dtcon, dtclose, the contact pass);
   * the material's speed of sound at rest (as c_L of the stress pass, without compression)
   * still bounds its step, as before the bonds broke */
  const dm_fin_material *mt = &f->mat[f->imat[i]];
  const double rho0 = eos_rho0(mt->eos), c0 = eos_c0(mt->eos);
  const double cL = sqrt(c0 * c0 + (mt->yield != DM_YIELD_NONE ? 4.0 * mt->G / (3.0 * rho0) : 0));
  return fmin(f->par.courant * f->par.ell / cL, f->dtcon[i]);
}

/* ---- broken bonds and the shape matrix (dm_frac_commit) ----
 * The state of family member k during dm_frac_commit (a mirror ghost: its partner's): 0 intact,
 * 1 failed before this commit, 2 failed with its bonds breaking in the current round, 4 failed
 * in the current round's reshapes (its bonds break in the next round). */
static uint8_t member_state(const dm_fin *f, size_t k) {
  return f->failed[k < f->n ? k : f->m->s->partner[k]];
}

/* Particle i's shape matrix over the members it still holds (states 0, 4): A⁻¹ into m->Ainv
 * (dm_sym_inverse, as dm_build_shape over the whole family: the same bits while none failed),
 * nintact[i]; returns cond A (∞: singular, A⁻¹ = 0). With book, the bond-penalty energy of the
 * bonds it loses in this round (members in state 2) moves from E_hg to broken, in proportion
 * to their share of Σ|z|² over the bonds it held, z = Δw − (F − I)ξ the penalty's measure
 * (dm_finite.c; F of this evaluation): a lost bond's penalty energy is released, as a failed
 * particle's whole E_hg is. */
static double reshape(dm_fin *f, size_t i, bool book) {
  dm_model *m = f->m;
  const double *w = m->s->w, *F = &f->F[9 * i];
  double A[9] = {0}, zlost = 0.0, zheld = 0.0;
  uint32_t cnt = 0;
  for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
    const size_t k = m->nbr[b];
    const uint8_t sk = member_state(f, k);
    if (sk == 1) continue;
    double xi[3];
    dm_bond_vector(m, i, b, xi);
    if (sk != 2) {
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) A[3 * a + c] += xi[a] * xi[c];
      ++cnt;
    }
    if (!book) continue;
    double zz = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double z = (w[3 * k + a] - w[3 * i + a]) + xi[a] -
                       (F[3 * a] * xi[0] + F[3 * a + 1] * xi[1] + F[3 * a + 2] * xi[2]);
      zz += z * z;
    }
    zheld += zz, zlost += sk == 2 ? zz : 0.0;
  }
  if (book && zlost > 0 && zheld > 0) {
    const double moved = f->ehg[i] * (zlost / zheld);
    f->ehg[i] -= moved, f->broken[i] += moved;
  }
  f->nintact[i] = cnt;
  return dm_sym_inverse(f->dim, A, &m->Ainv[9 * i]);
}

/* An intact particle left with too few members fails (state 4): as at a failure in the stress
 * pass, its penalty energy is booked as broken and it has no stress from now on. */
static void fail_isolated(dm_fin *f, size_t i) {
  dm_model *m = f->m;
  f->failed[i] = 4;
  f->broken[i] += f->ehg[i];
  f->ehg[i] = 0.0, m->kappa[i] = 0.0, f->nintact[i] = 0;
  for (int a = 0; a < 9; ++a)
    m->Q[9 * i + a] = f->QP[9 * i + a] = f->sig[9 * i + a] = f->s[9 * i + a] = 0.0;
}

bool dm_frac_commit(dm_fin *f) {
  if (!f->failed) return false;
  const dm_model *m = f->m;
  const size_t n = f->n, n1 = n ? n : 1;
  size_t nq = 0, head = 0, *marked = f->fq + n1;
  for (size_t i = 0; i < n; ++i)
    if (f->fresh[i]) {
      ++*(f->fresh[i] == 2 ? &f->nfail_degenerate : &f->nfail_stress);
      f->fresh[i] = 0, f->failed[i] = 2, f->fq[nq++] = i;
    }
  if (!nq) return false;
  while (head < nq) { /* a round: the failures so far break their bonds */
    const size_t end = nq;
    size_t nm = 0;
    for (size_t h = head; h < end; ++h) { /* their intact members, each once, in order */
      const size_t k = f->fq[h];
      f->cut[k] = 1, f->nintact[k] = 0;
      for (size_t b = m->start[k]; b < m->start[k + 1]; ++b) {
        const size_t j = m->nbr[b] < n ? m->nbr[b] : m->s->partner[m->nbr[b]];
        if (f->failed[j] || f->fmark[j]) continue; /* (a ghost's partner holds the mirror bond) */
        f->fmark[j] = 1, marked[nm++] = j;
      }
    }
    for (size_t q = 0; q < nm; ++q) {
      const size_t i = marked[q];
      f->fmark[i] = 0, f->cut[i] = 1;
      const double cond = reshape(f, i, true);
      const uint8_t bc = m->s->bc[i]; /* driven particles never fail (dm_frac_stress) */
      if (bc == DM_PRESCRIBED || bc == DM_FIXED) continue;
      const double n0 = (double)(m->start[i + 1] - m->start[i]);
      if ((double)f->nintact[i] < DM_FRAC_MIN_INTACT * n0 || !(cond <= DM_FRAC_COND_MAX))
        fail_isolated(f, i), f->fq[nq++] = i, ++f->nfail_isolated;
    }
    for (size_t h = head; h < end; ++h) f->failed[f->fq[h]] = 1;
    for (size_t h = end; h < nq; ++h) f->failed[f->fq[h]] = 2;
    head = end;
  }
  return true;
}

void dm_frac_restore(dm_fin *f) {
  if (!f->failed) return;
  const dm_model *m = f->m;
  for (size_t i = 0; i < f->n; ++i) {
    f->cut[i] = f->failed[i] != 0, f->fresh[i] = f->fmark[i] = 0;
    if (f->failed[i]) {
      f->nintact[i] = 0;
      continue;
    }
    bool lost = false;
    for (size_t b = m->start[i]; b < m->start[i + 1] && !lost; ++b)
      lost = member_state(f, m->nbr[b]) != 0;
    if (lost) f->cut[i] = 1, reshape(f, i, false);
  }
}

bool dm_frac_degenerate(dm_fin *f, size_t i, double J_prev) {
  if (!f->failed || !f->cut[i] || f->mat[f->imat[i]].frac.model == DM_FRACTURE_NONE) return false;
  const uint8_t bc = f->m->s->bc[i];
  if (bc == DM_PRESCRIBED || bc == DM_FIXED) return false;
  f->fresh[i] = 2; /* as a failure in dm_frac_stress: committed after the pass */
  f->broken[i] += f->ehg[i];
  f->ehg[i] = 0.0, f->m->kappa[i] = 0.0;
  f->J[i] = J_prev; /* held from the last valid state, as a failed particle's */
  return true;
}

/* The pair vectors of bond b of particle i (to k): ξ = (X_k − X_i) + shift and y = ξ + w_k − w_i
 * (the pair's negation is exact: both ends see the same |y|, the same bits). */
static void pair_vectors(const dm_model *m, const double *w, size_t i, size_t b, double xi[3],
                         double y[3]) {
  const double *X = m->s->X, *sh = m->shift[m->img[b]];
  const size_t k = m->nbr[b];
  for (int a = 0; a < 3; ++a) {
    xi[a] = (X[3 * k + a] - X[3 * i + a]) + sh[a];
    y[a] = xi[a] + (w[3 * k + a] - w[3 * i + a]);
  }
}

/* The contact force on particle i (failed, or intact with a failed family member) from its
 * broken, compressed bonds (to a failed member, or all of a failed particle's): the spring into
 * fcon_i, the dashpot's g = η ṙ (≤ 0, along y/|y|) into gcon[b]; their sum is returned in ft.
 * Its virial pressure p_i = Σ_k |f_ik| |y| / (2 d V_i λ̄^d) (each pair's virial shared by its two
 * particles, over the current volume, λ̄ the mean |y|/L of its bonds in contact: K tr ε/(1 +
 * tr ε) under a uniform compression). Its closing-speed step dtclose_i = courant · min L/(−ṙ)
 * over its approaching broken bonds (no pair closes by more than courant · L in a step, so none
 * jumps past the spring). Returns the smallest |y|/L (1 if none). Writes particle i's entries
 * and its bonds' only. */
static double contact_one(dm_fin *f, size_t i, double ft[3]) {
  const dm_model *m = f->m;
  const double *w = m->s->w, *u = m->s->u, *mass = m->s->mass;
  double fc[3] = {0, 0, 0}, vir = 0.0, lmin = 1.0, lsum = 0.0, nc = 0.0, closing = 0.0, smax = 1;
  for (int a = 0; a < 3; ++a) ft[a] = 0.0;
  for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
    const size_t k = m->nbr[b];
    f->gcon[b] = 0.0;
    if (!f->failed[i] && !f->failed[k]) continue; /* unbroken */
    double xi[3], y[3];
    pair_vectors(m, w, i, b, xi, y);
    const double r = sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
    if (f->lcon[b] < 0) /* the bond has just broken: its rest length (both sides, same bits) */
      f->lcon[b] = fmin(sqrt(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]), r);
    const double L = f->lcon[b];
    if (!(r > 0)) {
      lmin = 0.0;
      continue;
    }
    /* ṙ = (u_k − u_i)·y/r; the dashpot only while approaching, so the pair force stays
     * compressive (as q acts only in compression) */
    const double rdot = ((u[3 * k] - u[3 * i]) * y[0] + (u[3 * k + 1] - u[3 * i + 1]) * y[1] +
                         (u[3 * k + 2] - u[3 * i + 2]) * y[2]) /
                        r;
    /* no pair closes in one step by more than courant · L, nor by more than courant times its
     * gap to the end of the EOS's range (r − λ_end L; λ_end = 0: no end), where the springs
     * stiffen without bound: a pair at 6.7 km/s crossed from λ ≈ 0.9 past mg_linear's 0.63 in
     * one step of the first rule alone (the Piekutowski perforation, docs/validation.md) */
    const double lend = fmax(f->lam_end[f->imat[i]], f->lam_end[f->imat[k]]);
    if (rdot < 0) closing = fmax(closing, -rdot / fmin(L, fmax(r - lend * L, 1e-300)));
    if (!(r < L)) continue;
    double gi, si, gk, sk;
    dm_pair_law(f, i, r / L, &gi, &si);
    dm_pair_law(f, k, r / L, &gk, &sk);
    const double kap = f->kcon[i] + f->kcon[k], gl = 0.5 * (gi + gk), sl = 0.5 * (si + sk);
    if (!isfinite(gl) || !isfinite(sl)) {
      lmin = 0.0;
      continue;
    }
    smax = fmax(smax, sl);
    const double eta = f->par.cl * sqrt(kap * sl * sqrt(mass[i] * mass[k]));
    const double g = rdot < 0 ? eta * rdot : 0.0, spring = kap * L * gl;
    f->gcon[b] = g;
    lmin = fmin(lmin, r / L), lsum += r / L, nc += 1.0;
    for (int a = 0; a < 3; ++a) fc[a] -= spring * y[a] / r, ft[a] += (g - spring) * y[a] / r;
    vir += (spring - g) * r;
  }
  for (int a = 0; a < 3; ++a) f->fcon[3 * i + a] = fc[a];
  f->dtclose[i] = fmin(closing > 0 ? f->par.courant / closing : INFINITY,
                       f->dtcon[i] / sqrt(smax)); /* the springs stiffen with the EOS */
  if (f->failed[i])                               /* an intact particle's p is its EOS pressure */
    f->p[i] = nc > 0 ? vir / (2.0 * f->dim * m->s->vol[i] * pow(lsum / nc, f->dim)) : 0.0;
  return lmin;
}

ms_status dm_frac_contact(dm_fin *f, double *dtmin, long *imin) {
  const long n = (long)f->n;
  long bad = n;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > 4096)
  for (long i = 0; i < n; ++i)
    if (f->cut[i]) {
      double ft[3];
      const double lmin = contact_one(f, (size_t)i, ft);
      for (int a = 0; a < 3; ++a) f->frc[3 * i + a] += ft[a];
      if (!(lmin >= DM_CONTACT_MIN_RATIO) && i < bad) bad = i;
    }
  if (bad < n) {
    /* the limit of the linear spring: compressed this far, the pair is about to pass through */
    double ft[3];
    f->bad = (size_t)bad, f->bad_value = contact_one(f, (size_t)bad, ft);
    f->bad_what = "contact: a broken bond's length over its rest length (< 0.5)";
    return MS_ERR_UNSTABLE;
  }
  for (long i = 0; i < n; ++i) /* the smallest index of ties, as the stress pass */
    if (f->cut[i] && (f->dtclose[i] < *dtmin || (f->dtclose[i] == *dtmin && i < *imin)))
      *dtmin = f->dtclose[i], *imin = i;
  return MS_OK;
}

/* The spring's work into econ, the dashpot's into heat over the half kick of mean velocity vb
 * (f->vbar, or f->vclose for the closing one): a pair's dissipation h g (ū_k − ū_i)·y/r, half
 * to each particle (each end sees the same g, y and Δū negated). */
void dm_frac_contact_work(dm_fin *f, double h, const double *vb) {
  if (!f->failed) return;
  const dm_model *m = f->m;
  const double *w = m->s->w;
  const long n = (long)f->n;
#pragma omp parallel for schedule(static) if (n > 4096)
  for (long i = 0; i < n; ++i)
    if (f->cut[i]) {
      const double *fc = &f->fcon[3 * i];
      f->econ[i] -= h * (fc[0] * vb[3 * i] + fc[1] * vb[3 * i + 1] + fc[2] * vb[3 * i + 2]);
      double heat = 0.0;
      for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
        if (f->gcon[b] == 0.0) continue;
        const size_t k = m->nbr[b];
        double xi[3], y[3];
        pair_vectors(m, w, (size_t)i, b, xi, y);
        const double r = sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
        double dv = 0.0;
        for (int a = 0; a < 3; ++a) dv += (vb[3 * k + a] - vb[3 * i + a]) * y[a];
        heat += 0.5 * h * f->gcon[b] * dv / r;
      }
      f->e[i] += heat / m->s->mass[i];
    }
}

double dm_fin_broken_energy(const dm_fin *f) {
  double b = 0.0;
  if (f->broken)
    for (size_t i = 0; i < f->n; ++i) b += dm_fin_fold(f, i) * f->broken[i];
  return b;
}

double dm_fin_contact_energy(const dm_fin *f) {
  double c = 0.0;
  if (f->econ)
    for (size_t i = 0; i < f->n; ++i) c += dm_fin_fold(f, i) * f->econ[i];
  return c + dm_contact_energy(f); /* and the short-range contact's (dm_contact.c) */
}

double dm_fin_contact_potential(const dm_fin *f) {
  if (!f->failed) return 0.0;
  const dm_model *m = f->m;
  const double *X = m->s->X, *w = m->s->w;
  double U = 0.0;
  for (size_t i = 0; i < f->n; ++i)
    if (f->cut[i])
      for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
        const size_t k = m->nbr[b];
        if (!f->failed[i] && !f->failed[k]) continue;
        const double *sh = m->shift[m->img[b]];
        double L2 = 0, r2 = 0;
        for (int a = 0; a < 3; ++a) {
          const double xi = (X[3 * k + a] - X[3 * i + a]) + sh[a];
          const double y = xi + (w[3 * k + a] - w[3 * i + a]);
          L2 += xi * xi, r2 += y * y;
        }
        const double r = sqrt(r2), L = f->lcon[b] < 0 ? fmin(sqrt(L2), r) : f->lcon[b];
        if (!(r < L)) continue;
        /* κ L² ∫_λ^1 g dλ' (Simpson, 32 intervals), ½ per side */
        const int nsimp = 32;
        const double lam = r / L, hs = (1.0 - lam) / nsimp;
        double integral = 0.0;
        for (int q = 0; q <= nsimp; ++q) {
          double gi, si, gk, sk;
          dm_pair_law(f, i, lam + q * hs, &gi, &si);
          dm_pair_law(f, k, lam + q * hs, &gk, &sk);
          integral += (q == 0 || q == nsimp ? 1.0 : q % 2 ? 4.0 : 2.0) * 0.5 * (gi + gk);
        }
        U += dm_fin_fold(f, i) * 0.5 * (f->kcon[i] + f->kcon[k]) * L * L * integral * hs / 3.0;
      }
  return U;
}

size_t dm_fin_failed_count(const dm_fin *f) {
  size_t c = 0;
  if (f->failed)
    for (size_t i = 0; i < f->n; ++i) c += f->failed[i] ? (size_t)dm_fin_fold(f, i) : 0;
  return c;
}

/* The `fracture: {model, spall_strength, failure_strain}` map of a deck section (a discrete_model
 * layer, the coupled problem's particles), docs/input-dm.md. */
void dm_frac_read(dk_errors *e, dk_doc *doc, const dk_node *section, const char *where,
                  dm_fracture *out) {
  static const char *const models[] = {"none", "mean_stress", "principal_stress", NULL};
  *out = (dm_fracture){0};
  const dk_node *F = dk_get(section, "fracture");
  if (!F) return;
  char what[96];
  snprintf(what, sizeof what, "%s.fracture", where);
  if (!dk_expect_map(e, doc, F, what)) return;
  dk_read_enum(e, doc, F, "model", false, DM_FRACTURE_MEAN_STRESS, models, &out->model);
  if (out->model == DM_FRACTURE_NONE) return;
  if (!dk_get(F, "spall_strength")) {
    dk_error(e, doc, F, "%s: a failure model needs 'spall_strength' (the tension σ_s, > 0)", what);
    return;
  }
  dk_read_positive(e, doc, F, "spall_strength", MS_DIM_PRESSURE, true, 0, &out->spall_strength);
  dk_read_double(e, doc, F, "failure_strain", MS_DIM_NONE, false, 0.0, 0.0, 100.0,
                 &out->failure_strain);
}
