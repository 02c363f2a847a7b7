/* test_tile_order.c - tile orders: each a permutation of the tile indices for
 * any grid, and each the order its name promises (rows and columns exactly,
 * morton as bit interleaving, hilbert as a curve of 4-neighbour steps that
 * other grids cut out of the enclosing square, spiral as rings of
 * non-decreasing Chebyshev distance from the centre tile, shuffle as a
 * seed-determined permutation). */
#include <criterion/criterion.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/render/tile_order.h"

typedef struct grid {
    int x, y;
} grid;

/* 1920x1080 in 16-pixel tiles is 120x68; the rest are edge cases and odd shapes. */
static const grid sizes[] = {{1, 1},  {1, 9},  {9, 1},   {2, 2},    {7, 5},   {5, 7},  {120, 68},
                             {33, 17}, {16, 16}, {64, 3}, {3, 64}, {1, 1000}, {1000, 1}, {31, 32}};
#define SIZE_COUNT (sizeof sizes / sizeof sizes[0])

/* order[] as filled, in a fresh buffer (caller frees). */
static uint32_t *fill(tile_order o, grid g, uint32_t seed)
{
    size_t n = (size_t)g.x * (size_t)g.y;
    uint32_t *order = malloc(n * sizeof *order);
    cr_assert(order);
    tile_order_fill(o, g.x, g.y, seed, order);
    return order;
}

static void expect_permutation(const uint32_t *order, size_t n, const char *what, grid g)
{
    unsigned char *seen = calloc(n, 1);
    cr_assert(seen);
    size_t bad = 0;
    for (size_t i = 0; i < n; i++) {
        if (order[i] >= n || seen[order[i]]) {
            bad++;
            continue;
        }
        seen[order[i]] = 1;
    }
    cr_expect_eq(bad, 0, "%s %dx%d: %zu entries out of range or repeated", what, g.x, g.y, bad);
    free(seen);
}

Test(tile_order, every_order_is_a_permutation_for_any_grid)
{
    for (int o = 0; o < TILE_ORDER_COUNT; o++)
        for (size_t k = 0; k < SIZE_COUNT; k++) {
            uint32_t *order = fill((tile_order)o, sizes[k], 12345u);
            expect_permutation(order, (size_t)sizes[k].x * (size_t)sizes[k].y, tile_order_name((tile_order)o),
                               sizes[k]);
            free(order);
        }
}

Test(tile_order, long_thin_grids_do_not_walk_the_enclosing_square)
{
    /* 1 x 2^20: the enclosing square has 2^40 cells; pruning makes this instant */
    const grid g = {1, 1 << 20};
    const tile_order curves[] = {TILE_ORDER_MORTON, TILE_ORDER_HILBERT, TILE_ORDER_SPIRAL};
    for (size_t k = 0; k < 3; k++) {
        uint32_t *order = fill(curves[k], g, 0);
        expect_permutation(order, (size_t)g.y, tile_order_name(curves[k]), g);
        free(order);
    }
}

Test(tile_order, rows_and_columns_are_exact)
{
    for (size_t k = 0; k < SIZE_COUNT; k++) {
        grid g = sizes[k];
        uint32_t *rows = fill(TILE_ORDER_ROWS, g, 0), *cols = fill(TILE_ORDER_COLUMNS, g, 0);
        size_t n = (size_t)g.x * (size_t)g.y, bad_rows = 0, bad_cols = 0;
        for (size_t i = 0; i < n; i++) {
            bad_rows += rows[i] != i;
            size_t x = i / (size_t)g.y, y = i % (size_t)g.y; /* i-th in column-major order */
            bad_cols += cols[i] != y * (size_t)g.x + x;
        }
        cr_expect_eq(bad_rows, 0, "rows %dx%d", g.x, g.y);
        cr_expect_eq(bad_cols, 0, "columns %dx%d", g.x, g.y);
        free(rows);
        free(cols);
    }
}

/* Bit interleaving: x in the even bits, y in the odd bits. */
static uint64_t interleave(uint32_t x, uint32_t y)
{
    uint64_t code = 0;
    for (int b = 0; b < 32; b++)
        code |= (uint64_t)((x >> b) & 1u) << (2 * b) | (uint64_t)((y >> b) & 1u) << (2 * b + 1);
    return code;
}

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

