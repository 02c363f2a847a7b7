/* vec.h - the few double-precision 3-vector operations the shape builders
 * need. Geometry is computed in double and rounded to float once, when a
 * vertex is stored. */
#ifndef TESSERA_GEN_ASSEMBLY_VEC_H
#define TESSERA_GEN_ASSEMBLY_VEC_H

#include <math.h>

struct ga_v3 {
    double x, y, z;
};

static inline struct ga_v3 ga_v3_make(double x, double y, double z) { return (struct ga_v3){x, y, z}; }

static inline struct ga_v3 ga_v3_add(struct ga_v3 a, struct ga_v3 b) { return ga_v3_make(a.x + b.x, a.y + b.y, a.z + b.z); }

static inline struct ga_v3 ga_v3_sub(struct ga_v3 a, struct ga_v3 b) { return ga_v3_make(a.x - b.x, a.y - b.y, a.z - b.z); }

static inline struct ga_v3 ga_v3_scale(struct ga_v3 a, double s) { return ga_v3_make(a.x * s, a.y * s, a.z * s); }

static inline double ga_v3_dot(struct ga_v3 a, struct ga_v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

static inline struct ga_v3 ga_v3_cross(struct ga_v3 a, struct ga_v3 b)
{
    return ga_v3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* a * s + b * t: a point or direction in the frame spanned by a and b. */
static inline struct ga_v3 ga_v3_comb(struct ga_v3 a, double s, struct ga_v3 b, double t)
{
    return ga_v3_make(a.x * s + b.x * t, a.y * s + b.y * t, a.z * s + b.z * t);
}

static inline struct ga_v3 ga_v3_normalize(struct ga_v3 a)
{
    double len = sqrt(ga_v3_dot(a, a));
    return len > 0.0 ? ga_v3_scale(a, 1.0 / len) : ga_v3_make(0.0, 0.0, 1.0);
}

#endif
