/* test_bindings.c - bindings files (input/bindings.h): the shipped
 * ../configs/bindings.json (the suite runs in tests/) against
 * input_bindings_default, action and gesture names, the section rules
 * (a section given replaces the defaults, one left out keeps them), the kind
 * rules (drag, flight, command actions on keys, buttons and gestures), the
 * quit chord, and every kind of bad input with the field its message names. */
#include <criterion/criterion.h>

#include <linux/input-event-codes.h>
#include <stdio.h>
#include <string.h>

#include "input/bindings.h"
#include "support.h"

#define SHIPPED_BINDINGS "../configs/bindings.json"
#define HEAD "\"format\": \"tessera-bindings\", \"version\": 1"

/* ---- helpers ---------------------------------------------------------------- */

static bool parse(const char *text, input_bindings *b, tess_error *err)
{
    return input_bindings_parse("bindings.json", text, strlen(text), b, err);
}

static input_bindings parse_ok(const char *text)
{
    input_bindings b;
    tess_error err = {{0}};
    cr_assert(parse(text, &b, &err), "%s\n  for: %s", err.msg, text);
    return b;
}

/* Parsing must fail with a message that names `field` (as "field 'FIELD'",
 * or any prefix such as "bindings.json:3:" when field starts with the file)
 * and contains `problem`; *out must be left as it was. */
static void expect_failure(const char *text, const char *field, const char *problem)
{
    input_bindings b, before;
    memset(&b, 0xa5, sizeof b);
    memcpy(&before, &b, sizeof b);
    tess_error err = {{0}};
    cr_assert_not(parse(text, &b, &err), "accepted: %s", text);
    char want_field[256];
    if (strncmp(field, "bindings.json", 13) == 0)
        snprintf(want_field, sizeof want_field, "%s", field);
    else
        snprintf(want_field, sizeof want_field, "bindings.json: field '%s': ", field);
    cr_expect(strncmp(err.msg, want_field, strlen(want_field)) == 0, "for %s\n  got:  %s\n  want field: %s", text,
              err.msg, want_field);
    cr_expect(strstr(err.msg, problem), "for %s\n  got:  %s\n  want: %s", text, err.msg, problem);
    cr_expect_null(strchr(err.msg, '\n'), "one line: %s", err.msg);
    cr_expect(memcmp(&b, &before, sizeof b) == 0, "a failed parse must leave *out untouched");
}

/* A file of HEAD plus `members` (", ..." or ""). */
static void expect_members_failure(const char *members, const char *field, const char *problem)
{
    char text[2048];
    snprintf(text, sizeof text, "{" HEAD "%s}", members);
    expect_failure(text, field, problem);
}

static int bound_codes(const input_bindings *b)
{
    int n = 0;
    for (int code = 0; code < INPUT_CODE_COUNT; code++)
        n += b->code_action[code] != INPUT_ACTION_NONE;
    return n;
}

/* Field by field (for a readable message), then byte for byte. */
static void expect_same_bindings(const input_bindings *got, const input_bindings *want)
{
    for (int code = 0; code < INPUT_CODE_COUNT; code++)
        cr_expect_eq(got->code_action[code], want->code_action[code], "code 0x%x: %s, want %s", code,
                     input_action_name(got->code_action[code]), input_action_name(want->code_action[code]));
    for (int g = 0; g < INPUT_GESTURE_COUNT; g++)
        cr_expect_eq(got->gesture_action[g], want->gesture_action[g], "gesture %s: %s, want %s",
                     input_gesture_name(g), input_action_name(got->gesture_action[g]),
                     input_action_name(want->gesture_action[g]));
    cr_expect_eq(got->quit_chord_len, want->quit_chord_len, "quit chord length");
    for (int i = 0; i < INPUT_CHORD_MAX; i++)
        cr_expect_eq(got->quit_chord[i], want->quit_chord[i], "quit_chord[%d]", i);
    cr_expect(memcmp(got, want, sizeof *got) == 0, "not equal byte for byte");
}

/* ---- the shipped bindings ---------------------------------------------------------- */

