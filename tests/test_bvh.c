/* test_bvh.c - the binned-SAH BVH builder (engine/accel/bvh.c) and the parallel loops
 * it runs on (engine/base/parallel.c).
 *
 * Every input is generated here from a fixed seed. check_bvh() walks a built tree
 * and asserts everything bvh.h promises: each primitive exactly once, each node's
 * bounds the exact union of what is below it, leaves of 1..BVH_LEAF_MAX primitives
 * tiling prim_order, the documented depth-first pair layout, the depth bound.
 * Builds with 1, 2, 3 and 7 threads must give the same bytes. */
#include <criterion/criterion.h>

#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "engine/accel/bvh.h"
#include "engine/accel/wbvh.h"
#include "engine/base/parallel.h"

static const int thread_counts[] = {1, 2, 3, 7};
#define THREAD_VARIANTS (sizeof thread_counts / sizeof thread_counts[0])

/* ---- inputs ------------------------------------------------------------ */

/* splitmix64: a fixed sequence on every host */
static uint64_t rng_next(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static float rng_unit(uint64_t *state) { return (float)(rng_next(state) >> 40) / (float)(1u << 24); }

static vec3 rng_point(uint64_t *state, float scale)
{
    float x = rng_unit(state), y = rng_unit(state), z = rng_unit(state);
    return v3(x * scale, y * scale, z * scale);
}

static aabb *alloc_boxes(uint32_t n)
{
    aabb *b = malloc(((size_t)n + 1) * sizeof *b);
    cr_assert_not_null(b);
    return b;
}

/* Boxes of random size (up to 2) at random places in a 100-unit cube. */
static aabb *random_boxes(uint32_t n, uint64_t seed)
{
    aabb *b = alloc_boxes(n);
    for (uint32_t i = 0; i < n; i++) {
        vec3 lo = rng_point(&seed, 100.f);
        b[i] = (aabb){lo, v3_add(lo, rng_point(&seed, 2.f))};
    }
    return b;
}

/* Bounds of small random triangles (edges up to 0.5) in a 100-unit cube. */
static aabb *random_triangle_boxes(uint32_t n, uint64_t seed)
{
    aabb *b = alloc_boxes(n);
    for (uint32_t i = 0; i < n; i++) {
        vec3 p0 = rng_point(&seed, 100.f);
        vec3 p1 = v3_add(p0, v3_sub(rng_point(&seed, 0.5f), v3(0.25f, 0.25f, 0.25f)));
        vec3 p2 = v3_add(p0, v3_sub(rng_point(&seed, 0.5f), v3(0.25f, 0.25f, 0.25f)));
        b[i] = aabb_grow_point(aabb_grow_point(aabb_grow_point(aabb_empty(), p0), p1), p2);
    }
    return b;
}

/* side^3 unit boxes on an integer grid, in x-fastest order. */
static aabb *grid_boxes(uint32_t side)
{
    aabb *b = alloc_boxes(side * side * side);
    uint32_t i = 0;
    for (uint32_t z = 0; z < side; z++)
        for (uint32_t y = 0; y < side; y++)
            for (uint32_t x = 0; x < side; x++, i++) {
                vec3 lo = v3((float)x, (float)y, (float)z);
                b[i] = (aabb){lo, v3_add(lo, v3(1.f, 1.f, 1.f))};
            }
    return b;
}

/* Boxes of different sizes all centred on (1, 2, 3): no split by centroid exists. */
static aabb *same_centroid_boxes(uint32_t n, uint64_t seed)
{
    aabb *b = alloc_boxes(n);
    vec3 c = v3(1.f, 2.f, 3.f);
    for (uint32_t i = 0; i < n; i++) {
        float r = 0.25f * (float)(1 + rng_next(&seed) % 8); /* exact in binary */
        b[i] = (aabb){v3_sub(c, v3(r, r, r)), v3_add(c, v3(r, r, r))};
    }
    return b;
}

/* ---- checking a tree ----------------------------------------------------- */

static bool contains(aabb outer, aabb inner)
{
    if (aabb_is_empty(inner))
        return true;
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           outer.hi.x >= inner.hi.x && outer.hi.y >= inner.hi.y && outer.hi.z >= inner.hi.z;
}

static bool same_box(aabb a, aabb b)
{
    return a.lo.x == b.lo.x && a.lo.y == b.lo.y && a.lo.z == b.lo.z && a.hi.x == b.hi.x && a.hi.y == b.hi.y &&
           a.hi.z == b.hi.z;
}

/* Everything bvh.h promises about a tree over boxes[0..n). */
static void check_bvh(const bvh *b, const aabb *boxes, uint32_t n)
{
    if (n == 0) {
        cr_assert_eq(b->node_count, 0);
        cr_assert_null(b->nodes);
        cr_assert_eq(b->prim_count, 0);
        return;
    }
    cr_assert_eq(b->prim_count, n);
    cr_assert(b->node_count >= 1 && b->node_count <= 2 * n - 1, "node_count %u for %u primitives", b->node_count, n);

    /* prim_order is a permutation of 0..n-1 */
    uint8_t *seen = calloc(n, 1);
    cr_assert_not_null(seen);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t id = b->prim_order[i];
        cr_assert(id < n, "prim_order[%u] = %u out of range", i, id);
        cr_assert(!seen[id], "primitive %u appears twice", id);
        seen[id] = 1;
    }

    /* walk: depth first, left first, as the layout is defined */
    uint8_t *covered = calloc(n, 1), *visited = calloc(b->node_count, 1);
    uint32_t *stack = malloc(((size_t)b->node_count + 1) * sizeof *stack);
    uint32_t *stack_depth = malloc(((size_t)b->node_count + 1) * sizeof *stack_depth);
    cr_assert(covered && visited && stack && stack_depth);
    uint32_t top = 0, visits = 0, max_depth = 0, next_pair = 1;
    stack[top] = 0;
    stack_depth[top++] = 1;
    while (top > 0) {
        top--;
        uint32_t i = stack[top], depth = stack_depth[top];
        cr_assert(!visited[i], "node %u reached twice", i);
        visited[i] = 1;
        visits++;
        cr_assert(depth <= BVH_MAX_DEPTH, "depth %u over BVH_MAX_DEPTH", depth);
        if (depth > max_depth)
            max_depth = depth;
        const bvh_node *node = &b->nodes[i];
        aabb below = aabb_empty();
        if (node->count == 0) {
            cr_assert_eq(node->first, next_pair, "node %u: children at %u, the layout puts them at %u", i,
                         node->first, next_pair);
            next_pair += 2;
            cr_assert((uint64_t)node->first + 1 < b->node_count, "node %u: children %u out of range", i, node->first);
            for (uint32_t k = 0; k < 2; k++) {
                aabb child = b->nodes[node->first + k].bounds;
                cr_assert(contains(node->bounds, child), "node %u does not contain child %u", i, node->first + k);
                below = aabb_grow(below, child);
            }
            stack[top] = node->first + 1;
            stack_depth[top++] = depth + 1;
            stack[top] = node->first;
            stack_depth[top++] = depth + 1;
        } else {
            cr_assert(node->count >= 1 && node->count <= BVH_LEAF_MAX, "leaf %u has %u primitives", i, node->count);
            cr_assert((uint64_t)node->first + node->count <= n, "leaf %u range out of prim_order", i);
            for (uint32_t k = node->first; k < node->first + node->count; k++) {
                cr_assert(!covered[k], "prim_order slot %u in two leaves", k);
                covered[k] = 1;
                aabb prim = boxes[b->prim_order[k]];
                cr_assert(contains(node->bounds, prim), "leaf %u does not contain primitive %u", i, b->prim_order[k]);
                below = aabb_grow(below, prim);
            }
        }
        /* tight: exactly the union of what is below */
        cr_assert(same_box(node->bounds, below), "node %u bounds are not the union of its contents", i);
    }
    cr_assert_eq(visits, b->node_count, "%u of %u nodes reachable from the root", visits, b->node_count);
    for (uint32_t k = 0; k < n; k++)
        cr_assert(covered[k], "prim_order slot %u in no leaf", k);
    cr_assert_eq(b->depth, max_depth, "depth field %u, walked %u", b->depth, max_depth);
    free(stack_depth);
    free(stack);
    free(visited);
    free(covered);
    free(seen);
}

