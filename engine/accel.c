/* accel.c - two levels: a wide BVH per geometry (wbvh.h) traced by the
 * kernels of the best instruction set (kernels.h), under a small binary BVH
 * over the geometries' bounds for single rays. */
#include "accel.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "intersect.h"
#include "kernels.h"
#include "parallel.h"
#include "scene.h"
#include "wbvh.h"

struct accel {
    wbvh *geoms;               /* geom_count entries; index = geometry id */
    uint32_t geom_count;
    bvh top;                   /* over the geometries' bounds; prim ids are geometry ids */
    const kernel_table *kernels; /* resolved once at build */
    float coord_abs_max;         /* largest |coordinate| of the scene bounds (cull slack) */
    /* geom_count flags, nonzero: hidden. The only mutable part (see accel.h):
     * relaxed loads in the loops over geometries, one byte per geometry visit */
    atomic_uchar *hidden;
};

static float abs_max(vec3 a)
{
    float x = fabsf(a.x), y = fabsf(a.y), z = fabsf(a.z);
    float m = x > y ? x : y;
    return m > z ? m : z;
}

static bool build_geometry(wbvh *out, const aabb *boxes, uint32_t count, const mesh *m, const uint32_t *prim_ids,
                           const sphere_set *spheres, int threads, tess_error *err)
{
    bvh binary;
    if (!bvh_build(&binary, boxes, count, threads, err))
        return false;
    bool ok = m ? wbvh_build_triangles(out, &binary, m, prim_ids, err) : wbvh_build_spheres(out, &binary, spheres, err);
    bvh_finish(&binary);
    return ok;
}

static vec3 mesh_point(const mesh *m, uint32_t i)
{
    const float *p = m->positions + 3 * (size_t)i;
    return v3(p[0], p[1], p[2]);
}

/* Shared by the threads computing triangle boxes. */
typedef struct box_job {
    const mesh *m;
    aabb *boxes;        /* per triangle; empty for one of zero area */
} box_job;

static void triangle_boxes(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    box_job *job = ctx;
    const mesh *m = job->m;
    for (size_t i = begin; i < end; i++) {
        const uint32_t *t = m->indices + 3 * i;
        vec3 v0 = mesh_point(m, t[0]), v1 = mesh_point(m, t[1]), v2 = mesh_point(m, t[2]);
        job->boxes[i] = intersect_triangle_degenerate(v0, v1, v2)
                            ? aabb_empty()
                            : aabb_grow_point(aabb_grow_point(aabb_grow_point(aabb_empty(), v0), v1), v2);
    }
}

/* Triangles per parallel chunk of box computation. */
#define ACCEL_BOX_GRAIN 16384

/* Triangles of zero area can never be hit: they are left out of the BVH. */
static bool build_triangles(wbvh *out, const mesh *m, aabb *bounds, int threads, tess_error *err)
{
    aabb *boxes = malloc(((size_t)m->triangle_count + 1) * sizeof *boxes);
    uint32_t *prim_ids = malloc(((size_t)m->triangle_count + 1) * sizeof *prim_ids);
    if (!boxes || !prim_ids) {
        free(boxes);
        free(prim_ids);
        return tess_error_set(err, "accel: out of memory for %u triangle bounds", m->triangle_count);
    }
    box_job job = {m, boxes};
    parallel_for(threads, m->triangle_count, ACCEL_BOX_GRAIN, triangle_boxes, &job);
    /* compact (in order, so the result does not depend on the thread count) */
    *bounds = aabb_empty();
    uint32_t kept = 0;
    for (uint32_t i = 0; i < m->triangle_count; i++) {
        if (aabb_is_empty(boxes[i]))
            continue;
        *bounds = aabb_grow(*bounds, boxes[i]);
        boxes[kept] = boxes[i];
        prim_ids[kept++] = i;
    }
    bool ok = build_geometry(out, boxes, kept, m, prim_ids, NULL, threads, err);
    free(boxes);
    free(prim_ids);
    return ok;
}

static bool build_spheres(wbvh *out, const sphere_set *s, aabb *bounds, int threads, tess_error *err)
{
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
    bool ok = build_geometry(out, boxes, s->count, NULL, NULL, s, threads, err);
    free(boxes);
    return ok;
}

