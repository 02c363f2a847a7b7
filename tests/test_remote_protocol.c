/* test_remote_protocol.c - the page's messages (remote/protocol.h): each
 * kind parsed to its fields, each way a message can be malformed dropped
 * with its reason, the key table, the rate limit on a synthetic clock, the
 * event runs each message makes over an area of the plane, and the frame
 * header's bytes; and the page built into the binary is remote/page.html. */
#include <criterion/criterion.h>
#include <linux/input-event-codes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "remote/page.h"
#include "remote/protocol.h"

static remote_message parse_ok(const char *text)
{
    remote_message m;
    remote_drop_reason why = REMOTE_DROP_REASONS;
    cr_assert(remote_message_parse(text, strlen(text), &m, &why), "%s: dropped (%s)", text,
              remote_drop_reason_name(why));
    return m;
}

static void parse_drops(const char *text, remote_drop_reason want)
{
    remote_message m;
    remote_drop_reason why = REMOTE_DROP_REASONS;
    cr_assert_not(remote_message_parse(text, strlen(text), &m, &why), "%s was accepted", text);
    cr_assert_eq(why, want, "%s: %s, not %s", text, remote_drop_reason_name(why), remote_drop_reason_name(want));
}

Test(remote_protocol, every_kind_parses_to_its_fields)
{
    remote_message m = parse_ok("{\"t\":\"ack\",\"frame\":12345}");
    cr_assert(m.kind == REMOTE_MSG_ACK && m.frame == 12345);
    m = parse_ok("{\"t\":\"down\",\"x\":0.25,\"y\":0.75,\"button\":2}");
    cr_assert(m.kind == REMOTE_MSG_DOWN && m.x == 0.25 && m.y == 0.75 && m.button == 2);
    m = parse_ok("{\"t\":\"move\",\"x\":-0.5,\"y\":1.5}"); /* a drag past the edge: clamped */
    cr_assert(m.kind == REMOTE_MSG_MOVE && m.x == 0.0 && m.y == 1.0);
    m = parse_ok("{\"t\":\"wheel\",\"x\":0.5,\"y\":0.5,\"dy\":-1.5}");
    cr_assert(m.kind == REMOTE_MSG_WHEEL && m.dy == -1.5);
    m = parse_ok("{\"t\":\"leave\"}");
    cr_assert(m.kind == REMOTE_MSG_LEAVE);
    m = parse_ok("{\"t\":\"touch\",\"touches\":[{\"id\":3,\"x\":0.1,\"y\":0.2},{\"id\":0,\"x\":0.3,\"y\":0.4}],"
                 "\"ended\":[5],\"cancel\":false}");
    cr_assert(m.kind == REMOTE_MSG_TOUCH && m.touch_count == 2 && m.touches[0].id == 3 && m.touches[1].y == 0.4 &&
              m.ended_count == 1 && m.ended[0] == 5 && !m.cancel);
    m = parse_ok("{\"t\":\"key\",\"code\":\"KeyW\",\"down\":true}");
    cr_assert(m.kind == REMOTE_MSG_KEY && m.key_code == KEY_W && m.down);
    m = parse_ok("{\"t\":\"view\",\"private\":true}");
    cr_assert(m.kind == REMOTE_MSG_VIEW && m.private_view);
}

