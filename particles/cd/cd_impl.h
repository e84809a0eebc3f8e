/* SPDX-License-Identifier: MIT */
/* cd_impl.h — private to the cluster-dynamics files of particles/: the neighbour-list layout
 * shared by neighbour.c (build), cd_force.c (kernels) and cd_sim.c (time step).
 *
 * Link cells of width >= r_list = R_c,max + skin. The cells are grouped in LAYERS: one cell
 * layer along the "slab axis" (the axis with most cells). A half list stores each pair once:
 * under the particle whose layer is lower (layer l pairs with layer l+1, cyclically when the
 * slab axis is periodic), and inside one layer under the particle that comes first in cell
 * order. A layer therefore writes forces only into itself and the next layer, so layers of
 * the same parity can run concurrently (phases: even layers, odd layers, and the last layer
 * alone when a periodic axis has an odd number of layers). Every force component is then a sum
 * in an order fixed by the layer layout alone: results are bitwise independent of the number of
 * OpenMP threads (docs/particles-cd.md).
 *
 * Per particle (in cell order, position p): the list lives in the buffer of its layer, from
 * first[p]: nplain[p] entries j (no periodic image: d = x_i − x_j), then nimg[p] entry pairs
 * (j, image code): d = x_i − (x_j + shift[code]). Positions are wrapped into the periodic box at
 * each rebuild only, so images stay valid between rebuilds. With `reorder`, a build also
 * renumbers the particles into cell order (ptl_state arrays and partner lists permuted; gid
 * keeps each particle's identity).
 * In bonded mode bit 31 of a plain/image j marks a set-up partner (CD_NB_BONDED).
 * Full lists (nl->full, the fit kernel's: cd_sim.c decides) hold every pair under both
 * particles, in groups of CD_GROUP positions (cd_plain_list below). */
#ifndef MSCALE_CD_IMPL_H
#define MSCALE_CD_IMPL_H

#include "cd.h"

#include <math.h>
#include <string.h>

/* Loops over fewer particles than this run serially (thread start-up would dominate). */
/* Strict C11 + POSIX does not define M_PI. */
#define CD_PI 3.14159265358979323846

#define CD_PAR(n) ((long)(n) >= 8192)

/* The simulation (cd.h: cd_sim, opaque to the library's users). */
/* Runtime dispatch of the SIMD kernels (docs/benchmarks.md, "One binary for every x86-64").
 * A portable build (x86-64-v2, MSCALE_NATIVE=OFF) holds the AVX2 and AVX-512 kernels too,
 * compiled for their instruction sets by `#pragma GCC target`, and picks them by CPU detection
 * (cd_kernel.c): cd_simd_level_ says which. The hot loops without intrinsics (the table-path
 * force loops, the list build) are compiled three times by MS_KERNEL_CLONES, so that fma() is
 * one instruction wherever the CPU has FMA (under x86-64-v2 it would be a libm call). A native
 * build for an AVX-512 CPU needs no clones. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CD_X86_DISPATCH 1
#else
#define CD_X86_DISPATCH 0
#endif
#if CD_X86_DISPATCH && !defined(__AVX512F__)
/* a cloned loop (MS_KERNEL_CLONES, core.h; its helpers MS_KERNEL_INLINE: fma() one instruction
 * in each clone, not a libm call) whose callees (the SIMD kernels of its instruction set among them) are all
 * inlined where the clone's target allows */
#define CD_KERNEL_FLATTEN __attribute__((flatten))
#else
#define CD_KERNEL_FLATTEN
#endif
enum { CD_SIMD_SCALAR = 0, CD_SIMD_AVX2 = 1, CD_SIMD_AVX512 = 2 };
extern int cd_simd_level_; /* CD_SIMD_*, set when the library loads (cd_kernel.c) */

