/* input_pick.h - the input controller's pick hook (input/controller.h) over a
 * scene and its accel: the first visible surface along a ray, and the part
 * that hiding, isolating and highlighting act on.
 *
 * With a part tree (scene.parts) and a hit instance placed on a part: what =
 * "part PATH triangle N", the part = that part's whole subtree as an instance
 * id range (scene_part_instances) labelled by its path, and the ancestors =
 * its parent, grandparent, ... up to the top-level part (the root, which
 * stands for the file, is none), at most INPUT_HIT_ANCESTORS of them. A path
 * longer than a label keeps its tail after "...". Without parts (or for an
 * instance without one) the part is the instance hit, (geom_id, 1), labelled
 * as before ("mesh 0 'bunny'", "the sphere set (6 spheres)"), no ancestors.
 *
 * Threading: the input thread; the accel is read-only but for the hidden
 * flags, which accel_pick reads atomically; the scene and part tree are
 * only read. */
#ifndef TESSERA_CLI_INPUT_PICK_H
#define TESSERA_CLI_INPUT_PICK_H

#include "engine/base/vec3.h"
#include "input/controller.h"

struct scene;
struct accel;

void cli_input_pick(const struct scene *s, const struct accel *a, vec3 origin, vec3 dir, input_hit *out);

#endif
