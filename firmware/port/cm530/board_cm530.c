/* firmware/port/cm530/board_cm530.c: the ROBOTIS CM-530 (STM32F103RE, 8 MHz crystal). Core at 72 MHz from the PLL,
 * the GS1500M on the "ZigBee" port: UART5, TX on PC12, RX on PD2, 460800 baud 8N1 (thesis 7.1), received by
 * interrupt into the driver's ring and sent by the transmit-empty interrupt, so a send never waits for the line.
 * The image starts at 0x08003000, behind ROBOTIS's bootloader (ld/stm32f103re.ld), and ends before the last two
 * 2 KB flash pages, 0x0807F000 and 0x0807F800, which keep the boot epoch (board_epoch_next). If the crystal or the
 * PLL fails the board runs on a slower clock with every divisor computed for it (cm530_clock.h) and says so in its
 * keep-alive. It builds and links here; it cannot run in the emulator (qemu has no STM32F1 with an RCC or a flash
 * controller), so its arithmetic is tested on the host (tests/test_board.c). */
#include "board.h"
#include "cm530_clock.h"
#include "stm32.h"

#ifndef BOARD_BASE_IP
/** The base station the module's first UDP client points at (the test robot's default gateway). */
#define BOARD_BASE_IP {192, 168, 1, 10}
#endif

#define RCC_BASE 0x40021000u
#define RCC_CR REG32(RCC_BASE + 0x00u)
#define RCC_CFGR REG32(RCC_BASE + 0x04u)
#define RCC_APB2ENR REG32(RCC_BASE + 0x18u)
#define RCC_APB1ENR REG32(RCC_BASE + 0x1Cu)
#define RCC_CR_HSION (1u << 0)
#define RCC_CR_HSIRDY (1u << 1)
#define RCC_CR_HSEON (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_CFGR_SWS (3u << 2)
#define FLASH_ACR REG32(0x40022000u)
#define GPIOA_CRH REG32(0x40010804u)
#define GPIOA_BRR REG32(0x40010814u)
#define GPIOC_CRH REG32(0x40011004u)
#define GPIOD_CRL REG32(0x40011400u)
#define GPIOD_BSRR REG32(0x40011410u)
/** The rate the port runs the GS1500M at (thesis 7.1); the module is set to it at start (gs1500m.h). */
#define GS1500M_BAUD 460800u
/** The module's own rate before it is told another (GainSpan's serial-to-WiFi firmware: 9600 8N1). */
#define GS1500M_FACTORY_BAUD 9600u

/** The plan the start-up reached, for the keep-alive's BoardHealth and the UART's divisor. */
static cm530_clock_t clock;

/** Waits for a bit of RCC_CR, boundedly (about 0.1 s on the RC oscillator). */
static int wait_for(uint32_t bit) {
    for (uint32_t i = 0; i < 200000u; i++)
        if (RCC_CR & bit) return 1;
    return 0;
}

/** Waits until the clock switch reports `sws`, boundedly. */
static int wait_switch(uint32_t sws) {
    for (uint32_t i = 0; i < 200000u; i++)
        if ((RCC_CFGR & RCC_CFGR_SWS) == sws) return 1;
    return 0;
}

/** Starts the fastest clock that comes up: the crystal through the PLL, else the RC oscillator through it, else
 *  the RC oscillator alone; returns its plan, so every divisor matches the clock that really runs. */
