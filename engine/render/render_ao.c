/* render_ao.c - the ambient-occlusion renderer (render_ao.h). */
#include "render_ao.h"

#include <math.h>
#include <stdalign.h>
#include <stdint.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "ao.h"
#include "engine/accel/clip.h"
#include "engine/scene/frame_state.h"
#include "engine/accel/packet.h"
#include "engine/scene/scene.h"
#include "surface.h"

/* Primary rays per packet: 8 x 8 pixels, as the raytracer. */
#define AO_BLOCK_PX 8
/* A tile is worked through in sub-tiles of at most this edge, so the
 * per-thread buffers (sub-tile plus apron) have a fixed size whatever tile
 * size the caller uses. The apron is traced once per sub-tile: with the 5 x 5
 * filter a 16-pixel tile (RENDER_TILE_PX, the pipeline's default) traces
 * 20 x 20 pixels (x 1.56), a 32-pixel one 36 x 36 (x 1.27), so the AO
 * renderers run faster with traverser.tile_px 32 (docs/inspection.md). */
#define AO_SUBTILE_PX 32
#define AO_APRON_MAX_PX ((AO_MAX_FILTER_PX - 1) / 2)
#define AO_REGION_MAX_PX (AO_SUBTILE_PX + 2 * AO_APRON_MAX_PX)
#define AO_REGION_MAX_PIXELS (AO_REGION_MAX_PX * AO_REGION_MAX_PX)

/* How AO rays are grouped into packets. The AO rays of a whole region
 * (sub-tile and apron) are generated into a pool, counting-sorted by
 * direction (octant, then a cell of an AO_DIRECTION_GRID^2 grid over the
 * octant's octahedral map; within a cell in pixel order) and cut into
 * packets of up to 64 in that order, a new packet at each change of octant
 * (constant signs for the kernels' interval culling). A packet then holds
 * rays of neighbouring directions from neighbouring origins, which share
 * more of the tree than rays binned by octant alone. Measured (dragon,
 * 1920x1080, 8 rays, filter off, 1 thread, AMD EPYC, quiet, median frame of 3,
 * runs alternating): 64 rays of one 8 x 8 block binned by octant 498 / 502
 * ms, the block sorted by direction 493 / 484 ms; octant 505 / 497 ms, the
 * region's pool sorted 497 / 489 ms; grids of 2 to 32 cells a side within
 * noise of 8. A small gain: these rays stay incoherent (K^2 direction sets
 * interleaved); with one set (K = 1) the same frame took 408 ms against 538.
 * BENCHMARKS.md, "Ambient occlusion", has the figures against Embree. (Earlier, bunny:
 * ray s of every pixel of a block in one packet, as the Embree peer does,
 * 338 ms against 331 ms by octant; packets of 16 or 32 rays were slower than
 * 64 on the dragon, 2-ray single-ray traversal 1.6x slower.) */
#ifndef AO_DIRECTION_GRID
#define AO_DIRECTION_GRID 8
#endif
#define AO_DIRECTION_KEYS (8 * AO_DIRECTION_GRID * AO_DIRECTION_GRID)
/* Rays the pool holds: a region of AO_POOL_RAYS / N pixels at a time. */
#define AO_POOL_RAYS 4096

/* What one view's settings ask for, clamped into range once per tile. */
typedef struct ao_params {
    int rays;        /* N, 1 .. AO_MAX_RAYS */
    int interleave;  /* K, 1 .. AO_MAX_INTERLEAVE */
    int filter_px;   /* the configured filter edge, odd, 1 .. AO_MAX_FILTER_PX (frame 0's:
                        render_ao_filter_edge) */
    int frames;      /* F, 1 .. AO_MAX_FRAMES (render_ao.h, FRAMES) */
    uint32_t frame_base;
    float distance;  /* AO ray length, world units (unit directions) */
    float exponent;  /* renderer ao: the pixel is kd x A^exponent (render_ao.h, RESPONSE); 1 exactly: kd x A */
    bool term;       /* raytracer-ao: occlusion darkens the raytracer's ambient light (render_ao.h, TERM);
                        false: renderer ao, occlusion alone */
} ao_params;

