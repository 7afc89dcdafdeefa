/* firmware/src/fr_internal.h: what the library's modules share; not part of the public API. Each section names the
 * file that defines it: fr_frame.c, fr_core.c, fr_rpc.c, fr_debug.c, fr_gc.c, fr_stream.c, fr_sign.c, fr_sha256.c and
 * fr_body.c. The other files of src/ share nothing through it: fr_dxl.c is declared in include/fr_body.h, gs1500m.c in
 * include/gs1500m.h, and fr_pb_groups.c is called only by the build's copy of nanopb's pb_decode.c. */
#ifndef FR_INTERNAL_H
#define FR_INTERNAL_H
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <pb.h>
#include <pb_decode.h>
#include <pb_encode.h>
#include "fr.h"
#include "naogateway/proto/message.pb.h"

/* shared by several files */
/** Bytes of the legacy header, the larger of the two forms (protocol.md 4.1). */
#define FR_HEADER_MAX 12
/** Bytes the signature field adds to a Message (protocol.md 6.7): key 3, length 1, timestamp 9, mac 10. */
#define FR_SIGNATURE_FIELD_SIZE 23

/** Where an outgoing frame goes and how: the answer to a request takes the request's form and transport. */
typedef struct {
    fr_endpoint_t to;
    fr_form_t form;
    bool via_stream;
} fr_route_t;

/* fr_frame.c */
/** Why a datagram starting 00 2A was refused (protocol.md 4.4), or FR_FRAME_OK. */
typedef enum {
    FR_FRAME_OK = 0,
    FR_FRAME_OVERSIZE,
    FR_FRAME_TRUNCATED,
    FR_FRAME_WRONG_OPERATION,
    FR_FRAME_UNSUPPORTED_FLAGS,
    FR_FRAME_LENGTH_MISMATCH,
    FR_FRAME_GZIP
} fr_frame_error_t;

/** Finds the payload of a frame: both header forms, gzip refused (this library has no inflater, 4.3). */
fr_frame_error_t fr_frame_parse(const uint8_t *data, size_t len, const uint8_t **payload, size_t *payload_len,
                                fr_form_t *form);

/** Writes the header of `form` for a payload of `payload_len` bytes just before `payload`; returns where the
 *  frame starts (payload - 12 or payload - 8). `payload` must have FR_HEADER_MAX bytes before it. */
uint8_t *fr_frame_header(uint8_t *payload, size_t payload_len, fr_form_t form);

/* shared by several files */
/** Keeps a function out of its callers, so its locals are on the stack only while it runs (send_keepalive's Status
 *  and RobotHealth would otherwise sit in every fr_poll frame, also on the request path). */
#if defined(__GNUC__)
#define FR_NOINLINE __attribute__((noinline))
#else
#define FR_NOINLINE
#endif

/** An HMAC-SHA-256 key made ready once: the hash states after its inner and outer padded key blocks, so each MAC
 *  saves the two compressions of those blocks. */
typedef struct {
    uint32_t inner[8], outer[8];
} fr_hmac_key_t;

/* fr_core.c */
/** The library's state shared between its modules; one instance, static. */
typedef struct {
    fr_settings_t settings;
    uint32_t boot_ms;           /* fr_port_millis() at fr_init */
    uint32_t next_keepalive;    /* uptime of the next keep-alive */
    bool link_up;
    fr_endpoint_t gateway;      /* the paired gateway: frames and segments are taken from it alone */
    bool paired;                /* false only while pairing on the first signed frame waits for one */
    bool started;               /* fr_init accepted the settings */
    bool signing;               /* not a development build: every frame signed, every gateway frame checked */
    uint32_t epoch;             /* the boot epoch: high 32 bits of the robot's signature timestamps */
    fr_hmac_key_t mac_key;      /* the robot key, prepared once at fr_init */
    uint32_t sign_counter;      /* frame counter of the robot's signature timestamps */
    bool gateway_ts_seen;       /* a signed gateway frame has been accepted in this boot epoch */
    uint64_t gateway_ts;        /* its timestamp: the replay window (RAM: a new epoch starts it empty) */
    fr_stats_t stats;
} fr_state_t;

extern fr_state_t fr_state;

/** Encodes `msg` (robotID and its extensions), frames it in the route's form, signs it when a key is set,
 *  and sends it (or offers it to the stream); false when it did not fit or could not be sent. */
bool fr_send_message(const fr_route_t *route, naogateway_proto_Message *msg);

/** The default route: the gateway's endpoint, the configured header form, a plain datagram. */
fr_route_t fr_route_gateway(void);

/** Sends a raw datagram through the port, counting a refusal. */
bool fr_send_raw(const fr_endpoint_t *to, const uint8_t *data, size_t len);

/** Handles one frame's protobuf payload from `from` (plain datagram or stream payload). */
void fr_handle_frame(const fr_endpoint_t *from, const uint8_t *data, size_t len, bool via_stream);

/* fr_rpc.c */
/** Resets the handler table and the deferred calls (fr_init). */
void fr_rpc_reset(void);
/** Gives the decoder what it needs to read a Request into the library's call buffer. */
void fr_rpc_prepare(void *request_struct);
/** Dispatches the request decoded into the call buffer and answers it on `route`. */
void fr_rpc_dispatch(const fr_route_t *route);

/* fr_debug.c */
/** Switches every option off and forgets the list (fr_init). */
void fr_debug_reset(void);
/** Gives the decoder callbacks for DebuggingCommands: with `apply` they switch options by name (the a.b.*
 *  rule), without they only read the names. */
