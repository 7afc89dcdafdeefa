/* firmware/port/qemu/board_qemu.c: the qemu `netduino2` machine as a stand-in CM-530. Its UART5 has the CM-530's
 * address, registers and interrupt; it has no RCC (reads give 0), so there is no clock set-up; SysTick runs on the
 * 120 MHz core clock. The program's arguments, its log and its end go through semihosting
 * (-semihosting-config enable=on,target=native; `-append "id=2 run_ms=5000"` gives arguments). Bytes leave by
 * polling: the emulated UART takes each at once. The boot epoch lives in a file on the host, read and written
 * through semihosting: `epoch=<path>` among the arguments, robot.epoch in qemu's working directory by default. */
#include <string.h>

#include "board.h"
#include "stm32.h"

#ifndef BOARD_CORE_HZ
#define BOARD_CORE_HZ 120000000u
#endif
#ifndef BOARD_BASE_IP
/** The base station the module's first UDP client points at (the test robot's default gateway). */
#define BOARD_BASE_IP {192, 168, 1, 10}
#endif
#ifndef BOARD_BOOT_MS
/** The emulated module (the test's bridge) needs no 4 s; a real one does. */
#define BOARD_BOOT_MS 50u
#endif

#define SYS_OPEN 0x01u
#define SYS_CLOSE 0x02u
#define SYS_WRITE 0x05u
#define SYS_READ 0x06u
#define SYS_WRITE0 0x04u
#define SYS_GET_CMDLINE 0x15u
#define SYS_EXIT 0x18u
#define SYS_EXIT_EXTENDED 0x20u
#define ADP_STOPPED_APPLICATION_EXIT 0x20026u

static uint32_t semihost(uint32_t op, const void *arg) {
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void board_log(const char *text) {
    semihost(SYS_WRITE0, text);
    semihost(SYS_WRITE0, "\n");
}

void (*board_exit_hook)(int status);

void board_exit(int status) {
    if (board_exit_hook != NULL) board_exit_hook(status); /* port/qemu/boardcheck.c: a reset instead */
    /* SYS_EXIT with a parameter block {reason, status}: qemu exits with `status` (ARM semihosting v2). */
    static uint32_t block[2];
    block[0] = ADP_STOPPED_APPLICATION_EXIT;
    block[1] = (uint32_t)status;
    for (;;) {
        semihost(SYS_EXIT_EXTENDED, block);
        /* an emulator without the extended call: plain exit (status 0 for success, 1 otherwise) */
        semihost(SYS_EXIT, (const void *)(uintptr_t)(status == 0 ? ADP_STOPPED_APPLICATION_EXIT : 0x20024u));
    }
}

#define MAX_ARGS 16
static char cmdline[512];
static char *args[MAX_ARGS + 1];

int board_args(char ***argv) {
    /* argv[0] is the program; the words after it are qemu's -append. */
    static uint32_t block[2];
    int argc = 0;
    block[0] = (uint32_t)(uintptr_t)cmdline;
    block[1] = sizeof cmdline - 1u;
    if (semihost(SYS_GET_CMDLINE, block) == 0u) {
        cmdline[sizeof cmdline - 1u] = '\0';
        char *p = cmdline;
        while (*p && argc < MAX_ARGS) {
            while (*p == ' ') *p++ = '\0';
            if (!*p) break;
            args[argc++] = p;
            while (*p && *p != ' ') p++;
        }
    }
    if (argc == 0) args[argc++] = (char *)"robot";
    args[argc] = NULL;
    *argv = args;
    return argc;
}

void board_tx_kick(void) {
    uint8_t b;
    while ((UART5_SR & USART_SR_TXE) && gs1500m_tx_pop(&board_gs, &b)) UART5_DR = b;
}

void board_uart_baud(uint32_t baud) { (void)baud; /* the emulator ignores the rate */ }

uint32_t board_core_clock_hz(void) { return 0; /* the host's, not a board's */ }

void board_init(void) {
    static const gs1500m_config_t config = {{BOARD_BASE_IP, 11011u}, GS1500M_SERVER_PORT, BOARD_BOOT_MS, 460800u,
                                            0u /* the emulator ignores the rate: nothing to set */};
    gs1500m_init(&board_gs, &config, 0);
    UART5_BRR = 0x10u; /* the emulator ignores the rate */
    UART5_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    irq_enable(UART5_IRQ);
    SYST_RVR = BOARD_CORE_HZ / 1000u - 1u;
    SYST_CVR = 0;
    SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_TICKINT | SYST_CSR_CORE_CLOCK;
}

/** The host file of the boot epoch (`epoch=<path>`). */
static char epoch_path[128] = "robot.epoch";

int board_option(const char *arg) {
    size_t n = strlen(arg);
    if (strncmp(arg, "epoch=", 6) != 0 || n == 6 || n - 6 >= sizeof epoch_path) return 0;
    memcpy(epoch_path, arg + 6, n - 5);
    return 1;
}

/** Opens the epoch file on the host in semihosting `mode` (0 "r", 4 "w"); its handle, or -1. */
static int32_t epoch_open(uint32_t mode) {
    static uint32_t block[3];
    block[0] = (uint32_t)(uintptr_t)epoch_path;
    block[1] = mode;
    block[2] = (uint32_t)strlen(epoch_path);
    return (int32_t)semihost(SYS_OPEN, block);
}

int board_epoch_next(uint32_t *epoch) {
    static uint32_t block[3];
    char text[16];
    uint32_t last = 0;
    int32_t h = epoch_open(0);
    if (h >= 0) {
        block[0] = (uint32_t)h;
        block[1] = (uint32_t)(uintptr_t)text;
        block[2] = sizeof text - 1u;
        uint32_t missing = semihost(SYS_READ, block); /* the bytes NOT read */
        block[0] = (uint32_t)h;
        semihost(SYS_CLOSE, block);
        size_t n = missing <= sizeof text - 1u ? sizeof text - 1u - missing : 0;
        size_t k = 0;
        for (; k < n && text[k] >= '0' && text[k] <= '9' && k < 10; k++) {
            uint64_t next = (uint64_t)last * 10u + (uint32_t)(text[k] - '0');
            if (next >= 0xFFFFFFFFu) return -1;
            last = (uint32_t)next;
        }
        if (k == 0 || (k < n && text[k] != '\n')) {
            board_log("epoch file damaged: refusing to guess an epoch");
            return -1;
        }
    }
    uint32_t next = last + 1u;
    size_t n = 0;
    char digits[12];
    for (uint32_t v = next; v > 0; v /= 10u) digits[n++] = (char)('0' + v % 10u);
    for (size_t k = 0; k < n; k++) text[k] = digits[n - 1 - k];
    text[n++] = '\n';
    h = epoch_open(4);
    if (h < 0) { board_log("epoch file cannot be written"); return -1; }
    block[0] = (uint32_t)h;
    block[1] = (uint32_t)(uintptr_t)text;
    block[2] = (uint32_t)n;
    uint32_t unwritten = semihost(SYS_WRITE, block);
    block[0] = (uint32_t)h;
    semihost(SYS_CLOSE, block);
    if (unwritten != 0) { board_log("epoch file cannot be written"); return -1; }
    *epoch = next;
    return 0;
}
