/* pipeline_cli.h - what the pipeline commands (run, render, bench --path,
 * bench --scaling) share: the pipeline's components chosen by name, from a
 * pipeline config file (--config FILE, docs/pipeline-config.md) and then the
 * command line, which overrides the file; and the camera-path animation and
 * recording callbacks. */
#ifndef TESSERA_CLI_PIPELINE_H
#define TESSERA_CLI_PIPELINE_H

#include <stdbool.h>
#include <stdio.h>

#include "cli.h"
#include "engine/frame/camera_path.h"
#include "engine/frame/pipeline.h"
#include "engine/render/upscale.h"
#include "input_cli.h"
#include "remote/remote.h"
#include "input/source.h"
#include "wall/display_backend.h"

#define CLI_PATTERN_BYTES 4096

/* One viewpoint: its size, camera and display. */
typedef struct cli_channel_spec {
    int width_px, height_px;
    bool have_camera;            /* else the scene's camera, else framed bounds */
    camera_desc camera;
    char display[16];            /* a name of wall/display_backend.h's table */
    char out[CLI_PATTERN_BYTES]; /* dump: file pattern */
} cli_channel_spec;

typedef struct cli_pipeline_spec {
    int threads;
    pipeline_time_mode time_mode;
    double rate_hz;              /* FIXED_RATE, and the path sample rate of bench --path */
    int frames;                  /* 0: until stopped */
    int tile_px;
    tile_order order;
    uint32_t order_seed;
    pixel_sampler sampler;
    const renderer *renderer;    /* renderer_by_name */
    bool shadows;
    /* channel 0 comes from the top-level options; a config's "channels" adds more */
    cli_channel_spec channels[PIPELINE_MAX_CHANNELS];
    int channel_count;           /* >= 1 */
    char path_file[CLI_PATTERN_BYTES];   /* camera path for channel 0, "" for none */
    char record_file[CLI_PATTERN_BYTES]; /* --record: write channel 0's camera changes, "" for none */
    char wall_file[CLI_PATTERN_BYTES];   /* --wall: the channels are a wall's outputs, "" for none */
    char card_path[CLI_PATTERN_BYTES];   /* --card: the device of a DISPLAY_OPTION_CARD backend, "" = its choice */
    bool display_given, frames_given, time_given; /* on the command line or in --config */
    cli_input_spec input;        /* --input ..., the config's "input" object */
    remote_config remote;        /* --remote ..., the config's "remote" object (port -1: none) */
    /* render --scale / --upscale (engine/render/upscale.h; pipeline.h, RENDER SCALE): every channel
     * renders at render_scale of its size, the same view, and the render threads upscale it
     * with `upscale`; 1 (nothing scaled) for the other commands */
    double render_scale;         /* (0, 1] */
    upscale_filter upscale;
    char render_scale_text[32];  /* as given ("3/4"), for messages; "1" by default */
    /* --budget-ms, --refine-k, --still-s (pipeline.h, GOVERNOR): budget 0 is no governor;
     * `upscale` is then its filter */
    double budget_ms;
    double sync_timeout_s;       /* --sync-timeout: mpirun, how long a process waits for the others (0: 10 s) */
    int input_rank;              /* --input-rank: mpirun, the rank that reads input and leads (default 0) */
    bool carry_on_node_loss;     /* --on-node-loss carry-on: mpirun, the others go on when a machine is lost */
    int refine_k;
    double still_s;
    /* inspection (the config's renderer.transparency, renderer.caps, renderer.ao, opacity,
     * cutting_planes; docs/pipeline-config.md): copied into the pipeline config as they are */
    render_settings settings;    /* render_settings_default(), then the config's */
    float opacity;               /* initial global opacity, [0, 1]; 1 */
    clip_plane clip[CLIP_MAX_PLANES]; /* initial planes, as pipeline_config.clip (unused: zeroed) */
    /* optional (NULL): put a display in front of each channel's display (not a wall's):
     * returns the display to add, owning `inner` (destroyed on failure, then NULL with err) */
    image_display *(*wrap_display)(void *ctx, int channel, image_display *inner, tess_error *err);
    void *wrap_ctx;
    /* optional (NULL): the backend of a --wall's outputs when it is not one of the table's (a test's
     * own, tests/test_display_backend.c); NULL: the table's called channels[0].display */
    const display_backend *wall_backend;
} cli_pipeline_spec;

