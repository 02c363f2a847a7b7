/* bindings.h - what each key, button and gesture does: configs/bindings.json
 * (format reference: docs/bindings-format.md), keys and buttons by their
 * evdev names as libevdev knows them ("KEY_W", "BTN_LEFT"), gestures by name.
 *
 * Actions come in two kinds:
 *  - drag actions (orbit, pan, dolly, plane-push) follow a motion: bound to pointer
 *    buttons (held while the pointer moves), the wheel, and the touch and
 *    touchpad gestures that move;
 *  - command actions (flight, speed, home, pick, fly-to, the part commands
 *    hide-object, isolate, show, show-all, select-parent, highlight, the
 *    opacity and cutting-plane commands) happen
 *    on a key or button press (flight keys and buttons act while held), or on
 *    a discrete gesture (click, tap, double tap, long press, two-finger tap).
 * Binding an action where its kind cannot happen is an error naming the
 * field: a drag action on a keyboard key or a discrete gesture, a command
 * action on a moving gesture, flight on a discrete gesture (it cannot be
 * held). "none" may be bound anywhere. A code is a button when its evdev name
 * starts with BTN_, else a keyboard key. Unknown names, a code given twice
 * (also under two names, e.g. BTN_A and BTN_SOUTH) and bad quit chords are
 * errors too.
 *
 * Each section the file gives ("keys", "gestures", "quit_chord") replaces the
 * defaults of that section completely; a section left out keeps them. */
#ifndef TESSERA_INPUT_BINDINGS_H
#define TESSERA_INPUT_BINDINGS_H

#include <stdbool.h>
#include <stddef.h>

#include "engine/base/err.h"

typedef enum input_action {
    INPUT_ACTION_NONE,
    /* drag actions */
    INPUT_ACTION_ORBIT,       /* about the point picked under the cursor / finger */
    INPUT_ACTION_PAN,         /* the picked point follows the cursor */
    INPUT_ACTION_DOLLY,       /* towards the point under the cursor */
    /* command actions */
    INPUT_ACTION_FLY_FORWARD, /* held: flight at the current speed */
    INPUT_ACTION_FLY_BACK,
    INPUT_ACTION_FLY_LEFT,
    INPUT_ACTION_FLY_RIGHT,
    INPUT_ACTION_FLY_UP,
    INPUT_ACTION_FLY_DOWN,
    INPUT_ACTION_SPEED_UP,    /* flight speed x 1.5 */
    INPUT_ACTION_SPEED_DOWN,  /* flight speed / 1.5 */
    INPUT_ACTION_HOME,        /* the scene's home view */
    INPUT_ACTION_PICK,        /* report the part under the cursor and select it */
    INPUT_ACTION_HIDE_OBJECT, /* hide the part under the cursor (its whole subtree) */
    INPUT_ACTION_SHOW_ALL,    /* "show-all" (also read as its old name "unhide-all") */
    INPUT_ACTION_FLY_TO,      /* fly to the point under the cursor */
    INPUT_ACTION_GOVERNOR_STATUS, /* show / hide the frame-budget governor's state in the status line */
    INPUT_ACTION_ISOLATE,     /* show only the selection (none: the part under the cursor) */
    INPUT_ACTION_SELECT_PARENT, /* widen the selection to its parent part */
    INPUT_ACTION_HIGHLIGHT,   /* highlight of the selection on / off */
    INPUT_ACTION_SHOW,        /* show the part hidden last again (undo hide-object) */
    /* inspection (controller.h, OPACITY and CUTTING PLANES) */
    INPUT_ACTION_OPACITY_DOWN,      /* global opacity one step (INPUT_OPACITY_STEPS) down, to 0 at least */
    INPUT_ACTION_OPACITY_UP,        /* ... up, to 1 at most */
    INPUT_ACTION_PART_OPACITY_DOWN, /* the selection's opacity one step down */
    INPUT_ACTION_PART_OPACITY_UP,
    INPUT_ACTION_PLANE_PLACE,       /* a cutting plane through the point under the cursor, facing the camera */
    INPUT_ACTION_PLANE_NEXT,        /* select the next plane that is on */
    INPUT_ACTION_PLANE_FLIP,        /* the selected plane removes the other side */
    INPUT_ACTION_PLANE_REMOVE,      /* the selected plane off */
    INPUT_ACTION_PLANE_REMOVE_ALL,  /* every plane off */
    INPUT_ACTION_PLANE_PUSH,        /* drag: the selected plane along its normal (up: away from its normal) */
    INPUT_ACTION_AMBIENT_OCCLUSION, /* the next renderer of the AO cycle (controller.h, AMBIENT OCCLUSION) */
    /* scientific data (controller.h, CROP) */
    INPUT_ACTION_CROP_DOWN,         /* the particles' crop window one step down its attribute's range */
    INPUT_ACTION_CROP_UP,           /* ... up */
    INPUT_ACTION_CROP_OFF,          /* every particle seen again */
    /* time steps (controller.h, TIME STEPS) */
    INPUT_ACTION_TIME_PLAY,         /* play / pause the time series */
    INPUT_ACTION_TIME_BACK,         /* one step back (wrapping) */
    INPUT_ACTION_TIME_FORWARD,      /* one step forward (wrapping) */
    INPUT_ACTION_TIME_SLOWER,       /* playing rate / 1.5 */
    INPUT_ACTION_TIME_FASTER,       /* playing rate x 1.5 */
    INPUT_ACTION_VALUE_DOWN,        /* every iso-value one step (INPUT_VALUE_STEPS of its range) down */
    INPUT_ACTION_VALUE_UP,          /* ... up */
    INPUT_ACTION_COLORMAP_NEXT,     /* the next built-in colour map / transfer function */
    INPUT_ACTION_VALUE_DRAG,        /* drag: every iso-value follows the motion (up: higher) */
    INPUT_ACTION_COUNT
} input_action;

