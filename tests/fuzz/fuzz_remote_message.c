/* fuzz_remote_message.c - the remote view's page messages (remote/protocol.c)
 * through remote_message_parse. A message that parses must hold what the
 * parser promises (fractions in [0, 1], distinct touch ids in range, a known
 * button and key), and the events it makes (remote_message_events, over a
 * viewer whose held state carries over between inputs) must be finite,
 * at most REMOTE_EVENTS_MAX, and closed by a frame. A dropped one has a
 * reason. */
#include "fuzz.h"

#include <math.h>
#include <string.h>

#include "remote/protocol.h"

static remote_viewer_input viewer;
static bool viewer_made;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!viewer_made) {
        remote_viewer_input_init(&viewer, 3);
        viewer_made = true;
    }
    remote_message m;
    remote_drop_reason why = REMOTE_DROP_REASONS;
    if (!remote_message_parse((const char *)data, size, &m, &why)) {
        if ((unsigned)why >= REMOTE_DROP_REASONS)
            fuzz_fail("a message was dropped without a reason");
        return 0;
    }
    if (!(m.x >= 0.0 && m.x <= 1.0 && m.y >= 0.0 && m.y <= 1.0))
        fuzz_fail("a fraction outside [0, 1]: (%g, %g)", m.x, m.y);
    if (m.touch_count < 0 || m.touch_count > INPUT_MAX_TOUCHES || m.ended_count < 0 ||
        m.ended_count > INPUT_MAX_TOUCHES)
        fuzz_fail("%d touches, %d ended", m.touch_count, m.ended_count);
    unsigned seen = 0;
    for (int i = 0; i < m.touch_count; i++) {
        int id = m.touches[i].id;
        if (id < 0 || id >= INPUT_MAX_TOUCHES || (seen >> id & 1u))
            fuzz_fail("touch id %d out of range or repeated", id);
        seen |= 1u << id;
        if (!(m.touches[i].x >= 0.0 && m.touches[i].x <= 1.0 && m.touches[i].y >= 0.0 && m.touches[i].y <= 1.0))
            fuzz_fail("a touch outside the picture");
    }
    if (m.button < 0 || m.button > 2 || (m.kind == REMOTE_MSG_KEY && m.key_code < 0) || !isfinite(m.dy))
        fuzz_fail("button %d, key %d, dy %g", m.button, m.key_code, m.dy);
    const camera_window area = {0.25f, -0.5f, 0.75f, 0.5f};
    input_event events[REMOTE_EVENTS_MAX];
    int n = remote_message_events(&viewer, &m, &area, 1, events);
    if (n < 0 || n > REMOTE_EVENTS_MAX)
        fuzz_fail("%d events", n);
    for (int i = 0; i < n; i++)
        if (!isfinite(events[i].x) || !isfinite(events[i].y) || !isfinite(events[i].dy))
            fuzz_fail("event %d is not finite", i);
    if (n > 0 && events[n - 1].kind != INPUT_FRAME && events[n - 1].kind != INPUT_TOUCH_FRAME)
        fuzz_fail("the events of a message end without a frame (kind %d)", (int)events[n - 1].kind);
    return 0;
}
