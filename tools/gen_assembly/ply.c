/* ply.c - a layout flattened into one binary PLY mesh (ply.h). */
#include "ply.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "layout.h"
#include "mesh.h"
#include "shapes.h"

#define PLY_MAX_VERTICES 2147483647ull /* the face list's indices are PLY `int` */
#define OUT_BUFFER_BYTES (1u << 20)

/* A node's placement in the world: a rotation about x, then a translation. */
struct placement {
    double angle;
    double t[3];
};

/* The output buffer: little-endian records, written out when full. */
struct out_buf {
    FILE *f;
    unsigned char *data;
    size_t size;
    uint64_t written;
    bool failed;
};

static void out_flush(struct out_buf *o)
{
    if (!o->failed && o->size && fwrite(o->data, 1, o->size, o->f) != o->size)
        o->failed = true;
    o->written += o->size;
    o->size = 0;
}

static void out_u32(struct out_buf *o, uint32_t v)
{
    unsigned char *p = o->data + o->size;
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
    o->size += 4;
}

static void out_f32(struct out_buf *o, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    out_u32(o, bits);
}

/* Room for `bytes` more in the buffer (bytes < OUT_BUFFER_BYTES). */
static void out_room(struct out_buf *o, size_t bytes)
{
    if (o->size + bytes > OUT_BUFFER_BYTES)
        out_flush(o);
}

bool ga_ply_write(const struct ga_layout *layout, FILE *out, const char *path, struct ga_ply_stats *stats,
                  char *err, size_t err_bytes)
{
    size_t nn = layout->node_count, ns = layout->shape_count;
    struct ga_mesh *meshes = calloc(ns ? ns : 1, sizeof *meshes);
    struct placement *world = malloc((nn ? nn : 1) * sizeof *world);
    struct out_buf o = {out, malloc(OUT_BUFFER_BYTES), 0, 0, false};
    bool ok = false;
    memset(stats, 0, sizeof *stats);
    if (!meshes || !world || !o.data) {
        snprintf(err, err_bytes, "out of memory");
        goto done;
    }
    /* every distinct shape once; the normals are not written */
    for (size_t m = 0; m < ns; m++) {
        ga_mesh_init(&meshes[m]);
        if (!ga_shape_build(&layout->shapes[m], &meshes[m])) {
            snprintf(err, err_bytes, "out of memory tessellating a %s", ga_shape_kind_name(layout->shapes[m].kind));
            goto done;
        }
        free(meshes[m].normals);
        meshes[m].normals = NULL;
    }
    /* the world placements (parents come before their children) and the totals */
    for (size_t i = 0; i < nn; i++) {
        const struct ga_node *n = &layout->nodes[i];
        struct placement p = {0.0, {0.0, 0.0, 0.0}};
        if (n->parent >= 0)
            p = world[n->parent];
        double c = cos(p.angle), s = sin(p.angle);
        world[i].angle = p.angle + n->rotation_x;
        world[i].t[0] = p.t[0] + n->translation[0];
        world[i].t[1] = p.t[1] + c * n->translation[1] - s * n->translation[2];
        world[i].t[2] = p.t[2] + s * n->translation[1] + c * n->translation[2];
        if (n->shape >= 0) {
            stats->vertices += meshes[n->shape].vertex_count;
            stats->triangles += ga_mesh_triangle_count(&meshes[n->shape]);
        }
    }
    if (stats->vertices > PLY_MAX_VERTICES) {
        snprintf(err, err_bytes, "%llu placed vertices, over a PLY int index (%llu): ask for fewer triangles",
                 (unsigned long long)stats->vertices, PLY_MAX_VERTICES);
        goto done;
    }
    char head[512];
    int hn = snprintf(head, sizeof head,
                      "ply\nformat binary_little_endian 1.0\n"
                      "comment gen-assembly: %zu parts flattened, node transforms baked in\n"
                      "element vertex %llu\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face %llu\nproperty list uchar int vertex_indices\nend_header\n",
                      layout->part_count, (unsigned long long)stats->vertices, (unsigned long long)stats->triangles);
    memcpy(o.data, head, (size_t)hn);
    o.size = (size_t)hn;
    /* the vertices, part by part */
    for (size_t i = 0; i < nn; i++) {
        const struct ga_node *n = &layout->nodes[i];
        if (n->shape < 0)
            continue;
        const struct ga_mesh *m = &meshes[n->shape];
        const struct placement *w = &world[i];
        double c = cos(w->angle), s = sin(w->angle);
        for (size_t v = 0; v < m->vertex_count; v++) {
            const float *q = m->positions + 3 * v;
            double x = q[0], y = q[1], z = q[2];
            out_room(&o, 12);
            out_f32(&o, (float)(w->t[0] + x));
            out_f32(&o, (float)(w->t[1] + c * y - s * z));
            out_f32(&o, (float)(w->t[2] + s * y + c * z));
        }
    }
    /* the faces, part by part, offset by the vertices of the parts before */
    uint64_t base = 0;
    for (size_t i = 0; i < nn; i++) {
        const struct ga_node *n = &layout->nodes[i];
        if (n->shape < 0)
            continue;
        const struct ga_mesh *m = &meshes[n->shape];
        for (size_t k = 0; k + 2 < m->index_count; k += 3) {
            out_room(&o, 13);
            o.data[o.size++] = 3;
            for (int j = 0; j < 3; j++)
                out_u32(&o, (uint32_t)(base + m->indices[k + (size_t)j]));
        }
        base += m->vertex_count;
    }
    errno = 0;
    out_flush(&o);
    if (o.failed || fflush(out) != 0) {
        snprintf(err, err_bytes, "cannot write %s: %s", path, errno ? strerror(errno) : "write failed");
        goto done;
    }
    stats->bytes = o.written;
    ok = true;
done:
    if (meshes)
        for (size_t m = 0; m < ns; m++)
            ga_mesh_finish(&meshes[m]);
    free(meshes);
    free(world);
    free(o.data);
    return ok;
}
