/* lsm_band: the narrow band of a pair morph (see the header).
 *
 * Sets of cells are bitmaps, a row of `words` 64-bit words per grid row (bit b of word w is
 * column 64 w + b), so that widening the kept levels into the band is a few word operations
 * per row and step, and a segment of LSM_BAND_SEGMENT = 8 cells is one byte. */
#include "solver/pde/lsm_band.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernels/lsm_cell.h"

/* The levels kept: the particle level set's band, 3 cell widths (solver/README.md §11). */
#define BAND_LEVEL_CELLS 3.0f
/* The travel allowed between rebuilds (cells): solver/README.md §4, "The narrow band". */
#define BAND_TRAVEL_CELLS 4

typedef struct heap_entry {
  double g;        /* the relaxation factor at which the cell comes within the kept levels */
  float amplitude; /* the cell's amplitude then (an entry whose cell's has changed is stale) */
  int32_t k;       /* the cell's offset */
} heap_entry;

/* A growable array of n elements of `size` bytes. */
typedef struct vec {
  void *data;
  size_t n, cap, size;
} vec;

struct lsm_band {
  lsm_band_params p;
  int nx, ny, words;
  ptrdiff_t stride;
  double inv_stride;
  uint64_t last_mask;         /* the bits of a row's last word inside the grid */
  const float *target;        /* borrowed: the caller's phi_target */
  lsm_grid *amplitude;        /* phi = target + amplitude g outside the band */
  uint64_t *band, *next, *kept, *rim, *row_tmp; /* bitmaps (ny words rows), a row */
  uint64_t *facing; /* cells kept from the start: the slices' fronts face each other */
  vec heap;                   /* heap_entry: max-heap on g */
  vec run_start, run_length, rim_cells, rim_amplitude, enter, enter_value;
  size_t cells;
  int kept_lo, kept_hi, band_lo, band_hi; /* rows holding kept levels, band cells (lo > hi: none) */
  int facing_lo, facing_hi;               /* ... facing cells */
  uint8_t *flags;                         /* a run's kept flags (nx) */
  float speed, enter_speed;
  int edge; /* the band's stencils read the ghost ring */
};

static int vec_reserve(vec *v, size_t need) {
  if (need <= v->cap) return 1;
  size_t cap = v->cap ? v->cap : 256;
  while (cap < need) cap *= 2;
  void *d = realloc(v->data, cap * v->size);
  if (!d) return 0;
  v->data = d;
  v->cap = cap;
  return 1;
}

static void vec_free(vec *v) {
  free(v->data);
  v->data = NULL;
  v->n = v->cap = 0;
}

int lsm_scheme_reach(lsm_scheme scheme) {
  return scheme == LSM_SCHEME_ROEFIX ? 4 : scheme == LSM_SCHEME_WENO5 ? 3 : 1;
}

void lsm_band_params_of(lsm_scheme scheme, float dx, float dy, lsm_band_params *params) {
  params->level = BAND_LEVEL_CELLS * (dx > dy ? dx : dy);
  params->reach = lsm_scheme_reach(scheme);
  params->travel = BAND_TRAVEL_CELLS;
}

/* ---- the heap of cells outside the band, by the g at which they enter ------------------ */

/* The g below g_now at which target + amplitude g, outside [-level, level] at g_now, comes
 * into it: the cell's value runs from its present one to the target's as g falls.  -1: never
 * (the target beyond the levels on the same side, or the levels crossed before g_now). */
static double enter_g(float target, float amplitude, float level, double g_now) {
  double g = -1.0;
  if (amplitude > 0.0f && target <= level) g = ((double)level - target) / amplitude;
  if (amplitude < 0.0f && target >= -level) g = ((double)level + target) / -amplitude;
  return g < g_now ? g : -1.0;
}

/* The g below g_now at which cell k's value t + a g becomes an extremum of its 4-neighbours'
 * that the morph holds: a minimum where phi falls towards the target (a > 0), a maximum where
 * it rises (a < 0).  The upwind Hamiltonian is 0 there (the viscosity solution keeps such an
 * extremum), so from then on the cell no longer follows t + a g: it must be in the band.  Each
 * neighbour n bounds g by the sign of (t_n - t_k) + g (a_n - a_k); -1: never, or already (the
 * kept levels decide then). */
