/* test_geometry_kind.c - a geometry kind added from outside the engine
 * through the public registration alone (scene_add_geometry with a
 * geometry_ops table defined here): analytic discs. They render, cast
 * shadows, are picked and hidden like the built-in kinds, and single rays
 * and packets agree on them bit for bit; and instances: a mesh stored once
 * and placed by transforms traces and shades like the same mesh with the
 * transforms baked in. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/base/camera.h"
#include "engine/scene/frame_state.h"
#include "engine/frame/txn.h"
#include "engine/accel/geometry.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/accel/packet.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"

/* ---- the disc kind: centre, unit normal, radius per disc ---------------- */

typedef struct discs {
    uint32_t count;
    vec3 centre[8], normal[8];
    float radius[8];
    uint32_t material_id;
    int *destroyed; /* set to 1 by destroy, so the test sees the scene freed it */
} discs;

static uint32_t disc_count(const void *data) { return ((const discs *)data)->count; }

static bool disc_prim_bounds(const void *data, uint32_t prim, aabb *out)
{
    const discs *d = data;
    float r = d->radius[prim];
    if (!(r > 0.f))
        return false;
    vec3 c = d->centre[prim];
    *out = (aabb){v3_sub(c, v3(r, r, r)), v3_add(c, v3(r, r, r))};
    return true;
}

/* Plane hit in (t_near, t_far] within the radius. */
static bool disc_intersect(const void *data, uint32_t prim, const ray *r, float *t, float *u, float *v)
{
    const discs *d = data;
    vec3 n = d->normal[prim];
    float denom = v3_dot(n, r->dir);
    if (denom == 0.f)
        return false;
    float th = v3_dot(n, v3_sub(d->centre[prim], r->org)) / denom;
    if (!(th > r->t_near && th <= r->t_far))
        return false;
    vec3 p = v3_add(r->org, v3_scale(r->dir, th));
    vec3 off = v3_sub(p, d->centre[prim]);
    if (v3_dot(off, off) > d->radius[prim] * d->radius[prim])
        return false;
    *t = th;
    *u = *v = 0.f;
    return true;
}

static void disc_describe(const void *data, uint32_t prim, const ray *r, const hit *h, bool need_position,
                          geometry_surface *out)
{
    const discs *d = data;
    (void)need_position;
    vec3 p = v3_add(r->org, v3_scale(r->dir, h->t));
    /* project onto the plane; the error bound covers the ray's rounding generously */
    vec3 n = d->normal[prim];
    p = v3_sub(p, v3_scale(n, v3_dot(n, v3_sub(p, d->centre[prim]))));
    float mag = fabsf(p.x) + fabsf(p.y) + fabsf(p.z) + 1.f;
    out->position = p;
    out->position_error = v3(mag * 1e-5f, mag * 1e-5f, mag * 1e-5f);
    out->geometric_n = n;
    out->shading_n = n;
    out->has_colour = false;
    out->material_id = d->material_id;
}

static void disc_destroy(void *data)
{
    discs *d = data;
    if (d->destroyed)
        *d->destroyed = 1;
    free(d);
}

static const geometry_ops disc_ops = {
    .name = "discs",
    .leaf = GEOMETRY_LEAF_PRIMS,
    .prim_count = disc_count,
    .prim_bounds = disc_prim_bounds,
    .intersect = disc_intersect,
    .describe = disc_describe,
    .destroy = disc_destroy,
};

/* A grey floor (two triangles, y = 0, [-4, 4]^2), a red disc of radius 1 at
 * height 1 facing up, light straight from above. */
