/* test_assembly_load.c - engine/load/assembly_load.h on glTF and OBJ files written
 * here (glTF with its buffer embedded as a base64 data URI), through a sink
 * that records every call; and `tessera parts` on such a file.
 *
 * Every test writes its input into a fresh mkdtemp directory (removed after
 * the test). The buffer's floats are written little-endian byte by byte. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "engine/load/assembly_load.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/scene/part_tree.h"
#include "support.h"
#include "engine/load/mesh_load.h"

#define PATH_BYTES 512

static char scratch_dir[128];

static void scratch_create(void) { support_make_tmp_dir(scratch_dir, sizeof scratch_dir, "assembly"); }

static void scratch_remove(void) { support_remove_tmp_dir(scratch_dir); }

TestSuite(assembly_load, .init = scratch_create, .fini = scratch_remove);
TestSuite(parts_cli, .init = scratch_create, .fini = scratch_remove);

static const char *scratch_path(char out[PATH_BYTES], const char *name)
{
    snprintf(out, PATH_BYTES, "%s/%.200s", scratch_dir, name);
    return out;
}

/* ---- glTF files ---------------------------------------------------------- */

/* The buffer every glTF here uses: one triangle (0,0,0) (1,0,0) (0,1,0) as
 * accessor 0, its indices 0 1 2 (uint16) as accessor 1, normals (0,0,1) as
 * accessor 2. `nan_vertex`: vertex 1's y is NaN. */
#define GLTF_BUFFER_BYTES 80
static const char gltf_views[] =
    "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},"
    "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},{\"buffer\":0,\"byteOffset\":44,\"byteLength\":36}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
    "\"min\":[0,0,0],\"max\":[1,1,0]},{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
    "{\"bufferView\":2,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}]";

static void put_f32(unsigned char *p, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(bits >> (8 * i));
}

static void make_buffer(unsigned char buf[GLTF_BUFFER_BYTES], bool nan_vertex)
{
    static const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const float normals[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    memset(buf, 0, GLTF_BUFFER_BYTES);
    for (int i = 0; i < 9; i++) {
        put_f32(buf + 4 * i, positions[i]);
        put_f32(buf + 44 + 4 * i, normals[i]);
    }
    if (nan_vertex)
        put_f32(buf + 16, NAN);
    for (int i = 0; i < 3; i++) {
        buf[36 + 2 * i] = (unsigned char)i;
        buf[37 + 2 * i] = 0;
    }
}

static void base64(const unsigned char *in, size_t n, char *out)
{
    static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t o = 0;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) | (i + 2 < n ? in[i + 2] : 0);
        out[o++] = digits[v >> 18 & 63];
        out[o++] = digits[v >> 12 & 63];
        out[o++] = i + 1 < n ? digits[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? digits[v & 63] : '=';
    }
    out[o] = '\0';
}

/* The text of a glTF file: `body` (nodes, scenes, meshes, materials: JSON
 * members without the braces) with the buffer, views and accessors. */
static char *gltf_text(const char *body, bool nan_vertex)
{
    unsigned char buf[GLTF_BUFFER_BYTES];
    char b64[4 * GLTF_BUFFER_BYTES / 3 + 8];
    make_buffer(buf, nan_vertex);
    base64(buf, sizeof buf, b64);
    size_t size = strlen(body) + sizeof gltf_views + sizeof b64 + 256;
    char *text = malloc(size);
    cr_assert_not_null(text);
    snprintf(text, size,
             "{\"asset\":{\"version\":\"2.0\"},%s,%s,"
             "\"buffers\":[{\"byteLength\":%d,\"uri\":\"data:application/octet-stream;base64,%s\"}]}\n",
             body, gltf_views, GLTF_BUFFER_BYTES, b64);
    return text;
}

static const char *write_gltf(char path[PATH_BYTES], const char *name, const char *body, bool nan_vertex)
{
    char *text = gltf_text(body, nan_vertex);
    support_write_file(scratch_dir, name, text);
    free(text);
    return scratch_path(path, name);
}

/* A 3-level hierarchy: mesh "tri" used by three nodes (the two "bolt"s under
 * "frame/1", rotated 90 degrees about z, and the "bolt" under "panel"), mesh
 * "lit" (with normals) by "panel"; an unused mesh and material. */
