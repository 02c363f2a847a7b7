/* test_input_parts.c - parts through input: the controller's selection and
 * part commands (pick, hide-object, show, isolate, select-parent, highlight,
 * show-all) on keys, buttons and touch (long press, two-finger tap) with a
 * fake pick hook that reports parts with ranges and ancestors, on a synthetic
 * clock; and the command line's pick hook (app/input_pick.h) on the
 * shipped assembly: a ray at a known bolt names its path and its subtree. */
#include <criterion/criterion.h>
#include <linux/input-event-codes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/part_tree.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "input/controller.h"
#include "app/input_pick.h"

#define ASPECT (16.f / 9.f)
#define MAX_TXNS 1024

/* ---- a fake assembly: left of the middle the bolt, right of it the skin,
 * above y = 0.5 of the plane nothing ------------------------------------------ */

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

static void fake_pick(void *ctx, vec3 o, vec3 d, input_hit *out)
{
    (void)ctx;
    memset(out, 0, sizeof *out);
    if (d.y > 0.12f) /* the home camera looks down -z: the top of the plane is background */
        return;
    out->hit = true;
    out->point = v3_add(o, v3_scale(d, 5.f));
    if (d.x < 0.f) {
        out->geom_id = 10;
        out->prim_id = 7;
        snprintf(out->what, sizeof out->what, "part asm/sec-1/frame-2/bolt-3 triangle 7");
        out->part = part(10, 1, "asm/sec-1/frame-2/bolt-3");
        out->ancestors[0] = part(8, 4, "asm/sec-1/frame-2");
        out->ancestors[1] = part(5, 20, "asm/sec-1");
        out->ancestors[2] = part(0, 100, "asm");
        out->ancestor_count = 3;
    } else {
        out->geom_id = 50;
        out->prim_id = 2;
        snprintf(out->what, sizeof out->what, "part asm/sec-2/skin-1 triangle 2");
        out->part = part(50, 1, "asm/sec-2/skin-1");
        out->ancestors[0] = part(40, 30, "asm/sec-2");
        out->ancestors[1] = part(0, 100, "asm");
        out->ancestor_count = 2;
    }
}

static void rig_emit(void *ctx, const input_txn *t)
{
    rig *r = ctx;
    cr_assert(r->count < MAX_TXNS);
    r->txns[r->count++] = *t;
}

