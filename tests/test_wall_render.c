/* test_wall_render.c - the wall layout rendered headless: every output is an
 * off-axis window of one camera, so a 1x1 wall is the plain render, a wall
 * without bezels is the big picture cut in pieces, straight lines stay
 * straight across outputs and bezels, and the stitched image shows bezels as
 * black. Runs the tessera binary (tests/support.h) and the engine directly. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/base/camera.h"
#include "support.h"
#include "wall/dump.h"
#include "wall/wall_config.h"
#include "wall/wall_headless.h"

#define TIMEOUT_S 120

static char tmp_dir[256];

static void make_tmp_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "wall"); }

TestSuite(wall_render, .init = make_tmp_dir, .timeout = 300);

static float *read_exr(const char *name, int *w, int *h) { return support_read_image(tmp_dir, name, w, h); }

/* A wall of `cols` x 1 outputs of w x h pixels, each 4 mm per pixel... as JSON. */
static void write_row_wall(const char *name, int cols, int w_px, int h_px, double bezel_mm)
{
    char text[4096];
    size_t n = (size_t)snprintf(text, sizeof text,
                                "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": [");
    for (int c = 0; c < cols; c++)
        n += (size_t)snprintf(text + n, sizeof text - n,
                              "%s{\"connector\": \"Virtual-%d\", \"mode\": \"%dx%d\", \"grid\": [%d, 0],"
                              " \"size_mm\": [%d, %d], \"bezel_mm\": {\"left\": %g, \"right\": %g, \"top\": %g,"
                              " \"bottom\": %g}}",
                              c ? ", " : "", c + 1, w_px, h_px, c, 4 * w_px, 4 * h_px, bezel_mm, bezel_mm, bezel_mm,
                              bezel_mm);
    snprintf(text + n, sizeof text - n, "]}");
    support_write_file(tmp_dir, name, text);
}

Test(wall_render, one_output_without_bezels_is_the_plain_render_bit_for_bit)
{
    char out[8192];
    write_row_wall("desk.json", 1, 64, 36, 0.0);
    cr_assert_eq(support_tessera(tmp_dir, TIMEOUT_S, out, sizeof out,
                                 "render --wall %s/desk.json --threads 2 --out %s/wall.exr"),
                 0, "%s", out);
    cr_assert_eq(support_tessera(tmp_dir, TIMEOUT_S, out, sizeof out, "render --size 64x36 --out %s/plain.exr"), 0,
                 "%s", out);
    int w, h, w2, h2, w3, h3;
    float *plain = read_exr("plain.exr", &w, &h), *output = read_exr("wall-Virtual-1.exr", &w2, &h2),
          *stitched = read_exr("wall.exr", &w3, &h3);
    cr_assert(w == w2 && h == h2 && w == w3 && h == h3, "sizes %dx%d %dx%d %dx%d", w, h, w2, h2, w3, h3);
    size_t bytes = (size_t)w * h * 3 * sizeof(float);
    cr_expect(!memcmp(plain, output, bytes), "the output's image differs from the plain render");
    cr_expect(!memcmp(plain, stitched, bytes), "the stitched image differs from the plain render");
    free(plain);
    free(output);
    free(stitched);
}

/* Two outputs side by side without bezels show the two halves of one picture:
 * equal to the plain render of the whole up to the rounding of the off-axis
 * directions (a few silhouette pixels may flip). */
Test(wall_render, outputs_without_bezels_are_the_big_picture_cut_in_pieces)
{
    char out[8192];
    write_row_wall("pair.json", 2, 40, 36, 0.0);
    cr_assert_eq(support_tessera(tmp_dir, TIMEOUT_S, out, sizeof out,
                                 "render --wall %s/pair.json --threads 2 --out %s/pair.exr"),
                 0, "%s", out);
    cr_assert_eq(support_tessera(tmp_dir, TIMEOUT_S, out, sizeof out, "render --size 80x36 --out %s/big.exr"), 0,
                 "%s", out);
    int w, h, ws, hs;
    float *big = read_exr("big.exr", &w, &h), *stitched = read_exr("pair.exr", &ws, &hs);
    cr_assert(w == ws && h == hs, "stitched %dx%d, plain %dx%d", ws, hs, w, h);
    size_t close = 0, total = (size_t)w * h * 3;
    double worst = 0.0;
    for (size_t i = 0; i < total; i++) {
        double d = fabs((double)big[i] - (double)stitched[i]);
        close += d <= 1e-4;
        worst = fmax(worst, d);
    }
    cr_expect(close >= total * 99 / 100, "only %zu of %zu channel values within 1e-4 (worst %g)", close, total,
              worst);
    free(big);
    free(stitched);
}

Test(wall_render, bezels_are_black_in_the_stitched_image_and_hidden_pixels_are_skipped)
{
    char out[8192];
    write_row_wall("bezel.json", 2, 30, 20, 8.0); /* 8 mm = 2 pixels at 4 mm per pixel */
    cr_assert_eq(support_tessera(tmp_dir, TIMEOUT_S, out, sizeof out,
                                 "render --wall %s/bezel.json --threads 2 --out %s/b.exr"),
                 0, "%s", out);
    int w, h;
    float *st = read_exr("b.exr", &w, &h);
    /* wall: 2 x (120 + 16) mm by (80 + 16) mm at 4 mm/px = 68 x 24 */
    cr_assert(w == 68 && h == 24, "stitched %dx%d", w, h);
    int x_bezel[] = {0, 1, 32, 33, 34, 35, 66, 67}; /* outer and the two middle bezels */
    for (size_t k = 0; k < sizeof x_bezel / sizeof x_bezel[0]; k++)
        for (int y = 0; y < h; y++) {
            const float *px = st + 3 * ((size_t)y * w + x_bezel[k]);
            cr_expect(px[0] == 0.f && px[1] == 0.f && px[2] == 0.f, "bezel pixel (%d, %d) not black", x_bezel[k], y);
        }
    /* the output images hold exactly the active pixels */
    int w1, h1;
    float *left = read_exr("b-Virtual-1.exr", &w1, &h1);
    cr_expect(w1 == 30 && h1 == 20);
    for (int y = 0; y < h1; y++)
        for (int x = 0; x < w1; x++)
            cr_expect(!memcmp(left + 3 * ((size_t)y * w1 + x), st + 3 * ((size_t)(y + 2) * w + (x + 2)),
                              3 * sizeof(float)),
                      "stitched pixel of the left output (%d, %d) differs", x, y);
    free(st);
    free(left);
}

/* Where a world point lands on the wall, through output i's camera (mm). */
static void wall_position(const wall_config *wc, int i, const camera_desc *cam, vec3 p, double *x_mm, double *y_mm)
{
    const wall_output *o = &wc->outputs[i];
    camera_basis b = camera_basis_window(cam, wall_plane_aspect(wc), wall_output_window(wc, i), o->width_px,
                                         o->height_px);
    /* solve d = t (forward + sx right + sy up) for sx, sy: right and up are orthogonal to each other and
     * to the camera's true forward, so project on them against the component along forward x right */
    vec3 d = v3_sub(p, cam->eye);
    vec3 n = v3_normalize(v3_cross(b.right, b.up)); /* the true view axis (up to sign) */
    double depth = v3_dot(d, n) / v3_dot(b.forward, n);
    vec3 on_plane = v3_sub(v3_scale(d, (float)(1.0 / depth)), b.forward);
    double sx = v3_dot(on_plane, b.right) / v3_dot(b.right, b.right);
    double sy = v3_dot(on_plane, b.up) / v3_dot(b.up, b.up);
    *x_mm = o->x_mm + (sx + 1.0) * 0.5 * o->width_mm;
    *y_mm = o->y_mm + (1.0 - sy) * 0.5 * o->height_mm;
}

/* A 3D line seen by two outputs with a wide bezel between them lands on one
 * straight line of the wall (as through a window frame), not two offset ones. */
Test(wall_render, a_straight_line_stays_straight_across_outputs_and_bezels)
{
    const char *json = "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"DP-1\", \"mode\": \"800x600\", \"position_mm\": [0, 0], \"size_mm\": [400, 300],"
                       " \"bezel_mm\": {\"right\": 35}},"
                       "{\"connector\": \"DP-2\", \"mode\": \"800x600\", \"position_mm\": [435, 20], \"size_mm\": [400, 300]}]}";
    wall_config wc;
    tess_error err = {{0}};
    cr_assert(wall_config_parse("line.json", json, strlen(json), &wc, &err), "%s", err.msg);
    cr_assert(wall_config_headless_sizes(&wc, &err), "%s", err.msg);
    camera_desc cam = {v3(0.f, 1.f, 10.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    /* a slanted 3D line crossing the view from left to right */
    vec3 a = v3(-6.f, -1.f, -2.f), b = v3(6.f, 2.5f, 1.f);
    double xs[64], ys[64];
    int count = 0;
    for (int k = 0; k <= 40; k++) {
        vec3 p = v3_add(a, v3_scale(v3_sub(b, a), (float)k / 40.f));
        for (int i = 0; i < wc.count; i++) {
            double x, y;
            wall_position(&wc, i, &cam, p, &x, &y);
            const wall_output *o = &wc.outputs[i];
            if (x >= o->x_mm && x < o->x_mm + o->width_mm && y >= o->y_mm && y < o->y_mm + o->height_mm) {
                xs[count] = x, ys[count] = y, count++;
                break;
            }
        }
    }
    cr_assert(count > 10, "too few points on the outputs (%d)", count);
    bool left = false, right = false;
    for (int k = 0; k < count; k++) {
        left = left || xs[k] < 400.0;
        right = right || xs[k] >= 435.0;
    }
    cr_assert(left && right, "the line must cross from one output to the other");
    /* every point on the line through the first and last */
    double dx = xs[count - 1] - xs[0], dy = ys[count - 1] - ys[0], len = sqrt(dx * dx + dy * dy);
    for (int k = 0; k < count; k++) {
        double off = fabs((xs[k] - xs[0]) * dy - (ys[k] - ys[0]) * dx) / len;
        cr_expect(off < 1e-2, "point %d is %g mm off the straight line", k, off);
    }
}

Test(wall_render, wall_errors_are_clear)
{
    support_write_file(tmp_dir, "pref.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"Virtual-1\", \"grid\": [0, 0], \"size_mm\": [160, 90]}]}");
    const char *pref[] = {"pref.json", "preferred", NULL};
    support_expect_error(tmp_dir, TIMEOUT_S, "render --wall %s/pref.json --out %s/w.png", pref);
    support_write_file(tmp_dir, "overlap.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"DP-1\", \"mode\": \"160x90\", \"position_mm\": [0, 0], \"size_mm\": [160, 90]},"
                       "{\"connector\": \"DP-2\", \"mode\": \"160x90\", \"position_mm\": [100, 0], \"size_mm\": [160, 90]}]}");
    const char *overlap[] = {"overlap.json", "overlap", NULL};
    support_expect_error(tmp_dir, TIMEOUT_S, "render --wall %s/overlap.json --out %s/w.png", overlap);
    const char *missing[] = {"nowall.json", NULL};
    support_expect_error(tmp_dir, TIMEOUT_S, "render --wall %s/nowall.json --out %s/w.png", missing);
    const char *drm_no_wall[] = {"--display drm", "--wall", NULL};
    support_expect_error(tmp_dir, TIMEOUT_S, "run --display drm --out %s/f_####.png", drm_no_wall);
}

/* `tessera outputs` lists the cards, or says clearly there is none (exit 1). */
Test(wall_render, outputs_lists_cards_or_says_there_is_none)
{
    char out[8192];
    int code = support_tessera(tmp_dir, TIMEOUT_S, out, sizeof out, "outputs");
    if (access("/dev/dri/card0", F_OK) == 0)
        cr_expect(code == 0 && strstr(out, "/dev/dri/card"), "exit %d: %s", code, out);
    else
        cr_expect(code == 1 && strstr(out, "no DRM card"), "exit %d: %s", code, out);
}

/* Every example wall renders headless. */
Test(wall_render, example_walls_render)
{
    const char *walls[] = {"desk.json", "wall_2x2.json", "portrait_3x1.json", "vm_2x2.json"};
    for (size_t i = 0; i < sizeof walls / sizeof walls[0]; i++) {
        char args[512], out[8192];
        snprintf(args, sizeof args, "render --wall ../configs/walls/%s --threads 2 --renderer eyelight --out %%s/ex.png",
                 walls[i]);
        /* large example walls: render them small by skipping? they carry real modes; keep one frame */
        cr_expect_eq(support_tessera(tmp_dir, TIMEOUT_S, out, sizeof out, args), 0, "%s: %s", walls[i], out);
    }
}