static const char hierarchy_body[] =
    "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
    "\"nodes\":["
    "{\"name\":\"assembly\",\"children\":[1,4],\"translation\":[10,0,0]},"
    "{\"name\":\"frame/1\",\"children\":[2,3],\"rotation\":[0,0,0.70710678,0.70710678]},"
    "{\"name\":\"bolt\",\"mesh\":0,\"translation\":[0,2,0]},"
    "{\"name\":\"bolt\",\"mesh\":0,\"translation\":[0,0,3],\"scale\":[2,2,2]},"
    "{\"name\":\"panel\",\"children\":[5],\"mesh\":1},"
    "{\"name\":\"bolt\",\"mesh\":0}],"
    "\"meshes\":["
    "{\"name\":\"tri\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]},"
    "{\"name\":\"lit\",\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":2},\"indices\":1,\"material\":1}]},"
    "{\"name\":\"unused\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":2}]}],"
    "\"materials\":["
    "{\"name\":\"steel\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.25,0.5,0.75,1]}},"
    "{\"name\":\"paint\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[2,-1,0.5,1]}},"
    "{\"name\":\"spare\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0,0,1,1]}}]";

/* ---- a sink that records ----------------------------------------------- */

#define REC_MAX 32

typedef struct recorder {
    char log[4096];               /* the calls in order: "P name", "M name", "G name", "I part:mesh", ';'-separated */
    int calls, fail_at;           /* fail_at: the 1-based call that returns -1 (0: none) */
    int materials;
    char material_names[REC_MAX][64];
    float material_rgb[REC_MAX][3];
    int meshes;
    int mesh_material[REC_MAX];
    uint32_t mesh_triangles[REC_MAX];
    bool mesh_normals[REC_MAX];
    float mesh_vertex1[REC_MAX][3]; /* the mesh's vertex 1 in object space */
    part_tree *tree;                /* the parts: refuses anything out of preorder */
    int instances;
    int instance_part[REC_MAX], instance_mesh[REC_MAX];
    float instance_xform[REC_MAX][12];
} recorder;

static void rec_log(recorder *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void rec_log(recorder *r, const char *fmt, ...)
{
    size_t n = strlen(r->log);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->log + n, sizeof r->log - n, fmt, ap);
    va_end(ap);
}

/* Count the call; true when it is the one to refuse. */
static bool rec_refuse(recorder *r) { return ++r->calls == r->fail_at; }

static int rec_material(void *ctx, const char *name, const float rgb[3])
{
    recorder *r = ctx;
    rec_log(r, "M %s;", name);
    if (rec_refuse(r))
        return -1;
    cr_assert_lt(r->materials, REC_MAX);
    snprintf(r->material_names[r->materials], 64, "%s", name);
    memcpy(r->material_rgb[r->materials], rgb, 3 * sizeof *rgb);
    return r->materials++;
}

static int rec_mesh(void *ctx, mesh *m, int material, const char *name)
{
    recorder *r = ctx;
    rec_log(r, "G %s;", name);
    cr_assert(material >= 0 && material < r->materials, "mesh '%s': material %d was never reported", name, material);
    if (rec_refuse(r)) {
        mesh_destroy(m);
        return -1;
    }
    cr_assert_lt(r->meshes, REC_MAX);
    int id = r->meshes++;
    r->mesh_material[id] = material;
    r->mesh_triangles[id] = m->triangle_count;
    r->mesh_normals[id] = m->normals != NULL;
    cr_assert_geq(m->vertex_count, 2);
    memcpy(r->mesh_vertex1[id], m->positions + 3, 3 * sizeof(float));
    mesh_destroy(m);
    return id;
}

static int rec_part(void *ctx, int parent, const char *name)
{
    recorder *r = ctx;
    rec_log(r, "P %s;", name);
    if (rec_refuse(r))
        return -1;
    tess_error err = {{0}};
    int32_t id = part_tree_add(r->tree, parent < 0 ? PART_ROOT : parent, name, &err);
    cr_assert_neq(id, PART_NONE, "part '%s' under %d: %s", name, parent, err.msg);
    return id;
}

static int rec_instance(void *ctx, int part, int mesh_id, const float to_world[12])
{
    recorder *r = ctx;
    rec_log(r, "I %d:%d;", part, mesh_id);
    cr_assert_eq(part, part_tree_count(r->tree) - 1, "an instance comes right after its part");
    cr_assert(mesh_id >= 0 && mesh_id < r->meshes, "instance of unreported mesh %d", mesh_id);
    if (rec_refuse(r))
        return -1;
    cr_assert_lt(r->instances, REC_MAX);
    r->instance_part[r->instances] = part;
    r->instance_mesh[r->instances] = mesh_id;
    memcpy(r->instance_xform[r->instances], to_world, 12 * sizeof(float));
    r->instances++;
    return 0;
}

