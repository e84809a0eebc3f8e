/* SPDX-License-Identifier: MIT */
/* mscale spectrum SNAPSHOT.h5 [--bond B]: the fragment spectrum N(g) of a particle snapshot as
 * CSV on stdout (header `g,count,mass`), docs/design.md §8. Snapshot layout: docs/coupling.md. */
#include "commands.h"
#include "cpl.h"

#include <getopt.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Default bond factor b: the cluster-dynamics cutoff R_c = 1.2 a of the benchmark
 * (docs/design.md §5.1), so fragments are the components of the interacting-pair graph. */
#define SPECTRUM_DEFAULT_BOND 1.2

static void spectrum_usage(FILE *f) {
  fprintf(f,
          "Usage: mscale spectrum SNAPSHOT.h5 [--bond B] [--spacing A] [--rho0 RHO]\n"
          "                       [--period PX,PY,PZ] [--fragments FILE]\n\n"
          "Fragment spectrum of a particle snapshot: particles i, k are bonded when\n"
          "|r_i - r_k| <= B*A; fragments are the connected components. Prints CSV on stdout:\n"
          "'#' comment lines (title, units), then the header g,count,mass and one row per\n"
          "fragment size g (clusters) with the number of fragments and their total mass [g].\n\n"
          "Options:\n"
          "  --bond B          bond factor b (default %.1f, the cluster-dynamics cutoff)\n"
          "  --spacing A       lattice spacing a [cm]; default: attribute r0 of /particles\n"
          "  --rho0 RHO        reference density [g/cm^3] for equivalent diameters in\n"
          "                    --fragments; default: attribute rho0 of /particles if present\n"
          "  --period PX,PY,PZ periodic box lengths [cm] (0 = open axis); default: attributes\n"
          "                    period_x/y/z (and lo_x/y/z) of /particles if present, else open\n"
          "  --fragments FILE  also write the per-fragment table (id,count,mass,d,x,y,z,vx,vy,\n"
          "                    vz,rg) to FILE\n\n"
          "Snapshot datasets: /particles/x [n][3] cm, /particles/mass [n] g, optional\n"
          "/particles/v [n][3] km/s and /particles/gid [n] (distinct global ids: fragments\n"
          "are then numbered by their smallest gid, so a snapshot of an MPI run, stored in\n"
          "rank order, gives the same table as a serial one) (docs/coupling.md). Exit 0 ok,\n"
          "1 I/O failure, 2 bad usage or a bad snapshot (missing dataset, wrong shape,\n"
          "non-finite value, repeated gid).\n",
          SPECTRUM_DEFAULT_BOND);
}

/* Parse a positive finite number; false otherwise. */
static bool parse_positive(const char *s, double *out) {
  char *end;
  double v = strtod(s, &end);
  if (end == s || *end || !isfinite(v) || !(v > 0)) return false;
  *out = v;
  return true;
}

static bool parse_triple(const char *s, double out[3]) {
  char *end;
  for (int k = 0; k < 3; k++) {
    out[k] = strtod(s, &end);
    if (end == s || !isfinite(out[k]) || out[k] < 0) return false;
    if (k < 2) {
      if (*end != ',') return false;
      s = end + 1;
    }
  }
  return *end == 0;
}

typedef struct snapshot {
  size_t n;
  double *x, *y, *z, *vx, *vy, *vz, *mass;
  int64_t *gid; /* /particles/gid if present: fragments numbered by smallest gid */
} snapshot;

static void snapshot_free(snapshot *s) {
  free(s->gid);
  free(s->x);
  free(s->y);
  free(s->z);
  free(s->vx);
  free(s->vy);
  free(s->vz);
  free(s->mass);
}

static int cmp_gid(const void *a, const void *b) {
  int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return x < y ? -1 : x > y;
}

/* Optional /particles/gid (cluster-dynamics snapshots; a run on MPI ranks stores its particles
 * in rank order): [n] distinct integers >= 0. With it, fragment ids follow the smallest gid, so
 * the table does not depend on the storage order (docs/mpi.md "Fragments on MPI ranks"). */
