/* test_robust.c - numerical robustness of ray tracing, through the public API
 * only (scene + accel_*, and intersect_triangle / intersect_sphere where one
 * primitive is the point), so every test holds for any kernels behind it.
 * Every accel query runs on the kernels of each instruction set the CPU can
 * run (accel_use_isa), which must also agree with each other bit for bit.
 *
 * Every case is generated from a fixed seed (no data files) and has a numeric
 * pass criterion; the measured numbers go to cr_log_info. Where a case compares
 * against a reference, the reference is computed in double from the same float
 * inputs the engine gets: the float ray and float vertices ARE the problem, and
 * double only removes the engine's own rounding. Failures print the offending
 * ray and primitive in hex floats, ready to paste into a reproduction. */
#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "isa_skip.h"
#include "engine/scene/accel.h"
#include "engine/base/camera.h"
#include "engine/accel/intersect.h"
#include "engine/accel/packet.h"
#include "engine/scene/scene.h"
#include "tools/robust/hard_cases.h"

/* u: the unit roundoff of float, the relative error of one rounding. */
#define F_ROUNDOFF 0x1p-24

/* Failures listed in full before a test gives up printing them. */
#define MAX_REPORTED 5

/* ------------------------------------------------------------------------ */
/* Helpers: scenes, hit records (random numbers, double vectors and the
 * generators of the cases: tools/robust/hard_cases.h, shared with `tessera
 * robust`). */

static scene *scene_new(void)
{
    scene *s = scene_create();
    cr_assert(s);
    material m = material_default();
    cr_assert_eq(scene_add_material(s, &m), 0);
    return s;
}

static mesh *mesh_new(void)
{
    mesh *m = mesh_create();
    cr_assert(m);
    return m;
}

static uint32_t mesh_put_vertex(mesh *m, vec3 p)
{
    cr_assert(mesh_add_vertex(m, p.x, p.y, p.z));
    return m->vertex_count - 1;
}

static void mesh_put_triangle(mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    cr_assert(mesh_add_triangle(m, a, b, c));
}

static void mesh_put_triangle_vertices(mesh *m, vec3 a, vec3 b, vec3 c)
{
    uint32_t i = mesh_put_vertex(m, a);
    mesh_put_vertex(m, b);
    mesh_put_vertex(m, c);
    mesh_put_triangle(m, i, i + 1, i + 2);
}

static void scene_put_mesh(scene *s, mesh *m) { cr_assert(scene_add_mesh(s, m, 0, "robust") >= 0); }

static void log_isas(accel *a);

static accel *accel_for(const scene *s)
{
    tess_error err = {{0}};
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "accel_build: %s", err.msg);
    log_isas(a);
    return a;
}

static vec3 mesh_vertex_at(const mesh *m, uint32_t i)
{
    const float *p = m->positions + 3 * (size_t)i;
    return v3(p[0], p[1], p[2]);
}

static void triangle_vertices(const mesh *m, uint32_t tri, vec3 *v0, vec3 *v1, vec3 *v2)
{
    const uint32_t *idx = m->indices + 3 * (size_t)tri;
    *v0 = mesh_vertex_at(m, idx[0]);
    *v1 = mesh_vertex_at(m, idx[1]);
    *v2 = mesh_vertex_at(m, idx[2]);
}

static bool same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

static bool hits_identical(const hit *a, const hit *b)
{
    return same_bits(a->t, b->t) && same_bits(a->u, b->u) && same_bits(a->v, b->v) && a->prim_id == b->prim_id &&
           a->geom_id == b->geom_id;
}

static bool hit_has_nan(const hit *h) { return isnan(h->t) || isnan(h->u) || isnan(h->v); }

static bool hit_is_none(const hit *h)
{
    hit none = hit_none();
    return hits_identical(h, &none);
}

static ray make_ray(vec3 org, vec3 dir, float t_near, float t_far) { return (ray){org, dir, t_near, t_far}; }

/* The float ulp at |x| (the spacing of floats there). */
static double float_ulp(double x)
{
    float f = fabsf((float)x);
    if (!isfinite(f))
        return INFINITY;
    return (double)nextafterf(f, INFINITY) - (double)f;
}

static ray_packet *packet_new(void)
{
    ray_packet *p = aligned_alloc(64, sizeof *p);
    cr_assert(p);
    memset(p, 0, sizeof *p);
    return p;
}

#define RAY_FMT "org (%a, %a, %a) dir (%a, %a, %a) t (%a, %a]"
#define RAY_ARGS(r) (r).org.x, (r).org.y, (r).org.z, (r).dir.x, (r).dir.y, (r).dir.z, (r).t_near, (r).t_far
#define TRI_FMT "v0 (%a, %a, %a) v1 (%a, %a, %a) v2 (%a, %a, %a)"
#define TRI_ARGS(a, b, c) (a).x, (a).y, (a).z, (b).x, (b).y, (b).z, (c).x, (c).y, (c).z

/* ------------------------------------------------------------------------ */
/* Every query runs on the kernels of each instruction set this CPU can run
 * (accel_use_isa), which must agree bit for bit; each test checks
 * isa_disagreements at its end. The result returned is the first ISA's. */

static const char *const isa_names[] = {"sse2", "avx2", "avx512"};
#define ISA_COUNT (sizeof isa_names / sizeof isa_names[0])

static uint64_t isa_disagreements; /* queries where two ISAs differed (this test's process) */

/* Log once per test (each runs in its own process) which instruction sets it
 * covers, and say which it skips (a CPU without them, or TESSERA_ISA_MAX). */
static void log_isas(accel *a)
{
    static bool logged;
    if (logged)
        return;
    logged = true;
    char names[64] = "";
    for (size_t k = 0; k < ISA_COUNT; k++) {
        if (!isa_skip_note(isa_names[k]) && accel_use_isa(a, isa_names[k])) {
            strcat(names, " ");
            strcat(names, isa_names[k]);
        }
    }
    cr_log_info("robust: kernels tested:%s", names);
}

/* End of every test: all instruction sets gave the same bits. */
static void expect_isas_agree(const char *test)
{
    cr_log_info("%s: %llu queries where instruction sets disagreed", test, (unsigned long long)isa_disagreements);
    cr_expect_eq(isa_disagreements, 0u, "%s: instruction sets disagree on %llu queries", test,
                 (unsigned long long)isa_disagreements);
}

static bool trace_closest(accel *a, const ray *r, hit *h)
{
    bool have = false, got = false;
    for (size_t k = 0; k < ISA_COUNT; k++) {
        if (!accel_use_isa(a, isa_names[k]))
            continue;
        hit hk;
        bool gk = accel_intersect(a, r, &hk);
        if (!have) {
            *h = hk;
            got = gk;
            have = true;
        } else if (gk != got || !hits_identical(&hk, h))
            isa_disagreements++;
    }
    return got;
}

static bool trace_any(accel *a, const ray *r)
{
    bool have = false, got = false;
    for (size_t k = 0; k < ISA_COUNT; k++) {
        if (!accel_use_isa(a, isa_names[k]))
            continue;
        bool gk = accel_occluded(a, r);
        if (!have) {
            got = gk;
            have = true;
        } else if (gk != got)
            isa_disagreements++;
    }
    return got;
}

static bool lane_unchanged(const ray_packet *a, const ray_packet *b, uint32_t i);

static bool packets_equal(const ray_packet *a, const ray_packet *b)
{
    for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++)
        if (!lane_unchanged(a, b, i))
            return false;
    return a->count == b->count && a->active == b->active;
}

/* accel_intersect_packet on each ISA from the same input packet; the packet
 * ends as the first ISA left it. */
static void trace_packet(accel *a, packet_range range)
{
    ray_packet *input = packet_new(), *first = packet_new();
    memcpy(input, range.packet, sizeof *input);
    bool have = false;
    for (size_t k = 0; k < ISA_COUNT; k++) {
        if (!accel_use_isa(a, isa_names[k]))
            continue;
        memcpy(range.packet, input, sizeof *input);
        accel_intersect_packet(a, range);
        if (!have) {
            memcpy(first, range.packet, sizeof *first);
            have = true;
        } else if (!packets_equal(first, range.packet))
            isa_disagreements++;
    }
    memcpy(range.packet, first, sizeof *first);
    free(input);
    free(first);
}

static uint64_t trace_packet_any(accel *a, packet_range range)
{
    ray_packet *input = packet_new(), *first = packet_new();
    memcpy(input, range.packet, sizeof *input);
    bool have = false;
    uint64_t mask = 0;
    for (size_t k = 0; k < ISA_COUNT; k++) {
        if (!accel_use_isa(a, isa_names[k]))
            continue;
        memcpy(range.packet, input, sizeof *input);
        uint64_t mk = accel_occluded_packet(a, range);
        if (!have) {
            memcpy(first, range.packet, sizeof *first);
            mask = mk;
            have = true;
        } else if (mk != mask || !packets_equal(first, range.packet))
            isa_disagreements++;
    }
    memcpy(range.packet, first, sizeof *first);
    free(input);
    free(first);
    return mask;
}

TestSuite(robust, .timeout = 300);

/* ------------------------------------------------------------------------ */
/* a. A closed mesh does not leak: rays from inside aimed at its vertices and
 * at points on its edges all hit it. */


/* Rays traced in packets of 64 through both packet entry points, counting
 * those that hit nothing. */
