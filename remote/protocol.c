/* protocol.c (remote) - the page's messages, their events, the rate limit
 * and the frame header (protocol.h, docs/remote-protocol.md). */
#include "protocol.h"

#include <json-c/json.h>
#include <linux/input-event-codes.h>
#include <math.h>
#include <string.h>

#include "input/source.h"

#define JSON_DEPTH_MAX 4 /* a message is an object holding arrays of objects: depth 3 */
/* Fractions a browser reports a little outside [0, 1] for a drag past the
 * canvas edge (pointer capture): clamped. Beyond these: out of range. */
#define FRACTION_LO -1.0
#define FRACTION_HI 2.0
#define WHEEL_CLICKS_MAX 100.0

static const char *const drop_names[REMOTE_DROP_REASONS] = {
    [REMOTE_DROP_NOT_JSON] = "not-json",
    [REMOTE_DROP_NOT_OBJECT] = "not-object",
    [REMOTE_DROP_UNKNOWN_TYPE] = "unknown-type",
    [REMOTE_DROP_MISSING_FIELD] = "missing-field",
    [REMOTE_DROP_WRONG_TYPE] = "wrong-type",
    [REMOTE_DROP_OUT_OF_RANGE] = "out-of-range",
    [REMOTE_DROP_UNKNOWN_KEY] = "unknown-key",
    [REMOTE_DROP_TOO_LONG] = "too-long",
    [REMOTE_DROP_RATE] = "over-rate",
    [REMOTE_DROP_BINARY] = "binary",
};

const char *remote_drop_reason_name(remote_drop_reason r)
{
    return (unsigned)r < REMOTE_DROP_REASONS ? drop_names[r] : "?";
}

/* ---- keys ---------------------------------------------------------------------- */

static const struct {
    const char *code;
    int key;
} keys[] = {
    {"KeyA", KEY_A}, {"KeyB", KEY_B}, {"KeyC", KEY_C}, {"KeyD", KEY_D}, {"KeyE", KEY_E}, {"KeyF", KEY_F},
    {"KeyG", KEY_G}, {"KeyH", KEY_H}, {"KeyI", KEY_I}, {"KeyJ", KEY_J}, {"KeyK", KEY_K}, {"KeyL", KEY_L},
    {"KeyM", KEY_M}, {"KeyN", KEY_N}, {"KeyO", KEY_O}, {"KeyP", KEY_P}, {"KeyQ", KEY_Q}, {"KeyR", KEY_R},
    {"KeyS", KEY_S}, {"KeyT", KEY_T}, {"KeyU", KEY_U}, {"KeyV", KEY_V}, {"KeyW", KEY_W}, {"KeyX", KEY_X},
    {"KeyY", KEY_Y}, {"KeyZ", KEY_Z},
    {"Digit0", KEY_0}, {"Digit1", KEY_1}, {"Digit2", KEY_2}, {"Digit3", KEY_3}, {"Digit4", KEY_4},
    {"Digit5", KEY_5}, {"Digit6", KEY_6}, {"Digit7", KEY_7}, {"Digit8", KEY_8}, {"Digit9", KEY_9},
    {"ArrowLeft", KEY_LEFT}, {"ArrowRight", KEY_RIGHT}, {"ArrowUp", KEY_UP}, {"ArrowDown", KEY_DOWN},
    {"Space", KEY_SPACE}, {"Enter", KEY_ENTER}, {"Escape", KEY_ESC}, {"Backspace", KEY_BACKSPACE},
    {"Tab", KEY_TAB}, {"Delete", KEY_DELETE}, {"Insert", KEY_INSERT}, {"Home", KEY_HOME}, {"End", KEY_END},
    {"PageUp", KEY_PAGEUP}, {"PageDown", KEY_PAGEDOWN}, {"Comma", KEY_COMMA}, {"Period", KEY_DOT},
    {"Slash", KEY_SLASH}, {"Semicolon", KEY_SEMICOLON}, {"Quote", KEY_APOSTROPHE},
    {"BracketLeft", KEY_LEFTBRACE}, {"BracketRight", KEY_RIGHTBRACE}, {"Backslash", KEY_BACKSLASH},
    {"Minus", KEY_MINUS}, {"Equal", KEY_EQUAL}, {"Backquote", KEY_GRAVE},
    {"ShiftLeft", KEY_LEFTSHIFT}, {"ShiftRight", KEY_RIGHTSHIFT}, {"ControlLeft", KEY_LEFTCTRL},
    {"ControlRight", KEY_RIGHTCTRL}, {"AltLeft", KEY_LEFTALT}, {"AltRight", KEY_RIGHTALT},
    {"MetaLeft", KEY_LEFTMETA}, {"MetaRight", KEY_RIGHTMETA},
    {"F1", KEY_F1}, {"F2", KEY_F2}, {"F3", KEY_F3}, {"F4", KEY_F4}, {"F5", KEY_F5}, {"F6", KEY_F6},
    {"F7", KEY_F7}, {"F8", KEY_F8}, {"F9", KEY_F9}, {"F10", KEY_F10}, {"F11", KEY_F11}, {"F12", KEY_F12},
    {"Numpad0", KEY_KP0}, {"Numpad1", KEY_KP1}, {"Numpad2", KEY_KP2}, {"Numpad3", KEY_KP3},
    {"Numpad4", KEY_KP4}, {"Numpad5", KEY_KP5}, {"Numpad6", KEY_KP6}, {"Numpad7", KEY_KP7},
    {"Numpad8", KEY_KP8}, {"Numpad9", KEY_KP9}, {"NumpadAdd", KEY_KPPLUS}, {"NumpadSubtract", KEY_KPMINUS},
    {"NumpadEnter", KEY_KPENTER},
};

