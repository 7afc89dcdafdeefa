/* firmware/include/fr_config.h: every buffer size and compile-time setting of the library, in one place.
 * Each can be overridden on the compiler's command line (-DFR_STREAM_WINDOW=4). docs/firmware.md has the
 * memory table these sizes give. */
#ifndef FR_CONFIG_H
#define FR_CONFIG_H

/** Largest datagram to or from a robot (docs/protocol.md section 1): the GS1500M's one buffer. */
#ifndef FR_DATAGRAM_MAX
#define FR_DATAGRAM_MAX 1400
#endif

/** Keep-alive period in milliseconds (protocol.md 6.2). */
#ifndef FR_KEEPALIVE_MS
#define FR_KEEPALIVE_MS 200
#endif

/** RPC handlers the program can register (the ten of protocol.md 7.2 and its own). */
#ifndef FR_RPC_HANDLERS_MAX
#define FR_RPC_HANDLERS_MAX 16
#endif

/** Parameters of one call kept for its handler; further ones are counted, so the count is always right. */
#ifndef FR_RPC_PARAMS_MAX
#define FR_RPC_PARAMS_MAX 6
#endif

/** Bytes for the string and binary parameters of one call, all together (speech.say's text is the long one). */
#ifndef FR_RPC_STRING_POOL
#define FR_RPC_STRING_POOL 256
#endif

/** Longest module or method name kept, with its terminating zero. */
#ifndef FR_RPC_NAME_MAX
#define FR_RPC_NAME_MAX 32
#endif

/** Calls a handler may answer later (motion.posture answers when its motion has ended). */
#ifndef FR_RPC_DEFERRED_MAX
#define FR_RPC_DEFERRED_MAX 2
#endif

/** Longest error text of a Response, with its terminating zero. */
#ifndef FR_RPC_ERROR_MAX
#define FR_RPC_ERROR_MAX 96
#endif

/** Debug options the program can offer (protocol.md section 8). */
#ifndef FR_OPTIONS_MAX
#define FR_OPTIONS_MAX 16
#endif

/** Longest debug option name accepted in an optionEnable/optionDisable, with its terminating zero. */
#ifndef FR_OPTION_NAME_MAX
#define FR_OPTION_NAME_MAX 32
#endif

/** HaViMo2 region records in one frame (the camera has 15 slots, protocol.md 6.5). */
#define FR_HAVIMO_REGIONS_MAX 15
/** Bytes of one HaViMo2 region record. */
#define FR_HAVIMO_RECORD_SIZE 16
/** Bytes of one HaViMo2 grid (32 x 24 cells). */
#define FR_HAVIMO_GRID_SIZE 768

/** Secure stream (protocol.md section 11): sequence numbers run 0 .. FR_STREAM_MAX_SEQ. */
#ifndef FR_STREAM_MAX_SEQ
#define FR_STREAM_MAX_SEQ 20
#endif

/** Secure stream window: 1 = the thesis's stop-and-wait, more = selective repeat. 2W <= maxSeq + 1. The
 *  largest RAM cost of the library: W send slots and W reorder slots of FR_STREAM_PAYLOAD_MAX bytes each. */
#ifndef FR_STREAM_WINDOW
#define FR_STREAM_WINDOW 1
#endif

/** Send slots of the secure stream: the window, plus payloads that may wait for it; fr_stream_send refuses one
 *  more. Each slot is FR_STREAM_PAYLOAD_MAX bytes, so the default keeps none waiting. */
#ifndef FR_STREAM_QUEUE
#define FR_STREAM_QUEUE FR_STREAM_WINDOW
#endif

/** Reorder slots of the secure stream (W > 1): segments received ahead of the next expected one that are kept
 *  until the gap is filled (1 .. W - 1). One keeps the nearest segment after a single loss, the common case; a
 *  segment that finds no slot is acknowledged cumulatively and comes again. Each slot is FR_STREAM_PAYLOAD_MAX
 *  bytes. */
#ifndef FR_STREAM_REORDER
#define FR_STREAM_REORDER 1
#endif

