/* wall_config.h (wall) - the wall configuration file (configs/walls/NAME.json):
 * which monitors (outputs) make up a display wall, their modes and rotations,
 * and where their active areas and bezels sit on ONE virtual image plane.
 *
 * COORDINATES. Millimetres on the wall; the origin is the top-left corner of
 * the wall's bounding box (active areas and bezels of all outputs), x grows to
 * the right and y downwards, as the viewer faces the wall. Every size and
 * position is "as mounted", i.e. after the panel's rotation.
 *
 * WALL FILE FORMAT (docs/wall-format.md holds the same reference)
 *
 * One JSON object, read as strictly as scene files (engine/base/json_read.h):
 * comments allowed, an unknown field or a key given twice is an error, numbers
 * finite and within float range.
 *
 *   "format": "tessera-wall"           required, exactly this (checked first)
 *   "version": 1                       required, exactly 1
 *   "units": "mm"                      required, exactly "mm"
 *   "outputs": [                       required, 1..WALL_MAX_OUTPUTS
 *     {"connector": "HDMI-A-1",        required: DRM connector name TYPE-INDEX
 *                                      (letters, digits, '-'; ends in -N), 1..31 chars
 *      "edid": {"manufacturer": "DEL", optional object, at least one field; when
 *               "model": "U2415",      given it identifies the monitor and wins over
 *               "serial": "ABC123"},   the connector name. manufacturer: 3 letters
 *                                      A-Z (the EDID PNP id); model, serial: 1..63 chars
 *      "mode": "1920x1200@60",         "WxH", "WxH@HZ" (HZ may be fractional, 59.94)
 *                                      or "preferred" (the default). W, H are the
 *                                      pixels the monitor scans out, before rotation;
 *                                      1..32767. No HZ: any refresh rate
 *      "rotation": 0,                  0, 90, 180 or 270: degrees clockwise the panel
 *                                      is turned as the viewer sees it; default 0.
 *                                      90 and 270 swap the mode's W and H
 *      "grid": [column, row],          exactly one of grid, position_mm and
 *      "position_mm": [x, y],          position_px places the output; see below
 *      "position_px": [x, y],
 *      "size_mm": [width, height],     required: the ACTIVE area as mounted, 0.1..1e6
 *      "bezel_mm": {"left": 0, "top": 0, "right": 0, "bottom": 0}
 *                                      as mounted; each optional (default 0), >= 0
 *     }, ...
 *   ],
 *   "nodes": [                         optional: a wall of several machines (cluster/),
 *     {"rank": 0,                      one process each (mpirun -np N): exactly one of
 *      "host": "wall-a",               rank (0..WALL_MAX_OUTPUTS-1, the MPI rank) and host
 *                                      (the machine's host name, 1..63 chars; nodes on one
 *                                      host take its ranks in file order)
 *      "outputs": ["HDMI-A-1", ...]},  the outputs it drives, each by its connector name
 *     ...                              or by its index in "outputs" (needed when outputs
 *   ]                                  of several nodes share a connector name: each
 *                                      machine has its own DP-1). Each output is in
 *                                      exactly one node, a node has >= 1; connector
 *                                      names are unique within a node. Ranks given must
 *                                      be 0..count-1, each once.
 *
 * Placement (all give the top-left corner of the output's active area):
 *  - position_mm: [x, y] in wall millimetres (within +-1e6; see below).
 *  - position_px: [x, y] in wall pixels, where one wall pixel is this output's
 *    pixel as mounted: x_mm = x * width_mm / width_px and y_mm likewise, with
 *    width_px, height_px the mode's pixels after rotation. Needs an explicit mode.
 *  - grid: [column, row], integers 0..255. Every grid-placed output must have
 *    the same size_mm and bezel_mm as the first grid-placed one; the tile is
 *    tile_w = width + left + right and tile_h = height + top + bottom, and cell
 *    (c, r) puts the active area at (c * tile_w + left, r * tile_h + top).
 *    Grid and position_mm / position_px outputs may be mixed (same coordinates).
 * After reading, every output is shifted so that the bounding box of all the
 * tiles (active area plus bezels) starts at (0, 0); width_mm and height_mm of
 * the wall are that box's size.
 *
 * Checks made from the file alone (each message names the outputs involved):
 * 1..16 outputs; exactly one placement; the grid rule above; no two tiles
 * (active + bezels) overlapping by more than WALL_OVERLAP_TOLERANCE_MM in both
 * directions; no two outputs with the same connector name (of one node, when
 * the file has nodes), nor with the same
 * EDID identity (all three fields equal, an absent field equal only to an
 * absent one); with an explicit mode, |(w_mm / h_mm) / (w_px / h_px) - 1| <=
 * WALL_ASPECT_TOLERANCE using the mounted sizes (non-square pixels are refused).
 *
 * Messages are one line: "FILE: field 'outputs[2].bezel_mm.left': must be >= 0,
 * got -3". Checks that need a device (wall_config_match_device) or a headless
 * run (wall_config_headless_sizes) report "outputs[N]: ..." without the file
 * name, which the caller may add with tess_error_prefix. */
