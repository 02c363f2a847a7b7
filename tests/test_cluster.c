/* test_cluster.c - a wall of several machines (cluster/), on one machine:
 * `mpirun --oversubscribe -np 4`, each process one output of a 2x2 headless
 * wall (dump display), against the same wall rendered by one process: every
 * output's every frame equal byte for byte, for an orbit and for a replayed
 * input session; a process that stops answering ends the run within the
 * sync time-out with a message naming what was waited for; processes built
 * over different scenes refuse to start; a process count that does not
 * match the wall's nodes is named. Skipped, saying why, where mpirun is
 * missing (tools/deps.sh installs it). */
#define _DEFAULT_SOURCE
#include <criterion/criterion.h>
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cluster/cluster.h"
#include "engine/scene/accel.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "engine/frame/txn.h"
#include "input/record.h"
#include "support.h"
#include "wall/wall_config.h"
#include "ws_client.h"

#define RUN_TIMEOUT_S 300 /* a hang guard, not a speed limit */
/* as root (CI), OpenMPI wants to be told; the environment reaches every process */
#define MPIRUN "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 mpirun"

static const char *wall_text =
    "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": [\n"
    " {\"connector\": \"Virtual-1\", \"mode\": \"96x54\", \"grid\": [0, 0], \"size_mm\": [160, 90], "
    "\"bezel_mm\": {\"right\": 5, \"bottom\": 5}},\n"
    " {\"connector\": \"Virtual-2\", \"mode\": \"96x54\", \"grid\": [1, 0], \"size_mm\": [160, 90], "
    "\"bezel_mm\": {\"right\": 5, \"bottom\": 5}},\n"
    " {\"connector\": \"Virtual-3\", \"mode\": \"96x54\", \"grid\": [0, 1], \"size_mm\": [160, 90], "
    "\"bezel_mm\": {\"right\": 5, \"bottom\": 5}},\n"
    " {\"connector\": \"Virtual-4\", \"mode\": \"96x54\", \"grid\": [1, 1], \"size_mm\": [160, 90], "
    "\"bezel_mm\": {\"right\": 5, \"bottom\": 5}}],\n"
    " \"nodes\": [{\"rank\": 0, \"outputs\": [\"Virtual-1\"]}, {\"rank\": 1, \"outputs\": [\"Virtual-2\"]},\n"
    "           {\"rank\": 2, \"outputs\": [\"Virtual-3\"]}, {\"rank\": 3, \"outputs\": [\"Virtual-4\"]}]}\n";

static void need_mpirun(void)
{
    if (support_run("command -v mpirun > /dev/null 2>&1") != 0)
        cr_skip_test("mpirun is not installed (tools/deps.sh installs openmpi-bin)");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Run a shell command under a hang guard; its status; its output in dir/NAME.log (and *log). */
static int run_logged(const char *dir, const char *name, const char *command, char *log, size_t log_bytes)
{
    char cmd[8192], path[512];
    snprintf(path, sizeof path, "%s/%s.log", dir, name);
    snprintf(cmd, sizeof cmd, "timeout %d sh -c '%s' > '%s' 2>&1", RUN_TIMEOUT_S, command, path);
    int status = support_run(cmd);
    support_read_text(path, log, log_bytes);
    return status;
}

/* Every per-output file (NAME-Virtual-N.png) in dir a equals the one of that name in b; how many. */
static int same_output_files(const char *a, const char *b)
{
    DIR *d = opendir(a);
    cr_assert(d, "%s", a);
    int compared = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (!strstr(e->d_name, "-Virtual-"))
            continue;
        char pa[1024], pb[1024];
        snprintf(pa, sizeof pa, "%s/%s", a, e->d_name);
        snprintf(pb, sizeof pb, "%s/%s", b, e->d_name);
        tess_error err = {{0}};
        int wa, ha, wb, hb;
        uint8_t *ia = NULL, *ib = NULL;
        cr_assert(dump_read_rgb8(pa, &wa, &ha, &ia, &err), "%s", err.msg);
        cr_assert(dump_read_rgb8(pb, &wb, &hb, &ib, &err), "%s (the one-process reference)", err.msg);
        cr_assert(wa == wb && ha == hb && memcmp(ia, ib, (size_t)wa * (size_t)ha * 3) == 0,
                  "%s differs from the one-process wall's", e->d_name);
        free(ia);
        free(ib);
        compared++;
    }
    closedir(d);
    return compared;
}

/* No stitched image from a process that drives part of the wall. */
static bool has_stitched(const char *dir)
{
    DIR *d = opendir(dir);
    cr_assert(d);
    bool found = false;
    struct dirent *e;
    while ((e = readdir(d)))
        found = found || (strstr(e->d_name, ".png") && !strstr(e->d_name, "-Virtual-"));
    closedir(d);
    return found;
}

/* The same wall rendered by 4 processes and by 1; `args`: the rest of the command line. */
static void four_equal_one(const char *name, const char *command, const char *args, int frames)
{
    need_mpirun();
    char dir[256], cmd[4096], log[16384];
    support_make_tmp_dir(dir, sizeof dir, name);
    support_write_file(dir, "wall.json", wall_text);
    snprintf(cmd, sizeof cmd, "mkdir -p %s/four %s/one", dir, dir);
    cr_assert_eq(support_run(cmd), 0);
    snprintf(cmd, sizeof cmd,
             MPIRUN " -np 4 %s %s --wall %s/wall.json --display dump --out %s/four/f_####.png --threads 1 %s",
             support_tessera_bin(), command, dir, dir, args);
    int status = run_logged(dir, "four", cmd, log, sizeof log);
    cr_assert_eq(status, 0, "4 processes: status %d: %s", status, log);
    for (int r = 0; r < 4; r++) {
        char line[64];
        snprintf(line, sizeof line, "cluster: rank %d of 4", r);
        cr_assert(strstr(log, line), "no counts from rank %d: %s", r, log);
    }
    cr_assert_null(strstr(log, "FAILED"), "%s", log);
    snprintf(cmd, sizeof cmd, "%s %s --wall %s/wall.json --display dump --out %s/one/f_####.png --threads 2 %s",
             support_tessera_bin(), command, dir, dir, args);
    status = run_logged(dir, "one", cmd, log, sizeof log);
    cr_assert_eq(status, 0, "1 process: status %d: %s", status, log);
    char four[300], one[300];
    snprintf(four, sizeof four, "%s/four", dir);
    snprintf(one, sizeof one, "%s/one", dir);
    int compared = same_output_files(four, one);
    cr_assert_eq(compared, 4 * frames, "%d output frames compared, %d expected", compared, 4 * frames);
    cr_assert_not(has_stitched(four), "a process driving one output wrote a stitched image");
    cr_assert(has_stitched(one));
    support_remove_tmp_dir(dir);
}

Test(cluster, four_processes_render_the_orbit_of_one_bit_for_bit, .timeout = 900)
{
    four_equal_one("cluster-orbit", "run", "--frames 6", 6);
}

/* A recorded session (cameras, a hide, a status line) replayed on the leader, one record a
 * frame: every process shows what one process shows. */
Test(cluster, a_replayed_input_session_reaches_every_process, .timeout = 900)
{
    need_mpirun();
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "cluster-record");
    /* the records, written as input does */
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert(s, "%s", err.msg);
    camera_desc c = s->camera;
    char text[8192] = INPUT_RECORD_HEADER "\n";
    size_t used = strlen(text);
    for (int i = 0; i < 5; i++) {
        camera_desc k = c;
        k.eye.x += 0.4f * (float)(i + 1);
        k.eye.y += 0.1f * (float)i;
        txn_record r = txn_camera(TXN_ALL_CHANNELS, &k);
        char line[TXN_TEXT_BYTES * 2];
        cr_assert(txn_encode_text(&r, line, sizeof line));
        used += (size_t)snprintf(text + used, sizeof text - used, "%.6f %s\n", 0.1 * i, line);
    }
    /* a hide, and a status line (drawn where the whole wall has it: on the bottom-left output) */
    txn_record more[2] = {txn_geoms_record(TXN_HIDE, 0, 1), txn_status("status from the leader")};
    for (int i = 0; i < 2; i++) {
        char line[TXN_TEXT_BYTES * 2];
        cr_assert(txn_encode_text(&more[i], line, sizeof line));
        used += (size_t)snprintf(text + used, sizeof text - used, "%.6f %s\n", 0.6 + 0.1 * i, line);
    }
    scene_destroy(s);
    support_write_file(dir, "rec.txt", text);
    char args[600];
    snprintf(args, sizeof args, "--frames 8 --replay-input %s/rec.txt --replay-speed frames", dir);
    four_equal_one("cluster-replay", "render", args, 8);
    support_remove_tmp_dir(dir);
}

