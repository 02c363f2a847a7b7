/* series.c - a time series loaded one step ahead (series.h). */
#include "series.h"

#include <errno.h>
#include <glob.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thread_name.h"

/* no step (want, needed, pending.step) */
#define NO_STEP UINT32_MAX

/* The pending slot: a step being loaded, loaded, or failed. */
typedef enum slot_state { SLOT_EMPTY, SLOT_LOADING, SLOT_READY, SLOT_FAILED } slot_state;

/* lock guards want, needed, pending, held, quit and loader_started; cond
 * signals every change of them. shown is written under lock (series_take)
 * and read anywhere. */
struct series {
    char **paths;             /* count file names, in step order; owned */
    uint32_t count;
    series_load_fn load;
    series_free_fn free_data;
    void *ctx;                /* the callbacks' */
    atomic_uint shown;        /* the step the owner shows */
    pthread_mutex_t lock;
    pthread_cond_t cond;
    pthread_t loader;
    bool loader_started, quit;
    uint32_t want;            /* the step to load ahead; NO_STEP: none */
    uint32_t needed;          /* the step series_take waits for; NO_STEP: none. It goes before want */
    bool held;                /* between a take that gave data and series_done: the owner holds two
                                 steps, so nothing loads */
    struct {
        uint32_t step;        /* NO_STEP: none */
        slot_state state;
        void *data;           /* SLOT_READY: the step's data, owned until taken */
        char error[TESS_ERROR_MSG_BYTES]; /* SLOT_FAILED: why */
        bool reported;        /* SLOT_FAILED: a take returned the error: the next take of the step
                                 (another sharer of the same step change) gets it without a reload */
    } pending;
};

static void pending_clear(series *S)
{
    if (S->pending.data)
        S->free_data(S->ctx, S->pending.data);
    S->pending.data = NULL;
    S->pending.state = SLOT_EMPTY;
}

/* The step the pending slot should hold (lock held). */
static uint32_t target(const series *S) { return S->needed != NO_STEP ? S->needed : S->want; }

/* Load `step` into the pending slot (lock held; released during the load). */
static void load_pending(series *S, uint32_t step)
{
    pending_clear(S);
    S->pending.step = step;
    S->pending.state = SLOT_LOADING;
    const char *path = S->paths[step];
    pthread_mutex_unlock(&S->lock);

    tess_error why = {{0}};
    void *data = S->load(S->ctx, path, step, &why);

    pthread_mutex_lock(&S->lock);
    if (data) {
        S->pending.data = data;
        S->pending.state = SLOT_READY;
    } else {
        snprintf(S->pending.error, sizeof S->pending.error, "%s",
                 why.msg[0] ? why.msg : "cannot load the step");
        S->pending.state = SLOT_FAILED;
        S->pending.reported = false;
    }
    pthread_cond_broadcast(&S->cond);
}

/* The loader thread: loads the step asked for (target) while frames render. */
static void *loader_main(void *arg)
{
    series *S = arg;
    thread_name_set("tess-series");
    pthread_mutex_lock(&S->lock);
    for (;;) {
        while (!S->quit && (S->held || target(S) == NO_STEP ||
                            (S->pending.step == target(S) && S->pending.state != SLOT_EMPTY)))
            pthread_cond_wait(&S->cond, &S->lock);
        if (S->quit)
            break;
        load_pending(S, target(S));
    }
    pthread_mutex_unlock(&S->lock);
    return NULL;
}

/* The loader runs (if a thread can be had) and sees the latest request
 * (lock held). */
static void wake(series *S)
{
    if (!S->loader_started)
        S->loader_started = pthread_create(&S->loader, NULL, loader_main, S) == 0;
    pthread_cond_broadcast(&S->cond);
}

/* lock held */
static void request(series *S, uint32_t step)
{
    if (S->want == step)
        return;
    S->want = step;
    wake(S);
}

series *series_create(const char *const *paths, uint32_t count, uint32_t shown, series_load_fn load,
                      series_free_fn free_data, void *ctx, tess_error *err)
{
    if (count == 0 || shown >= count) {
        tess_error_set(err, "series: step %u of %u", shown, count);
        return NULL;
    }
    series *S = calloc(1, sizeof *S);
    if (!S || !(S->paths = calloc(count, sizeof *S->paths)))
        goto oom;
    for (; S->count < count; S->count++) /* count: the paths copied so far */
        if (!(S->paths[S->count] = strdup(paths[S->count])))
            goto oom;
    if (pthread_mutex_init(&S->lock, NULL) != 0)
        goto oom;
    if (pthread_cond_init(&S->cond, NULL) != 0) {
        pthread_mutex_destroy(&S->lock);
        goto oom;
    }
    S->load = load;
    S->free_data = free_data;
    S->ctx = ctx;
    atomic_init(&S->shown, shown);
    S->want = S->needed = NO_STEP;
    S->pending.step = NO_STEP;
    return S;
oom:
    if (S) {
        for (uint32_t i = 0; i < S->count; i++)
            free(S->paths[i]);
        free(S->paths);
        free(S);
    }
    tess_error_set(err, "out of memory for a series of %u steps", count);
    return NULL;
}

