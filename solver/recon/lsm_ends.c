/* lsm_ends: how an object ends inside a gap whose far side is an empty slice
 * (see the header; the rules end-* in lsm_rules.h). */
#include "solver/recon/lsm_ends.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "solver/base/lsm_flood.h"

static int compare_float(const void *x, const void *y) {
  const float a = *(const float *)x, b = *(const float *)y;
  return (a > b) - (a < b);
}

/* One 8-connected component of F's section where the object ends (a gap
 * with one empty side, cubic profile), and how it ends. */
typedef struct end_part {
  double area_f;  /* its cells */
  double area_n;  /* cells of N's components that go on into it (shared by overlap) */
  double area_m;  /* cells of M's components (the slice beyond N) that reach it */
  int has_m;      /* some component of M reaches it */
  double nested;  /* its cells inside N */
  double weight;  /* share of it that narrows like N -> F; the rest is a flat end */
  double rate;    /* dA/dz of the line through A_N and A_F toward the end, <= 0
                  * (cells per unit z); the narrowing share follows weight x it */
  double power;   /* exponent p of its tip past mid-gap, 2 to 3 */
} end_part;

typedef struct end_parts {
  int count;
  int32_t *region; /* per cell: the part it lies in or is nearest to (8-connected steps) */
  size_t *first;   /* count + 1 offsets into inside: part c's cells of F */
  int32_t *inside; /* F's inside cells, grouped by part */
  end_part *part;
} end_parts;

static void end_parts_free(end_parts *e) {
  free(e->region);
  free(e->first);
  free(e->inside);
  free(e->part);
  memset(e, 0, sizeof *e);
}

/* Exponent p of the tip past mid-gap, area A_F (2 (1 - sigma))^p, from the
 * areas of F and of N beyond it (rule end-tip-power): end_tip_narrow where
 * the section narrows toward the end by end_cone_from or more, end_tip_flat
 * (a cone's area) where it keeps its size or grows (a flat end gives no hint
 * of where the object stops), linear in between. */
static double end_tip_power(double area_f, double area_n, const lsm_rules *rules) {
  const double narrowing = area_f > 0.0 ? (area_n - area_f) / area_f : 1.0;
  return rules->end_tip_flat + (rules->end_tip_narrow - rules->end_tip_flat) *
                                   fmin(fmax(narrowing / rules->end_cone_from, 0.0), 1.0);
}

/* Each component of `other` (N, or M beyond it) that overlaps F gives its
 * area to the parts it overlaps, in proportion to the overlap: into area_n
 * (and the overlapping cells into nested) for N, into area_m (has_m set) for
 * M.  A component that misses F ended before it and says nothing about how F
 * ends.  label and queue hold nx * ny entries each. */
