/* accel.h - the scene's acceleration structure, two levels: one wide BVH per
 * geometry (stored once, however many instances place it) under a wide BVH
 * over the instances' world boxes (the top level). Single rays and packets
 * traverse both with the same kernels; a packet meets an instance with a
 * transform in that instance's object space (rays mapped once per visit).
 *
 * Built once per scene; read-only afterwards, so any number of render threads
 * may trace through it concurrently without locks, with one exception: the
 * per-instance HIDDEN flags (accel_set_hidden) and the top level's boxes that
 * follow them. A hidden instance is not hit by any query here (so it is not
 * seen and casts no shadows). Change them only where nothing traces for a
 * picture, i.e. in a pipeline's serial section (what pipeline_queue_hide
 * does; hiding is a property of the accel, seen by every pipeline using it)
 * or while no pipeline or render runs. Another thread may pick meanwhile
 * through accel_pick (which takes the lock a refit holds), seeing the state
 * before or after the change.
 *
 * Showing an instance refits the top level at once (O(top nodes)); hiding
 * only sets the flag (traversal skips the instance) and leaves the boxes for
 * accel_commit to shrink, so a hidden subtree of parts costs no traversal
 * after the next commit. Results never depend on whether a commit ran. */
#ifndef TESSERA_ACCEL_H
#define TESSERA_ACCEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"
#include "engine/accel/geometry.h"
#include "engine/accel/packet.h"
#include "engine/accel/ray.h"

struct scene;
typedef struct accel accel;

/* The scene must outlive the accel and stay unchanged while it is used.
 * `threads` threads build it (the caller's included). */
accel *accel_build(const struct scene *s, int threads, tess_error *err);
void accel_destroy(accel *a); /* NULL is fine */

/* Closest hit in (r->t_near, r->t_far]; fills *h (hit_none() on a miss) and
 * returns whether something was hit. Degenerate rays miss. */
bool accel_intersect(const accel *a, const ray *r, hit *h);

/* The next surface along a ray: the closest hit in (r->t_near, r->t_far]
 * that comes after `after` (a hit of this ray found before; after->t finite)
 * in the closest-hit order (t, geom_id, prim_id). Walking a ray's surfaces
 * one by one this way visits each exactly once, coplanar ones (equal t) in
 * id order, whatever the packet, thread or tile: what transparency and caps
 * need. In packets: packet_set_after on the rays, then
 * accel_intersect_packet (bit-identical to this). */
bool accel_intersect_after(const accel *a, const ray *r, const hit *after, hit *h);

/* accel_intersect restricted to instance geom_id (hidden or not), and with
 * a next-hit bound when `after` is not NULL: parity counts of one part. */
bool accel_intersect_instance(const accel *a, uint32_t geom_id, const ray *r, const hit *after, hit *h);

/* Any hit in (r->t_near, r->t_far]; stops at the first one found. */
bool accel_occluded(const accel *a, const ray *r);

/* A measurement switch (tessera bench --single-rays): with it the packet
 * queries below trace each ray alone through the single-ray queries above
 * (same results, bit for bit), so the packet path can be timed against
 * single rays on the same frames. Set it before tracing, never during. */
void accel_set_single_rays(accel *a, bool single_rays);

/* Closest hits for the active rays of a sub-packet: fills hit_* and shrinks
 * t_far of each ray that hits. Results are bit-identical to accel_intersect on
 * each ray alone (ties in t go to the lowest geometry id, then primitive id). */
void accel_intersect_packet(const accel *a, packet_range r);

/* Any-hit for the active rays of a sub-packet: returns the mask of rays
 * (bits as in packet->active) that are occluded. */
uint64_t accel_occluded_packet(const accel *a, packet_range r);

/* The closest hit like accel_intersect, from a thread other than the render
 * threads while a serial section may change hidden flags (picking). */
bool accel_pick(const accel *a, const ray *r, hit *h);

/* Instances: ids 0..count-1 as in scene.h (hit.geom_id). */
uint32_t accel_geometry_count(const accel *a);

/* The world box of every instance as the scene placed it, taken at build
 * (the boxes traversal starts from: for triangles the vertices' box): what
 * scene_bounds gives, in O(1), and the same whatever is hidden or moved
 * later (ambient occlusion scales its ray length by it, and must not change
 * while a part is hidden). False when nothing can be hit. Any thread. */
