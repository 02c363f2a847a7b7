/* bvh.c - parallel binned-SAH BVH builder (Wald 2007), deterministic for any
 * thread count.
 *
 * Shape of the build:
 *  - Primitives become 32-byte refs (box + id) in one array that is partitioned
 *    in place, node by node; a node owns the contiguous range of its refs.
 *  - Top phase (threads > 1): nodes larger than the task size are split one at
 *    a time by every thread: data-parallel binning (each thread bins chunks into
 *    its own bins, then the bins are merged) and a parallel partition.
 *  - Subtree phase: the remaining ranges are built as independent subtrees, one
 *    thread each, largest first. (Wald, "Fast Construction of SAH BVHs on the
 *    Intel MIC Architecture", TVCG 2012, calls these horizontal and vertical
 *    parallelism.)
 *  - Node slots come from a shared pool in per-thread blocks, so where a node
 *    lands depends on scheduling; a final walk copies the tree into its canonical
 *    layout (bvh.h), each subtree task's part in parallel. With one thread the
 *    pool already is that layout and nothing is copied.
 *
 * Why the output is independent of the thread count: every node's work is a
 * function of the refs in its range, computed in a way that does not depend on
 * who computes it:
 *  - bounds and bins combine with min, max and integer sums, which are exact,
 *    so chunking and merge order cannot change them; the split choice is then a
 *    serial sweep over the merged bins;
 *  - the partition is one fixed algorithm on fixed BVH_PARTITION_BLOCK-ref
 *    blocks (classify a block's refs, swap the k-th misplaced right ref with the
 *    k-th misplaced left ref; then the same exchange across blocks), whatever
 *    thread runs which block or which swaps, and whether the node is split in
 *    the top phase or inside a subtree;
 *  - child ranges follow from the partition, node slots are renumbered by the
 *    final walk, and prim_order is read off the refs at the end.
 *
 * Memory: 32 bytes per primitive of refs, a node pool of 2n slots of which only
 * the used ones are touched, and per-thread scratch of O(n / 4096) words. */
#include "bvh.h"

#include <assert.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/parallel.h"
#include "engine/base/progress.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* Bins per axis: 16 is where Wald (2007) found SAH quality saturates for binned builds. */
#define BVH_BINS 16
/* Refs per block of the canonical in-place partition: 128 KiB, fits in L2. Part of
 * the output's definition (it fixes the order of refs within large nodes): changing
 * it changes prim_order, never the thread-count independence. */
#define BVH_PARTITION_BLOCK 4096u
/* Leaf primitives a subtree task places before telling the progress reporter:
 * one atomic add per this many, so the reporter costs nothing measurable. */
#define BVH_PROGRESS_GRAIN 4096
/* Misplaced pairs swapped per chunk of a parallel partition's exchange step. */
#define BVH_SWAP_GRAIN 16384u
/* Refs per chunk of parallel binning and bounds passes: a few tens of microseconds. */
#define BVH_SCAN_GRAIN 16384u
/* A node is split by all threads together only above this size (and above the
 * subtree task size); an input no larger builds on the caller alone. A node this
 * size takes ~0.2 ms on one thread, a parallel loop a few microseconds, and
 * starting a thread tens of microseconds. */
#define BVH_PARALLEL_NODE_MIN 8192u
/* Subtree tasks per thread the top phase aims for, so largest-first scheduling
 * balances to within a few percent. */
#define BVH_TASKS_PER_THREAD 8u
/* Node slots a thread claims from the shared pool at a time (even: slots go in pairs). */
#define BVH_NODE_BLOCK 512u
/* Ranges at least this long are binned into two bin sets (see bin_refs): below it
 * clearing and merging the second set costs more than it saves. */
#define BVH_BIN_TWO_SETS_MIN 64u

/* --- 4-lane vectors: SSE2 (the x86-64 baseline) or GCC vector extensions, same results ---
 * v4: floats; v4m: a lane mask; v4u: unsigned counts below 2^31. */

