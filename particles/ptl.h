/* ptl.h — the one public header of the particle library (DESIGN.md §5).
 *
 * Two particle models share this library:
 *   - cluster dynamics (cd_*): pair potentials from an EOS cold curve, paper 002;
 *   - the Hamiltonian discrete model (dm_*): least-squares deformation gradient, paper 000;
 * and the symplectic RKN integrators (rkn_*) both use.
 */
#ifndef MSCALE_PTL_H
#define MSCALE_PTL_H

#include "core.h"
#include "eos.h"

/* === Cluster dynamics (cd_) === */

/* Cluster dynamics (paper 002, DESIGN.md §5.1): particles ("clusters") of size r0 on a close-packed
 * lattice interact through pair potentials built from an EOS cold curve; docs/particles-cd.md.
 * Units are the internal ones (g, cm, 10 µs: velocity km/s, energy kJ... see DESIGN.md §2).
 *
 * Generic particle storage (ptl_) comes first: structure-of-arrays, sized once. */

enum {
  PTL_DRIVEN = 1u,  /* moves with a prescribed velocity (piston); forces on it are only recorded */
  PTL_SURFACE = 2u, /* tagged at set-up as the free-surface layer (free-surface velocity) */
  PTL_REMOVED = 4u  /* left the run (not integrated, not listed) */
};

typedef struct ptl_state {
  size_t n, cap;        /* particles in use / allocated (never grows during a run) */
  size_t nlocal;        /* owned particles [0, nlocal); under MPI the ghost copies of other
                         * ranks' particles follow in [nlocal, n) (docs/mpi.md). Serial: n */
  int dim;              /* 3 (fcc) or 2 (triangular, plane strain: z == 0, vz == 0) */
  double *x, *y, *z;    /* positions, cm */
  double *vx, *vy, *vz; /* velocities, km/s */
  double *fx, *fy, *fz; /* forces, g·cm/(10 µs)² */
  double *mass;         /* g */
  int64_t *gid;         /* global id (creation order) */
  uint8_t *mat;         /* material index (< CD_MAX_MATERIALS) */
  uint8_t *flags;       /* PTL_* bits */
} ptl_state;

ptl_state *ptl_state_create(size_t cap, int dim);
void ptl_state_free(ptl_state *s);
/* Append one particle at rest; returns its index, or (size_t)-1 if the capacity is exhausted. */
size_t ptl_state_add(ptl_state *s, double x, double y, double z, double mass, int mat);
/* Bytes held by the arrays above (for the memory-per-particle figure). */
size_t ptl_state_bytes(const ptl_state *s);
/* Grow the capacity to at least cap (contents kept). */
void ptl_state_reserve(ptl_state *s, size_t cap);
/* Keep only the particles [lo, hi) (moved to the front, order kept): a rank's share of a
 * particle set every rank generated identically (docs/mpi.md). */
void ptl_state_keep_range(ptl_state *s, size_t lo, size_t hi);

/* splitmix64 (the benchmark's generator): u_k in [0,1) is the k-th output (k from 0) of the
 * generator started from `seed` (bench/cd_lammps, /work/shared/bench/cd_lammps.md). */
double ptl_splitmix64_uniform(uint64_t seed, uint64_t k);

/* ---- lattices ---- */
typedef enum cd_lattice { CD_LATTICE_FCC = 0, CD_LATTICE_TRI2D } cd_lattice;

/* Cluster mass and reference volume per particle for nearest-neighbour distance r0:
 * fcc m = ρ0 r0³/√2; 2D triangular m = ρ0 (√3/2) r0² h, h = the plane-strain thickness. */
double cd_cluster_volume(cd_lattice lat, double r0, double thickness);
/* Memory per particle of a cluster-dynamics run, for the check-time estimate (core.h
 * ms_mem_*): 300 B of state, pair-table share, outputs and set-up lists, plus 8 B per
 * neighbour-list entry within `reach` r0 (R_c + skin). Calibrated on inputs/cd-piston-al.yaml
 * (fcc, reach 1.3: 404 B): 20 376 -> 203 688 particles raised the peak RSS by 350 B per particle,
 * of which cd_sim_bytes counts 225 B. */
double cd_particle_bytes(cd_lattice lat, double reach);

/* fcc lattice of nx×ny×nz cubic cells (cubic constant a = √2 r0) with the benchmark's order:
 * basis atom fastest, then cell x, y, z; basis (0,0,0), (½,½,0), (½,0,½), (0,½,½); positions
 * (cell + basis + shift)·a + origin. Appends to s with the given mass/material. */
size_t cd_lattice_fcc(ptl_state *s, int nx, int ny, int nz, const double shift[3],
                      const double origin[3], double r0, double mass, int mat);
/* Triangular lattice (2D) of nx×ny rectangular cells (r0 × √3 r0, 2 particles each). */
size_t cd_lattice_tri(ptl_state *s, int nx, int ny, const double shift[2], const double origin[2],
                      double r0, double mass, int mat);

/* Voronoi polycrystal in the box [lo, hi) (lattice_poly.c): `ngrains` grains with uniformly
 * random lattice orientations; sites closer than dmin·r0 across a grain boundary are removed.
 * `periodic` (NULL: none) marks axes along which the grains and the overlap test wrap
 * (minimum image), for a polycrystal filling a periodic box. `keep` (optional) filters sites.
 * Returns the number of sites; *xyz ([n][3]) and *grain ([n]) are malloc'd;
 * *porosity = 1 − n·V_site/V_box. */
typedef bool (*cd_site_filter)(void *user, const double x[3]);
size_t cd_polycrystal(int dim, double r0, double thickness, const double lo[3], const double hi[3],
                      const bool periodic[3], int ngrains, uint64_t seed, double dmin,
                      cd_site_filter keep, void *user, double **xyz, int32_t **grain,
                      double *porosity);

/* ---- pair potentials (DESIGN.md §5.1) ---- */
/* fcc:  E(r) = (√2 ρ0 r0³/12) ε_x((r0/r)³),  f(r) = −dE/dr = (√2/4) r² P_x((r0/r)³);
 * 2D:   E(r) = (m/3) ε_x((r0/r)²),           f(r) = r h P_x((r0/r)²)/√3 (docs/particles-cd.md).
 * Tabulated once as a cubic Hermite interpolant of E in s = r² (values and exact slopes
 * dE/ds = −f/(2r) at the nodes); the force used is F/r = −2 dE/ds of the SAME cubic, so the
 * force is the exact derivative of the energy that is reported. */
