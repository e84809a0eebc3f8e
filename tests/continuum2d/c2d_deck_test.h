/* SPDX-License-Identifier: MIT */
/* The grid2d deck fixture of the 2D-grid deck tests (test_c2d_deck.c, test_c2d_blocks.c; include
 * after <cmocka.h>): a deck text loaded and read through the problem's reader. */
#ifndef C2D_DECK_TEST_H
#define C2D_DECK_TEST_H

#include <stdio.h>

#include "cont2d.h"

/* The deck (named deck.yaml in the messages), its materials and problem; p is NULL where the
 * deck is bad, e holds its errors. */
typedef struct c2d_deck {
  dk_doc *doc;
  eos_materials *mats;
  c2d_problem *p;
  dk_errors e;
} c2d_deck;

/* Loads and reads text; prints the errors, one a line. */
static inline void c2d_deck_load(c2d_deck *l, const char *text) {
  dk_errors_init(&l->e);
  l->doc = dk_load_string(text, "deck.yaml", &l->e);
  assert_non_null(l->doc);
  l->mats = eos_materials_read(l->doc, &l->e);
  assert_non_null(l->mats);
  l->p = c2d_problem_read(l->doc, dk_get(dk_root(l->doc), "grid2d"), l->mats, &l->e);
  for (size_t i = 0; i < l->e.n; ++i) printf("  %s\n", l->e.msg[i]);
}

static inline void c2d_deck_close(c2d_deck *l) {
  c2d_problem_destroy(&l->p);
  eos_materials_destroy(&l->mats);
  dk_free(l->doc);
  dk_errors_free(&l->e);
}

#endif
