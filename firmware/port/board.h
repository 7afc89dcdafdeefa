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

/** fr_port_epoch_next of the board: raises the boot epoch in its persistent store (flash on a CM-530, a host file
 *  through semihosting on qemu); 0 when done, < 0 when it cannot. */
int board_epoch_next(uint32_t *epoch);

/** fr_port_option of the board: a `key=value` argument it understands (qemu: `epoch=<host path>`). */
int board_option(const char *arg);

/** Starts the UART sending what waits in the driver's transmit ring, without waiting for it. */
void board_tx_kick(void);

/** The GS1500M driver the port runs (one per board). */
extern gs1500m_t board_gs;

/** Fills the unused stack below the caller with 0xCD (the thesis's pattern, 7.1); returns the stack pointer. */
uintptr_t board_stack_paint(void);

/** Bytes of stack used below `sp` since board_stack_paint returned it: the deepest byte no longer 0xCD. */
size_t board_stack_used(uintptr_t sp);

#endif