static double extremum_g(const float *t, const float *a, ptrdiff_t k, ptrdiff_t s, int i, int j,
                         int nx, int ny, double g_now) {
  if (a[k] == 0.0f) return -1.0;
  const double sign = a[k] > 0.0f ? 1.0 : -1.0;
  const ptrdiff_t nb[4] = {k - 1, k + 1, k - s, k + s};
  const int inside[4] = {i > 0, i + 1 < nx, j > 0, j + 1 < ny};
  double lo = 0.0, hi = INFINITY;
  for (int q = 0; q < 4; ++q) {
    if (!inside[q]) continue; /* the ghost repeats the cell: no bound */
    const double p = sign * ((double)t[nb[q]] - t[k]), r = sign * ((double)a[nb[q]] - a[k]);
    if (r > 0.0) {
      const double g = -p / r;
      lo = g > lo ? g : lo;
    } else if (r < 0.0) {
      const double g = p / -r;
      hi = g < hi ? g : hi;
    } else if (p < 0.0) {
      return -1.0;
    }
  }
  return hi >= lo && hi > 0.0 && hi < g_now ? hi : -1.0;
}

/* The g at which cell k (column i, row j) enters the band by itself: the larger of the two
 * above; -1 never. */
static double wait_g(const lsm_band *b, ptrdiff_t k, int i, int j, double g_now) {
  const float *a = b->amplitude->data;
  const double level = enter_g(b->target[k], a[k], b->p.level, g_now);
  const double extremum = extremum_g(b->target, a, k, b->stride, i, j, b->nx, b->ny, g_now);
  return extremum > level ? extremum : level;
}

static int heap_push(vec *h, heap_entry x) {
  if (!vec_reserve(h, h->n + 1)) return 0;
  heap_entry *e = h->data;
  size_t k = h->n++;
  while (k > 0) {
    size_t up = (k - 1) / 2;
    if (e[up].g >= x.g) break;
    e[k] = e[up];
    k = up;
  }
  e[k] = x;
  return 1;
}

/* Moves x down from slot k of e[0 .. n) to its place. */
static void heap_sift(heap_entry *e, size_t n, size_t k, heap_entry x) {
  for (;;) {
    size_t c = 2 * k + 1;
    if (c >= n) break;
    if (c + 1 < n && e[c + 1].g > e[c].g) c++;
    if (e[c].g <= x.g) break;
    e[k] = e[c];
    k = c;
  }
  e[k] = x;
}

static heap_entry heap_pop(vec *h) {
  heap_entry *e = h->data;
  const heap_entry top = e[0];
  if (--h->n) heap_sift(e, h->n, 0, e[h->n]);
  return top;
}

double lsm_band_next_g(const lsm_band *b) {
  return b->heap.n ? ((const heap_entry *)b->heap.data)[0].g : 0.0;
}

float lsm_band_speed(const lsm_band *b) { return b->speed; }
float lsm_band_enter_speed(const lsm_band *b) { return b->enter_speed; }

/* ---- bitmaps ------------------------------------------------------------------------------ */

static inline uint64_t *row_bits(const lsm_band *b, uint64_t *map, int j) {
  return map + (size_t)j * (size_t)b->words;
}

static inline int has_bit(const lsm_band *b, const uint64_t *map, ptrdiff_t k) {
  int j = (int)((double)k * b->inv_stride);
  while ((ptrdiff_t)(j + 1) * b->stride <= k) ++j;
  while ((ptrdiff_t)j * b->stride > k) --j;
  const int i = (int)(k - (ptrdiff_t)j * b->stride);
  return (int)((map[(size_t)j * (size_t)b->words + (size_t)(i >> 6)] >> (i & 63)) & 1u);
}

/* Sets cell k's bit; returns its row. */
static inline int set_bit(const lsm_band *b, uint64_t *map, ptrdiff_t k) {
  int j = (int)((double)k * b->inv_stride);
  while ((ptrdiff_t)(j + 1) * b->stride <= k) ++j;
  while ((ptrdiff_t)j * b->stride > k) --j;
  const int i = (int)(k - (ptrdiff_t)j * b->stride);
  map[(size_t)j * (size_t)b->words + (size_t)(i >> 6)] |= (uint64_t)1 << (i & 63);
  return j;
}

