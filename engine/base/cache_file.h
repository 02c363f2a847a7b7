/* cache_file.h - a cache of built structures on disk (issue 17, "massive models").
 *
 * After a mesh and its acceleration structure are built, their arrays are written as named
 * sections of one file whose name is a 128-bit content hash (the *key*) of everything the
 * build read: the model file's bytes and the settings that decide the result. On the next
 * start the same inputs give the same key, the file is memory-mapped read-only, checked, and
 * its sections used in place: no parsing, no build, no copy.
 *
 * The module knows nothing of meshes or BVHs: a section is a tag (a short name), an element
 * size and a count. What the sections mean is the caller's, versioned by the caller's
 * content_version.
 *
 * A cache is never trusted. cache_open checks, in this order: the magic, the byte order, this
 * module's format version, the header's checksum, the file's size against the header, the
 * caller's content version, the key, the section table's checksum, the table itself (each
 * section in bounds, 64-byte aligned, in order without overlap, its size = element size x
 * count), that every byte between sections is zero, and the XXH3-64 checksum of every section.
 * So a flipped byte anywhere in the file is found; checking reads the whole file once (at
 * memory speed when it is in the page cache). Anything that fails gives a status saying which
 * check it was and one line naming the file and the problem; the caller then rebuilds and
 * writes a new cache over it. A file that fails is never mapped for use.
 *
 * Writing is atomic and best-effort: the file is written as a temporary beside its real name,
 * fsync'd and renamed over it, so a crash or a concurrent writer never leaves a half file under
 * the real name (concurrent writers of one key: the last rename wins, whole). A write that
 * fails (read-only directory, full disk) returns false with a message; the program goes on
 * without a cache.
 *
 * Typical use (the caller logs; this module never prints):
 *
 *     cache_key key;
 *     if (!cache_hash_file(model_path, &params, sizeof params, &key, &err)) ... no cache
 *     char path[CACHE_PATH_BYTES];
 *     if (cache_enabled() && cache_path_for_key(key, path, sizeof path, &err)) {
 *         cache_file *c = NULL;
 *         cache_status s = cache_open(path, key, MY_LAYOUT_VERSION, &c, &err);
 *         if (s == CACHE_OK) { nodes = cache_section(c, "nodes", sizeof *nodes, &n, &err); ... }
 *         else if (s != CACHE_MISSING) log_warn("%s - rebuilding", err.msg);
 *         ... after a build: if (!cache_write(path, key, MY_LAYOUT_VERSION, secs, n, &err))
 *                                log_warn("%s", err.msg);
 *     }
 *
 * Caches are never evicted: there is no size limit on the cache directory (yet).
 *
 * The file (all integers in the writer's byte order, which must be the reader's):
 *   [0, 128)                 cache_file_header
 *   [128, 128 + 64 n)        n cache_section_entry, in increasing offset order
 *   then the sections, each at a multiple of CACHE_SECTION_ALIGN, zero bytes between them,
 *   and nothing after the last one. */
#ifndef TESSERA_CACHE_FILE_H
#define TESSERA_CACHE_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "err.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Cost, measured on a 2 GiB file of random bytes in the page cache (a 2-core "AMD EPYC" VM,
 * family 26 model 2, under the load of other builds; Debian's libxxhash 0.8.1):
 * cache_hash_file 6.5..17 GB/s, cache_open (all checks) 7.7..17.5 GB/s, XXH3 on a heap
 * buffer 13 GB/s. Cold (evicted with POSIX_FADV_DONTNEED) both run at the disk's speed:
 * 1.2..3.3 GB/s, where O_DIRECT reads 1.3..1.4 GB/s. Writing 2 GiB with its fsync: 2.9 s.
 *
 * ---- the on-disk layout (exposed for the tests and for documentation) ---- */

