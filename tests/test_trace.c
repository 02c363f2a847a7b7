/* test_trace.c - `tessera trace` end to end: rays written to a file, traced by
 * the binary, and the hits compared bit for bit with accel_intersect /
 * accel_occluded run here on the same scene; and every input error gets one
 * clear line and a non-zero exit. Runs ../tessera (or $TESSERA_BIN) from the
 * tests/ directory; scenes and rays are generated into a mkdtemp directory. */
#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "support.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"

/* Seconds one run of the binary may take before it counts as a hang. */
#define TRACE_TIMEOUT_S 60
/* Rays in the main file: more than one 65536-ray chunk of the command, and
 * not a multiple of the 64-ray packet, so both boundaries are crossed. */
#define TRACE_RAYS 70001u

static char tmp_dir[256]; /* this test's mkdtemp directory */

static void make_dir(void) { support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "trace"); }

static void path_in_dir(char *out, size_t size, const char *name) { snprintf(out, size, "%s/%s", tmp_dir, name); }

/* Run `tessera trace ARGS`, where every "@" in ARGS is replaced by the temp
 * directory. Returns the exit status (128 + signal when killed); stdout and
 * stderr go to `log`. */
static int run_trace(char *log, size_t log_size, const char *args)
{
    char expanded[2048] = "", cmd[4096], log_path[512];
    size_t n = 0;
    for (const char *a = args; *a && n + sizeof tmp_dir < sizeof expanded; a++) {
        if (*a == '@')
            n += (size_t)snprintf(expanded + n, sizeof expanded - n, "%s", tmp_dir);
        else
            expanded[n++] = *a;
    }
    expanded[n] = '\0';
    path_in_dir(log_path, sizeof log_path, "trace.log");
    snprintf(cmd, sizeof cmd, "timeout %d %s trace %s > %s 2>&1", TRACE_TIMEOUT_S, support_tessera_bin(), expanded,
             log_path);
    int code = support_run(cmd);
    support_read_text(log_path, log, log_size);
    return code;
}

static void write_bytes(const char *name, const void *data, size_t size)
{
    char path[512];
    path_in_dir(path, sizeof path, name);
    FILE *f = fopen(path, "wb");
    cr_assert(f, "cannot write %s", path);
    cr_assert_eq(fwrite(data, 1, size, f), size);
    cr_assert_eq(fclose(f), 0);
}

