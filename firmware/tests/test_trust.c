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
    s.development = true; /* a development build checks the sender and the robot id all the same */
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

/** The robot key of robot 1 for the team key 00 01 .. 1F (test_protocol.c has its derivation). */
static uint8_t key[32];

/** A gateway frame for robot `id` in `epoch`, signed with direction 02 and `ts`, around the Message bytes `body`. */
static size_t signed_frame(int32_t id, uint32_t epoch, uint64_t ts, const char *body, uint8_t *out) {
    uint8_t *payload = out + 12;
    size_t n = hex(body, payload);
    uint8_t *p = payload + n;
    *p++ = 0xFA; *p++ = 0xC1; *p++ = 0x03; *p++ = 19; *p++ = 0x09;
    for (int k = 0; k < 8; k++) *p++ = (uint8_t)(ts >> (8 * k));
    *p++ = 0x12; *p++ = 8;
    fr_sign_mac(key, 32, 2, id, epoch, ts, payload, n, p);
    n += 23;
    fr_frame_header(payload, n, FR_FORM_LEGACY);
    return n + 12;
}

static fr_settings_t signing(void) {
    fr_settings_t s = settings();
    s.development = false;
    s.signing_key = key;
    s.signing_key_len = sizeof key;
    return s;
}

static void test_fail_closed(void) {
    /* keys given in hex: 16 to 64 bytes of hex digit pairs, anything else refused with a reason */
    uint8_t k[FR_SIGNING_KEY_MAX];
    size_t len = 0;
    char hexkey[140];
    memset(hexkey, 'a', sizeof hexkey);
    hexkey[32] = '\0';
    CHECK(fr_key_from_hex(hexkey, k, &len) == FR_KEY_OK && len == 16 && k[0] == 0xAA);
    hexkey[30] = '\0';
    CHECK(fr_key_from_hex(hexkey, k, &len) == FR_KEY_TOO_SHORT);
    memset(hexkey, 'F', sizeof hexkey);
    hexkey[128] = '\0';
    CHECK(fr_key_from_hex(hexkey, k, &len) == FR_KEY_OK && len == 64);
    hexkey[128] = 'F';
    hexkey[130] = '\0';
    CHECK(fr_key_from_hex(hexkey, k, &len) == FR_KEY_TOO_LONG);
    hexkey[33] = '\0';
    CHECK(fr_key_from_hex(hexkey, k, &len) == FR_KEY_ODD_LENGTH);
    hexkey[10] = 'g';
    hexkey[32] = '\0';
    CHECK(fr_key_from_hex(hexkey, k, &len) == FR_KEY_NOT_HEX);
    CHECK(fr_key_from_hex("", k, &len) == FR_KEY_TOO_SHORT);
    CHECK(strstr(fr_key_error_text(FR_KEY_NOT_HEX), "hex") != NULL);
    /* fr_init refuses what would not be safe, and then sends nothing and acts on nothing */
    fr_settings_t s = settings();
    s.development = false;
    fake_now = 0;
    CHECK(fr_init(&s) == FR_INIT_NO_KEY);
    s.signing_key = key;
    s.signing_key_len = 15;
    CHECK(fr_init(&s) == FR_INIT_KEY_LENGTH);
    s.signing_key_len = 65;
    CHECK(fr_init(&s) == FR_INIT_KEY_LENGTH);
    s.signing_key_len = 32;
    s.development = true;
    CHECK(fr_init(&s) == FR_INIT_KEY_IN_DEVELOPMENT);
    s = settings();
    s.pair_on_first_signed = true;
    CHECK(fr_init(&s) == FR_INIT_PAIRING_UNSIGNED);
    s = signing();
    fake_epoch_fails = true;
    CHECK(fr_init(&s) == FR_INIT_EPOCH);
    fake_epoch_fails = false;
    CHECK(strstr(fr_init_error_text(FR_INIT_EPOCH), "epoch") != NULL);
    fake_clear_sent();
    uint8_t f[128];
    size_t n = plain_frame(probe1, f);
    fake_receive(&gateway, f, n);
    for (fake_now = 0; fake_now < 1000; fake_now += 100) fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->not_started == 1);
    CHECK(!fr_stream_send((const uint8_t *)"x", 1));
    /* every epoch comes from the port, one higher per start; none is taken for a refused start */
    uint32_t before = fake_epoch;
    CHECK(fr_init(&s) == FR_INIT_OK && fr_epoch() == before + 1);
    s.signing_key_len = 3;
    CHECK(fr_init(&s) == FR_INIT_KEY_LENGTH && fake_epoch == before + 1);
}