typedef struct leak_probe {
    accel *accel;
    ray_packet *packet;
    uint32_t fill;          /* rays waiting in the packet */
    uint64_t rays;          /* traced so far */
    uint64_t leaks_closest; /* accel_intersect_packet found no hit */
    uint64_t leaks_any;     /* accel_occluded_packet found no hit */
    ray first_leak;
    bool have_leak;
} leak_probe;

static void leak_flush(leak_probe *lp)
{
    ray_packet *p = lp->packet;
    if (lp->fill == 0)
        return;
    uint32_t n = lp->fill;
    p->count = n;
    p->active = packet_span_mask(0, n);
    packet_detect_facts(p);
    trace_packet(lp->accel, packet_whole(p));
    for (uint32_t i = 0; i < n; i++) {
        hit h = packet_get_hit(p, i);
        if (h.prim_id == RAY_INVALID_ID || !isfinite(h.t)) {
            if (!lp->have_leak) {
                lp->first_leak = packet_get_ray(p, i);
                lp->first_leak.t_far = FLT_MAX;
                lp->have_leak = true;
            }
            lp->leaks_closest++;
        }
        p->t_far[i] = FLT_MAX;
    }
    p->active = packet_span_mask(0, n);
    uint64_t occluded = trace_packet_any(lp->accel, packet_whole(p));
    for (uint32_t i = 0; i < n; i++)
        if (!(occluded >> i & 1u)) {
            if (!lp->have_leak) {
                lp->first_leak = packet_get_ray(p, i);
                lp->have_leak = true;
            }
            lp->leaks_any++;
        }
    lp->rays += n;
    lp->fill = 0;
}

static void leak_add(leak_probe *lp, vec3 org, vec3 target)
{
    if (lp->fill == 0)
        packet_reset(lp->packet, PACKET_MAX_RAYS, 0);
    ray r = make_ray(org, v3_sub(target, org), 0.f, FLT_MAX);
    packet_set_ray(lp->packet, lp->fill++, &r);
    if (lp->fill == PACKET_MAX_RAYS)
        leak_flush(lp);
}

Test(robust, closed_mesh_does_not_leak_at_vertices_or_edges)
{
    /* 64 x 40 UV sphere: 4992 triangles, 2498 vertices, 7488 edges. Per origin:
     * every vertex and 22 points on every edge; 2 origins per offset, 3 offsets:
     * 1,003,404 rays, each through both packet entry points. */
    const int slices = 64, stacks = 40, points_per_edge = 22;
    const double offsets[] = {0.0, 1e3, 1e5};
    rng g = {20261122};
    leak_probe lp = {.packet = packet_new()};
    uint64_t leaks_total = 0;
    for (size_t k = 0; k < sizeof offsets / sizeof offsets[0]; k++) {
        dvec centre = dv(offsets[k], offsets[k], offsets[k]);
        scene *s = scene_new();
        mesh *m = jittered_sphere(slices, stacks, 0.05, centre, &g);
        cr_assert(m);
        scene_put_mesh(s, m);
        lp.accel = accel_for(s);
        /* every vertex, then points_per_edge points on each undirected edge */
        vec3 *targets;
        size_t edges;
        size_t target_count = closed_mesh_targets(m, points_per_edge, &targets, &edges);
        cr_assert(target_count > 0);
        /* a closed genus-0 triangle mesh has E = 3V - 6 */
        cr_assert_eq(edges, 3 * (size_t)m->vertex_count - 6, "mesh not closed: %zu edges, %u vertices", edges,
                     m->vertex_count);
        vec3 origins[2] = {dv_round(centre), dv_round(dv_add(centre, dv(0.0731, -0.0412, 0.0253)))};
        uint64_t rays_before = lp.rays, leaks_before = lp.leaks_closest + lp.leaks_any;
        for (int o = 0; o < 2; o++)
            for (size_t i = 0; i < target_count; i++)
                leak_add(&lp, origins[o], targets[i]);
        leak_flush(&lp);
        uint64_t leaks = lp.leaks_closest + lp.leaks_any - leaks_before;
        cr_log_info("robust/closed mesh: offset %g: %llu rays, %llu leaks (closest-hit + any-hit)", offsets[k],
                    (unsigned long long)(lp.rays - rays_before), (unsigned long long)leaks);
        leaks_total += leaks;
        free(targets);
        accel_destroy(lp.accel);
        scene_destroy(s);
    }
    cr_log_info("robust/closed mesh: %llu rays in total; leaks: %llu closest-hit, %llu any-hit",
                (unsigned long long)lp.rays, (unsigned long long)lp.leaks_closest, (unsigned long long)lp.leaks_any);
    cr_expect_geq(lp.rays, 1000000u, "only %llu rays", (unsigned long long)lp.rays);
    if (lp.have_leak)
        cr_log_error("robust/closed mesh: first leak: " RAY_FMT, RAY_ARGS(lp.first_leak));
    cr_expect_eq(leaks_total, 0u, "%llu of %llu rays leaked out of a closed mesh", (unsigned long long)leaks_total,
                 (unsigned long long)lp.rays);
    free(lp.packet);
    expect_isas_agree("robust/closed mesh");
}

/* ------------------------------------------------------------------------ */
/* b. Slivers and zero-area triangles. */

Test(robust, slivers_are_hit_at_every_scale)
{
    /* 17 scales (longest edge 1e-8 .. 1e8), 40 orientations x 2 shapes each,
     * 150 rays per triangle: 204,000 rays. Each is aimed at an interior point
     * P whose barycentrics are all >= 0.2 (at least 0.2 sliver heights from
     * every edge), from an origin 1e-4 .. 1e-2 edge lengths away at >= 5 deg
     * from the plane. P is exact (double) and the direction is P - origin
     * rounded once, so the ray passes within ~1e-9 edge lengths of P: 1000x
     * inside the margin. A reference in double confirms every ray hits. */
    const int orientations = 40, rays_per_triangle = 150;
    rng g = {0x51713};
    uint64_t rays = 0, accel_misses = 0, direct_misses = 0, reference_misses = 0, nan_outputs = 0;
    int reported = 0;
    for (int e = -8; e <= 8; e++) {
        double len = pow(10.0, e);
        for (int o = 0; o < orientations; o++)
            for (int shape = 0; shape < 2; shape++) {
                vec3 v[3];
                random_sliver(&g, len, shape == 0, v);
                scene *s = scene_new();
                mesh *m = mesh_new();
                mesh_put_triangle_vertices(m, v[0], v[1], v[2]);
                scene_put_mesh(s, m);
                accel *a = accel_for(s);
                for (int k = 0; k < rays_per_triangle; k++) {
                    double b1, b2;
                    ray r = sliver_ray(&g, v, len, &b1, &b2);
                    rays++;
                    ref_triangle_hit ref = reference_triangle(&r, v[0], v[1], v[2]);
                    reference_misses += !reference_hits(&ref, r.t_near, r.t_far);
                    hit h;
                    bool got = trace_closest(a, &r, &h);
                    nan_outputs += hit_has_nan(&h);
                    ray_derived d = ray_derive(&r);
                    float t = -1.f, u = -1.f, vv = -1.f;
                    bool direct = intersect_triangle(&r, &d, v[0], v[1], v[2], &t, &u, &vv);
                    nan_outputs += isnan(t) || isnan(u) || isnan(vv);
                    if (!got || h.prim_id != 0 || h.geom_id != 0) {
                        accel_misses++;
                        if (reported++ < MAX_REPORTED)
                            cr_log_error("robust/slivers: accel_intersect misses " RAY_FMT " aimed at barycentrics "
                                         "(%.3f, %.3f, %.3f) of " TRI_FMT,
                                         RAY_ARGS(r), 1.0 - b1 - b2, b1, b2, TRI_ARGS(v[0], v[1], v[2]));
                    }
                    direct_misses += !direct;
                }
                accel_destroy(a);
                scene_destroy(s);
            }
    }
    uint64_t allowed = rays / 10000; /* 99.99 % must hit */
    cr_log_info("robust/slivers: %llu rays at aspect ratio 1e6, edge lengths 1e-8..1e8: %llu misses through "
                "accel_intersect, %llu through intersect_triangle (allowed %llu each); reference misses %llu; "
                "NaN outputs %llu",
                (unsigned long long)rays, (unsigned long long)accel_misses, (unsigned long long)direct_misses,
                (unsigned long long)allowed, (unsigned long long)reference_misses, (unsigned long long)nan_outputs);
    cr_assert_eq(reference_misses, 0u, "test construction: the reference misses %llu rays",
                 (unsigned long long)reference_misses);
    cr_expect_leq(accel_misses, allowed, "accel_intersect hit only %.5f %% of sliver rays",
                  100.0 * (double)(rays - accel_misses) / (double)rays);
    cr_expect_leq(direct_misses, allowed, "intersect_triangle hit only %.5f %% of sliver rays",
                  100.0 * (double)(rays - direct_misses) / (double)rays);
    cr_expect_eq(nan_outputs, 0u);
    expect_isas_agree("robust/slivers");
}