struct cd_sim {
  ptl_state *p; /* owned */
  cd_box box;
  cd_config cfg;
  int nmat;
  char *material_names; /* "al,pb" for snapshots (NULL: none); owned */
  cd_pair_table *pair[CD_MAX_MATERIALS][CD_MAX_MATERIALS]; /* [a][b] == [b][a], owned */
  double rc_max;
  cd_neigh *nl;
  double t;
  long step;
  /* piston */
  cd_history piston; /* u(t) of every PTL_DRIVEN particle */
  double piston_dir[3];
  size_t n_driven;
  int32_t *driven; /* indices of driven particles */
  /* balance accumulators */
  double dissipated, piston_work, broken_bonded;
  long n_inside0[CD_MAX_MATERIALS][CD_MAX_MATERIALS]; /* pairs inside R_c at start (plain) */
  bool have_inside0;
  double *scratch;   /* 3N, damping velocity increments (NULL if no damping) */
  int32_t *partners; /* bonded mode: [N][CD_MAX_PARTNERS] (−1 = none/broken) */
  long n_broken_bonds;
  bool forces_zeroed;         /* the step zeroed f in its drift loop */
  double disp_bound;          /* Σ Δt·max|v| since the last build (cheap rebuild pre-check) */
  double vmax_last;           /* max|v| of the last Verlet step (when to take the extents) */
  struct cd_layer_sums *sums; /* per-layer accumulators of the kernels */
  int sums_cap;
  double *pw; /* [N][6] per-particle virials (allocated by diagnostics) */
  /* RKN integrators (cfg.integrator != velocity Verlet): stage buffers, driven particles'
   * positions at the start of the step, the piston force at each stage */
  struct rkn_integrator *rkn;
  double rkn_reach[2]; /* stage excursion bound: |q_l − r^n| ≤ Δt c0 max|v| + Δt² c1 max|a| */
  double *driven_x0;   /* [n_driven][3] */
  double stage_force[3];
  int stage;
  double wall_time_force, wall_time_neigh;
  long last_build_step; /* step of the last list build (full or half lists: cd_sim.c) */
  double kick_hdt;      /* > 0: the fit kernel also kicks v += kick_hdt f/m (cd_sim.c) */
  struct cd_dd *dd;     /* MPI decomposition (cd_par.c); NULL on one rank */
  cd_mpi_config mpi;
  bool mpi_on;   /* cd_sim_set_mpi was called */
  char err[512]; /* what the instability guard found (cd_sim_error) */
};

#define CD_NB_BONDED ((int32_t)0x40000000)
#define CD_NB_INDEX  ((int32_t)0x3fffffff)

struct cd_neigh {
  double rlist, skin;
  int ncell[3];
  double cell_lo[3], cell_inv_w[3];
  int slab_axis;
  int nlayer;
  int nphase;
  int phase_start[4]; /* layers of phase k: phase_layer[phase_start[k] .. phase_start[k+1]) */
  int *phase_layer;
  size_t ncells, cells_cap;
  int32_t *cell_start;  /* ncells + 1, into sorted */
  int32_t *sorted;      /* particle indices in cell order (layer-major) */
  int32_t *cell_of;     /* cell index of each particle (build scratch) */
  int32_t *layer_start; /* nlayer + 1, into sorted */
  int layers_cap;
  uint32_t *first; /* per position: offset in the layer's buffer */
  uint16_t *nplain, *nimg;
  int32_t **buf; /* per layer */
  size_t *buf_cap, *buf_len;
  float *xb, *yb, *zb; /* positions at the last build (float: see xb_err) */
  double xb_err;       /* bound on |x − (double)xb| from float rounding, subtracted from skin/2 */
  float *xs, *ys, *zs; /* positions in cell order at the last build, for the candidate test (one
                        * block, also the renumbering scratch) */
  double shift[27][3];
  long nbuild;
  size_t n;        /* particles when built */
  bool colour;     /* layers are processed in parallel phases */
  bool full;       /* full lists: every pair under both particles (the fast path's;
                        * cd_half_pair picks the half list out of them) */
  bool overfull;   /* some particle had more than CD_MAX_CAND candidates */
  int cell_factor; /* cell-count cap factor (cells <= factor n + 64; 0 = 2): raised on overfull */
};

/* Entry k of a list row that starts at `row` with np plain entries, then its image pairs (see
 * the top of this file): returns the entry (its word carries j and the flag bits) and sets *shift
 * to the periodic shift to add to x_j (shift[13] is the zero shift of a plain entry). */
