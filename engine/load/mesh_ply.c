/* mesh_ply.c - PLY meshes: ascii, binary_little_endian and binary_big_endian,
 * read through the shared PLY format level (engine/load/ply_read.h).
 *
 * Kept: the vertex element's x y z (required), nx ny nz and red green blue
 * (each group only when all three are present), and the face element's
 * vertex_indices (or vertex_index) list, fan-split into triangles. Every other
 * property and element is read past. Element numbers in messages count from 0,
 * line numbers from 1.
 *
 * Nothing here is global: one ply_loader per call, so loads run in parallel. */
#include "engine/geometry/triangles/mesh.h"

#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ply_read.h"
#include "engine/base/progress.h"
#include "mesh_load.h"

/* What the loader does with a property (its ply_property.role). ROLE_X..ROLE_BLUE
 * are consecutive: role - ROLE_X is the property's slot in a vertex (see
 * vertex_slot_names). ROLE_SKIP is ply_read's PLY_ROLE_SKIP. */
enum ply_role {
    ROLE_SKIP = PLY_ROLE_SKIP,
    ROLE_X,
    ROLE_Y,
    ROLE_Z,
    ROLE_NX,
    ROLE_NY,
    ROLE_NZ,
    ROLE_RED,
    ROLE_GREEN,
    ROLE_BLUE,
    ROLE_INDICES,
};

#define VERTEX_SLOTS 9
static const char *const vertex_slot_names[VERTEX_SLOTS] = {"x",  "y",  "z",     "nx",   "ny",
                                                            "nz", "red", "green", "blue"};

typedef struct ply_loader {
    ply_file f;               /* the file, its header and its messages */
    ply_element *vertex;      /* the vertex element (in f.elements), set once the header is read */
    ply_element *face;        /* the face element (in f.elements), or NULL when there is none */
    bool has_normals;         /* nx ny nz are all present */
    bool has_colors;          /* red green blue are all present */
    float color_range[3];     /* red/green/blue value meaning full intensity (255, 65535 or 1) */
    mesh *m;                  /* the result, owned by the loader until returned */
    uint32_t vertex_total;    /* vertices declared by the header: face indices must be below it */
    uint32_t triangle_total;  /* triangles written to m->indices so far */
    progress progress;        /* bytes of the file read, once the header is checked */
} ply_loader;

static uint32_t min_u32(uint64_t a, uint64_t b) { return (uint32_t)(a < b ? a : b); }

/* ---- records ----------------------------------------------------------- */

static inline float clamp_unit(float v) { return v < 0.f ? 0.f : v > 1.f ? 1.f : v; } /* NaN passes through */

/* Storage was reserved for what the file size allows; a file that grew since
 * it was measured gets more, up to the header's count. */
static bool grow_vertices(ply_loader *ld)
{
    uint64_t capacity = ld->m->vertex_capacity;
    uint64_t wanted = capacity + capacity / 2 + 1024;
    if (!mesh_reserve_vertices(ld->m, min_u32(wanted, ld->vertex_total)))
        return ply_fail(&ld->f, "out of memory for %" PRIu64 " vertices", wanted);
    return true;
}

static bool store_vertex(ply_loader *ld, uint32_t index, const float slot[VERTEX_SLOTS])
{
    for (int k = 0; k < 3; k++)
        if (!isfinite(slot[k]))
            return ply_fail(&ld->f, "vertex %" PRIu32 ": coordinate '%s' is %g (must be finite)", index,
                            vertex_slot_names[k], (double)slot[k]);
    mesh *m = ld->m;
    if (index >= m->vertex_capacity && !grow_vertices(ld))
        return false;
    memcpy(m->positions + 3 * (size_t)index, slot, 3 * sizeof(float));
    if (ld->has_normals)
        memcpy(m->normals + 3 * (size_t)index, slot + 3, 3 * sizeof(float));
    if (ld->has_colors)
        for (int k = 0; k < 3; k++)
            m->colors[3 * (size_t)index + (size_t)k] = clamp_unit(slot[6 + k] / ld->color_range[k]);
    return true;
}

static bool read_vertex(ply_loader *ld, const ply_element *e, uint32_t index)
{
    float slot[VERTEX_SLOTS] = {0};
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (p->role == ROLE_SKIP) {
            if (!ply_skip_property(&ld->f, e, index, p))
                return false;
            continue;
        }
        double v = 0;
        if (!ply_read_number(&ld->f, e, index, p->name, p->type, &v))
            return false;
        slot[p->role - ROLE_X] = ply_to_float(v);
    }
    return store_vertex(ld, index, slot);
}

