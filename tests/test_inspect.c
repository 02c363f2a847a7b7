/* test_inspect.c - transparency and cutting planes against analytic results:
 * stacks of coplanar and parallel panes, a transparent sphere over a
 * checkerboard, shadows through a pane, the layer and transmittance limits;
 * caps of a cut sphere and of a mesh cut through its vertices, open parts not
 * capped, shadow rays clipped like primary ones, several planes; every image
 * the same for any thread count. Scenes are generated here. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/accel/clip.h"
#include "engine/scene/frame_state.h"
#include "engine/accel/packet.h"
#include "engine/render/render.h"
#include "engine/render/render_ao.h"
#include "engine/scene/scene.h"

static scene *bare_scene(vec3 background, vec3 ambient)
{
    scene *s = scene_create();
    cr_assert(s);
    s->background = background;
    s->ambient = ambient;
    return s;
}

static uint32_t lambert(scene *s, vec3 albedo, float ambient)
{
    material m = material_default();
    m.model = MATERIAL_LAMBERT;
    m.diffuse = albedo;
    m.ambient = ambient;
    int id = scene_add_material(s, &m);
    cr_assert(id >= 0);
    return (uint32_t)id;
}

/* A square [x0, x1] x [y0, y1] at height z, facing +z; its own instance. */
static uint32_t add_pane(scene *s, float x0, float y0, float x1, float y1, float z, uint32_t mat)
{
    mesh *m = mesh_create();
    cr_assert(m);
    cr_assert(mesh_add_vertex(m, x0, y0, z) && mesh_add_vertex(m, x1, y0, z) && mesh_add_vertex(m, x1, y1, z) &&
              mesh_add_vertex(m, x0, y1, z));
    cr_assert(mesh_add_triangle(m, 0, 1, 2) && mesh_add_triangle(m, 0, 2, 3));
    int id = scene_add_mesh(s, m, mat, "pane");
    cr_assert(id >= 0);
    return (uint32_t)(s->instance_count - 1);
}

/* The closed surface of the box [-1, 1]^3, every face an n x n grid (n even:
 * the planes x, y, z = 0 run through vertices and edges). Skip face `open`
 * (0..5) to leave a hole; -1 for none. */
static void add_grid_cube(scene *s, int n, int open, uint32_t mat)
{
    mesh *m = mesh_create();
    cr_assert(m);
    for (int f = 0; f < 6; f++) {
        if (f == open)
            continue;
        int axis = f / 2;
        float side = f % 2 ? 1.f : -1.f;
        uint32_t base = m->vertex_count;
        for (int j = 0; j <= n; j++)
            for (int i = 0; i <= n; i++) {
                float u = -1.f + 2.f * (float)i / (float)n, w = -1.f + 2.f * (float)j / (float)n;
                float p[3];
                p[axis] = side;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = w;
                cr_assert(mesh_add_vertex(m, p[0], p[1], p[2]));
            }
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                uint32_t a = base + (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
                cr_assert(mesh_add_triangle(m, a, b, d) && mesh_add_triangle(m, a, d, c));
            }
    }
    cr_assert(scene_add_mesh(s, m, mat, "cube") >= 0);
}

typedef struct fixture {
    scene *s;
    accel *a;
    frame_state st;
    render_settings set;
} fixture;

