/* bindings.c (input) - the shipped bindings and reading bindings files: evdev
 * names through libevdev, actions and gestures by name, the kind rules (which
 * action may be bound where) and the quit chord. The format is documented in
 * bindings.h and docs/bindings-format.md. */
#include "bindings.h"

#include <json.h>
#include <libevdev/libevdev.h>
#include <linux/input-event-codes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/json_read.h"

/* A bindings file is a page of text; a larger file is most likely a mistake. */
#define BINDINGS_FILE_MAX_BYTES (1u << 20)
/* Bytes of a value the file gave that a message quotes (longer ones are cut). */
#define SHOWN_VALUE_BYTES 64

_Static_assert(INPUT_CODE_COUNT == KEY_CNT, "INPUT_CODE_COUNT must be the evdev key code space");
_Static_assert(INPUT_ACTION_COUNT <= 256, "an action must fit code_action's unsigned char");

static const char format_name[] = "tessera-bindings";
static const int format_version = 1;

/* NULL-terminated so that they also serve as lists for jr_check_fields and messages. */
static const char *const action_names[INPUT_ACTION_COUNT + 1] = {
    [INPUT_ACTION_NONE] = "none",
    [INPUT_ACTION_ORBIT] = "orbit",
    [INPUT_ACTION_PAN] = "pan",
    [INPUT_ACTION_DOLLY] = "dolly",
    [INPUT_ACTION_FLY_FORWARD] = "fly-forward",
    [INPUT_ACTION_FLY_BACK] = "fly-back",
    [INPUT_ACTION_FLY_LEFT] = "fly-left",
    [INPUT_ACTION_FLY_RIGHT] = "fly-right",
    [INPUT_ACTION_FLY_UP] = "fly-up",
    [INPUT_ACTION_FLY_DOWN] = "fly-down",
    [INPUT_ACTION_SPEED_UP] = "speed-up",
    [INPUT_ACTION_SPEED_DOWN] = "speed-down",
    [INPUT_ACTION_HOME] = "home",
    [INPUT_ACTION_PICK] = "pick",
    [INPUT_ACTION_HIDE_OBJECT] = "hide-object",
    [INPUT_ACTION_SHOW_ALL] = "show-all",
    [INPUT_ACTION_FLY_TO] = "fly-to",
    [INPUT_ACTION_GOVERNOR_STATUS] = "governor-status",
    [INPUT_ACTION_ISOLATE] = "isolate",
    [INPUT_ACTION_SELECT_PARENT] = "select-parent",
    [INPUT_ACTION_HIGHLIGHT] = "highlight",
    [INPUT_ACTION_SHOW] = "show",
    [INPUT_ACTION_OPACITY_DOWN] = "opacity-down",
    [INPUT_ACTION_OPACITY_UP] = "opacity-up",
    [INPUT_ACTION_PART_OPACITY_DOWN] = "part-opacity-down",
    [INPUT_ACTION_PART_OPACITY_UP] = "part-opacity-up",
    [INPUT_ACTION_PLANE_PLACE] = "plane-place",
    [INPUT_ACTION_PLANE_NEXT] = "plane-next",
    [INPUT_ACTION_PLANE_FLIP] = "plane-flip",
    [INPUT_ACTION_PLANE_REMOVE] = "plane-remove",
    [INPUT_ACTION_PLANE_REMOVE_ALL] = "plane-remove-all",
    [INPUT_ACTION_PLANE_PUSH] = "plane-push",
    [INPUT_ACTION_AMBIENT_OCCLUSION] = "ambient-occlusion",
    [INPUT_ACTION_CROP_DOWN] = "crop-down",
    [INPUT_ACTION_CROP_UP] = "crop-up",
    [INPUT_ACTION_CROP_OFF] = "crop-off",
    [INPUT_ACTION_TIME_PLAY] = "time-play",
    [INPUT_ACTION_TIME_BACK] = "time-back",
    [INPUT_ACTION_TIME_FORWARD] = "time-forward",
    [INPUT_ACTION_TIME_SLOWER] = "time-slower",
    [INPUT_ACTION_TIME_FASTER] = "time-faster",
    [INPUT_ACTION_VALUE_DOWN] = "value-down",
    [INPUT_ACTION_VALUE_UP] = "value-up",
    [INPUT_ACTION_COLORMAP_NEXT] = "colormap-next",
    [INPUT_ACTION_VALUE_DRAG] = "value-drag",
    [INPUT_ACTION_COUNT] = NULL,
};