/* ---- a job in the background: mpirun over `sh -c "echo RANK PID >> DIR/pids; exec tessera ..."` ---- */

/* The command line that starts 4 processes (mpirun options `mpi`) each writing "RANK PID" to
 * dir/pids before it becomes `tessera ARGS` (stdout and stderr to dir/run.log). */
static void job_command(char *cmd, size_t bytes, const char *dir, const char *mpi, const char *args)
{
    snprintf(cmd, bytes,
             MPIRUN " -np 4 %s sh -c \"echo \\$OMPI_COMM_WORLD_RANK \\$\\$ >> %s/pids; exec %s %s\" > %s/run.log 2>&1",
             mpi, dir, support_tessera_bin(), args, dir);
}

static pid_t start_job(const char *cmd)
{
    pid_t job = fork();
    cr_assert(job >= 0);
    if (job == 0) {
        execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
        _exit(127);
    }
    return job;
}

/* Until `end`: wait for `path` to exist (an event: a frame written); whether it does. */
static bool wait_file(const char *path, double end)
{
    while (access(path, F_OK) != 0 && now_s() < end)
        nanosleep(&(struct timespec){0, 20000000}, NULL);
    return access(path, F_OK) == 0;
}

/* The PID of rank `rank` as dir/pids says (0: not there). */
static int rank_pid(const char *dir, int rank)
{
    char path[400], pids[512];
    snprintf(path, sizeof path, "%s/pids", dir);
    support_read_text(path, pids, sizeof pids);
    for (const char *p = pids; *p; ) {
        int r = -1, pid = 0;
        if (sscanf(p, "%d %d", &r, &pid) == 2 && r == rank)
            return pid;
        const char *next = strchr(p, '\n');
        if (!next)
            break;
        p = next + 1;
    }
    return 0;
}

/* Until `end`: wait for the job to end; its wait status (0 when it did not). */
static int wait_job(pid_t job, double end)
{
    int status = 0;
    while (waitpid(job, &status, WNOHANG) == 0 && now_s() < end)
        nanosleep(&(struct timespec){0, 20000000}, NULL);
    return status;
}

