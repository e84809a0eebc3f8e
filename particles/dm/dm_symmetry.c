/* SPDX-License-Identifier: MIT */
/* dm_symmetry.c — symmetry planes of the finite-deformation discrete model (docs/particles-dm.md,
 * "Symmetry planes"): a body symmetric about up to three coordinate planes is run as its part on
 * the + side of every plane (a half, a quarter, an eighth).
 *
 * Images. The reflection of plane j is x ↦ M_j x + 2 pos_j e_j, M_j = I − 2 e_j e_jᵀ. In the full
 * body the image k' of a particle k under any product M of the planes' reflections is in the
 * mirrored state: X_k' = M X_k (+ shift), w_k' = M w_k, u_k' = M u_k, F_k' = M F_k M,
 * σ_k' = M σ_k M, P_k' = M P_k M, A_k' = M A_k M, so Q_k' = V P' A'⁻¹ − κ C' = M Q_k M; its e,
 * ε_p, κ and failure are k's. The model keeps the real particles (+ side) and, after them, mirror
 * ghosts: the images of the real particles within a horizon of the planes involved (an image of k
 * farther than δ from the plane cannot be within δ of a particle on the + side). The real
 * particles' families are built over reals and ghosts (dm_family.c), so each is the full body's
 * family; ghosts have no family (dm_options.ghost_rows): their rows are copied from their
 * partners before every pass that reads them (dm_sym_sync; M is a diagonal of ±1, so the copies
 * are exact). Every force on a real particle is then the full body's, by the same bond sums in
 * another order: the quarter equals the full run to the round-off of the summation order.
 *
 * On a plane. A particle on plane j is its own image: no ghost; by symmetry u_j = 0 and the
 * normal force vanishes (the full body's bonds to the two sides cancel), so the model holds
 * u_j = 0 and drops f_j (which is round-off). Held components do no work (v̄_j = 0), so the
 * energy identity of dm_finite.c keeps holding.
 *
 * Full-body sums. Each real particle stands for its orbit, fold_i = Π_j (2 off plane j, 1 on it)
 * particles of the same state, so Σ_i fold_i (·) over the real particles is the full body's
 * energy, work or momentum (the components normal to a plane cancel in each orbit: 0). The
 * energy identity of the full body is the fold-weighted identity of the real particles, so the
 * fold-weighted K + U + E_hg − W is conserved to round-off. */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool dm_sym_on_plane(double x, double pos, double ell) { return fabs(x - pos) <= 1e-9 * ell; }

/* A copy of the first `keep` elements of p (each `size` bytes) in a zeroed block of n. */
static void *grow(void *p, size_t keep, size_t n, size_t size, bool aligned) {
  void *q = aligned ? ms_aligned_alloc(n, size) : ms_calloc(n, size);
  memcpy(q, p, keep * size);
  free(p);
  return q;
}

/* Is real particle i's image under the planes of mask a ghost (off each such plane, within reach)? */
static bool has_image(const dm_state *s, size_t i, const dm_sym_planes *pl, unsigned mask,
                      double reach, double ell) {
  for (int j = 0; j < pl->n; ++j) {
    if (!(mask >> j & 1u)) continue;
    const double x = s->X[3 * i + pl->axis[j]];
    if (dm_sym_on_plane(x, pl->pos[j], ell) || !(x - pl->pos[j] < reach)) return false;
  }
  return true;
}

size_t dm_sym_ghosts(dm_state *s, size_t nreal, const dm_sym_planes *pl, double reach, double ell) {
  for (size_t i = 0; i < nreal; ++i) /* a particle on a plane: exactly on it */
    for (int j = 0; j < pl->n; ++j)
      if (dm_sym_on_plane(s->X[3 * i + pl->axis[j]], pl->pos[j], ell))
        s->X[3 * i + pl->axis[j]] = pl->pos[j];
  const unsigned nmask = 1u << pl->n;
  size_t ng = 0;
  for (unsigned mask = 1; mask < nmask; ++mask)
    for (size_t i = 0; i < nreal; ++i) ng += has_image(s, i, pl, mask, reach, ell);
  const size_t n = nreal + ng, m = n ? n : 1;
  s->X = grow(s->X, 3 * nreal, 3 * m + 1, sizeof(double), true); /* +1: 4-lane loads */
  s->w = grow(s->w, 3 * nreal, 3 * m + 1, sizeof(double), true);
  s->u = grow(s->u, 3 * nreal, 3 * m + 1, sizeof(double), true);
  s->mass = grow(s->mass, nreal, m, sizeof(double), true);
  s->vol = grow(s->vol, nreal, m, sizeof(double), true);
  s->K = grow(s->K, nreal, m, sizeof(double), true);
  s->G = grow(s->G, nreal, m, sizeof(double), true);
  s->bc = grow(s->bc, nreal, m, 1, false);
  s->partner = grow(s->partner, nreal, m, sizeof(uint32_t), false);
  s->msign = grow(s->msign, 3 * nreal, 3 * m, sizeof(int8_t), false);
  size_t g = nreal;
  for (unsigned mask = 1; mask < nmask; ++mask) /* in the order of the masks, then of i */
    for (size_t i = 0; i < nreal; ++i) {
      if (!has_image(s, i, pl, mask, reach, ell)) continue;
      for (int a = 0; a < 3; ++a) s->msign[3 * g + a] = 1, s->X[3 * g + a] = s->X[3 * i + a];
      for (int j = 0; j < pl->n; ++j)
        if (mask >> j & 1u) {
          const int a = pl->axis[j];
          s->msign[3 * g + a] = -1, s->X[3 * g + a] = 2.0 * pl->pos[j] - s->X[3 * i + a];
        }
      for (int a = 0; a < 3; ++a) {
        s->w[3 * g + a] = s->msign[3 * g + a] * s->w[3 * i + a];
        s->u[3 * g + a] = s->msign[3 * g + a] * s->u[3 * i + a];
      }
      s->mass[g] = s->mass[i], s->vol[g] = s->vol[i], s->K[g] = s->K[i], s->G[g] = s->G[i];
      s->bc[g] = DM_MIRROR, s->partner[g] = (uint32_t)i;
      ++g;
    }
  s->n = n;
  return ng;
}

