/* SPDX-License-Identifier: MIT */
/* ptl.h — what the particle models share (docs/developing.md): the structure-of-arrays
 * particle state, the counter-based random generator and the symplectic RKN integrators.
 * Cluster dynamics (particles/cd/cd.h) and the discrete model (particles/dm/dm.h) build on it. */
#ifndef MSCALE_PTL_H
#define MSCALE_PTL_H

#include "core.h"
#include "eos.h"

/* Particle storage (ptl_): structure-of-arrays, sized once. Units are the internal ones (g, cm,
 * 10 µs: velocity km/s, docs/design.md §2). */

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

typedef struct ptl_state_params {
  size_t cap; /* particles it can hold */
  int dim;    /* 2 or 3 */
} ptl_state_params;
/* MS_ERR_INPUT (and *out NULL) unless dim is 2 or 3. */
ms_status ptl_state_create(const ptl_state_params *p, ptl_state **out);
void ptl_state_destroy(ptl_state **s); /* null-safe; sets *s = NULL */
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
 * generator started from `seed` (bench/cd_lammps, bench/problems/cd_lammps.md). */
double ptl_splitmix64_uniform(uint64_t seed, uint64_t k);

/* === Particle snapshots (ptl_snapshot.c): the one HDF5 + XDMF particle writer === */

/* A dataset of a snapshot beyond x, v and mass: [n][ncomp] doubles, or n int64 when d is NULL. */
typedef struct ptl_snapshot_data {
  const char *name; /* path in the file, e.g. "particles/sigma_u" */
  const double *d;
  const int64_t *i;
  int ncomp;
  const char *units; /* doubles only (NULL: no units attribute) */
} ptl_snapshot_data;

typedef struct ptl_snapshot_attr {
  const char *name; /* attribute of the /particles group */
  double value;
} ptl_snapshot_attr;

enum { PTL_SNAPSHOT_MAX_ATTR = 16 };

/* Parts of the standard layout a snapshot can leave out (ptl_snapshot.omit; 0: all written). */
enum {
  PTL_SNAPSHOT_NO_V = 1u,      /* no particles/v (v unused) */
  PTL_SNAPSHOT_NO_MASS = 2u,   /* no particles/mass (mass unused) */
  PTL_SNAPSHOT_NO_VERTEX = 4u, /* no particles/vertex; the sidecar's Polyvertex topology then
                                * has no connectivity (ms_xdmf_write_points) */
  PTL_SNAPSHOT_NO_SERIES = 8u  /* no time-series sidecar of the file's prefix */
};

/* What a snapshot holds. Datasets, in this order: particles/x [n][3] from x[0..2] (x[2] NULL:
 * 0), particles/v [n][3] from v[0..2] (a NULL component: 0), particles/mass [n], then
 * data[0..ndata), then particles/vertex (0..N-1, the sidecar's connectivity); then the
 * attributes attr[0..nattr) of /particles, in order ("time" in the output time unit with
 * time_units beside it, "step" as an integer) and material_names. `omit` leaves out v, mass, vertex (and the
 * time series). The sidecar (PATH with .h5 replaced by .xmf, naming the file by its base name)
 * shows xdmf[0..nxdmf) at `time`; with it, for a numbered name, the time series
 * DIR/particles.xmf of every sidecar of the file's prefix (its name up to the first digit). Collective when dist: every rank gives
 * its own n particles, stored in rank order (docs/mpi.md). */
typedef struct ptl_snapshot {
  size_t n;
  const double *x[3], *v[3];
  const double *mass;
  size_t ndata;
  const ptl_snapshot_data *data;
  size_t nattr;
  ptl_snapshot_attr attr[PTL_SNAPSHOT_MAX_ATTR];
  size_t nxdmf;
  const ms_xdmf_attr *xdmf;
  double time;
  bool dist;
  unsigned omit;              /* PTL_SNAPSHOT_NO_* */
  const char *material_names; /* the names of the material indices, "al,pb" (NULL: none) */
} ptl_snapshot;