static void build(bvh *b, const aabb *boxes, uint32_t n, int threads)
{
    tess_error err = {{0}};
    cr_assert(bvh_build(b, boxes, n, threads, &err), "bvh_build: %s", err.msg);
}

/* Build with every thread count; check each tree and that all are the same bytes.
 * Returns the single-thread tree (caller finishes it). */
static bvh check_all_thread_counts(const aabb *boxes, uint32_t n)
{
    bvh ref;
    build(&ref, boxes, n, thread_counts[0]);
    check_bvh(&ref, boxes, n);
    for (size_t t = 1; t < THREAD_VARIANTS; t++) {
        bvh other;
        build(&other, boxes, n, thread_counts[t]);
        int threads = thread_counts[t];
        cr_assert_eq(other.node_count, ref.node_count, "%d threads: %u nodes, 1 thread: %u", threads,
                     other.node_count, ref.node_count);
        cr_assert_eq(other.depth, ref.depth);
        cr_assert_eq(memcmp(other.nodes, ref.nodes, ref.node_count * sizeof *ref.nodes), 0,
                     "%d threads: nodes differ from 1 thread", threads);
        cr_assert_eq(memcmp(other.prim_order, ref.prim_order, n * sizeof *ref.prim_order), 0,
                     "%d threads: prim_order differs from 1 thread", threads);
        double a = bvh_sah_cost(&ref), c = bvh_sah_cost(&other);
        cr_assert(memcmp(&a, &c, sizeof a) == 0, "%d threads: SAH cost %.17g, 1 thread %.17g", threads, c, a);
        bvh_finish(&other);
    }
    return ref;
}

