/* accel.h - the scene's acceleration structure: one BVH per geometry (mesh or
 * sphere set) under a top-level BVH over the geometries' bounds.
 *
 * Built once per scene; read-only afterwards, so any number of render threads
 * may trace through it concurrently without locks, with one exception: the
 * per-geometry HIDDEN flags (accel_set_hidden). A hidden geometry is not hit
 * by any query here (so it is not seen and casts no shadows). The flags are
 * relaxed atomics, so reading them while they change is not a data race, but
 * a frame traced while one changes mixes both states: change them only where
 * nothing traces for a picture, i.e. in a pipeline's serial section (what
 * pipeline_queue_hide does; hiding is a property of the accel, seen by every
 * pipeline using it) or while no pipeline or render runs. Another thread may
 * query the accel meanwhile (picking), seeing each flag old or new. */
#ifndef TESSERA_ACCEL_H
#define TESSERA_ACCEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "err.h"
#include "packet.h"
#include "ray.h"

struct scene;
typedef struct accel accel;

/* The scene must outlive the accel and stay unchanged while it is used.
 * `threads` threads build it (the caller's included). */
accel *accel_build(const struct scene *s, int threads, tess_error *err);
void accel_destroy(accel *a); /* NULL is fine */

/* Closest hit in (r->t_near, r->t_far]; fills *h (hit_none() on a miss) and
 * returns whether something was hit. Degenerate rays miss. */
bool accel_intersect(const accel *a, const ray *r, hit *h);

/* Any hit in (r->t_near, r->t_far]; stops at the first one found. */
bool accel_occluded(const accel *a, const ray *r);

/* Closest hits for the active rays of a sub-packet: fills hit_* and shrinks
 * t_far of each ray that hits. Results are bit-identical to accel_intersect on
 * each ray alone (ties in t go to the lowest geometry id, then primitive id). */
void accel_intersect_packet(const accel *a, packet_range r);

/* Any-hit for the active rays of a sub-packet: returns the mask of rays
 * (bits as in packet->active) that are occluded. */
uint64_t accel_occluded_packet(const accel *a, packet_range r);

/* Geometries: ids 0..count-1 as in scene.h (meshes, then the sphere set). */
uint32_t accel_geometry_count(const accel *a);

/* Hide geometry geom_id from every query above, or show it again; ids out of
 * range are ignored. Who may call these: see the header comment. New accels
 * hide nothing. */
void accel_set_hidden(const accel *a, uint32_t geom_id, bool hidden);
void accel_unhide_all(const accel *a);
/* Whether geom_id is hidden (false out of range). Any thread. */
bool accel_hidden(const accel *a, uint32_t geom_id);

/* Bytes of acceleration data (nodes, primitive blocks), not counting the scene. */
size_t accel_bytes(const accel *a);

/* The instruction set of the kernels in use ("sse2", "avx2", "avx512"). */
const char *accel_isa_name(const accel *a);

/* Switch to the kernels of instruction set `isa_name`; false (kernels
 * unchanged) when the name is unknown or this CPU cannot run them. Results
 * are bit-identical for every instruction set. Not while rays are traced. */
bool accel_use_isa(accel *a, const char *isa_name);

#endif
