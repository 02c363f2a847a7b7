/* scene_json.c - scene_load_json: JSON scene files, read with json-c.
 *
 * SCENE FILE FORMAT (docs/scene-format.md holds the same reference as Markdown)
 *
 * A scene file is one JSON object. Every field is optional except as noted, a
 * field the format does not name is an error, and so is a key given twice in
 * one object. Comments are allowed: / * ... * / and // to the end of the line.
 * Colours are linear RGB; lengths are in the units of the mesh files (world
 * units); angles are in degrees.
 *
 *   "camera": {                     without it the renderer frames the bounds
 *       "eye": [x, y, z],           required: the pinhole
 *       "look_at": [x, y, z],       required: the point at the image centre
 *       "up": [x, y, z],            default [0, 1, 0]; not parallel to the view
 *       "fov_deg": 40               vertical field of view, in (0, 180); default 40
 *   }
 *   "background": [r, g, b]         colour of rays that hit nothing, each >= 0;
 *                                   default [0.02, 0.02, 0.03]
 *   "ambient": [r, g, b]            ambient light, each >= 0; default [0.1, 0.1, 0.1]
 *   "materials": {                  name -> material, names 1..63 bytes
 *       "NAME": {
 *           "model": "lambert" | "phong",   default "lambert"
 *           "diffuse": [r, g, b],   reflectance, each in [0, 1]; default 0.7 grey
 *           "specular": [r, g, b],  Phong lobe colour, each >= 0; default [0, 0, 0]
 *           "shininess": 32,        Phong exponent, >= 0; default 0
 *           "ambient": 1.0          fraction of diffuse under ambient light, [0, 1]; default 1
 *       }, ...
 *   }
 *   "lights": [                     absent: one default directional light
 *       {"type": "directional",     required: "directional" or "point"
 *        "direction": [x, y, z],    directional only, required: towards the light, not zero
 *        "position": [x, y, z],     point only, required
 *        "color": [r, g, b],        each >= 0; default [1, 1, 1]
 *        "intensity": 1,            >= 0; default 1 (point lights fall off as 1/d^2)
 *        "shadows": true},          default true
 *       ...                         [] means no lights at all (ambient only)
 *   ]
 *   "meshes": [
 *       {"file": "mesh.ply",        required: any file mesh_load() reads; a relative
 *                                   path is relative to the scene file's directory
 *        "material": "NAME",        a name from "materials"; without it the mesh's own
 *                                   file materials (OBJ+MTL) are used, else the default
 *                                   material; with it, file materials are ignored
 *        "transform": {             object -> world: p' = T * Rz * Ry * Rx * S * p
 *            "translate": [x, y, z],    default [0, 0, 0]
 *            "rotate_deg": [x, y, z],   about X, then Y, then Z (right-handed); default 0
 *            "scale": s | [sx, sy, sz]  no component 0; default 1
 *        },
 *        "matrix": [12 numbers],    instead of "transform": row-major 3x4 [R|t],
 *                                   p' = R p + t; R must not be singular
 *        "optional": false},        true: a file that does not exist is skipped with a
 *                                   warning (a file that exists but fails to load is
 *                                   still an error)
 *   ]
 *   "spheres": [
 *       {"center": [x, y, z],       required
 *        "radius": r,               required, > 0
 *        "material": "NAME"}        default: the default material
 *   ]
 *
 *   "particles": [                  docs/scene-format.md "Particles" (particles/particle_json.c)
 *       {"file": "atoms.dump", "radius": 0.5 | "ATTRIBUTE", "crop": {...},
 *        "material", "transform" | "matrix", "optional": as for meshes}
 *   ]
 *
 * The default material is material_default() (grey Lambert), or the file's own
 * material if "materials" names one "default". A scene must end up with at
 * least one thing to hit (a triangle, sphere or particle). Numbers must be
 * finite (json-c would otherwise
 * accept NaN and Infinity) and fit a float.
 *
 * Errors are one line: "PATH: cannot open: REASON", "PATH:LINE:COL: JSON syntax
 * error: DESC" (column in bytes), "PATH:LINE:COL: duplicate key 'K' in a JSON
 * object", "PATH: field 'lights[1].color': PROBLEM", or "PATH: scene has no
 * geometry".
 *
 * The file, its syntax, duplicate keys and the typed field reads are
 * engine/json_read.[ch] (shared with camera paths); its header has the json-c
 * notes: the non-strict mode needed for comments also tolerates single-quoted
 * strings, trailing commas and any-case true/false/null, which are not part of
 * the format. */