/* Widens the row range *lo .. *hi to hold row j. */
static inline void note_row(int *lo, int *hi, int j) {
  if (j < *lo) *lo = j;
  if (j > *hi) *hi = j;
}

/* One 4-neighbour step of dilation of map in place over its rows *lo .. *hi (the others are
 * empty), which grow by one: each row ORed with its neighbours one column either side and
 * with the rows above and below (as they were). */
static void dilate_step(lsm_band *b, uint64_t *map, int *lo, int *hi) {
  const int w = b->words;
  if (*lo > *hi) return;
  if (*lo > 0) --*lo;
  if (*hi + 1 < b->ny) ++*hi;
  uint64_t *above = b->row_tmp, *here = b->row_tmp + w;
  memset(above, 0, (size_t)w * sizeof *above);
  for (int j = *lo; j <= *hi; ++j) {
    uint64_t *row = row_bits(b, map, j);
    memcpy(here, row, (size_t)w * sizeof *here);
    const uint64_t *below = j + 1 < b->ny ? row_bits(b, map, j + 1) : NULL;
    for (int q = 0; q < w; ++q) {
      const uint64_t x = here[q];
      uint64_t y = x | (x << 1) | (x >> 1) | above[q];
      if (q > 0) y |= here[q - 1] >> 63;
      if (q + 1 < w) y |= here[q + 1] << 63;
      if (below) y |= below[q];
      row[q] = y;
    }
    row[w - 1] &= b->last_mask;
    uint64_t *t = above;
    above = here;
    here = t;
  }
}

/* Every byte (a segment) of map's rows lo .. hi with a bit set becomes whole, within the grid. */
static void widen_segments(lsm_band *b, uint64_t *map, int lo, int hi) {
  for (int j = lo; j <= hi; ++j) {
    uint64_t *row = row_bits(b, map, j);
    for (int q = 0; q < b->words; ++q) {
      uint64_t x = row[q];
      x |= x >> 1;
      x |= x >> 2;
      x |= x >> 4;
      row[q] = (x & 0x0101010101010101u) * 0xFFu;
    }
    row[b->words - 1] &= b->last_mask;
  }
}

#define NOMEM(err) lsm_fail(err, LSM_ERR_NOMEM, NULL, "narrow band: out of memory")

/* From the kept levels (b->kept): the band (travel + reach steps around them, whole
 * segments), the cells entering and leaving it, the rim and the runs.  phi: the old band's
 * values (NULL at creation: no old band). */
