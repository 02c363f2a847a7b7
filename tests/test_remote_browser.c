/* test_remote_browser.c - the remote view (remote/, docs/remote-protocol.md)
 * end to end: the kiosk (../tessera run --remote 0) serves its page to
 * headless Chromium driven over the DevTools protocol (cdp.h) and to a raw
 * WebSocket client. The page connects with the token and shows frames; a
 * wrong token is refused (page and socket); a drag on the page orbits the
 * camera and the wall's last frame equals the native replay of what was
 * recorded; two pages see each other's pointers in the viewer's colour; a
 * client that stops reading leaves the wall running (its frames per second
 * measured and printed, not asserted: tests do not depend on machine speed).
 * Skipped, saying why, where Chromium cannot be started (the raw-client
 * tests still run). Every wait is for an event, with a generous cap. */
#define _DEFAULT_SOURCE
#include <arpa/inet.h>
#include <criterion/criterion.h>
#include <dirent.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cdp.h"
#include "ws_client.h"
#include "support.h"
#include "wall/dump.h"

#define WAIT_S 60.0

typedef struct kiosk {
    pid_t pid;
    char err_path[512];
    char host[64];
    int port;
    char token[80];
    char url[256];
} kiosk;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void pause_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

/* Start `tessera run ARGS... --remote 0` with stderr in dir/kiosk.err and
 * wait for its URL line (the event: the line is written), at most WAIT_S. */
static void kiosk_start(kiosk *k, const char *dir, const char *const *args)
{
    memset(k, 0, sizeof *k);
    snprintf(k->err_path, sizeof k->err_path, "%s/kiosk.err", dir);
    unlink(k->err_path); /* never the URL of a run before */
    const char *argv[48];
    int n = 0;
    argv[n++] = support_tessera_bin();
    argv[n++] = "run";
    for (int i = 0; args[i] && n < 44; i++)
        argv[n++] = args[i];
    argv[n] = NULL;
    k->pid = fork();
    cr_assert(k->pid >= 0);
    if (k->pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL); /* a test that stops early (a failed assertion) takes it along */
        int e = open(k->err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644), o = open("/dev/null", O_WRONLY);
        dup2(e, 2);
        dup2(o, 1);
        execv(argv[0], (char *const *)argv);
        _exit(127);
    }
    double end = now_s() + WAIT_S;
    char text[8192];
    for (;;) {
        support_read_text(k->err_path, text, sizeof text);
        const char *u = strstr(text, "tessera: remote view: http://");
        if (u && strchr(u, '\n')) {
            cr_assert(sscanf(u, "tessera: remote view: http://%63[0-9.]:%d/?token=%79[0-9a-zA-Z_-]", k->host, &k->port,
                             k->token) == 3,
                      "the URL line: %s", u);
            snprintf(k->url, sizeof k->url, "http://%s:%d/?token=%s", k->host, k->port, k->token);
            return;
        }
        int status;
        if (waitpid(k->pid, &status, WNOHANG) == k->pid) {
            k->pid = -1;
            cr_assert_fail("tessera ended before serving the remote view: %s", text);
        }
        cr_assert(now_s() < end, "no URL line in %.0f s: %s", WAIT_S, text);
        pause_ms(10);
    }
}

/* Stop it (SIGTERM: the frame in flight is finished and shown) or wait for
 * its own end; its exit status. */
static int kiosk_stop(kiosk *k, bool terminate)
{
    if (k->pid <= 0)
        return -1;
    if (terminate)
        kill(k->pid, SIGTERM);
    double end = now_s() + WAIT_S;
    int status = 0;
    while (waitpid(k->pid, &status, WNOHANG) == 0) {
        if (now_s() > end) {
            kill(k->pid, SIGKILL);
            waitpid(k->pid, &status, 0);
            k->pid = -1;
            cr_assert_fail("tessera did not end within %.0f s", WAIT_S);
        }
        pause_ms(10);
    }
    k->pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

static cdp_browser *browser_or_skip(void)
{
    char why[512];
    cdp_browser *b = cdp_launch(1000, 700, why, sizeof why);
    if (!b)
        cr_skip_test("headless Chromium is not available: %s", why);
    return b;
}

static cdp_page *open_page(cdp_browser *b, const char *url)
{
    char why[512];
    cdp_page *p = cdp_open_page(b, url, why, sizeof why);
    cr_assert(p, "opening %s: %s", url, why);
    return p;
}

static void wait_js(cdp_page *p, const char *condition)
{
    char why[1024];
    cr_assert(cdp_wait_js(p, condition, WAIT_S, why, sizeof why), "%s", why);
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    cr_assert(f, "%s", path);
    fputs(text, f);
    fclose(f);
}

/* The page connects with the token, shows frames of the hello's size; a
 * wrong token gets neither the page (403) nor a socket. */
Test(remote_browser, the_page_shows_frames_and_a_wrong_token_is_refused, .timeout = 300)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-page");
    char cfg[512];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    write_file(cfg, "{\"remote\": {\"width\": 640, \"height\": 360}}");
    const char *args[] = {"--config", cfg, "--display", "null", "--size", "320x180", "--threads", "2",
                          "--time", "fixed", "--rate", "30", NULL};
    cdp_browser *b = browser_or_skip(); /* before the kiosk: a skip leaves nothing running */
    kiosk k;
    kiosk_start(&k, dir, args);
    cdp_page *p = open_page(b, k.url);
    wait_js(p, "window.tessera.connected && window.tessera.framesShown >= 3");
    cr_assert_eq(cdp_eval_number(p, "document.getElementById('view').width"), 640.0);
    cr_assert_eq(cdp_eval_number(p, "document.getElementById('view').height"), 360.0);
    cr_assert(cdp_eval_bool(p, "/^#[0-9a-f]{6}$/.test(window.tessera.colour) && window.tessera.viewer === 0"));
    cr_assert_gt(cdp_eval_number(p, "window.tessera.bytes"), 3000.0, "JPEG frames arrived");
    /* the page itself, asked for with a wrong token: 403 */
    cr_assert_eq(cdp_eval_number(p, "fetch('/?token=wrong').then(r => r.status)"), 403.0);
    cr_assert_eq(cdp_eval_number(p, "fetch('/?').then(r => r.status)"), 403.0);
    cr_assert_eq(cdp_eval_number(p, "fetch('/other?token=' + new URLSearchParams(location.search).get('token'))"
                                    ".then(r => r.status)"),
                 404.0);
    /* a socket with a wrong token gets no hello and no frame: only a close with its reason */
    cr_assert(cdp_eval_bool(p, "new Promise(done => { const w = new WebSocket('ws://' + location.host + "
                               "'/ws?token=wrong', 'tessera-remote-1'); let got = 0;"
                               " w.onmessage = () => { got++; };"
                               " w.onclose = (e) => done(got === 0 && e.code === 4403 &&"
                               "                         e.reason === 'a wrong or missing token'); })"),
              "a WebSocket with a wrong token got something, or no close code 4403 with its reason");
    cdp_close(b);
    cr_assert_eq(kiosk_stop(&k, true), 0);
    char text[16384];
    support_read_text(k.err_path, text, sizeof text);
    cr_assert(strstr(text, "refused: 1 token"), "the refusal is counted: %s", text);
    support_remove_tmp_dir(dir);
}