static void fixture_open(fixture *fx, scene *s)
{
    tess_error err = {{0}};
    fx->s = s;
    fx->a = accel_build(s, 1, &err);
    cr_assert(fx->a, "%s", err.msg);
    frame_state_init(&fx->st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    fx->set = render_settings_default();
}

static void fixture_close(fixture *fx)
{
    frame_state_finish(&fx->st);
    accel_destroy(fx->a);
    scene_destroy(fx->s);
}

static render_view fixture_view(const fixture *fx, camera_desc cam, int w, int h, bool shadows)
{
    return (render_view){.scene = fx->s, .accel = fx->a, .camera = camera_basis_make(&cam, w, h), .shadows = shadows,
                         .shading = RENDER_SHADE_PHONG, .state = &fx->st, .settings = &fx->set};
}

static float *render_fixture(const fixture *fx, camera_desc cam, int w, int h, bool shadows, int threads)
{
    float *rgb = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(rgb);
    render_view v = fixture_view(fx, cam, w, h, shadows);
    render_image(&v, threads, rgb, NULL);
    return rgb;
}

static vec3 pixel(const float *rgb, int w, int x, int y)
{
    const float *p = rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
    return v3(p[0], p[1], p[2]);
}

static bool near3(vec3 a, vec3 b, float tol)
{
    return fabsf(a.x - b.x) <= tol && fabsf(a.y - b.y) <= tol && fabsf(a.z - b.z) <= tol;
}

/* Front-to-back blending as the renderer defines it, step by step in float. */
typedef struct blend {
    vec3 sum;
    float transmit;
} blend;

static void blend_add(blend *b, vec3 colour, float alpha)
{
    b->sum = v3_add(b->sum, v3_scale(colour, b->transmit * alpha));
    b->transmit *= 1.f - alpha;
}

/* ---- transparency ---- */

/* Four panes seen from above: two coplanar at z = 0 (ids 0 and 1, so 0 is
 * in front), one at z = -1, an opaque one at z = -2; only ambient light, so a
 * surface's colour is its albedo. */
Test(transparency, coplanar_and_parallel_stack)
{
    scene *s = bare_scene(v3(0.1f, 0.2f, 0.3f), v3(1.f, 1.f, 1.f));
    const vec3 colour[4] = {v3(1.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), v3(0.f, 0.f, 1.f), v3(1.f, 1.f, 1.f)};
    const float z[4] = {0.f, 0.f, -1.f, -2.f}, alpha[4] = {0.5f, 0.25f, 0.6f, 1.f};
    for (int k = 0; k < 4; k++)
        add_pane(s, -4.f, -4.f, 4.f, 4.f, z[k], lambert(s, colour[k], 1.f));
    fixture fx;
    fixture_open(&fx, s);
    for (uint32_t k = 0; k < 4; k++)
        cr_assert(frame_state_set_opacity(&fx.st, k, 1, alpha[k]));
    camera_desc cam = {v3(0.3f, 0.2f, 10.f), v3(0.3f, 0.2f, 0.f), v3(0.f, 1.f, 0.f), 20.f};
    const int w = 32, h = 24;
    float *rgb = render_fixture(&fx, cam, w, h, false, 1);
    blend want = {v3(0.f, 0.f, 0.f), 1.f};
    for (int k = 0; k < 4; k++)
        blend_add(&want, colour[k], alpha[k]);
    long wrong = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            wrong += !near3(pixel(rgb, w, x, y), want.sum, 1e-6f);
    cr_expect_eq(wrong, 0, "%ld of %d pixels differ from the blend (%g %g %g)", wrong, w * h, (double)want.sum.x,
                 (double)want.sum.y, (double)want.sum.z);
    free(rgb);
    /* the global opacity multiplies every part's; the last pane stays opaque */
    frame_state_set_global_opacity(&fx.st, 0.5f);
    rgb = render_fixture(&fx, cam, w, h, false, 1);
    want = (blend){v3(0.f, 0.f, 0.f), 1.f};
    for (int k = 0; k < 4; k++)
        blend_add(&want, colour[k], 0.5f * alpha[k]);
    want.sum = v3_add(want.sum, v3_scale(s->background, want.transmit));
    cr_expect(near3(pixel(rgb, w, w / 2, h / 2), want.sum, 1e-6f), "global 0.5: got %g %g %g want %g %g %g",
              (double)pixel(rgb, w, w / 2, h / 2).x, (double)pixel(rgb, w, w / 2, h / 2).y,
              (double)pixel(rgb, w, w / 2, h / 2).z, (double)want.sum.x, (double)want.sum.y, (double)want.sum.z);
    free(rgb);
    fixture_close(&fx);
}

/* max_layers: the last layer counts as opaque; min_transmittance: the rest is dropped. */
Test(transparency, layer_limit_and_transmittance_threshold)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
    vec3 colour[10];
    for (int k = 0; k < 10; k++) {
        colour[k] = v3(0.1f * (float)k, 1.f - 0.1f * (float)k, 0.5f);
        add_pane(s, -4.f, -4.f, 4.f, 4.f, -(float)k, lambert(s, colour[k], 1.f));
    }
    fixture fx;
    fixture_open(&fx, s);
    cr_assert(frame_state_set_opacity(&fx.st, 0, 10, 0.5f));
    camera_desc cam = {v3(0.f, 0.f, 10.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 10.f};
    fx.set.max_layers = 3;
    float *rgb = render_fixture(&fx, cam, 9, 9, false, 1);
    blend want = {v3(0.f, 0.f, 0.f), 1.f};
    blend_add(&want, colour[0], 0.5f);
    blend_add(&want, colour[1], 0.5f);
    blend_add(&want, colour[2], 1.f);
    cr_expect(near3(pixel(rgb, 9, 4, 4), want.sum, 1e-6f), "3 layers: %g %g %g, want %g %g %g",
              (double)pixel(rgb, 9, 4, 4).x, (double)pixel(rgb, 9, 4, 4).y, (double)pixel(rgb, 9, 4, 4).z,
              (double)want.sum.x, (double)want.sum.y, (double)want.sum.z);
    free(rgb);
    fx.set.max_layers = 16;
    fx.set.min_transmittance = 0.3f; /* after two panes 0.25 is left: stop */
    rgb = render_fixture(&fx, cam, 9, 9, false, 1);
    want = (blend){v3(0.f, 0.f, 0.f), 1.f};
    blend_add(&want, colour[0], 0.5f);
    blend_add(&want, colour[1], 0.5f);
    cr_expect(near3(pixel(rgb, 9, 4, 4), want.sum, 1e-6f), "threshold 0.3");
    free(rgb);
    fixture_close(&fx);
}

/* Which checker cell (0 or 1) world point (x, y) on the board lies in, or -1 near an edge. */
static int checker_cell(double x, double y, double cell, double margin)
{
    double fx = x / cell - floor(x / cell), fy = y / cell - floor(y / cell);
    if (fx < margin || fx > 1.0 - margin || fy < margin || fy > 1.0 - margin)
        return -1;
    return (int)(floor(x / cell) + floor(y / cell)) & 1;
}

/* A sphere of opacity 0.3 over a checkerboard: through the sphere a pixel is
 * a * S + (1 - a) a S + (1 - a)^2 C (front face, back face, the cell), else
 * the cell's colour C; found by intersecting each pixel's ray in double. */
Test(transparency, sphere_over_checkerboard_is_the_closed_form_blend)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
    const vec3 cell_colour[2] = {v3(0.9f, 0.2f, 0.1f), v3(0.1f, 0.3f, 0.8f)}, sphere_colour = v3(0.9f, 0.8f, 0.1f);
    uint32_t mats[2] = {lambert(s, cell_colour[0], 1.f), lambert(s, cell_colour[1], 1.f)};
    const float cell = 0.5f;
    for (int j = -8; j < 8; j++)
        for (int i = -8; i < 8; i++)
            add_pane(s, (float)i * cell, (float)j * cell, (float)(i + 1) * cell, (float)(j + 1) * cell, 0.f,
                     mats[(i + j) & 1]);
    const vec3 centre = v3(0.2f, -0.1f, 1.5f);
    const float radius = 1.f, a = 0.3f;
    cr_assert(scene_add_sphere(s, centre, radius, lambert(s, sphere_colour, 1.f)) >= 0);
    fixture fx;
    fixture_open(&fx, s);
    cr_assert(frame_state_set_opacity(&fx.st, s->sphere_instance, 1, a));
    camera_desc cam = {v3(0.f, 0.f, 8.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    const int w = 96, h = 96;
    float *rgb = render_fixture(&fx, cam, w, h, false, 2);
    render_view v = fixture_view(&fx, cam, w, h, false);
    long checked = 0, through = 0, wrong = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            ray r = packet_primary_ray_at(&v.camera, (float)x + 0.5f, (float)y + 0.5f);
            double o[3] = {r.org.x, r.org.y, r.org.z}, d[3] = {r.dir.x, r.dir.y, r.dir.z};
            double t_board = -o[2] / d[2];
            int c = checker_cell(o[0] + t_board * d[0], o[1] + t_board * d[1], cell, 1e-3);
            if (c < 0 || fabs(o[0] + t_board * d[0]) > 3.9 || fabs(o[1] + t_board * d[1]) > 3.9)
                continue;
            double f[3] = {o[0] - centre.x, o[1] - centre.y, o[2] - centre.z};
            double bq = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
            double cq = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - (double)radius * radius;
            double disc = bq * bq - cq; /* |d| = 1 */
            if (fabs(disc) < 1e-3)
                continue; /* the silhouette */
            blend want = {v3(0.f, 0.f, 0.f), 1.f};
            if (disc > 0) {
                blend_add(&want, sphere_colour, a);
                blend_add(&want, sphere_colour, a);
                through++;
            }
            blend_add(&want, cell_colour[c], 1.f);
            checked++;
            wrong += !near3(pixel(rgb, w, x, y), want.sum, 1e-5f);
        }
    cr_expect(through > 1000 && checked > 5000, "%ld pixels checked, %ld through the sphere", checked, through);
    cr_expect_eq(wrong, 0, "%ld of %ld pixels differ from the closed form", wrong, checked);
    free(rgb);
    fixture_close(&fx);
}

/* A pane of opacity a between a light and a floor: the floor in its shadow
 * gets (1 - a) of the light, or none with transparent_shadows off. */
Test(transparency, shadows_through_a_pane)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 0.f));
    const vec3 floor_colour = v3(0.8f, 0.6f, 0.4f);
    add_pane(s, -10.f, -10.f, 10.f, 10.f, 0.f, lambert(s, floor_colour, 0.f));
    uint32_t pane = add_pane(s, -1.f, -1.f, 1.f, 1.f, 1.f, lambert(s, v3(1.f, 1.f, 1.f), 0.f));
    const float k = 0.70710678f;
    light l = {.kind = LIGHT_DIRECTIONAL, .direction = v3(k, 0.f, k), .color = v3(1.f, 1.f, 1.f), .intensity = 1.f,
               .casts_shadows = true};
    cr_assert(scene_add_light(s, &l) >= 0);
    fixture fx;
    fixture_open(&fx, s);
    const float a = 0.35f;
    cr_assert(frame_state_set_opacity(&fx.st, pane, 1, a));
    camera_desc cam = {v3(-1.5f, 0.f, 5.f), v3(-1.5f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 30.f};
    render_view v = fixture_view(&fx, cam, 9, 9, true);
    ray r = {v3(-1.5f, 0.f, 5.f), v3(0.f, 0.f, -1.f), 0.f, FLT_MAX}; /* to (-1.5, 0, 0): in the pane's shadow */
    uint64_t shadow_rays = 0;
    vec3 got = render_shade(&v, &r, &shadow_rays);
    vec3 want = v3_scale(floor_colour, l.direction.z * (1.f - a));
    cr_expect(near3(got, want, 1e-6f), "through the pane: %g %g %g, want %g %g %g", (double)got.x, (double)got.y,
              (double)got.z, (double)want.x, (double)want.y, (double)want.z);
    cr_expect(shadow_rays >= 2, "the shadow ray walks past the pane");
    fx.set.transparent_shadows = false;
    got = render_shade(&v, &r, &shadow_rays);
    cr_expect(near3(got, v3(0.f, 0.f, 0.f), 0.f), "opaque shadows: %g %g %g", (double)got.x, (double)got.y,
              (double)got.z);
    fixture_close(&fx);
}

