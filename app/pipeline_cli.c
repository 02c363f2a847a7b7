/* pipeline_cli.c - pipeline components by name: the config file, the
 * command-line options, making the pipeline, camera-path playback and
 * recording. The config format is in docs/pipeline-config.md. */
#include "pipeline_cli.h"
#include "cluster_cli.h"
#include "remote_cli.h"

#include <libgen.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/base/json_read.h"
#include "engine/base/log.h"
#include "engine/scene/scene.h"
#include "option_check.h"
#include "wall/display_backend.h"
#include "wall/wall_headless.h"

#define CONFIG_MAX_BYTES (1u << 20) /* a pipeline config is a few hundred bytes */

static int online_cpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > PIPELINE_MAX_THREADS ? PIPELINE_MAX_THREADS : (int)n;
}

void cli_pipeline_spec_default(cli_pipeline_spec *s, const char *display, const char *out)
{
    memset(s, 0, sizeof *s);
    s->threads = online_cpus();
    s->time_mode = PIPELINE_TIME_REAL;
    s->rate_hz = 30.0;
    s->frames = 0;
    s->tile_px = RENDER_TILE_PX;
    s->order = TILE_ORDER_ROWS;
    s->order_seed = 1;
    s->sampler = pixel_sampler_single();
    s->renderer = renderer_by_name("raytracer");
    s->shadows = true;
    s->channel_count = 1;
    s->channels[0].width_px = 1280;
    s->channels[0].height_px = 720;
    snprintf(s->channels[0].display, sizeof s->channels[0].display, "%s", display);
    snprintf(s->channels[0].out, sizeof s->channels[0].out, "%s", out ? out : "");
    cli_input_spec_default(&s->input);
    remote_config_default(&s->remote);
    s->render_scale = 1.0;
    s->upscale = UPSCALE_BILINEAR;
    snprintf(s->render_scale_text, sizeof s->render_scale_text, "1");
    s->budget_ms = 0.0;
    s->refine_k = GOVERNOR_DEFAULT_REFINE_K;
    s->still_s = GOVERNOR_DEFAULT_STILL_S;
    render_settings settings = render_settings_default();
    memcpy(&s->settings, &settings, sizeof settings); /* with its zeroed padding (compared byte for byte) */
    s->opacity = 1.f; /* clip: zeroed above, every plane unused */
}

/* ---------------------------------------------------------------- the config file */

/* An integer member in [lo, hi]. */
static bool opt_int(jr_ctx *c, json_object *obj, const char *key, int lo, int hi, int *out)
{
    double v = 0.0;
    json_object *m;
    if (!jr_get_member(obj, key, &m))
        return true;
    size_t saved = jr_field_key(c, key);
    bool ok = jr_double(c, m, (jr_range){lo, hi, false, false}, &v);
    if (ok && v != floor(v))
        ok = jr_field_fail(c, "expected an integer, got %g", v);
    jr_field_leave(c, saved);
    if (ok)
        *out = (int)v;
    return ok;
}

/* A string member copied into a fixed buffer. */
static bool opt_text(jr_ctx *c, json_object *obj, const char *key, char *out, size_t out_bytes)
{
    const char *v = NULL;
    if (!jr_opt_string(c, obj, key, &v))
        return false;
    if (!v)
        return true;
    if (strlen(v) >= out_bytes)
        return jr_member_fail(c, key, "too long");
    snprintf(out, out_bytes, "%s", v);
    return true;
}

static bool opt_size(jr_ctx *c, json_object *obj, int *w, int *h)
{
    json_object *m;
    if (!jr_get_member(obj, "size", &m))
        return true;
    size_t saved = jr_field_key(c, "size");
    float v[2];
    bool ok = jr_numbers(c, m, 2, (jr_range){1, CLI_MAX_IMAGE_EDGE_PX, false, false}, v);
    if (ok && (v[0] != floorf(v[0]) || v[1] != floorf(v[1])))
        ok = jr_field_fail(c, "expected whole pixel counts, got [%g, %g]", v[0], v[1]);
    jr_field_leave(c, saved);
    if (ok) {
        *w = (int)v[0];
        *h = (int)v[1];
    }
    return ok;
}

static bool opt_camera(jr_ctx *c, json_object *obj, cli_channel_spec *ch)
{
    static const char *const fields[] = {"eye", "look_at", "up", "fov_deg", NULL};
    json_object *m;
    if (!jr_get_member(obj, "camera", &m))
        return true;
    size_t saved = jr_field_key(c, "camera");
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) && jr_camera_members(c, m, &ch->camera);
    jr_field_leave(c, saved);
    if (ok)
        ch->have_camera = true;
    return ok;
}

/* A path in the config is relative to the config file's directory. */
static bool resolve_relative(const char *config_file, const char *path, char *out, size_t out_bytes)
{
    if (path[0] == '/') {
        snprintf(out, out_bytes, "%s", path);
        return strlen(path) < out_bytes;
    }
    char copy[CLI_PATTERN_BYTES];
    snprintf(copy, sizeof copy, "%s", config_file);
    int n = snprintf(out, out_bytes, "%s/%s", dirname(copy), path);
    return n >= 0 && (size_t)n < out_bytes;
}

