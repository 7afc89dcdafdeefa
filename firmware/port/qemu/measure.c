/* firmware/port/qemu/measure.c: the footprint measurement of docs/firmware.md, run on the emulated Cortex-M3 as the
 * thesis measured its firmware (7.1): the stack of each entry point by painting it with 0xCD (the thesis's pattern)
 * and finding the deepest byte the call overwrote, and the work of each by counting instructions. qemu runs it with `-icount shift=3`, where
 * every instruction advances virtual time by exactly 8 ns, so SysTick (not interrupting, counting down on the
 * core clock) reads a deterministic instruction count; a loop of known length calibrates the ratio.
 *
 * The library runs over the real GS1500M driver (so "frame" is the driver's `ESC Z` framing), but the module is
 * scripted here and the clock is this program's: the port below replaces port/stm32/fr_port_gs1500m.c. It prints
 * one line per figure ("measure <entry> insns=<n> stack=<bytes> bytes=<n>") and exits. */
#include <string.h>

#include "board.h"
#include "fr.h"
#include "fr_port.h"
#include "stm32.h"

gs1500m_t board_gs;
static uint32_t fake_ms;

/* ---- the port: the driver with this program's clock; no interrupts take part ---------------------------- */

void SysTick_Handler(void);
void SysTick_Handler(void) {}
void UART5_IRQHandler(void);
void UART5_IRQHandler(void) {}

uint32_t fr_port_millis(void) { return fake_ms; }
int fr_port_send(const fr_endpoint_t *to, const uint8_t *data, size_t len) {
    return gs1500m_send(&board_gs, fake_ms, to, data, len);
}
bool fr_port_board_health(fr_board_health_t *out) {
    (void)out;
    return false;
}
bool fr_port_frame_free(void) { return !gs1500m_tx_busy(&board_gs) && !gs1500m_rx_busy(&board_gs); }
int fr_port_recv(fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    return gs1500m_recv(&board_gs, fake_ms, from, buf, cap);
}
bool fr_port_link_up(void) {
    gs1500m_tick(&board_gs, fake_ms);
    return gs1500m_link_up(&board_gs);
}
void fr_port_idle(void) {}
/* The measurement's epoch lives in RAM: it signs nothing a gateway keeps. */
static uint32_t measure_epoch;
int fr_port_epoch_next(uint32_t *epoch) {
    *epoch = ++measure_epoch;
    return 0;
}

/* ---- counting -------------------------------------------------------------------------------------------- */

static uint32_t ticks_now(void) { return SYST_CVR; }
static uint32_t ticks_since(uint32_t start) { return (start - SYST_CVR) & 0xFFFFFFu; }

/* SysTick ticks for 2^16 instructions: 2^15 turns of a two-instruction loop, measured. */
static uint32_t ticks_per_64k;

static void calibrate(void) {
    uint32_t start = ticks_now();
    __asm__ volatile(
        "mov r0, #32768\n"
        "1: subs r0, r0, #1\n"
        "bne 1b\n" ::: "r0", "cc");
    ticks_per_64k = ticks_since(start);
}

static uint32_t instructions(uint32_t ticks) {
    return (uint32_t)(((uint64_t)ticks * 65536u + ticks_per_64k / 2u) / ticks_per_64k);
}

/* ---- output ---------------------------------------------------------------------------------------------- */

static char *put_u32(char *out, uint32_t v) {
    char tmp[10];
    int n = 0;
    do tmp[n++] = (char)('0' + v % 10u);
    while ((v /= 10u) != 0u);
    while (n > 0) *out++ = tmp[--n];
    return out;
}

static char *put_s(char *out, const char *s) {
    while (*s) *out++ = *s++;
    return out;
}

static void report(const char *entry, uint32_t insns, size_t stack, size_t bytes) {
    char line[96];
    char *p = put_s(line, "measure ");
    p = put_s(p, entry);
    p = put_u32(put_s(p, " insns="), insns);
    p = put_u32(put_s(p, " stack="), (uint32_t)stack);
    p = put_u32(put_s(p, " bytes="), (uint32_t)bytes);
    *p = '\0';
    board_log(line);
}

/* The serial bytes the driver has framed since the last call (what the UART would have sent). */
static uint8_t line_out[2048];
static size_t take_line(void) {
    size_t n = 0;
    uint8_t b;
    while (gs1500m_tx_pop(&board_gs, &b))
        if (n < sizeof line_out) line_out[n++] = b;
    return n;
}

/* One fr_poll, measured: its instructions and its stack; returns the serial bytes it framed. */
static size_t measure_poll(const char *entry) {
    (void)take_line();
    uintptr_t sp = board_stack_paint();
    uint32_t start = ticks_now();
    fr_poll();
    uint32_t ticks = ticks_since(start);
    size_t stack = board_stack_used(sp);
    size_t bytes = take_line();
    report(entry, instructions(ticks), stack, bytes);
    return bytes;
}

