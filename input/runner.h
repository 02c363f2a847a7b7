/* runner.h - the input thread: polls its input sources (source.h, through
 * their interface only: libinput's devices today), feeds the mapping layer
 * (controller.h) and its clock, and hands what it says to the sink (sink.h),
 * which queues pipeline transactions. Nothing here touches renderer state.
 *
 * The thread waits in poll(2) on every source's fd and a wake-up eventfd,
 * with the controller's deadline as time-out (animation ticks at ~60 Hz while
 * something moves, the idle deadline otherwise; at least once a second, when
 * every source is dispatched for its own timers). On a VT switch (the seat
 * no longer ours) it suspends every source, and resumes them on return.
 *
 * PRIVATE VIEWS. An INPUT_PRIVATE_VIEW event (a remote viewer asking for a
 * camera of its own: remote/) gives its device a controller of its own
 * (controller.h, PRIVATE VIEW; up to INPUT_MAX_VIEWERS at once) that steers
 * channel `code`: the runner emits that channel's camera (the wall's camera
 * as it is then) and then switches the channel on. From then on the
 * device's events go to that controller alone (the wall's never sees them),
 * until the device is removed: its removal ends the view and switches the
 * channel off. The source releases what the device held in the wall's
 * controller before it asks (remote_viewer_input_release). */
#ifndef TESSERA_INPUT_RUNNER_H
#define TESSERA_INPUT_RUNNER_H

#include "engine/base/err.h"
#include "controller.h"
#include "sink.h"
#include "source.h"

struct session;

typedef struct input_runner input_runner;

/* Pick callback as in controller.h (called on the input thread). */
typedef void (*input_pick_fn)(void *ctx, vec3 origin, vec3 dir, input_hit *out);

/* Time-step readiness as in controller.h (called on the input thread). */
typedef bool (*input_step_ready_fn)(void *ctx, uint32_t step);

/* Start the thread over sources[0 .. source_count) (1..INPUT_MAX_SOURCES), which
 * the runner owns from this call on, also when it fails. pick and step_ready
 * (NULL: every step is ready) take pick_ctx; `sn` (NULL: none) tells whether
 * the seat is ours. NULL with err. */
input_runner *input_runner_start(input_source *const *sources, int source_count,
                                 const input_controller_config *controller, input_pick_fn pick,
                                 input_step_ready_fn step_ready, void *pick_ctx, input_sink *sink, struct session *sn,
                                 tess_error *err);

/* Stop the thread and destroy the sources (before the sink goes). NULL is fine. */
void input_runner_stop(input_runner *r);

#endif
