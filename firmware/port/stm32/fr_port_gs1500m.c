/* firmware/port/stm32/fr_port_gs1500m.c: fr_port.h on a Cortex-M3 board whose GS1500M sits on UART5 (the CM-530
 * and qemu's netduino2). The UART's receive interrupt fills the driver's ring; SysTick counts milliseconds; the
 * board decides how bytes leave (board_tx_kick). */
#include "board.h"
#include "fr_port.h"
#include "stm32.h"

gs1500m_t board_gs;

static volatile uint32_t millis;

/** 1 kHz tick: the library's clock. */
void SysTick_Handler(void);
void SysTick_Handler(void) { millis++; }

/** UART5: every received byte into the driver's ring; the transmit side when the board sends by interrupt. */
void UART5_IRQHandler(void);
void UART5_IRQHandler(void) {
    uint32_t sr = UART5_SR;
    while (sr & (USART_SR_RXNE | USART_SR_ORE)) {
        /* Reading DR clears RXNE and an overrun alike; an overrun's lost byte shows up as garbage later. */
        (void)gs1500m_rx_push(&board_gs, (uint8_t)UART5_DR);
        sr = UART5_SR;
    }
    if ((UART5_CR1 & USART_CR1_TXEIE) && (sr & USART_SR_TXE)) {
        uint8_t b;
        if (gs1500m_tx_pop(&board_gs, &b)) UART5_DR = b;
        else UART5_CR1 &= ~USART_CR1_TXEIE;
    }
}

uint32_t fr_port_millis(void) { return millis; }

int fr_port_send(const fr_endpoint_t *to, const uint8_t *data, size_t len) {
    int r = gs1500m_send(&board_gs, millis, to, data, len);
    board_tx_kick(); /* also when refused: the driver may have queued an AT command */
    return r;
}

bool fr_port_frame_free(void) { return !gs1500m_tx_busy(&board_gs) && !gs1500m_rx_busy(&board_gs); }

int fr_port_recv(fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    int r = gs1500m_recv(&board_gs, millis, from, buf, cap);
    board_tx_kick();
    return r;
}

bool fr_port_link_up(void) {
    gs1500m_tick(&board_gs, millis);
    board_tx_kick();
    return gs1500m_link_up(&board_gs);
}

void fr_port_idle(void) {
    /* Sleep until the next interrupt (SysTick within 1 ms, or a byte) unless bytes wait that the parser can use:
     * the emulator then idles too. Interrupts are masked around the check so a byte arriving in between still
     * wakes the core. */
    cpu_irq_disable();
    if (!gs1500m_rx_ready(&board_gs)) cpu_wfi();
    cpu_irq_enable();
}

int fr_port_epoch_next(uint32_t *epoch) { return board_epoch_next(epoch); }

void fr_port_log(const char *text) { board_log(text); }

bool fr_port_option(const char *arg) { return board_option(arg) != 0; }