static inline const int32_t *cd_nb_entry(const cd_neigh *nl, const int32_t *row, int np, int k,
                                         const double **shift) {
  const int32_t *entry = k < np ? row + k : row + np + 2 * (k - np);
  *shift = nl->shift[k < np ? 13 : entry[1]];
  return entry;
}

/* Plain and shifted cutoffs: every pair closer than R_c interacts, with the same forces. */
static inline bool cd_pairs_by_distance(cd_cutoff_mode m) { return m != CD_CUTOFF_BONDED; }

/* Full lists (nl->full) hold, for the particle at position pos, the entries of its half list
 * plus those listing it; the half list's pair (i, j) is the one with j in the next layer, or in
 * the same layer and later in cell order: positions are ordered by (cell, index), the counting
 * sort being stable. Same entries, same order as the half list the build would make. */
static inline bool cd_half_pair(const cd_neigh *nl, int32_t i, int32_t j) {
  const int32_t ci = nl->cell_of[i], cj = nl->cell_of[j];
  if (nl->colour) {
    const int32_t per_layer = (int32_t)(nl->ncells / (size_t)nl->nlayer);
    const int32_t dl = cj / per_layer - ci / per_layer;
    if (dl != 0) return dl == 1 || dl == 1 - nl->nlayer; /* next layer, cyclically */
  }
  return cj > ci || (cj == ci && j > i);
}

/* F/r of the fit at s (cd_pair_fit_eval; the fast kernel's arithmetic, lane for lane). */
static inline double cd_fit_eval(const cd_pair_table *t, double s) {
  uint64_t bs;
  memcpy(&bs, &s, sizeof bs);
  const uint64_t k = (bs >> CD_FIT_SHIFT) % CD_FIT_NSEG;
  /* centre of the segment: s with the bits below the shift replaced by 100…0 */
  const uint64_t cb =
      (bs & ~((UINT64_C(1) << CD_FIT_SHIFT) - 1)) | (UINT64_C(1) << (CD_FIT_SHIFT - 1));
  double centre;
  memcpy(&centre, &cb, sizeof centre);
  const double tt = s - centre;
  /* Estrin's scheme in the fast kernel's order (cd_force.c): coefficients above fit_deg are 0 */
  const double(*c)[CD_FIT_NSEG] = t->fit_coef;
  const double t2 = tt * tt, t4 = t2 * t2, t8 = t4 * t4;
  const double p01 = fma(c[1][k], tt, c[0][k]), p23 = fma(c[3][k], tt, c[2][k]),
               p45 = fma(c[5][k], tt, c[4][k]), p67 = fma(c[7][k], tt, c[6][k]),
               p89 = fma(c[9][k], tt, c[8][k]);
  const double q03 = fma(p23, t2, p01), q47 = fma(p67, t2, p45);
  return fma(p89, t8, fma(q47, t4, q03));
}

/* Full lists are stored by groups of CD_GROUP consecutive positions of a layer (the fit kernel
 * takes a group's particles as the lanes of one vector): entry k of the plain list of lane l
 * is at block[CD_GROUP k + l], the block starting CD_GROUP·kmax entries before first[g0] (g0
 * the group's first position, kmax its longest plain list); the image entries of each position
 * start at first[pos], after the block. Half lists: plain entries from first[pos], stride 1,
 * then the image entries. */
enum { CD_GROUP = 8 };
static inline int32_t *cd_plain_list(const cd_neigh *nl, int layer, int32_t pos, int *stride) {
  int32_t *buf = nl->buf[layer];
  if (!nl->full) {
    *stride = 1;
    return buf + nl->first[pos];
  }
  const int32_t ls = nl->layer_start[layer], le = nl->layer_start[layer + 1];
  const int32_t g0 = ls + (pos - ls) / CD_GROUP * CD_GROUP;
  int kmax = 0;
  for (int32_t q = g0; q < g0 + CD_GROUP && q < le; q++)
    kmax = nl->nplain[q] > kmax ? nl->nplain[q] : kmax;
  *stride = CD_GROUP;
  return buf + nl->first[g0] - (size_t)CD_GROUP * kmax + (pos - g0);
}
static inline int32_t *cd_image_list(const cd_neigh *nl, int layer, int32_t pos) {
  return nl->buf[layer] + nl->first[pos] + (nl->full ? 0 : nl->nplain[pos]);
}