#if defined(__SSE2__)
typedef __m128 v4;
typedef __m128 v4m;
typedef __m128i v4u;
static inline v4 v4_load(const float *p) { return _mm_loadu_ps(p); }
static inline void v4_store(float *p, v4 a) { _mm_storeu_ps(p, a); }
static inline v4 v4_splat(float f) { return _mm_set1_ps(f); }
static inline v4 v4_add(v4 a, v4 b) { return _mm_add_ps(a, b); }
static inline v4 v4_sub(v4 a, v4 b) { return _mm_sub_ps(a, b); }
static inline v4 v4_mul(v4 a, v4 b) { return _mm_mul_ps(a, b); }
static inline v4 v4_div(v4 a, v4 b) { return _mm_div_ps(a, b); }
/* a < b ? a : b and a > b ? a : b per lane: a NaN in `a` yields b */
static inline v4 v4_min(v4 a, v4 b) { return _mm_min_ps(a, b); }
static inline v4 v4_max(v4 a, v4 b) { return _mm_max_ps(a, b); }
static inline v4m v4_lt(v4 a, v4 b) { return _mm_cmplt_ps(a, b); }
static inline v4m v4m_and(v4m a, v4m b) { return _mm_and_ps(a, b); }
static inline v4 v4_select(v4m m, v4 a, v4 b) { return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)); }
static inline v4m v4m_from_bool(bool b) { return _mm_castsi128_ps(_mm_set1_epi32(-(int32_t)b)); }
/* lanes x, y, z of p[0..3]; lane w zero (p[3] may hold anything) */
static inline v4 v4_load_xyz(const float *p)
{
    return _mm_and_ps(_mm_loadu_ps(p), _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)));
}
/* truncation toward zero of lanes already clamped to [0, BVH_BINS - 1] */
static inline void v4_to_int(v4 a, int32_t out[4]) { _mm_storeu_si128((__m128i *)out, _mm_cvttps_epi32(a)); }
/* (a.x, b.x, c.x, 0), (a.y, b.y, c.y, 0), (a.z, b.z, c.z, 0) from lanes x, y, z of a, b, c */
static inline void v4_transpose3(v4 a, v4 b, v4 c, v4 *x, v4 *y, v4 *z)
{
    v4 ab_lo = _mm_unpacklo_ps(a, b), ab_hi = _mm_unpackhi_ps(a, b); /* ax bx ay by | az bz aw bw */
    v4 c_lo = _mm_unpacklo_ps(c, _mm_setzero_ps()), c_hi = _mm_unpackhi_ps(c, _mm_setzero_ps());
    *x = _mm_movelh_ps(ab_lo, c_lo);
    *y = _mm_movehl_ps(c_lo, ab_lo);
    *z = _mm_movelh_ps(ab_hi, c_hi);
}
static inline v4u v4u_zero(void) { return _mm_setzero_si128(); }
static inline v4u v4u_load(const uint32_t *p) { return _mm_loadu_si128((const __m128i *)p); }
static inline v4u v4u_add(v4u a, v4u b) { return _mm_add_epi32(a, b); }
/* (n + (1 << shift) - 1) >> shift, as floats */
static inline v4 v4u_blocks(v4u n, int shift)
{
    return _mm_cvtepi32_ps(_mm_srli_epi32(_mm_add_epi32(n, _mm_set1_epi32((1 << shift) - 1)), shift));
}
#else
/* GCC/Clang vector extensions: any target; masks are all-ones lanes, as in SSE */
typedef float v4 __attribute__((vector_size(16)));
typedef int32_t v4m __attribute__((vector_size(16)));
typedef uint32_t v4u __attribute__((vector_size(16)));
static inline v4 v4_load(const float *p)
{
    v4 r;
    memcpy(&r, p, sizeof r);
    return r;
}
static inline void v4_store(float *p, v4 a) { memcpy(p, &a, sizeof a); }
static inline v4 v4_splat(float f) { return (v4){f, f, f, f}; }
static inline v4 v4_add(v4 a, v4 b) { return a + b; }
static inline v4 v4_sub(v4 a, v4 b) { return a - b; }
static inline v4 v4_mul(v4 a, v4 b) { return a * b; }
static inline v4 v4_div(v4 a, v4 b) { return a / b; }
static inline v4 v4_select(v4m m, v4 a, v4 b) { return (v4)((m & (v4m)a) | (~m & (v4m)b)); }
static inline v4 v4_min(v4 a, v4 b) { return v4_select(a < b, a, b); }
static inline v4 v4_max(v4 a, v4 b) { return v4_select(a > b, a, b); }
static inline v4m v4_lt(v4 a, v4 b) { return a < b; }
static inline v4m v4m_and(v4m a, v4m b) { return a & b; }
static inline v4m v4m_from_bool(bool b) { return (v4m){-(int32_t)b, -(int32_t)b, -(int32_t)b, -(int32_t)b}; }
static inline v4 v4_load_xyz(const float *p) { return (v4){p[0], p[1], p[2], 0.f}; }
static inline void v4_to_int(v4 a, int32_t out[4])
{
    v4m i = __builtin_convertvector(a, v4m);
    memcpy(out, &i, sizeof i);
}
static inline void v4_transpose3(v4 a, v4 b, v4 c, v4 *x, v4 *y, v4 *z)
{
    *x = (v4){a[0], b[0], c[0], 0.f};
    *y = (v4){a[1], b[1], c[1], 0.f};
    *z = (v4){a[2], b[2], c[2], 0.f};
}
static inline v4u v4u_zero(void) { return (v4u){0, 0, 0, 0}; }
static inline v4u v4u_load(const uint32_t *p)
{
    v4u r;
    memcpy(&r, p, sizeof r);
    return r;
}
static inline v4u v4u_add(v4u a, v4u b) { return a + b; }
static inline v4 v4u_blocks(v4u n, int shift)
{
    return __builtin_convertvector((v4m)((n + ((1u << shift) - 1)) >> shift), v4);
}
#endif

/* --- primitive refs, boxes, bins --- */

/* One primitive as the builder moves it: f[0..2] box min, f[3] the primitive id's
 * bits, f[4..6] box max, f[7] zero. Its "centroid" is min + max (twice the centre:
 * the factor cancels out of binning), one add away, so it is not stored. */
typedef struct prim_ref {
    float f[8];
} prim_ref;

static inline v4 ref_lo(const prim_ref *r) { return v4_load_xyz(r->f); }
static inline v4 ref_hi(const prim_ref *r) { return v4_load(r->f + 4); }
static inline v4 ref_centroid(const prim_ref *r) { return v4_add(ref_lo(r), ref_hi(r)); }
static inline uint32_t ref_id(const prim_ref *r)
{
    uint32_t id;
    memcpy(&id, &r->f[3], sizeof id);
    return id;
}

typedef struct box4 {
    v4 lo, hi; /* lane w unused; empty: lo = +inf, hi = -inf */
} box4;

static inline box4 box4_empty(void) { return (box4){v4_splat(INFINITY), v4_splat(-INFINITY)}; }
/* Grow by a box or point; the new value goes first so a NaN in it is ignored. */
static inline box4 box4_grow(box4 b, v4 lo, v4 hi) { return (box4){v4_min(lo, b.lo), v4_max(hi, b.hi)}; }
static inline box4 box4_merge(box4 a, box4 b) { return box4_grow(a, b.lo, b.hi); }

/* Half the surface area, as aabb_half_area (same operations, same bits). */
static float box4_half_area(box4 b)
{
    float lo[4], hi[4];
    v4_store(lo, b.lo);
    v4_store(hi, b.hi);
    if (!(lo[0] <= hi[0]))
        return 0.f;
    float ex = hi[0] - lo[0], ey = hi[1] - lo[1], ez = hi[2] - lo[2];
    return ex * ey + ey * ez + ez * ex;
}

/* Half areas of three non-empty boxes in lanes 0..2, each with box4_half_area's
 * operations (an empty box gives garbage: callers skip sides without refs). */
static inline v4 box4_half_areas3(const box4 b[3])
{
    v4 ex, ey, ez;
    v4_transpose3(v4_sub(b[0].hi, b[0].lo), v4_sub(b[1].hi, b[1].lo), v4_sub(b[2].hi, b[2].lo), &ex, &ey, &ez);
    return v4_add(v4_add(v4_mul(ex, ey), v4_mul(ey, ez)), v4_mul(ez, ex));
}

static aabb box4_to_aabb(box4 b)
{
    float lo[4], hi[4];
    v4_store(lo, b.lo);
    v4_store(hi, b.hi);
    return (aabb){v3(lo[0], lo[1], lo[2]), v3(hi[0], hi[1], hi[2])};
}

/* Two boxes accumulated per worker in parallel passes; 64 bytes, one cache line. */
typedef struct box_pair {
    box4 a, b;
} box_pair;

static box_pair box_pair_empty(void) { return (box_pair){box4_empty(), box4_empty()}; }

/* The centroid-to-bin map of one node: bin = clamp((c - lo) * scale, 0, BINS-1)
 * per axis, truncated. Binning and partitioning both call bin_ids, so a ref's bin
 * is the same in both (the same IEEE operations in the same order). */
typedef struct bin_map {
    v4 lo;    /* centroid box min */
    v4 scale; /* BINS (1 - 1e-6) / extent, or 0 on an axis without extent */
} bin_map;