/* Run `command` (run or render) on the 4-output wall in dir until stopped, wait until the
 * wall runs (frame 3 of every output written), send `sig` to rank `rank` alone and wait for
 * the job to end: its wait status; *took the seconds from the signal to the end; the job's
 * log in log. */
static int signal_a_running_wall(const char *dir, const char *command, int rank, int sig, double *took, char *log,
                                 size_t log_bytes)
{
    char cmd[4096], args[1024], path[400];
    snprintf(args, sizeof args,
             "%s --wall %s/wall.json --display dump --out %s/f_####.png --frames 100000000 --threads 1 "
             "--sync-timeout 5",
             command, dir, dir);
    job_command(cmd, sizeof cmd, dir, "", args);
    pid_t job = start_job(cmd);
    double end = now_s() + RUN_TIMEOUT_S;
    for (int i = 1; i <= 4; i++) {
        snprintf(path, sizeof path, "%s/f_0003-Virtual-%d.png", dir, i);
        cr_assert(wait_file(path, end), "the wall never ran (%s)", path);
    }
    int pid = rank_pid(dir, rank);
    cr_assert_gt(pid, 0);
    cr_assert_eq(kill(pid, sig), 0);
    double signalled = now_s();
    int status = wait_job(job, end);
    *took = now_s() - signalled;
    kill(pid, SIGKILL); /* a stopped one: what a dead machine is */
    snprintf(path, sizeof path, "%s/run.log", dir);
    support_read_text(path, log, log_bytes);
    return status;
}

/* A process that stops answering (SIGSTOP) while the wall runs ends the run on the others
 * within the sync time-out (5 s here, generous for sanitizer builds) plus a frame: the leader
 * names the lost process and what it waited for, tells the others, and the first to exit
 * (status 3) makes mpirun end the job. */
Test(cluster, a_process_that_stops_answering_ends_the_run_within_the_time_out, .timeout = 900)
{
    need_mpirun();
    char dir[256], log[32768];
    support_make_tmp_dir(dir, sizeof dir, "cluster-stop");
    support_write_file(dir, "wall.json", wall_text);
    double took;
    int status = signal_a_running_wall(dir, "render", 1, SIGSTOP, &took, log, sizeof log);
    cr_assert(WIFEXITED(status) && WEXITSTATUS(status) != 0, "the job ended with status %d: %s", status, log);
    cr_assert(strstr(log, "cluster: rank 0 lost rank 1 (") && strstr(log, "time-out 5.0 s): the wall stops"), "%s",
              log);
    cr_assert(strstr(log, "FAILED"), "%s", log);
    cr_log_info("cluster: the job ended %.2f s after a process stopped answering (time-out 5 s)", took);
    support_remove_tmp_dir(dir);
}

/* Different scenes on different processes: the accel checksums differ and none runs. */
Test(cluster, processes_over_different_scenes_refuse_to_run, .timeout = 900)
{
    need_mpirun();
    char dir[256], cmd[4096], log[16384];
    support_make_tmp_dir(dir, sizeof dir, "cluster-scenes");
    support_write_file(dir, "wall.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"Virtual-1\", \"mode\": \"96x54\", \"grid\": [0, 0], \"size_mm\": [160, 90]},"
                       "{\"connector\": \"Virtual-2\", \"mode\": \"96x54\", \"grid\": [1, 0], \"size_mm\": [160, 90]}],"
                       "\"nodes\": [{\"rank\": 0, \"outputs\": [\"Virtual-1\"]}, {\"rank\": 1, \"outputs\": "
                       "[\"Virtual-2\"]}]}");
    snprintf(cmd, sizeof cmd,
             MPIRUN " -np 1 %s run --wall %s/wall.json --display null --frames 2 : -np 1 %s run --wall %s/wall.json "
                    "--display null --frames 2 --scene ../configs/scenes/cornell_like.json",
             support_tessera_bin(), dir, support_tessera_bin(), dir);
    int status = run_logged(dir, "scenes", cmd, log, sizeof log);
    cr_assert_neq(status, 0, "%s", log);
    cr_assert(strstr(log, "cluster: the acceleration structure's checksum differs: rank 0"), "%s", log);
    /* three processes for a wall of four nodes */
    support_write_file(dir, "four.json", wall_text);
    snprintf(cmd, sizeof cmd, MPIRUN " -np 3 %s run --wall %s/four.json --display null --frames 2",
             support_tessera_bin(), dir);
    status = run_logged(dir, "count", cmd, log, sizeof log);
    cr_assert_neq(status, 0, "%s", log);
    cr_assert(strstr(log, "the wall has 4 nodes and 3 processes were started (mpirun -np 4)"), "%s", log);
    /* an input rank that is not one of them */
    snprintf(cmd, sizeof cmd, MPIRUN " -np 4 %s run --wall %s/four.json --display null --frames 2 --input-rank 5",
             support_tessera_bin(), dir);
    status = run_logged(dir, "input-rank", cmd, log, sizeof log);
    cr_assert_neq(status, 0, "%s", log);
    cr_assert(strstr(log, "the input rank 5 is not one of the 4 processes (0..3)"), "%s", log);
    support_remove_tmp_dir(dir);
}

/* Every machine has its own Virtual-1 and Virtual-2: a wall of two such machines names its
 * outputs by index in the nodes, and the files call them nodeK-NAME; two processes render
 * what one does. With the drm display, another machine's output without an explicit mode is
 * refused before any card is opened: no process could know that monitor's pixels. */
