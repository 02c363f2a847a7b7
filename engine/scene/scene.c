/* scene.c - the scene container: growth of its arrays, bounds, defaults.
 * scene_create_default lives in scene_default.c, the part queries in
 * scene_parts.c; loading a scene from files is engine/load/ (scene_load.h). */
#include "scene.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/geometry/triangles/mesh_tree.h"
#include "engine/base/parallel.h"
#include "part_tree.h"

/* First capacity of a growing array; it doubles from there. Small because most
 * scenes hold a handful of materials, lights and meshes. */
#define SCENE_FIRST_CAPACITY 8u
/* Counts stay below this so every index fits the int that scene_add_* returns. */
#define SCENE_MAX_COUNT ((uint32_t)INT_MAX)

/* Defaults of a fresh scene (linear RGB): a near-black blue-ish background, so
 * silhouettes stay visible against it, and a dim grey ambient light. */
static const vec3 scene_default_background = {0.02f, 0.02f, 0.03f};
static const vec3 scene_default_ambient = {0.1f, 0.1f, 0.1f};

scene *scene_create(void)
{
    scene *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->background = scene_default_background;
    s->ambient = scene_default_ambient;
    s->has_camera = false;
    s->sphere_instance = RAY_INVALID_ID;
    atomic_init(&s->closed, NULL);
    return s;
}

static void sphere_set_finish(sphere_set *ss)
{
    free(ss->center_x);
    free(ss->center_y);
    free(ss->center_z);
    free(ss->radius);
    free(ss->material_id);
    memset(ss, 0, sizeof *ss);
}

void scene_destroy(scene *s)
{
    if (!s)
        return;
    for (uint32_t g = 0; g < s->geometry_count; g++)
        if (s->geometries[g].ops->destroy)
            s->geometries[g].ops->destroy(s->geometries[g].data);
    for (uint32_t m = 0; m < s->medium_count; m++)
        if (s->media[m].ops->destroy)
            s->media[m].ops->destroy(s->media[m].data);
    free(s->media);
    for (uint32_t i = 0; i < s->mesh_count; i++) {
        mesh_tree_release(s->meshes[i]);
        mesh_destroy(s->meshes[i]->mesh);
        free(s->meshes[i]->mesh_material_ids);
        free(s->meshes[i]);
    }
    free(s->meshes);
    free(s->geometries);
    free(s->instances);
    free(s->parted);
    part_tree_destroy(s->parts);
    sphere_set_finish(&s->spheres);
    free(s->materials);
    free(s->lights);
    free(atomic_load_explicit(&s->closed, memory_order_relaxed));
    free(s);
}

/* realloc to `count` items of `item_bytes`, overflow-checked. Returns the new
 * block, or NULL with `array` untouched. */
static void *resize_array(void *array, size_t count, size_t item_bytes)
{
    if (count == 0 || count > SIZE_MAX / item_bytes)
        return NULL;
    return realloc(array, count * item_bytes);
}

/* The capacity to grow to so that at least `needed` items fit: doubling from
 * SCENE_FIRST_CAPACITY, at most SCENE_MAX_COUNT. 0 when `needed` is too large. */
static uint32_t grown_capacity(uint32_t capacity, uint64_t needed)
{
    if (needed > SCENE_MAX_COUNT)
        return 0;
    uint64_t cap = capacity ? capacity : SCENE_FIRST_CAPACITY;
    while (cap < needed)
        cap *= 2;
    return cap > SCENE_MAX_COUNT ? SCENE_MAX_COUNT : (uint32_t)cap;
}

/* Make room for `extra` more materials. */
static bool reserve_materials(scene *s, uint32_t extra)
{
    uint64_t needed = (uint64_t)s->material_count + extra;
    if (needed <= s->material_capacity)
        return true;
    uint32_t cap = grown_capacity(s->material_capacity, needed);
    material *p = cap ? resize_array(s->materials, cap, sizeof *p) : NULL;
    if (!p)
        return false;
    s->materials = p;
    s->material_capacity = cap;
    return true;
}

int scene_add_material(scene *s, const material *m)
{
    if (!reserve_materials(s, 1))
        return -1;
    s->materials[s->material_count] = *m;
    /* the name is always terminated, whatever the caller filled in */
    s->materials[s->material_count].name[SCENE_NAME_BYTES - 1] = '\0';
    return (int)s->material_count++;
}

