/* SPDX-License-Identifier: MIT */
/* mscale export SNAPSHOT.h5... --format extxyz|lammps-dump [-o FILE]: particle snapshots in the
 * formats OVITO, ASE and LAMMPS's tools read (docs/output.md). Every numeric per-particle dataset
 * of /particles is carried over: positions, velocities, mass, material, fragment id and the
 * model's own fields. Several snapshots become several frames of one file. */
#include "commands.h"

#include <getopt.h>

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum export_format { EXPORT_EXTXYZ, EXPORT_LAMMPS_DUMP };

static void export_usage(FILE *f) {
  fprintf(f, "Usage: mscale export SNAPSHOT.h5... --format extxyz|lammps-dump [-o FILE]\n\n"
             "Writes particle snapshots (HDF5, /particles/x [n][3] and the other per-particle\n"
             "datasets) as extended XYZ (ASE, OVITO) or a LAMMPS text dump (OVITO, LAMMPS\n"
             "tools), one frame per snapshot, to FILE (written under FILE.part, then renamed)\n"
             "or to stdout. Units are the snapshot's: positions cm, velocities km/s, mass g,\n"
             "time us (10 us in files of mscale before 0.2); the extended-XYZ comment line names "
             "them. Species: the material's name\n"
             "when it is an element symbol (attribute material_names of /particles), else X.\n\n"
             "Options:\n"
             "  --format F   extxyz or lammps-dump\n"
             "  -o FILE      output file (default: stdout)\n"
             "  -h, --help   this text\n\n"
             "Exit codes: 0 success, 1 I/O failure, 2 bad usage or a bad snapshot.\n");
}

/* Element symbols, so that ASE (which wants real species) reads the file. */
static const char *const element_symbols[] = {
    "H",  "He", "Li", "Be", "B",  "C",  "N",  "O",  "F",  "Ne", "Na", "Mg", "Al", "Si", "P",
    "S",  "Cl", "Ar", "K",  "Ca", "Sc", "Ti", "V",  "Cr", "Mn", "Fe", "Co", "Ni", "Cu", "Zn",
    "Ga", "Ge", "As", "Se", "Br", "Kr", "Rb", "Sr", "Y",  "Zr", "Nb", "Mo", "Tc", "Ru", "Rh",
    "Pd", "Ag", "Cd", "In", "Sn", "Sb", "Te", "I",  "Xe", "Cs", "Ba", "La", "Ce", "Pr", "Nd",
    "Pm", "Sm", "Eu", "Gd", "Tb", "Dy", "Ho", "Er", "Tm", "Yb", "Lu", "Hf", "Ta", "W",  "Re",
    "Os", "Ir", "Pt", "Au", "Hg", "Tl", "Pb", "Bi", "Po", "At", "Rn", "Fr", "Ra", "Ac", "Th",
    "Pa", "U",  "Np", "Pu", "Am", "Cm", "Bk", "Cf", "Es", "Fm", "Md", "No", "Lr"};

/* The element symbol a material name spells ("pb" -> "Pb"), else "X". */
static const char *species_of(const char *material) {
  char buf[4] = {0};
  size_t len = strlen(material);
  if (len == 0 || len > 2) return "X";
  buf[0] = (char)toupper((unsigned char)material[0]);
  if (len == 2) buf[1] = (char)tolower((unsigned char)material[1]);
  for (size_t k = 0; k < sizeof element_symbols / sizeof *element_symbols; k++)
    if (!strcmp(buf, element_symbols[k])) return element_symbols[k];
  return "X";
}

/* One snapshot in memory: every per-particle dataset as doubles (integers kept exact: |v| <
 * 2^53 for every id and count we write). */
typedef struct snapshot {
  size_t n, nfield;
  ms_h5_entry *field; /* from ms_h5_list, minus x */
  double **data;      /* [nfield][n * cols] */
  double *x;          /* [n][3] */
  double time;        /* in time_unit; NAN if the file has none */
  char time_unit[16]; /* the file's time_units ("us"), else the internal "10us" */
  char **names;       /* material names (NULL: none) */
  size_t nnames;
} snapshot;

static void snapshot_free(snapshot *s) {
  for (size_t k = 0; k < s->nfield; k++) free(s->data[k]);
  free(s->data);
  ms_h5_entries_free(s->field, s->nfield);
  free(s->x);
  for (size_t k = 0; k < s->nnames; k++) free(s->names[k]);
  free(s->names);
  memset(s, 0, sizeof *s);
}

static void split_names(snapshot *s, char *list) {
  for (char *tok = strtok(list, ","); tok; tok = strtok(NULL, ",")) {
    s->names = ms_realloc(s->names, s->nnames + 1, sizeof *s->names);
    s->names[s->nnames++] = ms_strdup(tok);
  }
}

