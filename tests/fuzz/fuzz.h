/* fuzz.h - what the libFuzzer targets in tests/fuzz/ share (README.md there).
 *
 * Each target is one file with LLVMFuzzerTestOneInput. Parsers that read a
 * named file get the input through fuzz_memfd (a regular file in memory) or
 * fuzz_write into the process's scratch directory. A target checks more than
 * "no crash": a failed parse must say why in one line that starts with the
 * name it was given (fuzz_check_error), and a successful one must hold what
 * the parser promises; a broken promise aborts as a finding (fuzz_fail). */
#ifndef TESSERA_FUZZ_H
#define TESSERA_FUZZ_H

#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"

struct mesh;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Report a broken promise on stdout (libFuzzer runs may silence stderr) and
 * abort, which libFuzzer records as a crash with its input. */
void fuzz_fail(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));

/* The bytes as the contents of a regular file, returned as its path
 * ("/proc/self/fd/N" of one memfd per process, rewritten per call). */
const char *fuzz_memfd(const uint8_t *data, size_t size);

/* A directory made once per process (mkdtemp under $TMPDIR, else /tmp),
 * removed with its files at exit. */
const char *fuzz_scratch_dir(void);

/* Write the bytes to `path` (created or truncated); a failure is the
 * harness's, reported by fuzz_fail. */
void fuzz_write(const char *path, const void *data, size_t size);

/* A parse of `name` failed: err must hold one line starting with `name`,
 * with no control characters (messages quote input and must stay one line). */
void fuzz_check_error(const tess_error *err, const char *name);

/* A loaded mesh must pass mesh_validate, have its colours in [0, 1] and its
 * material names terminated; every array element is read, so the sanitizer
 * sees any array shorter than its count. */
void fuzz_check_mesh(const struct mesh *m, const char *name);

/* Call at the end of every input of a target whose library may leak (assimp). libFuzzer's own
 * per-input leak check runs only when an input made more allocations than frees, is skipped
 * for the last input of a run, and is switched off for good after 1,000 tries; a leak it misses
 * is found at exit with no input to show for it. This keeps the last FUZZ_RECENT_INPUTS inputs,
 * runs LeakSanitizer after every FUZZ_RECENT_INPUTS-th one and at exit, and on a leak writes
 * those inputs to $FUZZ_SUSPECT_DIR (else the working directory) as leak-suspect-K (K = 1 the
 * oldest) before aborting as a finding. Each suspect is then run alone to find the leaking one. */
#define FUZZ_RECENT_INPUTS 16
void fuzz_watch_leaks(const uint8_t *data, size_t size);

#endif
