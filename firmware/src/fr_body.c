/* firmware/src/fr_body.c: the robot's body on its Dynamixel bus: servo telemetry (protocol.md 6.8), the HaViMo2
 * read over the bus (6.5) and the bus bridge (6.9), sharing one master (fr_dxl.c). Between transactions the bus is
 * given in this order: a bridged request first, then the camera and the telemetry by turns, so a bridged request
 * waits for at most the one transaction in progress. Nothing waits: fr_poll moves everything on through the hooks
 * of fr_internal.h. */
#include <string.h>
#include "fr_internal.h"
#include "fr_body.h"
#include "fr_port_bus.h"
#include "naogateway/proto/body.pb.h"

/** Who the transaction in progress is for. */
typedef enum { OWNER_NONE, OWNER_BRIDGE, OWNER_SERVO, OWNER_CAMERA } owner_t;

/** Where the camera's read cycle is. */
typedef enum { CAM_IDLE, CAM_CAPTURE, CAM_WAIT, CAM_REGIONS, CAM_GRID_CAPTURE, CAM_GRID_WAIT, CAM_GRID_READ } cam_state_t;

/** One bridged request waiting for the bus, and where its reply goes. */
typedef struct {
    uint32_t sequence;
    bool bad;              /* no request, or longer than FR_DXL_TX_MAX: malformed without a look */
    uint8_t len;
    uint8_t request[FR_DXL_TX_MAX];
    fr_route_t route;
} bridge_request_t;

static fr_body_settings_t cfg;
static bool bus_open;
static fr_body_stats_t stats;
static owner_t owner;
static bool camera_turn;
static uint32_t last_bridged;   /* uptime of the latest bridged request */
static bool bridged;
static uint8_t game_state; /* of the latest GameController packet the library used; 0 INITIAL before any */
static void (*program_game)(const fr_game_t *game, void *ctx);

static fr_servo_t servos[FR_BODY_SERVOS_MAX];
static size_t sweep_next;       /* the servo the sweep reads next; servo_count when the sweep is done */
static uint32_t next_sweep, next_telemetry;

static struct {
    cam_state_t state;
    uint32_t next_at, began, wait_began;
    uint32_t frame;
    uint8_t k;                  /* region record or grid chunk read next */
    bool has_frame, has_grid, grid_this_frame;
    uint8_t table[FR_HAVIMO_TABLE_SIZE];
    uint8_t records[FR_HAVIMO_TABLE_SIZE]; /* of the last whole frame */
    size_t count;
    uint8_t next_records[FR_HAVIMO_TABLE_SIZE]; /* of the frame being read */
    size_t next_count;
    uint8_t cells[FR_HAVIMO_GRID_SIZE];
} cam;

static bridge_request_t queue[FR_BODY_BRIDGE_QUEUE];
static size_t queue_head, queue_count;
static bridge_request_t incoming;          /* the frame being decoded */
static naogateway_proto_BusBridge incoming_msg;
static bool incoming_found;              /* the frame had a busBridge */
static struct {
    bool pending;
    uint32_t sequence;
    naogateway_proto_BusResult result;
    uint8_t reply[FR_DXL_RX_MAX];
    size_t len;
    fr_route_t route;
} answer;

static naogateway_proto_ServoTelemetry telemetry_msg;

const fr_body_stats_t *fr_body_stats(void) { return &stats; }

const fr_servo_t *fr_body_servos(size_t *count) {
    *count = cfg.servo_count;
    return servos;
}

bool fr_body_camera(uint32_t *frame, const uint8_t **records, size_t *count, const uint8_t **cells) {
    if (!cam.has_frame) return false;
    *frame = cam.frame;
    *records = cam.records;
    *count = cam.count;
    *cells = cam.has_grid && cam.state != CAM_GRID_READ ? cam.cells : NULL; /* never a grid half read */
    return true;
}

