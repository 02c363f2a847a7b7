/* test_overlay.c - the overlay (status line, cursor; engine/render/overlay.h) and
 * hidden geometries (accel_set_hidden, pipeline_queue_hide): where things
 * are drawn, that channels of one plane agree, that clearing restores the
 * plain image bit for bit, that images do not depend on threads, tile size
 * or tile order, the font, the setters' contract; hidden geometries are
 * neither hit nor cast shadows, packets agree with single rays, and frames
 * stay whole while another thread picks and moves the cursor.
 * Only Test(), cr_assert*, cr_expect, cr_expect_eq are used, so the file also
 * compiles against tests/tsan/criterion/criterion.h. */
#include <criterion/criterion.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/scene/accel.h"
#include "engine/render/overlay.h"
#include "engine/accel/packet.h"
#include "engine/frame/pipeline.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"

#define GRAB_MAX 64

/* ---- frames a display was shown, kept by the test (outlives the display) ---- */
typedef struct grabbed {
    int w, h, count;
    float *frames[GRAB_MAX];
} grabbed;

typedef struct grab_display {
    image_display base;
    grabbed *to;
} grab_display;

static bool grab_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)err;
    grabbed *g = ((grab_display *)d)->to;
    cr_assert(g->count < GRAB_MAX, "too many frames");
    size_t bytes = (size_t)img->width_px * (size_t)img->height_px * 3 * sizeof(float);
    float *copy = malloc(bytes);
    cr_assert(copy);
    memcpy(copy, img->rgb, bytes);
    g->w = img->width_px;
    g->h = img->height_px;
    g->frames[g->count++] = copy;
    return true;
}

static void grab_destroy(image_display *d) { free(d); }

static const image_display_ops grab_ops = {.name = "grab", .show = grab_show, .destroy = grab_destroy};

static image_display *grab_create(grabbed *to)
{
    grab_display *d = calloc(1, sizeof *d);
    cr_assert(d);
    d->base.ops = &grab_ops;
    d->to = to;
    return &d->base;
}

static void grabbed_free(grabbed *g)
{
    for (int i = 0; i < g->count; i++)
        free(g->frames[i]);
    memset(g, 0, sizeof *g);
}

/* ---- scenes ---- */
typedef struct fixture {
    scene *scene;
    accel *accel;
    camera_desc camera;
} fixture;

static fixture fixture_from(scene *s, camera_desc cam)
{
    tess_error err = {{0}};
    fixture fx = {s, accel_build(s, 2, &err), cam};
    cr_assert(fx.accel, "accel_build: %s", err.msg);
    return fx;
}

static fixture fixture_default(void)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert(s, "default scene: %s", err.msg);
    camera_desc cam = s->camera;
    if (!s->has_camera) {
        vec3 lo, hi;
        cr_assert(scene_bounds(s, &lo, &hi));
        cam = camera_frame_bounds(lo, hi, CAMERA_DEFAULT_VIEW_DIR, CAMERA_DEFAULT_FOV_DEG, 16, 9);
    }
    return fixture_from(s, cam);
}

static void fixture_free(fixture *fx)
{
    accel_destroy(fx->accel);
    scene_destroy(fx->scene);
}

/* A floor (mesh 0, y = 0), a roof tile (mesh 1, y = 3 over x 2..4, z -1..1)
 * and, with_sphere, a sphere over the floor's centre (the sphere set, id 2);
 * light from nearly straight above, so the sphere shadows the floor. */
static scene *hide_scene(bool with_sphere)
{
    scene *s = scene_create();
    cr_assert(s);
    s->background = v3(0.1f, 0.2f, 0.3f);
    s->ambient = v3(0.2f, 0.2f, 0.2f);
    material m = material_default();
    m.diffuse = v3(0.7f, 0.6f, 0.5f);
    m.ambient = 1.f;
    int mat = scene_add_material(s, &m);
    cr_assert(mat >= 0);
    mesh *floor = mesh_create();
    cr_assert(floor);
    cr_assert(mesh_add_vertex(floor, -10.f, 0.f, -10.f) && mesh_add_vertex(floor, 10.f, 0.f, -10.f) &&
              mesh_add_vertex(floor, 10.f, 0.f, 10.f) && mesh_add_vertex(floor, -10.f, 0.f, 10.f));
    cr_assert(mesh_add_triangle(floor, 0, 2, 1) && mesh_add_triangle(floor, 0, 3, 2));
    cr_assert_eq(scene_add_mesh(s, floor, (uint32_t)mat, "floor"), 0);
    mesh *roof = mesh_create();
    cr_assert(roof);
    cr_assert(mesh_add_vertex(roof, 2.f, 3.f, -1.f) && mesh_add_vertex(roof, 4.f, 3.f, -1.f) &&
              mesh_add_vertex(roof, 4.f, 3.f, 1.f) && mesh_add_vertex(roof, 2.f, 3.f, 1.f));
    cr_assert(mesh_add_triangle(roof, 0, 2, 1) && mesh_add_triangle(roof, 0, 3, 2));
    cr_assert_eq(scene_add_mesh(s, roof, (uint32_t)mat, "roof"), 1);
    if (with_sphere)
        cr_assert(scene_add_sphere(s, v3(0.f, 1.f, 0.f), 0.6f, (uint32_t)mat) >= 0);
    light l = light_default_directional();
    l.direction = v3_normalize(v3(0.15f, 1.f, 0.1f));
    cr_assert(scene_add_light(s, &l) >= 0);
    return s;
}

static camera_desc hide_camera(void) { return (camera_desc){v3(0.f, 7.f, 9.f), v3(0.5f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 50.f}; }

/* ---- pipelines ---- */
typedef struct channel_spec {
    camera_window window;
    float plane_aspect;
    int w, h;
} channel_spec;

static channel_spec full_channel(int w, int h) { return (channel_spec){CAMERA_WINDOW_FULL, (float)w / (float)h, w, h}; }

typedef struct overlay_setup {
    const char *status; /* NULL: none */
    bool cursor;
    float sx, sy;
} overlay_setup;

static const overlay_setup no_overlay = {NULL, false, 0.f, 0.f};

typedef void (*prepare_fn)(pipeline *p, void *ctx);

/* One pipeline over `n` channels with cfg, the overlay set up before the
 * run (setters work while no loop runs), prepare(p, ctx) if given; the
 * frames shown go to out[0..n). */
static void run_channels(const fixture *fx, pipeline_config cfg, const channel_spec *specs, int n,
                         overlay_setup ov, prepare_fn prepare, void *ctx, grabbed *out)
{
    tess_error err = {{0}};
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p, "pipeline_create: %s", err.msg);
    for (int i = 0; i < n; i++) {
        memset(&out[i], 0, sizeof out[i]);
        cr_assert_eq(pipeline_add_channel_window(p, &fx->camera, specs[i].plane_aspect, specs[i].window, specs[i].w,
                                                 specs[i].h, grab_create(&out[i]), &err),
                     i, "add channel: %s", err.msg);
    }
    if (ov.status)
        cr_assert(pipeline_set_status(p, ov.status));
    cr_assert(pipeline_set_cursor(p, ov.cursor, ov.sx, ov.sy));
    if (prepare)
        prepare(p, ctx);
    cr_assert(pipeline_run(p, &err), "pipeline_run: %s", err.msg);
    pipeline_destroy(p);
}

