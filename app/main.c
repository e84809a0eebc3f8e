/* SPDX-License-Identifier: MIT */
/* mscale — command-line front end (docs/design.md §8). */
#include "commands.h"

#include <stdio.h>
#include <string.h>

static void usage(FILE *f) {
  fprintf(f,
          "mscale %s — coupled particle–continuum shock-physics code\n\n"
          "Usage:\n"
          "  mscale run DECK [-o OUTDIR] [--force] [--quiet]   run a deck\n"
          "  mscale check DECK                                 validate a deck only\n"
          "  mscale hugoniot DECK --material NAME --up LIST    shock Hugoniot as CSV\n"
          "  mscale spectrum SNAPSHOT.h5 [--bond B]            fragment spectrum as CSV\n"
          "  mscale export SNAPSHOT.h5... --format extxyz|lammps-dump [-o FILE]\n"
          "                                                    snapshots for OVITO, ASE\n"
          "  mscale --version | --help\n\n"
          "Every subcommand takes --help. Internal units: g, cm, 10 us (velocity km/s,\n"
          "pressure GPa, density g/cm^3, specific energy kJ/g).\n"
          "Exit codes: 0 success, 1 the run failed, 2 bad usage or bad input.\n"
          "Under MPI: mpirun -np N mscale run DECK\n",
          app_version());
}

int app_wants_help(int argc, char **argv) {
  for (int i = 1; i < argc; i++)
    if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return 1;
  return 0;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V")) {
    app_print_version(stdout);
    return 0;
  }
  if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
    usage(stdout);
    return 0;
  }
  static const struct {
    const char *name;
    int (*fn)(int, char **);
  } commands[] = {{"run", cmd_run},
                  {"check", cmd_check},
                  {"hugoniot", cmd_hugoniot},
                  {"spectrum", cmd_spectrum},
                  {"export", cmd_export}};
  for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
    if (!strcmp(cmd, commands[i].name)) return commands[i].fn(argc - 1, argv + 1);
  const char *names[sizeof commands / sizeof commands[0] + 1] = {NULL};
  for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++) names[i] = commands[i].name;
  const char *hint = dk_suggest(cmd, names);
  if (hint) {
    fprintf(stderr, "mscale: unknown command '%s' (did you mean '%s'?); see mscale --help\n", cmd,
            hint);
    return 2;
  }
  fprintf(stderr, "mscale: unknown command '%s'\n\n", cmd);
  usage(stderr);
  return 2;
}
