/* SPDX-License-Identifier: MIT */
/* dm.h — the public header of the discrete-model library (particles/dm/). */
#ifndef MSCALE_DM_H
#define MSCALE_DM_H

#include "ptl.h"
#include "ptl_region.h"

/* The least-squares deformation-gradient particle model of [Sofronov] §1 with the exact pairwise
 * Hamiltonian force (docs/design.md §5.2; docs/particles-dm.md). Small-strain linear elasticity:
 *   A_i = Σ_k ξ_ik⊗ξ_ik,  C_i = Σ_k (w_k − w_i)⊗(A_i⁻¹ξ_ik),  E_i = sym C_i,
 *   σ_i = λ_i tr(E_i) I + 2G_i E_i,  H = Σ m_i|u_i|²/2 + Σ V_i σ_i:E_i/2,
 *   F_i = −∂H/∂w_i = Σ_{k∈N_i} (P_i + P_k) ξ_ik,  P_i = V_i σ_i A_i⁻¹   (families are symmetric).
 * dim = 1: a chain along x (σ_xx = (K + 4G/3) E_xx, = E for ν = 0); dim = 2: plane strain in x–y;
 * dim = 3: full 3D. Vectors are always stored with 3 components (unused ones stay 0). */

typedef enum dm_bc {
  DM_FREE = 0,       /* moves under the model's forces */
  DM_FIXED = 1,      /* u = 0, w held at its initial value (fixed particle layers) */
  DM_PRESCRIBED = 2, /* w(t) given by the model's prescribed-displacement callback */
  DM_MIRROR = 3      /* ghost: w = S w_partner (S = diag(msign)), a mirror image across a wall
                      * (S = −I: clamped wall, u = 0 on it) or a symmetry plane (S flips the
                      * normal component only); excluded from energies and momenta */
} dm_bc;

/* Particle data (structure of arrays; X, w, u are [n][3]). Units: cm, km/s, g, cm³, GPa. */
typedef struct dm_state {
  size_t n;
  int dim;
  double *X;         /* reference positions */
  double *w;         /* displacements */
  double *u;         /* velocities (momentum p = m u) */
  double *mass;      /* m_i */
  double *vol;       /* V_i = m_i / ρ_i⁰ */
  double *K, *G;     /* bulk and shear moduli per particle (material interfaces) */
  uint8_t *bc;       /* dm_bc */
  uint32_t *partner; /* DM_MIRROR: the real particle mirrored */
  int8_t *msign;     /* DM_MIRROR: [n][3] sign per component */
} dm_state;

void dm_state_alloc(dm_state *s, size_t n, int dim); /* zeroed arrays */
void dm_state_free(dm_state *s);

typedef struct dm_options {
  double horizon; /* δ_r (cm): N_i = {k ≠ i : |X_k − X_i| < δ_r} (periodic images included) */
  double box[3];  /* periodic length per axis, 0 = not periodic (X must lie in [0, box)) */
  double cond_max;  /* largest accepted condition number of A_i (0 → default 1e8) */
  double hourglass; /* stabilisation coefficient c_s (0 = off; docs/particles-dm.md) */
  bool ghost_rows;  /* mirror ghosts (DM_MIRROR) get no family and no shape matrix of their own:
                     * rows that the finite model fills from their partners (dm_symmetry.c) */
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
  double shift4[27][4]; /* the same, 4th lane 0 (4-lane loads, dm_finite.c) */
  size_t nbonds;
  double *Ainv;  /* [n][9] A_i⁻¹ (zero outside the dim×dim block) */
  double *cond;  /* [n] condition number of A_i */
  double *kappa; /* [n] hourglass stiffness c_s G_i V_i / tr A_i (0 when off) */
  /* Per-family references (dm_fin_rebase_local; NULL: one reference X for all, ξ_ik = X_k −
   * X_i): xref[3b..3b+2] the bond vector ξ of bond b in its family's own reference (one double
   * of padding at the end), rev[b] the bond k → i of bond b = i → k. */
  double *xref;
  size_t *rev;
  /* Work and output arrays, filled by dm_forces: */
  double *C;      /* [n][9] displacement gradient C_i (row a: ∂w_a, column b: ∂/∂X_b) */
  double *sigma;  /* [n][9] stress σ_i (symmetric; GPa) */
  double *Q;      /* [n][9] V_i σ_i A_i⁻¹ − κ_i C_i */
  double *energy; /* [n] V_i U_i (+ hourglass energy), kJ */
  dm_prescribe_fn prescribe;
  void *prescribe_user;
} dm_model;

