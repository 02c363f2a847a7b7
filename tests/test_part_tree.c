/* test_part_tree.c - engine/scene/part_tree.h: preorder enforcement, names, paths,
 * find, subtree ranges, sibling uniquifying, glob patterns, and 100,000 parts
 * (correctness and memory, no timing). */
#include <criterion/criterion.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/part_tree.h"

/* An assertion for hot loops: Criterion reports every passing cr_assert to
 * its runner, which costs more than the tree operations checked. */
#define CHECK(cond, ...)                                                                                          \
    do {                                                                                                          \
        if (!(cond))                                                                                              \
            cr_assert_fail(__VA_ARGS__);                                                                          \
    } while (0)

static part_tree *tree_new(void)
{
    part_tree *t = part_tree_create();
    cr_assert_not_null(t);
    return t;
}

static int32_t add_ok(part_tree *t, int32_t parent, const char *name)
{
    tess_error err = {{0}};
    int32_t id = part_tree_add(t, parent, name, &err);
    CHECK(id != PART_NONE, "adding '%s' under %d: %s", name, parent, err.msg);
    return id;
}

static void add_fails(part_tree *t, int32_t parent, const char *name, const char *needle)
{
    tess_error err = {{0}};
    int32_t before = part_tree_count(t);
    cr_expect_eq(part_tree_add(t, parent, name, &err), PART_NONE, "adding '%s' under %d should fail", name, parent);
    cr_expect(strstr(err.msg, needle), "message for '%s' lacks '%s': %s", name, needle, err.msg);
    cr_expect_eq(part_tree_count(t), before, "a refused part must not be added");
}

static void expect_path(const part_tree *t, int32_t id, const char *want)
{
    char buf[256];
    size_t n = part_tree_path(t, id, buf, sizeof buf);
    cr_expect_str_eq(buf, want);
    cr_expect_eq(n, strlen(want));
    cr_expect_eq(part_tree_find(t, want), id, "find '%s'", want);
}

Test(part_tree, root_only)
{
    part_tree *t = tree_new();
    cr_expect_eq(part_tree_count(t), 1);
    cr_expect_str_eq(part_tree_name(t, PART_ROOT), "");
    cr_expect_eq(part_tree_parent(t, PART_ROOT), PART_NONE);
    cr_expect_eq(part_tree_subtree_end(t, PART_ROOT), 1);
    expect_path(t, PART_ROOT, "");
    part_tree_destroy(t);
    part_tree_destroy(NULL);
}

/*   fuselage (1)
 *     frame-12 (2)
 *       bracket-3 (3)
 *       bracket-4 (4)
 *     frame-13 (5)
 *   wing (6)          */
static part_tree *small_tree(void)
{
    part_tree *t = tree_new();
    cr_assert_eq(add_ok(t, PART_ROOT, "fuselage"), 1);
    cr_assert_eq(add_ok(t, 1, "frame-12"), 2);
    cr_assert_eq(add_ok(t, 2, "bracket-3"), 3);
    cr_assert_eq(add_ok(t, 2, "bracket-4"), 4);
    cr_assert_eq(add_ok(t, 1, "frame-13"), 5);
    cr_assert_eq(add_ok(t, PART_ROOT, "wing"), 6);
    return t;
}

