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

/** Encodes `msg` (robotID and its extensions) with nanopb, frames it in the route's form, signs it when a key is set,
 *  and sends it (or offers it to the stream); false when it did not fit or could not be sent. For the body's
 *  messages: the library writes its own with fr_out_* (a program without the body links no nanopb encoder). */
bool fr_send_message(const fr_route_t *route, naogateway_proto_Message *msg);

/** The default route: the gateway's endpoint, the configured header form, a plain datagram. */
fr_route_t fr_route_gateway(void);

/** Sends a raw datagram through the port, counting a refusal. */
bool fr_send_raw(const fr_endpoint_t *to, const uint8_t *data, size_t len);

/** Handles one frame's protobuf payload from `from` (plain datagram or stream payload). */
void fr_handle_frame(const fr_endpoint_t *from, const uint8_t *data, size_t len, bool via_stream);

/* fr_in.c: reading incoming messages field by field (the same acceptance as nanopb's pb_decode) */
/** Handles field `tag` of wire type `wire` of a message being read: 1 read, 0 not a field it knows (skipped by the
 *  caller), -1 malformed. */
typedef int (*fr_in_field_t)(pb_istream_t *s, uint32_t tag, pb_wire_type_t wire, void *ctx);
/** Reads a string, bytes or repeated field's value from `s` (a substream holding just that value). */
typedef bool (*fr_in_reader_t)(pb_istream_t *s, void *arg);
/** Reads the message in `s` to its end, field by field through `field`; false when malformed. */
bool fr_in_message(pb_istream_t *s, fr_in_field_t field, void *ctx);
/** A callback field's value as nanopb passes it: a length-delimited one's payload, a scalar's raw bytes; `reader`
 *  NULL reads it over. */
bool fr_in_callback(pb_istream_t *s, pb_wire_type_t wire, fr_in_reader_t reader, void *arg);
/** A uint32 field (varint; refused when larger than 32 bits). */
bool fr_in_uint32(pb_istream_t *s, pb_wire_type_t wire, uint32_t *out);
/** A submessage field: its fields through `field`. */
bool fr_in_submessage(pb_istream_t *s, pb_wire_type_t wire, fr_in_field_t field, void *ctx);

/* fr_rpc.c */
/** Resets the handler table and the deferred calls (fr_init). */
void fr_rpc_reset(void);
/** Empties the call buffer before a frame is read. */
void fr_rpc_prepare(void);
/** Reads one rpcRequest (its value of wire type `wire`) into the call buffer; false when malformed. */
bool fr_rpc_read(pb_istream_t *s, pb_wire_type_t wire);
/** Dispatches the request decoded into the call buffer and answers it on `route`. */
void fr_rpc_dispatch(const fr_route_t *route);

/* fr_debug.c */
/** Switches every option off and forgets the list (fr_init). */
void fr_debug_reset(void);
/** Prepares reading a frame's DebuggingCommands: with `apply` their names switch options (the a.b.* rule),
 *  without they are only read. */
void fr_debug_prepare(bool apply);
/** Reads one debuggingCommands (its value of wire type `wire`); false when malformed. */
bool fr_debug_read(pb_istream_t *s, pb_wire_type_t wire);
/** Acts on the DebuggingCommands read: answers a pull (or a change) with the option list on `route`. */
void fr_debug_after(const fr_route_t *route);

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
    bool (*keepalive)(pb_ostream_t *out); /* writes the servoTelemetry extension when this keep-alive has it */
    void (*prepare)(void);               /* before an incoming frame is read */
    fr_in_field_t field;                 /* reads the body's extension of an incoming frame (the fr_in_field_t rule) */
    void (*after)(const fr_route_t *route); /* the frame was decoded: acts on its busBridge, if any */
} fr_body_hooks_t;
extern fr_body_hooks_t fr_body_hooks;

/* fr_out.c: the writer of outgoing frames (protobuf fields by hand, the bytes nanopb would write) */
/** A cursor over an outgoing payload; `p` NULL once something did not fit (the frame is then not sent). */
typedef struct {
    uint8_t *p, *end;
} fr_out_t;
/** One raw byte. */
void fr_out_byte(fr_out_t *w, uint8_t b);
/** A varint; an int32's negative value goes in as its 64-bit sign extension (10 bytes), as protobuf writes it. */
void fr_out_varint(fr_out_t *w, uint64_t v);
/** Field `field` as a uint32, bool or enum of non-negative value (varint). */
void fr_out_uint(fr_out_t *w, uint32_t field, uint32_t v);
/** Field `field` as an int32 or enum (varint, negative values sign-extended). */
void fr_out_int(fr_out_t *w, uint32_t field, int32_t v);
/** Field `field` as a sint32 (zigzag varint). */
void fr_out_sint(fr_out_t *w, uint32_t field, int32_t v);
/** Field `field` as a float (fixed32, little-endian). */
void fr_out_float(fr_out_t *w, uint32_t field, float f);
/** Field `field` as bytes. */
void fr_out_bytes(fr_out_t *w, uint32_t field, const uint8_t *data, size_t n);
/** `n` bytes as they are (the body of a bytes field whose length was written). */
void fr_out_raw(fr_out_t *w, const uint8_t *data, size_t n);
/** Field `field` as a string; nothing when `s` is NULL. */
void fr_out_string(fr_out_t *w, uint32_t field, const char *s);
/** Opens submessage `field`: its key and two bytes for its length; returns where they are. */
uint8_t *fr_out_open(fr_out_t *w, uint32_t field);
/** Closes the submessage opened at `at`: its length (< 16384 bytes) as a minimal varint. */
void fr_out_close(fr_out_t *w, uint8_t *at);
/** Starts a frame on `route` in the frame buffer: false when nothing may be sent now (counted); else `w` is over
 *  the payload (the signature's room apart) with Message.robotID written. */
bool fr_out_begin(fr_out_t *w, const fr_route_t *route);
/** Signs, frames and sends what `w` holds (a payload that did not fit is counted as send_failed). */
bool fr_out_send(fr_out_t *w, const fr_route_t *route);


#endif
