/* test_alloc_sweep.c - every allocation of loading each file format and of
 * building the acceleration structure fails in turn (fault.h): each must fail
 * with one line naming the file and "out of memory" and leak nothing (LSan in
 * make test-asan), or, where the allocation has a fallback, give the same
 * result as without the failure. Never a crash.
 *
 * Inputs: the example files in configs/ (the tests run in tests/) and small
 * files written here that use every optional part of their format (PLY
 * normals, colours, polygons, skipped elements; OBJ with MTL materials; a
 * record with every transaction kind). */
#define _GNU_SOURCE /* open_memstream in tests' helpers, mkdtemp */
#include <criterion/criterion.h>
#include <criterion/logging.h>

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/accel/bvh.h"
#include "engine/frame/camera_path.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/geometry/particles/particles.h"
#include "engine/frame/pipeline.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "input/bindings.h"
#include "input/record.h"
#include "fault.h"
#include "tests/support.h"
#include "app/pipeline_cli.h"
#include "wall/display.h"
#include "wall/edid.h"
#include "wall/wall_config.h"
#include "engine/load/mesh_load.h"
#include "engine/load/particle_load.h"

#define PATH_BYTES 512

/* ---- scratch files -------------------------------------------------------- */

static char scratch_dir[128];

static void scratch_create(void) { support_make_tmp_dir(scratch_dir, sizeof scratch_dir, "fault"); }

static void scratch_remove(void) { support_remove_tmp_dir(scratch_dir); }

TestSuite(alloc_sweep, .init = scratch_create, .fini = scratch_remove);

static const char *write_file(char path[PATH_BYTES], const char *name, const void *data, size_t len)
{
    snprintf(path, PATH_BYTES, "%s/%s", scratch_dir, name);
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f, "cannot create %s", path);
    cr_assert_eq(fwrite(data, 1, len, f), len);
    cr_assert_eq(fclose(f), 0);
    return path;
}

static const char *write_text(char path[PATH_BYTES], const char *name, const char *text)
{
    return write_file(path, name, text, strlen(text));
}

/* An ascii PLY with normals, uchar colours, a polygon (fan-split), an extra
 * vertex property and an element the reader skips. */
static const char ply_ascii[] =
    "ply\nformat ascii 1.0\ncomment fault sweep\n"
    "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float confidence\n"
    "element face 2\nproperty list uchar int vertex_indices\n"
    "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
    "end_header\n"
    "0 0 0 0 0 1 255 0 0 1\n1 0 0 0 0 1 0 255 0 1\n1 1 0 0 0 1 0 0 255 1\n0 1 0 0 0 1 10 20 30 1\n"
    "0.5 2 0 0 0 1 1 2 3 1\n"
    "4 0 1 2 3\n3 3 2 4\n"
    "0 1\n";

/* A binary little-endian PLY of 300 triangles (int indices, ushort colours). */
static size_t ply_binary(unsigned char *buf, size_t cap)
{
    const uint32_t tris = 300, verts = 3 * tris;
    int n = snprintf((char *)buf, cap,
                     "ply\nformat binary_little_endian 1.0\nelement vertex %u\nproperty float x\nproperty float y\n"
                     "property float z\nproperty ushort red\nproperty ushort green\nproperty ushort blue\n"
                     "element face %u\nproperty list uchar uint vertex_indices\nend_header\n",
                     verts, tris);
    size_t len = (size_t)n;
    for (uint32_t v = 0; v < verts; v++) {
        float xyz[3] = {(float)(v % 17), (float)(v / 17 % 13) * 0.5f, (float)(v % 3) + (float)v * 1e-3f};
        uint16_t rgb[3] = {(uint16_t)v, (uint16_t)(2 * v), 65535};
        cr_assert(len + sizeof xyz + sizeof rgb <= cap);
        memcpy(buf + len, xyz, sizeof xyz); /* x86-64: little-endian */
        len += sizeof xyz;
        memcpy(buf + len, rgb, sizeof rgb);
        len += sizeof rgb;
    }
    for (uint32_t t = 0; t < tris; t++) {
        uint32_t idx[3] = {3 * t, 3 * t + 1, 3 * t + 2};
        cr_assert(len + 1 + sizeof idx <= cap);
        buf[len++] = 3;
        memcpy(buf + len, idx, sizeof idx);
        len += sizeof idx;
    }
    return len;
}

static const char obj_text[] = "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nvn 0 0 1\n"
                               "usemtl red\nf 1//1 2//1 3//1\nusemtl blue\nf 2//1 4//1 3//1\nf 2//1 5//1 4//1\n";