static void rec_init(recorder *r, assembly_sink *sink)
{
    memset(r, 0, sizeof *r);
    r->tree = part_tree_create();
    cr_assert_not_null(r->tree);
    *sink = (assembly_sink){.ctx = r,
                            .material = rec_material,
                            .mesh = rec_mesh,
                            .part = rec_part,
                            .instance = rec_instance};
}

static void rec_load_ok(recorder *r, const char *path)
{
    assembly_sink sink;
    rec_init(r, &sink);
    tess_error err = {{0}};
    cr_assert(assembly_load(path, &sink, &err), "%s", err.msg);
    cr_expect_str_empty(err.msg);
}

static void expect_path(const recorder *r, int32_t id, const char *want)
{
    char path[256];
    part_tree_path(r->tree, id, path, sizeof path);
    cr_expect_str_eq(path, want, "part %d", id);
}

/* to_world applied to p */
static void apply(const float m[12], const float p[3], float out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
}

static void expect_near3(const float got[3], float x, float y, float z, const char *what)
{
    cr_expect(fabsf(got[0] - x) < 1e-5f && fabsf(got[1] - y) < 1e-5f && fabsf(got[2] - z) < 1e-5f,
              "%s: got (%g, %g, %g), want (%g, %g, %g)", what, (double)got[0], (double)got[1], (double)got[2],
              (double)x, (double)y, (double)z);
}

/* ---- tests --------------------------------------------------------------- */

Test(assembly_load, gltf_hierarchy_shares_one_mesh)
{
    char path[PATH_BYTES];
    write_gltf(path, "assembly.gltf", hierarchy_body, false);
    recorder r;
    rec_load_ok(&r, path);
    /* preorder; materials and meshes once each, on first use, only used ones;
     * '/' sanitized; sibling "bolt"s made unique; the root node is a part */
    cr_expect_str_eq(r.log, "P assembly;P frame_1;P bolt;M steel;G tri;I 3:0;P bolt#2;I 4:0;"
                            "P panel;M paint;G lit;I 5:1;P bolt;I 6:0;");
    expect_path(&r, 1, "assembly");
    expect_path(&r, 2, "assembly/frame_1");
    expect_path(&r, 3, "assembly/frame_1/bolt");
    expect_path(&r, 4, "assembly/frame_1/bolt#2");
    expect_path(&r, 5, "assembly/panel");
    expect_path(&r, 6, "assembly/panel/bolt");
    cr_assert_eq(r.meshes, 2);
    cr_assert_eq(r.instances, 4);
    cr_expect_eq(r.mesh_triangles[0], 1);
    cr_expect_not(r.mesh_normals[0]);
    cr_expect(r.mesh_normals[1], "normals are kept");
    /* materials: glTF's base colour as given, clamped to [0, 1] */
    cr_assert_eq(r.materials, 2);
    expect_near3(r.material_rgb[0], 0.25f, 0.5f, 0.75f, "steel");
    expect_near3(r.material_rgb[1], 1.f, 0.f, 0.5f, "paint");
    cr_expect_eq(r.mesh_material[0], 0);
    cr_expect_eq(r.mesh_material[1], 1);
    /* placement: translate(10,0,0) * rotate_z(90) * translate(0,2,0) takes
     * vertex (1,0,0) to (8,1,0); the second bolt adds scale 2 and (0,0,3) */
    const float *v1 = r.mesh_vertex1[0];
    expect_near3(v1, 1, 0, 0, "vertex 1 in object space");
    float w[3];
    apply(r.instance_xform[0], v1, w);
    expect_near3(w, 8, 1, 0, "first bolt");
    const float want0[12] = {0, -1, 0, 8, 1, 0, 0, 0, 0, 0, 1, 0};
    for (int k = 0; k < 12; k++)
        cr_expect(fabsf(r.instance_xform[0][k] - want0[k]) < 1e-6f, "first bolt's matrix [%d]: %g, want %g", k,
                  (double)r.instance_xform[0][k], (double)want0[k]);
    apply(r.instance_xform[1], v1, w);
    expect_near3(w, 10, 2, 3, "second bolt");
    apply(r.instance_xform[2], r.mesh_vertex1[1], w);
    expect_near3(w, 11, 0, 0, "panel");
    apply(r.instance_xform[3], v1, w);
    expect_near3(w, 11, 0, 0, "panel's bolt");
    part_tree_destroy(r.tree);
}

/* Several scene roots: assimp's made-up "ROOT" is no part, the roots are
 * top-level parts. */
