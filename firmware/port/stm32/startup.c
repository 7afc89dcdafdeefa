/* firmware/port/stm32/startup.c: reset and vector table for both Cortex-M3 boards (STM32F103 layout: 16 system
 * vectors and 60 interrupts, UART5 at 53). Masks interrupts and switches off whatever a bootloader left on, copies
 * .data, zeroes .bss, runs board_init with interrupts still masked, then unmasks them and runs the program's main.
 * Every vector has a handler. The stack's guard (ld/sections.ld) is checked by board_stack_check; a broken guard
 * or a fault resets the board and leaves a note in .noinit that the next start reads (board_reset_note). */
#include <stdint.h>
#include <string.h>

#include "board.h"
#include "stm32.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _sstack, _estack, _sguard, _eguard;

int main(int argc, char **argv);

/* Defined by the port (port/stm32/fr_port_gs1500m.c). */
void SysTick_Handler(void);
void UART5_IRQHandler(void);

/** What ended the previous run, kept in .noinit (not zeroed at start): a magic word and the reason. */
#define NOTE_MAGIC 0x5EB0075Eu
__attribute__((section(".noinit"))) static volatile uint32_t note_magic, note_reason;
static uint32_t previous_note;

/** Resets the board, leaving `reason` for the next start. */
static void reset_with_note(uint32_t reason) {
    note_reason = reason;
    note_magic = NOTE_MAGIC;
    board_exit(70);
}

/** Every fault and unexpected interrupt: the program is wrong, so it ends visibly (a reset with a note) instead
 *  of running on. */
void Default_Handler(void);
void Default_Handler(void) { reset_with_note(BOARD_RESET_FAULT); }

uint32_t board_reset_note(void) { return previous_note; }

#define GUARD_WORD 0xDEADBEEFu

void board_stack_check(void) {
    for (volatile uint32_t *p = &_sguard; p < &_eguard; p++)
        if (*p != GUARD_WORD) reset_with_note(BOARD_RESET_STACK);
}

/** The Dynamixel bus's USART (port/cm530/bus_cm530.c); a board without one never enables its interrupt. */
void USART1_IRQHandler(void) __attribute__((weak, alias("Default_Handler")));

#define VECTORS (16 + 60)
static void (*const vectors[VECTORS])(void);

#define NVIC_ICER(n) REG32(0xE000E180u + 4u * (n))
#define NVIC_ICPR(n) REG32(0xE000E280u + 4u * (n))

/** Power-up and reset: interrupts off, C's memory model, then the board, then the program. */
void Reset_Handler(void);
void Reset_Handler(void) {
    /* A bootloader may jump here with its interrupts enabled and pending: none may run before its handler's state
     * exists. Masked (PRIMASK) first, then every source switched off and its pending bit cleared. */
    cpu_irq_disable();
    SYST_CSR = 0;
    for (uint32_t n = 0; n < 3; n++) {
        NVIC_ICER(n) = 0xFFFFFFFFu;
        NVIC_ICPR(n) = 0xFFFFFFFFu;
    }
    /* Interrupts through this table wherever the image starts (after ROBOTIS's bootloader on a CM-530). */
    SCB_VTOR = (uint32_t)(uintptr_t)vectors;
    memcpy(&_sdata, &_sidata, (size_t)((uintptr_t)&_edata - (uintptr_t)&_sdata));
    memset(&_sbss, 0, (size_t)((uintptr_t)&_ebss - (uintptr_t)&_sbss));
    previous_note = note_magic == NOTE_MAGIC ? note_reason : BOARD_RESET_NONE; /* after .bss is zeroed */
    note_magic = 0;
    for (volatile uint32_t *p = &_sguard; p < &_eguard; p++) *p = GUARD_WORD;
    board_init();
    cpu_irq_enable();
    char **argv;
    int argc = board_args(&argv);
    board_exit(main(argc, argv));
}

/* The table the core reads at reset (initial stack pointer, then handlers): every entry a handler. */
#define D Default_Handler
__attribute__((section(".isr_vector"), used)) static void (*const vectors[VECTORS])(void) = {
    (void (*)(void))(uintptr_t)&_estack, Reset_Handler,
    D, D, D, D, D, D, D, D, D, D, D, D, D, SysTick_Handler,          /* NMI .. PendSV, SysTick */
    D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, D,      /* IRQ 0 .. 19 */
    D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, D, USART1_IRQHandler, D, D, /* IRQ 20 .. 39, USART1 at 37 */
    D, D, D, D, D, D, D, D, D, D, D, D, D, UART5_IRQHandler, D, D,   /* IRQ 40 .. 55, UART5 at 53 */
    D, D, D, D,                                                      /* IRQ 56 .. 59 */
};
#undef D

uintptr_t board_stack_paint(void) {
    uintptr_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    /* Everything below this function's own frame; the loop itself keeps to registers. */
    for (volatile uint8_t *p = (volatile uint8_t *)&_sstack; (uintptr_t)p < sp - 8u; p++) *p = 0xCD;
    return sp;
}

size_t board_stack_used(uintptr_t sp) {
    /* From the bottom up to the first byte the call overwrote: its deepest point, even where a frame left parts
     * of a local buffer untouched (four pattern bytes in a row would end a scan from the top there). */
    const volatile uint8_t *p = (const volatile uint8_t *)&_sstack;
    while ((uintptr_t)p < sp - 8u && *p == 0xCD) p++;
    return (size_t)(sp - (uintptr_t)p);
}