/* The forces-only fast path's fit of F/r (cd_potential.c, docs/particles-cd.md): segments of s
 * are the values sharing bits(s) >> CD_FIT_SHIFT (8 per octave of s), 16 consecutive ones. */
enum { CD_FIT_MAXDEG = 9, CD_FIT_SHIFT = 49, CD_FIT_NSEG = 16 };

typedef struct cd_pair_table {
  int nint;          /* intervals in s */
  double s_lo, h, inv_h;
  double rc, rc2;    /* cutoff (hard truncation) */
  double r0;         /* nearest-neighbour distance at rest */
  double e_rc;       /* E(rc): energy a pair takes with it when it leaves the cutoff */
  double *fcoef;     /* [nint][4]: F/r = f0 + t(f1 + t f2), t in [0,1) (4th slot padding) */
  double *ecoef;     /* [nint][4]: E = e0 + t(e1 + t(e2 + t e3)) */
  /* F/r on fit_slo <= s < rc2 as Σ_p fit_coef[p][k mod 16] (s − c_k)^p, c_k the centre of the
   * segment k = bits(s) >> CD_FIT_SHIFT; fit_ok when it matches the cold curve to 1e-12 and
   * the table to 1e-9 of max|F/r| (else the kernels use the table only) */
  bool fit_ok;
  int fit_deg;
  double fit_slo;
  double fit_coef[CD_FIT_MAXDEG + 1][CD_FIT_NSEG];
} cd_pair_table;

/* Reference (untabulated) pair energy and force from an EOS cold curve. */
double cd_pair_energy_exact(const eos_t *eos, cd_lattice lat, double r0, double thickness,
                            double r);
double cd_pair_force_exact(const eos_t *eos, cd_lattice lat, double r0, double thickness,
                           double r);
/* Build the table for materials a and b (b == a: the material's own potential; otherwise the
 * mixing rule E_ab = ½(E_a + E_b), whose attractive branch (E' < 0, r > r0) is scaled by
 * `attraction` in [0, 1] so an interface can be weaker than either bulk). r_min: inner end
 * (clamped to the EOS's cold-curve range). nint: intervals (0: default 4096).
 * MS_ERR_INPUT if the cold curve is missing or not finite on [r_min, rc]. */
ms_status cd_pair_table_build(cd_pair_table *t, const eos_t *a, const eos_t *b, cd_lattice lat,
                              double r0, double thickness, double rc, double r_min,
                              double attraction, int nint);
void cd_pair_table_free(cd_pair_table *t);
double cd_pair_table_energy(const cd_pair_table *t, double r); /* 0 beyond rc */
double cd_pair_table_force(const cd_pair_table *t, double r);  /* scalar f, + = repulsive */
/* F/r of the fit at s (fit_ok tables; meaningful for fit_slo <= s < rc2): the fast kernel's
 * arithmetic, lane for lane */
double cd_pair_fit_eval(const cd_pair_table *t, double s);

/* ---- the simulation ---- */
enum { CD_MAX_MATERIALS = 8 };

typedef enum cd_bc { CD_BC_FREE = 0, CD_BC_PERIODIC, CD_BC_WALL } cd_bc;

/* Cutoff treatment (DESIGN.md §5.1, "known trap"):
 *  CD_CUTOFF_PLAIN  — every pair closer than R_c interacts (the benchmark's model);
 *  CD_CUTOFF_BONDED — interaction partners fixed at set-up (pairs closer than R_c then);
 *                     a bond farther than R_c breaks for good; non-bonded pairs (and broken
 *                     bonds) only repel, through the compressive branch r < r0. */
typedef enum cd_cutoff_mode { CD_CUTOFF_PLAIN = 0, CD_CUTOFF_BONDED } cd_cutoff_mode;

/* Time integrator (docs/particles-cd.md): velocity Verlet (fused kick–drift, the default and
 * the benchmark's), or one of the symplectic RKN schemes of rkn_ (DESIGN.md §5.2) — position
 * Verlet = RKN "verlet", SIA4, RKN4, RKN4 conjugate; damping is a separate step after any. */
typedef enum cd_integrator {
  CD_INT_VELOCITY_VERLET = 0,
  CD_INT_POSITION_VERLET,
  CD_INT_SIA4,
  CD_INT_RKN4,
  CD_INT_RKN4_CONJ,
  CD_INT_COUNT
} cd_integrator;
/* NULL-terminated deck names indexed by cd_integrator (for dk_read_enum). */
extern const char *const cd_integrator_names[];

typedef struct cd_box {
  double lo[3], hi[3]; /* periodic period / wall positions (unused for free axes) */
  cd_bc bc[3];
} cd_box;

typedef struct cd_config {
  double r0;               /* nearest-neighbour distance (cluster size a) */
  double skin;             /* Verlet skin (list radius = max R_c + skin) */
  double dt;               /* time step */
  cd_cutoff_mode cutoff;
  double damping_gamma;    /* Γ of eq. 6 (paper 002), 1/time; 0 = off */
  int sort_every;          /* renumber particles into cell order every k-th list build (0: 8) */
  cd_lattice lattice;      /* for the reference volume per particle (per-particle stress) */
  double thickness;        /* 2D plane-strain thickness h (unused in 3D) */
  cd_integrator integrator; /* default (0): velocity Verlet */
} cd_config;

/* Velocity history of the piston: piecewise linear u(t) through (t_k, u_k), constant beyond
 * the ends; direction is a unit vector. */
typedef struct cd_history {
  size_t n;
  double *t, *u;
} cd_history;
double cd_history_eval(const cd_history *h, double t);
/* ∫_{t0}^{t1} u dt of the piecewise-linear history (exact). */
double cd_history_integral(const cd_history *h, double t0, double t1);
/* Reads a CSV/whitespace table with columns t, u (internal units; `si` converts s, m/s).
 * Errors: fewer than 1 row, t not strictly increasing (a jump in time). */