static const char mtl_text[] = "newmtl red\nKd 1 0 0\n\nnewmtl unused\nKd 0 1 0\n\nnewmtl blue\nKd 0 0 0.5\n";

/* ---- comparing results ---------------------------------------------------- */

static bool same_array(const void *a, const void *b, size_t bytes)
{
    if (!a || !b)
        return a == b;
    return memcmp(a, b, bytes) == 0;
}

static bool mesh_materials_same(const mesh *a, const mesh *b)
{
    for (uint32_t i = 0; i < a->material_count; i++)
        if (strcmp(a->materials[i].name, b->materials[i].name) != 0 ||
            memcmp(a->materials[i].diffuse_rgb, b->materials[i].diffuse_rgb, sizeof a->materials[i].diffuse_rgb) != 0)
            return false;
    return true;
}

static bool mesh_same(const mesh *a, const mesh *b)
{
    size_t v = 3 * (size_t)a->vertex_count * sizeof(float);
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           a->material_count == b->material_count && same_array(a->positions, b->positions, v) &&
           same_array(a->normals, b->normals, v) && same_array(a->colors, b->colors, v) &&
           same_array(a->indices, b->indices, 3 * (size_t)a->triangle_count * sizeof(uint32_t)) &&
           same_array(a->triangle_material, b->triangle_material, (size_t)a->triangle_count * sizeof(uint32_t)) &&
           mesh_materials_same(a, b);
}

