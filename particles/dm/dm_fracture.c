/* SPDX-License-Identifier: MIT */
/* dm_fracture.c — fracture of the finite-deformation discrete model (docs/particles-dm.md,
 * "Fracture"): an instantaneous tensile cut-off at the spall strength σ_s (the pmin / "spall"
 * model of hydrocodes: a cell whose tension reaches the threshold loses its deviator and
 * carries pressure in compression only [Kanel2010], [Grady1988]), per particle, for good.
 *
 * A failed particle keeps its mass, momentum and family: σ = −max(p + q, 0) I, so it still
 * resists compression (a closed crack), and p = 0 while its family is stretched (J > 1: the
 * crack is open, the EOS is not asked about the void). Its bond penalty κ_i is set to 0 (the
 * penalty would otherwise carry the tension the break removed); the penalty energy it held is
 * booked as broken energy (it can no longer be returned). A bond is broken when both of its
 * particles have failed: then neither side's stress nor penalty acts through it in tension,
 * and the unbroken bonds define the fragments (dm_region.c). The internal energy of a failed
 * particle (its share of the elastic energy at the break included) stays in U as heat, so the
 * kick–drift–kick identity of dm_finite.c closes with the broken term:
 * K + U + E_hg + broken − W = const to round-off. */
#include "dm_impl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

void dm_frac_alloc(dm_fin *f) {
  bool any = false;
  for (size_t i = 0; i < f->n && !any; ++i) any = f->mat[f->imat[i]].frac.model != DM_FRACTURE_NONE;
  if (!any) return;
  f->failed = ms_calloc(f->n ? f->n : 1, 1);
  f->broken = ms_calloc(f->n ? f->n : 1, sizeof(double));
}

void dm_frac_free(dm_fin *f) {
  free(f->failed), free(f->broken);
  f->failed = NULL, f->broken = NULL;
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
    const double tension = fr->model == DM_FRACTURE_PRINCIPAL_STRESS
                               ? dm_frac_max_principal(sig)
                               : (sig[0] + sig[4] + sig[8]) / 3.0;
    const bool strained = fr->failure_strain > 0 && J - 1.0 >= fr->failure_strain;
    if (!(tension >= fr->spall_strength) && !strained) return;
    f->failed[i] = 1;
    f->broken[i] += f->ehg[i]; /* the penalty's stored energy leaves E_hg: it is released */
    f->ehg[i] = 0.0;
    f->m->kappa[i] = 0.0;
  }
  /* failed: no deviator, no tension; p + q = −tr σ/3 (s is traceless) */
  const double pq = -(sig[0] + sig[4] + sig[8]) / 3.0;
  for (int a = 0; a < 9; ++a) s[a] = 0.0, sig[a] = 0.0;
  sig[0] = sig[4] = sig[8] = -fmax(pq, 0.0);
}

/* The grain test of dm_impl.h. Why: the least-squares F of a failed particle's scattered
 * family can show any J, and a pressure from it is work never done — in the Piekutowski
 * perforation (docs/validation.md) failed particles' J fell from 0.77 to 0.26 in one step,
 * their pressure reached 4·10⁵ GPa and their internal energy −1.6·10⁶ kJ/g fed the kinetic
 * energy of the cloud (the balance held to round-off, the state was nonsense). A stretch of 2
 * puts a neighbour a whole spacing from where a continuum would keep it; a real flow changes J
 * by less than ~courant·|Δu|/c per step (≤ 0.2 at courant 0.4), a 30 % jump is the fit's. */
bool dm_frac_grain(dm_fin *f, size_t i, double J, double Jprev) {
  if (!dm_frac_failed(f, i)) return false;
  if (f->failed[i] == 2) return true;
  bool grain = !(J > 0) || (Jprev > 0 && fabs(J / Jprev - 1.0) > DM_FRAC_JUMP);
  const dm_model *m = f->m;
  const double *w = m->s->w;
  const double l2 = DM_FRAC_DISPERSED * DM_FRAC_DISPERSED;
  for (size_t b = m->start[i]; !grain && b < m->start[i + 1]; ++b) {
    const size_t k = m->nbr[b];
    double xi[3], r0 = 0, r1 = 0;
    dm_bond_vector(m, i, b, xi);
    for (int a = 0; a < 3; ++a) {
      const double d = xi[a] + w[3 * k + a] - w[3 * i + a];
      r0 += xi[a] * xi[a], r1 += d * d;
    }
    grain = r1 > l2 * r0;
  }
  if (grain) f->failed[i] = 2;
  return grain;
}

double dm_fin_broken_energy(const dm_fin *f) {
  double b = 0.0;
  if (f->broken)
    for (size_t i = 0; i < f->n; ++i) b += f->broken[i];
  return b;
}

size_t dm_fin_failed_count(const dm_fin *f) {
  size_t c = 0;
  if (f->failed)
    for (size_t i = 0; i < f->n; ++i) c += f->failed[i] != 0;
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
