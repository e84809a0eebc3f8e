/* SPDX-License-Identifier: MIT */
/* cpl.h — the one public header of the coupling library (docs/design.md §6, docs/coupling.md).
 *
 * What lives here:
 *   - fragments: bonds |r_i − r_k| ≤ b·a, connected components by union–find over a cell-list
 *     pair search (or over a neighbour list supplied by the particle code), per-fragment
 *     statistics, the spectrum N(g) and the distributions ejecta experiments report;
 *   - gas drag on fragments (Schiller–Naumann, or pure Stokes for reference tests);
 *   - transport of detached fragments as point masses through a gas given by a callback, to a
 *     detector plane, integrated with SUNDIALS CVODE (BDF: small fragments make the ODE stiff);
 *   - the piston drive built from a tagged grid node's history (displacement-preserving);
 *   - the deck problem `coupled`, which reaches the grid through continuum/cont.h and the
 *     particles through the particle-region interface particles/ptl_region.h.
 *
 * Units are internal (docs/design.md §2): g, cm, 10 µs; velocity km/s, viscosity g/(cm·10 µs),
 * force g·cm/(10 µs)², energy kJ.
 */
#ifndef MSCALE_CPL_H
#define MSCALE_CPL_H

#include "core.h"
#include "eos.h"

/* ========================================================================================== */
/* Union–find (disjoint sets) with path compression and union by size.                        */

typedef struct cpl_uf {
  size_t n;
  size_t *parent; /* parent[i] == i for a root */
  size_t *size;   /* set size, valid at roots */
} cpl_uf;

/* n singletons; uf must be zeroed or previously initialised (storage is reused). */
void cpl_uf_init(cpl_uf *uf, size_t n);
void cpl_uf_free(cpl_uf *uf);
size_t cpl_uf_find(cpl_uf *uf, size_t i);
/* Merge the sets of i and k; true if they were different sets. */
bool cpl_uf_union(cpl_uf *uf, size_t i, size_t k);

/* ========================================================================================== */
/* Fragments                                                                                   */

/* A read-only view of particles in structure-of-arrays form (matches ptl_state). z, vx, vy,
 * vz may be NULL (taken as 0: 2D runs, or positions only). `skip` (optional) excludes
 * particles (e.g. removed or piston particles): they belong to no fragment (id −1). `gid`
 * (optional, distinct values ≥ 0) names particles independently of their storage order: with
 * it, fragments are numbered by their smallest gid (what a distributed run reproduces); without
 * it, by their smallest index. */
typedef struct cpl_particles {
  size_t n;
  const double *x, *y, *z;    /* cm */
  const double *vx, *vy, *vz; /* km/s */
  const double *mass;         /* g */
  const uint8_t *skip;
  const int64_t *gid;
} cpl_particles;

/* Periodic box: axis k is periodic with period period[k] > 0 starting at lo[k]; period 0 =
 * open axis. The bond length must be below half of every period (minimum image). */
typedef struct cpl_box {
  double lo[3];
  double period[3];
} cpl_box;

typedef struct cpl_fragment_opts {
  double bond;    /* b: bond criterion |r_i − r_k| ≤ b·a (> 0) */
  double spacing; /* a: lattice spacing / cluster size, cm (> 0) */
  double rho0;    /* reference density for equivalent diameters, g/cm³ (≤ 0: diameters NaN) */
  cpl_box box;    /* zero = open in every direction */
  /* optional: the particle model's own connectivity (ptl_region_links): particles i and
   * link_nbr[link_start[i] .. link_start[i + 1]) are bonded whatever their distance, and no
   * distance search is made (NULL: the criterion above). Indices into the view. */
  const size_t *link_start;
  const int32_t *link_nbr;
} cpl_fragment_opts;

/* Fragments of one particle configuration. Fragment k is numbered in the order of its smallest
 * particle index, or smallest gid if the view has gids (deterministic, independent of the
 * search order and the thread count).
 * Per-fragment arrays are length n. Centres of mass on periodic axes are computed from
 * positions unwrapped around the fragment's circular mean and wrapped back into the box. */
