/* triangle_kind.c - triangle meshes as a geometry kind (triangle_kind.h):
 * data is a scene_mesh, read in place by the SIMD watertight kernels. */
#include "triangle_kind.h"

#include <stdlib.h>
#include <string.h>

#include "engine/accel/intersect.h"
#include "engine/accel/wbvh.h"
#include "mesh_tree.h"

static vec3 mesh_point(const mesh *m, uint32_t i)
{
    const float *p = m->positions + 3 * (size_t)i;
    return v3(p[0], p[1], p[2]);
}

static vec3 interpolate(const float *array, const uint32_t *idx, float u, float v)
{
    const float *a = array + 3 * (size_t)idx[0], *b = array + 3 * (size_t)idx[1], *c = array + 3 * (size_t)idx[2];
    return v3_add(v3_scale(v3(a[0], a[1], a[2]), 1.f - u - v),
                  v3_add(v3_scale(v3(b[0], b[1], b[2]), u), v3_scale(v3(c[0], c[1], c[2]), v)));
}

static uint32_t triangles_count(const void *data) { return ((const scene_mesh *)data)->mesh->triangle_count; }

static bool triangles_bounds(const void *data, aabb *out)
{
    float lo[3], hi[3];
    if (!mesh_bounds(((const scene_mesh *)data)->mesh, lo, hi))
        return false;
    *out = (aabb){v3(lo[0], lo[1], lo[2]), v3(hi[0], hi[1], hi[2])};
    return true;
}

/* A triangle of zero area can never be hit: left out of the BVH. */
static bool triangles_prim_bounds(const void *data, uint32_t prim, aabb *out)
{
    const mesh *m = ((const scene_mesh *)data)->mesh;
    const uint32_t *t = m->indices + 3 * (size_t)prim;
    vec3 v0 = mesh_point(m, t[0]), v1 = mesh_point(m, t[1]), v2 = mesh_point(m, t[2]);
    if (intersect_triangle_degenerate(v0, v1, v2))
        return false;
    *out = aabb_grow_point(aabb_grow_point(aabb_grow_point(aabb_empty(), v0), v1), v2);
    return true;
}

static const wbvh *triangles_tree(void *data, int threads, tess_error *err)
{
    return mesh_tree_get(data, threads, err);
}

static bool triangles_intersect(const void *data, uint32_t prim, const ray *r, float *t, float *u, float *v)
{
    const mesh *m = ((const scene_mesh *)data)->mesh;
    const uint32_t *idx = m->indices + 3 * (size_t)prim;
    ray_derived d = ray_derive(r);
    return intersect_triangle(r, &d, mesh_point(m, idx[0]), mesh_point(m, idx[1]), mesh_point(m, idx[2]), t, u, v);
}

static void triangles_describe(const void *data, uint32_t prim, const ray *r, const hit *h, bool need_position,
                               geometry_surface *out)
{
    (void)r;
    const scene_mesh *sm = data;
    const mesh *m = sm->mesh;
    const uint32_t *idx = m->indices + 3 * (size_t)prim;
    vec3 v0 = mesh_point(m, idx[0]), v1 = mesh_point(m, idx[1]), v2 = mesh_point(m, idx[2]);
    /* from barycentrics rather than org + t dir: on the surface, with a known error */
    if (need_position) {
        surface_point sp = surface_point_triangle(v0, v1, v2, h->u, h->v);
        out->position = sp.p;
        out->position_error = sp.error;
    }
    out->geometric_n = v3_normalize(v3_cross(v3_sub(v1, v0), v3_sub(v2, v0)));
    out->shading_n = m->normals ? v3_normalize(interpolate(m->normals, idx, h->u, h->v)) : out->geometric_n;
    out->material_id = sm->mesh_material_ids && m->triangle_material
                           ? sm->mesh_material_ids[m->triangle_material[prim]]
                           : sm->material_id;
    out->has_colour = m->colors != NULL;
    if (out->has_colour)
        out->colour = interpolate(m->colors, idx, h->u, h->v);
}

static size_t triangles_bytes(const void *data) { return mesh_bytes(((const scene_mesh *)data)->mesh); }