static scene *disc_scene(int *destroyed, uint32_t *disc_instance)
{
    scene *s = scene_create();
    material grey = material_default(), red = material_default();
    red.diffuse = v3(0.9f, 0.1f, 0.1f);
    int g = scene_add_material(s, &grey), r = scene_add_material(s, &red);
    cr_assert(g >= 0 && r >= 0);
    mesh *m = mesh_create();
    cr_assert(mesh_add_vertex(m, -4.f, 0.f, -4.f) && mesh_add_vertex(m, 4.f, 0.f, -4.f) &&
              mesh_add_vertex(m, 4.f, 0.f, 4.f) && mesh_add_vertex(m, -4.f, 0.f, 4.f));
    cr_assert(mesh_add_triangle(m, 0, 2, 1) && mesh_add_triangle(m, 0, 3, 2));
    cr_assert_geq(scene_add_mesh(s, m, (uint32_t)g, "floor"), 0);
    discs *d = calloc(1, sizeof *d);
    d->count = 1;
    d->centre[0] = v3(0.f, 1.f, 0.f);
    d->normal[0] = v3(0.f, 1.f, 0.f);
    d->radius[0] = 1.f;
    d->material_id = (uint32_t)r;
    d->destroyed = destroyed;
    int geom = scene_add_geometry(s, &disc_ops, d, "disc");
    cr_assert_geq(geom, 0);
    int inst = scene_add_instance(s, (uint32_t)geom, NULL, SCENE_NO_PART);
    cr_assert_geq(inst, 0);
    *disc_instance = (uint32_t)inst;
    light l = light_default_directional();
    l.direction = v3(0.f, 1.f, 0.f);
    cr_assert_geq(scene_add_light(s, &l), 0);
    s->ambient = v3(0.f, 0.f, 0.f);
    return s;
}

static camera_basis top_camera(int w, int h)
{
    camera_desc c = {.eye = v3(0.f, 10.f, 0.01f), .look_at = v3(0.f, 0.f, 0.f), .up = v3(0.f, 1.f, 0.f),
                     .fov_deg = 40.f};
    return camera_basis_make(&c, w, h);
}

static vec3 pixel(const float *rgb, int w, int x, int y)
{
    const float *p = rgb + 3 * ((size_t)y * w + x);
    return v3(p[0], p[1], p[2]);
}

Test(geometry_kind, a_kind_from_outside_renders_shadows_picks_and_hides)
{
    int destroyed = 0;
    uint32_t disc_inst;
    scene *s = disc_scene(&destroyed, &disc_inst);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    const int w = 64, h = 64;
    render_view v = {.scene = s, .accel = a, .camera = top_camera(w, h), .shadows = true,
                     .shading = RENDER_SHADE_PHONG};
    float *rgb = calloc((size_t)w * h * 3, sizeof *rgb);
    render_image(&v, 1, rgb, NULL);
    /* the disc's centre shows red; a floor point under its rim is in its
     * shadow; a floor point well outside is lit grey */
    vec3 centre = pixel(rgb, w, w / 2, h / 2);
    cr_assert_gt(centre.x, 0.5f, "disc centre red %g", (double)centre.x);
    cr_assert_lt(centre.y, 0.2f);
    /* find a floor pixel just outside the disc but inside its shadow?
     * light is straight down: the shadow is exactly under the disc, hidden
     * by it from above; so look from the side instead */
    camera_desc side = {.eye = v3(0.f, 0.5f, 6.f), .look_at = v3(0.f, 0.f, 0.f), .up = v3(0.f, 1.f, 0.f),
                        .fov_deg = 50.f};
    v.camera = camera_basis_make(&side, w, h);
    render_image(&v, 1, rgb, NULL);
    /* the floor point (0, 0, 0): in shadow under the disc; (0, 0, 2.5): lit */
    ray to_centre = {side.eye, v3_normalize(v3_sub(v3(0.f, 0.f, 0.5f), side.eye)), 0.f, INFINITY};
    hit hc;
    cr_assert(accel_pick(a, &to_centre, &hc));
    cr_assert_eq(hc.geom_id, 0u, "floor under the disc seen from the side");
    uint64_t shadow_rays = 0;
    vec3 shaded = render_shade(&v, &to_centre, &shadow_rays);
    cr_assert_eq(shadow_rays, 1u);
    cr_assert_lt(shaded.x, 1e-6f, "the disc casts no shadow: %g", (double)shaded.x);
    ray to_lit = {side.eye, v3_normalize(v3_sub(v3(0.f, 0.f, 2.5f), side.eye)), 0.f, INFINITY};
    vec3 lit = render_shade(&v, &to_lit, &shadow_rays);
    cr_assert_gt(lit.x, 0.5f, "a lit floor point is dark: %g", (double)lit.x);

    /* picking from above names the disc and its primitive */
    ray down = {v3(0.2f, 5.f, 0.1f), v3(0.f, -1.f, 0.f), 0.f, INFINITY};
    hit hd;
    cr_assert(accel_pick(a, &down, &hd));
    cr_assert_eq(hd.geom_id, disc_inst);
    cr_assert_eq(hd.prim_id, 0u);
    cr_assert_float_eq(hd.t, 4.f, 1e-6f);

    /* hidden: not seen, no shadow; shown again: the same hit bit for bit */
    accel_set_hidden(a, disc_inst, true);
    cr_assert(accel_pick(a, &down, &hd));
    cr_assert_eq(hd.geom_id, 0u, "a hidden disc is picked");
    vec3 unshadowed = render_shade(&v, &to_centre, &shadow_rays);
    cr_assert_gt(unshadowed.x, 0.5f, "a hidden disc still casts a shadow");
    cr_assert(accel_commit(a), "hiding leaves a refit for the commit");
    cr_assert(accel_pick(a, &down, &hd));
    cr_assert_eq(hd.geom_id, 0u);
    accel_set_hidden(a, disc_inst, false);
    cr_assert(accel_pick(a, &down, &hd));
    cr_assert_eq(hd.geom_id, disc_inst, "shown again after a commit shrank the boxes");
    cr_assert_float_eq(hd.t, 4.f, 1e-6f);

    free(rgb);
    accel_destroy(a);
    scene_destroy(s);
    cr_assert_eq(destroyed, 1, "the scene frees a kind's data through its destroy op");
}