/* Where a kept property sits in a fixed-size binary vertex record. */
typedef struct vertex_field {
    size_t offset;      /* bytes from the start of the record */
    enum ply_type type; /* its type */
    int slot;           /* index into a vertex's slots (role - ROLE_X) */
} vertex_field;

/* Binary vertices whose properties are all scalars: one block per record. */
static bool read_fixed_vertices(ply_loader *ld, const ply_element *e, size_t record)
{
    vertex_field fields[VERTEX_SLOTS];
    int field_count = 0;
    size_t offset = 0;
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (p->role != ROLE_SKIP)
            fields[field_count++] = (vertex_field){offset, p->type, p->role - ROLE_X};
        offset += ply_type_bytes(p->type);
    }
    bool big = ld->f.format == PLY_BINARY_BE;
    for (uint32_t v = 0; v < ld->vertex_total; v++) {
        const unsigned char *bytes = ply_take(&ld->f.in, record);
        if (!bytes)
            return ply_fail_input(&ld->f, e, v, false);
        float slot[VERTEX_SLOTS] = {0};
        for (int k = 0; k < field_count; k++)
            slot[fields[k].slot] = ply_to_float(ply_decode_number(bytes + fields[k].offset, fields[k].type, big));
        if (!store_vertex(ld, v, slot))
            return false;
    }
    return true;
}

static bool grow_triangles(ply_loader *ld)
{
    uint32_t capacity = ld->m->triangle_capacity;
    if (capacity == UINT32_MAX)
        return ply_fail(&ld->f, "more than %" PRIu32 " triangles", UINT32_MAX);
    uint64_t wanted = (uint64_t)capacity + capacity / 2 + 1024;
    if (!mesh_reserve_triangles(ld->m, wanted > UINT32_MAX ? UINT32_MAX : (uint32_t)wanted))
        return ply_fail(&ld->f, "out of memory for %" PRIu64 " triangles", wanted);
    return true;
}

static inline bool emit_triangle(ply_loader *ld, uint32_t a, uint32_t b, uint32_t c)
{
    if (ld->triangle_total == ld->m->triangle_capacity && !grow_triangles(ld))
        return false;
    uint32_t *t = ld->m->indices + 3 * (size_t)ld->triangle_total++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    return true;
}

static bool index_error(ply_loader *ld, uint32_t face, int64_t v)
{
    if (v < 0)
        return ply_fail(&ld->f, "face %" PRIu32 ": negative vertex index %" PRId64, face, v);
    return ply_fail(&ld->f, "face %" PRIu32 ": vertex index %" PRId64 " out of range (file has %" PRIu32 " vertices)",
                    face, v, ld->vertex_total);
}

/* Fan-split state of one polygon: (v0, v1, v2), (v0, v2, v3), ... */
typedef struct polygon_fan {
    uint32_t first;  /* the polygon's first vertex */
    uint32_t prev;   /* the vertex before the current one */
    uint32_t corner; /* vertices seen so far */
} polygon_fan;

static inline bool fan_add(ply_loader *ld, polygon_fan *fan, uint32_t face, int64_t v)
{
    if ((uint64_t)v >= ld->vertex_total) /* a negative v wraps to a huge value */
        return index_error(ld, face, v);
    if (fan->corner == 0)
        fan->first = (uint32_t)v;
    else if (fan->corner >= 2 && !emit_triangle(ld, fan->first, fan->prev, (uint32_t)v))
        return false;
    fan->prev = (uint32_t)v;
    fan->corner++;
    return true;
}

/* Most polygons are this short; a binary one is then decoded from one block. */
#define POLYGON_BLOCK_MAX 64