bool accel_scene_bounds(const accel *a, vec3 *lo, vec3 *hi);

/* Hide instance geom_id (or ids [first, first + count)) from every query
 * above, or show it again; ids out of range are ignored. Who may call these:
 * see the header comment. New accels hide nothing. */
void accel_set_hidden(const accel *a, uint32_t geom_id, bool hidden);
void accel_set_hidden_range(const accel *a, uint32_t first, uint32_t count, bool hidden);
void accel_unhide_all(const accel *a);
/* Shrink the top level's boxes to the instances still shown, if anything was
 * hidden since the last refit; returns whether it refitted. Same callers as
 * accel_set_hidden. */
bool accel_commit(const accel *a);
/* Whether geom_id is hidden (false out of range). Any thread. */
bool accel_hidden(const accel *a, uint32_t geom_id);

/* Where instance geom_id is now: the scene's placement, or after
 * accel_set_placement the move applied after it. Render threads read it
 * while shading; it changes only where hidden flags may (header comment). */
typedef struct accel_placement {
    affine3 to_world, to_object;
    bool identity; /* to_world is the identity */
} accel_placement;
const accel_placement *accel_placement_of(const accel *a, uint32_t geom_id);

/* Place instances [first, first + count) by moves[i] applied after the
 * scene's placement (the identity: back where the scene put them), and
 * refit the instance level once. moves must be invertible (txn_validate);
 * one that is not leaves its instance where it was. Same callers as
 * accel_set_hidden. */
void accel_set_placement(const accel *a, uint32_t first, uint32_t count, const affine3 *moves);

/* Set the crop of instance geom_id's geometry (geometry_ops.set_crop:
 * particles seen only where their crop attribute lies in the range; every
 * instance of that geometry follows). Ids out of range and kinds without a
 * crop are ignored. Same callers as accel_set_hidden. */
void accel_set_crop(const accel *a, uint32_t geom_id, geometry_crop crop);

/* Set the scalar parameter (an iso-value: geometry_ops.set_value) / the
 * colour map (geometry_ops.set_colormap) of instance geom_id's geometry
 * (every instance of it follows). Ids out of range and kinds without one
 * are ignored. Same callers as accel_set_hidden. */
void accel_set_value(const accel *a, uint32_t geom_id, float value);
void accel_set_colormap(const accel *a, uint32_t geom_id, const char *name);
/* Every medium of the scene (scene.h, PARTICIPATING MEDIA) that can change
 * it takes the built-in transfer function `name`. Same callers. */
void accel_set_transfer(const accel *a, const char *name);

/* Show time step `step` of every geometry and medium that has steps
 * (geometry_ops.set_step, medium_ops.set_step; each takes it modulo its
 * own count), take the new trees of GEOMETRY_LEAF_POINTS kinds, rebuild the
 * bottom level of other stepped kinds (their boxes may move: an
 * iso-surface's one box), drop their cached `closed` answers and refit the
 * instance level.
 * Waits for a step that is not loaded yet. False, with the first error,
 * when a step could not be had (those geometries keep theirs). Same callers
 * as accel_set_hidden. */
bool accel_set_time_step(const accel *a, uint32_t step, tess_error *err);

/* Bytes of acceleration data (nodes, primitive blocks), not counting the scene. */
size_t accel_bytes(const accel *a);

/* The instruction set of the kernels in use ("sse2", "avx2", "avx512"). */
const char *accel_isa_name(const accel *a);

/* Switch to the kernels of instruction set `isa_name`; false (kernels
 * unchanged) when the name is unknown or this CPU cannot run them. Results
 * are bit-identical for every instruction set. Not while rays are traced. */
bool accel_use_isa(accel *a, const char *isa_name);

/* A 64-bit checksum (XXH3) of the trees as built: every geometry's and the
 * instance boxes. Equal on two processes that built the same scene the same
 * way (the build is deterministic, whatever the thread count), so processes
 * rendering one picture compare it before they start (cluster/). Hiding and
 * moving change what it reads: take it before either. 0 when out of memory. */
uint64_t accel_checksum(const accel *a);

#endif
