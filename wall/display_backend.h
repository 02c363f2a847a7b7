/* display_backend.h (wall) - every display backend the pipeline can hand
 * frames to, in one table: its name (--display, a config's display.name),
 * a line for --help, the options it takes, what it needs, and how it is made.
 * The commands read only this table, so a new backend is one entry of
 * display_backends[] (display_backend.c) and its own file in wall/.
 *
 * Two kinds of backend:
 *   - headless (null, convert, dump, ...): `create` makes one channel's
 *     display, `create_wall` (optional) a headless wall's; `lifecycle` NULL.
 *   - on a device (drm): DISPLAY_NEEDS_DEVICE, `create` NULL, and a
 *     `lifecycle` (as wlroots' wlr_backend_impl): `start` opens the device
 *     (for drm the seat and the card), matches a wall's outputs to it and
 *     brings them up, returning a display_instance that owns all of it; the
 *     instance's hooks are set before pipeline_run; `destroy` after the
 *     pipeline is destroyed gives the device back as it was found.
 * The commands drive the second kind only through display_backend_start and
 * display_instance_* below, whatever the backend. */
#ifndef TESSERA_WALL_DISPLAY_BACKEND_H
#define TESSERA_WALL_DISPLAY_BACKEND_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "engine/render/display.h"
#include "engine/base/err.h"
#include "wall_config.h"

/* The options a backend takes (display_backend.options). */
enum {
    DISPLAY_OPTION_OUT = 1u << 0,  /* --out / display.out: a file pattern, required */
    DISPLAY_OPTION_CARD = 1u << 1, /* --card: the device to open (display_start_args.card_path) */
};

/* What a backend needs (display_backend.needs). */
enum {
    DISPLAY_NEEDS_OIIO = 1u << 0, /* writes images through OpenImageIO (wall/dump_oiio.cpp) */
    DISPLAY_NEEDS_DEVICE = 1u << 1, /* a device and --wall: its displays are the wall's outputs, made by its
                                       lifecycle's start on the device, never one by one. Exactly the
                                       backends with a lifecycle; the kiosk of `tessera run` (real time,
                                       until stopped, input on) */
};

/* What a backend's displays are made from besides their size. */
typedef struct display_backend_args {
    const char *out_pattern; /* DISPLAY_OPTION_OUT: file pattern (dump_frame_path rules); else unused */
    bool sequence;           /* frame numbers in the file names */
    const bool *present;     /* a headless wall: the outputs this process drives (a wall of several
                                machines: cluster/); NULL: all. The stitched image needs them all */
} display_backend_args;

struct pipeline;
struct session;
typedef struct display_backend display_backend;

/* A started backend on a device: what its lifecycle's start opened (drm: the
 * seat, the card, the outputs brought up), until display_instance_destroy.
 * Each backend's own state is a struct whose first member is this one (as
 * wlroots' private backends embed struct wlr_backend); only its backend's
 * lifecycle looks past it. */
typedef struct display_instance {
    const display_backend *backend; /* whose lifecycle made it: set by display_backend_start */
} display_instance;

/* What a lifecycle's start is given besides the wall. */
typedef struct display_start_args {
    const char *card_path; /* DISPLAY_OPTION_CARD: --card; NULL or "": the backend's own choice */
} display_start_args;

/* Told on the display thread while the outputs are paused because the seat took the device away
 * (a VT switch): paused true when the pause starts and then at least every 200 ms while it lasts,
 * false when the outputs go on. The frame loop waits meanwhile, healthy (a service watchdog is fed
 * from here: wall/service.h). */
typedef void (*display_pause_fn)(void *ctx, bool paused);

/* Told on the display thread of each output's completed flip: the frame now on screen, the
 * output's name, its vblank counter and the vblank's time (CLOCK_MONOTONIC us). */
typedef void (*display_flip_fn)(void *ctx, uint64_t frame, const char *output, unsigned vblank_sequence,
                                int64_t vblank_monotonic_us);

/* The operations of a backend on a device. Called on the main thread, before pipeline_run and after
 * it returns, except the hooks the instance calls. Every entry is set except where "optional". */