/* ---- cutting planes ---- */

static void set_plane(frame_state *st, int index, vec3 point, vec3 normal)
{
    clip_plane p = {point, v3_normalize(normal), true};
    frame_state_set_clip_plane(st, index, &p);
}

/* A unit sphere cut by the plane z = 0.3 (the part above removed), seen from
 * above with ambient light only: inside the disc of radius sqrt(1 - 0.09) on
 * the plane the cap (the part's colour x the tint factor), outside it the
 * sphere's surface or the background, exactly where the analytic cut says. */
Test(cutting, sphere_cap_is_the_analytic_disc)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
    const vec3 kd = v3(0.9f, 0.4f, 0.2f);
    cr_assert(scene_add_sphere(s, v3(0.f, 0.f, 0.f), 1.f, lambert(s, kd, 1.f)) >= 0);
    fixture fx;
    fixture_open(&fx, s);
    const double zc = 0.3, disc = sqrt(1.0 - zc * zc);
    set_plane(&fx.st, 2, v3(0.f, 0.f, (float)zc), v3(0.f, 0.f, 1.f));
    camera_desc cam = {v3(0.05f, 0.1f, 6.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 30.f};
    const int w = 128, h = 128;
    float *rgb = render_fixture(&fx, cam, w, h, false, 2);
    render_view v = fixture_view(&fx, cam, w, h, false);
    vec3 cap = pixel(rgb, w, w / 2, h / 2);
    cr_expect(cap.x < kd.x && cap.x > 0.5f * kd.x, "the centre is a (tinted) cap: %g", (double)cap.x);
    long caps = 0, wrong = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            ray r = packet_primary_ray_at(&v.camera, (float)x + 0.5f, (float)y + 0.5f);
            double t = (zc - r.org.z) / r.dir.z;
            double px = r.org.x + t * r.dir.x, py = r.org.y + t * r.dir.y, rho = sqrt(px * px + py * py);
            vec3 got = pixel(rgb, w, x, y);
            if (rho < disc - 1e-3) {
                caps++;
                wrong += !near3(got, cap, 0.f);
            } else if (rho > disc + 1e-3) {
                wrong += near3(got, cap, 1e-4f); /* the surface below, or nothing: never a cap */
            }
        }
    double pixel_side = 2.0 * tan(15.0 * 3.14159265358979 / 180.0) / h, plane_distance = 6.0 - zc;
    double expected = 3.14159265358979 * disc * disc / (pixel_side * plane_distance * pixel_side * plane_distance);
    cr_expect(fabs((double)caps - expected) < 0.02 * expected, "%ld cap pixels, ~%.0f expected", caps, expected);
    cr_expect_eq(wrong, 0, "%ld pixels on the wrong side of the analytic cut", wrong);
    free(rgb);
    fixture_close(&fx);
}

