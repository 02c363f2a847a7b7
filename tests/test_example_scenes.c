/* test_example_scenes.c - every example scene in configs/scenes, rendered
 * small (96 x 72, one frame, 2 threads) with its own camera.
 *
 * The SUBJECT of a scene is everything but its backdrop, and the backdrop is
 * the shipped quad (configs/scenes/data/quad.obj: every floor and wall of
 * the example scenes). A pixel shows the subject when its primary ray's
 * closest hit is not a backdrop quad, or when the volumes rendered directly
 * on the way to that hit take at least SUBJECT_OPACITY of the light. Where a
 * scene's data are there, the picture must show the subject (at least
 * MIN_SUBJECT_SHARE of the pixels, nearly all of them not the background
 * colour) whole: no subject pixel within MARGIN of any edge of the image
 * (5 columns, 4 rows), so that it is not cut off at another size or
 * aspect (the vertical field of view is kept) either. And it must rest
 * on its floor (the lowest horizontal backdrop quad, "horizontal" along the
 * camera's up, which must be an axis): the lowest point of each part of the
 * subject within FLOOR_TOLERANCE of its top's height above the floor. For a
 * mesh, sphere set or particle set the lowest point is its bounds'; for an
 * iso-surface, or the volumes rendered directly taken together, it is found
 * by rays straight up from the floor over the box's footprint (the first
 * hit of the surface, or where the volume has taken half the light), so a
 * volume's faint or hidden parts under the floor do not count. Up side
 * down is NOT checked: nothing here knows which way up a bunny goes, nor
 * whether the picture is pleasing; a bunny's bounding box is not its
 * silhouette either, so "rests on the floor" for a mesh is "its lowest
 * vertex is at the floor".
 *
 * The example scenes take their big data from ../shared/data beside the
 * repository, each entry optional. Without it a scene must still load, say
 * which file is missing (a warning naming the file under shared/data/), and
 * render its floor. load_without_the_shared_data always checks that, on
 * copies of the scene files in a temporary tree where ../../../shared does
 * not exist; the render test, where the real ../shared/data lacks a scene's
 * file, checks the same and says SKIPPED for that scene's render checks. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <criterion/criterion.h>
#include <criterion/logging.h>

#include <dirent.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/accel/intersect.h"
#include "engine/base/log.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "support.h"

#define SCENES_DIR "../configs/scenes"
#define SHARED_REF "../../../shared/data/" /* how the scene files name the shared data */
#define W 96
#define H 72
#define THREADS 2
#define MAX_SCENES 64
#define NAME_BYTES 128
#define MAX_REFS 16
#define MAX_LINES 32
#define LINE_BYTES 1400
#define MIN_SUBJECT_SHARE 0.01 /* of the pixels */
#define MARGIN 0.05            /* of the image's width and height, clear of the subject at each edge */
#define SUBJECT_OPACITY 0.1f   /* of a volume rendered directly, for a pixel to show it */
#define FLOOR_TOLERANCE 0.02f  /* of the subject's height */
#define MEDIUM_CHUNKS 256      /* pieces a ray's stretch through a volume is integrated in */

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- what the loader says ----------------------------------------------- */

typedef struct log_lines {
    char line[MAX_LINES][LINE_BYTES];
    int count;
} log_lines;

static void collect_line(void *ctx, const char *line)
{
    log_lines *l = ctx;
    if (l->count < MAX_LINES)
        snprintf(l->line[l->count++], LINE_BYTES, "%s", line);
}

/* scene_load with this thread's log lines caught (the warnings for skipped
 * optional files come from the loading thread). */
static scene *load_quietly(const char *path, log_lines *lines, tess_error *err)
{
    setenv("TESSERA_LOG", "warn", 1); /* warnings are what is checked: not silenced by the caller's TESSERA_LOG */
    /* no structure cache written for the big meshes unless the caller asks
     * (TESSERA_CACHE set to anything): each run builds their trees, the
     * bulk of the test's cost, and leaves nothing behind */
    setenv("TESSERA_CACHE", "off", 0);
    lines->count = 0;
    log_divert_thread(collect_line, lines);
    scene *s = scene_load(path, err);
    log_divert_thread(NULL, NULL);
    return s;
}

static bool is_skip_line(const char *line) { return strstr(line, "skipped (optional)") != NULL; }

/* ---- the scene files ---------------------------------------------------- */

static int by_name(const void *a, const void *b) { return strcmp(a, b); }

