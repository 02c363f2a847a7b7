/* controller_private.h - what the controller's files share and nothing else
 * includes: the controller's state and the functions one of them calls in
 * another. The public contract is controller.h.
 *
 * THE FILES. controller.c: the controller's life (create, destroy), its
 * entry points (events, ticks, the deadline), which hand each event to
 * gesture.c or commands.c (the wheel, the touchpad's pinch and swipe and the
 * viewers' pointers, one event each, it turns into motions itself); gesture.c: what a person is doing, recognised
 * from keys, buttons, the pointer and touch (gesture_*), each thing
 * recognised handed to commands.c as an action (commands_run) or a motion
 * (commands_drag); commands.c: what was recognised turned into records
 * (commands_*). Every function here takes the controller the entry point
 * was called with.
 *
 * Threading (controller.h): one thread, the input thread, calls everything;
 * nothing here is shared with another thread. */
#ifndef TESSERA_INPUT_CONTROLLER_PRIVATE_H
#define TESSERA_INPUT_CONTROLLER_PRIVATE_H

#include <stdbool.h>
#include <stdint.h>

#include "controller.h"

#define TOUCH_SLOTS 20            /* touches tracked at once, over all devices */
#define SELECTION_LEVELS (1 + INPUT_HIT_ANCESTORS) /* the picked part and its ancestors */

typedef struct touch {
    bool active;
    int device, slot;
    double x, y;       /* now */
    double x0, y0;     /* where it went down */
} touch;

struct input_controller {
    input_controller_config cfg;
    input_controller_hooks hooks;

    camera_desc cam;           /* the camera being steered */
    bool cam_dirty;            /* changed since the last emitted camera */
    double fly_speed;          /* world units per second */

    /* remote viewers' pointers (plane coordinates), by viewer slot */
    bool pointer_visible[INPUT_MAX_VIEWERS], pointer_dirty[INPUT_MAX_VIEWERS];
    double pointer_x[INPUT_MAX_VIEWERS], pointer_y[INPUT_MAX_VIEWERS];

    /* CAMERA HOLDER (controller.h): the device whose camera motion counts, -1 none; it holds
     * while its drag or touches last and until hold_until_us after its last camera motion */
    int cam_holder;
    uint64_t cam_hold_until_us;
    int event_device;          /* the device of the event being handled; -1 in ticks */
    uint64_t event_us;         /* its time */

    /* cursor (plane coordinates) */
    double cur_x, cur_y;
    bool cursor_visible, cursor_dirty;
    bool status_shown;         /* the last status emitted was not "" */
    bool governor_status_shown; /* the governor's line is asked for (governor-status toggles it) */

    /* a pointer button drag */
    bool dragging;
    int drag_code, drag_device;
    input_action drag_action;
    vec3 drag_point;           /* the picked point the drag turns about / keeps under the cursor */
    double drag_travel;        /* plane units moved since the press */

    /* keys and buttons held: count per code, and the device that pressed it last */
    unsigned char held[INPUT_CODE_COUNT];
    int held_device[INPUT_CODE_COUNT];
    bool chord_fired;

    /* flight and animations */
    uint64_t last_tick_us;     /* the last input_controller_tick */
    uint64_t last_flight_us;
    bool animating;
    camera_desc anim_from, anim_to;
    uint64_t anim_start_us;

    /* touch */
    touch touches[TOUCH_SLOTS];
    int fingers_prev;          /* fingers at the end of the previous touch frame */
    vec3 touch_point;          /* anchor picked when the finger count last changed */
    double prev_x, prev_y;     /* one finger: its position; two: their centre */
    double prev_spread;        /* two fingers: their distance */
    bool one_drag_started;     /* one finger moved beyond the tap slop */
    /* the current touch sequence (from the first finger down to the last up) */
    uint64_t seq_start_us;
    int seq_max_fingers;
    double seq_x0, seq_y0, seq_travel;
    bool have_last_tap;
    uint64_t last_tap_us;
    double last_tap_x, last_tap_y;
    bool seq_long_pressed;     /* this sequence's long press has fired (its finger does nothing more) */

    /* parts (controller.h, PARTS) */
    bool have_selection;
    input_part sel_levels[SELECTION_LEVELS]; /* the part picked last, then its ancestors nearest first */
    int sel_level_count;       /* valid entries of sel_levels (>= 1 with a selection) */
    int sel_level;             /* the selection is sel_levels[sel_level] */
    bool highlight_on;         /* the selection is highlighted ... */
    input_part highlighted;    /* ... as this range (what the last highlight-on record named) */
    input_part hidden[INPUT_HIDDEN_MAX]; /* hide-object's parts not shown again yet, oldest first */
    int hidden_count;

