/* lsm_schedule: gaps to tasks, threads and processes (see the header). */
#include "solver/recon/lsm_schedule.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "solver/recon/lsm_flows.h"
#include "solver/recon/lsm_gap_run.h"

lsm_output_grid lsm_output_grid_of(const double *z, size_t count, double dz) {
  double min_gap = dz;
  for (size_t i = 0; i + 1 < count; ++i) min_gap = fmin(min_gap, z[i + 1] - z[i]);
  return (lsm_output_grid){count ? z[0] : 0.0, dz, 1e-6 * min_gap};
}

int lsm_output_below(const lsm_output_grid *g, size_t k, double z) {
  return (double)k * g->dz < (z - g->z0) - g->eps;
}

int lsm_output_not_above(const lsm_output_grid *g, size_t k, double z) {
  return (double)k * g->dz <= (z - g->z0) + g->eps;
}

/* ---- the gaps of the default mode, one task each ------------------------------------------ */

/* A gap's output slices (an lsm_gap_result), held until their turn when gaps
 * run concurrently or on another process. */
static lsm_status buffer_emit(void *ctx, const float *phi, int width, int height, double z,
                              long input_index, lsm_err *err) {
  lsm_gap_result *b = ctx;
  const size_t cells = (size_t)width * (size_t)height;
  if (b->count == b->cap) { /* the expected count at once, else doubling */
    const size_t cap = b->cap ? 2 * b->cap : b->reserve ? b->reserve : 1;
    size_t bytes;
    if (!lsm_size_mul(cap, cells * sizeof(float), &bytes))
      return lsm_fail(err, LSM_ERR_LIMIT, NULL, "gap buffer size overflows");
    float *phis = realloc(b->phi, bytes);
    if (!phis) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot buffer the slices of a gap");
    b->phi = phis;
    double *zs = realloc(b->z, cap * sizeof *zs);
    if (!zs) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot buffer the slices of a gap");
    b->z = zs;
    long *in = realloc(b->input, cap * sizeof *in);
    if (!in) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot buffer the slices of a gap");
    b->input = in;
    b->cap = cap;
  }
  memcpy(b->phi + b->count * cells, phi, cells * sizeof(float));
  b->z[b->count] = z;
  b->input[b->count] = input_index;
  b->width = width;
  b->height = height;
  b->count++;
  return LSM_OK;
}


/* Hands a finished gap's slices to the real sink, in order. */
static lsm_status buffer_replay(lsm_run *r, const lsm_gap_result *b, lsm_err *err) {
  const size_t cells = (size_t)r->width * (size_t)r->height;
  for (size_t k = 0; k < b->count; ++k) {
    memcpy(r->out, b->phi + k * cells, cells * sizeof(float));
    LSM_TRY(lsm_emit(r, b->z[k], b->input[k], err));
  }
  return LSM_OK;
}

/* The output range of gap i: indices [first, last) of the regular grid with
 * heights in [z_i, z_{i+1}). */
typedef struct gap_plan {
  size_t first, last;
} gap_plan;

/* Gap i of the default mode, start to end: loads its own window of input
 * slices (A, B, and the neighbours for the cubic), emits the input slice on
 * z_A if it lies on the grid, then the intermediate slices.  `r` is this
 * task's own run (its sink, output buffer and scratch). */