/* Gestures by name in the file ("gestures" object). */
typedef enum input_gesture {
    INPUT_GESTURE_CLICK,            /* "click": a button bound to a drag action pressed and released
                                       without moving */
    INPUT_GESTURE_WHEEL,            /* "wheel": scroll wheel */
    INPUT_GESTURE_TAP,              /* "tap": a short touch without motion */
    INPUT_GESTURE_DOUBLE_TAP,       /* "double-tap" */
    INPUT_GESTURE_ONE_FINGER_DRAG,  /* "one-finger-drag" */
    INPUT_GESTURE_TWO_FINGER_DRAG,  /* "two-finger-drag": motion of the two fingers' centre */
    INPUT_GESTURE_TWO_FINGER_PINCH, /* "two-finger-pinch": change of the fingers' spread */
    INPUT_GESTURE_TOUCHPAD_PINCH,   /* "touchpad-pinch": libinput pinch gesture, its scale */
    INPUT_GESTURE_TOUCHPAD_SWIPE,   /* "touchpad-swipe": libinput swipe gesture */
    INPUT_GESTURE_LONG_PRESS,       /* "long-press": one finger held still (controller.h:
                                       INPUT_LONG_PRESS_S); selects the part under it first */
    INPUT_GESTURE_TWO_FINGER_TAP,   /* "two-finger-tap": two fingers down and up, short, without motion */
    INPUT_GESTURE_THREE_FINGER_TAP, /* "three-finger-tap": three fingers down and up, short, without motion;
                                       acts where the first finger landed */
    INPUT_GESTURE_THREE_FINGER_DRAG, /* "three-finger-drag": the motion of three fingers' centre */
    INPUT_GESTURE_COUNT
} input_gesture;

/* evdev codes: KEY_* and BTN_* share one space below KEY_CNT (0x300). */
#define INPUT_CODE_COUNT 0x300
#define INPUT_CHORD_MAX 8

typedef struct input_bindings {
    unsigned char code_action[INPUT_CODE_COUNT];   /* input_action per KEY_ / BTN_ code */
    unsigned char gesture_action[INPUT_GESTURE_COUNT];
    int quit_chord[INPUT_CHORD_MAX];               /* keyboard key codes held together quit; the slots
                                                      from quit_chord_len on are 0 */
    int quit_chord_len;                            /* 0: no quit chord */
} input_bindings;

/* The bindings of configs/bindings.json as shipped (also what an absent
 * file means; a test checks that the two are equal): WASD and arrows fly,
 * PageUp/PageDown up/down, = and - (main and keypad + and -) speed, Home,
 * left button orbit (click: pick), right and middle pan, wheel dolly, one
 * finger orbit, two fingers pan and pinch dolly, tap pick, double tap fly-to,
 * touchpad pinch dolly and swipe pan, long press isolate, two-finger tap
 * show-all, P pick, F fly-to, H hide-object, U show-all, I isolate,
 * Backspace select-parent, L highlight, Z show (undo the last hide), [ and ]
 * opacity down / up, ; and ' the selection's opacity down / up, C places a
 * cutting plane, N selects the next, X flips it, Delete removes it, End
 * removes them all, the middle button drags the selected plane along its
 * normal, a three-finger tap places a plane, quit chord Ctrl+Alt+Q (left
 * keys). The whole struct is written,
 * padding included (memset), so bindings may be compared with memcmp. */
void input_bindings_default(input_bindings *out);

/* Load / parse a bindings file. False with err naming the file, the field and
 * the problem ("bindings.json: field 'keys.KEY_WW': unknown evdev key or button
 * name ..."; syntax errors as "bindings.json:LINE:COL: ..."); *out untouched on
 * failure. `name` only names the text in messages. Files over 1 MiB are
 * refused. On success every byte of *out is written, as by
 * input_bindings_default. */
bool input_bindings_load(const char *file, input_bindings *out, tess_error *err);
bool input_bindings_parse(const char *name, const char *text, size_t len, input_bindings *out, tess_error *err);

/* Names as in the file: "orbit", "fly-forward", ...; "none" for NONE; NULL
 * for a value out of range (COUNT included). Reading also takes the old
 * name "unhide-all" for show-all. */
const char *input_action_name(input_action a);
const char *input_gesture_name(input_gesture g);
bool input_action_is_drag(input_action a);

#endif
