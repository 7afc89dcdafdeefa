/* firmware/tests/test_board.c: the CM-530 board's logic on the host. Its clock plans (every divisor true to the
 * clock that runs, the ADC within 14 MHz) and the UART interrupt (port/stm32/uart_isr.h) driven by a model of the
 * STM32 USART, because qemu 7.2's USART never raises the transmit-empty interrupt the CM-530 sends with. */
#include <stdio.h>
#include <string.h>
#include "check.h"
#include "gs1500m.h"
#include "../port/cm530/cm530_clock.h"
#include "../port/stm32/stm32.h"

/* ---- a model of the USART: SR, DR, CR1 as the interrupt sees them ---------------------------------------- */

static uint32_t model_sr = USART_SR_TXE | USART_SR_TC, model_cr1;
static uint8_t model_rx_byte;
static uint8_t model_line[2048]; /* bytes the USART put on the line */
static size_t model_line_len;
static bool model_tx_busy;       /* a byte in the shift register: TXE clear until the line takes it */
static int model_overwrites;     /* DR written while still full: a byte lost on a real USART */

static uint32_t uart_sr(void) { return model_sr; }
static uint32_t uart_dr_read(void) {
    model_sr &= ~(USART_SR_RXNE | USART_SR_ORE); /* reading DR clears both, as on the STM32 */
    return model_rx_byte;
}
static void uart_dr_write(uint8_t b) {
    if (!(model_sr & USART_SR_TXE)) model_overwrites++;
    if (model_line_len < sizeof model_line) model_line[model_line_len++] = b;
    model_sr &= ~(USART_SR_TXE | USART_SR_TC);
    model_tx_busy = true;
}
static uint32_t uart_cr1(void) { return model_cr1; }
static void uart_cr1_write(uint32_t v) { model_cr1 = v; }
#include "../port/stm32/uart_isr.h"

static gs1500m_t gs;

/** The NVIC: the interrupt runs while one of its enabled causes is set. */
static bool irq_pending(void) {
    return (model_sr & (USART_SR_RXNE | USART_SR_ORE)) ||
           ((model_cr1 & USART_CR1_TXEIE) && (model_sr & USART_SR_TXE));
}

/** One byte time of the line: the shift register empties; a byte from the module may arrive. */
static void line_tick(const uint8_t *incoming, size_t *at, size_t n) {
    if (model_tx_busy) {
        model_tx_busy = false;
        model_sr |= USART_SR_TXE | USART_SR_TC;
    }
    if (*at < n) {
        if (model_sr & USART_SR_RXNE) model_sr |= USART_SR_ORE;
        model_rx_byte = incoming[(*at)++];
        model_sr |= USART_SR_RXNE;
    }
    for (int k = 0; k < 4 && irq_pending(); k++) uart_isr(&gs);
}

static void test_clock_plans(void) {
    static const struct { cm530_clock_source_t source; uint32_t core; } plans[] = {
        {CM530_CLOCK_HSE_PLL, 72000000u}, {CM530_CLOCK_HSI_PLL, 64000000u}, {CM530_CLOCK_HSI, 8000000u}};
    for (size_t i = 0; i < 3; i++) {
        cm530_clock_t c = cm530_clock_plan(plans[i].source, 460800u);
        CHECK(c.core_hz == plans[i].core);
        CHECK(c.pclk1_hz <= 36000000u && c.adc_hz <= 14000000u);
        /* SysTick counts core cycles: 1 kHz exactly */
        CHECK((c.systick_reload + 1u) * 1000u == c.core_hz);
        /* the UART's real rate within 2.5 % of the module's (the receiver samples 16 times a bit) */
        uint32_t real = c.pclk1_hz / c.uart_brr;
        CHECK(real > 460800u * 975u / 1000u && real < 460800u * 1025u / 1000u);
        /* the PLL's multiplier and source, and the flash's wait states, match the clock */
        uint32_t mul = ((c.cfgr >> 18) & 0xFu) + 2u;
        if (plans[i].source == CM530_CLOCK_HSE_PLL) CHECK((c.cfgr & (1u << 16)) && 8000000u * mul == c.core_hz);
        if (plans[i].source == CM530_CLOCK_HSI_PLL) CHECK(!(c.cfgr & (1u << 16)) && 4000000u * mul == c.core_hz);
        CHECK((c.flash_acr & 7u) == (c.core_hz > 48000000u ? 2u : c.core_hz > 24000000u ? 1u : 0u));
        /* APB1 at HCLK / 2 exactly when HCLK exceeds its 36 MHz */
        CHECK(((c.cfgr >> 8) & 7u) == (c.core_hz > 36000000u ? 4u : 0u));
    }
    /* the board as built: BRR 78 (36 MHz / 460800), the factory rate reachable too */
    CHECK(cm530_clock_plan(CM530_CLOCK_HSE_PLL, 460800u).uart_brr == 78u);
    CHECK(cm530_clock_plan(CM530_CLOCK_HSE_PLL, 9600u).uart_brr == 3750u);
}

