/* particle_json.h - one entry of a scene file's "particles" array
 * (docs/scene-format.md "Particles"): what it says about the particles
 * themselves. The scene loader reads the members every placed thing has
 * ("file", "material", "transform"/"matrix", "optional") and hands the
 * loaded set here. */
#ifndef TESSERA_PARTICLE_JSON_H
#define TESSERA_PARTICLE_JSON_H

#include <json.h>
#include <stdbool.h>
#include <stdint.h>

#include "engine/base/json_read.h"
#include "engine/geometry/particles/particle_kind.h"

/* The members of a "particles" entry (NULL-terminated), the scene loader's
 * and this module's, for jr_check_fields. */
extern const char *const particle_json_fields[];

/* A kind over `set` (taken, also on failure) as entry `v` (the current field
 * of c) describes it: "radius", "crop", and the colour members. Errors name
 * the field: "PATH: field 'particles[0].crop.attribute': no attribute 'x'
 * (the file has: id, type, c_ke)". */
particle_kind *particle_json_kind(jr_ctx *c, json_object *v, particle_set *set, uint32_t material_id);

#endif
