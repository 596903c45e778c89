/* lsm_flows: the fields of a run's pairs, each computed once (see the header). */
#include "solver/recon/lsm_flows.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "solver/recon/lsm_choose.h"
#include "solver/recon/lsm_pairing.h"

typedef struct flow_slot {
  omp_lock_t lock;         /* the field's */
  lsm_motion_field *field; /* NULL until computed, when no part takes it, after it is freed */
  int done;                /* decided (field set or none needed) */
  int finished;            /* gaps of this process beside it that have finished */
  int freed;               /* every such gap has finished: the field is gone */
  omp_lock_t choice_lock;  /* the choice's: held while predictions run, which may borrow
                              other pairs' fields (never the other way round) */
  int chosen;              /* --motion auto: the choice is made (lsm_choose) */
  lsm_choice choice;       /* --motion auto's choice (field always set with --motion field) */
} flow_slot;

/* --motion auto: one input slice left out and predicted (lsm_choose), for the two pairs
 * beside it. */
typedef struct left_out_slot {
  omp_lock_t lock;
  int done;
  long long missed_field, missed_in_place;
} left_out_slot;

struct lsm_flows {
  size_t pairs;
  int rank, size;
  const lsm_slice_source *src; /* the run's slices, for --motion auto's choice */
  const lsm_flows_lender *lender; /* a prediction's: the run it borrows fields from */
  const lsm_progress *progress;   /* the run's, told when a pair is tried; NULL */
  flow_slot *slots;
  left_out_slot *left_out; /* one per input slice (--motion auto) */
};

