/* txn.h - transactions as tagged data records: a kind and its arguments.
 *
 * Every change of what a frame shows between frames (engine/scene/frame_state.h)
 * is one of these records, so it can be queued (pipeline_submit), recorded
 * to a file and replayed (input/record.h uses the text form below), and
 * later broadcast to other processes (the binary form below). A record
 * holds its arguments by value: no pointers, so a copy is the record.
 *
 * KINDS. Each kind has a name (the text form's first word), a validation
 * that needs no scene (txn_validate: ranges, finiteness, a NUL-terminated
 * text, a renderer that exists; errors name the field), and an apply that
 * edits a frame state (txn_apply; it checks what needs the scene: geometry
 * ids against the state's geometry count, channels against its channels).
 * Geometry arguments are a RANGE of ids [first, first + count): a part whose
 * instances have contiguous ids is hidden by one record; one geometry is
 * count 1. count is >= 1 and the range does not wrap past UINT32_MAX.
 *
 *   kind             arguments                     effect on the frame state
 *   camera           channel (or TXN_ALL_CHANNELS: a channel's camera, or the wall's (every
 *                    the wall), camera_desc           channel's but the private ones': frame_state.h)
 *   cursor           on, sx, sy (finite)           the cursor at plane point (sx, sy), or hidden
 *   pointer          slot (0..TXN_POINTERS-1), on, remote viewer `slot`'s pointer at plane point
 *                    sx, sy (finite)               (sx, sy) in the viewer's colour, or hidden
 *   status           text (NUL-terminated)         the status line ("" hides it)
 *   governor-status  on                            the governor's line shown after the status
 *   hide / show      first, count                  those geometries hidden / shown again
 *   isolate          first, count                  only those shown, every other one hidden
 *   show-all         -                             every geometry shown
 *   highlight        first, count, on              highlight flag of those geometries
 *   colour           first, count, reset | rgb     colour override (linear RGB, finite, >= 0)
 *                                                  of those geometries, or the override removed
 *   move             first, count, m[12]           those instances placed by the row-major 3x4
 *                                                  affine m (finite, invertible) applied after
 *                                                  their own placement: relative to where the
 *                                                  scene put them, never cumulative (the
 *                                                  identity puts them back)
 *   opacity          all | first, count; a         the global opacity, or those parts' opacity
 *                    (finite, in [0, 1])           (frame_state.h, OPACITY: 1 opaque, 0 see-through)
 *   clip-plane       index (0..TXN_CLIP_PLANES-1), cutting plane `index` (clip.h) set, and
 *                    on, point (finite), normal    switched on or off; apply stores the normal
 *                    (finite, length > 0)          normalised: each component n / |n| computed in
 *                                                  double and rounded once to float (a record
 *                                                  holds any nonzero normal, the state a unit one;
 *                                                  an off plane keeps its place to come back to)
 *   crop             first, count, on, lo, hi      the particles of those instances' geometries
 *                    (finite, lo <= hi)            seen only where their crop attribute lies in
 *                                                  [lo, hi] (on), or all of them (off); kinds
 *                                                  without a crop ignore it
 *   value            first, count, v (finite)      those geometries' scalar parameter (an
 *                                                  iso-value: geometry_ops.set_value)
 *   colormap         first, count, name            those geometries' colour map or transfer
 *                                                  function: a built-in (colormap.h), range kept
 *   transfer         name                          every volume rendered directly (scene media)
 *                                                  takes the built-in transfer function `name`
 *                                                  (colormap.h, one with opacity points)
 *   time-step        step                          every time series shows that step (modulo its
 *                                                  own count); waits at the barrier for a step
 *                                                  not loaded yet (input asks only for ready ones)
 *   shadows          on                            shadow rays traced or not
 *   renderer         name                          the renderer (renderer_by_name)
 *   threads          count (1..TXN_MAX_THREADS)    render threads
 *   channel-active   channel, on                   a channel rendered and displayed, or not
 *   tour             on                            INPUT-LEVEL: the attract tour (input/sink.c)
 *   quit             -                             INPUT-LEVEL: stop the pipeline (input/sink.c)
 * The two input-level kinds are records so that they are recorded and
 * replayed with the rest, but they are no frame state: the input sink
 * carries them out (the tour is a serial animation of the sink; quit stops
 * the loop); txn_apply and pipeline_submit refuse them.
 *
 * TEXT FORM (one line, no newline; what the record file stores after the
 * time): the kind's name, then its arguments separated by single spaces.
 * Floats in C99 hexadecimal (%a), so a text round trip is bit-exact;
 * decoding also takes decimal numbers but refuses one that is not exactly a
 * float. Flags are 0 or 1; channels a decimal number or "all"; texts in
 * double quotes with \" \\ and \xHH escapes (bytes outside 32..126 are
 * written as \xHH).
 *   camera all|CH EX EY EZ LX LY LZ UX UY UZ FOV     cursor ON SX SY
 *   status "TEXT"          governor-status ON        hide FIRST COUNT
 *   show FIRST COUNT       isolate FIRST COUNT       show-all
 *   highlight FIRST COUNT ON                         colour FIRST COUNT R G B | colour FIRST COUNT reset
 *   shadows ON             renderer NAME             threads N
 *   channel-active CH ON   tour ON                   quit
 *   move FIRST COUNT M0 .. M11
 *   opacity all A | opacity FIRST COUNT A
 *   clip-plane I ON PX PY PZ NX NY NZ
 *   crop FIRST COUNT ON LO HI                        time-step N
 *   value FIRST COUNT V                              colormap FIRST COUNT NAME
 *   transfer NAME                                    pointer SLOT ON SX SY
 * TXN_TEXT_V1 decodes the older input-record lines (record format 1):
 * "camera EX..FOV" (no channel: the wall), "hide GEOM_ID" (count 1),
 * "unhide-all" (show-all), and only the kinds that format had.
 *
 * BINARY FORM (TXN_BINARY_BYTES bytes, fixed size, for broadcast): all
 * integers little-endian, floats as their IEEE-754 binary32 bit patterns
 * (little-endian u32), flags one byte 0 or 1, every byte not listed zero.
 *   offset 0   u32 kind (txn_kind's value)
 *   offset 4   the arguments:
 *     camera          i32 channel (-1: all), then f32 eye xyz, look_at xyz, up xyz, fov_deg
 *     cursor          u8 on, 3 zero bytes, f32 sx, f32 sy
 *     pointer         i32 slot, u8 on, 3 zero bytes, f32 sx, f32 sy
 *     status          TXN_TEXT_BYTES bytes: the text, NUL-padded
 *     renderer        TXN_NAME_BYTES bytes: the name, NUL-padded
 *     governor-status, shadows, tour: u8 on
 *     hide, show, isolate: u32 first, u32 count
 *     highlight       u32 first, u32 count, u8 on
 *     colour          u32 first, u32 count, u8 reset, 3 zero bytes, f32 r, g, b
 *     threads         i32 count
 *     channel-active  i32 channel, u8 on
 *     move            u32 first, u32 count, 12 x f32 m (row-major 3x4)
 *     opacity         u8 all, 3 zero bytes, u32 first, u32 count, f32 a (all: first and count 0)
 *     clip-plane      i32 index, u8 on, 3 zero bytes, f32 point xyz, f32 normal xyz
 *     crop            u32 first, u32 count, u8 on, 3 zero bytes, f32 lo, f32 hi
 *     time-step       u32 step
 *     value           u32 first, u32 count, f32 v
 *     colormap        u32 first, u32 count, TXN_NAME_BYTES bytes: the name, NUL-padded
 *     transfer        TXN_NAME_BYTES bytes: the name, NUL-padded
 *     show-all, quit  nothing
 * Decoding checks the kind, the zero bytes and then txn_validate. */
