/* SPDX-License-Identifier: MIT */
/* CSV tables with a units header. Columns in a time-bearing internal unit (10 µs) are written
 * in the output unit µs (docs/output.md, "Units"): the header converts the unit names and keeps
 * the factor of each column for the rows written to the same FILE after it. */
#include "core.h"

#include <stdlib.h>
#include <string.h>

enum { CSV_MAX_FILES = 64 };

/* The columns' factors of the files whose header was written last (a few files are open at once;
 * an entry is dropped when its file is committed or aborted, ms_csv_forget). */
static struct {
  FILE *f;
  size_t ncol;
  double *scale; /* NULL: every factor 1 */
} open_tables[CSV_MAX_FILES];

static int table_slot(FILE *f, bool make) {
  static int evict; /* files closed without ms_csv_forget: the oldest entries go first */
  int free_slot = -1;
  for (int i = 0; i < CSV_MAX_FILES; i++) {
    if (open_tables[i].f == f) return i;
    if (!open_tables[i].f && free_slot < 0) free_slot = i;
  }
  if (!make) return -1;
  if (free_slot < 0) {
    free_slot = evict;
    evict = (evict + 1) % CSV_MAX_FILES;
    free(open_tables[free_slot].scale);
    open_tables[free_slot].scale = NULL;
  }
  open_tables[free_slot].f = f;
  return free_slot;
}

void ms_csv_forget(FILE *f) {
  int i = f ? table_slot(f, false) : -1;
  if (i < 0) return;
  free(open_tables[i].scale);
  memset(&open_tables[i], 0, sizeof open_tables[i]);
}

static void remember(FILE *f, size_t ncol, const double *scale) {
  ms_csv_forget(f);
  bool any = false;
  for (size_t i = 0; i < ncol; i++) any = any || scale[i] != 1.0;
  if (!any) return;
  int k = table_slot(f, true);
  open_tables[k].ncol = ncol;
  open_tables[k].scale = ms_calloc(ncol, sizeof(double));
  memcpy(open_tables[k].scale, scale, ncol * sizeof(double));
}

void ms_csv_header(FILE *f, const char *title, size_t ncol, const char *const *names,
                   const char *const *units) {
  if (title && title[0]) fprintf(f, "# %s\n", title);
  double *scale = ms_calloc(ncol ? ncol : 1, sizeof(double));
  for (size_t i = 0; i < ncol; i++) scale[i] = 1.0;
  if (units) {
    fprintf(f, "# units: ");
    for (size_t i = 0; i < ncol; i++)
      fprintf(f, "%s%s [%s]", i ? ", " : "", names[i],
              ms_out_unit(units[i] ? units[i] : "1", &scale[i]));
    fputc('\n', f);
  }
  for (size_t i = 0; i < ncol; i++) fprintf(f, "%s%s", i ? "," : "", names[i]);
  fputc('\n', f);
  remember(f, ncol, scale);
  free(scale);
}

void ms_csv_resume(FILE *f, const char *text, size_t len) {
  /* the last "# units: name [unit], ..." line of the text written before a checkpoint */
  const char *line = NULL;
  for (size_t i = 0; i + 9 <= len; i++)
    if ((i == 0 || text[i - 1] == '\n') && !strncmp(text + i, "# units: ", 9)) line = text + i + 9;
  if (!line) return;
  double scale[256];
  size_t ncol = 0;
  for (const char *p = line; *p && *p != '\n' && ncol < 256; p++) {
    if (*p != '[') continue;
    const char *end = strchr(p, ']');
    if (!end) break;
    char unit[64] = "";
    size_t n = (size_t)(end - p - 1) < sizeof unit - 1 ? (size_t)(end - p - 1) : sizeof unit - 1;
    memcpy(unit, p + 1, n);
    unit[n] = 0;
    scale[ncol++] = ms_out_unit_factor(unit);
    p = end;
  }
  remember(f, ncol, scale);
}

void ms_csv_row(FILE *f, size_t ncol, const double *values) {
  int k = table_slot(f, false);
  const double *scale = k >= 0 ? open_tables[k].scale : NULL;
  size_t ns = k >= 0 ? open_tables[k].ncol : 0;
  for (size_t i = 0; i < ncol; i++)
    fprintf(f, "%s%.10g", i ? "," : "", i < ns && scale ? values[i] * scale[i] : values[i]);
  fputc('\n', f);
}
