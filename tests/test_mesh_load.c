/* test_mesh_load.c - the PLY reader and the assimp loader on files written here.
 *
 * Every test writes its input into a fresh mkdtemp directory (removed after the
 * test). Binary PLY files are assembled byte by byte in the declared byte order,
 * so the tests hold on hosts of either endianness. */
#include <criterion/criterion.h>

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "engine/geometry/triangles/mesh.h"
#include "support.h"
#include "engine/load/mesh_load.h"

#define PATH_BYTES 512

/* ---- scratch directory ------------------------------------------------- */

/* This test's scratch directory. Criterion runs every test in its own
 * process, and the suite's init/fini create and remove it around the test. */
static char scratch_dir[128];

static void scratch_create(void) { support_make_tmp_dir(scratch_dir, sizeof scratch_dir, "mesh_load"); }

static void scratch_remove(void) { support_remove_tmp_dir(scratch_dir); }

TestSuite(mesh_load, .init = scratch_create, .fini = scratch_remove);

static const char *scratch_path(char out[PATH_BYTES], const char *name)
{
    snprintf(out, PATH_BYTES, "%s/%.200s", scratch_dir, name);
    return out;
}

/* ---- building files ---------------------------------------------------- */

/* A growing byte string. */
typedef struct bytes {
    unsigned char *data; /* len bytes written, cap allocated */
    size_t len;          /* bytes written */
    size_t cap;          /* bytes allocated */
} bytes;

static void put_bytes(bytes *b, const void *src, size_t n)
{
    if (b->len + n > b->cap) {
        b->cap = 2 * (b->len + n) + 256;
        b->data = realloc(b->data, b->cap);
        cr_assert_not_null(b->data);
    }
    memcpy(b->data + b->len, src, n);
    b->len += n;
}

static void put_text(bytes *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put_text(bytes *b, const char *fmt, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    cr_assert(n >= 0 && (size_t)n < sizeof text);
    put_bytes(b, text, (size_t)n);
}

/* The low `size` bytes of v, most significant first when big, else last. */
static void put_uint(bytes *b, uint64_t v, unsigned size, bool big)
{
    for (unsigned i = 0; i < size; i++) {
        unsigned shift = 8 * (big ? size - 1 - i : i);
        unsigned char byte = (unsigned char)(v >> shift & 0xff);
        put_bytes(b, &byte, 1);
    }
}

static const char *write_bytes(char path[PATH_BYTES], const char *name, const void *data, size_t len)
{
    scratch_path(path, name);
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f, "cannot create %s", path);
    cr_assert_eq(fwrite(data, 1, len, f), len);
    cr_assert_eq(fclose(f), 0);
    return path;
}

static const char *write_text(char path[PATH_BYTES], const char *name, const char *text)
{
    return write_bytes(path, name, text, strlen(text));
}

enum ply_format { ASCII, BINARY_LE, BINARY_BE };
static const char *const format_names[] = {"ascii", "binary_little_endian", "binary_big_endian"};

/* PLY scalar types by name: size in bytes and whether it is a float type. */
static const struct scalar_type {
    const char *name; /* as written in a header */
    unsigned size;    /* bytes in binary */
    bool is_float;    /* float or double */
} scalar_types[] = {
    {"char", 1, false},   {"uchar", 1, false},  {"short", 2, false},  {"ushort", 2, false},
    {"int", 4, false},    {"uint", 4, false},   {"float", 4, true},   {"double", 8, true},
    {"int8", 1, false},   {"uint8", 1, false},  {"int16", 2, false},  {"uint16", 2, false},
    {"int32", 4, false},  {"uint32", 4, false}, {"float32", 4, true}, {"float64", 8, true},
};

static const struct scalar_type *scalar_type(const char *name)
{
    for (size_t i = 0; i < sizeof scalar_types / sizeof scalar_types[0]; i++)
        if (strcmp(scalar_types[i].name, name) == 0)
            return &scalar_types[i];
    cr_assert_fail("test bug: unknown type %s", name);
    return NULL;
}

/* One value of `type` in the body: ascii text, or its bytes in the file's order. */
static void put_value(bytes *b, enum ply_format format, const char *type, double v)
{
    const struct scalar_type *t = scalar_type(type);
    if (format == ASCII) {
        if (!t->is_float)
            put_text(b, "%lld ", (long long)v);
        else if (t->size == 4)
            put_text(b, "%.9g ", (double)(float)v);
        else
            put_text(b, "%.17g ", v);
        return;
    }
    bool big = format == BINARY_BE;
    if (t->is_float && t->size == 4) {
        float f = (float)v;
        uint32_t bits;
        memcpy(&bits, &f, sizeof bits); /* the IEEE bit pattern; its byte order is put_uint's job */
        put_uint(b, bits, 4, big);
    } else if (t->is_float) {
        uint64_t bits;
        memcpy(&bits, &v, sizeof bits);
        put_uint(b, bits, 8, big);
    } else {
        put_uint(b, (uint64_t)(int64_t)v, t->size, big); /* two's complement, cut to size */
    }
}

static void end_record(bytes *b, enum ply_format format, bool crlf)
{
    if (format == ASCII)
        put_text(b, crlf ? "\r\n" : "\n");
}

/* ---- the cube ---------------------------------------------------------- */

static const double cube_positions[8][3] = {
    {-1.5, -0.25, -2}, {1.5, -0.25, -2}, {1.5, 0.75, -2}, {-1.5, 0.75, -2},
    {-1.5, -0.25, 2},  {1.5, -0.25, 2},  {1.5, 0.75, 2},  {-1.5, 0.75, 2},
};
static const unsigned cube_quads[6][4] = {
    {0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}, {0, 4, 7, 3},
};

