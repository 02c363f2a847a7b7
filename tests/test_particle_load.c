/* test_particle_load.c - the particle loaders (engine/load/particle_load.c)
 * on PLY point sets and LAMMPS dumps written here.
 *
 * Every test writes its files into a fresh mkdtemp directory, removed after
 * the test. Binary PLY values are assembled byte by byte in the declared
 * byte order, so the tests hold on hosts of either endianness. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "engine/geometry/particles/particles.h"
#include "support.h"
#include "engine/load/particle_load.h"

#define PATH_BYTES 512

/* ---- scratch files ------------------------------------------------------ */

/* This test's directory: Criterion runs each test in its own process, and
 * the suite's init and fini make and remove it. */
static char scratch_dir[128];

static void scratch_create(void) { support_make_tmp_dir(scratch_dir, sizeof scratch_dir, "particle_load"); }

static void scratch_remove(void) { support_remove_tmp_dir(scratch_dir); }

TestSuite(particle_load, .init = scratch_create, .fini = scratch_remove);

/* A growing byte string. */
typedef struct buffer {
    unsigned char *data; /* len bytes used of cap */
    size_t len, cap;     /* bytes used, bytes allocated */
} buffer;

static void append(buffer *b, const void *src, size_t n)
{
    if (b->len + n > b->cap) {
        b->cap = 2 * (b->len + n) + 512;
        b->data = realloc(b->data, b->cap);
        cr_assert_not_null(b->data);
    }
    memcpy(b->data + b->len, src, n);
    b->len += n;
}

