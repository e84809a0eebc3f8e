/* SPDX-License-Identifier: MIT */
/* cont2d.h — the 2D Lagrangian grid of the continuum library (issue 24, docs/continuum2d.md):
 * a staggered logical-rectangle quadrilateral mesh in plane (x–y) or axisymmetric (r–z)
 * geometry with the compatible ("energy-conserving") discretisation of [CBSW98].
 *
 * Nodes carry x, y (r, z in r–z) and the velocity; zones carry mass, density, specific internal
 * energy, pressure, sound speed. Every force on a node is a sum of corner forces f_zp (zone z,
 * node p): the zone pressure (and the optional sub-zonal pressure of [CS98]) times the gradient of
 * the zone's (corner's) area, and the edge viscosity of [CSW98]. The node accelerates with the
 * sum of its corner forces; the zone's internal energy changes by −Σ_p f_zp·ū_p dt with the same
 * forces and the time-centred velocity ū = ½(uⁿ + uⁿ⁺¹), so Σ m e + Σ ½ M u² − (boundary work)
 * is conserved to round-off. r–z uses the control-volume form with node masses lumped by the
 * bilinear shape functions (docs/continuum2d.md §1–2).
 *
 * Units as the 1D grid (g, cm, 10 µs; km/s, GPa, kJ/g). In r–z, masses, forces and energies are
 * per radian.
 *
 * Index conventions: ni × nj zones, (ni+1) × (nj+1) nodes; node (i, j) is i + (ni+1) j, zone
 * (i, j) is i + ni j, and zone (i, j) has the nodes (i,j), (i+1,j), (i+1,j+1), (i,j+1), which
 * must be counter-clockwise (positive area).
 */
#ifndef MSCALE_CONT2D_H
#define MSCALE_CONT2D_H

#include "cont.h"

typedef enum c2d_geometry { C2D_XY = 0, C2D_RZ = 1 } c2d_geometry;

/* The four sides of the logical rectangle. */
typedef enum c2d_side { C2D_ILO = 0, C2D_IHI, C2D_JLO, C2D_JHI } c2d_side;

typedef enum c2d_bc_kind {
  C2D_BC_FREE = 0, /* p = 0 outside */
  C2D_BC_WALL,     /* symmetry plane / rigid wall: velocity component along `normal` is 0 */
  C2D_BC_PISTON, /* prescribed node velocity fn(t)·dir (radial: fn(t)·x̂_p, x̂_p = x_p/|x_p| at t=0) */
  C2D_BC_FIXED,   /* both components 0 (e.g. the degenerate centre of a polar mesh) */
  C2D_BC_PRESSURE /* outside pressure fn(t) on the side's edges */
} c2d_bc_kind;

typedef struct c2d_bc {
  c2d_bc_kind kind;
  double normal[2]; /* wall: unit normal (set by c2d_grid_create from the side if both are 0) */
  double dir[2];    /* piston: direction of the velocity (unit vector) */
  bool radial;      /* piston: along x_p/|x_p| instead of dir */
  cont_fn fn;       /* piston speed or outside pressure history (copied) */
} c2d_bc;

typedef struct c2d_setup {
  c2d_geometry geometry;
  size_t ni, nj;
  const double *x, *y;     /* (ni+1)(nj+1) node positions (copied) */
  const double *u, *v;     /* initial node velocities (NULL: 0) */
  const double *rho, *e;   /* ni·nj initial zone density and specific internal energy */
  const eos_t *const *eos; /* ni·nj, one per zone (pure zones; not owned) */
  const int *material;     /* ni·nj material index (NULL: 0) */
  c2d_bc bc[4];            /* per side (c2d_side); corner nodes obey both sides */
  /* Edge viscosity [CSW98]: q = ρ(1−ψ)|Δu|(q2 ζ|Δu| + sqrt(q2² ζ²|Δu|² + q1² c²)),
   * ζ = (q_gamma + 1)/4; ψ the limiter (use_limiter). */
  double q1, q2, q_gamma;
  bool use_limiter;
  /* r–z form: false = control volume (f = P ∂V/∂x, V the per-radian volume; pdV-consistent,
   * momentum in z conserved), true = area-weighted (f = r̃_p P ∂A/∂x; docs/continuum2d.md §2). */
  bool rz_area_weighted;
  double hg_coef;    /* sub-zonal pressure coefficient [CS98], 0 = off */
  double cfl;        /* 0 < cfl < 1 */
  double dv_max;     /* max relative volume change per step */
  double dt_initial; /* 0: 0.1 × the first stability limit */
  double dt_max, dt_min, dt_growth;
} c2d_setup;

/* Defaults: x–y, all sides free, q1 = 0.5, q2 = 1, q_gamma = 5/3, limiter on, hg 0, cfl 0.5,
 * dv_max 0.1, dt_max ∞, dt_min 1e-12, growth 1.1. */
void c2d_setup_defaults(c2d_setup *s);

typedef struct c2d_grid c2d_grid;

