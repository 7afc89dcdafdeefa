/* firmware/tests/test_stream.c: the secure stream against the datagram sequences of docs/protocol.md 11.9
 * (stop-and-wait, the robot as R) at FR_STREAM_WINDOW 1, and 11.10 (selective repeat, the robot as G) and 11.11
 * (skip notices, the robot as R) at FR_STREAM_WINDOW 4; `make test` builds it for both windows. */
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "../src/fr_internal.h"

static const fr_endpoint_t gateway = {{192, 168, 1, 10}, 11011};
static char got[256];
static size_t got_len;
static bool answer_ok;

static void on_stream(const uint8_t *data, size_t len, void *ctx) {
    (void)ctx;
    memcpy(got + got_len, data, len);
    got_len += len;
    got[got_len] = '\0';
    if (answer_ok && strcmp(got, "Lorem") == 0) CHECK(fr_stream_send((const uint8_t *)"OK", 2));
}

static void start(void) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.development = true; /* unsigned frames: the signed path has its own tests (test_protocol, test_trust) */
    s.gateway = gateway;
    s.callbacks.stream = on_stream;
    fake_now = 0;
    fr_init(&s);
    fr_poll(); /* the first keep-alive */
    fake_clear_sent();
    got_len = 0;
    got[0] = '\0';
}

/** Delivers one segment (hex) and polls; then the segments the robot sent (keep-alives left out) must be `want`
 *  (hex, one segment per '|', empty for none). */
static int sent(const char *want);
static int step(const char *in, const char *want) {
    unsigned char b[64];
    fake_clear_sent();
    if (in) {
        size_t n = hex(in, b);
        fake_receive(&gateway, b, n);
    }
    fr_poll();
    return sent(want);
}

/** Whether the segments sent since the last clear (keep-alives left out) are `want`. */
static int sent(const char *want) {
    char line[256];
    size_t k = 0, out = 0;
    int ok = 1;
    const char *w = want;
    for (;;) {
        const char *bar = strchr(w, '|');
        size_t n = bar ? (size_t)(bar - w) : strlen(w);
        memcpy(line, w, n);
        line[n] = '\0';
        while (k < fake_sent_count && fake_sent[k].len > 2 && fake_sent[k].data[0] == 0 && fake_sent[k].data[1] == 42) k++;
        if (n > 0) {
            if (k >= fake_sent_count) { printf("  missing %s\n", line); ok = 0; }
            else if (!same_bytes(fake_sent[k].data, fake_sent[k].len, line)) ok = 0;
            k++;
            out++;
        }
        if (!bar) break;
        w = bar + 1;
    }
    while (k < fake_sent_count) {
        if (!(fake_sent[k].len > 2 && fake_sent[k].data[0] == 0 && fake_sent[k].data[1] == 42)) {
            printf("  unexpected segment of %zu bytes: %02X %02X\n", fake_sent[k].len, fake_sent[k].data[0], fake_sent[k].data[1]);
            ok = 0;
        }
        k++;
    }
    (void)out;
    return ok;
}