void dm_sym_reference(dm_state *s, size_t nreal, const dm_sym_planes *pl) {
  for (size_t g = nreal; g < s->n; ++g) {
    const size_t i = s->partner[g];
    for (int a = 0; a < 3; ++a) s->X[3 * g + a] = s->X[3 * i + a];
    for (int j = 0; j < pl->n; ++j) { /* dm_sym_ghosts' arithmetic */
      const int a = pl->axis[j];
      if (s->msign[3 * g + a] < 0) s->X[3 * g + a] = 2.0 * pl->pos[j] - s->X[3 * i + a];
    }
    s->vol[g] = s->vol[i];
  }
}

/* The ghosts' materials (imat_all) and the arrays of nall rows that the passes read at the ghosts
 * (v̄, v_close) for the current ghost set. */
void dm_sym_resize(dm_fin *f, const uint8_t *imat) {
  const dm_state *s = f->m->s;
  f->nall = s->n;
  const size_t na = f->nall ? f->nall : 1;
  uint8_t *im = ms_calloc(na, 1);
  memcpy(im, imat, f->n);
  for (size_t g = f->n; g < f->nall; ++g) im[g] = im[s->partner[g]];
  free(f->imat_all);
  f->imat_all = im, f->imat = im;
  free(f->vbar), free(f->vclose);
  f->vbar = ms_calloc(3 * na + 1, sizeof(double)); /* +1: ld4 */
  f->vclose = ms_calloc(3 * na + 1, sizeof(double));
}

ms_status dm_sym_init(dm_fin *f, const dm_sym_planes *pl, const uint8_t *imat) {
  const dm_state *s = f->m->s;
  f->sym = *pl;
  dm_sym_resize(f, imat);
  const size_t n1 = f->n ? f->n : 1;
  f->fold = ms_calloc(n1, sizeof(double));
  f->onplane = ms_calloc(3 * n1, sizeof(size_t));
  for (size_t i = 0; i < f->n; ++i) {
    f->fold[i] = 1.0;
    for (int j = 0; j < pl->n; ++j) {
      const int a = pl->axis[j];
      if (s->X[3 * i + a] < pl->pos[j]) return MS_ERR_INPUT; /* a real particle on the − side */
      if (s->X[3 * i + a] != pl->pos[j]) { /* dm_sym_ghosts put the ones on it exactly on it */
        f->fold[i] *= 2.0;
        continue;
      }
      if (s->u[3 * i + a] != 0.0) return MS_ERR_INPUT; /* a velocity through its plane */
      f->onplane[f->nonplane++] = 3 * i + (size_t)a;
    }
  }
  return MS_OK;
}

void dm_sym_free(dm_fin *f) {
  free(f->fold), free(f->onplane), free(f->imat_all);
  f->fold = NULL, f->onplane = NULL, f->imat_all = NULL;
}

void dm_sym_sync(dm_fin *f) {
  if (f->nall <= f->n) return;
  dm_model *m = f->m;
  dm_state *s = m->s;
  const long n0 = (long)f->n, n1 = (long)f->nall;
#pragma omp parallel for schedule(static) if (n1 - n0 > 4096)
  for (long g = n0; g < n1; ++g) {
    const size_t p = s->partner[g];
    const int8_t *sg = &s->msign[3 * g];
    for (int a = 0; a < 3; ++a) {
      s->w[3 * g + a] = sg[a] * s->w[3 * p + a], s->u[3 * g + a] = sg[a] * s->u[3 * p + a];
      f->vbar[3 * g + a] = sg[a] * f->vbar[3 * p + a];
      f->vclose[3 * g + a] = sg[a] * f->vclose[3 * p + a];
    }
    for (int a = 0; a < 3; ++a) /* Q' = M Q M (Q stored transposed: the same signs) */
      for (int b = 0; b < 3; ++b) m->Q[9 * g + 3 * a + b] = sg[a] * sg[b] * m->Q[9 * p + 3 * a + b];
    m->kappa[g] = m->kappa[p];
    if (f->failed) f->failed[g] = f->failed[p], f->kcon[g] = f->kcon[p];
  }
}

void dm_fin_momentum(const dm_fin *f, double P[3]) {
  const dm_state *s = f->m->s;
  P[0] = P[1] = P[2] = 0.0;
  for (size_t i = 0; i < f->n; ++i)
    for (int a = 0; a < 3; ++a) P[a] += dm_fin_fold(f, i) * s->mass[i] * s->u[3 * i + a];
  for (int j = 0; j < f->sym.n; ++j) P[f->sym.axis[j]] = 0.0;
}