Test(robust, zero_area_triangles_are_never_hit)
{
    /* Exactly degenerate in float: every coordinate is a small integer times a
     * power of two 2^-27 .. 2^27 (about 7e-9 .. 1.3e8), so the three vertices
     * are exactly collinear or coincident. Four kinds: collinear in a general
     * direction, collinear along an axis, two vertices coincident, all three
     * coincident. Rays are aimed at the vertices, at points on the segment and
     * at points within 1e-3 of the segment's length of it, from random origins
     * at 1 .. 100 segment lengths, plus rays along the segment's own line. */
    static const int kinds = 4;
    static const float ints[4][3][3] = {
        {{3, -5, 7}, {4, -3, 4}, {8, 5, -8}},  /* p, p + d, p + 5d with d = (1, 2, -3) */
        {{1, 2, 3}, {4, 2, 3}, {9, 2, 3}},     /* along x */
        {{3, -5, 7}, {3, -5, 7}, {4, -3, 4}},  /* v0 == v1 */
        {{3, -5, 7}, {3, -5, 7}, {3, -5, 7}},  /* a point */
    };
    rng g = {0xDE9E};
    uint64_t rays = 0, hits_accel = 0, hits_direct = 0, hits_occluded = 0, nan_outputs = 0;
    int reported = 0;
    for (int e = -27; e <= 27; e += 3) {
        float scale = ldexpf(1.f, e);
        scene *s = scene_new();
        mesh *m = mesh_new();
        vec3 tri[4][3];
        for (int k = 0; k < kinds; k++) {
            for (int i = 0; i < 3; i++)
                tri[k][i] = v3_scale(v3(ints[k][i][0], ints[k][i][1], ints[k][i][2]), scale);
            mesh_put_triangle_vertices(m, tri[k][0], tri[k][1], tri[k][2]);
        }
        scene_put_mesh(s, m);
        accel *a = accel_for(s);
        for (int k = 0; k < kinds; k++) {
            dvec p0 = dv_of(tri[k][0]), p2 = dv_of(tri[k][2]);
            double len = fmax(dv_len(dv_sub(p2, p0)), (double)scale);
            for (int j = 0; j < 400; j++) {
                dvec target;
                int what = j % 8;
                if (what < 3)
                    target = dv_of(tri[k][what]);
                else if (what < 6)
                    target = dv_add(p0, dv_scale(dv_sub(p2, p0), rng_unit(&g)));
                else
                    target = dv_add(dv_add(p0, dv_scale(dv_sub(p2, p0), rng_unit(&g))),
                                    dv_scale(dv_random_unit(&g), 1e-3 * len * rng_unit(&g)));
                vec3 org;
                if (j % 50 == 49 && k < 2) /* along the segment's line, from outside it */
                    org = dv_round(dv_add(p0, dv_scale(dv_sub(p0, p2), rng_range(&g, 0.5, 3.0))));
                else
                    org = dv_round(dv_add(target, dv_scale(dv_random_unit(&g), len * rng_log_range(&g, 1, 100))));
                ray r = make_ray(org, dv_round(dv_sub(target, dv_of(org))), 0.f, FLT_MAX);
                rays++;
                hit h;
                bool got = trace_closest(a, &r, &h);
                hits_accel += got;
                nan_outputs += hit_has_nan(&h);
                hits_occluded += trace_any(a, &r);
                ray_derived d = ray_derive(&r);
                float t = -1.f, u = -1.f, v = -1.f;
                bool direct = intersect_triangle(&r, &d, tri[k][0], tri[k][1], tri[k][2], &t, &u, &v);
                hits_direct += direct;
                nan_outputs += isnan(t) || isnan(u) || isnan(v);
                if ((got || direct) && reported++ < MAX_REPORTED)
                    cr_log_error("robust/zero area: hit (accel %d: prim %u t %a; intersect_triangle %d) " RAY_FMT
                                 " on " TRI_FMT,
                                 got, h.prim_id, h.t, direct, RAY_ARGS(r), TRI_ARGS(tri[k][0], tri[k][1], tri[k][2]));
            }
        }
        accel_destroy(a);
        scene_destroy(s);
    }
    cr_log_info("robust/zero area: %llu rays at collinear and coincident triangles (scales 2^-27..2^27): hits %llu "
                "accel_intersect, %llu accel_occluded, %llu intersect_triangle; NaN outputs %llu",
                (unsigned long long)rays, (unsigned long long)hits_accel, (unsigned long long)hits_occluded,
                (unsigned long long)hits_direct, (unsigned long long)nan_outputs);
    cr_expect_eq(hits_accel, 0u);
    cr_expect_eq(hits_occluded, 0u);
    cr_expect_eq(hits_direct, 0u);
    cr_expect_eq(nan_outputs, 0u);
    expect_isas_agree("robust/zero area");
}

/* ------------------------------------------------------------------------ */
/* c. Grazing rays against a double-precision reference. */

/* Distance in world units below which a reference hit point counts as "on an
 * edge" and hit/miss is not compared: 2 float ulps of the point's largest
 * coordinate, the closest a float kernel can place the crossing. */
#define GRAZING_EDGE_BAND_ULPS 2.0
/* A grazing ray's t is ill-conditioned: moving the float ray by one ulp moves
 * its crossing by about ulp / angle along the ray, so no float kernel can give
 * t to a few ulps forward. The criterion is backward: the reported hit point
 * org + t dir (in double) lies within GRAZING_PLANE_ULPS float ulps of the
 * largest coordinate involved from the triangle's plane - as close as a float
 * point can be. The forward t error is logged. */
#define GRAZING_PLANE_ULPS 16.0
/* The crossing must be clear of t_near = 0 by this many ulps of the side to be compared. */
#define GRAZING_T_ULPS 16.0

/* Per decade of the angle between the ray and the triangle's plane. */
typedef struct grazing_tally {
    uint64_t rays, compared, in_band, mismatches, t_mismatches;
    double worst_t_error; /* largest |t - t_ref| / t_ref among agreeing hits */
} grazing_tally;

