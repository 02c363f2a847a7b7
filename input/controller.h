/* controller.h - the mapping layer: input events (event.h) in, input
 * transactions out. It holds what a person is doing (buttons held, fingers
 * down, keys held, the cursor, the idle clock) and the camera it is steering,
 * and says what should change as input_txn records; the embedding
 * (input/sink.h) turns each into a pipeline transaction and records it.
 * Nothing here touches renderer state, a pipeline or a device: tests drive it
 * with synthetic events and a synthetic clock.
 *
 * WHAT IT DOES (bindings.h names the actions; the defaults in brackets):
 *  - a button bound to a drag action [left: orbit, right: pan, middle:
 *    plane-push (CUTTING PLANES below)] picks
 *    the point under the cursor when pressed (the pick callback: a ray into
 *    the scene; on a miss the point on the cursor ray at the view distance)
 *    and drags about it: orbit turns about the point, pan keeps the point
 *    under the cursor, dolly scales the view about it. Released without
 *    moving: the "click" gesture [pick];
 *  - wheel [dolly]: towards the point under the cursor, x0.85 per click;
 *  - keys: flight while held at a speed that scales with the scene (its
 *    bounding-box diagonal / 4 per second by default), speed x / 1.5, home
 *    (flies back to the home view), pick / hide / fly-to at the cursor, and
 *    the part commands below;
 *  - touch: one finger [orbit] about the point it landed on; two fingers:
 *    the spread [dolly by the spread's ratio about the point between them,
 *    so a pinch's effect depends only on how much the spread changed, never
 *    on its size or the scene's scale] and the centre's motion [pan]; a tap
 *    [pick], a double tap [fly-to the tapped point], a long press (one
 *    finger down INPUT_LONG_PRESS_S on the events' clock without leaving the
 *    tap slop) [selects the part under it, then isolate], a two-finger tap
 *    [show-all];
 *  - touchpad gestures: pinch [dolly by libinput's scale about the cursor's
 *    point], swipe [pan];
 *  - PARTS (input_part: a part's subtree as an instance range, from the
 *    pick callback). The SELECTION is the last part picked (pick, isolate at
 *    the cursor, a long press) or widened to its parent (select-parent, up
 *    the ancestors the pick reported). hide-object hides the part under the
 *    cursor (remembered, up to INPUT_HIDDEN_MAX, for `show`: the last hidden
 *    one shown again); isolate shows only the selection (nothing selected:
 *    the part under the cursor, which it selects); show-all shows every
 *    part (and forgets the hidden ones); highlight toggles the highlight of
 *    the selection, which then follows the selection as it changes. Each
 *    says what it did in the status line ("hidden: PATH", "isolated: PATH
 *    (N instances)", "selected: PATH (N instances)", "all parts shown");
 *  - OPACITY. opacity-down / -up step the global opacity by 1 /
 *    INPUT_OPACITY_STEPS on the grid of those steps (from a value off the
 *    grid, to the nearest grid value beyond it), clamped to [0, 1], as an
 *    "opacity all A" record; part-opacity-down / -up do the same for the
 *    selection ("opacity FIRST COUNT A", the whole range at once), stepping
 *    from the value input last set for that range, else for the innermost
 *    range it set that holds it, else 1 (what input set is remembered for
 *    INPUT_OPACITY_PARTS ranges, the oldest forgotten first; a range set
 *    forgets the ranges inside it, which it overwrote). At a limit only the
 *    status line says so;
 *  - CUTTING PLANES (engine/accel/clip.h; "clip-plane" records). plane-place [C,
 *    three-finger tap] puts a plane through the point picked under the
 *    cursor with its normal the unit vector from that point towards the eye
 *    (computed in double, rounded once): it removes what lies between the
 *    camera and the point. It takes the lowest plane index that is off; with
 *    all CLIP_MAX_PLANES on, the selected plane's. The plane placed is the
 *    SELECTED PLANE; plane-next [N] selects the next plane that is on (in
 *    index order, wrapping); plane-flip [X] negates its normal;
 *    plane-remove [Delete] switches it off (its point and normal kept in the
 *    record) and selects the next plane on; plane-remove-all [End] switches
 *    every plane that is on off. plane-push [middle button] is a drag: the
 *    selected plane moves along its normal, INPUT_PLANE_PUSH_PER_UNIT scene
 *    sizes per plane unit of motion up (up: against its normal, deeper into
 *    what it cuts when it faces the camera), one record per input frame.
 *    The controller starts from the config's planes and opacity (what the
 *    pipeline starts from);
 *  - AMBIENT OCCLUSION. ambient-occlusion [O] steps the renderer through
 *    the cycle CONFIGURED -> "raytracer-ao" -> "ao" -> CONFIGURED, where
 *    CONFIGURED is the config's renderer (the one the pipeline starts with;
 *    "raytracer" when that is one of the two AO renderers or unset), as
 *    "renderer NAME" records; a renderer outside the cycle steps to
 *    raytracer-ao;
 *  - CROP. crop-down [,] and crop-up [.] move a window over the crop
 *    attribute of every particle set that has one (config `crops`, from the
 *    scene), one step of half a window (a window is INPUT_CROP_WINDOW of the
 *    attribute's range) down or up, clamped to the range; the first step
 *    from an inactive crop starts at the bottom (up) or the top (down) of the
 *    range. crop-off [/] shows every particle. "crop FIRST COUNT ON LO HI"
 *    records, one per set, and the window in the status line;
 *  - TIME STEPS. With a time series (config time_steps > 1): time-play
 *    [Space] plays or pauses, advancing one step every 1 / time_rate
 *    seconds (default INPUT_TIME_RATE steps/s), but only to a step the
 *    step_ready callback says is loaded: playing waits for the loader and
 *    never stalls a frame; time-back [9] and time-forward [0] step at once
 *    (wrapping); time-slower [7] and time-faster [8] divide or multiply the
 *    rate by 1.5. "time-step N" records, the step in the status line;
 *  - VALUES AND MAPS. value-down [T] and value-up [Y] step the scalar
 *    parameter (an iso-value) of every geometry that has one (config
 *    `values`) by INPUT_VALUE_STEPS of its range, clamped ("value FIRST
 *    COUNT V"); value-drag [side button, three fingers] is a drag: up raises every value,
 *    INPUT_VALUE_DRAG_PER_UNIT of its range per plane unit, the records
 *    coalesced to one per target an input frame; colormap-next [M] gives every geometry coloured through a
 *    map (config `maps`) the next built-in map or transfer function
 *    (colormap_names order, wrapping; "colormap FIRST COUNT NAME") and
 *    volumes rendered directly (config `media`) the next built-in transfer
 *    function, a built-in with opacity ("transfer NAME");
 *  - REMOTE VIEWERS' POINTERS: an INPUT_VIEWER_POINTER event (remote/) shows,
 *    moves or hides viewer `slot`'s pointer: at most one "pointer" record a
 *    slot an input frame. It counts as someone being there (the idle clock
 *    restarts), and moves neither the cursor nor the camera;
 *  - CAMERA HOLDER (two people at once, e.g. one at the wall and one on a
 *    tablet): the camera has one holder, a device. A device's camera motion
 *    (a drag, a touch gesture, the wheel, a touchpad gesture) takes the
 *    camera when nobody holds it; the holder keeps it while its drag lasts or
 *    a finger of it is down, and for INPUT_CAMERA_HOLD_S after its last
 *    camera motion. Meanwhile other devices' camera motions are dropped
 *    (their cursor and pointers still move; picks, hides, planes, opacity and
 *    other commands still apply). A holder whose device is removed (a viewer
 *    that left) lets go at once. After the hold ends, the next camera motion
 *    of any device takes the camera, also in the middle of a drag that
 *    started while it was held (its pivot is the one picked at its press).
 *    Animations (flight, fly-to, home, the tour) are not arbitrated: they
 *    were started by a key or a gesture that was;
 *  - PRIVATE VIEW (cfg.private_channel > 0: a remote viewer with a camera of
 *    its own, made by the runner for that viewer's device): the same
 *    gestures, keys and animations steer that channel's camera ("camera
 *    CHANNEL" records) and nothing else: it emits no cursor, status,
 *    pointer or scene record (hide, planes, opacity, time, ...: those act on
 *    what everybody sees, so they are the shared view's), has no tour and
 *    no camera holder to share with;
 *  - the quit chord (all its keys held together);
 *  - kiosk: after idle_timeout_s without input it starts the attract tour
 *    (TXN_TOUR on; the tour player eases into the path); the first
 *    event afterwards stops it (TOUR off) and steering starts from the
 *    camera the tour showed (the current_camera callback). With a tour it
 *    starts in tour mode (nobody is there yet).
 *
 * COALESCING. Camera changes accumulate while one input frame (up to
 * INPUT_FRAME or INPUT_TOUCH_FRAME) is handled and go out as at most one
 * TXN_CAMERA at its end; the same for the cursor. Animations (flight,
 * fly-to, home) advance in input_controller_tick, one camera per tick.
 *
 * Threading: one thread (the input thread) calls everything; the callbacks
 * run on it. */