Test(geometry_kind, packets_and_single_rays_agree_on_a_registered_kind)
{
    int destroyed = 0;
    uint32_t disc_inst;
    scene *s = disc_scene(&destroyed, &disc_inst);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    camera_basis cam = top_camera(64, 64);
    ray_packet *p = aligned_alloc(64, sizeof *p);
    int disc_hits = 0;
    for (int ty = 0; ty < 64; ty += 8)
        for (int tx = 0; tx < 64; tx += 8) {
            packet_primary(p, &cam, tx, ty, 8, 8);
            accel_intersect_packet(a, packet_whole(p));
            for (uint32_t i = 0; i < p->count; i++) {
                ray r = packet_get_ray(p, i);
                r.t_far = FLT_MAX;
                hit want;
                accel_intersect(a, &r, &want);
                hit got = packet_get_hit(p, i);
                cr_assert(memcmp(&want, &got, sizeof want) == 0, "ray %u of tile (%d, %d): packet and single differ", i,
                          tx, ty);
                disc_hits += got.geom_id == disc_inst;
            }
            packet_primary(p, &cam, tx, ty, 8, 8);
            uint64_t occluded = accel_occluded_packet(a, packet_whole(p));
            for (uint32_t i = 0; i < p->count; i++) {
                ray r = packet_get_ray(p, i);
                cr_assert_eq((occluded >> i & 1u) != 0, accel_occluded(a, &r));
            }
        }
    cr_assert_gt(disc_hits, 100, "the disc covers part of the image (%d rays)", disc_hits);
    free(p);
    accel_destroy(a);
    scene_destroy(s);
}

Test(geometry_kind, bad_ops_are_refused_and_the_data_freed)
{
    scene *s = scene_create();
    int destroyed = 0;
    discs *d = calloc(1, sizeof *d);
    d->destroyed = &destroyed;
    geometry_ops broken = disc_ops;
    broken.intersect = NULL;
    cr_assert_eq(scene_add_geometry(s, &broken, d, "broken"), -1);
    cr_assert_eq(destroyed, 1, "refused data is freed (ownership passed)");
    cr_assert_eq(scene_add_instance(s, 0, NULL, SCENE_NO_PART), -1, "an instance of no geometry");
    scene_destroy(s);
}

/* ---- instances -------------------------------------------------------- */