/* ---- a reference tree for SAH comparisons -------------------------------- */

/* Object-median split on the longest centroid axis down to leaves of 4: the
 * simple builder the SAH has to beat. Fills nodes in the bvh.h layout. */
typedef struct median_ctx {
    const aabb *boxes;
    uint32_t *order;
    bvh_node *nodes;
    uint32_t node_count;
    int axis;
} median_ctx;

static median_ctx *sort_ctx;

static float centre_on(const aabb *b, int axis) { return v3_get(b->lo, axis) + v3_get(b->hi, axis); }

static int by_centre(const void *pa, const void *pb)
{
    float a = centre_on(&sort_ctx->boxes[*(const uint32_t *)pa], sort_ctx->axis);
    float b = centre_on(&sort_ctx->boxes[*(const uint32_t *)pb], sort_ctx->axis);
    return a < b ? -1 : a > b;
}

static void median_build(median_ctx *c, uint32_t node, uint32_t begin, uint32_t end)
{
    aabb box = aabb_empty(), centres = aabb_empty();
    for (uint32_t i = begin; i < end; i++) {
        box = aabb_grow(box, c->boxes[c->order[i]]);
        centres = aabb_grow_point(centres, aabb_centre(c->boxes[c->order[i]]));
    }
    c->nodes[node].bounds = box;
    if (end - begin <= 4) {
        c->nodes[node].first = begin;
        c->nodes[node].count = end - begin;
        return;
    }
    vec3 e = v3_sub(centres.hi, centres.lo);
    c->axis = e.x >= e.y && e.x >= e.z ? 0 : e.y >= e.z ? 1 : 2;
    sort_ctx = c;
    qsort(c->order + begin, end - begin, sizeof *c->order, by_centre);
    uint32_t kids = c->node_count;
    c->node_count += 2;
    c->nodes[node].first = kids;
    c->nodes[node].count = 0;
    median_build(c, kids, begin, begin + (end - begin) / 2);
    median_build(c, kids + 1, begin + (end - begin) / 2, end);
}

static double median_tree_sah(const aabb *boxes, uint32_t n)
{
    median_ctx c = {boxes, malloc(n * sizeof(uint32_t)), malloc((2 * (size_t)n) * sizeof(bvh_node)), 1, 0};
    cr_assert(c.order && c.nodes);
    for (uint32_t i = 0; i < n; i++)
        c.order[i] = i;
    median_build(&c, 0, 0, n);
    bvh b = {c.nodes, c.node_count, c.order, n, 0};
    double cost = bvh_sah_cost(&b);
    free(c.nodes);
    free(c.order);
    return cost;
}

/* ---- tests: the tree ----------------------------------------------------- */

Test(bvh, empty_input_gives_empty_bvh)
{
    bvh b;
    memset(&b, 0xab, sizeof b); /* the builder must clear every field */
    build(&b, NULL, 0, 4);
    check_bvh(&b, NULL, 0);
    cr_assert_null(b.prim_order);
    cr_assert_eq(b.depth, 0);
    cr_assert_eq(bvh_bytes(&b), 0);
    cr_assert_eq(bvh_sah_cost(&b), 0.0);
    bvh_finish(&b);
    bvh_finish(NULL);
}

