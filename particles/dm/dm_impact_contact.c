/* SPDX-License-Identifier: MIT */
/* dm_impact_contact.c — contact between the bodies of the deck problem type `impact`
 * (docs/input-impact.md, "Contact between bodies"): a pairwise penalty between particles of
 * different bodies closer than one spacing h (two lattices touching face to face have their
 * particles one spacing apart),
 *   f_i = k_ij (h − r) (x_i − x_j)/r,  r = |x_i − x_j| < h,
 *   k_ij = c_c h · 2 M_i M_j/(M_i + M_j),
 * M = ρ0 c_L² the P-wave modulus of each particle's material (the wall's stiffness, dm_impact.c,
 * with the harmonic mean of the two sides). A penetration d = h − r carries the contact stress
 * k d/h² = c_c M d/h: c_c = 10 keeps d below 0.1 h up to a contact stress of M (110 GPa for
 * Al, above the 90 GPa of Al on Al at 6.7 km/s). Central and equal and opposite: momentum is
 * conserved exactly; the stored energy Σ k d²/2 equals minus the contact's work up to the time
 * discretisation (reported with the wall's). No friction, no bonding (the bodies' families
 * stay their own: docs/input-impact.md).
 *
 * Neighbours: the hashed cell list of dm_cells.c (dm_cells, cell size 1.5 h, and its walk), rebuilt at
 * every force evaluation into arrays allocated once. Time step: ω Δt ≤ courant, ω = √(2 k_ij/m) the pair's frequency
 * (half the wall's 2·courant: the contact is 10× stiffer, so its ω Δt rather than the
 * material's limits the step, and at 2·courant two elastic boxes colliding at ±0.1 km/s gained
 * 2.3 % of E0 through the penalty's time discretisation, test_dm_impact); a pair closer than 1.5 h approaches by at most 0.1 h per step; and no two
 * particles anywhere approach by more than 0.25 h per step (the velocity spread over all
 * particles), so that a pair is seen at r ≥ 1.25 h before it can touch.
 *
 * Symmetry planes (dm_symmetry.c): a particle also touches the mirror images of the other
 * bodies' particles, found by their current positions (the images of j near x_i are the
 * particles near M x_i): the families' mirror ghosts, fixed by the reference positions, would
 * miss debris that has moved towards a plane (the full-size Piekutowski quarter left the full
 * run at 0.55 µs with them). Forces on the real particles only; the stored energy counts each
 * visit with the particle's fold, so it is the full body's. */
#include "dm_impact_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void dmi_contact_init(dmi_contact *c, const dm_impact *p, size_t n, const uint8_t *imat,
                      const double *M) {
  memset(c, 0, sizeof *c);
  c->on = p->nbodies > 1 && p->contact_stiffness > 0;
  if (!c->on) return;
  c->h = p->h, c->courant = p->courant, c->n = n, c->imat = imat;
  dm_cells_init(&c->cells, n, 3, 1.5 * p->h, p->lo, NULL); /* not periodic: cannot fail */
  c->k = ms_calloc(n ? n : 1, sizeof(double)); /* c_c h M_i; the pair's k is their harmonic mean */
  c->dt_k = INFINITY;
  for (size_t i = 0; i < n; ++i) c->k[i] = p->contact_stiffness * p->h * M[i];
}

void dmi_contact_free(dmi_contact *c) {
  dm_cells_free(&c->cells), free(c->k);
  memset(c, 0, sizeof *c);
}

