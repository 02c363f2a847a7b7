/* series.h - a time series of files loaded one step ahead on a thread of
 * its own: what a particle set's steps and a volume's steps share. The
 * owner (a geometry kind, a shared volume) shows one step; the series'
 * loader thread loads the step asked for next, through the owner's load
 * callback (which may build what the step needs: a tree, a macrocell
 * grid), while frames render; a serial section takes it and swaps it in.
 *
 * POLICY.
 *  - At most two steps in memory: the one shown (the owner's) and one
 *    pending (the series'). Loading another step frees the pending one
 *    first; taking a step hands the pending one to the owner, who frees
 *    the one it showed.
 *  - A step a serial section waits for (series_take: `needed`) goes before
 *    a step asked for ahead (series_request, series_ready: `want`): a
 *    prefetch asked for meanwhile never takes its place, so a storm of
 *    prefetches from another thread cannot starve a take.
 *  - After a take that gave data the owner swaps the step in, frees the
 *    one it showed and calls series_done; until then nothing loads (a
 *    prefetch asked meanwhile would be a third step in memory). Then the
 *    step after the one shown is asked for ahead (playing forward).
 *  - A step that failed to load keeps its error in the pending slot; asking
 *    whether it is ready does not load it again (no retry loop at the
 *    input's rate). Taking a step whose read-ahead failed loads it again
 *    (the file may be there now); taking it again after a take failed
 *    gives the same error without a reload (the other sharers of one step
 *    change: a volume's iso-surfaces and its medium), until another step
 *    loads. The step shown stays shown on every failure.
 *  - The thread starts with the first request, and series_destroy asks it
 *    to stop and joins it: a load in progress finishes first (a destroy
 *    waits for at most one load), its result is freed.
 *
 * CALLBACKS. load(ctx, path, step, err) runs on the loader thread (or on
 * the caller of series_take when no thread can be started) and returns the
 * step's data, or NULL with err set (an error naming the file); it must
 * not touch what the render threads read. free(ctx, data) frees a step's
 * data that was never taken. ctx must outlive the series.
 *
 * Threading: every function but create/destroy may be called from any
 * thread; series.lock (series.c) guards the request and pending state.
 * The owner swaps a taken step in only where nothing traces. */
#ifndef TESSERA_SERIES_H
#define TESSERA_SERIES_H

#include <stdbool.h>
#include <stdint.h>

#include "err.h"

typedef struct series series;

/* One step's data from its file (loader thread); NULL with err set. */
typedef void *(*series_load_fn)(void *ctx, const char *path, uint32_t step, tess_error *err);
/* Free step data the owner never took. */
typedef void (*series_free_fn)(void *ctx, void *data);

/* A series over `count` >= 1 paths (copied) in step order, showing step
 * `shown` (the owner loaded it itself). NULL, err set, on no memory. */
series *series_create(const char *const *paths, uint32_t count, uint32_t shown, series_load_fn load,
                      series_free_fn free_data, void *ctx, tess_error *err);
/* Stop and join the loader (after the load it may be in), free what is
 * pending. NULL is fine. */
void series_destroy(series *s);

uint32_t series_step_count(const series *s);
/* The step shown (the last one taken, or `shown` at creation). */
uint32_t series_step(const series *s);
/* The path of step `step` (< count). */
const char *series_path(const series *s, uint32_t step);

/* Ask for `step` (mod the count) to be loaded ahead. */
void series_request(series *s, uint32_t step);
/* Whether `step` (mod the count) can be taken without waiting: it is shown,
 * or loaded and pending. When not (and it did not fail), it is asked for
 * ahead. */
bool series_ready(series *s, uint32_t step);
/* Make `step` (mod the count) the step shown: wait for its load (at once
 * when it is pending). True with *data the step's data, now the caller's
 * (swap it in and free the old step's), or with *data NULL when the step is
 * shown already (nothing to swap). False with the load's error: the shown
 * step stays. After data, call series_done once the old step is freed. */
bool series_take(series *s, uint32_t step, void **data, tess_error *err);
/* The owner shows the step it took and freed the one before: loading goes
 * on, and the next step is asked for ahead. */
void series_done(series *s);

/* A series' files: the names matching a glob(3) pattern ("melt/step_*.dump"),
 * sorted by name, which is the step order (name steps with leading zeros). */
#define SERIES_MAX_STEPS 100000
typedef struct series_paths {
    char **paths;
    uint32_t count;
    bool failed; /* listing failed (not merely: nothing matched) */
} series_paths;
/* False with err ("no file matches 'P'", also when a folder of P does not
 * exist; too many; a directory that cannot be read); *out is empty then. */
bool series_paths_glob(const char *pattern, series_paths *out, tess_error *err);
void series_paths_free(series_paths *p);

#endif