/* Frame 0 of one full-plane channel (caller frees). */
static float *one_frame(const fixture *fx, pipeline_config cfg, int w, int h, overlay_setup ov)
{
    channel_spec spec = full_channel(w, h);
    grabbed g;
    cfg.max_frames = 1;
    run_channels(fx, cfg, &spec, 1, ov, NULL, NULL, &g);
    cr_assert_eq(g.count, 1);
    float *img = g.frames[0];
    g.frames[0] = NULL;
    grabbed_free(&g);
    return img;
}

static pipeline_config config(const fixture *fx, int threads)
{
    pipeline_config cfg = pipeline_config_default(fx->scene, fx->accel);
    cfg.threads = threads;
    cfg.max_frames = 1;
    return cfg;
}

static bool same_pixel(const float *a, const float *b) { return memcmp(a, b, 3 * sizeof(float)) == 0; }

static bool same_image(const float *a, const float *b, int w, int h)
{
    return memcmp(a, b, (size_t)w * (size_t)h * 3 * sizeof(float)) == 0;
}

static bool is_grey(const float *px, float v) { return px[0] == v && px[1] == v && px[2] == v; }

/* Whether text pixel (u, v) (font pixels from the first cell's top-left) is
 * set, by overlay.h's layout. */
static bool expect_text_bit(const char *text, int u, int v)
{
    int cell = u / OVERLAY_CELL_W, col = u % OVERLAY_CELL_W;
    if (u < 0 || v < 0 || cell >= (int)strlen(text) || col >= OVERLAY_GLYPH_W || v >= OVERLAY_GLYPH_H)
        return false;
    const uint8_t *g = overlay_glyph((unsigned char)text[cell]);
    return (g[v] >> (OVERLAY_GLYPH_W - 1 - col)) & 1u;
}

/* ================================================================ overlay */

Test(overlay, every_printable_glyph_has_ink_and_no_two_are_equal)
{
    for (int c = 32; c <= 126; c++) {
        const uint8_t *g = overlay_glyph((unsigned char)c);
        cr_assert(g, "no glyph for %d", c);
        int ink = 0;
        for (int r = 0; r < OVERLAY_GLYPH_H; r++) {
            cr_assert_eq(g[r] & ~0x1fu, 0u, "glyph '%c' row %d uses more than %d columns", c, r, OVERLAY_GLYPH_W);
            ink += g[r] != 0;
        }
        if (c == ' ')
            cr_assert_eq(ink, 0, "space has ink");
        else
            cr_assert(ink > 0, "glyph '%c' is empty", c);
        for (int d = 32; d < c; d++)
            cr_assert(memcmp(g, overlay_glyph((unsigned char)d), OVERLAY_GLYPH_H) != 0, "glyphs '%c' and '%c' are equal",
                      c, d);
    }
    cr_assert_null(overlay_glyph(31));
    cr_assert_null(overlay_glyph(127));
    cr_assert_null(overlay_glyph(200));
}

Test(overlay, scale_follows_the_channel_height)
{
    cr_assert_eq(overlay_scale(1), 1);
    cr_assert_eq(overlay_scale(480), 1);
    cr_assert_eq(overlay_scale(719), 1);
    cr_assert_eq(overlay_scale(720), 2);
    cr_assert_eq(overlay_scale(1080), 3);
    cr_assert_eq(overlay_scale(2160), 6);
}

Test(overlay, status_text_is_stored_cut_and_sanitised)
{
    fixture fx = fixture_default();
    tess_error err = {{0}};
    pipeline_config cfg = config(&fx, 1);
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    cr_assert_eq(pipeline_status(p)[0], '\0', "a new pipeline shows no status line");
    cr_assert(pipeline_set_status(p, "a\tb\x80\x7f~"));
    cr_assert(strcmp(pipeline_status(p), "a?b??~") == 0, "got '%s'", pipeline_status(p));
    char longer[300];
    memset(longer, 'x', sizeof longer - 1);
    longer[sizeof longer - 1] = '\0';
    cr_assert(pipeline_set_status(p, longer));
    cr_assert_eq(strlen(pipeline_status(p)), (size_t)PIPELINE_STATUS_BYTES - 1);
    cr_assert(pipeline_set_status(p, ""));
    cr_assert_eq(pipeline_status(p)[0], '\0');
    cr_assert_not(pipeline_set_status(p, NULL));
    float sx = 0.f, sy = 0.f;
    cr_assert_not(pipeline_cursor(p, &sx, &sy), "a new pipeline shows no cursor");
    cr_assert(pipeline_set_cursor(p, true, 0.25f, -0.5f));
    cr_assert(pipeline_cursor(p, &sx, &sy));
    cr_assert(sx == 0.25f && sy == -0.5f);
    cr_assert_not(pipeline_set_cursor(p, true, NAN, 0.f));
    cr_assert_not(pipeline_set_cursor(p, true, 0.f, INFINITY));
    cr_assert(pipeline_cursor(p, NULL, NULL), "a refused change changed the cursor");
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* The band covers exactly the documented rectangle at the bottom-left, its
 * white pixels are exactly the glyphs' set bits (scale x scale each), and
 * every other pixel is the plain render's, bit for bit. */
static void check_status_band(const fixture *fx, int w, int h, const char *text)
{
    float *plain = one_frame(fx, config(fx, 2), w, h, no_overlay);
    overlay_setup ov = {text, false, 0.f, 0.f};
    float *img = one_frame(fx, config(fx, 2), w, h, ov);
    int scale = overlay_scale(h), len = (int)strlen(text);
    int band_w = (len * OVERLAY_CELL_W - 1 + 2 * OVERLAY_PAD) * scale;
    int band_h = (OVERLAY_CELL_H + 2 * OVERLAY_PAD) * scale;
    cr_assert(band_w < w && band_h < h, "test text too long for the image");
    int text_x = OVERLAY_PAD * scale, text_y = h - band_h + OVERLAY_PAD * scale;
    long white = 0, inked = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = 3 * ((size_t)y * (size_t)w + (size_t)x);
            bool in_band = x < band_w && y >= h - band_h;
            if (!in_band) {
                cr_assert(same_pixel(&img[i], &plain[i]), "%dx%d: pixel (%d, %d) outside the band changed", w, h, x,
                          y);
                continue;
            }
            int dx = x - text_x, dy = y - text_y;
            bool ink = dx >= 0 && dy >= 0 && expect_text_bit(text, dx / scale, dy / scale);
            inked += ink;
            white += is_grey(&img[i], 1.f);
            if (ink)
                cr_assert(is_grey(&img[i], 1.f), "%dx%d: glyph pixel (%d, %d) is not white", w, h, x, y);
            else
                for (int k = 0; k < 3; k++)
                    cr_assert(img[i + k] == plain[i + k] * OVERLAY_BAND_KEEP,
                              "%dx%d: band pixel (%d, %d) is not the darkened render", w, h, x, y);
        }
    cr_assert(inked > 0 && white == inked, "%ld white pixels in the band, %ld glyph pixels", white, inked);
    free(plain);
    free(img);
}

