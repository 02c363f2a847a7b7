/* particle_load.h - a particle set (engine/geometry/particles/particles.h)
 * from a file: PLY point sets (over ply_read.h) and LAMMPS text dumps. */
#ifndef TESSERA_LOAD_PARTICLE_LOAD_H
#define TESSERA_LOAD_PARTICLE_LOAD_H

#include "engine/base/err.h"
#include "engine/geometry/particles/particles.h"

/* Load a particle file: PLY (vertex element only: x y z and any other
 * scalar vertex property as an attribute, ascii or binary) by the ".ply"
 * extension, a LAMMPS text dump ("ITEM: ATOMS id type x y z ...", also
 * xs/ys/zs scaled and xu/yu/zu unwrapped coordinates) by ".dump",
 * ".lammpstrj" or a first line "ITEM: TIMESTEP". An error names the file,
 * the line or element, and the problem. The set is finished. */
particle_set *particles_load(const char *path, tess_error *err);
particle_set *particles_load_ply(const char *path, tess_error *err);
particle_set *particles_load_lammps(const char *path, tess_error *err);

#endif