ms_status cd_history_read(cd_history *h, const char *path, bool si, dk_errors *e);
void cd_history_free(cd_history *h);

typedef struct cd_energy {
  double kinetic;      /* ½ m v² of integrated (non-driven) particles */
  double potential;    /* Σ pair energies of pairs inside their cutoff */
  double dissipated;   /* energy removed by the relative-velocity damping */
  double broken;       /* energy carried away by pairs/bonds leaving the cutoff */
  double piston_work;  /* work done on the particles by driven (piston) particles */
  double wall_work;    /* 0 (specular walls do no work); kept for the balance's form */
  double total;        /* kinetic + potential + dissipated + broken − piston_work */
  double momentum[3];  /* Σ m v of integrated particles */
} cd_energy;

typedef struct cd_neigh cd_neigh; /* link cells + Verlet lists (particles/neighbour.c) */

/* ---- CD domain partition (particles/cd_partition.c, docs/mpi.md) ---- */
typedef enum cd_partition_method {
  CD_PART_SLAB = 0,
  CD_PART_METIS,
  CD_PART_AUTO
} cd_partition_method;
typedef struct cd_partition_stats {
  cd_partition_method method; /* of the map (CD_PART_AUTO: the one it chose) */
  double imbalance; /* max part weight / mean part weight (weights as given) */
  double load;      /* max over parts of (part weight + 0.25 × weight of its halo cells, the
                     * ghosts) / mean part weight: the cost model CD_PART_AUTO minimises */
  double rejected_load; /* CD_PART_AUTO: the load of the map it did not take; else NaN */
  long edge_cut;    /* edges of the 26-neighbour coarse-cell graph joining different parts */
  long halo_cells;  /* Σ over parts of the cells not in the part but adjacent to it */
} cd_partition_stats;
/* Assign each of the ncell[0]*ncell[1]*ncell[2] coarse cells (index ix + ncell[0]*(iy +
 * ncell[1]*iz)) to one of nparts parts balancing Σ weight (particle counts); periodic axes wrap in
 * the graph. CD_PART_SLAB: the cells in plane-major order along slab_axis (then the lower, then
 * the higher other axis) cut into contiguous runs by cumulative weight (a cut may fall inside a
 * plane; each part within one cell weight of the mean). CD_PART_METIS: METIS_PartGraphKway on
 * the 26-neighbour graph, vertex weight = weight+1, fixed seed, so every rank calling it with
 * the same input gets the same owner map (no broadcast needed). CD_PART_AUTO: both, keeping the
 * one of lower `load` (stats->method says which; slabs on ties). nparts == 1 → all zero. stats
 * may be NULL. Pass particle counts scaled up (e.g. ×64, as cd_par.c does) so that empty cells
 * weigh little against particles. METIS with nparts ≥ cells gives cell c to part c. Vertex
 * weights summing above 2^30 are scaled down for METIS's 32-bit idx_t. MS_ERR_INPUT: bad
 * arguments, negative weights, more than 2^31/26 cells; MS_ERR_INTERNAL: METIS failed. */
ms_status cd_partition_cells(const int ncell[3], const bool periodic[3], const int64_t *weight,
                             int nparts, cd_partition_method method, int slab_axis,
                             int32_t *owner, cd_partition_stats *stats);
/* The figures of a given owner map (stats->method is meaningless). MS_ERR_INPUT: bad
 * arguments or an owner outside [0, nparts). */
ms_status cd_partition_evaluate(const int ncell[3], const bool periodic[3], const int64_t *weight,
                                int nparts, const int32_t *owner, cd_partition_stats *stats);
/* Per-part figures of an owner map: halo[p] = cells outside part p adjacent to it (its ghost
 * cells), neighbours[p] = distinct other parts adjacent to p (its messages per exchange).
 * Arrays of nparts entries; either may be NULL. */
void cd_partition_halo(const int ncell[3], const bool periodic[3], const int32_t *owner,
                       int nparts, long *halo, int *neighbours);

/* Cluster dynamics on MPI ranks (particles/cd_par.c, docs/mpi.md): the box is cut into coarse
 * cells (>= r_list wide) owned by ranks (cd_partition_cells, recomputed when the load is
 * uneven); each rank integrates the particles of its cells and holds ghost copies of the other
 * ranks' particles in adjacent cells. */
typedef struct cd_mpi_config {
  cd_partition_method partition;
  double rebalance_threshold; /* repartition when max/mean owned particles exceeds it (0: never) */
  int rebalance_interval;     /* list builds between two repartition attempts (>= 1) */
  bool replicated;            /* every rank passes the whole particle set (each keeps what its
                               * cells own); false: disjoint shares (migrated to their owners) */
  const int32_t *owner;       /* restart on the same rank count: the checkpoint's coarse-cell
                               * owner map (used instead of a new partition if the grid has
                               * owner_cells cells), so every rank gets its old particles back */
  size_t owner_cells;
} cd_mpi_config;
typedef struct cd_mpi_stats {
  int ranks;
  int ncell[3];                  /* coarse cells */
  size_t owned, ghosts;          /* this rank, at the last list build */
  size_t global, max_owned, total_ghosts;
  double imbalance;              /* max owned / mean owned, at the last list build */
  cd_partition_stats partition;  /* of the owner map in use (weights = particle counts) */
  long partitions;               /* partitions computed (1 = the initial one) */
  long rebalances;               /* repartitions because of imbalance */
  long rebalance_step;           /* step of the last rebalance, imbalance before and after */
  double rebalance_before, rebalance_after;
  double exchange_s;             /* wall time in ghost refreshes and migrations, this rank */
  double exchanged_doubles;      /* received, this rank */
  long lost_bonds;               /* bonded mode: partners not found on the rank at a migration */
} cd_mpi_stats;