static camera_desc home(void)
{
    return (camera_desc){v3(0.f, 0.f, 6.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
}

static camera_desc rig_current(void *ctx)
{
    (void)ctx;
    return home();
}

static rig *rig_make(const input_bindings *b)
{
    rig *r = calloc(1, sizeof *r);
    cr_assert(r);
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    if (b)
        cfg.bindings = *b;
    cfg.plane_aspect = ASPECT;
    cfg.home = home();
    cfg.scene_size = 4.0;
    input_controller_hooks hooks = {.ctx = r, .pick = fake_pick, .emit = rig_emit, .current_camera = rig_current};
    r->c = input_controller_create(&cfg, &hooks);
    cr_assert(r->c);
    r->now_us = 1000000;
    input_controller_tick(r->c, r->now_us);
    return r;
}

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

/* A key or button pressed and released; the transactions it made start at
 * the returned index. */
static int press(rig *r, int code)
{
    int at = r->count;
    input_event_kind kind = code >= BTN_MISC && code < KEY_OK ? INPUT_BUTTON : INPUT_KEY;
    send(r, (input_event){.kind = kind, .code = code, .pressed = true});
    frame(r);
    send(r, (input_event){.kind = kind, .code = code, .pressed = false});
    frame(r);
    return at;
}

static void move_to(rig *r, double x, double y)
{
    send(r, (input_event){.kind = INPUT_POINTER_ABS, .x = x, .y = y});
    frame(r);
}

static void touch(rig *r, input_event_kind kind, int slot, double x, double y)
{
    send(r, (input_event){.kind = kind, .slot = slot, .x = x, .y = y});
}

static void touch_frame(rig *r)
{
    send(r, (input_event){.kind = INPUT_TOUCH_FRAME});
    r->now_us += 10000;
}

/* Time passes as the input thread lets it: ticks at the controller's own
 * deadlines (input/runner.c). */
static void tick_for(rig *r, double seconds)
{
    uint64_t end = r->now_us + (uint64_t)(seconds * 1e6);
    for (int guard = 0;; guard++) {
        cr_assert(guard < 100000, "the controller's deadline never moves on");
        uint64_t due = input_controller_deadline_us(r->c, r->now_us);
        if (due > end)
            break;
        if (due > r->now_us)
            r->now_us = due;
        input_controller_tick(r->c, r->now_us);
    }
    r->now_us = end;
}

/* The transactions from index `from` on but cursor and camera, as their
 * text forms joined by " | " (status texts included). */
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

static int count_kind(const rig *r, int from, txn_kind k)
{
    int n = 0;
    for (int i = from; i < r->count; i++)
        n += r->txns[i].kind == k;
    return n;
}

#define LEFT -0.5, 0.0  /* over the bolt */
#define RIGHT 0.5, 0.0  /* over the skin */
#define SKY 0.0, 0.9    /* background */

/* ---- keys and buttons ------------------------------------------------------------ */

Test(input_parts, pick_hide_show_isolate_and_show_all_by_keys)
{
    rig *r = rig_make(NULL);
    move_to(r, LEFT);
    int at = press(r, KEY_P);
    cr_expect(strstr(made_since(r, at), "status \"picked part asm/sec-1/frame-2/bolt-3 triangle 7 at ("),
              "%s", made_since(r, at));
    cr_expect_str_eq(made_since(r, press(r, KEY_H)), "hide 10 1 | status \"hidden: asm/sec-1/frame-2/bolt-3\"");
    move_to(r, RIGHT);
    cr_expect_str_eq(made_since(r, press(r, KEY_H)), "hide 50 1 | status \"hidden: asm/sec-2/skin-1\"");
    /* show (Z) undoes the hides, the last first */
    cr_expect_str_eq(made_since(r, press(r, KEY_Z)), "show 50 1 | status \"shown: asm/sec-2/skin-1\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_Z)), "show 10 1 | status \"shown: asm/sec-1/frame-2/bolt-3\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_Z)), "status \"nothing hidden to show\"");
    /* isolate (I) acts on the selection (the bolt, picked above), not on the part under the cursor */
    cr_expect_str_eq(made_since(r, press(r, KEY_I)),
                     "isolate 10 1 | status \"isolated: asm/sec-1/frame-2/bolt-3 (1 instance)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_U)), "show-all | status \"all parts shown\"");
    /* show-all forgets the hidden parts */
    press(r, KEY_H);
    press(r, KEY_U);
    cr_expect_str_eq(made_since(r, press(r, KEY_Z)), "status \"nothing hidden to show\"");
    move_to(r, SKY);
    cr_expect_str_eq(made_since(r, press(r, KEY_H)), "status \"nothing to hide there\"");
    rig_free(r);
}

Test(input_parts, select_parent_widens_the_selection_up_to_the_top)
{
    rig *r = rig_make(NULL);
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"nothing selected (pick a part first)\"");
    move_to(r, LEFT);
    press(r, KEY_P);
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"selected: asm/sec-1/frame-2 (4 instances)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"selected: asm/sec-1 (20 instances)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_I)), "isolate 5 20 | status \"isolated: asm/sec-1 (20 instances)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"selected: asm (100 instances)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)),
                     "status \"selected: asm (100 instances; no parent above it)\"");
    /* a new pick starts again at the part picked */
    move_to(r, RIGHT);
    press(r, KEY_P);
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"selected: asm/sec-2 (30 instances)\"");
    /* hide-object acts on the part under the cursor, whatever is selected */
    cr_expect_str_eq(made_since(r, press(r, KEY_H)), "hide 50 1 | status \"hidden: asm/sec-2/skin-1\"");
    /* a pick of the background clears the selection */
    move_to(r, SKY);
    press(r, KEY_P);
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"nothing selected (pick a part first)\"");
    rig_free(r);
}

