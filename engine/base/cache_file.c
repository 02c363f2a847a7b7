/* cache_file.c - content-keyed cache files of named, aligned, checksummed sections: see
 * cache_file.h for the format and the checks. Hashing is XXH3 (libxxhash): the 128-bit
 * variant for keys, the 64-bit one for the header, table and section checksums. */
#define _GNU_SOURCE /* madvise, MADV_* */
#include "cache_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>
#include <xxhash.h>

_Static_assert(sizeof(cache_file_header) == 128, "the header is 128 bytes on disk");
_Static_assert(offsetof(cache_file_header, header_checksum) == 120, "the header checksum is its last 8 bytes");
_Static_assert(sizeof(cache_section_entry) == 64, "a table entry is 64 bytes on disk");
_Static_assert(sizeof(CACHE_FILE_MAGIC) == 9, "the magic is 8 bytes and a NUL");
_Static_assert((CACHE_SECTION_ALIGN & (CACHE_SECTION_ALIGN - 1)) == 0, "the alignment is a power of two");

#define HEADER_CHECKED_BYTES offsetof(cache_file_header, header_checksum)

/* pwrite calls are at most this long (Linux writes at most ~2 GiB per call anyway) */
#define WRITE_CHUNK_BYTES ((size_t)1 << 30)

/* ---------------------------------------------------------------- keys */

bool cache_key_equal(cache_key a, cache_key b) { return a.lo == b.lo && a.hi == b.hi; }

void cache_key_hex(cache_key key, char out[CACHE_KEY_HEX_BYTES])
{
    static const char digits[] = "0123456789abcdef";
    for (int i = 0; i < 16; i++) {
        out[i] = digits[(key.hi >> (60 - 4 * i)) & 0xf];
        out[16 + i] = digits[(key.lo >> (60 - 4 * i)) & 0xf];
    }
    out[32] = '\0';
}

struct cache_hasher {
    XXH3_state_t *state; /* a 128-bit XXH3 stream, reset at creation */
};

cache_hasher *cache_hasher_new(void)
{
    cache_hasher *h = malloc(sizeof *h);
    if (!h)
        return NULL;
    h->state = XXH3_createState();
    if (!h->state || XXH3_128bits_reset(h->state) != XXH_OK) {
        XXH3_freeState(h->state);
        free(h);
        return NULL;
    }
    return h;
}

void cache_hasher_free(cache_hasher *h)
{
    if (!h)
        return;
    XXH3_freeState(h->state);
    free(h);
}

/* Each piece starts with its length as 8 little-endian bytes, so pieces cannot run together. */
static void add_length_frame(cache_hasher *h, uint64_t byte_count)
{
    unsigned char le[8];
    for (int i = 0; i < 8; i++)
        le[i] = (unsigned char)(byte_count >> (8 * i));
    XXH3_128bits_update(h->state, le, sizeof le);
}

void cache_hasher_add_bytes(cache_hasher *h, const void *bytes, size_t byte_count)
{
    add_length_frame(h, byte_count);
    if (byte_count > 0)
        XXH3_128bits_update(h->state, bytes, byte_count);
}

bool cache_hasher_add_file(cache_hasher *h, const char *path, tess_error *err)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return tess_error_set(err, "%s: cannot open for hashing: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return tess_error_set(err, "%s: cannot stat for hashing: %s", path, strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return tess_error_set(err, "%s: cannot hash: not a regular file", path);
    }
    if ((uint64_t)st.st_size > SIZE_MAX) {
        close(fd);
        return tess_error_set(err, "%s: cannot hash: %lld bytes do not fit in memory", path, (long long)st.st_size);
    }
    size_t bytes = (size_t)st.st_size;
    if (bytes == 0) { /* mmap refuses length 0 */
        close(fd);
        cache_hasher_add_bytes(h, NULL, 0);
        return true;
    }
    void *map = mmap(NULL, bytes, PROT_READ, MAP_PRIVATE, fd, 0);
    int map_errno = errno;
    close(fd); /* the mapping keeps the file */
    if (map == MAP_FAILED)
        return tess_error_set(err, "%s: cannot map %zu bytes for hashing: %s", path, bytes, strerror(map_errno));
    (void)madvise(map, bytes, MADV_SEQUENTIAL); /* advice only: aggressive read-ahead */
    cache_hasher_add_bytes(h, map, bytes);
    munmap(map, bytes);
    return true;
}

