/* SPDX-License-Identifier: MIT */
/* grid2d_blocks.c — `mesh: {blocks: [...]}` of the grid2d deck (docs/continuum2d.md §8):
 * logical-rectangle blocks, each a (graded, skewed) rectangle or a polar sector over its own
 * node ranges [i0, i1] × [j0, j1] of the grid's one logical (i, j) mesh, with its own material
 * and state. The blocks must tile the logical rectangle (no overlap, no gap), agree on every
 * node they share, leave every zone with positive area (r ≥ 0 in r–z) and not overlap in space;
 * each problem is a located deck error at the block. */
#include "grid2d_deck_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

void c2d_deck_mesh_alloc(c2d_deck_mesh *m, long ni, long nj) {
  const size_t nn = (size_t)(ni + 1) * (size_t)(nj + 1), nz = (size_t)ni * (size_t)nj;
  m->ni = ni, m->nj = nj;
  m->x = ms_calloc(nn, sizeof *m->x), m->y = ms_calloc(nn, sizeof *m->y);
  m->u = ms_calloc(nn, sizeof *m->u), m->v = ms_calloc(nn, sizeof *m->v);
  m->rho = ms_calloc(nz, sizeof *m->rho), m->en = ms_calloc(nz, sizeof *m->en);
  m->eos = ms_calloc(nz, sizeof *m->eos), m->mid = ms_calloc(nz, sizeof *m->mid);
}

void c2d_deck_mesh_free(c2d_deck_mesh *m) {
  free(m->x), free(m->y), free(m->u), free(m->v);
  free(m->rho), free(m->en), free(m->eos), free(m->mid);
  memset(m, 0, sizeof *m);
}

enum { BLOCK_RECT = 0, BLOCK_POLAR };

typedef struct c2d_block {
  const dk_node *node;
  bool valid;
  int type;
  long i0, i1, j0, j1;
  double x[2], y[2], r[2], th[2], grade[2], skew;
  const eos_material *mat;
  double rho, e, p; /* NAN if not given */
  bool has_vel;
  double vel[2];
} c2d_block;

/* Node k of n intervals on [a, b] whose successive sizes grow by `ratio` (1: uniform); the end
 * nodes are exactly a and b, so blocks that share an edge give the same coordinates. */
static double graded(double a, double b, long n, double ratio, long k) {
  if (k == 0) return a;
  if (k == n) return b;
  if (ratio == 1.0) return a + (b - a) * (double)k / (double)n;
  return a + (b - a) * (pow(ratio, (double)k) - 1.0) / (pow(ratio, (double)n) - 1.0);
}

/* Position of node (i, j) (global indices inside the block's range). A rectangle's skew moves x
 * by skew · (j1 − j) Δy sin(π (i − i0)/(i1 − i0)), as the single `rect` mesh does; a polar
 * sector's radius runs along i, its angle (degrees) along j. */
static void block_node(const c2d_block *b, long i, long j, double *x, double *y) {
  const long ni = b->i1 - b->i0, nj = b->j1 - b->j0, ki = i - b->i0, kj = j - b->j0;
  if (b->type == BLOCK_POLAR) {
    const double r = graded(b->r[0], b->r[1], ni, b->grade[0], ki);
    const double th = graded(b->th[0], b->th[1], nj, b->grade[1], kj) * PI / 180.0;
    const double cs = cos(th), sn = sin(th);
    /* exact zeros on the axes, as c2d_mesh_polar */
    *x = fabs(cs) < 1e-15 ? 0.0 : r * cs;
    *y = fabs(sn) < 1e-15 ? 0.0 : r * sn;
    return;
  }
  *x = graded(b->x[0], b->x[1], ni, b->grade[0], ki);
  *y = graded(b->y[0], b->y[1], nj, b->grade[1], kj);
  if (b->skew != 0.0)
    *x += b->skew * (double)(nj - kj) * (b->y[1] - b->y[0]) / (double)nj *
          sin(PI * (double)ki / (double)ni);
}

static bool read_pair(dk_errors *e, dk_doc *doc, const dk_node *map, const char *key, ms_dim dim,
                      bool required, double def, double out[2]) {
  out[0] = out[1] = def;
  if (!dk_get(map, key)) {
    if (required) dk_error(e, doc, map, "block: %s: required ([from, to])", key);
    return !required;
  }
  double *v = NULL;
  size_t n = 0;
  bool ok = dk_read_double_list(e, doc, map, key, dim, true, &v, &n);
  if (ok && n == 2) out[0] = v[0], out[1] = v[1];
  else if (ok) dk_error(e, doc, dk_get(map, key), "block: %s: expected [from, to]", key);
  free(v);
  return ok && n == 2;
}

