/* SPDX-License-Identifier: MIT */
/* mscale check DECK: validate only; exit 0, or 2 with FILE:LINE:COL: message lines. */
#include "commands.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

static void check_usage(FILE *f) {
  fprintf(f, "Usage: mscale check DECK [--set PATH=VALUE]...\n\n"
             "Reads DECK completely (materials, problem section, data files it names) and\n"
             "reports every error as DECK:LINE:COL: message. Exit 0 if the deck is valid,\n"
             "2 otherwise. --set overrides a deck value as `mscale run --set` does.\n"
             "Problem types:\n");
  app_print_problem_types(f);
}

int cmd_check(int argc, char **argv) {
  static const struct option opts[] = {
      {"set", required_argument, NULL, 's'}, {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
  const char **sets = ms_calloc((size_t)argc + 1, sizeof *sets);
  size_t nsets = 0;
  const char *deck = NULL;
  int rc = -1, c;
  opterr = 0;
  optind = 0; /* glibc: a full reset (tests call the commands in-process, repeatedly) */
  while (rc < 0 && (c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
    if (c == 's' && app_option_value_missing("check", "--set", optarg)) rc = 2;
    else if (c == 's') sets[nsets++] = optarg;
    else if (c == 'h') rc = 0, check_usage(stdout);
    else rc = app_option_error("check", c, optopt, argv[optind - 1], opts);
  }
  if (rc < 0 && optind == argc - 1) deck = argv[optind];
  else if (rc < 0) rc = 2, check_usage(stderr);
  if (rc >= 0) {
    free(sets);
    return rc;
  }
  dk_errors e;
  dk_errors_init(&e);
  app_deck d;
  ms_status s = app_deck_read_set(deck, sets, nsets, &d, &e);
  dk_errors_print(&e, stderr);
  if (s == MS_OK) printf("%s: ok\n", deck);
  else
    fprintf(stderr, "%s: %zu error%s\n", deck, dk_errors_count(&e),
            dk_errors_count(&e) == 1 ? "" : "s");
  app_deck_free(&d);
  dk_errors_free(&e);
  free(sets);
  return s == MS_OK ? 0 : 2;
}
