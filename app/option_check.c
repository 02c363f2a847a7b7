/* option_check.c - options that do not apply are said (option_check.h). */
#include "option_check.h"

#include <stdarg.h>
#include <string.h>

#include "wall/display_backend.h"

void cli_given_add(cli_given *g, const char *name)
{
    if (g->count < CLI_GIVEN_MAX)
        g->names[g->count++] = name;
}

bool cli_given_has(const cli_given *g, const char *name)
{
    for (int i = 0; i < g->count; i++)
        if (!strcmp(g->names[i], name))
            return true;
    return false;
}

void cli_warn(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cli_say("warning", fmt, ap);
    va_end(ap);
}

/* The options that only steer live input (libinput), not a replay. */
static const char *const live_input_options[] = {"--bindings", "--seat", "--input-device", "--map-input",
                                                 "--idle-timeout", "--tour", NULL};

void cli_check_ignored_render_run(const cli_given *g, const cli_pipeline_spec *s, const char *command)
{
    const char *display = s->channels[0].display;
    const display_backend *backend = display_backend_by_name(display); /* checked when parsed */
    const display_backend *kiosk = display_backend_kiosk_kind(); /* whose wall turns input on by default */
    bool live_input = s->input.enabled == 1;
    if (s->wall_file[0] && cli_given_has(g, "--size"))
        cli_warn("--size is ignored with --wall (each output's size comes from the wall config)");
    char takers[128];
    if (!(backend->options & DISPLAY_OPTION_OUT) && cli_given_has(g, "--out")) {
        display_backend_names(DISPLAY_OPTION_OUT, " or ", takers, sizeof takers);
        cli_warn("--out is ignored with --display %s (only the %s display writes files)", display, takers);
    }
    if (s->time_mode == PIPELINE_TIME_REAL && cli_given_has(g, "--rate")) {
        bool kiosk_time = (backend->needs & DISPLAY_NEEDS_DEVICE) && !s->time_given;
        cli_warn("--rate is ignored in real time (it is the frame rate of --time fixed)%s%s%s",
                 kiosk_time ? "; the kiosk on a " : "", kiosk_time ? backend->lifecycle->device_label : "",
                 kiosk_time ? " card runs in real time" : "");
    }
    if (!(backend->options & DISPLAY_OPTION_CARD) && cli_given_has(g, "--card")) {
        display_backend_names(DISPLAY_OPTION_CARD, " or ", takers, sizeof takers);
        cli_warn("--card is ignored with --display %s (only the %s display drives a card)", display, takers);
    }
    if (s->path_file[0] && !live_input && !s->input.replay_file[0] && cli_given_has(g, "--camera"))
        cli_warn("--camera is ignored with --path (the path sets the camera from the first frame)");
    const bool governed = s->budget_ms > 0.0;
    if (!governed && s->render_scale >= 1.0 && cli_given_has(g, "--upscale"))
        cli_warn("--upscale is ignored at --scale 1 without --budget-ms (the image is rendered at full size: "
                 "nothing is upscaled)");
    if (!governed)
        for (const char *const *o = (const char *const[]){"--refine-k", "--still-s", NULL}; *o; o++)
            if (cli_given_has(g, *o))
                cli_warn("%s is ignored without --budget-ms (it steers the frame-budget governor)", *o);
    if (governed && s->sampler.kind != PIXEL_SAMPLER_SINGLE)
        cli_warn("--sampler %s: with --budget-ms only its seed is used (moving frames take one ray per pixel, "
                 "still ones converge to jittered:%d, --refine-k)",
                 s->sampler.kind == PIXEL_SAMPLER_JITTERED ? "jittered" : "?", s->refine_k);
    if (!s->input.replay_file[0] && cli_given_has(g, "--replay-speed"))
        cli_warn("--replay-speed is ignored without --replay-input");
    if (!live_input)
        for (const char *const *o = live_input_options; *o; o++)
            if (cli_given_has(g, *o)) {
                if (!strcmp(command, "render"))
                    cli_warn("%s is ignored: 'tessera %s' reads no input devices here (render never does; "
                             "'tessera run' can)", *o, command);
                else
                    cli_warn("%s is ignored: 'tessera %s' reads no input devices here (--input on, the default "
                             "on a %s wall, turns them on)", *o, command, kiosk ? kiosk->lifecycle->device_label
                                                                                : "device");
            }
}

bool cli_check_ignored_bench(const cli_given *g, const cli_pipeline_spec *s, const char *mode)
{
    (void)s;
    static const char *const input_options[] = {"--input", "--bindings", "--seat", "--input-device", "--map-input",
                                                "--idle-timeout", "--tour", "--record-input", "--replay-input",
                                                "--replay-speed", NULL};
    for (const char *const *o = input_options; *o; o++)
        if (cli_given_has(g, *o)) {
            cli_error("%s: not an option of bench %s (benchmarks read no input; 'tessera run' does)", *o, mode);
            return false;
        }
    /* what each mode sets itself */
    static const struct {
        const char *mode, *option, *why;
    } fixed[] = {
        {"--path", "--frames", "it renders until the path's transactions are done"},
        {"--path", "--time", "it runs in real time: frame times are what it measures"},
        {"--path", "--camera", "the path sets the camera"},
        {"--path", "--rounds", "--rounds is for --scaling"},
        {"--path", "--keep-noisy", "--keep-noisy is for --scaling"},
        {"--path", "--record", "it records nothing"},
        {"--scaling", "--time", "it runs in fixed-rate time: the same frames at every thread count"},
        {"--scaling", "--record", "it records nothing"},
    };
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        if (!strcmp(mode, fixed[i].mode) && cli_given_has(g, fixed[i].option)) {
            cli_error("%s: not an option of bench %s (%s)", fixed[i].option, mode, fixed[i].why);
            return false;
        }
    return true;
}
