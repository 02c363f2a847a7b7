/* volume.h - a structured regular volume: nx * ny * nz scalar samples on a
 * grid with constant spacing, as a CT, an MRI or a simulation writes them.
 *
 * LAYOUT. Sample (i, j, k) is voxel i + nx * (j + ny * k): x fastest, then y,
 * then z. Samples keep the file's width in memory (uint8, int16, uint16,
 * float32), never widened: a 35 MB uint8 MRI stays 35 MB. volume_sample
 * converts one sample to float when it is read.
 *
 * WORLD. Sample (i, j, k) sits at origin + (i, j, k) * spacing (world units,
 * typically mm; spacing > 0 on every axis, the grid axis-aligned). The
 * trilinear field is defined on [origin, origin + (n - 1) * spacing]; its
 * cells span samples i..i+1 on each axis (macrocell.h, iso_cell.h).
 *
 * LOADING from files is engine/load/volume_read.h.
 *
 * Ownership: the volume owns its samples (mapping or buffer);
 * volume_destroy releases them. Threading: none inside; a finished volume is
 * read-only and may be sampled from any number of threads. */
#ifndef TESSERA_VOLUME_H
#define TESSERA_VOLUME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"

/* one axis may have at most this many samples (2^20): beyond any scanner or
 * simulation we load, and with the product capped as below every index
 * i + nx * (j + ny * k) and byte count fits in 64 bits with room to spare */
#define VOLUME_MAX_DIM (1u << 20)
/* the most samples one volume may hold: 2^36 (64 Gi samples, 256 GiB of
 * float32); a header asking for more is refused before any file size check */
#define VOLUME_MAX_VOXELS ((uint64_t)1 << 36)

typedef enum volume_type {
    VOLUME_UINT8,
    VOLUME_INT16,
    VOLUME_UINT16,
    VOLUME_FLOAT32,
} volume_type;

typedef struct volume {
    uint32_t nx, ny, nz;  /* samples per axis, each in 1..VOLUME_MAX_DIM */
    volume_type type;     /* width and meaning of one sample in `data` */
    double spacing[3];    /* world units between neighbouring samples along x, y, z; > 0, finite */
    double origin[3];     /* world position of sample (0, 0, 0); finite */
    const void *data;     /* nx * ny * nz samples of `type`, host byte order, aligned to the type */
    float min, max;       /* over all samples (volume_update_range); float data is finite */
    /* ownership (volume.c): exactly one of map / buffer is set */
    void *map;            /* the whole data file, mmap'd read-only, or NULL */
    size_t map_bytes;     /* length of map */
    void *buffer;         /* malloc'd samples (swapped, created or unaligned), or NULL */
} volume;

/* Bytes of one sample of `type`. */
size_t volume_type_size(volume_type type);
/* "uint8", "int16", "uint16", "float32". */
const char *volume_type_name(volume_type type);

/* A volume in memory, samples zeroed, spacing 1, origin 0; fill it through
 * volume_voxels, then call volume_update_range. NULL (err set) when a
 * dimension is 0 or above VOLUME_MAX_DIM, the count above VOLUME_MAX_VOXELS,
 * or memory is short. */
volume *volume_create(uint32_t nx, uint32_t ny, uint32_t nz, volume_type type, tess_error *err);
void volume_destroy(volume *v); /* NULL is fine */

/* The writable samples of a created (or read, not mapped) volume; NULL for a
 * mapped one, whose pages are read-only. */
void *volume_voxels(volume *v);

/* Recompute min and max over every sample. False (err names `source` and
 * the first bad sample) when float data holds a NaN or an infinity. */
bool volume_update_range(volume *v, const char *source, tess_error *err);

static inline size_t volume_count(const volume *v) { return (size_t)v->nx * v->ny * v->nz; }

static inline size_t volume_index(const volume *v, uint32_t i, uint32_t j, uint32_t k)
{
    return (size_t)i + (size_t)v->nx * ((size_t)j + (size_t)v->ny * k);
}

/* Sample (i, j, k) as float; i < nx, j < ny, k < nz (not checked). int16 and
 * uint16 convert exactly; a switch, not a pointer, as it sits in inner loops. */
static inline float volume_sample_at(const volume *v, size_t index)
{
    switch (v->type) {
    case VOLUME_UINT8: return (float)((const uint8_t *)v->data)[index];
    case VOLUME_INT16: return (float)((const int16_t *)v->data)[index];
    case VOLUME_UINT16: return (float)((const uint16_t *)v->data)[index];
    case VOLUME_FLOAT32: return ((const float *)v->data)[index];
    }
    return 0.0f;
}

static inline float volume_sample(const volume *v, uint32_t i, uint32_t j, uint32_t k)
{
    return volume_sample_at(v, volume_index(v, i, j, k));
}

/* The eight samples of the trilinear cell whose low corner is (i, j, k)
 * (i < nx - 1, j < ny - 1, k < nz - 1), in the order corner[x + 2y + 4z]. */
void volume_cell_corners(const volume *v, uint32_t i, uint32_t j, uint32_t k, float corner[8]);

/* Whether `v` (loaded from `path`) lays its samples out as `first` does:
 * the same dimensions, type, spacing and origin (what the steps of a time
 * series must share). False with err naming the path and the first field
 * that differs: "PATH: dimensions 20 x 16 x 16 differ from the first
 * step's 16 x 16 x 16". Reads only those fields of `first` (its samples
 * may be gone). */
bool volume_same_layout(const volume *first, const volume *v, const char *path, tess_error *err);

/* For the readers (engine/load/volume_read.c): whether dims n lie within the
 * caps (VOLUME_MAX_DIM, VOLUME_MAX_VOXELS), false with err naming `what` (a
 * file and field); and a volume of dims n and `type` with no samples yet
 * (spacing 1, origin 0; the reader sets data and the range), NULL on no
 * memory. */
bool volume_check_dims(const uint32_t n[3], const char *what, tess_error *err);
volume *volume_alloc_header(const uint32_t n[3], volume_type type);

#endif