/* Hooks run in a page before its own script: every WebSocket it makes is
 * made with window.__token instead of its token when that is set, to
 * window.__host instead of the kiosk when that is set, records
 * the status line at the moment it is made (window.__statusAtConnect), and
 * while window.__hold is true keeps the frames it gets (window.__held) from
 * the page until the test lets them through. */
#define PAGE_HOOKS                                                                                              \
    "window.__held = []; window.__hold = !!window.__hold;"                                                       \
    "window.WebSocket = class extends WebSocket {"                                                               \
    " constructor(url, protocols) {"                                                                             \
    "  const s = document.getElementById('status');"                                                             \
    "  window.__statusAtConnect = document.getElementById('status-line').textContent + (s.hidden ? '|hidden' : '|shown');" \
    "  if (window.__token !== undefined) url = url.replace(/token=[^&]*/, 'token=' + window.__token);"            \
    "  if (window.__host !== undefined) url = url.replace(/\\/\\/[^/]+/, '//' + window.__host);"                  \
    "  super(url, protocols);"                                                                                   \
    " }"                                                                                                         \
    " set onmessage(f) { super.onmessage = (m) => {"                                                             \
    "  if (window.__hold && typeof m.data !== 'string') window.__held.push(() => f(m)); else f(m); }; }"         \
    " get onmessage() { return super.onmessage; }"                                                               \
    "};"

/* The status over the canvas is there for a person: not hidden, laid out, on the screen. */
#define STATUS_VISIBLE                                                                                          \
    "(() => { const s = document.getElementById('status'), r = s.getBoundingClientRect();"                       \
    " return !s.hidden && getComputedStyle(s).display !== 'none' && getComputedStyle(s).visibility !== 'hidden'" \
    " && r.width > 100 && r.height > 20 && r.top >= 0 && r.bottom <= innerHeight; })()"

static void status_text(cdp_page *p, char *out, size_t out_bytes)
{
    json_object *v;
    char why[512];
    cr_assert(cdp_eval(p, "document.getElementById('status-line').textContent", &v, why, sizeof why), "%s", why);
    snprintf(out, out_bytes, "%s", v ? json_object_get_string(v) : "");
    json_object_put(v);
}

/* What the page says before its first frame, when it is refused (too many
 * viewers: it retries and gets in when a place frees; a wrong token: it
 * stops and says so), when nobody answers, that it says nothing once frames
 * show, and that it says the wall stopped when the kiosk stops. */
