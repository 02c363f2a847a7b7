/* test_colormap.c - colour maps and transfer functions (engine/base/colormap.h):
 * the built-ins against published values, lightness order, interpolation,
 * clamping and the odd inputs (NaN, infinities, lo == hi), the baked table
 * against exact evaluation, and the JSON form with every error message. */
#include <criterion/criterion.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/base/colormap.h"
#include "engine/base/json_read.h"
#include "engine/base/srgb.h"

TestSuite(colormap);

/* ---- helpers ------------------------------------------------------------- */

/* sRGB code values (0..255) agree within this: the tables are 8-bit
 * roundings, so a published colour may be off by one code value */
#define SRGB_TOLERANCE_CODES 1.5

static colormap preset(const char *name)
{
    colormap cm;
    cr_assert(colormap_preset(name, &cm), "no built-in '%s'", name);
    return cm;
}

/* The colour at normalised position t must be the sRGB colour 0xRRGGBB. */
static void expect_srgb(const char *name, double t, uint32_t want)
{
    colormap cm = preset(name);
    colormap_rgba got = colormap_eval_unit(&cm, t);
    const float lin[3] = {got.r, got.g, got.b};
    for (int k = 0; k < 3; k++) {
        double code = srgb_curve_encode(lin[k]) * 255.0;
        double expect = (double)((want >> (16 - 8 * k)) & 0xffu);
        cr_assert(fabs(code - expect) <= SRGB_TOLERANCE_CODES, "%s at %g: channel %d is %.2f, want %.0f (#%06x)",
                  name, t, k, code, expect, want);
    }
}

/* CIE L* (D65) of a linear RGB colour, from its relative luminance. */
static double lightness(colormap_rgba c)
{
    double y = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    const double d = 6.0 / 29.0;
    double f = y > d * d * d ? cbrt(y) : y / (3.0 * d * d) + 4.0 / 29.0;
    return 116.0 * f - 16.0;
}

static bool same_rgba(colormap_rgba a, colormap_rgba b)
{
    return a.r == b.r && a.g == b.g && a.b == b.b && a.a == b.a;
}

static float max_diff(colormap_rgba a, colormap_rgba b)
{
    return fmaxf(fmaxf(fabsf(a.r - b.r), fabsf(a.g - b.g)), fmaxf(fabsf(a.b - b.b), fabsf(a.a - b.a)));
}

/* ---- built-ins -------------------------------------------------------------- */

Test(colormap, names_list_every_builtin_and_each_is_valid)
{
    const char *const want[] = {"viridis", "magma", "cool-warm", "greyscale", "ct-bone", "mri-soft"};
    const char *const *names = colormap_names();
    size_t n = 0;
    for (; names[n]; n++) {
        cr_assert(n < sizeof want / sizeof want[0], "more names than expected");
        cr_assert_str_eq(names[n], want[n]);
        colormap cm = preset(names[n]);
        tess_error err = {{0}};
        cr_assert(colormap_validate(&cm, &err), "%s: %s", names[n], err.msg);
        cr_assert_str_eq(cm.name, names[n]);
        cr_assert(cm.range_auto);
        cr_assert(cm.lo == 0.f && cm.hi == 1.f);
        cr_assert(cm.color_count >= 2 && cm.color_count <= 33);
    }
    cr_assert_eq(n, sizeof want / sizeof want[0]);

    colormap untouched = preset("magma"), copy = untouched;
    cr_assert_not(colormap_preset("jet", &untouched));
    cr_assert_not(colormap_preset(NULL, &untouched));
    cr_assert_not(colormap_preset("", &untouched));
    cr_assert(memcmp(&untouched, &copy, sizeof copy) == 0, "a failed lookup leaves *out as it was");
}

Test(colormap, published_values)
{
    /* matplotlib's viridis and magma tables (entries 0, 255, and the mean of
     * 127 and 128 for the middle); Moreland's cool-warm ends and middle */
    expect_srgb("viridis", 0.0, 0x440154);
    expect_srgb("viridis", 0.5, 0x21908c);
    expect_srgb("viridis", 1.0, 0xfde725);
    expect_srgb("magma", 0.0, 0x000004);
    expect_srgb("magma", 1.0, 0xfcfdbf);
    expect_srgb("cool-warm", 0.0, 0x3b4cc0);
    expect_srgb("cool-warm", 0.5, 0xdddddd);
    expect_srgb("cool-warm", 1.0, 0xb40426);
    expect_srgb("greyscale", 0.0, 0x000000);
    expect_srgb("greyscale", 0.5, 0x808080);
    expect_srgb("greyscale", 1.0, 0xffffff);
}