/* show-all's name before parts came (bindings files may still say it). */
static const char show_all_old_name[] = "unhide-all";

static const char *const gesture_names[INPUT_GESTURE_COUNT + 1] = {
    [INPUT_GESTURE_CLICK] = "click",
    [INPUT_GESTURE_WHEEL] = "wheel",
    [INPUT_GESTURE_TAP] = "tap",
    [INPUT_GESTURE_DOUBLE_TAP] = "double-tap",
    [INPUT_GESTURE_ONE_FINGER_DRAG] = "one-finger-drag",
    [INPUT_GESTURE_TWO_FINGER_DRAG] = "two-finger-drag",
    [INPUT_GESTURE_TWO_FINGER_PINCH] = "two-finger-pinch",
    [INPUT_GESTURE_TOUCHPAD_PINCH] = "touchpad-pinch",
    [INPUT_GESTURE_TOUCHPAD_SWIPE] = "touchpad-swipe",
    [INPUT_GESTURE_LONG_PRESS] = "long-press",
    [INPUT_GESTURE_TWO_FINGER_TAP] = "two-finger-tap",
    [INPUT_GESTURE_THREE_FINGER_TAP] = "three-finger-tap",
    [INPUT_GESTURE_THREE_FINGER_DRAG] = "three-finger-drag",
    [INPUT_GESTURE_COUNT] = NULL,
};

/* ---- names and kinds -------------------------------------------------------- */

const char *input_action_name(input_action a)
{
    return (unsigned)a < INPUT_ACTION_COUNT ? action_names[a] : NULL;
}

const char *input_gesture_name(input_gesture g)
{
    return (unsigned)g < INPUT_GESTURE_COUNT ? gesture_names[g] : NULL;
}

bool input_action_is_drag(input_action a)
{
    return a == INPUT_ACTION_ORBIT || a == INPUT_ACTION_PAN || a == INPUT_ACTION_DOLLY || a == INPUT_ACTION_PLANE_PUSH ||
           a == INPUT_ACTION_VALUE_DRAG;
}

/* Flight acts for as long as its key or button is held. */
static bool action_is_held(input_action a)
{
    return a >= INPUT_ACTION_FLY_FORWARD && a <= INPUT_ACTION_FLY_DOWN;
}

/* Gestures that carry motion (drag actions only); the others are discrete
 * (command actions only). */
static bool gesture_moves(input_gesture g)
{
    return g != INPUT_GESTURE_CLICK && g != INPUT_GESTURE_TAP && g != INPUT_GESTURE_DOUBLE_TAP &&
           g != INPUT_GESTURE_LONG_PRESS && g != INPUT_GESTURE_TWO_FINGER_TAP && g != INPUT_GESTURE_THREE_FINGER_TAP;
}

/* A code is a (pointer, joystick, tablet, ...) button when its evdev name
 * starts with BTN_, else a keyboard key. No code has names of both kinds. */
static bool code_is_button(int code)
{
    const char *name = libevdev_event_code_get_name(EV_KEY, (unsigned)code);
    return name && strncmp(name, "BTN_", 4) == 0;
}

/* ---- the shipped bindings ---------------------------------------------------- */

typedef struct code_binding {
    unsigned short code;
    unsigned char action;
} code_binding;

