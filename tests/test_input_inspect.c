/* test_input_inspect.c - inspection through input: the controller's opacity
 * commands (global and the selection's) and cutting planes (place at the
 * picked point facing the eye, next, flip, remove, remove all, the
 * plane-push drag, the three-finger tap) on keys, buttons and touch, with a
 * fake pick hook on a synthetic clock: events in, exactly the expected
 * records out (indices, points and normals bit for bit), and those records
 * through the record file and back bit for bit, then applied to a frame
 * state. */
#include <criterion/criterion.h>
#include <linux/input-event-codes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/colormap.h"
#include "engine/scene/frame_state.h"
#include "engine/render/render.h"
#include "input/controller.h"
#include "input/navigate.h"
#include "input/record.h"

#define ASPECT (16.f / 9.f)
#define SCENE_SIZE 4.0
#define PICK_DEPTH 5.f /* the fake pick hits 5 units along the ray */
#define MAX_TXNS 1024

typedef struct rig {
    input_txn txns[MAX_TXNS];
    int count;
    input_controller *c;
    uint64_t now_us;
} rig;

static input_part part(uint32_t first, uint32_t count, const char *label)
{
    input_part p = {.first = first, .count = count};
    snprintf(p.label, sizeof p.label, "%s", label);
    return p;
}

/* Left of the middle a bolt (10) inside a frame (8..11), right of it a skin (50); the top is sky. */
static void fake_pick(void *ctx, vec3 o, vec3 d, input_hit *out)
{
    (void)ctx;
    memset(out, 0, sizeof *out);
    if (d.y > 0.12f)
        return;
    out->hit = true;
    out->point = v3_add(o, v3_scale(d, PICK_DEPTH));
    if (d.x < 0.f) {
        out->geom_id = 10;
        snprintf(out->what, sizeof out->what, "part asm/frame/bolt triangle 1");
        out->part = part(10, 1, "asm/frame/bolt");
        out->ancestors[0] = part(8, 4, "asm/frame");
        out->ancestor_count = 1;
    } else {
        out->geom_id = 50;
        snprintf(out->what, sizeof out->what, "part asm/skin triangle 2");
        out->part = part(50, 1, "asm/skin");
    }
}

static void rig_emit(void *ctx, const input_txn *t)
{
    rig *r = ctx;
    cr_assert(r->count < MAX_TXNS);
    r->txns[r->count++] = *t;
}

