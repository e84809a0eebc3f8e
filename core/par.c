/* SPDX-License-Identifier: MIT */
/* The MPI layer: the only file of mscale that names MPI_COMM_WORLD. Every collective here is a
 * thin typed wrapper; physics code calls these and never MPI directly. The communicator is the
 * run context's (ms_ctx.comm, made by par_init); core/h5io.c reaches it through
 * core/par_mpi.h for MPI-IO. */
#include "core.h"
#include "par_mpi.h"

#include <mpi.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static bool mpi_started_here = false;

/* The run's communicator: par_init fills it and hands it to the context (ctx->comm); the par_*
 * calls without a communicator argument act on it. */
struct ms_comm {
  MPI_Comm comm;
};
static ms_comm run_comm;
static bool run_comm_set = false;

/* Time spent inside the MPI calls that distributed particle runs make every step (waits
 * included): on a shared machine a rank spins there while its peer is descheduled, so speed
 * figures subtract it from the process CPU time (bench/cd_mpi). */
static double comm_wall, comm_cpu;
typedef struct comm_clock {
  double wall, cpu;
} comm_clock;
static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static comm_clock comm_start(void) { return (comm_clock){ms_wall_time(), cpu_now()}; }
static void comm_stop(comm_clock c) {
  comm_wall += ms_wall_time() - c.wall;
  comm_cpu += cpu_now() - c.cpu;
}
void par_comm_time(double *wall, double *cpu) {
  *wall = comm_wall;
  *cpu = comm_cpu;
}

ms_status par_init(int *argc, char ***argv, ms_ctx *ctx) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) {
    /* A rank waiting for its partner (ghost exchange, the rebuild all-reduce) polls; Open MPI
     * spins unless it sees more ranks than cores. On a machine shared with other work the
     * partner is often descheduled, and the spinning takes the CPU share the partner needs:
     * yielding in the poll loop cut bench/cd_mpi's 2-rank wall time from 18.2 to 13.5 s at load
     * 9 (docs/mpi.md). Costless on an idle core (sched_yield returns at once). The user's
     * setting (environment or mpirun --mca) wins. */
    setenv("OMPI_MCA_mpi_yield_when_idle", "1", 0);
    if (MPI_Init(argc, argv) != MPI_SUCCESS) return MS_ERR_INTERNAL;
    mpi_started_here = true;
  }
  run_comm.comm = MPI_COMM_WORLD;
  run_comm_set = true;
  ctx->comm = &run_comm;
  MPI_Comm_rank(run_comm.comm, &ctx->rank);
  MPI_Comm_size(run_comm.comm, &ctx->size);
  /* Ranks sharing a node split its cores between their OpenMP teams, unless OMP_NUM_THREADS
   * says otherwise: with more threads than cores every OpenMP barrier waits for a descheduled
   * thread (two 2-thread runs on 2 cores: a coupled Rz80 deck's 60 s run showed a 50-minute
   * ETA; docs/mpi.md). omp_get_num_procs counts the cores this rank may run on (its binding). */
  if (ctx->size > 1 && !getenv("OMP_NUM_THREADS")) {
    int on_node = 1;
    MPI_Comm node;
    if (MPI_Comm_split_type(run_comm.comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) ==
        MPI_SUCCESS) {
      MPI_Comm_size(node, &on_node);
      MPI_Comm_free(&node);
    }
    const int threads = omp_get_num_procs() / on_node;
    omp_set_num_threads(threads > 1 ? threads : 1);
  }
  return MS_OK;
}

void par_finalize(void) {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (mpi_started_here && !finalized) MPI_Finalize();
}

static bool active(void) {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  return run_comm_set && initialized && !finalized;
}

const ms_comm *par_comm(void) { return active() ? &run_comm : NULL; }

MPI_Comm par_comm_mpi(const ms_comm *c) { return c->comm; }

/* ---- on an explicit communicator (NULL: serial, no communication) ---- */

int par_comm_rank(const ms_comm *c) {
  int r = 0;
  if (c) MPI_Comm_rank(c->comm, &r);
  return r;
}

int par_comm_min_int(const ms_comm *c, int v) {
  int r = v;
  if (c) MPI_Allreduce(&v, &r, 1, MPI_INT, MPI_MIN, c->comm);
  return r;
}

int par_comm_max_int(const ms_comm *c, int v) {
  int r = v;
  if (c) MPI_Allreduce(&v, &r, 1, MPI_INT, MPI_MAX, c->comm);
  return r;
}

void par_comm_bcast_int(const ms_comm *c, int *v, int root) {
  if (c) MPI_Bcast(v, 1, MPI_INT, root, c->comm);
}

uint64_t par_comm_sum_u64(const ms_comm *c, uint64_t v) {
  unsigned long long mine = v, r = v;
  if (c) MPI_Allreduce(&mine, &r, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, c->comm);
  return r;
}

