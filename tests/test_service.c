/* test_service.c - the kiosk under systemd (wall/service.h,
 * configs/systemd/): READY=1, WATCHDOG=1, STATUS= and STOPPING=1 from
 * `tessera run` on a fake NOTIFY_SOCKET (a unix datagram socket bound in a
 * temp dir, as systemd's is); a frame loop stuck in its display stage stops
 * the pings, a healthy pause (the wall switched away from its VT) feeds
 * them; a freshly started kiosk comes up playing its attract tour (what a
 * restart comes back to); the unit file passes `systemd-analyze verify`.
 *
 * Every wait is for an event (a message on the socket, a line in the log)
 * with a generous deadline; the only fixed wait is the silence of a stuck
 * loop, which is what systemd acts on: no ping for a whole watchdog interval
 * (checked over SILENT_INTERVALS of them). */
#define _XOPEN_SOURCE 700 /* realpath */
#include <criterion/criterion.h>
#include <errno.h>
#include <limits.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/base/clock.h"
#include "engine/frame/pipeline.h"
#include "engine/scene/scene.h"
#include "support.h"
#include "wall/service.h"

#define EVENT_DEADLINE_S 60.0 /* generous: any event we wait for comes far sooner on a working build */
#define SILENT_INTERVALS 3    /* a stuck loop: no WATCHDOG=1 over this many watchdog intervals */
#define LOG_BYTES 65536

/* ---- the fake service manager: a datagram socket and what arrived on it ---- */

typedef struct listener {
    int fd;
    char path[256];
    char log[LOG_BYTES]; /* every message, for failure output */
    size_t log_len;
} listener;

static void listener_open(listener *l, const char *dir)
{
    memset(l, 0, sizeof *l);
    snprintf(l->path, sizeof l->path, "%s/notify", dir);
    l->fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    cr_assert(l->fd >= 0, "socket: %s", strerror(errno));
    struct sockaddr_un addr = {.sun_family = AF_UNIX};
    cr_assert(strlen(l->path) < sizeof addr.sun_path, "socket path too long: %s", l->path);
    memcpy(addr.sun_path, l->path, strlen(l->path) + 1);
    cr_assert(bind(l->fd, (struct sockaddr *)&addr, sizeof addr) == 0, "bind %s: %s", l->path, strerror(errno));
}

static void listener_close(listener *l) { close(l->fd); }

/* The next message within timeout_s into msg (NUL-terminated); false on time-out. */
static bool listener_next(listener *l, double timeout_s, char *msg, size_t msg_bytes)
{
    struct pollfd pfd = {l->fd, POLLIN, 0};
    int ms = timeout_s <= 0.0 ? 0 : (int)(timeout_s * 1e3) + 1;
    if (poll(&pfd, 1, ms) <= 0)
        return false;
    ssize_t n = recv(l->fd, msg, msg_bytes - 1, 0);
    cr_assert(n >= 0, "recv: %s", strerror(errno));
    msg[n] = '\0';
    int w = snprintf(l->log + l->log_len, sizeof l->log - l->log_len, "[%s] ", msg);
    if (w > 0 && l->log_len + (size_t)w < sizeof l->log)
        l->log_len += (size_t)w;
    return true;
}

/* Whether one of the message's newline-separated assignments is `line`
 * exactly ("WATCHDOG=1"), or starts with it when it ends in '=' ("STATUS="). */
static bool has_line(const char *msg, const char *line)
{
    size_t len = strlen(line);
    bool prefix = len > 0 && line[len - 1] == '=';
    for (const char *p = msg; *p;) {
        const char *end = strchr(p, '\n');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        if (prefix ? n >= len && !strncmp(p, line, len) : n == len && !strncmp(p, line, len))
            return true;
        p = end ? end + 1 : p + n;
    }
    return false;
}

/* Wait for a message with `line` (and `also` somewhere in it, if not NULL);
 * counts the WATCHDOG=1 seen meanwhile into *pings (may be NULL). */
