/* SPDX-License-Identifier: MIT */
/* Check-time memory estimate (core.h, "Check-time memory estimate"). */
#include "core.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <unistd.h>

void ms_mem_init(ms_mem_estimate *m) { memset(m, 0, sizeof *m); }

void ms_mem_free(ms_mem_estimate *m) {
  free(m->item);
  memset(m, 0, sizeof *m);
}

void ms_mem_format(double bytes, char *buf, size_t n) {
  static const char *const unit[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int k = 0;
  while (bytes >= 1024 && k < 6) bytes /= 1024, k++;
  snprintf(buf, n, k ? "%.3g %s" : "%.0f %s", bytes, unit[k]);
}

void ms_mem_add(ms_mem_estimate *m, const dk_node *at, const char *what, double count,
                double bytes_each) {
  if (!(count >= 0) || !(bytes_each >= 0)) return;
  if (m->n == m->cap) {
    m->cap = m->cap ? 2 * m->cap : 8;
    m->item = ms_realloc(m->item, m->cap, sizeof *m->item);
  }
  ms_mem_item *it = &m->item[m->n++];
  char each[32];
  ms_mem_format(bytes_each, each, sizeof each);
  snprintf(it->what, sizeof it->what, "%s: %.3g x %s", what, count, each);
  it->line = at ? dk_node_line(at) : 0;
  it->col = at ? dk_node_col(at) : 0;
  it->bytes = count * bytes_each;
  m->total += it->bytes;
}

/* A byte count with an optional K/M/G/T suffix (powers of 1024); NAN if malformed. */
static double parse_bytes(const char *s) {
  char *end;
  double v = strtod(s, &end);
  if (end == s || !(v >= 0)) return NAN;
  while (*end == ' ') end++;
  const char *suffix = "KMGT";
  const char *p = *end ? strchr(suffix, *end >= 'a' ? *end - 32 : *end) : NULL;
  if (p) {
    v *= pow(1024.0, (double)(p - suffix + 1));
    end++;
    if (*end == 'i' || *end == 'I') end++;
    if (*end == 'B' || *end == 'b') end++;
  }
  while (*end == ' ' || *end == '\n') end++;
  return *end ? NAN : v;
}

static double read_limit_file(const char *path) {
  FILE *f = fopen(path, "r");
  if (!f) return INFINITY;
  char buf[64] = "";
  double v = INFINITY;
  if (fgets(buf, sizeof buf, f) && strncmp(buf, "max", 3) != 0) {
    double x = parse_bytes(buf);
    if (x > 0) v = x;
  }
  fclose(f);
  return v;
}

double ms_mem_limit(void) {
  double limit = INFINITY;
  long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) limit = (double)pages * (double)page;
  limit = fmin(limit, read_limit_file("/sys/fs/cgroup/memory.max"));
  limit = fmin(limit, read_limit_file("/sys/fs/cgroup/memory/memory.limit_in_bytes"));
  struct rlimit rl;
  if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
    limit = fmin(limit, (double)rl.rlim_cur);
  const char *env = getenv("MSCALE_MEMORY_LIMIT");
  if (env && env[0]) {
    double v = parse_bytes(env);
    if (v > 0) limit = fmin(limit, v);
  }
  return limit;
}

bool ms_mem_check(const ms_mem_estimate *m, double limit, int nranks, int ranks_per_node,
                  dk_errors *e, const dk_doc *doc) {
  if (nranks < 1) nranks = 1;
  if (ranks_per_node < 1) ranks_per_node = 1;
  if (ranks_per_node > nranks) ranks_per_node = nranks;
  double per_node = m->total / nranks * ranks_per_node;
  if (!(per_node > limit)) return true;
  /* the three largest items, largest first */
  size_t top[3] = {0, 0, 0};
  int ntop = 0;
  for (int k = 0; k < 3 && (size_t)k < m->n; k++) {
    size_t best = m->n;
    for (size_t i = 0; i < m->n; i++) {
      bool taken = false;
      for (int j = 0; j < ntop; j++) taken |= top[j] == i;
      if (!taken && (best == m->n || m->item[i].bytes > m->item[best].bytes)) best = i;
    }
    top[ntop++] = best;
  }
  char total[32], node[32], lim[32], parts[600] = "";
  ms_mem_format(m->total, total, sizeof total);
  ms_mem_format(per_node, node, sizeof node);
  ms_mem_format(limit, lim, sizeof lim);
  for (int j = 0; j < ntop; j++) {
    const ms_mem_item *it = &m->item[top[j]];
    char b[32];
    ms_mem_format(it->bytes, b, sizeof b);
    size_t len = strlen(parts);
    snprintf(parts + len, sizeof parts - len, "%s%s = %s", j ? "; " : "", it->what, b);
  }
  const ms_mem_item *big = ntop ? &m->item[top[0]] : NULL;
  char where[96] = "";
  if (nranks > 1)
    snprintf(where, sizeof where, " (%d ranks, %d per node: %s per node)", nranks, ranks_per_node,
             node);
  dk_error_at(e, dk_file(doc), big ? big->line : 0, big ? big->col : 0,
              "the run would need about %s of memory%s, but %s is available (largest: %s); "
              "reduce the problem, or set MSCALE_MEMORY_LIMIT if the limit is wrong",
              total, where, lim, parts);
  return false;
}
