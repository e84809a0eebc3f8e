/* SPDX-License-Identifier: MIT */
/* Partition quality of the cluster-dynamics coarse-cell graph (docs/benchmarks.md "CD
 * partition"): METIS vs plain slabs (cd_partition_cells).
 *
 *   bench_cd_partition snapshot FILE.h5 [--cell K] [--parts 2,4,8,16,64] [--scale S]
 *       a particle snapshot (/particles/x; attributes of /particles: r0, period_x.. and lo_x..
 *       of periodic axes): coarse cells of K·r0 (default 4) over the particles' bounding box
 *       (over the period on periodic axes), weight = S × particles per cell (default 64, what
 *       cd_par.c passes); per part count: imbalance, edge cut, halo cells (Σ and max per part)
 *       of METIS and of slabs along every axis with > 1 cell.
 *   bench_cd_partition grid NX NY NZ PPC P1 [P2 ...] [--periodic]
 *       a uniform NX×NY×NZ grid, PPC particles per cell (weight 64·PPC): one CSV row per
 *       (method, parts):
 *       method,parts,cells,imbalance,edge_cut,halo_sum,halo_max,halo_mean,nbr_max,nbr_mean,seconds
 *       (tools/cd_comm_model.py builds the communication model from these rows).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cd.h"

typedef struct row {
  cd_partition_stats st;
  long halo_max;
  double halo_mean, nbr_mean;
  int nbr_max;
  double seconds;
} row;

static int partition(const int nc[3], const bool per[3], const int64_t *w, int parts,
                     cd_partition_method m, int axis, int32_t *owner, row *r) {
  double t0 = ms_wall_time();
  ms_status s = cd_partition_cells(nc, per, w, parts, m, axis, owner, &r->st);
  r->seconds = ms_wall_time() - t0;
  if (s != MS_OK) {
    fprintf(stderr, "bench_cd_partition: partition failed (%s)\n", ms_status_str(s));
    return 1;
  }
  long *halo = ms_calloc((size_t)parts, sizeof *halo);
  int *nbr = ms_calloc((size_t)parts, sizeof *nbr);
  cd_partition_halo(nc, per, owner, parts, halo, nbr);
  r->halo_max = 0;
  r->nbr_max = 0;
  double hs = 0, ns = 0;
  for (int p = 0; p < parts; ++p) {
    r->halo_max = halo[p] > r->halo_max ? halo[p] : r->halo_max;
    r->nbr_max = nbr[p] > r->nbr_max ? nbr[p] : r->nbr_max;
    hs += (double)halo[p];
    ns += nbr[p];
  }
  r->halo_mean = hs / parts;
  r->nbr_mean = ns / parts;
  free(halo);
  free(nbr);
  return 0;
}

static int parse_parts(const char *s, int *parts, int max) {
  int n = 0;
  while (*s && n < max) {
    char *end;
    long v = strtol(s, &end, 10);
    if (end == s || v < 1) return -1;
    parts[n++] = (int)v;
    s = *end == ',' ? end + 1 : end;
  }
  return n;
}

static int cmd_snapshot(int argc, char **argv) {
  const char *path = argv[0];
  double kcell = 4;
  long scale = 64;
  int parts[16] = {2, 4, 8, 16, 64}, nparts = 5;
  for (int i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--cell") && i + 1 < argc) kcell = atof(argv[++i]);
    else if (!strcmp(argv[i], "--scale") && i + 1 < argc) scale = atol(argv[++i]);
    else if (!strcmp(argv[i], "--parts") && i + 1 < argc)
      nparts = parse_parts(argv[++i], parts, 16);
    else nparts = -1;
  }
  if (nparts < 1 || !(kcell > 0) || scale < 1) {
    fprintf(stderr,
            "bench_cd_partition snapshot FILE.h5 [--cell K] [--parts 2,4,...] [--scale S]\n");
    return 2;
  }
  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *h = ms_h5_open_read(path, &e);
  double *x = NULL, r0 = 0;
  size_t n = 0, n1 = 0;
  if (!h || ms_h5_read_doubles(h, "/particles/x", &x, &n, &n1, &e) != MS_OK || n1 != 3 ||
      ms_h5_read_attr_double(h, "/particles", "r0", &r0, &e) != MS_OK) {
    for (size_t k = 0; k < e.n; ++k) fprintf(stderr, "%s\n", e.msg[k]);
    fprintf(stderr, "bench_cd_partition: cannot read %s\n", path);
    return 1;
  }
  static const char *const pname[3] = {"period_x", "period_y", "period_z"};
  static const char *const lname[3] = {"lo_x", "lo_y", "lo_z"};
  double period[3] = {0, 0, 0}, lo[3], hi[3];
  bool per[3];
  for (int a = 0; a < 3; ++a) {
    dk_errors quiet;
    dk_errors_init(&quiet);
    per[a] = ms_h5_read_attr_double(h, "/particles", pname[a], &period[a], &quiet) == MS_OK &&
             period[a] > 0;
    lo[a] = INFINITY;
    hi[a] = -INFINITY;
    for (size_t i = 0; i < n; ++i) {
      lo[a] = fmin(lo[a], x[3 * i + a]);
      hi[a] = fmax(hi[a], x[3 * i + a]);
    }
    if (per[a]) {
      ms_h5_read_attr_double(h, "/particles", lname[a], &lo[a], &quiet);
      hi[a] = lo[a] + period[a];
    }
    dk_errors_free(&quiet);
  }
  ms_h5_close_read(h);
  const double w = kcell * r0;
  int nc[3];
  size_t nv = 1;
  for (int a = 0; a < 3; ++a) {
    nc[a] = (int)fmax(1, floor((hi[a] - lo[a]) / w)); /* cells ≥ K r0 (periodic: tile the period) */
    nv *= (size_t)nc[a];
  }
  int64_t *wt = ms_calloc(nv, sizeof *wt);
  for (size_t i = 0; i < n; ++i) {
    size_t c = 0, stride = 1;
    for (int a = 0; a < 3; ++a) {
      double s = (x[3 * i + a] - lo[a]) / (hi[a] - lo[a] > 0 ? hi[a] - lo[a] : 1) * nc[a];
      if (per[a]) s -= nc[a] * floor(s / nc[a]);
      int q = (int)s;
      q = q < 0 ? 0 : q >= nc[a] ? nc[a] - 1 : q;
      c += (size_t)q * stride;
      stride *= (size_t)nc[a];
    }
    wt[c] += scale;
  }
  size_t occupied = 0;
  for (size_t c = 0; c < nv; ++c) occupied += wt[c] > 0;
  printf("# %s: %zu particles, r0 = %.4g cm, cells %d x %d x %d of %.3g r0 (%zu, %zu occupied), "
         "weight %ld per particle\n",
         path, n, r0, nc[0], nc[1], nc[2], kcell, nv, occupied, scale);
  printf("# extent [cm]: x %.4g..%.4g  y %.4g..%.4g  z %.4g..%.4g; periodic %d%d%d\n", lo[0], hi[0],
         lo[1], hi[1], lo[2], hi[2], per[0], per[1], per[2]);
  printf("| parts | method | imbalance | edge cut | halo cells (sum) | halo max/part | neighbour "
         "parts max |\n");
  printf("|---|---|---|---|---|---|---|\n");
  int32_t *owner = ms_calloc(nv, sizeof *owner);
  for (int k = 0; k < nparts; ++k) {
    row r;
    if (partition(nc, per, wt, parts[k], CD_PART_METIS, 0, owner, &r)) return 1;
    printf("| %d | METIS | %.4f | %ld | %ld | %ld | %d |\n", parts[k], r.st.imbalance,
           r.st.edge_cut, r.st.halo_cells, r.halo_max, r.nbr_max);
    for (int a = 0; a < 3; ++a) {
      if (nc[a] < 2) continue;
      if (partition(nc, per, wt, parts[k], CD_PART_SLAB, a, owner, &r)) return 1;
      printf("| %d | slabs along %c | %.4f | %ld | %ld | %ld | %d |\n", parts[k], "xyz"[a],
             r.st.imbalance, r.st.edge_cut, r.st.halo_cells, r.halo_max, r.nbr_max);
    }
  }
  free(owner);
  free(wt);
  free(x);
  dk_errors_free(&e);
  return 0;
}

