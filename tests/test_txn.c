/* test_txn.c - transaction records (engine/frame/txn.h): every kind validates,
 * applies to a frame state, and survives the text and binary round trips bit
 * for bit; bad values are refused with the field named; the binary layout is
 * the documented one. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine/scene/frame_state.h"
#include "engine/render/render.h"
#include "engine/frame/txn.h"

#define GEOMS 10u

static camera_desc cam(float x)
{
    return (camera_desc){v3(x, 1.f / 3.f, -7.5f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 1e-20f), 39.99999f};
}

/* One valid record of every kind, with awkward values (floats with every mantissa bit used). */
static txn_record sample(txn_kind k)
{
    camera_desc c = cam(0.1f);
    const float rgb[3] = {0.1f, 2.5f, 3.4028235e38f};
    switch (k) {
    case TXN_CAMERA: return txn_camera(1, &c);
    case TXN_CURSOR: return txn_cursor(true, -0.3f, 1e-7f);
    case TXN_STATUS: return txn_status("picked 'a \"q\" \\ b' \x01\xe9");
    case TXN_HIDE: return txn_geoms_record(TXN_HIDE, 2, 3);
    case TXN_SHOW_ALL: return txn_simple(TXN_SHOW_ALL);
    case TXN_TOUR: return txn_flag(TXN_TOUR, true);
    case TXN_QUIT: return txn_simple(TXN_QUIT);
    case TXN_GOVERNOR_STATUS: return txn_flag(TXN_GOVERNOR_STATUS, true);
    case TXN_SHOW: return txn_geoms_record(TXN_SHOW, 3, 1);
    case TXN_ISOLATE: return txn_geoms_record(TXN_ISOLATE, 4, 2);
    case TXN_HIGHLIGHT: return txn_highlight(5, 5, true);
    case TXN_COLOUR: return txn_colour(0, GEOMS, rgb);
    case TXN_SHADOWS: return txn_flag(TXN_SHADOWS, false);
    case TXN_RENDERER: return txn_renderer("eyelight");
    case TXN_THREADS: return txn_threads(7);
    case TXN_CHANNEL_ACTIVE: return txn_channel_active(1, false);
    case TXN_MOVE: {
        const float m[12] = {0.f, -1.f, 0.f, 0.1f, 1.f, 0.f, 0.f, 1e-7f, 0.f, 0.f, 3.f, -3.4028235e38f};
        return txn_move(6, 3, m);
    }
    case TXN_OPACITY: return txn_opacity(1, 3, 0.3f);
    case TXN_CLIP_PLANE: {
        const float point[3] = {0.1f, -3.4028235e38f, 1e-7f}, normal[3] = {0.f, 3.f, -4.f};
        return txn_clip_plane(3, true, point, normal);
    }
    case TXN_CROP: return txn_crop(2, 3, true, -3.4028235e38f, 0.1f);
    case TXN_TIME_STEP: return txn_time_step(4294967295u);
    case TXN_VALUE: return txn_value(1, 2, -1e-7f);
    case TXN_COLORMAP: return txn_colormap(0, GEOMS, "cool-warm");
    case TXN_TRANSFER: return txn_transfer("ct-bone");
    case TXN_POINTER: return txn_pointer(7, true, -3.4028235e38f, 1e-7f);
    case TXN_KIND_COUNT: break;
    }
    cr_assert_fail("no sample for kind %d", (int)k);
    return txn_simple(TXN_QUIT);
}

static frame_state make_state(void)
{
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), true, 2, GEOMS);
    camera_desc c = cam(5.f);
    cr_assert_eq(frame_state_add_channel(&st, &c), 0);
    cr_assert_eq(frame_state_add_channel(&st, &c), 1);
    return st;
}

