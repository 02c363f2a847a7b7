/* uinput_touch: a multitouch touchscreen, or with -p a touchpad (clickpad),
 * made with /dev/uinput, driven by one text command per line (guest-side
 * helper of the VM tests).
 *
 * The touchscreen (default): INPUT_PROP_DIRECT, BTN_TOUCH, BTN_TOOL_FINGER/
 * DOUBLETAP/TRIPLETAP/QUADTAP, ABS_X/ABS_Y and ABS_MT_POSITION_X/Y over
 * 0..W-1 and 0..H-1 (so a coordinate is a pixel of the output the screen is
 * mapped to: libinput's x_transformed(W) gives it back exactly), ABS_MT_SLOT
 * 0..9, ABS_MT_TRACKING_ID 0..65535, resolution -R units/mm on every axis.
 * udev's input_id calls it ID_INPUT_TOUCHSCREEN.
 *
 * The touchpad (-p): the same axes and keys plus BTN_LEFT, with
 * INPUT_PROP_POINTER and INPUT_PROP_BUTTONPAD instead of INPUT_PROP_DIRECT:
 * a clickpad as on most laptops. udev's input_id calls it ID_INPUT_TOUCHPAD
 * (BTN_TOOL_FINGER, absolute axes, no INPUT_PROP_DIRECT), libinput makes it a
 * touchpad with the capabilities pointer and gesture. Defaults -s 4000x2400
 * -R 40: 100 x 60 mm, coordinates in device units (40 = 1 mm). A touchpad
 * has no pressure or touch size axes here, so libinput's palm and thumb
 * detection use positions only (see README.md, "Touchpad gestures", for what
 * a gesture needs to be recognised).
 *
 * Events follow the multitouch protocol B: a new contact gets a new tracking
 * id in its slot, a lifted one tracking id -1; at each frame ABS_X/ABS_Y
 * follow the oldest contact, BTN_TOUCH and the BTN_TOOL_* of the number of
 * contacts are updated, then SYN_REPORT.
 *
 * usage: uinput_touch [-p] [-n NAME] [-s WxH] [-R RES] [-i MS] [-g GAP] [-f FIFO]
 *   -p  a touchpad (clickpad) instead of a touchscreen
 *   -n  device name       (default tessera-test-touch, with -p tessera-test-touchpad)
 *   -s  size: coordinates are 0..W-1, 0..H-1     (default 640x480, with -p 4000x2400)
 *   -R  resolution in units per mm of every axis (default 10, with -p 40)
 *   -i  milliseconds between the frames of drag, pinch, pan2 and swipe3
 *       (default 10; a frame is never sent less than MS/2 after the previous
 *       one, even when the program is late: no bursts after a stall)
 *   -g  distance between neighbouring fingers of pan2 and swipe3, in units
 *       (default 80, with -p 20 mm: 20 * RES)
 *   -f  read the commands from this FIFO (made if missing), opened read-write
 *       so that writers may come and go (`echo "tap 10 20" > FIFO`) without
 *       an end of file: only `quit` (or SIGTERM/SIGINT) ends the program.
 *       Without -f: commands from stdin, end of file = quit.
 *
 * Once the device exists (and, when udevd runs, udev has recorded it) it
 * prints "uinput_touch: ready /dev/input/eventN". Then, per command, after it
 * completed: "ok N" (N counts the commands from 1), or "err N: reason" (the
 * command did nothing, or for a gesture: released its fingers). Blank lines
 * and lines starting with '#' are no commands. stdout is flushed at each line.
 *
 * commands (integers; coordinates out of range are clamped into it):
 *   down SLOT X Y     new contact in SLOT (0..9), no SYN_REPORT yet
 *   move SLOT X Y     move the contact in SLOT, no SYN_REPORT yet
 *   up SLOT           lift the contact in SLOT, no SYN_REPORT yet
 *   frame             end the frame: BTN_*, ABS_X/Y, SYN_REPORT
 *   tap X Y [MS]      one finger down, frame, MS (default 50) ms, up, frame
 *   doubletap X Y     two taps of 50 ms whose downs are 120 ms apart
 *   drag X0 Y0 X1 Y1 STEPS   one finger: down at X0,Y0, then STEPS frames of
 *                     motion to X1,Y1 (-i ms apart), then up (all frames)
 *   pinch CX CY R0 R1 STEPS  two fingers at CX-R,CY and CX+R,CY; R goes from
 *                     R0 to R1 in STEPS frames; both down and up in one frame
 *   pan2 X0 Y0 X1 Y1 STEPS   two fingers GAP apart (X-GAP/2 and X+GAP/2)
 *                     moving together from X0,Y0 to X1,Y1 in STEPS frames
 *   swipe3 X0 Y0 X1 Y1 STEPS three fingers in a row GAP apart (X-GAP, X,
 *                     X+GAP) moving together from X0,Y0 to X1,Y1
 *   garbage N SEED    N raw events no well-behaved device sends (a broken or hostile
 *                     one): random EV_ABS/EV_KEY/EV_SYN events of the device's codes
 *                     with values out of range (INT_MIN, INT_MAX, slots -1 and 10,
 *                     tracking ids reused), SYN_MT_REPORT, frames closed at random,
 *                     bursts with no pause (a SYN_DROPPED sent is dropped by the input
 *                     core; a reader sees real ones when a burst overflows its evdev
 *                     buffer); then every slot is lifted in one well-formed frame, so
 *                     later commands start clean
 *   sleep MS          wait
 *   quit              lift every contact, remove the device, exit 0
 * Gestures take the lowest free slots; all their fingers go down in one
 * frame and up in one frame, the last motion frame and the up frame are -i ms
 * apart. Exit status 0, 1 on a setup error.
 *
 * build: gcc -std=c11 -O2 -Wall -Wextra -Werror -o uinput_touch uinput_touch.c
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <linux/input.h>
#include <linux/uinput.h>

#define SLOTS 10
#define MAX_ID 65535
#define GAP 80             /* touchscreen: px between the fingers of pan2, swipe3 */
#define PAD_GAP_MM 20      /* touchpad: mm between the fingers of pan2, swipe3 */
#define MAX_FINGERS 3      /* of a gesture command */
#define TAP_MS 50          /* how long a tap's finger stays down */
#define DOUBLETAP_MS 120   /* from the first tap's down to the second's */