static camera_desc home(void) { return (camera_desc){v3(0.f, 0.f, 6.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f}; }

static camera_desc rig_current(void *ctx)
{
    (void)ctx;
    return home();
}

/* What the rig's step_ready callback answers (TIME STEPS tests). */
static bool steps_loaded = true;
static uint32_t steps_asked = UINT32_MAX;

static bool rig_step_ready(void *ctx, uint32_t step)
{
    (void)ctx;
    steps_asked = step;
    return steps_loaded;
}

static rig *rig_make_with(const input_controller_config *base)
{
    rig *r = calloc(1, sizeof *r);
    cr_assert(r);
    input_controller_config cfg;
    if (base)
        cfg = *base;
    else
        input_controller_config_default(&cfg);
    cfg.plane_aspect = ASPECT;
    cfg.home = home();
    cfg.scene_size = SCENE_SIZE;
    input_controller_hooks hooks = {.ctx = r, .pick = fake_pick, .emit = rig_emit, .current_camera = rig_current,
                                    .step_ready = rig_step_ready};
    r->c = input_controller_create(&cfg, &hooks);
    cr_assert(r->c);
    r->now_us = 1000000;
    input_controller_tick(r->c, r->now_us);
    return r;
}

static rig *rig_make(void) { return rig_make_with(NULL); }

static void rig_free(rig *r)
{
    input_controller_destroy(r->c);
    free(r);
}

static void send(rig *r, input_event e)
{
    e.time_us = r->now_us;
    input_controller_event(r->c, &e);
}

static void frame(rig *r)
{
    send(r, (input_event){.kind = INPUT_FRAME});
    r->now_us += 8000;
}

static void key(rig *r, int code, bool pressed)
{
    input_event_kind kind = code >= BTN_MISC && code < KEY_OK ? INPUT_BUTTON : INPUT_KEY;
    send(r, (input_event){.kind = kind, .code = code, .pressed = pressed});
    frame(r);
}

/* Pressed and released; the records it made start at the returned index. */
static int press(rig *r, int code)
{
    int at = r->count;
    key(r, code, true);
    key(r, code, false);
    return at;
}

static void move_to(rig *r, double x, double y)
{
    send(r, (input_event){.kind = INPUT_POINTER_ABS, .x = x, .y = y});
    frame(r);
}

/* The records from `from` on but cursor and camera, as text forms joined by " | ". */
static const char *made_since(const rig *r, int from)
{
    static char out[4096];
    size_t used = 0;
    out[0] = '\0';
    for (int i = from; i < r->count; i++) {
        if (r->txns[i].kind == TXN_CURSOR || r->txns[i].kind == TXN_CAMERA)
            continue;
        char line[TXN_TEXT_MAX];
        cr_assert(txn_encode_text(&r->txns[i], line, sizeof line) > 0);
        used += (size_t)snprintf(out + used, sizeof out - used, "%s%s", used ? " | " : "", line);
        cr_assert(used < sizeof out);
    }
    return out;
}

/* The one record of kind k from `from` on (asserts there is exactly one). */
static input_txn only(const rig *r, int from, txn_kind k)
{
    int n = 0, at = -1;
    for (int i = from; i < r->count; i++)
        if (r->txns[i].kind == k) {
            n++;
            at = i;
        }
    cr_assert_eq(n, 1, "%d %s records: %s", n, txn_kind_name(k), made_since(r, from));
    return r->txns[at];
}

static const char *text_of(input_txn t)
{
    static char line[TXN_TEXT_MAX];
    cr_assert(txn_encode_text(&t, line, sizeof line) > 0);
    return line;
}

/* What placing a plane at plane point (sx, sy) must send: the fake pick's point, and the unit
 * vector from it to the home eye, in double rounded once. */
static input_txn expected_place(int index, double sx, double sy)
{
    camera_desc cam = home();
    vec3 o, d;
    navigate_plane_ray(&cam, ASPECT, sx, sy, &o, &d);
    vec3 p = v3_add(o, v3_scale(d, PICK_DEPTH));
    double n[3] = {(double)cam.eye.x - p.x, (double)cam.eye.y - p.y, (double)cam.eye.z - p.z};
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const float point[3] = {p.x, p.y, p.z}, normal[3] = {(float)(n[0] / len), (float)(n[1] / len),
                                                         (float)(n[2] / len)};
    return txn_clip_plane(index, true, point, normal);
}

static void expect_same(input_txn got, input_txn want)
{
    char g[TXN_TEXT_MAX];
    cr_assert(txn_encode_text(&got, g, sizeof g) > 0);
    cr_expect(memcmp(&got, &want, sizeof got) == 0, "got '%s', want '%s'", g, text_of(want));
}

#define LEFT -0.5, 0.0
#define RIGHT 0.5, 0.0
#define SKY 0.0, 0.9

/* ---- opacity ------------------------------------------------------------------------- */

Test(input_inspect, global_opacity_steps_by_a_tenth_and_stops_at_the_ends)
{
    rig *r = rig_make();
    cr_expect_str_eq(made_since(r, press(r, KEY_RIGHTBRACE)), "status \"opacity 1 (the most)\"");
    int at = press(r, KEY_LEFTBRACE);
    expect_same(only(r, at, TXN_OPACITY), txn_opacity_all(0.9f));
    cr_expect(strstr(made_since(r, at), "status \"opacity 0.9\""), "%s", made_since(r, at));
    for (int k = 8; k >= 0; k--) {
        at = press(r, KEY_LEFTBRACE);
        expect_same(only(r, at, TXN_OPACITY), txn_opacity_all((float)(k / 10.0)));
    }
    cr_expect_str_eq(made_since(r, press(r, KEY_LEFTBRACE)), "status \"opacity 0 (the least)\"");
    at = press(r, KEY_RIGHTBRACE);
    expect_same(only(r, at, TXN_OPACITY), txn_opacity_all(0.1f));
    rig_free(r);
}

Test(input_inspect, the_opacity_starts_where_the_config_put_it_and_steps_onto_the_grid)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.opacity = 0.55f;
    rig *r = rig_make_with(&cfg);
    expect_same(only(r, press(r, KEY_LEFTBRACE), TXN_OPACITY), txn_opacity_all(0.5f));
    rig_free(r);
    r = rig_make_with(&cfg);
    expect_same(only(r, press(r, KEY_RIGHTBRACE), TXN_OPACITY), txn_opacity_all(0.6f));
    rig_free(r);
}