/* ---- the scripted module --------------------------------------------------------------------------------- */

static void module_says(const char *text) {
    while (*text) (void)gs1500m_rx_push(&board_gs, (uint8_t)*text++);
}

/* Answers every command the driver sent, as the module would, until the link is up (bounded). */
static void bring_up(void) {
    uint8_t cid = 0;
    for (int turn = 0; turn < 2000 && !gs1500m_link_up(&board_gs); turn++) {
        fake_ms += 10;
        fr_poll();
        size_t n = take_line();
        for (size_t i = 0; i + 1 < n; i++) {
            if (line_out[i] != '\r' || line_out[i + 1] != '\n') continue;
            size_t start = i;
            while (start > 0 && line_out[start - 1] != '\n') start--;
            if (n - start >= 6 && (memcmp(&line_out[start], "AT+NCU", 6) == 0 || memcmp(&line_out[start], "AT+NSU", 6) == 0)) {
                char connect[] = "CONNECT 0\r\n";
                connect[8] = (char)('0' + cid++);
                module_says(connect);
            }
            module_says("OK\r\n");
        }
    }
}

/* protocol.md 9.4: motion.walk(0.2, 0.0, 0.5), callId 7, arriving on the UDP server from the gateway. */
static const uint8_t walk_request[] = {
    0x1B, 0x79, '1', '1', '9', '2', '.', '1', '6', '8', '.', '1', '.', '1', '0', ' ', '1', '1', '0', '1', '1', '\t',
    '0', '0', '5', '5',
    0x00, 0x2A, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x2B, 0x08, 0x01, 0xB2, 0xBC,
    0x03, 0x25, 0x0A, 0x06, 0x6D, 0x6F, 0x74, 0x69, 0x6F, 0x6E, 0x12, 0x04, 0x77, 0x61, 0x6C, 0x6B,
    0x1A, 0x05, 0x1D, 0xCD, 0xCC, 0x4C, 0x3E, 0x1A, 0x05, 0x1D, 0x00, 0x00, 0x00, 0x00, 0x1A, 0x05,
    0x1D, 0x00, 0x00, 0x00, 0x3F, 0x78, 0x07};

static fr_rpc_status_t walk(const fr_call_t *call, fr_value_t *result, char *error, size_t error_cap,
                            fr_deferred_t later, void *ctx) {
    (void)later;
    (void)ctx;
    if (!fr_rpc_expect_floats(call, 3, error, error_cap)) return FR_RPC_ERROR;
    result->kind = FR_VALUE_BOOL;
    result->u.b = true;
    return FR_RPC_OK;
}

/* protocol.md 9.10: optionEnable "havimo" (switches havimo.* on by the prefix rule). */
static const uint8_t enable_havimo[] = {
    0x1B, 0x79, '1', '1', '9', '2', '.', '1', '6', '8', '.', '1', '.', '1', '0', ' ', '1', '1', '0', '1', '1', '\t',
    '0', '0', '2', '8',
    0x00, 0x2A, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x10, 0x08, 0x01, 0xEA, 0xBB,
    0x03, 0x0A, 0x1A, 0x08, 0x0A, 0x06, 0x68, 0x61, 0x76, 0x69, 0x6D, 0x6F};

/* The debug options of the thesis's Table 2 that the library has: text, HaViMo2 regions and grid. */
static int opt_text, opt_regions, opt_grid;
static uint8_t records[FR_HAVIMO_REGIONS_MAX * FR_HAVIMO_RECORD_SIZE];
static uint8_t cells[FR_HAVIMO_GRID_SIZE];
static char text_long[1301];

/* One debug-data call, measured like an fr_poll; returns the serial bytes it framed. */
typedef bool (*debug_call_t)(void);
static bool send_text_short(void) {
    /* 65 characters, the thesis's example text */
    return fr_debug_text(opt_text, "The quick brown fox jumps over the lazy dog while the robot waits.");
}
static bool send_text_long(void) { return fr_debug_text(opt_text, text_long); }
static bool send_regions(void) { return fr_havimo_regions(opt_regions, 1, records, FR_HAVIMO_REGIONS_MAX); }
static bool send_grid(void) { return fr_havimo_grid(opt_grid, 1, cells); }

static void measure_debug(const char *entry, debug_call_t call) {
    (void)take_line();
    uintptr_t sp = board_stack_paint();
    uint32_t start = ticks_now();
    bool sent = call();
    uint32_t ticks = ticks_since(start);
    size_t stack = board_stack_used(sp);
    size_t bytes = take_line();
    report(entry, instructions(ticks), stack, sent ? bytes : 0);
}

static void health(fr_health_t *out, void *ctx) {
    (void)ctx;
    out->battery_voltage = 12.4f;
    out->posture = "sit";
}

static const uint8_t key[32] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16,
                                17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32};

static fr_settings_t settings;