/* The *.json files of SCENES_DIR, sorted. */
static int list_scenes(char names[][NAME_BYTES])
{
    DIR *d = opendir(SCENES_DIR);
    cr_assert_not_null(d, "cannot list %s (run from tests/)", SCENES_DIR);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 5 || strcmp(e->d_name + len - 5, ".json") != 0)
            continue;
        cr_assert_lt(n, MAX_SCENES);
        snprintf(names[n++], NAME_BYTES, "%.*s", NAME_BYTES - 1, e->d_name);
    }
    closedir(d);
    qsort(names, (size_t)n, sizeof names[0], by_name);
    cr_assert_geq(n, 5, "only %d example scenes in %s", n, SCENES_DIR);
    return n;
}

static void read_whole(const char *path, char *out, size_t bytes)
{
    FILE *f = fopen(path, "rb");
    cr_assert_not_null(f, "cannot open %s", path);
    size_t n = fread(out, 1, bytes - 1, f);
    cr_assert(feof(f), "%s is larger than %zu bytes", path, bytes - 1);
    fclose(f);
    out[n] = '\0';
}

/* The shared files a scene names: what follows SHARED_REF up to the closing
 * quote ("meshes/stanford_bunny.obj", "points/x/step*.dump"). */
static int shared_refs(const char *text, char refs[][256])
{
    int n = 0;
    for (const char *p = strstr(text, SHARED_REF); p; p = strstr(p + 1, SHARED_REF)) {
        const char *start = p + strlen(SHARED_REF), *end = strchr(start, '"');
        cr_assert_not_null(end);
        cr_assert_lt(n, MAX_REFS);
        snprintf(refs[n++], 256, "%.*s", (int)(end - start), start);
    }
    return n;
}

/* The lines that say an optional file was skipped must be one per missing
 * shared file, each naming it (its path ends in shared/data/REF) and saying
 * that it does not exist or that nothing matches it. */
static void check_missing_named(const char *scene_name, const log_lines *lines, char refs[][256], int ref_count,
                                const bool *missing)
{
    int skips = 0, expected = 0;
    for (int i = 0; i < lines->count; i++)
        skips += is_skip_line(lines->line[i]);
    for (int r = 0; r < ref_count; r++) {
        if (!missing[r])
            continue;
        expected++;
        char named[300];
        snprintf(named, sizeof named, "shared/data/%s", refs[r]);
        int found = 0;
        for (int i = 0; i < lines->count; i++)
            if (is_skip_line(lines->line[i]) && strstr(lines->line[i], named) &&
                (strstr(lines->line[i], "does not exist") || strstr(lines->line[i], "no file matches")))
                found++;
        cr_expect_eq(found, 1, "%s: %d warnings name the missing %s (want 1); the lines were:\n%s\n%s", scene_name,
                     found, named, lines->count > 0 ? lines->line[0] : "(none)",
                     lines->count > 1 ? lines->line[1] : "");
    }
    cr_expect_eq(skips, expected, "%s: %d files skipped, %d shared files missing", scene_name, skips, expected);
}

/* Whether ../shared/data (relative to SCENES_DIR) holds REF; a pattern
 * (with '*') is there when its directory is (the loader says whether
 * anything matches). */
static bool shared_file_there(const char *ref)
{
    char path[600];
    snprintf(path, sizeof path, "%s/%s%.255s", SCENES_DIR, SHARED_REF, ref);
    char *star = strchr(path, '*');
    if (star) {
        char *slash = star;
        while (slash > path && *slash != '/')
            slash--;
        *slash = '\0';
    }
    struct stat st;
    return stat(path, &st) == 0;
}

/* ---- rendering and looking at the picture ------------------------------- */

static float *render(const scene *s, const accel *a, const camera_basis *cam)
{
    float *rgb = calloc((size_t)W * H * 3, sizeof(float));
    cr_assert_not_null(rgb);
    render_view v = {s, a, *cam, true, RENDER_SHADE_PHONG, NULL, NULL};
    render_image(&v, THREADS, rgb, NULL);
    return rgb;
}

static bool is_background(const scene *s, const float *px)
{
    const float eps = 1e-3f;
    return fabsf(px[0] - s->background.x) < eps && fabsf(px[1] - s->background.y) < eps &&
           fabsf(px[2] - s->background.z) < eps;
}

static bool is_backdrop(const scene *s, uint32_t instance)
{
    const scene_geometry *g = scene_instance_geometry(s, instance);
    return g->ops == &geometry_triangles_ops && strcmp(g->name, "quad.obj") == 0;
}

/* The opacity the volumes rendered directly give ray r over [t_near, t_far]
 * (nearest first, render_media_spans: as the renderers composite them), and where along r the light
 * left first fell below one half (*t_seen, INFINITY when it never did). */
