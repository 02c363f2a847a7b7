/* input_probe: what libinput (udev backend, seat0) sees, one line per device
 * and per event (guest-side debugging tool of the VM tests).
 *
 * usage: input_probe [-t SECS] [-s WxH] [-S SEAT] [-v]
 *   -t  run that many seconds, then exit 0 (default 10; 0: until SIGTERM/SIGINT)
 *   -s  size the absolute coordinates are transformed to (default 640x480):
 *       libinput's *_get_{x,y}_transformed(W, H)
 *   -S  seat (default seat0)
 *   -v  libinput's debug log too (default: its info and error messages)
 * Opens the devices itself with open(2) (run it as root: no logind, no seatd).
 *
 * Output (stdout, flushed at every line; times are the kernel's event time,
 * CLOCK_MONOTONIC, in seconds, and lag is how much later this program got the
 * event from libinput):
 *   probe: seat0, transform 640x480
 *   added event3 "QEMU Virtio Keyboard" caps=keyboard touchscreen=no
 *         udev=ID_INPUT_KEY,ID_INPUT_KEYBOARD path=pci-0000:00:03.0 [size=WxHmm]
 *   probe: ready (4 devices)         after the devices present at start-up
 *   event3 KEYBOARD_KEY key=30 pressed seat_count=1 t=12.345678 lag=0.8ms
 *   event4 POINTER_MOTION dx=.. dy=.. udx=20.00 udy=10.00 t=.. lag=..
 *   event5 POINTER_MOTION_ABSOLUTE x=320.00 y=240.00 ax=.. ay=.. t=.. lag=..
 *   event5 POINTER_BUTTON button=272 pressed seat_count=1 t=.. lag=..
 *   event5 POINTER_AXIS source=wheel v=15.00 h=0.00 t=..
 *   event5 POINTER_SCROLL_WHEEL v=15.00 h=0.00 v120=120 h120=0 t=..
 *   event6 TOUCH_DOWN slot=0 seat_slot=0 x=100.00 y=200.00 t=.. lag=..
 *   event6 TOUCH_MOTION slot=0 seat_slot=0 x=.. y=.. t=..
 *   event6 TOUCH_UP slot=0 seat_slot=0 t=..     (also TOUCH_CANCEL)
 *   event6 TOUCH_FRAME t=..
 *   event7 TABLET_TOOL_AXIS tool=pen x=.. y=.. tip=up t=..  (PROXIMITY, TIP, BUTTON)
 *   event8 GESTURE_PINCH_UPDATE fingers=2 dx=.. dy=.. udx=.. udy=.. scale=1.234 angle=.. t=..
 *   event8 GESTURE_PINCH_END fingers=2 dx=0.00 dy=0.00 udx=.. udy=.. scale=.. angle=..
 *         cancelled=0 t=..       (SWIPE_* alike, without scale and angle)
 *   event8 GESTURE_HOLD_BEGIN fingers=1 t=..    (GESTURE_HOLD_END fingers=1 cancelled=0)
 *   event8 POINTER_SCROLL_FINGER v=2.50 h=0.00 t=..   (two-finger scrolling; the
 *         end of a scroll is one event with v=0.00 or h=0.00)
 *   removed event6 "tessera-test-touch"
 *   log: <libinput's own messages>
 *   probe: end after 10.0 s, 42 events
 * caps: keyboard pointer touch tablet-tool tablet-pad gesture switch (those
 * the device has, comma separated); touchscreen: udev's ID_INPUT_TOUCHSCREEN;
 * udev: the ID_INPUT_* properties set to 1; path: ID_PATH; uniq: the kernel's
 * uniq of the device (only if set; qemu: virtio-*-pci,serial=...); size: as
 * libinput computes it from the resolution (only if the device has one);
 * tp (touchpads only): libinput's configuration, e.g.
 * tp=tap:off/3fg,scroll:2fg,click:areas,dwt:on,natural:off.
 *
 * build: gcc -std=c11 -O2 -Wall -Wextra -Werror -o input_probe input_probe.c \
 *            $(pkg-config --cflags --libs libinput libudev)
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <libinput.h>
#include <libudev.h>

static volatile sig_atomic_t stop;
static int width = 640, height = 480;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static int open_restricted(const char *path, int flags, void *data)
{
    (void)data;
    int fd = open(path, flags | O_CLOEXEC);
    return fd < 0 ? -errno : fd;
}

static void close_restricted(int fd, void *data)
{
    (void)data;
    close(fd);
}

static const struct libinput_interface iface = {
    .open_restricted = open_restricted,
    .close_restricted = close_restricted,
};

static void log_handler(struct libinput *li, enum libinput_log_priority prio, const char *fmt,
                        va_list args)
{
    (void)li;
    (void)prio;
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, args);
    msg[strcspn(msg, "\n")] = 0;
    printf("log: %s\n", msg);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

static const char *type_name(enum libinput_event_type type)
{
    switch (type) {
    case LIBINPUT_EVENT_NONE: return "NONE";
    case LIBINPUT_EVENT_DEVICE_ADDED: return "DEVICE_ADDED";
    case LIBINPUT_EVENT_DEVICE_REMOVED: return "DEVICE_REMOVED";
    case LIBINPUT_EVENT_KEYBOARD_KEY: return "KEYBOARD_KEY";
    case LIBINPUT_EVENT_POINTER_MOTION: return "POINTER_MOTION";
    case LIBINPUT_EVENT_POINTER_MOTION_ABSOLUTE: return "POINTER_MOTION_ABSOLUTE";
    case LIBINPUT_EVENT_POINTER_BUTTON: return "POINTER_BUTTON";
    case LIBINPUT_EVENT_POINTER_AXIS: return "POINTER_AXIS";
    case LIBINPUT_EVENT_POINTER_SCROLL_WHEEL: return "POINTER_SCROLL_WHEEL";
    case LIBINPUT_EVENT_POINTER_SCROLL_FINGER: return "POINTER_SCROLL_FINGER";
    case LIBINPUT_EVENT_POINTER_SCROLL_CONTINUOUS: return "POINTER_SCROLL_CONTINUOUS";
    case LIBINPUT_EVENT_TOUCH_DOWN: return "TOUCH_DOWN";
    case LIBINPUT_EVENT_TOUCH_UP: return "TOUCH_UP";
    case LIBINPUT_EVENT_TOUCH_MOTION: return "TOUCH_MOTION";
    case LIBINPUT_EVENT_TOUCH_CANCEL: return "TOUCH_CANCEL";
    case LIBINPUT_EVENT_TOUCH_FRAME: return "TOUCH_FRAME";
    case LIBINPUT_EVENT_TABLET_TOOL_AXIS: return "TABLET_TOOL_AXIS";
    case LIBINPUT_EVENT_TABLET_TOOL_PROXIMITY: return "TABLET_TOOL_PROXIMITY";
    case LIBINPUT_EVENT_TABLET_TOOL_TIP: return "TABLET_TOOL_TIP";
    case LIBINPUT_EVENT_TABLET_TOOL_BUTTON: return "TABLET_TOOL_BUTTON";
    case LIBINPUT_EVENT_TABLET_PAD_BUTTON: return "TABLET_PAD_BUTTON";
    case LIBINPUT_EVENT_TABLET_PAD_RING: return "TABLET_PAD_RING";
    case LIBINPUT_EVENT_TABLET_PAD_STRIP: return "TABLET_PAD_STRIP";
    case LIBINPUT_EVENT_TABLET_PAD_KEY: return "TABLET_PAD_KEY";
    case LIBINPUT_EVENT_GESTURE_SWIPE_BEGIN: return "GESTURE_SWIPE_BEGIN";
    case LIBINPUT_EVENT_GESTURE_SWIPE_UPDATE: return "GESTURE_SWIPE_UPDATE";
    case LIBINPUT_EVENT_GESTURE_SWIPE_END: return "GESTURE_SWIPE_END";
    case LIBINPUT_EVENT_GESTURE_PINCH_BEGIN: return "GESTURE_PINCH_BEGIN";
    case LIBINPUT_EVENT_GESTURE_PINCH_UPDATE: return "GESTURE_PINCH_UPDATE";
    case LIBINPUT_EVENT_GESTURE_PINCH_END: return "GESTURE_PINCH_END";
    case LIBINPUT_EVENT_GESTURE_HOLD_BEGIN: return "GESTURE_HOLD_BEGIN";
    case LIBINPUT_EVENT_GESTURE_HOLD_END: return "GESTURE_HOLD_END";
    case LIBINPUT_EVENT_SWITCH_TOGGLE: return "SWITCH_TOGGLE";
    }
    return "UNKNOWN";
}

static void print_device(const char *what, struct libinput_device *dev)
{
    static const struct {
        enum libinput_device_capability cap;
        const char *name;
    } caps[] = {
        {LIBINPUT_DEVICE_CAP_KEYBOARD, "keyboard"},       {LIBINPUT_DEVICE_CAP_POINTER, "pointer"},
        {LIBINPUT_DEVICE_CAP_TOUCH, "touch"},             {LIBINPUT_DEVICE_CAP_TABLET_TOOL, "tablet-tool"},
        {LIBINPUT_DEVICE_CAP_TABLET_PAD, "tablet-pad"},   {LIBINPUT_DEVICE_CAP_GESTURE, "gesture"},
        {LIBINPUT_DEVICE_CAP_SWITCH, "switch"},
    };
    printf("%s %s \"%s\"", what, libinput_device_get_sysname(dev), libinput_device_get_name(dev));
    if (strcmp(what, "added") != 0) {
        printf("\n");
        return;
    }
    const char *sep = " caps=";
    for (size_t i = 0; i < sizeof caps / sizeof caps[0]; i++) {
        if (libinput_device_has_capability(dev, caps[i].cap)) {
            printf("%s%s", sep, caps[i].name);
            sep = ",";
        }
    }
    if (*sep == ' ')
        printf(" caps=none");
    struct udev_device *ud = libinput_device_get_udev_device(dev);
    const char *ts = ud ? udev_device_get_property_value(ud, "ID_INPUT_TOUCHSCREEN") : NULL;
    printf(" touchscreen=%s", ts && !strcmp(ts, "1") ? "yes" : "no");
    sep = " udev=";
    for (struct udev_list_entry *e = ud ? udev_device_get_properties_list_entry(ud) : NULL; e;
         e = udev_list_entry_get_next(e)) {
        const char *name = udev_list_entry_get_name(e), *value = udev_list_entry_get_value(e);
        if (!strncmp(name, "ID_INPUT", 8) && value && !strcmp(value, "1")) {
            printf("%s%s", sep, name);
            sep = ",";
        }
    }
    const char *path = ud ? udev_device_get_property_value(ud, "ID_PATH") : NULL;
    printf(" path=%s", path ? path : "none");
    /* the kernel's uniq (qemu: -device virtio-tablet-pci,serial=...) is on the input parent */
    struct udev_device *in = ud ? udev_device_get_parent_with_subsystem_devtype(ud, "input", NULL) : NULL;
    const char *uniq = in ? udev_device_get_sysattr_value(in, "uniq") : NULL;
    if (uniq && *uniq && *uniq != '\n')
        printf(" uniq=%.*s", (int)strcspn(uniq, "\n"), uniq);
    double w, h;
    if (libinput_device_get_size(dev, &w, &h) == 0)
        printf(" size=%.1fx%.1fmm", w, h);
    /* touchpads (the only devices that can tap): libinput's default setup */
    int tap_fingers = libinput_device_config_tap_get_finger_count(dev);
    if (tap_fingers > 0) {
        enum libinput_config_scroll_method sm = libinput_device_config_scroll_get_method(dev);
        enum libinput_config_click_method cm = libinput_device_config_click_get_method(dev);
        printf(" tp=tap:%s/%dfg,scroll:%s,click:%s,dwt:%s,natural:%s",
               libinput_device_config_tap_get_enabled(dev) ? "on" : "off", tap_fingers,
               sm == LIBINPUT_CONFIG_SCROLL_2FG           ? "2fg"
               : sm == LIBINPUT_CONFIG_SCROLL_EDGE        ? "edge"
               : sm == LIBINPUT_CONFIG_SCROLL_ON_BUTTON_DOWN ? "button"
                                                          : "none",
               cm == LIBINPUT_CONFIG_CLICK_METHOD_BUTTON_AREAS  ? "areas"
               : cm == LIBINPUT_CONFIG_CLICK_METHOD_CLICKFINGER ? "clickfinger"
                                                                : "none",
               libinput_device_config_dwt_get_enabled(dev) ? "on" : "off",
               libinput_device_config_scroll_get_natural_scroll_enabled(dev) ? "on" : "off");
    }
    printf("\n");
    if (ud)
        udev_device_unref(ud);
}

