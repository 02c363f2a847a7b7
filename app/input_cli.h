/* input_cli.h - the command line's side of input: options and the "input"
 * section of a pipeline config, and starting the input thread (input/runner.h),
 * the transaction sink with its tour (input/sink.h), recording and replay for
 * a pipeline the commands made. */
#ifndef TESSERA_CLI_INPUT_H
#define TESSERA_CLI_INPUT_H

#include <stdbool.h>
#include <stdio.h>

#include "cli.h"
#include "engine/frame/camera_path.h"
#include "engine/base/json_read.h"
#include "engine/frame/pipeline.h"
#include "input/bindings.h"
#include "input/sink.h"
#include "input/libinput_source.h"

#define CLI_INPUT_PATH_BYTES 4096

typedef struct cli_input_spec {
    int enabled;                 /* -1: the command's default, 0 off, 1 on */
    char bindings_file[CLI_INPUT_PATH_BYTES]; /* "" = the built-in bindings (configs/bindings.json) */
    char seat[64];               /* "" = seat0 */
    char devices[INPUT_MAX_PATHS][INPUT_NAME_BYTES]; /* the path backend with these, else udev */
    int device_count;
    input_device_rule map[INPUT_MAX_RULES]; /* absolute device -> output */
    int map_count;
    double idle_timeout_s;       /* before the tour starts; 0: never */
    char tour_file[CLI_INPUT_PATH_BYTES]; /* "" = the pipeline's --path, if any */
    double tour_ease_s;
    char record_file[CLI_INPUT_PATH_BYTES];
    char replay_file[CLI_INPUT_PATH_BYTES];
    input_replay_speed replay_speed;
    bool replay_speed_given;
    bool replay_strict;          /* render: a replayed record the pipeline would refuse is an error of the
                                  * run (checked before the first frame); run: logged and counted */
    bool enabled_from_config;    /* enabled came from a config's input.enabled (for messages) */
    bool devices_from_cmdline, map_from_cmdline; /* the command line's lists replace the config's */
} cli_input_spec;

/* Input off unless asked, bindings built in, seat0, idle timeout 60 s, tour ease 2 s. */
void cli_input_spec_default(cli_input_spec *s);

/* Like cli_pipeline_option, for the input options. */
bool cli_input_option(int argc, char **argv, int *i, cli_input_spec *s, bool *handled);

/* The "input" member of a pipeline config (the current field of c is the
 * config's top level); relative paths are resolved against config_file. */
bool cli_input_config_load(jr_ctx *c, json_object *root, const char *config_file, cli_input_spec *s);

void cli_input_usage(FILE *f);

/* The files input reads, read once before the scene loads (so a bad one
 * stops the run early) and handed to cli_input_start. */
typedef struct cli_input_files {
    bool have_bindings;          /* --bindings given: `bindings` holds it, else the built-in ones */
    input_bindings bindings;
    camera_path tour;            /* --tour, else the pipeline's --path; empty: none given */
} cli_input_files;

/* Read the bindings and tour files (with input on) into *files, and say
 * which settings input off ignores. False after printing the error. */
bool cli_input_load_files(const cli_input_spec *s, const char *tour_path, cli_input_files *files);
void cli_input_files_free(cli_input_files *files);

/* Whether the spec needs anything started for a pipeline. */
bool cli_input_wanted(const cli_input_spec *s);

typedef struct cli_input cli_input;

/* Before pipeline_run: the sink (tour, recording), replay, and with
 * s->enabled == 1 the input thread on the devices, opened through `seat`
 * (the one the outputs' device was opened through: display_instance_seat;
 * NULL: none, as input_libinput_open takes it), with the files read by
 * cli_input_load_files (their tour is taken over: files->tour is left empty).
 * NULL after printing the error. */
struct session;
cli_input *cli_input_start(const cli_input_spec *s, pipeline *p, const cli_scene *cs, cli_input_files *files,
                           struct session *seat);

/* The sink input's transactions go through (for an embedding: cli_run_hooks). */
input_sink *cli_input_sink(cli_input *in);

/* After pipeline_run: stops the input thread, reports, frees. NULL is fine. */
void cli_input_finish(cli_input *in);

#endif
