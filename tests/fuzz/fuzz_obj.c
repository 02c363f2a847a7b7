/* fuzz_obj.c - OBJ meshes through mesh_load_assimp (engine/load/mesh_assimp.c):
 * tessera's number check, then assimp's OBJ and MTL readers. The input is
 * written to in.obj in a scratch directory; a line "#--mtl--" splits it, and
 * what follows goes to in.mtl beside it (seeds say "mtllib in.mtl"), so the
 * material reader is fuzzed too. */
#define _GNU_SOURCE /* memmem */
#include "fuzz.h"

#include <stdio.h>
#include <string.h>

#include "engine/geometry/triangles/mesh.h"
#include "engine/load/mesh_load.h"

#define MTL_SPLIT "\n#--mtl--\n"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char obj_path[512], mtl_path[512];
    if (!obj_path[0]) {
        snprintf(obj_path, sizeof obj_path, "%s/in.obj", fuzz_scratch_dir());
        snprintf(mtl_path, sizeof mtl_path, "%s/in.mtl", fuzz_scratch_dir());
    }
    size_t obj_bytes = size;
    const uint8_t *split = memmem(data, size, MTL_SPLIT, strlen(MTL_SPLIT));
    if (split)
        obj_bytes = (size_t)(split - data) + 1;
    size_t mtl_at = split ? obj_bytes + strlen(MTL_SPLIT) - 1 : size;
    fuzz_write(obj_path, data, obj_bytes);
    fuzz_write(mtl_path, data + mtl_at, size - mtl_at);

    tess_error err = {{0}};
    mesh *m = mesh_load_assimp(obj_path, &err);
    if (m)
        fuzz_check_mesh(m, obj_path);
    else
        fuzz_check_error(&err, obj_path);
    mesh_destroy(m);
    fuzz_watch_leaks(data, size);
    return 0;
}
