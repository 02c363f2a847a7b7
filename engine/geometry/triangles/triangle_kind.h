/* triangle_kind.h - triangle meshes as a geometry kind (geometry.h): a
 * scene_mesh is the kind's data, a mesh (mesh.h) with how it is shaded and
 * its tree (mesh_tree.h); the scene (scene.h) owns every scene_mesh. */
#ifndef TESSERA_GEOMETRY_TRIANGLE_KIND_H
#define TESSERA_GEOMETRY_TRIANGLE_KIND_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/accel/geometry.h"
#include "mesh.h"

struct wbvh;

/* One mesh in the scene and how its triangles are shaded. */
typedef struct scene_mesh {
    mesh *mesh;            /* owned, world space */
    uint32_t material_id;  /* index into the scene's materials (scene.h), used when the mesh has no own materials */
    uint32_t *mesh_material_ids; /* mesh->material_count scene material ids for a mesh with its own
                                    materials (OBJ+MTL), else NULL; owned */
    char name[GEOMETRY_NAME_BYTES];
    /* build its tree with spatial splits (bvh_spatial.h; set before the
     * first accel build, part of the cache key): the mesh then stores a
     * triangle once per leaf that holds it (mesh.h canon) */
    bool spatial_splits;
    /* its wide BVH (mesh_tree.h), NULL until the first accel is built;
     * building it put the mesh in the tree's order. Owned */
    _Atomic(struct wbvh *) tree;
    /* the structure cache (mesh_cache.h): a mesh_cache_state, and the key
     * the cache is written under after the tree's build (state PENDING) */
    int cache_state;
    uint64_t cache_key[2];
} scene_mesh;

/* The kind: data is a scene_mesh. */
extern const geometry_ops geometry_triangles_ops;

#endif
