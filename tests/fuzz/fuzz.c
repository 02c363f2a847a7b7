/* fuzz.c - the helpers of fuzz.h. */
#define _GNU_SOURCE /* memfd_create */
#include "fuzz.h"

#include "engine/geometry/triangles/mesh.h"

#include <dirent.h>
#include <sanitizer/allocator_interface.h>
#include <sanitizer/lsan_interface.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdint.h>
#include <sys/mman.h>
#include <unistd.h>

/* Huge pages for big blocks. ASan serves every block over 128 KiB from a fresh mmap and
 * unmaps it when the quarantine lets go, so each big block is faulted in page by page, every
 * execution. assimp's OBJ importer allocates and fills a 16 MiB line buffer for every file
 * (IOStreamBuffer), whatever the file's size: 4,096 page faults for each file assimp reads (a
 * page fault costs ~18 us on the 2-vCPU AMD EPYC: 16 MiB faulted in 4 KiB pages 76 ms, in 2 MiB
 * pages 3 ms; fuzz_obj A/B under load there: 42-44 exec/s without this hook, 93 with it). This malloc hook asks for transparent huge pages
 * (MADV_HUGEPAGE; honoured where /sys/kernel/mm/transparent_hugepage/enabled is "madvise" or
 * "always", a no-op under "never") on the 2 MiB-aligned part of every block of 4 MiB or more.
 * It changes no check: ASan still owns, poisons, quarantines and leak-checks the block. */
#define HUGE_BLOCK_MIN_BYTES ((size_t)4 << 20)
#define HUGE_PAGE_BYTES ((uintptr_t)2 << 20)

static void huge_pages_for_big_blocks(const volatile void *block, size_t size)
{
    if (size < HUGE_BLOCK_MIN_BYTES)
        return;
    uintptr_t start = ((uintptr_t)block + HUGE_PAGE_BYTES - 1) & ~(HUGE_PAGE_BYTES - 1);
    uintptr_t end = ((uintptr_t)block + size) & ~(HUGE_PAGE_BYTES - 1);
    if (end > start)
        (void)madvise((void *)start, end - start, MADV_HUGEPAGE); /* advice: failure changes no result */
}

static void no_free_hook(const volatile void *block) { (void)block; }

__attribute__((constructor)) static void install_allocation_hooks(void)
{
    /* both hooks or none: the runtime refuses a NULL one */
    if (!__sanitizer_install_malloc_and_free_hooks(huge_pages_for_big_blocks, no_free_hook))
        fprintf(stderr, "fuzz: could not install the huge-page malloc hook (big blocks fault in 4 KiB pages)\n");
}

void fuzz_fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("fuzz: FINDING: ", stdout);
    vfprintf(stdout, fmt, ap);
    fputc('\n', stdout);
    va_end(ap);
    fflush(stdout);
    abort();
}

static void write_all(int fd, const void *data, size_t size, const char *what)
{
    const char *p = data;
    while (size > 0) {
        ssize_t n = write(fd, p, size);
        if (n <= 0)
            fuzz_fail("harness: cannot write %s", what);
        p += n;
        size -= (size_t)n;
    }
}

const char *fuzz_memfd(const uint8_t *data, size_t size)
{
    static int fd = -1;
    static char path[64];
    if (fd < 0) {
        fd = memfd_create("fuzz-input", 0);
        if (fd < 0)
            fuzz_fail("harness: memfd_create failed");
        snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    }
    if (ftruncate(fd, 0) != 0 || lseek(fd, 0, SEEK_SET) != 0)
        fuzz_fail("harness: cannot truncate the memfd");
    write_all(fd, data, size, "the memfd");
    return path;
}

static char scratch[256];

static void remove_scratch(void)
{
    DIR *d = opendir(scratch);
    if (d) {
        for (struct dirent *e; (e = readdir(d));) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            char path[512];
            snprintf(path, sizeof path, "%s/%s", scratch, e->d_name);
            unlink(path);
        }
        closedir(d);
    }
    rmdir(scratch);
}

