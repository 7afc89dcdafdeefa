/* firmware/port/cm530/cm530_clock.h: the CM-530's clock plans (STM32F103RE, RM0008 section 7). Pure arithmetic, so
 * the host tests check every divisor (tests/test_board.c) and board_cm530.c only applies the plan the start-up
 * reached: the crystal through the PLL (72 MHz), the internal RC oscillator through the PLL when the crystal does
 * not start (64 MHz), or the RC oscillator alone when the PLL does not lock either (8 MHz). */
#ifndef CM530_CLOCK_H
#define CM530_CLOCK_H

#include <stdint.h>

/** Where the core clock comes from. */
typedef enum {
    CM530_CLOCK_HSE_PLL = 0, /**< 8 MHz crystal x 9 = 72 MHz: the board as built */
    CM530_CLOCK_HSI_PLL,     /**< 8 MHz RC / 2 x 16 = 64 MHz: the crystal did not start */
    CM530_CLOCK_HSI          /**< 8 MHz RC alone: the PLL did not lock */
} cm530_clock_source_t;

/** One plan: the clocks it gives and every value derived from them. */
typedef struct {
    uint32_t core_hz;        /**< SYSCLK = HCLK = PCLK2 */
    uint32_t pclk1_hz;       /**< APB1 (UART5's clock), at most 36 MHz */
    uint32_t adc_hz;         /**< PCLK2 / ADCPRE, at most 14 MHz */
    uint32_t cfgr;           /**< RCC_CFGR without SW: PLL source and multiplier, APB1, ADC prescalers */
    uint32_t flash_acr;      /**< FLASH_ACR: prefetch and the wait states for core_hz */
    uint32_t uart_brr;       /**< UART5_BRR for the requested baud rate at pclk1_hz */
    uint32_t systick_reload; /**< SysTick reload for 1 kHz at core_hz */
} cm530_clock_t;

/** The plan for `source` with the GS1500M's UART at `baud`. */
static inline cm530_clock_t cm530_clock_plan(cm530_clock_source_t source, uint32_t baud) {
    cm530_clock_t c;
    uint32_t adcpre; /* ADCPRE field: 0 = /2, 1 = /4, 2 = /6, 3 = /8 */
    switch (source) {
    case CM530_CLOCK_HSE_PLL:
        c.core_hz = 72000000u;
        c.cfgr = (7u << 18) | (1u << 16) | (4u << 8); /* PLL x9 from HSE, APB1 = HCLK / 2 */
        c.flash_acr = 0x12u;                          /* prefetch, two wait states (48 .. 72 MHz) */
        adcpre = 2u;                                  /* 72 / 6 = 12 MHz */
        break;
    case CM530_CLOCK_HSI_PLL:
        c.core_hz = 64000000u;
        c.cfgr = (14u << 18) | (4u << 8); /* PLL x16 from HSI / 2, APB1 = HCLK / 2 */
        c.flash_acr = 0x12u;
        adcpre = 2u; /* 64 / 6 = 10.7 MHz */
        break;
    default:
        c.core_hz = 8000000u;
        c.cfgr = 0u;          /* no PLL, APB1 = HCLK */
        c.flash_acr = 0x10u;  /* prefetch, no wait state (up to 24 MHz) */
        adcpre = 0u;          /* 8 / 2 = 4 MHz */
        break;
    }
    c.cfgr |= adcpre << 14;
    c.pclk1_hz = c.core_hz > 36000000u ? c.core_hz / 2u : c.core_hz;
    c.adc_hz = c.core_hz / (2u * (adcpre + 1u));
    /* BRR = PCLK1 / baud as a 12.4 fixed-point divider, rounded */
    c.uart_brr = (c.pclk1_hz + baud / 2u) / baud;
    c.systick_reload = c.core_hz / 1000u - 1u;
    return c;
}

#endif
