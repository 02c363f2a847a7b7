#include "accel.h"

#include <stdlib.h>

#include "bvh.h"
#include "intersect.h"
#include "scene.h"

typedef enum geom_kind { GEOM_TRIANGLES, GEOM_SPHERES } geom_kind;

typedef struct geom_accel {
    geom_kind kind;
    const mesh *mesh;          /* GEOM_TRIANGLES: world-space mesh (owned by the scene) */
    const sphere_set *spheres; /* GEOM_SPHERES (owned by the scene) */
    bvh bvh;                   /* over this geometry's primitives */
} geom_accel;

struct accel {
    geom_accel *geoms; /* geom_count entries; index = geometry id */
    uint32_t geom_count;
    bvh top;           /* over the geometries' bounds; prim ids are geometry ids */
};

static vec3 vertex(const mesh *m, uint32_t i)
{
    const float *p = m->positions + 3 * (size_t)i;
    return v3(p[0], p[1], p[2]);
}

static bool build_triangles(geom_accel *g, const mesh *m, aabb *bounds, tess_error *err)
{
    g->kind = GEOM_TRIANGLES;
    g->mesh = m;
    aabb *boxes = malloc(((size_t)m->triangle_count + 1) * sizeof *boxes);
    if (!boxes)
        return tess_error_set(err, "accel: out of memory for %u triangle bounds", m->triangle_count);
    *bounds = aabb_empty();
    for (uint32_t i = 0; i < m->triangle_count; i++) {
        const uint32_t *t = m->indices + 3 * (size_t)i;
        aabb b = aabb_grow_point(aabb_grow_point(aabb_grow_point(aabb_empty(), vertex(m, t[0])), vertex(m, t[1])),
                                 vertex(m, t[2]));
        boxes[i] = b;
        *bounds = aabb_grow(*bounds, b);
    }
    bool ok = bvh_build(&g->bvh, boxes, m->triangle_count, err);
    free(boxes);
    return ok;
}

static bool build_spheres(geom_accel *g, const sphere_set *s, aabb *bounds, tess_error *err)
{
    g->kind = GEOM_SPHERES;
    g->spheres = s;
    aabb *boxes = malloc(((size_t)s->count + 1) * sizeof *boxes);
    if (!boxes)
        return tess_error_set(err, "accel: out of memory for %u sphere bounds", s->count);
    *bounds = aabb_empty();
    for (uint32_t i = 0; i < s->count; i++) {
        vec3 c = v3(s->center_x[i], s->center_y[i], s->center_z[i]);
        vec3 r = v3(s->radius[i], s->radius[i], s->radius[i]);
        boxes[i] = (aabb){v3_sub(c, r), v3_add(c, r)};
        *bounds = aabb_grow(*bounds, boxes[i]);
    }
    bool ok = bvh_build(&g->bvh, boxes, s->count, err);
    free(boxes);
    return ok;
}

accel *accel_build(const scene *s, int threads, tess_error *err)
{
    (void)threads; /* the parallel build comes with the wide BVH */
    accel *a = calloc(1, sizeof *a);
    uint32_t count = s->mesh_count + (s->spheres.count > 0 ? 1u : 0u);
    aabb *geom_bounds = calloc((size_t)count + 1, sizeof *geom_bounds);
    if (!a || !geom_bounds || !(a->geoms = calloc((size_t)count + 1, sizeof *a->geoms))) {
        tess_error_set(err, "accel: out of memory");
        goto fail;
    }
    a->geom_count = count;
    for (uint32_t i = 0; i < s->mesh_count; i++)
        if (!build_triangles(&a->geoms[i], s->meshes[i].mesh, &geom_bounds[i], err))
            goto fail;
    if (s->spheres.count > 0 && !build_spheres(&a->geoms[s->mesh_count], &s->spheres, &geom_bounds[s->mesh_count], err))
        goto fail;
    if (!bvh_build(&a->top, geom_bounds, count, err))
        goto fail;
    free(geom_bounds);
    return a;
fail:
    free(geom_bounds);
    accel_destroy(a);
    return NULL;
}

void accel_destroy(accel *a)
{
    if (!a)
        return;
    if (a->geoms)
        for (uint32_t i = 0; i < a->geom_count; i++)
            bvh_finish(&a->geoms[i].bvh);
    free(a->geoms);
    bvh_finish(&a->top);
    free(a);
}

size_t accel_bytes(const accel *a)
{
    size_t bytes = sizeof *a + bvh_bytes(&a->top) + a->geom_count * sizeof *a->geoms;
    for (uint32_t i = 0; i < a->geom_count; i++)
        bytes += bvh_bytes(&a->geoms[i].bvh);
    return bytes;
}

/* Test primitive `prim` of geometry g; on a hit closer than r->t_far, shrink
 * r->t_far and record it in h. */
