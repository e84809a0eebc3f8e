/* SPDX-License-Identifier: MIT */
/* cont.h — the one public header of the continuum library: the 1D Lagrangian "cross" scheme
 * (docs/design.md §4) in planar, cylindrical and spherical geometry.
 *
 * Two levels of API:
 *   - the deck problem (`problem: continuum`): cont_problem_read / _run / _free, used by the
 *     front end; it writes profiles, histories, the x–t data and the energy balance;
 *   - the grid itself (cont_grid_*), used by tests and by the coupling module: build a grid from
 *     a cont_setup, step it (with an optional externally supplied force or velocity at any node,
 *     for two-way coupling), read tagged-node histories, sample the gas state at a position.
 *
 * Scheme (docs/continuum.md): staggered grid, node x and u, cell mass, ρ, e, p; quadratic +
 * linear artificial viscosity in compression only; a predictor–corrector step whose corrector
 * uses the time-centred nodal velocity ū = ½(uⁿ + uⁿ⁺¹) both to move the nodes and in the work
 * term, so Σ(m e + ½ m u²) − boundary work is conserved to round-off. Positions, velocities and
 * cell states are all known at the same time levels tⁿ, so histories need no re-centring.
 *
 * Units are internal (g, cm, 10 µs; km/s, GPa, kJ/g). In cylindrical/spherical geometry masses,
 * forces and energies are per radian / per steradian (face "area" r or r²).
 */
#ifndef MSCALE_CONT_H
#define MSCALE_CONT_H

#include "core.h"
#include "eos.h"

/* ------------------------------------------------------------------------------------------ */
/* Time functions (boundary histories)                                                         */

typedef enum cont_fn_kind {
  CONT_FN_CONST = 0, /* value */
  CONT_FN_TABLE,     /* piecewise linear in (t[k], v[k]), constant beyond the ends */
  CONT_FN_TRAPEZOID, /* 0 → value over rise, hold, back to 0 over fall (square/triangle pulses) */
  CONT_FN_EXP_DECAY  /* value · exp(−(t − t0)/tau) for t ≥ t0, linear rise over `rise` */
} cont_fn_kind;

typedef struct cont_fn {
  cont_fn_kind kind;
  double value;                     /* constant or pulse amplitude */
  double t0, rise, hold, fall, tau; /* pulse start and shape */
  size_t n;                         /* table length */
  double *t, *v;                    /* table (owned by the cont_fn; cont_fn_free) */
} cont_fn;

double cont_fn_eval(const cont_fn *f, double t);
void cont_fn_free(cont_fn *f);
/* Deep copy (tables duplicated). */
void cont_fn_copy(cont_fn *dst, const cont_fn *src);

/* ------------------------------------------------------------------------------------------ */
/* Grid set-up                                                                                 */

typedef enum cont_geometry {
  CONT_PLANAR = 0,
  CONT_CYLINDRICAL = 1,
  CONT_SPHERICAL = 2
} cont_geometry;

typedef enum cont_bc_kind {
  CONT_BC_WALL = 0, /* u = 0 */
  CONT_BC_FREE,     /* p = 0 outside */
  CONT_BC_PISTON,   /* prescribed node velocity u(t) */
  CONT_BC_PRESSURE  /* prescribed outside pressure p(t) */
} cont_bc_kind;

typedef struct cont_bc {
  cont_bc_kind kind;
  cont_fn fn; /* velocity (piston) or pressure history; unused for wall/free */
} cont_bc;

/* Grading: cell sizes form a geometric series, smallest at the named end(s) of the layer. */
typedef enum cont_grade_side {
  CONT_GRADE_NONE = 0,
  CONT_GRADE_LEFT,
  CONT_GRADE_RIGHT,
  CONT_GRADE_BOTH
} cont_grade_side;

typedef struct cont_layer_spec {
  const char *name; /* label for messages and outputs (not owned) */
  const eos_t *eos; /* not owned */
  int material;     /* index in the materials list (written to outputs) */
  double thickness; /* cm (> 0) */
  double rho, u, e; /* initial density, velocity, specific internal energy */
  bool e_from_p;    /* if true, e is solved from the initial pressure p below */
  double p;
  long ncells;        /* > 0 */
  double grade_ratio; /* ratio of neighbouring cell sizes (≥ 1), 1 = uniform */
  cont_grade_side grade_side;
} cont_layer_spec;

