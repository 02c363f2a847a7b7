/* layout.c - placing the fuselage's parts (layout.h). */
#include "layout.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"

#define PI 3.14159265358979323846

/* Sizes in metres: a narrow-body fuselage and its standard hardware. */
#define SKIN_THICKNESS 0.002
#define FRAME_DEPTH 0.09    /* radial */
#define FRAME_WIDTH 0.025   /* along x */
#define RIVET_ROW_PITCH 0.02
#define RIVET_MIN_PITCH 0.012 /* closest rivets in a row; more go to another row */

/* Parts a section gets, per part of the section's share of --parts: enough
 * structure to look like a fuselage, the rest rivets (the only count that
 * can absorb the remainder exactly). */
#define STRINGERS_PER_PART 0.08
#define PIPES_PER_PART 0.01
#define BRACKETS_PER_PART 0.04
#define BOLTS_PER_BRACKET 3

/* The density search: log-bisection over this range of s. */
#define DENSITY_MIN (1.0 / 32.0)
#define DENSITY_MAX 512.0
#define DENSITY_STEPS 48

const char *ga_node_kind_name(enum ga_node_kind kind)
{
    static const char *const names[GA_NODE_KIND_COUNT] = {
        [GA_NODE_ASSEMBLY] = "assembly", [GA_NODE_SECTION] = "section", [GA_NODE_FRAME] = "frame",
        [GA_NODE_STRINGER] = "stringer", [GA_NODE_SKIN] = "skin",       [GA_NODE_PIPE] = "pipe",
        [GA_NODE_BRACKET] = "bracket",   [GA_NODE_BOLT] = "bolt",       [GA_NODE_RIVET] = "rivet",
    };
    return (unsigned)kind < GA_NODE_KIND_COUNT ? names[kind] : "node";
}

void ga_layout_finish(struct ga_layout *layout)
{
    free(layout->nodes);
    free(layout->shapes);
    free(layout->shape_uses);
    memset(layout, 0, sizeof *layout);
}

static long clampl(long v, long lo, long hi) { return v < lo ? lo : v > hi ? hi : v; }

/* A tessellation count: base * s rounded, within [lo, hi]. */
static int segments(double base, double s, long lo, long hi) { return (int)clampl(lround(base * s), lo, hi); }

/* The index of `shape` among the layout's shapes, added when new; -1 when out of memory. */
static int32_t shape_id(struct ga_layout *layout, const struct ga_shape *shape)
{
    for (size_t i = layout->shape_count; i-- > 0;)
        if (!memcmp(&layout->shapes[i], shape, sizeof *shape))
            return (int32_t)i;
    if (layout->shape_count == layout->shape_cap) {
        size_t cap = layout->shape_cap ? 2 * layout->shape_cap : 64;
        struct ga_shape *shapes = realloc(layout->shapes, cap * sizeof *shapes);
        if (shapes)
            layout->shapes = shapes;
        uint64_t *uses = realloc(layout->shape_uses, cap * sizeof *uses);
        if (uses)
            layout->shape_uses = uses;
        if (!shapes || !uses) {
            layout->failed = true;
            return -1;
        }
        layout->shape_cap = cap;
    }
    layout->shapes[layout->shape_count] = *shape;
    layout->shape_uses[layout->shape_count] = 0;
    return (int32_t)layout->shape_count++;
}

/* Add a node; its index (-1 when out of memory). */
static int32_t add_node(struct ga_layout *layout, int32_t parent, enum ga_node_kind kind, uint32_t number,
                        int32_t shape, double x, double y, double z, double rotation_x)
{
    if (layout->failed)
        return -1;
    if (layout->count_only) {
        /* the density search needs the totals only */
    } else if (layout->node_count == layout->node_cap) {
        size_t cap = layout->node_cap ? 2 * layout->node_cap : 1024;
        struct ga_node *nodes = realloc(layout->nodes, cap * sizeof *nodes);
        if (!nodes) {
            layout->failed = true;
            return -1;
        }
        layout->nodes = nodes;
        layout->node_cap = cap;
    }
    if (!layout->count_only)
        layout->nodes[layout->node_count] = (struct ga_node){parent, shape, kind, number, {x, y, z}, rotation_x};
    if (shape >= 0) {
        layout->part_count++;
        layout->shape_uses[shape]++;
        layout->triangles_placed += ga_shape_triangles(&layout->shapes[shape]);
    }
    return (int32_t)layout->node_count++;
}

