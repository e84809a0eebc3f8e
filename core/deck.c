/* SPDX-License-Identifier: MIT */
/* Deck tree: libyaml's document model copied into nodes that remember their position, their
 * path in the deck (for messages) and which keys a reader asked for (for unknown-key reports).
 */
#include "core.h"
#include "deck_impl.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <yaml.h>

/* Guards against alias bombs and runaway nesting in hostile decks. Nodes written out in the
 * file are bounded by its size; nodes copied through aliases are not, and a "billion laughs"
 * deck reaching DK_MAX_NODES took > 10 s and ~1 GB under ASan (fuzz_deck timeout), so copies
 * through aliases have their own, much smaller budget (real decks reuse a block or two). */
enum { DK_MAX_DEPTH = 64, DK_MAX_NODES = 1000000, DK_MAX_ALIAS_NODES = 10000 };

/* ------------------------------------------------------------------------------------------ */
/* Nodes                                                                                       */

dk_node *dk_node_new(dk_kind kind, int line, int col, const char *path) {
  dk_node *n = ms_calloc(1, sizeof *n);
  n->kind = kind;
  n->line = line;
  n->col = col;
  n->path = ms_strdup(path);
  return n;
}

static void node_free(dk_node *n) {
  if (!n) return;
  for (size_t i = 0; i < n->n; i++) {
    node_free(n->items[i]);
    if (n->keys) free(n->keys[i]);
  }
  for (size_t i = 0; i < n->nasked; i++) free(n->asked[i]);
  free(n->asked);
  free(n->items);
  free(n->keys);
  free(n->used);
  free(n->is_default);
  free(n->value);
  free(n->path);
  free(n->origin);
  free(n);
}

void dk_node_append(dk_node *parent, const char *key, dk_node *child, bool used, bool is_default) {
  if (parent->n == parent->cap) {
    parent->cap = parent->cap ? 2 * parent->cap : 4;
    parent->items = ms_realloc(parent->items, parent->cap, sizeof *parent->items);
    if (parent->kind == DK_MAP) {
      parent->keys = ms_realloc(parent->keys, parent->cap, sizeof *parent->keys);
      parent->used = ms_realloc(parent->used, parent->cap, sizeof *parent->used);
      parent->is_default = ms_realloc(parent->is_default, parent->cap, sizeof *parent->is_default);
    }
  }
  size_t i = parent->n++;
  parent->items[i] = child;
  if (parent->kind == DK_MAP) {
    parent->keys[i] = ms_strdup(key);
    parent->used[i] = used;
    parent->is_default[i] = is_default;
  }
}

char *dk_child_path(const char *parent, const char *key, size_t index) {
  char idx[32];
  snprintf(idx, sizeof idx, "[%zu]", index);
  const char *sep = key && parent[0] ? "." : "";
  const char *tail = key ? key : idx;
  size_t n = strlen(parent) + strlen(sep) + strlen(tail) + 1;
  char *p = ms_calloc(n, 1);
  snprintf(p, n, "%s%s%s", parent, sep, tail);
  return p;
}

typedef struct build_state {
  yaml_document_t *ydoc;
  dk_doc *doc;
  dk_errors *e;
  size_t nnodes, alias_nodes;
  unsigned char *seen; /* per libyaml node index: already copied once (a second use is an alias) */
  size_t nseen;
  bool failed;
} build_state;

