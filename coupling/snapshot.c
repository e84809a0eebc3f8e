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
  ptl_snapshot_data data[3];
  size_t ndata = 0;
  if (p->gid) data[ndata++] = (ptl_snapshot_data){"particles/gid", NULL, p->gid, 1, NULL};
  data[ndata++] = (ptl_snapshot_data){"particles/fragment", NULL, id, 1, NULL};
  data[ndata++] = (ptl_snapshot_data){"particles/fragment_id", fid, NULL, 1, "1"};
  ptl_snapshot_attr attr[3 + 2 * 3] = {{"time", info->time}, {"r0", info->spacing}};
  size_t nattr = 2;
  if (info->rho0 > 0) attr[nattr++] = (ptl_snapshot_attr){"rho0", info->rho0};
  static const char *const pn[3] = {"period_x", "period_y", "period_z"};
  static const char *const ln[3] = {"lo_x", "lo_y", "lo_z"};
  for (int k = 0; k < 3; k++)
    if (info->box.period[k] > 0) {
      attr[nattr++] = (ptl_snapshot_attr){pn[k], info->box.period[k]};
      attr[nattr++] = (ptl_snapshot_attr){ln[k], info->box.lo[k]};
    }
  const ms_xdmf_attr xdmf[] = {{"velocity", "particles/v", 3, false},
                               {"mass", "particles/mass", 1, false},
                               {"fragment", "particles/fragment_id", 1, false}};
  const ptl_snapshot snap = {.n = n,
                             .x = p->x,
                             .y = p->y,
                             .z = p->z,
                             .vx = p->vx,
                             .vy = p->vy,
                             .vz = p->vz,
                             .mass = p->mass,
                             .ndata = ndata,
                             .data = data,
                             .nattr = nattr,
                             .attr = attr,
                             .nxdmf = 3,
                             .xdmf = xdmf,
                             .time = info->time,
                             .dist = par_size() > 1};
  const ms_status st = ptl_write_snapshot(path, &snap);
  free(fid);
  free(id);
  return st;
}