static bool vec3_same(vec3 a, vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* Field by field: names end at their NUL, structs have padding. */
static bool material_same(const material *a, const material *b)
{
    return strcmp(a->name, b->name) == 0 && a->model == b->model && vec3_same(a->diffuse, b->diffuse) &&
           vec3_same(a->specular, b->specular) && a->shininess == b->shininess && a->ambient == b->ambient;
}

static bool light_same(const light *a, const light *b)
{
    return a->kind == b->kind && vec3_same(a->direction, b->direction) && vec3_same(a->position, b->position) &&
           vec3_same(a->color, b->color) && a->intensity == b->intensity && a->casts_shadows == b->casts_shadows;
}

static bool camera_same(const camera_desc *a, const camera_desc *b)
{
    return vec3_same(a->eye, b->eye) && vec3_same(a->look_at, b->look_at) && vec3_same(a->up, b->up) &&
           a->fov_deg == b->fov_deg;
}

static bool scene_same(const scene *a, const scene *b)
{
    if (a->mesh_count != b->mesh_count || a->material_count != b->material_count ||
        a->light_count != b->light_count || a->spheres.count != b->spheres.count || a->has_camera != b->has_camera)
        return false;
    for (uint32_t i = 0; i < a->mesh_count; i++)
        if (!mesh_same(a->meshes[i]->mesh, b->meshes[i]->mesh) ||
            a->meshes[i]->material_id != b->meshes[i]->material_id ||
            !same_array(a->meshes[i]->mesh_material_ids, b->meshes[i]->mesh_material_ids,
                        a->meshes[i]->mesh->material_count * sizeof(uint32_t)) ||
            strcmp(a->meshes[i]->name, b->meshes[i]->name) != 0)
            return false;
    for (uint32_t i = 0; i < a->material_count; i++)
        if (!material_same(&a->materials[i], &b->materials[i]))
            return false;
    for (uint32_t i = 0; i < a->light_count; i++)
        if (!light_same(&a->lights[i], &b->lights[i]))
            return false;
    size_t n = a->spheres.count * sizeof(float);
    return same_array(a->spheres.center_x, b->spheres.center_x, n) &&
           same_array(a->spheres.center_y, b->spheres.center_y, n) &&
           same_array(a->spheres.center_z, b->spheres.center_z, n) &&
           same_array(a->spheres.radius, b->spheres.radius, n) &&
           same_array(a->spheres.material_id, b->spheres.material_id, a->spheres.count * sizeof(uint32_t)) &&
           (!a->has_camera || camera_same(&a->camera, &b->camera)) && vec3_same(a->background, b->background) &&
           vec3_same(a->ambient, b->ambient);
}

/* Loading has no fallbacks: an allocation that fails and the load still
 * succeeds means something was skipped silently (a check of the file left
 * out, so assimp reads what it crashes on; an optional part dropped). */
static void expect_no_fallback(const char *name, fault_sweep_stats st)
{
    cr_assert_eq(st.recovered, 0, "%s: %ld failed allocations were survived: something was skipped silently", name,
                 st.recovered);
    cr_assert_gt(st.failed, 0, "%s: nothing allocated: the sweep tests nothing", name);
}

/* ---- operations ------------------------------------------------------------- */

static void copy_msg(char *msg, size_t msg_bytes, const tess_error *err) { snprintf(msg, msg_bytes, "%s", err->msg); }

typedef struct mesh_op {
    const char *path;
    mesh *(*load)(const char *path, tess_error *err);
    mesh *ref;
} mesh_op;

static bool op_mesh(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    mesh_op *o = ctx;
    tess_error err = {{0}};
    mesh *m = o->load(o->path, &err);
    fault_disarm();
    if (!m) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = mesh_same(m, o->ref);
    mesh_destroy(m);
    return true;
}

static fault_sweep_stats sweep_mesh(const char *name, const char *path, mesh *(*load)(const char *, tess_error *))
{
    tess_error err = {{0}};
    mesh_op o = {path, load, load(path, &err)};
    cr_assert_not_null(o.ref, "%s", err.msg);
    const char *needles[] = {path, NULL};
    fault_sweep_stats st = fault_sweep(name, op_mesh, &o, needles);
    mesh_destroy(o.ref);
    return st;
}

Test(alloc_sweep, ply_ascii)
{
    char path[PATH_BYTES];
    write_text(path, "attrs.ply", ply_ascii);
    fault_sweep_stats st = sweep_mesh("ply ascii", path, mesh_load);
    expect_no_fallback("ply_ascii", st);
}

Test(alloc_sweep, ply_binary)
{
    static unsigned char buf[64 << 10];
    char path[PATH_BYTES];
    write_file(path, "many.ply", buf, ply_binary(buf, sizeof buf));
    fault_sweep_stats st = sweep_mesh("ply binary", path, mesh_load_ply);
    expect_no_fallback("ply_binary", st);
}

/* ---- particle files ------------------------------------------------------ */

static bool particles_same(const particle_set *a, const particle_set *b)
{
    if (a->count != b->count || a->attribute_count != b->attribute_count || a->timestep != b->timestep)
        return false;
    size_t n = (size_t)a->count * sizeof(float);
    if (!same_array(a->x, b->x, n) || !same_array(a->y, b->y, n) || !same_array(a->z, b->z, n))
        return false;
    for (uint32_t i = 0; i < a->attribute_count; i++)
        if (strcmp(a->attributes[i].name, b->attributes[i].name) != 0 ||
            !same_array(a->attributes[i].values, b->attributes[i].values, n))
            return false;
    return true;
}

typedef struct particles_op {
    const char *path;
    particle_set *ref;
} particles_op;

static bool op_particles(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    particles_op *o = ctx;
    tess_error err = {{0}};
    particle_set *p = particles_load(o->path, &err);
    fault_disarm();
    if (!p) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = particles_same(p, o->ref);
    particle_set_destroy(p);
    return true;
}

static void sweep_particles(const char *name, const char *path)
{
    tess_error err = {{0}};
    particles_op o = {path, particles_load(path, &err)};
    cr_assert_not_null(o.ref, "%s", err.msg);
    const char *needles[] = {path, NULL};
    fault_sweep_stats st = fault_sweep(name, op_particles, &o, needles);
    particle_set_destroy(o.ref);
    expect_no_fallback(name, st);
}

Test(alloc_sweep, particles_ply)
{
    static unsigned char buf[64 << 10];
    char path[PATH_BYTES];
    sweep_particles("particles ply ascii", write_text(path, "points.ply", ply_ascii));
    sweep_particles("particles ply binary", write_file(path, "cloud.ply", buf, ply_binary(buf, sizeof buf)));
}

Test(alloc_sweep, particles_lammps)
{
    char path[PATH_BYTES];
    write_text(path, "melt.dump",
               "ITEM: TIMESTEP\n250\nITEM: NUMBER OF ATOMS\n3\nITEM: BOX BOUNDS pp pp pp\n0 2\n0 2\n0 2\n"
               "ITEM: ATOMS id type xs ys zs vx c_ke\n1 1 0 0 0 0.5 1\n2 1 0.5 0.5 0 -0.5 2\n3 1 0.5 0 0.5 0 3\n");
    sweep_particles("particles lammps", path);
}

Test(alloc_sweep, obj_through_assimp)
{
    char path[PATH_BYTES];
    write_text(path, "two.mtl", mtl_text);
    write_text(path, "two.obj", obj_text);
    fault_sweep_stats st = sweep_mesh("obj (assimp)", path, mesh_load);
    expect_no_fallback("obj_through_assimp", st);
}

typedef struct scene_op {
    const char *path; /* NULL: the built-in scene */
    scene *ref;
} scene_op;

static scene *scene_op_load(const scene_op *o, tess_error *err)
{
    return o->path ? scene_load(o->path, err) : scene_create_default(err);
}

static bool op_scene(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    scene_op *o = ctx;
    tess_error err = {{0}};
    scene *s = scene_op_load(o, &err);
    fault_disarm();
    if (!s) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = scene_same(s, o->ref);
    scene_destroy(s);
    return true;
}

static fault_sweep_stats sweep_scene(const char *name, const char *path, const char *const *needles)
{
    tess_error err = {{0}};
    scene_op o = {path, NULL};
    o.ref = scene_op_load(&o, &err);
    cr_assert_not_null(o.ref, "%s", err.msg);
    fault_sweep_stats st = fault_sweep(name, op_scene, &o, needles);
    scene_destroy(o.ref);
    return st;
}

/* Every part of the format: camera, materials (Lambert and Phong), both kinds
 * of light, an OBJ with its own MTL materials (assimp), a transformed PLY with
 * normals and colours, spheres. A mesh's failure names the scene file too. */
Test(alloc_sweep, scene_json)
{
    char path[PATH_BYTES];
    write_text(path, "two.mtl", mtl_text);
    write_text(path, "two.obj", obj_text);
    write_text(path, "attrs.ply", ply_ascii);
    write_text(path, "scene.json",
               "// the fault sweep's scene\n"
               "{\"camera\": {\"eye\": [0, 1, 5], \"look_at\": [0, 0.5, 0], \"fov_deg\": 40},\n"
               " \"background\": [0.1, 0.1, 0.1], \"ambient\": [0.05, 0.05, 0.05],\n"
               " \"materials\": {\"m\": {\"diffuse\": [0.5, 0.5, 0.5]},\n"
               "               \"shiny\": {\"model\": \"phong\", \"diffuse\": [0.7, 0.1, 0.1],\n"
               "                         \"specular\": [0.5, 0.5, 0.5], \"shininess\": 32}},\n"
               " \"lights\": [{\"type\": \"directional\", \"direction\": [0.4, 1, 0.3], \"intensity\": 1},\n"
               "            {\"type\": \"point\", \"position\": [2, 4, 2], \"intensity\": 10}],\n"
               " \"meshes\": [{\"file\": \"two.obj\"},\n"
               "            {\"file\": \"attrs.ply\", \"material\": \"shiny\",\n"
               "             \"transform\": {\"scale\": 0.5, \"rotate_deg\": [0, 30, 0], \"translate\": [1, 0, 0]}}],\n"
               " \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1, \"material\": \"m\"},\n"
               "             {\"center\": [3, 0, 0], \"radius\": 1}]}\n");
    const char *needles[] = {path, NULL};
    fault_sweep_stats st = sweep_scene("scene json", path, needles);
    expect_no_fallback("scene_json", st);
}

/* A 4^3 float NRRD volume (a ramp along x, offset by `step`) as
 * NAME.nhdr + NAME.raw. */
static void write_volume_step(const char *name, int step)
{
    char path[PATH_BYTES], text[512];
    float samples[64];
    for (int i = 0; i < 64; i++)
        samples[i] = (float)(i % 4 + step);
    snprintf(text, sizeof text, "%s.raw", name);
    write_file(path, text, samples, sizeof samples);
    snprintf(text, sizeof text,
             "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nendian: little\nencoding: raw\n"
             "data file: %s.raw\n",
             name);
    char header[64];
    snprintf(header, sizeof header, "%s.nhdr", name);
    write_text(path, header, text);
}

/* A volume time series ("files"): the pattern's glob, step 0's volume, the
 * series attached to the shared volume, two iso-surfaces and the medium
 * watching it. (A step's own load runs on the loader thread, where the
 * read-ahead after each step makes the count differ from run to run: not
 * swept here.) */
Test(alloc_sweep, scene_volume_series)
{
    char path[PATH_BYTES];
    write_volume_step("vstep_0", 0);
    write_volume_step("vstep_1", 1);
    write_text(path, "volumes.json",
               "{\"volumes\": [{\"files\": \"vstep_*.nhdr\", \"iso\": [{\"value\": 1.5}, {\"value\": 2.5}],\n"
               "  \"dvr\": {\"transfer\": {\"map\": \"viridis\", \"opacity\": [[0, 0], [1, 0.5]]}}}]}\n");
    const char *needles[] = {path, NULL};
    fault_sweep_stats st = sweep_scene("scene volume series", path, needles);
    expect_no_fallback("scene_volume_series", st);
}

/* A mesh file given as the scene (scene_load wraps it). */
Test(alloc_sweep, scene_from_mesh_file)
{
    const char *path = "../configs/scenes/data/cube.ply";
    const char *needles[] = {path, NULL};
    expect_no_fallback("scene from a mesh", sweep_scene("scene from a mesh", path, needles));
}

Test(alloc_sweep, default_scene)
{
    expect_no_fallback("built-in scene", sweep_scene("built-in scene", NULL, NULL));
}

/* ---- the acceleration structure ------------------------------------------- */

typedef struct accel_op {
    const scene *s;
    int threads;
    size_t ref_bytes;
    const ray *rays;
    const hit *ref_hits;
    int ray_count;
} accel_op;

#define ACCEL_RAYS 64

static bool op_accel(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    accel_op *o = ctx;
    tess_error err = {{0}};
    accel *a = accel_build(o->s, o->threads, &err);
    fault_disarm();
    if (!a) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = accel_bytes(a) == o->ref_bytes;
    for (int i = 0; *same && i < o->ray_count; i++) {
        hit h;
        accel_intersect(a, &o->rays[i], &h);
        *same = memcmp(&h, &o->ref_hits[i], sizeof h) == 0;
    }
    accel_destroy(a);
    return true;
}

/* Rays from a point outside the scene towards points spread over its bounds. */
static void make_rays(const scene *s, ray *rays, int n)
{
    vec3 lo, hi;
    cr_assert(scene_bounds(s, &lo, &hi));
    vec3 eye = v3(hi.x + 3.f, hi.y + 2.f, hi.z + 5.f);
    for (int i = 0; i < n; i++) {
        float fx = (float)(i % 8) / 7.f, fy = (float)(i / 8) / 7.f;
        vec3 at = v3(lo.x + fx * (hi.x - lo.x), lo.y + fy * (hi.y - lo.y), 0.5f * (lo.z + hi.z));
        rays[i] = (ray){eye, v3_normalize(v3_sub(at, eye)), 0.f, INFINITY};
    }
}

static fault_sweep_stats sweep_accel(const char *name, const scene *s, int threads)
{
    static ray rays[ACCEL_RAYS];
    static hit hits[ACCEL_RAYS];
    make_rays(s, rays, ACCEL_RAYS);
    tess_error err = {{0}};
    accel *ref = accel_build(s, threads, &err);
    cr_assert_not_null(ref, "%s", err.msg);
    for (int i = 0; i < ACCEL_RAYS; i++)
        accel_intersect(ref, &rays[i], &hits[i]);
    accel_op o = {s, threads, accel_bytes(ref), rays, hits, ACCEL_RAYS};
    accel_destroy(ref);
    const char *needles[] = {NULL};
    return fault_sweep(name, op_accel, &o, needles);
}

Test(alloc_sweep, accel_build_serial)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert_not_null(s, "%s", err.msg);
    fault_sweep_stats st = sweep_accel("accel (1 thread)", s, 1);
    cr_assert_gt(st.failed, 0);
    scene_destroy(s);
}

