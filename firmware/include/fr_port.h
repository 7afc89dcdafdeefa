/* firmware/include/fr_port.h: what a board (port) gives the library. Agreed contract between the library
 * (src/) and the ports (port/posix, port/qemu, port/cm530). Extend with care; do not change signatures. */
#ifndef FR_PORT_H
#define FR_PORT_H
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/** An IPv4 address and UDP port, as the robot's network module reports them. */
typedef struct {
    uint8_t ip[4];
    uint16_t port;
} fr_endpoint_t;

/** Milliseconds since boot; wraps at 2^32 (callers compare with unsigned subtraction). */
uint32_t fr_port_millis(void);

/** Hands one UDP datagram for `to` to the network without blocking; 0 when accepted, < 0 when it cannot
 *  be sent now (module busy, buffer full, link down): the library counts the drop and goes on. The port may send
 *  straight from `data`: the library leaves it unchanged until fr_port_frame_free says true. */
int fr_port_send(const fr_endpoint_t *to, const uint8_t *data, size_t len);

/** What a board reports about itself in the keep-alive (RobotHealth.board, protocol.md 6.2). */
typedef struct {
    uint32_t core_clock_hz;    /**< the core clock it runs on */
    bool stack_overflow_reset; /**< the previous run ended in a reset because its stack overflowed */
    bool fault_reset;          /**< the previous run ended in a reset after a fault */
} fr_board_health_t;

/** Fills what the board reports about itself; false where there is no board of its own (posix, the emulator). */
bool fr_port_board_health(fr_board_health_t *out);

/** Whether the library may write into the memory of its datagrams now (docs/firmware.md, "Memory"): false while the
 *  port still sends a datagram from the memory fr_port_send was given, or is copying a datagram that is arriving
 *  into the buffer fr_port_recv was given. A port that copies both ways (posix) always says true. */
bool fr_port_frame_free(void);

/** Takes at most one received datagram without blocking: its length, 0 when none is waiting, < 0 when
 *  one was lost (too long for `cap`, framing error); `from` gets the sender. The port may copy a datagram into `buf`
 *  over several calls (fr_port_frame_free is false meanwhile): the library always passes the same buffer. */
int fr_port_recv(fr_endpoint_t *from, uint8_t *buf, size_t cap);

/** Whether the module reports the network as associated; the library tells the program on a change. */
bool fr_port_link_up(void);

/** Nothing to do until the next interrupt or datagram: `wfi` on a board, a short bounded sleep on posix. */
void fr_port_idle(void);

/** Raises the persisted boot epoch by one and gives the new value, once per start of a signing robot (fr_init):
 *  0 when done, < 0 when the store cannot be read or written (then the robot does not start). It must never
 *  give a value it gave before: flash on the CM-530, a file on posix, a host file on qemu (docs/firmware.md). */
int fr_port_epoch_next(uint32_t *epoch);

/** One line of text for whoever watches the robot (stderr on posix, semihosting on qemu, nothing on a CM-530). */
void fr_port_log(const char *text);

/** A `key=value` argument meant for the port (posix: `epoch=<path>`); false when the port does not know it. */
bool fr_port_option(const char *arg);

#endif
