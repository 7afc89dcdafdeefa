/* firmware/include/gs1500m.h: the GainSpan GS1500M WiFi module in bulk-data mode, driven over a serial line
 * (docs/protocol.md section 12; thesis sections 4.3, 5.2, 5.3, 6.1).
 *
 * A non-blocking state machine. The board's UART receive interrupt pushes each byte into the driver's receive ring
 * (gs1500m_rx_push); its transmit side takes bytes with gs1500m_tx_pop. Everything else runs from the robot's main
 * loop: gs1500m_recv parses what has arrived and copies a datagram's data out of the ring into the caller's buffer
 * as it arrives (so the ring only covers the main loop's latency, not a whole datagram), gs1500m_send frames one
 * datagram `ESC Z <cid> <len4> <data>`, gs1500m_tick runs the start-up and its timers.
 *
 * The buffers' rule (docs/firmware.md, "Memory"): a datagram longer than GS1500M_TX_COPY_MAX is sent straight from
 * the caller's `data`, which must stay unchanged while gs1500m_tx_busy; shorter ones and the AT commands are copied
 * into the small transmit ring. While a datagram is being received (gs1500m_rx_busy), every gs1500m_recv call must
 * pass the same buffer, and nothing else may write into it; the driver copies nothing into any buffer while a
 * datagram is going out, so the one buffer can serve both directions (the library's frame buffer).
 * No call waits for the module: the start-up (the module's boot, its silence while it joins, the AT commands that
 * open the UDP client towards the base station and the UDP server on 3838) advances one step per call.
 *
 * Both rings are single-producer, single-consumer: one side in an interrupt, the other in the main loop, so no
 * lock is needed on a single-core Cortex-M3. All memory is the gs1500m_t the board gives (static), no heap. */
#ifndef GS1500M_H
#define GS1500M_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "fr_config.h"
#include "fr_port.h"

/* Timings; the driver's buffer sizes are in fr_config.h with every other buffer. The build may override each
 * with -D; docs/firmware.md lists them with the library's. */

#ifndef GS1500M_BOOT_MS
/** How long the module takes after power-up before it listens (thesis 8.1: "up to about 4 seconds"). */
#define GS1500M_BOOT_MS 4000u
#endif

#ifndef GS1500M_PROBE_MS
/** While the module joins a network it answers nothing: the driver asks `AT` again this often. */
#define GS1500M_PROBE_MS 500u
#endif

#ifndef GS1500M_REPLY_MS
/** A command the module does not answer within this time is taken as lost: the start-up begins anew. */
#define GS1500M_REPLY_MS 2000u
#endif

#ifndef GS1500M_BAUD_PROBES
/** Unanswered `AT`s at one rate before the driver tries the module's factory rate (and back): a module that was
 *  never set to the board's rate answers there, and is told the board's rate with ATB. */
#define GS1500M_BAUD_PROBES 4u
#endif

#ifndef GS1500M_PAYLOAD_MS
/** A datagram whose announced bytes do not all arrive within this time had a false or damaged header: its
 *  bytes are read again as if no header had been seen (1400 bytes take 30 ms at 460800 baud). */
#define GS1500M_PAYLOAD_MS 500u
#endif

/** The UDP port the robot receives on (docs/protocol.md section 2). */
#define GS1500M_SERVER_PORT 3838u

/** Where the driver stands in bringing the module up. */
typedef enum {
    GS1500M_BOOTING = 0, /**< waiting out the module's boot after power-up or a reset */
    GS1500M_PROBING,     /**< sending `AT` until the module answers (it is silent while it joins) */
    GS1500M_CONFIGURING, /**< sending the start-up commands one by one */
    GS1500M_READY        /**< client and server connections open: datagrams flow */
} gs1500m_state_t;

