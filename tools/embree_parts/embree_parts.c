/* embree_parts.c - Intel Embree 3 on an assembly, for `make bench`
 * (tools/bench_parts.sh): the peer harness's measurement (../shared/tools/peer:
 * T render threads pulling 16x16 tiles from an atomic counter, single rays
 * or 8/16-wide packets, one RESULT line) on a glTF assembly, loaded with
 * tessera's own assembly_load, in one of two representations:
 *
 *   parts    (default) one Embree scene per mesh, each placed by its parts as
 *            RTC_GEOMETRY_TYPE_INSTANCE geometries (row-major 3x4 transforms)
 *            in a top scene: Embree's two-level scene;
 *   flatten  every instance's triangles baked into one triangle geometry.
 *
 * The camera is tessera bench's for the same representation, computed by
 * tessera's functions: camera_frame_bounds over scene_bounds' box (parts:
 * the union of each instance's transformed mesh box, as scene_bounds does;
 * flatten: the baked vertices' box) and camera_pixel_direction for each
 * pixel, so the two programs trace the same rays. --camera takes one in
 * tessera's syntax instead. The hit count of the last frame is printed
 * (hits=) for comparison with tessera's BENCH line.
 *
 * Built only by `make bench` / `make bench-parts` (links libembree3 and
 * libtessera.a); not part of `make` or `make test`. */
#define _GNU_SOURCE
#include <embree3/rtcore.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <time.h>
#include <xmmintrin.h>
#include <pmmintrin.h>

#include "engine/base/aabb.h"
#include "engine/load/assembly_load.h"
#include "engine/base/camera.h"
#include "engine/accel/geometry.h"
#include "engine/geometry/triangles/mesh.h"

#define TILE_PX 16

/* ---- small helpers ---------------------------------------------------------- */

static void fail(const char *what, const char *detail)
{
    fprintf(stderr, "embree_parts: error: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    exit(1);
}

static void *checked_alloc(size_t bytes)
{
    void *p = malloc(bytes ? bytes : 1);
    if (!p)
        fail("out of memory", NULL);
    return p;
}

static double wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Busy CPU seconds of the whole machine (/proc/stat: user nice system irq
 * softirq steal), or -1. */
static double machine_busy_s(void)
{
    FILE *f = fopen("/proc/stat", "r");
    if (!f)
        return -1.0;
    unsigned long long v[8] = {0};
    int n = fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                   &v[6], &v[7]);
    fclose(f);
    if (n != 8)
        return -1.0;
    unsigned long long busy = v[0] + v[1] + v[2] + v[5] + v[6] + v[7];
    return (double)busy / 100.0;
}