struct contact {
    int active;
    int id;
    int x, y;
    unsigned long seq; /* order of touch-down: ABS_X/Y follow the oldest */
};

struct touch {
    int fd;
    int pad;        /* a touchpad (clickpad), not a touchscreen */
    int w, h;
    int interval_ms;
    int gap;        /* between neighbouring fingers of pan2 and swipe3 */
    struct timespec last_frame; /* when the last frame of a gesture went out */
    int next_id;
    unsigned long next_seq;
    int tool;       /* BTN_TOOL_* key currently down, 0 if none */
    int touching;   /* BTN_TOUCH as last sent */
    struct contact c[SLOTS];
};

static volatile sig_atomic_t stop;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static int emit(struct touch *t, int type, int code, int value)
{
    struct input_event ev;
    memset(&ev, 0, sizeof ev); /* the kernel stamps the time */
    ev.type = (unsigned short)type;
    ev.code = (unsigned short)code;
    ev.value = value;
    if (write(t->fd, &ev, sizeof ev) != (ssize_t)sizeof ev) {
        fprintf(stderr, "uinput_touch: write: %s\n", strerror(errno));
        return -1;
    }
    return 0;
}

static int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* a + (b - a) * i / n, rounded to the nearest integer (n > 0) */
static int lerp(int a, int b, int i, int n)
{
    long num = (long)(b - a) * i;
    long q = num >= 0 ? (num + n / 2) / n : -((-num + n / 2) / n);
    return a + (int)q;
}

static void sleep_ms(long ms)
{
    struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
    while (!stop && nanosleep(&ts, &ts) == -1 && errno == EINTR) {
    }
}

