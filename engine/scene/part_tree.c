/* part_tree.c - the part tree of part_tree.h: parallel arrays in preorder, one
 * string arena, and an open-addressing hash table over (parent, name).
 *
 * Invariants: end[id] == 0 while id's subtree may still grow, i.e. exactly
 * for the parts on the `open` stack (the last added part and its ancestors,
 * root at the bottom); a part leaves the stack when a part outside its
 * subtree is added, and its end becomes that part's id. So "parent is open"
 * is the preorder check, in O(1). The hash table holds every part but the
 * root, at most half full. */
#include "part_tree.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* first sizes of the arrays (parts), the arena (bytes) and the hash table (slots) */
#define PART_TREE_FIRST_CAPACITY 64
#define PART_TREE_FIRST_ARENA 1024
#define PART_TREE_FIRST_SLOTS 128

struct part_tree {
    int32_t count;          /* parts, root included */
    int32_t capacity;       /* of the per-part arrays */
    uint32_t *name_offset;  /* into arena, per part */
    int32_t *parent;        /* per part; PART_NONE for the root */
    int32_t *end;           /* subtree end per part, 0 while open (see the top) */
    part_counts *counts;    /* the caller's, per part */
    uint32_t *next_suffix;  /* per part: the next "#N" to try for its name's duplicates (0: 2); NULL until needed */
    char *arena;            /* the names, each NUL-terminated */
    size_t arena_len, arena_cap;
    int32_t *slots;         /* part ids, -1 for empty; a power of two in size */
    uint32_t slot_mask;     /* size - 1 */
    int32_t *open;          /* the open stack: root first, last added part on top */
    int32_t open_count, open_cap;
};

/* FNV-1a over the name, the parent mixed in (a 32-bit finaliser, Murmur3's). */
static uint32_t hash_key(int32_t parent, const char *name, size_t len)
{
    uint32_t h = 2166136261u;
    for (size_t i = 0; i < len; i++)
        h = (h ^ (unsigned char)name[i]) * 16777619u;
    h ^= (uint32_t)parent * 0x9e3779b1u;
    h ^= h >> 16;
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    h ^= h >> 16;
    return h;
}

static const char *name_of(const part_tree *t, int32_t id) { return t->arena + t->name_offset[id]; }

/* The child of parent named name[0 .. len), or PART_NONE. */
static int32_t lookup(const part_tree *t, int32_t parent, const char *name, size_t len)
{
    for (uint32_t i = hash_key(parent, name, len) & t->slot_mask;; i = (i + 1) & t->slot_mask) {
        int32_t id = t->slots[i];
        if (id < 0)
            return PART_NONE;
        const char *s = name_of(t, id);
        if (t->parent[id] == parent && strncmp(s, name, len) == 0 && s[len] == '\0')
            return id;
    }
}

static void slot_insert(int32_t *slots, uint32_t mask, uint32_t hash, int32_t id)
{
    uint32_t i = hash & mask;
    while (slots[i] >= 0)
        i = (i + 1) & mask;
    slots[i] = id;
}

static bool grow_slots(part_tree *t)
{
    uint32_t size = 2 * (t->slot_mask + 1);
    int32_t *slots = malloc(size * sizeof *slots);
    if (!slots)
        return false;
    memset(slots, 0xff, size * sizeof *slots);
    for (int32_t id = 1; id < t->count; id++) {
        const char *s = name_of(t, id);
        slot_insert(slots, size - 1, hash_key(t->parent[id], s, strlen(s)), id);
    }
    free(t->slots);
    t->slots = slots;
    t->slot_mask = size - 1;
    return true;
}

/* realloc *array to n elements of `bytes` each. */
static bool resize(void **array, size_t n, size_t bytes)
{
    void *p = realloc(*array, n * bytes);
    if (!p)
        return false;
    *array = p;
    return true;
}

static bool grow_parts(part_tree *t)
{
    if (t->count < t->capacity)
        return true;
    int32_t cap = t->capacity ? 2 * t->capacity : PART_TREE_FIRST_CAPACITY;
    if (!resize((void **)&t->name_offset, (size_t)cap, sizeof *t->name_offset) ||
        !resize((void **)&t->parent, (size_t)cap, sizeof *t->parent) ||
        !resize((void **)&t->end, (size_t)cap, sizeof *t->end) ||
        !resize((void **)&t->counts, (size_t)cap, sizeof *t->counts))
        return false;
    if (t->next_suffix) {
        if (!resize((void **)&t->next_suffix, (size_t)cap, sizeof *t->next_suffix))
            return false;
        memset(t->next_suffix + t->capacity, 0, (size_t)(cap - t->capacity) * sizeof *t->next_suffix);
    }
    t->capacity = cap;
    return true;
}