/* A closed grid cube cut by z = 0, which runs through a ring of its vertices
 * and edges: from above, every ray that crosses the plane inside the square
 * sees the cap (no crack lets the background or an inner wall through), and
 * no ray outside it does. */
Test(cutting, mesh_cut_through_its_vertices_has_no_cracks)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
    const vec3 kd = v3(0.3f, 0.7f, 0.9f);
    add_grid_cube(s, 8, -1, lambert(s, kd, 1.f));
    fixture fx;
    fixture_open(&fx, s);
    set_plane(&fx.st, 0, v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f));
    camera_desc cam = {v3(0.37f, -0.21f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    const int w = 160, h = 160;
    float *rgb = render_fixture(&fx, cam, w, h, false, 1);
    render_view v = fixture_view(&fx, cam, w, h, false);
    vec3 cap = v3_scale(kd, 0.8f);
    long inside = 0, wrong = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            ray r = packet_primary_ray_at(&v.camera, (float)x + 0.5f, (float)y + 0.5f);
            double t = -(double)r.org.z / r.dir.z;
            double px = r.org.x + t * r.dir.x, py = r.org.y + t * r.dir.y;
            double edge = fmax(fabs(px), fabs(py));
            vec3 got = pixel(rgb, w, x, y);
            if (edge < 1.0 - 1e-4) {
                inside++;
                wrong += !near3(got, cap, 1e-6f);
            } else if (edge > 1.0 + 1e-4) {
                wrong += near3(got, cap, 1e-6f);
            }
        }
    cr_expect(inside > 2000, "%ld pixels see the cut", inside);
    cr_expect_eq(wrong, 0, "%ld pixels crack or leak", wrong);
    free(rgb);
    fixture_close(&fx);
}