Test(remote_browser, the_page_says_what_it_waits_for_and_why_it_is_refused, .timeout = 300)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-status");
    char cfg[512], text[256], why[1024];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    write_file(cfg, "{\"remote\": {\"width\": 320, \"height\": 180, \"max_viewers\": 1}}");
    const char *args[] = {"--config", cfg, "--display", "null", "--size", "320x180", "--threads", "1",
                          "--time", "fixed", "--rate", "30", NULL};
    cdp_browser *b = browser_or_skip();
    kiosk k;
    kiosk_start(&k, dir, args);

    /* before the socket opens, and connected with its frames held back */
    cdp_page *a = cdp_open_page_scripted(b, k.url, "window.__hold = true;" PAGE_HOOKS, why, sizeof why);
    cr_assert(a, "%s", why);
    json_object *v;
    cr_assert(cdp_eval(a, "window.__statusAtConnect", &v, why, sizeof why), "%s", why);
    cr_assert_str_eq(v ? json_object_get_string(v) : "", "Connecting to the wall…|shown");
    json_object_put(v);
    wait_js(a, "window.tessera.connected && window.__held.length > 0");
    cr_assert(cdp_eval_bool(a, STATUS_VISIBLE), "the status is not visible while waiting");
    status_text(a, text, sizeof text);
    cr_assert_str_eq(text, "Connected — waiting for the first frame");
    cr_assert(cdp_eval_bool(a, "window.tessera.status === 'waiting' && window.tessera.framesShown === 0"));
    cr_assert(cdp_eval_bool(a, "(() => { const s = document.getElementById('status');"
                               " return s.getAttribute('role') === 'status' && s.getAttribute('aria-live') === 'polite'; })()"),
              "the status is not announced (role=status, aria-live=polite)");
    /* the frames let through: the status goes */
    cr_assert(cdp_eval_bool(a, "window.__hold = false; window.__held.splice(0).forEach(g => g()); true"));
    wait_js(a, "window.tessera.framesShown >= 2 && window.tessera.status === 'shown'");
    cr_assert_not(cdp_eval_bool(a, STATUS_VISIBLE), "the status still covers the picture");

    /* a second viewer over max_viewers 1: refused, with the limit, and it retries */
    cdp_page *full = open_page(b, k.url);
    wait_js(full, "window.tessera.status === 'refused-full' && /^Refused: too many viewers \\(1 max\\) — retrying in"
                  " \\d+ s$/.test(document.getElementById('status-line').textContent)");
    cr_assert(cdp_eval_bool(full, STATUS_VISIBLE));
    cr_assert(cdp_eval_bool(full, "window.tessera.closeCode === 4503 && window.tessera.refused"));
    cr_assert(cdp_eval_bool(full, "document.getElementById('status-retry').getAttribute('aria-hidden') === 'true'"),
              "the countdown would be read out every second");

    /* a page whose socket carries a wrong token (as after a kiosk restarted with a new one) */
    cdp_page *bad = cdp_open_page_scripted(b, k.url, "window.__token = 'wrong';" PAGE_HOOKS, why, sizeof why);
    cr_assert(bad, "%s", why);
    wait_js(bad, "window.tessera.status === 'refused-token'");
    cr_assert(cdp_eval_bool(bad, STATUS_VISIBLE));
    status_text(bad, text, sizeof text);
    cr_assert_str_eq(text, "Refused: wrong or missing token", "no retry: the same token would be refused again");
    cr_assert(cdp_eval_bool(bad, "document.getElementById('retry').hidden && window.tessera.retryInS === 0 &&"
                                 " /reload/.test(document.getElementById('status-detail').textContent)"),
              "a refused token says to reload and schedules no retry");

    /* a page whose socket finds nobody (as when the kiosk is not running) */
    cdp_page *nobody = cdp_open_page_scripted(b, k.url, "window.__host = '127.0.0.1:1';" PAGE_HOOKS, why, sizeof why);
    cr_assert(nobody, "%s", why);
    wait_js(nobody, "window.tessera.status === 'unreachable' && /^Cannot reach the wall — retrying in \\d+ s$/.test("
                    "document.getElementById('status-line').textContent)");
    cr_assert(cdp_eval_bool(nobody, STATUS_VISIBLE));

    /* the first viewer leaves: the refused one gets in on a retry, and its status goes */
    cr_assert(cdp_eval_bool(a, "setTimeout(() => { location.href = 'about:blank'; }, 0); true"));
    wait_js(full, "window.tessera.status === 'shown' && window.tessera.framesShown >= 1");
    cr_assert_not(cdp_eval_bool(full, STATUS_VISIBLE));

    /* the kiosk stops: it says so (close 1001), and the page keeps saying so while its retries find nobody */
    double connects = cdp_eval_number(full, "window.tessera.connects");
    cr_assert_eq(kiosk_stop(&k, true), 0);
    char until[512];
    snprintf(until, sizeof until,
             "window.tessera.status === 'stopped' && window.tessera.connects > %.0f && window.tessera.closeCode === 1006"
             " && /^The wall stopped — retrying in \\d+ s$/.test(document.getElementById('status-line').textContent)",
             connects);
    wait_js(full, until);
    cr_assert(cdp_eval_bool(full, "(() => { const s = window.tessera.statuses;"
                                  " return s.indexOf('stopped') > s.lastIndexOf('shown'); })()"),
              "the stop was not said");
    cr_assert(cdp_eval_bool(full, STATUS_VISIBLE));
    cdp_close(b);
    char log[16384];
    support_read_text(k.err_path, log, sizeof log);
    cr_assert(strstr(log, "refused: 1 token, "), "the wrong token is counted once: %s", log);
    support_remove_tmp_dir(dir);
}

/* The canvas's centre in CSS pixels, and its size. */
static void canvas_box(cdp_page *p, double *cx, double *cy, double *w, double *h)
{
    *cx = cdp_eval_number(p, "(r => r.left + r.width / 2)(document.getElementById('view').getBoundingClientRect())");
    *cy = cdp_eval_number(p, "(r => r.top + r.height / 2)(document.getElementById('view').getBoundingClientRect())");
    *w = cdp_eval_number(p, "document.getElementById('view').getBoundingClientRect().width");
    *h = cdp_eval_number(p, "document.getElementById('view').getBoundingClientRect().height");
    cr_assert(*w > 100.0 && *h > 50.0, "the canvas is %gx%g CSS pixels", *w, *h);
}

/* The highest-numbered frame file wall_NNNN.png in dir. */
static void last_frame(const char *dir, char *out, size_t out_bytes)
{
    DIR *d = opendir(dir);
    cr_assert(d);
    int best = -1;
    struct dirent *e;
    while ((e = readdir(d))) {
        int n;
        if (sscanf(e->d_name, "wall_%d.png", &n) == 1 && n > best)
            best = n;
    }
    closedir(d);
    cr_assert_geq(best, 0, "no frames in %s", dir);
    snprintf(out, out_bytes, "%s/wall_%04d.png", dir, best);
}

/* A drag on the page orbits the wall's camera; the wall's last frame equals
 * the native replay of the recorded transactions. */
