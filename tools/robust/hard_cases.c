/* hard_cases.c - the generators of hard_cases.h (moved here from
 * tests/test_robust.c, draw for draw, so the tests' cases are unchanged). */
#include "hard_cases.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "engine/accel/intersect.h"

/* ---- random numbers ---- */

uint64_t rng_next(rng *g)
{
    uint64_t z = (g->state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

double rng_unit(rng *g) { return (double)(rng_next(g) >> 11) * 0x1p-53; }
double rng_range(rng *g, double lo, double hi) { return lo + (hi - lo) * rng_unit(g); }
double rng_log_range(rng *g, double lo, double hi) { return exp(rng_range(g, log(lo), log(hi))); }

/* ---- double vectors ---- */

dvec dv(double x, double y, double z) { return (dvec){x, y, z}; }
dvec dv_of(vec3 a) { return dv(a.x, a.y, a.z); }
vec3 dv_round(dvec a) { return v3((float)a.x, (float)a.y, (float)a.z); }
dvec dv_add(dvec a, dvec b) { return dv(a.x + b.x, a.y + b.y, a.z + b.z); }
dvec dv_sub(dvec a, dvec b) { return dv(a.x - b.x, a.y - b.y, a.z - b.z); }
dvec dv_scale(dvec a, double s) { return dv(a.x * s, a.y * s, a.z * s); }
double dv_dot(dvec a, dvec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
dvec dv_cross(dvec a, dvec b) { return dv(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
double dv_len(dvec a) { return sqrt(dv_dot(a, a)); }
dvec dv_unit(dvec a) { return dv_scale(a, 1.0 / dv_len(a)); }
double dv_max_abs(dvec a) { return fmax(fabs(a.x), fmax(fabs(a.y), fabs(a.z))); }

dvec dv_random_unit(rng *g)
{
    for (;;) {
        dvec p = dv(rng_range(g, -1, 1), rng_range(g, -1, 1), rng_range(g, -1, 1));
        double l2 = dv_dot(p, p);
        if (l2 > 1e-4 && l2 <= 1.0)
            return dv_scale(p, 1.0 / sqrt(l2));
    }
}

dvec dv_random_perpendicular(dvec n, rng *g)
{
    for (;;) {
        dvec r = dv_random_unit(g);
        dvec e = dv_sub(r, dv_scale(n, dv_dot(r, n)));
        if (dv_len(e) > 0.1)
            return dv_unit(e);
    }
}

void random_basis(rng *g, dvec *e0, dvec *e1, dvec *e2)
{
    *e2 = dv_random_unit(g);
    *e0 = dv_random_perpendicular(*e2, g);
    *e1 = dv_cross(*e2, *e0);
}

/* ---- the reference ray/triangle test ---- */

ref_triangle_hit reference_triangle(const ray *r, vec3 v0f, vec3 v1f, vec3 v2f)
{
    ref_triangle_hit out = {.crosses = false, .t = NAN, .b = {NAN, NAN, NAN}};
    dvec o = dv_of(r->org), d = dv_of(r->dir), v0 = dv_of(v0f);
    dvec e1 = dv_sub(dv_of(v1f), v0), e2 = dv_sub(dv_of(v2f), v0);
    dvec p = dv_cross(d, e2);
    double det = dv_dot(e1, p);
    if (det == 0.0 || !isfinite(det))
        return out;
    dvec s = dv_sub(o, v0);
    dvec q = dv_cross(s, e1);
    double b1 = dv_dot(s, p) / det, b2 = dv_dot(d, q) / det;
    out.crosses = true;
    out.t = dv_dot(e2, q) / det;
    out.b[0] = 1.0 - b1 - b2;
    out.b[1] = b1;
    out.b[2] = b2;
    return out;
}

bool reference_hits(const ref_triangle_hit *h, float t_near, float t_far)
{
    return h->crosses && h->b[0] >= 0.0 && h->b[1] >= 0.0 && h->b[2] >= 0.0 && h->t > t_near && h->t <= t_far;
}

/* ---- mesh building without asserts: false once an allocation failed ---- */

static bool put_vertex(mesh *m, vec3 p, uint32_t *index)
{
    if (!mesh_add_vertex(m, p.x, p.y, p.z))
        return false;
    if (index)
        *index = m->vertex_count - 1;
    return true;
}

static vec3 vertex_at(const mesh *m, uint32_t i)
{
    const float *p = m->positions + 3 * (size_t)i;
    return v3(p[0], p[1], p[2]);
}

/* ---- a. closed meshes ---- */

mesh *jittered_sphere(int slices, int stacks, double jitter, dvec centre, rng *g)
{
    mesh *m = mesh_create();
    if (!m)
        return NULL;
    const double pi = 3.14159265358979323846;
    bool ok = put_vertex(m, dv_round(dv_add(centre, dv(0, 1.0 + jitter * rng_range(g, -1, 1), 0))), NULL);
    for (int i = 1; i < stacks; i++)
        for (int j = 0; j < slices; j++) {
            double theta = pi * i / stacks, phi = 2.0 * pi * j / slices;
            double r = 1.0 + jitter * rng_range(g, -1, 1);
            dvec dir = dv(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
            ok = ok && put_vertex(m, dv_round(dv_add(centre, dv_scale(dir, r))), NULL);
        }
    uint32_t south = 0;
    ok = ok && put_vertex(m, dv_round(dv_add(centre, dv(0, -1.0 - jitter * rng_range(g, -1, 1), 0))), &south);
#define RING(i, j) (1u + (uint32_t)((i)-1) * (uint32_t)slices + (uint32_t)((j) % slices))
    for (int j = 0; j < slices && ok; j++) {
        ok = mesh_add_triangle(m, 0, RING(1, j), RING(1, j + 1));
        for (int i = 1; i + 1 < stacks && ok; i++)
            ok = mesh_add_triangle(m, RING(i, j + 1), RING(i, j), RING(i + 1, j)) &&
                 mesh_add_triangle(m, RING(i, j + 1), RING(i + 1, j), RING(i + 1, j + 1));
        ok = ok && mesh_add_triangle(m, RING(stacks - 1, j + 1), RING(stacks - 1, j), south);
    }
#undef RING
    if (!ok) {
        mesh_destroy(m);
        return NULL;
    }
    return m;
}

size_t closed_mesh_targets(const mesh *m, int points_per_edge, vec3 **targets, size_t *edges)
{
    *targets = NULL;
    *edges = 0;
    /* each undirected edge once: the direction with the smaller index first */
    size_t half_edges = 3 * (size_t)m->triangle_count;
    uint32_t *edge_a = malloc(half_edges * sizeof *edge_a), *edge_b = malloc(half_edges * sizeof *edge_b);
    if (!edge_a || !edge_b) {
        free(edge_a);
        free(edge_b);
        return 0;
    }
    size_t n_edges = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        for (int e = 0; e < 3; e++) {
            uint32_t a = m->indices[3 * t + e], b = m->indices[3 * t + (e + 1) % 3];
            if (a < b) {
                edge_a[n_edges] = a;
                edge_b[n_edges++] = b;
            }
        }
    size_t count = m->vertex_count + n_edges * (size_t)points_per_edge;
    vec3 *out = malloc((count ? count : 1) * sizeof *out);
    if (out) {
        size_t k = 0;
        for (uint32_t v = 0; v < m->vertex_count; v++)
            out[k++] = vertex_at(m, v);
        for (size_t e = 0; e < n_edges; e++) {
            vec3 a = vertex_at(m, edge_a[e]), b = vertex_at(m, edge_b[e]);
            for (int j = 1; j <= points_per_edge; j++) {
                float f = (float)j / (float)(points_per_edge + 1);
                out[k++] = v3_add(a, v3_scale(v3_sub(b, a), f));
            }
        }
    }
    free(edge_a);
    free(edge_b);
    if (!out)
        return 0;
    *targets = out;
    *edges = n_edges;
    return count;
}

/* ---- b. slivers ---- */

void random_sliver(rng *g, double len, bool needle, vec3 v[3])
{
    const double aspect = 1e6;
    double h = len / aspect;
    dvec e0, e1, e2;
    random_basis(g, &e0, &e1, &e2);
    dvec origin = dv(rng_range(g, -len, len), rng_range(g, -len, len), rng_range(g, -len, len));
    dvec local[3] = {dv(0, 0, 0), dv(len, 0, 0), dv(needle ? len : 0.5 * len, h, 0)};
    for (int i = 0; i < 3; i++)
        v[i] = dv_round(dv_add(origin, dv_add(dv_scale(e0, local[i].x), dv_scale(e1, local[i].y))));
}

ray sliver_ray(rng *g, const vec3 v[3], double len, double *b1_out, double *b2_out)
{
    dvec dv0 = dv_of(v[0]), dv1 = dv_of(v[1]), dv2 = dv_of(v[2]);
    dvec n = dv_unit(dv_cross(dv_sub(dv1, dv0), dv_sub(dv2, dv0)));
    double b1, b2;
    do {
        b1 = rng_range(g, 0.2, 0.6);
        b2 = rng_range(g, 0.2, 0.6);
    } while (1.0 - b1 - b2 < 0.2);
    dvec p = dv_add(dv0, dv_add(dv_scale(dv_sub(dv1, dv0), b1), dv_scale(dv_sub(dv2, dv0), b2)));
    dvec w;
    do
        w = dv_random_unit(g);
    while (fabs(dv_dot(w, n)) < sin(5.0 * 3.14159265358979 / 180.0));
    vec3 org = dv_round(dv_add(p, dv_scale(w, len * rng_log_range(g, 1e-4, 1e-2))));
    *b1_out = b1;
    *b2_out = b2;
    return (ray){org, dv_round(dv_sub(p, dv_of(org))), 0.f, FLT_MAX};
}

/* ---- g. lit planes ---- */

mesh *lit_plane_mesh(rng *g, double offset, int form, double half, dvec *shift, dvec *e0, dvec *e1, dvec *n)
{
    *shift = dv_scale(dv_unit(dv(1, 0.7, -0.4)), offset);
    mesh *m = mesh_create();
    if (!m)
        return NULL;
    bool ok = true;
    if (form == 0) {
        random_basis(g, e0, e1, n);
        dvec c[3] = {dv(-half, -half, 0), dv(3 * half, -half, 0), dv(-half, 3 * half, 0)};
        for (int i = 0; i < 3 && ok; i++)
            ok = put_vertex(m, dv_round(dv_add(*shift, dv_add(dv_scale(*e0, c[i].x), dv_scale(*e1, c[i].y)))), NULL);
        ok = ok && mesh_add_triangle(m, 0, 1, 2);
    } else {
        *e0 = dv(1, 0, 0), *e1 = dv(0, 0, 1), *n = dv(0, 1, 0);
        float y = (float)shift->y; /* every vertex has exactly this y */
        for (int i = 0; i <= 8 && ok; i++)
            for (int j = 0; j <= 8 && ok; j++)
                ok = put_vertex(m, v3((float)(shift->x - half + 25.0 * i), y, (float)(shift->z - half + 25.0 * j)),
                                NULL);
        for (uint32_t i = 0; i < 8 && ok; i++)
            for (uint32_t j = 0; j < 8 && ok; j++) {
                uint32_t c = i * 9 + j;
                ok = mesh_add_triangle(m, c, c + 1, c + 10) && mesh_add_triangle(m, c, c + 10, c + 9);
            }
    }
    if (!ok) {
        mesh_destroy(m);
        return NULL;
    }
    return m;
}

vec3 lit_plane_light(rng *g, dvec n, double tilt_deg)
{
    const double pi = 3.14159265358979323846;
    double tilt = tilt_deg * pi / 180.0;
    dvec light_dir = dv_add(dv_scale(dv_random_perpendicular(n, g), cos(tilt)), dv_scale(n, sin(tilt)));
    return dv_round(dv_unit(light_dir));
}

ray lit_plane_primary(rng *g, dvec shift, dvec e0, dvec e1, dvec n, double half)
{
    dvec q = dv_add(shift, dv_add(dv_scale(e0, rng_range(g, -0.95, 0.95) * half),
                                  dv_scale(e1, rng_range(g, -0.95, 0.95) * half)));
    dvec view;
    do
        view = dv_random_unit(g);
    while (dv_dot(view, n) < 0.2);
    vec3 eye = dv_round(dv_add(q, dv_scale(view, half * rng_range(g, 0.2, 2.0))));
    return (ray){eye, dv_round(dv_sub(q, dv_of(eye))), 0.f, FLT_MAX};
}

surface_point surface_at_hit(const mesh *m, const hit *h, vec3 ray_dir, vec3 *normal)
{
    const uint32_t *idx = m->indices + 3 * (size_t)h->prim_id;
    vec3 v0 = vertex_at(m, idx[0]), v1 = vertex_at(m, idx[1]), v2 = vertex_at(m, idx[2]);
    *normal = v3_normalize(v3_cross(v3_sub(v1, v0), v3_sub(v2, v0)));
    if (v3_dot(*normal, ray_dir) > 0.f)
        *normal = v3_scale(*normal, -1.f);
    return surface_point_triangle(v0, v1, v2, h->u, h->v);
}