static bool opt_display(jr_ctx *c, json_object *obj, cli_channel_spec *ch)
{
    static const char *const fields[] = {"name", "out", NULL};
    json_object *m;
    if (!jr_get_member(obj, "display", &m))
        return true;
    size_t saved = jr_field_key(c, "display");
    const char *name = NULL;
    const display_backend *b = NULL;
    char out[CLI_PATTERN_BYTES] = "", reason[512];
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) && jr_require_member(c, m, "name") &&
              jr_opt_string(c, m, "name", &name);
    if (ok && !(b = display_backend_by_name(name))) {
        char names[256];
        display_backend_names(0, ", ", names, sizeof names);
        snprintf(reason, sizeof reason, "unknown value '%s' (expected one of: %s)", name, names);
        ok = jr_member_fail(c, "name", reason);
    }
    ok = ok && opt_text(c, m, "out", out, sizeof out);
    if (ok && (b->options & DISPLAY_OPTION_OUT) && !out[0]) {
        snprintf(reason, sizeof reason, "required for the %s display (a file pattern such as out/frame_####.png)",
                 b->name);
        ok = jr_member_fail(c, "out", reason);
    }
    if (ok && out[0])
        snprintf(ch->out, sizeof ch->out, "%s", out); /* relative to the working directory, as --out */
    jr_field_leave(c, saved);
    if (ok)
        snprintf(ch->display, sizeof ch->display, "%s", b->name);
    return ok;
}

static bool load_channel(jr_ctx *c, json_object *v, cli_channel_spec *ch)
{
    static const char *const fields[] = {"size", "camera", "display", NULL};
    return jr_expect_object(c, v) && jr_check_fields(c, v, fields) && opt_size(c, v, &ch->width_px, &ch->height_px) &&
           opt_camera(c, v, ch) && opt_display(c, v, ch);
}

static bool load_time(jr_ctx *c, json_object *root, cli_pipeline_spec *s)
{
    static const char *const fields[] = {"mode", "rate_hz", NULL};
    static const char *const modes[] = {"real", "fixed", NULL};
    json_object *m;
    if (!jr_get_member(root, "time", &m))
        return true;
    size_t saved = jr_field_key(c, "time");
    int mode = s->time_mode == PIPELINE_TIME_FIXED_RATE ? 1 : 0;
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) && jr_opt_choice(c, m, "mode", modes, &mode) &&
              jr_opt_double(c, m, "rate_hz", (jr_range){0.0, 1e6, true, false}, &s->rate_hz);
    jr_field_leave(c, saved);
    s->time_mode = mode == 1 ? PIPELINE_TIME_FIXED_RATE : PIPELINE_TIME_REAL;
    return ok;
}

/* "governor": {"budget_ms", "refine_k", "still_s", "upscale"} (pipeline.h, GOVERNOR). */
static bool load_governor(jr_ctx *c, json_object *root, cli_pipeline_spec *s)
{
    static const char *const fields[] = {"budget_ms", "refine_k", "still_s", "upscale", NULL};
    static const char *const filters[] = {"bilinear", "clamped-cubic", NULL};
    json_object *m;
    if (!jr_get_member(root, "governor", &m))
        return true;
    size_t saved = jr_field_key(c, "governor");
    int filter = s->upscale == UPSCALE_CLAMPED_CUBIC ? 1 : 0;
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) &&
              jr_opt_double(c, m, "budget_ms", (jr_range){0.0, 1e6, false, false}, &s->budget_ms) &&
              opt_int(c, m, "refine_k", 1, PIXEL_SAMPLER_MAX_K, &s->refine_k) &&
              jr_opt_double(c, m, "still_s", (jr_range){0.0, 3600.0, false, false}, &s->still_s) &&
              jr_opt_choice(c, m, "upscale", filters, &filter);
    jr_field_leave(c, saved);
    s->upscale = filter == 1 ? UPSCALE_CLAMPED_CUBIC : UPSCALE_BILINEAR;
    return ok;
}

static bool load_traverser(jr_ctx *c, json_object *root, cli_pipeline_spec *s)
{
    static const char *const fields[] = {"name", "tile_px", "order", "seed", NULL};
    static const char *const names[] = {"tiled", NULL};
    const char *orders[TILE_ORDER_COUNT + 1];
    for (int i = 0; i < TILE_ORDER_COUNT; i++)
        orders[i] = tile_order_name((tile_order)i);
    orders[TILE_ORDER_COUNT] = NULL;
    json_object *m;
    if (!jr_get_member(root, "traverser", &m))
        return true;
    size_t saved = jr_field_key(c, "traverser");
    int name = 0, order = (int)s->order, seed = (int)(s->order_seed & 0x7fffffff);
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) && jr_opt_choice(c, m, "name", names, &name) &&
              opt_int(c, m, "tile_px", PIPELINE_TILE_PX_MIN, PIPELINE_TILE_PX_MAX, &s->tile_px) &&
              jr_opt_choice(c, m, "order", orders, &order) && opt_int(c, m, "seed", 0, INT32_MAX, &seed);
    jr_field_leave(c, saved);
    s->order = (tile_order)order;
    s->order_seed = (uint32_t)seed;
    return ok;
}

static bool load_sampler(jr_ctx *c, json_object *root, cli_pipeline_spec *s)
{
    static const char *const fields[] = {"name", "k", "seed", NULL};
    static const char *const names[] = {"single", "jittered", NULL};
    json_object *m;
    if (!jr_get_member(root, "sampler", &m))
        return true;
    size_t saved = jr_field_key(c, "sampler");
    int kind = s->sampler.kind == PIXEL_SAMPLER_JITTERED ? 1 : 0;
    int k = s->sampler.kind == PIXEL_SAMPLER_JITTERED ? s->sampler.k : PIXEL_SAMPLER_DEFAULT_K;
    int seed = (int)(s->sampler.seed & 0x7fffffff);
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) && jr_require_member(c, m, "name") &&
              jr_opt_choice(c, m, "name", names, &kind) && opt_int(c, m, "k", 1, PIXEL_SAMPLER_MAX_K, &k) &&
              opt_int(c, m, "seed", 0, INT32_MAX, &seed);
    jr_field_leave(c, saved);
    s->sampler = kind == 1 ? pixel_sampler_jittered(k, (uint32_t)seed) : pixel_sampler_single();
    return ok;
}