/* The raw term and what the filter tests, per pixel of a region (row-major,
 * region width `stride`). */
typedef struct ao_region {
    int x0, y0, width, height; /* pixels [x0, x0 + width) x [y0, y0 + height), inside the image */
    uint32_t geom_id[AO_REGION_MAX_PIXELS]; /* hit instance, RAY_INVALID_ID for a miss */
    float depth[AO_REGION_MAX_PIXELS];      /* hit distance along the unit primary ray */
    vec3 position[AO_REGION_MAX_PIXELS];    /* world */
    vec3 normal[AO_REGION_MAX_PIXELS];      /* unit geometric normal facing the eye */
    vec3 scaled[AO_REGION_MAX_PIXELS];      /* what the unoccluded fraction multiplies: ao, the diffuse
                                               colour; raytracer-ao, the first surface's ambient light */
    vec3 colour[AO_REGION_MAX_PIXELS];      /* raytracer-ao: the raytracer's colour (every pixel) */
    float open[AO_REGION_MAX_PIXELS];       /* raw unoccluded fraction, [0, 1] */
    /* hits: where their AO rays start and the frame they turn into the world */
    vec3 ray_origin[AO_REGION_MAX_PIXELS];
    ao_basis basis[AO_REGION_MAX_PIXELS];
    uint16_t occluded[AO_REGION_MAX_PIXELS]; /* AO rays found blocked */
    uint16_t hit_pixels[AO_REGION_MAX_PIXELS]; /* the region pixels that hit, block by block */
    int hit_count;
} ao_region;

/* Per thread, ~340 KB: too big for a worker's stack; one tile at a time. */
static _Thread_local struct ao_scratch {
    ray_packet primary;
    render_first_surfaces first;      /* raytracer-ao: the primary block's first surfaces */
    vec3 block_colour[PACKET_MAX_RAYS]; /* raytracer-ao: the primary block's colours */
    ray_packet ao;                    /* the AO packet being filled */
    uint16_t owner[PACKET_MAX_RAYS];  /* region pixel of each ray of ao */
    /* the pool: a region's AO rays before they are sorted into packets */
    vec3 pool_dir[AO_POOL_RAYS];
    uint16_t pool_owner[AO_POOL_RAYS]; /* region pixel */
    uint16_t pool_key[AO_POOL_RAYS];
    uint16_t pool_order[AO_POOL_RAYS];
    uint16_t key_start[AO_DIRECTION_KEYS + 1];
    ao_direction_sets sets;           /* valid when sets_ready, for its (K, N, frame) */
    bool sets_ready;
    ao_region region;
    vec3 sum[AO_SUBTILE_PX * AO_SUBTILE_PX]; /* jittered: colours summed over strata */
} scratch;

float render_ao_distance(const render_view *v)
{
    render_settings defaults = render_settings_default();
    const render_settings *st = v->settings ? v->settings : &defaults;
    if (st->ao_distance > 0.f)
        return st->ao_distance;
    vec3 lo, hi;
    if (!accel_scene_bounds(v->accel, &lo, &hi))
        return 0.f;
    return RENDER_AO_DISTANCE_FRACTION * v3_length(v3_sub(hi, lo));
}

static ao_params resolve_params(const render_view *v, bool term)
{
    render_settings defaults = render_settings_default();
    const render_settings *st = v->settings ? v->settings : &defaults;
    ao_params p;
    p.rays = st->ao_rays < 1 ? 1 : st->ao_rays > AO_MAX_RAYS ? AO_MAX_RAYS : st->ao_rays;
    p.interleave = st->ao_interleave < 1 ? 1 : st->ao_interleave > AO_MAX_INTERLEAVE ? AO_MAX_INTERLEAVE
                                                                                       : st->ao_interleave;
    /* an even edge counts as the odd one below it */
    int filter = st->ao_filter_px < 1 ? 1 : st->ao_filter_px > AO_MAX_FILTER_PX ? AO_MAX_FILTER_PX : st->ao_filter_px;
    p.filter_px = filter % 2 ? filter : filter - 1;
    p.frames = st->ao_frames < 1 ? 1 : st->ao_frames > AO_MAX_FRAMES ? AO_MAX_FRAMES : st->ao_frames;
    p.frame_base = st->ao_frame_base;
    p.distance = render_ao_distance(v);
    p.exponent = st->ao_exponent < 1.f ? 1.f : st->ao_exponent > RENDER_AO_EXPONENT_MAX ? RENDER_AO_EXPONENT_MAX
                                                                                       : st->ao_exponent;
    p.term = term;
    return p;
}

