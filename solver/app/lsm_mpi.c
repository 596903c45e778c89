#include "solver/app/lsm_mpi.h"

#include <stdlib.h>
#include <string.h>

#ifdef LSM_WITH_MPI
#include <mpi.h>
#endif

struct lsm_mpi {
  int rank, size;
  lsm_gap_transport transport;
};

int lsm_mpi_built(void) {
#ifdef LSM_WITH_MPI
  return 1;
#else
  return 0;
#endif
}

#ifdef LSM_WITH_MPI
/* The fixed part of a gap message. */
typedef struct gap_header {
  long long gap, count;
  int status, width, height, pad;
  char msg[LSM_ERR_MSG_MAX];
  lsm_pair_stats stats;
} gap_header;

static int tag_of(size_t gap) { return (int)(gap % 30000u); }

static lsm_status mpi_fail(lsm_err *err, int code, const char *what) {
  char text[MPI_MAX_ERROR_STRING];
  int len = 0;
  MPI_Error_string(code, text, &len);
  return lsm_fail(err, LSM_ERR_IO, NULL, "MPI: %s failed: %s", what, text);
}

static lsm_status send_gap(void *ctx, size_t gap, const lsm_gap_result *r, lsm_err *err) {
  (void)ctx;
  gap_header h;
  memset(&h, 0, sizeof h);
  h.gap = (long long)gap;
  h.status = (int)r->status;
  h.count = r->status == LSM_OK ? (long long)r->count : 0;
  h.width = r->width;
  h.height = r->height;
  memcpy(h.msg, r->msg, sizeof h.msg);
  h.stats = r->stats;
  const int tag = tag_of(gap);
  int rc = MPI_Send(&h, (int)sizeof h, MPI_BYTE, 0, tag, MPI_COMM_WORLD);
  if (rc != MPI_SUCCESS) return mpi_fail(err, rc, "sending a gap");
  if (h.count == 0) return LSM_OK;
  rc = MPI_Send(r->z, (int)h.count, MPI_DOUBLE, 0, tag, MPI_COMM_WORLD);
  if (rc == MPI_SUCCESS) rc = MPI_Send(r->input, (int)h.count, MPI_LONG, 0, tag, MPI_COMM_WORLD);
  const size_t cells = (size_t)r->width * (size_t)r->height;
  for (long long k = 0; rc == MPI_SUCCESS && k < h.count; ++k)
    rc = MPI_Send(r->phi + (size_t)k * cells, (int)cells, MPI_FLOAT, 0, tag, MPI_COMM_WORLD);
  return rc == MPI_SUCCESS ? LSM_OK : mpi_fail(err, rc, "sending a gap");
}

static lsm_status recv_gap(void *ctx, size_t gap, int from, lsm_gap_result *r, lsm_err *err) {
  (void)ctx;
  memset(r, 0, sizeof *r);
  gap_header h;
  const int tag = tag_of(gap);
  int rc = MPI_Recv(&h, (int)sizeof h, MPI_BYTE, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  if (rc != MPI_SUCCESS) return mpi_fail(err, rc, "receiving a gap");
  if (h.gap != (long long)gap)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "MPI: expected gap %zu from rank %d, got %lld", gap,
                    from, h.gap);
  r->status = (lsm_status)h.status;
  memcpy(r->msg, h.msg, sizeof r->msg);
  r->msg[sizeof r->msg - 1] = '\0';
  r->stats = h.stats;
  r->width = h.width;
  r->height = h.height;
  if (h.count <= 0) return LSM_OK;
  const size_t n = (size_t)h.count, cells = (size_t)h.width * (size_t)h.height;
  r->z = lsm_alloc(n, sizeof *r->z, err, "received heights");
  r->input = r->z ? lsm_alloc(n, sizeof *r->input, err, "received slices") : NULL;
  r->phi = r->input ? lsm_alloc(n * cells, sizeof *r->phi, err, "received slices") : NULL;
  if (!r->phi) {
    lsm_gap_result_free(r);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  r->count = n;
  rc = MPI_Recv(r->z, (int)n, MPI_DOUBLE, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  if (rc == MPI_SUCCESS)
    rc = MPI_Recv(r->input, (int)n, MPI_LONG, from, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  for (size_t k = 0; rc == MPI_SUCCESS && k < n; ++k)
    rc = MPI_Recv(r->phi + k * cells, (int)cells, MPI_FLOAT, from, tag, MPI_COMM_WORLD,
                  MPI_STATUS_IGNORE);
  if (rc != MPI_SUCCESS) {
    lsm_gap_result_free(r);
    return mpi_fail(err, rc, "receiving a gap");
  }
  return LSM_OK;
}
#endif

lsm_status lsm_mpi_init(int *argc, char ***argv, lsm_mpi **out, lsm_err *err) {
  *out = NULL;
  lsm_mpi *m = calloc(1, sizeof *m);
  if (!m) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate the MPI state");
  m->rank = 0;
  m->size = 1;
#ifdef LSM_WITH_MPI
  int provided = 0;
  int rc = MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  if (rc != MPI_SUCCESS) {
    free(m);
    return mpi_fail(err, rc, "MPI_Init_thread");
  }
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &m->rank);
  MPI_Comm_size(MPI_COMM_WORLD, &m->size);
  m->transport.ctx = m;
  m->transport.rank = m->rank;
  m->transport.size = m->size;
  m->transport.send = send_gap;
  m->transport.recv = recv_gap;
#else
  (void)argc;
  (void)argv;
#endif
  *out = m;
  return LSM_OK;
}

int lsm_mpi_rank(const lsm_mpi *m) { return m ? m->rank : 0; }
int lsm_mpi_size(const lsm_mpi *m) { return m ? m->size : 1; }

const lsm_gap_transport *lsm_mpi_transport(const lsm_mpi *m) {
  return m && m->size > 1 ? &m->transport : NULL;
}

void lsm_mpi_abort(lsm_mpi *m, int code) {
#ifdef LSM_WITH_MPI
  if (m && m->size > 1) MPI_Abort(MPI_COMM_WORLD, code);
#else
  (void)m;
  (void)code;
#endif
}

void lsm_mpi_finalize(lsm_mpi **m) {
  if (!m || !*m) return;
#ifdef LSM_WITH_MPI
  MPI_Finalize();
#endif
  free(*m);
  *m = NULL;
}
