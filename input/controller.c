/* controller.c - input events to input transactions (controller.h). */
#include "controller.h"
#include "controller_private.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "navigate.h"

#define TAP_MAX_S 0.30            /* a tap is shorter than this ... */
#define TAP_SLOP 0.02             /* ... and moves less than this (plane units) */
#define DOUBLE_TAP_S 0.40         /* second tap within this of the first's end ... */
#define DOUBLE_TAP_DIST 0.06      /* ... and this close to it */
#define CLICK_SLOP 0.01           /* a button released having moved less than this is a click */
#define WHEEL_DRAG_UNITS 0.05     /* a wheel click bound to orbit/pan acts as this much drag */
#define MAX_TICK_S 0.1            /* flight never jumps more than this much time at once */

void input_controller_config_default(input_controller_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    input_bindings_default(&cfg->bindings);
    cfg->plane_aspect = 16.f / 9.f;
    cfg->home = (camera_desc){v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), CAMERA_DEFAULT_FOV_DEG};
    cfg->scene_size = 1.0;
    cfg->opacity = 1.f; /* clip: zeroed, every plane off */
}

input_controller *input_controller_create(const input_controller_config *cfg, const input_controller_hooks *hooks)
{
    input_controller *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->cam_holder = -1;
    c->event_device = -1;
    c->cfg = *cfg;
    c->hooks = *hooks;
    if (c->cfg.private_channel < 0)
        c->cfg.private_channel = 0;
    if (c->cfg.private_channel > 0) { /* a private view: no tour of its own (the wall's plays on) */
        c->cfg.have_tour = false;
        c->cfg.idle_timeout_s = 0.0;
    }
    if (!(c->cfg.scene_size > 0.0) || !isfinite(c->cfg.scene_size))
        c->cfg.scene_size = 1.0;
    if (!(c->cfg.plane_aspect > 0.f))
        c->cfg.plane_aspect = 1.f;
    if (c->cfg.orbit_rad_per_unit <= 0.0)
        c->cfg.orbit_rad_per_unit = 3.14159265358979323846;
    if (c->cfg.wheel_factor <= 0.0 || c->cfg.wheel_factor >= 1.0)
        c->cfg.wheel_factor = 0.85;
    if (c->cfg.fly_to_s <= 0.0)
        c->cfg.fly_to_s = 0.6;
    c->fly_speed = c->cfg.fly_speed > 0.0 ? c->cfg.fly_speed : c->cfg.scene_size / 4.0;
    c->cam = c->cfg.home;
    c->opacity = c->cfg.opacity >= 0.f && c->cfg.opacity <= 1.f ? c->cfg.opacity : 1.f;
    memcpy(c->planes, c->cfg.clip, sizeof c->planes);
    snprintf(c->renderer, sizeof c->renderer, "%s", c->cfg.renderer[0] ? c->cfg.renderer : "raytracer");
    bool ao_renderer = !strcmp(c->renderer, "ao") || !strcmp(c->renderer, "raytracer-ao");
    snprintf(c->configured, sizeof c->configured, "%s", ao_renderer ? "raytracer" : c->renderer);
    c->time_rate = c->cfg.time_rate > 0.0 && isfinite(c->cfg.time_rate) ? c->cfg.time_rate : INPUT_TIME_RATE;
    if (c->cfg.value_count < 0 || c->cfg.value_count > INPUT_VALUE_MAX)
        c->cfg.value_count = 0;
    if (c->cfg.map_count < 0 || c->cfg.map_count > INPUT_MAP_MAX)
        c->cfg.map_count = 0;
    for (int i = 0; i < c->cfg.value_count; i++)
        c->values[i] = c->cfg.values[i].value;
    /* (memcpy of equal-sized arrays, NUL forced: snprintf between two members of *c reads to
     * -Wrestrict at -O1 as a possible overlap) */
    for (int i = 0; i < c->cfg.map_count; i++) {
        memcpy(c->maps[i], c->cfg.maps[i].name, sizeof c->maps[i]);
        c->maps[i][sizeof c->maps[i] - 1] = '\0';
    }
    memcpy(c->transfer, c->cfg.transfer, sizeof c->transfer);
    c->transfer[sizeof c->transfer - 1] = '\0';
    if (c->cfg.crop_count < 0 || c->cfg.crop_count > INPUT_CROP_MAX)
        c->cfg.crop_count = 0;
    for (int i = 0; i < c->cfg.crop_count; i++)
        c->crops[i] = c->cfg.crops[i].crop;
    c->plane_sel = -1;
    for (int i = CLIP_MAX_PLANES - 1; i >= 0; i--)
        if (c->planes[i].on)
            c->plane_sel = i; /* the first one on */
    return c;
}