Test(input_parts, isolate_without_a_selection_takes_the_part_under_the_cursor)
{
    rig *r = rig_make(NULL);
    move_to(r, SKY);
    cr_expect_str_eq(made_since(r, press(r, KEY_I)), "status \"nothing to isolate there\"");
    move_to(r, RIGHT);
    cr_expect_str_eq(made_since(r, press(r, KEY_I)), "isolate 50 1 | status \"isolated: asm/sec-2/skin-1 (1 instance)\"");
    /* ... and selects it */
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"selected: asm/sec-2 (30 instances)\"");
    rig_free(r);
}

Test(input_parts, the_highlight_follows_the_selection)
{
    rig *r = rig_make(NULL);
    cr_expect_str_eq(made_since(r, press(r, KEY_L)), "status \"nothing selected to highlight (pick a part first)\"");
    move_to(r, RIGHT);
    press(r, KEY_P);
    cr_expect_str_eq(made_since(r, press(r, KEY_L)), "highlight 50 1 1 | status \"highlighted: asm/sec-2/skin-1\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)),
                     "highlight 50 1 0 | highlight 40 30 1 | status \"selected: asm/sec-2 (30 instances)\"");
    /* a new pick moves it to the part picked */
    move_to(r, LEFT);
    int at = press(r, KEY_P);
    cr_expect(strncmp(made_since(r, at), "highlight 40 30 0 | highlight 10 1 1 | status \"picked part", 57) == 0, "%s",
              made_since(r, at));
    cr_expect_str_eq(made_since(r, press(r, KEY_L)), "highlight 10 1 0 | status \"highlight off: asm/sec-1/frame-2/bolt-3\"");
    /* off: selections change no highlight */
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"selected: asm/sec-1/frame-2 (4 instances)\"");
    /* on, then a pick of nothing: the highlight goes */
    press(r, KEY_L);
    move_to(r, SKY);
    at = press(r, KEY_P);
    cr_expect_str_eq(made_since(r, at), "highlight 8 4 0 | status \"picked nothing (background)\"");
    rig_free(r);
}

Test(input_parts, part_actions_on_pointer_buttons_and_a_click)
{
    input_bindings b;
    input_bindings_default(&b);
    b.code_action[BTN_SIDE] = INPUT_ACTION_ISOLATE;
    b.code_action[BTN_EXTRA] = INPUT_ACTION_SHOW_ALL;
    b.gesture_action[INPUT_GESTURE_CLICK] = INPUT_ACTION_HIDE_OBJECT;
    rig *r = rig_make(&b);
    move_to(r, LEFT);
    cr_expect_str_eq(made_since(r, press(r, BTN_LEFT)), "hide 10 1 | status \"hidden: asm/sec-1/frame-2/bolt-3\"");
    move_to(r, RIGHT);
    cr_expect_str_eq(made_since(r, press(r, BTN_SIDE)), "isolate 50 1 | status \"isolated: asm/sec-2/skin-1 (1 instance)\"");
    cr_expect_str_eq(made_since(r, press(r, BTN_EXTRA)), "show-all | status \"all parts shown\"");
    rig_free(r);
}

/* A pick hook that names no part (as before parts): the instance hit is one. */
static void partless_pick(void *ctx, vec3 o, vec3 d, input_hit *out)
{
    (void)ctx;
    memset(out, 0, sizeof *out);
    out->hit = true;
    out->point = v3_add(o, v3_scale(d, 5.f));
    out->geom_id = 3;
    snprintf(out->what, sizeof out->what, "mesh 3 'bunny' triangle 9");
}

Test(input_parts, a_pick_without_parts_acts_on_the_instance_hit)
{
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    rig *r = calloc(1, sizeof *r);
    cr_assert(r);
    input_controller_hooks hooks = {.ctx = r, .pick = partless_pick, .emit = rig_emit, .current_camera = rig_current};
    r->c = input_controller_create(&cfg, &hooks);
    r->now_us = 1000000;
    cr_expect_str_eq(made_since(r, press(r, KEY_H)), "hide 3 1 | status \"hidden: mesh 3 'bunny' triangle 9\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_I)), "isolate 3 1 | status \"isolated: mesh 3 'bunny' triangle 9 (1 instance)\"");
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)),
                     "status \"selected: mesh 3 'bunny' triangle 9 (1 instance; no parent above it)\"");
    rig_free(r);
}