Test(bindings, shipped_file_equals_the_defaults)
{
    input_bindings file, def;
    tess_error err = {{0}};
    memset(&file, 0x5a, sizeof file); /* every byte must come from the loader */
    cr_assert(input_bindings_load(SHIPPED_BINDINGS, &file, &err), "%s", err.msg);
    input_bindings_default(&def);
    expect_same_bindings(&file, &def);
}

Test(bindings, defaults_are_as_documented)
{
    input_bindings b;
    input_bindings_default(&b);
    static const struct {
        int code;
        input_action a;
    } want[] = {
        {KEY_W, INPUT_ACTION_FLY_FORWARD},    {KEY_UP, INPUT_ACTION_FLY_FORWARD},
        {KEY_S, INPUT_ACTION_FLY_BACK},       {KEY_DOWN, INPUT_ACTION_FLY_BACK},
        {KEY_A, INPUT_ACTION_FLY_LEFT},       {KEY_LEFT, INPUT_ACTION_FLY_LEFT},
        {KEY_D, INPUT_ACTION_FLY_RIGHT},      {KEY_RIGHT, INPUT_ACTION_FLY_RIGHT},
        {KEY_PAGEUP, INPUT_ACTION_FLY_UP},    {KEY_PAGEDOWN, INPUT_ACTION_FLY_DOWN},
        {KEY_EQUAL, INPUT_ACTION_SPEED_UP},   {KEY_KPPLUS, INPUT_ACTION_SPEED_UP},
        {KEY_MINUS, INPUT_ACTION_SPEED_DOWN}, {KEY_KPMINUS, INPUT_ACTION_SPEED_DOWN},
        {KEY_HOME, INPUT_ACTION_HOME},        {KEY_H, INPUT_ACTION_HIDE_OBJECT},
        {KEY_U, INPUT_ACTION_SHOW_ALL},       {KEY_P, INPUT_ACTION_PICK},
        {KEY_F, INPUT_ACTION_FLY_TO},         {KEY_G, INPUT_ACTION_GOVERNOR_STATUS},
        {KEY_I, INPUT_ACTION_ISOLATE},        {KEY_BACKSPACE, INPUT_ACTION_SELECT_PARENT},
        {KEY_L, INPUT_ACTION_HIGHLIGHT},      {KEY_Z, INPUT_ACTION_SHOW},
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
    size_t n = sizeof want / sizeof want[0];
    for (size_t i = 0; i < n; i++)
        cr_expect_eq(b.code_action[want[i].code], want[i].a, "code 0x%x", want[i].code);
    cr_expect_eq(bound_codes(&b), (int)n, "nothing else is bound");
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_CLICK], INPUT_ACTION_PICK);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_WHEEL], INPUT_ACTION_DOLLY);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_TAP], INPUT_ACTION_PICK);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_DOUBLE_TAP], INPUT_ACTION_FLY_TO);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_ONE_FINGER_DRAG], INPUT_ACTION_ORBIT);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_TWO_FINGER_DRAG], INPUT_ACTION_PAN);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_TWO_FINGER_PINCH], INPUT_ACTION_DOLLY);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_TOUCHPAD_PINCH], INPUT_ACTION_DOLLY);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_TOUCHPAD_SWIPE], INPUT_ACTION_PAN);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_LONG_PRESS], INPUT_ACTION_ISOLATE);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_TWO_FINGER_TAP], INPUT_ACTION_SHOW_ALL);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_THREE_FINGER_TAP], INPUT_ACTION_PLANE_PLACE);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_THREE_FINGER_DRAG], INPUT_ACTION_VALUE_DRAG);
    cr_expect_eq(b.quit_chord_len, 3);
    cr_expect_eq(b.quit_chord[0], KEY_LEFTCTRL);
    cr_expect_eq(b.quit_chord[1], KEY_LEFTALT);
    cr_expect_eq(b.quit_chord[2], KEY_Q);
}

Test(bindings, a_header_alone_means_the_defaults)
{
    input_bindings def;
    input_bindings_default(&def);
    input_bindings b = parse_ok("// nothing but the header\n{" HEAD "}");
    expect_same_bindings(&b, &def);
}

