/* dump.c - wall/dump.h: frame paths here, image files through the image module.
 *
 * The image module (wall/dump_oiio.cpp, linked against OpenImageIO; why it is a module:
 * wall/dump_module.h) is embedded in the executable by wall/dump_module_blob.S. The first
 * call that reads or writes an image loads it: the embedded bytes go to a memfd, which
 * dlopen() maps. TESSERA_IMAGE_MODULE=PATH loads PATH instead (a module built by the same
 * tree; the sanitizer runs point it at the file so that reports inside it are symbolized).
 *
 * Threads: the load runs once (pthread_once); `module_ops` and `module_error` are written
 * only inside it and read only after it, so they need no lock. */
#define _GNU_SOURCE /* memfd_create */
#include "dump.h"

#include "dump_module.h"

#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

/* the module's bytes, from wall/dump_module_blob.S */
extern const unsigned char tess_dump_module_start[];
extern const unsigned char tess_dump_module_end[];

static pthread_once_t module_once = PTHREAD_ONCE_INIT;
static const dump_module_ops *module_ops;          /* set by load_module; NULL when it failed */
static char module_error[TESS_ERROR_MSG_BYTES];    /* why it failed */

/* the host's calls lent to the module (dump_module.h: the fault tests' wraps reach them) */
static const dump_module_io module_io = {DUMP_MODULE_ABI, pwrite, close};

/* The embedded module as a file: a memfd holding its bytes; -1 with module_error set. */
static int embedded_module_fd(void)
{
    const unsigned char *bytes = tess_dump_module_start;
    size_t size = (size_t)(tess_dump_module_end - tess_dump_module_start);
    int fd = memfd_create("tessera-image-module", MFD_CLOEXEC);
    if (fd < 0) {
        snprintf(module_error, sizeof module_error, "memfd_create: %s", strerror(errno));
        return -1;
    }
    for (size_t done = 0; done < size;) {
        ssize_t n = write(fd, bytes + done, size - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            snprintf(module_error, sizeof module_error, "writing it to a memfd: %s",
                     n < 0 ? strerror(errno) : "short write");
            syscall(SYS_close, fd);
            return -1;
        }
        done += (size_t)n;
    }
    return fd;
}

static void load_module(void)
{
    const char *path = getenv("TESSERA_IMAGE_MODULE");
    char fd_path[64];
    int fd = -1;
    if (!path || !*path) {
        fd = embedded_module_fd();
        if (fd < 0)
            return;
        snprintf(fd_path, sizeof fd_path, "/proc/self/fd/%d", fd);
        path = fd_path;
    }
    /* RTLD_LOCAL: OpenImageIO's 260 libraries stay out of the global scope; never closed */
    void *module = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (fd >= 0) /* the mapping keeps the bytes; the raw system call, so that no test's wrap of
                  * close(2) (tests/fault/fault_io.c) counts this one */
        syscall(SYS_close, fd);
    if (!module) {
        const char *why = dlerror();
        snprintf(module_error, sizeof module_error, "%s", why ? why : "dlopen failed");
        return;
    }
    dump_module_entry_fn entry;
    void *sym = dlsym(module, DUMP_MODULE_ENTRY);
    memcpy(&entry, &sym, sizeof entry); /* (ISO C has no cast from object to function pointer) */
    const dump_module_ops *ops = entry ? entry(&module_io) : NULL;
    if (!ops || ops->abi != DUMP_MODULE_ABI) {
        snprintf(module_error, sizeof module_error, "%s: not an image module of this build (%s)",
                 fd >= 0 ? "the embedded module" : path, entry ? "another ABI" : "no " DUMP_MODULE_ENTRY);
        return;
    }
    module_ops = ops;
}

/* The module's functions, or NULL with err naming the file the caller wanted and why. */
static const dump_module_ops *image_module(const char *path, tess_error *err)
{
    pthread_once(&module_once, load_module);
    if (!module_ops)
        tess_error_set(err, "%s: images cannot be read or written: the OpenImageIO module did not load: %s",
                       path ? path : "(null)", module_error);
    return module_ops;
}

bool dump_write_rgb(const char *path, int width_px, int height_px, const float *rgb_linear, tess_error *err)
{
    const dump_module_ops *ops = image_module(path, err);
    return ops && ops->write_rgb(path, width_px, height_px, rgb_linear, err);
}

bool dump_read_rgb8(const char *path, int *width_px, int *height_px, uint8_t **rgb_out, tess_error *err)
{
    const dump_module_ops *ops = image_module(path, err);
    return ops && ops->read_rgb8(path, width_px, height_px, rgb_out, err);
}