#include "engine/scene/scene.h"
#include "scene_load.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "engine/base/json_read.h"
#include "engine/geometry/triangles/mesh_cache.h"
#include "engine/base/log.h"
#include "particle_json.h"
#include "engine/base/series.h"
#include "volume_json.h"
#include "mesh_load.h"
#include "particle_load.h"
#include "volume_read.h"

/* Scene files describe; the geometry lives in mesh files. Refusing anything
 * larger keeps a mistaken path (a mesh, /dev/zero) from eating memory. */
#define SCENE_JSON_MAX_BYTES (16u << 20)
/* Resolved mesh file paths. */
#define MESH_PATH_BYTES 4096

/* ---- building the scene ------------------------------------------------ */

typedef struct loader {
    jr_ctx ctx;
    scene *s;                 /* being built; owned by scene_load_json until returned */
    size_t dir_len;           /* bytes of ctx.path up to and including its last '/', 0 if none */
    uint32_t named_materials; /* scene materials 0..n-1 are the file's "materials", in file order */
    int default_material;     /* scene id of the fallback material, -1 until something needs it */
    scene_load_options opts;  /* the caller's defaults */
} loader;

static bool out_of_memory(loader *L)
{
    return tess_error_set(L->ctx.err, "%s: out of memory building the scene", L->ctx.path);
}

/* Id of the material named `name` in the file's "materials", or -1. */
static int find_material(const loader *L, const char *name)
{
    for (uint32_t i = 0; i < L->named_materials; i++)
        if (strcmp(L->s->materials[i].name, name) == 0)
            return (int)i;
    return -1;
}

/* The material for geometry without a "material": the file's "default" if it
 * defines one, else material_default(), added on first use. -1 on OOM. */
static int default_material_id(loader *L)
{
    if (L->default_material < 0)
        L->default_material = find_material(L, "default");
    if (L->default_material < 0) {
        material m = material_default();
        L->default_material = scene_add_material(L->s, &m);
    }
    return L->default_material;
}

/* Report member "material" naming `name`, which "materials" does not define. */
static bool unknown_material(jr_ctx *c, const char *name)
{
    char reason[160];
    snprintf(reason, sizeof reason, "unknown material '%.64s' (not defined under 'materials')", name);
    return jr_member_fail(c, "material", reason);
}

/* The material id for member "material" of `obj` (absent: the default). */
static bool material_ref(loader *L, json_object *obj, uint32_t *id)
{
    const char *name = NULL;
    if (!jr_opt_string(&L->ctx, obj, "material", &name))
        return false;
    int found = name ? find_material(L, name) : default_material_id(L);
    if (found >= 0) {
        *id = (uint32_t)found;
        return true;
    }
    return name ? unknown_material(&L->ctx, name) : out_of_memory(L);
}

static bool load_material(jr_ctx *c, json_object *v, const char *name, material *m)
{
    static const char *const fields[] = {"model", "diffuse", "specular", "shininess", "ambient", NULL};
    static const char *const models[] = {"lambert", "phong", NULL}; /* in material_model order */
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields))
        return false;
    *m = material_default();
    snprintf(m->name, sizeof m->name, "%s", name);
    int model = (int)m->model;
    if (!jr_opt_choice(c, v, "model", models, &model))
        return false;
    m->model = (material_model)model;
    return jr_opt_vec3(c, v, "diffuse", jr_range_unit, &m->diffuse) &&
           jr_opt_vec3(c, v, "specular", jr_range_nonneg, &m->specular) &&
           jr_opt_number(c, v, "shininess", jr_range_nonneg, &m->shininess) &&
           jr_opt_number(c, v, "ambient", jr_range_unit, &m->ambient);
}