/* ---- names ---------------------------------------------------------------------- */

Test(bindings, every_action_name_round_trips)
{
    for (int a = 0; a < INPUT_ACTION_COUNT; a++) {
        const char *name = input_action_name((input_action)a);
        cr_assert_not_null(name, "action %d has no name", a);
        for (int other = 0; other < a; other++)
            cr_expect_str_neq(name, input_action_name((input_action)other), "two actions named %s", name);
        bool drag = a == INPUT_ACTION_ORBIT || a == INPUT_ACTION_PAN || a == INPUT_ACTION_DOLLY ||
                    a == INPUT_ACTION_PLANE_PUSH || a == INPUT_ACTION_VALUE_DRAG;
        cr_expect_eq(input_action_is_drag((input_action)a), drag, "%s", name);

        /* a drag action on a button and the wheel; any other on a key and, unless
           it is flight (held), on a tap */
        bool flight = strncmp(name, "fly-", 4) == 0 && a != INPUT_ACTION_FLY_TO;
        char text[512];
        if (drag)
            snprintf(text, sizeof text, "{" HEAD ", \"keys\": {\"BTN_SIDE\": \"%s\"}, \"gestures\": {\"wheel\": \"%s\"}}",
                     name, name);
        else if (flight)
            snprintf(text, sizeof text, "{" HEAD ", \"keys\": {\"KEY_X\": \"%s\"}, \"gestures\": {}}", name);
        else
            snprintf(text, sizeof text, "{" HEAD ", \"keys\": {\"KEY_X\": \"%s\"}, \"gestures\": {\"tap\": \"%s\"}}",
                     name, name);
        input_bindings b = parse_ok(text);
        int code = drag ? BTN_SIDE : KEY_X;
        cr_expect_eq(b.code_action[code], a, "%s", text);
        if (drag)
            cr_expect_eq(b.gesture_action[INPUT_GESTURE_WHEEL], a, "%s", text);
        else if (!flight)
            cr_expect_eq(b.gesture_action[INPUT_GESTURE_TAP], a, "%s", text);
        cr_expect_eq(bound_codes(&b), a == INPUT_ACTION_NONE ? 0 : 1, "%s", text);
    }
    cr_expect_str_eq(input_action_name(INPUT_ACTION_NONE), "none");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_FLY_FORWARD), "fly-forward");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_HIDE_OBJECT), "hide-object");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_SHOW_ALL), "show-all");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_ISOLATE), "isolate");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_SELECT_PARENT), "select-parent");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_HIGHLIGHT), "highlight");
    cr_expect_str_eq(input_action_name(INPUT_ACTION_SHOW), "show");
    cr_expect_null(input_action_name(INPUT_ACTION_COUNT));
    cr_expect_null(input_action_name((input_action)-1));
}

Test(bindings, every_gesture_name_round_trips)
{
    static const bool moves[INPUT_GESTURE_COUNT] = {
        [INPUT_GESTURE_WHEEL] = true,           [INPUT_GESTURE_ONE_FINGER_DRAG] = true,
        [INPUT_GESTURE_TWO_FINGER_DRAG] = true, [INPUT_GESTURE_TWO_FINGER_PINCH] = true,
        [INPUT_GESTURE_TOUCHPAD_PINCH] = true,  [INPUT_GESTURE_TOUCHPAD_SWIPE] = true,
        [INPUT_GESTURE_THREE_FINGER_DRAG] = true,
    };
    for (int g = 0; g < INPUT_GESTURE_COUNT; g++) {
        const char *name = input_gesture_name((input_gesture)g);
        cr_assert_not_null(name, "gesture %d has no name", g);
        input_action a = moves[g] ? INPUT_ACTION_ORBIT : INPUT_ACTION_HOME;
        char text[512];
        snprintf(text, sizeof text, "{" HEAD ", \"gestures\": {\"%s\": \"%s\"}}", name, input_action_name(a));
        input_bindings b = parse_ok(text);
        for (int other = 0; other < INPUT_GESTURE_COUNT; other++)
            cr_expect_eq(b.gesture_action[other], other == g ? a : INPUT_ACTION_NONE, "%s: gesture %s", text,
                         input_gesture_name((input_gesture)other));
    }
    cr_expect_str_eq(input_gesture_name(INPUT_GESTURE_DOUBLE_TAP), "double-tap");
    cr_expect_str_eq(input_gesture_name(INPUT_GESTURE_LONG_PRESS), "long-press");
    cr_expect_str_eq(input_gesture_name(INPUT_GESTURE_TWO_FINGER_TAP), "two-finger-tap");
    cr_expect_null(input_gesture_name(INPUT_GESTURE_COUNT));
}