static bool hit_primitive(const geom_accel *g, uint32_t geom_id, uint32_t prim, ray *r, const ray_derived *d, hit *h)
{
    float t, u = 0.f, v = 0.f;
    bool found;
    if (g->kind == GEOM_TRIANGLES) {
        const uint32_t *idx = g->mesh->indices + 3 * (size_t)prim;
        found = intersect_triangle(r, d, vertex(g->mesh, idx[0]), vertex(g->mesh, idx[1]), vertex(g->mesh, idx[2]),
                                   &t, &u, &v);
    } else {
        const sphere_set *s = g->spheres;
        found = intersect_sphere(r, v3(s->center_x[prim], s->center_y[prim], s->center_z[prim]), s->radius[prim], &t);
    }
    if (!found)
        return false;
    r->t_far = t;
    if (h)
        *h = (hit){.t = t, .u = u, .v = v, .prim_id = prim, .geom_id = geom_id};
    return true;
}

/* Traverse one geometry's BVH, nearer child first. `any` stops at the first
 * hit (h may then be NULL). */
static bool traverse_geometry(const geom_accel *g, uint32_t geom_id, ray *r, const ray_derived *d, hit *h, bool any)
{
    const bvh *b = &g->bvh;
    if (b->node_count == 0)
        return false;
    uint32_t stack[BVH_MAX_DEPTH + 1];
    float stack_t_entry[BVH_MAX_DEPTH + 1]; /* entry distance of each stacked node's box */
    int top = 0;
    uint32_t node = 0;
    bool found = false;
    float t_entry;
    if (!intersect_box(r, d, &b->nodes[0].bounds, &t_entry))
        return false;
    for (;;) {
        const bvh_node *n = &b->nodes[node];
        if (n->count > 0) {
            for (uint32_t i = n->first; i < n->first + n->count; i++)
                if (hit_primitive(g, geom_id, b->prim_order[i], r, d, h)) {
                    found = true;
                    if (any)
                        return true;
                }
        } else {
            float t_left, t_right;
            bool hit_left = intersect_box(r, d, &b->nodes[n->first].bounds, &t_left);
            bool hit_right = intersect_box(r, d, &b->nodes[n->first + 1].bounds, &t_right);
            if (hit_left && hit_right) {
                /* nearer child first; the other waits on the stack */
                bool left_first = t_left <= t_right;
                stack_t_entry[top] = left_first ? t_right : t_left;
                stack[top++] = left_first ? n->first + 1 : n->first;
                node = left_first ? n->first : n->first + 1;
                continue;
            }
            if (hit_left || hit_right) {
                node = hit_left ? n->first : n->first + 1;
                continue;
            }
        }
        /* pop the next node whose box still starts before the closest hit */
        do {
            if (top == 0)
                return found;
            top--;
        } while (stack_t_entry[top] > r->t_far);
        node = stack[top];
    }
}

static bool trace(const accel *a, ray *r, hit *h, bool any)
{
    const bvh *b = &a->top;
    if (b->node_count == 0 || ray_is_degenerate(r))
        return false;
    ray_derived d = ray_derive(r);
    uint32_t stack[BVH_MAX_DEPTH + 1];
    int top = 0;
    stack[top++] = 0;
    bool found = false;
    while (top > 0) {
        const bvh_node *n = &b->nodes[stack[--top]];
        float t_entry;
        if (!intersect_box(r, &d, &n->bounds, &t_entry))
            continue;
        if (n->count == 0) {
            stack[top++] = n->first + 1;
            stack[top++] = n->first;
            continue;
        }
        for (uint32_t i = n->first; i < n->first + n->count; i++) {
            uint32_t geom_id = b->prim_order[i];
            if (traverse_geometry(&a->geoms[geom_id], geom_id, r, &d, h, any)) {
                found = true;
                if (any)
                    return true;
            }
        }
    }
    return found;
}

bool accel_intersect(const accel *a, const ray *r, hit *h)
{
    *h = hit_none();
    ray local = *r;
    return trace(a, &local, h, false);
}

bool accel_occluded(const accel *a, const ray *r)
{
    ray local = *r;
    return trace(a, &local, NULL, true);
}

void accel_intersect_packet(const accel *a, packet_range r)
{
    ray_packet *p = r.packet;
    uint64_t todo = packet_range_mask(r);
    while (todo) {
        uint32_t i = (uint32_t)__builtin_ctzll(todo);
        todo &= todo - 1;
        ray one = packet_get_ray(p, i);
        hit h;
        if (accel_intersect(a, &one, &h)) {
            p->hit_t[i] = h.t;
            p->hit_u[i] = h.u;
            p->hit_v[i] = h.v;
            p->prim_id[i] = h.prim_id;
            p->geom_id[i] = h.geom_id;
            p->t_far[i] = h.t;
        }
    }
}

uint64_t accel_occluded_packet(const accel *a, packet_range r)
{
    ray_packet *p = r.packet;
    uint64_t todo = packet_range_mask(r), occluded = 0;
    while (todo) {
        uint32_t i = (uint32_t)__builtin_ctzll(todo);
        todo &= todo - 1;
        ray one = packet_get_ray(p, i);
        if (accel_occluded(a, &one))
            occluded |= 1ull << i;
    }
    return occluded;
}
