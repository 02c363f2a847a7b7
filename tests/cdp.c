/* cdp.c - the DevTools protocol over a pipe (cdp.h). */
#define _GNU_SOURCE /* pipe2, mkdtemp */
#include "cdp.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define CDP_PAGES_MAX 8
#define CDP_START_S 60.0 /* Chromium's first reply */

struct cdp_page {
    cdp_browser *b;
    char target[128];
    char session[128];
};

struct cdp_browser {
    pid_t pid;
    int to_chrome, from_chrome; /* our ends of its fd 3 and fd 4 */
    char profile[64];
    int next_id;
    char *buf; /* what has been read and not yet taken: messages split at NULs */
    size_t buf_len, buf_cap;
    cdp_page *pages[CDP_PAGES_MAX];
    int page_count;
};

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void say(char *why, size_t bytes, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void say(char *why, size_t bytes, const char *fmt, ...)
{
    if (!why || !bytes)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, bytes, fmt, ap);
    va_end(ap);
}

/* The next whole message, waiting until `deadline`; NULL on time-out or EOF. */
static json_object *read_message(cdp_browser *b, double deadline, char *why, size_t why_bytes)
{
    for (;;) {
        char *nul = b->buf_len ? memchr(b->buf, '\0', b->buf_len) : NULL;
        if (nul) {
            size_t n = (size_t)(nul - b->buf);
            json_object *m = json_tokener_parse(b->buf);
            memmove(b->buf, nul + 1, b->buf_len - n - 1);
            b->buf_len -= n + 1;
            if (m)
                return m;
            continue; /* not JSON: skip it */
        }
        double left = deadline - now_s();
        if (left <= 0.0) {
            say(why, why_bytes, "no reply from Chromium in time");
            return NULL;
        }
        struct pollfd p = {.fd = b->from_chrome, .events = POLLIN};
        int r = poll(&p, 1, (int)(left * 1000.0) + 1);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            continue;
        if (b->buf_len + 65536 + 1 > b->buf_cap) {
            size_t cap = (b->buf_cap ? b->buf_cap * 2 : 1 << 20) + 65536;
            char *grown = realloc(b->buf, cap);
            if (!grown) {
                say(why, why_bytes, "out of memory");
                return NULL;
            }
            b->buf = grown;
            b->buf_cap = cap;
        }
        ssize_t got = read(b->from_chrome, b->buf + b->buf_len, 65536);
        if (got <= 0) {
            say(why, why_bytes, "Chromium closed its pipe (it exited?)");
            return NULL;
        }
        b->buf_len += (size_t)got;
    }
}

