/* volume.c - the regular volume and its range (volume.h); its readers are
 * engine/load/volume_read.c. */
#include "volume.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

size_t volume_type_size(volume_type type)
{
    switch (type) {
    case VOLUME_UINT8: return 1;
    case VOLUME_INT16:
    case VOLUME_UINT16: return 2;
    case VOLUME_FLOAT32: return 4;
    }
    return 1;
}

const char *volume_type_name(volume_type type)
{
    switch (type) {
    case VOLUME_UINT8: return "uint8";
    case VOLUME_INT16: return "int16";
    case VOLUME_UINT16: return "uint16";
    case VOLUME_FLOAT32: return "float32";
    }
    return "?";
}

bool volume_check_dims(const uint32_t n[3], const char *what, tess_error *err)
{
    uint64_t count = 1;
    for (int a = 0; a < 3; a++) {
        if (n[a] == 0 || n[a] > VOLUME_MAX_DIM)
            return tess_error_set(err, "%s: size %u along %c is not in 1..%u", what, n[a], "xyz"[a],
                                  VOLUME_MAX_DIM);
        count *= n[a]; /* < 2^60 after three factors of at most 2^20 */
    }
    if (count > VOLUME_MAX_VOXELS)
        return tess_error_set(err, "%s: %u x %u x %u = %llu samples, more than the %llu a volume may hold", what,
                              n[0], n[1], n[2], (unsigned long long)count, (unsigned long long)VOLUME_MAX_VOXELS);
    return true;
}

volume *volume_alloc_header(const uint32_t n[3], volume_type type)
{
    volume *v = calloc(1, sizeof *v);
    if (!v)
        return NULL;
    v->nx = n[0];
    v->ny = n[1];
    v->nz = n[2];
    v->type = type;
    for (int a = 0; a < 3; a++)
        v->spacing[a] = 1.0;
    return v;
}

volume *volume_create(uint32_t nx, uint32_t ny, uint32_t nz, volume_type type, tess_error *err)
{
    const uint32_t n[3] = {nx, ny, nz};
    if (!volume_check_dims(n, "volume_create", err))
        return NULL;
    volume *v = volume_alloc_header(n, type);
    if (v)
        v->buffer = calloc(volume_count(v), volume_type_size(type));
    if (!v || !v->buffer) {
        free(v);
        tess_error_set(err, "volume_create: out of memory for %u x %u x %u %s", nx, ny, nz, volume_type_name(type));
        return NULL;
    }
    v->data = v->buffer;
    return v;
}

void volume_destroy(volume *v)
{
    if (!v)
        return;
    if (v->map)
        munmap(v->map, v->map_bytes);
    free(v->buffer);
    free(v);
}

void *volume_voxels(volume *v) { return v->buffer; }

/* The min and max of `count` integer samples of type T at data: one plain
 * loop per type, a min/max reduction the compiler vectorises. */
#define INTEGER_RANGE(T, data, count, lo_out, hi_out)                                                                 \
    do {                                                                                                               \
        const T *s_ = (data);                                                                                          \
        T lo_ = s_[0], hi_ = s_[0];                                                                                    \
        for (size_t i_ = 1; i_ < (count); i_++) {                                                                      \
            lo_ = s_[i_] < lo_ ? s_[i_] : lo_;                                                                         \
            hi_ = s_[i_] > hi_ ? s_[i_] : hi_;                                                                         \
        }                                                                                                              \
        *(lo_out) = lo_;                                                                                               \
        *(hi_out) = hi_;                                                                                               \
    } while (0)

bool volume_update_range(volume *v, const char *source, tess_error *err)
{
    size_t count = volume_count(v);
    switch (v->type) {
    case VOLUME_UINT8:
        INTEGER_RANGE(uint8_t, v->data, count, &v->min, &v->max);
        return true;
    case VOLUME_INT16:
        INTEGER_RANGE(int16_t, v->data, count, &v->min, &v->max);
        return true;
    case VOLUME_UINT16:
        INTEGER_RANGE(uint16_t, v->data, count, &v->min, &v->max);
        return true;
    case VOLUME_FLOAT32: {
        const float *s = v->data;
        float lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < count; i++) {
            if (!isfinite(s[i])) {
                size_t x = i % v->nx, y = i / v->nx % v->ny, z = i / v->nx / v->ny;
                return tess_error_set(err, "%s: sample (%zu, %zu, %zu) is %s: float data must be finite", source, x,
                                      y, z, isnan(s[i]) ? "NaN" : "infinite");
            }
            lo = s[i] < lo ? s[i] : lo;
            hi = s[i] > hi ? s[i] : hi;
        }
        v->min = lo;
        v->max = hi;
        return true;
    }
    }
    return tess_error_set(err, "%s: unknown sample type", source);
}

void volume_cell_corners(const volume *v, uint32_t i, uint32_t j, uint32_t k, float corner[8])
{
    size_t base = volume_index(v, i, j, k);
    size_t dy = v->nx, dz = (size_t)v->nx * v->ny;
    for (int c = 0; c < 8; c++)
        corner[c] = volume_sample_at(v, base + (size_t)(c & 1) + ((c >> 1) & 1) * dy + ((c >> 2) & 1) * dz);
}

bool volume_same_layout(const volume *first, const volume *v, const char *path, tess_error *err)
{
    if (v->nx != first->nx || v->ny != first->ny || v->nz != first->nz)
        return tess_error_set(err, "%s: dimensions %u x %u x %u differ from the first step's %u x %u x %u", path,
                              v->nx, v->ny, v->nz, first->nx, first->ny, first->nz);
    if (v->type != first->type)
        return tess_error_set(err, "%s: type %s differs from the first step's %s", path, volume_type_name(v->type),
                              volume_type_name(first->type));
    for (int a = 0; a < 3; a++)
        if (v->spacing[a] != first->spacing[a])
            return tess_error_set(err, "%s: spacing %g %g %g differs from the first step's %g %g %g", path,
                                  v->spacing[0], v->spacing[1], v->spacing[2], first->spacing[0], first->spacing[1],
                                  first->spacing[2]);
    for (int a = 0; a < 3; a++)
        if (v->origin[a] != first->origin[a])
            return tess_error_set(err, "%s: origin %g %g %g differs from the first step's %g %g %g", path,
                                  v->origin[0], v->origin[1], v->origin[2], first->origin[0], first->origin[1],
                                  first->origin[2]);
    return true;
}