static inline void bin_ids(v4 centroid, const bin_map *m, int32_t out[4])
{
    v4 f = v4_mul(v4_sub(centroid, m->lo), m->scale);
    f = v4_max(f, v4_splat(0.f)); /* NaN (empty or infinite box) -> bin 0 */
    f = v4_min(f, v4_splat((float)(BVH_BINS - 1)));
    v4_to_int(f, out);
}

static bin_map bin_map_make(box4 centroids)
{
    float lo[4], hi[4], scale[4] = {0.f, 0.f, 0.f, 0.f};
    v4_store(lo, centroids.lo);
    v4_store(hi, centroids.hi);
    for (int axis = 0; axis < 3; axis++)
        if (hi[axis] > lo[axis])
            /* maps [lo, hi] to [0, BINS) with the top value landing in the last bin */
            scale[axis] = (float)BVH_BINS * (1.f - 1e-6f) / (hi[axis] - lo[axis]);
    return (bin_map){centroids.lo, v4_load(scale)};
}

typedef struct bin_set {
    box4 box[BVH_BINS][3];       /* [bin][axis]: the sweep reads one bin of all axes at once */
    uint32_t count[BVH_BINS][4]; /* [bin][axis]; [bin][3] stays 0 (a v4u lane) */
} bin_set;

static void bin_set_clear(bin_set *s)
{
    for (int b = 0; b < BVH_BINS; b++)
        for (int axis = 0; axis < 3; axis++)
            s->box[b][axis] = box4_empty();
    memset(s->count, 0, sizeof s->count);
}

static void bin_set_merge(bin_set *into, const bin_set *from)
{
    for (int b = 0; b < BVH_BINS; b++)
        for (int axis = 0; axis < 3; axis++) {
            into->box[b][axis] = box4_merge(into->box[b][axis], from->box[b][axis]);
            into->count[b][axis] += from->count[b][axis];
        }
}

static inline void bin_ref(const prim_ref *r, const bin_map *m, bin_set *s)
{
    v4 lo = ref_lo(r), hi = ref_hi(r);
    int32_t b[4];
    bin_ids(v4_add(lo, hi), m, b);
    /* written out: GCC -O2 does not unroll the three-axis loop */
    s->box[b[0]][0] = box4_grow(s->box[b[0]][0], lo, hi);
    s->box[b[1]][1] = box4_grow(s->box[b[1]][1], lo, hi);
    s->box[b[2]][2] = box4_grow(s->box[b[2]][2], lo, hi);
    s->count[b[0]][0]++;
    s->count[b[1]][1]++;
    s->count[b[2]][2]++;
}

/* Bin refs[begin, end) into s (which holds earlier results). Consecutive refs of
 * a coherent mesh often share a bin, and each update of a bin waits for the
 * previous one to come back from the store buffer; alternating between two bin
 * sets halves that chain. */
static void bin_refs(const prim_ref *refs, size_t begin, size_t end, const bin_map *m, bin_set *s)
{
    size_t i = begin;
    if (end - begin >= BVH_BIN_TWO_SETS_MIN) {
        bin_set other;
        bin_set_clear(&other);
        for (; i + 2 <= end; i += 2) {
            bin_ref(&refs[i], m, s);
            bin_ref(&refs[i + 1], m, &other);
        }
        bin_set_merge(s, &other);
    }
    for (; i < end; i++)
        bin_ref(&refs[i], m, s);
}

/* --- split choice --- */

static inline float leaf_blocks_of(uint32_t n, unsigned block_log2)
{
    return (float)((n + (1u << block_log2) - 1) >> block_log2);
}

typedef struct split {
    int axis;            /* -1: no split with primitives on both sides */
    int bin;             /* refs in bins [0, bin] on `axis` go left */
    float cost;          /* SAH cost of the split, relative to the parent's area */
    uint32_t left_count;
    box4 left, right;    /* bounds of the two sides */
} split;

/* Best SAH split over the bins of every axis with centroid extent (Wald 2007, §3):
 * the three axes sweep side by side in lanes 0..2. An axis without extent has all
 * its refs in bin 0 and so no candidate. Ties go to the lowest axis, then the
 * lowest bin. */
static split find_split(const bin_set *s, float parent_half_area, unsigned block_log2)
{
    /* sweep from the right: area and blocks of bins (b, BINS) per axis */
    v4 right_area[BVH_BINS], right_blocks[BVH_BINS];
    box4 acc[3] = {box4_empty(), box4_empty(), box4_empty()};
    v4u n = v4u_zero();
    for (int b = BVH_BINS - 1; b > 0; b--) {
        for (int axis = 0; axis < 3; axis++)
            acc[axis] = box4_merge(acc[axis], s->box[b][axis]);
        n = v4u_add(n, v4u_load(s->count[b]));
        right_area[b - 1] = box4_half_areas3(acc);
        right_blocks[b - 1] = v4u_blocks(n, block_log2);
    }
    v4 zero = v4_splat(0.f), traversal = v4_splat(BVH_COST_TRAVERSAL), intersect = v4_splat(BVH_COST_INTERSECT);
    v4 parent = v4_splat(parent_half_area);
    v4 best_cost = v4_splat(INFINITY), best_bin = zero; /* bins as floats, so they select like costs */
    acc[0] = acc[1] = acc[2] = box4_empty();
    n = v4u_zero();
    for (int b = 0; b < BVH_BINS - 1; b++) {
        for (int axis = 0; axis < 3; axis++)
            acc[axis] = box4_merge(acc[axis], s->box[b][axis]);
        n = v4u_add(n, v4u_load(s->count[b]));
        v4 left_blocks = v4u_blocks(n, block_log2);
        /* traversal + intersect * (A_l * blocks_l + A_r * blocks_r) / A_parent */
        v4 sides = v4_add(v4_mul(box4_half_areas3(acc), left_blocks), v4_mul(right_area[b], right_blocks[b]));
        v4 cost = v4_add(traversal, v4_div(v4_mul(intersect, sides), parent));
        /* both sides hold refs (lane 3 never does), and strictly better */
        v4m take = v4m_and(v4m_and(v4_lt(zero, left_blocks), v4_lt(zero, right_blocks[b])), v4_lt(cost, best_cost));
        best_cost = v4_select(take, cost, best_cost);
        best_bin = v4_select(take, v4_splat((float)b), best_bin);
    }
    float cost[4], bin[4];
    v4_store(cost, best_cost);
    v4_store(bin, best_bin);
    split best = {.axis = -1, .cost = INFINITY};
    for (int axis = 0; axis < 3; axis++)
        if (cost[axis] < best.cost) {
            best.axis = axis;
            best.bin = (int)bin[axis];
            best.cost = cost[axis];
        }
    if (best.axis >= 0) {
        best.left = best.right = box4_empty();
        best.left_count = 0;
        for (int b = 0; b < BVH_BINS; b++) {
            if (b <= best.bin) {
                best.left = box4_merge(best.left, s->box[b][best.axis]);
                best.left_count += s->count[b][best.axis];
            } else
                best.right = box4_merge(best.right, s->box[b][best.axis]);
        }
    }
    return best;
}