typedef struct cd_sim {
  ptl_state *p;                 /* owned */
  cd_box box;
  cd_config cfg;
  int nmat;
  cd_pair_table *pair[CD_MAX_MATERIALS][CD_MAX_MATERIALS]; /* [a][b] == [b][a], owned */
  double rc_max;
  cd_neigh *nl;
  double t;
  long step;
  /* piston */
  cd_history piston;            /* u(t) of every PTL_DRIVEN particle */
  double piston_dir[3];
  size_t n_driven;
  int32_t *driven;              /* indices of driven particles */
  /* balance accumulators */
  double dissipated, piston_work, broken_bonded;
  long n_inside0[CD_MAX_MATERIALS][CD_MAX_MATERIALS]; /* pairs inside R_c at start (plain) */
  bool have_inside0;
  double *scratch;              /* 3N, damping velocity increments (NULL if no damping) */
  int32_t *partners;            /* bonded mode: [N][CD_MAX_PARTNERS] (−1 = none/broken) */
  long n_broken_bonds;
  bool forces_zeroed;           /* the step zeroed f in its drift loop */
  double disp_bound;            /* Σ Δt·max|v| since the last build (cheap rebuild pre-check) */
  double vmax_last;             /* max|v| of the last Verlet step (when to take the extents) */
  struct cd_layer_sums *sums;   /* per-layer accumulators of the kernels */
  int sums_cap;
  double *pw;                   /* [N][6] per-particle virials (allocated by diagnostics) */
  /* RKN integrators (cfg.integrator != velocity Verlet): stage buffers, driven particles'
   * positions at the start of the step, the piston force at each stage */
  struct rkn_integrator *rkn;
  double rkn_reach[2];          /* stage excursion bound: |q_l − r^n| ≤ Δt c0 max|v| + Δt² c1 max|a| */
  double *driven_x0;            /* [n_driven][3] */
  double stage_force[3];
  int stage;
  double wall_time_force, wall_time_neigh;
  long last_build_step;         /* step of the last list build (full or half lists: cd_sim.c) */
  double kick_hdt;              /* > 0: the fit kernel also kicks v += kick_hdt f/m (cd_sim.c) */
  struct cd_dd *dd;             /* MPI decomposition (cd_par.c); NULL on one rank */
  cd_mpi_config mpi;
  bool mpi_on;                  /* cd_sim_set_mpi was called */
  char err[512];                /* what the instability guard found (cd_sim_error) */
} cd_sim;

enum { CD_MAX_PARTNERS = 16 };

/* Takes ownership of p. Tables are set afterwards with cd_sim_set_pair; cd_sim_init then
 * builds the lists (and, in bonded mode, the partner lists) and the first forces. */
cd_sim *cd_sim_create(ptl_state *p, const cd_box *box, const cd_config *cfg, int nmat);
/* Takes ownership of t (heap allocated); a != b sets both [a][b] and [b][a]. */
void cd_sim_set_pair(cd_sim *s, int a, int b, cd_pair_table *t);
/* Piston: every PTL_DRIVEN particle moves with u(t)·dir (history copied). */
void cd_sim_set_piston(cd_sim *s, const cd_history *h, const double dir[3]);
ms_status cd_sim_init(cd_sim *s);
void cd_sim_free(cd_sim *s);
/* Affine deformation x_a ← lo_a + λ_a (x_a − lo_a) of positions and box (homogeneous
 * compression/tension); rebuilds the lists and recomputes forces. Bonds are kept. */
ms_status cd_sim_affine(cd_sim *s, const double lambda[3]);
/* Relaxation before the run (docs/particles-cd.md "Polycrystals and the relaxation stage"),
 * after cd_sim_init: `time` of damped dynamics with the piston at rest (relative-velocity
 * damping with Γ = damping_gamma, and/or a quench that stops each particle moving against its
 * force), and with `box` every
 * box_every steps (0: 10) an affine strain of each non-wall axis by
 * λ_a − 1 = (box_every Δt/τ)·P_aa/modulus, at most max_strain (0: 1e-3) per rescale, toward
 * zero mean normal stress P_aa over the sample (Berendsen-like; a periodic axis's period
 * changes with it). Then every velocity is zeroed, in bonded mode with `rebond` (or `plain`)
 * the partners are formed anew from the relaxed packing, and time, step and the balance accumulators
 * restart from zero. Deterministic; collective under MPI. MS_ERR_INPUT: time < 0, or `box`
 * without modulus, tau > 0. */
typedef struct cd_relax_config {
  double time;          /* duration of the damped dynamics */
  double damping_gamma; /* Γ of eq. 6 during it, 1/time (0: none) */
  bool quench;          /* zero v_i whenever v_i·f_i < 0 */
  bool box;             /* rescale the box toward zero mean normal stress */
  int box_every;
  double tau, modulus;  /* box relaxation time; stiffness (GPa), e.g. ρ0 c0² */
  double max_strain;
  bool rebond;
  bool plain;           /* bonded runs: relax with the plain cutoff (every pair inside R_c
                         * attracts, so grain-boundary gaps close), then form the bonds anew */
} cd_relax_config;
typedef struct cd_relax_result {
  long steps;
  double stress0[6], stress[6]; /* mean stress of the sample before / after (xx yy zz xy yz zx) */
  double volume0, volume;       /* sample volume before / after: periods of periodic axes,
                                 * extent + one site spacing along the others */
  double mass;                  /* of the sample (ρ = mass/volume) */
  double lambda[3];             /* total stretch of each axis */
  double energy;                /* kinetic + potential before − potential after */
  double dissipated;            /* of which the damping and the quench removed */
  double quenched;
  long broken_bonds;            /* bonds broken during the relaxation */
} cd_relax_result;
ms_status cd_sim_relax(cd_sim *s, const cd_relax_config *cfg, cd_relax_result *out);
/* Before cd_sim_init: distribute over the MPI ranks (no effect on one rank). Each rank passes
 * to cd_sim_create either the whole particle set (cfg->replicated: generated or read
 * identically on every rank) or its own share (disjoint shares whose union is the system, any
 * split, e.g. ptl_state_keep_range); cd_sim_init partitions the coarse cells and keeps (resp.
 * migrates) every particle on the owner of its cell. From then on p holds
 * the owned particles in [0, nlocal) and ghosts in [nlocal, n) (positions current after every
 * force evaluation); diagnostics (energy, virial, profile, free-surface velocity, snapshot)
 * are collective and return global values on every rank. */