/* In the order of configs/bindings.json. */
static const code_binding default_codes[] = {
    {KEY_W, INPUT_ACTION_FLY_FORWARD},    {KEY_UP, INPUT_ACTION_FLY_FORWARD},
    {KEY_S, INPUT_ACTION_FLY_BACK},       {KEY_DOWN, INPUT_ACTION_FLY_BACK},
    {KEY_A, INPUT_ACTION_FLY_LEFT},       {KEY_LEFT, INPUT_ACTION_FLY_LEFT},
    {KEY_D, INPUT_ACTION_FLY_RIGHT},      {KEY_RIGHT, INPUT_ACTION_FLY_RIGHT},
    {KEY_PAGEUP, INPUT_ACTION_FLY_UP},    {KEY_PAGEDOWN, INPUT_ACTION_FLY_DOWN},
    {KEY_EQUAL, INPUT_ACTION_SPEED_UP},   {KEY_KPPLUS, INPUT_ACTION_SPEED_UP},
    {KEY_MINUS, INPUT_ACTION_SPEED_DOWN}, {KEY_KPMINUS, INPUT_ACTION_SPEED_DOWN},
    {KEY_HOME, INPUT_ACTION_HOME},        {KEY_H, INPUT_ACTION_HIDE_OBJECT},
    {KEY_U, INPUT_ACTION_SHOW_ALL},       {KEY_P, INPUT_ACTION_PICK},
    {KEY_F, INPUT_ACTION_FLY_TO},
    {KEY_I, INPUT_ACTION_ISOLATE},        {KEY_BACKSPACE, INPUT_ACTION_SELECT_PARENT},
    {KEY_L, INPUT_ACTION_HIGHLIGHT},      {KEY_Z, INPUT_ACTION_SHOW},
    {KEY_G, INPUT_ACTION_GOVERNOR_STATUS},
    {KEY_LEFTBRACE, INPUT_ACTION_OPACITY_DOWN}, {KEY_RIGHTBRACE, INPUT_ACTION_OPACITY_UP},
    {KEY_SEMICOLON, INPUT_ACTION_PART_OPACITY_DOWN}, {KEY_APOSTROPHE, INPUT_ACTION_PART_OPACITY_UP},
    {KEY_C, INPUT_ACTION_PLANE_PLACE},    {KEY_N, INPUT_ACTION_PLANE_NEXT},
    {KEY_X, INPUT_ACTION_PLANE_FLIP},     {KEY_DELETE, INPUT_ACTION_PLANE_REMOVE},
    {KEY_END, INPUT_ACTION_PLANE_REMOVE_ALL}, {KEY_O, INPUT_ACTION_AMBIENT_OCCLUSION},
    {KEY_COMMA, INPUT_ACTION_CROP_DOWN},  {KEY_DOT, INPUT_ACTION_CROP_UP},
    {KEY_SLASH, INPUT_ACTION_CROP_OFF},
    {KEY_SPACE, INPUT_ACTION_TIME_PLAY},  {KEY_9, INPUT_ACTION_TIME_BACK},
    {KEY_0, INPUT_ACTION_TIME_FORWARD},   {KEY_7, INPUT_ACTION_TIME_SLOWER},
    {KEY_8, INPUT_ACTION_TIME_FASTER},
    {KEY_T, INPUT_ACTION_VALUE_DOWN},     {KEY_Y, INPUT_ACTION_VALUE_UP},
    {KEY_M, INPUT_ACTION_COLORMAP_NEXT},
    {BTN_LEFT, INPUT_ACTION_ORBIT},
    {BTN_RIGHT, INPUT_ACTION_PAN},        {BTN_MIDDLE, INPUT_ACTION_PLANE_PUSH},
    {BTN_SIDE, INPUT_ACTION_VALUE_DRAG},
};

