/* SPDX-License-Identifier: MIT */
/* core.h — the one public header of mscale's core library.
 *
 * The core is what every physics folder stands on and nothing physical lives here:
 *   - status codes (one list, with messages) and the exit-code mapping of docs/design.md §8;
 *   - the run context (communicator wrapper, rank, logger, output directory);
 *   - units (docs/design.md §2: internal g, cm, 10 µs; decks may say `units: si`);
 *   - the deck reader (libyaml → a tree that remembers FILE:LINE:COL, typed readers that
 *     collect every error, unknown-key detection, defaults written back for the resolved deck);
 *   - output writers that never leave a truncated file under a final name (CSV with a units
 *     header, HDF5 with an XDMF sidecar), run directories, progress with ETA;
 *   - the MPI layer (`par_*`): core/par.c is the only file that calls MPI and names the world
 *     communicator; the run's communicator travels in ms_ctx.comm; core/h5io.c takes its MPI
 *     handle from core/par_mpi.h for HDF5's MPI-IO driver and reduces through par_comm_*.
 */
#ifndef MSCALE_CORE_H
#define MSCALE_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define MSCALE_VERSION_STRING "0.1.0"

/* Runtime dispatch of hot loops (docs/benchmarks.md, "One binary for every x86-64"): in a
 * portable build (x86-64-v2, MSCALE_NATIVE=OFF) a function marked MS_KERNEL_CLONES is compiled
 * for x86-64-v2, -v3 (AVX2, FMA) and -v4 (AVX-512) and the loader picks the one the CPU runs;
 * MS_KERNEL_INLINE marks a helper to inline into each clone (left out of line, it would be
 * compiled for the baseline). A native build for an AVX-512 CPU, clang and other targets need
 * no clones. Used by the cluster-dynamics and finite discrete-model loops, the 2D grid's row
 * kernels and the Mie–Grüneisen array EOS. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__AVX512F__)
#define MS_KERNEL_CLONES                                                                           \
  __attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#define MS_KERNEL_INLINE __attribute__((always_inline))
#else
#define MS_KERNEL_CLONES
#define MS_KERNEL_INLINE
#endif

/* ------------------------------------------------------------------------------------------ */
/* Status codes                                                                                */

typedef enum ms_status {
  MS_OK = 0,
  MS_ERR_INPUT,    /* bad deck, bad data file, bad command line  -> exit 2 */
  MS_ERR_IO,       /* cannot read/write a file                   -> exit 1 */
  MS_ERR_NOMEM,    /* allocation failed                          -> exit 1 */
  MS_ERR_UNSTABLE, /* NaN, negative volume, time-step collapse   -> exit 1 */
  MS_ERR_SOLVER,   /* a nonlinear/ODE solver did not converge    -> exit 1 */
  MS_ERR_INTERNAL, /* a bug: an invariant was violated           -> exit 1 */
  MS_INTERRUPTED   /* SIGINT/SIGTERM: stopped cleanly           -> exit 1 */
} ms_status;

const char *ms_status_str(ms_status s);
/* For a constructor whose arguments the caller knows to be valid (x_create(const x_params *,
 * x **out) returning ms_status, docs/developing.md "Conventions"): anything but MS_OK is a
 * programming error, reported with `what` and the status, and the run aborts. */
void ms_must(ms_status st, const char *what);
/* Process exit code for a status: 0 success, 2 bad input, 1 anything else (docs/design.md §8). */
int ms_exit_code(ms_status s);

/* ------------------------------------------------------------------------------------------ */
/* Memory: allocation that never returns NULL silently.                                        */

void *ms_calloc(size_t n, size_t size);           /* aborts with a message on failure */
void *ms_aligned_alloc(size_t n, size_t size);    /* 64-byte aligned, zeroed; free with free() */
void *ms_realloc(void *p, size_t n, size_t size); /* aborts with a message on failure */
char *ms_strdup(const char *s);

/* ------------------------------------------------------------------------------------------ */
/* Logging and the run context                                                                 */

typedef enum ms_log_level { MS_LOG_ERROR = 0, MS_LOG_WARN, MS_LOG_INFO, MS_LOG_DEBUG } ms_log_level;

