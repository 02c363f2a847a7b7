#include "tile_order.h"

#include <stddef.h>
#include <string.h>

#include "sampler.h"

static const char *const order_names[TILE_ORDER_COUNT] = {
    [TILE_ORDER_ROWS] = "rows",       [TILE_ORDER_COLUMNS] = "columns", [TILE_ORDER_MORTON] = "morton",
    [TILE_ORDER_HILBERT] = "hilbert", [TILE_ORDER_SPIRAL] = "spiral",   [TILE_ORDER_SHUFFLE] = "shuffle",
};

const char *tile_order_name(tile_order o)
{
    return (unsigned)o < TILE_ORDER_COUNT ? order_names[o] : NULL;
}

bool tile_order_from_name(const char *name, tile_order *out)
{
    if (!name)
        return false;
    for (int o = 0; o < TILE_ORDER_COUNT; o++)
        if (strcmp(name, order_names[o]) == 0) {
            *out = (tile_order)o;
            return true;
        }
    return false;
}

/* Where the next tile index goes, and the grid it must lie in. */
typedef struct order_writer {
    uint32_t *order;
    uint32_t written;
    int64_t tiles_x, tiles_y;
} order_writer;

static bool in_grid(const order_writer *w, int64_t x, int64_t y)
{
    return x >= 0 && y >= 0 && x < w->tiles_x && y < w->tiles_y;
}

static void emit(order_writer *w, int64_t x, int64_t y)
{
    w->order[w->written++] = (uint32_t)(y * w->tiles_x + x);
}

/* Smallest power of two >= the longer grid side. */
static int64_t enclosing_side(const order_writer *w)
{
    int64_t longer = w->tiles_x > w->tiles_y ? w->tiles_x : w->tiles_y, side = 1;
    while (side < longer)
        side *= 2;
    return side;
}

static void fill_rows(order_writer *w)
{
    for (int64_t y = 0; y < w->tiles_y; y++)
        for (int64_t x = 0; x < w->tiles_x; x++)
            emit(w, x, y);
}

static void fill_columns(order_writer *w)
{
    for (int64_t x = 0; x < w->tiles_x; x++)
        for (int64_t y = 0; y < w->tiles_y; y++)
            emit(w, x, y);
}

/* Z-order over the square [x0, x0 + side) x [y0, y0 + side): the quadrants in
 * code order (x bit low): (0,0), (1,0), (0,1), (1,1). The square's corner
 * (x0, y0) is non-negative, so it is outside the grid iff the corner is. */
static void morton_square(order_writer *w, int64_t x0, int64_t y0, int64_t side)
{
    if (x0 >= w->tiles_x || y0 >= w->tiles_y)
        return;
    if (side == 1) {
        emit(w, x0, y0);
        return;
    }
    int64_t h = side / 2;
    morton_square(w, x0, y0, h);
    morton_square(w, x0 + h, y0, h);
    morton_square(w, x0, y0 + h, h);
    morton_square(w, x0 + h, y0 + h, h);
}

/* An oriented square of side `side` for the Hilbert recursion: its cells are
 * corner + a * (ax, ay) + b * (bx, by) for a, b in [0, side), where (ax, ay)
 * and (bx, by) are orthogonal unit axis vectors. The curve through it starts
 * at the corner (a = b = 0) and ends at a = side - 1, b = 0. */
typedef struct hilbert_square {
    int64_t cx, cy;        /* corner cell */
    int64_t ax, ay, bx, by; /* unit steps along a and b */
    int64_t side;
} hilbert_square;

/* False when no cell of the square lies in the grid (its cells span the box
 * between the corner and the opposite corner). */
static bool hilbert_touches_grid(const order_writer *w, const hilbert_square *q)
{
    int64_t far_x = q->cx + (q->side - 1) * (q->ax + q->bx), far_y = q->cy + (q->side - 1) * (q->ay + q->by);
    int64_t lo_x = q->cx < far_x ? q->cx : far_x, hi_x = q->cx < far_x ? far_x : q->cx;
    int64_t lo_y = q->cy < far_y ? q->cy : far_y, hi_y = q->cy < far_y ? far_y : q->cy;
    return hi_x >= 0 && hi_y >= 0 && lo_x < w->tiles_x && lo_y < w->tiles_y;
}

/* The four sub-squares, in curve order: the first with a and b swapped (it
 * ends next to the second's corner), two with the parent's axes, the last with
 * both axes swapped and reversed (it starts next to the third's end and ends
 * at the parent's end). */