/* Copy name into the arena; its offset, or UINT32_MAX when out of memory. */
static uint32_t intern(part_tree *t, const char *name, size_t len)
{
    if (t->arena_len + len + 1 > UINT32_MAX)
        return UINT32_MAX;
    if (t->arena_len + len + 1 > t->arena_cap) {
        size_t cap = t->arena_cap ? 2 * t->arena_cap : PART_TREE_FIRST_ARENA;
        while (cap < t->arena_len + len + 1)
            cap *= 2;
        if (!resize((void **)&t->arena, cap, 1))
            return UINT32_MAX;
        t->arena_cap = cap;
    }
    uint32_t offset = (uint32_t)t->arena_len;
    memcpy(t->arena + offset, name, len);
    t->arena[offset + len] = '\0';
    t->arena_len += len + 1;
    return offset;
}

static bool push_open(part_tree *t, int32_t id)
{
    if (t->open_count == t->open_cap) {
        int32_t cap = t->open_cap ? 2 * t->open_cap : 16;
        if (!resize((void **)&t->open, (size_t)cap, sizeof *t->open))
            return false;
        t->open_cap = cap;
    }
    t->open[t->open_count++] = id;
    return true;
}

part_tree *part_tree_create(void)
{
    part_tree *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->slots = malloc(PART_TREE_FIRST_SLOTS * sizeof *t->slots);
    if (!t->slots || !grow_parts(t) || intern(t, "", 0) == UINT32_MAX || !push_open(t, PART_ROOT)) {
        part_tree_destroy(t);
        return NULL;
    }
    memset(t->slots, 0xff, PART_TREE_FIRST_SLOTS * sizeof *t->slots);
    t->slot_mask = PART_TREE_FIRST_SLOTS - 1;
    t->name_offset[PART_ROOT] = 0;
    t->parent[PART_ROOT] = PART_NONE;
    t->end[PART_ROOT] = 0;
    t->counts[PART_ROOT] = (part_counts){0};
    t->count = 1;
    return t;
}

void part_tree_destroy(part_tree *t)
{
    if (!t)
        return;
    free(t->name_offset);
    free(t->parent);
    free(t->end);
    free(t->counts);
    free(t->next_suffix);
    free(t->arena);
    free(t->slots);
    free(t->open);
    free(t);
}

/* The checks of part_tree_add but the sibling's; name is len bytes. */
static bool check_add(const part_tree *t, int32_t parent, const char *name, size_t len, tess_error *err)
{
    if (parent < 0 || parent >= t->count)
        return tess_error_set(err, "part '%.100s': parent %ld does not exist (%ld parts)", name, (long)parent,
                              (long)t->count);
    if (t->end[parent] != 0)
        return tess_error_set(err, "part '%.100s': parent %ld's subtree is closed (parts must be added in "
                                   "preorder: the parent must be the last added part or one of its ancestors)",
                              name, (long)parent);
    if (len == 0)
        return tess_error_set(err, "a part of parent %ld has an empty name", (long)parent);
    if (len >= PART_NAME_MAX_BYTES)
        return tess_error_set(err, "part '%.100s...': name of %zu bytes (at most %d)", name, len,
                              PART_NAME_MAX_BYTES - 1);
    if (memchr(name, '/', len))
        return tess_error_set(err, "part '%.100s': a name may not hold '/'", name);
    if (t->count >= PART_MAX_COUNT)
        return tess_error_set(err, "part '%.100s': more than %d parts", name, PART_MAX_COUNT);
    return true;
}

/* Add a part whose name passed check_add and is free among its siblings. */
static int32_t add_checked(part_tree *t, int32_t parent, const char *name, size_t len, tess_error *err)
{
    if ((uint32_t)t->count + 1 > (t->slot_mask + 1) / 2 && !grow_slots(t))
        goto oom;
    if (!grow_parts(t))
        goto oom;
    uint32_t offset = intern(t, name, len);
    if (offset == UINT32_MAX || !push_open(t, t->count)) /* room first; the push is undone below */
        goto oom;
    t->open_count--;
    int32_t id = t->count;
    while (t->open[t->open_count - 1] != parent) /* parent is open, so on the stack */
        t->end[t->open[--t->open_count]] = id;
    t->open[t->open_count++] = id;
    t->name_offset[id] = offset;
    t->parent[id] = parent;
    t->end[id] = 0;
    t->counts[id] = (part_counts){0};
    if (t->next_suffix)
        t->next_suffix[id] = 0;
    slot_insert(t->slots, t->slot_mask, hash_key(parent, name, len), id);
    t->count++;
    return id;
oom:
    tess_error_set(err, "part '%.100s': out of memory (%ld parts)", name, (long)t->count);
    return PART_NONE;
}

