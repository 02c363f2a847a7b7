/* test_xrgb.c - float frames to scan-out words (wall/xrgb.h): every rotation
 * against the definition pixel by pixel, tiles written in any order equal the
 * whole frame, and a tile touches only its own rotated rectangle. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "wall/dump.h"
#include "wall/xrgb.h"

#define MW 7 /* mounted size: odd, not square */
#define MH 5
#define SENTINEL 0xdeadbeefu

static void make_image(float *rgb)
{
    unsigned seed = 12345;
    for (int i = 0; i < MW * MH * 3; i++) {
        seed = seed * 1103515245u + 12345u;
        rgb[i] = (float)(seed >> 8 & 0xffff) / 65535.0f * 1.2f - 0.1f; /* some out of [0, 1] */
    }
}

static uint32_t encode(const float *c)
{
    return (uint32_t)dump_srgb_encode_u8(c[0]) << 16 | (uint32_t)dump_srgb_encode_u8(c[1]) << 8 |
           (uint32_t)dump_srgb_encode_u8(c[2]);
}

/* The definition (xrgb.c): scan-out pixel (u, v) shows mounted pixel (x, y). */
static void mounted_of(int rot, int u, int v, int *x, int *y)
{
    switch (rot) {
    case 90: *x = MW - 1 - v, *y = u; break;
    case 180: *x = MW - 1 - u, *y = MH - 1 - v; break;
    case 270: *x = v, *y = MH - 1 - u; break;
    default: *x = u, *y = v; break;
    }
}

typedef struct scanout {
    uint32_t words[MW * MH + 16]; /* pitch wider than a row: rows padded */
    xrgb_target t;
} scanout;

static void scanout_init(scanout *s, int rot)
{
    bool swap = rot == 90 || rot == 270;
    int w = swap ? MH : MW, h = swap ? MW : MH;
    for (size_t i = 0; i < sizeof s->words / sizeof s->words[0]; i++)
        s->words[i] = SENTINEL;
    s->t = (xrgb_target){(uint8_t *)s->words, (size_t)(w + 2) * sizeof(uint32_t), w, h};
    cr_assert((size_t)(w + 2) * h <= sizeof s->words / sizeof s->words[0] + 2);
}

static uint32_t word_at(const scanout *s, int u, int v)
{
    return s->words[(size_t)v * (s->t.pitch_bytes / sizeof(uint32_t)) + (size_t)u];
}

Test(xrgb, every_rotation_follows_the_definition)
{
    float rgb[MW * MH * 3];
    make_image(rgb);
    const int rots[] = {0, 90, 180, 270};
    for (int r = 0; r < 4; r++) {
        scanout s;
        scanout_init(&s, rots[r]);
        xrgb_write_rect(rgb, MW, MH, 0, 0, MW, MH, rots[r], &s.t);
        for (int v = 0; v < s.t.height_px; v++)
            for (int u = 0; u < s.t.width_px; u++) {
                int x, y;
                mounted_of(rots[r], u, v, &x, &y);
                cr_assert_eq(word_at(&s, u, v), encode(&rgb[3 * (y * MW + x)]),
                             "rotation %d: scan-out (%d, %d) should show mounted (%d, %d)", rots[r], u, v, x, y);
            }
        /* the padding at the end of each row is never written */
        for (int v = 0; v < s.t.height_px; v++)
            cr_assert_eq(word_at(&s, s.t.width_px, v), SENTINEL, "rotation %d row %d padding", rots[r], v);
    }
}

Test(xrgb, tiles_in_any_order_make_the_whole_frame_and_touch_only_their_rectangle)
{
    float rgb[MW * MH * 3];
    make_image(rgb);
    const int rots[] = {0, 90, 180, 270};
    for (int r = 0; r < 4; r++) {
        scanout whole, tiled;
        scanout_init(&whole, rots[r]);
        scanout_init(&tiled, rots[r]);
        xrgb_write_rect(rgb, MW, MH, 0, 0, MW, MH, rots[r], &whole.t);
        /* 3 x 2 tiles (edge tiles smaller), last to first */
        for (int ty = (MH - 1) / 2; ty >= 0; ty--)
            for (int tx = (MW - 1) / 3; tx >= 0; tx--) {
                int x0 = tx * 3, y0 = ty * 2, x1 = x0 + 3 < MW ? x0 + 3 : MW, y1 = y0 + 2 < MH ? y0 + 2 : MH;
                scanout before = tiled;
                xrgb_write_rect(rgb, MW, MH, x0, y0, x1, y1, rots[r], &tiled.t);
                for (int v = 0; v < tiled.t.height_px; v++)
                    for (int u = 0; u < tiled.t.width_px; u++) {
                        int x, y;
                        mounted_of(rots[r], u, v, &x, &y);
                        bool inside = x >= x0 && x < x1 && y >= y0 && y < y1;
                        if (!inside)
                            cr_assert_eq(word_at(&tiled, u, v), word_at(&before, u, v),
                                         "rotation %d: tile (%d,%d)-(%d,%d) wrote scan-out (%d, %d) outside it",
                                         rots[r], x0, y0, x1, y1, u, v);
                    }
            }
        cr_assert(memcmp(whole.words, tiled.words, sizeof whole.words) == 0, "rotation %d: tiles != whole frame",
                  rots[r]);
    }
}
