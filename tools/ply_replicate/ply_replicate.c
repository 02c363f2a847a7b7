/* ply_replicate.c - ply-replicate: a mesh copied onto a grid, written as one
 * binary little-endian PLY mesh, for benchmarks of one very large mesh (the
 * 4 M-triangle CT bunny 5 x 5 times is 100 M triangles).
 *
 *     build/ply-replicate [--grid CxR] [--gap G] -o OUT.ply IN
 *
 * IN is any mesh tessera loads (mesh_load: PLY, OBJ, glTF, ...). Copy (c, r),
 * c in [0, C), r in [0, R), is IN moved by c * (1 + G) * (extent along x) in
 * x and r * (1 + G) * (extent along z) in z, so copies never overlap (G > 0);
 * copies are numbered c + C * r and written in that order: first every
 * copy's vertices (float x y z; no normals or colours), then every copy's
 * triangles (list uchar int, 3 indices, the copy's vertices offset by
 * copy * vertices of IN). Only IN is held in memory; the copies are streamed.
 *
 * Prints one line:
 *     ply-replicate: copies=N triangles=T vertices=V bytes=B step=SX,SZ file=OUT
 * Errors: one line `ply-replicate: error: ...` on stderr, exit 2 for the
 * command line and 1 for the input or the output (then OUT is removed). */
#include <errno.h>
#include <inttypes.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/err.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/load/mesh_load.h"

#define MAX_GRID 1000
#define PLY_MAX_VERTICES 2147483647ull /* indices are PLY `int` */
#define OUT_BUFFER_BYTES (1u << 20)

static void usage(FILE *f)
{
    fprintf(f, "usage: ply-replicate [--grid CxR] [--gap G] -o OUT.ply IN\n"
               "Copy the mesh IN onto a C x R grid in the x-z plane (default 5x5), G times its extent apart\n"
               "(default 0.1), and write every copy as ONE binary little-endian PLY mesh: float x y z vertices\n"
               "and triangles as list uchar int. IN is any mesh tessera loads; only IN is held in memory.\n"
               "Prints: copies, triangles, vertices, bytes, step, file.\n");
}

static int usage_error(const char *what, const char *val)
{
    fprintf(stderr, "ply-replicate: error: %s%s%s%s (see ply-replicate --help)\n", what, val ? " '" : "",
            val ? val : "", val ? "'" : "");
    return 2;
}

/* The output buffer: little-endian records, written out when full. */
typedef struct out_buf {
    FILE *f;
    unsigned char *data;
    size_t size;
    uint64_t written;
    bool failed;
} out_buf;

static void out_flush(out_buf *o)
{
    if (!o->failed && o->size && fwrite(o->data, 1, o->size, o->f) != o->size)
        o->failed = true;
    o->written += o->size;
    o->size = 0;
}

static void out_u32(out_buf *o, uint32_t v)
{
    unsigned char *p = o->data + o->size;
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
    o->size += 4;
}

static void out_f32(out_buf *o, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    out_u32(o, bits);
}

static void out_room(out_buf *o, size_t bytes)
{
    if (o->size + bytes > OUT_BUFFER_BYTES)
        out_flush(o);
}

static bool parse_grid(const char *s, unsigned *c, unsigned *r)
{
    char *end;
    if (!s || s[0] < '1' || s[0] > '9')
        return false;
    errno = 0;
    unsigned long a = strtoul(s, &end, 10);
    if (errno || *end != 'x' || end[1] < '1' || end[1] > '9')
        return false;
    unsigned long b = strtoul(end + 1, &end, 10);
    if (errno || *end || a > MAX_GRID || b > MAX_GRID)
        return false;
    *c = (unsigned)a;
    *r = (unsigned)b;
    return true;
}

static bool parse_gap(const char *s, double *gap)
{
    char *end;
    if (!s || !s[0])
        return false;
    errno = 0;
    double g = strtod(s, &end);
    if (errno || *end || !(g >= 0.0 && g <= 100.0))
        return false;
    *gap = g;
    return true;
}