/* A closed box mesh (12 triangles) of half size 0.5 at the origin. */
static mesh *unit_box(void)
{
    mesh *m = mesh_create();
    for (int k = 0; k < 8; k++)
        cr_assert(mesh_add_vertex(m, k & 1 ? 0.5f : -0.5f, k & 2 ? 0.5f : -0.5f, k & 4 ? 0.5f : -0.5f));
    static const uint32_t tri[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (int t = 0; t < 12; t++)
        cr_assert(mesh_add_triangle(m, tri[t][0], tri[t][1], tri[t][2]));
    return m;
}

/* Placements: a translation, a rotation about y with a uniform scale, a non-uniform scale. */
static affine3 placement(int k)
{
    float c = cosf(0.6f), sn = sinf(0.6f);
    switch (k) {
    case 0: return (affine3){{1, 0, 0, -2.f, 0, 1, 0, 0.5f, 0, 0, 1, 0.f}};
    case 1: return (affine3){{1.5f * c, 0, 1.5f * sn, 0.f, 0, 1.5f, 0, 0.75f, -1.5f * sn, 0, 1.5f * c, 0.3f}};
    default: return (affine3){{0.5f, 0, 0, 2.f, 0, 2.f, 0, 1.f, 0, 0, 1.f, -0.5f}};
    }
}

/* The boxes either as one geometry placed 3 times or as 3 baked meshes. */
static scene *boxes_scene(bool instanced)
{
    scene *s = scene_create();
    material grey = material_default();
    int mat = scene_add_material(s, &grey);
    mesh *floor_mesh = mesh_create();
    cr_assert(mesh_add_vertex(floor_mesh, -5.f, 0.f, -5.f) && mesh_add_vertex(floor_mesh, 5.f, 0.f, -5.f) &&
              mesh_add_vertex(floor_mesh, 5.f, 0.f, 5.f) && mesh_add_vertex(floor_mesh, -5.f, 0.f, 5.f));
    cr_assert(mesh_add_triangle(floor_mesh, 0, 2, 1) && mesh_add_triangle(floor_mesh, 0, 3, 2));
    cr_assert_geq(scene_add_mesh(s, floor_mesh, (uint32_t)mat, "floor"), 0);
    if (instanced) {
        /* geometry 1 with its own identity instance 1 (hidden by the tests),
         * then three more instances of it */
        cr_assert_geq(scene_add_mesh(s, unit_box(), (uint32_t)mat, "box"), 0);
        for (int k = 0; k < 3; k++) {
            affine3 m = placement(k);
            cr_assert_geq(scene_add_instance(s, 1, &m, SCENE_NO_PART), 0);
        }
    } else {
        mesh *unused = unit_box();
        cr_assert_geq(scene_add_mesh(s, unused, (uint32_t)mat, "box"), 0); /* mirrors instance 1 */
        for (int k = 0; k < 3; k++) {
            mesh *m = unit_box();
            affine3 a = placement(k);
            mesh_transform(m, a.m);
            cr_assert_geq(scene_add_mesh(s, m, (uint32_t)mat, "box"), 0);
        }
    }
    light l = light_default_directional();
    cr_assert_geq(scene_add_light(s, &l), 0);
    return s;
}

/* Whether hit a of scene sa and hit b of scene sb are on the same triangle
 * in the world: each mesh is in its own tree's order (mesh_tree.h), so ids
 * name different triangles in two trees; the corners, placed, must agree. */
static bool same_world_triangle(const scene *sa, hit a, const scene *sb, hit b)
{
    const scene *s[2] = {sa, sb};
    const hit h[2] = {a, b};
    vec3 corner[2][3];
    for (int k = 0; k < 2; k++) {
        const mesh *m = ((const scene_mesh *)scene_instance_geometry(s[k], h[k].geom_id)->data)->mesh;
        const affine3 *to_world = &s[k]->instances[h[k].geom_id].to_world;
        for (int c = 0; c < 3; c++) {
            const float *p = m->positions + 3 * (size_t)m->indices[3 * (size_t)h[k].prim_id + (size_t)c];
            corner[k][c] = affine3_point(to_world, v3(p[0], p[1], p[2]));
        }
    }
    for (int c = 0; c < 3; c++)
        if (v3_length(v3_sub(corner[0][c], corner[1][c])) > 1e-5f)
            return false;
    return true;
}

Test(instances, placed_geometry_traces_and_shades_like_baked_geometry)
{
    scene *si = boxes_scene(true), *sb = boxes_scene(false);
    cr_assert_eq(si->geometry_count, 2u, "instanced: the box is stored once");
    cr_assert_eq(si->instance_count, 5u);
    cr_assert_eq(sb->geometry_count, 5u);
    cr_assert_eq(scene_instanced_triangle_count(si), scene_instanced_triangle_count(sb));
    tess_error err = {{0}};
    accel *ai = accel_build(si, 2, &err), *ab = accel_build(sb, 2, &err);
    cr_assert(ai && ab, "%s", err.msg);
    /* the unplaced box at the origin is hidden in both */
    accel_set_hidden(ai, 1, true);
    accel_set_hidden(ab, 1, true);
    accel_commit(ai);
    accel_commit(ab);
    vec3 lo_i, hi_i, lo_b, hi_b;
    cr_assert(scene_bounds(si, &lo_i, &hi_i) && scene_bounds(sb, &lo_b, &hi_b));
    cr_assert_float_eq(hi_i.y, hi_b.y, 1e-5f);

    camera_desc c = {.eye = v3(4.f, 5.f, 7.f), .look_at = v3(0.f, 0.5f, 0.f), .up = v3(0.f, 1.f, 0.f), .fov_deg = 45.f};
    const int w = 96, h = 64;
    camera_basis cam = camera_basis_make(&c, w, h);
    int box_hits = 0, id_mismatch = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            ray r = {cam.eye, camera_pixel_direction(&cam, x, y), 0.f, INFINITY};
            hit hi_, hb;
            bool a_hit = accel_intersect(ai, &r, &hi_), b_hit = accel_intersect(ab, &r, &hb);
            cr_assert_eq(a_hit, b_hit, "pixel (%d, %d): hit %d vs baked %d", x, y, a_hit, b_hit);
            if (!a_hit)
                continue;
            cr_assert_float_eq(hi_.t, hb.t, 1e-4f * hb.t, "pixel (%d, %d): t %g vs baked %g", x, y, (double)hi_.t,
                               (double)hb.t);
            box_hits += hi_.geom_id >= 2;
            id_mismatch += hi_.geom_id != hb.geom_id || !same_world_triangle(si, hi_, sb, hb);
        }
    cr_assert_gt(box_hits, 300, "the boxes are in view (%d)", box_hits);
    /* the triangles may differ only where two tie within rounding (box edges) */
    cr_assert_lt(id_mismatch, box_hits / 50, "%d of %d hits are on another triangle", id_mismatch, box_hits);

    /* shaded images: the same within rounding, shadows included (no acne
     * from the transformed positions) */
    render_view vi = {.scene = si, .accel = ai, .camera = cam, .shadows = true, .shading = RENDER_SHADE_PHONG};
    render_view vb = vi;
    vb.scene = sb;
    vb.accel = ab;
    float *img_i = calloc((size_t)w * h * 3, sizeof(float)), *img_b = calloc((size_t)w * h * 3, sizeof(float));
    render_image(&vi, 2, img_i, NULL);
    render_image(&vb, 2, img_b, NULL);
    int differ = 0;
    for (int i = 0; i < w * h * 3; i++)
        differ += fabsf(img_i[i] - img_b[i]) > 0.02f;
    cr_assert_lt(differ, w * h * 3 / 200, "%d of %d channel values differ by more than 0.02", differ, w * h * 3);
    free(img_i);
    free(img_b);
    accel_destroy(ai);
    accel_destroy(ab);
    scene_destroy(si);
    scene_destroy(sb);
}

