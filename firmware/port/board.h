/* firmware/port/board.h: what the Cortex-M3 boards (port/qemu, port/cm530) give beside fr_port.h: start-up
 * hooks, a log line, the end of the program, and the stack painting the footprint measurement uses. */
#ifndef BOARD_H
#define BOARD_H

#include <stddef.h>
#include <stdint.h>

#include "gs1500m.h"

/** Clocks, SysTick, the GS1500M's UART and its interrupt; runs before main. */
void board_init(void);

/** The program's arguments (`key=value` words): from the emulator's command line on qemu, none on a CM-530. */
int board_args(char ***argv);

/** One line of text for whoever watches the board (semihosting on qemu; nothing on a CM-530). */
void board_log(const char *text);

/** The program ended with `status` (semihosting exit on qemu; a reset on a CM-530). */
void board_exit(int status);

/** On qemu only: when set, board_exit calls it first (the board check's stand-in for a reset). */
extern void (*board_exit_hook)(int status);

/** fr_port_epoch_next of the board: raises the boot epoch in its persistent store (flash on a CM-530, a host file
 *  through semihosting on qemu); 0 when done, < 0 when it cannot. */
int board_epoch_next(uint32_t *epoch);

/** fr_port_option of the board: a `key=value` argument it understands (qemu: `epoch=<host path>`). */
int board_option(const char *arg);

/** Starts the UART sending what waits in the driver's transmit ring, without waiting for it. */
void board_tx_kick(void);

/** Sets the GS1500M's UART to `baud` at the clock the board runs on (the driver's start-up asks for the module's
 *  factory rate and back, gs1500m_uart_baud); the emulator ignores rates. */
void board_uart_baud(uint32_t baud);

/** The core clock the board runs at in Hz (the keep-alive's BoardHealth); 0 where it is not the board's own
 *  (the emulator). */
uint32_t board_core_clock_hz(void);

/** The GS1500M driver the port runs (one per board). */
extern gs1500m_t board_gs;

/** What ended the previous run (board_reset_note). */
enum { BOARD_RESET_NONE = 0, BOARD_RESET_FAULT = 1, BOARD_RESET_STACK = 2 };

/** What ended the previous run, as the start-up found it: BOARD_RESET_STACK when the stack's guard below it was
 *  overwritten, BOARD_RESET_FAULT after a fault or an unexpected interrupt, BOARD_RESET_NONE otherwise. */
uint32_t board_reset_note(void);

/** Resets the board with BOARD_RESET_STACK noted when the stack has grown into its guard (ld/sections.ld); the
 *  port calls it from its 1 kHz tick. */
void board_stack_check(void);

/** Fills the unused stack below the caller with 0xCD (the thesis's pattern, 7.1); returns the stack pointer. */
uintptr_t board_stack_paint(void);

/** Bytes of stack used below `sp` since board_stack_paint returned it: the deepest byte no longer 0xCD. */
size_t board_stack_used(uintptr_t sp);

#endif