#ifndef TESSERA_WALL_CONFIG_H
#define TESSERA_WALL_CONFIG_H

#include <stdbool.h>
#include <stddef.h>

#include "engine/base/err.h"

#define WALL_MAX_OUTPUTS 16
#define WALL_CONNECTOR_BYTES 32      /* name up to 31 chars + NUL */
#define WALL_EDID_TEXT_BYTES 64      /* model / serial up to 63 chars + NUL */
#define WALL_OVERLAP_TOLERANCE_MM 0.01
#define WALL_ASPECT_TOLERANCE 0.02   /* relative difference of the aspects */
#define WALL_REFRESH_TOLERANCE_HZ 0.5

/* What identifies a monitor. An empty string is a field the file did not give. */
typedef struct wall_edid {
    bool given;                           /* the file had an "edid" object */
    char manufacturer[4];                 /* 3 letters A-Z, or "" */
    char model[WALL_EDID_TEXT_BYTES];
    char serial[WALL_EDID_TEXT_BYTES];
} wall_edid;

/* One monitor of the wall. Lengths in wall mm (see COORDINATES). */
typedef struct wall_output {
    char connector[WALL_CONNECTOR_BYTES];
    wall_edid edid;
    bool mode_preferred;                  /* "preferred": mode_* are 0 */
    int mode_w_px, mode_h_px;             /* as the monitor scans out (before rotation) */
    double mode_hz;                       /* 0 = any refresh rate */
    int rotation_deg;                     /* 0, 90, 180, 270 clockwise */
    double x_mm, y_mm;                    /* top-left of the active area, after normalisation */
    double width_mm, height_mm;           /* active area as mounted, > 0 */
    double bezel_left_mm, bezel_top_mm, bezel_right_mm, bezel_bottom_mm; /* as mounted, >= 0 */
    int width_px, height_px;              /* mounted pixel size once resolved, 0 until then */
    int device_connector, device_mode;    /* indices chosen by wall_config_match_device, -1 until then */
} wall_output;

#define WALL_HOST_BYTES 64

/* One machine of a wall of several (the file's "nodes"). */
typedef struct wall_node {
    int rank;                             /* the MPI rank, or -1: by host */
    char host[WALL_HOST_BYTES];           /* "" when by rank */
    bool outputs[WALL_MAX_OUTPUTS];       /* the outputs it drives */
} wall_node;

typedef struct wall_config {
    wall_output outputs[WALL_MAX_OUTPUTS];
    int count;                            /* 1..WALL_MAX_OUTPUTS */
    double width_mm, height_mm;           /* bounding box of all tiles (active + bezels) */
    wall_node nodes[WALL_MAX_OUTPUTS];    /* node_count of them; 0: one machine drives every output */
    int node_count;
} wall_config;

/* Which node of w the process of MPI rank `rank` (of `size`) on host `host`
 * is: the node naming that rank, else the k-th node naming this host where
 * k is how many lower ranks' hosts (hosts[0..rank)) are this host. -1 with
 * err when none is. hosts: every rank's host name (size of them). */
int wall_config_node_of(const wall_config *w, int rank, int size, const char *const *hosts, tess_error *err);

/* The name output i goes by in file names and messages: its connector, or
 * "nodeK-CONNECTOR" when outputs of several nodes share that connector name
 * (each machine has its own DP-1). Returns buf. */
#define WALL_LABEL_BYTES (WALL_CONNECTOR_BYTES + 8)
const char *wall_output_label(const wall_config *w, int i, char *buf, size_t bytes);

/* The outputs of w where mask[i], in order, as a wall of their own in *out
 * (one machine's part of a wall of several: what it matches to its card).
 * Sizes and places stay the whole wall's; out has no nodes. index_of[j]: the
 * index in w of out's output j. Returns out->count. */
