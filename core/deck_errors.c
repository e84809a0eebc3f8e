/* SPDX-License-Identifier: MIT */
/* Deck errors: collected with their position, sorted by file, line and column, duplicates
 * dropped, printed as FILE:LINE:COL: message (docs/input.md "Errors"). */
#include "core.h"
#include "deck_impl.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* Errors                                                                                      */

void dk_errors_init(dk_errors *e) { memset(e, 0, sizeof *e); }

void dk_errors_free(dk_errors *e) {
  for (size_t i = 0; i < e->n; i++) {
    free(e->msg[i]);
    if (e->pos) free(e->pos[i].file), free(e->pos[i].about);
  }
  free(e->msg);
  free(e->pos);
  memset(e, 0, sizeof *e);
}

/* Order of two messages for printing: file (in order of first mention), line, column, then the
 * order recorded. `first` is the index of each message's file's first mention. */
typedef struct err_order {
  size_t index, first;
  int line, col;
} err_order;

static int err_order_cmp(const void *pa, const void *pb) {
  const err_order *a = pa, *b = pb;
  if (a->first != b->first) return a->first < b->first ? -1 : 1;
  if (a->line != b->line) return a->line < b->line ? -1 : 1;
  if (a->col != b->col) return a->col < b->col ? -1 : 1;
  return a->index < b->index ? -1 : a->index > b->index;
}

void dk_errors_print(const dk_errors *e, FILE *f) {
  if (!e->pos) { /* assembled by hand: no positions to sort by */
    for (size_t i = 0; i < e->n; i++) fprintf(f, "%s\n", e->msg[i]);
    return;
  }
  err_order *o = ms_calloc(e->n ? e->n : 1, sizeof *o);
  for (size_t i = 0; i < e->n; i++) {
    size_t first = i;
    for (size_t j = 0; j < i; j++)
      if (!strcmp(e->pos[j].file, e->pos[i].file)) {
        first = o[j].first;
        break;
      }
    o[i] = (err_order){i, first, e->pos[i].line, e->pos[i].col};
  }
  qsort(o, e->n, sizeof *o, err_order_cmp);
  for (size_t i = 0; i < e->n; i++)
    if (!e->pos[o[i].index].hidden) fprintf(f, "%s\n", e->msg[o[i].index]);
  free(o);
}

/* A message equal to one already recorded (the same node checked by two readers) is hidden; so
 * is a missing key that an unknown key in the same mapping misspells (DK_ROLE_*). Hidden errors
 * still count in e->n: readers decide by the count whether something went wrong. */
static void errors_push(dk_errors *e, char *msg, const char *file, int line, int col, int role,
                        const char *about) {
  bool hidden = false;
  for (size_t i = 0; i < e->n && e->pos; i++) {
    bool same_about = about && e->pos[i].about && !strcmp(e->pos[i].about, about);
    if (!strcmp(e->msg[i], msg)) hidden = true;
    if (same_about && role == DK_ROLE_MISSING && e->pos[i].role == DK_ROLE_MISSPELT) hidden = true;
    if (same_about && role == DK_ROLE_MISSPELT && e->pos[i].role == DK_ROLE_MISSING)
      e->pos[i].hidden = true;
  }
  if (e->n == e->cap) {
    e->cap = e->cap ? 2 * e->cap : 8;
    e->msg = ms_realloc(e->msg, e->cap, sizeof *e->msg);
    e->pos = ms_realloc(e->pos, e->cap, sizeof *e->pos);
  }
  e->pos[e->n] = (dk_error_pos){ms_strdup(file),
                                line > 0 ? line : 0,
                                line > 0 ? col : 0,
                                role,
                                about ? ms_strdup(about) : NULL,
                                hidden};
  e->msg[e->n++] = msg;
}

size_t dk_errors_count(const dk_errors *e) {
  size_t n = 0;
  for (size_t i = 0; i < e->n; i++) n += !(e->pos && e->pos[i].hidden);
  return n;
}

static void verror_at(dk_errors *e, const char *file, int line, int col, int role,
                      const char *about, const char *fmt, va_list ap) {
  char body[1536];
  vsnprintf(body, sizeof body, fmt, ap);
  char *msg = ms_calloc(strlen(body) + strlen(file) + 48, 1);
  if (line > 0) sprintf(msg, "%s:%d:%d: %s", file, line, col > 0 ? col : 1, body);
  else sprintf(msg, "%s: %s", file, body);
  errors_push(e, msg, file, line, col > 0 ? col : 1, role, about);
}

void dk_error_at(dk_errors *e, const char *file, int line, int col, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  verror_at(e, file ? file : "<input>", line, col, DK_ROLE_NONE, NULL, fmt, ap);
  va_end(ap);
}

void dk_error(dk_errors *e, const dk_doc *doc, const dk_node *at, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  if (at && at->origin) verror_at(e, at->origin, 0, 0, DK_ROLE_NONE, NULL, fmt, ap);
  else
    verror_at(e, doc ? doc->file : "<deck>", at ? at->line : 0, at ? at->col : 0, DK_ROLE_NONE,
              NULL, fmt, ap);
  va_end(ap);
}

void dk_error_role(dk_errors *e, const dk_doc *doc, const dk_node *at, int line, int col, int role,
                   const char *about, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  if (line > 0) verror_at(e, doc->file, line, col, role, about, fmt, ap);
  else if (at && at->origin) verror_at(e, at->origin, 0, 0, role, about, fmt, ap);
  else
    verror_at(e, doc ? doc->file : "<deck>", at ? at->line : 0, at ? at->col : 0, role, about, fmt,
              ap);
  va_end(ap);
}
