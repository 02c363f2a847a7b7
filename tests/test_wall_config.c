/* test_wall_config.c - wall files (wall/wall_config.h): the examples in
 * ../configs/walls (the suite runs in tests/) and their geometry, grid and
 * pixel placement, rotation, normalisation, every validation message, device
 * matching against synthetic connector lists (no hardware) and headless
 * sizes. Files for wall_config_load are written to a mkdtemp directory. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "support.h"
#include "wall/wall_config.h"

#define EXAMPLE_WALLS_DIR "../configs/walls"

/* ---- helpers ---------------------------------------------------------------- */

#define HEADER "\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", "

/* A 16:9 output of 160 x 90 mm at 640x360 on connector Virtual-N, placed by PLACE. */
#define OUT(n, place) "{\"connector\": \"Virtual-" #n "\", \"mode\": \"640x360\", " place ", \"size_mm\": [160, 90]}"

static bool parse(const char *text, wall_config *w, tess_error *err)
{
    return wall_config_parse("wall.json", text, strlen(text), w, err);
}

static wall_config parse_ok(const char *text)
{
    wall_config w;
    tess_error err = {{0}};
    cr_assert(parse(text, &w, &err), "%s\n  for: %s", err.msg, text);
    return w;
}

/* Parsing must fail with a message containing `want` (and nothing is returned). */
static void expect_failure(const char *text, const char *want)
{
    wall_config w;
    tess_error err = {{0}};
    cr_assert_not(parse(text, &w, &err), "accepted: %s", text);
    cr_assert(strstr(err.msg, want), "for %s\n  got:  %s\n  want: %s", text, err.msg, want);
    cr_assert_null(strchr(err.msg, '\n'), "one line: %s", err.msg);
    cr_assert_eq(w.count, 0, "a failed parse leaves an empty wall");
}

/* One output `o` of an otherwise valid file. */
static void expect_output_failure(const char *o, const char *want)
{
    char text[2048];
    snprintf(text, sizeof text, "{" HEADER "\"outputs\": [%s]}", o);
    expect_failure(text, want);
}

static void expect_near(double got, double want, const char *what)
{
    cr_expect(fabs(got - want) < 1e-9, "%s: got %.12g, want %.12g", what, got, want);
}

static void expect_rect(const wall_output *o, double x, double y, double w, double h)
{
    expect_near(o->x_mm, x, "x_mm");
    expect_near(o->y_mm, y, "y_mm");
    expect_near(o->width_mm, w, "width_mm");
    expect_near(o->height_mm, h, "height_mm");
}

static wall_config load_example(const char *name)
{
    char path[256];
    wall_config w;
    tess_error err = {{0}};
    snprintf(path, sizeof path, "%s/%s", EXAMPLE_WALLS_DIR, name);
    cr_assert(wall_config_load(path, &w, &err), "%s", err.msg);
    return w;
}

static void expect_headless(wall_config *w, int width_px, int height_px)
{
    tess_error err = {{0}};
    cr_assert(wall_config_headless_sizes(w, &err), "%s", err.msg);
    for (int i = 0; i < w->count; i++) {
        cr_expect_eq(w->outputs[i].width_px, width_px, "outputs[%d] width_px %d", i, w->outputs[i].width_px);
        cr_expect_eq(w->outputs[i].height_px, height_px, "outputs[%d] height_px %d", i, w->outputs[i].height_px);
    }
}

/* ---- the examples --------------------------------------------------------------- */

Test(wall_config, example_desk)
{
    wall_config w = load_example("desk.json");
    cr_assert_eq(w.count, 1);
    cr_expect_str_eq(w.outputs[0].connector, "Virtual-1");
    expect_rect(&w.outputs[0], 0, 0, 531.36, 298.89);
    expect_near(w.width_mm, 531.36, "wall width");
    expect_near(w.height_mm, 298.89, "wall height");
    cr_expect_eq(w.outputs[0].mode_hz, 60.0);
    expect_headless(&w, 1920, 1080);
}

Test(wall_config, example_wall_2x2)
{
    wall_config w = load_example("wall_2x2.json");
    cr_assert_eq(w.count, 4);
    expect_near(w.width_mm, 2 * (531 + 20), "wall width");
    expect_near(w.height_mm, 2 * (299 + 20), "wall height");
    expect_rect(&w.outputs[0], 10, 10, 531, 299);
    expect_rect(&w.outputs[1], 561, 10, 531, 299);
    expect_rect(&w.outputs[2], 10, 329, 531, 299);
    expect_rect(&w.outputs[3], 561, 329, 531, 299);
    for (int i = 0; i < 4; i++) {
        char name[32];
        snprintf(name, sizeof name, "Virtual-%d", i + 1);
        cr_expect_str_eq(w.outputs[i].connector, name);
        expect_near(w.outputs[i].bezel_right_mm, 10, "bezel right");
    }
    expect_headless(&w, 1920, 1080);
}

Test(wall_config, example_portrait_3x1)
{
    wall_config w = load_example("portrait_3x1.json");
    cr_assert_eq(w.count, 3);
    expect_near(w.width_mm, 3 * 323, "wall width");
    expect_near(w.height_mm, 561, "wall height");
    for (int i = 0; i < 3; i++) {
        cr_expect_eq(w.outputs[i].rotation_deg, 90);
        expect_rect(&w.outputs[i], 12 + 323 * i, 15, 299, 531);
    }
    expect_headless(&w, 1080, 1920);
}