void fr_body_defaults(fr_body_settings_t *s) {
    memset(s, 0, sizeof *s);
    s->baud = 1000000u;
    s->telemetry_ms = 1000u;
    s->servo_timeout_ms = 4u;
    s->havimo_id = 100u;
    s->havimo_capture = FR_HAVIMO_CAP_REGION;
    s->havimo_period_ms = 100u;
    s->havimo_wait_ms = 200u;
    s->havimo_ping_ms = 5u;
    s->havimo_timeout_ms = 10u;
    s->havimo_table_read = false;
    s->havimo_grid = true;
    s->havimo_grid_chunk = 16u;
    s->havimo_regions_option = -1;
    s->havimo_grid_option = -1;
    s->bridge = true;
    s->bridge_timeout_ms = 20u;
    s->bridge_quiet_ms = 2000u;
}

/* ---- the transaction ---------------------------------------------------------------------------------- */

/** Counts a failed transaction by kind (ServoTelemetry.busErrors counts them all). */
static void count_failure(fr_dxl_result_t r) {
    if (r == FR_DXL_OK || r == FR_DXL_BUSY || r == FR_DXL_IDLE) return;
    stats.bus_errors++;
    if (r == FR_DXL_TIMEOUT) stats.timeouts++;
    else if (r == FR_DXL_SHORT) stats.short_packets++;
    else if (r == FR_DXL_CHECKSUM) stats.checksums++;
    else stats.malformed++;
}

/** Starts a transaction for `who`: instruction `inst` with `n` parameters to `id`. */
static void begin(owner_t who, uint8_t id, uint8_t inst, const uint8_t *params, size_t n, size_t due, uint32_t timeout) {
    uint8_t packet[FR_DXL_TX_MAX];
    size_t len = fr_dxl_packet(packet, id, inst, params, n);
    if (len > 0 && fr_dxl_start(packet, len, due, timeout)) {
        owner = who;
        stats.transactions++;
    }
}

/* ---- telemetry (protocol.md 6.8) ---------------------------------------------------------------------- */

/** Reads the next servo of the sweep: 8 bytes from address 36 (position, speed, load, voltage, temperature). */
static void servo_begin(void) {
    static const uint8_t params[2] = {36, 8};
    begin(OWNER_SERVO, servos[sweep_next].id, FR_DXL_READ, params, 2, 14, cfg.servo_timeout_ms);
}

/** Keeps what the servo's status packet says. */
static void servo_done(fr_dxl_result_t r) {
    fr_servo_t *s = &servos[sweep_next++];
    size_t len;
    const uint8_t *p = fr_dxl_reply(&len);
    count_failure(r);
    if (r != FR_DXL_OK) {
        s->silent = true;
        s->read = false;
        s->error = 0;
        return;
    }
    s->silent = false;
    s->error = p[4];
    s->read = len == 14;
    if (!s->read) return; /* a bare status with its error byte: the error alone */
    s->position = (uint16_t)(p[5] | p[6] << 8);
    s->speed = (uint16_t)(p[7] | p[8] << 8);
    s->load = (uint16_t)(p[9] | p[10] << 8);
    s->voltage = p[11];
    s->temperature = p[12];
}

/** Encodes one ServoState per configured servo (callback of ServoTelemetry.servos). */
static bool encode_servos(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    (void)arg;
    for (size_t k = 0; k < cfg.servo_count; k++) {
        const fr_servo_t *s = &servos[k];
        naogateway_proto_ServoState st = naogateway_proto_ServoState_init_zero;
        st.id = s->id;
        if (s->silent) {
            st.has_silent = st.silent = true;
        } else {
            if (s->error != 0) { st.has_error = true; st.error = s->error; }
            if (s->read) {
                st.has_position = st.has_load = st.has_voltage = st.has_temperature = true;
                st.position = s->position & 0x3FFu;
                int32_t magnitude = (int32_t)(s->load & 0x3FFu);
                st.load = (s->load & 0x400u) ? -magnitude : magnitude;
                st.voltage = s->voltage;
                st.temperature = s->temperature;
            }
        }
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_ServoState_fields, &st))
            return false;
    }
    return true;
}

/** Writes the servoTelemetry extension (7106) when this keep-alive is the one of its period; false when it did not
 *  fit. */
