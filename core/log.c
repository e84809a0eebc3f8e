/* SPDX-License-Identifier: MIT */
/* Logging, the run context and output directories. */
#include "core.h"

#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

double ms_wall_time(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void ms_ctx_init_serial(ms_ctx *ctx) {
  memset(ctx, 0, sizeof *ctx);
  ctx->rank = 0;
  ctx->size = 1;
  ctx->verbosity = MS_LOG_INFO;
  ctx->outdir = ms_strdup("");
  ctx->quiet = true;
  ctx->wall_start = ms_wall_time();
}

void ms_ctx_close(ms_ctx *ctx) {
  if (ctx->log_file) fclose(ctx->log_file);
  ctx->log_file = NULL;
  free(ctx->outdir);
  ctx->outdir = NULL;
}

static const char *level_name[] = {"error", "warning", "info", "debug"};

void ms_log(const ms_ctx *ctx, ms_log_level level, const char *fmt, ...) {
  if (level > ctx->verbosity) return;
  char msg[2048];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  double t = ms_wall_time() - ctx->wall_start;
  if (ctx->rank == 0 || level == MS_LOG_ERROR) {
    if (level <= MS_LOG_WARN) fprintf(stderr, "mscale: %s: %s\n", level_name[level], msg);
    else fprintf(stderr, "[%8.2fs] %s\n", t, msg);
  }
  if (ctx->log_file) {
    fprintf(ctx->log_file, "[%8.2fs] %s%s%s\n", t, level <= MS_LOG_WARN ? level_name[level] : "",
            level <= MS_LOG_WARN ? ": " : "", msg);
    fflush(ctx->log_file);
  }
}

char *ms_out_path(const ms_ctx *ctx, const char *name) {
  const char *dir = ctx->outdir ? ctx->outdir : "";
  size_t n = strlen(dir) + strlen(name) + 2;
  char *p = ms_calloc(n, 1);
  if (dir[0]) snprintf(p, n, "%s/%s", dir, name);
  else snprintf(p, n, "%s", name);
  return p;
}

static bool dir_is_empty(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return true;
  struct dirent *ent;
  bool empty = true;
  while ((ent = readdir(d))) {
    if (strcmp(ent->d_name, ".") && strcmp(ent->d_name, "..")) {
      empty = false;
      break;
    }
  }
  closedir(d);
  return empty;
}

/* mkdir -p */
static int make_dirs(const char *path) {
  char *p = ms_strdup(path);
  for (char *s = p + 1; *s; s++) {
    if (*s == '/') {
      *s = 0;
      if (mkdir(p, 0755) && errno != EEXIST) {
        free(p);
        return -1;
      }
      *s = '/';
    }
  }
  int rc = (mkdir(p, 0755) && errno != EEXIST) ? -1 : 0;
  free(p);
  return rc;
}

ms_status ms_outdir_create(ms_ctx *ctx, const char *dir, bool force) {
  struct stat st;
  if (ctx->rank == 0) {
    if (stat(dir, &st) == 0) {
      if (!S_ISDIR(st.st_mode)) {
        fprintf(stderr, "mscale: output path '%s' exists and is not a directory\n", dir);
        return MS_ERR_INPUT;
      }
      if (!dir_is_empty(dir) && !force) {
        fprintf(stderr,
                "mscale: output directory '%s' already holds results; choose another with -o "
                "or pass --force to overwrite them\n",
                dir);
        return MS_ERR_INPUT;
      }
    } else if (make_dirs(dir)) {
      fprintf(stderr, "mscale: cannot create output directory '%s': %s\n", dir, strerror(errno));
      return MS_ERR_IO;
    }
  }
  free(ctx->outdir);
  ctx->outdir = ms_strdup(dir);
  if (ctx->rank == 0) {
    char *log = ms_out_path(ctx, "run.log");
    ctx->log_file = fopen(log, ctx->continuing ? "a" : "w"); /* --continue: the log goes on */
    free(log);
    if (!ctx->log_file) {
      fprintf(stderr, "mscale: cannot write run.log in '%s'\n", dir);
      return MS_ERR_IO;
    }
  }
  return MS_OK;
}