Test(overlay, status_line_is_drawn_in_the_documented_band_only, .timeout = 60)
{
    fixture fx = fixture_default();
    check_status_band(&fx, 160, 100, "Hi, wall! 42 gj_{}");
    check_status_band(&fx, 200, 720, "Ok ~"); /* scale 2 */
    fixture_free(&fx);
}

/* The cursor's tip is the top-left of its box, in the pixel containing its
 * plane point; the box is OVERLAY_CURSOR_W x OVERLAY_CURSOR_H font pixels
 * (its widest row and its last row are drawn); only the box changes. */
static void check_cursor_box(const fixture *fx, int w, int h, float px, float py)
{
    float sx = px / (float)w * 2.f - 1.f, sy = 1.f - py / (float)h * 2.f;
    float *plain = one_frame(fx, config(fx, 2), w, h, no_overlay);
    overlay_setup ov = {NULL, true, sx, sy};
    float *img = one_frame(fx, config(fx, 2), w, h, ov);
    int scale = overlay_scale(h), tx = (int)floorf(px), ty = (int)floorf(py);
    int lo_x = w, lo_y = h, hi_x = -1, hi_y = -1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = 3 * ((size_t)y * w + x);
            if (same_pixel(&img[i], &plain[i]))
                continue;
            cr_assert(is_grey(&img[i], 0.f) || is_grey(&img[i], 1.f), "cursor pixel (%d, %d) is not opaque", x, y);
            lo_x = x < lo_x ? x : lo_x;
            lo_y = y < lo_y ? y : lo_y;
            hi_x = x > hi_x ? x : hi_x;
            hi_y = y > hi_y ? y : hi_y;
        }
    cr_assert(lo_x == tx && lo_y == ty, "%dx%d: the cursor starts at (%d, %d), not (%d, %d)", w, h, lo_x, lo_y, tx, ty);
    cr_assert(hi_x == tx + OVERLAY_CURSOR_W * scale - 1 && hi_y == ty + OVERLAY_CURSOR_H * scale - 1,
              "%dx%d: the cursor ends at (%d, %d)", w, h, hi_x, hi_y);
    cr_assert(is_grey(&img[3 * ((size_t)ty * w + tx)], 0.f), "the tip is not outline");
    cr_assert(is_grey(&img[3 * ((size_t)(ty + 2 * scale) * w + tx + scale)], 1.f), "the arrow is not filled white");
    free(plain);
    free(img);
}

Test(overlay, the_cursor_tip_is_the_pixel_containing_its_point, .timeout = 60)
{
    fixture fx = fixture_default();
    check_cursor_box(&fx, 80, 60, 10.75f, 20.25f);
    check_cursor_box(&fx, 80, 60, 30.25f, 10.75f);
    check_cursor_box(&fx, 120, 720, 40.5f, 300.75f); /* scale 2 */
    fixture_free(&fx);
}

/* A 2x1 wall: each half of the plane on its own channel, against one wide
 * channel of the same pixel pitch. The cursor crosses the boundary; the
 * status line runs over both outputs (and off the plane's right edge). */
Test(overlay, a_cursor_on_the_boundary_of_two_channels_is_drawn_on_both_as_on_one_wide_channel, .timeout = 60)
{
    fixture fx = fixture_default();
    const int w = 64, h = 48;
    const float aspect = (float)(2 * w) / (float)h;
    channel_spec wall[2] = {{{-0.5f, 0.f, 0.5f, 1.f}, aspect, w, h}, {{0.5f, 0.f, 0.5f, 1.f}, aspect, w, h}};
    channel_spec wide = {CAMERA_WINDOW_FULL, aspect, 2 * w, h};
    /* the tip 3 pixels left of the boundary: the 10-pixel-wide arrow crosses it */
    overlay_setup ov = {"status over both outputs", true, -3.f / (float)w, 0.25f};
    grabbed wall_plain[2], wall_ov[2], wide_plain, wide_ov;
    pipeline_config cfg = config(&fx, 2);
    run_channels(&fx, cfg, wall, 2, no_overlay, NULL, NULL, wall_plain);
    run_channels(&fx, cfg, wall, 2, ov, NULL, NULL, wall_ov);
    run_channels(&fx, cfg, &wide, 1, no_overlay, NULL, NULL, &wide_plain);
    run_channels(&fx, cfg, &wide, 1, ov, NULL, NULL, &wide_ov);
    long cursor_px[2] = {0, 0}, changed = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < 2 * w; x++) {
            int side = x < w ? 0 : 1, sx = x - side * w;
            const float *wp = &wide_plain.frames[0][3 * ((size_t)y * 2 * w + x)];
            const float *wo = &wide_ov.frames[0][3 * ((size_t)y * 2 * w + x)];
            const float *sp = &wall_plain[side].frames[0][3 * ((size_t)y * w + sx)];
            const float *so = &wall_ov[side].frames[0][3 * ((size_t)y * w + sx)];
            bool wide_changed = !same_pixel(wp, wo), wall_changed = !same_pixel(sp, so);
            cr_assert_eq(wide_changed, wall_changed, "pixel (%d, %d): drawn on %s only", x, y,
                         wide_changed ? "the wide channel" : "the wall");
            changed += wall_changed;
            if (!wall_changed)
                continue;
            bool opaque = is_grey(wo, 0.f) || is_grey(wo, 1.f);
            if (opaque) { /* glyph or cursor: the same value whatever is under it */
                cr_assert(same_pixel(wo, so), "pixel (%d, %d): wide and wall overlays differ", x, y);
                cursor_px[side] += y < h / 2; /* the band is at the bottom, the cursor near the top */
            } else {
                for (int k = 0; k < 3; k++)
                    cr_assert(so[k] == sp[k] * OVERLAY_BAND_KEEP && wo[k] == wp[k] * OVERLAY_BAND_KEEP,
                              "pixel (%d, %d): neither band nor glyph nor cursor", x, y);
            }
        }
    cr_assert(cursor_px[0] > 0 && cursor_px[1] > 0, "cursor pixels: %ld on the left, %ld on the right", cursor_px[0],
              cursor_px[1]);
    cr_assert(changed > 0);
    /* the cursor's tip: the pixel containing its point, on the left output */
    const float *tip = &wall_ov[0].frames[0][3 * ((size_t)(h * 3 / 8) * w + (w - 3))];
    cr_assert(is_grey(tip, 0.f), "the tip pixel is not the outline");
    for (int i = 0; i < 2; i++) {
        grabbed_free(&wall_plain[i]);
        grabbed_free(&wall_ov[i]);
    }
    grabbed_free(&wide_plain);
    grabbed_free(&wide_ov);
    fixture_free(&fx);
}