static bool listener_wait(listener *l, const char *line, const char *also, int *pings, char *msg, size_t msg_bytes)
{
    double deadline = clock_monotonic_s() + EVENT_DEADLINE_S;
    char buf[1024];
    for (double now; (now = clock_monotonic_s()) < deadline;) {
        if (!listener_next(l, deadline - now, buf, sizeof buf))
            break;
        if (pings && has_line(buf, "WATCHDOG=1"))
            ++*pings;
        if (has_line(buf, line) && (!also || strstr(buf, also))) {
            if (msg)
                snprintf(msg, msg_bytes, "%s", buf);
            return true;
        }
    }
    return false;
}

/* ---- the binary as systemd starts it ---- */

/* Start `tessera ARGS` (split on spaces) with NOTIFY_SOCKET and, when
 * watchdog_usec > 0, WATCHDOG_USEC set; stdout and stderr to log_path. */
static pid_t spawn_tessera(const char *socket_path, long watchdog_usec, const char *log_path, const char *args)
{
    char copy[1024];
    snprintf(copy, sizeof copy, "%s", args);
    char *argv[64];
    int argc = 0;
    argv[argc++] = (char *)support_tessera_bin();
    for (char *save = NULL, *t = strtok_r(copy, " ", &save); t && argc < 63; t = strtok_r(NULL, " ", &save))
        argv[argc++] = t;
    argv[argc] = NULL;
    fflush(NULL);
    pid_t pid = fork();
    cr_assert(pid >= 0, "fork: %s", strerror(errno));
    if (pid == 0) {
        FILE *f = freopen(log_path, "w", stdout);
        if (!f || dup2(fileno(stdout), 2) < 0)
            _exit(126);
        setenv("NOTIFY_SOCKET", socket_path, 1);
        unsetenv("WATCHDOG_PID");
        if (watchdog_usec > 0) {
            char v[32];
            snprintf(v, sizeof v, "%ld", watchdog_usec);
            setenv("WATCHDOG_USEC", v, 1);
        } else {
            unsetenv("WATCHDOG_USEC");
        }
        execv(argv[0], argv);
        _exit(127);
    }
    return pid;
}

/* Exit status of pid within the deadline (128 + signal; -1: still running, then killed). */
static int reap(pid_t pid)
{
    double deadline = clock_monotonic_s() + EVENT_DEADLINE_S;
    int status;
    while (clock_monotonic_s() < deadline) {
        pid_t r = waitpid(pid, &status, WNOHANG);
        if (r == pid)
            return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
        poll(NULL, 0, 20);
    }
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return -1;
}

/* Wait until `needle` is in the file (a log being written); false at the deadline. */
static bool file_wait(const char *path, const char *needle, char *text, size_t text_bytes)
{
    double deadline = clock_monotonic_s() + EVENT_DEADLINE_S;
    do {
        support_read_text(path, text, text_bytes);
        if (strstr(text, needle))
            return true;
        poll(NULL, 0, 20);
    } while (clock_monotonic_s() < deadline);
    return false;
}