/* Cut the active rays of p to what the frame's cutting planes keep
 * (clip.h): a ray with nothing left is no longer active (it misses, or for
 * an AO ray is not occluded). Every ray this renderer casts passes here, so
 * the AO of a cut surface sees what the picture shows. No caps: the AO
 * renderer shows the surfaces the planes leave. */
static void clip_packet(const render_view *v, ray_packet *p)
{
    if (!v->state || !clip_planes_on(frame_state_clip_planes(v->state)))
        return;
    clip_set planes;
    clip_set_make(&planes, frame_state_clip_planes(v->state));
    for (uint64_t m = p->active; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        ray r = packet_get_ray(p, i);
        if (!clip_ray(&planes, &r, NULL)) {
            p->active &= ~(1ull << i);
            continue;
        }
        p->t_near[i] = r.t_near;
        p->t_far[i] = r.t_far;
    }
}

/* EVERY AO ray is cast here: the active rays of p, returns the occluded
 * ones. */
static uint64_t trace_ao_packet(const render_view *v, ray_packet *p, render_counts *counts)
{
    clip_packet(v, p);
    counts->ao_rays += (uint64_t)__builtin_popcountll(p->active);
    return accel_occluded_packet(v->accel, packet_whole(p));
}

/* Put AO ray `lane` of packet p: from `origin` along unit `dir` for `length`. */
static void set_ao_ray(ray_packet *p, uint32_t lane, vec3 origin, vec3 dir, float length)
{
    p->org_x[lane] = origin.x, p->org_y[lane] = origin.y, p->org_z[lane] = origin.z;
    p->dir_x[lane] = dir.x, p->dir_y[lane] = dir.y, p->dir_z[lane] = dir.z;
    p->t_near[lane] = 0.f;
    p->t_far[lane] = length;
}

/* The sign pattern of a direction as the kernels see it (zero counts as +),
 * 0..7, and within it the cell of an AO_DIRECTION_GRID^2 grid over the
 * octahedral map of |d| (|x|, |y|) / (|x| + |y| + |z|): the key AO rays
 * are sorted by into packets (trace_pool). */
static unsigned direction_key(vec3 d)
{
    unsigned octant = (d.x < 0.f ? 1u : 0u) | (d.y < 0.f ? 2u : 0u) | (d.z < 0.f ? 4u : 0u);
    float ax = fabsf(d.x), ay = fabsf(d.y), sum = ax + ay + fabsf(d.z);
    float scale = sum > 0.f ? (float)AO_DIRECTION_GRID / sum : 0.f;
    unsigned u = (unsigned)(ax * scale), w = (unsigned)(ay * scale);
    u = u < AO_DIRECTION_GRID ? u : AO_DIRECTION_GRID - 1u;
    w = w < AO_DIRECTION_GRID ? w : AO_DIRECTION_GRID - 1u;
    return (octant * AO_DIRECTION_GRID + u) * AO_DIRECTION_GRID + w;
}

/* Trace the AO rays in scratch.ao (fill of them): each one found occluded
 * counts for its owner's pixel. */
static void flush_ao_packet(const render_view *v, uint32_t fill, render_counts *counts)
{
    ray_packet *p = &scratch.ao;
    packet_reset(p, fill, PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED);
    for (uint64_t m = trace_ao_packet(v, p, counts); m; m &= m - 1)
        scratch.region.occluded[scratch.owner[__builtin_ctzll(m)]]++;
}

/* The AO rays of the region's hit pixels hit_pixels[first, end): into the
 * pool, counting-sorted by direction_key (stable, so in pixel order within a
 * key), then traced in packets of up to 64 in that order, a new packet at
 * each change of octant. */
