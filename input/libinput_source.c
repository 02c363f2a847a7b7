/* libinput_source.c - libinput devices as an input source (libinput_source.h). */
#define _XOPEN_SOURCE 700 /* realpath */
#include "libinput_source.h"

#include <errno.h>
#include <fcntl.h>
#include <libinput.h>
#include <libudev.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#include "engine/base/clock.h"
#include "engine/base/log.h"
#include "seat/session.h"

#define PATH_RETRY_S 1.0
#define SCROLL_FINGER_PX_PER_CLICK 15.0 /* touchpad two-finger scroll: pixels that make one wheel click */

/* What we keep per device (libinput's user data). */
typedef struct device_info {
    int id;                  /* the event's device number */
    int path_index;          /* path backend: which configured path it is, else -1 */
    camera_window area;      /* where an absolute device lands on the plane */
    char name[INPUT_NAME_BYTES];
} device_info;

typedef struct libinput_source {
    input_source base;
    input_libinput_config cfg;
    session *sn;
    struct udev *udev;
    struct libinput *li;
    int next_device_id;
    int device_count;
    bool path_open[INPUT_MAX_PATHS];    /* that configured path is a device of the context */
    char path_real[INPUT_MAX_PATHS][INPUT_NAME_BYTES]; /* realpath of each, "" if unresolved */
    double next_path_retry_s;
    bool path_missing_said[INPUT_MAX_PATHS]; /* its absence was logged (once until it is back) */
    bool retry_quiet;                   /* retrying a path already reported: libinput's messages are
                                           dropped (they would repeat every second forever) */
    bool suspended;                     /* libinput_suspend'ed (the seat is switched away) */
} libinput_source;

/* ---- opening device nodes: through the seat when there is one ---------------- */

static int open_restricted(const char *path, int flags, void *user_data)
{
    libinput_source *s = user_data;
    if (s->sn && session_has_seat(s->sn)) {
        tess_error err = {{0}};
        int fd = session_open_device(s->sn, path, &err);
        if (fd < 0) {
            log_warn("input: %s", err.msg);
            return -EACCES;
        }
        return fd;
    }
    int fd = open(path, flags | O_CLOEXEC);
    return fd < 0 ? -errno : fd;
}

static void close_restricted(int fd, void *user_data)
{
    libinput_source *s = user_data;
    if (s->sn && session_has_seat(s->sn))
        session_close_device(s->sn, fd);
    else
        close(fd);
}

/* libinput's own messages, in our log (its errors as warnings: a device
 * that cannot be opened is ours to report, once). */
static void libinput_message(struct libinput *li, enum libinput_log_priority priority, const char *fmt, va_list args)
    __attribute__((format(printf, 3, 0)));
static void libinput_message(struct libinput *li, enum libinput_log_priority priority, const char *fmt, va_list args)
{
    const libinput_source *s = libinput_get_user_data(li);
    if (s && s->retry_quiet)
        return;
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, args);
    size_t n = strlen(msg);
    while (n > 0 && msg[n - 1] == '\n')
        msg[--n] = '\0';
    if (priority >= LIBINPUT_LOG_PRIORITY_ERROR)
        log_warn("libinput: %s", msg);
    else
        log_info("libinput: %s", msg);
}

static const struct libinput_interface interface = {
    .open_restricted = open_restricted,
    .close_restricted = close_restricted,
};

/* ---- devices -------------------------------------------------------------------- */

static bool find_output(const input_libinput_config *cfg, const char *name, camera_window *out)
{
    for (int i = 0; i < cfg->output_count; i++)
        if (strcmp(cfg->outputs[i].name, name) == 0) {
            *out = cfg->outputs[i].window;
            return true;
        }
    return false;
}