static ms_status snapshot_read(const char *path, snapshot *s, dk_errors *e) {
  memset(s, 0, sizeof *s);
  ms_h5r *h = ms_h5_open_read(path, e);
  if (!h) return MS_ERR_INPUT;
  ms_h5_entry *all = NULL;
  size_t nall = 0, n0 = 0, n1 = 0;
  ms_status st = ms_h5_read_doubles(h, "/particles/x", &s->x, &n0, &n1, e);
  if (st == MS_OK && n1 != 3) {
    dk_error_at(e, path, 0, 0, "/particles/x has %zu columns, expected 3", n1);
    st = MS_ERR_INPUT;
  }
  if (st == MS_OK) st = ms_h5_list(h, "/particles", &all, &nall, e);
  s->n = n0;
  s->field = ms_calloc(nall ? nall : 1, sizeof *s->field);
  s->data = ms_calloc(nall ? nall : 1, sizeof *s->data);
  for (size_t k = 0; st == MS_OK && k < nall; k++) {
    if (!strcmp(all[k].name, "x") || all[k].rows != s->n || (all[k].cols != 1 && all[k].cols != 3))
      continue; /* the positions, or not a per-particle scalar/vector */
    char ds[300];
    snprintf(ds, sizeof ds, "/particles/%s", all[k].name);
    size_t nr, nc;
    double *d = NULL;
    if (all[k].is_int) {
      int64_t *iv = NULL;
      st = ms_h5_read_ints_rows(h, ds, 0, SIZE_MAX, &iv, &nr, &nc, e);
      if (st == MS_OK) {
        d = ms_calloc(nr * nc > 0 ? nr * nc : 1, sizeof *d);
        for (size_t i = 0; i < nr * nc; i++) d[i] = (double)iv[i];
      }
      free(iv);
    } else {
      st = ms_h5_read_doubles(h, ds, &d, &nr, &nc, e);
    }
    if (st != MS_OK) break;
    for (size_t i = 0; i < nr * nc; i++)
      if (!isfinite(d[i])) {
        dk_error_at(e, path, 0, 0, "%s: particle %zu is not finite", ds, i / nc);
        st = MS_ERR_INPUT;
        break;
      }
    s->field[s->nfield] = all[k];
    all[k].name = NULL; /* moved */
    s->data[s->nfield++] = d;
  }
  ms_h5_entries_free(all, nall);
  for (size_t i = 0; st == MS_OK && i < 3 * s->n; i++)
    if (!isfinite(s->x[i])) {
      dk_error_at(e, path, 0, 0, "/particles/x: particle %zu is not finite", i / 3);
      st = MS_ERR_INPUT;
    }
  s->time = NAN;
  if (st == MS_OK && ms_h5_read_attr_double(h, "/", "time", &s->time, NULL) != MS_OK)
    ms_h5_read_attr_double(h, "/particles", "time", &s->time, NULL);
  char *names = NULL, *tu = NULL;
  snprintf(s->time_unit, sizeof s->time_unit, "10us"); /* files before time_units */
  if (st == MS_OK && ms_h5_read_attr_string(h, "/particles", "time_units", &tu, NULL) == MS_OK &&
      strlen(tu) < sizeof s->time_unit && !strpbrk(tu, "\" \n"))
    snprintf(s->time_unit, sizeof s->time_unit, "%s", tu);
  free(tu);
  if (st == MS_OK &&
      ms_h5_read_attr_string(h, "/particles", "material_names", &names, NULL) == MS_OK) {
    split_names(s, names);
    free(names);
  }
  ms_h5_close_read(h);
  if (st != MS_OK) snapshot_free(s);
  return st;
}

static const double *field_of(const snapshot *s, const char *name, size_t cols) {
  for (size_t k = 0; k < s->nfield; k++)
    if (!strcmp(s->field[k].name, name) && s->field[k].cols == cols) return s->data[k];
  return NULL;
}

static const char *species_at(const snapshot *s, const double *mat, size_t i) {
  if (!mat || !s->names) return s->nnames == 1 ? species_of(s->names[0]) : "X";
  long m = (long)mat[i];
  return m >= 0 && (size_t)m < s->nnames ? species_of(s->names[m]) : "X";
}

/* A value as written: integers exactly, reals with 17 significant digits (round trip). */
static void put_value(FILE *f, double v, bool is_int) {
  if (is_int) fprintf(f, " %.0f", v);
  else fprintf(f, " %.17g", v);
}

static void write_extxyz(FILE *f, const snapshot *s) {
  const double *mat = field_of(s, "material", 1);
  fprintf(f, "%zu\nProperties=species:S:1:pos:R:3", s->n);
  for (size_t k = 0; k < s->nfield; k++)
    fprintf(f, ":%s:%c:%zu", strcmp(s->field[k].name, "v") ? s->field[k].name : "velo",
            s->field[k].is_int ? 'I' : 'R', s->field[k].cols);
  fprintf(f, " pbc=\"F F F\" units=\"pos:cm velo:km/s mass:g time:%s\"", s->time_unit);
  if (isfinite(s->time)) fprintf(f, " Time=%.17g", s->time);
  fputc('\n', f);
  for (size_t i = 0; i < s->n; i++) {
    fputs(species_at(s, mat, i), f);
    for (int c = 0; c < 3; c++) put_value(f, s->x[3 * i + c], false);
    for (size_t k = 0; k < s->nfield; k++)
      for (size_t c = 0; c < s->field[k].cols; c++)
        put_value(f, s->data[k][s->field[k].cols * i + c], s->field[k].is_int);
    fputc('\n', f);
  }
}

