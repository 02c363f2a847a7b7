/* source.h - an input source: something that turns what people do into
 * input events (event.h) on the wall's image plane. The input thread
 * (runner.h) polls every source's fd and dispatches the readable ones through
 * this interface alone, never by kind; a new source (a remote viewer) is a
 * new implementation of input_source_ops. The one today is libinput's
 * devices (libinput_source.h).
 *
 * A source placed on the plane maps a device fraction to plane coordinates
 * with input_area_point over the output it covers (input_output_area).
 *
 * Threading: a source is used by one thread at a time (the input thread
 * while it runs; the thread that made it before and after). */
#ifndef TESSERA_INPUT_SOURCE_H
#define TESSERA_INPUT_SOURCE_H

#include <stdbool.h>

#include "engine/base/camera.h"
#include "event.h"

#define INPUT_MAX_OUTPUTS 16
#define INPUT_MAX_SOURCES 4 /* sources one input thread polls */

/* One output of the wall: its name (connector) and where it is on the plane. */
typedef struct input_output_area {
    char name[48]; /* the output's label: "DP-1", or "node1-DP-1" on a wall of several machines */
    camera_window window;
} input_output_area;

/* Where a device fraction (fx, fy) in [0, 1]^2, fx right and fy down as
 * libinput's transformed coordinates, lands on the plane when the device
 * covers `area` (an output's window). */
void input_area_point(const camera_window *area, double fx, double fy, double *sx, double *sy);

typedef void (*input_event_fn)(void *ctx, const input_event *e);

typedef struct input_source input_source;

/* What a source does; every entry is set. */
typedef struct input_source_ops {
    const char *name; /* for messages: "libinput" */
    /* the fd to poll for readability */
    int (*fd)(const input_source *s);
    /* read what is there and hand each event to fn, frames closed as event.h says; also
     * called on every wake of the input thread (at least once a second) for the source's
     * own timers. False when the source failed for good: input stops */
    bool (*dispatch)(input_source *s, input_event_fn fn, void *ctx);
    /* a VT switch away: let go of the devices (idempotent) */
    void (*suspend)(input_source *s);
    /* the seat is ours again: take them back; on failure stays suspended and the caller
     * tries again on its next wake */
    void (*resume)(input_source *s);
    bool (*suspended)(const input_source *s);
    /* devices the source has open now (a source that is not devices: 1) */
    int (*device_count)(const input_source *s);
    void (*destroy)(input_source *s); /* frees s */
} input_source_ops;

/* Implementations embed this as their first member. */
struct input_source {
    const input_source_ops *ops;
};

static inline int input_source_fd(const input_source *s) { return s->ops->fd(s); }
static inline bool input_source_dispatch(input_source *s, input_event_fn fn, void *ctx)
{
    return s->ops->dispatch(s, fn, ctx);
}
static inline void input_source_suspend(input_source *s) { s->ops->suspend(s); }
static inline void input_source_resume(input_source *s) { s->ops->resume(s); }
static inline bool input_source_suspended(const input_source *s) { return s->ops->suspended(s); }
static inline int input_source_device_count(const input_source *s) { return s->ops->device_count(s); }
static inline void input_source_destroy(input_source *s)
{
    if (s)
        s->ops->destroy(s);
}

#endif