Test(input_inspect, the_selection_s_opacity_steps_from_what_input_set_for_it)
{
    rig *r = rig_make();
    cr_expect_str_eq(made_since(r, press(r, KEY_SEMICOLON)),
                     "status \"nothing selected to make transparent (pick a part first)\"");
    move_to(r, LEFT);
    press(r, KEY_P); /* the bolt */
    int at = press(r, KEY_SEMICOLON);
    expect_same(only(r, at, TXN_OPACITY), txn_opacity(10, 1, 0.9f));
    cr_expect(strstr(made_since(r, at), "status \"opacity of asm/frame/bolt 0.9\""), "%s", made_since(r, at));
    expect_same(only(r, press(r, KEY_SEMICOLON), TXN_OPACITY), txn_opacity(10, 1, 0.8f));
    /* the frame around it starts at 1 (the bolt's range is inside it, not around it) */
    press(r, KEY_BACKSPACE);
    expect_same(only(r, press(r, KEY_SEMICOLON), TXN_OPACITY), txn_opacity(8, 4, 0.9f));
    /* the bolt again: the frame's record overwrote it, so it steps from the frame's 0.9 */
    press(r, KEY_P);
    expect_same(only(r, press(r, KEY_APOSTROPHE), TXN_OPACITY), txn_opacity(10, 1, 1.f));
    cr_expect_str_eq(made_since(r, press(r, KEY_APOSTROPHE)), "status \"opacity of asm/frame/bolt 1 (the most)\"");
    /* the global opacity is apart from the parts' */
    expect_same(only(r, press(r, KEY_LEFTBRACE), TXN_OPACITY), txn_opacity_all(0.9f));
    rig_free(r);
}

/* ---- cutting planes ---------------------------------------------------------------------- */

Test(input_inspect, a_plane_is_placed_at_the_picked_point_facing_the_eye)
{
    rig *r = rig_make();
    move_to(r, SKY);
    cr_expect_str_eq(made_since(r, press(r, KEY_C)), "status \"no surface there to place a cutting plane on\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_X)), "status \"no cutting plane (place one first)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_DELETE)), "status \"no cutting plane (place one first)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_END)), "status \"no cutting planes to remove\"");
    move_to(r, LEFT);
    int at = press(r, KEY_C);
    input_txn p0 = expected_place(0, LEFT);
    expect_same(only(r, at, TXN_CLIP_PLANE), p0);
    cr_expect(strstr(made_since(r, at), "status \"cutting plane 0 at ("), "%s", made_since(r, at));
    /* the normal is unit and points from the point at the eye */
    const float *n = p0.args.clip_plane.normal, *p = p0.args.clip_plane.point;
    cr_expect(fabs(sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]) - 1.0) < 1e-6);
    cr_expect_gt((6.0 - p[2]) * n[2] + (0.0 - p[0]) * n[0] + (0.0 - p[1]) * n[1], 0.0);
    move_to(r, RIGHT);
    at = press(r, KEY_C);
    input_txn p1 = expected_place(1, RIGHT);
    expect_same(only(r, at, TXN_CLIP_PLANE), p1);
    /* next: from 1 round to 0; flip negates 0's normal, the point stays */
    cr_expect_str_eq(made_since(r, press(r, KEY_N)), "status \"cutting plane 0 selected\"");
    at = press(r, KEY_X);
    input_txn flipped = p0;
    for (int i = 0; i < 3; i++)
        flipped.args.clip_plane.normal[i] = -p0.args.clip_plane.normal[i];
    expect_same(only(r, at, TXN_CLIP_PLANE), flipped);
    /* remove: 0 off where it was; plane 1 becomes the selected one */
    at = press(r, KEY_DELETE);
    input_txn off0 = flipped;
    off0.args.clip_plane.on = false;
    expect_same(only(r, at, TXN_CLIP_PLANE), off0);
    cr_expect(strstr(made_since(r, at), "status \"cutting plane 0 removed\""));
    cr_expect_str_eq(made_since(r, press(r, KEY_N)), "status \"cutting plane 1 selected\"");
    /* a new plane takes the lowest index that is off: 0 again */
    move_to(r, LEFT);
    expect_same(only(r, press(r, KEY_C), TXN_CLIP_PLANE), expected_place(0, LEFT));
    /* remove all: each plane on, off, in index order */
    at = press(r, KEY_END);
    input_txn off_a = expected_place(0, LEFT), off_b = p1;
    off_a.args.clip_plane.on = off_b.args.clip_plane.on = false;
    cr_assert_eq(r->count - at, 3, "%s", made_since(r, at));
    expect_same(r->txns[at], off_a);
    expect_same(r->txns[at + 1], off_b);
    cr_expect_str_eq(made_since(r, at + 2), "status \"all cutting planes removed\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_X)), "status \"no cutting plane (place one first)\"");
    rig_free(r);
}