Test(remote_browser, a_drag_orbits_the_camera_and_the_wall_equals_the_replay, .timeout = 300)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-drag");
    char cfg[512], rec[512], out[512];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    snprintf(rec, sizeof rec, "%s/rec.txt", dir);
    snprintf(out, sizeof out, "%s/wall_####.png", dir);
    write_file(cfg, "{\"remote\": {\"width\": 480, \"height\": 270}}");
    const char *args[] = {"--config", cfg, "--display", "dump", "--out", out, "--size", "160x90", "--threads", "2",
                          "--time", "fixed", "--rate", "30", "--record-input", rec, NULL};
    cdp_browser *b = browser_or_skip(); /* before the kiosk: a skip leaves nothing running */
    kiosk k;
    kiosk_start(&k, dir, args);
    cdp_page *p = open_page(b, k.url);
    wait_js(p, "window.tessera.connected && window.tessera.framesShown >= 2");
    double serial0 = cdp_eval_number(p, "window.tessera.cameraSerial");
    double cx, cy, w, h;
    canvas_box(p, &cx, &cy, &w, &h);
    cr_assert(cdp_mouse(p, "mouseMoved", cx, cy, "none"));
    cr_assert(cdp_mouse(p, "mousePressed", cx, cy, "left"));
    for (int i = 1; i <= 8; i++) {
        cr_assert(cdp_mouse(p, "mouseMoved", cx + 0.03 * w * i, cy + 0.01 * h * i, "left"));
        wait_js(p, "true"); /* one round trip: the page has handled the move */
    }
    cr_assert(cdp_mouse(p, "mouseReleased", cx + 0.24 * w, cy + 0.08 * h, "left"));
    char cond[256];
    snprintf(cond, sizeof cond, "window.tessera.cameraSerial > %.0f", serial0);
    wait_js(p, cond);
    /* settle: the record stops growing while frames keep coming */
    double shown = cdp_eval_number(p, "window.tessera.framesShown");
    snprintf(cond, sizeof cond, "window.tessera.framesShown >= %.0f", shown + 10);
    wait_js(p, cond);
    /* stopped with the page still there: its leaving would be input after the last frame */
    cr_assert_eq(kiosk_stop(&k, true), 0);
    cdp_close(b);
    char text[16384];
    support_read_text(rec, text, sizeof text);
    cr_assert(strstr(text, " camera all "), "the drag recorded camera transactions: %s", text);
    cr_assert(strstr(text, " pointer 0 1 "), "the viewer's pointer was recorded: %s", text);
    char live[600], replay[600], cmd[2048], log[600];
    last_frame(dir, live, sizeof live);
    snprintf(replay, sizeof replay, "%s/replay.png", dir);
    snprintf(log, sizeof log, "%s/replay.log", dir);
    snprintf(cmd, sizeof cmd, "timeout 120 %s render --size 160x90 --threads 2 --replay-input '%s' --out '%s' > '%s' 2>&1",
             support_tessera_bin(), rec, replay, log);
    support_read_text(log, text, sizeof text);
    cr_assert_eq(support_run(cmd), 0, "the native replay failed: %s", text);
    tess_error err = {{0}};
    int lw, lh, rw, rh;
    uint8_t *a = NULL, *c = NULL;
    cr_assert(dump_read_rgb8(live, &lw, &lh, &a, &err), "%s", err.msg);
    cr_assert(dump_read_rgb8(replay, &rw, &rh, &c, &err), "%s", err.msg);
    cr_assert(lw == rw && lh == rh);
    size_t differ = 0;
    for (size_t i = 0; i < (size_t)lw * (size_t)lh * 3; i++)
        differ += a[i] != c[i];
    cr_assert_eq(differ, 0, "%zu values of the wall's last frame (%s) differ from the native replay", differ, live);
    free(a);
    free(c);
    support_remove_tmp_dir(dir);
}

/* Whether the page's canvas shows `colour` (#rrggbb, within a JPEG's
 * tolerance) near fraction (fx, fy) of the picture. */
static void pointer_condition(char *out, size_t bytes, const char *colour, double fx, double fy)
{
    snprintf(out, bytes,
             "(() => { const c = document.getElementById('view'), g = c.getContext('2d');"
             " const want = [1, 3, 5].map(i => parseInt('%s'.substr(i, 2), 16));"
             " const x0 = Math.round(%f * c.width) - 12, y0 = Math.round(%f * c.height) - 12;"
             " const d = g.getImageData(x0, y0, 25, 25).data;"
             " for (let i = 0; i < d.length; i += 4)"
             "  if (Math.abs(d[i] - want[0]) < 40 && Math.abs(d[i + 1] - want[1]) < 40 && Math.abs(d[i + 2] - want[2]) < 40)"
             "   return true;"
             " return false; })()",
             colour, fx, fy);
}