/* ---- touch -------------------------------------------------------------------------- */

Test(input_parts, a_long_press_selects_and_isolates_the_part_under_the_finger)
{
    rig *r = rig_make(NULL);
    int at = r->count;
    uint64_t down_us = r->now_us;
    touch(r, INPUT_TOUCH_DOWN, 0, LEFT);
    touch_frame(r);
    /* the input thread is asked to wake at the long press's time, on the events' clock */
    cr_expect_eq(input_controller_deadline_us(r->c, r->now_us), down_us + (uint64_t)(INPUT_LONG_PRESS_S * 1e6));
    tick_for(r, INPUT_LONG_PRESS_S - 0.1);
    /* a wobble within the tap slop keeps it a press */
    touch(r, INPUT_TOUCH_MOTION, 0, -0.505, 0.004);
    touch_frame(r);
    cr_expect_str_eq(made_since(r, at), "", "before 0.6 s: %s", made_since(r, at));
    tick_for(r, 0.2);
    cr_expect_str_eq(made_since(r, at), "isolate 10 1 | status \"isolated: asm/sec-1/frame-2/bolt-3 (1 instance)\"");
    /* the finger then moves and lifts: no orbit, no tap, no second press */
    at = r->count;
    touch(r, INPUT_TOUCH_MOTION, 0, -0.2, 0.1);
    touch_frame(r);
    tick_for(r, 1.0);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect_eq(r->count, at, "after the long press: %s", made_since(r, at));
    /* it selected: select-parent widens from the bolt */
    cr_expect_str_eq(made_since(r, press(r, KEY_BACKSPACE)), "status \"selected: asm/sec-1/frame-2 (4 instances)\"");
    /* a long press on another part isolates that one, though something is selected */
    at = r->count;
    touch(r, INPUT_TOUCH_DOWN, 0, RIGHT);
    touch_frame(r);
    tick_for(r, 0.7);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect_str_eq(made_since(r, at), "isolate 50 1 | status \"isolated: asm/sec-2/skin-1 (1 instance)\"");
    rig_free(r);
}

/* The input thread read the down and the up together, 1 s apart on the
 * events' clock, with no tick between: still a long press. */
Test(input_parts, a_press_read_late_is_timed_by_the_events)
{
    rig *r = rig_make(NULL);
    int at = r->count;
    touch(r, INPUT_TOUCH_DOWN, 0, RIGHT);
    touch_frame(r);
    r->now_us += 1000000;
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect_str_eq(made_since(r, at), "isolate 50 1 | status \"isolated: asm/sec-2/skin-1 (1 instance)\"");
    rig_free(r);
}

Test(input_parts, a_finger_that_moves_or_lifts_early_is_no_long_press)
{
    rig *r = rig_make(NULL);
    int at = r->count;
    /* moved beyond the slop: an orbit */
    touch(r, INPUT_TOUCH_DOWN, 0, LEFT);
    touch_frame(r);
    touch(r, INPUT_TOUCH_MOTION, 0, -0.4, 0.05);
    touch_frame(r);
    tick_for(r, 1.0);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect_eq(count_kind(r, at, TXN_ISOLATE), 0);
    cr_expect_gt(count_kind(r, at, TXN_CAMERA), 0, "no orbit");
    cr_expect_eq(input_controller_deadline_us(r->c, r->now_us), UINT64_MAX, "still waiting for something");
    /* lifted after 0.4 s: nothing (too long for a tap, too short for a press) */
    at = r->count;
    touch(r, INPUT_TOUCH_DOWN, 0, LEFT);
    touch_frame(r);
    tick_for(r, 0.4);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    tick_for(r, 1.0);
    cr_expect_str_eq(made_since(r, at), "");
    /* two fingers held still: no long press either */
    touch(r, INPUT_TOUCH_DOWN, 0, LEFT);
    touch(r, INPUT_TOUCH_DOWN, 1, RIGHT);
    touch_frame(r);
    tick_for(r, 1.0);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch(r, INPUT_TOUCH_UP, 1, 0, 0);
    touch_frame(r);
    cr_expect_str_eq(made_since(r, at), "");
    rig_free(r);
}

