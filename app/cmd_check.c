/* mscale check DECK: validate only; exit 0, or 2 with FILE:LINE:COL: message lines. */
#include "commands.h"

#include <string.h>

static void check_usage(FILE *f) {
  fprintf(f, "Usage: mscale check DECK\n\n"
             "Reads DECK completely (materials, problem section, data files it names) and\n"
             "reports every error as DECK:LINE:COL: message. Exit 0 if the deck is valid,\n"
             "2 otherwise. Problem types:\n");
  app_print_problem_types(f);
}

int cmd_check(int argc, char **argv) {
  if (app_wants_help(argc, argv)) {
    check_usage(stdout);
    return 0;
  }
  if (argc != 2 || argv[1][0] == '-') {
    check_usage(stderr);
    return 2;
  }
  dk_errors e;
  dk_errors_init(&e);
  app_deck d;
  ms_status s = app_deck_read(argv[1], &d, &e);
  dk_errors_print(&e, stderr);
  if (s == MS_OK) printf("%s: ok\n", argv[1]);
  else fprintf(stderr, "%s: %zu error%s\n", argv[1], e.n, e.n == 1 ? "" : "s");
  app_deck_free(&d);
  dk_errors_free(&e);
  return s == MS_OK ? 0 : 2;
}
