/* SPDX-License-Identifier: MIT */
/* CSV tables with a units header line. */
#include "core.h"

void ms_csv_header(FILE *f, const char *title, size_t ncol, const char *const *names,
                   const char *const *units) {
  if (title && title[0]) fprintf(f, "# %s\n", title);
  if (units) {
    fprintf(f, "# units: ");
    for (size_t i = 0; i < ncol; i++)
      fprintf(f, "%s%s [%s]", i ? ", " : "", names[i], units[i] ? units[i] : "1");
    fputc('\n', f);
  }
  for (size_t i = 0; i < ncol; i++) fprintf(f, "%s%s", i ? "," : "", names[i]);
  fputc('\n', f);
}

void ms_csv_row(FILE *f, size_t ncol, const double *values) {
  for (size_t i = 0; i < ncol; i++) fprintf(f, "%s%.10g", i ? "," : "", values[i]);
  fputc('\n', f);
}