static double own_cpu_s(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static int cmp_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* ---- the assembly, as assembly_load reports it ------------------------------ */

typedef struct placed {
    uint32_t mesh;
    float to_world[12];
} placed;

typedef struct assembly {
    mesh **meshes;
    uint32_t mesh_count, mesh_cap;
    placed *instances;
    uint32_t instance_count, instance_cap;
    int parts;
} assembly;

static int on_material(void *ctx, const char *name, const float rgb[3])
{
    (void)ctx, (void)name, (void)rgb;
    return 0; /* eyelight shading: materials are not used */
}

static int on_mesh(void *ctx, struct mesh *m, int material, const char *name)
{
    (void)material, (void)name;
    assembly *as = ctx;
    if (as->mesh_count == as->mesh_cap) {
        uint32_t cap = as->mesh_cap ? 2 * as->mesh_cap : 64;
        mesh **grown = realloc(as->meshes, cap * sizeof *grown);
        if (!grown) {
            mesh_destroy(m);
            return -1;
        }
        as->meshes = grown;
        as->mesh_cap = cap;
    }
    as->meshes[as->mesh_count] = m;
    return (int)as->mesh_count++;
}

static int on_part(void *ctx, int parent, const char *name)
{
    (void)parent, (void)name;
    assembly *as = ctx;
    return as->parts++;
}

static int on_instance(void *ctx, int part, int mesh_id, const float to_world[12])
{
    (void)part;
    assembly *as = ctx;
    if (mesh_id < 0 || (uint32_t)mesh_id >= as->mesh_count)
        return -1;
    if (as->instance_count == as->instance_cap) {
        uint32_t cap = as->instance_cap ? 2 * as->instance_cap : 1024;
        placed *grown = realloc(as->instances, cap * sizeof *grown);
        if (!grown)
            return -1;
        as->instances = grown;
        as->instance_cap = cap;
    }
    placed *p = &as->instances[as->instance_count++];
    p->mesh = (uint32_t)mesh_id;
    memcpy(p->to_world, to_world, sizeof p->to_world);
    return 0;
}

/* ---- options ---------------------------------------------------------------- */

typedef struct options {
    const char *path;
    int width, height, threads, frames, warmup, packet; /* packet: 1, 8 or 16 */
    enum RTCBuildQuality quality;
    bool flatten, have_camera;
    camera_desc camera;
} options;

static void usage(FILE *f)
{
    fputs("usage: embree_parts [options] ASSEMBLY.glb\n"
          "Embree 3 on a glTF assembly (loaded by tessera's assembly_load): primary rays, eyelight\n"
          "shading, one RESULT line in the peer harness's format (../shared/tools/peer).\n"
          "  -r, --res WxH      image size (default 1920x1080)\n"
          "  -t, --threads N    render and build threads (default 1)\n"
          "  -f, --frames N     timed frames (default 10); --warmup N untimed frames first (default 1)\n"
          "  -m, --mode M       single, p8 (4x2 packets) or p16 (4x4) (default single)\n"
          "  -q, --quality Q    build quality: low, medium, high (default high)\n"
          "  --flatten          one triangle geometry, every instance baked in (default: one scene\n"
          "                     per mesh, placed by instance geometries in a top scene)\n"
          "  --camera ex,ey,ez,lx,ly,lz,ux,uy,uz,fov   tessera's syntax (default: tessera bench's\n"
          "                     framing of the same representation)\n"
          "RESULT fields: mesh tris (placed) build_s quality threads mode res frames prim_mrays\n"
          "total_mrays fps median_ms cpu_other, then rep=parts|flat instances meshes tris_stored\n"
          "hits (last frame) mem_mib (Embree's memory monitor after the build).\n",
          f);
}

static int parse_int(const char *flag, const char *v, int lo, int hi)
{
    char *end;
    errno = 0;
    long x = v ? strtol(v, &end, 10) : 0;
    if (!v || errno || end == v || *end || x < lo || x > hi) {
        fprintf(stderr, "embree_parts: error: %s: expected a whole number from %d to %d\n", flag, lo, hi);
        exit(2);
    }
    return (int)x;
}

static void parse_options(int argc, char **argv, options *o)
{
    *o = (options){.width = 1920, .height = 1080, .threads = 1, .frames = 10, .warmup = 1, .packet = 1,
                   .quality = RTC_BUILD_QUALITY_HIGH};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        bool takes = true;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            exit(0);
        } else if (!strcmp(a, "-r") || !strcmp(a, "--res")) {
            if (!v || sscanf(v, "%dx%d", &o->width, &o->height) != 2 || o->width < 1 || o->height < 1 ||
                o->width > 16384 || o->height > 16384) {
                fprintf(stderr, "embree_parts: error: %s: expected WxH\n", a);
                exit(2);
            }
        } else if (!strcmp(a, "-t") || !strcmp(a, "--threads")) {
            o->threads = parse_int(a, v, 1, 256);
        } else if (!strcmp(a, "-f") || !strcmp(a, "--frames")) {
            o->frames = parse_int(a, v, 1, 100000);
        } else if (!strcmp(a, "--warmup")) {
            o->warmup = parse_int(a, v, 0, 100000);
        } else if (!strcmp(a, "-m") || !strcmp(a, "--mode")) {
            if (v && !strcmp(v, "single"))
                o->packet = 1;
            else if (v && !strcmp(v, "p8"))
                o->packet = 8;
            else if (v && !strcmp(v, "p16"))
                o->packet = 16;
            else {
                fprintf(stderr, "embree_parts: error: %s: expected single, p8 or p16\n", a);
                exit(2);
            }
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quality")) {
            if (v && !strcmp(v, "low"))
                o->quality = RTC_BUILD_QUALITY_LOW;
            else if (v && !strcmp(v, "medium"))
                o->quality = RTC_BUILD_QUALITY_MEDIUM;
            else if (v && !strcmp(v, "high"))
                o->quality = RTC_BUILD_QUALITY_HIGH;
            else {
                fprintf(stderr, "embree_parts: error: %s: expected low, medium or high\n", a);
                exit(2);
            }
        } else if (!strcmp(a, "--camera")) {
            float c[10];
            if (!v || sscanf(v, "%f,%f,%f,%f,%f,%f,%f,%f,%f,%f", &c[0], &c[1], &c[2], &c[3], &c[4], &c[5], &c[6],
                             &c[7], &c[8], &c[9]) != 10) {
                fprintf(stderr, "embree_parts: error: --camera: expected ten numbers ex,ey,ez,lx,ly,lz,ux,uy,uz,fov\n");
                exit(2);
            }
            o->camera = (camera_desc){v3(c[0], c[1], c[2]), v3(c[3], c[4], c[5]), v3(c[6], c[7], c[8]), c[9]};
            o->have_camera = true;
        } else if (!strcmp(a, "--flatten")) {
            o->flatten = true;
            takes = false;
        } else if (a[0] == '-' || o->path) {
            fprintf(stderr, "embree_parts: error: unexpected argument '%s' (see --help)\n", a);
            exit(2);
        } else {
            o->path = a;
            takes = false;
        }
        i += takes;
    }
    if (!o->path) {
        usage(stderr);
        exit(2);
    }
}