/* The block's node ranges `i: [i0, i1]`, `j: [j0, j1]`: integers, 0 ≤ first < last. */
static bool read_ranges(dk_errors *e, dk_doc *doc, const dk_node *bn, c2d_block *b) {
  double ir[2], jr[2];
  bool ok = read_pair(e, doc, bn, "i", MS_DIM_NONE, true, 0, ir);
  ok = read_pair(e, doc, bn, "j", MS_DIM_NONE, true, 0, jr) && ok;
  if (!ok) return false;
  const double lim = 1e8;
  for (int k = 0; k < 2; ++k)
    if (!(fabs(ir[k]) < lim && fabs(jr[k]) < lim)) ok = false;
  if (ok)
    b->i0 = lround(ir[0]), b->i1 = lround(ir[1]), b->j0 = lround(jr[0]), b->j1 = lround(jr[1]);
  if (!ok || b->i0 < 0 || b->j0 < 0 || b->i1 <= b->i0 || b->j1 <= b->j0 || ir[0] != (double)b->i0 ||
      ir[1] != (double)b->i1 || jr[0] != (double)b->j0 || jr[1] != (double)b->j1) {
    dk_error(e, doc, bn,
             "block: i and j must be integer node ranges [first, last], 0 <= first < last");
    return false;
  }
  return true;
}

static void read_block_state(dk_errors *e, dk_doc *doc, const dk_node *bn,
                             const eos_materials *mats, c2d_block *b) {
  const char *mname = NULL;
  if (dk_get(bn, "material") && dk_read_string(e, doc, bn, "material", true, NULL, &mname))
    b->mat = eos_materials_find(mats, mname, e, doc, dk_get(bn, "material"));
  if (dk_get(bn, "density"))
    dk_read_positive(e, doc, bn, "density", MS_DIM_DENSITY, true, 1, &b->rho);
  if (dk_get(bn, "pressure") && dk_get(bn, "energy"))
    dk_error(e, doc, bn, "block: give at most one of pressure, energy");
  if (dk_get(bn, "pressure"))
    dk_read_double(e, doc, bn, "pressure", MS_DIM_PRESSURE, true, 0, -INFINITY, INFINITY, &b->p);
  if (dk_get(bn, "energy"))
    dk_read_double(e, doc, bn, "energy", MS_DIM_SPEC_ENERGY, true, 0, -INFINITY, INFINITY, &b->e);
  if (dk_get(bn, "velocity"))
    b->has_vel = read_pair(e, doc, bn, "velocity", MS_DIM_VELOCITY, true, 0, b->vel);
}

static void read_block(dk_errors *e, dk_doc *doc, const dk_node *bn, const eos_materials *mats,
                       c2d_block *b) {
  memset(b, 0, sizeof *b);
  b->node = bn;
  b->rho = b->e = b->p = NAN;
  b->grade[0] = b->grade[1] = 1.0;
  if (!dk_expect_map(e, doc, bn, "block")) return;
  static const char *const types[] = {"rect", "polar", NULL};
  dk_read_enum(e, doc, bn, "type", false, BLOCK_RECT, types, &b->type);
  bool ok = read_ranges(e, doc, bn, b);
  if (b->type == BLOCK_RECT) {
    ok = read_pair(e, doc, bn, "x", MS_DIM_LENGTH, true, 0, b->x) && ok;
    ok = read_pair(e, doc, bn, "y", MS_DIM_LENGTH, true, 0, b->y) && ok;
    ok = dk_read_double(e, doc, bn, "skew", MS_DIM_NONE, false, 0, -INFINITY, INFINITY, &b->skew) &&
         ok;
  } else {
    ok = read_pair(e, doc, bn, "r", MS_DIM_LENGTH, true, 0, b->r) && ok;
    ok = read_pair(e, doc, bn, "theta", MS_DIM_NONE, true, 0, b->th) && ok; /* degrees */
  }
  if (read_pair(e, doc, bn, "grade", MS_DIM_NONE, false, 1.0, b->grade) &&
      (!(b->grade[0] > 0 && b->grade[0] < 1e3) || !(b->grade[1] > 0 && b->grade[1] < 1e3))) {
    dk_error(e, doc, dk_get(bn, "grade"), "block: grade: ratios must be in (0, 1000)");
    ok = false;
  }
  read_block_state(e, doc, bn, mats, b);
  b->valid = ok;
}