/* The part actions by name on keys, pointer buttons and the new touch
 * gestures; show-all's old name still reads; the long press and the
 * two-finger tap are discrete (no drag actions, no flight). */
Test(bindings, part_actions_on_keys_buttons_and_touch_gestures)
{
    input_bindings b = parse_ok("{" HEAD ", \"keys\": {\"KEY_X\": \"unhide-all\", \"BTN_SIDE\": \"isolate\", "
                                "\"BTN_EXTRA\": \"select-parent\", \"BTN_FORWARD\": \"highlight\", \"BTN_BACK\": \"show\", "
                                "\"BTN_TASK\": \"hide-object\"}, \"gestures\": {\"long-press\": \"hide-object\", "
                                "\"two-finger-tap\": \"unhide-all\", \"double-tap\": \"select-parent\"}}");
    cr_expect_eq(b.code_action[KEY_X], INPUT_ACTION_SHOW_ALL);
    cr_expect_eq(b.code_action[BTN_SIDE], INPUT_ACTION_ISOLATE);
    cr_expect_eq(b.code_action[BTN_EXTRA], INPUT_ACTION_SELECT_PARENT);
    cr_expect_eq(b.code_action[BTN_FORWARD], INPUT_ACTION_HIGHLIGHT);
    cr_expect_eq(b.code_action[BTN_BACK], INPUT_ACTION_SHOW);
    cr_expect_eq(b.code_action[BTN_TASK], INPUT_ACTION_HIDE_OBJECT);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_LONG_PRESS], INPUT_ACTION_HIDE_OBJECT);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_TWO_FINGER_TAP], INPUT_ACTION_SHOW_ALL);
    cr_expect_eq(b.gesture_action[INPUT_GESTURE_DOUBLE_TAP], INPUT_ACTION_SELECT_PARENT);
    expect_members_failure(", \"gestures\": {\"long-press\": \"orbit\"}", "gestures.long-press",
                           "'orbit' is a drag action, which follows motion, but long-press is a discrete gesture");
    expect_members_failure(", \"gestures\": {\"two-finger-tap\": \"fly-up\"}", "gestures.two-finger-tap",
                           "'fly-up' acts while held");
    expect_members_failure(", \"keys\": {\"KEY_X\": \"unhide\"}", "keys.KEY_X", "unknown action 'unhide'");
}

/* ---- sections -------------------------------------------------------------------- */

Test(bindings, gestures_alone_keep_the_default_keys_and_chord)
{
    input_bindings def;
    input_bindings_default(&def);
    input_bindings b = parse_ok("{" HEAD ", \"gestures\": {\"tap\": \"home\", \"wheel\": \"pan\"}}");
    cr_expect(memcmp(b.code_action, def.code_action, sizeof b.code_action) == 0, "default keys kept");
    cr_expect_eq(b.quit_chord_len, def.quit_chord_len);
    cr_expect(memcmp(b.quit_chord, def.quit_chord, sizeof b.quit_chord) == 0, "default chord kept");
    /* the gestures section replaces all gestures: those not named are unbound */
    for (int g = 0; g < INPUT_GESTURE_COUNT; g++) {
        input_action want = g == INPUT_GESTURE_TAP    ? INPUT_ACTION_HOME
                            : g == INPUT_GESTURE_WHEEL ? INPUT_ACTION_PAN
                                                       : INPUT_ACTION_NONE;
        cr_expect_eq(b.gesture_action[g], want, "gesture %s", input_gesture_name((input_gesture)g));
    }
}

