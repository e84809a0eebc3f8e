/* SPDX-License-Identifier: MIT */
/* Private layout of the deck tree (core/deck.c, core/deck_read.c). */
#ifndef MSCALE_DECK_IMPL_H
#define MSCALE_DECK_IMPL_H

#include "core.h"

struct dk_node {
  dk_kind kind;
  int line, col;         /* 1-based position in the deck */
  int key_line, key_col; /* position of the key naming this node in its parent map (0: none) */
  char *path;            /* e.g. "materials[0].eos.rho0", for messages */
  char *value;           /* scalar text */
  bool quoted;           /* scalar was quoted in the deck */
  size_t n, cap;         /* children */
  dk_node **items;       /* map values or list items */
  char **keys;           /* map keys */
  bool *used;            /* map: a reader asked for this key */
  bool *is_default;      /* map: the value was filled in by a reader's default */
  char **asked;          /* map: every key a reader asked for (for "did you mean") */
  size_t nasked;
  char *origin; /* set by a command-line override: messages name it instead of FILE:LINE:COL */
};

struct dk_doc {
  char *file, *dir;
  dk_node *root;
  ms_unit_system units;
  char **overrides; /* the `--set PATH=VALUE` applied (dk_set), for the resolved deck */
  size_t noverrides;
};

dk_node *dk_node_new(dk_kind kind, int line, int col, const char *path);
void dk_node_append(dk_node *parent, const char *key, dk_node *child, bool used, bool is_default);
char *dk_child_path(const char *parent, const char *key, size_t index);
/* dk_error with a role (DK_ROLE_*) about a key path; line > 0 overrides the node's position. */
void dk_error_role(dk_errors *e, const dk_doc *doc, const dk_node *at, int line, int col, int role,
                   const char *about, const char *fmt, ...) __attribute__((format(printf, 8, 9)));

#endif
