/* test_iso_kind.c - direct iso-surfaces as a geometry kind (engine/geometry/volume/
 * iso_kind.h) over a distance field made here: a 48^3 float volume whose
 * sample is the distance to an off-grid centre, so the iso-surface at r is
 * close to a sphere of radius r. Hits equal iso_volume_first_hit's roots,
 * lie on the sphere within the trilinear interpolation's error, face
 * radially; single rays and packets agree bit for bit in every ISA; the
 * value changes without a rebuild; next-hit walks the far side and nested
 * surfaces over one shared volume; instances move it; it renders. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "isa_skip.h"
#include "engine/scene/accel.h"
#include "engine/base/camera.h"
#include "engine/accel/geometry.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/accel/packet.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/geometry/volume/iso_kind.h"

#define N 48
/* off the grid's points and cell centres, so no ray runs along a symmetry */
static const double centre[3] = {23.3, 24.1, 23.7};

static volume *distance_volume(void)
{
    tess_error err = {{0}};
    volume *v = volume_create(N, N, N, VOLUME_FLOAT32, &err);
    cr_assert_not_null(v, "%s", err.msg);
    float *s = volume_voxels(v);
    for (uint32_t k = 0; k < N; k++)
        for (uint32_t j = 0; j < N; j++)
            for (uint32_t i = 0; i < N; i++) {
                double d[3] = {i - centre[0], j - centre[1], k - centre[2]};
                s[volume_index(v, i, j, k)] = (float)sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
    cr_assert(volume_update_range(v, "distance", &err), "%s", err.msg);
    return v;
}

static vec3 centre_v(void) { return v3((float)centre[0], (float)centre[1], (float)centre[2]); }

/* A scene with one iso kind (owning its shared volume) and its identity
 * instance; *kind gets the kind (the scene owns it). */
static scene *iso_scene(float iso, iso_kind **kind, uint32_t *inst)
{
    tess_error err = {{0}};
    scene *s = scene_create();
    material m = material_default();
    int mat = scene_add_material(s, &m);
    cr_assert_geq(mat, 0);
    iso_volume *shared = iso_volume_create(distance_volume(), NULL, &err);
    cr_assert_not_null(shared, "%s", err.msg);
    iso_kind *k = iso_kind_create_shared(shared, iso, v3(0.8f, 0.3f, 0.2f), (uint32_t)mat, ISO_METHOD_EXACT, &err);
    cr_assert_not_null(k, "%s", err.msg);
    iso_volume_release(shared);
    int g = scene_add_geometry(s, &iso_kind_ops, k, "iso");
    cr_assert_geq(g, 0);
    int i = scene_add_instance(s, (uint32_t)g, NULL, SCENE_NO_PART);
    cr_assert_geq(i, 0);
    light l = light_default_directional();
    l.direction = v3_normalize(v3(0.3f, 0.4f, 1.f));
    cr_assert_geq(scene_add_light(s, &l), 0);
    s->background = v3(0.f, 0.f, 0.f);
    s->ambient = v3(0.f, 0.f, 0.f);
    if (kind)
        *kind = k;
    if (inst)
        *inst = (uint32_t)i;
    return s;
}

static uint32_t rng_state = 12345u;
static float rnd(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return (float)(rng_state >> 8) * 0x1p-24f;
}

/* A ray from outside the volume towards a random point within `spread` of
 * the centre (some miss a small sphere, most hit). */
static ray random_ray(float spread)
{
    vec3 c = centre_v();
    float th = 6.2831853f * rnd(), z = 2.f * rnd() - 1.f, rr = sqrtf(1.f - z * z);
    vec3 org = v3_add(c, v3_scale(v3(rr * cosf(th), rr * sinf(th), z), 60.f));
    vec3 aim = v3_add(c, v3((2.f * rnd() - 1.f) * spread, (2.f * rnd() - 1.f) * spread, (2.f * rnd() - 1.f) * spread));
    return (ray){org, v3_normalize(v3_sub(aim, org)), 0.f, INFINITY};
}

/* The ray's entry into the sphere |p - c| = radius, or -1. */
static double sphere_entry(const ray *r, double radius)
{
    double o[3] = {r->org.x - centre[0], r->org.y - centre[1], r->org.z - centre[2]};
    double d[3] = {r->dir.x, r->dir.y, r->dir.z};
    double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2],
           c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - radius * radius;
    double disc = b * b - a * c;
    return disc < 0.0 ? -1.0 : (-b - sqrt(disc)) / a;
}