Test(input_inspect, with_every_plane_on_a_new_one_replaces_the_selected_one)
{
    rig *r = rig_make();
    move_to(r, LEFT);
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        expect_same(only(r, press(r, KEY_C), TXN_CLIP_PLANE), expected_place(i, LEFT));
    press(r, KEY_N); /* 7 -> 0 */
    press(r, KEY_N); /* 0 -> 1 */
    move_to(r, RIGHT);
    expect_same(only(r, press(r, KEY_C), TXN_CLIP_PLANE), expected_place(1, RIGHT));
    rig_free(r);
}

Test(input_inspect, the_middle_button_pushes_the_selected_plane_along_its_normal_once_per_frame)
{
    rig *r = rig_make();
    move_to(r, LEFT);
    input_txn placed = only(r, press(r, KEY_C), TXN_CLIP_PLANE);
    int at = r->count;
    key(r, BTN_MIDDLE, true);
    /* two motions in one input frame: one record, the plane moved by both */
    send(r, (input_event){.kind = INPUT_POINTER_ABS, .x = -0.5, .y = 0.05});
    send(r, (input_event){.kind = INPUT_POINTER_ABS, .x = -0.5, .y = 0.1});
    frame(r);
    key(r, BTN_MIDDLE, false);
    input_txn want = placed;
    double dys[2] = {0.05 - 0.0, 0.1 - 0.05};
    for (int k = 0; k < 2; k++) {
        double along = -dys[k] * INPUT_PLANE_PUSH_PER_UNIT * SCENE_SIZE;
        for (int i = 0; i < 3; i++)
            want.args.clip_plane.point[i] = (float)((double)want.args.clip_plane.point[i] +
                                                    along * (double)want.args.clip_plane.normal[i]);
    }
    expect_same(only(r, at, TXN_CLIP_PLANE), want);
    cr_expect_eq(made_since(r, at)[0], 'c', "no click, no status: %s", made_since(r, at));
    cr_expect_lt(want.args.clip_plane.point[2], placed.args.clip_plane.point[2], "up pushes away from the eye");
    /* without a plane the push does nothing */
    press(r, KEY_END);
    at = r->count;
    key(r, BTN_MIDDLE, true);
    move_to(r, -0.5, 0.3);
    key(r, BTN_MIDDLE, false);
    cr_expect_str_eq(made_since(r, at), "");
    rig_free(r);
}

