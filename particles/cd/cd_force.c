/* SPDX-License-Identifier: MIT */
/* cd_force.c — pair forces, energies, virials and the relative-velocity damping.
 *
 * Pair term ([Davydov] eqs. 1–2, tabulated in cd_potential.c): for a pair at d = x_i − x_j,
 * s = |d|², the force on i is (F/r)(s)·d and on j its opposite (F > 0 repulsive).
 * Virial: ½ Σ_{i≠j} f r_a r_b / r = Σ_{pairs} (F/r) d_a d_b.
 *
 * Loops run over the layers of the neighbour structure (cd_impl.h): the layers of one phase in
 * parallel (each writes only itself and the next layer), the phases one after the other, so
 * every sum has an order independent of the number of threads. The fast path on full lists
 * (cd_layer_forces_fit, cd_force_fit.h) needs no phases: no particle writes another's force.
 */
#include "cd_force_fit.h"

#include <math.h>
#include <string.h>
#if defined(_OPENMP)
#include <omp.h>
#endif

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

/* The rest of the particle at position pos (index i, at xi, yi, zi): its plain entries from k0
 * on and its image entries, one at a time, into its partners' forces and into the force it has
 * so far (fxi, ...), which is then added to f_i. */
MS_KERNEL_INLINE static inline void
finish_particle(const cd_neigh *nl, const int32_t *restrict lst, int k0, int32_t pos, int32_t i,
                double xi, double yi, double zi, const double *restrict x, const double *restrict y,
                const double *restrict z, double *restrict fx, double *restrict fy,
                double *restrict fz, double slo, double ih, double rc2, const double *restrict fc,
                double fxi, double fyi, double fzi) {
  const int np = nl->nplain[pos], ni = nl->nimg[pos];
  for (int k = k0; k < np; k++) {
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
  fx[i] += fxi;
  fy[i] += fyi;
  fz[i] += fzi;
}

/* Two consecutive particles at a time, their plain entries interleaved (entry k of each, then
 * entry k + 1), so that two independent chains s → table → F/r → f_j are in flight: one
 * particle's chain is latency-bound (docs/benchmarks.md, round 10: problem B's force loop
 * ~12 % faster on one core; three or four lanes were no better). Each particle's remaining
 * entries follow one at a time. The order of the f_j updates is fixed by the layout alone, so
 * results stay independent of the thread count. */
MS_KERNEL_CLONES static void layer_forces_fast(const cd_neigh *nl, ptl_state *p,
                                               const cd_pair_table *t, int layer) {
  const double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
  double *restrict fx = p->fx, *restrict fy = p->fy, *restrict fz = p->fz;
  const double slo = t->s_lo, ih = t->inv_h, rc2 = t->rc2;
  const double *restrict fc = t->fcoef;
  const int32_t *restrict buf = nl->buf[layer];
  const int32_t end = nl->layer_start[layer + 1];
  int32_t pos = nl->layer_start[layer];
  for (; pos + 1 < end; pos += 2) {
    const int32_t pa = nl->sorted[pos], pb = nl->sorted[pos + 1];
    const double xa = x[pa], ya = y[pa], za = z[pa], xb = x[pb], yb = y[pb], zb = z[pb];
    double fxa = 0.0, fya = 0.0, fza = 0.0, fxb = 0.0, fyb = 0.0, fzb = 0.0;
    const int32_t *restrict la = buf + nl->first[pos], *restrict lb = buf + nl->first[pos + 1];
    const int na = nl->nplain[pos], nb = nl->nplain[pos + 1];
    const int nboth = na < nb ? na : nb;
    for (int k = 0; k < nboth; k++) {
      const int32_t ja = la[k], jb = lb[k];
      const double dxa = xa - x[ja], dya = ya - y[ja], dza = za - z[ja];
      const double dxb = xb - x[jb], dyb = yb - y[jb], dzb = zb - z[jb];
      const double sa = fma(dxa, dxa, fma(dya, dya, dza * dza));
      const double sb = fma(dxb, dxb, fma(dyb, dyb, dzb * dzb));
      if (sa < rc2)
        pair_fast(sa, dxa, dya, dza, slo, ih, fc, &fxa, &fya, &fza, fx + ja, fy + ja, fz + ja);
      if (sb < rc2)
        pair_fast(sb, dxb, dyb, dzb, slo, ih, fc, &fxb, &fyb, &fzb, fx + jb, fy + jb, fz + jb);
    }
    finish_particle(nl, la, nboth, pos, pa, xa, ya, za, x, y, z, fx, fy, fz, slo, ih, rc2, fc, fxa,
                    fya, fza);
    finish_particle(nl, lb, nboth, pos + 1, pb, xb, yb, zb, x, y, z, fx, fy, fz, slo, ih, rc2, fc,
                    fxb, fyb, fzb);
  }
  if (pos < end) { /* an odd particle at the layer's end */
    const int32_t pi = nl->sorted[pos];
    finish_particle(nl, buf + nl->first[pos], 0, pos, pi, x[pi], y[pi], z[pi], x, y, z, fx, fy, fz,
                    slo, ih, rc2, fc, 0.0, 0.0, 0.0);
  }
}

/* Bonded mode: drop bond (i, j) from both partner rows. */
static void break_bond(int32_t *partners, int32_t i, int32_t j) {
  int32_t *pi = partners + (size_t)i * CD_MAX_PARTNERS,
          *pj = partners + (size_t)j * CD_MAX_PARTNERS;
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
MS_KERNEL_CLONES static void layer_forces_full(cd_sim *s, int layer, cd_layer_sums *sum, double *pw,
                                               bool wf) {
  const cd_neigh *nl = s->nl;
  ptl_state *p = s->p;
  const double *x = p->x, *y = p->y, *z = p->z;
  double *fx = p->fx, *fy = p->fy, *fz = p->fz;
  const bool bonded = s->cfg.cutoff == CD_CUTOFF_BONDED;
  const double r02 = s->cfg.r0 * s->cfg.r0;
  const int32_t nloc = (int32_t)p->nlocal;
  for (int32_t pos = nl->layer_start[layer]; pos < nl->layer_start[layer + 1]; pos++) {
    const int32_t i = nl->sorted[pos];
    const double xi = x[i], yi = y[i], zi = z[i];
    const int mi = p->mat[i];
    double fxi = 0.0, fyi = 0.0, fzi = 0.0;
    int stride;
    int32_t *lst = cd_plain_list(nl, layer, pos, &stride), *img = cd_image_list(nl, layer, pos);
    const int np = nl->nplain[pos], ni = nl->nimg[pos];
    for (int k = 0; k < np + ni; k++) {
      int32_t *entry = k < np ? lst + stride * k : img + 2 * (k - np);
      const int32_t j = *entry & CD_NB_INDEX;
      /* each pair once (cd_impl.h); under MPI a ghost's full row is empty, so an owned–ghost
       * pair is seen only from the owned side */
      if (nl->full && j < nloc && !cd_half_pair(nl, i, j)) continue;
      const double *sh = k < np ? nl->shift[13] : nl->shift[entry[1]];
      const double dx = xi - (x[j] + sh[0]), dy = yi - (y[j] + sh[1]), dz = zi - (z[j] + sh[2]);
      const double r2 = fma(dx, dx, fma(dy, dy, dz * dz));
      const int mj = p->mat[j];
      const cd_pair_table *t = s->pair[mi][mj];
      double fr, e = 0.0;
      if (!bonded) {
        if (r2 >= t->rc2) continue;
        fr = cd_tab_force(t, r2, sum ? &e : NULL);
        if (sum && books_pair(p, i, j)) sum->inside[mi * CD_MAX_MATERIALS + mj]++;
      } else if (*entry & CD_NB_BONDED) {
        if (r2 >= t->rc2) {
          if (!wf) continue; /* diagnostics never change the state */
          /* the bond breaks: its energy leaves the potential and is booked as broken. With the
           * hard truncation the force does work only up to R_c, so the energy lost is E(R_c):
           * evaluate there (r2 itself may lie far beyond the end of the table). */
          double eb;
          cd_tab_force(t, t->rc2, &eb);
          *entry &= ~CD_NB_BONDED;
          break_bond(s->partners, i, j);
          if (sum && books_pair(p, i, j)) {
            sum->broken += eb;
            sum->nbroken++;
          }
          continue;
        }
        fr = cd_tab_force(t, r2, sum ? &e : NULL);
      } else {
        if (r2 >= r02) continue; /* non-bonded: compressive branch only */
        fr = cd_tab_force(t, r2, sum ? &e : NULL);
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

/* Inside a parallel region: the calling thread's share [*ka, *kb) of the layers layer(a) ..
 * layer(b − 1) (layer(k) = list[k], or k without a list), contiguous runs holding ~1/T of
 * their particles each. With the particles in cell order a thread then works on about the
 * particles that the static schedules of the step's other loops give it, so its data stays in
 * its core's caches (with dynamic scheduling problem A's step was 20 % slower on 2 threads:
 * docs/benchmarks.md). */
static void thread_layers(const cd_neigh *nl, const int *list, int a, int b, int *ka, int *kb) {
  int nth = 1, tid = 0;
#if defined(_OPENMP)
  nth = omp_get_num_threads();
  tid = omp_get_thread_num();
#endif
  int64_t total = 0;
  for (int k = a; k < b; k++) {
    const int l = list ? list[k] : k;
    total += nl->layer_start[l + 1] - nl->layer_start[l];
  }
  const int64_t lo = total * tid / nth, hi = total * (tid + 1) / nth;
  int64_t before = 0; /* particles in the layers before k */
  *ka = *kb = b;
  for (int k = a; k < b; k++) {
    if (before >= lo && *ka == b) *ka = k;
    if (before >= hi && *kb == b) *kb = k;
    const int l = list ? list[k] : k;
    before += nl->layer_start[l + 1] - nl->layer_start[l];
  }
  if (tid == nth - 1) *kb = b;
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
  const bool fast = wf && !sums && !pw && s->nmat == 1 && cd_pairs_by_distance(s->cfg.cutoff);
  if (fast && nl->full) { /* no writes into other particles: every layer at once */
#pragma omp parallel if (CD_PAR(p->n))
    {
      int ka, kb;
      thread_layers(nl, NULL, 0, nl->nlayer, &ka, &kb);
      for (int l = ka; l < kb; l++) cd_layer_forces_fit(nl, p, s->pair[0][0], l, s->kick_hdt);
    }
    return;
  }
  for (int ph = 0; ph < nl->nphase; ph++) {
    const int a = nl->phase_start[ph], b = nl->phase_start[ph + 1];
#pragma omp parallel if (nl->colour && CD_PAR(p->n)) /* without colouring: one thread, a..b */
    {
      int ka, kb;
      thread_layers(nl, nl->phase_layer, a, b, &ka, &kb);
      for (int k = ka; k < kb; k++) {
        const int l = nl->phase_layer[k];
        if (fast) layer_forces_fast(nl, p, s->pair[0][0], l);
        else layer_forces_full(s, l, sums ? sums + l : NULL, pw, wf);
      }
    }
  }
}

/* ---- damping ([Davydov] eq. 6) ---- */

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
      const double *sh;
      const int32_t *entry = cd_nb_entry(nl, lst, np, k, &sh);
      const int32_t j = *entry & CD_NB_INDEX;
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
