/* controller.c - input events to input transactions (controller.h): the
 * controller's life (config, create, destroy) and its entry points (events,
 * ticks, the deadline), which hand what they get to gesture.c and commands.c
 * (controller_private.h). */
#include "controller.h"
#include "controller_private.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "navigate.h"

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

/* ---- events ------------------------------------------------------------------------------- */

static double clamp_plane(double v) { return v < -1.0 ? -1.0 : v > 1.0 ? 1.0 : v; }

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
        gesture_device_removed(c, e->device);
        if (c->cam_holder == e->device) /* a holder that went away lets go at once */
            c->cam_holder = -1;
        return;
    case INPUT_FRAME:
        commands_flush(c);
        return;
    case INPUT_TOUCH_FRAME:
        gesture_long_press_if_due(c, e->time_us);
        gesture_touch_frame(c, e->time_us);
        commands_flush(c);
        return;
    default:
        break;
    }
    commands_user_input(c, e->time_us);
    if (e->kind == INPUT_TOUCH_MOTION || e->kind == INPUT_TOUCH_UP)
        gesture_long_press_if_due(c, e->time_us);
    const unsigned char *g = c->cfg.bindings.gesture_action;
    switch (e->kind) {
    case INPUT_KEY:
    case INPUT_BUTTON:
        gesture_key_or_button(c, e);
        break;
    case INPUT_POINTER_MOTION:
        gesture_pointer_moved(c, clamp_plane(c->cur_x + e->dx), clamp_plane(c->cur_y + e->dy));
        break;
    case INPUT_POINTER_ABS:
        gesture_pointer_moved(c, clamp_plane(e->x), clamp_plane(e->y));
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
        gesture_touch_event(c, e);
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
    gesture_long_press_if_due(c, now_us);
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
    if (c->started && !c->touring && gesture_long_press_due(c, &press_due)) {
        if (press_due < now_us)
            press_due = now_us;
        if (press_due < due)
            due = press_due;
    }
    return due;
}