/** Largest payload of one secure-stream segment the robot keeps (protocol.md allows 1398). */
#ifndef FR_STREAM_PAYLOAD_MAX
#define FR_STREAM_PAYLOAD_MAX 1398
#endif

/** Retransmission timeout bounds and start value in milliseconds (protocol.md 11.2, 11.6). */
#ifndef FR_STREAM_RTO_INITIAL_MS
#define FR_STREAM_RTO_INITIAL_MS 200
#endif
#ifndef FR_STREAM_RTO_MIN_MS
#define FR_STREAM_RTO_MIN_MS 20
#endif
#ifndef FR_STREAM_RTO_MAX_MS
#define FR_STREAM_RTO_MAX_MS 2000
#endif
/** One pure ACK after this long without sending, once data has arrived (protocol.md 11.4). */
#ifndef FR_STREAM_IDLE_ACK_MS
#define FR_STREAM_IDLE_ACK_MS 200
#endif

/** Longest signing key in bytes (protocol.md 6.7 allows 16 to 64). */
#define FR_SIGNING_KEY_MAX 64

/** Depth of nested unknown groups the decoder skips before it refuses the frame (stack bound). */
#ifndef FR_PB_GROUP_DEPTH
#define FR_PB_GROUP_DEPTH 8
#endif

#if FR_STREAM_WINDOW < 1 || 2 * FR_STREAM_WINDOW > FR_STREAM_MAX_SEQ + 1
#error "FR_STREAM_WINDOW must be 1 .. (FR_STREAM_MAX_SEQ + 1) / 2"
#endif
/* The GS1500M driver (gs1500m.c) on the boards that talk to the module over a serial line. */

/** Largest datagram the module sends or receives: its one 1400-byte buffer (thesis 5.3, 6.1). */
#define GS1500M_MAX_DATAGRAM 1400

#ifndef GS1500M_RX_RING
/** Receive ring: the bytes that arrive while the main loop works, about 11 ms of 460800 baud; a datagram's data
 *  leave it for the program's buffer as they come (gs1500m.h), so it need not hold a whole datagram. */
#define GS1500M_RX_RING 512
#endif

#ifndef GS1500M_TX_RING
/** Transmit ring: AT commands, datagram headers and short datagrams (GS1500M_TX_COPY_MAX); a longer datagram is
 *  sent from the program's buffer. Must hold the longest command (about 40 bytes) with a header. */
#define GS1500M_TX_RING 96
#endif

#ifndef GS1500M_TX_COPY_MAX
/** Datagrams up to this length are copied into the transmit ring (acks, GameController returns); longer ones are
 *  sent from the caller's buffer. */
#define GS1500M_TX_COPY_MAX 40
#endif

#ifndef GS1500M_LINE_MAX
/** Longest status line kept; a longer one is read to its end and taken for garbage. */
#define GS1500M_LINE_MAX 48
#endif

#ifndef GS1500M_PEERS
/** UDP client connections the driver keeps open at once (the module has 16): the base station, the
 *  GameController's return address and two more destinations. */
#define GS1500M_PEERS 4
#endif

#if FR_STREAM_QUEUE < FR_STREAM_WINDOW || FR_STREAM_QUEUE > FR_STREAM_MAX_SEQ + 1 - FR_STREAM_WINDOW
#error "FR_STREAM_QUEUE must be FR_STREAM_WINDOW .. FR_STREAM_MAX_SEQ + 1 - FR_STREAM_WINDOW"
#endif
#if FR_STREAM_REORDER < 1 || (FR_STREAM_WINDOW > 1 && FR_STREAM_REORDER > FR_STREAM_WINDOW - 1)
#error "FR_STREAM_REORDER must be 1 .. FR_STREAM_WINDOW - 1"
#endif
#if FR_STREAM_MAX_SEQ < 1 || FR_STREAM_MAX_SEQ > 41
#error "FR_STREAM_MAX_SEQ must be 1 .. 41"
#endif

#endif