Test(service, run_tells_systemd_ready_watchdog_status_and_stopping, .timeout = 240)
{
    char dir[256], log_path[512], msg[1024], text[LOG_BYTES];
    support_make_tmp_dir(dir, sizeof dir, "service");
    listener l;
    listener_open(&l, dir);
    snprintf(log_path, sizeof log_path, "%s/tessera.log", dir);
    const long watchdog_usec = 400000; /* pings at most every 0.1 s */
    double start = clock_monotonic_s();
    pid_t pid = spawn_tessera(l.path, watchdog_usec, log_path,
                              "run --size 48x27 --threads 2 --display null --time real --frames 100000000");
    int pings = 0;
    bool ready = listener_wait(&l, "READY=1", NULL, &pings, msg, sizeof msg);
    support_read_text(log_path, text, sizeof text);
    cr_assert(ready, "no READY=1; messages: %s; log: %s", l.log, text);
    cr_expect(has_line(msg, "STATUS=") && strstr(msg, "running: 1 of 1 output up"),
              "READY=1 came without the status: '%s'", msg);
    /* pings from the frame loop, and a status with the frame rate */
    int before = pings;
    cr_expect(listener_wait(&l, "WATCHDOG=1", NULL, NULL, NULL, 0) &&
                  listener_wait(&l, "WATCHDOG=1", NULL, NULL, NULL, 0),
              "no WATCHDOG=1 after READY=1: %s", l.log);
    pings = before + 2;
    cr_expect(listener_wait(&l, "STATUS=", "frames/s, 1 of 1 output up", &pings, msg, sizeof msg),
              "no STATUS= with the frame rate: %s", l.log);
    double elapsed = clock_monotonic_s() - start;
    /* rate-limited: at most one ping per quarter interval (+2 for the edges), however fast frames come */
    double max_pings = elapsed / (1e-6 * (double)watchdog_usec / SERVICE_PINGS_PER_INTERVAL) + 2.0;
    cr_expect(pings <= max_pings, "%d pings in %.2f s: not rate-limited to WATCHDOG_USEC / %d", pings, elapsed,
              SERVICE_PINGS_PER_INTERVAL);
    kill(pid, SIGTERM);
    cr_expect(listener_wait(&l, "STOPPING=1", NULL, NULL, msg, sizeof msg), "no STOPPING=1 after SIGTERM: %s", l.log);
    int code = reap(pid);
    support_read_text(log_path, text, sizeof text);
    cr_expect_eq(code, 0, "exit %d after SIGTERM; log: %s", code, text);
    cr_expect(strstr(text, "service: watchdog every 0.4 s"), "the log does not say the watchdog is on: %s", text);
    listener_close(&l);
    support_remove_tmp_dir(dir);
}

/* NOTIFY_SOCKET without WATCHDOG_USEC (Type=notify, no WatchdogSec=): READY
 * and STATUS, never a ping. */
Test(service, without_a_watchdog_no_pings, .timeout = 240)
{
    char dir[256], log_path[512], msg[1024], text[LOG_BYTES];
    support_make_tmp_dir(dir, sizeof dir, "service");
    listener l;
    listener_open(&l, dir);
    snprintf(log_path, sizeof log_path, "%s/tessera.log", dir);
    pid_t pid = spawn_tessera(l.path, 0, log_path,
                              "run --size 48x27 --threads 2 --display null --time real --frames 100000000");
    int pings = 0;
    cr_expect(listener_wait(&l, "READY=1", NULL, &pings, NULL, 0), "no READY=1: %s", l.log);
    cr_expect(listener_wait(&l, "STATUS=", "frames/s", &pings, msg, sizeof msg), "no STATUS=: %s", l.log);
    kill(pid, SIGTERM);
    cr_expect(listener_wait(&l, "STOPPING=1", NULL, &pings, NULL, 0), "no STOPPING=1: %s", l.log);
    cr_expect_eq(reap(pid), 0);
    cr_expect_eq(pings, 0, "WATCHDOG=1 sent without WATCHDOG_USEC: %s", l.log);
    support_read_text(log_path, text, sizeof text);
    cr_expect(strstr(text, "no watchdog asked for"), "%s", text);
    listener_close(&l);
    support_remove_tmp_dir(dir);
}

/* Not started by systemd: no notifier at all (nothing attached, nothing sent). */
Test(service, without_notify_socket_there_is_no_notifier)
{
    unsetenv("NOTIFY_SOCKET");
    cr_expect_null(service_notifier_create());
    cr_expect(service_notifier_attach(NULL, NULL, -1));
    service_notifier_paused(NULL, "nothing");
    cr_expect_eq(service_notifier_watchdog_s(NULL), 0.0);
    setenv("NOTIFY_SOCKET", "", 1);
    cr_expect_null(service_notifier_create(), "an empty NOTIFY_SOCKET is no socket");
}