/* sleep until START + MS (CLOCK_MONOTONIC): a steady cadence of frames */
static void sleep_until(const struct timespec *start, long ms)
{
    struct timespec ts = *start;
    ts.tv_sec += ms / 1000;
    ts.tv_nsec += (ms % 1000) * 1000000L;
    if (ts.tv_nsec >= 1000000000L) {
        ts.tv_sec++;
        ts.tv_nsec -= 1000000000L;
    }
    while (!stop && clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

/* the frame I of a gesture that began at START: at START + I * interval, but
 * never less than interval/2 after the previous frame (when the program was
 * late, the frames after it would otherwise go out back to back; libinput's
 * touchpad jump detection scales a motion by 12 ms / the time since the
 * previous frame and drops it as a "jump" when that exceeds 20 mm, or the
 * previous frame's by 7 mm) */
static void pace(struct touch *t, const struct timespec *start, int i)
{
    sleep_until(start, (long)i * t->interval_ms);
    sleep_until(&t->last_frame, t->interval_ms / 2);
    clock_gettime(CLOCK_MONOTONIC, &t->last_frame);
}

static int touch_down(struct touch *t, int slot, int x, int y, char *err, size_t errlen)
{
    if (slot < 0 || slot >= SLOTS) {
        snprintf(err, errlen, "slot %d out of 0..%d", slot, SLOTS - 1);
        return -1;
    }
    struct contact *c = &t->c[slot];
    if (c->active) {
        snprintf(err, errlen, "slot %d is already down", slot);
        return -1;
    }
    c->active = 1;
    c->id = t->next_id;
    t->next_id = t->next_id == MAX_ID ? 0 : t->next_id + 1;
    c->x = clampi(x, 0, t->w - 1);
    c->y = clampi(y, 0, t->h - 1);
    c->seq = t->next_seq++;
    if (emit(t, EV_ABS, ABS_MT_SLOT, slot) || emit(t, EV_ABS, ABS_MT_TRACKING_ID, c->id) ||
        emit(t, EV_ABS, ABS_MT_POSITION_X, c->x) || emit(t, EV_ABS, ABS_MT_POSITION_Y, c->y)) {
        snprintf(err, errlen, "write to uinput failed");
        return -1;
    }
    return 0;
}

static int touch_move(struct touch *t, int slot, int x, int y, char *err, size_t errlen)
{
    if (slot < 0 || slot >= SLOTS || !t->c[slot].active) {
        snprintf(err, errlen, "slot %d is not down", slot);
        return -1;
    }
    struct contact *c = &t->c[slot];
    c->x = clampi(x, 0, t->w - 1);
    c->y = clampi(y, 0, t->h - 1);
    if (emit(t, EV_ABS, ABS_MT_SLOT, slot) || emit(t, EV_ABS, ABS_MT_POSITION_X, c->x) ||
        emit(t, EV_ABS, ABS_MT_POSITION_Y, c->y)) {
        snprintf(err, errlen, "write to uinput failed");
        return -1;
    }
    return 0;
}

static int touch_up(struct touch *t, int slot, char *err, size_t errlen)
{
    if (slot < 0 || slot >= SLOTS || !t->c[slot].active) {
        snprintf(err, errlen, "slot %d is not down", slot);
        return -1;
    }
    t->c[slot].active = 0;
    if (emit(t, EV_ABS, ABS_MT_SLOT, slot) || emit(t, EV_ABS, ABS_MT_TRACKING_ID, -1)) {
        snprintf(err, errlen, "write to uinput failed");
        return -1;
    }
    return 0;
}

/* end of a frame: the single-touch state derived from the contacts, SYN_REPORT */
static int touch_frame(struct touch *t, char *err, size_t errlen)
{
    static const int tools[] = {0, BTN_TOOL_FINGER, BTN_TOOL_DOUBLETAP, BTN_TOOL_TRIPLETAP,
                                BTN_TOOL_QUADTAP};
    int n = 0, oldest = -1;
    for (int s = 0; s < SLOTS; s++) {
        if (!t->c[s].active)
            continue;
        n++;
        if (oldest < 0 || t->c[s].seq < t->c[oldest].seq)
            oldest = s;
    }
    int tool = tools[n < 4 ? n : 4];
    int rc = 0;
    if (tool != t->tool) {
        if (t->tool)
            rc |= emit(t, EV_KEY, t->tool, 0);
        if (tool)
            rc |= emit(t, EV_KEY, tool, 1);
        t->tool = tool;
    }
    if ((n > 0) != t->touching) {
        t->touching = n > 0;
        rc |= emit(t, EV_KEY, BTN_TOUCH, t->touching);
    }
    if (oldest >= 0) {
        rc |= emit(t, EV_ABS, ABS_X, t->c[oldest].x);
        rc |= emit(t, EV_ABS, ABS_Y, t->c[oldest].y);
    }
    rc |= emit(t, EV_SYN, SYN_REPORT, 0);
    if (rc) {
        snprintf(err, errlen, "write to uinput failed");
        return -1;
    }
    return 0;
}

/* the lowest free slots: fills slots[0..n-1] */
static int free_slots(struct touch *t, int n, int *slots, char *err, size_t errlen)
{
    int k = 0;
    for (int s = 0; s < SLOTS && k < n; s++)
        if (!t->c[s].active)
            slots[k++] = s;
    if (k < n) {
        snprintf(err, errlen, "needs %d free slots", n);
        return -1;
    }
    return 0;
}

/* lift the given slots (those still down) in one frame: a gesture's cleanup */
static void release(struct touch *t, const int *slots, int n)
{
    char ignored[64];
    int any = 0;
    for (int i = 0; i < n; i++) {
        if (t->c[slots[i]].active) {
            touch_up(t, slots[i], ignored, sizeof ignored);
            any = 1;
        }
    }
    if (any)
        touch_frame(t, ignored, sizeof ignored);
}

static int tap(struct touch *t, int x, int y, int hold_ms, char *err, size_t errlen)
{
    int s = -1;
    if (free_slots(t, 1, &s, err, errlen))
        return -1;
    if (touch_down(t, s, x, y, err, errlen) || touch_frame(t, err, errlen))
        goto fail;
    sleep_ms(hold_ms);
    if (touch_up(t, s, err, errlen) || touch_frame(t, err, errlen))
        goto fail;
    return 0;
fail:
    release(t, &s, 1);
    return -1;
}

/* the path of a gesture: its centre moves from x0,y0 to x1,y1; one finger is
 * at the centre, two are at centre -+ r, three at centre - r, centre and
 * centre + r (in a horizontal row), r from r0 to r1 */
struct path {
    int fingers;        /* 1..MAX_FINGERS */
    int x0, y0, x1, y1; /* centre */
    int r0, r1;         /* two fingers: half their distance; three: the distance
                           between neighbours */
};

static void path_at(const struct path *p, int i, int n, int *x, int *y)
{
    int cx = lerp(p->x0, p->x1, i, n), cy = lerp(p->y0, p->y1, i, n);
    int r = lerp(p->r0, p->r1, i, n);
    for (int f = 0; f < p->fingers; f++)
        y[f] = cy;
    if (p->fingers == 1) {
        x[0] = cx;
    } else if (p->fingers == 2) {
        x[0] = cx - r;
        x[1] = cx + r;
    } else {
        x[0] = cx - r;
        x[1] = cx;
        x[2] = cx + r;
    }
}

/* down at step 0, then a frame per step every interval, up after the last one */
static int gesture(struct touch *t, const struct path *p, int steps, char *err, size_t errlen)
{
    int slots[MAX_FINGERS], x[MAX_FINGERS], y[MAX_FINGERS];
    if (steps < 1) {
        snprintf(err, errlen, "STEPS must be >= 1");
        return -1;
    }
    if (free_slots(t, p->fingers, slots, err, errlen))
        return -1;
    struct timespec start;
    clock_gettime(CLOCK_MONOTONIC, &start);
    t->last_frame = start;
    path_at(p, 0, steps, x, y);
    for (int f = 0; f < p->fingers; f++)
        if (touch_down(t, slots[f], x[f], y[f], err, errlen))
            goto fail;
    if (touch_frame(t, err, errlen))
        goto fail;
    for (int i = 1; i <= steps && !stop; i++) {
        pace(t, &start, i);
        path_at(p, i, steps, x, y);
        for (int f = 0; f < p->fingers; f++)
            if (touch_move(t, slots[f], x[f], y[f], err, errlen))
                goto fail;
        if (touch_frame(t, err, errlen))
            goto fail;
    }
    pace(t, &start, steps + 1);
    for (int f = 0; f < p->fingers; f++)
        if (touch_up(t, slots[f], err, errlen))
            goto fail;
    if (touch_frame(t, err, errlen))
        goto fail;
    return 0;
fail:
    release(t, slots, p->fingers);
    return -1;
}

/* parse exactly n integers after the command word; 0 on success */
static int ints(const char *args, int n, int *v)
{
    const char *s = args;
    for (int i = 0; i < n; i++) {
        char *end;
        errno = 0;
        long l = strtol(s, &end, 10);
        if (end == s || errno || l < INT_MIN / 4 || l > INT_MAX / 4)
            return -1;
        v[i] = (int)l;
        s = end;
    }
    while (*s == ' ' || *s == '\t')
        s++;
    return *s ? -1 : 0;
}

/* a random number from the command's seed (xorshift32; the seed is never 0) */
static unsigned next_random(unsigned *state)
{
    unsigned x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *state = x;
}

/* a value an axis of size `size` may be sent: mostly in range, often not */
static int wild_value(unsigned *rs, int size)
{
    switch (next_random(rs) % 8) {
    case 0:
        return INT_MIN;
    case 1:
        return INT_MAX;
    case 2:
        return -1;
    case 3:
        return size + (int)(next_random(rs) % 1000);
    case 4:
        return -(int)(next_random(rs) % 100000);
    default:
        return (int)(next_random(rs) % (unsigned)size);
    }
}

/* garbage N SEED (see the top): the events, then a clean lift of every slot */
static int garbage(struct touch *t, int n, int seed, char *err, size_t errlen)
{
    static const int keys[] = {BTN_TOUCH, BTN_TOOL_FINGER, BTN_TOOL_DOUBLETAP, BTN_TOOL_TRIPLETAP,
                               BTN_TOOL_QUADTAP, BTN_LEFT};
    unsigned rs = (unsigned)seed * 2654435761u + 1u;
    if (rs == 0)
        rs = 1;
    int rc = 0;
    for (int i = 0; i < n && !rc && !stop; i++) {
        unsigned pick = next_random(&rs) % 100;
        if (pick < 15) {
            rc = emit(t, EV_SYN, SYN_REPORT, 0);
        } else if (pick < 18) {
            rc = emit(t, EV_SYN, SYN_DROPPED, 0);
        } else if (pick < 20) {
            rc = emit(t, EV_SYN, SYN_MT_REPORT, 0);
        } else if (pick < 35) {
            int key = keys[next_random(&rs) % (sizeof keys / sizeof keys[0])];
            rc = emit(t, EV_KEY, key, (int)(next_random(&rs) % 4) - 1); /* -1..2: 2 is autorepeat */
        } else if (pick < 45) {
            rc = emit(t, EV_ABS, ABS_MT_SLOT, (int)(next_random(&rs) % (SLOTS + 2)) - 1);
        } else if (pick < 55) {
            int id = next_random(&rs) % 3 == 0 ? -1 : (int)(next_random(&rs) % 8); /* ids reused */
            rc = emit(t, EV_ABS, ABS_MT_TRACKING_ID, id);
        } else {
            static const int axes[] = {ABS_X, ABS_Y, ABS_MT_POSITION_X, ABS_MT_POSITION_Y};
            int axis = axes[next_random(&rs) % 4];
            int size = axis == ABS_X || axis == ABS_MT_POSITION_X ? t->w : t->h;
            rc = emit(t, EV_ABS, axis, wild_value(&rs, size));
        }
        if (next_random(&rs) % 64 == 0)
            sleep_ms(next_random(&rs) % 20); /* else a burst */
    }
    /* every slot lifted, no key down: the device is clean for the next command */
    for (int s = 0; s < SLOTS; s++) {
        rc |= emit(t, EV_ABS, ABS_MT_SLOT, s);
        rc |= emit(t, EV_ABS, ABS_MT_TRACKING_ID, -1);
        t->c[s].active = 0;
    }
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
        rc |= emit(t, EV_KEY, keys[k], 0);
    rc |= emit(t, EV_SYN, SYN_REPORT, 0);
    t->tool = 0;
    t->touching = 0;
    if (rc) {
        snprintf(err, errlen, "write to uinput failed");
        return -1;
    }
    return 0;
}

/* run one command; 1 for quit, 0 done, -1 failed (err says why) */
static int command(struct touch *t, char *line, char *err, size_t errlen)
{
    char word[16];
    int used = 0, v[5];
    if (sscanf(line, "%15s%n", word, &used) != 1)
        return 0;
    const char *args = line + used;
#define ARGS(n)                                                                  \
    do {                                                                         \
        if (ints(args, (n), v)) {                                                \
            snprintf(err, errlen, "%s takes %d integer argument%s", word, (n),   \
                     (n) == 1 ? "" : "s");                                       \
            return -1;                                                           \
        }                                                                        \
    } while (0)
    if (!strcmp(word, "down")) {
        ARGS(3);
        return touch_down(t, v[0], v[1], v[2], err, errlen);
    }
    if (!strcmp(word, "move")) {
        ARGS(3);
        return touch_move(t, v[0], v[1], v[2], err, errlen);
    }
    if (!strcmp(word, "up")) {
        ARGS(1);
        return touch_up(t, v[0], err, errlen);
    }
    if (!strcmp(word, "frame")) {
        ARGS(0);
        return touch_frame(t, err, errlen);
    }
    if (!strcmp(word, "tap")) {
        if (ints(args, 2, v) == 0) {
            v[2] = TAP_MS;
        } else if (ints(args, 3, v)) {
            snprintf(err, errlen, "tap takes X Y [MS]");
            return -1;
        }
        if (v[2] < 0) {
            snprintf(err, errlen, "negative hold time");
            return -1;
        }
        return tap(t, v[0], v[1], v[2], err, errlen);
    }
    if (!strcmp(word, "doubletap")) {
        ARGS(2);
        if (tap(t, v[0], v[1], TAP_MS, err, errlen))
            return -1;
        sleep_ms(DOUBLETAP_MS - TAP_MS);
        return tap(t, v[0], v[1], TAP_MS, err, errlen);
    }
    if (!strcmp(word, "drag")) {
        ARGS(5);
        struct path p = {1, v[0], v[1], v[2], v[3], 0, 0};
        return gesture(t, &p, v[4], err, errlen);
    }
    if (!strcmp(word, "pinch")) {
        ARGS(5);
        struct path p = {2, v[0], v[1], v[0], v[1], v[2], v[3]};
        return gesture(t, &p, v[4], err, errlen);
    }
    if (!strcmp(word, "pan2")) {
        ARGS(5);
        struct path p = {2, v[0], v[1], v[2], v[3], t->gap / 2, t->gap / 2};
        return gesture(t, &p, v[4], err, errlen);
    }
    if (!strcmp(word, "swipe3")) {
        ARGS(5);
        struct path p = {3, v[0], v[1], v[2], v[3], t->gap, t->gap};
        return gesture(t, &p, v[4], err, errlen);
    }
    if (!strcmp(word, "garbage")) {
        ARGS(2);
        if (v[0] < 0) {
            snprintf(err, errlen, "negative event count");
            return -1;
        }
        return garbage(t, v[0], v[1], err, errlen);
    }
    if (!strcmp(word, "sleep")) {
        ARGS(1);
        if (v[0] < 0) {
            snprintf(err, errlen, "negative sleep");
            return -1;
        }
        sleep_ms(v[0]);
        return 0;
    }
    if (!strcmp(word, "quit")) {
        ARGS(0);
        return 1;
    }
#undef ARGS
    snprintf(err, errlen, "unknown command '%s'", word);
    return -1;
}

static int ioctl_int(int fd, unsigned long req, int arg, const char *what)
{
    if (ioctl(fd, req, arg) < 0) {
        fprintf(stderr, "uinput_touch: %s: %s\n", what, strerror(errno));
        return -1;
    }
    return 0;
}

static int abs_axis(int fd, int code, int max, int res)
{
    struct uinput_abs_setup a;
    memset(&a, 0, sizeof a);
    a.code = (unsigned short)code;
    a.absinfo.minimum = 0;
    a.absinfo.maximum = max;
    a.absinfo.resolution = res;
    if (ioctl(fd, UI_ABS_SETUP, &a) < 0) {
        fprintf(stderr, "uinput_touch: UI_ABS_SETUP %d: %s\n", code, strerror(errno));
        return -1;
    }
    return 0;
}

static int create_device(struct touch *t, const char *name, int res)
{
    t->fd = open("/dev/uinput", O_WRONLY | O_CLOEXEC);
    if (t->fd < 0) {
        fprintf(stderr, "uinput_touch: /dev/uinput: %s\n", strerror(errno));
        return -1;
    }
    /* BTN_LEFT last: only the touchpad has it */
    static const int keys[] = {BTN_TOUCH,          BTN_TOOL_FINGER,  BTN_TOOL_DOUBLETAP,
                               BTN_TOOL_TRIPLETAP, BTN_TOOL_QUADTAP, BTN_LEFT};
    size_t nkeys = sizeof keys / sizeof keys[0] - (t->pad ? 0 : 1);
    if (ioctl_int(t->fd, UI_SET_EVBIT, EV_SYN, "UI_SET_EVBIT") ||
        ioctl_int(t->fd, UI_SET_EVBIT, EV_KEY, "UI_SET_EVBIT") ||
        ioctl_int(t->fd, UI_SET_EVBIT, EV_ABS, "UI_SET_EVBIT"))
        return -1;
    /* a touchscreen is a direct device; a touchpad is an indirect pointer,
     * and a clickpad (BTN_LEFT under the whole surface, no BTN_RIGHT): with
     * BTN_LEFT only and no INPUT_PROP_BUTTONPAD libinput logs a kernel bug
     * ("missing right button, assuming it is a clickpad") */
    if (t->pad ? ioctl_int(t->fd, UI_SET_PROPBIT, INPUT_PROP_POINTER, "UI_SET_PROPBIT") ||
                     ioctl_int(t->fd, UI_SET_PROPBIT, INPUT_PROP_BUTTONPAD, "UI_SET_PROPBIT")
               : ioctl_int(t->fd, UI_SET_PROPBIT, INPUT_PROP_DIRECT, "UI_SET_PROPBIT"))
        return -1;
    for (size_t i = 0; i < nkeys; i++)
        if (ioctl_int(t->fd, UI_SET_KEYBIT, keys[i], "UI_SET_KEYBIT"))
            return -1;
    static const int axes[] = {ABS_X, ABS_Y, ABS_MT_SLOT, ABS_MT_TRACKING_ID, ABS_MT_POSITION_X,
                               ABS_MT_POSITION_Y};
    for (size_t i = 0; i < sizeof axes / sizeof axes[0]; i++)
        if (ioctl_int(t->fd, UI_SET_ABSBIT, axes[i], "UI_SET_ABSBIT"))
            return -1;
    if (abs_axis(t->fd, ABS_X, t->w - 1, res) || abs_axis(t->fd, ABS_Y, t->h - 1, res) ||
        abs_axis(t->fd, ABS_MT_POSITION_X, t->w - 1, res) ||
        abs_axis(t->fd, ABS_MT_POSITION_Y, t->h - 1, res) ||
        abs_axis(t->fd, ABS_MT_SLOT, SLOTS - 1, 0) || abs_axis(t->fd, ABS_MT_TRACKING_ID, MAX_ID, 0))
        return -1;
    struct uinput_setup setup;
    memset(&setup, 0, sizeof setup);
    setup.id.bustype = BUS_VIRTUAL;
    setup.id.vendor = 0x7e55; /* arbitrary: "tess" */
    setup.id.product = t->pad ? 0x0002 : 0x0001;
    setup.id.version = 1;
    snprintf(setup.name, sizeof setup.name, "%s", name);
    if (ioctl(t->fd, UI_DEV_SETUP, &setup) < 0) {
        fprintf(stderr, "uinput_touch: UI_DEV_SETUP: %s\n", strerror(errno));
        return -1;
    }
    if (ioctl(t->fd, UI_DEV_CREATE) < 0) {
        fprintf(stderr, "uinput_touch: UI_DEV_CREATE: %s\n", strerror(errno));
        return -1;
    }
    return 0;
}

/* "/dev/input/eventN" of the created device into node; its "MAJ:MIN" into devnum */
static int event_node(struct touch *t, char *node, size_t nodelen, char *devnum, size_t devlen)
{
    char sys[64], dir[160];
    memset(sys, 0, sizeof sys);
    if (ioctl(t->fd, UI_GET_SYSNAME(sizeof sys - 1), sys) < 0) {
        fprintf(stderr, "uinput_touch: UI_GET_SYSNAME: %s\n", strerror(errno));
        return -1;
    }
    snprintf(dir, sizeof dir, "/sys/devices/virtual/input/%s", sys);
    for (int tries = 0; tries < 200; tries++) { /* the event child appears at once, normally */
        DIR *d = opendir(dir);
        struct dirent *e;
        while (d && (e = readdir(d))) {
            if (strncmp(e->d_name, "event", 5) != 0)
                continue;
            char path[480];
            snprintf(node, nodelen, "/dev/input/%s", e->d_name);
            snprintf(path, sizeof path, "%s/%s/dev", dir, e->d_name);
            FILE *f = fopen(path, "r");
            devnum[0] = 0;
            if (f) {
                if (!fgets(devnum, (int)devlen, f))
                    devnum[0] = 0;
                devnum[strcspn(devnum, "\n")] = 0;
                fclose(f);
            }
            closedir(d);
            return 0;
        }
        if (d)
            closedir(d);
        sleep_ms(10);
    }
    fprintf(stderr, "uinput_touch: no event node under %s\n", dir);
    return -1;
}

/* until the node exists and, if udevd runs, udev's database has the device
 * (udevd writes it before it announces the device to libinput & co.) */
static void wait_for_udev(const char *node, const char *devnum)
{
    char db[64];
    struct stat st;
    int udev = devnum[0] && stat("/run/udev/control", &st) == 0;
    snprintf(db, sizeof db, "/run/udev/data/c%s", devnum);
    for (int tries = 0; tries < 500 && !stop; tries++) {
        if (stat(node, &st) == 0 && (!udev || stat(db, &st) == 0))
            return;
        sleep_ms(10);
    }
    fprintf(stderr, "uinput_touch: warning: %s not %s after 5 s\n", node,
            stat(node, &st) == 0 ? "in udev's database" : "there");
}

static int parse_size(const char *s, int *w, int *h)
{
    char x;
    return sscanf(s, "%d%c%d", w, &x, h) == 3 && x == 'x' && *w >= 2 && *h >= 2 && *w <= 1 << 20 &&
                   *h <= 1 << 20
               ? 0
               : -1;
}

static void usage(void)
{
    fprintf(stderr, "usage: uinput_touch [-p] [-n NAME] [-s WxH] [-R RES] [-i MS] [-g GAP] [-f FIFO]\n"
                    "  -p: a touchpad (clickpad, default 4000x2400 at 40 units/mm) instead of a\n"
                    "      touchscreen (default 640x480 at 10 units/mm)\n"
                    "commands, one per line: down SLOT X Y | move SLOT X Y | up SLOT | frame |\n"
                    "  tap X Y [MS] | doubletap X Y | drag X0 Y0 X1 Y1 STEPS |\n"
                    "  pinch CX CY R0 R1 STEPS | pan2 X0 Y0 X1 Y1 STEPS |\n"
                    "  swipe3 X0 Y0 X1 Y1 STEPS | sleep MS | quit\n");
    exit(2);
}

int main(int argc, char **argv)
{
    const char *name = NULL, *fifo = NULL, *size = NULL;
    struct touch t;
    memset(&t, 0, sizeof t);
    t.interval_ms = 10;
    t.gap = -1;
    int res = -1, opt;
    while ((opt = getopt(argc, argv, "pn:s:R:i:g:f:h")) != -1) {
        switch (opt) {
        case 'p': t.pad = 1; break;
        case 'n': name = optarg; break;
        case 's': size = optarg; break;
        case 'R':
            res = atoi(optarg);
            if (res < 0)
                usage();
            break;
        case 'i': t.interval_ms = atoi(optarg); break;
        case 'g':
            t.gap = atoi(optarg);
            if (t.gap < 0)
                usage();
            break;
        case 'f': fifo = optarg; break;
        default: usage();
        }
    }
    if (!name)
        name = t.pad ? "tessera-test-touchpad" : "tessera-test-touch";
    if (parse_size(size ? size : t.pad ? "4000x2400" : "640x480", &t.w, &t.h))
        usage();
    if (res < 0)
        res = t.pad ? 40 : 10;
    if (t.gap < 0)
        t.gap = t.pad ? PAD_GAP_MM * (res ? res : 1) : GAP;
    if (optind != argc || t.interval_ms < 0 || strlen(name) >= UINPUT_MAX_NAME_SIZE)
        usage();

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: a blocked read returns EINTR */
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    FILE *in = stdin;
    if (fifo) {
        if (mkfifo(fifo, 0666) < 0 && errno != EEXIST) {
            fprintf(stderr, "uinput_touch: mkfifo %s: %s\n", fifo, strerror(errno));
            return 1;
        }
        /* read-write: never an end of file when a writer closes */
        int fd = open(fifo, O_RDWR | O_CLOEXEC);
        if (fd < 0 || !(in = fdopen(fd, "r"))) {
            fprintf(stderr, "uinput_touch: %s: %s\n", fifo, strerror(errno));
            return 1;
        }
    }

    char node[300], devnum[32];
    if (create_device(&t, name, res) || event_node(&t, node, sizeof node, devnum, sizeof devnum))
        return 1;
    wait_for_udev(node, devnum);
    printf("uinput_touch: ready %s\n", node);
    fflush(stdout);

    char *line = NULL, err[128];
    size_t cap = 0;
    long n = 0;
    int rc = 0;
    while (!stop) {
        errno = 0;
        ssize_t len = getline(&line, &cap, in);
        if (len < 0) {
            if (errno == EINTR && !stop) {
                clearerr(in);
                continue;
            }
            break;
        }
        line[strcspn(line, "\r\n")] = 0;
        const char *p = line + strspn(line, " \t");
        if (!*p || *p == '#')
            continue;
        n++;
        err[0] = 0;
        rc = command(&t, line, err, sizeof err);
        if (rc < 0)
            printf("err %ld: %s\n", n, err);
        else
            printf("ok %ld\n", n);
        fflush(stdout);
        if (rc > 0)
            break;
    }
    free(line);

    /* lift whatever is still down, so that nobody sees a stuck touch */
    int all[SLOTS];
    for (int s = 0; s < SLOTS; s++)
        all[s] = s;
    release(&t, all, SLOTS);
    ioctl(t.fd, UI_DEV_DESTROY);
    close(t.fd);
    return 0;
}
