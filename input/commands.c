/* commands.c - what the controller recognised turned into records (controller.h):
 * the output of records and the camera holder, picking, the camera motions,
 * the part commands, opacity, cutting planes and the other inspection
 * commands, the kiosk's tour on and off. */
#include "controller.h"
#include "controller_private.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "engine/base/colormap.h"
#include "navigate.h"

#define DOLLY_PER_UNIT 2.0        /* a dolly drag of one plane unit up scales distances by e^-2 */
#define SPEED_STEP 1.5
#define FLY_TO_DISTANCE 0.5       /* fly-to ends at this fraction of the distance to the point */

/* ---- output -------------------------------------------------------------- */

/* Every record goes out here. A private view's controller (cfg.private_channel)
 * says only where its channel's camera goes: the rest of what it would say
 * (cursor, status, scene commands) belongs to the shared view. */
void commands_emit(input_controller *c, input_txn *t)
{
    if (c->cfg.private_channel > 0) {
        if (t->kind != TXN_CAMERA)
            return;
        t->args.camera.channel = c->cfg.private_channel;
    }
    c->hooks.emit(c->hooks.ctx, t);
}

void input_controller_jump(input_controller *c, camera_desc cam)
{
    c->animating = false;
    c->cam = cam;
    input_txn t = txn_camera(TXN_ALL_CHANNELS, &c->cam);
    commands_emit(c, &t);
    c->cam_dirty = false;
}

