/* scene_load.h - a scene from files: a JSON scene file (scene_json.c), a
 * mesh file, an assembly (scene_assembly.c) or a particle file, into the
 * scene container (engine/scene/scene.h). Errors name the file. */
#ifndef TESSERA_LOAD_SCENE_LOAD_H
#define TESSERA_LOAD_SCENE_LOAD_H

#include <stdbool.h>
#include <stddef.h>

#include "engine/base/err.h"
#include "engine/scene/scene.h"

/* Load a JSON scene file (docs/scenes.md "Scene files"), or a mesh file directly
 * (any extension mesh_load() reads): then a grey Lambert material, the default
 * directional light, and no camera (so the caller frames the bounds). */
scene *scene_load(const char *path, tess_error *err);
scene *scene_load_json(const char *path, tess_error *err);
/* The same from `len` bytes of JSON text (need not be NUL-terminated): `path`
 * names the text in messages, and relative mesh paths resolve from its
 * directory. */
scene *scene_parse_json(const char *path, const char *text, size_t len, tess_error *err);

/* What a caller decides of a scene beyond its file (all false: scene_load). */
typedef struct scene_load_options {
    /* meshes get trees with spatial splits: a mesh file, and every JSON
     * "meshes" entry that does not say "spatial_splits" itself (assembly
     * parts never) */
    bool spatial_splits;
} scene_load_options;
scene *scene_load_with(const char *path, const scene_load_options *opts, tess_error *err);
scene *scene_load_json_with(const char *path, const scene_load_options *opts, tess_error *err);
scene *scene_parse_json_with(const char *path, const char *text, size_t len, const scene_load_options *opts,
                             tess_error *err);

/* Load an assembly (assembly_load.h: glTF 2.0 .gltf/.glb, OBJ groups, ...)
 * into s: its materials, meshes (stored once) and parts (under the root of
 * s->parts, made on first use) with their instances, each placed by
 * `placement` (NULL: as in the file) after its own transform. An error names
 * the file. */
bool scene_load_assembly(scene *s, const char *path, const affine3 *placement, tess_error *err);

#endif