Test(wall_config, example_vm_2x2)
{
    wall_config w = load_example("vm_2x2.json");
    cr_assert_eq(w.count, 4);
    expect_near(w.width_mm, 336, "wall width");
    expect_near(w.height_mm, 256, "wall height");
    expect_rect(&w.outputs[0], 4, 4, 160, 120);
    expect_rect(&w.outputs[3], 172, 132, 160, 120);
    cr_expect_eq(w.outputs[0].mode_hz, 0.0, "no refresh given: any");
    expect_headless(&w, 640, 480);
}

/* ---- geometry --------------------------------------------------------------- */

Test(wall_config, defaults)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": [{\"connector\": \"DP-1\", \"position_mm\": [0, 0], "
                             "\"size_mm\": [100, 50]}]}");
    const wall_output *o = &w.outputs[0];
    cr_expect(o->mode_preferred);
    cr_expect_eq(o->mode_w_px, 0);
    cr_expect_eq(o->rotation_deg, 0);
    cr_expect_not(o->edid.given);
    cr_expect_eq(o->bezel_left_mm + o->bezel_top_mm + o->bezel_right_mm + o->bezel_bottom_mm, 0.0);
    cr_expect_eq(o->width_px, 0, "unresolved until a device or a headless run");
    cr_expect_eq(o->device_connector, -1);
    cr_expect_eq(o->device_mode, -1);
}

Test(wall_config, grid_math_with_uneven_bezels)
{
    /* tile 4 + 160 + 6 = 170 wide, 1 + 90 + 3 = 94 high; cells (2, 0) and (0, 1) */
#define BZ "\"bezel_mm\": {\"left\": 4, \"top\": 1, \"right\": 6, \"bottom\": 3}"
    wall_config w = parse_ok("{" HEADER "\"outputs\": ["
                             "{\"connector\": \"DP-1\", \"mode\": \"640x360\", \"grid\": [2, 0], "
                             "\"size_mm\": [160, 90], " BZ "},"
                             "{\"connector\": \"DP-2\", \"mode\": \"640x360\", \"grid\": [0, 1], "
                             "\"size_mm\": [160, 90], " BZ "}]}");
#undef BZ
    /* before normalisation: (344, 1) and (4, 95); the box starts at (0, 0) */
    expect_rect(&w.outputs[0], 344, 1, 160, 90);
    expect_rect(&w.outputs[1], 4, 95, 160, 90);
    expect_near(w.width_mm, 3 * 170, "wall width");
    expect_near(w.height_mm, 2 * 94, "wall height");
}

Test(wall_config, normalisation_shifts_the_bounding_box_to_the_origin)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": ["
                             "{\"connector\": \"DP-1\", \"position_mm\": [-500, 200], \"size_mm\": [100, 50], "
                             "\"bezel_mm\": {\"left\": 5, \"top\": 7}},"
                             "{\"connector\": \"DP-2\", \"position_mm\": [-300, 100], \"size_mm\": [100, 50], "
                             "\"bezel_mm\": {\"bottom\": 2}}]}");
    /* box: x from -505 to -200, y from 100 to 250 */
    expect_rect(&w.outputs[0], 5, 100, 100, 50);
    expect_rect(&w.outputs[1], 205, 0, 100, 50);
    expect_near(w.width_mm, 305, "wall width");
    expect_near(w.height_mm, 150, "wall height");
}

Test(wall_config, rotation_swaps_the_mode_pixels)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": ["
                             "{\"connector\": \"DP-1\", \"mode\": \"1920x1080\", \"rotation\": 270, "
                             "\"position_mm\": [0, 0], \"size_mm\": [299, 531]},"
                             "{\"connector\": \"DP-2\", \"mode\": \"1920x1080\", \"rotation\": 180, "
                             "\"position_mm\": [400, 0], \"size_mm\": [531, 299]}]}");
    tess_error err = {{0}};
    cr_assert(wall_config_headless_sizes(&w, &err), "%s", err.msg);
    cr_expect_eq(w.outputs[0].width_px, 1080);
    cr_expect_eq(w.outputs[0].height_px, 1920);
    cr_expect_eq(w.outputs[0].mode_w_px, 1920, "the mode stays as scanned out");
    cr_expect_eq(w.outputs[1].width_px, 1920);
    cr_expect_eq(w.outputs[1].height_px, 1080);
}

Test(wall_config, position_px_uses_the_outputs_pixel_pitch)
{
    /* 640 px over 160 mm: 0.25 mm per pixel; rotated 90: 360 px over 90 mm across */
    wall_config w = parse_ok("{" HEADER "\"outputs\": ["
                             OUT(1, "\"position_px\": [0, 0]") ","
                             OUT(2, "\"position_px\": [700, 400]") ","
                             "{\"connector\": \"Virtual-3\", \"mode\": \"640x360@30\", \"rotation\": 90, "
                             "\"position_px\": [4000, 100], \"size_mm\": [90, 160]}]}");
    expect_rect(&w.outputs[0], 0, 0, 160, 90);
    expect_rect(&w.outputs[1], 175, 100, 160, 90);
    expect_rect(&w.outputs[2], 1000, 25, 90, 160);
    expect_near(w.width_mm, 1090, "wall width");
}

