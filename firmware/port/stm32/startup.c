/* firmware/port/stm32/startup.c: reset and vector table for both Cortex-M3 boards (STM32F103 layout: 16 system
 * vectors and 60 interrupts, UART5 at 53). Copies .data, zeroes .bss, runs board_init and the program's main. */
#include <stdint.h>
#include <string.h>

#include "board.h"
#include "stm32.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _sstack, _estack;

int main(int argc, char **argv);

/* Defined by the port (port/stm32/fr_port_gs1500m.c). */
void SysTick_Handler(void);
void UART5_IRQHandler(void);

/** Every fault and unexpected interrupt: the program is wrong, so it ends visibly instead of running on. */
void Default_Handler(void);
void Default_Handler(void) { board_exit(70); }

/** The Dynamixel bus's USART (port/cm530/bus_cm530.c); a board without one never enables its interrupt. */
void USART1_IRQHandler(void) __attribute__((weak, alias("Default_Handler")));

#define VECTORS (16 + 60)
static void (*const vectors[VECTORS])(void);

/** Power-up and reset: C's memory model, then the board, then the program. */
void Reset_Handler(void);
void Reset_Handler(void) {
    /* Interrupts through this table wherever the image starts (after ROBOTIS's bootloader on a CM-530). */
    SCB_VTOR = (uint32_t)(uintptr_t)vectors;
    memcpy(&_sdata, &_sidata, (size_t)((uintptr_t)&_edata - (uintptr_t)&_sdata));
    memset(&_sbss, 0, (size_t)((uintptr_t)&_ebss - (uintptr_t)&_sbss));
    board_init();
    char **argv;
    int argc = board_args(&argv);
    board_exit(main(argc, argv));
}

/* The table the core reads at reset (initial stack pointer, then handlers). */
__attribute__((section(".isr_vector"), used)) static void (*const vectors[VECTORS])(void) = {
    [0] = (void (*)(void))(uintptr_t)&_estack,
    [1] = Reset_Handler,
    [2] = Default_Handler,  /* NMI */
    [3] = Default_Handler,  /* HardFault */
    [4] = Default_Handler,  /* MemManage */
    [5] = Default_Handler,  /* BusFault */
    [6] = Default_Handler,  /* UsageFault */
    [11] = Default_Handler, /* SVCall */
    [14] = Default_Handler, /* PendSV */
    [15] = SysTick_Handler,
    [16 + 37] = USART1_IRQHandler,
    [16 + 53] = UART5_IRQHandler,
};

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