/* MS_ERR_INPUT (*out NULL) with a message in err (the zone and the problem) on impossible
 * input: a zone of non-positive area (tangled or inverted), r < 0 in r–z, ρ ≤ 0, an EOS
 * failure. */
ms_status c2d_grid_create(const c2d_setup *s, c2d_grid **out, char *err, size_t errlen);
void c2d_grid_destroy(c2d_grid **g); /* null-safe; sets *g = NULL */
ms_status c2d_grid_step(c2d_grid *g, double dt_limit);
ms_status c2d_grid_run_to(c2d_grid *g, double t_end);
const char *c2d_grid_error(const c2d_grid *g);
double c2d_grid_time(const c2d_grid *g);
long c2d_grid_steps(const c2d_grid *g);
/* Number of threads to use inside a step (OpenMP builds; results do not depend on it). */
void c2d_grid_set_threads(c2d_grid *g, int nthreads);

typedef struct c2d_view {
  size_t ni, nj, nnodes, nzones;
  const double *x, *y, *u, *v, *node_mass;    /* nodes */
  const double *rho, *e, *p, *c, *mass, *vol; /* zones */
  const int *material;
} c2d_view;
c2d_view c2d_grid_view(const c2d_grid *g);

/* Energy budget: internal Σ m e, kinetic Σ ½ M u², work done on the grid by the boundaries
 * since t = 0; internal + kinetic − work is constant to round-off. */
typedef struct c2d_balance {
  double internal, kinetic, work;
} c2d_balance;
c2d_balance c2d_grid_balance(const c2d_grid *g);

/* Hourglass indicator: the mass-weighted RMS over zones of |x₀ − x₁ + x₂ − x₃| / sqrt(A_z)
 * (the quad's hourglass vector, 0 for any parallelogram), and the largest relative corner-density
 * spread max_z (max_c ρ_c − min_c ρ_c)/ρ_z. */
void c2d_grid_hourglass(const c2d_grid *g, double *hg_rms, double *rho_spread);
/* Smallest zone area (planar) now; ≤ 0 means a tangled zone (whose index goes to *zone). */
double c2d_grid_min_area(const c2d_grid *g, size_t *zone);

/* Tagged node lines: the nodes (i, index), i = 0..ni (along_i) or (index, j), j = 0..nj,
 * recorded (t, x, y, u, v of every node) at creation of the tag and after every step (storage
 * grows by doubling). Returns the tag's index. */
size_t c2d_grid_add_tag_line(c2d_grid *g, const char *name, bool along_i, size_t index);
size_t c2d_grid_ntag_lines(const c2d_grid *g);
typedef struct c2d_line_history {
  const char *name;
  size_t nnodes;               /* nodes in the line */
  const size_t *node;          /* their indices */
  size_t n;                    /* records */
  const double *t;             /* n */
  const double *x, *y, *u, *v; /* n × nnodes, row k = record k */
} c2d_line_history;
c2d_line_history c2d_grid_line_history(const c2d_grid *g, size_t tag);

/* ------------------------------------------------------------------------------------------ */
/* Mesh builders (continuum/grid2d_mesh.c): fill x, y of (ni+1)(nj+1) nodes.                   */

/* Rectangle [x0, x1] × [y0, y1], uniform. */
void c2d_mesh_rect(size_t ni, size_t nj, double x0, double x1, double y0, double y1, double *x,
                   double *y);
/* The Saltzman skewed mesh (Dukowicz & Meltz 1992, [Saltzman]) on [0, 1] × [0, 0.1] scaled to
 * ni × nj: x = iΔx + (nj − j)Δy sin(π iΔx), y = jΔy. */
void c2d_mesh_saltzman(size_t ni, size_t nj, double *x, double *y);
/* Polar sector: radii r0 ≤ r ≤ r1 along i (uniform), angles th0 ≤ θ ≤ th1 along j (uniform,
 * counter-clockwise from +x); r0 = 0 gives a degenerate centre (give that side C2D_BC_FIXED). */
void c2d_mesh_polar(size_t ni, size_t nj, double r0, double r1, double th0, double th1, double *x,
                    double *y);

/* ------------------------------------------------------------------------------------------ */
/* The deck problem (`problem: grid2d`, docs/continuum2d.md §8; continuum/grid2d_deck.c)        */

typedef struct c2d_problem c2d_problem;
/* Reads the `grid2d:` section and builds the grid; every problem (including a tangled or
 * inverted mesh and r < 0 in r–z, located at the mesh entry) goes to *e. NULL on error. */
c2d_problem *c2d_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                              dk_errors *e);
/* Runs to time.end writing HDF5 snapshots grid2d_NNNN.h5 and the XDMF temporal collection
 * grid2d.xmf (ParaView opens the run as one series) into ctx->outdir; an inverted zone or EOS
 * failure stops the run with the zone and the step in the log and a last snapshot. */
ms_status c2d_problem_run(ms_ctx *ctx, c2d_problem *p);
void c2d_problem_destroy(c2d_problem **p); /* null-safe; sets *p = NULL */
c2d_grid *c2d_problem_grid(c2d_problem *p);

#endif /* MSCALE_CONT2D_H */
