/* mesh_load.c - a mesh file by its extension (mesh_load.h). */
#include "mesh_load.h"

#include "engine/base/path.h"

mesh *mesh_load(const char *path, tess_error *err)
{
    if (path_has_extension(path, ".ply"))
        return mesh_load_ply(path, err);
    return mesh_load_assimp(path, err);
}