static void trace_pool(const render_view *v, const ao_params *ap, int first, int end, render_counts *counts)
{
    const ao_direction_sets *sets = &scratch.sets;
    ao_region *rg = &scratch.region;
    uint16_t *start = scratch.key_start;
    memset(start, 0, sizeof scratch.key_start);
    uint32_t n = 0;
    for (int k = first; k < end; k++) {
        const int at = rg->hit_pixels[k];
        const int set = ao_pixel_set(ap->interleave, rg->x0 + at % rg->width, rg->y0 + at / rg->width);
        rg->occluded[at] = 0;
        for (int s = 0; s < ap->rays; s++, n++) {
            vec3 dir = ao_basis_to_world(&rg->basis[at], ao_direction_local(sets, set, s));
            unsigned key = direction_key(dir);
            scratch.pool_dir[n] = dir;
            scratch.pool_owner[n] = (uint16_t)at;
            scratch.pool_key[n] = (uint16_t)key;
            start[key + 1]++;
        }
    }
    for (unsigned k = 0; k < AO_DIRECTION_KEYS; k++)
        start[k + 1] = (uint16_t)(start[k + 1] + start[k]);
    for (uint32_t r = 0; r < n; r++)
        scratch.pool_order[start[scratch.pool_key[r]]++] = (uint16_t)r;
    uint32_t fill = 0;
    unsigned octant = 0;
    for (uint32_t k = 0; k < n; k++) {
        const uint32_t r = scratch.pool_order[k];
        const unsigned o = scratch.pool_key[r] / (AO_DIRECTION_GRID * AO_DIRECTION_GRID);
        if (fill && (fill == PACKET_MAX_RAYS || o != octant)) {
            flush_ao_packet(v, fill, counts);
            fill = 0;
        }
        octant = o;
        const uint16_t at = scratch.pool_owner[r];
        set_ao_ray(&scratch.ao, fill, rg->ray_origin[at], scratch.pool_dir[r], ap->distance);
        scratch.owner[fill++] = at;
    }
    if (fill)
        flush_ao_packet(v, fill, counts);
}

/* The raw term of every hit pixel of the region (rg->hit_pixels): its AO
 * rays traced pool by pool. */
static void trace_region_ao(const render_view *v, const ao_params *ap, render_counts *counts)
{
    ao_region *rg = &scratch.region;
    const int per_pool = AO_POOL_RAYS / ap->rays; /* >= 64: N <= AO_MAX_RAYS */
    for (int first = 0; first < rg->hit_count; first += per_pool)
        trace_pool(v, ap, first, first + per_pool < rg->hit_count ? first + per_pool : rg->hit_count, counts);
    const float rays = (float)ap->rays;
    for (int k = 0; k < rg->hit_count; k++) {
        const int at = rg->hit_pixels[k];
        rg->open[at] = (float)(ap->rays - rg->occluded[at]) / rays;
    }
}

/* Primary rays of the w x h block at image pixel (bx, by) for sampler s's
 * stratum (i, j) into scratch.primary. */
static void block_primary(const render_view *v, const pixel_sampler *s, int bx, int by, int w, int h, int i, int j)
{
    if (s->kind == PIXEL_SAMPLER_SINGLE) {
        packet_primary(&scratch.primary, &v->camera, bx, by, w, h);
        return;
    }
    alignas(64) float sample_x[PACKET_MAX_RAYS], sample_y[PACKET_MAX_RAYS];
    pixel_sampler_block_positions(s, bx, by, w, h, i, j, sample_x, sample_y);
    packet_primary_at(&scratch.primary, &v->camera, sample_x, sample_y, (uint32_t)(w * h));
}

/* Where block pixel r (of a block w wide at (bx, by)) sits in the region. */
static int region_index(int bx, int by, int w, int r)
{
    const ao_region *rg = &scratch.region;
    return (by - rg->y0 + r / w) * rg->width + (bx - rg->x0 + r % w);
}

