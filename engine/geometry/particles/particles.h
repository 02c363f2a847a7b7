/* particles.h - a particle set: millions of points drawn as spheres, each
 * with any number of named float attributes (temperature, energy, a
 * velocity component, a colour channel), as a simulation or a scanner
 * writes them.
 *
 * LAYOUT. Positions are structure of arrays (x[], y[], z[]: 12 bytes a
 * particle) and every attribute is one float array beside them, so a set
 * pays for the attributes its file has and nothing else. The radius is one
 * number for the whole set, or an attribute (per-particle radius).
 *
 * ORDER. particle_set_permute reorders every array at once (the BVH build
 * puts each leaf's particles next to each other, so a leaf is a range of
 * the arrays and no position is ever copied). Particle i is therefore the
 * i-th of the *current* order; a file's own particle ids, when it has them
 * (LAMMPS "id"), are an attribute like any other.
 *
 * Ownership: the set owns every array; particle_set_destroy frees them.
 * Threading: none inside; a set is read-only while an accel built from it
 * exists. */
#ifndef TESSERA_PARTICLES_H
#define TESSERA_PARTICLES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"

#define PARTICLE_NAME_BYTES 32
/* more named columns than any LAMMPS dump or PLY point cloud we know has */
#define PARTICLE_MAX_ATTRIBUTES 64
/* the most particles one set may hold: ids stay below RAY_INVALID_ID and
 * every byte count fits in size_t on the 64-bit targets we build for */
#define PARTICLE_MAX_COUNT 0x7FFFFFFFu

typedef struct particle_attribute {
    char name[PARTICLE_NAME_BYTES];
    float *values; /* one per particle (count of them), finite */
    float min, max; /* over all values, set by particle_set_finish (0, 0 for an empty set) */
} particle_attribute;

typedef struct particle_set {
    uint32_t count, capacity;          /* particles, allocated slots of every array */
    float *x, *y, *z;                  /* centres, object space */
    particle_attribute attributes[PARTICLE_MAX_ATTRIBUTES];
    uint32_t attribute_count;
    int64_t timestep;                  /* the file's time step (LAMMPS "ITEM: TIMESTEP"), -1 when none */
} particle_set;

particle_set *particle_set_create(void);
void particle_set_destroy(particle_set *p); /* NULL is fine */

/* Room for at least n particles in every array (positions and attributes);
 * false on allocation failure or n > PARTICLE_MAX_COUNT. */
bool particle_set_reserve(particle_set *p, uint32_t n);

/* Make every array hold exactly count + spare particles (the spare zeroed):
 * what a set keeps once loaded (geometric growth may have left up to twice
 * its size). False on no memory (the set is unchanged) or past
 * PARTICLE_MAX_COUNT. */
bool particle_set_fit(particle_set *p, uint32_t spare);

/* Add an attribute named `name` (its values array sized to the capacity,
 * zeroed); returns its index, or -1 when the name is taken, empty or too
 * long, the set already has PARTICLE_MAX_ATTRIBUTES, or memory is short. */
int particle_set_add_attribute(particle_set *p, const char *name);

/* The index of the attribute called `name`, or -1. */
int particle_set_find_attribute(const particle_set *p, const char *name);

/* Append one particle at (x, y, z) with its attributes' values (attribute_count
 * of them, or NULL: zeros), growing geometrically. False on no memory or at
 * PARTICLE_MAX_COUNT. */
bool particle_set_add(particle_set *p, float x, float y, float z, const float *attribute_values);

/* Check what rendering relies on (finite positions and attribute values)
 * and compute every attribute's min and max. `source` names the file in
 * the message: "SOURCE: particle N: ATTRIBUTE is not finite". */
bool particle_set_finish(particle_set *p, const char *source, tess_error *err);

/* Reorder every array: new particle i is old particle order[i] (order is a
 * permutation of 0..count-1). False (nothing changed) on no memory. */
bool particle_set_permute(particle_set *p, const uint32_t *order);

/* Bytes of the set's arrays (positions and attributes, by count, not capacity). */
size_t particle_set_bytes(const particle_set *p);

/* Bounds of the centres; false for an empty set. */
bool particle_set_bounds(const particle_set *p, float lo[3], float hi[3]);

/* Reading a particle file is engine/load/particle_load.h. */

#endif