double dmi_contact_force(dmi_contact *c, const dm_fin *f, double *fext) {
  c->stored = 0, c->in_contact = 0;
  if (!c->on) return INFINITY;
  const dm_state *s = f->m->s;
  const size_t n = f->n; /* the real particles (with symmetry planes: images below) */
  const double *X = s->X, *w = s->w, *u = s->u, *mass = s->mass;
  const dm_sym_planes *pl = &f->sym;
  /* the cell list (dm_cells.c) over the real particles (the mirror ghosts after them are
   * not listed: the images are found by current positions) and the velocity spread */
  c->cells.n = n; /* ≤ the rows it was made for */
  dm_cells_build(&c->cells, X, w);
  double umin[3] = {INFINITY, INFINITY, INFINITY}, umax[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      umin[a] = fmin(umin[a], u[3 * i + a]), umax[a] = fmax(umax[a], u[3 * i + a]);
  for (int p = 0; p < pl->n; ++p) { /* the images' velocities: the normal one negated */
    const int a = pl->axis[p];
    umax[a] = fmax(umax[a], -umin[a]), umin[a] = -umax[a];
  }
  const dm_cells *cl = &c->cells;
  const double h = c->h, r_see = 1.5 * h;
  const unsigned nmask = 1u << pl->n;
  double E = 0, vapp = 0;
  long nc = 0;
#pragma omp parallel for schedule(static) reduction(+ : E, nc) reduction(max : vapp)
  for (size_t i = 0; i < n; ++i) {
    double xi[3], fi[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) xi[a] = X[3 * i + a] + w[3 * i + a];
    int touching = 0;
    /* symmetry planes (dm_symmetry.c): the images M x_j of the particles j under each product
     * M of the planes' reflections near i, found as the particles near M x_i; an image is a
     * particle of its own only where j is off those planes. mask 0: the particles themselves. */
    for (unsigned mask = 0; mask < nmask; ++mask) {
      double xm[3], sg[3] = {1, 1, 1};
      long idx[3];
      bool near = true;
      for (int a = 0; a < 3; ++a) xm[a] = xi[a];
      for (int p = 0; p < pl->n; ++p)
        if (mask >> p & 1u) {
          const int a = pl->axis[p];
          near = near && fabs(xi[a] - pl->pos[p]) < r_see;
          xm[a] = 2.0 * pl->pos[p] - xi[a], sg[a] = -1;
        }
      if (!near) continue;
      dm_cells_of(cl, xm, idx);
      for (int q = 0; q < cl->nnear; ++q) {
        long cn[3];
        dm_cells_near(cl, idx, q, cn);
        for (long j = dm_cells_list(cl, cn); j >= 0; j = cl->next[j]) {
          if (f->imat[j] == f->imat[i] || !dm_cells_holds(cl, j, cn)) continue;
          double d[3], r2 = 0;
          bool own = false; /* j on a plane of the mask: its image is itself */
          for (int p = 0; p < pl->n; ++p)
            own = own || ((mask >> p & 1u) &&
                          X[3 * j + pl->axis[p]] + w[3 * j + pl->axis[p]] == pl->pos[p]);
          if (own) continue;
          for (int a = 0; a < 3; ++a) { /* x_i − M x_j = M (M x_i − x_j) */
            d[a] = sg[a] * (xm[a] - (X[3 * j + a] + w[3 * j + a]));
            r2 += d[a] * d[a];
          }
          if (r2 >= r_see * r_see) continue;
          const double r = sqrt(r2);
          double ur = 0; /* rate of approach: −d(r)/dt */
          for (int a = 0; a < 3; ++a) ur -= d[a] * (u[3 * i + a] - sg[a] * u[3 * j + a]) / r;
          vapp = fmax(vapp, ur);
          if (r >= h) continue;
          const double k = 2.0 * c->k[i] * c->k[(size_t)j] / (c->k[i] + c->k[(size_t)j]);
          const double pen = h - r;
          for (int a = 0; a < 3; ++a) fi[a] += k * pen * d[a] / r;
          /* each pair is visited from both sides; a real particle stands for its orbit of
           * fold particles (dm_symmetry.c), whose visits are all alike */
          E += 0.25 * dm_fin_fold(f, i) * k * pen * pen;
          touching = (int)dm_fin_fold(f, i);
        }
      }
    }
    for (int a = 0; a < 3; ++a) fext[3 * i + a] += fi[a];
    nc += touching;
  }
  c->stored = E, c->in_contact = nc;
  double spread2 = 0;
  for (int a = 0; a < 3; ++a) spread2 += (umax[a] - umin[a]) * (umax[a] - umin[a]);
  /* the stiffness limit of the stiffest pair that may touch: every particle's own k with the
   * lightest mass (computed once, the first time) */
  if (!isfinite(c->dt_k)) {
    double kmax = 0, mmin = INFINITY;
    for (size_t i = 0; i < n; ++i) kmax = fmax(kmax, c->k[i]), mmin = fmin(mmin, mass[i]);
    c->dt_k = c->courant / sqrt(2.0 * kmax / mmin);
  }
  double dt = c->dt_k;
  if (vapp > 0) dt = fmin(dt, 0.1 * h / vapp);
  if (spread2 > 0) dt = fmin(dt, 0.25 * h / sqrt(spread2));
  return dt;
}
