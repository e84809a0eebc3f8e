/* Particle snapshots with fragment ids (docs/coupling.md §2): the datasets cd_write_snapshot
 * writes (x, v, mass, gid when the view has gids) plus the fragment of each particle, as int64
 * (/particles/fragment) and as a double copy for the XDMF sidecar (ParaView colours by it), and
 * the attributes that `mscale spectrum` reads (r0, rho0, time, period_*, lo_*). Collective under
 * MPI: every rank calls it with its owned particles, stored in rank order (docs/mpi.md). */
#include "cpl_impl.h"

#include <stdlib.h>
#include <string.h>

ms_status cpl_write_snapshot(const char *path, const cpl_particles *p, const cpl_fragments *f,
                             const cpl_snapshot_info *info) {
  size_t n = p->n;
  double *xyz = ms_calloc(3 * n + 1, sizeof *xyz), *vel = ms_calloc(3 * n + 1, sizeof *vel);
  double *fid = ms_calloc(n + 1, sizeof *fid);
  int64_t *id = ms_calloc(n + 1, sizeof *id);
  for (size_t i = 0; i < n; i++) {
    xyz[3 * i] = p->x[i];
    xyz[3 * i + 1] = p->y[i];
    xyz[3 * i + 2] = p->z ? p->z[i] : 0.0;
    vel[3 * i] = p->vx ? p->vx[i] : 0.0;
    vel[3 * i + 1] = p->vy ? p->vy[i] : 0.0;
    vel[3 * i + 2] = p->vz ? p->vz[i] : 0.0;
    id[i] = f && i < f->n_particles ? f->id[i] : -1;
    fid[i] = (double)id[i];
  }
  ms_status st = MS_ERR_IO;
  const bool dist = par_size() > 1;
  ms_h5 *h = dist ? ms_h5_create_collective(path) : ms_h5_create(path);
  if (h) {
    st = ms_h5_write_doubles_dist(h, "particles/x", n, 3, xyz, "cm");
    if (!st) st = ms_h5_write_doubles_dist(h, "particles/v", n, 3, vel, "km/s");
    if (!st) st = ms_h5_write_doubles_dist(h, "particles/mass", n, 1, p->mass, "g");
    if (!st && p->gid) st = ms_h5_write_ints_dist(h, "particles/gid", n, p->gid);
    if (!st) st = ms_h5_write_ints_dist(h, "particles/fragment", n, id);
    if (!st) st = ms_h5_write_doubles_dist(h, "particles/fragment_id", n, 1, fid, "1");
    if (!st) st = ms_h5_attr_double(h, "particles", "time", info->time);
    if (!st) st = ms_h5_attr_double(h, "particles", "r0", info->spacing);
    if (!st && info->rho0 > 0) st = ms_h5_attr_double(h, "particles", "rho0", info->rho0);
    static const char *const pn[3] = {"period_x", "period_y", "period_z"};
    static const char *const ln[3] = {"lo_x", "lo_y", "lo_z"};
    for (int k = 0; k < 3 && !st; k++)
      if (info->box.period[k] > 0) {
        st = ms_h5_attr_double(h, "particles", pn[k], info->box.period[k]);
        if (!st) st = ms_h5_attr_double(h, "particles", ln[k], info->box.lo[k]);
      }
    if (!st) st = ms_h5_close(h);
    else ms_h5_abort(h);
  }
  const size_t nglobal = dist ? (size_t)par_sum_long((long)n) : n;
  if (st == MS_OK && (!dist || par_rank() == 0)) {
    size_t len = strlen(path);
    char *xmf = ms_calloc(len + 8, 1);
    memcpy(xmf, path, len);
    if (len > 3 && !strcmp(path + len - 3, ".h5")) len -= 3;
    strcpy(xmf + len, ".xmf");
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    ms_xdmf_attr attr[] = {{"velocity", "particles/v", 3, false},
                           {"mass", "particles/mass", 1, false},
                           {"fragment", "particles/fragment_id", 1, false}};
    st = ms_xdmf_write_points(xmf, base, "particles/x", nglobal, 3, info->time, 3, attr);
    free(xmf);
  }
  free(xyz);
  free(vel);
  free(fid);
  free(id);
  return dist ? par_agree_status(st) : st; /* the sidecar is rank 0's */
}