/* The area an absolute device covers: its rule's output, else the plane. */
static camera_window device_area(const libinput_source *s, struct libinput_device *dev, const char *name)
{
    const char *node = NULL;
    struct udev_device *ud = libinput_device_get_udev_device(dev);
    if (ud)
        node = udev_device_get_devnode(ud);
    camera_window area = CAMERA_WINDOW_FULL;
    for (int i = 0; i < s->cfg.rule_count; i++) {
        const input_device_rule *r = &s->cfg.rules[i];
        if (strcmp(r->device, name) == 0 || (node && strcmp(r->device, node) == 0)) {
            find_output(&s->cfg, r->output, &area); /* checked at open */
            log_info("input: '%s' covers output %s", name, r->output);
            break;
        }
    }
    if (ud)
        udev_device_unref(ud);
    return area;
}

/* realpath of p into out ("" when it does not resolve). */
static void real_path(const char *p, char *out, size_t size)
{
    char buf[PATH_MAX];
    if (realpath(p, buf) && strlen(buf) < size)
        snprintf(out, size, "%s", buf);
    else
        out[0] = '\0';
}

/* Which configured path a device is (its node, symlinks resolved), or -1. */
static int path_index_of(libinput_source *s, struct libinput_device *dev)
{
    struct udev_device *ud = libinput_device_get_udev_device(dev);
    const char *node = ud ? udev_device_get_devnode(ud) : NULL;
    char real[INPUT_NAME_BYTES];
    int found = -1;
    if (node) {
        real_path(node, real, sizeof real);
        for (int i = 0; i < s->cfg.path_count && found < 0; i++) {
            if (!s->path_real[i][0])
                real_path(s->cfg.paths[i], s->path_real[i], sizeof s->path_real[i]);
            if (strcmp(s->cfg.paths[i], node) == 0 || (real[0] && strcmp(s->path_real[i], real) == 0))
                found = i;
        }
    }
    if (ud)
        udev_device_unref(ud);
    return found;
}

static void device_added(libinput_source *s, struct libinput_device *dev, input_event *e)
{
    device_info *info = calloc(1, sizeof *info);
    if (!info) {
        log_error("input: out of memory for a device");
        return;
    }
    info->id = s->next_device_id++;
    snprintf(info->name, sizeof info->name, "%s", libinput_device_get_name(dev));
    info->area = device_area(s, dev, info->name);
    info->path_index = path_index_of(s, dev);
    if (info->path_index >= 0)
        s->path_open[info->path_index] = true;
    libinput_device_set_user_data(dev, info);
    s->device_count++;
    static const struct {
        enum libinput_device_capability cap;
        const char *name;
    } caps[] = {{LIBINPUT_DEVICE_CAP_KEYBOARD, "keyboard"}, {LIBINPUT_DEVICE_CAP_POINTER, "pointer"},
                {LIBINPUT_DEVICE_CAP_TOUCH, "touch"},       {LIBINPUT_DEVICE_CAP_GESTURE, "gestures"},
                {LIBINPUT_DEVICE_CAP_TABLET_TOOL, "tablet"}};
    char what[96] = "";
    for (size_t i = 0; i < sizeof caps / sizeof caps[0]; i++)
        if (libinput_device_has_capability(dev, caps[i].cap))
            snprintf(what + strlen(what), sizeof what - strlen(what), "%s%s", what[0] ? ", " : "", caps[i].name);
    log_info("input: device %d added: '%s' (%s) %s", info->id, info->name, libinput_device_get_sysname(dev),
             what[0] ? what : "no capability we use");
    e->kind = INPUT_DEVICE_ADDED;
    e->device = info->id;
}

static device_info *info_of(struct libinput_device *dev) { return libinput_device_get_user_data(dev); }

static void device_removed(libinput_source *s, struct libinput_device *dev, input_event *e)
{
    device_info *info = info_of(dev);
    /* a vanished path device is tried again; one removed by a suspend comes back with the resume */
    if (info && info->path_index >= 0 && !s->suspended)
        s->path_open[info->path_index] = false;
    e->kind = INPUT_DEVICE_REMOVED;
    e->device = info ? info->id : -1;
    if (info) {
        log_info("input: device %d removed: '%s'", info->id, info->name);
        libinput_device_set_user_data(dev, NULL);
        free(info);
        s->device_count--;
    }
}