typedef struct cpl_fragments {
  size_t n_particles;   /* particles in the configuration (length of id) */
  size_t n;             /* fragments */
  int64_t *id;          /* [n_particles] fragment of each particle, −1 for skipped */
  int64_t *first;       /* smallest particle index (gid if the view has gids) in the fragment */
  int64_t *count;       /* particles in the fragment (g) */
  double *mass;         /* g */
  double *diameter;     /* equivalent diameter d = (6 m/(π ρ0))^{1/3}, cm */
  double *cx, *cy, *cz; /* centre of mass, cm */
  double *vx, *vy, *vz; /* centre-of-mass velocity, km/s */
  double *rg;           /* radius of gyration sqrt(Σ m |r − r_c|² / M), cm */
  long n_bonds;         /* bonded pairs found (cell search: each pair once; CSR: list entries) */
  /* scratch kept between calls (no reallocation when the particle count does not grow) */
  size_t cap_particles, cap_fragments, cap_cells;
  cpl_uf uf;
  size_t *cell_of, *cell_start, *cell_items;
  double *work;
  int64_t *key; /* [n_particles] smallest gid per union–find root (numbering by gid) */
  int rounds;   /* cpl_fragments_find_dist: label-exchange rounds of the last search */
} cpl_fragments;

void cpl_fragments_init(cpl_fragments *f);
void cpl_fragments_free(cpl_fragments *f);
/* Find the fragments with the coupling module's own cell-list pair search.
 * MS_ERR_INPUT: non-finite positions/masses, bad options, bond ≥ half a period. */
ms_status cpl_fragments_find(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o);
/* Same with candidate pairs from a neighbour list in CSR form (e.g. the particle code's Verlet
 * lists, any radius ≥ b·a): the candidates of i are nbr[start[i] .. start[i+1]); each bonded
 * pair must appear at least once in either direction. The bond criterion is still checked. */
ms_status cpl_fragments_find_csr(cpl_fragments *f, const cpl_particles *p,
                                 const cpl_fragment_opts *o, const size_t *start,
                                 const int32_t *nbr);
/* Per-fragment statistics from a labelling f->id already filled (used by the two finders;
 * public so that a distributed finder can reuse it). */
void cpl_fragments_stats(cpl_fragments *f, const cpl_particles *p, const cpl_fragment_opts *o);

/* Fragments of particles distributed over MPI ranks (coupling/fragments_dist.c, docs/mpi.md
 * "Fragments on MPI ranks"). Collective. On each rank, p holds [0, n_owned) the owned particles
 * (positions, velocities, masses) and then [n_owned, p->n) ghost copies of other ranks'
 * particles (positions only: their masses and velocities are not read), ghost_owner[j] being
 * the rank that owns particle n_owned + j. p->gid is required: distinct over the owned
 * particles of all ranks, < 2^53; a ghost carries its original's gid and the same skip flag.
 * Every bond between particles of different ranks must be seen by one of them: the ghosts of a
 * rank include every particle within b·a of its owned ones (or the other rank's include its).
 * Result on every rank: f->id[i] of the owned particles (f->n_particles = n_owned) and the
 * whole table, fragments numbered by smallest gid: what cpl_fragments_find gives for the union
 * of the owned particles with their gids (counts and ids exactly, sums to round-off, summed in
 * another order). n_bonds: bonded pairs found on this rank (shared pairs counted twice).
 * MS_ERR_INPUT on every rank if any rank's input is bad (also: a ghost whose original is
 * unknown to or skipped by its owner, duplicate gids). */
ms_status cpl_fragments_find_dist(cpl_fragments *f, const cpl_particles *p, size_t n_owned,
                                  const int32_t *ghost_owner, const cpl_fragment_opts *o,
                                  const ms_ctx *ctx);