/* Two pages see each other's pointers in the other viewer's colour. */
Test(remote_browser, two_pages_see_each_others_pointers, .timeout = 300)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-pointers");
    char cfg[512];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    write_file(cfg, "{\"remote\": {\"width\": 480, \"height\": 270}}");
    const char *args[] = {"--config", cfg, "--display", "null", "--size", "160x90", "--threads", "2",
                          "--time", "fixed", "--rate", "30", NULL};
    cdp_browser *b = browser_or_skip(); /* before the kiosk: a skip leaves nothing running */
    kiosk k;
    kiosk_start(&k, dir, args);
    cdp_page *a = open_page(b, k.url), *c = open_page(b, k.url);
    wait_js(a, "window.tessera.connected && window.tessera.framesShown >= 1");
    wait_js(c, "window.tessera.connected && window.tessera.framesShown >= 1");
    json_object *v;
    char why[512], colour_a[16] = "", colour_c[16] = "";
    cr_assert(cdp_eval(a, "window.tessera.colour", &v, why, sizeof why) && v, "%s", why);
    snprintf(colour_a, sizeof colour_a, "%s", json_object_get_string(v));
    json_object_put(v);
    cr_assert(cdp_eval(c, "window.tessera.colour", &v, why, sizeof why) && v, "%s", why);
    snprintf(colour_c, sizeof colour_c, "%s", json_object_get_string(v));
    json_object_put(v);
    cr_assert_str_neq(colour_a, colour_c, "each viewer its own colour");
    double cx, cy, w, h;
    canvas_box(a, &cx, &cy, &w, &h);
    /* A points at (0.3, 0.4) of the picture, C at (0.7, 0.6) */
    cr_assert(cdp_mouse(a, "mouseMoved", cx - 0.2 * w, cy - 0.1 * h, "none"));
    canvas_box(c, &cx, &cy, &w, &h);
    cr_assert(cdp_mouse(c, "mouseMoved", cx + 0.2 * w, cy + 0.1 * h, "none"));
    char cond[1024];
    pointer_condition(cond, sizeof cond, colour_a, 0.3, 0.4);
    wait_js(c, cond);
    pointer_condition(cond, sizeof cond, colour_c, 0.7, 0.6);
    wait_js(a, cond);
    cdp_close(b);
    cr_assert_eq(kiosk_stop(&k, true), 0);
    support_remove_tmp_dir(dir);
}

/* ---- a raw WebSocket client (tests/ws_client.h), for what a browser will not do ---- */

/* Read `frames` frames, acknowledging each as the page does; their rate. */
static double read_frames(int fd, int frames)
{
    static uint8_t payload[4 << 20];
    double t0 = 0.0;
    for (int got = 0; got < frames;) {
        int op;
        size_t len;
        cr_assert(ws_read(fd, &op, payload, sizeof payload, &len), "the connection ended");
        if (op != 2)
            continue; /* the hello */
        cr_assert_geq(len, 32);
        uint64_t frame = 0;
        for (int i = 7; i >= 0; i--)
            frame = frame << 8 | payload[8 + i];
        char ack[64];
        snprintf(ack, sizeof ack, "{\"t\":\"ack\",\"frame\":%llu}", (unsigned long long)frame);
        ws_send_text(fd, ack);
        if (got++ == 0)
            t0 = now_s(); /* from the first frame: the channel was off before */
    }
    return (frames - 1) / (now_s() - t0);
}

/* The frames a client that reads gets per second, with a second client
 * beside it that did the handshake and never reads (or none). */
static double frames_per_second(const char *dir, bool stall, unsigned long long *skipped)
{
    char cfg[512];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    write_file(cfg, "{\"remote\": {\"width\": 480, \"height\": 270}}");
    const char *args[] = {"--config", cfg, "--display", "null", "--size", "320x180", "--threads", "2", NULL};
    kiosk k;
    kiosk_start(&k, dir, args);
    int status, stalled = -1;
    if (stall) {
        stalled = ws_connect(k.port, k.token, &status);
        cr_assert_eq(status, 101, "the stalled client was let in");
    }
    int reader = ws_connect(k.port, k.token, &status);
    cr_assert_eq(status, 101);
    double fps = read_frames(reader, 120);
    cr_assert_eq(kiosk_stop(&k, true), 0, "the kiosk ends cleanly with a client that never reads");
    close(reader);
    if (stalled >= 0)
        close(stalled);
    char text[16384];
    support_read_text(k.err_path, text, sizeof text);
    const char *at = strstr(text, " skipped for slow viewers");
    cr_assert(at, "%s", text);
    while (at > text && at[-1] >= '0' && at[-1] <= '9')
        at--;
    *skipped = strtoull(at, NULL, 10);
    return fps;
}

Test(remote_browser, a_client_that_stops_reading_does_not_hold_the_wall, .timeout = 300)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-stall");
    unsigned long long skipped_alone, skipped_stalled;
    double alone = frames_per_second(dir, false, &skipped_alone);
    double stalled = frames_per_second(dir, true, &skipped_stalled);
    cr_assert_gt(skipped_stalled, 100, "the client that never read missed the frames it could not take (%llu)",
                 skipped_stalled);
    fprintf(stderr,
            "remote view: a reading client got %.1f frames/s alone, %.1f beside a client that never reads "
            "(ratio %.2f; frames skipped for slow viewers: %llu, %llu)\n",
            alone, stalled, stalled / alone, skipped_alone, skipped_stalled);
    support_remove_tmp_dir(dir);
}

/* A refused viewer's socket: the handshake completes (101), then the first
 * and only frame is a close with `code` and `reason`. */
static void expect_refusal(int fd, int status, int code, const char *reason)
{
    cr_assert_eq(status, 101, "a refused viewer's handshake completes, to carry the close's reason");
    uint8_t payload[256];
    int op;
    size_t len;
    cr_assert(ws_read(fd, &op, payload, sizeof payload - 1, &len), "no close frame came");
    cr_assert_eq(op, 8, "the first frame is a close, not opcode %d", op);
    cr_assert_geq(len, 2);
    payload[len] = 0;
    cr_assert_eq(payload[0] << 8 | payload[1], code);
    cr_assert_str_eq((const char *)payload + 2, reason);
}

/* A wrong token, and more viewers than allowed, are refused: the socket is
 * closed at once with a code and a reason (docs/remote-protocol.md). */
