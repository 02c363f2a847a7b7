/* test_bench_cli.c - `tessera bench` end to end: the BENCH line has every
 * field, and the fields agree with the scene and with each other; bad options
 * give one error line and no BENCH line. Speeds are never asserted (only that
 * they are positive): the suite runs on shared, noisy machines.
 * Runs ../tessera (or $TESSERA_BIN) from the tests/ directory. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "support.h"
#include "wall/dump.h"
#include "engine/load/mesh_load.h"

/* Seconds one bench command may take before the test counts it as a hang. */
#define BENCH_TIMEOUT_S 60
#define OUTPUT_BYTES 16384

static char tmp_dir[256];

/* Every field of the BENCH line, in the documented order. */
static const char *const bench_fields[] = {
    "scene",        "size",         "threads",  "frames",        "warmup",     "shadows",     "isa",
    "triangles",    "spheres",      "load_s",   "build_s",       "prim_mrays", "total_mrays", "frame_ms_median",
    "frame_ms_min", "frame_ms_max", "hit_rate", "bytes_per_tri", "mesh_bytes", "accel_bytes", "cpu_other",
    "hits",         "instances",    "geometries", "triangles_instanced", "bytes_per_instanced_tri",
    "renderer",     "opacity",      "secondary_rays_frame", "tile_px", "peak_rss_mb", "rss_after_build_mb",
};
#define BENCH_FIELD_COUNT (sizeof bench_fields / sizeof bench_fields[0])

static void make_tmp_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "bench"); }

static void remove_tmp_dir(void) { support_remove_tmp_dir(tmp_dir); }


/* Run `tessera bench ARGS` (every %s in ARGS is the temp dir) with stdout and
 * stderr kept apart; returns the exit status (128+signal when killed). */
static int run_bench(char *out, char *err, const char *args_fmt)
{
    return support_tessera_bench(tmp_dir, BENCH_TIMEOUT_S, out, err, OUTPUT_BYTES, args_fmt);
}

static int count_lines(const char *text)
{
    int n = 0;
    for (const char *p = text; *p; p++)
        n += *p == '\n';
    return n;
}

/* The text after " key=" in a BENCH line, up to the next space, or NULL. */
static const char *field_text(const char *line, const char *key, char *buf, size_t buf_bytes)
{
    char needle[64];
    snprintf(needle, sizeof needle, " %s=", key);
    const char *p = strstr(line, needle);
    if (!p)
        return NULL;
    p += strlen(needle);
    size_t n = strcspn(p, " \n");
    if (n >= buf_bytes)
        n = buf_bytes - 1;
    memcpy(buf, p, n);
    buf[n] = '\0';
    return buf;
}

/* A numeric field; fails the test when it is missing or not a number. */
static double field(const char *line, const char *key)
{
    char buf[256];
    const char *text = field_text(line, key, buf, sizeof buf);
    cr_assert(text, "BENCH line lacks %s=: %s", key, line);
    char *end;
    double v = strtod(text, &end);
    cr_assert(end != text && *end == '\0' && isfinite(v), "%s=%s is not a number", key, text);
    return v;
}

/* Run a bench that must succeed; checks the shape of its output and leaves
 * the BENCH line in `line`. */
static void run_ok(const char *args_fmt, char *line)
{
    char err[OUTPUT_BYTES];
    int code = run_bench(line, err, args_fmt);
    cr_assert_eq(code, 0, "bench %s: exit %d: %s", args_fmt, code, err);
    cr_assert_eq(count_lines(line), 1, "bench %s: stdout should be one line: %s", args_fmt, line);
    cr_assert(!strncmp(line, "BENCH scene=", 12), "bench %s: not a BENCH line: %s", args_fmt, line);
    /* every field present, in the documented order */
    const char *at = line;
    for (size_t i = 0; i < BENCH_FIELD_COUNT; i++) {
        char needle[64];
        snprintf(needle, sizeof needle, " %s=", bench_fields[i]);
        const char *p = strstr(at, needle);
        cr_assert(p, "field %s missing or out of order: %s", bench_fields[i], line);
        at = p + 1;
    }
}

