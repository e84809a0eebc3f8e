/* Numeric tables (EOS tables, histories): CSV or whitespace separated, '#' comments, an
 * optional header line of column names. Every problem is reported as FILE:LINE. */
#include "core.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { TABLE_MAX_COLS = 64 };

/* Split a line into numbers; returns the count, or -1 (with *bad set) on a non-number. */
static int split_numbers(char *line, double *v, int max, char **bad) {
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
  char *line = NULL;
  size_t cap = 0, rows = 0, rcap = 0;
  int cols = -1, lineno = 0;
  bool header_allowed = true;
  double *out = NULL, v[TABLE_MAX_COLS];
  ms_status s = MS_OK;
  while (getline(&line, &cap, f) != -1) {
    lineno++;
    if (strlen(line) == 0) continue;
    char *p = line;
    while (isspace((unsigned char)*p)) p++;
    if (!*p || *p == '#') continue;
    char *bad = NULL;
    int n = split_numbers(p, v, TABLE_MAX_COLS, &bad);
    if (n < 0 && header_allowed && isalpha((unsigned char)*p)) {
      header_allowed = false; /* a line of column names */
      continue;
    }
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
        dk_error_at(e, path, lineno, 1, "column %d is not a finite number", i + 1);
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
      dk_error_at(e, path, lineno, 1, "expected %d columns like the first data row, found %d "
                  "(truncated or damaged table?)", cols, n);
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
