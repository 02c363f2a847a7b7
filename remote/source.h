/* source.h (remote) - remote viewers' input as an input source (input/source.h):
 * the server thread turns each page message into input events
 * (remote/protocol.h) and pushes them here; the input thread polls this
 * source's eventfd and dispatches them to the mapping layer like libinput's.
 * A message's events go in whole or not at all (the queue is bounded: a
 * message that does not fit is dropped and counted), so frames stay closed.
 *
 * Threading: remote_source_push from the server thread; the input_source_ops
 * on the input thread; a mutex guards the queue. */
#ifndef TESSERA_REMOTE_SOURCE_H
#define TESSERA_REMOTE_SOURCE_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/err.h"
#include "input/source.h"

#define REMOTE_SOURCE_QUEUE 4096 /* events waiting at most */

typedef struct remote_source remote_source;

/* NULL with err. Owned by the caller until handed to the input runner (which
 * destroys it with input_source_destroy). */
remote_source *remote_source_create(tess_error *err);
input_source *remote_source_input(remote_source *s);

/* Queue events[0 .. count) as one run; false (counted) when they do not fit. */
bool remote_source_push(remote_source *s, const input_event *events, int count);

/* Runs dropped because the queue was full. */
uint64_t remote_source_dropped(remote_source *s);

#endif
