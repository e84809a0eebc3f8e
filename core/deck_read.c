/* SPDX-License-Identifier: MIT */
/* Typed deck readers: look a key up, convert, range-check, convert units, record every error
 * with FILE:LINE:COL, and write defaults back into the tree for the resolved deck. */
#include "core.h"
#include "deck_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *where(const dk_node *map, const char *key, char *buf, size_t n) {
  if (map && map->path[0]) snprintf(buf, n, "%s.%s", map->path, key);
  else snprintf(buf, n, "%s", key);
  return buf;
}

static void missing(dk_errors *e, const dk_doc *doc, const dk_node *map, const char *key,
                    const char *expected) {
  char *about = dk_child_path(map ? map->path : "", key, 0);
  if (map && map->path[0] && map->key_line > 0)
    dk_error_role(e, doc, map, map->key_line, map->key_col, DK_ROLE_MISSING, about,
                  "%s: missing required key '%s' (%s)", map->path, key, expected);
  else if (map && map->path[0])
    dk_error_role(e, doc, map, 0, 0, DK_ROLE_MISSING, about, "%s: missing required key '%s' (%s)",
                  map->path, key, expected);
  else
    dk_error_role(e, doc, map, 0, 0, DK_ROLE_MISSING, about,
                  "missing required top-level key '%s' (%s)", key, expected);
  free(about);
}

/* Insert a default value into the tree so the resolved deck shows it. */
static void put_default(dk_doc *doc, const dk_node *cmap, const char *key, const char *text) {
  if (!cmap || cmap->kind != DK_MAP) return;
  dk_node *map = (dk_node *)cmap;
  char *path = dk_child_path(map->path, key, 0);
  dk_node *n = dk_node_new(DK_SCALAR, map->line, map->col, path);
  free(path);
  n->value = ms_strdup(text);
  dk_node_append(map, key, n, true, true);
  (void)doc;
}

/* A whole scalar as a double: 1 ok, 0 not a number, -1 a number outside the range of a double
 * (1e999, 1e-400: strtod's ERANGE), which would otherwise turn silently into inf or 0. */
static int parse_double(const char *s, double *out) {
  if (!s || !s[0]) return 0;
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s) return 0;
  while (*end == ' ') end++;
  if (*end) return 0;
  if (errno == ERANGE) return -1;
  *out = v;
  return 1;
}

bool dk_node_double(dk_errors *e, const dk_doc *doc, const dk_node *n, const char *what, ms_dim dim,
                    double *out) {
  double v;
  int parsed = n && n->kind == DK_SCALAR && !n->quoted ? parse_double(n->value, &v) : 0;
  if (parsed < 0) {
    dk_error(e, doc, n, "%s: '%s' is outside the range of a double-precision number", what,
             n->value);
    return false;
  }
  if (parsed == 0) {
    dk_error(e, doc, n, "%s: expected a number%s%s, found %s%s%s", what, dim ? " in " : "",
             dim ? (doc->units == MS_UNITS_SI ? "SI units" : ms_unit_label(dim)) : "",
             n && n->kind == DK_SCALAR ? "'" : "",
             n ? (n->kind == DK_SCALAR ? n->value
                  : n->kind == DK_MAP  ? "a mapping"
                                       : "a list")
               : "nothing",
             n && n->kind == DK_SCALAR ? "'" : "");
    return false;
  }
  if (!isfinite(v)) {
    dk_error(e, doc, n, "%s: expected a finite number, found '%s'", what, n->value);
    return false;
  }
  double internal = v * ms_unit_to_internal(doc->units, dim);
  if (!isfinite(internal)) { /* e.g. 1e305 s in an SI deck: 1e310 in units of 10 us */
    dk_error(e, doc, n,
             "%s: '%s' is outside the range of a double-precision number once "
             "converted to internal units (%s)",
             what, n->value, ms_unit_label(dim));
    return false;
  }
  *out = internal;
  return true;
}

static void format_bound(char *buf, size_t n, double lo, double hi, bool lo_open) {
  if (isinf(lo) && isinf(hi)) snprintf(buf, n, "a number");
  else if (isinf(hi)) snprintf(buf, n, "a number %s %g", lo_open ? ">" : ">=", lo);
  else if (isinf(lo)) snprintf(buf, n, "a number <= %g", hi);
  else snprintf(buf, n, "a number in %s%g, %g]", lo_open ? "(" : "[", lo, hi);
}

