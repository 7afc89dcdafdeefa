/* firmware/tests/test_trust.c: what the robot checks before it acts on a datagram (docs/firmware.md "What the
 * robot checks"): the sender is the paired gateway (its IP address and port), the frame names this robot's id,
 * and the signature (protocol.md 6.7) verifies and is newer than the last in this boot epoch. */
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "../src/fr_internal.h"

static const fr_endpoint_t gateway = {{192, 168, 1, 10}, 11011};
static const fr_endpoint_t stranger = {{192, 168, 1, 66}, 11011};
static const fr_endpoint_t other_port = {{192, 168, 1, 10}, 40000};

/* heartbeat.probe, callId 8, for robot 1 and for robot 2 */
static const char *const probe1 = "08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 08";
static const char *const probe2 = "08 02 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 08";

static fr_settings_t settings(void) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.team_number = 1;
    s.player_number = 1;
    s.gateway = gateway;
    s.boot_id = 1;
    return s;
}

/** An unsigned legacy frame around the Message bytes `body`. */
static size_t plain_frame(const char *body, uint8_t *out) {
    size_t n = hex(body, out + 12);
    fr_frame_header(out + 12, n, FR_FORM_LEGACY);
    return n + 12;
}

static void start(const fr_settings_t *s) {
    fake_now = 0;
    fr_init(s);
    fr_poll();
    fake_clear_sent();
}

static void test_sender_and_robot_id(void) {
    fr_settings_t s = settings();
    start(&s);
    uint8_t f[128];
    size_t n = plain_frame(probe1, f);
    /* from another host, and from the gateway's address but another port: dropped, counted, never answered */
    fake_receive(&stranger, f, n);
    fake_receive(&other_port, f, n);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->stranger == 2);
    /* a stream segment from a stranger is dropped as well */
    fake_receive(&stranger, (const uint8_t *)"\x00\x14\x41", 3);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->stranger == 3);
    /* from the gateway but naming robot 2: dropped and counted */
    n = plain_frame(probe2, f);
    fake_receive(&gateway, f, n);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->wrong_robot == 1);
    /* no robotID at all: not for this robot either */
    n = plain_frame("B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 08", f);
    fake_receive(&gateway, f, n);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->wrong_robot == 2);
    /* from the gateway, for robot 1: answered, to the gateway's address and port */
    n = plain_frame(probe1, f);
    fake_receive(&gateway, f, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && memcmp(&fake_sent[0].peer, &gateway, sizeof gateway) == 0);
}

int main(void) {
    test_sender_and_robot_id();
    return DONE();
}