Test(remote_browser, wrong_tokens_and_too_many_viewers_are_refused, .timeout = 120)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-refuse");
    char cfg[512];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    write_file(cfg, "{\"remote\": {\"width\": 160, \"height\": 90, \"max_viewers\": 2}}");
    const char *args[] = {"--config", cfg, "--display", "null", "--size", "160x90", "--threads", "2", NULL};
    kiosk k;
    kiosk_start(&k, dir, args);
    int status, fds[3];
    int bad = ws_connect(k.port, "0123456789abcdef0123456789abcdef", &status);
    expect_refusal(bad, status, 4403, "a wrong or missing token");
    close(bad);
    for (int i = 0; i < 2; i++) {
        fds[i] = ws_connect(k.port, k.token, &status);
        cr_assert_eq(status, 101, "viewer %d", i);
        read_frames(fds[i], 1); /* it is attached: its first frame came */
    }
    fds[2] = ws_connect(k.port, k.token, &status);
    expect_refusal(fds[2], status, 4503, "too many viewers (2 max)");
    /* malformed messages are dropped and the connection stays */
    ws_send_text(fds[0], "not json");
    ws_send_text(fds[0], "{\"t\":\"warp\"}");
    ws_send_text(fds[0], "{\"t\":\"down\",\"x\":0.5,\"y\":0.5,\"button\":7}");
    read_frames(fds[0], 3);
    cr_assert_eq(kiosk_stop(&k, true), 0);
    /* each viewer was told why it goes: after what was on its way, a close 1001 with its reason */
    for (int i = 0; i < 2; i++) {
        static uint8_t payload[4 << 20];
        int op = 0;
        size_t len = 0;
        while (op != 8)
            cr_assert(ws_read(fds[i], &op, payload, sizeof payload - 1, &len), "viewer %d: no close came", i);
        payload[len] = 0;
        cr_assert(len >= 2 && (payload[0] << 8 | payload[1]) == 1001, "viewer %d: close code", i);
        cr_assert_str_eq((const char *)payload + 2, "the kiosk stopped");
    }
    for (int i = 0; i < 3; i++)
        close(fds[i]);
    char text[16384];
    support_read_text(k.err_path, text, sizeof text);
    cr_assert(strstr(text, "refused: 1 token, 1 full"), "%s", text);
    cr_assert(strstr(text, "3 dropped (not-json 1) (unknown-type 1) (out-of-range 1)"), "%s", text);
    support_remove_tmp_dir(dir);
}

/* A 16x9 thumbnail of the page's canvas: the mean green of each cell. */
#define THUMB_CELLS (16 * 9)
static void thumbnail(cdp_page *p, int out[THUMB_CELLS])
{
    json_object *v;
    char why[512];
    cr_assert(cdp_eval(p,
                       "(() => { const c = document.getElementById('view'), g = c.getContext('2d');"
                       " const d = g.getImageData(0, 0, c.width, c.height).data, out = [];"
                       " for (let ty = 0; ty < 9; ty++) for (let tx = 0; tx < 16; tx++) {"
                       "  let s = 0, n = 0;"
                       "  for (let y = Math.floor(ty * c.height / 9); y < Math.floor((ty + 1) * c.height / 9); y++)"
                       "   for (let x = Math.floor(tx * c.width / 16); x < Math.floor((tx + 1) * c.width / 16); x++)"
                       "    { s += d[4 * (y * c.width + x) + 1]; n++; }"
                       "  out.push(Math.round(s / n)); }"
                       " return out.join(','); })()",
                       &v, why, sizeof why) &&
                  v,
              "%s", why);
    const char *s = json_object_get_string(v);
    for (int i = 0; i < THUMB_CELLS; i++) {
        char *end;
        out[i] = (int)strtol(s, &end, 10);
        cr_assert(end != s, "thumbnail: %s", json_object_get_string(v));
        s = *end == ',' ? end + 1 : end;
    }
    json_object_put(v);
}

static int thumbnail_max_difference(const int a[THUMB_CELLS], const int b[THUMB_CELLS])
{
    int worst = 0;
    for (int i = 0; i < THUMB_CELLS; i++)
        worst = abs(a[i] - b[i]) > worst ? abs(a[i] - b[i]) : worst;
    return worst;
}

/* Page A asks for a private view and orbits it with a one-finger touch
 * drag: A's picture turns, the wall and page B (following) do not move, and
 * nothing of it is recorded; back to following, A shows the wall's picture
 * again. */
