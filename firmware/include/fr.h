/* firmware/include/fr.h: the public API of the robot-side library (docs/firmware.md, docs/protocol.md).
 * A program calls fr_init once, registers its RPC methods and debug options, and then calls fr_poll from its
 * main loop as often as it can; fr_poll never blocks. No function allocates memory. */
#ifndef FR_H
#define FR_H
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "fr_config.h"
#include "fr_port.h"

/* ---- values ------------------------------------------------------------------------------------------- */

/** Which field of a MixedValue (protocol.md 6.6) a value carries. */
typedef enum {
    FR_VALUE_NONE = 0,
    FR_VALUE_STRING,
    FR_VALUE_INT,
    FR_VALUE_FLOAT,
    FR_VALUE_BINARY,
    FR_VALUE_BOOL,
    FR_VALUE_ARRAY /* received only: the elements are not kept */
} fr_value_kind_t;

/** One RPC parameter or return value; strings and bytes point into the library's buffer for one call. */
typedef struct {
    fr_value_kind_t kind;
    union {
        const char *s;  /* FR_VALUE_STRING: zero-terminated */
        uint32_t i;     /* FR_VALUE_INT */
        float f;        /* FR_VALUE_FLOAT */
        bool b;         /* FR_VALUE_BOOL */
        struct { const uint8_t *data; size_t len; } bin; /* FR_VALUE_BINARY */
    } u;
} fr_value_t;

/* ---- RPC (protocol.md section 7) ---------------------------------------------------------------------- */

/** One received call as its handler sees it. */
typedef struct {
    const char *module;
    const char *method;
    size_t count;                           /* parameters received (may exceed FR_RPC_PARAMS_MAX) */
    fr_value_t params[FR_RPC_PARAMS_MAX];   /* the first min(count, FR_RPC_PARAMS_MAX) */
    bool has_call_id;
    uint32_t call_id;
} fr_call_t;

/** What a handler decided: answer now with `result` or the error text, or later (fr_rpc_answer). */
typedef enum { FR_RPC_OK = 0, FR_RPC_ERROR, FR_RPC_LATER } fr_rpc_status_t;

/** A call the handler answers later; valid until answered. */
typedef int fr_deferred_t;

/** Handles one call: fills `result` (FR_RPC_OK), or writes the error text (starting with a prefix of 7.4)
 *  into `error` of `error_cap` bytes (FR_RPC_ERROR), or keeps `*later` and answers it with fr_rpc_answer. */
typedef fr_rpc_status_t (*fr_rpc_handler_t)(const fr_call_t *call, fr_value_t *result, char *error,
                                            size_t error_cap, fr_deferred_t later, void *ctx);

/** Registers a handler for module.method; false when the table (FR_RPC_HANDLERS_MAX) is full. The strings
 *  must live as long as the program. */
bool fr_rpc_register(const char *module, const char *method, fr_rpc_handler_t handler, void *ctx);

/** Answers a call a handler returned FR_RPC_LATER for: `error` NULL for a result, else the error text. */
void fr_rpc_answer(fr_deferred_t call, const fr_value_t *result, const char *error);

/** Writes the bad-parameters error of protocol.md 7.4 unless `call` has exactly `count` float parameters,
 *  all finite; true when they are fine. Shared by the program's motion handlers. */
bool fr_rpc_expect_floats(const fr_call_t *call, size_t count, char *error, size_t error_cap);

/* ---- debug options and debug data (protocol.md 6.3, 6.4, section 8) ------------------------------------ */

/** DebuggingOptionType values (protocol.md 6.3). */
typedef enum {
    FR_OPT_TEXT = 1, FR_OPT_PLOTTER = 3, FR_OPT_TABLE = 4, FR_OPT_DRAWING_CAMERA = 5, FR_OPT_DRAWING_FIELD = 6,
    FR_OPT_DRAWING_RELATIVE = 7, FR_OPT_DRAWING_VGA = 8, FR_OPT_STOPWATCH = 10, FR_OPT_PLOTTER3D = 11,
    FR_OPT_HAVIMO_REGIONS = 100, FR_OPT_HAVIMO_GRID = 101
} fr_option_type_t;