/* Enough triangles for the parallel build (more than BVH_PARALLEL_NODE_MIN):
 * the thread pool, task lists and the compaction pass allocate too. */
Test(alloc_sweep, accel_build_parallel)
{
    tess_error err = {{0}};
    scene *s = scene_create();
    cr_assert_not_null(s);
    mesh *m = mesh_create();
    cr_assert_not_null(m);
    const uint32_t grid = 80; /* 80 x 80 quads: 12800 triangles */
    for (uint32_t y = 0; y <= grid; y++)
        for (uint32_t x = 0; x <= grid; x++)
            cr_assert(mesh_add_vertex(m, (float)x, (float)y, 0.1f * (float)((x * 7 + y * 3) % 5)));
    for (uint32_t y = 0; y < grid; y++)
        for (uint32_t x = 0; x < grid; x++) {
            uint32_t a = y * (grid + 1) + x;
            cr_assert(mesh_add_triangle(m, a, a + 1, a + grid + 2));
            cr_assert(mesh_add_triangle(m, a, a + grid + 2, a + grid + 1));
        }
    material mat = material_default();
    cr_assert_geq(scene_add_material(s, &mat), 0);
    cr_assert_geq(scene_add_mesh(s, m, 0, "grid"), 0);
    cr_assert_geq(scene_add_sphere(s, v3(40.f, 40.f, 5.f), 3.f, 0), 0);
    fault_sweep_stats st = sweep_accel("accel (2 threads)", s, 2);
    cr_assert_gt(st.failed, 0);
    scene_destroy(s);
    (void)err;
}