static void write_lammps_dump(FILE *f, const snapshot *s, size_t frame) {
  const double *gid = field_of(s, "gid", 1), *mat = field_of(s, "material", 1);
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < s->n; i++)
    for (int c = 0; c < 3; c++) {
      lo[c] = fmin(lo[c], s->x[3 * i + c]);
      hi[c] = fmax(hi[c], s->x[3 * i + c]);
    }
  /* LAMMPS's TIMESTEP is an integer: the frame number; the time is in the unit line above it */
  fprintf(f, "ITEM: TIMESTEP\n%zu\nITEM: NUMBER OF ATOMS\n%zu\nITEM: BOX BOUNDS ff ff ff\n", frame,
          s->n);
  for (int c = 0; c < 3; c++) fprintf(f, "%.17g %.17g\n", s->n ? lo[c] : 0.0, s->n ? hi[c] : 0.0);
  fputs("ITEM: ATOMS id type x y z", f);
  static const char *const xyz[3] = {"x", "y", "z"};
  for (size_t k = 0; k < s->nfield; k++) {
    if (s->field[k].cols == 1) fprintf(f, " %s", s->field[k].name);
    else
      for (int c = 0; c < 3; c++)
        fprintf(f, " %s%s", strcmp(s->field[k].name, "v") ? s->field[k].name : "v", xyz[c]);
  }
  fputc('\n', f);
  for (size_t i = 0; i < s->n; i++) {
    fprintf(f, "%.0f %ld", gid ? gid[i] + 1 : (double)(i + 1), mat ? (long)mat[i] + 1 : 1L);
    for (int c = 0; c < 3; c++) put_value(f, s->x[3 * i + c], false);
    for (size_t k = 0; k < s->nfield; k++)
      for (size_t c = 0; c < s->field[k].cols; c++)
        put_value(f, s->data[k][s->field[k].cols * i + c], s->field[k].is_int);
    fputc('\n', f);
  }
}

int cmd_export(int argc, char **argv) {
  const char *format = NULL, *out = NULL;
  const char **snaps = ms_calloc((size_t)argc, sizeof *snaps);
  size_t nsnap = 0;
  static const struct option opts[] = {{"format", required_argument, NULL, 256},
                                       {"output", required_argument, NULL, 'o'},
                                       {"help", no_argument, NULL, 'h'},
                                       {NULL, 0, NULL, 0}};
  int c, rc = -1;
  opterr = 0;
  optind = 0; /* glibc: a full reset (tests call the commands in-process, repeatedly) */
  while (rc < 0 && (c = getopt_long(argc, argv, ":o:h", opts, NULL)) != -1) {
    if (c == 'h') rc = 0, export_usage(stdout);
    else if (c == ':' || c == '?')
      rc = app_option_error("export", c, optopt, argv[optind - 1], opts);
    else if (app_option_value_missing("export", c == 'o' ? "-o" : "--format", optarg)) rc = 2;
    else if (c == 'o') out = optarg;
    else format = optarg;
  }
  if (rc >= 0) {
    free(snaps);
    return rc;
  }
  for (int i = optind; i < argc; i++) snaps[nsnap++] = argv[i];
  enum export_format fmt = EXPORT_EXTXYZ;
  if (!format || nsnap == 0 ||
      !(!strcmp(format, "extxyz") || (fmt = EXPORT_LAMMPS_DUMP, !strcmp(format, "lammps-dump")))) {
    fprintf(stderr, "mscale export: %s\n\n",
            nsnap == 0 ? "no snapshot given"
            : !format  ? "--format is required (extxyz or lammps-dump)"
                       : "--format must be extxyz or lammps-dump");
    export_usage(stderr);
    free(snaps);
    return 2;
  }
  ms_afile afile = {0}, *af = NULL;
  FILE *f = stdout;
  if (out) {
    if (ms_afile_open(&afile, out) != MS_OK) {
      fprintf(stderr, "mscale export: cannot write %s\n", out);
      free(snaps);
      return 1;
    }
    af = &afile;
    f = af->f;
  }
  rc = 0;
  for (size_t k = 0; k < nsnap && rc == 0; k++) {
    dk_errors errs, *e = &errs;
    dk_errors_init(e);
    snapshot s;
    if (snapshot_read(snaps[k], &s, e) != MS_OK) {
      dk_errors_print(e, stderr);
      rc = 2;
    } else {
      if (fmt == EXPORT_EXTXYZ) write_extxyz(f, &s);
      else write_lammps_dump(f, &s, k);
      snapshot_free(&s);
    }
    dk_errors_free(e);
  }
  if (af) {
    if (rc == 0 && ms_afile_commit(af) != MS_OK) {
      fprintf(stderr, "mscale export: writing %s failed\n", out);
      rc = 1;
    } else if (rc != 0) ms_afile_abort(af);
  } else if (fflush(stdout) != 0) rc = 1;
  free(snaps);
  return rc;
}
