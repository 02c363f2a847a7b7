/* traverser.c - the tiled image traverser: the dynamic load balancer. */
#include "traverser.h"

#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>

/* One channel's tiles. Fixed after creation except `target` (serial section). */
typedef struct tiled_channel {
    int width_px, height_px;
    int tiles_x;
    uint32_t first;     /* index of this channel's first tile in the frame's sequence */
    uint32_t *order;    /* tiles_x * tiles_y tile indices (y * tiles_x + x) in hand-out order */
    traverser_target target;
} tiled_channel;

typedef struct tiled_traverser {
    image_traverser base;
    int tile_px;
    int channel_count;
    uint32_t tile_total; /* tiles of all channels */
    tiled_channel *channels;
    /* the next index into the frame's tile sequence; reset by begin_frame; on a
     * cache line of its own, as every render thread writes it once per tile */
    alignas(64) atomic_uint next; /* (the struct's size rounds up to whole lines: nothing follows it) */
} tiled_traverser;

static void tiled_begin_frame(image_traverser *t, const traverser_target *targets)
{
    tiled_traverser *tt = (tiled_traverser *)t;
    for (int i = 0; i < tt->channel_count; i++)
        tt->channels[i].target = targets[i];
    atomic_store_explicit(&tt->next, 0, memory_order_relaxed);
}

/* The accumulation step of one tile (traverser_target's accum fields): the
 * same float operations for every pixel, whichever thread runs it. */
static void accumulate_tile(const traverser_target *t, int width_px, int x0, int y0, int x1, int y1)
{
    const float samples = t->accum_samples;
    for (int y = y0; y < y1; y++) {
        size_t first = 3 * ((size_t)y * (size_t)width_px + (size_t)x0), count = 3 * (size_t)(x1 - x0);
        float *rgb = t->rgb + first, *acc = t->accum + first;
        if (t->resolve_only)
            for (size_t i = 0; i < count; i++)
                rgb[i] = acc[i] / samples;
        else if (t->accum_reset)
            for (size_t i = 0; i < count; i++) {
                acc[i] = 0.0f + rgb[i];
                rgb[i] = acc[i] / samples;
            }
        else
            for (size_t i = 0; i < count; i++) {
                acc[i] = acc[i] + rgb[i];
                rgb[i] = acc[i] / samples;
            }
    }
}

static void tiled_render(image_traverser *t, const renderer *r, const pixel_sampler *s, render_counts *counts)
{
    tiled_traverser *tt = (tiled_traverser *)t;
    const int tile_px = tt->tile_px;
    for (;;) {
        uint32_t g = atomic_fetch_add_explicit(&tt->next, 1, memory_order_relaxed);
        if (g >= tt->tile_total)
            return;
        int ci = 0; /* channels are few: a scan finds the one holding tile g */
        while (ci + 1 < tt->channel_count && g >= tt->channels[ci + 1].first)
            ci++;
        const tiled_channel *c = &tt->channels[ci];
        uint32_t tile = c->order[g - c->first];
        int x0 = (int)(tile % (uint32_t)c->tiles_x) * tile_px, y0 = (int)(tile / (uint32_t)c->tiles_x) * tile_px;
        int x1 = x0 + tile_px < c->width_px ? x0 + tile_px : c->width_px;
        int y1 = y0 + tile_px < c->height_px ? y0 + tile_px : c->height_px;
        if (!c->target.rgb)
            continue;
        if (!c->target.resolve_only)
            r->render_tile(c->target.view, s, x0, y0, x1, y1, c->target.rgb, counts);
        if (c->target.accum)
            accumulate_tile(&c->target, c->width_px, x0, y0, x1, y1);
        if (c->target.overlay) /* the one branch a frame without an overlay pays per tile */
            overlay_draw(c->target.overlay, c->width_px, x0, y0, x1, y1, c->target.rgb);
        if (c->target.sink)
            c->target.sink->ops->write_tile(c->target.sink, c->target.img, x0, y0, x1, y1);
    }
}

static void tiled_destroy(image_traverser *t)
{
    tiled_traverser *tt = (tiled_traverser *)t;
    for (int i = 0; i < tt->channel_count; i++)
        free(tt->channels[i].order);
    free(tt->channels);
    free(tt);
}

static const image_traverser_ops tiled_ops = {"tiled", tiled_begin_frame, tiled_render, tiled_destroy};

image_traverser *traverser_tiled_create(int tile_px, tile_order order, uint32_t seed, const int *widths_px,
                                        const int *heights_px, int channels, tess_error *err)
{
    tiled_traverser *tt = aligned_alloc(64, sizeof *tt);
    tiled_channel *chans = calloc(channels > 0 ? (size_t)channels : 1, sizeof *chans);
    if (!tt || !chans) {
        free(tt);
        free(chans);
        tess_error_set(err, "tiled traverser: out of memory");
        return NULL;
    }
    tt->base.ops = &tiled_ops;
    tt->tile_px = tile_px;
    tt->channel_count = channels;
    tt->channels = chans;
    tt->tile_total = 0;
    atomic_init(&tt->next, 0);
    for (int i = 0; i < channels; i++) {
        tiled_channel *c = &chans[i];
        c->width_px = widths_px[i];
        c->height_px = heights_px[i];
        c->tiles_x = (widths_px[i] + tile_px - 1) / tile_px;
        int tiles_y = (heights_px[i] + tile_px - 1) / tile_px;
        size_t tiles = (size_t)c->tiles_x * (size_t)tiles_y;
        c->order = malloc(tiles * sizeof *c->order);
        if (!c->order || tt->tile_total + tiles > UINT32_MAX / 2) {
            tt->channel_count = i + 1; /* free what was made */
            tiled_destroy(&tt->base);
            tess_error_set(err, "tiled traverser: out of memory for the tiles of channel %d", i);
            return NULL;
        }
        tile_order_fill(order, c->tiles_x, tiles_y, seed, c->order);
        c->first = tt->tile_total;
        tt->tile_total += (uint32_t)tiles;
    }
    return &tt->base;
}
