/* firmware/port/qemu/bus_qemu.c: the emulated board's Dynamixel bus (fr_port_bus.h) on the netduino2's USART1 (its
 * first -serial, e.g. -serial tcp:127.0.0.1:7000 to the standalone busmodel). qemu's USART takes every byte at once
 * and has no direction pins, so a write is done when it returns; received bytes come by the receive interrupt into a
 * ring. Whether a bus is there is found at open by one ping of servo 1, waited for at most BUS_PROBE_MS: with
 * `-serial null` (the tests of the network side) nothing answers and the body stays off. */
#include "fr_port.h"
#include "fr_port_bus.h"
#include "stm32.h"

#define USART1_BASE 0x40011000u /* the STM32F2's USART1 */
#define USART1_SR REG32(USART1_BASE + 0x00u)
#define USART1_DR REG32(USART1_BASE + 0x04u)
#define USART1_CR1 REG32(USART1_BASE + 0x0Cu)
#define USART1_IRQ 37u
/** The start-up probe's wait for servo 1's answer. */
#define BUS_PROBE_MS 50u
#define BUS_RX_RING 512u

static volatile uint8_t rx_ring[BUS_RX_RING];
static volatile uint32_t rx_head, rx_tail;
static bool opened;

/** Sends bytes by polling: the emulated USART empties its data register at once. */
static void put(const uint8_t *data, size_t len) {
    for (size_t k = 0; k < len; k++) {
        for (uint32_t spin = 0; spin < 100000u && !(USART1_SR & USART_SR_TXE); spin++) {
        }
        USART1_DR = data[k];
    }
}

int fr_port_bus_open(uint32_t baud) {
    static const uint8_t ping_1[] = {0xFF, 0xFF, 0x01, 0x02, 0x01, 0xFB};
    (void)baud;
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    irq_enable(USART1_IRQ);
    rx_tail = rx_head;
    put(ping_1, sizeof ping_1);
    uint32_t began = fr_port_millis();
    while (rx_head - rx_tail < 6u && fr_port_millis() - began < BUS_PROBE_MS) {
    }
    opened = rx_head - rx_tail >= 6u;
    rx_tail = rx_head;
    return opened ? 0 : -1;
}

int fr_port_bus_write(const uint8_t *data, size_t len) {
    if (!opened) return -1;
    put(data, len);
    return 0;
}

bool fr_port_bus_writing(void) { return false; }

size_t fr_port_bus_read(uint8_t *buf, size_t cap) {
    size_t n = 0;
    while (n < cap && rx_tail != rx_head) {
        buf[n++] = rx_ring[rx_tail % BUS_RX_RING];
        rx_tail++;
    }
    return n;
}

/** USART1: every received byte into the ring (dropped when it is full). */
void USART1_IRQHandler(void);
void USART1_IRQHandler(void) {
    uint32_t sr = USART1_SR;
    while (sr & (USART_SR_RXNE | USART_SR_ORE)) {
        uint8_t b = (uint8_t)USART1_DR;
        if (rx_head - rx_tail < BUS_RX_RING) rx_ring[(rx_head++) % BUS_RX_RING] = b;
        sr = USART1_SR;
    }
}