/* What a path that is not a character device is. */
static const char *not_a_device(mode_t mode)
{
    if (S_ISREG(mode))
        return "a regular file, not a device node";
    if (S_ISDIR(mode))
        return "a directory, not a device node";
    if (S_ISFIFO(mode))
        return "a FIFO, not a device node";
    if (S_ISSOCK(mode))
        return "a socket, not a device node";
    return "a block device, not an input device";
}

/* Whether udev has set up the character device `rdev` (its rules ran).
 * libinput's path backend waits for that itself, about 2 s, before it gives
 * up on a device: offered a node udev never sets up (/dev/null, or any node
 * where no udevd runs) every second, the input thread would stall for 2 s of
 * every 3 (seen before this check: /dev/null's "udev device never
 * initialized" came 2.1 s after it was offered; tests/test_input_cli.c now
 * checks that message never appears). */
static bool udev_ready(libinput_source *s, dev_t rdev)
{
    struct udev_device *ud = udev_device_new_from_devnum(s->udev, 'c', rdev);
    bool ready = ud && udev_device_get_is_initialized(ud);
    if (ud)
        udev_device_unref(ud);
    return ready;
}

/* Path backend: add the configured devices that are not (or no longer)
 * there, when their node exists and is one libinput can take; a missing or
 * unusable one is said once until it is back (libinput's own messages about
 * it too: they would repeat every second for as long as the kiosk runs). */
static void retry_paths(libinput_source *s)
{
    double now = clock_monotonic_s();
    if (now < s->next_path_retry_s)
        return;
    s->next_path_retry_s = now + PATH_RETRY_S;
    for (int i = 0; i < s->cfg.path_count; i++) {
        if (s->path_open[i])
            continue;
        const char *path = s->cfg.paths[i];
        if (s->path_missing_said[i])
            log_debug("input: %s: looked for again", path); /* what tests wait for */
        struct stat st;
        const char *problem = NULL; /* why it cannot be used now (said once), NULL to offer it to libinput */
        char why[160];
        if (stat(path, &st) != 0) {
            problem = "no such device now; waiting for it";
        } else if (!S_ISCHR(st.st_mode)) {
            snprintf(why, sizeof why, "not usable as an input device (%s); looked at again every second",
                     not_a_device(st.st_mode));
            problem = why;
        } else if (!udev_ready(s, st.st_rdev)) {
            problem = "udev has not set this device up (is systemd-udevd running?); waiting for it";
        }
        struct libinput_device *added = NULL;
        if (!problem) {
            s->retry_quiet = s->path_missing_said[i];
            added = libinput_path_add_device(s->li, path);
            s->retry_quiet = false;
            problem = "not usable as an input device (libinput's message above); trying again every second";
        }
        if (added) {
            s->path_open[i] = true; /* its DEVICE_ADDED event follows */
            s->path_missing_said[i] = false;
        } else if (!s->path_missing_said[i]) {
            log_warn("input: %s: %s", path, problem);
            s->path_missing_said[i] = true;
        }
    }
}

/* ---- opening ---------------------------------------------------------------------- */

static const input_source_ops libinput_ops;

