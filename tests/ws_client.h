/* ws_client.h - a raw WebSocket client (RFC 6455) for the tests that talk to
 * the remote view without a browser (tests/test_remote_browser.c,
 * tests/test_cluster.c): the handshake, masked text frames out, frames in.
 * Failures are Criterion assertions. */
#ifndef TESSERA_TESTS_WS_CLIENT_H
#define TESSERA_TESTS_WS_CLIENT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Connect to 127.0.0.1:port with `token` and read the handshake's reply up to
 * its blank line; the fd, the reply's status code in *status (101: a viewer).
 * Reads wait 30 s at most (then fail). */
int ws_connect(int port, const char *token, int *status);

/* One server frame (unmasked): its opcode and payload (at most cap bytes). */
bool ws_read(int fd, int *opcode, uint8_t *payload, size_t cap, size_t *len);

/* One masked text frame (a client's frames are masked); under 126 bytes. */
void ws_send_text(int fd, const char *text);

#endif