Test(instances, packets_equal_single_rays_through_transformed_instances)
{
    scene *s = boxes_scene(true);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    camera_desc c = {.eye = v3(4.f, 5.f, 7.f), .look_at = v3(0.f, 0.5f, 0.f), .up = v3(0.f, 1.f, 0.f), .fov_deg = 45.f};
    camera_basis cam = camera_basis_make(&c, 64, 64);
    ray_packet *p = aligned_alloc(64, sizeof *p);
    for (int hide = 0; hide < 2; hide++) {
        accel_set_hidden(a, 3, hide == 1); /* the rotated box */
        for (int ty = 0; ty < 64; ty += 8)
            for (int tx = 0; tx < 64; tx += 8) {
                packet_primary(p, &cam, tx, ty, 8, 8);
                accel_intersect_packet(a, packet_whole(p));
                for (uint32_t i = 0; i < p->count; i++) {
                    ray r = packet_get_ray(p, i);
                    r.t_far = FLT_MAX;
                    hit want, got = packet_get_hit(p, i);
                    accel_intersect(a, &r, &want);
                    cr_assert(memcmp(&want, &got, sizeof want) == 0,
                              "hide %d ray %u tile (%d, %d): packet t %a geom %u prim %u, single t %a geom %u prim %u",
                              hide, i, tx, ty, (double)got.t, got.geom_id, got.prim_id, (double)want.t, want.geom_id,
                              want.prim_id);
                    cr_assert(!(hide && got.geom_id == 3), "a hidden instance was hit");
                }
                packet_primary(p, &cam, tx, ty, 8, 8);
                uint64_t occluded = accel_occluded_packet(a, packet_whole(p));
                for (uint32_t i = 0; i < p->count; i++) {
                    ray r = packet_get_ray(p, i);
                    cr_assert_eq((occluded >> i & 1u) != 0, accel_occluded(a, &r));
                }
            }
    }
    free(p);
    accel_destroy(a);
    scene_destroy(s);
}