Test(bindings, a_keys_section_replaces_every_key)
{
    input_bindings def;
    input_bindings_default(&def);
    input_bindings b = parse_ok("{" HEAD ", \"keys\": {\"KEY_SPACE\": \"home\", \"BTN_LEFT\": \"pan\"}}");
    cr_expect_eq(bound_codes(&b), 2);
    cr_expect_eq(b.code_action[KEY_SPACE], INPUT_ACTION_HOME);
    cr_expect_eq(b.code_action[BTN_LEFT], INPUT_ACTION_PAN);
    cr_expect_eq(b.code_action[KEY_W], INPUT_ACTION_NONE, "default keys are gone");
    cr_expect(memcmp(b.gesture_action, def.gesture_action, sizeof b.gesture_action) == 0, "default gestures kept");
    cr_expect_eq(b.quit_chord_len, 3);

    input_bindings empty = parse_ok("{" HEAD ", \"keys\": {}, \"gestures\": {}}");
    cr_expect_eq(bound_codes(&empty), 0, "\"keys\": {} binds nothing");
    for (int g = 0; g < INPUT_GESTURE_COUNT; g++)
        cr_expect_eq(empty.gesture_action[g], INPUT_ACTION_NONE);
}

Test(bindings, quit_chord_forms)
{
    input_bindings none = parse_ok("{" HEAD ", \"quit_chord\": []}");
    cr_expect_eq(none.quit_chord_len, 0, "[]: no quit chord");
    for (int i = 0; i < INPUT_CHORD_MAX; i++)
        cr_expect_eq(none.quit_chord[i], 0);

    input_bindings one = parse_ok("{" HEAD ", \"quit_chord\": [\"KEY_ESC\"]}");
    cr_expect_eq(one.quit_chord_len, 1);
    cr_expect_eq(one.quit_chord[0], KEY_ESC);
    cr_expect_eq(one.quit_chord[1], 0);

    input_bindings full = parse_ok("{" HEAD ", \"quit_chord\": [\"KEY_1\", \"KEY_2\", \"KEY_3\", \"KEY_4\", "
                                   "\"KEY_5\", \"KEY_6\", \"KEY_7\", \"KEY_8\"]}");
    cr_expect_eq(full.quit_chord_len, INPUT_CHORD_MAX);
    for (int i = 0; i < INPUT_CHORD_MAX; i++)
        cr_expect_eq(full.quit_chord[i], KEY_1 + i);

    /* a chord key may be bound as well: pressing it still acts */
    input_bindings both = parse_ok("{" HEAD ", \"keys\": {\"KEY_Q\": \"home\"}, \"quit_chord\": [\"KEY_Q\", \"KEY_LEFTCTRL\"]}");
    cr_expect_eq(both.code_action[KEY_Q], INPUT_ACTION_HOME);
    cr_expect_eq(both.quit_chord_len, 2);
    cr_expect_eq(both.quit_chord[0], KEY_Q);
    cr_expect_eq(both.quit_chord[1], KEY_LEFTCTRL);
}

/* ---- kinds ------------------------------------------------------------------------- */

Test(bindings, commands_and_flight_may_be_bound_to_buttons)
{
    input_bindings b = parse_ok("{" HEAD ", \"keys\": {\"BTN_SIDE\": \"fly-forward\", \"BTN_EXTRA\": \"fly-back\", "
                                "\"BTN_FORWARD\": \"home\", \"BTN_BACK\": \"fly-to\", \"BTN_MIDDLE\": \"dolly\", "
                                "\"BTN_SOUTH\": \"pick\", \"BTN_TRIGGER_HAPPY1\": \"orbit\", \"KEY_UNKNOWN\": \"none\"}}");
    cr_expect_eq(b.code_action[BTN_SIDE], INPUT_ACTION_FLY_FORWARD);
    cr_expect_eq(b.code_action[BTN_EXTRA], INPUT_ACTION_FLY_BACK);
    cr_expect_eq(b.code_action[BTN_FORWARD], INPUT_ACTION_HOME);
    cr_expect_eq(b.code_action[BTN_BACK], INPUT_ACTION_FLY_TO);
    cr_expect_eq(b.code_action[BTN_MIDDLE], INPUT_ACTION_DOLLY);
    cr_expect_eq(b.code_action[BTN_SOUTH], INPUT_ACTION_PICK);
    cr_expect_eq(b.code_action[BTN_TRIGGER_HAPPY1], INPUT_ACTION_ORBIT);
    cr_expect_eq(bound_codes(&b), 7, "\"none\" binds nothing");
}

