/* tile_order.h - the order in which an image's tiles are handed to render threads.
 *
 * Tiles form a tiles_x x tiles_y grid; tile (x, y) has index y * tiles_x + x.
 * An order is a permutation of [0, tiles_x * tiles_y): the traverser hands
 * out order[0], order[1], ... from its atomic counter. Orders change only
 * which tile is rendered when, never a pixel (render.h: images are pure
 * functions of scene, camera and pixel).
 *
 *   rows     row by row, left to right, top row first (order[i] = i)
 *   columns  column by column, top to bottom, left column first
 *   morton   Z-order: ascending bit interleaving of (x, y), x in the even
 *            (lower) bits, over the enclosing power-of-two square
 *   hilbert  the Hilbert curve over the enclosing power-of-two square,
 *            starting at tile (0, 0) and ending at (side - 1, 0); on a
 *            power-of-two square grid consecutive tiles are 4-neighbours
 *   spiral   centre outwards: rings of growing Chebyshev distance
 *            max(|x - cx|, |y - cy|) from the centre tile
 *            (cx, cy) = ((tiles_x - 1) / 2, (tiles_y - 1) / 2) (integer division);
 *            ring r is walked clockwise on screen (y down), starting just below
 *            its top-right corner and ending on it, i.e. the square spiral
 *            right, down, left, up; tiles of a ring outside the grid are skipped
 *   shuffle  a pseudo-random permutation, a pure function of (grid, seed)
 *
 * Morton and hilbert on other grids visit the same curve and skip the tiles
 * outside the grid (without walking them: whole outside quadrants are pruned,
 * so a 1 x N grid costs O(N log N), not O(N^2)). */
#ifndef TESSERA_TILE_ORDER_H
#define TESSERA_TILE_ORDER_H

#include <stdbool.h>
#include <stdint.h>

typedef enum tile_order {
    TILE_ORDER_ROWS,
    TILE_ORDER_COLUMNS,
    TILE_ORDER_MORTON,
    TILE_ORDER_HILBERT,
    TILE_ORDER_SPIRAL,
    TILE_ORDER_SHUFFLE,
    TILE_ORDER_COUNT
} tile_order;

/* "rows", "columns", "morton", "hilbert", "spiral", "shuffle"; NULL for a value
 * outside the enum. */
const char *tile_order_name(tile_order o);

/* The order a name (exact, lower case) stands for; false, *out untouched, for
 * any other string (or NULL). */
bool tile_order_from_name(const char *name, tile_order *out);

/* A comma-separated list of every name, for usage and error text. */
#define TILE_ORDER_NAMES "rows, columns, morton, hilbert, spiral, shuffle"

/* Fill order[0 .. tiles_x * tiles_y) with a permutation of the tile indices
 * in order o. tiles_x, tiles_y >= 1 and tiles_x * tiles_y < 2^32; `seed`
 * matters only to TILE_ORDER_SHUFFLE. Allocates nothing. */
void tile_order_fill(tile_order o, int tiles_x, int tiles_y, uint32_t seed, uint32_t *order);

#endif
