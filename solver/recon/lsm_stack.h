/* lsm_stack: the stack driver.  Walks the input slices in height order, fills
 * each gap between consecutive slices and hands every output slice to a sink,
 * one at a time: at most a few gaps' slices and working grids are in memory.
 *
 * The data flow, module by module (solver/recon/README.md):
 *   lsm_slice      input slices, the window of four around a gap, their
 *                  signed distances (solver/sdf) on a working canvas
 *   lsm_frame      alignment: whether a pair moved, the gap's frame
 *   lsm_gap        a gap's working fields: moving parts (lsm_parts), parts
 *                  with no counterpart (lsm_unmatched), z-slopes (lsm_zprofile)
 *   lsm_gap_run    the gap's slices: the two-sided pair morph (lsm_two_sided,
 *                  solver/pde), the blend, or an end (lsm_ends)
 *   lsm_zprofile   the monotone cubic z-profile through the four nearest slices
 *   lsm_emit       to the sink: pinholes filled (lsm_pinholes), zero ties broken
 *   lsm_schedule   gaps as tasks on threads or MPI ranks, output in stack order
 *   lsm_rules      every reconstruction rule and constant (opts.rules; --rules-off)
 *
 * Output heights (default mode): the regular grid z0, z0 + dz, ... up to the
 * last input height.  An output height on an input height gets that input
 * slice exactly; a height a fraction s of the way through a gap gets the morph
 * at time t(s) = -ln(1 - s) (lsm_morph_time_of_fraction), or the blend
 * (1 - s) phi_A + s phi_B, with the cubic profile's shape.
 * Per-iteration mode (the document's, §3.6–3.8): every solver iteration of a
 * pair is a slice, at heights linspace(z_A, z_B, k + 2).
 *
 * Empty slices: the object is absent there.  Next to a non-empty slice A the
 * object keeps A's section at most up to mid-gap.  With the linear profile it
 * ends there (a paraboloid cap for ls and pls, the zero set of
 * (1-s) phi_A + s R for the blend, R the depth of A's deepest point; per
 * iteration the morph toward the constant R / ln 2).  With the cubic profile
 * the end follows the trend of the slices before A, and a section still whole
 * at mid-gap closes in a tip at the empty slice (lsm_ends.h).
 */
#ifndef LSM_STACK_H
#define LSM_STACK_H

#include <float.h>
#include <stddef.h>
#include <stdint.h>

#include "solver/base/lsm_grid.h"
#include "solver/base/lsm_names.h"
#include "solver/pde/lsm_morph.h"
#include "solver/recon/lsm_rules.h"
#include "solver/base/lsm_status.h"

/* The lengths a run accepts (pixel size, dz, the height between two input
 * slices), in any one unit: the solver holds them and the signed distances
 * in single-precision floats, whose products under- or overflow outside this
 * range (a pixel size of 1e36 changed the result, 1e-40 blew up the morph).
 * Inside it the result does not depend on the unit: scaling every length by
 * 2^64 or 2^-80 gives the same slices (tests/test_cli.sh). */
#define LSM_LENGTH_MIN 1e-30
#define LSM_LENGTH_MAX 1e30

/* Whether a length lies in that range (false for NaN). */
static inline int lsm_length_in_range(double v) {
  return v >= LSM_LENGTH_MIN && v <= LSM_LENGTH_MAX;
}

/* Whether output heights a step apart stay distinct doubles at heights up to
 * z_mag in size: at least 8 units in the last place (a smaller step repeats
 * heights in heights.txt, the mesh and the previews). */
static inline int lsm_output_step_resolved(double step, double z_mag) {
  return step >= 8.0 * DBL_EPSILON * z_mag;
}

/* Each list's order is the order the help, the command line's messages and the
 * README show; add new items at the end (lsm_names.h). */
#define LSM_METHOD_LIST(X)                                                      \
  X(LSM_METHOD_LS, "ls")       /* level-set morph */                            \
  X(LSM_METHOD_PLS, "pls")     /* level-set morph with the particle level set correction */ \
  X(LSM_METHOD_BLEND, "blend") /* linear interpolation of the two signed distances */
LSM_ENUM(lsm_method, LSM_METHOD, LSM_METHOD_LIST, lsm_method_name,
         lsm_method_from_name);

#define LSM_INPUT_LIST(X)                                                       \
  X(LSM_INPUT_MASK, "mask")       /* filled regions */                          \
  X(LSM_INPUT_OUTLINE, "outline") /* thin closed contours, inside by parity */
LSM_ENUM(lsm_input_kind, LSM_INPUT, LSM_INPUT_LIST, lsm_input_name,
         lsm_input_from_name);

#define LSM_ALIGN_LIST(X)                                                       \
  X(LSM_ALIGN_AUTO, "auto") /* hull for a pair only when its shape moved (see above) */ \
  X(LSM_ALIGN_HULL, "hull") /* convex-hull centroid to the image centre */      \
  X(LSM_ALIGN_NONE, "none")
