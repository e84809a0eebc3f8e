/* SPDX-License-Identifier: MIT */
/* dm_test.h — fixtures shared by the discrete model's tests (include after <cmocka.h>):
 *  - dm_test_deck: a deck text read as `mscale run` reads it before the problem's reader (units,
 *    materials), and dm_test_deck_free;
 *  - dm_test_problem: a `discrete_model` deck text read through the model's reader (test_dm_deck.c,
 *    tests/mpi/test_dm_mpi.c);
 *  - dm_fin_body: the finite-model test body of test_dm_contact.c (two blocks) and
 *    test_dm_fracture.c (a bar): particles of Al (mg_linear ρ0 2.703, c0 5.35, s 1.34, Γ0 2.0)
 *    on a lattice of spacing h, its model (horizon 1.5 h, periodic in y over ny h when dim > 1)
 *    and dm_fin of one material. */
#ifndef MSCALE_TEST_DM_TEST_H
#define MSCALE_TEST_DM_TEST_H

#include <math.h>
#include <stdlib.h>

#include "dm.h"

/* The deck text (named `name` in the messages) read up to the problem's reader: its units and
 * materials (*mats); e is initialised here and collects the errors. */
static inline dk_doc *dm_test_deck(const char *text, const char *name, eos_materials **mats,
                                   dk_errors *e) {
  dk_errors_init(e);
  dk_doc *doc = dk_load_string(text, name, e);
  assert_non_null(doc);
  dk_read_units(doc, e);
  dk_get(dk_root(doc), "problem"); /* read, as the front end reads it */
  *mats = eos_materials_read(doc, e);
  return doc;
}

/* Frees what dm_test_deck made (e NULL: the caller keeps the errors). */
static inline void dm_test_deck_free(dk_doc *doc, eos_materials **mats, dk_errors *e) {
  eos_materials_destroy(mats);
  dk_free(doc);
  if (e) dk_errors_free(e);
}

/* A discrete_model deck text read through the model's reader (dm_test_problem_read: p is NULL
 * and e holds the errors of a bad deck), and dm_test_problem_free. */
typedef struct dm_test_problem {
  dk_doc *doc;
  eos_materials *mats;
  dm_problem *p;
  dk_errors e;
} dm_test_problem;

static inline void dm_test_problem_read(dm_test_problem *L, const char *text) {
  L->doc = dm_test_deck(text, "deck.yaml", &L->mats, &L->e);
  L->p = dm_problem_read(L->doc, dk_get(dk_root(L->doc), "discrete_model"), L->mats, &L->e);
}

static inline void dm_test_problem_free(dm_test_problem *L) {
  dm_problem_destroy(&L->p);
  dm_test_deck_free(L->doc, &L->mats, &L->e);
}

typedef struct dm_fin_body {
  dm_state s;
  dm_model *m;
  dm_fin *f;
  eos_t *eos;
  dm_fin_material mat;
  uint8_t *imat;
  long nx, ny; /* the lattice (of each block) */
  double h;
} dm_fin_body;

/* n free particles at rest at X = 0, which the caller then places (and moves, or drives): mass
 * ρ0 h^dim, bulk modulus ρ0 c0², shear modulus mat->G; b->mat is mat with the Al EOS. */
static inline void dm_fin_body_alloc(dm_fin_body *b, int dim, size_t n, long nx, long ny, double h,
                                     const dm_fin_material *mat) {
  const double rho0 = 2.703, c0 = 5.35, vol = pow(h, dim);
  b->eos = eos_create_mg_linear(rho0, c0, 1.34, 2.0);
  b->mat = *mat;
  b->mat.eos = b->eos;
  b->nx = nx, b->ny = ny, b->h = h;
  dm_state_alloc(&b->s, n, dim);
  for (size_t i = 0; i < n; ++i) {
    b->s.mass[i] = rho0 * vol, b->s.vol[i] = vol;
    b->s.K[i] = rho0 * c0 * c0, b->s.G[i] = mat->G;
    b->s.bc[i] = DM_FREE;
  }
}

/* The model and the dm_fin of the placed particles: dm_fin_create's status. */
static inline ms_status dm_fin_body_finish(dm_fin_body *b, const dm_fin_params *par) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  dm_options opt = {.horizon = 1.5 * b->h, .cond_max = 1e8};
  if (b->s.dim > 1) opt.box[1] = b->ny * b->h;
  assert_int_equal(
      dm_model_create(&(dm_model_params){.state = &b->s, .opt = opt, .ctx = &ctx}, &b->m), MS_OK);
  ms_ctx_close(&ctx);
  b->imat = calloc(b->s.n, 1);
  return dm_fin_create(&(dm_fin_setup){.m = b->m, .mat = &b->mat, .imat = b->imat, .par = *par},
                       &b->f);
}

static inline void dm_fin_body_free(dm_fin_body *b) {
  dm_fin_destroy(&b->f);
  dm_model_destroy(&b->m);
  dm_state_free(&b->s);
  free(b->imat);
  eos_destroy(&b->eos);
}

/* What the scheme conserves: K + U + E_hg + broken + contact − the piston's work. */
static inline double dm_fin_body_energy(const dm_fin_body *b) {
  double K, U, H;
  dm_fin_energies(b->f, &K, &U, &H);
  return K + U + H + dm_fin_broken_energy(b->f) + dm_fin_contact_energy(b->f) - b->f->work;
}

#endif
