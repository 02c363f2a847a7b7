/* geometry.h - geometry kinds: what the engine needs of a kind of primitive
 * (triangles, spheres, or one a user adds), as one static const table of
 * operations, the shape of image_display_ops.
 *
 * A scene holds geometries (scene.h: a kind's ops and its data) and places
 * them by instances; hits name the instance (hit.geom_id) and the primitive
 * within the instance's geometry (hit.prim_id), and everything else about a
 * hit resolves through the scene (scene_instance_geometry), never by ranges
 * of ids.
 *
 * REGISTRATION. scene_add_geometry(scene, ops, data, name) is the whole of it:
 * a kind needs no change anywhere in the engine. Built-in kinds declare a
 * SIMD leaf layout (their blocks are tested by the per-ISA kernels, which the
 * tests hold to the kind's scalar `intersect`); any other kind uses
 * GEOMETRY_LEAF_PRIMS: its leaves hold primitive ids and every ray meets them
 * through `intersect`, one primitive at a time.
 *
 * Threading: every operation may be called from any number of render threads
 * at once; `data` is read-only while an accel built from it exists. */
#ifndef TESSERA_GEOMETRY_H
#define TESSERA_GEOMETRY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/aabb.h"
#include "engine/base/err.h"
#include "ray.h"
#include "engine/base/vec3.h"

/* a geometry's name (scene_add_geometry), with its terminator */
#define GEOMETRY_NAME_BYTES 64

/* How a kind's primitives sit in the leaves of its wide BVH (wbvh.h). */
typedef enum geometry_leaf_layout {
    GEOMETRY_LEAF_SPHERES,   /* wbvh_sphere_block, filled by fill_lane */
    GEOMETRY_LEAF_PRIMS,     /* wbvh_prim_block (ids only): `intersect` decides, one ray at a time */
    GEOMETRY_LEAF_POINTS,    /* spheres read in place from the kind's arrays (geometry_points): a
                                leaf is a range of them, tested RAY_LANES at a time, never copied;
                                the kind builds and keeps its tree (`tree`) */
    GEOMETRY_LEAF_MESH,      /* triangles read in place from the kind's indexed arrays
                                (geometry_mesh_arrays): a leaf is a range of them, never copied,
                                tested by the SIMD watertight kernels; the kind builds and keeps
                                its tree (`tree`), putting its triangles in the tree's order */
} geometry_leaf_layout;

/* What the kernels read of a GEOMETRY_LEAF_MESH kind, in place: triangle t
 * has vertices indices[3t..3t+2], each the xyz at positions[3 * index]. */
typedef struct geometry_mesh_arrays {
    const float *positions;  /* 3 floats a vertex */
    const uint32_t *indices; /* 3 a triangle, each < the vertex count */
    /* NULL, or per stored triangle the id it is hit as (mesh.h canon: a
     * triangle stored once per leaf of a tree with spatial splits) */
    const uint32_t *canon;
} geometry_mesh_arrays;

/* A range of values that hides the points whose value lies outside it
 * (particles cropped by an attribute). Read by every query; changed only
 * where nothing traces (a pipeline's serial section), like hidden flags. */
typedef struct geometry_crop {
    bool active; /* false: every point is seen */
    float lo, hi; /* seen: lo <= value <= hi */
} geometry_crop;

/* What a kind that crops crops by (geometry_ops.crop_attribute). */
#define GEOMETRY_ATTRIBUTE_NAME_BYTES 32
typedef struct geometry_crop_attribute {
    char name[GEOMETRY_ATTRIBUTE_NAME_BYTES]; /* the attribute's name in its file */
    float min, max;                           /* its values span [min, max] */
    geometry_crop crop;                       /* the crop now */
} geometry_crop_attribute;

/* What the kernels read of a GEOMETRY_LEAF_POINTS kind, in place. Every
 * array may be read GEOMETRY_POINTS_PAD floats past its last point (the
 * SIMD lanes beyond a leaf's range are loaded and masked off). */
#define GEOMETRY_POINTS_PAD 16
typedef struct geometry_points {
    uint32_t count;
    const float *x, *y, *z; /* centres */
    const float *radius;    /* per point, or NULL: every point has radius_all */
    float radius_all;       /* > 0 */
    const float *crop_value; /* the value each point is cropped by, or NULL: no cropping */
    const geometry_crop *crop; /* the range (with crop_value) */
} geometry_points;

struct wbvh;

/* The surface at a hit, in the geometry's own (object) space; render.c
 * places it in the world by the instance's transform. */
