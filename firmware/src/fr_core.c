/* firmware/src/fr_core.c: start-up (and its refusal of settings that would not be safe), the poll loop, telling
 * datagrams apart (docs/protocol.md section 3), the checks before a frame is acted on (the paired gateway, the
 * robot's id, the signature), the keep-alive (6.2), decoding incoming frames and encoding, framing and signing
 * outgoing ones. */
#include <string.h>
#include "fr_internal.h"
#include "naogateway/proto/debugging.pb.h"
#include "naogateway/proto/rpc.pb.h"

/** Datagrams handled per fr_poll at most, so one call stays short even under a flood. */
#define FR_POLL_DATAGRAMS 4

fr_state_t fr_state;
fr_body_hooks_t fr_body_hooks;

/* The one frame buffer of both directions (docs/firmware.md, "Memory"): a received datagram at its start (decoded in
 * place, its RPC parameters and option names copied out while decoding), an outgoing frame encoded at
 * frame + FR_HEADER_MAX with its header written in front. So nothing is encoded while a received frame is still
 * read: debug option callbacks run after decoding (fr_debug_after), and a stream callback's data are valid only
 * until it sends. The port may still be sending from it or copying into it: fr_port_frame_free guards every
 * write. */
static uint8_t frame_buf[FR_HEADER_MAX + FR_DATAGRAM_MAX];

uint32_t fr_uptime_ms(void) { return fr_port_millis() - fr_state.boot_ms; }

const fr_stats_t *fr_stats(void) { return &fr_state.stats; }

fr_route_t fr_route_gateway(void) {
    fr_route_t r;
    r.to = fr_state.gateway;
    r.form = fr_state.settings.form;
    r.via_stream = false;
    return r;
}

bool fr_send_raw(const fr_endpoint_t *to, const uint8_t *data, size_t len) {
    if (fr_port_send(to, data, len) < 0) {
        fr_state.stats.send_failed++;
        return false;
    }
    fr_state.stats.sent++;
    return true;
}

bool fr_out_begin(fr_out_t *w, const fr_route_t *route) {
    if (!fr_state.started) return false; /* refused settings: the robot says nothing it cannot sign */
    if (!fr_port_frame_free()) { /* the port still sends the last frame from the buffer, or receives into it */
        fr_state.stats.send_failed++;
        return false;
    }
    size_t header = route->form == FR_FORM_LEGACY ? 12u : 8u;
    size_t room = FR_DATAGRAM_MAX - header;
    if (route->via_stream && room > FR_STREAM_PAYLOAD_MAX - header) room = FR_STREAM_PAYLOAD_MAX - header;
    w->p = frame_buf + FR_HEADER_MAX;
    w->end = w->p + (fr_state.signing ? room - FR_SIGNATURE_FIELD_SIZE : room);
    fr_out_int(w, naogateway_proto_Message_robotID_tag, fr_state.settings.robot_id);
    return true;
}

bool fr_out_send(fr_out_t *w, const fr_route_t *route) {
    uint8_t *payload = frame_buf + FR_HEADER_MAX;
    size_t len = w->p ? (size_t)(w->p - payload) : 0u;
    if (len > 0 && fr_state.signing) len = fr_sign_append(payload, len, len + FR_SIGNATURE_FIELD_SIZE);
    if (len == 0) {
        fr_state.stats.send_failed++;
        return false;
    }
    size_t header = route->form == FR_FORM_LEGACY ? 12u : 8u;
    uint8_t *frame = fr_frame_header(payload, len, route->form);
    if (route->via_stream) return fr_stream_send(frame, len + header);
    return fr_send_raw(&route->to, frame, len + header);
}

bool fr_send_message(const fr_route_t *route, naogateway_proto_Message *msg) {
    fr_out_t w;
    if (!fr_out_begin(&w, route)) return false;
    uint8_t *payload = frame_buf + FR_HEADER_MAX;
    pb_ostream_t out = pb_ostream_from_buffer(payload, (size_t)(w.end - payload));
    msg->robotID = fr_state.settings.robot_id;
    w.p = pb_encode(&out, naogateway_proto_Message_fields, msg) ? payload + out.bytes_written : NULL;
    return fr_out_send(&w, route);
}

/* ---- the keep-alive ---------------------------------------------------------------------------------- */

