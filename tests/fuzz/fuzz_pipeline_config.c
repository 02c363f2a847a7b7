/* fuzz_pipeline_config.c - pipeline configs (--config FILE,
 * app/pipeline_cli.c, with the "input" object of app/input_cli.c)
 * through cli_pipeline_config_parse. Its errors go to stderr through
 * cli_error (run.sh silences it with -close_fd_mask=2); what a parse accepts
 * must be within the documented ranges. */
#include "fuzz.h"

#include <string.h>

#include "app/pipeline_cli.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *name = "/fuzz/config.json";
    static cli_pipeline_spec s;
    cli_pipeline_spec_default(&s, "dump", "out/render.png");
    if (!cli_pipeline_config_parse(name, (const char *)data, size, &s))
        return 0;
    if (s.threads < 1 || s.threads > PIPELINE_MAX_THREADS)
        fuzz_fail("%s: %d threads", name, s.threads);
    if (s.channel_count < 1 || s.channel_count > PIPELINE_MAX_CHANNELS)
        fuzz_fail("%s: %d channels", name, s.channel_count);
    if (!s.renderer)
        fuzz_fail("%s: no renderer", name);
    for (int i = 0; i < s.channel_count; i++) {
        const cli_channel_spec *c = &s.channels[i];
        if (c->width_px < 1 || c->height_px < 1)
            fuzz_fail("%s: channel %d is %dx%d", name, i, c->width_px, c->height_px);
        if (!memchr(c->display, '\0', sizeof c->display) || !memchr(c->out, '\0', sizeof c->out))
            fuzz_fail("%s: channel %d: a name is not terminated", name, i);
        tess_error err = {{0}};
        if (c->have_camera && !camera_validate(&c->camera, &err))
            fuzz_fail("%s: channel %d: an invalid camera was accepted: %s", name, i, err.msg);
    }
    if (!memchr(s.path_file, '\0', sizeof s.path_file))
        fuzz_fail("%s: path not terminated", name);
    return 0;
}
