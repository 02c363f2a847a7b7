/* packet.h - ray packets: up to 64 rays in structure-of-arrays layout.
 *
 * Every array is 64-byte aligned, so a kernel loads 4, 8 or 16 consecutive
 * rays of one component with one aligned load. Ray i of a packet lives at
 * index i of every array.
 *
 * Flags say what whoever filled the packet knows (PACKET_COMMON_ORIGIN ...),
 * so kernels can pick faster code, and which derived values have been
 * computed (PACKET_HAVE_...): each is computed at most once, by the
 * packet_derive_* functions, which check the flag first.
 *
 * Sub-packets are index ranges [begin, end) of one packet (packet_range),
 * never copies. Rays that are done are cleared from `active`; kernels touch
 * only active rays inside their range.
 *
 * Conventions are those of ray.h: hits in (t_near, t_far]; a miss leaves
 * hit_t = +inf and ids RAY_INVALID_ID; on a hit t_far becomes hit_t. */
#ifndef TESSERA_PACKET_H
#define TESSERA_PACKET_H

#include <stdalign.h>
#include <stdbool.h>
#include <stdint.h>

#include "ray.h"

#define PACKET_MAX_RAYS 64

enum packet_flags {
    /* facts about the rays, set by whoever generates them */
    PACKET_COMMON_ORIGIN = 1u << 0,  /* all rays in [0, count) share org of ray 0 */
    PACKET_CONSTANT_SIGNS = 1u << 1, /* each dir component has one sign over [0, count) (zero counts as +) */
    PACKET_NORMALIZED = 1u << 2,     /* every dir has unit length */
    /* a query bound: only hits after (after_t, after_geom, after_prim) of each ray count
     * (accel_intersect_after's order); set by packet_set_after, cleared by packet_reset */
    PACKET_AFTER_HIT = 1u << 3,
    /* derived values, computed lazily and at most once */
    PACKET_HAVE_INV_DIR = 1u << 8,         /* inv_dir_* */
    PACKET_HAVE_HIT_POSITION = 1u << 9,    /* pos_* of rays that hit */
    PACKET_HAVE_GEOMETRIC_NORMAL = 1u << 10, /* ng_* of rays that hit */
    PACKET_HAVE_SHADING_NORMAL = 1u << 11, /* ns_* of rays that hit */
};

typedef struct ray_packet {
    /* the rays */
    alignas(64) float org_x[PACKET_MAX_RAYS];
    alignas(64) float org_y[PACKET_MAX_RAYS];
    alignas(64) float org_z[PACKET_MAX_RAYS];
    alignas(64) float dir_x[PACKET_MAX_RAYS];
    alignas(64) float dir_y[PACKET_MAX_RAYS];
    alignas(64) float dir_z[PACKET_MAX_RAYS];
    alignas(64) float t_near[PACKET_MAX_RAYS]; /* exclusive */
    alignas(64) float t_far[PACKET_MAX_RAYS];  /* inclusive; shrinks to the closest hit */
    /* hit record */
    alignas(64) float hit_t[PACKET_MAX_RAYS];
    alignas(64) float hit_u[PACKET_MAX_RAYS];
    alignas(64) float hit_v[PACKET_MAX_RAYS];
    alignas(64) uint32_t prim_id[PACKET_MAX_RAYS];
    alignas(64) uint32_t geom_id[PACKET_MAX_RAYS];
    alignas(64) uint32_t material_id[PACKET_MAX_RAYS]; /* filled by shading, not by traversal */
    /* next-hit bounds (PACKET_AFTER_HIT): after_t -inf for a ray without one */
    alignas(64) float after_t[PACKET_MAX_RAYS];
    alignas(64) uint32_t after_geom[PACKET_MAX_RAYS];
    alignas(64) uint32_t after_prim[PACKET_MAX_RAYS];
    /* derived values (see flags) */
    alignas(64) float inv_dir_x[PACKET_MAX_RAYS]; /* 1/dir, +-FLT_MAX for a zero component */
    alignas(64) float inv_dir_y[PACKET_MAX_RAYS];
    alignas(64) float inv_dir_z[PACKET_MAX_RAYS];
    alignas(64) float pos_x[PACKET_MAX_RAYS]; /* hit position, world */
    alignas(64) float pos_y[PACKET_MAX_RAYS];
    alignas(64) float pos_z[PACKET_MAX_RAYS];
    alignas(64) float ng_x[PACKET_MAX_RAYS]; /* unit geometric normal facing the ray's origin */
    alignas(64) float ng_y[PACKET_MAX_RAYS];
    alignas(64) float ng_z[PACKET_MAX_RAYS];
    alignas(64) float ns_x[PACKET_MAX_RAYS]; /* unit shading normal, same side as ng */
    alignas(64) float ns_y[PACKET_MAX_RAYS];
    alignas(64) float ns_z[PACKET_MAX_RAYS];
    uint64_t active;  /* bit i set: ray i is still to be traced / shaded */
    uint32_t flags;   /* enum packet_flags */
    uint32_t count;   /* rays in use: [0, count), count <= PACKET_MAX_RAYS */
} ray_packet;

