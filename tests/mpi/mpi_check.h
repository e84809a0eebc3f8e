/* SPDX-License-Identifier: MIT */
/* CHECK for the MPI test programs (no cmocka under mpirun): a failed condition prints its rank,
 * place and message and counts; main sums the counts over ranks (par_sum_long) for the exit
 * code. */
#ifndef MSCALE_MPI_CHECK_H
#define MSCALE_MPI_CHECK_H

#include <stdio.h>

#include "core.h"

static int failures = 0;
#define CHECK(cond, ...)                                                                           \
  do {                                                                                             \
    if (!(cond)) {                                                                                 \
      fprintf(stderr, "FAIL rank %d %s:%d: ", par_rank(), __FILE__, __LINE__);                     \
      fprintf(stderr, __VA_ARGS__);                                                                \
      fputc('\n', stderr);                                                                         \
      failures++;                                                                                  \
    }                                                                                              \
  } while (0)

#endif
