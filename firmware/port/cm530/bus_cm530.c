/* firmware/port/cm530/bus_cm530.c: the CM-530's Dynamixel bus (fr_port_bus.h), written from ROBOTIS's public CM-530
 * documentation and examples: USART1 remapped to PB6 (TX) and PB7 (RX), one half-duplex line behind a buffer whose
 * direction two pins set, PB4 high to transmit (TX enable) and PB5 high to receive (RX enable). The vendor's code
 * sends byte by byte and waits for each; here the transmit-empty interrupt feeds the bytes and the transmit-complete
 * interrupt turns the line back to receive the moment the last stop bit has left, so a servo's answer (after its
 * return delay, 0 to 508 microseconds) is never missed and nothing waits. Received bytes go into a ring. */
#include "fr_port_bus.h"
#include "stm32.h"

#define RCC_APB2ENR REG32(0x40021018u)
#define AFIO_MAPR REG32(0x40010004u)
#define GPIOB_CRL REG32(0x40010C00u)
#define GPIOB_BSRR REG32(0x40010C10u)
#define USART1_BASE 0x40013800u
#define USART1_SR REG32(USART1_BASE + 0x00u)
#define USART1_DR REG32(USART1_BASE + 0x04u)
#define USART1_BRR REG32(USART1_BASE + 0x08u)
#define USART1_CR1 REG32(USART1_BASE + 0x0Cu)
#define USART_SR_TC (1u << 6)
#define USART_CR1_TCIE (1u << 6)
#define USART1_IRQ 37u
#define PCLK2_HZ 72000000u
#define PIN_TX_ENABLE 4u
#define PIN_RX_ENABLE 5u

/** Receive ring: a whole status packet of 259 bytes and what follows it before the next poll. */
#define BUS_RX_RING 512u

static volatile uint8_t rx_ring[BUS_RX_RING];
static volatile uint32_t rx_head, rx_tail;
static uint8_t tx_buf[143];
static volatile uint32_t tx_len, tx_next;
static volatile bool sending;
static bool opened;

/** Line to transmit (PB4 high, PB5 low) or to receive (PB4 low, PB5 high). */
static void direction(bool transmit) {
    GPIOB_BSRR = transmit ? (1u << PIN_TX_ENABLE) | (1u << (PIN_RX_ENABLE + 16u))
                          : (1u << (PIN_TX_ENABLE + 16u)) | (1u << PIN_RX_ENABLE);
}

int fr_port_bus_open(uint32_t baud) {
    if (baud == 0) return -1;
    RCC_APB2ENR |= (1u << 0) | (1u << 3) | (1u << 14); /* AFIO, GPIOB, USART1 */
    /* USART1 on PB6/PB7; JTAG off (SWD stays) so PB4, JTAG's NJTRST, is a plain pin */
    AFIO_MAPR = (AFIO_MAPR & ~(7u << 24)) | (2u << 24) | (1u << 2);
    GPIOB_CRL = (GPIOB_CRL & ~(0xFFFFu << 16)) | (0x3u << 16) | (0x3u << 20) /* PB4, PB5: push-pull outputs */
                | (0xBu << 24)                                               /* PB6: alternate push-pull */
                | (0x4u << 28);                                              /* PB7: floating input */
    direction(false);
    /* 72 MHz / 1 Mbps = 72 = 4.5 in the 12.4 divider, exact */
    USART1_BRR = (PCLK2_HZ + baud / 2u) / baud;
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    irq_enable(USART1_IRQ);
    opened = true;
    return 0;
}

int fr_port_bus_write(const uint8_t *data, size_t len) {
    if (!opened || sending || len == 0 || len > sizeof tx_buf) return -1;
    for (size_t k = 0; k < len; k++) tx_buf[k] = data[k];
    tx_len = (uint32_t)len;
    tx_next = 0;
    sending = true;
    direction(true);
    USART1_CR1 |= USART_CR1_TXEIE;
    return 0;
}

bool fr_port_bus_writing(void) { return sending; }

size_t fr_port_bus_read(uint8_t *buf, size_t cap) {
    size_t n = 0;
    while (n < cap && rx_tail != rx_head) {
        buf[n++] = rx_ring[rx_tail % BUS_RX_RING];
        rx_tail++;
    }
    return n;
}

/** USART1: received bytes into the ring (none while sending: the line is ours), the next byte to send, and the
 *  turn back to receive once the last one has left. */
void USART1_IRQHandler(void);
void USART1_IRQHandler(void) {
    uint32_t sr = USART1_SR;
    while (sr & (USART_SR_RXNE | USART_SR_ORE)) {
        uint8_t b = (uint8_t)USART1_DR; /* reading DR clears RXNE and an overrun alike */
        if (!sending && rx_head - rx_tail < BUS_RX_RING) rx_ring[(rx_head++) % BUS_RX_RING] = b;
        sr = USART1_SR;
    }
    if ((USART1_CR1 & USART_CR1_TXEIE) && (sr & USART_SR_TXE)) {
        if (tx_next < tx_len) {
            USART1_DR = tx_buf[tx_next++];
        } else {
            USART1_CR1 = (USART1_CR1 & ~USART_CR1_TXEIE) | USART_CR1_TCIE;
        }
    }
    if ((USART1_CR1 & USART_CR1_TCIE) && (USART1_SR & USART_SR_TC)) {
        USART1_CR1 &= ~USART_CR1_TCIE;
        USART1_SR = ~USART_SR_TC; /* rc_w0: clears TC alone */
        direction(false);
        sending = false;
    }
}