Test(input_inspect, a_three_finger_tap_places_a_plane_where_the_first_finger_landed)
{
    rig *r = rig_make();
    int at = r->count;
    send(r, (input_event){.kind = INPUT_TOUCH_DOWN, .slot = 0, .x = -0.5, .y = 0.0});
    send(r, (input_event){.kind = INPUT_TOUCH_DOWN, .slot = 1, .x = -0.3, .y = 0.0});
    send(r, (input_event){.kind = INPUT_TOUCH_DOWN, .slot = 2, .x = -0.1, .y = 0.0});
    send(r, (input_event){.kind = INPUT_TOUCH_FRAME});
    r->now_us += 50000;
    for (int s = 0; s < 3; s++)
        send(r, (input_event){.kind = INPUT_TOUCH_UP, .slot = s});
    send(r, (input_event){.kind = INPUT_TOUCH_FRAME});
    expect_same(only(r, at, TXN_CLIP_PLANE), expected_place(0, LEFT));
    cr_expect_eq(only(r, at, TXN_STATUS).kind, TXN_STATUS);
    rig_free(r);
}

Test(input_inspect, the_config_s_planes_are_the_controller_s_start)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.clip[3] = (clip_plane){v3(1.f, 2.f, 3.f), v3(0.f, 1.f, 0.f), true};
    rig *r = rig_make_with(&cfg);
    /* plane 3 is selected: flip it */
    const float point[3] = {1.f, 2.f, 3.f}, down[3] = {-0.f, -1.f, -0.f};
    expect_same(only(r, press(r, KEY_X), TXN_CLIP_PLANE), txn_clip_plane(3, true, point, down));
    /* a new plane takes index 0, the lowest off */
    move_to(r, LEFT);
    expect_same(only(r, press(r, KEY_C), TXN_CLIP_PLANE), expected_place(0, LEFT));
    rig_free(r);
}

/* ---- recorded and replayed ------------------------------------------------------------------ */

Test(input_inspect, what_input_made_is_recorded_and_replayed_bit_for_bit_and_applies)
{
    rig *r = rig_make();
    move_to(r, LEFT);
    press(r, KEY_P);
    press(r, KEY_SEMICOLON);
    press(r, KEY_LEFTBRACE);
    press(r, KEY_C);
    move_to(r, RIGHT);
    press(r, KEY_C);
    press(r, KEY_X);
    key(r, BTN_MIDDLE, true);
    move_to(r, 0.5, 0.2);
    key(r, BTN_MIDDLE, false);
    press(r, KEY_DELETE);
    press(r, KEY_END);
    press(r, KEY_O);
    int made[TXN_KIND_COUNT] = {0};
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    cr_assert_not_null(f);
    fprintf(f, "%s\n", INPUT_RECORD_HEADER);
    for (int i = 0; i < r->count; i++) {
        made[r->txns[i].kind]++;
        cr_assert(input_record_write(f, 0.125 * i, &r->txns[i]));
    }
    cr_assert_eq(fclose(f), 0);
    cr_expect_eq(made[TXN_OPACITY], 2);
    cr_expect_eq(made[TXN_CLIP_PLANE], 6, "two placed, a flip, a push, a removal, the rest removed");
    cr_expect_eq(made[TXN_RENDERER], 1);
    input_record rec = {0};
    tess_error err = {{0}};
    cr_assert(input_record_parse("rec.txt", text, len, &rec, &err), "%s", err.msg);
    cr_assert_eq(rec.count, (size_t)r->count);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), true, 1, 100);
    for (size_t i = 0; i < rec.count; i++) {
        cr_expect(memcmp(&rec.entries[i].txn, &r->txns[i], sizeof r->txns[i]) == 0, "entry %zu: %s", i,
                  text_of(r->txns[i]));
        txn_kind k = rec.entries[i].txn.kind;
        if (k == TXN_OPACITY || k == TXN_CLIP_PLANE || k == TXN_RENDERER)
            cr_expect(txn_apply(&rec.entries[i].txn, &st, &err), "entry %zu: %s", i, err.msg);
    }
    cr_expect_eq(frame_state_opacity(&st, 10), 0.9f * 0.9f);
    cr_expect_eq(st.translucent_count, 1u);
    cr_expect_str_eq(st.renderer->name, "raytracer-ao");
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        cr_expect_not(frame_state_clip_planes(&st)[i].on, "plane %d", i);
    frame_state_finish(&st);
    input_record_free(&rec);
    free(text);
    rig_free(r);
}

/* ---- ambient occlusion --------------------------------------------------------------- */

