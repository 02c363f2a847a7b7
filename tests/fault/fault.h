/* fault.h - allocation failures on purpose, for the fault tests (SQLite's
 * malloc fault tests are the shape: fail the n-th allocation of one
 * operation, for every n, and check that it fails cleanly).
 *
 * The fault test binary is linked with -Wl,--wrap=malloc,calloc,realloc,...
 * (the Makefile's FAULT_WRAP), so every allocation call in OUR objects (the
 * engine, wall, input, the CLI objects, these tests) goes through
 * fault_alloc.c; the libraries' own allocations (json-c, assimp, OpenImageIO,
 * Criterion, libc) do not, so only our handling of a failure is tested.
 *
 * Counting is armed around one operation at a time; the counter is atomic,
 * so allocations on the operation's worker threads count too (the operations
 * swept allocate in a fixed order whatever the threads: checked by the sweep,
 * which must see the same count twice). */
#ifndef TESSERA_TESTS_FAULT_H
#define TESSERA_TESTS_FAULT_H

#include <stdbool.h>
#include <stddef.h>

/* From now on count allocations; the n-th (n >= 1) fails, once (the ones
 * after it succeed again, so fallbacks and recovery paths run). n = 0
 * counts without failing any. */
void fault_arm(long n);

/* Stop counting; returns how many allocations were counted while armed. */
long fault_disarm(void);

/* Whether the armed failure happened (since the last fault_arm). */
bool fault_fired(void);

/* One operation under test. Runs it and calls fault_disarm() as soon as it
 * returns (so checking the result is not counted); on failure returns false
 * with the error message in msg (the tess_error text, or what the CLI
 * printed); on success checks the result against the fault-free one
 * (*same), frees it and returns true. */
typedef bool (*fault_op_fn)(void *ctx, char *msg, size_t msg_bytes, bool *same);

typedef struct fault_sweep_stats {
    long allocations; /* counted in one fault-free run: the sweep's size */
    long failed;      /* steps where the operation failed (with a checked message) */
    long recovered;   /* steps where it succeeded anyway (a fallback), with the same result */
} fault_sweep_stats;

/* Run `op` once counting allocations, then for n = 1 .. count with the n-th
 * failing. Every failure must give a message containing each string of
 * `needles` (NULL-terminated: the file name, ...) and "out of memory" (or
 * strerror(ENOMEM), for a failed fopen); a success must give the fault-free
 * result. Under AddressSanitizer, LeakSanitizer then checks that nothing
 * leaked. Criterion assertions report the first problem with its n. */
fault_sweep_stats fault_sweep(const char *name, fault_op_fn op, void *ctx, const char *const *needles);

/* Check for leaks now (LeakSanitizer when built with it; else nothing):
 * false when a leak was found (its report is on stderr). */
bool fault_no_leaks(void);

/* ---- I/O (fault_io.c) ------------------------------------------------------ */

/* From now on our objects' pwrite() calls fail with errnum after `skip`
 * more succeed (a disk that dies mid-file), until fault_io_reset. */
void fault_io_fail_pwrite(int errnum, long skip);

/* The next close() by our objects closes the descriptor and then reports
 * errnum (write-back failed), once. */
void fault_io_fail_close(int errnum);

void fault_io_reset(void);

#endif