/* Spectrum N(g): rows g ascending with count > 0; mass = total mass of those fragments. */
typedef struct cpl_spectrum {
  size_t n;
  int64_t *g, *count;
  double *mass;
} cpl_spectrum;
void cpl_spectrum_build(const cpl_fragments *f, cpl_spectrum *s);
void cpl_spectrum_free(cpl_spectrum *s);

/* Which fragments count as ejecta: centre of mass beyond the plane n·r > plane, optionally
 * leaving out the largest fragment (the bulk of the sample). */
typedef struct cpl_ejecta_sel {
  double normal[3]; /* unit normal pointing away from the sample (default +x) */
  double plane;     /* cm (-INFINITY: no plane) */
  bool exclude_largest;
} cpl_ejecta_sel;
void cpl_ejecta_sel_default(cpl_ejecta_sel *s); /* +x, no plane, exclude the largest */
bool cpl_is_ejecta(const cpl_fragments *f, size_t k, const cpl_ejecta_sel *s);
/* Total ejected mass (for the ejected-mass-vs-time history). */
double cpl_ejected_mass(const cpl_fragments *f, const cpl_ejecta_sel *s);

/* Jets vs spall layers vs debris ([Davydov] §4.2; coupling/ejecta_split.c, docs/coupling.md §9
 * "The split"). The drive axis is +x; the lateral (periodic) axes are cut into bins of width
 * `spacing` (an open lateral axis is one bin).
 *  - full-width fragment: its particles occupy at least `cover` (0.9) of the bins — a plate
 *    across the periodic width, as planar spall leaves it (a torn plate may miss a few bins);
 *  - bulk: the deepest full-width fragment (smallest x), if its deepest particle lies within
 *    `reach` spacings of the deepest particle of all (next to the driven layer): what stays on
 *    the driven layer (the driven particles belong to no fragment; a lone failed particle next
 *    to them is not the bulk, and a plate with a thicker failed zone beneath it has come off:
 *    it is a layer, and there is no bulk);
 *  - level: one spacing above the median over the bins of the front (largest x) of the
 *    foremost full-width fragment, the one whose median is largest (the bulk's own free surface
 *    if nothing spalled; the spacing: a plate's own roughness of a lattice row is not ejecta);
 *    NaN without a full-width fragment;
 *  - detached material: every fragment but the bulk. Each of its particles is a jet when it lies
 *    beyond the level (jets, their tips and the debris they lead: ejecta ahead of the foremost
 *    plate), else a layer particle when its fragment is full-width, else debris (pieces among
 *    or behind the layers). Without a full-width fragment every particle is debris.
 * Fragment counts: n_layer the detached full-width fragments; the other detached fragments count
 * as jets or debris by their centre of mass. Independently of shape, m_fast/n_fast: detached
 * fragments whose centre-of-mass velocity along x exceeds v_fast (the coupled run: (1 +
 * fragments.jet_margin) × the grid's free-surface plateau).
 * ctx NULL or serial: p and f over the same particles. On MPI ranks (collective): p holds the
 * rank's owned particles, f->id for them and the table replicated (cpl_fragments_find_dist);
 * every rank gets the serial classes (masses to round-off; bitwise when one rank owns all). */
typedef struct cpl_split_opts {
  double spacing; /* lateral bin width a, cm */
  cpl_box box;    /* the periodic lateral axes (y, z) */
  double cover;   /* fraction of the bins a full-width fragment occupies */
  double reach;   /* spacings between the deepest particle and the bulk's (2) */
  double v_fast;  /* km/s */
} cpl_split_opts;
/* spacing and box from the fragment search's options, cover 0.9, reach 2 */
void cpl_split_opts_default(cpl_split_opts *o, const cpl_fragment_opts *fo, double v_fast);
typedef struct cpl_ejecta_classes {
  double m_bulk, m_layer, m_jet, m_debris; /* g */
  size_t n_layer, n_jet, n_debris;         /* fragments */
  double m_fast;                           /* g, detached fragments faster than v_fast */
  size_t n_fast;
  double v_fast; /* km/s */
  double level;  /* cm; NaN without a full-width fragment */
  double v_max;  /* fastest detached fragment (centre of mass along x), km/s; 0 if none */
  size_t bulk;   /* fragment index of the bulk (SIZE_MAX if none) */
} cpl_ejecta_classes;
void cpl_ejecta_classify(const cpl_fragments *f, const cpl_particles *p, const cpl_split_opts *o,
                         const ms_ctx *ctx, cpl_ejecta_classes *out);