void input_controller_destroy(input_controller *c) { free(c); }


camera_desc input_controller_camera(const input_controller *c) { return c->cam; }
double input_controller_fly_speed(const input_controller *c) { return c->fly_speed; }
bool input_controller_touring(const input_controller *c) { return c->touring; }

/* ---- keys and buttons ------------------------------------------------------------ */

static bool chord_held(const input_controller *c)
{
    const input_bindings *b = &c->cfg.bindings;
    if (b->quit_chord_len <= 0)
        return false;
    for (int i = 0; i < b->quit_chord_len; i++)
        if (!c->held[b->quit_chord[i]])
            return false;
    return true;
}

static void key_or_button(input_controller *c, const input_event *e)
{
    if (e->code < 0 || e->code >= INPUT_CODE_COUNT)
        return;
    int code = e->code;
    if (e->pressed) {
        if (c->held[code] < 255)
            c->held[code]++;
        c->held_device[code] = e->device;
    } else if (c->held[code] > 0) {
        c->held[code]--;
    } else {
        return; /* a release we never saw pressed (held before we started) */
    }
    if (chord_held(c)) {
        if (!c->chord_fired) {
            c->chord_fired = true;
            input_txn t = txn_simple(TXN_QUIT);
            commands_emit(c, &t);
        }
    } else {
        c->chord_fired = false;
    }

    input_action action = (input_action)c->cfg.bindings.code_action[code];
    if (input_action_is_drag(action)) {
        if (e->kind != INPUT_BUTTON)
            return;
        if (e->pressed && !c->dragging) {
            c->animating = false;
            c->dragging = true;
            c->drag_code = code;
            c->drag_device = e->device;
            c->drag_action = action;
            c->drag_travel = 0.0;
            c->drag_point = commands_point_under(c, c->cur_x, c->cur_y, NULL);
        } else if (!e->pressed && c->dragging && c->drag_code == code) {
            c->dragging = false;
            if (c->drag_travel < CLICK_SLOP)
                commands_run(c, (input_action)c->cfg.bindings.gesture_action[INPUT_GESTURE_CLICK], c->cur_x, c->cur_y,
                        e->time_us);
        }
        return;
    }
    if (action >= INPUT_ACTION_FLY_FORWARD && action <= INPUT_ACTION_FLY_DOWN) {
        if (e->pressed) {
            if (!commands_flight_held(c) || c->held[code] == 1)
                c->last_flight_us = e->time_us;
            c->animating = false;
        }
        return;
    }
    if (e->pressed && action != INPUT_ACTION_NONE)
        commands_run(c, action, c->cur_x, c->cur_y, e->time_us);
}

/* ---- pointer ------------------------------------------------------------------------ */

static void pointer_moved(input_controller *c, double nx, double ny)
{
    double dx = nx - c->cur_x, dy = ny - c->cur_y;
    c->cur_x = nx;
    c->cur_y = ny;
    if (dx != 0.0 || dy != 0.0)
        c->cursor_dirty = true;
    commands_show_cursor(c, true);
    if (c->dragging) {
        c->drag_travel += sqrt(dx * dx + dy * dy);
        commands_drag(c, c->drag_action, c->drag_point, dx, dy);
    }
}

static double clamp_plane(double v) { return v < -1.0 ? -1.0 : v > 1.0 ? 1.0 : v; }

/* ---- touch ---------------------------------------------------------------------------- */

static touch *find_touch(input_controller *c, int device, int slot)
{
    for (int i = 0; i < TOUCH_SLOTS; i++)
        if (c->touches[i].active && c->touches[i].device == device && c->touches[i].slot == slot)
            return &c->touches[i];
    return NULL;
}

/* The first two fingers down (in slot-table order), for the two-finger gestures. */
static int active_touches(input_controller *c, touch **first, touch **second)
{
    int n = 0;
    *first = *second = NULL;
    for (int i = 0; i < TOUCH_SLOTS; i++) {
        if (!c->touches[i].active)
            continue;
        if (n == 0)
            *first = &c->touches[i];
        else if (n == 1)
            *second = &c->touches[i];
        n++;
    }
    return n;
}