Test(bvh, one_primitive_is_a_leaf_root)
{
    aabb box = {v3(1.f, 2.f, 3.f), v3(4.f, 5.f, 6.f)};
    bvh b = check_all_thread_counts(&box, 1);
    cr_assert_eq(b.node_count, 1);
    cr_assert_eq(b.nodes[0].count, 1);
    cr_assert_eq(b.depth, 1);
    cr_assert(same_box(b.nodes[0].bounds, box));
    bvh_finish(&b);
}

Test(bvh, two_touching_primitives_share_one_leaf)
{
    /* a leaf of 1..4 primitives costs one block: splitting neighbours saves nothing */
    aabb boxes[2] = {{v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f)}, {v3(1.f, 0.f, 0.f), v3(2.f, 1.f, 1.f)}};
    bvh b = check_all_thread_counts(boxes, 2);
    cr_assert_eq(b.node_count, 1);
    cr_assert_eq(b.nodes[0].count, 2);
    bvh_finish(&b);
}

Test(bvh, two_distant_primitives)
{
    aabb boxes[2] = {{v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f)}, {v3(100.f, 0.f, 0.f), v3(101.f, 1.f, 1.f)}};
    bvh b = check_all_thread_counts(boxes, 2);
    bvh_finish(&b);
}

Test(bvh, nine_primitives_split_above_the_leaf_limit)
{
    aabb *boxes = same_centroid_boxes(9, 7); /* even without an SAH split */
    bvh b = check_all_thread_counts(boxes, 9);
    cr_assert_eq(b.nodes[0].count, 0, "9 > BVH_LEAF_DEFAULT primitives in the root leaf");
    bvh_finish(&b);
    free(boxes);
    boxes = random_boxes(9, 8);
    b = check_all_thread_counts(boxes, 9);
    cr_assert_eq(b.nodes[0].count, 0);
    bvh_finish(&b);
    free(boxes);
}

Test(bvh, random_boxes)
{
    for (uint32_t n = 3; n <= 40000; n = n * 5 + 1) {
        aabb *boxes = random_boxes(n, n);
        bvh b = check_all_thread_counts(boxes, n);
        bvh_finish(&b);
        free(boxes);
    }
}

Test(bvh, grid_of_equal_boxes)
{
    uint32_t side = 28, n = side * side * side; /* 21952: above the parallel threshold */
    aabb *boxes = grid_boxes(side);
    bvh b = check_all_thread_counts(boxes, n);
    /* a regular grid splits into regular halves: no leaf straddles more than it must */
    cr_assert(b.depth <= 20, "depth %u for a %u^3 grid", b.depth, side);
    bvh_finish(&b);
    free(boxes);
}

Test(bvh, identical_centroids_halve_by_count)
{
    uint32_t sizes[] = {100, 1000, 200000};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        uint32_t n = sizes[s];
        aabb *boxes = same_centroid_boxes(n, n);
        bvh b = check_all_thread_counts(boxes, n);
        /* halving gives a balanced tree: depth ceil(log2(n / 8)) + 1 at most */
        uint32_t bound = 1;
        for (uint32_t leaves = BVH_LEAF_DEFAULT; leaves < n; leaves *= 2)
            bound++;
        cr_assert(b.depth <= bound, "n %u: depth %u, halving gives at most %u", n, b.depth, bound);
        bvh_finish(&b);
        free(boxes);
    }
}

Test(bvh, zero_size_boxes)
{
    /* points, many of them repeated, some on a plane */
    uint32_t n = 30000;
    aabb *boxes = alloc_boxes(n);
    uint64_t seed = 99;
    for (uint32_t i = 0; i < n; i++) {
        vec3 p = rng_point(&seed, 10.f);
        if (i % 3 == 0)
            p = v3(floorf(p.x), floorf(p.y), 0.f);
        boxes[i] = (aabb){p, p};
    }
    bvh b = check_all_thread_counts(boxes, n);
    bvh_finish(&b);
    /* all at one point: the root has no area */
    for (uint32_t i = 0; i < n; i++)
        boxes[i] = (aabb){v3(5.f, 5.f, 5.f), v3(5.f, 5.f, 5.f)};
    b = check_all_thread_counts(boxes, n);
    cr_assert(bvh_sah_cost(&b) > 0.0);
    bvh_finish(&b);
    free(boxes);
}

Test(bvh, empty_boxes_among_real_ones)
{
    /* a geometry without primitives has an empty box (a top-level build can see one) */
    uint32_t n = 20000;
    aabb *boxes = random_boxes(n, 5);
    for (uint32_t i = 0; i < n; i += 7)
        boxes[i] = aabb_empty();
    bvh b = check_all_thread_counts(boxes, n);
    bvh_finish(&b);
    free(boxes);
}