/* --- the builder --- */

/* A node whose slot is allocated and whose range is known, waiting to be split. */
typedef struct build_item {
    uint32_t node;         /* slot in builder.pool */
    uint32_t begin, end;   /* its refs: refs[begin, end) */
    uint32_t depth;        /* root = 1 */
    box4 bounds;           /* of its primitives */
    box4 centroids;        /* of its refs' centroids */
} build_item;

/* Per-thread state, written only by its own thread (index = parallel worker id). */
typedef struct worker_state {
    uint32_t slot_next, slot_end; /* this thread's unused node slots [next, end) of the pool */
    uint32_t depth;               /* deepest node this thread made */
    uint32_t inner_count;         /* inner nodes this thread made */
    uint32_t *scratch;            /* 5 * (max_blocks + 1) words for partition_range */
    char pad[40];                 /* 64 bytes: threads' states share few cache lines */
} worker_state;

/* One build's state, shared by its threads without locks: the caller writes the
 * fields between parallel loops (a loop's start and return order those writes);
 * inside a loop a thread writes only its own workers[] / bins[] / acc[] entry, the
 * refs of ranges it owns, node slots it claimed, and the atomic pool_top. */
typedef struct builder {
    prim_ref *refs;         /* count refs, partitioned in place */
    bvh_node *pool;         /* node slots in scheduling order; pool_capacity of them */
    uint32_t pool_capacity;
    atomic_uint pool_top;   /* first slot no thread has claimed (claims are BVH_NODE_BLOCK slots) */
    uint32_t max_blocks;    /* partition blocks of the largest range, the root */
    parallel_pool *threads; /* NULL: everything runs on the caller */
    int thread_count;       /* parallel_pool_threads(threads) */
    worker_state *workers;  /* thread_count */
    bin_set *bins;          /* thread_count: each thread's bins in top-phase binning */
    box_pair *acc;          /* thread_count: each thread's boxes in top-phase reductions */
    uint32_t task_size;     /* top phase splits nodes above this with all threads */
    build_item *tasks;      /* subtree tasks the top phase left; task_count of task_capacity */
    size_t task_count, task_capacity;
    uint32_t *task_inner;   /* per task: inner nodes its subtree got */
    uint32_t *task_at;      /* per task: its root's index in the final layout */
    uint32_t *task_next;    /* per task: first final index of its root's descendants */
    bvh_node *out_nodes;    /* the canonical layout being written */
    uint32_t leaf_max;      /* most primitives in a leaf, 1..BVH_LEAF_MAX */
    unsigned block_log2;    /* leaves are tested 2^this primitives at a time (the SAH's leaf cost) */
    progress *progress;     /* told the primitives placed in leaves; never read back by the build */
} builder;

static uint32_t alloc_pair(builder *B, worker_state *w)
{
    if (w->slot_next == w->slot_end) {
        uint32_t start = atomic_fetch_add_explicit(&B->pool_top, BVH_NODE_BLOCK, memory_order_relaxed);
        assert((uint64_t)start + BVH_NODE_BLOCK <= B->pool_capacity);
        w->slot_next = start;
        w->slot_end = start + BVH_NODE_BLOCK;
    }
    uint32_t slot = w->slot_next;
    w->slot_next += 2;
    return slot;
}

/* Parallel passes. Each takes a NULL pool to run serially on the calling thread,
 * then with one accumulator; with the builder's pool, one accumulator per thread. */

typedef struct bin_job {
    const prim_ref *refs;
    size_t begin;
    const bin_map *map;
    bin_set *bins; /* per worker */
} bin_job;

static void bin_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    bin_job *j = ctx;
    bin_refs(j->refs, j->begin + begin, j->begin + end, j->map, &j->bins[worker]);
}

static void bin_range(builder *B, parallel_pool *pool, const build_item *it, const bin_map *m, bin_set *out)
{
    bin_set_clear(out);
    if (!pool) {
        bin_refs(B->refs, it->begin, it->end, m, out);
        return;
    }
    for (int t = 0; t < B->thread_count; t++)
        bin_set_clear(&B->bins[t]);
    bin_job job = {B->refs, it->begin, m, B->bins};
    parallel_pool_for(pool, it->end - it->begin, BVH_SCAN_GRAIN, bin_chunk, &job);
    for (int t = 0; t < B->thread_count; t++)
        bin_set_merge(out, &B->bins[t]);
}

typedef struct bounds_job {
    const prim_ref *refs;
    size_t begin;
    box_pair *acc; /* per worker: a = bounds, b = centroid bounds */
} bounds_job;

static void bounds_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    bounds_job *j = ctx;
    box_pair acc = j->acc[worker];
    for (size_t i = j->begin + begin; i < j->begin + end; i++) {
        v4 lo = ref_lo(&j->refs[i]), hi = ref_hi(&j->refs[i]), c = v4_add(lo, hi);
        acc.a = box4_grow(acc.a, lo, hi);
        acc.b = box4_grow(acc.b, c, c);
    }
    j->acc[worker] = acc;
}

/* Bounds and centroid bounds of refs[begin, end). */
static box_pair range_bounds(builder *B, parallel_pool *pool, uint32_t begin, uint32_t end)
{
    box_pair local = box_pair_empty(), *acc = pool ? B->acc : &local;
    int n = pool ? B->thread_count : 1;
    for (int t = 0; t < n; t++)
        acc[t] = box_pair_empty();
    bounds_job job = {B->refs, begin, acc};
    parallel_pool_for(pool, end - begin, BVH_SCAN_GRAIN, bounds_chunk, &job);
    box_pair r = box_pair_empty();
    for (int t = 0; t < n; t++) {
        r.a = box4_merge(r.a, acc[t].a);
        r.b = box4_merge(r.b, acc[t].b);
    }
    return r;
}

/* A split as the partition applies it: refs whose bin on `axis` is at most
 * last_left_bin go left. */
typedef struct side_rule {
    bin_map map;
    int axis;
    int32_t last_left_bin;
} side_rule;

/* Whether a ref goes left; grows that side's centroid box in acc (a: left, b: right)
 * without a branch on the side, which is unpredictable. */
