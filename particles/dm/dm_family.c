/* SPDX-License-Identifier: MIT */
/* dm_family.c — families of the Hamiltonian discrete model ([Sofronov] §1, §3; docs/design.md §5.2).
 *
 * N_i = {k ≠ i : |X_k − X_i| < δ_r} in the reference configuration, built once with a cell
 * list of cell size ≥ δ_r (periodic axes wrap, recording which image a neighbour came from),
 * stored in CSR form sorted by neighbour index. Then A_i = Σ ξ⊗ξ is inverted on the dim×dim
 * block through its eigen-decomposition so that its condition number is known: a singular or
 * ill-conditioned A_i is an input error (with the particle's position), never inverted.
 */
#include "dm_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations (a is destroyed;
 * eigenvalues in lam, eigenvectors in the columns of v). Set-up only, so simplicity wins. */
static void jacobi_eigen3(double a[3][3], double lam[3], double v[3][3]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) v[i][j] = (i == j);
  for (int sweep = 0; sweep < 60; ++sweep) {
    double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
    double scale = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
    if (off <= 1e-300 || off < 1e-17 * scale) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
        double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < 3; ++k) { /* columns p, q */
          double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) { /* rows p, q */
          double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  for (int i = 0; i < 3; ++i) lam[i] = a[i][i];
}

/* Inverse of the dim×dim block of symmetric A (row-major 9) into inv; returns the condition
 * number λmax/λmin (INFINITY if singular or not positive definite). */
double dm_sym_inverse(int dim, const double *A, double *inv) {
  double a[3][3] = {{0}}, v[3][3], lam[3] = {0, 0, 0};
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) a[i][j] = A[3 * i + j];
  for (int i = dim; i < 3; ++i) a[i][i] = 1.0; /* unused block: identity, ignored below */
  jacobi_eigen3(a, lam, v);
  memset(inv, 0, 9 * sizeof(double));
  double lmax = 0.0, lmin = INFINITY;
  /* Only the eigenvectors lying in the used block belong to A's dim×dim part. */
  for (int e = 0; e < 3; ++e) {
    double out = 0.0;
    for (int i = dim; i < 3; ++i) out += v[i][e] * v[i][e];
    if (out > 0.5) continue;
    if (lam[e] > lmax) lmax = lam[e];
    if (lam[e] < lmin) lmin = lam[e];
  }
  if (!(lmin > 0.0) || !(lmax > 0.0)) return INFINITY;
  double cond = lmax / lmin;
  for (int e = 0; e < 3; ++e) {
    double out = 0.0;
    for (int i = dim; i < 3; ++i) out += v[i][e] * v[i][e];
    if (out > 0.5) continue;
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) inv[3 * i + j] += v[i][e] * v[j][e] / lam[e];
  }
  return cond;
}

typedef struct cell_grid {
  int nc[3];          /* cells per axis */
  double lo[3], w[3]; /* origin and cell width */
  int periodic[3];
  size_t *cstart;  /* [ncell+1] */
  uint32_t *cpart; /* particles sorted by cell */
} cell_grid;

static size_t cell_of(const cell_grid *g, const double *x) {
  size_t idx = 0;
  for (int a = 2; a >= 0; --a) {
    int c = (int)floor((x[a] - g->lo[a]) / g->w[a]);
    if (c < 0) c = 0;
    if (c >= g->nc[a]) c = g->nc[a] - 1;
    idx = idx * (size_t)g->nc[a] + (size_t)c;
  }
  return idx;
}