/* Record the hit surface of region pixel `at` and where its AO rays start. */
static void note_surface(int at, uint32_t geom_id, float depth, vec3 position, vec3 position_error, vec3 normal,
                         vec3 scaled)
{
    ao_region *rg = &scratch.region;
    rg->geom_id[at] = geom_id;
    rg->depth[at] = depth;
    rg->position[at] = position;
    rg->normal[at] = normal;
    rg->scaled[at] = scaled;
    rg->ray_origin[at] = ray_offset_origin((surface_point){position, position_error}, normal);
    rg->basis[at] = ao_basis_from_normal(normal);
}

/* Renderer ao: trace the primary block in scratch.primary (cut by the
 * planes, closest hits) and note its surfaces; returns the hits (block
 * pixels). */
static uint64_t block_unshaded(const render_view *v, int bx, int by, int w, render_counts *counts)
{
    ray_packet *p = &scratch.primary;
    clip_packet(v, p);
    accel_intersect_packet(v->accel, packet_whole(p));
    counts->primary_rays += p->count;
    uint64_t hits = 0;
    for (uint32_t r = 0; r < p->count; r++) {
        int at = region_index(bx, by, w, (int)r);
        if (p->hit_t[r] == INFINITY) {
            scratch.region.geom_id[at] = RAY_INVALID_ID;
            continue;
        }
        hits |= 1ull << r;
        ray pr = packet_get_ray(p, r);
        hit ph = packet_get_hit(p, r);
        surface sf = surface_describe(v, &pr, &ph, true);
        note_surface(at, ph.geom_id, ph.t, sf.position, sf.position_error, sf.geometric_n, sf.kd);
    }
    counts->primary_hits += (uint64_t)__builtin_popcountll(hits);
    return hits;
}

/* Renderer raytracer-ao: the raytracer traces and shades the primary block
 * (render_trace_primary: transparency, planes, caps, lights and shadows);
 * its colours and first surfaces are noted; returns the hits. */
static uint64_t block_shaded(const render_view *v, int bx, int by, int w, render_counts *counts)
{
    ray_packet *p = &scratch.primary;
    render_first_surfaces *f = &scratch.first;
    render_trace_primary(v, p, scratch.block_colour, f, counts);
    for (uint32_t r = 0; r < p->count; r++) {
        int at = region_index(bx, by, w, (int)r);
        scratch.region.colour[at] = scratch.block_colour[r];
        if (!(f->hits >> r & 1u)) {
            scratch.region.geom_id[at] = RAY_INVALID_ID;
            continue;
        }
        note_surface(at, f->geom_id[r], f->t[r], f->position[r], f->position_error[r], f->normal[r], f->ambient[r]);
    }
    return f->hits;
}

/* The raw term of every pixel of scratch.region for stratum (i, j): the
 * primary rays block by block, then the AO rays of the whole region. */
static void region_raw(const render_view *v, const pixel_sampler *s, const ao_params *ap, int i, int j,
                       render_counts *counts)
{
    ao_region *rg = &scratch.region;
    rg->hit_count = 0;
    for (int by = rg->y0; by < rg->y0 + rg->height; by += AO_BLOCK_PX)
        for (int bx = rg->x0; bx < rg->x0 + rg->width; bx += AO_BLOCK_PX) {
            int w = rg->x0 + rg->width - bx < AO_BLOCK_PX ? rg->x0 + rg->width - bx : AO_BLOCK_PX;
            int h = rg->y0 + rg->height - by < AO_BLOCK_PX ? rg->y0 + rg->height - by : AO_BLOCK_PX;
            block_primary(v, s, bx, by, w, h, i, j);
            uint64_t hits = ap->term ? block_shaded(v, bx, by, w, counts) : block_unshaded(v, bx, by, w, counts);
            for (uint64_t m = hits; m; m &= m - 1)
                rg->hit_pixels[rg->hit_count++] = (uint16_t)region_index(bx, by, w, __builtin_ctzll(m));
        }
    trace_region_ao(v, ap, counts);
}

/* The filtered colour of region pixel (x, y) (image coordinates, a pixel
 * of the region whose whole box inside the image lies in the region), the
 * box reaching apron_px pixels to each side. */
