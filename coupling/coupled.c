/* SPDX-License-Identifier: MIT */
/* coupled.c — the `coupled` problem (docs/input-coupled.md, docs/coupling.md §6): a Lagrangian
 * grid computes the loading, a particle region represents the sample near its free surface,
 * fragments are found in it, feel the gas's drag and are transported to a detector. The drive
 * is one-way (coupled_one_way.c: the grid first, its tag history then drives the particles) or
 * two-way (coupled_two_way.c: grid and particles in lock-step). The files are listed in
 * coupled_impl.h. */
#include "coupled_impl.h"

#include <string.h>

/* The particle model's notes on the deck (deprecated key names), one log line each. */
static void log_notes(const ms_ctx *ctx, const cpl_problem *p) {
  const char *s = ptl_region_params_notes(p->region);
  while (*s) {
    size_t n = strcspn(s, "\n");
    ms_log(ctx, MS_LOG_WARN, "%.*s", (int)n, s);
    s += n + (s[n] == '\n');
  }
}

ms_status cpl_problem_run(ms_ctx *ctx, cpl_problem *p) {
  log_notes(ctx, p);
  return p->drive_mode == DRIVE_TWO_WAY ? cpl_run_two_way(ctx, p) : cpl_run_one_way(ctx, p);
}
