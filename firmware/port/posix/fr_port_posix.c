/* firmware/port/posix/fr_port_posix.c: the posix port. Host UDP sockets stand in for the GS1500M: one
 * socket bound to the robot's receive address (port 3838), which also sends, so the gateway sees the robot at
 * that IP address. Environment (read once, at the first call):
 *   FR_POSIX_BIND   ip:port to receive on (default 0.0.0.0:3838); a test gives each robot its own loopback IP
 *   FR_POSIX_LOSS   percent of datagrams lost in each direction (default 0), for the stream's tests
 *   FR_POSIX_SEED   seed of that loss (default 1), so a run can be repeated
 *   FR_POSIX_LINK   a file: while it exists the module reports the network lost (the link-loss tests)
 * The boot epoch lives in a file, `epoch=<path>` on the robot's command line (default: robot.epoch beside the
 * binary); one file may serve several robots, each start taking the next number under a lock. */
#define _POSIX_C_SOURCE 200809L
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>
#include "fr_port.h"

/** The port's state: the socket and the test knobs from the environment. */
static struct {
    int fd;
    bool ready;
    unsigned loss;
    uint32_t rng;
    const char *link_file;
    struct timespec start;
} px = {-1, false, 0, 1, NULL, {0, 0}};

/** A pseudo-random number (xorshift32), for repeatable loss. */
static uint32_t next_random(void) {
    px.rng ^= px.rng << 13;
    px.rng ^= px.rng >> 17;
    px.rng ^= px.rng << 5;
    return px.rng;
}

/** Whether this datagram is lost (FR_POSIX_LOSS percent of them). */
static bool lose(void) { return px.loss > 0 && next_random() % 100u < px.loss; }

/** Opens the socket on first use; exits the process when the address cannot be bound (a test set-up error). */
static void ensure_ready(void) {
    if (px.ready) return;
    px.ready = true;
    clock_gettime(CLOCK_MONOTONIC, &px.start);
    const char *bind_to = getenv("FR_POSIX_BIND");
    const char *loss = getenv("FR_POSIX_LOSS");
    const char *seed = getenv("FR_POSIX_SEED");
    px.link_file = getenv("FR_POSIX_LINK");
    if (loss) px.loss = (unsigned)strtoul(loss, NULL, 10);
    if (seed) px.rng = (uint32_t)strtoul(seed, NULL, 10);
    if (px.rng == 0) px.rng = 1;
    char host[64] = "0.0.0.0";
    unsigned port = 3838;
    if (bind_to) {
        const char *colon = strrchr(bind_to, ':');
        size_t n = colon ? (size_t)(colon - bind_to) : strlen(bind_to);
        if (n >= sizeof host) n = sizeof host - 1;
        memcpy(host, bind_to, n);
        host[n] = '\0';
        if (colon) port = (unsigned)strtoul(colon + 1, NULL, 10);
    }
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    px.fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0);
    int one = 1;
    if (px.fd < 0 || inet_pton(AF_INET, host, &a.sin_addr) != 1 ||
        setsockopt(px.fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        setsockopt(px.fd, SOL_SOCKET, SO_BROADCAST, &one, sizeof one) != 0 ||
        bind(px.fd, (struct sockaddr *)&a, sizeof a) != 0) {
        fprintf(stderr, "fr_port_posix: cannot bind %s:%u: %s\n", host, port, strerror(errno));
        exit(3);
    }
}

uint32_t fr_port_millis(void) {
    ensure_ready();
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    int64_t ms = (int64_t)(now.tv_sec - px.start.tv_sec) * 1000 + (now.tv_nsec - px.start.tv_nsec) / 1000000;
    return (uint32_t)ms;
}

int fr_port_send(const fr_endpoint_t *to, const uint8_t *data, size_t len) {
    ensure_ready();
    if (!fr_port_link_up()) return -1;
    if (lose()) return 0; /* lost on the radio: the sender cannot know */
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons(to->port);
    memcpy(&a.sin_addr.s_addr, to->ip, 4);
    ssize_t n = sendto(px.fd, data, len, 0, (struct sockaddr *)&a, sizeof a);
    return n == (ssize_t)len ? 0 : -1;
}

/** A host is no board: nothing to report. */
bool fr_port_board_health(fr_board_health_t *out) {
    (void)out;
    return false;
}

/** Sockets copy both ways: the library's buffer is always free. */
bool fr_port_frame_free(void) { return true; }

