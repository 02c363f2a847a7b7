/* gesture.c - what a person is doing, recognised from the events (controller.h):
 * keys and buttons held (the quit chord, button drags and clicks, flight keys),
 * the pointer, touch (taps, double taps, long presses, two- and three-finger
 * taps, one-finger, two-finger and three-finger drags, pinches), devices that
 * go away. What it recognises it hands to commands.c as an action. */
#include "controller.h"
#include "controller_private.h"

#include <math.h>

#include "navigate.h"

#define TAP_MAX_S 0.30            /* a tap is shorter than this ... */
#define TAP_SLOP 0.02             /* ... and moves less than this (plane units) */
#define DOUBLE_TAP_S 0.40         /* second tap within this of the first's end ... */
#define DOUBLE_TAP_DIST 0.06      /* ... and this close to it */
#define CLICK_SLOP 0.01           /* a button released having moved less than this is a click */

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

void gesture_key_or_button(input_controller *c, const input_event *e)
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

void gesture_pointer_moved(input_controller *c, double nx, double ny)
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
bool gesture_long_press_due(const input_controller *c, uint64_t *due_us)
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
void gesture_long_press_if_due(input_controller *c, uint64_t now_us)
{
    uint64_t due;
    if (!c->touring && gesture_long_press_due(c, &due) && now_us >= due)
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

void gesture_touch_frame(input_controller *c, uint64_t now_us)
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

void gesture_touch_event(input_controller *c, const input_event *e)
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

void gesture_device_removed(input_controller *c, int device)
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