static double sphere_exit(const ray *r, double radius)
{
    double o[3] = {r->org.x - centre[0], r->org.y - centre[1], r->org.z - centre[2]};
    double d[3] = {r->dir.x, r->dir.y, r->dir.z};
    double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2],
           c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - radius * radius;
    double disc = b * b - a * c;
    return disc < 0.0 ? -1.0 : (-b + sqrt(disc)) / a;
}

/* |org + t dir - c| - radius: how far the hit is off the sphere, radially
 * (t itself moves by far more on grazing rays) */
static double off_sphere(const ray *r, float t, vec3 c, double radius)
{
    double d[3] = {(double)r->org.x + (double)t * r->dir.x - c.x, (double)r->org.y + (double)t * r->dir.y - c.y,
                   (double)r->org.z + (double)t * r->dir.z - c.z};
    return fabs(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - radius);
}

static const geometry_ops *ops_of(const scene *s, uint32_t inst) { return scene_instance_geometry(s, inst)->ops; }
static void *data_of(const scene *s, uint32_t inst) { return scene_instance_geometry(s, inst)->data; }

/* the trilinear interpolation of |p - c| over unit cells differs from it by
 * at most (3/8) h^2 max|second derivative| ~ 3 / (8 r): 0.03 at r = 12;
 * half a cell is far beyond it and far below a miss */
#define SPHERE_TOL 0.06

Test(iso_kind, hits_are_the_trilinear_roots_on_the_sphere_facing_out)
{
    iso_kind *k;
    uint32_t inst;
    const float iso = 12.f;
    scene *s = iso_scene(iso, &k, &inst);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    /* the kind's own walk, straight, over a volume and grid of its own */
    volume *v = distance_volume();
    macrocell_grid *g = macrocell_grid_create(v, MACROCELL_DEFAULT_K, &err);
    cr_assert_not_null(g, "%s", err.msg);
    int hits = 0;
    double worst_root = 0.0, worst_sphere = 0.0, worst_cos = 1.0, worst_shading = 1.0;
    for (int n = 0; n < 2000; n++) {
        ray r = random_ray(14.f);
        hit h;
        bool got = accel_intersect(a, &r, &h);
        iso_hit ih;
        const double org[3] = {r.org.x, r.org.y, r.org.z}, dir[3] = {r.dir.x, r.dir.y, r.dir.z};
        bool want = iso_volume_first_hit(v, g, org, dir, 0.0, INFINITY, iso, ISO_METHOD_EXACT, &ih);
        cr_assert_eq(got, want, "ray %d: accel %d, first_hit %d", n, got, want);
        double entry = sphere_entry(&r, iso);
        if (got) {
            hits++;
            cr_assert_eq(h.geom_id, inst);
            cr_assert_eq(h.prim_id, 0u);
            double dt = fabs((double)h.t - ih.t); /* unit directions, unit cells: t is cells */
            worst_root = dt > worst_root ? dt : worst_root;
            cr_assert_leq(dt, 1e-4, "ray %d: t %.9g vs root %.9g", n, (double)h.t, ih.t);
            /* the field at the hit is the iso-value (to the root's and t's rounding) */
            float corner[8];
            volume_cell_corners(v, ih.cell[0], ih.cell[1], ih.cell[2], corner);
            cr_assert_float_eq(iso_cell_value(corner, ih.local), iso, 1e-5);
            cr_assert_geq(entry, 0.0, "ray %d hits a surface the sphere misses", n);
            double ds = off_sphere(&r, h.t, centre_v(), iso);
            worst_sphere = ds > worst_sphere ? ds : worst_sphere;
            cr_assert_leq(ds, SPHERE_TOL, "ray %d: t %.6g is %.3g off the sphere", n, (double)h.t, ds);
            geometry_surface sf;
            ops_of(s, inst)->describe(data_of(s, inst), h.prim_id, &r, &h, true, &sf);
            vec3 radial = v3_normalize(v3_sub(sf.position, centre_v()));
            double c = v3_dot(radial, sf.geometric_n);
            worst_cos = c < worst_cos ? c : worst_cos;
            cr_assert_gt(c, 0.995, "ray %d: normal %g degrees off radial", n, acos(c) * 57.29578);
            double cs = v3_dot(radial, sf.shading_n);
            worst_shading = cs < worst_shading ? cs : worst_shading;
            cr_assert_gt(cs, c - 1e-6, "ray %d: the smooth shading normal is no better than the cell's", n);
            cr_assert(sf.has_colour);
            cr_assert_float_eq(sf.colour.x, 0.8f, 0.f);
            /* the position is on the ray at t, and its error is small and positive */
            vec3 at = v3_add(r.org, v3_scale(r.dir, h.t));
            cr_assert_leq(fabsf(at.x - sf.position.x), 1e-4f);
            cr_assert(sf.position_error.x > 0.f && sf.position_error.x < 1e-3f);
        } else {
            /* a miss grazes at most: the sphere is missed or barely touched */
            cr_assert(entry < 0.0 || sphere_exit(&r, iso) - entry < 2.0, "ray %d misses the sphere's middle", n);
        }
    }
    macrocell_grid_destroy(g);
    volume_destroy(v);
    cr_log_info("%d hits of 2000; worst |t - root| %.3g cell, |t - sphere| %.3g cell, normal %.3g deg, shading normal "
                "%.3g deg", hits, worst_root, worst_sphere, acos(worst_cos) * 57.29578, acos(worst_shading) * 57.29578);
    cr_assert_gt(worst_shading, 0.99999, "the smooth normal is within 0.26 degrees of radial");
    cr_assert_gt(hits, 1000);
    accel_destroy(a);
    scene_destroy(s);
}

