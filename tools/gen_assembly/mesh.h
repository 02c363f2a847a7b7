/* mesh.h - a growing triangle mesh: float positions and unit normals per
 * vertex, 32-bit indices, counter-clockwise triangles seen from outside.
 *
 * The shape builders (shapes.h) fill one, the glb writer copies it into the
 * binary chunk, and it is freed before the next mesh is built, so only one
 * unique mesh is ever held. Allocation failure is sticky (`failed`): adding
 * after a failure does nothing, and the caller checks once at the end. */
#ifndef TESSERA_GEN_ASSEMBLY_MESH_H
#define TESSERA_GEN_ASSEMBLY_MESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "vec.h"

struct ga_mesh {
    float *positions;    /* 3 floats a vertex, vertex_count of them (owned) */
    float *normals;      /* 3 floats a vertex, unit length (owned) */
    uint32_t *indices;   /* 3 a triangle, index_count of them (owned) */
    size_t vertex_count; /* vertices stored */
    size_t vertex_cap;   /* vertices allocated */
    size_t index_count;  /* indices stored */
    size_t index_cap;    /* indices allocated */
    bool failed;         /* an allocation failed or the 32-bit index range ran out */
};

void ga_mesh_init(struct ga_mesh *mesh);
void ga_mesh_finish(struct ga_mesh *mesh);

/* Store a vertex (position and normal rounded to float); its index. The same
 * double position always rounds to the same float, so builders that reuse a
 * computed point get bit-identical positions on every face that shares it. */
uint32_t ga_mesh_vertex(struct ga_mesh *mesh, struct ga_v3 position, struct ga_v3 normal);

void ga_mesh_triangle(struct ga_mesh *mesh, uint32_t a, uint32_t b, uint32_t c);

/* Add the triangle so that it faces `want` (a planar face's outward normal):
 * a, b, c or a, c, b, decided by the stored positions. */
void ga_mesh_triangle_facing(struct ga_mesh *mesh, uint32_t a, uint32_t b, uint32_t c, struct ga_v3 want);

static inline size_t ga_mesh_triangle_count(const struct ga_mesh *mesh) { return mesh->index_count / 3; }

#endif
