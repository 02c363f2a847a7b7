/* input_cli.c - input options, config section and start-up (input_cli.h). */
#include "input_cli.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/frame/camera_path.h"
#include "engine/base/colormap.h"
#include "engine/scene/frame_state.h"
#include "engine/base/log.h"
#include "engine/scene/scene.h"
#include "input/bindings.h"
#include "input/controller.h"
#include "input/navigate.h"
#include "input/record.h"
#include "input/runner.h"
#include "input_pick.h"
#include "pipeline_cli.h"
#include "remote_cli.h"
#include "wall/display_backend.h"

#define CLI_TOUR_ORBIT_PERIOD_S 24.0 /* the default tour: one turn around the home view */

void cli_input_spec_default(cli_input_spec *s)
{
    memset(s, 0, sizeof *s);
    s->enabled = -1;
    s->idle_timeout_s = 60.0;
    s->tour_ease_s = 2.0;
    s->replay_speed = INPUT_REPLAY_RECORDED;
}

bool cli_input_wanted(const cli_input_spec *s)
{
    return s->enabled == 1 || s->record_file[0] || s->replay_file[0] || cli_remote_channel() >= 0;
}

/* ---- options ------------------------------------------------------------------- */

static bool copy_text(const char *what, const char *value, char *out, size_t size)
{
    if (strlen(value) >= size) {
        cli_error("%s: value longer than %zu bytes", what, size - 1);
        return false;
    }
    snprintf(out, size, "%s", value);
    return true;
}

/* "DEVICE=OUTPUT" */
static bool parse_map(const char *what, const char *value, cli_input_spec *s)
{
    const char *eq = strrchr(value, '=');
    if (!eq || eq == value || !eq[1]) {
        cli_error("%s: '%s' is not DEVICE=OUTPUT (a device name or /dev/input node, an output's connector)", what,
                  value);
        return false;
    }
    if (!s->map_from_cmdline) { /* the command line's mappings replace the config's */
        s->map_from_cmdline = true;
        s->map_count = 0;
    }
    if (s->map_count == INPUT_MAX_RULES) {
        cli_error("%s: more than %d device mappings", what, INPUT_MAX_RULES);
        return false;
    }
    input_device_rule *r = &s->map[s->map_count];
    size_t n = (size_t)(eq - value);
    if (n >= sizeof r->device || strlen(eq + 1) >= sizeof r->output) {
        cli_error("%s: '%s': device or output name too long", what, value);
        return false;
    }
    memcpy(r->device, value, n);
    r->device[n] = '\0';
    snprintf(r->output, sizeof r->output, "%s", eq + 1);
    s->map_count++;
    return true;
}

static bool parse_seconds(const char *what, const char *value, double lo, double *out)
{
    char *end;
    double v = strtod(value, &end);
    if (end == value || *end || !isfinite(v) || v < lo || v > 1e6) {
        cli_error("%s: '%s' is not a number of seconds in [%g, 1e6]", what, value, lo);
        return false;
    }
    *out = v;
    return true;
}

