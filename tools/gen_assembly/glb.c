/* glb.c - the binary glTF writer (glb.h). */
#include "glb.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "layout.h"
#include "mesh.h"
#include "shapes.h"

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the BIN chunk is copied from memory: glTF wants little-endian"
#endif

#define GLB_MAGIC 0x46546C67u      /* "glTF" */
#define GLB_CHUNK_JSON 0x4E4F534Au /* "JSON" */
#define GLB_CHUNK_BIN 0x004E4942u  /* "BIN\0" */
#define GLTF_FLOAT 5126
#define GLTF_UNSIGNED_INT 5125
#define GLTF_ARRAY_BUFFER 34962
#define GLTF_ELEMENT_ARRAY_BUFFER 34963
#define GLTF_TRIANGLES 4

/* ---- materials ------------------------------------------------------------ */

struct material {
    const char *name;
    double rgba[4];
    double metallic, roughness;
};

enum { MAT_ALUMINIUM, MAT_PRIMER, MAT_STEEL, MAT_PIPE, MAT_BRACKET, MAT_COUNT };

static const struct material materials[MAT_COUNT] = {
    [MAT_ALUMINIUM] = {"aluminium", {0.77, 0.78, 0.80, 1.0}, 1.0, 0.35},
    [MAT_PRIMER] = {"primer-green", {0.42, 0.58, 0.33, 1.0}, 0.0, 0.7},
    [MAT_STEEL] = {"steel", {0.28, 0.29, 0.31, 1.0}, 1.0, 0.4},
    [MAT_PIPE] = {"pipe-orange", {0.93, 0.45, 0.08, 1.0}, 0.0, 0.55},
    [MAT_BRACKET] = {"bracket-blue", {0.16, 0.33, 0.74, 1.0}, 0.0, 0.5},
};

static int material_of(enum ga_shape_kind kind)
{
    switch (kind) {
    case GA_SHAPE_FRAME:
    case GA_SHAPE_STRINGER_BOX:
    case GA_SHAPE_STRINGER_Z: return MAT_PRIMER;
    case GA_SHAPE_PIPE: return MAT_PIPE;
    case GA_SHAPE_BRACKET: return MAT_BRACKET;
    case GA_SHAPE_BOLT: return MAT_STEEL;
    case GA_SHAPE_SKIN:
    case GA_SHAPE_RIVET:
    case GA_SHAPE_KIND_COUNT: break;
    }
    return MAT_ALUMINIUM;
}

/* ---- growing byte buffers ------------------------------------------------- */

struct bytes {
    char *data;
    size_t size, cap;
    bool failed; /* sticky: out of memory */
};

static bool bytes_reserve(struct bytes *b, size_t more)
{
    if (b->failed)
        return false;
    if (b->size + more <= b->cap)
        return true;
    size_t cap = b->cap ? b->cap : 1 << 16;
    while (cap < b->size + more)
        cap *= 2;
    char *p = realloc(b->data, cap);
    if (!p) {
        b->failed = true;
        return false;
    }
    b->data = p;
    b->cap = cap;
    return true;
}

static void bytes_add(struct bytes *b, const void *data, size_t size)
{
    if (size && bytes_reserve(b, size)) {
        memcpy(b->data + b->size, data, size);
        b->size += size;
    }
}