void cd_sim_set_mpi(cd_sim *s, const cd_mpi_config *cfg);
/* Decomposition figures (NULL when not distributed). */
const cd_mpi_stats *cd_sim_mpi_stats(const cd_sim *s);
/* True when this rank owns the coarse cell containing x (periodic axes wrapped): whether a
 * particle read from a file belongs here. Serial: always true. */
bool cd_sim_owns_position(const cd_sim *s, const double x[3]);
/* Bring the ghosts' positions and velocities up to date (collective; no-op serially). */
void cd_sim_refresh_ghosts(cd_sim *s);
/* The rank owning each ghost: owner[j] for particle nlocal + j, j < n − nlocal (for the
 * distributed fragment finder, cpl_fragments_find_dist). Serial: nothing to fill. */
void cd_sim_ghost_owners(const cd_sim *s, int32_t *owner);
/* One step of cfg.integrator (plus the damping sub-step if Γ > 0). Every CD_GUARD_EVERY steps
 * the instability guard (cd_sim_guard) runs: MS_ERR_UNSTABLE, with cd_sim_error saying why
 * (on the rank that found it; every rank stops together).
 * After an RKN step p->f holds the forces of the scheme's last stage, not of x^{n+1}. */
ms_status cd_sim_step(cd_sim *s);
enum { CD_GUARD_EVERY = 10 };
/* Instability guard (docs/reliability.md §5): a non-finite position or velocity, a particle
 * moving more than half the nearest-neighbour distance in one step (the step cannot resolve
 * its collisions, e.g. a piston faster than the lattice can follow), or a particle beyond a
 * wall (it crossed it within one step). MS_ERR_UNSTABLE with a message naming the step, time,
 * particle and quantity (cd_sim_error), else MS_OK. */
ms_status cd_sim_guard(cd_sim *s);
const char *cd_sim_error(const cd_sim *s);
/* Energies and momentum at the current state (one extra pass over the pairs). */
void cd_sim_energy(cd_sim *s, cd_energy *out);
/* Compression-positive virial stress of the whole system (the pressure tensor)
 * P_ab = (1/V)[Σ m v_a v_b + ½ Σ_pairs f(r) r_a r_b / r]; V given by the caller.
 * s[0..5] = xx, yy, zz, xy, yz, zx. */
void cd_sim_virial(cd_sim *s, double volume, double stress[6]);
/* Per-particle virial W_i = ½ Σ_j f r_a r_b / r (energy units), [N][6] (xx yy zz xy yz zx).
 * The per-particle stress of snapshots is (W_i + m v_a v_b)/V0 with V0 the reference volume
 * per site (cd_cluster_volume): compression-positive, referred to the undeformed volume. */
void cd_sim_particle_virial(cd_sim *s, double *w);
/* Von Mises intensity σ_u of a symmetric tensor (DESIGN.md §5.1, eq. 4 corrected). */
double cd_von_mises(const double s[6]);
/* Mean velocity of the PTL_SURFACE particles along `axis` (NaN if none). */
double cd_free_surface_velocity(const cd_sim *s, int axis);
/* Neighbour-list statistics: rebuilds so far, pairs listed, bytes held. */
long cd_sim_rebuilds(const cd_sim *s);
size_t cd_sim_pairs(const cd_sim *s);
size_t cd_sim_bytes(const cd_sim *s);

/* Binned 1D profile along `axis` over [lo, hi) with nbin bins of cross-section `area`
 * (cm² in 3D; in 2D: width × thickness). Per bin: count, density, mean velocity (3), and the
 * compression-positive stress (xx, yy, zz, xy, yz, zx, with the kinetic part relative to the
 * bin's mean velocity) and σ_u. out has nbin rows of CD_PROFILE_NCOL doubles. */
enum { CD_PROFILE_NCOL = 13 };
extern const char *const cd_profile_columns[CD_PROFILE_NCOL];
void cd_profile(cd_sim *s, int axis, double lo, double hi, int nbin, double area, double *out);
/* Shock front along `axis` from a cd_profile table: scanning occupied bins upward, the first position where the
 * bin-mean velocity along axis falls below frac·u_ref (linear interpolation between bin
 * centres); NaN if not found. */
double cd_front_position(const double *profile, int nbin, int axis, double u_ref, double frac);
/* HDF5 particle snapshot (positions, velocities, material, gid, per-particle σ_u and
 * pressure) plus an XDMF sidecar "<path without .h5>.xmf". */
ms_status cd_write_snapshot(cd_sim *s, const char *path);

/* ---- checkpoint / restart (particles/cd_checkpoint.c, docs/mpi.md) ---- */
/* Rebuild the lists with renumbering and recompute the forces: what a restart does, so the run
 * calls it right before each checkpoint and both continue bit for bit. */
ms_status cd_sim_refresh(cd_sim *s);
/* Group /cd of a checkpoint file made by ms_ckpt_create: particles (each rank its own segment),
 * bonded partners as gids, the balance accumulators, time, step, list-build count. Collective. */
ms_status cd_checkpoint_write(ms_h5 *h, const ms_ctx *ctx, const cd_sim *s);
typedef struct cd_restart cd_restart;
/* Reads group /cd (bonded: with partners); NULL with messages in e if it is missing, damaged
 * or truncated. */
cd_restart *cd_restart_read(ms_h5r *h, const ms_ctx *ctx, int dim, bool bonded, dk_errors *e);
/* The checkpoint's particles, for cd_sim_create (ownership passes to the caller). */
ptl_state *cd_restart_take_particles(cd_restart *r);
double cd_restart_time(const cd_restart *r);
long cd_restart_step(const cd_restart *r);
/* cd_sim_init for a sim made from cd_restart_take_particles (tables and piston set): restores
 * partners, accumulators, time and step, then builds lists and forces as cd_sim_refresh. */
ms_status cd_sim_init_restart(cd_sim *s, const cd_restart *r, dk_errors *e);
void cd_restart_free(cd_restart *r);

/* ---- deck problem `cluster_dynamics` (docs/input-cd.md) ---- */
typedef struct cd_problem cd_problem;
cd_problem *cd_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                            dk_errors *e);
ms_status cd_problem_run(ms_ctx *ctx, cd_problem *p);
void cd_problem_free(cd_problem *p);


