/* SPDX-License-Identifier: MIT */
/* HDF5 output (temporary name + rename) and input for post-processing. */
#include "core.h"
#include "par_mpi.h"

#include <hdf5.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct ms_h5 {
  hid_t file;
  char *path, *tmp_path;
  const ms_comm *comm; /* collective: opened by every rank of comm with MPI-IO; else NULL */
};

struct ms_h5r {
  hid_t file;
  char *path;
};

static void quiet_hdf5(void) { H5Eset_auto2(H5E_DEFAULT, NULL, NULL); }

static ms_h5 *create_file(const char *path, const ms_comm *comm) {
  quiet_hdf5();
  ms_h5 *h = ms_calloc(1, sizeof *h);
  h->path = ms_strdup(path);
  h->tmp_path = ms_calloc(strlen(path) + 6, 1);
  sprintf(h->tmp_path, "%s.part", path);
  h->comm = comm;
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (comm) H5Pset_fapl_mpio(fapl, par_comm_mpi(comm), MPI_INFO_NULL);
  h->file = H5Fcreate(h->tmp_path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  H5Pclose(fapl);
  if (comm) {
    /* every rank must agree that the file exists before anyone writes */
    const int all = par_comm_min_int(comm, h->file >= 0);
    if (!all && h->file >= 0) {
      H5Fclose(h->file);
      h->file = -1;
    }
  }
  if (h->file < 0) {
    fprintf(stderr, "mscale: cannot create HDF5 file '%s'\n", h->tmp_path);
    free(h->path);
    free(h->tmp_path);
    free(h);
    return NULL;
  }
  return h;
}

ms_h5 *ms_h5_create(const char *path) { return create_file(path, NULL); }

ms_h5 *ms_h5_create_collective(const char *path) { return create_file(path, par_comm()); }

static hid_t link_props(void) {
  hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  return lcpl;
}

static ms_status write_units(hid_t obj, const char *units) {
  if (!units) return MS_OK;
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, strlen(units) + 1);
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t attr = H5Acreate2(obj, "units", type, space, H5P_DEFAULT, H5P_DEFAULT);
  herr_t rc = attr >= 0 ? H5Awrite(attr, type, units) : -1;
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
  return rc < 0 ? MS_ERR_IO : MS_OK;
}