/** Offers a debug option (off until enabled); its index, or -1 when FR_OPTIONS_MAX are offered. The
 *  strings must live as long as the program; `description` may be NULL (better: frame size). */
int fr_option_add(const char *name, fr_option_type_t type, const char *description);

/** Whether option `index` is enabled now. */
bool fr_option_enabled(int index);

/** One row of a DebugTable. */
typedef struct { const char *key; const char *value; } fr_table_row_t;
/** One sample of a DebugPlot. */
typedef struct { const char *series; float value; } fr_plot_sample_t;
/** One object of a DebugRelativePosition: millimetres, radians (left positive). */
typedef struct { const char *name; uint32_t distance; float angle; } fr_relative_t;
/** One Shape (protocol.md 6.4); `label` may be NULL; `has_colour` says whether r, g, b are sent. */
typedef struct {
    uint8_t kind; /* 0 POINT, 1 LINE, 2 RECTANGLE, 3 CIRCLE */
    int32_t x1, y1, x2, y2;
    bool has_second; /* x2, y2 sent */
    uint32_t radius; /* sent when > 0 */
    bool has_colour;
    uint8_t r, g, b;
    const char *label;
} fr_shape_t;

/** Sends a DebugText line for option `index` when it is enabled; false when disabled or not sent. */
bool fr_debug_text(int index, const char *text);
/** Sends a DebugTable for option `index` when it is enabled. */
bool fr_debug_table(int index, const fr_table_row_t *rows, size_t count);
/** Sends a DebugPlot for option `index` when it is enabled. */
bool fr_debug_plot(int index, const fr_plot_sample_t *samples, size_t count);
/** Sends a DebugRelativePosition for option `index` when it is enabled. */
bool fr_debug_relative(int index, const fr_relative_t *objects, size_t count);
/** Sends a DebugFieldDrawing for option `index` when it is enabled. */
bool fr_debug_field(int index, const fr_shape_t *shapes, size_t count);
/** Sends a DebugImage (`format` 0..3 of protocol.md 6.4) with its overlay for option `index`. */
bool fr_debug_image(int index, uint32_t width, uint32_t height, uint8_t format, const uint8_t *pixels,
                    size_t pixel_len, const fr_shape_t *overlay, size_t overlay_count);

/* ---- HaViMo2 camera frames (protocol.md 6.5) ---------------------------------------------------------- */

/** Sends a HaViMoRegionFrame of `count` 16-byte records (slots with index 0 are left out) when option
 *  `index` is enabled. */
bool fr_havimo_regions(int index, uint32_t frame, const uint8_t *records, size_t count);
/** Sends a HaViMoGridFrame of FR_HAVIMO_GRID_SIZE cells when option `index` is enabled. */
bool fr_havimo_grid(int index, uint32_t frame, const uint8_t *cells);

/* ---- GameController (protocol.md section 10) ---------------------------------------------------------- */

/** The game as the latest used control packet says it, for the robot's own team and player. */
typedef struct {
    uint8_t version;          /* 7, 8, 12 or 19 */
    uint8_t packet_number;    /* 0 for version 7 */
    uint8_t game_state;       /* 0 INITIAL, 1 READY, 2 SET, 3 PLAYING, 4 FINISHED */
    bool first_half;
    uint8_t kick_off_team;    /* colour (7, 8) or team number (12, 19) */
    uint8_t secondary_state;
    int32_t secs_remaining;
    int32_t secondary_time;
    uint8_t team_index;       /* 0 or 1: which team[] entry is the robot's */
    uint8_t score;            /* the robot's team */
    uint8_t opponent_score;
    uint8_t penalty;          /* the robot's own; 0 = not penalised */
    uint8_t secs_till_unpenalised;
} fr_game_t;

/** Return-packet messages (protocol.md 10.3). */
typedef enum { FR_GC_PENALISE = 0, FR_GC_UNPENALISE = 1, FR_GC_ALIVE = 2 } fr_gc_message_t;