static void touch_sequence_ended(input_controller *c, uint64_t now_us)
{
    double dt_s = (double)(now_us - c->seq_start_us) * 1e-6;
    bool still = dt_s <= TAP_MAX_S && c->seq_travel < TAP_SLOP;
    const unsigned char *g = c->cfg.bindings.gesture_action;
    if (still && c->seq_max_fingers == 3) {
        c->have_last_tap = false;
        commands_run(c, (input_action)g[INPUT_GESTURE_THREE_FINGER_TAP], c->seq_x0, c->seq_y0, now_us);
        return;
    }
    if (still && c->seq_max_fingers == 2) {
        c->have_last_tap = false;
        commands_run(c, (input_action)g[INPUT_GESTURE_TWO_FINGER_TAP], c->seq_x0, c->seq_y0, now_us);
        return;
    }
    bool tap = c->seq_max_fingers == 1 && still;
    if (!tap)
        return;
    double ddx = c->seq_x0 - c->last_tap_x, ddy = c->seq_y0 - c->last_tap_y;
    bool second = c->have_last_tap && (double)(c->seq_start_us - c->last_tap_us) * 1e-6 <= DOUBLE_TAP_S &&
                  sqrt(ddx * ddx + ddy * ddy) <= DOUBLE_TAP_DIST;
    if (second) {
        c->have_last_tap = false;
        commands_run(c, (input_action)g[INPUT_GESTURE_DOUBLE_TAP], c->seq_x0, c->seq_y0, now_us);
    } else {
        c->have_last_tap = true;
        c->last_tap_us = now_us;
        c->last_tap_x = c->seq_x0;
        c->last_tap_y = c->seq_y0;
        commands_run(c, (input_action)g[INPUT_GESTURE_TAP], c->seq_x0, c->seq_y0, now_us);
    }
}

/* When the finger down now becomes a long press: one finger in this
 * sequence, still within the tap slop, not fired yet, a long press bound. */
static bool long_press_due(const input_controller *c, uint64_t *due_us)
{
    if (c->seq_long_pressed || c->seq_max_fingers > 1 || c->seq_travel >= TAP_SLOP ||
        c->cfg.bindings.gesture_action[INPUT_GESTURE_LONG_PRESS] == INPUT_ACTION_NONE)
        return false;
    int down = 0;
    for (int i = 0; i < TOUCH_SLOTS; i++)
        down += c->touches[i].active;
    if (down != 1)
        return false;
    *due_us = c->seq_start_us + (uint64_t)(INPUT_LONG_PRESS_S * 1e6);
    return true;
}

/* The long press: the part under the finger is selected, then its action. */
static void long_press(input_controller *c, uint64_t now_us)
{
    touch *a, *b;
    if (active_touches(c, &a, &b) != 1)
        return;
    c->seq_long_pressed = true;
    c->have_last_tap = false;
    input_hit pk;
    commands_point_under(c, a->x, a->y, &pk);
    commands_select_hit(c, &pk);
    commands_run(c, (input_action)c->cfg.bindings.gesture_action[INPUT_GESTURE_LONG_PRESS], a->x, a->y, now_us);
}

/* A long press whose time came by now_us happens now: from a tick at its
 * deadline, or from the finger's next event when the input thread got to
 * the events late (a finger lifted 1 s after it came down, both read at
 * once, was held 1 s). */
static void long_press_if_due(input_controller *c, uint64_t now_us)
{
    uint64_t due;
    if (!c->touring && long_press_due(c, &due) && now_us >= due)
        long_press(c, now_us);
}

/* The centre of the fingers down. */
static void touch_centre(const input_controller *c, double *x, double *y)
{
    double sx = 0.0, sy = 0.0;
    int n = 0;
    for (int i = 0; i < TOUCH_SLOTS; i++)
        if (c->touches[i].active) {
            sx += c->touches[i].x;
            sy += c->touches[i].y;
            n++;
        }
    *x = n ? sx / n : 0.0;
    *y = n ? sy / n : 0.0;
}