cache_key cache_hasher_key(const cache_hasher *h)
{
    XXH128_hash_t d = XXH3_128bits_digest(h->state);
    return (cache_key){.lo = d.low64, .hi = d.high64};
}

bool cache_hash_file(const char *path, const void *params, size_t params_bytes, cache_key *key_out,
                     tess_error *err)
{
    cache_hasher *h = cache_hasher_new();
    if (!h)
        return tess_error_set(err, "%s: cannot hash: out of memory", path);
    bool ok = cache_hasher_add_file(h, path, err);
    if (ok) {
        cache_hasher_add_bytes(h, params, params_bytes);
        *key_out = cache_hasher_key(h);
    }
    cache_hasher_free(h);
    return ok;
}

/* ---------------------------------------------------------------- where caches live */

bool cache_enabled(void)
{
    const char *v = getenv("TESSERA_CACHE");
    return !(v && (strcmp(v, "off") == 0 || strcmp(v, "0") == 0));
}

static const char *env_nonempty(const char *name)
{
    const char *v = getenv(name);
    return v && v[0] ? v : NULL;
}

bool cache_dir(char *out, size_t out_bytes, tess_error *err)
{
    const char *dir = env_nonempty("TESSERA_CACHE_DIR");
    const char *xdg = env_nonempty("XDG_CACHE_HOME");
    const char *home = env_nonempty("HOME");
    int n;
    if (dir)
        n = snprintf(out, out_bytes, "%s", dir);
    else if (xdg && xdg[0] == '/') /* the XDG spec: a relative path is to be ignored */
        n = snprintf(out, out_bytes, "%s/tessera", xdg);
    else if (home)
        n = snprintf(out, out_bytes, "%s/.cache/tessera", home);
    else
        return tess_error_set(err, "cache: no directory for caches (set TESSERA_CACHE_DIR, XDG_CACHE_HOME or HOME)");
    if (n < 0 || (size_t)n >= out_bytes)
        return tess_error_set(err, "cache: the cache directory's path is longer than %zu bytes", out_bytes - 1);
    return true;
}

bool cache_path_for_key(cache_key key, char *out, size_t out_bytes, tess_error *err)
{
    char dir[CACHE_PATH_BYTES];
    if (!cache_dir(dir, sizeof dir, err))
        return false;
    char hex[CACHE_KEY_HEX_BYTES];
    cache_key_hex(key, hex);
    int n = snprintf(out, out_bytes, "%s/%s.tcache", dir, hex);
    if (n < 0 || (size_t)n >= out_bytes)
        return tess_error_set(err, "cache: the path of a cache in %s is longer than %zu bytes", dir, out_bytes - 1);
    return true;
}

/* ---------------------------------------------------------------- layout, shared by both sides */

static uint64_t align_up(uint64_t offset) { return (offset + CACHE_SECTION_ALIGN - 1) & ~(uint64_t)(CACHE_SECTION_ALIGN - 1); }

/* Where the table ends and the first section may start. */
static uint64_t table_end(uint64_t section_count)
{
    return sizeof(cache_file_header) + section_count * sizeof(cache_section_entry);
}

/* A tag is 1..15 printable, non-space ASCII characters. */
static bool tag_valid(const char *tag)
{
    size_t n = strlen(tag);
    if (n == 0 || n >= CACHE_TAG_BYTES)
        return false;
    for (size_t i = 0; i < n; i++)
        if (tag[i] <= ' ' || tag[i] > '~')
            return false;
    return true;
}

/* ---------------------------------------------------------------- writing */

