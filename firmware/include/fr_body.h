/* firmware/include/fr_body.h: the robot's body on its Dynamixel bus (docs/firmware.md "The body"): a protocol 1.0
 * master (fr_dxl_*), servo telemetry in the keep-alive (protocol.md 6.8), the HaViMo2 camera read over the bus
 * (6.5) and the bus bridge through the secure stream (6.9). Every buffer of the body is sized here; each size can
 * be overridden on the compiler's command line like those of fr_config.h. Nothing here runs without a bus: a
 * program that never calls fr_body_init links none of it. */
#ifndef FR_BODY_H
#define FR_BODY_H
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "fr.h"

/* ---- sizes -------------------------------------------------------------------------------------------- */

/** Servos in the telemetry at most (protocol.md 6.8). */
#ifndef FR_BODY_SERVOS_MAX
#define FR_BODY_SERVOS_MAX 32
#endif
/** Longest instruction packet: a bridged request (protocol.md 6.9: 6 to 143 bytes). */
#define FR_DXL_TX_MAX 143
/** Longest status packet protocol 1.0 can carry: FF FF id length(255) ... = 259 bytes; the master keeps that much
 *  of what the bus returns (bytes before the packet included), so a damaged reply goes back whole to a bridge. */
#ifndef FR_DXL_RX_MAX
#define FR_DXL_RX_MAX 260
#endif
/** Bridged requests waiting for the bus; the gateway keeps one in flight (6.9), so two leave room for a repeat. */
#ifndef FR_BODY_BRIDGE_QUEUE
#define FR_BODY_BRIDGE_QUEUE 2
#endif
/** Bytes a read of the camera's region table may return at once (15 records of 16 bytes). */
#define FR_HAVIMO_TABLE_SIZE (FR_HAVIMO_REGIONS_MAX * FR_HAVIMO_RECORD_SIZE)

/* ---- the protocol 1.0 master -------------------------------------------------------------------------- */

/** Dynamixel instructions the body uses (protocol 1.0) and the HaViMo2's own (docs/firmware.md). */
enum {
    FR_DXL_PING = 0x01, FR_DXL_READ = 0x02, FR_DXL_WRITE = 0x03, FR_DXL_REG_WRITE = 0x04, FR_DXL_ACTION = 0x05,
    FR_DXL_SYNC_WRITE = 0x83, FR_DXL_BROADCAST = 0xFE,
    FR_HAVIMO_CAP_REGION = 0x0E, FR_HAVIMO_CAP_GRID = 0x15, FR_HAVIMO_READ_GRID = 0x16
};

/** How one transaction ended. */
typedef enum {
    FR_DXL_IDLE = 0,     /* nothing started */
    FR_DXL_BUSY,         /* sending or waiting for the status packet */
    FR_DXL_OK,           /* a valid status packet from the addressed id, or no status was due */
    FR_DXL_TIMEOUT,      /* nothing (or no packet start) within the timeout */
    FR_DXL_SHORT,        /* a packet began but did not come whole within the timeout */
    FR_DXL_CHECKSUM,     /* a whole packet with a wrong checksum */
    FR_DXL_MALFORMED     /* a whole packet from another id, or with a length the request does not allow */
} fr_dxl_result_t;

/** Writes an instruction packet (FF FF id length instruction params checksum) into `out` (FR_DXL_TX_MAX bytes);
 *  its length, 0 when the parameters do not fit. */
size_t fr_dxl_packet(uint8_t *out, uint8_t id, uint8_t instruction, const uint8_t *params, size_t count);

/** Whether `p` of `len` bytes is exactly one well-formed instruction packet (header, length, checksum). */
bool fr_dxl_well_formed(const uint8_t *p, size_t len);

/** Bytes of the status packet a well-formed request makes due (protocol.md 6.9): 0 for the broadcast id and sync
 *  write, 6 + n for a read of n bytes, else 6. */
size_t fr_dxl_reply_due(const uint8_t *p, size_t len);

/** Starts one transaction: sends `len` bytes, then waits up to `timeout_ms` for the `due` bytes of its status
 *  packet (0: none due, done once sent); false while another runs. The packet is copied. */
bool fr_dxl_start(const uint8_t *packet, size_t len, size_t due, uint32_t timeout_ms);

