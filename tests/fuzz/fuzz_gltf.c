/* fuzz_gltf.c - glTF files through assembly_load (engine/load/assembly_load.c):
 * assimp's glTF 2.0 reader, then tessera's walk of the node tree. The input
 * is written to in.gltf in a scratch directory (buffers come as data URIs in
 * the seeds). The sink checks what assembly_load.h promises: parts in
 * preorder with unique sibling names and no '/' (a part_tree refuses
 * anything else), an instance right after its part's callback, of a mesh
 * already reported, with a finite matrix; materials before their meshes,
 * colours in [0, 1]; every mesh valid (fuzz_check_mesh), freed here. */
#include "fuzz.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/load/assembly_load.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/part_tree.h"

typedef struct fuzz_sink {
    const char *path;
    part_tree *parts;
    int materials, meshes;
} fuzz_sink;

static int on_material(void *ctx, const char *name, const float rgb[3])
{
    fuzz_sink *s = ctx;
    for (int k = 0; k < 3; k++)
        if (!(rgb[k] >= 0.f && rgb[k] <= 1.f))
            fuzz_fail("%s: material '%s': component %d is %g, not in [0, 1]", s->path, name, k, (double)rgb[k]);
    return s->materials++;
}

static int on_mesh(void *ctx, struct mesh *m, int material, const char *name)
{
    fuzz_sink *s = ctx;
    if (material < 0 || material >= s->materials)
        fuzz_fail("%s: mesh '%s': material %d was not reported (%d were)", s->path, name, material, s->materials);
    fuzz_check_mesh(m, s->path);
    mesh_destroy(m);
    return s->meshes++;
}

static int on_part(void *ctx, int parent, const char *name)
{
    fuzz_sink *s = ctx;
    tess_error err = {{0}};
    int32_t id = part_tree_add(s->parts, parent < 0 ? PART_ROOT : parent, name, &err);
    if (id == PART_NONE)
        fuzz_fail("%s: part '%s' under %d refused by the part tree: %s", s->path, name, parent, err.msg);
    return id;
}

static int on_instance(void *ctx, int part, int mesh_id, const float to_world[12])
{
    fuzz_sink *s = ctx;
    if (part != part_tree_count(s->parts) - 1)
        fuzz_fail("%s: instance on part %d after part %d", s->path, part, part_tree_count(s->parts) - 1);
    if (mesh_id < 0 || mesh_id >= s->meshes)
        fuzz_fail("%s: instance of mesh %d (%d reported)", s->path, mesh_id, s->meshes);
    for (int k = 0; k < 12; k++)
        if (!isfinite(to_world[k]))
            fuzz_fail("%s: instance on part %d: matrix element %d is %g", s->path, part, k, (double)to_world[k]);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char path[512];
    if (!path[0])
        snprintf(path, sizeof path, "%s/in.gltf", fuzz_scratch_dir());
    fuzz_write(path, data, size);
    fuzz_sink s = {.path = path, .parts = part_tree_create()};
    if (!s.parts)
        fuzz_fail("out of memory for the part tree");
    assembly_sink sink = {.ctx = &s, .material = on_material, .mesh = on_mesh, .part = on_part, .instance = on_instance};
    tess_error err = {{0}};
    if (!assembly_load(path, &sink, &err))
        fuzz_check_error(&err, path);
    part_tree_destroy(s.parts);
    fuzz_watch_leaks(data, size);
    return 0;
}