static int cmd_grid(int argc, char **argv) {
  if (argc < 5) {
    fprintf(stderr, "bench_cd_partition grid NX NY NZ PPC P1 [P2 ...] [--periodic]\n");
    return 2;
  }
  int nc[3] = {atoi(argv[0]), atoi(argv[1]), atoi(argv[2])};
  long ppc = atol(argv[3]);
  bool per[3] = {false, false, false};
  int parts[64], np = 0;
  for (int i = 4; i < argc; ++i) {
    if (!strcmp(argv[i], "--periodic")) per[0] = per[1] = per[2] = true;
    else if (np < 64) parts[np++] = atoi(argv[i]);
  }
  size_t nv = (size_t)nc[0] * (size_t)nc[1] * (size_t)nc[2];
  if (nc[0] < 1 || nc[1] < 1 || nc[2] < 1 || ppc < 0 || np < 1) return 2;
  int64_t *w = ms_calloc(nv, sizeof *w);
  for (size_t c = 0; c < nv; ++c) w[c] = 64 * ppc;
  int32_t *owner = ms_calloc(nv, sizeof *owner);
  printf("method,parts,cells,imbalance,edge_cut,halo_sum,halo_max,halo_mean,nbr_max,nbr_mean,"
         "seconds\n");
  for (int k = 0; k < np; ++k)
    for (int m = 0; m < 2; ++m) {
      row r;
      if (partition(nc, per, w, parts[k], m ? CD_PART_SLAB : CD_PART_METIS, 0, owner, &r)) return 1;
      printf("%s,%d,%zu,%.5f,%ld,%ld,%ld,%.2f,%d,%.2f,%.3f\n", m ? "slab" : "metis", parts[k], nv,
             r.st.imbalance, r.st.edge_cut, r.st.halo_cells, r.halo_max, r.halo_mean, r.nbr_max,
             r.nbr_mean, r.seconds);
      fflush(stdout);
    }
  free(w);
  free(owner);
  return 0;
}

int main(int argc, char **argv) {
  if (argc >= 3 && !strcmp(argv[1], "snapshot")) return cmd_snapshot(argc - 2, argv + 2);
  if (argc >= 2 && !strcmp(argv[1], "grid")) return cmd_grid(argc - 2, argv + 2);
  fprintf(stderr, "usage: bench_cd_partition snapshot FILE.h5 [--cell K] [--parts 2,4,8]\n"
                  "       bench_cd_partition grid NX NY NZ PPC P1 [P2 ...] [--periodic]\n");
  return 2;
}