static bool load_materials(loader *L, json_object *root)
{
    jr_ctx *c = &L->ctx;
    json_object *all;
    if (!jr_get_member(root, "materials", &all))
        return true;
    size_t outer = jr_field_key(c, "materials");
    if (!jr_expect_object(c, all)) {
        jr_field_leave(c, outer);
        return false;
    }
    bool ok = true;
    struct json_object_iterator it = json_object_iter_begin(all), end = json_object_iter_end(all);
    for (; ok && !json_object_iter_equal(&it, &end); json_object_iter_next(&it)) {
        const char *name = json_object_iter_peek_name(&it);
        size_t saved = jr_field_key(c, name);
        material m;
        if (strlen(name) == 0 || strlen(name) >= SCENE_NAME_BYTES)
            ok = jr_field_fail(c, "a material name must be 1 to %d bytes long", SCENE_NAME_BYTES - 1);
        else if (load_material(c, json_object_iter_peek_value(&it), name, &m))
            ok = scene_add_material(L->s, &m) >= 0 || out_of_memory(L);
        else
            ok = false;
        jr_field_leave(c, saved);
    }
    jr_field_leave(c, outer);
    L->named_materials = L->s->material_count;
    return ok;
}

/* A direction normalised in double precision, so tiny vectors survive; false
 * for the zero vector. */
static bool unit_direction(vec3 d, vec3 *out)
{
    double x = d.x, y = d.y, z = d.z, len = sqrt(x * x + y * y + z * z);
    if (!(len > 0.0))
        return false;
    *out = v3((float)(x / len), (float)(y / len), (float)(z / len));
    return true;
}

static bool load_light(jr_ctx *c, json_object *v, light *l)
{
    static const char *const fields[] = {"type", "direction", "position", "color", "intensity", "shadows", NULL};
    static const char *const types[] = {"directional", "point", NULL}; /* in light_kind order */
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields) || !jr_require_member(c, v, "type"))
        return false;
    *l = light_default_directional();
    int kind = 0;
    if (!jr_opt_choice(c, v, "type", types, &kind))
        return false;
    l->kind = (light_kind)kind;
    const char *needed = l->kind == LIGHT_DIRECTIONAL ? "direction" : "position";
    const char *unused = l->kind == LIGHT_DIRECTIONAL ? "position" : "direction";
    json_object *ignored;
    if (jr_get_member(v, unused, &ignored))
        return jr_member_fail(c, unused,
                              l->kind == LIGHT_DIRECTIONAL ? "only point lights have a position"
                                                           : "only directional lights have a direction");
    if (!jr_require_member(c, v, needed))
        return false;
    if (l->kind == LIGHT_DIRECTIONAL) {
        vec3 d;
        if (!jr_opt_vec3(c, v, "direction", jr_range_float, &d))
            return false;
        if (!unit_direction(d, &l->direction))
            return jr_member_fail(c, "direction", "must not be the zero vector");
    } else if (!jr_opt_vec3(c, v, "position", jr_range_float, &l->position)) {
        return false;
    }
    return jr_opt_vec3(c, v, "color", jr_range_nonneg, &l->color) &&
           jr_opt_number(c, v, "intensity", jr_range_nonneg, &l->intensity) &&
           jr_opt_bool(c, v, "shadows", &l->casts_shadows);
}

static bool load_lights(loader *L, json_object *root)
{
    jr_ctx *c = &L->ctx;
    json_object *all;
    if (!jr_get_member(root, "lights", &all)) {
        light l = light_default_directional();
        return scene_add_light(L->s, &l) >= 0 || out_of_memory(L);
    }
    size_t outer = jr_field_key(c, "lights");
    bool ok = jr_expect_array(c, all);
    size_t n = ok ? json_object_array_length(all) : 0;
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = jr_field_index(c, i);
        light l;
        ok = load_light(c, json_object_array_get_idx(all, i), &l) &&
             (scene_add_light(L->s, &l) >= 0 || out_of_memory(L));
        jr_field_leave(c, saved);
    }
    jr_field_leave(c, outer);
    return ok;
}

static bool load_camera(loader *L, json_object *root)
{
    static const char *const fields[] = {"eye", "look_at", "up", "fov_deg", NULL};
    jr_ctx *c = &L->ctx;
    json_object *v;
    if (!jr_get_member(root, "camera", &v))
        return true;
    size_t outer = jr_field_key(c, "camera");
    camera_desc cam;
    bool ok = jr_expect_object(c, v) && jr_check_fields(c, v, fields) && jr_camera_members(c, v, &cam);
    jr_field_leave(c, outer);
    if (ok) {
        L->s->camera = cam;
        L->s->has_camera = true;
    }
    return ok;
}