typedef struct geometry_surface {
    vec3 position;       /* on the surface (only when asked for: need_position) */
    vec3 position_error; /* componentwise bound of position's rounding (ray.h surface_point) */
    vec3 geometric_n;    /* unit; either side (shading makes it face the ray) */
    vec3 shading_n;      /* unit */
    bool has_colour;     /* colour below overrides the material's diffuse colour (vertex colours) */
    vec3 colour;         /* linear RGB in [0, 1] */
    uint32_t material_id; /* index into scene.materials */
} geometry_surface;

/* USER CONTROLS: what input and records may change of a geometry (and of a
 * medium: scene.h) without knowing its kind, in one optional table the kind
 * points to (geometry_ops.controls, medium_ops.controls). Any member may be
 * NULL: the kind has no such control. geometry_controls_of gives an empty
 * table for a kind without one, so callers test members only. */
typedef struct geometry_controls {
    /* Kinds that crop (geometry_points.crop_value): set the range. Only
     * where nothing traces (a serial section). NULL: the kind has no crop. */
    void (*set_crop)(void *data, geometry_crop crop);
    /* The attribute it crops by, its range and the crop now; false when
     * this geometry crops by none (a set without "crop"). NULL: no crop. */
    bool (*crop_attribute)(const void *data, geometry_crop_attribute *out);
    /* TIME STEPS (a series of files; NULL: one state only). step_count:
     * how many. step_ready: whether `step` can be shown without waiting
     * (else it is loaded in the background); any thread. set_step: show
     * `step`, only where nothing traces; false with err when its data
     * cannot be had (the step shown stays). A GEOMETRY_LEAF_POINTS kind's
     * tree changes with the step: the accel takes it again; any other
     * kind's bottom level is rebuilt from prim_bounds at every step, so
     * such a kind should have few primitives (an iso-surface has one)
     * (accel_set_time_step). Several geometries may share one series
     * (the iso-surfaces of one volume): each is set, the first swaps. */
    uint32_t (*step_count)(const void *data);
    bool (*step_ready)(void *data, uint32_t step);
    bool (*set_step)(void *data, uint32_t step, tess_error *err);
    /* ONE SCALAR PARAMETER (an iso-surface's iso-value; NULL: the kind has
     * none), so the engine can step it without knowing the kind. value:
     * the parameter now and the range it is useful over (lo <= hi, the
     * data's min and max; any thread); false when there is none. set_value:
     * only where nothing traces (a serial section); false, and nothing
     * changes, for a value the kind refuses (not finite). The kind's
     * primitives and bounds must not depend on the value (an accel built
     * before stays valid, no rebuild), but its `closed` answer may: the
     * caller drops the scene's cached answer (scene_geometry_closed). */
    bool (*set_value)(void *data, float value);
    bool (*value)(const void *data, float *value, float *lo, float *hi);
    /* A kind coloured through a colour map (particles by an attribute, a
     * volume's transfer function): use the built-in map `name`
     * (colormap.h), keeping the range it has. False: no such map. Only
     * where nothing traces. NULL: the kind has none. */
    bool (*set_colormap)(void *data, const char *name);
    /* The map in use (its range fitted), NULL when this geometry is not
     * coloured through one; NULL op: the kind never is. Where nothing
     * changes it (the input thread at start, a serial section). */
    const struct colormap *(*colormap)(const void *data);
} geometry_controls;

typedef struct geometry_ops {
    const char *name; /* the kind, for logs and `tessera parts` ("triangles", "spheres", ...) */
    geometry_leaf_layout leaf;
    /* Primitives, ids 0..count-1. */
    uint32_t (*prim_count)(const void *data);
    /* Bounds of the whole geometry (what frames the camera); false when it
     * has nothing. NULL: the union of prim_bounds. */
    bool (*bounds)(const void *data, aabb *out);
    /* Bounds of primitive `prim`; false when it can never be hit (it is left
     * out of the BVH: a degenerate triangle, a sphere of radius 0). */
    bool (*prim_bounds)(const void *data, uint32_t prim, aabb *out);
    /* SPHERES layout: write primitive `prim` into lane `lane`
     * of a zeroed block of that layout (unused for PRIMS; may be NULL). */
    void (*fill_lane)(void *block, int lane, uint32_t prim, const void *data);
    /* The scalar reference: the hit of ray r with primitive `prim` in
     * (r->t_near, r->t_far], its t and its (u, v) (what describe reads back).
     * The SIMD kernels of the built-in layouts give exactly its results; for
     * PRIMS leaves it is what traversal calls. */
    bool (*intersect)(const void *data, uint32_t prim, const ray *r, float *t, float *u, float *v);
    /* The surface at hit h of ray r (both in object space). The position and
     * its error only when need_position (shading lights the point or casts
     * a ray from it); the rest always. */
    void (*describe)(const void *data, uint32_t prim, const ray *r, const hit *h, bool need_position,
                     geometry_surface *out);
    /* Bytes of the kind's own data (for memory reports); NULL: 0. */
    size_t (*bytes)(const void *data);
    /* Free `data` when the scene is destroyed; NULL: the caller owns it. */
    void (*destroy)(void *data);
    /* Whether the primitives bound a solid (every cut of it by a plane can be
     * capped by parity: a point is inside when a ray from it crosses the
     * surface an odd number of times). NULL: not closed (no caps). May be
     * slow (a pass over the data); the scene caches it
     * (scene_geometry_closed). */
    bool (*closed)(const void *data);
    /* GEOMETRY_LEAF_POINTS only. The arrays the leaves read (valid as long
     * as the data, in the order of the kind's tree). */
    void (*points)(const void *data, geometry_points *out);
    /* GEOMETRY_LEAF_POINTS and GEOMETRY_LEAF_MESH: the kind's wide BVH,
     * built on the first call over `threads` threads (which may reorder the
     * kind's points or triangles so that each leaf is a range of them) and
     * kept with the data: every accel borrows it. Safe to call from several threads at once; NULL
     * with err set on failure. */
    const struct wbvh *(*tree)(void *data, int threads, tess_error *err);
    /* What a person may change of this geometry (crop, time steps, a
     * scalar value, a colour map); NULL: nothing. */
    const struct geometry_controls *controls;
} geometry_ops;