int scene_add_light(scene *s, const light *l)
{
    if (s->light_count == s->light_capacity) {
        uint32_t cap = grown_capacity(s->light_capacity, (uint64_t)s->light_count + 1);
        light *p = cap ? resize_array(s->lights, cap, sizeof *p) : NULL;
        if (!p)
            return -1;
        s->lights = p;
        s->light_capacity = cap;
    }
    s->lights[s->light_count] = *l;
    return (int)s->light_count++;
}

/* A scene material for a material the mesh file named (OBJ's MTL): Lambert with
 * its diffuse colour, clamped to [0, 1] (NaN becomes 0), everything else as
 * material_default(). */
static material material_from_mesh(const mesh_material *mm)
{
    material m = material_default();
    float rgb[3];
    for (int k = 0; k < 3; k++)
        rgb[k] = fminf(fmaxf(mm->diffuse_rgb[k], 0.f), 1.f);
    m.diffuse = v3(rgb[0], rgb[1], rgb[2]);
    snprintf(m.name, sizeof m.name, "%.*s", (int)(sizeof m.name - 1), mm->name);
    return m;
}

/* Append one scene material per mesh material; ids[i] receives the scene id of
 * mesh material i. All or nothing: false leaves the scene unchanged. */
static bool add_mesh_materials(scene *s, const mesh *m, uint32_t *ids)
{
    if (!reserve_materials(s, m->material_count))
        return false;
    for (uint32_t i = 0; i < m->material_count; i++) {
        ids[i] = s->material_count;
        s->materials[s->material_count++] = material_from_mesh(&m->materials[i]);
    }
    return true;
}

/* Make room for one more element of a growing array. */
static bool reserve_one(void **array, uint32_t count, uint32_t *capacity, size_t item_bytes)
{
    if (count < *capacity)
        return true;
    uint32_t cap = grown_capacity(*capacity, (uint64_t)count + 1);
    void *p = cap ? resize_array(*array, cap, item_bytes) : NULL;
    if (!p)
        return false;
    *array = p;
    *capacity = cap;
    return true;
}

int scene_add_geometry(scene *s, const geometry_ops *ops, void *data, const char *name)
{
    bool ops_ok = ops && ops->prim_count && ops->prim_bounds && ops->intersect && ops->describe &&
                  (ops->leaf == GEOMETRY_LEAF_PRIMS || (ops->leaf == GEOMETRY_LEAF_SPHERES && ops->fill_lane) ||
                   (ops->leaf == GEOMETRY_LEAF_MESH && ops->tree) ||
                   (ops->leaf == GEOMETRY_LEAF_POINTS && ops->points && ops->tree));
    if (!ops_ok || !reserve_one((void **)&s->geometries, s->geometry_count, &s->geometry_capacity,
                                sizeof *s->geometries)) {
        if (ops && ops->destroy)
            ops->destroy(data);
        return -1;
    }
    /* the closed cache has a byte per geometry there was: drop it (no frame
     * renders while the scene changes; the next question makes a new one) */
    free(atomic_exchange_explicit(&s->closed, NULL, memory_order_relaxed));
    scene_geometry *g = &s->geometries[s->geometry_count];
    g->ops = ops;
    g->data = data;
    snprintf(g->name, sizeof g->name, "%.*s", (int)(sizeof g->name - 1), name ? name : "");
    return (int)s->geometry_count++;
}

int scene_add_instance(scene *s, uint32_t geometry, const affine3 *to_world, uint32_t part)
{
    if (geometry >= s->geometry_count)
        return -1;
    scene_instance inst = {.geometry = geometry, .to_world = affine3_identity(), .to_object = affine3_identity(),
                           .identity = true, .part = part, .material = SCENE_NO_MATERIAL, .opacity = 1.f};
    /* instances with parts come in preorder of their parts (scene.h PARTS) */
    if (part != SCENE_NO_PART && s->parted_count > 0 && s->instances[s->parted[s->parted_count - 1]].part > part)
        return -1;
    if (to_world && !affine3_is_identity(to_world)) {
        if (!affine3_invert(to_world, &inst.to_object))
            return -1;
        inst.to_world = *to_world;
        inst.identity = false;
    }
    if (!reserve_one((void **)&s->instances, s->instance_count, &s->instance_capacity, sizeof *s->instances))
        return -1;
    if (part != SCENE_NO_PART) {
        if (!reserve_one((void **)&s->parted, s->parted_count, &s->parted_capacity, sizeof *s->parted))
            return -1;
        s->parted[s->parted_count++] = s->instance_count;
    }
    s->instances[s->instance_count] = inst;
    return (int)s->instance_count++;
}

