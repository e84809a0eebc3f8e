/* SPDX-License-Identifier: MIT */
/* dm_impl.h — internals shared by the discrete-model sources (not part of the public API). */
#ifndef MSCALE_DM_IMPL_H
#define MSCALE_DM_IMPL_H

#include "dm.h"
#include "dm_cells.h"

#include <math.h>
#include <string.h>

/* The per-particle arrays of a model of n particles (at least 1 row each), zeroed: A⁻¹, cond,
 * κ, C, σ, Q, energy (dm_create; the local model of dm_par.c). */
void dm_alloc_work(dm_model *m, size_t n);
ms_status dm_build_families(dm_model *m, const ms_ctx *ctx);
ms_status dm_build_shape(dm_model *m, const ms_ctx *ctx, size_t *first_bad);
double dm_sym_inverse(int dim, const double *A, double *inv);
/* dm_forces' passes restricted to particles [0, n): C, σ, Q, energy; then F. */
void dm_stress_pass(dm_model *m, const double *w, size_t n);
void dm_gather_pass(dm_model *m, const double *w, double *F, size_t n);

/* ---- Steinberg–Guinan strength (dm_strength.c; docs/particles-dm.md, [SCG1980]) ----
 * G = G0 + G'_P p η^(−1/3) + G'_T (T − T0),  Y = min(Y0 [1 + β(ε_p + ε_i)]^n, Ymax) · G/G0,
 * both 0 at T ≥ T_m(η) = T_m0 exp(2a(1 − 1/η)) η^(2(Γ0 − a − 1/3)), η = ρ/ρ0 of the EOS, and
 * clipped at 0 from below. T = T0 + (e − ε_x(η))/c_v: ε_x is the EOS's cold curve
 * (eos_cold_energy: the 0 K isotherm or the reference isentrope through (ρ0, e0)), taken as the
 * T0 isotherm, so the reference state (ρ0, e0) is at T0 = 300 K. */
struct dm_sg {
  double G0, dGdP, dGdT; /* GPa, dimensionless, GPa/K */
  double Y0, Ymax;       /* GPa */
  double beta, n, eps_i; /* hardening */
  double Tm0, gamma0, a; /* melt curve (K, −, −) */
  double cv, T0;         /* specific heat kJ/(g·K), reference temperature K */
  /* johnson_cook (dm_jc_yield): Y = (A + B ε_p^n)(1 + C ln ε̇*)(1 − T*^m), T_melt in Tm0, T_room
   * in T0, G0 constant, the same T(ρ, e) route (cv, T0) as steinberg_guinan */
  double jA, jB, jn, jC, jm; /* GPa, GPa, −, −, − */
};
/* A built-in parameter set by name (Al6061_T6, Cu_OFHC, Pb, Sn; docs/particles-dm.md); false if
 * unknown. dm_sg_set_names: the names, comma-separated (for messages). */
bool dm_sg_set(const char *name, dm_sg *out);
const char *dm_sg_set_names(void);
double dm_sg_melt_temperature(const dm_sg *sg, double eta);
/* T (K) of (ρ, e) on eos; NaN where the EOS has no cold curve at ρ/ρ0. */
double dm_sg_temperature(const dm_sg *sg, const eos_t *eos, double rho, double e);
/* G and Y (GPa) at η = ρ/ρ0, pressure p (GPa), temperature T (K), plastic strain ε_p. */
void dm_sg_moduli(const dm_sg *sg, double eta, double p, double T, double eps_p, double *G,
                  double *Y);
/* Johnson–Cook [JohnsonCook1983]: Y (GPa) at plastic strain ε_p, equivalent strain rate (1/code time) and
 * T (K); ε̇* = max(rate/ε̇0, 1), ε̇0 = 1/s; T* = (T − T0)/(Tm0 − T0) clamped to [0, 1]; 0 for NaN T.
 * dm_jc_set: the built-in set (Cu_OFHC_JC) by name, false if unknown. */
double dm_jc_yield(const dm_sg *sg, double eps_p, double rate, double T);
bool dm_jc_set(const char *name, dm_sg *out);
/* The deck keys of one discrete_model layer: `strength_set` and/or `strength: {...}` with
 * yield: steinberg_guinan (errors otherwise), every value checked, located errors in *e.
 * eos may be NULL (already reported). */
void dm_sg_read(dk_errors *e, dk_doc *doc, const dk_node *layer, int yield, const eos_t *eos,
                dm_sg *out);