Test(assembly_load, gltf_several_roots)
{
    char path[PATH_BYTES];
    write_gltf(path, "roots.gltf",
               "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],"
               "\"nodes\":[{\"name\":\"left\",\"mesh\":0,\"translation\":[-1,0,0]},"
               "{\"name\":\"right\",\"mesh\":0,\"translation\":[1,0,0]}],"
               "\"meshes\":[{\"name\":\"tri\",\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}]",
               false);
    recorder r;
    rec_load_ok(&r, path);
    cr_expect_eq(part_tree_count(r.tree), 3);
    expect_path(&r, 1, "left");
    expect_path(&r, 2, "right");
    cr_expect_eq(r.meshes, 1);
    cr_expect_eq(r.materials, 1, "assimp's default material is reported");
    float w[3];
    apply(r.instance_xform[1], r.mesh_vertex1[0], w);
    expect_near3(w, 2, 0, 0, "right");
    part_tree_destroy(r.tree);
}

Test(assembly_load, obj_groups_are_parts)
{
    char path[PATH_BYTES], mtl[PATH_BYTES];
    support_write_file(scratch_dir, "groups.mtl", "newmtl red\nKd 0.8 0.1 0.1\n");
    support_write_file(scratch_dir, "groups.obj",
                       "mtllib groups.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl red\n"
                       "g left\nf 1 2 3\ng right/side\nf 2 4 3\nf 1 2 4\n");
    (void)mtl;
    recorder r;
    rec_load_ok(&r, scratch_path(path, "groups.obj"));
    cr_expect_str_eq(r.log, "P left;M red;G left;I 1:0;P right_side;G right/side;I 2:1;");
    expect_path(&r, 1, "left");
    expect_path(&r, 2, "right_side");
    cr_expect_eq(r.mesh_triangles[1], 2);
    expect_near3(r.material_rgb[0], 0.8f, 0.1f, 0.1f, "Kd");
    const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    cr_expect_arr_eq(r.instance_xform[0], identity, sizeof identity);
    part_tree_destroy(r.tree);

    /* no groups: one part named after the file */
    support_write_file(scratch_dir, "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    rec_load_ok(&r, scratch_path(path, "plain.obj"));
    cr_expect_str_eq(r.log, "P plain;M DefaultMaterial;G defaultobject;I 1:0;");
    expect_near3(r.material_rgb[0], 0.6f, 0.6f, 0.6f, "default grey");
    part_tree_destroy(r.tree);
}

/* assembly_load fails with err naming the file and holding every needle. */
static void expect_load_error(const char *path, const char *needle)
{
    recorder r;
    assembly_sink sink;
    rec_init(&r, &sink);
    tess_error err = {{0}};
    cr_expect_not(assembly_load(path, &sink, &err), "%s should not load", path);
    cr_expect(strstr(err.msg, path), "message does not name %s: %s", path, err.msg);
    cr_expect(strstr(err.msg, needle), "message lacks '%s': %s", needle, err.msg);
    part_tree_destroy(r.tree);
}

Test(assembly_load, broken_inputs)
{
    char path[PATH_BYTES];
    expect_load_error(scratch_path(path, "absent.gltf"), "assimp");
    /* not JSON: refused before assimp (which would offer it to every other
     * importer: engine/load/gltf_check.c) */
    support_write_file(scratch_dir, "text.gltf", "hello, not a model\n");
    expect_load_error(scratch_path(path, "text.gltf"), "byte 0: 'h' outside a string is not JSON");
    /* truncated JSON */
    char *text = gltf_text(hierarchy_body, false);
    text[strlen(text) / 2] = '\0';
    support_write_file(scratch_dir, "truncated.gltf", text);
    free(text);
    expect_load_error(scratch_path(path, "truncated.gltf"), "is not closed"); /* the cut falls in the data URI */
    /* an accessor index out of range */
    write_gltf(path, "accessor.gltf",
               "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"name\":\"a\",\"mesh\":0}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":7}]}]",
               false);
    expect_load_error(path, "assimp");
    /* a node's mesh index out of range */
    write_gltf(path, "node_mesh.gltf",
               "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"name\":\"a\",\"mesh\":9}],"
               "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}]",
               false);
    expect_load_error(path, "assimp");
    /* a NaN position */
    write_gltf(path, "nan.gltf", hierarchy_body, true);
    expect_load_error(path, "must be finite");
    /* OBJ: the flattening loader's checks hold here too */
    support_write_file(scratch_dir, "bad.obj", "v 0 0 0\nv 1 abc 0\nv 0 1 0\nf 1 2 3\n");
    expect_load_error(scratch_path(path, "bad.obj"), "expected a number");
    support_write_file(scratch_dir, "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nf 1 2 3\ng b\nf 1 2 9\n");
    expect_load_error(scratch_path(path, "range.obj"), "vertex index 9 out of range");
}