#define CACHE_FILE_MAGIC "TSRCACHE"        /* 8 bytes, no NUL on disk */
#define CACHE_FILE_FORMAT_VERSION 1u       /* this header and table layout */
#define CACHE_BYTE_ORDER_MARK 0x01020304u  /* reads as 0x04030201 on the other byte order */
#define CACHE_SECTION_ALIGN 64u            /* bytes: a cache line, the widest SIMD load */
#define CACHE_TAG_BYTES 16u                /* a tag is 1..15 printable chars, NUL-padded */
#define CACHE_MAX_SECTIONS 1024u           /* bounds the table a reader will look at */

typedef struct cache_file_header {
    char magic[8];            /* CACHE_FILE_MAGIC */
    uint32_t byte_order;      /* CACHE_BYTE_ORDER_MARK as the writer stored it */
    uint32_t format_version;  /* CACHE_FILE_FORMAT_VERSION of the writer */
    uint32_t content_version; /* the caller's: what the sections hold and how */
    uint32_t section_count;   /* <= CACHE_MAX_SECTIONS */
    uint64_t key_lo, key_hi;  /* the cache_key the file was written for */
    uint64_t file_bytes;      /* the whole file's size */
    uint64_t table_checksum;  /* XXH3-64 of the section_count table entries */
    uint64_t reserved[8];     /* zero */
    uint64_t header_checksum; /* XXH3-64 of the 120 bytes before this field */
} cache_file_header;

typedef struct cache_section_entry {
    char tag[CACHE_TAG_BYTES]; /* NUL-terminated and NUL-padded */
    uint64_t offset;           /* bytes from the file's start; a multiple of CACHE_SECTION_ALIGN */
    uint64_t bytes;            /* = element_bytes * element_count */
    uint64_t element_bytes;    /* >= 1 */
    uint64_t element_count;
    uint64_t checksum; /* XXH3-64 of the section's bytes */
    uint64_t reserved; /* zero */
} cache_section_entry;

/* ---- keys ---- */

/* A 128-bit content hash (XXH3-128) of a build's inputs. */
typedef struct cache_key {
    uint64_t lo, hi;
} cache_key;

#define CACHE_KEY_HEX_BYTES 33 /* 32 hex digits and a NUL */

bool cache_key_equal(cache_key a, cache_key b);
/* 32 lower-case hex digits, hi then lo (XXH128's canonical order). */
void cache_key_hex(cache_key key, char out[CACHE_KEY_HEX_BYTES]);

/* Streaming key: any number of files and byte strings, in order. Each piece is framed by its
 * length, so ("ab", "c") and ("a", "bc") give different keys. */
typedef struct cache_hasher cache_hasher;

cache_hasher *cache_hasher_new(void); /* NULL when out of memory */
void cache_hasher_free(cache_hasher *h);
void cache_hasher_add_bytes(cache_hasher *h, const void *bytes, size_t byte_count);
/* The whole content of the file at path (mmap'd read-only, read sequentially). False with a
 * message naming the file when it cannot be opened, stat'd or mapped; h is then unchanged. */
bool cache_hasher_add_file(cache_hasher *h, const char *path, tess_error *err);
cache_key cache_hasher_key(const cache_hasher *h);

/* The key of one model file and the build parameters that decide the result: a small struct
 * of the caller's settings as bytes (leaf size, layout name, transforms...; memset it to zero
 * before filling so padding bytes are zero, and keep the content version out of it: a
 * version change then rewrites the same file instead of leaving the old one behind).
 * params may be NULL when params_bytes is 0. False with a message naming the file. */
bool cache_hash_file(const char *path, const void *params, size_t params_bytes, cache_key *key_out,
                     tess_error *err);

/* ---- where caches live ---- */

#define CACHE_PATH_BYTES 4096

/* False when TESSERA_CACHE is "off" or "0": then nothing is read or written. */
bool cache_enabled(void);
/* The cache directory: $TESSERA_CACHE_DIR, else $XDG_CACHE_HOME/tessera (when absolute), else
 * $HOME/.cache/tessera (empty variables count as unset). False with a message when none is
 * set or the path does not fit. The directory need not exist (cache_write makes it). */
