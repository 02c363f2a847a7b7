/* ws_client.c - a raw WebSocket client for the tests (ws_client.h). */
#define _DEFAULT_SOURCE
#include "ws_client.h"

#include <arpa/inet.h>
#include <criterion/criterion.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

int ws_connect(int port, const char *token, int *status)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    cr_assert(fd >= 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    cr_assert(connect(fd, (struct sockaddr *)&a, sizeof a) == 0, "connecting to port %d", port);
    struct timeval cap = {30, 0}; /* a read that waits longer fails the test instead of hanging it */
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &cap, sizeof cap);
    char req[512];
    int n = snprintf(req, sizeof req,
                     "GET /ws?token=%s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                     "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                     "Sec-WebSocket-Protocol: tessera-remote-1\r\n\r\n",
                     token, port);
    cr_assert(write(fd, req, (size_t)n) == n);
    char reply[2048];
    size_t len = 0;
    while (len + 1 < sizeof reply) { /* byte by byte: what follows the headers is the first frame's */
        ssize_t got = read(fd, reply + len, 1);
        if (got <= 0)
            break;
        len++;
        if (len >= 4 && !memcmp(reply + len - 4, "\r\n\r\n", 4))
            break;
    }
    reply[len] = '\0';
    *status = 0;
    sscanf(reply, "HTTP/1.1 %d", status);
    return fd;
}

static bool read_exact(int fd, uint8_t *p, size_t n)
{
    while (n) {
        ssize_t got = read(fd, p, n);
        if (got <= 0)
            return false;
        p += got;
        n -= (size_t)got;
    }
    return true;
}

bool ws_read(int fd, int *opcode, uint8_t *payload, size_t cap, size_t *len)
{
    uint8_t h[8];
    if (!read_exact(fd, h, 2))
        return false;
    *opcode = h[0] & 0x0f;
    uint64_t n = h[1] & 0x7f;
    if (n == 126) {
        if (!read_exact(fd, h, 2))
            return false;
        n = (uint64_t)h[0] << 8 | h[1];
    } else if (n == 127) {
        if (!read_exact(fd, h, 8))
            return false;
        n = 0;
        for (int i = 0; i < 8; i++)
            n = n << 8 | h[i];
    }
    cr_assert_leq(n, cap, "a %llu-byte frame", (unsigned long long)n);
    *len = (size_t)n;
    return read_exact(fd, payload, (size_t)n);
}

void ws_send_text(int fd, const char *text)
{
    uint8_t f[256];
    size_t n = strlen(text);
    cr_assert(n < 126);
    const uint8_t mask[4] = {0x12, 0x34, 0x56, 0x78};
    f[0] = 0x81;
    f[1] = (uint8_t)(0x80 | n);
    memcpy(f + 2, mask, 4);
    for (size_t i = 0; i < n; i++)
        f[6 + i] = (uint8_t)text[i] ^ mask[i % 4];
    cr_assert(write(fd, f, 6 + n) == (ssize_t)(6 + n));
}