/* The communicator a run's ranks share (opaque; core/par.c). */
typedef struct ms_comm ms_comm;

typedef struct ms_ctx {
  const ms_comm *comm;    /* the run's communicator (par_init); NULL in a serial context */
  int rank, size;         /* rank and size in comm (0, 1 in a serial run) */
  ms_log_level verbosity; /* messages above this level are dropped */
  FILE *log_file;         /* run.log in the output directory, or NULL */
  char *outdir;           /* output directory ("" = none: tests, tools) */
  bool quiet;             /* no progress lines on stderr */
  double wall_start;      /* ms_wall_time() when the context was made */
  const char *restart;    /* `mscale run --restart FILE`: checkpoint to continue from, or NULL */
  bool continuing;        /* `mscale run --continue`: the output directory is the run's own */
} ms_ctx;

/* Interrupts (docs/reliability.md "Interrupts"): ms_interrupts_install makes SIGINT and SIGTERM
 * set a flag (a second signal ends the process at once); the run loops poll it and stop cleanly
 * with MS_INTERRUPTED — at their next checkpoint when checkpoints are on, so that
 * `mscale run --continue` reproduces the uninterrupted run bit for bit. */
void ms_interrupts_install(void);
bool ms_interrupt_requested(void); /* this process's flag (loops agree on it over the ranks) */
/* Whether any rank has the flag (collective under MPI: every rank of ctx calls it). */
bool ms_interrupt_agreed(const ms_ctx *ctx);