/* === Symplectic RKN integrators (rkn_) === */

/* Explicit symplectic Runge–Kutta–Nyström schemes for r'' = a(r) (DESIGN.md §5.2, paper 000 §2).
 * An m-stage scheme is given by α, γ (β_l = γ_l(1 − α_l), a_lk = γ_k(α_l − α_k) for k < l):
 *   q_l     = r + Δt α_l u + Δt² Σ_{k<l} a_lk a(q_k)
 *   r^{n+1} = r + Δt u + Δt² Σ β_l a(q_l),   u^{n+1} = u + Δt Σ γ_l a(q_l).
 * The integrator works on flat arrays of `ndof` doubles, so any particle model (DM, cluster
 * dynamics) can use it through an acceleration callback. */
typedef enum rkn_kind {
  RKN_VERLET = 0, /* 1 stage, order 2 (position Verlet) */
  RKN_SIA4,       /* 3 stages, order 4 (Candy–Rozmus) */
  RKN_RKN4,       /* 3 stages, order 4 */
  RKN_RKN4_CONJ,  /* 3 stages, order 4 (every √3 of RKN4 with the opposite sign) */
  RKN_KIND_COUNT
} rkn_kind;

typedef struct rkn_scheme {
  rkn_kind kind;
  const char *name; /* deck name: verlet, sia4, rkn4, rkn4_conjugate */
  int stages;       /* force evaluations per step */
  int order;
  double alpha[3], gamma[3];
} rkn_scheme;

/* NULL-terminated deck names indexed by rkn_kind (for dk_read_enum). */
extern const char *const rkn_scheme_names[];
const rkn_scheme *rkn_scheme_get(rkn_kind kind);

/* Acceleration a = F/m of configuration q at (stage) time t; `acc` has ndof entries. */
typedef ms_status (*rkn_accel_fn)(void *user, double t, const double *q, double *acc);
/* Optional constraint hook: overwrite prescribed degrees of freedom with their values at time t,
 * in the stage positions q (u == NULL) and at the end of the step (q = r^{n+1}, u = u^{n+1}). */
typedef void (*rkn_constrain_fn)(void *user, double t, double *q, double *u);

typedef struct rkn_integrator rkn_integrator;
rkn_integrator *rkn_create(rkn_kind kind, size_t ndof);
void rkn_destroy(rkn_integrator *ig);
const rkn_scheme *rkn_integrator_scheme(const rkn_integrator *ig);
/* Dofs of the next steps, at most the ndof of rkn_create (MPI: the owned particle count changes
 * at each migration; 0 is allowed: a rank may own nothing). MS_ERR_INPUT beyond it. */
ms_status rkn_resize(rkn_integrator *ig, size_t ndof);
/* One step t -> t + dt of (r, u) in place. No allocation. Loops are OpenMP-parallel over dofs
 * with a static schedule (results do not depend on the thread count). */
ms_status rkn_step(rkn_integrator *ig, double t, double dt, double *r, double *u,
                   rkn_accel_fn accel, rkn_constrain_fn constrain, void *user);
/* Structure-of-arrays form, for models that keep one array per component (cluster dynamics:
 * x, y, z). Create the integrator with ndof = ncomp·n; r[c], u[c] (c < ncomp) hold n entries.
 * The stage positions q_l are formed IN PLACE in r (the integrator keeps r^n), so a force
 * routine that reads the model's own position arrays sees q_l; `accel` fills acc[c][i] with
 * a(q_l). `constrain` (optional) overwrites prescribed entries of r at stage time t (end ==
 * false) and of r and u at the end of the step (end == true). No allocation. */
enum { RKN_MAX_COMPONENTS = 3 };
typedef ms_status (*rkn_accel_soa_fn)(void *user, double t, double *const acc[]);
typedef void (*rkn_constrain_soa_fn)(void *user, double t, bool end);
ms_status rkn_step_soa(rkn_integrator *ig, double t, double dt, int ncomp, double *const r[],
                       double *const u[], rkn_accel_soa_fn accel, rkn_constrain_soa_fn constrain,
                       void *user);
/* Stability limit of a scheme: the largest ω·Δt for which r'' = −ω²r stays bounded (|tr M| < 2
 * for the step's 2×2 amplification matrix M), found numerically; Verlet: 2. */
double rkn_stability_limit(rkn_kind kind);

/* === Hamiltonian discrete model (dm_) === */

/* The least-squares deformation-gradient particle model of paper 000 §1 with the exact pairwise
 * Hamiltonian force (DESIGN.md §5.2; docs/particles-dm.md). Small-strain linear elasticity:
 *   A_i = Σ_k ξ_ik⊗ξ_ik,  C_i = Σ_k (w_k − w_i)⊗(A_i⁻¹ξ_ik),  E_i = sym C_i,
 *   σ_i = λ_i tr(E_i) I + 2G_i E_i,  H = Σ m_i|u_i|²/2 + Σ V_i σ_i:E_i/2,
 *   F_i = −∂H/∂w_i = Σ_{k∈N_i} (P_i + P_k) ξ_ik,  P_i = V_i σ_i A_i⁻¹   (families are symmetric).
 * dim = 1: a chain along x (σ_xx = (K + 4G/3) E_xx, = E for ν = 0); dim = 2: plane strain in x–y;
 * dim = 3: full 3D. Vectors are always stored with 3 components (unused ones stay 0). */

typedef enum dm_bc {
  DM_FREE = 0,      /* moves under the model's forces */
  DM_FIXED = 1,     /* u = 0, w held at its initial value (fixed particle layers) */
  DM_PRESCRIBED = 2, /* w(t) given by the model's prescribed-displacement callback */
  DM_MIRROR = 3      /* ghost: w = S w_partner (S = diag(msign)), a mirror image across a wall
                      * (S = −I: clamped wall, u = 0 on it) or a symmetry plane (S flips the
                      * normal component only); excluded from energies and momenta */
} dm_bc;

