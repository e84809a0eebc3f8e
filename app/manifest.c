/* SPDX-License-Identifier: MIT */
/* The manifest of a run directory: run_info.yaml lists every file the run wrote (`manifest:`),
 * so that a rerun with --force removes exactly the previous run's files first and readers
 * (tools/plot_run.py, python/mscale) take only the files of the last run (docs/output.md,
 * "Reruns"). The files a run wrote are found by comparing the directory before and after the
 * run: a file is the run's if it is new or if its inode, size or modification time changed (the
 * atomic writers rename a new file over the old one, so a rewritten file has a new inode). */
#include "commands.h"

#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

struct app_listing {
  size_t n, cap;
  char **names;
  struct stat *st;
};

static int cmp_str(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

static char *join(const char *dir, const char *name) {
  size_t len = strlen(dir) + strlen(name) + 2;
  char *p = ms_calloc(len, 1);
  snprintf(p, len, "%s/%s", dir, name);
  return p;
}

static void listing_add(app_listing *l, const char *name, const struct stat *st) {
  if (l->n == l->cap) {
    l->cap = l->cap ? 2 * l->cap : 64;
    char **names = ms_calloc(l->cap, sizeof *names);
    struct stat *st_new = ms_calloc(l->cap, sizeof *st_new);
    if (l->n)
      memcpy(names, l->names, l->n * sizeof *names), memcpy(st_new, l->st, l->n * sizeof *st);
    free(l->names);
    free(l->st);
    l->names = names;
    l->st = st_new;
  }
  l->names[l->n] = ms_strdup(name);
  l->st[l->n++] = *st;
}

app_listing *app_listing_take(const char *dir) {
  app_listing *l = ms_calloc(1, sizeof *l);
  DIR *d = opendir(dir);
  if (!d) return l; /* a directory still to be made: nothing in it */
  struct dirent *e;
  while ((e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    char *p = join(dir, e->d_name);
    struct stat st;
    if (lstat(p, &st) == 0 && S_ISREG(st.st_mode)) listing_add(l, e->d_name, &st);
    free(p);
  }
  closedir(d);
  return l;
}

void app_listing_free(app_listing **pl) {
  if (!pl || !*pl) return;
  for (size_t i = 0; i < (*pl)->n; i++) free((*pl)->names[i]);
  free((*pl)->names);
  free((*pl)->st);
  free(*pl);
  *pl = NULL;
}

static const struct stat *listing_find(const app_listing *l, const char *name) {
  for (size_t i = 0; i < l->n; i++)
    if (!strcmp(l->names[i], name)) return &l->st[i];
  return NULL;
}

static bool same_file(const struct stat *a, const struct stat *b) {
  return a->st_ino == b->st_ino && a->st_size == b->st_size &&
         a->st_mtim.tv_sec == b->st_mtim.tv_sec && a->st_mtim.tv_nsec == b->st_mtim.tv_nsec;
}

/* A name the manifest may hold: a plain file name of the directory (no path, no "..") */
static bool plain_name(const char *s) {
  return s && *s && strcmp(s, ".") && strcmp(s, "..") && !strchr(s, '/');
}

/* "2026-12-04T16:41:50Z" (run_info.yaml's `started`) as seconds since the epoch, -1 if not
 * (days from the civil date: the proleptic Gregorian count, March-based years) */
static long long parse_utc(const char *s) {
  int y, m, d, hh, mm, ss;
  if (!s || sscanf(s, "%d-%d-%dT%d:%d:%dZ", &y, &m, &d, &hh, &mm, &ss) != 6) return -1;
  y -= m <= 2;
  long long era = (y >= 0 ? y : y - 399) / 400, yoe = y - era * 400;
  long long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  long long days = era * 146097 + yoe * 365 + yoe / 4 - yoe / 100 + doy - 719468;
  return days * 86400 + hh * 3600 + mm * 60 + ss;
}

/* The previous run's files: its manifest; for a run_info.yaml without one (a run killed before
 * it ended, or written by a version without manifests) the files modified since it started. */
static app_listing *previous_files(const char *dir) {
  app_listing *prev = ms_calloc(1, sizeof *prev);
  char *info = join(dir, "run_info.yaml");
  struct stat st;
  if (stat(info, &st) != 0) {
    free(info);
    return prev;
  }
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load(info, &e);
  const dk_node *root = doc ? dk_root(doc) : NULL;
  const dk_node *man = dk_get(root, "manifest");
  if (man && dk_node_kind(man) == DK_SEQ) {
    for (size_t i = 0; i < dk_seq_len(man); i++) {
      const char *name = dk_scalar(dk_seq_at(man, i));
      char *p = plain_name(name) ? join(dir, name) : NULL;
      struct stat fs;
      if (p && lstat(p, &fs) == 0 && S_ISREG(fs.st_mode)) listing_add(prev, name, &fs);
      free(p);
    }
  } else if (root) {
    long long started = parse_utc(dk_scalar(dk_get(root, "started")));
    app_listing *all = app_listing_take(dir);
    for (size_t i = 0; started >= 0 && i < all->n; i++)
      if ((long long)all->st[i].st_mtim.tv_sec >= started)
        listing_add(prev, all->names[i], &all->st[i]);
    app_listing_free(&all);
  }
  dk_free(doc);
  dk_errors_free(&e);
  free(info);
  return prev;
}

app_listing *app_manifest_previous(const char *dir) { return previous_files(dir); }

/* The PNGs and PDFs tools/plot_run.py wrote under plots/, and the folder if then empty */
static size_t remove_plots(const char *dir) {
  char *plots = join(dir, "plots");
  size_t n = 0;
  DIR *d = opendir(plots);
  if (d) {
    struct dirent *e;
    while ((e = readdir(d))) {
      size_t len = strlen(e->d_name);
      if (len < 5 || (strcmp(e->d_name + len - 4, ".png") && strcmp(e->d_name + len - 4, ".pdf")))
        continue;
      char *p = join(plots, e->d_name);
      if (remove(p) == 0) n++;
      free(p);
    }
    closedir(d);
    rmdir(plots); /* fails, harmlessly, when something else is in it */
  }
  free(plots);
  return n;
}

ms_status app_manifest_clear(const char *dir, size_t *removed) {
  *removed = 0;
  app_listing *prev = previous_files(dir);
  ms_status s = MS_OK;
  for (size_t i = 0; i < prev->n; i++) {
    char *p = join(dir, prev->names[i]);
    if (remove(p) == 0) ++*removed;
    else if (errno != ENOENT) {
      fprintf(stderr, "mscale: --force: cannot remove '%s' of the previous run: %s\n", p,
              strerror(errno));
      s = MS_ERR_IO;
    }
    free(p);
  }
  app_listing_free(&prev);
  *removed += remove_plots(dir);
  return s;
}

void app_manifest_write(FILE *f, const char *dir, const app_listing *before,
                        const app_listing *keep) {
  app_listing *now = app_listing_take(dir);
  char **names = ms_calloc(now->n + 1, sizeof *names);
  size_t n = 0;
  for (size_t i = 0; i < now->n; i++) {
    const char *name = now->names[i];
    const struct stat *old = before ? listing_find(before, name) : NULL;
    bool written = !old || !same_file(old, &now->st[i]);
    if (!strcmp(name, "run_info.yaml.part")) continue; /* the file being written */
    if (written || (keep && listing_find(keep, name)) || !strcmp(name, "run_info.yaml"))
      names[n++] = now->names[i];
  }
  if (!listing_find(now, "run_info.yaml")) names[n++] = "run_info.yaml"; /* being written */
  qsort(names, n, sizeof *names, cmp_str);
  fprintf(f, "manifest:  # every file of this run (mscale run --force removes them first)\n");
  for (size_t i = 0; i < n; i++) {
    fputs("  - ", f);
    app_put_yaml_quoted(f, names[i]);
    fputc('\n', f);
  }
  free(names);
  app_listing_free(&now);
}