static lsm_status gap_task(lsm_run *r, size_t i, const gap_plan *plan, const lsm_output_grid *g,
                           lsm_pair_stats *ps, lsm_err *err) {
  const lsm_slice_source *src = r->src;
  const lsm_stack_opts *o = r->opts;
  const int cubic = o->interp == LSM_INTERP_CUBIC;
  lsm_slice s[4];
  memset(s, 0, sizeof s);
  memset(ps, 0, sizeof *ps);
  ps->source = i;
  ps->target = i + 1;
  lsm_status st = LSM_OK;
  /* A and B, then for the cubic the neighbours: the one past a non-empty
   * side; past an empty side (the object ends in this gap) the end rule reads
   * M instead, the slice beyond the next one past the full side (lsm_ends).
   * At most four input slices are held. */
  lsm_slice farther;
  memset(&farther, 0, sizeof farther);
  long m_idx = -1;
  static const int load_order[4] = {1, 2, 0, 3}; /* A, B, prev, next */
  for (int q = 0; q < 4 && st == LSM_OK; ++q) {
    const int k = load_order[q];
    const long idx = (long)i - 1 + k;
    if (idx < 0 || idx >= (long)src->count) continue;
    if ((k == 0 || k == 3) && !cubic) continue;
    if ((k == 0 && s[1].empty) || (k == 3 && s[2].empty)) continue;
    st = lsm_slice_load(src, (size_t)idx, r->width, r->height, o->input, &s[k], err);
  }
  if (st == LSM_OK && cubic && s[1].empty != s[2].empty)
    m_idx = s[1].empty ? (long)i + 3 : (long)i - 2;
  if (m_idx >= 0 && m_idx < (long)src->count)
    st = lsm_slice_load(src, (size_t)m_idx, r->width, r->height, o->input, &farther, err);
  const double za = src->z[i], zb = src->z[i + 1];
  const size_t n_out = plan->last - plan->first;
  double *zs = NULL, *fs = NULL;
  if (st == LSM_OK) {
    zs = lsm_alloc(n_out + 1, sizeof *zs, err, "heights");
    fs = zs ? lsm_alloc(n_out + 1, sizeof *fs, err, "fractions") : NULL;
    if (!fs) st = err ? err->status : LSM_ERR_NOMEM;
  }
  size_t n = 0;
  for (size_t q = plan->first; st == LSM_OK && q < plan->last; ++q) {
    /* the plan puts q at most eps below z_A: within eps of it, q is A */
    const double z = g->z0 + (double)q * g->dz;
    const double f = ((double)q * g->dz - (za - g->z0)) / (zb - za);
    if (lsm_output_not_above(g, q, za) || !(f > 0.0)) {
      st = lsm_emit_input(r, &s[1], i, z, err);
      continue;
    }
    zs[n] = z;
    fs[n] = f;
    ++n;
  }
  if (st == LSM_OK) {
    lsm_window w = {{s[0].loaded ? &s[0] : NULL, &s[1], &s[2], s[3].loaded ? &s[3] : NULL},
                {i > 0 ? src->z[i - 1] : 0.0, za, zb, i + 2 < src->count ? src->z[i + 2] : 0.0},
                farther.loaded ? &farther : NULL, farther.loaded ? src->z[m_idx] : 0.0,
                i == 0, i + 2 == src->count, i};
    st = lsm_gap_run(r, &w, zs, fs, n, ps, err);
  }
  if (r->flows) lsm_flows_gap_done(r->flows, i);
  free(zs);
  free(fs);
  for (int k = 0; k < 4; ++k) lsm_slice_free(&s[k]);
  lsm_slice_free(&farther);
  return st;
}

/* How many gaps to run at once: all cores on separate gaps when one gap's
 * grid is too small to keep them busy (up to 1024^2 pixels), else one gap at
 * a time with the threads inside it.  On a device backend every gap's morphs
 * have their own queue, kernels and buffers (one context), so gaps run side
 * by side there too: the host work of one gap (distance transforms, slopes,
 * combining, writing) overlaps the device work of the others. */