/** Sends a return packet with `message` to the GameController last heard (the manual penalty button);
 *  false when none has been heard yet. The library sends "alive" itself. */
bool fr_gc_send(fr_gc_message_t message);

/* ---- secure stream (protocol.md section 11) ----------------------------------------------------------- */

/** Offers a payload (1 .. FR_STREAM_PAYLOAD_MAX bytes) to the stream towards the gateway; false when the
 *  window and its queue are full or the size is wrong: nothing is dropped silently. */
bool fr_stream_send(const uint8_t *data, size_t len);
/** Payloads the stream accepted and the gateway has not acknowledged yet. */
size_t fr_stream_pending(void);

/* ---- set-up ------------------------------------------------------------------------------------------- */

/** The robot as its keep-alive describes it (protocol.md 6.2); the program fills it on request. */
typedef struct {
    float battery_voltage;
    const char *posture;      /* "sit", "stand", "crouch", "walking", "moving", "fallen" */
    bool has_position;
    int32_t x_mm, y_mm;
    float rotation;
    const char *current_state; /* NULL: the posture */
} fr_health_t;

/** Callbacks into the robot's program; each may be NULL. They run inside fr_poll. */
typedef struct {
    /** Fills the keep-alive's view of the robot, every FR_KEEPALIVE_MS. */
    void (*health)(fr_health_t *out, void *ctx);
    /** A used GameController control packet for the robot's team arrived. */
    void (*game)(const fr_game_t *game, void *ctx);
    /** The module reports the network lost (`up` false) or back (`up` true). Never called because the
     *  gateway is silent: the rules forbid the base station to send during a game. */
    void (*link)(bool up, void *ctx);
    /** A stream payload arrived in order that is not an FU-Remote frame (frames are handled as frames). */
    void (*stream)(const uint8_t *data, size_t len, void *ctx);
    /** Debug option `index` was switched on or off. */
    void (*option)(int index, bool enabled, void *ctx);
    void *ctx;
} fr_callbacks_t;

/** Header form of the frames the robot starts (keep-alives, debug data); answers use the request's form. */
typedef enum { FR_FORM_LEGACY = 0, FR_FORM_COMPACT = 1 } fr_form_t;

/** Everything fr_init needs. Strings must live as long as the program. */
typedef struct {
    int32_t robot_id;
    uint32_t team_number;      /* Status.teamID and the GameController's teamNumber */
    uint8_t player_number;     /* 1-based, for the GameController */
    fr_endpoint_t gateway;     /* where keep-alives, debug data and stream segments go (port 11011) */
    const char *agent;         /* Status.activeAgent, may be NULL */
    const char *role;          /* Status.activeRole, may be NULL */
    uint32_t boot_id;          /* RobotHealth.bootId: one higher at every start (kept in flash) */
    fr_form_t form;
    /* Trust (protocol.md 6.7, docs/firmware.md "What the robot checks"). Signing is the default: without
     * `development` a robot key is required, every frame is signed and only the gateway's valid, newer signed
     * frames are acted on. */
    const uint8_t *signing_key; /* the robot key (16 to 64 bytes; `robotctl keys <id>` prints it, fr_robot_key
                                 * derives it from the team key) */
    size_t signing_key_len;
    bool development;          /* an unsigned development build, asked for by name: no key, nothing signed, and
                                * RobotHealth.development set in every keep-alive */
    bool pair_on_first_signed; /* learn the gateway's IP address and port from the first frame whose signature
                                * verifies (frames go to `gateway` until then); needs signing */
    uint8_t gc_source[4];      /* the GameController's IP address; 0.0.0.0 = take control packets from anyone */
    fr_callbacks_t callbacks;
} fr_settings_t;