/* ---- the Embree scene ------------------------------------------------------- */

static atomic_llong g_mem_bytes;

static bool on_memory(void *user, ssize_t bytes, bool post)
{
    (void)user, (void)post;
    atomic_fetch_add(&g_mem_bytes, (long long)bytes);
    return true;
}

static void on_error(void *user, enum RTCError code, const char *msg)
{
    (void)user;
    fprintf(stderr, "embree_parts: embree error %d: %s\n", (int)code, msg ? msg : "");
}

/* A triangle geometry of n_vertices / n_triangles whose buffers the caller fills. */
static RTCGeometry new_triangles(RTCDevice dev, size_t n_vertices, size_t n_triangles, float **vb, uint32_t **ib)
{
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), n_vertices);
    *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), n_triangles);
    if (!*vb || !*ib)
        fail("rtcSetNewGeometryBuffer failed", NULL);
    return g;
}

static void point_xform(const float *m, const float *p, float *out)
{
    for (int r = 0; r < 3; r++)
        out[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
}

/* Per instance the world-from-object normal matrix (inverse transpose of the
 * linear part, row-major 3x3), to shade with a world-space Ng. */
static void normal_matrix(const float *m, float *n)
{
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], k = m[10];
    double co[9] = {e * k - f * h, f * g - d * k, d * h - e * g, c * h - b * k, a * k - c * g,
                    b * g - a * h, b * f - c * e, c * d - a * f, a * e - b * d};
    double det = a * co[0] + b * co[1] + c * co[2];
    for (int i = 0; i < 9; i++) /* inverse = cofactor^T / det; its transpose = cofactor / det */
        n[i] = (float)(det != 0.0 ? co[i] / det : 0.0);
}

/* Build the scene to trace; *bounds gets tessera's framing box for it. Times
 * every rtcCommitScene (all BVH builds) into *build_s. */