/* What a model is built from (dm_model_create). */
typedef struct dm_model_params {
  dm_state *state; /* the particles (not owned, outlive the model; u of DM_FIXED particles is
                    * set to 0) */
  dm_options opt;
  const ms_ctx *ctx; /* set-up errors are logged here */
  size_t *first_bad; /* if not NULL: receives the first particle with a singular or
                      * ill-conditioned A_i */
} dm_model_params;
/* Builds the families with a cell list and precomputes A_i⁻¹ into *out (NULL on failure).
 * Singular or ill-conditioned A_i (too few or coplanar/collinear neighbours) are reported
 * through ctx (each with the particle's position, up to 20): MS_ERR_INPUT. Other errors: bad
 * particles or options (MS_ERR_INPUT). */
ms_status dm_model_create(const dm_model_params *par, dm_model **out);
void dm_model_destroy(dm_model **m); /* null-safe; *m = NULL */

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
/* Cauchy stress Σ_i = σ_i (I + C_iᵀ) / det(I + C_i) ([Sofronov] §1), [n][9], from the last
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
  long edge_cut, edge_cut_slab;     /* cut bonds: METIS, plain x slabs (comparison) */
  double imbalance, imbalance_slab; /* max rank weight / mean (weight = bonds + 1) */
  size_t owned, ghosts;             /* this rank */
  size_t max_owned, max_ghosts, total_ghosts, bonds;
  double partition_s;
  double exchange_s,
      exchanged_doubles; /* this rank: wall time in ghost exchanges, doubles received */
} dm_dist_stats;
typedef struct dm_dist_diag {
  double kinetic, potential; /* kJ, non-mirror particles */
  double hourglass, dw_norm; /* as dm_hourglass_norm (sums per particle, then in global order) */
} dm_dist_diag;
typedef struct dm_dist_params {
  dm_model *global;  /* the replicated global model (not owned; dm_dist_release_global frees
                      * its families) */
  const ms_ctx *ctx; /* rank, size and the log */
} dm_dist_params;
/* The global model's prescribe callback must be set before this (it is copied). Collective:
 * every rank gets the same status (*out NULL on failure). */
ms_status dm_dist_create(const dm_dist_params *par, dm_dist **out);
void dm_dist_destroy(dm_dist **d);   /* null-safe; *d = NULL */
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

/* Exact reference solutions of [Sofronov] §5 (units g, cm, 10 µs). */
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
void dm_exact_sphere(double r, double t, double r0, double w0, double period, double cl, double *w,
                     double *u);

/* Deck problem type `discrete_model` (docs/input-dm.md). */
typedef struct dm_problem dm_problem;
dm_problem *dm_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                            dk_errors *e);
ms_status dm_problem_run(ms_ctx *ctx, dm_problem *p);
void dm_problem_destroy(dm_problem **p); /* null-safe; sets *p = NULL */

/* What a run measured (also written to the log and to OUTDIR/dm_summary.csv). Fields that do
 * not apply to the deck's problem are NaN. */
typedef struct dm_run_summary {
  size_t particles, bonds; /* all particles incl. ghosts / fixed layers; bonds = Σ|N_i| */
  size_t real_particles;   /* the lattice inside the domain (the ones that are timed) */
  long steps;
  double dt, t_end;
  double omega_dt; /* ω_max Δt (power iteration) vs the scheme's stability limit */
  double wall_s, particle_steps_per_s; /* time-stepping loop only (real particles) */
  double cpu_s;          /* process CPU time of that loop, all threads (load-independent) */
  double energy_err_max; /* max |H(t) − H(0)| / H(0) over the energy samples */
  /* zero-energy-mode indicator |z|(t) / max_t |Δw|(t) (dm_hourglass_norm) at the energy
   * samples: first, largest and last value */
  double hourglass_first, hourglass_max, hourglass_last;
  double amp_err, phase_err; /* rod, over the last 10 L/c of w(x_probe, t): A − 1 and s (units
                               * of L/c) of the least-squares fit w ≈ A·w_exact(t − s) */
  double peak_err;           /* rod: (max|w| − max|w_exact|)/max|w_exact| (includes ringing) */
  double rms_err;            /* rod: rms(w − w_exact)/max|w_exact| over that window, no fit */
  double err_l1, err_l2, err_max;    /* contact: σ_xx at t_end; sphere: radial w at t_end; all
                                   * relative to the exact solution's maximum */
  double err_u_l2;                   /* sphere: radial velocity, L2, relative to u0 = w0 ω */
  double kinetic_end, potential_end; /* energies at t_end (kJ) */
  int ranks;                         /* MPI ranks of the run; partition quality (dm_dist_stats): */
  long edge_cut, edge_cut_slab;
  double imbalance, imbalance_slab;
  long restart_step; /* step the run continued from (0: a fresh start) */
} dm_run_summary;
const dm_run_summary *dm_problem_summary(const dm_problem *p);
/* Global displacements and velocities ([n][3], particle order) at the end of the last run
 * (the same on every rank); returns n (0 before a run). */