Test(service, watchdog_due_every_quarter_interval)
{
    cr_expect(service_watchdog_due(5.0, -1.0, 20.0), "never pinged: due");
    cr_expect(!service_watchdog_due(5.0, 0.1, 20.0));
    cr_expect(service_watchdog_due(5.1, 0.1, 20.0));
    cr_expect(!service_watchdog_due(100.0, 99.0, 20.0));
}

/* A restart comes back to the attract tour: a freshly started kiosk (input on,
 * nobody there) queues its tour at once, and tells systemd it is up. */
Test(service, a_fresh_kiosk_comes_up_playing_its_tour, .timeout = 240)
{
    char dir[256], log_path[512], text[LOG_BYTES];
    support_make_tmp_dir(dir, sizeof dir, "service");
    listener l;
    listener_open(&l, dir);
    snprintf(log_path, sizeof log_path, "%s/tessera.log", dir);
    pid_t pid = spawn_tessera(l.path, 2000000, log_path,
                              "run --input on --size 48x27 --threads 2 --display null --time real --frames 100000000");
    cr_expect(listener_wait(&l, "READY=1", NULL, NULL, NULL, 0), "no READY=1: %s", l.log);
    cr_expect(file_wait(log_path, "input: the attract tour starts", text, sizeof text),
              "a fresh kiosk did not start its tour: %s", text);
    kill(pid, SIGTERM);
    int code = reap(pid);
    support_read_text(log_path, text, sizeof text);
    cr_expect_eq(code, 0, "exit %d; log: %s", code, text);
    listener_close(&l);
    support_remove_tmp_dir(dir);
}

/* ---- in process: a display that blocks (a stuck frame loop), then the same
 * stall declared a healthy pause, as the DRM wall does while switched away ---- */

typedef enum { STALL_NONE, STALL_SILENT, STALL_PAUSED, STALL_RELEASED } stall_mode;

typedef struct stall_display {
    image_display base;
    pthread_mutex_t lock;
    pthread_cond_t changed;
    uint64_t stall_frame;   /* show() of this frame blocks */
    stall_mode mode;        /* lock */
    bool blocked;           /* show() is blocked (lock) */
    service_notifier *sn;   /* told while paused */
    double pause_every_s;
} stall_display;

static bool stall_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)err;
    stall_display *s = (stall_display *)d;
    if (img->frame != s->stall_frame)
        return true;
    pthread_mutex_lock(&s->lock);
    s->blocked = true;
    pthread_cond_broadcast(&s->changed);
    while (s->mode != STALL_RELEASED) {
        if (s->mode == STALL_PAUSED) {
            pthread_mutex_unlock(&s->lock);
            service_notifier_paused(s->sn, "test pause");
            pthread_mutex_lock(&s->lock);
        }
        struct timespec until;
        clock_gettime(CLOCK_REALTIME, &until);
        long ns = until.tv_nsec + (long)(s->pause_every_s * 1e9);
        until.tv_sec += ns / 1000000000L;
        until.tv_nsec = ns % 1000000000L;
        pthread_cond_timedwait(&s->changed, &s->lock, &until);
    }
    service_notifier_paused(s->sn, NULL);
    s->blocked = false;
    pthread_mutex_unlock(&s->lock);
    return true;
}

static void stall_destroy(image_display *d)
{
    stall_display *s = (stall_display *)d;
    pthread_mutex_destroy(&s->lock);
    pthread_cond_destroy(&s->changed);
    free(s);
}

static const image_display_ops stall_ops = {.name = "stall", .show = stall_show, .destroy = stall_destroy};

static void stall_set(stall_display *s, stall_mode mode)
{
    pthread_mutex_lock(&s->lock);
    s->mode = mode;
    pthread_cond_broadcast(&s->changed);
    pthread_mutex_unlock(&s->lock);
}

static void *run_pipeline(void *arg)
{
    tess_error err = {{0}};
    bool ok = pipeline_run(arg, &err);
    if (!ok)
        fprintf(stderr, "pipeline_run: %s\n", err.msg);
    return (void *)(intptr_t)ok;
}