static RTCScene build_scene(RTCDevice dev, const options *o, const assembly *as, aabb *bounds, double *build_s,
                            float **normal_mats)
{
    RTCScene top = rtcNewScene(dev);
    rtcSetSceneBuildQuality(top, o->quality);
    *bounds = aabb_empty();
    *normal_mats = NULL;
    double built = 0.0;
    if (o->flatten) {
        size_t nv = 0, nt = 0;
        for (uint32_t i = 0; i < as->instance_count; i++) {
            nv += as->meshes[as->instances[i].mesh]->vertex_count;
            nt += as->meshes[as->instances[i].mesh]->triangle_count;
        }
        float *vb;
        uint32_t *ib;
        RTCGeometry g = new_triangles(dev, nv, nt, &vb, &ib);
        size_t v0 = 0, t0 = 0;
        for (uint32_t i = 0; i < as->instance_count; i++) {
            const mesh *m = as->meshes[as->instances[i].mesh];
            for (uint32_t v = 0; v < m->vertex_count; v++) {
                float *p = vb + 3 * (v0 + v);
                point_xform(as->instances[i].to_world, m->positions + 3 * (size_t)v, p);
                *bounds = aabb_grow_point(*bounds, v3(p[0], p[1], p[2]));
            }
            for (size_t k = 0; k < 3 * (size_t)m->triangle_count; k++)
                ib[3 * t0 + k] = (uint32_t)v0 + m->indices[k];
            v0 += m->vertex_count;
            t0 += m->triangle_count;
        }
        rtcSetGeometryBuildQuality(g, o->quality);
        rtcCommitGeometry(g);
        rtcAttachGeometry(top, g);
        rtcReleaseGeometry(g);
    } else {
        RTCScene *objects = checked_alloc(as->mesh_count * sizeof *objects);
        aabb *object_box = checked_alloc(as->mesh_count * sizeof *object_box);
        for (uint32_t i = 0; i < as->mesh_count; i++) {
            const mesh *m = as->meshes[i];
            float *vb;
            uint32_t *ib;
            RTCGeometry g = new_triangles(dev, m->vertex_count, m->triangle_count, &vb, &ib);
            memcpy(vb, m->positions, 3 * sizeof(float) * m->vertex_count);
            memcpy(ib, m->indices, 3 * sizeof(uint32_t) * m->triangle_count);
            rtcSetGeometryBuildQuality(g, o->quality);
            rtcCommitGeometry(g);
            objects[i] = rtcNewScene(dev);
            rtcSetSceneBuildQuality(objects[i], o->quality);
            rtcAttachGeometry(objects[i], g);
            rtcReleaseGeometry(g);
            double t0 = wall_s();
            rtcCommitScene(objects[i]);
            built += wall_s() - t0;
            float lo[3], hi[3];
            object_box[i] = mesh_bounds(m, lo, hi) ? (aabb){v3(lo[0], lo[1], lo[2]), v3(hi[0], hi[1], hi[2])}
                                                   : aabb_empty();
        }
        float *nm = checked_alloc(9 * sizeof(float) * (as->instance_count ? as->instance_count : 1));
        for (uint32_t i = 0; i < as->instance_count; i++) {
            const placed *p = &as->instances[i];
            RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(g, objects[p->mesh]);
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, p->to_world);
            rtcCommitGeometry(g);
            if (rtcAttachGeometry(top, g) != i)
                fail("instance ids are not attachment order", NULL);
            rtcReleaseGeometry(g);
            normal_matrix(p->to_world, nm + 9 * (size_t)i);
            /* tessera's scene_bounds: each instance's mesh box, transformed (8 corners) */
            if (!aabb_is_empty(object_box[p->mesh])) {
                affine3 a;
                memcpy(a.m, p->to_world, sizeof a.m);
                aabb b = affine3_box(&a, object_box[p->mesh]);
                *bounds = (aabb){v3_min(bounds->lo, b.lo), v3_max(bounds->hi, b.hi)};
            }
        }
        for (uint32_t i = 0; i < as->mesh_count; i++)
            rtcReleaseScene(objects[i]); /* the instances hold them */
        free(object_box);
        free(objects);
        *normal_mats = nm;
    }
    double t0 = wall_s();
    rtcCommitScene(top);
    built += wall_s() - t0;
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE)
        fail("the Embree build failed", o->path);
    *build_s = built;
    return top;
}

/* ---- rendering -------------------------------------------------------------- */

typedef struct renderer renderer;

typedef struct worker {
    alignas(64) renderer *r;
    uint64_t rays, hits;
    pthread_t thread;
} worker;

struct renderer {
    const options *o;
    RTCScene scene;
    camera_basis cam;
    const float *normal_mats; /* parts: per instance; flatten: NULL */
    float *shade;             /* W x H */
    int tiles_x, tiles;
    bool quit;
    cpu_set_t start_mask;
    bool have_start_mask;
    pthread_barrier_t go, done;
    alignas(64) atomic_int next_tile;
};

