/* SPDX-License-Identifier: MIT */
/* bench_dm_jets — the Richtmyer–Meshkov microjet sweep of the discrete model (jets.h;
 * docs/validation.md "Microjets"): spike-tip velocity vs k h0 at two resolutions, and the
 * arrested growth vs the yield stress.
 *
 *   bench_dm_jets [--deck D] [--material M] [--up U] [--kh0 LIST] [--ncol LIST] [--h H]
 *                 [--depth WL] [--obs WL] [--fit-from WL] [--dt-margin F]
 *                 [--yield LIST --shear-modulus G --strength-kh0 X --strength-ncol N]
 *                 [--strength-set NAME] [--visc-linear CL] [--hourglass CS] [--decay TAU]
 *                 [--spall-strength S] [--reference-update T]
 *                 [--trace] -o OUTDIR
 *
 * Defaults: inputs/eos-materials.yaml's pb, u_p 0.8 km/s (26.2 GPa, `mscale hugoniot`),
 * kh0 0.05,0.1,0.2,0.5,1,1.5, ncol 64,128 (spacings per wavelength), h 1e-4 cm, depth 1.5 λ,
 * obs 3 λ/U_s after breakout, fit from 1 λ/U_s, dt_margin 0.35; strength at kh0 0.5 and
 * ncol 64 with Y = 0 (none) and the --yield list, G from --shear-modulus. --strength-set NAME:
 * the k h0 sweep's cases with yield steinberg_guinan and that built-in set (Al6061_T6, Cu_OFHC,
 * Pb, Sn: particles/dm/dm_strength.c) instead of yield none. Diagnostics: --visc-linear CL
 * and --hourglass CS set the region's viscosity.linear and hourglass (defaults 0.5, 1);
 * --decay TAU drives with u_p exp(−t/τ), τ = TAU λ/U_s (default: held at u_p);
 * --spall-strength S adds fracture {model: mean_stress, spall_strength: S} (GPa; default none);
 * --reference-update T the region's reference_update {threshold: T} (per-family references,
 * families kept; default none; jets_kh0.csv's energy_err = |ΔE|/W shows the balance). Besides the
 * old tip measures, jets_kh0.csv has those of jets_tip.h (leading-mass fronts, jet cluster).
 * Writes OUTDIR/jets_kh0.csv and OUTDIR/jets_strength.csv (units in the headers), with
 * --trace the histories OUTDIR/trace_<kind>_<i>.csv and the final particle snapshots
 * OUTDIR/snap_<kind>_<i>.h5 (pressure, density); one line per case on stdout.
 * Plot: /usr/bin/python3 tools/plot_jets.py OUTDIR. Threads: OMP_NUM_THREADS. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "jets.h"

#define MAXL 32

static int parse_list(const char *s, double *v) {
  int n = 0;
  char *end;
  while (*s && n < MAXL) {
    v[n++] = strtod(s, &end);
    if (end == s) return -1;
    s = *end == ',' ? end + 1 : end;
  }
  return n;
}

typedef struct opts {
  const char *deck, *material, *outdir, *strength_set;
  double up, h, depth, obs, fit_from, fit_to, dt_margin, G, skh0, sobs, sdepth;
  double visc_linear, hourglass, decay; /* 0: the region's defaults, a held piston */
  double spall;                         /* > 0: fracture with this spall strength, GPa */
  double ref;                           /* > 0: reference_update {threshold: ref} */
  double kh0[MAXL], ncol[MAXL], Y[MAXL];
  int nk, nn, ny, trace;
  long sncol;
} opts;

static const char *const kh0_names[] = {"kh0",
                                        "ncol",
                                        "h",
                                        "lambda",
                                        "a0_over_h0",
                                        "up",
                                        "us",
                                        "du",
                                        "v_lin",
                                        "v_spike",
                                        "v_tip",
                                        "v_eta",
                                        "ratio",
                                        "v_spike_peak",
                                        "v_spike_late",
                                        "v_spike_max",
                                        "eta_end",
                                        "t_end",
                                        "stopped",
                                        "particles",
                                        "v_bubble",
                                        "v_spike_nl",
                                        "v_bubble_nl",
                                        "keta_start",
                                        "keta_end",
                                        "k_deta_end",
                                        "u_fs_start",
                                        "v_tip_slope",
                                        "v_front1",
                                        "v_front10",
                                        "v_front50",
                                        "v_lead1",
                                        "v_lead10",
                                        "v_lead50",
                                        "v_main",
                                        "m_jet_end",
                                        "n_jet_end",
                                        "n_clusters_end",
                                        "n_ahead_end",
                                        "tip_cluster_end",
                                        "visc_linear",
                                        "hourglass",
                                        "decay",
                                        "reference_update",
                                        "energy_err"};