/* The same cube without its bottom face is not closed: no cap; through the
 * cut one sees its inner walls and the background below. */
Test(cutting, open_parts_are_not_capped)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
    const vec3 kd = v3(0.3f, 0.7f, 0.9f);
    add_grid_cube(s, 8, 4, lambert(s, kd, 1.f)); /* face 4: z = -1 */
    fixture fx;
    fixture_open(&fx, s);
    set_plane(&fx.st, 0, v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f));
    camera_desc cam = {v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    float *rgb = render_fixture(&fx, cam, 33, 33, false, 1);
    cr_expect(near3(pixel(rgb, 33, 16, 16), s->background, 0.f), "the centre looks through the open cube");
    long capped = 0;
    for (int i = 0; i < 33 * 33; i++)
        capped += near3(pixel(rgb, 33, i % 33, i / 33), v3_scale(kd, 0.8f), 1e-6f);
    cr_expect_eq(capped, 0, "%ld cap pixels on an open part", capped);
    free(rgb);
    fixture_close(&fx);
}

/* A sphere over a floor, lit from the side; a plane removes the whole sphere
 * (and nothing of the floor): the picture equals the floor alone, shadows
 * included, bit for bit: shadow rays are clipped like primary ones. */
Test(cutting, shadow_rays_are_clipped_like_primary_rays)
{
    const vec3 floor_colour = v3(0.8f, 0.8f, 0.8f);
    light l = {.kind = LIGHT_DIRECTIONAL, .direction = v3_normalize(v3(-1.f, 0.3f, 1.f)), .color = v3(1.f, 1.f, 1.f),
               .intensity = 1.f, .casts_shadows = true};
    camera_desc cam = {v3(0.f, -6.f, 6.f), v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f), 50.f};
    float *img[2];
    for (int k = 0; k < 2; k++) {
        scene *s = bare_scene(v3(0.2f, 0.2f, 0.2f), v3(0.1f, 0.1f, 0.1f));
        add_pane(s, -5.f, -5.f, 5.f, 5.f, 0.f, lambert(s, floor_colour, 1.f));
        cr_assert(scene_add_light(s, &l) >= 0);
        if (k == 1)
            cr_assert(scene_add_sphere(s, v3(0.f, 0.f, 1.5f), 1.f, lambert(s, v3(1.f, 0.f, 0.f), 1.f)) >= 0);
        fixture fx;
        fixture_open(&fx, s);
        if (k == 1)
            set_plane(&fx.st, 5, v3(0.f, 0.f, 0.4f), v3(0.f, 0.f, 1.f));
        img[k] = render_fixture(&fx, cam, 64, 48, true, 1);
        fixture_close(&fx);
    }
    cr_expect(memcmp(img[0], img[1], sizeof(float) * 64 * 48 * 3) == 0,
              "the cut-away sphere still shows or casts a shadow");
    free(img[0]);
    free(img[1]);
}

/* Two planes cut a wedge out of the sphere: each cap lies on its own plane
 * (lit by a directional light through its own normal) and only where both
 * planes keep the point. */