Test(remote_browser, a_private_view_turns_alone_and_following_again_shows_the_wall, .timeout = 300)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-private");
    char cfg[512], rec[512], out[512];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    snprintf(rec, sizeof rec, "%s/rec.txt", dir);
    snprintf(out, sizeof out, "%s/wall_####.png", dir);
    write_file(cfg, "{\"remote\": {\"width\": 480, \"height\": 270, \"max_viewers\": 3, \"private_views\": 1}}");
    const char *args[] = {"--config", cfg, "--display", "dump", "--out", out, "--size", "160x90", "--threads", "2",
                          "--time", "fixed", "--rate", "30", "--record-input", rec, NULL};
    cdp_browser *b = browser_or_skip(); /* before the kiosk: a skip leaves nothing running */
    kiosk k;
    kiosk_start(&k, dir, args);
    cdp_page *a = open_page(b, k.url), *c = open_page(b, k.url);
    wait_js(a, "window.tessera.connected && window.tessera.framesShown >= 2");
    wait_js(c, "window.tessera.connected && window.tessera.framesShown >= 2");
    cr_assert_eq(cdp_eval_number(a, "window.tessera.privateViews"), 1.0, "the hello says how many private views");
    int wall_before[THUMB_CELLS], a_private[THUMB_CELLS], a_turned[THUMB_CELLS], c_after[THUMB_CELLS],
        a_back[THUMB_CELLS];
    thumbnail(c, wall_before);
    double c_serial = cdp_eval_number(c, "window.tessera.cameraSerial");

    /* A: private; its first frames show the wall's camera */
    cr_assert(cdp_eval_bool(a, "(document.getElementById('private').click(), true)"));
    wait_js(a, "window.tessera.private && window.tessera.framesSinceView >= 2");
    thumbnail(a, a_private);
    cr_assert_leq(thumbnail_max_difference(a_private, wall_before), 2,
                  "a private view starts from the wall's camera");
    /* C asks too: the only private view is lent, so C is told and keeps following */
    cr_assert(cdp_eval_bool(c, "(document.getElementById('private').click(), true)"));
    wait_js(c, "window.tessera.views >= 1 && !window.tessera.private");
    wait_js(c, "document.getElementById('note').textContent.includes('no private view is free')");

    /* A orbits with one finger */
    double a_serial = cdp_eval_number(a, "window.tessera.cameraSerial");
    double cx, cy, w, h;
    canvas_box(a, &cx, &cy, &w, &h);
    double xy[2] = {cx, cy};
    cr_assert(cdp_touch(a, "touchStart", xy, 1));
    for (int i = 1; i <= 8; i++) {
        xy[0] = cx + 0.04 * w * i;
        xy[1] = cy + 0.01 * h * i;
        cr_assert(cdp_touch(a, "touchMove", xy, 1));
        wait_js(a, "true"); /* one round trip: the page has handled the move */
    }
    cr_assert(cdp_touch(a, "touchEnd", xy, 0));
    char cond[256];
    snprintf(cond, sizeof cond, "window.tessera.cameraSerial > %.0f", a_serial);
    wait_js(a, cond);
    double shown = cdp_eval_number(a, "window.tessera.framesShown");
    snprintf(cond, sizeof cond, "window.tessera.framesShown >= %.0f", shown + 5);
    wait_js(a, cond);
    thumbnail(a, a_turned);
    cr_assert_gt(thumbnail_max_difference(a_turned, a_private), 20, "the touch drag turned A's private view");
    /* the wall did not move: C's frames go on with the same camera and picture */
    shown = cdp_eval_number(c, "window.tessera.framesShown");
    snprintf(cond, sizeof cond, "window.tessera.framesShown >= %.0f", shown + 5);
    wait_js(c, cond);
    cr_assert_eq(cdp_eval_number(c, "window.tessera.cameraSerial"), c_serial, "the wall's camera was set");
    thumbnail(c, c_after);
    cr_assert_leq(thumbnail_max_difference(c_after, wall_before), 2, "the wall's picture changed");

    /* A follows the wall again: its picture is the wall's */
    cr_assert(cdp_eval_bool(a, "(document.getElementById('private').click(), true)"));
    wait_js(a, "!window.tessera.private && window.tessera.framesSinceView >= 2");
    thumbnail(a, a_back);
    cr_assert_leq(thumbnail_max_difference(a_back, wall_before), 2, "following again shows the wall's picture");
    cr_assert_eq(kiosk_stop(&k, true), 0);
    cdp_close(b);

    char text[16384];
    support_read_text(k.err_path, text, sizeof text);
    cr_assert(strstr(text, "viewer 0 has a private view") || strstr(text, "viewer 1 has a private view"), "%s", text);
    cr_assert(strstr(text, "1 private views (1 refused: none free)"), "the counts at exit: %s", text);
    support_read_text(rec, text, sizeof text);
    cr_assert_null(strstr(text, "channel-active"), "the private view's channel switches were recorded: %s", text);
    for (int ch = 1; ch < 8; ch++) {
        char camera[32];
        snprintf(camera, sizeof camera, " camera %d ", ch);
        cr_assert_null(strstr(text, camera), "a private camera was recorded: %s", text);
    }
    /* the wall's first and last frames are the same picture */
    char first[600], last[600];
    snprintf(first, sizeof first, "%s/wall_0000.png", dir);
    last_frame(dir, last, sizeof last);
    tess_error err = {{0}};
    int fw, fh, lw, lh;
    uint8_t *f0 = NULL, *f1 = NULL;
    cr_assert(dump_read_rgb8(first, &fw, &fh, &f0, &err), "%s", err.msg);
    cr_assert(dump_read_rgb8(last, &lw, &lh, &f1, &err), "%s", err.msg);
    cr_assert(fw == lw && fh == lh && memcmp(f0, f1, (size_t)fw * (size_t)fh * 3) == 0,
              "the wall's last frame (%s) is not its first: the private view moved the wall", last);
    free(f0);
    free(f1);
    support_remove_tmp_dir(dir);
}

/* A broken "remote" object or option: the run refuses to start, naming the
 * file, the field and the problem. */
