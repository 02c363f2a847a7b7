/* scene_load.c - a scene from one file (scene_load.h): the dispatch between
 * JSON scene files (scene_json.c), assemblies (scene_assembly.c), particle
 * files and bare mesh files, each with the default material and light. */
#include "scene_load.h"

#include <stdint.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "engine/geometry/particles/particle_kind.h"
#include "engine/base/path.h"
#include "engine/geometry/triangles/mesh_cache.h"
#include "mesh_load.h"
#include "particle_load.h"
#include "ply_read.h"

static scene *scene_load_particle_file(const char *path, tess_error *err);

/* A scene of one mesh file in file coordinates, the default material and light. */
static scene *scene_load_mesh_file(const char *path, bool spatial_splits, tess_error *err)
{
    mesh_cache_params params;
    memset(&params, 0, sizeof params);
    params.spatial_splits = spatial_splits;
    memcpy(params.xform, (const float[12]){1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}, sizeof params.xform);
    mesh_cache_load cached;
    mesh *m = mesh_cache_load_file(path, &params, mesh_load, &cached, err);
    if (!m)
        return NULL;
    if (m->triangle_count == 0 && m->vertex_count > 0 && path_has_extension(path, ".ply")) {
        /* vertices only: a point set, drawn as particles (as the Embree peer does) */
        mesh_cache_abandon(&cached);
        mesh_destroy(m);
        return scene_load_particle_file(path, err);
    }
    if (m->triangle_count == 0) {
        mesh_cache_abandon(&cached);
        mesh_destroy(m);
        uint64_t vertices = 0;
        int64_t faces = 0;
        tess_error probe = {{0}};
        if (path_has_extension(path, ".ply") && ply_probe_counts(path, &vertices, &faces, &probe) && faces < 0)
            tess_error_set(err, "%s: scene has no geometry (the point set has no points: 0 vertices)", path);
        else
            tess_error_set(err, "%s: scene has no geometry (the mesh has no triangles)", path);
        return NULL;
    }
    scene *s = scene_create();
    material def_mat = material_default();
    light def_light = light_default_directional();
    int mat_id = s ? scene_add_material(s, &def_mat) : -1;
    int mesh_id = mat_id < 0 ? -1 : scene_add_mesh(s, m, (uint32_t)mat_id, path_basename(path));
    if (mesh_id >= 0) {
        s->meshes[mesh_id]->spatial_splits = spatial_splits;
        mesh_cache_adopt(s->meshes[mesh_id], &cached);
    }
    else
        mesh_cache_abandon(&cached);
    if (mesh_id < 0 || scene_add_light(s, &def_light) < 0) {
        if (mat_id < 0)
            mesh_destroy(m); /* scene_add_mesh was never reached to take it */
        scene_destroy(s);
        tess_error_set(err, "%s: out of memory building the scene", path);
        return NULL;
    }
    return s;
}

/* A scene of one particle file (a LAMMPS dump, a PLY of vertices only) as
 * spheres of the default radius, the default material and light. */
static scene *scene_load_particle_file(const char *path, tess_error *err)
{
    particle_set *set = particles_load(path, err);
    if (!set)
        return NULL;
    if (set->count == 0) {
        particle_set_destroy(set);
        tess_error_set(err, "%s: scene has no geometry (no particles)", path);
        return NULL;
    }
    scene *s = scene_create();
    material def_mat = material_default();
    light def_light = light_default_directional();
    int mat_id = s ? scene_add_material(s, &def_mat) : -1;
    if (mat_id < 0 || scene_add_light(s, &def_light) < 0) {
        particle_set_destroy(set);
        scene_destroy(s);
        tess_error_set(err, "%s: out of memory building the scene", path);
        return NULL;
    }
    /* a scanner's colours when the file has them */
    bool rgb = particle_set_find_attribute(set, "red") >= 0 && particle_set_find_attribute(set, "green") >= 0 &&
               particle_set_find_attribute(set, "blue") >= 0;
    particle_kind_options opt = {.radius = particle_kind_default_radius(set),
                                 .material_id = (uint32_t)mat_id,
                                 .colouring = rgb ? PARTICLE_COLOUR_RGB : PARTICLE_COLOUR_MATERIAL};
    particle_kind *k = particle_kind_create(set, &opt, path, err);
    int g = k ? scene_add_geometry(s, &particle_kind_ops, k, path_basename(path)) : -1;
    if (g < 0 || scene_add_instance(s, (uint32_t)g, NULL, SCENE_NO_PART) < 0) {
        scene_destroy(s);
        if (k) /* else particle_kind_create said why */
            tess_error_set(err, "%s: out of memory building the scene", path);
        return NULL;
    }
    return s;
}

/* A scene of one assembly file (its parts and instances), the default light. */
static scene *scene_load_assembly_file(const char *path, tess_error *err)
{
    scene *s = scene_create();
    light def_light = light_default_directional();
    if (!s || scene_add_light(s, &def_light) < 0) {
        scene_destroy(s);
        tess_error_set(err, "%s: out of memory building the scene", path);
        return NULL;
    }
    if (!scene_load_assembly(s, path, NULL, err)) {
        scene_destroy(s);
        return NULL;
    }
    if (scene_instanced_triangle_count(s) == 0) {
        scene_destroy(s);
        tess_error_set(err, "%s: scene has no geometry (no part has triangles)", path);
        return NULL;
    }
    return s;
}

scene *scene_load(const char *path, tess_error *err) { return scene_load_with(path, NULL, err); }

scene *scene_load_with(const char *path, const scene_load_options *opts, tess_error *err)
{
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        tess_error_set(err, "%s: is a directory (a scene is a file: .json, a mesh, an assembly or a particle file)",
                       path);
        return NULL;
    }
    const scene_load_options none = {0};
    if (!opts)
        opts = &none;
    if (path_has_extension(path, ".json"))
        return scene_load_json_with(path, opts, err);
    if (path_has_extension(path, ".gltf") || path_has_extension(path, ".glb"))
        return scene_load_assembly_file(path, err);
    if (path_has_extension(path, ".dump") || path_has_extension(path, ".lammpstrj"))
        return scene_load_particle_file(path, err);
    return scene_load_mesh_file(path, opts->spatial_splits, err);
}
