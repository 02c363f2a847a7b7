/* test_cli.c - the tessera binary end to end: every bad input gets one clear
 * line and a non-zero exit, never a crash or a hang; good input writes images.
 * Runs ../tessera (or $TESSERA_BIN) from the tests/ directory. */
#define _GNU_SOURCE /* dladdr */
#include <criterion/criterion.h>
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "support.h"
#include "wall/dump.h"

/* Seconds any single command may take before the test counts it as a hang. */
#define CLI_TIMEOUT_S 60

static char tmp_dir[256];

static void make_tmp_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "cli"); }

static void write_text(const char *name, const char *text) { support_write_file(tmp_dir, name, text); }

/* Run `tessera ARGS` (every %s in ARGS is the temp dir); output goes to `out`. */
static int run_tessera(char *out, size_t out_bytes, const char *args_fmt)
{
    return support_tessera(tmp_dir, CLI_TIMEOUT_S, out, out_bytes, args_fmt);
}

/* Expect failure with a message containing every needle (NULL-terminated). */
static void expect_error(const char *args_fmt, const char *const *needles)
{
    support_expect_error(tmp_dir, CLI_TIMEOUT_S, args_fmt, needles);
}

#define EXPECT_ERROR(args, ...) expect_error(args, (const char *const[]){__VA_ARGS__, NULL})

TestSuite(cli, .init = make_tmp_dir, .timeout = 300);

Test(cli, help_lists_commands_and_options)
{
    char out[8192];
    cr_expect_eq(run_tessera(out, sizeof out, "--help"), 0);
    cr_expect(strstr(out, "render") && strstr(out, "run"), "%s", out);
    cr_expect_eq(run_tessera(out, sizeof out, "render --help"), 0);
    const char *options[] = {"--scene", "--size", "--out", "--camera", "--threads", "--frames"};
    for (size_t i = 0; i < sizeof options / sizeof options[0]; i++)
        cr_expect(strstr(out, options[i]), "render --help lacks %s", options[i]);
    cr_expect_eq(run_tessera(out, sizeof out, "run --help"), 0);
}

/* The help states each command's own defaults of --time and --rate (docs/command-line.md's table):
 * render fixed at 30 Hz, run fixed at 24 Hz headless and real time on a DRM wall. */
Test(cli, help_gives_each_commands_time_default)
{
    char out[16384];
    cr_expect_eq(run_tessera(out, sizeof out, "render --help"), 0);
    cr_expect(strstr(out, "(reproducible; default fixed)\n"), "%s", out);
    cr_expect(strstr(out, "fixed mode (default 30)"), "%s", out);
    cr_expect_eq(run_tessera(out, sizeof out, "run --help"), 0);
    cr_expect(strstr(out, "(reproducible; default fixed; real on a DRM wall)"), "%s", out);
    cr_expect(strstr(out, "fixed mode (default 24)"), "%s", out);
    cr_expect(strstr(out, "default real)") == NULL, "%s", out);
}

/* Images go through a module loaded on first use (wall/dump.c). When it cannot load, a run that
 * writes an image fails before it renders, naming the image and why: a module file that is
 * missing, a file that is no shared object, and a shared object that is not the module (libm,
 * found by dladdr, so the test names no path of this machine). */