Test(colormap, lightness_rises_along_sequential_maps)
{
    const char *const names[] = {"viridis", "magma", "greyscale"};
    for (size_t m = 0; m < sizeof names / sizeof names[0]; m++) {
        colormap cm = preset(names[m]);
        double prev = -1.0;
        for (int i = 0; i <= 1000; i++) {
            double l = lightness(colormap_eval_unit(&cm, i / 1000.0));
            cr_assert(l > prev, "%s: L* %.3f at t=%.3f is not above %.3f", names[m], l, i / 1000.0, prev);
            prev = l;
        }
    }
}

Test(colormap, cool_warm_is_lightest_in_the_middle)
{
    colormap cm = preset("cool-warm");
    double mid = lightness(colormap_eval_unit(&cm, 0.5));
    double prev = lightness(colormap_eval_unit(&cm, 0.0));
    for (int i = 1; i <= 500; i++) { /* rises to the middle ... */
        double l = lightness(colormap_eval_unit(&cm, i / 1000.0));
        cr_assert(l > prev, "L* does not rise at t=%.3f", i / 1000.0);
        prev = l;
    }
    for (int i = 501; i <= 1000; i++) { /* ... and falls after it */
        double l = lightness(colormap_eval_unit(&cm, i / 1000.0));
        cr_assert(l < prev, "L* does not fall at t=%.3f", i / 1000.0);
        prev = l;
    }
    cr_assert(mid > 85.0, "the middle grey is light (L* %.1f)", mid);
}

Test(colormap, transfer_functions_have_opacity_ramps)
{
    colormap bone = preset("ct-bone"), soft = preset("mri-soft"), vir = preset("viridis");
    cr_assert(bone.opacity_count >= 2 && soft.opacity_count >= 2);
    cr_assert_eq(vir.opacity_count, 0);
    /* ct-bone, range [-1000, 2000] HU: water transparent, cortical bone nearly opaque */
    bone.lo = -1000.f;
    bone.hi = 2000.f;
    cr_assert_eq(colormap_eval(&bone, 0.f).a, 0.f);
    cr_assert_float_eq(colormap_eval(&bone, 1100.f).a, 0.8f, 1e-6f);
    cr_assert_float_eq(colormap_eval(&bone, 2000.f).a, 0.95f, 1e-6f);
    double prev = -1.0;
    for (int i = 0; i <= 100; i++) { /* opacity never falls along either ramp */
        double a = colormap_eval_unit(&soft, i / 100.0).a;
        cr_assert(a >= prev);
        prev = a;
        cr_assert(colormap_eval_unit(&bone, i / 100.0).a <= 1.f);
        cr_assert_eq(colormap_eval_unit(&vir, i / 100.0).a, 1.f, "a map without opacity points is opaque");
    }
}

/* ---- mapping --------------------------------------------------------------- */

/* Black at 0.25, linear grey 0.5 at 0.75 (sRGB would not be linear here). */
static colormap two_points(void)
{
    colormap cm;
    memset(&cm, 0, sizeof cm);
    cm.color_count = 2;
    cm.colors[0] = (colormap_color_point){0.25f, {0.f, 0.f, 0.f}};
    cm.colors[1] = (colormap_color_point){0.75f, {0.5f, 1.f, 0.25f}};
    cm.opacity_count = 3;
    cm.opacity[0] = (colormap_opacity_point){0.f, 0.f};
    cm.opacity[1] = (colormap_opacity_point){0.5f, 1.f};
    cm.opacity[2] = (colormap_opacity_point){1.f, 0.f};
    cm.lo = 10.f;
    cm.hi = 20.f;
    return cm;
}