input_source *input_libinput_open(const input_libinput_config *cfg, struct session *sn, tess_error *err)
{
    for (int i = 0; i < cfg->rule_count; i++) {
        camera_window w;
        if (!find_output(cfg, cfg->rules[i].output, &w)) {
            char names[INPUT_MAX_OUTPUTS * 34] = "";
            for (int k = 0; k < cfg->output_count; k++)
                snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", k ? ", " : "",
                         cfg->outputs[k].name);
            tess_error_set(err, "input: device '%s' is mapped to output '%s', which is not one of the outputs (%s)",
                           cfg->rules[i].device, cfg->rules[i].output, names);
            return NULL;
        }
    }
    libinput_source *s = calloc(1, sizeof *s);
    if (!s) {
        tess_error_set(err, "input: out of memory");
        return NULL;
    }
    s->base.ops = &libinput_ops;
    s->cfg = *cfg;
    s->sn = sn;
    if (cfg->path_count > 0) {
        s->li = libinput_path_create_context(&interface, s);
        if (!s->li) {
            tess_error_set(err, "input: libinput: cannot create a path context");
            goto fail;
        }
        libinput_log_set_handler(s->li, libinput_message);
        s->udev = udev_new(); /* only to ask whether udev set a node up (udev_ready) */
        if (!s->udev) {
            tess_error_set(err, "input: cannot create a udev context");
            goto fail;
        }
        retry_paths(s); /* at once: next_path_retry_s is 0 */
    } else {
        s->udev = udev_new();
        if (!s->udev) {
            tess_error_set(err, "input: cannot create a udev context");
            goto fail;
        }
        s->li = libinput_udev_create_context(&interface, s, s->udev);
        if (s->li)
            libinput_log_set_handler(s->li, libinput_message);
        const char *seat = cfg->seat[0] ? cfg->seat : "seat0";
        if (!s->li || libinput_udev_assign_seat(s->li, seat) != 0) {
            tess_error_set(err, "input: libinput could not take seat '%s' through udev", seat);
            goto fail;
        }
    }
    return &s->base;
fail:
    input_source_destroy(&s->base);
    return NULL;
}

static void libinput_source_destroy(input_source *base)
{
    libinput_source *s = (libinput_source *)base;
    if (s->li) {
        libinput_suspend(s->li); /* removes every device: their infos are freed by the events */
        struct libinput_event *ev;
        libinput_dispatch(s->li);
        while ((ev = libinput_get_event(s->li))) {
            if (libinput_event_get_type(ev) == LIBINPUT_EVENT_DEVICE_REMOVED) {
                struct libinput_device *dev = libinput_event_get_device(ev);
                free(info_of(dev));
                libinput_device_set_user_data(dev, NULL);
            }
            libinput_event_destroy(ev);
        }
        libinput_unref(s->li);
    }
    if (s->udev)
        udev_unref(s->udev);
    free(s);
}

static int libinput_source_fd(const input_source *base) { return libinput_get_fd(((const libinput_source *)base)->li); }

static void libinput_source_suspend(input_source *base)
{
    libinput_source *s = (libinput_source *)base;
    if (s->suspended)
        return;
    s->suspended = true;
    libinput_suspend(s->li); /* every device is removed: DEVICE_REMOVED events follow */
    log_info("input: devices released (the seat is switched away)");
}

static void libinput_source_resume(input_source *base)
{
    libinput_source *s = (libinput_source *)base;
    if (!s->suspended)
        return;
    if (libinput_resume(s->li) != 0) {
        log_warn("input: libinput could not take the devices back; trying again");
        return;
    }
    s->suspended = false;
    log_info("input: devices taken back");
}

static bool libinput_source_suspended(const input_source *base) { return ((const libinput_source *)base)->suspended; }

static int libinput_source_device_count(const input_source *base)
{
    return ((const libinput_source *)base)->device_count;
}

/* ---- events ------------------------------------------------------------------------- */

/* A fraction (0..1 across the device) inside an area, as plane coordinates. */

/* Convert one libinput event; returns how many input events it made (0..1),
 * and whether a frame must close after it (non-touch events are one frame). */
