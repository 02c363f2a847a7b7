/* test_input_cli.c - the input options and the config's "input" object through
 * the tessera binary: bad values and config fields get errors naming the
 * option, file and field; a mapping to an output the wall lacks is refused;
 * --replay-input steers a render (and a broken record names its line);
 * --record-input writes the header and invents no transactions. */
#define _DEFAULT_SOURCE /* usleep */
#include <criterion/criterion.h>
#include <fcntl.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "engine/base/camera.h"
#include "input/controller.h"
#include "input/record.h"
#include "support.h"

#define TIMEOUT_S 60
/* a udev seat no device is on, so a run with input on opens none even where
 * /dev/input has devices */
#define NO_DEVICES "--seat tessera-test-no-such-seat"
#define OUT_BYTES 16384

static char tmp_dir[256];

static void make_tmp_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "inputcli"); }

static void remove_tmp_dir(void) { support_remove_tmp_dir(tmp_dir); }

TestSuite(input_cli, .init = make_tmp_dir, .fini = remove_tmp_dir, .timeout = 120);

static char out_text[OUT_BYTES], err_text[OUT_BYTES];

/* Run `tessera ARGS` (every %s in args_fmt, up to 4, is the temp dir) with
 * stdout and stderr kept apart in out_text and err_text; the exit status. */
static int run(const char *args_fmt)
{
    char args[4096], cmd[8192], out_path[512], err_path[512];
    snprintf(args, sizeof args, args_fmt, tmp_dir, tmp_dir, tmp_dir, tmp_dir);
    snprintf(out_path, sizeof out_path, "%s/cli.out", tmp_dir);
    snprintf(err_path, sizeof err_path, "%s/cli.err", tmp_dir);
    snprintf(cmd, sizeof cmd, "timeout %d %s %s > '%s' 2> '%s'", TIMEOUT_S, support_tessera_bin(), args, out_path,
             err_path);
    int code = support_run(cmd);
    support_read_text(out_path, out_text, sizeof out_text);
    support_read_text(err_path, err_text, sizeof err_text);
    return code;
}

/* An exit status for expect_error_code: 1 (a failed run) or 2 (a bad option). */
#define FAILED_CLEANLY (-1)

/* `tessera ARGS` exits with `code` (FAILED_CLEANLY: 1 or 2), and its stderr
 * has an error line with every one of the NULL-terminated needles; nothing
 * was rendered. */
static void expect_error_code(int code, const char *args_fmt, const char *const *needles)
{
    int got = run(args_fmt);
    if (code == FAILED_CLEANLY)
        cr_expect(got == 1 || got == 2, "'%s': exit %d, expected 1 or 2\nstderr: %s\nstdout: %s", args_fmt, got,
                  err_text, out_text);
    else
        cr_expect_eq(got, code, "'%s': exit %d, expected %d\nstderr: %s\nstdout: %s", args_fmt, got, code,
                     err_text, out_text);
    cr_expect(strstr(err_text, "error") != NULL, "'%s': no error line on stderr: %s", args_fmt, err_text);
    for (const char *const *n = needles; *n; n++)
        cr_expect(strstr(err_text, *n) != NULL, "'%s': stderr lacks '%s': %s", args_fmt, *n, err_text);
    cr_expect(strstr(err_text, "frames rendered") == NULL, "'%s': it ran the pipeline anyway: %s", args_fmt,
              err_text);
}

#define EXPECT_ERROR(code, args, ...) expect_error_code(code, args, (const char *const[]){__VA_ARGS__, NULL})

static void write_file(const char *name, const char *text) { support_write_file(tmp_dir, name, text); }

static void read_file(const char *name, char *out, size_t out_bytes)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", tmp_dir, name);
    support_read_text(path, out, out_bytes);
}

/* ---- bad option values ------------------------------------------------------------------ */

