/* volume_json.h - one entry of a scene file's "volumes" array
 * (docs/scene-format.md "Volumes"): a structured volume shown as direct
 * iso-surfaces (iso_kind.h: each value a geometry of its own, with its own
 * colour) and/or rendered directly (dvr_medium.h: a participating medium
 * through a transfer function). The scene loader reads the members every
 * placed thing has ("file" or "files", "transform"/"matrix", "optional")
 * and hands the loaded volume (a series' first step) here. */
#ifndef TESSERA_VOLUME_JSON_H
#define TESSERA_VOLUME_JSON_H

#include <json.h>
#include <stdint.h>

#include "engine/accel/geometry.h"
#include "engine/base/json_read.h"
#include "engine/geometry/volume/volume.h"

struct scene;

/* The members of a "volumes" entry (NULL-terminated), the scene loader's
 * and this module's, for jr_check_fields. */
extern const char *const volume_json_fields[];

/* The scene material named `name`, or -1 (the scene loader's lookup). */
typedef int (*volume_json_material_fn)(void *ctx, const char *name);

/* Add volume `v` (taken, also on failure) to scene s as entry `obj` (the
 * current field of c) says, placed by `placement` (NULL: as in the file):
 * its "iso" surfaces as geometries and instances in the material named by
 * each (or default_material), and its "dvr" medium. At least one of the
 * two is required. A time series ("files"): `steps` names step_count files
 * in step order, v being steps[0] loaded; the iso-surfaces and the medium
 * step together (iso_kind.h TIME STEPS). NULL: one volume. False with a
 * message naming the field. */
bool volume_json_add(jr_ctx *c, json_object *obj, volume *v, const char *const *steps, uint32_t step_count,
                     const affine3 *placement, struct scene *s, uint32_t default_material,
                     volume_json_material_fn find_material, void *material_ctx);

#endif