Test(remote_protocol, malformed_messages_are_dropped_with_their_reason)
{
    parse_drops("{\"t\":\"move\",\"x\":0.5", REMOTE_DROP_NOT_JSON);
    parse_drops("{\"t\":\"leave\"} trailing", REMOTE_DROP_NOT_JSON);
    parse_drops("{\"t\":\"move\",\"x\":NaN,\"y\":0}", REMOTE_DROP_OUT_OF_RANGE); /* json-c reads NaN */
    parse_drops("[1,2,3]", REMOTE_DROP_NOT_OBJECT);
    parse_drops("{\"x\":1}", REMOTE_DROP_UNKNOWN_TYPE);
    parse_drops("{\"t\":\"warp\"}", REMOTE_DROP_UNKNOWN_TYPE);
    parse_drops("{\"t\":7}", REMOTE_DROP_UNKNOWN_TYPE);
    parse_drops("{\"t\":\"down\",\"x\":0.5,\"y\":0.5}", REMOTE_DROP_MISSING_FIELD);
    parse_drops("{\"t\":\"move\",\"x\":\"left\",\"y\":0.5}", REMOTE_DROP_WRONG_TYPE);
    parse_drops("{\"t\":\"view\",\"private\":1}", REMOTE_DROP_WRONG_TYPE);
    parse_drops("{\"t\":\"down\",\"x\":0.5,\"y\":0.5,\"button\":3}", REMOTE_DROP_OUT_OF_RANGE);
    parse_drops("{\"t\":\"down\",\"x\":0.5,\"y\":0.5,\"button\":0.5}", REMOTE_DROP_OUT_OF_RANGE);
    parse_drops("{\"t\":\"move\",\"x\":3,\"y\":0.5}", REMOTE_DROP_OUT_OF_RANGE);
    parse_drops("{\"t\":\"move\",\"x\":1e308,\"y\":0.5}", REMOTE_DROP_OUT_OF_RANGE);
    parse_drops("{\"t\":\"wheel\",\"x\":0,\"y\":0,\"dy\":1000}", REMOTE_DROP_OUT_OF_RANGE);
    parse_drops("{\"t\":\"ack\",\"frame\":-1}", REMOTE_DROP_OUT_OF_RANGE);
    parse_drops("{\"t\":\"touch\",\"touches\":[{\"id\":1,\"x\":0,\"y\":0},{\"id\":1,\"x\":1,\"y\":1}]}",
                REMOTE_DROP_OUT_OF_RANGE); /* one id twice */
    parse_drops("{\"t\":\"touch\",\"touches\":[{\"id\":10,\"x\":0,\"y\":0}]}", REMOTE_DROP_OUT_OF_RANGE);
    parse_drops("{\"t\":\"touch\",\"touches\":{}}", REMOTE_DROP_WRONG_TYPE);
    parse_drops("{\"t\":\"touch\",\"touches\":[{\"x\":0,\"y\":0}]}", REMOTE_DROP_MISSING_FIELD);
    parse_drops("{\"t\":\"key\",\"code\":\"Launch\",\"down\":true}", REMOTE_DROP_UNKNOWN_KEY);
    parse_drops("{\"t\":{\"a\":{\"b\":{\"c\":{\"d\":1}}}}}", REMOTE_DROP_NOT_JSON); /* deeper than the limit */
    /* eleven touches */
    char many[1024] = "{\"t\":\"touch\",\"touches\":[";
    for (int i = 0; i < 11; i++)
        snprintf(many + strlen(many), sizeof many - strlen(many), "%s{\"id\":%d,\"x\":0,\"y\":0}", i ? "," : "",
                 i % 10);
    strcat(many, "]}");
    parse_drops(many, REMOTE_DROP_OUT_OF_RANGE);
    cr_assert_str_eq(remote_drop_reason_name(REMOTE_DROP_RATE), "over-rate");
}

/* The size limit: REMOTE_MESSAGE_MAX_BYTES bytes pass, one more does not. */
Test(remote_protocol, the_size_limit)
{
    char text[REMOTE_MESSAGE_MAX_BYTES + 2];
    const char *head = "{\"t\":\"leave\",\"pad\":\"";
    size_t n = strlen(head);
    memcpy(text, head, n);
    memset(text + n, 'a', REMOTE_MESSAGE_MAX_BYTES - n - 2);
    memcpy(text + REMOTE_MESSAGE_MAX_BYTES - 2, "\"}", 3);
    remote_message m;
    remote_drop_reason why;
    cr_assert(remote_message_parse(text, REMOTE_MESSAGE_MAX_BYTES, &m, &why), "%s", remote_drop_reason_name(why));
    memmove(text + n + 1, text + n, REMOTE_MESSAGE_MAX_BYTES - n + 1);
    cr_assert_not(remote_message_parse(text, REMOTE_MESSAGE_MAX_BYTES + 1, &m, &why));
    cr_assert_eq(why, REMOTE_DROP_TOO_LONG);
}