Test(input_cli, bad_option_values_name_the_option_and_the_value)
{
    EXPECT_ERROR(2, "run --input maybe --display null --frames 1 --size 32x18", "--input", "'maybe'", "on or off");
    EXPECT_ERROR(2, "run --replay-speed fast --display null --frames 1 --size 32x18", "--replay-speed", "'fast'",
                 "recorded, frames, all");
    EXPECT_ERROR(2, "run --idle-timeout -1 --display null --frames 1 --size 32x18", "--idle-timeout", "'-1'",
                 "seconds");
    EXPECT_ERROR(2, "run --idle-timeout abc --display null --frames 1 --size 32x18", "--idle-timeout", "'abc'",
                 "seconds");
    EXPECT_ERROR(2, "run --map-input nothing --display null --frames 1 --size 32x18", "--map-input", "'nothing'",
                 "DEVICE=OUTPUT");
    EXPECT_ERROR(2, "run --map-input =Virtual-1 --display null --frames 1 --size 32x18", "--map-input",
                 "'=Virtual-1'", "DEVICE=OUTPUT");
    EXPECT_ERROR(2, "run --map-input dev= --display null --frames 1 --size 32x18", "--map-input", "'dev='",
                 "DEVICE=OUTPUT");
    /* an option with no value at all */
    EXPECT_ERROR(2, "run --display null --frames 1 --size 32x18 --map-input", "--map-input");
    /* and the good values of the same options are accepted (input off: nothing is opened) */
    int code = run("run --input off --replay-speed frames --idle-timeout 0 --display null --frames 1 --size 32x18 "
                   "--threads 1");
    cr_expect_eq(code, 0, "good input option values refused: %s", err_text);
}

static void repeat_option(char *args, size_t size, const char *head, const char *option, const char *value_fmt,
                          int count, const char *tail)
{
    size_t n = (size_t)snprintf(args, size, "%s", head);
    for (int i = 0; i < count && n < size; i++) {
        n += (size_t)snprintf(args + n, size - n, " %s ", option);
        n += (size_t)snprintf(args + n, size - n, value_fmt, i);
    }
    cr_assert(n < size);
    snprintf(args + n, size - n, " %s", tail);
}

Test(input_cli, at_most_16_device_mappings_and_16_devices)
{
    char args[4096];
    const char *tail = "--display null --frames 1 --size 32x18 --threads 1";
    /* 16 of each are fine (input off: the devices are never opened) */
    repeat_option(args, sizeof args, "run --input off --wall ../configs/walls/vm_2x2.json --renderer eyelight",
                  "--map-input", "dev%d=Virtual-1", 16, "--display null --frames 1 --threads 2");
    cr_expect_eq(run(args), 0, "16 --map-input refused: %s", err_text);
    repeat_option(args, sizeof args, "run --input off", "--input-device", "/dev/input/event%d", 16, tail);
    cr_expect_eq(run(args), 0, "16 --input-device refused: %s", err_text);
    /* the 17th is refused, naming the option and the limit */
    repeat_option(args, sizeof args, "run --input off", "--map-input", "dev%d=Virtual-1", 17, tail);
    EXPECT_ERROR(2, args, "--map-input", "more than 16");
    repeat_option(args, sizeof args, "run --input off", "--input-device", "/dev/input/event%d", 17, tail);
    EXPECT_ERROR(2, args, "--input-device", "more than 16");
}

/* Bindings load only when input starts (today: after the scene is loaded
 * and the pipeline made, exit 1), but before any frame. */
Test(input_cli, a_missing_bindings_file_fails_before_any_frame)
{
    EXPECT_ERROR(FAILED_CLEANLY,
                 "run --input on --bindings %s/nope.json --display null --frames 1 --size 32x18 --threads 1",
                 "nope.json", "cannot open");
    /* the same bindings option with the built-in file is fine */
    int code = run("run --input on " NO_DEVICES " --bindings ../configs/bindings.json --display null --frames 1 "
                   "--size 32x18 --threads 1");
    cr_expect_eq(code, 0, "--bindings configs/bindings.json refused: %s", err_text);
}

Test(input_cli, render_refuses_live_input)
{
    EXPECT_ERROR(2, "render --input on --out %s/a.exr --size 32x18", "--input on", "render", "run");
    cr_expect(strstr(err_text, "scene (") == NULL, "render loaded the scene before refusing: %s", err_text);
    /* from a config too */
    write_file("on.json", "{\"input\": {\"enabled\": true}}");
    EXPECT_ERROR(2, "render --config %s/on.json --out %s/a.exr --size 32x18", "render", "input");
    /* --input off is fine */
    cr_expect_eq(run("render --input off --out %s/off.exr --size 32x18 --threads 1"), 0, "%s", err_text);
}

