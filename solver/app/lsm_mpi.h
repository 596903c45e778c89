/* lsm_mpi: spreading the gaps of a stack over MPI processes.
 *
 * Built with MPI only by `make MPI=1` (mpicc, Open MPI); otherwise every call
 * behaves as a single process (size 1, no transport).  Rank 0 reads, computes
 * its own gaps, receives the others' slices in stack order and writes the
 * result; every other rank computes the gaps i with i % size == rank and
 * sends them (lsm_gap_transport in lsm_stack.h).  Messages: a fixed header
 * (gap, status, message, statistics, slice count and size), then the heights,
 * the input indices and one message per slice.  The processes are assumed
 * to be alike (same byte order and type sizes), as on a cluster.
 */
#ifndef LSM_MPI_H
#define LSM_MPI_H

#include "solver/recon/lsm_stack.h"
#include "solver/base/lsm_status.h"

typedef struct lsm_mpi lsm_mpi;

/* 1 when this build has MPI. */
int lsm_mpi_built(void);

/* MPI_Init (thread level FUNNELED: only the main thread calls MPI) when built
 * with MPI; *out gets rank and size. */
lsm_status lsm_mpi_init(int *argc, char ***argv, lsm_mpi **out, lsm_err *err);
int lsm_mpi_rank(const lsm_mpi *m);
int lsm_mpi_size(const lsm_mpi *m);
/* The gap transport, or NULL for a single process. */
const lsm_gap_transport *lsm_mpi_transport(const lsm_mpi *m);
/* Ends every process with exit code `code` (after rank 0 has reported and
 * cleaned up); returns only without MPI. */
void lsm_mpi_abort(lsm_mpi *m, int code);
/* MPI_Finalize and free. */
void lsm_mpi_finalize(lsm_mpi **m);

#endif