int lsm_schedule_gap_workers(const lsm_stack_opts *o, int width, int height, size_t gaps,
                             size_t most_slices) {
  const int threads = o->morph.threads < 1 ? 1 : o->morph.threads;
  const int device = o->morph.backend && !lsm_backend_host_threads(o->morph.backend);
  if (threads == 1 || gaps < 2) return 1;
  const long long pixels = (long long)width * height;
  if (!device && pixels > 1024LL * 1024LL) return 1;
  long long workers = (size_t)threads < gaps ? threads : (long long)gaps;
  /* each gap in flight holds its working grids on the host: at most about
   * 2^26 pixels of slices in flight (four 4096^2 gaps, one 8192^2) */
  const long long cap = pixels > 0 ? (1LL << 26) / pixels : workers;
  if (device && workers > cap) workers = cap > 1 ? cap : 1;
  /* a gap in flight also buffers its output slices until its turn to write
   * them, and holds as many of its reverse morph's slices on its working
   * canvas, (W + 4) x (H + 4) where the pair is not aligned (lsm_park): at
   * most 512 MiB of them in all (1024^2 slices with --dz 0.01 over gaps of
   * 10 buffered 4 GB per gap); one worker writes as it goes */
  const double canvas = ((double)width + 4.0) * ((double)height + 4.0);
  const double buffered = (double)most_slices * ((double)pixels + canvas) * sizeof(float);
  const long long fit = buffered > 0.0 ? (long long)((double)(1LL << 29) / buffered) : workers;
  if (workers > fit) workers = fit > 1 ? fit : 1;
  return (int)workers;
}

/* Per-iteration mode: gap by gap (the slice count of a gap is known only
 * after it ran), with the threads inside each gap. */
static lsm_status run_per_iteration(lsm_run *r, lsm_pair_stats *stats, lsm_err *err) {
  const lsm_slice_source *src = r->src;
  lsm_slice a = {0}, b = {0};
  lsm_status st = lsm_slice_load(src, 0, r->width, r->height, r->opts->input, &a, err);
  if (st == LSM_OK) st = lsm_emit_input(r, &a, 0, src->z[0], err);
  for (size_t i = 0; st == LSM_OK && i + 1 < src->count; ++i) {
    lsm_pair_stats *ps = &stats[i];
    memset(ps, 0, sizeof *ps);
    ps->source = i;
    ps->target = i + 1;
    st = lsm_slice_load(src, i + 1, r->width, r->height, r->opts->input, &b, err);
    if (st != LSM_OK) break;
    lsm_window w = {{NULL, &a, &b, NULL}, {0.0, src->z[i], src->z[i + 1], 0.0}, NULL, 0.0,
                i == 0, i + 2 == src->count, i};
    st = lsm_gap_run_iterations(r, &w, ps, err);
    if (st == LSM_OK) st = lsm_emit_input(r, &b, i + 1, src->z[i + 1], err);
    lsm_slice_free(&a);
    a = b;
    memset(&b, 0, sizeof b);
  }
  lsm_slice_free(&a);
  lsm_slice_free(&b);
  return st;
}

/* ---- gaps spread over processes ---------------------------------------------------------- */

/* Computes gap i into res (its slices, statistics or error) with its own
 * buffers, on `threads` threads: one task of the gap-parallel and of the
 * distributed runs. */