static const char *const kh0_units[] = {
    "1",    "1",    "cm",   "cm",   "1",    "km/s", "km/s", "km/s", "km/s", "km/s",
    "km/s", "km/s", "1",    "km/s", "km/s", "km/s", "cm",   "10us", "1",    "particles",
    "km/s", "km/s", "km/s", "1",    "1",    "1",    "km/s", "km/s", "km/s", "km/s",
    "km/s", "km/s", "km/s", "km/s", "km/s", "1",    "1",    "1",    "1",    "1",
    "1",    "1",    "1",    "1",    "1"}; /* one per name (m_jet_end: rho0 h0 lambda) */
_Static_assert(sizeof kh0_units == sizeof kh0_names, "a unit per column");
static const char *const str_names[] = {
    "Y",        "G",         "kh0",      "ncol",   "lambda",         "du",      "v_lin", "eta_b",
    "deta_max", "t_eta_max", "arrested", "k_deta", "rho_v2_over_kY", "stopped", "t_end"};
static const char *const str_units[] = {"GPa", "GPa",  "1", "1", "cm", "km/s", "km/s", "cm",
                                        "cm",  "10us", "1", "1", "1",  "1",    "10us"};

static FILE *open_trace(const opts *o, const char *kind, int i) {
  if (!o->trace) return NULL;
  char path[1024];
  snprintf(path, sizeof path, "%s/trace_%s_%d.csv", o->outdir, kind, i);
  return fopen(path, "w");
}

static jets_case base_case(const opts *o, const eos_t *eos) {
  return (jets_case){.eos = eos,
                     .up = o->up,
                     .h = o->h,
                     .depth_wl = o->depth,
                     .obs_wl = o->obs,
                     .fit_from = o->fit_from,
                     .fit_to = o->fit_to,
                     .dt_margin = o->dt_margin,
                     .G = o->G,
                     .strength_set = o->strength_set,
                     .visc_linear = o->visc_linear,
                     .hourglass = o->hourglass,
                     .decay = o->decay,
                     .spall_strength = o->spall,
                     .ref_threshold = o->ref};
}

static int sweep_kh0(const opts *o, const eos_t *eos) {
  char path[1024];
  snprintf(path, sizeof path, "%s/jets_kh0.csv", o->outdir);
  ms_afile af;
  if (ms_afile_open(&af, path) != MS_OK) return 1;
  ms_csv_header(
      af.f,
      "Richtmyer-Meshkov spike velocity vs kh0 (discrete model, bench_dm_jets; v_spike = slope "
      "of x_valley - x_fs, v_eta of (x_valley - x_peak)/2, v_lin = k a0 (1 - up/Us) du)",
      sizeof kh0_names / sizeof *kh0_names, kh0_names, kh0_units);
  int i = 0;
  for (int a = 0; a < o->nn; a++)
    for (int b = 0; b < o->nk; b++, i++) {
      jets_case c = base_case(o, eos);
      c.ncol = (long)o->ncol[a], c.kh0 = o->kh0[b];
      jets_result r;
      FILE *tr = open_trace(o, "kh0", i);
      char snap[1024];
      snprintf(snap, sizeof snap, "%s/snap_kh0_%d.h5", o->outdir, i);
      c.snapshot = o->trace ? snap : NULL;
      ms_status st = jets_run(&c, &r, tr, 10);
      if (tr) fclose(tr);
      if (st != MS_OK) {
        fprintf(stderr, "case kh0 %g ncol %ld: set-up failed (%s) %s\n", c.kh0, c.ncol,
                ms_status_str(st), r.err);
        continue;
      }
      const double row[] = {c.kh0,
                            (double)c.ncol,
                            c.h,
                            r.lambda,
                            r.a0 / r.h0,
                            c.up,
                            r.us,
                            r.du,
                            r.v_lin,
                            r.v_spike,
                            r.v_tip,
                            r.v_eta,
                            r.v_spike / r.v_lin,
                            r.v_spike_peak,
                            r.v_spike_late,
                            r.v_spike_max,
                            0.5 * r.spike_len,
                            r.t_end,
                            r.status,
                            (double)r.particles,
                            r.v_bubble,
                            r.v_spike_nl,
                            r.v_bubble_nl,
                            r.keta_fit0,
                            r.keta_fit1,
                            r.k * r.deta_end,
                            r.u_fs_b,
                            r.v_tip_slope,
                            r.v_front[0],
                            r.v_front[1],
                            r.v_front[2],
                            r.v_lead[0],
                            r.v_lead[1],
                            r.v_lead[2],
                            r.v_main,
                            r.m_jet_end,
                            (double)r.n_jet_end,
                            (double)r.n_clusters_end,
                            (double)r.n_ahead_end,
                            (double)r.tip_cluster_end,
                            c.visc_linear,
                            c.hourglass,
                            c.decay,
                            c.ref_threshold,
                            r.energy_err};
      ms_csv_row(af.f, sizeof row / sizeof *row, row);
      fflush(af.f);
      printf("kh0 %-5g ncol %-4ld a0/h0 %.3f du %.4f v_lin %.4f v_spike %.4f (ratio %.3f) "
             "peak %.4f late %.4f max %.4f v_tip %.4f v_eta %.4f eta_b %.3g eta_end %.3g  %ld "
             "particles, %ld "
             "steps%s%s\n",
             c.kh0, c.ncol, r.a0 / r.h0, r.du, r.v_lin, r.v_spike, r.v_spike / r.v_lin,
             r.v_spike_peak, r.v_spike_late, r.v_spike_max, r.v_tip, r.v_eta, r.eta_b,
             0.5 * r.spike_len, r.particles, r.steps, r.status ? "; STOPPED: " : "",
             r.status ? r.err : "");
      printf(
          "    second order [VelikovichDimonte1996]: spike %.4f vs eta*(1+k eta) %.4f (%+.1f %%), "
          "bubble %.4f vs %.4f; k eta %.3f -> %.3f, k deta %.3f; tip u_fs + spike %.4f km/s\n",
          r.v_spike, r.v_spike_nl, 100 * (r.v_spike / r.v_spike_nl - 1), r.v_bubble, r.v_bubble_nl,
          r.keta_fit0, r.keta_fit1, r.k * r.deta_end, r.du + r.v_spike);
      printf("    tip measures (absolute, km/s): foremost particle %.4f; leading-mass fronts "
             "(0.01, 0.1, 0.5 rho0 h0 lambda) %.4f %.4f %.4f, their mean velocities %.4f %.4f "
             "%.4f; jet cluster's front %.4f; u_fs %.4f at the window's start\n"
             "    at the window's end: jet %.3f rho0 h0 lambda (%ld particles), %ld clusters, %ld "
             "particles ahead of the jet cluster, the foremost particle's cluster %ld; energy "
             "|dE|/W %.2e\n",
             r.v_tip_slope, r.v_front[0], r.v_front[1], r.v_front[2], r.v_lead[0], r.v_lead[1],
             r.v_lead[2], r.v_main, r.u_fs_b, r.m_jet_end, r.n_jet_end, r.n_clusters_end,
             r.n_ahead_end, r.tip_cluster_end, r.energy_err);
      fflush(stdout);
    }
  return ms_afile_commit(&af) == MS_OK ? 0 : 1;
}