accel *accel_build(const scene *s, int threads, tess_error *err)
{
    accel *a = calloc(1, sizeof *a);
    uint32_t count = s->mesh_count + (s->spheres.count > 0 ? 1u : 0u);
    aabb *geom_bounds = calloc((size_t)count + 1, sizeof *geom_bounds);
    if (!a || !geom_bounds || !(a->geoms = calloc((size_t)count + 1, sizeof *a->geoms)) ||
        !(a->hidden = calloc((size_t)count + 1, sizeof *a->hidden))) {
        tess_error_set(err, "accel: out of memory");
        goto fail;
    }
    a->kernels = kernels_select();
    a->geom_count = count;
    for (uint32_t i = 0; i < s->mesh_count; i++)
        if (!build_triangles(&a->geoms[i], s->meshes[i].mesh, &geom_bounds[i], threads, err))
            goto fail;
    if (s->spheres.count > 0 &&
        !build_spheres(&a->geoms[s->mesh_count], &s->spheres, &geom_bounds[s->mesh_count], threads, err))
        goto fail;
    for (uint32_t i = 0; i < count; i++)
        if (aabb_is_empty(geom_bounds[i])) /* nothing to hit: a point box keeps the top level finite */
            geom_bounds[i] = (aabb){v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 0.f)};
    if (!bvh_build(&a->top, geom_bounds, count, 1, err))
        goto fail;
    for (uint32_t i = 0; i < count; i++)
        a->coord_abs_max = fmaxf(a->coord_abs_max, fmaxf(abs_max(geom_bounds[i].lo), abs_max(geom_bounds[i].hi)));
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
            wbvh_finish(&a->geoms[i]);
    free(a->geoms);
    free(a->hidden);
    bvh_finish(&a->top);
    free(a);
}

size_t accel_bytes(const accel *a)
{
    size_t bytes = sizeof *a + bvh_bytes(&a->top) + a->geom_count * sizeof *a->geoms;
    for (uint32_t i = 0; i < a->geom_count; i++)
        bytes += wbvh_bytes(&a->geoms[i]);
    return bytes;
}

uint32_t accel_geometry_count(const accel *a) { return a->geom_count; }

void accel_set_hidden(const accel *a, uint32_t geom_id, bool hidden)
{
    if (geom_id < a->geom_count)
        atomic_store_explicit(&a->hidden[geom_id], hidden ? 1u : 0u, memory_order_relaxed);
}

void accel_unhide_all(const accel *a)
{
    for (uint32_t g = 0; g < a->geom_count; g++)
        atomic_store_explicit(&a->hidden[g], 0u, memory_order_relaxed);
}

bool accel_hidden(const accel *a, uint32_t geom_id)
{
    return geom_id < a->geom_count && atomic_load_explicit(&a->hidden[geom_id], memory_order_relaxed) != 0;
}

static inline bool is_hidden(const accel *a, uint32_t geom_id)
{
    return atomic_load_explicit(&a->hidden[geom_id], memory_order_relaxed) != 0;
}

const char *accel_isa_name(const accel *a) { return a->kernels->isa_name; }

bool accel_use_isa(accel *a, const char *isa_name)
{
    for (int i = 0; i < KERNEL_ISA_COUNT; i++) {
        const kernel_table *t = kernels_for((kernel_isa)i);
        if (t && strcmp(t->isa_name, isa_name) == 0) {
            a->kernels = t;
            return true;
        }
    }
    return false;
}

/* Single ray through the top level, then each geometry's wide BVH. */
static bool trace(const accel *a, ray *r, hit *h, bool any)
{
    const bvh *b = &a->top;
    if (b->node_count == 0 || ray_is_degenerate(r))
        return false;
    ray_derived d = ray_derive(r);
    d.cull_slack = intersect_cull_slack(abs_max(r->org), abs_max(r->dir), a->coord_abs_max);
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
            if (is_hidden(a, geom_id))
                continue;
            if (a->kernels->intersect1(&a->geoms[geom_id], geom_id, r, &d, h, any)) {
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
    hit unused = hit_none();
    return trace(a, &local, &unused, true);
}

void accel_intersect_packet(const accel *a, packet_range r)
{
    /* hits change: what was derived from them is stale */
    r.packet->flags &= ~(uint32_t)(PACKET_HAVE_HIT_POSITION | PACKET_HAVE_GEOMETRIC_NORMAL | PACKET_HAVE_SHADING_NORMAL);
    uint64_t mask = a->kernels->traceable(r.packet, packet_range_mask(r));
    if (!mask)
        return;
    packet_derive_inv_dir(r.packet);
    for (uint32_t g = 0; g < a->geom_count; g++)
        if (!is_hidden(a, g))
            a->kernels->intersect_packet(&a->geoms[g], g, r.packet, mask, false);
}

uint64_t accel_occluded_packet(const accel *a, packet_range r)
{
    uint64_t mask = a->kernels->traceable(r.packet, packet_range_mask(r)), occluded = 0;
    if (!mask)
        return 0;
    packet_derive_inv_dir(r.packet);
    for (uint32_t g = 0; g < a->geom_count && (mask & ~occluded); g++)
        if (!is_hidden(a, g))
            occluded |= a->kernels->intersect_packet(&a->geoms[g], g, r.packet, mask & ~occluded, true);
    return occluded;
}
