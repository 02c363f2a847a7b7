/* test_volume.c - the regular volume and its readers (engine/geometry/volume/volume.h):
 * raw data with a text header and NRRD (detached and attached), on files
 * written here, and every refusal a broken header must give: one line that
 * names the file, the field and the problem, and no volume.
 *
 * Every test writes into a fresh mkdtemp directory (removed after the test).
 * Multi-byte samples are written byte by byte in the declared order, so the
 * tests hold on hosts of either endianness. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/geometry/volume/volume.h"
#include "support.h"
#include "engine/load/volume_read.h"

#define PATH_BYTES 512

static char scratch_dir[128];

static void scratch_create(void) { support_make_tmp_dir(scratch_dir, sizeof scratch_dir, "volume"); }

static void scratch_remove(void) { support_remove_tmp_dir(scratch_dir); }

TestSuite(volume, .init = scratch_create, .fini = scratch_remove);

static const char *scratch_path(char out[PATH_BYTES], const char *name)
{
    snprintf(out, PATH_BYTES, "%s/%.200s", scratch_dir, name);
    return out;
}

static void write_bytes(const char *name, const void *data, size_t n)
{
    char path[PATH_BYTES];
    FILE *f = fopen(scratch_path(path, name), "wb");
    cr_assert_not_null(f, "%s", path);
    cr_assert_eq(fwrite(data, 1, n, f), n);
    cr_assert_eq(fclose(f), 0);
}

static void write_text(const char *name, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void write_text(const char *name, const char *fmt, ...)
{
    char text[4096];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    cr_assert(n >= 0 && (size_t)n < sizeof text);
    write_bytes(name, text, (size_t)n);
}

/* 16-bit samples as bytes in the given order */
static void put_u16(unsigned char *out, uint16_t v, bool big)
{
    out[big ? 1 : 0] = (unsigned char)(v & 0xFF);
    out[big ? 0 : 1] = (unsigned char)(v >> 8);
}

static void put_f32(unsigned char *out, float f, bool big)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    for (int b = 0; b < 4; b++)
        out[big ? 3 - b : b] = (unsigned char)(u >> (8 * b));
}

/* Load `name` from the scratch directory; the volume (NULL on failure, err set). */
static volume *load(const char *name, tess_error *err)
{
    char path[PATH_BYTES];
    return volume_load(scratch_path(path, name), err);
}

/* Loading `name` fails with one line that starts with the scratch path of
 * `blamed` (the header named) and contains `expect`. */
static void expect_refused(const char *name, const char *blamed, const char *expect)
{
    tess_error err = {{0}};
    volume *v = load(name, &err);
    cr_assert_null(v, "%s loaded but should be refused (%s)", name, expect);
    char path[PATH_BYTES];
    scratch_path(path, blamed);
    cr_assert(strncmp(err.msg, path, strlen(path)) == 0, "message does not start with %s: %s", path, err.msg);
    cr_assert(strstr(err.msg, expect), "message lacks '%s': %s", expect, err.msg);
    cr_assert_null(strchr(err.msg, '\n'));
}

/* ---- the raw + text header ---------------------------------------------- */

/* a 3 x 2 x 2 uint8 volume, sample (i, j, k) = 10 * (i + 3 * (j + 2 * k)) + 1 */
static void write_u8_volume(const char *raw_name)
{
    unsigned char s[12];
    for (int i = 0; i < 12; i++)
        s[i] = (unsigned char)(10 * i + 1);
    write_bytes(raw_name, s, sizeof s);
}

