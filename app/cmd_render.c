/* cmd_render.c - `tessera render` (headless frames of one camera) and
 * `tessera run` (the main job: with no device output it runs the pipeline with
 * the dump display into out/, the camera orbiting or following a path). Both
 * run the parallel pipeline (engine/frame/pipeline.h) with components chosen by
 * name (pipeline_cli.h). */
#include <errno.h>
#include <signal.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "engine/scene/accel.h"
#include "engine/scene/scene.h"
#include "option_check.h"
#include "pipeline_cli.h"
#include "cluster_cli.h"
#include "remote_cli.h"
#include "wall/display_backend.h"
#include "wall/dump.h"
#include "wall/service.h"

/* render's own option: --scale (engine/render/upscale.h; --upscale is a pipeline option). False
 * after an error for a bad value; *handled when argv[*i] was one. */
static bool render_scale_option(int argc, char **argv, int *i, cli_pipeline_spec *s, bool *handled)
{
    const char *a = argv[*i], *val;
    *handled = true;
    if (!strcmp(a, "--scale")) {
        if (!(val = cli_option_value(argc, argv, i)) || !cli_parse_scale(a, val, &s->render_scale))
            return false;
        snprintf(s->render_scale_text, sizeof s->render_scale_text, "%.*s", (int)sizeof s->render_scale_text - 1,
                 val);
        return true;
    }
    *handled = false;
    return true;
}

/* Parse the options both commands take (after loading --config), and with
 * `scale_options` render's --scale. Returns false when the
 * command should stop: after --help (*exit_code 0) or a bad option
 * (*exit_code 2). */
static bool parse_options(int argc, char **argv, cli_pipeline_spec *s, const char **scene_path,
                          void (*usage)(FILE *), int *exit_code, cli_given *given, bool scale_options)
{
    const char *config = cli_pipeline_find_config(argc, argv);
    if (config && !cli_pipeline_config_load(config, s))
        goto bad;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        bool handled;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            *exit_code = 0;
            return false;
        }
        cli_given_add(given, a);
        if (!cli_pipeline_option(argc, argv, &i, s, &handled))
            goto bad;
        if (handled)
            continue;
        if (scale_options && !render_scale_option(argc, argv, &i, s, &handled))
            goto bad;
        if (handled)
            continue;
        if (!strcmp(a, "--scene")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                goto bad;
            *scene_path = strcmp(val, "default") ? val : NULL;
        } else {
            cli_error("unknown option '%s' (see 'tessera %s --help')", a, argv[0]);
            goto bad;
        }
    }
    if (s->budget_ms > 0.0 && s->render_scale < 1.0) {
        cli_error("--scale %s and --budget-ms %g: choose one (with a budget the governor picks the scale)",
                  s->render_scale_text, s->budget_ms);
        goto bad;
    }
    return true;
bad:
    *exit_code = 2;
    return false;
}

/* Fail before rendering when the output directory is missing or read-only. */
static bool check_output_dir(const char *path)
{
    char copy[4096];
    snprintf(copy, sizeof copy, "%s", path);
    const char *dir = dirname(copy);
    struct stat st;
    if (stat(dir, &st) != 0) {
        cli_error("%s: cannot write: directory '%s' does not exist", path, dir);
        return false;
    }
    if (!S_ISDIR(st.st_mode)) {
        cli_error("%s: cannot write: '%s' is not a directory", path, dir);
        return false;
    }
    if (access(dir, W_OK) != 0) {
        cli_error("%s: cannot write: directory '%s' is not writable: %s", path, dir, strerror(errno));
        return false;
    }
    return true;
}

static bool check_outputs(const cli_pipeline_spec *s)
{
    for (int i = 0; i < s->channel_count; i++)
        if ((display_backend_by_name(s->channels[i].display)->options & DISPLAY_OPTION_OUT) &&
            !check_output_dir(s->channels[i].out))
            return false;
    return (!s->record_file[0] || check_output_dir(s->record_file)) &&
           (!s->input.record_file[0] || check_output_dir(s->input.record_file));
}

/* Options that cannot go together; false after printing why (exit 2). */
static bool check_option_conflicts(const cli_pipeline_spec *s)
{
    if (s->input.replay_file[0] && s->input.enabled != 1 && s->path_file[0]) {
        cli_error("--path and --replay-input both steer the camera: give one");
        return false;
    }
    return true;
}

/* The running pipeline, for SIGINT/SIGTERM: pipeline_stop only stores to a
 * lock-free atomic, which a signal handler may do. */
static pipeline *volatile signal_target;

static void stop_on_signal(int sig)
{
    (void)sig;
    pipeline *p = signal_target;
    if (p)
        pipeline_stop(p);
}

/* The callbacks of cli_run_with around the frame loop (NULL: none). Set
 * only for the duration of that call, on its thread. */
