/* overlay.h - what is drawn over the rendered image: a status line and a
 * cursor, composited into each tile right after it is rendered (traverser.c),
 * so every display, also one that scans tiles out as they finish, shows it.
 *
 * POSITIONS are points of the image plane in camera.h's screen coordinates
 * (sx right, sy up, the whole plane [-1, 1]^2). A channel shows a window of
 * that plane (camera_window); an overlay element is drawn by every channel
 * whose pixels it overlaps, in that channel's pixels, so a cursor on the
 * boundary of two outputs appears partly on each, and on outputs of one
 * resolution the parts fit together as on one wide image. A plane point maps
 * to the channel's continuous pixel coordinates
 *     px = (sx - (cx - hw)) / (2 hw) * W,   py = ((cy + hh) - sy) / (2 hh) * H
 * (computed in double).
 *
 * SIZE. Elements are bitmaps of "font pixels", each drawn as a block of
 * scale x scale channel pixels, scale = overlay_scale(H) = max(1, H / 360)
 * (integer division) of the channel that draws it: 1 up to 719 lines (a
 * 640x480 monitor: 5x7-pixel capitals), 2 at 720, 3 at 1080, 6 at 2160. Each
 * channel uses its own scale, so on a wall of mixed resolutions an element
 * that crosses outputs has a different size on each.
 *
 * STATUS LINE: white text on a dark translucent band (every pixel under it is
 * multiplied by OVERLAY_BAND_KEEP), anchored at the bottom-left corner of
 * what the outputs show (state.anchor_*: the least left and least bottom edge
 * of the channels' windows; (-1, -1) for windows covering the plane; on a wall
 * with bezels the plane's own corner lies behind one): the band's bottom-left
 * corner is the pixel corner nearest to that point. Band, in font pixels: OVERLAY_PAD, then the glyph cells
 * (OVERLAY_CELL_W x OVERLAY_CELL_H each, the last cell without its spacing
 * column), then OVERLAY_PAD, on every side; so in channel pixels it is
 *     width  (len * OVERLAY_CELL_W - 1 + 2 * OVERLAY_PAD) * scale
 *     height (OVERLAY_CELL_H + 2 * OVERLAY_PAD) * scale.
 * One line, never wrapped: text longer than the outputs along the bottom edge
 * is cut off by the plane's edge.
 *
 * CURSOR: an arrow, white with a black outline, OVERLAY_CURSOR_W x
 * OVERLAY_CURSOR_H font pixels, drawn over the status line; its tip is the
 * top-left font pixel, whose top-left channel pixel is the one containing
 * the cursor's plane point (floor of px, py).
 *
 * FONT: 95 glyphs for printable ASCII 32..126, each 5 x 9 font pixels (rows
 * 0-6 from cap height to the baseline, rows 7-8 descenders), drawn for
 * tessera; a cell is one column wider (the spacing). Bytes outside 32..126
 * are drawn as '?'.
 *
 * All drawing is in linear float RGB and a pure function of (the pixel's
 * rendered value, its coordinates, the overlay state, the channel's window
 * and size): images stay identical for any tile size, tile order and thread
 * count. */
#ifndef TESSERA_OVERLAY_H
#define TESSERA_OVERLAY_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/camera.h"

#define OVERLAY_TEXT_BYTES 128 /* status text, with its terminating NUL */
#define OVERLAY_GLYPH_W 5
#define OVERLAY_GLYPH_H 9
#define OVERLAY_CELL_W 6       /* glyph and one spacing column */
#define OVERLAY_CELL_H 9
#define OVERLAY_PAD 2          /* band margin around the text, font pixels */
#define OVERLAY_BAND_KEEP 0.3f /* what the band leaves of the pixels under it */
#define OVERLAY_CURSOR_W 10
#define OVERLAY_CURSOR_H 17
#define OVERLAY_SCALE_LINES 360 /* channel lines per unit of scale */
#define OVERLAY_POINTERS 8        /* remote viewers' pointers (= TXN_POINTERS) */
#define OVERLAY_POINTER_R 7       /* a pointer's disc radius, font pixels */
#define OVERLAY_POINTER_EDGE 2    /* its dark outline's width, font pixels */