/* Lists for up to cap particles, list radius rlist = R_c,max + skin (rebuilt when a particle
 * has moved skin/2). MS_ERR_INPUT (*out NULL) unless rlist > skin ≥ 0. */
typedef struct cd_neigh_params {
  size_t cap;
  double rlist, skin;
} cd_neigh_params;
ms_status cd_neigh_create(const cd_neigh_params *p, cd_neigh **out);
void cd_neigh_destroy(cd_neigh **nl); /* null-safe; sets *nl = NULL */
/* Wraps positions into periodic axes, bins, builds the half lists (bonded flags from
 * `partners` when non-NULL). MS_ERR_INPUT if a periodic period is below 2 r_list. */
ms_status cd_neigh_build(cd_neigh *nl, ptl_state *p, const cd_box *box, int32_t *partners,
                         bool reorder);
/* The rebuild test (neighbour.c's header) on particles [0, n): true while the lists hold every
 * pair within R_c of positions that reach up to `reach` beyond the displacements (RKN stages;
 * 0 for Verlet); `bound`: a known bound on every |Δ| (Σ Δt·max|v|), which spares the pass
 * over the positions while below skin/2 − reach.
 * With `dd` (MPI) every rank calls it with the same bound (a max over ranks) and the same
 * xb_err (max-reduced at the build) and gets the same answer, the serial run's.
 * `known_ext` (or NULL): the displacement extents of particles [0, n), already taken by the
 * caller — {max|Δ|², max Δx, max Δy, max Δz, −min Δx, −min Δy, −min Δz}, all INFINITY if some
 * position is not finite — which spares the test its own pass. */
bool cd_neigh_holds(const cd_neigh *nl, const ptl_state *p, long n, double bound, double reach,
                    bool dd, const double *known_ext);
/* The displacement extents of cd_neigh_holds, taken in a loop over particles: one displacement
 * (dx, dy, dz) into the running maxima *d2max, *hx, *hy, *hz, *lx, *ly, *lz (−min, so that all
 * are maxima) and *nan_seen. Callers keep them in locals of an OpenMP max-reduction (the loops
 * stay vectorised once this is inlined), then cd_extents_finish. */
static inline void cd_extent_update(double dx, double dy, double dz, double *d2max, double *hx,
                                    double *hy, double *hz, double *lx, double *ly, double *lz,
                                    int *nan_seen) {
  const double d2 = dx * dx + dy * dy + dz * dz;
  *nan_seen = d2 == d2 ? *nan_seen : 1;
  *d2max = d2 > *d2max ? d2 : *d2max;
  *hx = dx > *hx ? dx : *hx;
  *hy = dy > *hy ? dy : *hy;
  *hz = dz > *hz ? dz : *hz;
  *lx = -dx > *lx ? -dx : *lx;
  *ly = -dy > *ly ? -dy : *ly;
  *lz = -dz > *lz ? -dz : *lz;
}
static inline void cd_extents_finish(double ext[7], double d2max, double hx, double hy, double hz,
                                     double lx, double ly, double lz, int nan_seen) {
  const double e[7] = {d2max, hx, hy, hz, lx, ly, lz};
  const bool finite = !nan_seen && d2max < INFINITY; /* an infinite component makes d2 infinite */
  for (int k = 0; k < 7; k++) ext[k] = finite ? e[k] : INFINITY; /* NaN: rebuild */
}
size_t cd_neigh_bytes(const cd_neigh *nl);
size_t cd_neigh_pairs(const cd_neigh *nl);

/* Per-layer accumulators of the force/diagnostic kernels. */
typedef struct cd_layer_sums {
  double epot;
  double vir[6];
  double broken; /* bonded mode: energy of bonds broken in this evaluation */
  long nbroken;
  long inside[CD_MAX_MATERIALS * CD_MAX_MATERIALS];
  char pad[64];
} cd_layer_sums;

