/* test_mesh_cache.c - a mesh file through the structure cache (mesh_cache.h):
 * the first load builds and writes, the second maps and gives the same hits
 * bit for bit; a changed model, a changed transform, a corrupt or truncated
 * cache is never used (rebuilt with a message); TESSERA_CACHE=off writes
 * nothing. Models are generated here; every test works in its own mkdtemp
 * directory (TESSERA_CACHE_DIR inside it), removed afterwards. */
#define _GNU_SOURCE /* mkdtemp, setenv */
#include <criterion/criterion.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/geometry/triangles/mesh_cache.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"

static char dir[64];
static char cache_dir_path[128];

static void setup(void)
{
    snprintf(dir, sizeof dir, "/tmp/tessera_test_mesh_cache_XXXXXX");
    cr_assert(mkdtemp(dir));
    snprintf(cache_dir_path, sizeof cache_dir_path, "%s/cache", dir);
    setenv("TESSERA_CACHE_DIR", cache_dir_path, 1);
    setenv("TESSERA_CACHE_MIN_BYTES", "0", 1); /* the test models are small */
    unsetenv("TESSERA_CACHE");
}

static void teardown(void)
{
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    cr_assert_eq(system(cmd), 0);
}

/* A bumpy sphere as an ASCII PLY of (n+1)^2 vertices, 2 n^2 triangles; `bump` shifts one vertex. */
static void write_sphere(const char *path, int n, float bump)
{
    FILE *f = fopen(path, "w");
    cr_assert(f);
    int nv = (n + 1) * (n + 1), nt = 2 * n * n;
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
               "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
            nv, nt);
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            float th = 3.14159265f * (float)j / (float)n, ph = 6.2831853f * (float)i / (float)n;
            float r = 1.f + 0.05f * sinf(7.f * ph) * sinf(5.f * th) + (i == n / 2 && j == n / 2 ? bump : 0.f);
            fprintf(f, "%.9g %.9g %.9g\n", (double)(r * sinf(th) * cosf(ph)), (double)(r * cosf(th)),
                    (double)(r * sinf(th) * sinf(ph)));
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            fprintf(f, "3 %d %d %d\n3 %d %d %d\n", a, c, b, b, c, d);
        }
    cr_assert_eq(fclose(f), 0);
}

/* Files in the cache directory ending in .tcache (temporaries do not). */
static int cache_files(char *first, size_t first_bytes)
{
    DIR *d = opendir(cache_dir_path);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t len = strlen(e->d_name);
        if (len > 7 && strcmp(e->d_name + len - 7, ".tcache") == 0) {
            if (n++ == 0 && first)
                snprintf(first, first_bytes, "%s/%s", cache_dir_path, e->d_name);
        }
    }
    closedir(d);
    return n;
}

#define RAYS 4000

/* Load `path` as a scene, build, trace RAYS fixed rays; the mesh's cache state. */
static int trace(const char *path, hit *hits, bool *hit_any)
{
    tess_error err = {{0}};
    scene *s = scene_load(path, &err);
    cr_assert(s, "%s", err.msg);
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    uint64_t seed = 77;
    for (int i = 0; i < RAYS; i++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        float u = (float)(seed >> 40) / 16777216.f, v = (float)((seed >> 16) & 0xFFFFFF) / 16777216.f;
        ray r = {v3(-3.f, (u - 0.5f) * 2.4f, (v - 0.5f) * 2.4f), v3(1.f, 0.01f, -0.02f), 0.f, INFINITY};
        hit_any[i] = accel_intersect(a, &r, &hits[i]);
    }
    int state = s->meshes[0]->cache_state;
    accel_destroy(a);
    scene_destroy(s);
    return state;
}

static bool same_hits(const hit *a, const bool *ha, const hit *b, const bool *hb)
{
    for (int i = 0; i < RAYS; i++)
        if (ha[i] != hb[i] || (ha[i] && memcmp(&a[i], &b[i], sizeof a[i]) != 0))
            return false;
    return true;
}

static hit hits_a[RAYS], hits_b[RAYS];
static bool any_a[RAYS], any_b[RAYS];

TestSuite(mesh_cache, .init = setup, .fini = teardown);

Test(mesh_cache, second_start_maps_the_cache_and_hits_the_same)
{
    char model[128];
    snprintf(model, sizeof model, "%s/sphere.ply", dir);
    write_sphere(model, 60, 0.f);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_WRITTEN);
    cr_assert_eq(cache_files(NULL, 0), 1);
    cr_assert_eq(trace(model, hits_b, any_b), MESH_CACHE_HIT);
    cr_assert(same_hits(hits_a, any_a, hits_b, any_b), "the mapped mesh and tree give other hits");
    int hit_count = 0;
    for (int i = 0; i < RAYS; i++)
        hit_count += any_a[i];
    cr_assert_gt(hit_count, RAYS / 4, "the sphere is in the rays' way (%d hits)", hit_count);
    cr_assert_eq(cache_files(NULL, 0), 1, "a hit writes nothing");
}

Test(mesh_cache, a_changed_model_is_not_served_from_the_old_cache)
{
    char model[128];
    snprintf(model, sizeof model, "%s/sphere.ply", dir);
    write_sphere(model, 60, 0.f);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_WRITTEN);
    write_sphere(model, 60, 0.5f); /* same path, one vertex moved */
    cr_assert_eq(trace(model, hits_b, any_b), MESH_CACHE_WRITTEN, "the changed file has another key");
    cr_assert(!same_hits(hits_a, any_a, hits_b, any_b), "the moved vertex shows in the hits");
    cr_assert_eq(cache_files(NULL, 0), 2);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_HIT);
    cr_assert(same_hits(hits_a, any_a, hits_b, any_b));
}

