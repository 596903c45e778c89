/* lsm_mesh: streaming marching tetrahedra (see lsm_mesh.h). */
#include "io/lsm_mesh.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Padded planes are numbered p = 0 (the pad below the first slice), 1..N (the
 * slices), N+1 (the pad above).  Slab s lies between planes s and s+1; it is
 * meshed once plane s+2 exists (its gradients need planes s-1 .. s+2), so a
 * ring of 4 planes suffices.  Grid edges go from a node to the node + d with
 * d in {x, y, xy} (in a plane) or {z, xz, yz, xyz} (across a slab), keyed by
 * their lower node: 3 index planes per padded plane (two kept: the slab's
 * bottom and top) and 4 per slab.
 *
 * A slab's triangles use vertices of its own and of the slab below (those on
 * its bottom plane's edges), so only the vertices made since the slab below
 * began stay in memory (the window); every vertex and triangle goes to its
 * scratch stream, in the PLY's own bytes, as it is made. */

#define RING 4

struct lsm_mesh {
  int nx, ny;           /* slice size */
  int w, h;             /* padded plane size: nx + 2, ny + 2 */
  size_t plane_n;       /* w * h */
  double sx, sy, dz_pad; /* dz_pad 0: the step to the neighbouring slice */
  float *plane[RING];   /* padded planes, slot p % RING */
  double pz[RING];      /* their heights */
  long top;             /* highest plane built, -1 before the first slice */
  int32_t *eplane[2][3]; /* in-plane edge vertices, by plane parity: x, y, xy */
  int32_t *eslab[4];    /* slab edge vertices: z, xz, yz, xyz */
  size_t slices;
  double last_z, prev_z; /* the last two heights added */
  long pad_top;          /* the plane of the top pad once closing, else -1 */
  int closed;
  int failed;
  /* the mesh */
  size_t nv, nt;        /* vertices and triangles made */
  float *win;           /* 6 floats per vertex from index win_base on */
  size_t win_base, win_n, win_cap;
  size_t slab_start;    /* nv when the slab below the current one began */
  FILE *vertices, *triangles; /* scratch streams, unlinked, PLY bytes */
  char scratch_dir[4096];
  int scratch_errno;    /* a failed scratch write: its errno */
};

/* ---- building planes ----------------------------------------------------------------------- */

/* A pad sample: the mirror of the boundary sample, strictly positive: at
 * least a millionth of a pixel. */
static inline float pad_value(const lsm_mesh *m, float v) {
  const float least = (float)(1e-6 * m->sx);
  float a = fabsf(v);
  if (!(a >= least)) a = least; /* also catches NaN */
  return a;
}

static void build_slice_plane(lsm_mesh *m, float *dst, const float *phi) {
  const int w = m->w, h = m->h, nx = m->nx, ny = m->ny;
  for (int j = 0; j < h; ++j) {
    int sj = j - 1 < 0 ? 0 : j - 1 >= ny ? ny - 1 : j - 1;
    const float *row = phi + (size_t)sj * (size_t)nx;
    float *out = dst + (size_t)j * (size_t)w;
    int border_row = j == 0 || j == h - 1;
    for (int i = 0; i < w; ++i) {
      int si = i - 1 < 0 ? 0 : i - 1 >= nx ? nx - 1 : i - 1;
      float v = row[si];
      out[i] = (border_row || i == 0 || i == w - 1) ? pad_value(m, v) : v;
    }
  }
}

static void build_pad_plane(lsm_mesh *m, float *dst, const float *src) {
  for (size_t k = 0; k < m->plane_n; ++k) dst[k] = pad_value(m, src[k]);
}

/* ---- growing the mesh ---------------------------------------------------------------------- */

static int grow(void **buf, size_t *cap, size_t need, size_t elem) {
  if (need <= *cap) return 1;
  size_t nc = *cap ? *cap : 4096;
  while (nc < need) {
    if (nc > SIZE_MAX / 2 / elem) return 0;
    nc *= 2;
  }
  void *p = realloc(*buf, nc * elem);
  if (!p) return 0;
  *buf = p;
  *cap = nc;
  return 1;
}

/* ---- the scratch streams ------------------------------------------------------------------- */

