/* firmware/tests/test_body.c: the body (fr_dxl.c, fr_body.c) against the emulated bus (tools/busmodel.c, linked in
 * here as the port's bus): the master's timeouts and checks (a servo that never answers, a corrupt checksum, a status
 * packet cut short, a bus stuck low), the HaViMo2 read, servo telemetry in the keep-alive (decoded with nanopb), and
 * the bridge (replies in order, gate closed, malformed, plain datagrams, no bus). Time is the fake port's: the
 * keep-alives must leave every 200 ms to the millisecond throughout. */
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "fr_body.h"
#include "fr_port_bus.h"
#include "../src/fr_internal.h"
#include "naogateway/proto/body.pb.h"
#include "naogateway/proto/havimo.pb.h"
#include "../tools/busmodel.c"

static const fr_endpoint_t gateway = {{192, 168, 1, 10}, 11011};

/* ---- the bus port over the model ------------------------------------------------------------------------ */

static uint8_t bus_rx[8192];
static size_t bus_rx_len, bus_rx_pos;
static bool bus_present = true;
static bool bus_stuck_low;     /* the line reads as a stream of 0x00 bytes (framing errors) */
static uint32_t bus_writes;

int fr_port_bus_open(uint32_t baud) {
    (void)baud;
    return bus_present ? 0 : -1;
}

int fr_port_bus_write(const uint8_t *data, size_t len) {
    if (!bus_present) return -1;
    bus_writes++;
    if (bus_rx_pos == bus_rx_len) bus_rx_pos = bus_rx_len = 0;
    bus_rx_len += busmodel_feed(data, len, bus_rx + bus_rx_len, sizeof bus_rx - bus_rx_len, fake_now);
    return 0;
}

bool fr_port_bus_writing(void) { return false; }

size_t fr_port_bus_read(uint8_t *buf, size_t cap) {
    if (bus_stuck_low) {
        size_t n = cap < 48 ? cap : 48; /* what 0.5 ms of a stuck line delivers at 1 Mbps */
        memset(buf, 0, n);
        return n;
    }
    size_t n = bus_rx_len - bus_rx_pos;
    if (n > cap) n = cap;
    memcpy(buf, bus_rx + bus_rx_pos, n);
    bus_rx_pos += n;
    return n;
}

/* ---- keep-alives ----------------------------------------------------------------------------------------- */

static uint32_t keepalive_at[256];
static size_t keepalives;
static size_t telemetry_count;
static naogateway_proto_ServoState decoded[FR_BODY_SERVOS_MAX + 4];
static size_t decoded_count;
static uint32_t decoded_bus_errors;

/** Decode callback: one ServoState into `decoded`. */
static bool decode_servo(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field; (void)arg;
    naogateway_proto_ServoState st = naogateway_proto_ServoState_init_zero;
    if (!pb_decode(stream, naogateway_proto_ServoState_fields, &st)) return false;
    if (decoded_count < sizeof decoded / sizeof decoded[0]) decoded[decoded_count++] = st;
    return true;
}

/** The frame's payload of a datagram the robot sent (or of a stream segment's payload); NULL when not a frame. */
static const uint8_t *payload_of(const fake_datagram_t *d, size_t *len, bool *segment) {
    const uint8_t *data = d->data;
    size_t n = d->len;
    *segment = false;
    if (n > 2 && data[0] < 42 && data[1] < 42) { data += 2; n -= 2; *segment = true; }
    if (n < 2 || data[0] != 0 || data[1] != 42) return NULL;
    const uint8_t *payload;
    fr_form_t form;
    if (fr_frame_parse(data, n, &payload, len, &form) != FR_FRAME_OK) return NULL;
    return payload;
}

