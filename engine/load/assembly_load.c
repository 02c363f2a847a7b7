/* assembly_load.c - assimp's node tree reported to a sink (assembly_load.h).
 *
 * The walk is iterative (a file may nest nodes 100,000 deep): a stack of
 * pending nodes with their depths, and per depth the open ancestor's world
 * matrix and ids, valid because in preorder everything popped between a
 * node's parent and the node lies deeper than the parent. Sibling names are
 * made unique by a part_tree of our own (a hash over (parent, name): O(1) a
 * part), whose ids mirror the parts reported. */
#include "assembly_load.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assimp_import.h"
#include "engine/base/path.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/part_tree.h"

/* Base colour for a material that names none (assimp's own default grey). */
#define DEFAULT_BASE_COLOR 0.6f
/* Imported names are cut to this many bytes, leaving room for a "#N" suffix. */
#define NAME_MAX_BYTES (PART_NAME_MAX_BYTES - 32)
/* The group assimp's OBJ reader makes for faces before any "o" or "g". */
#define OBJ_DEFAULT_GROUP "defaultobject"

enum { MESH_UNSEEN = -2, MESH_SKIPPED = -3 }; /* mesh_ids / material_ids before the sink's id */

/* A node waiting to be walked. */
typedef struct pending {
    const struct aiNode *node;
    size_t depth; /* 0 for a top-level part */
} pending;

/* The open ancestor at one depth. */
typedef struct ancestor {
    double world[12]; /* its to_world, row-major 3x4 */
    int32_t name_id;  /* its id in loader.names */
    int sink_part;    /* the id the sink gave it */
} ancestor;

typedef struct loader {
    const char *path;
    const assembly_sink *sink;
    tess_error *err;
    const struct aiScene *scene;
    int *mesh_ids;          /* per aiMesh: the sink's id, MESH_UNSEEN or MESH_SKIPPED */
    int *material_ids;      /* per aiMaterial: the sink's id or MESH_UNSEEN */
    part_tree *names;       /* the parts reported, for unique sibling names */
    pending *todo;          /* the walk's stack */
    size_t todo_count, todo_cap;
    ancestor *ancestors;    /* [depth]: see the top */
    size_t ancestor_cap;
    double top_world[12];   /* what a top-level part's transform composes with */
    bool obj;               /* an .obj file: OBJ_DEFAULT_GROUP gets the stem */
    char stem[256];         /* the file's base name without its extension */
    char file_name[256];    /* the file's base name */
} loader;

static bool grow(void **array, size_t *cap, size_t need, size_t bytes)
{
    if (need <= *cap)
        return true;
    size_t n = *cap ? *cap : 64;
    while (n < need)
        n *= 2;
    void *p = realloc(*array, n * bytes);
    if (!p)
        return false;
    *array = p;
    *cap = n;
    return true;
}

static bool out_of_memory(loader *L, const char *what)
{
    return tess_error_set(L->err, "%s: out of memory (%s)", L->path, what);
}

/* ---- materials and meshes ------------------------------------------------ */

static bool material_color(const struct aiMaterial *mat, float rgb[3])
{
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, AI_MATKEY_BASE_COLOR, &c) != aiReturn_SUCCESS &&
        aiGetMaterialColor(mat, AI_MATKEY_COLOR_DIFFUSE, &c) != aiReturn_SUCCESS)
        c.r = c.g = c.b = DEFAULT_BASE_COLOR;
    rgb[0] = c.r;
    rgb[1] = c.g;
    rgb[2] = c.b;
    for (int k = 0; k < 3; k++) {
        if (!isfinite(rgb[k]))
            return false;
        rgb[k] = rgb[k] < 0.f ? 0.f : rgb[k] > 1.f ? 1.f : rgb[k];
    }
    return true;
}

/* The sink's id of material `index`, reported on first use; -1 on failure. */
static int report_material(loader *L, unsigned index)
{
    if (L->material_ids[index] != MESH_UNSEEN)
        return L->material_ids[index];
    const struct aiMaterial *mat = L->scene->mMaterials[index];
    struct aiString name;
    char fallback[32];
    const char *text = fallback;
    snprintf(fallback, sizeof fallback, "material-%u", index);
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && name.data[0])
        text = name.data;
    float rgb[3];
    if (!material_color(mat, rgb)) {
        tess_error_set(L->err, "%s: material '%s': base colour is not finite", L->path, text);
        return -1;
    }
    int id = L->sink->material(L->sink->ctx, text, rgb);
    if (id < 0)
        tess_error_set(L->err, "%s: loading stopped: the receiver refused material '%s'", L->path, text);
    return L->material_ids[index] = id < 0 ? -1 : id;
}