/* CLOSED. A mesh bounds a solid when, after welding vertices of equal
 * position (meshes split vertices for normals and UVs; only exactly equal
 * floats are welded, -0 with +0, since nearly equal ones leave a crack the
 * watertight test can see), every undirected edge is used by an EVEN number
 * of its non-degenerate triangles, and it has at least one. Two is a closed
 * 2-manifold; four, six are solids touching along an edge, as CAD parts do.
 * Even counts are exactly what parity needs: the triangles are then the
 * boundary of a region (mod 2), so whether a ray crosses them an odd number
 * of times does not depend on the ray, and a cut can be capped by it. An odd
 * count (a hole's rim: 1; a stray duplicate face: 3) is open. Orientation is
 * not looked at (parity does not need it). Degenerate triangles (zero area,
 * which includes a repeated vertex) are ignored: they are never hit.
 * O(V log V + T log T) time, 16 bytes a vertex then 4 a vertex and 24 a
 * triangle of scratch; false (no caps) when that memory is not there. */

typedef struct weld_key {
    uint32_t bits[3]; /* the coordinates' bit patterns, -0 made +0 */
    uint32_t vertex;
} weld_key;

static int weld_key_compare(const void *a, const void *b)
{
    const weld_key *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x->bits[i] != y->bits[i])
            return x->bits[i] < y->bits[i] ? -1 : 1;
    return x->vertex < y->vertex ? -1 : x->vertex > y->vertex;
}

static int edge_compare(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static uint32_t position_bits(float f)
{
    f += 0.f; /* -0 + +0 is +0: one key for one position */
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    return bits;
}

/* weld[v] = the lowest vertex at v's position; false without memory */
static bool weld_vertices(const mesh *m, uint32_t *weld)
{
    weld_key *keys = malloc((size_t)m->vertex_count * sizeof *keys + 1);
    if (!keys)
        return false;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const float *p = m->positions + 3 * (size_t)v;
        keys[v] = (weld_key){{position_bits(p[0]), position_bits(p[1]), position_bits(p[2])}, v};
    }
    qsort(keys, m->vertex_count, sizeof *keys, weld_key_compare);
    for (uint32_t i = 0, first = 0; i < m->vertex_count; i++) {
        if (memcmp(keys[i].bits, keys[first].bits, sizeof keys[i].bits) != 0)
            first = i;
        weld[keys[i].vertex] = keys[first].vertex; /* the run's first is its lowest vertex */
    }
    free(keys);
    return true;
}

static bool triangles_closed(const void *data)
{
    const mesh *m = ((const scene_mesh *)data)->mesh;
    uint32_t *weld = malloc((size_t)m->vertex_count * sizeof *weld + 1);
    uint64_t *edges = malloc(3 * (size_t)m->triangle_count * sizeof *edges + 1);
    bool closed = false;
    if (!weld || !edges || !weld_vertices(m, weld))
        goto done;
    size_t edge_count = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *idx = m->indices + 3 * (size_t)t;
        if (m->canon && m->canon[t] != t) /* a repeated copy (spatial splits): its edges count once */
            continue;
        if (intersect_triangle_degenerate(mesh_point(m, idx[0]), mesh_point(m, idx[1]), mesh_point(m, idx[2])))
            continue;
        for (int e = 0; e < 3; e++) {
            uint32_t a = weld[idx[e]], b = weld[idx[(e + 1) % 3]];
            /* a != b: equal welded ids are equal positions, a degenerate triangle */
            edges[edge_count++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
    }
    qsort(edges, edge_count, sizeof *edges, edge_compare);
    closed = edge_count > 0;
    for (size_t i = 0; i < edge_count && closed;) {
        size_t run = i;
        while (run < edge_count && edges[run] == edges[i])
            run++;
        closed = (run - i) % 2 == 0;
        i = run;
    }
done:
    free(weld);
    free(edges);
    return closed;
}

const geometry_ops geometry_triangles_ops = {
    .name = "triangles",
    .leaf = GEOMETRY_LEAF_MESH,
    .prim_count = triangles_count,
    .bounds = triangles_bounds,
    .prim_bounds = triangles_prim_bounds,
    .tree = triangles_tree,
    .intersect = triangles_intersect,
    .describe = triangles_describe,
    .bytes = triangles_bytes,
    .destroy = NULL, /* the scene's meshes array owns its scene_mesh */
    .closed = triangles_closed,
};