int wall_config_subset(const wall_config *w, const bool *mask, wall_config *out, int *index_of);

/* Read and check a wall file; *out is fully written (zeroed on failure). */
bool wall_config_load(const char *file, wall_config *out, tess_error *err);

/* The same for `len` bytes of `text`; `name` only names it in messages. */
bool wall_config_parse(const char *name, const char *text, size_t len, wall_config *out, tess_error *err);

/* ---- resolving pixel sizes ----------------------------------------------- */

/* A mode a connector offers, as DRM lists it (scan-out pixels, before rotation). */
typedef struct wall_device_mode {
    int width_px, height_px;
    double refresh_hz;
} wall_device_mode;

/* What one connector of a DRM card offers. Strings may be NULL or "" (unknown). */
typedef struct wall_device_connector {
    const char *name;                     /* e.g. "HDMI-A-1" */
    bool connected;                       /* a monitor is attached */
    const char *edid_manufacturer, *edid_model, *edid_serial;
    const wall_device_mode *modes;
    size_t mode_count;
    int preferred;                        /* index into modes, -1 if none is marked */
    int user_defined;                     /* index of a mode the user added (kernel video=), -1 if none */
} wall_device_connector;

/* Pick for every output the connector of conns[0..n) that drives it and its
 * mode, filling device_connector, device_mode, width_px and height_px.
 * Connector: with an edid, the one connected connector whose EDID has every
 * given field equal (the name is then ignored); else the connector of that
 * name, which must be connected. Mode: an explicit one needs exact W and H and,
 * when HZ was given, a refresh within WALL_REFRESH_TOLERANCE_HZ (the closest;
 * without HZ the preferred mode if it fits, else the highest refresh);
 * "preferred" takes the connector's preferred mode, else the user-defined one
 * (video= on the kernel command line), else the largest (area, then refresh),
 * and must then pass the aspect check too. Fails with e.g.
 *   "outputs[1]: connector 'HDMI-A-3' not found (the card has: HDMI-A-1, DP-1)"
 *   "outputs[0]: mode 2560x1440@60 not offered by HDMI-A-1 (it offers: 1920x1080@60, ...)"
 * and when two outputs resolve to one connector. On failure the outputs' resolved
 * fields are left unresolved (-1 / 0). */
bool wall_config_match_device(wall_config *w, const wall_device_connector *conns, size_t n, tess_error *err);

/* ---- hotplug ----------------------------------------------------------------
 * After a connector-change event the card's connectors are read again and each
 * output of a running wall (matched before by wall_config_match_device: its
 * pixel size is fixed for the run) gets one step: */
typedef enum wall_hotplug_action {
    WALL_HOTPLUG_KEEP, /* stays as it is: driven, or dark (reason says why it cannot come back) */
    WALL_HOTPLUG_GONE, /* was driven; its monitor is unplugged, or moved: stop driving it */
    WALL_HOTPLUG_BACK, /* was dark; its monitor is there again: drive it on `connector` in `mode` */
} wall_hotplug_action;

typedef struct wall_hotplug_step {
    wall_hotplug_action action;
    int connector, mode;  /* BACK: indices into the new conns and that connector's modes */
    tess_error reason;    /* GONE, or KEEP of a dark output: why, naming the output and connector */
} wall_hotplug_step;

/* Plan the steps for every output of w. live[i]: output i is driven now;
 * driving[i]: the index in conns of the connector driving it (-1 when dark, or
 * when its connector is no longer listed). An output is GONE when it would no
 * longer match (wall_config_match_device's rules: unplugged, EDID elsewhere,
 * connector vanished) or matches a different connector than the one driving
 * it; a dark output comes BACK when it matches a connector no other output
 * keeps, in a mode of the size the wall started with (else it stays dark with
 * the reason). A monitor that moved connectors takes two plans: GONE, then
 * BACK once the caller has applied the first. Pure: no device involved, so
 * tests feed recorded connector states. */
void wall_hotplug_plan(const wall_config *w, const bool *live, const int *driving, const wall_device_connector *conns,
                       size_t n, wall_hotplug_step *steps);

/* Without a device: width_px, height_px from each explicit mode (rotated).
 * Fails for "preferred" with "outputs[1] (Virtual-2): mode 'preferred' needs a
 * device; give an explicit mode such as 1920x1080 for headless runs". */
bool wall_config_headless_sizes(wall_config *w, tess_error *err);

#endif