static void clear_overlay_now(pipeline *p, void *args)
{
    (void)args;
    cr_assert(pipeline_set_status(p, ""));
    cr_assert(pipeline_set_cursor(p, false, 0.f, 0.f));
}

static void queue_overlay(pipeline *p, void *ctx)
{
    (void)ctx;
    /* the transactions apply at frame 0's barrier; the one-shot clears at frame 2 */
    cr_assert(pipeline_queue_status(p, "going, going, gone"));
    cr_assert(pipeline_queue_cursor(p, true, 0.f, 0.f));
    cr_assert(pipeline_at_frame(p, 2, "clear", clear_overlay_now, NULL, 0));
}

Test(overlay, an_empty_status_and_a_hidden_cursor_give_the_plain_image_back, .timeout = 60)
{
    fixture fx = fixture_default();
    const int w = 80, h = 60;
    pipeline_config cfg = config(&fx, 3);
    float *plain = one_frame(&fx, cfg, w, h, no_overlay);
    cfg.max_frames = 4;
    channel_spec spec = full_channel(w, h);
    grabbed g;
    run_channels(&fx, cfg, &spec, 1, no_overlay, queue_overlay, NULL, &g);
    cr_assert_eq(g.count, 4);
    cr_assert_not(same_image(g.frames[0], plain, w, h), "frame 0 shows no overlay");
    cr_assert(same_image(g.frames[0], g.frames[1], w, h));
    cr_assert(same_image(g.frames[2], plain, w, h), "frame 2 is not the plain image after clearing");
    cr_assert(same_image(g.frames[3], plain, w, h));
    grabbed_free(&g);
    free(plain);
    fixture_free(&fx);
}

Test(overlay, images_with_an_overlay_are_identical_for_threads_tile_sizes_and_orders, .timeout = 120)
{
    fixture fx = fixture_default();
    const int w = 72, h = 40;
    overlay_setup ov = {"determinism: 0123456789", true, 0.1f, 0.2f};
    const int threads[] = {1, 3}, tiles[] = {5, 16};
    const tile_order orders[] = {TILE_ORDER_ROWS, TILE_ORDER_SHUFFLE};
    /* the reference: render_image, then the overlay composited over the whole image at once */
    float *ref = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(ref);
    render_view v = {fx.scene, fx.accel, camera_basis_make(&fx.camera, w, h), true, RENDER_SHADE_PHONG, NULL, NULL};
    render_image(&v, 1, ref, NULL);
    overlay_state st;
    memset(&st, 0, sizeof st);
    st.anchor_sx = st.anchor_sy = -1.f; /* one channel showing the whole plane */
    overlay_set_status(&st, ov.status);
    st.cursor_visible = true;
    st.cursor_sx = ov.sx;
    st.cursor_sy = ov.sy;
    overlay_plan plan;
    cr_assert(overlay_plan_make(&plan, &st, CAMERA_WINDOW_FULL, w, h));
    overlay_draw(&plan, w, 0, 0, w, h, ref);
    for (int ti = 0; ti < 2; ti++)
        for (int zi = 0; zi < 2; zi++)
            for (int oi = 0; oi < 2; oi++) {
                pipeline_config cfg = config(&fx, threads[ti]);
                cfg.tile_px = tiles[zi];
                cfg.order = orders[oi];
                cfg.order_seed = 7;
                float *img = one_frame(&fx, cfg, w, h, ov);
                cr_assert(same_image(img, ref, w, h), "%d threads, %d px tiles, order %s differ", threads[ti],
                          tiles[zi], tile_order_name(orders[oi]));
                free(img);
            }
    free(ref);
    fixture_free(&fx);
}

/* ---- the contract: setters only in the serial section; refused queueing ---- */
typedef struct outside_log {
    pipeline *p;
    bool status, cursor, hide, unhide; /* true: the call was refused */
} outside_log;

static void *set_from_outside(void *arg)
{
    outside_log *o = arg;
    o->status = !pipeline_set_status(o->p, "nope");
    o->cursor = !pipeline_set_cursor(o->p, true, 0.f, 0.f);
    o->hide = !pipeline_set_hidden(o->p, 0, true);
    o->unhide = !pipeline_unhide_all(o->p);
    return NULL;
}

static void spawn_outsider(pipeline *p, void *args)
{
    (void)p;
    outside_log *o = *(outside_log **)args;
    pthread_t th; /* a thread that is not in the serial section, while the pipeline runs */
    cr_assert_eq(pthread_create(&th, NULL, set_from_outside, o), 0);
    pthread_join(th, NULL);
}

