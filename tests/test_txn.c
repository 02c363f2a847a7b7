/* test_txn.c - transaction records (engine/txn.h): every kind validates,
 * applies to a frame state, and survives the text and binary round trips bit
 * for bit; bad values are refused with the field named; the binary layout is
 * the documented one. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "engine/frame_state.h"
#include "engine/render.h"
#include "engine/txn.h"

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
    cr_expect(strstr(err.msg, "kind: 17 is not a transaction kind"), "%s", err.msg);
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
    cr_expect(strstr(err.msg, "highlight: count: 0 geometries"), "%s", err.msg);
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
        {txn_geoms_record(TXN_HIDE, 0, 0), "hide: count: 0 geometries"},
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
        {txn_simple(TXN_KIND_COUNT), "kind: 17 is not a transaction kind"},
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
        {"show 1.5 1", "show: the geometry id must be a whole number >= 0"},
        {"highlight 1 1 2", "highlight on/off: expected 0 or 1, got '2'"},
        {"colour 1 1 rest", "colour r: expected a finite number, got 'rest'"},
        {"status \"a\\x00b\"", "status: the text holds a NUL byte"},
        {"colour 1 1 1 1", "colour b is missing"},
        {"renderer", "renderer name is missing"},
        {"threads 300", "threads: the count must be a whole number in 1..256"},
        {"channel-active 16 1", "channel-active: the channel must be a whole number in 0..15"},
        {"shadows 1 1", "unexpected text after the transaction"},
        {"status \"a", "status: the text has no closing quote"},
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
    /* out of the state's range: the error names it, nothing changes */
    txn_record past = txn_geoms_record(TXN_HIDE, GEOMS - 1, 2);
    err = (tess_error){{0}};
    cr_expect_not(txn_apply(&past, &st, &err));
    cr_expect(strstr(err.msg, "hide: geometries 9..10: there are 10 geometries (ids 0..9)"), "%s", err.msg);
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
