/* dvec3.h - 3-vectors in double precision, for the math that must not lose
 * what float would (camera path interpolation, camera motions): computed in
 * double, rounded to float once at the end (dv_to_float). Header-only. */
#ifndef TESSERA_DVEC3_H
#define TESSERA_DVEC3_H

#include <math.h>
#include <stdbool.h>

#include "vec3.h"

typedef struct dvec3 {
    double x, y, z;
} dvec3;

static inline dvec3 dv(vec3 a) { return (dvec3){a.x, a.y, a.z}; }
static inline vec3 dv_to_float(dvec3 a) { return v3((float)a.x, (float)a.y, (float)a.z); }
static inline dvec3 dv_add(dvec3 a, dvec3 b) { return (dvec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline dvec3 dv_sub(dvec3 a, dvec3 b) { return (dvec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline dvec3 dv_scale(dvec3 a, double s) { return (dvec3){a.x * s, a.y * s, a.z * s}; }
static inline double dv_dot(dvec3 a, dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline dvec3 dv_cross(dvec3 a, dvec3 b)
{
    return (dvec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline double dv_length(dvec3 a) { return sqrt(dv_dot(a, a)); }

/* Unit vector along a; false (and *out untouched) for a zero or non-finite a. */
static inline bool dv_unit(dvec3 a, dvec3 *out)
{
    double len = dv_length(a);
    if (!(len > 0.0 && isfinite(len)))
        return false;
    *out = dv_scale(a, 1.0 / len);
    return true;
}

/* a + s (b - a) */
static inline dvec3 dv_lerp(dvec3 a, dvec3 b, double s) { return dv_add(a, dv_scale(dv_sub(b, a), s)); }

#endif
