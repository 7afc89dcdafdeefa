/* firmware/examples/robot.c: the example robot program. It uses only the public API (fr.h) and the port
 * (fr_port.h), so the same file runs on the posix port (tests, teams without hardware) and on the boards.
 * It serves the ten methods of docs/protocol.md 7.2 with a small model of the robot's body, offers the debug
 * option catalogue of protocol.md section 8 and a synthetic camera, answers the GameController and echoes
 * every secure-stream payload back to the gateway.
 *
 * Settings come as `key=value` arguments (a board calls main(0, 0) and gets the defaults):
 *   id=1 team=1 player=1 gateway=127.0.0.1:11011 boot=1 form=legacy|compact key=<hex> signing=required
 *   run_ms=0 (0 = for ever) reset_ms=4000 (silence of a restart) gc=<ip of the GameController>
 * A board image can carry its signing key from the build instead: -DROBOT_SIGNING_KEY=\"<hex>\" (and then
 * requires the gateway's frames signed). */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include "fr.h"
#include "fr_port.h"

/* ---- settings from key=value arguments -------------------------------------------------------------- */

/** The program's settings beside the library's. */
typedef struct {
    uint32_t run_ms;
    uint32_t reset_ms;
} robot_args_t;

static uint8_t signing_key[FR_SIGNING_KEY_MAX];

/** Parses a decimal number; false on anything else. */
static bool parse_u32(const char *s, uint32_t *out) {
    uint32_t v = 0;
    if (*s == '\0') return false;
    for (; *s; s++) {
        if (*s < '0' || *s > '9' || v > 429496728u) return false;
        v = v * 10u + (uint32_t)(*s - '0');
    }
    *out = v;
    return true;
}

/** Parses "a.b.c.d:port"; false on anything else. */
static bool parse_endpoint(const char *s, fr_endpoint_t *ep) {
    uint32_t part = 0;
    int dots = 0;
    bool digit = false;
    for (; *s; s++) {
        if (*s >= '0' && *s <= '9') {
            part = part * 10u + (uint32_t)(*s - '0');
            digit = true;
            if (part > 65535u) return false;
        } else if ((*s == '.' && dots < 3) || (*s == ':' && dots == 3)) {
            if (!digit || part > 255u) return false;
            ep->ip[dots++] = (uint8_t)part;
            part = 0;
            digit = false;
            if (*s == ':') return parse_u32(s + 1, &part) && part <= 65535u && (ep->port = (uint16_t)part, true);
        } else {
            return false;
        }
    }
    return false;
}

/** Parses hex digits into signing_key; its length, or 0 on anything else. */
static size_t parse_key(const char *s) {
    size_t n = 0;
    while (s[0] && s[1] && n < sizeof signing_key) {
        uint8_t byte = 0;
        for (int k = 0; k < 2; k++) {
            char c = s[k];
            uint8_t v = (uint8_t)(c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10
                                  : c >= 'A' && c <= 'F' ? c - 'A' + 10 : 255);
            if (v == 255) return 0;
            byte = (uint8_t)(byte << 4 | v);
        }
        signing_key[n++] = byte;
        s += 2;
    }
    return *s ? 0 : n;
}

/** Whether argument `arg` is `key=...`; then `*value` points after the '='. */
static bool arg_is(const char *arg, const char *key, const char **value) {
    size_t n = strlen(key);
    if (strncmp(arg, key, n) != 0 || arg[n] != '=') return false;
    *value = arg + n + 1;
    return true;
}

/* ---- the robot's body: a model good enough to answer as protocol.md 7.2 says -------------------------- */

/** Postures of protocol.md 7.2 (fallen is never reached by this model). */
typedef enum { P_SIT, P_STAND, P_CROUCH, P_WALKING, P_MOVING } posture_t;
static const char *const posture_names[] = {"sit", "stand", "crouch", "walking", "moving"};