static void touch_frame(input_controller *c, uint64_t now_us)
{
    touch *a, *b;
    int n = active_touches(c, &a, &b);
    const unsigned char *g = c->cfg.bindings.gesture_action;
    if (n == 0) {
        if (c->fingers_prev > 0)
            touch_sequence_ended(c, now_us);
        c->fingers_prev = 0;
        return;
    }
    if (n > c->seq_max_fingers)
        c->seq_max_fingers = n;
    if (n != c->fingers_prev) { /* fingers came or went: anchor again, move nothing */
        if (n == 1) {
            c->prev_x = a->x;
            c->prev_y = a->y;
            c->one_drag_started = false;
            c->touch_point = commands_point_under(c, a->x, a->y, NULL);
        } else if (n == 3) {
            touch_centre(c, &c->prev_x, &c->prev_y);
            c->touch_point = commands_point_under(c, c->prev_x, c->prev_y, NULL);
        } else {
            c->prev_x = 0.5 * (a->x + b->x);
            c->prev_y = 0.5 * (a->y + b->y);
            c->prev_spread = hypot(a->x - b->x, (a->y - b->y) / c->cfg.plane_aspect);
            c->touch_point = commands_point_under(c, c->prev_x, c->prev_y, NULL);
        }
        c->fingers_prev = n;
        return;
    }
    if (n == 1) {
        if (c->seq_long_pressed) /* a long press took this finger: it steers nothing */
            return;
        if (!c->one_drag_started) { /* within the tap slop nothing moves */
            if (hypot(a->x - a->x0, a->y - a->y0) < TAP_SLOP)
                return;
            c->one_drag_started = true;
        }
        commands_drag(c, (input_action)g[INPUT_GESTURE_ONE_FINGER_DRAG], c->touch_point, a->x - c->prev_x,
             a->y - c->prev_y);
        c->prev_x = a->x;
        c->prev_y = a->y;
        return;
    }
    if (n == 3) { /* the three fingers' centre drags (no pinch) */
        double cx, cy;
        touch_centre(c, &cx, &cy);
        commands_drag(c, (input_action)g[INPUT_GESTURE_THREE_FINGER_DRAG], c->touch_point, cx - c->prev_x, cy - c->prev_y);
        c->prev_x = cx;
        c->prev_y = cy;
        return;
    }
    double cx = 0.5 * (a->x + b->x), cy = 0.5 * (a->y + b->y);
    /* spread measured in width units both ways, so it does not depend on the direction of the fingers */
    double spread = hypot(a->x - b->x, (a->y - b->y) / c->cfg.plane_aspect);
    input_action pinch = (input_action)g[INPUT_GESTURE_TWO_FINGER_PINCH];
    if (spread > 0.0 && c->prev_spread > 0.0 && spread != c->prev_spread) {
        if (pinch == INPUT_ACTION_DOLLY)
            commands_set_camera(c, navigate_dolly(&c->cam, c->touch_point, c->prev_spread / spread));
        else
            commands_drag(c, pinch, c->touch_point, 0.0, spread - c->prev_spread);
    }
    commands_drag(c, (input_action)g[INPUT_GESTURE_TWO_FINGER_DRAG], c->touch_point, cx - c->prev_x, cy - c->prev_y);
    c->prev_x = cx;
    c->prev_y = cy;
    if (spread > 0.0)
        c->prev_spread = spread;
}

static void touch_event(input_controller *c, const input_event *e)
{
    touch *t = find_touch(c, e->device, e->slot);
    switch (e->kind) {
    case INPUT_TOUCH_DOWN:
        if (!t) {
            for (int i = 0; i < TOUCH_SLOTS && !t; i++)
                if (!c->touches[i].active)
                    t = &c->touches[i];
            if (!t)
                return; /* more fingers than we track: ignored */
        }
        {
            int down = 0;
            for (int i = 0; i < TOUCH_SLOTS; i++)
                down += c->touches[i].active;
            if (down == 0) { /* the first finger: a new sequence */
                c->seq_start_us = e->time_us;
                c->seq_max_fingers = 0;
                c->seq_x0 = e->x;
                c->seq_y0 = e->y;
                c->seq_travel = 0.0;
                c->seq_long_pressed = false;
                c->animating = false;
            }
        }
        *t = (touch){.active = true, .device = e->device, .slot = e->slot, .x = e->x, .y = e->y, .x0 = e->x,
                     .y0 = e->y};
        commands_show_cursor(c, false);
        break;
    case INPUT_TOUCH_MOTION:
        if (t) {
            t->x = e->x;
            t->y = e->y;
            double travel = hypot(t->x - t->x0, t->y - t->y0);
            if (travel > c->seq_travel)
                c->seq_travel = travel;
        }
        break;
    case INPUT_TOUCH_UP:
        if (t)
            t->active = false;
        break;
    case INPUT_TOUCH_CANCEL:
        for (int i = 0; i < TOUCH_SLOTS; i++)
            if (c->touches[i].device == e->device)
                c->touches[i].active = false;
        c->seq_max_fingers = 99; /* no tap from a cancelled sequence */
        break;
    default:
        break;
    }
}