lsm_status lsm_flows_create(const lsm_slice_source *src, int rank, int size,
                            const lsm_flows_lender *lender, const lsm_progress *progress,
                            lsm_flows **out, lsm_err *err) {
  const size_t pairs = src->count - 1;
  lsm_flows *f = lsm_alloc(1, sizeof *f, err, "field cache");
  if (!f) return err ? err->status : LSM_ERR_NOMEM;
  f->pairs = pairs;
  f->src = src;
  f->lender = lender;
  f->progress = progress;
  f->rank = rank;
  f->size = size < 1 ? 1 : size;
  f->slots = lsm_alloc(pairs ? pairs : 1, sizeof *f->slots, err, "field cache");
  if (!f->slots) {
    free(f);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  f->left_out = lsm_alloc(pairs + 1, sizeof *f->left_out, err, "field cache");
  if (!f->left_out) {
    free(f->slots);
    free(f);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  for (size_t k = 0; k <= pairs; ++k) {
    omp_init_lock(&f->left_out[k].lock);
    f->left_out[k].done = 0;
  }
  for (size_t k = 0; k < pairs; ++k) {
    omp_init_lock(&f->slots[k].lock);
    omp_init_lock(&f->slots[k].choice_lock);
    f->slots[k].field = NULL;
    f->slots[k].done = 0;
    f->slots[k].finished = 0;
    f->slots[k].freed = 0;
    f->slots[k].chosen = 0;
    f->slots[k].choice = (lsm_choice){.field = 1};
  }
  *out = f;
  return LSM_OK;
}

void lsm_flows_destroy(lsm_flows **flows) {
  if (!flows || !*flows) return;
  lsm_flows *f = *flows;
  for (size_t k = 0; k < f->pairs; ++k) {
    lsm_motion_field_destroy(&f->slots[k].field);
    omp_destroy_lock(&f->slots[k].lock);
    omp_destroy_lock(&f->slots[k].choice_lock);
  }
  for (size_t k = 0; k <= f->pairs; ++k) omp_destroy_lock(&f->left_out[k].lock);
  free(f->left_out);
  free(f->slots);
  free(f);
  *flows = NULL;
}

void lsm_flows_params(const lsm_stack_opts *o, lsm_motion_params *p) {
  lsm_motion_params_default(p);
  p->sigma_field_px = o->rules.motion_sigma_field_px;
  p->sigma_update_px = o->rules.motion_sigma_update_px;
  p->clip_nodes = o->rules.motion_clip_nodes;
  lsm_backend_motion(o->morph.backend, &p->device); /* a device backend registers there */
}

/* The two slices' phi on the fields' canvas and their parts (rule field-parts; NULL when the
 * rule is off); *needs: some part may take the field. */
static lsm_status pair_parts(const lsm_slice *a, const lsm_slice *b, const lsm_stack_opts *o,
                             int width, int height, lsm_grid **pa, lsm_grid **pb,
                             lsm_pairing **parts, int *needs, lsm_err *err) {
  const int pad = LSM_FLOWS_PAD;
  const float hx = (float)o->pixel_dx, hy = (float)o->pixel_dy;
  *needs = 1;
  LSM_TRY(lsm_grid_create(width + 2 * pad, height + 2 * pad, hx, hy, pa, err));
  LSM_TRY(lsm_grid_create(width + 2 * pad, height + 2 * pad, hx, hy, pb, err));
  LSM_TRY(lsm_slice_phi(a, o, pad, pad, *pa, err));
  LSM_TRY(lsm_slice_phi(b, o, pad, pad, *pb, err));
  if (!lsm_rule_on(&o->rules, LSM_RULE_FIELD_PARTS)) return LSM_OK;
  return lsm_pairing_create(&a->filled, &b->filled, *pa, *pb, pad, parts, needs, err);
}

/* --motion auto, under the slot's choice lock: a pair where some part may take the field is
 * tried on the stack's own slices (lsm_choose); the others stay in place untried. */
static lsm_status choose(lsm_flows *flows, size_t pair, const lsm_slice *a, const lsm_slice *b,
                         const lsm_stack_opts *o, int width, int height, int threads,
                         flow_slot *slot, lsm_grid **keep_a, lsm_grid **keep_b, lsm_err *err) {
  if (slot->chosen) return LSM_OK;
  slot->choice = (lsm_choice){0};
  lsm_status st = LSM_OK;
  if (!a->empty && !b->empty) {
    lsm_grid *pa = NULL, *pb = NULL;
    lsm_pairing *parts = NULL;
    int needs = 0;
    st = pair_parts(a, b, o, width, height, &pa, &pb, &parts, &needs, err);
    lsm_pairing_destroy(&parts);
    if (st == LSM_OK && keep_a && keep_b) { /* the caller's gap may work on them */
      *keep_a = pa;
      *keep_b = pb;
      pa = pb = NULL;
    }
    lsm_grid_destroy(&pa);
    lsm_grid_destroy(&pb);
    if (st == LSM_OK && needs && flows->progress && flows->progress->trying)
      flows->progress->trying(flows->progress->ctx, pair, flows->pairs);
    /* until a slice the field predicts no better: the pair then stays in place */
    for (size_t j = pair; st == LSM_OK && needs && j <= pair + 1 &&
                          slot->choice.field_better == slot->choice.tests;
         ++j) {
      if (!lsm_choose_can_leave_out(flows->src, j, o)) continue;
      left_out_slot *lo = &flows->left_out[j];
      omp_set_lock(&lo->lock); /* the pair beside may be testing it */
      if (!lo->done)
        st = lsm_choose_left_out(flows->src, j, width, height, o, threads, flows,
                                 &lo->missed_field, &lo->missed_in_place, err);
      lo->done = st == LSM_OK;
      if (st == LSM_OK) {
        slot->choice.tests++;
        slot->choice.field_better += lo->missed_field < lo->missed_in_place;
        slot->choice.missed_field += lo->missed_field;
        slot->choice.missed_in_place += lo->missed_in_place;
      }
      omp_unset_lock(&lo->lock);
    }
    lsm_choose_decide(&slot->choice);
  }
  slot->chosen = st == LSM_OK;
  return st;
}

lsm_status lsm_flows_choice(lsm_flows *flows, size_t pair, const lsm_slice *a, const lsm_slice *b,
                            const lsm_stack_opts *o, int width, int height, int threads,
                            lsm_choice *choice, lsm_grid **phi_a, lsm_grid **phi_b,
                            lsm_err *err) {
  flow_slot *slot = &flows->slots[pair];
  omp_set_lock(&slot->choice_lock);
  const lsm_status st =
      o->motion == LSM_MOTION_AUTO
          ? choose(flows, pair, a, b, o, width, height, threads, slot, phi_a, phi_b, err)
          : LSM_OK;
  *choice = slot->choice;
  omp_unset_lock(&slot->choice_lock);
  return st;
}

/* Whether gap g runs on this process. */
static int local(const lsm_flows *f, size_t g) { return (int)(g % (size_t)f->size) == f->rank; }

/* The gaps of this process that read pair k's field: k - 1, k and k + 1. */
static int readers(const lsm_flows *f, size_t k) {
  int n = 0;
  for (size_t g = k > 0 ? k - 1 : 0; g <= k + 1 && g < f->pairs; ++g) n += local(f, g);
  return n;
}

/* Computes the slot's field, under its lock (slot->done then set). */
static lsm_status compute(flow_slot *slot, const lsm_slice *a, const lsm_slice *b,
                          const lsm_stack_opts *o, int width, int height, int threads,
                          lsm_err *err) {
  lsm_grid *pa = NULL, *pb = NULL;
  lsm_pairing *parts = NULL;
  /* rule field-parts: only a pair where some part may take the field is registered */
  const int per_part = lsm_rule_on(&o->rules, LSM_RULE_FIELD_PARTS);
  int needs = 1, taken = 1;
  lsm_status st = pair_parts(a, b, o, width, height, &pa, &pb, &parts, &needs, err);
  lsm_motion_params p;
  lsm_flows_params(o, &p);
  if (st == LSM_OK && needs) st = lsm_motion_register(pa, pb, &p, threads, &slot->field, err);
  if (st == LSM_OK && needs && per_part)
    st = lsm_pairing_weigh(parts, slot->field, threads, &taken, err);
  if (st != LSM_OK || !taken) lsm_motion_field_destroy(&slot->field);
  slot->done = st == LSM_OK;
  lsm_pairing_destroy(&parts);
  lsm_grid_destroy(&pa);
  lsm_grid_destroy(&pb);
  return st;
}

/* Pair k of the lender's run, for a prediction: *copy its field (NULL where no part takes
 * it) and *lent 1, computed there if the run will still read it; *lent 0 where the run has
 * freed it or will not read it (the prediction computes its own). */
static lsm_status lend(lsm_flows *run, size_t k, const lsm_slice *a, const lsm_slice *b,
                       const lsm_stack_opts *o, int width, int height, int threads,
                       lsm_motion_field **copy, int *lent, lsm_err *err) {
  flow_slot *slot = &run->slots[k];
  lsm_status st = LSM_OK;
  *copy = NULL;
  *lent = 0;
  omp_set_lock(&slot->lock);
  if (!slot->freed && (slot->done || slot->finished < readers(run, k))) {
    if (!slot->done) st = compute(slot, a, b, o, width, height, threads, err);
    if (st == LSM_OK && slot->field) st = lsm_motion_field_clone(slot->field, copy, err);
    *lent = st == LSM_OK;
  }
  omp_unset_lock(&slot->lock);
  return st;
}

lsm_status lsm_flows_get(lsm_flows *flows, size_t pair, const lsm_slice *a, const lsm_slice *b,
                         const lsm_stack_opts *o, int width, int height, int threads,
                         const lsm_motion_field **field, lsm_err *err) {
  flow_slot *slot = &flows->slots[pair];
  lsm_status st = LSM_OK;
  omp_set_lock(&slot->lock);
  const lsm_flows_lender *l = flows->lender;
  if (!slot->done && l && pair + 1 < l->count && l->index[pair + 1] == l->index[pair] + 1) {
    int lent = 0;
    st = lend(l->flows, l->index[pair], a, b, o, width, height, threads, &slot->field, &lent, err);
    slot->done = st == LSM_OK && lent;
  }
  if (st == LSM_OK && !slot->done) st = compute(slot, a, b, o, width, height, threads, err);
  *field = slot->field;
  omp_unset_lock(&slot->lock);
  return st;
}

void lsm_flows_gap_done(lsm_flows *flows, size_t gap) {
  /* the gaps beside pair k are k - 1, k and k + 1 (gap g is pair g) */
  for (size_t k = gap > 0 ? gap - 1 : 0; k <= gap + 1 && k < flows->pairs; ++k) {
    flow_slot *slot = &flows->slots[k];
    omp_set_lock(&slot->lock);
    if (++slot->finished >= readers(flows, k)) {
      lsm_motion_field_destroy(&slot->field);
      slot->freed = 1;
    }
    omp_unset_lock(&slot->lock);
  }
}