Test(bvh, many_random_triangles_same_for_every_thread_count)
{
    uint32_t n = 300000;
    aabb *boxes = random_triangle_boxes(n, 2024);
    bvh b = check_all_thread_counts(boxes, n);
    bvh_finish(&b);
    free(boxes);
}

Test(bvh, sah_beats_object_median)
{
    uint32_t n = 50000;
    aabb *boxes = random_triangle_boxes(n, 77);
    /* clustered input, where the SAH matters most: 90 % squeezed into a corner
     * (the SAH build costs about 0.70 of the median tree here) */
    for (uint32_t i = 0; i < n; i++)
        if (i % 10 != 0) {
            boxes[i].lo = v3_scale(boxes[i].lo, 0.01f);
            boxes[i].hi = v3_scale(boxes[i].hi, 0.01f);
        }
    bvh b;
    build(&b, boxes, n, 2);
    double sah = bvh_sah_cost(&b), median = median_tree_sah(boxes, n);
    cr_assert(sah < 0.8 * median, "SAH cost %.3f, object median %.3f", sah, median);
    bvh_finish(&b);
    free(boxes);
}

Test(bvh, root_split_finds_the_gap_between_uneven_clusters)
{
    /* 2000 boxes spread over x in [0, 80] and 2000 packed into x in [99, 100]: the
     * SAH splits at the gap (a middle split at x = 50 would cost ~20 % more) */
    uint32_t n = 4000;
    aabb *boxes = alloc_boxes(n);
    uint64_t seed = 3;
    for (uint32_t i = 0; i < n; i++) {
        vec3 lo = rng_point(&seed, 9.f);
        lo.x = i % 2 ? 99.f + 0.5f * rng_unit(&seed) : 79.f * rng_unit(&seed);
        boxes[i] = (aabb){lo, v3_add(lo, v3(0.5f, 1.f, 1.f))};
    }
    bvh b = check_all_thread_counts(boxes, n);
    cr_assert_eq(b.nodes[0].count, 0);
    aabb left = b.nodes[b.nodes[0].first].bounds, right = b.nodes[b.nodes[0].first + 1].bounds;
    cr_assert(left.hi.x <= 80.f && right.lo.x >= 99.f, "root split at left.hi.x %g, right.lo.x %g, not at the gap",
              left.hi.x, right.lo.x);
    bvh_finish(&b);
    free(boxes);
}

/* bvh_sah_cost of a hand-made tree (the builder's constants are its own business). */
static double sah_of(bvh_node *nodes, uint32_t node_count)
{
    uint32_t order[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    bvh b = {nodes, node_count, order, 8, node_count > 1 ? 2 : 1};
    return bvh_sah_cost(&b);
}

Test(bvh, sah_cost_follows_the_model)
{
    aabb unit = {v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f)}, point = {v3(0.f, 0.f, 0.f), v3(0.f, 0.f, 0.f)};
    /* a root leaf: the intersection cost per started block of 4 */
    double block = sah_of((bvh_node[]){{unit, 0, 1}}, 1);
    cr_assert(block > 0.0);
    cr_assert_eq(sah_of((bvh_node[]){{unit, 0, 4}}, 1), block, "4 primitives are one block");
    cr_assert_eq(sah_of((bvh_node[]){{unit, 0, 5}}, 1), 2.0 * block, "5 primitives are two blocks");
    cr_assert_eq(sah_of((bvh_node[]){{unit, 0, 8}}, 1), 2.0 * block);
    /* an inner root over leaves without area: the traversal cost alone */
    double traversal = sah_of((bvh_node[]){{unit, 1, 0}, {point, 0, 1}, {point, 1, 1}}, 3);
    cr_assert(traversal > 0.0);
    /* a 2x1x1 root (half area 2 + 1 + 2 = 5) over two unit cubes (3 each) of 1 and
     * 5 primitives: traversal + 3/5 * 1 block + 3/5 * 2 blocks */
    bvh_node tree[3] = {
        {{v3(0.f, 0.f, 0.f), v3(2.f, 1.f, 1.f)}, 1, 0},
        {{v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f)}, 0, 1},
        {{v3(1.f, 0.f, 0.f), v3(2.f, 1.f, 1.f)}, 1, 5},
    };
    cr_assert_float_eq(sah_of(tree, 3), traversal + 0.6 * block + 1.2 * block, 1e-12);
}