Test(colormap, piecewise_linear_in_linear_rgb)
{
    colormap cm = two_points();
    tess_error err = {{0}};
    cr_assert(colormap_validate(&cm, &err), "%s", err.msg);
    colormap_rgba mid = colormap_eval(&cm, 15.f); /* t 0.5: half way between the colours */
    cr_assert_float_eq(mid.r, 0.25f, 1e-6f);
    cr_assert_float_eq(mid.g, 0.5f, 1e-6f);
    cr_assert_float_eq(mid.b, 0.125f, 1e-6f);
    cr_assert_float_eq(mid.a, 1.f, 1e-6f);
    colormap_rgba q = colormap_eval(&cm, 16.25f); /* t 0.625: colour 3/4 of the way, opacity 1/4 down */
    cr_assert_float_eq(q.r, 0.375f, 1e-6f);
    cr_assert_float_eq(q.a, 0.75f, 1e-6f);
    /* before the first colour point and after the last the end colours hold */
    cr_assert(same_rgba(colormap_eval_unit(&cm, 0.1), (colormap_rgba){0.f, 0.f, 0.f, 0.2f}));
    colormap_rgba end = colormap_eval_unit(&cm, 0.9);
    cr_assert(end.r == 0.5f && end.g == 1.f && end.b == 0.25f);
    cr_assert_float_eq(end.a, 0.2f, 1e-6f);
}

Test(colormap, clamping_nan_infinities_and_an_empty_range)
{
    colormap cm = preset("viridis");
    cm.lo = -2.f;
    cm.hi = 3.f;
    colormap_rgba first = colormap_eval_unit(&cm, 0.0), last = colormap_eval_unit(&cm, 1.0);
    cr_assert(same_rgba(colormap_eval(&cm, -100.f), first));
    cr_assert(same_rgba(colormap_eval(&cm, 1e30f), last));
    cr_assert(same_rgba(colormap_eval(&cm, NAN), first), "NaN gives the first colour");
    cr_assert(same_rgba(colormap_eval(&cm, -INFINITY), first));
    cr_assert(same_rgba(colormap_eval(&cm, INFINITY), last));
    cr_assert(same_rgba(colormap_eval_unit(&cm, NAN), first));

    cm.lo = cm.hi = 4.f; /* lo == hi: everything is the first colour, no division by zero */
    const float values[] = {4.f, 3.f, 5.f, NAN, INFINITY, -INFINITY, FLT_MAX};
    colormap_table table;
    colormap_bake(&cm, &table);
    for (size_t i = 0; i < sizeof values / sizeof values[0]; i++) {
        cr_assert(same_rgba(colormap_eval(&cm, values[i]), first), "value %g", values[i]);
        cr_assert(same_rgba(colormap_lookup(&table, values[i]), first), "value %g (table)", values[i]);
    }

    /* the widest float range: nothing overflows */
    cm.lo = -FLT_MAX;
    cm.hi = FLT_MAX;
    colormap_bake(&cm, &table);
    cr_assert(same_rgba(colormap_lookup(&table, FLT_MAX), last));
    cr_assert(same_rgba(colormap_lookup(&table, -FLT_MAX), first));
    cr_assert_lt(max_diff(colormap_lookup(&table, 0.f), colormap_eval(&cm, 0.f)), COLORMAP_TABLE_TOLERANCE);
}

Test(colormap, fit_range_only_when_automatic)
{
    colormap cm = preset("magma");
    colormap_fit_range(&cm, -5.f, 7.f);
    cr_assert(cm.lo == -5.f && cm.hi == 7.f);
    colormap_fit_range(&cm, NAN, 1.f); /* ignored */
    colormap_fit_range(&cm, 3.f, 1.f); /* ignored */
    cr_assert(cm.lo == -5.f && cm.hi == 7.f);
    cm.range_auto = false;
    colormap_fit_range(&cm, 0.f, 1.f);
    cr_assert(cm.lo == -5.f && cm.hi == 7.f, "a fixed range stays");
}

Test(colormap, baked_table_within_tolerance_of_exact)
{
    for (const char *const *name = colormap_names(); *name; name++) {
        colormap cm = preset(*name);
        cm.lo = -3.f;
        cm.hi = 7.f;
        colormap_table table;
        colormap_bake(&cm, &table);
        float worst = 0.f;
        for (int i = 0; i <= 200000; i++) { /* past both ends too */
            float v = -4.f + 12.f * (float)i / 200000.f;
            worst = fmaxf(worst, max_diff(colormap_lookup(&table, v), colormap_eval(&cm, v)));
        }
        cr_assert(worst <= colormap_table_error(&cm), "%s: table off by %g, bound %g", *name, worst,
                  colormap_table_error(&cm));
        cr_assert(colormap_table_error(&cm) <= COLORMAP_TABLE_TOLERANCE, "%s: bound %g", *name,
                  colormap_table_error(&cm));
        cr_log_info("%s: table off by at most %.5f (bound %.5f)", *name, worst, colormap_table_error(&cm));
        cr_assert(same_rgba(colormap_lookup(&table, NAN), colormap_eval(&cm, NAN)));
        cr_assert(same_rgba(colormap_lookup(&table, -3.f), colormap_eval_unit(&cm, 0.0)), "entry 0 is exact");
        cr_assert(same_rgba(colormap_lookup(&table, 7.f), colormap_eval_unit(&cm, 1.0)), "the last entry is exact");
    }
}

