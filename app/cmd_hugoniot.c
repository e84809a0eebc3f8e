/* SPDX-License-Identifier: MIT */
/* mscale hugoniot DECK --material NAME --up LIST: shock Hugoniot of a deck material as CSV on
 * stdout (docs/design.md §8); --mixture for the Kuropatenko rule (docs/eos.md). Only the deck's
 * `units:`, `materials:` and `mixtures:` are read; other sections are left alone. */
#include "commands.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void hugoniot_usage(FILE *f) {
  fprintf(f, "Usage: mscale hugoniot DECK --material NAME --up LIST [--rho0 X] [--e0 Y]\n"
             "       mscale hugoniot DECK --mixture MIX --up LIST\n\n"
             "Solves the Rankine-Hugoniot jump conditions for the EOS of material NAME of DECK\n"
             "and prints CSV on stdout: '#' comment lines with the title and units, then the\n"
             "header up,Us,P,rho,e (km/s, km/s, GPa, g/cm^3, kJ/g) and one row per up.\n\n"
             "Options:\n"
             "  --material NAME   a material of the deck's materials: list\n"
             "  --up LIST         particle velocities in km/s (> 0): '0.5,1,2' or a range\n"
             "                    'FIRST:LAST:COUNT' (COUNT evenly spaced values)\n"
             "  --rho0 X          initial density, g/cm^3 (default: the EOS's rho0)\n"
             "  --e0 Y            initial specific internal energy, kJ/g (default: the EOS's\n"
             "                    reference e0: 0 for condensed matter, p0/((gamma-1) rho0)\n"
             "                    for an ideal gas)\n"
             "  --mixture MIX     Kuropatenko mixture: the name of an entry of the deck's\n"
             "                    mixtures: list, or 'NAME:ALPHA,NAME:ALPHA,...' with volume\n"
             "                    fractions ALPHA (sum 1) of deck materials. Components start\n"
             "                    from their reference states (rho0_i, e0_i).\n"
             "  -h, --help        this text\n\n"
             "Exit codes: 0 success, 1 a point has no solution (e.g. outside a table),\n"
             "2 bad usage or bad deck (messages DECK:LINE:COL: ...).\n");
}

static bool parse_number(const char *s, double *out) {
  char *end;
  errno = 0;
  double v = strtod(s, &end);
  if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v)) return false;
  *out = v;
  return true;
}

/* "a,b,c" or "first:last:count". Returns a malloc'd list or NULL with a message. */
static double *parse_up_list(const char *s, size_t *n) {
  *n = 0;
  char *copy = ms_strdup(s);
  double *up = NULL;
  char *b = strchr(copy, ':');
  if (b) {
    char *a = copy, *c = NULL;
    *b++ = '\0';
    if ((c = strchr(b, ':')) != NULL) *c++ = '\0';
    double first, last, count;
    if (!c || !parse_number(a, &first) || !parse_number(b, &last) || !parse_number(c, &count) ||
        count < 1 || count != floor(count) || count > 1e6) {
      fprintf(stderr,
              "mscale hugoniot: --up '%s': expected FIRST:LAST:COUNT with an integer "
              "COUNT >= 1\n",
              s);
      free(copy);
      return NULL;
    }
    *n = (size_t)count;
    up = ms_calloc(*n, sizeof *up);
    for (size_t i = 0; i < *n; ++i)
      up[i] = *n == 1 ? first : first + (last - first) * (double)i / (double)(*n - 1);
  } else {
    size_t cap = 8;
    up = ms_calloc(cap, sizeof *up);
    for (char *tok = strtok(copy, ", "); tok; tok = strtok(NULL, ", ")) {
      double v;
      if (!parse_number(tok, &v)) {
        fprintf(stderr, "mscale hugoniot: --up: expected a number, found '%s'\n", tok);
        free(up), free(copy);
        *n = 0;
        return NULL;
      }
      if (*n == cap) up = ms_realloc(up, cap *= 2, sizeof *up);
      up[(*n)++] = v;
    }
  }
  free(copy);
  if (*n == 0) {
    fprintf(stderr, "mscale hugoniot: --up: the list is empty\n");
    free(up);
    return NULL;
  }
  for (size_t i = 0; i < *n; ++i)
    if (!(up[i] > 0.0)) {
      fprintf(stderr, "mscale hugoniot: --up: particle velocities must be > 0 km/s, found %g\n",
              up[i]);
      free(up);
      *n = 0;
      return NULL;
    }
  return up;
}