/* CSV writers (core's units header; `f` may be stdout or an ms_afile's FILE).
 *   spectrum:    g,count,mass
 *   table:       id,count,mass,d,x,y,z,vx,vy,vz,rg        (one row per fragment)
 *   cumulative:  mass,N_ge,M_ge   N(≥m) and the mass in fragments ≥ m, m descending
 *   histogram:   lo,hi,count,mass  logarithmic bins of mass or diameter (nbins > 0)
 *   ejecta:      v,M_ge            cumulative ejected mass with normal velocity ≥ v */
void cpl_write_spectrum(FILE *out, const cpl_fragments *f, const char *title);
void cpl_write_fragment_table(FILE *out, const cpl_fragments *f, const char *title);
void cpl_write_cumulative(FILE *out, const cpl_fragments *f, const char *title);
typedef enum cpl_hist_of { CPL_HIST_MASS = 0, CPL_HIST_DIAMETER } cpl_hist_of;
void cpl_write_histogram(FILE *out, const cpl_fragments *f, cpl_hist_of what, int nbins,
                         const char *title);
void cpl_write_ejecta_velocity(FILE *out, const cpl_fragments *f, const cpl_ejecta_sel *s,
                               const char *title);

/* Particle snapshot with fragment ids (layout in docs/coupling.md §2): /particles/x, v, mass,
 * /particles/fragment (int64, −1 = none) and fragment_id (the same as doubles, for the XDMF
 * sidecar "<path without .h5>.xmf"), attributes time, r0, rho0, period_x.. and lo_x.. of periodic
 * axes. f may be NULL (all ids −1). */
typedef struct cpl_snapshot_info {
  double time;    /* 10 µs */
  double spacing; /* lattice spacing a, cm */
  double rho0;    /* reference density (≤ 0: not written) */
  cpl_box box;
  const char *material; /* the particles' material name (NULL: no material table) */
} cpl_snapshot_info;
ms_status cpl_write_snapshot(const char *path, const cpl_particles *p, const cpl_fragments *f,
                             const cpl_snapshot_info *info);

/* ========================================================================================== */
/* Gas drag (docs/design.md §6; Schiller–Naumann as in the Logos multiphase paper, [Logos])        */

/* Gas state at a point: density g/cm³, velocity km/s, pressure GPa, dynamic viscosity
 * g/(cm·10 µs) (air at 300 K: 1.8e-5 Pa·s = 1.8e-9 internal). */
typedef struct cpl_gas {
  double rho, u[3], p, mu;
} cpl_gas;

typedef enum cpl_drag_law {
  CPL_DRAG_SCHILLER_NAUMANN = 0, /* C_D = 24/Re (1 + 0.15 Re^0.687), Re < 1000; 0.44 above */
  CPL_DRAG_STOKES,               /* C_D = 24/Re at every Re (reference tests, analytic) */
  CPL_DRAG_NONE
} cpl_drag_law;
extern const char *const cpl_drag_law_names[]; /* "schiller_naumann", "stokes", "none", NULL */

/* Drag coefficient C_D(Re) (Re > 0). */
double cpl_drag_coefficient(cpl_drag_law law, double re);
/* Drag factor f = C_D Re / 24 (1 in the Stokes limit; finite at Re = 0). */
double cpl_drag_factor(cpl_drag_law law, double re);
/* Reynolds number Re = ρ_g |v_r| d / μ_g. */
double cpl_reynolds(const cpl_gas *g, double d, const double v[3]);
/* Drag force on a sphere of diameter d moving with v: F = ½ ρ_g C_D (π d²/4) |v_r| v_r with
 * v_r = u_g − v, evaluated as F = 3π μ d f(Re) v_r (finite at v_r → 0). */
