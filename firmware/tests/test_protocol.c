/* firmware/tests/test_protocol.c: the library against the worked examples of docs/protocol.md section 9, byte
 * for byte, through a fake port; plus the refusals of 4.4, groups (5) and the RPC errors of 7.4. */
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "../src/fr_internal.h"
#include "naogateway/proto/message.pb.h"

static const fr_endpoint_t gateway = {{192, 168, 1, 10}, 11011};

static float float_of(uint32_t bits) {
    float f;
    memcpy(&f, &bits, 4);
    return f;
}

/** The simulated firmware's keep-alive state of 9.13. */
static void health(fr_health_t *h, void *ctx) {
    (void)ctx;
    h->battery_voltage = float_of(0x4146624Eu);
    h->posture = "sit";
    h->has_position = true;
    h->x_mm = -1000;
    h->y_mm = 0;
    h->rotation = 0.0f;
}

static fr_rpc_status_t walk(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)later; (void)ctx;
    if (!fr_rpc_expect_floats(c, 3, err, cap)) return FR_RPC_ERROR;
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

static fr_deferred_t parked = -1;
static fr_rpc_status_t slow(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)r; (void)err; (void)cap; (void)ctx;
    parked = later;
    return FR_RPC_LATER;
}

static fr_rpc_status_t say(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)later; (void)ctx; (void)err; (void)cap;
    r->kind = FR_VALUE_STRING;
    r->u.s = c->count == 1 && c->params[0].kind == FR_VALUE_STRING ? c->params[0].u.s : "?";
    return FR_RPC_OK;
}

static fr_settings_t settings(void) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.team_number = 1;
    s.player_number = 1;
    s.gateway = gateway;
    s.agent = "SimAgent";
    s.role = "striker";
    s.boot_id = 1;
    s.development = true; /* the worked examples are unsigned; the signed ones set a key */
    s.callbacks.health = health;
    return s;
}

static void deliver(const char *hexbytes) {
    unsigned char b[1400];
    size_t n = hex(hexbytes, b);
    fake_receive(&gateway, b, n);
}

/** Starts the library at time 0 and swallows the first keep-alive. */
static void start(const fr_settings_t *s) {
    fake_now = 0;
    fr_init(s);
    fr_poll();
    fake_clear_sent();
}

static void test_frame_headers(void) {
    /* 9.1 and 9.2: the same payload in both forms */
    unsigned char buf[64];
    size_t n = hex("08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74", buf + 12);
    uint8_t *f = fr_frame_header(buf + 12, n, FR_FORM_LEGACY);
    CHECK(same_bytes(f, n + 12, "00 2A 00 00 00 00 00 00 00 00 00 12 08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74"));
    f = fr_frame_header(buf + 12, n, FR_FORM_COMPACT);
    CHECK(same_bytes(f, n + 8, "00 2A 00 00 00 00 00 12 08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74"));
    const uint8_t *payload;
    size_t len;
    fr_form_t form;
    CHECK(fr_frame_parse(f, n + 8, &payload, &len, &form) == FR_FRAME_OK && len == n && form == FR_FORM_COMPACT);
    /* 9.3: gzip-flagged frames are refused whole (4.3, this library's choice) */
    unsigned char gz[64];
    size_t gn = hex("00 2A 02 00 00 00 00 00 00 00 00 26 1F 8B 08 00 00 00 00 00 00 FF E3 60 DC C5 C8 2B C0 98 C4 E9"
                    "98 9E 9A 57 12 92 5A 5C 02 00 A3 06 58 D6 12 00 00 00", gz);
    CHECK(fr_frame_parse(gz, gn, &payload, &len, &form) == FR_FRAME_GZIP);
    /* 4.4, in its order */
    unsigned char bad[16] = {0, 42, 0, 0, 0, 0, 0};
    CHECK(fr_frame_parse(bad, 7, &payload, &len, &form) == FR_FRAME_TRUNCATED);
    bad[1] = 43;
    CHECK(fr_frame_parse(bad, 12, &payload, &len, &form) == FR_FRAME_WRONG_OPERATION);
    bad[1] = 42;
    bad[2] = 1;
    CHECK(fr_frame_parse(bad, 12, &payload, &len, &form) == FR_FRAME_UNSUPPORTED_FLAGS);
    bad[2] = 0;
    CHECK(fr_frame_parse(bad, 10, &payload, &len, &form) == FR_FRAME_TRUNCATED);
    bad[11] = 1;
    CHECK(fr_frame_parse(bad, 12, &payload, &len, &form) == FR_FRAME_LENGTH_MISMATCH);
    CHECK(fr_frame_parse(bad, 1401, &payload, &len, &form) == FR_FRAME_OVERSIZE);
}