Test(input_inspect, ambient_occlusion_steps_through_the_ao_renderers_and_back)
{
    rig *r = rig_make();
    cr_expect_str_eq(made_since(r, press(r, KEY_O)),
                     "renderer raytracer-ao | status \"renderer raytracer-ao (ambient occlusion on)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_O)), "renderer ao | status \"renderer ao (ambient occlusion alone)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_O)),
                     "renderer raytracer | status \"renderer raytracer (ambient occlusion off)\"");
    rig_free(r);
    /* back to the renderer the pipeline started with */
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    snprintf(cfg.renderer, sizeof cfg.renderer, "eyelight");
    r = rig_make_with(&cfg);
    expect_same(only(r, press(r, KEY_O), TXN_RENDERER), txn_renderer("raytracer-ao"));
    expect_same(only(r, press(r, KEY_O), TXN_RENDERER), txn_renderer("ao"));
    expect_same(only(r, press(r, KEY_O), TXN_RENDERER), txn_renderer("eyelight"));
    rig_free(r);
    /* started on an AO renderer: the cycle's other end is the raytracer */
    snprintf(cfg.renderer, sizeof cfg.renderer, "ao");
    r = rig_make_with(&cfg);
    expect_same(only(r, press(r, KEY_O), TXN_RENDERER), txn_renderer("raytracer"));
    expect_same(only(r, press(r, KEY_O), TXN_RENDERER), txn_renderer("raytracer-ao"));
    rig_free(r);
}

/* The crop window over a particle set's attribute (controller.h, CROP):
 * up from an inactive crop starts at the bottom, steps of half a window,
 * clamped at the top; off shows everything; down starts at the top. */
Test(input_inspect, crop_keys_move_a_window_over_the_attribute)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.crops[0] = (input_crop_target){.first = 3, .count = 1, .attribute = "c_ke", .min = 0.f, .max = 8.f};
    cfg.crop_count = 1;
    rig *r = rig_make_with(&cfg);
    const struct {
        int key;
        const char *record;
    } steps[] = {
        {KEY_DOT, "crop 3 1 1 0x0p+0 0x1p+1"},          /* [0, 2] */
        {KEY_DOT, "crop 3 1 1 0x1p+0 0x1.8p+1"},        /* [1, 3] */
        {KEY_DOT, "crop 3 1 1 0x1p+1 0x1p+2"},          /* [2, 4] */
        {KEY_COMMA, "crop 3 1 1 0x1p+0 0x1.8p+1"},      /* back to [1, 3] */
        {KEY_SLASH, "crop 3 1 0 0x1p+0 0x1.8p+1"},      /* off (the window kept in the record) */
        {KEY_COMMA, "crop 3 1 1 0x1.8p+2 0x1p+3"},      /* down from off: the top, [6, 8] */
        {KEY_DOT, "crop 3 1 1 0x1.8p+2 0x1p+3"},        /* clamped at the top */
    };
    for (size_t i = 0; i < sizeof steps / sizeof steps[0]; i++) {
        int at = press(r, steps[i].key);
        cr_expect_str_eq(text_of(only(r, at, TXN_CROP)), steps[i].record, "step %zu", i);
    }
    int at = press(r, KEY_COMMA);
    cr_expect_str_eq(text_of(only(r, at, TXN_STATUS)), "status \"crop c_ke [5, 7]\"");
    rig_free(r);
}

Test(input_inspect, crop_keys_without_particles_say_so)
{
    rig *r = rig_make();
    int at = press(r, KEY_DOT);
    cr_expect_str_eq(made_since(r, at), "status \"nothing to crop (no particles with a crop attribute)\"");
    rig_free(r);
}

/* Advance the rig's clock by `ms` in animation ticks. */
static void run_ms(rig *r, int ms)
{
    for (int t = 0; t < ms * 1000; t += INPUT_TICK_US) {
        r->now_us += INPUT_TICK_US;
        input_controller_tick(r->c, r->now_us);
    }
}