void cpl_drag_force(cpl_drag_law law, const cpl_gas *g, double d, const double v[3], double F[3]);
/* Stokes relaxation time τ = ρ_p d²/(18 μ) ([Logos], Logos paper). */
double cpl_stokes_time(double rho_p, double d, double mu);

/* Gas state at position x and time t. Returns false where there is no gas (no drag there). */
typedef bool (*cpl_gas_fn)(void *user, const double x[3], double t, cpl_gas *out);

/* Particle phase (docs/design.md §6: the force is shared over the fragment's particles): add to
 * particle i's force m_i/M times its fragment's drag, the fragment moving with its centre-of-
 * mass velocity with diameter f->diameter (so f must have been found with rho0 > 0). Only the
 * fragments selected by `sel` feel drag (NULL: all). fz may be NULL (2D). Uses f's scratch,
 * allocates nothing. */
void cpl_drag_fragments(cpl_drag_law law, cpl_fragments *f, const cpl_particles *p,
                        const cpl_ejecta_sel *sel, cpl_gas_fn gas, void *gas_user, double t,
                        double *fx, double *fy, double *fz);

/* ========================================================================================== */
/* Transport of fragments to a detector (coupling/transport.c, SUNDIALS CVODE BDF)             */

/* Momentum and energy the gas must receive (two-way transport): over [t0, t1] a fragment's
 * momentum changed by dp and its kinetic energy by de; the gas at x (the fragment's mid-step
 * position) gets −dp and −de. */
typedef void (*cpl_gas_return_fn)(void *user, const double x[3], double t0, double t1,
                                  const double dp[3], double de);

typedef struct cpl_transport_opts {
  cpl_drag_law law;
  double rho_p;                /* fragment material density (diameter from mass), g/cm³ */
  double det_normal[3];        /* detector plane: arrival when normal·x ≥ det_x (normal unit) */
  double det_x;                /* cm */
  double rtol, atol_x, atol_v; /* CVODE tolerances (0: 1e-8, 1e-10 cm, 1e-10 km/s) */
  long max_steps;              /* per fragment and advance call (0: 100000) */
} cpl_transport_opts;
void cpl_transport_opts_default(cpl_transport_opts *o);

typedef enum cpl_frag_state {
  CPL_FLYING = 0,
  CPL_ARRIVED, /* crossed the detector plane */
  CPL_FAILED   /* the integrator failed (reported through cpl_transport_error) */
} cpl_frag_state;

typedef struct cpl_transport cpl_transport;
typedef struct cpl_transport_params {
  const cpl_transport_opts *opts;
  cpl_gas_fn gas; /* the gas the fragments fly through */
  void *gas_user;
} cpl_transport_params;
/* MS_ERR_INPUT (and *out NULL) without options or a gas. */
ms_status cpl_transport_create(const cpl_transport_params *p, cpl_transport **out);
void cpl_transport_destroy(cpl_transport **tr); /* null-safe; sets *tr = NULL */
/* Optional momentum/energy return to the gas. */
void cpl_transport_set_return(cpl_transport *tr, cpl_gas_return_fn fn, void *user);
/* Add a fragment (mass g, position cm, velocity km/s) at time t0; returns its index.
 * A fragment already beyond the plane arrives at t0. */
size_t cpl_transport_add(cpl_transport *tr, double mass, const double x[3], const double v[3],
                         double t0);
/* Add every fragment of f selected by sel (NULL: all); returns how many were added. */
size_t cpl_transport_add_fragments(cpl_transport *tr, const cpl_fragments *f,
                                   const cpl_ejecta_sel *sel, double t0);
/* Advance every flying fragment to t_end (each with its own CVODE history, kept between calls
 * so small windows cost little). MS_ERR_SOLVER if any fragment's integration failed (the
 * others are still advanced). */
