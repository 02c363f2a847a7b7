/* event.h - input events as the mapping layer (controller.h) sees them:
 * libinput's events already placed on the wall's image plane, so the mapping
 * layer needs neither libinput nor a device and tests can feed it synthetic
 * events.
 *
 * PLANE COORDINATES. Every position is a point of the wall's one virtual
 * image plane in the screen coordinates of camera.h: sx right, sy up, the
 * whole plane is [-1, 1] x [-1, 1] whatever its aspect (plane width / height
 * = input_layout.plane_aspect). A touch on an output lands in that output's
 * camera_window of the plane; an absolute pointer (tablet) covers the whole
 * plane; relative pointer motion is converted from device units (libinput's
 * normalised 1000 dpi pixels) to plane units by the plane's size in pixels.
 *
 * FRAMES. One hardware frame (everything up to EV_SYN) arrives as a run of
 * events closed by INPUT_FRAME (pointer, keyboard, gestures: libinput already
 * delivers one event per frame, the source appends INPUT_FRAME) or
 * INPUT_TOUCH_FRAME (touch). The mapping layer emits at most one camera per
 * frame. */
#ifndef TESSERA_INPUT_EVENT_H
#define TESSERA_INPUT_EVENT_H

#include <stdbool.h>
#include <stdint.h>

typedef enum input_event_kind {
    INPUT_KEY,                  /* code: evdev KEY_*, pressed */
    INPUT_BUTTON,               /* code: evdev BTN_* of a pointer, pressed; at the cursor */
    INPUT_POINTER_MOTION,       /* dx, dy: relative motion in plane units (dy up) */
    INPUT_POINTER_ABS,          /* x, y: absolute cursor position in plane units */
    INPUT_SCROLL,               /* dy: wheel clicks, > 0 away from the user (towards the scene) */
    INPUT_TOUCH_DOWN,           /* slot, x, y */
    INPUT_TOUCH_MOTION,         /* slot, x, y */
    INPUT_TOUCH_UP,             /* slot */
    INPUT_TOUCH_CANCEL,         /* every touch of the device ends without effect */
    INPUT_TOUCH_FRAME,          /* end of a touch frame */
    INPUT_PINCH_BEGIN,          /* touchpad gesture; fingers */
    INPUT_PINCH_UPDATE,         /* dx, dy: centre motion in plane units; scale: finger spread
                                   relative to the begin (cumulative, 1 at begin) */
    INPUT_PINCH_END,            /* cancelled */
    INPUT_SWIPE_BEGIN,          /* fingers */
    INPUT_SWIPE_UPDATE,         /* dx, dy in plane units */
    INPUT_SWIPE_END,            /* cancelled */
    INPUT_FRAME,                /* end of a non-touch frame */
    INPUT_DEVICE_ADDED,         /* device (informational: the controller forgets nothing) */
    INPUT_DEVICE_REMOVED,       /* device: its held keys, buttons and touches are released */
    INPUT_VIEWER_POINTER,       /* a remote viewer's pointer (remote/): slot = the viewer's slot
                                   (0..INPUT_MAX_VIEWERS-1), pressed = shown, x, y its plane point;
                                   drawn on the wall and every view in the viewer's colour */
    INPUT_PRIVATE_VIEW,         /* device (a remote viewer's) steers channel `code` (a private
                                   channel: engine/scene/frame_state.h) from now on, until the device is
                                   removed; its events then go to a private view's controller
                                   (runner.h; controller.h, PRIVATE VIEW) */
} input_event_kind;

typedef struct input_event {
    input_event_kind kind;
    uint64_t time_us;   /* monotonic microseconds (libinput's event time) */
    int device;         /* the source's device number (held state is per device) */
    int code;           /* KEY / BUTTON */
    bool pressed;       /* KEY / BUTTON */
    int slot;           /* TOUCH_*: the touch's slot on its device, 0..INPUT_MAX_TOUCHES-1 */
    int fingers;        /* PINCH_BEGIN / SWIPE_BEGIN */
    bool cancelled;     /* PINCH_END / SWIPE_END */
    double x, y;        /* POINTER_ABS, TOUCH_DOWN/MOTION: plane coordinates */
    double dx, dy;      /* POINTER_MOTION, SWIPE/PINCH_UPDATE: plane units; SCROLL: dy clicks */
    double scale;       /* PINCH_UPDATE */
} input_event;

#define INPUT_MAX_TOUCHES 10
#define INPUT_MAX_VIEWERS 8 /* remote viewers at once: their pointers' slots */

#endif