/* u little endian at b, as PLY's binary_little_endian stores it. */
static void put_u32(unsigned char *b, uint32_t u) {
  b[0] = (unsigned char)(u & 0xffu);
  b[1] = (unsigned char)((u >> 8) & 0xffu);
  b[2] = (unsigned char)((u >> 16) & 0xffu);
  b[3] = (unsigned char)((u >> 24) & 0xffu);
}

static int scratch_write(lsm_mesh *m, FILE *f, const unsigned char *b, size_t n) {
  if (fwrite(b, 1, n, f) == n) return 1;
  if (!m->scratch_errno) m->scratch_errno = errno ? errno : EIO;
  m->failed = 1;
  return 0;
}

/* An unlinked scratch file in dir: nothing is left behind, whatever ends the run. */
static FILE *scratch_open(const char *dir) {
  char path[4200];
  if (snprintf(path, sizeof path, "%s/.lsmorph-mesh-XXXXXX", dir) >= (int)sizeof path) {
    errno = ENAMETOOLONG;
    return NULL;
  }
  const int fd = mkstemp(path);
  if (fd < 0) return NULL;
  unlink(path);
  FILE *f = fdopen(fd, "w+b");
  if (!f) {
    const int e = errno;
    close(fd);
    errno = e;
    return NULL;
  }
  setvbuf(f, NULL, _IOFBF, (size_t)1 << 20);
  return f;
}

/* Forgets the vertices made before the slab below the one starting now. */
static void window_advance(lsm_mesh *m) {
  const size_t drop = m->slab_start - m->win_base;
  if (drop > 0 && m->win_n > drop) /* (no window yet: nothing to move) */
    memmove(m->win, m->win + drop * 6, (m->win_n - drop) * 6 * sizeof(float));
  m->win_n -= drop;
  m->win_base = m->slab_start;
  m->slab_start = m->nv;
}

/* ---- gradients and vertices ------------------------------------------------------------------ */

static inline const float *plane_at(const lsm_mesh *m, long p) { return m->plane[p % RING]; }

/* Gradient of phi at node (i, j) of padded plane p, physical units. */
static void node_gradient(const lsm_mesh *m, int i, int j, long p, double g[3]) {
  const float *P = plane_at(m, p);
  const size_t w = (size_t)m->w;
  const size_t k = (size_t)j * w + (size_t)i;
  int i0 = i > 0 ? i - 1 : i, i1 = i < m->w - 1 ? i + 1 : i;
  int j0 = j > 0 ? j - 1 : j, j1 = j < m->h - 1 ? j + 1 : j;
  g[0] = ((double)P[(size_t)j * w + (size_t)i1] - (double)P[(size_t)j * w + (size_t)i0]) /
         ((double)(i1 - i0) * m->sx);
  g[1] = ((double)P[(size_t)j1 * w + (size_t)i] - (double)P[(size_t)j0 * w + (size_t)i]) /
         ((double)(j1 - j0) * m->sy);
  long p0 = p > 0 ? p - 1 : p, p1 = p < m->top ? p + 1 : p;
  double dz = m->pz[p1 % RING] - m->pz[p0 % RING];
  g[2] = dz > 0 ? ((double)plane_at(m, p1)[k] - (double)plane_at(m, p0)[k]) / dz : 0.0;
}

/* Offsets of the 7 edge directions d (bits: 1 x, 2 y, 4 z). */
#define DX(d) ((d) & 1)
#define DY(d) (((d) >> 1) & 1)
#define DZ(d) (((d) >> 2) & 1)

/* A node of the pad layer around the volume. */
static inline int is_pad(const lsm_mesh *m, int i, int j, long p) {
  return i == 0 || j == 0 || i == m->w - 1 || j == m->h - 1 || p == 0 || p == m->pad_top;
}

/* The least fraction of an edge from a to b (one coordinate) that float32,
 * in which the PLY stores vertices, still tells from its ends: two units in
 * the last place at the larger end.  Large coordinates (heights far from 0
 * against the slice step, very wide slices) would otherwise round a vertex
 * kept 1/256 of the edge from a node onto the node. */
static double float_least(double a, double b) {
  const double len = fabs(b - a);
  if (!(len > 0.0)) return 0.0;
  const float big = (float)fmax(fabs(a), fabs(b));
  const double ulp = (double)nextafterf(big, INFINITY) - (double)big;
  return 2.0 * ulp / len;
}