static void json(struct bytes *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void json(struct bytes *b, const char *fmt, ...)
{
    char small[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) {
        b->failed = true;
        return;
    }
    if ((size_t)n < sizeof small) {
        bytes_add(b, small, (size_t)n);
        return;
    }
    if (!bytes_reserve(b, (size_t)n + 1))
        return;
    va_start(ap, fmt);
    vsnprintf(b->data + b->size, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->size += (size_t)n;
}

/* A number with `digits` significant digits; -0 prints as 0. */
static void json_num(struct bytes *b, double v, int digits)
{
    if (v == 0.0)
        v = 0.0;
    json(b, "%.*g", digits, v);
}

/* ---- meshes --------------------------------------------------------------- */

/* Where one shape's mesh went in the BIN chunk. */
struct stored {
    uint64_t offset;        /* of the positions; normals and indices follow */
    uint64_t vertices, indices;
    float min[3], max[3];   /* of the positions */
};

static bool store_mesh(const struct ga_shape *shape, struct bytes *bin, struct stored *st, char *err,
                       size_t err_bytes)
{
    struct ga_mesh mesh;
    ga_mesh_init(&mesh);
    bool ok = ga_shape_build(shape, &mesh);
    if (ok && ga_mesh_triangle_count(&mesh) != ga_shape_triangles(shape)) {
        snprintf(err, err_bytes, "internal error: a %s mesh has %zu triangles, %llu expected",
                 ga_shape_kind_name(shape->kind), ga_mesh_triangle_count(&mesh),
                 (unsigned long long)ga_shape_triangles(shape));
        ga_mesh_finish(&mesh);
        return false;
    }
    if (!ok) {
        snprintf(err, err_bytes, "out of memory tessellating a %s", ga_shape_kind_name(shape->kind));
        ga_mesh_finish(&mesh);
        return false;
    }
    st->offset = bin->size;
    st->vertices = mesh.vertex_count;
    st->indices = mesh.index_count;
    for (int a = 0; a < 3; a++) {
        st->min[a] = FLT_MAX;
        st->max[a] = -FLT_MAX;
    }
    for (size_t v = 0; v < mesh.vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            float x = mesh.positions[3 * v + (size_t)a];
            st->min[a] = x < st->min[a] ? x : st->min[a];
            st->max[a] = x > st->max[a] ? x : st->max[a];
        }
    bytes_add(bin, mesh.positions, mesh.vertex_count * 3 * sizeof(float));
    bytes_add(bin, mesh.normals, mesh.vertex_count * 3 * sizeof(float));
    bytes_add(bin, mesh.indices, mesh.index_count * sizeof(uint32_t));
    ga_mesh_finish(&mesh);
    if (bin->failed) {
        snprintf(err, err_bytes, "out of memory: the binary chunk reached %zu bytes", bin->size);
        return false;
    }
    return true;
}

/* ---- JSON ----------------------------------------------------------------- */

static void json_node(struct bytes *j, const struct ga_layout *layout, size_t i, const size_t *child_start,
                      const uint32_t *children)
{
    const struct ga_node *n = &layout->nodes[i];
    json(j, "%s{\"name\":\"%s", i ? "," : "", ga_node_kind_name(n->kind));
    if (n->number)
        json(j, "-%u", n->number);
    json(j, "\"");
    if (n->shape >= 0)
        json(j, ",\"mesh\":%d", n->shape);
    if (n->translation[0] != 0.0 || n->translation[1] != 0.0 || n->translation[2] != 0.0) {
        json(j, ",\"translation\":[");
        for (int a = 0; a < 3; a++) {
            json(j, a ? "," : "");
            json_num(j, n->translation[a], 9);
        }
        json(j, "]");
    }
    if (n->rotation_x != 0.0) {
        /* a unit quaternion (x, y, z, w) about the x axis */
        json(j, ",\"rotation\":[");
        json_num(j, sin(0.5 * n->rotation_x), 9);
        json(j, ",0,0,");
        json_num(j, cos(0.5 * n->rotation_x), 9);
        json(j, "]");
    }
    if (child_start[i + 1] > child_start[i]) {
        json(j, ",\"children\":[");
        for (size_t c = child_start[i]; c < child_start[i + 1]; c++)
            json(j, "%s%u", c > child_start[i] ? "," : "", children[c]);
        json(j, "]");
    }
    json(j, "}");
}

static bool json_chunk(struct bytes *j, const struct ga_layout *layout, const struct stored *st, uint64_t bin_bytes)
{
    size_t nn = layout->node_count, ns = layout->shape_count;
    size_t *child_start = calloc(nn + 2, sizeof *child_start);
    uint32_t *children = malloc((nn ? nn : 1) * sizeof *children);
    if (!child_start || !children) {
        free(child_start);
        free(children);
        return false;
    }
    /* children of node i: children[child_start[i] .. child_start[i + 1]), in creation order */
    for (size_t i = 0; i < nn; i++)
        if (layout->nodes[i].parent >= 0)
            child_start[(size_t)layout->nodes[i].parent + 2]++;
    for (size_t i = 2; i < nn + 2; i++)
        child_start[i] += child_start[i - 1];
    for (size_t i = 0; i < nn; i++)
        if (layout->nodes[i].parent >= 0)
            children[child_start[(size_t)layout->nodes[i].parent + 1]++] = (uint32_t)i;

    json(j, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"tessera gen-assembly\"},");
    json(j, "\"scene\":0,\"scenes\":[{\"name\":\"assembly\",\"nodes\":[0]}],\"nodes\":[");
    for (size_t i = 0; i < nn; i++)
        json_node(j, layout, i, child_start, children);
    free(child_start);
    free(children);

    json(j, "],\"meshes\":[");
    uint32_t per_kind[GA_SHAPE_KIND_COUNT] = {0};
    for (size_t m = 0; m < ns; m++) {
        enum ga_shape_kind kind = layout->shapes[m].kind;
        /* both stringer profiles are "stringer-mesh-N", numbered together */
        enum ga_shape_kind counter = kind == GA_SHAPE_STRINGER_Z ? GA_SHAPE_STRINGER_BOX : kind;
        json(j, "%s{\"name\":\"%s-mesh-%u\",\"primitives\":[{\"attributes\":{\"POSITION\":%zu,\"NORMAL\":%zu},"
                "\"indices\":%zu,\"material\":%d,\"mode\":%d}]}",
             m ? "," : "", ga_shape_kind_name(kind), ++per_kind[counter], 3 * m, 3 * m + 1, 3 * m + 2,
             material_of(kind), GLTF_TRIANGLES);
    }
    json(j, "],\"materials\":[");
    for (int i = 0; i < MAT_COUNT; i++) {
        const struct material *mat = &materials[i];
        json(j, "%s{\"name\":\"%s\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[", i ? "," : "", mat->name);
        for (int c = 0; c < 4; c++) {
            json(j, c ? "," : "");
            json_num(j, mat->rgba[c], 6);
        }
        json(j, "],\"metallicFactor\":");
        json_num(j, mat->metallic, 6);
        json(j, ",\"roughnessFactor\":");
        json_num(j, mat->roughness, 6);
        json(j, "}}");
    }
    json(j, "],\"accessors\":[");
    for (size_t m = 0; m < ns; m++) {
        json(j, "%s{\"bufferView\":%zu,\"componentType\":%d,\"count\":%llu,\"type\":\"VEC3\",\"min\":[", m ? "," : "",
             3 * m, GLTF_FLOAT, (unsigned long long)st[m].vertices);
        for (int a = 0; a < 3; a++) {
            json(j, a ? "," : "");
            json_num(j, st[m].min[a], 9);
        }
        json(j, "],\"max\":[");
        for (int a = 0; a < 3; a++) {
            json(j, a ? "," : "");
            json_num(j, st[m].max[a], 9);
        }
        json(j, "]},{\"bufferView\":%zu,\"componentType\":%d,\"count\":%llu,\"type\":\"VEC3\"}", 3 * m + 1,
             GLTF_FLOAT, (unsigned long long)st[m].vertices);
        json(j, ",{\"bufferView\":%zu,\"componentType\":%d,\"count\":%llu,\"type\":\"SCALAR\"}", 3 * m + 2,
             GLTF_UNSIGNED_INT, (unsigned long long)st[m].indices);
    }
    json(j, "],\"bufferViews\":[");
    for (size_t m = 0; m < ns; m++) {
        unsigned long long at = st[m].offset, vb = 12ull * st[m].vertices, ib = 4ull * st[m].indices;
        json(j, "%s{\"buffer\":0,\"byteOffset\":%llu,\"byteLength\":%llu,\"target\":%d}", m ? "," : "", at, vb,
             GLTF_ARRAY_BUFFER);
        json(j, ",{\"buffer\":0,\"byteOffset\":%llu,\"byteLength\":%llu,\"target\":%d}", at + vb, vb,
             GLTF_ARRAY_BUFFER);
        json(j, ",{\"buffer\":0,\"byteOffset\":%llu,\"byteLength\":%llu,\"target\":%d}", at + 2 * vb, ib,
             GLTF_ELEMENT_ARRAY_BUFFER);
    }
    json(j, "],\"buffers\":[{\"byteLength\":%llu}]}", (unsigned long long)bin_bytes);
    /* the JSON chunk is padded with spaces to 4 bytes */
    while (j->size % 4)
        bytes_add(j, " ", 1);
    return !j->failed;
}

/* ---- the file ------------------------------------------------------------- */

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

bool ga_glb_write(const struct ga_layout *layout, FILE *out, const char *path, struct ga_glb_stats *stats,
                  char *err, size_t err_bytes)
{
    struct bytes bin = {0}, js = {0};
    struct stored *st = calloc(layout->shape_count ? layout->shape_count : 1, sizeof *st);
    bool ok = false;
    memset(stats, 0, sizeof *stats);
    if (!st) {
        snprintf(err, err_bytes, "out of memory");
        goto out;
    }
    for (size_t m = 0; m < layout->shape_count; m++) {
        if (!store_mesh(&layout->shapes[m], &bin, &st[m], err, err_bytes))
            goto out;
        stats->triangles_stored += st[m].indices / 3;
        if (layout->shape_uses[m] > 1)
            stats->instances += layout->shape_uses[m];
    }
    stats->meshes = layout->shape_count;
    if (!json_chunk(&js, layout, st, bin.size)) {
        snprintf(err, err_bytes, "out of memory writing the JSON chunk");
        goto out;
    }
    size_t bin_padded = (bin.size + 3) & ~(size_t)3;
    uint64_t total = 12 + 8 + (uint64_t)js.size + 8 + bin_padded;
    if (total > UINT32_MAX) {
        snprintf(err, err_bytes, "the file would be %llu bytes, over glb's 4 GiB: ask for fewer parts or triangles",
                 (unsigned long long)total);
        goto out;
    }
    unsigned char head[20], bin_head[8];
    put_u32(head, GLB_MAGIC);
    put_u32(head + 4, 2);
    put_u32(head + 8, (uint32_t)total);
    put_u32(head + 12, (uint32_t)js.size);
    put_u32(head + 16, GLB_CHUNK_JSON);
    put_u32(bin_head, (uint32_t)bin_padded);
    put_u32(bin_head + 4, GLB_CHUNK_BIN);
    static const unsigned char zeros[4] = {0};
    errno = 0;
    if (fwrite(head, 1, sizeof head, out) != sizeof head || fwrite(js.data, 1, js.size, out) != js.size ||
        fwrite(bin_head, 1, sizeof bin_head, out) != sizeof bin_head ||
        (bin.size && fwrite(bin.data, 1, bin.size, out) != bin.size) ||
        fwrite(zeros, 1, bin_padded - bin.size, out) != bin_padded - bin.size || fflush(out) != 0) {
        snprintf(err, err_bytes, "cannot write %s: %s", path, errno ? strerror(errno) : "write failed");
        goto out;
    }
    stats->bytes = total;
    ok = true;
out:
    free(st);
    free(bin.data);
    free(js.data);
    return ok;
}