Test(overlay, setters_are_refused_outside_the_serial_section_and_queueing_is_checked, .timeout = 60)
{
    fixture fx = fixture_default();
    tess_error err = {{0}};
    pipeline_config cfg = config(&fx, 2);
    cfg.max_frames = 3;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    grabbed g = {0, 0, 0, {0}};
    cr_assert_eq(pipeline_add_channel(p, &fx.camera, 32, 24, grab_create(&g), &err), 0, "%s", err.msg);
    outside_log o = {p, false, false, false, false};
    outside_log *op = &o;
    cr_assert(pipeline_transaction(p, "outsider", spawn_outsider, &op, sizeof op));
    cr_assert_not(pipeline_queue_status(p, NULL));
    cr_assert_not(pipeline_queue_cursor(p, true, NAN, 0.f));
    cr_assert_not(pipeline_queue_cursor(p, true, 0.f, -INFINITY));
    cr_assert(pipeline_queue_status(p, "queued before the run"));
    cr_assert(pipeline_run(p, &err), "%s", err.msg);
    cr_assert(o.status && o.cursor && o.hide && o.unhide,
              "refused outside the serial section: status %d cursor %d hide %d unhide %d", o.status, o.cursor,
              o.hide, o.unhide);
    cr_assert(strcmp(pipeline_status(p), "queued before the run") == 0);
    cr_assert_not(accel_hidden(fx.accel, 0), "the outsider's hide went through");
    /* stopped: transactions are refused */
    cr_assert_not(pipeline_queue_status(p, "late"));
    cr_assert_not(pipeline_queue_cursor(p, true, 0.f, 0.f));
    cr_assert_not(pipeline_queue_hide(p, 0, true));
    cr_assert_not(pipeline_queue_unhide_all(p));
    pipeline_destroy(p);
    grabbed_free(&g);
    fixture_free(&fx);
}

/* ================================================================ hide */

static ray down_ray(float x, float z)
{
    return (ray){v3(x, 5.f, z), v3(0.f, -1.f, 0.f), 0.f, INFINITY};
}

Test(hide, a_hidden_geometry_is_not_hit_and_what_is_behind_it_is)
{
    scene *s = hide_scene(true);
    fixture fx = fixture_from(s, hide_camera());
    accel *a = fx.accel;
    cr_assert_eq(accel_geometry_count(a), 3u);
    hit before, h;
    ray r = down_ray(0.f, 0.f);
    cr_assert(accel_intersect(a, &r, &before));
    cr_assert_eq(before.geom_id, 2u, "the ray should hit the sphere first");
    ray near = r;
    near.t_far = 4.f; /* the sphere (t 3.4) but not the floor (t 5) */
    cr_assert(accel_occluded(a, &near));

    accel_set_hidden(a, 2, true);
    cr_assert(accel_hidden(a, 2));
    cr_assert_not(accel_hidden(a, 0));
    cr_assert(accel_intersect(a, &r, &h));
    cr_assert_eq(h.geom_id, 0u, "with the sphere hidden the floor behind it is hit");
    cr_assert(h.t == 5.f, "t %g", (double)h.t);
    cr_assert_not(accel_occluded(a, &near), "a hidden sphere occludes");

    ray under_roof = down_ray(3.f, 0.f);
    cr_assert(accel_intersect(a, &under_roof, &h));
    cr_assert_eq(h.geom_id, 1u);
    accel_set_hidden(a, 1, true);
    cr_assert(accel_intersect(a, &under_roof, &h));
    cr_assert_eq(h.geom_id, 0u, "a hidden mesh is hit");
    accel_set_hidden(a, 0, true);
    cr_assert_not(accel_intersect(a, &under_roof, &h), "everything is hidden, yet something was hit");
    cr_assert_eq(h.geom_id, RAY_INVALID_ID);
    cr_assert_not(accel_occluded(a, &r));

    /* out of range: ignored */
    accel_set_hidden(a, 3, true);
    cr_assert_not(accel_hidden(a, 3));
    cr_assert_not(accel_hidden(a, UINT32_MAX));

    accel_unhide_all(a);
    for (uint32_t g = 0; g < 3; g++)
        cr_assert_not(accel_hidden(a, g));
    cr_assert(accel_intersect(a, &r, &h));
    cr_assert(memcmp(&h, &before, sizeof h) == 0, "unhide_all did not restore the hit bit for bit");
    fixture_free(&fx);
}

Test(hide, packets_and_single_rays_agree_with_geometries_hidden)
{
    scene *s = hide_scene(true);
    fixture fx = fixture_from(s, hide_camera());
    const int w = 64, h = 48;
    camera_basis cam = camera_basis_make(&fx.camera, w, h);
    const unsigned configs[] = {0u, 1u << 2, 1u << 0, (1u << 1) | (1u << 2), 7u};
    static ray_packet pk; /* 64-byte aligned by its members */
    for (size_t ci = 0; ci < sizeof configs / sizeof configs[0]; ci++) {
        for (uint32_t g = 0; g < 3; g++)
            accel_set_hidden(fx.accel, g, (configs[ci] >> g) & 1u);
        long hits_per_geom[3] = {0, 0, 0}, occluded_rays = 0;
        for (int y0 = 0; y0 < h; y0 += 8)
            for (int x0 = 0; x0 < w; x0 += 8) {
                for (int any = 0; any < 2; any++) {
                    packet_primary(&pk, &cam, x0, y0, 8, 8);
                    ray rays[PACKET_MAX_RAYS];
                    for (uint32_t i = 0; i < pk.count; i++)
                        rays[i] = packet_get_ray(&pk, i);
                    if (any) {
                        uint64_t occ = accel_occluded_packet(fx.accel, packet_whole(&pk));
                        for (uint32_t i = 0; i < pk.count; i++) {
                            bool single = accel_occluded(fx.accel, &rays[i]);
                            cr_assert_eq(single, ((occ >> i) & 1u) != 0, "config %zu: occlusion of ray %u differs",
                                         ci, i);
                            occluded_rays += single;
                        }
                        continue;
                    }
                    accel_intersect_packet(fx.accel, packet_whole(&pk));
                    for (uint32_t i = 0; i < pk.count; i++) {
                        hit one;
                        accel_intersect(fx.accel, &rays[i], &one);
                        hit from_packet = packet_get_hit(&pk, i);
                        cr_assert(memcmp(&one, &from_packet, sizeof one) == 0,
                                  "config %zu, tile (%d, %d), ray %u: packet and single ray differ", ci, x0, y0, i);
                        if (one.geom_id < 3) {
                            cr_assert_not((configs[ci] >> one.geom_id) & 1u, "hidden geometry %u was hit",
                                          one.geom_id);
                            hits_per_geom[one.geom_id]++;
                        }
                    }
                }
            }
        for (uint32_t g = 0; g < 3; g++)
            if (!((configs[ci] >> g) & 1u))
                cr_assert(hits_per_geom[g] > 0, "config %zu: geometry %u is visible but never hit", ci, g);
        if (configs[ci] == 7u)
            cr_assert_eq(occluded_rays, 0);
    }
    accel_unhide_all(fx.accel);
    fixture_free(&fx);
}

static void unhide_now(pipeline *p, void *args)
{
    (void)args;
    cr_assert(pipeline_unhide_all(p));
}

static void hide_sphere_now(pipeline *p, void *args)
{
    (void)args;
    cr_assert(pipeline_set_hidden(p, 2, true));
    cr_assert(pipeline_hidden(p, 2));
}

