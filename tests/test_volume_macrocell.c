/* test_volume_macrocell.c - the min/max grid and the 3D-DDA
 * (engine/geometry/volume/macrocell.h) against brute force on random volumes and
 * random rays: every macrocell's range against its samples scanned directly,
 * every walk against the boxes the ray meets, clipped one by one. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/geometry/volume/macrocell.h"
#include "engine/geometry/volume/volume.h"

/* a small deterministic generator (splitmix64), so failures reproduce */
static uint64_t rng_state;

static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double rng_unit(void) { return (double)(rng_next() >> 11) * 0x1.0p-53; }

static volume *random_volume(uint32_t nx, uint32_t ny, uint32_t nz)
{
    tess_error err = {{0}};
    volume *v = volume_create(nx, ny, nz, VOLUME_FLOAT32, &err);
    cr_assert_not_null(v, "%s", err.msg);
    float *s = volume_voxels(v);
    for (size_t i = 0; i < volume_count(v); i++)
        s[i] = (float)(rng_unit() * 200.0 - 100.0);
    cr_assert(volume_update_range(v, "random", &err), "%s", err.msg);
    return v;
}

Test(volume_macrocell, ranges_match_brute_force)
{
    rng_state = 1;
    const uint32_t dims[][3] = {{2, 2, 2}, {9, 9, 9}, {17, 5, 23}, {8, 16, 3}, {33, 12, 7}};
    const uint32_t ks[] = {1, 2, 3, 4, 8, 16};
    for (size_t d = 0; d < sizeof dims / sizeof dims[0]; d++) {
        volume *v = random_volume(dims[d][0], dims[d][1], dims[d][2]);
        for (size_t ki = 0; ki < sizeof ks / sizeof ks[0]; ki++) {
            uint32_t k = ks[ki];
            tess_error err = {{0}};
            macrocell_grid *g = macrocell_grid_create(v, k, &err);
            cr_assert_not_null(g, "%s", err.msg);
            for (int a = 0; a < 3; a++)
                cr_assert_eq(g->m[a], (dims[d][a] - 1 + k - 1) / k);
            for (uint32_t c = 0; c < g->m[2]; c++)
                for (uint32_t b = 0; b < g->m[1]; b++)
                    for (uint32_t a = 0; a < g->m[0]; a++) {
                        /* the samples of every cell in the block, shared faces included */
                        float lo = INFINITY, hi = -INFINITY;
                        for (uint32_t z = c * k; z <= (c + 1) * k && z < v->nz; z++)
                            for (uint32_t y = b * k; y <= (b + 1) * k && y < v->ny; y++)
                                for (uint32_t x = a * k; x <= (a + 1) * k && x < v->nx; x++) {
                                    float s = volume_sample(v, x, y, z);
                                    lo = fminf(lo, s);
                                    hi = fmaxf(hi, s);
                                }
                        size_t m = macrocell_index(g, a, b, c);
                        cr_assert_eq(g->min[m], lo, "dims %u %u %u k %u macrocell (%u %u %u)", v->nx, v->ny, v->nz,
                                     k, a, b, c);
                        cr_assert_eq(g->max[m], hi);
                    }
            /* may_reach against every trilinear cell: a cell whose corners bracket iso lies in a
             * macrocell that says it may reach iso */
            for (int trial = 0; trial < 50; trial++) {
                float iso = (float)(rng_unit() * 220.0 - 110.0);
                for (uint32_t z = 0; z + 1 < v->nz; z++)
                    for (uint32_t y = 0; y + 1 < v->ny; y++)
                        for (uint32_t x = 0; x + 1 < v->nx; x++) {
                            float corner[8], lo = INFINITY, hi = -INFINITY;
                            volume_cell_corners(v, x, y, z, corner);
                            for (int i = 0; i < 8; i++) {
                                lo = fminf(lo, corner[i]);
                                hi = fmaxf(hi, corner[i]);
                            }
                            if (lo <= iso && iso <= hi)
                                cr_assert(macrocell_may_reach(g, macrocell_index(g, x / k, y / k, z / k), iso));
                        }
            }
            macrocell_grid_destroy(g);
        }
        volume_destroy(v);
    }
}

