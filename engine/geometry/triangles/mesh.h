/* mesh.h - an indexed triangle mesh as loaded from a file or generated in code.
 *
 * Optional per-vertex attributes (normals, colours) and per-triangle materials
 * are NULL unless the source has them, so a mesh pays only for what it uses.
 * Ownership: the mesh owns every array; mesh_destroy frees them. */
#ifndef TESSERA_MESH_H
#define TESSERA_MESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"

#define MESH_NAME_BYTES 64

/* A material named by the mesh file itself (OBJ's MTL): only what we render. */
typedef struct mesh_material {
    char name[MESH_NAME_BYTES];
    float diffuse_rgb[3]; /* linear RGB reflectance in [0, 1] (MTL "Kd") */
} mesh_material;

typedef struct mesh {
    uint32_t vertex_count;
    uint32_t triangle_count;
    float *positions;           /* 3 * vertex_count floats, xyz interleaved, object space */
    float *normals;             /* 3 * vertex_count floats, or NULL (geometric normals are used) */
    float *colors;              /* 3 * vertex_count linear RGB floats in [0, 1], or NULL */
    uint32_t *indices;          /* 3 * triangle_count vertex indices, each < vertex_count */
    uint32_t *triangle_material; /* triangle_count indices into materials, or NULL */
    mesh_material *materials;   /* material_count entries, or NULL */
    uint32_t material_count;
    /* SPATIAL SPLITS (mesh_tree.c): a tree with spatial splits holds a
     * triangle in several leaves, and the arrays above then hold it once per
     * leaf (a reference). canon[t] is the position of stored triangle t's
     * first copy (canon[canon[t]] == canon[t]): the one id every copy is hit
     * as. NULL when no triangle is stored twice (no cost for plain meshes).
     * duplicate_count: stored triangles t with canon[t] != t. */
    uint32_t *canon;
    uint32_t duplicate_count;
    /* capacities in elements (vertices / triangles), for the append helpers */
    uint32_t vertex_capacity;
    uint32_t triangle_capacity;
    /* NULL: the mesh allocated its arrays (and may grow and change them).
     * Else the arrays are read-only views into `owner` (a mapped cache file,
     * mesh_cache.h), which mesh_destroy gives to release instead of freeing
     * them; such a mesh must never be changed */
    void *owner;
    void (*release)(void *owner);
} mesh;

mesh *mesh_create(void);
void mesh_destroy(mesh *m); /* NULL is fine */

/* Grow storage to hold at least n vertices / triangles (attributes that are
 * non-NULL grow too). Return false on allocation failure. */
bool mesh_reserve_vertices(mesh *m, uint32_t n);
bool mesh_reserve_triangles(mesh *m, uint32_t n);
/* Allocate the optional arrays for the current vertex_capacity / triangle_capacity. */
bool mesh_enable_normals(mesh *m);
bool mesh_enable_colors(mesh *m);
bool mesh_enable_triangle_materials(mesh *m);

/* Append one vertex / triangle, growing geometrically. */
bool mesh_add_vertex(mesh *m, float x, float y, float z);
bool mesh_add_triangle(mesh *m, uint32_t a, uint32_t b, uint32_t c);

/* Check what every consumer relies on: finite coordinates (and normals, colours),
 * indices in range. `source` names the file for the message. */
bool mesh_validate(const mesh *m, const char *source, tess_error *err);

/* Axis-aligned bounds of all vertices; false when the mesh has none. */
bool mesh_bounds(const mesh *m, float lo[3], float hi[3]);

/* Apply a row-major 3x4 affine transform [R|t] to positions (and normals, by
 * the inverse transpose, renormalised). */
void mesh_transform(mesh *m, const float xform[12]);

/* Put the triangles in a new order: triangle i becomes the old triangle
 * order[i] (with its material); order is a permutation of
 * 0..triangle_count-1. Gathered over `threads` threads into new arrays, one
 * old array freed as its new one is filled (mesh.c, REORDERING). False: out
 * of memory, nothing moved. */
bool mesh_permute_triangles(mesh *m, const uint32_t *order, int threads);
/* Put the triangles in the order of a tree with spatial splits: stored
 * triangle i becomes the old triangle from[i] (with its material), for i <
 * count; from may repeat a triangle, and every triangle that is not in from
 * is dropped. Sets canon (NULL when nothing repeats) and duplicate_count.
 * The mesh must have no canon yet. False: out of memory (or a canon
 * already), nothing moved. */
bool mesh_gather_triangles(mesh *m, const uint32_t *from, uint32_t count, int threads);
/* Triangles as loaded: triangle_count less the repeated copies. */
static inline uint32_t mesh_unique_triangles(const mesh *m) { return m->triangle_count - m->duplicate_count; }
/* Number the vertices in the order the triangles first use them (unused
 * ones last, in their order), so the vertices of neighbouring triangles are
 * neighbours in memory; the triangles keep their corners. False: out of
 * memory, nothing moved. */
bool mesh_renumber_vertices(mesh *m, int threads);

/* Bytes held by the mesh's arrays (by count, not capacity). */
size_t mesh_bytes(const mesh *m);

/* Reading a mesh from a file is engine/load/mesh_load.h. */

#endif