/* ---- the pipeline: create, channels, displays, frames, destroy ------------- */

/* The frames the dump display wrote (pattern frame_####.png, frames 0..2 of
 * 2 channels: NAME-c0/-c1 beside it) equal the reference run's files. */
#define PIPELINE_FRAMES 3

typedef struct pipeline_op {
    const scene *s;
    const accel *a;
    camera_desc camera;
    char pattern[PATH_BYTES]; /* where each run of the op writes */
    char ref_dir[PATH_BYTES]; /* the fault-free run's files */
} pipeline_op;

/* A 2-thread pipeline with two channels (a whole picture and a window of a
 * wall), each to a dump display, for PIPELINE_FRAMES frames at fixed time. */
static bool run_pipeline(const pipeline_op *o, const char *pattern, tess_error *err)
{
    pipeline_config cfg = pipeline_config_default(o->s, o->a);
    cfg.threads = 2;
    cfg.max_frames = PIPELINE_FRAMES;
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE;
    pipeline *p = pipeline_create(&cfg, err);
    if (!p)
        return false;
    char path[2][PATH_BYTES];
    for (int c = 0; c < 2; c++)
        snprintf(path[c], PATH_BYTES, "%s-c%d_####.png", pattern, c);
    image_display *d0 = display_dump_create(path[0], true, err);
    bool ok = d0 && pipeline_add_channel(p, &o->camera, 40, 24, d0, err) >= 0;
    image_display *d1 = ok ? display_dump_create(path[1], true, err) : NULL;
    camera_window right_half = {0.5f, 0.0f, 0.5f, 1.0f};
    ok = ok && d1 && pipeline_add_channel_window(p, &o->camera, 2.0f, right_half, 20, 20, d1, err) >= 0;
    ok = ok && pipeline_run(p, err);
    pipeline_destroy(p);
    return ok;
}

