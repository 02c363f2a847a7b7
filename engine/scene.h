/* scene.h - what is rendered: geometry, materials, lights, camera, background.
 *
 * A scene owns its meshes (already transformed to world space at load time)
 * and its spheres. Geometry ids: meshes are 0..mesh_count-1 in order, the
 * sphere set (if any) is mesh_count. Primitive ids are per geometry
 * (triangle index in its mesh, sphere index in the sphere set).
 * The scene is immutable while frames render; changes go through transactions
 * (the pipeline issue). */
#ifndef TESSERA_SCENE_H
#define TESSERA_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "camera.h"
#include "err.h"
#include "mesh.h"
#include "vec3.h"

#define SCENE_NAME_BYTES 64

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

/* One mesh in the scene and how its triangles are shaded. */
typedef struct scene_mesh {
    mesh *mesh;            /* owned, world space */
    uint32_t material_id;  /* index into scene.materials, used when the mesh has no own materials */
    uint32_t *mesh_material_ids; /* mesh->material_count scene material ids for a mesh with its own
                                    materials (OBJ+MTL), else NULL; owned */
    char name[SCENE_NAME_BYTES];
} scene_mesh;

/* All spheres of a scene, structure of arrays (millions of particles later). */
typedef struct sphere_set {
    uint32_t count, capacity;
    float *center_x, *center_y, *center_z; /* world units */
    float *radius;                          /* world units, > 0 */
    uint32_t *material_id;                  /* per sphere */
} sphere_set;

typedef struct scene {
    scene_mesh *meshes;
    uint32_t mesh_count, mesh_capacity;
    sphere_set spheres;
    material *materials;
    uint32_t material_count, material_capacity;
    light *lights;
    uint32_t light_count, light_capacity;
    vec3 background;      /* linear RGB of rays that hit nothing */
    vec3 ambient;         /* linear RGB ambient light */
    bool has_camera;      /* false: frame the bounds with camera_frame_bounds() */
    camera_desc camera;
} scene;

scene *scene_create(void);
void scene_destroy(scene *s); /* NULL is fine */

/* Append; return the new element's index, or -1 on allocation failure. */
int scene_add_material(scene *s, const material *m);
int scene_add_light(scene *s, const light *l);
/* Takes ownership of `m` (also on failure). */
int scene_add_mesh(scene *s, mesh *m, uint32_t material_id, const char *name);
int scene_add_sphere(scene *s, vec3 center, float radius, uint32_t material_id);

/* World-space bounds of all geometry; false for an empty scene. */
bool scene_bounds(const scene *s, vec3 *lo, vec3 *hi);

/* Total triangles over all meshes. */
size_t scene_triangle_count(const scene *s);

/* Defaults used by loaders. */
material material_default(void);          /* grey Lambert */
light light_default_directional(void);    /* direction (0.4, 1, 0.3), white, casts shadows */

/* The built-in scene that needs no data file: a ground plane, a tessellated
 * mesh, a group of spheres and two lights. NULL only on allocation failure. */
scene *scene_create_default(tess_error *err);

/* Load a JSON scene file (see README "Scene files"), or a mesh file directly
 * (any extension mesh_load() reads): then a grey Lambert material, the default
 * directional light, and no camera (so the caller frames the bounds). */
scene *scene_load(const char *path, tess_error *err);
scene *scene_load_json(const char *path, tess_error *err);
/* The same from `len` bytes of JSON text (need not be NUL-terminated): `path`
 * names the text in messages, and relative mesh paths resolve from its
 * directory. */
scene *scene_parse_json(const char *path, const char *text, size_t len, tess_error *err);

#endif