    /* inspection: what input asked for last (controller.h, OPACITY and CUTTING PLANES) */
    float opacity;             /* global */
    struct {
        uint32_t first, count;
        float opacity;
    } part_opacity[INPUT_OPACITY_PARTS]; /* oldest first */
    int part_opacity_count;
    clip_plane planes[CLIP_MAX_PLANES]; /* as the records said (normals as sent) */
    int plane_sel;             /* the selected plane (on), or -1 */
    char renderer[TXN_NAME_BYTES];   /* the renderer input asked for last (or the config's) */
    char configured[TXN_NAME_BYTES]; /* the cycle's first renderer (controller.h, AMBIENT OCCLUSION) */
    bool plane_dirty;          /* plane_sel moved since the last emitted record (plane-push) */
    geometry_crop crops[INPUT_CROP_MAX]; /* as the records said, per cfg.crops entry */
    /* time steps (controller.h, TIME STEPS) */
    uint32_t time_step;        /* the step asked for last */
    bool playing;
    double time_rate;          /* steps per second */
    uint64_t next_step_us;     /* playing: when the next step is due */
    float values[INPUT_VALUE_MAX];              /* as the records said, per cfg.values entry */
    bool values_dirty;                          /* values moved by value-drag since the last records */
    char maps[INPUT_MAP_MAX][TXN_NAME_BYTES];   /* as the records said, per cfg.maps entry */
    char transfer[TXN_NAME_BYTES];              /* as the last transfer record said (cfg.media) */

    /* touchpad gestures */
    vec3 gesture_point;
    double pinch_prev_scale;

    /* kiosk */
    bool touring, started;
    uint64_t last_input_us;
};

/* ---- gesture.c ---- */

/* A key or button pressed or released (INPUT_KEY, INPUT_BUTTON): held counts,
 * the quit chord, a drag button's drag or click, flight keys, commands. */
void gesture_key_or_button(input_controller *c, const input_event *e);
/* The cursor moved to plane point (nx, ny) (clamped by the caller): it shows,
 * and a button drag going moves by the difference. */
void gesture_pointer_moved(input_controller *c, double nx, double ny);
/* A touch down, motion, up or cancel: the slot table and the touch sequence
 * (what it did is recognised at its frame, gesture_touch_frame). */
void gesture_touch_event(input_controller *c, const input_event *e);
/* A touch frame's end: fingers that came or went anchor again; else the one,
 * two or three fingers drag and pinch; the last finger up ends the sequence
 * (a tap, double tap, two- or three-finger tap). */
void gesture_touch_frame(input_controller *c, uint64_t now_us);
/* Whether the finger down may become a long press (one finger this sequence,
 * within the tap slop, not fired yet, a long press bound), and when (*due_us). */
bool gesture_long_press_due(const input_controller *c, uint64_t *due_us);
/* The long press, when its time came by now_us (and no tour plays). */
void gesture_long_press_if_due(input_controller *c, uint64_t now_us);
/* `device` went away: its keys, buttons, drag and fingers let go. */
void gesture_device_removed(input_controller *c, int device);

/* ---- commands.c ---- */

/* Every record goes out here (a private view's controller says only where its
 * channel's camera goes). */
void commands_emit(input_controller *c, input_txn *t);
/* End of an input frame or tick: what accumulated goes out, at most one camera,
 * one cursor, one plane, one value record per value target, one pointer per
 * viewer. */
void commands_flush(input_controller *c);
/* The camera becomes `next` (to go out at the next flush) when the event being
 * handled may move it (CAMERA HOLDER, controller.h). */
void commands_set_camera(input_controller *c, camera_desc next);
void commands_show_cursor(input_controller *c, bool visible);
/* The point under plane point (sx, sy): the first surface, else the cursor
 * ray at the look-at depth. hit_out (may be NULL) gets the pick as the
 * controller uses it: a hit always names a part (else its instance), labels
 * end in NUL, ancestor_count lies in [0, INPUT_HIT_ANCESTORS]. */
vec3 commands_point_under(input_controller *c, double sx, double sy, input_hit *hit_out);
/* A drag of (dx, dy) plane units with `action` (orbit, pan, dolly, value-drag,
 * plane-push; others do nothing) about `point`. */
void commands_drag(input_controller *c, input_action action, vec3 point, double dx, double dy);
/* The held flight keys as a direction (-1, 0 or +1 along each; forward,
 * right and up all NULL or none); whether any is held. */
bool commands_flight_direction(const input_controller *c, double *forward, double *right, double *up);
bool commands_flight_held(const input_controller *c);
/* The selection becomes the part hit (nothing on a miss); a highlight follows. */
void commands_select_hit(input_controller *c, const input_hit *pk);
/* Playing time steps: the next one when it is due and ready. */
void commands_play_if_due(input_controller *c, uint64_t now_us);
/* A command action (bindings.h) at plane point (sx, sy); a drag action or
 * INPUT_ACTION_NONE does nothing. */
void commands_run(input_controller *c, input_action action, double sx, double sy, uint64_t now_us);
/* A person touched something: the tour hands over, the idle clock restarts. */
void commands_user_input(input_controller *c, uint64_t now_us);
/* The idle tour starts: drags and animations stop, cursor and status go. */
void commands_start_tour(input_controller *c);

#endif