#ifndef TESSERA_TXN_H
#define TESSERA_TXN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "engine/base/err.h"

struct frame_state;

#define TXN_TEXT_BYTES 128        /* status text with its NUL (= PIPELINE_STATUS_BYTES) */
#define TXN_NAME_BYTES 32         /* renderer name with its NUL */
#define TXN_ALL_CHANNELS (-1)     /* camera: every channel (the wall's camera) */
#define TXN_CLIP_PLANES 8         /* = CLIP_MAX_PLANES (clip.h, not included: its ray.h names `hit`) */
#define TXN_MAX_CHANNELS 16       /* = PIPELINE_MAX_CHANNELS */
#define TXN_MAX_THREADS 256       /* = PIPELINE_MAX_THREADS */
#define TXN_POINTERS 8            /* remote viewers' pointers (= INPUT_MAX_VIEWERS, input/event.h) */
#define TXN_BINARY_BYTES (4 + TXN_TEXT_BYTES)
#define TXN_TEXT_MAX (48 + 4 * TXN_TEXT_BYTES) /* longest text form with its NUL (a status of escapes) */

/* The order of the first eight is record format 1's (input_txn_kind then).
 * New kinds go at the end (before TXN_KIND_COUNT): a kind's number is in
 * every binary record, so it never changes. */