int scene_add_mesh_geometry(scene *s, mesh *m, uint32_t material_id, const char *name)
{
    uint32_t *ids = NULL;
    scene_mesh *sm = NULL;
    if (!m)
        return -1;
    if (!reserve_one((void **)&s->meshes, s->mesh_count, &s->mesh_capacity, sizeof *s->meshes) ||
        !(sm = calloc(1, sizeof *sm)))
        goto fail;
    bool own_materials = m->material_count > 0 && m->triangle_material != NULL;
    if (own_materials) {
        ids = malloc((size_t)m->material_count * sizeof *ids);
        if (!ids || !add_mesh_materials(s, m, ids))
            goto fail;
    }
    sm->mesh = m;
    sm->material_id = material_id;
    sm->mesh_material_ids = ids;
    snprintf(sm->name, sizeof sm->name, "%.*s", (int)(sizeof sm->name - 1), name ? name : "");
    /* the geometry does not own sm (ops.destroy is NULL): the meshes array does */
    int g = scene_add_geometry(s, &geometry_triangles_ops, sm, sm->name);
    if (g < 0)
        goto fail;
    s->meshes[s->mesh_count++] = sm;
    return g;

fail:
    free(ids);
    free(sm);
    mesh_destroy(m);
    return -1;
}

int scene_add_mesh(scene *s, mesh *m, uint32_t material_id, const char *name)
{
    int g = scene_add_mesh_geometry(s, m, material_id, name);
    if (g < 0)
        return -1;
    if (scene_add_instance(s, (uint32_t)g, NULL, SCENE_NO_PART) < 0) {
        /* undo the geometry: the mesh was taken, so it is freed here */
        scene_mesh *sm = s->meshes[--s->mesh_count];
        s->geometry_count--;
        mesh_tree_release(sm);
        mesh_destroy(sm->mesh);
        free(sm->mesh_material_ids);
        free(sm);
        return -1;
    }
    return (int)s->mesh_count - 1;
}

/* Grow every array of the sphere set to hold at least `needed` spheres. An
 * array that was already resized when a later one fails is merely larger than
 * `capacity`, which is harmless. */
static bool sphere_set_reserve(sphere_set *ss, uint64_t needed)
{
    if (needed <= ss->capacity)
        return true;
    uint32_t cap = grown_capacity(ss->capacity, needed);
    if (cap == 0)
        return false;
    float *cx = resize_array(ss->center_x, cap, sizeof *cx);
    if (!cx)
        return false;
    ss->center_x = cx;
    float *cy = resize_array(ss->center_y, cap, sizeof *cy);
    if (!cy)
        return false;
    ss->center_y = cy;
    float *cz = resize_array(ss->center_z, cap, sizeof *cz);
    if (!cz)
        return false;
    ss->center_z = cz;
    float *r = resize_array(ss->radius, cap, sizeof *r);
    if (!r)
        return false;
    ss->radius = r;
    uint32_t *mid = resize_array(ss->material_id, cap, sizeof *mid);
    if (!mid)
        return false;
    ss->material_id = mid;
    ss->capacity = cap;
    return true;
}

int scene_add_sphere(scene *s, vec3 center, float radius, uint32_t material_id)
{
    sphere_set *ss = &s->spheres;
    if (!sphere_set_reserve(ss, (uint64_t)ss->count + 1))
        return -1;
    if (s->sphere_instance == RAY_INVALID_ID) {
        int g = scene_add_geometry(s, &geometry_spheres_ops, ss, "spheres");
        int inst = g >= 0 ? scene_add_instance(s, (uint32_t)g, NULL, SCENE_NO_PART) : -1;
        if (inst < 0) {
            if (g >= 0)
                s->geometry_count--;
            return -1;
        }
        s->sphere_instance = (uint32_t)inst;
    }
    ss->center_x[ss->count] = center.x;
    ss->center_y[ss->count] = center.y;
    ss->center_z[ss->count] = center.z;
    ss->radius[ss->count] = radius;
    ss->material_id[ss->count] = material_id;
    return (int)ss->count++;
}