static const float identity_xform[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

/* sin and cos of an angle in degrees, exact for multiples of 90 degrees so that
 * axis-aligned rotations do not smear 1e-17 into other axes. */
static void sin_cos_deg(double deg, double *s, double *co)
{
    static const double quarter_sin[4] = {0, 1, 0, -1};
    double turns = fmod(deg, 360.0);
    if (turns < 0)
        turns += 360.0;
    if (fmod(turns, 90.0) == 0.0) {
        int q = (int)(turns / 90.0) % 4;
        *s = quarter_sin[q];
        *co = quarter_sin[(q + 1) % 4];
        return;
    }
    double rad = deg * (3.14159265358979323846 / 180.0);
    *s = sin(rad);
    *co = cos(rad);
}

/* 3x3 product a * b, row-major. */
static void mat3_mul(const double a[9], const double b[9], double out[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

/* xform = T * Rz * Ry * Rx * S, row-major 3x4. */
static void compose_transform(vec3 translate, vec3 rotate_deg, vec3 scale, float xform[12])
{
    double sx, cx, sy, cy, sz, cz;
    sin_cos_deg(rotate_deg.x, &sx, &cx);
    sin_cos_deg(rotate_deg.y, &sy, &cy);
    sin_cos_deg(rotate_deg.z, &sz, &cz);
    const double rx[9] = {1, 0, 0, 0, cx, -sx, 0, sx, cx};
    const double ry[9] = {cy, 0, sy, 0, 1, 0, -sy, 0, cy};
    const double rz[9] = {cz, -sz, 0, sz, cz, 0, 0, 0, 1};
    double zy[9], r[9];
    mat3_mul(rz, ry, zy);
    mat3_mul(zy, rx, r);
    const double s[3] = {scale.x, scale.y, scale.z}, t[3] = {translate.x, translate.y, translate.z};
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++)
            xform[4 * i + j] = (float)(r[3 * i + j] * s[j]);
        xform[4 * i + 3] = (float)t[i];
    }
}

/* "scale": one number for all axes or three; none of them 0. */
static bool read_scale(jr_ctx *c, json_object *t, vec3 *scale)
{
    json_object *v;
    if (!jr_get_member(t, "scale", &v))
        return true;
    size_t saved = jr_field_key(c, "scale");
    bool ok;
    if (jr_is_number(v)) {
        float k = 1.f;
        ok = jr_number(c, v, jr_range_float, &k);
        *scale = v3(k, k, k);
    } else if (json_object_is_type(v, json_type_array)) {
        ok = jr_vec3(c, v, jr_range_float, scale);
    } else {
        ok = jr_field_fail(c, "expected a number or an array of 3 numbers, got %s", jr_kind(v));
    }
    if (ok && (scale->x == 0.f || scale->y == 0.f || scale->z == 0.f))
        ok = jr_field_fail(c, "must not be zero (on any axis)");
    jr_field_leave(c, saved);
    return ok;
}

static bool read_transform(jr_ctx *c, json_object *t, float xform[12])
{
    static const char *const fields[] = {"translate", "rotate_deg", "scale", NULL};
    vec3 translate = v3(0.f, 0.f, 0.f), rotate = v3(0.f, 0.f, 0.f), scale = v3(1.f, 1.f, 1.f);
    if (!jr_expect_object(c, t) || !jr_check_fields(c, t, fields) ||
        !jr_opt_vec3(c, t, "translate", jr_range_float, &translate) ||
        !jr_opt_vec3(c, t, "rotate_deg", jr_range_float, &rotate) || !read_scale(c, t, &scale))
        return false;
    compose_transform(translate, rotate, scale, xform);
    return true;
}

static bool read_matrix(jr_ctx *c, json_object *v, float xform[12])
{
    if (!jr_numbers(c, v, 12, jr_range_float, xform))
        return false;
    const float *m = xform;
    double det = (double)m[0] * ((double)m[5] * m[10] - (double)m[6] * m[9]) -
                 (double)m[1] * ((double)m[4] * m[10] - (double)m[6] * m[8]) +
                 (double)m[2] * ((double)m[4] * m[9] - (double)m[5] * m[8]);
    return det != 0.0 || jr_field_fail(c, "the 3x3 part is singular (determinant 0)");
}

/* Object -> world transform of mesh entry `v`: "transform", "matrix" or identity. */
static bool mesh_xform(jr_ctx *c, json_object *v, float xform[12])
{
    json_object *t, *m;
    bool has_t = jr_get_member(v, "transform", &t), has_m = jr_get_member(v, "matrix", &m);
    memcpy(xform, identity_xform, sizeof identity_xform);
    if (has_t && has_m)
        return jr_field_fail(c, "give either 'transform' or 'matrix', not both");
    const char *key = has_t ? "transform" : "matrix";
    if (!has_t && !has_m)
        return true;
    size_t saved = jr_field_key(c, key);
    bool ok = has_t ? read_transform(c, t, xform) : read_matrix(c, m, xform);
    jr_field_leave(c, saved);
    return ok;
}

/* Each element of the array member `key` of `obj` (absent: nothing) through
 * `one`, with the field path following ("key[i]"). */
static bool load_each(loader *L, json_object *obj, const char *key, bool (*one)(loader *L, json_object *v))
{
    jr_ctx *c = &L->ctx;
    json_object *all;
    if (!jr_get_member(obj, key, &all))
        return true;
    size_t outer = jr_field_key(c, key);
    bool ok = jr_expect_array(c, all);
    size_t n = ok ? json_object_array_length(all) : 0;
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = jr_field_index(c, i);
        ok = one(L, json_object_array_get_idx(all, i));
        jr_field_leave(c, saved);
    }
    jr_field_leave(c, outer);
    return ok;
}