static vec3 filtered_colour(const render_view *v, const ao_params *ap, int apron_px, int x, int y)
{
    const ao_region *rg = &scratch.region;
    int at = (y - rg->y0) * rg->width + (x - rg->x0);
    if (rg->geom_id[at] == RAY_INVALID_ID)
        return ap->term ? rg->colour[at] : v->scene->background;
    const uint32_t id = rg->geom_id[at];
    const vec3 n = rg->normal[at], pos = rg->position[at];
    const float plane_tolerance = AO_FILTER_PLANE_REL * rg->depth[at];
    int qx0 = x - apron_px < rg->x0 ? rg->x0 : x - apron_px;
    int qy0 = y - apron_px < rg->y0 ? rg->y0 : y - apron_px;
    int qx1 = x + apron_px >= rg->x0 + rg->width ? rg->x0 + rg->width - 1 : x + apron_px;
    int qy1 = y + apron_px >= rg->y0 + rg->height ? rg->y0 + rg->height - 1 : y + apron_px;
    float sum = 0.f;
    int taken = 0;
    for (int qy = qy0; qy <= qy1; qy++)
        for (int qx = qx0; qx <= qx1; qx++) {
            int q = (qy - rg->y0) * rg->width + (qx - rg->x0);
            if (rg->geom_id[q] != id || v3_dot(rg->normal[q], n) < AO_FILTER_MIN_COS ||
                fabsf(v3_dot(n, v3_sub(rg->position[q], pos))) > plane_tolerance)
                continue;
            sum += rg->open[q];
            taken++;
        }
    /* taken >= 1: p passes its own tests */
    const float open = sum / (float)taken;
    if (ap->term) /* unoccluded (open 1): the raytracer's colour exactly */
        return v3_sub(rg->colour[at], v3_scale(rg->scaled[at], 1.f - open));
    return v3_scale(rg->scaled[at], ap->exponent == 1.f ? open : powf(open, ap->exponent));
}

/* The stratum index of stratum (i, j) of sampler s: 0 for single. */
static uint32_t stratum_index(const pixel_sampler *s, int i, int j)
{
    switch (s->kind) {
    case PIXEL_SAMPLER_JITTERED:
        return (uint32_t)(j * s->k + i);
    case PIXEL_SAMPLER_STRATUM:
        return (uint32_t)s->stratum;
    case PIXEL_SAMPLER_SINGLE:
    default:
        return 0u;
    }
}

/* The frame index (ao.h) of AO frame f (0 .. F - 1) of stratum (i, j) of
 * sampler s: base + stratum x F + f (render_ao.h, FRAMES). */
static uint32_t stratum_frame(const pixel_sampler *s, const ao_params *ap, int i, int j, int f)
{
    return ap->frame_base + stratum_index(s, i, j) * (uint32_t)ap->frames + (uint32_t)f;
}

static void ensure_sets(const ao_params *ap, uint32_t frame)
{
    ao_direction_sets *d = &scratch.sets;
    if (scratch.sets_ready && d->interleave == ap->interleave && d->ray_count == ap->rays && d->frame == frame)
        return;
    ao_direction_sets_fill(d, ap->interleave, ap->rays, frame);
    scratch.sets_ready = true;
}

static void store_pixel(const camera_basis *cam, int x, int y, vec3 c, float *rgb)
{
    float *out = rgb + 3 * ((size_t)y * (size_t)cam->width_px + (size_t)x);
    out[0] = c.x;
    out[1] = c.y;
    out[2] = c.z;
}

int render_ao_filter_edge(int filter_px, uint32_t frame)
{
    int shrink = 0; /* ceil(log4(frame + 1)) */
    for (uint64_t limit = 1; limit < (uint64_t)frame + 1u; limit *= 4u)
        shrink++;
    int edge = filter_px - 2 * shrink;
    return edge < 1 ? 1 : edge;
}

/* Set up scratch.region for the sub-tile [x0, x1) x [y0, y1) and AO frame
 * `frame`, and fill it: its apron the frame's filter needs. Returns that
 * apron. */