typedef struct cont_tag_spec {
  const char *name; /* not owned; used in file names and dataset paths */
  size_t node;      /* node index, 0 .. ncells_total */
} cont_tag_spec;

typedef struct cont_setup {
  cont_geometry geometry;
  double x_left; /* position of node 0 (≥ 0 for curvilinear geometry; 0 means the axis/centre) */
  size_t nlayers;
  const cont_layer_spec *layers;
  cont_bc left, right;   /* copied (tables duplicated) by cont_grid_create */
  double q_quad, q_lin;  /* viscosity q = ρ|Δu|(q_quad|Δu| + q_lin c) for Δu < 0 */
  double cfl;            /* safety factor, 0 < cfl < 1 */
  double dt_initial;     /* first step (0: cfl-based × 0.1) */
  double dt_max, dt_min; /* dt_min: below it the run is declared unstable */
  double dt_growth;      /* max ratio of consecutive steps (> 1) */
  size_t ntags;
  const cont_tag_spec *tags;
} cont_setup;

/* Defaults: planar, x_left 0, walls, q_quad 1, q_lin 0.2, cfl 0.5, dt_max ∞, dt_min 1e-12,
 * growth 1.1, no layers, no tags. */
void cont_setup_defaults(cont_setup *s);
/* Solve p(ρ, e) = p for e (bracketing); false if no root is found. */
bool cont_energy_from_pressure(const eos_t *eos, double rho, double p, double *e);
/* Index of the node where layer `layer` starts (= total cells of the layers before it;
 * layer = nlayers gives the last node). */
size_t cont_setup_layer_first_node(const cont_setup *s, size_t layer);

/* ------------------------------------------------------------------------------------------ */
/* The grid                                                                                    */

typedef struct cont_grid cont_grid;

/* Build the grid. MS_ERR_INPUT (and *out NULL) with a message in err on impossible input. */
ms_status cont_grid_create(const cont_setup *s, cont_grid **out, char *err, size_t errlen);
void cont_grid_destroy(cont_grid **g); /* null-safe; sets *g = NULL */

/* One step. The step size is the stability constraint, limited by dt_limit (pass INFINITY for
 * none; the run loop uses it to land exactly on output times). MS_ERR_UNSTABLE on NaN/Inf,
 * negative volume, EOS failure or dt < dt_min; cont_grid_error() then names the step, time,
 * cell and quantity. */
ms_status cont_grid_step(cont_grid *g, double dt_limit);
/* Step until time t_end (exactly); stops early on error. */
ms_status cont_grid_run_to(cont_grid *g, double t_end);
const char *cont_grid_error(const cont_grid *g);

double cont_grid_time(const cont_grid *g);
long cont_grid_steps(const cont_grid *g);
double cont_grid_last_dt(const cont_grid *g);
size_t cont_grid_ncells(const cont_grid *g);
/* Bytes the grid holds per cell (check-time memory estimates). */
size_t cont_grid_bytes_per_cell(void);
cont_geometry cont_grid_geometry(const cont_grid *g);

/* Current state (arrays owned by the grid, valid until the next step). */
typedef struct cont_view {
  size_t ncells, nnodes;
  const double *x, *u;                      /* nodes */
  const double *rho, *e, *p, *q, *c, *mass; /* cells */
  const int *material;                      /* cells: material index */
  const int *layer;                         /* cells: layer index */
} cont_view;
cont_view cont_grid_view(const cont_grid *g);

/* Energy budget: internal Σ m e, kinetic Σ ½ m u², work done on the grid by boundaries and
 * external forces since t = 0 (so internal + kinetic − work is constant), momentum Σ m u and
 * impulse delivered (planar: momentum − impulse is constant). */
typedef struct cont_balance {
  double internal, kinetic, work, momentum, impulse;
  double source_energy, source_momentum; /* the part of work/impulse from cell sources */
} cont_balance;
cont_balance cont_grid_balance(const cont_grid *g);

/* Two-way coupling hooks (persist until changed).
 * Extra force on a node, as a pressure acting on the node's face area (planar: GPa = force per
 * cm²): positive pushes towards +x. */