size_t dm_problem_final_state(const dm_problem *p, const double **w, const double **u);

/* ---- the discrete model at finite deformation (dm_finite.c, docs/particles-dm.md §Finite) ----
 * F_i = I + Σ_k (w_k − w_i) ⊗ g_ik = Σ_k (x_k − x_i) ⊗ g_ik, Ḟ_i = Σ_k (u_k − u_i) ⊗ g_ik,
 * L = Ḟ F⁻¹, J = det F, ρ = ρ0/J, σ = −(p(ρ, e) + q) I + s, P = J σ F⁻ᵀ, force
 * f_i = Σ_k (Q_i + Q_k) ξ_ik with Q_i = V_i P_i A_i⁻¹ − κ_i C_i (+ the bond penalty
 * (κ_i + κ_k) Δw_ik), m_i ė_i = V_i P_i : Ḟ_i(ū) with ū the time-centred velocity of each half
 * kick of velocity Verlet: Σ m|u|²/2 + Σ m e + E_hg − W_piston is conserved to round-off. */
typedef enum dm_yield {
  DM_YIELD_NONE = 0,
  DM_YIELD_ELASTIC_PLASTIC = 1,
  DM_YIELD_STEINBERG_GUINAN = 2, /* G(P, T), Y(ε_p, P, T), melt (dm_strength.c) */
  DM_YIELD_JOHNSON_COOK = 3      /* G0, Y(ε_p, ε̇, T) (dm_strength.c) */
} dm_yield;
typedef struct dm_sg dm_sg; /* Steinberg–Guinan parameters (dm_impl.h) */
/* Fracture (dm_fracture.c, docs/particles-dm.md "Fracture"): a particle fails for good when its
 * tensile stress reaches the spall strength σ_s (criterion: the mean stress tr σ/3 or the
 * largest principal stress), or, with failure_strain > 0, when J − 1 reaches it. A failed
 * particle carries no stress of its own (no F, no EOS) and no bond penalty; a bond is broken
 * when both its particles have failed, and across a broken bond only a compression-only central
 * pair force (contact) acts. */
typedef enum dm_fracture_model {
  DM_FRACTURE_NONE = 0,
  DM_FRACTURE_MEAN_STRESS = 1,     /* tr σ/3 ≥ σ_s */
  DM_FRACTURE_PRINCIPAL_STRESS = 2 /* max eigenvalue of σ ≥ σ_s */
} dm_fracture_model;
typedef struct dm_fracture {
  int model;             /* dm_fracture_model (0: no fracture) */
  double spall_strength; /* σ_s (GPa), > 0 */
  double failure_strain; /* ε_f (volumetric, J − 1); 0: not used */
} dm_fracture;
typedef struct dm_fin_material {
  const eos_t *eos; /* not owned */
  int yield;        /* dm_yield */
  double G, Y0;     /* shear modulus, yield stress (GPa); G0, Y0 for steinberg_guinan */
  const dm_sg *sg;  /* steinberg_guinan, johnson_cook: its parameters (not owned), else NULL */
  dm_fracture frac; /* zero: no fracture */
} dm_fin_material;
/* Symmetry planes of the finite-deformation model (dm_symmetry.c, docs/particles-dm.md
 * "Symmetry planes"): x_axis[j] = pos[j], j < n, distinct axes; the model holds the particles on
 * the + side of every plane (and on the planes) and mirror ghosts of those within the horizon. */
typedef struct dm_sym_planes {
  int n;
  int axis[3];
  double pos[3];
} dm_sym_planes;
typedef struct dm_fin_params {
  double cq, cl;    /* quadratic and linear viscosity coefficients */
  double courant;   /* dt = courant · min_i ℓ_i / (c_L + 2 ν_q / ℓ_i) */
  double hourglass; /* bond-penalty coefficient c_s: κ_i = c_s M_i V_i / tr A_i (0 = off) */
  double ell;       /* particle spacing ℓ (cm) */
  double contact;   /* short-range contact distance d_c / ℓ between particles not in each
                       other's family (dm_contact.c; 0 = off) */
} dm_fin_params;
struct dm_fin;
/* An external force on the particles (dm_impact.c's rigid wall): fills fext [n][3] at the
 * current configuration (w, u of f->m->s) and returns its stable time step (INFINITY: none). */