Test(robust, grazing_rays_agree_with_double_reference)
{
    /* 600 triangles (every 4th in an axis-aligned plane, the others rotated at
     * random), sides 0.1 .. 10, within 10 of the origin; 200 rays each at an
     * angle of 1e-3 .. 1e-7 rad (log-uniform) to the plane, aimed at
     * barycentrics -0.1 .. 1.1 (so both hits and misses), from 0.5 .. 3 sides
     * away. The float ray (rounded once from the construction) is the problem;
     * the reference solves exactly that float ray in double.
     * Criteria: hit/miss equal to the reference for every ray farther than the
     * edge band from every edge (GRAZING_EDGE_BAND_ULPS); the hit point within
     * GRAZING_PLANE_ULPS of the plane; for 5 values of t_near (just below,
     * at and just above the float of the reference t, half and twice it) and
     * the same 5 of t_far, no hit outside (t_near, t_far], and hit/miss equal
     * to the reference where the bound is a factor 2 away from t;
     * accel_intersect on a scene of that one triangle bit-identical to
     * intersect_triangle. */
    const int triangles = 600, rays_per_triangle = 200;
    rng g = {0x62A21E};
    grazing_tally tally[2][4]; /* [axis-aligned][decade of the angle: 1e-4..1e-3 first] */
    memset(tally, 0, sizeof tally);
    uint64_t interval_violations = 0, bound_mismatches = 0, accel_differs = 0, nan_outputs = 0, parallel_hits = 0;
    int reported = 0;
    for (int tri = 0; tri < triangles; tri++) {
        bool axis_aligned = tri % 4 == 0;
        double side = rng_log_range(&g, 0.1, 10.0);
        dvec e0, e1, e2;
        if (axis_aligned) {
            dvec axes[3] = {dv(1, 0, 0), dv(0, 1, 0), dv(0, 0, 1)};
            int k = (tri / 4) % 3;
            e0 = axes[k];
            e1 = axes[(k + 1) % 3];
            e2 = axes[(k + 2) % 3];
        } else
            random_basis(&g, &e0, &e1, &e2);
        dvec origin = dv(rng_range(&g, -10, 10), rng_range(&g, -10, 10), rng_range(&g, -10, 10));
        double local[3][2] = {{0, 0},
                              {1 + rng_range(&g, -0.2, 0.2), rng_range(&g, -0.2, 0.2)},
                              {rng_range(&g, 0, 0.6), 1 + rng_range(&g, -0.2, 0.2)}};
        vec3 v[3];
        for (int i = 0; i < 3; i++)
            v[i] = dv_round(dv_add(origin, dv_add(dv_scale(e0, side * local[i][0]), dv_scale(e1, side * local[i][1]))));
        dvec dvv[3] = {dv_of(v[0]), dv_of(v[1]), dv_of(v[2])};
        dvec normal = dv_cross(dv_sub(dvv[1], dvv[0]), dv_sub(dvv[2], dvv[0]));
        double twice_area = dv_len(normal);
        normal = dv_scale(normal, 1.0 / twice_area);
        double height[3]; /* of each vertex above its opposite edge */
        for (int i = 0; i < 3; i++)
            height[i] = twice_area / dv_len(dv_sub(dvv[(i + 2) % 3], dvv[(i + 1) % 3]));
        scene *s = scene_new();
        mesh *m = mesh_new();
        mesh_put_triangle_vertices(m, v[0], v[1], v[2]);
        scene_put_mesh(s, m);
        accel *a = accel_for(s);
        for (int k = 0; k < rays_per_triangle; k++) {
            double log_angle = rng_range(&g, -7.0, -3.0);
            double angle = pow(10.0, log_angle);
            int decade = (int)floor(-log_angle) - 3;
            grazing_tally *tl = &tally[axis_aligned][decade < 0 ? 0 : decade > 3 ? 3 : decade];
            dvec in_plane = dv_random_perpendicular(normal, &g);
            double sign = rng_unit(&g) < 0.5 ? -1.0 : 1.0;
            dvec dir = dv_add(dv_scale(in_plane, cos(angle)), dv_scale(normal, sign * sin(angle)));
            double b1 = rng_range(&g, -0.1, 1.1), b2 = rng_range(&g, -0.1, 1.1 - b1);
            dvec target = dv_add(dvv[0], dv_add(dv_scale(dv_sub(dvv[1], dvv[0]), b1),
                                                dv_scale(dv_sub(dvv[2], dvv[0]), b2)));
            vec3 org = dv_round(dv_sub(target, dv_scale(dir, side * rng_range(&g, 0.5, 3.0))));
            ray r = make_ray(org, dv_round(dv_unit(dv_sub(target, dv_of(org)))), 0.f, FLT_MAX);
            tl->rays++;
            ref_triangle_hit ref = reference_triangle(&r, v[0], v[1], v[2]);
            ray_derived d = ray_derive(&r);
            float t = -1.f, u = -1.f, w = -1.f;
            bool got = intersect_triangle(&r, &d, v[0], v[1], v[2], &t, &u, &w);
            nan_outputs += isnan(t) || isnan(u) || isnan(w);
            hit h;
            bool got_accel = trace_closest(a, &r, &h);
            nan_outputs += hit_has_nan(&h);
            hit direct = got ? (hit){.t = t, .u = u, .v = w, .prim_id = 0, .geom_id = 0} : hit_none();
            if (got_accel != got || !hits_identical(&h, &direct))
                accel_differs++;
            if (!ref.crosses) { /* parallel to the plane (the origin rounded into it): no crossing to hit */
                parallel_hits += got;
                continue;
            }
            dvec crossing = dv_add(dv_of(r.org), dv_scale(dv_of(r.dir), ref.t));
            double band = GRAZING_EDGE_BAND_ULPS * float_ulp(dv_max_abs(crossing));
            bool near_edge = false;
            for (int i = 0; i < 3; i++)
                near_edge |= fabs(ref.b[i] * height[i]) <= band;
            /* the crossing must also be clear of t_near = 0 by the t tolerance */
            if (near_edge || fabs(ref.t) <= GRAZING_T_ULPS * float_ulp(side)) {
                tl->in_band++;
                continue;
            }
            tl->compared++;
            bool want = reference_hits(&ref, r.t_near, r.t_far);
            if (got != want) {
                tl->mismatches++;
                if (reported++ < MAX_REPORTED)
                    cr_log_error("robust/grazing: intersect_triangle %s, reference %s (barycentrics %.9g %.9g %.9g, "
                                 "t %.9g, angle %.3g rad): " RAY_FMT " on " TRI_FMT,
                                 got ? "hit" : "miss", want ? "hit" : "miss", ref.b[0], ref.b[1], ref.b[2], ref.t,
                                 angle,
                                 RAY_ARGS(r), TRI_ARGS(v[0], v[1], v[2]));
                continue;
            }
            if (!want)
                continue;
            double t_error = fabs((double)t - ref.t) / ref.t;
            /* backward error: distance of the reported point from the plane */
            dvec p0 = dv_of(v[0]), hit_point = dv_add(dv_of(r.org), dv_scale(dv_of(r.dir), (double)t));
            dvec plane_n = dv_cross(dv_sub(dv_of(v[1]), p0), dv_sub(dv_of(v[2]), p0));
            double plane_distance = fabs(dv_dot(dv_sub(hit_point, p0), plane_n)) / sqrt(dv_dot(plane_n, plane_n));
            double magnitude = fmax(dv_max_abs(crossing), fmax(dv_max_abs(dv_of(r.org)),
                                    fmax(dv_max_abs(p0), fmax(dv_max_abs(dv_of(v[1])), dv_max_abs(dv_of(v[2]))))));
            if (plane_distance > GRAZING_PLANE_ULPS * float_ulp(magnitude)) {
                tl->t_mismatches++;
                if (reported++ < MAX_REPORTED)
                    cr_log_error("robust/grazing: t %a, reference %.17g: hit point %.3g off the plane, %.3g ulps "
                                 "(angle %.3g rad): " RAY_FMT " on " TRI_FMT,
                                 t, ref.t, plane_distance, plane_distance / float_ulp(magnitude), angle, RAY_ARGS(r),
                                 TRI_ARGS(v[0], v[1], v[2]));
            }
            tl->worst_t_error = fmax(tl->worst_t_error, t_error);
            /* the interval bounds around the reference t */
            float tf = (float)ref.t;
            float bounds[5] = {nextafterf(tf, 0.f), tf, nextafterf(tf, INFINITY), 0.5f * tf, 2.f * tf};
            for (int j = 0; j < 10; j++) {
                ray rb = r;
                if (j < 5)
                    rb.t_near = bounds[j];
                else
                    rb.t_far = bounds[j - 5];
                ray_derived db = ray_derive(&rb);
                float tb = NAN, ub, vb;
                bool got_b = intersect_triangle(&rb, &db, v[0], v[1], v[2], &tb, &ub, &vb);
                hit hb;
                bool got_ba = trace_closest(a, &rb, &hb);
                if ((got_b && !(tb > rb.t_near && tb <= rb.t_far)) ||
                    (got_ba && !(hb.t > rb.t_near && hb.t <= rb.t_far))) {
                    interval_violations++;
                    if (reported++ < MAX_REPORTED)
                        cr_log_error("robust/grazing: hit at t %a / %a outside " RAY_FMT, tb, hb.t, RAY_ARGS(rb));
                }
                if (j % 5 >= 3) { /* the bound is a factor 2 from t: the answer is certain */
                    bool want_b = reference_hits(&ref, rb.t_near, rb.t_far);
                    bound_mismatches += (got_b != want_b) + (got_ba != want_b);
                }
            }
        }
        accel_destroy(a);
        scene_destroy(s);
    }
    uint64_t compared = 0, mismatches = 0, t_mismatches = 0;
    for (int aligned = 0; aligned < 2; aligned++)
        for (int k = 0; k < 4; k++) {
            grazing_tally *tl = &tally[aligned][k];
            cr_log_info("robust/grazing: %s plane, angle 1e-%d..1e-%d rad: %llu rays, %llu compared, %llu within "
                        "the edge band; %llu hit/miss mismatches, %llu hit points off the plane (worst forward relative t "
                        "error %.3g)",
                        aligned ? "axis-aligned" : "rotated", k + 4, k + 3, (unsigned long long)tl->rays,
                        (unsigned long long)tl->compared, (unsigned long long)tl->in_band,
                        (unsigned long long)tl->mismatches, (unsigned long long)tl->t_mismatches, tl->worst_t_error);
            compared += tl->compared;
            mismatches += tl->mismatches;
            t_mismatches += tl->t_mismatches;
        }
    cr_log_info("robust/grazing: %llu rays compared: %llu hit/miss mismatches, %llu hit points off the plane, %llu "
                "hits outside "
                "(t_near, t_far], %llu wrong answers with a bound 2x from t, %llu accel/intersect_triangle "
                "differences, %llu hits by rays parallel to the plane, %llu NaN outputs",
                (unsigned long long)compared, (unsigned long long)mismatches, (unsigned long long)t_mismatches,
                (unsigned long long)interval_violations, (unsigned long long)bound_mismatches,
                (unsigned long long)accel_differs, (unsigned long long)parallel_hits, (unsigned long long)nan_outputs);
    cr_expect_eq(mismatches, 0u);
    cr_expect_eq(t_mismatches, 0u);
    cr_expect_eq(interval_violations, 0u);
    cr_expect_eq(bound_mismatches, 0u);
    cr_expect_eq(accel_differs, 0u);
    cr_expect_eq(parallel_hits, 0u);
    cr_expect_eq(nan_outputs, 0u);
    expect_isas_agree("robust/grazing");
}

/* ------------------------------------------------------------------------ */
/* d. Axis-parallel rays starting on slab planes: the BVH equals brute force. */

/* A staircase of unit quads at integer coordinates (+ `shift`, integer): step k
 * has a tread in y = k (x in [k, k+1]) and a riser in x = k+1 (y in [k, k+1]),
 * each `width` quads deep in z. Quads alternate their diagonal. Every
 * coordinate is an integer, so every box of the BVH has its faces on integer
 * planes. */
static mesh *staircase(int steps, int width, dvec shift)
{
    mesh *m = mesh_new();
    for (int k = 0; k < steps; k++)
        for (int j = 0; j < width; j++)
            for (int riser = 0; riser < 2; riser++) {
                dvec c[4];
                if (!riser) {
                    c[0] = dv(k, k, j), c[1] = dv(k + 1, k, j), c[2] = dv(k + 1, k, j + 1), c[3] = dv(k, k, j + 1);
                } else {
                    c[0] = dv(k + 1, k, j), c[1] = dv(k + 1, k + 1, j), c[2] = dv(k + 1, k + 1, j + 1),
                    c[3] = dv(k + 1, k, j + 1);
                }
                uint32_t i = m->vertex_count;
                for (int q = 0; q < 4; q++)
                    mesh_put_vertex(m, dv_round(dv_add(shift, c[q])));
                if ((k + j + riser) % 2) {
                    mesh_put_triangle(m, i, i + 1, i + 2);
                    mesh_put_triangle(m, i, i + 2, i + 3);
                } else {
                    mesh_put_triangle(m, i, i + 1, i + 3);
                    mesh_put_triangle(m, i + 1, i + 2, i + 3);
                }
            }
    return m;
}