LSM_ENUM(lsm_align, LSM_ALIGN, LSM_ALIGN_LIST, lsm_align_name,
         lsm_align_from_name);

/* The correspondence field (solver/README.md §9): field, each gap in the moving frame of a
 * symmetric diffeomorphic registration of its two slices; none, in place; auto, per pair
 * the one that predicts the stack's own slices better, left out one at a time (lsm_choose). */
#define LSM_MOTION_LIST(X)                                                      \
  X(LSM_MOTION_FIELD, "field")                                                  \
  X(LSM_MOTION_NONE, "none")                                                    \
  X(LSM_MOTION_AUTO, "auto")
LSM_ENUM(lsm_motion_mode, LSM_MOTION, LSM_MOTION_LIST, lsm_motion_name,
         lsm_motion_from_name);

#define LSM_INTERP_LIST(X)                                                      \
  X(LSM_INTERP_LINEAR, "linear") /* each gap from its two slices only */        \
  X(LSM_INTERP_CUBIC, "cubic")   /* monotone cubic (PCHIP) through the four nearest slices */
LSM_ENUM(lsm_interp, LSM_INTERP, LSM_INTERP_LIST, lsm_interp_name,
         lsm_interp_from_name);

/* How the cubic profile ends an object at an empty slice (lsm_ends.h;
 * solver/README.md, section 8); the linear profile always ends it at mid-gap.
 * tip: whole or narrowing up to mid-gap, then a tip closing at the empty
 * slice; halfway: the same up to mid-gap, nothing past it; auto: tip where
 * the empty slice is the first or last input slice (a stack cut one slice
 * beyond the object), halfway where more slices lie beyond it (a scan that
 * covers more than the object). */
#define LSM_ENDS_LIST(X)                                                        \
  X(LSM_ENDS_AUTO, "auto")                                                      \
  X(LSM_ENDS_TIP, "tip")                                                        \
  X(LSM_ENDS_HALFWAY, "halfway")
LSM_ENUM(lsm_end_rule, LSM_ENDS, LSM_ENDS_LIST, lsm_end_rule_name,
         lsm_end_rule_from_name);

typedef struct lsm_stack_opts {
  lsm_method method;
  lsm_input_kind input;
  lsm_align align;
  lsm_motion_mode motion; /* the correspondence field (default auto; field and auto only for
                          * ls and pls in default mode: lsm_stack_opts_resolve) */
  lsm_interp interp;   /* z-profile (default cubic) */
  lsm_end_rule ends;   /* how the cubic profile ends an object (default auto) */
  double pixel_dx;     /* physical width of a pixel: the step along a row, x (default 1) */
  double pixel_dy;     /* physical height of a pixel: the step down a column, y (default 1) */
  double dz;           /* output slice spacing; <= 0 means the smaller of pixel_dx, pixel_dy */
  int per_iteration;   /* the document's output mode */
  double tol;          /* CP threshold (per-iteration mode, default 0.25) */
  int max_iter;        /* most solver steps per pair (default 100000) */
  lsm_morph_opts morph;
  const struct lsm_gap_transport *transport; /* NULL: one process (see below) */
  lsm_rules rules;     /* the reconstruction rules switched on, and their constants */
  double held_max;     /* most bytes of slices one gap may hold for their turn (0: no limit;
                          per-iteration's count is known only then: the CLI's --max-memory) */
  double canvas_max;   /* most cells of one gap's working canvas (0: no limit; an aligned pair
                          widens it by its shift: the CLI's --max-memory) */
  const struct lsm_flows_lender *lender; /* internal (lsm_choose): the fields a prediction
                                            borrows from its run; NULL */
} lsm_stack_opts;

void lsm_stack_opts_default(lsm_stack_opts *opts);

/* The options a run actually uses: per_iteration (the design document's mode)
 * takes the linear profile, whatever interp says, and the linear profile ends
 * an object at mid-gap, whatever ends says (recorded as halfway).
 * lsm_stack_run applies this to its own copy; callers that record the options
 * (run.json) apply it first. */
void lsm_stack_opts_resolve(lsm_stack_opts *opts);
/* The mode that rules out the correspondence field (and auto's choice of it) (blend, the textbook; --per-iteration and
 * --align hull, the document's modes): its option name, or NULL when the field can run. */
const char *lsm_stack_field_excluded_by(const lsm_stack_opts *opts);

/* Where input slices come from (the CLI reads PNG files; tests synthesise). */
typedef struct lsm_slice_source {
  void *ctx;
  size_t count;       /* number of slices (>= 2) */
  const double *z;    /* their heights, strictly increasing */
  /* Loads slice `index` as read (an outline or a mask, per opts.input). */
  lsm_status (*load)(void *ctx, size_t index, lsm_mask *out, lsm_err *err);
  /* A name for messages (a file name); may be NULL. */
  const char *(*name)(void *ctx, size_t index);
} lsm_slice_source;

/* Where output slices go.  phi is width*height floats, row-major, physical
 * units, negative inside; input_index is the input slice it reproduces or -1. */
