/* mesh_cache.h - a mesh file and its tree through the structure cache
 * (cache_file.h): after the first build, the mesh as the tree ordered it
 * and the tree's nodes are written to a file named by a content hash of the
 * model file and of what was done to it; the next start maps that file and
 * uses its arrays in place: no parsing, no build, no copy.
 *
 * Only files of at least mesh_cache_min_bytes() are cached (small models
 * load faster than they hash). TESSERA_CACHE=off turns caching off;
 * TESSERA_CACHE_DIR says where (cache_file.h). A cache that fails any check
 * (stale, corrupt, another version, truncated) is reported in one line and
 * rebuilt over, never used. */
#ifndef TESSERA_MESH_CACHE_H
#define TESSERA_MESH_CACHE_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/cache_file.h"
#include "engine/base/err.h"
#include "mesh.h"
#include "triangle_kind.h"

/* What decides a cached mesh besides its file's bytes. */
typedef struct mesh_cache_params {
    float xform[12];         /* row-major [R|t] applied after loading (the identity when none) */
    uint32_t drop_materials; /* 1: the file's own materials are dropped (a scene names one) */
    uint32_t spatial_splits; /* 1: the tree is built with spatial splits (scene_mesh.spatial_splits) */
} mesh_cache_params;

typedef enum mesh_cache_state {
    MESH_CACHE_UNUSED,  /* not cached: off, a small file, or no cache directory */
    MESH_CACHE_HIT,     /* mesh and tree mapped from the cache */
    MESH_CACHE_PENDING, /* loaded from the file; the cache is written after the tree's build */
    MESH_CACHE_WRITTEN, /* ... and it was */
    MESH_CACHE_FAILED,  /* ... and writing failed (reported; the program goes on) */
} mesh_cache_state;

/* One load through the cache, until the scene_mesh takes it (mesh_cache_adopt). */
typedef struct mesh_cache_load {
    mesh_cache_state state;
    cache_key key;
    struct wbvh *tree; /* HIT: the mapped tree, for the scene_mesh (owned until adopted) */
} mesh_cache_load;

/* Files smaller than this many bytes are loaded without the cache
 * (TESSERA_CACHE_MIN_BYTES overrides the default of 16 MiB). */
uint64_t mesh_cache_min_bytes(void);

/* How a mesh file is read when the cache does not have it (the cache does
 * not know file formats: engine/load/mesh_load.h's mesh_load is one). */
typedef mesh *mesh_file_reader(const char *path, tess_error *err);

/* The mesh of the file at path. HIT: mapped from the cache with params
 * applied already, its tree in out->tree. Else read by `read`, params NOT
 * applied (the caller applies them, then mesh_cache_adopt). NULL with err
 * set when the file cannot be loaded. */
mesh *mesh_cache_load_file(const char *path, const mesh_cache_params *params, mesh_file_reader *read,
                           mesh_cache_load *out, tess_error *err);
/* Give the scene_mesh holding the loaded mesh what the load found: a HIT's
 * tree, or the key under which mesh_tree writes the cache after building. */
void mesh_cache_adopt(scene_mesh *sm, mesh_cache_load *load);
/* Drop a load that no scene_mesh took (its mesh destroyed by the caller). */
void mesh_cache_abandon(mesh_cache_load *load);
/* After sm's tree was built (mesh_tree): write the cache when one is
 * pending. Best-effort: a failure is logged and remembered in sm. */
void mesh_cache_store(scene_mesh *sm, const struct wbvh *tree);

#endif
