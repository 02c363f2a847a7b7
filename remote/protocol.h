/* protocol.h (remote) - the page's side of the remote view's protocol
 * (docs/remote-protocol.md) as pure functions: one page->server text message
 * parsed into a remote_message (or dropped with a reason), a message turned
 * into the input events (input/event.h) the mapping layer takes, the rate
 * limit, and the binary frame header the server sends. No I/O, no threads:
 * tests and the fuzzer drive it directly.
 *
 * Threading: a remote_viewer_input and a remote_rate belong to one viewer and
 * are used by one thread at a time (the server thread). */
#ifndef TESSERA_REMOTE_PROTOCOL_H
#define TESSERA_REMOTE_PROTOCOL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "input/event.h"

#define REMOTE_MESSAGE_MAX_BYTES 1024 /* a longer page->server message is dropped (REMOTE_DROP_TOO_LONG) */
#define REMOTE_RATE_PER_S 400.0       /* messages a second a viewer may send, sustained */
#define REMOTE_RATE_BURST 200.0       /* and in a burst (the token bucket's depth) */
#define REMOTE_FRAME_HEADER_BYTES 32
#define REMOTE_FRAME_MAGIC 0x46525354u /* "TSRF" in little-endian memory */
/* A refused viewer's WebSocket is opened, then closed with one of these codes
 * (RFC 6455's private range) and a reason (docs/remote-protocol.md). */
#define REMOTE_CLOSE_TOKEN 4403 /* a wrong or missing token */
#define REMOTE_CLOSE_FULL 4503  /* max_viewers are connected; reason "too many viewers (N max)" */
#define REMOTE_DEVICE_BASE 1000        /* input device number of viewer slot s: REMOTE_DEVICE_BASE + s */

/* Why a message was dropped (counted per reason by the server). */
typedef enum remote_drop_reason {
    REMOTE_DROP_NOT_JSON,      /* not parseable JSON (or nested deeper than the parser allows) */
    REMOTE_DROP_NOT_OBJECT,    /* JSON, but not an object */
    REMOTE_DROP_UNKNOWN_TYPE,  /* no "t", or one the protocol does not have */
    REMOTE_DROP_MISSING_FIELD, /* a field the kind needs is absent */
    REMOTE_DROP_WRONG_TYPE,    /* a field of the wrong JSON type */
    REMOTE_DROP_OUT_OF_RANGE,  /* a number outside its range or not finite, too many touches */
    REMOTE_DROP_UNKNOWN_KEY,   /* a key code with no evdev key */
    REMOTE_DROP_TOO_LONG,      /* over REMOTE_MESSAGE_MAX_BYTES */
    REMOTE_DROP_RATE,          /* over the rate limit */
    REMOTE_DROP_BINARY,        /* a binary message (the page sends text only) */
    REMOTE_DROP_REASONS
} remote_drop_reason;

/* "not-json", "not-object", ... (for logs and stats). */
const char *remote_drop_reason_name(remote_drop_reason r);

typedef enum remote_message_kind {
    REMOTE_MSG_ACK,
    REMOTE_MSG_MOVE,
    REMOTE_MSG_DOWN,
    REMOTE_MSG_UP,
    REMOTE_MSG_WHEEL,
    REMOTE_MSG_LEAVE,
    REMOTE_MSG_TOUCH,
    REMOTE_MSG_KEY,
    REMOTE_MSG_VIEW,
} remote_message_kind;

typedef struct remote_touch_point {
    int id;      /* the page's touch slot, 0..INPUT_MAX_TOUCHES-1 */
    double x, y; /* fractions of the picture */
} remote_touch_point;

/* One parsed message; only the fields of its kind are set. */
typedef struct remote_message {
    remote_message_kind kind;
    uint64_t frame;  /* ACK */
    double x, y;     /* MOVE, DOWN, UP, WHEEL: fractions of the picture, [0, 1], x right, y down */
    int button;      /* DOWN, UP: 0 left, 1 middle, 2 right (DOM MouseEvent.button) */
    double dy;       /* WHEEL: clicks, > 0 towards the scene; finite, |dy| <= 100 */
    int touch_count; /* TOUCH: touches down now, 0..INPUT_MAX_TOUCHES, distinct ids */
    remote_touch_point touches[INPUT_MAX_TOUCHES];
    int ended_count; /* TOUCH: ids lifted in this frame, 0..INPUT_MAX_TOUCHES */
    int ended[INPUT_MAX_TOUCHES];
    bool cancel;       /* TOUCH: every touch ends without effect */
    int key_code;      /* KEY: evdev KEY_* */
    bool down;         /* KEY: pressed */
    bool private_view; /* VIEW */
} remote_message;

