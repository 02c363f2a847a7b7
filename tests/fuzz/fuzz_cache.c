/* fuzz_cache.c - acceleration-structure cache files (engine/base/cache_file.c), opened with
 * cache_open as a start does. Each input is opened twice: as it is (random bytes almost never
 * carry valid checksums, so this explores the header's checks), then *made plausible*: magic,
 * byte order, versions, key and file size set to what is expected and every checksum
 * recomputed over what the table claims, so the table's structural checks and the section
 * accessors see every shape of table the fuzzer finds.
 *
 * A refused file must say why in one line starting with "cache PATH"; an accepted one must
 * keep cache_file.h's promises: sections 64-byte aligned, inside the file, tags valid,
 * bytes = element size x count, each found again by its tag. Every byte of every section is
 * read, so a section past the mapping would fault.
 *
 * Seeds (tests/fuzz/corpus/cache/) are files written by cache_write for FUZZ_KEY, version 1. */
#include "fuzz.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "engine/base/cache_file.h"

static const cache_key FUZZ_KEY = {.lo = 0x1111111111111111ull, .hi = 0x2222222222222222ull};
#define FUZZ_VERSION 1u

static void check_open(const char *path, size_t size)
{
    char name[128];
    snprintf(name, sizeof name, "cache %s", path);
    tess_error err = {{0}};
    cache_file *c = NULL;
    cache_status s = cache_open(path, FUZZ_KEY, FUZZ_VERSION, &c, &err);
    if (s != CACHE_OK) {
        if (c)
            fuzz_fail("%s: status %s with an open cache", name, cache_status_name(s));
        fuzz_check_error(&err, name);
        return;
    }
    if (cache_file_bytes(c) != size)
        fuzz_fail("%s: %llu bytes accepted, the file has %zu", name, (unsigned long long)cache_file_bytes(c), size);
    volatile unsigned sink = 0;
    for (size_t i = 0; i < cache_section_count(c); i++) {
        cache_section_info info = cache_section_at(c, i);
        size_t n = strlen(info.tag);
        if (n == 0 || n > 15)
            fuzz_fail("%s: section %zu has a tag of %zu characters", name, i, n);
        if ((uintptr_t)info.data % CACHE_SECTION_ALIGN != 0)
            fuzz_fail("%s: section '%s' is not 64-byte aligned", name, info.tag);
        if (info.element_bytes == 0 || info.element_bytes * info.element_count != info.bytes)
            fuzz_fail("%s: section '%s': %llu bytes, %llu x %llu", name, info.tag, (unsigned long long)info.bytes,
                      (unsigned long long)info.element_bytes, (unsigned long long)info.element_count);
        if (info.bytes > size)
            fuzz_fail("%s: section '%s' is larger than the file", name, info.tag);
        const uint8_t *p = info.data;
        for (uint64_t k = 0; k < info.bytes; k++)
            sink += p[k];
        size_t count = 0;
        if (cache_section(c, info.tag, (size_t)info.element_bytes, &count, &err) != info.data ||
            count != info.element_count)
            fuzz_fail("%s: section '%s' is not found again by its tag: %s", name, info.tag, err.msg);
    }
    (void)sink;
    cache_close(c);
}

/* The input with everything a random mutation cannot guess made right. */
static uint8_t *make_plausible(const uint8_t *data, size_t size)
{
    uint8_t *f = malloc(size);
    if (!f)
        fuzz_fail("harness: out of memory");
    memcpy(f, data, size);
    cache_file_header h;
    memcpy(&h, f, sizeof h);
    memcpy(h.magic, CACHE_FILE_MAGIC, sizeof h.magic);
    h.byte_order = CACHE_BYTE_ORDER_MARK;
    h.format_version = CACHE_FILE_FORMAT_VERSION;
    h.content_version = FUZZ_VERSION;
    h.key_lo = FUZZ_KEY.lo;
    h.key_hi = FUZZ_KEY.hi;
    h.file_bytes = size;
    uint64_t table_bytes = (uint64_t)h.section_count * sizeof(cache_section_entry);
    if (h.section_count <= CACHE_MAX_SECTIONS && sizeof h + table_bytes <= size) {
        cache_section_entry *table = (cache_section_entry *)(f + sizeof h); /* malloc: aligned */
        for (uint32_t i = 0; i < h.section_count; i++) {
            cache_section_entry *e = &table[i];
            if (e->bytes <= size && e->offset <= size - e->bytes)
                e->checksum = XXH3_64bits(f + e->offset, (size_t)e->bytes);
        }
        h.table_checksum = XXH3_64bits(table, (size_t)table_bytes);
    }
    h.header_checksum = XXH3_64bits(&h, offsetof(cache_file_header, header_checksum));
    memcpy(f, &h, sizeof h);
    return f;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    check_open(fuzz_memfd(data, size), size);
    if (size >= sizeof(cache_file_header)) {
        uint8_t *f = make_plausible(data, size);
        check_open(fuzz_memfd(f, size), size);
        free(f);
    }
    return 0;
}