/* Transmit by the transmit-empty interrupt as on the CM-530: a long datagram straight from the caller's buffer, a
 * short one after it, while the module sends bytes the same interrupt receives. */
static void test_interrupt_transmit(void) {
    gs1500m_config_t config = {{{192, 168, 1, 10}, 11011}, GS1500M_SERVER_PORT, 0, 460800u, 0u};
    gs1500m_init(&gs, &config, 0);
    static const char *const answers[] = {"OK\r\n", "OK\r\n", "OK\r\n", "CONNECT 0\r\nOK\r\n", "CONNECT 1\r\nOK\r\n"};
    uint32_t now = 1;
    for (size_t k = 0; k < 5; k++) {
        gs1500m_tick(&gs, now++);
        gs1500m_tick(&gs, now++);
        if (gs1500m_tx_pending(&gs)) model_cr1 |= USART_CR1_TXEIE; /* board_tx_kick */
        size_t at = 0, n = strlen(answers[k]);
        for (int t = 0; t < 200; t++) line_tick((const uint8_t *)answers[k], &at, n);
    }
    gs1500m_tick(&gs, now++);
    CHECK(gs1500m_link_up(&gs));
    model_line_len = 0;
    static uint8_t frame[1000];
    for (size_t i = 0; i < sizeof frame; i++) frame[i] = (uint8_t)(i * 13u + 1u);
    const fr_endpoint_t base = {{192, 168, 1, 10}, 11011};
    CHECK(gs1500m_send(&gs, now, &base, frame, sizeof frame) == 0);
    CHECK(gs1500m_send(&gs, now, &base, (const uint8_t *)"ping", 4) == 0);
    model_cr1 |= USART_CR1_TXEIE;
    /* the module's reply arrives while the frame goes out: one byte per byte time, both ways */
    const uint8_t reply[] = "\x1bZ00003abc";
    size_t at = 0;
    int ticks = 0;
    while ((model_cr1 & USART_CR1_TXEIE) && ticks < 5000) {
        line_tick(reply, &at, sizeof reply - 1);
        ticks++;
    }
    CHECK(!(model_cr1 & USART_CR1_TXEIE) && !gs1500m_tx_pending(&gs) && !gs1500m_tx_busy(&gs));
    CHECK(model_line_len == 7 + 1000 + 7 + 4 && memcmp(model_line, "\x1bZ01000", 7) == 0);
    CHECK(memcmp(model_line + 7, frame, 1000) == 0 && memcmp(model_line + 1007, "\x1bZ00004ping", 11) == 0);
    /* one interrupt per byte each way (plus the one that switched the transmit interrupt off), nothing lost */
    CHECK(ticks >= 1018 && ticks <= 1020);
    uint8_t buf[16];
    fr_endpoint_t from;
    CHECK(gs1500m_recv(&gs, now, &from, buf, sizeof buf) == 3 && memcmp(buf, "abc", 3) == 0);
    CHECK(gs1500m_stats(&gs)->rx_overruns == 0 && model_overwrites == 0);
}

int main(void) {
    test_clock_plans();
    test_interrupt_transmit();
    return DONE();
}