/* Make every missing directory of path's parent (0755). False with errno set on failure. */
static bool make_parent_dirs(const char *path)
{
    char dir[CACHE_PATH_BYTES];
    size_t n = strlen(path);
    if (n >= sizeof dir) {
        errno = ENAMETOOLONG;
        return false;
    }
    memcpy(dir, path, n + 1);
    char *slash = strrchr(dir, '/');
    if (!slash || slash == dir) /* in the working directory, or in / */
        return true;
    *slash = '\0';
    /* each prefix in turn; EEXIST is fine (a file in the way shows up when the file is made) */
    for (char *p = dir + 1;; p++) {
        if (*p == '/' || *p == '\0') {
            char c = *p;
            *p = '\0';
            if (mkdir(dir, 0755) != 0 && errno != EEXIST)
                return false;
            *p = c;
            if (c == '\0')
                return true;
        }
    }
}

static bool pwrite_all(int fd, const void *data, uint64_t byte_count, uint64_t offset)
{
    const unsigned char *p = data;
    while (byte_count > 0) {
        size_t n = byte_count < WRITE_CHUNK_BYTES ? (size_t)byte_count : WRITE_CHUNK_BYTES;
        ssize_t w = pwrite(fd, p, n, (off_t)offset);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0) {
            if (w == 0)
                errno = EIO;
            return false;
        }
        p += w;
        offset += (uint64_t)w;
        byte_count -= (uint64_t)w;
    }
    return true;
}

/* fsync the directory holding path, so the rename itself is on disk (best-effort). */
static void sync_parent_dir(const char *path)
{
    char dir[CACHE_PATH_BYTES];
    size_t n = strlen(path);
    if (n >= sizeof dir)
        return;
    memcpy(dir, path, n + 1);
    char *slash = strrchr(dir, '/');
    if (!slash)
        strcpy(dir, ".");
    else if (slash == dir)
        dir[1] = '\0';
    else
        *slash = '\0';
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
}

/* The header and table for sections, with every offset and checksum (the checksums read all
 * the data). NULL with a message on a bad argument or no memory. *prefix_bytes_out: where
 * the first section starts; *file_bytes_out: the whole file. */
static unsigned char *build_prefix(const char *path, cache_key key, uint32_t content_version,
                                   const cache_section_source *sections, size_t section_count,
                                   uint64_t *prefix_bytes_out, uint64_t *file_bytes_out, tess_error *err)
{
    if (section_count > CACHE_MAX_SECTIONS) {
        tess_error_set(err, "cache %s: not written: %zu sections, at most %u", path, section_count,
                       CACHE_MAX_SECTIONS);
        return NULL;
    }
    uint64_t end = table_end(section_count);
    uint64_t prefix_bytes = align_up(end);
    if (section_count == 0)
        prefix_bytes = end; /* nothing follows the header */
    unsigned char *prefix = calloc(1, (size_t)prefix_bytes);
    if (!prefix) {
        tess_error_set(err, "cache %s: not written: out of memory", path);
        return NULL;
    }
    cache_section_entry *table = (cache_section_entry *)(prefix + sizeof(cache_file_header));
    for (size_t i = 0; i < section_count; i++) {
        const cache_section_source *s = &sections[i];
        const char *why = NULL;
        if (!s->tag || !tag_valid(s->tag))
            why = "its tag is not 1..15 printable characters";
        else if (s->element_bytes == 0)
            why = "its element size is 0";
        else if (s->element_count > UINT64_MAX / s->element_bytes ||
                 (uint64_t)s->element_count * s->element_bytes > UINT64_MAX / 2)
            why = "it is too large";
        else if (!s->data && s->element_count > 0)
            why = "its data is NULL";
        for (size_t j = 0; !why && j < i; j++)
            if (strcmp(sections[j].tag, s->tag) == 0)
                why = "its tag is used twice";
        if (why) {
            tess_error_set(err, "cache %s: not written: section %zu ('%s'): %s", path, i, s->tag ? s->tag : "",
                           why);
            free(prefix);
            return NULL;
        }
        uint64_t bytes = (uint64_t)s->element_count * s->element_bytes;
        uint64_t offset = align_up(end);
        cache_section_entry *e = &table[i];
        memcpy(e->tag, s->tag, strlen(s->tag)); /* the rest stays NUL */
        e->offset = offset;
        e->bytes = bytes;
        e->element_bytes = s->element_bytes;
        e->element_count = s->element_count;
        e->checksum = XXH3_64bits(bytes ? s->data : "", (size_t)bytes);
        end = offset + bytes;
    }
    cache_file_header h;
    memset(&h, 0, sizeof h);
    memcpy(h.magic, CACHE_FILE_MAGIC, sizeof h.magic);
    h.byte_order = CACHE_BYTE_ORDER_MARK;
    h.format_version = CACHE_FILE_FORMAT_VERSION;
    h.content_version = content_version;
    h.section_count = (uint32_t)section_count;
    h.key_lo = key.lo;
    h.key_hi = key.hi;
    h.file_bytes = end;
    h.table_checksum = XXH3_64bits(table, section_count * sizeof(cache_section_entry));
    h.header_checksum = XXH3_64bits(&h, HEADER_CHECKED_BYTES);
    memcpy(prefix, &h, sizeof h);
    *prefix_bytes_out = prefix_bytes;
    *file_bytes_out = end;
    return prefix;
}