bool cli_input_option(int argc, char **argv, int *i, cli_input_spec *s, bool *handled)
{
    const char *a = argv[*i], *val;
    *handled = true;
    if (!strcmp(a, "--input")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (strcmp(val, "on") && strcmp(val, "off")) {
            cli_error("--input: '%s' (expected on or off)", val);
            return false;
        }
        s->enabled = !strcmp(val, "on");
        s->enabled_from_config = false;
        return true;
    } else if (!strcmp(a, "--bindings")) {
        return (val = cli_option_value(argc, argv, i)) && copy_text(a, val, s->bindings_file, sizeof s->bindings_file);
    } else if (!strcmp(a, "--seat")) {
        return (val = cli_option_value(argc, argv, i)) && copy_text(a, val, s->seat, sizeof s->seat);
    } else if (!strcmp(a, "--input-device")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (!val[0]) {
            cli_error("--input-device: empty path (expected a device node such as /dev/input/event3)");
            return false;
        }
        if (!s->devices_from_cmdline) { /* the command line's devices replace the config's */
            s->devices_from_cmdline = true;
            s->device_count = 0;
        }
        if (s->device_count == INPUT_MAX_PATHS) {
            cli_error("--input-device: more than %d devices", INPUT_MAX_PATHS);
            return false;
        }
        return copy_text(a, val, s->devices[s->device_count++], sizeof s->devices[0]);
    } else if (!strcmp(a, "--map-input")) {
        return (val = cli_option_value(argc, argv, i)) && parse_map(a, val, s);
    } else if (!strcmp(a, "--idle-timeout")) {
        return (val = cli_option_value(argc, argv, i)) && parse_seconds(a, val, 0.0, &s->idle_timeout_s);
    } else if (!strcmp(a, "--tour")) {
        return (val = cli_option_value(argc, argv, i)) && copy_text(a, val, s->tour_file, sizeof s->tour_file);
    } else if (!strcmp(a, "--record-input")) {
        return (val = cli_option_value(argc, argv, i)) && copy_text(a, val, s->record_file, sizeof s->record_file);
    } else if (!strcmp(a, "--replay-input")) {
        return (val = cli_option_value(argc, argv, i)) && copy_text(a, val, s->replay_file, sizeof s->replay_file);
    } else if (!strcmp(a, "--replay-speed")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (!input_replay_speed_from_name(val, &s->replay_speed)) {
            cli_error("--replay-speed: '%s' (expected one of: %s)", val, INPUT_REPLAY_SPEED_NAMES);
            return false;
        }
        s->replay_speed_given = true;
        return true;
    }
    *handled = false;
    return true;
}

void cli_input_usage(FILE *f)
{
    const display_backend *kiosk = display_backend_kiosk_kind(); /* whose wall turns input on */
    fprintf(f, "input options (a config's \"input\" object sets the same; docs/pipeline-config.md):\n"
               "  --input on|off   libinput devices steer the camera (default: on for `run` on a %s wall)\n",
            kiosk ? kiosk->lifecycle->device_label : "device");
    fputs("  --bindings FILE  keys, buttons and gestures (configs/bindings.json; default: its contents)\n"
          "  --seat NAME      libinput's udev seat (default seat0)\n"
          "  --input-device PATH  use only these devices (libinput's path backend; repeatable)\n"
          "  --map-input DEVICE=OUTPUT  a touchscreen or tablet (name or /dev/input node) covers that\n"
          "                   output of the wall (repeatable; default: the whole wall)\n"
          "  --idle-timeout S seconds without input before the attract tour starts (0: never; default 60)\n"
          "  --tour FILE      the tour's camera path (default: --path, else one turn around the home view\n"
          "                   every 24 s)\n"
          "  --record-input FILE  write the transactions input makes, with their times\n"
          "  --replay-input FILE  play recorded input transactions back\n"
          "  --replay-speed recorded|frames|all  at their times, one per frame, or all before the\n"
          "                   first frame (default: recorded for run, all for render)\n",
          f);
}

/* ---- the config's "input" object --------------------------------------------------- */

static bool config_text(jr_ctx *c, json_object *obj, const char *key, const char *config_file, bool path, char *out,
                        size_t size)
{
    const char *v = NULL;
    if (!jr_opt_string(c, obj, key, &v))
        return false;
    if (!v)
        return true;
    char resolved[CLI_INPUT_PATH_BYTES];
    if (path && v[0] != '/') { /* relative to the config file */
        const char *slash = strrchr(config_file, '/');
        int dir_len = slash ? (int)(slash - config_file + 1) : 0;
        if (snprintf(resolved, sizeof resolved, "%.*s%s", dir_len, config_file, v) >= (int)sizeof resolved)
            return jr_member_fail(c, key, "path too long");
        v = resolved;
    }
    if (strlen(v) >= size)
        return jr_member_fail(c, key, "too long");
    snprintf(out, size, "%s", v);
    return true;
}

