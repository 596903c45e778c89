/* lsm_flows: the fields of a run's pairs, each computed once (see the header). */
#include "solver/recon/lsm_flows.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "solver/recon/lsm_pairing.h"

typedef struct flow_slot {
  omp_lock_t lock;
  lsm_motion_field *field; /* NULL until computed, when no part takes it, after it is freed */
  int done;                /* decided (field set or none needed) */
  int finished;            /* gaps of this process beside it that have finished */
} flow_slot;

struct lsm_flows {
  size_t pairs;
  int rank, size;
  flow_slot *slots;
};

lsm_status lsm_flows_create(size_t pairs, int rank, int size, lsm_flows **out, lsm_err *err) {
  lsm_flows *f = lsm_alloc(1, sizeof *f, err, "field cache");
  if (!f) return err ? err->status : LSM_ERR_NOMEM;
  f->pairs = pairs;
  f->rank = rank;
  f->size = size < 1 ? 1 : size;
  f->slots = lsm_alloc(pairs ? pairs : 1, sizeof *f->slots, err, "field cache");
  if (!f->slots) {
    free(f);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  for (size_t k = 0; k < pairs; ++k) {
    omp_init_lock(&f->slots[k].lock);
    f->slots[k].field = NULL;
    f->slots[k].done = 0;
    f->slots[k].finished = 0;
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
  }
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

lsm_status lsm_flows_get(lsm_flows *flows, size_t pair, const lsm_slice *a, const lsm_slice *b,
                         const lsm_stack_opts *o, int width, int height, int threads,
                         const lsm_motion_field **field, lsm_err *err) {
  flow_slot *slot = &flows->slots[pair];
  lsm_status st = LSM_OK;
  omp_set_lock(&slot->lock);
  if (!slot->done) {
    const int pad = LSM_FLOWS_PAD;
    const float hx = (float)o->pixel_dx, hy = (float)o->pixel_dy;
    lsm_grid *pa = NULL, *pb = NULL;
    lsm_pairing *parts = NULL;
    st = lsm_grid_create(width + 2 * pad, height + 2 * pad, hx, hy, &pa, err);
    if (st == LSM_OK) st = lsm_grid_create(width + 2 * pad, height + 2 * pad, hx, hy, &pb, err);
    if (st == LSM_OK) st = lsm_slice_phi(a, o, pad, pad, pa, err);
    if (st == LSM_OK) st = lsm_slice_phi(b, o, pad, pad, pb, err);
    /* rule field-parts: only a pair where some part may take the field is registered */
    const int per_part = lsm_rule_on(&o->rules, LSM_RULE_FIELD_PARTS);
    int needs = 1, taken = 1;
    if (st == LSM_OK && per_part)
      st = lsm_pairing_create(&a->filled, &b->filled, pa, pb, pad, &parts, &needs, err);
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
  }
  *field = slot->field;
  omp_unset_lock(&slot->lock);
  return st;
}

/* Whether gap g runs on this process. */
static int local(const lsm_flows *f, size_t g) { return (int)(g % (size_t)f->size) == f->rank; }

void lsm_flows_gap_done(lsm_flows *flows, size_t gap) {
  /* the gaps beside pair k are k - 1, k and k + 1 (gap g is pair g) */
  for (size_t k = gap > 0 ? gap - 1 : 0; k <= gap + 1 && k < flows->pairs; ++k) {
    int readers = 0;
    for (size_t g = k > 0 ? k - 1 : 0; g <= k + 1 && g < flows->pairs; ++g) readers += local(flows, g);
    flow_slot *slot = &flows->slots[k];
    omp_set_lock(&slot->lock);
    if (++slot->finished >= readers) lsm_motion_field_destroy(&slot->field);
    omp_unset_lock(&slot->lock);
  }
}