bool cache_write(const char *path, cache_key key, uint32_t content_version,
                 const cache_section_source *sections, size_t section_count, tess_error *err)
{
    uint64_t prefix_bytes = 0, file_bytes = 0;
    unsigned char *prefix =
        build_prefix(path, key, content_version, sections, section_count, &prefix_bytes, &file_bytes, err);
    if (!prefix)
        return false;

    char tmp[CACHE_PATH_BYTES];
    int n = snprintf(tmp, sizeof tmp, "%s.tmp-XXXXXX", path);
    if (n < 0 || (size_t)n >= sizeof tmp) {
        free(prefix);
        return tess_error_set(err, "cache %s: not written: the path is too long", path);
    }
    if (!make_parent_dirs(path)) {
        int e = errno;
        free(prefix);
        return tess_error_set(err, "cache %s: not written: cannot make its directory: %s", path, strerror(e));
    }
    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        free(prefix);
        return tess_error_set(err, "cache %s: not written: cannot create a temporary file beside it: %s", path,
                              strerror(e));
    }
    (void)fcntl(fd, F_SETFD, FD_CLOEXEC);

    const char *step = NULL; /* what failed, for the message; errno holds why */
    int e = 0;
    if (fchmod(fd, 0644) != 0)
        step = "setting its mode";
    /* reserve the space first, so a full disk fails before gigabytes are written
       (file systems without fallocate support just skip this) */
    if (!step) {
        int r = posix_fallocate(fd, 0, (off_t)file_bytes);
        if (r == ENOSPC || r == EFBIG) {
            errno = r;
            step = "reserving its space";
        }
    }
    if (!step && !pwrite_all(fd, prefix, prefix_bytes, 0))
        step = "writing its header";
    const cache_section_entry *table = (const cache_section_entry *)(prefix + sizeof(cache_file_header));
    /* the gaps between sections are never written: a new file reads zero there */
    for (size_t i = 0; !step && i < section_count; i++)
        if (!pwrite_all(fd, sections[i].data, table[i].bytes, table[i].offset))
            step = "writing a section";
    if (!step && fsync(fd) != 0)
        step = "flushing it to disk";
    if (step)
        e = errno;
    if (close(fd) != 0 && !step) {
        e = errno;
        step = "closing it";
    }
    if (!step && rename(tmp, path) != 0) {
        e = errno;
        step = "renaming it into place";
    }
    free(prefix);
    if (step) {
        unlink(tmp);
        return tess_error_set(err, "cache %s: not written: %s (%s): %s", path, step, tmp, strerror(e));
    }
    sync_parent_dir(path);
    return true;
}