Test(remote_protocol, dom_key_codes_to_evdev)
{
    cr_assert_eq(remote_key_code("KeyA"), KEY_A);
    cr_assert_eq(remote_key_code("Digit0"), KEY_0);
    cr_assert_eq(remote_key_code("Digit9"), KEY_9);
    cr_assert_eq(remote_key_code("Space"), KEY_SPACE);
    cr_assert_eq(remote_key_code("ArrowLeft"), KEY_LEFT);
    cr_assert_eq(remote_key_code("Comma"), KEY_COMMA);
    cr_assert_eq(remote_key_code("Period"), KEY_DOT);
    cr_assert_eq(remote_key_code("Slash"), KEY_SLASH);
    cr_assert_eq(remote_key_code("Delete"), KEY_DELETE);
    cr_assert_eq(remote_key_code("End"), KEY_END);
    cr_assert_eq(remote_key_code("ShiftLeft"), KEY_LEFTSHIFT);
    cr_assert_eq(remote_key_code("F12"), KEY_F12);
    cr_assert_eq(remote_key_code("keya"), -1);
    cr_assert_eq(remote_key_code(""), -1);
    cr_assert_eq(remote_key_code(NULL), -1);
}

Test(remote_protocol, the_rate_limit_on_a_synthetic_clock)
{
    remote_rate r;
    remote_rate_init(&r, 1000000);
    int taken = 0;
    while (remote_rate_take(&r, 1000000))
        taken++;
    cr_assert_eq(taken, (int)REMOTE_RATE_BURST, "a burst of %d", taken);
    cr_assert_not(remote_rate_take(&r, 1000000 + 2000), "2 ms: less than one message's worth (2.5 ms)");
    cr_assert(remote_rate_take(&r, 1000000 + 2500));
    /* a second later: REMOTE_RATE_PER_S more, but never more than the burst */
    taken = 0;
    while (remote_rate_take(&r, 1000000 + 2500 + 1000000))
        taken++;
    cr_assert_eq(taken, (int)REMOTE_RATE_BURST);
}

static const camera_window area = {0.5f, -0.25f, 0.5f, 0.75f}; /* x in [0, 1], y in [-1, 0.5] */

static int events_of(remote_viewer_input *v, const char *text, input_event *out)
{
    remote_message m = parse_ok(text);
    int n = remote_message_events(v, &m, &area, 777, out);
    cr_assert_leq(n, REMOTE_EVENTS_MAX);
    for (int i = 0; i < n; i++) {
        cr_assert_eq(out[i].device, REMOTE_DEVICE_BASE + v->slot);
        cr_assert_eq(out[i].time_us, 777u);
    }
    return n;
}

Test(remote_protocol, mouse_messages_make_closed_event_runs_on_the_area)
{
    remote_viewer_input v;
    remote_viewer_input_init(&v, 2);
    input_event e[REMOTE_EVENTS_MAX];
    int n = events_of(&v, "{\"t\":\"move\",\"x\":0.5,\"y\":0.5}", e);
    cr_assert_eq(n, 2, "no button held: the viewer's pointer only");
    cr_assert(e[0].kind == INPUT_VIEWER_POINTER && e[0].slot == 2 && e[0].pressed);
    cr_assert_float_eq(e[0].x, 0.5, 1e-12);
    cr_assert_float_eq(e[0].y, -0.25, 1e-12);
    cr_assert_eq(e[1].kind, INPUT_FRAME);
    n = events_of(&v, "{\"t\":\"down\",\"x\":0,\"y\":0,\"button\":0}", e);
    cr_assert_eq(n, 4);
    cr_assert(e[0].kind == INPUT_POINTER_ABS && e[0].x == 0.0 && e[0].y == 0.5, "top-left: (%g, %g)", e[0].x, e[0].y);
    cr_assert(e[2].kind == INPUT_BUTTON && e[2].code == BTN_LEFT && e[2].pressed);
    cr_assert_eq(e[3].kind, INPUT_FRAME);
    cr_assert_eq(events_of(&v, "{\"t\":\"down\",\"x\":0,\"y\":0,\"button\":0}", e), 0, "already down");
    n = events_of(&v, "{\"t\":\"move\",\"x\":1,\"y\":1}", e);
    cr_assert_eq(n, 3, "held: the cursor moves too");
    cr_assert(e[0].kind == INPUT_POINTER_ABS && e[0].x == 1.0 && e[0].y == -1.0);
    n = events_of(&v, "{\"t\":\"up\",\"x\":1,\"y\":1,\"button\":0}", e);
    cr_assert(n == 3 && e[1].kind == INPUT_BUTTON && !e[1].pressed);
    cr_assert_eq(events_of(&v, "{\"t\":\"up\",\"x\":1,\"y\":1,\"button\":2}", e), 0, "never down");
    n = events_of(&v, "{\"t\":\"wheel\",\"x\":0.5,\"y\":0.5,\"dy\":2}", e);
    cr_assert(n == 3 && e[1].kind == INPUT_SCROLL && e[1].dy == 2.0);
    n = events_of(&v, "{\"t\":\"leave\"}", e);
    cr_assert(n == 2 && e[0].kind == INPUT_VIEWER_POINTER && !e[0].pressed);
    cr_assert_eq(events_of(&v, "{\"t\":\"leave\"}", e), 0, "hidden already");
    n = events_of(&v, "{\"t\":\"key\",\"code\":\"KeyH\",\"down\":true}", e);
    cr_assert(n == 2 && e[0].kind == INPUT_KEY && e[0].code == KEY_H && e[0].pressed);
    cr_assert_eq(events_of(&v, "{\"t\":\"ack\",\"frame\":3}", e), 0);
}