/* A sub-packet: rays [begin, end) of `packet` that are also active. */
typedef struct packet_range {
    ray_packet *packet;
    uint32_t begin, end;
} packet_range;

/* Bit mask of rays [begin, end). */
static inline uint64_t packet_span_mask(uint32_t begin, uint32_t end)
{
    uint64_t upto_end = end >= 64 ? ~0ull : (1ull << end) - 1ull;
    uint64_t below_begin = begin >= 64 ? ~0ull : (1ull << begin) - 1ull;
    return upto_end & ~below_begin;
}

static inline packet_range packet_whole(ray_packet *p) { return (packet_range){p, 0, p->count}; }
static inline uint64_t packet_range_mask(packet_range r) { return r.packet->active & packet_span_mask(r.begin, r.end); }

/* Start a packet of `count` rays, all active, hits cleared, with the given
 * facts (PACKET_COMMON_ORIGIN ...); rays are filled afterwards. */
void packet_reset(ray_packet *p, uint32_t count, uint32_t fact_flags);

/* Copy one ray in or out (for code that wants a ray as a vector). */
void packet_set_ray(ray_packet *p, uint32_t i, const ray *r);
ray packet_get_ray(const ray_packet *p, uint32_t i);
hit packet_get_hit(const ray_packet *p, uint32_t i);
/* Ray i's closest hit becomes h (found by a query on the ray alone): its
 * t_far shrinks to h->t, as the packet kernels leave a ray that hits. */
void packet_set_hit(ray_packet *p, uint32_t i, const hit *h);

/* Ray i (already set) looks only for hits after `after` (a hit it found
 * before, t finite), in the closest-hit order (t, geom_id, prim_id): the
 * next surface along it. Lowers nothing: t_near becomes the float below
 * after->t when it is smaller. Sets PACKET_AFTER_HIT (the first call gives
 * the packet's other rays no bound). Closest-hit queries only. */
void packet_set_after(ray_packet *p, uint32_t i, const hit *after);

/* Find PACKET_COMMON_ORIGIN / PACKET_CONSTANT_SIGNS / PACKET_NORMALIZED by
 * looking at the rays (for callers that do not know them). */
void packet_detect_facts(ray_packet *p);

/* Derived values; each checks its flag and computes at most once. */
void packet_derive_inv_dir(ray_packet *p);

/* Primary rays through the pixels of a tile of at most 8 x 8 pixels
 * (x0 .. x0+w-1, y0 .. y0+h-1), row-major within the tile: unit directions,
 * common origin, t in (0, FLT_MAX]. Sets the facts it knows. */
struct camera_basis;
void packet_primary(ray_packet *p, const struct camera_basis *cam, int x0, int y0, int w, int h);

/* Primary rays through continuous pixel positions: ray i (i < count <= 64)
 * goes through (px[i], py[i]), where pixel x spans [x, x + 1) and its centre
 * is x + 0.5, with camera.h's mapping written as
 *   sx = px * (2 / W) - 1,  sy = 1 - py * (2 / H)
 * (the scales computed once per call: no division per ray but the
 * normalisation's; at pixel centres a direction can differ from
 * packet_primary's by an ulp). Unit directions (v3_normalize's arithmetic),
 * common origin, t in (0, FLT_MAX]; PACKET_CONSTANT_SIGNS is set exactly when
 * it holds. */
void packet_primary_at(ray_packet *p, const struct camera_basis *cam, const float *px, const float *py,
                       uint32_t count);

/* The ray packet_primary_at puts in a packet for the position (px, py), bit
 * for bit (for single-ray code and tests). */
ray packet_primary_ray_at(const struct camera_basis *cam, float px, float py);

#endif