/* ---- devices ---------------------------------------------------------------------------- */

static void device_removed(input_controller *c, int device)
{
    for (int code = 0; code < INPUT_CODE_COUNT; code++)
        if (c->held[code] && c->held_device[code] == device)
            c->held[code] = 0;
    if (c->dragging && c->drag_device == device)
        c->dragging = false;
    for (int i = 0; i < TOUCH_SLOTS; i++)
        if (c->touches[i].active && c->touches[i].device == device) {
            c->touches[i].active = false;
            c->seq_max_fingers = 99;
        }
    c->chord_fired = chord_held(c);
}

/* ---- events ------------------------------------------------------------------------------- */

/* Whether the numbers an event of its kind carries are finite: a broken
 * device's NaN or infinity must never reach the camera (it is dropped, and
 * does not count as someone being there either). */
static bool event_finite(const input_event *e)
{
    switch (e->kind) {
    case INPUT_POINTER_ABS:
    case INPUT_TOUCH_DOWN:
    case INPUT_TOUCH_MOTION:
        return isfinite(e->x) && isfinite(e->y);
    case INPUT_VIEWER_POINTER:
        return !e->pressed || (isfinite(e->x) && isfinite(e->y));
    case INPUT_POINTER_MOTION:
    case INPUT_SWIPE_UPDATE:
        return isfinite(e->dx) && isfinite(e->dy);
    case INPUT_SCROLL:
        return isfinite(e->dy);
    case INPUT_PINCH_UPDATE:
        return isfinite(e->dx) && isfinite(e->dy) && isfinite(e->scale);
    default:
        return true;
    }
}

void input_controller_event(input_controller *c, const input_event *e)
{
    if (!event_finite(e))
        return;
    c->event_device = e->device;
    c->event_us = e->time_us;
    switch (e->kind) {
    case INPUT_DEVICE_ADDED:
    case INPUT_PRIVATE_VIEW: /* the runner's (runner.h) */
        return;
    case INPUT_DEVICE_REMOVED:
        device_removed(c, e->device);
        if (c->cam_holder == e->device) /* a holder that went away lets go at once */
            c->cam_holder = -1;
        return;
    case INPUT_FRAME:
        commands_flush(c);
        return;
    case INPUT_TOUCH_FRAME:
        long_press_if_due(c, e->time_us);
        touch_frame(c, e->time_us);
        commands_flush(c);
        return;
    default:
        break;
    }
    commands_user_input(c, e->time_us);
    if (e->kind == INPUT_TOUCH_MOTION || e->kind == INPUT_TOUCH_UP)
        long_press_if_due(c, e->time_us);
    const unsigned char *g = c->cfg.bindings.gesture_action;
    switch (e->kind) {
    case INPUT_KEY:
    case INPUT_BUTTON:
        key_or_button(c, e);
        break;
    case INPUT_POINTER_MOTION:
        pointer_moved(c, clamp_plane(c->cur_x + e->dx), clamp_plane(c->cur_y + e->dy));
        break;
    case INPUT_POINTER_ABS:
        pointer_moved(c, clamp_plane(e->x), clamp_plane(e->y));
        break;
    case INPUT_VIEWER_POINTER:
        if (e->slot >= 0 && e->slot < INPUT_MAX_VIEWERS && c->cfg.private_channel == 0) {
            int s = e->slot;
            double x = e->pressed ? clamp_plane(e->x) : c->pointer_x[s], y = e->pressed ? clamp_plane(e->y) : c->pointer_y[s];
            if (c->pointer_visible[s] != e->pressed || x != c->pointer_x[s] || y != c->pointer_y[s])
                c->pointer_dirty[s] = true;
            c->pointer_visible[s] = e->pressed;
            c->pointer_x[s] = x;
            c->pointer_y[s] = y;
        }
        break;
    case INPUT_SCROLL: {
        c->animating = false;
        input_action a = (input_action)g[INPUT_GESTURE_WHEEL];
        vec3 p = commands_point_under(c, c->cur_x, c->cur_y, NULL);
        if (a == INPUT_ACTION_DOLLY)
            commands_set_camera(c, navigate_dolly(&c->cam, p, pow(c->cfg.wheel_factor, e->dy)));
        else
            commands_drag(c, a, p, 0.0, e->dy * WHEEL_DRAG_UNITS);
        break;
    }
    case INPUT_TOUCH_DOWN:
    case INPUT_TOUCH_MOTION:
    case INPUT_TOUCH_UP:
    case INPUT_TOUCH_CANCEL:
        touch_event(c, e);
        break;
    case INPUT_PINCH_BEGIN:
    case INPUT_SWIPE_BEGIN:
        c->animating = false;
        c->gesture_point = commands_point_under(c, c->cur_x, c->cur_y, NULL);
        c->pinch_prev_scale = 1.0;
        break;
    case INPUT_PINCH_UPDATE: {
        input_action a = (input_action)g[INPUT_GESTURE_TOUCHPAD_PINCH];
        if (a == INPUT_ACTION_DOLLY) {
            if (e->scale > 0.0 && c->pinch_prev_scale > 0.0)
                commands_set_camera(c, navigate_dolly(&c->cam, c->gesture_point, c->pinch_prev_scale / e->scale));
        } else {
            commands_drag(c, a, c->gesture_point, e->dx, e->dy);
        }
        if (e->scale > 0.0)
            c->pinch_prev_scale = e->scale;
        break;
    }
    case INPUT_SWIPE_UPDATE:
        commands_drag(c, (input_action)g[INPUT_GESTURE_TOUCHPAD_SWIPE], c->gesture_point, e->dx, e->dy);
        break;
    default:
        break;
    }
}