/* "renderer.transparency": {"min_transmittance", "max_layers", "shadows"}. */
static bool load_transparency(jr_ctx *c, json_object *renderer_obj, render_settings *rs)
{
    static const char *const fields[] = {"min_transmittance", "max_layers", "shadows", NULL};
    json_object *m;
    if (!jr_get_member(renderer_obj, "transparency", &m))
        return true;
    size_t saved = jr_field_key(c, "transparency");
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) &&
              jr_opt_number(c, m, "min_transmittance", (jr_range){0.0, 1.0, true, true}, &rs->min_transmittance) &&
              opt_int(c, m, "max_layers", 1, PIPELINE_MAX_LAYERS_MAX, &rs->max_layers) &&
              jr_opt_bool(c, m, "shadows", &rs->transparent_shadows);
    jr_field_leave(c, saved);
    return ok;
}

/* "renderer.caps": {"on", "style"}. */
static bool load_caps(jr_ctx *c, json_object *renderer_obj, render_settings *rs)
{
    static const char *const fields[] = {"on", "style", NULL};
    static const char *const styles[] = {"tint", "hatch", NULL}; /* in render_cap_style's order */
    json_object *m;
    if (!jr_get_member(renderer_obj, "caps", &m))
        return true;
    size_t saved = jr_field_key(c, "caps");
    int style = rs->cap_style == RENDER_CAP_HATCH ? 1 : 0;
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) && jr_opt_bool(c, m, "on", &rs->caps) &&
              jr_opt_choice(c, m, "style", styles, &style);
    jr_field_leave(c, saved);
    rs->cap_style = style == 1 ? RENDER_CAP_HATCH : RENDER_CAP_TINT;
    return ok;
}

/* "renderer.ao": {"rays", "distance", "interleave", "filter_px", "frames", "exponent"}. */
static bool load_ao(jr_ctx *c, json_object *renderer_obj, render_settings *rs)
{
    static const char *const fields[] = {"rays", "distance", "interleave", "filter_px", "frames", "exponent", NULL};
    json_object *m;
    if (!jr_get_member(renderer_obj, "ao", &m))
        return true;
    size_t saved = jr_field_key(c, "ao");
    int filter_px = rs->ao_filter_px;
    float exponent = rs->ao_exponent;
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) &&
              opt_int(c, m, "rays", 1, PIPELINE_AO_RAYS_MAX, &rs->ao_rays) &&
              jr_opt_number(c, m, "distance", jr_range_positive, &rs->ao_distance) &&
              opt_int(c, m, "interleave", 1, PIPELINE_AO_INTERLEAVE_MAX, &rs->ao_interleave) &&
              opt_int(c, m, "filter_px", 1, PIPELINE_AO_FILTER_PX_MAX, &filter_px) &&
              opt_int(c, m, "frames", 1, PIPELINE_AO_FRAMES_MAX, &rs->ao_frames) &&
              jr_opt_number(c, m, "exponent", jr_range_positive, &exponent);
    if (ok && !(exponent >= 1.f && exponent <= RENDER_AO_EXPONENT_MAX))
        ok = jr_member_fail(c, "exponent", "expected a number in [1, 8] (1: linear)");
    if (ok)
        rs->ao_exponent = exponent;
    if (ok && filter_px % 2 == 0)
        ok = jr_member_fail(c, "filter_px", "expected an odd filter edge (1 = off, 3, 5, 7 or 9)");
    if (ok)
        rs->ao_filter_px = filter_px;
    jr_field_leave(c, saved);
    return ok;
}

static bool load_renderer(jr_ctx *c, json_object *root, cli_pipeline_spec *s)
{
    static const char *const fields[] = {"name", "shadows", "transparency", "caps", "ao", NULL};
    json_object *m;
    if (!jr_get_member(root, "renderer", &m))
        return true;
    size_t saved = jr_field_key(c, "renderer");
    const char *name = NULL;
    bool ok = jr_expect_object(c, m) && jr_check_fields(c, m, fields) && jr_opt_string(c, m, "name", &name) &&
              jr_opt_bool(c, m, "shadows", &s->shadows) && load_transparency(c, m, &s->settings) &&
              load_caps(c, m, &s->settings) && load_ao(c, m, &s->settings);
    if (ok && name) {
        const renderer *r = renderer_by_name(name);
        if (!r) {
            char reason[256];
            snprintf(reason, sizeof reason, "unknown renderer '%s' (expected one of: %s)", name, RENDERER_NAMES);
            ok = jr_member_fail(c, "name", reason);
        } else {
            s->renderer = r;
        }
    }
    jr_field_leave(c, saved);
    return ok;
}

/* One of "cutting_planes": {"point", "normal", "on"}; point and normal required. */
static bool load_plane(jr_ctx *c, json_object *v, clip_plane *out)
{
    static const char *const fields[] = {"point", "normal", "on", NULL};
    clip_plane p = {.on = true};
    json_object *m;
    bool ok = jr_expect_object(c, v) && jr_check_fields(c, v, fields) && jr_require_member(c, v, "point") &&
              jr_require_member(c, v, "normal") && jr_opt_vec3(c, v, "point", jr_range_float, &p.point) &&
              jr_opt_vec3(c, v, "normal", jr_range_float, &p.normal) && jr_opt_bool(c, v, "on", &p.on);
    /* the pipeline normalises it (a clip-plane record): any length but 0 */
    if (ok && p.normal.x == 0.f && p.normal.y == 0.f && p.normal.z == 0.f && jr_get_member(v, "normal", &m))
        ok = jr_member_fail(c, "normal", "zero length (a plane needs a direction: the side it removes)");
    if (ok)
        *out = p;
    return ok;
}