Test(cluster, machines_with_the_same_connector_names_make_one_wall, .timeout = 900)
{
    need_mpirun();
    char dir[256], cmd[4096], log[16384];
    support_make_tmp_dir(dir, sizeof dir, "cluster-shared-names");
    static const char *shared =
        "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": [\n"
        " {\"connector\": \"Virtual-1\", \"mode\": \"96x54\", \"grid\": [0, 0], \"size_mm\": [160, 90]},\n"
        " {\"connector\": \"Virtual-2\", \"mode\": \"96x54\", \"grid\": [1, 0], \"size_mm\": [160, 90]},\n"
        " {\"connector\": \"Virtual-1\", \"mode\": \"%s\", \"grid\": [0, 1], \"size_mm\": [160, 90]},\n"
        " {\"connector\": \"Virtual-2\", \"mode\": \"96x54\", \"grid\": [1, 1], \"size_mm\": [160, 90]}],\n"
        " \"nodes\": [{\"rank\": 0, \"outputs\": [0, 1]}, {\"rank\": 1, \"outputs\": [2, 3]}]}\n";
    char text[2048];
    snprintf(text, sizeof text, shared, "96x54");
    support_write_file(dir, "wall.json", text);
    snprintf(cmd, sizeof cmd, "mkdir -p %s/two %s/one", dir, dir);
    cr_assert_eq(support_run(cmd), 0);
    const char *args = "run --display dump --frames 3";
    snprintf(cmd, sizeof cmd, MPIRUN " -np 2 --bind-to none %s %s --wall %s/wall.json --out %s/two/f_####.png "
                              "--threads 1", support_tessera_bin(), args, dir, dir);
    int status = run_logged(dir, "two", cmd, log, sizeof log);
    cr_assert_eq(status, 0, "2 processes: status %d: %s", status, log);
    snprintf(cmd, sizeof cmd, "%s %s --wall %s/wall.json --out %s/one/f_####.png --threads 2", support_tessera_bin(),
             args, dir, dir);
    status = run_logged(dir, "one", cmd, log, sizeof log);
    cr_assert_eq(status, 0, "1 process: status %d: %s", status, log);
    char two[300], one[300], path[400];
    snprintf(two, sizeof two, "%s/two", dir);
    snprintf(one, sizeof one, "%s/one", dir);
    cr_assert_eq(same_output_files(two, one), 4 * 3);
    const char *names[] = {"node0-Virtual-1", "node0-Virtual-2", "node1-Virtual-1", "node1-Virtual-2"};
    for (int i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/f_0002-%s.png", two, names[i]);
        cr_assert_eq(access(path, R_OK), 0, "no %s", path);
    }
    /* the drm display: node 1's Virtual-1 runs the monitor's preferred mode */
    snprintf(text, sizeof text, shared, "preferred");
    support_write_file(dir, "preferred.json", text);
    snprintf(cmd, sizeof cmd, MPIRUN " -np 2 --bind-to none %s run --wall %s/preferred.json --display drm --frames 2",
             support_tessera_bin(), dir);
    status = run_logged(dir, "drm", cmd, log, sizeof log);
    cr_assert_neq(status, 0, "%s", log);
    cr_assert(strstr(log, "outputs[2] (node1-Virtual-1, another machine's): a wall of several machines needs every "
                          "output's mode in the file"),
              "%s", log);
    support_remove_tmp_dir(dir);
}

/* A display that fails on one process (its output folder replaced by a file mid-run) stops
 * every process at the same step, as a quit would: the failing one still passes the barrier
 * before the flip the others wait at, and its stop goes through the next frame sync. Before,
 * the others waited for it there until the sync time-out and gave it up as lost. */
Test(cluster, a_display_that_fails_on_one_process_stops_every_process_at_the_same_step, .timeout = 900)
{
    need_mpirun();
    char dir[256], cmd[4096], log[16384];
    support_make_tmp_dir(dir, sizeof dir, "cluster-display-fails");
    support_write_file(dir, "wall.json",
                       "{\"format\": \"tessera-wall\", \"version\": 1, \"units\": \"mm\", \"outputs\": ["
                       "{\"connector\": \"Virtual-1\", \"mode\": \"96x54\", \"grid\": [0, 0], \"size_mm\": [160, 90]},"
                       "{\"connector\": \"Virtual-2\", \"mode\": \"96x54\", \"grid\": [1, 0], \"size_mm\": [160, 90]}],"
                       "\"nodes\": [{\"rank\": 0, \"outputs\": [\"Virtual-1\"]}, {\"rank\": 1, \"outputs\": "
                       "[\"Virtual-2\"]}]}");
    snprintf(cmd, sizeof cmd, "mkdir -p %s/a %s/b", dir, dir);
    cr_assert_eq(support_run(cmd), 0);
    /* once rank 1 wrote frame 3, its folder becomes a file: its next write fails */
    const char *args = "run --display dump --frames 100000 --threads 1 --sync-timeout 250";
    snprintf(cmd, sizeof cmd,
             "(while [ ! -e %s/b/f_0003-Virtual-2.png ]; do sleep 0.05; done; mv %s/b %s/b.gone; touch %s/b) & "
             MPIRUN " --bind-to none -np 1 %s %s --wall %s/wall.json --out %s/a/f_####.png : -np 1 %s %s --wall "
             "%s/wall.json --out %s/b/f_####.png; echo status $?",
             dir, dir, dir, dir, support_tessera_bin(), args, dir, dir, support_tessera_bin(), args, dir, dir);
    run_logged(dir, "fails", cmd, log, sizeof log);
    cr_assert(strstr(log, "cannot open for writing"), "rank 1's display did not fail: %s", log);
    cr_assert_null(strstr(log, " lost "), "a process was given up on: %s", log);
    cr_assert_null(strstr(log, "gave up"), "%s", log);
    cr_assert_null(strstr(log, "FAILED"), "%s", log);
    unsigned long long steps[2] = {0, 0};
    for (int r = 0; r < 2; r++) {
        char line[64];
        snprintf(line, sizeof line, "cluster: rank %d of 2", r);
        const char *at = strstr(log, line);
        cr_assert(at, "no counts from rank %d: %s", r, log);
        const char *colon = strstr(at, "): ");
        cr_assert(colon && sscanf(colon, "): %llu frames in step", &steps[r]) == 1, "%s", at);
    }
    cr_assert_eq(steps[0], steps[1], "rank 0 stopped after %llu steps, rank 1 after %llu: %s", steps[0], steps[1],
                 log);
    cr_assert(strstr(log, "status 0") == NULL, "the job ended well although a display failed: %s", log);
    support_remove_tmp_dir(dir);
}

/* The checksum is the build's: the same scene built with 1 and 2 threads agrees, another
 * scene does not. */
Test(cluster, the_accel_checksum_is_the_same_for_the_same_scene)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err), *t = scene_load("../configs/scenes/cornell_like.json", &err);
    cr_assert(s && t, "%s", err.msg);
    accel *a1 = accel_build(s, 1, &err), *a2 = accel_build(s, 2, &err), *b = accel_build(t, 2, &err);
    cr_assert(a1 && a2 && b, "%s", err.msg);
    cr_assert_eq(accel_checksum(a1), accel_checksum(a2), "one scene, built by 1 and by 2 threads");
    cr_assert_neq(accel_checksum(a1), 0u);
    cr_assert_neq(accel_checksum(a1), accel_checksum(b), "another scene");
    accel_destroy(a1);
    accel_destroy(a2);
    accel_destroy(b);
    scene_destroy(s);
    scene_destroy(t);
}