static void emit_status(input_controller *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void emit_status(input_controller *c, const char *fmt, ...)
{
    input_txn t = txn_status("");
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(t.args.status.text, sizeof t.args.status.text, fmt, ap);
    va_end(ap);
    c->status_shown = t.args.status.text[0] != '\0';
    commands_emit(c, &t);
}

static void emit_plane(input_controller *c, int index)
{
    const clip_plane *p = &c->planes[index];
    const float point[3] = {p->point.x, p->point.y, p->point.z}, normal[3] = {p->normal.x, p->normal.y, p->normal.z};
    input_txn t = txn_clip_plane(index, p->on, point, normal);
    commands_emit(c, &t);
}

/* Every value moved by `fraction` of its range, clamped (c->values; no record). */
static void move_values(input_controller *c, double fraction)
{
    for (int i = 0; i < c->cfg.value_count; i++) {
        const input_value_target *tg = &c->cfg.values[i];
        double v = (double)c->values[i] + fraction * ((double)tg->hi - tg->lo);
        c->values[i] = (float)(v < tg->lo ? tg->lo : v > tg->hi ? tg->hi : v);
    }
}

/* One "value" record per target with c->values, and the status line. */
static void emit_values(input_controller *c)
{
    char text[INPUT_TEXT_BYTES] = "";
    size_t used = 0;
    for (int i = 0; i < c->cfg.value_count; i++) {
        const input_value_target *tg = &c->cfg.values[i];
        input_txn t = txn_value(tg->first, tg->count, c->values[i]);
        commands_emit(c, &t);
        int n = snprintf(text + used, sizeof text - used, "%siso-value %.4g", i ? "; " : "", (double)c->values[i]);
        if (n > 0 && (size_t)n < sizeof text - used)
            used += (size_t)n;
    }
    emit_status(c, "%s", text);
}

/* End of an input frame or tick: at most one camera, one cursor, one plane
 * and one value record per value target. */
void commands_flush(input_controller *c)
{
    if (c->values_dirty) {
        emit_values(c);
        c->values_dirty = false;
    }
    if (c->plane_dirty) {
        if (c->plane_sel >= 0)
            emit_plane(c, c->plane_sel);
        c->plane_dirty = false;
    }
    if (c->cam_dirty) {
        input_txn t = txn_camera(TXN_ALL_CHANNELS, &c->cam);
        commands_emit(c, &t);
        c->cam_dirty = false;
    }
    if (c->cursor_dirty) {
        input_txn t = txn_cursor(c->cursor_visible, (float)c->cur_x, (float)c->cur_y);
        commands_emit(c, &t);
        c->cursor_dirty = false;
    }
    for (int i = 0; i < INPUT_MAX_VIEWERS; i++)
        if (c->pointer_dirty[i]) {
            input_txn t = txn_pointer(i, c->pointer_visible[i], (float)c->pointer_x[i], (float)c->pointer_y[i]);
            commands_emit(c, &t);
            c->pointer_dirty[i] = false;
        }
}

/* Whether `device` has a camera gesture going: a drag, or a finger down. */
static bool gesture_going(const input_controller *c, int device)
{
    if (c->dragging && c->drag_device == device)
        return true;
    for (int i = 0; i < TOUCH_SLOTS; i++)
        if (c->touches[i].active && c->touches[i].device == device)
            return true;
    return false;
}

/* CAMERA HOLDER: may the event being handled move the camera? Takes the
 * camera for its device when nobody holds it (or the holder's hold ran
 * out), and extends the hold. Ticks (animations) always may. */
static bool may_move_camera(input_controller *c)
{
    int d = c->event_device;
    if (d < 0)
        return true;
    bool held = c->cam_holder >= 0 && c->cam_holder != d &&
                (c->event_us < c->cam_hold_until_us || gesture_going(c, c->cam_holder));
    if (held)
        return false;
    c->cam_holder = d;
    c->cam_hold_until_us = c->event_us + (uint64_t)(INPUT_CAMERA_HOLD_S * 1e6);
    return true;
}

void commands_set_camera(input_controller *c, camera_desc next)
{
    if (memcmp(&next, &c->cam, sizeof next) != 0 && may_move_camera(c)) {
        c->cam = next;
        c->cam_dirty = true;
    }
}

void commands_show_cursor(input_controller *c, bool visible)
{
    if (c->cursor_visible != visible) {
        c->cursor_visible = visible;
        c->cursor_dirty = true;
    }
}

/* ---- picking ---------------------------------------------------------------- */

static double view_distance(const camera_desc *cam)
{
    return v3_length(v3_sub(cam->look_at, cam->eye));
}

/* The point under plane point (sx, sy): the first surface, else the cursor
 * ray at the depth of the look-at point. */
vec3 commands_point_under(input_controller *c, double sx, double sy, input_hit *hit_out)
{
    vec3 origin, dir;
    navigate_plane_ray(&c->cam, c->cfg.plane_aspect, sx, sy, &origin, &dir);
    input_hit pk = {.hit = false};
    c->hooks.pick(c->hooks.ctx, origin, dir, &pk);
    if (pk.hit && pk.part.count == 0) { /* a pick that names no part: the instance hit is one */
        pk.part.first = pk.geom_id;
        pk.part.count = 1;
        if (!pk.part.label[0])
            snprintf(pk.part.label, sizeof pk.part.label, "%s", pk.what);
    }
    pk.part.label[sizeof pk.part.label - 1] = '\0';
    if (pk.ancestor_count < 0 || pk.ancestor_count > INPUT_HIT_ANCESTORS)
        pk.ancestor_count = pk.ancestor_count < 0 ? 0 : INPUT_HIT_ANCESTORS;
    for (int i = 0; i < pk.ancestor_count; i++)
        pk.ancestors[i].label[sizeof pk.ancestors[i].label - 1] = '\0';
    if (hit_out)
        *hit_out = pk;
    if (pk.hit)
        return pk.point;
    vec3 view = v3_normalize(v3_sub(c->cam.look_at, c->cam.eye));
    double cosine = v3_dot(dir, view);
    double t = view_distance(&c->cam) / (cosine > 0.05 ? cosine : 0.05);
    return v3_add(origin, v3_scale(dir, (float)t));
}

/* ---- motions ---------------------------------------------------------------- */

/* A drag of (dx, dy) plane units with `action` about `point`. */
void commands_drag(input_controller *c, input_action action, vec3 point, double dx, double dy)
{
    if (dx == 0.0 && dy == 0.0)
        return;
    switch (action) {
    case INPUT_ACTION_ORBIT: {
        /* the same turn per physical length across and up the plane */
        double k = c->cfg.orbit_rad_per_unit;
        commands_set_camera(c, navigate_orbit(&c->cam, point, -dx * k, -dy * k / c->cfg.plane_aspect));
        break;
    }
    case INPUT_ACTION_PAN: {
        vec3 view = v3_normalize(v3_sub(c->cam.look_at, c->cam.eye));
        double depth = v3_dot(v3_sub(point, c->cam.eye), view);
        if (depth > 0.0)
            commands_set_camera(c, navigate_pan(&c->cam, c->cfg.plane_aspect, depth, dx, dy));
        break;
    }
    case INPUT_ACTION_DOLLY:
        commands_set_camera(c, navigate_dolly(&c->cam, point, exp(-dy * DOLLY_PER_UNIT)));
        break;
    case INPUT_ACTION_VALUE_DRAG: /* up (dy > 0: plane y points up) raises; the picture's height (2 units) is the range */
        if (c->cfg.value_count > 0 && dy != 0.0) {
            move_values(c, dy * INPUT_VALUE_DRAG_PER_UNIT);
            c->values_dirty = true;
        }
        break;
    case INPUT_ACTION_PLANE_PUSH: {
        if (c->plane_sel < 0 || dy == 0.0)
            break;
        clip_plane *p = &c->planes[c->plane_sel];
        double along = -dy * INPUT_PLANE_PUSH_PER_UNIT * c->cfg.scene_size; /* up: against the normal */
        p->point = v3((float)((double)p->point.x + along * (double)p->normal.x),
                      (float)((double)p->point.y + along * (double)p->normal.y),
                      (float)((double)p->point.z + along * (double)p->normal.z));
        c->plane_dirty = true;
        break;
    }
    default:
        break;
    }
}

static void animate_to(input_controller *c, camera_desc target, uint64_t now_us)
{
    c->animating = true;
    c->anim_from = c->cam;
    c->anim_to = target;
    c->anim_start_us = now_us;
}

/* The held flight keys as a direction (each -1, 0 or +1 along forward, right,
 * up; of two opposite keys held together the one with the higher code wins);
 * whether any is held. One pass over the held codes. */
bool commands_flight_direction(const input_controller *c, double *forward, double *right, double *up)
{
    double f = 0.0, r = 0.0, u = 0.0;
    bool any = false;
    for (int code = 0; code < INPUT_CODE_COUNT; code++) {
        if (!c->held[code])
            continue;
        switch ((input_action)c->cfg.bindings.code_action[code]) {
        case INPUT_ACTION_FLY_FORWARD: f = 1.0; any = true; break;
        case INPUT_ACTION_FLY_BACK: f = -1.0; any = true; break;
        case INPUT_ACTION_FLY_RIGHT: r = 1.0; any = true; break;
        case INPUT_ACTION_FLY_LEFT: r = -1.0; any = true; break;
        case INPUT_ACTION_FLY_UP: u = 1.0; any = true; break;
        case INPUT_ACTION_FLY_DOWN: u = -1.0; any = true; break;
        default: break;
        }
    }
    if (forward) {
        *forward = f;
        *right = r;
        *up = u;
    }
    return any;
}

bool commands_flight_held(const input_controller *c) { return commands_flight_direction(c, NULL, NULL, NULL); }

/* ---- parts ------------------------------------------------------------------- */

static const input_part *selection(const input_controller *c)
{
    return c->have_selection ? &c->sel_levels[c->sel_level] : NULL;
}

static bool same_range(const input_part *a, const input_part *b)
{
    return a->first == b->first && a->count == b->count;
}

/* While highlight is on it follows the selection: off on the range it lit,
 * on on the selection's (off altogether when nothing is selected). */
static void highlight_follow(input_controller *c)
{
    if (!c->highlight_on)
        return;
    const input_part *sel = selection(c);
    if (sel && same_range(sel, &c->highlighted))
        return;
    input_txn t = txn_highlight(c->highlighted.first, c->highlighted.count, false);
    commands_emit(c, &t);
    if (!sel) {
        c->highlight_on = false;
        return;
    }
    c->highlighted = *sel;
    t = txn_highlight(sel->first, sel->count, true);
    commands_emit(c, &t);
}

/* The selection becomes the part hit (nothing on a miss). */
void commands_select_hit(input_controller *c, const input_hit *pk)
{
    c->have_selection = pk->hit;
    if (pk->hit) {
        c->sel_levels[0] = pk->part;
        for (int i = 0; i < pk->ancestor_count; i++)
            c->sel_levels[1 + i] = pk->ancestors[i];
        c->sel_level_count = 1 + pk->ancestor_count;
        c->sel_level = 0;
    }
    highlight_follow(c);
}

static void remember_hidden(input_controller *c, const input_part *p)
{
    if (c->hidden_count == INPUT_HIDDEN_MAX) { /* the oldest is forgotten (show-all still shows it) */
        memmove(&c->hidden[0], &c->hidden[1], (INPUT_HIDDEN_MAX - 1) * sizeof c->hidden[0]);
        c->hidden_count--;
    }
    c->hidden[c->hidden_count++] = *p;
}

/* The part commands (controller.h, PARTS) at plane point (sx, sy). */
static void part_command(input_controller *c, input_action action, double sx, double sy)
{
    input_hit pk;
    const input_part *sel = selection(c);
    switch (action) {
    case INPUT_ACTION_HIDE_OBJECT:
        commands_point_under(c, sx, sy, &pk);
        if (pk.hit) {
            input_txn t = txn_geoms_record(TXN_HIDE, pk.part.first, pk.part.count);
            commands_emit(c, &t);
            remember_hidden(c, &pk.part);
            emit_status(c, "hidden: %s", pk.part.label);
        } else {
            emit_status(c, "nothing to hide there");
        }
        break;
    case INPUT_ACTION_SHOW:
        if (c->hidden_count == 0) {
            emit_status(c, "nothing hidden to show");
        } else {
            const input_part *p = &c->hidden[--c->hidden_count];
            input_txn t = txn_geoms_record(TXN_SHOW, p->first, p->count);
            commands_emit(c, &t);
            emit_status(c, "shown: %s", p->label);
        }
        break;
    case INPUT_ACTION_ISOLATE:
        if (!sel) {
            commands_point_under(c, sx, sy, &pk);
            if (!pk.hit) {
                emit_status(c, "nothing to isolate there");
                break;
            }
            commands_select_hit(c, &pk);
            sel = selection(c);
        }
        {
            input_txn t = txn_geoms_record(TXN_ISOLATE, sel->first, sel->count);
            commands_emit(c, &t);
            emit_status(c, "isolated: %s (%u instance%s)", sel->label, sel->count, sel->count == 1 ? "" : "s");
        }
        break;
    case INPUT_ACTION_SHOW_ALL: {
        input_txn t = txn_simple(TXN_SHOW_ALL);
        commands_emit(c, &t);
        c->hidden_count = 0;
        emit_status(c, "all parts shown");
        break;
    }
    case INPUT_ACTION_SELECT_PARENT:
        if (!sel) {
            emit_status(c, "nothing selected (pick a part first)");
            break;
        }
        if (c->sel_level + 1 < c->sel_level_count) {
            c->sel_level++;
            highlight_follow(c);
            sel = selection(c);
            emit_status(c, "selected: %s (%u instance%s)", sel->label, sel->count, sel->count == 1 ? "" : "s");
        } else {
            emit_status(c, "selected: %s (%u instance%s; no parent above it)", sel->label, sel->count,
                        sel->count == 1 ? "" : "s");
        }
        break;
    case INPUT_ACTION_HIGHLIGHT:
        if (!sel) {
            emit_status(c, "nothing selected to highlight (pick a part first)");
        } else if (c->highlight_on) {
            c->highlight_on = false;
            input_txn t = txn_highlight(c->highlighted.first, c->highlighted.count, false);
            commands_emit(c, &t);
            emit_status(c, "highlight off: %s", sel->label);
        } else {
            c->highlight_on = true;
            c->highlighted = *sel;
            input_txn t = txn_highlight(sel->first, sel->count, true);
            commands_emit(c, &t);
            emit_status(c, "highlighted: %s", sel->label);
        }
        break;
    default:
        break;
    }
}

/* ---- opacity and cutting planes ---------------------------------------------------- */

/* One opacity step from `from` (dir -1 or +1) on the grid of INPUT_OPACITY_STEPS, clamped. */
static float opacity_step(float from, int dir)
{
    double k = (double)from * INPUT_OPACITY_STEPS;
    if (fabs(k - nearbyint(k)) < 1e-4) /* a grid value as a float (0.9f is not 9 / 10) */
        k = nearbyint(k);
    double next = dir < 0 ? ceil(k) - 1.0 : floor(k) + 1.0; /* the grid value beyond `from` */
    if (next < 0.0)
        next = 0.0;
    if (next > INPUT_OPACITY_STEPS)
        next = INPUT_OPACITY_STEPS;
    return (float)(next / INPUT_OPACITY_STEPS);
}

/* What input last set for the range [first, first + count): its own entry, else the innermost
 * remembered range holding it, else 1. */
static float part_opacity_of(const input_controller *c, uint32_t first, uint32_t count)
{
    float found = 1.f;
    uint64_t best = UINT64_MAX;
    for (int i = 0; i < c->part_opacity_count; i++) {
        uint64_t f = c->part_opacity[i].first, n = c->part_opacity[i].count;
        if (f <= first && f + n >= (uint64_t)first + count && n < best) {
            best = n;
            found = c->part_opacity[i].opacity;
        }
    }
    return found;
}

static void remember_part_opacity(input_controller *c, uint32_t first, uint32_t count, float opacity)
{
    int kept = 0;
    for (int i = 0; i < c->part_opacity_count; i++) { /* ranges inside this one were overwritten */
        uint64_t f = c->part_opacity[i].first, n = c->part_opacity[i].count;
        if (!(f >= first && f + n <= (uint64_t)first + count))
            c->part_opacity[kept++] = c->part_opacity[i];
    }
    c->part_opacity_count = kept;
    if (c->part_opacity_count == INPUT_OPACITY_PARTS) {
        memmove(&c->part_opacity[0], &c->part_opacity[1], (INPUT_OPACITY_PARTS - 1) * sizeof c->part_opacity[0]);
        c->part_opacity_count--;
    }
    c->part_opacity[c->part_opacity_count].first = first;
    c->part_opacity[c->part_opacity_count].count = count;
    c->part_opacity[c->part_opacity_count++].opacity = opacity;
}

static void opacity_command(input_controller *c, input_action action)
{
    int dir = action == INPUT_ACTION_OPACITY_DOWN || action == INPUT_ACTION_PART_OPACITY_DOWN ? -1 : 1;
    if (action == INPUT_ACTION_OPACITY_DOWN || action == INPUT_ACTION_OPACITY_UP) {
        float next = opacity_step(c->opacity, dir);
        if (next == c->opacity) {
            emit_status(c, "opacity %.2g (the %s)", (double)next, dir < 0 ? "least" : "most");
            return;
        }
        c->opacity = next;
        input_txn t = txn_opacity_all(next);
        commands_emit(c, &t);
        emit_status(c, "opacity %.2g", (double)next);
        return;
    }
    const input_part *sel = selection(c);
    if (!sel) {
        emit_status(c, "nothing selected to make transparent (pick a part first)");
        return;
    }
    float from = part_opacity_of(c, sel->first, sel->count), next = opacity_step(from, dir);
    if (next == from) {
        emit_status(c, "opacity of %s %.2g (the %s)", sel->label, (double)next, dir < 0 ? "least" : "most");
        return;
    }
    remember_part_opacity(c, sel->first, sel->count, next);
    input_txn t = txn_opacity(sel->first, sel->count, next);
    commands_emit(c, &t);
    emit_status(c, "opacity of %s %.2g", sel->label, (double)next);
}

/* ambient-occlusion: the next renderer of the cycle (controller.h, AMBIENT OCCLUSION). */
static void ambient_occlusion_command(input_controller *c)
{
    const char *next = !strcmp(c->renderer, "raytracer-ao") ? "ao"
                       : !strcmp(c->renderer, "ao")         ? c->configured
                                                            : "raytracer-ao";
    snprintf(c->renderer, sizeof c->renderer, "%s", next);
    input_txn t = txn_renderer(next);
    commands_emit(c, &t);
    emit_status(c, "renderer %s%s", next,
                !strcmp(next, "raytracer-ao") ? " (ambient occlusion on)"
                : !strcmp(next, "ao")         ? " (ambient occlusion alone)"
                                              : " (ambient occlusion off)");
}

/* crop-down, crop-up, crop-off on every particle set with a crop (controller.h, CROP). */
static void crop_command(input_controller *c, input_action action)
{
    if (c->cfg.crop_count == 0) {
        emit_status(c, "nothing to crop (no particles with a crop attribute)");
        return;
    }
    char text[INPUT_TEXT_BYTES] = "";
    size_t used = 0;
    for (int i = 0; i < c->cfg.crop_count; i++) {
        const input_crop_target *tg = &c->cfg.crops[i];
        geometry_crop *cur = &c->crops[i];
        float range = tg->max - tg->min;
        if (action == INPUT_ACTION_CROP_OFF) {
            cur->active = false;
        } else if (!cur->active) { /* start at the end the step comes from */
            float width = INPUT_CROP_WINDOW * range;
            *cur = action == INPUT_ACTION_CROP_UP ? (geometry_crop){true, tg->min, tg->min + width}
                                                  : (geometry_crop){true, tg->max - width, tg->max};
        } else {
            float width = cur->hi - cur->lo;
            if (!(width > 0.f))
                width = INPUT_CROP_WINDOW * range;
            float lo = cur->lo + (action == INPUT_ACTION_CROP_UP ? 0.5f : -0.5f) * width;
            lo = lo + width > tg->max ? tg->max - width : lo;
            lo = lo < tg->min ? tg->min : lo;
            *cur = (geometry_crop){true, lo, lo + width};
        }
        input_txn t = txn_crop(tg->first, tg->count, cur->active, cur->lo, cur->hi);
        commands_emit(c, &t);
        int n = cur->active ? snprintf(text + used, sizeof text - used, "%scrop %s [%.4g, %.4g]", i ? "; " : "",
                                       tg->attribute, (double)cur->lo, (double)cur->hi)
                            : snprintf(text + used, sizeof text - used, "%scrop %s off", i ? "; " : "",
                                       tg->attribute);
        if (n > 0 && (size_t)n < sizeof text - used)
            used += (size_t)n;
    }
    emit_status(c, "%s", text);
}

/* value-down / value-up (controller.h, VALUES AND MAPS). */
static void value_command(input_controller *c, int dir)
{
    if (c->cfg.value_count == 0) {
        emit_status(c, "no iso-values to change in this scene");
        return;
    }
    move_values(c, dir / INPUT_VALUE_STEPS);
    c->values_dirty = false; /* a drag's move goes out with these records */
    emit_values(c);
}

/* colormap-next (controller.h, VALUES AND MAPS). */
static void colormap_command(input_controller *c)
{
    if (c->cfg.map_count == 0 && !c->cfg.media) {
        emit_status(c, "nothing coloured through a map in this scene");
        return;
    }
    const char *const *names = colormap_names();
    if (c->cfg.media) { /* the next built-in with opacity after the one in use */
        int k = 0, count = 0;
        while (names[count])
            count++;
        while (k < count && strcmp(names[k], c->transfer) != 0)
            k++;
        for (int step = 1; step <= count; step++) {
            colormap probe;
            const char *next = names[(k + step) % count];
            if (colormap_preset(next, &probe) && probe.opacity_count > 0) {
                snprintf(c->transfer, sizeof c->transfer, "%s", next);
                break;
            }
        }
        input_txn t = txn_transfer(c->transfer);
        commands_emit(c, &t);
        if (c->cfg.map_count == 0) {
            emit_status(c, "transfer function %s", c->transfer);
            return;
        }
    }
    for (int i = 0; i < c->cfg.map_count; i++) {
        int k = 0;
        while (names[k] && strcmp(names[k], c->maps[i]) != 0)
            k++;
        const char *next = names[k] && names[k + 1] ? names[k + 1] : names[0]; /* unknown: the first */
        snprintf(c->maps[i], sizeof c->maps[i], "%s", next);
        input_txn t = txn_colormap(c->cfg.maps[i].first, c->cfg.maps[i].count, next);
        commands_emit(c, &t);
    }
    emit_status(c, "colour map %s", c->maps[0]);
}

/* Ask for time step `step` and say so. */
static void emit_time_step(input_controller *c, uint32_t step)
{
    c->time_step = step;
    input_txn t = txn_time_step(step);
    commands_emit(c, &t);
    emit_status(c, "time step %u/%u%s", step + 1, c->cfg.time_steps, c->playing ? " (playing)" : "");
}

/* time-play, -back, -forward, -slower, -faster (controller.h, TIME STEPS). */
static void time_command(input_controller *c, input_action action, uint64_t now_us)
{
    uint32_t n = c->cfg.time_steps;
    if (n < 2) {
        emit_status(c, "no time steps in this scene");
        return;
    }
    switch (action) {
    case INPUT_ACTION_TIME_PLAY:
        c->playing = !c->playing;
        c->next_step_us = now_us + (uint64_t)(1e6 / c->time_rate);
        emit_status(c, "time step %u/%u (%s, %.3g steps/s)", c->time_step + 1, n, c->playing ? "playing" : "paused",
                    c->time_rate);
        break;
    case INPUT_ACTION_TIME_BACK: emit_time_step(c, (c->time_step + n - 1) % n); break;
    case INPUT_ACTION_TIME_FORWARD: emit_time_step(c, (c->time_step + 1) % n); break;
    default: /* slower, faster */
        c->time_rate *= action == INPUT_ACTION_TIME_FASTER ? 1.5 : 1.0 / 1.5;
        c->time_rate = c->time_rate < 0.05 ? 0.05 : c->time_rate > 120.0 ? 120.0 : c->time_rate;
        emit_status(c, "time: %.3g steps/s", c->time_rate);
        break;
    }
}

/* Playing: the next step when it is due and loaded (else look again next tick). */
void commands_play_if_due(input_controller *c, uint64_t now_us)
{
    if (!c->playing || now_us < c->next_step_us)
        return;
    uint32_t next = (c->time_step + 1) % c->cfg.time_steps;
    if (c->hooks.step_ready && !c->hooks.step_ready(c->hooks.ctx, next))
        return;
    emit_time_step(c, next);
    c->next_step_us += (uint64_t)(1e6 / c->time_rate);
    if (c->next_step_us < now_us) /* loading was slower than the rate: no catching up */
        c->next_step_us = now_us + (uint64_t)(1e6 / c->time_rate);
}

/* The next plane that is on after `after` (wrapping, `after` itself last), or -1. */
static int next_plane_on(const input_controller *c, int after)
{
    for (int k = 1; k <= CLIP_MAX_PLANES; k++) {
        int i = ((after < 0 ? -1 : after) + k) % CLIP_MAX_PLANES;
        if (c->planes[i].on)
            return i;
    }
    return -1;
}

static void plane_command(input_controller *c, input_action action, double sx, double sy)
{
    if (c->plane_dirty) /* a push still waiting for its frame's end goes first */
        commands_flush(c);
    int sel = c->plane_sel;
    switch (action) {
    case INPUT_ACTION_PLANE_PLACE: {
        input_hit pk;
        commands_point_under(c, sx, sy, &pk);
        if (!pk.hit) {
            emit_status(c, "no surface there to place a cutting plane on");
            return;
        }
        double d[3] = {(double)c->cam.eye.x - pk.point.x, (double)c->cam.eye.y - pk.point.y,
                       (double)c->cam.eye.z - pk.point.z};
        double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(len > 0.0)) {
            emit_status(c, "the eye is on that point: no direction for a plane");
            return;
        }
        int index = -1;
        for (int i = 0; i < CLIP_MAX_PLANES && index < 0; i++)
            if (!c->planes[i].on)
                index = i;
        if (index < 0)
            index = sel >= 0 ? sel : 0; /* all on: the selected one moves here */
        c->planes[index] = (clip_plane){pk.point, v3((float)(d[0] / len), (float)(d[1] / len), (float)(d[2] / len)),
                                        true};
        c->plane_sel = index;
        emit_plane(c, index);
        emit_status(c, "cutting plane %d at (%.4g, %.4g, %.4g)", index, (double)pk.point.x, (double)pk.point.y,
                    (double)pk.point.z);
        return;
    }
    case INPUT_ACTION_PLANE_REMOVE_ALL: {
        int removed = 0;
        for (int i = 0; i < CLIP_MAX_PLANES; i++)
            if (c->planes[i].on) {
                c->planes[i].on = false;
                emit_plane(c, i);
                removed++;
            }
        c->plane_sel = -1;
        if (removed)
            emit_status(c, "all cutting planes removed");
        else
            emit_status(c, "no cutting planes to remove");
        return;
    }
    default:
        break;
    }
    if (sel < 0) {
        emit_status(c, "no cutting plane (place one first)");
        return;
    }
    clip_plane *p = &c->planes[sel];
    switch (action) {
    case INPUT_ACTION_PLANE_NEXT:
        c->plane_sel = next_plane_on(c, sel);
        emit_status(c, "cutting plane %d selected", c->plane_sel);
        break;
    case INPUT_ACTION_PLANE_FLIP:
        p->normal = v3(-p->normal.x, -p->normal.y, -p->normal.z);
        emit_plane(c, sel);
        emit_status(c, "cutting plane %d flipped", sel);
        break;
    case INPUT_ACTION_PLANE_REMOVE:
        p->on = false;
        emit_plane(c, sel);
        c->plane_sel = next_plane_on(c, sel);
        emit_status(c, "cutting plane %d removed", sel);
        break;
    default:
        break;
    }
}