#ifndef TESSERA_INPUT_CONTROLLER_H
#define TESSERA_INPUT_CONTROLLER_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "engine/accel/clip.h"
#include "engine/accel/geometry.h"
#include "engine/frame/txn.h"
#include "engine/base/vec3.h"
#include "bindings.h"
#include "event.h"

#define INPUT_TEXT_BYTES TXN_TEXT_BYTES /* status text, as PIPELINE_STATUS_BYTES */

/* What input asks the renderer to do: a transaction record (engine/frame/txn.h),
 * the same records the pipeline applies (pipeline_submit) and the record
 * file stores (input/record.h). The controller emits camera (always
 * TXN_ALL_CHANNELS: the wall's camera), cursor, status, hide, show and
 * isolate (a part's instance range: input_part), show-all, highlight,
 * governor-status, opacity, clip-plane, renderer, crop, time-step, value, colormap, and the
 * input-level tour and quit. */
typedef txn_record input_txn;
typedef txn_kind input_txn_kind;

#define INPUT_PART_LABEL_BYTES 128 /* a part's label with its NUL (a longer path keeps its tail: "...") */
#define INPUT_HIT_ANCESTORS 8      /* ancestors a pick reports (select-parent widens up to this many levels) */

/* A part as input acts on it: the instance ids of its whole subtree (a
 * scene's part tree numbers instances in preorder, so a subtree is one
 * range: engine/scene/scene.h, PARTS) and what the status line calls it. Without a
 * part tree every instance is its own part: (geom_id, 1). */
