/* SPDX-License-Identifier: MIT */
/* coupled2d.c — the deck problem `coupled2d` (docs/coupling.md §5a, docs/input-coupled.md
 * "coupled2d"): a 2D grid runs to its end recording a tagged node line, then a 2D particle region
 * (the discrete model) between that line and the free-surface line is driven by it one piston
 * column per node (cpl_drive_from_line), stepped to the grid's end time, with particle snapshots
 * and the free-surface velocity per column of both beside each other. The grid through cont2d.h,
 * the particles through ptl_region.h. */
#include "cont2d.h"
#include "cpl_impl.h"
#include "ptl_region.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct cpl2d_problem {
  const eos_materials *mats;
  c2d_problem *grid;
  size_t tag_drive, tag_fs;
  int sample_mat;
  double depth;       /* the region's extent along dir: line to free surface, cm */
  cpl_line_drive how; /* y0 < 0 before the run: the default (width/2 with mirror) */
  const ptl_region_model *model;
  ptl_region_params *region;
  long n_out, column_every;
  double column_upto; /* |s| of the sampled columns, cm */
};

static size_t find_line(const c2d_grid *g, const char *name) {
  for (size_t i = 0; i < c2d_grid_ntag_lines(g); i++)
    if (!strcmp(c2d_grid_line_history(g, i).name, name)) return i;
  return (size_t)-1;
}

/* `direction: [dx, dy]`: the grid direction of the region's drive axis, normalised; across is it
 * turned by +90°. */
static void read_direction(cpl2d_problem *p, dk_doc *doc, const dk_node *D, dk_errors *e) {
  double *v = NULL;
  size_t n = 0;
  p->how.dir[0] = 0, p->how.dir[1] = -1;
  if (dk_get(D, "direction") &&
      dk_read_double_list(e, doc, D, "direction", MS_DIM_NONE, true, &v, &n)) {
    const double len = n == 2 ? hypot(v[0], v[1]) : 0;
    if (!(len > 0) || !isfinite(len))
      dk_error(e, doc, dk_get(D, "direction"), "drive.direction: expected [dx, dy], not zero");
    else p->how.dir[0] = v[0] / len, p->how.dir[1] = v[1] / len;
  }
  free(v);
  p->how.across[0] = -p->how.dir[1], p->how.across[1] = p->how.dir[0];
}

static void read_sections(cpl2d_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e,
                          const char **tag, const char **fs_tag) {
  const dk_node *G = dk_get(sec, "grid");
  if (!G)
    dk_error(e, doc, sec,
             "coupled2d: a 'grid:' section (the keys of a grid2d section) is required");
  else if (dk_expect_map(e, doc, G, "grid")) p->grid = c2d_problem_read(doc, G, p->mats, e);
  const dk_node *D = dk_get(sec, "drive");
  if (!D)
    dk_error(e, doc, sec, "coupled2d: a 'drive:' section (tag, free_surface_tag, t0) is required");
  else if (dk_expect_map(e, doc, D, "drive")) {
    dk_read_string(e, doc, D, "tag", true, NULL, tag);
    dk_read_string(e, doc, D, "free_surface_tag", true, NULL, fs_tag);
    dk_read_double(e, doc, D, "t0", MS_DIM_TIME, false, 0.0, 0.0, INFINITY, &p->how.t0);
    dk_read_bool(e, doc, D, "mirror", false, false, &p->how.mirror);
    dk_read_bool(e, doc, D, "lateral", false, true, &p->how.lateral);
    p->how.y0 = -1; /* absent: width/2 with mirror, else −min s (set at the run) */
    if (dk_get(D, "y0"))
      dk_read_double(e, doc, D, "y0", MS_DIM_LENGTH, true, 0.0, 0.0, INFINITY, &p->how.y0);
    read_direction(p, doc, D, e);
  }
  const dk_node *P = dk_get(sec, "particles");
  if (!P) dk_error(e, doc, sec, "coupled2d: a 'particles:' section is required");
  else if (dk_expect_map(e, doc, P, "particles")) {
    int model = 1;
    if (dk_read_enum(e, doc, P, "model", false, 1, ptl_region_model_names, &model) &&
        strcmp(ptl_region_model_names[model], "discrete_model"))
      dk_error(e, doc, dk_get(P, "model"),
               "particles.model %s has no piston by columns: coupled2d needs discrete_model",
               ptl_region_model_names[model]);
    else {
      p->model = ptl_region_model_find(ptl_region_model_names[model]);
      p->region = ptl_region_params_read(p->model, doc, P, e);
    }
  }
  const dk_node *O = dk_get(sec, "output");
  p->n_out = 4, p->column_every = 1, p->column_upto = INFINITY;
  if (O && dk_expect_map(e, doc, O, "output")) {
    dk_read_int(e, doc, O, "snapshots", false, 4, 1, 1000, &p->n_out);
    dk_read_int(e, doc, O, "column_every", false, 1, 1, 1000000, &p->column_every);
    if (dk_get(O, "column_upto")) /* absent: every node */
      dk_read_double(e, doc, O, "column_upto", MS_DIM_LENGTH, true, 0.0, 0.0, INFINITY,
                     &p->column_upto);
  }
}