static float shade_of(const renderer *r, vec3 dir, float ngx, float ngy, float ngz, unsigned inst)
{
    vec3 n = v3(ngx, ngy, ngz);
    if (r->normal_mats && inst != RTC_INVALID_GEOMETRY_ID) {
        const float *m = r->normal_mats + 9 * (size_t)inst;
        n = v3(m[0] * ngx + m[1] * ngy + m[2] * ngz, m[3] * ngx + m[4] * ngy + m[5] * ngz,
               m[6] * ngx + m[7] * ngy + m[8] * ngz);
    }
    float nl = sqrtf(n.x * n.x + n.y * n.y + n.z * n.z), dl = sqrtf(dir.x * dir.x + dir.y * dir.y + dir.z * dir.z);
    if (!(nl > 0.f) || !(dl > 0.f))
        return 0.f;
    return fabsf(n.x * dir.x + n.y * dir.y + n.z * dir.z) / (nl * dl);
}

static void tile_single(renderer *r, worker *w, int x0, int y0, int x1, int y1)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            vec3 d = camera_pixel_direction(&r->cam, x, y);
            struct RTCRayHit rh;
            memset(&rh, 0, sizeof rh);
            rh.ray.org_x = r->cam.eye.x, rh.ray.org_y = r->cam.eye.y, rh.ray.org_z = r->cam.eye.z;
            rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
            rh.ray.tnear = 0.f;
            rh.ray.tfar = INFINITY;
            rh.ray.mask = 0xFFFFFFFFu;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(r->scene, &ctx, &rh);
            w->rays++;
            float s = 0.f;
            if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
                w->hits++;
                s = shade_of(r, d, rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z, rh.hit.instID[0]);
            }
            r->shade[(size_t)y * (size_t)r->o->width + (size_t)x] = s;
        }
}

/* One packet of width N (8: 4x2 pixels, 16: 4x4), structure of arrays. */
#define PACKET_BODY(N, TYPE, CALL)                                                                               \
    do {                                                                                                       \
        const int pw = 4, ph = (N) / 4;                                                                        \
        for (int by = y0; by < y1; by += ph)                                                                   \
            for (int bx = x0; bx < x1; bx += pw) {                                                             \
                alignas(64) TYPE p;                                                                            \
                alignas(64) int valid[N];                                                                      \
                vec3 dirs[N];                                                                                  \
                int n = 0;                                                                                     \
                for (int i = 0; i < (N); i++) {                                                                \
                    int x = bx + i % pw, y = by + i / pw;                                                      \
                    valid[i] = x < x1 && y < y1 ? -1 : 0;                                                      \
                    dirs[i] = valid[i] ? camera_pixel_direction(&r->cam, x, y) : v3(0.f, 0.f, 1.f);            \
                    n += valid[i] != 0;                                                                        \
                    p.ray.org_x[i] = r->cam.eye.x, p.ray.org_y[i] = r->cam.eye.y, p.ray.org_z[i] = r->cam.eye.z; \
                    p.ray.dir_x[i] = dirs[i].x, p.ray.dir_y[i] = dirs[i].y, p.ray.dir_z[i] = dirs[i].z;        \
                    p.ray.tnear[i] = 0.f, p.ray.tfar[i] = INFINITY, p.ray.time[i] = 0.f;                       \
                    p.ray.mask[i] = 0xFFFFFFFFu, p.ray.id[i] = (unsigned)i, p.ray.flags[i] = 0;                \
                    p.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID, p.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;   \
                }                                                                                              \
                CALL(valid, r->scene, &ctx, &p);                                                               \
                w->rays += (uint64_t)n;                                                                        \
                for (int i = 0; i < (N); i++) {                                                                \
                    if (!valid[i])                                                                             \
                        continue;                                                                              \
                    int x = bx + i % pw, y = by + i / pw;                                                      \
                    float s = 0.f;                                                                             \
                    if (p.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID) {                                          \
                        w->hits++;                                                                             \
                        s = shade_of(r, dirs[i], p.hit.Ng_x[i], p.hit.Ng_y[i], p.hit.Ng_z[i], p.hit.instID[0][i]); \
                    }                                                                                          \
                    r->shade[(size_t)y * (size_t)r->o->width + (size_t)x] = s;                                 \
                }                                                                                              \
            }                                                                                                  \
    } while (0)