/* The hardware shared by every section. */
struct hardware {
    int32_t bolt, rivet, bracket;
    double bracket_leg_y, bracket_leg_z, bracket_t, bracket_w; /* metres, where the bolts go */
};

static void make_hardware(struct ga_layout *layout, double s, struct hardware *hw)
{
    struct ga_shape bolt = ga_shape_make(GA_SHAPE_BOLT);
    bolt.segments[0] = 12 * segments(1.0, s, 1, 64);
    bolt.size[0] = 0.0058; /* M6: 10 mm across flats */
    bolt.size[1] = 0.004;
    bolt.size[2] = 0.003;
    bolt.size[3] = 0.02;
    hw->bolt = shape_id(layout, &bolt);

    struct ga_shape rivet = ga_shape_make(GA_SHAPE_RIVET);
    rivet.segments[0] = segments(8.0, s, 6, 256);
    rivet.segments[1] = segments(1.0, 1.0 + s, 2, 64);
    rivet.size[0] = 0.004;
    rivet.size[1] = 0.0018;
    rivet.size[2] = 0.002;
    rivet.size[3] = 0.006;
    hw->rivet = shape_id(layout, &rivet);

    struct ga_shape bracket = ga_shape_make(GA_SHAPE_BRACKET);
    bracket.size[0] = hw->bracket_leg_y = 0.06;
    bracket.size[1] = hw->bracket_leg_z = 0.05;
    bracket.size[2] = hw->bracket_t = 0.003;
    bracket.size[3] = hw->bracket_w = 0.04;
    hw->bracket = shape_id(layout, &bracket);
}

/* A bracket on the inner edge of a frame at angle theta, its legs pointing
 * inwards, and its bolts: two through the leg on the frame, one through the
 * other leg. */
static void place_bracket(struct ga_layout *layout, const struct hardware *hw, int32_t frame, uint32_t number,
                          double inner_radius, double theta)
{
    int32_t b = add_node(layout, frame, GA_NODE_BRACKET, number, hw->bracket, 0.0, inner_radius * cos(theta),
                         inner_radius * sin(theta), theta + PI / 2);
    const double bolt_at[BOLTS_PER_BRACKET][4] = {
        /* x, y, z, rotation: head up on the leg along y, then sideways on the leg along z */
        {-hw->bracket_w / 4, hw->bracket_leg_y * 0.65, hw->bracket_t, 0.0},
        {hw->bracket_w / 4, hw->bracket_leg_y * 0.65, hw->bracket_t, 0.0},
        {0.0, hw->bracket_t, hw->bracket_leg_z * 0.6, -PI / 2},
    };
    for (int i = 0; i < BOLTS_PER_BRACKET; i++)
        add_node(layout, b, GA_NODE_BOLT, (uint32_t)i + 1, hw->bolt, bolt_at[i][0], bolt_at[i][1], bolt_at[i][2],
                 bolt_at[i][3]);
}

/* Rivets along frame j's line on the skin, in as many rows as their pitch needs. */
static void place_rivets(struct ga_layout *layout, const struct hardware *hw, int32_t section, uint32_t *number,
                         double x, double radius, long count)
{
    if (count <= 0 || layout->failed)
        return;
    if (layout->count_only) {
        /* the bulk of the parts: the density search counts them without placing them */
        layout->node_count += (size_t)count;
        layout->part_count += (size_t)count;
        layout->shape_uses[hw->rivet] += (uint64_t)count;
        layout->triangles_placed += (uint64_t)count * ga_shape_triangles(&layout->shapes[hw->rivet]);
        *number += (uint32_t)count;
        return;
    }
    long per_row_max = (long)floor(2.0 * PI * radius / RIVET_MIN_PITCH);
    long rows = (count + per_row_max - 1) / per_row_max;
    long left = count;
    for (long r = 0; r < rows; r++) {
        long in_row = left / (rows - r);
        double row_x = x + (r - (rows - 1) / 2.0) * RIVET_ROW_PITCH, stagger = (r % 2) * 0.5;
        for (long i = 0; i < in_row; i++) {
            double theta = 2.0 * PI * (i + stagger) / in_row;
            add_node(layout, section, GA_NODE_RIVET, (*number)++, hw->rivet, row_x, radius * cos(theta),
                     radius * sin(theta), theta - PI / 2);
        }
        left -= in_row;
    }
}