/* aiMesh `am` as a tessera mesh in its object space, validated; NULL on failure. */
static mesh *convert_mesh(loader *L, const struct aiMesh *am, const char *name)
{
    mesh *m = mesh_create();
    if (!m || !mesh_reserve_vertices(m, am->mNumVertices) || !mesh_reserve_triangles(m, am->mNumFaces) ||
        (am->mNormals && !mesh_enable_normals(m)) || (am->mColors[0] && !mesh_enable_colors(m))) {
        tess_error_set(L->err, "%s: mesh '%s': out of memory for %u vertices and %u triangles", L->path, name,
                       am->mNumVertices, am->mNumFaces);
        mesh_destroy(m);
        return NULL;
    }
    assimp_append_vertices(m, am);
    m->vertex_count = am->mNumVertices;
    char source[512];
    snprintf(source, sizeof source, "%s: mesh '%.200s'", L->path, name);
    if (!assimp_append_triangles(m, am, 0, 0, L->path, L->err) || !mesh_validate(m, source, L->err)) {
        mesh_destroy(m);
        return NULL;
    }
    return m;
}

/* The sink's id of aiMesh `index`, reported (with its material) on first
 * use; MESH_SKIPPED for a mesh of points or lines; -1 on failure. */
static int report_mesh(loader *L, unsigned index)
{
    if (L->mesh_ids[index] != MESH_UNSEEN)
        return L->mesh_ids[index];
    const struct aiMesh *am = L->scene->mMeshes[index];
    if (!assimp_is_triangle_mesh(am))
        return L->mesh_ids[index] = MESH_SKIPPED;
    char fallback[32];
    const char *name = fallback;
    snprintf(fallback, sizeof fallback, "mesh-%u", index);
    if (am->mName.data[0])
        name = am->mName.data;
    if (am->mMaterialIndex >= L->scene->mNumMaterials) { /* ValidateDataStructure refuses these; checked anyway */
        tess_error_set(L->err, "%s: mesh '%s': material index %u out of range (%u materials)", L->path, name,
                       am->mMaterialIndex, L->scene->mNumMaterials);
        return -1;
    }
    int material = report_material(L, am->mMaterialIndex);
    if (material < 0)
        return -1;
    mesh *m = convert_mesh(L, am, name);
    if (!m)
        return -1;
    int id = L->sink->mesh(L->sink->ctx, m, material, name); /* m is the sink's now */
    if (id < 0)
        tess_error_set(L->err, "%s: loading stopped: the receiver refused mesh '%s'", L->path, name);
    return L->mesh_ids[index] = id < 0 ? -1 : id;
}

/* ---- the node tree ------------------------------------------------------- */

static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

/* out = parent * local (row-major 3x4 affine; local's fourth row is taken as 0 0 0 1). */
static void compose(const double parent[12], const struct aiMatrix4x4 *l, double out[12])
{
    const double m[12] = {l->a1, l->a2, l->a3, l->a4, l->b1, l->b2, l->b3, l->b4, l->c1, l->c2, l->c3, l->c4};
    for (int r = 0; r < 3; r++) {
        const double *p = parent + 4 * r;
        for (int c = 0; c < 4; c++)
            out[4 * r + c] = p[0] * m[c] + p[1] * m[4 + c] + p[2] * m[8 + c] + (c == 3 ? p[3] : 0.0);
    }
}

/* The name node gets, before uniquifying: sanitized, cut, or made up. */
static void part_name(const loader *L, const struct aiNode *node, size_t depth, char out[NAME_MAX_BYTES])
{
    size_t n = strnlen(node->mName.data, NAME_MAX_BYTES - 1);
    memcpy(out, node->mName.data, n);
    out[n] = '\0';
    for (char *c = out; *c; c++)
        if (*c == '/')
            *c = '_';
    if (n == 0)
        snprintf(out, NAME_MAX_BYTES, "node-%ld", (long)part_tree_count(L->names) - 1);
    else if (L->obj && depth == 0 && strcmp(out, OBJ_DEFAULT_GROUP) == 0 && L->stem[0])
        snprintf(out, NAME_MAX_BYTES, "%s", L->stem);
}

static bool push_children(loader *L, const struct aiNode *node, size_t depth)
{
    if (!grow((void **)&L->todo, &L->todo_cap, L->todo_count + node->mNumChildren, sizeof *L->todo))
        return out_of_memory(L, "the node stack");
    for (unsigned i = node->mNumChildren; i-- > 0;) /* reversed: the first child is walked first */
        L->todo[L->todo_count++] = (pending){node->mChildren[i], depth};
    return true;
}