/* Defaults for a command: one channel of 1280x720 with `display` writing to
 * `out`, threads = CPUs, real time at rate 30, 16-pixel row-order tiles,
 * single sample, Phong with shadows, the default render settings, opaque, no
 * cutting plane. */
void cli_pipeline_spec_default(cli_pipeline_spec *s, const char *display, const char *out);

/* Load --config FILE into s (only the fields it names). False after printing
 * the error (file, line or field, problem). */
bool cli_pipeline_config_load(const char *file, cli_pipeline_spec *s);
/* The same from `len` bytes of JSON text (need not be NUL-terminated): `file`
 * names the text in messages, and relative paths resolve from its directory. */
bool cli_pipeline_config_parse(const char *file, const char *text, size_t len, cli_pipeline_spec *s);

/* If argv[*i] is a pipeline option, parse it (advancing *i past its value)
 * and set *handled. False after printing an error for a bad value. */
bool cli_pipeline_option(int argc, char **argv, int *i, cli_pipeline_spec *s, bool *handled);

/* The --config value in argv, or NULL (read before the other options, so the
 * command line overrides the file whatever the order). */
const char *cli_pipeline_find_config(int argc, char **argv);

/* The option help shared by the commands, with the command's defaults of
 * --time and --rate (e.g. "fixed", "30"). */
void cli_pipeline_usage(FILE *f, const char *time_default, const char *rate_default);

/* The pipeline config the spec describes (threads, time, frames, components). */
pipeline_config cli_pipeline_config(const cli_pipeline_spec *s, const cli_scene *cs);

/* Make the pipeline: channels with their cameras (given, else the scene's,
 * else framed) and displays; with --wall, one channel per output of the wall
 * (each its window of the one camera's image plane) and, with the dump
 * display, per-output images beside the stitched wall image. With --wall and
 * a backend on a device (DISPLAY_NEEDS_DEVICE), *outputs is the started
 * backend (display_backend_start) and the pipeline is attached to it; else
 * NULL. The caller hands it to cli_pipeline_release_outputs after
 * pipeline_destroy. NULL after printing the error (*outputs NULL: released). */
pipeline *cli_pipeline_create(const cli_pipeline_spec *s, const cli_scene *cs, display_instance **outputs);

/* The image plane the pipeline's channels show: its aspect (width / height)
 * in *plane_aspect, and per channel its output's name (a wall: the
 * connector; else "channel-N") and window; returns the count (<= max). */
int cli_pipeline_layout(const pipeline *p, float *plane_aspect, input_output_area *areas, int max);

/* Release what cli_pipeline_create opened besides the pipeline: the started
 * backend (display_instance_destroy: the device as it was found; NULL is
 * fine) and the wall's layout. After pipeline_destroy. */
void cli_pipeline_release_outputs(display_instance *outputs);

/* Channel 0 follows a camera path: a serial animation callback sets the
 * camera at each frame's time (time_offset_s added). */
typedef struct cli_path_player {
    camera_path path;
    double time_offset_s;
    bool all_channels; /* a wall: every output shows the one camera */
} cli_path_player;
bool cli_path_player_start(pipeline *p, cli_path_player *player);

/* The default animation of `tessera run` and `bench --scaling`: channel 0's
 * eye orbits its look-at point about the vertical axis, one turn per
 * period_s of pipeline time, from the camera the channel has when started. */
#define CLI_ORBIT_PERIOD_S 2.0
typedef struct cli_orbit {
    camera_desc start;
    double period_s;
    bool all_channels; /* a wall: every output shows the one camera */
} cli_orbit;
bool cli_orbit_start(pipeline *p, cli_orbit *orbit, double period_s);

/* --record: every change of channel 0's camera becomes a key at its frame's
 * time; written (linear interpolation) when the pipeline terminates. */
typedef struct cli_recorder {
    camera_path path;
    uint64_t last_serial;
    bool started, failed;
    const char *file;
} cli_recorder;
bool cli_recorder_start(pipeline *p, cli_recorder *rec, const char *file);

/* Print the pipeline's counters as one line on stderr. */
void cli_pipeline_report(pipeline *p, const cli_pipeline_spec *s);

#endif