Test(bvh, bytes_count_nodes_and_order)
{
    aabb *boxes = random_boxes(1000, 1);
    bvh b;
    build(&b, boxes, 1000, 1);
    cr_assert_eq(bvh_bytes(&b), b.node_count * sizeof(bvh_node) + 1000 * sizeof(uint32_t));
    bvh_finish(&b);
    cr_assert_null(b.nodes);
    free(boxes);
}

Test(bvh, too_many_primitives_is_an_error)
{
    /* refused before the boxes are read, so none are needed */
    bvh b;
    tess_error err = {{0}};
    cr_assert(!bvh_build(&b, NULL, 0x80000000u, 2, &err));
    cr_assert(strstr(err.msg, "too many primitives"), "message: %s", err.msg);
    cr_assert_null(b.nodes);
    cr_assert_null(b.prim_order);
    cr_assert_eq(b.node_count, 0);
}

/* Virtual memory this process maps now, in bytes (Linux). */
static size_t mapped_bytes(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    cr_assert_not_null(f);
    unsigned long pages = 0;
    cr_assert_eq(fscanf(f, "%lu", &pages), 1);
    fclose(f);
    return pages * 4096ul; /* statm counts 4 KiB pages on every Linux target we build for */
}

Test(bvh, out_of_memory_fails_cleanly_at_every_step)
{
#if defined(__SANITIZE_ADDRESS__)
    cr_skip_test("an address-space limit starves ASan's own allocator");
#endif
    /* Each try caps the address space a little higher, so allocations (and the
     * worker threads' stacks) fail at a different point until the build fits. */
    uint32_t n = 100000;
    aabb *boxes = random_triangle_boxes(n, 11);
    struct rlimit old;
    cr_assert_eq(getrlimit(RLIMIT_AS, &old), 0);
    /* measured before any build: malloc keeps freed memory for reuse */
    size_t base = mapped_bytes(), step = 512 * 1024;
    int failures = 0;
    bool built = false;
    bvh ref = {0};
    for (size_t extra = 0; !built && extra < ((size_t)512 << 20); extra += step) {
        struct rlimit cap = {base + extra, old.rlim_max};
        bvh b;
        tess_error err = {{0}};
        cr_assert_eq(setrlimit(RLIMIT_AS, &cap), 0);
        bool ok = bvh_build(&b, boxes, n, 3, &err);
        cr_assert_eq(setrlimit(RLIMIT_AS, &old), 0);
        if (!ok) {
            failures++;
            cr_assert(strstr(err.msg, "out of memory"), "message: %s", err.msg);
            cr_assert(!b.nodes && !b.prim_order && b.node_count == 0 && b.prim_count == 0);
            continue;
        }
        /* possibly with fewer threads than asked for: the same tree regardless */
        build(&ref, boxes, n, 3);
        cr_assert_eq(b.node_count, ref.node_count);
        cr_assert_eq(memcmp(b.nodes, ref.nodes, ref.node_count * sizeof *ref.nodes), 0);
        cr_assert_eq(memcmp(b.prim_order, ref.prim_order, n * sizeof *ref.prim_order), 0);
        bvh_finish(&b);
        built = true;
    }
    cr_assert(built, "never built within 512 MiB over %zu bytes", base);
    cr_assert(failures > 3, "only %d capped builds failed: the cap did not bite", failures);
    bvh_finish(&ref);
    free(boxes);
}

/* ---- tests: parallel loops ----------------------------------------------- */

typedef struct cover_ctx {
    atomic_uint *hits;  /* per index */
    atomic_uint calls;
    int threads;
    size_t grain;
    atomic_bool bad;    /* a chunk was malformed or a worker id out of range */
} cover_ctx;

static void cover_fn(void *ctx, size_t begin, size_t end, int worker)
{
    cover_ctx *c = ctx;
    if (worker < 0 || worker >= c->threads || end <= begin || end - begin > c->grain || begin % c->grain != 0)
        atomic_store(&c->bad, true);
    for (size_t i = begin; i < end; i++)
        atomic_fetch_add(&c->hits[i], 1);
    atomic_fetch_add(&c->calls, 1);
}

