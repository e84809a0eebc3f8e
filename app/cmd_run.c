/* mscale run DECK [-o OUTDIR] [--force]: validate, then run into OUTDIR, which receives the
 * resolved deck, run.log, run_info.yaml and the problem's data files. */
#include "commands.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

static void run_usage(FILE *f) {
  fprintf(f,
          "Usage: mscale run DECK [-o OUTDIR] [--force] [--quiet] [--verbose] [--restart FILE]\n\n"
          "  -o OUTDIR   output directory (default: out/<deck name>)\n"
          "  --force     allow writing into an OUTDIR that already holds results\n"
          "  --quiet     no progress line\n"
          "  --verbose   debug messages in the log\n"
          "  --restart FILE  continue from a checkpoint the same deck wrote (discrete_model,\n"
          "              cluster_dynamics, coupled one-way; docs/mpi.md)\n\n"
          "The deck is validated completely before anything runs (see `mscale check`).\n"
          "OUTDIR receives deck.resolved.yaml (defaults filled in), run.log, run_info.yaml and\n"
          "the problem's data (CSV with units headers, HDF5 + XDMF for ParaView).\n"
          "Problem types:\n");
  app_print_problem_types(f);
}

static char *default_outdir(const char *deck) {
  const char *base = strrchr(deck, '/');
  base = base ? base + 1 : deck;
  char *out = ms_calloc(strlen(base) + 8, 1);
  sprintf(out, "out/%s", base);
  char *dot = strrchr(out, '.');
  if (dot && dot > out + 4) *dot = 0;
  return out;
}

/* A YAML double-quoted scalar: the command line and paths may hold quotes, backslashes or
 * control characters, and run_info.yaml must still load (docs/reliability.md §6). */
static void put_quoted(FILE *f, const char *prefix, const char *s) {
  fputs(prefix, f);
  for (; *s; s++) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\') fprintf(f, "\\%c", c);
    else if (c < 0x20 || c == 0x7f) fprintf(f, "\\x%02x", c);
    else fputc(c, f);
  }
}

static void write_run_info(const ms_ctx *ctx, int argc, char **argv, const char *deck,
                           const char *started, ms_status s, double wall) {
  char *path = ms_out_path(ctx, "run_info.yaml");
  ms_afile af;
  if (ms_afile_open(&af, path) == MS_OK) {
    fprintf(af.f, "# What produced this run directory.\nprogram: mscale\nversion: %s\n",
            MSCALE_VERSION_STRING);
    fprintf(af.f, "command: \"");
    for (int i = 0; i < argc; i++) put_quoted(af.f, i ? " " : "mscale ", argv[i]);
    put_quoted(af.f, "\"\ndeck: \"", deck);
    fprintf(af.f, "\"\nranks: %d\nstarted: \"%s\"\n", ctx->size, started);
    fprintf(af.f, "status: %s\nstatus_message: \"%s\"\nwall_time_s: %.3f\n",
            s == MS_OK ? "completed" : "failed", ms_status_str(s), wall);
    ms_afile_commit(&af);
  }
  free(path);
}

int cmd_run(int argc, char **argv) {
  if (app_wants_help(argc, argv)) {
    run_usage(stdout);
    return 0;
  }
  const char *deck = NULL, *outdir_arg = NULL, *restart = NULL;
  bool force = false, quiet = false, verbose = false;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "-o") && i + 1 < argc) outdir_arg = argv[++i];
    else if (!strcmp(argv[i], "--restart") && i + 1 < argc) restart = argv[++i];
    else if (!strcmp(argv[i], "--force")) force = true;
    else if (!strcmp(argv[i], "--quiet")) quiet = true;
    else if (!strcmp(argv[i], "--verbose")) verbose = true;
    else if (argv[i][0] != '-' && !deck) deck = argv[i];
    else {
      fprintf(stderr, "mscale run: unexpected argument '%s'\n", argv[i]);
      run_usage(stderr);
      return 2;
    }
  }
  if (!deck) {
    run_usage(stderr);
    return 2;
  }
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.quiet = quiet;
  ctx.restart = restart;
  if (verbose) ctx.verbosity = MS_LOG_DEBUG;
  if (par_init(&argc, &argv, &ctx)) {
    fprintf(stderr, "mscale: cannot start MPI\n");
    return 1;
  }
  time_t now = time(NULL);
  char started[64];
  strftime(started, sizeof started, "%Y-%m-%dT%H:%M:%SZ", gmtime(&now));

  dk_errors e;
  dk_errors_init(&e);
  app_deck d;
  ms_status s = app_deck_read(deck, &d, &e);
  if (s) {
    if (ctx.rank == 0) {
      dk_errors_print(&e, stderr);
      fprintf(stderr, "%s: %zu error%s; nothing was run\n", deck, e.n, e.n == 1 ? "" : "s");
    }
  } else if (restart && !app_deck_restartable(&d)) {
    if (ctx.rank == 0)
      fprintf(stderr, "mscale run: --restart is not available for this deck's problem type "
                      "(discrete_model, cluster_dynamics and coupled write checkpoints)\n");
    s = MS_ERR_INPUT;
  } else {
    char *outdir = outdir_arg ? ms_strdup(outdir_arg) : default_outdir(deck);
    s = par_agree_status(ms_outdir_create(&ctx, outdir, force));
    free(outdir);
    if (!s) {
      char *resolved = ms_out_path(&ctx, "deck.resolved.yaml");
      if (ctx.rank == 0) s = dk_write_resolved(d.doc, resolved);
      free(resolved);
      s = par_agree_status(s);
    }
    if (!s) {
      ms_log(&ctx, MS_LOG_INFO, "mscale %s: running %s on %d rank%s into %s", MSCALE_VERSION_STRING,
             deck, ctx.size, ctx.size == 1 ? "" : "s", ctx.outdir);
      s = par_agree_status(app_deck_run(&ctx, &d));
      double wall = ms_wall_time() - ctx.wall_start;
      if (s)
        ms_log(&ctx, MS_LOG_ERROR, "run failed: %s (outputs so far are in %s)", ms_status_str(s),
               ctx.outdir);
      else ms_log(&ctx, MS_LOG_INFO, "run completed in %.2f s; outputs in %s", wall, ctx.outdir);
      if (ctx.rank == 0) write_run_info(&ctx, argc, argv, deck, started, s, wall);
    }
  }
  app_deck_free(&d);
  dk_errors_free(&e);
  ms_ctx_close(&ctx);
  par_finalize();
  return ms_exit_code(s);
}