int32_t part_tree_add(part_tree *t, int32_t parent, const char *name, tess_error *err)
{
    size_t len = strlen(name);
    if (!check_add(t, parent, name, len, err))
        return PART_NONE;
    if (lookup(t, parent, name, len) != PART_NONE) {
        tess_error_set(err, "part '%.100s': parent %ld already has a child of that name", name, (long)parent);
        return PART_NONE;
    }
    return add_checked(t, parent, name, len, err);
}

int32_t part_tree_add_unique(part_tree *t, int32_t parent, const char *name, tess_error *err)
{
    size_t len = strlen(name);
    if (!check_add(t, parent, name, len, err))
        return PART_NONE;
    int32_t first = lookup(t, parent, name, len);
    if (first == PART_NONE)
        return add_checked(t, parent, name, len, err);
    if (!t->next_suffix && !(t->next_suffix = calloc((size_t)t->capacity, sizeof *t->next_suffix))) {
        tess_error_set(err, "part '%.100s': out of memory (%ld parts)", name, (long)t->count);
        return PART_NONE;
    }
    /* numbers below next_suffix[first] are taken; the loop passes names
     * that were themselves given as "name#N" */
    char unique[PART_NAME_MAX_BYTES + 16];
    uint32_t n = t->next_suffix[first] ? t->next_suffix[first] : 2;
    int ulen;
    for (;; n++) {
        ulen = snprintf(unique, sizeof unique, "%s#%u", name, (unsigned)n);
        if (ulen >= PART_NAME_MAX_BYTES) {
            tess_error_set(err, "part '%.100s...': name of %d bytes with its suffix (at most %d)", name, ulen,
                           PART_NAME_MAX_BYTES - 1);
            return PART_NONE;
        }
        if (lookup(t, parent, unique, (size_t)ulen) == PART_NONE)
            break;
    }
    t->next_suffix[first] = n + 1;
    return add_checked(t, parent, unique, (size_t)ulen, err);
}

int32_t part_tree_count(const part_tree *t) { return t->count; }

const char *part_tree_name(const part_tree *t, int32_t id) { return name_of(t, id); }

int32_t part_tree_parent(const part_tree *t, int32_t id) { return t->parent[id]; }

int32_t part_tree_subtree_end(const part_tree *t, int32_t id) { return t->end[id] ? t->end[id] : t->count; }

int part_tree_depth(const part_tree *t, int32_t id)
{
    int depth = 0;
    for (; id != PART_ROOT; id = t->parent[id])
        depth++;
    return depth;
}

int32_t part_tree_child(const part_tree *t, int32_t parent, const char *name)
{
    return lookup(t, parent, name, strlen(name));
}

size_t part_tree_path(const part_tree *t, int32_t id, char *buf, size_t size)
{
    size_t total = 0;
    for (int32_t p = id; p != PART_ROOT; p = t->parent[p])
        total += strlen(name_of(t, p)) + (t->parent[p] != PART_ROOT);
    if (size == 0)
        return total;
    /* fill from the end; bytes at or past size - 1 are dropped */
    size_t at = total;
    for (int32_t p = id; p != PART_ROOT; p = t->parent[p]) {
        const char *s = name_of(t, p);
        size_t n = strlen(s);
        at -= n;
        for (size_t k = 0; k < n; k++)
            if (at + k < size - 1)
                buf[at + k] = s[k];
        if (t->parent[p] != PART_ROOT && --at < size - 1)
            buf[at] = '/';
    }
    buf[total < size - 1 ? total : size - 1] = '\0';
    return total;
}

int32_t part_tree_find(const part_tree *t, const char *path)
{
    int32_t id = PART_ROOT;
    if (*path == '\0')
        return id;
    for (const char *s = path;;) {
        size_t n = strcspn(s, "/");
        if (n == 0 || (id = lookup(t, id, s, n)) == PART_NONE)
            return PART_NONE;
        if (s[n] == '\0')
            return id;
        s += n + 1;
    }
}