static ms_status write_dataset(ms_h5 *h, const char *name, int rank, const hsize_t *dims,
                               hid_t memtype, hid_t filetype, const void *data, const char *units) {
  hid_t space = H5Screate_simple(rank, dims, NULL);
  hid_t lcpl = link_props();
  hid_t ds = H5Dcreate2(h->file, name, filetype, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  herr_t rc = -1;
  if (ds >= 0) {
    /* an empty dataset (e.g. no rows recorded yet) is created, not written */
    rc = H5Sget_simple_extent_npoints(space) > 0
             ? H5Dwrite(ds, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data)
             : 0;
    if (rc >= 0 && write_units(ds, units)) rc = -1;
    H5Dclose(ds);
  }
  H5Pclose(lcpl);
  H5Sclose(space);
  if (rc < 0) {
    fprintf(stderr, "mscale: cannot write dataset '%s' to '%s'\n", name, h->tmp_path);
    return MS_ERR_IO;
  }
  return MS_OK;
}

ms_status ms_h5_write_times(ms_h5 *h, const char *name, size_t n, const double *t) {
  double *out = ms_calloc(n ? n : 1, sizeof *out);
  for (size_t i = 0; i < n; i++) out[i] = ms_out_time(t[i]);
  ms_status s = ms_h5_write_doubles(h, name, n, 1, out, ms_out_time_label());
  free(out);
  return s;
}

ms_status ms_h5_write_doubles(ms_h5 *h, const char *name, size_t n0, size_t n1, const double *data,
                              const char *units) {
  hsize_t dims[2] = {n0, n1};
  return write_dataset(h, name, n1 > 1 ? 2 : 1, dims, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, data,
                       units);
}

ms_status ms_h5_write_ints(ms_h5 *h, const char *name, size_t n, const int64_t *data) {
  hsize_t dims[1] = {n};
  return write_dataset(h, name, 1, dims, H5T_NATIVE_INT64, H5T_STD_I64LE, data, NULL);
}

/* Distributed rows: rank r writes rows [offset_r, offset_r + n_local) of a [N][ncomp] dataset,
 * offset_r = sum of n_local over lower ranks. One collective write, so the file holds the same
 * bytes whatever the rank count. */
static ms_status write_rows_dist(ms_h5 *h, const char *name, size_t n_local, size_t ncomp,
                                 hid_t memtype, hid_t filetype, const void *data,
                                 const char *units) {
  if (!h->comm) {
    hsize_t dims[2] = {n_local, ncomp};
    return write_dataset(h, name, ncomp > 1 ? 2 : 1, dims, memtype, filetype, data, units);
  }
  const uint64_t offset = par_comm_exscan_u64(h->comm, n_local);
  const uint64_t total = par_comm_sum_u64(h->comm, n_local);
  const int rank = par_comm_rank(h->comm);
  int rank_dims = ncomp > 1 ? 2 : 1;
  hsize_t gdims[2] = {total, ncomp}, start[2] = {offset, 0}, count[2] = {n_local, ncomp};
  hid_t fspace = H5Screate_simple(rank_dims, gdims, NULL);
  hid_t lcpl = link_props();
  hid_t ds = H5Dcreate2(h->file, name, filetype, fspace, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  herr_t rc = -1;
  if (ds >= 0) {
    hid_t mspace = H5Screate_simple(rank_dims, count, NULL);
    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL);
    if (n_local == 0) {
      H5Sselect_none(fspace);
      H5Sselect_none(mspace);
    }
    hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
    H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
    /* an empty dataset is created, not written (the same decision on every rank) */
    rc = total * ncomp > 0 ? H5Dwrite(ds, memtype, mspace, fspace, dxpl, data) : 0;
    H5Pclose(dxpl);
    H5Sclose(mspace);
    if (rc >= 0 && write_units(ds, units)) rc = -1;
    H5Dclose(ds);
  }
  H5Pclose(lcpl);
  H5Sclose(fspace);
  if (par_comm_max_int(h->comm, rc < 0)) {
    if (rank == 0)
      fprintf(stderr, "mscale: cannot write dataset '%s' to '%s'\n", name, h->tmp_path);
    return MS_ERR_IO;
  }
  return MS_OK;
}

ms_status ms_h5_write_doubles_dist(ms_h5 *h, const char *name, size_t n_local, size_t ncomp,
                                   const double *data, const char *units) {
  return write_rows_dist(h, name, n_local, ncomp, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, data, units);
}

ms_status ms_h5_write_ints_dist(ms_h5 *h, const char *name, size_t n_local, const int64_t *data) {
  return write_rows_dist(h, name, n_local, 1, H5T_NATIVE_INT64, H5T_STD_I64LE, data, NULL);
}

ms_status ms_h5_write_bytes_dist(ms_h5 *h, const char *name, size_t n_local, const void *data) {
  return write_rows_dist(h, name, n_local, 1, H5T_NATIVE_UINT8, H5T_STD_U8LE, data, NULL);
}

static hid_t open_object(hid_t file, const char *obj) {
  if (!obj || !obj[0] || !strcmp(obj, "/")) return H5Oopen(file, "/", H5P_DEFAULT);
  if (H5Lexists(file, obj, H5P_DEFAULT) <= 0) {
    hid_t lcpl = link_props();
    hid_t g = H5Gcreate2(file, obj, lcpl, H5P_DEFAULT, H5P_DEFAULT);
    H5Pclose(lcpl);
    return g;
  }
  return H5Oopen(file, obj, H5P_DEFAULT);
}

/* A scalar attribute of the file type `ftype`, written from `v` in the memory type `mtype`. */
static ms_status attr_scalar(ms_h5 *h, const char *obj, const char *attr, hid_t ftype, hid_t mtype,
                             const void *v) {
  hid_t o = open_object(h->file, obj);
  if (o < 0) return MS_ERR_IO;
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(o, attr, ftype, space, H5P_DEFAULT, H5P_DEFAULT);
  herr_t rc = a >= 0 ? H5Awrite(a, mtype, v) : -1;
  if (a >= 0) H5Aclose(a);
  H5Sclose(space);
  H5Oclose(o);
  return rc < 0 ? MS_ERR_IO : MS_OK;
}

ms_status ms_h5_attr_double(ms_h5 *h, const char *obj, const char *attr, double v) {
  return attr_scalar(h, obj, attr, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v);
}

ms_status ms_h5_attr_int(ms_h5 *h, const char *obj, const char *attr, int64_t v) {
  return attr_scalar(h, obj, attr, H5T_STD_I64LE, H5T_NATIVE_INT64, &v);
}

ms_status ms_h5_attr_string(ms_h5 *h, const char *obj, const char *attr, const char *v) {
  hid_t o = open_object(h->file, obj);
  if (o < 0) return MS_ERR_IO;
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, strlen(v) + 1);
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(o, attr, type, space, H5P_DEFAULT, H5P_DEFAULT);
  herr_t rc = a >= 0 ? H5Awrite(a, type, v) : -1;
  if (a >= 0) H5Aclose(a);
  H5Sclose(space);
  H5Tclose(type);
  H5Oclose(o);
  return rc < 0 ? MS_ERR_IO : MS_OK;
}