/* One face's index list, fan-split into triangles. */
static bool read_polygon(ply_loader *ld, const ply_element *e, uint32_t face, const ply_property *p)
{
    int64_t n;
    if (!ply_read_integer(&ld->f, e, face, p->name, p->count_type, &n))
        return false;
    if (n < 3)
        return ply_fail(&ld->f, "face %" PRIu32 ": has %" PRId64 " vertices (a face needs at least 3)", face, n);
    polygon_fan fan = {0};
    if (ld->f.format != PLY_ASCII && n <= POLYGON_BLOCK_MAX) {
        unsigned size = ply_type_bytes(p->type);
        const unsigned char *block = ply_take(&ld->f.in, (size_t)n * size);
        if (!block)
            return ply_fail_input(&ld->f, e, face, false);
        bool big = ld->f.format == PLY_BINARY_BE;
        for (int64_t i = 0; i < n; i++)
            if (!fan_add(ld, &fan, face, ply_decode_integer(block + (size_t)i * size, p->type, big)))
                return false;
        return true;
    }
    for (int64_t i = 0; i < n; i++) {
        int64_t v;
        if (!ply_read_integer(&ld->f, e, face, p->name, p->type, &v) || !fan_add(ld, &fan, face, v))
            return false;
    }
    return true;
}

static bool read_face(ply_loader *ld, const ply_element *e, uint32_t index)
{
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (!(p->role == ROLE_INDICES ? read_polygon(ld, e, index, p) : ply_skip_property(&ld->f, e, index, p)))
            return false;
    }
    return true;
}

static bool read_element(ply_loader *ld, const ply_element *e)
{
    if (e->prop_count == 0) /* records of nothing: no bytes, no lines */
        return true;
    if (e->kind == PLY_ELEMENT_OTHER)
        return ply_skip_element(&ld->f, e);
    uint64_t record = ld->f.format != PLY_ASCII ? ply_fixed_record_bytes(e) : 0;
    if (e->kind == PLY_ELEMENT_VERTEX && record > 0)
        return read_fixed_vertices(ld, e, (size_t)record);
    /* vertex and face counts were checked to fit in uint32_t */
    for (uint32_t i = 0; i < (uint32_t)e->count; i++) {
        if (!ply_record_begin(&ld->f, e, i))
            return false;
        if (!(e->kind == PLY_ELEMENT_VERTEX ? read_vertex(ld, e, i) : read_face(ld, e, i)))
            return false;
        if (!ply_record_end(&ld->f, e, i))
            return false;
    }
    return true;
}

/* ---- header ------------------------------------------------------------ */

/* The role of property p of element e (ply_property_hook), checked against its shape. */
static bool assign_role(ply_file *f, const ply_element *e, ply_property *p, void *ctx)
{
    (void)ctx;
    p->role = ROLE_SKIP;
    if (e->kind == PLY_ELEMENT_VERTEX) {
        for (int k = 0; k < VERTEX_SLOTS; k++)
            if (strcmp(p->name, vertex_slot_names[k]) == 0) {
                if (p->count_type != PLY_NONE)
                    return ply_fail(f, "vertex property '%s' must be a scalar, not a list", p->name);
                p->role = ROLE_X + k;
            }
    } else if (e->kind == PLY_ELEMENT_FACE &&
               (strcmp(p->name, "vertex_indices") == 0 || strcmp(p->name, "vertex_index") == 0)) {
        if (p->count_type == PLY_NONE || !ply_type_is_integer(p->type))
            return ply_fail(f, "face property '%s' must be a list of integers", p->name);
        p->role = ROLE_INDICES;
        p->min_items = 3; /* a face needs three corners: bounds the faces a file can hold */
    }
    if (p->role == ROLE_SKIP)
        return true;
    for (size_t i = 0; i < e->prop_count; i++) /* only kept properties: linear, however long the header */
        if (e->props[i].role == p->role)
            return ply_fail(f, "%s element has two '%s' properties", e->name,
                            p->role == ROLE_INDICES ? "vertex_indices" : p->name);
    return true;
}

static const ply_property *find_role(const ply_element *e, enum ply_role role)
{
    for (size_t i = 0; i < e->prop_count; i++)
        if (e->props[i].role == (int)role)
            return &e->props[i];
    return NULL;
}

/* Are the three roles first, first + 1, first + 2 all present? Their types go to types[]. */
static bool has_role_group(const ply_element *v, enum ply_role first, enum ply_type types[3])
{
    for (int k = 0; k < 3; k++) {
        const ply_property *p = find_role(v, (enum ply_role)(first + k));
        if (!p)
            return false;
        types[k] = p->type;
    }
    return true;
}

/* Kept only as a complete group: demote a partial one to skipped. */
static void drop_role_group(ply_element *v, enum ply_role first)
{
    for (size_t i = 0; i < v->prop_count; i++)
        if (v->props[i].role >= (int)first && v->props[i].role < (int)first + 3)
            v->props[i].role = ROLE_SKIP;
}