int remote_key_code(const char *dom_code)
{
    if (!dom_code)
        return -1;
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (!strcmp(keys[i].code, dom_code))
            return keys[i].key;
    return -1;
}

/* ---- parsing ------------------------------------------------------------------- */

/* Each returns false with *reason set. */
static bool get_number(json_object *o, const char *key, double lo, double hi, double *out, remote_drop_reason *reason)
{
    json_object *v;
    if (!json_object_object_get_ex(o, key, &v) || !v) {
        *reason = REMOTE_DROP_MISSING_FIELD;
        return false;
    }
    enum json_type t = json_object_get_type(v);
    if (t != json_type_double && t != json_type_int) {
        *reason = REMOTE_DROP_WRONG_TYPE;
        return false;
    }
    double d = json_object_get_double(v);
    if (!isfinite(d) || d < lo || d > hi) {
        *reason = REMOTE_DROP_OUT_OF_RANGE;
        return false;
    }
    *out = d;
    return true;
}

static bool get_fraction(json_object *o, const char *key, double *out, remote_drop_reason *reason)
{
    if (!get_number(o, key, FRACTION_LO, FRACTION_HI, out, reason))
        return false;
    *out = *out < 0.0 ? 0.0 : *out > 1.0 ? 1.0 : *out;
    return true;
}

static bool get_bool(json_object *o, const char *key, bool *out, remote_drop_reason *reason)
{
    json_object *v;
    if (!json_object_object_get_ex(o, key, &v) || !v) {
        *reason = REMOTE_DROP_MISSING_FIELD;
        return false;
    }
    if (json_object_get_type(v) != json_type_boolean) {
        *reason = REMOTE_DROP_WRONG_TYPE;
        return false;
    }
    *out = json_object_get_boolean(v);
    return true;
}

static bool get_touch_id(json_object *v, int *out, remote_drop_reason *reason)
{
    if (!v || json_object_get_type(v) != json_type_int) {
        *reason = v ? REMOTE_DROP_WRONG_TYPE : REMOTE_DROP_MISSING_FIELD;
        return false;
    }
    int64_t id = json_object_get_int64(v);
    if (id < 0 || id >= INPUT_MAX_TOUCHES) {
        *reason = REMOTE_DROP_OUT_OF_RANGE;
        return false;
    }
    *out = (int)id;
    return true;
}