ms_status ms_h5_close(ms_h5 *h) {
  if (!h) return MS_ERR_IO;
  ms_status s = H5Fclose(h->file) < 0 ? MS_ERR_IO : MS_OK;
  if (h->comm) {
    /* the file is complete only when every rank has closed it; then one rank renames it */
    const int rank = par_comm_rank(h->comm);
    if (par_comm_max_int(h->comm, s != MS_OK)) s = MS_ERR_IO;
    int renamed = 1;
    if (!s && rank == 0) renamed = rename(h->tmp_path, h->path) == 0;
    par_comm_bcast_int(h->comm, &renamed, 0);
    if (!renamed) s = MS_ERR_IO;
    if (s && rank != 0) { /* only rank 0 reports and cleans up */
      free(h->path);
      free(h->tmp_path);
      free(h);
      return s;
    }
  } else if (!s && rename(h->tmp_path, h->path) != 0) {
    s = MS_ERR_IO;
  }
  if (s) {
    fprintf(stderr, "mscale: cannot complete HDF5 file '%s'\n", h->path);
    remove(h->tmp_path);
  }
  free(h->path);
  free(h->tmp_path);
  free(h);
  return s;
}

void ms_h5_abort(ms_h5 *h) {
  if (!h) return;
  H5Fclose(h->file);
  remove(h->tmp_path);
  free(h->path);
  free(h->tmp_path);
  free(h);
}

/* ------------------------------------------------------------------------------------------ */

ms_h5r *ms_h5_open_read(const char *path, dk_errors *e) {
  quiet_hdf5();
  if (H5Fis_hdf5(path) <= 0) {
    dk_error_at(e, path, 0, 0, "not a readable HDF5 file");
    return NULL;
  }
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) {
    dk_error_at(e, path, 0, 0, "cannot open the HDF5 file");
    return NULL;
  }
  ms_h5r *h = ms_calloc(1, sizeof *h);
  h->file = f;
  h->path = ms_strdup(path);
  return h;
}

bool ms_h5_exists(ms_h5r *h, const char *name) {
  /* H5Lexists needs every intermediate group to exist: walk the path. */
  char buf[512];
  snprintf(buf, sizeof buf, "%s", name);
  for (char *p = buf + 1; *p; p++) {
    if (*p == '/') {
      *p = 0;
      if (H5Lexists(h->file, buf, H5P_DEFAULT) <= 0) return false;
      *p = '/';
    }
  }
  return H5Lexists(h->file, buf, H5P_DEFAULT) > 0;
}