static void list_materials(const eos_materials *mats, FILE *f) {
  for (size_t i = 0; i < mats->n; ++i) fprintf(f, "%s%s", i ? ", " : "", mats->m[i].name);
  if (mats->n == 0) fprintf(f, "none");
}

/* Inline mixture "a:0.3,b:0.7" -> components and volume fractions. */
static bool parse_inline_mixture(const char *spec, const eos_materials *mats, size_t *ncomp,
                                 const eos_t ***comp, double **alpha) {
  char *copy = ms_strdup(spec);
  size_t cap = 4, n = 0;
  *comp = ms_calloc(cap, sizeof **comp);
  *alpha = ms_calloc(cap, sizeof **alpha);
  bool ok = true;
  for (char *tok = strtok(copy, ","); tok && ok; tok = strtok(NULL, ",")) {
    char *colon = strrchr(tok, ':');
    double a;
    if (!colon || !parse_number(colon + 1, &a) || !(a >= 0.0 && a <= 1.0)) {
      fprintf(stderr,
              "mscale hugoniot: --mixture: expected NAME:ALPHA with 0 <= ALPHA <= 1, "
              "found '%s'\n",
              tok);
      ok = false;
      break;
    }
    *colon = '\0';
    const eos_material *m = eos_materials_find(mats, tok, NULL, NULL, NULL);
    if (!m) {
      fprintf(stderr, "mscale hugoniot: --mixture: unknown material '%s' (known: ", tok);
      list_materials(mats, stderr);
      fprintf(stderr, ")\n");
      ok = false;
      break;
    }
    if (n == cap) {
      cap *= 2;
      *comp = ms_realloc(*comp, cap, sizeof **comp);
      *alpha = ms_realloc(*alpha, cap, sizeof **alpha);
    }
    (*comp)[n] = m->eos;
    (*alpha)[n] = a;
    ++n;
  }
  free(copy);
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) sum += (*alpha)[i];
  if (ok && (n == 0 || fabs(sum - 1.0) > 1e-6)) {
    fprintf(stderr, "mscale hugoniot: --mixture: volume fractions must add up to 1, found %g\n",
            sum);
    ok = false;
  }
  *ncomp = n;
  return ok;
}

/* The Hugoniot of deck material `material` from (rho0, e0) (NaN: the EOS's reference state)
 * into pts, its CSV title into title. Returns 0, or the exit code 2 with a message. */
static int material_hugoniot(const eos_materials *mats, const char *deck, const char *material,
                             double rho0_opt, double e0_opt, size_t nup, const double *up,
                             eos_hugoniot_point *pts, char *title, size_t tlen, ms_status *st) {
  const eos_material *m = eos_materials_find(mats, material, NULL, NULL, NULL);
  if (!m) {
    fprintf(stderr, "mscale hugoniot: %s has no material '%s' (known: ", deck, material);
    list_materials(mats, stderr);
    fprintf(stderr, ")\n");
    return 2;
  }
  double rho0 = isnan(rho0_opt) ? eos_rho0(m->eos) : rho0_opt;
  double e0 = isnan(e0_opt) ? eos_e0(m->eos) : e0_opt;
  double p0 = eos_pressure(m->eos, rho0, e0);
  if (!isfinite(p0)) {
    fprintf(stderr,
            "mscale hugoniot: the initial state rho0 = %g g/cm^3, e0 = %g kJ/g is "
            "outside the domain of the EOS of '%s'\n",
            rho0, e0, material);
    return 2;
  }
  snprintf(title, tlen,
           "Shock Hugoniot of %s (%s EOS) from rho0 = %.10g g/cm^3, e0 = %.10g kJ/g, "
           "P0 = %.10g GPa (mscale %s)",
           m->name, eos_kind_name(eos_get_kind(m->eos)), rho0, e0, p0, MSCALE_VERSION_STRING);
  *st = eos_hugoniot(m->eos, rho0, e0, nup, up, pts);
  return 0;
}

