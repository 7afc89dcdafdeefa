/* firmware/port/stm32/uart_isr.h: the GS1500M UART's interrupt, as logic over five accessors the includer defines
 * (uart_sr, uart_dr_read, uart_dr_write, uart_cr1, uart_cr1_write): registers on the boards
 * (port/stm32/fr_port_gs1500m.c), a model of the USART on the host (tests/test_board.c), because qemu 7.2's STM32
 * USART never raises the transmit-empty interrupt (docs/firmware.md, "QEMU"). */
#ifndef UART_ISR_H
#define UART_ISR_H

#include "gs1500m.h"
#include "stm32.h"

/** One UART interrupt: every received byte into the driver's ring (reading DR clears RXNE and an overrun alike;
 *  an overrun's lost byte shows up as garbage later), then one byte out while the transmit-empty interrupt is on,
 *  which it switches off when nothing is left. */
static inline void uart_isr(gs1500m_t *gs) {
    uint32_t sr = uart_sr();
    while (sr & (USART_SR_RXNE | USART_SR_ORE)) {
        (void)gs1500m_rx_push(gs, (uint8_t)uart_dr_read());
        sr = uart_sr();
    }
    if ((uart_cr1() & USART_CR1_TXEIE) && (sr & USART_SR_TXE)) {
        uint8_t b;
        if (gs1500m_tx_pop(gs, &b)) uart_dr_write(b);
        else uart_cr1_write(uart_cr1() & ~USART_CR1_TXEIE);
    }
}

#endif