static ms_status grid_build(cell_grid *g, const dm_state *s, const dm_options *opt,
                            const ms_ctx *ctx) {
  const double h = opt->horizon;
  size_t ncell = 1;
  for (int a = 0; a < 3; ++a) {
    g->periodic[a] = opt->box[a] > 0.0;
    if (g->periodic[a]) {
      if (opt->box[a] < 3.0 * h) {
        ms_log(ctx, MS_LOG_ERROR,
               "discrete model: periodic length %g along axis %d is shorter than 3 horizons (%g)",
               opt->box[a], a, 3.0 * h);
        return MS_ERR_INPUT;
      }
      g->lo[a] = 0.0;
      g->nc[a] = (int)floor(opt->box[a] / h);
      g->w[a] = opt->box[a] / g->nc[a];
    } else {
      double lo = INFINITY, hi = -INFINITY;
      for (size_t i = 0; i < s->n; ++i) {
        lo = fmin(lo, s->X[3 * i + a]);
        hi = fmax(hi, s->X[3 * i + a]);
      }
      g->lo[a] = lo;
      double ext = hi - lo;
      int nc = (int)floor(ext / h);
      if (nc < 1) nc = 1;
      if (nc > 4096) nc = 4096;
      g->nc[a] = nc;
      g->w[a] = ext > 0 ? ext / nc * (1.0 + 1e-12) : 1.0;
      if (g->w[a] < h && nc > 1) g->w[a] = h; /* never narrower than the horizon */
    }
    ncell *= (size_t)g->nc[a];
  }
  g->cstart = ms_calloc(ncell + 1, sizeof(size_t));
  g->cpart = ms_calloc(s->n ? s->n : 1, sizeof(uint32_t));
  size_t *cid = ms_calloc(s->n ? s->n : 1, sizeof(size_t));
  for (size_t i = 0; i < s->n; ++i) {
    cid[i] = cell_of(g, &s->X[3 * i]);
    g->cstart[cid[i] + 1]++;
  }
  for (size_t c = 0; c < ncell; ++c) g->cstart[c + 1] += g->cstart[c];
  size_t *fill = ms_calloc(ncell, sizeof(size_t));
  for (size_t i = 0; i < s->n; ++i) g->cpart[g->cstart[cid[i]] + fill[cid[i]]++] = (uint32_t)i;
  free(fill);
  free(cid);
  return MS_OK;
}

/* Visit the neighbours of particle i: count (out == NULL) or write them. */
static size_t visit_family(const cell_grid *g, const dm_state *s, const dm_model *m, size_t i,
                           uint32_t *nbr, uint8_t *img) {
  if (m->opt.ghost_rows && s->bc[i] == DM_MIRROR) return 0; /* rows filled by the model */
  const double h2 = m->opt.horizon * m->opt.horizon;
  const double *xi = &s->X[3 * i];
  int ci[3];
  for (int a = 0; a < 3; ++a) {
    int c = (int)floor((xi[a] - g->lo[a]) / g->w[a]);
    if (c < 0) c = 0;
    if (c >= g->nc[a]) c = g->nc[a] - 1;
    ci[a] = c;
  }
  size_t cnt = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        int d[3] = {dx, dy, dz}, cc[3], im[3] = {0, 0, 0};
        int skip = 0;
        for (int a = 0; a < 3; ++a) {
          cc[a] = ci[a] + d[a];
          if (cc[a] < 0 || cc[a] >= g->nc[a]) {
            if (!g->periodic[a]) {
              skip = 1;
              break;
            }
            /* Wrapped cell: the neighbour's image is shifted by ∓box. */
            im[a] = cc[a] < 0 ? -1 : 1;
            cc[a] = (cc[a] + g->nc[a]) % g->nc[a];
          }
        }
        if (skip) continue;
        size_t c =
            ((size_t)cc[2] * (size_t)g->nc[1] + (size_t)cc[1]) * (size_t)g->nc[0] + (size_t)cc[0];
        int code = (im[0] + 1) + 3 * (im[1] + 1) + 9 * (im[2] + 1);
        for (size_t p = g->cstart[c]; p < g->cstart[c + 1]; ++p) {
          uint32_t k = g->cpart[p];
          if (k == i && code == 13) continue;
          double r2 = 0.0;
          for (int a = 0; a < 3; ++a) {
            double dd = s->X[3 * k + a] + m->shift[code][a] - xi[a];
            r2 += dd * dd;
          }
          if (r2 < h2) {
            if (nbr) {
              nbr[cnt] = k;
              img[cnt] = (uint8_t)code;
            }
            ++cnt;
          }
        }
      }
  return cnt;
}

/* Sort one family by (neighbour, image): a fixed summation order, cache-friendly gathers. */
static void sort_family(uint32_t *nbr, uint8_t *img, size_t n) {
  for (size_t a = 1; a < n; ++a) { /* insertion sort: families are short and nearly sorted */
    uint32_t k = nbr[a];
    uint8_t c = img[a];
    size_t b = a;
    while (b > 0 && (nbr[b - 1] > k || (nbr[b - 1] == k && img[b - 1] > c))) {
      nbr[b] = nbr[b - 1];
      img[b] = img[b - 1];
      --b;
    }
    nbr[b] = k;
    img[b] = c;
  }
}

