/* fuzz_ply.c - PLY meshes (engine/load/mesh_ply.c), ascii and binary: the input is
 * the file, handed over as a memfd (the reader takes a path and wants a
 * regular file). */
#include "fuzz.h"

#include "engine/geometry/triangles/mesh.h"
#include "engine/load/mesh_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_memfd(data, size);
    tess_error err = {{0}};
    mesh *m = mesh_load_ply(path, &err);
    if (m)
        fuzz_check_mesh(m, path);
    else
        fuzz_check_error(&err, path);
    mesh_destroy(m);
    return 0;
}