Test(wall_config, mode_strings)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": [{\"connector\": \"HDMI-A-1\", \"mode\": \"1920x1200@59.94\", "
                             "\"position_mm\": [0, 0], \"size_mm\": [518.4, 324]}]}");
    cr_expect_eq(w.outputs[0].mode_w_px, 1920);
    cr_expect_eq(w.outputs[0].mode_h_px, 1200);
    cr_expect_eq(w.outputs[0].mode_hz, 59.94);
    cr_expect_not(w.outputs[0].mode_preferred);
    w = parse_ok("{" HEADER "\"outputs\": [{\"connector\": \"HDMI-A-1\", \"mode\": \"preferred\", "
                 "\"position_mm\": [0, 0], \"size_mm\": [518.4, 324]}]}");
    cr_expect(w.outputs[0].mode_preferred);
}

Test(wall_config, edid_is_read)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": [{\"connector\": \"DP-1\", \"edid\": {\"manufacturer\": "
                             "\"DEL\", \"serial\": \"ABC123\"}, \"position_mm\": [0, 0], \"size_mm\": [10, 10]}]}");
    cr_expect(w.outputs[0].edid.given);
    cr_expect_str_eq(w.outputs[0].edid.manufacturer, "DEL");
    cr_expect_str_eq(w.outputs[0].edid.model, "");
    cr_expect_str_eq(w.outputs[0].edid.serial, "ABC123");
}

Test(wall_config, touching_tiles_and_tiny_overlaps_are_fine)
{
    parse_ok("{" HEADER "\"outputs\": [" OUT(1, "\"position_mm\": [0, 0]") "," OUT(2, "\"position_mm\": [159.995, 0]")
             "]}");
}

/* ---- validation ---------------------------------------------------------------- */

Test(wall_config, overlapping_tiles)
{
    expect_failure("{" HEADER "\"outputs\": [" OUT(1, "\"position_mm\": [0, 0]") ","
                   OUT(2, "\"position_mm\": [300, 0]") "," OUT(3, "\"position_mm\": [150, 80]") "]}",
                   "wall.json: field 'outputs[2]': its tile (active area + bezels, x 150..310, y 80..170 mm) "
                   "overlaps that of outputs[0] (x 0..160, y 0..90 mm) by 10 x 10 mm");
    /* bezels count: 5 mm bezels on tiles 8 mm apart */
    expect_failure("{" HEADER "\"outputs\": ["
                   "{\"connector\": \"DP-1\", \"position_mm\": [0, 0], \"size_mm\": [100, 50], "
                   "\"bezel_mm\": {\"right\": 5}},"
                   "{\"connector\": \"DP-2\", \"position_mm\": [108, 0], \"size_mm\": [100, 50], "
                   "\"bezel_mm\": {\"left\": 5}}]}",
                   "field 'outputs[1]': its tile");
}

Test(wall_config, duplicate_connector)
{
    expect_failure("{" HEADER "\"outputs\": [" OUT(1, "\"grid\": [0, 0]") "," OUT(2, "\"grid\": [1, 0]") ","
                   OUT(1, "\"grid\": [2, 0]") "]}",
                   "wall.json: field 'outputs[2].connector': 'Virtual-1' is also the connector of outputs[0]");
}

Test(wall_config, duplicate_edid)
{
#define EDID "\"edid\": {\"manufacturer\": \"DEL\", \"model\": \"U2415\", \"serial\": \"ABC123\"}"
    expect_failure("{" HEADER "\"outputs\": ["
                   "{\"connector\": \"DP-1\", " EDID ", \"grid\": [0, 0], \"size_mm\": [10, 10]},"
                   "{\"connector\": \"DP-2\", " EDID ", \"grid\": [1, 0], \"size_mm\": [10, 10]}]}",
                   "wall.json: field 'outputs[1].edid': the same monitor identity as outputs[0] (manufacturer "
                   "DEL, model U2415, serial ABC123)");
#undef EDID
    /* different serials are different monitors */
    parse_ok("{" HEADER "\"outputs\": ["
             "{\"connector\": \"DP-1\", \"edid\": {\"model\": \"U2415\", \"serial\": \"A\"}, \"grid\": [0, 0], "
             "\"size_mm\": [10, 10]},"
             "{\"connector\": \"DP-2\", \"edid\": {\"model\": \"U2415\", \"serial\": \"B\"}, \"grid\": [1, 0], "
             "\"size_mm\": [10, 10]}]}");
}

Test(wall_config, aspect_mismatch)
{
    expect_output_failure("{\"connector\": \"DP-1\", \"mode\": \"1920x1200\", \"grid\": [0, 0], "
                          "\"size_mm\": [531, 299]}",
                          "field 'outputs[0]': size_mm 531 x 299 has aspect 1.7759 but mode 1920x1200 rotated 0 "
                          "gives 1920 x 1200 px, aspect 1.6000; they must agree within 2%");
    /* rotation is taken into account: a landscape size on a portrait mounting */
    expect_output_failure("{\"connector\": \"DP-1\", \"mode\": \"1920x1080\", \"rotation\": 90, "
                          "\"grid\": [0, 0], \"size_mm\": [531, 299]}",
                          "gives 1080 x 1920 px, aspect 0.5625");
}