Test(cutting, several_planes_combine)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 0.f));
    const vec3 kd = v3(0.5f, 0.5f, 0.5f);
    cr_assert(scene_add_sphere(s, v3(0.f, 0.f, 0.f), 1.f, lambert(s, kd, 0.f)) >= 0);
    light l = {.kind = LIGHT_DIRECTIONAL, .direction = v3_normalize(v3(0.6f, 0.3f, 1.f)), .color = v3(1.f, 1.f, 1.f),
               .intensity = 1.f, .casts_shadows = false};
    cr_assert(scene_add_light(s, &l) >= 0);
    fixture fx;
    fixture_open(&fx, s);
    const vec3 n[2] = {v3_normalize(v3(1.f, 0.f, 1.f)), v3_normalize(v3(0.f, 1.f, 2.f))};
    const vec3 point[2] = {v3(0.1f, 0.f, 0.f), v3(0.f, 0.f, 0.2f)};
    set_plane(&fx.st, 1, point[0], n[0]);
    set_plane(&fx.st, 6, point[1], n[1]);
    camera_desc cam = {v3(2.f, 1.5f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 35.f};
    const int w = 128, h = 128;
    float *rgb = render_fixture(&fx, cam, w, h, false, 2);
    render_view v = fixture_view(&fx, cam, w, h, false);
    long on_cap[2] = {0, 0}, wrong = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            ray r = packet_primary_ray_at(&v.camera, (float)x + 0.5f, (float)y + 0.5f);
            /* the kept interval in double: entering through plane k at t_k */
            double t_in = 0.0, t_out = INFINITY;
            int entry = -1;
            for (int k = 0; k < 2; k++) {
                double dn = (double)n[k].x * r.dir.x + (double)n[k].y * r.dir.y + (double)n[k].z * r.dir.z;
                double num = (double)n[k].x * (point[k].x - r.org.x) + (double)n[k].y * (point[k].y - r.org.y) +
                             (double)n[k].z * (point[k].z - r.org.z);
                double tc = num / dn;
                if (dn < 0 && tc > t_in)
                    t_in = tc, entry = k;
                else if (dn > 0 && tc < t_out)
                    t_out = tc;
            }
            if (entry < 0 || !(t_in < t_out))
                continue;
            double p[3] = {r.org.x + t_in * r.dir.x, r.org.y + t_in * r.dir.y, r.org.z + t_in * r.dir.z};
            double rho = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            if (rho > 1.0 - 1e-3)
                continue; /* not inside, or too near the rim to say */
            /* an edge of the wedge: both planes within a hair */
            double other = (double)n[1 - entry].x * (p[0] - point[1 - entry].x) +
                           (double)n[1 - entry].y * (p[1] - point[1 - entry].y) +
                           (double)n[1 - entry].z * (p[2] - point[1 - entry].z);
            if (fabs(other) < 1e-3)
                continue;
            vec3 face = v3_dot(n[entry], r.dir) > 0.f ? v3_scale(n[entry], -1.f) : n[entry];
            float lambert_cos = fmaxf(0.f, v3_dot(face, l.direction));
            vec3 want = v3_scale(v3_scale(kd, 0.8f), lambert_cos);
            on_cap[entry]++;
            wrong += !near3(pixel(rgb, w, x, y), want, 1e-5f);
        }
    cr_expect(on_cap[0] > 300 && on_cap[1] > 300, "cap pixels per plane: %ld, %ld", on_cap[0], on_cap[1]);
    cr_expect_eq(wrong, 0, "%ld cap pixels differ from their plane's shading", wrong);
    free(rgb);
    fixture_close(&fx);
}

/* Transparency, caps and several planes together: the same image for 1, 2
 * and 3 threads, and render_shade agrees with the packets. */
Test(cutting, images_are_the_same_for_any_thread_count)
{
    scene *s = bare_scene(v3(0.1f, 0.1f, 0.15f), v3(0.2f, 0.2f, 0.2f));
    add_pane(s, -5.f, -5.f, 5.f, 5.f, -1.2f, lambert(s, v3(0.7f, 0.7f, 0.7f), 1.f));
    add_grid_cube(s, 4, -1, lambert(s, v3(0.2f, 0.6f, 0.9f), 1.f));
    for (int i = 0; i < 6; i++)
        cr_assert(scene_add_sphere(s, v3(-2.f + 0.8f * (float)i, 1.5f, 0.f), 0.5f, lambert(s, v3(0.9f, 0.5f, 0.2f), 1.f)) >=
                  0);
    light l = {.kind = LIGHT_POINT, .position = v3(3.f, -2.f, 6.f), .color = v3(1.f, 1.f, 1.f), .intensity = 30.f,
               .casts_shadows = true};
    cr_assert(scene_add_light(s, &l) >= 0);
    fixture fx;
    fixture_open(&fx, s);
    cr_assert(frame_state_set_opacity(&fx.st, 1, 1, 0.45f));
    cr_assert(frame_state_set_opacity(&fx.st, s->sphere_instance, 1, 0.7f));
    set_plane(&fx.st, 0, v3(0.f, 0.f, 0.3f), v3(0.2f, 0.1f, 1.f));
    set_plane(&fx.st, 3, v3(0.5f, 0.f, 0.f), v3(1.f, -0.2f, 0.3f));
    camera_desc cam = {v3(4.f, -5.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f), 45.f};
    const int w = 70, h = 50;
    float *one = render_fixture(&fx, cam, w, h, true, 1);
    for (int threads = 2; threads <= 3; threads++) {
        float *many = render_fixture(&fx, cam, w, h, true, threads);
        cr_expect(memcmp(one, many, sizeof(float) * (size_t)w * h * 3) == 0, "%d threads differ from one", threads);
        free(many);
    }
    render_view v = fixture_view(&fx, cam, w, h, true);
    static ray_packet p;
    long differ = 0;
    for (int y = 0; y < h; y += 3)
        for (int x = 0; x < w; x += 3) {
            packet_primary(&p, &v.camera, x, y, 1, 1); /* the ray the tile's packet holds for (x, y) */
            ray r = packet_get_ray(&p, 0);
            uint64_t shadow_rays = 0;
            vec3 c = render_shade(&v, &r, &shadow_rays);
            differ += !near3(c, pixel(one, w, x, y), 0.f);
        }
    cr_expect_eq(differ, 0, "%ld pixels differ from render_shade", differ);
    free(one);
    fixture_close(&fx);
}

/* A closed cube standing on an open floor (its bottom face coplanar with the
 * floor, which comes first in id order), cut by x = 0: every ray entering
 * through the plane inside the cube sees the cap, also where the first
 * surface behind the plane is the floor at the same depth as the cube's
 * bottom (the search walks past open parts to the closed one). */