static void test_keepalive(void) {
    fr_settings_t s = settings();
    fake_now = 0;
    fr_init(&s);
    for (fake_now = 0; fake_now <= 5000; fake_now += 200) {
        fake_clear_sent();
        fr_poll();
        CHECK(fake_sent_count == 1);
    }
    /* 9.13, byte for byte, sent to the gateway's 11011; a development build adds RobotHealth.development = true
     * (field 5: 28 01), so the frame is 2 bytes longer (4E) and RobotHealth 17 bytes (11) */
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 00 00 00 00 4E 08 01 BA 01 34 08 88 27 10 01 18 05 3A 12 08 98 F8 FF FF FF"
        "FF FF FF FF 01 10 00 1D 00 00 00 00 62 08 53 69 6D 41 67 65 6E 74 7A 07 73 74 72 69 6B 65 72 82"
        "01 03 73 69 74 8A BC 03 11 0D 4E 62 46 41 12 03 73 69 74 18 88 27 20 01 28 01"));
    CHECK(memcmp(&fake_sent[0].peer, &gateway, sizeof gateway) == 0);
    /* nothing more until 200 ms later */
    fake_clear_sent();
    fake_now = 5199;
    fr_poll();
    CHECK(fake_sent_count == 0);
    /* A board reports its clock and its last reset in RobotHealth.board (field 6): a CM-530 that fell back to
     * 64 MHz after its stack overflowed. Posix and the emulator report nothing (the bytes above). */
    fake_board_present = true;
    fake_board.core_clock_hz = 64000000u;
    fake_board.stack_overflow_reset = true;
    fake_board.fault_reset = false;
    fake_clear_sent();
    fake_now = 5200;
    fr_poll();
    uint8_t board[9];
    hex("32 07 08 80 A0 C2 1E 10 01", board);
    CHECK(fake_sent_count == 1 && fake_sent[0].len == 0x4E + 12 + 9 &&
          memcmp(fake_sent[0].data + fake_sent[0].len - 9, board, 9) == 0);
    fake_board_present = false;
}

/* The keep-alive is written by hand (fr_core.c); nanopb's encoding of the same Status and RobotHealth is the
 * reference, over the cases that change its bytes: a position with negative coordinates, strings left out, long
 * strings (two-byte lengths), the development flag, each board field. */
static fr_health_t variant;
static void variant_health(fr_health_t *h, void *ctx) {
    (void)ctx;
    *h = variant;
}

static bool write_str(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const char *str = (const char *)*arg;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, (const pb_byte_t *)str, strlen(str));
}

static pb_callback_t str_field(const char *str) {
    pb_callback_t cb;
    cb.funcs.encode = str ? write_str : NULL;
    cb.arg = (void *)(uintptr_t)str;
    return cb;
}