/* Stepping wraps; playing advances at the rate but only to loaded steps. */
Test(input_inspect, time_keys_step_and_play_only_loaded_steps)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.time_steps = 3;
    cfg.time_rate = 4.0;
    steps_loaded = true;
    rig *r = rig_make_with(&cfg);
    cr_expect_str_eq(text_of(only(r, press(r, KEY_0), TXN_TIME_STEP)), "time-step 1");
    cr_expect_str_eq(text_of(only(r, press(r, KEY_9), TXN_TIME_STEP)), "time-step 0");
    int at = press(r, KEY_9);
    cr_expect_str_eq(text_of(only(r, at, TXN_TIME_STEP)), "time-step 2", "back from 0 wraps");
    cr_expect_str_eq(text_of(only(r, at, TXN_STATUS)), "status \"time step 3/3\"");
    at = press(r, KEY_SPACE);
    cr_expect_str_eq(made_since(r, at), "status \"time step 3/3 (playing, 4 steps/s)\"");
    at = r->count;
    run_ms(r, 300); /* one step due after 250 ms */
    cr_expect_str_eq(text_of(only(r, at, TXN_TIME_STEP)), "time-step 0");
    /* the next one is not loaded: nothing while it loads, then it comes at once */
    steps_loaded = false;
    at = r->count;
    run_ms(r, 1000);
    cr_expect_eq(r->count, at, "no step while the next one loads: %s", made_since(r, at));
    cr_expect_eq(steps_asked, 1u, "asked for step 1");
    steps_loaded = true;
    run_ms(r, 20);
    cr_expect_str_eq(text_of(only(r, at, TXN_TIME_STEP)), "time-step 1");
    at = press(r, KEY_SPACE);
    cr_expect_str_eq(made_since(r, at), "status \"time step 2/3 (paused, 4 steps/s)\"");
    at = r->count;
    run_ms(r, 1000);
    cr_expect_eq(r->count, at, "paused: %s", made_since(r, at));
    at = press(r, KEY_8);
    cr_expect_str_eq(made_since(r, at), "status \"time: 6 steps/s\"");
    rig_free(r);
}

Test(input_inspect, time_keys_without_a_series_say_so)
{
    rig *r = rig_make();
    int at = press(r, KEY_SPACE);
    cr_expect_str_eq(made_since(r, at), "status \"no time steps in this scene\"");
    rig_free(r);
}

/* T and Y step every iso-value by 1/50 of its range, clamped; M cycles the
 * built-in maps (wrapping). */
Test(input_inspect, value_and_colormap_keys)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.values[0] = (input_value_target){.first = 2, .count = 1, .value = 10.f, .lo = 0.f, .hi = 100.f};
    cfg.value_count = 1;
    cfg.maps[0] = (input_map_target){.first = 5, .count = 1, .name = "greyscale"};
    cfg.map_count = 1;
    rig *r = rig_make_with(&cfg);
    int at = press(r, KEY_Y);
    cr_expect_str_eq(text_of(only(r, at, TXN_VALUE)), "value 2 1 0x1.8p+3");
    cr_expect_str_eq(text_of(only(r, at, TXN_STATUS)), "status \"iso-value 12\"");
    for (int i = 0; i < 10; i++)
        press(r, KEY_T);
    at = press(r, KEY_T);
    cr_expect_str_eq(text_of(only(r, at, TXN_VALUE)), "value 2 1 0x0p+0", "clamped at the bottom of the range");
    const char *const *names = colormap_names();
    int k = 0;
    while (names[k] && strcmp(names[k], "greyscale") != 0)
        k++;
    cr_assert(names[k]);
    at = press(r, KEY_M);
    char want[64];
    snprintf(want, sizeof want, "colormap 5 1 %s", names[k + 1] ? names[k + 1] : names[0]);
    cr_expect_str_eq(text_of(only(r, at, TXN_COLORMAP)), want);
    rig_free(r);
}

/* value-drag (the side button): every iso-value follows the drag, half its
 * range per plane unit up, clamped; the motions of one input frame make one
 * record per target; without iso-values it does nothing. */