/* Where a vertex sits along its edge, as a fraction from node a (phi va) to
 * node b (phi vb), one inside (phi <= 0), the other outside.  An edge into the
 * pad layer is cut half-way, so the caps of an object cut by the volume's
 * boundary are flat, at the faces of the boundary voxels, whatever the edge's
 * direction.  Elsewhere the zero of the linear interpolant, kept 1/256 of the
 * edge from its ends: a node where phi is exactly 0 (an outline's contour
 * pixels, a blend's tie) would otherwise put the vertices of all its edges on
 * one point, with triangles of no area; farther where float32 could not
 * tell the vertex from the node (float_least). */
static double edge_fraction(const lsm_mesh *m, int i, int j, long p, int i2, int j2, long p2,
                            double va, double vb, const double a[3], const double b[3]) {
  if (is_pad(m, i, j, p) != is_pad(m, i2, j2, p2)) return 0.5;
  double least = 1.0 / 256.0;
  for (int c = 0; c < 3; ++c) least = fmax(least, float_least(a[c], b[c]));
  if (least > 0.5) least = 0.5; /* an edge shorter than four float steps: its midpoint */
  double t = va / (va - vb);
  if (!(t >= least)) t = least; /* also catches NaN */
  if (t > 1.0 - least) t = 1.0 - least;
  return t;
}

/* The vertex on the edge from node (i, j, plane p) to (i, j, p) + d; creates it. */
static int32_t edge_vertex(lsm_mesh *m, int i, int j, long p, int d, int32_t *slot) {
  if (*slot >= 0) return *slot;
  const size_t w = (size_t)m->w;
  const int i2 = i + DX(d), j2 = j + DY(d);
  const long p2 = p + DZ(d);
  const double va = plane_at(m, p)[(size_t)j * w + (size_t)i];
  const double vb = plane_at(m, p2)[(size_t)j2 * w + (size_t)i2];
  const double za = m->pz[p % RING], zb = m->pz[p2 % RING];
  const double xa = (i - 1) * m->sx, ya = (j - 1) * m->sy;
  const double xb = (i2 - 1) * m->sx, yb = (j2 - 1) * m->sy;
  const double ends_a[3] = {xa, ya, za}, ends_b[3] = {xb, yb, zb};
  const double t = edge_fraction(m, i, j, p, i2, j2, p2, va, vb, ends_a, ends_b);
  double ga[3], gb[3], n[3] = {0.0, 0.0, 0.0};
  const int pad_a = is_pad(m, i, j, p), pad_b = is_pad(m, i2, j2, p2);
  if (pad_a != pad_b) {
    /* a vertex on a cap (an edge into the pad layer) lies on a face of the
     * volume's box (an edge or corner of it for a diagonal edge): its normal
     * is that face's, out of the box along each axis on which the pad end
     * lies in the pad layer (the gradient there is taken across the
     * mirrored pad values and could point inward) */
    const int pi = pad_a ? i : i2, pj = pad_a ? j : j2;
    const long pp = pad_a ? p : p2;
    n[0] = pi == 0 ? -1.0 : pi == m->w - 1 ? 1.0 : 0.0;
    n[1] = pj == 0 ? -1.0 : pj == m->h - 1 ? 1.0 : 0.0;
    n[2] = pp == 0 ? -1.0 : pp == m->pad_top ? 1.0 : 0.0;
  } else {
    node_gradient(m, i, j, p, ga);
    node_gradient(m, i2, j2, p2, gb);
    for (int c = 0; c < 3; ++c) n[c] = ga[c] + t * (gb[c] - ga[c]);
  }
  double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 1e-30) || !isfinite(len)) {
    /* flat: point from the inside end to the outside one */
    double s = va <= 0.0 ? 1.0 : -1.0;
    n[0] = s * (xb - xa);
    n[1] = s * (yb - ya);
    n[2] = s * (zb - za);
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
  if (m->nv >= (size_t)INT32_MAX ||
      !grow((void **)&m->win, &m->win_cap, (m->win_n + 1) * 6, sizeof(float))) {
    m->failed = 1;
    return -1;
  }
  float *o = m->win + m->win_n * 6;
  o[0] = (float)(xa + t * (xb - xa));
  o[1] = (float)(ya + t * (yb - ya));
  o[2] = (float)(za + t * (zb - za));
  o[3] = (float)(n[0] / len);
  o[4] = (float)(n[1] / len);
  o[5] = (float)(n[2] / len);
  unsigned char bytes[24];
  for (int c = 0; c < 6; ++c) {
    uint32_t u;
    memcpy(&u, &o[c], sizeof u);
    put_u32(bytes + 4 * c, u);
  }
  if (!scratch_write(m, m->vertices, bytes, sizeof bytes)) return -1;
  *slot = (int32_t)m->nv;
  m->win_n++;
  m->nv++;
  return *slot;
}