/** The keep-alive's payload as nanopb encodes it from the same state. */
static size_t nanopb_keepalive(const fr_settings_t *s, const fr_health_t *h, uint32_t up, uint8_t *out, size_t cap) {
    naogateway_proto_Status status = naogateway_proto_Status_init_zero;
    status.has_timestamp = status.has_teamID = status.has_timeOnline = true;
    status.timestamp = up;
    status.teamID = s->team_number;
    status.timeOnline = up / 1000u;
    if (h->has_position) {
        status.has_robotPosition = true;
        status.robotPosition.has_x = status.robotPosition.has_y = status.robotPosition.has_rotation = true;
        status.robotPosition.x = h->x_mm;
        status.robotPosition.y = h->y_mm;
        status.robotPosition.rotation = h->rotation;
    }
    status.activeAgent = str_field(s->agent);
    status.activeRole = str_field(s->role);
    status.currentState = str_field(h->current_state ? h->current_state : h->posture);
    naogateway_proto_RobotHealth health = naogateway_proto_RobotHealth_init_zero;
    health.has_batteryVoltage = health.has_uptimeMs = health.has_bootId = true;
    health.batteryVoltage = h->battery_voltage;
    health.posture = str_field(h->posture);
    health.uptimeMs = up;
    health.bootId = s->boot_id;
    health.has_development = health.development = s->development;
    if (fake_board_present) {
        health.has_board = health.board.has_coreClockHz = true;
        health.board.coreClockHz = fake_board.core_clock_hz;
        health.board.has_stackOverflowReset = health.board.stackOverflowReset = fake_board.stack_overflow_reset;
        health.board.has_faultReset = health.board.faultReset = fake_board.fault_reset;
    }
    pb_extension_t ext_health = {&naogateway_proto_robotHealth, &health, NULL, true};
    pb_extension_t ext_status = {&naogateway_proto_status, &status, &ext_health, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.robotID = s->robot_id;
    msg.extensions = &ext_status;
    pb_ostream_t o = pb_ostream_from_buffer(out, cap);
    return pb_encode(&o, naogateway_proto_Message_fields, &msg) ? o.bytes_written : 0;
}

static void test_keepalive_as_nanopb(void) {
    static char long_agent[301], long_state[131];
    memset(long_agent, 'a', sizeof long_agent - 1);
    memset(long_state, 's', sizeof long_state - 1);
    struct {
        fr_health_t h;
        const char *agent, *role;
        int32_t robot_id;
        bool development, board, overflow, fault;
    } cases[] = {
        {{12.5f, "sit", false, 0, 0, 0.0f, NULL}, "SimAgent", "striker", 1, true, false, false, false},
        {{-1.0f, "walking", true, -1000, 123456, -3.25f, "kick"}, "A", "", 7, false, true, true, false},
        {{0.0f, NULL, true, -2147483647 - 1, 2147483647, 1.0f, NULL}, NULL, NULL, 200, false, true, false, true},
        {{7.75f, "stand", false, 0, 0, 0.0f, long_state}, long_agent, "keeper", 3, true, true, true, true},
        {{7.75f, "fallen", true, -1, -1, 0.5f, NULL}, long_agent, long_state, 2147483647, false, false, false, false},
    };
    static const uint8_t key[16] = {1};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        fr_settings_t s = settings();
        s.callbacks.health = variant_health;
        s.agent = cases[k].agent;
        s.role = cases[k].role;
        s.robot_id = cases[k].robot_id;
        s.team_number = 3 + (uint32_t)k * 100u;
        s.boot_id = 0x12345u * (uint32_t)k;
        s.development = cases[k].development;
        if (!s.development) {
            s.signing_key = key;
            s.signing_key_len = sizeof key;
        }
        variant = cases[k].h;
        fake_board_present = cases[k].board;
        fake_board.core_clock_hz = 72000000u - (uint32_t)k;
        fake_board.stack_overflow_reset = cases[k].overflow;
        fake_board.fault_reset = cases[k].fault;
        fake_now = 1000;
        CHECK(fr_init(&s) == FR_INIT_OK);
        fake_clear_sent();
        fake_now = 1000 + 987654u * (uint32_t)k;
        fr_poll();
        uint8_t expected[1400];
        size_t n = nanopb_keepalive(&s, &variant, 987654u * (uint32_t)k, expected, sizeof expected);
        /* a signed keep-alive carries its signature (23 bytes) after the same fields */
        size_t sig = s.development ? 0 : FR_SIGNATURE_FIELD_SIZE;
        CHECK(n > 0 && fake_sent_count == 1 && fake_sent[0].len == 12 + n + sig &&
              memcmp(fake_sent[0].data + 12, expected, n) == 0);
    }
    fake_board_present = false;
}