uint64_t par_comm_exscan_u64(const ms_comm *c, uint64_t v) {
  unsigned long long mine = v, r = 0;
  if (!c) return 0;
  MPI_Exscan(&mine, &r, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, c->comm);
  return par_comm_rank(c) == 0 ? 0 : r; /* MPI_Exscan leaves the first rank's result undefined */
}

void par_barrier(void) {
  if (active()) MPI_Barrier(run_comm.comm);
}

static double reduce_double(double v, MPI_Op op) {
  double r = v;
  if (active()) {
    comm_clock c = comm_start();
    MPI_Allreduce(&v, &r, 1, MPI_DOUBLE, op, run_comm.comm);
    comm_stop(c);
  }
  return r;
}

double par_sum_double(double v) { return reduce_double(v, MPI_SUM); }
double par_max_double(double v) { return reduce_double(v, MPI_MAX); }
double par_min_double(double v) { return reduce_double(v, MPI_MIN); }

long par_sum_long(long v) {
  long r = v;
  if (active()) MPI_Allreduce(&v, &r, 1, MPI_LONG, MPI_SUM, run_comm.comm);
  return r;
}

int par_max_int(int v) {
  int r = v;
  if (active()) {
    comm_clock c = comm_start();
    MPI_Allreduce(&v, &r, 1, MPI_INT, MPI_MAX, run_comm.comm);
    comm_stop(c);
  }
  return r;
}

ms_status par_agree_status(ms_status s) { return (ms_status)par_max_int((int)s); }

void par_bcast_doubles(double *v, size_t n, int root) {
  if (active()) MPI_Bcast(v, (int)n, MPI_DOUBLE, root, run_comm.comm);
}

void par_bcast_ints(int32_t *v, size_t n, int root) {
  if (active()) MPI_Bcast(v, (int)n, MPI_INT32_T, root, run_comm.comm);
}

void par_sum_doubles(double *v, size_t n) {
  if (active() && n > 0) MPI_Allreduce(MPI_IN_PLACE, v, (int)n, MPI_DOUBLE, MPI_SUM, run_comm.comm);
}

void par_max_doubles(double *v, size_t n) {
  if (active() && n > 0) MPI_Allreduce(MPI_IN_PLACE, v, (int)n, MPI_DOUBLE, MPI_MAX, run_comm.comm);
}

/* Fixed-order sum: rank 0 gathers every rank's v and adds them in rank order
 * ((v_0 + v_1) + v_2 ...), then broadcasts the sums. Every rank gets the same bits, and they
 * depend only on the operands and the rank count, not on the MPI library's reduction algorithm:
 * what enters a replicated state (the coupled problem's grid, docs/mpi.md) stays bitwise equal
 * on every rank and reproducible on the same rank count. Chunked so that rank 0 buffers at most
 * ORDERED_MAX doubles; the buffer grows on first use and is reused (no allocation per call). */
enum { ORDERED_MAX = 1 << 17 };
static double *ordered_buf;
static size_t ordered_cap;

void par_sum_doubles_ordered(double *v, size_t n) {
  if (!active() || n == 0) return;
  int size = 1, rank = 0;
  MPI_Comm_size(run_comm.comm, &size);
  MPI_Comm_rank(run_comm.comm, &rank);
  if (size == 1) return;
  const size_t per = (size_t)size, chunk = ORDERED_MAX / per > 0 ? ORDERED_MAX / per : 1;
  const size_t need = (n < chunk ? n : chunk) * per;
  if (rank == 0 && need > ordered_cap) {
    free(ordered_buf);
    ordered_cap = need;
    ordered_buf = ms_calloc(ordered_cap, sizeof *ordered_buf);
  }
  comm_clock c = comm_start();
  for (size_t off = 0; off < n; off += chunk) {
    const size_t m = n - off < chunk ? n - off : chunk;
    MPI_Gather(v + off, (int)m, MPI_DOUBLE, ordered_buf, (int)m, MPI_DOUBLE, 0, run_comm.comm);
    if (rank == 0)
      for (size_t j = 0; j < m; j++) {
        double s = ordered_buf[j];
        for (size_t r = 1; r < per; r++) s += ordered_buf[r * m + j];
        v[off + j] = s;
      }
    MPI_Bcast(v + off, (int)m, MPI_DOUBLE, 0, run_comm.comm);
  }
  comm_stop(c);
}

void par_alltoallv_doubles(const double *send, const int *scount, const int *sdispl, double *recv,
                           const int *rcount, const int *rdispl) {
  if (active()) {
    comm_clock c = comm_start();
    MPI_Alltoallv(send, scount, sdispl, MPI_DOUBLE, recv, rcount, rdispl, MPI_DOUBLE,
                  run_comm.comm);
    comm_stop(c);
  } else if (scount[0] > 0) {
    memcpy(recv + rdispl[0], send + sdispl[0], (size_t)scount[0] * sizeof(double));
  }
}

