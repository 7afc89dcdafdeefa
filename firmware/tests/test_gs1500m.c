/* firmware/tests/test_gs1500m.c: unit tests of the GS1500M driver on the host, against the serial examples of
 * docs/protocol.md section 12, the start-up the thesis describes (4.3, 5.1, 8.1), and hostile byte streams. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gs1500m.h"

static int passed, failed;

#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (cond) passed++;                                                          \
        else {                                                                       \
            failed++;                                                                \
            printf("FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond);                   \
        }                                                                            \
    } while (0)

static gs1500m_t gs;

static const fr_endpoint_t base = {{192, 168, 1, 10}, 11011};

/* The `Status` frame of protocol.md 9.1 (30 bytes). */
static const uint8_t status_frame[30] = {0x00, 0x2A, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x12,
                                         0x08, 0x01, 0xBA, 0x01, 0x0D, 0x10, 0x01, 0x62, 0x09, 0x41, 0x67, 0x65,
                                         0x6E, 0x74, 0x54, 0x65, 0x73, 0x74};

/* protocol.md 12, example serial-send-status. */
static const uint8_t serial_send_status[37] = {0x1B, 0x5A, 0x30, 0x30, 0x30, 0x33, 0x30, 0x00, 0x2A, 0x00,
                                               0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x12, 0x08,
                                               0x01, 0xBA, 0x01, 0x0D, 0x10, 0x01, 0x62, 0x09, 0x41, 0x67,
                                               0x65, 0x6E, 0x74, 0x54, 0x65, 0x73, 0x74};

/* protocol.md 12, example serial-receive-udp-server: the optionPull of 9.8 from 192.168.1.10:11011. */
static const uint8_t serial_receive_udp_server[46] = {
    0x1B, 0x79, 0x30, 0x31, 0x39, 0x32, 0x2E, 0x31, 0x36, 0x38, 0x2E, 0x31, 0x2E, 0x31, 0x30, 0x20,
    0x31, 0x31, 0x30, 0x31, 0x31, 0x09, 0x30, 0x30, 0x32, 0x30, 0x00, 0x2A, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x00, 0x00, 0x00, 0x00, 0x08, 0x08, 0x01, 0xEA, 0xBB, 0x03, 0x02, 0x08, 0x01};

static void feed(const void *bytes, size_t n) {
    const uint8_t *b = bytes;
    for (size_t i = 0; i < n; i++) gs1500m_rx_push(&gs, b[i]);
}

static void feeds(const char *text) { feed(text, strlen(text)); }

/* Everything the driver has put on the line since the last call, as a string (binary-safe length in *len). */
static size_t drain(uint8_t *out, size_t cap) {
    size_t n = 0;
    uint8_t b;
    while (gs1500m_tx_pop(&gs, &b))
        if (n < cap) out[n++] = b;
    return n;
}

static int drained_equals(const char *text) {
    uint8_t out[2048];
    size_t n = drain(out, sizeof out);
    int same = n == strlen(text) && memcmp(out, text, n) == 0;
    if (!same) printf("  line had %zu bytes: %.*s\n", n, (int)n, (const char *)out);
    return same;
}

static int recv_at(uint32_t now, fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    return gs1500m_recv(&gs, now, from, buf, cap);
}