static bool parse_touch(json_object *o, remote_message *m, remote_drop_reason *reason)
{
    json_object *touches, *ended, *cancel;
    if (!json_object_object_get_ex(o, "touches", &touches) || !touches) {
        *reason = REMOTE_DROP_MISSING_FIELD;
        return false;
    }
    if (json_object_get_type(touches) != json_type_array) {
        *reason = REMOTE_DROP_WRONG_TYPE;
        return false;
    }
    size_t n = json_object_array_length(touches);
    if (n > INPUT_MAX_TOUCHES) {
        *reason = REMOTE_DROP_OUT_OF_RANGE;
        return false;
    }
    bool seen[INPUT_MAX_TOUCHES] = {false};
    for (size_t i = 0; i < n; i++) {
        json_object *t = json_object_array_get_idx(touches, i);
        if (!t || json_object_get_type(t) != json_type_object) {
            *reason = REMOTE_DROP_WRONG_TYPE;
            return false;
        }
        json_object *id;
        remote_touch_point *p = &m->touches[i];
        if (!json_object_object_get_ex(t, "id", &id)) {
            *reason = REMOTE_DROP_MISSING_FIELD;
            return false;
        }
        if (!get_touch_id(id, &p->id, reason) || !get_fraction(t, "x", &p->x, reason) ||
            !get_fraction(t, "y", &p->y, reason))
            return false;
        if (seen[p->id]) { /* one id twice */
            *reason = REMOTE_DROP_OUT_OF_RANGE;
            return false;
        }
        seen[p->id] = true;
    }
    m->touch_count = (int)n;
    m->ended_count = 0;
    if (json_object_object_get_ex(o, "ended", &ended) && ended) {
        if (json_object_get_type(ended) != json_type_array) {
            *reason = REMOTE_DROP_WRONG_TYPE;
            return false;
        }
        size_t k = json_object_array_length(ended);
        if (k > INPUT_MAX_TOUCHES) {
            *reason = REMOTE_DROP_OUT_OF_RANGE;
            return false;
        }
        for (size_t i = 0; i < k; i++)
            if (!get_touch_id(json_object_array_get_idx(ended, i), &m->ended[i], reason))
                return false;
        m->ended_count = (int)k;
    }
    m->cancel = false;
    if (json_object_object_get_ex(o, "cancel", &cancel) && cancel) {
        if (json_object_get_type(cancel) != json_type_boolean) {
            *reason = REMOTE_DROP_WRONG_TYPE;
            return false;
        }
        m->cancel = json_object_get_boolean(cancel);
    }
    return true;
}

static bool parse_object(json_object *o, remote_message *m, remote_drop_reason *reason)
{
    json_object *tv;
    if (!json_object_object_get_ex(o, "t", &tv) || !tv || json_object_get_type(tv) != json_type_string) {
        *reason = REMOTE_DROP_UNKNOWN_TYPE;
        return false;
    }
    const char *t = json_object_get_string(tv);
    double d;
    if (!strcmp(t, "ack")) {
        m->kind = REMOTE_MSG_ACK;
        if (!get_number(o, "frame", 0.0, 9007199254740992.0, &d, reason)) /* 2^53: exact in a double */
            return false;
        m->frame = (uint64_t)d;
        return true;
    }
    if (!strcmp(t, "move") || !strcmp(t, "down") || !strcmp(t, "up") || !strcmp(t, "wheel")) {
        m->kind = t[0] == 'm' ? REMOTE_MSG_MOVE : t[0] == 'd' ? REMOTE_MSG_DOWN : t[0] == 'u' ? REMOTE_MSG_UP
                                                                                          : REMOTE_MSG_WHEEL;
        if (!get_fraction(o, "x", &m->x, reason) || !get_fraction(o, "y", &m->y, reason))
            return false;
        if (m->kind == REMOTE_MSG_DOWN || m->kind == REMOTE_MSG_UP) {
            if (!get_number(o, "button", 0.0, 2.0, &d, reason))
                return false;
            if (d != floor(d)) {
                *reason = REMOTE_DROP_OUT_OF_RANGE;
                return false;
            }
            m->button = (int)d;
        }
        if (m->kind == REMOTE_MSG_WHEEL && !get_number(o, "dy", -WHEEL_CLICKS_MAX, WHEEL_CLICKS_MAX, &m->dy, reason))
            return false;
        return true;
    }
    if (!strcmp(t, "leave")) {
        m->kind = REMOTE_MSG_LEAVE;
        return true;
    }
    if (!strcmp(t, "touch")) {
        m->kind = REMOTE_MSG_TOUCH;
        return parse_touch(o, m, reason);
    }
    if (!strcmp(t, "key")) {
        m->kind = REMOTE_MSG_KEY;
        json_object *code;
        if (!json_object_object_get_ex(o, "code", &code) || !code) {
            *reason = REMOTE_DROP_MISSING_FIELD;
            return false;
        }
        if (json_object_get_type(code) != json_type_string) {
            *reason = REMOTE_DROP_WRONG_TYPE;
            return false;
        }
        if (!get_bool(o, "down", &m->down, reason))
            return false;
        m->key_code = remote_key_code(json_object_get_string(code));
        if (m->key_code < 0) {
            *reason = REMOTE_DROP_UNKNOWN_KEY;
            return false;
        }
        return true;
    }
    if (!strcmp(t, "view")) {
        m->kind = REMOTE_MSG_VIEW;
        return get_bool(o, "private", &m->private_view, reason);
    }
    *reason = REMOTE_DROP_UNKNOWN_TYPE;
    return false;
}