typedef struct input_part {
    uint32_t first, count;             /* instance ids [first, first + count); count >= 1 */
    char label[INPUT_PART_LABEL_BYTES]; /* the part's path ("assembly/section-2/frame-3/bracket-1"), or
                                          e.g. "mesh 0 'bunny'" / "the sphere set (6 spheres)" */
} input_part;

/* A pick: the first visible surface along a ray. */
typedef struct input_hit {
    bool hit;
    vec3 point;            /* world position of the hit */
    uint32_t geom_id, prim_id; /* geom_id: the instance hit */
    char what[128];        /* the primitive, for the status line: "part PATH triangle N", or
                              "mesh 0 'bunny' triangle 1234" */
    input_part part;       /* what hide, isolate and highlight act on: the hit instance's part and
                              everything under it (no part tree: that instance) */
    int ancestor_count;    /* 0..INPUT_HIT_ANCESTORS */
    input_part ancestors[INPUT_HIT_ANCESTORS]; /* the part's parent first, then its parent, ..., up to
                              the top-level part (the file's root is none); the nearest
                              INPUT_HIT_ANCESTORS when deeper */
} input_hit;

/* A particle set input may crop (a scene's "crop"): its instance range,
 * the crop attribute's name and range, and the crop it starts with. */
#define INPUT_CROP_MAX 8
#define INPUT_CROP_WINDOW 0.25f /* of the attribute's range: the window crop-up/-down start with */
typedef struct input_crop_target {
    uint32_t first, count;
    char attribute[GEOMETRY_ATTRIBUTE_NAME_BYTES];
    float min, max;    /* the attribute's values span [min, max] */
    geometry_crop crop; /* at start */
} input_crop_target;

/* A geometry input may step the scalar parameter of (an iso-value): its
 * instances, the value it starts with and the range to step over. */
#define INPUT_VALUE_MAX 8
#define INPUT_VALUE_STEPS 50.0 /* steps over a value's range */
/* value-drag: of a value's range per plane unit dragged; a drag across the
 * picture's height (2 units) sweeps the whole range. */
#define INPUT_VALUE_DRAG_PER_UNIT 0.5
typedef struct input_value_target {
    uint32_t first, count;
    float value, lo, hi;
} input_value_target;

/* A geometry coloured through a map input may change: its instances and
 * the map it starts with. */
#define INPUT_MAP_MAX 8
typedef struct input_map_target {
    uint32_t first, count;
    char name[TXN_NAME_BYTES];
} input_map_target;