static void emit_triangle(lsm_mesh *m, int32_t a, int32_t b, int32_t c) {
  if (a < 0 || b < 0 || c < 0) {
    m->failed = 1;
    return;
  }
  /* PLY face: the count 3, then the three indices */
  unsigned char bytes[13];
  bytes[0] = 3;
  put_u32(bytes + 1, (uint32_t)a);
  put_u32(bytes + 5, (uint32_t)b);
  put_u32(bytes + 9, (uint32_t)c);
  if (scratch_write(m, m->triangles, bytes, sizeof bytes)) m->nt++;
}

/* ---- one slab ------------------------------------------------------------------------------ */

/* Kuhn split: tetrahedron (0, e_a, e_a + e_b, 7) for each permutation (a, b, c). */
static const int kuhn[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                               {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

typedef struct cube_ctx {
  lsm_mesh *m;
  int i, j;  /* cube origin node */
  long s;    /* slab (bottom plane) */
  int32_t cache[8][8]; /* vertex of the edge between corners a < b, -1 unknown */
} cube_ctx;

/* Vertex on the edge between cube corners a and b (one a subset of the other). */
static int32_t cube_vertex(cube_ctx *c, int a, int b) {
  if (a > b) {
    int t = a;
    a = b;
    b = t;
  }
  if (c->cache[a][b] >= 0) return c->cache[a][b];
  lsm_mesh *m = c->m;
  const int d = a ^ b;
  const int i = c->i + DX(a), j = c->j + DY(a);
  const long p = c->s + DZ(a);
  const size_t k = (size_t)j * (size_t)m->w + (size_t)i;
  int32_t *slot;
  if (d & 4) {
    static const int slab_dir[8] = {-1, -1, -1, -1, 0, 1, 2, 3};
    slot = &m->eslab[slab_dir[d]][k];
  } else {
    slot = &m->eplane[p & 1][d - 1][k];
  }
  return c->cache[a][b] = edge_vertex(m, i, j, p, d, slot);
}

static int det_sign(int a, int b, int c, int d) {
  int u[3] = {DX(b) - DX(a), DY(b) - DY(a), DZ(b) - DZ(a)};
  int v[3] = {DX(c) - DX(a), DY(c) - DY(a), DZ(c) - DZ(a)};
  int w[3] = {DX(d) - DX(a), DY(d) - DY(a), DZ(d) - DZ(a)};
  int det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
            u[2] * (v[0] * w[1] - v[1] * w[0]);
  return det > 0 ? 1 : -1;
}

static double dist2(const lsm_mesh *m, int32_t a, int32_t b) {
  const float *p = m->win + ((size_t)a - m->win_base) * 6, *q = m->win + ((size_t)b - m->win_base) * 6;
  double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
  return dx * dx + dy * dy + dz * dz;
}

static void mesh_tet(cube_ctx *c, const int q[4], const int in[4]) {
  int n_in = in[0] + in[1] + in[2] + in[3];
  if (n_in == 0 || n_in == 4) return;
  lsm_mesh *m = c->m;
  if (n_in == 1 || n_in == 3) {
    /* a: the lone vertex; b, c, d: the others in tetrahedron order */
    int lone = 0;
    for (int k = 0; k < 4; ++k)
      if (in[k] == (n_in == 1)) lone = k;
    int o[3], n = 0;
    for (int k = 0; k < 4; ++k)
      if (k != lone) o[n++] = q[k];
    int a = q[lone];
    int32_t e1 = cube_vertex(c, a, o[0]), e2 = cube_vertex(c, a, o[1]), e3 = cube_vertex(c, a, o[2]);
    /* (e1, e2, e3) faces away from a iff det(b-a, c-a, d-a) > 0 */
    int away = det_sign(a, o[0], o[1], o[2]) > 0;
    int outward = n_in == 1 ? away : !away;
    if (outward)
      emit_triangle(m, e1, e2, e3);
    else
      emit_triangle(m, e1, e3, e2);
    return;
  }
  /* two inside (a, b), two outside (c, d), each pair in tetrahedron order */
  int ins[2], outs[2], ni = 0, no = 0;
  for (int k = 0; k < 4; ++k) {
    if (in[k])
      ins[ni++] = q[k];
    else
      outs[no++] = q[k];
  }
  int a = ins[0], b = ins[1], cc = outs[0], d = outs[1];
  int32_t P[4] = {cube_vertex(c, a, cc), cube_vertex(c, a, d), cube_vertex(c, b, d),
                  cube_vertex(c, b, cc)};
  if (P[0] < 0 || P[1] < 0 || P[2] < 0 || P[3] < 0) {
    m->failed = 1;
    return;
  }
  /* the cycle (ac, ad, bd, bc) faces from {a, b} to {c, d} iff det(b-a, c-a, d-a) > 0 */
  if (det_sign(a, b, cc, d) < 0) {
    int32_t t = P[1];
    P[1] = P[3];
    P[3] = t;
  }
  if (dist2(m, P[0], P[2]) <= dist2(m, P[1], P[3])) {
    emit_triangle(m, P[0], P[1], P[2]);
    emit_triangle(m, P[0], P[2], P[3]);
  } else {
    emit_triangle(m, P[1], P[2], P[3]);
    emit_triangle(m, P[1], P[3], P[0]);
  }
}

static void mesh_slab(lsm_mesh *m, long s) {
  const size_t w = (size_t)m->w;
  window_advance(m);
  /* the top plane's in-plane edges are new; the bottom's carry over */
  for (int d = 0; d < 3; ++d)
    for (size_t k = 0; k < m->plane_n; ++k) m->eplane[(s + 1) & 1][d][k] = -1;
  for (int d = 0; d < 4; ++d)
    for (size_t k = 0; k < m->plane_n; ++k) m->eslab[d][k] = -1;
  const float *lo = plane_at(m, s), *hi = plane_at(m, s + 1);
  cube_ctx c;
  c.m = m;
  c.s = s;
  for (int j = 0; j + 1 < m->h && !m->failed; ++j) {
    for (int i = 0; i + 1 < m->w && !m->failed; ++i) {
      const size_t k = (size_t)j * w + (size_t)i;
      float v[8] = {lo[k], lo[k + 1], lo[k + w], lo[k + w + 1],
                    hi[k], hi[k + 1], hi[k + w], hi[k + w + 1]};
      int in[8], n_in = 0;
      for (int q = 0; q < 8; ++q) n_in += in[q] = v[q] <= 0.0f;
      if (n_in == 0 || n_in == 8) continue;
      c.i = i;
      c.j = j;
      memset(c.cache, 0xff, sizeof c.cache);
      for (int t = 0; t < 6; ++t) {
        const int *q = kuhn[t];
        int tin[4] = {in[q[0]], in[q[1]], in[q[2]], in[q[3]]};
        mesh_tet(&c, q, tin);
      }
    }
  }
}

/* ---- the public functions ---------------------------------------------------------------------- */

lsm_status lsm_mesh_open(int nx, int ny, double sx, double sy, double dz_pad,
                         const char *scratch_dir, lsm_mesh **out, lsm_err *err) {
  if (out) *out = NULL;
  if (!out || !scratch_dir) return lsm_fail(err, LSM_ERR_INTERNAL, "mesh", "bad arguments");
  if (nx <= 0 || ny <= 0 || nx > INT32_MAX - 2 || ny > INT32_MAX - 2)
    return lsm_fail(err, LSM_ERR_INPUT, "mesh", "slice size %dx%d is not usable", nx, ny);
  if (!(isfinite(sx) && sx > 0 && isfinite(sy) && sy > 0 && isfinite(dz_pad) && dz_pad >= 0))
    return lsm_fail(err, LSM_ERR_INPUT, "mesh",
                    "spacings %g %g must be finite and positive, the pad distance %g finite and "
                    "not negative",
                    sx, sy, dz_pad);
  size_t n;
  if (!lsm_size_mul((size_t)nx + 2, (size_t)ny + 2, &n) || n > (size_t)INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, "mesh", "slice size %dx%d is too large", nx, ny);
  lsm_mesh *m = calloc(1, sizeof *m);
  if (!m) return lsm_fail(err, LSM_ERR_NOMEM, "mesh", "cannot allocate the mesh builder");
  m->nx = nx;
  m->ny = ny;
  m->w = nx + 2;
  m->h = ny + 2;
  m->plane_n = n;
  m->sx = sx;
  m->sy = sy;
  m->dz_pad = dz_pad;
  m->top = -1;
  m->pad_top = -1;
  snprintf(m->scratch_dir, sizeof m->scratch_dir, "%s", scratch_dir);
  m->vertices = scratch_open(scratch_dir);
  if (m->vertices) m->triangles = scratch_open(scratch_dir);
  if (!m->triangles) {
    const int e = errno;
    lsm_mesh_free(&m);
    return lsm_fail(err, LSM_ERR_IO, scratch_dir, "cannot create the mesh's scratch file: %s",
                    strerror(e));
  }
  int ok = 1;
  for (int k = 0; k < RING; ++k) ok &= (m->plane[k] = malloc(n * sizeof(float))) != NULL;
  for (int p = 0; p < 2; ++p)
    for (int d = 0; d < 3; ++d) ok &= (m->eplane[p][d] = malloc(n * sizeof(int32_t))) != NULL;
  for (int d = 0; d < 4; ++d) ok &= (m->eslab[d] = malloc(n * sizeof(int32_t))) != NULL;
  if (!ok) {
    lsm_mesh_free(&m);
    return lsm_fail(err, LSM_ERR_NOMEM, "mesh", "cannot allocate %zu bytes of slab buffers",
                    n * 4 * (RING + 10));
  }
  for (int p = 0; p < 2; ++p)
    for (int d = 0; d < 3; ++d)
      for (size_t k = 0; k < n; ++k) m->eplane[p][d][k] = -1;
  *out = m;
  return LSM_OK;
}

static lsm_status mesh_status(lsm_mesh *m, lsm_err *err) {
  if (!m->failed) return LSM_OK;
  if (m->scratch_errno)
    return lsm_fail(err, LSM_ERR_IO, m->scratch_dir, "mesh scratch file: write failed: %s",
                    strerror(m->scratch_errno));
  if (m->nv >= (size_t)INT32_MAX)
    return lsm_fail(err, LSM_ERR_LIMIT, "mesh", "more than %d vertices", INT32_MAX);
  return lsm_fail(err, LSM_ERR_NOMEM, "mesh", "cannot grow the mesh (%zu vertices, %zu triangles)",
                  m->nv, m->nt);
}

lsm_status lsm_mesh_add_slice(lsm_mesh *m, const float *phi, double z, lsm_err *err) {
  if (!m || !phi) return lsm_fail(err, LSM_ERR_INTERNAL, "mesh", "bad arguments to add a slice");
  if (m->failed) return lsm_fail(err, LSM_ERR_INTERNAL, "mesh", "an earlier step failed");
  if (m->closed) return lsm_fail(err, LSM_ERR_INTERNAL, "mesh", "slice added after closing");
  if (!isfinite(z) || (m->slices > 0 && !(z > m->last_z)))
    return lsm_fail(err, LSM_ERR_INPUT, "mesh", "slice height %g does not increase", z);
  if (m->slices == 0) {
    build_slice_plane(m, m->plane[1], phi);
    m->pz[1] = z;
    build_pad_plane(m, m->plane[0], m->plane[1]);
    m->pz[0] = z - (m->dz_pad > 0 ? m->dz_pad : m->sx); /* 0: set with the second slice */
    m->top = 1;
  } else {
    long p = (long)m->slices + 1;
    build_slice_plane(m, m->plane[p % RING], phi);
    m->pz[p % RING] = z;
    m->top = p;
    if (m->slices == 1 && !(m->dz_pad > 0)) m->pz[0] = m->last_z - (z - m->last_z);
    mesh_slab(m, p - 2);
  }
  m->slices++;
  m->prev_z = m->last_z;
  m->last_z = z;
  return mesh_status(m, err);
}

lsm_status lsm_mesh_close(lsm_mesh *m, lsm_err *err) {
  if (!m) return lsm_fail(err, LSM_ERR_INTERNAL, "mesh", "bad arguments to close");
  if (m->failed) return lsm_fail(err, LSM_ERR_INTERNAL, "mesh", "an earlier step failed");
  if (m->closed) return LSM_OK;
  if (m->slices == 0) return lsm_fail(err, LSM_ERR_INPUT, "mesh", "no slices were added");
  long p = (long)m->slices + 1;
  build_pad_plane(m, m->plane[p % RING], m->plane[(p - 1) % RING]);
  const double step = m->dz_pad > 0 ? m->dz_pad : m->slices > 1 ? m->last_z - m->prev_z : m->sx;
  m->pz[p % RING] = m->last_z + step;
  m->top = p;
  m->pad_top = p;
  mesh_slab(m, p - 2);
  if (!m->failed) mesh_slab(m, p - 1);
  m->closed = 1;
  return mesh_status(m, err);
}

size_t lsm_mesh_vertex_count(const lsm_mesh *m) { return m ? m->nv : 0; }
size_t lsm_mesh_triangle_count(const lsm_mesh *m) { return m ? m->nt : 0; }

/* ---- PLY ------------------------------------------------------------------------------------- */

/* Appends the whole scratch stream src to out through buf. */
static int copy_scratch(FILE *src, FILE *out, unsigned char *buf, size_t size, int *read_errno) {
  if (fflush(src) != 0 || fseeko(src, 0, SEEK_SET) != 0) {
    *read_errno = errno;
    return 0;
  }
  for (;;) {
    const size_t n = fread(buf, 1, size, src);
    if (n && fwrite(buf, 1, n, out) != n) return 0;
    if (n < size) break;
  }
  if (ferror(src)) {
    *read_errno = errno ? errno : EIO;
    return 0;
  }
  return 1;
}

lsm_status lsm_mesh_write_ply(lsm_mesh *m, const char *path, lsm_err *err) {
  if (!m || !path) return lsm_fail(err, LSM_ERR_INTERNAL, path, "bad arguments to write a mesh");
  if (m->failed || !m->closed)
    return lsm_fail(err, LSM_ERR_INTERNAL, path, "the mesh is not closed, or failed");
  const size_t size = (size_t)1 << 20;
  unsigned char *buf = malloc(size);
  if (!buf) return lsm_fail(err, LSM_ERR_NOMEM, path, "cannot allocate a copy buffer");
  FILE *f = fopen(path, "wb");
  if (!f) {
    free(buf);
    return lsm_fail(err, LSM_ERR_IO, path, "cannot create: %s", strerror(errno));
  }
  int bad = fprintf(f,
                    "ply\n"
                    "format binary_little_endian 1.0\n"
                    "comment lsmorph: zero level set of the signed distance, physical units\n"
                    "comment x = column * pixel width, y = row * pixel height, z = height; "
                    "normals point outward\n"
                    "element vertex %zu\n"
                    "property float x\n"
                    "property float y\n"
                    "property float z\n"
                    "property float nx\n"
                    "property float ny\n"
                    "property float nz\n"
                    "element face %zu\n"
                    "property list uchar int vertex_indices\n"
                    "end_header\n",
                    m->nv, m->nt) < 0;
  int read_errno = 0;
  bad = bad || !copy_scratch(m->vertices, f, buf, size, &read_errno) ||
        !copy_scratch(m->triangles, f, buf, size, &read_errno);
  int e = errno;
  bad = bad || ferror(f);
  const int closed = fclose(f);
  if (!bad && closed != 0) e = errno;
  free(buf);
  if (read_errno)
    return lsm_fail(err, LSM_ERR_IO, m->scratch_dir, "mesh scratch file: read failed: %s",
                    strerror(read_errno));
  if (bad || closed != 0) return lsm_fail(err, LSM_ERR_IO, path, "write failed: %s", strerror(e));
  return LSM_OK;
}

void lsm_mesh_free(lsm_mesh **mp) {
  if (!mp || !*mp) return;
  lsm_mesh *m = *mp;
  for (int k = 0; k < RING; ++k) free(m->plane[k]);
  for (int p = 0; p < 2; ++p)
    for (int d = 0; d < 3; ++d) free(m->eplane[p][d]);
  for (int d = 0; d < 4; ++d) free(m->eslab[d]);
  free(m->win);
  if (m->vertices) fclose(m->vertices);
  if (m->triangles) fclose(m->triangles);
  free(m);
  *mp = NULL;
}
