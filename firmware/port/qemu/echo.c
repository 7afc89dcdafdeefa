/* firmware/port/qemu/echo.c: a program for the board without the library, so the serial link, the GS1500M driver
 * and the host's bridge can be tested alone: once the link is up it sends "hello <n>" to the base station every
 * 200 ms and sends every datagram it receives back to its sender; a datagram "exit" ends it. */
#include <string.h>

#include "board.h"
#include "fr_port.h"

static uint8_t buf[GS1500M_MAX_DATAGRAM];
static uint8_t scratch[GS1500M_MAX_DATAGRAM];

/** Writes `v` in decimal at `out`; returns the characters written. */
static size_t put_decimal(char *out, uint32_t v) {
    char tmp[10];
    size_t n = 0, k = 0;
    do tmp[n++] = (char)('0' + v % 10u);
    while ((v /= 10u) != 0u);
    while (n > 0) out[k++] = tmp[--n];
    return k;
}

int main(int argc, char **argv) {
    static const fr_endpoint_t base = {{192, 168, 1, 10}, 11011u};
    (void)argc;
    (void)argv;
    uint32_t hello = 0, last = 0;
    bool up = false;
    board_log("echo: started");
    fr_endpoint_t to;
    int pending = 0; /* a datagram to send back, waiting while the module opens a connection to its sender */
    uint32_t pending_since = 0;
    for (;;) {
        int n = 0;
        if (pending > 0) {
            if (fr_port_send(&to, buf, (size_t)pending) == 0 || fr_port_millis() - pending_since > 2000u) pending = 0;
        }
        /* Receiving goes on meanwhile: the module's answers (CONNECT, OK) come that way. */
        if (pending == 0) n = fr_port_recv(&to, buf, sizeof buf);
        else {
            fr_endpoint_t other;
            (void)fr_port_recv(&other, scratch, sizeof scratch); /* dropped: one echo at a time */
        }
        if (n > 0) {
            if (n == 4 && memcmp(buf, "exit", 4) == 0) {
                board_log("echo: exit");
                return 0;
            }
            pending = n;
            pending_since = fr_port_millis();
        }
        if (fr_port_link_up() != up) {
            up = !up;
            board_log(up ? "echo: link up" : "echo: link down");
        }
        uint32_t now = fr_port_millis();
        if (up && now - last >= 200u) {
            char text[16] = "hello ";
            size_t len = 6 + put_decimal(text + 6, ++hello);
            (void)fr_port_send(&base, (const uint8_t *)text, len);
            last = now;
        }
        if (n == 0 && pending == 0) fr_port_idle();
    }
}
