/* scene.h - what is rendered: geometry, materials, lights, camera, background.
 *
 * GEOMETRIES AND INSTANCES. A geometry is a kind's ops (geometry.h) and its
 * data, stored once; an instance places a geometry in the world by an affine
 * transform (a part used many times is stored once). Hits name an instance
 * (hit.geom_id, "geometry id" in older code and messages) and a primitive of
 * its geometry (hit.prim_id); both resolve through the scene
 * (scene_instance_geometry), never by ranges of ids.
 * The built-in kinds' data lives in `meshes` (each also a geometry with one
 * identity instance, added by scene_add_mesh; loaders bake their transforms
 * in) and in the sphere set (one geometry and one instance, made when the
 * first sphere is added).
 * The scene is immutable while frames render; changes go through transactions
 * (the pipeline issue). */
#ifndef TESSERA_SCENE_H
#define TESSERA_SCENE_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "engine/base/err.h"
#include "engine/accel/geometry.h"
#include "engine/geometry/spheres/sphere_kind.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/geometry/triangles/triangle_kind.h"
#include "engine/base/vec3.h"

#define SCENE_NAME_BYTES GEOMETRY_NAME_BYTES

typedef enum material_model {
    MATERIAL_LAMBERT, /* diffuse only */
    MATERIAL_PHONG,   /* diffuse + specular lobe (R.V)^shininess */
} material_model;

typedef struct material {
    char name[SCENE_NAME_BYTES];
    material_model model;
    vec3 diffuse;     /* linear RGB reflectance, each in [0, 1] */
    vec3 specular;    /* linear RGB, Phong only */
    float shininess;  /* Phong exponent, >= 0 */
    float ambient;    /* fraction of diffuse returned under the scene's ambient light, [0, 1] */
} material;

typedef enum light_kind {
    LIGHT_DIRECTIONAL, /* parallel rays; `direction` points from the surface towards the light */
    LIGHT_POINT,       /* at `position`; irradiance falls off as 1/d^2 */
} light_kind;

typedef struct light {
    light_kind kind;
    vec3 direction;   /* unit, towards the light (directional) */
    vec3 position;    /* world units (point) */
    vec3 color;       /* linear RGB */
    float intensity;  /* scale on color: irradiance for directional, W/sr-like for point */
    bool casts_shadows;
} light;

/* PARTICIPATING MEDIA: what is integrated along rays rather than hit (a
 * volume rendered directly). A medium lies in its own box (object space),
 * placed by to_world; along a primary ray it is integrated from the ray's
 * start to its first surface (or to the end of the box) and composited in
 * front of that surface: colour = medium + transmittance x surface; where
 * rays walk translucent surfaces layer by layer, each stretch between two
 * layers in turn, up to the first opaque one; only the part on the kept side
 * of the cutting planes. Media are assumed not to overlap (each is
 * integrated alone, nearest first).
 * A scene without media pays nothing (medium_count 0). */
typedef struct medium_ops {
    const char *name; /* the kind, for logs ("dvr") */
    /* The medium's box in object space; false when it is empty. */
    bool (*bounds)(const void *data, aabb *out);
    /* Integrate along r (object space; r->t_near .. r->t_far are already
     * clipped to the box and to the stretch between surfaces): emitted colour (linear
     * RGB, associated: already weighted by opacity) and the transmittance
     * left, in [0, 1]. jitter in [0, 1): where within its first step the
     * first sample lies. Any thread. */
    void (*integrate)(const void *data, const ray *r, float jitter, vec3 *rgb, float *transmittance);
    /* Free data with the scene (NULL: the caller owns it). */
    void (*destroy)(void *data);
    /* What a person may change, as a geometry's (geometry.h: USER
     * CONTROLS); NULL: nothing. A medium uses set_colormap / colormap for
     * its transfer function and the time steps, whose change must leave
     * its bounds as they are; it has no crop or value. */
    const geometry_controls *controls;
} medium_ops;

/* ops' controls, or geometry_controls_none. */
static inline const geometry_controls *medium_controls_of(const medium_ops *ops)
{
    return ops->controls ? ops->controls : &geometry_controls_none;
}

typedef struct scene_medium {
    const medium_ops *ops;
    void *data;
    affine3 to_world, to_object;
    bool identity;
    char name[SCENE_NAME_BYTES];
} scene_medium;

/* A geometry: a kind and its data (ops->destroy frees data with the scene). */
typedef struct scene_geometry {
    const geometry_ops *ops;
    void *data;
    char name[SCENE_NAME_BYTES];
} scene_geometry;

