/* ply.h - writing a layout flattened: every placed part's triangles, its node
 * transforms baked in, as ONE binary little-endian PLY mesh.
 *
 * The file: `element vertex V` with float x y z (no normals: renderers use
 * the geometric ones) and `element face F` with `property list uchar int
 * vertex_indices`, 3 per face. Parts come in node order, each its shape's
 * vertices then (in the face element) its shape's triangles, so the file is
 * what a glTF importer that bakes node transforms would give, without any
 * importer's memory: each distinct shape is tessellated once and held (the
 * stored triangles, far fewer than the placed ones), the placed copies are
 * streamed. Positions are transformed in double and rounded to float once.
 *
 * The bytes depend only on the layout, as the .glb's do. */
#ifndef TESSERA_GEN_ASSEMBLY_PLY_H
#define TESSERA_GEN_ASSEMBLY_PLY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

struct ga_layout;

struct ga_ply_stats {
    uint64_t vertices;  /* placed vertices written */
    uint64_t triangles; /* placed triangles written (the layout's triangles_placed) */
    uint64_t bytes;     /* file size */
};

/* Write `layout` flattened to `out`, opened on `path` (named in messages).
 * False with the reason in err when memory runs out, the vertices pass a
 * PLY int index (2^31 - 1) or a write fails; the caller then removes the file. */
bool ga_ply_write(const struct ga_layout *layout, FILE *out, const char *path, struct ga_ply_stats *stats,
                  char *err, size_t err_bytes);

#endif