/* The two lines (record 0: the initial mesh): parallel rows or columns of nodes, the free-surface
 * line a fixed distance along dir from the drive line, one material with an EOS between them. */
static void check_lines(cpl2d_problem *p, dk_doc *doc, const dk_node *at, const dk_node *at_fs,
                        dk_errors *e) {
  const c2d_grid *g = c2d_problem_grid(p->grid);
  const c2d_line_history d = c2d_grid_line_history(g, p->tag_drive),
                         f = c2d_grid_line_history(g, p->tag_fs);
  const c2d_view v = c2d_grid_view(g);
  const size_t w = v.ni + 1;
  const bool along_i = d.nnodes > 1 && d.node[1] == d.node[0] + 1;
  if (d.nnodes != f.nnodes || (f.nnodes > 1 && (f.node[1] == f.node[0] + 1) != along_i) ||
      d.node[0] == f.node[0]) {
    dk_error(e, doc, at_fs, "drive.free_surface_tag '%s' must be a node line parallel to '%s'",
             f.name, d.name);
    return;
  }
  p->depth = (f.x[0] - d.x[0]) * p->how.dir[0] + (f.y[0] - d.y[0]) * p->how.dir[1];
  for (size_t q = 0; q < d.nnodes; q++) {
    const double dx = f.x[q] - d.x[q], dy = f.y[q] - d.y[q];
    const double along = dx * p->how.dir[0] + dy * p->how.dir[1],
                 off = dx * p->how.across[0] + dy * p->how.across[1];
    /* the region is a flat slab: the lines straight and parallel to within round-off */
    if (!(p->depth > 0) || fabs(along - p->depth) > 1e-9 * p->depth ||
        fabs(off) > 1e-9 * p->depth) {
      dk_error(e, doc, at,
               "the particle region does not fit the line '%s': the free surface '%s' must lie "
               "a constant distance > 0 from it along drive.direction (node %zu: %g cm along, "
               "%g cm across)",
               d.name, f.name, q, along, off);
      return;
    }
  }
  /* the zones between the lines: rows (along i) or columns of the logical mesh */
  const size_t a = along_i ? d.node[0] / w : d.node[0] % w,
               b = along_i ? f.node[0] / w : f.node[0] % w;
  const size_t lo = a < b ? a : b, hi = a < b ? b : a;
  p->sample_mat = -1;
  for (size_t k = lo; k < hi; k++)
    for (size_t m = 0; m < (along_i ? v.ni : v.nj); m++) {
      const size_t z = along_i ? k * v.ni + m : m * v.ni + k;
      if (p->sample_mat < 0) p->sample_mat = v.material[z];
      if (v.material[z] != p->sample_mat) {
        dk_error(e, doc, at,
                 "the zones between '%s' and '%s' must be one material (the particles')", d.name,
                 f.name);
        return;
      }
    }
  if (!p->mats->m[p->sample_mat].eos)
    dk_error(e, doc, at, "the sample material has no equation of state");
}

/* The region's width (particles.width, if given) against the line's extent across. */
static void check_width(cpl2d_problem *p, dk_doc *doc, const dk_node *sec, dk_errors *e) {
  const dk_node *P = dk_get(sec, "particles");
  const dk_node *W = dk_get(P, "width");
  if (!W) return;
  double width = 0;
  dk_errors scratch; /* the model's reader reports a bad value */
  dk_errors_init(&scratch);
  const bool ok =
      dk_read_double(&scratch, doc, P, "width", MS_DIM_LENGTH, true, 0, 0, INFINITY, &width);
  dk_errors_free(&scratch);
  if (!ok) return;
  const c2d_line_history d = c2d_grid_line_history(c2d_problem_grid(p->grid), p->tag_drive);
  double smin = INFINITY, smax = -INFINITY;
  for (size_t q = 0; q < d.nnodes; q++) {
    const double s = d.x[q] * p->how.across[0] + d.y[q] * p->how.across[1];
    smin = fmin(smin, s), smax = fmax(smax, s);
  }
  const double need = p->how.mirror ? 2 * fmax(fabs(smin), fabs(smax)) : smax - smin;
  if (width < need * (1 - 1e-9))
    dk_error(e, doc, W, "particles.width %g cm does not fit the line '%s': it spans %g cm across%s",
             width, d.name, need, p->how.mirror ? " (mirrored about s = 0)" : "");
}