static bool gid_read(ms_h5r *h, const char *path, snapshot *s, dk_errors *e) {
  size_t ng = 0, ncol = 0;
  if (ms_h5_read_ints_rows(h, "/particles/gid", 0, SIZE_MAX, &s->gid, &ng, &ncol, e) != MS_OK)
    return false;
  const char *bad = NULL;
  if (ng != s->n || ncol != 1) bad = "must have one integer per particle";
  int64_t *sorted = ms_calloc(ng + 1, sizeof *sorted);
  memcpy(sorted, s->gid, ng * sizeof *sorted);
  qsort(sorted, ng, sizeof *sorted, cmp_gid);
  for (size_t i = 0; i < ng && !bad; i++)
    if (sorted[i] < 0 || (i > 0 && sorted[i] == sorted[i - 1]))
      bad = "must hold distinct integers >= 0";
  free(sorted);
  if (bad) dk_error_at(e, path, 0, 0, "dataset '/particles/gid' (%zu x %zu) %s", ng, ncol, bad);
  return bad == NULL;
}

/* Read and check the datasets; every problem goes to e (naming the file). */
static ms_status snapshot_read(ms_h5r *h, const char *path, snapshot *s, dk_errors *e) {
  memset(s, 0, sizeof *s);
  double *xyz = NULL, *vel = NULL, *m = NULL;
  size_t nx = 0, cx = 0, nv = 0, cv = 0, nm = 0, cm = 0;
  ms_status st = ms_h5_read_doubles(h, "/particles/x", &xyz, &nx, &cx, e);
  ms_status sm = ms_h5_read_doubles(h, "/particles/mass", &m, &nm, &cm, e);
  bool have_v = ms_h5_exists(h, "/particles/v");
  ms_status sv = have_v ? ms_h5_read_doubles(h, "/particles/v", &vel, &nv, &cv, e) : MS_OK;
  bool ok = st == MS_OK && sm == MS_OK && sv == MS_OK;
  if (st == MS_OK && cx != 2 && cx != 3) {
    dk_error_at(e, path, 0, 0,
                "dataset '/particles/x' must have shape [n][3] (or [n][2]), not [%zu][%zu]", nx,
                cx);
    ok = false;
  }
  if (sm == MS_OK && cm != 1) {
    dk_error_at(e, path, 0, 0, "dataset '/particles/mass' must have shape [n], not [%zu][%zu]", nm,
                cm);
    ok = false;
  }
  if (st == MS_OK && sm == MS_OK && nm != nx) {
    dk_error_at(e, path, 0, 0,
                "'/particles/mass' has %zu entries but '/particles/x' has %zu particles", nm, nx);
    ok = false;
  }
  if (have_v && sv == MS_OK && st == MS_OK && (nv != nx || (cv != 2 && cv != 3))) {
    dk_error_at(e, path, 0, 0, "dataset '/particles/v' must have shape [%zu][3], not [%zu][%zu]",
                nx, nv, cv);
    ok = false;
  }
  if (ok) {
    size_t n = nx;
    s->n = n;
    s->x = ms_calloc(n + 1, sizeof(double));
    s->y = ms_calloc(n + 1, sizeof(double));
    s->z = ms_calloc(n + 1, sizeof(double));
    s->vx = ms_calloc(n + 1, sizeof(double));
    s->vy = ms_calloc(n + 1, sizeof(double));
    s->vz = ms_calloc(n + 1, sizeof(double));
    s->mass = ms_calloc(n + 1, sizeof(double));
    size_t bad_x = 0, bad_v = 0, bad_m = 0, first_x = 0, first_v = 0, first_m = 0;
    for (size_t i = 0; i < n; i++) {
      s->x[i] = xyz[i * cx];
      s->y[i] = xyz[i * cx + 1];
      s->z[i] = cx == 3 ? xyz[i * cx + 2] : 0.0;
      if (!isfinite(s->x[i]) || !isfinite(s->y[i]) || !isfinite(s->z[i])) {
        if (!bad_x++) first_x = i;
      }
      if (vel) {
        s->vx[i] = vel[i * cv];
        s->vy[i] = vel[i * cv + 1];
        s->vz[i] = cv == 3 ? vel[i * cv + 2] : 0.0;
        if (!isfinite(s->vx[i]) || !isfinite(s->vy[i]) || !isfinite(s->vz[i])) {
          if (!bad_v++) first_v = i;
        }
      }
      s->mass[i] = m[i];
      if (!isfinite(m[i]) || !(m[i] > 0)) {
        if (!bad_m++) first_m = i;
      }
    }
    if (bad_x) {
      dk_error_at(
          e, path, 0, 0,
          "'/particles/x': %zu particle(s) with a non-finite position (first: particle %zu)", bad_x,
          first_x);
      ok = false;
    }
    if (bad_v) {
      dk_error_at(
          e, path, 0, 0,
          "'/particles/v': %zu particle(s) with a non-finite velocity (first: particle %zu)", bad_v,
          first_v);
      ok = false;
    }
    if (bad_m) {
      dk_error_at(e, path, 0, 0,
                  "'/particles/mass': %zu particle(s) with a mass that is not a positive number "
                  "(first: particle %zu)",
                  bad_m, first_m);
      ok = false;
    }
  }
  free(xyz);
  free(vel);
  free(m);
  if (ok && ms_h5_exists(h, "/particles/gid") && !gid_read(h, path, s, e)) ok = false;
  return ok ? MS_OK : MS_ERR_INPUT;
}