Test(part_tree, paths_find_and_subtrees)
{
    part_tree *t = small_tree();
    expect_path(t, 1, "fuselage");
    expect_path(t, 3, "fuselage/frame-12/bracket-3");
    expect_path(t, 4, "fuselage/frame-12/bracket-4");
    expect_path(t, 5, "fuselage/frame-13");
    expect_path(t, 6, "wing");
    cr_expect_eq(part_tree_find(t, "fuselage/frame-14"), PART_NONE);
    cr_expect_eq(part_tree_find(t, "frame-12"), PART_NONE);
    cr_expect_eq(part_tree_find(t, "fuselage/"), PART_NONE);
    cr_expect_eq(part_tree_find(t, "/fuselage"), PART_NONE);
    cr_expect_eq(part_tree_find(t, "fuselage//frame-12"), PART_NONE);
    cr_expect_eq(part_tree_find(t, "fuselage/frame-1"), PART_NONE, "a prefix of a name is no match");
    cr_expect_eq(part_tree_child(t, 2, "bracket-4"), 4);
    cr_expect_eq(part_tree_child(t, 1, "bracket-4"), PART_NONE);
    /* subtree ranges: closed ones and the open chain (root, wing) */
    const int32_t want_end[] = {7, 6, 5, 4, 5, 6, 7};
    for (int32_t id = 0; id < 7; id++)
        cr_expect_eq(part_tree_subtree_end(t, id), want_end[id], "end of %d", id);
    const int want_depth[] = {0, 1, 2, 3, 3, 2, 1};
    for (int32_t id = 0; id < 7; id++)
        cr_expect_eq(part_tree_depth(t, id), want_depth[id]);
    /* a cut path says its full length */
    char small[10];
    cr_expect_eq(part_tree_path(t, 3, small, sizeof small), strlen("fuselage/frame-12/bracket-3"));
    cr_expect_str_eq(small, "fuselage/");
    part_tree_destroy(t);
}

Test(part_tree, preorder_is_enforced)
{
    part_tree *t = small_tree();
    /* the open chain is root -> wing: anything else is closed */
    add_fails(t, 1, "late", "preorder");
    add_fails(t, 2, "late", "preorder");
    add_fails(t, 5, "late", "preorder");
    add_fails(t, 99, "x", "does not exist");
    add_fails(t, -1, "x", "does not exist");
    cr_expect_eq(add_ok(t, 6, "flap"), 7);     /* a child of the last part */
    cr_expect_eq(add_ok(t, 6, "aileron"), 8);  /* of an ancestor of the last */
    add_fails(t, 7, "hinge", "preorder");      /* flap closed when aileron came */
    cr_expect_eq(part_tree_subtree_end(t, 6), 9);
    cr_expect_eq(part_tree_subtree_end(t, 7), 8);
    part_tree_destroy(t);
}