/* ---- time ----------------------------------------------------------------------------------- */

void input_controller_tick(input_controller *c, uint64_t now_us)
{
    c->event_device = -1; /* animations are not arbitrated: the holder started them */
    c->last_tick_us = now_us;
    if (!c->started) { /* the first tick: nobody is there yet */
        c->started = true;
        c->last_input_us = now_us;
        if (c->cfg.have_tour && c->cfg.idle_timeout_s > 0.0)
            commands_start_tour(c);
        return;
    }
    commands_play_if_due(c, now_us); /* the tour plays on too */
    if (c->touring)
        return;
    long_press_if_due(c, now_us);
    if (c->cfg.have_tour && c->cfg.idle_timeout_s > 0.0 && !c->dragging &&
        (double)(now_us - c->last_input_us) * 1e-6 >= c->cfg.idle_timeout_s) {
        bool fingers = false;
        for (int i = 0; i < TOUCH_SLOTS; i++)
            fingers |= c->touches[i].active;
        if (!fingers && !commands_flight_held(c)) {
            commands_start_tour(c);
            return;
        }
    }
    if (c->animating) {
        double s = (double)(now_us - c->anim_start_us) * 1e-6 / c->cfg.fly_to_s;
        if (s >= 1.0) {
            commands_set_camera(c, c->anim_to);
            c->animating = false;
        } else {
            commands_set_camera(c, navigate_blend(&c->anim_from, &c->anim_to, navigate_ease(s)));
        }
    }
    double f, r, u;
    if (commands_flight_direction(c, &f, &r, &u)) {
        double dt_s = (double)(now_us - c->last_flight_us) * 1e-6;
        if (dt_s > MAX_TICK_S)
            dt_s = MAX_TICK_S;
        c->last_flight_us = now_us;
        double step = c->fly_speed * dt_s;
        if (step > 0.0)
            commands_set_camera(c, navigate_fly(&c->cam, f * step, r * step, u * step));
    }
    commands_flush(c);
}

/* input_controller_deadline_us but for a long press. */
static uint64_t deadline_us(const input_controller *c, uint64_t now_us)
{
    if (!c->started)
        return now_us;
    if (c->animating || (!c->touring && commands_flight_held(c)) || c->playing) {
        /* the next tick of the animation clock; a new flight or animation starts with one now */
        uint64_t next = c->last_tick_us + INPUT_TICK_US;
        return next > now_us ? next : now_us;
    }
    if (!c->touring && c->cfg.have_tour && c->cfg.idle_timeout_s > 0.0) {
        uint64_t idle_end = c->last_input_us + (uint64_t)(c->cfg.idle_timeout_s * 1e6);
        /* past it but a button or finger is still down: look again in a second */
        return idle_end > now_us ? idle_end : now_us + 1000000;
    }
    return UINT64_MAX;
}

uint64_t input_controller_deadline_us(const input_controller *c, uint64_t now_us)
{
    uint64_t due = deadline_us(c, now_us), press_due;
    if (c->started && !c->touring && long_press_due(c, &press_due)) {
        if (press_due < now_us)
            press_due = now_us;
        if (press_due < due)
            due = press_due;
    }
    return due;
}
