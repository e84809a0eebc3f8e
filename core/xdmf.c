/* SPDX-License-Identifier: MIT */
/* XDMF sidecar so ParaView opens the HDF5 snapshots (Polyvertex topology). */
#include "core.h"

#include <dirent.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

ms_status ms_xdmf_write_points(const char *xmf_path, const char *h5_name, const char *coords,
                               size_t npoints, int dim, double time, size_t nattr,
                               const ms_xdmf_attr *attr) {
  return ms_xdmf_write_particles(xmf_path, h5_name, coords, NULL, npoints, dim, time, nattr, attr);
}

ms_status ms_xdmf_write_particles(const char *xmf_path, const char *h5_name, const char *coords,
                                  const char *vertex, size_t npoints, int dim, double time,
                                  size_t nattr, const ms_xdmf_attr *attr) {
  ms_afile af;
  ms_status s = ms_afile_open(&af, xmf_path);
  if (s) return s;
  FILE *f = af.f;
  fprintf(f, "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n");
  fprintf(f, "  <Grid Name=\"mscale\" GridType=\"Uniform\">\n");
  fprintf(f, "   <Time Value=\"%.17g\"/>\n", time);
  bool has_cells = false;
  for (size_t i = 0; i < nattr; i++) has_cells = has_cells || attr[i].cell_centred;
  if (has_cells && npoints > 1) {
    /* A 1D grid: segments between consecutive nodes, so cell data has cells to live on. */
    fprintf(f,
            "   <Topology TopologyType=\"Polyline\" NumberOfElements=\"%zu\" "
            "NodesPerElement=\"2\">\n    <DataItem Dimensions=\"%zu 2\" NumberType=\"Int\" "
            "Format=\"XML\">",
            npoints - 1, npoints - 1);
    for (size_t i = 0; i + 1 < npoints; i++) fprintf(f, "%s%zu %zu", i % 8 ? " " : "\n", i, i + 1);
    fprintf(f, "\n    </DataItem>\n   </Topology>\n");
  } else if (vertex) {
    /* explicit connectivity: ParaView's Xdmf3 reader makes one vertex cell per particle only
     * from it (without, it shows the points with no cells, and the default Surface view draws
     * nothing) */
    fprintf(f,
            "   <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%zu\" "
            "NodesPerElement=\"1\">\n    <DataItem Dimensions=\"%zu\" NumberType=\"Int\" "
            "Precision=\"8\" Format=\"HDF\">%s:%s</DataItem>\n   </Topology>\n",
            npoints, npoints, h5_name, vertex);
  } else {
    fprintf(f,
            "   <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%zu\" "
            "NodesPerElement=\"1\"/>\n",
            npoints);
  }
  if (dim != 2 && dim != 3) {
    ms_afile_abort(&af);
    return MS_ERR_INTERNAL;
  }
  fprintf(f, "   <Geometry GeometryType=\"%s\">\n", dim == 2 ? "XY" : "XYZ");
  fprintf(f,
          "    <DataItem Dimensions=\"%zu %d\" NumberType=\"Float\" Precision=\"8\" "
          "Format=\"HDF\">%s:%s</DataItem>\n",
          npoints, dim, h5_name, coords);
  fprintf(f, "   </Geometry>\n");
  for (size_t i = 0; i < nattr; i++) {
    size_t n = attr[i].cell_centred && npoints > 0 ? npoints - 1 : npoints;
    fprintf(f, "   <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"%s\">\n", attr[i].name,
            attr[i].ncomp == 3 ? "Vector" : "Scalar", attr[i].cell_centred ? "Cell" : "Node");
    if (attr[i].ncomp > 1)
      fprintf(f,
              "    <DataItem Dimensions=\"%zu %d\" NumberType=\"Float\" Precision=\"8\" "
              "Format=\"HDF\">%s:%s</DataItem>\n",
              n, attr[i].ncomp, h5_name, attr[i].dataset);
    else
      fprintf(f,
              "    <DataItem Dimensions=\"%zu\" NumberType=\"Float\" Precision=\"8\" "
              "Format=\"HDF\">%s:%s</DataItem>\n",
              n, h5_name, attr[i].dataset);
    fprintf(f, "   </Attribute>\n");
  }
  fprintf(f, "  </Grid>\n </Domain>\n</Xdmf>\n");
  return ms_afile_commit(&af);
}

typedef struct series_frame {
  char *name;
  double time;
} series_frame;

static int compare_frames(const void *a, const void *b) {
  const series_frame *x = a, *y = b;
  if (x->time != y->time) return x->time < y->time ? -1 : 1;
  return strcmp(x->name, y->name);
}

/* The Time Value of a sidecar we wrote (NAN if it has none). */
static double sidecar_time(const char *dir, const char *name) {
  char *path = ms_calloc(strlen(dir) + strlen(name) + 2, 1);
  sprintf(path, "%s/%s", dir, name);
  FILE *f = fopen(path, "r");
  free(path);
  double t = NAN;
  char line[256];
  while (f && fgets(line, sizeof line, f))
    if (sscanf(line, " <Time Value=\"%lf\"", &t) == 1) break;
  if (f) fclose(f);
  return t;
}

ms_status ms_xdmf_write_series(const char *dir, const char *prefix, const char *series_name) {
  DIR *d = opendir(dir);
  if (!d) return MS_ERR_IO;
  size_t n = 0, cap = 0, plen = strlen(prefix);
  series_frame *fr = NULL;
  for (struct dirent *ent; (ent = readdir(d));) {
    size_t len = strlen(ent->d_name);
    if (len <= plen + 4 || strncmp(ent->d_name, prefix, plen) ||
        strcmp(ent->d_name + len - 4, ".xmf") || !strcmp(ent->d_name, series_name))
      continue;
    double t = sidecar_time(dir, ent->d_name);
    if (isnan(t)) continue;
    if (n == cap) fr = ms_realloc(fr, cap = cap ? 2 * cap : 16, sizeof *fr);
    fr[n++] = (series_frame){ms_strdup(ent->d_name), t};
  }
  closedir(d);
  /* in time order; a second sidecar of the same time (profile_final after the last regular
   * profile) is left out: ParaView cannot show two grids at one time step */
  if (n > 1) qsort(fr, n, sizeof *fr, compare_frames);
  char *path = ms_calloc(strlen(dir) + strlen(series_name) + 2, 1);
  sprintf(path, "%s/%s", dir, series_name);
  ms_afile af;
  ms_status s = ms_afile_open(&af, path);
  if (s == MS_OK) {
    fprintf(af.f,
            "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\" "
            "xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n <Domain>\n"
            "  <Grid Name=\"%.*s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
            (int)strcspn(series_name, "."), series_name);
    for (size_t k = 0; k < n; k++)
      if (k == 0 || fr[k].time != fr[k - 1].time)
        fprintf(af.f, "   <xi:include href=\"%s\" xpointer=\"xpointer(//Xdmf/Domain/Grid)\"/>\n",
                fr[k].name);
    fprintf(af.f, "  </Grid>\n </Domain>\n</Xdmf>\n");
    s = ms_afile_commit(&af);
  }
  for (size_t k = 0; k < n; k++) free(fr[k].name);
  free(fr);
  free(path);
  return s;
}