/* Rows [row0, row0 + nrow) of a 1D/2D dataset of class `cls` read as `memtype` (elem bytes). */
static ms_status read_rows(ms_h5r *h, const char *name, size_t row0, size_t nrow, H5T_class_t cls,
                           hid_t memtype, size_t elem, void **data, size_t *nread, size_t *ncol,
                           dk_errors *e) {
  *data = NULL;
  *nread = *ncol = 0;
  if (!ms_h5_exists(h, name)) {
    dk_error_at(e, h->path, 0, 0, "dataset '%s' is missing", name);
    return MS_ERR_INPUT;
  }
  hid_t ds = H5Dopen2(h->file, name, H5P_DEFAULT);
  if (ds < 0) {
    dk_error_at(e, h->path, 0, 0, "'%s' is not a dataset", name);
    return MS_ERR_INPUT;
  }
  hid_t space = H5Dget_space(ds), type = H5Dget_type(ds);
  int rank = H5Sget_simple_extent_ndims(space);
  hsize_t dims[2] = {0, 1};
  ms_status s = MS_ERR_INPUT;
  if (rank < 1 || rank > 2 || H5Tget_class(type) != cls) {
    dk_error_at(e, h->path, 0, 0, "dataset '%s' must be a 1D or 2D %s array", name,
                cls == H5T_FLOAT ? "floating-point" : "integer");
  } else {
    H5Sget_simple_extent_dims(space, dims, NULL);
    if (rank == 1) dims[1] = 1;
    if (nrow == SIZE_MAX && row0 <= dims[0]) nrow = (size_t)(dims[0] - row0);
    /* Refuse sizes that cannot be real before allocating: a damaged or hostile file can declare
     * any shape (fuzz_h5 found 2^30 x 8 declared with nothing stored -> an 8 GiB calloc). Without
     * filters (mscale writes none) the file must store every element; with filters, at least
     * the result must fit in half of this machine's memory. */
    hsize_t count = dims[1] ? dims[0] * dims[1] : 0, tsize = H5Tget_size(type);
    hsize_t stored = H5Dget_storage_size(ds);
    hid_t dcpl = H5Dget_create_plist(ds);
    int nfilters = dcpl >= 0 ? H5Pget_nfilters(dcpl) : 0;
    if (dcpl >= 0) H5Pclose(dcpl);
    double ram = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
    if (dims[1] && dims[0] > (hsize_t)SIZE_MAX / elem / dims[1]) {
      dk_error_at(e, h->path, 0, 0, "dataset '%s' declares an impossible size", name);
    } else if (nfilters == 0 && (double)stored < (double)count * (double)tsize) {
      dk_error_at(e, h->path, 0, 0,
                  "dataset '%s' of shape [%llu][%llu] stores only %llu of its %llu bytes "
                  "(truncated or damaged file?)",
                  name, (unsigned long long)dims[0], (unsigned long long)dims[1],
                  (unsigned long long)stored, (unsigned long long)(count * tsize));
    } else if (ram > 0 && (double)count * (double)elem > 0.5 * ram) {
      dk_error_at(e, h->path, 0, 0,
                  "dataset '%s' needs %.3g GiB, more than half of this "
                  "machine's memory (%.3g GiB)",
                  name, (double)count * (double)elem / 1073741824.0, ram / 1073741824.0);
    } else if (row0 > dims[0] || nrow > dims[0] - row0) {
      dk_error_at(e, h->path, 0, 0, "dataset '%s' has %llu rows, rows %zu..%zu were asked for",
                  name, (unsigned long long)dims[0], row0, row0 + nrow);
    } else {
      void *buf = calloc(nrow * dims[1] + 1, elem);
      hsize_t start[2] = {row0, 0}, cnt[2] = {nrow, dims[1]};
      hid_t mspace = H5Screate_simple(rank, cnt, NULL);
      H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, cnt, NULL);
      const bool empty = nrow == 0 || dims[1] == 0;
      if (!buf || (!empty && H5Dread(ds, memtype, mspace, space, H5P_DEFAULT, buf) < 0)) {
        dk_error_at(e, h->path, 0, 0, "cannot read dataset '%s'", name);
        free(buf);
      } else {
        *data = buf;
        *nread = nrow;
        *ncol = (size_t)dims[1];
        s = MS_OK;
      }
      H5Sclose(mspace);
    }
  }
  H5Tclose(type);
  H5Sclose(space);
  H5Dclose(ds);
  return s;
}

