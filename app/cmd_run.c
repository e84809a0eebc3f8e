/* SPDX-License-Identifier: MIT */
/* mscale run DECK [-o OUTDIR] [--force]: validate, then run into OUTDIR, which receives the
 * resolved deck, run.log, run_info.yaml and the problem's data files. */
#include "commands.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void run_usage(FILE *f) {
  fprintf(f,
          "Usage: mscale run DECK [-o OUTDIR] [--force] [--quiet] [--verbose] [--restart FILE]\n"
          "                       [--continue] [--set PATH=VALUE]...\n\n"
          "  -o, --output=OUTDIR  output directory (default: out/<deck name>)\n"
          "  --force              write into an OUTDIR that already holds results, after\n"
          "                       removing the files of its previous run (run_info.yaml's\n"
          "                       manifest) and its plots/\n"
          "  --quiet              no progress line\n"
          "  --verbose            debug messages in the log\n"
          "  --restart=FILE       continue from a checkpoint the same deck wrote (discrete_model,\n"
          "                       cluster_dynamics, impact, coupled; docs/mpi.md)\n"
          "  --continue           continue in OUTDIR from its own last checkpoint (after an\n"
          "                       interrupt or a wall-time limit; docs/reliability.md)\n"
          "  --set PATH=VALUE     override a deck value before the deck is checked, e.g.\n"
          "                       --set continuum.time.end=0.1 --set materials[0].eos.gamma=1.4\n"
          "                       (repeatable; VALUE is YAML; recorded in run_info.yaml and\n"
          "                       deck.resolved.yaml)\n\n"
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

/* `prefix`, then s escaped for a YAML double-quoted scalar (app_put_yaml_escaped). */
static void put_quoted(FILE *f, const char *prefix, const char *s) {
  fputs(prefix, f);
  app_put_yaml_escaped(f, s);
}

/* The directory before the run and, for --continue, the previous run's files: what the
 * manifest is made of (app/manifest.c). */
typedef struct run_files {
  app_listing *before, *keep;
} run_files;

static void write_run_info(const ms_ctx *ctx, int argc, char **argv, const char *deck,
                           const char *const *sets, size_t nsets, const char *started, ms_status s,
                           double wall, const run_files *files) {
  char *path = ms_out_path(ctx, "run_info.yaml");
  ms_afile af;
  if (ms_afile_open(&af, path) == MS_OK) {
    fprintf(af.f, "# What produced this run directory.\nprogram: mscale\n");
    app_write_provenance(af.f, ctx);
    fprintf(af.f, "command: \"");
    for (int i = 0; i < argc; i++) put_quoted(af.f, i ? " " : "mscale ", argv[i]);
    put_quoted(af.f, "\"\ndeck: \"", deck);
    fprintf(af.f, "\"\noverrides:%s\n", nsets ? "" : " []");
    for (size_t i = 0; i < nsets; i++) put_quoted(af.f, "  - \"", sets[i]), fputs("\"\n", af.f);
    fprintf(af.f, "started: \"%s\"\n", started);
    /* s < 0: the run is under way (written when it starts) */
    const char *status = (int)s < 0            ? "running"
                         : s == MS_OK          ? "completed"
                         : s == MS_INTERRUPTED ? "interrupted"
                                               : "failed";
    fprintf(af.f, "status: %s\nstatus_message: \"%s\"\nwall_time_s: %.3f\n", status,
            (int)s < 0 ? "" : ms_status_str(s), wall);
    if ((int)s >= 0) app_manifest_write(af.f, ctx->outdir, files->before, files->keep);
    ms_afile_commit(&af);
  }
  free(path);
}

/* OUTDIR made or reused: --force removes the previous run's files first, so that reruns never
 * mix (docs/output.md); --continue keeps them in the manifest. Every rank calls it. */
static ms_status open_outdir(ms_ctx *ctx, const char *outdir, bool force, bool cont,
                             run_files *files) {
  size_t removed = 0;
  ms_status s = MS_OK;
  if (ctx->rank == 0) {
    if (cont) files->keep = app_manifest_previous(outdir);
    else if (force) s = app_manifest_clear(outdir, &removed);
    if (!s) files->before = app_listing_take(outdir);
  }
  s = par_agree_status(s);
  if (!s) s = par_agree_status(ms_outdir_create(ctx, outdir, force || cont));
  if (!s && removed)
    ms_log(ctx, MS_LOG_INFO, "--force: removed the %zu files of the previous run", removed);
  return s;
}

/* The run's last log line: completed, failed, or interrupted with how to go on (--continue from
 * the problem's checkpoint, or --force for a problem type that writes none). */
static void log_outcome(const ms_ctx *ctx, const app_deck *d, ms_status s, const char *deck,
                        double wall) {
  if (s == MS_INTERRUPTED && app_deck_restartable(d))
    ms_log(ctx, MS_LOG_WARN,
           "run interrupted (outputs so far are in %s; `mscale run %s -o %s --continue` "
           "goes on from the last checkpoint)",
           ctx->outdir, deck, ctx->outdir);
  else if (s == MS_INTERRUPTED) /* continuum, grid2d, ...: nothing to continue from */
    ms_log(ctx, MS_LOG_WARN,
           "run interrupted (outputs so far are in %s; this problem type writes no "
           "checkpoints: `mscale run %s -o %s --force` starts it again)",
           ctx->outdir, deck, ctx->outdir);
  else if (s)
    ms_log(ctx, MS_LOG_ERROR, "run failed: %s (outputs so far are in %s)", ms_status_str(s),
           ctx->outdir);
  else ms_log(ctx, MS_LOG_INFO, "run completed in %.2f s; outputs in %s", wall, ctx->outdir);
}

int cmd_run(int argc, char **argv) {
  /* the command line as given, for run_info.yaml (getopt_long permutes argv) */
  char **cmdline = ms_calloc((size_t)argc + 1, sizeof *cmdline);
  for (int i = 0; i < argc; i++) cmdline[i] = argv[i];
  const int cmdline_n = argc;
  const char *deck = NULL, *outdir_arg = NULL, *restart = NULL;
  const char **sets = ms_calloc((size_t)argc + 1, sizeof *sets);
  size_t nsets = 0;
  bool force = false, quiet = false, verbose = false, cont = false;
  enum { OPT_FORCE = 256, OPT_QUIET, OPT_VERBOSE, OPT_RESTART, OPT_SET, OPT_CONTINUE };
  static const struct option opts[] = {{"output", required_argument, NULL, 'o'},
                                       {"force", no_argument, NULL, OPT_FORCE},
                                       {"quiet", no_argument, NULL, OPT_QUIET},
                                       {"verbose", no_argument, NULL, OPT_VERBOSE},
                                       {"restart", required_argument, NULL, OPT_RESTART},
                                       {"set", required_argument, NULL, OPT_SET},
                                       {"continue", no_argument, NULL, OPT_CONTINUE},
                                       {"help", no_argument, NULL, 'h'},
                                       {NULL, 0, NULL, 0}};
  int rc = -1, c;
  opterr = 0;
  optind = 0; /* glibc: a full reset (tests call the commands in-process, repeatedly) */
  while (rc < 0 && (c = getopt_long(argc, argv, ":o:h", opts, NULL)) != -1) {
    const char *name = c == 'o' ? "-o" : c == OPT_RESTART ? "--restart" : "--set";
    if ((c == 'o' || c == OPT_RESTART || c == OPT_SET) &&
        app_option_value_missing("run", name, optarg))
      rc = 2;
    else if (c == 'o') outdir_arg = optarg;
    else if (c == OPT_RESTART) restart = optarg;
    else if (c == OPT_SET) sets[nsets++] = optarg;
    else if (c == OPT_FORCE) force = true;
    else if (c == OPT_CONTINUE) cont = true;
    else if (c == OPT_QUIET) quiet = true;
    else if (c == OPT_VERBOSE) verbose = true;
    else if (c == 'h') rc = 0, run_usage(stdout);
    else rc = app_option_error("run", c, optopt, argv[optind - 1], opts);
  }
  for (int i = optind; rc < 0 && i < argc; i++) {
    if (!deck) deck = argv[i];
    else {
      fprintf(stderr, "mscale run: unexpected argument '%s' (one deck per run)\n", argv[i]);
      rc = 2;
    }
  }
  if (rc < 0 && cont && restart) {
    fprintf(stderr, "mscale run: --continue takes the output directory's own checkpoint; give "
                    "it or --restart FILE, not both\n");
    rc = 2;
  }
  if (rc < 0 && !deck) {
    fprintf(stderr, "mscale run: no deck given\n\n");
    run_usage(stderr);
    rc = 2;
  }
  if (rc >= 0) {
    free(cmdline);
    free(sets);
    return rc;
  }
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  ctx.quiet = quiet;
  ctx.restart = restart;
  ctx.continuing = cont;
  char *continue_from = NULL; /* --continue: OUTDIR/<the problem's checkpoint> */
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
  run_files files = {NULL, NULL};
  ms_status s = app_deck_read_set(deck, sets, nsets, &d, &e);
  if (s) {
    if (ctx.rank == 0) {
      dk_errors_print(&e, stderr);
      fprintf(stderr, "%s: %zu error%s; nothing was run\n", deck, dk_errors_count(&e),
              dk_errors_count(&e) == 1 ? "" : "s");
    }
  } else if ((restart || cont) && !app_deck_restartable(&d)) {
    if (ctx.rank == 0)
      fprintf(stderr, "mscale run: --restart is not available for this deck's problem type "
                      "(discrete_model, cluster_dynamics, impact and coupled write checkpoints)\n");
    s = MS_ERR_INPUT;
  } else {
    char *outdir = outdir_arg ? ms_strdup(outdir_arg) : default_outdir(deck);
    if (cont) { /* the directory's own checkpoint, which must be there */
      size_t len = strlen(outdir) + strlen(app_deck_checkpoint_name(&d)) + 2;
      continue_from = ms_calloc(len, 1);
      snprintf(continue_from, len, "%s/%s", outdir, app_deck_checkpoint_name(&d));
      FILE *f = fopen(continue_from, "rb");
      if (f) fclose(f);
      else {
        if (ctx.rank == 0)
          fprintf(stderr, "mscale run: --continue: no checkpoint %s (the run wrote none yet?)\n",
                  continue_from);
        s = MS_ERR_INPUT;
      }
      ctx.restart = continue_from;
    }
    if (!s) s = open_outdir(&ctx, outdir, force, cont, &files);
    free(outdir);
    if (!s) {
      char *resolved = ms_out_path(&ctx, "deck.resolved.yaml");
      if (ctx.rank == 0) s = dk_write_resolved(d.doc, resolved);
      free(resolved);
      s = par_agree_status(s);
    }
    if (!s) {
      ms_log(&ctx, MS_LOG_INFO, "mscale %s: running %s on %d rank%s into %s", app_version(), deck,
             ctx.size, ctx.size == 1 ? "" : "s", ctx.outdir);
      if (ctx.rank == 0) /* status: running, until the run ends */
        write_run_info(&ctx, cmdline_n, cmdline, deck, sets, nsets, started, (ms_status)-1, 0.0,
                       &files);
      ms_interrupts_install();
      s = par_agree_status(app_deck_run(&ctx, &d));
      double wall = ms_wall_time() - ctx.wall_start;
      log_outcome(&ctx, &d, s, deck, wall);
      if (ctx.rank == 0)
        write_run_info(&ctx, cmdline_n, cmdline, deck, sets, nsets, started, s, wall, &files);
    }
  }
  app_deck_free(&d);
  dk_errors_free(&e);
  app_listing_free(&files.before);
  app_listing_free(&files.keep);
  free(continue_from);
  free(cmdline);
  free(sets);
  ms_ctx_close(&ctx);
  par_finalize();
  return ms_exit_code(s);
}