/* What holds for any successful run. */
static void check_consistent(const char *line)
{
    double prim = field(line, "prim_mrays"), total = field(line, "total_mrays");
    cr_expect(prim > 0.0, "prim_mrays %g", prim);
    cr_expect(total >= prim, "total_mrays %g < prim_mrays %g", total, prim);
    double median = field(line, "frame_ms_median"), lo = field(line, "frame_ms_min"), hi = field(line, "frame_ms_max");
    cr_expect(lo > 0.0 && lo <= median && median <= hi, "frame ms min %g median %g max %g", lo, median, hi);
    cr_expect(field(line, "load_s") >= 0.0 && field(line, "build_s") >= 0.0);
    double hit_rate = field(line, "hit_rate");
    cr_expect(hit_rate > 0.0 && hit_rate <= 1.0, "hit_rate %g", hit_rate);
    double tris = field(line, "triangles"), mesh_b = field(line, "mesh_bytes"), accel_b = field(line, "accel_bytes");
    double per_tri = field(line, "bytes_per_tri");
    cr_expect(mesh_b > 0.0 && accel_b > 0.0, "mesh_bytes %g accel_bytes %g", mesh_b, accel_b);
    cr_expect(per_tri > 0.0, "bytes_per_tri %g", per_tri);
    cr_expect(fabs(per_tri - (mesh_b + accel_b) / tris) <= 0.051, "bytes_per_tri %g, expected (%g + %g) / %g",
              per_tri, mesh_b, accel_b, tris);
    double other = field(line, "cpu_other");
    cr_expect(other >= 0.0 || other == -1.0, "cpu_other %g", other);
    /* the instancing fields */
    double placed = field(line, "triangles_instanced"), per_placed = field(line, "bytes_per_instanced_tri");
    cr_expect(placed >= tris, "triangles_instanced %g < triangles %g", placed, tris);
    cr_expect(fabs(per_placed - (mesh_b + accel_b) / placed) <= 0.0051, "bytes_per_instanced_tri %g, expected (%g + %g) / %g",
              per_placed, mesh_b, accel_b, placed);
    cr_expect(field(line, "instances") >= 1 && field(line, "geometries") >= 1, "%s", line);
    /* memory after load + build: resident then, and a peak at least that */
    double peak = field(line, "peak_rss_mb"), after = field(line, "rss_after_build_mb");
    cr_expect(after > 0.0 && peak >= after, "peak_rss_mb %g, rss_after_build_mb %g", peak, after);
    char size[64];
    int w = 0, h = 0;
    cr_assert(field_text(line, "size", size, sizeof size) && sscanf(size, "%dx%d", &w, &h) == 2);
    cr_expect(fabs(field(line, "hits") - hit_rate * w * h) <= 0.00005 * w * h + 0.5, "hits %g, hit_rate %g, %dx%d",
              field(line, "hits"), hit_rate, w, h);
}

/* An ascii PLY octahedron: 6 vertices, 8 triangles, closed (so shadow rays
 * from its lit side are traced and some hit it). */
static void write_octahedron(const char *name)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", tmp_dir, name);
    FILE *f = fopen(path, "wb");
    cr_assert(f, "cannot write %s", path);
    fputs("ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
          "element face 8\nproperty list uchar int vertex_indices\nend_header\n"
          "1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
          "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n",
          f);
    fclose(f);
}

/* Expect a clean failure: the exit code, one error line naming each needle,
 * no BENCH line. */
static void expect_error(int want_code, const char *args_fmt, const char *const *needles)
{
    char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    int code = run_bench(out, err, args_fmt);
    cr_expect_eq(code, want_code, "bench %s: exit %d, expected %d: %s", args_fmt, code, want_code, err);
    cr_expect_eq(count_lines(err), 1, "bench %s: stderr should be one line: %s", args_fmt, err);
    cr_expect(!strncmp(err, "tessera: error: ", 16), "bench %s: %s", args_fmt, err);
    cr_expect(!strstr(out, "BENCH"), "bench %s printed a result: %s", args_fmt, out);
    for (const char *const *n = needles; *n; n++)
        cr_expect(strstr(err, *n), "bench %s: message lacks '%s': %s", args_fmt, *n, err);
}

#define EXPECT_ERROR(code, args, ...) expect_error(code, args, (const char *const[]){__VA_ARGS__, NULL})

TestSuite(bench_cli, .init = make_tmp_dir, .fini = remove_tmp_dir, .timeout = 240);