static lsm_status share_areas(const lsm_grid *other, end_parts *e, int32_t *label, int32_t *queue,
                              int farther, lsm_err *err) {
  const size_t n = (size_t)other->nx * (size_t)other->ny;
  const int32_t count = lsm_grid_label_components(other, 0.0f, label, queue);
  double *area = lsm_alloc((size_t)count + 1, sizeof *area, err, "end components");
  double *hits = area ? lsm_alloc((size_t)count + 1, sizeof *hits, err, "end components") : NULL;
  if (!hits) {
    free(area);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  memset(area, 0, ((size_t)count + 1) * sizeof *area);
  memset(hits, 0, ((size_t)count + 1) * sizeof *hits);
  for (size_t k = 0; k < n; ++k)
    if (label[k] >= 0) {
      area[label[k]] += 1.0;
      if (e->region[k] >= 0) hits[label[k]] += 1.0;
    }
  for (size_t k = 0; k < n; ++k)
    if (label[k] >= 0 && e->region[k] >= 0) {
      end_part *pc = &e->part[e->region[k]];
      const double share = area[label[k]] / hits[label[k]];
      if (farther) {
        pc->area_m += share;
        pc->has_m = 1;
      } else {
        pc->nested += 1.0;
        pc->area_n += share;
      }
    }
  free(area);
  free(hits);
  return LSM_OK;
}

/* F's components and how each ends (see the header).  nb: N's field in F's
 * frame, or NULL (no slice beyond F: every part is a flat end); hn: the
 * height from N to F. */
static lsm_status end_parts_find(const lsm_grid *full, const lsm_grid *nb, double hn,
                                 const lsm_grid *nm, const lsm_rules *rules, end_parts *e,
                                 lsm_err *err) {
  memset(e, 0, sizeof *e);
  const int nx = full->nx, ny = full->ny;
  const size_t n = (size_t)nx * (size_t)ny;
  int32_t *queue = lsm_alloc(n, sizeof *queue, err, "end components");
  int32_t *label_n = queue ? lsm_alloc(n, sizeof *label_n, err, "end components") : NULL;
  e->region = label_n ? lsm_alloc(n, sizeof *e->region, err, "end components") : NULL;
  if (!e->region) {
    free(queue);
    free(label_n);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  e->count = lsm_grid_label_components(full, 0.0f, e->region, queue);
  if (!lsm_rule_on(rules, LSM_RULE_END_PARTS) && e->count > 1) { /* the section as one part */
    for (size_t k = 0; k < n; ++k) e->region[k] = e->region[k] >= 0 ? 0 : -1;
    e->count = 1;
  }
  const int m = e->count;
  e->part = lsm_alloc((size_t)m + 1, sizeof *e->part, err, "end components");
  e->first = e->part ? lsm_alloc((size_t)m + 2, sizeof *e->first, err, "end components") : NULL;
  size_t inside = 0;
  for (size_t k = 0; k < n; ++k) inside += e->region[k] >= 0;
  e->inside = e->first ? lsm_alloc(inside + 1, sizeof *e->inside, err, "end components") : NULL;
  if (!e->inside) {
    free(queue);
    free(label_n);
    end_parts_free(e);
    return err ? err->status : LSM_ERR_NOMEM;
  }
  memset(e->part, 0, ((size_t)m + 1) * sizeof *e->part);
  memset(e->first, 0, ((size_t)m + 2) * sizeof *e->first);
  /* F's inside cells grouped by part (a counting sort) */
  for (size_t k = 0; k < n; ++k)
    if (e->region[k] >= 0) e->first[e->region[k] + 1]++;
  for (int c = 0; c < m; ++c) {
    e->part[c].area_f = (double)e->first[c + 1];
    e->first[c + 1] += e->first[c];
  }
  for (size_t k = 0, *fill = e->first; k < n; ++k)
    if (e->region[k] >= 0) e->inside[fill[e->region[k]]++] = (int32_t)k;
  for (int c = m; c > 0; --c) e->first[c] = e->first[c - 1]; /* fill advanced each start */
  e->first[0] = 0;
  lsm_status st = LSM_OK;
  if (nb) st = share_areas(nb, e, label_n, queue, 0, err);
  if (st == LSM_OK && nm) st = share_areas(nm, e, label_n, queue, 1, err);
  if (st != LSM_OK) {
    free(queue);
    free(label_n);
    end_parts_free(e);
    return st;
  }
  for (int c = 0; c < m; ++c) {
    end_part *pc = &e->part[c];
    /* A part mostly outside N grows out toward the end (a tail, a paw, a thin
     * part meeting a wide body): N's area says nothing of how it stops, and
     * it is a flat end (rule end-flat-share). */
    const double share = pc->area_f > 0.0 ? pc->nested / pc->area_f : 0.0;
    pc->weight = !nb ? 0.0
                 : !lsm_rule_on(rules, LSM_RULE_END_FLAT_SHARE)
                     ? 1.0
                     : fmin(fmax((share - rules->end_share_flat) / rules->end_share_ramp, 0.0), 1.0);
    pc->rate = nb ? fmin((pc->area_f - pc->area_n) / hn, 0.0) : 0.0;
    pc->power = rules->end_tip_flat;
    if (lsm_rule_on(rules, LSM_RULE_END_TIP_POWER))
      pc->power += pc->weight * (end_tip_power(pc->area_f, pc->area_n, rules) - rules->end_tip_flat);
  }
  /* every cell joins the part nearest to it (breadth-first from the parts),
   * so each part's erosion moves the field around it */
  size_t tail = 0;
  for (size_t k = 0; k < n; ++k)
    if (e->region[k] >= 0) queue[tail++] = (int32_t)k;
  lsm_flood(e->region, nx, ny, 8, -1, queue, tail);
  free(queue);
  free(label_n);
  return LSM_OK;
}

/* The cells of sorted (ascending, count of them) that stay inside when the
 * field is raised past sorted[cut] (erode_parts): those at least `tie`
 * deeper; all of them when cut == count. */
static size_t cells_kept(const float *sorted, size_t count, size_t cut, float tie) {
  if (cut >= count) return count;
  size_t kept = cut;
  while (kept > 0 && sorted[kept - 1] > sorted[cut] - tie) --kept;
  return kept;
}

/* Moves work around each part c (the cells of its region) uniformly so that
 * the part keeps between least[c] and target[c] of its cells inside.  Too
 * many: raised (an erosion, exact for a signed distance) past the value of
 * the (target+1)-th deepest (cells tied with it leave too, unless that
 * would leave fewer than least[c], or fewer than half the target with the
 * tie nearer to it: then they stay; a target below 1 empties the part).
 * Too few (the per-cell trend took more): lowered until
 * the least[c] deepest of F's cells are inside, but never below F itself
 * (full), so nothing grows past F.  scratch holds nx * ny floats, raise
 * count doubles. */
static void erode_parts(lsm_grid *work, const lsm_grid *full, const end_parts *e,
                        const double *target, const double *least, int tie_nearer,
                        float *scratch, double *raise) {
  const int nx = work->nx;
  for (int c = 0; c < e->count; ++c) {
    /* the part's cells' values, those inside (<= 0) first: each side is
     * sorted only when its order is needed */
    const size_t cells = e->first[c + 1] - e->first[c];
    size_t count = 0, outside = cells;
    for (size_t q = e->first[c]; q < e->first[c + 1]; ++q) {
      const int32_t k = e->inside[q];
      const float v = LSM_AT(work, k % nx, k / nx);
      if (v <= 0.0f)
        scratch[count++] = v;
      else
        scratch[--outside] = v;
    }
    /* (targets are sums of shared areas: a rounding error must not cost a cell) */
    const size_t keep = target[c] < 1.0 ? 0 : (size_t)floor(target[c] + 1e-6);
    size_t need = least[c] < 1.0 ? 0 : (size_t)floor(least[c] + 1e-6);
    if (need > cells) need = cells;
    raise[c] = 0.0;
    if (count > keep) {
      qsort(scratch, count, sizeof *scratch, compare_float);
      const float tie = 1e-4f * work->dx; /* values this close leave together */
      /* cells tied with the cut (the signed distance of a pixel mask has
       * many equal values: a straight edge's row all half a pixel deep)
       * leave together; but where that would keep less than half the
       * target, they stay when that comes nearer it (rule end-tie-nearer: a
       * section of 7 cells eroded to 6.6 keeps 7, not the one cell deeper
       * than its six tied ones).  A target below 1 still empties the part. */
      size_t cut = keep;
      if (keep > 0 && tie_nearer) {
        size_t past = keep;
        while (past < count && scratch[past] < scratch[keep] + tie) ++past;
        const double fewer = (double)cells_kept(scratch, count, keep, tie);
        const double more = (double)cells_kept(scratch, count, past, tie);
        if (fewer < 0.5 * target[c] && more - target[c] < target[c] - fewer) cut = past;
      }
      /* and where the least count is among them, the cut moves past the
       * tie */
      while (need > 0 && cut < count && scratch[cut] <= scratch[need - 1]) ++cut;
      if (cut == 0)
        raise[c] = 1e-3 * work->dx - scratch[0];
      else if (cut < count)
        raise[c] = 1e-4 * work->dx - scratch[cut];
    } else if (count < need) {
      qsort(scratch + count, cells - count, sizeof *scratch, compare_float);
      raise[c] = -1e-4 * work->dx - scratch[need - 1];
    }
  }
  for (int j = 0; j < work->ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int32_t c = e->region[(size_t)j * nx + i];
      if (c < 0) continue;
      float *v = &LSM_AT(work, i, j);
      *v += (float)raise[c];
      if (raise[c] < 0.0) *v = fmaxf(*v, LSM_AT(full, i, j));
    }
}

int lsm_end_profile_is_trend(lsm_end_profile profile) {
  return profile == LSM_END_TREND || profile == LSM_END_TREND_HALFWAY;
}

double lsm_end_depth(const lsm_grid *phi) {
  return fmax(-(double)lsm_grid_min(phi), 0.5 * fmin(phi->dx, phi->dy));
}

double lsm_end_depth_in(const lsm_grid *phi, int x0, int y0, int nx, int ny) {
  float least = 0.0f;
  for (int j = y0 < 0 ? 0 : y0; j < y0 + ny && j < phi->ny; ++j)
    for (int i = x0 < 0 ? 0 : x0; i < x0 + nx && i < phi->nx; ++i)
      least = fminf(least, LSM_AT(phi, i, j));
  return fmax(-(double)least, 0.5 * fmin(phi->dx, phi->dy));
}

double lsm_end_cap_depth(double R, double sigma, double dx) {
  if (sigma >= 0.5) return R * (1.0 + 1e-6) + 1e-6 * dx;
  return R * (1.0 - sqrt(1.0 - 2.0 * sigma));
}

struct lsm_end {
  lsm_end_profile profile;
  const lsm_grid *full; /* F's phi (borrowed) */
  double R;             /* F's largest depth (linear profiles) */
  double H;             /* the gap's height */
  double trend_reach;   /* how far past F the per-cell trend is carried (h_N) */
  double h_farther;     /* |z_M - z_N| */
  int has_beyond;       /* there is a slice N beyond F */
  lsm_grid *slope;      /* per cell max(phi_F - phi_N, 0): the slope times h_N (trend) */
  end_parts parts;      /* F's components and how each ends (trend) */
  const lsm_rules *rules; /* the rules and constants (borrowed) */
  double *target;       /* per part: cells kept at the current sigma, at most */
  double *least;        /* per part: and at least (a tenth of the tip) */
  double *raise;        /* per part: the erosion that keeps them */
  float *scratch;       /* one float per cell */
};

void lsm_end_destroy(lsm_end **end) {
  if (!end || !*end) return;
  lsm_end *e = *end;
  lsm_grid_destroy(&e->slope);
  end_parts_free(&e->parts);
  free(e->target);
  free(e->least);
  free(e->raise);
  free(e->scratch);
  free(e);
  *end = NULL;
}

lsm_status lsm_end_create(const lsm_grid *full, const lsm_grid *beyond, double h_beyond,
                          const lsm_grid *farther, double h_farther, double H,
                          lsm_end_profile profile, const lsm_rules *rules, lsm_end **out,
                          lsm_err *err) {
  *out = NULL;
  if (!rules) rules = lsm_rules_defaults();
  lsm_end *e = lsm_alloc(1, sizeof *e, err, "end of an object");
  if (!e) return err ? err->status : LSM_ERR_NOMEM;
  memset(e, 0, sizeof *e);
  e->profile = profile;
  e->rules = rules;
  e->full = full;
  e->R = lsm_end_depth(full);
  e->H = H;
  e->trend_reach = H;
  if (!lsm_end_profile_is_trend(profile)) {
    *out = e;
    return LSM_OK;
  }
  const size_t cells = (size_t)full->nx * (size_t)full->ny;
  lsm_status st = lsm_grid_clone(full, &e->slope, err);
  if (st == LSM_OK && !(e->scratch = lsm_alloc(cells, sizeof *e->scratch, err, "end cells")))
    st = err ? err->status : LSM_ERR_NOMEM;
  if (st == LSM_OK) {
    const double hn = beyond ? h_beyond : 1.0;
    e->trend_reach = hn;
    e->has_beyond = beyond != NULL;
    /* the slope times h_N: a difference of phi, whatever the units of z
     * (rule end-trend) */
    const int trend = beyond && lsm_rule_on(rules, LSM_RULE_END_TREND);
    for (int j = 0; j < full->ny; ++j)
      for (int i = 0; i < full->nx; ++i)
        LSM_AT(e->slope, i, j) =
            trend ? fmaxf(LSM_AT(full, i, j) - LSM_AT(beyond, i, j), 0.0f) : 0.0f;
    /* with no slice N beyond F (a lone section) nothing tells how the object
     * ends: every part is a flat end */
    e->h_farther = h_farther;
    st = end_parts_find(full, beyond, hn, beyond ? farther : NULL, rules, &e->parts, err);
  }
  const size_t parts = (size_t)e->parts.count + 1;
  if (st == LSM_OK && !(e->target = lsm_alloc(parts, sizeof *e->target, err, "end parts")))
    st = err ? err->status : LSM_ERR_NOMEM;
  if (st == LSM_OK && !(e->least = lsm_alloc(parts, sizeof *e->least, err, "end parts")))
    st = err ? err->status : LSM_ERR_NOMEM;
  if (st == LSM_OK && !(e->raise = lsm_alloc(parts, sizeof *e->raise, err, "end parts")))
    st = err ? err->status : LSM_ERR_NOMEM;
  if (st != LSM_OK) {
    lsm_end_destroy(&e);
    return st;
  }
  *out = e;
  return LSM_OK;
}

void lsm_end_set_depth(lsm_end *end, double R) { end->R = R; }

void lsm_end_at(lsm_end *e, double sigma, lsm_grid *work) {
  const lsm_grid *full = e->full;
  const lsm_rules *rules = e->rules;
  if (e->profile == LSM_END_BLEND) {
    /* the textbook: the empty slice is R; from mid-gap on nothing is left
     * (at mid-gap the deepest cell's 0 is a tie, outside: a millionth of dx) */
    const float keep = (float)(1.0 - sigma), rise = (float)(sigma * e->R);
    const float above = (float)(1e-6 * full->dx);
    for (int j = 0; j < work->ny; ++j)
      for (int i = 0; i < work->nx; ++i) {
        const float v = keep * LSM_AT(full, i, j) + rise;
        LSM_AT(work, i, j) = sigma >= 0.5 && !(v > 0.0f) ? above : v;
      }
    return;
  }
  if (!lsm_end_profile_is_trend(e->profile)) {
    const float depth = (float)lsm_end_cap_depth(e->R, sigma, full->dx);
    for (int j = 0; j < work->ny; ++j)
      for (int i = 0; i < work->nx; ++i) LSM_AT(work, i, j) = LSM_AT(full, i, j) + depth;
    return;
  }
  /* the trend carried sigma H past F, at most h_N (rule end-trend-reach), in
   * units of h_N */
  const double carried = sigma * (e->H / e->trend_reach);
  const float rise =
      (float)(lsm_rule_on(rules, LSM_RULE_END_TREND_REACH) ? fmin(carried, 1.0) : carried);
  for (int j = 0; j < work->ny; ++j)
    for (int i = 0; i < work->nx; ++i)
      LSM_AT(work, i, j) = LSM_AT(full, i, j) + rise * LSM_AT(e->slope, i, j);
  /* 1 up to mid-gap, then falling to 0 at the empty slice, or 0 at once
   * without the tip */
  const double tip = e->profile == LSM_END_TREND_HALFWAY ? (sigma > 0.5 + 1e-9 ? 0.0 : 1.0)
                                                         : fmin(1.0, 2.0 * (1.0 - sigma));
  for (int c = 0; c < e->parts.count; ++c) {
    const end_part *pc = &e->parts.part[c];
    const double tip_area = pc->area_f * pow(tip, pc->power);
    /* With a third section M beyond N the parabola through the areas of M,
     * N and F caps the narrowing share (rule end-parabola); without M the
     * line through A_N and A_F does (rule end-line), and the parabola through
     * A_N, A_F and zero at the empty slice, the latest a quadratic area
     * through N and F can close. */
    const int has_m = pc->has_m && e->h_farther > 0.0;
    e->target[c] = tip_area;
    if (!has_m && lsm_rule_on(rules, LSM_RULE_END_LINE)) {
      const double narrowing = fmax(pc->weight * (pc->area_f + sigma * e->H * pc->rate), 0.0);
      e->target[c] = fmin(narrowing + (1.0 - pc->weight) * pc->area_f, tip_area);
    }
    if (e->has_beyond && lsm_rule_on(rules, LSM_RULE_END_PARABOLA)) {
      /* Newton's form, z from F toward the end */
      const double hn = e->trend_reach, z = sigma * e->H;
      const double d1 = (pc->area_f - pc->area_n) / hn;
      double curvature;
      if (has_m) {
        const double hm = e->h_farther, d0 = (pc->area_n - pc->area_m) / hm;
        curvature = (d1 - d0) / (hn + hm);
      } else {
        curvature = (-pc->area_f / e->H - d1) / (e->H + hn);
      }
      /* a parabola opening upward is held at its vertex past it: an area
       * that shrank toward F and would grow again closes no later (rule
       * end-parabola-vertex) */
      double zc = z;
      if (curvature > 0.0 && lsm_rule_on(rules, LSM_RULE_END_PARABOLA_VERTEX)) {
        const double z_vertex = -(d1 + curvature * hn) / (2.0 * curvature);
        if (z_vertex > 0.0 && z > z_vertex) zc = z_vertex;
      }
      const double parabola = pc->area_f + d1 * zc + curvature * zc * (zc + hn);
      e->target[c] = fmin(e->target[c], (1.0 - pc->weight) * pc->area_f +
                                            pc->weight * fmin(fmax(parabola, 0.0), pc->area_f));
    }
    /* (rule end-floor) */
    e->least[c] = lsm_rule_on(rules, LSM_RULE_END_FLOOR)
                      ? rules->end_floor * pc->area_f * pow(tip, pc->power - 1.0)
                      : 0.0;
    e->target[c] = fmax(e->target[c], e->least[c]);
  }
  erode_parts(work, full, &e->parts, e->target, e->least,
              lsm_rule_on(rules, LSM_RULE_END_TIE_NEARER), e->scratch, e->raise);
}