cpl2d_problem *cpl2d_problem_read(dk_doc *doc, const dk_node *sec, const eos_materials *mats,
                                  dk_errors *e) {
  const size_t nerr0 = e->n;
  cpl2d_problem *p = ms_calloc(1, sizeof *p);
  p->mats = mats;
  const char *tag = NULL, *fs_tag = NULL;
  read_sections(p, doc, sec, e, &tag, &fs_tag);
  const dk_node *D = dk_get(sec, "drive");
  if (p->grid && tag && fs_tag) {
    const c2d_grid *g = c2d_problem_grid(p->grid);
    p->tag_drive = find_line(g, tag);
    p->tag_fs = find_line(g, fs_tag);
    if (p->tag_drive == (size_t)-1)
      dk_error(e, doc, dk_get(D, "tag"), "drive.tag: no tag named '%s' in grid.tags", tag);
    if (p->tag_fs == (size_t)-1)
      dk_error(e, doc, dk_get(D, "free_surface_tag"),
               "drive.free_surface_tag: no tag named '%s' in grid.tags", fs_tag);
    if (e->n == nerr0) check_lines(p, doc, dk_get(D, "tag"), dk_get(D, "free_surface_tag"), e);
    if (e->n == nerr0) check_width(p, doc, sec, e);
    /* the drive starts before the grid's end (grid.time.end, read by the grid's reader) */
    double t_grid = INFINITY;
    dk_errors scratch;
    dk_errors_init(&scratch);
    dk_read_double(&scratch, doc, dk_get(dk_get(sec, "grid"), "time"), "end", MS_DIM_TIME, true,
                   INFINITY, 0.0, INFINITY, &t_grid);
    dk_errors_free(&scratch);
    if (e->n == nerr0 && !(p->how.t0 < t_grid))
      dk_error(e, doc, dk_get(D, "t0") ? dk_get(D, "t0") : D,
               "drive.t0 = %g must be before the grid's time.end = %g", p->how.t0, t_grid);
  }
  if (e->n != nerr0) {
    cpl2d_problem_destroy(&p);
    return NULL;
  }
  return p;
}

void cpl2d_problem_destroy(cpl2d_problem **pp) {
  if (!pp || !*pp) return;
  c2d_problem_destroy(&(*pp)->grid);
  ptl_region_params_destroy(&(*pp)->region);
  free(*pp);
  *pp = NULL;
}

/* The sampled columns: every column_every-th node with |s| ≤ column_upto, each averaging the
 * particles' surface layer within half a node spacing of it (both sides of the mirror). */
typedef struct columns {
  size_t n;
  size_t *node;
  double *s, *half, *sum;
  size_t *cnt;
} columns;

static void columns_build(const cpl2d_problem *p, const c2d_line_history *d, columns *c) {
  memset(c, 0, sizeof *c);
  c->node = ms_calloc(d->nnodes, sizeof *c->node);
  c->s = ms_calloc(d->nnodes, sizeof *c->s);
  c->half = ms_calloc(d->nnodes, sizeof *c->half);
  c->sum = ms_calloc(d->nnodes, sizeof *c->sum);
  c->cnt = ms_calloc(d->nnodes, sizeof *c->cnt);
  for (size_t q = 0; q < d->nnodes; q += (size_t)p->column_every) {
    const double s = d->x[q] * p->how.across[0] + d->y[q] * p->how.across[1];
    if (fabs(s) > p->column_upto) continue;
    double h = INFINITY;
    for (int k = -1; k <= 1; k += 2) {
      const long o = (long)q + k;
      if (o < 0 || o >= (long)d->nnodes) continue;
      h = fmin(h, 0.5 * hypot(d->x[o] - d->x[q], d->y[o] - d->y[q]));
    }
    c->node[c->n] = q, c->s[c->n] = s, c->half[c->n] = h, c->n++;
  }
}