/* "cutting_planes": [plane, ...], at most CLIP_MAX_PLANES: planes 0.. in order; the rest unused. */
static bool load_cutting_planes(jr_ctx *c, json_object *root, cli_pipeline_spec *s)
{
    json_object *m;
    if (!jr_get_member(root, "cutting_planes", &m))
        return true;
    size_t saved = jr_field_key(c, "cutting_planes");
    bool ok = jr_expect_array(c, m);
    size_t n = ok ? json_object_array_length(m) : 0;
    if (ok && n > CLIP_MAX_PLANES)
        ok = jr_field_fail(c, "%zu planes; at most %d", n, CLIP_MAX_PLANES);
    clip_plane planes[CLIP_MAX_PLANES];
    memset(planes, 0, sizeof planes);
    for (size_t i = 0; ok && i < n; i++) {
        size_t at = jr_field_index(c, i);
        ok = load_plane(c, json_object_array_get_idx(m, i), &planes[i]);
        jr_field_leave(c, at);
    }
    jr_field_leave(c, saved);
    if (ok)
        memcpy(s->clip, planes, sizeof planes);
    return ok;
}

static bool load_channels(jr_ctx *c, json_object *root, cli_pipeline_spec *s)
{
    json_object *m;
    if (!jr_get_member(root, "channels", &m))
        return true;
    size_t saved = jr_field_key(c, "channels");
    bool ok = jr_expect_array(c, m);
    size_t n = ok ? json_object_array_length(m) : 0;
    if (ok && n + 1 > PIPELINE_MAX_CHANNELS)
        ok = jr_field_fail(c, "%zu channels; at most %d besides the main one", n, PIPELINE_MAX_CHANNELS - 1);
    for (size_t i = 0; ok && i < n; i++) {
        cli_channel_spec *ch = &s->channels[1 + i];
        *ch = s->channels[0]; /* size and display default to the main channel's */
        ch->have_camera = false;
        ch->out[0] = '\0';
        size_t at = jr_field_index(c, i);
        ok = load_channel(c, json_object_array_get_idx(m, i), ch);
        if (ok && (display_backend_by_name(ch->display)->options & DISPLAY_OPTION_OUT) && !ch->out[0])
            ok = jr_field_fail(c, "a %s display needs its own \"out\" pattern", ch->display);
        jr_field_leave(c, at);
    }
    jr_field_leave(c, saved);
    if (ok)
        s->channel_count = 1 + (int)n;
    return ok;
}

bool cli_pipeline_config_load(const char *file, cli_pipeline_spec *s)
{
    tess_error err = {{0}};
    size_t len = 0;
    char *text = jr_read_file(file, CONFIG_MAX_BYTES, "a pipeline config", &len, &err);
    if (!text) {
        cli_error("%s", err.msg);
        return false;
    }
    bool ok = cli_pipeline_config_parse(file, text, len, s);
    free(text);
    return ok;
}

bool cli_pipeline_config_parse(const char *file, const char *text, size_t len, cli_pipeline_spec *s)
{
    static const char *const fields[] = {"threads", "frames", "time", "traverser", "sampler", "renderer", "size",
                                         "camera", "display", "path", "channels", "input", "governor",
                                         "opacity", "cutting_planes", "remote", NULL};
    tess_error err = {{0}};
    json_object *root = NULL;
    bool ok = jr_parse(file, text, len, &root, &err);
    jr_ctx c = {file, &err, "", 0};
    char path[CLI_PATTERN_BYTES] = "";
    ok = ok && jr_expect_object(&c, root) && jr_check_fields(&c, root, fields) &&
         opt_int(&c, root, "threads", 1, PIPELINE_MAX_THREADS, &s->threads) &&
         opt_int(&c, root, "frames", 0, 100000000, &s->frames) && load_time(&c, root, s) &&
         load_traverser(&c, root, s) && load_sampler(&c, root, s) && load_renderer(&c, root, s) &&
         load_governor(&c, root, s) && jr_opt_number(&c, root, "opacity", jr_range_unit, &s->opacity) &&
         load_cutting_planes(&c, root, s) &&
         opt_size(&c, root, &s->channels[0].width_px, &s->channels[0].height_px) &&
         opt_camera(&c, root, &s->channels[0]) && opt_display(&c, root, &s->channels[0]) &&
         opt_text(&c, root, "path", path, sizeof path) && load_channels(&c, root, s) &&
         cli_input_config_load(&c, root, file, &s->input) && cli_remote_config_load(&c, root, &s->remote);
    if (ok && path[0] && !resolve_relative(file, path, s->path_file, sizeof s->path_file))
        ok = jr_member_fail(&c, "path", "path too long");
    json_object *given;
    s->display_given = s->display_given || (ok && jr_get_member(root, "display", &given));
    s->frames_given = s->frames_given || (ok && jr_get_member(root, "frames", &given));
    s->time_given = s->time_given || (ok && jr_get_member(root, "time", &given));
    json_object_put(root);
    if (!ok)
        cli_error("%s", err.msg);
    return ok;
}

/* ---------------------------------------------------------------- the command line */

const char *cli_pipeline_find_config(int argc, char **argv)
{
    for (int i = 1; i + 1 < argc; i++)
        if (!strcmp(argv[i], "--config"))
            return argv[i + 1];
    return NULL;
}

static bool copy_value(const char *option, const char *value, char *out, size_t out_bytes)
{
    if (strlen(value) >= out_bytes) {
        cli_error("%s: value longer than %zu bytes", option, out_bytes - 1);
        return false;
    }
    snprintf(out, out_bytes, "%s", value);
    return true;
}