static lsm_status build(lsm_band *b, const float *phi, float g, lsm_err *err) {
  const int w = b->words;
  const size_t n = (size_t)b->ny * (size_t)w;
  const ptrdiff_t s = b->stride;
  float *a = b->amplitude->data;
  memcpy(b->next, b->kept, n * sizeof *b->next);
  int lo = b->kept_lo, hi = b->kept_hi;
  for (int d = 0; d < b->p.travel + b->p.reach; ++d) dilate_step(b, b->next, &lo, &hi);
  widen_segments(b, b->next, lo, hi);
  /* entering and leaving cells over the rows of either band; the runs */
  b->enter.n = b->run_start.n = 0;
  b->cells = 0;
  float enter_speed = 0.0f;
  const int j0 = lo < b->band_lo ? lo : b->band_lo, j1 = hi > b->band_hi ? hi : b->band_hi;
  for (int j = j0; j <= j1; ++j) {
    const uint64_t *now = row_bits(b, b->band, j), *next = row_bits(b, b->next, j);
    for (int q = 0; q < w; ++q) {
      if (!(next[q] | now[q])) continue;
      uint64_t in = next[q] & ~now[q], out = now[q] & ~next[q];
      b->cells += (size_t)__builtin_popcountll(next[q]);
      if (phi && in) {
        if (!vec_reserve(&b->enter, b->enter.n + 64) ||
            !vec_reserve(&b->enter_value, b->enter.n + 64))
          return NOMEM(err);
        for (; in; in &= in - 1) {
          const ptrdiff_t k = (ptrdiff_t)j * s + 64 * q + __builtin_ctzll(in);
          const float v = lsm_relaxed(b->target[k], a[k], g);
          ((int32_t *)b->enter.data)[b->enter.n] = (int32_t)k;
          ((float *)b->enter_value.data)[b->enter.n++] = v;
          enter_speed = lsm_maxf(enter_speed, fabsf(v - b->target[k]));
        }
      }
      /* cells leaving the band keep their value as amplitude, and wait on the heap */
      for (; phi && out; out &= out - 1) {
        const ptrdiff_t k = (ptrdiff_t)j * s + 64 * q + __builtin_ctzll(out);
        a[k] = (float)(((double)phi[k] - (double)b->target[k]) / (double)g);
        const int i = 64 * q + __builtin_ctzll(out);
        const double ge = wait_g(b, k, i, j, g);
        if (ge > 0.0 && !heap_push(&b->heap, (heap_entry){ge, a[k], (int32_t)k}))
          return NOMEM(err);
      }
    }
    /* runs: consecutive segments (bytes; the last one clipped to the grid) */
    for (int m = 0; m < w * 8; ++m) {
      if (!(m & 7) && !next[m >> 3]) {
        m += 7;
        continue;
      }
      if (!((next[m >> 3] >> (8 * (m & 7))) & 0xFFu)) continue;
      const int i0 = 8 * m;
      int len = b->nx - i0 < 8 ? b->nx - i0 : 8;
      if (!vec_reserve(&b->run_start, b->run_start.n + 1) ||
          !vec_reserve(&b->run_length, b->run_start.n + 1))
        return NOMEM(err);
      int32_t *start = b->run_start.data, *length = b->run_length.data;
      const int32_t k0 = (int32_t)((ptrdiff_t)j * s + i0);
      size_t r = b->run_start.n;
      if (r && start[r - 1] + length[r - 1] == k0) {
        length[r - 1] += len;
      } else {
        start[r] = k0;
        length[r] = len;
        b->run_start.n++;
      }
    }
  }
  b->run_length.n = b->run_start.n;
  b->enter_value.n = b->enter.n;
  b->enter_speed = enter_speed;
  uint64_t *t = b->band;
  b->band = b->next;
  b->next = t;
  b->band_lo = lo;
  b->band_hi = hi;
  /* the rim: within reach of the band, outside it */
  memcpy(b->rim, b->band, n * sizeof *b->rim);
  for (int d = 0; d < b->p.reach; ++d) dilate_step(b, b->rim, &lo, &hi);
  /* the stencils read the ghost ring when the band comes within reach of the grid's edge */
  b->edge = 0;
  for (int j = lo; j <= hi && !b->edge; ++j) {
    const uint64_t *rim = row_bits(b, b->rim, j);
    if (j == 0 || j + 1 == b->ny) {
      for (int q = 0; q < w; ++q) b->edge |= rim[q] != 0;
    } else {
      b->edge = (rim[0] & 1u) || ((rim[(b->nx - 1) >> 6] >> ((b->nx - 1) & 63)) & 1u);
    }
  }
  b->rim_cells.n = 0;
  for (int j = lo; j <= hi; ++j) {
    const uint64_t *band = row_bits(b, b->band, j), *rim = row_bits(b, b->rim, j);
    for (int q = 0; q < w; ++q) {
      uint64_t x = rim[q] & ~band[q];
      if (!x) continue;
      if (!vec_reserve(&b->rim_cells, b->rim_cells.n + 64) ||
          !vec_reserve(&b->rim_amplitude, b->rim_cells.n + 64))
        return NOMEM(err);
      for (; x; x &= x - 1) {
        const ptrdiff_t k = (ptrdiff_t)j * s + 64 * q + __builtin_ctzll(x);
        ((int32_t *)b->rim_cells.data)[b->rim_cells.n] = (int32_t)k;
        ((float *)b->rim_amplitude.data)[b->rim_cells.n++] = a[k];
      }
    }
  }
  b->rim_amplitude.n = b->rim_cells.n;
  /* entries of cells in the band are dropped (a cell leaving it is entered again) */
  while (b->heap.n && has_bit(b, b->band, ((heap_entry *)b->heap.data)[0].k)) heap_pop(&b->heap);
  return LSM_OK;
}