/* The whole file (caller frees); *size its length. */
static unsigned char *read_bytes(const char *name, size_t *size)
{
    char path[512];
    path_in_dir(path, sizeof path, name);
    FILE *f = fopen(path, "rb");
    cr_assert(f, "cannot read %s", path);
    cr_assert_eq(fseek(f, 0, SEEK_END), 0);
    long len = ftell(f);
    cr_assert(len >= 0);
    rewind(f);
    unsigned char *data = malloc((size_t)len + 1);
    cr_assert(data);
    cr_assert_eq(fread(data, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *size = (size_t)len;
    return data;
}

static bool exists_in_dir(const char *name)
{
    char path[512];
    path_in_dir(path, sizeof path, name);
    return access(path, F_OK) == 0;
}

static void put_u32(unsigned char *b, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        b[i] = (unsigned char)(v >> (8 * i));
}

static void put_f32(unsigned char *b, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    put_u32(b, bits);
}

static uint32_t get_u32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float get_f32(const unsigned char *b)
{
    uint32_t bits = get_u32(b);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

static uint64_t rng_state = 0x7ACE;

static double rng_unit(void) /* [0, 1), splitmix64 */
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return (double)((z ^ (z >> 31)) >> 11) * 0x1p-53;
}

static float rng_range(float lo, float hi) { return lo + (hi - lo) * (float)rng_unit(); }

/* A small scene: a binary little-endian PLY (an 8 x 8 grid floor and 200
 * random triangles) and a JSON file that adds it, a second mesh (the same
 * file, moved) and 20 spheres: geometry ids 0, 1 (meshes) and 2 (spheres). */
static void write_scene(void)
{
    const int grid = 8, soup = 200;
    const uint32_t vertices = (uint32_t)((grid + 1) * (grid + 1) + 3 * soup);
    const uint32_t faces = (uint32_t)(2 * grid * grid + soup);
    char header[512];
    int header_len = snprintf(header, sizeof header,
                              "ply\nformat binary_little_endian 1.0\nelement vertex %u\nproperty float x\n"
                              "property float y\nproperty float z\nelement face %u\n"
                              "property list uchar uint vertex_indices\nend_header\n",
                              vertices, faces);
    size_t size = (size_t)header_len + 12u * vertices + 13u * faces;
    unsigned char *ply = malloc(size), *p = ply;
    cr_assert(ply);
    memcpy(p, header, (size_t)header_len);
    p += header_len;
    for (int j = 0; j <= grid; j++)
        for (int i = 0; i <= grid; i++, p += 12) {
            put_f32(p, (float)(i - grid / 2));
            put_f32(p + 4, -2.f);
            put_f32(p + 8, (float)(j - grid / 2));
        }
    for (int k = 0; k < 3 * soup; k++, p += 12) {
        put_f32(p, rng_range(-4.f, 4.f));
        put_f32(p + 4, rng_range(-2.f, 3.f));
        put_f32(p + 8, rng_range(-4.f, 4.f));
    }
    for (int j = 0; j < grid; j++)
        for (int i = 0; i < grid; i++) {
            uint32_t a = (uint32_t)(j * (grid + 1) + i), b = a + 1, c = a + (uint32_t)grid + 1, d = c + 1;
            uint32_t tris[2][3] = {{a, c, b}, {b, c, d}};
            for (int t = 0; t < 2; t++, p += 13) {
                p[0] = 3;
                for (int k = 0; k < 3; k++)
                    put_u32(p + 1 + 4 * k, tris[t][k]);
            }
        }
    uint32_t first = (uint32_t)((grid + 1) * (grid + 1));
    for (uint32_t t = 0; t < (uint32_t)soup; t++, p += 13) {
        p[0] = 3;
        for (uint32_t k = 0; k < 3; k++)
            put_u32(p + 1 + 4 * k, first + 3 * t + k);
    }
    cr_assert_eq((size_t)(p - ply), size);
    write_bytes("mesh.ply", ply, size);
    free(ply);
    char json[4096];
    int n = snprintf(json, sizeof json,
                     "{\n  \"meshes\": [{\"file\": \"mesh.ply\"},\n"
                     "             {\"file\": \"mesh.ply\", \"transform\": {\"translate\": [0.5, 6, -1]}}],\n"
                     "  \"spheres\": [\n");
    for (int i = 0; i < 20; i++)
        n += snprintf(json + n, sizeof json - (size_t)n, "    {\"center\": [%.3f, %.3f, %.3f], \"radius\": %.3f}%s\n",
                      rng_range(-4.f, 4.f), rng_range(-1.f, 8.f), rng_range(-4.f, 4.f), rng_range(0.1f, 0.8f),
                      i < 19 ? "," : "");
    snprintf(json + n, sizeof json - (size_t)n, "  ]\n}\n");
    write_bytes("scene.json", json, strlen(json));
}

/* TRACE_RAYS rays: most aimed into the scene from around it, some missing it,
 * some with bounded intervals, and every 97th degenerate (NaN, infinities,
 * zero direction, empty interval), which must miss. */
static ray *make_rays(void)
{
    ray *rays = malloc(TRACE_RAYS * sizeof *rays);
    cr_assert(rays);
    const float nan = NAN, inf = INFINITY;
    const ray degenerate[] = {
        {v3(nan, 0.f, 9.f), v3(0.f, 0.f, -1.f), 0.f, FLT_MAX}, {v3(0.f, 0.f, 9.f), v3(0.f, inf, -1.f), 0.f, FLT_MAX},
        {v3(0.f, 0.f, 9.f), v3(0.f, 0.f, 0.f), 0.f, FLT_MAX},  {v3(0.f, 0.f, 9.f), v3(0.f, 0.f, -1.f), nan, FLT_MAX},
        {v3(0.f, 0.f, 9.f), v3(0.f, 0.f, -1.f), 5.f, 5.f},     {v3(0.f, 0.f, 9.f), v3(0.f, 0.f, -1.f), 6.f, 2.f},
    };
    for (uint32_t i = 0; i < TRACE_RAYS; i++) {
        if (i % 97 == 96) {
            rays[i] = degenerate[(i / 97) % (sizeof degenerate / sizeof degenerate[0])];
            continue;
        }
        vec3 org = v3(rng_range(-12.f, 12.f), rng_range(-1.f, 12.f), rng_range(-12.f, 12.f));
        vec3 aim = v3(rng_range(-5.f, 5.f), rng_range(-2.5f, 8.f), rng_range(-5.f, 5.f));
        if (i % 5 == 0) /* away from the scene */
            aim = v3_add(org, v3_sub(org, aim));
        vec3 dir = v3_sub(aim, org);
        if (i % 3 == 0)
            dir = v3_normalize(dir);
        float t_near = i % 7 == 0 ? rng_range(0.f, 0.5f) : 0.f;
        float t_far = i % 11 == 0 ? rng_range(0.6f, 1.2f) : i % 13 == 0 ? INFINITY : FLT_MAX;
        rays[i] = (ray){org, dir, t_near, t_far};
    }
    return rays;
}

static void write_rays(const char *name, const ray *rays, uint32_t count)
{
    unsigned char *buf = malloc((size_t)count * 32u + 1u);
    cr_assert(buf);
    for (uint32_t i = 0; i < count; i++) {
        unsigned char *b = buf + (size_t)i * 32u;
        const float v[8] = {rays[i].org.x, rays[i].org.y, rays[i].org.z, rays[i].dir.x,
                            rays[i].dir.y, rays[i].dir.z, rays[i].t_near, rays[i].t_far};
        for (int k = 0; k < 8; k++)
            put_f32(b + 4 * k, v[k]);
    }
    write_bytes(name, buf, (size_t)count * 32u);
    free(buf);
}

/* The scene as the binary loads it, built here. */
static accel *load_here(scene **s)
{
    char path[512];
    path_in_dir(path, sizeof path, "scene.json");
    tess_error err = {{0}};
    *s = scene_load(path, &err);
    cr_assert(*s, "%s", err.msg);
    cr_assert_eq((*s)->mesh_count, 2u);
    cr_assert_eq((*s)->spheres.count, 20u);
    accel *a = accel_build(*s, 2, &err);
    cr_assert(a, "%s", err.msg);
    return a;
}

static bool same_float_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

TestSuite(trace, .init = make_dir, .timeout = 300);

Test(trace, help_describes_options_and_formats)
{
    char log[8192];
    cr_assert_eq(run_trace(log, sizeof log, "--help"), 0, "%s", log);
    const char *needles[] = {"--scene", "--rays", "--hits", "--occluded", "--threads", "32 bytes", "20 bytes",
                             "little-endian", "t_near", "prim_id", "geom_id", "0xFFFFFFFF"};
    for (size_t i = 0; i < sizeof needles / sizeof needles[0]; i++)
        cr_expect(strstr(log, needles[i]), "trace --help lacks '%s':\n%s", needles[i], log);
}

Test(trace, closest_hits_match_accel_bit_for_bit)
{
    write_scene();
    ray *rays = make_rays();
    write_rays("rays.bin", rays, TRACE_RAYS);
    char log[8192];
    cr_assert_eq(run_trace(log, sizeof log, "--scene @/scene.json --rays @/rays.bin --hits @/hits.bin --threads 3"), 0,
                 "%s", log);
    cr_expect(strstr(log, "traced 70001 rays"), "no summary line: %s", log);
    size_t size;
    unsigned char *out = read_bytes("hits.bin", &size);
    cr_assert_eq(size, (size_t)TRACE_RAYS * 20u, "hits file has %zu bytes", size);
    scene *s;
    accel *a = load_here(&s);
    uint64_t hits = 0, wrong = 0, degenerate_hits = 0;
    uint64_t per_geom[3] = {0, 0, 0};
    for (uint32_t i = 0; i < TRACE_RAYS; i++) {
        const unsigned char *rec = out + (size_t)i * 20u;
        hit want;
        bool hit_here = accel_intersect(a, &rays[i], &want);
        hit got = {.t = get_f32(rec), .prim_id = get_u32(rec + 4), .geom_id = get_u32(rec + 8), .u = get_f32(rec + 12),
                   .v = get_f32(rec + 16)};
        bool same = same_float_bits(got.t, want.t) && got.prim_id == want.prim_id && got.geom_id == want.geom_id &&
                    same_float_bits(got.u, want.u) && same_float_bits(got.v, want.v);
        if (!same && wrong++ < 5)
            cr_log_error("ray %u: file t %a prim %u geom %u u %a v %a; accel_intersect t %a prim %u geom %u u %a v %a",
                         i, got.t, got.prim_id, got.geom_id, got.u, got.v, want.t, want.prim_id, want.geom_id, want.u,
                         want.v);
        hits += hit_here;
        if (hit_here && want.geom_id < 3)
            per_geom[want.geom_id]++;
        if (i % 97 == 96)
            degenerate_hits += !(isinf(got.t) && got.t > 0.f && got.prim_id == RAY_INVALID_ID &&
                                 got.geom_id == RAY_INVALID_ID && got.u == 0.f && got.v == 0.f);
    }
    cr_log_info("trace: %u rays, %llu hits (meshes %llu + %llu, spheres %llu); %llu records differ from "
                "accel_intersect",
                TRACE_RAYS, (unsigned long long)hits, (unsigned long long)per_geom[0], (unsigned long long)per_geom[1],
                (unsigned long long)per_geom[2], (unsigned long long)wrong);
    cr_expect_eq(wrong, 0u);
    cr_expect_eq(degenerate_hits, 0u, "degenerate rays must be written as misses");
    cr_expect(per_geom[0] > 1000 && per_geom[1] > 1000 && per_geom[2] > 1000, "every geometry should be hit");
    cr_expect(hits < TRACE_RAYS - 1000, "some rays should miss");
    /* the same output for any thread count */
    cr_assert_eq(run_trace(log, sizeof log, "--scene @/scene.json --rays @/rays.bin --hits @/hits1.bin --threads 1"), 0,
                 "%s", log);
    size_t size1;
    unsigned char *out1 = read_bytes("hits1.bin", &size1);
    cr_expect(size1 == size && memcmp(out, out1, size) == 0, "1 thread and 3 threads wrote different hits");
    free(out1);
    free(out);
    free(rays);
    accel_destroy(a);
    scene_destroy(s);
}

Test(trace, occluded_matches_accel_occluded)
{
    write_scene();
    ray *rays = make_rays();
    write_rays("rays.bin", rays, TRACE_RAYS);
    char log[8192];
    cr_assert_eq(run_trace(log, sizeof log, "--scene @/scene.json --rays @/rays.bin --hits @/occ.bin --occluded"), 0,
                 "%s", log);
    size_t size;
    unsigned char *out = read_bytes("occ.bin", &size);
    cr_assert_eq(size, (size_t)TRACE_RAYS, "occlusion file has %zu bytes", size);
    scene *s;
    accel *a = load_here(&s);
    uint64_t occluded = 0, wrong = 0;
    for (uint32_t i = 0; i < TRACE_RAYS; i++) {
        unsigned char want = accel_occluded(a, &rays[i]) ? 1 : 0;
        occluded += want;
        if (out[i] != want && wrong++ < 5)
            cr_log_error("ray %u: file says %u, accel_occluded %u", i, out[i], want);
    }
    cr_log_info("trace --occluded: %u rays, %llu occluded; %llu bytes differ from accel_occluded", TRACE_RAYS,
                (unsigned long long)occluded, (unsigned long long)wrong);
    cr_expect_eq(wrong, 0u);
    cr_expect(occluded > 1000 && occluded < TRACE_RAYS - 1000);
    free(out);
    free(rays);
    accel_destroy(a);
    scene_destroy(s);
}

Test(trace, empty_rays_file_gives_empty_hits)
{
    write_scene();
    write_bytes("empty.bin", "", 0);
    char log[8192];
    cr_assert_eq(run_trace(log, sizeof log, "--scene @/scene.json --rays @/empty.bin --hits @/hits.bin"), 0, "%s", log);
    size_t size;
    free(read_bytes("hits.bin", &size));
    cr_expect_eq(size, 0u);
    cr_assert_eq(run_trace(log, sizeof log, "--scene default --rays @/empty.bin --hits @/occ.bin --occluded"), 0, "%s",
                 log);
    free(read_bytes("occ.bin", &size));
    cr_expect_eq(size, 0u);
}

/* Expect a failure with exit code `code`, one error line, and every needle
 * (NULL-terminated) in the output. */
static void expect_failure(int code, const char *args, const char *const *needles)
{
    char log[8192];
    int got = run_trace(log, sizeof log, args);
    cr_expect_eq(got, code, "'trace %s': exit %d, expected %d: %s", args, got, code, log);
    cr_expect(strstr(log, "tessera: error: ") != NULL, "'trace %s': no error line: %s", args, log);
    const char *first_newline = strchr(log, '\n');
    cr_expect(first_newline && first_newline[1] == '\0', "'trace %s': expected exactly one line: %s", args, log);
    for (const char *const *n = needles; *n; n++)
        cr_expect(strstr(log, *n) != NULL, "'trace %s': message lacks '%s': %s", args, *n, log);
}

#define EXPECT_FAILURE(code, args, ...) expect_failure(code, args, (const char *const[]){__VA_ARGS__, NULL})

Test(trace, command_line_errors)
{
    write_scene();
    write_bytes("rays.bin", "", 0);
    EXPECT_FAILURE(2, "--rays @/rays.bin --hits @/hits.bin", "--scene");
    EXPECT_FAILURE(2, "--scene @/scene.json --hits @/hits.bin", "--rays");
    EXPECT_FAILURE(2, "--scene @/scene.json --rays @/rays.bin", "--hits");
    EXPECT_FAILURE(2, "--scene @/scene.json --rays @/rays.bin --hits", "--hits", "needs a value");
    EXPECT_FAILURE(2, "--scene @/scene.json --rays @/rays.bin --hits @/hits.bin --threads 0", "--threads", "'0'");
    EXPECT_FAILURE(2, "--scene @/scene.json --rays @/rays.bin --hits @/hits.bin --bogus", "unknown option", "--bogus");
    cr_expect(!exists_in_dir("hits.bin"), "a failed command left a hits file");
}

Test(trace, rays_file_errors)
{
    write_scene();
    EXPECT_FAILURE(1, "--scene @/scene.json --rays @/nope.bin --hits @/hits.bin", "nope.bin", "cannot read",
                   "No such file");
    unsigned char hundred[100] = {0};
    write_bytes("odd.bin", hundred, sizeof hundred);
    EXPECT_FAILURE(1, "--scene @/scene.json --rays @/odd.bin --hits @/hits.bin",
                   "odd.bin: 100 bytes is not a whole number of 32-byte ray records");
    char sub[512];
    path_in_dir(sub, sizeof sub, "subdir");
    cr_assert_eq(mkdir(sub, 0777), 0);
    EXPECT_FAILURE(1, "--scene @/scene.json --rays @/subdir --hits @/hits.bin", "subdir", "directory");
    unsigned char one_ray[32] = {0};
    write_bytes("one.bin", one_ray, sizeof one_ray);
    EXPECT_FAILURE(1, "--scene @/scene.json --rays @/one.bin --hits @/one.bin", "one.bin", "same file");
    size_t size;
    free(read_bytes("one.bin", &size));
    cr_expect_eq(size, 32u, "the rays file was overwritten");
    cr_expect(!exists_in_dir("hits.bin"), "a failed command left a hits file");
}

Test(trace, hits_path_errors)
{
    write_scene();
    unsigned char one_ray[32] = {0};
    write_bytes("rays.bin", one_ray, sizeof one_ray);
    EXPECT_FAILURE(1, "--scene @/scene.json --rays @/rays.bin --hits @/no/such/dir/hits.bin", "no/such/dir/hits.bin",
                   "does not exist");
    write_bytes("plain", "x", 1);
    EXPECT_FAILURE(1, "--scene @/scene.json --rays @/rays.bin --hits @/plain/hits.bin", "plain/hits.bin",
                   "not a directory");
    char sub[512];
    path_in_dir(sub, sizeof sub, "outdir");
    cr_assert_eq(mkdir(sub, 0777), 0);
    EXPECT_FAILURE(1, "--scene @/scene.json --rays @/rays.bin --hits @/outdir", "outdir", "directory");
}

Test(trace, scene_errors)
{
    unsigned char one_ray[32] = {0};
    write_bytes("rays.bin", one_ray, sizeof one_ray);
    EXPECT_FAILURE(1, "--scene @/nope.json --rays @/rays.bin --hits @/hits.bin", "nope.json");
    const char *broken = "{\n  \"spheres\": [ {\"center\": [0, 0, 0], \"radius\": -1} ]\n}\n";
    write_bytes("broken.json", broken, strlen(broken));
    EXPECT_FAILURE(1, "--scene @/broken.json --rays @/rays.bin --hits @/hits.bin", "broken.json", "radius");
    const char *range_ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    write_bytes("range.ply", range_ply, strlen(range_ply));
    EXPECT_FAILURE(1, "--scene @/range.ply --rays @/rays.bin --hits @/hits.bin", "range.ply", "out of range");
    cr_expect(!exists_in_dir("hits.bin"), "a failed command left a hits file");
}