#define SCENE_NO_PART 0xFFFFFFFFu
#define SCENE_NO_MATERIAL 0xFFFFFFFFu

struct part_tree;
struct scene_closed_cache;

/* A geometry placed in the world. */
typedef struct scene_instance {
    uint32_t geometry;   /* index into scene.geometries */
    affine3 to_world;    /* object -> world */
    affine3 to_object;   /* world -> object (the inverse) */
    bool identity;       /* to_world is the identity: nothing is transformed, results are the
                            geometry's own bit for bit */
    uint32_t part;       /* the part it belongs to (scene.parts), or SCENE_NO_PART */
    uint32_t material;   /* a material replacing the geometry's own everywhere on this instance
                            (a colour given to a part by the scene file), or SCENE_NO_MATERIAL */
    float opacity;       /* where a view starts: the part opacity the pipeline gives it (frame_state.h
                            OPACITY), in [0, 1]; 1 (opaque) unless the scene file says otherwise */
} scene_instance;

typedef struct scene {
    scene_mesh **meshes;  /* each allocated apart, so a geometry's data pointer stays valid */
    uint32_t mesh_count, mesh_capacity;
    sphere_set spheres;
    uint32_t sphere_instance; /* the sphere set's instance, RAY_INVALID_ID before the first sphere */
    scene_geometry *geometries;
    uint32_t geometry_count, geometry_capacity;
    scene_instance *instances;
    uint32_t instance_count, instance_capacity;
    scene_medium *media;     /* participating media (above); NULL while there are none */
    uint32_t medium_count, medium_capacity;
    /* the volume files a scene file placed ("volumes" entries, each shown by
     * iso-surface geometries, a medium or both) and their samples (a
     * series: its first step's); what the summary line counts */
    uint32_t volume_count;
    uint64_t volume_voxels;
    /* PARTS. The part tree of an assembly (part_tree.h), or NULL when the
     * scene has none (then it costs nothing). Instances with a part come in
     * preorder of their parts (part ids never decrease along the instances
     * that have one), so the instances of a part's subtree are one id range
     * (scene_part_instances): hiding a subtree is hiding a range. */
    struct part_tree *parts;
    /* the ids of the instances that have a part, in order (so their parts
     * never decrease): what scene_part_instances binary-searches, without
     * stepping over instances that have none. NULL while there are none. */
    uint32_t *parted;
    uint32_t parted_count, parted_capacity;
    material *materials;
    uint32_t material_count, material_capacity;
    light *lights;
    uint32_t light_count, light_capacity;
    vec3 background;      /* linear RGB of rays that hit nothing */
    vec3 ambient;         /* linear RGB ambient light */
    bool has_camera;      /* false: frame the bounds with camera_frame_bounds() */
    camera_desc camera;
    /* CLOSED GEOMETRIES (scene_geometry_closed): a byte per geometry, NULL
     * until the first question about a kind that has a `closed` operation,
     * so a scene without cutting planes pays nothing. Guarded by atomics, no
     * lock: the pointer is published once by compare-and-swap (release;
     * readers acquire: they see the zeroed bytes) and dropped only by
     * scene_add_geometry, which like every change runs while no frame
     * renders. The bytes are relaxed atomics, 0 until known: an answer is a
     * pure function of the geometry's data, so two threads that compute it
     * at once store the same byte. */
    _Atomic(struct scene_closed_cache *) closed;
} scene;

scene *scene_create(void);
void scene_destroy(scene *s); /* NULL is fine */

/* Append; return the new element's index, or -1 on allocation failure. */
int scene_add_material(scene *s, const material *m);
int scene_add_light(scene *s, const light *l);
/* Takes ownership of `m` (also on failure). Adds the mesh as a geometry of
 * the triangles kind and one identity instance of it; returns the mesh index
 * (into meshes), which is also that instance's id while no other geometry
 * was placed before it. */
int scene_add_mesh(scene *s, mesh *m, uint32_t material_id, const char *name);
/* The first sphere also adds the sphere set's geometry and instance
 * (sphere_instance). */
int scene_add_sphere(scene *s, vec3 center, float radius, uint32_t material_id);

/* Register a geometry of any kind (geometry.h: this is the whole
 * registration). The ops must outlive the scene and give every operation a
 * kind needs (prim_count, prim_bounds, intersect, describe; fill_lane for the
 * SIMD layouts); the scene owns `data` from now on when ops->destroy is set
 * (also on failure). Returns the geometry index, or -1 (allocation, bad ops). */