/* ---- replay: errors -------------------------------------------------------------------- */

Test(input_cli, replay_of_a_missing_file_names_it)
{
    EXPECT_ERROR(1, "render --replay-input %s/missing.rec --out %s/a.exr --size 32x18 --threads 1",
                 "--replay-input", "missing.rec", "cannot open");
    char text[64];
    read_file("a.exr", text, sizeof text);
    cr_expect(text[0] == '\0', "an image was written anyway");
}

/* A camera line in %a as the recorder writes it (time 0.5). */
static void camera_line(FILE *f, camera_desc c)
{
    input_txn t = txn_camera(TXN_ALL_CHANNELS, &c);
    cr_assert(input_record_write(f, 0.5, &t));
}

static const camera_desc top_camera = {{0.f, 8.f, 3.f}, {0.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, 60.f};

/* dir/name: the header, a comment, a good camera line, then `tail` lines. */
static void write_record(const char *name, const char *tail)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", tmp_dir, name);
    FILE *f = fopen(path, "w");
    cr_assert(f, "cannot write %s", path);
    fprintf(f, "%s\n# written by test_input_cli\n", INPUT_RECORD_HEADER);
    camera_line(f, top_camera);
    fputs(tail, f);
    fclose(f);
}

Test(input_cli, a_broken_record_names_the_file_the_line_and_the_problem)
{
    write_record("bad_number.rec", "0.75 camera all 0x1p+0 zz 0x0p+0 0x0p+0 0x0p+0 0x0p+0 0x0p+0 0x1p+0 0x0p+0 "
                                   "0x1.ep+5\n");
    EXPECT_ERROR(1, "render --replay-input %s/bad_number.rec --out %s/a.exr --size 32x18 --threads 1",
                 "--replay-input", "bad_number.rec:4:", "camera eye.y", "'zz'");
    write_record("bad_kind.rec", "\n0.75 teleport 1\n");
    EXPECT_ERROR(1, "render --replay-input %s/bad_kind.rec --out %s/a.exr --size 32x18 --threads 1",
                 "bad_kind.rec:5:", "unknown transaction kind 'teleport'");
    write_record("backwards.rec", "0.25 quit\n");
    EXPECT_ERROR(1, "render --replay-input %s/backwards.rec --out %s/a.exr --size 32x18 --threads 1",
                 "backwards.rec:4:", "before the previous line");
    write_file("noheader.rec", "0.5 quit\n");
    EXPECT_ERROR(1, "render --replay-input %s/noheader.rec --out %s/a.exr --size 32x18 --threads 1",
                 "noheader.rec:1:", INPUT_RECORD_HEADER);
}

/* A record the scene cannot take (an instance or a channel it does not have): render's replay
 * is a reproduction, so that is an error naming the line, before anything is rendered; run
 * (a kiosk) logs it with its line, counts it in the summary and goes on. */
Test(input_cli, a_replayed_record_the_scene_refuses)
{
    write_record("past.rec", "0.75 hide 0 1\n0.75 hide 99 5\n0.8 camera 5 0x1p+0 0x1p+0 0x1p+0 0x0p+0 0x0p+0 "
                             "0x0p+0 0x0p+0 0x1p+0 0x0p+0 0x1.ep+5\n0.9 show-all\n");
    EXPECT_ERROR(1, "render --replay-input %s/past.rec --out %s/a.png --size 32x18 --threads 1",
                 "--replay-input", "past.rec:5: hide: instances 99..103: the scene has",
                 "past.rec:6: camera: no channel 5 (there are 1)", "2 of 5 records refused", "nothing rendered");
    char text[64];
    read_file("a.png", text, sizeof text);
    cr_expect(text[0] == '\0', "an image was written anyway");
    /* run: logged with the line, counted, the run goes on */
    cr_assert_eq(run("run --replay-input %s/past.rec --replay-speed all --display null --frames 2 --size 32x18 "
                     "--threads 1"),
                 0, "%s", err_text);
    cr_expect(strstr(err_text, "transaction refused: --replay-input") && strstr(err_text, "past.rec:5: hide: "
                                                                                        "instances 99..103"),
              "%s", err_text);
    cr_expect(strstr(err_text, "past.rec:6: camera: no channel 5"), "%s", err_text);
    cr_expect(strstr(err_text, "(2 refused, "), "the summary does not count them: %s", err_text);
}

