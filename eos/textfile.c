/* SPDX-License-Identifier: MIT */
/* textfile.c — plain numeric text tables with line numbers, for EOS data files
 * (format in eos_impl.h and docs/eos.md). Every problem is reported as FILE:LINE:COL. */

#include "eos_impl.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#define MAX_ERRORS 20 /* stop reporting after this many problems in one file */

static char *trim(char *s) {
  while (isspace((unsigned char)*s)) ++s;
  size_t n = strlen(s);
  while (n > 0 && isspace((unsigned char)s[n - 1])) s[--n] = '\0';
  return s;
}

/* "# key: value" -> metadata (key is one word of letters, digits, '_'). */
static void parse_meta(eos_text_table *t, char *comment) {
  char *s = trim(comment);
  char *colon = strchr(s, ':');
  if (!colon || colon == s) return;
  for (char *q = s; q < colon; ++q)
    if (!(isalnum((unsigned char)*q) || *q == '_')) return;
  *colon = '\0';
  t->meta_key = ms_realloc(t->meta_key, t->nmeta + 1, sizeof *t->meta_key);
  t->meta_val = ms_realloc(t->meta_val, t->nmeta + 1, sizeof *t->meta_val);
  t->meta_key[t->nmeta] = ms_strdup(s);
  t->meta_val[t->nmeta] = ms_strdup(trim(colon + 1));
  t->nmeta++;
}

const char *eos_text_meta(const eos_text_table *t, const char *key) {
  for (size_t i = 0; i < t->nmeta; ++i)
    if (strcmp(t->meta_key[i], key) == 0) return t->meta_val[i];
  return NULL;
}

void eos_text_free(eos_text_table *t) {
  if (!t) return;
  free(t->v);
  free(t->line);
  for (size_t i = 0; i < t->nmeta; ++i) free(t->meta_key[i]), free(t->meta_val[i]);
  free(t->meta_key);
  free(t->meta_val);
  memset(t, 0, sizeof *t);
}

ms_status eos_text_read(const char *path, size_t min_cols, size_t max_cols, eos_text_table *t,
                        dk_errors *e) {
  memset(t, 0, sizeof *t);
  FILE *f = fopen(path, "r");
  if (!f) {
    dk_error_at(e, path, 0, 0, "cannot open table file: %s", strerror(errno));
    return MS_ERR_INPUT;
  }
  size_t nerr0 = e->n, cap = 0, ncol = 0;
  int lineno = 0, ncol_line = 0;
  bool seen_content = false;
  char *buf = NULL;
  size_t bufcap = 0;
  double row[64];
  while (getline(&buf, &bufcap, f) >= 0) {
    ++lineno;
    if (e->n - nerr0 >= MAX_ERRORS) break;
    char *hash = strchr(buf, '#');
    if (hash) {
      *hash = '\0';
      parse_meta(t, hash + 1);
    }
    /* Tokenise on blanks and commas, remembering columns for messages. */
    size_t ntok = 0;
    bool numeric = true, any_number = false;
    char *p = buf;
    int bad_col = 0;
    const char *bad_tok = NULL;
    char *toks[64];
    int cols[64];
    while (*p) {
      while (*p && (isspace((unsigned char)*p) || *p == ',')) ++p;
      if (!*p) break;
      char *start = p;
      while (*p && !(isspace((unsigned char)*p) || *p == ',')) ++p;
      if (*p) *p++ = '\0';
      if (ntok < 64) {
        toks[ntok] = start;
        cols[ntok] = (int)(start - buf) + 1;
      }
      ++ntok;
    }
    if (ntok == 0) continue;
    if (ntok > 64) {
      dk_error_at(e, path, lineno, 1, "too many columns (%zu; at most %zu expected)", ntok,
                  max_cols);
      continue;
    }
    for (size_t k = 0; k < ntok; ++k) {
      char *end;
      errno = 0;
      double v = strtod(toks[k], &end);
      if (end == toks[k] || *end != '\0' || !isfinite(v) || errno == ERANGE) {
        if (numeric) bad_col = cols[k], bad_tok = toks[k];
        numeric = false;
      } else {
        any_number = true;
        row[k] = v;
      }
    }
    if (!numeric) {
      if (!seen_content && !any_number) { /* a header line of column names */
        seen_content = true;
        continue;
      }
      dk_error_at(e, path, lineno, bad_col, "expected a finite number, found '%s'", bad_tok);
      seen_content = true;
      continue;
    }
    seen_content = true;
    if (ncol == 0) {
      if (ntok < min_cols || ntok > max_cols) {
        if (min_cols == max_cols)
          dk_error_at(e, path, lineno, 1, "expected %zu columns, found %zu", min_cols, ntok);
        else
          dk_error_at(e, path, lineno, 1, "expected %zu to %zu columns, found %zu", min_cols,
                      max_cols, ntok);
        continue;
      }
      ncol = ntok;
      ncol_line = lineno;
    } else if (ntok != ncol) {
      dk_error_at(e, path, lineno, cols[ntok - 1],
                  "expected %zu columns (as on line %d), found %zu (truncated or extra data?)",
                  ncol, ncol_line, ntok);
      continue;
    }
    if (t->nrow == cap) {
      cap = cap ? 2 * cap : 64;
      t->v = ms_realloc(t->v, cap * ncol, sizeof *t->v);
      t->line = ms_realloc(t->line, cap, sizeof *t->line);
    }
    memcpy(t->v + t->nrow * ncol, row, ncol * sizeof *row);
    t->line[t->nrow] = lineno;
    t->nrow++;
  }
  bool read_error = ferror(f) != 0;
  free(buf);
  fclose(f);
  t->ncol = ncol;
  t->last_line = lineno;
  if (read_error) dk_error_at(e, path, lineno, 0, "read error");
  if (t->nrow == 0 && e->n == nerr0) dk_error_at(e, path, lineno, 0, "no data rows in table");
  if (e->n != nerr0) {
    eos_text_free(t);
    return MS_ERR_INPUT;
  }
  return MS_OK;
}