/* The layout at density s; with count_only, the totals without the nodes. */
static bool build(struct ga_layout *layout, const struct ga_layout_params *params, double s, bool count_only)
{
    memset(layout, 0, sizeof *layout);
    layout->density = s;
    layout->count_only = count_only;
    struct ga_rng rng;
    ga_rng_seed(&rng, params->seed);
    struct hardware hw;
    make_hardware(layout, s, &hw);

    long sections = clampl(lround(sqrt((double)params->parts) / 6.0), 1, 80);
    double share = (double)params->parts / (double)sections; /* parts a section */
    long stringers = clampl(lround(STRINGERS_PER_PART * share), 4, 64);
    long skins = clampl(stringers / 4, 4, 16);
    long pipes = clampl(lround(PIPES_PER_PART * share), 1, 8);
    long brackets = lround(BRACKETS_PER_PART * share);
    double radius0 = ga_rng_range(&rng, 1.8, 2.4), pitch = ga_rng_range(&rng, 0.45, 0.6);

    int32_t root = add_node(layout, -1, GA_NODE_ASSEMBLY, 0, -1, 0, 0, 0, 0);
    double x0 = 0.0;
    for (long k = 1; k <= sections; k++) {
        /* a smaller nose and tail section, the same barrel between */
        double radius = radius0 * (sections >= 3 && k == 1 ? 0.8 : sections >= 3 && k == sections ? 0.85 : 1.0);
        long frames = ga_rng_int(&rng, 6, 10);
        double length = frames * pitch;
        bool z_stringers = ga_rng_unit(&rng) < 0.5;
        int32_t sec = add_node(layout, root, GA_NODE_SECTION, (uint32_t)k, -1, x0, 0, 0, 0);
        size_t parts_before = layout->part_count;

        struct ga_shape frame = ga_shape_make(GA_SHAPE_FRAME);
        frame.segments[0] = segments(48.0, s, 16, 16384);
        frame.size[1] = radius - SKIN_THICKNESS;
        frame.size[0] = frame.size[1] - FRAME_DEPTH;
        frame.size[2] = FRAME_WIDTH;
        int32_t frame_shape = shape_id(layout, &frame);
        long rivet_total = (long)llround((double)params->parts * k / sections) - (long)parts_before -
                           (long)(frames + stringers + skins + pipes + brackets * (1 + BOLTS_PER_BRACKET));
        uint32_t rivet_number = 1;
        for (long j = 0; j < frames; j++) {
            double fx = (j + 0.5) * pitch;
            int32_t fr = add_node(layout, sec, GA_NODE_FRAME, (uint32_t)j + 1, frame_shape, fx, 0, 0, 0);
            long nb = brackets * (j + 1) / frames - brackets * j / frames;
            for (long b = 0; b < nb; b++)
                place_bracket(layout, &hw, fr, (uint32_t)b + 1, frame.size[0], ga_rng_range(&rng, 0.0, 2.0 * PI));
            place_rivets(layout, &hw, sec, &rivet_number, fx, radius,
                         rivet_total * (j + 1) / frames - rivet_total * j / frames);
        }

        struct ga_shape stringer = ga_shape_make(z_stringers ? GA_SHAPE_STRINGER_Z : GA_SHAPE_STRINGER_BOX);
        stringer.size[0] = length;
        stringer.size[1] = radius - SKIN_THICKNESS;
        if (z_stringers) {
            stringer.size[2] = 0.022;
            stringer.size[3] = 0.035;
            stringer.size[4] = 0.0025;
        } else {
            stringer.size[2] = 0.018;
            stringer.size[3] = 0.03;
        }
        int32_t stringer_shape = shape_id(layout, &stringer);
        for (long i = 0; i < stringers; i++)
            add_node(layout, sec, GA_NODE_STRINGER, (uint32_t)i + 1, stringer_shape, 0, 0, 0,
                     2.0 * PI * (i + 0.5) / stringers - PI / 2);

        struct ga_shape skin = ga_shape_make(GA_SHAPE_SKIN);
        skin.segments[0] = segments(12.0, s, 4, 1024);
        skin.segments[1] = segments(2.0, s, 1, 256);
        skin.size[0] = length;
        skin.size[1] = radius - SKIN_THICKNESS;
        skin.size[2] = SKIN_THICKNESS;
        skin.size[3] = 2.0 * PI / skins - 0.001 / radius; /* a 1 mm gap between panels */
        int32_t skin_shape = shape_id(layout, &skin);
        for (long i = 0; i < skins; i++)
            add_node(layout, sec, GA_NODE_SKIN, (uint32_t)i + 1, skin_shape, 0, 0, 0, 2.0 * PI * i / skins - PI / 2);

        for (long i = 0; i < pipes; i++) {
            struct ga_shape pipe = ga_shape_make(GA_SHAPE_PIPE);
            double theta = ga_rng_range(&rng, 0.0, 2.0 * PI), at = radius * ga_rng_range(&rng, 0.6, 0.75);
            pipe.segments[0] = segments(12.0, sqrt(s), 6, 128);
            pipe.segments[1] = segments(4.0, sqrt(s), 2, 64);
            pipe.size[0] = ga_rng_range(&rng, 0.01, 0.03);
            pipe.size[1] = 4.0 * pipe.size[0];
            pipe.size[2] = length * ga_rng_range(&rng, 0.2, 0.4);
            pipe.size[3] = length * ga_rng_range(&rng, 0.15, 0.3);
            pipe.size[4] = length * ga_rng_range(&rng, 0.1, 0.2);
            pipe.size[5] = ga_rng_range(&rng, 0.3, 0.8) * (ga_rng_unit(&rng) < 0.5 ? -1.0 : 1.0);
            double second = ga_rng_unit(&rng);
            pipe.size[6] = second < 0.5 ? -pipe.size[5] * (0.5 + second) : 0.0;
            int32_t pipe_shape = shape_id(layout, &pipe);
            add_node(layout, sec, GA_NODE_PIPE, (uint32_t)i + 1, pipe_shape, 0.05 * length, at * cos(theta),
                     at * sin(theta), theta);
        }
        x0 += length;
    }
    return !layout->failed;
}