static bool same_hit(hit a, hit b) { return memcmp(&a, &b, sizeof a) == 0; }

/* The sphere with a floor that cuts it (so the closest hit races between
 * two geometries and rays are shortened in different orders). */
static scene *sphere_and_floor(void)
{
    scene *s = iso_scene(13.f, NULL, NULL);
    mesh *m = mesh_create();
    cr_assert(mesh_add_vertex(m, -10.f, 20.f, -10.f) && mesh_add_vertex(m, 60.f, 20.f, -10.f) &&
              mesh_add_vertex(m, 60.f, 20.f, 60.f) && mesh_add_vertex(m, -10.f, 20.f, 60.f));
    cr_assert(mesh_add_triangle(m, 0, 2, 1) && mesh_add_triangle(m, 0, 3, 2));
    cr_assert_geq(scene_add_mesh(s, m, 0, "floor"), 0);
    return s;
}

Test(iso_kind, packets_equal_single_rays_in_every_isa, .timeout = 120)
{
    scene *s = sphere_and_floor();
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    enum { RAYS = 1500 };
    ray *list = malloc(RAYS * sizeof *list);
    hit *want = malloc(RAYS * sizeof *want), *want_after = malloc(RAYS * sizeof *want_after);
    rng_state = 777u;
    for (int i = 0; i < RAYS; i++)
        list[i] = random_ray(16.f);
    cr_assert(accel_use_isa(a, "sse2"));
    int iso_hits = 0, second = 0;
    for (int i = 0; i < RAYS; i++) {
        accel_intersect(a, &list[i], &want[i]);
        iso_hits += want[i].geom_id == 0;
        want_after[i] = hit_none();
        if (want[i].t != INFINITY)
            second += accel_intersect_after(a, &list[i], &want[i], &want_after[i]);
    }
    cr_assert_gt(iso_hits, 500);
    cr_assert_gt(second, 500);
    const char *isas[] = {"sse2", "avx2", "avx512"};
    int tested = 0;
    for (size_t k = 0; k < sizeof isas / sizeof isas[0]; k++) {
        if (isa_skip_note(isas[k]))
            continue;
        cr_assert(accel_use_isa(a, isas[k]), "%s: usable but refused", isas[k]);
        tested++;
        long mismatches = 0;
        for (int i = 0; i < RAYS; i++) {
            hit h;
            accel_intersect(a, &list[i], &h);
            mismatches += !same_hit(h, want[i]);
            mismatches += accel_occluded(a, &list[i]) != (want[i].t != INFINITY);
            if (want[i].t != INFINITY) {
                accel_intersect_after(a, &list[i], &want[i], &h);
                mismatches += !same_hit(h, want_after[i]);
            }
        }
        static ray_packet p;
        int next = 0;
        for (uint32_t width = 1; next < RAYS; width = width % 64 + 1) {
            uint32_t count = width < (uint32_t)(RAYS - next) ? width : (uint32_t)(RAYS - next);
            packet_reset(&p, count, 0);
            for (uint32_t i = 0; i < count; i++)
                packet_set_ray(&p, i, &list[next + (int)i]);
            packet_detect_facts(&p);
            uint64_t occ = accel_occluded_packet(a, packet_whole(&p));
            accel_intersect_packet(a, packet_whole(&p));
            for (uint32_t i = 0; i < count; i++) {
                mismatches += !same_hit(packet_get_hit(&p, i), want[next + (int)i]);
                mismatches += (bool)(occ >> i & 1u) != (want[next + (int)i].t != INFINITY);
            }
            /* the next surface, in a packet */
            packet_reset(&p, count, 0);
            for (uint32_t i = 0; i < count; i++) {
                packet_set_ray(&p, i, &list[next + (int)i]);
                if (want[next + (int)i].t != INFINITY)
                    packet_set_after(&p, i, &want[next + (int)i]);
            }
            packet_detect_facts(&p);
            accel_intersect_packet(a, packet_whole(&p));
            for (uint32_t i = 0; i < count; i++)
                if (want[next + (int)i].t != INFINITY)
                    mismatches += !same_hit(packet_get_hit(&p, i), want_after[next + (int)i]);
            next += (int)count;
        }
        cr_log_info("%s: %d rays single, after and in packets of 1..64: %ld mismatches", isas[k], RAYS, mismatches);
        cr_expect_eq(mismatches, 0, "%s: %ld results differ", isas[k], mismatches);
    }
    cr_expect(tested >= 1);
    free(list);
    free(want);
    free(want_after);
    accel_destroy(a);
    scene_destroy(s);
}