static const char *pressed(int state)
{
    return state ? "pressed" : "released";
}

static const char *tool_name(struct libinput_tablet_tool *tool)
{
    switch (libinput_tablet_tool_get_type(tool)) {
    case LIBINPUT_TABLET_TOOL_TYPE_PEN: return "pen";
    case LIBINPUT_TABLET_TOOL_TYPE_ERASER: return "eraser";
    case LIBINPUT_TABLET_TOOL_TYPE_BRUSH: return "brush";
    case LIBINPUT_TABLET_TOOL_TYPE_PENCIL: return "pencil";
    case LIBINPUT_TABLET_TOOL_TYPE_AIRBRUSH: return "airbrush";
    case LIBINPUT_TABLET_TOOL_TYPE_MOUSE: return "mouse";
    case LIBINPUT_TABLET_TOOL_TYPE_LENS: return "lens";
    case LIBINPUT_TABLET_TOOL_TYPE_TOTEM: return "totem";
    }
    return "unknown";
}

/* the event's own fields; returns its time in microseconds (0 if it has none) */
static uint64_t print_fields(struct libinput_event *ev)
{
    enum libinput_event_type type = libinput_event_get_type(ev);
    switch (type) {
    case LIBINPUT_EVENT_KEYBOARD_KEY: {
        struct libinput_event_keyboard *k = libinput_event_get_keyboard_event(ev);
        printf(" key=%u %s seat_count=%u", libinput_event_keyboard_get_key(k),
               pressed(libinput_event_keyboard_get_key_state(k) == LIBINPUT_KEY_STATE_PRESSED),
               libinput_event_keyboard_get_seat_key_count(k));
        return libinput_event_keyboard_get_time_usec(k);
    }
    case LIBINPUT_EVENT_POINTER_MOTION:
    case LIBINPUT_EVENT_POINTER_MOTION_ABSOLUTE:
    case LIBINPUT_EVENT_POINTER_BUTTON:
    case LIBINPUT_EVENT_POINTER_AXIS:
    case LIBINPUT_EVENT_POINTER_SCROLL_WHEEL:
    case LIBINPUT_EVENT_POINTER_SCROLL_FINGER:
    case LIBINPUT_EVENT_POINTER_SCROLL_CONTINUOUS: {
        struct libinput_event_pointer *p = libinput_event_get_pointer_event(ev);
        if (type == LIBINPUT_EVENT_POINTER_MOTION) {
            printf(" dx=%.2f dy=%.2f udx=%.2f udy=%.2f", libinput_event_pointer_get_dx(p),
                   libinput_event_pointer_get_dy(p), libinput_event_pointer_get_dx_unaccelerated(p),
                   libinput_event_pointer_get_dy_unaccelerated(p));
        } else if (type == LIBINPUT_EVENT_POINTER_MOTION_ABSOLUTE) {
            printf(" x=%.2f y=%.2f ax=%.3f ay=%.3f",
                   libinput_event_pointer_get_absolute_x_transformed(p, (uint32_t)width),
                   libinput_event_pointer_get_absolute_y_transformed(p, (uint32_t)height),
                   libinput_event_pointer_get_absolute_x(p), libinput_event_pointer_get_absolute_y(p));
        } else if (type == LIBINPUT_EVENT_POINTER_BUTTON) {
            printf(" button=%u %s seat_count=%u", libinput_event_pointer_get_button(p),
                   pressed(libinput_event_pointer_get_button_state(p) ==
                           LIBINPUT_BUTTON_STATE_PRESSED),
                   libinput_event_pointer_get_seat_button_count(p));
        } else {
            const enum libinput_pointer_axis v = LIBINPUT_POINTER_AXIS_SCROLL_VERTICAL,
                                             h = LIBINPUT_POINTER_AXIS_SCROLL_HORIZONTAL;
            int hv = libinput_event_pointer_has_axis(p, v), hh = libinput_event_pointer_has_axis(p, h);
            if (type == LIBINPUT_EVENT_POINTER_AXIS) {
                enum libinput_pointer_axis_source src = libinput_event_pointer_get_axis_source(p);
                printf(" source=%s", src == LIBINPUT_POINTER_AXIS_SOURCE_WHEEL        ? "wheel"
                                     : src == LIBINPUT_POINTER_AXIS_SOURCE_FINGER     ? "finger"
                                     : src == LIBINPUT_POINTER_AXIS_SOURCE_CONTINUOUS ? "continuous"
                                                                                      : "other");
                printf(" v=%.2f h=%.2f", hv ? libinput_event_pointer_get_axis_value(p, v) : 0.0,
                       hh ? libinput_event_pointer_get_axis_value(p, h) : 0.0);
            } else {
                printf(" v=%.2f h=%.2f", hv ? libinput_event_pointer_get_scroll_value(p, v) : 0.0,
                       hh ? libinput_event_pointer_get_scroll_value(p, h) : 0.0);
                if (type == LIBINPUT_EVENT_POINTER_SCROLL_WHEEL)
                    printf(" v120=%.0f h120=%.0f",
                           hv ? libinput_event_pointer_get_scroll_value_v120(p, v) : 0.0,
                           hh ? libinput_event_pointer_get_scroll_value_v120(p, h) : 0.0);
            }
        }
        return libinput_event_pointer_get_time_usec(p);
    }
    case LIBINPUT_EVENT_TOUCH_DOWN:
    case LIBINPUT_EVENT_TOUCH_UP:
    case LIBINPUT_EVENT_TOUCH_MOTION:
    case LIBINPUT_EVENT_TOUCH_CANCEL:
    case LIBINPUT_EVENT_TOUCH_FRAME: {
        struct libinput_event_touch *t = libinput_event_get_touch_event(ev);
        if (type != LIBINPUT_EVENT_TOUCH_FRAME)
            printf(" slot=%d seat_slot=%d", libinput_event_touch_get_slot(t),
                   libinput_event_touch_get_seat_slot(t));
        if (type == LIBINPUT_EVENT_TOUCH_DOWN || type == LIBINPUT_EVENT_TOUCH_MOTION)
            printf(" x=%.2f y=%.2f", libinput_event_touch_get_x_transformed(t, (uint32_t)width),
                   libinput_event_touch_get_y_transformed(t, (uint32_t)height));
        return libinput_event_touch_get_time_usec(t);
    }
    case LIBINPUT_EVENT_TABLET_TOOL_AXIS:
    case LIBINPUT_EVENT_TABLET_TOOL_PROXIMITY:
    case LIBINPUT_EVENT_TABLET_TOOL_TIP:
    case LIBINPUT_EVENT_TABLET_TOOL_BUTTON: {
        struct libinput_event_tablet_tool *t = libinput_event_get_tablet_tool_event(ev);
        printf(" tool=%s x=%.2f y=%.2f", tool_name(libinput_event_tablet_tool_get_tool(t)),
               libinput_event_tablet_tool_get_x_transformed(t, (uint32_t)width),
               libinput_event_tablet_tool_get_y_transformed(t, (uint32_t)height));
        if (type == LIBINPUT_EVENT_TABLET_TOOL_PROXIMITY)
            printf(" proximity=%s", libinput_event_tablet_tool_get_proximity_state(t) ==
                                            LIBINPUT_TABLET_TOOL_PROXIMITY_STATE_IN
                                        ? "in"
                                        : "out");
        printf(" tip=%s", libinput_event_tablet_tool_get_tip_state(t) == LIBINPUT_TABLET_TOOL_TIP_DOWN
                              ? "down"
                              : "up");
        if (type == LIBINPUT_EVENT_TABLET_TOOL_BUTTON)
            printf(" button=%u %s", libinput_event_tablet_tool_get_button(t),
                   pressed(libinput_event_tablet_tool_get_button_state(t) ==
                           LIBINPUT_BUTTON_STATE_PRESSED));
        return libinput_event_tablet_tool_get_time_usec(t);
    }
    case LIBINPUT_EVENT_TABLET_PAD_BUTTON:
    case LIBINPUT_EVENT_TABLET_PAD_RING:
    case LIBINPUT_EVENT_TABLET_PAD_STRIP:
    case LIBINPUT_EVENT_TABLET_PAD_KEY: {
        struct libinput_event_tablet_pad *t = libinput_event_get_tablet_pad_event(ev);
        if (type == LIBINPUT_EVENT_TABLET_PAD_BUTTON)
            printf(" button=%u %s", libinput_event_tablet_pad_get_button_number(t),
                   pressed(libinput_event_tablet_pad_get_button_state(t) ==
                           LIBINPUT_BUTTON_STATE_PRESSED));
        return libinput_event_tablet_pad_get_time_usec(t);
    }
    case LIBINPUT_EVENT_GESTURE_SWIPE_BEGIN:
    case LIBINPUT_EVENT_GESTURE_SWIPE_UPDATE:
    case LIBINPUT_EVENT_GESTURE_SWIPE_END:
    case LIBINPUT_EVENT_GESTURE_PINCH_BEGIN:
    case LIBINPUT_EVENT_GESTURE_PINCH_UPDATE:
    case LIBINPUT_EVENT_GESTURE_PINCH_END:
    case LIBINPUT_EVENT_GESTURE_HOLD_BEGIN:
    case LIBINPUT_EVENT_GESTURE_HOLD_END: {
        struct libinput_event_gesture *g = libinput_event_get_gesture_event(ev);
        printf(" fingers=%d", libinput_event_gesture_get_finger_count(g));
        /* a hold has no motion: libinput logs a client bug for get_dx() on it */
        if (type != LIBINPUT_EVENT_GESTURE_HOLD_BEGIN && type != LIBINPUT_EVENT_GESTURE_HOLD_END)
            printf(" dx=%.2f dy=%.2f udx=%.2f udy=%.2f", libinput_event_gesture_get_dx(g),
                   libinput_event_gesture_get_dy(g), libinput_event_gesture_get_dx_unaccelerated(g),
                   libinput_event_gesture_get_dy_unaccelerated(g));
        if (type >= LIBINPUT_EVENT_GESTURE_PINCH_BEGIN && type <= LIBINPUT_EVENT_GESTURE_PINCH_END)
            printf(" scale=%.3f angle=%.2f", libinput_event_gesture_get_scale(g),
                   libinput_event_gesture_get_angle_delta(g));
        if (type == LIBINPUT_EVENT_GESTURE_SWIPE_END || type == LIBINPUT_EVENT_GESTURE_PINCH_END ||
            type == LIBINPUT_EVENT_GESTURE_HOLD_END)
            printf(" cancelled=%d", libinput_event_gesture_get_cancelled(g));
        return libinput_event_gesture_get_time_usec(g);
    }
    case LIBINPUT_EVENT_SWITCH_TOGGLE: {
        struct libinput_event_switch *s = libinput_event_get_switch_event(ev);
        printf(" switch=%d state=%d", (int)libinput_event_switch_get_switch(s),
               (int)libinput_event_switch_get_switch_state(s));
        return libinput_event_switch_get_time_usec(s);
    }
    case LIBINPUT_EVENT_NONE:
    case LIBINPUT_EVENT_DEVICE_ADDED:
    case LIBINPUT_EVENT_DEVICE_REMOVED:
        break;
    }
    return 0;
}