Test(input_cli, path_and_replay_together_are_refused)
{
    write_record("ok.rec", "");
    EXPECT_ERROR(2,
                 "run --path ../configs/paths/flythrough.json --replay-input %s/ok.rec --display null --frames 1 "
                 "--size 32x18 --threads 1",
                 "--path", "--replay-input");
    cr_expect(strstr(err_text, "scene (") == NULL, "the scene was loaded before refusing: %s", err_text);
    EXPECT_ERROR(2,
                 "render --path ../configs/paths/flythrough.json --replay-input %s/ok.rec --out %s/a.exr "
                 "--size 32x18 --threads 1",
                 "--path", "--replay-input");
    /* the replay alone is fine */
    cr_expect_eq(run("run --replay-input %s/ok.rec --display null --frames 1 --size 32x18 --threads 1"), 0, "%s",
                 err_text);
}

/* ---- the config's "input" object -------------------------------------------------------- */

Test(input_cli, config_input_errors_name_the_file_and_the_field)
{
    static const struct {
        const char *file, *json, *field, *problem;
    } cases[] = {
        {"xyz.json", "{\"input\": {\"xyz\": 1}}", "'input.xyz'", "unknown field"},
        {"idle.json", "{\"input\": {\"idle_timeout_s\": -1}}", "'input.idle_timeout_s'", "-1"},
        {"mapout.json", "{\"input\": {\"map\": [{\"device\": \"a\"}]}}", "'input.map[0].output'", "missing"},
        {"mapobj.json", "{\"input\": {\"map\": {\"device\": \"a\", \"output\": \"b\"}}}", "'input.map'",
         "expected an array"},
        {"mapfield.json", "{\"input\": {\"map\": [{\"device\": \"a\", \"output\": \"b\", \"screen\": 1}]}}",
         "'input.map[0].screen'", "unknown field"},
        {"devs.json", "{\"input\": {\"devices\": [\"\"]}}", "'input.devices[0]'", "empty path"},
        {"devnum.json", "{\"input\": {\"devices\": [\"/dev/input/event0\", 3]}}", "'input.devices[1]'", "number"},
        {"enabled.json", "{\"input\": {\"enabled\": \"yes\"}}", "'input.enabled'", "boolean"},
        {"ease.json", "{\"input\": {\"tour_ease_s\": 0}}", "'input.tour_ease_s'", "(0, 600]"},
        {"notobj.json", "{\"input\": 3}", "'input'", "expected an object"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        write_file(cases[i].file, cases[i].json);
        char args[512];
        snprintf(args, sizeof args, "run --config %%s/%s --display null --frames 1 --size 32x18 --threads 1",
                 cases[i].file);
        EXPECT_ERROR(2, args, cases[i].file, cases[i].field, cases[i].problem);
    }
    /* a good input object is accepted (input off: nothing opened) */
    write_file("good.json", "{\"input\": {\"enabled\": false, \"seat\": \"seat0\", \"idle_timeout_s\": 0,"
                            " \"tour_ease_s\": 0.5, \"devices\": [\"/dev/input/event0\"],"
                            " \"map\": [{\"device\": \"a\", \"output\": \"Virtual-1\"}]}}");
    cr_expect_eq(run("run --config %s/good.json --display null --frames 1 --size 32x18 --threads 1"), 0, "%s",
                 err_text);
}

/* ---- a mapping to an output the wall does not have -------------------------------------- */

/* With no /dev/input libinput's udev backend still opens (no devices); the
 * mapping is checked against the wall's connectors when input starts. */
Test(input_cli, a_mapping_to_an_output_the_wall_lacks_is_refused)
{
    EXPECT_ERROR(1, "run --wall ../configs/walls/vm_2x2.json --display null --input on --map-input dev=HDMI-A-9 "
                    "--frames 2 --threads 2",
                 "HDMI-A-9", "'dev'", "not one of the outputs (Virtual-1, Virtual-2, Virtual-3, Virtual-4)");
    /* the same from a config */
    write_file("map.json", "{\"input\": {\"enabled\": true, \"map\": [{\"device\": \"touch\", \"output\": "
                           "\"DP-7\"}]}}");
    EXPECT_ERROR(1, "run --config %s/map.json --wall ../configs/walls/vm_2x2.json --display null --frames 2 "
                    "--threads 2",
                 "DP-7", "'touch'", "not one of the outputs");
    /* an output it has is fine, and the run goes on with no devices */
    int code = run("run --wall ../configs/walls/vm_2x2.json --display null --input on " NO_DEVICES
                   " --map-input dev=Virtual-3 --frames 1 --threads 2 --renderer eyelight");
    cr_expect_eq(code, 0, "a mapping to Virtual-3 refused: %s", err_text);
    cr_expect(strstr(err_text, "1 frames rendered") != NULL, "%s", err_text);
}

/* ---- replay and record that work -------------------------------------------------------- */

static float *read_image(const char *name, int *w, int *h) { return support_read_image(tmp_dir, name, w, h); }

static bool same_pixels(const char *a, const char *b)
{
    int wa, ha, wb, hb;
    float *pa = read_image(a, &wa, &ha), *pb = read_image(b, &wb, &hb);
    cr_assert(wa == wb && ha == hb, "%s is %dx%d, %s %dx%d", a, wa, ha, b, wb, hb);
    bool same = !memcmp(pa, pb, (size_t)wa * ha * 3 * sizeof(float));
    free(pa);
    free(pb);
    return same;
}

Test(input_cli, replayed_camera_moves_the_render)
{
    /* the camera, then a status line: the camera moves and the status line is drawn */
    write_record("move.rec", "0.75 status \"hello\"\n");
    int code = run("render --replay-input %s/move.rec --out %s/replay.exr --size 32x18 --threads 1");
    cr_assert_eq(code, 0, "replay render failed: %s", err_text);
    cr_expect(strstr(err_text, "replaying 2 input transactions") != NULL, "%s", err_text);
    cr_assert_eq(run("render --out %s/plain.exr --size 32x18 --threads 1"), 0, "%s", err_text);
    int w, h;
    free(read_image("replay.exr", &w, &h));
    cr_expect(w == 32 && h == 18, "replay image %dx%d", w, h);
    cr_expect(!same_pixels("replay.exr", "plain.exr"), "the replay did not change the image");
    /* the camera alone: exactly the image of that camera */
    write_record("cam.rec", "");
    cr_assert_eq(run("render --replay-input %s/cam.rec --out %s/cam.exr --size 32x18 --threads 1"), 0, "%s",
                 err_text);
    cr_assert_eq(run("render --camera 0,8,3,0,0,0,0,1,0,60 --out %s/top.exr --size 32x18 --threads 1"), 0, "%s",
                 err_text);
    cr_expect(!same_pixels("cam.exr", "plain.exr"), "the replayed camera did not move the image");
    cr_expect(same_pixels("cam.exr", "top.exr"), "the replay differs from a render of the recorded camera");
    /* and the status line is drawn over that */
    cr_expect(!same_pixels("replay.exr", "cam.exr"), "the replayed status line was not drawn");
}

Test(input_cli, record_input_writes_the_header_and_invents_nothing)
{
    char text[4096];
    cr_assert_eq(run("run --input off --record-input %s/off.rec --frames 2 --display null --size 32x18 "
                     "--threads 1"),
                 0, "%s", err_text);
    read_file("off.rec", text, sizeof text);
    cr_expect_str_eq(text, INPUT_RECORD_HEADER "\n");
    /* with input on (the input thread runs), no devices and no tour (which would start at once: nobody is
     * there): still only the header */
    cr_assert_eq(run("run --input on " NO_DEVICES " --idle-timeout 0 --record-input %s/on.rec --frames 2 --display null "
                     "--size 32x18 --threads 1"),
                 0, "%s", err_text);
    read_file("on.rec", text, sizeof text);
    cr_expect_str_eq(text, INPUT_RECORD_HEADER "\n");
    /* and it replays as an empty record */
    cr_assert_eq(run("render --replay-input %s/on.rec --out %s/a.exr --size 32x18 --threads 1"), 0, "%s", err_text);
    cr_expect(strstr(err_text, "replaying 0 input transactions") != NULL, "%s", err_text);
    /* a record file that cannot be written */
    EXPECT_ERROR(1, "run --record-input %s/no/dir/x.rec --frames 1 --display null --size 32x18 --threads 1",
                 "no/dir/x.rec", "cannot write", "does not exist");
}

Test(input_cli, run_help_lists_the_input_options)
{
    cr_assert_eq(run("run --help"), 0, "%s", err_text);
    static const char *const options[] = {"--input on|off", "--record-input", "--replay-input", "--replay-speed",
                                          "--map-input",    "--input-device", "--idle-timeout", "--bindings"};
    for (size_t i = 0; i < sizeof options / sizeof options[0]; i++)
        cr_expect(strstr(out_text, options[i]) != NULL, "run --help lacks %s: %s", options[i], out_text);
}

/* The command line's lists replace the config's (it overrides the file), and
 * an empty device path is refused as the config refuses it. */
Test(input_cli, command_line_lists_replace_the_configs)
{
    write_file("map.json", "{\"input\": {\"map\": [{\"device\": \"touch\", \"output\": \"DP-7\"}]}}");
    int code = run("run --config %s/map.json --wall ../configs/walls/vm_2x2.json --display null --input on "
                   NO_DEVICES " --map-input touch=Virtual-1 --frames 1 --threads 2 --renderer eyelight");
    cr_expect_eq(code, 0, "the config's mapping to DP-7 survived --map-input: %s", err_text);
    EXPECT_ERROR(1, "run --config %s/map.json --wall ../configs/walls/vm_2x2.json --display null --input on "
                    NO_DEVICES " --frames 1 --threads 2",
                 "DP-7");
    EXPECT_ERROR(2, "run --input-device '' --display null --frames 1 --size 32x18", "--input-device", "empty path");
}

/* Early checks: a bindings or tour file that cannot be read stops the run
 * before the scene loads, naming the option. */
Test(input_cli, bindings_and_tour_files_are_checked_before_the_scene_loads)
{
    EXPECT_ERROR(1, "run --input on --bindings %s/nope.json --display null --frames 1 --size 32x18 --threads 1",
                 "--bindings", "nope.json", "cannot open");
    cr_expect(strstr(err_text, "scene (") == NULL, "the scene was loaded first: %s", err_text);
    EXPECT_ERROR(1, "run --input on --tour %s/nope.json --display null --frames 1 --size 32x18 --threads 1",
                 "--tour", "nope.json", "cannot open");
    cr_expect(strstr(err_text, "scene (") == NULL, "the scene was loaded first: %s", err_text);
    /* with input off the same options are said to be ignored, and the run goes on */
    cr_expect_eq(run("run --input off --bindings %s/nope.json --display null --frames 1 --size 32x18 --threads 1"), 0,
                 "%s", err_text);
    cr_expect(strstr(err_text, "input is off") != NULL, "%s", err_text);
}

/* ---- devices that are not input devices ------------------------------------------------ */

/* Count the lines of `text` that hold both `a` and `b`. */
static int count_lines_with(const char *text, const char *a, const char *b)
{
    int n = 0;
    for (const char *line = text; line && *line;) {
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) : strlen(line);
        char buf[1024];
        snprintf(buf, sizeof buf, "%.*s", (int)(len < sizeof buf ? len : sizeof buf - 1), line);
        if (strstr(buf, a) && strstr(buf, b))
            n++;
        line = end ? end + 1 : NULL;
    }
    return n;
}