/* ---------------------------------------------------------------- reading */

struct cache_file {
    char *path;              /* for messages */
    const unsigned char *map; /* the whole file, PROT_READ */
    uint64_t file_bytes;
    uint32_t section_count;
    const cache_section_entry *table; /* in the map; checked by cache_open */
};

const char *cache_status_name(cache_status s)
{
    static const char *const names[CACHE_STATUS_COUNT] = {
        [CACHE_OK] = "ok",
        [CACHE_MISSING] = "missing",
        [CACHE_UNREADABLE] = "unreadable",
        [CACHE_NOT_A_CACHE] = "not-a-cache",
        [CACHE_BYTE_ORDER] = "byte-order",
        [CACHE_FORMAT_VERSION] = "format-version",
        [CACHE_SIZE] = "size",
        [CACHE_CORRUPT_HEADER] = "corrupt-header",
        [CACHE_VERSION] = "version",
        [CACHE_STALE] = "stale",
        [CACHE_BAD_TABLE] = "bad-table",
        [CACHE_CORRUPT_SECTION] = "corrupt-section",
    };
    return (unsigned)s < CACHE_STATUS_COUNT ? names[s] : "?";
}

/* The checks after the magic, on a mapped file of file_bytes >= the header's size. */
static cache_status check_mapped(const char *path, const unsigned char *map, uint64_t file_bytes, cache_key key,
                                 uint32_t content_version, tess_error *err)
{
    cache_file_header h;
    memcpy(&h, map, sizeof h);
    if (h.byte_order != CACHE_BYTE_ORDER_MARK) {
        if (h.byte_order == __builtin_bswap32(CACHE_BYTE_ORDER_MARK)) {
            tess_error_set(err, "cache %s: written on a machine of the other byte order", path);
            return CACHE_BYTE_ORDER;
        }
        tess_error_set(err, "cache %s: corrupt (its byte order mark is 0x%08x)", path, h.byte_order);
        return CACHE_CORRUPT_HEADER;
    }
    if (h.format_version != CACHE_FILE_FORMAT_VERSION) {
        tess_error_set(err, "cache %s: written by cache file format version %u, this reads %u", path, h.format_version,
                       CACHE_FILE_FORMAT_VERSION);
        return CACHE_FORMAT_VERSION;
    }
    if (XXH3_64bits(map, HEADER_CHECKED_BYTES) != h.header_checksum) {
        tess_error_set(err, "cache %s: corrupt (header checksum mismatch)", path);
        return CACHE_CORRUPT_HEADER;
    }
    if (h.file_bytes != file_bytes) {
        if (file_bytes < h.file_bytes)
            tess_error_set(err, "cache %s: truncated: %llu bytes, its header says %llu", path,
                           (unsigned long long)file_bytes, (unsigned long long)h.file_bytes);
        else
            tess_error_set(err, "cache %s: %llu bytes, its header says %llu (extra bytes at the end)", path,
                           (unsigned long long)file_bytes, (unsigned long long)h.file_bytes);
        return CACHE_SIZE;
    }
    if (h.content_version != content_version) {
        tess_error_set(err, "cache %s: written by format version %u, this is %u", path, h.content_version,
                       content_version);
        return CACHE_VERSION;
    }
    if (h.key_lo != key.lo || h.key_hi != key.hi) {
        tess_error_set(err, "cache %s: stale (its key does not match the inputs' content)", path);
        return CACHE_STALE;
    }

    /* the table: in bounds, checksummed, then each entry placed exactly where a writer puts it */
    if (h.section_count > CACHE_MAX_SECTIONS || table_end(h.section_count) > file_bytes) {
        tess_error_set(err, "cache %s: bad section table (%u sections do not fit in %llu bytes)", path,
                       h.section_count, (unsigned long long)file_bytes);
        return CACHE_BAD_TABLE;
    }
    const cache_section_entry *table = (const cache_section_entry *)(map + sizeof(cache_file_header));
    if (XXH3_64bits(table, h.section_count * sizeof *table) != h.table_checksum) {
        tess_error_set(err, "cache %s: corrupt (section table checksum mismatch)", path);
        return CACHE_CORRUPT_HEADER;
    }
    uint64_t end = table_end(h.section_count); /* of what precedes section i */
    for (uint32_t i = 0; i < h.section_count; i++) {
        const cache_section_entry *e = &table[i];
        char tag[CACHE_TAG_BYTES];
        memcpy(tag, e->tag, sizeof tag);
        const char *why = NULL;
        if (memchr(e->tag, '\0', sizeof e->tag) == NULL) {
            tag[CACHE_TAG_BYTES - 1] = '\0';
            why = "its tag has no end";
        } else if (!tag_valid(tag)) {
            why = "its tag is not 1..15 printable characters";
        } else if (e->element_bytes == 0 || e->element_count > UINT64_MAX / e->element_bytes ||
                   e->element_bytes * e->element_count != e->bytes) {
            why = "its size is not element size x count";
        } else if (e->offset != align_up(end)) {
            why = "it does not start at the next aligned offset after the one before";
        } else if (e->bytes > file_bytes || e->offset > file_bytes - e->bytes) {
            why = "it runs past the end of the file";
        } else if (e->reserved != 0) {
            why = "its reserved field is not zero";
        }
        for (uint32_t j = 0; !why && j < i; j++)
            if (strncmp(table[j].tag, tag, CACHE_TAG_BYTES) == 0)
                why = "its tag is used twice";
        if (why) {
            tess_error_set(err, "cache %s: bad section table (section %u '%s': %s)", path, i, tag, why);
            return CACHE_BAD_TABLE;
        }
        end = e->offset + e->bytes;
    }
    if (end != file_bytes) {
        tess_error_set(err, "cache %s: bad section table (its sections end at %llu, the file at %llu)", path,
                       (unsigned long long)end, (unsigned long long)file_bytes);
        return CACHE_BAD_TABLE;
    }

    /* every remaining byte: the gaps are zero, the sections match their checksums */
    (void)madvise((void *)map, (size_t)file_bytes, MADV_SEQUENTIAL);
    end = table_end(h.section_count);
    cache_status s = CACHE_OK;
    for (uint32_t i = 0; i < h.section_count && s == CACHE_OK; i++) {
        const cache_section_entry *e = &table[i];
        for (uint64_t at = end; at < e->offset; at++)
            if (map[at] != 0) {
                tess_error_set(err, "cache %s: corrupt (a nonzero byte between sections at offset %llu)", path,
                               (unsigned long long)at);
                s = CACHE_CORRUPT_SECTION;
                break;
            }
        if (s == CACHE_OK && XXH3_64bits(map + e->offset, (size_t)e->bytes) != e->checksum) {
            tess_error_set(err, "cache %s: corrupt (section '%.15s' checksum mismatch)", path, e->tag);
            s = CACHE_CORRUPT_SECTION;
        }
        end = e->offset + e->bytes;
    }
    /* from here on the sections are used as their owner likes (a BVH: at random) */
    (void)madvise((void *)map, (size_t)file_bytes, MADV_NORMAL);
    return s;
}

