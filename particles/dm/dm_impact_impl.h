/* SPDX-License-Identifier: MIT */
/* dm_impact_impl.h — internals of the deck problem type `impact` (docs/input-impact.md):
 * dm_impact_deck.c reads and checks the deck, dm_impact.c builds the bodies, runs the
 * finite-deformation model against the rigid wall and writes the outputs. */
#ifndef MSCALE_DM_IMPACT_IMPL_H
#define MSCALE_DM_IMPACT_IMPL_H

#include "dm_problem_impl.h"

enum dmi_shape { DMI_CYLINDER = 0, DMI_SPHERE, DMI_BOX };

typedef struct dmi_body {
  int shape, axis;  /* enum dmi_shape; the cylinder's axis (0, 1, 2) */
  double center[3]; /* cylinder: the middle of its axis */
  double radius, length, size[3];
  double velocity[3];   /* initial velocity (km/s) */
  const char *material; /* name (owned by the deck) */
  dm_fin_material mat;  /* eos, yield, G, Y0; sg points to `sg` below */
  dm_sg sg;
  size_t first, count; /* its particles (set by dmi_build) */
} dmi_body;

struct dm_impact {
  double h, horizon; /* spacing (cm), δ/h */
  double lo[3], hi[3];
  size_t nbodies;
  dmi_body *bodies;
  int has_wall, wall_axis, wall_side; /* side +1: bodies on the + side of the plane */
  double wall_pos, wall_stiffness;    /* plane x_axis = pos; penalty coefficient c_w */
  double t_end, courant, cq, cl, hourglass, cond_max;
  double ref_threshold;     /* reference update when a bond stretch exceeds 1 + this (0: off) */
  int ref_keep;             /* 1: the update keeps the families (dm_fin_rebase), 0: rebuilds */
  int ref_family;           /* 1: per-family references (dm_fin_rebase_local), 0: one for all */
  long family_updates;      /* per-family: the families updated so far (log only) */
  double contact_stiffness; /* c_c of the body–body contact (dm_impact_contact.c; 0: off) */
  double contact_distance;  /* d_c / h of the short-range contact inside bodies (dm_contact.c) */
  dm_sym_planes sym;        /* symmetry planes (dm_impact_sym.c; sym.n = 0: none) */
  long energy_every;
  double *particle_times;
  size_t nparticle_times;
  long checkpoint_every;  /* output.checkpoint_every (steps; 0: off) */
  double checkpoint_time; /* output.checkpoint_time (0: off) */
  uint64_t deck_hash;     /* of the resolved deck but t_end and the checkpoint cadence */
  dm_impact_summary sum;
};

/* Contact between bodies (dm_impact_contact.c): a pairwise penalty between particles of
 * different bodies closer than h; a cell list over the domain allocated once. */
typedef struct dmi_contact {
  int on;
  double h, courant;
  size_t n;            /* particles */
  const uint8_t *imat; /* [n] body of each particle (not owned) */
  dm_cells cells;      /* the hashed cell list (dm_cells.c), cells of 1.5 h */
  double *k;           /* [n] c_c h M_i */
  double dt_k;         /* 2 courant / max ω of a pair */
  double stored;       /* Σ k d²/2 at the last evaluation (kJ) */
  long in_contact;     /* particles touching another body */
} dmi_contact;
/* M[i]: the P-wave modulus ρ0 c_L² of particle i's material (GPa). Off (no arrays) with one
 * body or c_c = 0. */
void dmi_contact_init(dmi_contact *c, const dm_impact *p, size_t n, const uint8_t *imat,
                      const double *M);
void dmi_contact_free(dmi_contact *c);
/* Adds the contact forces to fext (not zeroed here) at the current configuration of f; returns
 * the contact's stable time step. */
double dmi_contact_force(dmi_contact *c, const struct dm_fin *f, double *fext);

/* Symmetry planes (dm_impact_sym.c): `impact.symmetry` into p->sym (after the domain and the
 * wall), the bodies' symmetry (after the bodies), and the run's reduction of the full lattice
 * to the + side with the mirror ghosts after it (imat reallocated with their rows). */
void dmi_sym_read(dm_impact *p, dk_doc *doc, const dk_node *sec, dk_errors *e);
void dmi_sym_check(const dm_impact *p, dk_doc *doc, const dk_node *sec, dk_errors *e);
void dmi_sym_reduce(dm_impact *p, dm_state *s, uint8_t **imat);

/* Is x inside body b (strictly)? */
bool dmi_inside(const dmi_body *b, const double x[3]);
/* The lattice sites of body b: the number of them, and their positions into X ([n][3]) when X
 * is not NULL. Cylinder: cross-section (i + ½)h about the axis with r < R, n_L = round(L/h)
 * layers centred on `center`; sphere: (i + ½)h about the centre, r < R; box: round(size/h)
 * sites per axis centred on `center`. */
size_t dmi_body_sites(const dmi_body *b, double h, double *X);
/* The P-wave modulus ρ0 c_L² (GPa) and c_L, c at (ρ0, e0) of a body's material. */
void dmi_body_speeds(const dmi_body *b, double *cL, double *c);

#endif
