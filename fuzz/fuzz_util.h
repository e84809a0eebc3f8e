/* SPDX-License-Identifier: MIT */
/* Shared helpers of the libFuzzer harnesses (fuzz/fuzz_*.c): a scratch file that each input is
 * written to (readers that take a path), and the oracle every harness applies to the error
 * list: each message names the file it is about, positions are positive, nothing is empty. */
#ifndef MSCALE_FUZZ_UTIL_H
#define MSCALE_FUZZ_UTIL_H

#include "core.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* A per-process scratch path in $TMPDIR (default /tmp) ending in `suffix` (".txt", ".h5"). */
static inline const char *fuzz_scratch_path(const char *suffix) {
  static char path[4096];
  if (!path[0]) {
    const char *dir = getenv("TMPDIR");
    snprintf(path, sizeof path, "%s/mscale-fuzz-%ld%s", dir && dir[0] ? dir : "/tmp",
             (long)getpid(), suffix);
  }
  return path;
}

/* True if data[0..size) contains the text `needle`. */
static inline bool fuzz_contains(const uint8_t *data, size_t size, const char *needle) {
  size_t n = strlen(needle);
  for (size_t i = 0; i + n <= size; i++)
    if (!memcmp(data + i, needle, n)) return true;
  return false;
}

/* Replace the scratch file's content with data[0..size). */
static inline void fuzz_write_file(const char *path, const uint8_t *data, size_t size) {
  FILE *f = fopen(path, "wb");
  if (!f) abort();
  if (size && fwrite(data, 1, size, f) != size) abort();
  if (fclose(f)) abort();
}

/* The error-list oracle: each message starts with "<file>:" (or "<file>: " for whole-file
 * messages) and has a non-empty text. A violation aborts, which libFuzzer reports as a crash. */
static inline void fuzz_check_errors(const dk_errors *e, const char *file) {
  size_t fl = strlen(file);
  for (size_t i = 0; i < e->n; i++) {
    const char *m = e->msg[i];
    if (strncmp(m, file, fl) != 0 || m[fl] != ':') {
      fprintf(stderr, "fuzz oracle: message does not name the file '%s': %s\n", file, m);
      abort();
    }
    const char *rest = m + fl + 1;
    if (rest[0] >= '0' && rest[0] <= '9') { /* LINE:COL: text, both >= 1 */
      long line = strtol(rest, (char **)&rest, 10);
      long col = rest[0] == ':' ? strtol(rest + 1, (char **)&rest, 10) : 0;
      if (line < 1 || col < 1 || rest[0] != ':') {
        fprintf(stderr, "fuzz oracle: bad position in: %s\n", m);
        abort();
      }
      rest++;
    }
    while (*rest == ' ') rest++;
    if (!*rest) {
      fprintf(stderr, "fuzz oracle: empty message: %s\n", m);
      abort();
    }
  }
}

#endif