static const unsigned char default_gestures[INPUT_GESTURE_COUNT] = {
    [INPUT_GESTURE_CLICK] = INPUT_ACTION_PICK,
    [INPUT_GESTURE_WHEEL] = INPUT_ACTION_DOLLY,
    [INPUT_GESTURE_TAP] = INPUT_ACTION_PICK,
    [INPUT_GESTURE_DOUBLE_TAP] = INPUT_ACTION_FLY_TO,
    [INPUT_GESTURE_ONE_FINGER_DRAG] = INPUT_ACTION_ORBIT,
    [INPUT_GESTURE_TWO_FINGER_DRAG] = INPUT_ACTION_PAN,
    [INPUT_GESTURE_TWO_FINGER_PINCH] = INPUT_ACTION_DOLLY,
    [INPUT_GESTURE_TOUCHPAD_PINCH] = INPUT_ACTION_DOLLY,
    [INPUT_GESTURE_TOUCHPAD_SWIPE] = INPUT_ACTION_PAN,
    [INPUT_GESTURE_LONG_PRESS] = INPUT_ACTION_ISOLATE,
    [INPUT_GESTURE_TWO_FINGER_TAP] = INPUT_ACTION_SHOW_ALL,
    [INPUT_GESTURE_THREE_FINGER_TAP] = INPUT_ACTION_PLANE_PLACE,
    [INPUT_GESTURE_THREE_FINGER_DRAG] = INPUT_ACTION_VALUE_DRAG,
};

static const int default_chord[] = {KEY_LEFTCTRL, KEY_LEFTALT, KEY_Q};

_Static_assert(sizeof default_chord / sizeof default_chord[0] <= INPUT_CHORD_MAX, "default chord too long");

void input_bindings_default(input_bindings *out)
{
    /* memset first: padding included, so that bindings compare with memcmp */
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < sizeof default_codes / sizeof default_codes[0]; i++)
        out->code_action[default_codes[i].code] = default_codes[i].action;
    memcpy(out->gesture_action, default_gestures, sizeof out->gesture_action);
    out->quit_chord_len = (int)(sizeof default_chord / sizeof default_chord[0]);
    for (int i = 0; i < out->quit_chord_len; i++)
        out->quit_chord[i] = default_chord[i];
}

/* ---- reading ------------------------------------------------------------------ */

/* "none, orbit, pan, ..." */
static const char *action_list(char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; action_names[i] && used < size; i++)
        used += (size_t)snprintf(buf + used, size - used, "%s%s", i ? ", " : "", action_names[i]);
    return buf;
}

/* "speed-up, speed-down, ...": the actions of one kind, for messages. */
static const char *command_list(char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int a = INPUT_ACTION_NONE + 1; a < INPUT_ACTION_COUNT && used < size; a++)
        if (!input_action_is_drag((input_action)a) && !action_is_held((input_action)a))
            used += (size_t)snprintf(buf + used, size - used, "%s%s", used ? ", " : "", action_names[a]);
    return buf;
}

/* The current field as an action name. */
static bool read_action(jr_ctx *c, json_object *v, input_action *out)
{
    if (!json_object_is_type(v, json_type_string))
        return jr_field_fail(c, "expected an action name (a string), got %s", jr_kind(v));
    const char *s = json_object_get_string(v);
    size_t len = (size_t)json_object_get_string_len(v);
    for (int a = 0; a < INPUT_ACTION_COUNT; a++)
        if (strlen(action_names[a]) == len && memcmp(action_names[a], s, len) == 0) {
            *out = (input_action)a;
            return true;
        }
    if (len == strlen(show_all_old_name) && memcmp(show_all_old_name, s, len) == 0) {
        *out = INPUT_ACTION_SHOW_ALL;
        return true;
    }
    char list[512];
    return jr_field_fail(c, "unknown action '%.*s' (expected one of: %s)", SHOWN_VALUE_BYTES, s,
                         action_list(list, sizeof list));
}

/* The evdev code of KEY_* / BTN_* name `name`, for the current field. */
static bool read_code(jr_ctx *c, const char *name, int *code)
{
    int k = libevdev_event_code_from_name(EV_KEY, name);
    if (k < 0)
        return jr_field_fail(c, "unknown evdev key or button name (names as in linux/input-event-codes.h, "
                                "e.g. KEY_W, BTN_LEFT)");
    if (k == KEY_RESERVED || k == KEY_MAX || k >= INPUT_CODE_COUNT)
        return jr_field_fail(c, "'%.*s' (code 0x%x) is a placeholder of the code space, not a key or button",
                             SHOWN_VALUE_BYTES, name, (unsigned)k);
    *code = k;
    return true;
}