Test(wall_config, placement_missing_or_given_twice)
{
    expect_output_failure("{\"connector\": \"DP-1\", \"size_mm\": [10, 10]}",
                          "wall.json: field 'outputs[0]': needs one of grid, position_mm or position_px");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0], \"position_mm\": [0, 0], "
                          "\"size_mm\": [10, 10]}",
                          "field 'outputs[0]': give only one of grid, position_mm and position_px, got grid and "
                          "position_mm");
    expect_output_failure("{\"connector\": \"DP-1\", \"position_px\": [0, 0], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].position_px': needs an explicit mode");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0.5, 0], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].grid[0]': must be a whole number from 0 to 255, got 0.5");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, -1], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].grid[1]': must be >= 0, got -1");
    expect_output_failure("{\"connector\": \"DP-1\", \"position_mm\": [0], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].position_mm': expected an array of 2 numbers, got 1 element");
}

Test(wall_config, grid_outputs_must_share_a_tile)
{
    expect_failure("{" HEADER "\"outputs\": [" OUT(1, "\"grid\": [0, 0]") ","
                   "{\"connector\": \"Virtual-2\", \"grid\": [1, 0], \"size_mm\": [160, 90], "
                   "\"bezel_mm\": {\"top\": 1}}]}",
                   "wall.json: field 'outputs[1]': grid placement needs every grid output to have the same "
                   "size_mm and bezel_mm as outputs[0]; use position_mm");
}

Test(wall_config, bad_rotation)
{
    expect_output_failure("{\"connector\": \"DP-1\", \"rotation\": 45, \"grid\": [0, 0], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].rotation': must be 0, 90, 180 or 270 (degrees clockwise), got 45");
}

Test(wall_config, bad_mode_strings)
{
    static const char *const bad[] = {"19x", "x1080", "1920x", "1920X1080", "1920x1080@", "1920x1080@60Hz",
                                      "0x1080", "99999x1080", "1920x1080@0", "1920x1080@-60", " 1920x1080",
                                      "1920x1080@.5", "Preferred", NULL};
    for (const char *const *m = bad; *m; m++) {
        char o[256];
        snprintf(o, sizeof o, "{\"connector\": \"DP-1\", \"mode\": \"%s\", \"grid\": [0, 0], \"size_mm\": [16, 9]}",
                 *m);
        char want[256];
        snprintf(want, sizeof want, "field 'outputs[0].mode': expected \"WIDTHxHEIGHT\", \"WIDTHxHEIGHT@HZ\" "
                                    "(1..32767 pixels, refresh in (0, 1000] Hz) or \"preferred\", got \"%s\"", *m);
        expect_output_failure(o, want);
    }
}

Test(wall_config, bezel_and_size_ranges)
{
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0], \"size_mm\": [10, 10], "
                          "\"bezel_mm\": {\"left\": -3}}",
                          "wall.json: field 'outputs[0].bezel_mm.left': must be in [0, 1e+06], got -3");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0], \"size_mm\": [10, 0]}",
                          "field 'outputs[0].size_mm[1]': must be in [0.1, 1e+06], got 0");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0], \"size_mm\": [2e6, 10]}",
                          "field 'outputs[0].size_mm[0]': must be in [0.1, 1e+06], got 2e+06");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0], \"size_mm\": [10, 10], "
                          "\"bezel_mm\": {\"top\": 1e7}}",
                          "field 'outputs[0].bezel_mm.top': must be in [0, 1e+06], got 1e+07");
    expect_output_failure("{\"connector\": \"DP-1\", \"position_mm\": [0, -3e6], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].position_mm[1]': must be in [-1e+06, 1e+06], got -3e+06");
    /* found by fuzz_wall_config: 5.6e18 px down made a 339 mm tall output 0 mm tall */
    expect_output_failure("{\"connector\": \"HDMI-A-1\", \"mode\": \"2560x1440@59.95\", "
                          "\"position_px\": [0, 5555555555555555550], \"size_mm\": [597, 339]}",
                          "field 'outputs[0].position_px[1]': 5.55556e+18 px at this output's 0.235417 mm pixels "
                          "is 1.30787e+18 mm from the origin; a wall spans at most 1e+06 mm");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0]}",
                          "field 'outputs[0].size_mm': required field is missing");
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0], \"size_mm\": [10, 10], "
                          "\"bezel_mm\": {\"middle\": 1}}",
                          "field 'outputs[0].bezel_mm.middle': unknown field (expected one of: left, top, right, "
                          "bottom)");
}

Test(wall_config, connector_and_edid_fields)
{
    expect_output_failure("{\"grid\": [0, 0], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].connector': required field is missing");
    expect_output_failure("{\"connector\": \"HDMI\", \"grid\": [0, 0], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].connector': expected a DRM connector name TYPE-INDEX such as HDMI-A-1 "
                          "or DP-2, got 'HDMI'");
    expect_output_failure("{\"connector\": \"Virtual-1234567890123456789012345\", \"grid\": [0, 0], "
                          "\"size_mm\": [10, 10]}",
                          "field 'outputs[0].connector': at most 31 characters, got 33");
    expect_output_failure("{\"connector\": \"DP-1\", \"edid\": {}, \"grid\": [0, 0], \"size_mm\": [10, 10]}",
                          "field 'outputs[0].edid': give at least one of manufacturer, model and serial");
    expect_output_failure("{\"connector\": \"DP-1\", \"edid\": {\"manufacturer\": \"Dell\"}, \"grid\": [0, 0], "
                          "\"size_mm\": [10, 10]}",
                          "field 'outputs[0].edid.manufacturer': expected the 3-letter EDID manufacturer id in "
                          "capitals such as \"DEL\", got \"Dell\"");
    expect_output_failure("{\"connector\": \"DP-1\", \"edid\": {\"vendor\": \"DEL\"}, \"grid\": [0, 0], "
                          "\"size_mm\": [10, 10]}",
                          "field 'outputs[0].edid.vendor': unknown field");
}

