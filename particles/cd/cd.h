/* SPDX-License-Identifier: MIT */
/* cd.h — the public header of the cluster-dynamics library (particles/cd/).
 *
 * Cluster dynamics ([Davydov], docs/design.md §5.1): particles ("clusters") of size r0 on a
 * close-packed lattice interact through pair potentials built from an EOS cold curve;
 * docs/particles-cd.md. Units are the internal ones (docs/design.md §2). */
#ifndef MSCALE_CD_H
#define MSCALE_CD_H

#include "ptl.h"
#include "ptl_region.h"

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

/* ---- pair potentials (docs/design.md §5.1) ---- */
/* fcc:  E(r) = (√2 ρ0 r0³/12) ε_x((r0/r)³),  f(r) = −dE/dr = (√2/4) r² P_x((r0/r)³);
 * 2D:   E(r) = (m/3) ε_x((r0/r)²),           f(r) = r h P_x((r0/r)²)/√3 (docs/particles-cd.md).
 * Tabulated once as a cubic Hermite interpolant of E in s = r² (values and exact slopes
 * dE/ds = −f/(2r) at the nodes); the force used is F/r = −2 dE/ds of the SAME cubic, so the
 * force is the exact derivative of the energy that is reported. */
/* The forces-only fast path's fit of F/r (cd_potential.c, docs/particles-cd.md): segments of s
 * are the values sharing bits(s) >> CD_FIT_SHIFT (8 per octave of s), 16 consecutive ones. */
enum { CD_FIT_MAXDEG = 9, CD_FIT_SHIFT = 49, CD_FIT_NSEG = 16 };

