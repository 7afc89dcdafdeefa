/* firmware/examples/hello_robot.c: the smallest robot program a team copies to start its own (docs/firmware.md,
 * "Your first robot program"). It goes online at the gateway, keeps itself online with keep-alives and answers one
 * command, motion.head(pan, tilt), as protocol.md 7.2 describes it. It uses only the public API (fr.h) and the port
 * (fr_port.h), so it runs on the posix port as it is (`make -C firmware example`: build/posix-w1/hello_robot) and
 * on a board once its start-up calls main. The full robot the tests and the board images use is
 * firmware/testrobot/robot.c.
 *
 * Arguments, all `key=value` and all optional except the trust setting:
 *   id=1 gateway=192.168.1.10:11011 run_ms=0 (0 = for ever)
 *   key=<robot key, hex: `robotctl keys <id>` prints it> | development (an unsigned development build) */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include "fr.h"
#include "fr_port.h"

/** What this robot knows about itself: where its head points. A real program reads and moves its servos here. */
static struct {
    float pan, tilt;
} head;

/** motion.head(pan, tilt): turns the head; refused outside pan -2..2 and tilt -0.6..0.5 radians. */
static fr_rpc_status_t on_head(const fr_call_t *call, fr_value_t *result, char *error, size_t error_cap,
                               fr_deferred_t later, void *ctx) {
    (void)later; /* a handler that needs time keeps `later` and answers with fr_rpc_answer when done */
    (void)ctx;
    if (!fr_rpc_expect_floats(call, 2, error, error_cap)) return FR_RPC_ERROR; /* the library wrote the error */
    float pan = call->params[0].u.f, tilt = call->params[1].u.f;
    if (pan < -2.0f || pan > 2.0f || tilt < -0.6f || tilt > 0.5f) {
        strncpy(error, "out of range: pan -2..2, tilt -0.6..0.5", error_cap - 1);
        error[error_cap - 1] = '\0';
        return FR_RPC_ERROR; /* the caller's RobotInterface sees this text as the call's error */
    }
    head.pan = pan;
    head.tilt = tilt;
    result->kind = FR_VALUE_BOOL;
    result->u.b = true;
    return FR_RPC_OK;
}

/** Fills each keep-alive (protocol.md 6.2): the gateway shows these values and takes the robot as online. */
static void on_health(fr_health_t *health, void *ctx) {
    (void)ctx;
    health->battery_voltage = 12.4f; /* a real robot reads its battery here */
    health->posture = "stand";
    health->has_position = false;
    health->current_state = NULL;
}

/** Parses a decimal number below 2^32; false on anything else. */
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

/** Parses "a.b.c.d:port" into `ep`; false on anything else. */
static bool parse_endpoint(const char *s, fr_endpoint_t *ep) {
    uint32_t part = 0;
    int field = 0;
    bool digit = false;
    for (;; s++) {
        if (*s >= '0' && *s <= '9' && part < 65536u) {
            part = part * 10u + (uint32_t)(*s - '0');
            digit = true;
        } else if (digit && field < 4 && part <= 255u && *s == (field < 3 ? '.' : ':')) {
            ep->ip[field++] = (uint8_t)part;
            part = 0;
            digit = false;
        } else {
            if (*s != '\0' || field != 4 || !digit || part > 65535u) return false;
            ep->port = (uint16_t)part;
            return true;
        }
    }
}

/** Whether `arg` is `name=...`; then `*value` points after the '='. */
static bool arg_is(const char *arg, const char *name, const char **value) {
    size_t n = strlen(name);
    if (strncmp(arg, name, n) != 0 || arg[n] != '=') return false;
    *value = arg + n + 1;
    return true;
}

/** Reads the arguments, starts the library, registers the command and polls for ever (or for run_ms). Exits 2 on
 *  an argument it does not know or settings the library refuses; the message never shows the key. */
int main(int argc, char **argv) {
    static fr_settings_t s;
    static uint8_t key[FR_SIGNING_KEY_MAX];
    uint32_t v, run_ms = 0;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.team_number = 1;
    s.player_number = 1;
    s.gateway = (fr_endpoint_t){{192, 168, 1, 10}, 11011};
    s.boot_id = 1; /* a board keeps this in flash and counts it up at every start */
    s.callbacks.health = on_health;
    for (int k = 1; k < argc; k++) {
        const char *val;
        if (arg_is(argv[k], "id", &val) && parse_u32(val, &v)) s.robot_id = (int32_t)v;
        else if (arg_is(argv[k], "gateway", &val) && parse_endpoint(val, &s.gateway)) continue;
        else if (arg_is(argv[k], "run_ms", &val) && parse_u32(val, &v)) run_ms = v;
        else if (strcmp(argv[k], "development") == 0) s.development = true;
        else if (arg_is(argv[k], "key", &val)) {
            fr_key_result_t r = fr_key_from_hex(val, key, &s.signing_key_len);
            if (r != FR_KEY_OK) {
                fr_port_log(fr_key_error_text(r));
                return 2;
            }
            s.signing_key = key;
        } else if (!fr_port_option(argv[k])) { /* the port's own, e.g. posix's epoch=<path> */
            fr_port_log("hello_robot: unknown or malformed argument");
            return 2;
        }
    }
    fr_init_result_t r = fr_init(&s);
    if (r != FR_INIT_OK) {
        fr_port_log(fr_init_error_text(r));
        return 2;
    }
    fr_rpc_register("motion", "head", on_head, NULL); /* after fr_init, which empties the table */
    fr_port_log("hello_robot: started");
    uint32_t began = fr_port_millis();
    for (;;) {
        fr_poll(); /* keep-alives, requests, answers: never blocks */
        if (run_ms != 0u && fr_port_millis() - began >= run_ms) return 0;
        fr_port_idle();
    }
}
