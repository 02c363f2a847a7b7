/* mesh_load.h - a triangle mesh (engine/geometry/triangles/mesh.h) from a
 * file: .ply by tessera's streaming reader (mesh_ply.c over ply_read.h),
 * anything else by assimp (mesh_assimp.c: .obj with .mtl, .stl, .off,
 * .gltf, ...). */
#ifndef TESSERA_LOAD_MESH_LOAD_H
#define TESSERA_LOAD_MESH_LOAD_H

#include "engine/base/err.h"
#include "engine/geometry/triangles/mesh.h"

/* Load by file extension: .ply (tessera's streaming reader) or anything
 * assimp reads (.obj with .mtl, .stl, .off, .gltf, ...). The result is
 * validated. On failure returns NULL and err names the file and the problem.
 * The shape of mesh_file_reader (mesh_cache.h). */
mesh *mesh_load(const char *path, tess_error *err);
mesh *mesh_load_ply(const char *path, tess_error *err);
mesh *mesh_load_assimp(const char *path, tess_error *err);

#endif