Test(instances, a_singular_or_non_finite_transform_is_refused)
{
    scene *s = scene_create();
    material grey = material_default();
    int mat = scene_add_material(s, &grey);
    cr_assert_geq(scene_add_mesh(s, unit_box(), (uint32_t)mat, "box"), 0);
    affine3 flat = {{1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0}};
    cr_assert_eq(scene_add_instance(s, 0, &flat, SCENE_NO_PART), -1);
    affine3 nan_t = affine3_identity();
    nan_t.m[3] = NAN;
    cr_assert_eq(scene_add_instance(s, 0, &nan_t, SCENE_NO_PART), -1);
    cr_assert_eq(scene_add_instance(s, 7, NULL, SCENE_NO_PART), -1);
    cr_assert_eq(s->instance_count, 1u);
    scene_destroy(s);
}

/* ---- highlight and colour from the frame state ------------------------ */

Test(geometry_kind, highlight_and_colour_of_the_frame_state_tint_only_their_instances)
{
    int destroyed = 0;
    uint32_t disc_inst;
    scene *s = disc_scene(&destroyed, &disc_inst);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    const int w = 48, h = 48;
    render_view v = {.scene = s, .accel = a, .camera = top_camera(w, h), .shadows = true,
                     .shading = RENDER_SHADE_PHONG};
    size_t n = (size_t)w * h * 3;
    float *plain = calloc(n, sizeof(float)), *tinted = calloc(n, sizeof(float));
    render_image(&v, 1, plain, NULL);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), true, 1, s->instance_count);
    v.state = &st;
    render_image(&v, 1, tinted, NULL);
    cr_assert(memcmp(plain, tinted, n * sizeof(float)) == 0, "an empty frame state changes the picture");

    cr_assert(frame_state_set_highlight(&st, disc_inst, 1, true));
    render_image(&v, 1, tinted, NULL);
    vec3 before = pixel(plain, w, w / 2, h / 2), after = pixel(tinted, w, w / 2, h / 2);
    cr_assert_gt(after.y, before.y + 0.1f, "the highlighted disc is not tinted: g %g -> %g", (double)before.y,
                 (double)after.y);
    vec3 floor_before = pixel(plain, w, 2, 2), floor_after = pixel(tinted, w, 2, 2);
    cr_assert(memcmp(&floor_before, &floor_after, sizeof floor_before) == 0, "the floor changed with the disc's highlight");

    cr_assert(frame_state_set_highlight(&st, disc_inst, 1, false));
    const float blue[3] = {0.f, 0.f, 1.f};
    cr_assert(frame_state_set_colour(&st, 0, 1, blue));
    render_image(&v, 1, tinted, NULL);
    floor_after = pixel(tinted, w, 2, 2);
    cr_assert(floor_after.x == 0.f && floor_after.z > 0.3f, "the floor's colour override: (%g, %g, %g)",
              (double)floor_after.x, (double)floor_after.y, (double)floor_after.z);
    after = pixel(tinted, w, w / 2, h / 2);
    cr_assert(memcmp(&before, &after, sizeof before) == 0, "the disc changed with the floor's colour");
    cr_assert(frame_state_set_colour(&st, 0, 1, NULL));
    render_image(&v, 1, tinted, NULL);
    cr_assert(memcmp(plain, tinted, n * sizeof(float)) == 0, "highlight off and colour removed: not the plain picture");

    frame_state_finish(&st);
    free(plain);
    free(tinted);
    accel_destroy(a);
    scene_destroy(s);
}

