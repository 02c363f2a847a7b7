/* session.c (seat) - the seat through libseat (see session.h). */
#include "session.h"

#include <errno.h>
#include <fcntl.h>
#include <libseat.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "engine/base/clock.h"
#include "engine/base/log.h"

#define SESSION_MAX_DEVICES 64
#define SESSION_ENABLE_WAIT_MS 5000 /* a seat that is not ours by then: run without it */

typedef struct session_device {
    int fd, id; /* id: libseat's device id, -1 when opened directly */
} session_device;

/* Two threads use a session: the display thread (the card, VT switches) and
 * the input thread (event devices). `lock` serialises every libseat call and
 * guards the device table; the flags are atomics so that session_active needs
 * no lock. session_dispatch waits for the seat's fd without the lock. */
struct session {
    struct libseat *seat;      /* NULL: direct mode */
    pthread_mutex_t lock;
    atomic_bool active;        /* enabled by the seat (always, in direct mode) */
    atomic_bool disable_pending; /* the seat asked for the devices back; not yet acknowledged */
    session_device devices[SESSION_MAX_DEVICES]; /* lock */
    int device_count;          /* lock */
};

static void seat_enabled(struct libseat *seat, void *data)
{
    (void)seat;
    session *s = data;
    s->active = true;
    s->disable_pending = false;
}

static void seat_disabled(struct libseat *seat, void *data)
{
    (void)seat;
    session *s = data;
    s->disable_pending = true;
}

static const struct libseat_seat_listener listener = {.enable_seat = seat_enabled, .disable_seat = seat_disabled};

/* libseat's messages, in the run's log: only its errors (its info chatter is
 * kept out of the kiosk's output). */
static char last_libseat_error[256];
static void libseat_message(enum libseat_log_level level, const char *fmt, va_list args)
{
    if (level != LIBSEAT_LOG_LEVEL_ERROR)
        return;
    vsnprintf(last_libseat_error, sizeof last_libseat_error, fmt, args);
}

static double now_ms(void) { return 1e3 * clock_monotonic_s(); }

session *session_open(void)
{
    session *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    pthread_mutex_init(&s->lock, NULL);
    libseat_set_log_handler(libseat_message);
    libseat_set_log_level(LIBSEAT_LOG_LEVEL_ERROR);
    last_libseat_error[0] = '\0';
    s->seat = libseat_open_seat(&listener, s);
    double start = now_ms();
    while (s->seat && !s->active && now_ms() - start < SESSION_ENABLE_WAIT_MS)
        if (libseat_dispatch(s->seat, 100) < 0)
            break;
    if (s->seat && !s->active) {
        log_warn("seat: '%s' was not handed to us within %d ms; opening devices directly",
                 libseat_seat_name(s->seat), SESSION_ENABLE_WAIT_MS);
        libseat_close_seat(s->seat);
        s->seat = NULL;
    }
    if (!s->seat)
        log_info("seat: none (%s); opening devices directly (needs root), no VT switching",
                 last_libseat_error[0] ? last_libseat_error : "no seatd, logind or builtin backend");
    else
        log_info("seat: %s", libseat_seat_name(s->seat));
    s->active = true; /* direct mode is always active; a seat just said so */
    return s;
}

void session_close(session *s)
{
    if (!s)
        return;
    while (s->device_count > 0)
        session_close_device(s, s->devices[s->device_count - 1].fd);
    if (s->seat)
        libseat_close_seat(s->seat);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

bool session_has_seat(const session *s) { return s->seat != NULL; }

static int session_open_device_locked(session *s, const char *path, tess_error *err);

int session_open_device(session *s, const char *path, tess_error *err)
{
    pthread_mutex_lock(&s->lock);
    int fd = session_open_device_locked(s, path, err);
    pthread_mutex_unlock(&s->lock);
    return fd;
}

static int session_open_device_locked(session *s, const char *path, tess_error *err)
{
    if (s->device_count == SESSION_MAX_DEVICES) {
        tess_error_set(err, "%s: more than %d devices open", path, SESSION_MAX_DEVICES);
        return -1;
    }
    int fd = -1, id = -1;
    if (s->seat) {
        last_libseat_error[0] = '\0';
        id = libseat_open_device(s->seat, path, &fd);
        if (id < 0) {
            tess_error_set(err, "%s: the seat would not open it: %s", path,
                           last_libseat_error[0] ? last_libseat_error : strerror(errno));
            return -1;
        }
    } else {
        fd = open(path, O_RDWR | O_CLOEXEC | O_NONBLOCK);
        if (fd < 0) {
            tess_error_set(err, "%s: cannot open: %s", path, strerror(errno));
            return -1;
        }
    }
    s->devices[s->device_count++] = (session_device){fd, id};
    return fd;
}

void session_close_device(session *s, int fd)
{
    pthread_mutex_lock(&s->lock);
    for (int i = 0; i < s->device_count; i++) {
        if (s->devices[i].fd != fd)
            continue;
        if (s->seat && s->devices[i].id >= 0)
            libseat_close_device(s->seat, s->devices[i].id);
        close(fd);
        s->devices[i] = s->devices[--s->device_count];
        pthread_mutex_unlock(&s->lock);
        return;
    }
    pthread_mutex_unlock(&s->lock);
    close(fd); /* not one of ours: still closed */
}

void session_dispatch(session *s, int timeout_ms)
{
    if (!s->seat)
        return;
    if (timeout_ms != 0) { /* wait without the lock, so the other thread can open devices */
        struct pollfd pfd = {.fd = libseat_get_fd(s->seat), .events = POLLIN};
        if (pfd.fd >= 0)
            poll(&pfd, 1, timeout_ms);
    }
    pthread_mutex_lock(&s->lock);
    if (libseat_dispatch(s->seat, 0) < 0)
        log_warn("seat: dispatching its events failed: %s", strerror(errno));
    pthread_mutex_unlock(&s->lock);
}

bool session_active(const session *s) { return s->active && !s->disable_pending; }

bool session_disable_pending(const session *s) { return s->disable_pending; }

void session_ack_disable(session *s)
{
    if (!s->disable_pending)
        return;
    s->active = false;
    s->disable_pending = false;
    pthread_mutex_lock(&s->lock);
    if (s->seat && libseat_disable_seat(s->seat) < 0)
        log_warn("seat: acknowledging the switch away failed: %s", strerror(errno));
    pthread_mutex_unlock(&s->lock);
}