Test(bench_cli, help_documents_options_and_every_field)
{
    char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    cr_assert_eq(run_bench(out, err, "--help"), 0, "%s", err);
    const char *options[] = {"--scene",  "--size",   "--threads", "--frames",  "--warmup",     "--shadows",
                             "--camera", "--isa",    "--out",     "--flatten", "--part-txns", "PARTTXN",
                             "--renderer", "--ao-rays", "--ao-dist", "--ao-filter", "--ao-interleave", "--opacity"};
    for (size_t i = 0; i < sizeof options / sizeof options[0]; i++)
        cr_expect(strstr(out, options[i]), "bench --help lacks %s", options[i]);
    for (size_t i = 0; i < BENCH_FIELD_COUNT; i++) {
        char needle[64];
        snprintf(needle, sizeof needle, "%s=", bench_fields[i]);
        cr_expect(strstr(out, needle), "bench --help lacks the field %s", bench_fields[i]);
    }
}

Test(bench_cli, default_scene)
{
    char line[OUTPUT_BYTES], buf[256];
    run_ok("--size 64x36 --threads 2 --frames 3", line);
    check_consistent(line);
    cr_expect_str_eq(field_text(line, "scene", buf, sizeof buf), "default");
    cr_expect_str_eq(field_text(line, "size", buf, sizeof buf), "64x36");
    cr_expect_eq(field(line, "threads"), 2);
    cr_expect_eq(field(line, "frames"), 3);
    cr_expect_eq(field(line, "warmup"), 1);
    cr_expect_eq(field(line, "shadows"), 0);
    cr_expect_eq(field(line, "total_mrays"), field(line, "prim_mrays"), "no shadow rays, yet total != primary");
    const char *isa = field_text(line, "isa", buf, sizeof buf);
    cr_expect(isa && (!strcmp(isa, "sse2") || !strcmp(isa, "avx2") || !strcmp(isa, "avx512")), "isa=%s",
              isa ? isa : "(missing)");

    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert(s, "%s", err.msg);
    size_t mesh_b = 0;
    for (uint32_t i = 0; i < s->mesh_count; i++)
        mesh_b += mesh_bytes(s->meshes[i]->mesh);
    cr_expect_eq(field(line, "triangles"), (double)scene_triangle_count(s));
    cr_expect_eq(field(line, "spheres"), (double)s->spheres.count);
    cr_expect_eq(field(line, "mesh_bytes"), (double)mesh_b);
    scene_destroy(s);
}

/* --opacity: rays blend what they cross; the layers past the first are counted */
Test(bench_cli, opacity_blends_layers)
{
    char line[OUTPUT_BYTES];
    run_ok("--size 64x36 --threads 2 --frames 2", line);
    cr_expect_eq(field(line, "opacity"), 1.0);
    cr_expect_eq(field(line, "secondary_rays_frame"), 0.0, "opaque: no layers");
    run_ok("--size 64x36 --threads 2 --frames 2 --opacity 0.3", line);
    check_consistent(line);
    cr_expect_float_eq(field(line, "opacity"), 0.3, 1e-6);
    cr_expect(field(line, "secondary_rays_frame") > field(line, "hits") / 4,
              "opacity 0.3: few rays went past their first surface: %s", line);
}

/* --renderer ao: the AO fields; with the filter off the AO rays are hits x N
 * (the peer's count), with it the apron adds primary and AO rays. */
Test(bench_cli, ambient_occlusion_renderer)
{
    char line[OUTPUT_BYTES], buf[256];
    run_ok("--size 64x36 --threads 2 --frames 2 --renderer ao --ao-rays 4 --ao-filter 1", line);
    check_consistent(line);
    cr_expect_str_eq(field_text(line, "renderer", buf, sizeof buf), "ao");
    cr_expect_eq(field(line, "ao_rays"), 4);
    cr_expect_eq(field(line, "ao_filter"), 1);
    cr_expect(field(line, "ao_dist") > 0.0);
    cr_expect_eq(field(line, "ao_rays_frame"), 4 * field(line, "hits"), "AO rays %g, hits %g", field(line, "ao_rays_frame"),
                 field(line, "hits"));
    cr_expect_eq(field(line, "primary_rays_frame"), 64 * 36);
    cr_expect(field(line, "ao_mrays") > 0.0);
    run_ok("--size 64x36 --threads 1 --frames 1 --renderer ao --ao-rays 4 --ao-dist 0.5", line);
    cr_expect_eq(field(line, "ao_filter"), 5);
    cr_expect_eq(field(line, "ao_dist"), 0.5);
    cr_expect(field(line, "primary_rays_frame") > 64 * 36, "the apron traces pixels again");
    char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    cr_expect_eq(run_bench(out, err, "--renderer ao --shadows --size 8x8"), 2, "ao with --shadows: %s", err);
    cr_expect_eq(run_bench(out, err, "--renderer ao --ao-filter 4 --size 8x8"), 2, "an even filter: %s", err);
    cr_expect_eq(run_bench(out, err, "--renderer phong --size 8x8"), 2, "an unknown renderer: %s", err);
}