static void check_cover(parallel_pool *p, size_t count, size_t grain)
{
    cover_ctx c = {calloc(count + 1, sizeof(atomic_uint)), 0, parallel_pool_threads(p), grain ? grain : 1, false};
    cr_assert_not_null(c.hits);
    parallel_pool_for(p, count, grain, cover_fn, &c);
    cr_assert(!atomic_load(&c.bad), "malformed chunk or worker id (count %zu grain %zu)", count, grain);
    for (size_t i = 0; i < count; i++)
        cr_assert_eq(atomic_load(&c.hits[i]), 1, "index %zu run %u times", i, atomic_load(&c.hits[i]));
    size_t g = grain ? grain : 1;
    cr_assert_eq(atomic_load(&c.calls), (count + g - 1) / g);
    free(c.hits);
}

Test(parallel, every_index_once_with_valid_worker_ids)
{
    parallel_pool *p = parallel_pool_create(4);
    cr_assert_not_null(p);
    cr_assert_eq(parallel_pool_threads(p), 4);
    check_cover(p, 100003, 97);
    check_cover(p, 5, 1);
    check_cover(p, 1, 10);
    check_cover(p, 0, 10);
    check_cover(p, 1000, 0); /* grain 0 counts as 1 */
    parallel_pool_destroy(p);
}

Test(parallel, pool_survives_many_loops_and_idle_sleeps)
{
    parallel_pool *p = parallel_pool_create(3);
    cr_assert_not_null(p);
    for (int round = 0; round < 2000; round++) /* back to back: workers still spinning */
        check_cover(p, 64, 8);
    /* long enough that every worker has gone to sleep on the condition variable */
    nanosleep(&(struct timespec){0, 50 * 1000 * 1000}, NULL);
    check_cover(p, 10000, 100);
    nanosleep(&(struct timespec){0, 50 * 1000 * 1000}, NULL);
    check_cover(p, 3, 1);
    parallel_pool_destroy(p);
}

static void slow_fn(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    nanosleep(&(struct timespec){0, 2 * 1000 * 1000}, NULL);
    for (size_t i = begin; i < end; i++)
        ((char *)ctx)[i] = 1; /* plain writes: the loop's return must order them */
}

Test(parallel, returns_only_after_every_chunk_finished)
{
    parallel_pool *p = parallel_pool_create(4);
    cr_assert_not_null(p);
    for (int round = 0; round < 5; round++) {
        char done[16] = {0};
        parallel_pool_for(p, sizeof done, 1, slow_fn, done);
        for (size_t i = 0; i < sizeof done; i++)
            cr_assert(done[i], "round %d: chunk %zu still running after the loop returned", round, i);
    }
    parallel_pool_destroy(p);
}

typedef struct order_ctx {
    size_t next; /* the NULL pool runs on the caller alone: no atomics needed */
    bool in_order;
} order_ctx;

static void order_fn(void *ctx, size_t begin, size_t end, int worker)
{
    order_ctx *c = ctx;
    if (begin != c->next || worker != 0)
        c->in_order = false;
    c->next = end;
}

Test(parallel, null_pool_runs_chunks_in_order_on_the_caller)
{
    cr_assert_eq(parallel_pool_threads(NULL), 1);
    order_ctx c = {0, true};
    parallel_pool_for(NULL, 1000, 7, order_fn, &c);
    cr_assert(c.in_order);
    cr_assert_eq(c.next, 1000);
    parallel_pool_destroy(NULL);
}

Test(parallel, one_shot_loops)
{
    for (int threads = 0; threads <= 8; threads += 4) {
        cover_ctx c = {calloc(50001, sizeof(atomic_uint)), 0, threads > 1 ? threads : 1, 1000, false};
        cr_assert_not_null(c.hits);
        parallel_for(threads, 50000, 1000, cover_fn, &c);
        cr_assert(!atomic_load(&c.bad));
        for (size_t i = 0; i < 50000; i++)
            cr_assert_eq(atomic_load(&c.hits[i]), 1);
        free(c.hits);
    }
}