Test(bindings, none_is_accepted_everywhere)
{
    input_bindings b = parse_ok("{" HEAD ", \"keys\": {\"KEY_W\": \"none\", \"BTN_LEFT\": \"none\"}, "
                                "\"gestures\": {\"click\": \"none\", \"wheel\": \"none\", \"tap\": \"none\"}}");
    cr_expect_eq(bound_codes(&b), 0);
    for (int g = 0; g < INPUT_GESTURE_COUNT; g++)
        cr_expect_eq(b.gesture_action[g], INPUT_ACTION_NONE);
}

/* ---- bad input ---------------------------------------------------------------------------- */

Test(bindings, bad_key_names)
{
    expect_members_failure(", \"keys\": {\"KEY_WW\": \"pick\"}", "keys.KEY_WW",
                           "unknown evdev key or button name (names as in linux/input-event-codes.h, e.g. KEY_W, "
                           "BTN_LEFT)");
    expect_members_failure(", \"keys\": {\"key_w\": \"pick\"}", "keys.key_w", "unknown evdev key or button name");
    expect_members_failure(", \"keys\": {\"ABS_X\": \"pick\"}", "keys.ABS_X", "unknown evdev key or button name");
    expect_members_failure(", \"keys\": {\"KEY_RESERVED\": \"pick\"}", "keys.KEY_RESERVED",
                           "is a placeholder of the code space, not a key or button");
    expect_members_failure(", \"keys\": {\"KEY_MAX\": \"pick\"}", "keys.KEY_MAX", "not a key or button");
}

Test(bindings, bad_actions)
{
    expect_members_failure(", \"keys\": {\"KEY_W\": \"fly-fwd\"}", "keys.KEY_W",
                           "unknown action 'fly-fwd' (expected one of: none, orbit, pan, dolly, fly-forward, "
                           "fly-back, fly-left, fly-right, fly-up, fly-down, speed-up, speed-down, home, pick, "
                           "hide-object, show-all, fly-to, governor-status, isolate, select-parent, highlight, show, "
                           "opacity-down, opacity-up, part-opacity-down, part-opacity-up, plane-place, plane-next, "
                           "plane-flip, plane-remove, plane-remove-all, plane-push, ambient-occlusion, crop-down, crop-up, "
                           "crop-off, time-play, time-back, time-forward, time-slower, time-faster, value-down, value-up, "
                           "colormap-next, value-drag)");
    expect_members_failure(", \"keys\": {\"KEY_W\": 3}", "keys.KEY_W", "expected an action name (a string), got number");
    expect_members_failure(", \"keys\": {\"KEY_W\": null}", "keys.KEY_W", "expected an action name (a string), got null");
    expect_members_failure(", \"gestures\": {\"tap\": [\"pick\"]}", "gestures.tap",
                           "expected an action name (a string), got array");
    expect_members_failure(", \"gestures\": {\"tap\": \"Pick\"}", "gestures.tap", "unknown action 'Pick'");
}