int main(int argc, char **argv)
{
    unsigned cols = 5, rows = 5;
    double gap = 0.1;
    const char *out_path = NULL, *in_path = NULL;
    for (int i = 1; i < argc; i++) {
        const char *opt = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(opt, "--help") || !strcmp(opt, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(opt, "--grid")) {
            if (!parse_grid(val, &cols, &rows))
                return usage_error("--grid: expected CxR, each 1 to 1000, got", val ? val : "nothing");
            i++;
        } else if (!strcmp(opt, "--gap")) {
            if (!parse_gap(val, &gap))
                return usage_error("--gap: expected a number from 0 to 100, got", val ? val : "nothing");
            i++;
        } else if (!strcmp(opt, "-o")) {
            if (!val || !val[0])
                return usage_error("-o needs a file", NULL);
            out_path = val;
            i++;
        } else if (opt[0] == '-' && opt[1]) {
            return usage_error("unknown option", opt);
        } else if (in_path) {
            return usage_error("more than one input mesh:", opt);
        } else {
            in_path = opt;
        }
    }
    if (!in_path || !out_path)
        return usage_error(!in_path ? "the input mesh IN is required" : "-o OUT.ply is required", NULL);

    tess_error err = {{0}};
    mesh *m = mesh_load(in_path, &err);
    if (!m) {
        fprintf(stderr, "ply-replicate: error: %s\n", err.msg);
        return 1;
    }
    float lo[3], hi[3];
    uint64_t copies = (uint64_t)cols * rows;
    uint64_t nv = m->vertex_count, nt = m->triangle_count;
    if (nt == 0 || !mesh_bounds(m, lo, hi)) {
        fprintf(stderr, "ply-replicate: error: %s: no triangles to copy\n", in_path);
        mesh_destroy(m);
        return 1;
    }
    if (copies * nv > PLY_MAX_VERTICES) {
        fprintf(stderr, "ply-replicate: error: %" PRIu64 " copies of %" PRIu64 " vertices pass a PLY int index\n",
                copies, nv);
        mesh_destroy(m);
        return 1;
    }
    /* the step in double, each copy's offset rounded to float once */
    double step_x = (1.0 + gap) * ((double)hi[0] - lo[0]), step_z = (1.0 + gap) * ((double)hi[2] - lo[2]);

    FILE *f = fopen(out_path, "wb");
    out_buf o = {f, malloc(OUT_BUFFER_BYTES), 0, 0, false};
    if (!f || !o.data) {
        fprintf(stderr, "ply-replicate: error: cannot write %s: %s\n", out_path, f ? "out of memory" : strerror(errno));
        if (f) {
            fclose(f);
            remove(out_path);
        }
        free(o.data);
        mesh_destroy(m);
        return 1;
    }
    int hn = snprintf((char *)o.data, OUT_BUFFER_BYTES,
                      "ply\nformat binary_little_endian 1.0\n"
                      "comment ply-replicate: %ux%u copies, step %.9g %.9g\n"
                      "element vertex %" PRIu64 "\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face %" PRIu64 "\nproperty list uchar int vertex_indices\nend_header\n",
                      cols, rows, step_x, step_z, copies * nv, copies * nt);
    o.size = (size_t)hn;
    for (uint64_t k = 0; k < copies && !o.failed; k++) {
        float dx = (float)(step_x * (double)(k % cols)), dz = (float)(step_z * (double)(k / cols));
        for (uint64_t v = 0; v < nv; v++) {
            const float *p = m->positions + 3 * v;
            out_room(&o, 12);
            out_f32(&o, p[0] + dx);
            out_f32(&o, p[1]);
            out_f32(&o, p[2] + dz);
        }
    }
    for (uint64_t k = 0; k < copies && !o.failed; k++) {
        uint32_t base = (uint32_t)(k * nv);
        for (uint64_t t = 0; t < 3 * nt; t += 3) {
            out_room(&o, 13);
            o.data[o.size++] = 3;
            for (int j = 0; j < 3; j++)
                out_u32(&o, base + m->indices[t + (uint64_t)j]);
        }
    }
    errno = 0;
    out_flush(&o);
    bool ok = !o.failed;
    if (fclose(f) != 0)
        ok = false;
    free(o.data);
    mesh_destroy(m);
    if (!ok) {
        fprintf(stderr, "ply-replicate: error: cannot write %s: %s\n", out_path, errno ? strerror(errno) : "write failed");
        remove(out_path);
        return 1;
    }
    printf("ply-replicate: copies=%" PRIu64 " triangles=%" PRIu64 " vertices=%" PRIu64 " bytes=%" PRIu64
           " step=%.9g,%.9g file=%s\n",
           copies, copies * nt, copies * nv, o.written, step_x, step_z, out_path);
    return 0;
}
