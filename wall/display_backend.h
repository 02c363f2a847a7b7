/* display_backend.h (wall) - every display backend the pipeline can hand
 * frames to, in one table: its name (--display, a config's display.name),
 * a line for --help, the options it takes, what it needs, and how it is made.
 * The commands read only this table, so a new backend is one entry of
 * display_backends[] (display_backend.c). */
#ifndef TESSERA_WALL_DISPLAY_BACKEND_H
#define TESSERA_WALL_DISPLAY_BACKEND_H

#include <stdbool.h>
#include <stddef.h>

#include "engine/render/display.h"
#include "engine/base/err.h"
#include "wall_config.h"

/* The options a backend takes (display_backend.options). */
enum {
    DISPLAY_OPTION_OUT = 1u << 0,  /* --out / display.out: a file pattern, required */
    DISPLAY_OPTION_CARD = 1u << 1, /* --card: the DRM card */
};

/* What a backend needs (display_backend.needs). */
enum {
    DISPLAY_NEEDS_OIIO = 1u << 0, /* writes images through OpenImageIO (wall/dump_oiio.cpp) */
    DISPLAY_NEEDS_CARD = 1u << 1, /* a DRM card and --wall: its displays are the wall's outputs, made by
                                     drm_wall_start (wall/drm.h) on the card, never one by one */
};

/* What a backend's displays are made from besides their size. */
typedef struct display_backend_args {
    const char *out_pattern; /* DISPLAY_OPTION_OUT: file pattern (dump_frame_path rules); else unused */
    bool sequence;           /* frame numbers in the file names */
    const bool *present;     /* a headless wall: the outputs this process drives (a wall of several
                                machines: cluster/); NULL: all. The stitched image needs them all */
} display_backend_args;

typedef struct display_backend {
    const char *name;  /* as --display and a config's display.name give it */
    const char *what;  /* one line for --help */
    unsigned options;  /* DISPLAY_OPTION_* it takes */
    unsigned needs;    /* DISPLAY_NEEDS_* */
    /* one channel's display; NULL with err. NULL for a DISPLAY_NEEDS_CARD backend */
    image_display *(*create)(const display_backend_args *a, tess_error *err);
    /* the displays of a headless wall's outputs (displays[i] for output i, sizes resolved), when
     * they are not one `create` each (dump also writes the stitched wall); NULL: one `create` each */
    bool (*create_wall)(const wall_config *w, const display_backend_args *a, image_display **displays,
                        tess_error *err);
} display_backend;

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

/* A display of the backend called `name` (any but a DISPLAY_NEEDS_CARD one), writing to
 * `out_pattern` if it takes --out. NULL with err naming an unknown name and the table's names. */
image_display *display_create(const char *name, const char *out_pattern, bool sequence, tess_error *err);

/* The displays of a headless wall's outputs with backend b (not DISPLAY_NEEDS_CARD): its
 * create_wall, else one `create` per output. False with err and every displays[i] NULL (what
 * was made is destroyed). */
bool display_backend_create_wall(const display_backend *b, const wall_config *w, const display_backend_args *a,
                                 image_display **displays, tess_error *err);

#endif
