/* lsm_flood: breadth-first floods on label images (see the header). */
#include "solver/base/lsm_flood.h"

size_t lsm_flood(int32_t *label, int nx, int ny, int conn, int32_t from, int32_t *queue,
                 size_t tail) {
  for (size_t head = 0; head < tail;) {
    const int32_t q = queue[head++];
    const int i = q % nx, j = q / nx;
    if (conn == 4) { /* the edge neighbours: above, left, right, below */
      const int32_t nb[4] = {q - nx, q - 1, q + 1, q + nx};
      const int ok[4] = {j > 0, i > 0, i < nx - 1, j < ny - 1};
      for (int m = 0; m < 4; ++m) {
        if (!ok[m] || label[nb[m]] != from) continue;
        label[nb[m]] = label[q];
        queue[tail++] = nb[m];
      }
      continue;
    }
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const int a = i + di, b = j + dj;
        if ((di == 0 && dj == 0) || a < 0 || b < 0 || a >= nx || b >= ny) continue;
        const int32_t t = b * nx + a;
        if (label[t] != from) continue;
        label[t] = label[q];
        queue[tail++] = t;
      }
  }
  return tail;
}

int32_t lsm_flood_components(int32_t *label, int nx, int ny, int conn, int32_t from, int32_t first,
                             int32_t *queue) {
  const size_t n = (size_t)nx * (size_t)ny;
  int32_t next = first;
  for (size_t k = 0; k < n; ++k) {
    if (label[k] != from) continue;
    label[k] = next++;
    queue[0] = (int32_t)k;
    lsm_flood(label, nx, ny, conn, from, queue, 1);
  }
  return next - first;
}
