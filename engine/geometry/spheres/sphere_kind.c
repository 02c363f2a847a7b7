/* sphere_kind.c - sphere sets as a geometry kind (sphere_kind.h): data is a
 * sphere_set, copied into the SIMD sphere blocks of its tree's leaves. */
#include "sphere_kind.h"

#include "engine/accel/intersect.h"
#include "engine/accel/wbvh.h"

static uint32_t spheres_count(const void *data) { return ((const sphere_set *)data)->count; }

static bool spheres_prim_bounds(const void *data, uint32_t prim, aabb *out)
{
    const sphere_set *s = data;
    vec3 c = v3(s->center_x[prim], s->center_y[prim], s->center_z[prim]);
    vec3 r = v3(s->radius[prim], s->radius[prim], s->radius[prim]);
    *out = (aabb){v3_sub(c, r), v3_add(c, r)};
    return true;
}

static void spheres_fill_lane(void *block, int lane, uint32_t prim, const void *data)
{
    wbvh_sphere_block *b = block;
    const sphere_set *s = data;
    b->cx[lane] = s->center_x[prim];
    b->cy[lane] = s->center_y[prim];
    b->cz[lane] = s->center_z[prim];
    b->r[lane] = s->radius[prim];
    b->prim_id[lane] = prim;
}

static bool spheres_intersect(const void *data, uint32_t prim, const ray *r, float *t, float *u, float *v)
{
    const sphere_set *s = data;
    *u = *v = 0.f;
    return intersect_sphere(r, v3(s->center_x[prim], s->center_y[prim], s->center_z[prim]), s->radius[prim], t);
}

static void spheres_describe(const void *data, uint32_t prim, const ray *r, const hit *h, bool need_position,
                             geometry_surface *out)
{
    (void)need_position; /* the normal comes with the point */
    const sphere_set *s = data;
    vec3 c = v3(s->center_x[prim], s->center_y[prim], s->center_z[prim]);
    surface_point pt = surface_point_sphere(r->org, r->dir, h->t, c, s->radius[prim], &out->geometric_n);
    out->position = pt.p;
    out->position_error = pt.error;
    out->shading_n = out->geometric_n;
    out->material_id = s->material_id[prim];
    out->has_colour = false;
}

static size_t spheres_bytes(const void *data)
{
    return (size_t)((const sphere_set *)data)->count * (4 * sizeof(float) + sizeof(uint32_t));
}

/* Each sphere bounds a ball (overlapping ones: parity takes the points in an
 * odd number of them, as for meshes that overlap). */
static bool spheres_closed(const void *data)
{
    (void)data;
    return true;
}

const geometry_ops geometry_spheres_ops = {
    .name = "spheres",
    .leaf = GEOMETRY_LEAF_SPHERES,
    .prim_count = spheres_count,
    .bounds = NULL,
    .prim_bounds = spheres_prim_bounds,
    .fill_lane = spheres_fill_lane,
    .intersect = spheres_intersect,
    .describe = spheres_describe,
    .bytes = spheres_bytes,
    .destroy = NULL, /* the scene's sphere set */
    .closed = spheres_closed,
};