bool ga_layout_build(struct ga_layout *layout, const struct ga_layout_params *params, double s)
{
    return build(layout, params, s, false);
}

bool ga_layout_fit(struct ga_layout *layout, const struct ga_layout_params *params)
{
    double lo = log(DENSITY_MIN), hi = log(DENSITY_MAX), best_s = 1.0, best_err = INFINITY;
    double target = (double)params->triangles;
    memset(layout, 0, sizeof *layout);
    for (int step = 0; step < DENSITY_STEPS; step++) {
        double s = exp(0.5 * (lo + hi));
        struct ga_layout trial;
        if (!build(&trial, params, s, true)) {
            ga_layout_finish(&trial);
            return false;
        }
        double got = (double)trial.triangles_placed, err = fabs(log(got / target));
        if (err < best_err) {
            best_err = err;
            best_s = s;
        }
        ga_layout_finish(&trial);
        if (got < target)
            lo = log(s);
        else
            hi = log(s);
    }
    /* the ends of the range, when the target lies beyond them */
    const double ends[2] = {DENSITY_MIN, DENSITY_MAX};
    for (int i = 0; i < 2; i++) {
        struct ga_layout trial;
        if (!build(&trial, params, ends[i], true)) {
            ga_layout_finish(&trial);
            return false;
        }
        double err = fabs(log((double)trial.triangles_placed / target));
        if (err < best_err) {
            best_err = err;
            best_s = ends[i];
        }
        ga_layout_finish(&trial);
    }
    return ga_layout_build(layout, params, best_s);
}
