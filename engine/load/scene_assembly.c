/* scene_assembly.c - assemblies in a scene (scene_load.h): the sink that
 * turns what assembly_load finds into scene materials, mesh geometries stored
 * once, the part tree and instances. The queries on parts are the scene's
 * (engine/scene/scene_parts.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assembly_load.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/part_tree.h"
#include "engine/scene/scene.h"
#include "scene_load.h"

typedef struct scene_sink {
    scene *s;
    const char *path;
    const affine3 *placement; /* NULL: none */
    tess_error *err;
    /* assembly ids -> scene ids: materials and meshes by the order the sink
     * handed them out, parts too (ids of this file start at part_base) */
    uint32_t *material_ids, material_count, material_capacity;
    uint32_t *geometry_ids, geometry_count, geometry_capacity;
    int32_t part_base; /* scene part id of the assembly's part 0 minus 1 */
} scene_sink;

static bool push(uint32_t **array, uint32_t *count, uint32_t *capacity, uint32_t value)
{
    if (*count == *capacity) {
        uint32_t cap = *capacity ? *capacity * 2 : 64;
        uint32_t *p = realloc(*array, (size_t)cap * sizeof *p);
        if (!p)
            return false;
        *array = p;
        *capacity = cap;
    }
    (*array)[(*count)++] = value;
    return true;
}

static int oom(scene_sink *k)
{
    tess_error_set(k->err, "%s: out of memory building the scene", k->path);
    return -1;
}

static int sink_material(void *ctx, const char *name, const float rgb[3])
{
    scene_sink *k = ctx;
    material m = material_default();
    m.diffuse = v3(rgb[0], rgb[1], rgb[2]);
    snprintf(m.name, sizeof m.name, "%.*s", (int)(sizeof m.name - 1), name ? name : "");
    int id = scene_add_material(k->s, &m);
    if (id < 0 || !push(&k->material_ids, &k->material_count, &k->material_capacity, (uint32_t)id))
        return oom(k);
    return (int)k->material_count - 1;
}

static int sink_mesh(void *ctx, mesh *m, int material_index, const char *name)
{
    scene_sink *k = ctx;
    if (material_index < 0 || (uint32_t)material_index >= k->material_count) {
        mesh_destroy(m);
        tess_error_set(k->err, "%s: mesh '%s' names material %d of %u", k->path, name, material_index,
                       k->material_count);
        return -1;
    }
    int g = scene_add_mesh_geometry(k->s, m, k->material_ids[material_index], name);
    if (g < 0 || !push(&k->geometry_ids, &k->geometry_count, &k->geometry_capacity, (uint32_t)g))
        return oom(k);
    return (int)k->geometry_count - 1;
}

static int sink_part(void *ctx, int parent, const char *name)
{
    scene_sink *k = ctx;
    int32_t scene_parent = parent < 0 ? PART_ROOT : k->part_base + parent;
    int32_t id = part_tree_add(k->s->parts, scene_parent, name, k->err);
    if (id < 0)
        return -1;
    return (int)(id - k->part_base);
}

static int sink_instance(void *ctx, int part, int mesh_id, const float to_world[12])
{
    scene_sink *k = ctx;
    if (mesh_id < 0 || (uint32_t)mesh_id >= k->geometry_count) {
        tess_error_set(k->err, "%s: an instance names mesh %d of %u", k->path, mesh_id, k->geometry_count);
        return -1;
    }
    affine3 xform;
    memcpy(xform.m, to_world, sizeof xform.m);
    if (k->placement) /* placement after the file's own transform */
        xform = affine3_compose(k->placement, &xform);
    uint32_t scene_part = (uint32_t)(k->part_base + part);
    if (scene_add_instance(k->s, k->geometry_ids[mesh_id], &xform, scene_part) < 0) {
        tess_error_set(k->err, "%s: part %u: its transform is singular or not finite, or out of memory", k->path,
                       scene_part);
        return -1;
    }
    part_counts *counts = part_tree_counts(k->s->parts, (int32_t)scene_part);
    counts->instances++;
    const scene_geometry *g = &k->s->geometries[k->geometry_ids[mesh_id]];
    counts->triangles += g->ops->prim_count(g->data);
    return 0;
}

bool scene_load_assembly(scene *s, const char *path, const affine3 *placement, tess_error *err)
{
    if (!s->parts && !(s->parts = part_tree_create()))
        return tess_error_set(err, "%s: out of memory building the scene", path);
    scene_sink k = {.s = s, .path = path, .placement = placement, .err = err};
    /* the file's parts go after those already there (a preorder still: they
     * are new children of the root, after every existing subtree) */
    k.part_base = part_tree_count(s->parts) - 1;
    assembly_sink sink = {.ctx = &k, .material = sink_material, .mesh = sink_mesh, .part = sink_part,
                          .instance = sink_instance};
    bool ok = assembly_load(path, &sink, err);
    free(k.material_ids);
    free(k.geometry_ids);
    return ok;
}

/* How many instances with a part have a part below `part` (a lower bound
 * in s->parted, whose parts never decrease). */