static dk_node *build(build_state *st, int index, const char *path, int depth, bool in_alias) {
  yaml_node_t *y = yaml_document_get_node(st->ydoc, index);
  if (!y || st->failed) return NULL;
  int line = (int)y->start_mark.line + 1, col = (int)y->start_mark.column + 1;
  if (index >= 1 && (size_t)index <= st->nseen) {
    if (st->seen[index - 1]) in_alias = true;
    st->seen[index - 1] = 1;
  }
  if (in_alias) st->alias_nodes++;
  if (depth > DK_MAX_DEPTH || ++st->nnodes > DK_MAX_NODES || st->alias_nodes > DK_MAX_ALIAS_NODES) {
    dk_error_at(st->e, st->doc->file, line, col,
                "the deck nests deeper than %d levels, expands to more than %d nodes, or "
                "copies more than %d nodes through aliases (recursive or exploding aliases?)",
                DK_MAX_DEPTH, DK_MAX_NODES, DK_MAX_ALIAS_NODES);
    st->failed = true;
    return NULL;
  }
  switch (y->type) {
  case YAML_SCALAR_NODE: {
    dk_node *n = dk_node_new(DK_SCALAR, line, col, path);
    n->value = ms_calloc(y->data.scalar.length + 1, 1);
    memcpy(n->value, y->data.scalar.value, y->data.scalar.length);
    if (strlen(n->value) != y->data.scalar.length) {
      dk_error_at(st->e, st->doc->file, line, col, "%s: a value contains a NUL character",
                  path[0] ? path : "deck");
    }
    n->quoted = y->data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE ||
                y->data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE;
    return n;
  }
  case YAML_SEQUENCE_NODE: {
    dk_node *n = dk_node_new(DK_SEQ, line, col, path);
    size_t i = 0;
    for (yaml_node_item_t *it = y->data.sequence.items.start; it < y->data.sequence.items.top;
         it++, i++) {
      char *cp = dk_child_path(path, NULL, i);
      dk_node *c = build(st, *it, cp, depth + 1, in_alias);
      free(cp);
      if (!c) break;
      dk_node_append(n, NULL, c, false, false);
    }
    return n;
  }
  case YAML_MAPPING_NODE: {
    dk_node *n = dk_node_new(DK_MAP, line, col, path);
    for (yaml_node_pair_t *pr = y->data.mapping.pairs.start; pr < y->data.mapping.pairs.top; pr++) {
      yaml_node_t *k = yaml_document_get_node(st->ydoc, pr->key);
      if (!k) continue;
      int kl = (int)k->start_mark.line + 1, kc = (int)k->start_mark.column + 1;
      if (k->type != YAML_SCALAR_NODE) {
        dk_error_at(st->e, st->doc->file, kl, kc, "%s: a key must be a plain name, not a %s",
                    path[0] ? path : "deck", k->type == YAML_MAPPING_NODE ? "mapping" : "list");
        continue;
      }
      char key[256];
      size_t kn = k->data.scalar.length < sizeof key - 1 ? k->data.scalar.length : sizeof key - 1;
      memcpy(key, k->data.scalar.value, kn);
      key[kn] = 0;
      bool dup = false;
      for (size_t j = 0; j < n->n; j++)
        if (!strcmp(n->keys[j], key)) dup = true;
      if (dup) {
        dk_error_at(st->e, st->doc->file, kl, kc, "%s: key '%s' appears twice",
                    path[0] ? path : "deck", key);
        continue;
      }
      char *cp = dk_child_path(path, key, 0);
      dk_node *c = build(st, pr->value, cp, depth + 1, in_alias);
      free(cp);
      if (!c) break;
      c->key_line = kl;
      c->key_col = kc;
      dk_node_append(n, key, c, false, false);
    }
    return n;
  }
  default:
    return NULL;
  }
}

static char *dir_of(const char *path) {
  const char *slash = strrchr(path, '/');
  if (!slash) return ms_strdup(".");
  if (slash == path) return ms_strdup("/");
  char *d = ms_calloc((size_t)(slash - path) + 1, 1);
  memcpy(d, path, (size_t)(slash - path));
  return d;
}