static float media_opacity(const scene *s, const ray *r, float *t_seen)
{
    *t_seen = INFINITY;
    render_media_span spans[RENDER_MEDIA_SPANS_MAX];
    uint32_t n = render_media_spans(s, r, spans);
    float through = 1.f;
    for (uint32_t k = 0; k < n; k++) {
        const scene_medium *md = &s->media[spans[k].medium];
        ray local = md->identity ? *r : affine3_ray(&md->to_object, r);
        float step = (spans[k].leave - spans[k].enter) / MEDIUM_CHUNKS;
        for (int c = 0; c < MEDIUM_CHUNKS && through > 1e-3f; c++) {
            local.t_near = spans[k].enter + step * (float)c;
            local.t_far = c == MEDIUM_CHUNKS - 1 ? spans[k].leave : local.t_near + step;
            vec3 rgb;
            float trans;
            md->ops->integrate(md->data, &local, 0.5f, &rgb, &trans);
            if (through >= 0.5f && through * trans < 0.5f)
                *t_seen = 0.5f * (local.t_near + local.t_far);
            through *= trans;
        }
    }
    return 1.f - through;
}

/* Lowest and highest of box b along unit vector up. */
static void along(const aabb *b, vec3 up, float *lo, float *hi)
{
    *lo = INFINITY, *hi = -INFINITY;
    for (int c = 0; c < 8; c++) {
        vec3 p = v3(c & 1 ? b->hi.x : b->lo.x, c & 2 ? b->hi.y : b->lo.y, c & 4 ? b->hi.z : b->lo.z);
        float h = v3_dot(p, up);
        *lo = fminf(*lo, h), *hi = fmaxf(*hi, h);
    }
}

/* The lowest point above the floor (height floor_h along up, which must be
 * an axis) of what iso-surface instance `inst` shows, or with UINT32_MAX of
 * what the volumes rendered directly show, within box b: rays straight up
 * from the floor over a PROBES x PROBES lattice across b; each gives its
 * first hit of the instance or where half the light is taken. What lies
 * under the floor is hidden by it and not looked at. INFINITY: nothing. */
#define PROBES 48
static float lowest_above_floor(const scene *s, const accel *a, uint32_t inst, const aabb *b, vec3 up,
                                float floor_h)
{
    const float u[3] = {up.x, up.y, up.z}, blo[3] = {b->lo.x, b->lo.y, b->lo.z}, bhi[3] = {b->hi.x, b->hi.y, b->hi.z};
    int axis = fabsf(u[0]) > 0.999f ? 0 : fabsf(u[1]) > 0.999f ? 1 : 2;
    cr_assert_gt(fabsf(u[axis]), 0.999f, "the floor check needs a camera up along an axis");
    int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    float lo, hi;
    along(b, up, &lo, &hi);
    float start = fmaxf(lo, floor_h) + 1e-4f * (hi - lo), lowest = INFINITY;
    for (int i = 0; i < PROBES; i++)
        for (int j = 0; j < PROBES; j++) {
            float o[3];
            o[axis] = start * u[axis];
            o[ua] = blo[ua] + (bhi[ua] - blo[ua]) * ((float)i + 0.5f) / PROBES;
            o[va] = blo[va] + (bhi[va] - blo[va]) * ((float)j + 0.5f) / PROBES;
            ray r = {v3(o[0], o[1], o[2]), up, 0.f, hi - start};
            float t;
            if (inst == UINT32_MAX) {
                media_opacity(s, &r, &t);
            } else {
                hit h;
                t = accel_intersect_instance(a, inst, &r, NULL, &h) ? h.t : INFINITY;
            }
            lowest = fminf(lowest, start + t);
        }
    return lowest;
}

/* The scene's accel (*a, the caller destroys it), its own camera at W x H
 * (*cam) and the picture from it (the caller frees it). */
static float *render_own_camera(const char *name, scene *s, accel **a, camera_basis *cam)
{
    cr_assert(s->has_camera, "%s: an example scene has its own camera", name);
    *cam = camera_basis_make(&s->camera, W, H);
    tess_error err = {{0}};
    *a = accel_build(s, THREADS, &err);
    cr_assert_not_null(*a, "%s: accel_build: %s", name, err.msg);
    return render(s, *a, cam);
}

