/* assimp_import.h - internal to the engine's two assimp loaders: the
 * flattening one (mesh_assimp.c, mesh_load_assimp) and the part-tree one
 * (assembly_load.c). What they share so it exists once: the checks that plug
 * assimp 5.2's holes (assimp_import.c says which), the import under the one
 * lock around assimp's process-wide error string, and copying a triangle
 * aiMesh into a tessera mesh. Not for other callers: use mesh_load or
 * assembly_load. */
#ifndef TESSERA_ASSIMP_IMPORT_H
#define TESSERA_ASSIMP_IMPORT_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/err.h"

struct aiScene;
struct aiMesh;
struct mesh;

/* Import `path` with aiProcess_Triangulate | SortByPType | ValidateDataStructure
 * | extra_flags, after checking an .obj's numbers, indices and material
 * libraries ourselves; then check every triangle mesh's positions and normals
 * are finite and join identical vertices. The scene (free with
 * assimp_release), or NULL with err naming the file and the problem.
 * Thread-safe. Runs on a thread with a deep stack (assimp recurses over the
 * node tree: assimp_import.c). */
const struct aiScene *assimp_import_file(const char *path, unsigned extra_flags, tess_error *err);
/* aiReleaseImport on a deep stack (aiNode's destructor recurses); NULL is fine. */
void assimp_release(const struct aiScene *scene);

/* Only triangles (after SortByPType), at least one, with vertices: the meshes
 * the loaders keep (points and lines are dropped). */
bool assimp_is_triangle_mesh(const struct aiMesh *am);

/* Append am's vertices at m->vertex_count (without counting them: the caller
 * adds am->mNumVertices): positions, and normals / colours (first set, clamped
 * to [0, 1]) when m has those arrays. m must have room. */
void assimp_append_vertices(struct mesh *m, const struct aiMesh *am);
/* Append am's triangles at m->triangle_count, indices offset by first_vertex,
 * each with `material` when m has per-triangle materials. m must have room.
 * False (err names path and the mesh) for a face that is not a triangle. */
bool assimp_append_triangles(struct mesh *m, const struct aiMesh *am, uint32_t first_vertex, uint32_t material,
                             const char *path, tess_error *err);

/* A glTF file (named .gltf or .glb, or glTF by content) is one assimp's glTF
 * 2.0 reader accepts and holds only well-formed base64 data URIs; false with
 * err naming the file, the byte offset where it can, and the problem
 * otherwise (gltf_check.c says why each check exists). Other files pass.
 * Run by assimp_import_file on every file but .obj. */
bool assimp_check_gltf(const char *path, tess_error *err);

#endif
