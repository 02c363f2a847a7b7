/* test_cli_ignored.c - options that do not apply are said, never silently
 * dropped (app/option_check.h): render and run warn and go on (exit 0,
 * the same result as without the option); the benchmarks refuse (exit 2).
 * Runs ../tessera (or $TESSERA_BIN) from the tests/ directory. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <string.h>

#include "support.h"

#define OUT_BYTES 16384
#define RUN_TIMEOUT_S 120

/* A small wall (two 64x36 outputs side by side) and a config with an extra channel. */
static const char wall_json[] = "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                                "{\"connector\": \"A-1\", \"mode\": \"64x36@60\", \"grid\": [0, 0], \"size_mm\": [64, 36]},"
                                "{\"connector\": \"A-2\", \"mode\": \"64x36@60\", \"grid\": [1, 0], \"size_mm\": [64, 36]}]}";
static const char channels_json[] = "{\"channels\": [{\"size\": [16, 9], \"display\": {\"name\": \"null\"}}]}";

static char dir[256];

static void setup(void)
{
    support_make_tmp_dir(dir, sizeof dir, "cli-ignored");
    support_write_file(dir, "wall.json", wall_json);
    support_write_file(dir, "channels.json", channels_json);
}

static void teardown(void) { support_remove_tmp_dir(dir); }

TestSuite(cli_ignored, .init = setup, .fini = teardown, .timeout = 240);

/* `tessera ARGS` goes on (exit 0) and says `warning` (NULL: warns about nothing). */
static void expect_warning(const char *args, const char *warning)
{
    char out[OUT_BYTES];
    int code = support_tessera(dir, RUN_TIMEOUT_S, out, sizeof out, args);
    cr_expect_eq(code, 0, "'%s': exit %d: %s", args, code, out);
    if (warning) {
        char line[512];
        snprintf(line, sizeof line, "tessera: warning: %s\n", warning);
        cr_expect(strstr(out, line), "'%s' does not say '%s': %s", args, warning, out);
    } else {
        cr_expect(!strstr(out, "warning"), "'%s' warns about nothing ignored: %s", args, out);
    }
}

/* `tessera ARGS` refuses with exit 2 and says `error`. */
static void expect_refusal(const char *args, const char *error)
{
    char out[OUT_BYTES];
    int code = support_tessera(dir, RUN_TIMEOUT_S, out, sizeof out, args);
    cr_expect_eq(code, 2, "'%s': exit %d (expected 2): %s", args, code, out);
    cr_expect(strstr(out, error), "'%s' does not say '%s': %s", args, error, out);
}

Test(cli_ignored, size_with_a_wall)
{
    expect_warning("render --wall %s/wall.json --size 1000x580 --out %s/wall.png --threads 2",
                   "--size is ignored with --wall (each output's size comes from the wall config)");
    int w, h;
    float *rgb = support_read_image(dir, "wall-A-1.png", &w, &h);
    cr_expect(w == 64 && h == 36, "the output's image is %dx%d, not the wall's 64x36", w, h);
    free(rgb);
    expect_warning("run --wall %s/wall.json --size 100x50 --display null --frames 2 --threads 2",
                   "--size is ignored with --wall (each output's size comes from the wall config)");
}

Test(cli_ignored, out_without_the_dump_display)
{
    expect_warning("run --display null --out %s/frames.png --size 32x18 --frames 2 --threads 2",
                   "--out is ignored with --display null (only the dump display writes files)");
    expect_warning("render --display convert --out %s/x.png --size 32x18 --threads 2",
                   "--out is ignored with --display convert (only the dump display writes files)");
}

Test(cli_ignored, rate_in_real_time)
{
    expect_warning("run --time real --rate 10 --display null --size 32x18 --frames 2 --threads 2",
                   "--rate is ignored in real time (it is the frame rate of --time fixed)");
    expect_warning("run --time fixed --rate 10 --display null --size 32x18 --frames 2 --threads 2", NULL);
}

Test(cli_ignored, card_without_the_drm_display)
{
    expect_warning("render --card /dev/dri/card7 --out %s/x.png --size 32x18 --threads 2",
                   "--card is ignored with --display dump (only the drm display drives a card)");
}

Test(cli_ignored, camera_with_a_path)
{
    expect_warning("render --path ../configs/paths/orbit.json --camera 0,1,5,0,0,0,0,1,0,40 --display null "
                   "--size 32x18 --frames 2 --threads 2",
                   "--camera is ignored with --path (the path sets the camera from the first frame)");
}

Test(cli_ignored, input_options_without_input)
{
    expect_warning("run --input off --tour ../configs/paths/tour.json --display null --size 32x18 --frames 2 --threads 2",
                   "--tour is ignored: 'tessera run' reads no input devices here (--input on, the default on a DRM "
                   "wall, turns them on)");
    expect_warning("render --idle-timeout 5 --display null --size 32x18 --threads 2",
                   "--idle-timeout is ignored: 'tessera render' reads no input devices here (render never does; "
                   "'tessera run' can)");
    expect_warning("run --replay-speed frames --display null --size 32x18 --frames 2 --threads 2",
                   "--replay-speed is ignored without --replay-input");
}

Test(cli_ignored, extra_config_channels_with_a_wall)
{
    char out[OUT_BYTES];
    int code = support_tessera(dir, RUN_TIMEOUT_S, out, sizeof out,
                               "run --config %s/channels.json --wall %s/wall.json --display null --frames 2 --threads 2");
    cr_expect_eq(code, 0, "exit %d: %s", code, out);
    cr_expect(strstr(out, "tessera: warning: the config's extra channels are ignored with --wall"), "%s", out);
    cr_expect(!strstr(out, "error"), "a warning, not an error line: %s", out);
}

Test(cli_ignored, render_scale_options_that_do_not_apply)
{
    expect_warning("render --size 32x18 --upscale clamped-cubic --out %s/x.png --threads 2",
                   "--upscale is ignored at --scale 1 without --budget-ms (the image is rendered at full size: nothing "
                   "is upscaled)");
    expect_warning("render --size 32x18 --scale 1 --upscale bilinear --out %s/x.png --threads 2",
                   "--upscale is ignored at --scale 1 without --budget-ms (the image is rendered at full size: nothing "
                   "is upscaled)");
    /* a wall renders every output at the scale (the same in every output), each at its own size */
    expect_warning("render --wall %s/wall.json --scale 1/2 --upscale clamped-cubic --out %s/wall.png --threads 2",
                   NULL);
    int w, h;
    float *rgb = support_read_image(dir, "wall-A-1.png", &w, &h);
    cr_expect(w == 64 && h == 36, "the output's image is %dx%d, not the wall's 64x36", w, h);
    free(rgb);
}

/* The governor's own options say when there is no governor to steer. */
Test(cli_ignored, governor_options_without_a_budget)
{
    expect_warning("render --size 32x18 --refine-k 2 --out %s/x.png --threads 2",
                   "--refine-k is ignored without --budget-ms (it steers the frame-budget governor)");
    expect_warning("render --size 32x18 --still-s 0 --out %s/x.png --threads 2",
                   "--still-s is ignored without --budget-ms (it steers the frame-budget governor)");
    expect_warning("render --size 32x18 --budget-ms 50 --upscale clamped-cubic --refine-k 2 --still-s 0 "
                   "--out %s/x.png --threads 2",
                   NULL);
    expect_refusal("render --size 32x18 --budget-ms 50 --scale 1/2 --out x.png",
                   "--scale 1/2 and --budget-ms 50: choose one (with a budget the governor picks the scale)");
    expect_refusal("render --size 32x18 --budget-ms -3 --out x.png",
                   "--budget-ms: '-3' is not a frame budget in milliseconds (a number in [0, 1e6]; 0: no governor)");
}

/* Everything given applies: not a word. */
Test(cli_ignored, nothing_said_when_every_option_applies)
{
    expect_warning("render --size 32x18 --out %s/x.png --camera 0,1,5,0,0,0,0,1,0,40 --threads 2 --rate 12 "
                   "--tile-size 8 --sampler single",
                   NULL);
    expect_warning("render --size 32x18 --out %s/x.png --scale 1/2 --upscale clamped-cubic --threads 2", NULL);
    expect_warning("run --size 32x18 --display dump --out %s/f_####.png --frames 2 --threads 2 --time fixed --rate 10",
                   NULL);
}

Test(cli_ignored, benchmarks_refuse_what_they_cannot_honour)
{
    expect_refusal("bench --path ../configs/paths/orbit.json --frames 3 --size 32x18",
                   "--frames: not an option of bench --path (it renders until the path's transactions are done)");
    expect_refusal("bench --path ../configs/paths/orbit.json --time fixed --size 32x18",
                   "--time: not an option of bench --path");
    expect_refusal("bench --path ../configs/paths/orbit.json --rounds 2 --size 32x18",
                   "--rounds: not an option of bench --path (--rounds is for --scaling)");
    expect_refusal("bench --scaling --time real --size 32x18", "--time: not an option of bench --scaling");
    expect_refusal("bench --scaling --input on --size 32x18",
                   "--input: not an option of bench --scaling (benchmarks read no input; 'tessera run' does)");
    expect_refusal("bench --wall %s/wall.json --tour ../configs/paths/tour.json",
                   "--tour: not an option of bench --wall (benchmarks read no input; 'tessera run' does)");
}