Test(wall_config, unknown_field)
{
    expect_output_failure("{\"connector\": \"DP-1\", \"grid\": [0, 0], \"size_mm\": [10, 10], \"scale\": 2}",
                          "wall.json: field 'outputs[0].scale': unknown field (expected one of: connector, edid, "
                          "mode, rotation, grid, position_mm, position_px, size_mm, bezel_mm)");
    expect_failure("{" HEADER "\"name\": \"x\", \"outputs\": [" OUT(1, "\"grid\": [0, 0]") "]}",
                   "wall.json: field 'name': unknown field (expected one of: format, version, units, outputs, nodes)");
}

Test(wall_config, header_fields)
{
    expect_failure("{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"inch\", \"outputs\": []}",
                   "wall.json: field 'units': expected \"mm\" (sizes and positions are millimetres), got \"inch\"");
    expect_failure("{\"format\": \"tessera-wall\", \"version\": 1, \"outputs\": []}",
                   "wall.json: field 'units': required field is missing");
    expect_failure("{\"format\": \"tessera-camera-path\", \"version\": 1}",
                   "wall.json: field 'format': expected \"tessera-wall\", got \"tessera-camera-path\"");
    expect_failure("{\"version\": 1}", "field 'format': required field is missing (a wall file has");
    expect_failure("{\"format\": \"tessera-wall\", \"version\": 2, \"units\": \"mm\", \"outputs\": []}",
                   "field 'version': unsupported version 2 (this build reads version 1)");
    expect_failure("[]", "wall.json: expected a JSON object at the top level, got array");
}

Test(wall_config, output_count)
{
    expect_failure("{" HEADER "\"outputs\": []}", "wall.json: field 'outputs': needs at least 1 output");
    char text[8192];
    size_t used = (size_t)snprintf(text, sizeof text, "{" HEADER "\"outputs\": [");
    for (int i = 0; i < WALL_MAX_OUTPUTS + 1; i++)
        used += (size_t)snprintf(text + used, sizeof text - used,
                                 "%s{\"connector\": \"DP-%d\", \"grid\": [%d, 0], \"size_mm\": [10, 10]}",
                                 i ? "," : "", i + 1, i);
    snprintf(text + used, sizeof text - used, "]}");
    expect_failure(text, "field 'outputs': has 17 outputs, at most 16 are supported");
}

Test(wall_config, syntax_error_has_line_and_column)
{
    expect_failure("{\n  \"format\": \"tessera-wall\",\n  \"version\": 1\n  \"units\": \"mm\"\n}",
                   "wall.json:4:3: JSON syntax error");
    expect_failure("{" HEADER "\"outputs\": [],\n \"units\": \"mm\"}", "wall.json:2:2: duplicate key 'units'");
}

/* ---- files ----------------------------------------------------------------------- */

Test(wall_config, load_from_a_file_and_missing_file)
{
    char dir[64], path[128];
    support_make_tmp_dir(dir, sizeof dir, "wall-config");
    support_write_file(dir, "w.json", "// a comment\n{" HEADER "\"outputs\": [" OUT(1, "\"grid\": [0, 0]") "]}\n");
    snprintf(path, sizeof path, "%s/w.json", dir);
    wall_config w;
    tess_error err = {{0}};
    cr_expect(wall_config_load(path, &w, &err), "%s", err.msg);
    cr_expect_eq(w.count, 1);
    unlink(path);
    rmdir(dir);
    err = (tess_error){{0}};
    cr_expect_not(wall_config_load(path, &w, &err));
    cr_expect(strstr(err.msg, "w.json: cannot open"), "%s", err.msg);
}

/* ---- device matching ------------------------------------------------------------- */

static const wall_device_mode modes_1080[] = {{1920, 1080, 60.0}, {1920, 1080, 50.0}, {1280, 720, 60.0}};
static const wall_device_mode modes_1440[] = {{1920, 1080, 60.0}, {2560, 1440, 59.951}, {2560, 1440, 144.0}};

/* HDMI-A-1: a Dell (serial AAA) offering 1080 modes, preferred 0; DP-1: a Dell
 * (serial BBB) offering 1440 modes, none marked preferred; DP-2: nothing connected. */
static void card(wall_device_connector conns[3])
{
    conns[0] = (wall_device_connector){"HDMI-A-1", true, "DEL", "U2415", "AAA", modes_1080, 3, 0, -1};
    conns[1] = (wall_device_connector){"DP-1", true, "DEL", "U2415", "BBB", modes_1440, 3, -1, -1};
    conns[2] = (wall_device_connector){"DP-2", false, NULL, NULL, NULL, NULL, 0, -1, -1};
}

static wall_config one_output(const char *connector, const char *edid, const char *mode)
{
    char text[1024];
    snprintf(text, sizeof text,
             "{" HEADER "\"outputs\": [{\"connector\": \"%s\", %s \"mode\": \"%s\", \"position_mm\": [0, 0], "
             "\"size_mm\": [160, 90]}]}",
             connector, edid, mode);
    return parse_ok(text);
}

static void expect_match(wall_config *w, int conn, int mode, int width_px, int height_px)
{
    wall_device_connector conns[3];
    tess_error err = {{0}};
    card(conns);
    cr_assert(wall_config_match_device(w, conns, 3, &err), "%s", err.msg);
    cr_expect_eq(w->outputs[0].device_connector, conn);
    cr_expect_eq(w->outputs[0].device_mode, mode);
    cr_expect_eq(w->outputs[0].width_px, width_px);
    cr_expect_eq(w->outputs[0].height_px, height_px);
}

