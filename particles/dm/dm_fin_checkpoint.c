/* SPDX-License-Identifier: MIT */
/* dm_fin_checkpoint.c — the state of the finite-deformation model (dm_finite.c) into a
 * checkpoint and back, every array the next step reads (the stress and forces of the last
 * evaluation included), so that a restarted run continues bit for bit (docs/particles-dm.md
 * "Checkpoints"). */
#include "dm_impl.h"

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct fin_array {
  const char *name, *units;
  size_t ncomp;
  double *data;
} fin_array;

/* Every per-particle array of dm_fin; a field added to dm_fin that a step reads belongs here. */
static size_t fin_arrays(const dm_fin *f, fin_array a[21]) {
  size_t k = 0;
  a[k++] = (fin_array){"e", "kJ/g", 1, f->e};
  a[k++] = (fin_array){"rho", "g/cm^3", 1, f->rho};
  a[k++] = (fin_array){"p", "GPa", 1, f->p};
  a[k++] = (fin_array){"q", "GPa", 1, f->q};
  a[k++] = (fin_array){"J", "1", 1, f->J};
  a[k++] = (fin_array){"eps_p", "1", 1, f->eps_p};
  a[k++] = (fin_array){"e_hourglass", "kJ", 1, f->ehg};
  a[k++] = (fin_array){"F", "1", 9, f->F};
  a[k++] = (fin_array){"s", "GPa", 9, f->s};
  a[k++] = (fin_array){"QP", "GPa cm^3/cm^2", 9, f->QP};
  a[k++] = (fin_array){"sigma", "GPa", 9, f->sig};
  a[k++] = (fin_array){"force", "g cm/(10 us)^2", 3, f->frc};
  a[k++] = (fin_array){"vbar", "km/s", 3, f->vbar};
  if (f->broken) { /* fracture only */
    a[k++] = (fin_array){"broken", "kJ", 1, f->broken};
    a[k++] = (fin_array){"contact_energy", "kJ", 1, f->econ};
    a[k++] = (fin_array){"contact_force", "g cm/(10 us)^2", 3, f->fcon};
  }
  if (f->sr) { /* the short-range contact (dm_contact.c) */
    a[k++] = (fin_array){"short_range_energy", "kJ", 1, f->sr->energy};
    a[k++] = (fin_array){"short_range_force", "g cm/(10 us)^2", 3, f->sr->force};
    a[k++] = (fin_array){"short_range_step", "10 us", 1, f->sr->dt};
  }
  if (f->fext) /* an external force (dm_impact.c's wall): the next half kick books its work */
    a[k++] = (fin_array){"external_force", "g cm/(10 us)^2", 3, f->fext};
  return k;
}

static void path(char *buf, size_t len, const char *group, const char *name) {
  snprintf(buf, len, "%s/%s", group, name);
}

ms_status dm_fin_checkpoint_write(const dm_fin *f, const dm_state *s, ms_h5 *h, const char *group,
                                  bool owner) {
  const size_t n = owner ? f->n : 0; /* rows this rank adds (a replicated model: the owner's) */
  fin_array a[21];
  const size_t na = fin_arrays(f, a);
  char name[256];
  ms_status st = MS_OK;
  for (size_t k = 0; k < na && st == MS_OK; ++k) {
    path(name, sizeof name, group, a[k].name);
    st = ms_h5_write_doubles_dist(h, name, n, a[k].ncomp, a[k].data, a[k].units);
  }
  if (st == MS_OK)
    path(name, sizeof name, group, "w"), st = ms_h5_write_doubles_dist(h, name, n, 3, s->w, "cm");
  if (st == MS_OK)
    path(name, sizeof name, group, "u"), st = ms_h5_write_doubles_dist(h, name, n, 3, s->u, "km/s");
  if (st == MS_OK && f->failed) { /* fracture: the failed flags (as 0/1) */
    double *fl = ms_calloc(f->n + 1, sizeof *fl);
    for (size_t i = 0; i < f->n; ++i) fl[i] = f->failed[i];
    path(name, sizeof name, group, "failed");
    st = ms_h5_write_doubles_dist(h, name, n, 1, fl, "1");
    free(fl);
    const size_t nb = owner ? f->nlcon : 0; /* per bond: rest length (−1: not broken), dashpot */
    path(name, sizeof name, group, "contact_length");
    if (st == MS_OK) st = ms_h5_write_doubles_dist(h, name, nb, 1, f->lcon, "cm");
    path(name, sizeof name, group, "contact_dashpot");
    if (st == MS_OK) st = ms_h5_write_doubles_dist(h, name, nb, 1, f->gcon, "g cm/(10 us)^2");
  }
  if (st == MS_OK && f->sr) { /* the short-range contact: where it acted (as 0/1) */
    double *fl = ms_calloc(f->n + 1, sizeof *fl);
    for (size_t i = 0; i < f->n; ++i) fl[i] = f->sr->touch[i];
    path(name, sizeof name, group, "short_range_touch");
    st = ms_h5_write_doubles_dist(h, name, n, 1, fl, "1");
    free(fl);
  }
  /* the scalars as attributes of the group's e dataset: the step count exactly (< 2^53) */
  path(name, sizeof name, group, "e");
  if (st == MS_OK) st = ms_h5_attr_double(h, name, "work", f->work);
  if (st == MS_OK) st = ms_h5_attr_double(h, name, "dt_next", f->dt_next);
  if (st == MS_OK) st = ms_h5_attr_double(h, name, "step", (double)f->step);
  if (st == MS_OK && f->fext) st = ms_h5_attr_double(h, name, "external_work", f->ext_work);
  return st;
}