void cont_grid_set_node_force(cont_grid *g, size_t node, double traction);
/* Prescribe a node's velocity (u = NAN releases it). The force the constraint needed in the
 * last step (same units as above) is cont_grid_node_reaction. */
void cont_grid_set_node_velocity(cont_grid *g, size_t node, double u);
double cont_grid_node_reaction(const cont_grid *g, size_t node);
/* Cell source (two-way ejecta transport, docs/coupling.md §4): add momentum dp and total energy
 * de to cell `cell` now, in the grid's mass units (planar: per cm² of face area, like the
 * traction). Conservative by construction: both nodes of the cell get the same velocity change
 * dp/(M_left + M_right) (nodal masses), which the momentum sum Σ M u receives exactly; what de
 * leaves after the nodes' kinetic-energy change goes into the cell's internal energy (the
 * dissipated part of the drag becomes heat); p and c are re-evaluated. Both are booked in
 * cont_balance.work/impulse (and source_energy/source_momentum), so internal + kinetic − work
 * stays constant. A prescribed (wall/piston/coupled) node keeps its velocity: its share goes to
 * the boundary as a reaction in the next step. MS_ERR_UNSTABLE (cont_grid_error names it) if
 * the cell's energy would turn negative or the EOS fails; the grid is then unchanged. */
ms_status cont_grid_add_cell_source(cont_grid *g, size_t cell, double dp, double de);

/* Tagged nodes: x, u of the node and p, ρ of the cells on its left/right (NAN where there is no
 * cell), recorded at t = 0 and after every step (same time level for all). */
typedef struct cont_history {
  const char *name;
  size_t node;
  size_t n;
  const double *t, *x, *u, *p_left, *rho_left, *p_right, *rho_right;
} cont_history;
size_t cont_grid_ntags(const cont_grid *g);
/* Add a tag after creation (its history starts now); returns its index. */
size_t cont_grid_add_tag(cont_grid *g, const char *name, size_t node);
cont_history cont_grid_history(const cont_grid *g, size_t tag);
/* The history at any time t in [t_0, t_last] (clamped outside): u piecewise linear between
 * rows, x its exact integral (x_k + (t − t_k)(u_k + u(t))/2), so x(t) and u(t) stay consistent
 * for a particle piston that samples them at its own time steps. */
void cont_history_at(const cont_history *h, double t, double *x, double *u);
/* Node nearest to position x (current positions). */
size_t cont_grid_nearest_node(const cont_grid *g, double x);

/* Gas/material state at position x (linear interpolation of u between the cell's nodes).
 * Returns false if x is outside the grid. */
typedef struct cont_sample {
  double rho, u, p, e, c;
  int material, layer;
  size_t cell;
} cont_sample;
bool cont_grid_sample(const cont_grid *g, double x, cont_sample *out);

/* ------------------------------------------------------------------------------------------ */
/* The deck problem (`problem: continuum`, docs/input-continuum.md)                             */

typedef struct cont_problem cont_problem;
cont_problem *cont_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                                dk_errors *e);
ms_status cont_problem_run(ms_ctx *ctx, cont_problem *p);
void cont_problem_destroy(cont_problem **p); /* null-safe; sets *p = NULL */
/* The grid of a problem that has been read (built by cont_problem_read); for tests/coupling. */
cont_grid *cont_problem_grid(cont_problem *p);
/* Run with a caller stepping alongside (two-way coupling): the problem's own loop — output
 * times, x–t frames, histories, balance log, instability guard — calls before(user, g) ahead of
 * every grid step and after(user, g) once it succeeded; a status other than MS_OK from either
 * ends the run with that status (outputs so far are kept, as on instability). Hooks may be
 * NULL. end > 0 replaces the section's time.end. */
typedef struct cont_step_hooks {
  ms_status (*before)(void *user, cont_grid *g);
  ms_status (*after)(void *user, cont_grid *g);
  void *user;
  double end;
} cont_step_hooks;
ms_status cont_problem_run_hooked(ms_ctx *ctx, cont_problem *p, const cont_step_hooks *hooks);

#endif /* MSCALE_CONT_H */