static void columns_free(columns *c) {
  free(c->node), free(c->s), free(c->half), free(c->sum), free(c->cnt);
}

/* One CSV row at grid time t: the grid's free-surface velocity along dir at each column's node
 * (linear in time between records) and the particles' (their x velocity). */
static void write_row(FILE *f, const cpl2d_problem *p, ptl_region *r, const c2d_line_history *fs,
                      columns *c, double t, size_t *kf) {
  while (*kf + 2 < fs->n && fs->t[*kf + 1] < t) (*kf)++;
  const size_t k = *kf;
  const double w = fmin(1.0, fmax(0.0, (t - fs->t[k]) / (fs->t[k + 1] - fs->t[k])));
  const ptl_state *ps = ptl_region_state(r);
  memset(c->sum, 0, c->n * sizeof *c->sum);
  memset(c->cnt, 0, c->n * sizeof *c->cnt);
  for (size_t i = 0; i < ps->n; i++) {
    if (!(ps->flags[i] & PTL_SURFACE) || (ps->flags[i] & PTL_REMOVED)) continue;
    const double dy = ps->y[i] - p->how.y0;
    for (size_t m = 0; m < c->n; m++) {
      const bool hit =
          fabs(dy - c->s[m]) <= c->half[m] || (p->how.mirror && fabs(-dy - c->s[m]) <= c->half[m]);
      if (hit) c->sum[m] += ps->vx[i], c->cnt[m]++;
    }
  }
  fprintf(f, "%.9g", ms_out_time(t)); /* µs, as the header says */
  for (size_t m = 0; m < c->n; m++) {
    const size_t a0 = k * fs->nnodes + c->node[m], a1 = a0 + fs->nnodes;
    const double ug0 = fs->u[a0] * p->how.dir[0] + fs->v[a0] * p->how.dir[1],
                 ug1 = fs->u[a1] * p->how.dir[0] + fs->v[a1] * p->how.dir[1];
    fprintf(f, ",%.9g,", (1 - w) * ug0 + w * ug1);
    if (c->cnt[m])
      fprintf(f, "%.9g", c->sum[m] / (double)c->cnt[m]); /* empty: no surface particle */
  }
  fputc('\n', f);
}

static ms_status open_csv(const ms_ctx *ctx, ms_afile *af, const columns *c) {
  char *path = ms_out_path(ctx, "free_surface_columns.csv");
  ms_status st = ms_afile_open(af, path);
  free(path);
  if (st != MS_OK) return st;
  const size_t nc = 1 + 2 * c->n;
  char **names = ms_calloc(nc, sizeof *names);
  const char **units = ms_calloc(nc, sizeof *units);
  names[0] = ms_strdup("t"), units[0] = "10us";
  for (size_t m = 0; m < c->n; m++) {
    char buf[64];
    snprintf(buf, sizeof buf, "u_grid@s=%.6g", c->s[m]);
    names[1 + 2 * m] = ms_strdup(buf);
    snprintf(buf, sizeof buf, "u_particles@s=%.6g", c->s[m]);
    names[2 + 2 * m] = ms_strdup(buf);
    units[1 + 2 * m] = units[2 + 2 * m] = "km/s";
  }
  ms_csv_header(af->f,
                "free-surface velocity along drive.direction per column (s: the column's "
                "coordinate along the line, cm): grid free-surface tag vs particle surface layer",
                nc, (const char *const *)names, units);
  for (size_t k = 0; k < nc; k++) free(names[k]);
  free(names), free(units);
  return MS_OK;
}

static ms_status snapshot(const ms_ctx *ctx, ptl_region *r, long index, const char *material) {
  char name[64];
  ptl_snapshot_name(name, sizeof name, index);
  char *path = ms_out_path(ctx, name);
  const ms_status st = ptl_region_write_snapshot(r, path, material);
  free(path);
  return st;
}

