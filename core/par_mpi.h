/* SPDX-License-Identifier: MIT */
/* par_mpi.h — core-private: the MPI handle behind an ms_comm, for the core files that hand a
 * communicator to a library taking one (core/h5io.c: HDF5's MPI-IO file driver). Everything
 * else goes through the par_* calls of core.h. */
#ifndef MSCALE_PAR_MPI_H
#define MSCALE_PAR_MPI_H

#include "core.h"

#include <mpi.h>

MPI_Comm par_comm_mpi(const ms_comm *c);

#endif /* MSCALE_PAR_MPI_H */
