/* source.h - libinput devices as input events (event.h) on the wall's image
 * plane.
 *
 * Devices: libinput's udev backend on a seat (default "seat0": every input
 * device udev gives that seat, added and removed while running), or, when
 * device paths are given, the path backend with exactly those (a path that
 * is missing or vanished is tried again every second). Device nodes are
 * opened through the seat (seat/session.h) when there is one, else directly.
 *
 * Placement on the plane (event.h): an absolute device (touchscreen, tablet
 * or absolute pointer) covers the output a rule names (matched by the
 * device's name or its /dev/input node), else the whole plane; relative
 * pointer motion is scaled by the plane's pixels per plane unit. Key and
 * button codes are evdev's.
 *
 * Threading: one thread (the input thread). */
#ifndef TESSERA_INPUT_SOURCE_H
#define TESSERA_INPUT_SOURCE_H

#include <stdbool.h>

#include "engine/camera.h"
#include "engine/err.h"
#include "input/event.h"

struct session;

#define INPUT_NAME_BYTES 128
#define INPUT_MAX_OUTPUTS 16
#define INPUT_MAX_RULES 16
#define INPUT_MAX_PATHS 16

/* One output of the wall: its name (connector) and where it is on the plane. */
typedef struct input_output_area {
    char name[32];
    camera_window window;
} input_output_area;

/* An absolute device (by name or node) covers an output (by name). */
typedef struct input_device_rule {
    char device[INPUT_NAME_BYTES];
    char output[32];
} input_device_rule;

typedef struct input_source_config {
    char seat[64];                                /* udev backend; "" = "seat0" */
    char paths[INPUT_MAX_PATHS][INPUT_NAME_BYTES]; /* path backend when path_count > 0 */
    int path_count;
    double px_per_unit_x, px_per_unit_y;          /* plane pixels per plane unit (relative motion) */
    input_output_area outputs[INPUT_MAX_OUTPUTS];
    int output_count;
    input_device_rule rules[INPUT_MAX_RULES];
    int rule_count;
} input_source_config;

typedef struct input_source input_source;

/* NULL with err (libinput or udev unavailable, a rule naming an unknown output). */
input_source *input_source_open(const input_source_config *cfg, struct session *sn, tess_error *err);
void input_source_close(input_source *s);

/* The fd to poll for readability. */
int input_source_fd(const input_source *s);

typedef void (*input_event_fn)(void *ctx, const input_event *e);

/* Read what libinput has and hand each event to fn (frames closed as event.h
 * says); retries missing path devices when due. False when libinput failed. */
bool input_source_dispatch(input_source *s, input_event_fn fn, void *ctx);

/* Where a device fraction (fx, fy) in [0, 1]^2, fx right and fy down as
 * libinput's transformed coordinates, lands on the plane when the device
 * covers `area` (an output's window). */
void input_area_point(const camera_window *area, double fx, double fy, double *sx, double *sy);

/* A VT switch: release every device (libinput_suspend), and take them back
 * when the seat is ours again (resume; retried by the caller on failure). */
void input_source_suspend(input_source *s);
void input_source_resume(input_source *s);
bool input_source_suspended(const input_source *s);

/* Devices currently open. */
int input_source_device_count(const input_source *s);

#endif