Test(cutting, an_open_surface_in_front_does_not_hide_the_cap)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
    add_pane(s, -4.f, -4.f, 4.f, 4.f, -1.f, lambert(s, v3(0.9f, 0.9f, 0.9f), 1.f));
    const vec3 kd = v3(0.2f, 0.5f, 0.8f);
    add_grid_cube(s, 4, -1, lambert(s, kd, 1.f));
    fixture fx;
    fixture_open(&fx, s);
    set_plane(&fx.st, 0, v3(0.f, 0.f, 0.f), v3(1.f, 0.f, 0.f));
    camera_desc cam = {v3(6.f, 0.4f, 0.5f), v3(0.f, 0.f, -0.6f), v3(0.f, 0.f, 1.f), 40.f};
    const int w = 120, h = 120;
    float *rgb = render_fixture(&fx, cam, w, h, false, 1);
    render_view v = fixture_view(&fx, cam, w, h, false);
    vec3 cap = v3_scale(kd, 0.8f);
    long inside = 0, wrong = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            ray r = packet_primary_ray_at(&v.camera, (float)x + 0.5f, (float)y + 0.5f);
            double t = -(double)r.org.x / r.dir.x;
            double py = r.org.y + t * r.dir.y, pz = r.org.z + t * r.dir.z;
            if (fabs(py) < 1.0 - 1e-4 && fabs(pz) < 1.0 - 1e-4) {
                inside++;
                wrong += !near3(pixel(rgb, w, x, y), cap, 1e-6f);
            }
        }
    cr_expect(inside > 1000, "%ld pixels see the cut", inside);
    cr_expect_eq(wrong, 0, "%ld of %ld pixels inside the cut are not the cap", wrong, inside);
    free(rgb);
    fixture_close(&fx);
}

/* The ao renderer clips its rays too: a cube over a floor, cut away
 * entirely, leaves the floor's ambient occlusion exactly as without it
 * (and without the plane the cube does darken the floor). */
Test(cutting, ao_rays_are_clipped)
{
    camera_desc cam = {v3(0.f, -5.f, 4.f), v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 1.f), 50.f};
    const int w = 48, h = 40;
    float *img[2];
    for (int k = 0; k < 2; k++) {
        scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
        add_pane(s, -3.f, -3.f, 3.f, 3.f, -1.5f, lambert(s, v3(0.8f, 0.8f, 0.8f), 1.f));
        if (k == 1)
            add_grid_cube(s, 2, -1, lambert(s, v3(0.5f, 0.2f, 0.2f), 1.f)); /* 0.5 above the floor: occludes it */
        fixture fx;
        fixture_open(&fx, s);
        fx.set.ao_distance = 2.f;
        if (k == 1)
            set_plane(&fx.st, 0, v3(0.f, 0.f, -1.2f), v3(0.f, 0.f, 1.f));
        img[k] = calloc((size_t)w * h * 3, sizeof(float));
        cr_assert(img[k]);
        render_view v = fixture_view(&fx, cam, w, h, false);
        pixel_sampler single = pixel_sampler_single();
        render_ao_image(&v, &single, 1, 16, img[k], NULL);
        fixture_close(&fx);
    }
    cr_expect(memcmp(img[0], img[1], sizeof(float) * (size_t)w * h * 3) == 0,
              "the cut-away cube still occludes the floor");
    {
        scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f));
        add_pane(s, -3.f, -3.f, 3.f, 3.f, -1.5f, lambert(s, v3(0.8f, 0.8f, 0.8f), 1.f));
        add_grid_cube(s, 2, -1, lambert(s, v3(0.5f, 0.2f, 0.2f), 1.f));
        fixture fx;
        fixture_open(&fx, s);
        fx.set.ao_distance = 2.f;
        float *uncut = calloc((size_t)w * h * 3, sizeof(float));
        cr_assert(uncut);
        render_view v = fixture_view(&fx, cam, w, h, false);
        pixel_sampler single = pixel_sampler_single();
        render_ao_image(&v, &single, 1, 16, uncut, NULL);
        cr_expect(memcmp(img[0], uncut, sizeof(float) * (size_t)w * h * 3) != 0, "the cube should darken the floor");
        free(uncut);
        fixture_close(&fx);
    }
    free(img[0]);
    free(img[1]);
}

/* ---- the raytracer's AO term with planes, caps and transparency ---------- */

static float *render_renderer(const fixture *fx, const char *name, camera_desc cam, int w, int h, bool shadows,
                              int threads, int tile_px)
{
    const renderer *r = renderer_by_name(name);
    cr_assert(r);
    float *rgb = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(rgb);
    render_view v = fixture_view(fx, cam, w, h, shadows);
    v.shading = r->shading;
    pixel_sampler single = pixel_sampler_single();
    render_image_tiles(r, &v, &single, threads, tile_px, rgb, NULL);
    return rgb;
}

/* A unit sphere alone, cut by z = 0.3 and seen from above: the cap's AO rays
 * leave into the cut-away half, which is gone for them as for the eye, and
 * nothing else is near, so the cap (and the convex surface around it) is
 * unoccluded: raytracer-ao is the raytracer bit for bit. Without the clip,
 * the sphere's removed inside would darken the cap. */