/* --input-device paths a kiosk may be given by mistake or find broken: a
 * regular file of garbage bytes, /dev/null (a character device that is no
 * evdev device, and one udev may not have set up: libinput alone would wait
 * 2 s for it on every retry), a FIFO, a directory, and a path that does not
 * exist. Each is said once, naming the path and what it is; the path backend
 * looks at them again every second (a debug line each time, which this test
 * waits for: two retries of every path), saying nothing more; a node udev
 * has not set up is never handed to libinput (its "never initialized"
 * message would say it waited); frames keep coming; SIGINT ends the run
 * cleanly. */
Test(input_cli, paths_that_are_not_input_devices_are_said_once_and_the_kiosk_goes_on)
{
    char garbage[512], fifo[512], dir[512], missing[512], log_path[512];
    snprintf(garbage, sizeof garbage, "%s/garbage-device", tmp_dir);
    snprintf(fifo, sizeof fifo, "%s/fifo-device", tmp_dir);
    snprintf(dir, sizeof dir, "%s/dir-device", tmp_dir);
    snprintf(missing, sizeof missing, "%s/missing-device", tmp_dir);
    snprintf(log_path, sizeof log_path, "%s/run.log", tmp_dir);
    FILE *f = fopen(garbage, "wb");
    cr_assert(f);
    unsigned state = 12345u;
    for (int i = 0; i < 4096; i++) {
        state = state * 1103515245u + 12345u;
        fputc((int)(state >> 24), f);
    }
    fclose(f);
    cr_assert_eq(mkfifo(fifo, 0600), 0);
    cr_assert_eq(mkdir(dir, 0700), 0);
    const char *paths[] = {garbage, "/dev/null", fifo, dir, missing};
    enum { PATHS = sizeof paths / sizeof paths[0] };

    pid_t pid = fork();
    cr_assert(pid >= 0);
    if (pid == 0) {
        int fd = open(log_path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        if (fd < 0 || dup2(fd, 1) < 0 || dup2(fd, 2) < 0)
            _exit(127);
        setenv("TESSERA_LOG", "debug", 1);
        execl(support_tessera_bin(), "tessera", "run", "--input", "on", "--input-device", paths[0],
              "--input-device", paths[1], "--input-device", paths[2], "--input-device", paths[3], "--input-device",
              paths[4], "--display", "null", "--frames", "100000000", "--size", "16x16", "--threads", "1",
              "--renderer", "eyelight", (char *)NULL);
        _exit(127);
    }
    /* wait (an event, bounded) for two retries of every path */
    static char text[1 << 20];
    bool retried = false;
    for (int waited_ms = 0; waited_ms < TIMEOUT_S * 1000 && !retried; waited_ms += 50) {
        usleep(50 * 1000);
        support_read_text(log_path, text, sizeof text);
        retried = true;
        for (int i = 0; i < PATHS; i++)
            retried = retried && count_lines_with(text, paths[i], "looked for again") >= 2;
        if (waitpid(pid, NULL, WNOHANG) == pid) {
            pid = -1;
            break;
        }
    }
    int status = -1;
    if (pid > 0) {
        kill(pid, SIGINT);
        for (int waited_ms = 0; waited_ms < TIMEOUT_S * 1000; waited_ms += 50) {
            if (waitpid(pid, &status, WNOHANG) == pid)
                break;
            usleep(50 * 1000);
        }
        if (status == -1) {
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            cr_expect(false, "the run did not end on SIGINT");
        }
    }
    support_read_text(log_path, text, sizeof text);
    cr_assert(pid > 0, "the run ended by itself:\n%s", text);
    cr_assert(retried, "no two retries of every path within %d s:\n%s", TIMEOUT_S, text);
    cr_expect(WIFEXITED(status) && WEXITSTATUS(status) == 0, "exit status %d after SIGINT:\n%s", status, text);
    for (int i = 0; i < PATHS; i++)
        cr_expect_eq(count_lines_with(text, paths[i], "warn: input:"), 1, "%s: said %d times, expected once:\n%s",
                     paths[i], count_lines_with(text, paths[i], "warn: input:"), text);
    cr_expect(count_lines_with(text, missing, "no such device now") == 1, "%s", text);
    cr_expect(count_lines_with(text, garbage, "a regular file") == 1, "%s", text);
    cr_expect(count_lines_with(text, fifo, "a FIFO") == 1, "%s", text);
    cr_expect(count_lines_with(text, dir, "a directory") == 1, "%s", text);
    cr_expect(strstr(text, "never initialized") == NULL, "libinput was made to wait for udev:\n%s", text);
    cr_expect(strstr(text, "frames rendered") != NULL, "no frame report:\n%s", text);
    cr_expect(count_lines_with(text, "error", "") == 0, "an error line:\n%s", text);
}
