/* part_tree.h - the parts of an assembly (a CAD model, a glTF node tree, an
 * OBJ's groups) as a tree of named nodes, independent of any scene.
 *
 * Ids and order: parts are numbered in PREORDER as they are added, so the
 * subtree of part `id` is the contiguous id range [id, part_tree_subtree_end(id)).
 * Part 0 is the root: it stands for the file, has the empty name and the path
 * "" and is made by part_tree_create. part_tree_add only accepts a parent that
 * is the last added part or one of its ancestors (the root included): that is
 * exactly what keeps the numbering a preorder.
 *
 * Names and paths: a name is a non-empty string without '/' (at most
 * PART_NAME_MAX_BYTES - 1 bytes), unique among its siblings. A part's path is
 * the names from the root's child down to the part joined by '/', the root
 * omitted: "fuselage/frame-12/bracket-3". part_tree_add_unique makes a name
 * unique by appending "#2", "#3", ... (the first free number; a later
 * duplicate never reuses a number, so "bolt", "bolt#2", "bolt#3" in the order
 * the duplicates come).
 *
 * Patterns (part_tree_match, part_glob_match): '/'-separated like paths; in a
 * segment '*' matches any run of characters but '/', '?' one character but '/';
 * a segment that is exactly "**" matches any number of whole segments, none
 * included. (The examples write " / " for the separator: a C comment cannot
 * hold it next to a '*'.) "**" alone matches every path; "section-2 / **"
 * the part section-2 and everything under it; "** / bolt-*" every part whose
 * own name starts with "bolt-", at any depth; "* / frame-?" the parts
 * frame-0 .. frame-9 one level down.
 *
 * Cost: per part a name in one string arena, a parent, a subtree end, the
 * counters and a slot in a hash table over (parent, name), at most half
 * full, that serves sibling-uniqueness checks and part_tree_find (one probe
 * per segment): about 40 bytes plus the name. Measured on 100,101 parts
 * (100 sections x 10 frames x 99 bolts, names uniquified), 2-CPU AMD EPYC:
 * 6.3 MB with the arrays' doubling slack, building 0.5 to 1.3 us a part,
 * part_tree_find 0.1 to 0.25 us a path. Not thread-safe; a tree is used by
 * one thread at a time. */
#ifndef TESSERA_PART_TREE_H
#define TESSERA_PART_TREE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"

#define PART_NONE (-1)           /* "no part": part_tree_find's miss, the root's parent */
#define PART_ROOT 0              /* the root's id */
#define PART_NAME_MAX_BYTES 1024 /* a name's bytes with its NUL (longer names are refused) */
#define PART_MAX_COUNT (INT32_MAX / 2) /* parts in one tree, root included */

typedef struct part_tree part_tree;

/* What a caller may count per part (part_tree_counts); zero when added. */
typedef struct part_counts {
    uint32_t instances; /* instances placed directly on the part */
    uint64_t triangles; /* their triangles, counted once per instance */
} part_counts;

/* A tree holding only the root; NULL when out of memory. */
part_tree *part_tree_create(void);
void part_tree_destroy(part_tree *t); /* NULL is fine */

/* Add a child `name` to `parent` (PART_ROOT for a top-level part); its id,
 * which is the number of parts before it. PART_NONE with err set when parent
 * is not the last added part or one of its ancestors, the name is empty,
 * holds '/', is too long or is taken among parent's children, or memory
 * runs out. */
int32_t part_tree_add(part_tree *t, int32_t parent, const char *name, tess_error *err);
/* The same, but a name taken among the siblings gets the suffix "#N" (see
 * the top); part_tree_name says what it became. */
int32_t part_tree_add_unique(part_tree *t, int32_t parent, const char *name, tess_error *err);

int32_t part_tree_count(const part_tree *t);                 /* parts, root included */
const char *part_tree_name(const part_tree *t, int32_t id);  /* "" for the root */
int32_t part_tree_parent(const part_tree *t, int32_t id);    /* PART_NONE for the root */
/* One past the last part of id's subtree: [id, end) is the subtree. A part
 * whose subtree may still grow (the last added part and its ancestors) ends
 * at part_tree_count. */
int32_t part_tree_subtree_end(const part_tree *t, int32_t id);
int part_tree_depth(const part_tree *t, int32_t id);         /* 0 for the root, O(depth) */
/* The child of parent named name, or PART_NONE. */
int32_t part_tree_child(const part_tree *t, int32_t parent, const char *name);

/* Write id's path into buf (NUL-terminated, cut at size - 1 bytes); the
 * path's full length, as snprintf, so a result >= size means it was cut. */
size_t part_tree_path(const part_tree *t, int32_t id, char *buf, size_t size);
/* The part at `path` ("" is the root; no leading, trailing or doubled '/'),
 * or PART_NONE. */
int32_t part_tree_find(const part_tree *t, const char *path);

/* The caller's counters of part id (never NULL for a valid id). */
part_counts *part_tree_counts(part_tree *t, int32_t id);
const part_counts *part_tree_counts_const(const part_tree *t, int32_t id);

/* Call fn for every part but the root whose path matches pattern, in id
 * order (preorder), with the path; fn returns false to stop. Paths are built
 * incrementally (O(1) a part), a match costs up to the path's length times
 * the pattern's "**" count, so deep trees with "**" patterns cost the sum of
 * their path lengths. Returns the
 * number of parts matched (fn calls), or -1 when out of memory. */
typedef bool (*part_match_fn)(void *ctx, int32_t id, const char *path);
long part_tree_match(const part_tree *t, const char *pattern, part_match_fn fn, void *ctx);

/* Does path match pattern (the rules at the top)? */
bool part_glob_match(const char *pattern, const char *path);

/* Bytes the tree holds (arrays by capacity, the arena, the hash table). */
size_t part_tree_bytes(const part_tree *t);

#endif