/* Zone owners: every zone of [0, ni) × [0, nj) in exactly one block (else a located error). */
static bool tile(dk_errors *e, dk_doc *doc, const dk_node *blocks, const c2d_block *b, size_t nb,
                 long ni, long nj, int *owner) {
  bool ok = true;
  for (long z = 0; z < ni * nj; ++z) owner[z] = -1;
  for (size_t k = 0; k < nb; ++k) {
    bool reported = false;
    for (long j = b[k].j0; j < b[k].j1; ++j)
      for (long i = b[k].i0; i < b[k].i1; ++i) {
        int *o = &owner[i + ni * j];
        if (*o >= 0 && !reported) {
          dk_error(e, doc, b[k].node, "block %zu overlaps block %d at zone (i = %ld, j = %ld)", k,
                   *o, i, j);
          ok = false, reported = true;
        }
        if (*o < 0) *o = (int)k;
      }
  }
  for (long z = 0; z < ni * nj && ok; ++z)
    if (owner[z] < 0) {
      dk_error(e, doc, blocks,
               "blocks: zone (i = %ld, j = %ld) is in no block (a gap: the blocks must tile the "
               "logical rectangle [0, %ld) x [0, %ld) of zones)",
               z % ni, z / ni, ni, nj);
      ok = false;
    }
  return ok;
}

/* Node positions; a node shared by blocks must agree (to 1e-12 of the blocks' size), else a
 * located error (the blocks do not meet: a gap in space). first[n]: the first block holding n. */
static bool place_nodes(dk_errors *e, dk_doc *doc, const c2d_block *b, size_t nb, c2d_deck_mesh *m,
                        int *first) {
  const long ni = m->ni, nn = (ni + 1) * (m->nj + 1);
  for (long n = 0; n < nn; ++n) first[n] = -1;
  bool ok = true;
  for (size_t k = 0; k < nb; ++k) {
    const c2d_block *bk = &b[k];
    double scale = bk->type == BLOCK_POLAR ? fabs(bk->r[1]) + fabs(bk->r[0])
                                           : fabs(bk->x[1] - bk->x[0]) + fabs(bk->y[1] - bk->y[0]);
    bool reported = false;
    for (long j = bk->j0; j <= bk->j1; ++j)
      for (long i = bk->i0; i <= bk->i1; ++i) {
        const long n = i + (ni + 1) * j;
        double xn, yn;
        block_node(bk, i, j, &xn, &yn);
        if (first[n] < 0) {
          m->x[n] = xn, m->y[n] = yn, first[n] = (int)k;
        } else if (!reported && hypot(xn - m->x[n], yn - m->y[n]) > 1e-12 * scale) {
          dk_error(e, doc, bk->node,
                   "blocks %d and %zu do not meet at node (i = %ld, j = %ld): (%g, %g) vs "
                   "(%g, %g) (a gap or an overlap between them)",
                   first[n], k, i, j, m->x[n], m->y[n], xn, yn);
          ok = false, reported = true;
        }
      }
  }
  return ok;
}

/* Zone states (material, density, energy from the block's pressure through its EOS) and node
 * velocities (the first block holding the node; else the section's). */
static bool fill_state(dk_errors *e, dk_doc *doc, const c2d_block *b, size_t nb,
                       const eos_materials *mats, const c2d_deck_defaults *def, const int *first,
                       c2d_deck_mesh *m) {
  bool ok = true;
  for (size_t k = 0; k < nb; ++k) {
    const c2d_block *bk = &b[k];
    const eos_material *mat = bk->mat ? bk->mat : def->mat;
    const double r = isnan(bk->rho) ? def->rho : bk->rho;
    if (!mat || isnan(r)) {
      dk_error(e, doc, bk->node, "block %zu: %s: required (in the block or in grid2d)", k,
               mat ? "density" : "material");
      ok = false;
      continue;
    }
    /* energy: the block's, or from its pressure, or the section's for the section's material,
     * or the block material's reference energy */
    double en = !isnan(bk->e) ? bk->e : (mat == def->mat ? def->e : eos_e0(mat->eos));
    if (!isnan(bk->p) && !cont_energy_from_pressure(mat->eos, r, bk->p, &en)) {
      dk_error(e, doc, bk->node, "block %zu: no energy gives pressure %g at density %g", k, bk->p,
               r);
      ok = false;
      continue;
    }
    for (long j = bk->j0; j < bk->j1; ++j)
      for (long i = bk->i0; i < bk->i1; ++i) {
        const long z = i + m->ni * j;
        m->rho[z] = r, m->en[z] = en, m->eos[z] = mat->eos, m->mid[z] = (int)(mat - mats->m);
      }
  }
  const long nn = (m->ni + 1) * (m->nj + 1);
  for (long n = 0; n < nn; ++n) {
    const c2d_block *bk = &b[first[n]];
    const double rr = hypot(m->x[n], m->y[n]);
    m->u[n] = bk->has_vel ? bk->vel[0] : def->vel[0] + (rr > 0 ? def->vrad * m->x[n] / rr : 0);
    m->v[n] = bk->has_vel ? bk->vel[1] : def->vel[1] + (rr > 0 ? def->vrad * m->y[n] / rr : 0);
  }
  return ok;
}