typedef struct display_lifecycle {
    /* Open the device and bring up every output of w (the outputs this process drives), matched to
     * the device, which resolves their sizes in *w; displays[0 .. w->count): their displays, which
     * refer to the instance (destroy them, the pipeline, before it). b: the row being started (a
     * backend may keep its own data beside it). NULL with err, and nothing is left open or changed. */
    display_instance *(*start)(const display_backend *b, const display_start_args *a, wall_config *w,
                               image_display **displays, tess_error *err);
    /* The pipeline whose channels first_channel .. + (start's w->count) are the outputs, so that the
     * instance can switch them off and on (hotplug). Optional. */
    void (*attach)(display_instance *d, struct pipeline *p, int first_channel);
    /* Set the pause hook (fn NULL: nobody is told). Optional: a device nobody takes away. */
    void (*set_pause_hook)(display_instance *d, display_pause_fn fn, void *ctx);
    /* Set the flip hook (fn NULL: nobody is told). Optional: no flip events. */
    void (*set_flip_hook)(display_instance *d, display_flip_fn fn, void *ctx);
    /* The seat start opened the device through: input opens its devices through the same one.
     * Optional (NULL: none). */
    struct session *(*seat)(const display_instance *d);
    /* Give the device back as it was found and free everything; after the displays are destroyed. */
    void (*destroy)(display_instance *d);
    /* Whether the device is there (the kiosk: `tessera run --wall` with no --display takes the
     * first backend whose device is there). Optional (NULL: never chosen by default). */
    bool (*device_present)(void);
    /* `tessera outputs`: list the devices and what they offer, for writing wall configs; returns
     * how many devices it listed. Optional. */
    int (*print_outputs)(FILE *f);
    const char *outputs_what; /* with print_outputs: what it lists, for the command's summary line */
    const char *outputs_help; /* with print_outputs: the same as whole lines for `tessera outputs --help` */
    const char *device_label; /* its kind of device in messages: "a <label> wall", "a <label> card" */
    const char *card_help;    /* DISPLAY_OPTION_CARD: --card's line in --help, after "--card PATH" */
    const char *kiosk_help;   /* device_present: how `tessera run --help` says the kiosk comes up (whole
                                 lines, after "The main job. ") */
} display_lifecycle;

struct display_backend {
    const char *name;  /* as --display and a config's display.name give it */
    const char *what;  /* one line for --help */
    unsigned options;  /* DISPLAY_OPTION_* it takes */
    unsigned needs;    /* DISPLAY_NEEDS_* */
    /* one channel's display; NULL with err. NULL for a DISPLAY_NEEDS_DEVICE backend */
    image_display *(*create)(const display_backend_args *a, tess_error *err);
    /* the displays of a headless wall's outputs (displays[i] for output i, sizes resolved), when
     * they are not one `create` each (dump also writes the stitched wall); NULL: one `create` each */
    bool (*create_wall)(const wall_config *w, const display_backend_args *a, image_display **displays,
                        tess_error *err);
    /* a backend on a device (DISPLAY_NEEDS_DEVICE); NULL for a headless one */
    const display_lifecycle *lifecycle;
};

/* The table, display_backend_count entries, at most DISPLAY_BACKENDS_MAX (checked at compile
 * time: callers size arrays of backends by it). */
#define DISPLAY_BACKENDS_MAX 16
extern const display_backend display_backends[];
extern const size_t display_backend_count;

/* The backend called `name`, or NULL. */
const display_backend *display_backend_by_name(const char *name);

/* The names of the backends that take every option in `options` (0: all of them), joined by
 * `separator`, into out (for messages; truncated to fit). */
void display_backend_names(unsigned options, const char *separator, char *out, size_t out_bytes);

/* A display of the backend called `name` (any but a DISPLAY_NEEDS_DEVICE one), writing to
 * `out_pattern` if it takes --out. NULL with err naming an unknown name and the table's names. */
image_display *display_create(const char *name, const char *out_pattern, bool sequence, tess_error *err);

/* The displays of a headless wall's outputs with backend b (not DISPLAY_NEEDS_DEVICE): its
 * create_wall, else one `create` per output. False with err and every displays[i] NULL (what
 * was made is destroyed). */
bool display_backend_create_wall(const display_backend *b, const wall_config *w, const display_backend_args *a,
                                 image_display **displays, tess_error *err);

/* The backend `tessera run --wall` uses when no display is given: the first of the table whose
 * lifecycle's device_present says its device is there; NULL: none (headless). */
const display_backend *display_backend_kiosk(void);

/* The first backend of the table with a device_present probe (whether or not its device is
 * there): the one help texts and messages describe as the kiosk's; NULL: none. */
const display_backend *display_backend_kiosk_kind(void);

/* `tessera outputs`: every backend's print_outputs in turn; how many devices they listed. */
int display_backends_print_outputs(FILE *f);

/* Start backend b (DISPLAY_NEEDS_DEVICE) on the wall w: the outputs this process drives
 * (present[i], NULL: all) are brought up by its lifecycle's start, which resolves their sizes;
 * the others' (a wall of several machines: cluster/) come from their explicit modes, as on their
 * machine, so that every process derives the same picture size. displays[i]: output i's, NULL for
 * another process's. NULL with err (naming the output or the device; a headless b, another
 * machine's output without an explicit mode), *w and displays[] then as they were. */
display_instance *display_backend_start(const display_backend *b, const display_start_args *a, const bool *present,
                                        wall_config *w, image_display **displays, tess_error *err);

/* What the backend offers, through the instance (NULL d: nothing happens). The channels of the
 * outputs start made (display_backend_start) are first_channel onward, in output order. */
void display_instance_attach(display_instance *d, struct pipeline *p, int first_channel);
/* Whether the backend has the hook (then it is set); false for NULL d. */
bool display_instance_set_pause_hook(display_instance *d, display_pause_fn fn, void *ctx);
bool display_instance_set_flip_hook(display_instance *d, display_flip_fn fn, void *ctx);
/* The seat the device was opened through, or NULL (none, or NULL d). */
struct session *display_instance_seat(const display_instance *d);
/* Give the device back; after the pipeline (its displays) is destroyed. NULL is fine. */
void display_instance_destroy(display_instance *d);

#endif
