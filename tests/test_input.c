/* test_input.c - the input mapping layer (input/controller.h) fed synthetic
 * libinput-like events, the placement of absolute devices on the wall's plane
 * (input/source.h), the record file (input/record.h), and record -> replay
 * through a running pipeline giving the same camera bit for bit
 * (input/sink.h). */
#include <criterion/criterion.h>
#include <fcntl.h>
#include <linux/input-event-codes.h>
#include <math.h>
#include <pthread.h>
#include <time.h>
#include <stdio.h>
#include <stdlib.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/base/camera.h"
#include "engine/frame/camera_path.h"
#include "engine/base/clock.h"
#include "engine/frame/pipeline.h"
#include "engine/scene/scene.h"
#include "input/controller.h"
#include "input/navigate.h"
#include "input/record.h"
#include "input/runner.h"
#include "input/sink.h"
#include "input/source.h"
#include "remote/source.h"
#include "support.h"
#include "wall/display_backend.h"
#include "wall/wall_config.h"
#include "wall/wall_headless.h"

#define ASPECT (16.f / 9.f)
#define MAX_TXNS 8192

/* ---- a world to pick in: a unit sphere at the origin (geometry 0) on a
 * floor y = -1 (geometry 1), scaled by `scale` ---------------------------- */
typedef struct rig {
    input_txn txns[MAX_TXNS];
    int count;
    camera_desc shown;  /* what "the wall" shows: the last camera emitted */
    double scale;
    input_controller *c;
    uint64_t now_us;
} rig;

static void rig_pick(void *ctx, vec3 o, vec3 d, input_hit *out)
{
    rig *r = ctx;
    double s = r->scale;
    *out = (input_hit){.hit = false};
    /* sphere |p| = s (d is unit) */
    double b = v3_dot(o, d), cc = v3_dot(o, o) - s * s, disc = b * b - cc;
    if (disc >= 0.0) {
        double t = -b - sqrt(disc);
        if (t > 0.0) {
            out->hit = true;
            out->point = v3_add(o, v3_scale(d, (float)t));
            out->geom_id = 0;
            snprintf(out->what, sizeof out->what, "sphere");
            snprintf(out->part.label, sizeof out->part.label, "the sphere set");
            return;
        }
    }
    if (d.y < 0.f && o.y > -s) {
        double t = (-s - o.y) / d.y;
        out->hit = true;
        out->point = v3_add(o, v3_scale(d, (float)t));
        out->geom_id = 1;
        snprintf(out->what, sizeof out->what, "floor");
    }
}

static void rig_emit(void *ctx, const input_txn *t)
{
    rig *r = ctx;
    cr_assert(r->count < MAX_TXNS);
    r->txns[r->count++] = *t;
    if (t->kind == TXN_CAMERA)
        r->shown = t->args.camera.camera;
}

static camera_desc rig_current(void *ctx) { return ((rig *)ctx)->shown; }