/* Particle data (structure of arrays; X, w, u are [n][3]). Units: cm, km/s, g, cm³, GPa. */
typedef struct dm_state {
  size_t n;
  int dim;
  double *X;       /* reference positions */
  double *w;       /* displacements */
  double *u;       /* velocities (momentum p = m u) */
  double *mass;    /* m_i */
  double *vol;     /* V_i = m_i / ρ_i⁰ */
  double *K, *G;   /* bulk and shear moduli per particle (material interfaces) */
  uint8_t *bc;     /* dm_bc */
  uint32_t *partner; /* DM_MIRROR: the real particle mirrored */
  int8_t *msign;     /* DM_MIRROR: [n][3] sign per component */
} dm_state;

void dm_state_alloc(dm_state *s, size_t n, int dim); /* zeroed arrays */
void dm_state_free(dm_state *s);

typedef struct dm_options {
  double horizon;  /* δ_r (cm): N_i = {k ≠ i : |X_k − X_i| < δ_r} (periodic images included) */
  double box[3];   /* periodic length per axis, 0 = not periodic (X must lie in [0, box)) */
  double cond_max; /* largest accepted condition number of A_i (0 → default 1e8) */
  double hourglass; /* stabilisation coefficient c_s (0 = off; docs/particles-dm.md) */
} dm_options;

/* Prescribed displacement: fill w (3 components) of particle i at time t. */
typedef void (*dm_prescribe_fn)(void *user, size_t i, const double X[3], double t, double w[3]);

typedef struct dm_model {
  dm_state *s; /* not owned */
  dm_options opt;
  /* Families in CSR form: the bonds of i are nbr[start[i] .. start[i+1]), sorted by index;
   * img[b] codes the periodic image of the neighbour (13 = same image). */
  size_t *start;
  uint32_t *nbr;
  uint8_t *img;
  double shift[27][3];
  size_t nbonds;
  double *Ainv;  /* [n][9] A_i⁻¹ (zero outside the dim×dim block) */
  double *cond;  /* [n] condition number of A_i */
  double *kappa; /* [n] hourglass stiffness c_s G_i V_i / tr A_i (0 when off) */
  /* Work and output arrays, filled by dm_forces: */
  double *C;     /* [n][9] displacement gradient C_i (row a: ∂w_a, column b: ∂/∂X_b) */
  double *sigma; /* [n][9] stress σ_i (symmetric; GPa) */
  double *Q;     /* [n][9] V_i σ_i A_i⁻¹ − κ_i C_i */
  double *energy; /* [n] V_i U_i (+ hourglass energy), kJ */
  dm_prescribe_fn prescribe;
  void *prescribe_user;
} dm_model;

/* Builds the families with a cell list and precomputes A_i⁻¹. Singular or ill-conditioned A_i
 * (too few or coplanar/collinear neighbours) are reported through ctx (each with the particle's
 * position, up to 20) and make this return NULL with *status = MS_ERR_INPUT; *first_bad (if
 * not NULL) is the first such particle. Other errors: bad options (MS_ERR_INPUT). */
dm_model *dm_create(dm_state *s, const dm_options *opt, const ms_ctx *ctx, ms_status *status,
                    size_t *first_bad);
void dm_destroy(dm_model *m);

/* Forces F = −∂H/∂w at displacement w (both [n][3]); fills m->C, sigma, Q, energy.
 * OpenMP-parallel over particles; each particle sums its own bonds in a fixed order, so the
 * result is independent of the thread count. */
void dm_forces(dm_model *m, const double *w, double *F);
/* Elastic (+ hourglass) energy Σ V_i U_i of displacement w (kJ) over all particles except
 * mirror ghosts; also fills m->C, sigma. Without ghosts this is exactly the H whose gradient
 * dm_forces returns. */
double dm_potential_energy(dm_model *m, const double *w);
double dm_kinetic_energy(const dm_state *s); /* Σ m|u|²/2 (mirror ghosts excluded) */
/* Total linear momentum Σ m u and the reference angular momentum J = Σ X × m u, which the
 * small-strain Hamiltonian conserves exactly (docs/particles-dm.md). */
void dm_momenta(const dm_state *s, double P[3], double J[3]);
/* Cauchy stress Σ_i = σ_i (I + C_iᵀ) / det(I + C_i) (paper 000 §1), [n][9], from the last
 * dm_forces / dm_potential_energy call. */
void dm_cauchy_stress(const dm_model *m, double *S);
/* Zero-energy-mode measure: returns sqrt(Σ_i Σ_k |z_ik|²) with z_ik the least-squares residual
 * w_k − w_i − C_i ξ_ik (0 for any linear field; = sqrt(Σ|w_k − w_i|²) for a pure hourglass
 * pattern) and sets *dw_norm = sqrt(Σ_i Σ_k |w_k − w_i|²). Sums over free particles only. Uses m->C of the
 * last force/energy call. */
double dm_hourglass_norm(const dm_model *m, const double *w, double *dw_norm);

/* The RKN acceleration callback over the flat array q = w[n][3] (user = dm_model *):
 * a = F/m for free particles, 0 for fixed/prescribed ones and for components ≥ dim. */
ms_status dm_accel(void *user, double t, const double *q, double *acc);
/* The RKN constraint callback: sets prescribed particles' w (and u by central difference when
 * u != NULL) from m->prescribe, then mirror ghosts from their partners. A mirror ghost layer
 * must be two horizons thick so that the ghosts next to the wall have complete families. */
void dm_constrain(void *user, double t, double *q, double *u);

/* ---- the discrete model on MPI ranks (particles/dm_par.c, docs/mpi.md) ----
 * Set-up is replicated (every rank builds the global model); the bond graph is partitioned with
 * METIS (mirror ghosts stay with their partners), each rank integrates its owned particles plus
 * ghost copies of the off-rank family members, whose w and Q arrive before every force pass.
 * Owned values are bitwise independent of the rank count. */