Test(cli, image_module_that_does_not_load_is_an_error_naming_the_image)
{
    char missing[512], not_elf[512];
    snprintf(missing, sizeof missing, "%s/missing.so", tmp_dir);
    snprintf(not_elf, sizeof not_elf, "%s/not_elf.so", tmp_dir);
    write_text("not_elf.so", "this is not a shared object\n");
    Dl_info libm;
    cr_assert(dladdr((void *)&cos, &libm) && libm.dli_fname, "dladdr(cos) found no library");
    const struct {
        const char *module, *why;
    } cases[] = {
        {missing, "missing.so: "}, /* then dlerror()'s words */
        {not_elf, "not_elf.so: "},
        {libm.dli_fname, "not an image module of this build (no tessera_dump_module)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cr_assert_eq(setenv("TESSERA_IMAGE_MODULE", cases[i].module, 1), 0);
        EXPECT_ERROR("render --size 16x12 --out %s/a.png", "a.png: images cannot be read or written",
                     "the OpenImageIO module did not load", cases[i].why);
        char path[512];
        struct stat st;
        snprintf(path, sizeof path, "%s/a.png", tmp_dir);
        cr_expect(stat(path, &st) != 0, "%s: an image was written without the module", cases[i].module);
    }
    /* a command that reads and writes no image never loads the module */
    write_text("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    char out[4096];
    cr_expect_eq(run_tessera(out, sizeof out, "parts %s/tri.obj"), 0, "%s", out);
    cr_expect(strstr(out, "triangles_stored=1 "), "%s", out);
}

Test(cli, renders_default_scene_to_png_and_exr)
{
    char out[8192];
    cr_assert_eq(run_tessera(out, sizeof out, "render --size 64x48 --out %s/a.png"), 0, "%s", out);
    cr_expect(strstr(out, "frames/s"), "no frame rate: %s", out);
    char path[512];
    snprintf(path, sizeof path, "%s/a.png", tmp_dir);
    int w, h;
    uint8_t *rgb;
    tess_error err = {{0}};
    cr_assert(dump_read_rgb8(path, &w, &h, &rgb, &err), "%s", err.msg);
    cr_expect(w == 64 && h == 48);
    free(rgb);
    cr_assert_eq(run_tessera(out, sizeof out, "render --size 32x24 --frames 3 --out %s/seq_###.exr"), 0, "%s", out);
    for (int f = 0; f < 3; f++) {
        snprintf(path, sizeof path, "%s/seq_%03d.exr", tmp_dir, f);
        cr_expect(access(path, R_OK) == 0, "missing %s", path);
    }
}

Test(cli, camera_option_changes_the_view)
{
    char out[8192];
    cr_assert_eq(run_tessera(out, sizeof out, "render --size 32x24 --out %s/a.png"), 0, "%s", out);
    cr_assert_eq(run_tessera(out, sizeof out, "render --size 32x24 --out %s/b.png --camera 0,10,0.1,0,0,0,0,0,-1,30"),
                 0, "%s", out);
    char pa[512], pb[512];
    snprintf(pa, sizeof pa, "%s/a.png", tmp_dir);
    snprintf(pb, sizeof pb, "%s/b.png", tmp_dir);
    int w, h;
    uint8_t *a, *b;
    tess_error err = {{0}};
    cr_assert(dump_read_rgb8(pa, &w, &h, &a, &err) && dump_read_rgb8(pb, &w, &h, &b, &err));
    cr_expect(memcmp(a, b, (size_t)w * h * 3) != 0);
    free(a);
    free(b);
}

Test(cli, unknown_command_and_option)
{
    EXPECT_ERROR("frobnicate", "unknown command", "frobnicate");
    EXPECT_ERROR("render --bogus", "unknown option", "--bogus");
    EXPECT_ERROR("render --size", "--size", "needs a value");
}

Test(cli, malformed_values_say_what_was_expected)
{
    EXPECT_ERROR("render --size 0x10 --out %s/a.png", "--size", "0x10", "from 1");
    EXPECT_ERROR("render --size 640 --out %s/a.png", "--size", "WIDTHxHEIGHT");
    EXPECT_ERROR("render --size 64x48x2 --out %s/a.png", "--size", "WIDTHxHEIGHT");
    EXPECT_ERROR("render --threads two --out %s/a.png", "--threads", "whole number");
    EXPECT_ERROR("render --frames 0 --out %s/a.png", "--frames", "from 1");
    EXPECT_ERROR("render --camera 1,2,3 --out %s/a.png", "--camera", "10 finite numbers");
    EXPECT_ERROR("render --camera 0,0,0,0,0,0,0,1,0,40 --out %s/a.png", "--camera", "same point");
    EXPECT_ERROR("render --camera 0,0,5,0,0,0,0,1,0,nan --out %s/a.png", "--camera");
    EXPECT_ERROR("render --camera 0,0,5,0,0,0,0,1,0,200 --out %s/a.png", "--camera", "fov");
}

Test(cli, missing_scene_file)
{
    EXPECT_ERROR("render --scene %s/nope.json --out %s/a.png", "nope.json");
    EXPECT_ERROR("render --scene %s/nope.ply --out %s/a.png", "nope.ply");
}

/* A frame too big for the memory the process may have: one line naming the channel, the size
 * and what did not fit (it once said "channel 0: pipeline: channel 0: out of memory"), exit 1,
 * no image. Run under a 3 GB address-space limit (16384x16384 needs 3 frame buffers of 3 GiB);
 * an AddressSanitizer build needs terabytes of address space to start, so it is not run there. */
Test(cli, a_frame_too_big_for_memory_says_so_once)
{
    if (strstr(support_tessera_bin(), "asan"))
        return; /* cannot start under an address-space limit */
    char cmd[2048], log_path[512], out[8192];
    snprintf(log_path, sizeof log_path, "%s/oom.log", tmp_dir);
    snprintf(cmd, sizeof cmd,
             "ulimit -v 3000000 && timeout %d %s render --size 16384x16384 --threads 1 --out %s/big.png > %s 2>&1",
             CLI_TIMEOUT_S, support_tessera_bin(), tmp_dir, log_path);
    int code = support_run(cmd);
    support_read_text(log_path, out, sizeof out);
    cr_expect_eq(code, 1, "%s", out);
    cr_expect(strstr(out, "error: pipeline: channel 0: out of memory for its 16384x16384 frame buffers (3 of 3.0 GiB "
                          "each)\n"),
              "%s", out);
    const char *first = strstr(out, "channel 0");
    cr_expect(first && !strstr(first + 1, "channel 0"), "the channel is named twice: %s", out);
    char path[512];
    snprintf(path, sizeof path, "%s/big.png", tmp_dir);
    cr_expect(access(path, F_OK) != 0, "an image was written");
}

Test(cli, unwritable_output_path)
{
    EXPECT_ERROR("render --size 8x8 --out %s/no/such/dir/a.png", "no/such/dir", "does not exist");
    write_text("file", "x");
    EXPECT_ERROR("render --size 8x8 --out %s/file/a.png", "file/a.png", "not a directory");
    EXPECT_ERROR("render --size 8x8 --out %s/a.unknownformat", "a.unknownformat");
}

Test(cli, broken_scene_and_mesh_files)
{
    write_text("syntax.json", "{\n  \"background\": [0, 0, 0],\n  \"lights\": [ }\n");
    EXPECT_ERROR("render --scene %s/syntax.json --out %s/a.png", "syntax.json:3");
    write_text("field.json", "{ \"spheres\": [ {\"center\": [0,0,0], \"radius\": 1, \"colour\": 1} ] }");
    EXPECT_ERROR("render --scene %s/field.json --out %s/a.png", "field.json", "colour");
    write_text("type.json", "{ \"spheres\": [ {\"center\": [0,0,0], \"radius\": \"big\"} ] }");
    EXPECT_ERROR("render --scene %s/type.json --out %s/a.png", "type.json", "radius");
    write_text("range.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    EXPECT_ERROR("render --scene %s/range.ply --out %s/a.png", "range.ply", "out of range");
    write_text("nan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                          "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
    EXPECT_ERROR("render --scene %s/nan.ply --out %s/a.png", "nan.ply");
    write_text("words.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 abc 0\n0 1 0\n3 0 1 2\n");
    EXPECT_ERROR("render --scene %s/words.ply --out %s/a.png", "words.ply", "abc");
    /* binary PLY whose face block is cut short */
    write_text("cut.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                          "property float y\nproperty float z\nelement face 1\n"
                          "property list uchar int vertex_indices\nend_header\n");
    char path[512];
    snprintf(path, sizeof path, "%s/cut.ply", tmp_dir);
    FILE *f = fopen(path, "ab");
    cr_assert(f);
    const float vertices[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const unsigned char face_start[3] = {3, 0, 0}; /* count, then half of the first index */
    fwrite(vertices, sizeof vertices, 1, f);
    fwrite(face_start, sizeof face_start, 1, f);
    fclose(f);
    EXPECT_ERROR("render --scene %s/cut.ply --out %s/a.png", "cut.ply");
}

/* Scenes with nothing to draw say what they are: a PLY of points without points, a mesh without
 * triangles; a directory is named as one (not assimp's "No suitable reader found"). */
Test(cli, empty_point_sets_meshes_and_directories_say_what_they_are)
{
    write_text("nopoints.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                               "property float z\nend_header\n");
    EXPECT_ERROR("render --scene %s/nopoints.ply --out %s/a.png --size 8x8",
                 "nopoints.ply: scene has no geometry (the point set has no points: 0 vertices)");
    write_text("notris.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
    EXPECT_ERROR("render --scene %s/notris.ply --out %s/a.png --size 8x8",
                 "notris.ply: scene has no geometry (the mesh has no triangles)");
    char dir[512];
    snprintf(dir, sizeof dir, "%s/scenes", tmp_dir);
    cr_assert_eq(mkdir(dir, 0777), 0);
    EXPECT_ERROR("render --scene %s/scenes --out %s/a.png --size 8x8", "scenes: is a directory (a scene is a file");
    snprintf(dir, sizeof dir, "%s/d.json", tmp_dir);
    cr_assert_eq(mkdir(dir, 0777), 0);
    EXPECT_ERROR("render --scene %s/d.json --out %s/a.png --size 8x8", "d.json: is a directory");
    char path[512];
    snprintf(path, sizeof path, "%s/a.png", tmp_dir);
    cr_expect(access(path, F_OK) != 0, "an image was written");
}

Test(cli, run_writes_frames_and_reports_rate)
{
    char out[8192];
    cr_assert_eq(run_tessera(out, sizeof out, "run --size 32x24 --frames 4 --out %s/f_####.png"), 0, "%s", out);
    cr_expect(strstr(out, "frames/s"), "%s", out);
    char path[512];
    snprintf(path, sizeof path, "%s/f_0003.png", tmp_dir);
    cr_expect(access(path, R_OK) == 0, "missing %s: %s", path, out);
}