/* The highest frame number of dir/f_NNNN-CONNECTOR.png, -1 for none. */
static int last_frame_of(const char *dir, const char *connector)
{
    DIR *d = opendir(dir);
    cr_assert(d, "%s", dir);
    char pattern[64];
    snprintf(pattern, sizeof pattern, "f_%%d-%s.png%%n", connector);
    int last = -1;
    struct dirent *e;
    while ((e = readdir(d))) {
        int n, used = 0; /* %n: the whole name matched (sscanf counts only the number) */
        if (sscanf(e->d_name, pattern, &n, &used) == 1 && used > 0 && e->d_name[used] == '\0' && n > last)
            last = n;
    }
    closedir(d);
    return last;
}

/* Live input on the leader steers every process: with --input-rank 2 a remote viewer (a raw
 * WebSocket client) on rank 2 drags the wall; rank 2 is then stopped (SIGTERM to it alone: the
 * others stop at the same frame through the stop vote); every output's last frame equals one
 * process's replay of what the leader recorded. */
Test(cluster, live_input_on_the_leader_steers_every_process, .timeout = 900)
{
    need_mpirun();
    char dir[256], cmd[4096], log[16384], path[512];
    support_make_tmp_dir(dir, sizeof dir, "cluster-live");
    support_write_file(dir, "wall.json", wall_text);
    snprintf(cmd, sizeof cmd, "mkdir -p %s/four %s/one", dir, dir);
    cr_assert_eq(support_run(cmd), 0);
    char args[1024];
    snprintf(args, sizeof args,
             "run --wall %s/wall.json --display dump --out %s/four/f_####.png --threads 1 --time fixed --rate 30 "
             "--remote 0 --remote-token cluster-live-token --record-input %s/rec.txt --input-rank 2",
             dir, dir, dir);
    job_command(cmd, sizeof cmd, dir, "", args);
    pid_t job = start_job(cmd);
    /* the leader's URL line (an event), then a viewer */
    double end = now_s() + RUN_TIMEOUT_S;
    int port = 0;
    snprintf(path, sizeof path, "%s/run.log", dir);
    while (!port && now_s() < end) {
        support_read_text(path, log, sizeof log);
        const char *u = strstr(log, "tessera: remote view: http://127.0.0.1:");
        if (!u || sscanf(u, "tessera: remote view: http://127.0.0.1:%d/", &port) != 1)
            nanosleep(&(struct timespec){0, 20000000}, NULL);
    }
    cr_assert_gt(port, 0, "the leader served no remote view: %s", log);
    int status = 0, fd = ws_connect(port, "cluster-live-token", &status);
    cr_assert_eq(status, 101);
    ws_send_text(fd, "{\"t\":\"down\",\"x\":0.5,\"y\":0.5,\"button\":0}");
    for (int i = 1; i <= 8; i++) {
        char move[96];
        snprintf(move, sizeof move, "{\"t\":\"move\",\"x\":%.3f,\"y\":%.3f}", 0.5 + 0.04 * i, 0.5 + 0.01 * i);
        ws_send_text(fd, move);
    }
    ws_send_text(fd, "{\"t\":\"up\",\"x\":0.82,\"y\":0.58,\"button\":0}");
    /* the drag reached the record, then ten more frames on the last process's output */
    snprintf(path, sizeof path, "%s/rec.txt", dir);
    char rec[65536] = "";
    while (!strstr(rec, " camera all ") && now_s() < end) {
        support_read_text(path, rec, sizeof rec);
        nanosleep(&(struct timespec){0, 20000000}, NULL);
    }
    cr_assert(strstr(rec, " camera all "), "the drag recorded no camera");
    char four[300];
    snprintf(four, sizeof four, "%s/four", dir);
    int settled = last_frame_of(four, "Virtual-4") + 10;
    while (last_frame_of(four, "Virtual-4") < settled && now_s() < end)
        nanosleep(&(struct timespec){0, 20000000}, NULL);
    /* the leader (rank 2) alone is stopped */
    int leader = rank_pid(dir, 2);
    cr_assert_gt(leader, 0);
    cr_assert_eq(kill(leader, SIGTERM), 0);
    status = wait_job(job, end);
    close(fd);
    snprintf(path, sizeof path, "%s/run.log", dir);
    support_read_text(path, log, sizeof log);
    cr_assert(WIFEXITED(status) && WEXITSTATUS(status) == 0, "the job ended with status %d: %s", status, log);
    /* one process replays the record: every output's last frame is its picture */
    snprintf(cmd, sizeof cmd,
             "%s render --wall %s/wall.json --display dump --out %s/one/r.png --replay-input %s/rec.txt",
             support_tessera_bin(), dir, dir, dir);
    int replay = run_logged(dir, "replay", cmd, log, sizeof log);
    cr_assert_eq(replay, 0, "%s", log);
    const char *outputs[4] = {"Virtual-1", "Virtual-2", "Virtual-3", "Virtual-4"};
    int last = last_frame_of(four, "Virtual-1");
    for (int i = 0; i < 4; i++) {
        cr_assert_eq(last_frame_of(four, outputs[i]), last, "%s stopped at another frame", outputs[i]);
        char live[400], one[400];
        snprintf(live, sizeof live, "%s/f_%04d-%s.png", four, last, outputs[i]);
        snprintf(one, sizeof one, "%s/one/r-%s.png", dir, outputs[i]);
        tess_error err = {{0}};
        int wa, ha, wb, hb;
        uint8_t *a = NULL, *b = NULL;
        cr_assert(dump_read_rgb8(live, &wa, &ha, &a, &err) && dump_read_rgb8(one, &wb, &hb, &b, &err), "%s", err.msg);
        cr_assert(wa == wb && ha == hb && memcmp(a, b, (size_t)wa * (size_t)ha * 3) == 0,
                  "%s: the live frame %d differs from the one-process replay", outputs[i], last);
        free(a);
        free(b);
    }
    support_remove_tmp_dir(dir);
}