Test(colormap, table_error_bound_holds_for_a_steep_custom_map)
{
    colormap cm = two_points(); /* black to white within 1/2000 of the range */
    cm.colors[0].pos = 0.5f;
    cm.colors[1].pos = 0.5005f;
    cm.colors[1] = (colormap_color_point){0.5005f, {1.f, 1.f, 1.f}};
    colormap_table table;
    colormap_bake(&cm, &table);
    float bound = colormap_table_error(&cm), worst = 0.f;
    for (int i = 0; i <= 100000; i++) {
        float v = 10.f + 10.f * (float)i / 100000.f;
        worst = fmaxf(worst, max_diff(colormap_lookup(&table, v), colormap_eval(&cm, v)));
    }
    cr_assert(worst <= bound, "off by %g, bound %g", worst, bound);
    cr_assert(worst > 0.1f, "a step narrower than an entry is not representable (off by %g)", worst);
}

Test(colormap, validate_messages)
{
    colormap cm = two_points();
    tess_error err = {{0}};
    cm.color_count = 1;
    cr_assert_not(colormap_validate(&cm, &err));
    cr_assert_str_eq(err.msg, "colour map: 1 colour points (expected 2 to 64)");

    cm = two_points();
    err.msg[0] = '\0';
    cm.opacity_count = 1;
    cr_assert_not(colormap_validate(&cm, &err));
    cr_assert_str_eq(err.msg, "colour map: 1 opacity points (expected none or 2 to 64)");

    cm = two_points();
    err.msg[0] = '\0';
    cm.colors[1].pos = 0.25f;
    cr_assert_not(colormap_validate(&cm, &err));
    cr_assert_str_eq(err.msg, "colour map: colour point 1: position 0.25 is not greater than the previous point's (0.25)");

    cm = two_points();
    err.msg[0] = '\0';
    cm.colors[0].rgb[1] = 1.5f;
    cr_assert_not(colormap_validate(&cm, &err));
    cr_assert_str_eq(err.msg, "colour map: colour point 0: position and channels must be in [0, 1]");

    cm = two_points();
    err.msg[0] = '\0';
    cm.opacity[2].opacity = NAN;
    cr_assert_not(colormap_validate(&cm, &err));
    cr_assert_str_eq(err.msg, "colour map: opacity point 2: position and opacity must be in [0, 1]");

    cm = two_points();
    err.msg[0] = '\0';
    cm.opacity[1].pos = 0.f;
    cr_assert_not(colormap_validate(&cm, &err));
    cr_assert_str_eq(err.msg, "colour map: opacity point 1: position 0 is not greater than the previous point's (0)");

    cm = two_points();
    err.msg[0] = '\0';
    cm.lo = 30.f;
    cr_assert_not(colormap_validate(&cm, &err));
    cr_assert_str_eq(err.msg, "colour map: range [30, 20] must be finite with lo <= hi");
}

/* ---- JSON ------------------------------------------------------------------- */

/* Read `text` as the colour map of particles[0] in scene.json. */
static bool from_json(const char *text, colormap *out, tess_error *err)
{
    json_object *root = NULL;
    cr_assert(jr_parse("scene.json", text, strlen(text), &root, err), "bad test JSON: %s", err->msg);
    jr_ctx c = {.path = "scene.json", .err = err};
    jr_field_key(&c, "particles");
    jr_field_index(&c, 0);
    jr_field_key(&c, "color_map");
    bool ok = colormap_from_json(root, &c, out);
    cr_assert_str_eq(c.field, "particles[0].color_map", "the field path is given back");
    json_object_put(root);
    return ok;
}

