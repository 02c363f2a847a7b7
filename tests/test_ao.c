/* test_ao.c - the ambient-occlusion renderer and its sampling (engine/render/ao.h,
 * engine/render/render_ao.h) against analytic results, and its images' independence
 * of threads, tiles and the filter where nothing is occluded.
 *
 * Materials are white (kd = 1), so a pixel's value is the AO term A itself
 * under the linear response (settings.ao_exponent 1), which the tests against
 * closed forms and frame sums set; the default response shows A^2.2
 * (render_ao.h, RESPONSE), which the ao_look tests hold to what it promises. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/render/ao.h"
#include "engine/render/render.h"
#include "engine/render/render_ao.h"
#include "engine/scene/scene.h"
#include "engine/base/srgb.h"

static const double pi_d = 3.14159265358979323846;

static scene *white_scene(int *material_id)
{
    scene *s = scene_create();
    cr_assert(s);
    s->background = v3(0.25f, 0.5f, 0.75f);
    material m = material_default();
    m.model = MATERIAL_LAMBERT;
    m.diffuse = v3(1.f, 1.f, 1.f);
    *material_id = scene_add_material(s, &m);
    cr_assert(*material_id >= 0);
    return s;
}

/* A quad v0 v1 v2 v3 (two triangles), appended to mesh m. */
static void quad_into(mesh *m, vec3 a, vec3 b, vec3 c, vec3 d)
{
    uint32_t base = (uint32_t)m->vertex_count;
    cr_assert(mesh_add_vertex(m, a.x, a.y, a.z) && mesh_add_vertex(m, b.x, b.y, b.z) &&
              mesh_add_vertex(m, c.x, c.y, c.z) && mesh_add_vertex(m, d.x, d.y, d.z));
    cr_assert(mesh_add_triangle(m, base, base + 1, base + 2) && mesh_add_triangle(m, base, base + 2, base + 3));
}

static void add_quad(scene *s, int mat, vec3 a, vec3 b, vec3 c, vec3 d, const char *name)
{
    mesh *m = mesh_create();
    cr_assert(m);
    quad_into(m, a, b, c, d);
    cr_assert(scene_add_mesh(s, m, (uint32_t)mat, name) >= 0);
}

/* The floor y = 0, |x|, |z| <= half. */
static void add_floor(scene *s, int mat, float half)
{
    add_quad(s, mat, v3(-half, 0.f, -half), v3(half, 0.f, -half), v3(half, 0.f, half), v3(-half, 0.f, half), "floor");
}

typedef struct ao_image {
    int w, h;
    float *rgb;
} ao_image;

/* Render with render_ao_image (threads, tile_px) and the given settings and sampler. */
static ao_image render(const scene *s, const accel *a, camera_desc cam, int w, int h, const render_settings *st,
                       pixel_sampler ps, int threads, int tile_px)
{
    ao_image im = {w, h, calloc((size_t)w * (size_t)h * 3, sizeof(float))};
    cr_assert(im.rgb);
    render_view v = {s, a, camera_basis_make(&cam, w, h), false, RENDER_SHADE_PHONG, NULL, st};
    render_ao_image(&v, &ps, threads, tile_px, im.rgb, NULL);
    return im;
}

static accel *build(const scene *s)
{
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "accel_build: %s", err.msg);
    return a;
}

static bool same_pixels(const ao_image *x, const ao_image *y)
{
    return x->w == y->w && x->h == y->h && !memcmp(x->rgb, y->rgb, (size_t)x->w * (size_t)x->h * 3 * sizeof(float));
}

/* ---- sampling ------------------------------------------------------------ */

Test(ao, directions_are_unit_and_above_the_surface)
{
    static ao_direction_sets d;
    for (int k = 1; k <= AO_MAX_INTERLEAVE; k += 3)
        for (int n = 1; n <= AO_MAX_RAYS; n = n * 2 + 1)
            for (uint32_t f = 0; f < 5; f++) {
                ao_direction_sets_fill(&d, k, n, f);
                for (int i = 0; i < k * k * n; i++) {
                    float len = sqrtf(d.x[i] * d.x[i] + d.y[i] * d.y[i] + d.z[i] * d.z[i]);
                    cr_assert(fabsf(len - 1.f) <= 4e-7f, "k %d n %d f %u: |dir %d| = %.9g", k, n, f, i, len);
                    cr_assert(d.z[i] > 0.f, "k %d n %d f %u: dir %d has z %g", k, n, f, i, d.z[i]);
                }
            }
}

/* For N a power of 2 each set is a (0, log2 N, 2)-net: one u in each of the
 * N strips [i / N, (i + 1) / N); the K^2 sets of a frame together one u in
 * each of K^2 N strips (ao.h). */
Test(ao, sets_are_stratified_alone_and_together)
{
    const int k = 4, n = 8;
    for (uint32_t f = 0; f < 6; f++) {
        int all[4 * 4 * 8] = {0};
        for (int c = 0; c < k * k; c++) {
            int own_u[8] = {0}, own_v[8] = {0};
            for (int s = 0; s < n; s++) {
                float u, v;
                ao_set_point(n, f, c, s, &u, &v);
                own_u[(int)(u * (float)n)]++;
                own_v[(int)(v * (float)n)]++;
                all[(int)(u * (float)(k * k * n))]++;
            }
            for (int i = 0; i < n; i++)
                cr_assert(own_u[i] == 1 && own_v[i] == 1, "frame %u set %d: strip %d holds %d u, %d v", f, c, i,
                          own_u[i], own_v[i]);
        }
        for (int i = 0; i < k * k * n; i++)
            cr_assert_eq(all[i], 1, "frame %u: fine strip %d holds %d points", f, i, all[i]);
    }
}