/* `named[code]` is the name that first gave `code` in this section, or NULL. */
static bool check_code_unique(jr_ctx *c, const char **named, int code, const char *name)
{
    if (!named[code]) {
        named[code] = name;
        return true;
    }
    return jr_field_fail(c, "same code as '%.*s' (0x%x); a key or button is bound once", SHOWN_VALUE_BYTES,
                         named[code], (unsigned)code);
}

/* Whether action `a` may be bound to code `code` (the current field). */
static bool check_code_action(jr_ctx *c, int code, input_action a)
{
    if (!input_action_is_drag(a) || code_is_button(code))
        return true;
    return jr_field_fail(c, "'%s' is a drag action, which follows motion: bind it to a pointer button (BTN_*) "
                            "or a moving gesture, not to a keyboard key", action_names[a]);
}

/* Whether action `a` may be bound to gesture `g` (the current field). */
static bool check_gesture_action(jr_ctx *c, input_gesture g, input_action a)
{
    char list[512];
    if (a == INPUT_ACTION_NONE)
        return true;
    if (gesture_moves(g)) {
        if (input_action_is_drag(a))
            return true;
        return jr_field_fail(c, "'%s' is a command action, but %s is a moving gesture, which takes only "
                                "drag actions (orbit, pan, dolly, plane-push, value-drag) or none", action_names[a],
                             gesture_names[g]);
    }
    if (input_action_is_drag(a))
        return jr_field_fail(c, "'%s' is a drag action, which follows motion, but %s is a discrete gesture "
                                "without motion (it takes %s or none)", action_names[a], gesture_names[g],
                             command_list(list, sizeof list));
    if (action_is_held(a))
        return jr_field_fail(c, "'%s' acts while held, and a %s cannot be held: bind flight to a key or button",
                             action_names[a], gesture_names[g]);
    return true;
}

static bool read_keys(jr_ctx *c, json_object *root, input_bindings *b)
{
    json_object *keys;
    if (!jr_get_member(root, "keys", &keys))
        return true; /* the shipped keys stay */
    size_t outer = jr_field_key(c, "keys");
    bool ok = jr_expect_object(c, keys);
    if (ok) {
        const char *named[INPUT_CODE_COUNT] = {0};
        memset(b->code_action, 0, sizeof b->code_action);
        struct json_object_iterator it = json_object_iter_begin(keys), end = json_object_iter_end(keys);
        for (; ok && !json_object_iter_equal(&it, &end); json_object_iter_next(&it)) {
            const char *name = json_object_iter_peek_name(&it);
            size_t saved = jr_field_key(c, name);
            int code = 0;
            input_action a = INPUT_ACTION_NONE;
            ok = read_code(c, name, &code) && check_code_unique(c, named, code, name) &&
                 read_action(c, json_object_iter_peek_value(&it), &a) && check_code_action(c, code, a);
            if (ok)
                b->code_action[code] = (unsigned char)a;
            jr_field_leave(c, saved);
        }
    }
    jr_field_leave(c, outer);
    return ok;
}

static bool read_gestures(jr_ctx *c, json_object *root, input_bindings *b)
{
    json_object *gestures;
    if (!jr_get_member(root, "gestures", &gestures))
        return true; /* the shipped gestures stay */
    size_t outer = jr_field_key(c, "gestures");
    bool ok = jr_expect_object(c, gestures) && jr_check_fields(c, gestures, gesture_names);
    if (ok)
        memset(b->gesture_action, 0, sizeof b->gesture_action);
    for (int g = 0; ok && g < INPUT_GESTURE_COUNT; g++) {
        json_object *v;
        if (!jr_get_member(gestures, gesture_names[g], &v))
            continue;
        size_t saved = jr_field_key(c, gesture_names[g]);
        input_action a = INPUT_ACTION_NONE;
        ok = read_action(c, v, &a) && check_gesture_action(c, (input_gesture)g, a);
        if (ok)
            b->gesture_action[g] = (unsigned char)a;
        jr_field_leave(c, saved);
    }
    jr_field_leave(c, outer);
    return ok;
}