static void expect_no_match(wall_config *w, const char *want)
{
    wall_device_connector conns[3];
    tess_error err = {{0}};
    card(conns);
    cr_assert_not(wall_config_match_device(w, conns, 3, &err), "matched");
    cr_expect(strstr(err.msg, want), "\n  got:  %s\n  want: %s", err.msg, want);
    cr_expect_eq(w->outputs[0].device_connector, -1);
    cr_expect_eq(w->outputs[0].width_px, 0);
}

Test(wall_config, match_by_name_and_explicit_mode)
{
    wall_config w = one_output("HDMI-A-1", "", "1920x1080@50");
    expect_match(&w, 0, 1, 1920, 1080);
    w = one_output("HDMI-A-1", "", "1920x1080"); /* any refresh: the preferred one fits */
    expect_match(&w, 0, 0, 1920, 1080);
    w = one_output("DP-1", "", "2560x1440@60"); /* 59.951 is within 0.5 Hz */
    expect_match(&w, 1, 1, 2560, 1440);
    w = one_output("DP-1", "", "2560x1440"); /* none preferred: the highest refresh */
    expect_match(&w, 1, 2, 2560, 1440);
}

Test(wall_config, edid_wins_over_the_name)
{
    wall_config w = one_output("HDMI-A-1", "\"edid\": {\"manufacturer\": \"DEL\", \"serial\": \"BBB\"},", "preferred");
    expect_match(&w, 1, 2, 2560, 1440);
    w = one_output("HDMI-A-1", "\"edid\": {\"manufacturer\": \"DEL\"},", "preferred");
    expect_no_match(&w, "outputs[0]: EDID manufacturer DEL matches 2 connected monitors (HDMI-A-1, DP-1)");
    w = one_output("HDMI-A-1", "\"edid\": {\"serial\": \"CCC\"},", "preferred");
    expect_no_match(&w, "outputs[0]: no connected monitor has EDID serial CCC (the card has: HDMI-A-1 "
                        "(manufacturer DEL, model U2415, serial AAA), DP-1 (manufacturer DEL, model U2415, serial "
                        "BBB), DP-2 (not connected))");
}

Test(wall_config, preferred_mode_or_the_largest)
{
    wall_config w = one_output("HDMI-A-1", "", "preferred");
    expect_match(&w, 0, 0, 1920, 1080);
    w = one_output("DP-1", "", "preferred"); /* not marked: largest area, then refresh */
    expect_match(&w, 1, 2, 2560, 1440);
}

Test(wall_config, unknown_connector_lists_the_cards_connectors)
{
    wall_config w = one_output("HDMI-A-3", "", "preferred");
    expect_no_match(&w, "outputs[0]: connector 'HDMI-A-3' not found (the card has: HDMI-A-1, DP-1, DP-2)");
    w = one_output("DP-2", "", "preferred");
    expect_no_match(&w, "outputs[0]: connector 'DP-2' has no monitor connected");
}

Test(wall_config, mode_not_offered_lists_the_offered_modes)
{
    wall_config w = one_output("HDMI-A-1", "", "2560x1440@60");
    expect_no_match(&w, "outputs[0]: mode 2560x1440@60 not offered by HDMI-A-1 (it offers: 1920x1080@60, "
                        "1920x1080@50, 1280x720@60)");
    w = one_output("DP-1", "", "2560x1440@120");
    expect_no_match(&w, "mode 2560x1440@120 not offered by DP-1 (it offers: 1920x1080@60, 2560x1440@59.95, "
                        "2560x1440@144)");
}

Test(wall_config, two_outputs_on_one_connector)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": ["
                             "{\"connector\": \"HDMI-A-1\", \"grid\": [0, 0], \"size_mm\": [160, 90]},"
                             "{\"connector\": \"DP-1\", \"edid\": {\"serial\": \"AAA\"}, \"grid\": [1, 0], "
                             "\"size_mm\": [160, 90]}]}");
    wall_device_connector conns[3];
    tess_error err = {{0}};
    card(conns);
    cr_assert_not(wall_config_match_device(&w, conns, 3, &err));
    cr_expect(strstr(err.msg, "outputs[0] and outputs[1] both resolve to connector HDMI-A-1"), "%s", err.msg);
}

Test(wall_config, preferred_mode_with_the_wrong_aspect)
{
    wall_device_mode m[] = {{1920, 1200, 60.0}};
    wall_device_connector conn = {"DP-3", true, NULL, NULL, NULL, m, 1, 0, -1};
    wall_config w = one_output("DP-3", "", "preferred");
    tess_error err = {{0}};
    cr_assert_not(wall_config_match_device(&w, &conn, 1, &err));
    cr_expect(strstr(err.msg, "outputs[0]: the preferred mode of DP-3, 1920x1200@60 rotated 0 (1920 x 1200 px, "
                              "aspect 1.6000), does not fit size_mm 160 x 90"), "%s", err.msg);
}