static bool keepalive_hook(pb_ostream_t *out) {
    if (!bus_open || cfg.telemetry_ms == 0 || cfg.servo_count == 0) return true;
    uint32_t now = fr_uptime_ms();
    if ((int32_t)(now - next_telemetry) < 0) return true;
    next_telemetry += cfg.telemetry_ms;
    if ((int32_t)(now - next_telemetry) >= 0) next_telemetry = now + cfg.telemetry_ms;
    memset(&telemetry_msg, 0, sizeof telemetry_msg);
    telemetry_msg.servos.funcs.encode = encode_servos;
    telemetry_msg.has_busErrors = true;
    telemetry_msg.busErrors = stats.bus_errors;
    return pb_encode_tag(out, PB_WT_STRING, naogateway_proto_servoTelemetry_tag) &&
           pb_encode_submessage(out, naogateway_proto_ServoTelemetry_fields, &telemetry_msg);
}

/* ---- the HaViMo2 (docs/firmware.md "The HaViMo2 driver") ---------------------------------------------- */

/** Whether the grid option is on and the grid is read at all. */
static bool grid_wanted(void) {
    return cfg.havimo_grid && cfg.havimo_grid_option >= 0 && fr_option_enabled(cfg.havimo_grid_option);
}

/** Gives the frame up (a capture that never finished, a read that failed); the next capture comes on time. */
static void camera_lost(void) {
    stats.havimo_lost++;
    cam.state = CAM_IDLE;
    cam.next_at = cam.began + cfg.havimo_period_ms;
}

/** Whether the camera needs the bus now. */
static bool camera_due(uint32_t now) {
    if (!cfg.havimo) return false;
    /* a tool on the bridge (the calibration tool) has the camera to itself; a frame begun is finished */
    if (cam.state == CAM_IDLE && bridged && now - last_bridged < cfg.bridge_quiet_ms) return false;
    if (cam.state == CAM_IDLE) {
        if ((int32_t)(now - cam.next_at) < 0) return false;
        cam.state = CAM_CAPTURE;
        cam.began = now;
        return true;
    }
    if (cam.state == CAM_WAIT || cam.state == CAM_GRID_WAIT) return (int32_t)(now - cam.next_at) >= 0;
    return true;
}

/** Starts the camera's next transaction. */
static void camera_begin(void) {
    uint8_t params[2];
    uint8_t id = cfg.havimo_id;
    switch (cam.state) {
    case CAM_CAPTURE:
        params[0] = params[1] = 0; /* a write of 0 to address 0, when that is the capture */
        begin(OWNER_CAMERA, id, cfg.havimo_capture, params, cfg.havimo_capture == FR_DXL_WRITE ? 2u : 0u, 0, 0);
        break;
    case CAM_GRID_CAPTURE: begin(OWNER_CAMERA, id, FR_HAVIMO_CAP_GRID, NULL, 0, 0, 0); break;
    case CAM_WAIT:
    case CAM_GRID_WAIT: begin(OWNER_CAMERA, id, FR_DXL_PING, NULL, 0, 6, cfg.havimo_ping_ms); break;
    case CAM_REGIONS:
        if (cfg.havimo_table_read) {
            params[0] = FR_HAVIMO_RECORD_SIZE;
            params[1] = (uint8_t)FR_HAVIMO_TABLE_SIZE;
        } else {
            params[0] = (uint8_t)(FR_HAVIMO_RECORD_SIZE * (cam.k + 1u));
            params[1] = FR_HAVIMO_RECORD_SIZE;
        }
        begin(OWNER_CAMERA, id, FR_DXL_READ, params, 2, 6u + params[1], cfg.havimo_timeout_ms);
        break;
    case CAM_GRID_READ:
        params[0] = (uint8_t)(cam.k * cfg.havimo_grid_chunk / 16u); /* the camera counts the address in 16 bytes */
        params[1] = cfg.havimo_grid_chunk;
        begin(OWNER_CAMERA, id, FR_HAVIMO_READ_GRID, params, 2, 6u + params[1], cfg.havimo_timeout_ms);
        break;
    case CAM_IDLE: break;
    }
}

/** The frame is whole: keep it and hand it to the HaViMo2 frames (protocol.md 6.5). */
static void camera_finish(void) {
    cam.frame++;
    cam.has_frame = true;
    memcpy(cam.records, cam.next_records, cam.next_count * FR_HAVIMO_RECORD_SIZE);
    cam.count = cam.next_count;
    stats.havimo_frames++;
    if (cfg.havimo_regions_option >= 0) (void)fr_havimo_regions(cfg.havimo_regions_option, cam.frame, cam.records, cam.count);
    if (cam.grid_this_frame) {
        cam.has_grid = true;
        if (cfg.havimo_grid_option >= 0) (void)fr_havimo_grid(cfg.havimo_grid_option, cam.frame, cam.cells);
    }
    cam.state = CAM_IDLE;
    cam.next_at = cam.began + cfg.havimo_period_ms;
}