ms_status ms_h5_read_doubles(ms_h5r *h, const char *name, double **data, size_t *n0, size_t *n1,
                             dk_errors *e) {
  return read_rows(h, name, 0, SIZE_MAX, H5T_FLOAT, H5T_NATIVE_DOUBLE, sizeof(double),
                   (void **)data, n0, n1, e);
}

ms_status ms_h5_read_doubles_rows(ms_h5r *h, const char *name, size_t row0, size_t nrow,
                                  double **data, size_t *nread, size_t *ncol, dk_errors *e) {
  return read_rows(h, name, row0, nrow, H5T_FLOAT, H5T_NATIVE_DOUBLE, sizeof(double), (void **)data,
                   nread, ncol, e);
}

ms_status ms_h5_read_ints_rows(ms_h5r *h, const char *name, size_t row0, size_t nrow,
                               int64_t **data, size_t *nread, size_t *ncol, dk_errors *e) {
  return read_rows(h, name, row0, nrow, H5T_INTEGER, H5T_NATIVE_INT64, sizeof(int64_t),
                   (void **)data, nread, ncol, e);
}

ms_status ms_h5_read_bytes(ms_h5r *h, const char *name, char **data, size_t *n, dk_errors *e) {
  size_t ncol = 0;
  ms_status s =
      read_rows(h, name, 0, SIZE_MAX, H5T_INTEGER, H5T_NATIVE_UINT8, 1, (void **)data, n, &ncol, e);
  if (s == MS_OK && ncol != 1) {
    dk_error_at(e, h->path, 0, 0, "dataset '%s' must be 1D bytes", name);
    free(*data);
    *data = NULL;
    s = MS_ERR_INPUT;
  }
  return s;
}

ms_status ms_h5_read_attr_string(ms_h5r *h, const char *obj, const char *attr, char **v,
                                 dk_errors *e) {
  const char *o = obj && obj[0] ? obj : "/";
  *v = NULL;
  if ((strcmp(o, "/") && !ms_h5_exists(h, o)) ||
      H5Aexists_by_name(h->file, o, attr, H5P_DEFAULT) <= 0) {
    if (e) dk_error_at(e, h->path, 0, 0, "attribute '%s' of '%s' is missing", attr, o);
    return MS_ERR_INPUT;
  }
  hid_t a = H5Aopen_by_name(h->file, o, attr, H5P_DEFAULT, H5P_DEFAULT);
  ms_status s = MS_ERR_INPUT;
  if (a >= 0) {
    hid_t type = H5Aget_type(a);
    size_t len = H5Tget_size(type);
    if (H5Tget_class(type) == H5T_STRING && !H5Tis_variable_str(type) && len < (1u << 20)) {
      hid_t mt = H5Tcopy(H5T_C_S1);
      H5Tset_size(mt, len + 1);
      char *buf = ms_calloc(len + 2, 1);
      if (H5Aread(a, mt, buf) >= 0) {
        *v = buf;
        s = MS_OK;
      } else {
        free(buf);
      }
      H5Tclose(mt);
    }
    H5Tclose(type);
    H5Aclose(a);
  }
  if (s != MS_OK && e)
    dk_error_at(e, h->path, 0, 0, "attribute '%s' of '%s' is not a string", attr, o);
  return s;
}

