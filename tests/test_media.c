/* test_media.c - participating media (scene.h, PARTICIPATING MEDIA): a
 * medium defined here (constant extinction in a unit box: transmittance
 * exp(-sigma L), colour c (1 - exp(-sigma L)) over a segment of length L)
 * is composited in front of each ray's first surface, and stops there;
 * cutting planes cut it. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/frame/txn.h"

#define SIGMA 0.7f

static bool fog_bounds(const void *data, aabb *out)
{
    (void)data;
    *out = (aabb){v3(-1.f, -1.f, -1.f), v3(1.f, 1.f, 1.f)};
    return true;
}

static void fog_integrate(const void *data, const ray *r, float jitter, vec3 *rgb, float *transmittance)
{
    (void)data;
    (void)jitter;
    float length = (r->t_far - r->t_near) * v3_length(r->dir);
    float t = expf(-SIGMA * length);
    *transmittance = t;
    *rgb = v3_scale(v3(0.2f, 0.4f, 0.8f), 1.f - t);
}

static const medium_ops fog_ops = {.name = "fog", .bounds = fog_bounds, .integrate = fog_integrate};

/* A white floor at z = -3 facing +z, lit head on; the fog box scaled by `scale` in x. */
static scene *fog_scene(bool with_fog, float scale)
{
    scene *s = scene_create();
    material m = material_default();
    m.diffuse = v3(1.f, 1.f, 1.f);
    int mat = scene_add_material(s, &m);
    mesh *q = mesh_create();
    cr_assert(mesh_add_vertex(q, -10.f, -10.f, -3.f) && mesh_add_vertex(q, 10.f, -10.f, -3.f) &&
              mesh_add_vertex(q, 10.f, 10.f, -3.f) && mesh_add_vertex(q, -10.f, 10.f, -3.f));
    cr_assert(mesh_add_triangle(q, 0, 1, 2) && mesh_add_triangle(q, 0, 2, 3));
    cr_assert_geq(scene_add_mesh(s, q, (uint32_t)mat, "floor"), 0);
    light l = light_default_directional();
    l.direction = v3(0.f, 0.f, 1.f);
    l.casts_shadows = false;
    cr_assert_geq(scene_add_light(s, &l), 0);
    s->ambient = v3(0.f, 0.f, 0.f);
    if (with_fog) {
        affine3 stretch = {{scale, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f}};
        cr_assert_geq(scene_add_medium(s, &fog_ops, NULL, &stretch, "fog"), 0);
    }
    return s;
}

/* The centre pixel looking down -z from z = 5 (through 2 units of fog, then
 * the floor), rendered with frame state `st` (NULL: none). */
static vec3 centre_pixel_with(scene *s, const frame_state *st)
{
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    camera_desc c = {.eye = v3(0.f, 0.f, 5.f), .look_at = v3(0.f, 0.f, 0.f), .up = v3(0.f, 1.f, 0.f), .fov_deg = 30.f};
    render_view v = {.scene = s, .accel = a, .camera = camera_basis_make(&c, 33, 33), .shading = RENDER_SHADE_PHONG,
                     .state = st};
    float *rgb = calloc(33 * 33 * 3, sizeof *rgb);
    render_image(&v, 2, rgb, NULL);
    vec3 px = v3(rgb[3 * (16 * 33 + 16)], rgb[3 * (16 * 33 + 16) + 1], rgb[3 * (16 * 33 + 16) + 2]);
    free(rgb);
    accel_destroy(a);
    return px;
}

static vec3 centre_pixel(scene *s) { return centre_pixel_with(s, NULL); }

/* The centre pixel with every surface of opacity 0.5. */
static vec3 centre_pixel_half_opaque(scene *s)
{
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    frame_state_set_global_opacity(&st, 0.5f);
    vec3 px = centre_pixel_with(s, &st);
    frame_state_finish(&st);
    return px;
}

Test(media, a_medium_is_composited_in_front_of_the_first_surface)
{
    scene *clear = fog_scene(false, 1.f), *foggy = fog_scene(true, 1.f);
    vec3 floor = centre_pixel(clear), seen = centre_pixel(foggy);
    float t = expf(-SIGMA * 2.f); /* the centre ray crosses the box's 2 units of depth */
    vec3 want = v3_add(v3_scale(v3(0.2f, 0.4f, 0.8f), 1.f - t), v3_scale(floor, t));
    cr_assert_gt(floor.x, 0.5f, "the floor is lit");
    cr_assert_float_eq(seen.x, want.x, 1e-5f);
    cr_assert_float_eq(seen.y, want.y, 1e-5f);
    cr_assert_float_eq(seen.z, want.z, 1e-5f);
    scene_destroy(clear);
    scene_destroy(foggy);
}

/* A surface inside the medium ends the integration there. */
Test(media, integration_stops_at_the_first_surface)
{
    scene *s = fog_scene(true, 1.f);
    /* a second floor inside the fog at z = 0.5: 0.5 units of fog in front of it */
    mesh *q = mesh_create();
    cr_assert(mesh_add_vertex(q, -10.f, -10.f, 0.5f) && mesh_add_vertex(q, 10.f, -10.f, 0.5f) &&
              mesh_add_vertex(q, 10.f, 10.f, 0.5f) && mesh_add_vertex(q, -10.f, 10.f, 0.5f));
    cr_assert(mesh_add_triangle(q, 0, 1, 2) && mesh_add_triangle(q, 0, 2, 3));
    cr_assert_geq(scene_add_mesh(s, q, 0, "inner"), 0);
    scene *bare = fog_scene(false, 1.f);
    vec3 floor = centre_pixel(bare), seen = centre_pixel(s);
    float t = expf(-SIGMA * 0.5f);
    cr_assert_float_eq(seen.z, 0.8f * (1.f - t) + floor.z * t, 1e-5f);
    scene_destroy(s);
    scene_destroy(bare);
}

