/* mesh_tree.h - a triangle mesh's wide BVH (wbvh.h, WBVH_MESH), built once
 * and kept with its scene_mesh: the triangle kind's `tree` operation.
 *
 * Building puts the mesh in the tree's order (mesh_permute_triangles: leaf
 * [first, first + count) is triangles first..; the triangles no ray can hit
 * follow the last leaf) and numbers its vertices in that order
 * (mesh_renumber_vertices), so a leaf's indices are contiguous and its
 * vertices nearly so. The kernels read the mesh in place: nothing of the
 * triangles is copied. A triangle's id (hit.prim_id) is its place in this
 * order, from the first build on. */
#ifndef TESSERA_MESH_TREE_H
#define TESSERA_MESH_TREE_H

#include "engine/base/err.h"
#include "triangle_kind.h"
#include "engine/accel/wbvh.h"

/* The mesh's tree, built over `threads` threads on the first call (which
 * reorders sm->mesh); any thread, any number at once. NULL with err set on
 * failure (the mesh is unchanged then, or fully reordered). */
const wbvh *mesh_tree_get(scene_mesh *sm, int threads, tess_error *err);
/* Free the tree (the scene, destroying sm). */
void mesh_tree_release(scene_mesh *sm);

#endif