/* Closest hit over every triangle of a one-mesh scene by intersect_triangle:
 * smallest t, ties to the lowest primitive id (accel.h's rule). */
static bool brute_force_closest(const mesh *m, const ray *r, hit *out)
{
    *out = hit_none();
    if (ray_is_degenerate(r))
        return false;
    ray_derived d = ray_derive(r);
    for (uint32_t i = 0; i < m->triangle_count; i++) {
        vec3 v0, v1, v2;
        float t, u, v;
        triangle_vertices(m, i, &v0, &v1, &v2);
        if (intersect_triangle(r, &d, v0, v1, v2, &t, &u, &v) && t < out->t)
            *out = (hit){.t = t, .u = u, .v = v, .prim_id = i, .geom_id = 0};
    }
    return out->prim_id != RAY_INVALID_ID;
}

Test(robust, axis_parallel_rays_on_slab_planes_match_brute_force)
{
    /* 6 steps x 3 quads deep (72 triangles), at the origin and shifted by
     * (1024, -2048, 4096). Origins on a lattice of spacing 0.5 covering the
     * staircase and a margin of 1 (3179 origins, so most lie on box planes,
     * many on edges), in each of the 6 axis directions with every sign of
     * zero in the other two components (24 directions), with t in (0, max],
     * (1, max] and (0, 2] (hits exactly at t_near = 1 are excluded, exactly at
     * t_far = 2 included): 457,776 rays. Criterion: accel_intersect equals
     * brute force on every ray (same primitive, same t, u, v bits) and
     * accel_occluded agrees with it. */
    const int steps = 6, width = 3;
    const dvec shifts[2] = {dv(0, 0, 0), dv(1024, -2048, 4096)};
    const float t_ranges[3][2] = {{0.f, FLT_MAX}, {1.f, FLT_MAX}, {0.f, 2.f}};
    uint64_t rays = 0, hits = 0, hit_miss = 0, tie_break = 0, wrong_t = 0, occluded_wrong = 0;
    int reported = 0;
    for (int sh = 0; sh < 2; sh++) {
        scene *s = scene_new();
        mesh *m = staircase(steps, width, shifts[sh]);
        scene_put_mesh(s, m);
        accel *a = accel_for(s);
        for (int ix = -2; ix <= 2 * steps + 2; ix++)
            for (int iy = -2; iy <= 2 * steps + 2; iy++)
                for (int iz = -2; iz <= 2 * width + 2; iz++) {
                    vec3 org = dv_round(dv_add(shifts[sh], dv(0.5 * ix, 0.5 * iy, 0.5 * iz)));
                    for (int dir_index = 0; dir_index < 24; dir_index++) {
                        int axis = dir_index % 3;
                        float sign = dir_index / 3 % 2 ? -1.f : 1.f;
                        float zero_a = dir_index / 6 % 2 ? -0.f : 0.f, zero_b = dir_index / 12 ? -0.f : 0.f;
                        float c[3];
                        c[axis] = sign;
                        c[(axis + 1) % 3] = zero_a;
                        c[(axis + 2) % 3] = zero_b;
                        for (int tr = 0; tr < 3; tr++) {
                            ray r = make_ray(org, v3(c[0], c[1], c[2]), t_ranges[tr][0], t_ranges[tr][1]);
                            hit want, got;
                            bool want_hit = brute_force_closest(m, &r, &want);
                            bool got_hit = trace_closest(a, &r, &got);
                            rays++;
                            hits += want_hit;
                            occluded_wrong += trace_any(a, &r) != want_hit;
                            if (hits_identical(&want, &got))
                                continue;
                            const char *what;
                            if (want_hit != got_hit) {
                                hit_miss++;
                                what = "hit/miss";
                            } else if (same_bits(want.t, got.t)) {
                                tie_break++;
                                what = "tie (same t)";
                            } else {
                                wrong_t++;
                                what = "t";
                            }
                            if (reported++ < MAX_REPORTED)
                                cr_log_error("robust/staircase: %s: accel prim %u t %a, brute force prim %u t %a: "
                                             RAY_FMT,
                                             what, got.prim_id, got.t, want.prim_id, want.t, RAY_ARGS(r));
                        }
                    }
                }
        accel_destroy(a);
        scene_destroy(s);
    }
    cr_log_info("robust/staircase: %llu axis-parallel rays from slab planes (%llu hit): accel_intersect differs from "
                "brute force on %llu (hit/miss %llu, ties broken differently %llu, other t %llu); accel_occluded wrong "
                "on %llu",
                (unsigned long long)rays, (unsigned long long)hits,
                (unsigned long long)(hit_miss + tie_break + wrong_t), (unsigned long long)hit_miss,
                (unsigned long long)tie_break, (unsigned long long)wrong_t, (unsigned long long)occluded_wrong);
    cr_expect_eq(hit_miss + tie_break + wrong_t, 0u);
    cr_expect_eq(occluded_wrong, 0u);
    expect_isas_agree("robust/staircase");
}

/* ------------------------------------------------------------------------ */
/* Shared by e and f: a scene with two meshes and a set of spheres (geometry
 * ids 0, 1 and 2). */

static scene *mixed_scene(rng *g)
{
    scene *s = scene_new();
    mesh *ball = jittered_sphere(24, 12, 0.05, dv(0, 0, 0), g);
    cr_assert(ball);
    scene_put_mesh(s, ball);
    mesh *ground = mesh_new();
    for (int i = 0; i <= 4; i++)
        for (int j = 0; j <= 4; j++)
            mesh_put_vertex(ground, v3(-10.f + 5.f * (float)i, -1.5f, -10.f + 5.f * (float)j));
    for (uint32_t i = 0; i < 4; i++)
        for (uint32_t j = 0; j < 4; j++) {
            uint32_t c = i * 5 + j;
            mesh_put_triangle(ground, c, c + 1, c + 6);
            mesh_put_triangle(ground, c, c + 6, c + 5);
        }
    scene_put_mesh(s, ground);
    for (int i = 0; i < 24; i++) {
        vec3 c = dv_round(dv(rng_range(g, -4, 4), rng_range(g, -1.5, 3), rng_range(g, -4, 4)));
        cr_assert(scene_add_sphere(s, c, (float)rng_range(g, 0.1, 0.6), 0) >= 0);
    }
    return s;
}

/* ------------------------------------------------------------------------ */
/* e. Degenerate rays miss, through every entry point. */

