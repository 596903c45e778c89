/* lsm_moving: a gap in the moving frame of its field (see the header). */
#include "solver/recon/lsm_moving.h"

#include <string.h>

#include "kernels/lsm_motion_cell.h"

void lsm_moving_free(lsm_moving *mv) {
  lsm_grid_destroy(&mv->raw_a);
  lsm_grid_destroy(&mv->raw_b);
  lsm_grid_destroy(&mv->mid_a);
  lsm_grid_destroy(&mv->mid_b);
  lsm_motion_map_free(&mv->half_back);
  lsm_motion_map_free(&mv->half_fwd);
  lsm_motion_map_free(&mv->m1);
  lsm_motion_map_free(&mv->m2);
  lsm_motion_map_free(&mv->m3);
  lsm_motion_map_free(&mv->scratch);
  lsm_motion_map_free(&mv->bend[0]);
  lsm_motion_map_free(&mv->bend[1]);
  memset(mv, 0, sizeof *mv);
}

lsm_status lsm_moving_setup(lsm_moving *mv, const lsm_motion_field *w, lsm_grid *phi_a,
                            lsm_grid *phi_b, int threads, lsm_err *err) {
  memset(mv, 0, sizeof *mv);
  mv->w = w;
  mv->threads = threads;
  lsm_status st = lsm_grid_clone(phi_a, &mv->raw_a, err);
  if (st == LSM_OK) st = lsm_grid_clone(phi_b, &mv->raw_b, err);
  lsm_motion_map *maps[] = {&mv->half_back, &mv->half_fwd, &mv->m1, &mv->m2, &mv->m3,
                            &mv->scratch};
  for (size_t k = 0; st == LSM_OK && k < sizeof maps / sizeof *maps; ++k)
    st = lsm_motion_map_create(w, maps[k], err);
  if (st == LSM_OK) {
    lsm_motion_exp(w, -0.5, &mv->half_back, &mv->scratch, threads);
    lsm_motion_exp(w, 0.5, &mv->half_fwd, &mv->scratch, threads);
    lsm_motion_pull(mv->raw_a, &mv->half_back, phi_a, threads);
    lsm_motion_pull(mv->raw_b, &mv->half_fwd, phi_b, threads);
    st = lsm_grid_clone(phi_a, &mv->mid_a, err);
  }
  if (st == LSM_OK) st = lsm_grid_clone(phi_b, &mv->mid_b, err);
  if (st != LSM_OK) lsm_moving_free(mv);
  return st;
}

lsm_status lsm_moving_pull_neighbour(lsm_moving *mv, const lsm_motion_field *w_beyond, int side,
                                     lsm_grid *phi, lsm_err *err) {
  lsm_grid *copy = NULL;
  LSM_TRY(lsm_grid_clone(phi, &copy, err));
  /* m2 = the beyond pair's full map (backward before A, forward after B), m3 = it after
   * the half map of this gap */
  lsm_motion_exp(w_beyond, side ? 1.0 : -1.0, &mv->m2, &mv->scratch, mv->threads);
  lsm_motion_compose(side ? &mv->half_fwd : &mv->half_back, &mv->m2, &mv->m3, mv->threads);
  lsm_motion_pull(copy, &mv->m3, phi, mv->threads);
  lsm_grid_destroy(&copy);
  return LSM_OK;
}

lsm_status lsm_moving_tangent(lsm_moving *mv, const lsm_motion_field *w_beyond, int side,
                              double H, double H_beyond, lsm_err *err) {
  const lsm_motion_field *w = mv->w;
  lsm_motion_map *bend = &mv->bend[side];
  if (!bend->dx) LSM_TRY(lsm_motion_map_create(w, bend, err));
  const lsm_motion_map *half = side ? &mv->half_fwd : &mv->half_back;
  /* per unit height: this pair's velocity v = w / H, the other's v_b = w_b / H_b; the
   * three-point slope weighs each by the other interval */
  const float c_this = (float)(H_beyond / (H + H_beyond)) ;
  const float c_beyond = (float)(H * H / (H_beyond * (H + H_beyond)));
  const float st = (float)w->step;
  for (int j = 0; j < w->ny; ++j)
    for (int i = 0; i < w->nx; ++i) {
      const size_t k = (size_t)j * w->nx + i;
      const float px = st * ((float)i + half->dx[k]), py = st * ((float)j + half->dy[k]);
      float vx, vy, bx, by;
      lsm_motion_velocity_at(w, px, py, &vx, &vy);
      lsm_motion_velocity_at(w_beyond, px, py, &bx, &by);
      /* T = H m = c_this v H + c_beyond ... in cells per gap: T = c_this V + c_beyond V_b,
       * V = w (per gap), V_b = w_b (per its gap); bend = T - V */
      bend->dx[k] = ((c_this - 1.0f) * vx + c_beyond * bx) / st;
      bend->dy[k] = ((c_this - 1.0f) * vy + c_beyond * by) / st;
    }
  mv->bent[side] = 1;
  return LSM_OK;
}