static dk_doc *load_from_parser(yaml_parser_t *parser, const char *name, const char *dir,
                                dk_errors *e) {
  dk_doc *doc = ms_calloc(1, sizeof *doc);
  doc->file = ms_strdup(name);
  doc->dir = ms_strdup(dir);
  doc->units = MS_UNITS_INTERNAL;
  yaml_document_t ydoc;
  if (!yaml_parser_load(parser, &ydoc)) {
    int line = (int)parser->problem_mark.line + 1, col = (int)parser->problem_mark.column + 1;
    dk_error_at(e, name, line, col, "YAML syntax error: %s%s%s",
                parser->problem ? parser->problem : "cannot parse", parser->context ? " " : "",
                parser->context ? parser->context : "");
    dk_free(doc);
    return NULL;
  }
  build_state st = {.ydoc = &ydoc, .doc = doc, .e = e};
  st.nseen = (size_t)(ydoc.nodes.top - ydoc.nodes.start);
  st.seen = ms_calloc(st.nseen ? st.nseen : 1, 1);
  yaml_node_t *root = yaml_document_get_root_node(&ydoc);
  if (!root) {
    doc->root = dk_node_new(DK_MAP, 1, 1, "");
  } else {
    doc->root = build(&st, 1, "", 0, false);
    if (!doc->root || st.failed) {
      free(st.seen);
      yaml_document_delete(&ydoc);
      dk_free(doc);
      return NULL;
    }
    if (doc->root->kind != DK_MAP) {
      dk_error(e, doc, doc->root,
               "a deck must be a mapping of keys (e.g. 'materials:'), "
               "found a %s",
               doc->root->kind == DK_SEQ ? "list" : "single value");
      free(st.seen);
      yaml_document_delete(&ydoc);
      dk_free(doc);
      return NULL;
    }
  }
  free(st.seen);
  yaml_document_delete(&ydoc);
  /* A second YAML document in the same file is almost certainly a mistake. */
  yaml_document_t extra;
  if (yaml_parser_load(parser, &extra)) {
    yaml_node_t *r = yaml_document_get_root_node(&extra);
    if (r)
      dk_error_at(e, name, (int)r->start_mark.line + 1, (int)r->start_mark.column + 1,
                  "a deck holds one YAML document; found a second one ('---')");
    yaml_document_delete(&extra);
  } else {
    int line = (int)parser->problem_mark.line + 1, col = (int)parser->problem_mark.column + 1;
    dk_error_at(e, name, line, col, "YAML syntax error: %s",
                parser->problem ? parser->problem : "cannot parse");
  }
  return doc;
}

dk_doc *dk_load(const char *path, dk_errors *e) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    dk_error_at(e, path, 0, 0, "cannot open the deck file");
    return NULL;
  }
  yaml_parser_t parser;
  yaml_parser_initialize(&parser);
  yaml_parser_set_input_file(&parser, f);
  char *dir = dir_of(path);
  dk_doc *doc = load_from_parser(&parser, path, dir, e);
  free(dir);
  yaml_parser_delete(&parser);
  fclose(f);
  return doc;
}

dk_doc *dk_load_string(const char *text, const char *name, dk_errors *e) {
  yaml_parser_t parser;
  yaml_parser_initialize(&parser);
  yaml_parser_set_input_string(&parser, (const unsigned char *)text, strlen(text));
  dk_doc *doc = load_from_parser(&parser, name ? name : "<string>", ".", e);
  yaml_parser_delete(&parser);
  return doc;
}

void dk_free(dk_doc *doc) {
  if (!doc) return;
  for (size_t i = 0; i < doc->noverrides; i++) free(doc->overrides[i]);
  free(doc->overrides);
  node_free(doc->root);
  free(doc->file);
  free(doc->dir);
  free(doc);
}

/* ------------------------------------------------------------------------------------------ */
/* Command-line overrides                                                                      */

/* A copy of `src` (from the override's own small YAML document) at `path` in the deck. */
static dk_node *clone_node(const dk_node *src, const char *path, const char *origin) {
  dk_node *n = dk_node_new(src->kind, 0, 0, path);
  n->origin = ms_strdup(origin);
  n->quoted = src->quoted;
  if (src->value) n->value = ms_strdup(src->value);
  for (size_t i = 0; i < src->n; i++) {
    char *cp = dk_child_path(path, src->kind == DK_MAP ? src->keys[i] : NULL, i);
    dk_node_append(n, src->kind == DK_MAP ? src->keys[i] : NULL,
                   clone_node(src->items[i], cp, origin), false, false);
    free(cp);
  }
  return n;
}