cache_status cache_open(const char *path, cache_key expected_key, uint32_t expected_content_version,
                        cache_file **out, tess_error *err)
{
    *out = NULL;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        int e = errno;
        if (e == ENOENT) {
            tess_error_set(err, "cache %s: none yet", path);
            return CACHE_MISSING;
        }
        tess_error_set(err, "cache %s: cannot open: %s", path, strerror(e));
        return CACHE_UNREADABLE;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        tess_error_set(err, "cache %s: cannot stat: %s", path, strerror(e));
        return CACHE_UNREADABLE;
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        tess_error_set(err, "cache %s: not a regular file", path);
        return CACHE_UNREADABLE;
    }
    uint64_t file_bytes = (uint64_t)st.st_size;
    if (file_bytes == 0) {
        close(fd);
        tess_error_set(err, "cache %s: empty (0 bytes)", path);
        return CACHE_SIZE;
    }
    if (file_bytes > SIZE_MAX) {
        close(fd);
        tess_error_set(err, "cache %s: %llu bytes do not fit in memory", path, (unsigned long long)file_bytes);
        return CACHE_UNREADABLE;
    }
    void *map = mmap(NULL, (size_t)file_bytes, PROT_READ, MAP_PRIVATE, fd, 0);
    int map_errno = errno;
    close(fd); /* the mapping keeps the file */
    if (map == MAP_FAILED) {
        tess_error_set(err, "cache %s: cannot map %llu bytes: %s", path, (unsigned long long)file_bytes,
                       strerror(map_errno));
        return CACHE_UNREADABLE;
    }

    cache_status s;
    size_t magic_bytes = file_bytes < 8 ? (size_t)file_bytes : 8;
    if (memcmp(map, CACHE_FILE_MAGIC, magic_bytes) != 0) {
        tess_error_set(err, "cache %s: not a tessera cache file (no %s magic)", path, CACHE_FILE_MAGIC);
        s = CACHE_NOT_A_CACHE;
    } else if (file_bytes < sizeof(cache_file_header)) {
        tess_error_set(err, "cache %s: truncated: %llu bytes, shorter than its %zu-byte header", path,
                       (unsigned long long)file_bytes, sizeof(cache_file_header));
        s = CACHE_SIZE;
    } else {
        s = check_mapped(path, map, file_bytes, expected_key, expected_content_version, err);
    }
    cache_file *c = NULL;
    if (s == CACHE_OK) {
        c = calloc(1, sizeof *c);
        char *path_copy = c ? strdup(path) : NULL;
        if (!path_copy) {
            free(c);
            c = NULL;
            tess_error_set(err, "cache %s: cannot open: out of memory", path);
            s = CACHE_UNREADABLE;
        } else {
            cache_file_header h;
            memcpy(&h, map, sizeof h);
            c->path = path_copy;
            c->map = map;
            c->file_bytes = file_bytes;
            c->section_count = h.section_count;
            c->table = (const cache_section_entry *)((const unsigned char *)map + sizeof(cache_file_header));
        }
    }
    if (s != CACHE_OK) {
        munmap(map, (size_t)file_bytes);
        return s;
    }
    *out = c;
    return CACHE_OK;
}

