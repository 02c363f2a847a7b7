/* test_display_faults.c - the dump display when writing fails: EIO from the
 * disk (pwrite, and close reporting a lost write: fault_io.c), and the output
 * directory removed while a pipeline runs. Each failure names the file and
 * the problem, leaves no partial file, and stops the run with that error (the
 * dump display's frames are the product of a headless run: a lost frame is a
 * failed run). A full disk is tested in tests/test_dump.c (/dev/full). */
#include <criterion/criterion.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/frame/pipeline.h"
#include "engine/scene/scene.h"
#include "fault.h"
#include "wall/display.h"
#include "wall/dump.h"

static char dir[64];

static void dir_create(void)
{
    snprintf(dir, sizeof dir, "/tmp/tessera_fault_io_XXXXXX");
    cr_assert_not_null(mkdtemp(dir));
}

static void dir_remove(void)
{
    fault_io_reset();
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
}

TestSuite(display_faults, .init = dir_create, .fini = dir_remove);

static bool exists(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0;
}

/* 64 x 64 of poorly compressible values: several writes per file */
static const float *test_image(void)
{
    static float rgb[64 * 64 * 3];
    for (int i = 0; i < 64 * 64 * 3; i++)
        rgb[i] = (float)((i * 7919) % 1000) / 1000.0f;
    return rgb;
}

static void assert_write_fails(const char *name, const char *problem)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    tess_error err = {{0}};
    bool ok = dump_write_rgb(path, 64, 64, test_image(), &err);
    fault_io_reset();
    cr_assert_not(ok, "%s: written despite the injected failure", path);
    cr_assert(strstr(err.msg, path), "the message does not name %s: %s", path, err.msg);
    cr_assert(strstr(err.msg, problem), "the message does not say '%s': %s", problem, err.msg);
    cr_assert_not(exists(path), "%s: the partial file was left behind", path);
}

static const char *const formats[] = {"png", "exr", "jpg"};

/* The first write of the file fails: EIO. */
Test(display_faults, eio_on_the_first_write)
{
    for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
        char name[32];
        snprintf(name, sizeof name, "first.%s", formats[f]);
        fault_io_fail_pwrite(EIO, 0);
        assert_write_fails(name, strerror(EIO));
    }
}

/* Later writes fail (the disk dies mid-file); the writers that buffer the
 * whole image make one write, so this is the same case for them. */
Test(display_faults, eio_mid_file)
{
    for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
        char name[32];
        snprintf(name, sizeof name, "mid.%s", formats[f]);
        fault_io_fail_pwrite(EIO, 1);
        char path[256];
        snprintf(path, sizeof path, "%s/%s", dir, name);
        tess_error err = {{0}};
        bool ok = dump_write_rgb(path, 64, 64, test_image(), &err);
        fault_io_reset();
        if (ok) { /* one write for the whole file: nothing failed, and the file is whole */
            int w = 0, h = 0;
            float *back = NULL;
            cr_assert(dump_read_rgbf(path, &w, &h, &back, &err), "%s", err.msg);
            cr_assert(w == 64 && h == 64);
            free(back);
            continue;
        }
        cr_assert(strstr(err.msg, path) && strstr(err.msg, strerror(EIO)), "%s", err.msg);
        cr_assert_not(exists(path), "%s left behind", path);
    }
}

/* Every write went through, but close reports that the data never made it
 * (NFS, a USB disk pulled): the file is incomplete and must not stay. */
Test(display_faults, eio_at_close)
{
    for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
        char name[32];
        snprintf(name, sizeof name, "close.%s", formats[f]);
        fault_io_fail_close(EIO);
        assert_write_fails(name, strerror(EIO));
    }
}

/* ---- the output directory vanishes while a pipeline runs ----------------- */

/* A display in front of the dump display that removes the output directory
 * once frame `vanish_after` has been written: deterministic, no timing. */
typedef struct vanishing {
    image_display base;
    image_display *dump;
    char dir[128];
    uint64_t vanish_after;
    int shown;
} vanishing;

static bool vanishing_show(image_display *d, const frame_image *img, tess_error *err)
{
    vanishing *v = (vanishing *)d;
    if (!v->dump->ops->show(v->dump, img, err))
        return false;
    v->shown++;
    if (img->frame == v->vanish_after) {
        char cmd[256];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", v->dir);
        cr_assert_eq(system(cmd), 0);
    }
    return true;
}

static void vanishing_destroy(image_display *d)
{
    vanishing *v = (vanishing *)d;
    image_display_destroy(v->dump);
    free(v);
}

static const image_display_ops vanishing_ops = {.name = "vanishing", .show = vanishing_show,
                                                .destroy = vanishing_destroy};

Test(display_faults, output_directory_vanishes_mid_run, .timeout = 60)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert_not_null(s, "%s", err.msg);
    accel *a = accel_build(s, 2, &err);
    cr_assert_not_null(a, "%s", err.msg);
    pipeline_config cfg = pipeline_config_default(s, a);
    cfg.threads = 2;
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE;
    cfg.rate_hz = 24;
    cfg.max_frames = 10;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert_not_null(p, "%s", err.msg);

    vanishing *v = calloc(1, sizeof *v);
    cr_assert_not_null(v);
    v->base.ops = &vanishing_ops;
    snprintf(v->dir, sizeof v->dir, "%s/frames", dir);
    cr_assert_eq(mkdir(v->dir, 0755), 0);
    char pattern[256];
    snprintf(pattern, sizeof pattern, "%s/frame_####.png", v->dir);
    v->dump = display_dump_create(pattern, true, &err);
    cr_assert_not_null(v->dump, "%s", err.msg);
    v->vanish_after = 2;
    camera_desc cam = s->camera;
    cr_assert_geq(pipeline_add_channel(p, &cam, 48, 27, &v->base, &err), 0, "%s", err.msg);

    bool ok = pipeline_run(p, &err);
    cr_assert_not(ok, "the run went on without its output directory");
    char lost[256];
    snprintf(lost, sizeof lost, "%s/frame_0003.png", v->dir);
    cr_assert(strstr(err.msg, lost), "the error does not name the lost frame %s: %s", lost, err.msg);
    cr_assert(strstr(err.msg, strerror(ENOENT)), "the error does not say why: %s", err.msg);
    cr_assert(strchr(err.msg, '\n') == NULL, "more than one line: %s", err.msg);
    cr_assert_eq(v->shown, 3, "frames 0..2 written, then the failure: %d shown", v->shown);
    cr_assert_not(exists(v->dir), "the directory came back");
    pipeline_destroy(p);
    accel_destroy(a);
    scene_destroy(s);
}