static const cli_run_hooks *run_hooks;

static void catch_stop_signals(pipeline *p)
{
    signal_target = p;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = p ? stop_on_signal : SIG_DFL;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

/* The wall paused for a VT switch: a healthy wait, the watchdog is fed (wall/service.h). */
static void wall_paused(void *ctx, bool paused)
{
    service_notifier_paused(ctx, paused ? "switched away from our VT, waiting for the seat" : NULL);
}

/* Run the pipeline for a command; `orbit` animates channel 0 when no path is
 * given; `service`: tell systemd how it goes (NULL when not started by it). */
static int run_job(cli_pipeline_spec *s, const char *scene_path, bool orbit, service_notifier *service)
{
    cli_input_files input_files; /* with input on, a --path is the tour */
    if (!cli_cluster_begin(s)) /* mpirun: this process's part of the wall (cluster_cli.h) */
        return 1;
    if (!check_outputs(s) || !cli_input_load_files(&s->input, s->input.enabled == 1 ? s->path_file : NULL,
                                                   &input_files))
        return 1;
    cli_scene cs;
    if (!cli_scene_prepare(scene_path, s->threads, &cs)) {
        cli_scene_finish(&cs);
        cli_input_files_free(&input_files);
        return 1;
    }
    int code = 1;
    cli_path_player player = {.time_offset_s = 0.0, .all_channels = false};
    cli_recorder recorder;
    cli_orbit orbit_state;
    cli_input *input = NULL;
    pipeline *p = NULL;
    display_instance *outputs = NULL; /* a wall on a device: the started backend (after p is destroyed) */
    tess_error err = {{0}};
    /* live input steers the camera (a --path becomes its idle tour); a replay steers it alone */
    bool steered = s->input.enabled == 1 || s->input.replay_file[0] || s->remote.port >= 0;
    if (!cli_cluster_agree(cs.accel)) /* the same scene, built the same way, on every machine */
        goto done;
    p = cli_pipeline_create(s, &cs, &outputs);
    if (!p)
        goto done;
    if (steered || cli_cluster_follower()) {
        /* the camera moves only by input transactions (and the tour), or by the leader's records */
    } else if (s->path_file[0]) {
        if (!camera_path_load(s->path_file, &player.path, &err)) {
            cli_error("%s", err.msg);
            goto done;
        }
        player.all_channels = s->wall_file[0] != '\0';
        cli_path_player_start(p, &player);
    } else if (orbit) {
        orbit_state.all_channels = s->wall_file[0] != '\0';
        cli_orbit_start(p, &orbit_state, CLI_ORBIT_PERIOD_S);
    }
    if (s->record_file[0])
        cli_recorder_start(p, &recorder, s->record_file);
    if (!service_notifier_attach(service, p, cli_remote_channel())) { /* -1: no remote view, every channel */
        cli_error("service notifier: too many pipeline callbacks");
        goto done;
    }
    if (service)
        display_instance_set_pause_hook(outputs, wall_paused, service);
    if (cli_input_wanted(&s->input) &&
        !(input = cli_input_start(&s->input, p, &cs, &input_files, display_instance_seat(outputs))))
        goto done;
    if (!cli_remote_start(p)) /* after input: viewers' events go to its runner */
        goto done;
    if (run_hooks && run_hooks->started && !run_hooks->started(run_hooks->ctx, p, input))
        goto done;
    if (!cli_cluster_attach(p, outputs)) /* last: the syncs meet the other processes from the first frame on */
        goto done;
    catch_stop_signals(p); /* the frame in flight is finished and shown, then outputs are restored */
    bool ran = pipeline_run(p, &err);
    catch_stop_signals(NULL);
    if (run_hooks && run_hooks->finished)
        run_hooks->finished(run_hooks->ctx, p, input, ran);
    cli_remote_stop(); /* before input: the view's source is the input runner's */
    cli_input_finish(input);
    input = NULL;
    if (!ran) /* e.g. the cluster's barrier before the flip timed out: its display sync's error */
        cli_error("%s", err.msg);
    if (cli_cluster_report()) { /* a process died or stopped answering: said above */
        code = 3;
        goto done;
    }
    if (!ran)
        goto done;
    if (s->record_file[0] && recorder.failed)
        goto done;
    pipeline_stats st = pipeline_get_stats(p);
    const cli_channel_spec *ch = &s->channels[0];
    double pixels = 0.0; /* per frame, over the outputs' channels (not the remote view's: rendered while watched) */
    char what[128];
    /* the wall's or the picture's channels: the remote view's come last and are not outputs */
    int channels = cli_remote_channel() >= 0 ? cli_remote_channel() : pipeline_channel_count(p);
    for (int i = 0; i < channels; i++) {
        camera_basis b = pipeline_channel_basis(p, i);
        pixels += (double)b.width_px * b.height_px;
    }
    if (s->wall_file[0])
        snprintf(what, sizeof what, "wall of %d outputs (%.2f Mpixels)", channels, pixels * 1e-6);
    else
        snprintf(what, sizeof what, "%dx%d%s", ch->width_px, ch->height_px, channels > 1 ? " (+ more channels)" : "");
    if ((display_backend_by_name(ch->display)->options & DISPLAY_OPTION_OUT) && cli_cluster_active()) {
        /* part of a wall: its outputs' own files, no stitched image */
        printf("wrote %llu frames of this process's %d output%s (%s with -CONNECTOR added)\n",
               (unsigned long long)st.frames_displayed, channels, channels == 1 ? "" : "s", ch->out);
    } else if (display_backend_by_name(ch->display)->options & DISPLAY_OPTION_OUT) {
        char first[4096], last[4096];
        uint64_t n = st.frames_displayed;
        bool sequence = s->frames != 1;
        if (dump_frame_path(ch->out, 0, sequence, first, sizeof first, &err) &&
            dump_frame_path(ch->out, n > 0 ? (int)(n - 1) : 0, sequence, last, sizeof last, &err))
        {
            if (n == 1)
                printf("wrote %s\n", first);
            else
                printf("wrote %llu frames: %s ... %s\n", (unsigned long long)n, first, last);
        }
    }
    double fps = st.run_s > 0.0 ? (double)st.frames_rendered / st.run_s : 0.0;
    printf("%llu frame%s %s, %d thread%s: %.2f frames/s (%.1f ms/frame, %.2f Mpixels/s), display %s "
           "%.1f ms/frame on thread 0\n",
           (unsigned long long)st.frames_rendered, st.frames_rendered == 1 ? "" : "s", what, s->threads,
           s->threads == 1 ? "" : "s", fps,
           fps > 0.0 ? 1e3 / fps : 0.0, pixels * fps * 1e-6, ch->display,
           st.frames_displayed ? 1e3 * st.display_s / (double)st.frames_displayed : 0.0);
    if (s->render_scale < 1.0 && st.frames_reduced) {
        int low_w = upscale_low_res_px(ch->width_px, s->render_scale);
        int low_h = upscale_low_res_px(ch->height_px, s->render_scale);
        printf("render scale %s: %dx%d rendered, upscaled to %dx%d (%s): %.2f ms/frame upscaling on the render "
               "threads\n",
               s->render_scale_text, low_w, low_h, ch->width_px, ch->height_px, upscale_filter_name(s->upscale),
               1e3 * st.upscale_s / (double)st.frames_reduced);
    }
    cli_pipeline_report(p, s);
    code = 0;
done:
    cli_remote_stop();
    cli_input_finish(input);
    cli_input_files_free(&input_files);
    pipeline_destroy(p);
    cli_remote_release(); /* after the pipeline, which owns its display */
    cli_pipeline_release_outputs(outputs); /* a device: as it was found (a card: its CRTCs) */
    camera_path_free(&player.path);
    if (s->record_file[0] && p)
        camera_path_free(&recorder.path);
    cli_scene_finish(&cs);
    return code;
}

static void render_usage(FILE *f)
{
    fputs("usage: tessera render [options]\n"
          "Render a scene headless and write the image(s) through the dump backend.\n"
          "  --scene FILE     JSON scene, or a mesh file (.ply, .obj, ...) framed automatically;\n"
          "                   'default' or no --scene: the built-in scene\n"
          "  --size WxH       image size in pixels (default 1280x720)\n"
          "  --out FILE       output image; .png = 8-bit sRGB, .exr = linear float (default out/render.png).\n"
          "                   With --frames > 1: '####' or '%04d' in the name is the frame number,\n"
          "                   otherwise _NNNN is added before the extension\n"
          "  --camera ex,ey,ez,lx,ly,lz,ux,uy,uz,fov\n"
          "                   eye, look-at point, up vector, vertical field of view in degrees\n"
          "                   (default: the scene's camera, else the bounding box framed from (1,0.5,1.5))\n"
          "  --frames N       render and write N frames (default 1; with --path the camera moves)\n"
          "  --scale S        render at S of --size and upscale to --size: S in (0, 1], a fraction\n"
          "                   (3/4, 1/3) or a decimal (0.5); each edge max(1, round(edge * S)) pixels,\n"
          "                   the same view (default 1: no upscaling; a wall: every output); --upscale\n"
          "                   (below) is its filter\n",
          f);
    cli_pipeline_usage(f, "fixed", "30");
}

int cli_render(int argc, char **argv)
{
    cli_pipeline_spec s;
    cli_pipeline_spec_default(&s, "dump", "out/render.png");
    s.frames = 1;
    s.time_mode = PIPELINE_TIME_FIXED_RATE;
    const char *scene_path = NULL;
    int code = 0;
    cli_given given = {.count = 0};
    if (!parse_options(argc, argv, &s, &scene_path, render_usage, &code, &given, true))
        return code;
    if (s.input.enabled == 1) {
        cli_error("%s: 'tessera render' reads no input devices (use 'tessera run'; render can --replay-input)",
                  s.input.enabled_from_config ? "input.enabled in the config" : "--input on");
        return 2;
    }
    if (!check_option_conflicts(&s))
        return 2;
    if (!s.input.replay_speed_given)
        s.input.replay_speed = INPUT_REPLAY_ALL;
    s.input.replay_strict = true; /* a replayed record refused: exit 1, no image (run logs and counts it) */
    cli_check_ignored_render_run(&given, &s, "render");
    int done = run_job(&s, scene_path, false, NULL);
    cli_cluster_end();
    return done;
}

int cli_run_with(int argc, char **argv, const cli_run_hooks *hooks)
{
    run_hooks = hooks;
    int code = cli_run(argc, argv);
    run_hooks = NULL;
    return code;
}

static void run_usage(FILE *f)
{
    /* the kiosk's backend, as the table describes it */
    const display_backend *kiosk = display_backend_kiosk_kind();
    const display_lifecycle *kl = kiosk ? kiosk->lifecycle : NULL;
    const char *kiosk_name = kiosk ? kiosk->name : "a device";
    fprintf(f, "usage: tessera run [options]\nThe main job. %s", kl && kl->kiosk_help ? kl->kiosk_help : "\n");
    fprintf(f,
            "Otherwise it runs the pipeline headless with the dump display: the camera orbits the\n"
            "scene (one turn per 2 s of frame time) or follows --path, frames go to\n"
            "out/frame_NNNN.png, and it prints the frame rate.\n"
            "  --scene FILE     JSON scene or mesh file (default: the built-in scene)\n"
            "  --size WxH       image size in pixels (default 1280x720)\n"
            "  --frames N       frames to render (headless default 48: one turn at 24 Hz; %s, --remote: until\n"
            "                   stopped)\n"
            "  --out PATTERN    frame file pattern (default out/frame_####.png)\n"
            "  --camera ...     start camera, as for 'tessera render'\n"
            "  (headless, run's default time is fixed at 24 Hz: frame k shows time k/24 s; with\n"
            "  %s it is real time: give --time fixed --rate HZ for reproducible frames on a wall)\n",
            kiosk_name, kiosk_name);
    char time_default[64];
    snprintf(time_default, sizeof time_default, "fixed; real on a %s wall", kl ? kl->device_label : "device");
    cli_pipeline_usage(f, time_default, "24");
}

int cli_run(int argc, char **argv)
{
    cli_pipeline_spec s;
    cli_pipeline_spec_default(&s, "dump", "out/frame_####.png");
    s.frames = 48;
    s.time_mode = PIPELINE_TIME_FIXED_RATE;
    s.rate_hz = 24.0;
    const char *scene_path = NULL;
    int code = 0;
    cli_given given = {.count = 0};
    if (!parse_options(argc, argv, &s, &scene_path, run_usage, &code, &given, false))
        return code;
    /* the kiosk: a wall on a device when there is one, until stopped, in real time */
    const display_backend *kiosk = s.wall_file[0] && !s.display_given ? display_backend_kiosk() : NULL;
    if (kiosk)
        snprintf(s.channels[0].display, sizeof s.channels[0].display, "%s", kiosk->name);
    if (display_backend_by_name(s.channels[0].display)->needs & DISPLAY_NEEDS_DEVICE) {
        if (!s.wall_file[0]) {
            cli_error("--display %s needs --wall FILE (configs/walls/desk.json for one monitor)", s.channels[0].display);
            return 2;
        }
        if (!s.frames_given)
            s.frames = 0;
        if (!s.time_given)
            s.time_mode = PIPELINE_TIME_REAL;
        if (s.input.enabled < 0) /* the kiosk: people steer it */
            s.input.enabled = 1;
    }
    if (s.remote.port >= 0 && !s.frames_given) /* watched and steered from browsers: until stopped */
        s.frames = 0;
    if (!check_option_conflicts(&s))
        return 2;
    cli_check_ignored_render_run(&given, &s, "run");
    /* the default output directory is ours to create */
    if ((display_backend_by_name(s.channels[0].display)->options & DISPLAY_OPTION_OUT) &&
        !strcmp(s.channels[0].out, "out/frame_####.png") &&
        mkdir("out", 0777) != 0 && errno != EEXIST) {
        cli_error("out: cannot create directory: %s", strerror(errno));
        return 1;
    }
    service_notifier *service = service_notifier_create(); /* NULL unless started by systemd */
    code = run_job(&s, scene_path, true, service);
    service_notifier_destroy(service);
    cli_cluster_end();
    return code;
}