Test(robust, degenerate_rays_miss_everywhere)
{
    /* 19 degenerate variants of a ray that hits (NaN and infinities in the
     * origin, the direction and the bounds; zero directions; empty intervals):
     * each must miss through accel_intersect (and leave hit_none() exactly),
     * accel_occluded, and both packet functions, where they share packets with
     * good rays that must still get their single-ray answers. Also 9 extreme
     * but valid rays (huge, tiny and subnormal directions, origins near
     * FLT_MAX, infinite bounds, which ray.h allows): no NaN in any output, hits
     * inside (t_near, t_far]. */
    rng g = {0xBAD};
    scene *s = mixed_scene(&g);
    accel *a = accel_for(s);
    const vec3 org = v3(0.f, 0.f, 5.f), dir = v3(0.f, 0.f, -1.f);
    ray base = make_ray(org, dir, 0.f, FLT_MAX);
    hit base_hit;
    cr_assert(trace_closest(a, &base, &base_hit), "the base ray must hit");
    const float t_hit = base_hit.t, nan = NAN, inf = INFINITY;
    const ray degenerate[] = {
        make_ray(v3(nan, 0.f, 5.f), dir, 0.f, FLT_MAX),
        make_ray(v3(0.f, -nan, 5.f), dir, 0.f, FLT_MAX),
        make_ray(v3(0.f, inf, 5.f), dir, 0.f, FLT_MAX),
        make_ray(v3(0.f, 0.f, -inf), dir, 0.f, FLT_MAX),
        make_ray(org, v3(nan, 0.f, -1.f), 0.f, FLT_MAX),
        make_ray(org, v3(0.f, 0.f, nan), 0.f, FLT_MAX),
        make_ray(org, v3(inf, 0.f, -1.f), 0.f, FLT_MAX),
        make_ray(org, v3(0.f, 0.f, -inf), 0.f, FLT_MAX),
        make_ray(org, v3(0.f, 0.f, 0.f), 0.f, FLT_MAX),
        make_ray(org, v3(-0.f, 0.f, -0.f), 0.f, FLT_MAX),
        make_ray(org, dir, nan, FLT_MAX),
        make_ray(org, dir, 0.f, nan),
        make_ray(org, dir, nan, nan),
        make_ray(org, dir, t_hit + 1.f, t_hit - 1.f), /* t_near > t_far around the hit */
        make_ray(org, dir, t_hit, t_hit),             /* t_near == t_far == the hit's t */
        make_ray(org, dir, 0.f, 0.f),
        make_ray(org, dir, inf, inf),
        make_ray(org, dir, -inf, -inf),
        make_ray(org, dir, inf, FLT_MAX),
    };
    const size_t degenerate_count = sizeof degenerate / sizeof degenerate[0];
    const ray extreme[] = {
        make_ray(org, v3(FLT_MAX, FLT_MAX, -FLT_MAX), 0.f, FLT_MAX),
        make_ray(org, v3(1e-30f, 1e-30f, -1e-30f), 0.f, FLT_MAX),
        make_ray(org, v3(FLT_TRUE_MIN, 0.f, -FLT_TRUE_MIN), 0.f, FLT_MAX),
        make_ray(org, v3(0.f, 0.f, -FLT_TRUE_MIN), 0.f, FLT_MAX),
        make_ray(v3(1e30f, 0.f, 0.f), v3(-1.f, 0.f, 0.f), 0.f, FLT_MAX),
        make_ray(v3(-FLT_MAX, 0.1f, 0.1f), v3(1.f, 0.f, 0.f), 0.f, inf),
        make_ray(org, dir, 0.f, inf),
        make_ray(org, dir, -inf, inf),
        make_ray(org, dir, -FLT_MAX, FLT_MAX),
    };
    const size_t extreme_count = sizeof extreme / sizeof extreme[0];
    uint64_t not_missed = 0, nan_outputs = 0, bad_extreme = 0, packet_wrong = 0;
    for (size_t i = 0; i < degenerate_count; i++) {
        hit h;
        bool got = trace_closest(a, &degenerate[i], &h);
        bool occluded = trace_any(a, &degenerate[i]);
        nan_outputs += hit_has_nan(&h);
        if (got || !hit_is_none(&h) || occluded) {
            not_missed++;
            cr_log_error("robust/degenerate: not a miss (intersect %d, occluded %d): " RAY_FMT, got, occluded,
                         RAY_ARGS(degenerate[i]));
        }
    }
    hit inf_hit;
    trace_closest(a, &extreme[6], &inf_hit);
    cr_expect(hits_identical(&inf_hit, &base_hit), "t_far = +inf must give the same hit as t_far = FLT_MAX");
    for (size_t i = 0; i < extreme_count; i++) {
        const ray *r = &extreme[i];
        hit h;
        bool got = trace_closest(a, r, &h);
        trace_any(a, r);
        nan_outputs += hit_has_nan(&h);
        bool consistent = got ? h.t > r->t_near && h.t <= r->t_far && isfinite(h.u) && isfinite(h.v) &&
                                    h.geom_id < 3 && h.prim_id != RAY_INVALID_ID
                              : hit_is_none(&h);
        if (!consistent) {
            bad_extreme++;
            cr_log_error("robust/degenerate: inconsistent hit (t %a, prim %u, geom %u) for " RAY_FMT, h.t, h.prim_id,
                         h.geom_id, RAY_ARGS(*r));
        }
    }
    /* packets: degenerate, extreme and good rays interleaved, at every offset */
    ray_packet *p = packet_new();
    for (uint32_t shift = 0; shift < 8; shift++) {
        ray rays[PACKET_MAX_RAYS];
        packet_reset(p, PACKET_MAX_RAYS, 0);
        for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++) {
            uint32_t k = i + shift;
            if (k % 3 == 0)
                rays[i] = degenerate[k / 3 % degenerate_count];
            else if (k % 3 == 1)
                rays[i] = extreme[k / 3 % extreme_count];
            else
                rays[i] = make_ray(dv_round(dv(rng_range(&g, -6, 6), rng_range(&g, -1, 6), 8.0)),
                                   dv_round(dv(rng_range(&g, -0.5, 0.5), rng_range(&g, -0.5, 0.2), -1.0)), 0.f,
                                   FLT_MAX);
            packet_set_ray(p, i, &rays[i]);
        }
        trace_packet(a, packet_whole(p));
        for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++) {
            hit want, got = packet_get_hit(p, i);
            bool want_hit = trace_closest(a, &rays[i], &want);
            nan_outputs += hit_has_nan(&got);
            bool t_far_right = want_hit ? same_bits(p->t_far[i], want.t) : same_bits(p->t_far[i], rays[i].t_far);
            if (!hits_identical(&got, &want) || !t_far_right) {
                packet_wrong++;
                cr_log_error("robust/degenerate: packet lane %u: prim %u t %a, single ray prim %u t %a: " RAY_FMT, i,
                             got.prim_id, got.t, want.prim_id, want.t, RAY_ARGS(rays[i]));
            }
        }
        for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++)
            packet_set_ray(p, i, &rays[i]);
        p->active = ~0ull;
        uint64_t occluded = trace_packet_any(a, packet_whole(p));
        for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++)
            if ((occluded >> i & 1u) != (uint64_t)trace_any(a, &rays[i])) {
                packet_wrong++;
                cr_log_error("robust/degenerate: occluded packet lane %u differs from accel_occluded: " RAY_FMT, i,
                             RAY_ARGS(rays[i]));
            }
    }
    cr_log_info("robust/degenerate: %zu degenerate rays: %llu not missed; %zu extreme rays: %llu inconsistent; "
                "packet lanes differing from single rays: %llu; NaN outputs: %llu",
                degenerate_count, (unsigned long long)not_missed, extreme_count, (unsigned long long)bad_extreme,
                (unsigned long long)packet_wrong, (unsigned long long)nan_outputs);
    cr_expect_eq(not_missed, 0u);
    cr_expect_eq(bad_extreme, 0u);
    cr_expect_eq(packet_wrong, 0u);
    cr_expect_eq(nan_outputs, 0u);
    free(p);
    accel_destroy(a);
    scene_destroy(s);
    expect_isas_agree("robust/degenerate");
}

/* ------------------------------------------------------------------------ */
/* f. Packets give exactly the single-ray answers and touch nothing else. */

enum packet_kind { PACKET_KIND_MIXED, PACKET_KIND_COMMON_ORIGIN, PACKET_KIND_PRIMARY };

/* Does ray i of `a` equal ray i of `b` in every per-ray array? */
static bool lane_unchanged(const ray_packet *a, const ray_packet *b, uint32_t i)
{
    const float *fa[] = {a->org_x, a->org_y, a->org_z, a->dir_x, a->dir_y, a->dir_z, a->t_near, a->t_far, a->hit_t,
                         a->hit_u, a->hit_v};
    const float *fb[] = {b->org_x, b->org_y, b->org_z, b->dir_x, b->dir_y, b->dir_z, b->t_near, b->t_far, b->hit_t,
                         b->hit_u, b->hit_v};
    for (size_t k = 0; k < sizeof fa / sizeof fa[0]; k++)
        if (!same_bits(fa[k][i], fb[k][i]))
            return false;
    return a->prim_id[i] == b->prim_id[i] && a->geom_id[i] == b->geom_id[i] && a->material_id[i] == b->material_id[i];
}