bool dump_read_rgbf(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err)
{
    const dump_module_ops *ops = image_module(path, err);
    return ops && ops->read_rgbf(path, width_px, height_px, rgb_out, err);
}

bool dump_read_linear_rgb(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err)
{
    const dump_module_ops *ops = image_module(path, err);
    return ops && ops->read_linear_rgb(path, width_px, height_px, rgb_out, err);
}

/* ---- frame paths (no image library needed) ---- */

/* One frame-number field of a pattern: pattern[at, at + len) becomes the frame number
 * zero-padded to `digits`. */
typedef struct frame_field {
    size_t at, len, digits;
} frame_field;

/* Find the frame-number field of `pattern`: *found says whether there is one (then *field
 * is set); false (with err) for a malformed pattern. */
static bool find_field(const char *pattern, frame_field *field, bool *found, tess_error *err)
{
    const size_t max_digits = 4096; /* wider than any path; caps %0Nd parsing well below overflow */
    *found = false;
    for (size_t i = 0; pattern[i];) {
        frame_field f = {i, 0, 0};
        if (pattern[i] == '#') {
            while (pattern[i + f.len] == '#')
                f.len++;
            f.digits = f.len;
        } else if (pattern[i] == '%') {
            size_t j = i + 1;
            const bool zero = pattern[j] == '0';
            size_t width = 0;
            while (pattern[j] >= '0' && pattern[j] <= '9') {
                width = width * 10 + (size_t)(pattern[j++] - '0');
                if (width > max_digits)
                    return tess_error_set(err, "%s: frame-number field width too large", pattern);
            }
            if (pattern[j] == 'd') {
                if (width > 0 && !zero)
                    return tess_error_set(err, "%s: space-padded '%%Nd' is not supported, use '%%0Nd' or '#'",
                                          pattern);
                f.len = j + 1 - i;
                f.digits = width > 0 ? width : 1;
            }
        }
        if (f.len == 0) { /* any other character, including a lone '%', is literal */
            i++;
            continue;
        }
        if (*found)
            return tess_error_set(err, "%s: more than one frame-number field", pattern);
        *field = f;
        *found = true;
        i += f.len;
    }
    return true;
}

bool dump_frame_path(const char *pattern, int frame, bool sequence, char *out, size_t out_bytes,
                     tess_error *err)
{
    if (!pattern || !out || out_bytes == 0)
        return tess_error_set(err, "%s: frame path: NULL argument or empty buffer", pattern ? pattern : "(null)");
    out[0] = '\0';
    if (frame < 0)
        return tess_error_set(err, "%s: frame number %d is negative", pattern, frame);

    frame_field field = {0, 0, 0};
    bool found;
    if (!find_field(pattern, &field, &found, err))
        return false;

    const size_t pattern_len = strlen(pattern);
    if (!found && !sequence) {
        if (pattern_len >= out_bytes)
            return tess_error_set(err, "%s: frame %d path needs %zu bytes, buffer has %zu", pattern, frame,
                                  pattern_len + 1, out_bytes);
        memcpy(out, pattern, pattern_len + 1);
        return true;
    }
    const char *insert = ""; /* "_" before a number the pattern had no field for */
    if (!found) {            /* "_NNNN" before the extension of the last component */
        const char *base = strrchr(pattern, '/');
        base = base ? base + 1 : pattern;
        const char *dot = strrchr(base, '.');
        field.at = (dot && dot != base) ? (size_t)(dot - pattern) : pattern_len;
        field.len = 0;
        field.digits = 4;
        insert = "_";
    }
    char number[16];
    size_t number_len = (size_t)snprintf(number, sizeof number, "%d", frame);
    size_t zeros = number_len < field.digits ? field.digits - number_len : 0;
    size_t insert_len = strlen(insert);
    size_t path_len = pattern_len - field.len + insert_len + zeros + number_len;
    if (path_len >= out_bytes)
        return tess_error_set(err, "%s: frame %d path needs %zu bytes, buffer has %zu", pattern, frame,
                              path_len + 1, out_bytes);
    char *at = out;
    memcpy(at, pattern, field.at);
    at += field.at;
    memcpy(at, insert, insert_len);
    at += insert_len;
    memset(at, '0', zeros);
    at += zeros;
    memcpy(at, number, number_len);
    at += number_len;
    memcpy(at, pattern + field.at + field.len, pattern_len - field.at - field.len + 1);
    return true;
}