int par_rank(void) {
  int r = 0;
  if (active()) MPI_Comm_rank(run_comm.comm, &r);
  return r;
}

int par_size(void) {
  int n = 1;
  if (active()) MPI_Comm_size(run_comm.comm, &n);
  return n;
}

void par_sum_int64s(int64_t *v, size_t n) {
  if (active() && n > 0) {
    comm_clock c = comm_start();
    MPI_Allreduce(MPI_IN_PLACE, v, (int)n, MPI_INT64_T, MPI_SUM, run_comm.comm);
    comm_stop(c);
  }
}

/* ---- distributed fragment analysis (coupling/fragments_dist.c) ---- */

void par_alltoall_ints(const int *send, int *recv) {
  if (active()) {
    comm_clock c = comm_start();
    MPI_Alltoall(send, 1, MPI_INT, recv, 1, MPI_INT, run_comm.comm);
    comm_stop(c);
  } else {
    recv[0] = send[0];
  }
}

void par_alltoallv_int64(const int64_t *send, const int *scount, const int *sdispl, int64_t *recv,
                         const int *rcount, const int *rdispl) {
  if (active()) {
    MPI_Alltoallv(send, scount, sdispl, MPI_INT64_T, recv, rcount, rdispl, MPI_INT64_T,
                  run_comm.comm);
  } else if (scount[0] > 0) {
    memcpy(recv + rdispl[0], send + sdispl[0], (size_t)scount[0] * sizeof(int64_t));
  }
}

int64_t par_max_int64(int64_t v) {
  int64_t r = v;
  if (active()) MPI_Allreduce(&v, &r, 1, MPI_INT64_T, MPI_MAX, run_comm.comm);
  return r;
}

void par_allgather_long(long v, long *all) {
  if (active()) MPI_Allgather(&v, 1, MPI_LONG, all, 1, MPI_LONG, run_comm.comm);
  else all[0] = v;
}

void par_allgatherv_doubles(const double *send, int n, double *recv, const int *counts,
                            const int *displs) {
  if (active()) {
    MPI_Allgatherv(send, n, MPI_DOUBLE, recv, counts, displs, MPI_DOUBLE, run_comm.comm);
  } else if (n > 0) {
    memcpy(recv + displs[0], send, (size_t)n * sizeof(double));
  }
}

/* Requests of the neighbour exchanges posted and not yet waited for: grown when a post needs
 * more (the first steps), then reused, so that the exchange of every force evaluation does not
 * allocate. */
static MPI_Request *nbr_req;
static int nbr_req_cap, nbr_req_n;

void par_exchange_post(int nnbr, const int *ranks, const double *send, const int *scount,
                       const int *sdispl, double *recv, const int *rcount, const int *rdispl,
                       int tag) {
  if (!active() || nnbr == 0) return;
  if (nbr_req_n + 2 * nnbr > nbr_req_cap) {
    nbr_req_cap = nbr_req_n + 2 * nnbr;
    nbr_req = ms_realloc(nbr_req, (size_t)nbr_req_cap, sizeof *nbr_req);
  }
  comm_clock c = comm_start();
  for (int k = 0; k < nnbr; k++)
    if (rcount[k] > 0)
      MPI_Irecv(recv + rdispl[k], rcount[k], MPI_DOUBLE, ranks[k], tag, run_comm.comm,
                &nbr_req[nbr_req_n++]);
  for (int k = 0; k < nnbr; k++)
    if (scount[k] > 0)
      MPI_Isend(send + sdispl[k], scount[k], MPI_DOUBLE, ranks[k], tag, run_comm.comm,
                &nbr_req[nbr_req_n++]);
  comm_stop(c);
}

void par_exchange_wait(void) {
  if (nbr_req_n == 0) return;
  comm_clock c = comm_start();
  MPI_Waitall(nbr_req_n, nbr_req, MPI_STATUSES_IGNORE);
  nbr_req_n = 0;
  comm_stop(c);
}

void par_exchange_doubles(int nnbr, const int *ranks, const double *send, const int *scount,
                          const int *sdispl, double *recv, const int *rcount, const int *rdispl) {
  par_exchange_post(nnbr, ranks, send, scount, sdispl, recv, rcount, rdispl, 77);
  par_exchange_wait();
}

void par_mpi_library_version(char *buf, size_t n) {
  char v[MPI_MAX_LIBRARY_VERSION_STRING] = "";
  int len = 0;
  if (MPI_Get_library_version(v, &len) != MPI_SUCCESS) v[0] = 0;
  v[sizeof v - 1] = 0;
  size_t k = strcspn(v, "\n\r");
  v[k] = 0;
  while (k > 0 && (v[k - 1] == ',' || v[k - 1] == ' ')) v[--k] = 0;
  snprintf(buf, n, "%s", v);
}

int par_max_threads(void) { return omp_get_max_threads(); }
