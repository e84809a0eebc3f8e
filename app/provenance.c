/* SPDX-License-Identifier: MIT */
/* What built this mscale and where it runs: the version (git describe at build time, else the
 * project version), the commit, the compiler and flags, the libraries' versions, ranks,
 * threads and host. For `mscale --version` and run_info.yaml (issue 23 items 1 and 7). */
#include "commands.h"

#include "cd.h"
#include "mscale_build_config.h"
#include "mscale_git.h"

#include <metis.h>
#include <sundials/sundials_config.h>
#include <unistd.h>

const char *app_version(void) { return MSCALE_GIT_VERSION; }

void app_put_yaml_escaped(FILE *f, const char *s) {
  for (; *s; s++) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\') fprintf(f, "\\%c", c);
    else if (c < 0x20 || c == 0x7f) fprintf(f, "\\x%02x", c);
    else fputc(c, f);
  }
}

void app_put_yaml_quoted(FILE *f, const char *s) {
  fputc('"', f);
  app_put_yaml_escaped(f, s);
  fputc('"', f);
}

static void put_field(FILE *f, const char *indent, const char *key, const char *value) {
  fprintf(f, "%s%s: ", indent, key);
  app_put_yaml_quoted(f, value);
  fputc('\n', f);
}

void app_print_version(FILE *f) {
  char mpi[256], h5[32];
  par_mpi_library_version(mpi, sizeof mpi);
  ms_h5_library_version(h5, sizeof h5);
  fprintf(f, "mscale %s\n", MSCALE_GIT_VERSION);
  if (MSCALE_GIT_COMMIT[0]) fprintf(f, "commit %s\n", MSCALE_GIT_COMMIT);
  fprintf(f, "built with %s (%s), flags: %s\n", MSCALE_BUILD_COMPILER, MSCALE_BUILD_TYPE,
          MSCALE_BUILD_FLAGS);
  fprintf(f, "libraries: MPI %s; HDF5 %s; SUNDIALS %s; METIS %d.%d.%d; libyaml %s\n", mpi, h5,
          SUNDIALS_VERSION, METIS_VER_MAJOR, METIS_VER_MINOR, METIS_VER_SUBMINOR,
          dk_yaml_version());
  fprintf(f, "cluster-dynamics kernels: %s (chosen for this CPU at run time)\n", cd_kernel_name());
}

void app_write_provenance(FILE *f, const ms_ctx *ctx) {
  char mpi[256], h5[32], metis[32], host[256] = "";
  par_mpi_library_version(mpi, sizeof mpi);
  ms_h5_library_version(h5, sizeof h5);
  snprintf(metis, sizeof metis, "%d.%d.%d", METIS_VER_MAJOR, METIS_VER_MINOR, METIS_VER_SUBMINOR);
  if (gethostname(host, sizeof host - 1) != 0) snprintf(host, sizeof host, "unknown");
  host[sizeof host - 1] = 0;
  put_field(f, "", "version", MSCALE_GIT_VERSION);
  put_field(f, "", "git_describe", MSCALE_GIT_DESCRIBE);
  put_field(f, "", "git_commit", MSCALE_GIT_COMMIT);
  fprintf(f, "build:\n");
  put_field(f, "  ", "type", MSCALE_BUILD_TYPE);
  put_field(f, "  ", "compiler", MSCALE_BUILD_COMPILER);
  put_field(f, "  ", "flags", MSCALE_BUILD_FLAGS);
  put_field(f, "  ", "cd_kernel", cd_kernel_name()); /* the SIMD kernels this CPU runs */
  fprintf(f, "libraries:\n");
  put_field(f, "  ", "mpi", mpi);
  put_field(f, "  ", "hdf5", h5);
  put_field(f, "  ", "sundials", SUNDIALS_VERSION);
  put_field(f, "  ", "metis", metis);
  put_field(f, "  ", "libyaml", dk_yaml_version());
  fprintf(f, "ranks: %d\nthreads: %d\n", ctx->size, par_max_threads());
  put_field(f, "", "host", host);
}