typedef double (*dm_fin_ext_fn)(void *user, const struct dm_fin *f, double *fext);
typedef struct dm_fin {
  dm_model *m; /* not owned; families, A⁻¹; m->Q holds the gather's Q, transposed */
  size_t n;
  int dim;
  const dm_fin_material *mat; /* not owned */
  const uint8_t *imat;        /* [n] material of each particle (not owned) */
  dm_fin_params par;
  double *e, *rho, *p, *q, *J, *eps_p, *ehg; /* [n]: e (kJ/g), ρ, p, q (GPa), det F, ε_p,
                                                accumulated bond-penalty energy (kJ) */
  double *F, *s, *QP, *sig;                  /* [n][9]: F, deviator s, V P A⁻¹, Cauchy σ */
  double *frc, *vbar;                        /* [n][3] */
  /* The closing half kick's energies (of length h_close, mean velocity vclose [n][3]) are left
   * pending by dm_fin_advance and added by the next step's stress pass (at the same QP, F and
   * w, so the same bits) or by dm_fin_flush; keep_e, keep_ehg (optional, [n]): where that pass
   * also writes e and e_hg with them added, i.e. of the state at the start of its step (a
   * backup of that state, dm_fin_run.h). */
  double *vclose, h_close, *keep_e, *keep_ehg;
  bool pending;
  double work; /* work done by driven (DM_PRESCRIBED/DM_FIXED) particles (kJ) */
  /* fracture (dm_fracture.c; NULL when no material has a fracture model): failed[i] = 1 once
   * particle i failed; broken[i] the bond-penalty energy it held then (kJ), taken out of E_hg;
   * the contact of failed particles across their broken bonds: kcon[i] its share of a broken
   * bond's contact stiffness, dtcon[i] its stable step, fcon [n][3] the contact force of the
   * last evaluation, econ[i] the contact energy (kJ, the pair forces' work booked with each half
   * kick's time-centred velocity), lcon [bonds] the contact's rest length of each broken bond
   * (−1 while not broken; nlcon = the model's bond count), gcon [bonds] its dashpot force of the
   * last evaluation, dtclose[i] its closing-speed step of the last evaluation; lam_end[256]
   * per material index: the smallest r/L at which its EOS springs are finite (0: none).
   * A bond is broken when either of its particles has failed: it leaves the intact one's F,
   * stress and force, and its compression is the contact's (docs/particles-dm.md "Fracture").
   * fresh[i] = 1: failed in the stress pass under way (committed by dm_frac_commit after it);
   * cut[i] = 1: i has a broken bond (failed, or a failed family member); nintact[i] its intact
   * family members (failed: 0); fq [n], fmark [n]: dm_frac_commit's work list and marks */
  uint8_t *failed, *fresh, *cut, *fmark;
  /* failures by cause since set-up (diagnostics, not checkpointed): the criterion of
   * dm_frac_stress, the isolated-particle rule, a degenerate F (dm_frac_degenerate) */
  long nfail_stress, nfail_isolated, nfail_degenerate;
  uint32_t *nintact;
  size_t *fq;
  double *broken;
  double *kcon, *dtcon, *fcon, *econ, *lcon, *gcon, *dtclose, *lam_end;
  size_t nlcon;
  struct dm_contact *sr; /* the short-range contact (dm_contact.c; NULL when par.contact = 0) */
  double dt_next;
  size_t dt_particle; /* the particle whose stable step is dt_next (smallest index of ties) */
  long step;
  size_t bad;           /* on MS_ERR_UNSTABLE: the particle */
  const char *bad_what; /* and the quantity */
  double bad_value;
  /* optional external force (dm_fin_set_external): added to frc at every force evaluation;
   * its work on the free particles, with the half kick's time-centred velocity, is ext_work,
   * so K + U + E_hg − work − ext_work is conserved to round-off */
  dm_fin_ext_fn ext;
  void *ext_user;
  double *fext; /* [n][3] the external force of the last evaluation (NULL without one) */
  double ext_work;
  /* symmetry planes (dm_symmetry.c; sym.n = 0: none): the state holds the n real particles,
   * then mirror ghosts up to nall = m->s->n, filled from their partners at every evaluation
   * (w, u, v̄ by the reflection M, Q by M Q M, κ, failed); fold[i] the size of particle i's
   * orbit (2 per plane it is off, 1 per plane it lies on), the weight that makes every sum over
   * the real particles a sum over the full body (energies, works, momenta); onplane [nonplane]:
   * 3 i + axis of each particle component held on a plane (u_axis = 0, its force dropped);
   * imat_all [nall]: the materials with the ghosts' rows (f->imat points to it) */
  dm_sym_planes sym;
  size_t nall, nonplane;
  double *fold;
  size_t *onplane;
  uint8_t *imat_all;
} dm_fin;
/* What a finite-deformation model is built from (dm_fin_create). */
typedef struct dm_fin_setup {
  dm_model *m;                /* families and A⁻¹ (not owned; its κ and hourglass are set) */
  const dm_fin_material *mat; /* not owned */
  const uint8_t *imat;        /* [n] material of each particle (not owned) */
  dm_fin_params par;
  dm_sym_planes sym; /* symmetry planes (n = 0: none); the state's mirror ghosts, from
                      * dm_sym_ghosts, follow its real particles */
} dm_fin_setup;
/* Driven particles (DM_PRESCRIBED, DM_FIXED) keep their velocity u; mirror ghosts without
 * symmetry planes (or not after the real particles, or with a velocity normal to a plane they lie
 * on) and bad parameters are not accepted (MS_ERR_INPUT). e starts at eos_e0. Computes the first forces
 * and dt_next (their status on failure). *out is NULL on failure. */