#if FR_STREAM_WINDOW == 1
static void test_window1(void) {
    start();
    answer_ok = true;
    CHECK(step("00 14 4C 6F", "14 00"));          /* 1, 2 */
    CHECK(step("01 14 72 65", "14 01"));          /* 4, 5 (3 was lost) */
    CHECK(step("01 14 72 65", "14 01"));          /* 6, 7: a duplicate, acknowledged again, not delivered */
    CHECK(strcmp(got, "Lore") == 0);
    CHECK(step("02 14 6D", "00 02 4F 4B"));       /* 8, 9: "Lorem" complete, "OK" carries the ACK */
    CHECK(strcmp(got, "Lorem") == 0);
    CHECK(step("02 00", ""));                     /* 10: a pure ACK is never answered */
    CHECK(fr_stream_pending() == 0);
    fake_now += 199;
    CHECK(step(NULL, ""));
    fake_now += 1;
    CHECK(step(NULL, "00 02"));                   /* 11: one idle ACK */
    fake_now += 1000;
    CHECK(step(NULL, ""));                        /* and then silence */
    CHECK(step("02 00", ""));                     /* 12 */
    answer_ok = false;
    /* stop-and-wait: with one send slot a second payload is refused until the first is acknowledged; a timeout
     * resends only the oldest */
    fake_clear_sent();
    CHECK(fr_stream_send((const uint8_t *)"A", 1));
    CHECK(!fr_stream_send((const uint8_t *)"B", 1));
    CHECK(sent("01 02 41"));
    fake_now += 5000;
    CHECK(step(NULL, "01 02 41"));
    CHECK(step("02 01", ""));
    CHECK(fr_stream_pending() == 0 && fr_stream_send((const uint8_t *)"B", 1));
    CHECK(step("02 02", ""));
    CHECK(fr_stream_pending() == 0);
    /* back-pressure: while its one slot is taken the robot does not accept the next data segment */
    CHECK(fr_stream_send((const uint8_t *)"C", 1));
    uint32_t held = fr_stats()->stream_backpressure;
    CHECK(step("03 02 44", ""));
    CHECK(fr_stats()->stream_backpressure == held + 1);
    CHECK(step("03 03 44", "03 03"));
    CHECK(strcmp(got + got_len - 1, "D") == 0);
    /* misbehaving: an ACK of something never sent, numbers above maxSeq: ignored whole */
    uint32_t before = fr_stats()->stream_misbehaving;
    CHECK(step("02 09", ""));
    CHECK(step("15 01", ""));
    CHECK(step("05 01 41", ""));
    CHECK(fr_stats()->stream_misbehaving == before + 3);
    /* a restart puts the stream back to its fresh state: silent */
    start();
    fake_now += 1000;
    CHECK(step(NULL, ""));
}
#endif

#if FR_STREAM_WINDOW == 4
static void test_window4(void) {
    start();
    answer_ok = false;
    /* mid-stream: seq 0 .. 4 sent and acknowledged */
    fake_clear_sent();
    for (int k = 0; k < 4; k++) CHECK(fr_stream_send((const uint8_t *)"x", 1));
    CHECK(sent("00 14 78|01 14 78|02 14 78|03 14 78"));
#if FR_STREAM_QUEUE > FR_STREAM_WINDOW
    /* a fifth waits in the queue, a sixth is refused */
    CHECK(fr_stream_send((const uint8_t *)"y", 1));
    CHECK(!fr_stream_send((const uint8_t *)"z", 1));
    CHECK(step("14 03", "04 14 79"));
#else
    CHECK(!fr_stream_send((const uint8_t *)"y", 1)); /* window and slots full */
    CHECK(step("14 03", ""));
    fake_clear_sent();
    CHECK(fr_stream_send((const uint8_t *)"y", 1));
    CHECK(sent("04 14 79"));
#endif
    CHECK(step("14 04", ""));
    fake_clear_sent();
    /* 11.10 */
    CHECK(fr_stream_send((const uint8_t *)"a", 1) && fr_stream_send((const uint8_t *)"b", 1));
    CHECK(fr_stream_send((const uint8_t *)"c", 1) && fr_stream_send((const uint8_t *)"d", 1));
    CHECK(sent("05 14 61|06 14 62|07 14 63|08 14 64"));
    CHECK(step("14 05", ""));                                     /* 5: base 6 */
    CHECK(step("14 05", ""));                                     /* 6: duplicate ACK 1 */
    fake_clear_sent();
    CHECK(fr_stream_send((const uint8_t *)"e", 1));
    CHECK(sent("09 14 65"));                                /* 7 */
    CHECK(step("14 05", "06 14 62"));                             /* 8, 9: fast retransmit of the oldest */
    CHECK(step("14 07", "08 14 64"));                             /* 10, 11: partial ACK, the new oldest at once */
    CHECK(step("14 09", ""));                                     /* 12 */
    CHECK(fr_stream_pending() == 0);
}