/* The particle phase: region, drive, steps with the CSV rows and snapshots. */
static ms_status run_particles(ms_ctx *ctx, cpl2d_problem *p, const c2d_line_history *d,
                               const c2d_line_history *fs, double t_end) {
  const eos_material *sm = &p->mats->m[p->sample_mat];
  ptl_region *r = NULL;
  ms_status st = ptl_region_create(p->region, ctx, sm->eos, 0.0, p->depth, &r);
  if (st != MS_OK) return st;
  const ptl_region_geometry geo = ptl_region_get_geometry(r);
  cpl_line_drive how = p->how;
  if (how.y0 < 0) {
    double smin = INFINITY;
    for (size_t q = 0; q < d->nnodes; q++)
      smin = fmin(smin, d->x[q] * how.across[0] + d->y[q] * how.across[1]);
    how.y0 = how.mirror ? 0.5 * geo.period[1] : -smin;
  }
  p->how.y0 = how.y0;
  st = cpl_drive_from_line(r, d, &how);
  if (st == MS_OK) st = ptl_region_init(r);
  if (st != MS_OK) {
    ms_log(ctx, MS_LOG_ERROR, "coupled2d: the region could not be driven from '%s' (%s)", d->name,
           ms_status_str(st));
    ptl_region_destroy(&r);
    return st;
  }
  columns c;
  columns_build(p, d, &c);
  ms_afile af;
  st = open_csv(ctx, &af, &c);
  /* the last step ends before the grid's last record, where the free-surface history ends */
  const long nsteps = (long)ceil((t_end - how.t0) / geo.dt) - 1;
  ms_log(ctx, MS_LOG_INFO,
         "coupled2d: 2/2 %zu particles driven by %zu nodes of '%s' from t = %g to %g %s, %ld "
         "steps of %g",
         geo.particles, d->nnodes, d->name, ms_out_time(how.t0), ms_out_time(t_end),
         ms_out_time_label(), nsteps, geo.dt);
  size_t kf = 0;
  long next_out = 0;
  ms_progress prog;
  ms_progress_start(&prog, ctx, "particles", how.t0, t_end);
  for (long step = 0; st == MS_OK && step <= nsteps; step++) {
    const double t = how.t0 + ptl_region_time(r);
    write_row(af.f, p, r, fs, &c, t, &kf);
    if (step >= next_out * nsteps / p->n_out) st = snapshot(ctx, r, next_out++, sm->name);
    if (st != MS_OK || step == nsteps) break;
    st = ptl_region_step(r);
    if (st != MS_OK) {
      ms_log(ctx, MS_LOG_ERROR, "coupled2d: particles (clock started at t = %g %s): %s",
             ms_out_time(how.t0), ms_out_time_label(),
             st == MS_ERR_UNSTABLE ? ptl_region_error(r) : ms_status_str(st));
      char *path = ms_out_path(ctx, PTL_SNAPSHOT_UNSTABLE);
      if (ptl_region_write_snapshot(r, path, sm->name) == MS_OK)
        ms_log(ctx, MS_LOG_ERROR, "coupled2d: final state written to " PTL_SNAPSHOT_UNSTABLE);
      free(path);
    } else ms_progress_update(&prog, how.t0 + ptl_region_time(r), step + 1);
  }
  ms_progress_finish(&prog, how.t0 + ptl_region_time(r), nsteps);
  if (af.f) {
    if (st == MS_OK) st = ms_afile_commit(&af);
    else ms_afile_abort(&af);
  }
  if (st == MS_OK)
    ms_log(ctx, MS_LOG_INFO,
           "coupled2d: wrote %ld particle snapshots (particles.xmf) and the free-surface velocity "
           "of %zu columns (free_surface_columns.csv)",
           next_out, c.n);
  columns_free(&c);
  ptl_region_destroy(&r);
  return st;
}

ms_status cpl2d_problem_run(ms_ctx *ctx, cpl2d_problem *p) {
  if (ctx->size > 1) { /* the grid runs on rank 0 only; the region is not distributed here */
    ms_log(ctx, MS_LOG_ERROR, "coupled2d: runs on one rank only (mpirun -np 1)");
    return MS_ERR_INPUT;
  }
  ms_log(ctx, MS_LOG_INFO, "coupled2d: 1/2 grid run (the tagged line's history)");
  ms_status st = c2d_problem_run(ctx, p->grid);
  if (st != MS_OK) return st;
  const c2d_grid *g = c2d_problem_grid(p->grid);
  const c2d_line_history d = c2d_grid_line_history(g, p->tag_drive),
                         fs = c2d_grid_line_history(g, p->tag_fs);
  const double t_end = d.t[d.n - 1];
  if (!(p->how.t0 < t_end) || d.n < 2) {
    ms_log(ctx, MS_LOG_ERROR, "coupled2d: drive.t0 = %g %s is not before the grid's end %g",
           ms_out_time(p->how.t0), ms_out_time_label(), ms_out_time(t_end));
    return MS_ERR_INPUT;
  }
  return run_particles(ctx, p, &d, &fs, t_end);
}
