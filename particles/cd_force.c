/* cd_force.c — pair forces, energies, virials and the relative-velocity damping.
 *
 * Pair term (paper 002 eqs. 1–2, tabulated in cd_potential.c): for a pair at d = x_i − x_j,
 * s = |d|², the force on i is (F/r)(s)·d and on j its opposite (F > 0 repulsive).
 * Virial: ½ Σ_{i≠j} f r_a r_b / r = Σ_{pairs} (F/r) d_a d_b.
 *
 * Loops run over the layers of the neighbour structure (cd_impl.h): the layers of one phase in
 * parallel (each writes only itself and the next layer), the phases one after the other, so
 * every sum has an order independent of the number of threads.
 */
#include "cd_impl.h"

#include <math.h>
#include <string.h>

/* Hot path: one table, plain cutoff, forces only (the benchmark's model). The table has one
 * spare interval at the top for s rounding onto rc²; fma() makes the Horner steps single
 * roundings. */
static inline void pair_fast(double s, double dx, double dy, double dz, double slo, double ih,
                             const double *restrict fc, double *fxi, double *fyi, double *fzi,
                             double *fxj, double *fyj, double *fzj) {
  double fr;
  if (s >= slo) {
    const double u = (s - slo) * ih;
    const int m = (int)u;
    const double w = u - m;
    const double *c = fc + 4 * m;
    fr = fma(w, fma(w, c[2], c[1]), c[0]);
  } else { /* below r_min: linear continuation of F/r in s (cd_potential.c) */
    fr = fma((s - slo) * ih, fc[1], fc[0]);
  }
  *fxi = fma(fr, dx, *fxi);
  *fyi = fma(fr, dy, *fyi);
  *fzi = fma(fr, dz, *fzi);
  *fxj = fma(-fr, dx, *fxj);
  *fyj = fma(-fr, dy, *fyj);
  *fzj = fma(-fr, dz, *fzj);
}

static void layer_forces_fast(const cd_neigh *nl, ptl_state *p, const cd_pair_table *t,
                              int layer) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  double *restrict fx = p->fx, *restrict fy = p->fy, *restrict fz = p->fz;
  const double slo = t->s_lo, ih = t->inv_h, rc2 = t->rc2;
  const double *restrict fc = t->fcoef;
  const int32_t *restrict buf = nl->buf[layer];
  for (int32_t i = nl->layer_start[layer]; i < nl->layer_start[layer + 1]; i++) {
    const int32_t pi = nl->sorted[i];
    const double xi = x[pi], yi = y[pi], zi = z[pi];
    double fxi = 0.0, fyi = 0.0, fzi = 0.0;
    const int32_t *restrict lst = buf + nl->first[i];
    const int np = nl->nplain[i], ni = nl->nimg[i];
    for (int k = 0; k < np; k++) {
      const int32_t j = lst[k];
      const double dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
      const double s = fma(dx, dx, fma(dy, dy, dz * dz));
      if (s < rc2) pair_fast(s, dx, dy, dz, slo, ih, fc, &fxi, &fyi, &fzi, fx + j, fy + j, fz + j);
    }
    lst += np;
    for (int k = 0; k < ni; k++) {
      const int32_t j = lst[2 * k];
      const double *sh = nl->shift[lst[2 * k + 1]];
      const double dx = xi - (x[j] + sh[0]), dy = yi - (y[j] + sh[1]), dz = zi - (z[j] + sh[2]);
      const double s = fma(dx, dx, fma(dy, dy, dz * dz));
      if (s < rc2) pair_fast(s, dx, dy, dz, slo, ih, fc, &fxi, &fyi, &fzi, fx + j, fy + j, fz + j);
    }
    fx[pi] += fxi;
    fy[pi] += fyi;
    fz[pi] += fzi;
  }
}

/* F/r at s (same arithmetic as pair_fast) and optionally the energy (cd_potential.c). */
static inline double tab_force(const cd_pair_table *t, double s, double *e) {
  double w, fr;
  int m = 0;
  if (s >= t->s_lo) {
    const double u = (s - t->s_lo) * t->inv_h;
    m = (int)u;
    w = u - m;
    const double *c = t->fcoef + 4 * m;
    fr = fma(w, fma(w, c[2], c[1]), c[0]);
  } else { /* below r_min: linear F/r, quadratic E (cd_potential.c) */
    w = (s - t->s_lo) * t->inv_h;
    fr = fma(w, t->fcoef[1], t->fcoef[0]);
  }
  if (e) {
    const double *ec = t->ecoef + 4 * m;
    *e = s >= t->s_lo ? fma(w, fma(w, fma(w, ec[3], ec[2]), ec[1]), ec[0])
                      : fma(w, fma(w, ec[2], ec[1]), ec[0]);
  }
  return fr;
}

/* Bonded mode: drop bond (i, j) from both partner rows. */
static void break_bond(int32_t *partners, int32_t i, int32_t j) {
  int32_t *pi = partners + (size_t)i * CD_MAX_PARTNERS, *pj = partners + (size_t)j * CD_MAX_PARTNERS;
  for (int k = 0; k < CD_MAX_PARTNERS; k++) {
    if (pi[k] == j) pi[k] = -1;
    if (pj[k] == i) pj[k] = -1;
  }
}