static void test_rpc(void) {
    fr_settings_t s = settings();
    start(&s);
    CHECK(fr_rpc_register("motion", "walk", walk, NULL));
    CHECK(fr_rpc_register("motion", "posture", slow, NULL));
    CHECK(fr_rpc_register("speech", "say", say, NULL));
    /* 9.4 -> 9.5 */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 2B 08 01 B2 BC 03 25 0A 06 6D 6F 74 69 6F 6E 12 04 77 61 6C 6B"
            "1A 05 1D CD CC 4C 3E 1A 05 1D 00 00 00 00 1A 05 1D 00 00 00 3F 78 07");
    fr_poll();
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 00 00 00 00 0C 08 01 BA BC 03 06 0A 02 28 01 78 07"));
    /* 9.6 -> 9.7 */
    fake_clear_sent();
    deliver("00 2A 00 00 00 00 00 00 00 00 00 1A 08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70"
            "72 6F 62 65 78 08");
    fr_poll();
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 00 00 00 00 29 08 01 BA BC 03 23 12 1F 75 6E 6B 6E 6F 77 6E 20 6D 65 74 68"
        "6F 64 3A 20 68 65 61 72 74 62 65 61 74 2E 70 72 6F 62 65 78 08"));
    /* walk with two parameters: "bad parameters: expected 3 numbers, got 2 parameter(s)", callId 9, compact form
     * answered in the compact form */
    fake_clear_sent();
    deliver("00 2A 00 00 00 00 00 1E 08 01 B2 BC 03 17 0A 06 6D 6F 74 69 6F 6E 12 04 77 61 6C 6B"
            "1A 05 1D CD CC 4C 3E 78 09");
    fr_poll();
    CHECK(fake_sent_count == 0); /* the length above is wrong on purpose: refused, not answered */
    CHECK(fr_stats()->bad_frame == 1);
    deliver("00 2A 00 00 00 00 00 1D 08 01 B2 BC 03 17 0A 06 6D 6F 74 69 6F 6E 12 04 77 61 6C 6B"
            "1A 05 1D CD CC 4C 3E 78 09");
    fr_poll();
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 40 08 01 BA BC 03 3A 12 36"
        "62 61 64 20 70 61 72 61 6D 65 74 65 72 73 3A 20 65 78 70 65 63 74 65 64 20 33 20 6E 75 6D 62 65 72 73"
        "2C 20 67 6F 74 20 31 20 70 61 72 61 6D 65 74 65 72 28 73 29 78 09"));
    /* a deferred answer goes out when the program gives it, with the request's callId and form */
    fake_clear_sent();
    deliver("00 2A 00 00 00 00 00 00 00 00 00 1B 08 01 B2 BC 03 15 0A 06 6D 6F 74 69 6F 6E 12 07 70 6F 73 74 75 72 65"
            "1A 00 78 0B");
    fr_poll();
    CHECK(fake_sent_count == 0 && parked >= 0);
    fr_value_t v = {FR_VALUE_STRING, {.s = "stand"}};
    fr_rpc_answer(parked, &v, NULL);
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 00 00 00 00 11 08 01 BA BC 03 0B 0A 07 0A 05 73 74 61 6E 64 78 0B"));
    /* a string parameter, and unknown groups skipped at both depths (protocol.md 5): a group (field 50) in the
     * Message and another (field 40, nesting field 41) inside the Request */
    fake_clear_sent();
    deliver("00 2A 00 00 00 00 00 00 00 00 00 2B 08 01 93 03 08 05 94 03 B2 BC 03 1F 0A 06 73 70 65 65 63 68"
            "12 03 73 61 79 1A 04 0A 02 68 69 C3 02 CB 02 08 01 CC 02 C4 02 78 0C");
    fr_poll();
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 00 00 00 00 0E 08 01 BA BC 03 08 0A 04 0A 02 68 69 78 0C"));
    /* an end-group without its start is refused: no answer */
    fake_clear_sent();
    deliver("00 2A 00 00 00 00 00 00 00 00 00 0C 08 01 94 03 B2 BC 03 04 0A 00 12 00");
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->bad_protobuf == 1);
    /* a group closed by another field's end-group is refused */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 06 08 01 93 03 9C 03");
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->bad_protobuf == 2);
}