/* ---- closed geometries (scene.h CLOSED GEOMETRIES) ------------------------ */

enum { CLOSED_UNKNOWN = 0, CLOSED_NO = 1, CLOSED_YES = 2 };

struct scene_closed_cache {
    uint32_t count;       /* geometries when it was made (scene_add_geometry drops it) */
    atomic_uchar state[]; /* CLOSED_*, relaxed */
};

/* The cache, made on first use; NULL without memory. */
static struct scene_closed_cache *closed_cache(const scene *s)
{
    /* the cache is not the scene's content, so a const scene may fill it
     * (scenes are never defined const: scene_create allocates them) */
    scene *cached = (scene *)s;
    struct scene_closed_cache *c = atomic_load_explicit(&cached->closed, memory_order_acquire);
    if (c)
        return c;
    c = malloc(sizeof *c + s->geometry_count * sizeof c->state[0]);
    if (!c)
        return NULL;
    c->count = s->geometry_count;
    for (uint32_t g = 0; g < c->count; g++)
        atomic_init(&c->state[g], CLOSED_UNKNOWN);
    struct scene_closed_cache *seen = NULL;
    if (atomic_compare_exchange_strong_explicit(&cached->closed, &seen, c, memory_order_acq_rel,
                                                memory_order_acquire))
        return c;
    free(c); /* another thread published one first */
    return seen;
}

bool scene_geometry_closed(const scene *s, uint32_t geometry)
{
    if (geometry >= s->geometry_count)
        return false;
    const scene_geometry *g = &s->geometries[geometry];
    if (!g->ops->closed)
        return false;
    struct scene_closed_cache *c = closed_cache(s);
    if (!c || geometry >= c->count)
        return false;
    unsigned char state = atomic_load_explicit(&c->state[geometry], memory_order_relaxed);
    if (state == CLOSED_UNKNOWN) {
        state = g->ops->closed(g->data) ? CLOSED_YES : CLOSED_NO;
        atomic_store_explicit(&c->state[geometry], state, memory_order_relaxed);
    }
    return state == CLOSED_YES;
}

void scene_forget_closed(scene *s, uint32_t geometry)
{
    struct scene_closed_cache *c = atomic_load_explicit(&s->closed, memory_order_acquire);
    if (c && geometry < c->count)
        atomic_store_explicit(&c->state[geometry], CLOSED_UNKNOWN, memory_order_relaxed);
}

static void prepare_closed_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    const scene *s = ctx;
    for (size_t g = begin; g < end; g++)
        (void)scene_geometry_closed(s, (uint32_t)g);
}

void scene_prepare_closed(const scene *s, int threads)
{
    if (s->geometry_count == 0 || !closed_cache(s))
        return;
    /* one geometry a chunk: their costs differ by orders of magnitude */
    parallel_for(threads, s->geometry_count, 1, prepare_closed_chunk, (void *)s);
}

bool scene_geometry_bounds(const scene *s, uint32_t geometry, aabb *out)
{
    const scene_geometry *g = &s->geometries[geometry];
    if (g->ops->bounds)
        return g->ops->bounds(g->data, out);
    aabb box = aabb_empty();
    uint32_t n = g->ops->prim_count(g->data);
    for (uint32_t i = 0; i < n; i++) {
        aabb b;
        if (g->ops->prim_bounds(g->data, i, &b))
            box = aabb_grow(box, b);
    }
    *out = box;
    return !aabb_is_empty(box);
}

bool scene_instance_bounds(const scene *s, uint32_t instance, aabb *out)
{
    const scene_instance *inst = &s->instances[instance];
    aabb box;
    if (!scene_geometry_bounds(s, inst->geometry, &box))
        return false;
    *out = inst->identity ? box : affine3_box(&inst->to_world, box);
    return true;
}

bool scene_bounds(const scene *s, vec3 *lo, vec3 *hi)
{
    aabb all = aabb_empty();
    for (uint32_t i = 0; i < s->instance_count; i++) {
        aabb b;
        if (scene_instance_bounds(s, i, &b))
            all = aabb_grow(all, b);
    }
    for (uint32_t m = 0; m < s->medium_count; m++) {
        aabb b;
        if (s->media[m].ops->bounds(s->media[m].data, &b))
            all = aabb_grow(all, s->media[m].identity ? b : affine3_box(&s->media[m].to_world, b));
    }
    if (aabb_is_empty(all))
        return false;
    *lo = all.lo;
    *hi = all.hi;
    return true;
}