/* A snapshot of n particles at positions x[0..2], velocities v[0..2] and masses at `time`
 * (no extra datasets, attributes or sidecar attributes yet); of particles [0, n) of p. */
ptl_snapshot ptl_snapshot_of(size_t n, const double *const x[3], const double *const v[3],
                             const double *mass, double time, bool dist);
ptl_snapshot ptl_snapshot_of_state(const ptl_state *p, size_t n, double time, bool dist);
/* The set-up every particle writer shares: the datasets data[0..ndata) beyond x, v and mass, the
 * sidecar's xdmf[0..nxdmf) and the table of material names (NULL: none); then the attributes
 * "time" (snap->time) and, for step >= 0, "step" (called before any other attribute, these
 * come first). The arrays and names must live until the snapshot is written. */
void ptl_snapshot_contents(ptl_snapshot *snap, size_t ndata, const ptl_snapshot_data *data,
                           size_t nxdmf, const ms_xdmf_attr *xdmf, const char *material_names,
                           long step);
/* Appends the attribute name = v to /particles (at most PTL_SNAPSHOT_MAX_ATTR: more aborts). */
void ptl_snapshot_attr_add(ptl_snapshot *snap, const char *name, double v);
/* The attributes of periodic axis `axis` (0, 1, 2) that `mscale spectrum` reads: period_x|y|z
 * = period, then lo_x|y|z = lo. */
void ptl_snapshot_period_add(ptl_snapshot *snap, int axis, double period, double lo);

/* Writes the snapshot to path (and its sidecar, rank 0's under MPI). dist: every rank calls it
 * and gets the same status. */
ms_status ptl_write_snapshot(const char *path, const ptl_snapshot *snap);

/* The one naming scheme of every particle problem's snapshots (docs/output.md, "Files"): the
 * index-th snapshot of a run is particles_NNNN.h5 (4 digits, wider beyond 9999), with its
 * sidecar particles_NNNN.xmf and the run's time series particles.xmf; the last good state of a
 * run that went unstable is PTL_SNAPSHOT_UNSTABLE (not part of the series). */
#define PTL_SNAPSHOT_UNSTABLE "particles_unstable.h5"
void ptl_snapshot_name(char *name, size_t size, long index);
/* Appends `name` to the material table `table` (size bytes, "" at first): "al" -> "al,pb". */
void ptl_material_table_add(char *table, size_t size, const char *name);

/* === Graph partition (ptl_partition.c): the one METIS wrapper of the particle models === */

/* k-way partition of a graph of nv vertices in CSR form (xadj[nv + 1], adj[xadj[nv]]; C
 * numbering) into nparts parts: METIS_PartGraphKway with a fixed seed (12345), so every rank
 * and every run computes the same map from the same input on one build. vwgt: vertex weights
 * (NULL: unit); adjw: edge weights beside adj (NULL: unit); ufactor: allowed imbalance above
 * the mean part weight in 1/1000 (0: METIS's default, 30). part[v] in [0, nparts).
 * MS_ERR_INTERNAL if METIS fails (its code in *code, if code is not NULL). */
ms_status ptl_partition_kway(int32_t nv, const int32_t *xadj, const int32_t *adj,
                             const int32_t *vwgt, const int32_t *adjw, int nparts, int ufactor,
                             int32_t *part, int *code);


/* === Symplectic RKN integrators (rkn_) === */

/* Explicit symplectic Runge–Kutta–Nyström schemes for r'' = a(r) (docs/design.md §5.2, [Sofronov] §2).
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
typedef struct rkn_params {
  rkn_kind kind;
  size_t ndof; /* > 0 */
} rkn_params;
/* MS_ERR_INPUT (and *out NULL) for an unknown kind or ndof 0. */
ms_status rkn_create(const rkn_params *p, rkn_integrator **out);
void rkn_destroy(rkn_integrator **ig); /* null-safe; sets *ig = NULL */
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

#endif /* MSCALE_PTL_H */