/* Cosine-weighted directions: E[z] = 2/3, E[z^2] = 1/2, E[x] = E[y] = 0, both
 * over all sets and frame after frame for ONE set (what a pixel accumulates
 * without the filter). */
Test(ao, cosine_weighted_means_converge)
{
    static ao_direction_sets d;
    const int k = 4, n = 8;
    double all_z = 0, all_z2 = 0, all_x = 0, one_z = 0, one_x = 0, one_y = 0;
    int all_count = 0, one_count = 0;
    for (uint32_t f = 0; f < 256; f++) {
        ao_direction_sets_fill(&d, k, n, f);
        for (int i = 0; i < k * k * n; i++) {
            all_z += d.z[i], all_z2 += (double)d.z[i] * d.z[i], all_x += d.x[i];
            all_count++;
        }
        const int set = 5;
        for (int s = 0; s < n; s++) {
            vec3 w = ao_direction_local(&d, set, s);
            one_z += w.z, one_x += w.x, one_y += w.y;
            one_count++;
        }
    }
    cr_expect(fabs(all_z / all_count - 2.0 / 3.0) < 1e-3, "mean z %g over all sets", all_z / all_count);
    cr_expect(fabs(all_z2 / all_count - 0.5) < 1e-3, "mean z^2 %g over all sets", all_z2 / all_count);
    cr_expect(fabs(all_x / all_count) < 1e-3, "mean x %g over all sets", all_x / all_count);
    cr_expect(fabs(one_z / one_count - 2.0 / 3.0) < 3e-3, "mean z %g of one set over frames", one_z / one_count);
    cr_expect(fabs(one_x / one_count) < 3e-3 && fabs(one_y / one_count) < 3e-3, "mean x %g, y %g of one set",
              one_x / one_count, one_y / one_count);
}

Test(ao, basis_is_orthonormal_and_right_handed)
{
    const vec3 normals[] = {v3(0.f, 0.f, 1.f), v3(0.f, 0.f, -1.f), v3(1.f, 0.f, 0.f), v3(0.f, 1.f, 0.f),
                            v3(0.f, 1e-7f, -1.f), v3(1e-8f, 0.f, 1.f), v3(0.6f, 0.f, -0.8f)};
    for (size_t i = 0; i < sizeof normals / sizeof normals[0] + 200; i++) {
        vec3 n;
        if (i < sizeof normals / sizeof normals[0])
            n = normals[i];
        else { /* a spiral over the sphere */
            double t = (double)(i - 7) / 200.0, z = 1.0 - 2.0 * t, r = sqrt(1.0 - z * z), phi = 2.399963 * (double)i;
            n = v3_normalize(v3((float)(r * cos(phi)), (float)(r * sin(phi)), (float)z));
        }
        ao_basis f = ao_basis_from_normal(n);
        cr_assert(fabsf(v3_length(f.t) - 1.f) < 1e-5f && fabsf(v3_length(f.b) - 1.f) < 1e-5f);
        cr_assert(fabsf(v3_dot(f.t, f.b)) < 1e-5f && fabsf(v3_dot(f.t, n)) < 1e-5f && fabsf(v3_dot(f.b, n)) < 1e-5f);
        vec3 c = v3_cross(f.t, f.b);
        cr_assert(v3_dot(c, n) > 0.9999f, "normal %g %g %g: t x b is not n", n.x, n.y, n.z);
    }
}

/* ---- analytic scenes ----------------------------------------------------- */

/* Looking down at the floor from height 1 (up +Z: the view is along -Y). */
static camera_desc look_down(float x, float z, float fov_deg)
{
    return (camera_desc){v3(x, 1.f, z), v3(x, 0.f, z), v3(0.f, 0.f, 1.f), fov_deg};
}

