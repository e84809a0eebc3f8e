/* SPDX-License-Identifier: MIT */
/* Progress: an updating line with ETA on a terminal, plain log lines otherwise. */
#include "core.h"

#include <unistd.h>

void ms_progress_start(ms_progress *p, const ms_ctx *ctx, const char *what, double t_start,
                       double t_end) {
  p->ctx = ctx;
  p->what = what;
  p->t_start = t_start;
  p->t_end = t_end;
  p->wall_start = p->wall_last = ms_wall_time();
  p->log_interval_s = 10.0;
  p->tty = ctx->rank == 0 && !ctx->quiet && isatty(STDERR_FILENO);
  p->active = true;
}

static void format_seconds(char *buf, size_t n, double s) {
  if (s < 0 || s != s) snprintf(buf, n, "--");
  else if (s < 120) snprintf(buf, n, "%.0fs", s);
  else if (s < 7200)
    snprintf(buf, n, "%.0fm%02.0fs", (double)(long)(s / 60), s - 60 * (double)(long)(s / 60));
  else snprintf(buf, n, "%.1fh", s / 3600);
}

void ms_progress_update(ms_progress *p, double t, long step) {
  if (!p->active) return;
  double now = ms_wall_time();
  double interval = p->tty ? 0.25 : p->log_interval_s;
  if (now - p->wall_last < interval) return;
  p->wall_last = now;
  double span = p->t_end - p->t_start;
  double frac = span > 0 ? (t - p->t_start) / span : 1.0;
  if (frac < 0) frac = 0;
  if (frac > 1) frac = 1;
  double elapsed = now - p->wall_start;
  double eta = frac > 1e-6 ? elapsed * (1 - frac) / frac : -1;
  char e1[32], e2[32];
  format_seconds(e1, sizeof e1, elapsed);
  format_seconds(e2, sizeof e2, eta);
  if (p->tty) {
    fprintf(stderr, "\r%s: %5.1f%%  step %ld  t = %.4g %s  elapsed %s  ETA %s   ", p->what,
            100 * frac, step, ms_out_time(t), ms_out_time_label(), e1, e2);
    fflush(stderr);
  } else {
    ms_log(p->ctx, MS_LOG_INFO, "%s: %.1f%% step %ld t = %.6g %s elapsed %s ETA %s", p->what,
           100 * frac, step, ms_out_time(t), ms_out_time_label(), e1, e2);
  }
}

void ms_progress_finish(ms_progress *p, double t, long step) {
  if (!p->active) return;
  if (p->tty) fprintf(stderr, "\r%*s\r", 100, "");
  char e1[32];
  format_seconds(e1, sizeof e1, ms_wall_time() - p->wall_start);
  ms_log(p->ctx, MS_LOG_INFO, "%s: done, %ld steps to t = %.6g %s in %s", p->what, step,
         ms_out_time(t), ms_out_time_label(), e1);
  p->active = false;
}