/* What the overlay shows: part of the pipeline's state (changed only in its
 * serial section). */
typedef struct overlay_state {
    char status[OVERLAY_TEXT_BYTES]; /* printable ASCII only; "": no status line */
    float anchor_sx, anchor_sy;      /* the status line's bottom-left corner, a plane point: the
                                        bottom-left corner of the outputs' windows (the plane's
                                        corner itself may lie behind a bezel) */
    bool cursor_visible;
    float cursor_sx, cursor_sy;      /* the tip, a plane point; finite */
    bool pointer_visible[OVERLAY_POINTERS]; /* remote viewers' pointers by slot: discs in the slot's colour */
    float pointer_sx[OVERLAY_POINTERS], pointer_sy[OVERLAY_POINTERS]; /* their centres, plane points; finite */
} overlay_state;

/* Pixels [x0, x1) x [y0, y1) of a channel; may reach outside the image. */
typedef struct overlay_rect {
    int x0, y0, x1, y1;
} overlay_rect;

/* What one channel draws during one frame: the state resolved to its pixels. */
typedef struct overlay_plan {
    int scale;
    bool band_on;        /* the band overlaps the image */
    overlay_rect band;
    int text_x, text_y;  /* top-left pixel of the first glyph cell */
    int text_len;
    char text[OVERLAY_TEXT_BYTES];
    bool cursor_on;      /* the cursor's box overlaps the image */
    overlay_rect cursor; /* its box; the tip is (x0, y0) */
    int pointer_count;   /* pointers whose discs overlap the image: */
    struct {
        overlay_rect box;  /* the disc's bounding box */
        double cx, cy;     /* its centre, continuous pixel coordinates */
        float rgb[3];      /* linear */
    } pointers[OVERLAY_POINTERS];
} overlay_plan;

/* Remote viewers' pointers (remote/): one colour per viewer slot, the same on
 * the wall, in every view and on the page's swatch. OVERLAY_POINTER_COLOURS
 * distinct colours; slots past them wrap. */
#define OVERLAY_POINTER_COLOURS 8
/* Slot `slot`'s colour as sRGB "#rrggbb" into out (8 bytes with the NUL). */
void overlay_pointer_colour_hex(int slot, char out[8]);
/* The same colour as linear RGB (what the overlay composites). */
void overlay_pointer_rgb(int slot, float linear_rgb[3]);

/* The text a status line shows for `text`: at most OVERLAY_TEXT_BYTES - 1
 * bytes of it (the rest is cut off), every byte outside 32..126 replaced by
 * '?'. NULL is "". */
void overlay_set_status(overlay_state *s, const char *text);

/* Font pixels per channel pixel edge for a channel `height_px` lines tall. */
int overlay_scale(int height_px);

/* Resolve `s` for a channel of width_px x height_px pixels showing `window`
 * of the plane. Returns whether anything falls on the channel's pixels
 * (false: nothing to draw, the traverser is given no plan). */
bool overlay_plan_make(overlay_plan *plan, const overlay_state *s, camera_window window, int width_px,
                       int height_px);

/* Composite the plan into pixels [x0, x1) x [y0, y1) of rgb (the whole
 * image, width_px pixels a row, 3 floats a pixel): only the parts of the
 * rectangle the band and the cursor cover are touched. Any thread; many at
 * once on disjoint rectangles. */
void overlay_draw(const overlay_plan *plan, int width_px, int x0, int y0, int x1, int y1, float *rgb);

/* Glyph of byte c: OVERLAY_GLYPH_H rows, bit 4 the leftmost column, bit 0
 * the rightmost; NULL for bytes outside 32..126. */
const uint8_t *overlay_glyph(unsigned char c);

#endif