typedef struct lsm_slice_sink {
  void *ctx;
  lsm_status (*emit)(void *ctx, const float *phi, int width, int height, double z,
                     long input_index, lsm_err *err);
} lsm_slice_sink;

/* What happened in one gap; the CLI writes these to run.json. */
typedef struct lsm_pair_stats {
  size_t source, target;  /* input indices */
  int iterations;         /* solver steps taken */
  double dt;              /* step size (the fixed CFL step) */
  double cp;              /* CP of the last step (0 if no step) */
  double t_final;         /* morph time reached */
  double seconds;         /* solver time for the pair */
  long long cells;        /* grid cells (updated per iteration with --band off) */
  long long cell_updates; /* cells updated by the solver's stages, both morphs */
  size_t slices;          /* intermediate slices emitted */
  int hit_max_iter;       /* 1 if max_iter stopped the pair early */
  int aligned;            /* 1 if the pair was hull-aligned (--align hull, or chosen by auto),
                             or the object ends in the gap moving with the aligned pair beyond */
  int moving_parts;       /* parts that moved off their place, morphed on their own (lsm_parts) */
  int motion_iterations;  /* the registration of the pair's field: iterations at all levels */
  double motion_seconds;  /* its time */
  double motion_max_px;   /* the field's largest displacement, pixels (0: no field) */
  int motion_tests;       /* --motion auto: slices left out to choose (0: not tried) */
  int motion_field;       /* 1: the pair takes the field (auto's choice, or --motion field) */
  long long motion_missed_field, motion_missed_in_place; /* pixels the left-out predictions
                                                            missed, with and without it */
  /* --method pls (both morphs of a two-sided pair added up) */
  long long pls_seeded;     /* particles seeded */
  long long pls_discarded;  /* dropped by attraction (and leaving the grid) */
  long long pls_escaped;    /* escaped particles, summed over steps */
  long long pls_corrected;  /* grid values changed by corrections */
  long long pls_steps;      /* corrections made (steps) */
  int rank;                 /* the process (MPI rank) that ran the gap; 0 without MPI */
} lsm_pair_stats;

/* A finished gap on its way to the writing process: its output slices in
 * order (phi: count * width * height floats), its statistics, or its error. */
typedef struct lsm_gap_result {
  lsm_status status;
  char msg[LSM_ERR_MSG_MAX];
  size_t count;
  size_t cap;     /* slices allocated (while buffering) */
  size_t reserve; /* slices expected, allocated at once (0: unknown, grown by doubling) */
  int width, height;
  float *phi;
  double *z;
  long *input;
  lsm_pair_stats stats;
} lsm_gap_result;

void lsm_gap_result_free(lsm_gap_result *g);

/* Spreading the gaps over processes.  Gap i is computed by rank i % size;
 * rank 0 computes its own gaps and receives the others' in stack order, and
 * only rank 0 writes, so the output is the one a single process writes, byte
 * for byte.  Implemented with MPI in solver/app/lsm_mpi.c (make MPI=1). */
typedef struct lsm_gap_transport {
  void *ctx;
  int rank, size;
  /* rank != 0: hands gap `gap` (or its error) to rank 0 */
  lsm_status (*send)(void *ctx, size_t gap, const lsm_gap_result *result, lsm_err *err);
  /* rank 0: receives gap `gap` from rank `from` into *result (allocated; free
   * with lsm_gap_result_free) */
  lsm_status (*recv)(void *ctx, size_t gap, int from, lsm_gap_result *result, lsm_err *err);
} lsm_gap_transport;

typedef struct lsm_progress {
  void *ctx;
  /* Called after each output slice: done of total (total 0 when unknown). */
  void (*update)(void *ctx, size_t done, size_t total, size_t pair, size_t pairs);
  /* NULL, or called as --motion auto begins to try pair `pair` of `pairs` by leaving its
   * slices out (lsm_choose), which takes a while before the pair writes anything; from the
   * gap's thread, concurrently with update: the callee serialises. */
  void (*trying)(void *ctx, size_t pair, size_t pairs);
} lsm_progress;

/* The output slice spacing of default mode: --dz, or when it is not set the
 * pixel size (isotropic voxels; the smaller side of a pixel that is not
 * square, so that z is sampled as finely as the finer in-plane axis). */
double lsm_stack_output_dz(const lsm_stack_opts *opts);

/* Number of output slices in default mode: the heights z[0] + k dz up to
 * the last input height (within a millionth of dz or of the closest pair of
 * input heights).  At least LSM_OUTPUT_COUNT_MAX is returned as that. */
#define LSM_OUTPUT_COUNT_MAX (SIZE_MAX / 2)
size_t lsm_stack_output_count(const double *z, size_t count, double dz);

/* Runs the whole stack.  stats has source->count - 1 entries.  progress may
 * be NULL. */
lsm_status lsm_stack_run(const lsm_slice_source *source, int width, int height,
                         const lsm_stack_opts *opts, const lsm_slice_sink *sink,
                         lsm_pair_stats *stats, const lsm_progress *progress, lsm_err *err);

#endif