typedef struct dm_dist dm_dist;
typedef struct dm_dist_stats {
  long edge_cut, edge_cut_slab;         /* cut bonds: METIS, plain x slabs (comparison) */
  double imbalance, imbalance_slab;     /* max rank weight / mean (weight = bonds + 1) */
  size_t owned, ghosts;                 /* this rank */
  size_t max_owned, max_ghosts, total_ghosts, bonds;
  double partition_s;
  double exchange_s, exchanged_doubles; /* this rank: wall time in ghost exchanges, doubles received */
} dm_dist_stats;
typedef struct dm_dist_diag {
  double kinetic, potential; /* kJ, non-mirror particles */
  double hourglass, dw_norm; /* as dm_hourglass_norm (sums per particle, then in global order) */
} dm_dist_diag;
/* The global model's prescribe callback must be set before this (it is copied). Collective. */
dm_dist *dm_dist_create(dm_model *global, const ms_ctx *ctx, ms_status *status);
void dm_dist_free(dm_dist *d);
dm_state *dm_dist_state(dm_dist *d); /* local particles: owned [0, owned), then ghosts */
dm_model *dm_dist_model(dm_dist *d);
size_t dm_dist_owned(const dm_dist *d);
const dm_dist_stats *dm_dist_get_stats(const dm_dist *d);
long dm_dist_local_index(const dm_dist *d, size_t global); /* owned here: local index, else -1 */
/* RKN callbacks over the local arrays (user = dm_dist *); the constraint hook also brings the
 * ghosts' w up to date, which the acceleration relies on (rkn_step calls it first). */
ms_status dm_dist_accel(void *user, double t, const double *q, double *acc);
void dm_dist_constrain(void *user, double t, double *q, double *u);
/* Energies and the hourglass indicator of the local state, summed in global particle order
 * (the same bits on every rank and for every rank count). Collective. */
void dm_dist_diagnostics(dm_dist *d, dm_dist_diag *out);
/* Σ m_i x_i·y_i over free particles of two local [n_local][3] arrays, in global particle order
 * (as dm_dist_diagnostics). Collective. */
double dm_dist_mass_dot(dm_dist *d, const double *x, const double *y);
/* C and σ of every particle into the global model's m->C, m->sigma (every rank), from the local
 * state: what dm_potential_energy(global, w) would give, bit for bit. Collective. */
void dm_dist_global_stress(dm_dist *d);
/* Frees the global model's families and work arrays once the local model exists (the run
 * then keeps only its state and C, σ for outputs): O(N/P) bonds per rank in the time loop. */
void dm_dist_release_global(dm_dist *d);
/* Owned rows of a local [n_local][width] array into the global [n][width] array, on every
 * rank (collective); and global → local (owned and ghosts). */
void dm_dist_gather(dm_dist *d, const double *local, int width, double *global);
void dm_dist_scatter(dm_dist *d, const double *global, int width, double *local);

/* Exact reference solutions of paper 000 §5 (units g, cm, 10 µs). */
/* §5.1 rod 0<x<2L, fixed ends, triangle initial displacement (series, nterms terms). */
double dm_exact_rod_triangle(double x, double t, double L, double eps, double c, int nterms);
/* §5.1 smooth data: w = εL sin(πx/2L) cos(πct/2L). */
double dm_exact_rod_sine(double x, double t, double L, double eps, double c);
/* §5.2 harmonic wave ε sin(8πx/L) in 0<x<L (medium 1) hitting the contact x = L with medium 2;
 * normal stress σ(x,t) = E ∂w/∂x from d'Alembert's solution (the printed formulas miss a
 * factor ω and a sign; docs/particles-dm.md). Valid while no wave reaches x = 2L. */
double dm_exact_contact_stress(double x, double t, double L, double eps, double rho1, double E1,
                               double rho2, double E2);
/* §5.3 spherical wave from a source w(r0, t) = w0(1 − cos ωt): radial displacement w(r,t),
 * radial velocity u(r,t). cl = longitudinal wave speed. */
void dm_exact_sphere(double r, double t, double r0, double w0, double period, double cl,
                     double *w, double *u);

/* Deck problem type `discrete_model` (docs/input-dm.md). */
typedef struct dm_problem dm_problem;
dm_problem *dm_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                            dk_errors *e);
ms_status dm_problem_run(ms_ctx *ctx, dm_problem *p);
void dm_problem_free(dm_problem *p);

/* What a run measured (also written to the log and to OUTDIR/dm_summary.csv). Fields that do
 * not apply to the deck's problem are NaN. */
typedef struct dm_run_summary {
  size_t particles, bonds; /* all particles incl. ghosts / fixed layers; bonds = Σ|N_i| */
  size_t real_particles;   /* the lattice inside the domain (the ones that are timed) */
  long steps;
  double dt, t_end;
  double omega_dt;        /* ω_max Δt (power iteration) vs the scheme's stability limit */
  double wall_s, particle_steps_per_s; /* time-stepping loop only (real particles) */
  double cpu_s;           /* process CPU time of that loop, all threads (load-independent) */
  double energy_err_max;  /* max |H(t) − H(0)| / H(0) over the energy samples */
  /* zero-energy-mode indicator |z|(t) / max_t |Δw|(t) (dm_hourglass_norm) at the energy
   * samples: first, largest and last value */
  double hourglass_first, hourglass_max, hourglass_last;
  double amp_err, phase_err;  /* rod, over the last 10 L/c of w(x_probe, t): A − 1 and s (units
                               * of L/c) of the least-squares fit w ≈ A·w_exact(t − s) */
  double peak_err;            /* rod: (max|w| − max|w_exact|)/max|w_exact| (includes ringing) */
  double rms_err;             /* rod: rms(w − w_exact)/max|w_exact| over that window, no fit */
  double err_l1, err_l2, err_max; /* contact: σ_xx at t_end; sphere: radial w at t_end; all
                                   * relative to the exact solution's maximum */
  double err_u_l2;            /* sphere: radial velocity, L2, relative to u0 = w0 ω */
  double kinetic_end, potential_end; /* energies at t_end (kJ) */
  int ranks;                  /* MPI ranks of the run; partition quality (dm_dist_stats): */
  long edge_cut, edge_cut_slab;
  double imbalance, imbalance_slab;
  long restart_step;          /* step the run continued from (0: a fresh start) */
} dm_run_summary;
const dm_run_summary *dm_problem_summary(const dm_problem *p);
/* Global displacements and velocities ([n][3], particle order) at the end of the last run
 * (the same on every rank); returns n (0 before a run). */
size_t dm_problem_final_state(const dm_problem *p, const double **w, const double **u);

#endif /* MSCALE_PTL_H */