typedef struct cd_pair_table {
  int nint; /* intervals in s */
  double s_lo, h, inv_h;
  double rc, rc2; /* cutoff (hard truncation) */
  double r0;      /* nearest-neighbour distance at rest */
  double e_rc;    /* E(rc): energy a pair takes with it when it leaves the cutoff */
  double e_shift; /* subtracted from every E of the table (cd_pair_table_shift_energy): the
                   * plain table's E(rc) in cutoff_mode shifted, else 0 */
  double *fcoef;  /* [nint][4]: F/r = f0 + t(f1 + t f2), t in [0,1) (4th slot padding) */
  double *ecoef;  /* [nint][4]: E = e0 + t(e1 + t(e2 + t e3)) */
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
double cd_pair_force_exact(const eos_t *eos, cd_lattice lat, double r0, double thickness, double r);
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
/* The energy-shifted cutoff (cutoff_mode shifted, docs/particles-cd.md): E(r) − E(rc) inside
 * rc, so E is continuous at rc; the force coefficients (and the fit) are left bitwise as they
 * are. Sets e_shift = the old e_rc and e_rc = 0; a second call does nothing. */
void cd_pair_table_shift_energy(cd_pair_table *t);
/* F/r of the fit at s (fit_ok tables; meaningful for fit_slo <= s < rc2): the fast kernel's
 * arithmetic, lane for lane */
double cd_pair_fit_eval(const cd_pair_table *t, double s);

/* ---- the simulation ---- */
enum { CD_MAX_MATERIALS = 8 };

typedef enum cd_bc { CD_BC_FREE = 0, CD_BC_PERIODIC, CD_BC_WALL } cd_bc;

/* Cutoff treatment (docs/design.md §5.1, "known trap"):
 *  CD_CUTOFF_PLAIN   — every pair closer than R_c interacts (the benchmark's model);
 *  CD_CUTOFF_BONDED  — interaction partners fixed at set-up (pairs closer than R_c then);
 *                      a bond farther than R_c breaks for good; non-bonded pairs (and broken
 *                      bonds) only repel, through the compressive branch r < r0;
 *  CD_CUTOFF_SHIFTED — the pairs and forces of PLAIN, the energy E(r) − E(R_c) (the shifted
 *                      potential of [AllenTildesley1987], p. 145): cd_sim_set_pair shifts the
 *                      tables (cd_pair_table_shift_energy), so the trajectory is PLAIN's bit for
 *                      bit and only the energy booking differs (docs/particles-cd.md). */
typedef enum cd_cutoff_mode {
  CD_CUTOFF_PLAIN = 0,
  CD_CUTOFF_BONDED,
  CD_CUTOFF_SHIFTED
} cd_cutoff_mode;

/* Time integrator (docs/particles-cd.md): velocity Verlet (fused kick–drift, the default and
 * the benchmark's), or one of the symplectic RKN schemes of rkn_ (docs/design.md §5.2) — position
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
  double r0;   /* nearest-neighbour distance (cluster size a) */
  double skin; /* Verlet skin (list radius = max R_c + skin) */
  double dt;   /* time step */
  cd_cutoff_mode cutoff;
  double damping_gamma;     /* Γ of eq. 6 ([Davydov]), 1/time; 0 = off */
  int sort_every;           /* renumber particles into cell order every k-th list build (0: 8) */
  cd_lattice lattice;       /* for the reference volume per particle (per-particle stress) */
  double thickness;         /* 2D plane-strain thickness h (unused in 3D) */
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
  double kinetic;     /* ½ m v² of integrated (non-driven) particles */
  double potential;   /* Σ pair energies of pairs inside their cutoff */
  double dissipated;  /* energy removed by the relative-velocity damping */
  double broken;      /* energy carried away by pairs/bonds leaving the cutoff */
  double piston_work; /* work done on the particles by driven (piston) particles */
  double wall_work;   /* 0 (specular walls do no work); kept for the balance's form */
  double total;       /* kinetic + potential + dissipated + broken − piston_work */
  double momentum[3]; /* Σ m v of integrated particles */
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
  double imbalance;           /* max part weight / mean part weight (weights as given) */
  double load;          /* max over parts of (part weight + 0.25 × weight of its halo cells, the
                     * ghosts) / mean part weight: the cost model CD_PART_AUTO minimises */
  double rejected_load; /* CD_PART_AUTO: the load of the map it did not take; else NaN */
  long edge_cut;        /* edges of the 26-neighbour coarse-cell graph joining different parts */
  long halo_cells;      /* Σ over parts of the cells not in the part but adjacent to it */
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
                             int nparts, cd_partition_method method, int slab_axis, int32_t *owner,
                             cd_partition_stats *stats);
/* The figures of a given owner map (stats->method is meaningless). MS_ERR_INPUT: bad
 * arguments or an owner outside [0, nparts). */
ms_status cd_partition_evaluate(const int ncell[3], const bool periodic[3], const int64_t *weight,
                                int nparts, const int32_t *owner, cd_partition_stats *stats);
/* Per-part figures of an owner map: halo[p] = cells outside part p adjacent to it (its ghost
 * cells), neighbours[p] = distinct other parts adjacent to p (its messages per exchange).
 * Arrays of nparts entries; either may be NULL. */
void cd_partition_halo(const int ncell[3], const bool periodic[3], const int32_t *owner, int nparts,
                       long *halo, int *neighbours);

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
  int ncell[3];         /* coarse cells */
  size_t owned, ghosts; /* this rank, at the last list build */
  size_t global, max_owned, total_ghosts;
  double imbalance;             /* max owned / mean owned, at the last list build */
  cd_partition_stats partition; /* of the owner map in use (weights = particle counts) */
  long partitions;              /* partitions computed (1 = the initial one) */
  long rebalances;              /* repartitions because of imbalance */
  long rebalance_step;          /* step of the last rebalance, imbalance before and after */
  double rebalance_before, rebalance_after;
  double exchange_s;        /* wall time in ghost refreshes and migrations, this rank */
  double exchanged_doubles; /* received, this rank */
  long lost_bonds;          /* bonded mode: partners not found on the rank at a migration */
} cd_mpi_stats;