void series_destroy(series *S)
{
    if (!S)
        return;
    if (S->loader_started) {
        pthread_mutex_lock(&S->lock);
        S->quit = true;
        pthread_cond_broadcast(&S->cond);
        pthread_mutex_unlock(&S->lock);
        pthread_join(S->loader, NULL);
    }
    pending_clear(S);
    for (uint32_t i = 0; i < S->count; i++)
        free(S->paths[i]);
    free(S->paths);
    pthread_cond_destroy(&S->cond);
    pthread_mutex_destroy(&S->lock);
    free(S);
}

uint32_t series_step_count(const series *S) { return S->count; }
uint32_t series_step(const series *S) { return atomic_load_explicit(&S->shown, memory_order_acquire); }
const char *series_path(const series *S, uint32_t step) { return S->paths[step]; }

void series_request(series *S, uint32_t step)
{
    step %= S->count;
    pthread_mutex_lock(&S->lock);
    if (step != series_step(S))
        request(S, step);
    pthread_mutex_unlock(&S->lock);
}

bool series_ready(series *S, uint32_t step)
{
    step %= S->count;
    pthread_mutex_lock(&S->lock);
    bool ready = step == series_step(S) || (S->pending.step == step && S->pending.state == SLOT_READY);
    if (!ready && !(S->pending.step == step && S->pending.state == SLOT_FAILED))
        request(S, step);
    pthread_mutex_unlock(&S->lock);
    return ready;
}

bool series_take(series *S, uint32_t step, void **data, tess_error *err)
{
    *data = NULL;
    step %= S->count;
    pthread_mutex_lock(&S->lock);
    S->held = false; /* a take ends any swap before it (series_done forgotten) */
    if (step == series_step(S)) {
        pthread_mutex_unlock(&S->lock);
        return true;
    }
    if (S->pending.step == step && S->pending.state == SLOT_FAILED) {
        if (S->pending.reported) { /* failed for this take already: not read again */
            tess_error_set(err, "%s", S->pending.error);
            pthread_mutex_unlock(&S->lock);
            return false;
        }
        pending_clear(S); /* a read-ahead failed: ask again, the file may be there now */
    }
    S->needed = step;
    wake(S);
    if (!S->loader_started && !(S->pending.step == step && S->pending.state == SLOT_READY))
        load_pending(S, step); /* no thread to be had: load here */
    while (!(S->pending.step == step && (S->pending.state == SLOT_READY || S->pending.state == SLOT_FAILED)))
        pthread_cond_wait(&S->cond, &S->lock);
    S->needed = NO_STEP;
    if (S->pending.state == SLOT_FAILED) {
        tess_error_set(err, "%s", S->pending.error);
        S->pending.reported = true;
        S->want = NO_STEP;
        pthread_mutex_unlock(&S->lock);
        return false;
    }
    *data = S->pending.data;
    S->pending.data = NULL;
    S->pending.state = SLOT_EMPTY;
    S->pending.step = NO_STEP;
    atomic_store_explicit(&S->shown, step, memory_order_release);
    S->held = true; /* until series_done: the owner frees the old step first */
    pthread_mutex_unlock(&S->lock);
    return true;
}

void series_done(series *S)
{
    pthread_mutex_lock(&S->lock);
    S->held = false;
    request(S, (series_step(S) + 1) % S->count); /* playing forward: the next one in the background */
    pthread_mutex_unlock(&S->lock);
}

/* glob's error callback: a folder of the pattern that does not exist (or is
 * not a folder) holds no match, as an empty one (so an optional series whose
 * folder is missing is skipped, not an error); any other failure to read a
 * folder stops the listing. With GLOB_ERR glob would stop at a missing folder
 * too. */
static int glob_error(const char *path, int error)
{
    (void)path;
    return error != ENOENT && error != ENOTDIR;
}

bool series_paths_glob(const char *pattern, series_paths *out, tess_error *err)
{
    memset(out, 0, sizeof *out);
    glob_t g;
    int rc = glob(pattern, 0, glob_error, &g);
    if (rc == GLOB_NOMATCH) {
        globfree(&g);
        return tess_error_set(err, "no file matches '%s'", pattern);
    }
    if (rc != 0) {
        globfree(&g);
        out->failed = true;
        return tess_error_set(err, "cannot list the files of '%s'%s", pattern,
                              rc == GLOB_NOSPACE ? ": out of memory" : ": a directory cannot be read");
    }
    if (g.gl_pathc > SERIES_MAX_STEPS) {
        size_t n = g.gl_pathc;
        globfree(&g);
        out->failed = true;
        return tess_error_set(err, "'%s' matches %zu files (at most %d steps)", pattern, n, SERIES_MAX_STEPS);
    }
    out->paths = calloc(g.gl_pathc, sizeof *out->paths);
    for (size_t i = 0; out->paths && i < g.gl_pathc; i++)
        if (!(out->paths[i] = strdup(g.gl_pathv[i]))) {
            out->count = (uint32_t)i;
            series_paths_free(out);
            break;
        }
    if (!out->paths) {
        globfree(&g);
        out->failed = true;
        return tess_error_set(err, "out of memory listing '%s'", pattern);
    }
    out->count = (uint32_t)g.gl_pathc; /* sorted by name (glob's order) */
    globfree(&g);
    return true;
}

void series_paths_free(series_paths *p)
{
    for (uint32_t i = 0; p->paths && i < p->count; i++)
        free(p->paths[i]);
    free(p->paths);
    p->paths = NULL;
    p->count = 0;
}