Test(wall_config, long_mode_lists_are_cut)
{
    wall_device_mode m[64];
    for (int i = 0; i < 64; i++)
        m[i] = (wall_device_mode){1000 + i, 500 + i, 60.0};
    wall_device_connector conn = {"DP-3", true, NULL, NULL, NULL, m, 64, 0, -1};
    wall_config w = one_output("DP-3", "", "640x360");
    tess_error err = {{0}};
    cr_assert_not(wall_config_match_device(&w, &conn, 1, &err));
    cr_expect(strstr(err.msg, "(it offers: 1000x500@60, 1001x501@60, "), "%s", err.msg);
    cr_expect(strstr(err.msg, ", ...)"), "%s", err.msg);
}

/* ---- headless ------------------------------------------------------------------ */

Test(wall_config, headless_needs_explicit_modes)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": [" OUT(1, "\"grid\": [0, 0]") ","
                             "{\"connector\": \"Virtual-2\", \"grid\": [1, 0], \"size_mm\": [160, 90]}]}");
    tess_error err = {{0}};
    cr_assert_not(wall_config_headless_sizes(&w, &err));
    cr_expect_str_eq(err.msg, "outputs[1] (Virtual-2): mode 'preferred' needs a device; give an explicit mode "
                              "such as 1920x1080 for headless runs");
}

/* ---- nodes: a wall of several machines ---------------------------------------------- */

#define FOUR OUT(1, "\"grid\": [0, 0]") "," OUT(2, "\"grid\": [1, 0]") "," OUT(3, "\"grid\": [0, 1]") "," \
    OUT(4, "\"grid\": [1, 1]")

Test(wall_config, nodes_by_rank_and_by_host)
{
    wall_config w = parse_ok("{" HEADER "\"outputs\": [" FOUR "], \"nodes\": ["
                             "{\"rank\": 1, \"outputs\": [\"Virtual-2\", \"Virtual-4\"]},"
                             "{\"rank\": 0, \"outputs\": [\"Virtual-1\", \"Virtual-3\"]}]}");
    cr_assert_eq(w.node_count, 2);
    cr_assert(w.nodes[0].rank == 1 && w.nodes[0].outputs[1] && w.nodes[0].outputs[3] && !w.nodes[0].outputs[0]);
    cr_assert(w.nodes[1].rank == 0 && w.nodes[1].outputs[0] && w.nodes[1].outputs[2]);
    tess_error err = {{0}};
    const char *hosts[2] = {"a", "a"};
    cr_assert_eq(wall_config_node_of(&w, 0, 2, hosts, &err), 1);
    cr_assert_eq(wall_config_node_of(&w, 1, 2, hosts, &err), 0);
    cr_assert_eq(wall_config_node_of(&w, 0, 3, hosts, &err), -1);
    cr_assert(strstr(err.msg, "the wall has 2 nodes and 3 processes were started"), "%s", err.msg);
    /* by host: two nodes on one host take its ranks in file order */
    w = parse_ok("{" HEADER "\"outputs\": [" FOUR "], \"nodes\": ["
                 "{\"host\": \"left\", \"outputs\": [\"Virtual-1\"]},"
                 "{\"host\": \"right\", \"outputs\": [\"Virtual-2\", \"Virtual-4\"]},"
                 "{\"host\": \"left\", \"outputs\": [\"Virtual-3\"]}]}");
    const char *where[3] = {"right", "left", "left"};
    cr_assert_eq(wall_config_node_of(&w, 0, 3, where, &err), 1);
    cr_assert_eq(wall_config_node_of(&w, 1, 3, where, &err), 0);
    cr_assert_eq(wall_config_node_of(&w, 2, 3, where, &err), 2);
    const char *elsewhere[3] = {"right", "left", "middle"};
    err = (tess_error){{0}};
    cr_assert_eq(wall_config_node_of(&w, 2, 3, elsewhere, &err), -1);
    cr_assert(strstr(err.msg, "on host 'middle'"), "%s", err.msg);
    /* without nodes: none */
    w = parse_ok("{" HEADER "\"outputs\": [" FOUR "]}");
    cr_assert_eq(w.node_count, 0);
}

/* Every machine has its own Virtual-1: outputs of different nodes may share a
 * connector name, named in the nodes by index; files call them nodeK-NAME. */