/** Sends one keep-alive: Status and RobotHealth in one frame (protocol.md 6.2, 9.13). */
static FR_NOINLINE void send_keepalive(void) {
    fr_route_t route = fr_route_gateway();
    fr_out_t w;
    if (!fr_out_begin(&w, &route)) return;
    fr_health_t h = {0.0f, "sit", false, 0, 0, 0.0f, NULL};
    if (fr_state.settings.callbacks.health) fr_state.settings.callbacks.health(&h, fr_state.settings.callbacks.ctx);
    uint32_t up = fr_uptime_ms();

    uint8_t *at = fr_out_open(&w, naogateway_proto_status_tag);
    fr_out_uint(&w, naogateway_proto_Status_timestamp_tag, up);
    fr_out_uint(&w, naogateway_proto_Status_teamID_tag, fr_state.settings.team_number);
    fr_out_uint(&w, naogateway_proto_Status_timeOnline_tag, up / 1000u);
    if (h.has_position) {
        uint8_t *pos = fr_out_open(&w, naogateway_proto_Status_robotPosition_tag);
        fr_out_int(&w, naogateway_proto_Position_x_tag, h.x_mm);
        fr_out_int(&w, naogateway_proto_Position_y_tag, h.y_mm);
        fr_out_float(&w, naogateway_proto_Position_rotation_tag, h.rotation);
        fr_out_close(&w, pos);
    }
    fr_out_string(&w, naogateway_proto_Status_activeAgent_tag, fr_state.settings.agent);
    fr_out_string(&w, naogateway_proto_Status_activeRole_tag, fr_state.settings.role);
    fr_out_string(&w, naogateway_proto_Status_currentState_tag, h.current_state ? h.current_state : h.posture);
    fr_out_close(&w, at);

    at = fr_out_open(&w, naogateway_proto_robotHealth_tag);
    fr_out_float(&w, naogateway_proto_RobotHealth_batteryVoltage_tag, h.battery_voltage);
    fr_out_string(&w, naogateway_proto_RobotHealth_posture_tag, h.posture);
    fr_out_uint(&w, naogateway_proto_RobotHealth_uptimeMs_tag, up);
    fr_out_uint(&w, naogateway_proto_RobotHealth_bootId_tag, fr_state.settings.boot_id);
    /* every keep-alive of an unsigned build says so (protocol.md 6.7) */
    if (fr_state.settings.development) fr_out_uint(&w, naogateway_proto_RobotHealth_development_tag, 1);
    fr_board_health_t board = {0, false, false};
    if (fr_port_board_health(&board)) {
        uint8_t *b = fr_out_open(&w, naogateway_proto_RobotHealth_board_tag);
        fr_out_uint(&w, naogateway_proto_BoardHealth_coreClockHz_tag, board.core_clock_hz);
        if (board.stack_overflow_reset) fr_out_uint(&w, naogateway_proto_BoardHealth_stackOverflowReset_tag, 1);
        if (board.fault_reset) fr_out_uint(&w, naogateway_proto_BoardHealth_faultReset_tag, 1);
        fr_out_close(&w, b);
    }
    fr_out_close(&w, at);

    /* servoTelemetry (7106) after robotHealth, once per telemetry period (protocol.md 6.8) */
    if (w.p != NULL && fr_body_hooks.keepalive) {
        pb_ostream_t out = pb_ostream_from_buffer(w.p, (size_t)(w.end - w.p));
        w.p = fr_body_hooks.keepalive(&out) ? w.p + out.bytes_written : NULL;
    }
    (void)fr_out_send(&w, &route);
}

/* ---- incoming frames ---------------------------------------------------------------------------------- */

/** What one reading of a frame's Message found (protocol.md 6): its robotID and which extensions. */
typedef struct {
    bool robot_id, request, commands;
} message_seen_t;

/** One field of the Message envelope: robotID (required), rpcRequest, debuggingCommands and the body's extension;
 *  any other is skipped (message.proto: every other field number is an extension the robot does not read). */
static int message_field(pb_istream_t *s, uint32_t tag, pb_wire_type_t wire, void *ctx) {
    message_seen_t *seen = (message_seen_t *)ctx;
    uint64_t v;
    switch (tag) {
    case naogateway_proto_Message_robotID_tag: /* an int32: any varint fits once cast, as nanopb casts it */
        seen->robot_id = true;
        return wire == PB_WT_VARINT && pb_decode_varint(s, &v) ? 1 : -1;
    case naogateway_proto_rpcRequest_tag:
        seen->request = true;
        return fr_rpc_read(s, wire) ? 1 : -1;
    case naogateway_proto_debuggingCommands_tag:
        seen->commands = true;
        return fr_debug_read(s, wire) ? 1 : -1;
    default: return fr_body_hooks.field ? fr_body_hooks.field(s, tag, wire, NULL) : 0;
    }
}

