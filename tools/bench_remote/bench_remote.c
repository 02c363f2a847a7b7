/* bench_remote.c - the remote view's benchmark (make bench-remote,
 * tools/bench_remote.sh): a kiosk (`tessera run --remote 0`) with a
 * 1280x720 view, one headless Chromium page (tests/cdp.h), and
 *   latency: EVENTS single drag steps on the page's canvas, each from the
 *     moment the page handles the pointer event (performance.now() in a
 *     listener added before the page's own) to the moment the page has drawn
 *     the first frame whose camera serial is newer than the one shown before
 *     the event (a setter on window.tessera.cameraSerial takes the time);
 *   frames per second the page shows and JPEG bytes a frame, over SECONDS
 *     with the camera still.
 * usage: bench_remote TESSERA QUALITY SUBSAMPLING EVENTS SECONDS
 * Prints one line: quality=Q subsampling=S events=N p50_ms= p95_ms= max_ms=
 * fps= kb_per_frame= wall_fps= (the kiosk's own frames per second), or an
 * error on stderr and exit 1. */
#define _GNU_SOURCE
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "tests/cdp.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int fail(const char *what, const char *why)
{
    fprintf(stderr, "bench_remote: %s: %s\n", what, why);
    return 1;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    if (argc != 6) {
        fprintf(stderr, "usage: bench_remote TESSERA QUALITY SUBSAMPLING EVENTS SECONDS\n");
        return 2;
    }
    const char *tessera = argv[1], *quality = argv[2], *sub = argv[3];
    int events = atoi(argv[4]);
    double seconds = atof(argv[5]);
    if (events < 1 || events > 10000 || !(seconds > 0.0))
        return fail("arguments", "EVENTS 1..10000, SECONDS > 0");
    char dir[] = "/tmp/tessera-bench-remote-XXXXXX";
    if (!mkdtemp(dir))
        return fail("mkdtemp", "failed");
    char cfg[128], err_path[128], out_path[128];
    snprintf(cfg, sizeof cfg, "%s/cfg.json", dir);
    snprintf(err_path, sizeof err_path, "%s/kiosk.err", dir);
    snprintf(out_path, sizeof out_path, "%s/kiosk.out", dir);
    FILE *f = fopen(cfg, "w");
    if (!f)
        return fail(cfg, "cannot write");
    fprintf(f, "{\"remote\": {\"width\": 1280, \"height\": 720, \"quality\": %s, \"subsampling\": \"%s\"}}\n", quality,
            sub);
    fclose(f);
    pid_t pid = fork();
    if (pid == 0) {
        int e = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644), o = open(out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(e, 2);
        dup2(o, 1);
        execl(tessera, tessera, "run", "--config", cfg, "--display", "null", "--size", "640x360", (char *)NULL);
        _exit(127);
    }
    /* the URL line */
    char url[256] = "", text[8192];
    for (double end = now_s() + 60.0; !url[0] && now_s() < end;) {
        FILE *e = fopen(err_path, "r");
        size_t n = e ? fread(text, 1, sizeof text - 1, e) : 0;
        if (e)
            fclose(e);
        text[n] = '\0';
        const char *u = strstr(text, "http://");
        if (u && strchr(u, '\n'))
            sscanf(u, "%255s", url);
        else
            usleep(10000);
    }
    int code = 1;
    cdp_browser *b = NULL;
    if (!url[0]) {
        fail("tessera", "no URL line in 60 s");
        goto done;
    }
    char why[1024];
    if (!(b = cdp_launch(1400, 900, why, sizeof why))) {
        fail("chromium", why);
        goto done;
    }
    cdp_page *p = cdp_open_page(b, url, why, sizeof why);
    if (!p || !cdp_wait_js(p, "window.tessera.connected && window.tessera.framesShown >= 5", 60.0, why, sizeof why)) {
        fail("the page", why);
        goto done;
    }
    json_object *v = NULL;
    if (!cdp_eval(p,
                  "(() => { const T = window.tessera; let s = T.cameraSerial; window.__serials = [];"
                  " Object.defineProperty(T, 'cameraSerial', {get() { return s; },"
                  "  set(x) { if (x !== s) window.__serials.push([x, performance.now()]); s = x; }});"
                  " window.__moves = [];"
                  " document.getElementById('view').addEventListener('pointermove',"
                  "  () => window.__moves.push(performance.now()), true); return true; })()",
                  &v, why, sizeof why)) {
        fail("instrumenting the page", why);
        goto done;
    }
    json_object_put(v);
    double cx = cdp_eval_number(p, "(r => r.left + r.width / 2)(document.getElementById('view').getBoundingClientRect())");
    double cy = cdp_eval_number(p, "(r => r.top + r.height / 2)(document.getElementById('view').getBoundingClientRect())");
    double w = cdp_eval_number(p, "document.getElementById('view').getBoundingClientRect().width");
    /* frames per second and bytes a frame, the camera still */
    double f0 = cdp_eval_number(p, "window.tessera.framesShown"), b0 = cdp_eval_number(p, "window.tessera.bytes");
    double t0 = now_s();
    usleep((useconds_t)(seconds * 1e6));
    double f1 = cdp_eval_number(p, "window.tessera.framesShown"), b1 = cdp_eval_number(p, "window.tessera.bytes");
    double fps = (f1 - f0) / (now_s() - t0), kb = (b1 - b0) / (f1 - f0) / 1024.0;
    /* latency: a drag, one step an event */
    double *lat = calloc((size_t)events, sizeof *lat);
    cdp_mouse(p, "mouseMoved", cx, cy, "none");
    cdp_mouse(p, "mousePressed", cx, cy, "left");
    for (int i = 0; i < events; i++) {
        double serial = cdp_eval_number(p, "window.tessera.cameraSerial");
        double step = (i % 20 < 10 ? 1.0 : -1.0) * 0.004 * w; /* back and forth: the camera stays in view */
        cx += step;
        if (!cdp_mouse(p, "mouseMoved", cx, cy, "left")) {
            fail("dispatching a move", "no reply");
            goto done;
        }
        char js[512];
        snprintf(js, sizeof js,
                 "(async () => { const start = window.__moves[window.__moves.length - 1];"
                 " const end = performance.now() + 30000;"
                 " for (;;) { const e = window.__serials.find(e => e[0] > %.0f);"
                 "  if (e) return e[1] - start; if (performance.now() > end) return -1;"
                 "  await new Promise(r => setTimeout(r, 2)); } })()",
                 serial);
        lat[i] = cdp_eval_number(p, js);
        if (!(lat[i] >= 0.0)) {
            fail("latency", "no frame with a newer camera within 30 s of an event");
            goto done;
        }
    }
    cdp_mouse(p, "mouseReleased", cx, cy, "left");
    qsort(lat, (size_t)events, sizeof *lat, cmp_double);
    double p50 = lat[(events - 1) / 2], p95 = lat[(int)ceil(0.95 * events) - 1], max = lat[events - 1];
    free(lat);
    cdp_close(b);
    b = NULL;
    kill(pid, SIGTERM);
    int status;
    waitpid(pid, &status, 0);
    pid = -1;
    FILE *o = fopen(out_path, "r");
    double wall_fps = 0.0;
    while (o && fgets(text, sizeof text, o)) {
        const char *fs = strstr(text, " frames/s");
        if (fs) {
            const char *q = fs;
            while (q > text && q[-1] != ' ')
                q--;
            wall_fps = atof(q);
        }
    }
    if (o)
        fclose(o);
    printf("quality=%s subsampling=%s events=%d p50_ms=%.1f p95_ms=%.1f max_ms=%.1f fps=%.1f kb_per_frame=%.1f "
           "wall_fps=%.1f\n",
           quality, sub, events, p50, p95, max, fps, kb, wall_fps);
    code = 0;
done:
    cdp_close(b);
    if (pid > 0) {
        kill(pid, SIGTERM);
        waitpid(pid, NULL, 0);
    }
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "bench_remote: could not remove %s\n", dir);
    return code;
}
