/* SPDX-License-Identifier: MIT */
/* ejecta_split.c — jets vs spall layers vs debris in a driven slab's fragments ([Davydov] §4.2;
 * the definitions and why: docs/coupling.md §9 "The split"). Shape, not speed: a spalled layer
 * is a plate that spans the periodic width (what a planar spall leaves), and a jet is material
 * thrown ahead of the foremost such plate. A speed threshold (faster than the flat free surface)
 * fails under a decaying drive, where the jets slow with everything else (docs/validation.md "At
 * the paper's 15 GPa"), so speed only gives the separate "fast" column.
 * MPI only through core's par_* wrappers; scratch is allocated per call (the classification
 * runs at fragment searches, as the distributed fragment search does). */
#include "cpl_impl.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Lateral bins of width a across the periodic axes y (and z): nb[k] per axis. An open lateral
 * axis is one bin (there is no width for a layer to span). */
static void lateral_bins(const cpl_split_opts *o, size_t nb[2]) {
  for (int k = 0; k < 2; k++) {
    const double P = o->box.period[k + 1];
    const double n = P > 0 ? floor(P / o->spacing + 0.5) : 1.0;
    nb[k] = n >= 1 ? (size_t)n : 1;
  }
}

static size_t bin_of(const cpl_split_opts *o, const size_t nb[2], const cpl_particles *p,
                     size_t i) {
  size_t b[2] = {0, 0};
  const double *c[2] = {p->y, p->z};
  for (int k = 0; k < 2; k++) {
    const double P = o->box.period[k + 1];
    if (!(P > 0) || !c[k]) continue;
    double u = (c[k][i] - o->box.lo[k + 1]) / P;
    u -= floor(u);
    size_t j = (size_t)(u * (double)nb[k]);
    b[k] = j < nb[k] ? j : nb[k] - 1;
  }
  return b[0] + nb[0] * b[1];
}

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Median of the finite entries of v[0..n) (sorted in place after compaction); NaN if none. */
static double median_finite(double *v, size_t n) {
  size_t m = 0;
  for (size_t j = 0; j < n; j++)
    if (isfinite(v[j])) v[m++] = v[j];
  if (!m) return NAN;
  qsort(v, m, sizeof *v, cmp_double);
  return m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2]);
}

void cpl_split_opts_default(cpl_split_opts *o, const cpl_fragment_opts *fo, double v_fast) {
  memset(o, 0, sizeof *o);
  o->spacing = fo->spacing;
  o->box = fo->box;
  o->cover = 0.9;
  o->reach = 2.0;
  o->v_fast = v_fast;
}

void cpl_ejecta_classify(const cpl_fragments *f, const cpl_particles *p, const cpl_split_opts *o,
                         const ms_ctx *ctx, cpl_ejecta_classes *out) {
  memset(out, 0, sizeof *out);
  out->bulk = SIZE_MAX;
  out->level = NAN;
  out->v_fast = o->v_fast;
  const bool dist = ctx && ctx->size > 1;
  size_t nb[2];
  lateral_bins(o, nb);
  const size_t nbin = nb[0] * nb[1];
  const double need = o->cover * (double)nbin; /* bins a full-width fragment occupies */
  /* 1. candidates: fragments with at least `need` particles (fewer cannot cover the width) */
  int64_t *slot = ms_calloc(f->n + 1, sizeof *slot);
  size_t ncand = 0;
  for (size_t k = 0; k < f->n; k++) slot[k] = (double)f->count[k] >= need ? (int64_t)ncand++ : -1;
  /* 2. per candidate: the front (largest x) in each bin, and its deepest particle (as −x, so
   * that one max-reduction serves both); −∞ where it has no particle. The last entry: the
   * deepest particle of any fragment (as −x), next to the driven layer. */
  const size_t row = nbin + 1;
  double *front = ms_calloc(ncand * row + 1, sizeof *front);
  for (size_t j = 0; j <= ncand * row; j++) front[j] = -INFINITY;
  const size_t n = p->n < f->n_particles ? p->n : f->n_particles;
  for (size_t i = 0; i < n; i++) {
    if (f->id[i] >= 0 && -p->x[i] > front[ncand * row]) front[ncand * row] = -p->x[i];
    if (f->id[i] < 0 || slot[f->id[i]] < 0) continue;
    double *fr = front + (size_t)slot[f->id[i]] * row;
    const size_t b = bin_of(o, nb, p, i);
    if (p->x[i] > fr[b]) fr[b] = p->x[i];
    if (-p->x[i] > fr[nbin]) fr[nbin] = -p->x[i];
  }
  if (dist) par_max_doubles(front, ncand * row + 1); /* exact: max is order-free */
  /* 3. full width, the bulk (the deepest full-width fragment, if it reaches down to the driven
   * layer: what stays on it) and each full-width fragment's level (median front over the bins
   * it occupies) */
  double *scratch = ms_calloc(nbin + 1, sizeof *scratch);
  double deepest = INFINITY, level = -INFINITY;
  size_t deepest_k = SIZE_MAX;
  for (size_t k = 0; k < f->n; k++) {
    if (slot[k] < 0) continue;
    const double *fr = front + (size_t)slot[k] * row;
    size_t covered = 0;
    for (size_t b = 0; b < nbin; b++) covered += isfinite(fr[b]);
    if ((double)covered < need) {
      slot[k] = -1; /* not full-width after all */
      continue;
    }
    if (-fr[nbin] < deepest) deepest = -fr[nbin], deepest_k = k;
    memcpy(scratch, fr, nbin * sizeof *scratch);
    const double lk = median_finite(scratch, nbin);
    if (lk > level) level = lk;
  }
  const double x_low = -front[ncand * row]; /* the deepest particle of all */
  if (deepest_k != SIZE_MAX && deepest <= x_low + o->reach * o->spacing) out->bulk = deepest_k;
  /* one spacing above the median front: a plate's own roughness of a lattice row is not ejecta */
  if (deepest_k != SIZE_MAX) out->level = level + o->spacing;
  /* 4. per particle of a detached fragment: ahead of the level (jets), in a full-width fragment
   * (layers), or neither (debris) */
  const bool have_level = deepest_k != SIZE_MAX;
  double m[3] = {0, 0, 0}; /* jets, layers, debris */
  for (size_t i = 0; i < n; i++) {
    const int64_t k = f->id[i];
    if (k < 0 || (size_t)k == out->bulk) continue;
    const double mi = p->mass ? p->mass[i] : 1.0;
    if (have_level && p->x[i] > out->level) m[0] += mi;
    else if (slot[k] >= 0) m[1] += mi;
    else m[2] += mi;
  }
  /* rank order: a model that keeps every particle on rank 0 (the discrete model) gets the
   * serial bits */
  if (dist) par_sum_doubles_ordered(m, 3);
  out->m_jet = m[0], out->m_layer = m[1], out->m_debris = m[2];
  /* 5. per fragment (the table is replicated): counts, speeds */
  bool any = false;
  for (size_t k = 0; k < f->n; k++) {
    if (k == out->bulk) {
      out->m_bulk = f->mass[k];
      continue;
    }
    if (slot[k] >= 0) out->n_layer++;
    else if (have_level && f->cx[k] > out->level) out->n_jet++;
    else out->n_debris++;
    if (!any || f->vx[k] > out->v_max) out->v_max = f->vx[k];
    any = true;
    if (f->vx[k] > o->v_fast) {
      out->m_fast += f->mass[k];
      out->n_fast++;
    }
  }
  free(scratch);
  free(front);
  free(slot);
}