static bool same_file(const char *a, const char *b)
{
    char cmd[5 * PATH_BYTES];
    snprintf(cmd, sizeof cmd, "cmp -s '%s' '%s'", a, b);
    return support_run(cmd) == 0;
}

static bool op_pipeline(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    pipeline_op *o = ctx;
    tess_error err = {{0}};
    bool ok = run_pipeline(o, o->pattern, &err);
    fault_disarm();
    if (!ok) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = true;
    for (int c = 0; c < 2 && *same; c++)
        for (int f = 0; f < PIPELINE_FRAMES && *same; f++) {
            char got[2 * PATH_BYTES], want[2 * PATH_BYTES];
            snprintf(got, sizeof got, "%s-c%d_%04d.png", o->pattern, c, f);
            snprintf(want, sizeof want, "%s/ref-c%d_%04d.png", o->ref_dir, c, f);
            *same = same_file(got, want);
        }
    return true;
}

/* Every allocation of making a pipeline (threads, channels, tiles, the
 * transaction queue, the displays) and of running it fails cleanly: an error
 * saying "out of memory", no leak, no crash; or the frames are those of the
 * fault-free run. */
Test(alloc_sweep, pipeline_create_run_destroy, .timeout = 600)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert_not_null(s, "%s", err.msg);
    accel *a = accel_build(s, 1, &err);
    cr_assert_not_null(a, "%s", err.msg);
    vec3 lo, hi;
    cr_assert(scene_bounds(s, &lo, &hi));
    pipeline_op o = {s, a, s->has_camera ? s->camera : camera_frame_bounds(lo, hi, v3(0.f, 0.f, -1.f), 50.f, 40, 24), "",
                     ""};
    snprintf(o.pattern, sizeof o.pattern, "%s/run", scratch_dir);
    snprintf(o.ref_dir, sizeof o.ref_dir, "%s", scratch_dir);
    char ref[PATH_BYTES];
    snprintf(ref, sizeof ref, "%s/ref", scratch_dir);
    cr_assert(run_pipeline(&o, ref, &err), "the fault-free run: %s", err.msg);
    const char *needles[] = {NULL};
    fault_sweep_stats st = fault_sweep("pipeline", op_pipeline, &o, needles);
    cr_assert_gt(st.failed, 0, "nothing failed: the sweep tests nothing");
    accel_destroy(a);
    scene_destroy(s);
}

/* ---- wall, bindings, camera path, record, pipeline config ----------------- */