Test(txn, every_kind_has_a_name_that_reads_back)
{
    for (int k = 0; k < TXN_KIND_COUNT; k++) {
        txn_kind back;
        cr_assert(txn_kind_from_name(txn_kind_name((txn_kind)k), TXN_TEXT_V2, &back), "kind %d", k);
        cr_expect_eq(back, (txn_kind)k);
    }
    txn_kind back;
    cr_expect(txn_kind_from_name("unhide-all", TXN_TEXT_V1, &back) && back == TXN_SHOW_ALL);
    cr_expect_not(txn_kind_from_name("unhide-all", TXN_TEXT_V2, &back));
    cr_expect_not(txn_kind_from_name("isolate", TXN_TEXT_V1, &back));
    cr_expect_str_eq(txn_kind_name(TXN_KIND_COUNT), "?");
}

Test(txn, every_kind_round_trips_as_text_and_binary_bit_for_bit)
{
    for (int k = 0; k < TXN_KIND_COUNT; k++) {
        txn_record r = sample((txn_kind)k);
        tess_error err = {{0}};
        cr_assert(txn_validate(&r, &err), "%s: %s", txn_kind_name(r.kind), err.msg);
        char text[TXN_TEXT_MAX];
        size_t n = txn_encode_text(&r, text, sizeof text);
        cr_assert(n > 0 && n == strlen(text), "%s", txn_kind_name(r.kind));
        txn_record back;
        cr_assert(txn_decode_text(text, n, TXN_TEXT_V2, &back, &err), "'%s': %s", text, err.msg);
        cr_expect(memcmp(&r, &back, sizeof r) == 0, "text '%s' did not read back bit for bit", text);
        unsigned char bin[TXN_BINARY_BYTES];
        cr_assert(txn_encode_binary(&r, bin), "%s", txn_kind_name(r.kind));
        txn_record back2;
        cr_assert(txn_decode_binary(bin, &back2, &err), "%s: %s", txn_kind_name(r.kind), err.msg);
        cr_expect(memcmp(&r, &back2, sizeof r) == 0, "%s: binary did not read back bit for bit",
                  txn_kind_name(r.kind));
    }
}

Test(txn, text_forms_are_the_documented_ones)
{
    static const struct {
        txn_kind kind;
        const char *text;
    } want[] = {
        {TXN_STATUS, "status \"picked 'a \\\"q\\\" \\\\ b' \\x01\\xe9\""},
        {TXN_HIDE, "hide 2 3"},
        {TXN_SHOW_ALL, "show-all"},
        {TXN_ISOLATE, "isolate 4 2"},
        {TXN_HIGHLIGHT, "highlight 5 5 1"},
        {TXN_SHADOWS, "shadows 0"},
        {TXN_RENDERER, "renderer eyelight"},
        {TXN_THREADS, "threads 7"},
        {TXN_CHANNEL_ACTIVE, "channel-active 1 0"},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        txn_record r = sample(want[i].kind);
        char text[TXN_TEXT_MAX];
        cr_assert(txn_encode_text(&r, text, sizeof text) > 0);
        cr_expect_str_eq(text, want[i].text);
    }
    char text[TXN_TEXT_MAX];
    txn_record r = txn_cursor(true, 0.5f, -2.f);
    cr_assert(txn_encode_text(&r, text, sizeof text) > 0);
    cr_expect_str_eq(text, "cursor 1 0x1p-1 -0x1p+1");
    r = txn_colour(1, 2, NULL);
    cr_assert(txn_encode_text(&r, text, sizeof text) > 0);
    cr_expect_str_eq(text, "colour 1 2 reset");
    camera_desc c = cam(1.f);
    r = txn_camera(TXN_ALL_CHANNELS, &c);
    cr_assert(txn_encode_text(&r, text, sizeof text) > 0);
    cr_expect(strncmp(text, "camera all 0x1p+0 ", 18) == 0, "%s", text);
    /* too small a buffer: nothing, not a cut line */
    cr_expect_eq(txn_encode_text(&r, text, 12), 0u);
    cr_expect_str_eq(text, "");
}