/* One key of the chord (the current field is quit_chord[i]); `given` holds
 * the names of elements 0..i-1. */
static bool read_chord_key(jr_ctx *c, json_object *v, const input_bindings *b, const char *const *given,
                           int *code)
{
    if (!json_object_is_type(v, json_type_string))
        return jr_field_fail(c, "expected a key name (a string), got %s", jr_kind(v));
    const char *name = json_object_get_string(v);
    if (!read_code(c, name, code))
        return false;
    if (code_is_button(*code))
        return jr_field_fail(c, "'%.*s' is a button; the quit chord takes keyboard keys only", SHOWN_VALUE_BYTES,
                             name);
    for (int j = 0; j < b->quit_chord_len; j++)
        if (b->quit_chord[j] == *code)
            return jr_field_fail(c, "same code as '%.*s' (quit_chord[%d]); a chord lists each key once",
                                 SHOWN_VALUE_BYTES, given[j], j);
    return true;
}

static bool read_chord(jr_ctx *c, json_object *root, input_bindings *b)
{
    json_object *chord;
    if (!jr_get_member(root, "quit_chord", &chord))
        return true; /* the shipped chord stays */
    size_t outer = jr_field_key(c, "quit_chord");
    bool ok = json_object_is_type(chord, json_type_array) ||
              jr_field_fail(c, "expected an array of 1 to %d key names, or [] for no quit chord, got %s",
                            INPUT_CHORD_MAX, jr_kind(chord));
    size_t n = ok ? json_object_array_length(chord) : 0;
    if (ok && n > INPUT_CHORD_MAX)
        ok = jr_field_fail(c, "at most %d keys, got %zu", INPUT_CHORD_MAX, n);
    if (ok) {
        memset(b->quit_chord, 0, sizeof b->quit_chord);
        b->quit_chord_len = 0;
    }
    const char *given[INPUT_CHORD_MAX] = {0};
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = jr_field_index(c, i);
        json_object *v = json_object_array_get_idx(chord, i);
        int code = 0;
        ok = read_chord_key(c, v, b, given, &code);
        if (ok) {
            given[b->quit_chord_len] = json_object_get_string(v);
            b->quit_chord[b->quit_chord_len++] = code;
        }
        jr_field_leave(c, saved);
    }
    jr_field_leave(c, outer);
    return ok;
}

static bool read_bindings(jr_ctx *c, json_object *root, input_bindings *b)
{
    static const char *const fields[] = {"format", "version", "keys", "gestures", "quit_chord", NULL};
    if (!json_object_is_type(root, json_type_object))
        return tess_error_set(c->err, "%s: expected a JSON object at the top level, got %s", c->path,
                              jr_kind(root));
    return jr_check_format(c, root, format_name, "a bindings file") && jr_check_fields(c, root, fields) &&
           jr_check_version(c, root, format_version) && read_keys(c, root, b) && read_gestures(c, root, b) &&
           read_chord(c, root, b);
}

bool input_bindings_parse(const char *name, const char *text, size_t len, input_bindings *out, tess_error *err)
{
    input_bindings b;
    input_bindings_default(&b); /* a section the file leaves out keeps these */
    json_object *root = NULL;
    jr_ctx ctx = {.path = name, .err = err};
    bool ok = jr_parse(name, text, len, &root, err) && read_bindings(&ctx, root, &b);
    json_object_put(root);
    if (ok)
        memcpy(out, &b, sizeof b); /* bytes, padding included (see input_bindings_default) */
    return ok;
}

bool input_bindings_load(const char *file, input_bindings *out, tess_error *err)
{
    size_t len = 0;
    char *text = jr_read_file(file, BINDINGS_FILE_MAX_BYTES, "a bindings file", &len, err);
    if (!text)
        return false;
    bool ok = input_bindings_parse(file, text, len, out, err);
    free(text);
    return ok;
}