/* The one frame buffer's rule (docs/firmware.md, "Memory"): option callbacks run after the frame is decoded, so a
 * callback that sends (and so encodes into the buffer the frame was received in) cannot spoil the names after it. */
static int rule_text = -1;
static int rule_calls;
static char rule_long[301];
static void send_on_switch(int index, bool on, void *ctx) {
    (void)index; (void)on; (void)ctx;
    rule_calls++;
    (void)fr_debug_text(rule_text, rule_long);
}

static void test_frame_buffer_rule(void) {
    fr_settings_t s = settings();
    s.callbacks.option = send_on_switch;
    start(&s);
    int regions = fr_option_add("havimo.regions", FR_OPT_HAVIMO_REGIONS, NULL);
    rule_text = fr_option_add("text", FR_OPT_TEXT, NULL);
    memset(rule_long, 'x', sizeof rule_long - 1);
    rule_calls = 0;
    /* optionEnable "text", "havimo.regions": the first callback sends 300 bytes of text */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 1E 08 01 EA BB 03 18 1A 16 0A 04 74 65 78 74 0A 0E 68 61 76 69 6D 6F"
            "2E 72 65 67 69 6F 6E 73");
    fr_poll();
    CHECK(fr_option_enabled(rule_text) && fr_option_enabled(regions) && rule_calls == 2);
    /* both callbacks' texts, then the option list */
    CHECK(fake_sent_count == 3 && fake_sent[0].len > 300 && fake_sent[1].len > 300);
    /* While the port still sends from the buffer (or receives into it) nothing is encoded: a keep-alive due then goes
     * at the first poll after, late but not skipped, and debug data are refused (counted). */
    fake_clear_sent();
    fake_now = 200;
    fake_frame_busy = true;
    uint32_t failed = fr_stats()->send_failed;
    fr_poll();
    CHECK(fake_sent_count == 0);
    CHECK(!fr_debug_text(rule_text, "busy") && fr_stats()->send_failed == failed + 1);
    fake_now = 230;
    fake_frame_busy = false;
    fr_poll();
    CHECK(fake_sent_count == 1 && fake_sent[0].len > 60);
    fake_now = 400;
    fake_clear_sent();
    fr_poll();
    CHECK(fake_sent_count == 1);
}