static void test_lost_resend(void) {
    /* 11.10 up to its line 9, but the fast retransmit of seq 6 is lost too: 7, 8 and 9 were sent after seq 5 (the
     * segment the last advancing ACK covered), so two duplicate ACKs more than those three mean the resend was lost */
    start();
    fake_clear_sent();
    for (int k = 0; k < 4; k++) CHECK(fr_stream_send((const uint8_t *)"x", 1));
    CHECK(step("14 03", ""));
    CHECK(fr_stream_send((const uint8_t *)"x", 1));
    CHECK(step("14 04", ""));
    CHECK(fr_stream_send((const uint8_t *)"a", 1) && fr_stream_send((const uint8_t *)"b", 1));
    CHECK(fr_stream_send((const uint8_t *)"c", 1) && fr_stream_send((const uint8_t *)"d", 1));
    CHECK(step("14 05", ""));
    CHECK(step("14 05", ""));
    fake_clear_sent();
    CHECK(fr_stream_send((const uint8_t *)"e", 1));
    CHECK(step("14 05", "06 14 62"));                 /* the fast retransmit (lost) */
    for (int k = 0; k < 4; k++) CHECK(step("14 05", ""));
    CHECK(step("14 05", "06 14 62"));                 /* the fifth: sent again at once, no timer */
}

static void test_reuse(void) {
    /* 11.8: segment 18 must not go while segment 1 (18 - (21 - 4)) was sent again within the last smoothed RTT */
    start();
    fake_clear_sent();
    CHECK(fr_stream_send((const uint8_t *)"a", 1));
    fake_now += 10;
    CHECK(step("14 00", ""));                         /* a 10 ms sample */
    fake_clear_sent();
    CHECK(fr_stream_send((const uint8_t *)"b", 1));
    CHECK(sent("01 14 62"));
    fake_now += 40;
    CHECK(step(NULL, "01 14 62"));                    /* the timeout resends seq 1 */
    CHECK(step("14 01", ""));
    for (int batch = 0; batch < 4; batch++) {
        for (int k = 0; k < 4; k++) CHECK(fr_stream_send((const uint8_t *)"x", 1));
        const char *acks[] = {"14 05", "14 09", "14 0D", "14 11"};
        CHECK(step(acks[batch], ""));
    }
    fake_clear_sent();
    CHECK(fr_stream_send((const uint8_t *)"z", 1));   /* seq 18: held back */
    CHECK(sent(""));
    fake_now += 20;
    CHECK(step(NULL, "12 14 7A"));                     /* after the round trip it goes */
}

static void test_skip(void) {
    start();
    answer_ok = false;
    /* 11.11 with the robot as R: seq 0 and 1 lost, 2 kept, then two skip notices */
    CHECK(step("02 14 63", "14 14"));
    CHECK(got_len == 0);
    CHECK(step("00 14", "14 00"));
    CHECK(got_len == 0);
    CHECK(step("01 14", "14 02"));
    CHECK(strcmp(got, "c") == 0);
    /* an ordinary pure ACK whose byte 0 lags behind means nothing */
    CHECK(step("01 14", ""));
    /* out of order within the window, delivered in order */
    CHECK(step("05 14 66", "14 02"));
    CHECK(step("04 14 65", "14 02"));
#if FR_STREAM_REORDER >= 2
    CHECK(step("03 14 64", "14 05"));
#else
    /* one reorder slot keeps the nearest segment: 4 took 5's place, so 5 must come again */
    CHECK(step("03 14 64", "14 04"));
    CHECK(strcmp(got, "cde") == 0);
    CHECK(step("05 14 66", "14 05"));
#endif
    CHECK(strcmp(got, "cdef") == 0);
}
#endif

int main(void) {
#if FR_STREAM_WINDOW == 1
    test_window1();
#endif
#if FR_STREAM_WINDOW == 4
    test_window4();
    test_lost_resend();
    test_reuse();
    test_skip();
#endif
    return DONE();
}