ms_status ms_h5_read_attr_double(ms_h5r *h, const char *obj, const char *attr, double *v,
                                 dk_errors *e) {
  const char *o = obj && obj[0] ? obj : "/";
  if (strcmp(o, "/") && !ms_h5_exists(h, o)) {
    if (e)
      dk_error_at(e, h->path, 0, 0, "'%s' is missing (looking for its attribute '%s')", o, attr);
    return MS_ERR_INPUT;
  }
  if (H5Aexists_by_name(h->file, o, attr, H5P_DEFAULT) <= 0) {
    if (e) dk_error_at(e, h->path, 0, 0, "attribute '%s' of '%s' is missing", attr, o);
    return MS_ERR_INPUT;
  }
  hid_t a = H5Aopen_by_name(h->file, o, attr, H5P_DEFAULT, H5P_DEFAULT);
  ms_status s = MS_ERR_INPUT;
  if (a >= 0) {
    hid_t space = H5Aget_space(a), type = H5Aget_type(a);
    H5T_class_t cls = H5Tget_class(type);
    if (H5Sget_simple_extent_npoints(space) == 1 && (cls == H5T_FLOAT || cls == H5T_INTEGER) &&
        H5Aread(a, H5T_NATIVE_DOUBLE, v) >= 0)
      s = MS_OK;
    H5Tclose(type);
    H5Sclose(space);
    H5Aclose(a);
  }
  if (s != MS_OK && e)
    dk_error_at(e, h->path, 0, 0, "attribute '%s' of '%s' is not a single number", attr, o);
  return s;
}

void ms_h5_close_read(ms_h5r *h) {
  if (!h) return;
  H5Fclose(h->file);
  free(h->path);
  free(h);
}

/* One member of a group, if it is a numeric 1D/2D dataset. H5Gget_info + H5Lget_name_by_idx +
 * H5Oopen/H5Iget_type: the same calls in the HDF5 1.10 and 1.12+ APIs. */
static bool list_one(hid_t g, const char *name, ms_h5_entry *it) {
  hid_t obj = H5Oopen(g, name, H5P_DEFAULT);
  if (obj < 0) return false;
  bool ok = false;
  if (H5Iget_type(obj) == H5I_DATASET) {
    hid_t sp = H5Dget_space(obj), ty = H5Dget_type(obj);
    hsize_t dims[2] = {0, 1};
    int rank = H5Sget_simple_extent_ndims(sp);
    H5T_class_t cls = H5Tget_class(ty);
    if ((rank == 1 || rank == 2) && (cls == H5T_FLOAT || cls == H5T_INTEGER)) {
      H5Sget_simple_extent_dims(sp, dims, NULL);
      it->name = ms_strdup(name);
      it->is_int = cls == H5T_INTEGER;
      it->rows = (size_t)dims[0];
      it->cols = rank == 2 ? (size_t)dims[1] : 1;
      ok = true;
    }
    H5Tclose(ty);
    H5Sclose(sp);
  }
  H5Oclose(obj);
  return ok;
}

ms_status ms_h5_list(ms_h5r *h, const char *group, ms_h5_entry **items, size_t *n, dk_errors *e) {
  *items = NULL;
  *n = 0;
  hid_t g = ms_h5_exists(h, group) ? H5Gopen2(h->file, group, H5P_DEFAULT) : -1;
  H5G_info_t info;
  if (g < 0 || H5Gget_info(g, &info) < 0) {
    dk_error_at(e, h->path, 0, 0, "group '%s' is missing", group);
    if (g >= 0) H5Gclose(g);
    return MS_ERR_INPUT;
  }
  *items = ms_calloc(info.nlinks ? info.nlinks : 1, sizeof **items);
  for (hsize_t k = 0; k < info.nlinks; k++) {
    char name[256];
    ssize_t len =
        H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT);
    if (len > 0 && (size_t)len < sizeof name && list_one(g, name, &(*items)[*n])) ++*n;
  }
  H5Gclose(g);
  return MS_OK;
}

void ms_h5_entries_free(ms_h5_entry *items, size_t n) {
  for (size_t k = 0; k < n && items; k++) free(items[k].name);
  free(items);
}

void ms_h5_library_version(char *buf, size_t n) {
  unsigned maj = 0, min = 0, rel = 0;
  H5get_libversion(&maj, &min, &rel);
  snprintf(buf, n, "%u.%u.%u", maj, min, rel);
}