const char *fuzz_scratch_dir(void)
{
    if (!scratch[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(scratch, sizeof scratch, "%s/tessera-fuzz-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
        if (!mkdtemp(scratch))
            fuzz_fail("harness: cannot make a scratch directory under %s", tmp && tmp[0] ? tmp : "/tmp");
        atexit(remove_scratch);
    }
    return scratch;
}

void fuzz_write(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        fuzz_fail("harness: cannot write %s", path);
    bool written = size == 0 || fwrite(data, 1, size, f) == size;
    if (fclose(f) != 0 || !written)
        fuzz_fail("harness: cannot write %s", path);
}

void fuzz_check_error(const tess_error *err, const char *name)
{
    const char *msg = err->msg;
    if (!msg[0])
        fuzz_fail("a failed parse of %s left no error message", name);
    if (strncmp(msg, name, strlen(name)) != 0)
        fuzz_fail("error message does not start with the name '%s': %s", name, msg);
    for (const unsigned char *p = (const unsigned char *)msg; *p; p++)
        if (*p < 0x20 || *p == 0x7F)
            fuzz_fail("error message has control character 0x%02X at byte %d: %s", *p, (int)(p - (const unsigned char *)msg), msg);
}

void fuzz_check_mesh(const mesh *m, const char *name)
{
    tess_error err = {{0}};
    if (!mesh_validate(m, name, &err))
        fuzz_fail("a loaded mesh does not validate: %s", err.msg);
    if (m->vertex_count > m->vertex_capacity || m->triangle_count > m->triangle_capacity)
        fuzz_fail("%s: counts %u, %u exceed capacities %u, %u", name, m->vertex_count, m->triangle_count,
                  m->vertex_capacity, m->triangle_capacity);
    volatile float sink = 0.f;
    for (size_t i = 0; i < 3 * (size_t)m->vertex_count; i++) {
        sink += m->positions[i];
        if (m->normals)
            sink += m->normals[i];
        if (m->colors && !(m->colors[i] >= 0.f && m->colors[i] <= 1.f))
            fuzz_fail("%s: vertex %zu: colour %g outside [0, 1]", name, i / 3, (double)m->colors[i]);
    }
    for (uint32_t i = 0; i < m->material_count; i++) {
        if (!memchr(m->materials[i].name, '\0', sizeof m->materials[i].name))
            fuzz_fail("%s: material %u: name not terminated", name, i);
        for (int k = 0; k < 3; k++)
            if (!(m->materials[i].diffuse_rgb[k] >= 0.f && m->materials[i].diffuse_rgb[k] <= 1.f))
                fuzz_fail("%s: material %u: diffuse %g outside [0, 1]", name, i, (double)m->materials[i].diffuse_rgb[k]);
    }
    (void)sink;
}

/* The last inputs (fuzz_watch_leaks), oldest at recent_next once the ring is full. Only the
 * fuzzing thread touches them. The copies are reachable from here, so they are no leak. */
static struct recent_input {
    uint8_t *bytes;
    size_t size;
} recent[FUZZ_RECENT_INPUTS];
static unsigned recent_next;      /* ring slot the next input goes to */
static unsigned long inputs_seen; /* inputs since the process began */

static void write_suspects(void)
{
    const char *dir = getenv("FUZZ_SUSPECT_DIR");
    if (!dir || !dir[0])
        dir = ".";
    unsigned kept = inputs_seen < FUZZ_RECENT_INPUTS ? (unsigned)inputs_seen : FUZZ_RECENT_INPUTS;
    unsigned first = inputs_seen < FUZZ_RECENT_INPUTS ? 0 : recent_next;
    for (unsigned k = 0; k < kept; k++) {
        const struct recent_input *in = &recent[(first + k) % FUZZ_RECENT_INPUTS];
        char path[512];
        snprintf(path, sizeof path, "%s/leak-suspect-%u", dir, k + 1);
        FILE *f = fopen(path, "wb");
        bool written = f && (in->size == 0 || fwrite(in->bytes, 1, in->size, f) == in->size);
        if (f && fclose(f) != 0)
            written = false;
        printf("fuzz: leak suspect %u of %u (%zu bytes): %s%s\n", k + 1, kept, in->size, path,
               written ? "" : " (could not be written)");
    }
    fflush(stdout);
}

static void check_leaks(const char *when)
{
    if (inputs_seen == 0 || !__lsan_do_recoverable_leak_check())
        return;
    write_suspects();
    fuzz_fail("LeakSanitizer found a leak %s (report above); one of the %lu inputs before it "
              "leaks: run each leak-suspect-K alone", when,
              inputs_seen < FUZZ_RECENT_INPUTS ? inputs_seen : (unsigned long)FUZZ_RECENT_INPUTS);
}

static void check_leaks_at_exit(void) { check_leaks("at exit"); }

void fuzz_watch_leaks(const uint8_t *data, size_t size)
{
    if (inputs_seen == 0)
        atexit(check_leaks_at_exit);
    struct recent_input *in = &recent[recent_next];
    uint8_t *copy = realloc(in->bytes, size ? size : 1);
    if (!copy)
        fuzz_fail("harness: out of memory keeping an input of %zu bytes", size);
    if (size)
        memcpy(copy, data, size);
    in->bytes = copy;
    in->size = size;
    recent_next = (recent_next + 1) % FUZZ_RECENT_INPUTS;
    inputs_seen++;
    if (inputs_seen % FUZZ_RECENT_INPUTS == 0)
        check_leaks("after an input");
}