static inline bool classify(const prim_ref *r, const side_rule *rule, box_pair *acc)
{
    v4 c = ref_centroid(r);
    int32_t b[4];
    bin_ids(c, &rule->map, b);
    bool left = b[rule->axis] <= rule->last_left_bin;
    /* c + inf = inf and c - inf = -inf leave a box alone; c + 0 = c (or +0 for -0) */
    v4m m = v4m_from_bool(left);
    v4 inf = v4_splat(INFINITY), zero = v4_splat(0.f);
    v4 off_left = v4_select(m, zero, inf), off_right = v4_select(m, inf, zero);
    acc->a = box4_grow(acc->a, v4_add(c, off_left), v4_sub(c, off_left));
    acc->b = box4_grow(acc->b, v4_add(c, off_right), v4_sub(c, off_right));
    return left;
}

static inline uint64_t low_bits(uint32_t n) { return n >= 64 ? ~0ull : (1ull << n) - 1; }

/* Partition refs[begin, end) (at most BVH_PARTITION_BLOCK): classify every ref,
 * then swap the k-th right ref among the first `left count` positions with the
 * k-th left ref after them (the exchange BlockQuicksort uses to avoid branch
 * misses: Edelkamp & Weiss, ESA 2016). Returns the left count. */
static uint32_t partition_block(prim_ref *refs, uint32_t begin, uint32_t end, const side_rule *rule, box_pair *acc)
{
    uint64_t left_bits[BVH_PARTITION_BLOCK / 64]; /* bit i: ref begin + i goes left */
    uint32_t n = end - begin, words = (n + 63) / 64, left_count = 0;
    assert(n <= BVH_PARTITION_BLOCK);
    left_bits[0] = 0; /* read below even when n == 0 */
    box_pair a = *acc;
    for (uint32_t w = 0; w < words; w++) {
        uint32_t in_word = n - 64 * w < 64 ? n - 64 * w : 64;
        const prim_ref *r = refs + begin + 64 * w;
        uint64_t bits = 0;
        for (uint32_t k = 0; k < in_word; k++)
            bits |= (uint64_t)classify(&r[k], rule, &a) << k;
        left_bits[w] = bits;
        left_count += (uint32_t)__builtin_popcountll(bits);
    }
    *acc = a;
    /* misplaced: right refs (0 bits) below left_count, left refs (1 bits) from it on */
    uint32_t wa = 0, wb = left_count / 64;
    uint64_t ma = ~left_bits[0] & low_bits(left_count);
    uint64_t mb = wb < words ? left_bits[wb] & ~low_bits(left_count - 64 * wb) : 0;
    for (;;) {
        while (ma == 0) {
            if (64 * ++wa >= left_count)
                return left_count;
            ma = ~left_bits[wa] & low_bits(left_count - 64 * wa);
        }
        while (mb == 0) {
            assert(wb + 1 < words); /* as many misplaced lefts as rights */
            mb = left_bits[++wb];
        }
        prim_ref *x = &refs[begin + 64 * wa + (uint32_t)__builtin_ctzll(ma)];
        prim_ref *y = &refs[begin + 64 * wb + (uint32_t)__builtin_ctzll(mb)];
        prim_ref t = *x;
        *x = *y;
        *y = t;
        ma &= ma - 1;
        mb &= mb - 1;
    }
}

typedef struct partition_job {
    prim_ref *refs;
    uint32_t begin, end;
    const side_rule *rule;
    uint32_t *left_count; /* per block */
    box_pair *acc;        /* per worker */
} partition_job;

static void partition_chunk(void *ctx, size_t block_begin, size_t block_end, int worker)
{
    partition_job *j = ctx;
    for (size_t k = block_begin; k < block_end; k++) {
        uint32_t b = j->begin + (uint32_t)k * BVH_PARTITION_BLOCK;
        uint32_t e = j->end - b > BVH_PARTITION_BLOCK ? b + BVH_PARTITION_BLOCK : j->end;
        j->left_count[k] = partition_block(j->refs, b, e, j->rule, &j->acc[worker]);
    }
}

/* Misplaced refs after the per-block partitions, as runs in position order:
 * run r covers [start[r], start[r] + (prefix[r + 1] - prefix[r])). */
typedef struct run_list {
    uint32_t *start;
    uint32_t *prefix; /* runs + 1 entries; prefix[runs] = total */
    uint32_t runs;
} run_list;

static void run_add(run_list *l, uint32_t begin, uint32_t end)
{
    if (begin >= end)
        return;
    l->start[l->runs] = begin;
    l->prefix[l->runs + 1] = l->prefix[l->runs] + (end - begin);
    l->runs++;
}

/* The position of the k-th ref of a run list (k < total). */
static void run_seek(const run_list *l, uint32_t k, uint32_t *run, uint32_t *pos)
{
    uint32_t lo = 0, hi = l->runs; /* the run r with prefix[r] <= k < prefix[r + 1] */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (l->prefix[mid] <= k)
            lo = mid;
        else
            hi = mid;
    }
    *run = lo;
    *pos = l->start[lo] + (k - l->prefix[lo]);
}

typedef struct swap_job {
    prim_ref *refs;
    const run_list *right_in_left; /* right refs left of the final split position */
    const run_list *left_in_right; /* left refs right of it */
} swap_job;

static void swap_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    swap_job *j = ctx;
    uint32_t ra, pa, rb, pb;
    run_seek(j->right_in_left, (uint32_t)begin, &ra, &pa);
    run_seek(j->left_in_right, (uint32_t)begin, &rb, &pb);
    for (size_t k = begin; k < end; k++) {
        /* step into the next run when this one is used up */
        if (k == j->right_in_left->prefix[ra + 1]) {
            ra++;
            pa = j->right_in_left->start[ra];
        }
        if (k == j->left_in_right->prefix[rb + 1]) {
            rb++;
            pb = j->left_in_right->start[rb];
        }
        prim_ref t = j->refs[pa];
        j->refs[pa++] = j->refs[pb];
        j->refs[pb++] = t;
    }
}

/* The canonical in-place partition of refs[begin, end) (see the top of the file).
 * Fills the centroid boxes of the left (a) and right (b) sides; returns the left
 * count. `scratch` holds 5 * (blocks + 1) words. */
