/* firmware/port/qemu/boardcheck.c: the board's start-up checked on the emulated Cortex-M3 (`make test-qemu-board`):
 * every vector has a handler; an interrupt a bootloader left enabled and pending when it jumped to Reset_Handler
 * never runs; the stack's guard sits between the static data and the stack; a stack grown into the guard resets the
 * board and the next start reports it. A reset is Reset_Handler entered again, as a bootloader or the core would
 * (board_exit_hook); RAM outside .data and .bss keeps its contents, as on the board. Prints
 * "boardcheck: N passed, N failed" and exits with 0 only when all passed. */
#include <stdint.h>

#include "board.h"
#include "stm32.h"

extern uint32_t _ebss, _sguard[], _eguard[], _sstack[];
void Reset_Handler(void);
void Default_Handler(void);
void SysTick_Handler(void);
void UART5_IRQHandler(void);
void USART1_IRQHandler(void);

#define NVIC_ISPR(n) REG32(0xE000E200u + 4u * (n))
#define STAGE_MAGIC 0xB0A4D000u

/* Which part of the check runs, kept across the simulated resets (.noinit is not zeroed by the start-up). */
__attribute__((section(".noinit"))) static volatile uint32_t stage, passed, failed;

static char *put_u32(char *out, uint32_t v);

/** Counts one check; a failed one is logged with its line. */
#define check(ok) check_at((ok), __LINE__)
static void check_at(int ok, int line) {
    if (ok) {
        passed++;
        return;
    }
    failed++;
    char text[32] = "boardcheck: failed at line ";
    *put_u32(text + 27, (uint32_t)line) = '\0';
    board_log(text);
}

static char *put_u32(char *out, uint32_t v) {
    char tmp[10];
    int n = 0;
    do tmp[n++] = (char)('0' + v % 10u);
    while ((v /= 10u) != 0u);
    while (n > 0) *out++ = tmp[--n];
    return out;
}

static void reset(int status) {
    (void)status;
    Reset_Handler(); /* never returns: main runs again */
}

int main(int argc, char **argv) {
    (void)argc;
    (void)argv;
    if ((stage & 0xFFFFFF00u) != STAGE_MAGIC) {
        stage = STAGE_MAGIC;
        passed = failed = 0;
    }
    switch (stage & 0xFFu) {
    case 0: {
        /* every vector: a Thumb handler; all but reset, SysTick, UART5 and USART1 (the qemu board's bus) the default
         * one */
        void (*const *table)(void) = (void (*const *)(void))(uintptr_t)SCB_VTOR;
        int defaults = 0, bad = 0;
        for (int i = 2; i < 16 + 60; i++) {
            uintptr_t h = (uintptr_t)table[i];
            if (h == 0u || (h & 1u) == 0u) bad++;
            if (table[i] == Default_Handler) defaults++;
        }
        check(bad == 0 && defaults == 16 + 60 - 5);
        check(table[1] == Reset_Handler && table[15] == SysTick_Handler && table[16 + 53] == UART5_IRQHandler &&
              table[16 + 37] == USART1_IRQHandler);
        check(board_reset_note() == BOARD_RESET_NONE);
        /* the guard between the static data and the stack, intact */
        check((uintptr_t)_sguard >= (uintptr_t)&_ebss && (uintptr_t)_eguard <= (uintptr_t)_sstack && _eguard - _sguard == 8);
        board_stack_check(); /* returns: the guard is whole */
        check(1);
        /* a bootloader's leftover: interrupt 0 enabled and pending, then a jump to Reset_Handler with interrupts
         * masked, as ROBOTIS's does; if the start-up let it through, Default_Handler would reset with a note */
        stage = STAGE_MAGIC | 1u;
        board_exit_hook = reset;
        cpu_irq_disable();
        NVIC_ISER(0) = 1u;
        NVIC_ISPR(0) = 1u;
        Reset_Handler();
        break;
    }
    case 1:
        check(board_reset_note() == BOARD_RESET_NONE);
        check((NVIC_ISER(0) & 1u) == 0u && (NVIC_ISPR(0) & 1u) == 0u);
        /* the stack grown into its guard: the 1 kHz check resets the board, the next start reports it */
        stage = STAGE_MAGIC | 2u;
        board_exit_hook = reset;
        ((volatile uint32_t *)_sguard)[3] = 0x12345678u;
        for (uint32_t spin = 0; spin < 50000000u; spin++) __asm__ volatile("" ::: "memory"); /* SysTick finds it */
        check(0); /* not reached when the check resets */
        break;
    default:
        check(board_reset_note() == BOARD_RESET_STACK);
        break;
    }
    board_exit_hook = 0;
    stage = 0;
    char line[64] = "boardcheck: ";
    char *p = put_u32(line + 12, passed);
    const char *mid = " passed, ";
    while (*mid) *p++ = *mid++;
    p = put_u32(p, failed);
    const char *end = " failed";
    while (*end) *p++ = *end++;
    *p = '\0';
    board_log(line);
    return failed == 0 ? 0 : 1;
}