Test(input_parts, a_two_finger_tap_shows_all)
{
    rig *r = rig_make(NULL);
    move_to(r, LEFT);
    press(r, KEY_H);
    int at = r->count;
    touch(r, INPUT_TOUCH_DOWN, 0, LEFT);
    touch_frame(r);
    touch(r, INPUT_TOUCH_DOWN, 1, RIGHT);
    touch_frame(r);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch(r, INPUT_TOUCH_UP, 1, 0, 0);
    touch_frame(r);
    cr_expect_str_eq(made_since(r, at), "show-all | status \"all parts shown\"");
    cr_expect_eq(count_kind(r, at, TXN_CAMERA), 0);
    /* one finger's tap is still a pick */
    at = r->count;
    r->now_us += 1000000;
    touch(r, INPUT_TOUCH_DOWN, 0, RIGHT);
    touch_frame(r);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect(strstr(made_since(r, at), "picked part asm/sec-2/skin-1 triangle 2"), "%s", made_since(r, at));
    rig_free(r);
}

/* ---- the command line's pick hook on the shipped assembly --------------------------- */

#define BOLT "assembly/section-1/frame-3/bracket-1/bolt-1"

Test(input_parts, picking_the_shipped_assembly_names_the_bolt_and_its_subtree)
{
    tess_error err = {{0}};
    scene *s = scene_load("data/assembly-small.glb", &err);
    cr_assert(s, "%s", err.msg);
    cr_assert(s->parts);
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    int32_t bolt = part_tree_find(s->parts, BOLT);
    cr_assert_neq(bolt, PART_NONE);
    uint32_t first, end;
    scene_part_instances(s, (uint32_t)bolt, &first, &end);
    cr_assert_eq(end - first, 1u, "the bolt has one instance");
    int32_t bracket = part_tree_parent(s->parts, bolt);
    uint32_t bfirst, bend;
    scene_part_instances(s, (uint32_t)bracket, &bfirst, &bend);
    cr_assert_eq(bend - bfirst, 4u, "the bracket and its 3 bolts");

    /* only the bolt shown (so nothing stands in front of it), a ray at its box's centre from outside */
    uint32_t n = s->instance_count;
    accel_set_hidden_range(a, 0, first, true);
    accel_set_hidden_range(a, end, n - end, true);
    accel_commit(a);
    aabb box;
    cr_assert(scene_instance_bounds(s, first, &box));
    vec3 centre = v3_scale(v3_add(box.lo, box.hi), 0.5f);
    static const float dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    input_hit h = {.hit = false};
    for (int i = 0; i < 6 && !h.hit; i++) {
        vec3 d = v3(dirs[i][0], dirs[i][1], dirs[i][2]);
        cli_input_pick(s, a, v3_sub(centre, v3_scale(d, 100.f)), d, &h);
    }
    cr_assert(h.hit, "no ray at the bolt's centre hit it");
    cr_expect_eq(h.geom_id, first);
    char want[128];
    snprintf(want, sizeof want, "part " BOLT " triangle %u", h.prim_id);
    cr_expect_str_eq(h.what, want);
    cr_expect_str_eq(h.part.label, BOLT);
    cr_expect_eq(h.part.first, first);
    cr_expect_eq(h.part.count, 1u);
    /* its ancestors up to the top-level part, each its subtree's range */
    cr_assert_eq(h.ancestor_count, 4);
    static const char *const up[] = {"assembly/section-1/frame-3/bracket-1", "assembly/section-1/frame-3",
                                     "assembly/section-1", "assembly"};
    for (int i = 0; i < 4; i++) {
        int32_t id = part_tree_find(s->parts, up[i]);
        uint32_t f, e;
        scene_part_instances(s, (uint32_t)id, &f, &e);
        cr_expect_str_eq(h.ancestors[i].label, up[i]);
        cr_expect_eq(h.ancestors[i].first, f, "%s", up[i]);
        cr_expect_eq(h.ancestors[i].count, e - f, "%s", up[i]);
    }
    cr_expect_eq(h.ancestors[0].first, bfirst);
    cr_expect_eq(h.ancestors[3].count, n, "the top-level part holds every instance");
    /* a miss */
    cli_input_pick(s, a, v3_add(box.hi, v3(1e4f, 1e4f, 1e4f)), v3(1.f, 0.f, 0.f), &h);
    cr_expect(!h.hit);
    accel_destroy(a);
    scene_destroy(s);
}