Test(bench_cli, mesh_file_primary_and_shadows)
{
    char line[OUTPUT_BYTES], path[512];
    write_octahedron("octa.ply");
    run_ok("--scene %s/octa.ply --size 48x32 --threads 1 --frames 2 --warmup 0", line);
    check_consistent(line);
    cr_expect_eq(field(line, "triangles"), 8);
    cr_expect_eq(field(line, "spheres"), 0);
    cr_expect_eq(field(line, "warmup"), 0);
    double hit_rate = field(line, "hit_rate");
    cr_expect(hit_rate < 1.0, "the framed octahedron cannot fill the image: hit_rate %g", hit_rate);

    snprintf(path, sizeof path, "%s/octa.ply", tmp_dir);
    tess_error err = {{0}};
    mesh *m = mesh_load(path, &err);
    cr_assert(m, "%s", err.msg);
    cr_expect_eq(field(line, "mesh_bytes"), (double)mesh_bytes(m));
    mesh_destroy(m);

    char shadow_line[OUTPUT_BYTES];
    run_ok("--scene %s/octa.ply --size 48x32 --threads 2 --frames 2 --shadows", shadow_line);
    check_consistent(shadow_line);
    cr_expect_eq(field(shadow_line, "shadows"), 1);
    cr_expect(field(shadow_line, "total_mrays") > field(shadow_line, "prim_mrays"), "%s", shadow_line);
    cr_expect_eq(field(shadow_line, "hit_rate"), hit_rate, "shadows changed which pixels hit: %s", shadow_line);
}

Test(bench_cli, out_writes_the_last_frame)
{
    char line[OUTPUT_BYTES], path[512];
    write_octahedron("octa.ply");
    run_ok("--scene %s/octa.ply --size 40x30 --threads 1 --frames 1 --out %s/shade.pfm", line);
    snprintf(path, sizeof path, "%s/shade.pfm", tmp_dir);
    FILE *f = fopen(path, "rb");
    cr_assert(f, "no %s", path);
    char magic[3] = {0};
    int w = 0, h = 0;
    double scale = 0.0;
    cr_assert_eq(fscanf(f, "%2s %d %d %lf", magic, &w, &h, &scale), 4);
    cr_expect_str_eq(magic, "Pf");
    cr_expect(w == 40 && h == 30 && scale == -1.0, "PFM header %d %d %g", w, h, scale);
    fgetc(f); /* the newline after the scale */
    float grey[40 * 30];
    cr_assert_eq(fread(grey, sizeof grey[0], 40 * 30, f), 40 * 30, "PFM too short");
    fclose(f);
    int hits = 0;
    for (int i = 0; i < 40 * 30; i++) {
        cr_assert(grey[i] >= 0.f && grey[i] <= 1.f, "pixel %d = %g", i, grey[i]);
        hits += grey[i] > 0.f;
    }
    cr_expect_eq(hits, (int)lround(field(line, "hit_rate") * 40 * 30), "hit_rate disagrees with the image");

    run_ok("--scene %s/octa.ply --size 40x30 --threads 1 --frames 1 --out %s/shade.png", line);
    snprintf(path, sizeof path, "%s/shade.png", tmp_dir);
    uint8_t *rgb;
    tess_error err = {{0}};
    cr_assert(dump_read_rgb8(path, &w, &h, &rgb, &err), "%s", err.msg);
    cr_expect(w == 40 && h == 30);
    free(rgb);
}

Test(bench_cli, scene_path_with_space_stays_one_field)
{
    char line[OUTPUT_BYTES], buf[512];
    write_octahedron("two words.ply");
    run_ok("--scene '%s/two words.ply' --size 16x16 --threads 1 --frames 1", line);
    const char *scene_field = field_text(line, "scene", buf, sizeof buf);
    cr_expect(scene_field && strstr(scene_field, "two%20words.ply"), "scene=%s",
              scene_field ? scene_field : "(missing)");
    cr_expect_eq(field(line, "triangles"), 8);
}

