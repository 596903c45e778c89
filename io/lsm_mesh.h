/* lsm_mesh: a closed triangle mesh of the zero level set, built slab by slab
 * while the slices stream past, written as binary little-endian PLY.
 *
 * Method: marching tetrahedra on the Kuhn (Freudenthal) split of every cube of
 * the sample grid into 6 tetrahedra around its main diagonal.  The split is the
 * same in every cube, so neighbouring cubes cut their shared faces along the
 * same diagonal and the mesh is topologically consistent by construction: no
 * ambiguous cases, every edge shared by exactly two triangles.  A vertex lives
 * on a grid edge (axis, face diagonal or body diagonal) and is created once
 * (vertices are indexed, keyed by edge), so the mesh is a closed 2-manifold.
 *
 * Inside is phi <= 0 (as in the masks).  Triangles are wound so that their
 * normals point outward, to phi > 0 (the winding follows from the
 * orientation of each tetrahedron, exactly, in grid-index space); each vertex
 * also gets the normalised gradient of phi (central differences, interpolated
 * along its edge) as its normal.
 *
 * The volume is padded with one outside layer on every side (the x and y
 * borders, one slice below the first and one above the last, pad spacing
 * dz_pad): a pad sample mirrors the nearest boundary sample, |phi| (at least a
 * tiny positive value), and every edge between the pad and the volume is cut
 * half-way, so an object cut by the volume's boundary is capped flat, half-way
 * between the last samples and the pad: closed, at the faces of the volume's
 * voxels.  Elsewhere a vertex stays at least 1/256 of its edge from the edge's
 * ends, so a node where phi is exactly 0 gives no triangles of zero area.
 *
 * Coordinates are physical: x = column * sx, y = row * sy, z = the slice's
 * height.  Memory: four padded slices, ten edge-index planes and the
 * vertices of the last two slabs, whatever the slice count: every vertex and
 * triangle is written, as made, to one of two scratch files (unlinked, so
 * none is left behind) in the folder given, until the PLY is written; the
 * scratch holds about the PLY's size on disk until the mesh is freed.
 */
#ifndef LSM_MESH_H
#define LSM_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "solver/base/lsm_status.h"

typedef struct lsm_mesh lsm_mesh;

/* Starts a mesh of nx x ny slices with pixel spacings sx, sy; dz_pad is the
 * distance of the pad layers below the first and above the last slice, or 0
 * for the step to the neighbouring slice at each end (uneven heights).  The
 * scratch files go to scratch_dir (the output folder, beside the PLY). */
lsm_status lsm_mesh_open(int nx, int ny, double sx, double sy, double dz_pad,
                         const char *scratch_dir, lsm_mesh **out, lsm_err *err);
/* Adds the next slice (nx*ny floats, row-major, row 0 first) at height z;
 * heights must increase.  Meshes the slab below it as soon as it can. */
lsm_status lsm_mesh_add_slice(lsm_mesh *m, const float *phi, double z, lsm_err *err);
/* Closes the top (pad layer) and meshes the remaining slabs.  At least one
 * slice must have been added. */
lsm_status lsm_mesh_close(lsm_mesh *m, lsm_err *err);
/* Writes the closed mesh as binary little-endian PLY: vertex x y z nx ny nz
 * (float), face vertex_indices (uchar count, int indices): the header with
 * the counts, then the two scratch files' bytes. */
lsm_status lsm_mesh_write_ply(lsm_mesh *m, const char *path, lsm_err *err);

size_t lsm_mesh_vertex_count(const lsm_mesh *m);
size_t lsm_mesh_triangle_count(const lsm_mesh *m);

void lsm_mesh_free(lsm_mesh **m);

#endif