ms_status dm_fin_create(const dm_fin_setup *setup, dm_fin **out);
void dm_fin_destroy(dm_fin **f); /* null-safe; *f = NULL */
/* One kick–drift–kick step of length f->dt_next; MS_ERR_UNSTABLE (f->bad, f->bad_what) when a
 * J ≤ 0 or a non-finite e, p or force appears: the state is then the one of the bad step. */
ms_status dm_fin_step(dm_fin *f);
/* The same step, its closing half kick's energies left pending (f->pending): e and e_hg lack
 * them until dm_fin_flush or the next step (which adds them in its stress pass, saving a pass
 * over the bonds). dm_fin_step = dm_fin_advance + dm_fin_flush. */
ms_status dm_fin_advance(dm_fin *f);
/* Adds the pending half kick's energies (nothing pending: no-op); MS_ERR_UNSTABLE on a
 * non-finite e. Call before reading e or e_hg after dm_fin_advance. */
ms_status dm_fin_flush(dm_fin *f);
/* Installs an external force (NULL: none) and recomputes the forces and dt_next at the current
 * state (no deviator step). */
ms_status dm_fin_set_external(dm_fin *f, dm_fin_ext_fn fn, void *user);
/* Recomputes stresses, forces and dt_next at the current state without advancing the deviator
 * (after a change of the model's families: dm_refamily.c). */
ms_status dm_fin_refresh(dm_fin *f);
/* The bond-penalty stiffness κ_i = c_s M_i V_i / tr A_i of every particle from f->m's families
 * (M = ρ0 c0² + 4G/3 of the particle's material). */
void dm_fin_bond_penalty(dm_fin *f);
/* Reference-configuration update (dm_refamily.c, docs/particles-dm.md "Reference update"):
 * the largest bond stretch max(|x_k − x_i|/|ξ_ik|, |ξ_ik|/|x_k − x_i|) over all bonds (≥ 1; the
 * particle in *where), the trigger of an update; and the update itself, X ← x, w ← 0, V ← J V,
 * families and A⁻¹ rebuilt on the current configuration (deviator, ε_p, e, u kept). f->m is
 * replaced by the new model (the old one is destroyed: the caller destroys f->m at the end).
 * A degenerate new family (cond A > cond_max) refuses the update: the old state is restored,
 * rep->bad names the particle and MS_ERR_UNSTABLE is returned. Not with fracture (f->failed:
 * the contact's per-bond state belongs to the old families): MS_ERR_INTERNAL, nothing changed. */
typedef struct dm_refamily_report {
  double released;   /* the bond penalty's stored energy Σ κ|z|²/2 given up (kJ) */
  double jmin, jmax; /* range of J = V_new/V_old */
  size_t bonds;      /* bonds of the new families */
  size_t bad;        /* on refusal: the first particle with a degenerate family */
  size_t families;   /* dm_fin_rebase_local: the families updated (0: none passed the trigger) */
  size_t gained;     /* dm_fin_rebase_local: the others that gained bonds (merge) */
  bool uncovered;    /* refused: rep->bad's mirror image within the horizon has no ghost */
} dm_refamily_report;
double dm_fin_max_stretch(const dm_fin *f, size_t *where); /* per-family refs: their own ξ */
ms_status dm_fin_reference_update(dm_fin *f, const ms_ctx *ctx, dm_refamily_report *rep);
/* The reference update with the families kept (dm_refamily.c, docs/particles-dm.md "Reference
 * update"): X ← x, w ← 0, V ← J V and A⁻¹, κ from the same bonds' current vectors, so the bond
 * penalty's mismatch z restarts from 0; its stored energy Σ κ|z|²/2 moves into each particle's
 * e (rep->released). Never degenerate while J > 0 unless cond(F A Fᵀ) > cond_max (then refused
 * as above). merge: each family also gains the particles now within the horizon (the union
 * with the current configuration's families, symmetric). Not with fracture: MS_ERR_INTERNAL.
 * Symmetry planes: the set-up's ghosts kept (X, V from their partners); a merge that needs an
 * image without a ghost is refused (MS_ERR_UNSTABLE, rep->uncovered, rep->bad). */
