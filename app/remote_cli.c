/* remote_cli.c - the remote view on the command line and in configs (remote_cli.h). */
#include "remote_cli.h"

#include <math.h>
#include <string.h>

#include "cli.h"
#include "engine/base/log.h"
#include "engine/frame/pipeline.h"

/* The view of the running command (one a process). */
static struct {
    remote_view *view;
    bool started; /* serving */
    bool stopped; /* serving ended and the counts printed */
    remote_channels channels; /* follow -1: none */
    int width_px, height_px;
} active = {NULL, false, false, {-1, -1, 0}, 0, 0};

bool cli_remote_option(int argc, char **argv, int *i, remote_config *c, bool *handled)
{
    const char *a = argv[*i], *val;
    *handled = true;
    if (!strcmp(a, "--remote"))
        return (val = cli_option_value(argc, argv, i)) && cli_parse_int(a, val, 0, 65535, &c->port);
    bool bind = !strcmp(a, "--remote-bind"), token = !strcmp(a, "--remote-token");
    if (!bind && !token) {
        *handled = false;
        return true;
    }
    if (!(val = cli_option_value(argc, argv, i)))
        return false;
    char *out = bind ? c->bind : c->token;
    size_t bytes = bind ? sizeof c->bind : sizeof c->token;
    if (strlen(val) >= bytes) {
        cli_error("%s: value longer than %zu bytes", a, bytes - 1);
        return false;
    }
    snprintf(out, bytes, "%s", val);
    return true;
}

void cli_remote_usage(FILE *f)
{
    fputs("remote view (run; docs/remote-protocol.md, docs/remote-view.md):\n"
          "  --remote PORT    serve the remote view's page on PORT (0: a free one); prints its URL\n"
          "  --remote-bind A  the address to listen on (default 127.0.0.1; 0.0.0.0: every network)\n"
          "  --remote-token T the token the URL must carry (8..64 of A-Z a-z 0-9 - _; default random)\n",
          f);
}

static bool opt_int_in(jr_ctx *jc, json_object *obj, const char *key, int lo, int hi, int *out)
{
    double v = *out;
    if (!jr_opt_double(jc, obj, key, (jr_range){lo, hi, false, false}, &v))
        return false;
    if (v != floor(v))
        return jr_member_fail(jc, key, "expected an integer");
    *out = (int)v;
    return true;
}

static bool opt_text_in(jr_ctx *jc, json_object *obj, const char *key, char *out, size_t bytes)
{
    const char *v = NULL;
    if (!jr_opt_string(jc, obj, key, &v))
        return false;
    if (v && strlen(v) >= bytes)
        return jr_member_fail(jc, key, "too long");
    if (v)
        snprintf(out, bytes, "%s", v);
    return true;
}

bool cli_remote_config_load(jr_ctx *jc, json_object *root, remote_config *c)
{
    static const char *const fields[] = {"port",   "bind",    "token",       "max_viewers",   "width",
                                         "height", "quality", "subsampling", "private_views", NULL};
    static const char *const subsamplings[] = {"444", "422", "420", NULL};
    json_object *m;
    if (!jr_get_member(root, "remote", &m))
        return true;
    size_t saved = jr_field_key(jc, "remote");
    int sub = (int)c->subsampling;
    if (c->port < 0)
        c->port = 0; /* an object without a port: a free one */
    bool ok = jr_expect_object(jc, m) && jr_check_fields(jc, m, fields) &&
              opt_int_in(jc, m, "port", 0, 65535, &c->port) && opt_text_in(jc, m, "bind", c->bind, sizeof c->bind) &&
              opt_text_in(jc, m, "token", c->token, sizeof c->token) &&
              opt_int_in(jc, m, "max_viewers", 1, INPUT_MAX_VIEWERS, &c->max_viewers) &&
              opt_int_in(jc, m, "private_views", 0, INPUT_MAX_VIEWERS, &c->private_views) &&
              opt_int_in(jc, m, "width", 16, 4096, &c->width_px) && opt_int_in(jc, m, "height", 16, 4096, &c->height_px) &&
              opt_int_in(jc, m, "quality", REMOTE_JPEG_QUALITY_MIN, REMOTE_JPEG_QUALITY_MAX, &c->quality) &&
              jr_opt_choice(jc, m, "subsampling", subsamplings, &sub);
    tess_error err = {{0}};
    if (ok && !remote_config_validate(c, &err)) /* bind, token characters */
        ok = jr_field_fail(jc, "%s", err.msg);
    jr_field_leave(jc, saved);
    c->subsampling = (remote_subsampling)sub;
    return ok;
}

bool cli_remote_add_channel(struct pipeline *p, const remote_config *c, const camera_desc *camera, float plane_aspect)
{
    if (c->port < 0)
        return true;
    tess_error err = {{0}};
    /* the plane's aspect fitted inside width x height */
    int w = c->width_px, h = (int)lround((double)w / (double)plane_aspect);
    if (h > c->height_px) {
        h = c->height_px;
        w = (int)lround((double)h * (double)plane_aspect);
    }
    w = w < 16 ? 16 : w;
    h = h < 16 ? 16 : h;
    remote_view *v = remote_view_create(c, &err);
    int channel = v ? pipeline_add_channel_window(p, camera, plane_aspect, CAMERA_WINDOW_FULL, w, h,
                                                  remote_view_display(v), &err)
                    : -1;
    if (channel < 0) {
        cli_error("%s", err.msg);
        remote_view_destroy(v);
        return false;
    }
    /* the private channels: the same size and plane, made private; as many as the pipeline has room for */
    int room = PIPELINE_MAX_CHANNELS - pipeline_channel_count(p), privates = remote_view_private_count(v);
    if (privates > room) {
        log_warn("remote view: %d private views, not %d: the pipeline has room for %d channels more "
                 "(remote.private_views)",
                 room, privates, room);
        privates = room;
    }
    int first = pipeline_channel_count(p);
    for (int k = 0; k < privates && channel >= 0; k++) {
        int added = pipeline_add_channel_window(p, camera, plane_aspect, CAMERA_WINDOW_FULL, w, h,
                                                remote_view_private_display(v, k), &err);
        if (added < 0 || !pipeline_set_channel_private(p, added, &err))
            channel = -1;
    }
    if (channel < 0) {
        cli_error("%s", err.msg);
        remote_view_destroy(v);
        return false;
    }
    active.view = v;
    active.started = active.stopped = false;
    active.channels = (remote_channels){.follow = channel, .private_first = first, .private_count = privates};
    active.width_px = w;
    active.height_px = h;
    return true;
}

int cli_remote_channel(void) { return active.view ? active.channels.follow : -1; }

input_source *cli_remote_take_source(void) { return active.view ? remote_view_take_source(active.view) : NULL; }

bool cli_remote_start(struct pipeline *p)
{
    if (!active.view)
        return true;
    tess_error err = {{0}};
    if (!remote_view_start(active.view, p, &active.channels, active.width_px, active.height_px, CAMERA_WINDOW_FULL,
                           &err)) {
        cli_error("%s", err.msg);
        return false;
    }
    active.started = true;
    return true;
}

void cli_remote_stop(void)
{
    if (!active.view || active.stopped)
        return;
    active.stopped = true;
    remote_view_stop(active.view);
    if (active.started)
        remote_view_print_stats(active.view, stderr);
}

void cli_remote_release(void)
{
    remote_view_destroy(active.view);
    active.view = NULL;
    active.channels = (remote_channels){-1, -1, 0};
}
