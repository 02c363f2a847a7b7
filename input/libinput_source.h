/* libinput_source.h - libinput devices as an input source (source.h).
 *
 * Devices: libinput's udev backend on a seat (default "seat0": every input
 * device udev gives that seat, added and removed while running), or, when
 * device paths are given, the path backend with exactly those (a path that
 * is missing or vanished is tried again every second, on dispatch). Device
 * nodes are opened through the seat (seat/session.h) when there is one, else
 * directly.
 *
 * Placement on the plane (event.h): an absolute device (touchscreen, tablet
 * or absolute pointer) covers the output a rule names (matched by the
 * device's name or its /dev/input node), else the whole plane; relative
 * pointer motion is scaled by the plane's pixels per plane unit. Key and
 * button codes are evdev's. */
#ifndef TESSERA_INPUT_LIBINPUT_SOURCE_H
#define TESSERA_INPUT_LIBINPUT_SOURCE_H

#include "engine/base/err.h"
#include "source.h"

struct session;

#define INPUT_NAME_BYTES 128
#define INPUT_MAX_RULES 16
#define INPUT_MAX_PATHS 16

/* An absolute device (by name or node) covers an output (by name). */
typedef struct input_device_rule {
    char device[INPUT_NAME_BYTES];
    char output[32];
} input_device_rule;

typedef struct input_libinput_config {
    char seat[64];                                /* udev backend; "" = "seat0" */
    char paths[INPUT_MAX_PATHS][INPUT_NAME_BYTES]; /* path backend when path_count > 0 */
    int path_count;
    double px_per_unit_x, px_per_unit_y;          /* plane pixels per plane unit (relative motion) */
    input_output_area outputs[INPUT_MAX_OUTPUTS];
    int output_count;
    input_device_rule rules[INPUT_MAX_RULES];
    int rule_count;
} input_libinput_config;

/* The source; `sn` (NULL: none) opens the device nodes and must outlive it.
 * NULL with err (libinput or udev unavailable, a rule naming an unknown output). */
input_source *input_libinput_open(const input_libinput_config *cfg, struct session *sn, tess_error *err);

#endif
