/* shapes.h - the parts an assembly is made of, as data (a kind, tessellation
 * counts and sizes), their triangle counts without building them, and the
 * builders that tessellate them into a mesh.
 *
 * Every shape is one closed, consistently oriented solid: each undirected edge
 * is shared by exactly two triangles once vertices with equal positions are
 * merged (faces keep their own vertices where normals differ), and every
 * triangle is counter-clockwise seen from outside. Sizes are metres; each
 * kind's local frame is given with it, and the layout (layout.h) places it. */
#ifndef TESSERA_GEN_ASSEMBLY_SHAPES_H
#define TESSERA_GEN_ASSEMBLY_SHAPES_H

#include <stdbool.h>
#include <stdint.h>

struct ga_mesh;

enum ga_shape_kind {
    GA_SHAPE_FRAME,        /* ring frame about the x axis: size inner radius, outer radius, width along x;
                              segments[0] around */
    GA_SHAPE_STRINGER_BOX, /* box along +x from 0: size length, radius of its top face (on local +z),
                              width, height */
    GA_SHAPE_STRINGER_Z,   /* Z profile along +x from 0: size length, top radius, flange width, height,
                              thickness */
    GA_SHAPE_SKIN,         /* cylindrical panel about the x axis, centred on local +z, along +x from 0:
                              size length, inner radius, thickness, span (rad); segments[0] along the arc,
                              segments[1] along x */
    GA_SHAPE_PIPE,         /* round tube swept in the local xy plane from the origin along +x: size
                              radius, bend radius, straights a, b, c, bend 1, bend 2 (rad; 0: one bend);
                              segments[0] around, segments[1] per bend */
    GA_SHAPE_BRACKET,      /* L bracket: a leg along +y (z in [0, t]) and one along +z (y in [0, t]),
                              width along x centred on 0: size leg y, leg z, thickness, width */
    GA_SHAPE_BOLT,         /* hex head on z in [0, head height], shank down to -length: size head
                              circumradius, head height, shank radius, length; segments[0] around the
                              shank (a multiple of 12) */
    GA_SHAPE_RIVET,        /* half-ellipsoid dome on z >= 0, shank down to -length: size dome radius,
                              dome height, shank radius, length; segments[0] around, segments[1] dome
                              rings */
    GA_SHAPE_KIND_COUNT
};

#define GA_SHAPE_SIZES 8

/* One shape, compared with memcmp to share meshes: build it with
 * ga_shape_make so padding and unused fields are zero. */
struct ga_shape {
    enum ga_shape_kind kind;
    int segments[2];              /* tessellation counts, per kind (above) */
    double size[GA_SHAPE_SIZES];  /* metres or radians, per kind (above) */
};

struct ga_shape ga_shape_make(enum ga_shape_kind kind);

/* Triangles ga_shape_build makes for it. */
uint64_t ga_shape_triangles(const struct ga_shape *shape);

/* Tessellate the shape into `mesh` (appended). False when memory ran out. */
bool ga_shape_build(const struct ga_shape *shape, struct ga_mesh *mesh);

/* Kind names as used in node and mesh names: "frame", "stringer", ... */
const char *ga_shape_kind_name(enum ga_shape_kind kind);

#endif