static bool config_devices(jr_ctx *c, json_object *obj, cli_input_spec *s)
{
    json_object *arr;
    if (!jr_get_member(obj, "devices", &arr))
        return true;
    size_t saved = jr_field_key(c, "devices");
    bool ok = jr_expect_array(c, arr);
    size_t n = ok ? json_object_array_length(arr) : 0;
    if (ok && n > INPUT_MAX_PATHS)
        ok = jr_field_fail(c, "at most %d devices, got %zu", INPUT_MAX_PATHS, n);
    for (size_t i = 0; ok && i < n; i++) {
        size_t at = jr_field_index(c, i);
        json_object *v = json_object_array_get_idx(arr, i);
        if (!v || !json_object_is_type(v, json_type_string))
            ok = jr_field_fail(c, "expected a device path (a string), got %s", jr_kind(v));
        else if (!json_object_get_string_len(v))
            ok = jr_field_fail(c, "empty path (expected a device node such as /dev/input/event3)");
        else if ((size_t)json_object_get_string_len(v) >= sizeof s->devices[0])
            ok = jr_field_fail(c, "path too long");
        else
            snprintf(s->devices[i], sizeof s->devices[0], "%s", json_object_get_string(v));
        jr_field_leave(c, at);
    }
    jr_field_leave(c, saved);
    if (ok)
        s->device_count = (int)n;
    return ok;
}

static bool config_map(jr_ctx *c, json_object *obj, cli_input_spec *s)
{
    static const char *const fields[] = {"device", "output", NULL};
    json_object *arr;
    if (!jr_get_member(obj, "map", &arr))
        return true;
    size_t saved = jr_field_key(c, "map");
    bool ok = jr_expect_array(c, arr);
    size_t n = ok ? json_object_array_length(arr) : 0;
    if (ok && n > INPUT_MAX_RULES)
        ok = jr_field_fail(c, "at most %d mappings, got %zu", INPUT_MAX_RULES, n);
    for (size_t i = 0; ok && i < n; i++) {
        size_t at = jr_field_index(c, i);
        json_object *v = json_object_array_get_idx(arr, i);
        input_device_rule *r = &s->map[i];
        ok = jr_expect_object(c, v) && jr_check_fields(c, v, fields) && jr_require_member(c, v, "device") &&
             jr_require_member(c, v, "output") &&
             config_text(c, v, "device", "", false, r->device, sizeof r->device) &&
             config_text(c, v, "output", "", false, r->output, sizeof r->output);
        jr_field_leave(c, at);
    }
    jr_field_leave(c, saved);
    if (ok)
        s->map_count = (int)n;
    return ok;
}

bool cli_input_config_load(jr_ctx *c, json_object *root, const char *config_file, cli_input_spec *s)
{
    static const char *const fields[] = {"enabled", "bindings", "seat", "devices", "map", "idle_timeout_s",
                                         "tour", "tour_ease_s", NULL};
    json_object *obj;
    if (!jr_get_member(root, "input", &obj))
        return true;
    size_t saved = jr_field_key(c, "input");
    bool enabled = s->enabled == 1;
    json_object *given;
    bool had_enabled = obj && json_object_is_type(obj, json_type_object) && jr_get_member(obj, "enabled", &given);
    static const jr_range timeout = {0.0, 1e6, false, false};
    static const jr_range ease = {0.0, 600.0, true, false};
    bool ok = jr_expect_object(c, obj) && jr_check_fields(c, obj, fields) && jr_opt_bool(c, obj, "enabled", &enabled) &&
              config_text(c, obj, "bindings", config_file, true, s->bindings_file, sizeof s->bindings_file) &&
              config_text(c, obj, "seat", config_file, false, s->seat, sizeof s->seat) && config_devices(c, obj, s) &&
              config_map(c, obj, s) && jr_opt_double(c, obj, "idle_timeout_s", timeout, &s->idle_timeout_s) &&
              config_text(c, obj, "tour", config_file, true, s->tour_file, sizeof s->tour_file) &&
              jr_opt_double(c, obj, "tour_ease_s", ease, &s->tour_ease_s);
    if (ok && had_enabled) {
        s->enabled = enabled ? 1 : 0;
        s->enabled_from_config = true;
    }
    jr_field_leave(c, saved);
    return ok;
}