/* A process killed outright (SIGKILL, a machine gone): the job ends, never hangs, with a
 * failing status. */
Test(cluster, a_killed_process_ends_the_job, .timeout = 900)
{
    need_mpirun();
    char dir[256], log[16384];
    support_make_tmp_dir(dir, sizeof dir, "cluster-kill");
    support_write_file(dir, "wall.json", wall_text);
    double took;
    int status = signal_a_running_wall(dir, "run", 3, SIGKILL, &took, log, sizeof log);
    cr_assert(WIFEXITED(status) && WEXITSTATUS(status) != 0, "the job ended with status %d: %s", status, log);
    cr_log_info("cluster: the job ended %.2f s after a process was killed", took);
    support_remove_tmp_dir(dir);
}

/* Frames first..last of output `connector` in dir `a` equal those of dir `b` (NAME f_NNNN-...). */
static void same_frames(const char *a, const char *b, const char *connector, int first, int last)
{
    for (int f = first; f <= last; f++) {
        char pa[400], pb[400];
        snprintf(pa, sizeof pa, "%s/f_%04d-%s.png", a, f, connector);
        snprintf(pb, sizeof pb, "%s/f_%04d-%s.png", b, f, connector);
        tess_error err = {{0}};
        int wa, ha, wb, hb;
        uint8_t *ia = NULL, *ib = NULL;
        cr_assert(dump_read_rgb8(pa, &wa, &ha, &ia, &err) && dump_read_rgb8(pb, &wb, &hb, &ib, &err), "%s",
                  err.msg);
        cr_assert(wa == wb && ha == hb && memcmp(ia, ib, (size_t)wa * (size_t)ha * 3) == 0,
                  "%s frame %d differs from the one-process wall's", connector, f);
        free(ia);
        free(ib);
    }
}

/* Start a carry-on run of `frames` frames on the 4-output wall in dir (mpirun --enable-recovery,
 * sync time-out 5 s, the frames written to out) and wait until every output has frame 3; the job. */
static pid_t start_carry_on(const char *dir, const char *out, int frames, double end)
{
    char cmd[4096], args[1024], path[400];
    snprintf(args, sizeof args,
             "run --wall %s/wall.json --display dump --out %s/f_####.png --frames %d --threads 1 --time fixed --rate 30 "
             "--sync-timeout 5 --on-node-loss carry-on",
             dir, out, frames);
    job_command(cmd, sizeof cmd, dir, "--enable-recovery", args);
    pid_t job = start_job(cmd);
    for (int i = 1; i <= 4; i++) {
        snprintf(path, sizeof path, "%s/f_0003-Virtual-%d.png", out, i);
        cr_assert(wait_file(path, end), "the wall never ran (%s)", path);
    }
    return job;
}

/* --on-node-loss carry-on (under mpirun --enable-recovery): a process killed mid-run (SIGKILL,
 * a machine gone) is given up on by the leader after the time-out; the others go on in step to
 * the last frame and exit 0. Their outputs' every frame is the one-process wall's (the orbit at
 * a fixed rate), apart from the status line, which from the loss on says so on the bottom-left
 * output; the killed process's output stops. */