bool remote_message_parse(const char *text, size_t bytes, remote_message *out, remote_drop_reason *reason)
{
    memset(out, 0, sizeof *out);
    if (bytes > REMOTE_MESSAGE_MAX_BYTES) {
        *reason = REMOTE_DROP_TOO_LONG;
        return false;
    }
    struct json_tokener *tok = json_tokener_new_ex(JSON_DEPTH_MAX);
    if (!tok) {
        *reason = REMOTE_DROP_NOT_JSON;
        return false;
    }
    json_tokener_set_flags(tok, JSON_TOKENER_STRICT | JSON_TOKENER_VALIDATE_UTF8);
    json_object *root = json_tokener_parse_ex(tok, text, (int)bytes);
    enum json_tokener_error status = json_tokener_get_error(tok);
    size_t end = json_tokener_get_parse_end(tok);
    json_tokener_free(tok);
    bool ok = false;
    if (!root || status != json_tokener_success) {
        *reason = REMOTE_DROP_NOT_JSON;
    } else if (end != bytes) { /* something after the value */
        *reason = REMOTE_DROP_NOT_JSON;
    } else if (json_object_get_type(root) != json_type_object) {
        *reason = REMOTE_DROP_NOT_OBJECT;
    } else {
        ok = parse_object(root, out, reason);
    }
    json_object_put(root);
    return ok;
}

/* ---- rate ---------------------------------------------------------------------- */

void remote_rate_init(remote_rate *r, uint64_t now_us)
{
    r->tokens = REMOTE_RATE_BURST;
    r->last_us = now_us;
}

bool remote_rate_take(remote_rate *r, uint64_t now_us)
{
    if (now_us > r->last_us) {
        r->tokens += (double)(now_us - r->last_us) * 1e-6 * REMOTE_RATE_PER_S;
        if (r->tokens > REMOTE_RATE_BURST)
            r->tokens = REMOTE_RATE_BURST;
        r->last_us = now_us;
    }
    if (r->tokens < 1.0)
        return false;
    r->tokens -= 1.0;
    return true;
}

/* ---- events -------------------------------------------------------------------- */

void remote_viewer_input_init(remote_viewer_input *v, int slot)
{
    memset(v, 0, sizeof *v);
    v->slot = slot;
    v->device = REMOTE_DEVICE_BASE + slot;
}

typedef struct run {
    input_event *out;
    int n;
    const remote_viewer_input *v;
    uint64_t time_us;
} run;

static input_event *add(run *r, input_event_kind kind)
{
    input_event *e = &r->out[r->n++];
    memset(e, 0, sizeof *e);
    e->kind = kind;
    e->time_us = r->time_us;
    e->device = r->v->device;
    return e;
}

static void add_at(run *r, input_event_kind kind, const camera_window *area, double fx, double fy)
{
    input_event *e = add(r, kind);
    input_area_point(area, fx, fy, &e->x, &e->y);
}

static void add_pointer(run *r, remote_viewer_input *v, bool shown, const camera_window *area, double fx, double fy)
{
    input_event *e = add(r, INPUT_VIEWER_POINTER);
    e->slot = v->slot;
    e->pressed = shown;
    if (shown)
        input_area_point(area, fx, fy, &e->x, &e->y);
    v->pointer_shown = shown;
}

static const int button_codes[3] = {BTN_LEFT, BTN_MIDDLE, BTN_RIGHT};