ms_status cpl_transport_advance(cpl_transport *tr, double t_end);
const char *cpl_transport_error(const cpl_transport *tr);

typedef struct cpl_flight {
  cpl_frag_state state;
  double mass, diameter;
  double t, x[3], v[3];           /* current (or arrival) time, position, velocity */
  double t_arrival, v_arrival[3]; /* NaN until arrival */
  long steps;                     /* CVODE steps so far */
} cpl_flight;
size_t cpl_transport_count(const cpl_transport *tr);
cpl_flight cpl_transport_get(const cpl_transport *tr, size_t i);
/* CSV: id,mass,d,t_arrival,vx,vy,vz (arrived fragments only, in index order). */
void cpl_write_arrivals(FILE *out, const cpl_transport *tr, const char *title);

/* ========================================================================================== */
/* Piston drive from a tagged grid node (one-way drive, docs/coupling.md)                       */

/* The tagged node's history (t_k, x_k, u_k), k = 0..n−1, as the grid records it, turned into a
 * piston velocity whose integral reproduces the node's displacement exactly: on [t_k, t_k+1]
 *   u(t) = u_k + (u_k+1 − u_k) s + c_k,  s = (t − t_k)/(t_k+1 − t_k),
 *   c_k = (x_k+1 − x_k)/(t_k+1 − t_k) − ½(u_k + u_k+1),
 * so ∫ u dt over any interval [t_k, t_j] equals x_j − x_k. For the conservative cross scheme,
 * which moves nodes with ½(uⁿ + uⁿ⁺¹), c_k vanishes to round-off and u(t) is the piecewise-
 * linear history itself; max |c_k| is reported as a consistency check. Constant beyond the
 * ends (the last velocity). */
typedef struct cpl_piston {
  size_t n;
  double *t, *x, *u, *c;
  double max_correction; /* max |c_k|, km/s */
} cpl_piston;
/* MS_ERR_INPUT if n < 1, t not strictly increasing, or any value not finite. Arrays copied. */
ms_status cpl_piston_build(cpl_piston *p, size_t n, const double *t, const double *x,
                           const double *u);
void cpl_piston_free(cpl_piston *p);
double cpl_piston_velocity(const cpl_piston *p, double t);
/* Displacement x(t) − x(t_0) (exact integral of cpl_piston_velocity). */
double cpl_piston_displacement(const cpl_piston *p, double t);

/* Driving a 2D particle region from a 2D grid's tagged node line (one-way, docs/coupling.md
 * "Driving particles from a 2D node line"): every node of the line is a piston column. Node n
 * of the line, at initial position p_n, sits at the region's transverse coordinate
 * y = y0 + s_n, s_n = p_n · across (and also y0 − s_n with mirror: the grid's symmetry axis at
 * s = 0, e.g. a half-flyer with a wall); its velocity history U_n(t) = (u, v)_n · dir (dir: the
 * grid direction of the region's drive axis +x) becomes that column's piston on the region's
 * x (with lateral, (u, v)_n · across its velocity along y, reversed on the mirrored side)
 * clock τ = t − t0 (records before t0 but the last one are dropped; the region's piston is
 * constant before its first sample). The grid moves nodes with the time-centred velocity, so the
 * piecewise-linear U_n integrates to the node's recorded displacement (as cpl_piston); the
 * region follows it exactly (ptl_region_set_piston_columns). The region needs a model with a
 * piston by columns (the discrete model); MS_ERR_INPUT otherwise or for a line of < 2 records. */
typedef struct cpl_line_drive {
  double t0;        /* grid time of the region's clock 0 */
  double dir[2];    /* unit vector in the grid plane along the region's drive axis */
  double across[2]; /* unit vector in the grid plane along the region's y */
  double y0;        /* the region's y of s = 0 */
  bool mirror;      /* columns at y0 + s and y0 − s */
  bool lateral;     /* also the velocity along `across` (else the columns move along x only) */
} cpl_line_drive;
struct ptl_region;
struct c2d_line_history;
ms_status cpl_drive_from_line(struct ptl_region *r, const struct c2d_line_history *h,
                              const cpl_line_drive *d);