ms_status dm_fin_rebase(dm_fin *f, const ms_ctx *ctx, bool merge, dm_refamily_report *rep);
/* The per-family reference update (dm_fin_local.c, docs/particles-dm.md "Reference update"):
 * only the families whose own largest bond stretch exceeds 1 + threshold move their reference
 * to the current configuration (their bond vectors, V ← J V, A⁻¹, κ; the stored penalty energy
 * into e), each family keeping its own bond vectors from then on (m->xref); merge: they also
 * bond the particles now within the horizon (symmetrically; the partner's new bond pulled back
 * through its F). rep->families = 0: nothing passed the trigger, nothing changed. Refused as
 * dm_fin_rebase (MS_ERR_UNSTABLE, rep->bad, nothing changed; rep->uncovered: with symmetry
 * planes a mirror image that a merge needs has no ghost); MS_ERR_INTERNAL with fracture, the
 * short-range contact or a periodic box. Once called, dm_fin_rebase and
 * dm_fin_reference_update refuse (MS_ERR_INTERNAL). */
ms_status dm_fin_rebase_local(dm_fin *f, const ms_ctx *ctx, double threshold, bool merge,
                              dm_refamily_report *rep);
/* Switches f to per-family references (each family's vectors = the shared reference's, so
 * nothing changes but the kernels' round-off order) without updating any family; done by the
 * first dm_fin_rebase_local that updates. MS_ERR_INTERNAL for asymmetric families. */
ms_status dm_fin_local_init(dm_fin *f);
/* Symmetry planes (dm_symmetry.c): dm_sym_ghosts (re)builds the mirror ghosts of a state whose
 * first nreal rows are the real particles (on the + side of every plane or on it): the images
 * under every product of the planes' reflections of the real particles within `reach` of each
 * plane involved (none for a particle on such a plane: it is its own image), appended after the
 * real rows (the arrays reallocated; bc = DM_MIRROR, partner, msign, X = the mirrored X, mass,
 * vol, K, G copied; w, u filled by dm_sym_sync). Returns the ghost count. dm_sym_on_plane: is
 * coordinate x on the plane at pos (within 1e-9 of the spacing ell)? dm_fin_fold: particle i's
 * weight in a full-body sum. dm_fin_momentum: the full body's Σ m u (components normal to a plane
 * 0: the orbits cancel them). dm_sym_sync: the ghost rows from their partners (w, u, v̄, v_close,
 * Q, κ, failed). */
size_t dm_sym_ghosts(dm_state *s, size_t nreal, const dm_sym_planes *pl, double reach, double ell);
bool dm_sym_on_plane(double x, double pos, double ell);
/* The mirror ghosts' X and V from their partners' (a moved reference on a ghost set kept). */
void dm_sym_reference(dm_state *s, size_t nreal, const dm_sym_planes *pl);
static inline double dm_fin_fold(const dm_fin *f, size_t i) { return f->fold ? f->fold[i] : 1.0; }
void dm_fin_momentum(const dm_fin *f, double P[3]);
void dm_sym_sync(dm_fin *f);
/* Energies: kinetic of free particles, internal Σ m e, the bond penalty's (kJ); with symmetry
 * planes of the full body (dm_fin_fold). */
void dm_fin_energies(const dm_fin *f, double *kinetic, double *internal, double *hourglass);
/* Fracture (dm_fracture.c): the energy booked as broken (Σ broken[i], kJ), the contact energy
 * of failed particles (Σ econ[i], kJ; the accumulated work of the pair forces) and the contact
 * potential Σ_pairs κ (|ξ| − |y|)²/2 of the current configuration (kJ; equal to the contact
 * energy up to the integrator's O(dt²)), the number of failed particles, and whether bond (i, k)
 * is broken (either failed: no tension or shear across it, only the contact's compression; so a
 * failed particle is a fragment of its own). K + U + E_hg + broken + contact − W is conserved to round-off. All
 * 0/false without fracture. */