/* m1, m2, m3: the maps from the frame at s to A, to B and to the mid frame.  The path from
 * the mid frame is x = exp((s - 1/2) w)(y) + C_s(y), C_s = h10 bend_A + h11 bend_B; its
 * inverse by the fixed point y = exp((1/2 - s) w)(x - C_s(y)). */
static void carry_maps(lsm_moving *mv, double s) {
  const lsm_motion_field *w = mv->w;
  if (!mv->bent[0] && !mv->bent[1]) {
    lsm_motion_exp(w, -s, &mv->m1, &mv->scratch, mv->threads);
    lsm_motion_exp(w, 1.0 - s, &mv->m2, &mv->scratch, mv->threads);
    lsm_motion_exp(w, 0.5 - s, &mv->m3, &mv->scratch, mv->threads);
    return;
  }
  const double s2 = s * s, s3 = s2 * s;
  const float h10 = (float)(s3 - 2 * s2 + s), h11 = (float)(s3 - s2);
  lsm_motion_map *back = &mv->m2, *y = &mv->m3;
  lsm_motion_exp(w, 0.5 - s, back, &mv->scratch, mv->threads);
  const int nx = w->nx, ny = w->ny;
  const size_t n = (size_t)nx * (size_t)ny;
  memcpy(y->dx, back->dx, 2 * n * sizeof(float)); /* dx and dy are one block */
  for (int it = 0; it < 4; ++it) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const size_t k = (size_t)j * nx + i;
        const float qx = (float)i + y->dx[k], qy = (float)j + y->dy[k];
        float cx = 0.0f, cy = 0.0f;
        for (int side = 0; side < 2; ++side) {
          if (!mv->bent[side]) continue;
          const float hs = side ? h11 : h10;
          cx += hs * lsm_bilinear(mv->bend[side].dx, nx, ny, qx, qy);
          cy += hs * lsm_bilinear(mv->bend[side].dy, nx, ny, qx, qy);
        }
        /* y = back(x - C): x - C in nodes, then back's displacement there */
        const float rx = (float)i - cx, ry = (float)j - cy;
        mv->scratch.dx[k] = rx + lsm_bilinear(back->dx, nx, ny, rx, ry) - (float)i;
        mv->scratch.dy[k] = ry + lsm_bilinear(back->dy, nx, ny, rx, ry) - (float)j;
      }
    memcpy(y->dx, mv->scratch.dx, 2 * n * sizeof(float));
  }
  lsm_motion_compose(y, &mv->half_back, &mv->m1, mv->threads);
  lsm_motion_compose(y, &mv->half_fwd, &mv->m2, mv->threads);
}

void lsm_moving_carry(lsm_moving *mv, double s, lsm_grid *mid, lsm_grid *out) {
  const lsm_motion_field *w = mv->w;
  const float sf = (float)s;
  /* the departure of the mid frame's result from its own blend */
  for (int j = 0; j < mid->ny; ++j)
    for (int i = 0; i < mid->nx; ++i)
      LSM_AT(mid, i, j) -= (1.0f - sf) * LSM_AT(mv->mid_a, i, j) + sf * LSM_AT(mv->mid_b, i, j);
  carry_maps(mv, s);
  const lsm_motion_map *m1 = &mv->m1, *m2 = &mv->m2, *m3 = &mv->m3;
  const float inv = 1.0f / (float)w->step, st = (float)w->step;
  const lsm_grid *ra = mv->raw_a, *rb = mv->raw_b;
#pragma omp parallel for num_threads(lsm_grid_threads(out, mv->threads)) schedule(static)
  for (int j = 0; j < out->ny; ++j)
    for (int i = 0; i < out->nx; ++i) {
      const float x = (float)i * inv, y = (float)j * inv, fi = (float)i, fj = (float)j;
      const float a = lsm_bilinear_strided(
          ra->data, ra->stride, ra->nx, ra->ny, fi + st * lsm_bilinear(m1->dx, m1->nx, m1->ny, x, y),
          fj + st * lsm_bilinear(m1->dy, m1->nx, m1->ny, x, y));
      const float b = lsm_bilinear_strided(
          rb->data, rb->stride, rb->nx, rb->ny, fi + st * lsm_bilinear(m2->dx, m2->nx, m2->ny, x, y),
          fj + st * lsm_bilinear(m2->dy, m2->nx, m2->ny, x, y));
      const float d = lsm_bilinear_strided(
          mid->data, mid->stride, mid->nx, mid->ny,
          fi + st * lsm_bilinear(m3->dx, m3->nx, m3->ny, x, y),
          fj + st * lsm_bilinear(m3->dy, m3->nx, m3->ny, x, y));
      LSM_AT(out, i, j) = (1.0f - sf) * a + sf * b + d;
    }
  lsm_grid_fill_ghosts(out);
}