/* An affine map, row-major 3x4 [L | t]: p' = L p + t. */
typedef struct affine3 {
    float m[12];
} affine3;

static inline affine3 affine3_identity(void)
{
    return (affine3){{1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f}};
}

static inline bool affine3_is_identity(const affine3 *a)
{
    affine3 id = affine3_identity();
    for (int i = 0; i < 12; i++)
        if (a->m[i] != id.m[i])
            return false;
    return true;
}

static inline vec3 affine3_point(const affine3 *a, vec3 p)
{
    const float *m = a->m;
    return v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
              m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

static inline vec3 affine3_vector(const affine3 *a, vec3 v)
{
    const float *m = a->m;
    return v3(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
              m[8] * v.x + m[9] * v.y + m[10] * v.z);
}

/* Ray r in the space a maps to (world -> object with an instance's
 * to_object): origin as a point, direction as a vector, unnormalised, so
 * t means the same point on both sides. The kernels and the shading of a
 * hit both use this one mapping: a hit is described on the ray it was found
 * with, bit for bit. */
static inline ray affine3_ray(const affine3 *a, const ray *r)
{
    return (ray){affine3_point(a, r->org), affine3_vector(a, r->dir), r->t_near, r->t_far};
}

/* Transposed linear part times v: normals go object -> world by the
 * transpose of the world -> object map. */
static inline vec3 affine3_vector_transposed(const affine3 *a, vec3 v)
{
    const float *m = a->m;
    return v3(m[0] * v.x + m[4] * v.y + m[8] * v.z, m[1] * v.x + m[5] * v.y + m[9] * v.z,
              m[2] * v.x + m[6] * v.y + m[10] * v.z);
}

/* a after b: p -> a(b(p)). */
static inline affine3 affine3_compose(const affine3 *a, const affine3 *b)
{
    affine3 out;
    const float *x = a->m, *y = b->m;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 4; c++)
            out.m[4 * r + c] = x[4 * r] * y[c] + x[4 * r + 1] * y[4 + c] + x[4 * r + 2] * y[8 + c];
        out.m[4 * r + 3] += x[4 * r + 3];
    }
    return out;
}

/* The inverse (in double, rounded once); false when the linear part is
 * singular or anything is not finite. */
bool affine3_invert(const affine3 *a, affine3 *inverse);

/* Bounds of box b mapped by a (the 8 corners' box). */
aabb affine3_box(const affine3 *a, aabb b);

/* The boxes of a kind's primitives that can be hit (prim_bounds true), in
 * id order, computed over `threads` threads: (*boxes)[k] bounds primitive
 * (*ids)[k], *kept of them (the result does not depend on threads). The
 * caller frees both arrays. False: out of memory. */
bool geometry_hit_boxes(const geometry_ops *ops, const void *data, int threads, aabb **boxes, uint32_t **ids,
                        uint32_t *kept);

/* Every member NULL: the controls of a kind that has none. */
extern const geometry_controls geometry_controls_none;

/* ops' controls, or geometry_controls_none. */
static inline const geometry_controls *geometry_controls_of(const geometry_ops *ops)
{
    return ops->controls ? ops->controls : &geometry_controls_none;
}

/* The built-in kinds are in engine/geometry/: triangles (triangle_kind.h),
 * spheres (sphere_kind.h), particles, volumes. */

#endif