/* Under MPI a pair of an owned particle and a ghost is computed on both ranks (each keeps the
 * force on its own particle); its energy, virial and counts are booked by the rank owning the
 * particle with the smaller gid, so global sums count every pair once (docs/mpi.md). */
static inline bool books_pair(const ptl_state *p, int32_t i, int32_t j) {
  const int32_t nloc = (int32_t)p->nlocal;
  if (i < nloc && j < nloc) return true;
  return (p->gid[i] < p->gid[j] ? i : j) < nloc;
}

/* General path: several materials, bonded mode, energies and virials. */
static void layer_forces_full(cd_sim *s, int layer, cd_layer_sums *sum, double *pw, bool wf) {
  const cd_neigh *nl = s->nl;
  ptl_state *p = s->p;
  const double *x = p->x, *y = p->y, *z = p->z;
  double *fx = p->fx, *fy = p->fy, *fz = p->fz;
  const bool bonded = s->cfg.cutoff == CD_CUTOFF_BONDED;
  const double r02 = s->cfg.r0 * s->cfg.r0;
  int32_t *buf = nl->buf[layer];
  for (int32_t pos = nl->layer_start[layer]; pos < nl->layer_start[layer + 1]; pos++) {
    const int32_t i = nl->sorted[pos];
    const double xi = x[i], yi = y[i], zi = z[i];
    const int mi = p->mat[i];
    double fxi = 0.0, fyi = 0.0, fzi = 0.0;
    int32_t *lst = buf + nl->first[pos];
    const int np = nl->nplain[pos], ni = nl->nimg[pos];
    for (int k = 0; k < np + ni; k++) {
      int32_t *entry = k < np ? lst + k : lst + np + 2 * (k - np);
      const int32_t j = *entry & CD_NB_INDEX;
      const double *sh = k < np ? nl->shift[13] : nl->shift[entry[1]];
      const double dx = xi - (x[j] + sh[0]), dy = yi - (y[j] + sh[1]), dz = zi - (z[j] + sh[2]);
      const double r2 = fma(dx, dx, fma(dy, dy, dz * dz));
      const int mj = p->mat[j];
      const cd_pair_table *t = s->pair[mi][mj];
      double fr, e = 0.0;
      if (!bonded) {
        if (r2 >= t->rc2) continue;
        fr = tab_force(t, r2, sum ? &e : NULL);
        if (sum && books_pair(p, i, j)) sum->inside[mi * CD_MAX_MATERIALS + mj]++;
      } else if (*entry & CD_NB_BONDED) {
        if (r2 >= t->rc2) {
          if (!wf) continue; /* diagnostics never change the state */
          /* the bond breaks: its energy leaves the potential and is booked as broken. With the
           * hard truncation the force does work only up to R_c, so the energy lost is E(R_c):
           * evaluate there (r2 itself may lie far beyond the end of the table). */
          double eb;
          tab_force(t, t->rc2, &eb);
          *entry &= ~CD_NB_BONDED;
          break_bond(s->partners, i, j);
          if (sum && books_pair(p, i, j)) {
            sum->broken += eb;
            sum->nbroken++;
          }
          continue;
        }
        fr = tab_force(t, r2, sum ? &e : NULL);
      } else {
        if (r2 >= r02) continue; /* non-bonded: compressive branch only */
        fr = tab_force(t, r2, sum ? &e : NULL);
      }
      if (wf) {
        fxi = fma(fr, dx, fxi);
        fyi = fma(fr, dy, fyi);
        fzi = fma(fr, dz, fzi);
        fx[j] = fma(-fr, dx, fx[j]);
        fy[j] = fma(-fr, dy, fy[j]);
        fz[j] = fma(-fr, dz, fz[j]);
      }
      if (sum) {
        double v[6] = {fr * dx * dx, fr * dy * dy, fr * dz * dz,
                       fr * dx * dy, fr * dy * dz, fr * dz * dx};
        if (books_pair(p, i, j)) {
          sum->epot += e;
          for (int c = 0; c < 6; c++) sum->vir[c] += v[c];
        }
        if (pw)
          for (int c = 0; c < 6; c++) {
            pw[6 * (size_t)i + c] += 0.5 * v[c];
            pw[6 * (size_t)j + c] += 0.5 * v[c];
          }
      }
    }
    if (wf) {
      fx[i] += fxi;
      fy[i] += fyi;
      fz[i] += fzi;
    }
  }
}