typedef enum txn_kind {
    TXN_CAMERA,
    TXN_CURSOR,
    TXN_STATUS,
    TXN_HIDE,
    TXN_SHOW_ALL,
    TXN_TOUR,
    TXN_QUIT,
    TXN_GOVERNOR_STATUS,
    TXN_SHOW,
    TXN_ISOLATE,
    TXN_HIGHLIGHT,
    TXN_COLOUR,
    TXN_SHADOWS,
    TXN_RENDERER,
    TXN_THREADS,
    TXN_CHANNEL_ACTIVE,
    TXN_MOVE,
    TXN_OPACITY,
    TXN_CLIP_PLANE,
    TXN_CROP,
    TXN_TIME_STEP,
    TXN_VALUE,
    TXN_COLORMAP,
    TXN_TRANSFER,
    TXN_POINTER,
    TXN_KIND_COUNT
} txn_kind;

/* geometry ids [first, first + count) */
typedef struct txn_geoms {
    uint32_t first, count;
} txn_geoms;

typedef struct txn_record {
    txn_kind kind;
    union {
        struct {
            int32_t channel;    /* 0..channels-1, or TXN_ALL_CHANNELS */
            camera_desc camera;
        } camera;
        struct {
            bool on;
            float sx, sy;       /* plane point (camera.h screen coordinates) */
        } cursor;
        struct {
            char text[TXN_TEXT_BYTES];
        } status;
        struct {
            bool on;            /* governor-status, shadows, tour */
        } flag;
        txn_geoms geoms;        /* hide, show, isolate */
        struct {
            txn_geoms geoms;
            bool on;
        } highlight;
        struct {
            txn_geoms geoms;
            bool reset;         /* remove the override (rgb unused) */
            float rgb[3];       /* linear RGB */
        } colour;
        struct {
            char name[TXN_NAME_BYTES];
        } renderer;                 /* renderer, transfer */
        struct {
            txn_geoms geoms;
            float m[12];        /* row-major 3x4 affine, applied after each instance's placement */
        } move;
        struct {
            bool all;           /* the global opacity; geoms then zero */
            txn_geoms geoms;    /* the parts, when !all */
            float a;            /* opacity, [0, 1] */
        } opacity;
        struct {
            int32_t index;      /* 0..TXN_CLIP_PLANES-1 */
            bool on;
            float point[3];     /* world, finite */
            float normal[3];    /* world, finite, nonzero (the removed side; apply normalises) */
        } clip_plane;
        struct {
            txn_geoms geoms;    /* instances: their geometries' crop */
            bool on;
            float lo, hi;       /* finite, lo <= hi */
        } crop;
        struct {
            uint32_t step;
        } time_step;
        struct {
            txn_geoms geoms;
            float v;
        } value;
        struct {
            txn_geoms geoms;
            char name[TXN_NAME_BYTES];
        } colormap;
        struct {
            int32_t count;
        } threads;
        struct {
            int32_t channel;
            bool on;
        } channel;
        struct {
            int32_t slot;       /* 0..TXN_POINTERS-1: a remote viewer's */
            bool on;
            float sx, sy;       /* plane point (camera.h screen coordinates) */
        } pointer;
    } args;
} txn_record;