void fr_handle_frame(const fr_endpoint_t *from, const uint8_t *data, size_t len, bool via_stream) {
    const uint8_t *payload;
    size_t payload_len;
    fr_form_t form;
    fr_frame_error_t e = fr_frame_parse(data, len, &payload, &payload_len, &form);
    if (e == FR_FRAME_GZIP) { fr_state.stats.gzip++; return; }
    if (e != FR_FRAME_OK) { fr_state.stats.bad_frame++; return; }
    int32_t named = 0;
    int found = fr_message_robot_id(payload, payload_len, &named);
    if (found < 0) { fr_state.stats.bad_protobuf++; return; }
    if (found == 0 || named != fr_state.settings.robot_id) { fr_state.stats.wrong_robot++; return; }
    if (fr_state.signing) {
        size_t signed_len;
        switch (fr_sign_check(payload, payload_len, &signed_len)) {
        case FR_SIG_OK: break;
        case FR_SIG_UNSIGNED: fr_state.stats.unsigned_frames++; return;
        case FR_SIG_NOT_LAST: fr_state.stats.signature_not_last++; return;
        case FR_SIG_MALFORMED: fr_state.stats.malformed_signature++; return;
        case FR_SIG_BAD: fr_state.stats.bad_signature++; return;
        case FR_SIG_REPLAYED: fr_state.stats.replayed++; return;
        }
        if (!fr_state.paired) { /* pair on the first signed frame: this sender is the gateway until the restart */
            fr_state.gateway = *from;
            fr_state.paired = true;
        }
    }
    fr_route_t route;
    route.to = *from; /* the paired gateway: answers go back to its robot port (protocol.md 2) */
    route.form = form;
    route.via_stream = via_stream;

    /* Two passes when debug commands are present: the first only checks the whole frame (so a frame refused
     * half-way switches nothing), the second applies the names. */
    for (int pass = 0; pass < 2; pass++) {
        fr_rpc_prepare();
        fr_debug_prepare(pass == 1);
        if (fr_body_hooks.prepare) fr_body_hooks.prepare();
        message_seen_t seen = {false, false, false};
        pb_istream_t in = pb_istream_from_buffer(payload, payload_len);
        if (!fr_in_message(&in, message_field, &seen) || !seen.robot_id) {
            fr_state.stats.bad_protobuf++;
            return;
        }
        if (pass == 0 && seen.commands) continue;
        if (seen.commands) fr_debug_after(&route);
        if (seen.request) fr_rpc_dispatch(&route);
        if (fr_body_hooks.after) fr_body_hooks.after(&route);
        return;
    }
}

/** Tells datagrams apart by their first two bytes (protocol.md section 3). */
static void handle_datagram(const fr_endpoint_t *from, const uint8_t *data, size_t len) {
    if (len < 2 || len > FR_DATAGRAM_MAX) { fr_state.stats.unclassifiable++; return; }
    bool from_gateway = from->port == fr_state.gateway.port && memcmp(from->ip, fr_state.gateway.ip, 4) == 0;
    if (data[0] == 0 && data[1] == 42) {
        /* Until a pairing robot has paired, any sender may offer the first signed frame; only its signature counts. */
        if (fr_state.paired && !from_gateway) { fr_state.stats.stranger++; return; }
        if (!fr_state.started) { fr_state.stats.not_started++; return; }
        fr_handle_frame(from, data, len, false);
    } else if (data[0] == 'R' && data[1] == 'G') {
        fr_gc_receive(from, data, len);
    } else if (data[0] < 42 && data[1] < 42) {
        if (!fr_state.paired || !from_gateway) { fr_state.stats.stranger++; return; }
        if (!fr_state.started) { fr_state.stats.not_started++; return; }
        fr_stream_receive(data, len);
    } else {
        fr_state.stats.unclassifiable++;
    }
}

/* ---- start and poll ----------------------------------------------------------------------------------- */