/** Examines what the robot sent since the last clear: counts keep-alives (and when), decodes telemetry. */
static void scan_sent(void) {
    for (size_t k = 0; k < fake_sent_count; k++) {
        size_t len;
        bool segment;
        const uint8_t *p = payload_of(&fake_sent[k], &len, &segment);
        if (p == NULL || segment) continue;
        naogateway_proto_Status status = naogateway_proto_Status_init_zero;
        naogateway_proto_ServoTelemetry tele = naogateway_proto_ServoTelemetry_init_zero;
        tele.servos.funcs.decode = decode_servo;
        pb_extension_t ext_tele = {&naogateway_proto_servoTelemetry, &tele, NULL, false};
        pb_extension_t ext_status = {&naogateway_proto_status, &status, &ext_tele, false};
        naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
        msg.extensions = &ext_status;
        size_t before = decoded_count;
        decoded_count = 0;
        pb_istream_t in = pb_istream_from_buffer(p, len);
        if (!pb_decode(&in, naogateway_proto_Message_fields, &msg)) { CHECK(false); continue; }
        if (!ext_status.found) { decoded_count = before; continue; }
        if (keepalives < 256) keepalive_at[keepalives] = fake_now;
        keepalives++;
        if (ext_tele.found) {
            telemetry_count++;
            decoded_bus_errors = tele.busErrors;
        } else {
            decoded_count = before;
        }
    }
    fake_clear_sent();
}

/** Runs the robot for `ms` milliseconds, one poll per millisecond, scanning what it sends as it goes. */
static void run(uint32_t ms) {
    for (uint32_t k = 0; k < ms; k++) {
        fake_now++;
        fr_poll();
        scan_sent();
    }
}

/** Whether every keep-alive so far left exactly 200 ms after the one before. */
static bool keepalives_on_time(void) {
    size_t n = keepalives < 256 ? keepalives : 256;
    for (size_t k = 1; k < n; k++)
        if (keepalive_at[k] - keepalive_at[k - 1] != FR_KEEPALIVE_MS) {
            printf("  keep-alive %zu at %u, the one before at %u\n", k, keepalive_at[k], keepalive_at[k - 1]);
            return false;
        }
    return n > 0;
}

static void start_robot(void) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.development = true;
    s.gateway = gateway;
    fake_now = 1000;
    fake_clear_sent();
    fr_init(&s);
    fr_poll(); /* the first keep-alive, at uptime 0 */
    busmodel_init(fake_now);
    bus_rx_len = bus_rx_pos = 0;
    bus_stuck_low = false;
    keepalives = telemetry_count = decoded_count = 0;
    scan_sent();
}

static fr_body_settings_t body_settings(size_t servo_count, bool havimo) {
    fr_body_settings_t b;
    fr_body_defaults(&b);
    for (size_t k = 0; k < servo_count; k++) b.servo_ids[k] = (uint8_t)(k + 1);
    b.servo_count = servo_count;
    b.havimo = havimo;
    return b;
}

/* ---- the master ------------------------------------------------------------------------------------------- */

/** Runs one transaction to its end on the fake clock (at most `limit` ms); its result. */
static fr_dxl_result_t transact(const uint8_t *packet, size_t len, size_t due, uint32_t timeout, uint32_t limit) {
    if (!fr_dxl_start(packet, len, due, timeout)) return FR_DXL_IDLE;
    for (uint32_t k = 0; k <= limit; k++) {
        fr_dxl_result_t r = fr_dxl_poll();
        if (r != FR_DXL_BUSY) return r;
        fake_now++;
    }
    return FR_DXL_BUSY;
}

static void test_packets(void) {
    uint8_t p[FR_DXL_TX_MAX];
    size_t n = fr_dxl_packet(p, 1, FR_DXL_PING, NULL, 0);
    CHECK(same_bytes(p, n, "FF FF 01 02 01 FB")); /* the AX-12A e-manual's ping example */
    const uint8_t rd[2] = {43, 1};
    n = fr_dxl_packet(p, 1, FR_DXL_READ, rd, 2);
    CHECK(same_bytes(p, n, "FF FF 01 04 02 2B 01 CC")); /* its read of the temperature */
    CHECK(fr_dxl_well_formed(p, n));
    CHECK(fr_dxl_reply_due(p, n) == 7);
    p[7] ^= 1;
    CHECK(!fr_dxl_well_formed(p, n));
    CHECK(!fr_dxl_well_formed(p, 5));
    uint8_t big[FR_DXL_TX_MAX + 1] = {0};
    CHECK(fr_dxl_packet(big, 1, FR_DXL_WRITE, big, FR_DXL_TX_MAX) == 0);
    const uint8_t sync[] = {30, 2, 1, 0x00, 0x02, 2, 0x00, 0x02};
    n = fr_dxl_packet(p, FR_DXL_BROADCAST, FR_DXL_SYNC_WRITE, sync, sizeof sync);
    CHECK(fr_dxl_well_formed(p, n) && fr_dxl_reply_due(p, n) == 0);
    n = fr_dxl_packet(p, 3, FR_DXL_WRITE, sync, 3);
    CHECK(fr_dxl_reply_due(p, n) == 6);
}

