/* SPDX-License-Identifier: MIT */
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
/* The same with command-line overrides (`--set PATH=VALUE`, dk_set) applied before reading. */
ms_status app_deck_read_set(const char *path, const char *const *sets, size_t nsets, app_deck *d,
                            dk_errors *e);
/* Splits "PATH=VALUE" and applies it to the deck (dk_set); false with an error otherwise. */
bool app_apply_set(dk_doc *doc, const char *arg, dk_errors *e);
ms_status app_deck_run(ms_ctx *ctx, app_deck *d);
/* True if the deck's problem type can continue from a checkpoint (`run --restart`). */
bool app_deck_restartable(const app_deck *d);
/* The checkpoint file the deck's problem writes into its output directory (NULL: none). */
const char *app_deck_checkpoint_name(const app_deck *d);
void app_deck_free(app_deck *d);
/* One line per problem type, for --help. */
void app_print_problem_types(FILE *f);

/* The characters of `s` inside a YAML double-quoted scalar (", \ and control characters
 * escaped), and `s` as such a scalar, quotes included: command lines, paths and values from the
 * environment may hold anything, and run_info.yaml must still load (app/provenance.c). */
void app_put_yaml_escaped(FILE *f, const char *s);
void app_put_yaml_quoted(FILE *f, const char *s);
/* The version: `git describe` at build time, else the project version (app/provenance.c). */
const char *app_version(void);
/* `mscale --version`: version, commit, compiler and flags, library versions. */
void app_print_version(FILE *f);
/* run_info.yaml's provenance lines: version, git_describe, git_commit, build {type, compiler,
 * flags}, libraries {mpi, hdf5, sundials, metis, libyaml}, ranks, threads, host. */
void app_write_provenance(FILE *f, const ms_ctx *ctx);

/* Run-directory manifests (app/manifest.c): the regular files of a directory with their inode,
 * size and modification time; the previous run's files (run_info.yaml's `manifest:`, else those
 * modified since its `started`); --force's removal of them and of plots/ (*removed: how many);
 * and run_info.yaml's `manifest:` list: the files new or changed since `before`, those of
 * `keep` (--continue: the previous run's) and run_info.yaml. */
typedef struct app_listing app_listing;
app_listing *app_listing_take(const char *dir);
void app_listing_free(app_listing **pl);
app_listing *app_manifest_previous(const char *dir);
ms_status app_manifest_clear(const char *dir, size_t *removed);
void app_manifest_write(FILE *f, const char *dir, const app_listing *before,
                        const app_listing *keep);

/* Command-line parsing with getopt_long (app/cmd_run.c): the message for getopt's ':' (an option
 * without its value) or '?' (unknown; with a "did you mean") and exit code 2; and the check for
 * a value that is the next option ("-o --force"), which prints the message and returns 1. */
struct option;
int app_option_error(const char *cmd, int c, int optopt_, const char *arg,
                     const struct option *opts);
int app_option_value_missing(const char *cmd, const char *name, const char *value);

/* True if argv holds -h or --help. */
int app_wants_help(int argc, char **argv);

#endif