bool cli_pipeline_option(int argc, char **argv, int *i, cli_pipeline_spec *s, bool *handled)
{
    const char *a = argv[*i], *val = NULL;
    cli_channel_spec *main_ch = &s->channels[0];
    *handled = true;
    if (!strcmp(a, "--config")) {
        return cli_option_value(argc, argv, i) != NULL; /* loaded before the other options */
    } else if (!strcmp(a, "--size")) {
        return (val = cli_option_value(argc, argv, i)) && cli_parse_size(a, val, &main_ch->width_px,
                                                                          &main_ch->height_px);
    } else if (!strcmp(a, "--camera")) {
        if (!(val = cli_option_value(argc, argv, i)) || !cli_parse_camera(a, val, &main_ch->camera))
            return false;
        main_ch->have_camera = true;
        return true;
    } else if (!strcmp(a, "--threads")) {
        return (val = cli_option_value(argc, argv, i)) && cli_parse_int(a, val, 1, PIPELINE_MAX_THREADS, &s->threads);
    } else if (!strcmp(a, "--frames")) {
        s->frames_given = true;
        return (val = cli_option_value(argc, argv, i)) && cli_parse_int(a, val, 1, 100000000, &s->frames);
    } else if (!strcmp(a, "--time")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (strcmp(val, "real") && strcmp(val, "fixed")) {
            cli_error("--time: '%s' is not a time mode (expected real or fixed)", val);
            return false;
        }
        s->time_mode = !strcmp(val, "fixed") ? PIPELINE_TIME_FIXED_RATE : PIPELINE_TIME_REAL;
        s->time_given = true;
        return true;
    } else if (!strcmp(a, "--rate")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        char *end;
        double hz = strtod(val, &end);
        if (end == val || *end || !(hz > 0.0 && hz <= 1e6)) {
            cli_error("--rate: '%s' is not a frame rate in Hz (expected a number in (0, 1e6])", val);
            return false;
        }
        s->rate_hz = hz;
        return true;
    } else if (!strcmp(a, "--tile-size")) {
        return (val = cli_option_value(argc, argv, i)) &&
               cli_parse_int(a, val, PIPELINE_TILE_PX_MIN, PIPELINE_TILE_PX_MAX, &s->tile_px);
    } else if (!strcmp(a, "--tile-order")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (!tile_order_from_name(val, &s->order)) {
            cli_error("--tile-order: unknown order '%s' (expected one of: %s)", val, TILE_ORDER_NAMES);
            return false;
        }
        return true;
    } else if (!strcmp(a, "--sampler")) {
        tess_error err = {{0}};
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (!pixel_sampler_from_name(val, &s->sampler, &err)) {
            cli_error("--sampler: %s", err.msg);
            return false;
        }
        return true;
    } else if (!strcmp(a, "--budget-ms") || !strcmp(a, "--still-s")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        char *end;
        double v = strtod(val, &end);
        bool budget = !strcmp(a, "--budget-ms");
        if (end == val || *end || !(v >= 0.0 && v <= (budget ? 1e6 : 3600.0))) {
            cli_error("%s: '%s' is not %s", a, val,
                      budget ? "a frame budget in milliseconds (a number in [0, 1e6]; 0: no governor)"
                             : "a time in seconds (a number in [0, 3600])");
            return false;
        }
        *(budget ? &s->budget_ms : &s->still_s) = v;
        return true;
    } else if (!strcmp(a, "--refine-k")) {
        return (val = cli_option_value(argc, argv, i)) && cli_parse_int(a, val, 1, PIXEL_SAMPLER_MAX_K, &s->refine_k);
    } else if (!strcmp(a, "--upscale")) {
        tess_error err = {{0}};
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (!upscale_filter_from_name(val, &s->upscale, &err)) {
            cli_error("--upscale: %s", err.msg);
            return false;
        }
        return true;
    } else if (!strcmp(a, "--renderer")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        const renderer *r = renderer_by_name(val);
        if (!r) {
            cli_error("--renderer: unknown renderer '%s' (expected one of: %s)", val, RENDERER_NAMES);
            return false;
        }
        s->renderer = r;
        return true;
    } else if (!strcmp(a, "--display")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (!display_backend_by_name(val)) {
            char names[256];
            display_backend_names(0, ", ", names, sizeof names);
            cli_error("--display: unknown display '%s' (expected one of: %s)", val, names);
            return false;
        }
        s->display_given = true;
        return copy_value(a, val, main_ch->display, sizeof main_ch->display);
    } else if (!strcmp(a, "--out")) {
        return (val = cli_option_value(argc, argv, i)) && copy_value(a, val, main_ch->out, sizeof main_ch->out);
    } else if (!strcmp(a, "--no-shadows")) {
        s->shadows = false;
        return true;
    } else if (!strcmp(a, "--path")) {
        return (val = cli_option_value(argc, argv, i)) && copy_value(a, val, s->path_file, sizeof s->path_file);
    } else if (!strcmp(a, "--card")) {
        return (val = cli_option_value(argc, argv, i)) && copy_value(a, val, s->card_path, sizeof s->card_path);
    } else if (!strcmp(a, "--wall")) {
        return (val = cli_option_value(argc, argv, i)) && copy_value(a, val, s->wall_file, sizeof s->wall_file);
    } else if (!strcmp(a, "--record")) {
        return (val = cli_option_value(argc, argv, i)) && copy_value(a, val, s->record_file, sizeof s->record_file);
    } else if (!strcmp(a, "--sync-timeout")) {
        return (val = cli_option_value(argc, argv, i)) && cli_parse_double(a, val, 0.1, 3600.0, &s->sync_timeout_s);
    } else if (!strcmp(a, "--input-rank")) {
        return (val = cli_option_value(argc, argv, i)) && cli_parse_int(a, val, 0, WALL_MAX_OUTPUTS - 1, &s->input_rank);
    } else if (!strcmp(a, "--on-node-loss")) {
        if (!(val = cli_option_value(argc, argv, i)))
            return false;
        if (strcmp(val, "stop") && strcmp(val, "carry-on")) {
            cli_error("--on-node-loss: expected stop or carry-on, got '%s'", val);
            return false;
        }
        s->carry_on_node_loss = !strcmp(val, "carry-on");
        return true;
    }
    if (!cli_remote_option(argc, argv, i, &s->remote, handled))
        return false;
    if (*handled)
        return true;
    return cli_input_option(argc, argv, i, &s->input, handled);
}