static void test_master_faults(void) {
    start_robot();
    uint8_t p[FR_DXL_TX_MAX];
    const uint8_t rd[2] = {36, 8};
    size_t n = fr_dxl_packet(p, 7, FR_DXL_READ, rd, 2);
    size_t len;
    const uint8_t *reply;

    CHECK(transact(p, n, 14, 4, 50) == FR_DXL_OK);
    reply = fr_dxl_reply(&len);
    CHECK(len == 14 && reply[2] == 7 && (reply[5] | reply[6] << 8) == 512 && reply[11] == 120);

    busmodel_silent(7, true);
    uint32_t began = fake_now;
    CHECK(transact(p, n, 14, 4, 50) == FR_DXL_TIMEOUT);
    CHECK(fake_now - began >= 4 && fake_now - began <= 6); /* gives up after its timeout, not later */
    busmodel_silent(7, false);

    busmodel_corrupt_next(7);
    CHECK(transact(p, n, 14, 4, 50) == FR_DXL_CHECKSUM);
    reply = fr_dxl_reply(&len);
    CHECK(len == 14); /* the damaged packet, whole, for a bridge to hand back */

    busmodel_cut_next(7, 9);
    CHECK(transact(p, n, 14, 4, 50) == FR_DXL_SHORT);
    reply = fr_dxl_reply(&len);
    CHECK(len == 9);

    /* a packet from another id than the one asked */
    const uint8_t other[] = {0xFF, 0xFF, 0x08, 0x02, 0x00, 0xF5};
    bus_rx_len = bus_rx_pos = 0;
    busmodel_silent(7, true);
    CHECK(fr_dxl_start(p, n, 14, 4));
    CHECK(fr_dxl_poll() == FR_DXL_BUSY);
    memcpy(bus_rx, other, sizeof other);
    bus_rx_len = sizeof other;
    fr_dxl_result_t r;
    for (int k = 0; k < 10 && (r = fr_dxl_poll()) == FR_DXL_BUSY; k++) fake_now++;
    CHECK(r == FR_DXL_MALFORMED);

    /* garbage before the packet is skipped */
    bus_rx_len = bus_rx_pos = 0;
    CHECK(fr_dxl_start(p, n, 6, 4));
    const uint8_t noisy[] = {0x00, 0x13, 0xFF, 0x00, 0xFF, 0xFF, 0xFF, 0x07, 0x02, 0x00, 0xF6};
    CHECK(fr_dxl_poll() == FR_DXL_BUSY); /* sent: the silent model answers nothing... */
    memcpy(bus_rx, noisy, sizeof noisy);
    bus_rx_len = sizeof noisy;
    busmodel_silent(7, false);
    CHECK(fr_dxl_poll() == FR_DXL_OK); /* ...and the bytes put on the line are read */
    reply = fr_dxl_reply(&len);
    CHECK(same_bytes(reply, len, "FF FF 07 02 00 F6"));

    /* a bus stuck low: a stream of zero bytes; the transaction ends on its timeout */
    bus_stuck_low = true;
    began = fake_now;
    CHECK(transact(p, n, 14, 4, 50) == FR_DXL_TIMEOUT);
    CHECK(fake_now - began <= 6);
    bus_stuck_low = false;

    /* a status packet longer than the request allows */
    const uint8_t ping_params[1] = {0};
    (void)ping_params;
    n = fr_dxl_packet(p, 7, FR_DXL_PING, NULL, 0);
    CHECK(transact(p, n, 14, 4, 50) == FR_DXL_MALFORMED);
}

/* ---- telemetry ------------------------------------------------------------------------------------------------ */

