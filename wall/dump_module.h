/* dump_module.h - the boundary between wall/dump.c and the image module.
 *
 * OpenImageIO is loaded only by a process that reads or writes an image file.
 * Debian's libOpenImageIO pulls in about 260 shared libraries (GDAL, OpenCV,
 * OpenVDB, GDCM, FFmpeg, ...), and linking it into the executable cost every
 * start 0.33 s of CPU (measured: an empty main() linked with -lOpenImageIO
 * takes 0.33 s, one linked with every other dependency of tessera 0.00 s;
 * `tessera --version` 0.45 s), whether or not the process touches an image:
 * the test suite starts over 2,000 processes. So wall/dump_oiio.cpp (the one
 * C++ file) is built as a shared module of its own, linked against
 * OpenImageIO, and embedded in each executable (wall/dump_module_blob.S);
 * wall/dump.c loads it on the first call of a dump.h function.
 *
 * The module's one exported symbol, DUMP_MODULE_ENTRY, takes the host's I/O
 * calls (so the host's system-call wrappers, e.g. the fault tests' pwrite and
 * close, also reach the module's writes) and returns the table of the dump.h
 * functions. DUMP_MODULE_ABI changes whenever either struct does. */
#ifndef TESSERA_DUMP_MODULE_H
#define TESSERA_DUMP_MODULE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "engine/base/err.h"

#ifdef __cplusplus
extern "C" {
#endif

#define DUMP_MODULE_ABI 1
#define DUMP_MODULE_ENTRY "tessera_dump_module"

/* what the host lends the module: the calls its checked output file makes */
typedef struct dump_module_io {
    int abi;                                                   /* DUMP_MODULE_ABI */
    ssize_t (*pwrite)(int fd, const void *buf, size_t bytes, off_t offset);
    int (*close)(int fd);
} dump_module_io;

/* the dump.h functions, as the module implements them (same contracts) */
typedef struct dump_module_ops {
    int abi; /* DUMP_MODULE_ABI */
    bool (*write_rgb)(const char *path, int width_px, int height_px, const float *rgb_linear, tess_error *err);
    bool (*read_rgb8)(const char *path, int *width_px, int *height_px, uint8_t **rgb_out, tess_error *err);
    bool (*read_rgbf)(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err);
    bool (*read_linear_rgb)(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err);
} dump_module_ops;

/* The module's entry (looked up by the name DUMP_MODULE_ENTRY): NULL when io->abi is not
 * DUMP_MODULE_ABI. Called once; io stays valid for the process's life. */
typedef const dump_module_ops *(*dump_module_entry_fn)(const dump_module_io *io);

#ifdef __cplusplus
}
#endif

#endif
