/* glb.h - writing a layout as one binary glTF 2.0 file (.glb).
 *
 * The file: a 12-byte header, the JSON chunk (padded with spaces to 4 bytes)
 * and the BIN chunk (padded with zeros). Each distinct shape becomes one mesh
 * with one triangle primitive: POSITION (float VEC3 with min and max), NORMAL
 * (float VEC3) and UNSIGNED_INT indices, each in its own buffer view; every
 * part node refers to its shape's mesh and places it by translation and
 * rotation (TRS; no node has a scale or a matrix). Shapes are tessellated one
 * at a time into the BIN chunk, which is the only large buffer held.
 *
 * The bytes depend only on the layout: no time, no addresses, numbers printed
 * with fixed formats in the C locale, so equal layouts give equal files. */
#ifndef TESSERA_GEN_ASSEMBLY_GLB_H
#define TESSERA_GEN_ASSEMBLY_GLB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

struct ga_layout;

struct ga_glb_stats {
    uint64_t meshes;           /* distinct meshes stored */
    uint64_t instances;        /* part nodes whose mesh is used by more than one node */
    uint64_t triangles_stored; /* sum over meshes */
    uint64_t bytes;            /* file size */
};

/* Write `layout` to the stream `out`, opened on `path` (named in messages).
 * False with the reason in err when memory runs out, the file would pass
 * glb's 4 GiB or a write fails; the caller then removes the file. */
bool ga_glb_write(const struct ga_layout *layout, FILE *out, const char *path, struct ga_glb_stats *stats,
                  char *err, size_t err_bytes);

#endif