static void tile_p8(renderer *r, worker *w, int x0, int y0, int x1, int y1)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    PACKET_BODY(8, struct RTCRayHit8, rtcIntersect8);
}

static void tile_p16(renderer *r, worker *w, int x0, int y0, int x1, int y1)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    PACKET_BODY(16, struct RTCRayHit16, rtcIntersect16);
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    renderer *r = w->r;
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    /* Embree's task system may have narrowed the main thread's CPU mask,
     * which new threads inherit: give the render threads the starting one. */
    if (r->have_start_mask)
        pthread_setaffinity_np(pthread_self(), sizeof r->start_mask, &r->start_mask);
    for (;;) {
        pthread_barrier_wait(&r->go);
        if (r->quit)
            return NULL;
        for (;;) {
            int t = atomic_fetch_add_explicit(&r->next_tile, 1, memory_order_relaxed);
            if (t >= r->tiles)
                break;
            int x0 = (t % r->tiles_x) * TILE_PX, y0 = (t / r->tiles_x) * TILE_PX;
            int x1 = x0 + TILE_PX < r->o->width ? x0 + TILE_PX : r->o->width;
            int y1 = y0 + TILE_PX < r->o->height ? y0 + TILE_PX : r->o->height;
            if (r->o->packet == 8)
                tile_p8(r, w, x0, y0, x1, y1);
            else if (r->o->packet == 16)
                tile_p16(r, w, x0, y0, x1, y1);
            else
                tile_single(r, w, x0, y0, x1, y1);
        }
        pthread_barrier_wait(&r->done);
    }
}

