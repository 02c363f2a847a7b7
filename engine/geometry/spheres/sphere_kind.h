/* sphere_kind.h - spheres as a geometry kind (geometry.h): a sphere_set is
 * the kind's data; a scene keeps one (scene.h: scene_add_sphere). */
#ifndef TESSERA_GEOMETRY_SPHERE_KIND_H
#define TESSERA_GEOMETRY_SPHERE_KIND_H

#include <stdint.h>

#include "engine/accel/geometry.h"

/* All spheres of a scene, structure of arrays (millions of particles later). */
typedef struct sphere_set {
    uint32_t count, capacity;
    float *center_x, *center_y, *center_z; /* world units */
    float *radius;                          /* world units, > 0 */
    uint32_t *material_id;                  /* per sphere */
} sphere_set;

/* The kind: data is a sphere_set. */
extern const geometry_ops geometry_spheres_ops;

#endif