static void test_options(void) {
    fr_settings_t s = settings();
    start(&s);
    int regions = fr_option_add("havimo.regions", FR_OPT_HAVIMO_REGIONS, NULL);
    int grid = fr_option_add("havimo.grid", FR_OPT_HAVIMO_GRID, NULL);
    int text = fr_option_add("text", FR_OPT_TEXT, NULL);
    CHECK(regions == 0 && grid == 1 && text == 2);
    /* optionEnable "havimo.regions": answered with the list of 9.9 */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 18 08 01 EA BB 03 12 1A 10 0A 0E 68 61 76 69 6D 6F 2E 72 65 67 69 6F 6E 73");
    fr_poll();
    const char *push99 = "00 2A 00 00 00 00 00 00 00 00 00 3D 08 01 EA BB 03 37 12 35 0A 14 0A 0E 68 61 76 69 6D 6F 2E 72"
                         "65 67 69 6F 6E 73 10 64 18 01 0A 11 0A 0B 68 61 76 69 6D 6F 2E 67 72 69 64 10 65 18 00 0A 0A 0A"
                         "04 74 65 78 74 10 01 18 00";
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len, push99));
    CHECK(fr_option_enabled(regions) && !fr_option_enabled(grid) && !fr_option_enabled(text));
    /* 9.8: optionPull, answered with the same list */
    fake_clear_sent();
    deliver("00 2A 00 00 00 00 00 00 00 00 00 08 08 01 EA BB 03 02 08 01");
    fr_poll();
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len, push99));
    /* 9.10: "havimo" switches havimo.regions and havimo.grid (a.b.* rule), not "text" */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 10 08 01 EA BB 03 0A 1A 08 0A 06 68 61 76 69 6D 6F");
    fr_poll();
    CHECK(fr_option_enabled(regions) && fr_option_enabled(grid) && !fr_option_enabled(text));
    /* "havimo.reg" names nothing: a prefix counts only up to a dot */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 14 08 01 EA BB 03 0E 22 0C 0A 0A 68 61 76 69 6D 6F 2E 72 65 67");
    fr_poll();
    CHECK(fr_option_enabled(regions));
    /* 9.11 and 9.12 at 5000 ms after power-up */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 10 08 01 EA BB 03 0A 1A 08 0A 04 74 65 78 74 0A 00");
    fr_poll();
    CHECK(fr_option_enabled(text));
    fake_now = 5000;
    fr_poll(); /* the keep-alive due */
    fake_clear_sent();
    CHECK(fr_debug_text(text, "ready"));
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 00 00 00 00 18 08 01 F2 BB 03 12 0A 04 74 65 78 74 10 88 27 1A 07 0A 05 72"
        "65 61 64 79"));
    fake_clear_sent();
    uint8_t records[2 * 16];
    memset(records, 0, sizeof records);
    hex("01 02 32 00 A0 0F 00 00 B8 0B 00 00 54 4C 40 38", records + 16); /* slot 0 unused: left out */
    CHECK(fr_havimo_regions(regions, 42, records, 2));
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len,
        "00 2A 00 00 00 00 00 00 00 00 00 1D 08 01 FA BB 03 17 08 2A 10 88 27 1A 10 01 02 32 00 A0 0F 00"
        "00 B8 0B 00 00 54 4C 40 38"));
    /* a grid frame: 768 cells, 795 bytes as protocol.md 8 says */
    fake_clear_sent();
    uint8_t cells[768];
    memset(cells, 0x21, sizeof cells);
    CHECK(fr_havimo_grid(grid, 43, cells));
    CHECK(fake_sent_count == 1 && fake_sent[0].len == 795);
    /* disabled options send nothing */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 08 08 01 EA BB 03 02 22 00");
    fr_poll();
    fake_clear_sent();
    deliver("00 2A 00 00 00 00 00 00 00 00 00 10 08 01 EA BB 03 0A 22 08 0A 06 68 61 76 69 6D 6F");
    fr_poll();
    CHECK(!fr_option_enabled(regions) && !fr_option_enabled(grid));
    fake_clear_sent();
    CHECK(!fr_havimo_grid(grid, 44, cells) && fake_sent_count == 0);
    /* a restart switches every option off */
    fr_init(&s);
    CHECK(!fr_option_enabled(text));
}

/** The robot key of robot 1 for the team key 00 01 .. 1F, HKDF-SHA256 as protocol.md 6.7 says. Computed
 *  independently with Python's hmac and hashlib (a few lines, see the commit); the gateway derives the same. */
static const char *const robot1_key =
    "d50faec98cd1be71f7448262e12d46bedeffc984c9b79c928b3afded70791be1";

