/* firmware/port/posix/fr_port_bus_posix.c: the posix robot's Dynamixel bus (fr_port_bus.h). Environment, read at
 * fr_port_bus_open:
 *   FR_POSIX_BUS   unset or `none`: no bus (a bridged request is answered BUS_DISABLED)
 *                  `model`: the emulated bus of tools/busmodel.c in this process (18 AX-12A, a HaViMo2 at 100)
 *                  `tcp:<ip>:<port>`: a raw byte stream, e.g. the standalone busmodel (build/busmodel port=...)
 * A TCP byte stream has no line direction and no echo: what is written goes out, what comes back is the bus's. */
#define _POSIX_C_SOURCE 200809L
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>
#include "fr_port.h"
#include "fr_port_bus.h"
#include "../../tools/busmodel.h"

/** Which bus the robot has. */
typedef enum { BUS_NONE, BUS_MODEL, BUS_TCP } bus_kind_t;

static bus_kind_t kind;
static int fd = -1;
static uint8_t rx[4096];          /* the model's answers not yet read */
static size_t rx_len, rx_pos;

/** Connects to `ip:port` (blocking, loopback: at once); the socket, or -1. */
static int connect_tcp(const char *spec) {
    char host[64];
    const char *colon = strrchr(spec, ':');
    size_t n = colon ? (size_t)(colon - spec) : 0;
    if (colon == NULL || n == 0 || n >= sizeof host) return -1;
    memcpy(host, spec, n);
    host[n] = '\0';
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)strtoul(colon + 1, NULL, 10));
    if (inet_pton(AF_INET, host, &a.sin_addr) != 1) return -1;
    int s = socket(AF_INET, SOCK_STREAM, 0);
    if (s < 0) return -1;
    if (connect(s, (struct sockaddr *)&a, sizeof a) != 0) {
        close(s);
        return -1;
    }
    int one = 1;
    (void)setsockopt(s, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    (void)fcntl(s, F_SETFL, fcntl(s, F_GETFL) | O_NONBLOCK);
    return s;
}

int fr_port_bus_open(uint32_t baud) {
    (void)baud; /* an emulated line has no baud rate */
    const char *spec = getenv("FR_POSIX_BUS");
    if (fd >= 0) close(fd);
    fd = -1;
    kind = BUS_NONE;
    rx_len = rx_pos = 0;
    if (spec == NULL || strcmp(spec, "none") == 0 || spec[0] == '\0') return -1;
    if (strcmp(spec, "model") == 0) {
        busmodel_init(fr_port_millis());
        kind = BUS_MODEL;
        return 0;
    }
    if (strncmp(spec, "tcp:", 4) == 0) {
        fd = connect_tcp(spec + 4);
        if (fd < 0) {
            fprintf(stderr, "fr_port_bus_posix: cannot connect to %s: %s\n", spec + 4, strerror(errno));
            return -1;
        }
        kind = BUS_TCP;
        return 0;
    }
    fprintf(stderr, "fr_port_bus_posix: FR_POSIX_BUS=%s: neither none, model nor tcp:<ip>:<port>\n", spec);
    return -1;
}

int fr_port_bus_write(const uint8_t *data, size_t len) {
    if (kind == BUS_MODEL) {
        if (rx_pos == rx_len) rx_pos = rx_len = 0;
        rx_len += busmodel_feed(data, len, rx + rx_len, sizeof rx - rx_len, fr_port_millis());
        return 0;
    }
    if (kind != BUS_TCP) return -1;
    size_t done = 0;
    /* a packet is at most 143 bytes: the socket's buffer takes it whole, or the stream is gone */
    for (int tries = 0; done < len && tries < 100; tries++) {
        ssize_t n = send(fd, data + done, len - done, MSG_NOSIGNAL);
        if (n > 0) done += (size_t)n;
        else if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return -1;
    }
    return done == len ? 0 : -1;
}

bool fr_port_bus_writing(void) { return false; }

size_t fr_port_bus_read(uint8_t *buf, size_t cap) {
    if (kind == BUS_MODEL) {
        size_t n = rx_len - rx_pos;
        if (n > cap) n = cap;
        memcpy(buf, rx + rx_pos, n);
        rx_pos += n;
        return n;
    }
    if (kind != BUS_TCP || cap == 0) return 0;
    ssize_t n = recv(fd, buf, cap, 0);
    return n > 0 ? (size_t)n : 0;
}