static void test_telemetry(void) {
    start_robot();
    fr_body_settings_t b = body_settings(18, false);
    CHECK(fr_body_init(&b));
    run(3000);
    CHECK(keepalives == 16);
    CHECK(keepalives_on_time());
    CHECK(telemetry_count == 3); /* one keep-alive per period carries it */
    CHECK(decoded_count == 18);
    bool all = decoded_count == 18;
    for (size_t k = 0; k < decoded_count; k++)
        all = all && decoded[k].id == k + 1 && decoded[k].has_position && decoded[k].position == 512 &&
              decoded[k].has_voltage && decoded[k].voltage == 120 && decoded[k].has_temperature &&
              decoded[k].temperature >= 36 && decoded[k].temperature <= 39 && decoded[k].has_load && !decoded[k].has_silent;
    CHECK(all);
    CHECK(decoded_bus_errors == 0);

    /* a servo that never answers: silent, the others read, keep-alives on time, errors counted */
    busmodel_silent(5, true);
    busmodel_servo(9)[30] = 0x00; /* goal 256: it turns, with its load's direction bit set */
    busmodel_servo(9)[31] = 0x01;
    busmodel_servo(9)[24] = 1;
    run(2000);
    CHECK(keepalives_on_time());
    CHECK(telemetry_count == 5);
    CHECK(decoded_count == 18 && decoded[4].id == 5 && decoded[4].has_silent && decoded[4].silent && !decoded[4].has_position);
    CHECK(decoded[8].position < 512);
    CHECK(decoded_bus_errors >= 2 && decoded_bus_errors == fr_body_stats()->bus_errors);
    size_t count;
    const fr_servo_t *sv = fr_body_servos(&count);
    CHECK(count == 18 && sv[4].silent && !sv[3].silent && sv[3].position == 512);
    busmodel_silent(5, false);

    /* the whole bus stuck low: every read times out, the keep-alives still leave on time */
    bus_stuck_low = true;
    run(2000);
    bus_stuck_low = false;
    CHECK(keepalives_on_time());
    CHECK(telemetry_count == 7);
    bool silent = decoded_count == 18;
    for (size_t k = 0; k < decoded_count; k++) silent = silent && decoded[k].silent;
    CHECK(silent);

    /* telemetry off: keep-alives without it */
    start_robot();
    b.telemetry_ms = 0;
    CHECK(fr_body_init(&b));
    run(1500);
    CHECK(telemetry_count == 0 && keepalives == 8);
}

/* ---- the camera ------------------------------------------------------------------------------------------------ */

static size_t region_frames, grid_frames;
static uint8_t last_records[FR_HAVIMO_TABLE_SIZE], last_cells[FR_HAVIMO_GRID_SIZE];
static size_t last_records_len, last_cells_len;

/** Decode callback: the bytes of `records` or `cells` into the buffer in *arg. */
static bool decode_bytes(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field;
    bool cells = *arg != NULL;
    uint8_t *to = cells ? last_cells : last_records;
    size_t cap = cells ? sizeof last_cells : sizeof last_records, n = stream->bytes_left;
    if (n > cap) return false;
    if (cells) last_cells_len = n; else last_records_len = n;
    return pb_read(stream, to, n);
}

/** Counts the HaViMo2 frames among what was sent (debug data, not keep-alives). */
static void scan_camera(void) {
    for (size_t k = 0; k < fake_sent_count; k++) {
        size_t len;
        bool segment;
        const uint8_t *p = payload_of(&fake_sent[k], &len, &segment);
        if (p == NULL) continue;
        naogateway_proto_HaViMoRegionFrame rf = naogateway_proto_HaViMoRegionFrame_init_zero;
        naogateway_proto_HaViMoGridFrame gf = naogateway_proto_HaViMoGridFrame_init_zero;
        rf.records.funcs.decode = decode_bytes;
        rf.records.arg = NULL;
        gf.cells.funcs.decode = decode_bytes;
        gf.cells.arg = (void *)1;
        pb_extension_t eg = {&naogateway_proto_havimoGrid, &gf, NULL, false};
        pb_extension_t er = {&naogateway_proto_havimoRegions, &rf, &eg, false};
        naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
        msg.extensions = &er;
        pb_istream_t in = pb_istream_from_buffer(p, len);
        if (!pb_decode(&in, naogateway_proto_Message_fields, &msg)) continue;
        if (er.found) region_frames++;
        if (eg.found) grid_frames++;
    }
}