/* The Kuropatenko Hugoniot of `mixture` (a mixtures: entry or NAME:ALPHA,...) into pts, its
 * CSV title into title. Returns 0, or the exit code 2 with a message. */
static int mixture_hugoniot(const eos_materials *mats, const char *deck, const char *mixture,
                            size_t nup, const double *up, eos_hugoniot_point *pts, char *title,
                            size_t tlen, ms_status *st) {
  size_t ncomp = 0;
  const eos_t **comp = NULL;
  double *alpha = NULL;
  const eos_mixture *mx = eos_mixtures_find(mats, mixture);
  char desc[700] = "";
  bool ok = true;
  if (mx) {
    ncomp = mx->ncomp;
    comp = ms_calloc(ncomp, sizeof *comp);
    alpha = ms_calloc(ncomp, sizeof *alpha);
    for (size_t i = 0; i < ncomp; ++i) {
      comp[i] = mats->m[mx->comp[i]].eos;
      alpha[i] = mx->alpha[i];
    }
  } else if (strchr(mixture, ':')) {
    ok = parse_inline_mixture(mixture, mats, &ncomp, &comp, &alpha);
  } else {
    fprintf(stderr,
            "mscale hugoniot: %s has no mixture '%s' (give a mixtures: entry or "
            "NAME:ALPHA,NAME:ALPHA)\n",
            deck, mixture);
    ok = false;
  }
  if (!ok) {
    free(comp), free(alpha);
    return 2;
  }
  for (size_t i = 0; i < ncomp; ++i) {
    const char *cname = "?";
    for (size_t k = 0; k < mats->n; ++k)
      if (mats->m[k].eos == comp[i]) cname = mats->m[k].name;
    size_t len = strlen(desc);
    snprintf(desc + len, sizeof desc - len, "%s%s %.6g", i ? ", " : "", cname, alpha[i]);
  }
  snprintf(title, tlen,
           "Kuropatenko mixture Hugoniot, 1/(D-u) = sum alpha_i/(D_i-u_i), volume fractions: "
           "%s (mscale %s)",
           desc, MSCALE_VERSION_STRING);
  *st = eos_kuropatenko_hugoniot(ncomp, comp, alpha, nup, up, pts);
  free(comp), free(alpha);
  return 0;
}

