/* surface.h - a hit described for shading, in world space: what every
 * renderer (raytracer, eyelight, ao) needs of the surface a ray met.
 *
 * The hit's instance's geometry describes it in object space (the ray mapped
 * there as traversal mapped it), the instance's current placement (accel.h:
 * moves included) puts it in the world, and the frame state (render_view.state)
 * overrides its colour and highlights it. Pure: any render thread, any time. */
#ifndef TESSERA_SURFACE_H
#define TESSERA_SURFACE_H

#include <stdbool.h>

#include "engine/accel/ray.h"
#include "render.h"
#include "engine/scene/scene.h"
#include "engine/base/vec3.h"

/* What shading needs to know about a hit. */
typedef struct surface {
    vec3 position;       /* world */
    vec3 position_error; /* componentwise rounding bound of position (ray.h surface_point) */
    vec3 geometric_n;    /* unit, facing the incoming ray */
    vec3 shading_n;      /* unit, same hemisphere as geometric_n */
    vec3 kd;             /* diffuse reflectance */
    const material *mat;
} surface;

/* The surface of hit h of ray r (both world). The position (and its error
 * bound) only when need_position, i.e. when shading will cast a ray from it
 * or light it; normals face the ray's origin (two-sided surfaces). */
surface surface_describe(const render_view *v, const ray *r, const hit *h, bool need_position);

#endif
