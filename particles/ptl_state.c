/* SPDX-License-Identifier: MIT */
/* ptl_state.c — structure-of-arrays particle storage, sized once (ptl.h). */
#include "ptl.h"

#include <stdlib.h>
#include <string.h>

ms_status ptl_state_create(const ptl_state_params *p, ptl_state **out) {
  *out = NULL;
  if (p->dim != 2 && p->dim != 3) return MS_ERR_INPUT;
  const size_t cap = p->cap;
  const int dim = p->dim;
  ptl_state *s = ms_calloc(1, sizeof *s);
  s->cap = cap;
  s->dim = dim;
  size_t c = cap ? cap : 1;
  double **d[] = {&s->x, &s->y, &s->z, &s->vx, &s->vy, &s->vz, &s->fx, &s->fy, &s->fz, &s->mass};
  for (size_t k = 0; k < sizeof d / sizeof *d; k++) *d[k] = ms_aligned_alloc(c, sizeof(double));
  s->gid = ms_aligned_alloc(c, sizeof *s->gid);
  s->mat = ms_aligned_alloc(c, 1);
  s->flags = ms_aligned_alloc(c, 1);
  *out = s;
  return MS_OK;
}

static void ptl_state_free(ptl_state *s) {
  if (!s) return;
  free(s->x);
  free(s->y);
  free(s->z);
  free(s->vx);
  free(s->vy);
  free(s->vz);
  free(s->fx);
  free(s->fy);
  free(s->fz);
  free(s->mass);
  free(s->gid);
  free(s->mat);
  free(s->flags);
  free(s);
}

void ptl_state_destroy(ptl_state **s) {
  if (!s) return;
  ptl_state_free(*s);
  *s = NULL;
}

size_t ptl_state_add(ptl_state *s, double x, double y, double z, double mass, int mat) {
  if (s->n >= s->cap) return (size_t)-1;
  size_t i = s->n++;
  s->nlocal = s->n;
  s->x[i] = x;
  s->y[i] = y;
  s->z[i] = s->dim == 2 ? 0.0 : z;
  s->vx[i] = s->vy[i] = s->vz[i] = 0.0;
  s->fx[i] = s->fy[i] = s->fz[i] = 0.0;
  s->mass[i] = mass;
  s->gid[i] = (int64_t)i;
  s->mat[i] = (uint8_t)mat;
  s->flags[i] = 0;
  return i;
}

void ptl_state_reserve(ptl_state *s, size_t cap) {
  if (cap <= s->cap) return;
  ptl_state *t = NULL;
  ms_must(ptl_state_create(&(ptl_state_params){.cap = cap, .dim = s->dim}, &t), "ptl_state_create");
  double *src[] = {s->x, s->y, s->z, s->vx, s->vy, s->vz, s->fx, s->fy, s->fz, s->mass};
  double *dst[] = {t->x, t->y, t->z, t->vx, t->vy, t->vz, t->fx, t->fy, t->fz, t->mass};
  for (size_t k = 0; k < sizeof src / sizeof *src; k++)
    memcpy(dst[k], src[k], s->n * sizeof(double));
  memcpy(t->gid, s->gid, s->n * sizeof *s->gid);
  memcpy(t->mat, s->mat, s->n);
  memcpy(t->flags, s->flags, s->n);
  t->n = s->n;
  t->nlocal = s->nlocal;
  /* swap the arrays into s, free the old ones with t */
  ptl_state tmp = *s;
  *s = *t;
  *t = tmp;
  ptl_state_destroy(&t);
}

void ptl_state_keep_range(ptl_state *s, size_t lo, size_t hi) {
  if (hi > s->n) hi = s->n;
  if (lo > hi) lo = hi;
  size_t m = hi - lo;
  double *arr[] = {s->x, s->y, s->z, s->vx, s->vy, s->vz, s->fx, s->fy, s->fz, s->mass};
  for (size_t k = 0; k < sizeof arr / sizeof *arr; k++)
    memmove(arr[k], arr[k] + lo, m * sizeof(double));
  memmove(s->gid, s->gid + lo, m * sizeof *s->gid);
  memmove(s->mat, s->mat + lo, m);
  memmove(s->flags, s->flags + lo, m);
  s->n = s->nlocal = m;
}

size_t ptl_state_bytes(const ptl_state *s) {
  return s->cap * (10 * sizeof(double) + sizeof(int64_t) + 2);
}

/* splitmix64 (Steele, Lea, Flood 2014), exactly as bench/lammps/gen_inputs.py:
 * state_k = seed + (k+1)·0x9E3779B97F4A7C15, then the output mix; u = (z >> 11)·2^-53. */
double ptl_splitmix64_uniform(uint64_t seed, uint64_t k) {
  uint64_t z = seed + (k + 1) * 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}