/* Parse one text message of `bytes` bytes (need not be NUL-terminated). True
 * with *out filled, else false with *reason. Never reads past text + bytes. */
bool remote_message_parse(const char *text, size_t bytes, remote_message *out, remote_drop_reason *reason);

/* DOM KeyboardEvent.code ("KeyW", "Digit0", "ArrowLeft", "Space", "Enter",
 * "Escape", "Backspace", "Tab", "Delete", "Home", "End", "PageUp", "PageDown",
 * "Comma", "Period", "Slash", "Minus", "Equal", "ShiftLeft", "ControlRight",
 * "AltLeft", "F1".."F12", ...) -> evdev KEY_*; -1 for a code without one. */
int remote_key_code(const char *dom_code);

/* A token bucket of REMOTE_RATE_BURST messages refilled at REMOTE_RATE_PER_S
 * on the caller's clock (microseconds, never decreasing). */
typedef struct remote_rate {
    double tokens;
    uint64_t last_us;
} remote_rate;
void remote_rate_init(remote_rate *r, uint64_t now_us);
/* Take one message's token: false (the message is over the rate) when none is left. */
bool remote_rate_take(remote_rate *r, uint64_t now_us);

/* What one viewer holds, so its messages become well-formed event runs. */
typedef struct remote_viewer_input {
    int slot;                            /* viewer slot, 0..INPUT_MAX_VIEWERS-1 */
    int device;                          /* REMOTE_DEVICE_BASE + slot */
    unsigned buttons_held;               /* bit b: DOM button b is down */
    bool touch_down[INPUT_MAX_TOUCHES];  /* by the page's touch id */
    bool pointer_shown;                  /* its INPUT_VIEWER_POINTER is shown */
} remote_viewer_input;
void remote_viewer_input_init(remote_viewer_input *v, int slot);

#define REMOTE_EVENTS_MAX (3 * INPUT_MAX_TOUCHES + 8) /* events one message can make */

/* The input events of message m (not ACK or VIEW: those make none) from
 * viewer v, whose picture shows `area` of the wall's plane (input/source.h
 * input_area_point maps its fractions), stamped time_us, into out[0 ..
 * REMOTE_EVENTS_MAX); returns how many. Frames are closed as event.h says:
 *   move   POINTER_ABS (only while a button is held), VIEWER_POINTER shown, FRAME
 *   down   POINTER_ABS, VIEWER_POINTER shown, BUTTON pressed (BTN_LEFT / BTN_MIDDLE /
 *          BTN_RIGHT), FRAME; a button already down: nothing
 *   up     POINTER_ABS, BUTTON released, FRAME; a button not down: nothing
 *   wheel  POINTER_ABS, SCROLL, FRAME
 *   leave  VIEWER_POINTER hidden, FRAME (nothing if hidden already)
 *   touch  cancel: TOUCH_CANCEL, TOUCH_FRAME (every touch forgotten); else TOUCH_UP per
 *          ended id that is down, TOUCH_DOWN / TOUCH_MOTION per touch (down: not down
 *          before), TOUCH_FRAME; then the viewer pointer at the lowest id down (shown)
 *          or hidden when none is, closed by FRAME
 *   key    KEY, FRAME
 * remote_viewer_input_release: the events that let go of everything v holds
 * (its pointer hidden, then INPUT_DEVICE_REMOVED: the mapping layer releases
 * its buttons, touches and keys), for a viewer that went away. */
int remote_message_events(remote_viewer_input *v, const remote_message *m, const camera_window *area,
                          uint64_t time_us, input_event *out);
int remote_viewer_input_release(remote_viewer_input *v, uint64_t time_us, input_event *out);

/* The 32-byte little-endian frame header of docs/remote-protocol.md. */
void remote_frame_header(uint8_t out[REMOTE_FRAME_HEADER_BYTES], uint64_t frame, uint64_t camera_serial,
                         int width_px, int height_px, uint32_t jpeg_bytes);

#endif
