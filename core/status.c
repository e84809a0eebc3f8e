/* SPDX-License-Identifier: MIT */
/* Status codes (one list) and the exit-code mapping of docs/design.md §8; checked allocation. */
#include "core.h"

#include <signal.h>
#include <stdio.h>

#include <stdlib.h>
#include <string.h>

const char *ms_status_str(ms_status s) {
  switch (s) {
  case MS_OK:
    return "success";
  case MS_ERR_INPUT:
    return "bad input";
  case MS_ERR_IO:
    return "input/output error";
  case MS_ERR_NOMEM:
    return "out of memory";
  case MS_ERR_UNSTABLE:
    return "the run went unstable";
  case MS_ERR_SOLVER:
    return "a solver did not converge";
  case MS_ERR_INTERNAL:
    return "internal error";
  case MS_INTERRUPTED:
    return "interrupted";
  }
  return "unknown status";
}

int ms_exit_code(ms_status s) {
  if (s == MS_OK) return 0;
  if (s == MS_ERR_INPUT) return 2;
  return 1;
}

static void out_of_memory(size_t bytes) {
  fprintf(stderr, "mscale: out of memory (allocating %zu bytes)\n", bytes);
  abort();
}

void *ms_calloc(size_t n, size_t size) {
  if (n == 0 || size == 0) n = size = 1;
  void *p = calloc(n, size);
  if (!p) out_of_memory(n * size);
  return p;
}

void *ms_aligned_alloc(size_t n, size_t size) {
  size_t bytes = n * size;
  if (size != 0 && bytes / size != n) out_of_memory(SIZE_MAX);
  bytes = (bytes + 63) / 64 * 64;
  if (bytes == 0) bytes = 64;
  void *p = aligned_alloc(64, bytes);
  if (!p) out_of_memory(bytes);
  memset(p, 0, bytes);
  return p;
}

void *ms_realloc(void *p, size_t n, size_t size) {
  size_t bytes = n * size;
  if (size != 0 && bytes / size != n) out_of_memory(SIZE_MAX);
  void *q = realloc(p, bytes ? bytes : 1);
  if (!q) out_of_memory(bytes);
  return q;
}

char *ms_strdup(const char *s) {
  size_t n = strlen(s) + 1;
  char *d = ms_calloc(n, 1);
  memcpy(d, s, n);
  return d;
}

void ms_must(ms_status st, const char *what) {
  if (st == MS_OK) return;
  fprintf(stderr, "mscale: internal error: %s failed (%s)\n", what, ms_status_str(st));
  abort();
}

static volatile sig_atomic_t interrupt_flag = 0;

static void on_signal(int sig) {
  (void)sig;
  interrupt_flag = 1;
}

void ms_interrupts_install(void) {
  struct sigaction sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sa.sa_flags = SA_RESETHAND; /* a second signal takes the default action: the process ends */
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, NULL);
  sigaction(SIGTERM, &sa, NULL);
}

bool ms_interrupt_requested(void) { return interrupt_flag != 0; }

bool ms_interrupt_agreed(const ms_ctx *ctx) {
  int stop = interrupt_flag != 0;
  return ctx->size > 1 ? par_max_int(stop) != 0 : stop;
}