/* Damage the cache file, then load again: rebuilt (a message), the right
 * hits, and a good cache in its place. */
static void damaged_cache_is_rebuilt(void (*damage)(const char *path))
{
    char model[128], cache[256];
    snprintf(model, sizeof model, "%s/sphere.ply", dir);
    write_sphere(model, 50, 0.f);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_WRITTEN);
    cr_assert_eq(cache_files(cache, sizeof cache), 1);
    damage(cache);
    cr_assert_eq(trace(model, hits_b, any_b), MESH_CACHE_WRITTEN, "a damaged cache is rebuilt, never used");
    cr_assert(same_hits(hits_a, any_a, hits_b, any_b));
    cr_assert_eq(trace(model, hits_b, any_b), MESH_CACHE_HIT, "the rebuilt cache is whole");
    cr_assert(same_hits(hits_a, any_a, hits_b, any_b));
}

static void flip_a_byte_of_the_nodes(const char *path)
{
    FILE *f = fopen(path, "r+b");
    cr_assert(f);
    cr_assert_eq(fseek(f, -100, SEEK_END), 0); /* the last section: the nodes */
    int c = fgetc(f);
    cr_assert_eq(fseek(f, -100, SEEK_END), 0);
    fputc(c ^ 0x10, f);
    cr_assert_eq(fclose(f), 0);
}

static void truncate_to_half(const char *path)
{
    struct stat st;
    cr_assert_eq(stat(path, &st), 0);
    cr_assert_eq(truncate(path, st.st_size / 2), 0);
}

Test(mesh_cache, a_corrupt_cache_is_rebuilt) { damaged_cache_is_rebuilt(flip_a_byte_of_the_nodes); }
Test(mesh_cache, a_truncated_cache_is_rebuilt) { damaged_cache_is_rebuilt(truncate_to_half); }

Test(mesh_cache, off_writes_nothing)
{
    setenv("TESSERA_CACHE", "off", 1);
    char model[128];
    snprintf(model, sizeof model, "%s/sphere.ply", dir);
    write_sphere(model, 30, 0.f);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_UNUSED);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_UNUSED);
    cr_assert_eq(cache_files(NULL, 0), 0);
}

Test(mesh_cache, small_files_are_not_cached)
{
    setenv("TESSERA_CACHE_MIN_BYTES", "100000000", 1);
    char model[128];
    snprintf(model, sizeof model, "%s/sphere.ply", dir);
    write_sphere(model, 30, 0.f);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_UNUSED);
    cr_assert_eq(cache_files(NULL, 0), 0);
}

/* A scene file's transform is part of what was built: another transform,
 * another cache; each gives its own placement's hits. */
Test(mesh_cache, the_transform_is_in_the_key)
{
    char model[128], scene_a[128], scene_b[128];
    snprintf(model, sizeof model, "%s/sphere.ply", dir);
    write_sphere(model, 40, 0.f);
    const char *shift[2] = {"0, 0, 0", "0, 0.3, 0"};
    char *paths[2] = {scene_a, scene_b};
    for (int k = 0; k < 2; k++) {
        snprintf(paths[k], 128, "%s/scene_%d.json", dir, k);
        FILE *f = fopen(paths[k], "w");
        cr_assert(f);
        fprintf(f, "{\"meshes\": [{\"file\": \"sphere.ply\", \"transform\": {\"translate\": [%s]}}]}\n", shift[k]);
        cr_assert_eq(fclose(f), 0);
    }
    cr_assert_eq(trace(scene_a, hits_a, any_a), MESH_CACHE_WRITTEN);
    cr_assert_eq(trace(scene_b, hits_b, any_b), MESH_CACHE_WRITTEN);
    cr_assert_eq(cache_files(NULL, 0), 2);
    cr_assert(!same_hits(hits_a, any_a, hits_b, any_b));
    static hit again[RAYS];
    static bool any_again[RAYS];
    cr_assert_eq(trace(scene_b, again, any_again), MESH_CACHE_HIT);
    cr_assert(same_hits(hits_b, any_b, again, any_again));
    cr_assert_eq(trace(scene_a, again, any_again), MESH_CACHE_HIT);
    cr_assert(same_hits(hits_a, any_a, again, any_again));
}

/* A cache directory that cannot be made (a regular file in its path): the
 * write fails with a warning, the scene renders all the same. */
Test(mesh_cache, an_unwritable_cache_directory_is_a_warning_not_an_error)
{
    char blocker[160], under[200], model[128];
    snprintf(blocker, sizeof blocker, "%s/not_a_dir", dir);
    FILE *f = fopen(blocker, "w");
    cr_assert(f);
    cr_assert_eq(fclose(f), 0);
    snprintf(under, sizeof under, "%s/cache", blocker);
    setenv("TESSERA_CACHE_DIR", under, 1);
    snprintf(model, sizeof model, "%s/sphere.ply", dir);
    write_sphere(model, 30, 0.f);
    cr_assert_eq(trace(model, hits_a, any_a), MESH_CACHE_FAILED);
    cr_assert_eq(trace(model, hits_b, any_b), MESH_CACHE_FAILED, "nothing was written to be used");
    cr_assert(same_hits(hits_a, any_a, hits_b, any_b));
}