static bool convert(libinput_source *s, struct libinput_event *ev, input_event *e, bool *frame)
{
    enum libinput_event_type type = libinput_event_get_type(ev);
    struct libinput_device *dev = libinput_event_get_device(ev);
    *e = (input_event){0};
    *frame = true;
    if (type == LIBINPUT_EVENT_DEVICE_ADDED) {
        device_added(s, dev, e);
        *frame = false;
        return true;
    }
    if (type == LIBINPUT_EVENT_DEVICE_REMOVED) {
        device_removed(s, dev, e);
        *frame = false;
        return true;
    }
    device_info *info = info_of(dev);
    if (!info)
        return false;
    e->device = info->id;
    switch (type) {
    case LIBINPUT_EVENT_KEYBOARD_KEY: {
        struct libinput_event_keyboard *k = libinput_event_get_keyboard_event(ev);
        e->kind = INPUT_KEY;
        e->time_us = libinput_event_keyboard_get_time_usec(k);
        e->code = (int)libinput_event_keyboard_get_key(k);
        e->pressed = libinput_event_keyboard_get_key_state(k) == LIBINPUT_KEY_STATE_PRESSED;
        return true;
    }
    case LIBINPUT_EVENT_POINTER_MOTION: {
        struct libinput_event_pointer *p = libinput_event_get_pointer_event(ev);
        e->kind = INPUT_POINTER_MOTION;
        e->time_us = libinput_event_pointer_get_time_usec(p);
        e->dx = libinput_event_pointer_get_dx(p) / s->cfg.px_per_unit_x;
        e->dy = -libinput_event_pointer_get_dy(p) / s->cfg.px_per_unit_y;
        return true;
    }
    case LIBINPUT_EVENT_POINTER_MOTION_ABSOLUTE: {
        struct libinput_event_pointer *p = libinput_event_get_pointer_event(ev);
        e->kind = INPUT_POINTER_ABS;
        e->time_us = libinput_event_pointer_get_time_usec(p);
        input_area_point(&info->area, libinput_event_pointer_get_absolute_x_transformed(p, 1),
                   libinput_event_pointer_get_absolute_y_transformed(p, 1), &e->x, &e->y);
        return true;
    }
    case LIBINPUT_EVENT_POINTER_BUTTON: {
        struct libinput_event_pointer *p = libinput_event_get_pointer_event(ev);
        e->kind = INPUT_BUTTON;
        e->time_us = libinput_event_pointer_get_time_usec(p);
        e->code = (int)libinput_event_pointer_get_button(p);
        e->pressed = libinput_event_pointer_get_button_state(p) == LIBINPUT_BUTTON_STATE_PRESSED;
        return true;
    }
    case LIBINPUT_EVENT_POINTER_SCROLL_WHEEL:
    case LIBINPUT_EVENT_POINTER_SCROLL_FINGER: {
        struct libinput_event_pointer *p = libinput_event_get_pointer_event(ev);
        if (!libinput_event_pointer_has_axis(p, LIBINPUT_POINTER_AXIS_SCROLL_VERTICAL))
            return false;
        e->kind = INPUT_SCROLL;
        e->time_us = libinput_event_pointer_get_time_usec(p);
        /* libinput: positive is down (towards the user); ours: positive is away */
        if (type == LIBINPUT_EVENT_POINTER_SCROLL_WHEEL)
            e->dy = -libinput_event_pointer_get_scroll_value_v120(p, LIBINPUT_POINTER_AXIS_SCROLL_VERTICAL) / 120.0;
        else
            e->dy = -libinput_event_pointer_get_scroll_value(p, LIBINPUT_POINTER_AXIS_SCROLL_VERTICAL) /
                    SCROLL_FINGER_PX_PER_CLICK;
        return e->dy != 0.0;
    }
    case LIBINPUT_EVENT_TOUCH_DOWN:
    case LIBINPUT_EVENT_TOUCH_MOTION: {
        struct libinput_event_touch *t = libinput_event_get_touch_event(ev);
        e->kind = type == LIBINPUT_EVENT_TOUCH_DOWN ? INPUT_TOUCH_DOWN : INPUT_TOUCH_MOTION;
        e->time_us = libinput_event_touch_get_time_usec(t);
        e->slot = libinput_event_touch_get_slot(t);
        input_area_point(&info->area, libinput_event_touch_get_x_transformed(t, 1),
                   libinput_event_touch_get_y_transformed(t, 1), &e->x, &e->y);
        *frame = false;
        return e->slot >= 0;
    }
    case LIBINPUT_EVENT_TOUCH_UP:
    case LIBINPUT_EVENT_TOUCH_CANCEL: {
        struct libinput_event_touch *t = libinput_event_get_touch_event(ev);
        e->kind = type == LIBINPUT_EVENT_TOUCH_UP ? INPUT_TOUCH_UP : INPUT_TOUCH_CANCEL;
        e->time_us = libinput_event_touch_get_time_usec(t);
        e->slot = type == LIBINPUT_EVENT_TOUCH_UP ? libinput_event_touch_get_slot(t) : 0;
        *frame = false;
        return true;
    }
    case LIBINPUT_EVENT_TOUCH_FRAME: {
        struct libinput_event_touch *t = libinput_event_get_touch_event(ev);
        e->kind = INPUT_TOUCH_FRAME;
        e->time_us = libinput_event_touch_get_time_usec(t);
        *frame = false;
        return true;
    }
    case LIBINPUT_EVENT_GESTURE_PINCH_BEGIN:
    case LIBINPUT_EVENT_GESTURE_PINCH_UPDATE:
    case LIBINPUT_EVENT_GESTURE_PINCH_END:
    case LIBINPUT_EVENT_GESTURE_SWIPE_BEGIN:
    case LIBINPUT_EVENT_GESTURE_SWIPE_UPDATE:
    case LIBINPUT_EVENT_GESTURE_SWIPE_END: {
        struct libinput_event_gesture *g = libinput_event_get_gesture_event(ev);
        e->time_us = libinput_event_gesture_get_time_usec(g);
        bool pinch = type == LIBINPUT_EVENT_GESTURE_PINCH_BEGIN || type == LIBINPUT_EVENT_GESTURE_PINCH_UPDATE ||
                     type == LIBINPUT_EVENT_GESTURE_PINCH_END;
        if (type == LIBINPUT_EVENT_GESTURE_PINCH_BEGIN || type == LIBINPUT_EVENT_GESTURE_SWIPE_BEGIN) {
            e->kind = pinch ? INPUT_PINCH_BEGIN : INPUT_SWIPE_BEGIN;
            e->fingers = libinput_event_gesture_get_finger_count(g);
        } else if (type == LIBINPUT_EVENT_GESTURE_PINCH_END || type == LIBINPUT_EVENT_GESTURE_SWIPE_END) {
            e->kind = pinch ? INPUT_PINCH_END : INPUT_SWIPE_END;
            e->cancelled = libinput_event_gesture_get_cancelled(g) != 0;
        } else {
            e->kind = pinch ? INPUT_PINCH_UPDATE : INPUT_SWIPE_UPDATE;
            e->dx = libinput_event_gesture_get_dx(g) / s->cfg.px_per_unit_x;
            e->dy = -libinput_event_gesture_get_dy(g) / s->cfg.px_per_unit_y;
            if (pinch)
                e->scale = libinput_event_gesture_get_scale(g);
        }
        return true;
    }
    default:
        return false;
    }
}

static bool libinput_source_dispatch(input_source *base, input_event_fn fn, void *ctx)
{
    libinput_source *s = (libinput_source *)base;
    if (s->cfg.path_count > 0 && !s->suspended)
        retry_paths(s);
    if (libinput_dispatch(s->li) != 0) {
        log_error("input: libinput could not read its devices: %s", strerror(errno));
        return false;
    }
    struct libinput_event *ev;
    while ((ev = libinput_get_event(s->li))) {
        input_event e;
        bool frame;
        if (convert(s, ev, &e, &frame)) {
            fn(ctx, &e);
            if (frame) {
                input_event f = {.kind = INPUT_FRAME, .time_us = e.time_us, .device = e.device};
                fn(ctx, &f);
            }
        }
        libinput_event_destroy(ev);
    }
    return true;
}

static const input_source_ops libinput_ops = {
    .name = "libinput",
    .fd = libinput_source_fd,
    .dispatch = libinput_source_dispatch,
    .suspend = libinput_source_suspend,
    .resume = libinput_source_resume,
    .suspended = libinput_source_suspended,
    .device_count = libinput_source_device_count,
    .destroy = libinput_source_destroy,
};
