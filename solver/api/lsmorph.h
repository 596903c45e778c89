/* lsmorph.h: liblsmorph, the public C interface of lsmorph.
 *
 *   fill         fills the slices between the drawn slices of a label volume in
 *                memory, every label at once (`lsmorph fill` without the files)
 *   reconstruct  reconstructs a stack of binary masks in memory into a signed
 *                distance volume (`lsmorph reconstruct` without the files)
 *
 * Link with `pkg-config --cflags --libs lsmorph` (shared) or `--static`.
 * Every function returns a status, LSMORPH_OK (0) or an error code, and writes
 * "<where>: <what>" into the caller's message buffer when one is given.  The
 * library keeps no state between calls; calls may run on several threads at
 * once.  Options are a struct filled with lsmorph_options_default first, so
 * that fields added later keep their defaults in programs built before.
 */
#ifndef LSMORPH_H
#define LSMORPH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(__GNUC__)
#define LSMORPH_API __attribute__((visibility("default")))
#else
#define LSMORPH_API
#endif

#define LSMORPH_VERSION "0.1.0"

/* Status codes (the values of lsmorph's own lsm_status). */
enum {
  LSMORPH_OK = 0,
  LSMORPH_ERR_USAGE = 1,       /* a bad argument or option */
  LSMORPH_ERR_INPUT = 2,       /* the data cannot be filled as given */
  LSMORPH_ERR_IO = 3,
  LSMORPH_ERR_NOMEM = 4,
  LSMORPH_ERR_LIMIT = 5,       /* past a size limit */
  LSMORPH_ERR_NUMERIC = 6,     /* the solver blew up (too large a cfl) */
  LSMORPH_ERR_INTERRUPTED = 7,
  LSMORPH_ERR_UNSUPPORTED = 8,
  LSMORPH_ERR_INTERNAL = 9
};

/* "ok", "bad input", ...; never NULL. */
LSMORPH_API const char *lsmorph_status_name(int status);
LSMORPH_API const char *lsmorph_version(void);

/* Voxel types of a label volume. */
typedef enum lsmorph_dtype {
  LSMORPH_UINT8, LSMORPH_INT8, LSMORPH_UINT16, LSMORPH_INT16, LSMORPH_UINT32, LSMORPH_INT32,
  LSMORPH_UINT64, LSMORPH_INT64
} lsmorph_dtype;

/* The options of both calls.  Names are the command line's values; NULL or 0
 * takes the default. */
typedef struct lsmorph_options {
  size_t size;           /* sizeof(lsmorph_options), set by lsmorph_options_default */
  const char *method;    /* "ls" (default), "pls", "blend" */
  const char *interp;    /* "cubic" (default), "linear" */
  const char *ends;      /* "halfway" (fill's default), "tip", "auto" (reconstruct's) */
  const char *align;     /* "auto" (default), "hull", "none" */
  const char *scheme;    /* "upwind" (default), "roe-fix", "weno5" */
  const char *time;      /* "euler" (default), "rk2", "rk3" */
  double cfl;            /* 0.75 */
  int max_iter;          /* 100000 */
  int reinit_every;      /* 0: never */
  int reinit_iters;      /* 10 */
  int particles_per_cell;/* pls: 16 */
  uint64_t seed;         /* pls: 20130101 */
  int threads;           /* 0: all cores */
  const char *backend;   /* "c" (default), "opencl", "auto" */
  int device;            /* OpenCL device index, -1: the first GPU, else device 0 */
  const char *motion;    /* "auto" (default: per pair, the field where it predicts the stack's
                            own slices better), "field" (the correspondence field, ls and pls),
                            "none" (in place) */
} lsmorph_options;

LSMORPH_API void lsmorph_options_default(lsmorph_options *o);

/* Fills, in place, the slices between the drawn slices of a label volume of
 * n[0] x n[1] x n[2] voxels (i fastest), of physical spacing[3], across axis
 * (0, 1, 2; -1: the axis of the largest spacing, the last on ties).  slices
 * (n_slices of them, NULL: every slice holding a label plus one typical step
 * beyond each end) are the drawn ones; labels (NULL: every non-zero value)
 * the ones filled, the others kept.  Drawn slices come back exactly; each voxel
 * between gets the label it lies deepest inside, or 0 (`lsmorph help fill`).
 * *filled (may be NULL): the slices filled, 0 when every slice is drawn. */
LSMORPH_API int lsmorph_fill(void *labels, lsmorph_dtype dtype, const size_t n[3],
                             const double spacing[3], int axis, const size_t *slices,
                             size_t n_slices, const int64_t *fill_labels, size_t n_labels,
                             const lsmorph_options *options, size_t *filled, char *message,
                             size_t message_size);

/* The number of slices lsmorph_reconstruct writes for these heights (increasing)
 * and output spacing dz: z[0], z[0] + dz, ... up to the last height. */
LSMORPH_API size_t lsmorph_reconstruct_count(const double *z, size_t count, double dz);

/* Reconstructs count binary masks of width x height pixels (row-major, non-zero
 * inside), at heights z (increasing), of pixel size dx x dy, into the signed
 * distance (negative inside, physical units) of every output slice, z[0] + k dz
 * (dz <= 0: the smaller pixel side): out holds out_slices x height x width
 * floats, out_slices = lsmorph_reconstruct_count(z, count, dz). */
LSMORPH_API int lsmorph_reconstruct(const uint8_t *masks, size_t count, size_t width,
                                    size_t height, const double *z, double dx, double dy,
                                    double dz, const lsmorph_options *options, float *out,
                                    size_t out_slices, char *message, size_t message_size);

#ifdef __cplusplus
}
#endif

#endif