static void test_havimo(bool table_read, uint8_t capture) {
    start_robot();
    int regions = fr_option_add("havimo.regions", FR_OPT_HAVIMO_REGIONS, NULL);
    int grid = fr_option_add("havimo.grid", FR_OPT_HAVIMO_GRID, NULL);
    fr_body_settings_t b = body_settings(18, true);
    b.havimo_regions_option = regions;
    b.havimo_grid_option = grid;
    b.havimo_table_read = table_read;
    b.havimo_capture = capture;
    CHECK(fr_body_init(&b));
    /* switch both options on as the gateway does (protocol.md 9.10) */
    fr_state.stats.received = 0;
    {
        static const char *names[] = {"havimo"};
        (void)names;
    }
    uint8_t frame[64];
    /* protocol.md 9.10: optionEnable "havimo" */
    size_t n = hex("00 2A 00 00 00 00 00 00 00 00 00 10 08 01 EA BB 03 0A 1A 08 0A 06 68 61 76 69 6D 6F", frame);
    fake_receive(&gateway, frame, n);
    region_frames = grid_frames = 0;
    for (uint32_t k = 0; k < 1000; k++) {
        fake_now++;
        fr_poll();
        scan_camera();
        scan_sent();
    }
    /* on to the end of the frame being read, so the last frame sent is the one the body keeps */
    for (uint32_t frames = fr_body_stats()->havimo_frames, k = 0; k < 200 && fr_body_stats()->havimo_frames == frames; k++) {
        fake_now++;
        fr_poll();
        scan_camera();
        scan_sent();
    }
    CHECK(fr_option_enabled(regions) && fr_option_enabled(grid));
    CHECK(keepalives_on_time());
    const fr_body_stats_t *st = fr_body_stats();
    CHECK(st->havimo_frames >= 5);
    CHECK(st->havimo_lost == 0);
    CHECK(region_frames == st->havimo_frames && grid_frames == st->havimo_frames);
    uint32_t frame_no;
    const uint8_t *records, *cells;
    size_t count;
    CHECK(fr_body_camera(&frame_no, &records, &count, &cells));
    CHECK(count == 2 && records[0] == 1 && records[1] == 1 && records[16] == 2 && records[17] == 2);
    uint16_t pixels = (uint16_t)(records[2] | records[3] << 8);
    CHECK(pixels > 150 && pixels < 250); /* the ball, radius 8 */
    CHECK(last_records_len == 32 && memcmp(last_records, records, 32) == 0);
    CHECK(cells != NULL && last_cells_len == FR_HAVIMO_GRID_SIZE && memcmp(last_cells, cells, FR_HAVIMO_GRID_SIZE) == 0);
    CHECK(cells != NULL && (cells[32 * 23] & 0x0F) == 2 && (cells[32 * 23] >> 4) == 15); /* the field fills the bottom row */
    CHECK(telemetry_count == 1 && decoded_count == 18); /* the servos are read beside the camera */
    CHECK(st->bus_errors == 0);
}

/* ---- the bridge ------------------------------------------------------------------------------------------------ */

static uint8_t request_bytes[200];
static size_t request_len;

/** Encode callback: the request's bytes. */
static bool encode_request(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    (void)arg;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, request_bytes, request_len);
}