/** State of the modelled body. */
static struct {
    posture_t posture;
    posture_t target;          /* while P_MOVING */
    uint32_t motion_end;       /* uptime when the posture motion ends */
    fr_deferred_t motion_call; /* the motion.posture call answered at its end */
    uint32_t walk_until;       /* lease end while walking */
    float vx, vy, omega;
    float pan, tilt;
    float arms[4];
    float battery;
    uint8_t penalty;
    bool reset_requested;
    uint32_t camera_frame;
    uint32_t last_debug, last_camera, last_drain;
} body;

static int opt_status_text, opt_status_table, opt_motion_plot, opt_world_field, opt_world_relative, opt_camera_image,
    opt_havimo_regions, opt_havimo_grid;

/** Writes `v` with three decimals into `out`; the number of characters (no printf: boards lack float printf). */
static size_t fmt_fixed(char *out, size_t cap, float v, int decimals) {
    char tmp[24];
    size_t n = 0, k = 0;
    int32_t scale = decimals == 3 ? 1000 : 100;
    bool neg = v < 0;
    int64_t x = (int64_t)((neg ? -v : v) * (float)scale + 0.5f);
    for (int d = 0; d < decimals; d++) { tmp[k++] = (char)('0' + x % 10); x /= 10; }
    tmp[k++] = '.';
    do { tmp[k++] = (char)('0' + x % 10); x /= 10; } while (x > 0 && k < sizeof tmp - 1);
    if (neg) tmp[k++] = '-';
    while (k > 0 && n + 1 < cap) out[n++] = tmp[--k];
    out[n] = '\0';
    return n;
}

/** Appends `s` to the zero-terminated `out` of `cap` bytes. */
static void append(char *out, size_t cap, const char *s) {
    size_t n = strlen(out);
    while (*s && n + 1 < cap) out[n++] = *s++;
    out[n] = '\0';
}

/** Appends a number with `decimals` decimals to `out`. */
static void append_num(char *out, size_t cap, float v, int decimals) {
    char num[24];
    fmt_fixed(num, sizeof num, v, decimals);
    append(out, cap, num);
}

/** v within [lo, hi]. */
static float clampf(float v, float lo, float hi) { return v < lo ? lo : v > hi ? hi : v; }

/** Ends walking: a walking robot stands. */
static void stop_walking(void) {
    if (body.posture == P_WALKING) body.posture = P_STAND;
    body.vx = body.vy = body.omega = 0;
}

/** motion.walk(vx, vy, omega): only from stand or walking; speeds clamped; a 500 ms lease (protocol.md 7.2). */
static fr_rpc_status_t m_walk(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)later; (void)ctx;
    if (!fr_rpc_expect_floats(c, 3, err, cap)) return FR_RPC_ERROR;
    if (body.posture != P_STAND && body.posture != P_WALKING) {
        err[0] = '\0';
        append(err, cap, "not standing: ");
        append(err, cap, posture_names[body.posture]);
        return FR_RPC_ERROR;
    }
    body.vx = clampf(c->params[0].u.f, -0.3f, 0.3f);
    body.vy = clampf(c->params[1].u.f, -0.3f, 0.3f);
    body.omega = clampf(c->params[2].u.f, -1.0f, 1.0f);
    if (body.vx == 0 && body.vy == 0 && body.omega == 0) {
        body.posture = P_STAND;
    } else {
        body.posture = P_WALKING;
        body.walk_until = fr_uptime_ms() + 500u;
    }
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

/** motion.stop(): true in every state. */
static fr_rpc_status_t m_stop(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)err; (void)cap; (void)later; (void)ctx;
    stop_walking();
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

/** motion.head(pan, tilt): refused outside pan -2..2, tilt -0.6..0.5. */
static fr_rpc_status_t m_head(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)later; (void)ctx;
    if (!fr_rpc_expect_floats(c, 2, err, cap)) return FR_RPC_ERROR;
    float pan = c->params[0].u.f, tilt = c->params[1].u.f;
    if (pan < -2.0f || pan > 2.0f || tilt < -0.6f || tilt > 0.5f) {
        err[0] = '\0';
        append(err, cap, "out of range: pan ");
        append_num(err, cap, pan, 3);
        append(err, cap, " (\xC2\xB1" "2.0), tilt ");
        append_num(err, cap, tilt, 3);
        append(err, cap, " (-0.6..0.5)");
        return FR_RPC_ERROR;
    }
    body.pan = pan;
    body.tilt = tilt;
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