typedef enum txn_text_version {
    TXN_TEXT_V1 = 1, /* record format 1 (decoding only) */
    TXN_TEXT_V2 = 2, /* the current form */
} txn_text_version;

/* "camera", "show-all", ...; "?" for no kind. */
const char *txn_kind_name(txn_kind k);
/* The kind called `name` in text form `version`; false if none. */
bool txn_kind_from_name(const char *name, txn_text_version version, txn_kind *out);
/* tour and quit: carried out by the input sink, not by a frame state. */
bool txn_kind_input_level(txn_kind k);

/* Records built by their arguments (the rest zeroed, so two records of the
 * same change compare equal byte for byte). */
txn_record txn_camera(int channel, const camera_desc *c);
txn_record txn_cursor(bool on, float sx, float sy);
txn_record txn_pointer(int slot, bool on, float sx, float sy);
txn_record txn_status(const char *text); /* cut at TXN_TEXT_BYTES - 1 bytes; NULL: "" */
txn_record txn_flag(txn_kind kind, bool on); /* governor-status, shadows, tour */
txn_record txn_geoms_record(txn_kind kind, uint32_t first, uint32_t count); /* hide, show, isolate */
txn_record txn_highlight(uint32_t first, uint32_t count, bool on);
txn_record txn_colour(uint32_t first, uint32_t count, const float rgb[3]); /* rgb NULL: reset */
txn_record txn_move(uint32_t first, uint32_t count, const float m[12]);
txn_record txn_opacity_all(float a);
txn_record txn_opacity(uint32_t first, uint32_t count, float a);
txn_record txn_clip_plane(int index, bool on, const float point[3], const float normal[3]);
txn_record txn_crop(uint32_t first, uint32_t count, bool on, float lo, float hi);
txn_record txn_time_step(uint32_t step);
txn_record txn_value(uint32_t first, uint32_t count, float v);
txn_record txn_colormap(uint32_t first, uint32_t count, const char *name); /* cut at TXN_NAME_BYTES - 1 */
txn_record txn_renderer(const char *name);
txn_record txn_transfer(const char *name); /* cut at TXN_NAME_BYTES - 1 */
txn_record txn_threads(int count);
txn_record txn_channel_active(int channel, bool on);
txn_record txn_simple(txn_kind kind); /* show-all, quit */

/* The checks that need no scene; false with err naming the field. */
bool txn_validate(const txn_record *r, tess_error *err);

/* Set err to "KIND: instances F..L: the scene has N instances (ids 0..N-1)"
 * for g past count (geometry ids are what users see as instances: a part
 * covers a range of them); returns false. */
bool txn_range_error(const char *kind, const txn_geoms *g, uint32_t count, tess_error *err);

/* Validate and apply r to st (st->... as frame_state.h says); false with
 * err, st unchanged, for an invalid record, one out of st's range (a
 * geometry id past its geometry count, a channel it does not have), an
 * input-level kind, or no memory for a per-geometry array. */
bool txn_apply(const txn_record *r, struct frame_state *st, tess_error *err);

/* The text form into buf (at most TXN_TEXT_MAX bytes with the NUL); the
 * length, or 0 if it does not fit or r is invalid. */
size_t txn_encode_text(const txn_record *r, char *buf, size_t size);

/* Decode text[0..len) (one line without its newline); false with err
 * naming the field and the problem (no file or line: the caller adds them). */
bool txn_decode_text(const char *text, size_t len, txn_text_version version, txn_record *out, tess_error *err);

/* The binary form; encoding an invalid record fails (false). */
bool txn_encode_binary(const txn_record *r, unsigned char out[TXN_BINARY_BYTES]);
bool txn_decode_binary(const unsigned char in[TXN_BINARY_BYTES], txn_record *out, tess_error *err);

#endif