/* all queued events; returns how many input events (not device ones) there were */
static long drain(struct libinput *li, int *devices)
{
    long n = 0;
    struct libinput_event *ev;
    while ((ev = libinput_get_event(li))) {
        enum libinput_event_type type = libinput_event_get_type(ev);
        struct libinput_device *dev = libinput_event_get_device(ev);
        double got = now_s();
        if (type == LIBINPUT_EVENT_DEVICE_ADDED) {
            print_device("added", dev);
            (*devices)++;
        } else if (type == LIBINPUT_EVENT_DEVICE_REMOVED) {
            print_device("removed", dev);
            (*devices)--;
        } else {
            printf("%s %s", libinput_device_get_sysname(dev), type_name(type));
            uint64_t us = print_fields(ev);
            if (us)
                printf(" t=%.6f lag=%.1fms", us / 1e6, (got - us / 1e6) * 1e3);
            printf("\n");
            n++;
        }
        libinput_event_destroy(ev);
    }
    return n;
}

static void usage(void)
{
    fprintf(stderr, "usage: input_probe [-t SECS] [-s WxH] [-S SEAT] [-v]\n");
    exit(2);
}

int main(int argc, char **argv)
{
    double secs = 10;
    const char *seat = "seat0";
    int verbose = 0, opt;
    while ((opt = getopt(argc, argv, "t:s:S:vh")) != -1) {
        switch (opt) {
        case 't': secs = atof(optarg); break;
        case 's': {
            char x;
            if (sscanf(optarg, "%d%c%d", &width, &x, &height) != 3 || x != 'x' || width < 1 ||
                height < 1)
                usage();
            break;
        }
        case 'S': seat = optarg; break;
        case 'v': verbose = 1; break;
        default: usage();
        }
    }
    if (optind != argc || secs < 0)
        usage();
    setvbuf(stdout, NULL, _IOLBF, 0);

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);

    struct udev *udev = udev_new();
    if (!udev) {
        fprintf(stderr, "input_probe: udev_new failed\n");
        return 1;
    }
    struct libinput *li = libinput_udev_create_context(&iface, NULL, udev);
    if (!li) {
        fprintf(stderr, "input_probe: libinput_udev_create_context failed\n");
        return 1;
    }
    libinput_log_set_handler(li, log_handler);
    libinput_log_set_priority(li, verbose ? LIBINPUT_LOG_PRIORITY_DEBUG : LIBINPUT_LOG_PRIORITY_INFO);
    printf("probe: %s, transform %dx%d\n", seat, width, height);
    double start = now_s();
    if (libinput_udev_assign_seat(li, seat) != 0) {
        fprintf(stderr, "input_probe: libinput_udev_assign_seat(%s) failed\n", seat);
        return 1;
    }
    int devices = 0;
    long events = 0;
    libinput_dispatch(li);
    events += drain(li, &devices);
    printf("probe: ready (%d devices)\n", devices);

    struct pollfd pfd = {libinput_get_fd(li), POLLIN, 0};
    while (!stop) {
        int timeout = -1;
        if (secs > 0) {
            double left = start + secs - now_s();
            if (left <= 0)
                break;
            timeout = (int)(left * 1000) + 1;
        }
        int r = poll(&pfd, 1, timeout);
        if (r < 0 && errno != EINTR) {
            fprintf(stderr, "input_probe: poll: %s\n", strerror(errno));
            break;
        }
        if (libinput_dispatch(li) != 0)
            fprintf(stderr, "input_probe: libinput_dispatch failed\n");
        events += drain(li, &devices);
    }
    printf("probe: end after %.1f s, %ld events\n", now_s() - start, events);
    libinput_unref(li);
    udev_unref(udev);
    return 0;
}
