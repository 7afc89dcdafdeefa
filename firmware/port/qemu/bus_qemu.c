/* firmware/port/qemu/bus_qemu.c: the emulated board has no Dynamixel bus yet (docs/firmware.md "The busmodel":
 * the netduino2's USART1 on a second -serial is the way to give it one): every bus call says so, the body stays
 * off and a bridged request is answered BUS_DISABLED. */
#include "fr_port_bus.h"

int fr_port_bus_open(uint32_t baud) {
    (void)baud;
    return -1;
}

int fr_port_bus_write(const uint8_t *data, size_t len) {
    (void)data;
    (void)len;
    return -1;
}

bool fr_port_bus_writing(void) { return false; }

size_t fr_port_bus_read(uint8_t *buf, size_t cap) {
    (void)buf;
    (void)cap;
    return 0;
}