bool cache_dir(char *out, size_t out_bytes, tess_error *err);
/* cache_dir()/<32 hex digits of key>.tcache */
bool cache_path_for_key(cache_key key, char *out, size_t out_bytes, tess_error *err);

/* ---- writing ---- */

typedef struct cache_section_source {
    const char *tag;      /* 1..15 printable chars, unique in one file */
    const void *data;     /* element_bytes * element_count bytes (may be NULL when that is 0) */
    size_t element_bytes; /* >= 1 */
    size_t element_count;
} cache_section_source;

/* Write sections[0..section_count) as the cache for key at path: parent directories made
 * (0755) when missing, a temporary path.tmp-XXXXXX written, fsync'd, renamed over path, the
 * directory fsync'd. Best-effort: false with one line naming the file and why ("cache X: not
 * written: ...: No space left on device"); no temporary is left behind. */
bool cache_write(const char *path, cache_key key, uint32_t content_version,
                 const cache_section_source *sections, size_t section_count, tess_error *err);

/* ---- reading ---- */

typedef enum cache_status {
    CACHE_OK,
    CACHE_MISSING,         /* no file at the path: the first run, not a problem */
    CACHE_UNREADABLE,      /* open/stat/mmap failed (permissions, a directory, ...) */
    CACHE_NOT_A_CACHE,     /* the magic is not there */
    CACHE_BYTE_ORDER,      /* written on a machine of the other byte order */
    CACHE_FORMAT_VERSION,  /* another version of this module's layout */
    CACHE_SIZE,            /* empty, truncated, or longer than its header says */
    CACHE_CORRUPT_HEADER,  /* the header's or the table's checksum does not match */
    CACHE_VERSION,         /* the caller's content version differs */
    CACHE_STALE,           /* the key differs: the inputs changed */
    CACHE_BAD_TABLE,       /* a section out of bounds, unaligned, overlapping, bad tag, ... */
    CACHE_CORRUPT_SECTION, /* a section's checksum, or a byte between sections, is wrong */
    CACHE_STATUS_COUNT
} cache_status;

/* "ok", "missing", "unreadable", "not-a-cache", "byte-order", "format-version", "size",
 * "corrupt-header", "version", "stale", "bad-table", "corrupt-section" */
const char *cache_status_name(cache_status s);

typedef struct cache_file cache_file;

/* Map the file at path read-only and check it all (see the top). CACHE_OK: *out is the open
 * cache (cache_close it). Anything else: *out is NULL, nothing stays mapped, and err holds
 * "cache PATH: PROBLEM", e.g. "cache /c/1f...e2.tcache: stale (its key does not match the
 * inputs' content)". */
cache_status cache_open(const char *path, cache_key expected_key, uint32_t expected_content_version,
                        cache_file **out, tess_error *err);

/* The section tagged tag as a read-only array of *count_out elements of element_bytes each,
 * 64-byte aligned, valid until cache_close. NULL with a message when there is no such section
 * or its element size is not element_bytes (a layout changed without a version change). A
 * section of zero elements gives a non-NULL pointer that must not be read. */
const void *cache_section(const cache_file *c, const char *tag, size_t element_bytes, size_t *count_out,
                          tess_error *err);
size_t cache_section_count(const cache_file *c);

/* Section i (< cache_section_count) in file order, for listing and checking a whole file. */
typedef struct cache_section_info {
    const char *tag;   /* in the map: NUL-terminated */
    const void *data;  /* 64-byte aligned, read-only */
    uint64_t bytes;    /* = element_bytes * element_count */
    uint64_t element_bytes, element_count;
} cache_section_info;
cache_section_info cache_section_at(const cache_file *c, size_t i);
uint64_t cache_file_bytes(const cache_file *c);
/* Unmap; every pointer from cache_section dies. c may be NULL. */
void cache_close(cache_file *c);

#ifdef __cplusplus
}
#endif

#endif