/* The bond loops are dispatched at run time in a portable build (MS_KERNEL_CLONES, core.h).
 * Every path that computes the same quantity (the stress pass and the flush of the closing
 * kick; F in the stress pass and in a snapshot; the drift) is cloned, so one CPU computes each
 * with the same instructions, the same bits. */

/* det of a 3×3 matrix (row-major). */
static inline double dm_det3(const double *a) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
         a[2] * (a[3] * a[7] - a[4] * a[6]);
}

/* The displacement gradient C_i = F_i − I = (Σ_k Δw_ik ⊗ ξ_ik) A_i⁻¹ of displacements w, by the
 * stress pass's own arithmetic (dm_finite.c), so a state's F and J are the same bits wherever
 * they are computed (snapshots of the last good state). */
void dm_fin_displacement_gradient(const dm_model *m, const double *w, const uint8_t *failed,
                                  size_t i, double C[9]);

/* Per-family references (dm_fin_local.c; m->xref not NULL): bond b of family i's vector ξ and
 * Δw = Δx − ξ; the largest bond stretch over the families, each against its own reference.
 * dm_fin_kappa: κ_i = c_s M_i V_i / tr A_i (dm_fin_bond_penalty's, one particle). */
void dm_fin_local_bond(const dm_model *m, const double *w, size_t i, size_t b, double xi[3],
                       double dw[3]);
double dm_fin_local_max_stretch(const dm_fin *f, size_t *where);
double dm_fin_kappa(const dm_fin *f, size_t i, double trA);

/* ξ_ik = X_k + image shift − X_i of bond b of particle i. */
static inline void dm_bond_vector(const dm_model *m, size_t i, size_t b, double xi[3]) {
  const double *X = m->s->X;
  size_t k = m->nbr[b];
  const double *sh = m->shift[m->img[b]];
  for (int a = 0; a < 3; ++a) xi[a] = X[3 * k + a] + sh[a] - X[3 * i + a];
}

/* ---- symmetry planes (dm_symmetry.c) ----
 * dm_sym_init: f->sym, fold, the on-plane components (MS_ERR_INPUT: a real particle on the −
 * side of a plane, or a velocity through the plane a particle lies on), imat_all and v̄, v_close with the ghosts' rows; dm_sym_resize: the
 * last two for a new ghost set (after dm_sym_ghosts: dm_refamily.c); dm_sym_free. */
ms_status dm_sym_init(dm_fin *f, const dm_sym_planes *pl, const uint8_t *imat);
void dm_sym_resize(dm_fin *f, const uint8_t *imat);
void dm_sym_free(dm_fin *f);

/* ---- symmetry planes with kept families (dm_sym_family.c) ----
 * dm_sym_map: the mirror ghost of real particle i under the planes of mask m
 * (ghost[i·nmask + m], UINT32_MAX: none) and the planes i lies off (off[i]), of the fixed ghost
 * set. dm_sym_image: the index of particle k's image under the reflections of mask (k itself
 * when on those planes; SIZE_MAX: no such ghost). dm_sym_uncovered: the first real particle
 * whose image under some mask has no ghost and may lie within `reach` of a real particle (by
 * the current distances to the planes; SIZE_MAX: none). dm_sym_close_pairs: the new pairs (row << 32 | column, both directions)
 * closed under the reflections, real rows only, sorted unique (returns their count; *missing:
 * a real particle whose image partner has no ghost, SIZE_MAX if none). dm_sym_ghost_rows: the
 * CSR lists (n rows, the first nreal real) with each ghost row = the real particles bonded to
 * it, in order; from[c] the old bond of a real row's bond (from may be NULL: the identity),
 * SIZE_MAX for a ghost row's. dm_sym_ghost_xref: the ghost rows' bond vectors from their
 * partners' (MS_ERR_INTERNAL: a bond without its mirror). */
typedef struct dm_sym_map {
  size_t nreal;
  unsigned nmask;
  uint32_t *ghost;
  uint8_t *off;
} dm_sym_map;
void dm_sym_map_build(const dm_fin *f, dm_sym_map *mp);
void dm_sym_map_free(dm_sym_map *mp);
size_t dm_sym_image(const dm_fin *f, const dm_sym_map *mp, size_t k, unsigned mask);
size_t dm_sym_uncovered(const dm_fin *f, const dm_sym_map *mp, double reach);
size_t dm_sym_close_pairs(const dm_fin *f, const dm_sym_map *mp, uint64_t **pairs, size_t np,
                          size_t *missing);