/* Integer colours are 0..255 (0..65535 for 16-bit types); float colours are
 * 0..1. Either way the value is taken as linear RGB: PLY does not say, and
 * scanners write raw sensor values, so no sRGB decoding is applied. */
static float color_range(enum ply_type t)
{
    if (t == PLY_FLOAT32 || t == PLY_FLOAT64)
        return 1.f;
    if (t == PLY_INT16 || t == PLY_UINT16)
        return 65535.f;
    return 255.f;
}

static bool check_header(ply_loader *ld)
{
    ply_file *f = &ld->f;
    ld->vertex = ply_find_element(f, PLY_ELEMENT_VERTEX);
    ld->face = ply_find_element(f, PLY_ELEMENT_FACE);
    if (!ld->vertex)
        return ply_fail(f, "no 'vertex' element");
    for (int k = 0; k < 3; k++)
        if (!find_role(ld->vertex, (enum ply_role)(ROLE_X + k)))
            return ply_fail(f, "vertex element has no '%s' property", vertex_slot_names[k]);
    enum ply_type types[3];
    ld->has_normals = has_role_group(ld->vertex, ROLE_NX, types);
    if (!ld->has_normals)
        drop_role_group(ld->vertex, ROLE_NX);
    ld->has_colors = has_role_group(ld->vertex, ROLE_RED, types);
    if (ld->has_colors)
        for (int k = 0; k < 3; k++)
            ld->color_range[k] = color_range(types[k]);
    else
        drop_role_group(ld->vertex, ROLE_RED);
    if (ld->face && ld->face->count > 0) {
        if (!find_role(ld->face, ROLE_INDICES))
            return ply_fail(f, "face element has no 'vertex_indices' list");
    }
    return true;
}

static bool prepare_mesh(ply_loader *ld)
{
    ply_file *f = &ld->f;
    if (ld->vertex->count > UINT32_MAX)
        return ply_fail(f, "%" PRIu64 " vertices: more than a mesh can hold (%" PRIu32 ")", ld->vertex->count,
                        UINT32_MAX);
    if (ld->face && ld->face->count > UINT32_MAX)
        return ply_fail(f, "%" PRIu64 " faces: more than a mesh can hold (%" PRIu32 " triangles)", ld->face->count,
                        UINT32_MAX);
    ld->vertex_total = (uint32_t)ld->vertex->count;
    uint32_t vertices = min_u32(ld->vertex_total, ply_records_that_fit(f, ld->vertex));
    uint32_t faces = ld->face ? min_u32(ld->face->count, ply_records_that_fit(f, ld->face)) : 0;
    ld->m = mesh_create();
    if (!ld->m || !mesh_reserve_vertices(ld->m, vertices) || !mesh_reserve_triangles(ld->m, faces) ||
        (ld->has_normals && !mesh_enable_normals(ld->m)) || (ld->has_colors && !mesh_enable_colors(ld->m)))
        return ply_fail(f, "out of memory for %" PRIu32 " vertices and %" PRIu32 " faces", vertices, faces);
    return true;
}

static bool load(ply_loader *ld, const char *path, tess_error *err)
{
    if (!ply_open(&ld->f, path, err, assign_role, NULL) || !check_header(ld) || !prepare_mesh(ld))
        return false;
    ld->f.cite_line = ld->f.format == PLY_ASCII;
    const char *name = strrchr(path, '/');
    char what[PROGRESS_WHAT_BYTES];
    snprintf(what, sizeof what, "loading %s", name ? name + 1 : path);
    progress_begin(&ld->progress, what, ld->f.file_bytes, "B");
    ld->f.in.progress = &ld->progress;
    progress_set(&ld->progress, ld->f.in.base + ld->f.in.len); /* the header and the first buffer */
    for (size_t i = 0; i < ld->f.element_count; i++)
        if (!read_element(ld, &ld->f.elements[i]))
            return false;
    ld->f.cite_line = false;
    ld->m->vertex_count = ld->vertex_total;
    ld->m->triangle_count = ld->triangle_total;
    return mesh_validate(ld->m, path, err);
}

mesh *mesh_load_ply(const char *path, tess_error *err)
{
    ply_loader ld = {0};
    mesh *result = NULL;
    if (load(&ld, path, err)) {
        result = ld.m;
        ld.m = NULL;
    }
    progress_end(&ld.progress);
    mesh_destroy(ld.m);
    ply_close(&ld.f);
    return result;
}