/* A command action at plane point (sx, sy). */
void commands_run(input_controller *c, input_action action, double sx, double sy, uint64_t now_us)
{
    input_hit pk;
    switch (action) {
    case INPUT_ACTION_PICK:
        commands_point_under(c, sx, sy, &pk);
        commands_select_hit(c, &pk);
        if (pk.hit)
            emit_status(c, "picked %s at (%.4g, %.4g, %.4g)", pk.what, (double)pk.point.x, (double)pk.point.y,
                        (double)pk.point.z);
        else
            emit_status(c, "picked nothing (background)");
        break;
    case INPUT_ACTION_HIDE_OBJECT:
    case INPUT_ACTION_SHOW:
    case INPUT_ACTION_ISOLATE:
    case INPUT_ACTION_SHOW_ALL:
    case INPUT_ACTION_SELECT_PARENT:
    case INPUT_ACTION_HIGHLIGHT:
        part_command(c, action, sx, sy);
        break;
    case INPUT_ACTION_OPACITY_DOWN:
    case INPUT_ACTION_OPACITY_UP:
    case INPUT_ACTION_PART_OPACITY_DOWN:
    case INPUT_ACTION_PART_OPACITY_UP:
        opacity_command(c, action);
        break;
    case INPUT_ACTION_PLANE_PLACE:
    case INPUT_ACTION_PLANE_NEXT:
    case INPUT_ACTION_PLANE_FLIP:
    case INPUT_ACTION_PLANE_REMOVE:
    case INPUT_ACTION_PLANE_REMOVE_ALL:
        plane_command(c, action, sx, sy);
        break;
    case INPUT_ACTION_AMBIENT_OCCLUSION:
        ambient_occlusion_command(c);
        break;
    case INPUT_ACTION_CROP_DOWN:
    case INPUT_ACTION_CROP_UP:
    case INPUT_ACTION_CROP_OFF:
        crop_command(c, action);
        break;
    case INPUT_ACTION_VALUE_DOWN:
    case INPUT_ACTION_VALUE_UP:
        value_command(c, action == INPUT_ACTION_VALUE_UP ? 1 : -1);
        break;
    case INPUT_ACTION_COLORMAP_NEXT:
        colormap_command(c);
        break;
    case INPUT_ACTION_TIME_PLAY:
    case INPUT_ACTION_TIME_BACK:
    case INPUT_ACTION_TIME_FORWARD:
    case INPUT_ACTION_TIME_SLOWER:
    case INPUT_ACTION_TIME_FASTER:
        time_command(c, action, now_us);
        break;
    case INPUT_ACTION_GOVERNOR_STATUS: {
        c->governor_status_shown = !c->governor_status_shown;
        input_txn t = txn_flag(TXN_GOVERNOR_STATUS, c->governor_status_shown);
        commands_emit(c, &t);
        break;
    }
    case INPUT_ACTION_FLY_TO: {
        vec3 p = commands_point_under(c, sx, sy, &pk);
        if (!pk.hit) {
            emit_status(c, "nothing there to fly to");
            break;
        }
        double d = v3_length(v3_sub(p, c->cam.eye)) * FLY_TO_DISTANCE;
        if (d < c->cfg.scene_size * 1e-4)
            d = c->cfg.scene_size * 1e-4;
        animate_to(c, navigate_look_at_point(&c->cam, p, d), now_us);
        break;
    }
    case INPUT_ACTION_HOME:
        animate_to(c, c->cfg.home, now_us);
        break;
    case INPUT_ACTION_SPEED_UP:
    case INPUT_ACTION_SPEED_DOWN:
        c->fly_speed = action == INPUT_ACTION_SPEED_UP ? c->fly_speed * SPEED_STEP : c->fly_speed / SPEED_STEP;
        emit_status(c, "flight speed %.3g units/s", c->fly_speed);
        break;
    default:
        break;
    }
}

/* ---- kiosk -------------------------------------------------------------------- */

/* A person touched something: the tour hands over (steering starts from the
 * camera it showed) and the idle clock restarts. */
void commands_user_input(input_controller *c, uint64_t now_us)
{
    c->last_input_us = now_us;
    c->started = true;
    if (!c->touring)
        return;
    c->touring = false;
    c->cam = c->hooks.current_camera(c->hooks.ctx);
    c->cam_dirty = false;
    input_txn t = txn_flag(TXN_TOUR, false);
    commands_emit(c, &t);
}

void commands_start_tour(input_controller *c)
{
    c->touring = true;
    c->animating = false;
    c->dragging = false;
    c->cam_dirty = false;
    commands_show_cursor(c, false);
    commands_flush(c);
    if (c->status_shown) /* the tour shows no status line */
        emit_status(c, "%s", "");
    input_txn t = txn_flag(TXN_TOUR, true);
    commands_emit(c, &t);
}