double dm_fin_broken_energy(const dm_fin *f);
double dm_fin_contact_energy(const dm_fin *f);
double dm_fin_contact_potential(const dm_fin *f);
size_t dm_fin_failed_count(const dm_fin *f);
static inline bool dm_fin_bond_broken(const dm_fin *f, size_t i, size_t k) {
  return f->failed && (f->failed[i] || f->failed[k]);
}
/* Checkpoints (dm_fin_checkpoint.c): every array a step reads (the external force and its work
 * too, when one is installed) and the state's w, u, under
 * `group` of a checkpoint file (serial or collective; on ranks every rank calls it, `owner`
 * on the one rank whose rows are written), and back into a model built for the same particles
 * (same n; a mismatch is an error in e). */
ms_status dm_fin_checkpoint_write(const dm_fin *f, const dm_state *s, ms_h5 *h, const char *group,
                                  bool owner);
ms_status dm_fin_checkpoint_read(dm_fin *f, dm_state *s, ms_h5r *h, const char *group,
                                 dk_errors *e);
/* The families of a model that kept or merged them at reference updates, or has per-family
 * references (dm_family_checkpoint.c): the bond lists, the bond vectors ξ_b (m->xref), A⁻¹, cond
 * and κ of every row (mirror ghosts included) under `group`, and back into a model of the same
 * particles (the lists, xref, rev and the shapes replaced; a mismatch is an error in e). */
ms_status dm_families_checkpoint_write(const dm_model *m, ms_h5 *h, const char *group, bool owner);
ms_status dm_families_checkpoint_read(dm_model *m, ms_h5r *h, const char *group, dk_errors *e);
/* m->rev from the lists (dm_fin_local.c); MS_ERR_INTERNAL for asymmetric families. */
ms_status dm_fin_local_rev(dm_model *m);
/* Rows of a checkpoint's [rows][ncol] dataset `name` into dst: exactly nmax rows when `exact`,
 * else at most nmax (their number in *nrow, may be NULL); any other shape is an error in e. */
ms_status dm_ckpt_read_rows(ms_h5r *h, const char *name, size_t ncol, size_t nmax, bool exact,
                            double *dst, size_t *nrow, dk_errors *e);

/* A piston driving a planar shock into a slab along x (dm_finite.c): nx × ny × nz simple-cubic
 * lattice (spacing h, periodic in y, z), the first npiston x layers move at up. */
typedef struct dm_piston_spec {
  int dim;
  long nx, ny, nz, npiston;
  double h, horizon; /* horizon in spacings */
  dm_fin_material mat;
  dm_fin_params par;
  double up, t_end;
  int nsamples; /* front positions recorded at nsamples equal times in (t_end/2, t_end] */
} dm_piston_spec;
typedef struct dm_piston_result {
  double D, P, rho, e; /* shock speed (fit of the front's Lagrangian position), −σ_xx, ρ, e
                              averaged over the shocked layers between 30 % and 80 % of the way
                              from the piston to the front at t_end */
  double energy_err;   /* max |K + U + E_hg − W − E0| / W over the run */
  double work;         /* piston work at t_end (kJ) */
  double hg_ratio;     /* E_hg / W at t_end (zero-energy-mode indicator) */
  double sxx_max;      /* largest −σ_xx of the layer profile at t_end (overshoot) */
  long steps;
  ms_status status;
  /* layer profile at t_end (nx rows, each averaged over the layer): X, x, u_x, ρ, p, q, −σ_xx, e */
  double *profile; /* [nx][8], owned by the caller (free) */
  double *eps_p;   /* [nx] layer mean of the plastic strain at t_end (inside profile's block) */
} dm_piston_result;
ms_status dm_piston_run(const dm_piston_spec *spec, const ms_ctx *ctx, dm_piston_result *res);

/* The finite-deformation model as the coupled problem's particle region (dm_region.c;
 * ptl_region.h, deck name `discrete_model`, docs/particles-dm.md "As the coupled problem's
 * particle region"). */
const ptl_region_model *dm_region_model_get(void);

/* A flyer onto a target along x (dm_flyer.c): two bodies in contact at t = 0, a flyer of
 * nflyer x layers (material mat[0], velocity u[0] along x) and a target of ntarget layers
 * (mat[1], u[1]), nx × ny × nz simple-cubic lattice (spacing h), both x ends free, periodic in
 * y and z. No driven particles: K + U + E_hg is conserved. */
