/* SPDX-License-Identifier: MIT */
/* dm_contact.c — contact of the finite-deformation discrete model (docs/particles-dm.md
 * "Contact"): the one pair law and the short-range contact between particles that are not in
 * each other's family, over the hashed cell list of dm_cells.c.
 *
 * The pair law (dm_pair_law; used by the contact across broken bonds, dm_fracture.c, and by the
 * short-range contact below): a compression-only central spring of rest length L,
 *   |f| = κ_ik L g(λ),  λ = r/L < 1,  κ_ik = κc_i + κc_k,  κc_i = K d² V_i / Σ_k |ξ_ik|²,
 * K = ρ0 c0² of the particle's material, d the dimension: the lattice form of the bond-based
 * micromodulus c = 18K/(π δ⁴) of [SillingAskari2005]; g follows the material's EOS along e = e0,
 * g = [p(ρ0 λ^−d) − p(ρ0)] λ^(d−1)/(K d) → 1 − λ, so that a uniformly compressed lattice of such
 * pairs carries its EOS pressure; and a dashpot η ṙ while the pair approaches,
 * η = C_l √(κ s √(m_i m_k)) (s the spring's current stiffness over κ).
 *
 * The short-range contact (dm_contact_*; [SillingAskari2005] §5's short-range forces, LAMMPS PERI
 * [Parks2008]): the pair law between any two particles that are not in each other's family,
 * intact or failed, closer than the contact distance d_c = c ℓ (dm_fin_params.contact = c;
 * L = d_c). [SillingAskari2005] and LAMMPS act between every pair within min(0.9 |ξ|, 1.35 ℓ),
 * family members included; here the families carry their own stress, so only pairs outside
 * them are seen, and d_c must stay below the spacing that the lattice's neighbours reach under
 * the run's compression (30 GPa in Pb: ρ/ρ0 = 1.4, neighbours along a uniaxial compression at
 * 0.72 ℓ), while acting before two particles pass through each other. The default c = 0.5 (the
 * particle's radius: two particles overlap by half a spacing) needs ρ/ρ0 = 2 of uniaxial
 * compression to reach a lattice neighbour (~200 GPa in Pb); docs/particles-dm.md "Contact".
 * Its stiffness: κc_i = K d² V_i / ℓ², the calibration above with the family replaced by one
 * bond of length ℓ — across a contact a particle meets one or two particles of the other side
 * where inside the lattice its whole family carries the load, so one pair is as stiff as the
 * family (with the family's κc an intact particle of a Rz80 jet pushed a failed one to 0.25 ℓ:
 * the stop of the first version); at small penetration a pair carries 2 d² (d_c/ℓ) K (1 − r/d_c)
 * over the face ℓ^(d−1): K at a penetration of an eighth of d_c in 2D.
 * The spring's and dashpot's work, −h Σ f·v̄ over each half kick, is booked in energy[i] (the
 * dashpot's heat stays there: the contact's energy is the spring's potential plus the heat it
 * made), so K + U + E_hg + broken + contact − W = const to round-off. Step: the stiffness,
 * ω dt ≤ courant (√(1 + ζ²) − ζ), ω² = 2 Σ κ s/m over the particle's pairs in contact
 * (Gershgorin, as dm_fracture.c; half the stability limit, as the impact's contact, to resolve
 * the stiff pair), and no pair within the
 * seeing distance d_c + ℓ/2 closes by more than courant times its gap to d_c·λ_end (and to L
 * inside) in a step; pairs further out reach d_c only faster than (ℓ/2)/dt ≈ 1.25 c_L. A run in
 * which no outside pair comes within d_c + ℓ/2 keeps its bits (the forces and step are then
 * those without the contact). */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- the pair law ---- */

void dm_pair_stiffness(const dm_fin *f, double *kc, double ell) {
  const dm_model *m = f->m;
  const dm_state *st = m->s;
  const double d = f->dim;
  for (size_t i = 0; i < f->n; ++i) {
    const dm_fin_material *mt = &f->mat[f->imat[i]];
    const double rho0 = eos_rho0(mt->eos), c0 = eos_sound_speed(mt->eos, rho0, eos_e0(mt->eos));
    double trA = ell * ell;
    for (size_t b = m->start[i]; ell == 0 && b < m->start[i + 1]; ++b) {
      double xi[3];
      dm_bond_vector(m, i, b, xi);
      trA += xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2];
    }
    kc[i] = trA > 0 ? rho0 * c0 * c0 * d * d * st->vol[i] / trA : 0.0;
  }
}

/* g = [p(ρ0 λ^−d, e0) − p(ρ0, e0)] λ^(d−1)/(K d) — the EOS pressure of a uniform compression λ
 * over the pair's share of the face it acts on — and s ≥ |dg/dλ|, the stiffness over κ:
 * ρ0 c(ρ, e0)²/(K λ²) + (d − 1) p λ^(d−2)/(K d). */