/* A medium placed by a transform is integrated in its own space (a box
 * stretched along x is as deep along z as before), and frames the camera. */
Test(media, placed_media_bound_the_scene)
{
    scene *s = scene_create();
    affine3 far = {{1.f, 0.f, 0.f, 10.f, 0.f, 1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f}};
    cr_assert_geq(scene_add_medium(s, &fog_ops, NULL, &far, "fog"), 0);
    vec3 lo, hi;
    cr_assert(scene_bounds(s, &lo, &hi));
    cr_assert_float_eq(lo.x, 9.f, 1e-4f, "affine3_box widens by a few ulps at most");
    cr_assert_float_eq(hi.x, 11.f, 1e-4f);
    affine3 singular = {{0}};
    cr_assert_eq(scene_add_medium(s, &fog_ops, NULL, &singular, "bad"), -1);
    scene_destroy(s);
}

/* With transparent surfaces (the layer walk reuses the packet) the medium
 * still goes in front of each ray's first surface: foggy = fog + T x clear. */
Test(media, media_and_transparency_compose)
{
    scene *clear = fog_scene(false, 1.f), *foggy = fog_scene(true, 1.f);
    vec3 px[2] = {centre_pixel_half_opaque(clear), centre_pixel_half_opaque(foggy)};
    float t = expf(-SIGMA * 2.f);
    cr_assert_float_eq(px[1].z, 0.8f * (1.f - t) + px[0].z * t, 1e-5f, "%g vs %g", (double)px[1].z,
                       (double)(0.8f * (1.f - t) + px[0].z * t));
    scene_destroy(clear);
    scene_destroy(foggy);
}

/* A cutting plane cuts media too: the plane z = 0 removing z > 0 leaves one
 * unit of the fog (z in [-1, 0]) in front of the floor. */
Test(media, cutting_planes_cut_media)
{
    scene *s = fog_scene(true, 1.f), *clear = fog_scene(false, 1.f);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    vec3 px[2];
    px[0] = centre_pixel_with(s, &st);
    const float point[3] = {0.f, 0.f, 0.f}, normal[3] = {0.f, 0.f, 1.f};
    txn_record r = txn_clip_plane(0, true, point, normal);
    tess_error err = {{0}};
    cr_assert(txn_apply(&r, &st, &err), "%s", err.msg);
    px[1] = centre_pixel_with(s, &st);
    vec3 floor_px = centre_pixel(clear);
    for (int cut = 0; cut < 2; cut++) {
        float t = expf(-SIGMA * (cut ? 1.f : 2.f));
        cr_expect_float_eq(px[cut].z, 0.8f * (1.f - t) + floor_px.z * t, 1e-5f, "cut %d: %g vs %g", cut,
                           (double)px[cut].z, (double)(0.8f * (1.f - t) + floor_px.z * t));
    }
    frame_state_finish(&st);
    scene_destroy(s);
    scene_destroy(clear);
}

/* A white quad at z = `z` (10 x 10 around the axis) facing +z. */
static void add_quad(scene *s, uint32_t material_id, float z, const char *name)
{
    mesh *q = mesh_create();
    cr_assert(mesh_add_vertex(q, -10.f, -10.f, z) && mesh_add_vertex(q, 10.f, -10.f, z) &&
              mesh_add_vertex(q, 10.f, 10.f, z) && mesh_add_vertex(q, -10.f, 10.f, z));
    cr_assert(mesh_add_triangle(q, 0, 1, 2) && mesh_add_triangle(q, 0, 2, 3));
    cr_assert_geq(scene_add_mesh(s, q, material_id, name), 0);
}

/* Media go between translucent surfaces: a white sheet at z = 0 in the
 * middle of the fog and the white floor at z = -3, both of opacity 0.5.
 * Front to back: fog over z 1..0 (F, T: one unit), the sheet (C), fog over
 * z 0..-1 (F, T), the floor (C), the background (B):
 *     F + T (C/2 + 1/2 (F + T (C/2 + B/2)))
 * with C from the same view without fog (C/2 + C/4 + B/4). */
Test(media, media_lie_between_translucent_surfaces)
{
    vec3 px[2];
    float background = 0.f;
    for (int fog = 0; fog < 2; fog++) {
        scene *s = fog_scene(fog == 1, 1.f);
        add_quad(s, 0, 0.f, "sheet");
        background = s->background.z;
        px[fog] = centre_pixel_half_opaque(s);
        scene_destroy(s);
    }
    float C = (px[0].z - 0.25f * background) / 0.75f;
    float T = expf(-SIGMA * 1.f), F = 0.8f * (1.f - T);
    float want = F + T * (0.5f * C + 0.5f * (F + T * (0.5f * C + 0.5f * background)));
    cr_assert_float_eq(px[1].z, want, 1e-5f, "fog between the layers: %g, want %g (C %g)", (double)px[1].z,
                       (double)want, (double)C);
}