/** motion.arms(four joints): values clamped. */
static fr_rpc_status_t m_arms(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)later; (void)ctx;
    if (!fr_rpc_expect_floats(c, 4, err, cap)) return FR_RPC_ERROR;
    for (int k = 0; k < 4; k++) body.arms[k] = clampf(c->params[k].u.f, -3.1f, 3.1f);
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

/** motion.posture(name): answered when the motion has ended, busy during one. */
static fr_rpc_status_t m_posture(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)ctx;
    static const uint32_t durations[] = {1000u, 1500u, 600u};
    if (c->count != 1 || c->params[0].kind != FR_VALUE_STRING) {
        err[0] = '\0';
        append(err, cap, "bad parameters: expected one posture name");
        return FR_RPC_ERROR;
    }
    int target = -1;
    for (int k = 0; k < 3; k++) if (strcmp(c->params[0].u.s, posture_names[k]) == 0) target = k;
    if (target < 0) {
        err[0] = '\0';
        append(err, cap, "bad parameters: unknown posture ");
        append(err, cap, c->params[0].u.s);
        return FR_RPC_ERROR;
    }
    if (body.posture == P_MOVING) {
        err[0] = '\0';
        append(err, cap, "busy: moving");
        return FR_RPC_ERROR;
    }
    if (body.posture == (posture_t)target) {
        r->kind = FR_VALUE_STRING;
        r->u.s = posture_names[target];
        return FR_RPC_OK;
    }
    stop_walking();
    body.posture = P_MOVING;
    body.target = (posture_t)target;
    body.motion_end = fr_uptime_ms() + durations[target];
    body.motion_call = later;
    body.battery -= 0.002f;
    return FR_RPC_LATER;
}

/** motion.getPosture(). */
static fr_rpc_status_t m_get_posture(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)err; (void)cap; (void)later; (void)ctx;
    r->kind = FR_VALUE_STRING;
    r->u.s = posture_names[body.posture];
    return FR_RPC_OK;
}

/** speech.say(text): accepted (the example has no speech output). */
static fr_rpc_status_t m_say(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)later; (void)ctx;
    if (c->count != 1 || c->params[0].kind != FR_VALUE_STRING) {
        err[0] = '\0';
        append(err, cap, "bad parameters: expected one text");
        return FR_RPC_ERROR;
    }
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

/** system.battery(): volts. */
static fr_rpc_status_t m_battery(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)err; (void)cap; (void)later; (void)ctx;
    r->kind = FR_VALUE_FLOAT;
    r->u.f = body.battery;
    return FR_RPC_OK;
}

/** system.ping(): uptime in milliseconds. */
static fr_rpc_status_t m_ping(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)err; (void)cap; (void)later; (void)ctx;
    r->kind = FR_VALUE_INT;
    r->u.i = fr_uptime_ms();
    return FR_RPC_OK;
}

/** system.reset(): answers, then the main loop restarts. */
static fr_rpc_status_t m_reset(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)err; (void)cap; (void)later; (void)ctx;
    body.reset_requested = true; /* the answer goes out first; the main loop restarts after it */
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

/* ---- callbacks from the library --------------------------------------------------------------------- */

/** The keep-alive's view of the body. */
static void on_health(fr_health_t *h, void *ctx) {
    (void)ctx;
    h->battery_voltage = body.battery;
    h->posture = posture_names[body.posture];
    h->has_position = true;
    h->x_mm = -1000;
    h->y_mm = 0;
    h->rotation = 0.0f;
    h->current_state = NULL;
}