/* "line L of FILE", or the override a node came from. */
static void node_where(const dk_node *n, const dk_doc *doc, char *buf, size_t len) {
  if (n->origin) snprintf(buf, len, "from %s", n->origin);
  else snprintf(buf, len, "line %d of %s", n->line, doc->file);
}

bool dk_set(dk_doc *doc, const char *path, const char *value, dk_errors *e) {
  size_t olen = strlen(path) + strlen(value) + 8;
  char *origin = ms_calloc(olen, 1);
  snprintf(origin, olen, "--set %s=%s", path, value);
  /* the value: parsed as the YAML of one mapping entry */
  size_t tlen = strlen(value) + 8;
  char *text = ms_calloc(tlen, 1);
  snprintf(text, tlen, "v: %s\n", value);
  dk_errors ve;
  dk_errors_init(&ve);
  dk_doc *vdoc = strchr(value, '\n') ? NULL : dk_load_string(text, origin, &ve);
  free(text);
  const dk_node *vnode = vdoc && !ve.n && vdoc->root->n == 1 ? vdoc->root->items[0] : NULL;
  dk_errors_free(&ve);
  bool ok = vnode != NULL;
  if (!ok) dk_error_at(e, origin, 0, 0, "the value is not a YAML value on one line");
  /* walk the path: key segments separated by '.', each with optional [N] suffixes */
  dk_node *cur = doc->root, *parent = NULL;
  dk_node *created_in = NULL; /* the map where the path's first new key was appended */
  size_t slot = 0;
  char seg[256];
  const char *p = path;
  if (ok && !*p) {
    dk_error_at(e, origin, 0, 0, "no key path before '='");
    ok = false;
  }
  while (ok && *p) {
    size_t k = strcspn(p, ".[");
    if (k == 0 || k >= sizeof seg) {
      dk_error_at(e, origin, 0, 0, "a key path is names separated by '.', e.g. continuum.time.end");
      ok = false;
      break;
    }
    memcpy(seg, p, k);
    seg[k] = 0;
    p += k;
    if (cur->kind != DK_MAP) {
      char at[300];
      node_where(cur, doc, at, sizeof at);
      dk_error_at(e, origin, 0, 0, "%s (%s) is not a mapping: it has no key '%s'",
                  cur->path[0] ? cur->path : "the deck", at, seg);
      ok = false;
      break;
    }
    size_t i = 0;
    while (i < cur->n && strcmp(cur->keys[i], seg)) i++;
    if (i == cur->n) { /* a new key: a mapping on the way, the value at the end */
      if (!created_in) created_in = cur;
      char *cp = dk_child_path(cur->path, seg, 0);
      dk_node *m = dk_node_new(DK_MAP, 0, 0, cp);
      m->origin = ms_strdup(origin);
      free(cp);
      dk_node_append(cur, seg, m, false, false);
    }
    parent = cur;
    slot = i;
    cur = cur->items[i];
    while (ok && *p == '[') {
      char *end;
      long idx = strtol(p + 1, &end, 10);
      if (end == p + 1 || *end != ']' || idx < 0) {
        dk_error_at(e, origin, 0, 0, "a list index is [N] with N >= 0");
        ok = false;
        break;
      }
      p = end + 1;
      if (cur->kind != DK_SEQ || (size_t)idx >= cur->n) {
        char at[300];
        node_where(cur, doc, at, sizeof at);
        dk_error_at(e, origin, 0, 0, "%s (%s) has no item [%ld]", cur->path, at, idx);
        ok = false;
        break;
      }
      parent = cur;
      slot = (size_t)idx;
      cur = cur->items[idx];
    }
    if (ok && *p == '.') {
      p++;
      if (!*p) {
        dk_error_at(e, origin, 0, 0, "the key path ends with '.'");
        ok = false;
      }
    }
  }
  if (ok) {
    dk_node *n = clone_node(vnode, cur->path, origin);
    n->key_line = 0;
    node_free(cur);
    parent->items[slot] = n;
    if (parent->kind == DK_MAP) parent->used[slot] = parent->is_default[slot] = false;
    doc->overrides = ms_realloc(doc->overrides, doc->noverrides + 1, sizeof *doc->overrides);
    doc->overrides[doc->noverrides++] = ms_strdup(origin + 6);
  } else if (created_in) { /* a path that failed leaves no new keys behind (no knock-on errors) */
    size_t last = --created_in->n;
    node_free(created_in->items[last]);
    free(created_in->keys[last]);
  }
  dk_free(vdoc);
  free(origin);
  return ok;
}