/* A context for serial tools and tests: rank 0 of 1, no output directory, log to stderr. */
void ms_ctx_init_serial(ms_ctx *ctx);
void ms_ctx_close(ms_ctx *ctx);
/* Messages go to stderr (rank 0 only, unless ERROR) and to ctx->log_file. */
void ms_log(const ms_ctx *ctx, ms_log_level level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
double ms_wall_time(void);

/* Path inside the output directory; returns a malloc'd string. */
char *ms_out_path(const ms_ctx *ctx, const char *name);
/* Create the output directory; if it exists and holds files, refuse unless force (MS_ERR_INPUT). */
ms_status ms_outdir_create(ms_ctx *ctx, const char *dir, bool force);

/* Progress: a single updating line with ETA on a terminal, plain log lines every
 * `log_interval_s` seconds otherwise. */
typedef struct ms_progress {
  const ms_ctx *ctx;
  const char *what;
  double t_start, t_end; /* simulated time span */
  double wall_start, wall_last;
  double log_interval_s;
  bool tty;
  bool active;
} ms_progress;
void ms_progress_start(ms_progress *p, const ms_ctx *ctx, const char *what, double t_start,
                       double t_end);
void ms_progress_update(ms_progress *p, double t, long step);
void ms_progress_finish(ms_progress *p, double t, long step);

/* ------------------------------------------------------------------------------------------ */
/* Units (docs/design.md §2). Internal system: g, cm, 10 µs -> g/cm³, km/s, GPa, kJ/g.               */

typedef enum ms_dim {
  MS_DIM_NONE = 0,    /* dimensionless */
  MS_DIM_LENGTH,      /* cm */
  MS_DIM_TIME,        /* 10 µs */
  MS_DIM_MASS,        /* g */
  MS_DIM_DENSITY,     /* g/cm³ */
  MS_DIM_VELOCITY,    /* km/s = cm/10µs */
  MS_DIM_PRESSURE,    /* GPa */
  MS_DIM_SPEC_ENERGY, /* kJ/g = (km/s)² */
  MS_DIM_ENERGY,      /* g·cm²/(10µs)² = kJ */
  MS_DIM_VISCOSITY,   /* g/(cm·10µs) */
  MS_DIM_TEMPERATURE, /* K */
  MS_DIM_COUNT
} ms_dim;

typedef enum ms_unit_system { MS_UNITS_INTERNAL = 0, MS_UNITS_SI } ms_unit_system;

/* Factor that converts a value in `sys` to internal units. */
double ms_unit_to_internal(ms_unit_system sys, ms_dim dim);
/* Label of the internal unit of a dimension, e.g. "GPa", "km/s", "g/cm^3". */
const char *ms_unit_label(ms_dim dim);
/* Output units (docs/output.md, "Units"): outputs give times in µs ("us"), not in the internal
 * 10 µs. ms_out_unit: the output spelling of an internal unit ("10us" -> "us", "GPa*10us" ->
 * "GPa*us"; any other unit unchanged) and the factor internal -> output (*factor, may be NULL).
 * ms_out_unit_factor: that factor from the output spelling (1 for units that are unchanged).
 * ms_out_time: an internal time in the output unit ms_out_time_label() ("us"). */
const char *ms_out_unit(const char *internal, double *factor);
double ms_out_unit_factor(const char *output);
double ms_out_time(double t);
const char *ms_out_time_label(void);

/* ------------------------------------------------------------------------------------------ */
/* Deck reading (libyaml)                                                                      *
 *
 * dk_load parses a YAML file into a tree of nodes that remember FILE:LINE:COL. Readers look keys
 * up in mappings (marking them used), convert and range-check values, and append every problem
 * to a dk_errors list: `mscale check` reports all of them, not just the first. Keys that no
 * reader asked for are reported by dk_report_unused() as unknown (typos). Readers given a
 * default write it into the tree, so dk_write_resolved() emits the deck with defaults filled in.
 */

typedef struct dk_node dk_node;
typedef struct dk_doc dk_doc;

typedef struct dk_error_pos {
  char *file; /* the file the message names */
  int line, col;
  int role;    /* DK_ROLE_*: a missing key, or an unknown key that is a misspelling of one */
  char *about; /* the key path the role is about (NULL: none) */
  bool hidden; /* a repeat of another message, or a missing key a misspelling explains */
} dk_error_pos;
/* "missing required key 'gamma'" beside "unknown key 'gama' (did you mean 'gamma'?)" in the same
 * mapping is one mistake: the missing-key message is hidden (the deck still fails). */
enum { DK_ROLE_NONE = 0, DK_ROLE_MISSING, DK_ROLE_MISSPELT };

typedef struct dk_errors {
  size_t n, cap;     /* n counts every error recorded, hidden ones too (readers compare counts) */
  char **msg;        /* each "FILE:LINE:COL: message", in the order recorded */
  dk_error_pos *pos; /* where each message points (NULL in a list assembled by hand) */
} dk_errors;

void dk_errors_init(dk_errors *e);
void dk_errors_free(dk_errors *e);
/* Prints the messages sorted by file (in order of first mention), line and column; messages
 * about a whole file come first; each text once. */
void dk_errors_print(const dk_errors *e, FILE *f);
/* The number of messages dk_errors_print prints: repeats and explained missing keys hidden. */
size_t dk_errors_count(const dk_errors *e);
/* The entry of the NULL-terminated `choices` closest to `word` (edit distance at most 2 and at most
 * half of `word`'s length), for "did you mean" hints; NULL if none is close. */
const char *dk_suggest(const char *word, const char *const *choices);
/* Report key i of `map` as unknown, with "did you mean" from `allowed` (NULL-terminated) when a
 * close key is not written in the map, else the list of allowed keys; `what` names the map. */
void dk_report_unknown_key(dk_errors *e, const dk_doc *doc, const dk_node *map, size_t i,
                           const char *what, const char *const *allowed);
/* Record an error located at node `at` (NULL: at the file as a whole). */
void dk_error(dk_errors *e, const dk_doc *doc, const dk_node *at, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* Record an error at an explicit location (for data files that are not YAML). */
void dk_error_at(dk_errors *e, const char *file, int line, int col, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

/* Parse `path`. On a syntax error, returns NULL and adds the error (with libyaml's position). */
dk_doc *dk_load(const char *path, dk_errors *e);
dk_doc *dk_load_string(const char *text, const char *name, dk_errors *e);
void dk_free(dk_doc *doc);
const dk_node *dk_root(const dk_doc *doc);
const char *dk_file(const dk_doc *doc);
/* Override one value of the deck before it is read (`mscale run DECK --set PATH=VALUE`). PATH
 * names a value as messages do ("continuum.time.end", "materials[0].eos.gamma",
 * "cluster_dynamics.box.hi[2]"); VALUE is YAML (a number, a name, "[0, 0, 1]", "{a: 1}").
 * Missing mapping keys are created; list items must exist. Messages about the value name the
 * override ("--set PATH=VALUE: ...") instead of a deck position. The override is listed in the
 * resolved deck's header. Returns false (with an error in *e) if PATH or VALUE is malformed. */
bool dk_set(dk_doc *doc, const char *path, const char *value, dk_errors *e);
/* Directory of the deck file (for resolving relative data-file paths); "" for strings. */
const char *dk_dir(const dk_doc *doc);
/* Unit system of the deck (`units:` at top level, read by dk_read_units). */
ms_unit_system dk_units(const dk_doc *doc);
/* Reads the top-level `units:` key: `internal` (g, cm, 10 µs; the default) or `si`. */
void dk_read_units(dk_doc *doc, dk_errors *e);
/* Resolve a path given in the deck relative to the deck's directory, or, when no such file
 * exists, in the installed data directory (core/deck.c); malloc'd. */
char *dk_resolve_path(const dk_doc *doc, const char *path);
/* The installed data directory, PREFIX/share/mscale (inputs/, eos/data/, tools/): the
 * environment's MSCALE_DATA_DIR, else found from the binary's own location, else the configured
 * install prefix's; NULL if none exists (a build tree). */
const char *ms_data_dir(void);

typedef enum dk_kind { DK_SCALAR, DK_MAP, DK_SEQ } dk_kind;
dk_kind dk_node_kind(const dk_node *n);
int dk_node_line(const dk_node *n);
int dk_node_col(const dk_node *n);
const char *dk_scalar(const dk_node *n); /* NULL unless a scalar */
size_t dk_seq_len(const dk_node *n);     /* 0 unless a sequence */
const dk_node *dk_seq_at(const dk_node *n, size_t i);
size_t dk_map_len(const dk_node *n);
const char *dk_map_key(const dk_node *n, size_t i);
const dk_node *dk_map_value(const dk_node *n, size_t i);

/* Look a key up in a mapping and mark it used; NULL if absent or `map` is not a mapping. */
const dk_node *dk_get(const dk_node *map, const char *key);
/* Require `n` to be a mapping / sequence; records an error naming `what` otherwise. */
bool dk_expect_map(dk_errors *e, const dk_doc *doc, const dk_node *n, const char *what);
bool dk_expect_seq(dk_errors *e, const dk_doc *doc, const dk_node *n, const char *what);

/* Typed readers. `required` keys that are missing are errors; optional ones take `def`, which
 * is written back into the tree. Values are converted from the deck's unit system to internal
 * units according to `dim`. Return false (and record an error) when the value is absent and
 * required, has the wrong type, or is outside [lo, hi]. Use -INFINITY/INFINITY for no bound. */
bool dk_read_double(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                    bool required, double def, double lo, double hi, double *out);
/* Same with an exclusive lower bound (e.g. density > 0). */
bool dk_read_positive(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                      bool required, double def, double *out);
bool dk_read_int(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                 long def, long lo, long hi, long *out);
bool dk_read_bool(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                  bool def, bool *out);
/* String: *out points into the tree (valid while doc lives). */
bool dk_read_string(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                    const char *def, const char **out);
/* One of `choices` (NULL-terminated); *out is its index. */
bool dk_read_enum(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, bool required,
                  int def, const char *const *choices, int *out);
/* The checkpoint interval keys of a section: `checkpoint_every` (steps, 0 = none) or
 * `checkpoint_time` (simulated time, 0 = none), not both. `where` prefixes the key names in the
 * message ("" or "time."), `steps` names what a step is ("steps", "particle steps"). */
void dk_read_checkpoint_interval(dk_errors *e, dk_doc *doc, const dk_node *map, const char *where,
                                 const char *steps, long *every, double *time);
/* A sequence of numbers (or a single number); *out is malloc'd, *n its length. */
bool dk_read_double_list(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                         bool required, double **out, size_t *n);
/* Convert a scalar node to a double (with units); records an error if it is not a number. */
bool dk_node_double(dk_errors *e, const dk_doc *doc, const dk_node *n, const char *what, ms_dim dim,
                    double *out);

/* Mark `key` of `map` and everything below it as read, without reading it (a section that
 * could not be read because of earlier errors must not be reported as unknown keys). */
void dk_mark_used(const dk_node *map, const char *key);
/* Report every mapping key in the document that no reader asked for. */
void dk_report_unused(dk_errors *e, const dk_doc *doc);
/* Write the tree (with defaults filled in) as YAML, atomically (temporary name + rename). */
ms_status dk_write_resolved(const dk_doc *doc, const char *path);
/* 64-bit FNV-1a hash of the resolved tree (keys, values, structure; defaults included once
 * readers have filled them in), leaving out the nodes whose path (e.g. "cluster_dynamics.t_end")
 * is listed in the NULL-terminated `skip` (may be NULL). Checkpoints store it so that a restart
 * refuses a different deck. dk_hash_doubles mixes data read from files into such a hash. */
uint64_t dk_hash(const dk_doc *doc, const char *const *skip);
uint64_t dk_hash_doubles(uint64_t h, const double *v, size_t n);

/* ------------------------------------------------------------------------------------------ */
/* Atomic files: write to "<path>.part", rename to <path> on commit; an interrupted run never  *
 * leaves a truncated file under the final name.                                               */

typedef struct ms_afile {
  FILE *f;
  char *path, *tmp_path;
} ms_afile;
ms_status ms_afile_open(ms_afile *af, const char *path);
ms_status ms_afile_commit(ms_afile *af); /* fclose + rename; frees names */
void ms_afile_abort(ms_afile *af);       /* fclose + remove the temporary */

/* CSV tables with a units header:
 *   # <title>
 *   # units: up [km/s], Us [km/s], ...
 *   up,Us,...
 * `f` is any FILE (stdout or an ms_afile's f). */
void ms_csv_header(FILE *f, const char *title, size_t ncol, const char *const *names,
                   const char *const *units);
void ms_csv_row(FILE *f, size_t ncol, const double *values);
/* The header converts internal time units to output ones (ms_out_unit) and ms_csv_row writes the
 * later rows of that FILE in them. ms_csv_resume: the same for a file whose text so far (with its
 * header) was copied back from a checkpoint; ms_csv_forget: the file is closed (ms_afile does
 * both). Rows written by hand into such a file must convert with ms_out_time themselves. */
void ms_csv_resume(FILE *f, const char *text, size_t len);
/* The factor that takes column `col` of a table file to internal time, from the file's
 * "# units:" line ("t [us]": 0.1; [10us], [s], [ms], [ns]), else `fallback` (the deck's unit
 * system): an output CSV of one run (in µs) read as the history of another. */
double ms_table_time_factor(const char *path, size_t col, double fallback);
void ms_csv_forget(FILE *f);

/* Read a numeric table (CSV or whitespace separated; '#' comments; an optional header line of
 * names). Errors name FILE:LINE. On success *data is row-major [nrow][ncol], malloc'd. */
ms_status ms_read_table(const char *path, size_t min_cols, double **data, size_t *nrow,
                        size_t *ncol, dk_errors *e);

/* ------------------------------------------------------------------------------------------ */
/* HDF5 output with XDMF sidecar (core/h5io.c).                                                */

typedef struct ms_h5 ms_h5;
/* Creates "<path>.part"; ms_h5_close renames it to <path>. */
ms_h5 *ms_h5_create(const char *path);
/* Write a 1D/2D double dataset at `name` (groups made as needed) with a "units" attribute. */
ms_status ms_h5_write_doubles(ms_h5 *h, const char *name, size_t n0, size_t n1, const double *data,
                              const char *units);
ms_status ms_h5_write_ints(ms_h5 *h, const char *name, size_t n, const int64_t *data);
/* n internal times as a dataset in the output time unit (ms_out_time; units "us") */
ms_status ms_h5_write_times(ms_h5 *h, const char *name, size_t n, const double *t);
ms_status ms_h5_attr_double(ms_h5 *h, const char *obj, const char *attr, double v);
ms_status ms_h5_attr_int(ms_h5 *h, const char *obj, const char *attr, int64_t v); /* counts */
ms_status ms_h5_attr_string(ms_h5 *h, const char *obj, const char *attr, const char *v);
/* Parallel HDF5 (MPI-IO): every rank calls create, every write and close (collectively);
 * attributes must be written with the same values on every rank. Without MPI running it is
 * ms_h5_create. */
ms_h5 *ms_h5_create_collective(const char *path);
/* Each rank contributes n_local rows of a [N][ncomp] dataset, in rank order; the file is the
 * same whatever the rank count. On a non-collective file this is an ordinary write. */
ms_status ms_h5_write_doubles_dist(ms_h5 *h, const char *name, size_t n_local, size_t ncomp,
                                   const double *data, const char *units);
ms_status ms_h5_write_ints_dist(ms_h5 *h, const char *name, size_t n_local, const int64_t *data);
/* Bytes (e.g. the text of an output file so far) as a 1D uint8 dataset, distributed like the
 * rows above (a rank with nothing to add passes 0). */
ms_status ms_h5_write_bytes_dist(ms_h5 *h, const char *name, size_t n_local, const void *data);
ms_status ms_h5_close(ms_h5 *h); /* commit: close + rename (collective files: every rank) */
void ms_h5_abort(ms_h5 *h);      /* close + remove temporary */

/* Reading (for post-processing commands and tests). */
typedef struct ms_h5r ms_h5r;
ms_h5r *ms_h5_open_read(const char *path, dk_errors *e);
/* Reads a double dataset; *data malloc'd, dims in n0/n1 (n1 = 1 for 1D). */
ms_status ms_h5_read_doubles(ms_h5r *h, const char *name, double **data, size_t *n0, size_t *n1,
                             dk_errors *e);
bool ms_h5_exists(ms_h5r *h, const char *name);
/* Rows [row0, row0 + nrow) of a 1D/2D dataset (nrow = SIZE_MAX: to the end), as doubles or
 * int64 (integer datasets only); *data malloc'd, *ncol its row width. MS_ERR_INPUT with a
 * message naming the file when the dataset is missing, of the wrong class, shorter than asked
 * or not fully stored (truncated file). */
ms_status ms_h5_read_doubles_rows(ms_h5r *h, const char *name, size_t row0, size_t nrow,
                                  double **data, size_t *nread, size_t *ncol, dk_errors *e);
ms_status ms_h5_read_ints_rows(ms_h5r *h, const char *name, size_t row0, size_t nrow,
                               int64_t **data, size_t *nread, size_t *ncol, dk_errors *e);
/* A 1D uint8 dataset (ms_h5_write_bytes_dist); *data malloc'd (one extra 0 byte). */
ms_status ms_h5_read_bytes(ms_h5r *h, const char *name, char **data, size_t *n, dk_errors *e);
/* A string attribute; *v malloc'd. */
ms_status ms_h5_read_attr_string(ms_h5r *h, const char *obj, const char *attr, char **v,
                                 dk_errors *e);
/* Reads a scalar numeric attribute `attr` of the object `obj` (group or dataset; "/" = root).
 * MS_ERR_INPUT with a message naming the file if it is absent or not a number; e may be NULL
 * to probe quietly. */
ms_status ms_h5_read_attr_double(ms_h5r *h, const char *obj, const char *attr, double *v,
                                 dk_errors *e);
void ms_h5_close_read(ms_h5r *h);
/* The numeric 1D/2D datasets directly under `group`, in name order (for tools that take every
 * per-particle field of a snapshot, e.g. `mscale export`); *items malloc'd, freed with
 * ms_h5_entries_free. MS_ERR_INPUT naming the file if the group is missing. */
typedef struct ms_h5_entry {
  char *name;        /* the dataset's name inside the group */
  bool is_int;       /* integer class (read with ms_h5_read_ints_rows), else float */
  size_t rows, cols; /* cols = 1 for 1D */
} ms_h5_entry;
ms_status ms_h5_list(ms_h5r *h, const char *group, ms_h5_entry **items, size_t *n, dk_errors *e);
void ms_h5_entries_free(ms_h5_entry *items, size_t n);

/* XDMF sidecar describing datasets in an HDF5 file so ParaView can open it.
 * Points (particles): positions dataset `coords` with dims [n][dim], dim 2 or 3; attributes
 * are scalars [n] or vectors [n][3]. A 1D grid writes node positions as [n][3] = (x, 0, 0);
 * if any attribute is cell_centred ([n-1] values) the points are joined into a polyline. */
typedef struct ms_xdmf_attr {
  const char *name;    /* attribute name shown in ParaView */
  const char *dataset; /* path inside the .h5 */
  int ncomp;           /* 1 scalar, 3 vector */
  bool cell_centred;   /* lives on cells (1D grid) rather than nodes/points */
} ms_xdmf_attr;
ms_status ms_xdmf_write_points(const char *xmf_path, const char *h5_name, const char *coords,
                               size_t npoints, int dim, double time, size_t nattr,
                               const ms_xdmf_attr *attr);
/* The same with `vertex` (may be NULL), an int64 dataset [npoints] holding 0..npoints-1: the
 * Polyvertex connectivity, so that ParaView makes one vertex cell per particle. */
ms_status ms_xdmf_write_particles(const char *xmf_path, const char *h5_name, const char *coords,
                                  const char *vertex, size_t npoints, int dim, double time,
                                  size_t nattr, const ms_xdmf_attr *attr);
/* DIR/SERIES_NAME: a temporal collection of every DIR/PREFIX*.xmf (name order) but itself, so
 * ParaView opens a whole run as one time series. Call it again after each new snapshot. */
ms_status ms_xdmf_write_series(const char *dir, const char *prefix, const char *series_name);

/* ------------------------------------------------------------------------------------------ */
/* Checkpoints (core/checkpoint.c, docs/mpi.md): collective HDF5 files under a temporary name,  *
 * stamped with a format name, the resolved deck's hash (dk_hash) and the rank count.          */

/* Every rank: create OUTDIR/name(.part) and write the stamp. NULL on failure. */
ms_h5 *ms_ckpt_create(const ms_ctx *ctx, const char *name, const char *format, uint64_t deck_hash);
/* Every rank: agree on st (the writes' status), then complete (rename) or abort the file and
 * log it. The environment variable MSCALE_CHECKPOINT_DELAY (seconds) holds the complete
 * temporary file before the rename (kill tests). */
ms_status ms_ckpt_commit(const ms_ctx *ctx, ms_h5 *h, ms_status st, const char *name, long step);
/* Open a checkpoint for reading; refuses (NULL, message in e) another format or deck hash. */
ms_h5r *ms_ckpt_open(const char *path, const char *format, uint64_t deck_hash, dk_errors *e);
/* An output file being written (rank 0's ms_afile): its text so far into dataset `name`; and
 * back into a freshly opened ms_afile of the restarted run. Every rank calls both. */
ms_status ms_ckpt_save_afile(const ms_ctx *ctx, ms_h5 *h, const char *name, ms_afile *af);
ms_status ms_ckpt_restore_afile(const ms_ctx *ctx, ms_h5r *h, const char *name, ms_afile *af,
                                dk_errors *e);

/* ------------------------------------------------------------------------------------------ */
/* MPI layer (core/par.c). Serial builds and tests use the same calls on one rank.            *
 *                                                                                            *
 * par_init starts MPI (if nobody has) and puts the run's communicator into ctx->comm; the     *
 * par_* calls below without a communicator argument act on that communicator (serially, on   *
 * one rank, before par_init and after par_finalize). The par_comm_* calls take it explicitly  *
 * (NULL: serial, no communication).                                                          */

ms_status par_init(int *argc, char ***argv, ms_ctx *ctx);
/* The run's communicator while MPI is running (the one par_init gave the context), else NULL. */
const ms_comm *par_comm(void);
int par_comm_rank(const ms_comm *c);
int par_comm_min_int(const ms_comm *c, int v);
int par_comm_max_int(const ms_comm *c, int v);
void par_comm_bcast_int(const ms_comm *c, int *v, int root);
uint64_t par_comm_sum_u64(const ms_comm *c, uint64_t v);
/* Sum of v over the lower ranks (0 on rank 0). */
uint64_t par_comm_exscan_u64(const ms_comm *c, uint64_t v);
void par_finalize(void);
/* Provenance (run_info.yaml): the MPI library's version (MPI_Get_library_version, first line;
 * callable before par_init) and the OpenMP threads a parallel region gets. */
void par_mpi_library_version(char *buf, size_t n);
int par_max_threads(void);
/* The HDF5 library's version (H5get_libversion), "1.10.8". */
void ms_h5_library_version(char *buf, size_t n);
/* The libyaml version the deck reader runs with, "0.2.5". */
const char *dk_yaml_version(void);
void par_barrier(void);
double par_sum_double(double v);
double par_max_double(double v);
double par_min_double(double v);
long par_sum_long(long v);
int par_max_int(int v);
/* All ranks agree on a status: the worst (non-zero) one wins. */
ms_status par_agree_status(ms_status s);
void par_bcast_doubles(double *v, size_t n, int root);
/* Typed wrappers for distributed particle models (docs/mpi.md). */
void par_bcast_ints(int32_t *v, size_t n, int root);
/* In-place element-wise sum over ranks of v[0..n). */
void par_sum_doubles(double *v, size_t n);
/* In-place element-wise maximum over ranks of v[0..n). */
void par_max_doubles(double *v, size_t n);
/* The same sum in a fixed order (rank order, on rank 0, then broadcast): identical bits on every
 * rank, reproducible for a given rank count whatever the MPI library's algorithm. For values
 * that enter state every rank keeps a copy of (the coupled problem's replicated grid). */
void par_sum_doubles_ordered(double *v, size_t n);
/* All-to-all personalised exchange of doubles: counts and displacements (in doubles) per rank,
 * arrays of ctx->size entries. Serial: copies send[sdispl[0]..] to recv[rdispl[0]..]. */
void par_alltoallv_doubles(const double *send, const int *scount, const int *sdispl, double *recv,
                           const int *rcount, const int *rdispl);
/* Distributed fragment analysis (coupling/fragments_dist.c): one int per rank to every rank
 * (send and recv have size entries); alltoallv of int64 (counts in elements, as above); the
 * largest int64 over ranks; each rank's v into all[rank] on every rank; concatenation of every
 * rank's n doubles in rank order on every rank (counts/displs per rank, in doubles). */
void par_alltoall_ints(const int *send, int *recv);
void par_alltoallv_int64(const int64_t *send, const int *scount, const int *sdispl, int64_t *recv,
                         const int *rcount, const int *rdispl);
int64_t par_max_int64(int64_t v);
void par_allgather_long(long v, long *all);
void par_allgatherv_doubles(const double *send, int n, double *recv, const int *counts,
                            const int *displs);
/* Rank and size in the run's communicator (0 and 1 when MPI is not running). */
int par_rank(void);
int par_size(void);
/* In-place element-wise sum over ranks of v[0..n) (exact: integers). */
void par_sum_int64s(int64_t *v, size_t n);
/* Cumulative wall and process CPU time spent inside the par_* calls of distributed particle
 * runs (reductions, all-to-all, neighbour exchange), waits included. */
void par_comm_time(double *wall, double *cpu);
/* Point-to-point exchange with `nnbr` neighbour ranks (ranks[k]): send[sdispl[k]..+scount[k])
 * goes to ranks[k], recv[rdispl[k]..+rcount[k]) comes from it (counts in doubles). Every rank
 * must list each partner that lists it. Allocation-free after the first call. No-op serially. */
void par_exchange_doubles(int nnbr, const int *ranks, const double *send, const int *scount,
                          const int *sdispl, double *recv, const int *rcount, const int *rdispl);
/* The same, split: par_exchange_post starts it (nonblocking; `tag` tells apart several
 * exchanges posted together, e.g. one per array) and par_exchange_wait completes every posted
 * exchange. Buffers must stay untouched in between; the caller may compute meanwhile. */
void par_exchange_post(int nnbr, const int *ranks, const double *send, const int *scount,
                       const int *sdispl, double *recv, const int *rcount, const int *rdispl,
                       int tag);
void par_exchange_wait(void);

/* ------------------------------------------------------------------------------------------ */
/* Check-time memory estimate (core/mem_estimate.c): problem readers add their large arrays   *
 * while they read the deck (count × bytes each, at the deck node that sets the count); a deck *
 * that cannot fit is rejected with exit 2 and an estimate, never by the OOM killer. Counts are *
 * doubles, so 1e12 particles do not overflow on the way to the message.                       */

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

#endif /* MSCALE_CORE_H */