/* What the command line left open, from the snapshot's attributes: the lattice spacing (r0),
 * the reference density (rho0), the periods and box origin. False if one is invalid (in e). */
static bool snapshot_attrs(ms_h5r *h, const char *path, double *spacing, double *rho0,
                           double period[3], cpl_fragment_opts *o, dk_errors *e) {
  bool ok = true;
  /* lattice spacing: command line, else the snapshot's r0 attribute */
  if (isnan(*spacing)) {
    double v;
    if (ms_h5_read_attr_double(h, "/particles", "r0", &v, NULL) == MS_OK ||
        ms_h5_read_attr_double(h, "/", "r0", &v, NULL) == MS_OK) {
      *spacing = v;
      if (!(isfinite(v) && v > 0)) {
        dk_error_at(e, path, 0, 0,
                    "attribute r0 (lattice spacing) must be a positive length, not %g", v);
        ok = false;
      }
    } else {
      dk_error_at(
          e, path, 0, 0,
          "no lattice spacing: the attribute r0 of '/particles' is missing (give --spacing A)");
      ok = false;
    }
  }
  if (isnan(*rho0)) {
    double v;
    if (ms_h5_read_attr_double(h, "/particles", "rho0", &v, NULL) == MS_OK && v > 0) *rho0 = v;
  }
  static const char *const pnames[3] = {"period_x", "period_y", "period_z"};
  static const char *const lnames[3] = {"lo_x", "lo_y", "lo_z"};
  for (int k = 0; k < 3; k++) {
    double v = 0;
    if (isnan(period[k]))
      period[k] = ms_h5_read_attr_double(h, "/particles", pnames[k], &v, NULL) == MS_OK ? v : 0;
    if (ms_h5_read_attr_double(h, "/particles", lnames[k], &v, NULL) == MS_OK) o->box.lo[k] = v;
    if (!(period[k] >= 0) || !isfinite(period[k])) {
      dk_error_at(e, path, 0, 0, "attribute %s must be >= 0 (0 = open axis)", pnames[k]);
      ok = false;
    }
  }
  return ok;
}