Test(input_parts, picking_a_scene_without_parts_names_the_geometry)
{
    scene *s = scene_create();
    cr_assert(s);
    cr_assert_geq(scene_add_sphere(s, v3(0.f, 0.f, 0.f), 1.f, 0), 0);
    cr_assert_geq(scene_add_sphere(s, v3(5.f, 0.f, 0.f), 1.f, 0), 0);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    input_hit h;
    cli_input_pick(s, a, v3(5.f, 0.f, 10.f), v3(0.f, 0.f, -1.f), &h);
    cr_assert(h.hit);
    cr_expect_str_eq(h.what, "sphere 1");
    cr_expect_str_eq(h.part.label, "the sphere set (2 spheres)");
    cr_expect_eq(h.part.first, h.geom_id);
    cr_expect_eq(h.part.count, 1u);
    cr_expect_eq(h.ancestor_count, 0);
    accel_destroy(a);
    scene_destroy(s);
}

/* A path longer than a label keeps its tail after "...", in the label and in
 * `what` (whose primitive stays whole). */
Test(input_parts, a_long_path_keeps_its_tail)
{
    scene *s = scene_create();
    cr_assert(s);
    cr_assert(s->parts = part_tree_create());
    mesh *m = mesh_create();
    cr_assert(m);
    cr_assert(mesh_add_vertex(m, -1.f, -1.f, 0.f) && mesh_add_vertex(m, 1.f, -1.f, 0.f) &&
              mesh_add_vertex(m, 0.f, 1.f, 0.f) && mesh_add_triangle(m, 0, 1, 2));
    int geom = scene_add_mesh_geometry(s, m, 0, "tri");
    cr_assert_geq(geom, 0);
    tess_error err = {{0}};
    char name[64];
    int32_t part = PART_ROOT;
    for (int depth = 0; depth < 6; depth++) { /* 6 names of 40 bytes: a 245-byte path */
        snprintf(name, sizeof name, "level-%d-%033d", depth, depth);
        part = part_tree_add(s->parts, part, name, &err);
        cr_assert_neq(part, PART_NONE, "%s", err.msg);
    }
    cr_assert_geq(scene_add_instance(s, (uint32_t)geom, NULL, (uint32_t)part), 0);
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    input_hit h;
    cli_input_pick(s, a, v3(0.f, 0.f, 5.f), v3(0.f, 0.f, -1.f), &h);
    cr_assert(h.hit);
    char path[512];
    size_t n = part_tree_path(s->parts, part, path, sizeof path);
    cr_assert_gt(n, sizeof h.part.label);
    cr_expect_eq(strlen(h.part.label), sizeof h.part.label - 1);
    cr_expect(strncmp(h.part.label, "...", 3) == 0, "%s", h.part.label);
    cr_expect_str_eq(h.part.label + 3, path + n - (sizeof h.part.label - 4));
    cr_expect(strncmp(h.what, "part ...", 8) == 0, "%s", h.what);
    cr_expect_eq(strlen(h.what), sizeof h.what - 1, "%s", h.what);
    char end[96];
    snprintf(end, sizeof end, "/%s triangle 0", name); /* the last name made */
    cr_expect_str_eq(h.what + strlen(h.what) - strlen(end), end, "%s", h.what);
    cr_expect_eq(h.ancestor_count, 5);
    snprintf(name, sizeof name, "level-%d-%033d", 0, 0);
    cr_expect_str_eq(h.ancestors[4].label, name);
    accel_destroy(a);
    scene_destroy(s);
}