static uint32_t partition_range(builder *B, parallel_pool *pool, uint32_t begin, uint32_t end, const side_rule *rule,
                                uint32_t *scratch, box_pair *centroids)
{
    box_pair local = box_pair_empty(), *acc = pool ? B->acc : &local;
    int acc_count = pool ? B->thread_count : 1;
    for (int t = 0; t < acc_count; t++)
        acc[t] = box_pair_empty();
    uint32_t blocks = (end - begin + BVH_PARTITION_BLOCK - 1) / BVH_PARTITION_BLOCK;
    assert(blocks <= B->max_blocks);
    uint32_t *left_count = scratch;
    partition_job job = {B->refs, begin, end, rule, left_count, acc};
    parallel_pool_for(pool, blocks, 1, partition_chunk, &job);
    *centroids = box_pair_empty();
    for (int t = 0; t < acc_count; t++) {
        centroids->a = box4_merge(centroids->a, acc[t].a);
        centroids->b = box4_merge(centroids->b, acc[t].b);
    }
    if (blocks == 1)
        return left_count[0];

    uint32_t left_total = 0;
    for (uint32_t k = 0; k < blocks; k++)
        left_total += left_count[k];
    uint32_t mid = begin + left_total;
    uint32_t stride = B->max_blocks + 1;
    run_list right_in_left = {scratch + stride, scratch + 2 * stride, 0};
    run_list left_in_right = {scratch + 3 * stride, scratch + 4 * stride, 0};
    right_in_left.prefix[0] = left_in_right.prefix[0] = 0;
    for (uint32_t k = 0; k < blocks; k++) {
        uint32_t b = begin + k * BVH_PARTITION_BLOCK;
        uint32_t e = end - b > BVH_PARTITION_BLOCK ? b + BVH_PARTITION_BLOCK : end;
        uint32_t split_at = b + left_count[k]; /* block k: lefts [b, split_at), rights [split_at, e) */
        if (split_at < mid)
            run_add(&right_in_left, split_at, e < mid ? e : mid);
        if (e > mid)
            run_add(&left_in_right, b > mid ? b : mid, split_at);
    }
    uint32_t misplaced = right_in_left.prefix[right_in_left.runs];
    assert(misplaced == left_in_right.prefix[left_in_right.runs]);
    swap_job swaps = {B->refs, &right_in_left, &left_in_right};
    parallel_pool_for(pool, misplaced, BVH_SWAP_GRAIN, swap_chunk, &swaps);
    return left_total;
}

/* Split one node: write its bounds, then either make it a leaf (returns false) or
 * partition its range and fill the two child items (returns true). With a pool,
 * every pass runs on all threads; without, on the calling thread `w`. */
static bool split_node(builder *B, parallel_pool *pool, worker_state *w, const build_item *it, build_item kids[2])
{
    bvh_node *node = &B->pool[it->node];
    node->bounds = box4_to_aabb(it->bounds);
    if (it->depth > w->depth)
        w->depth = it->depth;
    uint32_t n = it->end - it->begin;
    uint32_t mid = it->begin;
    box4 left = box4_empty(), right = box4_empty();
    box_pair centroids = box_pair_empty();
    /* Up to one block, a leaf costs BVH_COST_INTERSECT and any split at least
     * BVH_COST_TRAVERSAL: when that is no less, the leaf wins without binning. */
    bool leaf_wins = n <= (1u << B->block_log2) && n <= B->leaf_max && BVH_COST_TRAVERSAL >= BVH_COST_INTERSECT;
    if (n > 1 && !leaf_wins && it->depth < BVH_SAH_DEPTH_LIMIT) {
        bin_map map = bin_map_make(it->centroids);
        bin_set local_bins;
        bin_range(B, pool, it, &map, &local_bins);
        split s = find_split(&local_bins, box4_half_area(it->bounds), B->block_log2);
        float leaf_cost = BVH_COST_INTERSECT * leaf_blocks_of(n, B->block_log2);
        if (s.axis >= 0 && (n > B->leaf_max || s.cost < leaf_cost)) {
            side_rule rule = {map, s.axis, s.bin};
            uint32_t left_count = partition_range(B, pool, it->begin, it->end, &rule, w->scratch, &centroids);
            assert(left_count == s.left_count);
            mid = it->begin + left_count;
            left = s.left;
            right = s.right;
        }
    }
    /* no useful SAH split (coincident centroids, or too deep): halve by count if too big */
    if (mid == it->begin && n > B->leaf_max) {
        mid = it->begin + n / 2;
        box_pair l = range_bounds(B, pool, it->begin, mid), r = range_bounds(B, pool, mid, it->end);
        left = l.a;
        right = r.a;
        centroids = (box_pair){l.b, r.b};
    }
    if (mid == it->begin) {
        node->first = it->begin;
        node->count = n;
        return false;
    }
    uint32_t slot = alloc_pair(B, w);
    w->inner_count++;
    node->first = slot;
    node->count = 0;
    kids[0] = (build_item){slot, it->begin, mid, it->depth + 1, left, centroids.a};
    kids[1] = (build_item){slot + 1, mid, it->end, it->depth + 1, right, centroids.b};
    return true;
}

/* Build a whole subtree on the calling thread, depth first (so with one thread
 * the pool fills in the canonical layout). Returns the inner nodes it made. */
static uint32_t build_subtree(builder *B, worker_state *w, const build_item *root)
{
    build_item stack[BVH_MAX_DEPTH + 1]; /* one pending right sibling per level */
    int top = 0;
    uint32_t inner = 0;
    uint32_t placed = 0; /* leaf primitives not yet told to B->progress */
    stack[top++] = *root;
    while (top > 0) {
        build_item it = stack[--top];
        build_item kids[2];
        if (split_node(B, NULL, w, &it, kids)) {
            inner++;
            assert(top + 2 <= BVH_MAX_DEPTH + 1);
            stack[top++] = kids[1];
            stack[top++] = kids[0];
        } else if ((placed += it.end - it.begin) >= BVH_PROGRESS_GRAIN) {
            progress_add(B->progress, placed);
            placed = 0;
        }
    }
    progress_add(B->progress, placed);
    return inner;
}

static void subtree_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    builder *B = ctx;
    for (size_t t = begin; t < end; t++)
        B->task_inner[t] = build_subtree(B, &B->workers[worker], &B->tasks[t]);
}

static bool add_task(builder *B, const build_item *it)
{
    if (B->task_count == B->task_capacity) {
        size_t cap = B->task_capacity ? 2 * B->task_capacity : 64;
        build_item *t = realloc(B->tasks, cap * sizeof *t);
        if (!t)
            return false;
        B->tasks = t;
        B->task_capacity = cap;
    }
    B->tasks[B->task_count++] = *it;
    return true;
}

/* Largest first, so the last tasks to start are small (ties: range order). */
static int task_order(const void *pa, const void *pb)
{
    const build_item *a = pa, *b = pb;
    uint32_t na = a->end - a->begin, nb = b->end - b->begin;
    if (na != nb)
        return na > nb ? -1 : 1;
    return a->begin < b->begin ? -1 : a->begin > b->begin;
}

/* Top phase: split nodes above the task size with all threads, on the caller;
 * everything else becomes a subtree task. */