const void *cache_section(const cache_file *c, const char *tag, size_t element_bytes, size_t *count_out,
                          tess_error *err)
{
    for (uint32_t i = 0; i < c->section_count; i++) {
        const cache_section_entry *e = &c->table[i];
        if (strncmp(e->tag, tag, CACHE_TAG_BYTES) != 0)
            continue;
        if (e->element_bytes != element_bytes) {
            tess_error_set(err, "cache %s: section '%s' has %llu-byte elements, expected %zu", c->path, tag,
                           (unsigned long long)e->element_bytes, element_bytes);
            return NULL;
        }
        if (count_out)
            *count_out = (size_t)e->element_count;
        return c->map + e->offset;
    }
    tess_error_set(err, "cache %s: no section '%s'", c->path, tag);
    return NULL;
}

size_t cache_section_count(const cache_file *c) { return c->section_count; }

cache_section_info cache_section_at(const cache_file *c, size_t i)
{
    const cache_section_entry *e = &c->table[i];
    return (cache_section_info){.tag = e->tag, /* NUL-terminated: checked by cache_open */
                                .data = c->map + e->offset,
                                .bytes = e->bytes,
                                .element_bytes = e->element_bytes,
                                .element_count = e->element_count};
}

uint64_t cache_file_bytes(const cache_file *c) { return c->file_bytes; }

void cache_close(cache_file *c)
{
    if (!c)
        return;
    munmap((void *)c->map, (size_t)c->file_bytes);
    free(c->path);
    free(c);
}