/* ---- before the scene loads ------------------------------------------------------------ */

bool cli_input_load_files(const cli_input_spec *s, const char *tour_path, cli_input_files *files)
{
    tess_error err = {{0}};
    *files = (cli_input_files){.have_bindings = false};
    if (s->enabled == 1) {
        if (s->bindings_file[0]) {
            if (!input_bindings_load(s->bindings_file, &files->bindings, &err)) {
                cli_error("--bindings %s", err.msg);
                return false;
            }
            files->have_bindings = true;
        }
        const char *tour_file = s->tour_file[0] ? s->tour_file : tour_path;
        if (tour_file && tour_file[0] && !camera_path_load(tour_file, &files->tour, &err)) {
            cli_error("%s%s", s->tour_file[0] ? "--tour " : "", err.msg);
            return false;
        }
    } else if (s->bindings_file[0] || s->map_count || s->device_count || s->tour_file[0] || s->seat[0]) {
        fprintf(stderr, "tessera: input is off: --bindings, --map-input, --input-device, --tour and --seat are "
                        "ignored (--input on reads the devices)\n");
    }
    if (s->replay_speed_given && !s->replay_file[0])
        fprintf(stderr, "tessera: --replay-speed without --replay-input is ignored\n");
    return true;
}

void cli_input_files_free(cli_input_files *files) { camera_path_free(&files->tour); }

/* ---- running ----------------------------------------------------------------------------- */

struct cli_input {
    input_sink *sink;
    input_runner *runner;
    camera_path tour;
    const cli_scene *cs;
    char record_file[CLI_INPUT_PATH_BYTES];
};

/* The pick hook (input_pick.h). */
static void pick(void *ctx, vec3 origin, vec3 dir, input_hit *out)
{
    const cli_scene *cs = ctx;
    cli_input_pick(cs->scene, cs->accel, origin, dir, out);
}

/* The particle sets input may crop: instances of kinds that crop. */
static void crop_targets(const scene *s, input_controller_config *cc)
{
    for (uint32_t i = 0; i < s->instance_count && cc->crop_count < INPUT_CROP_MAX; i++) {
        const scene_geometry *g = scene_instance_geometry(s, i);
        const geometry_controls *c = geometry_controls_of(g->ops);
        geometry_crop_attribute a;
        if (!c->crop_attribute || !c->crop_attribute(g->data, &a))
            continue;
        input_crop_target *t = &cc->crops[cc->crop_count++];
        *t = (input_crop_target){.first = i, .count = 1, .min = a.min, .max = a.max, .crop = a.crop};
        snprintf(t->attribute, sizeof t->attribute, "%s", a.name);
    }
}

/* The geometries input may step the value of, and those coloured through a
 * map (their first instance each: every instance of a geometry follows). */
static void value_and_map_targets(const scene *s, input_controller_config *cc)
{
    for (uint32_t g = 0; g < s->geometry_count; g++) {
        const scene_geometry *sg = &s->geometries[g];
        uint32_t inst = 0;
        while (inst < s->instance_count && s->instances[inst].geometry != g)
            inst++;
        if (inst == s->instance_count)
            continue;
        const geometry_controls *c = geometry_controls_of(sg->ops);
        float v, lo, hi;
        if (c->value && cc->value_count < INPUT_VALUE_MAX && c->value(sg->data, &v, &lo, &hi))
            cc->values[cc->value_count++] = (input_value_target){inst, 1, v, lo, hi};
        const colormap *cm = c->colormap ? c->colormap(sg->data) : NULL;
        if (cm && cc->map_count < INPUT_MAP_MAX) {
            input_map_target *t = &cc->maps[cc->map_count++];
            *t = (input_map_target){.first = inst, .count = 1};
            snprintf(t->name, sizeof t->name, "%s", cm->name[0] ? cm->name : "custom");
        }
    }
}

