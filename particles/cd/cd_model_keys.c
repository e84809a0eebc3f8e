/* SPDX-License-Identifier: MIT */
/* cd_model_keys.c — the model keys of a cluster-dynamics section (docs/input-cd.md), read the
 * same way for the `cluster_dynamics` problem and for the coupled problem's particle region
 * (docs/input-coupled.md "particles"). The region's older key names are accepted as aliases,
 * each with a note for the log. */
#include "cd_impl.h"

#include <stdarg.h>
#include <stdio.h>

static void note(char *notes, size_t cap, const char *fmt, ...) {
  size_t len = strlen(notes);
  if (len + 1 >= cap) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(notes + len, cap - len, fmt, ap);
  va_end(ap);
}

const char *cd_key_or_alias(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key,
                            const char *old, const char *where, char *notes, size_t cap) {
  const dk_node *o = old && notes ? dk_get(map, old) : NULL;
  if (!o) return key;
  if (dk_get(map, key)) {
    dk_error(e, doc, o, "%s: give '%s' (its old name '%s' is deprecated), not both", where, key,
             old);
    return key;
  }
  note(notes, cap, "%s:%d:%d: %s.%s is the deprecated name of %s.%s (read as such)\n", dk_file(doc),
       dk_node_line(o), dk_node_col(o), where, old, where, key);
  return old;
}

void cd_model_keys_read(dk_errors *e, dk_doc *doc, const dk_node *sec, int dim,
                        const cd_model_defaults *d, cd_model_keys *k, char *notes, size_t cap) {
  const char *w = d->where;
#define KEY(name, old) cd_key_or_alias(e, doc, sec, name, old, w, notes, cap)
  dk_read_positive(e, doc, sec, KEY("r0", "spacing"), MS_DIM_LENGTH, true, 0, &k->r0);
  if (dim == 2)
    dk_read_positive(e, doc, sec, "thickness", MS_DIM_LENGTH, false, k->r0, &k->thickness);
  else k->thickness = k->r0;
  const dk_node *rcn = dk_get(sec, "cutoff");
  dk_read_double(e, doc, sec, "cutoff", MS_DIM_NONE, false, 1.2, -INFINITY, INFINITY, &k->rc);
  if (!(k->rc > 1.0))
    dk_error(e, doc, rcn ? rcn : sec,
             "cutoff R_c/r0 = %g must exceed 1 (the nearest-neighbour "
             "distance): below it the lattice has no bonds",
             k->rc);
  static const char *const mode_names[] = {"plain", "bonded", "shifted", NULL};
  int mode = CD_CUTOFF_BONDED;
  dk_read_enum(e, doc, sec, "cutoff_mode", false, CD_CUTOFF_BONDED, mode_names, &mode);
  k->mode = (cd_cutoff_mode)mode;
  dk_read_double(e, doc, sec, "skin", MS_DIM_NONE, false, 0.1, 1e-3, 1.0, &k->skin);
  dk_read_double(e, doc, sec, KEY("courant", "dt_factor"), MS_DIM_NONE, false, d->courant, 1e-5,
                 0.2, &k->courant);
  dk_read_double(e, doc, sec, "dt", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &k->dt);
  dk_read_double(e, doc, sec, "r_min", MS_DIM_NONE, false, 0.5, 0.1, 0.95, &k->r_min);
  long nint = 4096;
  dk_read_int(e, doc, sec, "table_intervals", false, 4096, 64, 1 << 22, &nint);
  k->table_intervals = (int)nint;
  dk_read_double(e, doc, sec, KEY("damping", "damping_j"), MS_DIM_NONE, false, d->damping, 0.0, 1e6,
                 &k->damping_j);
#undef KEY
}