/** Why fr_init refused the settings, or FR_INIT_OK. */
typedef enum {
    FR_INIT_OK = 0,
    FR_INIT_NO_KEY,               /* signing (the default) without a key */
    FR_INIT_KEY_LENGTH,           /* a key shorter than 16 or longer than 64 bytes */
    FR_INIT_KEY_IN_DEVELOPMENT,   /* a development build that was given a key: which one was meant? */
    FR_INIT_PAIRING_UNSIGNED,     /* pair on first signed frame in a development build */
    FR_INIT_EPOCH                 /* the boot epoch could not be raised (fr_port_epoch_next failed) */
} fr_init_result_t;

/** Starts (or restarts, for system.reset) the library: every option off, uptime from 0, a fresh stream, and with
 *  signing the next boot epoch (fr_port_epoch_next). On a refusal the library neither sends a frame nor acts on
 *  one (GameController packets are still read and answered); the program should report it and stop. */
fr_init_result_t fr_init(const fr_settings_t *settings);

/** One line saying what an fr_init refusal means (never the key). */
const char *fr_init_error_text(fr_init_result_t result);

/** Why a key given in hex was refused, or FR_KEY_OK. */
typedef enum { FR_KEY_OK = 0, FR_KEY_TOO_SHORT, FR_KEY_TOO_LONG, FR_KEY_ODD_LENGTH, FR_KEY_NOT_HEX } fr_key_result_t;

/** Reads a key of 16 to 64 bytes written as hexadecimal digits into `out` (FR_SIGNING_KEY_MAX bytes) and its
 *  length into `*len`; nothing is written on a refusal. */
fr_key_result_t fr_key_from_hex(const char *hex, uint8_t *out, size_t *len);

/** One line saying what a key refusal means (never the key). */
const char *fr_key_error_text(fr_key_result_t result);

/** The robot key of robot `robot_id` from the team key (protocol.md 6.7): HKDF-SHA256 with salt
 *  "naogateway robot key", info "FUSIG2" | id (4 bytes, big-endian), 32 bytes. */
void fr_robot_key(const uint8_t *team_key, size_t team_key_len, int32_t robot_id, uint8_t out[32]);

/** The boot epoch of this start (the high 32 bits of the robot's signature timestamps); 0 when unsigned. */
uint32_t fr_epoch(void);

/** The gateway the robot takes frames from now (the configured one, or the one learned by pairing), and whether
 *  it is paired (always, unless pairing on the first signed frame and none has verified yet). */
bool fr_gateway(fr_endpoint_t *out);

/** Does what is due without blocking: receives and handles at most a few datagrams, sends the keep-alive,
 *  stream retransmissions and idle ACKs, notices link changes. Call it from the main loop. */
void fr_poll(void);

/** Milliseconds since fr_init (the robot's uptime as the keep-alive and system.ping report it). */
uint32_t fr_uptime_ms(void);

/** Why datagrams were dropped or not sent, counted by kind; never reset except by fr_init. */
typedef struct {
    uint32_t received, sent;
    uint32_t send_failed;      /* fr_port_send refused */
    uint32_t recv_lost;        /* the port lost a datagram (too long, framing) */
    uint32_t unclassifiable;   /* not a frame, GameController packet or segment (protocol.md 3) */
    uint32_t bad_frame;        /* refused header (protocol.md 4.4) */
    uint32_t gzip;             /* gzip-flagged frame: refused, the library has no inflater (4.3) */
    uint32_t bad_protobuf;
    uint32_t stranger;         /* a frame or stream segment not from the paired gateway (its IP address and port) */
    uint32_t wrong_robot;      /* a frame whose Message.robotID is not this robot's id */
    uint32_t unsigned_frames, signature_not_last, malformed_signature, bad_signature, replayed;
    uint32_t not_started;      /* a frame while fr_init's refusal stands: not acted on */
    uint32_t sign_exhausted;   /* a frame not sent: the boot's 2^32 signature counters are used up */
    uint32_t gc_ignored;       /* GameController packet not used (size, version, other team, source) */
    uint32_t stream_misbehaving;
    uint32_t stream_backpressure; /* data not accepted while every send slot was taken */
    uint32_t rpc_busy;         /* a deferred call that found no free slot, answered with busy: */
} fr_stats_t;

/** The counters since fr_init. */
const fr_stats_t *fr_stats(void);

#endif