/** A used GameController packet: a penalised robot, or one not playing, stops walking. */
static void on_game(const fr_game_t *g, void *ctx) {
    (void)ctx;
    body.penalty = g->penalty;
    if (g->penalty != 0 || g->game_state != 3) stop_walking(); /* a penalised robot stands still */
}

/* The program's link-loss policy: when the module reports the network lost, stop and sit down (a robot that
 * cannot be reached must not walk on). The gateway's silence is not link loss: it is silent during a game. */
static void on_link(bool up, void *ctx) {
    (void)ctx;
    if (up || body.posture == P_MOVING || body.posture == P_SIT) return;
    stop_walking();
    body.posture = P_MOVING;
    body.target = P_SIT;
    body.motion_end = fr_uptime_ms() + 1000u;
    body.motion_call = -1; /* nobody waits for this motion's answer */
}

/** A stream payload: echoed back through the stream. */
static void on_stream(const uint8_t *data, size_t len, void *ctx) {
    (void)ctx;
    (void)fr_stream_send(data, len); /* echo: the gateway's side checks what comes back */
}

/* ---- periodic work ---------------------------------------------------------------------------------- */

/** A synthetic camera frame: the ball (class 1) and the yellow goal (class 2), moving with the head. */
static void camera_frame(uint32_t frame) {
    static uint8_t records[2 * FR_HAVIMO_RECORD_SIZE];
    static uint8_t cells[FR_HAVIMO_GRID_SIZE];
    static const fr_shape_t boxes_template = {2, 0, 0, 0, 0, true, 0, false, 0, 0, 0, NULL};
    fr_shape_t boxes[2];
    uint8_t cx = (uint8_t)(80 + (int)(body.pan * 20.0f)), cy = 60;
    for (int k = 0; k < 2; k++) {
        uint8_t *r = records + k * FR_HAVIMO_RECORD_SIZE;
        uint8_t x = (uint8_t)(cx + k * 40), half = (uint8_t)(4 + k * 6);
        uint16_t pixels = (uint16_t)(half * half * 2);
        uint32_t sx = (uint32_t)x * pixels, sy = (uint32_t)cy * pixels;
        r[0] = (uint8_t)(k + 1); r[1] = (uint8_t)(k + 1);
        r[2] = (uint8_t)pixels; r[3] = (uint8_t)(pixels >> 8);
        for (int b = 0; b < 4; b++) { r[4 + b] = (uint8_t)(sx >> (8 * b)); r[8 + b] = (uint8_t)(sy >> (8 * b)); }
        r[12] = (uint8_t)(x + half); r[13] = (uint8_t)(x - half); r[14] = (uint8_t)(cy + half); r[15] = (uint8_t)(cy - half);
        boxes[k] = boxes_template;
        boxes[k].x1 = r[13]; boxes[k].y1 = r[15]; boxes[k].x2 = r[12]; boxes[k].y2 = r[14];
        boxes[k].label = k == 0 ? "colour 1" : "colour 2";
    }
    memset(cells, 0, sizeof cells);
    for (int k = 0; k < 2; k++) {
        const uint8_t *r = records + k * FR_HAVIMO_RECORD_SIZE;
        for (int y = r[15] / 5; y <= r[14] / 5 && y < 24; y++)
            for (int x = r[13] / 5; x <= r[12] / 5 && x < 32; x++) cells[x + 32 * y] = (uint8_t)(0xF0 | r[1]);
    }
    (void)fr_havimo_regions(opt_havimo_regions, frame, records, 2);
    (void)fr_havimo_grid(opt_havimo_grid, frame, cells);
    if (fr_option_enabled(opt_camera_image)) {
        static uint8_t classes[FR_HAVIMO_GRID_SIZE];
        for (size_t k = 0; k < sizeof classes; k++) classes[k] = cells[k] & 0x0F;
        (void)fr_debug_image(opt_camera_image, 32, 24, 3, classes, sizeof classes, boxes, 2);
    }
}