Test(input_inspect, value_drag_follows_the_pointer)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.values[0] = (input_value_target){.first = 2, .count = 1, .value = 10.f, .lo = 0.f, .hi = 100.f};
    cfg.values[1] = (input_value_target){.first = 3, .count = 1, .value = 50.f, .lo = 40.f, .hi = 60.f};
    cfg.value_count = 2;
    rig *r = rig_make_with(&cfg);
    move_to(r, 0.0, 0.0);
    int at = r->count;
    key(r, BTN_SIDE, true);
    send(r, (input_event){.kind = INPUT_POINTER_ABS, .x = 0.0, .y = 0.1});
    send(r, (input_event){.kind = INPUT_POINTER_ABS, .x = 0.3, .y = 0.2});
    frame(r);
    key(r, BTN_SIDE, false);
    /* up 0.2 units: + 0.1 of each range */
    cr_expect_str_eq(made_since(r, at), "value 2 1 0x1.4p+4 | value 3 1 0x1.ap+5 | status \"iso-value 20; iso-value 52\"",
                     "%s", made_since(r, at));
    at = r->count;
    key(r, BTN_SIDE, true);
    move_to(r, 0.3, -1.0);
    key(r, BTN_SIDE, false);
    cr_expect_str_eq(made_since(r, at), "value 2 1 0x0p+0 | value 3 1 0x1.4p+5 | status \"iso-value 0; iso-value 40\"",
                     "down past the bottom: clamped: %s", made_since(r, at));
    rig_free(r);
    r = rig_make();
    move_to(r, 0.0, 0.0);
    at = r->count;
    key(r, BTN_SIDE, true);
    move_to(r, 0.0, 0.5);
    key(r, BTN_SIDE, false);
    cr_expect_eq(strstr(made_since(r, at), "value") == NULL, true, "no values: no record: %s", made_since(r, at));
    rig_free(r);
}

/* Three fingers moved together up the screen drag every iso-value (the
 * shipped three-finger-drag), by their centre's motion; no tap, no plane. */
Test(input_inspect, three_fingers_drag_the_iso_value)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.values[0] = (input_value_target){.first = 2, .count = 1, .value = 10.f, .lo = 0.f, .hi = 100.f};
    cfg.value_count = 1;
    rig *r = rig_make_with(&cfg);
    int at = r->count;
    for (int s = 0; s < 3; s++)
        send(r, (input_event){.kind = INPUT_TOUCH_DOWN, .slot = s, .x = -0.2 + 0.2 * s, .y = 0.0});
    send(r, (input_event){.kind = INPUT_TOUCH_FRAME});
    r->now_us += 20000;
    for (int s = 0; s < 3; s++) /* the centre up by 0.2 units: + 0.1 of the range */
        send(r, (input_event){.kind = INPUT_TOUCH_MOTION, .slot = s, .x = -0.2 + 0.2 * s, .y = 0.2});
    send(r, (input_event){.kind = INPUT_TOUCH_FRAME});
    r->now_us += 20000;
    for (int s = 0; s < 3; s++)
        send(r, (input_event){.kind = INPUT_TOUCH_UP, .slot = s});
    send(r, (input_event){.kind = INPUT_TOUCH_FRAME});
    cr_expect_str_eq(text_of(only(r, at, TXN_VALUE)), "value 2 1 0x1.4p+4", "%s", made_since(r, at));
    cr_expect(strstr(made_since(r, at), "clip-plane") == NULL, "a drag is no tap: %s", made_since(r, at));
    rig_free(r);
}

/* With volumes rendered directly, M steps their transfer function through
 * the built-ins that have opacity. */
Test(input_inspect, colormap_next_steps_the_transfer_function_of_volumes)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.media = true;
    snprintf(cfg.transfer, sizeof cfg.transfer, "ct-bone");
    rig *r = rig_make_with(&cfg);
    int at = press(r, KEY_M);
    input_txn t = only(r, at, TXN_TRANSFER);
    colormap probe;
    cr_assert(colormap_preset(t.args.renderer.name, &probe));
    cr_expect_gt(probe.opacity_count, 0u, "%s has opacity", t.args.renderer.name);
    cr_expect_str_neq(t.args.renderer.name, "ct-bone");
    for (int i = 0; i < 8; i++)
        press(r, KEY_M);
    rig_free(r);
}