/* Every zone with positive area (counter-clockwise, untangled) and every node at r ≥ 0 in r–z,
 * else a located error at the block that holds it (the first problem of each block). */
static bool check_zones(dk_errors *e, dk_doc *doc, const c2d_block *b, size_t nb, c2d_geometry geo,
                        const c2d_deck_mesh *m, const int *owner, const int *first) {
  const long ni = m->ni, w = ni + 1;
  bool ok = true;
  char *told = ms_calloc(nb, 1);
  for (long z = 0; z < ni * m->nj; ++z) {
    const long i = z % ni, j = z / ni, a = i + w * j;
    const long nd[4] = {a, a + 1, a + 1 + w, a + w};
    double X[4], Y[4];
    for (int k = 0; k < 4; ++k) X[k] = m->x[nd[k]], Y[k] = m->y[nd[k]];
    const double area = 0.5 * ((X[0] - X[2]) * (Y[1] - Y[3]) - (X[1] - X[3]) * (Y[0] - Y[2]));
    /* a convex or concave quad splits along one of its diagonals into two positive triangles
     * (the corner triangles k−1, k, k+1 of corners 0, 2 or of 1, 3; ≥ 0: a polar centre
     * zone is a triangle); a tangled ("bow-tie") one
     * does not, even when its total area is positive */
    double cr[4];
    for (int k = 0; k < 4; ++k) {
      const int kn = (k + 1) & 3, kp = (k + 3) & 3;
      cr[k] = (X[kn] - X[k]) * (Y[kp] - Y[k]) - (Y[kn] - Y[k]) * (X[kp] - X[k]);
    }
    const bool corner_bad = !((cr[0] >= 0 && cr[2] >= 0) || (cr[1] >= 0 && cr[3] >= 0));
    const int k = owner[z];
    if ((!(area > 0) || corner_bad) && !told[k]) {
      dk_error(e, doc, b[k].node,
               "block %d: zone (i = %ld, j = %ld) is tangled or inverted (area %g; nodes must "
               "run counter-clockwise: x grows with i, y with j)",
               k, i, j, area);
      told[k] = 1, ok = false;
    }
  }
  for (long n = 0; geo == C2D_RZ && n < w * (m->nj + 1); ++n)
    if (m->x[n] < 0 && !told[first[n]]) {
      dk_error(e, doc, b[first[n]].node, "block %d: node (i = %ld, j = %ld) has r = %g < 0 (r–z)",
               first[n], n % w, n / w, m->x[n]);
      told[first[n]] = 1, ok = false;
    }
  free(told);
  return ok;
}