static int sweep_strength(const opts *o, const eos_t *eos) {
  char path[1024];
  snprintf(path, sizeof path, "%s/jets_strength.csv", o->outdir);
  ms_afile af;
  if (ms_afile_open(&af, path) != MS_OK) return 1;
  ms_csv_header(af.f,
                "Richtmyer-Meshkov growth arrested by strength (discrete model, bench_dm_jets; "
                "deta_max = max eta - eta at breakout, eta = (x_spike - x_bubble)/2)",
                sizeof str_names / sizeof *str_names, str_names, str_units);
  double v_lin0 = NAN; /* the strength-free growth rate (the first case, Y = 0) */
  for (int b = -1; b < o->ny; b++) {
    jets_case c = base_case(o, eos);
    c.ncol = o->sncol, c.kh0 = o->skh0, c.Y = b < 0 ? 0.0 : o->Y[b], c.obs_wl = o->sobs;
    c.depth_wl = o->sdepth;
    jets_result r;
    FILE *tr = open_trace(o, "Y", b + 1);
    char snap[1024];
    snprintf(snap, sizeof snap, "%s/snap_Y_%d.h5", o->outdir, b + 1);
    c.snapshot = o->trace ? snap : NULL;
    ms_status st = jets_run(&c, &r, tr, 10);
    if (tr) fclose(tr);
    if (st != MS_OK) {
      fprintf(stderr, "case Y %g: set-up failed (%s) %s\n", c.Y, ms_status_str(st), r.err);
      continue;
    }
    if (b < 0) v_lin0 = r.v_lin;
    /* ρ0 η̇0² / (k Y) with η̇0 the strength-free impulsive rate (Y in GPa = g/(cm·(10µs)²)) */
    const double scale = c.Y > 0 ? eos_rho0(eos) * v_lin0 * v_lin0 / c.Y : NAN;
    const double row[] = {
        c.Y,        c.G,         c.kh0,      (double)c.ncol,   r.lambda, r.du,     r.v_lin, r.eta_b,
        r.deta_max, r.t_eta_max, r.arrested, r.k * r.deta_max, scale,    r.status, r.t_end};
    ms_csv_row(af.f, sizeof row / sizeof *row, row);
    fflush(af.f);
    printf("Y %-5g kh0 %g ncol %ld du %.4f v_lin %.4f eta_b %.4g deta_max %.4g (k deta %.4f) at "
           "%.4g after breakout, %s; rho v^2/(kY) k = %.4g%s%s\n",
           c.Y, c.kh0, c.ncol, r.du, r.v_lin, r.eta_b, r.deta_max, r.k * r.deta_max, r.t_eta_max,
           r.arrested ? "arrested" : "still growing", scale, r.status ? "; STOPPED: " : "",
           r.status ? r.err : "");
    fflush(stdout);
  }
  return ms_afile_commit(&af) == MS_OK ? 0 : 1;
}