typedef struct wall_op {
    const char *path;
    wall_config ref;
} wall_op;

static bool op_wall(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    wall_op *o = ctx;
    tess_error err = {{0}};
    static wall_config w;
    memset(&w, 0, sizeof w);
    bool ok = wall_config_load(o->path, &w, &err);
    fault_disarm();
    if (!ok) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = memcmp(&w, &o->ref, sizeof w) == 0;
    return true;
}

Test(alloc_sweep, wall_config)
{
    static wall_op o;
    o.path = "../configs/walls/wall_2x2.json";
    tess_error err = {{0}};
    cr_assert(wall_config_load(o.path, &o.ref, &err), "%s", err.msg);
    const char *needles[] = {o.path, NULL};
    fault_sweep_stats st = fault_sweep("wall config", op_wall, &o, needles);
    expect_no_fallback("wall_config", st);
}

typedef struct bindings_op {
    const char *path;
    input_bindings ref;
} bindings_op;

static bool op_bindings(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    bindings_op *o = ctx;
    tess_error err = {{0}};
    input_bindings b;
    bool ok = input_bindings_load(o->path, &b, &err);
    fault_disarm();
    if (!ok) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = memcmp(&b, &o->ref, sizeof b) == 0;
    return true;
}

Test(alloc_sweep, bindings)
{
    bindings_op o;
    memset(&o, 0, sizeof o);
    o.path = "../configs/bindings.json";
    tess_error err = {{0}};
    cr_assert(input_bindings_load(o.path, &o.ref, &err), "%s", err.msg);
    const char *needles[] = {o.path, NULL};
    fault_sweep_stats st = fault_sweep("bindings", op_bindings, &o, needles);
    expect_no_fallback("bindings", st);
}

typedef struct path_op {
    const char *path;
    camera_path ref;
} path_op;

static bool op_path(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    path_op *o = ctx;
    tess_error err = {{0}};
    camera_path p;
    bool ok = camera_path_load(o->path, &p, &err);
    fault_disarm();
    if (!ok) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = p.count == o->ref.count && p.loop == o->ref.loop && p.interp == o->ref.interp &&
            memcmp(p.keys, o->ref.keys, p.count * sizeof *p.keys) == 0;
    camera_path_free(&p);
    return true;
}

Test(alloc_sweep, camera_path)
{
    path_op o = {"../configs/paths/tour.json", {0}};
    tess_error err = {{0}};
    cr_assert(camera_path_load(o.path, &o.ref, &err), "%s", err.msg);
    const char *needles[] = {o.path, NULL};
    fault_sweep_stats st = fault_sweep("camera path", op_path, &o, needles);
    expect_no_fallback("camera_path", st);
    camera_path_free(&o.ref);
}

/* Saving a path (the --record writer) formats it in memory first. */
typedef struct path_save_op {
    const camera_path *path;
    const char *file;
} path_save_op;

static bool op_path_save(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    path_save_op *o = ctx;
    tess_error err = {{0}};
    bool ok = camera_path_save(o->path, o->file, &err);
    fault_disarm();
    if (!ok) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    camera_path back;
    *same = camera_path_load(o->file, &back, &err) && back.count == o->path->count &&
            memcmp(back.keys, o->path->keys, back.count * sizeof *back.keys) == 0;
    camera_path_free(&back);
    return true;
}

Test(alloc_sweep, camera_path_save)
{
    camera_path p;
    tess_error err = {{0}};
    cr_assert(camera_path_load("../configs/paths/tour.json", &p, &err), "%s", err.msg);
    char file[PATH_BYTES];
    snprintf(file, sizeof file, "%s/saved.json", scratch_dir);
    path_save_op o = {&p, file};
    const char *needles[] = {file, NULL};
    expect_no_fallback("camera path save", fault_sweep("camera path save", op_path_save, &o, needles));
    camera_path_free(&p);
}

typedef struct record_op {
    const char *path;
    input_record ref;
} record_op;

static bool op_record(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    record_op *o = ctx;
    tess_error err = {{0}};
    input_record r;
    bool ok = input_record_load(o->path, &r, &err);
    fault_disarm();
    if (!ok) {
        copy_msg(msg, msg_bytes, &err);
        return false;
    }
    *same = r.count == o->ref.count && memcmp(r.entries, o->ref.entries, r.count * sizeof *r.entries) == 0;
    input_record_free(&r);
    return true;
}

