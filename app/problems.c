/* SPDX-License-Identifier: MIT */
/* The problem types a deck can describe (`problem:` at top level) and the deck → materials →
 * problem reading that `run` and `check` share. Each problem type is a module's
 * read/run/free triple; its deck section has the same name as the type. */
#include "cd.h"
#include "commands.h"
#include "cont.h"
#include "cont2d.h"
#include "cpl.h"
#include "dm.h"

#include <stdlib.h>
#include <string.h>

typedef void *(*problem_read_fn)(dk_doc *, const dk_node *, const eos_materials *, dk_errors *);
typedef ms_status (*problem_run_fn)(ms_ctx *, void *);
typedef void (*problem_destroy_fn)(void **); /* null-safe, sets the pointer to NULL */

typedef struct problem_type {
  const char *name, *summary;
  bool restartable; /* reads ctx->restart (`mscale run --restart`) */
  problem_read_fn read;
  problem_run_fn run;
  problem_destroy_fn destroy;
} problem_type;

/* Built in: Hugoniot curves of deck materials (app/problem_hugoniot.c). */
void *hugoniot_problem_read(dk_doc *, const dk_node *, const eos_materials *, dk_errors *);
ms_status hugoniot_problem_run(ms_ctx *, void *);
void hugoniot_problem_destroy(void **);

static const problem_type problem_types[] = {
    {"hugoniot", "shock Hugoniots of deck materials (CSV + plot data)", false,
     hugoniot_problem_read, hugoniot_problem_run, hugoniot_problem_destroy},
    {"continuum", "1D Lagrangian gas dynamics (cross scheme)", false,
     (problem_read_fn)cont_problem_read, (problem_run_fn)cont_problem_run,
     (problem_destroy_fn)cont_problem_destroy},
    {"grid2d", "2D Lagrangian quad grid, compatible discretisation (x-y, r-z)", false,
     (problem_read_fn)c2d_problem_read, (problem_run_fn)c2d_problem_run,
     (problem_destroy_fn)c2d_problem_destroy},
    {"cluster_dynamics", "cluster dynamics particles (pair potentials from the cold curve)", true,
     (problem_read_fn)cd_problem_read, (problem_run_fn)cd_problem_run,
     (problem_destroy_fn)cd_problem_destroy},
    {"discrete_model", "Hamiltonian discrete particle model with symplectic RKN schemes", true,
     (problem_read_fn)dm_problem_read, (problem_run_fn)dm_problem_run,
     (problem_destroy_fn)dm_problem_destroy},
    {"impact", "bodies of the finite-deformation discrete model onto a rigid wall (Taylor test)",
     true, (problem_read_fn)dm_impact_problem_read, (problem_run_fn)dm_impact_problem_run,
     (problem_destroy_fn)dm_impact_problem_destroy},
    {"coupled", "grid-driven particles: ejecta, fragment spectra, drag and transport", true,
     (problem_read_fn)cpl_problem_read, (problem_run_fn)cpl_problem_run,
     (problem_destroy_fn)cpl_problem_destroy},
    {"coupled2d", "2D grid, then particles driven column by column from its tagged node line",
     false, (problem_read_fn)cpl2d_problem_read, (problem_run_fn)cpl2d_problem_run,
     (problem_destroy_fn)cpl2d_problem_destroy},
};
enum { N_PROBLEM_TYPES = sizeof problem_types / sizeof problem_types[0] };

void app_print_problem_types(FILE *f) {
  for (int i = 0; i < N_PROBLEM_TYPES; i++)
    fprintf(f, "  %-18s %s\n", problem_types[i].name, problem_types[i].summary);
}

bool app_apply_set(dk_doc *doc, const char *arg, dk_errors *e) {
  const char *eq = strchr(arg, '=');
  if (!eq) {
    dk_error_at(e, "--set", 0, 0, "'%s': expected PATH=VALUE, e.g. --set continuum.time.end=0.1",
                arg);
    return false;
  }
  char *path = ms_calloc((size_t)(eq - arg) + 1, 1);
  memcpy(path, arg, (size_t)(eq - arg));
  bool ok = dk_set(doc, path, eq + 1, e);
  free(path);
  return ok;
}

ms_status app_deck_read(const char *path, app_deck *d, dk_errors *e) {
  return app_deck_read_set(path, NULL, 0, d, e);
}

ms_status app_deck_read_set(const char *path, const char *const *sets, size_t nsets, app_deck *d,
                            dk_errors *e) {
  memset(d, 0, sizeof *d);
  d->problem_kind = -1;
  d->doc = dk_load(path, e);
  if (!d->doc) return MS_ERR_INPUT;
  for (size_t i = 0; i < nsets; i++) app_apply_set(d->doc, sets[i], e);
  dk_read_units(d->doc, e);
  const dk_node *root = dk_root(d->doc);

  const char *names[N_PROBLEM_TYPES + 1];
  for (int i = 0; i < N_PROBLEM_TYPES; i++) names[i] = problem_types[i].name;
  names[N_PROBLEM_TYPES] = NULL;
  int kind = -1;
  bool kind_ok = dk_read_enum(e, d->doc, root, "problem", true, 0, names, &kind);

  d->mats = eos_materials_read(d->doc, e);
  if (kind_ok && d->mats) {
    const problem_type *pt = &problem_types[kind];
    const dk_node *section = dk_get(root, pt->name);
    if (!section)
      dk_error(e, d->doc, root, "problem '%s' needs a top-level '%s:' section", pt->name, pt->name);
    else if (dk_expect_map(e, d->doc, section, pt->name)) {
      d->problem = pt->read(d->doc, section, d->mats, e);
      d->problem_kind = kind;
    }
  }
  /* Keys written for other problem types or misspelt: report them all. If `problem:` or
   * `materials:` had errors, the problem sections were not read: their keys are not unknown. */
  if (d->problem_kind < 0)
    for (int i = 0; i < N_PROBLEM_TYPES; i++) dk_mark_used(root, problem_types[i].name);
  dk_report_unused(e, d->doc);
  return e->n ? MS_ERR_INPUT : MS_OK;
}

bool app_deck_restartable(const app_deck *d) {
  return d->problem_kind >= 0 && problem_types[d->problem_kind].restartable;
}

ms_status app_deck_run(ms_ctx *ctx, app_deck *d) {
  if (d->problem_kind < 0 || !d->problem) return MS_ERR_INTERNAL;
  return problem_types[d->problem_kind].run(ctx, d->problem);
}

void app_deck_free(app_deck *d) {
  if (d->problem_kind >= 0) problem_types[d->problem_kind].destroy(&d->problem);
  eos_materials_destroy(&d->mats);
  dk_free(d->doc);
  memset(d, 0, sizeof *d);
}

const char *app_deck_checkpoint_name(const app_deck *d) {
  /* the names the problems write (docs/mpi.md "Checkpoint / restart") */
  static const char *const names[][2] = {{"cluster_dynamics", "cd_checkpoint.h5"},
                                         {"discrete_model", "dm_checkpoint.h5"},
                                         {"impact", "impact_checkpoint.h5"},
                                         {"coupled", "coupled_checkpoint.h5"}};
  if (d->problem_kind < 0) return NULL;
  for (size_t k = 0; k < sizeof names / sizeof names[0]; k++)
    if (!strcmp(problem_types[d->problem_kind].name, names[k][0])) return names[k][1];
  return NULL;
}