int scene_add_geometry(scene *s, const geometry_ops *ops, void *data, const char *name);
/* Place geometry `geometry` by `to_world` (NULL: identity) as part `part`
 * (SCENE_NO_PART: none). Returns the instance id, or -1 for a geometry the
 * scene does not have, a transform that is singular or not finite, or no
 * memory. */
int scene_add_instance(scene *s, uint32_t geometry, const affine3 *to_world, uint32_t part);

/* Add a participating medium placed by to_world (NULL: identity); the
 * scene owns data from now on when ops->destroy is set (also on failure).
 * Returns its index, or -1 (no memory, a singular transform, bad ops). */
int scene_add_medium(scene *s, const medium_ops *ops, void *data, const affine3 *to_world, const char *name);

/* A geometry of the triangles kind without an instance (an assembly places
 * it by scene_add_instance). Takes ownership of `m` (also on failure).
 * Returns the geometry index, or -1. */
int scene_add_mesh_geometry(scene *s, mesh *m, uint32_t material_id, const char *name);

/* The instance id range [*first, *end) of part `part`'s subtree (the part
 * and every part under it); empty when it has no instances. Any thread,
 * O(log instances). */
void scene_part_instances(const scene *s, uint32_t part, uint32_t *first, uint32_t *end);

/* Give the instances of every part whose path matches `pattern`
 * (part_tree.h patterns) and of their subtrees material `material_id`.
 * Returns the number of parts matched (0 is not an error). */
long scene_colour_parts(scene *s, const char *pattern, uint32_t material_id);

/* The instance's geometry (instance < instance_count). */
static inline const scene_geometry *scene_instance_geometry(const scene *s, uint32_t instance)
{
    return &s->geometries[s->instances[instance].geometry];
}

/* Whether geometry `geometry` bounds a solid, so that where a cutting plane
 * cuts it the cut can be capped (its kind's `closed` operation, geometry.h;
 * false for a kind without one, or when memory for the cache is short: then
 * there are no caps rather than a pass over the data per call). Computed on
 * the first call for that geometry and cached (the scene's `closed`); any
 * thread, at any time the scene is not being changed. */
bool scene_geometry_closed(const scene *s, uint32_t geometry);
/* Forget the cached answer for geometry `geometry` (its kind's answer
 * changed: an iso-surface's value was set, geometry.h set_value); the next
 * question asks the kind again. Only where nothing renders. */
void scene_forget_closed(scene *s, uint32_t geometry);
/* Answer scene_geometry_closed for every geometry now, over `threads`
 * threads (the caller counted): for the serial section where cutting planes
 * turn on, so no render thread stalls on a first question. */
void scene_prepare_closed(const scene *s, int threads);

/* World bounds of one instance; false when its geometry has nothing to hit. */
bool scene_instance_bounds(const scene *s, uint32_t instance, aabb *out);
/* Object-space bounds of a geometry; false when it has nothing to hit. */
bool scene_geometry_bounds(const scene *s, uint32_t geometry, aabb *out);

/* World-space bounds of all instances; false for an empty scene. */
bool scene_bounds(const scene *s, vec3 *lo, vec3 *hi);

/* TIME STEPS of the scene: the steps of its longest time series over the
 * geometries and media that have step ops (1: none), and whether every one
 * of them can show `step` without waiting (each that cannot is asked to
 * load it: the input's play asks ahead this way). Any thread (the series'
 * own locks make the question safe while frames render). */
uint32_t scene_time_steps(const scene *s);
bool scene_step_ready(const scene *s, uint32_t step);

/* Total triangles over all meshes (each stored once). */
size_t scene_triangle_count(const scene *s);
/* Triangles over all instances (a mesh placed twice counts twice). */
size_t scene_instanced_triangle_count(const scene *s);

/* Points (primitives of GEOMETRY_LEAF_POINTS kinds: particles) over all
 * geometries, each stored once, and the bytes of those kinds' own data
 * (ops->bytes: positions and attributes; their trees are in accel_bytes). */
size_t scene_point_count(const scene *s);
size_t scene_point_bytes(const scene *s);

/* Defaults used by loaders. */
material material_default(void);          /* grey Lambert */
light light_default_directional(void);    /* direction (0.4, 1, 0.3), white, casts shadows */

/* The built-in scene that needs no data file: a ground plane, a tessellated
 * mesh, a group of spheres and two lights. NULL only on allocation failure. */
scene *scene_create_default(tess_error *err);

/* Loading a scene from files (a JSON scene file, a mesh, an assembly, a
 * particle file) is engine/load/scene_load.h. */

#endif