/* 150 lines of every kind: the entry array grows (64, 128, 256). */
Test(alloc_sweep, record_input)
{
    char path[PATH_BYTES];
    snprintf(path, sizeof path, "%s/session.rec", scratch_dir);
    FILE *f = fopen(path, "w");
    cr_assert_not_null(f);
    fprintf(f, "%s\n", INPUT_RECORD_HEADER);
    for (int i = 0; i < 150; i++) {
        /* camera, cursor, status, hide, show-all, tour: the kinds format 1 had but quit */
        camera_desc cam = {v3(1.f + (float)i, 2.f, 3.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
        char text[64];
        snprintf(text, sizeof text, "picked \"mesh\" %d", i);
        input_txn t = i % 6 == 0   ? txn_camera(TXN_ALL_CHANNELS, &cam)
                      : i % 6 == 1 ? txn_cursor(i % 2, 0.25f, -0.5f)
                      : i % 6 == 2 ? txn_status(text)
                      : i % 6 == 3 ? txn_geoms_record(TXN_HIDE, (uint32_t)i % 3, 1)
                      : i % 6 == 4 ? txn_simple(TXN_SHOW_ALL)
                                   : txn_flag(TXN_TOUR, i % 2);
        cr_assert(input_record_write(f, 0.01 * i, &t));
    }
    cr_assert_eq(fclose(f), 0);
    static record_op o;
    o.path = path;
    tess_error err = {{0}};
    cr_assert(input_record_load(path, &o.ref, &err), "%s", err.msg);
    cr_assert_eq(o.ref.count, 150);
    const char *needles[] = {path, NULL};
    fault_sweep_stats st = fault_sweep("record input", op_record, &o, needles);
    expect_no_fallback("record_input", st);
    input_record_free(&o.ref);
}

/* The pipeline config prints its error (the CLI's cli_error): stderr is
 * caught in a file around the call. */
typedef struct config_op {
    const char *path;
    const char *err_file;
    cli_pipeline_spec *ref, *spec;
} config_op;

static bool op_config(void *ctx, char *msg, size_t msg_bytes, bool *same)
{
    config_op *o = ctx;
    cli_pipeline_spec_default(o->spec, "dump", "out/x.png");
    fflush(stderr);
    int saved = dup(2), fd = open(o->err_file, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    cr_assert(saved >= 0 && fd >= 0);
    dup2(fd, 2);
    close(fd);
    bool ok = cli_pipeline_config_load(o->path, o->spec);
    fault_disarm();
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    if (!ok) {
        FILE *f = fopen(o->err_file, "r");
        cr_assert_not_null(f);
        size_t n = fread(msg, 1, msg_bytes - 1, f);
        fclose(f);
        msg[n] = '\0';
        if (n > 0 && msg[n - 1] == '\n') /* the one line cli_error prints */
            msg[n - 1] = '\0';
        return false;
    }
    *same = memcmp(o->spec, o->ref, sizeof *o->spec) == 0;
    return true;
}

Test(alloc_sweep, pipeline_config)
{
    static cli_pipeline_spec ref, spec;
    char err_file[PATH_BYTES];
    snprintf(err_file, sizeof err_file, "%s/stderr.txt", scratch_dir);
    const char *files[] = {"../configs/pipeline/kiosk.json", "../configs/pipeline/two_views.json"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        memset(&ref, 0, sizeof ref);
        memset(&spec, 0, sizeof spec);
        config_op o = {files[i], err_file, &ref, &spec};
        cli_pipeline_spec_default(&ref, "dump", "out/x.png");
        cr_assert(cli_pipeline_config_load(files[i], &ref));
        const char *needles[] = {files[i], NULL};
        fault_sweep_stats st = fault_sweep(files[i], op_config, &o, needles);
        expect_no_fallback("pipeline_config", st);
    }
}

/* EDID identities are parsed in place: no allocation to fail (if one is
 * added, this says so and it belongs in a sweep). */
Test(alloc_sweep, edid_allocates_nothing)
{
    uint8_t block[128] = {0x00, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x00, 0x10, 0xac, 0x34, 0x12};
    memcpy(&block[54 + 18 * 1], "\0\0\0\xfc\0TESSERA TEST\n ", 18);
    unsigned sum = 0;
    for (int i = 0; i < 127; i++)
        sum += block[i];
    block[127] = (uint8_t)(256 - sum % 256);
    edid_identity id;
    fault_arm(0);
    bool ok = edid_parse(block, sizeof block, &id);
    long n = fault_disarm();
    cr_assert(ok);
    cr_assert_str_eq(id.model, "TESSERA TEST");
    cr_assert_eq(n, 0, "edid_parse allocated %ld times: sweep it", n);
}
