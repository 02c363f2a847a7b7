/* test_cache_file.c - the acceleration-structure cache's file (engine/base/cache_file.h): a
 * written file opens with every section's bytes, 64-byte aligned; every way a file can be
 * wrong (another key, another version, truncated, extended, empty, not a cache, a flipped
 * byte anywhere, a table that lies with valid checksums) is refused with its own status and a
 * message naming the file; a write that cannot happen fails with a message and leaves
 * nothing; concurrent writers of one key leave one whole file; keys and paths.
 *
 * Every test works in a fresh mkdtemp directory, removed afterwards. */
#define _GNU_SOURCE /* mkdtemp, setenv */
#include <criterion/criterion.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include "engine/base/cache_file.h"
#include "support.h"

static char tmp_dir[256];
static char cache_path[512];

static void make_tmp_dir(void)
{
    support_make_tmp_dir(tmp_dir, sizeof tmp_dir, "cache");
    snprintf(cache_path, sizeof cache_path, "%s/model.tcache", tmp_dir);
}

static void remove_tmp_dir(void)
{
    /* a test may leave a read-only directory behind */
    char cmd[600];
    snprintf(cmd, sizeof cmd, "chmod -R u+w '%s' 2>/dev/null", tmp_dir);
    (void)system(cmd);
    support_remove_tmp_dir(tmp_dir);
}

TestSuite(cache_file, .init = make_tmp_dir, .fini = remove_tmp_dir);

static const cache_key KEY = {.lo = 0x0123456789abcdefull, .hi = 0xfedcba9876543210ull};
#define VERSION 3u

typedef struct node32 {
    float lo[3], hi[3];
    uint32_t child, count;
} node32;

/* Sample arrays of awkward sizes (none a multiple of 64 bytes), one empty; filled from seed. */
typedef struct sample {
    float verts[3 * 1001];
    uint32_t indices[3 * 777];
    node32 nodes[333];
    unsigned char odd[13];
    cache_section_source sections[5];
} sample;

static void sample_fill(sample *s, uint32_t seed)
{
    uint32_t x = seed * 2654435761u + 1u;
#define NEXT() (x ^= x << 13, x ^= x >> 17, x ^= x << 5, x)
    for (size_t i = 0; i < sizeof s->verts / sizeof s->verts[0]; i++)
        s->verts[i] = (float)(NEXT() % 100000) * 0.01f;
    for (size_t i = 0; i < sizeof s->indices / sizeof s->indices[0]; i++)
        s->indices[i] = NEXT() % 1001u;
    for (size_t i = 0; i < sizeof s->nodes / sizeof s->nodes[0]; i++) {
        for (int k = 0; k < 3; k++) {
            s->nodes[i].lo[k] = (float)(NEXT() % 1000);
            s->nodes[i].hi[k] = s->nodes[i].lo[k] + 1.0f;
        }
        s->nodes[i].child = NEXT();
        s->nodes[i].count = NEXT() % 8u;
    }
    for (size_t i = 0; i < sizeof s->odd; i++)
        s->odd[i] = (unsigned char)NEXT();
#undef NEXT
    s->sections[0] = (cache_section_source){"verts", s->verts, sizeof(float), sizeof s->verts / sizeof(float)};
    s->sections[1] = (cache_section_source){"indices", s->indices, sizeof(uint32_t), 3 * 777};
    s->sections[2] = (cache_section_source){"nodes", s->nodes, sizeof(node32), 333};
    s->sections[3] = (cache_section_source){"empty", NULL, 8, 0};
    s->sections[4] = (cache_section_source){"odd-bytes.15chr", s->odd, 1, sizeof s->odd};
}

static sample *sample_new(uint32_t seed)
{
    sample *s = malloc(sizeof *s);
    cr_assert(s);
    sample_fill(s, seed);
    return s;
}

static void write_sample(const char *path, const sample *s)
{
    tess_error err = {0};
    cr_assert(cache_write(path, KEY, VERSION, s->sections, 5, &err), "cache_write: %s", err.msg);
}

