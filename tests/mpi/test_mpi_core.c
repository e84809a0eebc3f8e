/* SPDX-License-Identifier: MIT */
/* The MPI layer and parallel HDF5: reductions agree with the serial formula (the fixed-order sum
 * bit for bit with the rank-order sum), and a dataset written collectively by any number of
 * ranks holds the same bytes as a serial write. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core.h"
#include "mpi_check.h"

/* Global row i of the test dataset: three components that identify it exactly. */
static void row_values(size_t i, double *v) {
  v[0] = (double)i;
  v[1] = 0.5 * (double)i + 1.0;
  v[2] = -(double)i * (double)i;
}

int main(int argc, char **argv) {
  ms_ctx ctx;
  ms_ctx_init_serial(&ctx);
  if (par_init(&argc, &argv, &ctx)) return 1;
  const int r = ctx.rank, p = ctx.size;

  /* reductions: exact for these integers in double precision */
  CHECK(par_sum_double((double)(r + 1)) == p * (p + 1) / 2.0, "sum");
  CHECK(par_max_double((double)r) == p - 1, "max");
  CHECK(par_min_double((double)r) == 0, "min");
  CHECK(par_sum_long(r) == (long)p * (p - 1) / 2, "sum long");
  CHECK(par_agree_status(r == p - 1 ? MS_ERR_UNSTABLE : MS_OK) == MS_ERR_UNSTABLE,
        "the failing rank's status must reach every rank");

  /* the context holds the run's communicator; the calls on an explicit one (core/h5io.c's) */
  CHECK(ctx.comm != NULL && ctx.comm == par_comm(), "par_init gives the context the communicator");
  CHECK(par_comm_rank(ctx.comm) == r, "rank in the context's communicator");
  CHECK(par_comm_min_int(ctx.comm, r + 5) == 5 && par_comm_max_int(ctx.comm, r) == p - 1,
        "min/max int");
  CHECK(par_comm_sum_u64(ctx.comm, (uint64_t)r + 1) == (uint64_t)p * (uint64_t)(p + 1) / 2,
        "sum u64");
  CHECK(par_comm_exscan_u64(ctx.comm, (uint64_t)r + 1) == (uint64_t)r * (uint64_t)(r + 1) / 2,
        "exscan: the sum over the lower ranks (0 on rank 0)");
  int root_value = r == 0 ? 42 : -1;
  par_comm_bcast_int(ctx.comm, &root_value, 0);
  CHECK(root_value == 42, "broadcast from rank 0");
  /* a NULL communicator is a serial one: nothing is exchanged */
  CHECK(par_comm_rank(NULL) == 0 && par_comm_sum_u64(NULL, 7) == 7 &&
            par_comm_exscan_u64(NULL, 7) == 0 && par_comm_max_int(NULL, r) == r,
        "NULL communicator");

  /* fixed-order sum: rank r's element j is a value whose sums round (1/(r+3) scaled by j), so
   * the order matters; the result must be ((v_0 + v_1) + v_2) ... computed here from every
   * rank's values, bit for bit, on every rank. 100 000 elements: more than one chunk (2^17/P) on
   * 2 and 3 ranks. */
  {
    const size_t n = 100000;
    double *v = ms_calloc(n, sizeof *v);
    for (size_t j = 0; j < n; j++) v[j] = (1.0 + (double)j) / (double)(r + 3);
    par_sum_doubles_ordered(v, n);
    size_t bad = 0;
    for (size_t j = 0; j < n; j++) {
      double s = (1.0 + (double)j) / 3.0;
      for (int q = 1; q < p; q++) s += (1.0 + (double)j) / (double)(q + 3);
      bad += memcmp(&s, v + j, sizeof s) != 0;
    }
    CHECK(bad == 0, "ordered sum: %zu of %zu elements differ from the rank-order sum", bad, n);
    free(v);
  }

  /* 1000 rows split unevenly over the ranks (rank r gets a share proportional to r + 1) */
  const size_t total = 1000;
  size_t weight = (size_t)p * (size_t)(p + 1) / 2, begin = 0;
  for (int k = 0; k < r; k++) begin += total * (size_t)(k + 1) / weight;
  size_t n_local = r == p - 1 ? total - begin : total * (size_t)(r + 1) / weight;
  double *rows = ms_calloc(3 * (n_local ? n_local : 1), sizeof *rows);
  int64_t *ids = ms_calloc(n_local ? n_local : 1, sizeof *ids);
  for (size_t i = 0; i < n_local; i++) {
    row_values(begin + i, rows + 3 * i);
    ids[i] = (int64_t)(begin + i);
  }
  const char *path = "mpi_core_test.h5";
  ms_h5 *h = ms_h5_create_collective(path);
  CHECK(h != NULL, "create");
  if (h) {
    CHECK(ms_h5_write_doubles_dist(h, "/particles/x", n_local, 3, rows, "cm") == MS_OK, "write x");
    CHECK(ms_h5_write_ints_dist(h, "/particles/id", n_local, ids) == MS_OK, "write id");
    /* nothing recorded yet on any rank (a checkpoint's history at its first write) */
    CHECK(ms_h5_write_doubles_dist(h, "/empty", 0, 2, rows, NULL) == MS_OK, "write empty");
    CHECK(ms_h5_attr_double(h, "/", "time", 1.25) == MS_OK, "attribute");
    CHECK(ms_h5_close(h) == MS_OK, "close");
  }
  par_barrier();
  if (r == 0) {
    dk_errors e;
    dk_errors_init(&e);
    ms_h5r *in = ms_h5_open_read(path, &e);
    CHECK(in != NULL, "reopen");
    double *back = NULL;
    size_t n0 = 0, n1 = 0;
    if (in) {
      CHECK(ms_h5_read_doubles(in, "/particles/x", &back, &n0, &n1, &e) == MS_OK, "read");
      CHECK(n0 == total && n1 == 3, "shape %zu x %zu", n0, n1);
      for (size_t i = 0; back && i < n0; i++) {
        double v[3];
        row_values(i, v);
        /* bit-identical: the values travel through HDF5 unchanged */
        CHECK(memcmp(v, back + 3 * i, sizeof v) == 0, "row %zu differs", i);
      }
      double *none = NULL;
      CHECK(ms_h5_read_doubles(in, "/empty", &none, &n0, &n1, &e) == MS_OK && n0 == 0, "empty");
      free(none);
      double t = 0;
      CHECK(ms_h5_read_attr_double(in, "/", "time", &t, &e) == MS_OK && t == 1.25, "time attr");
      free(back);
      ms_h5_close_read(in);
    }
    dk_errors_print(&e, stderr);
    dk_errors_free(&e);
    remove(path);
  }
  free(rows);
  free(ids);
  int all_failures = (int)par_sum_long(failures);
  if (r == 0)
    printf("%s: %d rank%s, %d failure%s\n", all_failures ? "FAILED" : "passed", p,
           p == 1 ? "" : "s", all_failures, all_failures == 1 ? "" : "s");
  ms_ctx_close(&ctx);
  par_finalize();
  return all_failures ? 1 : 0;
}