Test(bindings, drag_actions_need_motion)
{
    expect_members_failure(", \"keys\": {\"KEY_O\": \"orbit\"}", "keys.KEY_O",
                           "'orbit' is a drag action, which follows motion: bind it to a pointer button (BTN_*) or a "
                           "moving gesture, not to a keyboard key");
    expect_members_failure(", \"keys\": {\"KEY_W\": \"fly-forward\", \"KEY_SPACE\": \"dolly\"}", "keys.KEY_SPACE",
                           "'dolly' is a drag action");
    expect_members_failure(", \"gestures\": {\"tap\": \"orbit\"}", "gestures.tap",
                           "'orbit' is a drag action, which follows motion, but tap is a discrete gesture without "
                           "motion (it takes speed-up, speed-down, home, pick, hide-object, show-all, fly-to, governor-status, isolate, "
                           "select-parent, highlight, show, opacity-down, opacity-up, part-opacity-down, part-opacity-up, "
                           "plane-place, plane-next, plane-flip, plane-remove, plane-remove-all, ambient-occlusion, crop-down, "
                           "crop-up, crop-off, time-play, time-back, time-forward, time-slower, time-faster, value-down, "
                           "value-up, colormap-next or none)");
    expect_members_failure(", \"gestures\": {\"click\": \"pan\"}", "gestures.click", "'pan' is a drag action");
    expect_members_failure(", \"gestures\": {\"double-tap\": \"dolly\"}", "gestures.double-tap",
                           "'dolly' is a drag action");
}

Test(bindings, moving_gestures_take_only_drag_actions)
{
    expect_members_failure(", \"gestures\": {\"wheel\": \"pick\"}", "gestures.wheel",
                           "'pick' is a command action, but wheel is a moving gesture, which takes only drag actions "
                           "(orbit, pan, dolly, plane-push, value-drag) or none");
    expect_members_failure(", \"gestures\": {\"two-finger-pinch\": \"speed-up\"}", "gestures.two-finger-pinch",
                           "'speed-up' is a command action");
    expect_members_failure(", \"gestures\": {\"touchpad-swipe\": \"fly-left\"}", "gestures.touchpad-swipe",
                           "'fly-left' is a command action");
}

Test(bindings, flight_cannot_be_bound_to_a_discrete_gesture)
{
    expect_members_failure(", \"gestures\": {\"double-tap\": \"fly-forward\"}", "gestures.double-tap",
                           "'fly-forward' acts while held, and a double-tap cannot be held: bind flight to a key or "
                           "button");
}

Test(bindings, bad_gestures_section)
{
    expect_members_failure(", \"gestures\": {\"triple-tap\": \"pick\"}", "gestures.triple-tap",
                           "unknown field (expected one of: click, wheel, tap, double-tap, one-finger-drag, "
                           "two-finger-drag, two-finger-pinch, touchpad-pinch, touchpad-swipe, long-press, "
                           "two-finger-tap, three-finger-tap, three-finger-drag)");
    expect_members_failure(", \"gestures\": [\"tap\"]", "gestures", "expected an object, got array");
    expect_members_failure(", \"keys\": \"KEY_W\"", "keys", "expected an object, got string");
}

Test(bindings, same_code_under_two_names)
{
    /* libevdev knows both names of the gamepad's south button (0x130) */
    expect_members_failure(", \"keys\": {\"BTN_SOUTH\": \"pick\", \"BTN_A\": \"home\"}", "keys.BTN_A",
                           "same code as 'BTN_SOUTH' (0x130)");
    expect_members_failure(", \"quit_chord\": [\"BTN_SOUTH\"]", "quit_chord[0]",
                           "'BTN_SOUTH' is a button; the quit chord takes keyboard keys only");
}