/** Whether a camera read brought `want` bytes; otherwise the failure is counted and the frame given up. */
static bool camera_read_ok(fr_dxl_result_t r, size_t len, size_t want) {
    count_failure(r);
    if (r == FR_DXL_OK && len == 6 + want) return true;
    if (r == FR_DXL_OK) { /* a bare error status where data was due */
        stats.malformed++;
        stats.bus_errors++;
    }
    camera_lost();
    return false;
}

/** Moves the camera's cycle on after one of its transactions. */
static void camera_done(fr_dxl_result_t r, uint32_t now) {
    size_t len;
    const uint8_t *p = fr_dxl_reply(&len);
    switch (cam.state) {
    case CAM_CAPTURE:
    case CAM_GRID_CAPTURE:
        cam.state = cam.state == CAM_CAPTURE ? CAM_WAIT : CAM_GRID_WAIT;
        cam.next_at = now + cfg.havimo_ping_ms;
        cam.wait_began = now;
        break;
    case CAM_WAIT:
    case CAM_GRID_WAIT:
        /* A busy camera does not answer: silence here is the camera working, not a bus error. */
        if (r == FR_DXL_OK && len == 6) {
            cam.k = 0;
            cam.state = cam.state == CAM_WAIT ? CAM_REGIONS : CAM_GRID_READ;
        } else if (now - cam.wait_began > cfg.havimo_wait_ms) {
            count_failure(r);
            camera_lost();
        } else {
            cam.next_at = now + cfg.havimo_ping_ms;
        }
        break;
    case CAM_REGIONS: {
        size_t want = cfg.havimo_table_read ? FR_HAVIMO_TABLE_SIZE : FR_HAVIMO_RECORD_SIZE;
        if (!camera_read_ok(r, len, want)) break;
        memcpy(cam.table + (cfg.havimo_table_read ? 0u : (size_t)cam.k * FR_HAVIMO_RECORD_SIZE), p + 5, want);
        if (!cfg.havimo_table_read && ++cam.k < FR_HAVIMO_REGIONS_MAX) break;
        cam.next_count = 0;
        for (size_t k = 0; k < FR_HAVIMO_REGIONS_MAX; k++) {
            const uint8_t *rec = cam.table + k * FR_HAVIMO_RECORD_SIZE;
            if (rec[0] == 0) continue; /* an unused slot is never sent (6.5) */
            memcpy(cam.next_records + cam.next_count++ * FR_HAVIMO_RECORD_SIZE, rec, FR_HAVIMO_RECORD_SIZE);
        }
        cam.grid_this_frame = grid_wanted();
        if (cam.grid_this_frame) cam.state = CAM_GRID_CAPTURE;
        else camera_finish();
        break;
    }
    case CAM_GRID_READ: {
        size_t chunk = cfg.havimo_grid_chunk;
        if (!camera_read_ok(r, len, chunk)) break;
        memcpy(cam.cells + (size_t)cam.k * chunk, p + 5, chunk);
        if ((size_t)++cam.k * chunk < FR_HAVIMO_GRID_SIZE) break;
        camera_finish();
        break;
    }
    case CAM_IDLE: break;
    }
}

/* ---- the bridge (protocol.md 6.9) ---------------------------------------------------------------------- */

/** Takes the request's bytes into the frame being decoded; a longer one is skipped and marked malformed. */
static bool decode_request(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field; (void)arg;
    size_t n = stream->bytes_left;
    if (n > FR_DXL_TX_MAX) {
        incoming.bad = true;
        return pb_read(stream, NULL, n);
    }
    incoming.bad = false;
    incoming.len = (uint8_t)n;
    return pb_read(stream, incoming.request, n);
}

/** Empties the busBridge an incoming frame is read into. */
static void prepare_hook(void) {
    memset(&incoming, 0, sizeof incoming);
    incoming.bad = true; /* until a request field says otherwise */
    memset(&incoming_msg, 0, sizeof incoming_msg);
    incoming_msg.request.funcs.decode = decode_request;
    incoming_found = false;
}