static void test_signing(void) {
    /* HKDF-SHA256 against RFC 5869 Appendix A.1, test case 1 (L = 42: two expand blocks) */
    uint8_t ikm[22], salt[13], info[10], okm[42];
    memset(ikm, 0x0b, sizeof ikm);
    for (int k = 0; k < 13; k++) salt[k] = (uint8_t)k;
    for (int k = 0; k < 10; k++) info[k] = (uint8_t)(0xf0 + k);
    fr_hkdf_sha256(salt, sizeof salt, ikm, sizeof ikm, info, sizeof info, okm, sizeof okm);
    CHECK(same_bytes(okm, 42, "3cb25f25faacd57a90434f64d0362f2a2d2d0a90cf1a5a4c5db02d56ecc4c5bf"
                              "34007208d5b887185865"));
    /* the robot key: robot 1 and robot 63 of one team differ, and match the independent computation */
    uint8_t team[32], rk[32], rk63[32];
    for (int k = 0; k < 32; k++) team[k] = (uint8_t)k;
    fr_robot_key(team, sizeof team, 1, rk);
    CHECK(same_bytes(rk, 32, robot1_key));
    fr_robot_key(team, sizeof team, 63, rk63);
    CHECK(same_bytes(rk63, 32, "5e4ab8a63047006c8522918f4540b7285b47c9bd7a21eb4e57f45debfb11efc6"));
    /* FUSIG2: the MAC binds direction, robot id, epoch and timestamp; each changes it */
    uint8_t mac[8], other[8], msg[64];
    size_t n = hex("08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74", msg);
    fr_sign_mac(rk, 32, 1, 1, 3, 0x0000000300000005ull, msg, n, mac);
    CHECK(same_bytes(mac, 8, "b8 72 90 5f 6b a2 05 a0"));
    fr_sign_mac(rk, 32, 2, 1, 3, 0x0000000300000005ull, msg, n, other);
    CHECK(memcmp(mac, other, 8) != 0);
    fr_sign_mac(rk, 32, 1, 2, 3, 0x0000000300000005ull, msg, n, other);
    CHECK(memcmp(mac, other, 8) != 0);
    fr_sign_mac(rk, 32, 1, 1, 4, 0x0000000300000005ull, msg, n, other);
    CHECK(memcmp(mac, other, 8) != 0);
    /* the robot's own signed frame: epoch 3 from the port, frame counter 5 */
    fr_settings_t s = settings();
    s.development = false;
    s.signing_key = rk;
    s.signing_key_len = 32;
    fake_epoch = 2;
    start(&s); /* the first keep-alive took frame counter 0 */
    CHECK(fr_epoch() == 3 && fake_epoch == 3);
    fr_state.sign_counter = 5;
    uint8_t buf[128];
    memcpy(buf + 12, msg, n);
    size_t len = fr_sign_append(buf + 12, n, 100);
    uint8_t *f = fr_frame_header(buf + 12, len, FR_FORM_COMPACT);
    CHECK(same_bytes(f, len + 8, "00 2A 00 00 00 00 00 29 08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74 FA C1 03 13"
                                 "09 05 00 00 00 03 00 00 00 12 08 b8 72 90 5f 6b a2 05 a0"));
    /* SHA-256 of "abc" (FIPS 180-4's example) and HMAC-SHA-256 of RFC 4231 case 2 */
    fr_sha256_t sh;
    uint8_t digest[32];
    fr_sha256_init(&sh);
    fr_sha256_update(&sh, (const uint8_t *)"abc", 3);
    fr_sha256_final(&sh, digest);
    CHECK(same_bytes(digest, 32, "BA7816BF 8F01CFEA 414140DE 5DAE2223 B00361A3 96177A9C B410FF61 F20015AD"));
    /* The padding at every boundary: a length that leaves 0x80 and the length field one block (55), that pushes
     * the length field (56, 63) or all the padding (64, 119, 120) into a block of its own; fed in two pieces. */
    {
        static const struct { size_t n; const char *hex; } cases[] = {
            {55, "16fa57a0a3423a715d594516339f36189d6b5f93754a9714fef202616a9fabfe"},
            {56, "c37b44e5f1b18554b36966f4f8e08bfbf3164c4b6c10374d12d89850892073c5"},
            {63, "bbba992d2c85af960fb2987a1fd05e0aa82a3db3c740dd8982a9e273b75e36a3"},
            {64, "66bd4633ed6f71c4ecfa4763bf7ba1c8ec7612de9aa6c0578a7b675207c71e0b"},
            {119, "a3ed307b730fa77c07531300c6e4a282330011d4d4caf6bb7b63ae05950f4b66"},
            {120, "8e3b15d9fea7472655aa069620b7f8c2e55ee1499f763200a7515fe826e99d20"}};
        uint8_t m[120];
        for (size_t i = 0; i < sizeof m; i++) m[i] = (uint8_t)(i * 7u + 1u);
        for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
            fr_sha256_init(&sh);
            fr_sha256_update(&sh, m, cases[c].n / 3u);
            fr_sha256_update(&sh, m + cases[c].n / 3u, cases[c].n - cases[c].n / 3u);
            fr_sha256_final(&sh, digest);
            CHECK(same_bytes(digest, 32, cases[c].hex));
        }
    }
    const uint8_t *parts[1] = {(const uint8_t *)"what do ya want for nothing?"};
    size_t lens[1] = {28};
    fr_hmac_sha256((const uint8_t *)"Jefe", 4, parts, lens, 1, digest);
    CHECK(same_bytes(digest, 32, "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"));
}

