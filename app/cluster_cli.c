/* cluster_cli.c - a wall of several machines on the command line (cluster_cli.h). */
#define _GNU_SOURCE /* sched_getaffinity, CPU_COUNT */
#include "cluster_cli.h"

#include <sched.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "pipeline_cli.h"
#include "cluster/cluster.h"
#include "engine/base/log.h"
#include "engine/frame/pipeline.h"
#include "wall/display_backend.h"
#include "wall/wall_config.h"

/* The cluster of this process (one a process). */
static struct {
    cluster *c;
    int node;
    bool outputs[WALL_MAX_OUTPUTS];
    bool ended;
} active = {NULL, -1, {false}, false};

bool cli_cluster_begin(cli_pipeline_spec *s)
{
    if (!cluster_launched() || active.c)
        return true;
    tess_error err = {{0}};
    if (!s->wall_file[0]) {
        cli_error("started by mpirun: give --wall FILE whose \"nodes\" say which outputs each process drives");
        return false;
    }
    wall_config wall;
    if (!wall_config_load(s->wall_file, &wall, &err)) {
        cli_error("%s", err.msg);
        return false;
    }
    if (wall.node_count == 0) {
        cli_error("%s: started by mpirun, but the wall has no \"nodes\" (which outputs each process drives)",
                  s->wall_file);
        return false;
    }
    cluster_config cfg = {.timeout_s = s->sync_timeout_s, .leader = s->input_rank,
                          .on_loss = s->carry_on_node_loss ? CLUSTER_CARRY_ON : CLUSTER_STOP};
    if (!(active.c = cluster_start(NULL, NULL, &cfg, &err))) {
        cli_error("%s", err.msg);
        return false;
    }
    int rank = cluster_rank(active.c);
    active.node = wall_config_node_of(&wall, rank, cluster_size(active.c), cluster_hosts(active.c), &err);
    if (active.node < 0) {
        cli_error("%s: %s", s->wall_file, err.msg);
        return false;
    }
    memcpy(active.outputs, wall.nodes[active.node].outputs, sizeof active.outputs);
    cpu_set_t cpus; /* mpirun binds each process to one core unless told otherwise */
    if (sched_getaffinity(0, sizeof cpus, &cpus) == 0 && CPU_COUNT(&cpus) < s->threads)
        log_warn("cluster: rank %d may run on %d CPU%s but renders with %d threads: mpirun binds a process to a "
                 "core unless given --bind-to none (or --map-by node:PE=%d)",
                 rank, CPU_COUNT(&cpus), CPU_COUNT(&cpus) == 1 ? "" : "s", s->threads, s->threads);
    if (rank != cluster_leader(active.c)) { /* a follower: what changes the picture comes from the leader */
        s->input.enabled = 0;
        s->input.replay_file[0] = '\0';
        s->input.replay_speed_given = false;
        s->input.record_file[0] = '\0';
        s->remote.port = -1;
        s->path_file[0] = '\0';
        s->record_file[0] = '\0';
    }
    return true;
}

bool cli_cluster_active(void) { return active.c != NULL; }
bool cli_cluster_follower(void) { return active.c && cluster_rank(active.c) != cluster_leader(active.c); }
const bool *cli_cluster_outputs(void) { return active.c ? active.outputs : NULL; }

bool cli_cluster_agree(const accel *a)
{
    if (!active.c)
        return true;
    tess_error err = {{0}};
    if (!cluster_agree(active.c, accel_checksum(a), "the acceleration structure's checksum", &err)) {
        cli_error("%s", err.msg);
        return false;
    }
    return true;
}

/* display_flip_fn: an output's flip is the frame on screen; the cluster keeps its time
 * (CLOCK_REALTIME, the clock the processes compare) for the scan-out skew. */
static void note_flip(void *ctx, uint64_t frame, const char *output, unsigned vblank_sequence,
                      int64_t vblank_monotonic_us)
{
    (void)output, (void)vblank_sequence; /* the backend logs them */
    struct timespec real, mono;
    clock_gettime(CLOCK_REALTIME, &real);
    clock_gettime(CLOCK_MONOTONIC, &mono);
    int64_t offset_us = ((int64_t)real.tv_sec - mono.tv_sec) * 1000000 + (real.tv_nsec - mono.tv_nsec) / 1000;
    cluster_note_scanout(ctx, frame, vblank_monotonic_us + offset_us);
}

bool cli_cluster_attach(struct pipeline *p, display_instance *outputs)
{
    if (!active.c)
        return true;
    /* scan-out on a device: its flips say when each frame reached the screen */
    display_instance_set_flip_hook(outputs, note_flip, active.c);
    tess_error err = {{0}};
    if (!cluster_attach(active.c, p, &err)) {
        cli_error("%s", err.msg);
        return false;
    }
    return true;
}

bool cli_cluster_report(void)
{
    if (!active.c)
        return false;
    cluster_print_stats(active.c, stderr);
    cluster_stats st = cluster_get_stats(active.c);
    if (st.failed)
        return true;
    if (st.alone || st.nodes_lost > 0) /* carried on as configured: no skew over the ones left */
        return false;
    cluster_skew k;
    tess_error err = {{0}};
    if (!cluster_flip_skew(active.c, &k, &err)) {
        cli_error("%s", err.msg);
        return true;
    }
    if (cluster_rank(active.c) == cluster_leader(active.c)) {
        fprintf(stderr,
                "tessera: cluster: flip skew over %llu frames: median %.0f us, p95 %.0f us, max %.0f us (frames out "
                "of step: %llu)\n",
                (unsigned long long)k.barrier.frames, k.barrier.median_us, k.barrier.p95_us, k.barrier.max_us,
                (unsigned long long)k.barrier.frames_out_of_step);
        if (k.scanout.frames > 0)
            fprintf(stderr,
                    "tessera: cluster: scan-out skew (first to last output's flip, by vblank time) over %llu frames: "
                    "median %.0f us, p95 %.0f us, max %.0f us\n",
                    (unsigned long long)k.scanout.frames, k.scanout.median_us, k.scanout.p95_us, k.scanout.max_us);
    }
    return k.barrier.frames_out_of_step > 0;
}

void cli_cluster_end(void)
{
    if (active.ended)
        return;
    active.ended = true;
    cluster_finish(active.c);
    active.c = NULL;
}