/** Reads the busBridge extension (7107) of an incoming frame, by nanopb as an extension field is read: its value
 *  a length-delimited BusBridge, merged into what an earlier one in the same frame left. */
static int field_hook(pb_istream_t *s, uint32_t tag, pb_wire_type_t wire, void *ctx) {
    (void)ctx;
    if (tag != naogateway_proto_busBridge_tag) return 0;
    incoming_found = true;
    pb_istream_t sub;
    if (wire != PB_WT_STRING || !pb_make_string_substream(s, &sub)) return -1;
    return pb_decode_ex(&sub, naogateway_proto_BusBridge_fields, &incoming_msg, PB_DECODE_NOINIT) &&
                   pb_close_string_substream(s, &sub)
               ? 1
               : -1;
}

/** Queues a decoded busBridge request; one that came as a plain datagram is dropped and counted. */
static void after_hook(const fr_route_t *route) {
    if (!incoming_found) return;
    if (!route->via_stream) { stats.bridge_plain++; return; }
    if (queue_count == FR_BODY_BRIDGE_QUEUE) { stats.bridge_overflow++; return; }
    stats.bridge_requests++;
    bridged = true;
    last_bridged = fr_uptime_ms();
    incoming.sequence = incoming_msg.sequence;
    incoming.route = *route;
    queue[(queue_head + queue_count++) % FR_BODY_BRIDGE_QUEUE] = incoming;
}

/** Encodes the answer's status bytes (callback of BusBridge.reply). */
static bool encode_reply(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    (void)arg;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, answer.reply, answer.len);
}

/** Sends the answer once the stream has a free slot; it stays pending until then. */
static void send_answer(void) {
    if (!answer.pending || fr_stream_pending() >= FR_STREAM_QUEUE) return;
    naogateway_proto_BusBridge msg = naogateway_proto_BusBridge_init_zero;
    msg.sequence = answer.sequence;
    msg.has_result = true;
    msg.result = answer.result;
    if (answer.len > 0) msg.reply.funcs.encode = encode_reply;
    pb_extension_t ext = {&naogateway_proto_busBridge, &msg, NULL, true};
    naogateway_proto_Message m = naogateway_proto_Message_init_zero;
    m.extensions = &ext;
    if (fr_send_message(&answer.route, &m)) answer.pending = false;
}

/** Makes the queue's oldest request the answer with `result` and the given bytes. */
static void answer_head(naogateway_proto_BusResult result, const uint8_t *reply, size_t len) {
    bridge_request_t *q = &queue[queue_head];
    answer.pending = true;
    answer.sequence = q->sequence;
    answer.result = result;
    answer.route = q->route;
    answer.len = len > sizeof answer.reply ? sizeof answer.reply : len;
    if (answer.len > 0) memcpy(answer.reply, reply, answer.len);
    queue_head = (queue_head + 1) % FR_BODY_BRIDGE_QUEUE;
    queue_count--;
}

/** Whether the GameController state the robot uses says the game runs (READY, SET, PLAYING): the gate is closed. */
static bool gate_closed(void) { return game_state >= 1 && game_state <= 3; }

/** Answers the oldest request at once when it needs no bus; true when it needs the bus (and may have it). */
static bool bridge_due(void) {
    if (answer.pending || queue_count == 0) return false;
    bridge_request_t *q = &queue[queue_head];
    if (!bus_open || !cfg.bridge) { answer_head(naogateway_proto_BusResult_BUS_DISABLED, NULL, 0); return false; }
    if (gate_closed()) { stats.bridge_gate_closed++; answer_head(naogateway_proto_BusResult_BUS_GATE_CLOSED, NULL, 0); return false; }
    if (q->bad || !fr_dxl_well_formed(q->request, q->len)) {
        stats.bridge_malformed++;
        answer_head(naogateway_proto_BusResult_BUS_MALFORMED, NULL, 0);
        return false;
    }
    return true;
}

/** Sends the oldest request to the bus as it came. */
static void bridge_begin(void) {
    bridge_request_t *q = &queue[queue_head];
    if (fr_dxl_start(q->request, q->len, fr_dxl_reply_due(q->request, q->len), cfg.bridge_timeout_ms)) {
        owner = OWNER_BRIDGE;
        stats.transactions++;
    }
}