Test(tile_order, morton_is_ascending_bit_interleaving)
{
    for (size_t k = 0; k < SIZE_COUNT; k++) {
        grid g = sizes[k];
        size_t n = (size_t)g.x * (size_t)g.y;
        if (n > 100000)
            continue;
        /* the expected order: tiles sorted by code (codes are unique; the
         * tile index rides in the low 32 bits after the code is shifted up) */
        uint64_t *keyed = malloc(n * sizeof *keyed);
        cr_assert(keyed);
        for (size_t t = 0; t < n; t++)
            keyed[t] = interleave((uint32_t)(t % (size_t)g.x), (uint32_t)(t / (size_t)g.x)) << 24 | t;
        qsort(keyed, n, sizeof *keyed, compare_u64);
        uint32_t *order = fill(TILE_ORDER_MORTON, g, 0);
        size_t bad = 0;
        for (size_t i = 0; i < n; i++)
            bad += order[i] != (uint32_t)(keyed[i] & 0xffffffu);
        cr_expect_eq(bad, 0, "morton %dx%d: %zu positions differ from sorted bit interleaving", g.x, g.y, bad);
        free(order);
        free(keyed);
    }
}

static int manhattan(uint32_t a, uint32_t b, int tiles_x)
{
    int ax = (int)a % tiles_x, ay = (int)a / tiles_x, bx = (int)b % tiles_x, by = (int)b / tiles_x;
    return abs(ax - bx) + abs(ay - by);
}

Test(tile_order, hilbert_steps_to_a_neighbour_on_power_of_two_squares)
{
    for (int side = 1; side <= 128; side *= 2) {
        grid g = {side, side};
        uint32_t *order = fill(TILE_ORDER_HILBERT, g, 0);
        size_t n = (size_t)side * (size_t)side, jumps = 0;
        for (size_t i = 1; i < n; i++)
            jumps += manhattan(order[i - 1], order[i], side) != 1;
        cr_expect_eq(jumps, 0, "hilbert %dx%d: %zu steps are not to a 4-neighbour", side, side, jumps);
        cr_expect_eq(order[0], 0u, "starts at tile (0, 0)");
        cr_expect_eq(order[n - 1], (uint32_t)(side - 1), "ends at tile (side - 1, 0)");
        free(order);
    }
}

Test(tile_order, hilbert_on_other_grids_is_the_square_curve_cut_to_the_grid)
{
    const grid cut[] = {{7, 5}, {5, 7}, {33, 17}, {120, 68}, {1, 9}, {3, 64}};
    for (size_t k = 0; k < sizeof cut / sizeof cut[0]; k++) {
        grid g = cut[k];
        int side = 1;
        while (side < g.x || side < g.y)
            side *= 2;
        uint32_t *square = fill(TILE_ORDER_HILBERT, (grid){side, side}, 0), *order = fill(TILE_ORDER_HILBERT, g, 0);
        size_t at = 0, bad = 0;
        for (size_t i = 0; i < (size_t)side * (size_t)side; i++) {
            int x = (int)(square[i] % (uint32_t)side), y = (int)(square[i] / (uint32_t)side);
            if (x < g.x && y < g.y)
                bad += order[at++] != (uint32_t)(y * g.x + x);
        }
        cr_expect_eq(bad, 0, "hilbert %dx%d differs from the %dx%d curve cut to the grid", g.x, g.y, side, side);
        free(square);
        free(order);
    }
}

/* The spiral's ring of a tile: Chebyshev distance to the centre tile. */
static int spiral_ring(uint32_t t, grid g)
{
    int cx = (g.x - 1) / 2, cy = (g.y - 1) / 2, x = (int)t % g.x, y = (int)t / g.x;
    int dx = abs(x - cx), dy = abs(y - cy);
    return dx > dy ? dx : dy;
}

Test(tile_order, spiral_starts_at_the_centre_and_rings_never_shrink)
{
    for (size_t k = 0; k < SIZE_COUNT; k++) {
        grid g = sizes[k];
        size_t n = (size_t)g.x * (size_t)g.y, shrinks = 0;
        uint32_t *order = fill(TILE_ORDER_SPIRAL, g, 0);
        cr_expect_eq(order[0], (uint32_t)(((g.y - 1) / 2) * g.x + (g.x - 1) / 2), "%dx%d: first tile is the centre",
                     g.x, g.y);
        for (size_t i = 1; i < n; i++)
            shrinks += spiral_ring(order[i], g) < spiral_ring(order[i - 1], g);
        cr_expect_eq(shrinks, 0, "spiral %dx%d: %zu steps go to a nearer ring", g.x, g.y, shrinks);
        free(order);
    }
}