Test(cluster, with_carry_on_the_others_go_on_in_step_when_a_process_dies, .timeout = 900)
{
    need_mpirun();
    char dir[256], cmd[4096], log[32768], path[512], four[300], one[300];
    support_make_tmp_dir(dir, sizeof dir, "cluster-carry-on");
    support_write_file(dir, "wall.json", wall_text);
    snprintf(cmd, sizeof cmd, "mkdir -p %s/four %s/one", dir, dir);
    cr_assert_eq(support_run(cmd), 0);
    snprintf(four, sizeof four, "%s/four", dir);
    snprintf(one, sizeof one, "%s/one", dir);
    const int frames = 40;
    double end = now_s() + RUN_TIMEOUT_S;
    pid_t job = start_carry_on(dir, four, frames, end);
    int pid = rank_pid(dir, 3);
    cr_assert_gt(pid, 0);
    cr_assert_eq(kill(pid, SIGKILL), 0);
    int status = wait_job(job, end);
    snprintf(path, sizeof path, "%s/run.log", dir);
    support_read_text(path, log, sizeof log);
    cr_assert(WIFEXITED(status) && WEXITSTATUS(status) == 0, "the job ended with status %d: %s", status, log);
    cr_assert(strstr(log, "cluster: rank 0 lost rank 3 (") && strstr(log, "the wall carries on without its outputs"),
              "%s", log);
    for (int r = 0; r < 3; r++) {
        char line[96];
        snprintf(line, sizeof line, "cluster: rank %d of 4", r);
        const char *stats = strstr(log, line);
        cr_assert(stats, "no counts from rank %d: %s", r, log);
        cr_assert(strstr(stats, "carried on without a lost machine"), "rank %d: %s", r, log);
    }
    int killed_at = last_frame_of(four, "Virtual-4");
    cr_assert_lt(killed_at, frames - 1, "the killed process's output went on to frame %d: %s", killed_at, log);
    for (int i = 1; i <= 3; i++) {
        char connector[24];
        snprintf(connector, sizeof connector, "Virtual-%d", i);
        cr_assert_eq(last_frame_of(four, connector), frames - 1, "%s stopped early: %s", connector, log);
    }
    snprintf(cmd, sizeof cmd,
             "%s run --wall %s/wall.json --display dump --out %s/f_####.png --frames %d --threads 2 --time fixed "
             "--rate 30",
             support_tessera_bin(), dir, one, frames);
    cr_assert_eq(run_logged(dir, "one", cmd, log, sizeof log), 0, "%s", log);
    same_frames(four, one, "Virtual-1", 0, frames - 1);
    same_frames(four, one, "Virtual-2", 0, frames - 1);
    /* before the loss was noticed; the killed process's last file may be cut short by the kill */
    same_frames(four, one, "Virtual-3", 0, killed_at - 1);
    same_frames(four, one, "Virtual-4", 0, killed_at - 1);
    /* the last frame of the bottom-left output carries the message: it differs in its bottom rows only */
    snprintf(path, sizeof path, "%s/f_%04d-Virtual-3.png", four, frames - 1);
    char ref[400];
    snprintf(ref, sizeof ref, "%s/f_%04d-Virtual-3.png", one, frames - 1);
    tess_error err = {{0}};
    int w, h, w1, h1;
    uint8_t *a = NULL, *b = NULL;
    cr_assert(dump_read_rgb8(path, &w, &h, &a, &err) && dump_read_rgb8(ref, &w1, &h1, &b, &err), "%s", err.msg);
    cr_assert(w == w1 && h == h1);
    int first_row = h;
    for (int y = 0; y < h && first_row == h; y++)
        if (memcmp(a + (size_t)y * (size_t)w * 3, b + (size_t)y * (size_t)w * 3, (size_t)w * 3) != 0)
            first_row = y;
    cr_assert_lt(first_row, h, "no status line on the bottom-left output after the loss");
    cr_assert_gt(first_row, h / 2, "the last frame differs above its status line (row %d of %d)", first_row, h);
    free(a);
    free(b);
    support_remove_tmp_dir(dir);
}

/* With carry-on, a follower that stops answering (SIGSTOP) is given up on and the others go
 * on; when it comes back (SIGCONT) it finds it was dropped and stops with the reason rather
 * than show a picture out of step; the others reach their last frame. */
Test(cluster, with_carry_on_a_process_that_comes_back_late_is_told_and_stops, .timeout = 900)
{
    need_mpirun();
    char dir[256], log[32768] = "", path[400];
    support_make_tmp_dir(dir, sizeof dir, "cluster-late");
    support_write_file(dir, "wall.json", wall_text);
    double end = now_s() + RUN_TIMEOUT_S;
    const int frames = 60;
    pid_t job = start_carry_on(dir, dir, frames, end);
    int pid = rank_pid(dir, 1);
    cr_assert_gt(pid, 0);
    cr_assert_eq(kill(pid, SIGSTOP), 0);
    snprintf(path, sizeof path, "%s/run.log", dir);
    while (!strstr(log, "cluster: rank 0 lost rank 1 (") && now_s() < end) { /* an event: the leader's verdict */
        nanosleep(&(struct timespec){0, 20000000}, NULL);
        support_read_text(path, log, sizeof log);
    }
    cr_assert(strstr(log, "cluster: rank 0 lost rank 1 ("), "%s", log);
    cr_assert_eq(kill(pid, SIGCONT), 0);
    int status = wait_job(job, end);
    support_read_text(path, log, sizeof log);
    cr_assert(WIFEXITED(status), "the job ended with status %d: %s", status, log);
    cr_assert(strstr(log, "cluster: rank 1: the leader gave up waiting for this process at frame"), "%s", log);
    const char *one = strstr(log, "cluster: rank 1 of 4");
    cr_assert(one && strstr(one, "FAILED"), "%s", log);
    cr_assert_lt(last_frame_of(dir, "Virtual-2"), frames - 1, "the dropped process went on: %s", log);
    for (int i = 1; i <= 4; i++) {
        char connector[24];
        snprintf(connector, sizeof connector, "Virtual-%d", i);
        if (i != 2)
            cr_assert_eq(last_frame_of(dir, connector), frames - 1, "%s stopped early: %s", connector, log);
    }
    support_remove_tmp_dir(dir);
}

