/* SPDX-License-Identifier: MIT */
/* libFuzzer harness: the whole deck path of `mscale check` (app_deck_read in app/problems.c:
 * parser, units, problem type, materials and EOS readers including the table files they name,
 * the problem section, unknown keys). The input is written to a scratch file in $TMPDIR and
 * read from there, so relative `file:` paths resolve against $TMPDIR (copy the eos/data tables
 * there to let the fuzzer reach the table readers). Oracle: no sanitizer report; an invalid
 * deck has errors that each name a file; a valid deck has none. */
#include "commands.h"
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size > 1 << 16) return 0;
  /* device and process files are not decks' business (reading /dev/zero never ends) */
  if (fuzz_contains(data, size, "dev") || fuzz_contains(data, size, "proc") ||
      fuzz_contains(data, size, "sys"))
    return 0;
  const char *path = fuzz_scratch_path(".yaml");
  fuzz_write_file(path, data, size);
  dk_errors e;
  dk_errors_init(&e);
  app_deck d;
  ms_status s = app_deck_read(path, &d, &e);
  if ((s == MS_OK) != (e.n == 0)) {
    fprintf(stderr, "fuzz oracle: status %d with %zu errors\n", (int)s, e.n);
    abort();
  }
  /* messages name the deck or a data file it refers to: check those about the deck */
  dk_errors deck_only;
  dk_errors_init(&deck_only);
  for (size_t i = 0; i < e.n; i++)
    if (!strncmp(e.msg[i], path, strlen(path)) || e.msg[i][0] != '/') {
      deck_only.msg = realloc(deck_only.msg, (deck_only.n + 1) * sizeof *deck_only.msg);
      deck_only.msg[deck_only.n++] = e.msg[i];
    }
  fuzz_check_errors(&deck_only, path);
  free(deck_only.msg);
  app_deck_free(&d);
  dk_errors_free(&e);
  return 0;
}