Test(volume_macrocell, refusals)
{
    tess_error err = {{0}};
    volume *v = volume_create(5, 1, 5, VOLUME_UINT8, &err);
    cr_assert_not_null(v);
    cr_assert_null(macrocell_grid_create(v, 8, &err));
    cr_assert(strstr(err.msg, "along y"), "%s", err.msg);
    volume_destroy(v);
    v = volume_create(5, 5, 5, VOLUME_UINT8, &err);
    memset(&err, 0, sizeof err);
    cr_assert_null(macrocell_grid_create(v, 0, &err));
    cr_assert(strstr(err.msg, "block edge 0"), "%s", err.msg);
    volume_destroy(v);
    macrocell_grid_destroy(NULL);
}

/* ---- walks ------------------------------------------------------------------ */

/* a box the ray meets, as brute force finds it */
typedef struct box_span {
    int32_t cell[3];
    double t0, t1;
} box_span;

static int by_entry(const void *pa, const void *pb)
{
    const box_span *a = pa, *b = pb;
    return a->t0 < b->t0 ? -1 : a->t0 > b->t0;
}

/* spans shorter than this (in t, for rays of length ~1 per voxel) are a ray
 * grazing an edge or corner: brute force and the walk may disagree about
 * them by rounding, so neither list keeps them */
#define GRAZE_T 1e-9

/* Brute force: every cell of size `size` in the grid of `count` cells
 * (clipped to `extent`), clipped against the ray over [t0, t1]; sorted by
 * entry (ties, which only a ray in a plane could make, are excluded below). */
static size_t brute_force_spans(const double org[3], const double dir[3], double t0, double t1, uint32_t size,
                                const uint32_t count[3], const uint32_t extent[3], box_span *out, size_t cap)
{
    size_t n = 0;
    for (uint32_t c = 0; c < count[2]; c++)
        for (uint32_t b = 0; b < count[1]; b++)
            for (uint32_t a = 0; a < count[0]; a++) {
                const uint32_t idx[3] = {a, b, c};
                double lo[3], hi[3];
                for (int ax = 0; ax < 3; ax++) {
                    lo[ax] = (double)idx[ax] * size;
                    hi[ax] = fmin((double)(idx[ax] + 1) * size, extent[ax]);
                }
                /* a ray lying in a plane between cells parallel to it belongs to the
                 * cell above the plane (the last one at the far face): the walk's
                 * convention, floor of the coordinate, clamped */
                bool in_plane_elsewhere = false;
                for (int ax = 0; ax < 3; ax++)
                    if (dir[ax] == 0.0) {
                        double f = floor(org[ax] / size);
                        f = f > count[ax] - 1.0 ? count[ax] - 1.0 : f;
                        in_plane_elsewhere |= f != (double)idx[ax];
                    }
                double s0 = t0, s1 = t1;
                if (in_plane_elsewhere || !volume_clip_box(org, dir, lo, hi, &s0, &s1) || s1 - s0 <= GRAZE_T)
                    continue;
                cr_assert(n < cap);
                out[n] = (box_span){{(int32_t)a, (int32_t)b, (int32_t)c}, s0, s1};
                n++;
            }
    qsort(out, n, sizeof *out, by_entry);
    return n;
}

/* a random ray: from a point in a box around the grid towards a point in it,
 * sometimes along an axis, sometimes starting on integer coordinates (on
 * cell planes, edges and corners) */
static void random_ray(const uint32_t extent[3], double org[3], double dir[3])
{
    int kind = (int)(rng_next() % 4);
    double target[3];
    for (int a = 0; a < 3; a++) {
        org[a] = rng_unit() * (extent[a] + 8.0) - 4.0;
        target[a] = rng_unit() * extent[a];
        if (kind == 1) {
            org[a] = floor(org[a]);
            target[a] = floor(target[a]);
        }
    }
    for (int a = 0; a < 3; a++)
        dir[a] = target[a] - org[a];
    if (kind == 2) {
        int keep = (int)(rng_next() % 3);
        for (int a = 0; a < 3; a++)
            if (a != keep) {
                dir[a] = 0.0;
                org[a] = kind == 2 && rng_next() % 2 ? floor(target[a]) : target[a];
            }
        if (dir[keep] == 0.0)
            dir[keep] = 1.0;
    }
    if (kind == 3) {
        /* a diagonal through lattice points */
        for (int a = 0; a < 3; a++) {
            org[a] = floor(org[a]);
            dir[a] = rng_next() % 2 ? 1.0 : -1.0;
        }
    }
}