/* With carry-on, the leader killed: the followers wait twice the time-out for it, then each
 * goes on alone to its last frame (no more input), saying so on the wall. */
Test(cluster, with_carry_on_the_others_go_on_alone_when_the_leader_dies, .timeout = 900)
{
    need_mpirun();
    char dir[256], log[32768], path[400];
    support_make_tmp_dir(dir, sizeof dir, "cluster-leader");
    support_write_file(dir, "wall.json", wall_text);
    double end = now_s() + RUN_TIMEOUT_S;
    const int frames = 40;
    pid_t job = start_carry_on(dir, dir, frames, end);
    int pid = rank_pid(dir, 0);
    cr_assert_gt(pid, 0);
    cr_assert_eq(kill(pid, SIGKILL), 0);
    int status = wait_job(job, end);
    snprintf(path, sizeof path, "%s/run.log", dir);
    support_read_text(path, log, sizeof log);
    cr_assert(WIFEXITED(status) && WEXITSTATUS(status) == 0, "the job ended with status %d: %s", status, log);
    cr_assert_lt(last_frame_of(dir, "Virtual-1"), frames - 1, "the killed leader's output went on: %s", log);
    for (int r = 1; r < 4; r++) {
        char line[96], connector[24];
        snprintf(line, sizeof line, "cluster: rank %d lost rank 0 (", r);
        cr_assert(strstr(log, line) && strstr(log, "time-out 10.0 s): the leader is gone"), "rank %d: %s", r, log);
        snprintf(line, sizeof line, "cluster: rank %d of 4", r);
        const char *stats = strstr(log, line);
        cr_assert(stats && strstr(stats, "carried on alone (the leader was lost)"), "rank %d: %s", r, log);
        snprintf(connector, sizeof connector, "Virtual-%d", r + 1);
        cr_assert_eq(last_frame_of(dir, connector), frames - 1, "%s stopped early: %s", connector, log);
    }
    support_remove_tmp_dir(dir);
}

/* With a frame budget (--budget-ms) the governor picks each frame's scale for the whole wall:
 * the leader's governor plans for the slowest process (the followers send their step costs
 * with their votes) and every process renders its plan. Every frame's plan, as each process
 * logged it, is the same on all four, and the budget (far below a full-size frame here) made
 * the governor reduce the scale. */
Test(cluster, with_a_frame_budget_every_process_renders_the_leaders_plan, .timeout = 900)
{
    need_mpirun();
    char dir[256], cmd[4096];
    support_make_tmp_dir(dir, sizeof dir, "cluster-budget");
    char big[4096];
    snprintf(big, sizeof big, "%s", wall_text);
    for (char *m; (m = strstr(big, "96x54"));) /* four 480x270 outputs: frames that cost something */
        memmove(m + 7, m + 5, strlen(m + 5) + 1), memcpy(m, "480x270", 7);
    support_write_file(dir, "wall.json", big);
    const int frames = 30;
    snprintf(cmd, sizeof cmd,
             "TESSERA_LOG=debug " MPIRUN " -np 4 --bind-to none %s run --wall %s/wall.json --display null --frames %d "
             "--threads 1 --budget-ms 1",
             support_tessera_bin(), dir, frames);
    char *log = malloc(1 << 22);
    cr_assert(log);
    int status = run_logged(dir, "budget", cmd, log, 1 << 22);
    cr_assert_eq(status, 0, "status %d", status);
    /* plans[rank][frame]: "kind K rung R stratum S" */
    static char plans[4][64][48];
    memset(plans, 0, sizeof plans);
    int reduced = 0;
    for (const char *l = strstr(log, "cluster: rank "); l; l = strstr(l + 1, "cluster: rank ")) {
        int rank, frame, kind, rung, stratum;
        if (sscanf(l, "cluster: rank %d frame %d: plan kind %d rung %d stratum %d", &rank, &frame, &kind, &rung,
                   &stratum) != 5)
            continue;
        cr_assert(rank >= 0 && rank < 4 && frame >= 0 && frame < 64);
        snprintf(plans[rank][frame], sizeof plans[rank][frame], "kind %d rung %d stratum %d", kind, rung, stratum);
        reduced += rank == 0 && rung > 0;
    }
    for (int f = 0; f < frames; f++) {
        cr_assert(plans[0][f][0], "the leader logged no plan for frame %d", f);
        for (int r = 1; r < 4; r++)
            cr_assert_str_eq(plans[r][f], plans[0][f], "frame %d: rank %d rendered another plan", f, r);
    }
    cr_assert_gt(reduced, frames / 2, "the governor reduced %d of %d frames under a 1 ms budget", reduced, frames);
    free(log);
    support_remove_tmp_dir(dir);
}
