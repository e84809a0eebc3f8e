/* SPDX-License-Identifier: MIT */
/* Particle snapshots with fragment ids (docs/coupling.md §2): the datasets cd_write_snapshot
 * writes (x, v, mass, gid when the view has gids) plus the fragment of each particle, as int64
 * (/particles/fragment) and as a double copy for the XDMF sidecar (ParaView colours by it), and
 * the attributes that `mscale spectrum` reads (r0, rho0, time, period_*, lo_*). Collective under
 * MPI: every rank calls it with its owned particles, stored in rank order (docs/mpi.md). The
 * writing is ptl_write_snapshot's, which cluster dynamics' snapshots use too. */
#include "cpl_impl.h"
#include "ptl.h"

#include <stdlib.h>

ms_status cpl_write_snapshot(const char *path, const cpl_particles *p, const cpl_fragments *f,
                             const cpl_snapshot_info *info) {
  const size_t n = p->n;
  double *fid = ms_calloc(n + 1, sizeof *fid);
  int64_t *id = ms_calloc(n + 1, sizeof *id);
  for (size_t i = 0; i < n; i++) {
    id[i] = f && i < f->n_particles ? f->id[i] : -1;
    fid[i] = (double)id[i];
  }
  ptl_snapshot_data data[4];
  size_t ndata = 0;
  int64_t *mat = info->material ? ms_calloc(n + 1, sizeof *mat) : NULL; /* one material: 0 */
  if (mat) data[ndata++] = (ptl_snapshot_data){"particles/material", NULL, mat, 1, NULL};
  if (p->gid) data[ndata++] = (ptl_snapshot_data){"particles/gid", NULL, p->gid, 1, NULL};
  data[ndata++] = (ptl_snapshot_data){"particles/fragment", NULL, id, 1, NULL};
  data[ndata++] = (ptl_snapshot_data){"particles/fragment_id", fid, NULL, 1, "1"};
  const ms_xdmf_attr xdmf[] = {{"velocity", "particles/v", 3, false},
                               {"mass", "particles/mass", 1, false},
                               {"fragment", "particles/fragment_id", 1, false}};
  const double *const x[3] = {p->x, p->y, p->z}, *const v[3] = {p->vx, p->vy, p->vz};
  ptl_snapshot snap = ptl_snapshot_of(n, x, v, p->mass, info->time, par_size() > 1);
  /* material: the index table of particles/material; no step attribute */
  ptl_snapshot_contents(&snap, ndata, data, 3, xdmf, info->material, -1);
  ptl_snapshot_attr_add(&snap, "r0", info->spacing);
  if (info->rho0 > 0) ptl_snapshot_attr_add(&snap, "rho0", info->rho0);
  for (int k = 0; k < 3; k++)
    if (info->box.period[k] > 0)
      ptl_snapshot_period_add(&snap, k, info->box.period[k], info->box.lo[k]);
  const ms_status st = ptl_write_snapshot(path, &snap);
  free(fid);
  free(id);
  free(mat);
  return st;
}