/* Whether the gradients of the two slices' distances (central differences) are more than 90
 * degrees apart at interior cell k: the slices' fronts face each other there, and the blend's
 * gradient |(1 - s) grad a + s grad b| falls below cos 45 degrees on the way. */
static int facing(const float *a, const float *b, ptrdiff_t k, ptrdiff_t s) {
  const float ax = a[k + 1] - a[k - 1], ay = a[k + s] - a[k - s];
  const float bx = b[k + 1] - b[k - 1], by = b[k + s] - b[k - s];
  return ax * bx + ay * by < 0.0f;
}

/* A kept level: |v| <= level, a sign change against a 4-neighbour (the front), or an extremum
 * the morph holds.  phi holds values at the cell and its 4-neighbours (the band's, its rim's
 * and ghosts'). */
static inline int kept(const float *p, const float *t, ptrdiff_t k, ptrdiff_t s, float level) {
  const float v = p[k], l = p[k - 1], r = p[k + 1], d = p[k - s], u = p[k + s];
  const float lo = lsm_minf(lsm_minf(l, r), lsm_minf(d, u));
  const float hi = lsm_maxf(lsm_maxf(l, r), lsm_maxf(d, u));
  const float F = v - t[k];
  /* near zero; a sign change against a neighbour (the front); an extremum the morph holds
   * (extremum_g): a minimum where phi falls, a maximum where it rises */
  return (fabsf(v) <= level) | (v > 0.0f && lo < 0.0f) | (v < 0.0f && hi > 0.0f) |
         (F > 0.0f && v <= lo) | (F < 0.0f && v >= hi);
}