void dm_sym_ghost_rows(size_t n, size_t nreal, size_t **start, uint32_t **nbr, size_t **from,
                       size_t *nbonds);
ms_status dm_sym_ghost_xref(const dm_fin *f, const dm_sym_map *mp, const size_t *start,
                            const uint32_t *nbr, double *xref);

/* ---- fracture (dm_fracture.c; docs/particles-dm.md "Fracture") ----
 * dm_frac_alloc: failed[], broken[] and the contact's arrays (kcon, dtcon, fcon, econ) when a
 * material of f has a fracture model (else NULL); dm_frac_free releases them. dm_frac_stress, called by the stress pass after
 * σ = s − (p + q) I: the failure test of an intact particle (books its bond-penalty energy as
 * broken and switches its penalty off); a failed one gets σ = s = 0. dm_frac_failed_step: the
 * stress pass's whole work for a failed particle (Q = V P A⁻¹ = σ = s = 0, q = 0), returns its
 * stable step. Both touch particle i's entries only (safe in the parallel pass).
 * dm_frac_contact, after the gather: the compression-only pair forces across broken bonds into
 * frc (and fcon; p of a failed particle = its contact virial pressure), the closing-speed step
 * into *dtmin (its particle in *imin); MS_ERR_UNSTABLE (f->bad, bad_what, bad_value) when a
 * broken bond is compressed below DM_CONTACT_MIN_RATIO of its rest length. dm_frac_contact_work, after each half kick of length h: econ −= h fcon·v̄. */
#define DM_CONTACT_MIN_RATIO 0.5
void dm_frac_alloc(dm_fin *f);
void dm_frac_free(dm_fin *f);
static inline bool dm_frac_failed(const dm_fin *f, size_t i) { return f->failed && f->failed[i]; }
/* dm_frac_commit, after the stress pass (its drift done): the particles that failed in it (fresh)
 * become failed; every intact particle with a newly failed family member gets its shape matrix
 * A over its intact members back (A⁻¹, nintact), the penalty energy of its lost bonds booked as
 * broken, and fails itself (isolated) when fewer than DM_FRAC_MIN_INTACT of its reference family
 * is intact or cond A > DM_FRAC_COND_MAX — repeated until no particle fails. dm_frac_restore:
 * A⁻¹, nintact and cut from the failed flags alone (a checkpoint's), the same bits as the run's
 * last dm_frac_commit. docs/particles-dm.md "Fracture". */
bool dm_frac_commit(dm_fin *f); /* true if a particle failed */
/* dm_frac_degenerate, from the stress pass when particle i's F gives no valid state (J ≤ 0, or
 * p, c or T not finite): if i has lost family members (cut) and can fail, it fails now (fresh,
 * its penalty energy booked, J held at J_prev) and true is returned (the caller then returns
 * dm_frac_failed_step); false: the run stops as before. */
bool dm_frac_degenerate(dm_fin *f, size_t i, double J_prev);
void dm_frac_restore(dm_fin *f);
#define DM_FRAC_MIN_INTACT 0.25
#define DM_FRAC_COND_MAX   100.0
void dm_frac_stress(dm_fin *f, size_t i, const dm_fin_material *mt, double J, double *sig,
                    double *s);
double dm_frac_failed_step(dm_fin *f, size_t i);
ms_status dm_frac_contact(dm_fin *f, double *dtmin, long *imin);
void dm_frac_contact_work(dm_fin *f, double h, const double *vb);
/* The deck's `fracture: {model: mean_stress|principal_stress|none, spall_strength, failure_strain}`
 * of `section` (absent: no fracture); located errors (no or non-positive spall_strength) in e;
 * `where` names the section in messages. */
void dm_frac_read(dk_errors *e, dk_doc *doc, const dk_node *section, const char *where,
                  dm_fracture *out);
/* Largest eigenvalue of a symmetric 3×3 matrix (row-major), closed form. */
double dm_frac_max_principal(const double *a);

/* ---- contact (dm_contact.c; docs/particles-dm.md "Contact") ----
 * The pair law: dm_pair_stiffness, each particle's share κc_i of a pair's stiffness into kc[n]
 * (K d² V_i / Σ_k |ξ_ik|² over its family; with ell > 0, K d² V_i / ell²);
 * dm_pair_law, g(λ) and s ≥ |dg/dλ| of particle i's material at λ = r/L; dm_pair_ends, per
 * material index the smallest λ at which the law is finite (0: none) into lam_end[256]. */