static cm530_clock_t clock_start(void) {
    /* From the RC oscillator with the PLL off, whatever the bootloader left: the PLL cannot change while it runs. */
    RCC_CR |= RCC_CR_HSION;
    (void)wait_for(RCC_CR_HSIRDY);
    RCC_CFGR &= ~3u;
    (void)wait_switch(0u);
    FLASH_ACR = 0x12u; /* the most wait states any plan needs, before a faster clock */
    RCC_CR &= ~RCC_CR_PLLON;
    RCC_CR |= RCC_CR_HSEON;
    cm530_clock_source_t source = wait_for(RCC_CR_HSERDY) ? CM530_CLOCK_HSE_PLL : CM530_CLOCK_HSI_PLL;
    if (source == CM530_CLOCK_HSI_PLL) RCC_CR &= ~RCC_CR_HSEON;
    cm530_clock_t plan = cm530_clock_plan(source, GS1500M_BAUD);
    RCC_CFGR = plan.cfgr; /* SW = HSI still */
    RCC_CR |= RCC_CR_PLLON;
    if (wait_for(RCC_CR_PLLRDY)) {
        RCC_CFGR = plan.cfgr | 2u; /* system clock from the PLL */
        if (wait_switch(2u << 2)) {
            FLASH_ACR = plan.flash_acr;
            return plan;
        }
        RCC_CFGR = plan.cfgr; /* back to the RC oscillator */
        (void)wait_switch(0u);
    }
    RCC_CR &= ~(RCC_CR_PLLON | RCC_CR_HSEON);
    plan = cm530_clock_plan(CM530_CLOCK_HSI, GS1500M_BAUD);
    RCC_CFGR = plan.cfgr;
    FLASH_ACR = plan.flash_acr;
    return plan;
}

uint32_t board_core_clock_hz(void) { return clock.core_hz; }

void board_uart_baud(uint32_t baud) {
    /* Only between bytes: the driver asks once the transmit side is empty (gs1500m_uart_baud). */
    UART5_BRR = (clock.pclk1_hz + baud / 2u) / baud;
}

void board_init(void) {
    static const gs1500m_config_t config = {{BOARD_BASE_IP, 11011u}, GS1500M_SERVER_PORT, GS1500M_BOOT_MS,
                                            GS1500M_BAUD, GS1500M_FACTORY_BAUD};
    clock = clock_start();
    RCC_APB2ENR |= (1u << 2) | (1u << 4) | (1u << 5); /* GPIOA, GPIOC, GPIOD */
    RCC_APB1ENR |= (1u << 20);                        /* UART5 */
    /* PA12 drives the ZigBee port's reset/enable line; ROBOTIS's CM-530 code keeps it low to run the module.
     * Output push-pull, 2 MHz, low. */
    GPIOA_BRR = 1u << 12;
    GPIOA_CRH = (GPIOA_CRH & ~(0xFu << 16)) | (0x2u << 16);
    /* PC12: alternate function push-pull, 50 MHz; PD2: input with pull-up, so the line idles high without a module */
    GPIOC_CRH = (GPIOC_CRH & ~(0xFu << 16)) | (0xBu << 16);
    GPIOD_CRL = (GPIOD_CRL & ~(0xFu << 8)) | (0x8u << 8);
    GPIOD_BSRR = 1u << 2;
    gs1500m_init(&board_gs, &config, 0);
    UART5_BRR = clock.uart_brr; /* 72 MHz: 36 MHz / 460800 = 78.1 -> 78, 461538 baud, +0.2 % */
    UART5_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    irq_enable(UART5_IRQ);
    SYST_RVR = clock.systick_reload;
    SYST_CVR = 0;
    SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_TICKINT | SYST_CSR_CORE_CLOCK;
}

/* ---- the boot epoch in flash ---------------------------------------------------------------------------------
 * Two pages, each a log of 32-bit epochs written in rising order into erased words (0xFFFFFFFF). The epoch is the
 * largest word written in either page. A start programs one word after the largest; when that page is full it
 * erases the other page and writes there, so an erase never takes the largest value with it (it stays in the
 * page not erased) and a power cut in between loses nothing. 512 starts per page erase: the F103's 10,000 erase
 * cycles last about ten million starts. */