/* write_gltf's file with the buffer's data URI payload character at `at`
 * (0-based) replaced by the bytes `with` (which may be longer). */
static const char *write_gltf_payload_edit(char path[PATH_BYTES], const char *name, size_t at, const char *with)
{
    char *text = gltf_text(hierarchy_body, false);
    char *payload = strstr(text, ";base64,");
    cr_assert_not_null(payload);
    payload += strlen(";base64,") + at;
    size_t size = strlen(text) + strlen(with) + 1;
    char *edited = malloc(size);
    cr_assert_not_null(edited);
    snprintf(edited, size, "%.*s%s%s", (int)(payload - text), text, with, payload + 1);
    support_write_file(scratch_dir, name, edited);
    free(edited);
    free(text);
    return scratch_path(path, name);
}

/* Write a .glb: its 20-byte header and JSON chunk header from the given
 * words (so tests can get them wrong), then `json` padded with spaces to a
 * multiple of 4 bytes; the file is `file_bytes` long (zeros after the text)
 * whatever the header says. */
static const char *write_glb(char path[PATH_BYTES], const char *name, uint32_t version, uint32_t declared_total,
                             uint32_t json_len, uint32_t json_type, const char *json, size_t file_bytes)
{
    unsigned char *glb = calloc(1, file_bytes);
    cr_assert_not_null(glb);
    memcpy(glb, "glTF", 4);
    const uint32_t words[4] = {version, declared_total, json_len, json_type};
    for (int w = 0; w < 4; w++)
        for (int b = 0; b < 4; b++)
            glb[4 + 4 * w + b] = (unsigned char)(words[w] >> (8 * b));
    size_t text = strlen(json), room = file_bytes - 20;
    memset(glb + 20, ' ', ((text + 3) & ~(size_t)3) < room ? (text + 3) & ~(size_t)3 : room);
    memcpy(glb + 20, json, text < room ? text : room);
    FILE *f = fopen(scratch_path(path, name), "wb");
    cr_assert_not_null(f);
    cr_assert_eq(fwrite(glb, 1, file_bytes, f), file_bytes);
    fclose(f);
    free(glb);
    return path;
}

/* write_gltf's file with the buffer's data URI media type "application/octet-stream"
 * replaced by `media` (JSON text: escapes allowed). */
static const char *write_gltf_media_type(char path[PATH_BYTES], const char *name, const char *media)
{
    static const char standard[] = "application/octet-stream";
    char *text = gltf_text(hierarchy_body, false);
    char *at = strstr(text, standard);
    cr_assert_not_null(at);
    size_t size = strlen(text) + strlen(media) + 1;
    char *edited = malloc(size);
    cr_assert_not_null(edited);
    snprintf(edited, size, "%.*s%s%s", (int)(at - text), text, media, at + strlen(standard));
    support_write_file(scratch_dir, name, edited);
    free(edited);
    free(text);
    return scratch_path(path, name);
}

/* assimp 5.2 keeps the offsets inside a data URI in a signed char: with 127 bytes or more
 * before the ',' it decodes the wrong bytes as the buffer (found by fuzz_gltf as a leak:
 * tests/fuzz/corpus/gltf/crash-leak-long-data-uri-header). Such a URI is refused, counted in
 * the bytes assimp sees (a \u escape is its UTF-8 length); one byte shorter loads right. */
Test(assembly_load, data_uri_header_at_most_126_bytes)
{
    char path[PATH_BYTES], media[256];
    /* "data:" + media + ";base64" before the ',': 5 + n + 7 bytes, so n = 114 is 126 */
    memset(media, 'x', 114);
    memcpy(media, "application/", 12);
    media[114] = '\0';
    recorder r;
    rec_load_ok(&r, write_gltf_media_type(path, "longest.gltf", media));
    cr_expect_eq(r.meshes, 2);
    expect_near3(r.mesh_vertex1[0], 1.f, 0.f, 0.f, "vertex 1 of a buffer behind a 126-byte header");
    part_tree_destroy(r.tree);

    strcat(media, "x");
    expect_load_error(write_gltf_media_type(path, "long.gltf", media), "has 127 bytes before its ','");
    /* with a \u escape of a 2-byte character (6 characters of text): 119 characters of text
     * are 115 bytes for assimp, 127 before the ','; 118 are 126 and load */
    memset(media, 'x', 119);
    memcpy(media, "application/\\u00e9", 18);
    media[119] = '\0';
    expect_load_error(write_gltf_media_type(path, "escaped_long.gltf", media), "has 127 bytes before its ','");
    media[118] = '\0';
    rec_load_ok(&r, write_gltf_media_type(path, "escaped.gltf", media));
    expect_near3(r.mesh_vertex1[0], 1.f, 0.f, 0.f, "vertex 1 behind an escaped media type");
    part_tree_destroy(r.tree);
}