static void appendf(buffer *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void appendf(buffer *b, const char *fmt, ...)
{
    char text[4096];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    cr_assert(n >= 0 && (size_t)n < sizeof text, "test bug: text too long");
    append(b, text, (size_t)n);
}

/* Write `len` bytes to NAME in the scratch directory; its path into path. */
static const char *write_file(char path[PATH_BYTES], const char *name, const void *data, size_t len)
{
    snprintf(path, PATH_BYTES, "%s/%.200s", scratch_dir, name);
    FILE *f = fopen(path, "wb");
    cr_assert_not_null(f, "cannot create %s", path);
    cr_assert_eq(fwrite(data, 1, len, f), len);
    cr_assert_eq(fclose(f), 0);
    return path;
}

static const char *write_buffer(char path[PATH_BYTES], const char *name, buffer *b)
{
    write_file(path, name, b->data, b->len);
    free(b->data);
    *b = (buffer){0};
    return path;
}

static const char *write_text(char path[PATH_BYTES], const char *name, const char *text)
{
    return write_file(path, name, text, strlen(text));
}

/* ---- PLY values ---------------------------------------------------------- */

enum encoding { ASCII, BINARY_LE, BINARY_BE };
static const char *const encoding_names[] = {"ascii", "binary_little_endian", "binary_big_endian"};

/* A value of the PLY type `type` (a name from the header) in the body. */
static void put_value(buffer *b, enum encoding enc, const char *type, double v)
{
    static const struct {
        const char *name;
        unsigned size;
        bool is_float;
    } types[] = {{"char", 1, false},  {"uchar", 1, false}, {"short", 2, false}, {"ushort", 2, false},
                 {"int", 4, false},   {"uint", 4, false},  {"float", 4, true},  {"double", 8, true},
                 {"uint8", 1, false}, {"int16", 2, false}, {"float32", 4, true}, {"float64", 8, true}};
    size_t t = 0;
    while (t < sizeof types / sizeof types[0] && strcmp(types[t].name, type) != 0)
        t++;
    cr_assert(t < sizeof types / sizeof types[0], "test bug: type %s", type);
    if (enc == ASCII) {
        if (!types[t].is_float)
            appendf(b, "%lld ", (long long)v);
        else
            appendf(b, "%.17g ", types[t].size == 4 ? (double)(float)v : v);
        return;
    }
    uint64_t bits;
    if (types[t].is_float && types[t].size == 4) {
        float f = (float)v;
        uint32_t u;
        memcpy(&u, &f, sizeof u);
        bits = u;
    } else if (types[t].is_float) {
        memcpy(&bits, &v, sizeof bits);
    } else {
        bits = (uint64_t)(int64_t)v; /* two's complement, cut to size below */
    }
    unsigned size = types[t].size;
    for (unsigned i = 0; i < size; i++) {
        unsigned shift = 8 * (enc == BINARY_BE ? size - 1 - i : i);
        unsigned char byte = (unsigned char)(bits >> shift & 0xff);
        append(b, &byte, 1);
    }
}

static void end_record(buffer *b, enum encoding enc)
{
    if (enc == ASCII)
        appendf(b, "\n");
}

/* ---- results --------------------------------------------------------------- */

static particle_set *load_ok(particle_set *(*load)(const char *, tess_error *), const char *path)
{
    tess_error err = {{0}};
    particle_set *p = load(path, &err);
    cr_assert_not_null(p, "%s did not load: %s", path, err.msg);
    cr_assert_str_empty(err.msg, "a loaded set left a message: %s", err.msg);
    return p;
}

static const float *attribute(const particle_set *p, const char *name)
{
    int a = particle_set_find_attribute(p, name);
    cr_assert(a >= 0, "no attribute '%s'", name);
    return p->attributes[a].values;
}

/* The load fails with one line naming the path and holding every one of words. */
static void check_error(particle_set *(*load)(const char *, tess_error *), const char *path,
                        const char *const words[])
{
    tess_error err = {{0}};
    particle_set *p = load(path, &err);
    particle_set_destroy(p);
    cr_assert_null(p, "%s loaded; expected an error", path);
    cr_assert(strstr(err.msg, path) != NULL, "message lacks the path %s: %s", path, err.msg);
    cr_assert(strchr(err.msg, '\n') == NULL, "message is not one line: %s", err.msg);
    for (size_t i = 0; words[i]; i++)
        cr_assert(strstr(err.msg, words[i]) != NULL, "message lacks '%s': %s", words[i], err.msg);
}

#define expect_error(load, path, ...) check_error(load, path, (const char *const[]){__VA_ARGS__, NULL})

/* "PATH:LINE:" */
static const char *at_line(char out[PATH_BYTES + 32], const char *path, int line)
{
    snprintf(out, PATH_BYTES + 32, "%s:%d:", path, line);
    return out;
}

/* ---- PLY: what loads ------------------------------------------------------- */

/* Five points with colours, a normal component, an intensity, a list to read
 * past, and elements before and after the vertices to read past. */
#define POINTS 5
static const double point_xyz[POINTS][3] = {
    {0.5, -1.25, 3}, {1e-3, 2.5e4, -7.75}, {-0.1, 0.2, 0.3}, {100, 200, 300}, {0, 0, 0}};
static const unsigned point_rgb[POINTS][3] = {{255, 0, 1}, {10, 20, 30}, {0, 128, 255}, {7, 8, 9}, {200, 100, 50}};
static const double point_nx[POINTS] = {0.25, -1, 0.1, 1e-7, 0.333333333};
static const int point_intensity[POINTS] = {-32768, 0, 12345, 32767, -1};

static buffer points_ply(enum encoding enc)
{
    buffer b = {0};
    appendf(&b, "ply\nformat %s 1.0\ncomment test_particle_load.c\n", encoding_names[enc]);
    appendf(&b, "element camera 1\nproperty float fov\nproperty list uchar float clip\n");
    appendf(&b, "element vertex %d\n", POINTS);
    appendf(&b, "property float x\nproperty double y\nproperty float32 z\n");
    appendf(&b, "property uchar red\nproperty uint8 green\nproperty uchar blue\n");
    appendf(&b, "property list uchar int neighbours\n");
    appendf(&b, "property float nx\nproperty short intensity\n");
    appendf(&b, "element face 2\nproperty list uchar int vertex_indices\n");
    appendf(&b, "end_header\n");
    put_value(&b, enc, "float", 60);
    put_value(&b, enc, "uchar", 2);
    put_value(&b, enc, "float", 0.1);
    put_value(&b, enc, "float", 100);
    end_record(&b, enc);
    for (int i = 0; i < POINTS; i++) {
        put_value(&b, enc, "float", point_xyz[i][0]);
        put_value(&b, enc, "double", point_xyz[i][1]);
        put_value(&b, enc, "float32", point_xyz[i][2]);
        for (int k = 0; k < 3; k++)
            put_value(&b, enc, k == 1 ? "uint8" : "uchar", point_rgb[i][k]);
        put_value(&b, enc, "uchar", i % 3);
        for (int k = 0; k < i % 3; k++)
            put_value(&b, enc, "int", 1000 + k);
        put_value(&b, enc, "float", point_nx[i]);
        put_value(&b, enc, "short", point_intensity[i]);
        end_record(&b, enc);
    }
    for (int f = 0; f < 2; f++) {
        put_value(&b, enc, "uchar", 3);
        for (int k = 0; k < 3; k++)
            put_value(&b, enc, "int", f + k);
        end_record(&b, enc);
    }
    return b;
}

static void assert_points(const particle_set *p, const char *what)
{
    cr_assert_eq(p->count, POINTS, "%s: %u particles", what, p->count);
    cr_assert_eq(p->attribute_count, 5, "%s: %u attributes", what, p->attribute_count);
    static const char *const names[5] = {"red", "green", "blue", "nx", "intensity"};
    for (int a = 0; a < 5; a++)
        cr_assert_str_eq(p->attributes[a].name, names[a], "%s: attribute %d in file order", what, a);
    for (int i = 0; i < POINTS; i++) {
        cr_assert_eq(p->x[i], (float)point_xyz[i][0], "%s: x of %d", what, i);
        cr_assert_eq(p->y[i], (float)point_xyz[i][1], "%s: y of %d", what, i);
        cr_assert_eq(p->z[i], (float)point_xyz[i][2], "%s: z of %d", what, i);
        for (int k = 0; k < 3; k++)
            cr_assert_eq(attribute(p, names[k])[i], (float)point_rgb[i][k], "%s: %s of %d", what, names[k], i);
        cr_assert_eq(attribute(p, "nx")[i], (float)point_nx[i], "%s: nx of %d", what, i);
        cr_assert_eq(attribute(p, "intensity")[i], (float)point_intensity[i], "%s: intensity of %d", what, i);
    }
    const particle_attribute *red = &p->attributes[0], *intensity = &p->attributes[4];
    cr_assert(red->min == 0.f && red->max == 255.f, "%s: red range %g..%g", what, red->min, red->max);
    cr_assert(intensity->min == -32768.f && intensity->max == 32767.f, "%s", what);
    cr_assert_eq(p->timestep, -1, "%s: a PLY has no time step", what);
}

Test(particle_load, ply_points_with_extra_properties_in_every_encoding)
{
    for (int enc = 0; enc < 3; enc++) {
        char path[PATH_BYTES], name[64];
        snprintf(name, sizeof name, "points_%s.ply", encoding_names[enc]);
        buffer b = points_ply((enum encoding)enc);
        particle_set *p = load_ok(particles_load_ply, write_buffer(path, name, &b));
        assert_points(p, encoding_names[enc]);
        particle_set_destroy(p);
        p = load_ok(particles_load, path); /* by the extension */
        assert_points(p, encoding_names[enc]);
        particle_set_destroy(p);
    }
}

Test(particle_load, ply_mesh_faces_are_read_past)
{
    static const char text[] = "ply\n"
                               "format ascii 1.0\n"
                               "element vertex 4\n"
                               "property float x\nproperty float y\nproperty float z\n"
                               "element face 2\n"
                               "property list uchar int vertex_indices\n"
                               "end_header\n"
                               "0 0 0\n1 0 0\n1 1 0\n0 1 0.5\n"
                               "3 0 1 2\n4 0 1 2 3\n";
    char path[PATH_BYTES];
    particle_set *p = load_ok(particles_load_ply, write_text(path, "quad.ply", text));
    cr_assert_eq(p->count, 4);
    cr_assert_eq(p->attribute_count, 0);
    cr_assert_eq(p->z[3], 0.5f);
    float lo[3], hi[3];
    cr_assert(particle_set_bounds(p, lo, hi));
    cr_assert(lo[0] == 0.f && hi[0] == 1.f && hi[1] == 1.f && hi[2] == 0.5f);
    particle_set_destroy(p);
}

Test(particle_load, ply_found_by_content_and_big_binary_fast_path)
{
    /* binary scalars only: the fixed-record path, over more than one read chunk */
    enum { N = 100000 };
    for (int enc = BINARY_LE; enc <= BINARY_BE; enc++) {
        buffer b = {0};
        appendf(&b, "ply\nformat %s 1.0\nelement vertex %d\n", encoding_names[enc], N);
        appendf(&b, "property double x\nproperty float y\nproperty int z\nproperty ushort id\nend_header\n");
        for (int i = 0; i < N; i++) {
            put_value(&b, (enum encoding)enc, "double", i * 0.5);
            put_value(&b, (enum encoding)enc, "float", -i);
            put_value(&b, (enum encoding)enc, "int", i - N / 2);
            put_value(&b, (enum encoding)enc, "ushort", i % 65536);
        }
        char path[PATH_BYTES];
        particle_set *p = load_ok(particles_load, write_buffer(path, "cloud.points", &b)); /* the "ply" magic */
        cr_assert_eq(p->count, N);
        const float *id = attribute(p, "id");
        for (int i = 0; i < N; i += 997)
            cr_assert(p->x[i] == (float)(i * 0.5) && p->y[i] == (float)-i && p->z[i] == (float)(i - N / 2) &&
                          id[i] == (float)(i % 65536),
                      "particle %d", i);
        cr_assert_eq(p->x[N - 1], (float)((N - 1) * 0.5));
        particle_set_destroy(p);
    }
}

Test(particle_load, ply_empty_vertex_element)
{
    char path[PATH_BYTES];
    particle_set *p = load_ok(
        particles_load_ply,
        write_text(path, "empty.ply",
                   "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                   "property float z\nproperty float t\nend_header\n"));
    cr_assert_eq(p->count, 0);
    cr_assert_eq(p->attribute_count, 1);
    particle_set_destroy(p);
}

/* ---- PLY: what is refused ---------------------------------------------------- */

/* A header for three float x y z points (ascii unless said) and `more` header lines. */
static void put_xyz_header(buffer *b, enum encoding enc, long long count, const char *more)
{
    appendf(b, "ply\nformat %s 1.0\nelement vertex %lld\n", encoding_names[enc], count);
    appendf(b, "property float x\nproperty float y\nproperty float z\n%send_header\n", more);
}

Test(particle_load, ply_errors)
{
    char path[PATH_BYTES], where[PATH_BYTES + 32];

    write_text(path, "no_z.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                 "end_header\n1 2\n");
    expect_error(particles_load_ply, path, "vertex element has no 'z' property");

    write_text(path, "no_vertex.ply", "ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n");
    expect_error(particles_load_ply, path, "no 'vertex' element");

    buffer b = {0};
    put_xyz_header(&b, ASCII, 3, "");
    appendf(&b, "1 2 3\n4 five 6\n7 8 9\n");
    write_buffer(path, "word.ply", &b);
    expect_error(particles_load_ply, path, at_line(where, path, 9), "vertex 1: expected a number for 'y', got 'five'");

    put_xyz_header(&b, ASCII, 2, "");
    appendf(&b, "1 2 3\n4 5\n");
    write_buffer(path, "short_line.ply", &b);
    expect_error(particles_load_ply, path, at_line(where, path, 9), "vertex 1: expected a number for 'z', got end of line");

    put_xyz_header(&b, ASCII, 2, "");
    appendf(&b, "1 2 3 4\n4 5 6\n");
    write_buffer(path, "long_line.ply", &b);
    expect_error(particles_load_ply, path, at_line(where, path, 8), "vertex 0: unexpected extra value '4'");

    put_xyz_header(&b, ASCII, 3, "");
    appendf(&b, "1 2 3\n4 5 6\n");
    write_buffer(path, "few.ply", &b);
    expect_error(particles_load_ply, path, "truncated: expected 3 vertices, file ends before vertex 2");

    put_xyz_header(&b, ASCII, 2, "property float heat\n");
    appendf(&b, "1 2 3 0\n4 nan 6 0\n");
    write_buffer(path, "nan.ply", &b);
    expect_error(particles_load_ply, path, "particle 1: position is not finite");

    put_xyz_header(&b, ASCII, 2, "property float heat\n");
    appendf(&b, "1 2 3 0\n4 5 6 inf\n");
    write_buffer(path, "inf.ply", &b);
    expect_error(particles_load_ply, path, "particle 1: attribute 'heat' is not finite");

    put_xyz_header(&b, BINARY_LE, 2, "property double heat\n");
    for (int i = 0; i < 3; i++)
        put_value(&b, BINARY_LE, "float", i);
    put_value(&b, BINARY_LE, "double", 1e300); /* beyond a float: infinite */
    for (int i = 0; i < 3; i++)
        put_value(&b, BINARY_LE, "float", i);
    put_value(&b, BINARY_LE, "double", 0);
    write_buffer(path, "huge.ply", &b);
    expect_error(particles_load_ply, path, "particle 0: attribute 'heat' is not finite");

    put_xyz_header(&b, ASCII, 1, "property uchar red\nproperty uchar red\n");
    write_buffer(path, "twice.ply", &b);
    expect_error(particles_load_ply, path, at_line(where, path, 8), "vertex element has two 'red' properties");

    put_xyz_header(&b, ASCII, 1, "property list uchar float x\n");
    write_buffer(path, "list_x.ply", &b);
    expect_error(particles_load_ply, path, "vertex property 'x' must be a scalar, not a list");

    put_xyz_header(&b, ASCII, 1, "property float a_name_of_thirty_two_characters_\n");
    write_buffer(path, "long_name.ply", &b);
    expect_error(particles_load_ply, path, "name longer than 31 characters");

    char more[65 * 24] = "";
    for (int i = 0; i < 65; i++)
        snprintf(more + strlen(more), sizeof more - strlen(more), "property uchar a%d\n", i);
    put_xyz_header(&b, ASCII, 1, more);
    write_buffer(path, "many.ply", &b);
    expect_error(particles_load_ply, path, at_line(where, path, 71), "vertex property 'a64': more than 64 attributes");

    put_xyz_header(&b, ASCII, 4000000000LL, "");
    appendf(&b, "1 2 3\n");
    write_buffer(path, "over_max.ply", &b);
    expect_error(particles_load_ply, path, "4000000000 vertices: more than a particle set can hold (2147483647)");

    /* a count the file cannot hold: storage is capped by the file's size, the read stops where it ends */
    put_xyz_header(&b, BINARY_BE, 2000000000LL, "");
    for (int i = 0; i < 7; i++)
        put_value(&b, BINARY_BE, "float", i);
    write_buffer(path, "absurd.ply", &b);
    expect_error(particles_load_ply, path, "truncated: expected 2000000000 vertices, file ends in vertex 2");

    put_xyz_header(&b, BINARY_LE, 3, "");
    for (int i = 0; i < 8; i++)
        put_value(&b, BINARY_LE, "float", i);
    write_buffer(path, "cut.ply", &b);
    expect_error(particles_load_ply, path, "truncated: expected 3 vertices, file ends in vertex 2");

    put_xyz_header(&b, BINARY_LE, 1, "property list uchar int friends\n");
    for (int i = 0; i < 3; i++)
        put_value(&b, BINARY_LE, "float", i);
    put_value(&b, BINARY_LE, "uchar", 5);
    put_value(&b, BINARY_LE, "int", 5);
    write_buffer(path, "cut_list.ply", &b);
    expect_error(particles_load_ply, path, "truncated: expected 1 vertex, file ends in vertex 0");

    write_text(path, "header.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty floot x\n");
    expect_error(particles_load_ply, path, at_line(where, path, 4), "unknown property type 'floot'");

    snprintf(path, PATH_BYTES, "%s/missing.ply", scratch_dir);
    expect_error(particles_load_ply, path, "cannot open");
}

/* ---- LAMMPS: what loads ---------------------------------------------------- */

/* One snapshot: time step `step`, `n` atoms with the given ATOMS columns;
 * atom i's value in column c is value(i, c). */
static double atom_value(int i, int c) { return c == 0 ? i + 1 : c == 1 ? 1 + i % 2 : 0.25 * c - 1.5 * i + i * c * 0.001; }

static void put_snapshot(buffer *b, long long step, int n, const char *box, const char *columns)
{
    appendf(b, "ITEM: TIMESTEP\n%lld\nITEM: NUMBER OF ATOMS\n%d\n", step, n);
    appendf(b, "ITEM: BOX BOUNDS %s\n", box);
    bool triclinic = strstr(box, "xy") != NULL;
    for (int k = 0; k < 3; k++)
        appendf(b, triclinic ? "%g %g 0.5\n" : "%g %g\n", -1.0 * (k + 1), 10.0 * (k + 1));
    appendf(b, "ITEM: ATOMS %s\n", columns);
    int cols = 1;
    for (const char *s = columns; *s; s++)
        cols += *s == ' ';
    for (int i = 0; i < n; i++) {
        for (int c = 0; c < cols; c++)
            appendf(b, c ? " %.9g" : "%.9g", atom_value(i, c));
        appendf(b, "\n");
    }
}

Test(particle_load, lammps_x_columns_and_time_step)
{
    buffer b = {0};
    put_snapshot(&b, 1234, 6, "pp pp pp", "id type x y z vx c_ke");
    char path[PATH_BYTES];
    particle_set *p = load_ok(particles_load_lammps, write_buffer(path, "melt.dump", &b));
    cr_assert_eq(p->count, 6);
    cr_assert_eq(p->timestep, 1234);
    cr_assert_eq(p->attribute_count, 4);
    static const char *const names[4] = {"id", "type", "vx", "c_ke"};
    static const int columns[4] = {0, 1, 5, 6};
    for (int a = 0; a < 4; a++)
        cr_assert_str_eq(p->attributes[a].name, names[a]);
    for (int i = 0; i < 6; i++) {
        cr_assert_eq(p->x[i], (float)atom_value(i, 2), "x of %d", i);
        cr_assert_eq(p->y[i], (float)atom_value(i, 3), "y of %d", i);
        cr_assert_eq(p->z[i], (float)atom_value(i, 4), "z of %d", i);
        for (int a = 0; a < 4; a++)
            cr_assert_eq(p->attributes[a].values[i], (float)atom_value(i, columns[a]), "%s of %d", names[a], i);
    }
    cr_assert(p->attributes[0].min == 1.f && p->attributes[0].max == 6.f, "id range");
    particle_set_destroy(p);
}

Test(particle_load, lammps_unwrapped_and_scaled_positions)
{
    /* x alone is no position set: xu yu zu are the positions, x an attribute */
    buffer b = {0};
    put_snapshot(&b, 7, 4, "pp pp pp", "id xu yu zu x");
    char path[PATH_BYTES];
    particle_set *p = load_ok(particles_load_lammps, write_buffer(path, "unwrapped.lammpstrj", &b));
    cr_assert_eq(p->count, 4);
    cr_assert_eq(p->timestep, 7);
    cr_assert_eq(p->attribute_count, 2);
    for (int i = 0; i < 4; i++) {
        cr_assert_eq(p->x[i], (float)atom_value(i, 1));
        cr_assert_eq(p->z[i], (float)atom_value(i, 3));
        cr_assert_eq(attribute(p, "x")[i], (float)atom_value(i, 4));
    }
    particle_set_destroy(p);

    /* scaled: x = lo + xs * (hi - lo), box lines "-1 10", "-2 20", "-3 30" */
    put_snapshot(&b, 8, 5, "pp pp ff", "id type xs ys zs");
    p = load_ok(particles_load_lammps, write_buffer(path, "scaled.dump", &b));
    cr_assert_eq(p->count, 5);
    for (int i = 0; i < 5; i++) {
        const float *axis[3] = {p->x, p->y, p->z};
        for (int k = 0; k < 3; k++) {
            double lo = -1.0 * (k + 1), hi = 10.0 * (k + 1);
            char text[64];
            snprintf(text, sizeof text, "%.9g", atom_value(i, 2 + k)); /* the file's own digits */
            float want = (float)(lo + strtod(text, NULL) * (hi - lo));
            cr_assert_eq(axis[k][i], want, "axis %d of %d: %.9g, want %.9g", k, i, axis[k][i], want);
        }
    }
    cr_assert_eq(p->attribute_count, 2, "id and type; xs ys zs are positions");
    particle_set_destroy(p);

    /* a triclinic box with unscaled positions loads */
    put_snapshot(&b, 9, 3, "xy xz yz pp pp pp", "id x y z");
    p = load_ok(particles_load, write_buffer(path, "tilted.dump", &b));
    cr_assert_eq(p->count, 3);
    particle_set_destroy(p);
}

Test(particle_load, lammps_first_snapshot_only)
{
    buffer b = {0};
    put_snapshot(&b, 100, 3, "pp pp pp", "id type x y z");
    put_snapshot(&b, 200, 5, "pp pp pp", "id type x y z vx");
    appendf(&b, "this tail is never read\n");
    char path[PATH_BYTES];
    particle_set *p = load_ok(particles_load, write_buffer(path, "series.lammpstrj", &b));
    cr_assert_eq(p->count, 3);
    cr_assert_eq(p->timestep, 100);
    cr_assert_eq(p->attribute_count, 2);
    cr_assert_eq(p->z[2], (float)atom_value(2, 4));
    particle_set_destroy(p);
}

Test(particle_load, lammps_units_time_crlf_and_dispatch_by_content)
{
    static const char text[] = "ITEM: UNITS\r\nlj\r\nITEM: TIME\r\n0.5\r\n"
                               "ITEM: TIMESTEP\r\n  42 \r\nITEM: NUMBER OF ATOMS\r\n2\r\n"
                               "ITEM: BOX BOUNDS pp pp pp\r\n0 1\r\n0 1\r\n0 1\r\n"
                               "ITEM: ATOMS id x y z\r\n1 0.5 0.25 0.125\r\n2\t1e-3  -2E2 3\r\n";
    char path[PATH_BYTES];
    particle_set *p = load_ok(particles_load, write_text(path, "atoms.txt", text));
    cr_assert_eq(p->count, 2);
    cr_assert_eq(p->timestep, 42);
    cr_assert(p->x[0] == 0.5f && p->y[0] == 0.25f && p->z[0] == 0.125f);
    cr_assert(p->x[1] == 1e-3f && p->y[1] == -200.f && p->z[1] == 3.f);
    particle_set_destroy(p);

    p = load_ok(particles_load, write_text(path, "no_extension", "ITEM: TIMESTEP\n3\nITEM: NUMBER OF ATOMS\n1\n"
                                                                 "ITEM: ATOMS x y z\n1 2 3\n"));
    cr_assert_eq(p->count, 1);
    cr_assert_eq(p->timestep, 3);
    particle_set_destroy(p);

    p = load_ok(particles_load, write_text(path, "none.dump", "ITEM: TIMESTEP\n3\nITEM: NUMBER OF ATOMS\n0\n"
                                                              "ITEM: ATOMS x y z\n"));
    cr_assert_eq(p->count, 0);
    particle_set_destroy(p);

    write_text(path, "notes.txt", "particles, maybe\n");
    expect_error(particles_load, path, "not a particle file", ".ply", ".dump", ".lammpstrj", "ITEM: TIMESTEP");
    snprintf(path, PATH_BYTES, "%s/absent.xyz", scratch_dir);
    expect_error(particles_load, path, "cannot open");
    snprintf(path, PATH_BYTES, "%s/absent.dump", scratch_dir);
    expect_error(particles_load, path, "cannot open");
}

/* ---- LAMMPS: what is refused ---------------------------------------------- */

/* A dump of `count` atoms (declared) with ATOMS `columns`, then the atom lines as given. */
static const char *write_dump(char path[PATH_BYTES], const char *name, const char *count, const char *box,
                              const char *columns, const char *atoms)
{
    buffer b = {0};
    appendf(&b, "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n%s\nITEM: BOX BOUNDS %s\n", count, box);
    bool tilted = strstr(box, "xy") != NULL;
    for (int k = 0; k < 3; k++)
        appendf(&b, tilted ? "0 4 0.5\n" : "0 4\n");
    appendf(&b, "ITEM: ATOMS %s\n%s", columns, atoms);
    return write_buffer(path, name, &b);
}

Test(particle_load, lammps_errors)
{
    char path[PATH_BYTES], where[PATH_BYTES + 32];
    /* line 10 is the first atom line of write_dump's files */

    write_dump(path, "no_z.dump", "1", "pp pp pp", "id x y", "1 2 3\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 9), "ITEM: ATOMS has no 'z' column");

    write_dump(path, "no_xyz.dump", "1", "pp pp pp", "id type vx", "1 2 3\n");
    expect_error(particles_load_lammps, path, "ITEM: ATOMS has no position columns (x y z, xu yu zu, or xs ys zs)");

    write_dump(path, "few_values.dump", "2", "pp pp pp", "id type x y z", "1 1 0.5 0.5 0.5\n2 1 0.5 0.5\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 11),
                 "atom 1: expected 5 values (the columns of ITEM: ATOMS), got 4");

    write_dump(path, "more_values.dump", "2", "pp pp pp", "id type x y z", "1 1 0 0 0 9 9\n2 1 0 0 0\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 10), "atom 0: expected 5 values", "got 7");

    write_dump(path, "word.dump", "2", "pp pp pp", "id x y z vx", "1 0 0 0 0.5\n2 0 0 0 fast\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 11),
                 "atom 1: column 'vx': expected a number, got 'fast'");

    write_dump(path, "glued.dump", "1", "pp pp pp", "id x y z", "1 0 0 0.5.5\n");
    expect_error(particles_load_lammps, path, "column 'z': expected a number, got '0.5.5'");

    write_dump(path, "few_atoms.dump", "3", "pp pp pp", "id type x y z",
               "1 1 0.000000 0.000000 0.000000\n2 1 0.000000 0.000000 0.000000\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 12), "file ends after 2 of 3 atoms");

    write_dump(path, "next_snapshot.dump", "3", "pp pp pp", "x y z",
               "0.000000 0.000000 0.000000\n0.000000 0.000000 0.000000\nITEM: TIMESTEP\n5\n");
    expect_error(particles_load_lammps, path, "'ITEM: TIMESTEP' after 2 of 3 atoms");

    write_dump(path, "nan.dump", "2", "pp pp pp", "id x y z", "1 0 0 0\n2 0 nan 0\n");
    expect_error(particles_load_lammps, path, "particle 1: position is not finite");

    write_dump(path, "inf.dump", "2", "pp pp pp", "id x y z vx", "1 0 0 0 -inf\n2 0 0 0 0\n");
    expect_error(particles_load_lammps, path, "particle 0: attribute 'vx' is not finite");

    write_dump(path, "overflow.dump", "1", "pp pp pp", "x y z e", "0 0 0 1e39\n");
    expect_error(particles_load_lammps, path, "particle 0: attribute 'e' is not finite");

    char columns[68 * 8] = "x y z";
    for (int i = 0; i < 65; i++)
        snprintf(columns + strlen(columns), sizeof columns - strlen(columns), " c%d", i);
    write_dump(path, "many.dump", "1", "pp pp pp", columns, "0\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 9), "more than 67 columns (x y z and 64 attributes)");

    write_dump(path, "twice.dump", "1", "pp pp pp", "id x y z vx vx", "1 0 0 0 1 1\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 9), "ITEM: ATOMS: duplicate column 'vx'");

    write_dump(path, "long_name.dump", "1", "pp pp pp", "x y z c_a_column_name_of_32_characters", "0 0 0 0\n");
    expect_error(particles_load_lammps, path, "column name 'c_a_column_name_of_32_characters' longer than 31 characters");

    write_dump(path, "absurd.dump", "1000000", "pp pp pp", "id x y z", "1 0 0 0\n");
    /* an absurd count is the count's line's fault (line 4), not the ATOMS line's (9) */
    expect_error(particles_load_lammps, path, at_line(where, path, 4),
                 "NUMBER OF ATOMS 1000000: the rest of the file after line 9 (8 bytes) cannot hold that many lines of "
                 "4 columns");

    write_dump(path, "over_max.dump", "3000000000", "pp pp pp", "id x y z", "1 0 0 0\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 4),
                 "NUMBER OF ATOMS 3000000000: more than a particle set can hold");

    write_dump(path, "minus.dump", "-3", "pp pp pp", "id x y z", "1 0 0 0\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 4), "ITEM: NUMBER OF ATOMS: expected a count, got '-3'");

    write_dump(path, "tilted_scaled.dump", "1", "xy xz yz pp pp pp", "id xs ys zs", "1 0.5 0.5 0.5\n");
    expect_error(particles_load_lammps, path, "scaled coordinates (xs ys zs) in a triclinic box are not supported");

    write_text(path, "scaled_no_box.dump", "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: ATOMS xs ys zs\n0 0 0\n");
    expect_error(particles_load_lammps, path, "scaled coordinates (xs ys zs) need 'ITEM: BOX BOUNDS'");

    write_text(path, "box.dump", "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1 2\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 7), "box bounds: expected 2 numbers, got more");

    write_text(path, "box_word.dump", "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 one\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 7), "box bounds: expected a number, got 'one'");

    write_text(path, "step.dump", "ITEM: TIMESTEP\nzero\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 2), "ITEM: TIMESTEP: expected a time step");

    write_text(path, "no_count.dump", "ITEM: TIMESTEP\n0\nITEM: ATOMS x y z\n");
    expect_error(particles_load_lammps, path, "'ITEM: ATOMS' before 'ITEM: NUMBER OF ATOMS'");

    write_text(path, "unknown.dump", "ITEM: TIMESTEP\n0\nITEM: BONDS\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 3), "unknown section 'ITEM: BONDS'");

    write_text(path, "stray.dump", "ITEM: TIMESTEP\n0\nhello\n");
    expect_error(particles_load_lammps, path, at_line(where, path, 3), "expected an 'ITEM:' line, got 'hello'");

    write_text(path, "headless.dump", "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\n");
    expect_error(particles_load_lammps, path, "file ends before 'ITEM: ATOMS'");

    write_text(path, "empty.dump", "");
    expect_error(particles_load_lammps, path, "empty file");

    write_text(path, "cut_item.dump", "ITEM: TIMESTEP\n");
    expect_error(particles_load_lammps, path, "file ends after 'ITEM: TIMESTEP'");

    /* a control character in a quoted token stays out of the one-line message */
    write_dump(path, "control.dump", "1", "pp pp pp", "x y z", "0 0 \0335\n");
    expect_error(particles_load_lammps, path, "column 'z': expected a number, got '?5'");
}

/* A FIFO would block fopen until a writer came: refused before opening. */
Test(particle_load, special_files_are_refused_without_blocking, .timeout = 10)
{
    char path[PATH_BYTES];
    particle_set *(*const loads[])(const char *, tess_error *) = {particles_load, particles_load_ply,
                                                                  particles_load_lammps};
    snprintf(path, PATH_BYTES, "%s/pipe.dump", scratch_dir);
    cr_assert_eq(mkfifo(path, 0600), 0, "mkfifo %s", path);
    for (size_t i = 0; i < sizeof loads / sizeof loads[0]; i++)
        expect_error(loads[i], path, "cannot open: not a regular file");
    snprintf(path, PATH_BYTES, "%s/pipe", scratch_dir); /* no extension: particles_load looks inside */
    cr_assert_eq(mkfifo(path, 0600), 0, "mkfifo %s", path);
    expect_error(particles_load, path, "cannot open: not a regular file");
    snprintf(path, PATH_BYTES, "%s/folder.ply", scratch_dir);
    cr_assert_eq(mkdir(path, 0700), 0);
    for (size_t i = 0; i < sizeof loads / sizeof loads[0]; i++)
        expect_error(loads[i], path, "cannot open: not a regular file");
}