/* `file` relative to the scene file's directory (absolute paths as they are). */
static bool resolve_path(loader *L, const char *file, char *out, size_t out_bytes)
{
    size_t dir_len = file[0] == '/' ? 0 : L->dir_len;
    int n = snprintf(out, out_bytes, "%.*s%s", (int)dir_len, L->ctx.path, file);
    return (n >= 0 && (size_t)n < out_bytes) || jr_member_fail(&L->ctx, "file", "path too long");
}

/* Forget the mesh file's own materials (the scene file chose one for it). */
static void drop_mesh_materials(mesh *m)
{
    free(m->triangle_material);
    free(m->materials);
    m->triangle_material = NULL;
    m->materials = NULL;
    m->material_count = 0;
}

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* What every entry placed from a file reads (its fields already checked):
 * `key` ("file", or "files" for a pattern) resolved against the scene's
 * directory into resolved, "optional", and the placement ("transform" or
 * "matrix") into xform. */
static bool entry_path(loader *L, json_object *v, const char *key, char resolved[MESH_PATH_BYTES], float xform[12],
                       bool *optional)
{
    const char *file = NULL;
    *optional = false;
    return jr_opt_string(&L->ctx, v, key, &file) && jr_opt_bool(&L->ctx, v, "optional", optional) &&
           mesh_xform(&L->ctx, v, xform) && resolve_path(L, file, resolved, MESH_PATH_BYTES);
}

/* An optional entry whose file does not exist: said with a warning; the
 * caller skips the entry. */
static bool skip_missing(const loader *L, const char *resolved, bool optional)
{
    struct stat st;
    if (!optional || stat(resolved, &st) == 0 || (errno != ENOENT && errno != ENOTDIR))
        return false;
    log_warn("%s: field '%s.file': %s does not exist; skipped (optional)", L->ctx.path, L->ctx.field, resolved);
    return true;
}