ms_status dm_build_families(dm_model *m, const ms_ctx *ctx) {
  dm_state *s = m->s;
  for (int code = 0; code < 27; ++code) {
    int im[3] = {code % 3 - 1, (code / 3) % 3 - 1, code / 9 - 1};
    for (int a = 0; a < 3; ++a) m->shift[code][a] = m->shift4[code][a] = im[a] * m->opt.box[a];
    m->shift4[code][3] = 0.0;
  }
  cell_grid g;
  memset(&g, 0, sizeof g);
  ms_status st = grid_build(&g, s, &m->opt, ctx);
  if (st != MS_OK) {
    free(g.cstart);
    free(g.cpart);
    return st;
  }
  const long n = (long)s->n;
  m->start = ms_calloc(s->n + 1, sizeof(size_t));
#pragma omp parallel for schedule(dynamic, 256)
  for (long i = 0; i < n; ++i) m->start[i + 1] = visit_family(&g, s, m, (size_t)i, NULL, NULL);
  for (size_t i = 0; i < s->n; ++i) m->start[i + 1] += m->start[i];
  m->nbonds = m->start[s->n];
  m->nbr = ms_calloc(m->nbonds ? m->nbonds : 1, sizeof(uint32_t));
  m->img = ms_calloc(m->nbonds ? m->nbonds : 1, sizeof(uint8_t));
#pragma omp parallel for schedule(dynamic, 256)
  for (long i = 0; i < n; ++i) {
    size_t b0 = m->start[i];
    size_t cnt = visit_family(&g, s, m, (size_t)i, &m->nbr[b0], &m->img[b0]);
    sort_family(&m->nbr[b0], &m->img[b0], cnt);
  }
  free(g.cstart);
  free(g.cpart);
  return MS_OK;
}

ms_status dm_build_shape(dm_model *m, const ms_ctx *ctx, size_t *first_bad) {
  dm_state *s = m->s;
  const int dim = s->dim;
  const long n = (long)s->n;
  double cmax = m->opt.cond_max > 0 ? m->opt.cond_max : 1e8;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    if (m->opt.ghost_rows && s->bc[i] == DM_MIRROR) { /* no shape of its own */
      memset(&m->Ainv[9 * i], 0, 9 * sizeof(double));
      m->cond[i] = 1.0, m->kappa[i] = 0.0;
      continue;
    }
    double A[9] = {0};
    for (size_t b = m->start[i]; b < m->start[i + 1]; ++b) {
      double xi[3];
      dm_bond_vector(m, (size_t)i, b, xi);
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c) A[3 * a + c] += xi[a] * xi[c];
    }
    m->cond[i] = dm_sym_inverse(dim, A, &m->Ainv[9 * i]);
    double trA = A[0] + A[4] + A[8];
    m->kappa[i] =
        (m->opt.hourglass > 0 && trA > 0) ? m->opt.hourglass * s->G[i] * s->vol[i] / trA : 0.0;
  }
  size_t nbad = 0;
  for (size_t i = 0; i < s->n; ++i) {
    if (m->cond[i] <= cmax) continue;
    if (nbad == 0 && first_bad) *first_bad = i;
    if (nbad < 20)
      ms_log(ctx, MS_LOG_ERROR,
             "discrete model: particle %zu at (%g, %g, %g) has a singular or ill-conditioned "
             "shape matrix A (%zu neighbours, condition number %.3g > %.3g): too few or "
             "coplanar neighbours within the horizon %g",
             i, s->X[3 * i], s->X[3 * i + 1], s->X[3 * i + 2], m->start[i + 1] - m->start[i],
             m->cond[i], cmax, m->opt.horizon);
    ++nbad;
  }
  if (nbad) {
    if (nbad > 20) ms_log(ctx, MS_LOG_ERROR, "discrete model: ... %zu such particles in all", nbad);
    return MS_ERR_INPUT;
  }
  return MS_OK;
}