Test(wall_config, nodes_may_share_connector_names)
{
#define SHARED OUT(1, "\"grid\": [0, 0]") "," OUT(2, "\"grid\": [1, 0]") "," OUT(1, "\"grid\": [0, 1]") "," \
    OUT(2, "\"grid\": [1, 1]")
    wall_config w = parse_ok("{" HEADER "\"outputs\": [" SHARED "], \"nodes\": ["
                             "{\"rank\": 0, \"outputs\": [0, 1]}, {\"rank\": 1, \"outputs\": [2, 3]}]}");
    cr_assert_eq(w.node_count, 2);
    cr_assert(w.nodes[1].outputs[2] && w.nodes[1].outputs[3] && !w.nodes[1].outputs[0]);
    char label[WALL_LABEL_BYTES];
    cr_expect_str_eq(wall_output_label(&w, 0, label, sizeof label), "node0-Virtual-1");
    cr_expect_str_eq(wall_output_label(&w, 3, label, sizeof label), "node1-Virtual-2");
    /* one machine's part, as it matches its card */
    wall_config mine;
    int index_of[WALL_MAX_OUTPUTS];
    cr_assert_eq(wall_config_subset(&w, w.nodes[1].outputs, &mine, index_of), 2);
    cr_expect(index_of[0] == 2 && index_of[1] == 3);
    cr_expect_str_eq(mine.outputs[1].connector, "Virtual-2");
    cr_expect(mine.outputs[1].x_mm == w.outputs[3].x_mm && mine.outputs[1].y_mm == w.outputs[3].y_mm);
    cr_expect(mine.width_mm == w.width_mm && mine.node_count == 0);
    /* a unique name still goes by itself; names and indices mix */
    w = parse_ok("{" HEADER "\"outputs\": [" FOUR "], \"nodes\": ["
                 "{\"rank\": 0, \"outputs\": [0, \"Virtual-2\"]}, {\"rank\": 1, \"outputs\": [\"Virtual-3\", 3]}]}");
    cr_expect_str_eq(wall_output_label(&w, 3, label, sizeof label), "Virtual-4");
    /* what cannot be: a shared name named, the same name twice on one machine, and without
     * nodes the same name twice at all */
    expect_failure("{" HEADER "\"outputs\": [" SHARED "], \"nodes\": ["
                   "{\"rank\": 0, \"outputs\": [\"Virtual-1\", 1]}, {\"rank\": 1, \"outputs\": [2, 3]}]}",
                   "field 'nodes[0].outputs[0]': 'Virtual-1' is the connector of outputs[0] and outputs[2]: name each "
                   "by its index");
    expect_failure("{" HEADER "\"outputs\": [" SHARED "], \"nodes\": ["
                   "{\"rank\": 0, \"outputs\": [0, 2]}, {\"rank\": 1, \"outputs\": [1, 3]}]}",
                   "field 'nodes[0].outputs[1]': outputs[0] and outputs[2] are both connector 'Virtual-1' of this node");
    expect_failure("{" HEADER "\"outputs\": [" SHARED "]}",
                   "field 'outputs[2].connector': 'Virtual-1' is also the connector of outputs[0]");
#undef SHARED
}

Test(wall_config, bad_nodes_are_named)
{
    static const struct {
        const char *nodes, *want;
    } cases[] = {
        {"5", "field 'nodes': expected an array"},
        {"[]", "field 'nodes': has 0 nodes: 1..4"},
        {"[{\"rank\": 0, \"host\": \"a\", \"outputs\": [\"Virtual-1\"]}]", "field 'nodes[0]': give exactly one of rank and host"},
        {"[{\"outputs\": [\"Virtual-1\"]}]", "field 'nodes[0]': give exactly one of rank and host"},
        {"[{\"rank\": 0.5, \"outputs\": [\"Virtual-1\"]}]", "field 'nodes[0].rank': must be a whole number"},
        {"[{\"rank\": 0}]", "field 'nodes[0].outputs': required field is missing"},
        {"[{\"rank\": 0, \"outputs\": []}]", "field 'nodes[0].outputs': a node drives at least 1 output"},
        {"[{\"rank\": 0, \"outputs\": [\"HDMI-A-9\"]}]", "field 'nodes[0].outputs[0]': 'HDMI-A-9' is not one of the wall's outputs"},
        {"[{\"rank\": 0, \"outputs\": [true]}]",
         "field 'nodes[0].outputs[0]': expected a connector name or an output index, got"},
        {"[{\"rank\": 0, \"outputs\": [4]}]", "field 'nodes[0].outputs[0]': output index 4: the wall's outputs are 0..3"},
        {"[{\"rank\": 0, \"outputs\": [-1]}]", "field 'nodes[0].outputs[0]': output index -1: the wall's outputs are 0..3"},
        {"[{\"rank\": 0, \"outputs\": [\"Virtual-1\", \"Virtual-2\", \"Virtual-3\"]},"
         " {\"rank\": 1, \"outputs\": [\"Virtual-3\", \"Virtual-4\"]}]",
         "field 'nodes[1].outputs[0]': output 2 (Virtual-3) is driven by another node already"},
        {"[{\"rank\": 0, \"outputs\": [0, 1, 2]}, {\"rank\": 1, \"outputs\": [\"Virtual-3\", 3]}]",
         "field 'nodes[1].outputs[0]': output 2 (Virtual-3) is driven by another node already"},
        {"[{\"rank\": 0, \"outputs\": [\"Virtual-1\", \"Virtual-2\"]}, {\"rank\": 0, \"outputs\": [\"Virtual-3\", \"Virtual-4\"]}]",
         "field 'nodes[1]': rank 0 is nodes[0]'s already"},
        {"[{\"rank\": 0, \"outputs\": [\"Virtual-1\", \"Virtual-2\"]}, {\"rank\": 2, \"outputs\": [\"Virtual-3\", \"Virtual-4\"]}]",
         "field 'nodes[1]': rank 2: with 2 nodes the ranks are 0..1"},
        {"[{\"rank\": 0, \"outputs\": [\"Virtual-1\", \"Virtual-2\"]}, {\"host\": \"b\", \"outputs\": [\"Virtual-3\", \"Virtual-4\"]}]",
         "field 'nodes': name every node by rank or every node by host"},
        {"[{\"rank\": 0, \"outputs\": [\"Virtual-1\", \"Virtual-2\", \"Virtual-3\"]}]",
         "field 'nodes': output 'Virtual-4' (outputs[3]) is in no node"},
        {"[{\"rank\": 0, \"outputs\": [\"Virtual-1\"], \"gpu\": 1}]", "field 'nodes[0].gpu': unknown field"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[4096];
        snprintf(text, sizeof text, "{" HEADER "\"outputs\": [" FOUR "], \"nodes\": %s}", cases[i].nodes);
        expect_failure(text, cases[i].want);
    }
}