Test(remote_protocol, touch_messages_go_down_move_and_up)
{
    remote_viewer_input v;
    remote_viewer_input_init(&v, 0);
    input_event e[REMOTE_EVENTS_MAX];
    int n = events_of(&v, "{\"t\":\"touch\",\"touches\":[{\"id\":4,\"x\":0.5,\"y\":0.5}]}", e);
    cr_assert_eq(n, 4);
    cr_assert(e[0].kind == INPUT_TOUCH_DOWN && e[0].slot == 4 && e[0].x == 0.5 && e[0].y == -0.25);
    cr_assert_eq(e[1].kind, INPUT_TOUCH_FRAME);
    cr_assert(e[2].kind == INPUT_VIEWER_POINTER && e[2].pressed && e[3].kind == INPUT_FRAME);
    n = events_of(&v, "{\"t\":\"touch\",\"touches\":[{\"id\":4,\"x\":0.6,\"y\":0.5},{\"id\":1,\"x\":0,\"y\":0}]}", e);
    cr_assert(e[0].kind == INPUT_TOUCH_MOTION && e[0].slot == 4);
    cr_assert(e[1].kind == INPUT_TOUCH_DOWN && e[1].slot == 1);
    cr_assert(e[3].kind == INPUT_VIEWER_POINTER && e[3].x == 0.0, "the pointer at the lowest id (1)");
    n = events_of(&v, "{\"t\":\"touch\",\"touches\":[{\"id\":4,\"x\":0.6,\"y\":0.5}],\"ended\":[1,7]}", e);
    cr_assert(e[0].kind == INPUT_TOUCH_UP && e[0].slot == 1, "7 was never down: no event for it");
    cr_assert(e[1].kind == INPUT_TOUCH_MOTION && e[1].slot == 4);
    n = events_of(&v, "{\"t\":\"touch\",\"touches\":[],\"cancel\":true}", e);
    cr_assert(e[0].kind == INPUT_TOUCH_CANCEL && e[1].kind == INPUT_TOUCH_FRAME);
    cr_assert(e[2].kind == INPUT_VIEWER_POINTER && !e[2].pressed, "no touch left: the pointer hides");
    for (int i = 0; i < INPUT_MAX_TOUCHES; i++)
        cr_assert_not(v.touch_down[i]);
    n = remote_viewer_input_release(&v, 5, e);
    cr_assert(n == 1 && e[0].kind == INPUT_DEVICE_REMOVED, "nothing shown: the device goes");
}

Test(remote_protocol, the_frame_header_bytes)
{
    uint8_t h[REMOTE_FRAME_HEADER_BYTES];
    remote_frame_header(h, 0x0102030405060708ull, 0x1122334455667788ull, 1280, 720, 0xaabbccddu);
    const uint8_t want[REMOTE_FRAME_HEADER_BYTES] = {
        'T', 'S', 'R', 'F', 32, 0, 0, 0, 0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01,
        0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11, 0x00, 0x05, 0xd0, 0x02, 0xdd, 0xcc, 0xbb, 0xaa};
    cr_assert(memcmp(h, want, sizeof want) == 0);
}

Test(remote_protocol, the_built_in_page_is_page_html)
{
    FILE *f = fopen("../remote/page.html", "rb");
    cr_assert(f);
    static char file[1 << 20];
    size_t n = fread(file, 1, sizeof file, f);
    fclose(f);
    cr_assert_eq(n, remote_page_html_bytes);
    cr_assert(memcmp(file, remote_page_html, n) == 0);
    cr_assert_eq(remote_page_html[n], '\0');
    cr_assert(strstr(remote_page_html, "id=\"view\"") && strstr(remote_page_html, "window.tessera"));
}