void dm_pair_law(const dm_fin *f, size_t i, double lam, double *g, double *s) {
  const eos_t *eos = f->mat[f->imat[i]].eos;
  const double rho0 = eos_rho0(eos), e0 = eos_e0(eos), c0 = eos_sound_speed(eos, rho0, e0);
  const double K = rho0 * c0 * c0, d = f->dim, rho = rho0 * pow(lam, -d);
  const double p = eos_pressure(eos, rho, e0) - eos_pressure(eos, rho0, e0);
  const double c = eos_sound_speed(eos, rho, e0);
  *g = p * pow(lam, d - 1.0) / (K * d);
  *s = rho0 * c * c / (K * lam * lam) + (d - 1.0) * fabs(p) * pow(lam, d - 2.0) / (K * d);
}

/* The end of each material's EOS range as λ (mg_linear ends at ρ/ρ0 = s/(s − 1):
 * λ = ((s − 1)/s)^(1/d), 0.63 for Al in 3D), by bisection to 1e-9; 0 when the law is finite
 * down to λ = 1e-3. */
void dm_pair_ends(const dm_fin *f, double *lam_end) {
  bool seen[256] = {false};
  for (size_t i = 0; i < f->n; ++i) {
    const uint8_t im = f->imat[i];
    if (seen[im]) continue;
    seen[im] = true;
    double lo = 1e-3, hi = 1.0, g, sl;
    dm_pair_law(f, i, lo, &g, &sl);
    if (isfinite(g) && isfinite(sl)) continue;
    while (hi - lo > 1e-9) {
      const double mid = 0.5 * (lo + hi);
      dm_pair_law(f, i, mid, &g, &sl);
      if (isfinite(g) && isfinite(sl)) hi = mid;
      else lo = mid;
    }
    lam_end[im] = hi;
  }
}

/* ---- the short-range contact ---- */

ms_status dm_contact_alloc(dm_fin *f) {
  if (!(f->par.contact > 0)) return MS_OK;
  dm_contact *c = ms_calloc(1, sizeof *c);
  const size_t n1 = f->n ? f->n : 1;
  c->L = f->par.contact * f->par.ell, c->r_see = c->L + 0.5 * f->par.ell;
  if (dm_cells_init(&c->cells, f->n, f->dim, c->r_see, NULL, f->m->opt.box) != MS_OK) {
    free(c);
    return MS_ERR_INPUT; /* a periodic box narrower than 3 seeing distances */
  }
  c->kc = ms_calloc(n1, sizeof(double));
  c->force = ms_calloc(3 * n1, sizeof(double));
  c->energy = ms_calloc(n1, sizeof(double));
  c->dt = ms_calloc(n1, sizeof(double));
  c->touch = ms_calloc(n1, 1);
  dm_pair_stiffness(f, c->kc, f->par.ell); /* one pair as stiff as a whole family (head) */
  dm_pair_ends(f, c->lam_end);
  f->sr = c;
  return MS_OK;
}

void dm_contact_free(dm_fin *f) {
  dm_contact *c = f->sr;
  if (!c) return;
  dm_cells_free(&c->cells);
  free(c->kc), free(c->force), free(c->energy), free(c->dt), free(c->touch);
  free(c);
  f->sr = NULL;
}

/* Is k in i's family (sorted by index)? */
static bool in_family(const dm_model *m, size_t i, size_t k) {
  size_t lo = m->start[i], hi = m->start[i + 1];
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (m->nbr[mid] == k) return true;
    if (m->nbr[mid] < k) lo = mid + 1;
    else hi = mid;
  }
  return false;
}

/* Particle i's contact force (spring + dashpot) into c->force, its step into c->dt; returns the
 * smallest r/L of its pairs in contact (1 if none). Writes particle i's entries only; a pair is
 * seen from both sides with the same bits (the minimum image and every term are negated
 * exactly), so the forces are equal and opposite. */