Test(volume, txt_uint8_with_comments)
{
    write_u8_volume("head.raw");
    write_text("head.txt", "file:     head.raw\n"
                           "what:     a test volume\n"
                           "          (a continuation line: dims: 9 x 9 x 9 here is not a field)\n"
                           "dims:     3 x 2 x 2   (x fastest, then y, then z; no header)\n"
                           "type:     uint8 (values 1..111)\n"
                           "bytes:    12 = 3*2*2\n"
                           "spacing:  0.5 0.25 2 mm\n"
                           "origin:   -75.0 -107.0 -69.5 mm   (world position of voxel (0,0,0))\n");
    tess_error err = {{0}};
    volume *v = load("head.txt", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(v->nx, 3);
    cr_assert_eq(v->ny, 2);
    cr_assert_eq(v->nz, 2);
    cr_assert_eq(v->type, VOLUME_UINT8);
    cr_assert_eq(v->spacing[0], 0.5);
    cr_assert_eq(v->spacing[1], 0.25);
    cr_assert_eq(v->spacing[2], 2.0);
    cr_assert_eq(v->origin[0], -75.0);
    cr_assert_eq(v->origin[2], -69.5);
    cr_assert_eq(volume_sample(v, 0, 0, 0), 1.0f);
    cr_assert_eq(volume_sample(v, 2, 1, 0), 51.0f);
    cr_assert_eq(volume_sample(v, 1, 0, 1), 71.0f);
    cr_assert_eq(v->min, 1.0f);
    cr_assert_eq(v->max, 111.0f);
    cr_assert_not_null(v->map, "little-endian uint8 data is mapped, not copied");
    float c[8];
    volume_cell_corners(v, 1, 0, 0, c);
    cr_assert_eq(c[0], 11.0f);
    cr_assert_eq(c[1], 21.0f);
    cr_assert_eq(c[2], 41.0f);
    cr_assert_eq(c[7], 111.0f);
    volume_destroy(v);

    /* the .raw name finds its header */
    v = load("head.raw", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(v->nx, 3);
    volume_destroy(v);
}

/* the CT bunny's header: "16-bit little endian. Read as int16", negative samples */
Test(volume, txt_read_as_int16)
{
    const uint16_t samples[4] = {0, 2648, 63536 /* -2000 */, 1024};
    unsigned char raw[8];
    for (int i = 0; i < 4; i++)
        put_u16(raw + 2 * i, samples[i], false);
    write_bytes("ct.raw", raw, sizeof raw);
    write_text("ct.txt", "file: ct.raw\n"
                         "dims: 2 x 2 x 1\n"
                         "type:     16-bit little endian. Read as int16: 0..2648 = Hounsfield units + 1024 (air ~ 0..100),\n"
                         "          -2000 (uint16 63536) = outside the scanner's reconstruction circle\n"
                         "spacing:  0.675782 0.675782 1.0 mm   (full scan: 0.337891 0.337891 0.5)\n");
    tess_error err = {{0}};
    volume *v = load("ct.txt", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(v->type, VOLUME_INT16);
    cr_assert_eq(volume_sample(v, 0, 1, 0), -2000.0f);
    cr_assert_eq(volume_sample(v, 1, 0, 0), 2648.0f);
    cr_assert_eq(v->min, -2000.0f);
    cr_assert_eq(v->max, 2648.0f);
    cr_assert_eq(v->origin[0], 0.0, "origin defaults to 0");
    volume_destroy(v);

    /* the same bytes read unsigned, by a signedness word */
    write_text("ct.txt", "file: ct.raw\ndims: 2 x 2 x 1\ntype: 16-bit unsigned\n");
    v = load("ct.txt", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(v->type, VOLUME_UINT16);
    cr_assert_eq(volume_sample(v, 0, 1, 0), 63536.0f);
    volume_destroy(v);

    /* "uint16 ..., read as signed" */
    write_text("ct.txt", "file: ct.raw\ndims: 2 x 2 x 1\ntype: uint16, read as signed\n");
    v = load("ct.txt", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(v->type, VOLUME_INT16);
    volume_destroy(v);
}

Test(volume, txt_big_endian_and_float)
{
    unsigned char raw[16];
    const float values[4] = {-1.5f, 0.25f, 3e5f, 7.0f};
    for (int i = 0; i < 4; i++)
        put_f32(raw + 4 * i, values[i], true);
    write_bytes("f.raw", raw, sizeof raw);
    write_text("f.txt", "file: f.raw\ndims: 1x4x1\ntype: float32, big endian\n");
    tess_error err = {{0}};
    volume *v = load("f.txt", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(v->type, VOLUME_FLOAT32);
    for (uint32_t j = 0; j < 4; j++)
        cr_assert_eq(volume_sample(v, 0, j, 0), values[j]);
    cr_assert_eq(v->min, -1.5f);
    cr_assert_eq(v->max, 3e5f);
    cr_assert_null(v->map, "big-endian data is read and swapped");
    volume_destroy(v);

    unsigned char raw16[4];
    put_u16(raw16, 0x1234, true);
    put_u16(raw16 + 2, 0xFEDC, true);
    write_bytes("u.raw", raw16, sizeof raw16);
    write_text("u.txt", "file: u.raw\ndims: 2 x 1 x 1\ntype: uint16 big endian\n");
    v = load("u.txt", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(volume_sample(v, 0, 0, 0), (float)0x1234);
    cr_assert_eq(volume_sample(v, 1, 0, 0), (float)0xFEDC);
    volume_destroy(v);
}

Test(volume, txt_errors)
{
    write_u8_volume("v.raw");
    write_text("a.txt", "file: v.raw\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", "missing field 'dims'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\n");
    expect_refused("a.txt", "a.txt", "missing field 'type'");
    write_text("a.txt", "dims: 3 x 2 x 2\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", "missing field 'file'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", ":2: field 'dims': expected 'NX x NY x NZ'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2 x 1\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", ":2: field 'dims'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 0 x 2\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", "size 0 along y");
    /* products that overflow 64 bits, or merely exceed the cap, are refused before any allocation */
    write_text("a.txt", "file: v.raw\ndims: 4294967295 x 4294967295 x 4294967295\ntype: float32\n");
    expect_refused("a.txt", "a.txt", "along x is not in 1..");
    write_text("a.txt", "file: v.raw\ndims: 1048576 x 1048576 x 1048576\ntype: float32\n");
    expect_refused("a.txt", "a.txt", "more than the");
    write_text("a.txt", "file: v.raw\ndims: 99999999999999999999999 x 1 x 1\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", "field 'dims'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: complex128\n");
    expect_refused("a.txt", "a.txt", ":3: field 'type': unknown type");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: 16-bit little endian\n");
    expect_refused("a.txt", "a.txt", "16-bit without 'signed'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: int16 unsigned\n");
    expect_refused("a.txt", "a.txt", "says 'unsigned'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: 16-bit read as uint8\n");
    expect_refused("a.txt", "a.txt", "bit width disagrees");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint8 little endian big endian\n");
    expect_refused("a.txt", "a.txt", "both little and big");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint8\nspacing: 1 0 1 mm\n");
    expect_refused("a.txt", "a.txt", ":4: field 'spacing': 0 along y is not positive");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint8\nspacing: 1 -2 1\n");
    expect_refused("a.txt", "a.txt", "not positive");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint8\nspacing: 1 1\n");
    expect_refused("a.txt", "a.txt", "field 'spacing': expected three finite numbers");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint8\norigin: 1 nan 1\n");
    expect_refused("a.txt", "a.txt", "field 'origin'");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint8\nbytes: 13\n");
    expect_refused("a.txt", "a.txt", "field 'bytes': 13, but dims and type make 3*2*2 uint8 = 12");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ndims: 3 x 2 x 2\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", ":3: field 'dims' given again");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint8\nthis line has no colon\n");
    expect_refused("a.txt", "a.txt", ":4: expected 'field: value'");
    write_text("a.txt", "file: missing.raw\ndims: 3 x 2 x 2\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", "data file");
    /* dims x type size against the data file: too short, too long */
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 3\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", "v.raw: truncated: 12 bytes, the header says 3*2*3 uint8 = 18");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 1\ntype: uint8\n");
    expect_refused("a.txt", "a.txt", "v.raw: 12 bytes, the header says 3*2*1 uint8 = 6");
    write_text("a.txt", "file: v.raw\ndims: 3 x 2 x 2\ntype: uint16\n");
    expect_refused("a.txt", "a.txt", "3*2*2 uint16 = 24");
    write_text("b.raw", "x");
    expect_refused("b.raw", "b.raw", "needs its header");
    write_text("a.dat", "x");
    expect_refused("a.dat", "a.dat", "not a volume this reader knows");
}

Test(volume, float_data_must_be_finite)
{
    unsigned char raw[8];
    put_f32(raw, 1.0f, false);
    put_f32(raw + 4, NAN, false);
    write_bytes("n.raw", raw, sizeof raw);
    write_text("n.txt", "file: n.raw\ndims: 2 x 1 x 1\ntype: float32\n");
    expect_refused("n.txt", "n.txt", "n.raw: sample (1, 0, 0) is NaN");
}

/* ---- NRRD ------------------------------------------------------------------ */

Test(volume, nhdr_detached)
{
    write_u8_volume("d.raw");
    write_text("d.nhdr", "NRRD0004\n"
                         "# a comment\n"
                         "type: unsigned char\n"
                         "dimension: 3\n"
                         "sizes: 3 2 2\n"
                         "encoding: raw\n"
                         "spacings: 0.5 0.5 1.5\n"
                         "creator:=someone\n"
                         "data file: d.raw\n");
    tess_error err = {{0}};
    volume *v = load("d.nhdr", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(v->type, VOLUME_UINT8);
    cr_assert_eq(v->spacing[2], 1.5);
    cr_assert_eq(volume_sample(v, 2, 1, 1), 111.0f);
    volume_destroy(v);
}

/* attached data after the blank line: big-endian short, space directions, an
 * odd header length (the samples are then unaligned and copied) */
Test(volume, nrrd_attached_big_endian)
{
    const char *header = "NRRD0005\n"
                         "type: short\n"
                         "dimension: 3\n"
                         "space: left-posterior-superior\n"
                         "sizes: 2 1 2\n"
                         "space directions: (0.5,0,0) (0, 0.75, 0) (0,0,2)\n"
                         "space origin: (-10,20.5,3)\n"
                         "endian: big\n"
                         "encoding: raw\n"
                         "kinds: domain domain domain\n\n";
    for (int pad = 0; pad < 2; pad++) {
        unsigned char file[512];
        size_t len = 0;
        if (pad) {
            /* a comment one byte long shifts the samples by one */
            memcpy(file, "NRRD0005\n#\n", 11);
            len = 11;
            size_t rest = strlen(header) - 9;
            memcpy(file + len, header + 9, rest);
            len += rest;
        } else {
            memcpy(file, header, strlen(header));
            len = strlen(header);
        }
        const int16_t s[4] = {-3, 300, 32767, -32768};
        for (int i = 0; i < 4; i++, len += 2)
            put_u16(file + len, (uint16_t)s[i], true);
        write_bytes("a.nrrd", file, len);
        tess_error err = {{0}};
        volume *v = load("a.nrrd", &err);
        cr_assert_not_null(v, "%s", err.msg);
        cr_assert_eq(v->type, VOLUME_INT16);
        cr_assert_eq(v->nx, 2);
        cr_assert_eq(v->nz, 2);
        cr_assert_eq(v->spacing[0], 0.5);
        cr_assert_eq(v->spacing[1], 0.75);
        cr_assert_eq(v->spacing[2], 2.0);
        cr_assert_eq(v->origin[0], -10.0);
        cr_assert_eq(v->origin[1], 20.5);
        cr_assert_eq(v->origin[2], 3.0);
        for (int i = 0; i < 4; i++)
            cr_assert_eq(volume_sample(v, (uint32_t)i % 2, 0, (uint32_t)i / 2), (float)s[i]);
        cr_assert_eq(v->min, -32768.0f);
        cr_assert_eq(v->max, 32767.0f);
        volume_destroy(v);
    }
}

Test(volume, nrrd_little_endian_mapped_and_byte_skip)
{
    const char *header = "NRRD0004\ntype: ushort\ndimension: 3\nsizes: 2 2 1\nendian: little\nencoding: raw\n\n";
    unsigned char file[256];
    size_t len = strlen(header);
    cr_assert_eq(len % 2, 0, "the samples start aligned");
    memcpy(file, header, len);
    for (int i = 0; i < 4; i++, len += 2)
        put_u16(file + len, (uint16_t)(1000 * i + 7), false);
    write_bytes("m.nrrd", file, len);
    tess_error err = {{0}};
    volume *v = load("m.nrrd", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_not_null(v->map);
    cr_assert_eq(volume_sample(v, 1, 1, 0), 3007.0f);
    volume_destroy(v);

    /* detached, byte skip -1: the samples are the file's last bytes */
    unsigned char data[11] = {'j', 'u', 'n', 'k'};
    for (int i = 0; i < 4; i++)
        put_u16(data + 3 + 2 * i, (uint16_t)(i + 1), false);
    write_bytes("s.raw", data, sizeof data);
    write_text("s.nhdr", "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 2 2 1\nendian: little\nencoding: raw\n"
                         "byte skip: -1\ndata file: s.raw\n");
    v = load("s.nhdr", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(volume_sample(v, 0, 0, 0), 1.0f);
    cr_assert_eq(volume_sample(v, 1, 1, 0), 4.0f);
    volume_destroy(v);

    /* no extension: a NRRD by its magic */
    write_bytes("noext", file, len);
    v = load("noext", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(volume_sample(v, 1, 1, 0), 3007.0f);
    volume_destroy(v);

    /* byte skip 3 */
    write_text("s.nhdr", "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 2 2 1\nendian: little\nencoding: raw\n"
                         "byte skip: 3\ndata file: s.raw\n");
    v = load("s.nhdr", &err);
    cr_assert_not_null(v, "%s", err.msg);
    cr_assert_eq(volume_sample(v, 1, 1, 0), 4.0f);
    volume_destroy(v);
}

/* a NRRD header with one line replaced (or, for an empty `line`, dropped): the
 * valid base is uchar 3 x 2 x 2 with d.raw as data */
static void write_nhdr_with(const char *name, const char *field, const char *line)
{
    static const char *base[] = {
        "type: uchar", "dimension: 3", "sizes: 3 2 2", "encoding: raw", "data file: d.raw",
    };
    char text[2048] = "NRRD0004\n";
    bool replaced = false;
    for (size_t i = 0; i < sizeof base / sizeof base[0]; i++) {
        if (strncmp(base[i], field, strlen(field)) == 0) {
            replaced = true;
            if (line[0]) {
                strcat(text, line);
                strcat(text, "\n");
            }
            continue;
        }
        strcat(text, base[i]);
        strcat(text, "\n");
    }
    if (!replaced) {
        strcat(text, line);
        strcat(text, "\n");
    }
    write_text(name, "%s", text);
}

Test(volume, nrrd_errors)
{
    write_u8_volume("d.raw");
    write_nhdr_with("e.nhdr", "x", "");
    tess_error err = {{0}};
    volume *v = load("e.nhdr", &err);
    cr_assert_not_null(v, "the base header loads: %s", err.msg);
    volume_destroy(v);

    write_text("e.nhdr", "NRRD0009\ntype: uchar\n");
    expect_refused("e.nhdr", "e.nhdr", ":1: expected the magic");
    write_text("e.nhdr", "%s", "");
    expect_refused("e.nhdr", "e.nhdr", "empty file");
    write_nhdr_with("e.nhdr", "encoding", "encoding: gzip");
    expect_refused("e.nhdr", "e.nhdr", "field 'encoding': 'gzip' is not supported (raw only)");
    write_nhdr_with("e.nhdr", "encoding", "");
    expect_refused("e.nhdr", "e.nhdr", "missing field 'encoding'");
    write_nhdr_with("e.nhdr", "type", "type: double");
    expect_refused("e.nhdr", "e.nhdr", "field 'type': not supported: 'double'");
    write_nhdr_with("e.nhdr", "type", "type: quaternion");
    expect_refused("e.nhdr", "e.nhdr", "field 'type': unknown type 'quaternion'");
    write_nhdr_with("e.nhdr", "type", "type: short");
    expect_refused("e.nhdr", "e.nhdr", "missing field 'endian'");
    write_nhdr_with("e.nhdr", "type", "type: short\nendian: middle");
    expect_refused("e.nhdr", "e.nhdr", "field 'endian': expected 'little' or 'big'");
    write_nhdr_with("e.nhdr", "dimension", "dimension: 4");
    expect_refused("e.nhdr", "e.nhdr", "field 'dimension': '4', only 3");
    write_nhdr_with("e.nhdr", "sizes", "sizes: 3 2");
    expect_refused("e.nhdr", "e.nhdr", "field 'sizes': expected three positive integers");
    write_nhdr_with("e.nhdr", "sizes", "sizes: 3 2 2 1");
    expect_refused("e.nhdr", "e.nhdr", "field 'sizes': more than three");
    write_nhdr_with("e.nhdr", "sizes", "sizes: 3 -2 2");
    expect_refused("e.nhdr", "e.nhdr", "field 'sizes'");
    write_nhdr_with("e.nhdr", "sizes", "sizes: 2000000 2000000 2000000");
    expect_refused("e.nhdr", "e.nhdr", "not in 1..");
    write_nhdr_with("e.nhdr", "sizes", "sizes: 3 2 3");
    expect_refused("e.nhdr", "e.nhdr", "d.raw: truncated: 12 bytes");
    write_nhdr_with("e.nhdr", "x", "spacings: 1 nan 1");
    expect_refused("e.nhdr", "e.nhdr", "field 'spacings': expected three positive numbers");
    write_nhdr_with("e.nhdr", "x", "spacings: 1 0 1");
    expect_refused("e.nhdr", "e.nhdr", "field 'spacings'");
    write_nhdr_with("e.nhdr", "x", "space directions: (0.7071,0.7071,0) (-0.7071,0.7071,0) (0,0,1)");
    expect_refused("e.nhdr", "e.nhdr", "rotated or permuted axes are not supported");
    write_nhdr_with("e.nhdr", "x", "space directions: (0,1,0) (1,0,0) (0,0,1)");
    expect_refused("e.nhdr", "e.nhdr", "axis-aligned only");
    write_nhdr_with("e.nhdr", "x", "space directions: (-1,0,0) (0,1,0) (0,0,1)");
    expect_refused("e.nhdr", "e.nhdr", "flipped axis");
    write_nhdr_with("e.nhdr", "x", "space directions: (1,0,0) none (0,0,1)");
    expect_refused("e.nhdr", "e.nhdr", "field 'space directions': expected three vectors");
    write_nhdr_with("e.nhdr", "x", "spacings: 1 1 1\nspace directions: (1,0,0) (0,1,0) (0,0,1)");
    expect_refused("e.nhdr", "e.nhdr", "both 'spacings' and 'space directions'");
    write_nhdr_with("e.nhdr", "x", "space origin: (1,2)");
    expect_refused("e.nhdr", "e.nhdr", "field 'space origin'");
    write_nhdr_with("e.nhdr", "x", "space dimension: 2");
    expect_refused("e.nhdr", "e.nhdr", "field 'space dimension'");
    write_nhdr_with("e.nhdr", "x", "line skip: 2");
    expect_refused("e.nhdr", "e.nhdr", "field 'line skip': '2' is not supported");
    write_nhdr_with("e.nhdr", "x", "byte skip: lots");
    expect_refused("e.nhdr", "e.nhdr", "field 'byte skip'");
    write_nhdr_with("e.nhdr", "x", "type: uchar");
    expect_refused("e.nhdr", "e.nhdr", "field 'type' given again");
    write_nhdr_with("e.nhdr", "x", "nonsense line");
    expect_refused("e.nhdr", "e.nhdr", ":7: expected 'field: value'");
    write_nhdr_with("e.nhdr", "data file", "data file: nowhere.raw");
    expect_refused("e.nhdr", "e.nhdr", "nowhere.raw");
    write_nhdr_with("e.nhdr", "data file", "data file: LIST");
    expect_refused("e.nhdr", "e.nhdr", "several files");
    write_nhdr_with("e.nhdr", "data file", "");
    expect_refused("e.nhdr", "e.nhdr", "no blank line");

    /* attached data cut short */
    write_text("t.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 2 2\nencoding: raw\n\n0123456789");
    expect_refused("t.nrrd", "t.nrrd", "attached data: truncated: ");
    /* attached data with a byte too many */
    write_text("t.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 2 2\nencoding: raw\n\n0123456789abc");
    expect_refused("t.nrrd", "t.nrrd", "header bytes + 3*2*2 uint8");
}

Test(volume, create_and_range)
{
    tess_error err = {{0}};
    volume *v = volume_create(4, 3, 2, VOLUME_FLOAT32, &err);
    cr_assert_not_null(v, "%s", err.msg);
    float *s = volume_voxels(v);
    for (size_t i = 0; i < volume_count(v); i++)
        s[i] = (float)i - 5.0f;
    cr_assert(volume_update_range(v, "test", &err));
    cr_assert_eq(v->min, -5.0f);
    cr_assert_eq(v->max, 18.0f);
    cr_assert_eq(volume_sample(v, 3, 2, 1), 18.0f);
    volume_destroy(v);
    volume_destroy(NULL);
    cr_assert_null(volume_create(0, 1, 1, VOLUME_UINT8, &err));
    cr_assert(strstr(err.msg, "along x"), "%s", err.msg);
}