typedef struct input_controller_config {
    input_bindings bindings;
    float plane_aspect;          /* the wall's image plane, width / height */
    camera_desc home;            /* the home view (the scene's camera); also the starting camera */
    double scene_size;           /* bounding-box diagonal in world units, > 0 */
    double fly_speed;            /* world units per second; 0: scene_size / 4 */
    double orbit_rad_per_unit;   /* orbit per plane unit of drag; 0: pi (a drag across the plane: a full turn) */
    double wheel_factor;         /* dolly per wheel click towards the scene; 0: 0.85 */
    double idle_timeout_s;       /* 0: no tour */
    bool have_tour;              /* a tour is configured (the tour player runs it) */
    double fly_to_s;             /* duration of fly-to and home animations; 0: 0.6 */
    float opacity;               /* the global opacity the pipeline starts with, [0, 1]; default 1 */
    clip_plane clip[CLIP_MAX_PLANES]; /* the planes it starts with (pipeline_config.clip); default all off */
    char renderer[TXN_NAME_BYTES]; /* the renderer the pipeline starts with; "" (default): raytracer */
    input_crop_target crops[INPUT_CROP_MAX]; /* particle sets with a crop attribute (CROP); crop_count of them */
    int crop_count;
    uint32_t time_steps;         /* steps of the longest time series (TIME STEPS); 0 or 1: none */
    input_value_target values[INPUT_VALUE_MAX]; /* VALUES AND MAPS; value_count of them */
    int value_count;
    input_map_target maps[INPUT_MAP_MAX];       /* map_count of them */
    int map_count;
    bool media;                  /* the scene renders volumes directly: colormap-next steps their transfer
                                    function too (the built-ins with opacity) */
    char transfer[TXN_NAME_BYTES]; /* the one they start with ("" or custom: the first built-in) */
    double time_rate;            /* steps per second while playing; 0: INPUT_TIME_RATE */
    int private_channel;         /* 0: the wall's controller; > 0: a PRIVATE VIEW's, steering that channel */
} input_controller_config;

/* Defaults for the fields a caller need not set (bindings = the defaults). */
void input_controller_config_default(input_controller_config *cfg);

typedef struct input_controller_hooks {
    void *ctx;
    /* The first visible surface along the ray (origin, unit dir); fills *out. */
    void (*pick)(void *ctx, vec3 origin, vec3 dir, input_hit *out);
    /* Queue one transaction (called in the order they must apply). */
    void (*emit)(void *ctx, const input_txn *t);
    /* The camera the wall shows now (asked when the tour hands over). */
    camera_desc (*current_camera)(void *ctx);
    /* Whether time step `step` can be shown without waiting (loaded); NULL:
     * always. Asking may start its load. */
    bool (*step_ready)(void *ctx, uint32_t step);
} input_controller_hooks;

typedef struct input_controller input_controller;

/* NULL when out of memory. The config is copied. */
input_controller *input_controller_create(const input_controller_config *cfg, const input_controller_hooks *hooks);
void input_controller_destroy(input_controller *c);

/* Handle one event (emits at frame ends). */
void input_controller_event(input_controller *c, const input_event *e);

/* Time passes (same clock as the events' time_us): advances flight and
 * fly-to animations, starts the tour when idle. Call at least every
 * input_controller_tick_interval_us while that is nonzero, and at the idle
 * deadline (input_controller_deadline_us). */
void input_controller_tick(input_controller *c, uint64_t now_us);

/* When tick must next be called: an absolute time_us, or UINT64_MAX when
 * nothing waits (no animation, no tour pending). */
uint64_t input_controller_deadline_us(const input_controller *c, uint64_t now_us);

/* Put the camera at `cam` at once (an animation stops) and emit it: a
 * private view starting from the wall's camera. */
void input_controller_jump(input_controller *c, camera_desc cam);

/* The camera the controller steers, the flight speed, whether touring. */
camera_desc input_controller_camera(const input_controller *c);
double input_controller_fly_speed(const input_controller *c);
bool input_controller_touring(const input_controller *c);

/* Time steps played per second unless the config says (TIME STEPS). */
#define INPUT_TIME_RATE 4.0

/* CAMERA HOLDER: how long the camera stays with a device after its last camera motion. */
#define INPUT_CAMERA_HOLD_S 0.5

/* Interval between animation ticks (about 60 Hz). */
#define INPUT_TICK_US 16000
/* A finger held this long without moving is a long press (iOS and Android
 * use 0.5 s; a little longer keeps a slow tap from turning into one). */
#define INPUT_LONG_PRESS_S 0.6
/* Hidden parts remembered for `show` (undo the last hide). */
#define INPUT_HIDDEN_MAX 32
/* Opacity steps from 0 to 1: 0.1 a key press, eleven levels a person can count. */
#define INPUT_OPACITY_STEPS 10
/* Part ranges whose opacity input remembers (part-opacity-down / -up). */
#define INPUT_OPACITY_PARTS 32
/* plane-push: scene sizes (bounding-box diagonals) per plane unit dragged; a drag across
 * the plane's height (2 units) moves the plane through the whole scene. */
#define INPUT_PLANE_PUSH_PER_UNIT 0.5

#endif