#define GLB_JSON_CHUNK 0x4E4F534Au

/* A base64 data URI holding a character outside the alphabet is refused
 * before assimp reads it (assimp 5.2 leaks the buffer of one with a byte >=
 * 0x80 and decodes other strangers as data: engine/load/gltf_check.c), in a
 * .gltf and in a .glb's JSON chunk; JSON escapes of base64 characters are
 * data like any other. */
Test(assembly_load, data_uri_checked)
{
    char path[PATH_BYTES];
    /* the payload's character 5 is 'A' (the buffer starts with zero bytes) */
    expect_load_error(write_gltf_payload_edit(path, "high.gltf", 5, "\xff"), "character 0xff, which is not a base64");
    expect_load_error(write_gltf_payload_edit(path, "bang.gltf", 5, "!"), "holds '!', which is not a base64");
    expect_load_error(write_gltf_payload_edit(path, "escape.gltf", 5, "\\u00e9"), "character 0xe9");
    expect_load_error(write_gltf_payload_edit(path, "newline.gltf", 5, "\\n"), "character 0xa");
    /* the message names the byte: the text before the payload, plus 5 */
    char *text = gltf_text(hierarchy_body, false);
    long long at = (long long)(strstr(text, ";base64,") - text) + 8 + 5;
    free(text);
    char needle[64];
    snprintf(needle, sizeof needle, "byte %lld:", at);
    expect_load_error(write_gltf_payload_edit(path, "where.gltf", 5, "\x80"), needle);

    /* "\u0041" is 'A' and "\/" is '/': the file loads and means the same */
    recorder r;
    rec_load_ok(&r, write_gltf_payload_edit(path, "escaped.gltf", 5, "\\u0041"));
    cr_expect_eq(r.meshes, 2);
    cr_expect_eq(r.instances, 4);
    expect_near3(r.mesh_vertex1[0], 1.f, 0.f, 0.f, "vertex 1");
    part_tree_destroy(r.tree);

    /* a .glb whose JSON chunk holds the bad URI */
    char *json = gltf_text(hierarchy_body, false);
    char *p = strstr(json, ";base64,") + 8 + 5;
    *p = '\x9c';
    uint32_t json_len = (uint32_t)((strlen(json) + 3) & ~(size_t)3); /* chunks are padded to 4 bytes */
    write_glb(path, "bad.glb", 2, 20 + json_len, json_len, GLB_JSON_CHUNK, json, 20 + json_len);
    free(json);
    expect_load_error(path, "character 0x9c");
}

/* What assimp's glTF 2.0 reader would refuse (and assimp then offer to its
 * other importers) is refused first, each with its reason. */
Test(assembly_load, not_quite_gltf_refused_with_the_reason)
{
    char path[PATH_BYTES];
    static const struct {
        const char *name, *text, *needle;
    } cases[] = {
        {"comment.gltf", "{\"asset\":{\"version\":\"2.0\"} // note\n}", "'/' outside a string is not JSON (a comment?)"},
        {"quote.gltf", "{'asset':{}}", "(a single-quoted string?)"},
        {"comma.gltf", "{\"asset\":{\"version\":\"2.0\"},}", "a ',' before '}'"},
        {"nan.gltf", "{\"asset\":{\"version\":\"2.0\"},\"x\":NaN}", "'N' outside a string"},
        {"huge.gltf", "{\"asset\":{\"version\":\"2.0\"},\"x\":1e400}", "out of range"},
        {"control.gltf", "{\"asset\":{\"version\":\"2.0\",\"generator\":\"a\tb\"}}", "control character 0x09"},
        {"surrogate.gltf", "{\"asset\":{\"version\":\"2.0\",\"generator\":\"\\ud800x\"}}", "high surrogate"},
        {"twice.gltf", "{\"asset\":{},\"asset\":{\"version\":\"2.0\"}}", "duplicate key 'asset'"},
        {"array.gltf", "[1, 2]", "not an object"},
        {"noasset.gltf", "{\"scene\":0}", "no \"asset\" object"},
        {"version1.gltf", "{\"asset\":{\"version\":\"1.0\"}}", "asset.version is '1.0': tessera reads glTF 2.0"},
        {"number.gltf", "{\"asset\":{\"version\":2}}", "asset.version: missing or not a string"},
        {"json.glb", "{\"asset\":{\"version\":\"2.0\"}}", "does not start with \"glTF\""},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        support_write_file(scratch_dir, cases[i].name, cases[i].text);
        expect_load_error(scratch_path(path, cases[i].name), cases[i].needle);
    }
    /* binary headers: version, chunk type, lengths, a promised BIN chunk */
    static const char json[] = "{\"asset\":{\"version\":\"2.0\"}}"; /* 27 bytes: a 32-byte chunk */
    static const struct {
        const char *name;
        uint32_t version, total, json_len, json_type;
        const char *needle;
    } glbs[] = {
        {"v1.glb", 1, 52, 32, GLB_JSON_CHUNK, "binary glTF version 1"},
        {"type.glb", 2, 52, 32, 0x12345678u, "the first chunk is not JSON"},
        {"long.glb", 2, 52, 999, GLB_JSON_CHUNK, "does not fit the file"},
        {"nobin.glb", 2, 200, 32, GLB_JSON_CHUNK, "promises a BIN chunk"},
    };
    for (size_t i = 0; i < sizeof glbs / sizeof glbs[0]; i++) {
        write_glb(path, glbs[i].name, glbs[i].version, glbs[i].total, glbs[i].json_len, glbs[i].json_type, json,
                  52);
        expect_load_error(path, glbs[i].needle);
    }
}