/** What the driver has counted since gs1500m_init; nothing is ever logged per byte. */
typedef struct {
    uint32_t datagrams_in;    /**< datagrams handed to the program */
    uint32_t datagrams_out;   /**< datagrams framed for the module */
    uint32_t send_busy;       /**< sends refused: not ready, no connection yet, or the transmit ring full */
    uint32_t rx_overruns;     /**< bytes lost because the receive ring was full */
    uint32_t garbage_bytes;   /**< bytes that fit no item (e.g. a datagram whose header the module overwrote) */
    uint32_t too_long;        /**< datagrams larger than the program's buffer, dropped */
    uint32_t payload_timeouts;/**< headers whose data never came in full */
    uint32_t acks;            /**< `ESC O`: the module sent a packet */
    uint32_t fails;           /**< `ESC F`: the module could not send a packet */
    uint32_t other_replies;   /**< `ESC` and another letter */
    uint32_t status_lines;    /**< text lines from the module */
    uint32_t link_losses;     /**< times the link went down after it had been up */
    uint32_t restarts;        /**< start-ups begun again (no answer, an error, a module reset) */
} gs1500m_stats_t;

/** Settings fixed at start-up. */
typedef struct {
    fr_endpoint_t base;  /**< the base station's address and port 11011, opened as the first UDP client */
    uint16_t listen_port;/**< the UDP server's port (GS1500M_SERVER_PORT) */
    uint32_t boot_ms;    /**< GS1500M_BOOT_MS on a board; tests and the emulator may give less */
    uint32_t baud;       /**< the rate the board runs the module at */
    uint32_t factory_baud;/**< the module's own rate before it is told `baud` (ATB); 0: never try it */
} gs1500m_config_t;

/** One UDP client connection: a destination and the module's connection id for it. */
typedef struct {
    fr_endpoint_t to; /**< destination */
    int8_t cid;       /**< the module's connection id, or -1 while none */
    bool used;        /**< whether this slot names a destination */
} gs1500m_peer_t;

/** The driver's whole state; the board owns one, statically. Fields are private to gs1500m.c. */
typedef struct {
    gs1500m_config_t config;
    gs1500m_stats_t stats;
    gs1500m_state_t state;
    /* receive ring: written by the UART interrupt, read by the main loop */
    uint8_t rx[GS1500M_RX_RING];
    volatile uint16_t rx_head;
    volatile uint16_t rx_tail;
    /* transmit ring: written by the main loop, read by the UART (interrupt or polling) */
    uint8_t tx[GS1500M_TX_RING];
    volatile uint16_t tx_head;
    volatile uint16_t tx_tail;
    /* a datagram sent from the caller's memory: its bytes go when the ring's tail reaches tx_data_at; the UART
     * side clears tx_data when the last one is out */
    const uint8_t *volatile tx_data;
    uint16_t tx_data_len;
    volatile uint16_t tx_data_pos;
    uint16_t tx_data_at;
    /* the parser */
    uint8_t parse;          /* parser state (gs1500m.c) */
    bool udp_server;        /* the header being read is `ESC y` */
    int8_t cid;             /* connection id of the header being read */
    uint8_t digits;         /* length digits read */
    uint16_t length;        /* announced length */
    uint16_t consumed;      /* header bytes of the current item, counted as garbage if it breaks */
    uint16_t got;           /* data bytes of the current datagram copied out (or dropped) so far */
    uint32_t payload_since; /* when the header was complete */
    fr_endpoint_t sender;   /* sender of an `ESC y` datagram */
    bool sender_known;      /* whether the address field parsed */
    char line[GS1500M_LINE_MAX + 1];
    uint8_t line_len;
    bool line_long;
    uint32_t garbage_run;   /* garbage since the last item, reported once as a lost datagram */
    /* the start-up */
    uint8_t step;           /* command being answered in GS1500M_CONFIGURING */
    bool waiting;           /* a command was sent and its OK/ERROR has not come */
    int8_t opening;         /* peer slot whose AT+NCUDP is outstanding, or -1 */
    int8_t server_cid;      /* the UDP server's connection id, or -1 */
    uint32_t uart_baud;     /* the rate the UART must run at now (gs1500m_uart_baud) */
    uint8_t probes;         /* `AT`s unanswered at uart_baud */
    bool setting_baud;      /* ATB sent at the factory rate, its OK not yet in */
    uint32_t since;         /* when the current state or command began */
    gs1500m_peer_t peers[GS1500M_PEERS];
} gs1500m_t;

