/* Subcommands of the mscale front end (docs/design.md §8). Each returns the process exit code:
 * 0 success, 1 the run failed, 2 bad usage or bad input. */
#ifndef MSCALE_APP_COMMANDS_H
#define MSCALE_APP_COMMANDS_H

#include "core.h"
#include "eos.h"

int cmd_run(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_hugoniot(int argc, char **argv);
int cmd_spectrum(int argc, char **argv);
int cmd_export(int argc, char **argv);

/* A deck read completely: the tree, the materials and the problem the deck describes. */
typedef struct app_deck {
  dk_doc *doc;
  eos_materials *mats;
  int problem_kind; /* index into the problem table (app/problems.c) */
  void *problem;    /* the module's problem object */
} app_deck;

/* Load, read and validate a deck; every error goes to *e. Returns MS_OK only if *e is empty. */
ms_status app_deck_read(const char *path, app_deck *d, dk_errors *e);
ms_status app_deck_run(ms_ctx *ctx, app_deck *d);
/* True if the deck's problem type can continue from a checkpoint (`run --restart`). */
bool app_deck_restartable(const app_deck *d);
void app_deck_free(app_deck *d);
/* One line per problem type, for --help. */
void app_print_problem_types(FILE *f);

/* True if argv holds -h or --help. */
int app_wants_help(int argc, char **argv);

#endif