Test(txn, the_binary_layout_is_little_endian_as_documented)
{
    unsigned char b[TXN_BINARY_BYTES];
    txn_record r = txn_highlight(0x01020304u, 5, true);
    cr_assert(txn_encode_binary(&r, b));
    const unsigned char head[] = {TXN_HIGHLIGHT, 0, 0, 0, 4, 3, 2, 1, 5, 0, 0, 0, 1};
    cr_expect(memcmp(b, head, sizeof head) == 0);
    for (size_t i = sizeof head; i < TXN_BINARY_BYTES; i++)
        cr_expect_eq(b[i], 0, "byte %zu", i);
    r = txn_cursor(true, 1.f, -2.f); /* 1.0f = 0x3f800000, -2.0f = 0xc0000000 */
    cr_assert(txn_encode_binary(&r, b));
    const unsigned char cursor[] = {TXN_CURSOR, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0x80, 0x3f, 0, 0, 0, 0xc0};
    cr_expect(memcmp(b, cursor, sizeof cursor) == 0);
    camera_desc c = cam(1.f);
    r = txn_camera(TXN_ALL_CHANNELS, &c);
    cr_assert(txn_encode_binary(&r, b));
    const unsigned char camera[] = {TXN_CAMERA, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 0, 0, 0x80, 0x3f};
    cr_expect(memcmp(b, camera, sizeof camera) == 0);
    /* a corrupted record is refused: an unknown kind, a byte that must be zero, a flag of 2 */
    tess_error err = {{0}};
    txn_record back;
    b[0] = TXN_KIND_COUNT;
    cr_expect_not(txn_decode_binary(b, &back, &err));
    char want_kind[64];
    snprintf(want_kind, sizeof want_kind, "kind: %d is not a transaction kind", (int)TXN_KIND_COUNT);
    cr_expect(strstr(err.msg, want_kind), "%s", err.msg);
    r = txn_highlight(1, 1, true);
    cr_assert(txn_encode_binary(&r, b));
    b[100] = 1;
    err = (tess_error){{0}};
    cr_expect_not(txn_decode_binary(b, &back, &err));
    cr_expect(strstr(err.msg, "highlight: bytes that must be zero"), "%s", err.msg);
    b[100] = 0;
    b[12] = 2;
    err = (tess_error){{0}};
    cr_expect_not(txn_decode_binary(b, &back, &err));
    b[12] = 1;
    b[8] = 0; /* count 0 */
    err = (tess_error){{0}};
    cr_expect_not(txn_decode_binary(b, &back, &err));
    cr_expect(strstr(err.msg, "highlight: count: 0 instances"), "%s", err.msg);
}