/* Scene boxes_scene(true) with instance 2 placed by `move` after its own
 * placement, built directly (what a move transaction must equal). */
static scene *boxes_scene_moved(const affine3 *move)
{
    scene *s = boxes_scene(true);
    affine3 composed = affine3_compose(move, &s->instances[2].to_world);
    affine3 inverse;
    cr_assert(affine3_invert(&composed, &inverse));
    s->instances[2].to_world = composed;
    s->instances[2].to_object = inverse;
    s->instances[2].identity = false;
    return s;
}

Test(instances, a_move_transaction_places_an_instance_as_if_the_scene_had)
{
    const affine3 move = {{0.8f, -0.6f, 0.f, 1.5f, 0.6f, 0.8f, 0.f, 0.25f, 0.f, 0.f, 1.f, -1.f}};
    scene *s = boxes_scene(true), *want = boxes_scene_moved(&move);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err), *aw = accel_build(want, 1, &err);
    cr_assert(a && aw, "%s", err.msg);
    accel_set_hidden(a, 1, true);
    accel_set_hidden(aw, 1, true);
    camera_desc c = {.eye = v3(4.f, 5.f, 7.f), .look_at = v3(0.f, 0.5f, 0.f), .up = v3(0.f, 1.f, 0.f), .fov_deg = 45.f};
    const int w = 64, h = 48;
    render_view v = {.scene = s, .accel = a, .camera = camera_basis_make(&c, w, h), .shadows = true,
                     .shading = RENDER_SHADE_PHONG};
    render_view vw = v;
    vw.scene = want;
    vw.accel = aw;
    size_t n = (size_t)w * h * 3;
    float *before = calloc(n, sizeof(float)), *img = calloc(n, sizeof(float)), *ref = calloc(n, sizeof(float));
    render_image(&v, 1, before, NULL);
    render_image(&vw, 1, ref, NULL);
    cr_assert(memcmp(before, ref, n * sizeof(float)) != 0, "the move does not change the picture");

    /* through the frame state, as the serial section does it */
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), true, 1, s->instance_count);
    txn_record r = txn_move(2, 1, move.m);
    cr_assert(txn_apply(&r, &st, &err), "%s", err.msg);
    cr_assert_geq(frame_state_sync_accel(&st, a), 1u);
    render_image(&v, 1, img, NULL);
    cr_assert(memcmp(img, ref, n * sizeof(float)) == 0, "moved: not the picture of the scene placed so");
    const accel_placement *pl = accel_placement_of(a, 2);
    cr_assert(memcmp(&pl->to_world, &want->instances[2].to_world, sizeof pl->to_world) == 0);

    /* the identity puts it back, bit for bit */
    const float id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    r = txn_move(2, 1, id);
    cr_assert(txn_apply(&r, &st, &err), "%s", err.msg);
    frame_state_sync_accel(&st, a);
    render_image(&v, 1, img, NULL);
    cr_assert(memcmp(img, before, n * sizeof(float)) == 0, "moved back: not the original picture");
    frame_state_finish(&st);
    free(before);
    free(img);
    free(ref);
    accel_destroy(a);
    accel_destroy(aw);
    scene_destroy(s);
    scene_destroy(want);
}