static void test_signed_trust(void) {
    fr_settings_t s = signing();
    start(&s);
    uint32_t epoch = fr_epoch();
    uint8_t f[128];
    /* the keep-alive is signed and says nothing of development */
    fake_now = 200;
    fr_poll();
    CHECK(fake_sent_count == 1 && fake_sent[0].len > 23 && fake_sent[0].data[fake_sent[0].len - 23] == 0xFA);
    fake_clear_sent();
    /* a correctly signed frame from a stranger, or from the gateway's IP at another port: never answered */
    size_t n = signed_frame(1, epoch, 100, probe1, f);
    fake_receive(&stranger, f, n);
    fake_receive(&other_port, f, n);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->stranger == 2);
    /* a frame signed for robot 2 (robot A) delivered to robot 1 (robot B): it names robot 2 */
    n = signed_frame(2, epoch, 101, probe2, f);
    fake_receive(&gateway, f, n);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->wrong_robot == 1);
    /* the same bytes with robotID changed to 1: the MAC was for robot 2, so it is a bad signature */
    f[13] = 0x01;
    fake_receive(&gateway, f, n);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->bad_signature == 1);
    /* from the gateway, signed for this robot: answered, once */
    n = signed_frame(1, epoch, 102, probe1, f);
    fake_receive(&gateway, f, n);
    fake_receive(&gateway, f, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && fr_stats()->replayed == 1);
}

static void test_pairing(void) {
    fr_settings_t s = signing();
    s.pair_on_first_signed = true;
    s.gateway = (fr_endpoint_t){{192, 168, 1, 255}, 11011}; /* keep-alives to the network until paired */
    start(&s);
    fr_endpoint_t g;
    CHECK(!fr_gateway(&g));
    uint32_t epoch = fr_epoch();
    uint8_t f[128];
    /* unsigned or wrongly signed frames from anyone pair nothing; segments wait for the pairing */
    size_t n = plain_frame(probe1, f);
    fake_receive(&stranger, f, n);
    n = signed_frame(1, epoch + 1, 100, probe1, f);
    fake_receive(&stranger, f, n);
    fake_receive(&stranger, (const uint8_t *)"\x00\x14\x41", 3);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->unsigned_frames == 1 && fr_stats()->bad_signature == 1);
    CHECK(fr_stats()->stranger == 1 && !fr_gateway(&g));
    /* the first frame that verifies pairs its sender, address and port, and is answered there */
    n = signed_frame(1, epoch, 100, probe1, f);
    fake_receive(&other_port, f, n);
    fr_poll();
    CHECK(fr_gateway(&g) && memcmp(&g, &other_port, sizeof g) == 0);
    CHECK(fake_sent_count == 1 && memcmp(&fake_sent[0].peer, &other_port, sizeof other_port) == 0);
    /* from now on the learned gateway alone: the configured address is a stranger too */
    n = signed_frame(1, epoch, 101, probe1, f);
    fake_receive(&gateway, f, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && fr_stats()->stranger == 2);
    fake_clear_sent();
    fake_now += 200;
    fr_poll();
    CHECK(fake_sent_count == 1 && memcmp(&fake_sent[0].peer, &other_port, sizeof other_port) == 0);
}

static void test_development_keepalive(void) {
    /* a development build says so in every keep-alive: RobotHealth field 5 = true (28 01), unsigned */
    fr_settings_t s = settings();
    fake_now = 0;
    CHECK(fr_init(&s) == FR_INIT_OK && fr_epoch() == 0);
    for (int k = 0; k < 3; k++) {
        fake_clear_sent();
        fr_poll();
        fake_now += 200;
        CHECK(fake_sent_count == 1 && fake_sent[0].len > 2 &&
              fake_sent[0].data[fake_sent[0].len - 2] == 0x28 && fake_sent[0].data[fake_sent[0].len - 1] == 0x01);
    }
}

int main(void) {
    uint8_t team[32];
    for (int k = 0; k < 32; k++) team[k] = (uint8_t)k;
    fr_robot_key(team, sizeof team, 1, key);
    test_sender_and_robot_id();
    test_fail_closed();
    test_signed_trust();
    test_pairing();
    test_development_keepalive();
    return DONE();
}