Test(volume_macrocell, walks_match_brute_force)
{
    rng_state = 7;
    static box_span brute[20000], walked[20000];
    const uint32_t dims[][3] = {{17, 5, 23}, {9, 9, 9}, {33, 12, 7}};
    const uint32_t ks[] = {1, 3, 8};
    size_t rays_checked = 0, spans_checked = 0;
    for (size_t d = 0; d < sizeof dims / sizeof dims[0]; d++) {
        volume *v = random_volume(dims[d][0], dims[d][1], dims[d][2]);
        /* a world frame that is not the voxel frame */
        v->spacing[0] = 0.5;
        v->spacing[1] = 1.25;
        v->spacing[2] = 2.0;
        v->origin[0] = -3.0;
        v->origin[1] = 10.0;
        v->origin[2] = 0.25;
        for (size_t ki = 0; ki < sizeof ks / sizeof ks[0]; ki++) {
            tess_error err = {{0}};
            macrocell_grid *g = macrocell_grid_create(v, ks[ki], &err);
            cr_assert_not_null(g, "%s", err.msg);
            for (int r = 0; r < 300; r++) {
                double org_vox[3], dir_vox[3], org[3], dir[3];
                random_ray(g->cells, org_vox, dir_vox);
                for (int a = 0; a < 3; a++) {
                    org[a] = v->origin[a] + org_vox[a] * v->spacing[a];
                    dir[a] = dir_vox[a] * v->spacing[a];
                }
                /* the walk works on the voxel ray it maps the world ray to: brute force on the same */
                double ov[3], dv[3];
                volume_ray_to_voxel(v->origin, v->spacing, org, dir, ov, dv);
                double t_min = rng_next() % 2 ? 0.0 : -1e30, t_max = rng_next() % 4 ? 1e30 : 0.6;
                size_t nb = brute_force_spans(ov, dv, t_min, t_max, g->k, g->m, g->cells, brute, 20000);
                macrocell_walk w;
                bool any = macrocell_walk_begin(&w, g, org, dir, t_min, t_max);
                size_t nw = 0;
                macrocell_span span;
                double last_exit = NAN;
                while (any && macrocell_walk_next(&w, &span)) {
                    cr_assert(span.t_exit > span.t_enter);
                    if (nw > 0 || !isnan(last_exit))
                        cr_assert_eq(span.t_enter, last_exit, "spans tile the ray: no gap, no overlap");
                    last_exit = span.t_exit;
                    cr_assert_eq(span.index, macrocell_index(g, span.m[0], span.m[1], span.m[2]));
                    /* the cells inside the span tile it too, and lie in the macrocell */
                    volume_dda cells;
                    macrocell_walk_cells(&w, &span, &cells);
                    int32_t c[3];
                    double te, tx, cell_last = span.t_enter;
                    while (volume_dda_next(&cells, c, &te, &tx)) {
                        cr_assert_eq(te, cell_last);
                        cell_last = tx;
                        for (int a = 0; a < 3; a++)
                            cr_assert((uint32_t)c[a] / g->k == span.m[a]);
                    }
                    cr_assert_eq(cell_last, span.t_exit);
                    if (span.t_exit - span.t_enter <= GRAZE_T)
                        continue;
                    cr_assert(nw < 20000);
                    walked[nw++] = (box_span){{(int32_t)span.m[0], (int32_t)span.m[1], (int32_t)span.m[2]},
                                              span.t_enter, span.t_exit};
                }
                cr_assert_eq(nw, nb, "k %u ray %d: walk gave %zu macrocells, brute force %zu", g->k, r, nw, nb);
                for (size_t i = 0; i < nb; i++) {
                    cr_assert(memcmp(walked[i].cell, brute[i].cell, sizeof brute[i].cell) == 0,
                              "ray %d span %zu: (%d %d %d) against (%d %d %d)", r, i, walked[i].cell[0],
                              walked[i].cell[1], walked[i].cell[2], brute[i].cell[0], brute[i].cell[1],
                              brute[i].cell[2]);
                    double scale = 1.0 + fabs(brute[i].t1);
                    cr_assert(fabs(walked[i].t0 - brute[i].t0) <= 1e-12 * scale + 1e-12 * fabs(brute[i].t0));
                    cr_assert(fabs(walked[i].t1 - brute[i].t1) <= 1e-12 * scale);
                }
                rays_checked++;
                spans_checked += nb;
            }
            macrocell_grid_destroy(g);
        }
        volume_destroy(v);
    }
    cr_assert_gt(spans_checked, rays_checked, "the rays cross the grids");
}