typedef struct dm_flyer_spec {
  int dim;
  long nflyer, ntarget, ny, nz;
  double h, horizon; /* horizon in spacings */
  dm_fin_material mat[2];
  double u[2]; /* initial x velocities of flyer and target (km/s) */
  dm_fin_params par;
  double t_end;
  size_t nhist; /* rows of the free-surface history kept (>= 2; thinned by 2 when full) */
} dm_flyer_spec;
typedef struct dm_flyer_result {
  double K0;         /* initial kinetic energy (kJ) */
  double energy_err; /* max |K + U + E_hg − E0| / K0 over the run */
  double hg_ratio;   /* E_hg / K0 at t_end (zero-energy-mode indicator) */
  long steps;
  ms_status status;
  double *hist; /* [nhist][2]: t, mean u_x of the target's last x layer (owned: free) */
  size_t nhist;
  double *profile; /* [nx][8] layer means at t_end: X, x, u_x, ρ, p, q, −σ_xx, e (free) */
  /* fracture (a material with frac.model; energy_err then includes the broken term) */
  double broken;         /* broken energy at t_end (kJ) */
  size_t nfailed;        /* failed particles at t_end */
  double t_fail, X_fail; /* time of the first failure and the mean X of the particles failing
                            then (NaN: none) */
  double *failed_layer;  /* [nx] fraction of each x layer failed at t_end (free; NULL without) */
} dm_flyer_result;
ms_status dm_flyer_run(const dm_flyer_spec *spec, const ms_ctx *ctx, dm_flyer_result *res);

/* Deck problem type `impact` (dm_impact*.c, docs/input-impact.md): bodies (cylinder, sphere,
 * box) of the finite-deformation model with their own materials and initial velocities onto a
 * rigid frictionless wall (a penalty on the particles crossing its contact plane), free
 * surfaces, optional reference-configuration updates; energy and momentum balance, the length
 * and footprint of a cylinder standing on the wall (the Taylor anvil test); checkpoints and
 * restart (dm_impact_checkpoint.c); replicated on MPI ranks (dm_impact_run.h). */
typedef struct dm_impact dm_impact;
dm_impact *dm_impact_problem_read(dk_doc *doc, const dk_node *section, const eos_materials *mats,
                                  dk_errors *e);
ms_status dm_impact_problem_run(ms_ctx *ctx, dm_impact *p);
void dm_impact_problem_destroy(dm_impact **p); /* null-safe; sets *p = NULL */
/* heights, as fractions of the final length, of the Taylor profile in dm_impact_summary */
#define DM_TAYLOR_PROFILE_N 3
#define DM_TAYLOR_PROFILE_F                                                                        \
  { 0.2, 0.5, 2.0 / 3.0 }
typedef struct dm_impact_summary {
  size_t particles, bonds;
  long steps, ref_updates;
  double t_end, wall_s;
  double E0;           /* initial energy K + U + E_hg (kJ) */
  double energy_err;   /* max_t |K + U + E_hg − W_wall − E0| / E0 (round-off) */
  double wall_err;     /* max_t |W_wall + E_wall| / E0: the penalty's time-discretisation error */
  double hg_ratio;     /* E_hg / E0 at the end */
  double released;     /* bond-penalty energy given up at reference updates (kJ) */
  double p_transverse; /* max_t of the change of Σ m u along the wall plane / |Σ m u(0)| */
  double stretch_max;  /* largest bond stretch (dm_fin_max_stretch) over the history samples */
  double J_min, J_max; /* range of J = det F over the history samples */
  double p_normal;     /* Σ m u · n at the end / |Σ m u(0)|, n the wall normal into the bodies
                          (> 0: rebound) */
  double length0, length;       /* body 0, a cylinder along the wall normal: axial extent (cm) */
  double footprint0, footprint; /* and the largest diameter of its outer particles (cm); NaN
                                   when body 0 is not such a cylinder */
  double radius_at[DM_TAYLOR_PROFILE_N]; /* its surface radius (cm) at DM_TAYLOR_PROFILE_F of
                                            the final length from the face (dm_impact.c) */
  double broken;  /* energy booked as broken at failures (dm_fracture.c) at the end (kJ) */
  size_t failed;  /* failed particles at the end */
  double p_total; /* max_t |Σ m u − Σ m u(0)| / Σ m |u(0)|: with no wall every force is
                     pairwise, so round-off */
  double p0_body0, p_body0; /* body 0's momentum along its initial velocity, at 0 and at the
                               end (g·km/s) */
} dm_impact_summary;
const dm_impact_summary *dm_impact_get_summary(const dm_impact *p);

#endif /* MSCALE_DM_H */
