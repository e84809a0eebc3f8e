/* SPDX-License-Identifier: MIT */
/* ptl_snapshot.c — the particle snapshot writer (ptl.h) of cluster dynamics (cd/cd_diag.c), of
 * the discrete model (dm/dm_output.c, dm_fin_output.c, dm_region.c, dm_impact.c) and of the
 * coupled problem's fragment snapshots (coupling/snapshot.c): positions, velocities and masses as [n][3] and [n] datasets, the
 * caller's extra datasets and attributes, an XDMF sidecar that ParaView opens. Under MPI one
 * collective file, rows in rank order. */
#include "ptl.h"

#include <stdlib.h>
#include <string.h>

ptl_snapshot ptl_snapshot_of(size_t n, const double *const x[3], const double *const v[3],
                             const double *mass, double time, bool dist) {
  ptl_snapshot snap = {.n = n, .mass = mass, .time = time, .dist = dist};
  for (int a = 0; a < 3; a++) {
    snap.x[a] = x[a];
    snap.v[a] = v[a];
  }
  return snap;
}

ptl_snapshot ptl_snapshot_of_state(const ptl_state *p, size_t n, double time, bool dist) {
  const double *const x[3] = {p->x, p->y, p->z}, *const v[3] = {p->vx, p->vy, p->vz};
  return ptl_snapshot_of(n, x, v, p->mass, time, dist);
}

void ptl_snapshot_attr_add(ptl_snapshot *snap, const char *name, double v) {
  if (snap->nattr >= PTL_SNAPSHOT_MAX_ATTR) {
    fprintf(stderr, "mscale: internal error: more than %d snapshot attributes\n",
            PTL_SNAPSHOT_MAX_ATTR);
    abort();
  }
  snap->attr[snap->nattr++] = (ptl_snapshot_attr){name, v};
}

void ptl_snapshot_contents(ptl_snapshot *snap, size_t ndata, const ptl_snapshot_data *data,
                           size_t nxdmf, const ms_xdmf_attr *xdmf, const char *material_names,
                           long step) {
  snap->ndata = ndata;
  snap->data = data;
  snap->nxdmf = nxdmf;
  snap->xdmf = xdmf;
  snap->material_names = material_names;
  ptl_snapshot_attr_add(snap, "time", snap->time);
  if (step >= 0) ptl_snapshot_attr_add(snap, "step", (double)step);
}

void ptl_snapshot_period_add(ptl_snapshot *snap, int axis, double period, double lo) {
  static const char *const pname[3] = {"period_x", "period_y", "period_z"};
  static const char *const lname[3] = {"lo_x", "lo_y", "lo_z"};
  ptl_snapshot_attr_add(snap, pname[axis], period);
  ptl_snapshot_attr_add(snap, lname[axis], lo);
}

/* particles/vertex: each particle's row in the file (0..N-1, rank order under MPI), the XDMF
 * Polyvertex connectivity (ms_xdmf_write_particles). */
static ms_status write_vertex_ids(ms_h5 *h, size_t n, bool dist) {
  long offset = 0;
  if (dist) {
    long *all = ms_calloc((size_t)par_size(), sizeof *all);
    par_allgather_long((long)n, all);
    for (int r = 0; r < par_rank(); r++) offset += all[r];
    free(all);
  }
  int64_t *ids = ms_calloc(n + 1, sizeof *ids);
  for (size_t i = 0; i < n; i++) ids[i] = offset + (int64_t)i;
  ms_status st = ms_h5_write_ints_dist(h, "particles/vertex", n, ids);
  free(ids);
  return st;
}