static double orient(const double *a, const double *b, const double *c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Segments pq and rs cross (a proper crossing, or collinear with a common stretch); touching
 * at an end point is not a crossing. eps: what counts as collinear (length² scale). */
static bool segments_cross(const double *p, const double *q, const double *r, const double *s,
                           double eps) {
  const double d1 = orient(p, q, r), d2 = orient(p, q, s), d3 = orient(r, s, p),
               d4 = orient(r, s, q);
  const int s1 = (d1 > eps) - (d1 < -eps), s2 = (d2 > eps) - (d2 < -eps),
            s3 = (d3 > eps) - (d3 < -eps), s4 = (d4 > eps) - (d4 < -eps);
  if (s1 * s2 < 0 && s3 * s4 < 0) return true;
  if (s1 || s2 || s3 || s4) return false;
  /* collinear: overlap of the projections on the longer axis, beyond a point */
  const int ax =
      fabs(q[0] - p[0]) + fabs(s[0] - r[0]) >= fabs(q[1] - p[1]) + fabs(s[1] - r[1]) ? 0 : 1;
  const double lo = fmax(fmin(p[ax], q[ax]), fmin(r[ax], s[ax]));
  const double hi = fmin(fmax(p[ax], q[ax]), fmax(r[ax], s[ax]));
  return hi - lo > sqrt(eps);
}

/* With every zone positive, the mesh covers each point as often as its outer boundary winds
 * around it; so the blocks overlap in space exactly when the boundary loop crosses itself. The
 * loop runs jlo, ihi, jhi, ilo; repeated points (a polar block's degenerate centre) are merged. */
static bool check_overlap(dk_errors *e, dk_doc *doc, const c2d_block *b, const c2d_deck_mesh *m,
                          const int *owner) {
  const long ni = m->ni, nj = m->nj, w = ni + 1, nl = 2 * (ni + nj);
  double *pt = ms_calloc(2 * (size_t)nl, sizeof *pt);
  int *blk = ms_calloc((size_t)nl, sizeof *blk); /* block of the segment starting at point k */
  long np = 0;
  double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
  for (long k = 0; k < nl; ++k) {
    long i, j, zi, zj; /* the node, and the zone holding the segment from it */
    if (k < ni) i = k, j = 0, zi = k, zj = 0;
    else if (k < ni + nj) i = ni, j = k - ni, zi = ni - 1, zj = j;
    else if (k < 2 * ni + nj) i = 2 * ni + nj - k, j = nj, zi = i - 1, zj = nj - 1;
    else i = 0, j = nl - k, zi = 0, zj = j - 1;
    const double px = m->x[i + w * j], py = m->y[i + w * j];
    xmin = fmin(xmin, px), xmax = fmax(xmax, px), ymin = fmin(ymin, py), ymax = fmax(ymax, py);
    if (np > 0 && px == pt[2 * (np - 1)] && py == pt[2 * (np - 1) + 1]) continue;
    pt[2 * np] = px, pt[2 * np + 1] = py, blk[np] = owner[zi + ni * zj], np++;
  }
  while (np > 1 && pt[0] == pt[2 * (np - 1)] && pt[1] == pt[2 * (np - 1) + 1]) np--;
  const double L = fmax(xmax - xmin, ymax - ymin), eps = 1e-14 * L * L;
  bool ok = true;
  for (long a = 0; a < np && ok; ++a)
    for (long c = a + 2; c < np && ok; ++c) {
      if (a == 0 && c == np - 1) continue; /* adjacent through the loop's closure */
      const double *p = &pt[2 * a], *q = &pt[2 * ((a + 1) % np)];
      const double *r = &pt[2 * c], *s = &pt[2 * ((c + 1) % np)];
      if (!segments_cross(p, q, r, s, eps)) continue;
      const int ba = blk[a] < blk[c] ? blk[a] : blk[c], bc = blk[a] < blk[c] ? blk[c] : blk[a];
      dk_error(e, doc, b[bc].node,
               "block %d overlaps block %d in space: the mesh's outer boundary crosses itself "
               "near (%g, %g)",
               bc, ba, 0.5 * (r[0] + s[0]), 0.5 * (r[1] + s[1]));
      ok = false;
    }
  free(pt);
  free(blk);
  return ok;
}

bool c2d_blocks_build(dk_errors *e, dk_doc *doc, const dk_node *blocks, const eos_materials *mats,
                      c2d_geometry geo, const c2d_deck_defaults *def, c2d_deck_mesh *out) {
  memset(out, 0, sizeof *out);
  if (!dk_expect_seq(e, doc, blocks, "blocks")) return false;
  const size_t nb = dk_seq_len(blocks);
  if (nb == 0) {
    dk_error(e, doc, blocks, "blocks: give at least one block");
    return false;
  }
  c2d_block *b = ms_calloc(nb, sizeof *b);
  bool ok = true;
  long ni = 0, nj = 0;
  for (size_t k = 0; k < nb; ++k) {
    read_block(e, doc, dk_seq_at(blocks, k), mats, &b[k]);
    ok = ok && b[k].valid;
    if (b[k].valid) ni = b[k].i1 > ni ? b[k].i1 : ni, nj = b[k].j1 > nj ? b[k].j1 : nj;
  }
  if (ok) {
    c2d_deck_mesh_alloc(out, ni, nj);
    int *owner = ms_calloc((size_t)(ni * nj), sizeof *owner);
    int *first = ms_calloc((size_t)((ni + 1) * (nj + 1)), sizeof *first);
    ok = tile(e, doc, blocks, b, nb, ni, nj, owner) && place_nodes(e, doc, b, nb, out, first);
    ok = ok && fill_state(e, doc, b, nb, mats, def, first, out);
    ok = ok && check_zones(e, doc, b, nb, geo, out, owner, first);
    ok = ok && check_overlap(e, doc, b, out, owner);
    free(owner);
    free(first);
    if (!ok) c2d_deck_mesh_free(out);
  }
  free(b);
  return ok;
}