static void queue_hide_sphere(pipeline *p, void *ctx)
{
    (void)ctx;
    cr_assert(pipeline_queue_hide(p, 2, true));
    cr_assert(pipeline_at_frame(p, 1, "unhide", unhide_now, NULL, 0));
    cr_assert(pipeline_at_frame(p, 2, "hide again", hide_sphere_now, NULL, 0));
}

static float *render_plain(const fixture *fx, int w, int h)
{
    float *rgb = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(rgb);
    render_view v = {fx->scene, fx->accel, camera_basis_make(&fx->camera, w, h), true, RENDER_SHADE_PHONG, NULL, NULL};
    render_image(&v, 2, rgb, NULL);
    return rgb;
}

Test(hide, a_hidden_geometry_casts_no_shadow_and_unhiding_restores_the_image, .timeout = 60)
{
    const int w = 96, h = 64;
    fixture full = fixture_from(hide_scene(true), hide_camera());
    fixture without = fixture_from(hide_scene(false), hide_camera());
    float *with_sphere = render_plain(&full, w, h), *no_sphere = render_plain(&without, w, h);
    /* the test means something: some floor pixel lies in the sphere's shadow */
    camera_basis cam = camera_basis_make(&full.camera, w, h);
    long shadow_px = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = 3 * ((size_t)y * w + x);
            ray r = {cam.eye, camera_pixel_direction(&cam, x, y), 0.f, INFINITY};
            hit hh;
            if (!same_pixel(&with_sphere[i], &no_sphere[i]) && accel_intersect(full.accel, &r, &hh) &&
                hh.geom_id == 0)
                shadow_px++;
        }
    cr_assert(shadow_px > 10, "only %ld floor pixels are shadowed by the sphere", shadow_px);

    pipeline_config cfg = pipeline_config_default(full.scene, full.accel);
    cfg.threads = 2;
    cfg.max_frames = 4;
    cfg.tile_px = 8;
    channel_spec spec = full_channel(w, h);
    grabbed g;
    run_channels(&full, cfg, &spec, 1, no_overlay, queue_hide_sphere, NULL, &g);
    cr_assert_eq(g.count, 4);
    cr_assert(same_image(g.frames[0], no_sphere, w, h), "sphere hidden: not the image of the scene without it");
    cr_assert(same_image(g.frames[1], with_sphere, w, h), "unhide_all did not restore the image bit for bit");
    cr_assert(same_image(g.frames[2], no_sphere, w, h), "hidden again: not the image without the sphere");
    cr_assert(same_image(g.frames[3], no_sphere, w, h));
    cr_assert(accel_hidden(full.accel, 2), "the flag lives in the accel and outlasts the pipeline");
    accel_unhide_all(full.accel);
    float *again = render_plain(&full, w, h);
    cr_assert(same_image(again, with_sphere, w, h));
    grabbed_free(&g);
    free(with_sphere);
    free(no_sphere);
    free(again);
    fixture_free(&full);
    fixture_free(&without);
}

Test(hide, out_of_range_ids_are_refused)
{
    fixture fx = fixture_from(hide_scene(true), hide_camera());
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    cr_assert_eq(pipeline_geometry_count(p), 3u);
    cr_assert_not(pipeline_queue_hide(p, 3, true));
    cr_assert_not(pipeline_queue_hide(p, UINT32_MAX, false));
    cr_assert_not(pipeline_set_hidden(p, 3, true));
    cr_assert(pipeline_queue_hide(p, 2, true));
    cr_assert(pipeline_queue_unhide_all(p));
    pipeline_stats st = pipeline_get_stats(p);
    cr_assert_eq(st.transactions_rejected, 0u, "ids are checked before queueing");
    cr_assert(pipeline_set_hidden(p, 1, true), "not running: the setter works");
    cr_assert(accel_hidden(fx.accel, 1));
    cr_assert(pipeline_unhide_all(p));
    cr_assert_not(accel_hidden(fx.accel, 1));
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- threads: a picker and a cursor sender while hiding toggles each frame ---- */
#define RACE_W 72
#define RACE_H 40
#define RACE_CURSORS 3

static const float race_cursor[RACE_CURSORS][2] = {{-0.5f, 0.5f}, {0.f, 0.f}, {0.4f, -0.3f}};

typedef struct racer {
    pipeline *p;
    const accel *a;
    atomic_bool done;
    atomic_long picks, moves;
    atomic_int bad_picks;
} racer;

/* The racer: picks through accel_pick (the hidden flags and the boxes the
 * serial section refits; accel.h)
 * and cursor moves from its own thread while frames render. Each move waits
 * for a frame to be rendered after it (an event: a starved racer makes the
 * run longer, never the test wrong); after RACE_MOVES moves and two more
 * frames it stops the pipeline. */
#define RACE_MOVES 9
static void *pick_and_move(void *arg)
{
    racer *r = arg;
    struct timespec poll = {0, 50000};
    for (unsigned k = 0; !atomic_load(&r->done); k++) {
        ray down = down_ray(0.f, 0.f);
        hit h;
        bool any = accel_pick(r->a, &down, &h); /* a pick from another thread: the refit lock */
        /* the sphere or, while it is hidden, the floor */
        if (!any || (h.geom_id != 2 && h.geom_id != 0))
            atomic_fetch_add(&r->bad_picks, 1);
        (void)accel_hidden(r->a, 2);
        atomic_fetch_add(&r->picks, 1);
        const float *c = race_cursor[(k + 1) % RACE_CURSORS]; /* the first differs from the start's */
        uint64_t frames_then = pipeline_get_stats(r->p).frames_rendered;
        if (pipeline_queue_cursor(r->p, true, c[0], c[1]) && atomic_fetch_add(&r->moves, 1) + 1 >= RACE_MOVES)
            frames_then++; /* the last: two frames more */
        while (!atomic_load(&r->done) && pipeline_get_stats(r->p).frames_rendered < frames_then + 1)
            nanosleep(&poll, NULL);
        if (atomic_load(&r->moves) >= RACE_MOVES) {
            pipeline_stop(r->p);
            break;
        }
    }
    return NULL;
}

/* Frames of the race checked as they are shown (any number of them): each
 * must equal one of the references for its frame's hidden state (odd frames
 * hide the sphere) at one of the cursor positions. */
typedef struct race_display {
    image_display base;
    float *(*refs)[RACE_CURSORS]; /* [hidden][cursor] */
    int count;
    int seen[RACE_CURSORS];
    int first_whole_miss; /* -1: every frame matched */
} race_display;

static bool race_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)err;
    race_display *rd = (race_display *)d;
    int hidden = (int)(img->frame % 2), match = -1;
    for (int c = 0; c < RACE_CURSORS && match < 0; c++)
        if (img->width_px == RACE_W && img->height_px == RACE_H &&
            same_image(img->rgb, rd->refs[hidden][c], RACE_W, RACE_H))
            match = c;
    if (match >= 0)
        rd->seen[match]++;
    else if (rd->first_whole_miss < 0)
        rd->first_whole_miss = rd->count;
    rd->count++;
    return true;
}