static bool load_mesh(loader *L, json_object *v)
{
    static const char *const fields[] = {"file", "material", "transform", "matrix", "optional", "spatial_splits", NULL};
    jr_ctx *c = &L->ctx;
    const char *material_name = NULL;
    bool optional, spatial_splits = L->opts.spatial_splits;
    float xform[12];
    char resolved[MESH_PATH_BYTES];
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields) || !jr_require_member(c, v, "file") ||
        !jr_opt_string(c, v, "material", &material_name) || !jr_opt_bool(c, v, "spatial_splits", &spatial_splits) ||
        !entry_path(L, v, "file", resolved, xform, &optional))
        return false;
    int named = material_name ? find_material(L, material_name) : -1;
    if (material_name && named < 0)
        return unknown_material(c, material_name);
    if (skip_missing(L, resolved, optional))
        return true;
    tess_error why = {{0}};
    mesh_cache_params params;
    memset(&params, 0, sizeof params);
    memcpy(params.xform, xform, sizeof params.xform);
    params.drop_materials = named >= 0;
    params.spatial_splits = spatial_splits;
    mesh_cache_load cached;
    mesh *m = mesh_cache_load_file(resolved, &params, mesh_load, &cached, &why);
    if (!m)
        return jr_member_fail(c, "file", why.msg[0] ? why.msg : "cannot load the mesh");
    if (cached.state != MESH_CACHE_HIT) { /* a mapped mesh has them applied */
        if (named >= 0)
            drop_mesh_materials(m);
        if (memcmp(xform, identity_xform, sizeof identity_xform) != 0)
            mesh_transform(m, xform);
    }
    bool own_materials = m->material_count > 0 && m->triangle_material != NULL;
    int material_id = named >= 0 ? named : own_materials ? 0 : default_material_id(L);
    if (material_id < 0) {
        mesh_cache_abandon(&cached);
        mesh_destroy(m);
        return out_of_memory(L);
    }
    int id = scene_add_mesh(L->s, m, (uint32_t)material_id, base_name(resolved));
    if (id < 0) {
        mesh_cache_abandon(&cached);
        return out_of_memory(L);
    }
    scene_mesh *sm = L->s->meshes[id];
    sm->spatial_splits = spatial_splits;
    mesh_cache_adopt(sm, &cached);
    if (sm->mesh_material_ids) /* keep material_id a valid index even where it is unused */
        sm->material_id = sm->mesh_material_ids[0];
    return true;
}


/* One entry of an assembly's "colours": the parts matching `parts` (and
 * their subtrees) get a material, named or made from a diffuse colour. */
static bool load_part_colour(loader *L, json_object *v)
{
    static const char *const fields[] = {"parts", "material", "diffuse", NULL};
    jr_ctx *c = &L->ctx;
    const char *pattern = NULL;
    uint32_t material_id = 0;
    bool has_material = jr_get_member(v, "material", &(json_object *){NULL}),
         has_diffuse = jr_get_member(v, "diffuse", &(json_object *){NULL});
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields) || !jr_require_member(c, v, "parts") ||
        !jr_opt_string(c, v, "parts", &pattern))
        return false;
    if (has_material == has_diffuse)
        return jr_field_fail(c, "give either 'material' or 'diffuse'");
    if (has_material) {
        if (!material_ref(L, v, &material_id))
            return false;
    } else {
        material m = material_default();
        if (!jr_opt_vec3(c, v, "diffuse", jr_range_unit, &m.diffuse))
            return false;
        snprintf(m.name, sizeof m.name, "parts %.*s", (int)(sizeof m.name - 7), pattern);
        int id = scene_add_material(L->s, &m);
        if (id < 0)
            return out_of_memory(L);
        material_id = (uint32_t)id;
    }
    long matched = scene_colour_parts(L->s, pattern, material_id);
    if (matched < 0)
        return out_of_memory(L);
    if (matched == 0)
        log_warn("%s: field '%s.parts': no part matches '%s'", c->path, c->field, pattern);
    return true;
}

static bool load_assembly(loader *L, json_object *v)
{
    static const char *const fields[] = {"file", "transform", "matrix", "optional", "colours", NULL};
    jr_ctx *c = &L->ctx;
    bool optional;
    float xform[12];
    char resolved[MESH_PATH_BYTES];
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields) || !jr_require_member(c, v, "file") ||
        !entry_path(L, v, "file", resolved, xform, &optional))
        return false;
    if (skip_missing(L, resolved, optional))
        return true;
    affine3 placement;
    memcpy(placement.m, xform, sizeof placement.m);
    tess_error why = {{0}};
    if (!scene_load_assembly(L->s, resolved, affine3_is_identity(&placement) ? NULL : &placement, &why))
        return jr_member_fail(c, "file", why.msg[0] ? why.msg : "cannot load the assembly");
    return load_each(L, v, "colours", load_part_colour);
}