Test(bvh, leaves_of_one_primitive_for_an_instance_level)
{
    const uint32_t n = 3000;
    aabb *boxes = random_boxes(n, 77);
    for (int k = 0; k < 2; k++) {
        aabb *set = k == 0 ? boxes : same_centroid_boxes(n, 5); /* also where SAH finds no split */
        bvh one, two;
        tess_error err = {{0}};
        cr_assert(bvh_build_leaves(&one, set, n, 1, 1, &err), "%s", err.msg);
        cr_assert(bvh_build_leaves(&two, set, n, 2, 1, &err), "%s", err.msg);
        check_bvh(&one, set, n);
        uint32_t leaves = 0;
        for (uint32_t i = 0; i < one.node_count; i++)
            if (one.nodes[i].count) {
                cr_assert_eq(one.nodes[i].count, 1u, "node %u holds %u primitives", i, one.nodes[i].count);
                leaves++;
            }
        cr_assert_eq(leaves, n);
        cr_assert_eq(one.node_count, two.node_count);
        cr_assert(memcmp(one.nodes, two.nodes, one.node_count * sizeof *one.nodes) == 0, "threads change the tree");
        bvh_finish(&one);
        bvh_finish(&two);
        if (set != boxes)
            free(set);
    }
    bvh bad;
    tess_error err = {{0}};
    cr_assert_not(bvh_build_leaves(&bad, boxes, n, 1, 0, &err));
    cr_assert(strstr(err.msg, "leaves of 0 primitives"), "%s", err.msg);
    free(boxes);
}

/* Refitting only the stale nodes of an instance level (wbvh_mark_instances,
 * wbvh_refit_stale) gives the same nodes, bit for bit, as a full refit
 * after any mix of hiding, showing and moving instances, for leaves of one
 * instance (as accel builds them) and of several. */
Test(bvh, instance_level_partial_refit_equals_full)
{
    const uint32_t n = 2000;
    for (uint32_t leaf = 1; leaf <= 4; leaf += 3) {
        aabb *boxes = random_boxes(n, 91 + leaf);
        bvh binary;
        tess_error err = {{0}};
        cr_assert(bvh_build_leaves(&binary, boxes, n, 1, leaf, &err), "%s", err.msg);
        wbvh_instance *instances = calloc(n, sizeof *instances);
        atomic_uchar *hidden = calloc(n, sizeof *hidden);
        cr_assert(instances && hidden);
        wbvh part, full;
        cr_assert(wbvh_build_instances(&part, &binary, instances, hidden, &err), "%s", err.msg);
        cr_assert(wbvh_build_instances(&full, &binary, instances, hidden, &err), "%s", err.msg);
        bvh_finish(&binary);
        /* every instance's leaf node holds it */
        const wbvh_prim_block *blocks = part.blocks;
        for (uint32_t id = 0; id < n; id++) {
            const wbvh_node *node = &part.nodes[part.leaf_node[id]];
            bool found = false;
            for (int i = 0; i < WBVH_WIDTH; i++)
                for (uint32_t b = node->child[i]; node->leaf_blocks[i] && b < node->child[i] + node->leaf_blocks[i]; b++)
                    for (int lane = 0; lane < WBVH_BLOCK; lane++)
                        found |= blocks[b].prim_id[lane] == id;
            cr_assert(found, "instance %u is not in its leaf node %u", id, part.leaf_node[id]);
        }
        wbvh_refit_instances(&part, boxes);
        uint64_t seed = 5;
        for (int round = 0; round < 200; round++) {
            uint32_t first = (uint32_t)(rng_next(&seed) % n), count = 1 + (uint32_t)(rng_next(&seed) % 40);
            switch (rng_next(&seed) % 3) {
            case 0: /* hide or show a range */
            case 1: {
                bool hide = round % 5 != 4;
                for (uint32_t i = first; i < first + count && i < n; i++)
                    atomic_store(&hidden[i], hide);
                break;
            }
            case 2: /* move a range (one refit may follow several changes) */
                for (uint32_t i = first; i < first + count && i < n; i++) {
                    vec3 d = v3_sub(rng_point(&seed, 20.f), v3(10.f, 10.f, 10.f));
                    boxes[i] = (aabb){v3_add(boxes[i].lo, d), v3_add(boxes[i].hi, d)};
                }
                break;
            }
            wbvh_mark_instances(&part, first, count);
            if (round % 3 == 2)
                continue;
            wbvh_refit_stale(&part, boxes);
            wbvh_refit_instances(&full, boxes);
            cr_assert_eq(part.node_count, full.node_count);
            cr_assert(memcmp(part.nodes, full.nodes, part.node_count * sizeof *part.nodes) == 0,
                      "leaves of %u, round %d: the partial refit differs from the full one", leaf, round);
            for (uint32_t k = 0; k < part.node_count; k++)
                cr_assert_eq(part.stale[k], 0, "node %u left stale", k);
        }
        cr_assert_not(wbvh_refit_stale(&part, boxes), "nothing was stale");
        wbvh_finish(&part);
        wbvh_finish(&full);
        free(instances);
        free(hidden);
        free(boxes);
    }
}
