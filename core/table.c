/* SPDX-License-Identifier: MIT */
/* Numeric tables (EOS tables, histories): CSV or whitespace separated, '#' comments, an
 * optional header line of column names. Every problem is reported as FILE:LINE. */
#include "core.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { TABLE_MAX_COLS = 64, TABLE_MAX_LINE = 1 << 16 };

/* One line into buf (without its '\n'); returns its length, -1 at end of file. A line that
 * does not fit sets *too_long and stops reading, so a file without line breaks (a binary file,
 * /dev/zero) cannot make the reader allocate or loop without bound. */
static long read_line(FILE *f, char *buf, long cap, bool *too_long) {
  long n = 0;
  int c;
  *too_long = false;
  while ((c = getc(f)) != EOF && c != '\n') {
    if (n == cap - 1) {
      *too_long = true;
      break;
    }
    buf[n++] = (char)c;
  }
  if (c == EOF && n == 0) return -1;
  buf[n] = 0;
  return n;
}

/* Split a line into numbers (start of each in at[]); returns the count, or -1 (with *bad set)
 * on a non-number. */
static int split_numbers(char *line, double *v, char **at, int max, char **bad) {
  int n = 0;
  char *p = line;
  for (;;) {
    while (*p == ' ' || *p == '\t' || *p == ',' || *p == ';' || *p == '\r') p++;
    if (!*p || *p == '\n' || *p == '#') break;
    char *end;
    errno = 0;
    double x = strtod(p, &end);
    if (end == p || errno == ERANGE || (*end && !strchr(" \t,;\r\n#", *end))) {
      *bad = p;
      return -1;
    }
    if (n >= max) return max + 1;
    at[n] = p;
    v[n++] = x;
    p = end;
  }
  return n;
}

ms_status ms_read_table(const char *path, size_t min_cols, double **data, size_t *nrow,
                        size_t *ncol, dk_errors *e) {
  *data = NULL;
  *nrow = *ncol = 0;
  FILE *f = fopen(path, "r");
  if (!f) {
    dk_error_at(e, path, 0, 0, "cannot open the table file: %s", strerror(errno));
    return MS_ERR_INPUT;
  }
  char *line = ms_calloc(TABLE_MAX_LINE, 1);
  size_t rows = 0, rcap = 0;
  int cols = -1, lineno = 0;
  bool header_allowed = true;
  double *out = NULL, v[TABLE_MAX_COLS];
  char *at[TABLE_MAX_COLS];
  ms_status s = MS_OK;
  long len;
  bool too_long;
  while ((len = read_line(f, line, TABLE_MAX_LINE, &too_long)) != -1) {
    lineno++;
    if (too_long) {
      dk_error_at(e, path, lineno, 1, "line longer than %d characters (not a text table?)",
                  TABLE_MAX_LINE - 1);
      s = MS_ERR_INPUT;
      break;
    }
    if (strlen(line) != (size_t)len) { /* a binary file, or text damaged by NUL bytes */
      dk_error_at(e, path, lineno, (int)strlen(line) + 1,
                  "a NUL byte in a text table (binary or damaged file?)");
      s = MS_ERR_INPUT;
      break;
    }
    char *p = line;
    while (isspace((unsigned char)*p)) p++;
    if (!*p || *p == '#') continue;
    char *bad = NULL;
    int n = split_numbers(p, v, at, TABLE_MAX_COLS, &bad);
    if (n < 0 && header_allowed && isalpha((unsigned char)*p)) {
      header_allowed = false; /* a line of column names */
      continue;
    }
    if (n == 0) continue; /* only separators (",,,," rows of spreadsheet exports) */
    header_allowed = false;
    if (n < 0) {
      char tok[32];
      size_t k = 0;
      while (bad[k] && !strchr(" \t,;\r\n", bad[k]) && k < sizeof tok - 1) tok[k] = bad[k], k++;
      tok[k] = 0;
      dk_error_at(e, path, lineno, (int)(bad - line) + 1, "expected a number, found '%s'", tok);
      s = MS_ERR_INPUT;
      break;
    }
    if (n > TABLE_MAX_COLS) {
      dk_error_at(e, path, lineno, 1, "more than %d columns", TABLE_MAX_COLS);
      s = MS_ERR_INPUT;
      break;
    }
    for (int i = 0; i < n; i++)
      if (!isfinite(v[i])) {
        dk_error_at(e, path, lineno, (int)(at[i] - line) + 1,
                    "column %d is not a finite number (%g)", i + 1, v[i]);
        s = MS_ERR_INPUT;
      }
    if (s) break;
    if (cols < 0) {
      cols = n;
      if ((size_t)cols < min_cols) {
        dk_error_at(e, path, lineno, 1, "expected at least %zu columns, found %d", min_cols, n);
        s = MS_ERR_INPUT;
        break;
      }
    } else if (n != cols) {
      dk_error_at(e, path, lineno, 1,
                  "expected %d columns like the first data row, found %d "
                  "(truncated or damaged table?)",
                  cols, n);
      s = MS_ERR_INPUT;
      break;
    }
    if (rows == rcap) {
      rcap = rcap ? 2 * rcap : 64;
      out = ms_realloc(out, rcap * (size_t)cols, sizeof *out);
    }
    memcpy(out + rows * (size_t)cols, v, (size_t)cols * sizeof *v);
    rows++;
  }
  free(line);
  fclose(f);
  if (!s && rows == 0) {
    dk_error_at(e, path, 0, 0, "the table holds no data rows");
    s = MS_ERR_INPUT;
  }
  if (s) {
    free(out);
    return s;
  }
  *data = out;
  *nrow = rows;
  *ncol = (size_t)cols;
  return MS_OK;
}

double ms_table_time_factor(const char *path, size_t col, double fallback) {
  FILE *f = fopen(path, "r");
  if (!f) return fallback;
  char line[4096];
  double factor = fallback;
  while (fgets(line, sizeof line, f) && line[0] == '#') {
    if (strncmp(line, "# units:", 8) != 0) continue;
    const char *p = line + 8;
    for (size_t k = 0; k < col && p; k++) p = strchr(p, ','), p = p ? p + 1 : NULL;
    const char *lb = p ? strchr(p, '[') : NULL, *rb = lb ? strchr(lb, ']') : NULL;
    if (!rb) break;
    const char *comma = strchr(p, ',');
    if (comma && comma < lb) break; /* this column has no [unit] */
    char unit[32] = "";
    size_t n = (size_t)(rb - lb - 1);
    if (n < sizeof unit) memcpy(unit, lb + 1, n), unit[n] = 0;
    /* internal time is 10 µs: µs, 10 µs, s, ms and ns as written in units headers */
    static const struct {
      const char *name;
      double to_internal;
    } times[] = {{"us", 0.1}, {"10us", 1.0}, {"10 us", 1.0}, {"s", 1e5}, {"ms", 1e2}, {"ns", 1e-4}};
    for (size_t i = 0; i < sizeof times / sizeof times[0]; i++)
      if (!strcmp(unit, times[i].name)) factor = times[i].to_internal;
    break;
  }
  fclose(f);
  return factor;
}