const dk_node *dk_root(const dk_doc *doc) { return doc->root; }
const char *dk_file(const dk_doc *doc) { return doc->file; }
const char *dk_dir(const dk_doc *doc) { return doc->dir; }
ms_unit_system dk_units(const dk_doc *doc) { return doc->units; }

static bool file_exists(const char *path) { return access(path, F_OK) == 0; }

const char *ms_data_dir(void) {
  static char dir[4096];
  static bool done = false;
  if (done) return dir[0] ? dir : NULL;
  done = true;
  const char *env = getenv("MSCALE_DATA_DIR");
  if (env && env[0]) {
    snprintf(dir, sizeof dir, "%s", env);
    return dir;
  }
  /* PREFIX/BINDIR/mscale -> PREFIX/DATADIR/mscale: a relocated install still finds its data */
  char exe[4096];
  ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n > 0) {
    exe[n] = 0;
    char *slash = strrchr(exe, '/');
    if (slash) *slash = 0; /* the binary's directory */
    size_t lb = strlen(MSCALE_INSTALL_BINDIR), le = strlen(exe);
    if (le > lb && !strcmp(exe + le - lb, MSCALE_INSTALL_BINDIR) && exe[le - lb - 1] == '/') {
      exe[le - lb - 1] = 0;
      int w = snprintf(dir, sizeof dir, "%s/%s/mscale", exe, MSCALE_INSTALL_DATADIR);
      if (w > 0 && (size_t)w < sizeof dir && file_exists(dir)) return dir;
    }
  }
  snprintf(dir, sizeof dir, "%s", MSCALE_INSTALL_FULL_DATADIR "/mscale");
  if (file_exists(dir)) return dir;
  dir[0] = 0;
  return NULL;
}

/* Relative to the deck's directory; if no such file exists, in the installed data directory
 * (ms_data_dir): PATH without its leading "./" and "../" (a shipped deck's
 * "../eos/data/al_osa_cold.txt" is DATA/eos/data/al_osa_cold.txt), then DATA/inputs/PATH (the
 * history files beside the shipped decks). A deck copied out of share/mscale/inputs still runs. */
char *dk_resolve_path(const dk_doc *doc, const char *path) {
  if (path[0] == '/' || !doc->dir[0]) return ms_strdup(path);
  size_t n = strlen(doc->dir) + strlen(path) + 2;
  char *p = ms_calloc(n, 1);
  snprintf(p, n, "%s/%s", doc->dir, path);
  const char *data = file_exists(p) ? NULL : ms_data_dir();
  if (!data) return p;
  const char *rel = path;
  while (!strncmp(rel, "./", 2) || !strncmp(rel, "../", 3)) rel += rel[1] == '/' ? 2 : 3;
  const char *const sub[] = {"", "inputs/"};
  for (int i = 0; i < 2; i++) {
    size_t m = strlen(data) + strlen(sub[i]) + strlen(rel) + 2;
    char *q = ms_calloc(m, 1);
    snprintf(q, m, "%s/%s%s", data, sub[i], rel);
    if (file_exists(q)) {
      free(p);
      return q;
    }
    free(q);
  }
  return p;
}