Test(iso_kind, setting_the_value_moves_the_surface_without_a_rebuild)
{
    iso_kind *k;
    uint32_t inst;
    scene *s = iso_scene(10.f, &k, &inst);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    /* straight at the centre along +x from outside */
    ray r = {v3(-5.f, (float)centre[1], (float)centre[2]), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    hit h;
    cr_assert(accel_intersect(a, &r, &h));
    cr_assert_float_eq(h.t, (float)(centre[0] + 5.0 - 10.0), SPHERE_TOL);
    float value, lo, hi;
    const geometry_ops *ops = ops_of(s, inst);
    cr_assert(ops->controls->value(k, &value, &lo, &hi));
    cr_assert_eq(value, 10.f);
    /* the volume's range */
    cr_assert(lo >= 0.f && lo < 1.f && hi > 39.f && hi < 42.f, "range %g..%g", (double)lo, (double)hi);
    cr_assert(ops->controls->set_value(k, 17.f));
    cr_assert_eq(iso_kind_value(k), 17.f);
    cr_assert(accel_intersect(a, &r, &h));
    cr_assert_float_eq(h.t, (float)(centre[0] + 5.0 - 17.0), SPHERE_TOL);
    cr_assert(!iso_kind_set_value(k, NAN));
    cr_assert(!ops->controls->set_value(k, INFINITY));
    cr_assert_eq(iso_kind_value(k), 17.f, "a refused value changes nothing");
    /* above the volume's max: nothing to hit */
    cr_assert(iso_kind_set_value(k, hi + 1.f));
    cr_assert(!accel_intersect(a, &r, &h));
    cr_assert(iso_kind_set_value(k, 10.f));
    cr_assert(accel_intersect(a, &r, &h));
    cr_assert_float_eq(h.t, (float)(centre[0] + 5.0 - 10.0), SPHERE_TOL);
    accel_destroy(a);
    scene_destroy(s);
}

Test(iso_kind, closed_while_the_surface_stays_off_the_boundary)
{
    iso_kind *k;
    uint32_t inst;
    scene *s = iso_scene(12.f, &k, &inst);
    cr_assert(scene_geometry_closed(s, 0), "a sphere inside the box bounds a solid");
    /* the boundary's nearest sample is ~23.3 from the centre */
    cr_assert(iso_kind_set_value(k, 26.f));
    cr_assert(scene_geometry_closed(s, 0), "the answer is cached until forgotten");
    scene_forget_closed(s, 0);
    cr_assert(!scene_geometry_closed(s, 0), "a sphere cut by the box is not closed");
    cr_assert(iso_kind_set_value(k, 0.5f));
    scene_forget_closed(s, 0);
    cr_assert(scene_geometry_closed(s, 0));
    cr_assert(iso_kind_set_value(k, 1e6f));
    scene_forget_closed(s, 0);
    cr_assert(scene_geometry_closed(s, 0), "no surface at all is (vacuously) closed");
    scene_destroy(s);
}

Test(iso_kind, renders_lit_on_the_sphere_and_background_off_it)
{
    scene *s = iso_scene(12.f, NULL, NULL);
    tess_error err = {{0}};
    accel *a = accel_build(s, 2, &err);
    cr_assert_not_null(a, "%s", err.msg);
    const int w = 48, h = 48;
    /* looking down -z at the centre, the light behind the camera */
    camera_desc c = {.eye = v3((float)centre[0], (float)centre[1], 90.f), .look_at = centre_v(),
                     .up = v3(0.f, 1.f, 0.f), .fov_deg = 30.f};
    render_view v = {.scene = s, .accel = a, .camera = camera_basis_make(&c, w, h), .shadows = true,
                     .shading = RENDER_SHADE_PHONG};
    float *rgb = calloc((size_t)w * h * 3, sizeof *rgb);
    render_image(&v, 2, rgb, NULL);
    const float *mid = rgb + 3 * ((size_t)(h / 2) * w + w / 2);
    cr_assert_gt(mid[0], 0.3f, "the centre is lit in the kind's colour: %g %g %g", (double)mid[0], (double)mid[1],
                 (double)mid[2]);
    cr_assert_gt(mid[0], mid[2], "red over blue: the kind's colour");
    const float *corner = rgb + 3 * ((size_t)1 * w + 1);
    cr_assert(corner[0] == 0.f && corner[1] == 0.f && corner[2] == 0.f, "the corner is background: %g %g %g",
              (double)corner[0], (double)corner[1], (double)corner[2]);
    free(rgb);
    accel_destroy(a);
    scene_destroy(s);
}

Test(iso_kind, next_hit_finds_the_far_side)
{
    scene *s = iso_scene(12.f, NULL, NULL);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    rng_state = 99u;
    int walked = 0;
    for (int n = 0; n < 300; n++) {
        ray r = random_ray(6.f);
        hit first, far_side, none;
        if (!accel_intersect(a, &r, &first))
            continue;
        cr_assert(accel_intersect_after(a, &r, &first, &far_side), "ray %d: no far side", n);
        cr_assert_gt(far_side.t, first.t);
        cr_assert_gt(far_side.t, (float)(0.5 * (sphere_entry(&r, 12.0) + sphere_exit(&r, 12.0))), "ray %d", n);
        cr_assert_leq(off_sphere(&r, far_side.t, centre_v(), 12.0), SPHERE_TOL, "ray %d", n);
        cr_assert(!accel_intersect_after(a, &r, &far_side, &none), "ray %d: a third crossing", n);
        /* t_near raised to the hit by hand: the same */
        ray beyond = r;
        beyond.t_near = first.t;
        hit h;
        cr_assert(accel_intersect(a, &beyond, &h));
        cr_assert(same_hit(h, far_side));
        walked++;
    }
    cr_assert_gt(walked, 250);
    accel_destroy(a);
    scene_destroy(s);
}

Test(iso_kind, two_values_of_one_shared_volume_nest)
{
    tess_error err = {{0}};
    scene *s = scene_create();
    material m = material_default();
    cr_assert_geq(scene_add_material(s, &m), 0);
    iso_volume *shared = iso_volume_create(distance_volume(), NULL, &err);
    cr_assert_not_null(shared, "%s", err.msg);
    iso_kind *outer = iso_kind_create_shared(shared, 15.f, v3(1.f, 1.f, 1.f), 0, ISO_METHOD_EXACT, &err);
    iso_kind *inner = iso_kind_create_shared(shared, 7.f, v3(1.f, 0.f, 0.f), 0, ISO_METHOD_EXACT, &err);
    cr_assert(outer && inner, "%s", err.msg);
    iso_volume_release(shared); /* the kinds keep it */
    int go = scene_add_geometry(s, &iso_kind_ops, outer, "outer"), gi = scene_add_geometry(s, &iso_kind_ops, inner, "inner");
    cr_assert(go >= 0 && gi >= 0);
    int io = scene_add_instance(s, (uint32_t)go, NULL, SCENE_NO_PART),
        ii = scene_add_instance(s, (uint32_t)gi, NULL, SCENE_NO_PART);
    cr_assert(io >= 0 && ii >= 0);
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    rng_state = 4242u;
    int through = 0;
    for (int n = 0; n < 300; n++) {
        ray r = random_ray(4.f);
        hit h[4];
        cr_assert(accel_intersect(a, &r, &h[0]));
        cr_assert_eq(h[0].geom_id, (uint32_t)io, "ray %d: the outer surface first", n);
        for (int j = 1; j < 4; j++)
            cr_assert(accel_intersect_after(a, &r, &h[j - 1], &h[j]), "ray %d: surface %d missing", n, j);
        const uint32_t order[4] = {(uint32_t)io, (uint32_t)ii, (uint32_t)ii, (uint32_t)io};
        const double radius[4] = {15.0, 7.0, 7.0, 15.0};
        for (int j = 0; j < 4; j++) {
            cr_assert_eq(h[j].geom_id, order[j], "ray %d, surface %d", n, j);
            cr_assert_leq(off_sphere(&r, h[j].t, centre_v(), radius[j]), SPHERE_TOL, "ray %d, surface %d", n, j);
        }
        hit none;
        cr_assert(!accel_intersect_after(a, &r, &h[3], &none));
        through++;
    }
    cr_assert_eq(through, 300);
    accel_destroy(a);
    scene_destroy(s); /* frees both kinds, then the shared volume with the last */
}

Test(iso_kind, an_instance_moves_and_scales_the_surface)
{
    tess_error err = {{0}};
    scene *s = iso_scene(12.f, NULL, NULL);
    /* a second placement: scale 2 about the origin, then translate by (100, 5, -3) */
    affine3 place = {{2.f, 0.f, 0.f, 100.f, 0.f, 2.f, 0.f, 5.f, 0.f, 0.f, 2.f, -3.f}};
    int moved = scene_add_instance(s, 0, &place, SCENE_NO_PART);
    cr_assert_geq(moved, 0);
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    aabb box;
    cr_assert(scene_instance_bounds(s, (uint32_t)moved, &box));
    cr_assert_float_eq(box.lo.x, 100.f, 1e-3f);
    cr_assert_float_eq(box.hi.x, 100.f + 2.f * (N - 1), 1e-3f);
    vec3 c2 = v3(2.f * (float)centre[0] + 100.f, 2.f * (float)centre[1] + 5.f, 2.f * (float)centre[2] - 3.f);
    rng_state = 5u;
    int hits = 0;
    for (int n = 0; n < 300; n++) {
        /* rays at the moved centre from 150 away */
        float th = 6.2831853f * rnd(), z = 2.f * rnd() - 1.f, rr = sqrtf(1.f - z * z);
        vec3 org = v3_add(c2, v3_scale(v3(rr * cosf(th), rr * sinf(th), z), 150.f));
        vec3 aim = v3_add(c2, v3(10.f * (rnd() - 0.5f), 10.f * (rnd() - 0.5f), 10.f * (rnd() - 0.5f)));
        ray r = {org, v3_normalize(v3_sub(aim, org)), 0.f, INFINITY};
        hit h;
        cr_assert(accel_intersect(a, &r, &h), "ray %d", n);
        cr_assert_eq(h.geom_id, (uint32_t)moved);
        /* on the sphere of radius 24 about c2 (the error scaled by 2 too) */
        cr_assert_leq(off_sphere(&r, h.t, c2, 24.0), 2.0 * SPHERE_TOL, "ray %d", n);
        /* the same t as the object-space ray in the identity instance */
        const scene_instance *in = &s->instances[moved];
        ray local = affine3_ray(&in->to_object, &r);
        float t_obj, u, v;
        cr_assert(iso_kind_ops.intersect(scene_instance_geometry(s, (uint32_t)moved)->data, 0, &local, &t_obj, &u, &v));
        cr_assert_eq(h.t, t_obj, "ray %d: world %a, object %a", n, (double)h.t, (double)t_obj);
        hits++;
    }
    cr_assert_eq(hits, 300);
    accel_destroy(a);
    scene_destroy(s);
}

Test(iso_kind, borrowed_volumes_stay_the_callers)
{
    tess_error err = {{0}};
    volume *v = distance_volume();
    macrocell_grid *g = macrocell_grid_create(v, 4, &err);
    cr_assert_not_null(g, "%s", err.msg);
    iso_kind *k = iso_kind_create(v, g, 9.f, v3(1.f, 1.f, 1.f), 0, ISO_METHOD_EXACT, &err);
    cr_assert_not_null(k, "%s", err.msg);
    cr_assert_null(iso_kind_create(v, g, NAN, v3(1.f, 1.f, 1.f), 0, ISO_METHOD_EXACT, &err));
    cr_assert(strstr(err.msg, "not finite"), "%s", err.msg);
    ray r = {v3(-5.f, (float)centre[1], (float)centre[2]), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    float t, u, w;
    cr_assert(iso_kind_ops.intersect(k, 0, &r, &t, &u, &w));
    cr_assert_float_eq(t, (float)(centre[0] + 5.0 - 9.0), SPHERE_TOL);
    r.t_far = t; /* (t_near, t_far]: a hit exactly at t_far counts */
    cr_assert(iso_kind_ops.intersect(k, 0, &r, &t, &u, &w));
    r.t_far = nextafterf(t, 0.f);
    cr_assert(!iso_kind_ops.intersect(k, 0, &r, &t, &u, &w));
    iso_kind_destroy(k);
    /* still the caller's */
    cr_assert_eq(volume_sample(v, 0, 0, 0), (float)sqrt(centre[0] * centre[0] + centre[1] * centre[1] +
                                                          centre[2] * centre[2]));
    macrocell_grid_destroy(g);
    volume_destroy(v);
}

Test(iso_kind, bounds_are_the_macrocells_that_vary)
{
    tess_error err = {{0}};
    /* zero everywhere but a bump at samples 20..22 on each axis */
    volume *v = volume_create(N, N, N, VOLUME_FLOAT32, &err);
    cr_assert_not_null(v, "%s", err.msg);
    float *s = volume_voxels(v);
    for (uint32_t k = 20; k <= 22; k++)
        for (uint32_t j = 20; j <= 22; j++)
            for (uint32_t i = 20; i <= 22; i++)
                s[volume_index(v, i, j, k)] = 10.f;
    cr_assert(volume_update_range(v, "bump", &err));
    v->origin[0] = -3.0;
    iso_volume *shared = iso_volume_create(v, NULL, &err); /* k = 8: samples 20..22 lie in macrocell 2 */
    cr_assert_not_null(shared, "%s", err.msg);
    iso_kind *k = iso_kind_create_shared(shared, 5.f, v3(1.f, 1.f, 1.f), 0, ISO_METHOD_EXACT, &err);
    cr_assert_not_null(k);
    aabb box;
    cr_assert(iso_kind_ops.prim_bounds(k, 0, &box));
    cr_assert_float_eq(box.lo.x, -3.f + 16.f, 1e-5f);
    cr_assert_float_eq(box.hi.x, -3.f + 24.f, 1e-5f);
    cr_assert_float_eq(box.lo.z, 16.f, 1e-5f);
    cr_assert_float_eq(box.hi.z, 24.f, 1e-5f);
    /* the bump is found from outside its box */
    ray r = {v3(-50.f, 21.f, 21.f), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    float t, u, w;
    cr_assert(iso_kind_ops.intersect(k, 0, &r, &t, &u, &w));
    cr_assert_float_eq(t, 50.f - 3.f + 19.5f, 1e-4f);
    cr_assert(iso_kind_ops.closed(k), "the bump stays off the boundary");
    iso_volume_release(shared);
    iso_kind_destroy(k);

    /* a constant field: nothing to bound, nothing to hit, at any value */
    volume *flat = volume_create(8, 8, 8, VOLUME_UINT8, &err);
    cr_assert_not_null(flat);
    memset(volume_voxels(flat), 7, 512);
    cr_assert(volume_update_range(flat, "flat", &err));
    shared = iso_volume_create(flat, NULL, &err);
    cr_assert_not_null(shared);
    k = iso_kind_create_shared(shared, 7.f, v3(1.f, 1.f, 1.f), 0, ISO_METHOD_EXACT, &err);
    iso_volume_release(shared);
    cr_assert(!iso_kind_ops.prim_bounds(k, 0, &box));
    cr_assert(!iso_kind_ops.bounds(k, &box));
    scene *sc = scene_create();
    cr_assert_geq(scene_add_geometry(sc, &iso_kind_ops, k, "flat"), 0);
    cr_assert_geq(scene_add_instance(sc, 0, NULL, SCENE_NO_PART), 0);
    accel *a = accel_build(sc, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    hit h;
    ray through = {v3(-5.f, 3.5f, 3.5f), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    cr_assert(!accel_intersect(a, &through, &h));
    accel_destroy(a);
    scene_destroy(sc);
}

/* Count the surfaces along r by next-hit queries. */
static int surfaces_along(const accel *a, const ray *r, float *first_t)
{
    hit h, prev;
    int n = 0;
    if (!accel_intersect(a, r, &h))
        return 0;
    *first_t = h.t;
    do {
        n++;
        prev = h;
    } while (n < 16 && accel_intersect_after(a, r, &prev, &h));
    return n;
}

Test(iso_kind, a_sheet_at_exactly_the_value_keeps_parity)
{
    /* uint8: 100 everywhere but the plane i = 4, which is exactly 60. At
     * iso 60 the field only touches the value on that plane: traced as the
     * float above 60, the plane becomes a sheet ~1e-7 thin whose two
     * crossings share one float t and cancel; at 60.5 the sheet is thick
     * and has its two crossings; both keep parity (an even count) */
    tess_error err = {{0}};
    volume *v = volume_create(9, 6, 6, VOLUME_UINT8, &err);
    cr_assert_not_null(v, "%s", err.msg);
    uint8_t *s = volume_voxels(v);
    for (uint32_t k = 0; k < 6; k++)
        for (uint32_t j = 0; j < 6; j++)
            for (uint32_t i = 0; i < 9; i++)
                s[volume_index(v, i, j, k)] = i == 4 ? 60 : 100;
    cr_assert(volume_update_range(v, "sheet", &err));
    iso_volume *shared = iso_volume_create(v, NULL, &err);
    cr_assert_not_null(shared, "%s", err.msg);
    static const iso_method methods[3] = {ISO_METHOD_EXACT, ISO_METHOD_LINEAR, ISO_METHOD_REGULA_FALSI};
    for (int m = 0; m < 3; m++) {
        iso_kind *k = iso_kind_create_shared(shared, 60.f, v3(1.f, 1.f, 1.f), 0, methods[m], &err);
        cr_assert_not_null(k);
        scene *sc = scene_create();
        cr_assert_geq(scene_add_geometry(sc, &iso_kind_ops, k, "sheet"), 0);
        cr_assert_geq(scene_add_instance(sc, 0, NULL, SCENE_NO_PART), 0);
        accel *a = accel_build(sc, 1, &err);
        cr_assert_not_null(a, "%s", err.msg);
        rng_state = 31u;
        for (int n = 0; n < 200; n++) {
            /* from far away (a coarse float t) through the sheet at a slant */
            ray r = {v3(-1000.f, 2.5f + rnd(), 2.5f + rnd()), v3_normalize(v3(1.f, 1e-3f * (rnd() - 0.5f), 1e-3f * (rnd() - 0.5f))),
                     0.f, INFINITY};
            float t0 = 0.f;
            int count = surfaces_along(a, &r, &t0);
            cr_assert_eq(count % 2, 0, "method %d, ray %d: %d surfaces through a sheet", m, n, count);
        }
        cr_assert(iso_kind_set_value(k, 60.5f));
        ray r = {v3(-1000.f, 2.5f, 2.5f), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
        float t0 = 0.f;
        cr_assert_eq(surfaces_along(a, &r, &t0), 2, "method %d: a thick sheet has two sides", m);
        cr_assert_float_eq(t0, 1000.f + 3.f + 39.5f / 40.f, 1e-3f);
        accel_destroy(a);
        scene_destroy(sc);
    }
    iso_volume_release(shared);
}
