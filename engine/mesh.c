#include "mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

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
    bytes += m->material_count * sizeof(mesh_material);
    return bytes;
}

static bool has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n >= e && strcasecmp(path + n - e, ext) == 0;
}

mesh *mesh_load(const char *path, tess_error *err)
{
    if (has_extension(path, ".ply"))
        return mesh_load_ply(path, err);
    return mesh_load_assimp(path, err);
}

/* One bit per element, for the in-place permutations below. */
static uint64_t *bits_new(size_t n) { return calloc(n / 64 + 1, sizeof(uint64_t)); }
static inline bool bit_get(const uint64_t *b, size_t i) { return b[i / 64] >> (i % 64) & 1u; }
static inline void bit_set(uint64_t *b, size_t i) { b[i / 64] |= 1ull << (i % 64); }

bool mesh_permute_triangles(mesh *m, const uint32_t *order)
{
    uint32_t n = m->triangle_count;
    uint64_t *done = bits_new(n);
    if (!done)
        return false;
    uint32_t *idx = m->indices, *mat = m->triangle_material;
    /* gather in place along each cycle: slot j takes the triangle at order[j] */
    for (uint32_t i = 0; i < n; i++) {
        if (bit_get(done, i))
            continue;
        const uint32_t keep[3] = {idx[3 * (size_t)i], idx[3 * (size_t)i + 1], idx[3 * (size_t)i + 2]};
        const uint32_t keep_mat = mat ? mat[i] : 0;
        for (uint32_t j = i;;) {
            uint32_t k = order[j];
            bit_set(done, j);
            uint32_t *dst = idx + 3 * (size_t)j;
            if (k == i) {
                dst[0] = keep[0], dst[1] = keep[1], dst[2] = keep[2];
                if (mat)
                    mat[j] = keep_mat;
                break;
            }
            const uint32_t *src = idx + 3 * (size_t)k;
            dst[0] = src[0], dst[1] = src[1], dst[2] = src[2];
            if (mat)
                mat[j] = mat[k];
            j = k;
        }
    }
    free(done);
    return true;
}

/* Scatter the 3-float items of `a` in place: item v moves to new_id[v]. */
static void scatter3(float *a, const uint32_t *new_id, uint32_t n, uint64_t *done)
{
    memset(done, 0, (n / 64 + 1) * sizeof *done);
    for (uint32_t i = 0; i < n; i++) {
        if (bit_get(done, i))
            continue;
        float carry[3] = {a[3 * (size_t)i], a[3 * (size_t)i + 1], a[3 * (size_t)i + 2]};
        uint32_t j = i;
        do {
            uint32_t k = new_id[j];
            float *slot = a + 3 * (size_t)k;
            const float next[3] = {slot[0], slot[1], slot[2]};
            slot[0] = carry[0], slot[1] = carry[1], slot[2] = carry[2];
            bit_set(done, k);
            carry[0] = next[0], carry[1] = next[1], carry[2] = next[2];
            j = k;
        } while (j != i);
    }
}

bool mesh_renumber_vertices(mesh *m)
{
    uint32_t nv = m->vertex_count;
    uint32_t *new_id = malloc(((size_t)nv + 1) * sizeof *new_id);
    uint64_t *done = bits_new(nv);
    if (!new_id || !done) {
        free(new_id);
        free(done);
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
    for (size_t c = 0; c < corners; c++)
        m->indices[c] = new_id[m->indices[c]];
    scatter3(m->positions, new_id, nv, done);
    if (m->normals)
        scatter3(m->normals, new_id, nv, done);
    if (m->colors)
        scatter3(m->colors, new_id, nv, done);
    free(new_id);
    free(done);
    return true;
}