part_counts *part_tree_counts(part_tree *t, int32_t id) { return &t->counts[id]; }

const part_counts *part_tree_counts_const(const part_tree *t, int32_t id) { return &t->counts[id]; }

/* ---- patterns ------------------------------------------------------------ */

/* Does the segment pattern p[0 .. pn) ('*', '?') match s[0 .. sn)? Greedy
 * with one backtrack point: the last '*'. */
static bool segment_match(const char *p, size_t pn, const char *s, size_t sn)
{
    size_t pi = 0, si = 0, star = SIZE_MAX, mark = 0;
    while (si < sn) {
        if (pi < pn && (p[pi] == '?' || p[pi] == s[si])) {
            pi++;
            si++;
        } else if (pi < pn && p[pi] == '*') {
            star = pi++;
            mark = si;
        } else if (star != SIZE_MAX) {
            pi = star + 1;
            si = ++mark;
        } else {
            return false;
        }
    }
    while (pi < pn && p[pi] == '*')
        pi++;
    return pi == pn;
}

/* The segments p (pattern) and s (path) onwards; "" is no segments left. */
static bool glob_from(const char *p, const char *s)
{
    for (;;) {
        if (*p == '\0')
            return *s == '\0';
        size_t pn = strcspn(p, "/");
        if (pn == 2 && p[0] == '*' && p[1] == '*') {
            const char *rest = p[2] == '/' ? p + 3 : p + 2;
            if (*rest == '\0') /* a last "**" takes whatever is left */
                return true;
            for (const char *q = s;;) { /* "**" takes 0, 1, 2, ... segments */
                if (glob_from(rest, q))
                    return true;
                if (*q == '\0')
                    return false;
                size_t qn = strcspn(q, "/");
                q += q[qn] == '/' ? qn + 1 : qn;
            }
        }
        if (*s == '\0')
            return false;
        size_t sn = strcspn(s, "/");
        if (!segment_match(p, pn, s, sn))
            return false;
        p += p[pn] == '/' ? pn + 1 : pn;
        s += s[sn] == '/' ? sn + 1 : sn;
    }
}

bool part_glob_match(const char *pattern, const char *path) { return glob_from(pattern, path); }

long part_tree_match(const part_tree *t, const char *pattern, part_match_fn fn, void *ctx)
{
    /* paths are built incrementally along the preorder: stack[d] is the
     * open ancestor at depth d and lens[d] the length of its path */
    size_t cap = 256, depth_cap = 16, depth = 1;
    char *path = malloc(cap);
    int32_t *stack = malloc(depth_cap * sizeof *stack);
    size_t *lens = malloc(depth_cap * sizeof *lens);
    long matched = -1;
    if (!path || !stack || !lens)
        goto done;
    stack[0] = PART_ROOT;
    lens[0] = 0;
    path[0] = '\0';
    matched = 0;
    for (int32_t id = 1; id < t->count; id++) {
        while (stack[depth - 1] != t->parent[id])
            depth--;
        const char *name = name_of(t, id);
        size_t n = strlen(name), at = lens[depth - 1] + (depth > 1);
        if (at + n + 1 > cap) {
            while (at + n + 1 > cap)
                cap *= 2;
            if (!resize((void **)&path, cap, 1)) {
                matched = -1;
                goto done;
            }
        }
        if (depth == depth_cap) {
            depth_cap *= 2;
            if (!resize((void **)&stack, depth_cap, sizeof *stack) || !resize((void **)&lens, depth_cap, sizeof *lens)) {
                matched = -1;
                goto done;
            }
        }
        if (depth > 1)
            path[at - 1] = '/';
        memcpy(path + at, name, n + 1);
        stack[depth] = id;
        lens[depth++] = at + n;
        if (glob_from(pattern, path)) {
            matched++;
            if (!fn(ctx, id, path))
                break;
        }
    }
done:
    free(path);
    free(stack);
    free(lens);
    return matched;
}

size_t part_tree_bytes(const part_tree *t)
{
    size_t per_part = sizeof *t->name_offset + sizeof *t->parent + sizeof *t->end + sizeof *t->counts +
                      (t->next_suffix ? sizeof *t->next_suffix : 0);
    return sizeof *t + (size_t)t->capacity * per_part + t->arena_cap + (t->slot_mask + 1) * sizeof *t->slots +
           (size_t)t->open_cap * sizeof *t->open;
}