Test(bindings, bad_quit_chords)
{
    expect_members_failure(", \"quit_chord\": [\"KEY_LEFTCTRL\", \"KEY_QQ\"]", "quit_chord[1]",
                           "unknown evdev key or button name");
    expect_members_failure(", \"quit_chord\": [\"KEY_LEFTCTRL\", \"KEY_Q\", \"KEY_LEFTCTRL\"]", "quit_chord[2]",
                           "same code as 'KEY_LEFTCTRL' (quit_chord[0]); a chord lists each key once");
    expect_members_failure(", \"quit_chord\": [\"KEY_1\", \"KEY_2\", \"KEY_3\", \"KEY_4\", \"KEY_5\", \"KEY_6\", "
                           "\"KEY_7\", \"KEY_8\", \"KEY_9\"]",
                           "quit_chord", "at most 8 keys, got 9");
    expect_members_failure(", \"quit_chord\": \"KEY_Q\"", "quit_chord",
                           "expected an array of 1 to 8 key names, or [] for no quit chord, got string");
    expect_members_failure(", \"quit_chord\": {\"KEY_Q\": true}", "quit_chord", "got object");
    expect_members_failure(", \"quit_chord\": [\"KEY_Q\", 17]", "quit_chord[1]",
                           "expected a key name (a string), got number");
    expect_members_failure(", \"quit_chord\": [\"BTN_LEFT\", \"KEY_Q\"]", "quit_chord[0]",
                           "'BTN_LEFT' is a button; the quit chord takes keyboard keys only");
}

Test(bindings, bad_headers_and_top_level)
{
    expect_failure("{\"format\": \"tessera-wall\", \"version\": 1}", "format",
                   "expected \"tessera-bindings\", got \"tessera-wall\"");
    expect_failure("{\"version\": 1, \"keys\": {}}", "format",
                   "required field is missing (a bindings file has \"format\": \"tessera-bindings\")");
    expect_failure("{\"format\": \"tessera-bindings\", \"version\": 2}", "version",
                   "unsupported version 2 (this build reads version 1)");
    expect_failure("{\"format\": \"tessera-bindings\"}", "version", "required field is missing");
    expect_members_failure(", \"buttons\": {}", "buttons",
                           "unknown field (expected one of: format, version, keys, gestures, quit_chord)");
    expect_failure("[1, 2]", "bindings.json: expected a JSON object at the top level, got array", "array");
}

Test(bindings, syntax_errors_and_duplicate_keys_give_line_and_column)
{
    expect_failure("{" HEAD ",\n  \"keys\": {\n    \"KEY_W\" \"pick\"}}", "bindings.json:3:13: JSON syntax error: ",
                   "JSON syntax error");
    expect_failure("{" HEAD ",\n  \"keys\": {\"KEY_W\": \"pick\",\n           \"KEY_W\": \"home\"}}",
                   "bindings.json:3:12: duplicate key 'KEY_W' in a JSON object", "duplicate key");
    expect_failure("", "bindings.json:1:1: JSON syntax error", "JSON syntax error");
}

Test(bindings, load_names_the_file)
{
    input_bindings b, before;
    memset(&b, 0x3c, sizeof b);
    memcpy(&before, &b, sizeof b);
    tess_error err = {{0}};
    cr_expect_not(input_bindings_load("no/such/dir/bindings.json", &b, &err));
    cr_expect_str_eq(err.msg, "no/such/dir/bindings.json: cannot open: No such file or directory");
    cr_expect(memcmp(&b, &before, sizeof b) == 0, "*out untouched");

    char dir[256], path[320];
    support_make_tmp_dir(dir, sizeof dir, "bindings");
    snprintf(path, sizeof path, "%s/bad.json", dir);
    FILE *f = fopen(path, "w");
    cr_assert_not_null(f);
    fputs("{" HEAD ", \"keys\": {\"KEY_W\": \"orbit\"}}\n", f);
    fclose(f);
    tess_error err2 = {{0}};
    cr_expect_not(input_bindings_load(path, &b, &err2));
    char want[512];
    snprintf(want, sizeof want, "%s: field 'keys.KEY_W': 'orbit' is a drag action", path);
    cr_expect(strncmp(err2.msg, want, strlen(want)) == 0, "got:  %s\nwant: %s", err2.msg, want);
    cr_expect(memcmp(&b, &before, sizeof b) == 0, "*out untouched");

    tess_error err3 = {{0}};
    cr_expect_not(input_bindings_load(dir, &b, &err3), "a directory is not a bindings file");
    snprintf(want, sizeof want, "%s: cannot open: ", dir);
    cr_expect(strncmp(err3.msg, want, strlen(want)) == 0, "got: %s", err3.msg);
    support_remove_tmp_dir(dir);
}
