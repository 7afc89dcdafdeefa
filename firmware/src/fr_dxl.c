/* firmware/src/fr_dxl.c: the Dynamixel protocol 1.0 master on the port's half-duplex bus (fr_port_bus.h). One
 * transaction at a time, moved on by fr_dxl_poll without ever waiting: send, then collect the status packet until
 * it is whole or its timeout passes. Every length is checked before a byte is stored: garbage before the packet is
 * skipped, a packet that cannot fit is not one, a stuck line only costs the timeout. */
#include <string.h>
#include "fr_body.h"
#include "fr_port.h"
#include "fr_port_bus.h"

/** Received bytes thrown away per poll at most while the line is cleared or the buffer is full (a babbling bus). */
#define FR_DXL_DRAIN_MAX 256

/** Where the transaction is. */
typedef enum { PHASE_IDLE, PHASE_SEND, PHASE_SENDING, PHASE_RECEIVE } phase_t;

static struct {
    phase_t phase;
    fr_dxl_result_t result;
    uint8_t tx[FR_DXL_TX_MAX];
    size_t tx_len;
    size_t due;
    uint32_t timeout_ms, deadline;
    uint8_t rx[FR_DXL_RX_MAX];
    size_t rx_len;
    size_t start;        /* where the status packet begins in rx, once found */
    size_t total;        /* its length, once whole */
} m;

/** ~(sum of bytes) & 0xFF over id .. last parameter. */
static uint8_t checksum(const uint8_t *p, size_t n) {
    uint32_t sum = 0;
    for (size_t k = 0; k < n; k++) sum += p[k];
    return (uint8_t)~sum;
}

size_t fr_dxl_packet(uint8_t *out, uint8_t id, uint8_t instruction, const uint8_t *params, size_t count) {
    if (count + 6 > FR_DXL_TX_MAX) return 0;
    out[0] = out[1] = 0xFF;
    out[2] = id;
    out[3] = (uint8_t)(count + 2);
    out[4] = instruction;
    if (count > 0) memcpy(out + 5, params, count);
    out[5 + count] = checksum(out + 2, count + 3);
    return count + 6;
}

bool fr_dxl_well_formed(const uint8_t *p, size_t len) {
    if (len < 6 || len > FR_DXL_TX_MAX) return false;
    if (p[0] != 0xFF || p[1] != 0xFF || p[2] == 0xFF) return false;
    if ((size_t)p[3] + 4 != len) return false;
    return checksum(p + 2, len - 3) == p[len - 1];
}

size_t fr_dxl_reply_due(const uint8_t *p, size_t len) {
    if (!fr_dxl_well_formed(p, len)) return 0;
    if (p[2] == FR_DXL_BROADCAST || p[4] == FR_DXL_SYNC_WRITE) return 0;
    if (p[4] == FR_DXL_READ) return len == 8 ? 6u + p[6] : 0u; /* a read has exactly two parameters */
    return 6;
}

bool fr_dxl_start(const uint8_t *packet, size_t len, size_t due, uint32_t timeout_ms) {
    if (m.phase != PHASE_IDLE || len == 0 || len > FR_DXL_TX_MAX) return false;
    memcpy(m.tx, packet, len);
    m.tx_len = len;
    m.due = due > FR_DXL_RX_MAX ? FR_DXL_RX_MAX : due;
    m.timeout_ms = timeout_ms;
    m.rx_len = 0;
    m.start = 0;
    m.total = 0;
    m.result = FR_DXL_BUSY;
    m.phase = PHASE_SEND;
    return true;
}

void fr_dxl_reset(void) {
    m.phase = PHASE_IDLE;
    m.result = FR_DXL_IDLE;
    m.rx_len = m.total = m.start = 0;
}

/** Throws away up to FR_DXL_DRAIN_MAX received bytes. */
static void drain(void) {
    uint8_t scratch[64];
    for (size_t n = 0; n < FR_DXL_DRAIN_MAX; n += sizeof scratch)
        if (fr_port_bus_read(scratch, sizeof scratch) == 0) break;
}

/** Looks for a whole status packet in rx; FR_DXL_BUSY while none is whole yet. */
static fr_dxl_result_t parse(void) {
    size_t p = m.start;
    for (;;) {
        while (p + 1 < m.rx_len && !(m.rx[p] == 0xFF && m.rx[p + 1] == 0xFF && (p + 2 >= m.rx_len || m.rx[p + 2] != 0xFF)))
            p++;
        m.start = p;
        if (p + 4 > m.rx_len) return FR_DXL_BUSY; /* no header yet */
        size_t total = (size_t)m.rx[p + 3] + 4;
        if (m.rx[p + 3] < 2 || p + total > FR_DXL_RX_MAX) { p++; continue; } /* not a packet: look further */
        if (p + total > m.rx_len) return FR_DXL_BUSY;
        m.total = total;
        if (checksum(m.rx + p + 2, total - 3) != m.rx[p + total - 1]) return FR_DXL_CHECKSUM;
        if (m.rx[p + 2] != m.tx[2]) return FR_DXL_MALFORMED;
        /* the length the request makes due, or a bare status with its error byte set (a refused instruction) */
        if (total == m.due || (total == 6 && m.rx[p + 4] != 0)) return FR_DXL_OK;
        return FR_DXL_MALFORMED;
    }
}

fr_dxl_result_t fr_dxl_poll(void) {
    uint32_t now = fr_port_millis();
    switch (m.phase) {
    case PHASE_IDLE: return FR_DXL_IDLE;
    case PHASE_SEND:
        drain(); /* what the line carried before belongs to nobody */
        if (fr_port_bus_write(m.tx, m.tx_len) < 0) return FR_DXL_BUSY; /* the port is still busy: next poll */
        m.phase = PHASE_SENDING;
        /* fall through */
    case PHASE_SENDING:
        if (fr_port_bus_writing()) return FR_DXL_BUSY;
        if (m.due == 0) {
            m.phase = PHASE_IDLE;
            return FR_DXL_OK;
        }
        m.deadline = now + m.timeout_ms;
        m.phase = PHASE_RECEIVE;
        /* fall through */
    case PHASE_RECEIVE: {
        if (m.rx_len < FR_DXL_RX_MAX) m.rx_len += fr_port_bus_read(m.rx + m.rx_len, FR_DXL_RX_MAX - m.rx_len);
        else drain();
        fr_dxl_result_t r = parse();
        if (r == FR_DXL_BUSY && (int32_t)(now - m.deadline) > 0)
            r = m.start + 4 <= m.rx_len ? FR_DXL_SHORT : FR_DXL_TIMEOUT;
        if (r == FR_DXL_BUSY) return r;
        m.phase = PHASE_IDLE;
        m.result = r;
        return r;
    }
    }
    return FR_DXL_IDLE;
}

const uint8_t *fr_dxl_reply(size_t *len) {
    if (m.result == FR_DXL_OK && m.total > 0) {
        *len = m.total;
        return m.rx + m.start;
    }
    *len = m.result == FR_DXL_OK ? 0 : m.rx_len;
    return m.rx;
}