static bool load_sphere(loader *L, json_object *v)
{
    static const char *const fields[] = {"center", "radius", "material", NULL};
    jr_ctx *c = &L->ctx;
    vec3 center = v3(0.f, 0.f, 0.f);
    float radius = 0.f;
    uint32_t material_id = 0;
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields) || !jr_require_member(c, v, "center") ||
        !jr_require_member(c, v, "radius") || !jr_opt_vec3(c, v, "center", jr_range_float, &center) ||
        !jr_opt_number(c, v, "radius", jr_range_positive, &radius) || !material_ref(L, v, &material_id))
        return false;
    return scene_add_sphere(L->s, center, radius, material_id) >= 0 || out_of_memory(L);
}


/* What an entry that may be a time series gives (its fields already
 * checked): "file" or "files" (exactly one), resolved, with its placement;
 * a series' files in `steps`; `first` the file to load now. */
typedef struct series_entry {
    const char *key; /* "file" or "files" */
    char resolved[MESH_PATH_BYTES];
    float xform[12];
    bool optional;
    series_paths steps; /* files only; freed by the caller (series_paths_free) */
    const char *first;
} series_entry;

/* Read a series entry; false on an error (reported), true with *skip when
 * an optional entry's file (or every file of its pattern) is missing. */
static bool read_series_entry(loader *L, json_object *v, series_entry *e, bool *skip)
{
    jr_ctx *c = &L->ctx;
    json_object *ignored;
    bool has_file = jr_get_member(v, "file", &ignored), files = jr_get_member(v, "files", &ignored);
    *skip = false;
    memset(&e->steps, 0, sizeof e->steps);
    if (has_file == files)
        return jr_field_fail(c, "give either 'file' or 'files' (a time series)");
    e->key = files ? "files" : "file";
    if (!entry_path(L, v, e->key, e->resolved, e->xform, &e->optional))
        return false;
    e->first = e->resolved;
    if (!files) {
        *skip = skip_missing(L, e->resolved, e->optional);
        return true;
    }
    tess_error why = {{0}};
    if (!series_paths_glob(e->resolved, &e->steps, &why)) {
        if (e->optional && !e->steps.failed) {
            log_warn("%s: field '%s.files': no file matches %s; skipped (optional)", c->path, c->field, e->resolved);
            *skip = true;
            return true;
        }
        return jr_member_fail(c, "files", why.msg);
    }
    e->first = e->steps.paths[0];
    return true;
}

/* A "particles" entry: the file and where it goes here, the rest in
 * particles/particle_json.c. */
static bool load_particles(loader *L, json_object *v)
{
    jr_ctx *c = &L->ctx;
    uint32_t material_id = 0;
    series_entry e;
    bool skip;
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, particle_json_fields) || !material_ref(L, v, &material_id) ||
        !read_series_entry(L, v, &e, &skip))
        return false;
    if (skip)
        return true;
    tess_error why = {{0}};
    particle_set *set = particles_load(e.first, &why);
    if (!set) {
        series_paths_free(&e.steps);
        return jr_member_fail(c, e.key, why.msg[0] ? why.msg : "cannot load the particles");
    }
    particle_kind *k = particle_json_kind(c, v, set, material_id);
    if (k && e.steps.count > 0 &&
        !particle_kind_attach_series(k, (const char *const *)e.steps.paths, e.steps.count, particles_load, &why)) {
        particle_kind_destroy(k);
        k = NULL;
        jr_member_fail(c, e.key, why.msg);
    }
    series_paths_free(&e.steps);
    if (!k)
        return false;
    int g = scene_add_geometry(L->s, &particle_kind_ops, k, base_name(e.resolved));
    if (g < 0)
        return out_of_memory(L);
    affine3 placement;
    memcpy(placement.m, e.xform, sizeof placement.m);
    return scene_add_instance(L->s, (uint32_t)g, affine3_is_identity(&placement) ? NULL : &placement,
                              SCENE_NO_PART) >= 0 ||
           out_of_memory(L);
}

static int material_by_name(void *ctx, const char *name) { return find_material(ctx, name); }