Test(ao, open_plane_is_unoccluded_exactly)
{
    int mat;
    scene *s = white_scene(&mat);
    add_floor(s, mat, 1000.f);
    accel *a = build(s);
    render_settings st = render_settings_default();
    camera_desc cam = {v3(0.f, 2.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 60.f};
    for (int filter = 1; filter <= 5; filter += 4) {
        st.ao_filter_px = filter;
        ao_image im = render(s, a, cam, 48, 32, &st, pixel_sampler_single(), 1, RENDER_TILE_PX);
        int hits = 0;
        for (int p = 0; p < im.w * im.h; p++) {
            const float *c = im.rgb + 3 * p;
            bool background = c[0] == 0.25f && c[1] == 0.5f && c[2] == 0.75f;
            cr_assert(background || (c[0] == 1.f && c[1] == 1.f && c[2] == 1.f), "filter %d pixel %d: %g %g %g",
                      filter, p, c[0], c[1], c[2]);
            hits += !background;
        }
        cr_assert(hits > im.w * im.h / 3 && hits < im.w * im.h, "hits %d: the view should show floor and sky", hits);
        free(im.rgb);
    }
    accel_destroy(a);
    scene_destroy(s);
}

Test(ao, bottom_of_a_closed_box_is_fully_occluded)
{
    int mat;
    scene *s = white_scene(&mat);
    mesh *m = mesh_create();
    cr_assert(m);
    /* the unit cube [-0.5, 0.5]^3, six faces */
    const float h = 0.5f;
    quad_into(m, v3(-h, -h, -h), v3(h, -h, -h), v3(h, -h, h), v3(-h, -h, h));
    quad_into(m, v3(-h, h, -h), v3(-h, h, h), v3(h, h, h), v3(h, h, -h));
    quad_into(m, v3(-h, -h, -h), v3(-h, h, -h), v3(h, h, -h), v3(h, -h, -h));
    quad_into(m, v3(-h, -h, h), v3(h, -h, h), v3(h, h, h), v3(-h, h, h));
    quad_into(m, v3(-h, -h, -h), v3(-h, -h, h), v3(-h, h, h), v3(-h, h, -h));
    quad_into(m, v3(h, -h, -h), v3(h, h, -h), v3(h, h, h), v3(h, -h, h));
    cr_assert(scene_add_mesh(s, m, (uint32_t)mat, "box") >= 0);
    accel *a = build(s);
    render_settings st = render_settings_default();
    st.ao_distance = 100.f; /* >> the box */
    camera_desc cam = {v3(0.f, 0.3f, 0.f), v3(0.f, -0.5f, 0.f), v3(0.f, 0.f, 1.f), 60.f};
    ao_image im = render(s, a, cam, 32, 32, &st, pixel_sampler_single(), 1, RENDER_TILE_PX);
    for (int p = 0; p < im.w * im.h * 3; p++)
        cr_assert(im.rgb[p] == 0.f, "pixel %d channel %d: %g, expected 0 (fully enclosed)", p / 3, p % 3, im.rgb[p]);
    free(im.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

/* A point on the floor at distance d from an upright wall (the half-plane
 * x = d, y >= 0, wider and taller than the rays are long), AO rays of length
 * L. A cosine-distributed direction's projection onto the floor is uniform
 * on the unit disk (Malley), and the ray reaches the wall exactly when that
 * projection's x is >= a = d / L (the wall rises forever above y = 0). So the
 * occluded fraction is the disk segment x >= a over the disk's area:
 *   occluded = (acos(a) - a sqrt(1 - a^2)) / pi,   unoccluded = 1 - occluded
 * (a = 0: 1/2; a >= 1: 0). */
static double wall_unoccluded(double a)
{
    if (a >= 1.0)
        return 1.0;
    return 1.0 - (acos(a) - a * sqrt(1.0 - a * a)) / pi_d;
}

/* Render with renderer `name` through render_image_tiles, shadows on. */
static ao_image render_with(const char *name, const scene *s, const accel *a, camera_desc cam, int w, int h,
                            const render_settings *st, pixel_sampler ps, int threads, int tile_px)
{
    const renderer *r = renderer_by_name(name);
    cr_assert(r, "no renderer %s", name);
    ao_image im = {w, h, calloc((size_t)w * (size_t)h * 3, sizeof(float))};
    cr_assert(im.rgb);
    render_view v = {s, a, camera_basis_make(&cam, w, h), true, r->shading, NULL, st};
    render_image_tiles(r, &v, &ps, threads, tile_px, im.rgb, NULL);
    return im;
}

/* The floor of add_floor(big) and an upright wall x = d (y >= 0) beside the
 * point (0, 0, 0). */
static void add_wall(scene *s, int mat, float d, float big)
{
    add_floor(s, mat, big);
    add_quad(s, mat, v3(d, 0.f, -big), v3(d, big, -big), v3(d, big, big), v3(d, 0.f, big), "wall");
}

/* Renderer `name`'s value of the one pixel over the point (0, 0, 0), AO rays
 * of `length`, 64 rays x 8 x 8 stratum frames (4096 directions, one set, no
 * filter): the mean over the frames. The pixel is grey (asserted). */
static double mean_over_the_point(const char *name, const scene *s, const accel *a, float length)
{
    render_settings st = render_settings_default();
    st.ao_rays = 64;
    st.ao_interleave = 1;
    st.ao_filter_px = 1;
    st.ao_distance = length;
    st.ao_exponent = 1.f; /* the frames' mean is then the mean of A (of A^e it would not be A^e) */
    const int k = 8;
    double sum = 0.0;
    for (int f = 0; f < k * k; f++) {
        ao_image im = render_with(name, s, a, look_down(0.f, 0.f, 0.01f), 1, 1, &st, pixel_sampler_stratum(k, 0, f), 1,
                                  16);
        cr_assert(im.rgb[0] == im.rgb[1] && im.rgb[1] == im.rgb[2], "%s: a grey pixel", name);
        sum += im.rgb[0];
        free(im.rgb);
    }
    return sum / (k * k);
}

Test(ao, floor_next_to_a_wall_matches_the_closed_form)
{
    const float d = 0.25f;
    int mat;
    scene *s = white_scene(&mat);
    add_wall(s, mat, d, 1000.f);
    accel *a = build(s);
    const float lengths[] = {0.5f, 0.3f, 250.f}; /* a = 0.5, 0.833, 0.001 */
    for (size_t li = 0; li < sizeof lengths / sizeof lengths[0]; li++) {
        double got = mean_over_the_point("ao", s, a, lengths[li]), want = wall_unoccluded((double)d / lengths[li]);
        /* 4096 quasi-random points of a (0, 2)-sequence against an indicator with a straight
         * edge: error ~ N^-3/4 ~ 2e-3; 0.01 leaves room */
        cr_expect(fabs(got - want) < 0.01, "length %g: unoccluded %.4f, closed form %.4f", lengths[li], got, want);
    }
    accel_destroy(a);
    scene_destroy(s);
}

/* ---- images -------------------------------------------------------------- */

/* Floor, wall and spheres: something occluded everywhere. */
static scene *cluttered_scene(void)
{
    int mat;
    scene *s = white_scene(&mat);
    add_floor(s, mat, 4.f);
    add_quad(s, mat, v3(1.f, 0.f, -4.f), v3(1.f, 2.f, -4.f), v3(1.f, 2.f, 4.f), v3(1.f, 0.f, 4.f), "wall");
    cr_assert(scene_add_sphere(s, v3(0.f, 0.4f, 0.f), 0.4f, (uint32_t)mat) >= 0);
    cr_assert(scene_add_sphere(s, v3(-0.6f, 0.2f, 0.5f), 0.2f, (uint32_t)mat) >= 0);
    return s;
}

Test(ao, images_do_not_depend_on_threads_or_tiles)
{
    scene *s = cluttered_scene();
    accel *a = build(s);
    camera_desc cam = {v3(-2.f, 1.5f, 3.f), v3(0.f, 0.3f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    render_settings st = render_settings_default();
    st.ao_distance = 1.f;
    const pixel_sampler samplers[] = {pixel_sampler_single(), pixel_sampler_jittered(2, 7),
                                      pixel_sampler_stratum(2, 7, 3)};
    for (size_t si = 0; si < sizeof samplers / sizeof samplers[0]; si++) {
        ao_image ref = render(s, a, cam, 75, 53, &st, samplers[si], 1, RENDER_TILE_PX);
        const int tiles[][2] = {{2, RENDER_TILE_PX}, {2, 7}, {1, 5}, {2, 1000}, {1, 33}};
        for (size_t t = 0; t < sizeof tiles / sizeof tiles[0]; t++) {
            ao_image im = render(s, a, cam, 75, 53, &st, samplers[si], tiles[t][0], tiles[t][1]);
            cr_assert(same_pixels(&ref, &im), "sampler %zu, %d threads, tiles of %d: the image differs", si,
                      tiles[t][0], tiles[t][1]);
            free(im.rgb);
        }
        free(ref.rgb);
    }
    /* the renderer table's entry is this renderer */
    const renderer *r = renderer_by_name("ao");
    cr_assert(r && r->render_tile == render_ao_tile);
    accel_destroy(a);
    scene_destroy(s);
}

/* jittered:k is the mean of its k^2 stratum frames summed in stratum order,
 * bit for bit (what the governor's accumulation gives). */
Test(ao, jittered_equals_the_accumulated_stratum_frames)
{
    scene *s = cluttered_scene();
    accel *a = build(s);
    camera_desc cam = {v3(-2.f, 1.5f, 3.f), v3(0.f, 0.3f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    render_settings st = render_settings_default();
    st.ao_distance = 1.f;
    const int k = 2, w = 40, h = 30;
    ao_image jit = render(s, a, cam, w, h, &st, pixel_sampler_jittered(k, 3), 2, RENDER_TILE_PX);
    float *sum = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(sum);
    for (int f = 0; f < k * k; f++) {
        ao_image im = render(s, a, cam, w, h, &st, pixel_sampler_stratum(k, 3, f), 1, RENDER_TILE_PX);
        for (int p = 0; p < w * h * 3; p++)
            sum[p] = sum[p] + im.rgb[p];
        free(im.rgb);
    }
    for (int p = 0; p < w * h * 3; p++)
        cr_assert(sum[p] / (float)(k * k) == jit.rgb[p], "value %d: strata %g, jittered %g", p,
                  sum[p] / (float)(k * k), jit.rgb[p]);
    free(sum);
    free(jit.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

Test(ao, filter_changes_nothing_where_nothing_is_occluded)
{
    int mat;
    scene *s = white_scene(&mat);
    add_floor(s, mat, 50.f);
    accel *a = build(s);
    render_settings st = render_settings_default();
    camera_desc cam = {v3(0.f, 1.f, 3.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 70.f};
    st.ao_filter_px = 1;
    ao_image off = render(s, a, cam, 64, 48, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
    for (int filter = 3; filter <= AO_MAX_FILTER_PX; filter += 2) {
        st.ao_filter_px = filter;
        ao_image on = render(s, a, cam, 64, 48, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
        cr_assert(same_pixels(&off, &on), "filter %d changed an unoccluded image", filter);
        free(on.rgb);
    }
    free(off.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

/* A plate at distance 1 in front of the eye and a far wall at distance 10,
 * both facing the eye; a "ceiling" plane 0.5 behind the eye, parallel to
 * them, occludes the plate (at 1.5 < the ray length 2: unoccluded fraction
 * 1 - (1 - 0.75^2) = 0.5625, P(cos >= c) = 1 - c^2 for cosine weighting)
 * but not the wall (11.5 away): the wall is exactly 1 everywhere. A filter
 * that let plate pixels into a wall pixel's mean would darken the wall along
 * the plate's edge; one that let wall pixels into the plate would brighten
 * the plate's rim. As separate parts (the part test) and as one mesh (the
 * depth test alone: the normals agree). */
static void plate_and_wall(bool one_mesh)
{
    int mat;
    scene *s = white_scene(&mat);
    mesh *plate = mesh_create(), *wall = mesh_create(), *ceiling = mesh_create();
    cr_assert(plate && wall && ceiling);
    /* the eye at the origin looking along -Z */
    quad_into(plate, v3(-0.2f, -0.2f, -1.f), v3(0.2f, -0.2f, -1.f), v3(0.2f, 0.2f, -1.f), v3(-0.2f, 0.2f, -1.f));
    mesh *far = one_mesh ? plate : wall;
    quad_into(far, v3(-50.f, -50.f, -10.f), v3(50.f, -50.f, -10.f), v3(50.f, 50.f, -10.f), v3(-50.f, 50.f, -10.f));
    quad_into(ceiling, v3(-50.f, -50.f, 0.5f), v3(50.f, -50.f, 0.5f), v3(50.f, 50.f, 0.5f), v3(-50.f, 50.f, 0.5f));
    cr_assert(scene_add_mesh(s, plate, (uint32_t)mat, "plate") >= 0);
    if (!one_mesh)
        cr_assert(scene_add_mesh(s, wall, (uint32_t)mat, "wall") >= 0);
    else
        mesh_destroy(wall);
    cr_assert(scene_add_mesh(s, ceiling, (uint32_t)mat, "ceiling") >= 0);
    accel *a = build(s);
    render_settings st = render_settings_default();
    st.ao_distance = 2.f;
    st.ao_filter_px = AO_MAX_FILTER_PX;
    st.ao_exponent = 1.f; /* pixel = A, as the closed form gives it */
    camera_desc cam = {v3(0.f, 0.f, 0.f), v3(0.f, 0.f, -1.f), v3(0.f, 1.f, 0.f), 40.f};
    const int w = 96, h = 96;
    ao_image im = render(s, a, cam, w, h, &st, pixel_sampler_single(), 1, RENDER_TILE_PX);
    camera_basis b = camera_basis_make(&cam, w, h);
    int plate_pixels = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            /* which surface the pixel centre sees: the plate is |x|, |y| <= 0.2 at z = -1 */
            vec3 dir = camera_pixel_direction(&b, x, y);
            float px = dir.x / -dir.z, py = dir.y / -dir.z;
            float value = im.rgb[3 * (y * w + x)];
            if (fabsf(px) < 0.2f && fabsf(py) < 0.2f) {
                plate_pixels++;
                cr_assert(value > 0.45f && value < 0.68f, "%s: plate pixel (%d, %d) = %g, expected ~0.5625",
                          one_mesh ? "one mesh" : "two parts", x, y, value);
            } else if (fabsf(px) > 0.2f || fabsf(py) > 0.2f) {
                cr_assert(value == 1.f, "%s: wall pixel (%d, %d) = %g, expected exactly 1",
                          one_mesh ? "one mesh" : "two parts", x, y, value);
            }
        }
    cr_assert(plate_pixels > 100, "the plate covers %d pixels", plate_pixels);
    free(im.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

Test(ao, filter_does_not_bleed_across_parts) { plate_and_wall(false); }
Test(ao, filter_does_not_bleed_across_depth_edges) { plate_and_wall(true); }

/* 0.2 x the diagonal since issue 33 (0.1 before): render_ao.h, DEFAULTS. */
Test(ao, default_distance_is_a_fifth_of_the_scene_diagonal)
{
    int mat;
    scene *s = white_scene(&mat);
    add_quad(s, mat, v3(0.f, 0.f, 0.f), v3(3.f, 0.f, 0.f), v3(3.f, 4.f, 0.f), v3(0.f, 4.f, 0.f), "quad");
    accel *a = build(s);
    render_settings st = render_settings_default();
    camera_desc cam = {v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    render_view v = {s, a, camera_basis_make(&cam, 4, 4), false, RENDER_SHADE_PHONG, NULL, &st};
    cr_expect_float_eq(render_ao_distance(&v), 1.f, 1e-6f);
    st.ao_distance = 2.5f;
    cr_expect_eq(render_ao_distance(&v), 2.5f);
    accel_destroy(a);
    scene_destroy(s);
}

/* settings.ao_frames F: the pixel-centre picture averaging F AO frames is
 * the mean of the F single-frame pictures (frames base .. base + F - 1, each
 * rendered alone with ao_frame_base), summed in frame order: bit for bit, as
 * render_ao.h (FRAMES) promises; with the filter on. */
Test(ao, frames_average_the_single_frame_images)
{
    scene *s = cluttered_scene();
    accel *a = build(s);
    camera_desc cam = {v3(-2.f, 1.5f, 3.f), v3(0.f, 0.3f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    render_settings st = render_settings_default();
    st.ao_distance = 1.f;
    const int frames = 4, w = 40, h = 30;
    const uint32_t base = 5;
    st.ao_frames = frames;
    st.ao_frame_base = base;
    ao_image avg = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
    float *sum = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(sum);
    st.ao_frames = 1;
    for (int f = 0; f < frames; f++) {
        st.ao_frame_base = base + (uint32_t)f;
        ao_image im = render(s, a, cam, w, h, &st, pixel_sampler_single(), 1, RENDER_TILE_PX);
        for (int p = 0; p < w * h * 3; p++)
            sum[p] = sum[p] + im.rgb[p];
        free(im.rgb);
    }
    for (int p = 0; p < w * h * 3; p++)
        cr_assert(sum[p] / (float)frames == avg.rgb[p], "value %d: frames %g, averaged %g", p,
                  sum[p] / (float)frames, avg.rgb[p]);
    free(sum);
    free(avg.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

static double rmse(const ao_image *x, const ao_image *y)
{
    double e = 0.;
    for (int p = 0; p < x->w * x->h * 3; p++)
        e += ((double)x->rgb[p] - y->rgb[p]) * ((double)x->rgb[p] - y->rgb[p]);
    return sqrt(e / (x->w * x->h * 3));
}

/* F frames of N rays walk one sequence (ao.h): with one direction set
 * (interleave 1) and the filter off they are the N F-ray picture to float
 * rounding, and the error against 64 rays x 16 frames falls as F grows. */
Test(ao, frames_converge_to_the_many_ray_picture)
{
    scene *s = cluttered_scene();
    accel *a = build(s);
    camera_desc cam = {v3(-2.f, 1.5f, 3.f), v3(0.f, 0.3f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    render_settings st = render_settings_default();
    const int w = 40, h = 30;
    st.ao_distance = 1.f;
    st.ao_filter_px = 1;
    st.ao_interleave = 1;
    st.ao_rays = 4;
    st.ao_frames = 8;
    st.ao_exponent = 1.f; /* F frames are the N F-ray picture for the linear response only: the mean of
                             (N-ray A)^e over frames is not (N F-ray A)^e */
    ao_image frames = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
    st.ao_rays = 32;
    st.ao_frames = 1;
    ao_image rays = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
    for (int p = 0; p < w * h * 3; p++)
        cr_assert(fabsf(frames.rgb[p] - rays.rgb[p]) <= 1e-6f, "value %d: 4 rays x 8 frames %g, 32 rays %g", p,
                  frames.rgb[p], rays.rgb[p]);
    free(frames.rgb);
    free(rays.rgb);

    st = render_settings_default();
    st.ao_distance = 1.f;
    st.ao_filter_px = 1;
    st.ao_exponent = 1.f;
    st.ao_rays = 64;
    st.ao_frames = 16;
    ao_image ref = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
    st.ao_rays = 4;
    double last = INFINITY;
    for (int f = 1; f <= 16; f *= 4) {
        st.ao_frames = f;
        ao_image im = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
        double e = rmse(&im, &ref);
        cr_assert(e < 0.8 * last, "4 rays x %d frames: RMSE %g against 1024 rays, not below 0.8 x %g", f, e, last);
        last = e;
        free(im.rgb);
    }
    free(ref.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

/* ---- the raytracer's AO term (renderer raytracer-ao) ---------------------- */

/* White Lambert surfaces under ambient light `ambient` (material ambient 1)
 * and one directional light straight above (+y) of intensity `direct`. */
static scene *lit_scene(int *material_id, float ambient, float direct)
{
    scene *s = white_scene(material_id);
    s->ambient = v3(ambient, ambient, ambient);
    s->materials[*material_id].ambient = 1.f;
    light l = light_default_directional();
    l.direction = v3(0.f, 1.f, 0.f);
    l.color = v3(1.f, 1.f, 1.f);
    l.intensity = direct;
    cr_assert(scene_add_light(s, &l) >= 0);
    return s;
}

/* Where nothing is occluded the term changes nothing: raytracer-ao is the
 * raytracer bit for bit, filter on or off, for every sampler. */
Test(ao_term, unoccluded_is_the_raytracer_bit_for_bit)
{
    int mat;
    scene *s = lit_scene(&mat, 0.3f, 0.6f);
    add_floor(s, mat, 1000.f);
    accel *a = build(s);
    camera_desc cam = {v3(0.f, 2.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 60.f};
    const pixel_sampler samplers[] = {pixel_sampler_single(), pixel_sampler_jittered(2, 5),
                                      pixel_sampler_stratum(2, 5, 1)};
    for (size_t si = 0; si < sizeof samplers / sizeof samplers[0]; si++)
        for (int filter = 1; filter <= 5; filter += 4) {
            render_settings st = render_settings_default();
            st.ao_filter_px = filter;
            ao_image plain = render_with("raytracer", s, a, cam, 48, 32, &st, samplers[si], 1, RENDER_TILE_PX);
            ao_image term = render_with("raytracer-ao", s, a, cam, 48, 32, &st, samplers[si], 2, 7);
            cr_assert(same_pixels(&plain, &term), "sampler %zu filter %d: the term changed an open floor", si, filter);
            free(plain.rgb);
            free(term.rgb);
        }
    accel_destroy(a);
    scene_destroy(s);
}

/* The floor next to a wall (the closed form above): the light straight
 * above reaches the point unshadowed, so its direct light stays whole and
 * only the ambient light is scaled by the unoccluded fraction:
 *   pixel = direct + ambient x unoccluded. */
Test(ao_term, darkens_only_the_ambient_light_by_the_closed_form)
{
    const float d = 0.25f, ambient = 0.3f, direct = 0.6f;
    int mat;
    scene *s = lit_scene(&mat, ambient, direct);
    add_wall(s, mat, d, 1000.f);
    accel *a = build(s);
    const float lengths[] = {0.5f, 0.3f}; /* a = 0.5, 0.833 */
    for (size_t li = 0; li < sizeof lengths / sizeof lengths[0]; li++) {
        double got = mean_over_the_point("raytracer-ao", s, a, lengths[li]);
        double want = direct + ambient * wall_unoccluded((double)d / lengths[li]);
        /* the unoccluded fraction to 0.01 (the ao test above), times the ambient light */
        cr_expect(fabs(got - want) < 0.01 * ambient, "length %g: pixel %.4f, closed form %.4f", lengths[li], got,
                  want);
    }
    accel_destroy(a);
    scene_destroy(s);
}

/* On an opaque scene the term is the ao renderer's picture applied to the
 * ambient light: with white surfaces the ao renderer's pixel is A itself,
 * so raytracer-ao = raytracer - ambient x (1 - A) at every hit, filter on;
 * and the images do not depend on threads, tiles or how strata are summed. */
Test(ao_term, is_the_ao_pictures_fraction_of_the_ambient_light)
{
    int mat;
    scene *s = cluttered_scene();
    s->ambient = v3(0.4f, 0.4f, 0.4f);
    for (uint32_t m = 0; m < s->material_count; m++)
        s->materials[m].ambient = 1.f;
    light l = light_default_directional();
    cr_assert(scene_add_light(s, &l) >= 0);
    (void)mat;
    accel *a = build(s);
    camera_desc cam = {v3(-2.f, 1.5f, 3.f), v3(0.f, 0.3f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    render_settings st = render_settings_default();
    st.ao_distance = 1.f;
    st.ao_exponent = 1.f; /* the ao picture's value is then A itself, the fraction the term uses */
    const int w = 75, h = 53;
    ao_image plain = render_with("raytracer", s, a, cam, w, h, &st, pixel_sampler_single(), 1, RENDER_TILE_PX);
    ao_image occl = render_with("ao", s, a, cam, w, h, &st, pixel_sampler_single(), 1, RENDER_TILE_PX);
    ao_image term = render_with("raytracer-ao", s, a, cam, w, h, &st, pixel_sampler_single(), 1, RENDER_TILE_PX);
    int darkened = 0;
    for (int p = 0; p < w * h; p++) {
        const float *o = occl.rgb + 3 * p;
        if (o[0] == 0.25f && o[1] == 0.5f && o[2] == 0.75f) { /* a miss: the background */
            cr_assert(!memcmp(term.rgb + 3 * p, plain.rgb + 3 * p, 3 * sizeof(float)), "pixel %d: a miss", p);
            continue;
        }
        for (int c = 0; c < 3; c++) {
            float want = plain.rgb[3 * p + c] - 0.4f * (1.f - o[c]);
            cr_assert(fabsf(term.rgb[3 * p + c] - want) <= 1e-5f, "pixel %d channel %d: %g, expected %g", p, c,
                      term.rgb[3 * p + c], want);
        }
        darkened += o[0] < 1.f;
    }
    cr_assert(darkened > w * h / 10, "only %d pixels occluded: the scene should show creases", darkened);
    const pixel_sampler samplers[] = {pixel_sampler_single(), pixel_sampler_jittered(2, 7)};
    for (size_t si = 0; si < 2; si++) {
        ao_image ref = render_with("raytracer-ao", s, a, cam, w, h, &st, samplers[si], 1, RENDER_TILE_PX);
        const int tiles[][2] = {{2, RENDER_TILE_PX}, {2, 5}, {1, 1000}};
        for (size_t t = 0; t < sizeof tiles / sizeof tiles[0]; t++) {
            ao_image im = render_with("raytracer-ao", s, a, cam, w, h, &st, samplers[si], tiles[t][0], tiles[t][1]);
            cr_assert(same_pixels(&ref, &im), "sampler %zu, %d threads, tiles of %d: the image differs", si,
                      tiles[t][0], tiles[t][1]);
            free(im.rgb);
        }
        if (si == 1) { /* jittered:2 = its 4 stratum frames summed in order */
            for (int p = 0; p < w * h * 3; p++)
                plain.rgb[p] = 0.f;
            for (int f = 0; f < 4; f++) {
                ao_image im = render_with("raytracer-ao", s, a, cam, w, h, &st, pixel_sampler_stratum(2, 7, f), 2,
                                          RENDER_TILE_PX);
                for (int p = 0; p < w * h * 3; p++)
                    plain.rgb[p] = plain.rgb[p] + im.rgb[p];
                free(im.rgb);
            }
            for (int p = 0; p < w * h * 3; p++)
                cr_assert(plain.rgb[p] / 4.f == ref.rgb[p], "value %d: strata %g, jittered %g", p,
                          plain.rgb[p] / 4.f, ref.rgb[p]);
        }
        free(ref.rgb);
    }
    const renderer *r = renderer_by_name("raytracer-ao");
    cr_assert(r && r->render_tile == render_raytracer_ao_tile && r->shading == RENDER_SHADE_PHONG);
    free(plain.rgb);
    free(occl.rgb);
    free(term.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

/* ---- the filter over accumulated frames ---------------------------------- */

Test(ao, filter_shrinks_one_ring_each_time_the_frames_quadruple)
{
    const struct {
        int edge;
        uint32_t frame;
        int want;
    } cases[] = {{5, 0, 5},  {5, 1, 3},  {5, 3, 3},  {5, 4, 1},  {5, 1000, 1}, {9, 0, 9},  {9, 4, 5},
                 {9, 15, 5}, {9, 16, 3}, {9, 63, 3}, {9, 64, 1}, {1, 0, 1},    {1, 7, 1},  {7, UINT32_MAX, 1}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        cr_expect_eq(render_ao_filter_edge(cases[i].edge, cases[i].frame), cases[i].want, "edge %d frame %u: %d",
                     cases[i].edge, cases[i].frame, render_ao_filter_edge(cases[i].edge, cases[i].frame));
}

/* A still picture accumulating frames with the filter on converges to the
 * unfiltered many-ray reference, not to the filtered picture: its error
 * falls frame after frame and ends near the unfiltered accumulation's (a
 * filter kept on every frame stays at its own error, the blur of the AO
 * term across each box). */
Test(ao, accumulated_frames_with_the_filter_converge_to_the_unfiltered_reference)
{
    scene *s = cluttered_scene();
    accel *a = build(s);
    camera_desc cam = {v3(-2.f, 1.5f, 3.f), v3(0.f, 0.3f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    const int w = 64, h = 48;
    render_settings st = render_settings_default();
    st.ao_distance = 1.f;
    st.ao_filter_px = 1;
    st.ao_rays = 64;
    st.ao_frames = 64;
    st.ao_frame_base = 4096; /* the reference: other directions than the frames measured */
    ao_image ref = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
    st.ao_rays = 4;
    st.ao_frame_base = 0;
    double last = INFINITY, filtered = 0.0, unfiltered = 0.0;
    for (int f = 1; f <= 64; f *= 4) {
        st.ao_frames = f;
        st.ao_filter_px = 5;
        ao_image im = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
        filtered = rmse(&im, &ref);
        cr_expect(filtered < 0.8 * last, "filter 5, %d frames: RMSE %g, not below 0.8 x %g", f, filtered, last);
        last = filtered;
        free(im.rgb);
        st.ao_filter_px = 1;
        im = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
        unfiltered = rmse(&im, &ref);
        free(im.rgb);
        if (f == 1)
            cr_expect(filtered < 0.8 * unfiltered, "one frame: the filter should lower the error (%g, unfiltered %g)",
                      filtered, unfiltered);
    }
    cr_expect(filtered < 1.25 * unfiltered, "64 frames: filtered RMSE %g, unfiltered %g", filtered, unfiltered);
    free(ref.rgb);
    accel_destroy(a);
    scene_destroy(s);
}

/* ---- the default look: what the eye reads (render_ao.h, DEFAULTS) -------- */

/* A ball of radius R resting on the floor y = 0 at the origin; the floor
 * |x|, |z| <= 3. Default settings: the AO rays are 0.2 x the box's diagonal
 * sqrt(6^2 + 1^2 + 6^2) = 1.709 long. */
#define BALL_R 0.5f
static scene *ball_on_floor(void)
{
    int mat;
    scene *s = white_scene(&mat);
    add_floor(s, mat, 3.f);
    cr_assert(scene_add_sphere(s, v3(0.f, BALL_R, 0.f), BALL_R, (uint32_t)mat) >= 0);
    return s;
}

/* A linear value as the display shows it: its sRGB code, 0..1. */
static double display_code(float linear)
{
    return srgb_curve_encode(linear < 0.f ? 0.0 : linear > 1.f ? 1.0 : (double)linear);
}

/* The default still picture (16 accumulated AO frames, ao_frames) of the
 * one pixel looking straight down at the floor point (x, 0, z), as the
 * display shows it. */
static double shown_at(const scene *s, const accel *a, float x, float z)
{
    render_settings st = render_settings_default();
    st.ao_frames = 16;
    ao_image im = render(s, a, look_down(x, z, 0.01f), 1, 1, &st, pixel_sampler_single(), 1, 16);
    double code = display_code(im.rgb[0]);
    free(im.rgb);
    return code;
}

/* A floor point at distance rho from the contact point sees the ball (centre
 * at height R, distance D = sqrt(rho^2 + R^2), wholly above the floor's
 * plane) with the form factor of a differential area to a sphere,
 * (R / D)^2 cos(theta) with cos(theta) = R / D: the cosine-weighted occluded
 * fraction is (R / D)^3 when the rays reach the ball's far side (D + R <=
 * the ray length). At rho = 1.1 R: A = 1 - 0.304 = 0.696. The default
 * response must show that crease at most at A x the open floor's code (+
 * 0.05 for the estimate): occlusion must read on the screen in proportion.
 * The linear response (the old default) showed it at 0.86 x: a flat picture. */
Test(ao_look, a_crease_shows_as_dark_as_it_is_occluded)
{
    scene *s = ball_on_floor();
    accel *a = build(s);
    const double rho = 1.1 * BALL_R, d = sqrt(rho * rho + (double)BALL_R * BALL_R);
    const double open_fraction = 1.0 - pow((double)BALL_R / d, 3.0);
    cr_assert(d + BALL_R < 1.7, "the rays reach the ball's far side");
    const double open_floor = shown_at(s, a, 2.5f, 2.5f); /* 3.0 from the ball: out of the rays' reach */
    const double crease = shown_at(s, a, (float)rho, 0.f);
    cr_expect(fabs(open_floor - 1.0) < 1e-9, "open floor shown at %.17g, expected white", open_floor);
    cr_expect(crease <= (open_fraction + 0.05) * open_floor,
              "the crease (unoccluded %.3f) is shown at %.3f of the open floor's code, expected <= %.3f", open_fraction,
              crease / open_floor, open_fraction + 0.05);
    cr_expect(crease >= (open_fraction - 0.1) * open_floor, "the crease is shown at %.3f: darker than it is occluded",
              crease / open_floor);
    accel_destroy(a);
    scene_destroy(s);
}

static int compare_doubles(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* The default image (default settings, one frame, pixel centres) of the ball
 * on the floor seen from above at an angle: its surface pixels' display codes
 * span at least a third of the range between their 5th and 95th percentiles.
 * The view holds open floor (A = 1, white) and the band around the contact
 * where the floor under the ball's overhang and the ball's underside face
 * each other (A well below 0.5 there); a response that shows occlusion in
 * proportion spreads them over the range, the linear response squeezed them
 * into its top. */
Test(ao_look, the_default_image_spans_the_range)
{
    scene *s = ball_on_floor();
    accel *a = build(s);
    render_settings st = render_settings_default();
    camera_desc cam = {v3(0.f, 1.1f, 1.6f), v3(0.f, 0.2f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    const int w = 160, h = 120;
    double spread[2];
    for (int linear = 0; linear < 2; linear++) {
        st.ao_exponent = linear ? 1.f : render_settings_default().ao_exponent;
        ao_image im = render(s, a, cam, w, h, &st, pixel_sampler_single(), 2, RENDER_TILE_PX);
        double *codes = malloc((size_t)w * h * sizeof *codes);
        cr_assert(codes);
        int n = 0;
        for (int p = 0; p < w * h; p++) {
            const float *c = im.rgb + 3 * p;
            if (!(c[0] == 0.25f && c[1] == 0.5f && c[2] == 0.75f)) /* not the background */
                codes[n++] = display_code(c[0]);
        }
        cr_assert(n > w * h / 2, "the floor and ball cover %d of %d pixels", n, w * h);
        qsort(codes, (size_t)n, sizeof *codes, compare_doubles);
        spread[linear] = codes[n * 95 / 100] - codes[n * 5 / 100];
        free(codes);
        free(im.rgb);
    }
    cr_expect(spread[0] >= 1.0 / 3.0, "default: 5th-95th percentile codes span %.3f, expected >= 1/3", spread[0]);
    cr_expect(spread[1] < spread[0], "the linear response spans %.3f, the default %.3f", spread[1], spread[0]);
    accel_destroy(a);
    scene_destroy(s);
}