/** Forgets the transaction in progress, if any (fr_body_init). */
void fr_dxl_reset(void);

/** Moves the transaction on without waiting; FR_DXL_BUSY until it ends, then its result once, then FR_DXL_IDLE. */
fr_dxl_result_t fr_dxl_poll(void);

/** The bytes the bus returned for the last transaction: the status packet alone when it was valid, else everything
 *  received (up to FR_DXL_RX_MAX), so a bridge can hand back what the bus did. */
const uint8_t *fr_dxl_reply(size_t *len);

/* ---- the body ------------------------------------------------------------------------------------------ */

/** What fr_body_init needs; fr_body_defaults fills the defaults of docs/firmware.md. */
typedef struct {
    uint32_t baud;                 /* 1000000 */
    uint8_t servo_ids[FR_BODY_SERVOS_MAX];
    size_t servo_count;            /* 0: no telemetry */
    uint32_t telemetry_ms;         /* telemetry period (6.8), 1000; 0 = off */
    uint32_t servo_timeout_ms;     /* a servo's status packet, 4 */
    bool havimo;                   /* a HaViMo2 on the bus */
    uint8_t havimo_id;             /* 100 */
    uint8_t havimo_capture;        /* the capture: 0x0E CAP_REGION (datasheet), or 0x03: a write of 0 to address 0 */
    uint32_t havimo_period_ms;     /* a capture at most this often, 100 */
    uint32_t havimo_wait_ms;       /* give up a capture that has not finished after this long, 200 */
    uint32_t havimo_ping_ms;       /* ping the busy camera this often, 5 */
    uint32_t havimo_timeout_ms;    /* one camera read, 10 */
    bool havimo_table_read;        /* regions in one read of 240 bytes from address 16 (else 15 reads of 16) */
    bool havimo_grid;              /* also capture and read the grid when the grid option is on */
    uint8_t havimo_grid_chunk;     /* grid bytes per READ_GRID, a multiple of 16 (16) */
    int havimo_regions_option;     /* debug option indices the frames go to (-1: none) */
    int havimo_grid_option;
    bool bridge;                   /* serve busBridge requests (6.9) */
    uint32_t bridge_timeout_ms;    /* the reply timeout, 20 */
    uint32_t bridge_quiet_ms;      /* the robot's own camera reads pause this long after a bridged request, 2000 */
} fr_body_settings_t;

/** Fills `s` with the defaults: 1 Mbps, no servos, telemetry 1000 ms, no camera, the bridge on. */
void fr_body_defaults(fr_body_settings_t *s);

/** Starts the body after fr_init (again after every fr_init); false when the board has no bus (then the body stays
 *  off and a bridged request is answered BUS_DISABLED). */
bool fr_body_init(const fr_body_settings_t *s);

/** One servo as its last read found it (raw control-table units, protocol.md 6.8). */
typedef struct {
    uint8_t id;
    bool read;          /* a read has been attempted */
    bool silent;        /* the last read got no valid answer */
    uint8_t error;      /* the status packet's error byte */
    uint16_t position, speed, load;
    uint8_t voltage, temperature;
} fr_servo_t;

/** The configured servos' latest readings, in the configured order; `count` gets how many. */
const fr_servo_t *fr_body_servos(size_t *count);

/** The latest camera frame: its counter, its region records (index 0 slots left out) and their count, and the grid
 *  (FR_HAVIMO_GRID_SIZE cells; NULL until one was read and while the next one is being read); false before the first
 *  frame. */
bool fr_body_camera(uint32_t *frame, const uint8_t **records, size_t *count, const uint8_t **cells);

/** Why bus transactions failed or bridge frames were refused, by kind; since fr_body_init. */
typedef struct {
    uint32_t transactions;
    uint32_t bus_errors;        /* every failure below (ServoTelemetry.busErrors) */
    uint32_t timeouts, short_packets, checksums, malformed;
    uint32_t havimo_frames, havimo_lost; /* camera frames read whole / given up */
    uint32_t bridge_requests, bridge_plain, bridge_overflow, bridge_gate_closed, bridge_malformed;
} fr_body_stats_t;

/** The body's counters. */
const fr_body_stats_t *fr_body_stats(void);

#endif