static void race_destroy(image_display *d) { (void)d; /* the test's */ }

static const image_display_ops race_ops = {.name = "race", .show = race_show, .destroy = race_destroy};

static void toggle_sphere(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)ctx;
    cr_assert(pipeline_set_hidden(p, 2, fi->frame % 2 == 1));
}

Test(hide, frames_stay_whole_while_another_thread_picks_and_moves_the_cursor, .timeout = 120)
{
    fixture fx = fixture_from(hide_scene(true), hide_camera());
    /* references: sphere shown / hidden x each cursor position */
    float *refs[2][RACE_CURSORS];
    for (int hidden = 0; hidden < 2; hidden++) {
        accel_set_hidden(fx.accel, 2, hidden);
        for (int c = 0; c < RACE_CURSORS; c++) {
            refs[hidden][c] = render_plain(&fx, RACE_W, RACE_H);
            overlay_state st;
            memset(&st, 0, sizeof st);
            st.anchor_sx = st.anchor_sy = -1.f;
            overlay_set_status(&st, "racing");
            st.cursor_visible = true;
            st.cursor_sx = race_cursor[c][0];
            st.cursor_sy = race_cursor[c][1];
            overlay_plan plan;
            cr_assert(overlay_plan_make(&plan, &st, CAMERA_WINDOW_FULL, RACE_W, RACE_H));
            overlay_draw(&plan, RACE_W, 0, 0, RACE_W, RACE_H, refs[hidden][c]);
        }
    }
    accel_unhide_all(fx.accel);
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 3;
    cfg.tile_px = 8;
    cfg.max_frames = 0; /* until the racer stops it */
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    race_display rd = {.base = {.ops = &race_ops}, .refs = refs, .first_whole_miss = -1};
    cr_assert_eq(pipeline_add_channel(p, &fx.camera, RACE_W, RACE_H, &rd.base, &err), 0, "%s", err.msg);
    cr_assert(pipeline_set_status(p, "racing"));
    cr_assert(pipeline_set_cursor(p, true, race_cursor[0][0], race_cursor[0][1]));
    cr_assert(pipeline_add_serial_animation(p, "toggle sphere", toggle_sphere, NULL));
    racer r;
    r.p = p;
    r.a = fx.accel;
    atomic_init(&r.done, false);
    atomic_init(&r.picks, 0);
    atomic_init(&r.moves, 0);
    atomic_init(&r.bad_picks, 0);
    pthread_t th;
    cr_assert_eq(pthread_create(&th, NULL, pick_and_move, &r), 0);
    cr_assert(pipeline_run(p, &err), "%s", err.msg);
    atomic_store(&r.done, true);
    pthread_join(th, NULL);
    cr_assert(rd.count >= RACE_MOVES, "%d frames for %d cursor moves", rd.count, RACE_MOVES);
    cr_assert_eq(rd.first_whole_miss, -1, "frame %d (sphere %s) is no whole image", rd.first_whole_miss,
                 rd.first_whole_miss % 2 ? "hidden" : "shown");
    cr_assert((rd.seen[0] > 0) + (rd.seen[1] > 0) + (rd.seen[2] > 0) >= 2, "the cursor never moved between frames");
    cr_assert_eq(atomic_load(&r.bad_picks), 0);
    cr_assert(atomic_load(&r.picks) >= RACE_MOVES && atomic_load(&r.moves) >= RACE_MOVES);
    pipeline_destroy(p);
    accel_unhide_all(fx.accel);
    for (int hidden = 0; hidden < 2; hidden++)
        for (int c = 0; c < RACE_CURSORS; c++)
            free(refs[hidden][c]);
    fixture_free(&fx);
}

/* A wall with bezels: the windows leave a margin around the plane, so the
 * plane's corner (-1, -1) is behind a bezel. The status line sits at the
 * bottom-left corner of the bottom-left output instead, fully visible. */
Test(overlay, the_status_line_starts_at_the_bottom_left_output_not_behind_a_bezel, .timeout = 60)
{
    fixture fx = fixture_default();
    const int w = 64, h = 48;
    const float aspect = 2.f * (float)w / (float)h / 0.9f;
    /* two outputs side by side, each 0.9 of its half in x and 0.9 of the height, gaps between */
    channel_spec wall[2] = {{{-0.5f, 0.f, 0.45f, 0.9f}, aspect, w, h}, {{0.5f, 0.f, 0.45f, 0.9f}, aspect, w, h}};
    overlay_setup ov = {"bezel", false, 0.f, 0.f};
    grabbed plain[2], drawn[2];
    pipeline_config cfg = config(&fx, 2);
    run_channels(&fx, cfg, wall, 2, no_overlay, NULL, NULL, plain);
    run_channels(&fx, cfg, wall, 2, ov, NULL, NULL, drawn);
    /* the band: from the left output's bottom-left pixel, (5 * 6 - 1 + 4) x 13 pixels at scale 1 */
    const int band_w = 5 * OVERLAY_CELL_W - 1 + 2 * OVERLAY_PAD, band_h = OVERLAY_CELL_H + 2 * OVERLAY_PAD;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = 3 * ((size_t)y * w + x);
            bool in_band = x < band_w && y >= h - band_h;
            bool changed = !same_pixel(&plain[0].frames[0][i], &drawn[0].frames[0][i]);
            cr_assert_eq(changed, in_band, "left output pixel (%d, %d): %s", x, y,
                         in_band ? "not darkened by the band" : "changed outside the band");
            cr_assert(same_pixel(&plain[1].frames[0][i], &drawn[1].frames[0][i]), "right output pixel (%d, %d) changed",
                      x, y);
        }
    for (int i = 0; i < 2; i++) {
        grabbed_free(&plain[i]);
        grabbed_free(&drawn[i]);
    }
    fixture_free(&fx);
}

/* Remote viewers' pointers: a disc in the slot's colour at the point, with
 * a dark rim, drawn by every channel it falls on at the same plane point,
 * the same whatever the tiles; hidden ones and ones off the channel draw
 * nothing (the plan is empty). */