static bool build_top(builder *B, const build_item *root)
{
    build_item stack[BVH_MAX_DEPTH + 1];
    int top = 0;
    stack[top++] = *root;
    while (top > 0) {
        build_item it = stack[--top];
        if (it.end - it.begin <= B->task_size) {
            if (!add_task(B, &it))
                return false;
            continue;
        }
        build_item kids[2];
        if (split_node(B, B->threads, &B->workers[0], &it, kids)) {
            assert(top + 2 <= BVH_MAX_DEPTH + 1);
            stack[top++] = kids[1];
            stack[top++] = kids[0];
        } else {
            progress_add(B->progress, it.end - it.begin);
        }
    }
    return true;
}

typedef struct refs_job {
    const aabb *prim_bounds;
    prim_ref *refs;
    box_pair *acc; /* per worker: a = bounds, b = centroid bounds */
} refs_job;

static void refs_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    refs_job *j = ctx;
    box_pair acc = j->acc[worker];
    for (size_t i = begin; i < end; i++) {
        aabb b = j->prim_bounds[i];
        uint32_t id = (uint32_t)i;
        prim_ref *r = &j->refs[i];
        r->f[0] = b.lo.x;
        r->f[1] = b.lo.y;
        r->f[2] = b.lo.z;
        memcpy(&r->f[3], &id, sizeof id);
        r->f[4] = b.hi.x;
        r->f[5] = b.hi.y;
        r->f[6] = b.hi.z;
        r->f[7] = 0.f;
        v4 lo = ref_lo(r), hi = ref_hi(r), c = v4_add(lo, hi);
        acc.a = box4_grow(acc.a, lo, hi);
        acc.b = box4_grow(acc.b, c, c);
    }
    j->acc[worker] = acc;
}

typedef struct order_job {
    const prim_ref *refs;
    uint32_t *prim_order;
} order_job;

static void order_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    order_job *j = ctx;
    for (size_t i = begin; i < end; i++)
        j->prim_order[i] = ref_id(&j->refs[i]);
}

/* Lay out the descendants of out[at] (already copied from the pool, its `first`
 * still a pool slot) in canonical order from out[next] on: depth first, left
 * first, each inner node's children allocated as a pair when it is reached.
 * A subtree with k inner nodes takes exactly the 2k slots after `next`. */
static void compact_subtree(const bvh_node *pool, bvh_node *out, uint32_t at, uint32_t next)
{
    uint32_t stack[BVH_MAX_DEPTH + 1]; /* nodes of `out` whose children are still in pool slots */
    int top = 0;
    stack[top++] = at;
    while (top > 0) {
        bvh_node *n = &out[stack[--top]];
        if (n->count > 0)
            continue;
        uint32_t slot = n->first;
        n->first = next;
        out[next] = pool[slot];
        out[next + 1] = pool[slot + 1];
        assert(top + 2 <= BVH_MAX_DEPTH + 1);
        stack[top++] = next + 1;
        stack[top++] = next;
        next += 2;
    }
}

static void compact_chunk(void *ctx, size_t begin, size_t end, int worker)
{
    (void)worker;
    builder *B = ctx;
    for (size_t t = begin; t < end; t++)
        compact_subtree(B->pool, B->out_nodes, B->task_at[t], B->task_next[t]);
}

/* The task whose root is pool slot `slot`, or -1; tasks_by_slot is sorted by slot. */
static long task_of_slot(const builder *B, const uint32_t *tasks_by_slot, uint32_t slot)
{
    size_t lo = 0, hi = B->task_count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        uint32_t s = B->tasks[tasks_by_slot[mid]].node;
        if (s == slot)
            return (long)tasks_by_slot[mid];
        if (s < slot)
            lo = mid + 1;
        else
            hi = mid;
    }
    return -1;
}

static const builder *slot_sort_ctx; /* qsort has no context argument; used on the caller only */

static int by_slot(const void *pa, const void *pb)
{
    uint32_t a = slot_sort_ctx->tasks[*(const uint32_t *)pa].node, b = slot_sort_ctx->tasks[*(const uint32_t *)pb].node;
    return a < b ? -1 : a > b;
}

/* Copy the tree from the pool into its canonical layout: the nodes above the
 * tasks on the caller (the same walk as compact_subtree, which skips each task
 * root's descendants by its inner count), then every task's subtree in parallel. */
static bool compact(builder *B)
{
    uint32_t *tasks_by_slot = malloc(B->task_count * sizeof *tasks_by_slot);
    B->task_at = malloc(B->task_count * sizeof *B->task_at);
    B->task_next = malloc(B->task_count * sizeof *B->task_next);
    if (!tasks_by_slot || !B->task_at || !B->task_next) {
        free(tasks_by_slot);
        return false;
    }
    for (size_t t = 0; t < B->task_count; t++)
        tasks_by_slot[t] = (uint32_t)t;
    slot_sort_ctx = B;
    qsort(tasks_by_slot, B->task_count, sizeof *tasks_by_slot, by_slot);

    bvh_node *out = B->out_nodes;
    uint32_t stack[BVH_MAX_DEPTH + 1]; /* out index of each waiting node */
    uint32_t slots[BVH_MAX_DEPTH + 1]; /* and its pool slot */
    int top = 0;
    uint32_t next = 1;
    out[0] = B->pool[0];
    stack[top] = 0;
    slots[top++] = 0;
    while (top > 0) {
        top--;
        uint32_t at = stack[top], slot = slots[top];
        long task = task_of_slot(B, tasks_by_slot, slot);
        bvh_node *n = &out[at];
        if (task >= 0) {
            B->task_at[task] = at;
            B->task_next[task] = next;
            next += 2 * B->task_inner[task];
            continue;
        }
        assert(n->count == 0); /* above the tasks every node was split */
        uint32_t kids = n->first;
        n->first = next;
        out[next] = B->pool[kids];
        out[next + 1] = B->pool[kids + 1];
        assert(top + 2 <= BVH_MAX_DEPTH + 1);
        stack[top] = next + 1;
        slots[top++] = kids + 1;
        stack[top] = next;
        slots[top++] = kids;
        next += 2;
    }
    free(tasks_by_slot);
    parallel_pool_for(B->threads, B->task_count, 1, compact_chunk, B);
    return true;
}

static void builder_free(builder *B)
{
    if (B->workers)
        for (int t = 0; t < B->thread_count; t++)
            free(B->workers[t].scratch);
    free(B->workers);
    free(B->bins);
    free(B->acc);
    free(B->tasks);
    free(B->task_inner);
    free(B->task_at);
    free(B->task_next);
    free(B->pool);
    free(B->refs);
    parallel_pool_destroy(B->threads);
}