/** Debug data of the non-camera options, in name order (protocol.md section 8). */
static void debug_output(void) {
    char line[64], volts[16], uptime[24];
    fmt_fixed(volts, sizeof volts, body.battery, 2);
    if (fr_option_enabled(opt_motion_plot)) {
        const fr_plot_sample_t s[3] = {{"vx", body.vx}, {"vy", body.vy}, {"omega", body.omega}};
        (void)fr_debug_plot(opt_motion_plot, s, 3);
    }
    if (fr_option_enabled(opt_status_table)) {
        uint32_t up = fr_uptime_ms();
        char digits[12];
        size_t n = 0;
        do { digits[n++] = (char)('0' + up % 10u); up /= 10u; } while (up > 0);
        size_t k = 0;
        while (n > 0) uptime[k++] = digits[--n];
        uptime[k] = '\0';
        append(uptime, sizeof uptime, " ms");
        const fr_table_row_t rows[3] = {{"battery", volts}, {"posture", posture_names[body.posture]}, {"uptime", uptime}};
        (void)fr_debug_table(opt_status_table, rows, 3);
    }
    if (fr_option_enabled(opt_status_text)) {
        line[0] = '\0';
        append(line, sizeof line, "posture ");
        append(line, sizeof line, posture_names[body.posture]);
        append(line, sizeof line, ", battery ");
        append(line, sizeof line, volts);
        append(line, sizeof line, " V");
        (void)fr_debug_text(opt_status_text, line);
    }
    if (fr_option_enabled(opt_world_field)) {
        const fr_shape_t shapes[2] = {{3, -1000, 0, 0, 0, false, 150, false, 0, 0, 0, "robot"},
                                      {3, 0, 0, 0, 0, false, 50, false, 0, 0, 0, "ball"}};
        (void)fr_debug_field(opt_world_field, shapes, 2);
    }
    if (fr_option_enabled(opt_world_relative)) {
        const fr_relative_t ball = {"ball", 1000u, 0.0f};
        (void)fr_debug_relative(opt_world_relative, &ball, 1);
    }
}

/** What the body does by itself: leases, motions, battery drain, debug and camera output. */
static void robot_step(void) {
    uint32_t now = fr_uptime_ms();
    if (body.posture == P_WALKING && (int32_t)(now - body.walk_until) >= 0) stop_walking();
    if (body.posture == P_MOVING && (int32_t)(now - body.motion_end) >= 0) {
        body.posture = body.target;
        fr_value_t v = {FR_VALUE_STRING, {.s = posture_names[body.target]}};
        fr_rpc_answer(body.motion_call, &v, NULL);
    }
    if (now - body.last_drain >= 1000u) {
        body.battery -= body.posture == P_WALKING ? 0.001f : 0.0002f;
        body.last_drain = now;
    }
    if (now - body.last_debug >= 100u) {
        body.last_debug = now;
        debug_output();
    }
    if (now - body.last_camera >= 60u) {
        body.last_camera = now;
        camera_frame(++body.camera_frame);
    }
}

/** Starts the library and the body as at power-up (again after system.reset). */
static void start(fr_settings_t *s) {
    float battery = body.battery;
    memset(&body, 0, sizeof body);
    body.battery = battery > 0 ? battery : 12.4f;
    fr_init(s);
    fr_rpc_register("motion", "walk", m_walk, NULL);
    fr_rpc_register("motion", "stop", m_stop, NULL);
    fr_rpc_register("motion", "head", m_head, NULL);
    fr_rpc_register("motion", "arms", m_arms, NULL);
    fr_rpc_register("motion", "posture", m_posture, NULL);
    fr_rpc_register("motion", "getPosture", m_get_posture, NULL);
    fr_rpc_register("speech", "say", m_say, NULL);
    fr_rpc_register("system", "battery", m_battery, NULL);
    fr_rpc_register("system", "ping", m_ping, NULL);
    fr_rpc_register("system", "reset", m_reset, NULL);
    opt_status_text = fr_option_add("status.text", FR_OPT_TEXT, NULL);
    opt_status_table = fr_option_add("status.table", FR_OPT_TABLE, NULL);
    opt_motion_plot = fr_option_add("motion.plot", FR_OPT_PLOTTER, NULL);
    opt_world_field = fr_option_add("world.field", FR_OPT_DRAWING_FIELD, NULL);
    opt_world_relative = fr_option_add("world.relative", FR_OPT_DRAWING_RELATIVE, NULL);
    opt_camera_image = fr_option_add("camera.image", FR_OPT_DRAWING_CAMERA, NULL);
    opt_havimo_regions = fr_option_add("havimo.regions", FR_OPT_HAVIMO_REGIONS, NULL);
    opt_havimo_grid = fr_option_add("havimo.grid", FR_OPT_HAVIMO_GRID, NULL);
}