void dm_pair_stiffness(const dm_fin *f, double *kc, double ell);
void dm_pair_law(const dm_fin *f, size_t i, double lam, double *g, double *s);
void dm_pair_ends(const dm_fin *f, double *lam_end);
/* The short-range contact between particles not in each other's family (f->sr; NULL when
 * par.contact = 0): L = d_c, the seeing distance, each particle's κc, λ_end per material, the
 * force [n][3] and step [n] of the last evaluation, the energy booked [n] (kJ), touch[i] = 1
 * where a pair acted; touching = their count; within_material: pairs of different material
 * indices are left alone (the impact's bodies: their own contact). */
typedef struct dm_contact {
  dm_cells cells;
  double L, r_see;
  double *kc, lam_end[256];
  double *force, *dt, *energy;
  uint8_t *touch;
  long touching;
  bool within_material;
} dm_contact;
/* dm_contact_alloc (dm_fin_create): MS_ERR_INPUT for a periodic box narrower than 3 seeing
 * distances. dm_contact_force, after the gather: the forces into frc where they act, the step
 * into *dtmin (*imin); MS_ERR_UNSTABLE (f->bad ...) when a pair is closer than
 * DM_CONTACT_MIN_RATIO d_c. dm_contact_work, after each half kick of length h: energy −= h f·v̄. */
#define DM_CONTACT_DEFAULT 0.5 /* d_c / ℓ, the coupled region's default (dm_contact.c's head) */
#define DM_CONTACT_MAX     0.9 /* the largest accepted: below the spacing ℓ */
ms_status dm_contact_alloc(dm_fin *f);
void dm_contact_free(dm_fin *f);
ms_status dm_contact_force(dm_fin *f, double *dtmin, long *imin);
void dm_contact_work(dm_fin *f, double h, const double *vb);
double dm_contact_energy(const dm_fin *f); /* Σ energy[i] (0 when off), in dm_fin_contact_energy */

/* The thinning of a full history table of n rows of ncol doubles, in place: every other row is
 * dropped (rows 0, 2, 4, ... kept), so the rows stay evenly spaced at twice the interval, which
 * the caller doubles, and any run length fits a fixed table. Returns the kept count, n / 2. The
 * finite model's probes (dm_problem_finite.c) and the impact history (dm_impact.c). */
static inline size_t dm_rows_thin(double *rows, size_t n, size_t ncol) {
  for (size_t j = 0; j < n / 2; ++j)
    memmove(&rows[j * ncol], &rows[2 * j * ncol], ncol * sizeof *rows);
  return n / 2;
}

/* The x slab of the piston (dm_finite.c) and flyer (dm_flyer.c) problems: nx × ny × nz
 * particles of spacing h, particle i = (iz ny + iy) nx + ix (dm_flyer.c).
 * dm_slab_place: their X at the cell centres, w = u = 0, mass, volume, K = ρ0 c0², G of material
 * imat[i] of mat, free; dm_slab_create: the model (horizon × h, periodic in y and z over the
 * slab) and its dm_fin; on failure imat and s are freed (and *m, *f NULL);
 * dm_slab_layers: each x layer's mean X, x, u_x, ρ, p, q, −σ_xx, e added into lay[nx][8]. */
void dm_slab_place(dm_state *s, int dim, long nx, long ny, long nz, double h,
                   const dm_fin_material *mat, const uint8_t *imat);
ms_status dm_slab_create(dm_state *s, long ny, long nz, double h, double horizon,
                         const dm_fin_material *mat, uint8_t *imat, const dm_fin_params *par,
                         const ms_ctx *ctx, dm_model **m, dm_fin **f);
void dm_slab_layers(const dm_fin *f, const dm_state *s, long nx, long nyz, double *lay);

/* A free-surface history of fixed size: (t, mean u_x of the last x layer of an nx × nyz slab)
 * recorded every `stride`-th step; when full, every other row is dropped and the stride
 * doubled, so any run length fits (dm_finite.c). */
typedef struct dm_fs_history {
  double *rows; /* [cap][2] (owned: free) */
  size_t n, cap;
  long stride;
} dm_fs_history;
void dm_fs_history_init(dm_fs_history *h, size_t cap);
void dm_fs_history_record(dm_fs_history *h, long step, double t, const dm_state *s, long nx,
                          long nyz);

#endif