/* Forces on all particles (f overwritten when write_forces; diagnostics pass false so that
 * they never perturb the trajectory). With `sums` (nlayer entries), also the potential
 * energy, the virial sum ½Σ f r_a r_b / r, and pairs inside each cutoff. `pw` (optional,
 * [N][6]) receives per-particle virials. */
void cd_compute_forces(cd_sim *s, cd_layer_sums *sums, double *pw, bool write_forces);
/* Relative-velocity damping sub-step (eq. 6): v_i −= dt Γ Σ_k μ_ik/m_i (v_i − v_k) over pairs
 * inside R_c, with μ_ik = 2 m_i m_k/(m_i + m_k); returns the kinetic energy it removed. */
double cd_damping_step(cd_sim *s);

/* ---- MPI decomposition (cd_par.c, docs/mpi.md) ---- */
typedef struct cd_dd cd_dd;
/* In cd_sim_init (rc_max known, before the first list build): coarse grid and first partition;
 * grows p to hold the global count. Collective. */
ms_status cd_dd_create(cd_sim *s);
void cd_dd_free(cd_dd *d);
/* At every list build: repartition when due, migrate particles to their owners, sort the owned
 * ones by coarse cell, send full ghost copies, and remap bonded partners. Collective. */
ms_status cd_dd_redistribute(cd_sim *s);
/* Ghost refresh from their owners: CD_REFRESH_X positions (ghost forces zeroed; before a force
 * evaluation, which reads nothing else of a ghost), CD_REFRESH_V velocities (before the damping
 * sub-step; and for cd_sim_refresh_ghosts). Collective. */
enum { CD_REFRESH_X = 1u, CD_REFRESH_V = 2u };
void cd_dd_refresh(cd_sim *s, unsigned what);
/* The box changed (affine deformation): new coarse grid and partition. Collective. */
void cd_dd_regrid(cd_sim *s);
bool cd_dd_owns(const cd_dd *d, const double x[3]);
/* Checkpoints: the owner map in use and the list builds since the last rebalance attempt. */
const int32_t *cd_dd_owner(const cd_dd *d, size_t *ncells, long *builds_since);
void cd_dd_set_builds_since(cd_dd *d, long builds_since);
const cd_mpi_stats *cd_dd_stats(const cd_dd *d);

/* ---- the model keys of a section (cd_model_keys.c), shared by cd_problem.c and cd_region.c ---- */
typedef struct cd_model_keys {
  double r0, thickness, rc, skin, courant, dt, r_min, damping_j;
  int table_intervals;
  cd_cutoff_mode mode;
} cd_model_keys;
typedef struct cd_model_defaults {
  const char *where; /* section name in messages */
  double courant;    /* Δt = courant r0/c0 unless dt is given */
  double damping;    /* J of Γ = c0/(J r0); 0: no damping */
} cd_model_defaults;
/* notes (may be NULL: no aliases) collects the deprecation notes of the old key names
 * (spacing, dt_factor, damping_j), at most cap bytes. */
void cd_model_keys_read(dk_errors *e, dk_doc *doc, const dk_node *sec, int dim,
                        const cd_model_defaults *d, cd_model_keys *k, char *notes, size_t cap);
/* `key`, or its deprecated name `old` if the section uses that (noted in notes); both: an error. */
const char *cd_key_or_alias(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key,
                            const char *old, const char *where, char *notes, size_t cap);

/* ---- cd_sim.c internals that cd_relax.c calls ---- */
/* List build (under MPI first the redistribution and ghost refresh, cd_par.c); `reorder` sorts
 * the particles into cell order. */
ms_status cd_rebuild_lists(cd_sim *s, bool reorder);
/* Forces for the time step; in bonded mode also books broken bonds. */
void cd_step_forces(cd_sim *s);
/* Half lists (built at once) unless the full-list fit kernel serves the current settings. */
ms_status cd_half_lists_unless_fit(cd_sim *s);
/* Pairs inside R_c now, for the broken-pair energy of the plain cutoff. */
void cd_count_inside0(cd_sim *s);
/* Bonded mode: the partners are every pair closer than its R_c now (lists must be built). */
ms_status cd_form_partners(cd_sim *s);

#endif /* MSCALE_CD_IMPL_H */
