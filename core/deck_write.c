/* SPDX-License-Identifier: MIT */
/* The deck written back (run_info's resolved deck, with every default a reader filled in) and
 * the deck hash that checkpoints compare. */
#include "core.h"
#include "deck_impl.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* Resolved deck                                                                               */

/* Decode one UTF-8 sequence at s (libyaml hands out valid UTF-8); returns its length and the
 * code point in *cp, or 1 and the raw byte for an invalid sequence. */
static int utf8_decode(const unsigned char *s, unsigned long *cp) {
  int len = s[0] < 0x80             ? 1
            : (s[0] & 0xE0) == 0xC0 ? 2
            : (s[0] & 0xF0) == 0xE0 ? 3
            : (s[0] & 0xF8) == 0xF0 ? 4
                                    : 0;
  if (len == 0) {
    *cp = s[0];
    return 1;
  }
  unsigned long c = len == 1 ? s[0] : s[0] & (0x7F >> len);
  for (int i = 1; i < len; i++) {
    if ((s[i] & 0xC0) != 0x80) {
      *cp = s[0];
      return 1;
    }
    c = (c << 6) | (s[i] & 0x3F);
  }
  *cp = c;
  return len;
}

/* Characters YAML allows verbatim inside a double-quoted scalar (YAML 1.1 "printable", minus
 * the line separators NEL, LS, PS and the BOM, which a reader would fold or drop). */
static bool yaml_printable(unsigned long c) {
  if (c == 0x85 || c == 0x2028 || c == 0x2029 || c == 0xFEFF) return false;
  return (c >= 0x20 && c <= 0x7E) || (c >= 0xA0 && c <= 0xD7FF) || (c >= 0xE000 && c <= 0xFFFD) ||
         (c >= 0x10000 && c <= 0x10FFFF);
}

static bool needs_quotes(const char *s) {
  if (!s[0]) return true;
  if (!strncmp(s, "...", 3)) return true; /* the document end marker (found by fuzz_deck) */
  if (strchr("-?:,[]{}#&*!|>'\"%@` ", s[0])) {
    /* a leading '-' followed by a digit is a number */
    if (!(s[0] == '-' && s[1] >= '0' && s[1] <= '9')) return true;
  }
  for (const unsigned char *c = (const unsigned char *)s; *c;) {
    unsigned long cp;
    c += utf8_decode(c, &cp);
    if (cp == ':' || cp == '#' || cp == '"' || cp == '\\' || !yaml_printable(cp)) return true;
  }
  size_t n = strlen(s);
  return s[n - 1] == ' ';
}

/* A key or a scalar value, double-quoted with escapes when plain text would not read back the
 * same (the resolved deck must load again: tests/reliability, fuzz/fuzz_deck.c). */
static void emit_text(FILE *f, const char *s, bool force_quotes) {
  if (!force_quotes && !needs_quotes(s)) {
    fputs(s, f);
    return;
  }
  fputc('"', f);
  for (const unsigned char *c = (const unsigned char *)s; *c;) {
    unsigned long cp;
    int len = utf8_decode(c, &cp);
    if (cp == '"' || cp == '\\') fprintf(f, "\\%c", (int)cp);
    else if (cp == '\n') fputs("\\n", f);
    else if (yaml_printable(cp)) fwrite(c, 1, (size_t)len, f);
    else if (cp <= 0xFF) fprintf(f, "\\x%02lx", cp);
    else if (cp <= 0xFFFF) fprintf(f, "\\u%04lx", cp);
    else fprintf(f, "\\U%08lx", cp);
    c += len;
  }
  fputc('"', f);
}

static void emit_scalar(FILE *f, const dk_node *n) { emit_text(f, n->value, n->quoted); }

/* `first_indent` is the indentation of the first line: a mapping inside a list starts on the
 * line of its "- ". */
static void emit(FILE *f, const dk_node *n, int indent, int first_indent) {
  for (size_t i = 0; i < n->n; i++) {
    const dk_node *c = n->items[i];
    fprintf(f, "%*s", i ? indent : first_indent, "");
    if (n->kind == DK_MAP) {
      emit_text(f, n->keys[i], false);
      fputc(':', f);
    } else {
      fputc('-', f);
    }
    if (c->kind == DK_SCALAR) {
      fputc(' ', f);
      emit_scalar(f, c);
      if (n->kind == DK_MAP && n->is_default[i]) fputs("  # default", f);
      fputc('\n', f);
    } else if (c->n == 0) {
      fputs(c->kind == DK_MAP ? " {}\n" : " []\n", f);
    } else if (n->kind == DK_SEQ && c->kind == DK_MAP) {
      fputc(' ', f);
      emit(f, c, indent + 2, 0);
    } else {
      fputc('\n', f);
      emit(f, c, indent + 2, indent + 2);
    }
  }
}

ms_status dk_write_resolved(const dk_doc *doc, const char *path) {
  ms_afile af;
  ms_status s = ms_afile_open(&af, path);
  if (s) return s;
  fprintf(af.f, "# Resolved deck written by mscale %s from %s\n", MSCALE_VERSION_STRING, doc->file);
  fprintf(af.f, "# Every key the run used, with defaults filled in (marked '# default').\n");
  for (size_t i = 0; i < doc->noverrides; i++) {
    fputs("# overridden on the command line: --set ", af.f);
    for (const char *c = doc->overrides[i]; *c; c++) fputc(*c == '\n' ? ' ' : *c, af.f);
    fputc('\n', af.f);
  }
  emit(af.f, doc->root, 0, 0);
  return ms_afile_commit(&af);
}

/* ------------------------------------------------------------------------------------------ */
/* Deck hash (checkpoints refuse to continue a different deck)                                 */

/* FNV-1a, 64 bit */
static uint64_t fnv1a(uint64_t h, const void *data, size_t n) {
  const unsigned char *c = data;
  for (size_t i = 0; i < n; i++) h = (h ^ c[i]) * 0x100000001b3ull;
  return h;
}

static bool hash_skipped(const dk_node *n, const char *const *skip) {
  for (const char *const *s = skip; s && *s; s++)
    if (n->path && !strcmp(n->path, *s)) return true;
  return false;
}

/* A skipped node leaves no trace, key included: where a key sits in its map depends on whether
 * the deck, a --set override or a reader's default put it there. */
static uint64_t hash_node(uint64_t h, const dk_node *n, const char *const *skip) {
  char kind = n->kind == DK_SCALAR ? 's' : (n->kind == DK_MAP ? 'm' : 'q');
  h = fnv1a(h, &kind, 1);
  if (n->kind == DK_SCALAR)
    return fnv1a(h, n->value ? n->value : "", n->value ? strlen(n->value) + 1 : 1);
  for (size_t i = 0; i < n->n; i++) {
    if (hash_skipped(n->items[i], skip)) continue;
    if (n->kind == DK_MAP) h = fnv1a(h, n->keys[i], strlen(n->keys[i]) + 1);
    h = hash_node(h, n->items[i], skip);
  }
  return fnv1a(h, "}", 1);
}

uint64_t dk_hash(const dk_doc *doc, const char *const *skip) {
  uint64_t h = 0xcbf29ce484222325ull;
  return doc && doc->root ? hash_node(h, doc->root, skip) : h;
}

uint64_t dk_hash_doubles(uint64_t h, const double *v, size_t n) {
  return fnv1a(h, v, n * sizeof *v);
}