/* A "volumes" entry: the file (or a series' files) and where it goes here,
 * the rest in volume/volume_json.c. */
static bool load_volume(loader *L, json_object *v)
{
    jr_ctx *c = &L->ctx;
    series_entry e;
    bool skip;
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, volume_json_fields) || !read_series_entry(L, v, &e, &skip))
        return false;
    if (skip)
        return true;
    tess_error why = {{0}};
    volume *vol = volume_load(e.first, &why);
    int mat = vol ? default_material_id(L) : -1;
    bool ok;
    if (!vol)
        ok = jr_member_fail(c, e.key, why.msg[0] ? why.msg : "cannot load the volume");
    else if (mat < 0) {
        volume_destroy(vol);
        ok = out_of_memory(L);
    } else {
        affine3 placement;
        memcpy(placement.m, e.xform, sizeof placement.m);
        ok = volume_json_add(c, v, vol, e.steps.count > 0 ? (const char *const *)e.steps.paths : NULL, e.steps.count,
                             affine3_is_identity(&placement) ? NULL : &placement, L->s, (uint32_t)mat,
                             material_by_name, L);
    }
    series_paths_free(&e.steps);
    return ok;
}

/* Whether anything in the scene can be hit. */
static bool scene_has_geometry(const scene *s)
{
    if (s->medium_count > 0)
        return true;
    for (uint32_t i = 0; i < s->instance_count; i++) {
        const scene_geometry *g = scene_instance_geometry(s, i);
        if (g->ops->prim_count(g->data) > 0)
            return true;
    }
    return false;
}

static bool load_scene(loader *L, json_object *root)
{
    static const char *const fields[] = {"camera", "background", "ambient",    "materials", "lights",
                                         "meshes", "spheres",    "assemblies", "particles", "volumes", NULL};
    jr_ctx *c = &L->ctx;
    if (!json_object_is_type(root, json_type_object))
        return tess_error_set(c->err, "%s: expected a JSON object at the top level, got %s", c->path,
                              jr_kind(root));
    if (!jr_check_fields(c, root, fields) || !jr_opt_vec3(c, root, "background", jr_range_nonneg, &L->s->background) ||
        !jr_opt_vec3(c, root, "ambient", jr_range_nonneg, &L->s->ambient) || !load_materials(L, root) ||
        !load_lights(L, root) || !load_camera(L, root) || !load_each(L, root, "meshes", load_mesh) ||
        !load_each(L, root, "spheres", load_sphere) || !load_each(L, root, "assemblies", load_assembly) ||
        !load_each(L, root, "particles", load_particles) || !load_each(L, root, "volumes", load_volume))
        return false;
    if (!scene_has_geometry(L->s))
        return tess_error_set(c->err, "%s: scene has no geometry", c->path);
    return true;
}

scene *scene_load_json(const char *path, tess_error *err) { return scene_load_json_with(path, NULL, err); }

scene *scene_load_json_with(const char *path, const scene_load_options *opts, tess_error *err)
{
    size_t len = 0;
    char *text = jr_read_file(path, SCENE_JSON_MAX_BYTES, "a scene file", &len, err);
    if (!text)
        return NULL;
    scene *s = scene_parse_json_with(path, text, len, opts, err);
    free(text);
    return s;
}

scene *scene_parse_json(const char *path, const char *text, size_t len, tess_error *err)
{
    return scene_parse_json_with(path, text, len, NULL, err);
}

scene *scene_parse_json_with(const char *path, const char *text, size_t len, const scene_load_options *opts,
                             tess_error *err)
{
    json_object *root = NULL;
    bool ok = jr_parse(path, text, len, &root, err);
    loader L = {.ctx = {.path = path, .err = err}, .default_material = -1};
    if (opts)
        L.opts = *opts;
    const char *slash = strrchr(path, '/');
    L.dir_len = slash ? (size_t)(slash - path) + 1 : 0;
    L.s = ok ? scene_create() : NULL;
    if (ok && !L.s)
        ok = tess_error_set(err, "%s: out of memory building the scene", path);
    ok = ok && load_scene(&L, root);
    json_object_put(root);
    if (!ok) {
        scene_destroy(L.s);
        return NULL;
    }
    return L.s;
}