#define EPOCH_PAGE_A 0x0807F000u
#define EPOCH_PAGE_SIZE 2048u
#define EPOCH_WORDS (EPOCH_PAGE_SIZE / 4u)
#define FLASH_KEYR REG32(0x40022004u)
#define FLASH_SR REG32(0x4002200Cu)
#define FLASH_CR REG32(0x40022010u)
#define FLASH_AR REG32(0x40022014u)
#define FLASH_SR_BSY (1u << 0)
#define FLASH_SR_PGERR (1u << 2)
#define FLASH_SR_WRPRTERR (1u << 4)
#define FLASH_SR_EOP (1u << 5)
#define FLASH_CR_PG (1u << 0)
#define FLASH_CR_PER (1u << 1)
#define FLASH_CR_STRT (1u << 6)
#define FLASH_CR_LOCK (1u << 7)

/** Word `i` of epoch page `page` (0 or 1). */
static volatile const uint32_t *epoch_word(uint32_t page, uint32_t i) {
    return (volatile const uint32_t *)(uintptr_t)(EPOCH_PAGE_A + page * EPOCH_PAGE_SIZE + 4u * i);
}

/** Waits for the flash controller, boundedly (a page erase takes about 20 ms); false on a timeout or an error. */
static int flash_wait(void) {
    for (uint32_t i = 0; i < 20000000u; i++) {
        if (!(FLASH_SR & FLASH_SR_BSY)) {
            uint32_t sr = FLASH_SR;
            FLASH_SR = FLASH_SR_EOP | FLASH_SR_PGERR | FLASH_SR_WRPRTERR; /* written 1s clear them */
            return !(sr & (FLASH_SR_PGERR | FLASH_SR_WRPRTERR));
        }
    }
    return 0;
}

/** Erases epoch page `page`. */
static int flash_erase(uint32_t page) {
    FLASH_CR |= FLASH_CR_PER;
    FLASH_AR = EPOCH_PAGE_A + page * EPOCH_PAGE_SIZE;
    FLASH_CR |= FLASH_CR_STRT;
    int ok = flash_wait();
    FLASH_CR &= ~FLASH_CR_PER;
    return ok;
}

/** Programs `value` into the erased word `i` of page `page`, as two half-words (the F103 programs 16 bits). */
static int flash_program(uint32_t page, uint32_t i, uint32_t value) {
    volatile uint16_t *half = (volatile uint16_t *)(uintptr_t)(EPOCH_PAGE_A + page * EPOCH_PAGE_SIZE + 4u * i);
    int ok = 1;
    FLASH_CR |= FLASH_CR_PG;
    half[0] = (uint16_t)value;
    ok = ok && flash_wait();
    half[1] = (uint16_t)(value >> 16);
    ok = ok && flash_wait();
    FLASH_CR &= ~FLASH_CR_PG;
    return ok && *epoch_word(page, i) == value;
}

int board_epoch_next(uint32_t *epoch) {
    uint32_t best = 0, best_page = 0, best_index = 0;
    int found = 0;
    for (uint32_t page = 0; page < 2; page++)
        for (uint32_t i = 0; i < EPOCH_WORDS; i++) {
            uint32_t w = *epoch_word(page, i);
            if (w != 0xFFFFFFFFu && (!found || w > best)) { best = w; best_page = page; best_index = i; found = 1; }
        }
    if (found && best >= 0xFFFFFFFEu) return -1; /* used up: refuse rather than repeat an epoch */
    uint32_t next = found ? best + 1u : 1u;
    uint32_t page = best_page, index = found ? best_index + 1u : 0u;
    if (FLASH_CR & FLASH_CR_LOCK) {
        FLASH_KEYR = 0x45670123u;
        FLASH_KEYR = 0xCDEF89ABu;
    }
    int ok;
    if (found && index < EPOCH_WORDS && *epoch_word(page, index) == 0xFFFFFFFFu) {
        ok = flash_program(page, index, next);
    } else {
        /* this page is full (or the word after the largest is not blank): start the other page afresh */
        page = found ? 1u - best_page : 0u;
        ok = flash_erase(page) && flash_program(page, 0, next);
    }
    FLASH_CR |= FLASH_CR_LOCK;
    if (!ok) return -1;
    *epoch = next;
    return 0;
}

int board_option(const char *arg) {
    (void)arg; /* a CM-530 has no command line */
    return 0;
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