Test(service, a_stuck_frame_loop_stops_the_pings_and_a_pause_feeds_them, .timeout = 240)
{
    char dir[256], msg[1024];
    support_make_tmp_dir(dir, sizeof dir, "service");
    listener l;
    listener_open(&l, dir);
    const double interval_s = 0.2;
    setenv("NOTIFY_SOCKET", l.path, 1);
    setenv("WATCHDOG_USEC", "200000", 1);
    unsetenv("WATCHDOG_PID");
    service_notifier *sn = service_notifier_create();
    cr_assert(sn);
    cr_assert_float_eq(service_notifier_watchdog_s(sn), interval_s, 1e-9);

    tess_error err = {{0}};
    scene *sc = scene_create_default(&err);
    cr_assert(sc, "%s", err.msg);
    accel *ac = accel_build(sc, 2, &err);
    cr_assert(ac, "%s", err.msg);
    pipeline_config cfg = pipeline_config_default(sc, ac);
    cfg.threads = 2;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p, "%s", err.msg);
    stall_display *s = calloc(1, sizeof *s);
    cr_assert(s);
    s->base.ops = &stall_ops;
    pthread_mutex_init(&s->lock, NULL);
    pthread_cond_init(&s->changed, NULL);
    s->stall_frame = 8;
    s->mode = STALL_SILENT;
    s->sn = sn;
    s->pause_every_s = interval_s / 8;
    camera_desc cam = sc->camera;
    if (!sc->has_camera) {
        vec3 lo, hi;
        scene_bounds(sc, &lo, &hi);
        cam = camera_frame_bounds(lo, hi, CAMERA_DEFAULT_VIEW_DIR, CAMERA_DEFAULT_FOV_DEG, 48, 27);
    }
    cr_assert(pipeline_add_channel(p, &cam, 48, 27, &s->base, &err) == 0, "%s", err.msg);
    cr_assert(service_notifier_attach(sn, p, -1));
    pthread_t runner;
    cr_assert(pthread_create(&runner, NULL, run_pipeline, p) == 0);

    cr_assert(listener_wait(&l, "READY=1", NULL, NULL, NULL, 0), "no READY=1: %s", l.log);
    /* the display stage blocks: the loop is stuck */
    pthread_mutex_lock(&s->lock);
    while (!s->blocked)
        pthread_cond_wait(&s->changed, &s->lock);
    pthread_mutex_unlock(&s->lock);
    /* drain what is queued; the sender thread may still be sending the one ping the last
     * serial section posted before the display stage blocked, so one late ping is allowed:
     * a loop that kept pinging while stuck would send SERVICE_PINGS_PER_INTERVAL per interval */
    while (listener_next(&l, 0.0, msg, sizeof msg))
        ;
    double silent_until = clock_monotonic_s() + SILENT_INTERVALS * interval_s;
    int stuck_pings = 0;
    for (double now; (now = clock_monotonic_s()) < silent_until;)
        if (listener_next(&l, silent_until - now, msg, sizeof msg) && has_line(msg, "WATCHDOG=1"))
            stuck_pings++;
    cr_expect_leq(stuck_pings, 1, "%d WATCHDOG=1 over %d intervals while the frame loop was stuck: %s", stuck_pings,
                  SILENT_INTERVALS, l.log);

    /* the same wait as a healthy pause: pings again, and the status says so */
    stall_set(s, STALL_PAUSED);
    int pings = 0;
    cr_expect(listener_wait(&l, "STATUS=", "paused: test pause", &pings, NULL, 0), "no paused status: %s", l.log);
    cr_expect(listener_wait(&l, "WATCHDOG=1", NULL, NULL, NULL, 0) && listener_wait(&l, "WATCHDOG=1", NULL, NULL, NULL, 0) &&
                  listener_wait(&l, "WATCHDOG=1", NULL, NULL, NULL, 0),
              "a pause does not feed the watchdog: %s", l.log);
    /* going on: running again */
    stall_set(s, STALL_RELEASED);
    cr_expect(listener_wait(&l, "STATUS=", "running:", NULL, NULL, 0), "no running status after the pause: %s", l.log);
    cr_expect(listener_wait(&l, "WATCHDOG=1", NULL, NULL, NULL, 0), "no pings after the pause: %s", l.log);
    pipeline_stop(p);
    void *ok;
    pthread_join(runner, &ok);
    cr_expect(ok != NULL);
    cr_expect(listener_wait(&l, "STOPPING=1", NULL, NULL, NULL, 0), "no STOPPING=1: %s", l.log);
    pipeline_destroy(p);
    service_notifier_destroy(sn);
    accel_destroy(ac);
    scene_destroy(sc);
    listener_close(&l);
    support_remove_tmp_dir(dir);
}

