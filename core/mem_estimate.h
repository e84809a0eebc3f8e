/* mem_estimate.h — check-time memory estimate (issue 8, "resource limits"; docs/reliability.md).
 *
 * Proposal by the reliability helper, to be merged into core.h when the lead wires it: problem
 * readers add their large arrays while they read the deck (count x bytes per item, located at
 * the deck node that sets the count); `mscale check` and `mscale run` then compare the total
 * with the memory this process may use and reject the deck with exit 2 and an estimate, before
 * anything is allocated — instead of letting the OOM killer end the run.
 *
 * Counts are doubles: a deck may ask for 1e12 particles, which must not overflow on the way
 * to the message.
 */
#ifndef MSCALE_MEM_ESTIMATE_H
#define MSCALE_MEM_ESTIMATE_H

#include "core.h"

typedef struct ms_mem_item {
  char what[128]; /* e.g. "continuum.layers[0].cells: 1e+12 cells x 136 B" */
  int line, col;  /* deck position of the node that sets the count (0: none) */
  double bytes;
} ms_mem_item;

typedef struct ms_mem_estimate {
  size_t n, cap;
  ms_mem_item *item;
  double total; /* bytes, whole run (all ranks together) */
} ms_mem_estimate;

void ms_mem_init(ms_mem_estimate *m);
void ms_mem_free(ms_mem_estimate *m);
/* Add `count` items of `bytes_each` bytes, described by `what` (e.g. "cells"), counted at deck
 * node `at` (may be NULL). Negative or NaN counts are ignored (the reader reports those). */
void ms_mem_add(ms_mem_estimate *m, const dk_node *at, const char *what, double count,
                double bytes_each);
/* Bytes this process may use: the smallest of physical memory, the cgroup limit (v2
 * memory.max or v1 memory.limit_in_bytes), RLIMIT_AS and the environment variable
 * MSCALE_MEMORY_LIMIT (bytes, or with a K/M/G/T suffix). INFINITY if none is known. */
double ms_mem_limit(void);
/* Compare the estimate, shared over `nranks` ranks on `ranks_per_node` ranks per node (1, 1
 * for a serial run), with `limit` bytes per node. If it does not fit, records one error at the
 * largest item naming the total, the three largest items and the limit, and returns false. */
bool ms_mem_check(const ms_mem_estimate *m, double limit, int nranks, int ranks_per_node,
                  dk_errors *e, const dk_doc *doc);
/* "1.5 GiB" style text for a byte count. */
void ms_mem_format(double bytes, char *buf, size_t n);

#endif