/** Starts the driver at `now_ms` (power-up): it waits config->boot_ms, then brings the module up. */
void gs1500m_init(gs1500m_t *gs, const gs1500m_config_t *config, uint32_t now_ms);

/** Puts one byte from the module into the receive ring (from the UART interrupt); false when the ring was full
 *  and the byte was lost (counted). */
bool gs1500m_rx_push(gs1500m_t *gs, uint8_t byte);

/** Takes the next byte for the module from the transmit ring (for the UART); false when there is none. */
bool gs1500m_tx_pop(gs1500m_t *gs, uint8_t *byte);

/** Whether bytes wait to go to the module (the board enables its transmit interrupt while they do). */
bool gs1500m_tx_pending(const gs1500m_t *gs);

/** Whether a datagram is still being sent from the caller's memory (its `data` must stay unchanged). */
bool gs1500m_tx_busy(const gs1500m_t *gs);

/** Whether a datagram's header has arrived and its data are being copied out (into the buffer of gs1500m_recv). */
bool gs1500m_rx_busy(const gs1500m_t *gs);

/** Reads the module's answers and notices that have arrived (leaving datagrams for gs1500m_recv) and runs the
 *  start-up's timers at `now_ms`; gs1500m_recv and gs1500m_send call it too. Never blocks. */
void gs1500m_tick(gs1500m_t *gs, uint32_t now_ms);

/** Parses what has arrived and hands out at most one datagram (fr_port_recv's contract): its length, 0 when none is
 *  complete yet, < 0 when one was lost (longer than `cap`, or garbage where a datagram was). A datagram's data are
 *  copied into `buf` as they arrive, over as many calls as it takes, all with the same `buf` (gs1500m_rx_busy); none
 *  while a datagram is going out (gs1500m_tx_busy), so `buf` may be the memory being sent. */
int gs1500m_recv(gs1500m_t *gs, uint32_t now_ms, fr_endpoint_t *from, uint8_t *buf, size_t cap);

/** Frames one datagram for `to` (fr_port_send's contract): 0 when it is queued, < 0 when it cannot go now (module
 *  not ready, connection still opening, ring full, another datagram still going out, too long). Up to
 *  GS1500M_TX_COPY_MAX bytes are copied; a longer `data` is sent from where it is and must stay unchanged while
 *  gs1500m_tx_busy. A destination without a connection
 *  gets one opened (AT+NCUDP) and its datagrams go once the module has named it. */
int gs1500m_send(gs1500m_t *gs, uint32_t now_ms, const fr_endpoint_t *to, const uint8_t *data, size_t len);

/** Whether received bytes wait that the parser can use now (not only the start of a datagram still arriving):
 *  the board sleeps when not. */
bool gs1500m_rx_ready(const gs1500m_t *gs);

/** The rate the board's UART must run at now: config->baud, or config->factory_baud while the driver looks for a
 *  module still at its factory rate. The board applies a change once nothing waits to be sent
 *  (gs1500m_tx_pending). */
uint32_t gs1500m_uart_baud(const gs1500m_t *gs);

/** Whether the module is associated and both connections are open (fr_port_link_up's contract). */
bool gs1500m_link_up(const gs1500m_t *gs);

/** Where the start-up stands. */
gs1500m_state_t gs1500m_state(const gs1500m_t *gs);

/** The counters. */
const gs1500m_stats_t *gs1500m_stats(const gs1500m_t *gs);

#endif