/* A sink refusing any one call ends the load there: false, a message, no
 * call after the refused one (the sink's meshes are freed: see rec_mesh). */
Test(assembly_load, sink_refusal_aborts)
{
    char path[PATH_BYTES];
    write_gltf(path, "assembly.gltf", hierarchy_body, false);
    recorder full;
    rec_load_ok(&full, path);
    int total = full.calls;
    part_tree_destroy(full.tree);
    cr_assert_eq(total, 14);
    for (int k = 1; k <= total; k++) {
        recorder r;
        assembly_sink sink;
        rec_init(&r, &sink);
        r.fail_at = k;
        tess_error err = {{0}};
        cr_expect_not(assembly_load(path, &sink, &err), "refusing call %d", k);
        cr_expect(strstr(err.msg, "refused") && strstr(err.msg, path), "call %d: %s", k, err.msg);
        cr_expect_eq(r.calls, k, "no call after the refused call %d", k);
        part_tree_destroy(r.tree);
    }
}

/* A chain of nodes 100,000 deep (assimp recurses over it: 20,000 levels
 * overflowed the 8 MiB main stack): both assimp loaders survive it. */
Test(assembly_load, deep_hierarchy, .timeout = 120)
{
    enum { DEPTH = 100000 };
    size_t size = 64 * (size_t)DEPTH + 1024;
    char *body = malloc(size);
    cr_assert_not_null(body);
    size_t n = (size_t)snprintf(body, size, "\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[");
    for (int i = 0; i < DEPTH; i++)
        n += (size_t)(i + 1 < DEPTH ? snprintf(body + n, size - n, "{\"name\":\"n\",\"children\":[%d]},", i + 1)
                                    : snprintf(body + n, size - n, "{\"name\":\"n\",\"mesh\":0}],"));
    snprintf(body + n, size - n,
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}]");
    char path[PATH_BYTES];
    write_gltf(path, "deep.gltf", body, false);
    free(body);
    recorder r;
    rec_load_ok(&r, path);
    cr_expect_eq(part_tree_count(r.tree), 1 + DEPTH);
    cr_expect_eq(part_tree_depth(r.tree, DEPTH), DEPTH);
    cr_expect_eq(r.instances, 1);
    part_tree_destroy(r.tree);
    tess_error err = {{0}};
    mesh *m = mesh_load_assimp(path, &err);
    cr_expect_not_null(m, "%s", err.msg);
    mesh_destroy(m);
}

/* ---- tessera parts --------------------------------------------------------- */