int remote_message_events(remote_viewer_input *v, const remote_message *m, const camera_window *area,
                          uint64_t time_us, input_event *out)
{
    run r = {out, 0, v, time_us};
    switch (m->kind) {
    case REMOTE_MSG_ACK:
    case REMOTE_MSG_VIEW:
        return 0;
    case REMOTE_MSG_MOVE:
        if (v->buttons_held)
            add_at(&r, INPUT_POINTER_ABS, area, m->x, m->y);
        add_pointer(&r, v, true, area, m->x, m->y);
        add(&r, INPUT_FRAME);
        break;
    case REMOTE_MSG_DOWN:
    case REMOTE_MSG_UP: {
        bool down = m->kind == REMOTE_MSG_DOWN;
        unsigned bit = 1u << m->button;
        if (down == ((v->buttons_held & bit) != 0))
            return 0; /* already down / not down */
        add_at(&r, INPUT_POINTER_ABS, area, m->x, m->y);
        if (down)
            add_pointer(&r, v, true, area, m->x, m->y);
        input_event *e = add(&r, INPUT_BUTTON);
        e->code = button_codes[m->button];
        e->pressed = down;
        v->buttons_held = down ? v->buttons_held | bit : v->buttons_held & ~bit;
        add(&r, INPUT_FRAME);
        break;
    }
    case REMOTE_MSG_WHEEL:
        add_at(&r, INPUT_POINTER_ABS, area, m->x, m->y);
        add(&r, INPUT_SCROLL)->dy = m->dy;
        add(&r, INPUT_FRAME);
        break;
    case REMOTE_MSG_LEAVE:
        if (!v->pointer_shown)
            return 0;
        add_pointer(&r, v, false, area, 0.0, 0.0);
        add(&r, INPUT_FRAME);
        break;
    case REMOTE_MSG_TOUCH: {
        if (m->cancel) {
            add(&r, INPUT_TOUCH_CANCEL);
            add(&r, INPUT_TOUCH_FRAME);
            memset(v->touch_down, 0, sizeof v->touch_down);
        } else {
            for (int i = 0; i < m->ended_count; i++) {
                int id = m->ended[i];
                if (!v->touch_down[id])
                    continue;
                add(&r, INPUT_TOUCH_UP)->slot = id;
                v->touch_down[id] = false;
            }
            for (int i = 0; i < m->touch_count; i++) {
                const remote_touch_point *p = &m->touches[i];
                add_at(&r, v->touch_down[p->id] ? INPUT_TOUCH_MOTION : INPUT_TOUCH_DOWN, area, p->x, p->y);
                r.out[r.n - 1].slot = p->id;
                v->touch_down[p->id] = true;
            }
            add(&r, INPUT_TOUCH_FRAME);
        }
        /* the viewer's pointer at its lowest touch still down, else hidden */
        const remote_touch_point *lowest = NULL;
        for (int i = 0; !m->cancel && i < m->touch_count; i++)
            if (!lowest || m->touches[i].id < lowest->id)
                lowest = &m->touches[i];
        if (lowest || v->pointer_shown) {
            add_pointer(&r, v, lowest != NULL, area, lowest ? lowest->x : 0.0, lowest ? lowest->y : 0.0);
            add(&r, INPUT_FRAME);
        }
        break;
    }
    case REMOTE_MSG_KEY: {
        input_event *e = add(&r, INPUT_KEY);
        e->code = m->key_code;
        e->pressed = m->down;
        add(&r, INPUT_FRAME);
        break;
    }
    }
    return r.n;
}

int remote_viewer_input_release(remote_viewer_input *v, uint64_t time_us, input_event *out)
{
    run r = {out, 0, v, time_us};
    if (v->pointer_shown) {
        add_pointer(&r, v, false, &CAMERA_WINDOW_FULL, 0.0, 0.0);
        add(&r, INPUT_FRAME);
    }
    add(&r, INPUT_DEVICE_REMOVED);
    v->buttons_held = 0;
    memset(v->touch_down, 0, sizeof v->touch_down);
    return r.n;
}

/* ---- frame header -------------------------------------------------------------- */

static void put_le(uint8_t *p, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

void remote_frame_header(uint8_t out[REMOTE_FRAME_HEADER_BYTES], uint64_t frame, uint64_t camera_serial,
                         int width_px, int height_px, uint32_t jpeg_bytes)
{
    put_le(out + 0, REMOTE_FRAME_MAGIC, 4);
    put_le(out + 4, REMOTE_FRAME_HEADER_BYTES, 4);
    put_le(out + 8, frame, 8);
    put_le(out + 16, camera_serial, 8);
    put_le(out + 24, (uint64_t)width_px, 2);
    put_le(out + 26, (uint64_t)height_px, 2);
    put_le(out + 28, jpeg_bytes, 4);
}
