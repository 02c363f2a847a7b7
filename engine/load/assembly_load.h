/* assembly_load.h - load an assembly (glTF 2.0 node tree, OBJ groups, any
 * format assimp reads) as a PART TREE with instanced meshes, independent of
 * the scene: what is found is reported to a sink (callbacks), which builds
 * whatever it wants from it (the scene, or tessera parts' counting sink).
 * mesh_load_assimp (mesh.h) stays the loader that flattens a file into one
 * mesh.
 *
 * Order of the calls: a depth-first walk of the file's nodes in PREORDER. A
 * node's part callback comes before its children's, and its instances come
 * right after its own part callback, before its children's. A material is
 * reported just before the first mesh that uses it, a mesh just before its
 * first instance; each once, and only those some node uses (an aiMesh several
 * nodes use is one mesh and many instances). So part ids a sink hands out in
 * order are preorder ids, as part_tree.h wants.
 *
 * Parts: every node becomes a part, named by its node name with each '/'
 * replaced by '_', an empty name replaced by "node-K" (K: the number of parts
 * before it, root excluded), and names cut at PART_NAME_MAX_BYTES - 32 bytes;
 * a name taken among its siblings gets "#2", "#3", ... (part_tree.h). The
 * file's root node is no part when it only holds the file together: it has
 * no meshes and its name is one assimp makes up ("", "ROOT", which glTF files
 * with several scene roots get, "RootNode", or the file's own name, which OBJ
 * files get); its children are then the top-level parts (parent -1). Any
 * other root node is the one top-level part (a glTF scene with one root node).
 * OBJ: every "o" or "g" group is one top-level part named by the group; the
 * group assimp makes for faces before any group ("defaultobject") is named
 * after the file's base name without its extension ("plain.obj": "plain").
 *
 * Geometry: triangulated; points and lines dropped (a node with only those
 * is still a part); normals and the first colour set kept when present;
 * identical vertices joined after every position and normal is checked
 * finite (assimp_import.h); every mesh passes mesh_validate. Transforms: a
 * node's to_world is the product of the node transforms from the root down,
 * as a row-major 3x4 affine matrix [R | t] (world = R * object + t), composed
 * in double. Materials: linear RGB base colour (glTF's baseColorFactor, which
 * is linear already), else the diffuse colour (OBJ's MTL "Kd"), else 0.6
 * grey; clamped to [0, 1]; a non-finite colour is an error.
 *
 * Any callback returning a negative value stops the load (instance: any
 * value >= 0 goes on).
 *
 * Errors: false with err naming the file and the problem (missing file, not
 * a model, broken JSON, an index out of range, a NaN, a non-finite
 * transform, a sink returning -1). Everything assembly_load allocated is
 * freed on every path; what the sink made before is the sink's to free.
 * Thread-safe: concurrent loads (with their own sinks) may run. */
#ifndef TESSERA_ASSEMBLY_LOAD_H
#define TESSERA_ASSEMBLY_LOAD_H

#include <stdbool.h>

#include "engine/base/err.h"

struct mesh;

typedef struct assembly_sink {
    void *ctx;
    /* a material: linear RGB base colour in [0,1] and a name; returns its id (>=0) or -1 to abort */
    int (*material)(void *ctx, const char *name, const float rgb[3]);
    /* a mesh in its own object space (ownership passes to the sink, also on failure: it must free it);
       material: an id the sink returned; returns a mesh id (>=0) or -1 to abort */
    int (*mesh)(void *ctx, struct mesh *m, int material, const char *name);
    /* a part: parent part id (-1 for a child of the root), unique name among siblings; returns part id or -1 */
    int (*part)(void *ctx, int parent, const char *name);
    /* one use of mesh `mesh` by part `part`, placed by the row-major 3x4 affine object-to-world matrix */
    int (*instance)(void *ctx, int part, int mesh, const float to_world[12]);
} assembly_sink;

/* Load `path` and report its materials, meshes, parts and instances to sink
 * (every callback must be set) in the order described at the top. */
bool assembly_load(const char *path, const assembly_sink *sink, tess_error *err);

#endif