static float cube_normal(unsigned v, int k)
{
    const double *p = cube_positions[v];
    return (float)(p[k] / sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
}

static double cube_color(unsigned v, int k, bool is_float)
{
    static const unsigned char rgb[8][3] = {{255, 0, 0},     {0, 255, 0},   {0, 0, 255},  {10, 20, 30},
                                            {200, 100, 50},  {1, 2, 3},     {128, 64, 32}, {77, 154, 231}};
    return is_float ? rgb[v][k] / 256.0 : rgb[v][k];
}

/* What a test cube file contains besides positions and quads. */
typedef struct ply_spec {
    enum ply_format format; /* body encoding */
    const char *coord_type; /* type of x, y, z */
    const char *count_type; /* type of the vertex_indices length */
    const char *index_type; /* type of each vertex index */
    bool normals;           /* nx ny nz (float) */
    const char *color_type; /* type of red green blue, NULL for no colours */
    bool extras;            /* properties and elements the loader must read past */
    bool crlf;              /* header (and ascii body) lines end in "\r\n" */
} ply_spec;

static ply_spec cube_spec(enum ply_format format)
{
    return (ply_spec){.format = format, .coord_type = "float", .count_type = "uchar", .index_type = "int"};
}

static void put_header_line(bytes *b, const ply_spec *s, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void put_header_line(bytes *b, const ply_spec *s, const char *fmt, ...)
{
    char text[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    put_text(b, "%s%s", text, s->crlf ? "\r\n" : "\n");
}

static void put_cube_header(bytes *b, const ply_spec *s)
{
    put_header_line(b, s, "ply");
    put_header_line(b, s, "format %s 1.0", format_names[s->format]);
    put_header_line(b, s, "comment written by test_mesh_load.c");
    if (s->extras) {
        put_header_line(b, s, "obj_info an extra element before the vertices");
        put_header_line(b, s, "element material 2");
        put_header_line(b, s, "property uchar shininess");
        put_header_line(b, s, "property list uchar float params");
    }
    put_header_line(b, s, "element vertex 8");
    if (s->extras)
        put_header_line(b, s, "property short flag");
    put_header_line(b, s, "property %s x", s->coord_type);
    put_header_line(b, s, "property %s y", s->coord_type);
    put_header_line(b, s, "property %s z", s->coord_type);
    if (s->extras)
        put_header_line(b, s, "property list uchar int neighbours");
    if (s->normals)
        for (int k = 0; k < 3; k++)
            put_header_line(b, s, "property float n%c", "xyz"[k]);
    if (s->color_type) {
        put_header_line(b, s, "property %s red", s->color_type);
        put_header_line(b, s, "property %s green", s->color_type);
        put_header_line(b, s, "property %s blue", s->color_type);
    }
    if (s->extras)
        put_header_line(b, s, "property double confidence");
    put_header_line(b, s, "element face 6");
    if (s->extras)
        put_header_line(b, s, "property uchar visible");
    put_header_line(b, s, "property list %s %s vertex_indices", s->count_type, s->index_type);
    if (s->extras) {
        put_header_line(b, s, "property float quality");
        put_header_line(b, s, "element edge 3");
        put_header_line(b, s, "property int vertex1");
        put_header_line(b, s, "property int vertex2");
    }
    put_header_line(b, s, "end_header");
}

static void put_cube_vertex(bytes *b, const ply_spec *s, unsigned v)
{
    enum ply_format f = s->format;
    if (s->extras)
        put_value(b, f, "short", -300.0 * v);
    for (int k = 0; k < 3; k++)
        put_value(b, f, s->coord_type, cube_positions[v][k]);
    if (s->extras) {
        put_value(b, f, "uchar", v % 3);
        for (unsigned i = 0; i < v % 3; i++)
            put_value(b, f, "int", 1000 + i);
    }
    if (s->normals)
        for (int k = 0; k < 3; k++)
            put_value(b, f, "float", cube_normal(v, k));
    if (s->color_type)
        for (int k = 0; k < 3; k++)
            put_value(b, f, s->color_type, cube_color(v, k, scalar_type(s->color_type)->is_float));
    if (s->extras)
        put_value(b, f, "double", 0.125 * v);
    end_record(b, f, s->crlf);
}

/* The cube as a PLY file; *header_len (if given) gets the header's size. */
static bytes cube_bytes(const ply_spec *s, size_t *header_len)
{
    bytes b = {0};
    enum ply_format f = s->format;
    put_cube_header(&b, s);
    if (header_len)
        *header_len = b.len;
    for (unsigned i = 0; s->extras && i < 2; i++) { /* material */
        put_value(&b, f, "uchar", 7 + i);
        put_value(&b, f, "uchar", i + 1);
        for (unsigned k = 0; k <= i; k++)
            put_value(&b, f, "float", 0.5 * k);
        end_record(&b, f, s->crlf);
    }
    for (unsigned v = 0; v < 8; v++)
        put_cube_vertex(&b, s, v);
    for (unsigned q = 0; q < 6; q++) {
        if (s->extras)
            put_value(&b, f, "uchar", 1);
        put_value(&b, f, s->count_type, 4);
        for (int k = 0; k < 4; k++)
            put_value(&b, f, s->index_type, cube_quads[q][k]);
        if (s->extras)
            put_value(&b, f, "float", 0.25 * q);
        end_record(&b, f, s->crlf);
    }
    for (unsigned e = 0; s->extras && e < 3; e++) { /* edge */
        put_value(&b, f, "int", e);
        put_value(&b, f, "int", e + 1);
        end_record(&b, f, s->crlf);
    }
    return b;
}

static const char *write_cube(char path[PATH_BYTES], const char *name, const ply_spec *s)
{
    bytes b = cube_bytes(s, NULL);
    write_bytes(path, name, b.data, b.len);
    free(b.data);
    return path;
}

/* ---- checking results -------------------------------------------------- */

static mesh *load_ok(mesh *(*load)(const char *, tess_error *), const char *path)
{
    tess_error err = {{0}};
    mesh *m = load(path, &err);
    cr_assert_not_null(m, "%s did not load: %s", path, err.msg);
    cr_assert_str_empty(err.msg, "a loaded mesh left a message: %s", err.msg);
    return m;
}

/* The cube's positions and the fan-split quads, exactly. */
static void assert_cube(const mesh *m, const char *what)
{
    cr_assert_eq(m->vertex_count, 8, "%s: %u vertices", what, m->vertex_count);
    cr_assert_eq(m->triangle_count, 12, "%s: %u triangles", what, m->triangle_count);
    for (unsigned v = 0; v < 8; v++)
        for (int k = 0; k < 3; k++)
            cr_assert_eq(m->positions[3 * v + k], (float)cube_positions[v][k], "%s: vertex %u axis %d", what, v, k);
    for (unsigned q = 0; q < 6; q++) {
        const unsigned *c = cube_quads[q];
        const unsigned want[6] = {c[0], c[1], c[2], c[0], c[2], c[3]};
        for (int i = 0; i < 6; i++)
            cr_assert_eq(m->indices[6 * q + i], want[i], "%s: quad %u corner %d", what, q, i);
    }
    cr_assert_null(m->triangle_material, "%s", what);
    cr_assert_eq(m->material_count, 0, "%s", what);
}

/* The loader fails, and the message names the path and every one of words. */
static void check_error(mesh *(*load)(const char *, tess_error *), const char *path, const char *const words[])
{
    tess_error err = {{0}};
    mesh *m = load(path, &err);
    if (m)
        mesh_destroy(m);
    cr_assert_null(m, "%s loaded; expected an error", path);
    cr_assert(strstr(err.msg, path) != NULL, "message lacks the path %s: %s", path, err.msg);
    cr_assert(strchr(err.msg, '\n') == NULL, "message is not one line: %s", err.msg);
    for (size_t i = 0; words[i]; i++)
        cr_assert(strstr(err.msg, words[i]) != NULL, "message lacks '%s': %s", words[i], err.msg);
}

#define expect_error(load, path, ...) check_error(load, path, (const char *const[]){__VA_ARGS__, NULL})

/* "PATH:LINE:" for a message that must cite a line */
static const char *at_line(char out[PATH_BYTES + 32], const char *path, int line)
{
    snprintf(out, PATH_BYTES + 32, "%s:%d:", path, line);
    return out;
}

/* ---- PLY: what loads --------------------------------------------------- */

Test(mesh_load, cube_in_all_three_formats_is_identical)
{
    mesh *m[3];
    for (int f = 0; f < 3; f++) {
        char path[PATH_BYTES], name[32];
        snprintf(name, sizeof name, "cube_%s.ply", format_names[f]);
        ply_spec s = cube_spec((enum ply_format)f);
        m[f] = load_ok(mesh_load_ply, write_cube(path, name, &s));
        assert_cube(m[f], format_names[f]);
        cr_assert_null(m[f]->normals, "no nx ny nz in the file, so no normals");
        cr_assert_null(m[f]->colors, "no red green blue in the file, so no colours");
    }
    for (int f = 1; f < 3; f++) {
        cr_assert(memcmp(m[0]->positions, m[f]->positions, 8 * 3 * sizeof(float)) == 0);
        cr_assert(memcmp(m[0]->indices, m[f]->indices, 12 * 3 * sizeof(uint32_t)) == 0);
    }
    for (int f = 0; f < 3; f++)
        mesh_destroy(m[f]);
}

Test(mesh_load, every_integer_index_type)
{
    static const char *const types[][2] = {
        {"uchar", "int"},   {"uchar", "uint"},   {"uchar", "short"},  {"uchar", "uchar"},  {"uchar", "ushort"},
        {"char", "int"},    {"int", "int"},      {"uint", "uint32"},  {"short", "int16"},  {"uint8", "uint16"},
        {"int32", "int8"},  {"ushort", "int32"},
    };
    for (size_t t = 0; t < sizeof types / sizeof types[0]; t++)
        for (int f = 0; f < 3; f++) {
            char path[PATH_BYTES], what[96];
            ply_spec s = cube_spec((enum ply_format)f);
            s.count_type = types[t][0];
            s.index_type = types[t][1];
            snprintf(what, sizeof what, "list %s %s, %s", s.count_type, s.index_type, format_names[f]);
            mesh *m = load_ok(mesh_load_ply, write_cube(path, "cube.ply", &s));
            assert_cube(m, what);
            mesh_destroy(m);
        }
}

Test(mesh_load, double_and_integer_coordinates)
{
    for (int f = 0; f < 3; f++) {
        char path[PATH_BYTES];
        ply_spec s = cube_spec((enum ply_format)f);
        s.coord_type = f == 2 ? "float64" : "double";
        mesh *m = load_ok(mesh_load_ply, write_cube(path, "cube.ply", &s));
        assert_cube(m, format_names[f]);
        mesh_destroy(m);
    }
    /* integer coordinates (a voxel grid): any numeric type serves */
    char path[PATH_BYTES];
    const char *text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty short x\nproperty int y\n"
                       "property uchar z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                       "-5 70000 255\n1 2 3\n0 0 0\n3 0 1 2\n";
    mesh *m = load_ok(mesh_load_ply, write_text(path, "grid.ply", text));
    cr_assert_eq(m->positions[0], -5.f);
    cr_assert_eq(m->positions[1], 70000.f);
    cr_assert_eq(m->positions[2], 255.f);
    mesh_destroy(m);
}

Test(mesh_load, normals_and_uchar_colors)
{
    for (int f = 0; f < 3; f++) {
        char path[PATH_BYTES];
        ply_spec s = cube_spec((enum ply_format)f);
        s.normals = true;
        s.color_type = "uchar";
        mesh *m = load_ok(mesh_load_ply, write_cube(path, "cube.ply", &s));
        assert_cube(m, format_names[f]);
        cr_assert_not_null(m->normals);
        cr_assert_not_null(m->colors);
        for (unsigned v = 0; v < 8; v++)
            for (int k = 0; k < 3; k++) {
                cr_assert_eq(m->normals[3 * v + k], cube_normal(v, k), "%s: normal %u", format_names[f], v);
                float want = (float)cube_color(v, k, false) / 255.f;
                cr_assert_eq(m->colors[3 * v + k], want, "%s: colour %u.%d", format_names[f], v, k);
            }
        mesh_destroy(m);
    }
}

Test(mesh_load, float_colors_without_normals)
{
    for (int f = 0; f < 3; f++) {
        char path[PATH_BYTES];
        ply_spec s = cube_spec((enum ply_format)f);
        s.color_type = "float";
        mesh *m = load_ok(mesh_load_ply, write_cube(path, "cube.ply", &s));
        assert_cube(m, format_names[f]);
        cr_assert_null(m->normals);
        cr_assert_not_null(m->colors);
        for (unsigned v = 0; v < 8; v++)
            for (int k = 0; k < 3; k++)
                cr_assert_eq(m->colors[3 * v + k], (float)cube_color(v, k, true), "%s", format_names[f]);
        mesh_destroy(m);
    }
}

Test(mesh_load, partial_attribute_groups_are_ignored)
{
    char path[PATH_BYTES];
    const char *text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nproperty float nx\nproperty float ny\nproperty uchar red\n"
                       "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                       "0 0 0 1 0 9\n1 0 0 1 0 9\n0 1 0 1 0 9\n3 0 1 2\n";
    mesh *m = load_ok(mesh_load_ply, write_text(path, "partial.ply", text));
    cr_assert_null(m->normals, "nx ny without nz: no normals");
    cr_assert_null(m->colors, "red without green and blue: no colours");
    cr_assert_eq(m->positions[3], 1.f);
    cr_assert_eq(m->triangle_count, 1);
    mesh_destroy(m);
}

Test(mesh_load, extra_properties_and_elements_are_skipped)
{
    for (int f = 0; f < 3; f++) {
        char path[PATH_BYTES];
        ply_spec s = cube_spec((enum ply_format)f);
        s.extras = true;
        s.normals = true;
        s.color_type = "uchar";
        mesh *m = load_ok(mesh_load_ply, write_cube(path, "cube_extras.ply", &s));
        assert_cube(m, format_names[f]);
        for (unsigned v = 0; v < 8; v++)
            cr_assert_eq(m->normals[3 * v + 2], cube_normal(v, 2), "%s", format_names[f]);
        cr_assert_eq(m->colors[3 * 7 + 2], 231.f / 255.f, "%s", format_names[f]);
        mesh_destroy(m);
    }
}

/* a pentagon (and, binary, with a hexagon too) */
static bytes polygon_file(enum ply_format f)
{
    bytes b = {0};
    put_text(&b, "ply\nformat %s 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 2\nproperty list uchar uint vertex_indices\nend_header\n",
             format_names[f]);
    for (unsigned v = 0; v < 6; v++) {
        put_value(&b, f, "float", cos(v));
        put_value(&b, f, "float", sin(v));
        put_value(&b, f, "float", 0);
        end_record(&b, f, false);
    }
    const unsigned polygons[2][7] = {{5, 0, 1, 2, 3, 4}, {6, 5, 4, 3, 2, 1, 0}};
    for (int p = 0; p < 2; p++) {
        for (unsigned k = 0; k <= polygons[p][0]; k++)
            put_value(&b, f, k == 0 ? "uchar" : "uint", polygons[p][k]);
        end_record(&b, f, false);
    }
    return b;
}

Test(mesh_load, polygons_are_fan_split)
{
    const uint32_t want[7][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {5, 4, 3}, {5, 3, 2}, {5, 2, 1}, {5, 1, 0}};
    for (int f = 0; f < 3; f++) {
        char path[PATH_BYTES];
        bytes b = polygon_file((enum ply_format)f);
        mesh *m = load_ok(mesh_load_ply, write_bytes(path, "polygons.ply", b.data, b.len));
        free(b.data);
        cr_assert_eq(m->triangle_count, 7, "5-gon -> 3 triangles, 6-gon -> 4");
        for (int t = 0; t < 7; t++)
            for (int k = 0; k < 3; k++)
                cr_assert_eq(m->indices[3 * t + k], want[t][k], "%s: triangle %d", format_names[f], t);
        mesh_destroy(m);
    }
}

Test(mesh_load, vertices_without_faces_load_as_points)
{
    char path[PATH_BYTES];
    const char *text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nend_header\n1 2 3\n4 5 6\n7 8 9\n";
    mesh *m = load_ok(mesh_load_ply, write_text(path, "points.ply", text));
    cr_assert_eq(m->vertex_count, 3);
    cr_assert_eq(m->triangle_count, 0);
    cr_assert_eq(m->positions[8], 9.f);
    mesh_destroy(m);

    bytes b = {0};
    put_text(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
                 "property double z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n");
    for (int i = 0; i < 6; i++)
        put_value(&b, BINARY_BE, "double", i + 0.5);
    m = load_ok(mesh_load_ply, write_bytes(path, "points_be.ply", b.data, b.len));
    free(b.data);
    cr_assert_eq(m->vertex_count, 2);
    cr_assert_eq(m->triangle_count, 0);
    cr_assert_eq(m->positions[5], 5.5f);
    mesh_destroy(m);
}

Test(mesh_load, crlf_line_endings)
{
    for (int f = 0; f < 3; f++) {
        char path[PATH_BYTES];
        ply_spec s = cube_spec((enum ply_format)f);
        s.crlf = true;
        s.extras = true;
        mesh *m = load_ok(mesh_load_ply, write_cube(path, "cube_crlf.ply", &s));
        assert_cube(m, format_names[f]);
        mesh_destroy(m);
    }
}

/* also: the face list may be called vertex_index */
Test(mesh_load, faces_may_come_before_vertices)
{
    char path[PATH_BYTES];
    const char *text = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_index\n"
                       "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
                       "3 2 1 0\n0 0 0\n1 0 0\n0 1 0\n";
    mesh *m = load_ok(mesh_load_ply, write_text(path, "faces_first.ply", text));
    cr_assert_eq(m->triangle_count, 1);
    cr_assert_eq(m->indices[0], 2);
    cr_assert_eq(m->positions[7], 1.f);
    mesh_destroy(m);
}

/* ---- PLY: what fails, and how it says so -------------------------------- */

Test(mesh_load, missing_file)
{
    char path[PATH_BYTES];
    expect_error(mesh_load_ply, scratch_path(path, "nowhere.ply"), "cannot open", "No such file");
}

Test(mesh_load, not_a_ply)
{
    char path[PATH_BYTES];
    expect_error(mesh_load_ply, write_text(path, "text.ply", "solid cube\nfacet normal 0 0 1\n"), "not a PLY file",
                 "'ply' magic");
    expect_error(mesh_load_ply, write_text(path, "empty.ply", ""), "not a PLY file");
}

Test(mesh_load, truncated_binary_files)
{
    for (int f = BINARY_LE; f <= BINARY_BE; f++) {
        char path[PATH_BYTES];
        ply_spec s = cube_spec((enum ply_format)f);
        size_t header;
        bytes b = cube_bytes(&s, &header);
        /* in the vertex block: 3 whole vertices (12 bytes each) and 5 bytes of the 4th */
        write_bytes(path, "cut_vertices.ply", b.data, header + 3 * 12 + 5);
        expect_error(mesh_load_ply, path, "truncated", "expected 8 vertices", "vertex 3");
        /* in the face block: 2 whole quads (1 + 4 * 4 bytes each) and 3 bytes of the 3rd */
        write_bytes(path, "cut_faces.ply", b.data, header + 8 * 12 + 2 * 17 + 3);
        expect_error(mesh_load_ply, path, "truncated", "expected 6 faces", "face 2");
        /* just the header */
        write_bytes(path, "cut_header.ply", b.data, header);
        expect_error(mesh_load_ply, path, "truncated", "vertex 0");
        free(b.data);
    }
}

Test(mesh_load, truncated_ascii_file)
{
    char path[PATH_BYTES];
    const char *text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                       "0 0 0\n1 0 0\n";
    expect_error(mesh_load_ply, write_text(path, "cut.ply", text), "truncated", "expected 3 vertices", "vertex 2");
}

Test(mesh_load, truncated_skipped_element)
{
    char path[PATH_BYTES];
    bytes b = {0};
    put_text(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nelement edge 5\nproperty int a\nproperty int b\nend_header\n");
    for (int i = 0; i < 3 + 2 * 2 + 1; i++) /* one vertex, two whole edges, half a third */
        put_value(&b, BINARY_LE, i < 3 ? "float" : "int", i);
    expect_error(mesh_load_ply, write_bytes(path, "cut_edges.ply", b.data, b.len), "truncated", "edge 2");
    free(b.data);
}

/* A triangle file: 4 vertices, the faces given as ascii lines. */
static const char *write_ascii_faces(char path[PATH_BYTES], const char *name, int faces, const char *face_lines)
{
    char text[1024];
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
             "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n1 1 0\n%s",
             faces, face_lines);
    return write_text(path, name, text);
}

Test(mesh_load, face_index_out_of_range)
{
    char path[PATH_BYTES], line[PATH_BYTES + 32];
    /* line 10 is the first vertex, line 14 the first face */
    write_ascii_faces(path, "oob.ply", 2, "3 0 1 2\n3 1 3 99\n");
    expect_error(mesh_load_ply, path, at_line(line, path, 15), "face 1", "vertex index 99 out of range",
                 "file has 4 vertices");
    write_ascii_faces(path, "oob4.ply", 1, "3 0 1 4\n");
    expect_error(mesh_load_ply, path, at_line(line, path, 14), "face 0", "vertex index 4 out of range");

    for (int f = BINARY_LE; f <= BINARY_BE; f++) {
        bytes b = {0};
        put_text(&b, "ply\nformat %s 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 3\nproperty list uchar uint vertex_indices\nend_header\n",
                 format_names[f]);
        for (int i = 0; i < 9; i++)
            put_value(&b, (enum ply_format)f, "float", i);
        const unsigned faces[3][3] = {{0, 1, 2}, {2, 1, 0}, {0, 1, 70000}};
        for (int t = 0; t < 3; t++) {
            put_value(&b, (enum ply_format)f, "uchar", 3);
            for (int k = 0; k < 3; k++)
                put_value(&b, (enum ply_format)f, "uint", faces[t][k]);
        }
        write_bytes(path, "oob.ply", b.data, b.len);
        free(b.data);
        expect_error(mesh_load_ply, path, "face 2", "vertex index 70000 out of range", "file has 3 vertices");
    }
}

Test(mesh_load, negative_index)
{
    char path[PATH_BYTES], line[PATH_BYTES + 32];
    write_ascii_faces(path, "neg.ply", 1, "3 0 -1 2\n");
    expect_error(mesh_load_ply, path, at_line(line, path, 14), "face 0", "negative vertex index -1");

    bytes b = {0};
    put_text(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1\nproperty list uchar short vertex_indices\nend_header\n");
    for (int i = 0; i < 9; i++)
        put_value(&b, BINARY_BE, "float", i);
    put_value(&b, BINARY_BE, "uchar", 3);
    put_value(&b, BINARY_BE, "short", 0);
    put_value(&b, BINARY_BE, "short", 1);
    put_value(&b, BINARY_BE, "short", -2);
    write_bytes(path, "neg_be.ply", b.data, b.len);
    free(b.data);
    expect_error(mesh_load_ply, path, "face 0", "negative vertex index -2");
}

Test(mesh_load, non_numeric_and_missing_values)
{
    char path[PATH_BYTES], line[PATH_BYTES + 32];
    const char *head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nend_header\n";
    char text[512];
    snprintf(text, sizeof text, "%s0 0 0\n1 0 0\n0 abc 0\n", head);
    write_text(path, "abc.ply", text);
    expect_error(mesh_load_ply, path, at_line(line, path, 10), "vertex 2",
                 "expected a number for 'y', got 'abc'");
    snprintf(text, sizeof text, "%s0 0 0\n1 0\n0 1 0\n", head);
    write_text(path, "short_line.ply", text);
    expect_error(mesh_load_ply, path, at_line(line, path, 9), "vertex 1",
                 "'z'", "end of line");
    snprintf(text, sizeof text, "%s0 0 0\n1 0 0 5\n0 1 0\n", head);
    write_text(path, "long_line.ply", text);
    expect_error(mesh_load_ply, path, at_line(line, path, 9), "vertex 1",
                 "unexpected extra value '5'");
    snprintf(text, sizeof text, "%s0 0 0\n1 2e 0\n0 1 0\n", head);
    expect_error(mesh_load_ply, write_text(path, "bad_exponent.ply", text), "vertex 1", "got '2e'");
    write_ascii_faces(path, "bad_count.ply", 1, "x 0 1 2\n");
    expect_error(mesh_load_ply, path, at_line(line, path, 14), "face 0", "expected an integer", "got 'x'");
    write_ascii_faces(path, "float_index.ply", 1, "3 0 1.5 2\n");
    expect_error(mesh_load_ply, path, "face 0", "expected an integer", "got '1.5'");
}

Test(mesh_load, nan_and_inf_coordinates)
{
    const char *head = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                       "property double z\nend_header\n0 0 0\n1 1 1\n2 2 2\n";
    static const char *const cases[][3] = {
        {"3 nan 3\n", "'y' is nan", "nan.ply"},
        {"3 3 inf\n", "'z' is inf", "inf.ply"},
        {"-inf 3 3\n", "'x' is -inf", "neg_inf.ply"},
        {"3 1e39 3\n", "'y' is inf", "float_overflow.ply"},
        {"3 3 1e999\n", "'z' is inf", "double_overflow.ply"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[PATH_BYTES], line[PATH_BYTES + 32], text[512];
        snprintf(text, sizeof text, "%s%s", head, cases[i][0]);
        write_text(path, cases[i][2], text);
        expect_error(mesh_load_ply, path, at_line(line, path, 11), "vertex 3",
                     cases[i][1], "must be finite");
    }
    for (int f = BINARY_LE; f <= BINARY_BE; f++) {
        char path[PATH_BYTES];
        bytes b = {0};
        put_text(&b, "ply\nformat %s 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n",
                 format_names[f]);
        for (int i = 0; i < 15; i++)
            put_value(&b, (enum ply_format)f, "float", i == 3 * 3 + 1 ? NAN : i);
        write_bytes(path, "nan.ply", b.data, b.len);
        free(b.data);
        expect_error(mesh_load_ply, path, "vertex 3", "'y' is", "nan", "must be finite");
    }
}

Test(mesh_load, face_with_two_vertices)
{
    char path[PATH_BYTES], line[PATH_BYTES + 32];
    write_ascii_faces(path, "two.ply", 2, "3 0 1 2\n2 0 1\n");
    expect_error(mesh_load_ply, path, at_line(line, path, 15), "face 1", "has 2 vertices", "at least 3");

    bytes b = {0};
    put_text(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1\nproperty list char int vertex_indices\nend_header\n");
    for (int i = 0; i < 9; i++)
        put_value(&b, BINARY_LE, "float", i);
    put_value(&b, BINARY_LE, "char", -1);
    write_bytes(path, "minus_one.ply", b.data, b.len);
    free(b.data);
    expect_error(mesh_load_ply, path, "face 0", "has -1 vertices");
}

/* A binary little-endian file of `header` and `data` must fail, naming `word`,
 * at a cost that follows the file's few bytes, not the absurd counts it claims
 * (4e9 vertices, 2^64 - 1 elements): a loader that trusts them allocates or
 * loops for minutes, a sound one takes milliseconds. The bound is 10 s of
 * this process's CPU time, so neither a loaded machine nor a slow one (TCG,
 * sanitizers) can make a sound loader fail it. Frees data. */
static void expect_fast_failure(const char *header, bytes *data, const char *word)
{
    char path[PATH_BYTES];
    bytes b = {0};
    put_text(&b, "ply\nformat binary_little_endian 1.0\n%send_header\n", header);
    put_bytes(&b, data->data, data->len);
    write_bytes(path, "absurd.ply", b.data, b.len);
    free(b.data);
    free(data->data);
    struct timespec t0, t1;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
    expect_error(mesh_load_ply, path, "truncated", word);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
    double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    cr_assert_lt(seconds, 10.0, "%s: took %.3f s of CPU", header, seconds);
}

/* n copies of a value */
static void put_values(bytes *b, const char *type, double v, int n)
{
    for (int i = 0; i < n; i++)
        put_value(b, BINARY_LE, type, v);
}

#define XYZ "property float x\nproperty float y\nproperty float z\n"
#define FACES(count, list) "element face " count "\nproperty list " list " vertex_indices\n"

/* A header claiming far more than the file holds must fail at once, without
 * allocating for the claim (4e9 vertices would take 48 GB). */
Test(mesh_load, absurd_counts_fail_fast, .timeout = 10)
{
    bytes d = {0};
    put_values(&d, "float", 0, 25); /* 100 bytes: 8 vertices and a third */
    expect_fast_failure("element vertex 4000000000\n" XYZ, &d, "expected 4000000000 vertices, file ends in vertex 8");

    d = (bytes){0};
    put_values(&d, "float", 0, 9);
    for (int f = 0; f < 5; f++) { /* 4 triangles and part of a 5th */
        put_value(&d, BINARY_LE, "uchar", 3);
        put_values(&d, "int", 0, f < 4 ? 3 : 1);
    }
    expect_fast_failure("element vertex 3\n" XYZ FACES("4294967295", "uchar int"), &d, "face 4");

    d = (bytes){0};
    put_values(&d, "float", 0, 9);
    put_value(&d, BINARY_LE, "uint", 4294967295.0); /* a polygon of 2^32 - 1 corners */
    put_values(&d, "int", 0, 15);
    expect_fast_failure("element vertex 3\n" XYZ FACES("1", "uint int"), &d, "expected 1 face, file ends in face 0");

    d = (bytes){0};
    put_values(&d, "uchar", 0, 100);
    expect_fast_failure("element junk 18446744073709551615\nproperty uchar a\nelement vertex 1\n" XYZ, &d,
                        "junk 100");

    d = (bytes){0};
    put_values(&d, "float", 0, 3);
    put_value(&d, BINARY_LE, "uint", 4294967295.0); /* a list of 2^32 - 1 bytes */
    put_values(&d, "uchar", 0, 84);
    expect_fast_failure("element vertex 1\n" XYZ "element junk 18446744073709551615\nproperty list uint uchar a\n",
                        &d, "junk 0");

    char path[PATH_BYTES];
    const char *beyond = "ply\nformat ascii 1.0\nelement vertex 99999999999\n" XYZ "end_header\n0 0 0\n";
    expect_error(mesh_load_ply, write_text(path, "beyond.ply", beyond), "99999999999 vertices",
                 "more than a mesh can hold");
}

Test(mesh_load, header_errors_cite_their_line)
{
    static const struct {
        const char *text;  /* the file */
        int line;          /* the line to blame */
        const char *words; /* what the message must say */
    } cases[] = {
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float16 y\n", 5,
         "unknown property type 'float16'"},
        {"ply\nformat binary_middle_endian 1.0\n", 2, "unknown format 'binary_middle_endian'"},
        {"ply\nformat ascii 2.0\n", 2, "unsupported PLY version '2.0'"},
        {"ply\nformat ascii 1.0\nproperty float x\n", 3, "'property' before any 'element'"},
        {"ply\nformat ascii 1.0\nelement vertex -3\n", 3, "bad count '-3'"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\n", 4, "must be an integer type"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float\n", 4, "expected 'property <type> <name>'"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\n", 5,
         "two 'x' properties"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nelement face 0\n"
         "property list uchar float vertex_indices\n",
         5, "must be a list of integers"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nelement vertex 1\n", 4, "second 'vertex' element"},
        {"ply\nformat ascii 1.0\nbanana\n", 3, "unknown header keyword 'banana'"},
        {"ply\nformat ascii 1.0\ncomment\nelement vertex 1\nproperty float x\n", 6, "no 'end_header'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[PATH_BYTES], line[PATH_BYTES + 32], name[32];
        snprintf(name, sizeof name, "header%zu.ply", i);
        write_text(path, name, cases[i].text);
        expect_error(mesh_load_ply, path, at_line(line, path, cases[i].line), cases[i].words);
    }
}

/* Found by fuzzing (tests/fuzz/corpus/ply/crash-control-char): a token with a
 * control character was quoted into the message as it was; messages stay one
 * printable line, the character shown as '?'. */
Test(mesh_load, control_characters_in_quoted_tokens)
{
    char path[PATH_BYTES], line[PATH_BYTES + 32];
    write_text(path, "ctrl.ply", "ply\nformat ascii 1.0\nelement vertex 1\np\x1aroperty float x\n");
    expect_error(mesh_load_ply, path, at_line(line, path, 4), "unknown header keyword 'p?roperty'");
    write_text(path, "esc.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                "property float z\nend_header\n0 \x1b[2J 0\n");
    expect_error(mesh_load_ply, path, at_line(line, path, 8), "got '?[2J'");
    write_text(path, "ctrl.obj", "v 0 0 0\nv 1 \x1b[2J 0\nv 0 1 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "got '?[2J'");
}

Test(mesh_load, missing_required_parts)
{
    char path[PATH_BYTES];
    const char *no_x = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\n"
                       "end_header\n0 0\n";
    expect_error(mesh_load_ply, write_text(path, "no_x.ply", no_x), "no 'x' property");
    const char *no_vertex = "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\n"
                            "end_header\n";
    expect_error(mesh_load_ply, write_text(path, "no_vertex.ply", no_vertex), "no 'vertex' element");
    const char *no_format = "ply\nelement vertex 0\nproperty float x\nend_header\n";
    expect_error(mesh_load_ply, write_text(path, "no_format.ply", no_format), "no 'format' line");
    const char *no_indices = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int corners\n"
                             "end_header\n0 0 0\n3 0 0 0\n";
    expect_error(mesh_load_ply, write_text(path, "no_indices.ply", no_indices), "no 'vertex_indices' list");
}

/* ---- assimp ------------------------------------------------------------ */

static float triangle_area(const mesh *m, uint32_t t)
{
    const float *a = m->positions + 3 * m->indices[3 * t], *b = m->positions + 3 * m->indices[3 * t + 1],
                *c = m->positions + 3 * m->indices[3 * t + 2];
    float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return 0.5f * sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

Test(mesh_load, obj_with_two_mtl_materials)
{
    char path[PATH_BYTES];
    write_text(path, "two.mtl",
               "newmtl red\nKd 1 0 0\n\nnewmtl unused\nKd 0 1 0\n\nnewmtl blue\nKd 0 0 0.5\n");
    write_text(path, "two.obj",
               "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
               "usemtl red\nf 1 2 3\nusemtl blue\nf 2 4 3\n");
    mesh *m = load_ok(mesh_load_assimp, path);
    cr_assert_eq(m->triangle_count, 2);
    cr_assert_eq(m->material_count, 2, "the unused material is dropped: %u", m->material_count);
    cr_assert_not_null(m->triangle_material);
    for (uint32_t t = 0; t < 2; t++) {
        /* which face is it? the red one lies below the diagonal x + y = 1 */
        float cx = 0, cy = 0;
        for (int k = 0; k < 3; k++) {
            cx += m->positions[3 * m->indices[3 * t + k]] / 3;
            cy += m->positions[3 * m->indices[3 * t + k] + 1] / 3;
        }
        bool red = cx + cy < 1;
        const mesh_material *mat = &m->materials[m->triangle_material[t]];
        cr_assert_str_eq(mat->name, red ? "red" : "blue");
        const float want[3] = {red ? 1.f : 0.f, 0.f, red ? 0.f : 0.5f};
        for (int k = 0; k < 3; k++)
            cr_assert_float_eq(mat->diffuse_rgb[k], want[k], 1e-6f, "%s Kd[%d]", mat->name, k);
    }
    mesh_destroy(m);
}

Test(mesh_load, obj_quad_is_triangulated)
{
    char path[PATH_BYTES];
    write_text(path, "quad.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n");
    mesh *m = load_ok(mesh_load_assimp, path);
    cr_assert_eq(m->triangle_count, 2);
    cr_assert_eq(m->vertex_count, 4, "identical corners are joined");
    cr_assert_float_eq(triangle_area(m, 0) + triangle_area(m, 1), 2.f, 1e-6f);
    cr_assert_not_null(m->normals, "the file has normals");
    cr_assert_eq(m->normals[2], 1.f);
    cr_assert_null(m->triangle_material, "no MTL: no materials");
    cr_assert_null(m->colors);
    mesh_destroy(m);

    write_text(path, "no_normals.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nf 1 2 3\n");
    m = load_ok(mesh_load_assimp, path);
    cr_assert_null(m->normals, "normals are never invented");
    mesh_destroy(m);
}

Test(mesh_load, obj_errors)
{
    char path[PATH_BYTES], line[PATH_BYTES + 32];
    write_text(path, "oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 4), "vertex index 9 out of range (the file has 3 vertices)");
    /* found by fuzzing (tests/fuzz/corpus/obj/crash-leak-index-after-group): after
     * a second group, assimp 5.2 leaked the group's mesh on these; checked first */
    write_text(path, "oob_group.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1//1 3//1 4//1\ng rest\nl 1 2 7\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 7), "vertex index 7 out of range (the file has 4 vertices)");
    write_text(path, "negative.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\ng rest\nf -4/1 -6 -1\nv 2 2 2\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 7), "'f' line: vertex index -6 is before the first vertex (4 so far)");
    /* forward references and relative indices within range still load */
    write_text(path, "forward.obj", "v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\nf -1 -2 -3\n");
    mesh *m = load_ok(mesh_load_assimp, path);
    cr_expect_eq(m->triangle_count, 2);
    mesh_destroy(m);
    write_text(path, "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    expect_error(mesh_load_assimp, path, "assimp:");
    /* found by fuzzing (tests/fuzz/corpus/obj/crash-leak-corner-spelling): assimp 5.2 reads
     * "-30-1" as two indices, throws on the first with the group's mesh half built and
     * leaks it; corners are read strictly first */
    write_text(path, "spelling.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\ng rest\nf -3 -30-1 -2\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 6), "expected a corner like 1, 1/2, 1//3 or 1/2/3",
                 "'-30-1'");
    write_text(path, "plus.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 +2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 4), "'+2'");
    write_text(path, "slash.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/ 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 4), "'1/'");
    /* texture coordinate and normal indices are checked like vertex indices (assimp throws on
     * them too, after the same half-built mesh) */
    write_text(path, "vt_range.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\ng rest\nf 1/1 2/5 3/1\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 7),
                 "texture coordinate index 5 out of range (the file has 1 texture coordinates)");
    write_text(path, "vn_before.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//-3 3//1\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 5),
                 "'f' line: normal index -3 is before the first normal (1 so far)");
    /* found by fuzzing (tests/fuzz/corpus/obj/crash-leak-one-corner-line): an "l" line of one
     * corner after a second group leaked its group's mesh in assimp 5.2 */
    write_text(path, "short_line.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\ng rest\nl 2\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 6), "'l' line: a line needs 2 or more corners, got 1");
    /* found by fuzzing (tests/fuzz/corpus/obj/crash-leak-vtab-vertex): assimp skips a line
     * that starts with a vertical tab, so the check must not count its vertex */
    write_text(path, "vtab.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n\vv 0 1 0\nf 1 2 3\ng rest\nf 1 3 4\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 7), "vertex index 4 out of range (the file has 3 vertices)");
    /* assimp 5.2 reads a line by its first character: an indented line is skipped (its data
     * lost), "fx" is a face, "v" with 5 numbers is dropped; all refused with the reason (found by
     * fuzzing: each let an index out of range through to assimp, which leaked) */
    write_text(path, "indented.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n  v 0 1 0\nf 1 2 4\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 4), "an indented line", "'v 0 1 0'");
    write_text(path, "fx.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\ng rest\nfx 1 2 5\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 6), "unknown keyword 'fx' (assimp would read it as 'f')");
    write_text(path, "five.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0 1 1\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 3), "'v' line: expected 3, 4 or 6 numbers, got 5");
    write_text(path, "cstype.obj", "v 0 0 0\ncstype bspline\nv 1 0 0\nend\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "free-form geometry ('cstype') is not supported");
    /* assimp 5.2 reads a byte-order mark as the first line's first character and loses the line */
    write_text(path, "bom.obj", "\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, "bom.obj:1: a UTF-8 byte-order mark");
    write_text(path, "corners.obj",
               "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\nf 1/1 2/2 3/1\nf 1/2/1 3/1/1 -1//-1\n");
    mesh *corners = load_ok(mesh_load_assimp, path);
    cr_expect_eq(corners->triangle_count, 2, "v/vt, v/vt/vn and v//vn corners, negative ones too");
    mesh_destroy(corners);
    /* assimp alone drops this line and shifts every later index: checked ourselves */
    write_text(path, "abc.obj", "v 0 0 0\nv 1 abc 0\nv 0 1 0\nv 1 1 0\nf 1 3 4\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "expected a number", "'abc'");
    write_text(path, "suffix.obj", "v 0 0 0\nv 1 2abc 0\nv 0 1 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "'2abc'");
    /* found by fuzzing (tests/fuzz/corpus/obj/crash-leak-leading-point): assimp 5.2 does not
     * count ".5" when it counts a line's numbers, so it dropped this vertex, the face after
     * the group indexed past the end and assimp leaked the group's mesh */
    write_text(path, "point.obj", "v .5 0 0\nv 0 1 0\nv 0 0 1\nv 1 0 0\nf 1 2 3\ng rest\nf -4 -3 -1\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 1), "'v' line: a number needs a digit before its point",
                 "write 0.5", "got '.5'");
    write_text(path, "vt_point.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 .25\nf 1/1 2/1 3/1\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 4), "'vt' line: a number needs a digit", "'.25'");
    /* spellings strtod and assimp read differently (assimp: 0, 1.5, a wrapped 64-bit integer,
     * inf beyond a float): each as the second vertex, refused at line 2 */
    static const struct {
        const char *vertex, *expected, *also;
    } misread[] = {
        {"v 0x10 0 0", "'v' line: expected a number, got '0x10'", NULL},
        {"v 1,5 0 0", "expected a number, got '1,5'", NULL},
        {"v 123456789012345678901 0 0", "more than 19 digits before the point", "'123456789012345678901'"},
        {"v 1e 0 0", "expected a number, got '1e'", NULL},
        {"v nanx 0 0", "expected a number, got 'nanx'", NULL},
        {"v 1e39 0 0", "value 1 is 1e39, beyond a float's range", NULL},
    };
    for (size_t i = 0; i < sizeof misread / sizeof misread[0]; i++) {
        char text[128];
        snprintf(text, sizeof text, "v 0 0 0\n%s\nv 0 1 0\nf 1 2 3\n", misread[i].vertex);
        write_text(path, "misread.obj", text);
        /* the fragment list ends at the first NULL: `also` may be absent */
        expect_error(mesh_load_assimp, path, at_line(line, path, 2), misread[i].expected, misread[i].also);
    }
    /* assimp counts a comment's numbers with the line's, then fails on the '#' */
    write_text(path, "comment.obj", "v 0 0 0\nv 1 0 0 # 4\nv 0 1 0 # one\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "a number in the comment ('4'");
    /* a "vn" line assimp reads as 3 numbers without counting: its comment is its own */
    write_text(path, "vn_comment.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1 # 4\nf 1//1 2//1 3//1\n");
    m = load_ok(mesh_load_assimp, path);
    mesh_destroy(m);
    /* x y z w: assimp divides by w */
    write_text(path, "w_zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 3), "w = 0", "not finite floats");
    write_text(path, "w_tiny.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0 1e-40\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 3), "w = 1e-40");
    write_text(path, "w_two.obj", "v 0 0 0\nv 2 0 0 2 # w\nv 0 1 0\nf 1 2 3\n");
    m = load_ok(mesh_load_assimp, path);
    cr_expect_eq(m->positions[3], 1.f, "x / w");
    mesh_destroy(m);
    /* the spellings both read alike load, with the values assimp gives them */
    write_text(path, "spellings.obj",
               "v -.5 +.25 1.\nv 1.e1 +1E+1 -0\nv 000000000000000000000002 1.5e-1 1234567890123456789\n"
               "f 1 2 3\n");
    m = load_ok(mesh_load_assimp, path);
    cr_assert_eq(m->vertex_count, 3);
    static const float spelled[9] = {-0.5f, 0.25f, 1.f, 10.f, 10.f, 0.f, 2.f, 0.15f, 1234567890123456789.f};
    for (int i = 0; i < 9; i++)
        cr_expect_float_eq(m->positions[i], spelled[i], 1e-6f * fabsf(spelled[i]) + 1e-7f, "coordinate %d: %g", i,
                           (double)m->positions[i]);
    mesh_destroy(m);
    write_text(path, "short.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "expected 3, 4 or 6 numbers, got 2");
    /* assimp alone merges a NaN vertex into another one, silently */
    write_text(path, "nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "nan", "must be finite");
    write_text(path, "inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 3), "inf", "must be finite");
    write_text(path, "points.obj", "v 0 0 0\nv 1 0 0\np 1 2\n");
    expect_error(mesh_load_assimp, path, "no triangles");
    expect_error(mesh_load_assimp, scratch_path(path, "absent.obj"), "cannot open");
}

/* Found by fuzzing (tests/fuzz/corpus/obj/crash-mtl-texture-before-newmtl):
 * assimp 5.2's MTL reader crashed (SIGSEGV, a NULL material) on a texture
 * statement before the first "newmtl", also in the library assimp falls back
 * to (the .obj's name with .mtl) when the named one does not exist. */
Test(mesh_load, mtl_statements_before_newmtl)
{
    char path[PATH_BYTES], mtl[PATH_BYTES], line[PATH_BYTES + 32];
    static const char tri[] = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    char obj[256];
    write_text(mtl, "tex_first.mtl", "# a comment\n\nmap_Kd wood.png\nnewmtl a\nKd 1 1 1\n");
    snprintf(obj, sizeof obj, "# x\nmtllib tex_first.mtl\n%s", tri);
    write_text(path, "tex_first.obj", obj);
    expect_error(mesh_load_assimp, path, at_line(line, path, 2), "material library", mtl, ":3:", "'map_Kd'",
                 "before any 'newmtl'");
    write_text(mtl, "fallback.mtl", "Kd 1 0 0\nnewmtl a\n");
    snprintf(obj, sizeof obj, "mtllib absent.mtl\n%s", tri);
    write_text(path, "fallback.obj", obj);
    expect_error(mesh_load_assimp, path, at_line(line, path, 1), mtl, ":1:", "'Kd' before any 'newmtl'");
    /* assimp ends lines at '\r' and '\0' too (tests/fuzz/corpus/obj/crash-mtllib-after-nul) */
    static const char nul_obj[] = "# c\0mtllib tex_first.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    write_bytes(path, "nul.obj", nul_obj, sizeof nul_obj - 1);
    write_text(mtl, "tex_first.mtl", "# a comment\n\nmap_Kd wood.png\nnewmtl a\nKd 1 1 1\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 1), mtl, ":3:", "'map_Kd'");
    write_text(path, "cr.obj", "# c\rmtllib tex_first.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 1), mtl, ":3:", "'map_Kd'");
    write_text(mtl, "nul_mtl.mtl", "# x\rmap_Kd t.png\nnewmtl a\n");
    write_text(path, "nul_mtl.obj", "mtllib nul_mtl.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, at_line(line, path, 1), mtl, ":1:", "'map_Kd'");
    /* found by fuzzing (tests/fuzz/corpus/obj/crash-kd-out-of-range): Kd is a
     * reflectance, clamped to [0, 1] as vertex colours are; NaN is refused */
    write_text(mtl, "bright.mtl", "newmtl red\nKd 9 -1 0.5\nnewmtl dark\nKd nan 0 0\n");
    write_text(path, "bright.obj", "mtllib bright.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl red\nf 1 2 3\n");
    mesh *m = load_ok(mesh_load_assimp, path);
    cr_assert_eq(m->material_count, 1);
    cr_expect(m->materials[0].diffuse_rgb[0] == 1.f && m->materials[0].diffuse_rgb[1] == 0.f &&
              m->materials[0].diffuse_rgb[2] == 0.5f);
    mesh_destroy(m);
    write_text(path, "nan_kd.obj", "mtllib bright.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl dark\nf 1 2 3\n");
    expect_error(mesh_load_assimp, path, "material 'dark': diffuse colour (Kd) is not finite");
    /* a library that is absent altogether is assimp's to report (it goes on) */
    snprintf(obj, sizeof obj, "mtllib absent.mtl\n%s", tri);
    write_text(path, "no_library.obj", obj);
    m = load_ok(mesh_load_assimp, path);
    cr_expect_eq(m->triangle_count, 1);
    mesh_destroy(m);
}

Test(mesh_load, stl_nan_is_caught_before_vertices_are_joined)
{
    char path[PATH_BYTES];
    write_text(path, "nan.stl",
               "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 nan 0\nvertex 0 1 0\n"
               "endloop\nendfacet\nendsolid t\n");
    expect_error(mesh_load_assimp, path, "'y' is nan", "must be finite");
}

Test(mesh_load, mesh_load_dispatches_by_extension)
{
    char path[PATH_BYTES];
    /* only the PLY reader loads a point set; assimp refuses it */
    const char *points = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    write_text(path, "points.PLY", points);
    mesh *m = load_ok(mesh_load, path);
    cr_assert_eq(m->vertex_count, 3);
    cr_assert_eq(m->triangle_count, 0);
    mesh_destroy(m);
    expect_error(mesh_load_assimp, path, "assimp:", "no faces");
    /* a broken .ply gets the PLY reader's words, a broken .obj assimp's */
    expect_error(mesh_load, write_text(path, "broken.ply", "hello\n"), "not a PLY file");
    write_text(path, "broken.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 0\n");
    expect_error(mesh_load, path, "assimp:");
    write_text(path, "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    m = load_ok(mesh_load, path);
    cr_assert_eq(m->triangle_count, 1);
    mesh_destroy(m);
}

/* ---- threads ----------------------------------------------------------- */

/* One thread's job: load `path` `rounds` times, expecting success or not. */
typedef struct load_job {
    const char *path;     /* the file */
    bool expect_ok;       /* whether it should load */
    const char *word;     /* a word the error must contain when !expect_ok */
    int failures;         /* rounds that did not go as expected */
} load_job;

#define THREAD_ROUNDS 20

static void *run_load_job(void *arg)
{
    load_job *job = arg;
    for (int i = 0; i < THREAD_ROUNDS; i++) {
        tess_error err = {{0}};
        mesh *m = mesh_load(job->path, &err);
        bool ok = job->expect_ok ? m != NULL : m == NULL && strstr(err.msg, job->path) && strstr(err.msg, job->word);
        job->failures += !ok;
        mesh_destroy(m);
    }
    return NULL;
}

Test(mesh_load, loaders_run_in_parallel)
{
    char paths[4][PATH_BYTES];
    ply_spec le = cube_spec(BINARY_LE), ascii = cube_spec(ASCII);
    write_cube(paths[0], "le.ply", &le);
    write_cube(paths[1], "ascii.ply", &ascii);
    write_text(paths[2], "bad1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 8\n");
    write_text(paths[3], "bad2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n");
    load_job jobs[4] = {
        {paths[0], true, NULL, 0},
        {paths[1], true, NULL, 0},
        {paths[2], false, "out of range", 0},
        {paths[3], false, "Invalid face index", 0},
    };
    pthread_t threads[4];
    for (int i = 0; i < 4; i++)
        cr_assert_eq(pthread_create(&threads[i], NULL, run_load_job, &jobs[i]), 0);
    for (int i = 0; i < 4; i++) {
        pthread_join(threads[i], NULL);
        cr_assert_eq(jobs[i].failures, 0, "%s: %d of %d rounds went wrong", jobs[i].path, jobs[i].failures,
                     THREAD_ROUNDS);
    }
}
