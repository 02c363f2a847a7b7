/* fuzz_scene.c - JSON scene files (engine/load/scene_json.c over engine/base/json_read.c)
 * through scene_parse_json. The scene is named scene.json in a scratch
 * directory holding two tiny PLY meshes, quad.ply (with normals) and tri.ply,
 * so that seeds naming them reach the mesh and transform paths. No OBJ: one
 * assimp import costs 0.1-0.3 s under ASan (it clears a 16 MiB buffer), so a
 * scene of a few would pass the 1 s limit; scenes with OBJ materials are
 * tests/test_scene.c's, and OBJ itself is fuzz_obj's. */
#include "fuzz.h"

#include <math.h>
#include <stdio.h>

#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"

static const char quad_ply[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                               "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                               "-1 0 -1 0 1 0\n1 0 -1 0 1 0\n1 0 1 0 1 0\n-1 0 1 0 1 0\n4 0 3 2 1\n";
static const char tri_ply[] = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                              "property float y\nproperty float z\nelement face 1\n"
                              "property list uchar int vertex_indices\nend_header\n"
                              "\0\0\0\0\0\0\0\0\0\0\0\0" "\0\0\x80\x3f\0\0\0\0\0\0\0\0"
                              "\0\0\0\0\0\0\x80\x3f\0\0\0\0" "\x03\0\0\0\0\x01\0\0\0\x02\0\0\0";

static bool in_unit(vec3 v) { return v.x >= 0.f && v.x <= 1.f && v.y >= 0.f && v.y <= 1.f && v.z >= 0.f && v.z <= 1.f; }
static bool nonneg(vec3 v) { return v.x >= 0.f && v.y >= 0.f && v.z >= 0.f && isfinite(v.x + v.y + v.z); }

static void check_scene(const scene *s, const char *name)
{
    if (s->mesh_count == 0 && s->spheres.count == 0)
        fuzz_fail("%s: a scene without geometry was accepted", name);
    for (uint32_t i = 0; i < s->material_count; i++) {
        const material *m = &s->materials[i];
        if (!in_unit(m->diffuse) || !nonneg(m->specular) || !(m->shininess >= 0.f) || !(m->ambient >= 0.f && m->ambient <= 1.f))
            fuzz_fail("%s: material %u out of range", name, i);
    }
    for (uint32_t i = 0; i < s->light_count; i++) {
        const light *l = &s->lights[i];
        if (!nonneg(l->color) || !(l->intensity >= 0.f) || !isfinite(l->position.x + l->position.y + l->position.z))
            fuzz_fail("%s: light %u out of range", name, i);
        float len2 = l->direction.x * l->direction.x + l->direction.y * l->direction.y + l->direction.z * l->direction.z;
        if (l->kind == LIGHT_DIRECTIONAL && !(fabsf(len2 - 1.f) < 1e-3f))
            fuzz_fail("%s: light %u: direction not unit (|d|^2 = %g)", name, i, (double)len2);
    }
    for (uint32_t i = 0; i < s->mesh_count; i++) {
        const scene_mesh *sm = s->meshes[i];
        fuzz_check_mesh(sm->mesh, name);
        if (sm->material_id >= s->material_count)
            fuzz_fail("%s: mesh %u: material %u of %u", name, i, sm->material_id, s->material_count);
        for (uint32_t k = 0; sm->mesh_material_ids && k < sm->mesh->material_count; k++)
            if (sm->mesh_material_ids[k] >= s->material_count)
                fuzz_fail("%s: mesh %u: file material %u is %u of %u", name, i, k, sm->mesh_material_ids[k],
                          s->material_count);
    }
    const sphere_set *ss = &s->spheres;
    for (uint32_t i = 0; i < ss->count; i++) {
        if (!(ss->radius[i] > 0.f) || !isfinite(ss->radius[i] + ss->center_x[i] + ss->center_y[i] + ss->center_z[i]))
            fuzz_fail("%s: sphere %u out of range", name, i);
        if (ss->material_id[i] >= s->material_count)
            fuzz_fail("%s: sphere %u: material %u of %u", name, i, ss->material_id[i], s->material_count);
    }
    tess_error err = {{0}};
    if (s->has_camera && !camera_validate(&s->camera, &err))
        fuzz_fail("%s: an invalid camera was accepted: %s", name, err.msg);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char name[512];
    if (!name[0]) {
        const char *dir = fuzz_scratch_dir();
        char path[512];
        snprintf(path, sizeof path, "%s/quad.ply", dir);
        fuzz_write(path, quad_ply, sizeof quad_ply - 1);
        snprintf(path, sizeof path, "%s/tri.ply", dir);
        fuzz_write(path, tri_ply, sizeof tri_ply - 1);
        snprintf(name, sizeof name, "%s/scene.json", dir);
    }
    tess_error err = {{0}};
    scene *s = scene_parse_json(name, (const char *)data, size, &err);
    if (s)
        check_scene(s, name);
    else
        fuzz_check_error(&err, name);
    scene_destroy(s);
    return 0;
}