static bool read_double_impl(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key,
                             ms_dim dim, bool required, double def, double lo, double hi,
                             bool lo_open, double *out) {
  char w[512], expect[128];
  where(map, key, w, sizeof w);
  double f = ms_unit_to_internal(doc->units, dim);
  /* bounds are given in internal units; messages show them in the deck's units */
  format_bound(expect, sizeof expect, lo / f, hi / f, lo_open);
  const dk_node *n = dk_get(map, key);
  if (!n) {
    if (required) {
      char ex[200];
      snprintf(ex, sizeof ex, "%s%s%s", expect, dim ? ", " : "",
               dim ? (doc->units == MS_UNITS_SI ? "SI units" : ms_unit_label(dim)) : "");
      missing(e, doc, map, key, ex);
      return false;
    }
    char text[64];
    snprintf(text, sizeof text, "%.17g", def / f);
    put_default(doc, map, key, text);
    *out = def;
    return true;
  }
  double v;
  if (!dk_node_double(e, doc, n, w, dim, &v)) return false;
  if ((lo_open ? !(v > lo) : !(v >= lo)) || !(v <= hi)) {
    dk_error(e, doc, n, "%s: expected %s, found %s", w, expect, n->value);
    return false;
  }
  *out = v;
  return true;
}

bool dk_read_double(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                    bool required, double def, double lo, double hi, double *out) {
  return read_double_impl(e, doc, map, key, dim, required, def, lo, hi, false, out);
}

bool dk_read_positive(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                      bool required, double def, double *out) {
  return read_double_impl(e, doc, map, key, dim, required, def, 0.0, INFINITY, true, out);
}

bool dk_read_int(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                 long def, long lo, long hi, long *out) {
  char w[512];
  where(map, key, w, sizeof w);
  const dk_node *n = dk_get(map, key);
  if (!n) {
    if (required) {
      char ex[128];
      snprintf(ex, sizeof ex, "an integer in [%ld, %ld]", lo, hi);
      missing(e, doc, map, key, ex);
      return false;
    }
    char text[32];
    snprintf(text, sizeof text, "%ld", def);
    put_default(doc, map, key, text);
    *out = def;
    return true;
  }
  char *end = NULL;
  errno = 0;
  long v = 0;
  if (n->kind == DK_SCALAR && !n->quoted) v = strtol(n->value, &end, 10);
  if (n->kind != DK_SCALAR || n->quoted || !n->value[0] || *end || errno == ERANGE) {
    dk_error(e, doc, n, "%s: expected an integer, found %s%s%s", w, n->kind == DK_SCALAR ? "'" : "",
             n->kind == DK_SCALAR ? n->value
             : n->kind == DK_MAP  ? "a mapping"
                                  : "a list",
             n->kind == DK_SCALAR ? "'" : "");
    return false;
  }
  if (v < lo || v > hi) {
    dk_error(e, doc, n, "%s: expected an integer in [%ld, %ld], found %ld", w, lo, hi, v);
    return false;
  }
  *out = v;
  return true;
}

bool dk_read_bool(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                  bool def, bool *out) {
  char w[512];
  where(map, key, w, sizeof w);
  const dk_node *n = dk_get(map, key);
  if (!n) {
    if (required) {
      missing(e, doc, map, key, "true or false");
      return false;
    }
    put_default(doc, map, key, def ? "true" : "false");
    *out = def;
    return true;
  }
  static const char *yes[] = {"true", "yes", "on"}, *no[] = {"false", "no", "off"};
  if (n->kind == DK_SCALAR) {
    for (int i = 0; i < 3; i++) {
      if (!strcasecmp(n->value, yes[i])) {
        *out = true;
        return true;
      }
      if (!strcasecmp(n->value, no[i])) {
        *out = false;
        return true;
      }
    }
  }
  dk_error(e, doc, n, "%s: expected true or false, found %s%s%s", w,
           n->kind == DK_SCALAR ? "'" : "", n->kind == DK_SCALAR ? n->value : "a collection",
           n->kind == DK_SCALAR ? "'" : "");
  return false;
}