/* Whether every time series can show `step` without waiting (input thread:
 * scene_step_ready is safe while frames render). */
static bool step_ready(void *ctx, uint32_t step)
{
    const cli_scene *cs = ctx;
    return scene_step_ready(cs->scene, step);
}

static bool start_devices(cli_input *in, const cli_input_spec *s, pipeline *p, const cli_scene *cs,
                          const cli_input_files *files, struct session *seat)
{
    tess_error err = {{0}};
    input_controller_config cc;
    input_controller_config_default(&cc);
    if (files->have_bindings)
        cc.bindings = files->bindings;
    input_libinput_config sc = {0};
    snprintf(sc.seat, sizeof sc.seat, "%s", s->seat);
    for (int i = 0; i < s->device_count; i++)
        snprintf(sc.paths[i], sizeof sc.paths[i], "%s", s->devices[i]);
    sc.path_count = s->device_count;
    memcpy(sc.rules, s->map, sizeof s->map);
    sc.rule_count = s->map_count;
    sc.output_count = cli_pipeline_layout(p, &cc.plane_aspect, sc.outputs, INPUT_MAX_OUTPUTS);
    camera_basis b0 = pipeline_channel_basis(p, 0);
    const camera_window *w0 = &sc.outputs[0].window;
    sc.px_per_unit_x = (double)b0.width_px / (2.0 * (double)w0->half_width);
    sc.px_per_unit_y = (double)b0.height_px / (2.0 * (double)w0->half_height);
    cc.home = pipeline_camera(p, 0);
    /* inspection starts where the pipeline does (its config's opacity and planes): read before
     * the loop runs, so no barrier is needed */
    const frame_state *st = pipeline_frame_state(p);
    cc.opacity = st->opacity;
    memcpy(cc.clip, frame_state_clip_planes(st), sizeof cc.clip);
    snprintf(cc.renderer, sizeof cc.renderer, "%s", st->renderer->name);
    crop_targets(cs->scene, &cc);
    vec3 lo, hi;
    if (scene_bounds(cs->scene, &lo, &hi))
        cc.scene_size = v3_length(v3_sub(hi, lo));
    cc.idle_timeout_s = s->idle_timeout_s;
    cc.have_tour = in->tour.count > 0;
    cc.time_steps = scene_time_steps(cs->scene);
    value_and_map_targets(cs->scene, &cc);
    cc.media = cs->scene->medium_count > 0;
    const geometry_controls *media_controls = cc.media ? medium_controls_of(cs->scene->media[0].ops) : NULL;
    if (media_controls && media_controls->colormap)
        snprintf(cc.transfer, sizeof cc.transfer, "%s", media_controls->colormap(cs->scene->media[0].data)->name);
    /* libinput's devices with --input on; the remote view's viewers with --remote */
    input_source *sources[INPUT_MAX_SOURCES];
    int source_count = 0;
    bool ok = true;
    if (s->enabled == 1)
        ok = (sources[source_count++] = input_libinput_open(&sc, seat, &err)) != NULL;
    input_source *remote = cli_remote_take_source();
    if (remote)
        sources[source_count++] = remote;
    if (!ok) { /* the remote source is ours now: it goes too */
        input_source_destroy(remote);
        source_count = 0;
    }
    in->runner = ok && source_count ? input_runner_start(sources, source_count, &cc, pick, step_ready, (void *)cs,
                                                         in->sink, seat, &err)
                                    : NULL;
    if (!in->runner) {
        cli_error("%s", err.msg);
        return false;
    }
    return true;
}