/* The deck problem `coupled2d` (docs/input-coupled.md "coupled2d", docs/coupling.md §5a): a 2D
 * grid (`grid:`, the keys of a grid2d section) runs to its end, then a discrete-model region
 * between its tagged drive line and free-surface line is driven by the line
 * (cpl_drive_from_line) to the same end; particles_NNNN.h5 + particles.xmf and
 * free_surface_columns.csv (grid vs particles per column). Serial. */
typedef struct cpl2d_problem cpl2d_problem;
cpl2d_problem *cpl2d_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                                  dk_errors *e);
ms_status cpl2d_problem_run(ms_ctx *ctx, cpl2d_problem *p);
void cpl2d_problem_destroy(cpl2d_problem **p); /* null-safe; sets *p = NULL */

/* Drive check: free-surface velocity of the particles against the grid's free-surface tag,
 * sampled at the same times. Breakout t_break: the grid's velocity first exceeds 5 % of its
 * maximum; plateaus: means over [t_break + window/2, t_break + window]; t_half_*: first time
 * each reaches half its plateau (so a timing offset shows separately from a level error);
 * min_after: the particles' smallest velocity in the next two windows (a release reflected at
 * the piston comes back as a dip).
 * False if there is no breakout or no sample in the plateau interval. */
typedef struct cpl_fs_check {
  double t_break, plateau_grid, plateau_particles, rel_diff, t_half_grid, t_half_particles;
  double min_after; /* smallest particle velocity over (t_break + window, t_break + 3 window] */
  size_t samples;
} cpl_fs_check;
bool cpl_free_surface_check(size_t n, const double *t, const double *u_grid,
                            const double *u_particles, double window, cpl_fs_check *out);

/* ========================================================================================== */
/* The deck problem `coupled` (docs/input-coupled.md): grid → tagged node U(t) → the particle
 * region's piston → fragments, drag, transport to a detector (one-way drive), or grid and
 * particles in lock-step (two-way).                                                            */
typedef struct cpl_problem cpl_problem;
cpl_problem *cpl_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                              dk_errors *e);
ms_status cpl_problem_run(ms_ctx *ctx, cpl_problem *p);
void cpl_problem_destroy(cpl_problem **p); /* null-safe; sets *p = NULL */
/* What the last cpl_problem_run measured (for tests and summaries). */
typedef struct cpl_run_summary {
  size_t particles;
  long steps;
  cpl_fs_check check;         /* free-surface drive check */
  double energy_balance;      /* (E(t_end) − E(0) − drag work)/piston work, particle phase */
  long failed[3];             /* failed particles: criterion, isolated, degenerate (DM) */
  double piston_work;         /* kJ */
  size_t fragments;           /* at the end of the particle phase */
  double ejected_mass;        /* g (every fragment but the largest) */
  cpl_ejecta_classes classes; /* jets, layers, debris at the end (one-way runs) */
  double u_ref;               /* the grid's free-surface jump-off velocity (first peak) */
  double u_plateau;           /* the grid's free-surface plateau (drive check window) */
  size_t transported, arrived;
  /* two-way coupling: interface impulse and work as the grid received them vs as the particles
   * did (per unit area), their relative mismatch, and the end state */
  double impulse_grid, impulse_particles, work_grid, work_particles;
  double u_interface, u_free_surface; /* at the end of the run, km/s */
  /* drag.gas_return: momentum (along x) and energy the gas received from the fragments
   * (g·km/s, kJ); two-way with `gas:`: how far the gas grid's first node moved (cm) */
  double gas_momentum, gas_energy, gas_shift;
} cpl_run_summary;
const cpl_run_summary *cpl_problem_summary(const cpl_problem *p);

#endif /* MSCALE_CPL_H */