static void hilbert_curve(order_writer *w, const hilbert_square *q)
{
    if (!hilbert_touches_grid(w, q))
        return;
    if (q->side == 1) {
        if (in_grid(w, q->cx, q->cy))
            emit(w, q->cx, q->cy);
        return;
    }
    int64_t h = q->side / 2;
    hilbert_square first = {q->cx, q->cy, q->bx, q->by, q->ax, q->ay, h};
    hilbert_square second = {q->cx + h * q->bx, q->cy + h * q->by, q->ax, q->ay, q->bx, q->by, h};
    hilbert_square third = {second.cx + h * q->ax, second.cy + h * q->ay, q->ax, q->ay, q->bx, q->by, h};
    hilbert_square last = {q->cx + (q->side - 1) * q->ax + (h - 1) * q->bx,
                           q->cy + (q->side - 1) * q->ay + (h - 1) * q->by, -q->bx, -q->by, -q->ax, -q->ay, h};
    hilbert_curve(w, &first);
    hilbert_curve(w, &second);
    hilbert_curve(w, &third);
    hilbert_curve(w, &last);
}

static void fill_hilbert(order_writer *w)
{
    hilbert_square whole = {0, 0, 1, 0, 0, 1, enclosing_side(w)};
    hilbert_curve(w, &whole);
}

/* The tiles of one column (x = fixed, y from first towards last) or one row
 * (y = fixed, x from first towards last), clipped to the grid, in that order. */
static void spiral_segment(order_writer *w, bool column, int64_t fixed, int64_t first, int64_t last)
{
    int64_t fixed_limit = column ? w->tiles_x : w->tiles_y, run_limit = column ? w->tiles_y : w->tiles_x;
    if (fixed < 0 || fixed >= fixed_limit)
        return;
    int64_t step = last >= first ? 1 : -1;
    int64_t lo = step > 0 ? first : last, hi = step > 0 ? last : first;
    lo = lo < 0 ? 0 : lo;
    hi = hi >= run_limit ? run_limit - 1 : hi;
    for (int64_t k = 0; k <= hi - lo; k++) {
        int64_t along = step > 0 ? lo + k : hi - k;
        if (column)
            emit(w, fixed, along);
        else
            emit(w, along, fixed);
    }
}

/* Rings r = 0, 1, ... around the centre tile until every tile is out:
 * ring r > 0 is its right side downwards (from one below the top-right
 * corner), bottom leftwards, left side upwards, top rightwards (ending on the
 * top-right corner, next to where ring r + 1 starts). Each side is clipped to
 * the grid before it is walked, so the cost is O(tiles + rings). */
static void fill_spiral(order_writer *w)
{
    const int64_t cx = (w->tiles_x - 1) / 2, cy = (w->tiles_y - 1) / 2;
    int64_t last_ring = cx > cy ? cx : cy;
    if (w->tiles_x - 1 - cx > last_ring)
        last_ring = w->tiles_x - 1 - cx;
    if (w->tiles_y - 1 - cy > last_ring)
        last_ring = w->tiles_y - 1 - cy;
    emit(w, cx, cy);
    for (int64_t r = 1; r <= last_ring; r++) {
        spiral_segment(w, true, cx + r, cy - r + 1, cy + r);
        spiral_segment(w, false, cy + r, cx + r - 1, cx - r);
        spiral_segment(w, true, cx - r, cy + r - 1, cy - r);
        spiral_segment(w, false, cy - r, cx - r + 1, cx + r);
    }
}

/* Fisher-Yates from the identity, swap partner j of position i drawn from
 * sampler_hash64 of (seed, i): a counter-based draw, so the permutation is a
 * pure function of (n, seed). j = floor(h * (i + 1) / 2^32) for the top 32
 * bits h of the hash; its bias is below (i + 1) / 2^32 per draw. */
static void fill_shuffle(order_writer *w, uint32_t seed)
{
    const uint32_t n = (uint32_t)(w->tiles_x * w->tiles_y);
    for (uint32_t i = 0; i < n; i++)
        w->order[i] = i;
    const uint64_t stream = sampler_hash64(((uint64_t)seed << 32) ^ 0x74696c65ull); /* "tile": a stream apart from pixel samples */
    for (uint32_t i = n - 1; i > 0; i--) {
        uint64_t h = sampler_hash64(stream + i) >> 32;
        uint32_t j = (uint32_t)((h * ((uint64_t)i + 1)) >> 32);
        uint32_t t = w->order[i];
        w->order[i] = w->order[j];
        w->order[j] = t;
    }
    w->written = n;
}

void tile_order_fill(tile_order o, int tiles_x, int tiles_y, uint32_t seed, uint32_t *order)
{
    order_writer w = {order, 0, tiles_x, tiles_y};
    switch (o) {
    case TILE_ORDER_COLUMNS:
        fill_columns(&w);
        break;
    case TILE_ORDER_MORTON:
        morton_square(&w, 0, 0, enclosing_side(&w));
        break;
    case TILE_ORDER_HILBERT:
        fill_hilbert(&w);
        break;
    case TILE_ORDER_SPIRAL:
        fill_spiral(&w);
        break;
    case TILE_ORDER_SHUFFLE:
        fill_shuffle(&w, seed);
        break;
    case TILE_ORDER_ROWS:
    default: /* out-of-range values still get a permutation */
        fill_rows(&w);
        break;
    }
}