static bool write_all(int fd, const char *data, size_t n)
{
    while (n) {
        ssize_t w = write(fd, data, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return false;
        data += w;
        n -= (size_t)w;
    }
    return true;
}

bool cdp_call(cdp_browser *b, cdp_page *page, const char *method, json_object *params, json_object **result,
              double timeout_s, char *why, size_t why_bytes)
{
    if (result)
        *result = NULL;
    int id = ++b->next_id;
    json_object *m = json_object_new_object();
    json_object_object_add(m, "id", json_object_new_int(id));
    json_object_object_add(m, "method", json_object_new_string(method));
    json_object_object_add(m, "params", params ? params : json_object_new_object());
    if (page)
        json_object_object_add(m, "sessionId", json_object_new_string(page->session));
    const char *text = json_object_to_json_string_ext(m, JSON_C_TO_STRING_PLAIN);
    bool sent = write_all(b->to_chrome, text, strlen(text) + 1); /* with its NUL */
    json_object_put(m);
    if (!sent) {
        say(why, why_bytes, "%s: writing to Chromium failed", method);
        return false;
    }
    double deadline = now_s() + timeout_s;
    for (;;) {
        json_object *r = read_message(b, deadline, why, why_bytes);
        if (!r) {
            size_t n = why ? strlen(why) : 0;
            if (why && n + 1 < why_bytes)
                snprintf(why + n, why_bytes - n, " (waiting for %s)", method);
            return false;
        }
        json_object *rid;
        if (json_object_object_get_ex(r, "id", &rid) && json_object_get_int(rid) == id) {
            json_object *err, *res;
            bool ok = !json_object_object_get_ex(r, "error", &err);
            if (!ok)
                say(why, why_bytes, "%s: %s", method, json_object_to_json_string(err));
            else if (result && json_object_object_get_ex(r, "result", &res))
                *result = json_object_get(res);
            json_object_put(r);
            return ok;
        }
        json_object_put(r); /* an event, or another call's late reply */
    }
}

cdp_browser *cdp_launch(int width_px, int height_px, char *why, size_t why_bytes)
{
    const char *exe = getenv("TESSERA_CHROMIUM");
    if (!exe || !exe[0])
        exe = "chromium";
    cdp_browser *b = calloc(1, sizeof *b);
    if (!b) {
        say(why, why_bytes, "out of memory");
        return NULL;
    }
    b->pid = -1;
    b->to_chrome = b->from_chrome = -1;
    snprintf(b->profile, sizeof b->profile, "/tmp/tessera-cdp-XXXXXX");
    int in[2] = {-1, -1}, out[2] = {-1, -1};
    if (!mkdtemp(b->profile) || pipe2(in, O_CLOEXEC) != 0 || pipe2(out, O_CLOEXEC) != 0) {
        say(why, why_bytes, "making the profile or the pipes: %s", strerror(errno));
        b->profile[0] = '\0';
        goto fail;
    }
    char window[64], profile[128];
    snprintf(window, sizeof window, "--window-size=%d,%d", width_px, height_px);
    snprintf(profile, sizeof profile, "--user-data-dir=%s", b->profile);
    b->pid = fork();
    if (b->pid < 0) {
        say(why, why_bytes, "fork: %s", strerror(errno));
        goto fail;
    }
    if (b->pid == 0) {
        setpgid(0, 0);
        prctl(PR_SET_PDEATHSIG, SIGKILL); /* the test process gone (a failed assertion): so is the browser */
        /* its fd 3 reads our commands, its fd 4 writes to us: through copies above 4 first, since
         * the pipe's own fds may be 3 or 4 (and dup2 onto itself would keep O_CLOEXEC) */
        int reads = fcntl(in[0], F_DUPFD, 5), writes = fcntl(out[1], F_DUPFD, 5);
        if (reads < 0 || writes < 0 || dup2(reads, 3) < 0 || dup2(writes, 4) < 0)
            _exit(126);
        int devnull = open("/dev/null", O_RDWR);
        if (devnull >= 0) {
            dup2(devnull, 0);
            dup2(devnull, 1);
            dup2(devnull, 2);
        }
        execlp(exe, exe, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
               "--no-default-browser-check", "--disable-background-timer-throttling",
               "--disable-renderer-backgrounding", "--disable-backgrounding-occluded-windows", "--mute-audio",
               "--remote-debugging-pipe", window, profile, "about:blank", (char *)NULL);
        _exit(127);
    }
    close(in[0]);
    close(out[1]);
    b->to_chrome = in[1];
    b->from_chrome = out[0];
    signal(SIGPIPE, SIG_IGN); /* a dead Chromium: write errors, not a signal */
    json_object *version = NULL;
    char reason[256] = "";
    if (!cdp_call(b, NULL, "Browser.getVersion", NULL, &version, CDP_START_S, reason, sizeof reason)) {
        int status;
        if (waitpid(b->pid, &status, WNOHANG) == b->pid && WIFEXITED(status) && WEXITSTATUS(status) == 127)
            say(why, why_bytes, "Chromium '%s' is not installed (sh tools/deps.sh --test installs it)", exe);
        else
            say(why, why_bytes, "Chromium '%s' did not start: %s", exe, reason);
        json_object_put(version);
        goto fail;
    }
    json_object_put(version);
    return b;
fail:
    if (in[0] >= 0 && b->to_chrome < 0)
        close(in[0]), close(in[1]);
    if (out[0] >= 0 && b->from_chrome < 0)
        close(out[0]), close(out[1]);
    cdp_close(b);
    return NULL;
}

void cdp_close(cdp_browser *b)
{
    if (!b)
        return;
    if (b->pid > 0) {
        char why[128];
        cdp_call(b, NULL, "Browser.close", NULL, NULL, 5.0, why, sizeof why);
        int status;
        double deadline = now_s() + 10.0;
        pid_t done = 0;
        while ((done = waitpid(b->pid, &status, WNOHANG)) == 0 && now_s() < deadline)
            usleep(20000);
        kill(-b->pid, SIGKILL); /* its helpers (renderer, GPU, zygote) too */
        if (done == 0)
            waitpid(b->pid, &status, 0);
    }
    if (b->to_chrome >= 0)
        close(b->to_chrome);
    if (b->from_chrome >= 0)
        close(b->from_chrome);
    if (b->profile[0]) {
        char cmd[160];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", b->profile);
        if (system(cmd) != 0)
            fprintf(stderr, "cdp: could not remove %s\n", b->profile);
    }
    for (int i = 0; i < b->page_count; i++)
        free(b->pages[i]);
    free(b->buf);
    free(b);
}

static const char *string_member(json_object *o, const char *key)
{
    json_object *v;
    return o && json_object_object_get_ex(o, key, &v) ? json_object_get_string(v) : NULL;
}

cdp_page *cdp_open_page(cdp_browser *b, const char *url, char *why, size_t why_bytes)
{
    return cdp_open_page_scripted(b, url, NULL, why, why_bytes);
}

cdp_page *cdp_open_page_scripted(cdp_browser *b, const char *url, const char *js_before, char *why, size_t why_bytes)
{
    if (b->page_count == CDP_PAGES_MAX) {
        say(why, why_bytes, "too many pages");
        return NULL;
    }
    cdp_page *p = calloc(1, sizeof *p);
    if (!p) {
        say(why, why_bytes, "out of memory");
        return NULL;
    }
    p->b = b;
    b->pages[b->page_count++] = p;
    json_object *params = json_object_new_object(), *r = NULL;
    json_object_object_add(params, "url", json_object_new_string("about:blank"));
    /* a window of its own: a second tab of one window hides the first, which then stops drawing */
    json_object_object_add(params, "newWindow", json_object_new_boolean(1));
    if (!cdp_call(b, NULL, "Target.createTarget", params, &r, 30.0, why, why_bytes))
        return NULL;
    snprintf(p->target, sizeof p->target, "%s", string_member(r, "targetId") ? string_member(r, "targetId") : "");
    json_object_put(r);
    params = json_object_new_object();
    json_object_object_add(params, "targetId", json_object_new_string(p->target));
    json_object_object_add(params, "flatten", json_object_new_boolean(1));
    if (!cdp_call(b, NULL, "Target.attachToTarget", params, &r, 30.0, why, why_bytes))
        return NULL;
    snprintf(p->session, sizeof p->session, "%s", string_member(r, "sessionId") ? string_member(r, "sessionId") : "");
    json_object_put(r);
    if (!cdp_call(b, p, "Page.enable", NULL, NULL, 30.0, why, why_bytes) ||
        !cdp_call(b, p, "Runtime.enable", NULL, NULL, 30.0, why, why_bytes))
        return NULL;
    if (js_before) {
        params = json_object_new_object();
        json_object_object_add(params, "source", json_object_new_string(js_before));
        if (!cdp_call(b, p, "Page.addScriptToEvaluateOnNewDocument", params, NULL, 30.0, why, why_bytes))
            return NULL;
    }
    params = json_object_new_object();
    json_object_object_add(params, "url", json_object_new_string(url));
    if (!cdp_call(b, p, "Page.navigate", params, &r, 60.0, why, why_bytes))
        return NULL;
    const char *nav_error = string_member(r, "errorText");
    if (nav_error && nav_error[0]) {
        say(why, why_bytes, "navigating to %s: %s", url, nav_error);
        json_object_put(r);
        return NULL;
    }
    json_object_put(r);
    if (!cdp_wait_js(p, "document.readyState === 'complete'", 60.0, why, why_bytes))
        return NULL;
    return p;
}

bool cdp_eval(cdp_page *page, const char *js, json_object **value, char *why, size_t why_bytes)
{
    *value = NULL;
    json_object *params = json_object_new_object(), *r = NULL;
    json_object_object_add(params, "expression", json_object_new_string(js));
    json_object_object_add(params, "returnByValue", json_object_new_boolean(1));
    json_object_object_add(params, "awaitPromise", json_object_new_boolean(1));
    if (!cdp_call(page->b, page, "Runtime.evaluate", params, &r, 120.0, why, why_bytes))
        return false;
    json_object *exc, *res, *val;
    if (json_object_object_get_ex(r, "exceptionDetails", &exc)) {
        say(why, why_bytes, "JavaScript threw: %s", json_object_to_json_string(exc));
        json_object_put(r);
        return false;
    }
    if (json_object_object_get_ex(r, "result", &res) && json_object_object_get_ex(res, "value", &val))
        *value = json_object_get(val);
    json_object_put(r);
    return true;
}

double cdp_eval_number(cdp_page *page, const char *js)
{
    json_object *v;
    char why[256];
    if (!cdp_eval(page, js, &v, why, sizeof why) || !v)
        return NAN;
    enum json_type t = json_object_get_type(v);
    double d = t == json_type_double || t == json_type_int ? json_object_get_double(v) : NAN;
    json_object_put(v);
    return d;
}

bool cdp_eval_bool(cdp_page *page, const char *js)
{
    json_object *v;
    char why[256];
    if (!cdp_eval(page, js, &v, why, sizeof why) || !v)
        return false;
    bool b = json_object_get_type(v) == json_type_boolean && json_object_get_boolean(v);
    json_object_put(v);
    return b;
}

bool cdp_wait_js(cdp_page *page, const char *js_condition, double timeout_s, char *why, size_t why_bytes)
{
    char *js = malloc(strlen(js_condition) + 512);
    if (!js)
        return false;
    sprintf(js,
            "(async () => { const end = performance.now() + %.0f;"
            " for (;;) { try { if (%s) return true; } catch (e) {}"
            " if (performance.now() > end) return false;"
            " await new Promise(r => setTimeout(r, 10)); } })()",
            timeout_s * 1000.0, js_condition);
    json_object *v = NULL;
    bool ok = cdp_eval(page, js, &v, why, why_bytes);
    free(js);
    bool met = ok && v && json_object_get_type(v) == json_type_boolean && json_object_get_boolean(v);
    json_object_put(v);
    if (ok && !met)
        say(why, why_bytes, "waited %.0f s for: %s", timeout_s, js_condition);
    return met;
}

bool cdp_mouse(cdp_page *page, const char *type, double x, double y, const char *button)
{
    json_object *params = json_object_new_object();
    json_object_object_add(params, "type", json_object_new_string(type));
    json_object_object_add(params, "x", json_object_new_double(x));
    json_object_object_add(params, "y", json_object_new_double(y));
    json_object_object_add(params, "button", json_object_new_string(button));
    json_object_object_add(params, "buttons", json_object_new_int(strcmp(button, "left") == 0 &&
                                                                          strcmp(type, "mouseReleased") != 0
                                                                      ? 1
                                                                      : 0));
    json_object_object_add(params, "clickCount", json_object_new_int(strcmp(type, "mouseMoved") ? 1 : 0));
    char why[256];
    return cdp_call(page->b, page, "Input.dispatchMouseEvent", params, NULL, 30.0, why, sizeof why);
}

bool cdp_touch(cdp_page *page, const char *type, const double *xy, int points)
{
    json_object *params = json_object_new_object(), *list = json_object_new_array();
    json_object_object_add(params, "type", json_object_new_string(type));
    for (int i = 0; i < points; i++) {
        json_object *p = json_object_new_object();
        json_object_object_add(p, "x", json_object_new_double(xy[2 * i]));
        json_object_object_add(p, "y", json_object_new_double(xy[2 * i + 1]));
        json_object_object_add(p, "id", json_object_new_int(i));
        json_object_array_add(list, p);
    }
    json_object_object_add(params, "touchPoints", list);
    char why[256];
    return cdp_call(page->b, page, "Input.dispatchTouchEvent", params, NULL, 30.0, why, sizeof why);
}