static ms_status write_datasets(ms_h5 *h, const ptl_snapshot *sn, const double *xyz,
                                const double *vel) {
  const size_t n = sn->n;
  ms_status st = ms_h5_write_doubles_dist(h, "particles/x", n, 3, xyz, "cm");
  if (st == MS_OK && !(sn->omit & PTL_SNAPSHOT_NO_V))
    st = ms_h5_write_doubles_dist(h, "particles/v", n, 3, vel, "km/s");
  if (st == MS_OK && !(sn->omit & PTL_SNAPSHOT_NO_MASS))
    st = ms_h5_write_doubles_dist(h, "particles/mass", n, 1, sn->mass, "g");
  for (size_t k = 0; k < sn->ndata && st == MS_OK; k++) {
    const ptl_snapshot_data *d = &sn->data[k];
    st = d->d ? ms_h5_write_doubles_dist(h, d->name, n, (size_t)d->ncomp, d->d, d->units)
              : ms_h5_write_ints_dist(h, d->name, n, d->i);
  }
  if (st == MS_OK && !(sn->omit & PTL_SNAPSHOT_NO_VERTEX)) st = write_vertex_ids(h, n, sn->dist);
  if (st == MS_OK && sn->material_names) /* the names of the material indices, "al,pb" */
    st = ms_h5_attr_string(h, "particles", "material_names", sn->material_names);
  for (size_t k = 0; k < sn->nattr && st == MS_OK; k++) {
    /* the time in the output unit (docs/output.md, "Units"), named by time_units */
    bool is_time = !strcmp(sn->attr[k].name, "time");
    if (!strcmp(sn->attr[k].name, "step")) /* a count: an integer attribute */
      st = ms_h5_attr_int(h, "particles", "step", (int64_t)sn->attr[k].value);
    else
      st = ms_h5_attr_double(h, "particles", sn->attr[k].name,
                             is_time ? ms_out_time(sn->attr[k].value) : sn->attr[k].value);
    if (st == MS_OK && is_time)
      st = ms_h5_attr_string(h, "particles", "time_units", ms_out_time_label());
  }
  return st;
}

/* The sidecar next to the .h5, referring to it by its base name. */
static ms_status write_sidecar(const char *path, const ptl_snapshot *sn, size_t nglobal) {
  size_t len = strlen(path);
  char *xmf = ms_calloc(len + 8, 1);
  memcpy(xmf, path, len);
  if (len > 3 && strcmp(path + len - 3, ".h5") == 0) len -= 3;
  strcpy(xmf + len, ".xmf");
  const char *base = strrchr(path, '/');
  base = base ? base + 1 : path;
  const char *vertex = sn->omit & PTL_SNAPSHOT_NO_VERTEX ? NULL : "particles/vertex";
  ms_status st = ms_xdmf_write_particles(xmf, base, "particles/x", vertex, nglobal, 3,
                                         ms_out_time(sn->time), sn->nxdmf, sn->xdmf);
  free(xmf);
  /* the run's time series: every sidecar of this prefix (the name up to its number); a name
   * without a number before its extension (particles_unstable.h5: the 5 of .h5 is none) is no
   * part of it and leaves it as it is */
  size_t dirlen = (size_t)(base - path), plen = strcspn(base, "0123456789");
  if ((sn->omit & PTL_SNAPSHOT_NO_SERIES) || plen >= strcspn(base, ".")) return st;
  char *dir = ms_calloc(dirlen + 2, 1), *prefix = ms_calloc(plen + 1, 1);
  memcpy(dir, path, dirlen);
  if (dirlen == 0) strcpy(dir, ".");
  memcpy(prefix, base, plen);
  if (st == MS_OK) st = ms_xdmf_write_series(dir, prefix, "particles.xmf");
  free(dir);
  free(prefix);
  return st;
}

ms_status ptl_write_snapshot(const char *path, const ptl_snapshot *sn) {
  const size_t n = sn->n;
  double *xyz = ms_calloc(3 * n + 1, sizeof *xyz), *vel = ms_calloc(3 * n + 1, sizeof *vel);
  for (size_t i = 0; i < n; i++)
    for (int a = 0; a < 3; a++) {
      xyz[3 * i + a] = sn->x[a] ? sn->x[a][i] : 0.0;
      vel[3 * i + a] = sn->v[a] && !(sn->omit & PTL_SNAPSHOT_NO_V) ? sn->v[a][i] : 0.0;
    }
  ms_status st = MS_ERR_IO;
  ms_h5 *h = sn->dist ? ms_h5_create_collective(path) : ms_h5_create(path);
  if (h) {
    st = write_datasets(h, sn, xyz, vel);
    if (st == MS_OK) st = ms_h5_close(h);
    else ms_h5_abort(h);
  }
  free(xyz);
  free(vel);
  const size_t nglobal = sn->dist ? (size_t)par_sum_long((long)n) : n;
  if (st == MS_OK && (!sn->dist || par_rank() == 0)) st = write_sidecar(path, sn, nglobal);
  return sn->dist ? par_agree_status(st) : st; /* the sidecar is rank 0's */
}

void ptl_snapshot_name(char *name, size_t size, long index) {
  snprintf(name, size, "particles_%04ld.h5", index);
}

void ptl_material_table_add(char *table, size_t size, const char *name) {
  const size_t len = strlen(table);
  if (len < size) snprintf(table + len, size - len, "%s%s", len ? "," : "", name);
}
