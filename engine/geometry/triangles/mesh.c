#include "mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/parallel.h"

mesh *mesh_create(void) { return calloc(1, sizeof(mesh)); }

void mesh_destroy(mesh *m)
{
    if (!m)
        return;
    if (m->owner) {
        m->release(m->owner);
        free(m);
        return;
    }
    free(m->positions);
    free(m->normals);
    free(m->colors);
    free(m->indices);
    free(m->triangle_material);
    free(m->canon);
    free(m->materials);
    free(m);
}

/* realloc an array of `count` items of `item_bytes`, NULL-safe and overflow-checked */
static bool grow(void *ptr_to_array, size_t count, size_t item_bytes)
{
    void **array = ptr_to_array;
    if (count > SIZE_MAX / item_bytes)
        return false;
    size_t bytes = count * item_bytes;
    void *p = realloc(*array, bytes > 0 ? bytes : 1);
    if (!p)
        return false;
    *array = p;
    return true;
}

bool mesh_reserve_vertices(mesh *m, uint32_t n)
{
    if (n <= m->vertex_capacity)
        return true;
    if (!grow(&m->positions, n, 3 * sizeof(float)))
        return false;
    if (m->normals && !grow(&m->normals, n, 3 * sizeof(float)))
        return false;
    if (m->colors && !grow(&m->colors, n, 3 * sizeof(float)))
        return false;
    m->vertex_capacity = n;
    return true;
}

bool mesh_reserve_triangles(mesh *m, uint32_t n)
{
    if (n <= m->triangle_capacity)
        return true;
    if (!grow(&m->indices, n, 3 * sizeof(uint32_t)))
        return false;
    if (m->triangle_material && !grow(&m->triangle_material, n, sizeof(uint32_t)))
        return false;
    if (m->canon && !grow(&m->canon, n, sizeof(uint32_t)))
        return false;
    m->triangle_capacity = n;
    return true;
}

bool mesh_enable_normals(mesh *m)
{
    if (m->normals)
        return true;
    m->normals = calloc((size_t)m->vertex_capacity + 1, 3 * sizeof(float));
    return m->normals != NULL;
}

bool mesh_enable_colors(mesh *m)
{
    if (m->colors)
        return true;
    m->colors = calloc((size_t)m->vertex_capacity + 1, 3 * sizeof(float));
    return m->colors != NULL;
}

bool mesh_enable_triangle_materials(mesh *m)
{
    if (m->triangle_material)
        return true;
    m->triangle_material = calloc((size_t)m->triangle_capacity + 1, sizeof(uint32_t));
    return m->triangle_material != NULL;
}

static uint32_t next_capacity(uint32_t current)
{
    if (current < 1024)
        return 1024;
    return current > UINT32_MAX / 2 ? UINT32_MAX : current * 2;
}

bool mesh_add_vertex(mesh *m, float x, float y, float z)
{
    if (m->vertex_count == UINT32_MAX)
        return false;
    if (m->vertex_count == m->vertex_capacity && !mesh_reserve_vertices(m, next_capacity(m->vertex_capacity)))
        return false;
    float *p = m->positions + 3 * (size_t)m->vertex_count;
    p[0] = x;
    p[1] = y;
    p[2] = z;
    m->vertex_count++;
    return true;
}

bool mesh_add_triangle(mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    if (m->triangle_count == UINT32_MAX)
        return false;
    if (m->triangle_count == m->triangle_capacity &&
        !mesh_reserve_triangles(m, next_capacity(m->triangle_capacity)))
        return false;
    uint32_t *t = m->indices + 3 * (size_t)m->triangle_count;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    if (m->triangle_material)
        m->triangle_material[m->triangle_count] = 0;
    if (m->canon) /* a new triangle is its own first copy */
        m->canon[m->triangle_count] = m->triangle_count;
    m->triangle_count++;
    return true;
}

static bool all_finite(const float *v, size_t n, size_t *bad)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) {
            *bad = i;
            return false;
        }
    return true;
}

bool mesh_validate(const mesh *m, const char *source, tess_error *err)
{
    size_t bad;
    if (!all_finite(m->positions, 3 * (size_t)m->vertex_count, &bad))
        return tess_error_set(err, "%s: vertex %zu: coordinate %c is %g (must be finite)", source, bad / 3,
                              "xyz"[bad % 3], (double)m->positions[bad]);
    if (m->normals && !all_finite(m->normals, 3 * (size_t)m->vertex_count, &bad))
        return tess_error_set(err, "%s: vertex %zu: normal component %c is not finite", source, bad / 3,
                              "xyz"[bad % 3]);
    if (m->colors && !all_finite(m->colors, 3 * (size_t)m->vertex_count, &bad))
        return tess_error_set(err, "%s: vertex %zu: colour is not finite", source, bad / 3);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        if (m->indices[i] >= m->vertex_count)
            return tess_error_set(err, "%s: triangle %zu: vertex index %u out of range (mesh has %u vertices)",
                                  source, i / 3, m->indices[i], m->vertex_count);
    if (m->triangle_material)
        for (size_t i = 0; i < m->triangle_count; i++)
            if (m->triangle_material[i] >= m->material_count)
                return tess_error_set(err, "%s: triangle %zu: material %u out of range (%u materials)", source,
                                      i, m->triangle_material[i], m->material_count);
    return true;
}

