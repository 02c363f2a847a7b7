/* mesh_assimp.c - every mesh format assimp reads (.obj with .mtl, .stl, .off,
 * .gltf, ...) through its C API, merged into one tessera mesh.
 *
 * The scene is flattened (node transforms baked in), triangulated and split by
 * primitive type; every triangle mesh is appended, points and lines are
 * dropped. Normals and colours are kept only when every triangle mesh has them
 * (assimp is not asked to invent normals). Materials: see wants_materials().
 * The import and its checks against assimp 5.2's holes are shared with the
 * part-tree loader (assimp_import.h); assembly_load.h keeps the hierarchy. */
#include "engine/geometry/triangles/mesh.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assimp_import.h"
#include "mesh_load.h"

/* PreTransformVertices bakes the node hierarchy into the vertices, so all
 * meshes share one object space (assimp_import_file adds triangulation,
 * validation and the joining of identical vertices). */
#define IMPORT_FLAGS aiProcess_PreTransformVertices

/* Diffuse colour for a material that names none (assimp's own default grey). */
#define DEFAULT_DIFFUSE 0.6f

/* ---- the scene ---------------------------------------------------------- */

/* What the merged mesh will hold. */
typedef struct merge_plan {
    uint64_t vertex_count;   /* sum over triangle meshes */
    uint64_t triangle_count; /* sum over triangle meshes */
    bool normals;            /* every triangle mesh has normals */
    bool colors;             /* every triangle mesh has a first colour set */
} merge_plan;

static merge_plan plan_merge(const struct aiScene *scene)
{
    merge_plan plan = {.normals = true, .colors = true};
    for (unsigned i = 0; i < scene->mNumMeshes; i++) {
        const struct aiMesh *am = scene->mMeshes[i];
        if (!assimp_is_triangle_mesh(am))
            continue;
        plan.vertex_count += am->mNumVertices;
        plan.triangle_count += am->mNumFaces;
        plan.normals &= am->mNormals != NULL;
        plan.colors &= am->mColors[0] != NULL;
    }
    return plan;
}

static bool material_diffuse(const struct aiMaterial *mat, float rgb[3])
{
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, AI_MATKEY_COLOR_DIFFUSE, &c) != aiReturn_SUCCESS)
        return false;
    rgb[0] = c.r;
    rgb[1] = c.g;
    rgb[2] = c.b;
    return true;
}

static bool is_default_material(const struct aiMaterial *mat)
{
    struct aiString name;
    return aiGetMaterialString(mat, AI_MATKEY_NAME, &name) != aiReturn_SUCCESS ||
           strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) == 0;
}

/* The rule: per-triangle materials are kept when a triangle mesh uses a
 * material that the file itself defines, i.e. one with a diffuse colour and a
 * name other than the "DefaultMaterial" assimp makes up for files without
 * materials (an OBJ without MTL, STL, PLY). One MTL material is enough. */
static bool wants_materials(const struct aiScene *scene)
{
    float rgb[3];
    for (unsigned i = 0; i < scene->mNumMeshes; i++) {
        const struct aiMesh *am = scene->mMeshes[i];
        if (!assimp_is_triangle_mesh(am) || am->mMaterialIndex >= scene->mNumMaterials)
            continue;
        const struct aiMaterial *mat = scene->mMaterials[am->mMaterialIndex];
        if (!is_default_material(mat) && material_diffuse(mat, rgb))
            return true;
    }
    return false;
}

static void describe_material(const struct aiMaterial *mat, mesh_material *out)
{
    struct aiString name;
    out->name[0] = '\0';
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS) {
        size_t n = strnlen(name.data, sizeof out->name - 1); /* longer names are cut */
        memcpy(out->name, name.data, n);
        out->name[n] = '\0';
    }
    if (!material_diffuse(mat, out->diffuse_rgb))
        out->diffuse_rgb[0] = out->diffuse_rgb[1] = out->diffuse_rgb[2] = DEFAULT_DIFFUSE;
    /* a reflectance: clamped to [0, 1] as vertex colours are ("Kd 1.0000001",
     * or a fuzzer's "Kd 9"); NaN passes and is refused by convert_scene */
    for (int k = 0; k < 3; k++) {
        float v = out->diffuse_rgb[k];
        out->diffuse_rgb[k] = v < 0.f ? 0.f : v > 1.f ? 1.f : v;
    }
}