lsm_status lsm_band_create(const lsm_grid *phi_source, const lsm_grid *phi_target,
                           const lsm_band_params *params, lsm_band **out, lsm_err *err) {
  *out = NULL;
  const int nx = phi_source->nx, ny = phi_source->ny;
  const ptrdiff_t s = phi_source->stride;
  if (phi_target->nx != nx || phi_target->ny != ny)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "narrow band: source and target sizes differ");
  if ((double)(ny + 2 * LSM_GHOST) * (double)s > (double)INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, NULL,
                    "narrow band: a %dx%d grid is too large for its 32-bit cell lists (use --band off)",
                    nx, ny);
  if (params->reach < 1 || params->travel < 1)
    return lsm_fail(err, LSM_ERR_INTERNAL, NULL, "narrow band: widths out of range");
  lsm_band *b = calloc(1, sizeof *b);
  if (!b) return lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a narrow band");
  b->p = *params;
  b->nx = nx;
  b->ny = ny;
  b->words = (nx + 63) / 64;
  b->stride = s;
  b->inv_stride = 1.0 / (double)s;
  b->last_mask = nx % 64 ? ((uint64_t)1 << (nx % 64)) - 1 : ~(uint64_t)0;
  b->heap.size = sizeof(heap_entry);
  b->run_start.size = b->run_length.size = b->rim_cells.size = b->enter.size = sizeof(int32_t);
  b->rim_amplitude.size = b->enter_value.size = sizeof(float);
  b->target = phi_target->data;
  const size_t words = (size_t)ny * (size_t)b->words;
  lsm_status st = lsm_grid_clone(phi_source, &b->amplitude, err);
  if (st == LSM_OK) {
    b->band = calloc(words, sizeof(uint64_t));
    b->next = calloc(words, sizeof(uint64_t));
    b->kept = calloc(words, sizeof(uint64_t));
    b->rim = calloc(words, sizeof(uint64_t));
    b->row_tmp = calloc(2 * (size_t)b->words, sizeof(uint64_t));
    b->flags = malloc((size_t)nx);
    if (!b->band || !b->next || !b->kept || !b->rim || !b->row_tmp || !b->flags)
      st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a narrow band");
  }
  /* the source's kept levels (its ghosts filled), amplitudes, and the cells that wait on the
   * heap for their values to come near zero (those the band takes in are dropped later) */
  float *amp = b->amplitude->data;
  const float *src = phi_source->data, *t = b->target;
  if (st == LSM_OK && !(b->facing = calloc(words, sizeof(uint64_t))))
    st = lsm_fail(err, LSM_ERR_NOMEM, NULL, "cannot allocate a narrow band");
  for (int j = 0; st == LSM_OK && j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const ptrdiff_t k = (ptrdiff_t)j * s + i;
      amp[k] = src[k] - t[k];
    }
  /* the source's kept levels (its ghosts filled); where the two slices' fronts face each other
   * and the value will come near zero, the morph departs from t + a g at once (a split, a
   * merge, a hole, a part appearing): those cells are kept from the start; the others wait on
   * the heap for their values to come near zero (heap_sift orders it below) */
  for (int j = 0; st == LSM_OK && j < ny; ++j) {
    uint64_t *kept_row = row_bits(b, b->kept, j), *facing_row = row_bits(b, b->facing, j);
    for (int i = 0; i < nx; ++i) {
      const ptrdiff_t k = (ptrdiff_t)j * s + i;
      const uint64_t bit = (uint64_t)1 << (i & 63);
      const int opposed = i > 0 && j > 0 && i + 1 < nx && j + 1 < ny && facing(src, t, k, s);
      const double ge = enter_g(t[k], amp[k], params->level, 1.0);
      if (opposed && ge > 0.0) {
        kept_row[i >> 6] |= bit;
        facing_row[i >> 6] |= bit;
      } else if (kept(src, t, k, s, params->level)) {
        kept_row[i >> 6] |= bit;
      } else {
        const double wait = wait_g(b, k, i, j, 1.0);
        if (wait > 0.0) {
          if (!vec_reserve(&b->heap, b->heap.n + 1)) {
            st = NOMEM(err);
            break;
          }
          ((heap_entry *)b->heap.data)[b->heap.n++] = (heap_entry){wait, amp[k], (int32_t)k};
        }
      }
    }
  }
  b->kept_lo = b->facing_lo = b->band_lo = ny;
  b->kept_hi = b->facing_hi = b->band_hi = -1;
  for (int j = 0; st == LSM_OK && j < ny; ++j)
    for (int q = 0; q < b->words; ++q) {
      if (row_bits(b, b->kept, j)[q]) note_row(&b->kept_lo, &b->kept_hi, j);
      if (row_bits(b, b->facing, j)[q]) note_row(&b->facing_lo, &b->facing_hi, j);
    }
  heap_entry *e = b->heap.data;
  for (size_t k = b->heap.n / 2; st == LSM_OK && k-- > 0;) heap_sift(e, b->heap.n, k, e[k]);
  if (st == LSM_OK) st = build(b, NULL, 1.0f, err);
  const int32_t *rs = b->run_start.data, *rl = b->run_length.data;
  for (size_t r = 0; st == LSM_OK && r < b->run_start.n; ++r)
    for (int32_t k = rs[r]; k < rs[r] + rl[r]; ++k) b->speed = lsm_maxf(b->speed, fabsf(amp[k]));
  if (st != LSM_OK) {
    lsm_band_destroy(&b);
    return st;
  }
  *out = b;
  return LSM_OK;
}

void lsm_band_destroy(lsm_band **band) {
  if (!band || !*band) return;
  lsm_band *b = *band;
  lsm_grid_destroy(&b->amplitude);
  free(b->band);
  free(b->next);
  free(b->kept);
  free(b->rim);
  free(b->row_tmp);
  free(b->flags);
  free(b->facing);
  vec *v[] = {&b->heap, &b->run_start, &b->run_length, &b->rim_cells, &b->rim_amplitude,
              &b->enter, &b->enter_value};
  for (size_t q = 0; q < sizeof v / sizeof v[0]; ++q) vec_free(v[q]);
  free(b);
  *band = NULL;
}