Test(bench_cli, isa_option_picks_the_kernels)
{
    char line[OUTPUT_BYTES], buf[64];
    run_ok("--size 32x18 --threads 1 --frames 1 --isa sse2", line); /* every x86-64 CPU runs SSE2 */
    cr_expect_str_eq(field_text(line, "isa", buf, sizeof buf), "sse2");
}

/* TESSERA_ISA_MAX caps the kernels as a CPU without the ISAs above it would:
 * the bench picks SSE2 under TESSERA_ISA_MAX=sse2, --isa above the cap is
 * refused saying why (the cap, or a CPU that lacks it too), and a value that
 * names no ISA stops tessera before anything runs. */
Test(bench_cli, the_isa_cap_holds_and_a_bad_one_is_named)
{
    char line[OUTPUT_BYTES], buf[64];
    cr_assert_eq(setenv("TESSERA_ISA_MAX", "sse2", 1), 0); /* inherited by the bench process */
    run_ok("--size 32x18 --threads 1 --frames 1", line);
    cr_expect_str_eq(field_text(line, "isa", buf, sizeof buf), "sse2");
    char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    int code = run_bench(out, err, "--size 16x16 --threads 1 --frames 1 --isa avx2");
    cr_expect_eq(code, 1, "exit %d: %s", code, err);
    cr_expect(strstr(err, "--isa avx2") && (strstr(err, "TESSERA_ISA_MAX=sse2 caps it") || strstr(err, "lacks avx2")),
              "%s", err);
    cr_assert_eq(setenv("TESSERA_ISA_MAX", "avx3", 1), 0);
    EXPECT_ERROR(2, "--size 16x16", "TESSERA_ISA_MAX=avx3", "not an instruction set", "sse2, avx2, avx512");
    cr_assert_eq(unsetenv("TESSERA_ISA_MAX"), 0);
}

Test(bench_cli, bad_options_give_one_line)
{
    EXPECT_ERROR(2, "--bogus", "unknown option", "--bogus");
    EXPECT_ERROR(2, "--frames 0", "--frames", "from 1");
    EXPECT_ERROR(2, "--warmup -1", "--warmup", "from 0");
    EXPECT_ERROR(2, "--opacity 1.5", "--opacity");
    EXPECT_ERROR(2, "--threads zero", "--threads", "whole number");
    EXPECT_ERROR(2, "--size 640", "--size", "WIDTHxHEIGHT");
    EXPECT_ERROR(2, "--camera 1,2,3", "--camera");
    EXPECT_ERROR(2, "--scene", "--scene", "needs a value");
    EXPECT_ERROR(2, "--no-shadows", "unknown option");
    EXPECT_ERROR(2, "--isa neon", "--isa", "neon");
    EXPECT_ERROR(2, "--flatten --size 16x16", "--flatten", "--scene");
    EXPECT_ERROR(2, "--part-txns 0", "--part-txns", "from 1");
    EXPECT_ERROR(1, "--scene %s/missing.ply --size 16x16", "missing.ply");
    EXPECT_ERROR(1, "--size 16x16 --out %s/no/such/dir/x.pfm", "no/such/dir", "directory");
}

/* ---- parts and instances (suite bench_parts) ---- */

#define ASSEMBLY "data/assembly-small.glb"
/* the parts scene's default framing at 320x180, given to both runs so that
 * they trace the same rays */
#define ASSEMBLY_CAMERA "9.42882,3.01429,9.04286,3.40025,0,0,0,1,0,40"

TestSuite(bench_parts, .init = make_tmp_dir, .fini = remove_tmp_dir, .timeout = 240);