ms_status dm_ckpt_read_rows(ms_h5r *h, const char *name, size_t ncol, size_t nmax, bool exact,
                            double *dst, size_t *nrow, dk_errors *e) {
  double *v = NULL;
  size_t nr = 0, nc = 0;
  ms_status st = ms_h5_read_doubles_rows(h, name, 0, SIZE_MAX, &v, &nr, &nc, e);
  if (st == MS_OK && (nc != ncol || nr > nmax || (exact && nr != nmax))) {
    dk_error_at(e, "checkpoint", 0, 0,
                "'%s' has %zu rows of %zu values; this run needs %s%zu of %zu (a checkpoint of "
                "another run?)",
                name, nr, nc, exact ? "" : "at most ", nmax, ncol);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) memcpy(dst, v, nr * ncol * sizeof *dst);
  if (st == MS_OK && nrow) *nrow = nr;
  free(v);
  return st;
}

/* exactly n rows of ncomp values */
static ms_status read_into(ms_h5r *h, const char *name, size_t n, size_t ncomp, double *dst,
                           dk_errors *e) {
  return dm_ckpt_read_rows(h, name, ncomp, n, true, dst, NULL, e);
}

ms_status dm_fin_checkpoint_read(dm_fin *f, dm_state *s, ms_h5r *h, const char *group,
                                 dk_errors *e) {
  fin_array a[21];
  const size_t na = fin_arrays(f, a);
  char name[256];
  ms_status st = MS_OK;
  for (size_t k = 0; k < na && st == MS_OK; ++k) {
    path(name, sizeof name, group, a[k].name);
    st = read_into(h, name, f->n, a[k].ncomp, a[k].data, e);
  }
  if (st == MS_OK) path(name, sizeof name, group, "w"), st = read_into(h, name, f->n, 3, s->w, e);
  if (st == MS_OK) path(name, sizeof name, group, "u"), st = read_into(h, name, f->n, 3, s->u, e);
  if (st == MS_OK && f->failed) { /* a failed particle's bond penalty is off (dm_fracture.c) */
    double *fl = ms_calloc(f->n + 1, sizeof *fl);
    path(name, sizeof name, group, "failed");
    st = read_into(h, name, f->n, 1, fl, e);
    for (size_t i = 0; st == MS_OK && i < f->n; ++i) {
      f->failed[i] = (uint8_t)fl[i]; /* 1 failed (dm_fracture.c) */
      if (f->failed[i]) f->m->kappa[i] = 0.0;
    }
    free(fl);
    path(name, sizeof name, group, "contact_length");
    if (st == MS_OK) st = read_into(h, name, f->nlcon, 1, f->lcon, e);
    path(name, sizeof name, group, "contact_dashpot");
    if (st == MS_OK) st = read_into(h, name, f->nlcon, 1, f->gcon, e);
  }
  if (st == MS_OK && f->sr) {
    double *fl = ms_calloc(f->n + 1, sizeof *fl);
    path(name, sizeof name, group, "short_range_touch");
    st = read_into(h, name, f->n, 1, fl, e);
    f->sr->touching = 0;
    for (size_t i = 0; st == MS_OK && i < f->n; ++i)
      f->sr->touch[i] = fl[i] != 0, f->sr->touching += fl[i] != 0;
    free(fl);
  }
  double step = 0;
  path(name, sizeof name, group, "e");
  if (st == MS_OK) st = ms_h5_read_attr_double(h, name, "work", &f->work, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, name, "dt_next", &f->dt_next, e);
  if (st == MS_OK) st = ms_h5_read_attr_double(h, name, "step", &step, e);
  if (st == MS_OK && f->fext)
    st = ms_h5_read_attr_double(h, name, "external_work", &f->ext_work, e);
  f->step = (long)step;
  /* symmetry planes: the checkpoint holds the real particles; the mirror ghosts' rows (w, u, v̄,
   * M Q M, κ, failed) from their partners, as every step leaves them (kick_velocities) */
  if (st == MS_OK && f->sym.n) dm_sym_sync(f);
  /* the shape matrices of particles with failed members, from the failed flags (dm_fracture.c) */
  if (st == MS_OK) dm_frac_restore(f);
  return st;
}