void fr_debug_prepare(void *commands_struct, bool apply);
/** Acts on the decoded DebuggingCommands: answers a pull (or a change) with the option list on `route`. */
void fr_debug_after(const void *commands_struct, const fr_route_t *route);

/* fr_gc.c */
/** Handles a datagram starting "RG" from `from`. */
void fr_gc_receive(const fr_endpoint_t *from, const uint8_t *data, size_t len);
/** Forgets the GameController last heard (fr_init). */
void fr_gc_reset(void);
/** Parses a control packet of any supported version for `team`/`player` into `out`; false when not used. */
bool fr_gc_parse(const uint8_t *data, size_t len, uint32_t team, uint8_t player, fr_game_t *out);

/* fr_stream.c */
/** Back to the initial state of protocol.md 11.3 (fr_init). */
void fr_stream_reset(void);
/** Handles a datagram whose first two bytes are below 42 (a segment) from the gateway. */
void fr_stream_receive(const uint8_t *data, size_t len);
/** Retransmissions, idle ACKs and queued sends that are due. */
void fr_stream_poll(void);

/* fr_sign.c */
/** Appends the signature field over payload[0 .. len) with the next robot timestamp; the new length, or 0 when
 *  it does not fit in `cap` or the boot's counters are used up. */
size_t fr_sign_append(uint8_t *payload, size_t len, size_t cap);
/** What a signature check found (protocol.md 6.7). */
typedef enum { FR_SIG_OK, FR_SIG_UNSIGNED, FR_SIG_NOT_LAST, FR_SIG_MALFORMED, FR_SIG_BAD, FR_SIG_REPLAYED } fr_sig_result_t;
/** The last Message.robotID in a Message's top-level fields into `*id`: 1 when found, 0 when there is none,
 *  -1 when the bytes are no protobuf message (an end-group without its start, a truncated field). */
int fr_message_robot_id(const uint8_t *payload, size_t len, int32_t *id);
/** Checks a gateway frame's signature (direction 02, this robot's id and boot epoch) and moves the replay window
 *  on success; `*signed_len` gets the length of the bytes before the signature. */
fr_sig_result_t fr_sign_check(const uint8_t *payload, size_t len, size_t *signed_len);
/** The first 8 bytes of HMAC-SHA256(key, "FUSIG2" | direction | robot id | epoch | timestamp | bytes), the numbers
 *  big-endian (4, 4 and 8 bytes), into `mac` (protocol.md 6.7). */
void fr_sign_mac(const uint8_t *key, size_t key_len, uint8_t direction, int32_t robot_id, uint32_t epoch,
                 uint64_t timestamp, const uint8_t *bytes, size_t len, uint8_t mac[8]);
/** fr_sign_mac under a prepared key (the robot's own, fr_state.mac_key). */
void fr_sign_mac_with(const fr_hmac_key_t *key, uint8_t direction, int32_t robot_id, uint32_t epoch, uint64_t timestamp,
                      const uint8_t *bytes, size_t len, uint8_t mac[8]);

/* fr_sha256.c */
/** SHA-256 state of one running hash. */
typedef struct {
    uint32_t h[8];
    uint8_t block[64];
    size_t used;
    uint64_t total;
} fr_sha256_t;
/** Starts a hash. */
void fr_sha256_init(fr_sha256_t *s);
/** Adds `len` bytes to the hash. */
void fr_sha256_update(fr_sha256_t *s, const uint8_t *data, size_t len);
/** Ends the hash and writes the 32-byte digest. */
void fr_sha256_final(fr_sha256_t *s, uint8_t out[32]);
/** Prepares `key` (any length) for fr_hmac_with. */
void fr_hmac_key(fr_hmac_key_t *k, const uint8_t *key, size_t key_len);
/** HMAC-SHA-256 under a prepared key over the concatenation of `parts` (count of them). */
void fr_hmac_with(const fr_hmac_key_t *k, const uint8_t *const *parts, const size_t *lens, size_t count, uint8_t out[32]);
/** HMAC-SHA-256 over the concatenation of `parts` (count of them). */
void fr_hmac_sha256(const uint8_t *key, size_t key_len, const uint8_t *const *parts, const size_t *lens, size_t count,
                    uint8_t out[32]);

/** HKDF-SHA256 (RFC 5869): extract with `salt` from `ikm`, expand with `info` into `out_len` (<= 255 * 32) bytes. */
void fr_hkdf_sha256(const uint8_t *salt, size_t salt_len, const uint8_t *ikm, size_t ikm_len, const uint8_t *info,
                    size_t info_len, uint8_t *out, size_t out_len);

/* fr_body.c: the Dynamixel bus (include/fr_body.h). fr_body_init sets these; they stay NULL in a program without a
 * bus, so fr_core.c calls no body code and such a program links none of it. */
/** What the body adds to the library's loop, the keep-alive and incoming frames. */
typedef struct {
    void (*poll)(void);                  /* moves bus transactions on (fr_poll) */
    pb_extension_t *(*keepalive)(void);  /* the servoTelemetry extension for this keep-alive, or NULL */
    pb_extension_t *(*prepare)(void);    /* the busBridge extension to decode an incoming frame into */
    void (*after)(const fr_route_t *route); /* the frame was decoded: acts on its busBridge, if any */
} fr_body_hooks_t;
extern fr_body_hooks_t fr_body_hooks;

/* fr_core.c: pb helpers */
/** Encode callback for a zero-terminated string in `*arg`. */
bool fr_pb_write_string(pb_ostream_t *stream, const pb_field_t *field, void *const *arg);

#endif
