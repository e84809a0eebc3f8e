/* SPDX-License-Identifier: MIT */
/* Atomic files: write "<path>.part", rename to <path> when complete. */
#include "core.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

ms_status ms_afile_open(ms_afile *af, const char *path) {
  memset(af, 0, sizeof *af);
  af->path = ms_strdup(path);
  af->tmp_path = ms_calloc(strlen(path) + 6, 1);
  sprintf(af->tmp_path, "%s.part", path);
  af->f = fopen(af->tmp_path, "w");
  if (!af->f) {
    fprintf(stderr, "mscale: cannot write '%s': %s\n", af->tmp_path, strerror(errno));
    free(af->path);
    free(af->tmp_path);
    memset(af, 0, sizeof *af);
    return MS_ERR_IO;
  }
  return MS_OK;
}

ms_status ms_afile_commit(ms_afile *af) {
  ms_status s = MS_OK;
  if (!af->f) return MS_ERR_IO;
  ms_csv_forget(af->f);
  bool bad = ferror(af->f) != 0;
  if (fclose(af->f) != 0 || bad) {
    fprintf(stderr, "mscale: error writing '%s'\n", af->tmp_path);
    remove(af->tmp_path);
    s = MS_ERR_IO;
  } else if (rename(af->tmp_path, af->path) != 0) {
    fprintf(stderr, "mscale: cannot rename '%s' to '%s': %s\n", af->tmp_path, af->path,
            strerror(errno));
    s = MS_ERR_IO;
  }
  free(af->path);
  free(af->tmp_path);
  memset(af, 0, sizeof *af);
  return s;
}

void ms_afile_abort(ms_afile *af) {
  if (af->f) {
    ms_csv_forget(af->f);
    fclose(af->f);
    remove(af->tmp_path);
  }
  free(af->path);
  free(af->tmp_path);
  memset(af, 0, sizeof *af);
}