/** The robot's main loop; on a board, argc is 0 and every setting is its default. */
int main(int argc, char **argv) {
    static fr_settings_t s;
    robot_args_t a = {0u, 4000u};
    uint32_t v;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.team_number = 1;
    s.player_number = 1;
    s.gateway = (fr_endpoint_t){{192, 168, 1, 10}, 11011};
    s.agent = "CAgent";
    s.role = "striker";
    s.boot_id = 1;
    s.boot_counter = 1;
    s.callbacks = (fr_callbacks_t){on_health, on_game, on_link, on_stream, NULL, NULL};
#ifdef ROBOT_SIGNING_KEY
    s.signing_key = signing_key;
    s.signing_key_len = parse_key(ROBOT_SIGNING_KEY);
    s.require_signed = s.signing_key_len > 0;
#endif
    for (int k = 1; k < argc; k++) {
        const char *val;
        if (arg_is(argv[k], "id", &val) && parse_u32(val, &v)) s.robot_id = (int32_t)v;
        else if (arg_is(argv[k], "team", &val) && parse_u32(val, &v)) s.team_number = v;
        else if (arg_is(argv[k], "player", &val) && parse_u32(val, &v)) s.player_number = (uint8_t)v;
        else if (arg_is(argv[k], "gateway", &val) && parse_endpoint(val, &s.gateway)) continue;
        else if (arg_is(argv[k], "boot", &val) && parse_u32(val, &v)) s.boot_id = s.boot_counter = v;
        else if (arg_is(argv[k], "form", &val)) s.form = strcmp(val, "compact") == 0 ? FR_FORM_COMPACT : FR_FORM_LEGACY;
        else if (arg_is(argv[k], "key", &val)) { s.signing_key = signing_key; s.signing_key_len = parse_key(val); }
        else if (arg_is(argv[k], "signing", &val)) s.require_signed = strcmp(val, "required") == 0;
        else if (arg_is(argv[k], "gc", &val)) {
            fr_endpoint_t gc;
            char with_port[32];
            size_t n = strlen(val);
            if (n + 3 > sizeof with_port) return 2;
            memcpy(with_port, val, n);
            memcpy(with_port + n, ":0", 3);
            if (!parse_endpoint(with_port, &gc)) return 2;
            memcpy(s.gc_source, gc.ip, 4);
        }
        else if (arg_is(argv[k], "run_ms", &val) && parse_u32(val, &v)) a.run_ms = v;
        else if (arg_is(argv[k], "reset_ms", &val) && parse_u32(val, &v)) a.reset_ms = v;
        else return 2;
    }
    start(&s);
    uint32_t began = fr_port_millis();
    for (;;) {
        fr_poll();
        robot_step();
        if (body.reset_requested) {
            /* A board would reset itself here; the example restarts in place, which is what the wire sees:
             * the module's silence, then a new session with bootId one higher (protocol.md 7.2). */
            fr_poll();
            uint32_t silent = fr_port_millis();
            while (fr_port_millis() - silent < a.reset_ms) fr_port_idle();
            s.boot_id++;
            s.boot_counter++;
            start(&s);
        }
        if (a.run_ms != 0u && fr_port_millis() - began >= a.run_ms) return 0;
        fr_port_idle();
    }
}