static colormap accept(const char *text)
{
    colormap cm;
    tess_error err = {{0}};
    cr_assert(from_json(text, &cm, &err), "refused %s: %s", text, err.msg);
    cr_assert(colormap_validate(&cm, &err), "%s", err.msg);
    return cm;
}

/* Reading `text` must fail with exactly "scene.json: field 'particles[0].color_map`
 * followed by `want`, and leave *out alone. */
static void expect_error(const char *text, const char *want)
{
    colormap cm = preset("greyscale"), before = cm;
    tess_error err = {{0}};
    cr_assert_not(from_json(text, &cm, &err), "accepted: %s", text);
    char full[TESS_ERROR_MSG_BYTES];
    snprintf(full, sizeof full, "scene.json: field 'particles[0].color_map%s", want);
    cr_assert_str_eq(err.msg, full, "for %s", text);
    cr_assert(memcmp(&cm, &before, sizeof cm) == 0, "a failed read leaves *out alone");
}

Test(colormap, json_forms)
{
    colormap ref = preset("viridis");
    colormap cm = accept("\"viridis\"");
    cr_assert(memcmp(&cm, &ref, sizeof cm) == 0, "a name is the built-in with an automatic range");

    cm = accept("{\"map\": \"cool-warm\", \"range\": [-2.5, 4]}");
    cr_assert_str_eq(cm.name, "cool-warm");
    cr_assert_not(cm.range_auto);
    cr_assert(cm.lo == -2.5f && cm.hi == 4.f);

    cm = accept("{\"map\": \"magma\", \"range\": [1, 1]}"); /* lo == hi is allowed */
    cr_assert(cm.lo == 1.f && cm.hi == 1.f);

    cm = accept("{\"map\": \"magma\", \"range\": \"auto\"}");
    cr_assert(cm.range_auto);

    /* colours in JSON are sRGB code values: 0.5 is linear 0.214 */
    cm = accept("{\"colors\": [[0, 0, 0, 0], [0.5, 0.5, 0.5, 0.5], [1, 1, 0, 1]],"
                " \"opacity\": [[0, 0], [1, 0.75]], \"range\": \"auto\"}");
    cr_assert_str_eq(cm.name, "");
    cr_assert(cm.range_auto);
    cr_assert_eq(cm.color_count, 3);
    cr_assert_eq(cm.opacity_count, 2);
    cr_assert_float_eq(cm.colors[1].rgb[0], (float)srgb_curve_decode(0.5), 1e-6f);
    cr_assert(cm.colors[2].rgb[0] == 1.f && cm.colors[2].rgb[1] == 0.f && cm.colors[2].rgb[2] == 1.f);
    colormap_rgba mid = colormap_eval_unit(&cm, 0.5);
    cr_assert_float_eq(mid.g, 0.2140411f, 1e-6f);
    cr_assert_float_eq(mid.a, 0.375f, 1e-6f);

    /* opacity with a built-in replaces its opacity (none for viridis) */
    cm = accept("{\"map\": \"viridis\", \"opacity\": [[0.2, 0], [0.8, 1]]}");
    cr_assert_eq(cm.opacity_count, 2);
    cr_assert_float_eq(colormap_eval_unit(&cm, 0.5).a, 0.5f, 1e-6f);
    cm = accept("{\"map\": \"ct-bone\", \"opacity\": [[0, 1], [1, 1]]}");
    cr_assert_eq(colormap_eval_unit(&cm, 0.0).a, 1.f);
}

Test(colormap, json_type_and_name_errors)
{
    expect_error("3", "': expected a colour map name or an object, got number");
    expect_error("[\"viridis\"]", "': expected a colour map name or an object, got array");
    expect_error("\"jet\"",
                 "': unknown colour map 'jet' (known: viridis, magma, cool-warm, greyscale, ct-bone, mri-soft)");
    expect_error("{\"map\": \"Viridis\"}",
                 ".map': unknown colour map 'Viridis' (known: viridis, magma, cool-warm, greyscale, ct-bone, mri-soft)");
    expect_error("{\"map\": 4}", ".map': expected a string, got number");
    expect_error("{\"map\": \"viridis\", \"colour\": 1}",
                 ".colour': unknown field (expected one of: map, colors, opacity, range)");
    expect_error("{\"map\": \"viridis\", \"colors\": [[0, 0, 0, 0], [1, 1, 1, 1]]}",
                 "': give either 'map' (a built-in) or 'colors', not both");
    expect_error("{\"range\": [0, 1]}",
                 "': give 'map' (a built-in: viridis, magma, cool-warm, greyscale, ct-bone, mri-soft) or 'colors'");
}

