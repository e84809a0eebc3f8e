/* SPDX-License-Identifier: MIT */
/* grid2d_deck_impl.h — private to the grid2d deck (grid2d_deck.c, grid2d_blocks.c): the arrays a
 * deck mesh fills, and the mesh blocks of `mesh: {blocks: [...]}` (docs/continuum2d.md §8). */
#ifndef MSCALE_GRID2D_DECK_IMPL_H
#define MSCALE_GRID2D_DECK_IMPL_H

#include "cont2d.h"
#include "cont_impl.h"

/* The mesh and initial state the deck builds: (ni+1)(nj+1) nodes, ni·nj zones (cont2d.h). */
typedef struct c2d_deck_mesh {
  long ni, nj;
  double *x, *y, *u, *v; /* nodes */
  double *rho, *en;      /* zones */
  const eos_t **eos;
  int *mid; /* material index in the deck's table */
} c2d_deck_mesh;
void c2d_deck_mesh_alloc(c2d_deck_mesh *m, long ni, long nj);
void c2d_deck_mesh_free(c2d_deck_mesh *m);

/* The section's defaults that a block may override: material (NULL: every block names one),
 * density (NAN: every block gives one), specific energy, node velocity and radial velocity. */
typedef struct c2d_deck_defaults {
  const eos_material *mat;
  double rho, e, vel[2], vrad;
} c2d_deck_defaults;

/* `mesh: {blocks: [...]}`: every block a logical rectangle of nodes [i0, i1] × [j0, j1] of the
 * grid's one (i, j) mesh — a rectangle {x, y, grade, skew} or a polar sector {type: polar, r,
 * theta, grade} — with its own material and state. The blocks must tile [0, ni) × [0, nj) of
 * zones (no overlap, no gap; ni, nj the largest i1, j1), meet at every node they share, leave no
 * zone tangled or inverted, no node at r < 0 in r–z, and not overlap in space (the outer boundary
 * may not cross itself); each violation is a located deck error at the block. On success *out
 * holds the nodes and zone states (node velocities: the first block in deck order holding the
 * node). */
bool c2d_blocks_build(dk_errors *e, dk_doc *doc, const dk_node *blocks, const eos_materials *mats,
                      c2d_geometry geo, const c2d_deck_defaults *def, c2d_deck_mesh *out);

#endif
