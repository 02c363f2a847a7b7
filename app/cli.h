/* cli.h - the tessera command line: strict parsing of option values and the
 * commands. Every parse_* returns false after printing one line naming the
 * option, the value and what was expected. */
#ifndef TESSERA_CLI_H
#define TESSERA_CLI_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>

#include "engine/base/camera.h"

/* Largest image edge accepted, in pixels (a 16K wall output). */
#define CLI_MAX_IMAGE_EDGE_PX 16384

bool cli_parse_int(const char *option, const char *text, int min, int max, int *out);
/* A finite decimal number in [min, max]. */
bool cli_parse_double(const char *option, const char *text, double min, double max, double *out);
bool cli_parse_size(const char *option, const char *text, int *width_px, int *height_px);
bool cli_parse_camera(const char *option, const char *text, camera_desc *out);
/* A render scale in (0, 1] (engine/render/upscale.h): a fraction of two unsigned
 * decimal numbers ("3/4", "1/3") or one ("0.75", "1"); no signs, spaces or
 * exponents. */
bool cli_parse_scale(const char *option, const char *text, double *out);
/* The value after argv[*i] (advancing *i), or NULL with a message when missing. */
const char *cli_option_value(int argc, char **argv, int *i);
/* "tessera: SEVERITY: message" on stderr (the command line's own messages,
 * before and beside the logger); cli_error and cli_warn (option_check.h). */
void cli_say(const char *severity, const char *fmt, va_list ap) __attribute__((format(printf, 2, 0)));
void cli_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
double cli_now_s(void); /* monotonic seconds */
/* Busy CPU seconds of the whole machine since boot (user + nice + system + irq
 * + softirq + steal from /proc/stat); -1 when unreadable. With cli_own_cpu_s
 * (this process, all threads) it gives the CPU other programs took during a
 * measurement, for rejecting noisy runs. */
double cli_machine_busy_s(void);
double cli_own_cpu_s(void);
/* Median of n values (sorts them in place); 0 for n == 0. */
double cli_median(double *values, size_t n);
/* The q-quantile (0..1) of values[0 .. n), linear between order statistics
 * (sorts them; 0 for n = 0). */
double cli_quantile(double *values, size_t n, double q);

struct scene;
struct accel;

/* A loaded scene and its acceleration structure, as every command needs. */
typedef struct cli_scene {
    const char *name;      /* the path, or "(built-in default)", for messages */
    struct scene *scene;   /* owned */
    struct accel *accel;   /* owned */
    double load_s, build_s;
} cli_scene;

/* Load `scene_path` (NULL: the built-in scene) and build its accel with
 * `threads` threads; report sizes and times on stderr. On failure prints the
 * error and returns false (cli_scene_finish still frees what was made). */
bool cli_scene_prepare(const char *scene_path, int threads, cli_scene *out);
/* The same with load options (scene.h; NULL: none). */
struct scene_load_options;
bool cli_scene_prepare_with(const char *scene_path, const struct scene_load_options *opts, int threads,
                            cli_scene *out);
/* The camera: `given` (may be NULL), else the scene's, else the bounds framed
 * by the peer harness's rule for a W x H image; validated. */
bool cli_scene_camera(const cli_scene *cs, const camera_desc *given, int width_px, int height_px, camera_desc *out);
void cli_scene_finish(cli_scene *cs);

int cli_render(int argc, char **argv); /* tessera render ... */
int cli_run(int argc, char **argv);    /* tessera run ... */

struct pipeline;
struct cli_input;

/* `tessera run` embedded in another program (tests/soak: the kiosk under a
 * load of transactions): the same options, set-up, frame loop and teardown,
 * with callbacks on the thread that runs it. Either callback may be NULL. */
typedef struct cli_run_hooks {
    void *ctx;
    /* Everything is made (outputs, input, animations), pipeline_run comes
     * next; `in` is NULL without input. False: the run ends with exit code 1. */
    bool (*started)(void *ctx, struct pipeline *p, struct cli_input *in);
    /* pipeline_run has returned (`ran`: without an error); the input is still
     * there (its thread running) and the pipeline's stats are final. */
    void (*finished)(void *ctx, struct pipeline *p, struct cli_input *in, bool ran);
} cli_run_hooks;
int cli_run_with(int argc, char **argv, const cli_run_hooks *hooks);
int cli_trace(int argc, char **argv);  /* tessera trace ... (cmd_trace.c) */
int cli_bench(int argc, char **argv);  /* tessera bench ... (cmd_bench.c) */
int cli_bench_path(int argc, char **argv); /* tessera bench --path / --scaling (cmd_bench_path.c) */
int cli_bench_wall(int argc, char **argv); /* tessera bench --wall without --path / --scaling (cmd_bench_wall.c) */
int cli_compare(int argc, char **argv); /* tessera compare ... (cmd_compare.c) */
int cli_robust(int argc, char **argv);  /* tessera robust ... (cmd_robust.c) */
int cli_parts(int argc, char **argv);   /* tessera parts FILE ... (cmd_parts.c) */

#endif