void cli_pipeline_usage(FILE *f, const char *time_default, const char *rate_default)
{
    fprintf(f,
            "pipeline options (a --config file sets the same; the command line wins):\n"
            "  --config FILE    pipeline config (JSON; docs/pipeline-config.md): components, channels\n"
            "  --threads N      render threads (default: the number of CPUs)\n"
            "  --time real|fixed  frame time: the clock, or frame / rate (reproducible; default %s)\n"
            "  --rate HZ        frames per second of time in fixed mode (default %s)\n",
            time_default, rate_default);
    fputs("  --tile-size N    tile edge in pixels, 4..256 (default 16)\n"
          "  --tile-size N    tile edge in pixels, 4..256 (default 16)\n"
          "  --tile-order O   order tiles are handed out: rows, columns, morton, hilbert, spiral,\n"
          "                   shuffle (default rows; the image does not depend on it)\n"
          "  --sampler S      single, or jittered[:K] (K x K strata per pixel, default K 4)\n"
          "  --renderer R     raytracer (Phong, shadows), eyelight, ao (ambient occlusion alone) or\n"
          "                   raytracer-ao (the raytracer with an ambient-occlusion term) (default raytracer)\n"
          "  --budget-ms MS   frame-time budget: the governor renders moving frames at the scale that\n"
          "                   meets it and refines still ones to jittered:K (default 0: off)\n"
          "  --refine-k K     the governor's converged picture: jittered:K, K x K frames (default 4)\n"
          "  --still-s S      still this long before refining (default 0.25)\n"
          "  --upscale F      how reduced frames are enlarged: bilinear, or clamped-cubic (Catmull-Rom\n"
          "                   clamped to the 2x2 neighbourhood) (default bilinear)\n"
          "  --no-shadows     skip shadow rays\n"
          "  --display D      where frames go, one of:\n",
          f);
    for (size_t i = 0; i < display_backend_count; i++)
        fprintf(f, "                     %-14s %s\n", display_backends[i].name, display_backends[i].what);
    for (size_t i = 0; i < display_backend_count; i++) /* the options of a backend on a device */
        if ((display_backends[i].options & DISPLAY_OPTION_CARD) && display_backends[i].lifecycle &&
            display_backends[i].lifecycle->card_help)
            fprintf(f, "  --card PATH      %s\n", display_backends[i].lifecycle->card_help);
    fputs("  --path FILE      camera path (configs/paths/*.json) for the main channel\n"
          "  --record FILE    write the main channel's camera changes as a camera path\n"
          "  --wall FILE      render a display wall's layout (configs/walls/*.json, docs/wall-format.md):\n"
          "                   one channel per output, each its part of one picture; with the dump\n"
          "                   display each output's image goes beside --out (NAME-CONNECTOR.png) and\n"
          "                   --out gets the stitched wall with the bezels black\n",
          f);
    cli_input_usage(f);
    cli_remote_usage(f);
    fputs("a wall of several machines (mpirun -np N; the wall file's \"nodes\"; cluster/cluster.h):\n"
          "  --sync-timeout S how long the leader waits for a process at a sync point before it gives\n"
          "                   up on it (0.1..3600 s, default 10; the others wait twice as long for it)\n"
          "  --on-node-loss stop|carry-on  when a process dies or hangs: every process shows why and\n"
          "                   exits with status 3 (stop, the default), or the others go on in step and the\n"
          "                   lost machine's outputs stay dark (carry-on; needs mpirun --enable-recovery)\n"
          "  --input-rank R   the process that reads input, plays the path, serves a remote view and\n"
          "                   sends every frame's changes to the others (default 0)\n",
          f);
}

/* ---------------------------------------------------------------- making the pipeline */

/* The wall cli_pipeline_create laid out (for input: where each output is). */
static struct {
    bool valid;
    float plane_aspect;
    int count;
    input_output_area areas[WALL_MAX_OUTPUTS];
} active_layout;

int cli_pipeline_layout(const pipeline *p, float *plane_aspect, input_output_area *areas, int max)
{
    if (active_layout.valid) {
        int n = active_layout.count < max ? active_layout.count : max;
        memcpy(areas, active_layout.areas, (size_t)n * sizeof *areas);
        *plane_aspect = active_layout.plane_aspect;
        return n;
    }
    int channels = cli_remote_channel() >= 0 ? cli_remote_channel() : pipeline_channel_count(p); /* the view's are last */
    int n = channels < max ? channels : max;
    for (int i = 0; i < n; i++) {
        snprintf(areas[i].name, sizeof areas[i].name, "channel-%d", i);
        areas[i].window = CAMERA_WINDOW_FULL;
    }
    camera_basis b = pipeline_channel_basis(p, 0);
    *plane_aspect = (float)b.width_px / (float)b.height_px;
    return n;
}

void cli_pipeline_release_outputs(display_instance *outputs)
{
    display_instance_destroy(outputs);
    active_layout.valid = false;
}

/* The wall's outputs as channels: on a device (a DISPLAY_NEEDS_DEVICE backend, started into
 * *outputs: on a wall of several machines, this process's outputs only), else headless
 * (explicit modes) with the display asked for. */