/* A cluster-dynamics simulation (opaque: particles/cd/cd_impl.h holds its layout). */
typedef struct cd_sim cd_sim;
/* What a caller may read of it. The particles: [0, nlocal) owned, then ghosts; the pointer is
 * the sim's (it changes on a restart, cd_sim_init_restart). */
ptl_state *cd_sim_particles(const cd_sim *s);
double cd_sim_time(const cd_sim *s);       /* simulated time since the start, 10 µs */
long cd_sim_step_count(const cd_sim *s);   /* steps taken */
const cd_box *cd_sim_box(const cd_sim *s); /* the box (changes under cd_sim_affine) */
const cd_config *cd_sim_config(const cd_sim *s);
long cd_sim_broken_bonds(const cd_sim *s); /* bonded mode: set-up partners broken so far */
/* Wall time spent so far in the force kernels and in the neighbour lists (s). */
void cd_sim_wall_times(const cd_sim *s, double *force, double *neighbour);

enum { CD_MAX_PARTNERS = 16 };

/* Takes ownership of p. Tables are set afterwards with cd_sim_set_pair; cd_sim_init then
 * builds the lists (and, in bonded mode, the partner lists) and the first forces. */
typedef struct cd_sim_params {
  ptl_state *particles; /* ownership passes to the sim */
  const cd_box *box;
  const cd_config *cfg;
  int nmat;                   /* 1 .. CD_MAX_MATERIALS */
  const char *material_names; /* the materials' names for snapshots, "al,pb" (NULL: none) */
} cd_sim_params;
/* MS_ERR_INPUT (and *out NULL, the particles still the caller's) for a missing particle state,
 * box or configuration or a material count out of range. */
ms_status cd_sim_create(const cd_sim_params *p, cd_sim **out);
/* Takes ownership of t (heap allocated); a != b sets both [a][b] and [b][a]. In
 * CD_CUTOFF_SHIFTED it shifts t's energies (cd_pair_table_shift_energy). */
void cd_sim_set_pair(cd_sim *s, int a, int b, cd_pair_table *t);
/* Piston: every PTL_DRIVEN particle moves with u(t)·dir (history copied). */
void cd_sim_set_piston(cd_sim *s, const cd_history *h, const double dir[3]);
ms_status cd_sim_init(cd_sim *s);
void cd_sim_destroy(cd_sim **s); /* null-safe; sets *s = NULL */
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
  double tau, modulus; /* box relaxation time; stiffness (GPa), e.g. ρ0 c0² */
  double max_strain;
  bool rebond;
  bool plain; /* bonded runs: relax with the plain cutoff (every pair inside R_c
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
  long broken_bonds; /* bonds broken during the relaxation */
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
/* Von Mises intensity σ_u of a symmetric tensor (docs/design.md §5.1, eq. 4 corrected). */
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
/* Replaces the material table of the snapshots ("al,pb"; NULL: none). */
void cd_sim_set_material_names(cd_sim *s, const char *names);
/* The SIMD kernels this CPU runs: "avx512", "avx2" or "scalar" (cd_kernel.c; for --version and
 * run_info.yaml). */
const char *cd_kernel_name(void);

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
void cd_restart_destroy(cd_restart **r); /* null-safe; sets *r = NULL */

/* Cluster dynamics as the coupled problem's particle region (cd_region.c, ptl_region.h). */
const ptl_region_model *cd_region_model_get(void);

/* ---- deck problem `cluster_dynamics` (docs/input-cd.md) ---- */
typedef struct cd_problem cd_problem;
cd_problem *cd_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                            dk_errors *e);
ms_status cd_problem_run(ms_ctx *ctx, cd_problem *p);
void cd_problem_destroy(cd_problem **p); /* null-safe; sets *p = NULL */


#endif /* MSCALE_CD_H */
