/* firmware/include/fr_port_bus.h: what a board with a Dynamixel bus gives the body (src/fr_dxl.c, src/fr_body.c),
 * beside fr_port.h. One half-duplex line: the port turns the line to transmit when it starts sending and back to
 * receive as soon as the last stop bit has left (the CM-530 does this in its USART's transmit-complete interrupt,
 * with its two direction pins), because a servo may answer within microseconds. No call waits. */
#ifndef FR_PORT_BUS_H
#define FR_PORT_BUS_H
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/** Opens the bus at `baud` (1000000 on a Bioloid); 0 when the board has a bus, < 0 when it has none. */
int fr_port_bus_open(uint32_t baud);

/** Starts sending `len` bytes (line to transmit, back to receive after the last one) without waiting; 0 when taken,
 *  < 0 when the port is still sending or has no bus. Bytes received while sending are the port's to drop. */
int fr_port_bus_write(const uint8_t *data, size_t len);

/** Whether bytes of the last write are still leaving (the line is not yet back to receive). */
bool fr_port_bus_writing(void);

/** Takes up to `cap` received bytes without waiting; how many (0 when none wait). */
size_t fr_port_bus_read(uint8_t *buf, size_t cap);

#endif