static bool add_wall_channels(pipeline *p, const cli_pipeline_spec *s, const cli_scene *cs,
                              display_instance **outputs)
{
    tess_error err = {{0}};
    wall_config wall;
    const cli_channel_spec *main_ch = &s->channels[0];
    const display_backend *backend = s->wall_backend ? s->wall_backend : display_backend_by_name(main_ch->display);
    bool on_device = backend->needs & DISPLAY_NEEDS_DEVICE;
    image_display *displays[WALL_MAX_OUTPUTS] = {NULL};
    bool ok = wall_config_load(s->wall_file, &wall, &err);
    display_start_args start = {.card_path = s->card_path};
    if (ok && on_device) /* a wall of several machines: this process's outputs (cluster_cli.h) */
        ok = (*outputs = display_backend_start(backend, &start, cli_cluster_outputs(), &wall, displays, &err));
    else if (ok && !wall_config_headless_sizes(&wall, &err)) /* its messages name the output, not the file */
        ok = false;
    if (!ok) {
        cli_error("%s%s%s", strstr(err.msg, s->wall_file) ? "" : s->wall_file,
                  strstr(err.msg, s->wall_file) ? "" : ": ", err.msg);
        return false;
    }
    int stitched_w, stitched_h;
    wall_stitched_size(&wall, &stitched_w, &stitched_h);
    camera_desc cam;
    if (!cli_scene_camera(cs, main_ch->have_camera ? &main_ch->camera : NULL, stitched_w, stitched_h, &cam)) {
        for (int i = 0; i < wall.count; i++)
            image_display_destroy(displays[i]);
        return false;
    }
    /* a wall of several machines: this process's outputs only (cluster_cli.h) */
    display_backend_args args = {main_ch->out, s->frames != 1, cli_cluster_outputs()};
    ok = on_device || display_backend_create_wall(backend, &wall, &args, displays, &err);
    int first_channel = -1;
    for (int i = 0; ok && i < wall.count; i++) {
        if (!displays[i]) /* another process's output */
            continue;
        int channel = pipeline_add_channel_window(p, &cam, wall_plane_aspect(&wall), wall_output_window(&wall, i),
                                                  wall.outputs[i].width_px, wall.outputs[i].height_px, displays[i],
                                                  &err);
        displays[i] = NULL; /* the pipeline's from pipeline_add_channel_window on, also on failure */
        ok = channel >= 0;
        first_channel = first_channel < 0 ? channel : first_channel;
    }
    for (int i = 0; i < wall.count; i++) /* what a failure left */
        image_display_destroy(displays[i]);
    if (ok) {
        active_layout.valid = true;
        active_layout.plane_aspect = wall_plane_aspect(&wall);
        active_layout.count = wall.count;
        for (int i = 0; i < wall.count; i++) {
            wall_output_label(&wall, i, active_layout.areas[i].name, sizeof active_layout.areas[i].name);
            active_layout.areas[i].window = wall_output_window(&wall, i);
        }
    }
    if (ok && on_device)
        display_instance_attach(*outputs, p, first_channel); /* hotplug switches the outputs' channels */
    if (ok && !cli_remote_add_channel(p, &s->remote, &cam, wall_plane_aspect(&wall)))
        return false;
    /* the status line at the bottom-left corner of the wall's outputs, whatever this process
     * drives (part of the wall: cluster/) and whatever else it renders (a remote view's
     * channels, which show the whole plane) */
    float left = 1.f, bottom = 1.f;
    for (int i = 0; i < wall.count; i++) {
        camera_window w = wall_output_window(&wall, i);
        left = fminf(left, w.center_x - w.half_width);
        bottom = fminf(bottom, w.center_y - w.half_height);
    }
    if (ok && !pipeline_set_status_anchor(p, left, bottom))
        ok = tess_error_set(&err, "the status line's corner (%g, %g) is not a plane point", (double)left,
                            (double)bottom);
    if (!ok)
        cli_error("%s: %s", s->wall_file, err.msg);
    return ok;
}

pipeline_config cli_pipeline_config(const cli_pipeline_spec *s, const cli_scene *cs)
{
    pipeline_config cfg = pipeline_config_default(cs->scene, cs->accel);
    cfg.threads = s->threads;
    cfg.time_mode = s->time_mode;
    cfg.rate_hz = s->rate_hz;
    cfg.max_frames = (uint64_t)s->frames;
    cfg.tile_px = s->tile_px;
    cfg.order = s->order;
    cfg.order_seed = s->order_seed;
    cfg.sampler = s->sampler;
    cfg.renderer = s->renderer;
    cfg.shadows = s->shadows;
    cfg.budget_ms = s->budget_ms;
    cfg.refine_k = s->refine_k;
    cfg.still_s = s->still_s;
    cfg.upscale = s->upscale;
    cfg.render_scale = s->render_scale;
    cfg.settings = s->settings;
    cfg.opacity = s->opacity;
    memcpy(cfg.clip, s->clip, sizeof cfg.clip);
    return cfg;
}

pipeline *cli_pipeline_create(const cli_pipeline_spec *s, const cli_scene *cs, display_instance **outputs)
{
    tess_error err = {{0}};
    *outputs = NULL;
    pipeline_config cfg = cli_pipeline_config(s, cs);
    pipeline *p = pipeline_create(&cfg, &err);
    if (!p) {
        cli_error("%s", err.msg);
        return NULL;
    }
    if (s->wall_file[0]) {
        if (s->channel_count > 1)
            cli_warn("the config's extra channels are ignored with --wall (a wall's channels are its outputs)");
        if (!add_wall_channels(p, s, cs, outputs)) {
            pipeline_destroy(p);
            cli_pipeline_release_outputs(*outputs); /* after the displays that refer to it */
            *outputs = NULL;
            return NULL;
        }
        return p;
    }
    for (int i = 0; i < s->channel_count; i++) {
        const cli_channel_spec *ch = &s->channels[i];
        camera_desc cam;
        if (!cli_scene_camera(cs, ch->have_camera ? &ch->camera : NULL, ch->width_px, ch->height_px, &cam)) {
            pipeline_destroy(p);
            return NULL;
        }
        image_display *d = display_create(ch->display, ch->out, s->frames != 1, &err);
        if (d && s->wrap_display)
            d = s->wrap_display(s->wrap_ctx, i, d, &err);
        if (!d) {
            cli_error("channel %d: %s", i, err.msg);
            pipeline_destroy(p);
            return NULL;
        }
        if (pipeline_add_channel(p, &cam, ch->width_px, ch->height_px, d, &err) < 0) {
            cli_error("%s", err.msg); /* the pipeline's errors name the channel */
            pipeline_destroy(p);
            return NULL;
        }
    }
    /* the remote view follows the main channel: its camera, its picture's aspect */
    camera_desc main_cam = pipeline_camera(p, 0);
    if (!cli_remote_add_channel(p, &s->remote, &main_cam,
                                (float)s->channels[0].width_px / (float)s->channels[0].height_px)) {
        pipeline_destroy(p);
        return NULL;
    }
    return p;
}

