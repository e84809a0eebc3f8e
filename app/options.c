/* SPDX-License-Identifier: MIT */
/* The subcommands' command-line messages around getopt_long (app/commands.h). Its own file:
 * the spectrum fuzz replay (tests/reliability) builds cmd_spectrum.c with it. */
#include "commands.h"

#include <getopt.h>
#include <string.h>

/* getopt_long's "needs a value" and "unknown option" cases, said plainly (exit 2). */
int app_option_error(const char *cmd, int c, int optopt_, const char *arg,
                     const struct option *opts) {
  if (c == ':') {
    for (const struct option *o = opts; o->name; o++)
      if (o->val == optopt_) {
        if (o->val < 128)
          fprintf(stderr, "mscale %s: option '-%c' (--%s) needs a value\n", cmd, o->val, o->name);
        else fprintf(stderr, "mscale %s: option '--%s' needs a value\n", cmd, o->name);
        return 2;
      }
    fprintf(stderr, "mscale %s: option '%s' needs a value\n", cmd, arg);
    return 2;
  }
  const char *names[64] = {NULL};
  size_t n = 0;
  for (const struct option *o = opts; o->name && n < 63; o++) names[n++] = o->name;
  const char *word = arg;
  while (*word == '-') word++;
  char stem[128];
  snprintf(stem, sizeof stem, "%.*s", (int)strcspn(word, "="), word);
  const char *hint = dk_suggest(stem, names);
  if (hint)
    fprintf(stderr, "mscale %s: unknown option '%s' (did you mean '--%s'?)\n", cmd, arg, hint);
  else fprintf(stderr, "mscale %s: unknown option '%s'; see mscale %s --help\n", cmd, arg, cmd);
  return 2;
}

/* An option's value that is the next option ("-o --force"): the value was left out. */
int app_option_value_missing(const char *cmd, const char *name, const char *value) {
  if (value[0] == '-' && value[1] == '-') {
    fprintf(stderr, "mscale %s: option '%s' needs a value (found the option '%s' instead)\n", cmd,
            name, value);
    return 1;
  }
  return 0;
}