Test(part_tree, names_are_checked)
{
    part_tree *t = small_tree();
    add_fails(t, PART_ROOT, "", "empty name");
    add_fails(t, PART_ROOT, "a/b", "'/'");
    add_fails(t, PART_ROOT, "wing", "already has a child of that name");
    char long_name[PART_NAME_MAX_BYTES + 1];
    memset(long_name, 'x', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = '\0';
    add_fails(t, PART_ROOT, long_name, "at most");
    cr_expect_eq(add_ok(t, 6, "wing"), 7, "the same name under another parent is fine");
    expect_path(t, 7, "wing/wing");
    part_tree_destroy(t);
}

Test(part_tree, siblings_are_made_unique)
{
    part_tree *t = tree_new();
    tess_error err = {{0}};
    int32_t a = part_tree_add_unique(t, PART_ROOT, "bolt", &err);
    int32_t b = part_tree_add_unique(t, PART_ROOT, "bolt", &err);
    int32_t lit = part_tree_add_unique(t, PART_ROOT, "bolt#3", &err); /* given as such */
    int32_t c = part_tree_add_unique(t, PART_ROOT, "bolt", &err);
    int32_t d = part_tree_add_unique(t, PART_ROOT, "bolt", &err);
    int32_t e = part_tree_add_unique(t, PART_ROOT, "bolt#3", &err);
    cr_assert_str_empty(err.msg);
    cr_expect_str_eq(part_tree_name(t, a), "bolt");
    cr_expect_str_eq(part_tree_name(t, b), "bolt#2");
    cr_expect_str_eq(part_tree_name(t, lit), "bolt#3");
    cr_expect_str_eq(part_tree_name(t, c), "bolt#4", "#3 is taken: skipped");
    cr_expect_str_eq(part_tree_name(t, d), "bolt#5");
    cr_expect_str_eq(part_tree_name(t, e), "bolt#3#2");
    /* under another parent the numbering starts again */
    int32_t nut = part_tree_add_unique(t, e, "bolt", &err);
    cr_expect_str_eq(part_tree_name(t, nut), "bolt");
    cr_expect_eq(part_tree_add_unique(t, PART_ROOT, "a/b", &err), PART_NONE, "'/' is refused here too");
    part_tree_destroy(t);
}

Test(part_tree, glob_patterns)
{
    static const struct {
        const char *pattern, *path;
        bool match;
    } cases[] = {
        {"**", "a", true},
        {"**", "a/b/c", true},
        {"*", "a", true},
        {"*", "a/b", false},
        {"a/*", "a/b", true},
        {"a/*", "a/b/c", false},
        {"a/**", "a", true},
        {"a/**", "a/b/c", true},
        {"a/**", "ab/c", false},
        {"**/bolt-*", "bolt-1", true},
        {"**/bolt-*", "x/y/bolt-12", true},
        {"**/bolt-*", "x/y/bolt", false},
        {"**/bolt-*", "x/bolt-1/nut", false},
        {"section-2/**", "section-2/frame-3/bracket", true},
        {"section-2/**", "section-20/frame-3", false},
        {"*/frame-?", "s/frame-3", true},
        {"*/frame-?", "s/frame-12", false},
        {"a/**/c", "a/c", true},
        {"a/**/c", "a/b/b/c", true},
        {"a/**/c", "a/b/c/d", false},
        {"**/b/**", "a/b/c", true},
        {"**/b/**", "a/c", false},
        {"*b*", "abc", true},
        {"*b*", "ac", false},
        {"a*c*e", "abcde", true},
        {"a*c*e", "abcdf", false},
        {"fuselage", "fuselage", true},
        {"fuselage", "fuselage/x", false},
        {"", "", true},
        {"", "a", false},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        cr_expect_eq(part_glob_match(cases[i].pattern, cases[i].path), cases[i].match, "'%s' against '%s'",
                     cases[i].pattern, cases[i].path);
}

typedef struct collected {
    int32_t ids[16];
    char paths[16][64];
    int count, stop_after;
} collected;

static bool collect(void *ctx, int32_t id, const char *path)
{
    collected *c = ctx;
    cr_assert_lt(c->count, 16);
    c->ids[c->count] = id;
    snprintf(c->paths[c->count], sizeof c->paths[0], "%s", path);
    return ++c->count != c->stop_after;
}

Test(part_tree, match_walks_in_preorder)
{
    part_tree *t = small_tree();
    collected c = {0};
    cr_expect_eq(part_tree_match(t, "**", collect, &c), 6);
    for (int i = 0; i < 6; i++) {
        cr_expect_eq(c.ids[i], i + 1);
        char want[64];
        part_tree_path(t, i + 1, want, sizeof want);
        cr_expect_str_eq(c.paths[i], want);
    }
    c = (collected){0};
    cr_expect_eq(part_tree_match(t, "**/bracket-*", collect, &c), 2);
    cr_expect_eq(c.ids[0], 3);
    cr_expect_eq(c.ids[1], 4);
    c = (collected){0};
    cr_expect_eq(part_tree_match(t, "fuselage/*", collect, &c), 2);
    cr_expect_str_eq(c.paths[0], "fuselage/frame-12");
    cr_expect_str_eq(c.paths[1], "fuselage/frame-13");
    c = (collected){.stop_after = 1};
    cr_expect_eq(part_tree_match(t, "**", collect, &c), 1, "the callback stops the walk");
    part_tree_destroy(t);
}

Test(part_tree, counters)
{
    part_tree *t = small_tree();
    part_tree_counts(t, 3)->instances = 2;
    part_tree_counts(t, 3)->triangles = 5000000000ull;
    cr_expect_eq(part_tree_counts_const(t, 3)->instances, 2);
    cr_expect_eq(part_tree_counts_const(t, 3)->triangles, 5000000000ull);
    cr_expect_eq(part_tree_counts_const(t, 4)->instances, 0);
    cr_expect_eq(add_ok(t, PART_ROOT, "tail"), 7);
    cr_expect_eq(part_tree_counts_const(t, 7)->triangles, 0, "a new part starts at zero");
    part_tree_destroy(t);
}

static bool count_match(void *ctx, int32_t id, const char *path)
{
    (void)id;
    (void)path;
    ++*(long *)ctx;
    return true;
}

/* 100 sections x 10 frames x 99 bolts + the sections and frames: 100,100
 * parts, every one found by its path, ranges right, well under 10 MB. */
Test(part_tree, hundred_thousand_parts, .timeout = 60)
{
    char name[32], path[96];
    tess_error err = {{0}};
    part_tree *t = tree_new();
    /* frames all named "frame", bolts all "bolt": uniquified */
    for (int s = 0; s < 100; s++) {
        snprintf(name, sizeof name, "section-%d", s);
        int32_t sid = add_ok(t, PART_ROOT, name);
        for (int f = 0; f < 10; f++) {
            int32_t fid = part_tree_add_unique(t, sid, "frame", &err);
            CHECK(fid != PART_NONE, "%s", err.msg);
            for (int b = 0; b < 99; b++)
                CHECK(part_tree_add_unique(t, fid, "bolt", &err) != PART_NONE, "%s", err.msg);
            CHECK(part_tree_subtree_end(t, fid) == part_tree_count(t), "frame end");
        }
    }
    cr_assert_eq(part_tree_count(t), 1 + 100 * (1 + 10 * 100));
    cr_expect_lt(part_tree_bytes(t), 10u << 20, "%zu bytes for 100,101 parts", part_tree_bytes(t));
    int32_t id = 1;
    for (int s = 0; s < 100; s++) {
        snprintf(path, sizeof path, "section-%d", s);
        CHECK(part_tree_find(t, path) == id, "%s", path);
        CHECK(part_tree_subtree_end(t, id) == id + 1 + 10 * 100, "section %d", s);
        id++;
        for (int f = 0; f < 10; f++) {
            char frame[16];
            snprintf(frame, sizeof frame, f ? "frame#%d" : "frame", f + 1);
            snprintf(path, sizeof path, "section-%d/%s", s, frame);
            CHECK(part_tree_find(t, path) == id, "%s", path);
            CHECK(part_tree_subtree_end(t, id) == id + 100, "%s", path);
            id++;
            for (int b = 0; b < 99; b++) {
                if (b)
                    snprintf(path, sizeof path, "section-%d/%s/bolt#%d", s, frame, b + 1);
                else
                    snprintf(path, sizeof path, "section-%d/%s/bolt", s, frame);
                CHECK(part_tree_find(t, path) == id, "%s", path);
                char back[96];
                part_tree_path(t, id, back, sizeof back);
                CHECK(strcmp(back, path) == 0, "%s against %s", back, path);
                id++;
            }
        }
    }
    long count = 0;
    cr_expect_eq(part_tree_match(t, "section-7/**/bolt#9?", count_match, &count), 10 * 10);
    cr_expect_eq(count, 10 * 10);
    cr_expect_eq(part_tree_match(t, "**", count_match, &(long){0}), 100 * (1 + 10 * 100));
    part_tree_destroy(t);
}

/* A chain 100,000 deep: nothing recurses; closing it closes every level. */
Test(part_tree, hundred_thousand_deep, .timeout = 60)
{
    enum { DEPTH = 100000 };
    part_tree *t = tree_new();
    for (int32_t d = 0; d < DEPTH; d++)
        CHECK(add_ok(t, d, "n") == d + 1, "depth %d", d);
    size_t len = 2 * DEPTH - 1;
    char *path = malloc(len + 1);
    cr_assert_not_null(path);
    cr_expect_eq(part_tree_path(t, DEPTH, path, len + 1), len);
    cr_expect_eq(strlen(path), len);
    cr_expect_eq(part_tree_find(t, path), DEPTH);
    cr_expect_eq(part_tree_depth(t, DEPTH), DEPTH);
    cr_expect_eq(part_tree_subtree_end(t, 1), DEPTH + 1, "open");
    cr_expect_eq(add_ok(t, PART_ROOT, "m"), DEPTH + 1);
    cr_expect_eq(part_tree_subtree_end(t, 1), DEPTH + 1);
    cr_expect_eq(part_tree_subtree_end(t, DEPTH), DEPTH + 1);
    long count = 0;
    /* (a "**" pattern here would cost the sum of all path lengths: 10^10) */
    cr_expect_eq(part_tree_match(t, "n/n/n", count_match, &count), 1);
    free(path);
    part_tree_destroy(t);
}