Test(overlay, viewer_pointers_are_discs_in_their_colour)
{
    enum { W = 160, H = 90 };
    overlay_state st;
    memset(&st, 0, sizeof st);
    st.pointer_visible[2] = true;
    st.pointer_sx[2] = 0.f; /* the plane's centre */
    st.pointer_sy[2] = 0.f;
    st.pointer_visible[5] = false;
    st.pointer_sx[5] = 0.5f;
    overlay_plan plan;
    cr_assert(overlay_plan_make(&plan, &st, CAMERA_WINDOW_FULL, W, H));
    cr_assert_eq(plan.pointer_count, 1);
    static float whole[W * H * 3], tiled[W * H * 3];
    for (int i = 0; i < W * H * 3; i++)
        whole[i] = tiled[i] = 0.5f;
    overlay_draw(&plan, W, 0, 0, W, H, whole);
    for (int y0 = 0; y0 < H; y0 += 7)
        for (int x0 = 0; x0 < W; x0 += 5)
            overlay_draw(&plan, W, x0, y0, x0 + 5 < W ? x0 + 5 : W, y0 + 7 < H ? y0 + 7 : H, tiled);
    cr_assert(memcmp(whole, tiled, sizeof whole) == 0, "the tiles draw the same disc");
    float colour[3];
    overlay_pointer_rgb(2, colour);
    const float *centre = whole + 3 * ((H / 2) * W + W / 2);
    for (int c = 0; c < 3; c++)
        cr_assert_float_eq(centre[c], colour[c], 0.f, "the disc's centre has slot 2's colour");
    int rim = W / 2 + OVERLAY_POINTER_R - 1; /* inside the outer radius, in the rim */
    cr_assert_float_eq(whole[3 * ((H / 2) * W + rim)], 0.f, 0.f, "the rim is dark");
    cr_assert_float_eq(whole[3 * ((H / 2) * W + W / 2 + OVERLAY_POINTER_R + 2)], 0.5f, 0.f, "outside untouched");
    char hex[8];
    overlay_pointer_colour_hex(2, hex);
    cr_assert_str_eq(hex, "#4363d8");
    /* a channel showing the right half of the plane: the disc on its left edge */
    camera_window right = {0.5f, 0.f, 0.5f, 1.f};
    cr_assert(overlay_plan_make(&plan, &st, right, W, H));
    cr_assert_eq(plan.pointer_count, 1);
    cr_assert_float_eq(plan.pointers[0].cx, 0.0, 1e-9);
    st.pointer_visible[2] = false;
    cr_assert_not(overlay_plan_make(&plan, &st, CAMERA_WINDOW_FULL, W, H), "nothing shown: no plan");
}

/* PRIVATE CHANNELS (frame_state.h): a remote viewer's own view keeps its
 * camera when the wall's ("all") changes, and draws the status line but not
 * the wall's cursor or the viewers' pointers. */
static void make_private_and_move_the_wall(pipeline *p, void *ctx)
{
    const camera_desc *other = ctx;
    tess_error err = {{0}};
    cr_assert(pipeline_set_channel_private(p, 1, &err), "%s", err.msg);
    txn_record pointer = txn_pointer(3, true, 0.25f, -0.2f);
    txn_record wall = txn_camera(TXN_ALL_CHANNELS, other);
    cr_assert(pipeline_apply(p, &pointer));
    cr_assert(pipeline_apply(p, &wall));
    cr_assert(pipeline_channel_private(p, 1) && !pipeline_channel_private(p, 0));
    camera_desc kept = pipeline_camera(p, 1), moved = pipeline_camera(p, 0);
    cr_assert(memcmp(&moved, other, sizeof moved) == 0, "the wall's channel takes the wall's camera");
    cr_assert(memcmp(&kept, other, sizeof kept) != 0, "the private channel keeps its own");
    cr_assert_eq(pipeline_camera_serial(p, 1), 0, "no camera was set on the private channel");
}

Test(overlay, a_private_channel_keeps_its_camera_and_draws_the_status_line_without_cursor_or_pointers,
     .timeout = 120)
{
    fixture fx = fixture_default();
    const int w = 96, h = 64;
    camera_desc other = fx.camera;
    other.eye = v3_add(other.eye, v3(1.5f, 0.5f, 0.f));
    channel_spec specs[2] = {full_channel(w, h), full_channel(w, h)};
    grabbed out[2];
    overlay_setup ov = {"private", true, 0.1f, 0.1f};
    run_channels(&fx, config(&fx, 2), specs, 2, ov, make_private_and_move_the_wall, &other, out);
    cr_assert_eq(out[0].count, 1);
    cr_assert_eq(out[1].count, 1);
    /* the private channel: its own camera, the status line, nothing else */
    overlay_setup status_only = {"private", false, 0.f, 0.f};
    float *expected_private = one_frame(&fx, config(&fx, 2), w, h, status_only);
    cr_assert(same_image(out[1].frames[0], expected_private, w, h),
              "the private channel shows its camera with the status line, no cursor, no pointer");
    /* the wall's channel: the other camera, with the cursor and the pointer */
    fixture moved = fx;
    moved.camera = other;
    float *wall_plain = one_frame(&moved, config(&moved, 2), w, h, status_only);
    cr_assert_not(same_image(out[0].frames[0], wall_plain, w, h), "the wall draws the cursor and the pointer");
    int differing = 0;
    for (int i = 0; i < w * h; i++)
        differing += !same_pixel(out[0].frames[0] + 3 * i, wall_plain + 3 * i);
    cr_assert_lt(differing, w * h / 4, "only the cursor and the disc differ: the wall has the other camera");
    /* channel 0 (the wall's) or a channel that does not exist: refused, naming why */
    tess_error err = {{0}};
    pipeline_config cfg = config(&fx, 1);
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p, "%s", err.msg);
    grabbed unused[2];
    memset(unused, 0, sizeof unused);
    cr_assert_eq(pipeline_add_channel(p, &fx.camera, w, h, grab_create(&unused[0]), &err), 0);
    cr_assert_eq(pipeline_add_channel(p, &fx.camera, w, h, grab_create(&unused[1]), &err), 1);
    cr_assert_not(pipeline_set_channel_private(p, 0, &err));
    cr_assert(strstr(err.msg, "channel 0 is the wall's"), "%s", err.msg);
    cr_assert_not(pipeline_set_channel_private(p, 2, &err));
    cr_assert(pipeline_set_channel_private(p, 1, &err), "%s", err.msg);
    pipeline_destroy(p);
    free(expected_private);
    free(wall_plain);
    grabbed_free(&out[0]);
    grabbed_free(&out[1]);
    fixture_free(&fx);
}
