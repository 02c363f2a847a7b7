/* mesh_load.c - a mesh file by its extension (mesh_load.h). */
#include "mesh_load.h"

#include <string.h>
#include <strings.h>

static bool has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n >= e && strcasecmp(path + n - e, ext) == 0;
}

mesh *mesh_load(const char *path, tess_error *err)
{
    if (has_extension(path, ".ply"))
        return mesh_load_ply(path, err);
    return mesh_load_assimp(path, err);
}