Test(cutting, ao_term_sees_the_cut_away_half_as_gone)
{
    scene *s = bare_scene(v3(0.f, 0.f, 0.f), v3(0.5f, 0.5f, 0.5f));
    cr_assert(scene_add_sphere(s, v3(0.f, 0.f, 0.f), 1.f, lambert(s, v3(0.9f, 0.4f, 0.2f), 1.f)) >= 0);
    light l = light_default_directional();
    cr_assert(scene_add_light(s, &l) >= 0);
    fixture fx;
    fixture_open(&fx, s);
    fx.set.ao_distance = 5.f;
    set_plane(&fx.st, 0, v3(0.f, 0.f, 0.3f), v3(0.f, 0.f, 1.f));
    camera_desc cam = {v3(0.05f, 0.1f, 6.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 30.f};
    const int w = 64, h = 64;
    float *plain = render_renderer(&fx, "raytracer", cam, w, h, true, 1, RENDER_TILE_PX);
    float *term = render_renderer(&fx, "raytracer-ao", cam, w, h, true, 2, RENDER_TILE_PX);
    cr_expect(memcmp(plain, term, sizeof(float) * (size_t)w * h * 3) == 0,
              "the cap or the sphere was darkened by what the plane removed");
    free(term);
    fixture_close(&fx);
    free(plain);
}

/* Every surface at opacity 0.5 over a floor with a box on it, a plane cutting
 * the box: the term scales the first surface's ambient light by its weight in
 * the blend (0.5) and the unoccluded fraction the ao renderer finds at the
 * same surface (white surfaces: its pixel is that fraction), so
 *   raytracer-ao = raytracer - 0.5 x ambient x (1 - A)
 * wherever the first surface is not a cap (the ao renderer draws no caps);
 * and the image does not depend on threads or tiles. */
Test(transparency, ao_term_weights_the_first_surface_by_its_opacity)
{
    const float ambient = 0.4f;
    scene *s = bare_scene(v3(0.1f, 0.2f, 0.3f), v3(ambient, ambient, ambient));
    uint32_t white = lambert(s, v3(1.f, 1.f, 1.f), 1.f);
    add_pane(s, -3.f, -3.f, 3.f, 3.f, -1.2f, white);
    add_grid_cube(s, 2, -1, white);
    light l = light_default_directional();
    cr_assert(scene_add_light(s, &l) >= 0);
    fixture fx;
    fixture_open(&fx, s);
    fx.set.ao_distance = 1.f;
    fx.set.ao_exponent = 1.f; /* the ao picture's value is then A itself, the fraction the term uses */
    camera_desc cam = {v3(0.5f, -4.f, 3.f), v3(0.f, 0.f, -0.5f), v3(0.f, 0.f, 1.f), 55.f};
    const int w = 72, h = 56;
    float *occl = render_renderer(&fx, "ao", cam, w, h, true, 1, RENDER_TILE_PX);
    frame_state_set_global_opacity(&fx.st, 0.5f);
    float *plain = render_renderer(&fx, "raytracer", cam, w, h, true, 1, RENDER_TILE_PX);
    float *term = render_renderer(&fx, "raytracer-ao", cam, w, h, true, 1, RENDER_TILE_PX);
    int darkened = 0;
    for (int p = 0; p < w * h; p++) {
        const float *o = occl + 3 * p;
        for (int c = 0; c < 3; c++) {
            float want = o[0] == 0.1f && o[1] == 0.2f && o[2] == 0.3f ? plain[3 * p + c] /* a miss */
                                                                       : plain[3 * p + c] - 0.5f * ambient * (1.f - o[c]);
            cr_assert(fabsf(term[3 * p + c] - want) <= 1e-5f, "pixel %d channel %d: %g, expected %g", p, c,
                      term[3 * p + c], want);
        }
        darkened += o[0] < 1.f && !(o[0] == 0.1f && o[1] == 0.2f);
    }
    cr_assert(darkened > w * h / 20, "only %d pixels occluded", darkened);
    set_plane(&fx.st, 0, v3(0.f, 0.f, 0.f), v3(0.3f, -1.f, 0.2f));
    float *ref = render_renderer(&fx, "raytracer-ao", cam, w, h, true, 1, RENDER_TILE_PX);
    const int runs[][2] = {{2, RENDER_TILE_PX}, {3, 5}, {2, 1000}};
    for (size_t r = 0; r < sizeof runs / sizeof runs[0]; r++) {
        float *im = render_renderer(&fx, "raytracer-ao", cam, w, h, true, runs[r][0], runs[r][1]);
        cr_assert(memcmp(ref, im, sizeof(float) * (size_t)w * h * 3) == 0, "%d threads, tiles of %d: differs",
                  runs[r][0], runs[r][1]);
        free(im);
    }
    free(ref);
    free(occl);
    free(plain);
    free(term);
    fixture_close(&fx);
}