Test(txn, bad_values_are_refused_naming_the_field)
{
    camera_desc bad_cam = cam(1.f);
    bad_cam.fov_deg = 180.f;
    camera_desc good_cam = cam(1.f);
    const float neg[3] = {0.f, -1.f, 0.f}, inf[3] = {INFINITY, 0.f, 0.f};
    txn_record unterminated = txn_status("x");
    memset(unterminated.args.status.text, 'a', sizeof unterminated.args.status.text);
    const float flat[12] = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0}, nan_m[12] = {1, 0, 0, NAN, 0, 1, 0, 0, 0, 0, 1, 0},
                ident[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    const float origin[3] = {0.f, 0.f, 0.f}, up[3] = {0.f, 1.f, 0.f}, nan_point[3] = {0.f, NAN, 0.f},
                inf_normal[3] = {0.f, 1.f, INFINITY};
    txn_record all_with_range = txn_opacity_all(0.5f);
    all_with_range.args.opacity.geoms = (txn_geoms){2, 1};
    struct {
        txn_record r;
        const char *expect;
    } cases[] = {
        {txn_camera(0, &bad_cam), "camera: "},
        {txn_camera(TXN_MAX_CHANNELS, &good_cam), "camera: channel: 16 is not a channel"},
        {txn_camera(-2, &good_cam), "camera: channel: -2"},
        {txn_cursor(true, NAN, 0.f), "cursor: sx: nan is not finite"},
        {txn_cursor(false, 0.f, -INFINITY), "cursor: sy: -inf is not finite"},
        {unterminated, "status: text: not terminated"},
        {txn_geoms_record(TXN_HIDE, 0, 0), "hide: count: 0 instances"},
        {txn_geoms_record(TXN_SHOW, UINT32_MAX, 2), "show: first 4294967295 + count 2 is past"},
        {txn_geoms_record(TXN_ISOLATE, 1, 0), "isolate: count: 0"},
        {txn_highlight(0, 0, true), "highlight: count: 0"},
        {txn_colour(0, 1, neg), "colour: g: -1 is not a finite value >= 0"},
        {txn_colour(0, 1, inf), "colour: r: inf is not a finite value >= 0"},
        {txn_renderer("pathtracer"), "renderer: name: no renderer 'pathtracer'"},
        {txn_threads(0), "threads: count: 0 is not in 1..256"},
        {txn_threads(257), "threads: count: 257"},
        {txn_channel_active(-1, true), "channel-active: channel: -1 is not in 0..15"},
        {txn_move(0, 1, flat), "move: m: the 3x3 part is singular"},
        {txn_move(0, 1, nan_m), "move: m[3]: nan is not finite"},
        {txn_move(0, 0, ident), "move: count: 0"},
        {txn_opacity_all(-0.1f), "opacity: a: -0.1 is not a finite value in [0, 1]"},
        {txn_opacity_all(1.5f), "opacity: a: 1.5 is not a finite value in [0, 1]"},
        {txn_opacity(0, 1, NAN), "opacity: a: nan is not"},
        {txn_opacity(0, 0, 0.5f), "opacity: count: 0 instances"},
        {txn_opacity(UINT32_MAX, 2, 0.5f), "opacity: first 4294967295 + count 2 is past"},
        {all_with_range, "opacity: first/count: 2 1 with all (must be 0 0)"},
        {txn_clip_plane(-1, true, origin, up), "clip-plane: index: -1 is not in 0..7"},
        {txn_clip_plane(CLIP_MAX_PLANES, false, origin, up), "clip-plane: index: 8 is not in 0..7"},
        {txn_clip_plane(0, true, nan_point, up), "clip-plane: point.y: nan is not finite"},
        {txn_clip_plane(0, true, origin, inf_normal), "clip-plane: normal.z: inf is not finite"},
        {txn_clip_plane(0, false, origin, origin), "clip-plane: normal: zero length"},
        {txn_crop(0, 1, true, NAN, 1.f), "crop: lo: nan is not finite"},
        {txn_crop(0, 1, true, 0.f, INFINITY), "crop: hi: inf is not finite"},
        {txn_crop(0, 1, true, 2.f, 1.f), "crop: lo 2 is above hi 1"},
        {txn_crop(0, 0, false, 0.f, 1.f), "crop: count: 0 instances"},
        {txn_value(0, 1, NAN), "value: v: nan is not finite"},
        {txn_colormap(0, 1, "jet"), "colormap: name: no built-in map 'jet'"},
        {txn_colormap(0, 0, "magma"), "colormap: count: 0 instances"},
        {txn_transfer("viridis"), "transfer: name: no built-in transfer function 'viridis' (one with opacity)"},
        {txn_pointer(8, true, 0.f, 0.f), "pointer: slot: 8 is not in 0..7"},
        {txn_pointer(-1, false, 0.f, 0.f), "pointer: slot: -1 is not in 0..7"},
        {txn_pointer(0, true, NAN, 0.f), "pointer: sx, sy: (nan, 0) is not finite"},
        {txn_simple(TXN_KIND_COUNT), "kind: 25 is not a transaction kind"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        tess_error err = {{0}};
        cr_expect_not(txn_validate(&cases[i].r, &err), "case %zu validated", i);
        cr_expect(strstr(err.msg, cases[i].expect), "case %zu: '%s' lacks '%s'", i, err.msg, cases[i].expect);
        /* nothing invalid is encoded */
        char text[TXN_TEXT_MAX];
        unsigned char bin[TXN_BINARY_BYTES];
        cr_expect_eq(txn_encode_text(&cases[i].r, text, sizeof text), 0u, "case %zu", i);
        cr_expect_not(txn_encode_binary(&cases[i].r, bin), "case %zu", i);
        /* nor applied */
        frame_state st = make_state();
        frame_state before = st;
        err = (tess_error){{0}};
        cr_expect_not(txn_apply(&cases[i].r, &st, &err), "case %zu applied", i);
        cr_expect(memcmp(&st, &before, sizeof st) == 0, "case %zu changed the state", i);
        frame_state_finish(&st);
    }
}

Test(txn, bad_text_names_the_field)
{
    static const struct {
        const char *text, *expect;
    } cases[] = {
        {"", "the transaction kind is missing"},
        {"zoom 1", "unknown transaction kind 'zoom'"},
        {"camera all 1 2", "camera eye.z is missing"},
        {"camera 3 1 2 3 0 0 0 0 1 0 0x1.68p+7", "camera: "},
        {"cursor 1 0.1 0", "cursor x: 0.10000000000000001 is not exactly a float"},
        {"hide 1", "hide count is missing"},
        {"isolate 1 0", "isolate: the count must be a whole number >= 1"},
        {"show 1.5 1", "show: the instance id must be a whole number >= 0"},
        {"highlight 1 1 2", "highlight on/off: expected 0 or 1, got '2'"},
        {"colour 1 1 rest", "colour r: expected a finite number, got 'rest'"},
        {"status \"a\\x00b\"", "status: the text holds a NUL byte"},
        {"colour 1 1 1 1", "colour b is missing"},
        {"renderer", "renderer name is missing"},
        {"threads 300", "threads: the count must be a whole number in 1..256"},
        {"channel-active 16 1", "channel-active: the channel must be a whole number in 0..15"},
        {"shadows 1 1", "unexpected text after the transaction"},
        {"status \"a", "status: the text has no closing quote"},
        {"opacity all", "opacity a is missing"},
        {"opacity all 2", "opacity: a: 2 is not a finite value in [0, 1]"},
        {"opacity al 0.5", "opacity instance id: expected a finite number, got 'al'"},
        {"opacity 1 0 0.5", "opacity: the count must be a whole number >= 1"},
        {"opacity 1 1 0.1", "opacity a: 0.10000000000000001 is not exactly a float"},
        {"opacity all 0.5 1", "unexpected text after the transaction"},
        {"clip-plane 8 1 0 0 0 0 0 1", "clip-plane: the index must be a whole number in 0..7"},
        {"clip-plane 0 2 0 0 0 0 0 1", "clip-plane on/off: expected 0 or 1, got '2'"},
        {"clip-plane 0 1 0 x 0 0 0 1", "clip-plane point.y: expected a finite number, got 'x'"},
        {"clip-plane 0 1 0 0 0 0 0", "clip-plane normal.z is missing"},
        {"clip-plane 0 1 0 0 0 0 0 0", "clip-plane: normal: zero length"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        tess_error err = {{0}};
        txn_record r;
        cr_expect_not(txn_decode_text(cases[i].text, strlen(cases[i].text), TXN_TEXT_V2, &r, &err), "case %zu", i);
        cr_expect(strstr(err.msg, cases[i].expect), "case %zu: '%s' lacks '%s'", i, err.msg, cases[i].expect);
    }
}

Test(txn, every_engine_kind_applies_to_a_frame_state)
{
    frame_state st = make_state();
    tess_error err = {{0}};
    for (int k = 0; k < TXN_KIND_COUNT; k++) {
        txn_record r = sample((txn_kind)k);
        uint64_t version = st.version;
        bool applied = txn_apply(&r, &st, &err);
        cr_expect_eq(applied, !txn_kind_input_level(r.kind), "%s: %s", txn_kind_name(r.kind), err.msg);
        cr_expect_eq(st.version, version + (applied ? 1 : 0), "%s", txn_kind_name(r.kind));
    }
    /* what the samples asked for (in kind order: hide 2..4, show 3, isolate 4..5, ...) */
    camera_desc c = cam(0.1f);
    cr_expect(memcmp(&st.cameras[1], &c, sizeof c) == 0);
    cr_expect_eq(st.camera_serials[0], 0u);
    cr_expect_eq(st.camera_serials[1], 1u);
    cr_expect(st.cursor_visible && st.cursor_sx == -0.3f && st.cursor_sy == 1e-7f);
    cr_expect_str_eq(st.status, "picked 'a \"q\" \\ b' \x01\xe9");
    cr_expect(st.governor_status_shown);
    for (uint32_t id = 0; id < GEOMS; id++) {
        cr_expect_eq(frame_state_hidden(&st, id), id != 4 && id != 5, "geometry %u", id);
        cr_expect_eq(frame_state_highlighted(&st, id), id >= 5, "geometry %u", id);
        vec3 rgb;
        cr_expect(frame_state_colour(&st, id, &rgb) && rgb.x == 0.1f && rgb.y == 2.5f && rgb.z == 3.4028235e38f);
    }
    cr_expect_not(st.shadows);
    cr_expect_eq(st.renderer, renderer_by_name("eyelight"));
    cr_expect_eq(st.threads, 7);
    cr_expect(st.active[0] && !st.active[1]);
    cr_assert_not_null(st.moved);
    for (uint32_t id = 0; id < GEOMS; id++)
        cr_expect_eq(affine3_is_identity(&st.moved[id]), id < 6 || id > 8, "geometry %u moved", id);
    cr_expect(st.moved[7].m[11] == -3.4028235e38f && st.moved_first == 6 && st.moved_end == 9);
    for (uint32_t id = 0; id < GEOMS; id++)
        cr_expect_eq(frame_state_opacity(&st, id), id >= 1 && id <= 3 ? 0.3f : 1.f, "geometry %u opacity", id);
    cr_expect_eq(st.translucent_count, 3u);
    const clip_plane *planes = frame_state_clip_planes(&st);
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        cr_expect_eq(planes[i].on, i == 3, "plane %d", i);
    cr_expect(planes[3].point.x == 0.1f && planes[3].point.y == -3.4028235e38f && planes[3].point.z == 1e-7f);
    cr_expect(planes[3].normal.x == 0.f && planes[3].normal.y == 0.6f && planes[3].normal.z == -0.8f,
              "the normal (0, 3, -4) is stored as (0, 0.6, -0.8)");
    /* out of the state's range: the error names it, nothing changes */
    txn_record past = txn_geoms_record(TXN_HIDE, GEOMS - 1, 2);
    err = (tess_error){{0}};
    cr_expect_not(txn_apply(&past, &st, &err));
    cr_expect(strstr(err.msg, "hide: instances 9..10: the scene has 10 instances (ids 0..9)"), "%s", err.msg);
    txn_record ch = txn_channel_active(2, true);
    err = (tess_error){{0}};
    cr_expect_not(txn_apply(&ch, &st, &err));
    cr_expect(strstr(err.msg, "channel-active: channel 2: there are 2 channels"), "%s", err.msg);
    txn_record tour = txn_flag(TXN_TOUR, true);
    err = (tess_error){{0}};
    cr_expect_not(txn_apply(&tour, &st, &err));
    cr_expect(strstr(err.msg, "tour: an input-level transaction"), "%s", err.msg);
    /* the wall's camera sets every channel */
    camera_desc w = cam(9.f);
    txn_record wall = txn_camera(TXN_ALL_CHANNELS, &w);
    cr_assert(txn_apply(&wall, &st, &err), "%s", err.msg);
    cr_expect(st.cameras[0].eye.x == 9.f && st.cameras[1].eye.x == 9.f);
    /* show-all, colour reset, highlight off */
    txn_record all = txn_simple(TXN_SHOW_ALL), reset = txn_colour(0, GEOMS, NULL), off = txn_highlight(0, GEOMS, false);
    cr_assert(txn_apply(&all, &st, &err) && txn_apply(&reset, &st, &err) && txn_apply(&off, &st, &err));
    for (uint32_t id = 0; id < GEOMS; id++)
        cr_expect(!frame_state_hidden(&st, id) && !frame_state_highlighted(&st, id) &&
                  !frame_state_colour(&st, id, NULL));
    frame_state_finish(&st);
}

Test(txn, opacity_and_clip_plane_forms_are_the_documented_ones)
{
    char text[TXN_TEXT_MAX];
    txn_record r = txn_opacity_all(0.5f);
    cr_assert(txn_encode_text(&r, text, sizeof text) > 0);
    cr_expect_str_eq(text, "opacity all 0x1p-1");
    r = txn_opacity(4, 2, 0.f);
    cr_assert(txn_encode_text(&r, text, sizeof text) > 0);
    cr_expect_str_eq(text, "opacity 4 2 0x0p+0");
    const float point[3] = {1.f, -2.f, 0.25f}, normal[3] = {0.f, 0.f, -1.f};
    r = txn_clip_plane(7, false, point, normal);
    cr_assert(txn_encode_text(&r, text, sizeof text) > 0);
    cr_expect_str_eq(text, "clip-plane 7 0 0x1p+0 -0x1p+1 0x1p-2 0x0p+0 0x0p+0 -0x1p+0");
    /* decimal input that is exactly a float reads as the same record */
    txn_record back;
    tess_error err = {{0}};
    cr_assert(txn_decode_text("clip-plane 7 0 1 -2 0.25 0 0 -1", 31, TXN_TEXT_V2, &back, &err), "%s", err.msg);
    cr_expect(memcmp(&back, &r, sizeof r) == 0);
    cr_assert(txn_decode_text("opacity all 0.5", 15, TXN_TEXT_V2, &back, &err), "%s", err.msg);
    r = txn_opacity_all(0.5f);
    cr_expect(memcmp(&back, &r, sizeof r) == 0);
    cr_expect_not(txn_decode_text("opacity all 0.5", 15, TXN_TEXT_V1, &back, &err), "no such kind in format 1");

    unsigned char b[TXN_BINARY_BYTES];
    r = txn_opacity(0x01020304u, 5, 1.f); /* 1.0f = 0x3f800000 */
    cr_assert(txn_encode_binary(&r, b));
    const unsigned char parts[] = {TXN_OPACITY, 0, 0, 0, 0, 0, 0, 0, 4, 3, 2, 1, 5, 0, 0, 0, 0, 0, 0x80, 0x3f};
    cr_expect(memcmp(b, parts, sizeof parts) == 0);
    for (size_t i = sizeof parts; i < TXN_BINARY_BYTES; i++)
        cr_expect_eq(b[i], 0, "byte %zu", i);
    r = txn_opacity_all(0.5f); /* 0x3f000000 */
    cr_assert(txn_encode_binary(&r, b));
    const unsigned char all[] = {TXN_OPACITY, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x3f};
    cr_expect(memcmp(b, all, sizeof all) == 0);
    b[9] = 1; /* all with a range */
    err = (tess_error){{0}};
    cr_expect_not(txn_decode_binary(b, &back, &err));
    cr_expect(strstr(err.msg, "opacity: first/count: 256 0 with all"), "%s", err.msg);
    b[9] = 0;
    b[5] = 1; /* padding after the flag */
    err = (tess_error){{0}};
    cr_expect_not(txn_decode_binary(b, &back, &err));
    cr_expect(strstr(err.msg, "opacity: bytes that must be zero"), "%s", err.msg);

    r = txn_clip_plane(7, true, point, normal); /* -2 = 0xc0000000, 0.25 = 0x3e800000, -1 = 0xbf800000 */
    cr_assert(txn_encode_binary(&r, b));
    const unsigned char plane[] = {TXN_CLIP_PLANE, 0, 0, 0, 7, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0x80, 0x3f, 0, 0, 0, 0xc0,
                                   0, 0, 0x80, 0x3e, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x80, 0xbf};
    cr_expect(memcmp(b, plane, sizeof plane) == 0);
    for (size_t i = sizeof plane; i < TXN_BINARY_BYTES; i++)
        cr_expect_eq(b[i], 0, "byte %zu", i);
    cr_assert(txn_decode_binary(b, &back, &err), "%s", err.msg);
    cr_expect(memcmp(&back, &r, sizeof r) == 0);
    b[4] = 8; /* index 8 */
    err = (tess_error){{0}};
    cr_expect_not(txn_decode_binary(b, &back, &err));
    cr_expect(strstr(err.msg, "clip-plane: index: 8"), "%s", err.msg);
    b[4] = 7;
    b[35] = 0; /* normal.z 0: a zero normal */
    b[34] = 0;
    err = (tess_error){{0}};
    cr_expect_not(txn_decode_binary(b, &back, &err));
    cr_expect(strstr(err.msg, "clip-plane: normal: zero length"), "%s", err.msg);
}

Test(txn, a_clip_plane_normal_is_stored_normalised_in_double_rounded_once)
{
    frame_state st = make_state();
    tess_error err = {{0}};
    /* huge and tiny normals: the length in double neither overflows nor underflows */
    const float point[3] = {0.f, 0.f, 0.f};
    const float normals[][3] = {{3.4028235e38f, 3.4028235e38f, 0.f}, {1e-45f, 0.f, 0.f}, {1.f, 2.f, 2.f},
                                {0.f, -7.f, 0.f}, {1.f, 1.f, 1.f}};
    for (size_t i = 0; i < sizeof normals / sizeof normals[0]; i++) {
        const float *n = normals[i];
        txn_record r = txn_clip_plane((int)i, true, point, n);
        cr_assert(txn_apply(&r, &st, &err), "normal %zu: %s", i, err.msg);
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        vec3 want = v3((float)(n[0] / len), (float)(n[1] / len), (float)(n[2] / len));
        const clip_plane *p = &frame_state_clip_planes(&st)[i];
        cr_expect(p->normal.x == want.x && p->normal.y == want.y && p->normal.z == want.z, "normal %zu", i);
        double got = sqrt((double)p->normal.x * p->normal.x + (double)p->normal.y * p->normal.y +
                          (double)p->normal.z * p->normal.z);
        cr_expect(fabs(got - 1.0) < 2e-7, "normal %zu: length %.9g", i, got);
    }
    const clip_plane *p = frame_state_clip_planes(&st);
    cr_expect(p[2].normal.x == (float)(1.0 / 3.0) && p[2].normal.y == (float)(2.0 / 3.0));
    cr_expect(p[3].normal.x == 0.f && p[3].normal.y == -1.f && p[3].normal.z == 0.f);
    cr_expect(p[1].normal.x == 1.f);
    frame_state_finish(&st);
}

/* Out of range, in user terms: geometry ids are the instances a part covers. */
Test(txn, an_out_of_range_record_names_instances)
{
    static const struct {
        uint32_t first, count, have;
        const char *msg;
    } cases[] = {
        {99999, 5, 2000, "hide: instances 99999..100003: the scene has 2000 instances (ids 0..1999)"},
        {3, 1, 1, "hide: instance 3: the scene has 1 instance (id 0)"},
        {0, 2, 0, "hide: instances 0..1: the scene has no instances"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        tess_error err = {{0}};
        txn_geoms g = {cases[i].first, cases[i].count};
        cr_expect_not(txn_range_error("hide", &g, cases[i].have, &err));
        cr_expect_str_eq(err.msg, cases[i].msg);
    }
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), true, 1, 1);
    txn_record past = txn_geoms_record(TXN_ISOLATE, 1, 1);
    tess_error err = {{0}};
    cr_expect_not(txn_apply(&past, &st, &err));
    cr_expect_str_eq(err.msg, "isolate: instance 1: the scene has 1 instance (id 0)");
    frame_state_finish(&st);
}