/* Report the part of one node and its instances; push its children. */
static bool walk_node(loader *L, const pending *at)
{
    const struct aiNode *node = at->node;
    if (!grow((void **)&L->ancestors, &L->ancestor_cap, at->depth + 1, sizeof *L->ancestors))
        return out_of_memory(L, "the node stack");
    ancestor *self = &L->ancestors[at->depth];
    const ancestor *parent = at->depth ? &L->ancestors[at->depth - 1] : NULL;
    compose(parent ? parent->world : L->top_world, &node->mTransformation, self->world);
    char name[NAME_MAX_BYTES];
    part_name(L, node, at->depth, name);
    for (int k = 0; k < 12; k++)
        if (!isfinite(self->world[k]))
            return tess_error_set(L->err, "%s: node '%s': its transform to world is not finite", L->path, name);
    tess_error why = {{0}};
    self->name_id = part_tree_add_unique(L->names, parent ? parent->name_id : PART_ROOT, name, &why);
    if (self->name_id == PART_NONE)
        return tess_error_set(L->err, "%s: node '%s': %s", L->path, name, why.msg);
    const char *unique = part_tree_name(L->names, self->name_id);
    self->sink_part = L->sink->part(L->sink->ctx, parent ? parent->sink_part : -1, unique);
    if (self->sink_part < 0)
        return tess_error_set(L->err, "%s: loading stopped: the receiver refused part '%s'", L->path, unique);
    float to_world[12];
    for (int k = 0; k < 12; k++)
        to_world[k] = (float)self->world[k];
    for (unsigned i = 0; i < node->mNumMeshes; i++) {
        unsigned index = node->mMeshes[i];
        if (index >= L->scene->mNumMeshes) /* ValidateDataStructure refuses these; checked anyway */
            return tess_error_set(L->err, "%s: node '%s': mesh index %u out of range (%u meshes)", L->path, name,
                                  index, L->scene->mNumMeshes);
        int id = report_mesh(L, index);
        if (id == MESH_SKIPPED)
            continue;
        if (id < 0)
            return false;
        if (L->sink->instance(L->sink->ctx, self->sink_part, id, to_world) < 0)
            return tess_error_set(L->err, "%s: loading stopped: the receiver refused an instance of part '%s'",
                                  L->path, unique);
    }
    return push_children(L, node, at->depth + 1);
}

/* Is the root node only what holds the file together (assembly_load.h)? */
static bool root_is_container(const loader *L, const struct aiNode *root)
{
    const char *n = root->mName.data;
    return root->mNumMeshes == 0 && (n[0] == '\0' || strcmp(n, "ROOT") == 0 || strcmp(n, "RootNode") == 0 ||
                                     strcmp(n, L->file_name) == 0);
}

static bool walk(loader *L)
{
    const struct aiNode *root = L->scene->mRootNode;
    if (!root)
        return tess_error_set(L->err, "%s: no node tree", L->path);
    if (root_is_container(L, root)) { /* its children are the top-level parts, placed by its transform */
        compose(identity, &root->mTransformation, L->top_world);
        if (!push_children(L, root, 0))
            return false;
    } else {
        memcpy(L->top_world, identity, sizeof identity);
        if (!grow((void **)&L->todo, &L->todo_cap, 1, sizeof *L->todo))
            return out_of_memory(L, "the node stack");
        L->todo[L->todo_count++] = (pending){root, 0};
    }
    while (L->todo_count > 0) {
        pending at = L->todo[--L->todo_count];
        if (!walk_node(L, &at))
            return false;
    }
    return true;
}

static void name_file(loader *L, const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    snprintf(L->file_name, sizeof L->file_name, "%s", base);
    snprintf(L->stem, sizeof L->stem, "%s", base);
    char *dot = strrchr(L->stem, '.');
    if (dot && dot != L->stem)
        *dot = '\0';
    L->obj = path_has_extension(path, ".obj");
}

bool assembly_load(const char *path, const assembly_sink *sink, tess_error *err)
{
    loader L = {.path = path, .sink = sink, .err = err};
    name_file(&L, path);
    bool ok = false;
    L.scene = assimp_import_file(path, 0, err);
    if (!L.scene)
        return false;
    unsigned meshes = L.scene->mNumMeshes, materials = L.scene->mNumMaterials;
    L.mesh_ids = malloc((meshes ? meshes : 1) * sizeof *L.mesh_ids);
    L.material_ids = malloc((materials ? materials : 1) * sizeof *L.material_ids);
    L.names = part_tree_create();
    if (!L.mesh_ids || !L.material_ids || !L.names) {
        out_of_memory(&L, "the mesh tables");
        goto done;
    }
    for (unsigned i = 0; i < meshes; i++)
        L.mesh_ids[i] = MESH_UNSEEN;
    for (unsigned i = 0; i < materials; i++)
        L.material_ids[i] = MESH_UNSEEN;
    ok = walk(&L);
done:
    free(L.todo);
    free(L.ancestors);
    part_tree_destroy(L.names);
    free(L.mesh_ids);
    free(L.material_ids);
    assimp_release(L.scene);
    return ok;
}
