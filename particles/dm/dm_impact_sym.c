/* SPDX-License-Identifier: MIT */
/* dm_impact_sym.c — symmetry planes of the deck problem type `impact` (docs/input-impact.md,
 * "Symmetry planes"; the model's side: dm_symmetry.c): `symmetry: {x: 0.0, y: 0.0}` runs the
 * part of a problem symmetric about the planes x = 0 and y = 0 on their + side (a quarter of an
 * axisymmetric rod or sphere-on-plate). The deck's checks, located: every body straddles every
 * plane symmetrically (its centre on it; a body on one side only, or off-centre, is an error),
 * no initial velocity through a plane, no wall or plane along a plane's normal axis twice, the
 * plane inside the domain. The run then keeps the lattice sites on the + side (and on the
 * planes) and adds the mirror ghosts. */
#include "dm_impact_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const axis_key[] = {"x", "y", "z"};

void dmi_sym_read(dm_impact *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *S = dk_get(sec, "symmetry");
  p->sym.n = 0;
  if (!S || !dk_expect_map(e, doc, S, "impact.symmetry")) return;
  for (int a = 0; a < 3; ++a) {
    if (!dk_get(S, axis_key[a])) continue;
    double pos = 0;
    if (!dk_read_double(e, doc, S, axis_key[a], MS_DIM_LENGTH, true, 0, -INFINITY, INFINITY, &pos))
      continue;
    if (!(pos > p->lo[a] && pos < p->hi[a]))
      dk_error(e, doc, dk_get(S, axis_key[a]),
               "impact.symmetry.%s: the plane %s = %g is not inside the domain (%g, %g)",
               axis_key[a], axis_key[a], pos, p->lo[a], p->hi[a]);
    if (p->has_wall && p->wall_axis == a)
      dk_error(e, doc, dk_get(S, axis_key[a]),
               "impact.symmetry.%s: the wall's normal is %s too: a symmetry plane must contain "
               "the wall's normal",
               axis_key[a], axis_key[a]);
    p->sym.axis[p->sym.n] = a, p->sym.pos[p->sym.n] = pos, ++p->sym.n;
  }
  if (p->sym.n == 0)
    dk_error(e, doc, S, "impact.symmetry: give planes as {x: position, y: position, z: position}");
  /* the short-range contact (dm_contact.c) lists the real particles only: it would miss the
   * pairs across a plane, and the quarter would leave the full run */
  if (p->sym.n > 0 && p->contact_distance > 0)
    dk_error(e, doc, dk_get(sec, "contact_distance"),
             "impact.contact_distance: the short-range contact (%g spacing) does not take "
             "symmetry planes (impact.symmetry, line %d); drop one of the two",
             p->contact_distance, dk_node_line(S));
}

/* Every body symmetric about every plane: its centre on it (the lattice sites of
 * dmi_body_sites are then the plane's mirror images of each other), no velocity through it. */
void dmi_sym_check(const dm_impact *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *L = dk_get(sec, "bodies"), *S = dk_get(sec, "symmetry");
  for (size_t i = 0; i < p->nbodies; ++i) {
    const dmi_body *b = &p->bodies[i];
    const dk_node *it = dk_seq_at(L, i);
    for (int j = 0; j < p->sym.n; ++j) {
      const int a = p->sym.axis[j];
      const double pos = p->sym.pos[j], off = b->center[a] - pos;
      if (b->velocity[a] != 0.0)
        dk_error(e, doc, dk_get(it, "velocity") ? dk_get(it, "velocity") : it,
                 "impact.bodies[%zu].velocity: a component %g km/s through the symmetry plane "
                 "%s = %g (impact.symmetry, line %d): the mirrored body would move the other way",
                 i, b->velocity[a], axis_key[a], pos, dk_node_line(S));
      if (fabs(off) <= 1e-9 * p->h) continue;
      /* its half-extent along a: the farthest site from the centre, plus half a spacing */
      const size_t n = dmi_body_sites(b, p->h, NULL);
      double *X = ms_calloc(3 * (n ? n : 1), sizeof(double)), ext = 0;
      dmi_body_sites(b, p->h, X);
      for (size_t k = 0; k < n; ++k) ext = fmax(ext, fabs(X[3 * k + a] - b->center[a]));
      free(X);
      if (fabs(off) >= ext + 0.5 * p->h)
        dk_error(e, doc, dk_get(it, "center") ? dk_get(it, "center") : it,
                 "impact.bodies[%zu]: lies on one side of the symmetry plane %s = %g (centre "
                 "%s = %g): it must straddle the plane, centred on it (a body off the plane "
                 "needs its mirror image as a second body, i.e. no symmetry plane)",
                 i, axis_key[a], pos, axis_key[a], b->center[a]);
      else
        dk_error(e, doc, dk_get(it, "center") ? dk_get(it, "center") : it,
                 "impact.bodies[%zu]: the symmetry plane %s = %g passes through the body off its "
                 "symmetry (its centre is at %s = %g, %g spacings away): centre the body on the "
                 "plane",
                 i, axis_key[a], pos, axis_key[a], b->center[a], off / p->h);
    }
  }
}

/* The sites on the + side of every plane (or on it), compacted in place; the bodies' ranges
 * renumbered; then the mirror ghosts after them (dm_sym_ghosts) and their materials in *imat. */
void dmi_sym_reduce(dm_impact *p, dm_state *s, uint8_t **imat) {
  size_t nr = 0;
  for (size_t b = 0; b < p->nbodies; ++b) {
    dmi_body *bd = &p->bodies[b];
    const size_t first = nr;
    for (size_t i = bd->first; i < bd->first + bd->count; ++i) {
      bool keep = true;
      for (int j = 0; j < p->sym.n; ++j) {
        const double x = s->X[3 * i + p->sym.axis[j]];
        keep = keep && (x > p->sym.pos[j] || dm_sym_on_plane(x, p->sym.pos[j], p->h));
      }
      if (!keep) continue;
      memmove(&s->X[3 * nr], &s->X[3 * i], 3 * sizeof(double));
      memmove(&s->u[3 * nr], &s->u[3 * i], 3 * sizeof(double));
      s->mass[nr] = s->mass[i], s->vol[nr] = s->vol[i], s->K[nr] = s->K[i], s->G[nr] = s->G[i];
      s->bc[nr] = s->bc[i], (*imat)[nr] = (*imat)[i];
      ++nr;
    }
    bd->first = first, bd->count = nr - first;
  }
  dm_sym_ghosts(s, nr, &p->sym, p->horizon * p->h, p->h);
  uint8_t *im = ms_calloc(s->n, 1);
  memcpy(im, *imat, nr);
  for (size_t g = nr; g < s->n; ++g) im[g] = im[s->partner[g]];
  free(*imat);
  *imat = im;
}
