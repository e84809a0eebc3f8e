/* SPDX-License-Identifier: MIT */
/* ptl_partition.c — the one METIS call of mscale (ptl.h): cluster dynamics partitions its
 * coarse-cell graph with it (cd/cd_partition.c), the discrete model its bond graph
 * (dm/dm_par.c). */
#include "ptl.h"

#include <metis.h>

/* The callers build their graphs in int32_t; this build's METIS indexes with the same width. */
_Static_assert(sizeof(idx_t) == sizeof(int32_t), "METIS built with a 32-bit idx_t expected");

ms_status ptl_partition_kway(int32_t nv, const int32_t *xadj, const int32_t *adj,
                             const int32_t *vwgt, const int32_t *adjw, int nparts, int ufactor,
                             int32_t *part, int *code) {
  idx_t nvtx = nv, ncon = 1, np = nparts, objval = 0;
  idx_t opts[METIS_NOPTIONS];
  METIS_SetDefaultOptions(opts);
  opts[METIS_OPTION_SEED] = 12345; /* fixed: every rank and run computes the same map */
  opts[METIS_OPTION_NUMBERING] = 0;
  if (ufactor > 0) opts[METIS_OPTION_UFACTOR] = ufactor;
  /* METIS reads but does not write the graph arrays (its interface is not const-qualified) */
  const int rc = METIS_PartGraphKway(&nvtx, &ncon, (idx_t *)xadj, (idx_t *)adj, (idx_t *)vwgt, NULL,
                                     (idx_t *)adjw, &np, NULL, NULL, opts, &objval, (idx_t *)part);
  if (code) *code = rc;
  return rc == METIS_OK ? MS_OK : MS_ERR_INTERNAL;
}