static void compute_gap(const lsm_run *base, size_t i, const gap_plan *plan,
                        const lsm_output_grid *g, int threads, lsm_gap_result *res) {
  memset(res, 0, sizeof *res);
  lsm_err e;
  lsm_err_clear(&e);
  lsm_run task = *base;
  lsm_slice_sink buffered = {res, buffer_emit};
  task.sink = &buffered;
  task.progress = NULL;
  if (threads > 0) task.morph.threads = threads;
  task.image_phi = NULL;
  task.out = lsm_alloc((size_t)base->width * (size_t)base->height, sizeof(float), &e, "output slice");
  lsm_status st = task.out ? lsm_grid_create(base->width, base->height,
                                             (float)base->opts->pixel_dx,
                                             (float)base->opts->pixel_dy, &task.image_phi, &e)
                           : e.status;
  if (st == LSM_OK && base->opts->per_iteration) {
    lsm_slice a = {0}, b = {0};
    st = lsm_slice_load(base->src, i, base->width, base->height, base->opts->input, &a, &e);
    if (st == LSM_OK)
      st = lsm_slice_load(base->src, i + 1, base->width, base->height, base->opts->input, &b, &e);
    memset(&res->stats, 0, sizeof res->stats);
    res->stats.source = i;
    res->stats.target = i + 1;
    lsm_window w = {{NULL, &a, &b, NULL}, {0.0, base->src->z[i], base->src->z[i + 1], 0.0}, NULL, 0.0,
                i == 0, i + 2 == base->src->count, i};
    if (st == LSM_OK) st = lsm_gap_run_iterations(&task, &w, &res->stats, &e);
    if (st == LSM_OK) st = lsm_emit_input(&task, &b, i + 1, base->src->z[i + 1], &e);
    lsm_slice_free(&a);
    lsm_slice_free(&b);
  } else if (st == LSM_OK) {
    /* its slices on the output grid, and the last input slice (an upper
     * bound): buffered in one allocation of the size gap_workers planned */
    res->reserve = plan->last - plan->first + 1;
    st = gap_task(&task, i, plan, g, &res->stats, &e);
  }
  res->status = st;
  if (st != LSM_OK) snprintf(res->msg, sizeof res->msg, "%s", e.msg[0] ? e.msg : lsm_status_name(st));
  lsm_grid_destroy(&task.image_phi);
  free(task.out);
}

/* Gap i is computed by rank i % size; rank 0 writes everything, in order. */
static lsm_status run_distributed(lsm_run *r, const gap_plan *plan, const lsm_output_grid *g,
                                  lsm_pair_stats *stats, lsm_err *err) {
  const lsm_gap_transport *t = r->opts->transport;
  const size_t gaps = r->src->count - 1;
  lsm_status st = LSM_OK;
  if (t->rank == 0 && r->opts->per_iteration) {
    lsm_slice first = {0};
    st = lsm_slice_load(r->src, 0, r->width, r->height, r->opts->input, &first, err);
    if (st == LSM_OK) st = lsm_emit_input(r, &first, 0, r->src->z[0], err);
    lsm_slice_free(&first);
  }
  for (size_t i = 0; st == LSM_OK && i < gaps; ++i) {
    const int owner = (int)(i % (size_t)t->size);
    lsm_gap_result res;
    memset(&res, 0, sizeof res);
    if (owner == t->rank) {
      compute_gap(r, i, plan ? &plan[i] : NULL, g, 0, &res);
      res.stats.rank = t->rank;
      if (t->rank != 0) {
        st = t->send(t->ctx, i, &res, err);
        if (st == LSM_OK && res.status != LSM_OK) st = lsm_fail(err, res.status, NULL, "%s", res.msg);
        lsm_gap_result_free(&res);
        continue;
      }
    } else if (t->rank == 0) {
      st = t->recv(t->ctx, i, owner, &res, err);
    } else {
      continue; /* another worker's gap */
    }
    if (st == LSM_OK && res.status != LSM_OK) {
      st = lsm_fail(err, res.status, NULL, "%s", res.msg);
      stats[i].source = i; /* the failing gap is the last one started */
      stats[i].target = i + 1;
    }
    if (st == LSM_OK) {
      stats[i] = res.stats;
      st = buffer_replay(r, &res, err);
    }
    lsm_gap_result_free(&res);
  }
  return st;
}