/* rays that go nowhere or are not numbers cross nothing (and never reach an
 * integer conversion of a NaN: UBSan builds would say so) */
Test(volume_macrocell, degenerate_rays)
{
    rng_state = 9;
    volume *v = random_volume(9, 9, 9);
    tess_error err = {{0}};
    macrocell_grid *g = macrocell_grid_create(v, 4, &err);
    cr_assert_not_null(g, "%s", err.msg);
    const double inside[3] = {4.0, 4.0, 4.0}, zero[3] = {0.0, 0.0, 0.0}, nan_dir[3] = {NAN, 1.0, 0.0},
                 nan_org[3] = {NAN, 4.0, 4.0}, along[3] = {0.0, 1.0, 0.0};
    macrocell_walk w;
    macrocell_span span;
    cr_assert_not(macrocell_walk_begin(&w, g, inside, zero, -INFINITY, INFINITY));
    cr_assert_not(macrocell_walk_next(&w, &span));
    cr_assert_not(macrocell_walk_begin(&w, g, inside, nan_dir, 0.0, INFINITY));
    cr_assert_not(macrocell_walk_begin(&w, g, nan_org, along, 0.0, INFINITY));
    cr_assert_not(macrocell_walk_begin(&w, g, inside, along, NAN, INFINITY));
    /* an axis-parallel ray over an infinite t range: clipped to the box, both macrocells along y */
    cr_assert(macrocell_walk_begin(&w, g, inside, along, -INFINITY, INFINITY));
    int count = 0;
    double last = -INFINITY;
    while (macrocell_walk_next(&w, &span)) {
        cr_assert(isfinite(span.t_enter) && isfinite(span.t_exit) && span.t_enter >= last);
        cr_assert_eq(span.m[0], 1);
        cr_assert_eq(span.m[1], (uint32_t)count);
        last = span.t_exit;
        count++;
    }
    cr_assert_eq(count, 2);
    cr_assert_eq(last, 4.0, "the box's far face: y = 8, from y = 4");
    macrocell_grid_destroy(g);
    volume_destroy(v);
}

static bool same_span(const macrocell_span *a, const macrocell_span *b)
{
    return a->m[0] == b->m[0] && a->m[1] == b->m[1] && a->m[2] == b->m[2] && a->index == b->index &&
           a->t_enter == b->t_enter && a->t_exit == b->t_exit;
}

/* marks for a leap field: a few random balls of one class in the other, so
 * distances run from 1 to well past MACROCELL_LEAP_MIN */
static void random_marks(const macrocell_grid *g, uint8_t *leap)
{
    double centre[4][3], radius[4];
    for (int b = 0; b < 4; b++) {
        for (int a = 0; a < 3; a++)
            centre[b][a] = rng_unit() * g->m[a];
        radius[b] = 0.5 + rng_unit() * 4.0;
    }
    for (uint32_t c = 0; c < g->m[2]; c++)
        for (uint32_t b = 0; b < g->m[1]; b++)
            for (uint32_t a = 0; a < g->m[0]; a++) {
                bool inside = false;
                for (int i = 0; i < 4; i++) {
                    double dx = a - centre[i][0], dy = b - centre[i][1], dz = c - centre[i][2];
                    inside |= dx * dx + dy * dy + dz * dz <= radius[i] * radius[i];
                }
                leap[macrocell_index(g, a, b, c)] = inside ? 0 : MACROCELL_LEAP_MARK;
            }
}

/* the leap field against the distance scanned directly, and every walk
 * that leaps from every span against the walk that does not: its spans are
 * some of the full walk's, bit for bit, and those it leaps over are of the
 * class of the span it leapt from */