dk_kind dk_node_kind(const dk_node *n) { return n->kind; }
int dk_node_line(const dk_node *n) { return n->line; }
int dk_node_col(const dk_node *n) { return n->col; }
const char *dk_scalar(const dk_node *n) { return n && n->kind == DK_SCALAR ? n->value : NULL; }
size_t dk_seq_len(const dk_node *n) { return n && n->kind == DK_SEQ ? n->n : 0; }
const dk_node *dk_seq_at(const dk_node *n, size_t i) {
  return n && n->kind == DK_SEQ && i < n->n ? n->items[i] : NULL;
}
size_t dk_map_len(const dk_node *n) { return n && n->kind == DK_MAP ? n->n : 0; }
const char *dk_map_key(const dk_node *n, size_t i) {
  return n && n->kind == DK_MAP && i < n->n ? n->keys[i] : NULL;
}
const dk_node *dk_map_value(const dk_node *n, size_t i) {
  if (!n || n->kind != DK_MAP || i >= n->n) return NULL;
  ((dk_node *)n)->used[i] = true;
  return n->items[i];
}

static void remember_asked(dk_node *map, const char *key) {
  for (size_t i = 0; i < map->nasked; i++)
    if (!strcmp(map->asked[i], key)) return;
  map->asked = ms_realloc(map->asked, map->nasked + 1, sizeof *map->asked);
  map->asked[map->nasked++] = ms_strdup(key);
}

const dk_node *dk_get(const dk_node *cmap, const char *key) {
  if (!cmap || cmap->kind != DK_MAP) return NULL;
  dk_node *map = (dk_node *)cmap; /* asking for a key is recorded, the content is not changed */
  remember_asked(map, key);
  for (size_t i = 0; i < map->n; i++) {
    if (!strcmp(map->keys[i], key)) {
      map->used[i] = true;
      return map->items[i];
    }
  }
  return NULL;
}

static const char *kind_word(dk_kind k) {
  return k == DK_MAP ? "a mapping" : k == DK_SEQ ? "a list" : "a single value";
}

bool dk_expect_map(dk_errors *e, const dk_doc *doc, const dk_node *n, const char *what) {
  if (n && n->kind == DK_MAP) return true;
  if (n) dk_error(e, doc, n, "%s: expected a mapping of keys, found %s", what, kind_word(n->kind));
  return false;
}

bool dk_expect_seq(dk_errors *e, const dk_doc *doc, const dk_node *n, const char *what) {
  if (n && n->kind == DK_SEQ) return true;
  if (n) dk_error(e, doc, n, "%s: expected a list, found %s", what, kind_word(n->kind));
  return false;
}

/* ------------------------------------------------------------------------------------------ */
/* Unknown keys                                                                                */

static size_t edit_distance(const char *a, const char *b) {
  size_t la = strlen(a), lb = strlen(b);
  if (la > 63 || lb > 63) return 99;
  size_t d[64][64];
  for (size_t i = 0; i <= la; i++) d[i][0] = i;
  for (size_t j = 0; j <= lb; j++) d[0][j] = j;
  for (size_t i = 1; i <= la; i++)
    for (size_t j = 1; j <= lb; j++) {
      size_t sub = d[i - 1][j - 1] + (a[i - 1] != b[j - 1]);
      size_t del = d[i - 1][j] + 1, ins = d[i][j - 1] + 1;
      d[i][j] = sub < del ? (sub < ins ? sub : ins) : (del < ins ? del : ins);
    }
  return d[la][lb];
}

const char *dk_suggest(const char *word, const char *const *choices) {
  if (!word || !choices) return NULL;
  const char *best = NULL;
  size_t len = strlen(word), best_d = len / 2 + 1 < 3 ? len / 2 + 1 : 3;
  for (size_t i = 0; choices[i]; i++) {
    size_t d = edit_distance(word, choices[i]);
    if (d > 0 && d < best_d) {
      best_d = d;
      best = choices[i];
    }
  }
  return best;
}