static camera_desc home_camera(double s)
{
    return (camera_desc){v3(0.f, (float)(0.5 * s), (float)(6.0 * s)), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
}

static rig *rig_make(double scale, bool tour, double idle_s)
{
    rig *r = calloc(1, sizeof *r);
    cr_assert(r);
    r->scale = scale;
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.plane_aspect = ASPECT;
    cfg.home = home_camera(scale);
    cfg.scene_size = 4.0 * scale;
    cfg.have_tour = tour;
    cfg.idle_timeout_s = idle_s;
    r->shown = cfg.home;
    input_controller_hooks hooks = {.ctx = r, .pick = rig_pick, .emit = rig_emit, .current_camera = rig_current};
    r->c = input_controller_create(&cfg, &hooks);
    cr_assert(r->c);
    r->now_us = 1000000;
    input_controller_tick(r->c, r->now_us); /* the first tick (starts a tour when there is one) */
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

static void key(rig *r, int code, bool down)
{
    send(r, (input_event){.kind = INPUT_KEY, .code = code, .pressed = down});
    frame(r);
}

static void button(rig *r, int code, bool down)
{
    send(r, (input_event){.kind = INPUT_BUTTON, .code = code, .pressed = down});
    frame(r);
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

/* Time passes as the input thread lets it (input/runner.c): ticks at the
 * controller's own deadlines only, so a deadline that never comes due fails. */
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
        cr_assert(input_controller_deadline_us(r->c, r->now_us) > r->now_us || guard < 3,
                  "the controller wants a tick now, again");
    }
    r->now_us = end;
}

static int count_kind(const rig *r, input_txn_kind k)
{
    int n = 0;
    for (int i = 0; i < r->count; i++)
        n += r->txns[i].kind == k;
    return n;
}

static const input_txn *last_kind(const rig *r, input_txn_kind k)
{
    for (int i = r->count - 1; i >= 0; i--)
        if (r->txns[i].kind == k)
            return &r->txns[i];
    return NULL;
}

/* ---- remote viewers: pointers and the camera holder (controller.h) ---- */

static void on_device(rig *r, int device, input_event e)
{
    e.device = device;
    send(r, e);
}

static void device_frame(rig *r, int device)
{
    on_device(r, device, (input_event){.kind = INPUT_FRAME});
    r->now_us += 8000;
}

/* A viewer's pointer events become one "pointer" record a slot a frame,
 * and move neither the cursor nor the camera. */
Test(input, viewer_pointers_become_pointer_records)
{
    rig *r = rig_make(1.0, false, 0.0);
    on_device(r, 1003, (input_event){.kind = INPUT_VIEWER_POINTER, .slot = 3, .pressed = true, .x = 0.5, .y = 0.5});
    on_device(r, 1003, (input_event){.kind = INPUT_VIEWER_POINTER, .slot = 3, .pressed = true, .x = 0.25, .y = -0.5});
    device_frame(r, 1003);
    cr_assert_eq(count_kind(r, TXN_POINTER), 1, "coalesced to one record a frame");
    const input_txn *t = last_kind(r, TXN_POINTER);
    cr_assert(t->args.pointer.slot == 3 && t->args.pointer.on);
    cr_assert_float_eq(t->args.pointer.sx, 0.25f, 0.f);
    cr_assert_float_eq(t->args.pointer.sy, -0.5f, 0.f);
    device_frame(r, 1003); /* nothing changed: nothing emitted */
    cr_assert_eq(count_kind(r, TXN_POINTER), 1);
    on_device(r, 1003, (input_event){.kind = INPUT_VIEWER_POINTER, .slot = 3, .pressed = false});
    device_frame(r, 1003);
    cr_assert_eq(count_kind(r, TXN_POINTER), 2);
    cr_assert_not(last_kind(r, TXN_POINTER)->args.pointer.on);
    cr_assert_eq(count_kind(r, TXN_CURSOR), 0, "the wall's cursor stays where it was");
    cr_assert_eq(count_kind(r, TXN_CAMERA), 0);
    rig_free(r);
}

/* A mouse drag (device 1) holds the camera: a touch drag (device 2) at the
 * same time moves nothing; after the mouse lets go and the hold time passes,
 * the touch's next motion takes the camera. */
Test(input, one_device_holds_the_camera_at_a_time)
{
    rig *r = rig_make(1.0, false, 0.0);
    on_device(r, 1, (input_event){.kind = INPUT_POINTER_ABS, .x = 0.0, .y = 0.0});
    on_device(r, 1, (input_event){.kind = INPUT_BUTTON, .code = BTN_LEFT, .pressed = true});
    device_frame(r, 1);
    on_device(r, 1, (input_event){.kind = INPUT_POINTER_ABS, .x = 0.1, .y = 0.0});
    device_frame(r, 1);
    int cameras = count_kind(r, TXN_CAMERA);
    cr_assert_eq(cameras, 1, "the holder's drag moves the camera");
    on_device(r, 2, (input_event){.kind = INPUT_TOUCH_DOWN, .slot = 0, .x = 0.0, .y = 0.0});
    on_device(r, 2, (input_event){.kind = INPUT_TOUCH_FRAME});
    for (int i = 1; i <= 5; i++) {
        on_device(r, 2, (input_event){.kind = INPUT_TOUCH_MOTION, .slot = 0, .x = 0.05 * i, .y = 0.03 * i});
        on_device(r, 2, (input_event){.kind = INPUT_TOUCH_FRAME});
        r->now_us += 10000;
    }
    cr_assert_eq(count_kind(r, TXN_CAMERA), cameras, "another device's touch drag while the mouse holds the camera");
    on_device(r, 1, (input_event){.kind = INPUT_POINTER_ABS, .x = 0.2, .y = 0.0});
    device_frame(r, 1);
    cr_assert_eq(count_kind(r, TXN_CAMERA), cameras + 1, "the holder still steers");
    on_device(r, 1, (input_event){.kind = INPUT_BUTTON, .code = BTN_LEFT, .pressed = false});
    device_frame(r, 1);
    cameras = count_kind(r, TXN_CAMERA);
    on_device(r, 2, (input_event){.kind = INPUT_TOUCH_MOTION, .slot = 0, .x = 0.4, .y = 0.2});
    on_device(r, 2, (input_event){.kind = INPUT_TOUCH_FRAME});
    cr_assert_eq(count_kind(r, TXN_CAMERA), cameras, "within the hold time after the release");
    r->now_us += (uint64_t)(INPUT_CAMERA_HOLD_S * 1e6) + 1000;
    on_device(r, 2, (input_event){.kind = INPUT_TOUCH_MOTION, .slot = 0, .x = 0.5, .y = 0.3});
    on_device(r, 2, (input_event){.kind = INPUT_TOUCH_FRAME});
    cr_assert_eq(count_kind(r, TXN_CAMERA), cameras + 1, "the hold is over: the touch steers");
    on_device(r, 1, (input_event){.kind = INPUT_SCROLL, .dy = 1.0});
    device_frame(r, 1);
    cr_assert_eq(count_kind(r, TXN_CAMERA), cameras + 1, "now the mouse's wheel is the one refused");
    rig_free(r);
}

/* A holder that goes away (a viewer that disconnected) lets go at once;
 * commands other than camera motion are never held back. */
Test(input, a_removed_holder_lets_go_and_commands_still_apply)
{
    rig *r = rig_make(1.0, false, 0.0);
    on_device(r, 1001, (input_event){.kind = INPUT_POINTER_ABS, .x = 0.0, .y = 0.0});
    on_device(r, 1001, (input_event){.kind = INPUT_BUTTON, .code = BTN_LEFT, .pressed = true});
    device_frame(r, 1001);
    on_device(r, 1001, (input_event){.kind = INPUT_POINTER_ABS, .x = 0.1, .y = 0.1});
    device_frame(r, 1001);
    int cameras = count_kind(r, TXN_CAMERA);
    cr_assert_eq(cameras, 1);
    int before = r->count;
    on_device(r, 3, (input_event){.kind = INPUT_KEY, .code = KEY_G, .pressed = true}); /* governor-status toggle */
    device_frame(r, 3);
    on_device(r, 3, (input_event){.kind = INPUT_KEY, .code = KEY_G, .pressed = false});
    device_frame(r, 3);
    cr_assert_gt(r->count, before, "a key command of another device applies while the camera is held");
    cr_assert_eq(count_kind(r, TXN_CAMERA), cameras);
    on_device(r, 1001, (input_event){.kind = INPUT_DEVICE_REMOVED});
    on_device(r, 3, (input_event){.kind = INPUT_SCROLL, .dy = 1.0});
    device_frame(r, 3);
    cr_assert_eq(count_kind(r, TXN_CAMERA), cameras + 1, "the holder left: the wheel steers at once");
    rig_free(r);
}

/* Plane coordinates of world point p seen by c (camera_basis_window's basis). */
static void project(const camera_desc *c, vec3 p, double *sx, double *sy)
{
    camera_basis b = camera_basis_window(c, ASPECT, CAMERA_WINDOW_FULL, 1600, 900);
    vec3 d = v3_sub(p, b.eye);
    double a = v3_dot(d, b.forward) / v3_dot(b.forward, b.forward);
    *sx = v3_dot(d, b.right) / v3_dot(b.right, b.right) / a;
    *sy = v3_dot(d, b.up) / v3_dot(b.up, b.up) / a;
}

static double dist(vec3 a, vec3 b) { return v3_length(v3_sub(a, b)); }

/* ---- pointer -------------------------------------------------------------------- */

Test(input, left_drag_orbits_about_the_picked_point_keeping_its_distance)
{
    rig *r = rig_make(1.0, false, 0.0);
    move_to(r, 0.02, 0.03); /* over the sphere */
    input_hit h;
    vec3 o, d;
    navigate_plane_ray(&r->shown, ASPECT, 0.02, 0.03, &o, &d);
    rig_pick(r, o, d, &h);
    cr_assert(h.hit && h.geom_id == 0);
    vec3 pivot = h.point;
    double d0 = dist(r->shown.eye, pivot);
    button(r, BTN_LEFT, true);
    int cams_before = count_kind(r, TXN_CAMERA);
    for (int i = 0; i < 60; i++)
        move_to(r, 0.02 + 0.01 * i, 0.03 + 0.004 * i);
    button(r, BTN_LEFT, false);
    /* one camera per frame that moved */
    cr_expect_eq(count_kind(r, TXN_CAMERA) - cams_before, 59);
    camera_desc c = r->shown;
    cr_expect(fabs(dist(c.eye, pivot) - d0) < 1e-5 * d0, "pivot distance %g -> %g", d0, dist(c.eye, pivot));
    cr_expect(dist(c.eye, home_camera(1.0).eye) > 0.5, "the camera did not turn");
    double sx, sy, sx0, sy0;
    camera_desc home = home_camera(1.0);
    project(&home, pivot, &sx0, &sy0);
    project(&c, pivot, &sx, &sy);
    cr_expect(fabs(sx - sx0) < 1e-4 && fabs(sy - sy0) < 1e-4, "pivot moved in the image: (%g %g) -> (%g %g)", sx0,
              sy0, sx, sy);
    /* a drag is no click: nothing was picked */
    cr_expect_eq(count_kind(r, TXN_STATUS), 0);
    rig_free(r);
}

Test(input, one_frame_of_many_motions_gives_one_camera_transaction)
{
    rig *r = rig_make(1.0, false, 0.0);
    move_to(r, 0.0, 0.0);
    button(r, BTN_LEFT, true);
    int before = count_kind(r, TXN_CAMERA), cursors = count_kind(r, TXN_CURSOR);
    for (int i = 1; i <= 25; i++) /* a fast mouse: 25 reports, one frame */
        send(r, (input_event){.kind = INPUT_POINTER_MOTION, .dx = 0.004, .dy = 0.001});
    frame(r);
    cr_expect_eq(count_kind(r, TXN_CAMERA) - before, 1);
    cr_expect_eq(count_kind(r, TXN_CURSOR) - cursors, 1);
    const input_txn *cur = last_kind(r, TXN_CURSOR);
    cr_expect(cur->args.cursor.on && fabsf(cur->args.cursor.sx - 0.1f) < 1e-5f && fabsf(cur->args.cursor.sy - 0.025f) < 1e-5f);
    rig_free(r);
}

Test(input, right_drag_pans_so_the_grabbed_point_follows_the_cursor)
{
    rig *r = rig_make(1.0, false, 0.0);
    move_to(r, -0.05, 0.0);
    input_hit h;
    vec3 o, d;
    navigate_plane_ray(&r->shown, ASPECT, -0.05, 0.0, &o, &d);
    rig_pick(r, o, d, &h);
    cr_assert(h.hit);
    button(r, BTN_RIGHT, true);
    move_to(r, 0.3, -0.2);
    move_to(r, 0.45, -0.3);
    button(r, BTN_RIGHT, false);
    double sx, sy;
    project(&r->shown, h.point, &sx, &sy);
    cr_expect(fabs(sx - 0.45) < 1e-4 && fabs(sy + 0.3) < 1e-4, "grabbed point at (%g, %g), cursor (0.45, -0.3)", sx,
              sy);
    cr_expect(fabs(dist(r->shown.eye, r->shown.look_at) - dist(home_camera(1).eye, home_camera(1).look_at)) < 1e-5);
    rig_free(r);
}

Test(input, wheel_dollies_towards_the_point_under_the_cursor)
{
    rig *r = rig_make(1.0, false, 0.0);
    move_to(r, 0.3, -0.35); /* over the floor */
    input_hit h;
    vec3 o, d;
    navigate_plane_ray(&r->shown, ASPECT, 0.3, -0.35, &o, &d);
    rig_pick(r, o, d, &h);
    cr_assert(h.hit && h.geom_id == 1);
    double d0 = dist(r->shown.eye, h.point);
    send(r, (input_event){.kind = INPUT_SCROLL, .dy = 2.0});
    frame(r);
    double d1 = dist(r->shown.eye, h.point);
    cr_expect(fabs(d1 / d0 - 0.85 * 0.85) < 1e-5, "distance ratio %g, expected 0.7225", d1 / d0);
    double sx, sy;
    project(&r->shown, h.point, &sx, &sy);
    cr_expect(fabs(sx - 0.3) < 1e-4 && fabs(sy + 0.35) < 1e-4, "the point left the cursor: (%g, %g)", sx, sy);
    rig_free(r);
}

Test(input, click_picks_and_reports_the_object)
{
    rig *r = rig_make(1.0, false, 0.0);
    move_to(r, 0.0, 0.0);
    button(r, BTN_LEFT, true);
    button(r, BTN_LEFT, false);
    const input_txn *st = last_kind(r, TXN_STATUS);
    cr_assert(st, "no status after a click");
    cr_expect(strstr(st->args.status.text, "picked sphere at ("), "status '%s'", st->args.status.text);
    move_to(r, 0.95, 0.95); /* background */
    button(r, BTN_LEFT, true);
    button(r, BTN_LEFT, false);
    cr_expect(strstr(last_kind(r, TXN_STATUS)->args.status.text, "nothing"), "status '%s'", last_kind(r, TXN_STATUS)->args.status.text);
    /* hide the object under the cursor, then unhide all */
    move_to(r, 0.0, 0.0);
    key(r, KEY_H, true);
    key(r, KEY_H, false);
    const input_txn *hide = last_kind(r, TXN_HIDE);
    cr_assert(hide);
    cr_expect_eq(hide->args.geoms.first, 0u);
    cr_expect_eq(hide->args.geoms.count, 1u);
    cr_expect_str_eq(last_kind(r, TXN_STATUS)->args.status.text, "hidden: the sphere set");
    key(r, KEY_U, true);
    cr_expect_eq(count_kind(r, TXN_SHOW_ALL), 1);
    /* the governor's line: G shows it, G again hides it */
    key(r, KEY_G, true);
    key(r, KEY_G, false);
    const input_txn *gov = last_kind(r, TXN_GOVERNOR_STATUS);
    cr_assert(gov, "no governor-status transaction for G");
    cr_expect(gov->args.flag.on);
    key(r, KEY_G, true);
    key(r, KEY_G, false);
    cr_expect(!last_kind(r, TXN_GOVERNOR_STATUS)->args.flag.on);
    cr_expect_eq(count_kind(r, TXN_GOVERNOR_STATUS), 2);
    rig_free(r);
}

/* ---- keyboard --------------------------------------------------------------------- */

Test(input, flight_speed_scales_with_the_scene_and_with_plus_minus)
{
    for (int k = 0; k < 2; k++) {
        double scale = k ? 10.0 : 1.0;
        rig *r = rig_make(scale, false, 0.0);
        camera_desc start = r->shown;
        key(r, KEY_W, true);
        tick_for(r, 1.0);
        key(r, KEY_W, false);
        double moved = dist(r->shown.eye, start.eye);
        double expected = 4.0 * scale / 4.0; /* scene_size / 4 per second */
        cr_expect(fabs(moved - expected) < 0.03 * expected, "scale %g: moved %g in 1 s, expected %g", scale, moved,
                  expected);
        /* along the view, look_at carried along */
        vec3 view = v3_normalize(v3_sub(start.look_at, start.eye));
        cr_expect(fabs(v3_dot(v3_sub(r->shown.eye, start.eye), view) - moved) < 1e-4 * expected);
        cr_expect(fabs(dist(r->shown.eye, r->shown.look_at) - dist(start.eye, start.look_at)) < 1e-4 * scale);
        key(r, KEY_EQUAL, true);
        key(r, KEY_EQUAL, false);
        cr_expect(fabs(input_controller_fly_speed(r->c) - 1.5 * scale) < 1e-9 * scale);
        key(r, KEY_MINUS, true);
        key(r, KEY_MINUS, false);
        key(r, KEY_MINUS, true);
        key(r, KEY_MINUS, false);
        cr_expect(fabs(input_controller_fly_speed(r->c) - scale / 1.5) < 1e-9 * scale);
        /* PageUp: up along the up hint */
        camera_desc before = r->shown;
        key(r, KEY_PAGEUP, true);
        tick_for(r, 0.5);
        key(r, KEY_PAGEUP, false);
        vec3 dv = v3_sub(r->shown.eye, before.eye);
        cr_expect(dv.y > 0.9f * v3_length(dv) && v3_length(dv) > 0.2 * scale / 1.5, "PageUp moved (%g %g %g)",
                  (double)dv.x, (double)dv.y, (double)dv.z);
        /* Home: back to the home view exactly */
        key(r, KEY_HOME, true);
        tick_for(r, 1.0);
        cr_expect(memcmp(&r->shown, &start, sizeof start) == 0, "Home did not end at the home view");
        rig_free(r);
    }
}

Test(input, quit_chord_fires_once_and_only_with_all_keys)
{
    rig *r = rig_make(1.0, false, 0.0);
    key(r, KEY_LEFTCTRL, true);
    key(r, KEY_Q, true);
    cr_expect_eq(count_kind(r, TXN_QUIT), 0);
    key(r, KEY_LEFTALT, true);
    cr_expect_eq(count_kind(r, TXN_QUIT), 1);
    key(r, KEY_Q, false);
    key(r, KEY_Q, true);
    cr_expect_eq(count_kind(r, TXN_QUIT), 2);
    rig_free(r);
}

Test(input, a_vanished_device_leaves_no_key_held)
{
    rig *r = rig_make(1.0, false, 0.0);
    send(r, (input_event){.kind = INPUT_KEY, .code = KEY_W, .pressed = true, .device = 3});
    frame(r);
    tick_for(r, 0.1);
    send(r, (input_event){.kind = INPUT_DEVICE_REMOVED, .device = 3});
    camera_desc after_removal = r->shown;
    tick_for(r, 0.5);
    cr_expect(memcmp(&after_removal, &r->shown, sizeof after_removal) == 0, "flight went on after the keyboard left");
    cr_expect_eq(input_controller_deadline_us(r->c, r->now_us), UINT64_MAX);
    rig_free(r);
}

/* ---- touch ----------------------------------------------------------------------------- */

/* Spread two fingers around (cx, cy) from radius r0 to r1 in `steps` frames; returns the camera. */
static camera_desc pinch(double r0, double r1, int steps, double scale)
{
    rig *r = rig_make(scale, false, 0.0);
    double cx = 0.1, cy = -0.05;
    touch(r, INPUT_TOUCH_DOWN, 0, cx - r0, cy);
    touch(r, INPUT_TOUCH_DOWN, 1, cx + r0, cy);
    touch_frame(r);
    for (int i = 1; i <= steps; i++) {
        double rad = r0 + (r1 - r0) * i / steps;
        touch(r, INPUT_TOUCH_MOTION, 0, cx - rad, cy);
        touch(r, INPUT_TOUCH_MOTION, 1, cx + rad, cy);
        touch_frame(r);
    }
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch(r, INPUT_TOUCH_UP, 1, 0, 0);
    touch_frame(r);
    cr_expect_eq(count_kind(r, TXN_CAMERA), steps, "one camera per touch frame");
    cr_expect_eq(count_kind(r, TXN_STATUS), 0, "a pinch is no tap");
    camera_desc c = r->shown;
    rig_free(r);
    return c;
}

Test(input, pinch_depends_only_on_the_spread_ratio)
{
    camera_desc home = home_camera(1.0);
    camera_desc one = pinch(0.1, 0.2, 1, 1.0), many = pinch(0.1, 0.2, 17, 1.0), wide = pinch(0.3, 0.6, 5, 1.0);
    /* doubling the spread halves every distance to the point between the fingers */
    vec3 o, d;
    navigate_plane_ray(&home, ASPECT, 0.1, -0.05, &o, &d);
    input_hit h;
    rig tmp = {.scale = 1.0};
    rig_pick(&tmp, o, d, &h);
    cr_assert(h.hit);
    double ratio = dist(one.eye, h.point) / dist(home.eye, h.point);
    cr_expect(fabs(ratio - 0.5) < 1e-5, "distance ratio %g for a doubled spread", ratio);
    cr_expect(dist(one.eye, many.eye) < 1e-5, "1 step vs 17 steps differ by %g", dist(one.eye, many.eye));
    cr_expect(dist(one.eye, wide.eye) < 1e-5, "spread 0.1->0.2 vs 0.3->0.6 differ by %g", dist(one.eye, wide.eye));
    /* the scene 10 times larger: the same pinch, the camera 10 times farther */
    camera_desc big = pinch(0.1, 0.2, 4, 10.0);
    cr_expect(dist(v3_scale(one.eye, 10.f), big.eye) < 1e-4 * 10, "not scale invariant: %g",
              dist(v3_scale(one.eye, 10.f), big.eye));
}

Test(input, two_finger_drag_pans_and_one_finger_orbits)
{
    rig *r = rig_make(1.0, false, 0.0);
    /* one finger orbits about the point it landed on */
    touch(r, INPUT_TOUCH_DOWN, 0, 0.0, 0.0);
    touch_frame(r);
    vec3 pivot;
    {
        vec3 o, d;
        input_hit h;
        navigate_plane_ray(&r->shown, ASPECT, 0.0, 0.0, &o, &d);
        rig_pick(r, o, d, &h);
        pivot = h.point;
    }
    double d0 = dist(r->shown.eye, pivot);
    for (int i = 1; i <= 20; i++) {
        touch(r, INPUT_TOUCH_MOTION, 0, 0.02 * i, 0.0);
        touch_frame(r);
    }
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect(fabs(dist(r->shown.eye, pivot) - d0) < 1e-5 * d0);
    cr_expect(dist(r->shown.eye, home_camera(1).eye) > 0.3);
    /* two fingers moving together: the point between them follows */
    camera_desc before = r->shown;
    touch(r, INPUT_TOUCH_DOWN, 0, -0.1, 0.0);
    touch(r, INPUT_TOUCH_DOWN, 1, 0.1, 0.0);
    touch_frame(r);
    vec3 o, d;
    input_hit h;
    navigate_plane_ray(&before, ASPECT, 0.0, 0.0, &o, &d);
    rig_pick(r, o, d, &h);
    for (int i = 1; i <= 10; i++) {
        touch(r, INPUT_TOUCH_MOTION, 0, -0.1 + 0.03 * i, 0.02 * i);
        touch(r, INPUT_TOUCH_MOTION, 1, 0.1 + 0.03 * i, 0.02 * i);
        touch_frame(r);
    }
    double sx, sy;
    project(&r->shown, h.point, &sx, &sy);
    cr_expect(fabs(sx - 0.3) < 1e-4 && fabs(sy - 0.2) < 1e-4, "panned point at (%g, %g), fingers' centre (0.3, 0.2)",
              sx, sy);
    rig_free(r);
}

Test(input, tap_picks_and_double_tap_flies_to_the_point)
{
    rig *r = rig_make(1.0, false, 0.0);
    touch(r, INPUT_TOUCH_DOWN, 0, 0.0, 0.0);
    touch_frame(r);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect_eq(count_kind(r, TXN_STATUS), 1);
    cr_expect(strstr(last_kind(r, TXN_STATUS)->args.status.text, "sphere"));
    cr_expect_eq(count_kind(r, TXN_CAMERA), 0, "a tap moved the camera");
    r->now_us += 100000;
    touch(r, INPUT_TOUCH_DOWN, 0, 0.005, 0.004);
    touch_frame(r);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect_eq(count_kind(r, TXN_STATUS), 1, "the second tap of a double tap is no pick");
    vec3 o, d;
    input_hit h;
    navigate_plane_ray(&r->shown, ASPECT, 0.005, 0.004, &o, &d);
    rig_pick(r, o, d, &h);
    double d0 = dist(r->shown.eye, h.point);
    tick_for(r, 1.0);
    cr_expect(memcmp(&r->shown.look_at, &h.point, sizeof h.point) == 0, "fly-to does not look at the tapped point");
    cr_expect(fabs(dist(r->shown.eye, h.point) - 0.5 * d0) < 1e-4 * d0);
    /* two slow taps far apart are two picks */
    r->now_us += 2000000;
    touch(r, INPUT_TOUCH_DOWN, 0, 0.5, 0.5);
    touch_frame(r);
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    cr_expect_eq(count_kind(r, TXN_STATUS), 2);
    rig_free(r);
}

Test(input, touchpad_pinch_and_swipe)
{
    rig *r = rig_make(1.0, false, 0.0);
    move_to(r, 0.0, 0.0);
    vec3 o, d;
    input_hit h;
    navigate_plane_ray(&r->shown, ASPECT, 0.0, 0.0, &o, &d);
    rig_pick(r, o, d, &h);
    double d0 = dist(r->shown.eye, h.point);
    send(r, (input_event){.kind = INPUT_PINCH_BEGIN, .fingers = 2});
    frame(r);
    for (int i = 1; i <= 8; i++) {
        send(r, (input_event){.kind = INPUT_PINCH_UPDATE, .scale = 1.0 + 0.25 * i});
        frame(r);
    }
    send(r, (input_event){.kind = INPUT_PINCH_END});
    frame(r);
    cr_expect(fabs(dist(r->shown.eye, h.point) / d0 - 1.0 / 3.0) < 1e-5, "scale 3 gave distance ratio %g",
              dist(r->shown.eye, h.point) / d0);
    camera_desc before = r->shown;
    send(r, (input_event){.kind = INPUT_SWIPE_BEGIN, .fingers = 3});
    frame(r);
    send(r, (input_event){.kind = INPUT_SWIPE_UPDATE, .dx = 0.1, .dy = 0.0});
    frame(r);
    cr_expect(dist(before.eye, r->shown.eye) > 1e-3, "a swipe did not pan");
    cr_expect(fabs(dist(before.eye, before.look_at) - dist(r->shown.eye, r->shown.look_at)) < 1e-5);
    rig_free(r);
}

/* ---- kiosk --------------------------------------------------------------------------- */

Test(input, idle_tour_starts_stops_on_input_and_comes_back)
{
    rig *r = rig_make(1.0, true, 5.0);
    cr_assert(input_controller_touring(r->c), "a kiosk with a tour starts touring");
    const input_txn *t = last_kind(r, TXN_TOUR);
    cr_assert(t && t->args.flag.on);
    cr_expect_eq(count_kind(r, TXN_STATUS), 0, "no status line to clear, none cleared");
    /* the tour shows some other camera; a touch hands over from it */
    camera_desc tour_cam = {v3(3.f, 1.f, 3.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    r->shown = tour_cam;
    touch(r, INPUT_TOUCH_DOWN, 0, 0.0, 0.0);
    cr_expect(!input_controller_touring(r->c));
    cr_expect(!last_kind(r, TXN_TOUR)->args.flag.on);
    touch_frame(r);
    for (int i = 1; i <= 5; i++) {
        touch(r, INPUT_TOUCH_MOTION, 0, 0.05 * i, 0.0);
        touch_frame(r);
    }
    touch(r, INPUT_TOUCH_UP, 0, 0, 0);
    touch_frame(r);
    /* steering started from the tour's camera, not from home */
    cr_expect(fabs(dist(r->shown.eye, v3(0, 0, 0)) - dist(tour_cam.eye, v3(0, 0, 0))) < 0.5,
              "steering did not start from the tour camera");
    key(r, KEY_P, true); /* a pick puts up a status line */
    key(r, KEY_P, false);
    cr_expect(last_kind(r, TXN_STATUS)->args.status.text[0] != '\0');
    /* idle for less than the timeout: no tour; after it: the tour again */
    uint64_t deadline = input_controller_deadline_us(r->c, r->now_us);
    cr_expect(deadline > r->now_us && deadline <= r->now_us + 5000000);
    tick_for(r, 4.0);
    cr_expect(!input_controller_touring(r->c));
    tick_for(r, 1.2);
    cr_expect(input_controller_touring(r->c));
    cr_expect(last_kind(r, TXN_TOUR)->args.flag.on);
    cr_expect_str_eq(last_kind(r, TXN_STATUS)->args.status.text, "", "the tour left the status line up");
    cr_expect_eq(count_kind(r, TXN_TOUR), 3);
    /* a held button keeps the tour away */
    button(r, BTN_LEFT, true);
    cr_expect(!input_controller_touring(r->c));
    tick_for(r, 7.0);
    cr_expect(!input_controller_touring(r->c), "the tour started under a held button");
    rig_free(r);
}

/* ---- placement of absolute devices on the wall ---------------------------------------- */

Test(input, a_touch_on_the_third_output_lands_on_that_place_of_the_wall)
{
    tess_error err = {{0}};
    wall_config wall;
    cr_assert(wall_config_load("../configs/walls/vm_2x2.json", &wall, &err), "%s", err.msg);
    cr_assert(wall_config_headless_sizes(&wall, &err), "%s", err.msg);
    camera_desc cam = home_camera(1.0);
    float aspect = wall_plane_aspect(&wall);
    camera_window w = wall_output_window(&wall, 2); /* Virtual-3: bottom left */
    camera_basis b = camera_basis_window(&cam, aspect, w, wall.outputs[2].width_px, wall.outputs[2].height_px);
    /* the touchscreen on Virtual-3 touched at the centre of its pixel (100, 300) of 640x480 */
    for (int k = 0; k < 3; k++) {
        int px = k == 0 ? 100 : k == 1 ? 0 : 639, py = k == 0 ? 300 : k == 1 ? 0 : 479;
        double sx, sy;
        input_area_point(&w, (px + 0.5) / 640.0, (py + 0.5) / 480.0, &sx, &sy);
        vec3 o, d;
        navigate_plane_ray(&cam, aspect, sx, sy, &o, &d);
        vec3 want = v3_normalize(camera_pixel_direction(&b, px, py));
        cr_expect(v3_length(v3_sub(d, want)) < 1e-5, "pixel (%d, %d): ray off by %g", px, py,
                  (double)v3_length(v3_sub(d, want)));
    }
    /* and it is the bottom-left quarter of the plane */
    double sx, sy;
    input_area_point(&w, 0.5, 0.5, &sx, &sy);
    cr_expect(sx < -0.3 && sy < -0.3, "centre of Virtual-3 at (%g, %g)", sx, sy);
}

/* ---- the record file -------------------------------------------------------------------- */

Test(input, record_lines_read_back_bit_for_bit)
{
    camera_desc cam = {v3(0.1f, -1e-7f, 3.4028235e38f), v3(1.f / 3.f, 2.f, -7.f), v3(0.f, 1.f, 1e-20f), 39.99999f};
    const float rgb[3] = {0.1f, 2.5f, 1e-30f};
    input_txn in[] = {
        txn_camera(TXN_ALL_CHANNELS, &cam),
        txn_camera(3, &cam),
        txn_cursor(true, -0.3f, 0.7f),
        txn_status("picked mesh 0 'a \"q\" \\ b' \x01\xe9"),
        txn_geoms_record(TXN_HIDE, 4000000000u, 7),
        txn_geoms_record(TXN_SHOW, 5, 1),
        txn_geoms_record(TXN_ISOLATE, 0, 4294967295u),
        txn_simple(TXN_SHOW_ALL),
        txn_highlight(2, 3, true),
        txn_colour(1, 1, rgb),
        txn_colour(1, 2, NULL),
        txn_flag(TXN_SHADOWS, false),
        txn_renderer("eyelight"),
        txn_threads(7),
        txn_channel_active(2, false),
        txn_flag(TXN_TOUR, true),
        txn_simple(TXN_QUIT),
        txn_flag(TXN_GOVERNOR_STATUS, true),
    };
    const size_t n = sizeof in / sizeof in[0];
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    cr_assert(f);
    fprintf(f, "%s\n", INPUT_RECORD_HEADER);
    for (size_t i = 0; i < n; i++)
        cr_assert(input_record_write(f, 0.25 * (double)i, &in[i]));
    fclose(f);
    input_record rec;
    tess_error err = {{0}};
    cr_assert(input_record_parse("rec.txt", buf, len, &rec, &err), "%s\n%s", err.msg, buf);
    cr_assert_eq(rec.count, n);
    for (size_t i = 0; i < n; i++) {
        cr_expect(fabs(rec.entries[i].time_s - 0.25 * (double)i) < 1e-9);
        /* records are built zeroed and read back zeroed: byte for byte, every float bit */
        cr_expect(memcmp(&in[i], &rec.entries[i].txn, sizeof in[i]) == 0, "record %zu (%s) differs", i,
                  txn_kind_name(in[i].kind));
    }
    input_record_free(&rec);
    free(buf);
}

/* Recordings of format 1 still replay: the wall's camera, one geometry hidden, unhide-all. */
Test(input, version_1_records_still_read)
{
    const char text[] = INPUT_RECORD_HEADER_V1 "\n"
                        "0.1 camera 0x1p+0 0 0 0 0 -1 0 1 0 40\n"
                        "0.2 hide 12\n"
                        "0.3 unhide-all\n"
                        "0.4 governor-status 1\n";
    input_record rec;
    tess_error err = {{0}};
    cr_assert(input_record_parse("old.txt", text, strlen(text), &rec, &err), "%s", err.msg);
    cr_assert_eq(rec.count, 4u);
    cr_expect_eq(rec.entries[0].txn.kind, TXN_CAMERA);
    cr_expect_eq(rec.entries[0].txn.args.camera.channel, TXN_ALL_CHANNELS);
    cr_expect_eq(rec.entries[0].txn.args.camera.camera.eye.x, 1.f);
    cr_expect_eq(rec.entries[1].txn.kind, TXN_HIDE);
    cr_expect_eq(rec.entries[1].txn.args.geoms.first, 12u);
    cr_expect_eq(rec.entries[1].txn.args.geoms.count, 1u);
    cr_expect_eq(rec.entries[2].txn.kind, TXN_SHOW_ALL);
    cr_expect(rec.entries[3].txn.args.flag.on);
    input_record_free(&rec);
    /* format 1 has none of the new kinds; format 2 has no unhide-all */
    const char v1_new[] = INPUT_RECORD_HEADER_V1 "\n0.1 show-all\n";
    err = (tess_error){{0}};
    cr_expect(!input_record_parse("old.txt", v1_new, strlen(v1_new), &rec, &err));
    cr_expect(strstr(err.msg, "old.txt:2: unknown transaction kind 'show-all'"), "%s", err.msg);
    const char v2_old[] = INPUT_RECORD_HEADER "\n0.1 unhide-all\n";
    err = (tess_error){{0}};
    cr_expect(!input_record_parse("new.txt", v2_old, strlen(v2_old), &rec, &err));
    cr_expect(strstr(err.msg, "new.txt:2: unknown transaction kind 'unhide-all'"), "%s", err.msg);
}

Test(input, bad_record_files_name_the_line_and_the_problem)
{
    static const struct {
        const char *text, *expect;
    } cases[] = {
        {"", "rec.txt: empty file"},
        {"hello\n", "rec.txt:1: not an input record"},
        {INPUT_RECORD_HEADER_V1 "\n0.1 camera 1 2 3\n", "rec.txt:2: camera look_at.x is missing"},
        {INPUT_RECORD_HEADER "\n0.1 camera all 1 2 3\n", "rec.txt:2: camera look_at.x is missing"},
        {INPUT_RECORD_HEADER "\n0.1 camera 16 1 2 3\n", "rec.txt:2: camera channel: expected all or 0..15, got '16'"},
        {INPUT_RECORD_HEADER "\n0.1 camera all 0 0 0 0 0 0 0 1 0 40\n", "rec.txt:2: camera"},
        {INPUT_RECORD_HEADER "\n0.1 hide 3 0\n", "rec.txt:2: hide: the count must be a whole number >= 1"},
        {INPUT_RECORD_HEADER "\n0.1 colour 3 1 -1 1 0\n", "rec.txt:2: colour: r: -1 is not a finite value >= 0"},
        {INPUT_RECORD_HEADER "\n0.1 renderer pathtracer\n", "rec.txt:2: renderer: name: no renderer 'pathtracer'"},
        {INPUT_RECORD_HEADER "\n0.1 threads 0\n", "rec.txt:2: threads: the count must be a whole number in 1..256"},
        {INPUT_RECORD_HEADER "\n\n# c\n0.1 zoom 3\n", "rec.txt:4: unknown transaction kind 'zoom'"},
        {INPUT_RECORD_HEADER "\n0.5 quit\n0.25 quit\n", "rec.txt:3: time 0.250000 is before"},
        {INPUT_RECORD_HEADER "\n0.1 cursor 2 0 0\n", "rec.txt:2: cursor visibility: expected 0 or 1"},
        {INPUT_RECORD_HEADER "\n0.1 cursor 1 nan 0\n", "rec.txt:2: cursor x: expected a finite number"},
        {INPUT_RECORD_HEADER "\n0.1 cursor 1 0.1 0\n", "rec.txt:2: cursor x: 0.10000000000000001 is not exactly a float"},
        {INPUT_RECORD_HEADER "\n0.1 status \"abc\n", "rec.txt:2: status: the text has no closing quote"},
        {INPUT_RECORD_HEADER "\n0.1 status \"a\\q\"\n", "rec.txt:2: status: unknown escape"},
        {INPUT_RECORD_HEADER "\n0.1 hide -1 1\n", "rec.txt:2: hide: the instance id must be a whole number"},
        {INPUT_RECORD_HEADER_V1 "\n0.1 hide -1\n", "rec.txt:2: hide: the instance id must be a whole number"},
        {INPUT_RECORD_HEADER "\n0.1 tour 1 extra\n", "rec.txt:2: unexpected text after the transaction"},
        {INPUT_RECORD_HEADER "\n-1 quit\n", "rec.txt:2: the time is negative"},
        /* found by fuzzing (tests/fuzz/corpus/record/crash-control-char): words
         * with control characters are quoted as '?', so the message stays one line */
        {INPUT_RECORD_HEADER "\n0.1 hide 3\x14\n", "rec.txt:2: hide instance id: expected a finite number, got '3?'"},
        {INPUT_RECORD_HEADER "\n0.1 zo\x1b[2Jom\r\n", "rec.txt:2: unknown transaction kind 'zo?[2Jom'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        input_record rec = {0};
        tess_error err = {{0}};
        cr_expect(!input_record_parse("rec.txt", cases[i].text, strlen(cases[i].text), &rec, &err), "case %zu parsed",
                  i);
        cr_expect(strstr(err.msg, cases[i].expect), "case %zu: '%s' does not contain '%s'", i, err.msg,
                  cases[i].expect);
    }
    tess_error err = {{0}};
    input_record rec;
    cr_expect(!input_record_load("/nonexistent/rec.txt", &rec, &err));
    cr_expect(strstr(err.msg, "/nonexistent/rec.txt: cannot open"), "%s", err.msg);
}

/* ---- record -> replay through a pipeline ------------------------------------------------ */

typedef struct live {
    scene *scene;
    accel *accel;
    pipeline *p;
    input_sink *sink;
} live;

static live live_make_tour(const char *record_file, int frames, const camera_path *tour, double ease_s)
{
    live l = {0};
    tess_error err = {{0}};
    l.scene = scene_create_default(&err);
    cr_assert(l.scene, "%s", err.msg);
    l.accel = accel_build(l.scene, 1, &err);
    cr_assert(l.accel, "%s", err.msg);
    pipeline_config cfg = pipeline_config_default(l.scene, l.accel);
    cfg.threads = 2;
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE;
    cfg.max_frames = (uint64_t)frames;
    l.p = pipeline_create(&cfg, &err);
    cr_assert(l.p, "%s", err.msg);
    camera_desc cam = home_camera(3.0);
    image_display *d = display_create("null", NULL, false, &err);
    cr_assert(d, "%s", err.msg);
    cr_assert(pipeline_add_channel(l.p, &cam, 32, 18, d, &err) >= 0, "%s", err.msg);
    input_sink_config sc = {.record_file = record_file, .tour = tour, .tour_ease_s = ease_s};
    l.sink = input_sink_create(l.p, &sc, &err);
    cr_assert(l.sink, "%s", err.msg);
    return l;
}

static live live_make(const char *record_file, int frames) { return live_make_tour(record_file, frames, NULL, 0.0); }

static void live_free(live *l)
{
    input_sink_destroy(l->sink);
    pipeline_destroy(l->p);
    accel_destroy(l->accel);
    scene_destroy(l->scene);
}

static void drive_emit(void *ctx, const input_txn *t) { input_sink_emit(ctx, t); }
static camera_desc drive_current(void *ctx) { return input_sink_current_camera(ctx); }
static void drive_pick(void *ctx, vec3 o, vec3 d, input_hit *out)
{
    (void)ctx;
    rig tmp = {.scale = 1.0};
    rig_pick(&tmp, o, d, out);
}

typedef struct run_args {
    pipeline *p;
    bool ok;
    tess_error err;
} run_args;

static void *run_pipeline(void *arg)
{
    run_args *a = arg;
    a->ok = pipeline_run(a->p, &a->err);
    return NULL;
}

static void sleep_ms(int ms)
{
    struct timespec ts = {0, ms * 1000000L};
    nanosleep(&ts, NULL);
}

/* Replay `file` into a fresh pipeline at `speed`; its camera when done. */
static camera_desc replayed_camera(const char *file, input_replay_speed speed, size_t *entries)
{
    input_record rec;
    tess_error err = {{0}};
    cr_assert(input_record_load(file, &rec, &err), "%s", err.msg);
    *entries = rec.count;
    live b = live_make(NULL, speed == INPUT_REPLAY_ALL ? 1 : (int)rec.count + 2);
    cr_assert(input_sink_replay(b.sink, &rec, speed, &err), "%s", err.msg);
    input_record_free(&rec);
    cr_assert(pipeline_run(b.p, &err), "%s", err.msg);
    camera_desc c = pipeline_camera(b.p, 0);
    live_free(&b);
    return c;
}

Test(input, a_recorded_session_replays_to_the_same_camera_bit_for_bit, .timeout = 60)
{
    char dir[256], file[300];
    support_make_tmp_dir(dir, sizeof dir, "input-replay");
    snprintf(file, sizeof file, "%s/rec.txt", dir);
    /* a live session: the controller's transactions go through the sink while frames render */
    live a = live_make(file, 0);
    input_controller_config cfg;
    input_controller_config_default(&cfg);
    cfg.plane_aspect = 32.f / 18.f;
    cfg.home = home_camera(3.0);
    cfg.scene_size = 8.0;
    input_controller_hooks hooks = {.ctx = a.sink, .pick = drive_pick, .emit = drive_emit, .current_camera = drive_current};
    input_controller *c = input_controller_create(&cfg, &hooks);
    cr_assert(c);
    run_args ra = {.p = a.p};
    pthread_t th;
    cr_assert_eq(pthread_create(&th, NULL, run_pipeline, &ra), 0);
    uint64_t t = 1000000;
    input_controller_tick(c, t);
    input_event e = {0};
#define SEND(...) (e = (input_event){__VA_ARGS__}, e.time_us = t, input_controller_event(c, &e))
#define FRAME() (SEND(.kind = INPUT_FRAME), t += 7000, sleep_ms(1))
    SEND(.kind = INPUT_POINTER_ABS, .x = 0.1, .y = 0.05);
    FRAME();
    SEND(.kind = INPUT_BUTTON, .code = BTN_LEFT, .pressed = true);
    FRAME();
    for (int i = 0; i < 40; i++) { /* orbit */
        SEND(.kind = INPUT_POINTER_MOTION, .dx = 0.013, .dy = 0.004);
        SEND(.kind = INPUT_POINTER_MOTION, .dx = 0.006, .dy = -0.001);
        FRAME();
    }
    SEND(.kind = INPUT_BUTTON, .code = BTN_LEFT, .pressed = false);
    FRAME();
    SEND(.kind = INPUT_SCROLL, .dy = 1.0); /* dolly */
    FRAME();
    SEND(.kind = INPUT_BUTTON, .code = BTN_LEFT, .pressed = true); /* click: pick */
    FRAME();
    SEND(.kind = INPUT_BUTTON, .code = BTN_LEFT, .pressed = false);
    FRAME();
    SEND(.kind = INPUT_KEY, .code = KEY_A, .pressed = true); /* flight */
    FRAME();
    for (int i = 0; i < 20; i++) {
        t += INPUT_TICK_US;
        input_controller_tick(c, t);
        sleep_ms(1);
    }
    SEND(.kind = INPUT_KEY, .code = KEY_A, .pressed = false);
    FRAME();
#undef FRAME
#undef SEND
    camera_desc steered = input_controller_camera(c);
    /* wait until the wall shows the last camera, then stop */
    for (int i = 0; i < 5000; i++) {
        camera_desc shown = input_sink_current_camera(a.sink);
        if (memcmp(&shown, &steered, sizeof shown) == 0)
            break;
        sleep_ms(2);
    }
    pipeline_stop(a.p);
    pthread_join(th, NULL);
    cr_assert(ra.ok, "%s", ra.err.msg);
    camera_desc live_cam = pipeline_camera(a.p, 0);
    cr_assert(memcmp(&live_cam, &steered, sizeof live_cam) == 0, "the live pipeline did not end at the steered camera");
    input_sink_stats st = input_sink_get_stats(a.sink);
    cr_expect(st.emitted > 60, "only %llu transactions", (unsigned long long)st.emitted);
    cr_expect(st.camera_applied <= st.camera_changes);
    cr_expect_eq(st.refused, 0u);
    input_controller_destroy(c);
    live_free(&a);

    size_t n_all, n_frames;
    camera_desc all = replayed_camera(file, INPUT_REPLAY_ALL, &n_all);
    camera_desc frames = replayed_camera(file, INPUT_REPLAY_FRAMES, &n_frames);
    cr_expect_eq(n_all, (size_t)st.emitted, "the record holds %zu of %llu transactions", n_all,
                 (unsigned long long)st.emitted);
    cr_expect(memcmp(&all, &live_cam, sizeof all) == 0, "replay (all) differs from the live camera");
    cr_expect(memcmp(&frames, &live_cam, sizeof frames) == 0, "replay (frames) differs from the live camera");
    support_remove_tmp_dir(dir);
}

Test(input, replay_at_the_recorded_times_applies_each_when_due, .timeout = 60)
{
    char dir[256], file[300];
    support_make_tmp_dir(dir, sizeof dir, "input-timed");
    snprintf(file, sizeof file, "%s/rec.txt", dir);
    FILE *f = fopen(file, "w");
    cr_assert(f);
    fprintf(f, "%s\n", INPUT_RECORD_HEADER);
    camera_desc cams[3];
    for (int i = 0; i < 3; i++) {
        cams[i] = home_camera(3.0 + i);
        input_txn t = txn_camera(TXN_ALL_CHANNELS, &cams[i]);
        cr_assert(input_record_write(f, 0.3 * (i + 1), &t));
    }
    fclose(f);
    input_record rec;
    tess_error err = {{0}};
    cr_assert(input_record_load(file, &rec, &err), "%s", err.msg);
    live l = live_make(NULL, 0);
    cr_assert(input_sink_replay(l.sink, &rec, INPUT_REPLAY_RECORDED, &err), "%s", err.msg);
    input_record_free(&rec);
    run_args ra = {.p = l.p};
    pthread_t th;
    cr_assert_eq(pthread_create(&th, NULL, run_pipeline, &ra), 0);
    sleep_ms(150); /* before the first entry is due: the start camera */
    camera_desc shown = input_sink_current_camera(l.sink), start = home_camera(3.0);
    cr_expect(memcmp(&shown, &start, sizeof shown) == 0, "an entry applied before its time");
    sleep_ms(1200); /* all three are due (even on a slow machine they are queued by now) */
    for (int i = 0; i < 500; i++) {
        shown = input_sink_current_camera(l.sink);
        if (memcmp(&shown, &cams[2], sizeof shown) == 0)
            break;
        sleep_ms(10);
    }
    pipeline_stop(l.p);
    pthread_join(th, NULL);
    cr_assert(ra.ok, "%s", ra.err.msg);
    camera_desc last = pipeline_camera(l.p, 0);
    cr_expect(memcmp(&last, &cams[2], sizeof last) == 0, "the timed replay did not end at the last entry");
    live_free(&l);
    support_remove_tmp_dir(dir);
}

/* ---- the attract tour (the sink's serial animation) ------------------------------------------ */

#define TOUR_FRAMES 40
typedef struct tour_watch {
    input_sink *sink;
    camera_desc cams[TOUR_FRAMES];
    double times[TOUR_FRAMES];
} tour_watch;

/* registered after the tour: sees the camera the tour set for each frame */
static void watch_camera(pipeline *p, void *ctx, const frame_info *fi)
{
    tour_watch *w = ctx;
    if (fi->frame < TOUR_FRAMES) {
        w->cams[fi->frame] = pipeline_camera(p, 0);
        w->times[fi->frame] = fi->time_s;
    }
}

static void tour_off(pipeline *p, void *args)
{
    (void)p;
    input_txn t = txn_flag(TXN_TOUR, false);
    input_sink_emit(*(input_sink **)args, &t);
}

/* A tour of two keys, (10, 2, 0) at 1 s and (0, 2, 10) at 2 s, both looking at the origin. */
static camera_path two_key_tour(void)
{
    camera_path path = {0};
    tess_error err = {{0}};
    camera_desc k0 = {v3(10.f, 2.f, 0.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    camera_desc k1 = {v3(0.f, 2.f, 10.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    path.interp = CAMERA_PATH_LINEAR;
    cr_assert(camera_path_append(&path, 1.0, &k0, &err) && camera_path_append(&path, 2.0, &k1, &err), "%s", err.msg);
    return path;
}

Test(input, the_tour_eases_in_from_the_shown_camera_loops_and_stops_where_it_is, .timeout = 60)
{
    camera_path path = two_key_tour();
    tess_error err = {{0}};
    /* 30 Hz fixed: frame f at f/30 s; ease over 0.5 s; the tour starts at frame 0, stops at 31 */
    live l = live_make_tour(NULL, TOUR_FRAMES, &path, 0.5);
    tour_watch w = {.sink = l.sink};
    cr_assert(pipeline_add_serial_animation(l.p, "watch", watch_camera, &w));
    input_txn on = txn_flag(TXN_TOUR, true);
    input_sink_emit(l.sink, &on);
    cr_assert(pipeline_at_frame(l.p, 30, "tour off", tour_off, &l.sink, sizeof l.sink));
    cr_assert(pipeline_run(l.p, &err), "%s", err.msg);
    camera_desc home = home_camera(3.0);
    /* frame 0: eased in from the shown camera, which is exactly the start */
    cr_expect(memcmp(&w.cams[0], &home, sizeof home) == 0, "frame 0 is not the camera shown before the tour");
    /* half way through the easing: between the two, neither */
    camera_desc mid = w.cams[7]; /* t = 7/30 s */
    cr_expect(dist(mid.eye, home.eye) > 0.1 && dist(mid.eye, camera_path_eval(&path, 1.0 + 7.0 / 30.0).eye) > 0.1,
              "frame 7 is not a blend");
    /* after the easing: the path, from its first key, looping every second */
    for (int f = 15; f < 30; f++) {
        camera_desc want = camera_path_eval(&path, 1.0 + fmod(w.times[f], 1.0));
        cr_expect(memcmp(&w.cams[f], &want, sizeof want) == 0, "frame %d is not the path at %g s", f, w.times[f]);
    }
    cr_expect(dist(w.cams[29].eye, w.cams[15].eye) > 1.0, "the tour did not move");
    /* stopped at frame 31 (queued during frame 30's serial section): the camera stays where the tour left it */
    for (int f = 31; f < TOUR_FRAMES; f++)
        cr_expect(memcmp(&w.cams[f], &w.cams[30], sizeof w.cams[30]) == 0, "frame %d moved after the tour stopped", f);
    camera_desc shown = input_sink_current_camera(l.sink);
    cr_expect(memcmp(&shown, &w.cams[30], sizeof shown) == 0, "the hand-over camera is not the last tour camera");
    live_free(&l);
    camera_path_free(&path);
}

/* ---- a flood of input never floods the frame barrier -------------------------------------- */

typedef struct flood {
    input_sink *sink;
    int count;
    camera_desc last;
} flood;

static void *flood_main(void *arg)
{
    flood *f = arg;
    for (int i = 0; i < f->count; i++) {
        camera_desc c = home_camera(3.0 + 1e-4 * i);
        input_txn t = txn_camera(TXN_ALL_CHANNELS, &c);
        input_sink_emit(f->sink, &t);
        input_txn cur = txn_cursor(true, (float)(i % 100) * 0.01f, 0.f);
        input_sink_emit(f->sink, &cur);
        f->last = c;
    }
    return NULL;
}

Test(input, a_flood_of_camera_changes_waits_as_one_transaction_at_a_time, .timeout = 60)
{
    live l = live_make(NULL, 0);
    run_args ra = {.p = l.p};
    pthread_t th, producer;
    cr_assert_eq(pthread_create(&th, NULL, run_pipeline, &ra), 0);
    flood f = {.sink = l.sink, .count = 20000};
    cr_assert_eq(pthread_create(&producer, NULL, flood_main, &f), 0);
    pthread_join(producer, NULL);
    for (int i = 0; i < 5000; i++) { /* until the newest camera is shown */
        camera_desc shown = input_sink_current_camera(l.sink);
        if (memcmp(&shown, &f.last, sizeof shown) == 0)
            break;
        sleep_ms(1);
    }
    pipeline_stop(l.p);
    pthread_join(th, NULL);
    cr_assert(ra.ok, "%s", ra.err.msg);
    input_sink_stats st = input_sink_get_stats(l.sink);
    pipeline_stats ps = pipeline_get_stats(l.p);
    camera_desc final = pipeline_camera(l.p, 0);
    cr_expect(memcmp(&final, &f.last, sizeof final) == 0, "the newest camera was not applied");
    /* one mailbox transaction per barrier at most: never more than frames + 1, whatever the rate */
    cr_expect_eq(st.camera_changes, 20000u);
    cr_expect(st.camera_applied >= 1 && st.camera_applied <= ps.frames_rendered + 1,
              "%llu camera transactions applied for %llu frames", (unsigned long long)st.camera_applied,
              (unsigned long long)ps.frames_rendered);
    cr_expect_eq(st.refused, 0u);
    cr_expect_eq(ps.transactions_rejected, 0u);
    live_free(&l);
}

Test(input, the_default_tour_orbits_the_home_view_and_closes_its_loop)
{
    camera_desc home = home_camera(2.0);
    camera_path path;
    tess_error err = {{0}};
    cr_assert(navigate_orbit_path(&home, 24.0, 8, &path, &err), "%s", err.msg);
    cr_expect_eq(path.count, 9u);
    cr_expect(path.loop);
    camera_desc at0 = camera_path_eval(&path, 0.0), at_end = camera_path_eval(&path, 24.0),
                again = camera_path_eval(&path, 48.0);
    cr_expect(memcmp(&at0, &home, sizeof home) == 0, "the tour does not start at the home view");
    cr_expect(memcmp(&at_end, &home, sizeof home) == 0 && memcmp(&again, &home, sizeof home) == 0,
              "the loop does not close on the home view");
    double r0 = dist(home.eye, home.look_at);
    for (int i = 0; i < 48; i++) { /* between the keys too: about the same distance and height, all around */
        camera_desc c = camera_path_eval(&path, 0.5 * i);
        tess_error why = {{0}};
        cr_expect(camera_validate(&c, &why), "t = %g: %s", 0.5 * i, why.msg);
        cr_expect(fabs(dist(c.eye, home.look_at) - r0) < 0.02 * r0, "t = %g: distance %g vs %g", 0.5 * i,
                  dist(c.eye, home.look_at), r0);
        cr_expect(fabsf(c.eye.y - home.eye.y) < 1e-4f);
    }
    camera_desc half = camera_path_eval(&path, 12.0);
    cr_expect(dist(half.eye, v3(-home.eye.x, home.eye.y, -home.eye.z)) < 1e-4 * r0, "half way is not opposite");
    char dir[256], file[300];
    support_make_tmp_dir(dir, sizeof dir, "input-tour");
    snprintf(file, sizeof file, "%s/tour.json", dir);
    cr_expect(camera_path_save(&path, file, &err), "the tour is not a valid path file: %s", err.msg);
    support_remove_tmp_dir(dir);
    camera_path_free(&path);
    cr_expect(!navigate_orbit_path(&home, 0.0, 8, &path, &err));
}

/* ---- the runner polls its sources through source.h's interface ---- */

/* A source over a pipe: dispatch drains what was written and counts it;
 * after `fail_after` bytes it reports a failure. The counters are read by the
 * test thread while the input thread runs. */
typedef struct pipe_source {
    input_source base;
    int fds[2];
    atomic_int bytes, dispatches, suspends;
    int fail_after;         /* 0: never fails */
    atomic_bool *destroyed; /* set by destroy (outlives the source) */
} pipe_source;

static int pipe_fd(const input_source *s) { return ((const pipe_source *)s)->fds[0]; }

static bool pipe_dispatch(input_source *base, input_event_fn fn, void *ctx)
{
    (void)fn, (void)ctx;
    pipe_source *s = (pipe_source *)base;
    char buf[16];
    ssize_t n;
    while ((n = read(s->fds[0], buf, sizeof buf)) > 0)
        atomic_fetch_add(&s->bytes, (int)n);
    atomic_fetch_add(&s->dispatches, 1);
    return !(s->fail_after > 0 && atomic_load(&s->bytes) >= s->fail_after);
}

static void pipe_suspend(input_source *s) { atomic_fetch_add(&((pipe_source *)s)->suspends, 1); }
static void pipe_resume(input_source *s) { (void)s; }
static bool pipe_suspended(const input_source *s) { (void)s; return false; }
static int pipe_devices(const input_source *s) { (void)s; return 1; }

static void pipe_destroy(input_source *base)
{
    pipe_source *s = (pipe_source *)base;
    atomic_store(s->destroyed, true);
    close(s->fds[0]);
    close(s->fds[1]);
    free(s);
}

static const input_source_ops pipe_ops = {"pipe", pipe_fd, pipe_dispatch, pipe_suspend, pipe_resume,
                                          pipe_suspended, pipe_devices, pipe_destroy};

static pipe_source *pipe_source_create(int fail_after, atomic_bool *destroyed)
{
    pipe_source *s = calloc(1, sizeof *s);
    cr_assert(s);
    s->base.ops = &pipe_ops;
    cr_assert(pipe(s->fds) == 0);
    cr_assert(fcntl(s->fds[0], F_SETFL, O_NONBLOCK) == 0);
    s->fail_after = fail_after;
    s->destroyed = destroyed;
    return s;
}

/* Wait up to 5 s for *counter to reach at least `want`. */
/* Wait for the input thread to count `want`: an event, not a time; the 30 s
 * cap only keeps a broken runner from hanging the suite. */
static bool wait_count(atomic_int *counter, int want)
{
    for (int i = 0; i < 3000 && atomic_load(counter) < want; i++)
        nanosleep(&(struct timespec){0, 10000000}, NULL);
    return atomic_load(counter) >= want;
}

Test(input, runner_polls_every_source_through_the_interface)
{
    live l = live_make(NULL, 1);
    input_controller_config cc;
    input_controller_config_default(&cc);
    atomic_bool destroyed[2] = {false, false};
    pipe_source *a = pipe_source_create(0, &destroyed[0]), *b = pipe_source_create(3, &destroyed[1]);
    input_source *sources[2] = {&a->base, &b->base};
    tess_error err = {{0}};
    input_runner *r = input_runner_start(sources, 2, &cc, NULL, NULL, NULL, l.sink, NULL, &err);
    cr_assert(r, "%s", err.msg);
    /* bytes on either source's fd wake the thread and reach that source's dispatch */
    cr_assert_eq(write(a->fds[1], "x", 1), 1);
    cr_assert(wait_count(&a->bytes, 1), "source a never dispatched its byte");
    cr_assert_eq(write(b->fds[1], "yy", 2), 2);
    cr_assert(wait_count(&b->bytes, 2), "source b never dispatched its bytes");
    /* the second source failing for good stops the input thread: no dispatch after it */
    cr_assert_eq(write(b->fds[1], "z", 1), 1);
    cr_assert(wait_count(&b->bytes, 3));
    /* a (source 0) was dispatched before b in the pass where b failed, so its
     * count is final now if the thread stopped; the pause is only the window
     * in which a runner that went on would dispatch a's byte (a slow machine
     * can make this check miss a fault, never fail a correct runner) */
    int after = atomic_load(&a->dispatches);
    cr_assert_eq(write(a->fds[1], "x", 1), 1);
    nanosleep(&(struct timespec){0, 100000000}, NULL);
    cr_assert_eq(atomic_load(&a->dispatches), after, "a source was dispatched after another failed");
    cr_assert_eq(atomic_load(&a->suspends) + atomic_load(&b->suspends), 0, "no seat: nothing suspended");
    cr_assert(!destroyed[0] && !destroyed[1]);
    input_runner_stop(r); /* destroys both sources */
    cr_assert(destroyed[0] && destroyed[1]);
    live_free(&l);
}


/* ---- private views: a remote viewer's device steers a channel of its own ---------------- */

typedef struct view_watch {
    pthread_mutex_t lock;
    uint64_t serial[2];
    bool active1;
    camera_desc cam[2];
    uint64_t frames;
} view_watch;

static void watch_views(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)fi;
    view_watch *w = ctx;
    pthread_mutex_lock(&w->lock);
    for (int c = 0; c < 2; c++) {
        w->serial[c] = pipeline_camera_serial(p, c);
        w->cam[c] = pipeline_camera(p, c);
    }
    w->active1 = pipeline_channel_active(p, 1);
    w->frames++;
    pthread_mutex_unlock(&w->lock);
}

static view_watch watched(view_watch *w)
{
    pthread_mutex_lock(&w->lock);
    view_watch copy = *w;
    pthread_mutex_unlock(&w->lock);
    return copy;
}

/* Wait (for frames, not for a time: the cap only keeps a broken runner from
 * hanging the suite) until pred holds for the watched state. */
static bool wait_views(view_watch *w, bool (*pred)(const view_watch *s, const void *arg), const void *arg)
{
    for (int i = 0; i < 6000; i++) {
        view_watch s = watched(w);
        if (pred(&s, arg))
            return true;
        sleep_ms(5);
    }
    return false;
}

static bool private_steered(const view_watch *s, const void *arg)
{
    (void)arg;
    return s->active1 && s->serial[1] >= 3; /* the start (the wall's camera) and two drag steps */
}
static bool wall_moved(const view_watch *s, const void *arg)
{
    return s->serial[0] > *(const uint64_t *)arg;
}
static bool private_off(const view_watch *s, const void *arg)
{
    (void)arg;
    return !s->active1;
}

static void push_all(remote_source *src, const input_event *events, int n)
{
    cr_assert(remote_source_push(src, events, n));
}

/* A running pipeline (l) watched by w, with an input runner over one remote source:
 * what the runner tests drive. tour: the controller has one (idle after idle_s). */
typedef struct runner_rig {
    remote_source *src;
    input_runner *runner;
    run_args run;
    pthread_t thread;
} runner_rig;

static void runner_rig_start(runner_rig *g, live *l, view_watch *w, bool tour, double idle_s)
{
    tess_error err = {{0}};
    cr_assert(pipeline_add_serial_animation(l->p, "watch views", watch_views, w));
    g->src = remote_source_create(&err);
    cr_assert(g->src, "%s", err.msg);
    input_source *sources[1] = {remote_source_input(g->src)};
    input_controller_config cc;
    input_controller_config_default(&cc);
    cc.plane_aspect = 32.f / 18.f;
    cc.home = home_camera(3.0);
    cc.scene_size = 8.0;
    cc.have_tour = tour;
    cc.idle_timeout_s = idle_s;
    g->runner = input_runner_start(sources, 1, &cc, drive_pick, NULL, NULL, l->sink, NULL, &err);
    cr_assert(g->runner, "%s", err.msg);
    g->run = (run_args){.p = l->p};
    cr_assert_eq(pthread_create(&g->thread, NULL, run_pipeline, &g->run), 0);
}

/* Stop the pipeline, then the runner (which destroys the source). */
static void runner_rig_stop(runner_rig *g)
{
    pipeline_stop(g->run.p);
    pthread_join(g->thread, NULL);
    cr_assert(g->run.ok, "%s", g->run.err.msg);
    input_runner_stop(g->runner);
}

Test(input, a_private_view_steers_its_own_channel_and_the_wall_never_sees_it, .timeout = 120)
{
    char dir[256], file[300];
    support_make_tmp_dir(dir, sizeof dir, "input-private");
    snprintf(file, sizeof file, "%s/rec.txt", dir);
    live l = live_make(file, 0);
    tess_error err = {{0}};
    camera_desc home = home_camera(3.0);
    image_display *d = display_create("null", NULL, false, &err);
    cr_assert(d, "%s", err.msg);
    cr_assert_eq(pipeline_add_channel(l.p, &home, 32, 18, d, &err), 1, "%s", err.msg);
    cr_assert(pipeline_set_channel_private(l.p, 1, &err), "%s", err.msg);
    cr_assert(pipeline_set_channel_active(l.p, 1, false));
    view_watch w = {.lock = PTHREAD_MUTEX_INITIALIZER};
    runner_rig g;
    runner_rig_start(&g, &l, &w, false, 0.0);
    remote_source *src = g.src;

    const int viewer = 1000, wall_mouse = 7;
    uint64_t t = clock_monotonic_us();
    input_event start[] = {{.kind = INPUT_DEVICE_ADDED, .device = viewer, .time_us = t},
                           {.kind = INPUT_PRIVATE_VIEW, .device = viewer, .code = 1, .time_us = t}};
    push_all(src, start, 2);
    input_event drag[] = {
        {.kind = INPUT_POINTER_ABS, .device = viewer, .x = 0.0, .y = 0.0, .time_us = t},
        {.kind = INPUT_BUTTON, .device = viewer, .code = BTN_LEFT, .pressed = true, .time_us = t},
        {.kind = INPUT_FRAME, .device = viewer, .time_us = t},
        {.kind = INPUT_POINTER_ABS, .device = viewer, .x = 0.2, .y = 0.1, .time_us = t + 10000},
        {.kind = INPUT_FRAME, .device = viewer, .time_us = t + 10000},
        {.kind = INPUT_POINTER_ABS, .device = viewer, .x = 0.4, .y = 0.1, .time_us = t + 20000},
        {.kind = INPUT_FRAME, .device = viewer, .time_us = t + 20000},
        {.kind = INPUT_BUTTON, .device = viewer, .code = BTN_LEFT, .pressed = false, .time_us = t + 30000},
        {.kind = INPUT_FRAME, .device = viewer, .time_us = t + 30000},
        /* its pointer and a hide at the cursor: the shared view's business, not a private view's */
        {.kind = INPUT_VIEWER_POINTER, .device = viewer, .slot = 0, .pressed = true, .x = 0.1, .y = 0.1,
         .time_us = t + 40000},
        {.kind = INPUT_KEY, .device = viewer, .code = KEY_H, .pressed = true, .time_us = t + 40000},
        {.kind = INPUT_FRAME, .device = viewer, .time_us = t + 40000},
        {.kind = INPUT_KEY, .device = viewer, .code = KEY_H, .pressed = false, .time_us = t + 50000},
        {.kind = INPUT_FRAME, .device = viewer, .time_us = t + 50000},
    };
    push_all(src, drag, (int)(sizeof drag / sizeof drag[0]));
    cr_assert(wait_views(&w, private_steered, NULL), "the private view's channel never took the drag");
    view_watch s = watched(&w);
    cr_assert_eq(s.serial[0], 0, "the wall's camera was not touched by the private view");
    cr_assert(memcmp(&s.cam[0], &home, sizeof home) == 0);
    cr_assert(memcmp(&s.cam[1], &home, sizeof home) != 0, "the private camera moved");
    camera_desc private_cam = s.cam[1];
    uint64_t private_serial = s.serial[1];
    /* the wall's mouse dollies the wall: the private channel keeps its camera */
    input_event wheel[] = {{.kind = INPUT_POINTER_ABS, .device = wall_mouse, .x = 0.0, .y = 0.0, .time_us = t + 60000},
                           {.kind = INPUT_SCROLL, .device = wall_mouse, .dy = 1.0, .time_us = t + 60000},
                           {.kind = INPUT_FRAME, .device = wall_mouse, .time_us = t + 60000}};
    push_all(src, wheel, 3);
    uint64_t zero = 0;
    cr_assert(wait_views(&w, wall_moved, &zero), "the wall's wheel never moved the wall");
    s = watched(&w);
    cr_assert(memcmp(&s.cam[1], &private_cam, sizeof private_cam) == 0 && s.serial[1] == private_serial,
              "the wall's camera reached the private channel");
    /* the viewer goes: its view ends and the channel goes off */
    input_event gone = {.kind = INPUT_DEVICE_REMOVED, .device = viewer, .time_us = t + 70000};
    push_all(src, &gone, 1);
    cr_assert(wait_views(&w, private_off, NULL), "the private channel stayed on after its viewer left");
    runner_rig_stop(&g);
    cr_assert_eq(pipeline_hidden(l.p, 0) || pipeline_hidden(l.p, 1), false, "a private view hid a part");
    live_free(&l);
    /* the recording holds the wall's cameras only: it replays without the private channel */
    input_record rec;
    cr_assert(input_record_load(file, &rec, &err), "%s", err.msg);
    int wall_cameras = 0;
    for (size_t i = 0; i < rec.count; i++) {
        const input_txn *x = &rec.entries[i].txn;
        cr_assert(x->kind != TXN_CHANNEL_ACTIVE && x->kind != TXN_POINTER && x->kind != TXN_HIDE,
                  "entry %zu: a %s record of the private view was recorded", i, txn_kind_name(x->kind));
        if (x->kind == TXN_CAMERA) {
            cr_assert_eq(x->args.camera.channel, TXN_ALL_CHANNELS, "entry %zu: a private camera was recorded", i);
            wall_cameras++;
        }
    }
    cr_assert_geq(wall_cameras, 1, "the wall's wheel is in the recording");
    input_record_free(&rec);
    support_remove_tmp_dir(dir);
}

/* ---- the input thread's clock: the idle tour comes back (runner.h, its deadlines) ---------- */

/* Wait (for events: the sink's counts, which never miss a change; the cap only keeps a broken
 * runner from hanging the suite) until the tour has started `starts` and stopped `stops` times. */
static bool wait_tour(input_sink *sink, uint64_t starts, uint64_t stops)
{
    for (int i = 0; i < 6000; i++) {
        input_sink_stats st = input_sink_get_stats(sink);
        if (st.tour_starts >= starts && st.tour_stops >= stops)
            return true;
        sleep_ms(5);
    }
    return false;
}

Test(input, the_runner_brings_the_idle_tour_back_after_input_stops, .timeout = 120)
{
    camera_path path = two_key_tour();
    live l = live_make_tour(NULL, 0, &path, 0.1);
    view_watch w = {.lock = PTHREAD_MUTEX_INITIALIZER};
    runner_rig g;
    runner_rig_start(&g, &l, &w, true, 0.3);
    remote_source *src = g.src;
    cr_assert(wait_tour(l.sink, 1, 0), "nobody there: the tour never started");
    uint64_t t = clock_monotonic_us();
    input_event key[] = {{.kind = INPUT_DEVICE_ADDED, .device = 3, .time_us = t},
                         {.kind = INPUT_KEY, .device = 3, .code = KEY_LEFTSHIFT, .pressed = true, .time_us = t},
                         {.kind = INPUT_FRAME, .device = 3, .time_us = t},
                         {.kind = INPUT_KEY, .device = 3, .code = KEY_LEFTSHIFT, .pressed = false, .time_us = t},
                         {.kind = INPUT_FRAME, .device = 3, .time_us = t}};
    push_all(src, key, 5);
    cr_assert(wait_tour(l.sink, 1, 1), "a key did not stop the tour");
    cr_assert(wait_tour(l.sink, 2, 1), "the tour did not come back after the idle timeout");
    runner_rig_stop(&g);
    live_free(&l);
    camera_path_free(&path);
}