Test(robust, packets_match_single_rays_bit_for_bit)
{
    /* Every width 1..64 (primary packets: every tile of 1..8 x 1..8), 3 kinds
     * (mixed origins and directions with no facts; a common origin with the
     * facts packet_detect_facts finds; packet_primary), 12 packets each, random
     * active masks and sub-ranges [begin, end). Criteria: every active ray in
     * the range gets exactly accel_intersect's hit record (memcmp of t, u, v,
     * prim_id, geom_id) and t_far = t on a hit; accel_occluded_packet returns
     * exactly the accel_occluded mask of those rays; every other ray (inactive,
     * outside the range, or beyond count) is untouched in every array. */
    rng g = {0xFACE};
    scene *s = mixed_scene(&g);
    accel *a = accel_for(s);
    camera_desc cam_desc = {v3(0.5f, 1.f, 7.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    camera_basis cam = camera_basis_make(&cam_desc, 64, 48);
    ray_packet *p = packet_new(), *before = packet_new();
    uint64_t packets = 0, lanes = 0, lane_hits = 0, wrong_hits = 0, touched = 0, wrong_occluded = 0;
    int reported = 0;
    for (int kind = 0; kind < 3; kind++)
        for (uint32_t width = 1; width <= PACKET_MAX_RAYS; width++)
            for (int trial = 0; trial < 12; trial++) {
                memset(p, 0xA5, sizeof *p); /* lanes beyond count hold this pattern */
                uint32_t count = width;
                if (kind == PACKET_KIND_PRIMARY) {
                    int w = (int)(width - 1) % 8 + 1, h = (int)((width - 1) / 8 + trial) % 8 + 1;
                    packet_primary(p, &cam, (int)(rng_next(&g) % 57), (int)(rng_next(&g) % 41), w, h);
                    count = p->count;
                } else {
                    packet_reset(p, count, 0);
                    vec3 shared = dv_round(dv(rng_range(&g, -8, 8), rng_range(&g, -1, 8), rng_range(&g, 5, 10)));
                    for (uint32_t i = 0; i < count; i++) {
                        ray r;
                        if (kind == PACKET_KIND_MIXED) {
                            r.org = dv_round(dv(rng_range(&g, -8, 8), rng_range(&g, -2, 8), rng_range(&g, -8, 8)));
                            r.dir = dv_round(dv_scale(dv_random_unit(&g), rng_range(&g, 0.25, 4)));
                            r.t_near = rng_unit(&g) < 0.7 ? 0.f : (float)rng_range(&g, 0, 3);
                            double far_pick = rng_unit(&g);
                            r.t_far = far_pick < 0.4 ? FLT_MAX : far_pick < 0.6 ? INFINITY
                                                                                : (float)rng_range(&g, 3, 12);
                        } else {
                            r.org = shared;
                            dvec aim = dv(rng_range(&g, -3, 3), rng_range(&g, -1.5, 2), rng_range(&g, -3, 3));
                            r.dir = dv_round(dv_unit(dv_sub(aim, dv_of(shared))));
                            r.t_near = 0.f;
                            r.t_far = FLT_MAX;
                        }
                        packet_set_ray(p, i, &r);
                    }
                    if (kind == PACKET_KIND_COMMON_ORIGIN)
                        packet_detect_facts(p);
                }
                uint64_t pick = rng_next(&g) % 8;
                uint64_t active = pick == 0 ? 0 : pick < 3 ? ~0ull : rng_next(&g);
                p->active = active & packet_span_mask(0, count);
                uint32_t begin = 0, end = count;
                if (rng_unit(&g) < 0.6) {
                    begin = (uint32_t)(rng_next(&g) % (count + 1));
                    end = begin + (uint32_t)(rng_next(&g) % (count - begin + 1));
                }
                packet_range range = {p, begin, end};
                uint64_t traced = packet_range_mask(range);
                /* mark the lanes that must not change, so a write of hit_none() shows too */
                for (uint32_t i = 0; i < count; i++)
                    if (!(traced >> i & 1u)) {
                        p->hit_t[i] = 7.f + (float)i;
                        p->hit_u[i] = p->hit_v[i] = 0.25f;
                        p->prim_id[i] = 0xBAD00000u | i;
                        p->geom_id[i] = 0xBAD10000u | i;
                    }
                memcpy(before, p, sizeof *p);
                packets++;
                trace_packet(a, range);
                for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++) {
                    if (!(traced >> i & 1u)) {
                        touched += !lane_unchanged(p, before, i);
                        continue;
                    }
                    ray r = packet_get_ray(before, i);
                    hit want, got = packet_get_hit(p, i);
                    bool want_hit = trace_closest(a, &r, &want);
                    lanes++;
                    lane_hits += want_hit;
                    bool t_far_right = same_bits(p->t_far[i], want_hit ? want.t : r.t_far);
                    if (!hits_identical(&want, &got) || !t_far_right) {
                        wrong_hits++;
                        if (reported++ < MAX_REPORTED)
                            cr_log_error("robust/packets: kind %d width %u lane %u range [%u, %u): packet prim %u t %a "
                                         "u %a v %a, single prim %u t %a u %a v %a: " RAY_FMT,
                                         kind, count, i, begin, end, got.prim_id, got.t, got.u, got.v, want.prim_id,
                                         want.t, want.u, want.v, RAY_ARGS(r));
                    }
                }
                touched += p->count != before->count || (p->active & ~packet_span_mask(begin, end)) !=
                                                            (before->active & ~packet_span_mask(begin, end));
                /* the same packet again for any-hit */
                memcpy(p, before, sizeof *p);
                uint64_t occluded = trace_packet_any(a, range), want_occluded = 0;
                for (uint32_t i = 0; i < count; i++)
                    if (traced >> i & 1u) {
                        ray r = packet_get_ray(before, i);
                        want_occluded |= (uint64_t)trace_any(a, &r) << i;
                    }
                if (occluded != want_occluded) {
                    wrong_occluded++;
                    if (reported++ < MAX_REPORTED)
                        cr_log_error("robust/packets: kind %d width %u range [%u, %u) active %#llx: occluded %#llx, "
                                     "single rays %#llx",
                                     kind, count, begin, end, (unsigned long long)before->active,
                                     (unsigned long long)occluded, (unsigned long long)want_occluded);
                }
                for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++)
                    if (!(traced >> i & 1u))
                        touched += !lane_unchanged(p, before, i);
            }
    cr_log_info("robust/packets: %llu packets, %llu traced lanes (%llu hits): %llu hit records differ from "
                "accel_intersect, %llu occlusion masks differ from accel_occluded, %llu untraced lanes touched",
                (unsigned long long)packets, (unsigned long long)lanes, (unsigned long long)lane_hits,
                (unsigned long long)wrong_hits, (unsigned long long)wrong_occluded, (unsigned long long)touched);
    cr_expect_gt(lane_hits, lanes / 4, "too few hits for a meaningful comparison");
    cr_expect_eq(wrong_hits, 0u);
    cr_expect_eq(wrong_occluded, 0u);
    cr_expect_eq(touched, 0u);
    free(p);
    free(before);
    accel_destroy(a);
    scene_destroy(s);
    expect_isas_agree("robust/packets");
}

/* ------------------------------------------------------------------------ */
/* g. No self-shadowing on a lit plane, near and far from the origin. */

Test(robust, lit_plane_never_shadows_itself)
{
    /* A plane 200 units across, translated 0 .. 1e6 from the origin (offsets
     * 1, 10, ..., 1e6) along (1, 0.7, -0.4)/|.|, in two forms: one big
     * triangle in a random orientation, and an 8 x 8 grid of quads in an
     * axis-aligned plane (exactly planar in float). A directional light at
     * 1, 2, 3, 5, 10, 20 and 30 degrees to the plane. 1500 primary rays per
     * configuration from viewers on the lit side hit random points of the
     * plane; each hit shoots the shadow ray render.c shoots (origin
     * ray_offset_origin(the hit's surface_point, normal towards the light),
     * direction to the light, t in (0, FLT_MAX]). Nothing but the plane is in the scene, and
     * a plane cannot shadow itself: the criterion is 0 occluded shadow rays. */
    const double offsets[] = {1, 10, 100, 1e3, 1e4, 1e5, 1e6};
    const double tilts_deg[] = {1, 2, 3, 5, 10, 20, 30};
    const double half = 100.0;
    const int samples = 1500;
    rng g = {0x5AD0};
    uint64_t shadow_rays = 0, false_shadows = 0, primary_misses = 0, unlit = 0;
    uint64_t false_by_offset[7] = {0};
    int reported = 0;
    for (size_t oi = 0; oi < sizeof offsets / sizeof offsets[0]; oi++)
        for (size_t ti = 0; ti < sizeof tilts_deg / sizeof tilts_deg[0]; ti++)
            for (int form = 0; form < 2; form++) {
                dvec shift, e0, e1, n;
                scene *s = scene_new();
                mesh *m = lit_plane_mesh(&g, offsets[oi], form, half, &shift, &e0, &e1, &n);
                cr_assert(m);
                scene_put_mesh(s, m);
                accel *a = accel_for(s);
                vec3 to_light = lit_plane_light(&g, n, tilts_deg[ti]);
                for (int k = 0; k < samples; k++) {
                    /* a point well inside the square [-half, half]^2 of the plane */
                    ray primary = lit_plane_primary(&g, shift, e0, e1, n, half);
                    hit h;
                    if (!trace_closest(a, &primary, &h)) {
                        primary_misses++;
                        continue;
                    }
                    vec3 normal;
                    surface_point point = surface_at_hit(m, &h, primary.dir, &normal);
                    vec3 position = point.p;
                    if (!(v3_dot(normal, to_light) > 0.f)) {
                        unlit++; /* render.c shoots no shadow ray there */
                        continue;
                    }
                    ray shadow = make_ray(ray_offset_origin(point, normal), to_light, 0.f, FLT_MAX);
                    shadow_rays++;
                    if (trace_any(a, &shadow)) {
                        false_shadows++;
                        false_by_offset[oi]++;
                        hit self;
                        trace_closest(a, &shadow, &self);
                        if (reported++ < MAX_REPORTED)
                            cr_log_error("robust/shadows: offset %g, light at %g deg, %s: shadow ray " RAY_FMT
                                         " re-hits prim %u at t %a (position (%a, %a, %a), normal (%a, %a, %a))",
                                         offsets[oi], tilts_deg[ti], form ? "grid" : "triangle", RAY_ARGS(shadow),
                                         self.prim_id, self.t, position.x, position.y, position.z, normal.x, normal.y,
                                         normal.z);
                    }
                }
                accel_destroy(a);
                scene_destroy(s);
            }
    for (size_t oi = 0; oi < sizeof offsets / sizeof offsets[0]; oi++)
        cr_log_info("robust/shadows: offset %g: %llu falsely shadowed", offsets[oi],
                    (unsigned long long)false_by_offset[oi]);
    cr_log_info("robust/shadows: %llu shadow rays from a plane lit at 1..30 deg, offsets 1..1e6: %llu falsely "
                "shadowed; %llu primary rays missed, %llu hits unlit",
                (unsigned long long)shadow_rays, (unsigned long long)false_shadows,
                (unsigned long long)primary_misses, (unsigned long long)unlit);
    cr_expect_eq(primary_misses, 0u, "primary rays aimed inside the plane must hit it");
    cr_expect_eq(unlit, 0u);
    cr_expect_eq(false_shadows, 0u);
    expect_isas_agree("robust/shadows");
}