uint32_t scene_time_steps(const scene *s)
{
    uint32_t most = 1;
    for (uint32_t g = 0; g < s->geometry_count; g++) {
        const geometry_controls *c = geometry_controls_of(s->geometries[g].ops);
        if (c->step_count) {
            uint32_t n = c->step_count(s->geometries[g].data);
            most = n > most ? n : most;
        }
    }
    for (uint32_t m = 0; m < s->medium_count; m++) {
        const geometry_controls *c = medium_controls_of(s->media[m].ops);
        if (c->step_count) {
            uint32_t n = c->step_count(s->media[m].data);
            most = n > most ? n : most;
        }
    }
    return most;
}

bool scene_step_ready(const scene *s, uint32_t step)
{
    bool ready = true;
    /* no early exit: every series not ready is asked to load the step */
    for (uint32_t g = 0; g < s->geometry_count; g++) {
        const geometry_controls *c = geometry_controls_of(s->geometries[g].ops);
        if (c->step_ready)
            ready &= c->step_ready(s->geometries[g].data, step);
    }
    for (uint32_t m = 0; m < s->medium_count; m++) {
        const geometry_controls *c = medium_controls_of(s->media[m].ops);
        if (c->step_ready)
            ready &= c->step_ready(s->media[m].data, step);
    }
    return ready;
}

size_t scene_triangle_count(const scene *s)
{
    size_t total = 0;
    for (uint32_t i = 0; i < s->mesh_count; i++)
        total += mesh_unique_triangles(s->meshes[i]->mesh);
    return total;
}

size_t scene_instanced_triangle_count(const scene *s)
{
    size_t total = 0;
    for (uint32_t i = 0; i < s->instance_count; i++) {
        const scene_geometry *g = scene_instance_geometry(s, i);
        if (g->ops == &geometry_triangles_ops)
            total += mesh_unique_triangles(((const scene_mesh *)g->data)->mesh);
    }
    return total;
}

material material_default(void)
{
    return (material){
        .name = "default",
        .model = MATERIAL_LAMBERT,
        .diffuse = v3(0.7f, 0.7f, 0.7f),
        .specular = v3(0.f, 0.f, 0.f),
        .shininess = 0.f,
        .ambient = 1.f,
    };
}

light light_default_directional(void)
{
    return (light){
        .kind = LIGHT_DIRECTIONAL,
        .direction = v3_normalize(v3(0.4f, 1.f, 0.3f)),
        .position = v3(0.f, 0.f, 0.f),
        .color = v3(1.f, 1.f, 1.f),
        .intensity = 1.f,
        .casts_shadows = true,
    };
}

size_t scene_point_count(const scene *s)
{
    size_t n = 0;
    for (uint32_t g = 0; g < s->geometry_count; g++)
        if (s->geometries[g].ops->leaf == GEOMETRY_LEAF_POINTS)
            n += s->geometries[g].ops->prim_count(s->geometries[g].data);
    return n;
}

size_t scene_point_bytes(const scene *s)
{
    size_t bytes = 0;
    for (uint32_t g = 0; g < s->geometry_count; g++)
        if (s->geometries[g].ops->leaf == GEOMETRY_LEAF_POINTS && s->geometries[g].ops->bytes)
            bytes += s->geometries[g].ops->bytes(s->geometries[g].data);
    return bytes;
}

int scene_add_medium(scene *s, const medium_ops *ops, void *data, const affine3 *to_world, const char *name)
{
    affine3 world = to_world ? *to_world : affine3_identity(), object;
    bool ok = ops && ops->bounds && ops->integrate && affine3_invert(&world, &object) &&
              reserve_one((void **)&s->media, s->medium_count, &s->medium_capacity, sizeof *s->media);
    if (!ok) {
        if (ops && ops->destroy)
            ops->destroy(data);
        return -1;
    }
    scene_medium *m = &s->media[s->medium_count];
    memset(m, 0, sizeof *m);
    m->ops = ops;
    m->data = data;
    m->to_world = world;
    m->to_object = object;
    m->identity = affine3_is_identity(&world);
    snprintf(m->name, sizeof m->name, "%s", name ? name : "");
    return (int)s->medium_count++;
}