static void start(bool signed_frames) {
    memset(&settings, 0, sizeof settings);
    settings.robot_id = 1;
    settings.team_number = 1;
    settings.player_number = 1;
    settings.gateway = (fr_endpoint_t){{192, 168, 1, 10}, 11011};
    settings.agent = "SimAgent";
    settings.role = "striker";
    settings.boot_id = 1;
    settings.callbacks.health = health;
    settings.development = !signed_frames;
    if (signed_frames) {
        settings.signing_key = key;
        settings.signing_key_len = sizeof key;
    }
    uintptr_t sp = board_stack_paint();
    uint32_t begin = ticks_now();
    fr_init(&settings);
    uint32_t ticks = ticks_since(begin);
    size_t stack = board_stack_used(sp);
    if (!signed_frames) report("fr_init", instructions(ticks), stack, 0);
    (void)fr_rpc_register("motion", "walk", walk, NULL);
    opt_text = fr_option_add("havimo.log", FR_OPT_TEXT, NULL);
    opt_regions = fr_option_add("havimo.regions", FR_OPT_HAVIMO_REGIONS, NULL);
    opt_grid = fr_option_add("havimo.grid", FR_OPT_HAVIMO_GRID, NULL);
}

/* Keep-alives until the figures repeat (the first after start-up also reports the link). */
static void keepalives(const char *entry) {
    for (int i = 0; i < 3; i++) {
        fake_ms += FR_KEEPALIVE_MS;
        fr_poll();
        (void)take_line();
    }
    fake_ms += FR_KEEPALIVE_MS;
    (void)measure_poll(entry);
}

int main(int argc, char **argv) {
    (void)argc;
    (void)argv;
    /* SysTick as a free-running counter: no interrupt, the longest reload. */
    SYST_CSR = 0;
    SYST_RVR = 0xFFFFFFu;
    SYST_CVR = 0;
    SYST_CSR = SYST_CSR_ENABLE | SYST_CSR_CORE_CLOCK;
    calibrate();
    {
        char line[64];
        *put_u32(put_s(line, "measure calibration ticks_per_65536_insns="), ticks_per_64k) = '\0';
        board_log(line);
    }

    start(false);
    fake_ms = 0;
    bring_up();
    if (!gs1500m_link_up(&board_gs)) {
        board_log("measure: the scripted module did not come up");
        return 1;
    }
    keepalives("keepalive");
    (void)measure_poll("idle_poll");

    /* The framing alone: the keep-alive's bytes handed to the driver again (ESC Z header, copy into the ring). */
    {
        static uint8_t datagram[GS1500M_MAX_DATAGRAM];
        fake_ms += FR_KEEPALIVE_MS;
        fr_poll();
        size_t n = take_line();
        if (n > 7) {
            memcpy(datagram, &line_out[7], n - 7);
            uintptr_t sp = board_stack_paint();
            uint32_t begin = ticks_now();
            (void)gs1500m_send(&board_gs, fake_ms, &settings.gateway, datagram, n - 7);
            uint32_t ticks = ticks_since(begin);
            size_t stack = board_stack_used(sp); /* before anything else runs on the stack */
            report("frame_keepalive", instructions(ticks), stack, take_line());
        }
    }

    /* The request: the driver's receive interrupt pushes its bytes (measured alone), then one fr_poll decodes,
     * dispatches and answers it. */
    {
        uintptr_t sp = board_stack_paint();
        uint32_t begin = ticks_now();
        (void)gs1500m_rx_push(&board_gs, walk_request[0]);
        uint32_t ticks = ticks_since(begin);
        size_t stack = board_stack_used(sp); /* before anything else runs on the stack */
        report("uart_rx_byte", instructions(ticks), stack, 1);
        for (size_t i = 1; i < sizeof walk_request; i++) (void)gs1500m_rx_push(&board_gs, walk_request[i]);
        size_t answer = measure_poll("request_walk");
        if (answer == 0) {
            board_log("measure: the request got no answer");
            return 1;
        }
    }

    /* Debug data (the thesis's Table 2): the gateway enables havimo.*, then each kind is sent once. */
    for (size_t i = 0; i < sizeof enable_havimo; i++) (void)gs1500m_rx_push(&board_gs, enable_havimo[i]);
    fake_ms += 10;
    fr_poll();
    (void)take_line();
    memset(text_long, 'x', sizeof text_long - 1);
    for (size_t i = 0; i < sizeof records; i++) records[i] = (uint8_t)(i * 7u + 1u);
    for (size_t i = 0; i < sizeof cells; i++) cells[i] = (uint8_t)(i % 5u);
    measure_debug("debug_text", send_text_short);
    measure_debug("debug_text_long", send_text_long);
    measure_debug("havimo_regions", send_regions);
    measure_debug("havimo_grid", send_grid);

    /* The same with every frame signed (protocol.md 6.7, HMAC-SHA-256). */
    start(true);
    keepalives("keepalive_signed");
    board_log("measure: done");
    return 0;
}