Test(colormap, json_point_errors)
{
    expect_error("{\"colors\": [[0, 0, 0, 0]]}", ".colors': expected 2 to 64 points, got 1");
    expect_error("{\"colors\": []}", ".colors': expected 2 to 64 points, got 0");
    expect_error("{\"colors\": {\"a\": 1}}", ".colors': expected an array, got object");
    expect_error("{\"colors\": [[0, 0, 0, 0], [1, 1, 1]]}", ".colors[1]': expected [position, r, g, b], got 3 numbers");
    expect_error("{\"colors\": [[0, 0, 0, 0], 1]}", ".colors[1]': expected [position, r, g, b], got number");
    expect_error("{\"colors\": [[0, 0, 0, 0], [1.5, 1, 1, 1]]}", ".colors[1][0]': must be in [0, 1], got 1.5");
    expect_error("{\"colors\": [[-0.1, 0, 0, 0], [1, 1, 1, 1]]}", ".colors[0][0]': must be in [0, 1], got -0.1");
    expect_error("{\"colors\": [[0, 0, 0, 0], [0.5, 1, 1, 1], [0.9, 0.3, 2, 0]]}",
                 ".colors[2][2]': must be in [0, 1], got 2");
    expect_error("{\"colors\": [[0, 0, 0, 0], [0.5, 1, 1, 1], [0.3, 0, 0, 0]]}",
                 ".colors[2][0]': position 0.3 is not greater than the previous point's (0.5)");
    expect_error("{\"colors\": [[0, 0, 0, 0], [0, 1, 1, 1]]}",
                 ".colors[1][0]': position 0 is not greater than the previous point's (0)");
    expect_error("{\"colors\": [[0, 0, 0, 0], [1, \"1\", 1, 1]]}", ".colors[1][1]': expected a number, got string");
    expect_error("{\"map\": \"viridis\", \"opacity\": [[0, 0], [1, -0.5]]}",
                 ".opacity[1][1]': must be in [0, 1], got -0.5");
    expect_error("{\"map\": \"viridis\", \"opacity\": [[0, 0, 1], [1, 1]]}",
                 ".opacity[0]': expected [position, opacity], got 3 numbers");
    expect_error("{\"map\": \"viridis\", \"opacity\": [[0.5, 0], [0.5, 1]]}",
                 ".opacity[1][0]': position 0.5 is not greater than the previous point's (0.5)");
    expect_error("{\"map\": \"viridis\", \"opacity\": [[0.5, 0]]}", ".opacity': expected 2 to 64 points, got 1");

    /* 64 points are fine, 65 are not */
    char text[8192];
    for (int n = 64; n <= 65; n++) {
        size_t used = (size_t)snprintf(text, sizeof text, "{\"colors\": [");
        for (int i = 0; i < n; i++)
            used += (size_t)snprintf(text + used, sizeof text - used, "%s[%.6f, 0.5, 0.5, 0.5]", i ? ", " : "",
                                     (double)i / (n - 1));
        snprintf(text + used, sizeof text - used, "]}");
        if (n == 64)
            cr_assert_eq(accept(text).color_count, 64);
        else
            expect_error(text, ".colors': expected 2 to 64 points, got 65");
    }
}

Test(colormap, json_range_errors)
{
    expect_error("{\"map\": \"viridis\", \"range\": [5, 1]}", ".range': lo 5 is greater than hi 1");
    expect_error("{\"map\": \"viridis\", \"range\": [NaN, 1]}", ".range[0]': expected a finite number, got nan");
    expect_error("{\"map\": \"viridis\", \"range\": [0, Infinity]}", ".range[1]': expected a finite number, got inf");
    expect_error("{\"map\": \"viridis\", \"range\": [0, 1e39]}", ".range[1]': 1e+39 is out of range for a float");
    expect_error("{\"map\": \"viridis\", \"range\": [0]}", ".range': expected an array of 2 numbers, got 1 element");
    expect_error("{\"map\": \"viridis\", \"range\": \"automatic\"}",
                 ".range': expected [lo, hi] or \"auto\", got \"automatic\"");
    expect_error("{\"map\": \"viridis\", \"range\": null}", ".range': expected [lo, hi] or \"auto\", got null");
}
