/* firmware/port/cm530/board_cm530.c: the ROBOTIS CM-530 (STM32F103RE, 8 MHz crystal). Core at 72 MHz from the PLL,
 * the GS1500M on the "ZigBee" port: UART5, TX on PC12, RX on PD2, 460800 baud 8N1 (thesis 7.1), received by
 * interrupt into the driver's ring and sent by the transmit-empty interrupt, so a send never waits for the line.
 * The image starts at 0x08003000, behind ROBOTIS's bootloader (ld/stm32f103re.ld). It builds and links here; it cannot
 * run in the emulator (qemu has no STM32F1 with an RCC). */
#include "board.h"
#include "stm32.h"

#ifndef BOARD_BASE_IP
/** The base station the module's first UDP client points at (the example robot's default gateway). */
#define BOARD_BASE_IP {192, 168, 1, 10}
#endif

#define RCC_BASE 0x40021000u
#define RCC_CR REG32(RCC_BASE + 0x00u)
#define RCC_CFGR REG32(RCC_BASE + 0x04u)
#define RCC_APB2ENR REG32(RCC_BASE + 0x18u)
#define RCC_APB1ENR REG32(RCC_BASE + 0x1Cu)
#define RCC_CR_HSEON (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define FLASH_ACR REG32(0x40022000u)
#define GPIOC_CRH REG32(0x40011004u)
#define GPIOD_CRL REG32(0x40011400u)
#define CORE_HZ 72000000u
#define PCLK1_HZ 36000000u
#define GS1500M_BAUD 460800u

/** Waits for a clock to be ready, boundedly: a board whose crystal does not start runs on the 8 MHz HSI. */
static int wait_for(uint32_t bit) {
    for (uint32_t i = 0; i < 1000000u; i++)
        if (RCC_CR & bit) return 1;
    return 0;
}

static void clock_72mhz(void) {
    /* ROBOTIS's bootloader may have started the PLL already; its settings cannot change while it runs. */
    if ((RCC_CFGR & (3u << 2)) == (2u << 2)) return;
    RCC_CR |= RCC_CR_HSEON;
    if (!wait_for(RCC_CR_HSERDY)) return;
    FLASH_ACR = 0x12u;                 /* prefetch on, two wait states above 48 MHz */
    RCC_CFGR = (7u << 18)              /* PLL x9: 8 MHz x 9 = 72 MHz */
               | (1u << 16)            /* PLL from HSE */
               | (4u << 8);            /* APB1 = HCLK / 2 = 36 MHz (its limit); APB2 = AHB = 72 MHz */
    RCC_CR |= RCC_CR_PLLON;
    if (!wait_for(RCC_CR_PLLRDY)) return;
    RCC_CFGR |= 2u;                    /* system clock from the PLL */
    for (uint32_t i = 0; i < 1000000u && (RCC_CFGR & (3u << 2)) != (2u << 2); i++) {
    }
}

void board_init(void) {
    static const gs1500m_config_t config = {{BOARD_BASE_IP, 11011u}, GS1500M_SERVER_PORT, GS1500M_BOOT_MS};
    clock_72mhz();
    RCC_APB2ENR |= (1u << 0) | (1u << 4) | (1u << 5); /* AFIO, GPIOC, GPIOD */
    RCC_APB1ENR |= (1u << 20);                        /* UART5 */
    /* PC12: alternate function push-pull, 50 MHz; PD2: floating input */
    GPIOC_CRH = (GPIOC_CRH & ~(0xFu << 16)) | (0xBu << 16);
    GPIOD_CRL = (GPIOD_CRL & ~(0xFu << 8)) | (0x4u << 8);
    gs1500m_init(&board_gs, &config, 0);
    /* BRR = PCLK1 / baud, a 12.4 fixed-point divider: 36 MHz / 460800 = 78.1 -> 78 (0x4E), 461538 baud, +0.2 % */
    UART5_BRR = (PCLK1_HZ + GS1500M_BAUD / 2u) / GS1500M_BAUD;
    UART5_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    irq_enable(UART5_IRQ);
    SYST_RVR = CORE_HZ / 1000u - 1u;
    SYST_CVR = 0;
    SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_TICKINT | SYST_CSR_CORE_CLOCK;
}

int board_args(char ***argv) {
    static char *none[] = {(char *)"robot", 0};
    *argv = none;
    return 1;
}

void board_log(const char *text) { (void)text; /* the CM-530's PC link (USART1) is the program's, not ours */ }

void board_exit(int status) {
    (void)status;
    /* A robot's program does not end; if it does, the board starts again. */
    SCB_AIRCR = (0x5FAu << 16) | (1u << 2);
    for (;;) {
    }
}

void board_tx_kick(void) {
    /* The transmit-empty interrupt takes the ring's bytes one by one and switches itself off when it is empty. */
    if (gs1500m_tx_pending(&board_gs)) UART5_CR1 |= USART_CR1_TXEIE;
}