/* Runs the driver from power-up to READY against a scripted module; returns the time reached. */
static uint32_t bring_up(void) {
    gs1500m_config_t config = {base, GS1500M_SERVER_PORT, GS1500M_BOOT_MS, 460800u, 0u};
    uint8_t buf[8];
    gs1500m_init(&gs, &config, 0);
    recv_at(100, NULL, buf, sizeof buf);
    recv_at(4000, NULL, buf, sizeof buf);
    drain(buf, 0);
    feeds("OK\r\n");
    recv_at(4001, NULL, buf, sizeof buf);
    recv_at(4002, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(4003, NULL, buf, sizeof buf);
    recv_at(4004, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(4005, NULL, buf, sizeof buf);
    recv_at(4006, NULL, buf, sizeof buf);
    feeds("CONNECT 0\r\nOK\r\n");
    recv_at(4007, NULL, buf, sizeof buf);
    recv_at(4008, NULL, buf, sizeof buf);
    feeds("CONNECT 1\r\nOK\r\n");
    recv_at(4009, NULL, buf, sizeof buf);
    drain(buf, 0);
    return 4009;
}

static void test_startup(void) {
    gs1500m_config_t config = {base, GS1500M_SERVER_PORT, GS1500M_BOOT_MS, 460800u, 0u};
    uint8_t buf[64];
    gs1500m_init(&gs, &config, 0);
    CHECK(gs1500m_state(&gs) == GS1500M_BOOTING);
    /* The module boots for about 4 s and hears nothing: the driver says nothing. */
    CHECK(recv_at(3999, NULL, buf, sizeof buf) == 0);
    CHECK(drained_equals(""));
    CHECK(recv_at(4000, NULL, buf, sizeof buf) == 0);
    CHECK(gs1500m_state(&gs) == GS1500M_PROBING);
    CHECK(drained_equals("AT\r\n"));
    /* Silence while it joins: `AT` again every 500 ms, not more often. */
    recv_at(4499, NULL, buf, sizeof buf);
    CHECK(drained_equals(""));
    recv_at(4500, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT\r\n"));
    /* The boot banner and the echo are not an answer. */
    feeds("\r\nSerial2WiFi APP\r\nAT\r\r\n");
    recv_at(4600, NULL, buf, sizeof buf);
    CHECK(gs1500m_state(&gs) == GS1500M_PROBING);
    recv_at(5100, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT\r\n"));
    feeds("AT\r\r\nOK\r\n");
    recv_at(5110, NULL, buf, sizeof buf);
    CHECK(gs1500m_state(&gs) == GS1500M_CONFIGURING);
    recv_at(5111, NULL, buf, sizeof buf);
    CHECK(drained_equals("ATE0\r\n"));
    feeds("ATE0\r\r\nOK\r\n");
    recv_at(5112, NULL, buf, sizeof buf);
    recv_at(5113, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT+BDATA=1\r\n"));
    feeds("\r\nOK\r\n");
    recv_at(5114, NULL, buf, sizeof buf);
    recv_at(5115, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT+NCUDP=192.168.1.10,11011\r\n"));
    CHECK(!gs1500m_link_up(&gs));
    feeds("\r\nCONNECT 0\r\n\r\nOK\r\n");
    recv_at(5116, NULL, buf, sizeof buf);
    recv_at(5117, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT+NSUDP=3838\r\n"));
    CHECK(!gs1500m_link_up(&gs));
    feeds("\r\nCONNECT 1\r\n\r\nOK\r\n");
    recv_at(5118, NULL, buf, sizeof buf);
    CHECK(gs1500m_link_up(&gs));
    CHECK(gs1500m_state(&gs) == GS1500M_READY);
    CHECK(gs1500m_stats(&gs)->restarts == 0);
}

/* A program that only asks whether the link is up (fr_port_link_up) still brings the module up, and a datagram
 * that arrives meanwhile waits for gs1500m_recv. */
static void test_startup_by_tick_alone(void) {
    gs1500m_config_t config = {base, GS1500M_SERVER_PORT, 10, 460800u, 0u};
    uint8_t buf[64];
    fr_endpoint_t from;
    gs1500m_init(&gs, &config, 0);
    const char *answers[] = {"OK\r\n", "OK\r\n", "OK\r\n", "CONNECT 0\r\nOK\r\n", "CONNECT 1\r\nOK\r\n"};
    uint32_t now = 10;
    for (int i = 0; i < 5; i++) {
        gs1500m_tick(&gs, now++);
        drain(buf, 0);
        feeds(answers[i]);
    }
    feed(serial_send_status, sizeof serial_send_status);
    gs1500m_tick(&gs, now++);
    CHECK(gs1500m_link_up(&gs));
    CHECK(gs1500m_recv(&gs, now, &from, buf, sizeof buf) == 30);
    CHECK(memcmp(buf, status_frame, 30) == 0);
}

static void test_startup_retries(void) {
    gs1500m_config_t config = {base, GS1500M_SERVER_PORT, 100, 460800u, 0u};
    uint8_t buf[64];
    gs1500m_init(&gs, &config, 1000);
    recv_at(1100, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT\r\n"));
    feeds("OK\r\n");
    recv_at(1101, NULL, buf, sizeof buf);
    recv_at(1102, NULL, buf, sizeof buf);
    CHECK(drained_equals("ATE0\r\n"));
    /* An ERROR starts over with `AT`, after a probe interval. */
    feeds("ERROR\r\n");
    recv_at(1103, NULL, buf, sizeof buf);
    CHECK(gs1500m_state(&gs) == GS1500M_PROBING);
    CHECK(gs1500m_stats(&gs)->restarts == 1);
    recv_at(1602, NULL, buf, sizeof buf);
    CHECK(drained_equals(""));
    recv_at(1603, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT\r\n"));
    feeds("OK\r\n");
    recv_at(1604, NULL, buf, sizeof buf);
    recv_at(1605, NULL, buf, sizeof buf);
    CHECK(drained_equals("ATE0\r\n"));
    /* No answer within the reply time: over again too. */
    recv_at(1605 + GS1500M_REPLY_MS, NULL, buf, sizeof buf);
    CHECK(gs1500m_state(&gs) == GS1500M_PROBING);
    CHECK(gs1500m_stats(&gs)->restarts == 2);
    /* An OK for the client without its CONNECT: no connection id, so over again. */
    recv_at(5000, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(5001, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(5002, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(5003, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(5004, NULL, buf, sizeof buf);
    recv_at(5005, NULL, buf, sizeof buf);
    drain(buf, 0);
    CHECK(gs1500m_state(&gs) == GS1500M_PROBING);
    CHECK(gs1500m_stats(&gs)->restarts == 3);
}

static void test_send_matches_protocol_example(void) {
    uint32_t now = bring_up();
    uint8_t line[64];
    CHECK(gs1500m_send(&gs, now, &base, status_frame, sizeof status_frame) == 0);
    size_t n = drain(line, sizeof line);
    CHECK(n == sizeof serial_send_status && memcmp(line, serial_send_status, n) == 0);
    CHECK(gs1500m_stats(&gs)->datagrams_out == 1);
    /* Four-digit lengths: 1400 is the largest, one more is refused. */
    static uint8_t big[GS1500M_MAX_DATAGRAM + 1];
    CHECK(gs1500m_send(&gs, now, &base, big, GS1500M_MAX_DATAGRAM) == 0);
    uint8_t head[7];
    CHECK(gs1500m_tx_pop(&gs, &head[0]) && gs1500m_tx_pop(&gs, &head[1]) && gs1500m_tx_pop(&gs, &head[2]));
    CHECK(gs1500m_tx_pop(&gs, &head[3]) && gs1500m_tx_pop(&gs, &head[4]) && gs1500m_tx_pop(&gs, &head[5]));
    CHECK(gs1500m_tx_pop(&gs, &head[6]) && memcmp(head, "\x1bZ01400", 7) == 0);
    drain(big, 0);
    CHECK(gs1500m_send(&gs, now, &base, big, GS1500M_MAX_DATAGRAM + 1) < 0);
    CHECK(gs1500m_send(&gs, now, &base, big, 0) < 0);
    /* A full transmit ring refuses without blocking; once the UART took the bytes it accepts again. */
    CHECK(gs1500m_send(&gs, now, &base, big, 1000) == 0);
    CHECK(gs1500m_send(&gs, now, &base, big, 1000) < 0);
    drain(big, 0);
    CHECK(gs1500m_send(&gs, now, &base, big, 1000) == 0);
    drain(big, 0);
}

static void test_send_before_ready_and_new_destination(void) {
    gs1500m_config_t config = {base, GS1500M_SERVER_PORT, GS1500M_BOOT_MS, 460800u, 0u};
    uint8_t buf[64];
    gs1500m_init(&gs, &config, 0);
    CHECK(gs1500m_send(&gs, 10, &base, status_frame, 30) < 0);
    CHECK(gs1500m_stats(&gs)->send_busy == 1);
    uint32_t now = bring_up();
    /* The GameController's return address: a connection is opened first, the datagram is refused meanwhile. */
    fr_endpoint_t gc = {{192, 168, 1, 20}, 3838};
    CHECK(gs1500m_send(&gs, now, &gc, status_frame, 8) < 0);
    CHECK(drained_equals("AT+NCUDP=192.168.1.20,3838\r\n"));
    CHECK(gs1500m_send(&gs, now, &gc, status_frame, 8) < 0);
    CHECK(drained_equals(""));
    /* Other destinations still flow meanwhile. */
    CHECK(gs1500m_send(&gs, now, &base, status_frame, 2) == 0);
    uint8_t line[16];
    CHECK(drain(line, sizeof line) == 9 && memcmp(line, "\x1bZ00002\x00*", 9) == 0);
    feeds("CONNECT 2\r\nOK\r\n");
    CHECK(recv_at(now + 1, NULL, buf, sizeof buf) == 0);
    CHECK(gs1500m_send(&gs, now + 2, &gc, (const uint8_t *)"RGrt", 4) == 0);
    CHECK(drained_equals("\x1bZ20004RGrt"));
    /* A destination the module refuses is forgotten, and asked for again on the next send. */
    fr_endpoint_t other = {{10, 0, 0, 1}, 9};
    CHECK(gs1500m_send(&gs, now + 3, &other, status_frame, 4) < 0);
    CHECK(drained_equals("AT+NCUDP=10.0.0.1,9\r\n"));
    feeds("ERROR: INVALID INPUT\r\n");
    recv_at(now + 4, NULL, buf, sizeof buf);
    CHECK(gs1500m_send(&gs, now + 5, &other, status_frame, 4) < 0);
    CHECK(drained_equals("AT+NCUDP=10.0.0.1,9\r\n"));
    /* A DISCONNECT of that destination frees its slot; the link stays up. */
    feeds("CONNECT 3\r\nOK\r\nDISCONNECT 3\r\n");
    recv_at(now + 6, NULL, buf, sizeof buf);
    CHECK(gs1500m_link_up(&gs));
    CHECK(gs1500m_send(&gs, now + 7, &other, status_frame, 4) < 0);
    CHECK(drained_equals("AT+NCUDP=10.0.0.1,9\r\n"));
}

static void test_receive_matches_protocol_example(void) {
    uint32_t now = bring_up();
    uint8_t buf[GS1500M_MAX_DATAGRAM];
    fr_endpoint_t from;
    feed(serial_receive_udp_server, sizeof serial_receive_udp_server);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 20);
    CHECK(memcmp(buf, serial_receive_udp_server + 26, 20) == 0);
    CHECK(memcmp(from.ip, base.ip, 4) == 0 && from.port == 11011);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 0);
    /* `ESC Z` on the client connection comes from its destination; replies and lines in between are no data. */
    feeds("\x1bO\x1b" "F\x1bRCONNECT 5 6 10.0.0.9 4000\r\n");
    feed(serial_send_status, sizeof serial_send_status);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 30);
    CHECK(memcmp(buf, status_frame, 30) == 0);
    CHECK(memcmp(from.ip, base.ip, 4) == 0 && from.port == base.port);
    CHECK(gs1500m_stats(&gs)->acks == 1 && gs1500m_stats(&gs)->fails == 1 && gs1500m_stats(&gs)->other_replies == 1);
    /* Bulk data carry no escaping: ESC and line ends inside the data are data. */
    feeds("\x1by1127.0.0.1:9\t0005\x1bZ\r\n\x1b");
    CHECK(recv_at(now, &from, buf, sizeof buf) == 5);
    CHECK(memcmp(buf, "\x1bZ\r\n\x1b", 5) == 0 && from.port == 9 && from.ip[0] == 127 && from.ip[3] == 1);
    /* Too long for the program's buffer: dropped and reported; the next one is whole. */
    feed(serial_receive_udp_server, sizeof serial_receive_udp_server);
    feed(serial_send_status, sizeof serial_send_status);
    CHECK(recv_at(now, &from, buf, 10) == -1);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 30);
    CHECK(gs1500m_stats(&gs)->too_long == 1);
    CHECK(gs1500m_stats(&gs)->datagrams_in == 4);
}

static void test_byte_by_byte_equals_whole(void) {
    uint32_t now = bring_up();
    uint8_t buf[GS1500M_MAX_DATAGRAM];
    fr_endpoint_t from;
    int got = 0;
    CHECK(!gs1500m_rx_ready(&gs));
    for (size_t i = 0; i < sizeof serial_receive_udp_server; i++) {
        gs1500m_rx_push(&gs, serial_receive_udp_server[i]);
        /* every byte is work: a header byte for the parser, a data byte to copy out of the ring */
        CHECK(gs1500m_rx_ready(&gs));
        int r = recv_at(now, &from, buf, sizeof buf);
        /* from the end of the header to the last data byte the datagram is being copied into buf */
        CHECK(gs1500m_rx_busy(&gs) == (i >= 25 && i + 1 < sizeof serial_receive_udp_server));
        if (i + 1 < sizeof serial_receive_udp_server) CHECK(r == 0);
        else got = r;
    }
    CHECK(got == 20 && memcmp(buf, serial_receive_udp_server + 26, 20) == 0 && from.port == 11011);
}

static void test_damaged_frames(void) {
    uint32_t now = bring_up();
    uint8_t buf[GS1500M_MAX_DATAGRAM];
    fr_endpoint_t from;
    /* The tail of a datagram whose beginning (and header) the module overwrote (thesis 6.1), then a whole one:
     * one loss is reported, then the datagram. */
    feed(serial_receive_udp_server + 30, sizeof serial_receive_udp_server - 30);
    feed(serial_receive_udp_server, sizeof serial_receive_udp_server);
    CHECK(recv_at(now, &from, buf, sizeof buf) == -2);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 20);
    CHECK(gs1500m_stats(&gs)->garbage_bytes == 16);
    /* A broken header (a letter in the length) is garbage up to the next ESC. */
    feeds("\x1bZ00x3abc");
    feed(serial_send_status, sizeof serial_send_status);
    CHECK(recv_at(now, &from, buf, sizeof buf) == -2);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 30);
    /* A length over 1400 likewise. */
    feeds("\x1bZ01401zz\r\n");
    feed(serial_send_status, sizeof serial_send_status);
    CHECK(recv_at(now, &from, buf, sizeof buf) == -2);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 30);
    /* A header whose data never come in full: after GS1500M_PAYLOAD_MS its bytes are read again. */
    feeds("\x1bZ00999short");
    CHECK(recv_at(now, &from, buf, sizeof buf) == 0);
    CHECK(recv_at(now + GS1500M_PAYLOAD_MS - 1, &from, buf, sizeof buf) == 0);
    CHECK(recv_at(now + GS1500M_PAYLOAD_MS, &from, buf, sizeof buf) == -2);
    feeds("\r\n");
    feed(serial_send_status, sizeof serial_send_status);
    CHECK(recv_at(now + GS1500M_PAYLOAD_MS, &from, buf, sizeof buf) == 30);
    CHECK(gs1500m_stats(&gs)->payload_timeouts == 1);
    /* An over-long status line is dropped, not cut and acted on. */
    char longline[GS1500M_LINE_MAX + 20];
    memset(longline, 'x', sizeof longline);
    memcpy(longline + GS1500M_LINE_MAX + 5, "OK\r\n", 4);
    feed(longline, GS1500M_LINE_MAX + 9);
    feed(serial_send_status, sizeof serial_send_status);
    CHECK(recv_at(now + GS1500M_PAYLOAD_MS, &from, buf, sizeof buf) == -2);
    CHECK(recv_at(now + GS1500M_PAYLOAD_MS, &from, buf, sizeof buf) == 30);
    CHECK(gs1500m_link_up(&gs));
}

static void test_link_loss(void) {
    uint32_t now = bring_up();
    uint8_t buf[64];
    CHECK(gs1500m_link_up(&gs));
    feeds("\r\nDISASSOCIATED\r\n");
    recv_at(now, NULL, buf, sizeof buf);
    CHECK(!gs1500m_link_up(&gs));
    CHECK(gs1500m_stats(&gs)->link_losses == 1);
    CHECK(gs1500m_send(&gs, now, &base, status_frame, 30) < 0);
    /* It comes back by itself: probe, commands, connections anew. */
    recv_at(now + GS1500M_PROBE_MS, NULL, buf, sizeof buf);
    CHECK(drained_equals("AT\r\n"));
    feeds("OK\r\n");
    recv_at(now + 501, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(now + 502, NULL, buf, sizeof buf);
    feeds("OK\r\n");
    recv_at(now + 503, NULL, buf, sizeof buf);
    feeds("CONNECT 3\r\nOK\r\n");
    recv_at(now + 504, NULL, buf, sizeof buf);
    feeds("CONNECT 4\r\nOK\r\n");
    recv_at(now + 505, NULL, buf, sizeof buf);
    CHECK(gs1500m_link_up(&gs));
    drain(buf, 0);
    CHECK(gs1500m_send(&gs, now + 506, &base, (const uint8_t *)"ab", 2) == 0);
    CHECK(drained_equals("\x1bZ30002" "ab"));
    /* The server's DISCONNECT and a module reset end the link too; another connection's does not. */
    feeds("DISCONNECT 9\r\n");
    recv_at(now + 507, NULL, buf, sizeof buf);
    CHECK(gs1500m_link_up(&gs));
    feeds("DISCONNECT 4\r\n");
    recv_at(now + 508, NULL, buf, sizeof buf);
    CHECK(!gs1500m_link_up(&gs));
    CHECK(gs1500m_stats(&gs)->link_losses == 2);
    now = bring_up();
    feeds("Serial2WiFi APP\r\n");
    recv_at(now, NULL, buf, sizeof buf);
    CHECK(!gs1500m_link_up(&gs));
}

/* A datagram longer than the receive ring: its data leave the ring for the caller's buffer as they arrive, so it
 * comes through whole as long as the caller keeps up (here: a recv after every ring's worth). */
static void test_datagram_longer_than_ring(void) {
    uint32_t now = bring_up();
    static uint8_t buf[GS1500M_MAX_DATAGRAM], data[GS1500M_MAX_DATAGRAM];
    fr_endpoint_t from;
    for (size_t i = 0; i < sizeof data; i++) data[i] = (uint8_t)(i * 31u + 7u);
    feeds("\x1bZ01400");
    size_t fed = 0;
    int r = 0;
    while (fed < sizeof data) {
        size_t n = sizeof data - fed < GS1500M_RX_RING / 2 ? sizeof data - fed : GS1500M_RX_RING / 2;
        feed(data + fed, n);
        fed += n;
        r = recv_at(now, &from, buf, sizeof buf);
        if (fed < sizeof data) CHECK(r == 0 && gs1500m_rx_busy(&gs));
    }
    CHECK(r == (int)sizeof data && memcmp(buf, data, sizeof data) == 0);
    CHECK(!gs1500m_rx_busy(&gs) && gs1500m_stats(&gs)->rx_overruns == 0);
    /* longer than the caller's buffer: its data are dropped as they come, then the loss is reported */
    feeds("\x1bZ00300");
    feed(data, 300);
    CHECK(recv_at(now, &from, buf, 100) == -1);
    CHECK(gs1500m_stats(&gs)->too_long == 1);
    feed(serial_send_status, sizeof serial_send_status);
    CHECK(recv_at(now, &from, buf, sizeof buf) == 30 && memcmp(buf, status_frame, 30) == 0);
}

/* A long datagram is sent from the caller's memory: the header goes through the ring, the data from `data`, and
 * nothing is copied into a receive buffer meanwhile (it may be the same memory). */
static void test_send_from_caller_memory(void) {
    uint32_t now = bring_up();
    static uint8_t frame[GS1500M_MAX_DATAGRAM];
    static uint8_t out[2 * GS1500M_MAX_DATAGRAM];
    uint8_t small[3] = {'a', 'b', 'c'};
    fr_endpoint_t from;
    for (size_t i = 0; i < 1000; i++) frame[i] = (uint8_t)(i ^ 0x5Au);
    CHECK(gs1500m_send(&gs, now, &base, frame, 1000) == 0);
    CHECK(gs1500m_tx_busy(&gs) && gs1500m_tx_pending(&gs));
    /* a second long one waits for the first; a short one is copied and goes after it */
    CHECK(gs1500m_send(&gs, now, &base, frame, 500) < 0);
    CHECK(gs1500m_send(&gs, now, &base, small, sizeof small) == 0);
    /* a datagram arriving meanwhile stays in the ring: the frame is not written while it goes out */
    feed(serial_receive_udp_server, sizeof serial_receive_udp_server);
    CHECK(recv_at(now, &from, frame, sizeof frame) == 0);
    CHECK(gs1500m_rx_busy(&gs) && frame[0] == 0x5A);
    size_t n = drain(out, sizeof out);
    CHECK(!gs1500m_tx_busy(&gs) && !gs1500m_tx_pending(&gs));
    CHECK(n == 7 + 1000 + 7 + 3);
    CHECK(memcmp(out, "\x1bZ01000", 7) == 0);
    int same = 1;
    for (size_t i = 0; i < 1000; i++) same &= out[7 + i] == (uint8_t)(i ^ 0x5Au);
    CHECK(same);
    CHECK(memcmp(out + 1007, "\x1bZ00003abc", 10) == 0);
    /* the line is free: the waiting datagram is copied into the frame now */
    CHECK(recv_at(now, &from, frame, sizeof frame) == 20 && frame[0] == 0x00 && frame[1] == 0x2A);
}

/* A module still at its factory rate answers nothing at the board's: after GS1500M_BAUD_PROBES silent probes the
 * driver asks at the factory rate, tells the module the board's rate with ATB and goes on at it. */
static void test_module_at_factory_rate(void) {
    gs1500m_config_t config = {base, GS1500M_SERVER_PORT, 10, 460800u, 9600u};
    uint8_t buf[8];
    gs1500m_init(&gs, &config, 0);
    CHECK(gs1500m_uart_baud(&gs) == 460800u);
    uint32_t now = 10;
    for (unsigned i = 0; i < GS1500M_BAUD_PROBES; i++, now += GS1500M_PROBE_MS) {
        recv_at(now, NULL, buf, sizeof buf);
        CHECK(drained_equals("AT\r\n") && gs1500m_uart_baud(&gs) == 460800u);
    }
    recv_at(now, NULL, buf, sizeof buf);
    CHECK(gs1500m_uart_baud(&gs) == 9600u && drained_equals("AT\r\n"));
    feeds("OK\r\n");
    recv_at(now + 1, NULL, buf, sizeof buf);
    CHECK(drained_equals("ATB=460800\r\n") && gs1500m_uart_baud(&gs) == 9600u);
    feeds("OK\r\n");
    recv_at(now + 2, NULL, buf, sizeof buf);
    /* at the board's rate again: probed at once, then the usual start-up */
    CHECK(gs1500m_uart_baud(&gs) == 460800u && drained_equals("AT\r\n"));
    feeds("OK\r\n");
    recv_at(now + 3, NULL, buf, sizeof buf);
    recv_at(now + 4, NULL, buf, sizeof buf);
    CHECK(drained_equals("ATE0\r\n") && gs1500m_state(&gs) == GS1500M_CONFIGURING);
    /* a module silent at both rates (still booting) is asked at each in turn, never with ATB */
    gs1500m_init(&gs, &config, 0);
    now = 10;
    int switches = 0;
    uint32_t last = gs1500m_uart_baud(&gs);
    for (unsigned i = 0; i < 4 * GS1500M_BAUD_PROBES + 2; i++, now += GS1500M_PROBE_MS) {
        recv_at(now, NULL, buf, sizeof buf);
        CHECK(drained_equals("AT\r\n"));
        if (gs1500m_uart_baud(&gs) != last) switches++;
        last = gs1500m_uart_baud(&gs);
    }
    CHECK(switches == 4);
    /* without a factory rate the driver never leaves the board's */
    config.factory_baud = 0u;
    gs1500m_init(&gs, &config, 0);
    for (now = 10; now < 10 + 10 * GS1500M_PROBE_MS; now += GS1500M_PROBE_MS) recv_at(now, NULL, buf, sizeof buf);
    CHECK(gs1500m_uart_baud(&gs) == 460800u);
    drain(buf, 0);
}

static void test_rx_overrun(void) {
    bring_up();
    int accepted = 0;
    for (int i = 0; i < 3000; i++) accepted += gs1500m_rx_push(&gs, 'x');
    CHECK(accepted == GS1500M_RX_RING - 1);
    CHECK(gs1500m_stats(&gs)->rx_overruns == (uint32_t)(3000 - (GS1500M_RX_RING - 1)));
}

static uint32_t rng = 12345;
static uint32_t next_random(void) {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

/* Random bytes weighted towards the ones the parser cares about, so headers and lines half-form often. */
static uint8_t hostile_byte(void) {
    static const uint8_t special[] = {0x1B, 'Z', 'y', 'O', 'F', '0', '1', '4', '9', '\t', '\r', '\n', ' ', '.', ':'};
    uint32_t r = next_random();
    return (r & 1u) ? special[(r >> 1) % sizeof special] : (uint8_t)(r >> 8);
}

static void test_hostile_streams(void) {
    uint8_t buf[GS1500M_MAX_DATAGRAM + 16];
    int bad_length = 0, bad_bounds = 0, lost_frames = 0, runs = 300;
    for (int run = 0; run < runs; run++) {
        uint32_t now = bring_up();
        size_t cap = 1 + next_random() % GS1500M_MAX_DATAGRAM;
        /* A guard after the program's buffer: the driver must never write past `cap`. */
        memset(buf, 0xA5, sizeof buf);
        int total = 2000 + (int)(next_random() % 6000);
        for (int i = 0; i < total;) {
            int chunk = 1 + (int)(next_random() % 300);
            for (int k = 0; k < chunk && i < total; k++, i++) gs1500m_rx_push(&gs, hostile_byte());
            if (next_random() % 4 == 0) gs1500m_send(&gs, now, &base, buf, next_random() % 1500);
            drain(buf + cap, 0);
            now += next_random() % 50;
            for (int calls = 0; calls < 64; calls++) {
                fr_endpoint_t from;
                int r = recv_at(now, &from, buf, cap);
                if (r > (int)cap || r > GS1500M_MAX_DATAGRAM || r < -2) bad_length++;
                if (r == 0) break;
            }
            if (gs.rx_head >= GS1500M_RX_RING || gs.rx_tail >= GS1500M_RX_RING || gs.tx_head >= GS1500M_TX_RING ||
                gs.tx_tail >= GS1500M_TX_RING || gs.line_len > GS1500M_LINE_MAX)
                bad_bounds++;
        }
        for (size_t g = cap; g < sizeof buf; g++)
            if (buf[g] != 0xA5) { bad_bounds++; break; }
        /* Afterwards the stream recovers: a stale header times out, a line end ends any half item, and the next
         * datagram comes whole. Each timeout consumes a header, so this ends. */
        gs.stats.status_lines = 0;
        for (int k = 0; k < 64; k++) {
            now += GS1500M_PAYLOAD_MS;
            while (recv_at(now, NULL, buf, cap) != 0) {
            }
        }
        feeds("\r\n");
        feed(serial_receive_udp_server, sizeof serial_receive_udp_server);
        int r;
        do r = recv_at(now, NULL, buf, sizeof buf);
        while (r < 0);
        if (r != 20 || memcmp(buf, serial_receive_udp_server + 26, 20) != 0) lost_frames++;
    }
    CHECK(bad_length == 0);
    CHECK(bad_bounds == 0);
    CHECK(lost_frames == 0);
}

int main(void) {
    test_startup();
    test_startup_by_tick_alone();
    test_startup_retries();
    test_send_matches_protocol_example();
    test_send_before_ready_and_new_destination();
    test_receive_matches_protocol_example();
    test_byte_by_byte_equals_whole();
    test_damaged_frames();
    test_link_loss();
    test_rx_overrun();
    test_datagram_longer_than_ring();
    test_module_at_factory_rate();
    test_send_from_caller_memory();
    test_hostile_streams();
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}