Test(volume_macrocell, leaps_match_full_walk)
{
    rng_state = 11;
    const uint32_t dims[][3] = {{41, 31, 21}, {17, 40, 9}, {9, 9, 50}};
    const uint32_t ks[] = {1, 2};
    static macrocell_span full[4096];
    size_t leaps_taken = 0, spans_leapt = 0;
    for (size_t d = 0; d < sizeof dims / sizeof dims[0]; d++) {
        volume *v = random_volume(dims[d][0], dims[d][1], dims[d][2]);
        v->spacing[0] = 0.5;
        v->spacing[2] = 2.0;
        v->origin[1] = -7.0;
        for (size_t ki = 0; ki < sizeof ks / sizeof ks[0]; ki++) {
            tess_error err = {{0}};
            macrocell_grid *g = macrocell_grid_create(v, ks[ki], &err);
            cr_assert_not_null(g, "%s", err.msg);
            uint8_t *leap = malloc(macrocell_count(g));
            cr_assert_not_null(leap);
            for (int field = 0; field < 4; field++) {
                random_marks(g, leap);
                macrocell_leap_build(g, leap);
                for (uint32_t c = 0; c < g->m[2]; c++)
                    for (uint32_t b = 0; b < g->m[1]; b++)
                        for (uint32_t a = 0; a < g->m[0]; a++) {
                            uint8_t here = leap[macrocell_index(g, a, b, c)];
                            uint32_t best = MACROCELL_LEAP_MAX;
                            for (uint32_t z = 0; z < g->m[2]; z++)
                                for (uint32_t y = 0; y < g->m[1]; y++)
                                    for (uint32_t x = 0; x < g->m[0]; x++) {
                                        uint8_t there = leap[macrocell_index(g, x, y, z)];
                                        if ((there & MACROCELL_LEAP_MARK) == (here & MACROCELL_LEAP_MARK))
                                            continue;
                                        uint32_t dx = x > a ? x - a : a - x, dy = y > b ? y - b : b - y,
                                                 dz = z > c ? z - c : c - z;
                                        uint32_t dist = dx > dy ? dx : dy;
                                        dist = dz > dist ? dz : dist;
                                        best = dist < best ? dist : best;
                                    }
                            cr_assert_eq(macrocell_leap_dist(here), best, "(%u %u %u)", a, b, c);
                        }
                for (int r = 0; r < 200; r++) {
                    double org_vox[3], dir_vox[3], org[3], dir[3];
                    random_ray(g->cells, org_vox, dir_vox);
                    for (int a = 0; a < 3; a++) {
                        org[a] = v->origin[a] + org_vox[a] * v->spacing[a];
                        dir[a] = dir_vox[a] * v->spacing[a];
                    }
                    double t_min = rng_next() % 2 ? 0.0 : -1e30, t_max = rng_next() % 4 ? 1e30 : 0.6;
                    macrocell_walk w;
                    macrocell_span span;
                    size_t nf = 0;
                    bool any = macrocell_walk_begin(&w, g, org, dir, t_min, t_max);
                    while (any && macrocell_walk_next(&w, &span)) {
                        cr_assert(nf < 4096);
                        full[nf++] = span;
                    }
                    any = macrocell_walk_begin(&w, g, org, dir, t_min, t_max);
                    size_t at = 0;
                    uint8_t from_class = 0;
                    bool leapt = false;
                    while (any && macrocell_walk_next(&w, &span)) {
                        /* the full walk's spans it passed lie in the cube it leapt over */
                        while (at < nf && !same_span(&full[at], &span)) {
                            cr_assert(leapt, "ray %d: a span (%u %u %u) lost without a leap", r, full[at].m[0],
                                      full[at].m[1], full[at].m[2]);
                            cr_assert_eq(leap[full[at].index] & MACROCELL_LEAP_MARK, from_class);
                            at++;
                            spans_leapt++;
                        }
                        cr_assert(at < nf, "ray %d: span (%u %u %u) [%a %a] is not the full walk's", r, span.m[0],
                                  span.m[1], span.m[2], span.t_enter, span.t_exit);
                        at++;
                        uint8_t here = leap[span.index];
                        from_class = here & MACROCELL_LEAP_MARK;
                        leapt = macrocell_leap_dist(here) >= MACROCELL_LEAP_MIN;
                        leaps_taken += leapt;
                        macrocell_walk_leap(&w, &span, macrocell_leap_dist(here));
                    }
                    for (; at < nf; at++) {
                        cr_assert(leapt, "ray %d: the walk ended early without a leap", r);
                        cr_assert_eq(leap[full[at].index] & MACROCELL_LEAP_MARK, from_class);
                        spans_leapt++;
                    }
                }
            }
            free(leap);
            macrocell_grid_destroy(g);
        }
        volume_destroy(v);
    }
    cr_assert_gt(spans_leapt, leaps_taken, "leaps pass more than one span");
    cr_log_info("volume_macrocell leaps: %zu leaps passed %zu spans", leaps_taken, spans_leapt);
}