/** Whether the settings' trust part is one the library can run safely. */
static fr_init_result_t check_trust(const fr_settings_t *s) {
    if (s->development) {
        if (s->signing_key_len > 0) return FR_INIT_KEY_IN_DEVELOPMENT;
        if (s->pair_on_first_signed) return FR_INIT_PAIRING_UNSIGNED;
        return FR_INIT_OK;
    }
    if (s->signing_key == NULL || s->signing_key_len == 0) return FR_INIT_NO_KEY;
    if (s->signing_key_len < 16 || s->signing_key_len > FR_SIGNING_KEY_MAX) return FR_INIT_KEY_LENGTH;
    return FR_INIT_OK;
}

fr_init_result_t fr_init(const fr_settings_t *settings) {
    memset(&fr_state, 0, sizeof fr_state);
    fr_state.settings = *settings;
    fr_state.link_up = true;
    fr_state.gateway = settings->gateway;
    fr_state.paired = !settings->pair_on_first_signed;
    fr_rpc_reset();
    fr_debug_reset();
    fr_gc_reset();
    fr_stream_reset();
    /* What the module passed on before this start belongs to the previous session: drop it (bounded). */
    fr_endpoint_t from;
    for (int k = 0; k < 64 && fr_port_recv(&from, frame_buf, FR_DATAGRAM_MAX) != 0; k++) {}
    fr_state.boot_ms = fr_port_millis();
    fr_state.next_keepalive = 0;
    fr_init_result_t r = check_trust(settings);
    fr_state.signing = !settings->development;
    /* A new epoch at every start of a signing robot, before its first frame: its timestamps rise above every
     * earlier boot's, and the gateway's frames of an earlier boot no longer verify. */
    if (r == FR_INIT_OK && fr_state.signing && fr_port_epoch_next(&fr_state.epoch) < 0) r = FR_INIT_EPOCH;
    fr_state.started = r == FR_INIT_OK;
    if (fr_state.started && fr_state.signing)
        fr_hmac_key(&fr_state.mac_key, settings->signing_key, settings->signing_key_len);
    return r;
}

const char *fr_init_error_text(fr_init_result_t result) {
    switch (result) {
    case FR_INIT_OK: return "started";
    case FR_INIT_NO_KEY: return "no signing key: a robot signs unless it is built or started as a development build";
    case FR_INIT_KEY_LENGTH: return "signing key refused: it must be 16 to 64 bytes";
    case FR_INIT_KEY_IN_DEVELOPMENT: return "a development build takes no signing key: give either a key or development";
    case FR_INIT_PAIRING_UNSIGNED: return "pairing on the first signed frame needs signing: not in a development build";
    case FR_INIT_EPOCH: return "the boot epoch could not be raised (its store cannot be read or written)";
    }
    return "settings refused";
}

uint32_t fr_epoch(void) { return fr_state.epoch; }

bool fr_gateway(fr_endpoint_t *out) {
    *out = fr_state.gateway;
    return fr_state.paired;
}

void fr_poll(void) {
    bool up = fr_port_link_up();
    if (up != fr_state.link_up) {
        fr_state.link_up = up;
        if (fr_state.settings.callbacks.link) fr_state.settings.callbacks.link(up, fr_state.settings.callbacks.ctx);
    }
    for (int k = 0; k < FR_POLL_DATAGRAMS; k++) {
        fr_endpoint_t from;
        int n = fr_port_recv(&from, frame_buf, FR_DATAGRAM_MAX);
        if (n == 0) break;
        if (n < 0) { fr_state.stats.recv_lost++; continue; }
        fr_state.stats.received++;
        handle_datagram(&from, frame_buf, (size_t)n);
    }
    if (!fr_state.started) return; /* refused settings: nothing to send, nothing to resend */
    uint32_t up_ms = fr_uptime_ms();
    /* A keep-alive due while the buffer is busy goes at the first poll it is free: late, never skipped. */
    if ((int32_t)(up_ms - fr_state.next_keepalive) >= 0 && fr_port_frame_free()) {
        fr_state.next_keepalive += FR_KEEPALIVE_MS;
        if ((int32_t)(up_ms - fr_state.next_keepalive) >= 0) fr_state.next_keepalive = up_ms + FR_KEEPALIVE_MS;
        send_keepalive();
    }
    fr_stream_poll();
    if (fr_body_hooks.poll) fr_body_hooks.poll();
}