/* ---------------------------------------------------------------- path playback, recording */

/* A path's or the orbit's camera (serial section): for a wall the wall's camera, one record
 * for all channels (every output, the remote view's follow channel, not a private view: and
 * on a wall of several machines, what the leader sends: cluster/); else channel 0's and the
 * remote view's, which follows the main picture. */
static void set_main_cameras(pipeline *p, bool all_channels, const camera_desc *c)
{
    if (all_channels) {
        txn_record wall = txn_camera(TXN_ALL_CHANNELS, c);
        pipeline_apply(p, &wall);
        return;
    }
    pipeline_set_camera(p, 0, c);
    if (cli_remote_channel() >= 1)
        pipeline_set_camera(p, cli_remote_channel(), c);
}

static void play_path(pipeline *p, void *ctx, const frame_info *fi)
{
    cli_path_player *pl = ctx;
    camera_desc c = camera_path_eval(&pl->path, fi->time_s + pl->time_offset_s);
    set_main_cameras(p, pl->all_channels, &c);
}

bool cli_path_player_start(pipeline *p, cli_path_player *player)
{
    return pipeline_add_serial_animation(p, "camera path", play_path, player);
}

static void orbit_step(pipeline *p, void *ctx, const frame_info *fi)
{
    cli_orbit *o = ctx;
    camera_desc c = o->start;
    float angle = (float)(6.283185307179586 * fmod(fi->time_s / o->period_s, 1.0));
    vec3 r = v3_sub(c.eye, c.look_at);
    float cs = cosf(angle), sn = sinf(angle);
    c.eye = v3_add(c.look_at, v3(cs * r.x + sn * r.z, r.y, -sn * r.x + cs * r.z));
    set_main_cameras(p, o->all_channels, &c);
}

bool cli_orbit_start(pipeline *p, cli_orbit *orbit, double period_s)
{
    orbit->start = pipeline_camera(p, 0);
    orbit->period_s = period_s;
    return pipeline_add_serial_animation(p, "orbit", orbit_step, orbit);
}

static void record_camera(pipeline *p, void *ctx, const frame_info *fi)
{
    cli_recorder *r = ctx;
    uint64_t serial = pipeline_camera_serial(p, 0);
    if (r->failed || (r->started && serial == r->last_serial))
        return;
    tess_error err = {{0}};
    camera_desc c = pipeline_camera(p, 0);
    if (!camera_path_append(&r->path, fi->time_s, &c, &err)) {
        log_error("--record %s: %s; recording stopped", r->file, err.msg);
        r->failed = true;
    }
    r->started = true;
    r->last_serial = serial;
}

static void save_recording(pipeline *p, void *ctx)
{
    (void)p;
    cli_recorder *r = ctx;
    tess_error err = {{0}};
    if (r->path.count == 0)
        return;
    if (!camera_path_save(&r->path, r->file, &err)) {
        cli_error("%s", err.msg);
        r->failed = true;
    } else {
        fprintf(stderr, "tessera: recorded %zu camera keys to %s\n", r->path.count, r->file);
    }
}

bool cli_recorder_start(pipeline *p, cli_recorder *rec, const char *file)
{
    memset(rec, 0, sizeof *rec);
    rec->file = file;
    rec->path.interp = CAMERA_PATH_LINEAR; /* keys every frame: straight segments are exact enough */
    /* registered after any path player, so it sees the camera the frame will use */
    return pipeline_add_serial_animation(p, "camera recorder", record_camera, rec) &&
           pipeline_add_termination(p, "save recording", save_recording, rec);
}

void cli_pipeline_report(pipeline *p, const cli_pipeline_spec *s)
{
    pipeline_stats st = pipeline_get_stats(p);
    fprintf(stderr,
            "tessera: pipeline: %llu frames rendered, %llu displayed, %llu transactions (%llu refused, %llu slow), "
            "%d channel%s, %d threads\n",
            (unsigned long long)st.frames_rendered, (unsigned long long)st.frames_displayed,
            (unsigned long long)st.transactions_applied,
            (unsigned long long)(st.transactions_rejected + st.transactions_invalid),
            (unsigned long long)st.slow_callbacks, pipeline_channel_count(p), pipeline_channel_count(p) == 1 ? "" : "s",
            s->threads);
    if (s->budget_ms > 0.0)
        fprintf(stderr,
                "tessera: governor (budget %.1f ms): %llu moving frames (%llu at a reduced scale, %llu over the "
                "budget), %llu refining, %llu redrawn for the overlay, %llu idle steps\n",
                s->budget_ms, (unsigned long long)st.frames_scaled, (unsigned long long)st.frames_reduced,
                (unsigned long long)st.frames_over_budget, (unsigned long long)st.frames_accumulated,
                (unsigned long long)st.frames_resolved, (unsigned long long)st.idle_steps);
}