int main(int argc, char **argv) {
  opts o = {.deck = MSCALE_JETS_DECK,
            .material = "pb",
            .up = 0.8,
            .h = 1e-4,
            .depth = 1.5,
            .obs = 3.0,
            .fit_from = 1.0,
            .fit_to = 3.0,
            .sobs = 5.5,
            .sdepth = 3.0,
            .dt_margin = 0.35,
            .G = 8.6,
            .skh0 = 0.5,
            .sncol = 64};
  o.nk = parse_list("0.05,0.1,0.2,0.5,1,1.5", o.kh0);
  o.nn = parse_list("64,128", o.ncol);
  o.ny = 0;
  bool do_kh0 = true;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    if (!strcmp(a, "--help")) {
      printf("usage: see the head of bench/dm_jets/bench_dm_jets.c\n");
      return 0;
    }
    if (!strcmp(a, "--trace")) {
      o.trace = 1;
      continue;
    }
    if (!strcmp(a, "--no-kh0")) {
      do_kh0 = false;
      continue;
    }
    if (!v) {
      fprintf(stderr, "bench_dm_jets: %s needs a value\n", a);
      return 2;
    }
    i++;
    if (!strcmp(a, "--deck")) o.deck = v;
    else if (!strcmp(a, "--material")) o.material = v;
    else if (!strcmp(a, "-o")) o.outdir = v;
    else if (!strcmp(a, "--up")) o.up = atof(v);
    else if (!strcmp(a, "--h")) o.h = atof(v);
    else if (!strcmp(a, "--depth")) o.depth = atof(v);
    else if (!strcmp(a, "--obs")) o.obs = atof(v);
    else if (!strcmp(a, "--fit-from")) o.fit_from = atof(v);
    else if (!strcmp(a, "--fit-to")) o.fit_to = atof(v);
    else if (!strcmp(a, "--strength-obs")) o.sobs = atof(v);
    else if (!strcmp(a, "--strength-depth")) o.sdepth = atof(v);
    else if (!strcmp(a, "--dt-margin")) o.dt_margin = atof(v);
    else if (!strcmp(a, "--strength-set")) o.strength_set = v;
    else if (!strcmp(a, "--visc-linear")) o.visc_linear = atof(v);
    else if (!strcmp(a, "--hourglass")) o.hourglass = atof(v);
    else if (!strcmp(a, "--decay")) o.decay = atof(v);
    else if (!strcmp(a, "--spall-strength")) o.spall = atof(v);
    else if (!strcmp(a, "--reference-update")) o.ref = atof(v);
    else if (!strcmp(a, "--shear-modulus")) o.G = atof(v);
    else if (!strcmp(a, "--strength-kh0")) o.skh0 = atof(v);
    else if (!strcmp(a, "--strength-ncol")) o.sncol = atol(v);
    else if (!strcmp(a, "--kh0")) o.nk = parse_list(v, o.kh0);
    else if (!strcmp(a, "--ncol")) o.nn = parse_list(v, o.ncol);
    else if (!strcmp(a, "--yield")) o.ny = parse_list(v, o.Y);
    else {
      fprintf(stderr, "bench_dm_jets: unknown option %s\n", a);
      return 2;
    }
  }
  if (!o.outdir || o.nk < 0 || o.nn < 0 || o.ny < 0) {
    fprintf(stderr, "bench_dm_jets: give -o OUTDIR (and well-formed lists)\n");
    return 2;
  }
  if (mkdir(o.outdir, 0777) != 0 && errno != EEXIST) {
    perror(o.outdir);
    return 2;
  }
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load(o.deck, &e);
  eos_materials *mats = doc ? eos_materials_read(doc, &e) : NULL;
  const eos_material *m = mats ? eos_materials_find(mats, o.material, &e, doc, NULL) : NULL;
  if (e.n || !m) {
    dk_errors_print(&e, stderr);
    return 2;
  }
  int rc = do_kh0 ? sweep_kh0(&o, m->eos) : 0;
  if (o.ny > 0) rc |= sweep_strength(&o, m->eos);
  eos_materials_destroy(&mats);
  dk_free(doc);
  dk_errors_free(&e);
  return rc;
}