bool bvh_build(bvh *out, const aabb *prim_bounds, uint32_t count, int threads, tess_error *err)
{
    return bvh_build_leaves(out, prim_bounds, count, threads, BVH_LEAF_DEFAULT, err);
}

bool bvh_build_leaves(bvh *out, const aabb *prim_bounds, uint32_t count, int threads, uint32_t leaf_max,
                      tess_error *err)
{
    return bvh_build_blocks(out, prim_bounds, count, threads, leaf_max, BVH_SAH_BLOCK_LOG2, err);
}

bool bvh_build_blocks(bvh *out, const aabb *prim_bounds, uint32_t count, int threads, uint32_t leaf_max,
                      unsigned block_log2, tess_error *err)
{
    memset(out, 0, sizeof *out);
    if (leaf_max < 1 || leaf_max > BVH_LEAF_MAX)
        return tess_error_set(err, "bvh: leaves of %u primitives (1..%d)", leaf_max, BVH_LEAF_MAX);
    if (block_log2 > 4)
        return tess_error_set(err, "bvh: leaf tests of 2^%u primitives (at most 2^4)", block_log2);
    if (count == 0)
        return true;
    if (threads < 1 || count <= BVH_PARALLEL_NODE_MIN)
        threads = 1;
    progress report; /* leaf primitives placed (engine/base/progress.h) */
    progress_begin(&report, "building BVH", count, "prim");
    builder B = {0};
    B.progress = &report;
    B.leaf_max = leaf_max;
    B.block_log2 = block_log2;
    B.threads = threads > 1 ? parallel_pool_create(threads) : NULL; /* NULL: serial build */
    B.thread_count = parallel_pool_threads(B.threads);
    /* slots: the root, at most 2 * count - 2 below it, and each thread's unused block */
    uint64_t capacity = 2 * (uint64_t)count + (uint64_t)B.thread_count * BVH_NODE_BLOCK;
    if (capacity > UINT32_MAX) {
        builder_free(&B);
        progress_end(&report);
        return tess_error_set(err, "bvh: too many primitives (%u)", count);
    }
    B.pool_capacity = (uint32_t)capacity;
    B.max_blocks = (count + BVH_PARTITION_BLOCK - 1) / BVH_PARTITION_BLOCK;
    B.refs = malloc((size_t)count * sizeof *B.refs);
    B.pool = malloc((size_t)B.pool_capacity * sizeof *B.pool); /* only claimed slots get touched */
    B.workers = calloc((size_t)B.thread_count, sizeof *B.workers);
    B.bins = malloc((size_t)B.thread_count * sizeof *B.bins);
    B.acc = malloc((size_t)B.thread_count * sizeof *B.acc);
    out->prim_order = malloc((size_t)count * sizeof *out->prim_order);
    bool ok = B.refs && B.pool && B.workers && B.bins && B.acc && out->prim_order;
    for (int t = 0; ok && t < B.thread_count; t++)
        ok = (B.workers[t].scratch = malloc(5 * ((size_t)B.max_blocks + 1) * sizeof(uint32_t))) != NULL;
    if (!ok)
        goto out_of_memory;

    for (int t = 0; t < B.thread_count; t++)
        B.acc[t] = box_pair_empty();
    refs_job rj = {prim_bounds, B.refs, B.acc};
    parallel_pool_for(B.threads, count, BVH_SCAN_GRAIN, refs_chunk, &rj);
    build_item root = {0, 0, count, 1, box4_empty(), box4_empty()};
    for (int t = 0; t < B.thread_count; t++) {
        root.bounds = box4_merge(root.bounds, B.acc[t].a);
        root.centroids = box4_merge(root.centroids, B.acc[t].b);
    }
    atomic_init(&B.pool_top, 1); /* slot 0: the root */

    uint32_t per_task = count / ((uint32_t)B.thread_count * BVH_TASKS_PER_THREAD);
    B.task_size = B.thread_count == 1 ? count : per_task > BVH_PARALLEL_NODE_MIN ? per_task : BVH_PARALLEL_NODE_MIN;
    if (!build_top(&B, &root))
        goto out_of_memory;
    qsort(B.tasks, B.task_count, sizeof *B.tasks, task_order);
    B.task_inner = malloc(B.task_count * sizeof *B.task_inner);
    if (!B.task_inner)
        goto out_of_memory;
    parallel_pool_for(B.threads, B.task_count, 1, subtree_chunk, &B);

    uint32_t inner = 0;
    for (int t = 0; t < B.thread_count; t++) {
        inner += B.workers[t].inner_count;
        if (B.workers[t].depth > out->depth)
            out->depth = B.workers[t].depth;
    }
    out->node_count = 1 + 2 * inner;
    if (B.thread_count == 1) {
        /* one task, the root, built depth first by one thread from consecutive
         * slots: the pool already holds the canonical layout */
        assert(B.task_count == 1 && B.tasks[0].node == 0);
        bvh_node *shrunk = realloc(B.pool, (size_t)out->node_count * sizeof *out->nodes);
        out->nodes = shrunk ? shrunk : B.pool;
        B.pool = NULL;
    } else {
        out->nodes = B.out_nodes = malloc((size_t)out->node_count * sizeof *out->nodes);
        if (!out->nodes || !compact(&B))
            goto out_of_memory;
    }
    order_job oj = {B.refs, out->prim_order};
    parallel_pool_for(B.threads, count, BVH_SCAN_GRAIN, order_chunk, &oj);
    out->prim_count = count;
    builder_free(&B);
    progress_end(&report);
    return true;

out_of_memory:
    builder_free(&B);
    progress_end(&report);
    bvh_finish(out);
    return tess_error_set(err, "bvh: out of memory for %u primitives", count);
}

void bvh_finish(bvh *b)
{
    if (!b)
        return;
    free(b->nodes);
    free(b->prim_order);
    memset(b, 0, sizeof *b);
}

size_t bvh_bytes(const bvh *b)
{
    return (size_t)b->node_count * sizeof(bvh_node) + (size_t)b->prim_count * sizeof(uint32_t);
}

double bvh_sah_cost(const bvh *b)
{
    if (b->node_count == 0)
        return 0.0;
    double root = aabb_half_area(b->nodes[0].bounds);
    double cost = 0.0;
    for (uint32_t i = 0; i < b->node_count; i++) {
        const bvh_node *n = &b->nodes[i];
        /* a root without area (all boxes on one line or point): every node is visited */
        double p = root > 0.0 ? aabb_half_area(n->bounds) / root : 1.0;
        cost += n->count ? p * BVH_COST_INTERSECT * bvh_leaf_blocks(n->count) : p * BVH_COST_TRAVERSAL;
    }
    return cost;
}