void dk_report_unknown_key(dk_errors *e, const dk_doc *doc, const dk_node *map, size_t i,
                           const char *what, const char *const *allowed) {
  if (!map || map->kind != DK_MAP || i >= map->n) return;
  const char *key = map->keys[i], *hint = dk_suggest(key, allowed);
  for (size_t k = 0; hint && k < map->n; k++) /* a close key written in the map is not meant */
    if (!strcmp(map->keys[k], hint) && !map->is_default[k]) hint = NULL;
  if (hint) {
    char *about = dk_child_path(map->path, hint, 0);
    dk_error_role(e, doc, map->items[i], 0, 0, DK_ROLE_MISSPELT, about,
                  "%s: unknown key '%s' (did you mean '%s'?)", what, key, hint);
    free(about);
    return;
  }
  char list[600] = "";
  for (size_t k = 0; allowed[k]; ++k) {
    size_t len = strlen(list);
    snprintf(list + len, sizeof list - len, "%s%s", k ? ", " : "", allowed[k]);
  }
  dk_error(e, doc, map->items[i], "%s: unknown key '%s' (expected one of: %s)", what, key, list);
}

static void report_unused(dk_errors *e, const dk_doc *doc, const dk_node *n) {
  if (n->kind == DK_SEQ) {
    for (size_t i = 0; i < n->n; i++) report_unused(e, doc, n->items[i]);
    return;
  }
  if (n->kind != DK_MAP) return;
  for (size_t i = 0; i < n->n; i++) {
    if (n->used[i]) {
      report_unused(e, doc, n->items[i]);
      continue;
    }
    char expected[1024] = "";
    const char *best = NULL;
    size_t best_d = 3;
    for (size_t j = 0; j < n->nasked; j++) {
      size_t len = strlen(expected);
      snprintf(expected + len, sizeof expected - len, "%s%s", j ? ", " : "", n->asked[j]);
      size_t dist = edit_distance(n->keys[i], n->asked[j]);
      bool present = false;
      for (size_t k = 0; k < n->n; k++) /* a default filled in by a reader was not written */
        if (!strcmp(n->keys[k], n->asked[j]) && !n->is_default[k]) present = true;
      if (dist < best_d && !present) {
        best_d = dist;
        best = n->asked[j];
      }
    }
    const char *where = n->path[0] ? n->path : "top level";
    if (best) {
      char *about = dk_child_path(n->path, best, 0);
      dk_error_role(e, doc, n->items[i], 0, 0, DK_ROLE_MISSPELT, about,
                    "%s: unknown key '%s' (did you mean '%s'?)", where, n->keys[i], best);
      free(about);
    } else if (n->nasked)
      dk_error(e, doc, n->items[i], "%s: unknown key '%s' (expected one of: %s)", where, n->keys[i],
               expected);
    else
      dk_error(e, doc, n->items[i], "%s: unknown key '%s' (not used by this problem)", where,
               n->keys[i]);
  }
}

static void mark_used(dk_node *n) {
  for (size_t i = 0; i < n->n; i++) {
    if (n->kind == DK_MAP) n->used[i] = true;
    mark_used(n->items[i]);
  }
}

void dk_mark_used(const dk_node *map, const char *key) {
  if (!map || map->kind != DK_MAP) return;
  for (size_t i = 0; i < map->n; i++)
    if (!strcmp(map->keys[i], key)) {
      ((dk_node *)map)->used[i] = true; /* bookkeeping only; the content is unchanged */
      mark_used(map->items[i]);
    }
}

void dk_report_unused(dk_errors *e, const dk_doc *doc) {
  if (doc && doc->root) report_unused(e, doc, doc->root);
}

const char *dk_yaml_version(void) { return yaml_get_version_string(); }