Test(bench_parts, flatten_traces_the_same_triangles_as_the_parts)
{
    char parts[OUTPUT_BYTES], flat[OUTPUT_BYTES];
    run_ok("--scene " ASSEMBLY " --size 320x180 --threads 2 --frames 1 --camera " ASSEMBLY_CAMERA, parts);
    run_ok("--scene " ASSEMBLY " --flatten --size 320x180 --threads 2 --frames 1 --camera " ASSEMBLY_CAMERA, flat);
    check_consistent(parts);
    check_consistent(flat);

    tess_error err = {{0}};
    scene *s = scene_load(ASSEMBLY, &err);
    cr_assert(s, "%s", err.msg);
    cr_expect_eq(field(parts, "instances"), (double)s->instance_count);
    cr_expect_eq(field(parts, "geometries"), (double)s->geometry_count);
    cr_expect_eq(field(parts, "triangles"), (double)scene_triangle_count(s));
    cr_expect_eq(field(parts, "triangles_instanced"), (double)scene_instanced_triangle_count(s));
    cr_expect(field(parts, "instances") > field(parts, "geometries"), "the assembly places meshes more than once");
    cr_expect(field(parts, "triangles_instanced") > field(parts, "triangles"), "%s", parts);
    scene_destroy(s);

    /* flattened: one mesh holding every placed triangle */
    cr_expect_eq(field(flat, "instances"), 1);
    cr_expect_eq(field(flat, "geometries"), 1);
    cr_expect_eq(field(flat, "triangles"), field(parts, "triangles_instanced"), "flat %s\nparts %s", flat, parts);
    cr_expect_eq(field(flat, "triangles_instanced"), field(parts, "triangles_instanced"));
    /* instancing stores less per placed triangle */
    cr_expect(field(parts, "bytes_per_instanced_tri") < field(flat, "bytes_per_instanced_tri"), "parts %s\nflat %s",
              parts, flat);
    /* the same picture: the transforms baked by assimp round differently from
     * tessera's per-instance ones only in the last bits */
    double hp = field(parts, "hits"), hf = field(flat, "hits");
    cr_expect(hp > 0 && fabs(hp - hf) <= 0.001 * hp + 1.0, "hits: parts %g, flat %g", hp, hf);
}

Test(bench_parts, part_txns_line_and_the_hides_take_effect)
{
    char out[OUTPUT_BYTES], err[OUTPUT_BYTES], buf[512];
    int code = run_bench(out, err, "--scene " ASSEMBLY " --size 320x180 --threads 2 --part-txns 3");
    cr_assert_eq(code, 0, "exit %d: %s", code, err);
    cr_assert_eq(count_lines(out), 1, "stdout should be one line: %s", out);
    cr_assert(!strncmp(out, "PARTTXN scene=", 14), "not a PARTTXN line: %s", out);
    cr_expect(!strstr(out, "BENCH"), "%s", out);
    cr_expect_str_eq(field_text(out, "check", buf, sizeof buf), "ok");
    cr_expect_eq(field(out, "rounds"), 3);
    cr_expect_eq(field(out, "threads"), 2);

    tess_error e = {{0}};
    scene *s = scene_load(ASSEMBLY, &e);
    cr_assert(s, "%s", e.msg);
    cr_expect_eq(field(out, "instances"), (double)s->instance_count);
    double section_n = field(out, "section_instances"), bolt_n = field(out, "bolt_instances");
    cr_expect(section_n >= 1 && section_n < s->instance_count, "section_instances %g", section_n);
    cr_expect(bolt_n >= 1 && bolt_n < section_n, "bolt_instances %g", bolt_n);
    cr_expect(field(out, "part_instance") < s->instance_count);
    scene_destroy(s);
    const char *section = field_text(out, "section", buf, sizeof buf);
    cr_expect(section && !strncmp(section, "assembly/section-", 17), "section=%s", section ? section : "(missing)");
    const char *bolt = field_text(out, "bolt", buf, sizeof buf);
    cr_expect(bolt && strstr(bolt, "/bolt-"), "bolt=%s", bolt ? bolt : "(missing)");
    /* the check is only worth something when the hidden section was in view */
    cr_expect(field(out, "section_hits") > 0, "%s", out);

    static const char *const kinds[] = {"hide_section", "isolate_bolt", "show_all", "hide_part", "show_part"};
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
        char key[64];
        snprintf(key, sizeof key, "%s_us_median", kinds[k]);
        double median = field(out, key);
        snprintf(key, sizeof key, "%s_us_max", kinds[k]);
        double max = field(out, key);
        cr_expect(median >= 0.0 && median <= max, "%s: median %g max %g", kinds[k], median, max);
    }
}

Test(bench_parts, part_txns_needs_an_assembly)
{
    char out[OUTPUT_BYTES], err[OUTPUT_BYTES];
    write_octahedron("octa.ply");
    int code = run_bench(out, err, "--scene %s/octa.ply --size 16x16 --part-txns 2");
    cr_expect_eq(code, 1, "exit %d: %s", code, err);
    cr_expect(strstr(err, "tessera: error: ") && strstr(err, "--part-txns needs an assembly"), "%s", err);
    cr_expect(!strstr(out, "PARTTXN") && !strstr(out, "BENCH"), "%s", out);
}
