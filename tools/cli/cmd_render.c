/* cmd_render.c - `tessera render` (headless frames of one camera) and
 * `tessera run` (the main job: with no DRM output it renders an orbit of the
 * scene through the dump backend into out/). */
#include <errno.h>
#include <libgen.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "engine/accel.h"
#include "engine/render.h"
#include "engine/scene.h"
#include "wall/dump.h"

/* What both commands share once options are parsed. */
typedef struct job {
    const char *scene_path; /* NULL: the built-in default scene */
    int width_px, height_px;
    int threads;
    int frames;
    bool shadows;
    bool have_camera;       /* --camera given */
    camera_desc camera;
    const char *out;        /* output file or frame pattern */
    cli_scene loaded;       /* by job_prepare */
} job;

static int default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 256 ? 256 : (int)n;
}

/* Parse the options both commands take. Returns false when the command should
 * stop: after --help (*exit_code 0) or a bad option (*exit_code 2). */
static bool parse_common(int argc, char **argv, job *j, void (*usage)(FILE *), int *exit_code)
{
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *val;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            *exit_code = 0;
            return false;
        } else if (!strcmp(a, "--scene")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                goto bad;
            j->scene_path = strcmp(val, "default") ? val : NULL;
        } else if (!strcmp(a, "--size")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_size(a, val, &j->width_px, &j->height_px))
                goto bad;
        } else if (!strcmp(a, "--threads")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 256, &j->threads))
                goto bad;
        } else if (!strcmp(a, "--frames")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_int(a, val, 1, 1000000, &j->frames))
                goto bad;
        } else if (!strcmp(a, "--camera")) {
            if (!(val = cli_option_value(argc, argv, &i)) || !cli_parse_camera(a, val, &j->camera))
                goto bad;
            j->have_camera = true;
        } else if (!strcmp(a, "--out")) {
            if (!(val = cli_option_value(argc, argv, &i)))
                goto bad;
            j->out = val;
        } else if (!strcmp(a, "--no-shadows")) {
            j->shadows = false;
        } else {
            cli_error("unknown option '%s' (see 'tessera %s --help')", a, argv[0]);
            goto bad;
        }
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

static bool job_prepare(job *j)
{
    return cli_scene_prepare(j->scene_path, j->threads, &j->loaded) &&
           cli_scene_camera(&j->loaded, j->have_camera ? &j->camera : NULL, j->width_px, j->height_px, &j->camera);
}

static void job_finish(job *j) { cli_scene_finish(&j->loaded); }

/* Rotate the camera's eye about the vertical axis through look_at. */
static camera_desc orbit(camera_desc c, float angle_rad)
{
    vec3 r = v3_sub(c.eye, c.look_at);
    float cs = cosf(angle_rad), sn = sinf(angle_rad);
    c.eye = v3_add(c.look_at, v3(cs * r.x + sn * r.z, r.y, -sn * r.x + cs * r.z));
    return c;
}

/* Render j->frames frames (orbiting when `orbit_frames` > 0) and write each.
 * Prints the frame rate of rendering alone and with writing. */
static int render_frames(job *j, int orbit_frames)
{
    size_t pixels = (size_t)j->width_px * (size_t)j->height_px;
    float *rgb = malloc(pixels * 3 * sizeof *rgb);
    if (!rgb) {
        cli_error("out of memory for a %dx%d image", j->width_px, j->height_px);
        return 1;
    }
    double render_s = 0.0, total_start = cli_now_s();
    char path[4096], first[4096] = "";
    for (int f = 0; f < j->frames; f++) {
        camera_desc cam = orbit_frames > 0 ? orbit(j->camera, 6.2831853f * (float)f / (float)orbit_frames) : j->camera;
        render_view view = {j->loaded.scene, j->loaded.accel, camera_basis_make(&cam, j->width_px, j->height_px), j->shadows,
                            RENDER_SHADE_PHONG};
        double t0 = cli_now_s();
        render_image(&view, j->threads, rgb, NULL);
        render_s += cli_now_s() - t0;
        tess_error err = {{0}};
        if (!dump_frame_path(j->out, f, j->frames > 1, path, sizeof path, &err) ||
            !dump_write_rgb(path, j->width_px, j->height_px, rgb, &err)) {
            cli_error("%s", err.msg);
            free(rgb);
            return 1;
        }
        if (f == 0)
            snprintf(first, sizeof first, "%s", path);
    }
    double total_s = cli_now_s() - total_start;
    free(rgb);
    if (j->frames == 1)
        printf("wrote %s\n", first);
    else
        printf("wrote %d frames: %s ... %s\n", j->frames, first, path);
    printf("%d frame%s %dx%d, %d thread%s: rendering %.2f frames/s (%.1f ms/frame, %.2f Mpixels/s); "
           "with writing %.2f frames/s\n",
           j->frames, j->frames == 1 ? "" : "s", j->width_px, j->height_px, j->threads, j->threads == 1 ? "" : "s",
           j->frames / render_s, 1e3 * render_s / j->frames, (double)pixels * j->frames / render_s * 1e-6,
           j->frames / total_s);
    return 0;
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
          "  --threads N      render threads (default: the number of CPUs)\n"
          "  --frames N       render and write N frames of the same camera (default 1)\n"
          "  --no-shadows     skip shadow rays\n",
          f);
}

int cli_render(int argc, char **argv)
{
    job j = {.width_px = 1280, .height_px = 720, .threads = default_threads(), .frames = 1, .shadows = true,
             .out = "out/render.png"};
    int code = 0;
    if (!parse_common(argc, argv, &j, render_usage, &code))
        return code;
    if (!check_output_dir(j.out))
        return 1;
    if (!job_prepare(&j)) {
        job_finish(&j);
        return 1;
    }
    code = render_frames(&j, 0);
    job_finish(&j);
    return code;
}

static void run_usage(FILE *f)
{
    fputs("usage: tessera run [options]\n"
          "The main job. With no DRM/KMS output (not implemented yet: see the wall issue) it\n"
          "renders headless through the dump backend: an orbit of the camera around the\n"
          "scene, written as out/frame_NNNN.png, and prints the frame rate.\n"
          "  --scene FILE     JSON scene or mesh file (default: the built-in scene)\n"
          "  --size WxH       image size in pixels (default 1280x720)\n"
          "  --frames N       frames to render, one full orbit (default 48)\n"
          "  --out PATTERN    frame file pattern (default out/frame_####.png)\n"
          "  --camera ...     start camera, as for 'tessera render'\n"
          "  --threads N      render threads (default: the number of CPUs)\n"
          "  --no-shadows     skip shadow rays\n",
          f);
}

int cli_run(int argc, char **argv)
{
    job j = {.width_px = 1280, .height_px = 720, .threads = default_threads(), .frames = 48, .shadows = true,
             .out = "out/frame_####.png"};
    int code = 0;
    if (!parse_common(argc, argv, &j, run_usage, &code))
        return code;
    if (access("/dev/dri", F_OK) == 0)
        fprintf(stderr, "tessera: a DRM device is present, but the DRM/KMS backend is not built yet; "
                        "rendering headless\n");
    /* the default output directory is ours to create */
    if (!strcmp(j.out, "out/frame_####.png") && mkdir("out", 0777) != 0 && errno != EEXIST) {
        cli_error("out: cannot create directory: %s", strerror(errno));
        return 1;
    }
    if (!check_output_dir(j.out))
        return 1;
    if (!job_prepare(&j)) {
        job_finish(&j);
        return 1;
    }
    code = render_frames(&j, j.frames);
    job_finish(&j);
    return code;
}