static double contact_one(const dm_fin *f, dm_contact *c, size_t i) {
  const dm_model *m = f->m;
  const dm_state *s = m->s;
  const dm_cells *cl = &c->cells;
  const double *X = s->X, *w = s->w, *u = s->u, *mass = s->mass;
  const double L = c->L, rsee2 = c->r_see * c->r_see;
  double xi[3], ft[3] = {0, 0, 0}, lmin = 1.0, closing = 0.0, sk = 0.0;
  for (int a = 0; a < 3; ++a) xi[a] = X[3 * i + a] + w[3 * i + a];
  int touching = 0;
  for (int q = 0; q < cl->nnear; ++q) {
    long cn[3];
    dm_cells_near(cl, &cl->cidx[3 * i], q, cn);
    for (long j = dm_cells_list(cl, cn); j >= 0; j = cl->next[j]) {
      if ((size_t)j == i || !dm_cells_holds(cl, j, cn)) continue;
      double y[3], r2 = 0; /* y = x_j − x_i, the minimum image along periodic axes */
      for (int a = 0; a < 3; ++a) {
        y[a] = (X[3 * j + a] + w[3 * j + a]) - xi[a];
        if (cl->box[a] > 0) y[a] -= cl->box[a] * nearbyint(y[a] / cl->box[a]);
        r2 += y[a] * y[a];
      }
      if (!(r2 < rsee2) || in_family(m, i, (size_t)j) ||
          (c->within_material && f->imat[i] != f->imat[j]))
        continue;
      const double r = sqrt(r2);
      if (!(r > 0)) {
        lmin = 0.0;
        continue;
      }
      const double rdot = ((u[3 * j] - u[3 * i]) * y[0] + (u[3 * j + 1] - u[3 * i + 1]) * y[1] +
                           (u[3 * j + 2] - u[3 * i + 2]) * y[2]) /
                          r;
      /* no pair closes in a step by more than courant times its gap to the end of the EOS's
       * range (λ_end L), nor, in contact, by more than courant · L (dm_fracture.c) */
      const double lend = fmax(c->lam_end[f->imat[i]], c->lam_end[f->imat[j]]);
      const double gap = fmax(r - lend * L, 1e-300);
      if (rdot < 0) closing = fmax(closing, -rdot / (r < L ? fmin(L, gap) : gap));
      if (!(r < L)) continue;
      double gi, si, gk, sk_;
      dm_pair_law(f, i, r / L, &gi, &si);
      dm_pair_law(f, (size_t)j, r / L, &gk, &sk_);
      const double kap = c->kc[i] + c->kc[j], gl = 0.5 * (gi + gk), sl = 0.5 * (si + sk_);
      if (!isfinite(gl) || !isfinite(sl)) {
        lmin = 0.0;
        continue;
      }
      const double eta = f->par.cl * sqrt(kap * sl * sqrt(mass[i] * mass[j]));
      const double g = rdot < 0 ? eta * rdot : 0.0, spring = kap * L * gl;
      for (int a = 0; a < 3; ++a) ft[a] += (g - spring) * y[a] / r;
      sk += kap * sl;
      lmin = fmin(lmin, r / L);
      touching = 1;
    }
  }
  for (int a = 0; a < 3; ++a) c->force[3 * i + a] = ft[a];
  c->touch[i] = (uint8_t)touching;
  /* the stiffness limit with the dashpot's lowering (dm_fracture.c contact_stiffness) */
  const double zeta = f->par.cl / sqrt(2.0), damped = sqrt(1.0 + zeta * zeta) - zeta;
  double dt = closing > 0 ? f->par.courant / closing : INFINITY;
  if (sk > 0) dt = fmin(dt, f->par.courant * damped / sqrt(2.0 * sk / mass[i]));
  c->dt[i] = dt;
  return lmin;
}

ms_status dm_contact_force(dm_fin *f, double *dtmin, long *imin) {
  dm_contact *c = f->sr;
  const dm_state *s = f->m->s;
  dm_cells_build(&c->cells, s->X, s->w);
  const long n = (long)f->n;
  long bad = n, pairs = 0;
#pragma omp parallel for schedule(static) reduction(min : bad) reduction(+ : pairs) if (n > 4096)
  for (long i = 0; i < n; ++i) {
    const double lmin = contact_one(f, c, (size_t)i);
    pairs += c->touch[i];
    if (!(lmin >= DM_CONTACT_MIN_RATIO) && i < bad) bad = i;
  }
  c->touching = pairs;
  if (bad < n) {
    f->bad = (size_t)bad, f->bad_value = contact_one(f, c, (size_t)bad);
    f->bad_what = "short-range contact: a pair's distance over the contact distance (< 0.5)";
    return MS_ERR_UNSTABLE;
  }
  for (long i = 0; i < n;
       ++i) { /* only where it acts: elsewhere frc and the step keep their bits */
    if (c->touch[i])
      for (int a = 0; a < 3; ++a) f->frc[3 * i + a] += c->force[3 * i + a];
    if (c->dt[i] < *dtmin || (c->dt[i] == *dtmin && i < *imin)) *dtmin = c->dt[i], *imin = i;
  }
  return MS_OK;
}

void dm_contact_work(dm_fin *f, double h, const double *vb) {
  dm_contact *c = f->sr;
  if (!c || !c->touching) return;
  for (size_t i = 0; i < f->n; ++i)
    if (c->touch[i]) {
      const double *fc = &c->force[3 * i];
      c->energy[i] -= h * (fc[0] * vb[3 * i] + fc[1] * vb[3 * i + 1] + fc[2] * vb[3 * i + 2]);
    }
}

double dm_contact_energy(const dm_fin *f) {
  double e = 0.0;
  if (f->sr)
    for (size_t i = 0; i < f->n; ++i) e += dm_fin_fold(f, i) * f->sr->energy[i];
  return e;
}