/* The render checks of one scene whose data are all there. */
static void check_picture(const char *name, scene *s)
{
    accel *a;
    camera_basis cam;
    float *rgb = render_own_camera(name, s, &a, &cam);
    vec3 up = v3_normalize(s->camera.up);

    /* which pixels show the subject */
    int subject = 0, subject_coloured = 0, x0 = W, y0 = H, x1 = -1, y1 = -1;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            ray r = {cam.eye, v3_normalize(camera_pixel_direction(&cam, x, y)), 0.f, FLT_MAX};
            hit h;
            bool any = accel_intersect(a, &r, &h);
            bool shows = any && !is_backdrop(s, h.geom_id);
            if (s->medium_count > 0) {
                ray m = r;
                if (any)
                    m.t_far = h.t;
                float t_half;
                shows |= media_opacity(s, &m, &t_half) >= SUBJECT_OPACITY;
            }
            if (!shows)
                continue;
            subject++;
            subject_coloured += !is_background(s, rgb + 3 * ((size_t)y * W + x));
            x0 = x < x0 ? x : x0, x1 = x > x1 ? x : x1;
            y0 = y < y0 ? y : y0, y1 = y > y1 ? y : y1;
        }
    double share = (double)subject / (W * H);
    cr_expect_geq(share, MIN_SUBJECT_SHARE, "%s: the subject shows in %d of %d pixels (want %.0f%% at least)", name,
                  subject, W * H, 100 * MIN_SUBJECT_SHARE);
    cr_expect_geq(subject_coloured, subject * 9 / 10, "%s: %d of the subject's %d pixels have the background's colour",
                  name, subject - subject_coloured, subject);
    const int mx = (int)ceil(MARGIN * W), my = (int)ceil(MARGIN * H);
    cr_expect(subject == 0 || (x0 >= mx && y0 >= my && x1 <= W - 1 - mx && y1 <= H - 1 - my),
              "%s: the subject is cut off by the image's edge or nearly: it spans columns %d..%d and rows %d..%d of "
              "%dx%d (want %d columns and %d rows clear at each edge)", name, x0, x1, y0, y1, W, H, mx, my);

    /* the floor: the lowest backdrop quad flat across up */
    float floor_h = INFINITY;
    for (uint32_t i = 0; i < s->instance_count; i++) {
        aabb b;
        float lo, hi;
        if (!is_backdrop(s, i) || !scene_instance_bounds(s, i, &b))
            continue;
        along(&b, up, &lo, &hi);
        if (hi - lo <= 1e-4f * (fabsf(lo) + 1.f))
            floor_h = fminf(floor_h, lo);
    }
    char floor_note[400] = "no floor";
    if (isfinite(floor_h)) {
        int n = snprintf(floor_note, sizeof floor_note, "floor at %g; lowest point above it:", floor_h);
        /* meshes, spheres, particles by their bounds; iso-surfaces and the
         * volumes rendered directly (all together) by probing up from the floor */
        for (uint32_t i = 0; i <= s->instance_count; i++) {
            bool media = i == s->instance_count;
            if (media && s->medium_count == 0)
                break;
            const scene_geometry *g = media ? NULL : scene_instance_geometry(s, i);
            const char *what = media ? "volume" : g->name;
            aabb b;
            float lo, hi;
            if (media) {
                b = aabb_empty();
                for (uint32_t m = 0; m < s->medium_count; m++) {
                    aabb mb;
                    if (s->media[m].ops->bounds(s->media[m].data, &mb))
                        b = aabb_grow(b, affine3_box(&s->media[m].to_world, mb));
                }
            } else if (is_backdrop(s, i) || !scene_instance_bounds(s, i, &b)) {
                continue;
            }
            along(&b, up, &lo, &hi);
            if (media || strcmp(g->ops->name, "iso-surface") == 0)
                lo = lowest_above_floor(s, a, media ? UINT32_MAX : i, &b, up, floor_h);
            float gap = lo - floor_h, tol = FLOOR_TOLERANCE * (hi - floor_h);
            cr_expect(fabsf(gap) <= tol, "%s: %s (%s) does not rest on the floor: its lowest point is %g above it "
                      "(tolerance %g)", name, what, media ? "rendered directly" : g->ops->name, gap, tol);
            if (n > 0 && (size_t)n < sizeof floor_note)
                n += snprintf(floor_note + n, sizeof floor_note - (size_t)n, " %s %.3g", what, gap);
        }
    }
    cr_log_info("example_scenes: %s: subject in %.1f%% of %dx%d, columns %d..%d, rows %d..%d; %s", name, 100 * share,
                W, H, x0, x1, y0, y1, floor_note);
    free(rgb);
    accel_destroy(a);
}

/* The picture of a scene whose subject could not all be loaded: not empty
 * (at least the floor shows). */
static void check_not_empty(const char *name, scene *s)
{
    accel *a;
    camera_basis cam;
    float *rgb = render_own_camera(name, s, &a, &cam);
    int shown = 0;
    for (int i = 0; i < W * H; i++)
        shown += !is_background(s, rgb + 3 * i);
    cr_expect_gt(shown, W * H / 10, "%s without its data: only %d of %d pixels are not the background", name, shown,
                 W * H);
    free(rgb);
    accel_destroy(a);
}