Test(robust, lit_plane_through_the_origin_never_shadows_itself)
{
    /* The other end of the offset range: a triangle 400 units across through
     * the world origin (random orientation), hit within 1e-3 .. 3 of the
     * origin. The hit position is interpolated from vertices ~100x larger than
     * itself, so its rounding error is relative to the vertices, not to the
     * position itself (an offset scaled by |position| alone, as Waechter &
     * Binder's, falls short here: the engine at 15b769b shadowed 4 % of these
     * points). Light at 1 .. 30
     * degrees to the plane, 20,000 shadow rays per angle; criterion as above:
     * 0 falsely shadowed. */
    const double tilts_deg[] = {1, 2, 3, 5, 10, 20, 30};
    const double pi = 3.14159265358979323846, half = 100.0;
    const int samples = 20000;
    rng g = {0x0121};
    uint64_t shadow_rays = 0, false_shadows = 0, primary_misses = 0, unlit = 0;
    int reported = 0;
    for (size_t ti = 0; ti < sizeof tilts_deg / sizeof tilts_deg[0]; ti++) {
        dvec e0, e1, n;
        random_basis(&g, &e0, &e1, &n);
        scene *s = scene_new();
        mesh *m = mesh_new();
        dvec c[3] = {dv(-half, -half, 0), dv(3 * half, -half, 0), dv(-half, 3 * half, 0)};
        for (int i = 0; i < 3; i++)
            mesh_put_vertex(m, dv_round(dv_add(dv_scale(e0, c[i].x), dv_scale(e1, c[i].y))));
        mesh_put_triangle(m, 0, 1, 2);
        scene_put_mesh(s, m);
        accel *a = accel_for(s);
        double tilt = tilts_deg[ti] * pi / 180.0;
        vec3 to_light = dv_round(
            dv_unit(dv_add(dv_scale(dv_random_perpendicular(n, &g), cos(tilt)), dv_scale(n, sin(tilt)))));
        for (int k = 0; k < samples; k++) {
            dvec q = dv_scale(dv_random_perpendicular(n, &g), rng_log_range(&g, 1e-3, 3.0));
            dvec view;
            do
                view = dv_random_unit(&g);
            while (dv_dot(view, n) < 0.2);
            vec3 eye = dv_round(dv_add(q, dv_scale(view, rng_range(&g, 1.0, 50.0))));
            ray primary = make_ray(eye, dv_round(dv_sub(q, dv_of(eye))), 0.f, FLT_MAX);
            hit h;
            if (!trace_closest(a, &primary, &h)) {
                primary_misses++;
                continue;
            }
            vec3 normal;
            surface_point point = surface_at_hit(m, &h, primary.dir, &normal);
            vec3 position = point.p;
            if (!(v3_dot(normal, to_light) > 0.f)) {
                unlit++;
                continue;
            }
            ray shadow = make_ray(ray_offset_origin(point, normal), to_light, 0.f, FLT_MAX);
            shadow_rays++;
            if (trace_any(a, &shadow)) {
                false_shadows++;
                hit self;
                trace_closest(a, &shadow, &self);
                if (reported++ < MAX_REPORTED)
                    cr_log_error("robust/shadows near the origin: light at %g deg: shadow ray " RAY_FMT
                                 " re-hits at t %a; position (%a, %a, %a) normal (%a, %a, %a) on " TRI_FMT,
                                 tilts_deg[ti], RAY_ARGS(shadow), self.t, position.x, position.y, position.z,
                                 normal.x, normal.y, normal.z,
                                 TRI_ARGS(mesh_vertex_at(m, 0), mesh_vertex_at(m, 1), mesh_vertex_at(m, 2)));
            }
        }
        accel_destroy(a);
        scene_destroy(s);
    }
    cr_log_info("robust/shadows near the origin: %llu shadow rays within 1e-3..3 of the origin on a plane through it: "
                "%llu falsely shadowed; %llu primary rays missed, %llu hits unlit",
                (unsigned long long)shadow_rays, (unsigned long long)false_shadows,
                (unsigned long long)primary_misses, (unsigned long long)unlit);
    cr_expect_eq(primary_misses, 0u);
    cr_expect_eq(unlit, 0u);
    cr_expect_eq(false_shadows, 0u);
    expect_isas_agree("robust/shadows near the origin");
}

/* ------------------------------------------------------------------------ */
/* h. Small, distant spheres against a double-precision reference. */

/* Width of the band around the silhouette where hit/miss is not compared, in
 * units of u * (|org - centre| + radius). intersect_sphere computes the centre's
 * distance from the ray's line as |l| with l = f - dir (f.dir / dir.dir),
 * f = org - centre: f carries an error of u |f|, f.dir, dir.dir and their ratio
 * about 7 roundings, l one more, so |l| is within ~9 u |f| of the exact
 * distance; comparing |l|^2 with radius^2 adds ~2.5 u radius. A ray whose exact
 * distance is farther than that from the radius is decided correctly by any
 * float kernel of this accuracy; 16 gives a margin of almost 2. */
#define SPHERE_BAND_ROUNDOFFS 16.0

Test(robust, distant_spheres_agree_with_double_reference)
{
    /* 300 spheres, radius 1e-3 .. 1 and distance 1e3 .. 1e5 radii from the
     * ray origins (both log-uniform), in random directions from origins within
     * 1 of the world origin. 400 rays per sphere aimed at random points of the
     * disc through the centre facing the origin, out to 2 silhouette radii
     * (so half hit, half miss), plus 100 clearly missing (aimed 3 .. 10 radii
     * out). The reference is the exact distance of the centre from the float
     * ray's line, in double. Criterion: outside the band
     * SPHERE_BAND_ROUNDOFFS u (|org - centre| + radius) around the silhouette,
     * hit/miss equals the reference for accel_intersect (a scene of that one
     * sphere) and intersect_sphere, and hits are at t > 0. */
    const int spheres = 300, aimed = 400, missing = 100;
    rng g = {0x5F3E};
    uint64_t rays = 0, compared = 0, in_band = 0, mismatches = 0, direct_mismatches = 0, band_mismatches = 0;
    uint64_t nan_outputs = 0;
    double worst_band_fraction = 0.0; /* band width / radius */
    double widest_mismatch = 0.0;     /* |distance - radius| / band of the farthest in-band mismatch */
    int reported = 0;
    for (int sp = 0; sp < spheres; sp++) {
        double radius_d = rng_log_range(&g, 1e-3, 1.0);
        double ratio = rng_log_range(&g, 1e3, 1e5);
        dvec view = dv_random_unit(&g);
        vec3 centre = dv_round(dv_scale(view, radius_d * ratio));
        float radius = (float)radius_d;
        scene *s = scene_new();
        cr_assert(scene_add_sphere(s, centre, radius, 0) >= 0);
        accel *a = accel_for(s);
        for (int k = 0; k < aimed + missing; k++) {
            vec3 org = dv_round(dv(rng_range(&g, -1, 1), rng_range(&g, -1, 1), rng_range(&g, -1, 1)));
            dvec c = dv_of(centre), f = dv_sub(dv_of(org), c);
            double dist = dv_len(f);
            double disc_radius = radius / sqrt(1.0 - (radius / dist) * (radius / dist)); /* silhouette, at the centre */
            dvec e0 = dv_random_perpendicular(dv_scale(f, 1.0 / dist), &g);
            double rho = k < aimed ? 2.0 * disc_radius * sqrt(rng_unit(&g)) : radius * rng_range(&g, 3, 10);
            dvec target = dv_add(c, dv_scale(e0, rho));
            ray r = make_ray(org, dv_round(dv_unit(dv_sub(target, dv_of(org)))), 0.f, FLT_MAX);
            rays++;
            /* exact distance of the centre from the float ray's line */
            dvec d = dv_of(r.dir), fr = dv_sub(dv_of(r.org), c);
            dvec l = dv_sub(fr, dv_scale(d, dv_dot(fr, d) / dv_dot(d, d)));
            double line_distance = dv_len(l);
            bool want = line_distance <= radius && dv_dot(fr, d) < 0.0;
            double band = SPHERE_BAND_ROUNDOFFS * F_ROUNDOFF * (dv_len(fr) + radius);
            worst_band_fraction = fmax(worst_band_fraction, band / radius);
            hit h;
            bool got = trace_closest(a, &r, &h);
            nan_outputs += hit_has_nan(&h);
            float t = -1.f;
            bool direct = intersect_sphere(&r, centre, radius, &t);
            nan_outputs += isnan(t);
            if (fabs(line_distance - radius) <= band) {
                in_band++;
                if (got != want) {
                    band_mismatches++;
                    widest_mismatch = fmax(widest_mismatch, fabs(line_distance - radius) / band);
                }
                continue;
            }
            compared++;
            bool bad_t = (got && !(h.t > 0.f)) || (direct && !(t > 0.f));
            if (got != want || bad_t) {
                mismatches++;
                if (reported++ < MAX_REPORTED)
                    cr_log_error("robust/spheres: accel_intersect %s (t %a), reference %s (line distance %.9g, "
                                 "radius %a, band %.3g): " RAY_FMT " centre (%a, %a, %a)",
                                 got ? "hit" : "miss", h.t, want ? "hit" : "miss", line_distance, radius, band,
                                 RAY_ARGS(r), centre.x, centre.y, centre.z);
            }
            direct_mismatches += direct != want;
        }
        accel_destroy(a);
        scene_destroy(s);
    }
    cr_log_info("robust/spheres: %llu rays at spheres of radius 1e-3..1 from 1e3..1e5 radii: %llu compared, %llu in "
                "the silhouette band (widest %.3g radii; %llu of them differ from the reference, allowed, at most "
                "%.2f band widths from the silhouette); mismatches: %llu accel_intersect, %llu intersect_sphere; "
                "NaN outputs %llu",
                (unsigned long long)rays, (unsigned long long)compared, (unsigned long long)in_band,
                worst_band_fraction, (unsigned long long)band_mismatches, widest_mismatch,
                (unsigned long long)mismatches,
                (unsigned long long)direct_mismatches, (unsigned long long)nan_outputs);
    cr_expect_eq(mismatches, 0u);
    cr_expect_eq(direct_mismatches, 0u);
    cr_expect_eq(nan_outputs, 0u);
    expect_isas_agree("robust/spheres");
}