int main(int argc, char **argv)
{
    options o;
    parse_options(argc, argv, &o);
    renderer r = {.o = &o};
    r.have_start_mask = sched_getaffinity(0, sizeof r.start_mask, &r.start_mask) == 0;
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);

    assembly as = {0};
    assembly_sink sink = {&as, on_material, on_mesh, on_part, on_instance};
    tess_error err = {{0}};
    double t0 = wall_s();
    if (!assembly_load(o.path, &sink, &err))
        fail(err.msg, NULL);
    double load_s = wall_s() - t0;
    if (as.instance_count == 0)
        fail("no instances in", o.path);

    char cfg[64];
    snprintf(cfg, sizeof cfg, "threads=%d,set_affinity=0", o.threads);
    RTCDevice dev = rtcNewDevice(cfg);
    if (!dev)
        fail("rtcNewDevice failed", cfg);
    rtcSetDeviceErrorFunction(dev, on_error, NULL);
    rtcSetDeviceMemoryMonitorFunction(dev, on_memory, NULL);
    aabb box;
    double build_s;
    float *normal_mats;
    r.scene = build_scene(dev, &o, &as, &box, &build_s, &normal_mats);
    r.normal_mats = normal_mats;
    size_t tris = 0, tris_stored = 0;
    for (uint32_t i = 0; i < as.instance_count; i++)
        tris += as.meshes[as.instances[i].mesh]->triangle_count;
    for (uint32_t i = 0; i < as.mesh_count; i++)
        tris_stored += as.meshes[i]->triangle_count;
    double mem_mib = (double)atomic_load(&g_mem_bytes) / 1048576.0;

    if (!o.have_camera)
        o.camera = camera_frame_bounds(box.lo, box.hi, CAMERA_DEFAULT_VIEW_DIR, CAMERA_DEFAULT_FOV_DEG, o.width,
                                       o.height);
    if (!camera_validate(&o.camera, &err))
        fail("camera", err.msg);
    const camera_desc *c = &o.camera;
    printf("camera --eye %g,%g,%g --lookat %g,%g,%g --up %g,%g,%g --fov %g\n", c->eye.x, c->eye.y, c->eye.z,
           c->look_at.x, c->look_at.y, c->look_at.z, c->up.x, c->up.y, c->up.z, c->fov_deg);
    r.cam = camera_basis_make(&o.camera, o.width, o.height);
    r.tiles_x = (o.width + TILE_PX - 1) / TILE_PX;
    r.tiles = r.tiles_x * ((o.height + TILE_PX - 1) / TILE_PX);
    r.shade = checked_alloc((size_t)o.width * (size_t)o.height * sizeof *r.shade);

    worker *workers = aligned_alloc(64, ((size_t)o.threads * sizeof(worker) + 63) & ~(size_t)63);
    if (!workers)
        fail("out of memory", NULL);
    memset(workers, 0, (size_t)o.threads * sizeof *workers);
    pthread_barrier_init(&r.go, NULL, (unsigned)o.threads + 1);
    pthread_barrier_init(&r.done, NULL, (unsigned)o.threads + 1);
    for (int i = 0; i < o.threads; i++) {
        workers[i].r = &r;
        if (pthread_create(&workers[i].thread, NULL, worker_main, &workers[i]) != 0)
            fail("pthread_create failed", strerror(errno));
    }
    double *frame_s = checked_alloc((size_t)o.frames * sizeof *frame_s);
    double busy0 = 0.0, own0 = 0.0, wall0 = 0.0, total_s = 0.0;
    uint64_t rays = 0, hits = 0;
    for (int f = -o.warmup; f < o.frames; f++) {
        if (f == 0) {
            busy0 = machine_busy_s();
            own0 = own_cpu_s();
            wall0 = wall_s();
        }
        for (int i = 0; i < o.threads; i++)
            workers[i].rays = workers[i].hits = 0;
        atomic_store(&r.next_tile, 0);
        double fs = wall_s();
        pthread_barrier_wait(&r.go);
        pthread_barrier_wait(&r.done);
        double fe = wall_s() - fs;
        if (f < 0)
            continue;
        frame_s[f] = fe;
        total_s += fe;
        hits = 0;
        for (int i = 0; i < o.threads; i++) {
            rays += workers[i].rays;
            hits += workers[i].hits;
        }
    }
    double busy1 = machine_busy_s(), own1 = own_cpu_s(), wall1 = wall_s();
    double cpu_other = -1.0;
    if (busy0 >= 0.0 && busy1 >= 0.0 && wall1 > wall0) {
        cpu_other = ((busy1 - busy0) - (own1 - own0)) / (wall1 - wall0);
        cpu_other = cpu_other > 0.0 ? cpu_other : 0.0;
    }
    r.quit = true;
    pthread_barrier_wait(&r.go);
    for (int i = 0; i < o.threads; i++)
        pthread_join(workers[i].thread, NULL);

    qsort(frame_s, (size_t)o.frames, sizeof *frame_s, cmp_doubles);
    int n = o.frames;
    double median = n % 2 ? frame_s[n / 2] : 0.5 * (frame_s[n / 2 - 1] + frame_s[n / 2]);
    const char *quality = o.quality == RTC_BUILD_QUALITY_HIGH ? "high" : o.quality == RTC_BUILD_QUALITY_MEDIUM ? "medium"
                                                                                                           : "low";
    const char *mode = o.packet == 1 ? "single" : o.packet == 8 ? "p8" : "p16";
    printf("load %.3f s (assembly_load)  build %.3f s  embree mem %.1f MiB\n", load_s, build_s, mem_mib);
    printf("RESULT mesh=%s tris=%zu build_s=%.4f quality=%s threads=%d mode=%s res=%dx%d frames=%d "
           "prim_mrays=%.3f total_mrays=%.3f fps=%.3f median_ms=%.3f cpu_other=%.2f rep=%s instances=%u "
           "meshes=%u tris_stored=%zu hits=%llu mem_mib=%.1f load_s=%.3f\n",
           o.path, tris, build_s, quality, o.threads, mode, o.width, o.height, o.frames,
           1e-6 * (double)rays / total_s, 1e-6 * (double)rays / total_s, (double)o.frames / total_s, 1e3 * median,
           cpu_other, o.flatten ? "flat" : "parts", o.flatten ? 1u : as.instance_count, as.mesh_count, tris_stored,
           (unsigned long long)hits, mem_mib, load_s);
    fflush(stdout);

    free(frame_s);
    free(workers);
    free(r.shade);
    free(normal_mats);
    pthread_barrier_destroy(&r.go);
    pthread_barrier_destroy(&r.done);
    rtcReleaseScene(r.scene);
    rtcReleaseDevice(dev);
    for (uint32_t i = 0; i < as.mesh_count; i++)
        mesh_destroy(as.meshes[i]);
    free(as.meshes);
    free(as.instances);
    return 0;
}
