/* SPDX-License-Identifier: MIT */
/* dm_family_checkpoint.c — the families of a model whose bonds are no longer a function of the
 * reference positions into a checkpoint and back (docs/particles-dm.md "Families kept or
 * merged"): after a reference update that kept or merged the families (dm_fin_rebase) or a
 * per-family update (dm_fin_local.c) the bond lists, each family's own bond vectors ξ_b and the
 * shape arrays A⁻¹, cond and κ cannot be rebuilt from X, so they are stored as they are (every
 * row, the mirror ghosts' included: their set never changes with kept families) and read back
 * bit for bit; the reverse-bond index of the per-family gather is rebuilt from the lists
 * (integers, exact). Indices are stored as doubles (exact below 2^53). Datasets of GROUP:
 *   sizes [rows][1]: each row's bond count (the particles, real and ghosts);
 *   bonds [nbonds][2]: the neighbour's index and its periodic image code;
 *   bond_vectors [nbonds][3] (cm): ξ_b, only with per-family references (m->xref);
 *   shape [rows][11]: A⁻¹ (9), cond A, κ. */
#include "dm_impl.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

static void path(char *buf, size_t len, const char *group, const char *name) {
  snprintf(buf, len, "%s/%s", group, name);
}

ms_status dm_families_checkpoint_write(const dm_model *m, ms_h5 *h, const char *group, bool owner) {
  const size_t n = m->s->n, nb = m->nbonds;
  double *rows = ms_calloc(n + 1, sizeof *rows), *bonds = ms_calloc(2 * nb + 1, sizeof *bonds);
  double *shape = ms_calloc(11 * n + 1, sizeof *shape);
  for (size_t i = 0; i < n; ++i) {
    rows[i] = (double)(m->start[i + 1] - m->start[i]);
    memcpy(&shape[11 * i], &m->Ainv[9 * i], 9 * sizeof(double));
    shape[11 * i + 9] = m->cond[i], shape[11 * i + 10] = m->kappa[i];
  }
  for (size_t b = 0; b < nb; ++b) bonds[2 * b] = m->nbr[b], bonds[2 * b + 1] = m->img[b];
  char name[256];
  path(name, sizeof name, group, "sizes");
  ms_status st = ms_h5_write_doubles_dist(h, name, owner ? n : 0, 1, rows, "1");
  if (st == MS_OK) {
    path(name, sizeof name, group, "bonds");
    st = ms_h5_write_doubles_dist(h, name, owner ? nb : 0, 2, bonds, "1");
  }
  if (st == MS_OK && m->xref) {
    path(name, sizeof name, group, "bond_vectors");
    st = ms_h5_write_doubles_dist(h, name, owner ? nb : 0, 3, m->xref, "cm");
  }
  if (st == MS_OK) {
    path(name, sizeof name, group, "shape");
    st = ms_h5_write_doubles_dist(h, name, owner ? n : 0, 11, shape, "cm^-2, 1, GPa cm^3/cm^2");
  }
  free(rows), free(bonds), free(shape);
  return st;
}

/* The whole dataset NAME of ncol columns; its rows into *nrow (the caller frees *out). */
static ms_status read_all(ms_h5r *h, const char *group, const char *what, size_t ncol, double **out,
                          size_t *nrow, dk_errors *e) {
  char name[256];
  size_t nc = 0;
  path(name, sizeof name, group, what);
  ms_status st = ms_h5_read_doubles_rows(h, name, 0, SIZE_MAX, out, nrow, &nc, e);
  if (st == MS_OK && nc != ncol) {
    dk_error_at(e, "checkpoint", 0, 0, "'%s' has %zu values a row; expected %zu", name, nc, ncol);
    st = MS_ERR_INPUT;
  }
  return st;
}

/* The lists of the checkpoint checked against the model's particles: counts that add up, each
 * neighbour a particle other than the row's, image codes < 27. */
static ms_status check_lists(const dm_model *m, const double *rows, size_t nrows,
                             const double *bonds, size_t nb, dk_errors *e) {
  const size_t n = m->s->n;
  if (nrows != n) {
    dk_error_at(e, "checkpoint", 0, 0,
                "the checkpoint's families have %zu rows; this run has %zu particles (real and "
                "mirror ghosts): a checkpoint of another run?",
                nrows, n);
    return MS_ERR_INPUT;
  }
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += rows[i];
  bool ok = sum == (double)nb;
  for (size_t b = 0; ok && b < nb; ++b)
    ok = bonds[2 * b] >= 0 && bonds[2 * b] < (double)n && bonds[2 * b + 1] >= 0 &&
         bonds[2 * b + 1] < 27;
  if (!ok) {
    dk_error_at(e, "checkpoint", 0, 0,
                "the checkpoint's bond lists are inconsistent (%g bonds in the rows, %zu listed, "
                "or a neighbour outside the %zu particles)",
                sum, nb, n);
    return MS_ERR_INPUT;
  }
  return MS_OK;
}

ms_status dm_families_checkpoint_read(dm_model *m, ms_h5r *h, const char *group, dk_errors *e) {
  double *rows = NULL, *bonds = NULL, *xref = NULL, *shape = NULL;
  size_t nrows = 0, nb = 0, nx = 0, ns = 0;
  char name[256];
  path(name, sizeof name, group, "bond_vectors");
  const bool local = ms_h5_exists(h, name);
  ms_status st = read_all(h, group, "sizes", 1, &rows, &nrows, e);
  if (st == MS_OK) st = read_all(h, group, "bonds", 2, &bonds, &nb, e);
  if (st == MS_OK && local) st = read_all(h, group, "bond_vectors", 3, &xref, &nx, e);
  if (st == MS_OK) st = read_all(h, group, "shape", 11, &shape, &ns, e);
  if (st == MS_OK) st = check_lists(m, rows, nrows, bonds, nb, e);
  if (st == MS_OK && ((local && nx != nb) || ns != nrows)) {
    dk_error_at(e, "checkpoint", 0, 0,
                "the checkpoint's bond vectors (%zu rows) or shapes (%zu rows) do not match its "
                "%zu bonds and %zu families",
                nx, ns, nb, nrows);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) {
    const size_t n = nrows;
    size_t *start = ms_calloc(n + 1, sizeof *start);
    uint32_t *nbr = ms_calloc(nb + 1, sizeof *nbr);
    uint8_t *img = ms_calloc(nb + 1, 1);
    for (size_t i = 0; i < n; ++i) start[i + 1] = start[i] + (size_t)rows[i];
    for (size_t b = 0; b < nb; ++b)
      nbr[b] = (uint32_t)bonds[2 * b], img[b] = (uint8_t)bonds[2 * b + 1];
    free(m->start), free(m->nbr), free(m->img), free(m->xref), free(m->rev);
    m->start = start, m->nbr = nbr, m->img = img, m->nbonds = nb, m->xref = NULL, m->rev = NULL;
    for (size_t i = 0; i < n; ++i) {
      memcpy(&m->Ainv[9 * i], &shape[11 * i], 9 * sizeof(double));
      m->cond[i] = shape[11 * i + 9], m->kappa[i] = shape[11 * i + 10];
    }
    if (local) { /* one double of padding (4-lane loads) */
      m->xref = ms_calloc(3 * nb + 1, sizeof(double));
      memcpy(m->xref, xref, 3 * nb * sizeof(double));
      if (dm_fin_local_rev(m) != MS_OK) {
        dk_error_at(e, "checkpoint", 0, 0, "the checkpoint's families are not symmetric");
        st = MS_ERR_INPUT;
      }
    }
  }
  free(rows), free(bonds), free(xref), free(shape);
  return st;
}