/** Hands the robot a busBridge frame with `sequence` and the request `hexbytes`, as the stream (or a datagram) would. */
static void bridge_request(uint32_t sequence, const char *hexbytes, bool via_stream) {
    request_len = hex(hexbytes, request_bytes);
    naogateway_proto_BusBridge bb = naogateway_proto_BusBridge_init_zero;
    bb.sequence = sequence;
    bb.request.funcs.encode = encode_request;
    pb_extension_t ext = {&naogateway_proto_busBridge, &bb, NULL, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.robotID = 1;
    msg.extensions = &ext;
    uint8_t buf[FR_HEADER_MAX + 400];
    pb_ostream_t out = pb_ostream_from_buffer(buf + FR_HEADER_MAX, sizeof buf - FR_HEADER_MAX);
    CHECK(pb_encode(&out, naogateway_proto_Message_fields, &msg));
    uint8_t *frame = fr_frame_header(buf + FR_HEADER_MAX, out.bytes_written, FR_FORM_COMPACT);
    size_t len = out.bytes_written + 8;
    if (via_stream) fr_handle_frame(&gateway, frame, len, true);
    else fake_receive(&gateway, frame, len);
}

/** One bridge reply the robot sent through the stream. */
typedef struct {
    uint32_t sequence;
    int result;
    uint8_t reply[300];
    size_t reply_len;
    uint8_t seq; /* the stream segment's sequence number */
} bridge_reply_t;

static bridge_reply_t replies[16];
static size_t reply_count;
static uint8_t *reply_target;
static size_t *reply_target_len;

/** Decode callback: BusBridge.reply. */
static bool decode_reply(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field; (void)arg;
    size_t n = stream->bytes_left;
    if (n > 300) return false;
    *reply_target_len = n;
    return pb_read(stream, reply_target, n);
}

/** Collects the bridge replies among the stream segments sent, and ACKs each at once (as the gateway would). */
static void scan_replies(void) {
    for (size_t k = 0; k < fake_sent_count; k++) {
        size_t len;
        bool segment;
        const uint8_t *p = payload_of(&fake_sent[k], &len, &segment);
        if (p == NULL || !segment || reply_count == 16) continue;
        bridge_reply_t *r = &replies[reply_count];
        memset(r, 0, sizeof *r);
        reply_target = r->reply;
        reply_target_len = &r->reply_len;
        naogateway_proto_BusBridge bb = naogateway_proto_BusBridge_init_zero;
        bb.reply.funcs.decode = decode_reply;
        pb_extension_t ext = {&naogateway_proto_busBridge, &bb, NULL, false};
        naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
        msg.extensions = &ext;
        pb_istream_t in = pb_istream_from_buffer(p, len);
        if (!pb_decode(&in, naogateway_proto_Message_fields, &msg) || !ext.found) continue;
        r->sequence = bb.sequence;
        r->result = bb.has_result ? (int)bb.result : -1;
        r->seq = fake_sent[k].data[0];
        reply_count++;
        uint8_t ack[2] = {FR_STREAM_MAX_SEQ, r->seq}; /* a pure ACK: the gateway has sent no stream data itself */
        fake_receive(&gateway, ack, 2);
    }
}

/** Runs until `count` replies have come, at most `limit` milliseconds. */
static void wait_replies(size_t count, uint32_t limit);

/** Runs `ms` milliseconds collecting replies and keep-alives. */
static void run_bridge(uint32_t ms) {
    for (uint32_t k = 0; k < ms; k++) {
        fake_now++;
        fr_poll();
        scan_replies();
        scan_sent();
    }
}

static void wait_replies(size_t count, uint32_t limit) {
    for (uint32_t k = 0; k < limit && reply_count < count; k++) run_bridge(1);
}

static void test_bridge(void) {
    start_robot();
    fr_body_settings_t b = body_settings(18, true);
    CHECK(fr_body_init(&b));
    reply_count = 0;
    run_bridge(10);

    bridge_request(7, "FF FF 01 02 01 FB", true); /* ping servo 1 */
    wait_replies(1, 100);
    CHECK(reply_count == 1 && replies[0].sequence == 7 && replies[0].result == 0);
    CHECK(same_bytes(replies[0].reply, replies[0].reply_len, "FF FF 01 02 00 FC"));

    /* two requests at once: replies in order, each with its own sequence */
    uint8_t p[FR_DXL_TX_MAX];
    const uint8_t goal[3] = {30, 0x00, 0x03}; /* goal position 768 */
    size_t n = fr_dxl_packet(p, 2, FR_DXL_WRITE, goal, 3);
    char hexbuf[64];
    for (size_t k = 0; k < n; k++) snprintf(hexbuf + 3 * k, 4, "%02X ", p[k]);
    bridge_request(8, hexbuf, true);
    bridge_request(9, "FF FF 02 04 02 1E 02 D7", true); /* read its goal back */
    wait_replies(3, 100);
    CHECK(reply_count == 3 && replies[1].sequence == 8 && replies[2].sequence == 9);
    CHECK(replies[1].result == 0 && same_bytes(replies[1].reply, replies[1].reply_len, "FF FF 02 02 00 FB"));
    CHECK(replies[2].result == 0 && replies[2].reply_len == 8 && replies[2].reply[5] == 0x00 && replies[2].reply[6] == 0x03);
    uint32_t frames = fr_body_stats()->havimo_frames;
    run_bridge(1000);
    CHECK(busmodel_servo(2)[36] == 0x00 && busmodel_servo(2)[37] == 0x03); /* it got there */
    /* a tool on the bridge has the camera to itself: at most the frame in progress was finished */
    CHECK(fr_body_stats()->havimo_frames <= frames + 1);
    run_bridge(1500);
    CHECK(fr_body_stats()->havimo_frames >= frames + 3); /* and the robot's own reads come back after the quiet time */

    /* a servo's ping while the camera and the telemetry keep the bus busy */
    bridge_request(10, "FF FF 0C 02 01 F0", true);
    wait_replies(4, 100);
    CHECK(reply_count == 4 && replies[3].sequence == 10 && replies[3].result == 0 && replies[3].reply_len == 6);

    /* malformed: a wrong checksum; never on the bus */
    uint32_t writes = bus_writes;
    uint32_t transactions = fr_body_stats()->transactions;
    bridge_request(11, "FF FF 01 02 01 FA", true);
    wait_replies(5, 100);
    CHECK(reply_count == 5 && replies[4].sequence == 11 && replies[4].result == 3 && replies[4].reply_len == 0);
    (void)writes;
    CHECK(fr_body_stats()->bridge_malformed == 1);
    bridge_request(12, "FF FF 01", true); /* not even a header */
    wait_replies(6, 100);
    CHECK(reply_count == 6 && replies[5].result == 3);
    (void)transactions;

    /* a silent servo: BUS_TIMEOUT after the reply timeout, no reply bytes, keep-alives on time */
    busmodel_silent(4, true);
    bridge_request(13, "FF FF 04 02 01 F8", true);
    run_bridge(10);
    CHECK(reply_count == 6); /* still waiting: the reply timeout is 20 ms */
    wait_replies(7, 100);
    CHECK(reply_count == 7 && replies[6].sequence == 13 && replies[6].result == 1 && replies[6].reply_len == 0);
    busmodel_silent(4, false);

    /* a damaged status goes back as received, with BUS_TIMEOUT */
    busmodel_corrupt_next(1);
    bridge_request(14, "FF FF 01 02 01 FB", true);
    wait_replies(8, 100);
    CHECK(reply_count == 8 && replies[7].result == 1 && replies[7].reply_len == 6 && replies[7].reply[2] == 1);

    /* broadcast sync write: BUS_OK at once, no reply */
    const uint8_t speeds[] = {32, 2, 1, 100, 0, 2, 100, 0}; /* moving speed 100 for servos 1 and 2 */
    n = fr_dxl_packet(p, FR_DXL_BROADCAST, FR_DXL_SYNC_WRITE, speeds, sizeof speeds);
    for (size_t k = 0; k < n; k++) snprintf(hexbuf + 3 * k, 4, "%02X ", p[k]);
    bridge_request(15, hexbuf, true);
    wait_replies(9, 100);
    CHECK(reply_count == 9 && replies[8].result == 0 && replies[8].reply_len == 0);
    CHECK(busmodel_servo(1)[32] == 100 && busmodel_servo(2)[32] == 100);

    /* a plain datagram carrying busBridge: dropped and counted, never answered */
    bridge_request(16, "FF FF 01 02 01 FB", false);
    run_bridge(10);
    CHECK(reply_count == 9 && fr_body_stats()->bridge_plain == 1);

    /* the gate: READY, SET or PLAYING in the GameController packet the robot uses close it */
    fr_game_t game;
    memset(&game, 0, sizeof game);
    game.game_state = 3;
    fr_state.settings.callbacks.game(&game, fr_state.settings.callbacks.ctx);
    writes = bus_writes;
    bridge_request(17, "FF FF 01 02 01 FB", true);
    wait_replies(10, 100);
    CHECK(reply_count == 10 && replies[9].sequence == 17 && replies[9].result == 2);
    game.game_state = 4; /* FINISHED opens it */
    fr_state.settings.callbacks.game(&game, fr_state.settings.callbacks.ctx);
    bridge_request(18, "FF FF 01 02 01 FB", true);
    wait_replies(11, 100);
    CHECK(reply_count == 11 && replies[10].result == 0);

    /* three at once where two may wait: the third is dropped and counted (the gateway keeps one in flight) */
    bridge_request(21, "FF FF 01 02 01 FB", true);
    bridge_request(22, "FF FF 02 02 01 FA", true);
    bridge_request(23, "FF FF 03 02 01 F9", true);
    wait_replies(13, 100);
    run_bridge(50);
    CHECK(reply_count == 13 && replies[11].sequence == 21 && replies[12].sequence == 22 && replies[12].result == 0);
    CHECK(fr_body_stats()->bridge_overflow == 1);

    CHECK(keepalives_on_time());
    CHECK(telemetry_count >= 1);

    /* no bus: BUS_DISABLED */
    start_robot();
    bus_present = false;
    CHECK(!fr_body_init(&b));
    reply_count = 0;
    bridge_request(19, "FF FF 01 02 01 FB", true);
    wait_replies(1, 100);
    CHECK(reply_count == 1 && replies[0].sequence == 19 && replies[0].result == 4);
    CHECK(keepalives_on_time() && telemetry_count == 0);
    bus_present = true;

    /* the bridge switched off: BUS_DISABLED too */
    start_robot();
    b.bridge = false;
    CHECK(fr_body_init(&b));
    reply_count = 0;
    bridge_request(20, "FF FF 01 02 01 FB", true);
    wait_replies(1, 100);
    CHECK(reply_count == 1 && replies[0].result == 4);
}

/** A pseudo-random number (xorshift32), for repeatable mutations. */
static uint32_t rng = 12345;
static uint32_t next_random(void) {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

/** Random requests, some well-formed and most not, while the bus babbles now and then: never more replies than
 *  requests, the counters add up, and the keep-alives stay on time. */
static void test_bridge_fuzz(void) {
    start_robot();
    fr_body_settings_t b = body_settings(18, true);
    b.bridge_timeout_ms = 3;
    CHECK(fr_body_init(&b));
    reply_count = 0;
    size_t replies_seen = 0;
    uint32_t sent_requests = 0;
    char hexbuf[3 * 200 + 1];
    for (int round = 0; round < 1500; round++) {
        uint8_t p[200];
        size_t n = next_random() % 160;
        for (size_t k = 0; k < n; k++) p[k] = (uint8_t)next_random();
        if (next_random() % 3 == 0 && n >= 6) { /* a well-formed packet to a random id */
            uint8_t params[140];
            size_t count = n - 6 < sizeof params ? n - 6 : sizeof params;
            memcpy(params, p + 6, count);
            n = fr_dxl_packet(p, (uint8_t)(next_random() % 20 == 0 ? 0xFE : next_random() % 110), (uint8_t)next_random(),
                              params, count);
        }
        for (size_t k = 0; k < n; k++) snprintf(hexbuf + 3 * k, 4, "%02X ", p[k]);
        hexbuf[3 * n] = '\0';
        bus_stuck_low = next_random() % 10 == 0;
        bridge_request((uint32_t)round, n ? hexbuf : "", true);
        sent_requests++;
        for (int k = 0; k < 8; k++) {
            fake_now++;
            fr_poll();
            scan_replies();
            scan_sent();
            if (reply_count == 16) { replies_seen += 16; reply_count = 0; }
        }
    }
    bus_stuck_low = false;
    for (int k = 0; k < 100; k++) {
        fake_now++;
        fr_poll();
        scan_replies();
        scan_sent();
        if (reply_count == 16) { replies_seen += 16; reply_count = 0; }
    }
    replies_seen += reply_count;
    const fr_body_stats_t *st = fr_body_stats();
    CHECK(replies_seen <= sent_requests);
    CHECK(replies_seen == st->bridge_requests); /* every request taken was answered, once */
    CHECK(st->bridge_requests + st->bridge_overflow == sent_requests);
    CHECK(keepalives_on_time());
    CHECK(st->bridge_malformed > 100);
}

int main(void) {
    test_packets();
    test_master_faults();
    test_telemetry();
    test_havimo(false, FR_HAVIMO_CAP_REGION);
    test_havimo(true, FR_DXL_WRITE); /* one read of the region table; the capture as a write to address 0 */
    test_bridge();
    test_bridge_fuzz();
    return DONE();
}