bool dk_read_string(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                    const char *def, const char **out) {
  char w[512];
  where(map, key, w, sizeof w);
  const dk_node *n = dk_get(map, key);
  if (!n) {
    if (required) {
      missing(e, doc, map, key, "a text value");
      return false;
    }
    if (def) put_default(doc, map, key, def);
    *out = def;
    return true;
  }
  if (n->kind != DK_SCALAR || !n->value[0]) {
    dk_error(e, doc, n, "%s: expected a non-empty text value, found %s", w,
             n->kind == DK_MAP   ? "a mapping"
             : n->kind == DK_SEQ ? "a list"
                                 : "an empty value");
    return false;
  }
  *out = n->value;
  return true;
}

bool dk_read_enum(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                  int def, const char *const *choices, int *out) {
  char w[512], list[512] = "";
  where(map, key, w, sizeof w);
  for (int i = 0; choices[i]; i++) {
    size_t len = strlen(list);
    snprintf(list + len, sizeof list - len, "%s%s", i ? ", " : "", choices[i]);
  }
  const dk_node *n = dk_get(map, key);
  if (!n) {
    if (required) {
      char ex[600];
      snprintf(ex, sizeof ex, "one of: %s", list);
      missing(e, doc, map, key, ex);
      return false;
    }
    put_default(doc, map, key, choices[def]);
    *out = def;
    return true;
  }
  if (n->kind == DK_SCALAR) {
    for (int i = 0; choices[i]; i++)
      if (!strcmp(n->value, choices[i])) {
        *out = i;
        return true;
      }
  }
  const char *hint = n->kind == DK_SCALAR ? dk_suggest(n->value, choices) : NULL;
  if (hint)
    dk_error(e, doc, n, "%s: expected one of: %s; found '%s' (did you mean '%s'?)", w, list,
             n->value, hint);
  else
    dk_error(e, doc, n, "%s: expected one of: %s; found %s%s%s", w, list,
             n->kind == DK_SCALAR ? "'" : "", n->kind == DK_SCALAR ? n->value : "a collection",
             n->kind == DK_SCALAR ? "'" : "");
  return false;
}

bool dk_read_double_list(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                         bool required, double **out, size_t *count) {
  char w[512];
  where(map, key, w, sizeof w);
  *out = NULL;
  *count = 0;
  const dk_node *n = dk_get(map, key);
  if (!n) {
    if (required) missing(e, doc, map, key, "a list of numbers");
    return !required;
  }
  if (n->kind == DK_MAP) {
    dk_error(e, doc, n, "%s: expected a list of numbers, found a mapping", w);
    return false;
  }
  size_t len = n->kind == DK_SEQ ? n->n : 1;
  double *v = ms_calloc(len, sizeof *v);
  bool ok = true;
  for (size_t i = 0; i < len; i++) {
    const dk_node *item = n->kind == DK_SEQ ? n->items[i] : n;
    char wi[600];
    snprintf(wi, sizeof wi, "%s[%zu]", w, i);
    ok = dk_node_double(e, doc, item, wi, dim, &v[i]) && ok;
  }
  if (!ok) {
    free(v);
    return false;
  }
  *out = v;
  *count = len;
  return true;
}

void dk_read_units(dk_doc *doc, dk_errors *e) {
  static const char *const names[] = {"internal", "si", NULL};
  int u = 0;
  dk_read_enum(e, doc, doc->root, "units", false, 0, names, &u);
  doc->units = u == 1 ? MS_UNITS_SI : MS_UNITS_INTERNAL;
}

void dk_read_checkpoint_interval(dk_errors *e, dk_doc *doc, const dk_node *map, const char *where,
                                 const char *steps, long *every, double *time) {
  dk_read_int(e, doc, map, "checkpoint_every", false, 0, 0, 1L << 40, every);
  dk_read_double(e, doc, map, "checkpoint_time", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, time);
  if (*every > 0 && *time > 0)
    dk_error(e, doc, dk_get(map, "checkpoint_time"),
             "give %scheckpoint_every (%s) or %scheckpoint_time (simulated time), not both", where,
             steps, where);
}
