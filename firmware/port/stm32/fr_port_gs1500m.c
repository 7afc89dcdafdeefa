/* firmware/port/stm32/fr_port_gs1500m.c: fr_port.h on a Cortex-M3 board whose GS1500M sits on UART5 (the CM-530
 * and qemu's netduino2). The UART's receive interrupt fills the driver's ring; SysTick counts milliseconds; the
 * board decides how bytes leave (board_tx_kick). */
#include "board.h"
#include "fr_port.h"
#include "stm32.h"

gs1500m_t board_gs;

static volatile uint32_t millis;

/** 1 kHz tick: the library's clock, and the stack's guard checked. */
void SysTick_Handler(void);
void SysTick_Handler(void) {
    millis++;
    board_stack_check();
}

static uint32_t uart_sr(void) { return UART5_SR; }
static uint32_t uart_dr_read(void) { return UART5_DR; }
static void uart_dr_write(uint8_t b) { UART5_DR = b; }
static uint32_t uart_cr1(void) { return UART5_CR1; }
static void uart_cr1_write(uint32_t v) { UART5_CR1 = v; }
#include "uart_isr.h"

/** UART5: every received byte into the driver's ring; the transmit side when the board sends by interrupt. */
void UART5_IRQHandler(void);
void UART5_IRQHandler(void) { uart_isr(&board_gs); }

uint32_t fr_port_millis(void) { return millis; }

int fr_port_send(const fr_endpoint_t *to, const uint8_t *data, size_t len) {
    int r = gs1500m_send(&board_gs, millis, to, data, len);
    board_tx_kick(); /* also when refused: the driver may have queued an AT command */
    return r;
}

bool fr_port_frame_free(void) { return !gs1500m_tx_busy(&board_gs) && !gs1500m_rx_busy(&board_gs); }

bool fr_port_board_health(fr_board_health_t *out) {
    out->core_clock_hz = board_core_clock_hz();
    if (out->core_clock_hz == 0u) return false; /* the emulator: no board of its own */
    uint32_t note = board_reset_note();
    out->stack_overflow_reset = note == BOARD_RESET_STACK;
    out->fault_reset = note == BOARD_RESET_FAULT;
    return true;
}

int fr_port_recv(fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    int r = gs1500m_recv(&board_gs, millis, from, buf, cap);
    board_tx_kick();
    return r;
}

/** The UART's rate as last set; the driver's start-up may ask for the module's factory rate and back. */
static uint32_t uart_baud;

bool fr_port_link_up(void) {
    gs1500m_tick(&board_gs, millis);
    uint32_t want = gs1500m_uart_baud(&board_gs);
    if (uart_baud == 0u) uart_baud = want; /* board_init set the first */
    if (want != uart_baud && !gs1500m_tx_pending(&board_gs) && (UART5_SR & USART_SR_TC)) {
        board_uart_baud(want); /* between bytes: the last one has left the line */
        uart_baud = want;
    }
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