/* A file's bytes (caller frees); *bytes_out its size. */
static unsigned char *read_all(const char *path, size_t *bytes_out)
{
    FILE *f = fopen(path, "rb");
    cr_assert(f, "open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(n > 0 ? (size_t)n : 1);
    cr_assert(b);
    cr_assert_eq(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *bytes_out = (size_t)n;
    return b;
}

static void write_all(const char *path, const void *bytes, size_t n)
{
    FILE *f = fopen(path, "wb");
    cr_assert(f, "open %s", path);
    cr_assert_eq(fwrite(bytes, 1, n, f), n);
    cr_assert_eq(fclose(f), 0);
}

/* Open path expecting status want and (when want is not CACHE_OK) a message naming the file
 * and containing needle (NULL: anything). */
static void expect_open(const char *path, cache_key key, uint32_t version, cache_status want, const char *needle,
                        const char *what)
{
    tess_error err = {0};
    cache_file *c = (cache_file *)1;
    cache_status s = cache_open(path, key, version, &c, &err);
    cr_assert_eq(s, want, "%s: status %s, expected %s (%s)", what, cache_status_name(s), cache_status_name(want),
                 err.msg);
    if (want == CACHE_OK) {
        cr_assert_not_null(c);
        cache_close(c);
        return;
    }
    cr_assert_null(c, "%s: no cache on failure", what);
    cr_assert(strstr(err.msg, path), "%s: the message names the file: %s", what, err.msg);
    cr_assert(strncmp(err.msg, "cache ", 6) == 0, "%s: %s", what, err.msg);
    if (needle)
        cr_assert(strstr(err.msg, needle), "%s: message '%s' lacks '%s'", what, err.msg, needle);
}

/* Recompute the table's and the header's checksums after an edit, so only the structural
 * checks can find it. */
static void reseal(unsigned char *file)
{
    cache_file_header h;
    memcpy(&h, file, sizeof h);
    if (h.section_count <= CACHE_MAX_SECTIONS)
        h.table_checksum = XXH3_64bits(file + sizeof h, h.section_count * sizeof(cache_section_entry));
    h.header_checksum = XXH3_64bits(&h, offsetof(cache_file_header, header_checksum));
    memcpy(file, &h, sizeof h);
}

static cache_section_entry *entry(unsigned char *file, size_t i)
{
    return (cache_section_entry *)(file + sizeof(cache_file_header) + i * sizeof(cache_section_entry));
}

/* ---------------------------------------------------------------- round trips */

Test(cache_file, round_trip_every_section_byte_exact_and_aligned)
{
    sample *s = sample_new(1);
    write_sample(cache_path, s);
    tess_error err = {0};
    cache_file *c = NULL;
    cr_assert_eq(cache_open(cache_path, KEY, VERSION, &c, &err), CACHE_OK, "%s", err.msg);
    cr_assert_eq(cache_section_count(c), 5);
    struct stat st;
    cr_assert_eq(stat(cache_path, &st), 0);
    cr_assert_eq(cache_file_bytes(c), (uint64_t)st.st_size);
    cr_assert_eq(st.st_mode & 0777, 0644);

    for (size_t i = 0; i < 5; i++) {
        const cache_section_source *src = &s->sections[i];
        size_t count = 12345;
        const void *p = cache_section(c, src->tag, src->element_bytes, &count, &err);
        cr_assert_not_null(p, "section %s: %s", src->tag, err.msg);
        cr_assert_eq((uintptr_t)p % CACHE_SECTION_ALIGN, 0, "section %s at %p is not 64-byte aligned", src->tag, p);
        cr_assert_eq(count, src->element_count, "section %s", src->tag);
        if (count)
            cr_assert_eq(memcmp(p, src->data, count * src->element_bytes), 0, "section %s bytes", src->tag);
        cache_section_info info = cache_section_at(c, i); /* in the order written */
        cr_assert_str_eq(info.tag, src->tag);
        cr_assert(info.data == p && info.element_bytes == src->element_bytes &&
                  info.element_count == src->element_count && info.bytes == count * src->element_bytes);
    }

    /* the wrong element size (a layout changed without a version change) and a missing tag */
    cr_assert_null(cache_section(c, "nodes", 48, NULL, &err));
    cr_assert(strstr(err.msg, "section 'nodes' has 32-byte elements, expected 48"), "%s", err.msg);
    tess_error err2 = {0};
    cr_assert_null(cache_section(c, "normals", 12, NULL, &err2));
    cr_assert(strstr(err2.msg, "no section 'normals'") && strstr(err2.msg, cache_path), "%s", err2.msg);
    cache_close(c);
    cache_close(NULL);
    free(s);
}

Test(cache_file, a_cache_without_sections_opens)
{
    tess_error err = {0};
    cr_assert(cache_write(cache_path, KEY, VERSION, NULL, 0, &err), "%s", err.msg);
    cache_file *c = NULL;
    cr_assert_eq(cache_open(cache_path, KEY, VERSION, &c, &err), CACHE_OK, "%s", err.msg);
    cr_assert_eq(cache_section_count(c), 0);
    cr_assert_eq(cache_file_bytes(c), sizeof(cache_file_header));
    cache_close(c);
}

Test(cache_file, a_rewrite_replaces_the_file_whole)
{
    sample *a = sample_new(1), *b = sample_new(2);
    write_sample(cache_path, a);
    write_sample(cache_path, b);
    tess_error err = {0};
    cache_file *c = NULL;
    cr_assert_eq(cache_open(cache_path, KEY, VERSION, &c, &err), CACHE_OK, "%s", err.msg);
    size_t n = 0;
    const node32 *nodes = cache_section(c, "nodes", sizeof(node32), &n, &err);
    cr_assert_eq(n, 333);
    cr_assert_eq(memcmp(nodes, b->nodes, sizeof b->nodes), 0);
    cache_close(c);
    free(a);
    free(b);
}

/* ---------------------------------------------------------------- every refusal */

Test(cache_file, missing_file_is_missing_not_an_error)
{
    expect_open(cache_path, KEY, VERSION, CACHE_MISSING, "none yet", "missing");
}

Test(cache_file, another_key_is_stale)
{
    sample *s = sample_new(1);
    write_sample(cache_path, s);
    cache_key other = KEY;
    other.hi ^= 1;
    expect_open(cache_path, other, VERSION, CACHE_STALE, "stale (its key does not match", "key.hi");
    other = KEY;
    other.lo ^= 1u << 31;
    expect_open(cache_path, other, VERSION, CACHE_STALE, "stale", "key.lo");
    free(s);
}

Test(cache_file, another_content_version_is_refused)
{
    sample *s = sample_new(1);
    tess_error err = {0};
    cr_assert(cache_write(cache_path, KEY, 2, s->sections, 5, &err), "%s", err.msg);
    expect_open(cache_path, KEY, 3, CACHE_VERSION, "written by format version 2, this is 3", "version");
    free(s);
}

Test(cache_file, another_format_version_or_byte_order_is_refused)
{
    sample *s = sample_new(1);
    write_sample(cache_path, s);
    size_t n;
    unsigned char *file = read_all(cache_path, &n);
    cache_file_header h;
    memcpy(&h, file, sizeof h);

    h.format_version = CACHE_FILE_FORMAT_VERSION + 1;
    memcpy(file, &h, sizeof h);
    reseal(file);
    write_all(cache_path, file, n);
    expect_open(cache_path, KEY, VERSION, CACHE_FORMAT_VERSION, "cache file format version 2, this reads 1",
                "format version");

    h.format_version = CACHE_FILE_FORMAT_VERSION;
    h.byte_order = __builtin_bswap32(CACHE_BYTE_ORDER_MARK);
    memcpy(file, &h, sizeof h);
    reseal(file);
    write_all(cache_path, file, n);
    expect_open(cache_path, KEY, VERSION, CACHE_BYTE_ORDER, "other byte order", "byte order");
    free(file);
    free(s);
}

Test(cache_file, truncated_extended_and_empty_files_are_refused)
{
    sample *s = sample_new(1);
    write_sample(cache_path, s);
    size_t n;
    unsigned char *file = read_all(cache_path, &n);
    char what[64];

    size_t cuts[] = {n - 1, n - 13, n / 2, 1000, sizeof(cache_file_header)};
    for (size_t i = 0; i < sizeof cuts / sizeof cuts[0]; i++) {
        write_all(cache_path, file, cuts[i]);
        char needle[128];
        snprintf(needle, sizeof needle, "truncated: %zu bytes, its header says %zu", cuts[i], n);
        snprintf(what, sizeof what, "cut to %zu", cuts[i]);
        expect_open(cache_path, KEY, VERSION, CACHE_SIZE, needle, what);
    }
    /* shorter than the header: a prefix of the magic is a truncated cache, else not one */
    size_t short_cuts[] = {127, 64, 8, 7, 1};
    for (size_t i = 0; i < sizeof short_cuts / sizeof short_cuts[0]; i++) {
        write_all(cache_path, file, short_cuts[i]);
        snprintf(what, sizeof what, "cut to %zu", short_cuts[i]);
        expect_open(cache_path, KEY, VERSION, CACHE_SIZE, "shorter than its 128-byte header", what);
    }
    write_all(cache_path, file, 0);
    expect_open(cache_path, KEY, VERSION, CACHE_SIZE, "empty (0 bytes)", "empty");

    unsigned char *longer = calloc(1, n + 100);
    cr_assert(longer);
    memcpy(longer, file, n);
    write_all(cache_path, longer, n + 100);
    expect_open(cache_path, KEY, VERSION, CACHE_SIZE, "extra bytes at the end", "extended");
    free(longer);
    free(file);
    free(s);
}

Test(cache_file, other_files_are_not_caches)
{
    const char ply[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n"
                       "0 0 0\n1 0 0\n0 1 0\n"
                       "................................................................................";
    write_all(cache_path, ply, sizeof ply - 1);
    expect_open(cache_path, KEY, VERSION, CACHE_NOT_A_CACHE, "not a tessera cache file", "a PLY file");
    write_all(cache_path, "TSR", 3);
    expect_open(cache_path, KEY, VERSION, CACHE_SIZE, "truncated: 3 bytes", "the magic's start");
    write_all(cache_path, "PLY", 3);
    expect_open(cache_path, KEY, VERSION, CACHE_NOT_A_CACHE, NULL, "3 other bytes");
    cr_assert_eq(unlink(cache_path), 0);
    cr_assert_eq(mkdir(cache_path, 0755), 0);
    expect_open(cache_path, KEY, VERSION, CACHE_UNREADABLE, "not a regular file", "a directory");
}

/* Flip one byte at every offset of a small file in turn: each is refused; offsets in the
 * header and table as the header or table, between sections and in sections as a section. */
Test(cache_file, a_flipped_byte_anywhere_is_found)
{
    unsigned char a[5] = {1, 2, 3, 4, 5}, b[70], c[64];
    for (size_t i = 0; i < sizeof b; i++)
        b[i] = (unsigned char)(i * 7);
    for (size_t i = 0; i < sizeof c; i++)
        c[i] = (unsigned char)(255 - i);
    cache_section_source secs[3] = {{"a", a, 1, 5}, {"b", b, 2, 35}, {"c", c, 8, 8}};
    tess_error err = {0};
    cr_assert(cache_write(cache_path, KEY, VERSION, secs, 3, &err), "%s", err.msg);
    size_t n;
    unsigned char *file = read_all(cache_path, &n);
    uint64_t first_section = entry(file, 0)->offset;
    cr_assert_eq(first_section, 320); /* 128 + 3 x 64 = 320, already aligned */

    for (size_t at = 0; at < n; at++) {
        for (int bit = 0; bit < 8; bit += 7) { /* the low and the high bit */
            file[at] ^= (unsigned char)(1u << bit);
            write_all(cache_path, file, n);
            file[at] ^= (unsigned char)(1u << bit);
            cache_file *cf = NULL;
            tess_error e = {0};
            cache_status s = cache_open(cache_path, KEY, VERSION, &cf, &e);
            cr_assert_neq(s, CACHE_OK, "a flipped bit %d at offset %zu went unnoticed", bit, at);
            cr_assert_null(cf);
            cr_assert(strstr(e.msg, cache_path), "offset %zu: %s", at, e.msg);
            if (at >= 16 && at < sizeof(cache_file_header)) /* past magic, byte order, format version */
                cr_assert_eq(s, CACHE_CORRUPT_HEADER, "offset %zu: %s", at, e.msg);
            else if (at >= sizeof(cache_file_header) && at < first_section)
                cr_assert_eq(s, CACHE_CORRUPT_HEADER, "offset %zu: %s", at, e.msg);
            else if (at >= first_section)
                cr_assert_eq(s, CACHE_CORRUPT_SECTION, "offset %zu: %s", at, e.msg);
            if (at >= first_section && at < first_section + 5)
                cr_assert(strstr(e.msg, "section 'a' checksum mismatch"), "offset %zu: %s", at, e.msg);
            if (at >= first_section + 5 && at < first_section + 64)
                cr_assert(strstr(e.msg, "nonzero byte between sections"), "offset %zu: %s", at, e.msg);
        }
    }
    free(file);
}

Test(cache_file, a_flipped_byte_in_each_large_section_names_it)
{
    sample *s = sample_new(1);
    write_sample(cache_path, s);
    size_t n;
    unsigned char *file = read_all(cache_path, &n);
    for (size_t i = 0; i < 5; i++) {
        const cache_section_entry *e = entry(file, i);
        if (e->bytes == 0)
            continue;
        uint64_t ats[3] = {e->offset, e->offset + e->bytes / 2, e->offset + e->bytes - 1};
        for (int k = 0; k < 3; k++) {
            file[ats[k]] ^= 0x40;
            write_all(cache_path, file, n);
            file[ats[k]] ^= 0x40;
            char needle[64], what[64];
            snprintf(needle, sizeof needle, "corrupt (section '%s' checksum mismatch)", e->tag);
            snprintf(what, sizeof what, "section %s byte %llu", e->tag, (unsigned long long)ats[k]);
            expect_open(cache_path, KEY, VERSION, CACHE_CORRUPT_SECTION, needle, what);
        }
    }
    write_all(cache_path, file, n);
    expect_open(cache_path, KEY, VERSION, CACHE_OK, NULL, "restored");
    free(file);
    free(s);
}

/* A table that lies but carries valid checksums (a bug in a writer, or a crafted file): the
 * structural checks refuse it before any section is touched. */
Test(cache_file, a_lying_table_with_valid_checksums_is_refused)
{
    sample *s = sample_new(1);
    write_sample(cache_path, s);
    size_t n;
    unsigned char *orig = read_all(cache_path, &n);
    unsigned char *file = calloc(1, n + 64);
    cr_assert(file);

    struct edit {
        const char *what, *needle;
    } edits[] = {
        {"a section past the end", "runs past the end of the file"},
        {"huge byte count", "element size x count"},
        {"unaligned offset", "does not start at the next aligned offset"},
        {"overlapping sections", "does not start at the next aligned offset"},
        {"count overflows", "element size x count"},
        {"zero element size", "element size x count"},
        {"empty tag", "tag is not"},
        {"unterminated tag", "tag has no end"},
        {"repeated tag", "tag is used twice"},
        {"reserved field", "reserved field"},
        {"too many sections", "do not fit"},
        {"offset beyond the file", "does not start at the next aligned offset"},
        {"fewer sections", "does not start at the next aligned offset"},
        {"a gap after the last section", "its sections end at"},
    };
    for (size_t k = 0; k < sizeof edits / sizeof edits[0]; k++) {
        memset(file, 0, n + 64);
        memcpy(file, orig, n);
        size_t file_bytes = n;
        cache_section_entry *last = entry(file, 4), *nodes = entry(file, 2), *verts = entry(file, 0);
        cache_file_header h;
        memcpy(&h, file, sizeof h);
        switch (k) {
        case 0: last->bytes = last->element_count = n; break;
        case 1: last->bytes = (uint64_t)1 << 40; break;
        case 2: nodes->offset += 8; break;
        case 3: nodes->offset = verts->offset; break;
        case 4:
            nodes->element_count = UINT64_MAX / 2;
            nodes->element_bytes = 4;
            break;
        case 5: nodes->element_bytes = 0; break;
        case 6: memset(nodes->tag, 0, sizeof nodes->tag); break;
        case 7: memset(nodes->tag, 'n', sizeof nodes->tag); break;
        case 8: memcpy(nodes->tag, "verts", 6); break;
        case 9: nodes->reserved = 1; break;
        case 10: h.section_count = CACHE_MAX_SECTIONS + 1; break;
        case 11: last->offset = n + 64; break;
        case 12: h.section_count = 3; break;
        case 13:
            h.file_bytes = n + 64;
            file_bytes = n + 64;
            break;
        }
        if (k >= 10)
            memcpy(file, &h, sizeof h);
        reseal(file);
        write_all(cache_path, file, file_bytes);
        expect_open(cache_path, KEY, VERSION, CACHE_BAD_TABLE, edits[k].needle, edits[k].what);
    }
    free(file);
    free(orig);
    free(s);
}

/* ---------------------------------------------------------------- writes that cannot happen */

static size_t dir_entries(const char *dir)
{
    DIR *d = opendir(dir);
    cr_assert(d, "opendir %s", dir);
    size_t n = 0;
    for (struct dirent *e; (e = readdir(d));)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0)
            n++;
    closedir(d);
    return n;
}

Test(cache_file, a_write_that_cannot_happen_fails_with_a_message)
{
    sample *s = sample_new(1);
    /* a regular file where a directory should be: fails even for root */
    char blocker[600], path[700];
    snprintf(blocker, sizeof blocker, "%s/blocker", tmp_dir);
    write_all(blocker, "x", 1);
    snprintf(path, sizeof path, "%s/sub/model.tcache", blocker);
    tess_error err = {0};
    cr_assert_not(cache_write(path, KEY, VERSION, s->sections, 5, &err));
    cr_assert(strstr(err.msg, "not written") && strstr(err.msg, path), "%s", err.msg);
    cr_assert(strstr(err.msg, "Not a directory"), "%s", err.msg);
    cr_assert_eq(dir_entries(tmp_dir), 1, "nothing left behind");

    /* a read-only directory (root ignores the mode: then only the first case applies) */
    if (geteuid() != 0) {
        char ro[600], ro_path[700];
        snprintf(ro, sizeof ro, "%s/ro", tmp_dir);
        cr_assert_eq(mkdir(ro, 0555), 0);
        snprintf(ro_path, sizeof ro_path, "%s/model.tcache", ro);
        tess_error err2 = {0};
        cr_assert_not(cache_write(ro_path, KEY, VERSION, s->sections, 5, &err2));
        cr_assert(strstr(err2.msg, "Permission denied") && strstr(err2.msg, ro_path), "%s", err2.msg);
        cr_assert_eq(dir_entries(ro), 0);
    }

    /* the path is a directory: the rename fails, the temporary goes */
    char dir_path[600];
    snprintf(dir_path, sizeof dir_path, "%s/is-a-dir.tcache", tmp_dir);
    cr_assert_eq(mkdir(dir_path, 0755), 0);
    tess_error err3 = {0};
    cr_assert_not(cache_write(dir_path, KEY, VERSION, s->sections, 5, &err3));
    cr_assert(strstr(err3.msg, "renaming it into place"), "%s", err3.msg);
    cr_assert_eq(dir_entries(tmp_dir), geteuid() != 0 ? 3u : 2u, "blocker, ro and the directory only (%s)",
                 err3.msg);
    free(s);
}

Test(cache_file, bad_sections_are_refused_before_anything_is_written)
{
    uint32_t x[4] = {0};
    struct {
        cache_section_source secs[2];
        const char *needle;
    } cases[] = {
        {{{"a", x, 4, 4}, {"a", x, 4, 4}}, "tag is used twice"},
        {{{"a", x, 4, 4}, {"", x, 4, 4}}, "tag is not"},
        {{{"a", x, 4, 4}, {"sixteen-chars-xx", x, 4, 4}}, "tag is not"},
        {{{"a", x, 4, 4}, {"has space", x, 4, 4}}, "tag is not"},
        {{{"a", x, 4, 4}, {NULL, x, 4, 4}}, "tag is not"},
        {{{"a", x, 0, 4}, {"b", x, 4, 4}}, "element size is 0"},
        {{{"a", x, 4, 4}, {"b", NULL, 4, 4}}, "data is NULL"},
        {{{"a", x, 4, 4}, {"b", x, SIZE_MAX / 2, 4}}, "too large"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        tess_error err = {0};
        cr_assert_not(cache_write(cache_path, KEY, VERSION, cases[k].secs, 2, &err), "case %zu", k);
        cr_assert(strstr(err.msg, cases[k].needle) && strstr(err.msg, cache_path), "case %zu: %s", k, err.msg);
    }
    cr_assert_eq(dir_entries(tmp_dir), 0);
}

Test(cache_file, missing_directories_are_made)
{
    sample *s = sample_new(1);
    char path[700], dir[600];
    snprintf(dir, sizeof dir, "%s/a/b/c", tmp_dir);
    snprintf(path, sizeof path, "%s/model.tcache", dir);
    write_sample(path, s);
    struct stat st;
    cr_assert_eq(stat(dir, &st), 0);
    cr_assert(S_ISDIR(st.st_mode));
    expect_open(path, KEY, VERSION, CACHE_OK, NULL, "in made directories");
    free(s);
}

/* ---------------------------------------------------------------- concurrent writers */

#define WRITERS 4
#define WRITES_EACH 12

typedef struct writer_arg {
    const char *path;
    uint32_t seed;
    sample *s;
    int failures;
} writer_arg;

static void *writer_main(void *p)
{
    writer_arg *a = p;
    for (int i = 0; i < WRITES_EACH; i++) {
        tess_error err = {0};
        if (!cache_write(a->path, KEY, VERSION, a->s->sections, 5, &err))
            a->failures++;
    }
    return NULL;
}

typedef struct reader_arg {
    const char *path;
    _Atomic int stop;
    int opened, bad;
    char bad_msg[TESS_ERROR_MSG_BYTES];
} reader_arg;

/* Open again and again while the writers run: only ever missing (before the first rename) or
 * whole (some writer's file). */
static void *reader_main(void *p)
{
    reader_arg *r = p;
    while (!r->stop) {
        cache_file *c = NULL;
        tess_error err = {0};
        cache_status s = cache_open(r->path, KEY, VERSION, &c, &err);
        if (s == CACHE_OK) {
            r->opened++;
            cache_close(c);
        } else if (s != CACHE_MISSING && !r->bad++) {
            memcpy(r->bad_msg, err.msg, sizeof r->bad_msg);
        }
    }
    return NULL;
}

Test(cache_file, concurrent_writers_of_one_key_leave_one_whole_file)
{
    writer_arg w[WRITERS];
    pthread_t wt[WRITERS], rt;
    reader_arg r = {.path = cache_path};
    cr_assert_eq(pthread_create(&rt, NULL, reader_main, &r), 0);
    for (int i = 0; i < WRITERS; i++) {
        w[i] = (writer_arg){.path = cache_path, .seed = (uint32_t)i + 10, .s = sample_new((uint32_t)i + 10)};
        cr_assert_eq(pthread_create(&wt[i], NULL, writer_main, &w[i]), 0);
    }
    for (int i = 0; i < WRITERS; i++) {
        pthread_join(wt[i], NULL);
        cr_assert_eq(w[i].failures, 0, "writer %d", i);
    }
    r.stop = 1;
    pthread_join(rt, NULL);
    cr_assert_eq(r.bad, 0, "a reader saw a broken file %d times: %s", r.bad, r.bad_msg);

    /* one file, all of it from one writer */
    cr_assert_eq(dir_entries(tmp_dir), 1, "no temporaries left");
    tess_error err = {0};
    cache_file *c = NULL;
    cr_assert_eq(cache_open(cache_path, KEY, VERSION, &c, &err), CACHE_OK, "%s", err.msg);
    size_t count = 0;
    const float *verts = cache_section(c, "verts", sizeof(float), &count, &err);
    int from = -1;
    for (int i = 0; i < WRITERS; i++)
        if (memcmp(verts, w[i].s->verts, sizeof w[i].s->verts) == 0)
            from = i;
    cr_assert_geq(from, 0, "the verts are some writer's");
    for (size_t k = 0; k < 5; k++) {
        const cache_section_source *src = &w[from].s->sections[k];
        const void *p = cache_section(c, src->tag, src->element_bytes, &count, &err);
        cr_assert(p && count == src->element_count);
        if (count)
            cr_assert_eq(memcmp(p, src->data, count * src->element_bytes), 0, "section %s is writer %d's", src->tag,
                         from);
    }
    cache_close(c);
    for (int i = 0; i < WRITERS; i++)
        free(w[i].s);
}

/* ---------------------------------------------------------------- keys and paths */

Test(cache_file, keys_follow_content_and_parameters)
{
    char a[600], b[600], empty[600];
    snprintf(a, sizeof a, "%s/a.ply", tmp_dir);
    snprintf(b, sizeof b, "%s/b.ply", tmp_dir);
    snprintf(empty, sizeof empty, "%s/empty.ply", tmp_dir);
    write_all(a, "the same content", 16);
    write_all(b, "the same content", 16);
    write_all(empty, "", 0);
    struct params {
        uint32_t leaf_size;
        char layout[12];
    } p1 = {4, "wide8"}, p2 = {8, "wide8"};

    tess_error err = {0};
    cache_key ka, kb, ka2, ke, ke2;
    cr_assert(cache_hash_file(a, &p1, sizeof p1, &ka, &err), "%s", err.msg);
    cr_assert(cache_hash_file(b, &p1, sizeof p1, &kb, &err), "%s", err.msg);
    cr_assert(cache_key_equal(ka, kb), "same bytes and parameters, same key, whatever the name");
    cr_assert(cache_hash_file(a, &p2, sizeof p2, &ka2, &err), "%s", err.msg);
    cr_assert_not(cache_key_equal(ka, ka2), "another leaf size, another key");
    write_all(b, "the same contenT", 16);
    cr_assert(cache_hash_file(b, &p1, sizeof p1, &kb, &err), "%s", err.msg);
    cr_assert_not(cache_key_equal(ka, kb), "one byte changed, another key");
    cr_assert(cache_hash_file(empty, NULL, 0, &ke, &err), "%s", err.msg);
    cr_assert(cache_hash_file(empty, "", 1, &ke2, &err), "%s", err.msg);
    cr_assert_not(cache_key_equal(ke, ke2));

    /* pieces are framed: ("ab", "c") is not ("a", "bc") */
    cache_hasher *h1 = cache_hasher_new(), *h2 = cache_hasher_new();
    cr_assert(h1 && h2);
    cache_hasher_add_bytes(h1, "ab", 2);
    cache_hasher_add_bytes(h1, "c", 1);
    cache_hasher_add_bytes(h2, "a", 1);
    cache_hasher_add_bytes(h2, "bc", 2);
    cr_assert_not(cache_key_equal(cache_hasher_key(h1), cache_hasher_key(h2)));
    /* a file hashes as its bytes do */
    cache_hasher *h3 = cache_hasher_new();
    cr_assert(cache_hasher_add_file(h2, a, &err));
    cache_hasher_add_bytes(h3, "a", 1);
    cache_hasher_add_bytes(h3, "bc", 2);
    cache_hasher_add_bytes(h3, "the same content", 16);
    cr_assert(cache_key_equal(cache_hasher_key(h2), cache_hasher_key(h3)));
    cache_hasher_free(h1);
    cache_hasher_free(h2);
    cache_hasher_free(h3);
    cache_hasher_free(NULL);

    char missing[600];
    snprintf(missing, sizeof missing, "%s/nope.ply", tmp_dir);
    tess_error e1 = {0}, e2 = {0};
    cr_assert_not(cache_hash_file(missing, NULL, 0, &ka, &e1));
    cr_assert(strstr(e1.msg, missing) && strstr(e1.msg, "No such file"), "%s", e1.msg);
    cr_assert_not(cache_hash_file(tmp_dir, NULL, 0, &ka, &e2));
    cr_assert(strstr(e2.msg, tmp_dir) && strstr(e2.msg, "not a regular file"), "%s", e2.msg);
}

Test(cache_file, key_hex_is_hi_then_lo)
{
    char hex[CACHE_KEY_HEX_BYTES];
    cache_key_hex(KEY, hex);
    cr_assert_str_eq(hex, "fedcba98765432100123456789abcdef");
}

Test(cache_file, the_cache_directory_and_switch_come_from_the_environment)
{
    char out[CACHE_PATH_BYTES];
    tess_error err = {0};
    setenv("TESSERA_CACHE_DIR", "/tc", 1);
    setenv("XDG_CACHE_HOME", "/xdg", 1);
    setenv("HOME", "/home/u", 1);
    cr_assert(cache_path_for_key(KEY, out, sizeof out, &err), "%s", err.msg);
    cr_assert_str_eq(out, "/tc/fedcba98765432100123456789abcdef.tcache");
    setenv("TESSERA_CACHE_DIR", "", 1); /* empty counts as unset */
    cr_assert(cache_dir(out, sizeof out, &err));
    cr_assert_str_eq(out, "/xdg/tessera");
    setenv("XDG_CACHE_HOME", "relative", 1); /* the XDG spec: ignored */
    cr_assert(cache_dir(out, sizeof out, &err));
    cr_assert_str_eq(out, "/home/u/.cache/tessera");
    unsetenv("XDG_CACHE_HOME");
    cr_assert(cache_dir(out, sizeof out, &err));
    cr_assert_str_eq(out, "/home/u/.cache/tessera");
    unsetenv("HOME");
    unsetenv("TESSERA_CACHE_DIR");
    cr_assert_not(cache_dir(out, sizeof out, &err));
    cr_assert(strstr(err.msg, "TESSERA_CACHE_DIR"), "%s", err.msg);
    char tiny[8];
    tess_error err2 = {0};
    setenv("TESSERA_CACHE_DIR", "/tc", 1);
    cr_assert_not(cache_path_for_key(KEY, tiny, sizeof tiny, &err2));
    cr_assert(strstr(err2.msg, "longer than"), "%s", err2.msg);

    unsetenv("TESSERA_CACHE");
    cr_assert(cache_enabled());
    setenv("TESSERA_CACHE", "on", 1);
    cr_assert(cache_enabled());
    setenv("TESSERA_CACHE", "off", 1);
    cr_assert_not(cache_enabled());
    setenv("TESSERA_CACHE", "0", 1);
    cr_assert_not(cache_enabled());
}

Test(cache_file, status_names)
{
    cr_assert_str_eq(cache_status_name(CACHE_OK), "ok");
    cr_assert_str_eq(cache_status_name(CACHE_STALE), "stale");
    cr_assert_str_eq(cache_status_name(CACHE_CORRUPT_SECTION), "corrupt-section");
    for (int s = 0; s < CACHE_STATUS_COUNT; s++)
        cr_assert_not_null(cache_status_name((cache_status)s));
    cr_assert_str_eq(cache_status_name(CACHE_STATUS_COUNT), "?");
}