int cmd_spectrum(int argc, char **argv) {
  const char *path = NULL, *table_path = NULL;
  double bond = SPECTRUM_DEFAULT_BOND, spacing = NAN, rho0 = NAN;
  double period[3] = {NAN, NAN, NAN};
  enum { OPT_BOND = 256, OPT_SPACING, OPT_RHO0, OPT_PERIOD, OPT_FRAGMENTS };
  static const struct option opts[] = {{"bond", required_argument, NULL, OPT_BOND},
                                       {"spacing", required_argument, NULL, OPT_SPACING},
                                       {"rho0", required_argument, NULL, OPT_RHO0},
                                       {"period", required_argument, NULL, OPT_PERIOD},
                                       {"fragments", required_argument, NULL, OPT_FRAGMENTS},
                                       {"help", no_argument, NULL, 'h'},
                                       {NULL, 0, NULL, 0}};
  int c;
  opterr = 0;
  optind = 0; /* glibc: a full reset (tests call the commands in-process, repeatedly) */
  while ((c = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
    if (c == ':' || c == '?')
      return app_option_error("spectrum", c, optopt, argv[optind - 1], opts);
    if (c == 'h') {
      spectrum_usage(stdout);
      return 0;
    }
    const char *a = optarg;
    if (c == OPT_BOND && !parse_positive(a, &bond)) {
      fprintf(stderr, "mscale spectrum: --bond needs a positive number, not '%s'\n", a);
      return 2;
    } else if (c == OPT_SPACING && !parse_positive(a, &spacing)) {
      fprintf(stderr, "mscale spectrum: --spacing needs a positive length in cm, not '%s'\n", a);
      return 2;
    } else if (c == OPT_RHO0 && !parse_positive(a, &rho0)) {
      fprintf(stderr, "mscale spectrum: --rho0 needs a positive density, not '%s'\n", a);
      return 2;
    } else if (c == OPT_PERIOD && !parse_triple(a, period)) {
      fprintf(stderr, "mscale spectrum: --period needs PX,PY,PZ (cm, >= 0), not '%s'\n", a);
      return 2;
    } else if (c == OPT_FRAGMENTS) {
      if (app_option_value_missing("spectrum", "--fragments", a)) return 2;
      table_path = a;
    }
  }
  for (int i = optind; i < argc; i++) {
    if (!path) path = argv[i];
    else {
      fprintf(stderr, "mscale spectrum: more than one snapshot given ('%s', '%s')\n", path,
              argv[i]);
      return 2;
    }
  }
  if (!path) {
    spectrum_usage(stderr);
    return 2;
  }

  dk_errors e;
  dk_errors_init(&e);
  ms_h5r *h = ms_h5_open_read(path, &e);
  snapshot s;
  memset(&s, 0, sizeof s);
  ms_status st = h ? snapshot_read(h, path, &s, &e) : MS_ERR_INPUT;
  cpl_fragment_opts o;
  memset(&o, 0, sizeof o);
  if (h && !snapshot_attrs(h, path, &spacing, &rho0, period, &o, &e)) st = MS_ERR_INPUT;
  o.bond = bond;
  o.spacing = spacing;
  o.rho0 = isnan(rho0) ? 0.0 : rho0;
  for (int k = 0; k < 3; k++) o.box.period[k] = period[k] > 0 ? period[k] : 0.0;
  if (st == MS_OK)
    for (int k = 0; k < 3; k++)
      if (o.box.period[k] > 0 && !(2 * bond * spacing < o.box.period[k])) {
        dk_error_at(&e, path, 0, 0,
                    "bond length b*a = %g cm is not below half the period %g cm of axis %c",
                    bond * spacing, o.box.period[k], "xyz"[k]);
        st = MS_ERR_INPUT;
      }
  if (h) ms_h5_close_read(h);

  int rc = 0;
  if (st != MS_OK) {
    dk_errors_print(&e, stderr);
    rc = 2;
  } else {
    cpl_particles p = {s.n, s.x, s.y, s.z, s.vx, s.vy, s.vz, s.mass, NULL, s.gid};
    cpl_fragments f;
    cpl_fragments_init(&f);
    st = cpl_fragments_find(&f, &p, &o);
    if (st != MS_OK) {
      fprintf(stderr, "%s: the fragment search refused the snapshot (%s)\n", path,
              ms_status_str(st));
      rc = ms_exit_code(st);
    } else {
      char title[1024];
      snprintf(title, sizeof title,
               "fragment spectrum N(g) of %s: %zu particles, %zu fragments, bond b*a = %g*%g cm",
               path, s.n, f.n, bond, spacing);
      cpl_write_spectrum(stdout, &f, title);
      if (fflush(stdout) != 0) rc = 1;
      if (table_path) {
        ms_afile af;
        if (ms_afile_open(&af, table_path) != MS_OK) {
          fprintf(stderr, "mscale spectrum: cannot write '%s'\n", table_path);
          rc = 1;
        } else {
          cpl_write_fragment_table(af.f, &f, NULL);
          if (ms_afile_commit(&af) != MS_OK) {
            fprintf(stderr, "mscale spectrum: cannot write '%s'\n", table_path);
            rc = 1;
          }
        }
      }
    }
    cpl_fragments_free(&f);
  }
  snapshot_free(&s);
  dk_errors_free(&e);
  return rc;
}