int cmd_hugoniot(int argc, char **argv) {
  if (app_wants_help(argc, argv)) {
    hugoniot_usage(stdout);
    return 0;
  }
  const char *deck = NULL, *material = NULL, *up_spec = NULL, *mixture = NULL;
  const char *rho0_s = NULL, *e0_s = NULL;
  for (int i = 1; i < argc; ++i) {
    const char *a = argv[i];
    const char **target = NULL;
    const char *value = NULL;
    static const struct {
      const char *opt;
      int slot;
    } opts[] = {{"--material", 0}, {"--up", 1}, {"--mixture", 2}, {"--rho0", 3}, {"--e0", 4}};
    const char **slots[] = {&material, &up_spec, &mixture, &rho0_s, &e0_s};
    for (size_t k = 0; k < sizeof opts / sizeof opts[0]; ++k) {
      size_t len = strlen(opts[k].opt);
      if (strncmp(a, opts[k].opt, len) == 0 && (a[len] == '\0' || a[len] == '=')) {
        target = slots[opts[k].slot];
        if (a[len] == '=') value = a + len + 1;
        else if (i + 1 < argc) value = argv[++i];
        break;
      }
    }
    if (target) {
      if (!value) {
        fprintf(stderr, "mscale hugoniot: option %s needs a value\n\n", a);
        hugoniot_usage(stderr);
        return 2;
      }
      *target = value;
    } else if (a[0] == '-' && a[1] != '\0') {
      fprintf(stderr, "mscale hugoniot: unknown option '%s'\n\n", a);
      hugoniot_usage(stderr);
      return 2;
    } else if (!deck) {
      deck = a;
    } else {
      fprintf(stderr, "mscale hugoniot: unexpected argument '%s' (one DECK only)\n\n", a);
      hugoniot_usage(stderr);
      return 2;
    }
  }
  if (!deck || !up_spec || (!material && !mixture) || (material && mixture)) {
    fprintf(stderr, "mscale hugoniot: need DECK, --up and exactly one of --material or "
                    "--mixture\n\n");
    hugoniot_usage(stderr);
    return 2;
  }
  double rho0_opt = NAN, e0_opt = NAN;
  if ((rho0_s && (!parse_number(rho0_s, &rho0_opt) || !(rho0_opt > 0.0))) ||
      (e0_s && !parse_number(e0_s, &e0_opt))) {
    fprintf(stderr, "mscale hugoniot: --rho0 must be a number > 0 and --e0 a number\n");
    return 2;
  }
  if (mixture && (rho0_s || e0_s)) {
    fprintf(stderr, "mscale hugoniot: --rho0/--e0 apply to --material only (mixture components "
                    "start from their reference states)\n");
    return 2;
  }
  size_t nup;
  double *up = parse_up_list(up_spec, &nup);
  if (!up) return 2;

  /* The deck: only units, materials and mixtures. */
  dk_errors e;
  dk_errors_init(&e);
  dk_doc *doc = dk_load(deck, &e);
  eos_materials *mats = NULL;
  if (doc) {
    dk_read_units(doc, &e);
    mats = eos_materials_read(doc, &e);
  }
  int rc = 0;
  if (e.n > 0 || !mats) {
    dk_errors_print(&e, stderr);
    fprintf(stderr, "%s: %zu error%s\n", deck, dk_errors_count(&e),
            dk_errors_count(&e) == 1 ? "" : "s");
    rc = 2;
    goto done;
  }

  static const char *const names[] = {"up", "Us", "P", "rho", "e"};
  static const char *const units[] = {"km/s", "km/s", "GPa", "g/cm^3", "kJ/g"};
  eos_hugoniot_point *pts = ms_calloc(nup, sizeof *pts);
  char title[1024];
  ms_status st;
  rc = material ? material_hugoniot(mats, deck, material, rho0_opt, e0_opt, nup, up, pts, title,
                                    sizeof title, &st)
                : mixture_hugoniot(mats, deck, mixture, nup, up, pts, title, sizeof title, &st);
  if (rc != 0) {
    free(pts);
    goto done;
  }
  ms_csv_header(stdout, title, 5, names, units);
  for (size_t i = 0; i < nup; ++i) {
    if (!isfinite(pts[i].us) || !isfinite(pts[i].p)) {
      fprintf(stderr,
              "mscale hugoniot: no shock state found for up = %g km/s (outside the "
              "EOS's domain or table?)\n",
              up[i]);
      continue;
    }
    double row[5] = {pts[i].up, pts[i].us, pts[i].p, pts[i].rho, pts[i].e};
    ms_csv_row(stdout, 5, row);
  }
  fflush(stdout);
  if (st != MS_OK) rc = ms_exit_code(st) == 0 ? 1 : ms_exit_code(st);
  free(pts);
done:
  eos_materials_destroy(&mats);
  dk_free(doc);
  dk_errors_free(&e);
  free(up);
  return rc;
}