lsm_status lsm_schedule_run(lsm_run *r, lsm_pair_stats *stats, lsm_err *err) {
  const lsm_slice_source *src = r->src;
  const lsm_stack_opts *opts = r->opts;
  const int width = r->width, height = r->height;
  const double dz = lsm_stack_output_dz(opts);
  const size_t gaps = src->count - 1;
  lsm_status st = LSM_OK;
  const int distributed = opts->transport && opts->transport->size > 1;
  if (opts->per_iteration)
    return distributed ? run_distributed(r, NULL, NULL, stats, err)
                       : run_per_iteration(r, stats, err);

  /* Default mode: the regular output grid, split by gap. */
  r->total = lsm_stack_output_count(src->z, src->count, dz);
  const size_t K = r->total;
  const lsm_output_grid grid = lsm_output_grid_of(src->z, src->count, dz);
  gap_plan *plan = st == LSM_OK ? lsm_alloc(gaps, sizeof *plan, err, "gap plan") : NULL;
  if (st == LSM_OK && !plan) st = err ? err->status : LSM_ERR_NOMEM;
  size_t k = 0;
  for (size_t i = 0; st == LSM_OK && i < gaps; ++i) {
    plan[i].first = k;
    while (k < K && lsm_output_below(&grid, k, src->z[i + 1])) ++k;
    plan[i].last = k;
  }
  size_t most_slices = 0;
  for (size_t i = 0; st == LSM_OK && i < gaps; ++i)
    if (plan[i].last - plan[i].first > most_slices) most_slices = plan[i].last - plan[i].first;
  const int workers =
      st == LSM_OK && !distributed ? lsm_schedule_gap_workers(opts, width, height, gaps, most_slices)
                                   : 1;
  r->gap_workers = workers;
  if (st == LSM_OK && opts->motion != LSM_MOTION_NONE)
    st = lsm_flows_create(src, distributed ? opts->transport->rank : 0,
                          distributed ? opts->transport->size : 1, opts->lender, r->progress,
                          &r->flows, err);
  if (st == LSM_OK && distributed) {
    st = run_distributed(r, plan, &grid, stats, err);
  } else if (st == LSM_OK && workers == 1) {
    for (size_t i = 0; st == LSM_OK && i < gaps; ++i)
      st = gap_task(r, i, &plan[i], &grid, &stats[i], err);
  } else if (st == LSM_OK) {
    /* Gaps run concurrently, each single-threaded with its own buffers; the
     * ordered block hands their slices to the sink in stack order, so the
     * output is the same as one gap at a time, and at most `workers` gaps'
     * slices are held. */
    int failed = 0;
    lsm_status first_status = LSM_OK;
    lsm_err first_err;
    lsm_err_clear(&first_err);
    /* the tasks copy this, not r, which the ordered block updates */
    const lsm_run proto = *r;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1) ordered
    for (size_t i = 0; i < gaps; ++i) {
      lsm_gap_result buf;
      memset(&buf, 0, sizeof buf);
      int stop;
#pragma omp atomic read
      stop = failed;
      if (!stop) compute_gap(&proto, i, &plan[i], &grid, 1, &buf);
#pragma omp ordered
      {
        lsm_err e;
        lsm_err_clear(&e);
        lsm_status ts = stop ? LSM_OK : buf.status;
        if (ts != LSM_OK) lsm_fail(&e, ts, NULL, "%s", buf.msg);
        if (!failed && !stop && ts == LSM_OK) {
          stats[i] = buf.stats;
          ts = buffer_replay(r, &buf, &e);
        }
        if (!failed && ts != LSM_OK) {
          /* the failing gap is the last one started (lsmorph names it) */
          stats[i].source = i;
          stats[i].target = i + 1;
          first_status = ts;
          first_err = e;
#pragma omp atomic write
          failed = 1;
        }
      }
      lsm_gap_result_free(&buf);
    }
    if (failed) {
      st = first_status;
      if (err && err->status == LSM_OK) *err = first_err;
    }
  }
  /* The last input slice, if it lies on the output grid (written by rank 0):
   * K counts it when lsm_output_not_above holds, and the plan stopped at the first
   * k not more than eps below it. */
  if (st == LSM_OK && (!distributed || opts->transport->rank == 0) && k < K) {
    lsm_slice last = {0};
    st = lsm_slice_load(src, src->count - 1, width, height, opts->input, &last, err);
    if (st == LSM_OK) st = lsm_emit_input(r, &last, src->count - 1, grid.z0 + (double)k * dz, err);
    lsm_slice_free(&last);
  }
  free(plan);
  lsm_flows_destroy(&r->flows);
  return st;
}