/** The bridged transaction ended: its reply, with the bytes the bus returned. */
static void bridge_done(fr_dxl_result_t r) {
    size_t len;
    const uint8_t *p = fr_dxl_reply(&len);
    count_failure(r);
    answer_head(r == FR_DXL_OK ? naogateway_proto_BusResult_BUS_OK : naogateway_proto_BusResult_BUS_TIMEOUT, p, len);
}

/* ---- the loop ------------------------------------------------------------------------------------------ */

/** Records the game state of every used control packet for the gate, then tells the program. */
static void on_game(const fr_game_t *game, void *ctx) {
    game_state = game->game_state;
    if (program_game) program_game(game, ctx);
}

/** One step of the body: ends the transaction in progress or gives the bus to the next in line. */
static void poll_hook(void) {
    uint32_t now = fr_uptime_ms();
    if (fr_state.settings.callbacks.game != on_game) { /* fr_init was run again: wrap the program's callback anew */
        program_game = fr_state.settings.callbacks.game;
        fr_state.settings.callbacks.game = on_game;
    }
    if (owner != OWNER_NONE) {
        fr_dxl_result_t r = fr_dxl_poll();
        if (r == FR_DXL_BUSY) { send_answer(); return; }
        owner_t who = owner;
        owner = OWNER_NONE;
        if (who == OWNER_BRIDGE) bridge_done(r);
        else if (who == OWNER_SERVO) servo_done(r);
        else camera_done(r, now);
    }
    send_answer();
    if (bridge_due()) {
        bridge_begin();
        return;
    }
    send_answer();
    if (!bus_open) return;
    if (cfg.servo_count > 0 && cfg.telemetry_ms > 0 && sweep_next >= cfg.servo_count && (int32_t)(now - next_sweep) >= 0) {
        sweep_next = 0;
        next_sweep += cfg.telemetry_ms;
        if ((int32_t)(now - next_sweep) >= 0) next_sweep = now + cfg.telemetry_ms;
    }
    bool servo = cfg.servo_count > 0 && sweep_next < cfg.servo_count;
    bool camera = camera_due(now);
    if (servo && (!camera || !camera_turn)) {
        camera_turn = true;
        servo_begin();
    } else if (camera) {
        camera_turn = false;
        camera_begin();
    }
}

bool fr_body_init(const fr_body_settings_t *s) {
    cfg = *s;
    if (cfg.servo_count > FR_BODY_SERVOS_MAX) cfg.servo_count = FR_BODY_SERVOS_MAX;
    if (cfg.havimo_grid_chunk < 16 || cfg.havimo_grid_chunk % 16 != 0 || FR_HAVIMO_GRID_SIZE % cfg.havimo_grid_chunk != 0 ||
        cfg.havimo_grid_chunk > 240)
        cfg.havimo_grid_chunk = 16;
    memset(&stats, 0, sizeof stats);
    memset(servos, 0, sizeof servos);
    memset(&cam, 0, sizeof cam);
    memset(&answer, 0, sizeof answer);
    for (size_t k = 0; k < cfg.servo_count; k++) servos[k].id = cfg.servo_ids[k];
    queue_head = queue_count = 0;
    bridged = false;
    owner = OWNER_NONE;
    camera_turn = false;
    game_state = 0;
    fr_dxl_reset(); /* a transaction of an earlier start is nobody's now */
    uint32_t now = fr_uptime_ms();
    sweep_next = 0;
    next_sweep = now + cfg.telemetry_ms;
    next_telemetry = now + cfg.telemetry_ms;
    cam.next_at = now;
    if (fr_state.settings.callbacks.game != on_game) { /* (the poll hook may have wrapped it already) */
        program_game = fr_state.settings.callbacks.game;
        fr_state.settings.callbacks.game = on_game;
    }
    bus_open = fr_port_bus_open(cfg.baud) == 0;
    fr_body_hooks.poll = poll_hook;
    fr_body_hooks.keepalive = keepalive_hook;
    fr_body_hooks.prepare = prepare_hook;
    fr_body_hooks.field = field_hook;
    fr_body_hooks.after = after_hook;
    return bus_open;
}