bool mesh_bounds(const mesh *m, float lo[3], float hi[3])
{
    if (m->vertex_count == 0)
        return false;
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = m->positions[k];
    for (size_t i = 1; i < m->vertex_count; i++)
        for (int k = 0; k < 3; k++) {
            float v = m->positions[3 * i + (size_t)k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    return true;
}

void mesh_transform(mesh *m, const float x[12])
{
    for (size_t i = 0; i < m->vertex_count; i++) {
        float *p = m->positions + 3 * i;
        float px = p[0], py = p[1], pz = p[2];
        p[0] = x[0] * px + x[1] * py + x[2] * pz + x[3];
        p[1] = x[4] * px + x[5] * py + x[6] * pz + x[7];
        p[2] = x[8] * px + x[9] * py + x[10] * pz + x[11];
    }
    if (!m->normals)
        return;
    /* normals transform by the inverse transpose of the linear part M, which is
     * C / det(M) with C the cofactor matrix (row-major below); we renormalise,
     * so only the sign of det matters (a mirroring transform flips it) */
    float c[9] = {
        x[5] * x[10] - x[6] * x[9], x[6] * x[8] - x[4] * x[10], x[4] * x[9] - x[5] * x[8],
        x[2] * x[9] - x[1] * x[10], x[0] * x[10] - x[2] * x[8], x[1] * x[8] - x[0] * x[9],
        x[1] * x[6] - x[2] * x[5],  x[2] * x[4] - x[0] * x[6],  x[0] * x[5] - x[1] * x[4],
    };
    float det = x[0] * c[0] + x[1] * c[1] + x[2] * c[2];
    float det_sign = det < 0.f ? -1.f : 1.f;
    for (size_t i = 0; i < m->vertex_count; i++) {
        float *n = m->normals + 3 * i;
        float nx = c[0] * n[0] + c[1] * n[1] + c[2] * n[2];
        float ny = c[3] * n[0] + c[4] * n[1] + c[5] * n[2];
        float nz = c[6] * n[0] + c[7] * n[1] + c[8] * n[2];
        float len = sqrtf(nx * nx + ny * ny + nz * nz);
        float inv = len > 0.f ? det_sign / len : 0.f;
        n[0] = nx * inv;
        n[1] = ny * inv;
        n[2] = nz * inv;
    }
}

size_t mesh_bytes(const mesh *m)
{
    size_t v = m->vertex_count, t = m->triangle_count;
    size_t bytes = v * 3 * sizeof(float) + t * 3 * sizeof(uint32_t);
    if (m->normals)
        bytes += v * 3 * sizeof(float);
    if (m->colors)
        bytes += v * 3 * sizeof(float);
    if (m->triangle_material)
        bytes += t * sizeof(uint32_t);
    if (m->canon)
        bytes += t * sizeof(uint32_t);
    bytes += m->material_count * sizeof(mesh_material);
    return bytes;
}

/* REORDERING. Both reorderings gather: slot i of a new array takes item
 * from[i] of the old one, the slots written in order and the reads
 * prefetched a stretch ahead (from[] is read in order, so the random reads
 * overlap), over `threads` threads. Following the permutation's cycles in
 * place instead reads one item at a time, each a cache miss on a large
 * mesh: at 8 M triangles it was 13 % of load + build on one thread. The
 * price is a second copy of one array while it is gathered (indices: 12
 * bytes a triangle), less than the triangle boxes the build freed before. */

/* Items of item_bytes: dst item i = src item from[i]. */
typedef struct gather_job {
    const char *src;
    char *dst;
    const uint32_t *from;
    size_t count;
    size_t item_bytes;
} gather_job;

/* Items read ahead of the one copied: enough misses in flight to cover the
 * memory latency, few enough to stay in the L1. */
#define GATHER_PREFETCH_AHEAD 16
#define GATHER_GRAIN 65536

static void gather_range(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    const gather_job *g = ctx;
    const size_t w = g->item_bytes;
    for (size_t i = begin; i < end; i++) {
        if (i + GATHER_PREFETCH_AHEAD < g->count)
            __builtin_prefetch(g->src + w * g->from[i + GATHER_PREFETCH_AHEAD]);
        memcpy(g->dst + w * i, g->src + w * g->from[i], w);
    }
}

/* Up to 3 arrays of `count` items reordered through from, all or none:
 * array k (of item_bytes[k]) is skipped when *arrays[k] is NULL. False
 * (nothing changed) when out of memory. */
static bool gather_arrays(void **arrays[], const size_t item_bytes[], int array_count, size_t count,
                          const uint32_t *from, int threads)
{
    void *dst[3] = {NULL, NULL, NULL};
    for (int k = 0; k < array_count; k++)
        if (*arrays[k] && !(dst[k] = malloc((count ? count : 1) * item_bytes[k]))) {
            for (int j = 0; j < k; j++)
                free(dst[j]);
            return false;
        }
    for (int k = 0; k < array_count; k++) {
        if (!*arrays[k])
            continue;
        gather_job job = {*arrays[k], dst[k], from, count, item_bytes[k]};
        parallel_for(threads, count, GATHER_GRAIN, gather_range, &job);
        free(*arrays[k]);
        *arrays[k] = dst[k];
    }
    return true;
}

/* The per-triangle arrays gathered through from: count triangles after. */
static bool gather_triangle_arrays(mesh *m, const uint32_t *from, uint32_t count, int threads)
{
    void **arrays[2] = {(void **)&m->indices, (void **)&m->triangle_material};
    const size_t item_bytes[2] = {3 * sizeof(uint32_t), sizeof(uint32_t)};
    if (!gather_arrays(arrays, item_bytes, 2, count, from, threads))
        return false;
    m->triangle_count = m->triangle_capacity = count;
    return true;
}

bool mesh_permute_triangles(mesh *m, const uint32_t *order, int threads)
{
    return gather_triangle_arrays(m, order, m->triangle_count, threads);
}

bool mesh_gather_triangles(mesh *m, const uint32_t *from, uint32_t count, int threads)
{
    if (m->canon)
        return false;
    /* first_at[t]: where old triangle t is first stored, UINT32_MAX before that */
    uint32_t *first_at = malloc(((size_t)m->triangle_count + 1) * sizeof *first_at);
    uint32_t *canon = malloc(((size_t)count + 1) * sizeof *canon);
    if (!first_at || !canon) {
        free(first_at);
        free(canon);
        return false;
    }
    for (uint32_t t = 0; t < m->triangle_count; t++)
        first_at[t] = UINT32_MAX;
    uint32_t duplicates = 0;
    for (uint32_t i = 0; i < count; i++) {
        if (first_at[from[i]] == UINT32_MAX)
            first_at[from[i]] = i;
        canon[i] = first_at[from[i]];
        duplicates += canon[i] != i;
    }
    free(first_at);
    if (!gather_triangle_arrays(m, from, count, threads)) {
        free(canon);
        return false;
    }
    if (duplicates == 0) {
        free(canon);
        canon = NULL;
    }
    m->canon = canon;
    m->duplicate_count = duplicates;
    return true;
}

/* Corner indices rewritten through new_id, in parallel. */
typedef struct renumber_job {
    uint32_t *indices;
    const uint32_t *new_id;
} renumber_job;

static void renumber_range(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    renumber_job *job = ctx;
    for (size_t c = begin; c < end; c++)
        job->indices[c] = job->new_id[job->indices[c]];
}

bool mesh_renumber_vertices(mesh *m, int threads)
{
    uint32_t nv = m->vertex_count;
    uint32_t *new_id = malloc(((size_t)nv + 1) * sizeof *new_id);
    uint32_t *old_of = malloc(((size_t)nv + 1) * sizeof *old_of);
    if (!new_id || !old_of) {
        free(new_id);
        free(old_of);
        return false;
    }
    for (uint32_t v = 0; v < nv; v++)
        new_id[v] = UINT32_MAX;
    uint32_t next = 0;
    size_t corners = 3 * (size_t)m->triangle_count;
    for (size_t c = 0; c < corners; c++)
        if (new_id[m->indices[c]] == UINT32_MAX)
            new_id[m->indices[c]] = next++;
    for (uint32_t v = 0; v < nv; v++) /* unused vertices keep their order, after the used ones */
        if (new_id[v] == UINT32_MAX)
            new_id[v] = next++;
    for (uint32_t v = 0; v < nv; v++)
        old_of[new_id[v]] = v;
    void **arrays[3] = {(void **)&m->positions, (void **)&m->normals, (void **)&m->colors};
    const size_t item_bytes[3] = {3 * sizeof(float), 3 * sizeof(float), 3 * sizeof(float)};
    bool ok = gather_arrays(arrays, item_bytes, 3, nv, old_of, threads);
    if (ok) {
        renumber_job job = {m->indices, new_id};
        parallel_for(threads, corners, 3 * GATHER_GRAIN, renumber_range, &job);
        m->vertex_capacity = nv;
    }
    free(new_id);
    free(old_of);
    return ok;
}