/* ---- the tests ------------------------------------------------------------ */

Test(example_scenes, load_without_the_shared_data_and_name_what_is_missing, .timeout = 60)
{
    static char names[MAX_SCENES][NAME_BYTES], text[1 << 16], refs[MAX_REFS][256];
    static log_lines lines;
    int count = list_scenes(names);
    /* TMP/r/configs/scenes/NAME.json: ../../../shared is TMP/shared, which is not there */
    char dir[256], scenes[320], data[PATH_MAX], path[700];
    support_make_tmp_dir(dir, sizeof dir, "example-scenes");
    snprintf(scenes, sizeof scenes, "%s/r/configs/scenes", dir);
    snprintf(path, sizeof path, "mkdir -p '%s'", scenes);
    cr_assert_eq(support_run(path), 0);
    cr_assert_not_null(realpath(SCENES_DIR "/data", data));
    snprintf(path, sizeof path, "%s/data", scenes);
    cr_assert_eq(symlink(data, path), 0, "symlink %s", path);
    int with_shared = 0;
    for (int k = 0; k < count; k++) {
        snprintf(path, sizeof path, "%s/%.127s", SCENES_DIR, names[k]);
        read_whole(path, text, sizeof text);
        int ref_count = shared_refs(text, refs);
        bool missing[MAX_REFS];
        for (int r = 0; r < ref_count; r++)
            missing[r] = true;
        with_shared += ref_count > 0;
        snprintf(path, sizeof path, "%s/%.127s", scenes, names[k]);
        FILE *f = fopen(path, "wb");
        cr_assert_not_null(f);
        cr_assert_eq(fwrite(text, 1, strlen(text), f), strlen(text));
        fclose(f);
        tess_error err = {{0}};
        scene *s = load_quietly(path, &lines, &err);
        cr_assert_not_null(s, "%s without ../shared: %s", names[k], err.msg);
        check_missing_named(names[k], &lines, refs, ref_count, missing);
        check_not_empty(names[k], s);
        scene_destroy(s);
    }
    support_remove_tmp_dir(dir);
    cr_expect_geq(with_shared, 3, "only %d example scenes name shared data", with_shared);
}

Test(example_scenes, render_small_with_the_subject_whole_and_on_its_floor, .timeout = 180)
{
    static char names[MAX_SCENES][NAME_BYTES], text[1 << 16], refs[MAX_REFS][256];
    static log_lines lines;
    double start = seconds();
    int count = list_scenes(names);
    for (int k = 0; k < count; k++) {
        char path[600];
        snprintf(path, sizeof path, "%s/%.127s", SCENES_DIR, names[k]);
        read_whole(path, text, sizeof text);
        int ref_count = shared_refs(text, refs);
        bool missing[MAX_REFS];
        int missing_count = 0;
        for (int r = 0; r < ref_count; r++)
            missing_count += missing[r] = !shared_file_there(refs[r]);
        double t0 = seconds();
        tess_error err = {{0}};
        scene *s = load_quietly(path, &lines, &err);
        cr_assert_not_null(s, "%s: %s", names[k], err.msg);
        double t1 = seconds();
        /* a pattern whose folder is there may still match nothing: the loader's word decides */
        for (int i = 0; i < lines.count; i++)
            for (int r = 0; r < ref_count; r++)
                if (!missing[r] && is_skip_line(lines.line[i]) && strstr(lines.line[i], refs[r]))
                    missing[r] = true, missing_count++;
        check_missing_named(names[k], &lines, refs, ref_count, missing);
        if (missing_count > 0) {
            int r = 0;
            while (!missing[r])
                r++;
            cr_log_info("SKIPPED: example_scenes::render_small_with_the_subject_whole_and_on_its_floor: %s: the "
                        "subject's checks: ../shared/data/%s is missing (%d of its %d shared files); what loaded "
                        "was rendered and is not empty",
                        names[k], refs[r], missing_count, ref_count);
            check_not_empty(names[k], s);
        } else {
            check_picture(names[k], s);
        }
        scene_destroy(s);
        cr_log_info("example_scenes: %s: loaded in %.2f s, built, rendered and checked in %.2f s", names[k], t1 - t0,
                    seconds() - t1);
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    cr_log_info("example_scenes: %d scenes in %.1f s, %.1f s of CPU", count, seconds() - start,
                (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
                    1e-6 * (double)ru.ru_stime.tv_usec);
}
