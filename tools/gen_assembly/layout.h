/* layout.h - where the parts of the fuselage go: the node tree (names,
 * parents, placements) and the distinct shapes the nodes refer to.
 *
 * The fuselage runs along +x: `assembly` holds sections `section-K` end to
 * end; a section holds its ring frames `frame-N`, stringers `stringer-N`, skin
 * panels `skin-N`, pipes `pipe-N` and rivets `rivet-N`; a frame holds its L
 * brackets `bracket-N`, and a bracket the bolts `bolt-N` that hold it. Numbers
 * count from 1 among siblings of one kind, so names are unique among siblings.
 *
 * Every placement is a translation and a rotation about the local x axis (the
 * fuselage's axis), which is all a ring of parts around it needs. Shapes that
 * come out equal (memcmp) are one shape used by several nodes: the bolt, the
 * rivet and the bracket always, frames, stringers and skins of sections of
 * the same radius and length; every pipe is its own.
 *
 * One density scale s sets every tessellation count; ga_layout_fit searches s
 * so the triangles of all placed parts come near the asked number. The random
 * draws do not depend on s, so every s gives the same parts in the same
 * places, only finer or coarser. */
#ifndef TESSERA_GEN_ASSEMBLY_LAYOUT_H
#define TESSERA_GEN_ASSEMBLY_LAYOUT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "shapes.h"

/* Limits of --parts: below the minimum one section's frames, stringers and
 * skins alone outnumber the parts asked for; above the maximum the JSON chunk
 * nears glb's 4 GiB. */
#define GA_LAYOUT_MIN_PARTS 50
#define GA_LAYOUT_MAX_PARTS 2000000

enum ga_node_kind {
    GA_NODE_ASSEMBLY,
    GA_NODE_SECTION,
    GA_NODE_FRAME,
    GA_NODE_STRINGER,
    GA_NODE_SKIN,
    GA_NODE_PIPE,
    GA_NODE_BRACKET,
    GA_NODE_BOLT,
    GA_NODE_RIVET,
    GA_NODE_KIND_COUNT
};

struct ga_node {
    int32_t parent;         /* index of the parent node, -1 for the root */
    int32_t shape;          /* index into ga_layout.shapes, -1: no mesh */
    enum ga_node_kind kind; /* the name's stem */
    uint32_t number;        /* the name's number, from 1 among siblings of the kind (0: none) */
    double translation[3];  /* metres, in the parent's frame */
    double rotation_x;      /* radians about the parent's x axis, applied before the translation */
};

struct ga_layout {
    struct ga_node *nodes;     /* parents come before their children (owned) */
    size_t node_count, node_cap;
    struct ga_shape *shapes;   /* distinct shapes (owned) */
    uint64_t *shape_uses;      /* nodes that use each shape */
    size_t shape_count, shape_cap;
    size_t part_count;         /* nodes with a shape */
    uint64_t triangles_placed; /* sum over parts of their shape's triangles */
    double density;            /* the tessellation scale s it was made with */
    bool count_only;           /* totals only, `nodes` not kept (the density search) */
    bool failed;               /* out of memory */
};

struct ga_layout_params {
    uint64_t parts;     /* nodes with a mesh to aim at */
    uint64_t triangles; /* placed triangles to aim at */
    uint64_t seed;      /* the random stream */
};

/* Lay out the assembly at density s into a fresh `layout` (ga_layout_finish it). */
bool ga_layout_build(struct ga_layout *layout, const struct ga_layout_params *params, double density);

/* Search the density whose layout's placed triangles come nearest
 * params->triangles and leave that layout in `layout`. */
bool ga_layout_fit(struct ga_layout *layout, const struct ga_layout_params *params);

void ga_layout_finish(struct ga_layout *layout);

const char *ga_node_kind_name(enum ga_node_kind kind);

#endif
