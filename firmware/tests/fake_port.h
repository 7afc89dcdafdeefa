/* firmware/tests/fake_port.h: a port for the unit tests: datagrams in and out are queues the test fills and
 * reads, time moves only when the test says so, and the link is up unless the test takes it down. */
#ifndef FAKE_PORT_H
#define FAKE_PORT_H
#include <stddef.h>
#include <stdint.h>
#include "fr_port.h"

/** One datagram in a queue. */
typedef struct {
    fr_endpoint_t peer;
    size_t len;
    uint8_t data[1400];
} fake_datagram_t;

/** Datagrams the library sent, oldest first, and how many. */
extern fake_datagram_t fake_sent[64];
extern size_t fake_sent_count;
/** The time fr_port_millis returns. */
extern uint32_t fake_now;
/** What fr_port_link_up returns. */
extern bool fake_link;

/** What fr_port_frame_free returns negated: a board port still sending from (or receiving into) the library's
 *  buffer. */
extern bool fake_frame_busy;

/** What fr_port_board_health reports, and whether it reports anything (false: no board, as on posix). */
extern bool fake_board_present;
extern fr_board_health_t fake_board;

/** The boot epoch fr_port_epoch_next last gave (it raises it by one per call), and whether it fails. */
extern uint32_t fake_epoch;
extern bool fake_epoch_fails;
/** The last line fr_port_log was given. */
extern char fake_log[160];

/** Queues a datagram for fr_port_recv. */
void fake_receive(const fr_endpoint_t *from, const uint8_t *data, size_t len);
/** Forgets what was sent. */
void fake_clear_sent(void);
#endif
