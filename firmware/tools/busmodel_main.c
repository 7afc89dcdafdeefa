/* firmware/tools/busmodel_main.c: the emulated bus of busmodel.c served as a raw byte stream on a TCP port, so the
 * official DynamixelSDK reaches it through a pseudo-terminal (socat pty,link=/tmp/dxl,raw,echo=0
 * tcp:127.0.0.1:<port>), the posix robot through FR_POSIX_BUS=tcp:127.0.0.1:<port>, and qemu through
 * -serial tcp:127.0.0.1:<port>. One client at a time; the model keeps its state between clients.
 *   build/busmodel [port=7000] [bind=127.0.0.1] [run_ms=0] [log=1]
 * It prints "busmodel: listening on <ip>:<port>" once it accepts connections; with log=1 also, once a second while
 * a client sends, how many bytes came and went. */
#define _POSIX_C_SOURCE 200809L
#include <arpa/inet.h>
#include <stdbool.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>
#include "busmodel.h"

/** Milliseconds of the monotonic clock. */
static uint32_t now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (uint32_t)((uint64_t)t.tv_sec * 1000u + (uint64_t)t.tv_nsec / 1000000u);
}

/** Serves the bus; exits 2 on a bad argument, 3 when the port cannot be bound. */
int main(int argc, char **argv) {
    unsigned port = 7000;
    const char *bind_ip = "127.0.0.1";
    unsigned long run_ms = 0;
    bool log = false;
    unsigned long bytes_in = 0, bytes_out = 0;
    uint32_t last_log = 0;
    for (int k = 1; k < argc; k++) {
        if (strncmp(argv[k], "port=", 5) == 0) port = (unsigned)strtoul(argv[k] + 5, NULL, 10);
        else if (strncmp(argv[k], "bind=", 5) == 0) bind_ip = argv[k] + 5;
        else if (strncmp(argv[k], "run_ms=", 7) == 0) run_ms = strtoul(argv[k] + 7, NULL, 10);
        else if (strcmp(argv[k], "log=1") == 0) log = true;
        else { fprintf(stderr, "busmodel: unknown argument %s (port=, bind=, run_ms=)\n", argv[k]); return 2; }
    }
    signal(SIGPIPE, SIG_IGN);
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    int one = 1, lfd = socket(AF_INET, SOCK_STREAM, 0);
    if (lfd < 0 || inet_pton(AF_INET, bind_ip, &a.sin_addr) != 1 ||
        setsockopt(lfd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        bind(lfd, (struct sockaddr *)&a, sizeof a) != 0 || listen(lfd, 4) != 0) {
        fprintf(stderr, "busmodel: cannot listen on %s:%u: %s\n", bind_ip, port, strerror(errno));
        return 3;
    }
    uint32_t began = now_ms();
    busmodel_init(began);
    printf("busmodel: listening on %s:%u (AX-12A ids 1-%d, HaViMo2 id %d)\n", bind_ip, port, BUSMODEL_SERVOS,
           BUSMODEL_HAVIMO_ID);
    fflush(stdout);
    int cfd = -1;
    for (;;) {
        if (run_ms != 0 && now_ms() - began >= run_ms) return 0;
        if (log && bytes_in > 0 && now_ms() - last_log >= 1000u) {
            const busmodel_counters_t *c = busmodel_counters();
            unsigned servos_read = 0;
            for (int k = 0; k < BUSMODEL_SERVOS; k++) servos_read += c->servo_reads[k] > 0;
            printf("busmodel: %lu bytes in, %lu bytes out; since start %lu packets, %u servos read, %lu captures\n",
                   bytes_in, bytes_out, (unsigned long)c->packets, servos_read, (unsigned long)c->captures);
            fflush(stdout);
            bytes_in = bytes_out = 0;
            last_log = now_ms();
        }
        struct pollfd p[1] = {{cfd >= 0 ? cfd : lfd, POLLIN, 0}};
        int r = poll(p, 1, 5);
        busmodel_step(now_ms());
        if (r <= 0) continue;
        if (cfd < 0) {
            cfd = accept(lfd, NULL, NULL);
            if (cfd >= 0) (void)setsockopt(cfd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
            continue;
        }
        uint8_t in[512], out[4096];
        ssize_t n = recv(cfd, in, sizeof in, 0);
        if (n <= 0) {
            close(cfd);
            cfd = -1;
            continue;
        }
        size_t m = busmodel_feed(in, (size_t)n, out, sizeof out, now_ms());
        bytes_in += (unsigned long)n;
        bytes_out += m;
        for (size_t done = 0; done < m;) {
            ssize_t w = send(cfd, out + done, m - done, MSG_NOSIGNAL);
            if (w <= 0) break;
            done += (size_t)w;
        }
    }
}
