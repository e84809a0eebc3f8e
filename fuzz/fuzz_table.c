/* SPDX-License-Identifier: MIT */
/* libFuzzer harness: the numeric table reader ms_read_table (histories, generic tables).
 * Byte 0 chooses the minimum column count, the rest is the file. Oracles: no sanitizer report;
 * on success at least one row, at least min_cols columns, all values finite; on failure at
 * least one error, each naming the file with a positive LINE:COL when it has one. */
#include "core.h"
#include "fuzz_util.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1 || size > 1 << 16) return 0;
  size_t min_cols = data[0] % 6;
  const char *path = fuzz_scratch_path(".csv");
  fuzz_write_file(path, data + 1, size - 1);
  dk_errors e;
  dk_errors_init(&e);
  double *t = NULL;
  size_t nrow = 0, ncol = 0;
  ms_status s = ms_read_table(path, min_cols, &t, &nrow, &ncol, &e);
  if (s == MS_OK) {
    if (e.n || !t || nrow == 0 || ncol < min_cols || ncol == 0) {
      fprintf(stderr, "fuzz oracle: accepted a table with %zu errors, %zu rows, %zu columns\n", e.n,
              nrow, ncol);
      abort();
    }
    for (size_t i = 0; i < nrow * ncol; i++)
      if (!isfinite(t[i])) {
        fprintf(stderr, "fuzz oracle: accepted a non-finite value\n");
        abort();
      }
  } else if (e.n == 0 || t) {
    fprintf(stderr, "fuzz oracle: rejected a table without a message\n");
    abort();
  }
  fuzz_check_errors(&e, path);
  free(t);
  dk_errors_free(&e);
  return 0;
}