/** A gateway frame for robot `id` in `epoch`, signed with direction 02 and `ts`, around the Request `body` (hex of
 *  the Message bytes). */
static size_t signed_request(const uint8_t *key, int32_t id, uint32_t epoch, uint64_t ts, const char *body,
                             uint8_t *out) {
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

static void test_signed_receive(void) {
    uint8_t key[32];
    hex(robot1_key, key);
    fr_settings_t s = settings();
    s.development = false;
    s.signing_key = key;
    s.signing_key_len = 32;
    fake_epoch = 9;
    start(&s);
    CHECK(fr_epoch() == 10);
    fr_rpc_register("motion", "walk", walk, NULL);
    const char *probe = "08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 08";
    uint8_t frame[128];
    /* unsigned: ignored and counted */
    deliver("00 2A 00 00 00 00 00 00 00 00 00 1A 08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70"
            "72 6F 62 65 78 08");
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->unsigned_frames == 1);
    /* signed for this robot in its epoch: answered, and the answer is signed (23 more bytes) */
    size_t n = signed_request(key, 1, 10, 1000, probe, frame);
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && fake_sent[0].len == 53 + 23);
    /* the same again: replayed */
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && fr_stats()->replayed == 1);
    /* a changed byte: bad signature */
    n = signed_request(key, 1, 10, 1001, probe, frame);
    frame[20] ^= 1;
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && fr_stats()->bad_signature == 1);
    /* signed for the previous epoch, or as if for robot 2 (the frame still names robot 1): bad signature */
    n = signed_request(key, 1, 9, 1002, probe, frame);
    fake_receive(&gateway, frame, n);
    n = signed_request(key, 2, 10, 1002, probe, frame);
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && fr_stats()->bad_signature == 3);
    /* a field after the signature */
    n = signed_request(key, 1, 10, 1002, probe, frame);
    frame[n++] = 0x10;
    frame[n++] = 0x01;
    frame[11] = (uint8_t)(n - 12);
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 1 && fr_stats()->signature_not_last == 1);
    /* newer and intact: answered */
    n = signed_request(key, 1, 10, 1003, probe, frame);
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 2);
    /* after a restart (a new epoch) the frame captured before it no longer verifies, though its timestamp would
     * pass the emptied window */
    start(&s);
    CHECK(fr_epoch() == 11);
    fr_rpc_register("heartbeat", "probe", walk, NULL);
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->bad_signature == 1);
    n = signed_request(key, 1, 11, 1, probe, frame);
    fake_receive(&gateway, frame, n);
    fr_poll();
    CHECK(fake_sent_count == 1);
}

static int link_changes, link_last = -1;
static void on_link(bool up, void *ctx) {
    (void)ctx;
    link_changes++;
    link_last = up;
}

static void test_link_policy(void) {
    fr_settings_t s = settings();
    s.callbacks.link = on_link;
    start(&s);
    /* the gateway's silence is no link loss: minutes without a datagram tell the program nothing */
    for (int k = 0; k < 600; k++) { fake_now += 500; fr_poll(); }
    CHECK(link_changes == 0);
    /* the module reports the network lost, then back */
    fake_link = false;
    fr_poll();
    CHECK(link_changes == 1 && link_last == 0);
    fr_poll();
    CHECK(link_changes == 1);
    fake_link = true;
    fr_poll();
    CHECK(link_changes == 2 && link_last == 1);
}

int main(void) {
    test_frame_headers();
    test_keepalive();
    test_keepalive_as_nanopb();
    test_rpc();
    test_options();
    test_frame_buffer_rule();
    test_signing();
    test_signed_receive();
    test_link_policy();
    return DONE();
}