/* ---- the unit file ---- */

/* configs/systemd/tessera-kiosk.service through `systemd-analyze verify`
 * (unknown keys, bad values, a missing binary; it works as root without
 * systemd as PID 1). Its ExecStart points at /usr/local/bin/tessera, so the
 * copy checked points at this build's binary instead. SKIPPED, said so, when
 * systemd-analyze is not there (tools/deps.sh installs it). */
Test(service, the_unit_file_passes_systemd_analyze_verify, .timeout = 120)
{
    if (support_run("command -v systemd-analyze > /dev/null 2>&1") != 0) {
        fprintf(stderr, "SKIPPED: service::the_unit_file_passes_systemd_analyze_verify: systemd-analyze is not "
                        "installed (tools/deps.sh installs the systemd package)\n");
        cr_skip_test("systemd-analyze is not installed");
    }
    char dir[256], bin[PATH_MAX], cmd[PATH_MAX + 1024], out_path[512], out[8192], unit[16384];
    support_make_tmp_dir(dir, sizeof dir, "service");
    cr_assert(realpath(support_tessera_bin(), bin), "%s: %s", support_tessera_bin(), strerror(errno));
    support_read_text("../configs/systemd/tessera-kiosk.service", unit, sizeof unit);
    cr_assert(unit[0], "cannot read ../configs/systemd/tessera-kiosk.service");
    /* what the kiosk relies on is there */
    static const char *const needed[] = {"Type=notify", "WatchdogSec=", "Restart=on-failure", "User=tessera",
                                         "--display drm", "--wall ${TESSERA_WALL}", NULL};
    for (const char *const *n = needed; *n; n++)
        cr_expect(strstr(unit, *n), "the unit lacks '%s'", *n);
    snprintf(cmd, sizeof cmd, "sed 's#/usr/local/bin/tessera#%s#g' ../configs/systemd/tessera-kiosk.service > '%s/tessera-kiosk.service'",
             bin, dir);
    cr_assert_eq(support_run(cmd), 0, "%s", cmd);
    snprintf(out_path, sizeof out_path, "%s/verify.out", dir);
    snprintf(cmd, sizeof cmd, "cd '%s' && SYSTEMD_LOG_COLOR=0 systemd-analyze verify ./tessera-kiosk.service > '%s' 2>&1",
             dir, out_path);
    int code = support_run(cmd);
    support_read_text(out_path, out, sizeof out);
    if (code != 0 && (strstr(out, "Failed to initialize manager") || strstr(out, "Operation not permitted"))) {
        fprintf(stderr, "SKIPPED: service::the_unit_file_passes_systemd_analyze_verify: systemd-analyze cannot run "
                        "here: %s\n", out);
        support_remove_tmp_dir(dir);
        cr_skip_test("systemd-analyze cannot run here");
    }
    /* an unknown key is only a warning (exit 0): any message at all fails */
    cr_expect(code == 0 && out[0] == '\0', "systemd-analyze verify: exit %d: %s", code, out);
    support_remove_tmp_dir(dir);
}
