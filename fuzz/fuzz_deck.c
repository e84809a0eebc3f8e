/* SPDX-License-Identifier: MIT */
/* libFuzzer harness: the deck parser (dk_load_string) and the typed readers.
 *
 * The input is the deck text. After parsing, a generic walk visits every mapping and list and
 * asks for each key through one of the typed readers (chosen from the key, so the fuzzer can
 * steer it), asks for an absent key with and without a default, reports unused keys, writes the
 * resolved deck and loads it again (for inputs whose size is a multiple of 8). Oracles: no sanitizer report; every error message names the
 * deck with a positive LINE:COL (fuzz_check_errors); the resolved deck parses back without error
 * and with the same top-level keys. */
#include "core.h"
#include "fuzz_util.h"

#include <math.h>

static const char *const choices[] = {"internal", "si", "hugoniot", "mg_cold", NULL};

static void walk(dk_doc *doc, const dk_node *n, dk_errors *e, int depth) {
  if (!n || depth > 80) return;
  if (dk_node_kind(n) == DK_SEQ) {
    for (size_t i = 0; i < dk_seq_len(n); i++) {
      const dk_node *item = dk_seq_at(n, i);
      if (dk_node_kind(item) == DK_SCALAR) {
        double v;
        dk_node_double(e, doc, item, "item", (ms_dim)(i % MS_DIM_COUNT), &v);
      } else {
        walk(doc, item, e, depth + 1);
      }
    }
    return;
  }
  if (dk_node_kind(n) != DK_MAP) return;
  size_t len = dk_map_len(n); /* readers append defaults: walk only the deck's own keys */
  for (size_t i = 0; i < len; i++) {
    char key[300];
    snprintf(key, sizeof key, "%s", dk_map_key(n, i));
    size_t sel = strlen(key) % 9;
    double d;
    long l;
    bool b;
    const char *s;
    int k;
    double *list;
    size_t nl;
    switch (sel) {
    case 0:
      dk_read_double(e, doc, n, key, MS_DIM_PRESSURE, true, 0, -1e3, 1e3, &d);
      break;
    case 1:
      dk_read_positive(e, doc, n, key, MS_DIM_DENSITY, true, 1, &d);
      break;
    case 2:
      dk_read_int(e, doc, n, key, true, 0, -5, 1000000, &l);
      break;
    case 3:
      dk_read_bool(e, doc, n, key, true, false, &b);
      break;
    case 4:
      dk_read_string(e, doc, n, key, true, NULL, &s);
      break;
    case 5:
      dk_read_enum(e, doc, n, key, true, 0, choices, &k);
      break;
    case 6:
      if (dk_read_double_list(e, doc, n, key, MS_DIM_VELOCITY, true, &list, &nl)) free(list);
      break;
    case 7:
      dk_expect_map(e, doc, dk_get(n, key), key);
      break;
    default:
      dk_expect_seq(e, doc, dk_get(n, key), key);
      break;
    }
    walk(doc, dk_map_value(n, i), e, depth + 1);
  }
  /* absent keys: a required one (error at the map's key) and defaults written back */
  double d;
  long l;
  bool b;
  const char *s;
  int k;
  dk_read_double(e, doc, n, "fuzz_absent_required", MS_DIM_TIME, true, 0, 0, 1, &d);
  dk_read_double(e, doc, n, "fuzz_default_double", MS_DIM_LENGTH, false, 0.25, 0, 1, &d);
  dk_read_int(e, doc, n, "fuzz_default_int", false, 7, 0, 10, &l);
  dk_read_bool(e, doc, n, "fuzz_default_bool", false, true, &b);
  dk_read_string(e, doc, n, "fuzz_default_string", false, "text: with # specials", &s);
  dk_read_enum(e, doc, n, "fuzz_default_enum", false, 1, choices, &k);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size > 1 << 16) return 0;
  char *text = malloc(size + 1);
  memcpy(text, data, size);
  text[size] = 0;
  const char *name = "fuzz.yaml";
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load_string(text, name, &e);
  if (doc) {
    dk_read_units(doc, &e);
    walk(doc, dk_root(doc), &e, 0);
    dk_report_unused(&e, doc);
  }
  fuzz_check_errors(&e, name);

  /* The round trip costs file I/O (2.5x the parse): do it for one input in eight, chosen by
   * size so that the choice is deterministic for each input (libFuzzer needs that). */
  if (doc && size % 8 == 0) {
    /* The resolved deck must be valid YAML again, with the same top-level keys. */
    const char *out = fuzz_scratch_path(".resolved.yaml");
    if (dk_write_resolved(doc, out) != MS_OK) abort();
    dk_errors e2;
    dk_errors_init(&e2);
    dk_doc *again = dk_load(out, &e2);
    if (!again || e2.n) {
      fprintf(stderr, "fuzz oracle: the resolved deck does not load again:\n");
      dk_errors_print(&e2, stderr);
      abort();
    }
    const dk_node *r1 = dk_root(doc), *r2 = dk_root(again);
    if (dk_map_len(r1) != dk_map_len(r2)) abort();
    for (size_t i = 0; i < dk_map_len(r1); i++)
      if (strcmp(dk_map_key(r1, i), dk_map_key(r2, i)) != 0) {
        fprintf(stderr, "fuzz oracle: key '%s' came back as '%s'\n", dk_map_key(r1, i),
                dk_map_key(r2, i));
        abort();
      }
    dk_free(again);
    dk_errors_free(&e2);
    remove(out);
  }
  dk_free(doc);
  dk_errors_free(&e);
  free(text);
  return 0;
}