static int region_for_frame(const render_view *v, const pixel_sampler *s, const ao_params *ap, int x0, int y0,
                            int x1, int y1, int i, int j, uint32_t frame, render_counts *counts)
{
    const camera_basis *cam = &v->camera;
    ao_region *rg = &scratch.region;
    const int apron = (render_ao_filter_edge(ap->filter_px, frame) - 1) / 2;
    int rx0 = x0 - apron < 0 ? 0 : x0 - apron;
    int ry0 = y0 - apron < 0 ? 0 : y0 - apron;
    int rx1 = x1 + apron > cam->width_px ? cam->width_px : x1 + apron;
    int ry1 = y1 + apron > cam->height_px ? cam->height_px : y1 + apron;
    rg->x0 = rx0, rg->y0 = ry0, rg->width = rx1 - rx0, rg->height = ry1 - ry0;
    ensure_sets(ap, frame);
    region_raw(v, s, ap, i, j, counts);
    return apron;
}

/* One sub-tile [x0, x1) x [y0, y1) (at most AO_SUBTILE_PX a side). */
static void render_subtile(const render_view *v, const pixel_sampler *s, const ao_params *ap, int x0, int y0,
                           int x1, int y1, float *rgb, render_counts *counts)
{
    const camera_basis *cam = &v->camera;
    const int strata = pixel_sampler_strata(s), w = x1 - x0;
    if (s->kind != PIXEL_SAMPLER_JITTERED && ap->frames == 1) {
        int apron = region_for_frame(v, s, ap, x0, y0, x1, y1, 0, 0, stratum_frame(s, ap, 0, 0, 0), counts);
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++)
                store_pixel(cam, x, y, filtered_colour(v, ap, apron, x, y), rgb);
        return;
    }
    for (int r = 0; r < w * (y1 - y0); r++)
        scratch.sum[r] = v3(0.f, 0.f, 0.f);
    /* strata in row-major order, each stratum's F frames in order; the primary
     * rays of a stratum are traced again for each frame (the same rays: each
     * frame costs what it costs alone) */
    for (int j = 0; j < strata; j++)
        for (int i = 0; i < strata; i++)
            for (int f = 0; f < ap->frames; f++) {
                int apron = region_for_frame(v, s, ap, x0, y0, x1, y1, i, j, stratum_frame(s, ap, i, j, f), counts);
                for (int y = y0; y < y1; y++)
                    for (int x = x0; x < x1; x++) {
                        vec3 *sum = &scratch.sum[(y - y0) * w + (x - x0)];
                        *sum = v3_add(*sum, filtered_colour(v, ap, apron, x, y));
                    }
            }
    const float samples = (float)(strata * strata * ap->frames);
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            vec3 c = scratch.sum[(y - y0) * w + (x - x0)];
            store_pixel(cam, x, y, v3(c.x / samples, c.y / samples, c.z / samples), rgb);
        }
}

/* Both renderers' tiles: term false for ao, true for raytracer-ao. */
static void ao_tile(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                    render_counts *counts, bool term)
{
    const ao_params ap = resolve_params(v, term);
    for (int sy = y0; sy < y1; sy += AO_SUBTILE_PX)
        for (int sx = x0; sx < x1; sx += AO_SUBTILE_PX) {
            int ex = x1 - sx < AO_SUBTILE_PX ? x1 : sx + AO_SUBTILE_PX;
            int ey = y1 - sy < AO_SUBTILE_PX ? y1 : sy + AO_SUBTILE_PX;
            render_subtile(v, s, &ap, sx, sy, ex, ey, rgb, counts);
        }
}

void render_ao_tile(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                    render_counts *counts)
{
    ao_tile(v, s, x0, y0, x1, y1, rgb, counts, false);
}

void render_raytracer_ao_tile(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1,
                              float *rgb, render_counts *counts)
{
    ao_tile(v, s, x0, y0, x1, y1, rgb, counts, true);
}

void render_ao_image(const render_view *v, const pixel_sampler *s, int threads, int tile_px, float *rgb,
                     render_counts *counts)
{
    render_image_tiles(renderer_by_name("ao"), v, s, threads, tile_px, rgb, counts);
}