Test(remote_config, bad_remote_settings_are_named, .timeout = 120)
{
    static const struct {
        const char *config, *expect;
    } cases[] = {
        {"{\"remote\": 5}", "field 'remote': expected an object"},
        {"{\"remote\": {\"port\": 70000}}", "field 'remote.port': must be in [0, 65535], got 70000"},
        {"{\"remote\": {\"bind\": \"localhost\"}}", "remote.bind: 'localhost' is not an IPv4 address"},
        {"{\"remote\": {\"token\": \"short\"}}", "remote.token: 5 characters (8..64)"},
        {"{\"remote\": {\"token\": \"abc$defgh12\"}}", "remote.token: character 4 '$'"},
        {"{\"remote\": {\"max_viewers\": 9}}", "field 'remote.max_viewers': must be in [1, 8], got 9"},
        {"{\"remote\": {\"max_viewers\": 2, \"private_views\": 5}}", "remote.private_views: 5 (0..max_viewers = 2)"},
        {"{\"remote\": {\"width\": 8}}", "field 'remote.width': must be in [16, 4096], got 8"},
        {"{\"remote\": {\"quality\": 0}}", "field 'remote.quality': must be in [1, 100], got 0"},
        {"{\"remote\": {\"subsampling\": \"411\"}}", "field 'remote.subsampling': unknown value '411'"},
        {"{\"remote\": {\"colour\": 1}}", "field 'remote.colour': unknown field"},
    };
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-config");
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char cfg[512], log[512], cmd[2048], text[4096];
        snprintf(cfg, sizeof cfg, "%s/cfg%zu.json", dir, i);
        snprintf(log, sizeof log, "%s/log%zu.txt", dir, i);
        write_file(cfg, cases[i].config);
        snprintf(cmd, sizeof cmd, "timeout 60 %s run --config '%s' --display null --frames 1 > '%s' 2>&1",
                 support_tessera_bin(), cfg, log);
        int status = support_run(cmd);
        support_read_text(log, text, sizeof text);
        cr_expect(status != 0 && status != 124, "case %zu (%s) ran (status %d): %s", i, cases[i].config, status, text);
        cr_expect(strstr(text, cfg) && strstr(text, cases[i].expect), "case %zu: '%s' does not name '%s' and '%s'",
                  i, text, cfg, cases[i].expect);
    }
    char log[512], cmd[1024], text[4096];
    snprintf(log, sizeof log, "%s/option.txt", dir);
    snprintf(cmd, sizeof cmd, "timeout 60 %s run --remote 70000 --display null --frames 1 > '%s' 2>&1",
             support_tessera_bin(), log);
    cr_expect_neq(support_run(cmd), 0);
    support_read_text(log, text, sizeof text);
    cr_expect(strstr(text, "--remote: expected a whole number from 0 to 65535, got '70000'"), "%s", text);
    support_remove_tmp_dir(dir);
}

/* This machine's first IPv4 address that is not loopback, or false. */
static bool network_address(char *out, size_t bytes)
{
    struct ifaddrs *list;
    bool found = false;
    if (getifaddrs(&list) != 0)
        return false;
    for (struct ifaddrs *i = list; i && !found; i = i->ifa_next)
        if (i->ifa_addr && i->ifa_addr->sa_family == AF_INET && !(i->ifa_flags & IFF_LOOPBACK) &&
            (i->ifa_flags & IFF_UP))
            found = inet_ntop(AF_INET, &((struct sockaddr_in *)(void *)i->ifa_addr)->sin_addr, out,
                              (socklen_t)bytes) != NULL;
    freeifaddrs(list);
    return found;
}

static bool tcp_connects(const char *host, int port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    cr_assert(fd >= 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    cr_assert_eq(inet_pton(AF_INET, host, &a.sin_addr), 1, "%s", host);
    bool ok = connect(fd, (struct sockaddr *)&a, sizeof a) == 0;
    close(fd);
    return ok;
}

/* The tablet's way in: by default the view is reachable on loopback only;
 * with --remote-bind 0.0.0.0 the printed URL names the machine's network
 * address, and a page opened there shows frames and steers. */
Test(remote_browser, the_network_reaches_the_view_only_when_bound_to_it, .timeout = 300)
{
    char address[64];
    if (!network_address(address, sizeof address))
        cr_skip_test("this machine has no network address besides loopback");
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "remote-network");
    const char *local_args[] = {"--display", "null", "--size", "160x90", "--threads", "2", "--time", "fixed",
                                "--rate", "30", "--remote", "0", "--remote-token", "network-test-token", NULL};
    kiosk k;
    kiosk_start(&k, dir, local_args);
    cr_assert_str_eq(k.host, "127.0.0.1", "bound to loopback unless told otherwise");
    cr_assert(tcp_connects("127.0.0.1", k.port));
    cr_assert_not(tcp_connects(address, k.port), "the view answered on %s without --remote-bind", address);
    cr_assert_eq(kiosk_stop(&k, true), 0);

    cdp_browser *b = browser_or_skip(); /* before the kiosk: a skip leaves nothing running */
    const char *network_args[] = {"--display", "null", "--size", "160x90", "--threads", "2", "--time", "fixed",
                                  "--rate", "30", "--remote", "0", "--remote-bind", "0.0.0.0",
                                  "--remote-token", "network-test-token", NULL};
    kiosk_start(&k, dir, network_args);
    cr_assert_str_eq(k.host, address, "the URL names the machine's network address");
    cdp_page *p = open_page(b, k.url);
    wait_js(p, "window.tessera.connected && window.tessera.framesShown >= 2");
    double serial0 = cdp_eval_number(p, "window.tessera.cameraSerial");
    double cx, cy, w, h;
    canvas_box(p, &cx, &cy, &w, &h);
    cr_assert(cdp_mouse(p, "mouseMoved", cx, cy, "none"));
    cr_assert(cdp_mouse(p, "mousePressed", cx, cy, "left"));
    for (int i = 1; i <= 4; i++) {
        cr_assert(cdp_mouse(p, "mouseMoved", cx + 0.05 * w * i, cy, "left"));
        wait_js(p, "true");
    }
    cr_assert(cdp_mouse(p, "mouseReleased", cx + 0.2 * w, cy, "left"));
    char cond[128];
    snprintf(cond, sizeof cond, "window.tessera.cameraSerial > %.0f", serial0);
    wait_js(p, cond);
    cdp_close(b);
    cr_assert_eq(kiosk_stop(&k, true), 0);
    support_remove_tmp_dir(dir);
}