lsm_status lsm_band_rebuild(lsm_band *b, const lsm_grid *phi, double g, lsm_err *err) {
  const float level = b->p.level;
  const float *p = phi->data, *a = b->amplitude->data;
  const ptrdiff_t s = b->stride;
  memcpy(b->kept, b->facing, (size_t)b->ny * (size_t)b->words * sizeof *b->kept);
  b->kept_lo = b->facing_lo;
  b->kept_hi = b->facing_hi;
  float speed = 0.0f;
  /* the kept levels lie in the old band (a level moves at most `travel` cells between
   * rebuilds) ... */
  const int32_t *rs = b->run_start.data, *rl = b->run_length.data;
  for (size_t r = 0; r < b->run_start.n; ++r) {
    int j = (int)((double)rs[r] * b->inv_stride);
    while ((ptrdiff_t)(j + 1) * s <= rs[r]) ++j;
    while ((ptrdiff_t)j * s > rs[r]) --j;
    uint64_t *row = row_bits(b, b->kept, j);
    const int i0 = (int)(rs[r] - (ptrdiff_t)j * s), len = rl[r];
    /* flags of a run, branch-free (vectorised), then its bits */
    for (int q = 0; q < len; ++q) {
      const ptrdiff_t k = rs[r] + q;
      speed = lsm_maxf(speed, fabsf(p[k] - b->target[k]));
      b->flags[q] = (uint8_t)kept(p, b->target, k, s, level);
    }
    uint64_t any = 0;
    for (int q = 0; q < len; ++q) {
      row[(i0 + q) >> 6] |= (uint64_t)b->flags[q] << ((i0 + q) & 63);
      any |= b->flags[q];
    }
    if (any) note_row(&b->kept_lo, &b->kept_hi, j);
  }
  /* ... or where a value outside it has come near zero (a front may appear there) */
  while (b->heap.n && ((heap_entry *)b->heap.data)[0].g >= g) {
    const heap_entry e = heap_pop(&b->heap);
    if (has_bit(b, b->band, e.k) || a[e.k] != e.amplitude) continue; /* stale */
    note_row(&b->kept_lo, &b->kept_hi, set_bit(b, b->kept, e.k));
  }
  LSM_TRY(build(b, p, (float)g, err));
  b->speed = lsm_maxf(speed, b->enter_speed);
  return LSM_OK;
}

lsm_band_lists lsm_band_get(const lsm_band *b) {
  return (lsm_band_lists){.run_start = b->run_start.data,
                          .run_length = b->run_length.data,
                          .runs = b->run_start.n,
                          .cells = b->cells,
                          .rim = b->rim_cells.data,
                          .rim_amplitude = b->rim_amplitude.data,
                          .rim_cells = b->rim_cells.n,
                          .enter = b->enter.data,
                          .enter_value = b->enter_value.data,
                          .entered = b->enter.n,
                          .edge = b->edge};
}

void lsm_band_materialize(const lsm_band *b, const lsm_grid *phi, double g, lsm_grid *out,
                          int threads) {
  const float gf = (float)g;
  const float *amp = b->amplitude->data, *p = phi->data;
  float *o = out->data;
#pragma omp parallel for num_threads(lsm_grid_threads(out, threads)) schedule(static)
  for (int j = 0; j < b->ny; ++j) {
    const ptrdiff_t row = (ptrdiff_t)j * b->stride;
    const uint64_t *in = row_bits(b, b->band, j);
    for (int q = 0; q < b->words; ++q) {
      const int i0 = 64 * q, i1 = i0 + 64 < b->nx ? i0 + 64 : b->nx;
      const uint64_t w = in[q];
      if (!w) { /* a word outside the band: a loop that vectorises */
        for (int i = i0; i < i1; ++i)
          o[row + i] = lsm_relaxed(b->target[row + i], amp[row + i], gf);
      } else {
        for (int i = i0; i < i1; ++i)
          o[row + i] = (w >> (i & 63)) & 1u ? p[row + i]
                                            : lsm_relaxed(b->target[row + i], amp[row + i], gf);
      }
    }
  }
}

void lsm_band_rescale(lsm_band *b, double factor) {
  float *a = b->amplitude->data;
  for (int j = 0; j < b->ny; ++j)
    for (int i = 0; i < b->nx; ++i) a[(ptrdiff_t)j * b->stride + i] *= (float)factor;
  float *ra = b->rim_amplitude.data;
  for (size_t q = 0; q < b->rim_cells.n; ++q) ra[q] *= (float)factor;
  heap_entry *e = b->heap.data;
  for (size_t q = 0; q < b->heap.n; ++q) { /* the order is kept */
    e[q].g /= factor;
    e[q].amplitude *= (float)factor;
  }
}