Test(parts_cli, prints_the_tree)
{
    char path[PATH_BYTES], out[8192], err[8192];
    write_gltf(path, "assembly.gltf", hierarchy_body, false);
    int code = support_tessera_split(scratch_dir, 30, out, err, sizeof out, "parts", "%s/assembly.gltf");
    cr_assert_eq(code, 0, "exit %d: %s %s", code, out, err);
    cr_expect(strstr(out, "parts=6 meshes=2 materials=2 instances=4 triangles_stored=2 triangles_instanced=4 load_s="),
              "%s", out);
    cr_expect(strstr(out, "\nassembly  instances=0 triangles=0 subtree_triangles=4\n"), "%s", out);
    cr_expect(strstr(out, "\n  assembly/frame_1  instances=0 triangles=0 subtree_triangles=2\n"), "%s", out);
    cr_expect(strstr(out, "\n    assembly/frame_1/bolt#2  instances=1 triangles=1 subtree_triangles=1\n"), "%s", out);
    cr_expect(strstr(out, "\n  assembly/panel  instances=1 triangles=1 subtree_triangles=2\n"), "%s", out);

    code = support_tessera_split(scratch_dir, 30, out, err, sizeof out, "parts", "%s/assembly.gltf --depth 2");
    cr_assert_eq(code, 0);
    cr_expect(strstr(out, "assembly/panel  "), "%s", out);
    cr_expect_null(strstr(out, "bolt"), "--depth 2: %s", out);

    code = support_tessera_split(scratch_dir, 30, out, err, sizeof out, "parts", "%s/assembly.gltf --match '**/bolt*'");
    cr_assert_eq(code, 0);
    int lines = 0;
    for (const char *c = out; *c; c++)
        lines += *c == '\n';
    cr_expect_eq(lines, 1 + 3, "header and three bolts: %s", out);

    code = support_tessera_split(scratch_dir, 30, out, err, sizeof out, "parts", "%s/assembly.gltf --json --match 'assembly/*'");
    cr_assert_eq(code, 0);
    cr_expect(strstr(out, "\"parts\": 6, \"meshes\": 2"), "%s", out);
    cr_expect(strstr(out, "{\"path\": \"assembly/frame_1\", \"depth\": 2, \"instances\": 0, \"triangles\": 0, "
                          "\"subtree_triangles\": 2}"),
              "%s", out);
    cr_expect_null(strstr(out, "bolt"), "%s", out);
}

Test(parts_cli, errors)
{
    char path[PATH_BYTES];
    (void)path;
    support_write_file(scratch_dir, "broken.gltf", "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[");
    support_expect_error(scratch_dir, 30, "parts %s/broken.gltf", (const char *const[]){"broken.gltf", NULL});
    support_expect_error(scratch_dir, 30, "parts %s/absent.obj", (const char *const[]){"absent.obj", "cannot open", NULL});
    support_expect_error(scratch_dir, 30, "parts", (const char *const[]){"needs a FILE", NULL});
    support_expect_error(scratch_dir, 30, "parts %s/a.gltf --depth 0", (const char *const[]){"--depth", NULL});
    support_expect_error(scratch_dir, 30, "parts %s/a.gltf --frobnicate", (const char *const[]){"--frobnicate", NULL});
}

/* A PLY without faces is a point set: it has no parts, said in those words (assimp said
 * "Mesh contains no faces"); an empty one says what it lacks; a directory is named as one. */
Test(parts_cli, point_sets_empty_files_and_directories)
{
    static const char header[] = "ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                                 "property float z\n%send_header\n%s";
    char text[512];
    snprintf(text, sizeof text, header, 3, "", "0 0 0\n1 0 0\n0 1 0\n");
    support_write_file(scratch_dir, "points.ply", text);
    support_expect_error(scratch_dir, 30, "parts %s/points.ply",
                         (const char *const[]){"points.ply: a point set (3 points, no faces) has no parts",
                                               "draws it as particles", NULL});
    snprintf(text, sizeof text, header, 0, "", "");
    support_write_file(scratch_dir, "none.ply", text);
    support_expect_error(scratch_dir, 30, "parts %s/none.ply",
                         (const char *const[]){"none.ply: no geometry (0 vertices, no faces): it has no parts", NULL});
    snprintf(text, sizeof text, header, 0, "element face 0\nproperty list uchar int vertex_indices\n", "");
    support_write_file(scratch_dir, "nofaces.ply", text);
    support_expect_error(scratch_dir, 30, "parts %s/nofaces.ply",
                         (const char *const[]){"nofaces.ply: no geometry (0 vertices, 0 faces)", NULL});
    /* a mesh PLY is one part, as before */
    snprintf(text, sizeof text, header, 3, "element face 1\nproperty list uchar int vertex_indices\n",
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    support_write_file(scratch_dir, "tri.ply", text);
    char out[8192], err[8192];
    int code = support_tessera_split(scratch_dir, 30, out, err, sizeof out, "parts", "%s/tri.ply");
    cr_expect_eq(code, 0, "%s", err);
    cr_expect(strstr(out, "parts=1 meshes=1 materials=1 instances=1 triangles_stored=1"), "%s", out);
    char dir[PATH_BYTES];
    snprintf(dir, sizeof dir, "%s/folder", scratch_dir);
    cr_assert_eq(mkdir(dir, 0777), 0);
    support_expect_error(scratch_dir, 30, "parts %s/folder", (const char *const[]){"folder: is a directory", NULL});
}