/* Give m one mesh_material per scene material some triangle mesh uses, in
 * scene order; remap[scene index] = tessera index (UINT32_MAX when unused). */
static bool collect_materials(const struct aiScene *scene, mesh *m, uint32_t *remap)
{
    m->materials = calloc(scene->mNumMaterials ? scene->mNumMaterials : 1, sizeof *m->materials);
    if (!m->materials)
        return false;
    for (unsigned i = 0; i < scene->mNumMaterials; i++)
        remap[i] = UINT32_MAX;
    for (unsigned i = 0; i < scene->mNumMeshes; i++) {
        unsigned s = scene->mMeshes[i]->mMaterialIndex;
        if (assimp_is_triangle_mesh(scene->mMeshes[i]) && s < scene->mNumMaterials && remap[s] == UINT32_MAX)
            remap[s] = 0; /* mark used; numbered below in scene order */
    }
    for (unsigned s = 0; s < scene->mNumMaterials; s++)
        if (remap[s] != UINT32_MAX) {
            remap[s] = m->material_count;
            describe_material(scene->mMaterials[s], &m->materials[m->material_count++]);
        }
    return true;
}

static bool allocate(mesh *m, const merge_plan *plan, bool materials)
{
    return mesh_reserve_vertices(m, (uint32_t)plan->vertex_count) &&
           mesh_reserve_triangles(m, (uint32_t)plan->triangle_count) && (!plan->normals || mesh_enable_normals(m)) &&
           (!plan->colors || mesh_enable_colors(m)) && (!materials || mesh_enable_triangle_materials(m));
}

static mesh *convert_scene(const struct aiScene *scene, const char *path, tess_error *err)
{
    merge_plan plan = plan_merge(scene);
    if (plan.triangle_count == 0) {
        tess_error_set(err, "%s: no triangles", path);
        return NULL;
    }
    if (plan.vertex_count > UINT32_MAX || plan.triangle_count > UINT32_MAX) {
        tess_error_set(err, "%s: %llu vertices, %llu triangles: more than a mesh can hold", path,
                       (unsigned long long)plan.vertex_count, (unsigned long long)plan.triangle_count);
        return NULL;
    }
    bool materials = wants_materials(scene);
    mesh *m = mesh_create();
    uint32_t *remap = calloc(scene->mNumMaterials ? scene->mNumMaterials : 1, sizeof *remap);
    if (!m || !remap || !allocate(m, &plan, materials) || (materials && !collect_materials(scene, m, remap))) {
        tess_error_set(err, "%s: out of memory for %llu vertices and %llu triangles", path,
                       (unsigned long long)plan.vertex_count, (unsigned long long)plan.triangle_count);
        goto fail;
    }
    for (uint32_t i = 0; i < m->material_count; i++) {
        const mesh_material *mm = &m->materials[i];
        if (!isfinite(mm->diffuse_rgb[0] + mm->diffuse_rgb[1] + mm->diffuse_rgb[2])) {
            tess_error_set(err, "%s: material '%s': diffuse colour (Kd) is not finite", path, mm->name);
            goto fail;
        }
    }
    for (unsigned i = 0; i < scene->mNumMeshes; i++) {
        const struct aiMesh *am = scene->mMeshes[i];
        if (!assimp_is_triangle_mesh(am))
            continue;
        uint32_t material = materials && am->mMaterialIndex < scene->mNumMaterials ? remap[am->mMaterialIndex] : 0;
        uint32_t first = m->vertex_count;
        assimp_append_vertices(m, am);
        m->vertex_count += am->mNumVertices;
        if (!assimp_append_triangles(m, am, first, material, path, err))
            goto fail;
    }
    free(remap);
    return m;
fail:
    free(remap);
    mesh_destroy(m);
    return NULL;
}

mesh *mesh_load_assimp(const char *path, tess_error *err)
{
    const struct aiScene *scene = assimp_import_file(path, IMPORT_FLAGS, err);
    if (!scene)
        return NULL;
    mesh *m = convert_scene(scene, path, err);
    assimp_release(scene);
    if (m && !mesh_validate(m, path, err)) {
        mesh_destroy(m);
        return NULL;
    }
    return m;
}