/* Render's replay: every record the pipeline would refuse (an instance or a
 * channel the scene does not have) is an error naming its line, before any
 * frame is rendered: an image of a replay that went differently is not what
 * was asked for. The input-level kinds (tour, quit) are the sink's. */
static bool replay_checks(const pipeline *p, const input_record *rec)
{
    enum { SHOWN = 10 };
    size_t refused = 0;
    for (size_t i = 0; i < rec->count; i++) {
        const input_record_entry *e = &rec->entries[i];
        tess_error err = {{0}};
        if (txn_kind_input_level(e->txn.kind) || pipeline_check(p, &e->txn, &err))
            continue;
        if (++refused <= SHOWN)
            cli_error("--replay-input %s:%zu: %s", rec->name ? rec->name : "?", e->line, err.msg);
    }
    if (!refused)
        return true;
    if (refused > SHOWN)
        cli_error("--replay-input %s: %zu more refused records not shown", rec->name ? rec->name : "?",
                  refused - SHOWN);
    cli_error("--replay-input %s: %zu of %zu record%s refused for this scene: nothing rendered",
              rec->name ? rec->name : "?", refused, rec->count, rec->count == 1 ? "" : "s");
    return false;
}

cli_input *cli_input_start(const cli_input_spec *s, pipeline *p, const cli_scene *cs, cli_input_files *files,
                           struct session *seat)
{
    cli_input *in = calloc(1, sizeof *in);
    if (!in) {
        cli_error("input: out of memory");
        return NULL;
    }
    in->cs = cs;
    tess_error err = {{0}};
    in->tour = files->tour; /* taken over */
    files->tour = (camera_path){0};
    /* no tour given: every scene gets one, a slow orbit around its home view */
    if (s->enabled == 1 && !in->tour.count && s->idle_timeout_s > 0.0) {
        camera_desc home = pipeline_camera(p, 0);
        if (!navigate_orbit_path(&home, CLI_TOUR_ORBIT_PERIOD_S, 8, &in->tour, &err)) {
            cli_error("%s", err.msg);
            goto fail;
        }
    }
    input_sink_config sk = {.tour = in->tour.count ? &in->tour : NULL,
                            .tour_ease_s = s->tour_ease_s,
                            .record_file = s->record_file,
                            .print_status = true};
    in->sink = input_sink_create(p, &sk, &err);
    if (!in->sink) {
        cli_error("%s", err.msg);
        goto fail;
    }
    if (s->replay_file[0]) {
        input_record rec;
        if (!input_record_load(s->replay_file, &rec, &err)) {
            cli_error("--replay-input %s", err.msg);
            goto fail;
        }
        if (s->replay_strict && !replay_checks(p, &rec)) {
            input_record_free(&rec);
            goto fail;
        }
        bool ok = input_sink_replay(in->sink, &rec, s->replay_speed, &err);
        size_t count = rec.count;
        input_record_free(&rec);
        if (!ok) {
            cli_error("%s", err.msg);
            goto fail;
        }
        fprintf(stderr, "tessera: replaying %zu input transactions from %s\n", count, s->replay_file);
    }
    if ((s->enabled == 1 || cli_remote_channel() >= 0) && !start_devices(in, s, p, cs, files, seat))
        goto fail;
    return in;
fail:
    cli_input_finish(in);
    return NULL;
}

input_sink *cli_input_sink(cli_input *in) { return in ? in->sink : NULL; }

void cli_input_finish(cli_input *in)
{
    if (!in)
        return;
    input_runner_stop(in->runner);
    if (in->sink) {
        input_sink_stats st = input_sink_get_stats(in->sink);
        if (st.emitted)
            fprintf(stderr,
                    "tessera: input: %llu transactions (%llu camera changes applied in %llu camera transactions, "
                    "%llu refused)\n",
                    (unsigned long long)st.emitted, (unsigned long long)st.camera_changes,
                    (unsigned long long)st.camera_applied, (unsigned long long)st.refused);
    }
    input_sink_destroy(in->sink);
    camera_path_free(&in->tour);
    free(in);
}