Test(tile_order, spiral_on_odd_squares_is_one_connected_walk)
{
    /* no ring is clipped on an odd square: every step goes to a 4-neighbour,
     * and the first steps are right, down, left, left (clockwise on screen) */
    for (int side = 1; side <= 15; side += 2) {
        grid g = {side, side};
        uint32_t *order = fill(TILE_ORDER_SPIRAL, g, 0);
        size_t n = (size_t)side * (size_t)side, jumps = 0;
        for (size_t i = 1; i < n; i++)
            jumps += manhattan(order[i - 1], order[i], side) != 1;
        cr_expect_eq(jumps, 0, "spiral %dx%d: %zu steps are not to a 4-neighbour", side, side, jumps);
        if (side >= 3) {
            uint32_t c = order[0], w = (uint32_t)side;
            cr_expect_eq(order[1], c + 1, "right");
            cr_expect_eq(order[2], c + 1 + w, "down");
            cr_expect_eq(order[3], c + w, "left");
        }
        free(order);
    }
}

Test(tile_order, shuffle_is_fixed_by_its_seed)
{
    const grid g = {120, 68};
    const size_t n = (size_t)g.x * (size_t)g.y;
    uint32_t *a = fill(TILE_ORDER_SHUFFLE, g, 7), *b = fill(TILE_ORDER_SHUFFLE, g, 7), *c = fill(TILE_ORDER_SHUFFLE, g, 8);
    cr_expect(memcmp(a, b, n * sizeof *a) == 0, "the same seed gives the same permutation");
    size_t same_place = 0, in_place = 0;
    for (size_t i = 0; i < n; i++) {
        same_place += a[i] == c[i];
        in_place += a[i] == i;
    }
    /* a random permutation agrees with another (or with the identity) in ~1 place */
    cr_expect(same_place < 20, "seeds 7 and 8 agree in %zu of %zu places", same_place, n);
    cr_expect(in_place < 20, "seed 7 leaves %zu of %zu tiles in row order", in_place, n);
    free(a);
    free(b);
    free(c);
}

Test(tile_order, shuffle_moves_tiles_uniformly)
{
    /* where tile 0 ends up over many seeds on a 4x4 grid: each of the 16 places
     * ~1/16 of the time (chi-square, 15 degrees of freedom, 40 is p ~ 5e-4;
     * deterministic, so this cannot flake) */
    enum { places = 16, trials = 16000 };
    int hits[places] = {0};
    uint32_t order[places];
    for (uint32_t seed = 0; seed < trials; seed++) {
        tile_order_fill(TILE_ORDER_SHUFFLE, 4, 4, seed, order);
        for (int i = 0; i < places; i++)
            hits[i] += order[i] == 0;
    }
    double chi2 = 0.0, expect = (double)trials / places;
    for (int i = 0; i < places; i++)
        chi2 += (hits[i] - expect) * (hits[i] - expect) / expect;
    cr_expect(chi2 < 40.0, "chi-square %.1f over 15 degrees of freedom", chi2);
}

Test(tile_order, names_round_trip_and_unknown_names_are_rejected)
{
    for (int o = 0; o < TILE_ORDER_COUNT; o++) {
        const char *name = tile_order_name((tile_order)o);
        cr_assert(name, "order %d has a name", o);
        cr_expect(strstr(TILE_ORDER_NAMES, name), "'%s' is listed in TILE_ORDER_NAMES", name);
        tile_order back = TILE_ORDER_COUNT;
        cr_expect(tile_order_from_name(name, &back), "'%s' parses", name);
        cr_expect_eq(back, (tile_order)o);
    }
    const char *bad[] = {"", "Rows", "row", "spiral ", "hilbertx", "zorder", "shuffle:3"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        tile_order out = TILE_ORDER_SPIRAL;
        cr_expect(!tile_order_from_name(bad[k], &out), "'%s' is rejected", bad[k]);
        cr_expect_eq(out, TILE_ORDER_SPIRAL, "a rejected name leaves *out alone");
    }
    tile_order out = TILE_ORDER_ROWS;
    cr_expect(!tile_order_from_name(NULL, &out));
    cr_expect_null(tile_order_name(TILE_ORDER_COUNT));
}