void cd_compute_forces(cd_sim *s, cd_layer_sums *sums, double *pw, bool wf) {
  ptl_state *p = s->p;
  const cd_neigh *nl = s->nl;
  const long n = (long)p->n;
  double *fx = p->fx, *fy = p->fy, *fz = p->fz;
  if (wf && !s->forces_zeroed) {
#pragma omp parallel for schedule(static) if (CD_PAR(n))
    for (long i = 0; i < n; i++) fx[i] = fy[i] = fz[i] = 0.0;
  }
  if (pw) memset(pw, 0, 6 * (size_t)n * sizeof *pw);
  if (sums) memset(sums, 0, (size_t)nl->nlayer * sizeof *sums);
  s->forces_zeroed = false;
  const bool fast = wf && !sums && !pw && s->nmat == 1 && s->cfg.cutoff == CD_CUTOFF_PLAIN;
  for (int ph = 0; ph < nl->nphase; ph++) {
    const int a = nl->phase_start[ph], b = nl->phase_start[ph + 1];
    if (nl->colour) {
#pragma omp parallel for schedule(dynamic, 1) if (CD_PAR(p->n))
      for (int k = a; k < b; k++) {
        int l = nl->phase_layer[k];
        if (fast)
          layer_forces_fast(nl, p, s->pair[0][0], l);
        else
          layer_forces_full(s, l, sums ? sums + l : NULL, pw, wf);
      }
    } else {
      for (int k = a; k < b; k++) {
        int l = nl->phase_layer[k];
        if (fast)
          layer_forces_fast(nl, p, s->pair[0][0], l);
        else
          layer_forces_full(s, l, sums ? sums + l : NULL, pw, wf);
      }
    }
  }
}

/* ---- damping (paper 002 eq. 6) ---- */

static void layer_damping(cd_sim *s, int layer, double *dv) {
  const cd_neigh *nl = s->nl;
  const ptl_state *p = s->p;
  const double *x = p->x, *y = p->y, *z = p->z;
  const double *vx = p->vx, *vy = p->vy, *vz = p->vz;
  const double g = s->cfg.damping_gamma * s->cfg.dt;
  const bool bonded = s->cfg.cutoff == CD_CUTOFF_BONDED;
  const int32_t *buf = nl->buf[layer];
  for (int32_t pos = nl->layer_start[layer]; pos < nl->layer_start[layer + 1]; pos++) {
    const int32_t i = nl->sorted[pos];
    const int32_t *lst = buf + nl->first[pos];
    const int np = nl->nplain[pos], ni = nl->nimg[pos];
    for (int k = 0; k < np + ni; k++) {
      const int32_t *entry = k < np ? lst + k : lst + np + 2 * (k - np);
      const int32_t j = *entry & CD_NB_INDEX;
      const double *sh = k < np ? nl->shift[13] : nl->shift[entry[1]];
      const double dx = x[i] - (x[j] + sh[0]), dy = y[i] - (y[j] + sh[1]),
                   dz = z[i] - (z[j] + sh[2]);
      const double r2 = dx * dx + dy * dy + dz * dz;
      const cd_pair_table *t = s->pair[p->mat[i]][p->mat[j]];
      /* neighbours "within the range of the potential": inside R_c (bonds, in bonded mode) */
      if (bonded ? !(*entry & CD_NB_BONDED) && r2 >= t->r0 * t->r0 : r2 >= t->rc2) continue;
      double mi = p->mass[i], mj = p->mass[j];
      double mu = 2.0 * mi * mj / (mi + mj);
      double ux = vx[i] - vx[j], uy = vy[i] - vy[j], uz = vz[i] - vz[j];
      double ci = g * mu / mi, cj = g * mu / mj;
      dv[3 * (size_t)i] -= ci * ux;
      dv[3 * (size_t)i + 1] -= ci * uy;
      dv[3 * (size_t)i + 2] -= ci * uz;
      dv[3 * (size_t)j] += cj * ux;
      dv[3 * (size_t)j + 1] += cj * uy;
      dv[3 * (size_t)j + 2] += cj * uz;
    }
  }
}

double cd_damping_step(cd_sim *s) {
  ptl_state *p = s->p;
  const cd_neigh *nl = s->nl;
  const long n = (long)p->nlocal; /* ghosts' increments are their owners' business */
  double *dv = s->scratch;
  memset(dv, 0, 3 * p->n * sizeof *dv);
  for (int ph = 0; ph < nl->nphase; ph++) {
    const int a = nl->phase_start[ph], b = nl->phase_start[ph + 1];
#pragma omp parallel for schedule(dynamic, 1) if (nl->colour && CD_PAR(p->n))
    for (int k = a; k < b; k++) layer_damping(s, nl->phase_layer[k], dv);
  }
  /* Apply to integrated particles; the exact kinetic-energy change is the dissipation
   * (driven particles keep their prescribed velocity). Summed in index order per static
   * chunk, then over chunks: deterministic for a fixed thread count. */
  double removed = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : removed) if (CD_PAR(n))
  for (long i = 0; i < n; i++) {
    if (p->flags[i] & (PTL_DRIVEN | PTL_REMOVED)) continue;
    double ax = dv[3 * i], ay = dv[3 * i + 1], az = dv[3 * i + 2];
    double de = p->mass[i] * (p->vx[i] * ax + p->vy[i] * ay + p->vz[i] * az +
                              0.5 * (ax * ax + ay * ay + az * az));
    p->vx[i] += ax;
    p->vy[i] += ay;
    p->vz[i] += az;
    removed -= de;
  }
  return removed;
}