int fr_port_recv(fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    ensure_ready();
    for (;;) {
        struct sockaddr_in a;
        socklen_t alen = sizeof a;
        ssize_t n = recvfrom(px.fd, buf, cap, MSG_TRUNC, (struct sockaddr *)&a, &alen);
        if (n < 0) return 0; /* EAGAIN: nothing waiting */
        if (lose()) continue;
        memcpy(from->ip, &a.sin_addr.s_addr, 4);
        from->port = ntohs(a.sin_port);
        if ((size_t)n > cap) return -1;
        if (!fr_port_link_up()) return 0; /* no network: the module passes nothing on */
        return (int)n;
    }
}

bool fr_port_link_up(void) {
    return px.link_file == NULL || access(px.link_file, F_OK) != 0;
}

void fr_port_idle(void) {
    ensure_ready();
    struct pollfd p = {px.fd, POLLIN, 0};
    (void)poll(&p, 1, 2); /* at most 2 ms: a datagram wakes it at once */
}

/** The epoch file given with `epoch=`; empty = robot.epoch beside the binary. */
static char epoch_path[512];

bool fr_port_option(const char *arg) {
    if (strncmp(arg, "epoch=", 6) != 0 || arg[6] == '\0' || strlen(arg + 6) >= sizeof epoch_path - 8) return false;
    strcpy(epoch_path, arg + 6);
    return true;
}

void fr_port_log(const char *text) {
    fprintf(stderr, "%s\n", text);
    fflush(stderr);
}

/** Reports an epoch file problem on stderr; always -1. */
static int epoch_error(const char *path, const char *what) {
    fprintf(stderr, "fr_port_posix: epoch file %s: %s\n", path, what);
    return -1;
}

int fr_port_epoch_next(uint32_t *epoch) {
    char path[sizeof epoch_path], lock[sizeof epoch_path + 8], tmp[sizeof epoch_path + 8];
    if (epoch_path[0]) {
        strcpy(path, epoch_path);
    } else {
        ssize_t n = readlink("/proc/self/exe", path, sizeof path - 16);
        char *slash = n > 0 ? memchr(path, '/', (size_t)n) : NULL;
        if (slash == NULL) strcpy(path, "robot.epoch");
        else {
            path[n] = '\0';
            strcpy(strrchr(path, '/') + 1, "robot.epoch");
        }
    }
    snprintf(lock, sizeof lock, "%s.lock", path);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    /* One start at a time takes a number: an exclusive lock on a file beside it (the epoch file itself is replaced
     * by rename, so it cannot carry the lock). */
    int lfd = open(lock, O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    if (lfd < 0) return epoch_error(lock, strerror(errno));
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    if (fcntl(lfd, F_SETLKW, &fl) != 0) { close(lfd); return epoch_error(lock, strerror(errno)); }
    int result = -1;
    uint64_t last = 0;
    FILE *f = fopen(path, "r");
    if (f == NULL && errno != ENOENT) { result = epoch_error(path, strerror(errno)); goto done; }
    if (f != NULL) {
        char text[24];
        size_t n = fread(text, 1, sizeof text - 1, f);
        fclose(f);
        text[n] = '\0';
        size_t k = 0;
        for (; k < n && text[k] >= '0' && text[k] <= '9' && last <= UINT32_MAX; k++) last = last * 10u + (uint64_t)(text[k] - '0');
        if (k == 0 || k > 10 || last > UINT32_MAX || (k < n && strcmp(text + k, "\n") != 0)) {
            result = epoch_error(path, "damaged (not one decimal number): refusing to guess an epoch");
            goto done;
        }
    }
    if (last >= UINT32_MAX) { result = epoch_error(path, "used up (4294967295 starts)"); goto done; }
    FILE *out = fopen(tmp, "w");
    if (out == NULL) { result = epoch_error(tmp, strerror(errno)); goto done; }
    bool ok = fprintf(out, "%lu\n", (unsigned long)(last + 1u)) > 0 && fflush(out) == 0 && fsync(fileno(out)) == 0;
    ok = fclose(out) == 0 && ok;
    if (!ok || rename(tmp, path) != 0) { result = epoch_error(path, strerror(errno)); goto done; }
    *epoch = (uint32_t)(last + 1u);
    result = 0;
done:
    close(lfd); /* releases the lock */
    return result;
}
