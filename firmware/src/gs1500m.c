/* firmware/src/gs1500m.c: the GS1500M driver (see gs1500m.h). The parser follows the thesis's polled automaton
 * (5.2.2) and resynchronises as the host-side model does (sim/.../gs1500m/SerialDecoder.scala): an ESC
 * outside a datagram's data always starts a new item, a broken header or line is garbage up to the next ESC or LF,
 * and bulk data carry no escaping, so inside the announced length nothing is special. */
#include "gs1500m.h"

#include <string.h>

#define ESC 0x1B

/* The rings are shared with an interrupt: their bytes must be written before the index that publishes them, and
 * read after the index that says they are there. The compiler must not move ring accesses across this. */
#if defined(__GNUC__)
#define RING_BARRIER() __asm__ __volatile__("" ::: "memory")
#else
#define RING_BARRIER() ((void)0)
#endif

/* Parser states. */
enum {
    P_IDLE = 0, /* between items */
    P_SKIP,     /* garbage until ESC or LF */
    P_LINE,     /* a text status line */
    P_ESC,      /* after ESC */
    P_CID,      /* the connection id of a data header */
    P_ADDR,     /* `ESC y`: sender address up to the TAB */
    P_LEN,      /* four length digits */
    P_PAYLOAD   /* the datagram's bytes, copied out of the ring as they arrive */
};

/* Start-up commands, in order; the client's and the server's are filled in from the configuration. */
enum { STEP_ECHO_OFF = 0, STEP_BULK, STEP_CLIENT, STEP_SERVER, STEP_COUNT };


static uint16_t ring_next(uint16_t i, uint16_t size) { return (uint16_t)(i + 1u == size ? 0u : i + 1u); }

static uint16_t rx_count(const gs1500m_t *gs) {
    uint16_t h = gs->rx_head, t = gs->rx_tail;
    return (uint16_t)(h >= t ? h - t : GS1500M_RX_RING - t + h);
}

static uint16_t tx_free(const gs1500m_t *gs) {
    uint16_t h = gs->tx_head, t = gs->tx_tail;
    uint16_t used = (uint16_t)(h >= t ? h - t : GS1500M_TX_RING - t + h);
    return (uint16_t)(GS1500M_TX_RING - 1u - used);
}

/* Copies into the ring at `at` in at most two pieces; returns the index after the copy. Callers checked the room. */
static uint16_t tx_copy(gs1500m_t *gs, uint16_t at, const uint8_t *data, size_t len) {
    size_t first = (size_t)(GS1500M_TX_RING - at);
    if (first > len) first = len;
    memcpy(&gs->tx[at], data, first);
    memcpy(&gs->tx[0], data + first, len - first);
    at = (uint16_t)(at + len);
    return (uint16_t)(at >= GS1500M_TX_RING ? at - GS1500M_TX_RING : at);
}

static void tx_put(gs1500m_t *gs, const uint8_t *data, size_t len) {
    uint16_t head = tx_copy(gs, gs->tx_head, data, len);
    RING_BARRIER();
    gs->tx_head = head; /* published last: the UART never sees half of it */
}

/* Appends the decimal digits of `v` to `out`; returns the new length. */
static size_t put_uint(char *out, size_t at, uint32_t v) {
    char digits[10];
    size_t n = 0;
    do {
        digits[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u && n < sizeof digits);
    while (n > 0) out[at++] = digits[--n];
    return at;
}

static size_t put_str(char *out, size_t at, const char *s) {
    while (*s) out[at++] = *s++;
    return at;
}

/* "a.b.c.d,port" as AT+NCUDP and friends take it. */
static size_t put_endpoint(char *out, size_t at, const fr_endpoint_t *e) {
    for (int i = 0; i < 4; i++) {
        at = put_uint(out, at, e->ip[i]);
        out[at++] = (char)(i < 3 ? '.' : ',');
    }
    return put_uint(out, at, e->port);
}

/* Queues one command line; false when the ring has no room now (the caller tries again on a later tick). */
static bool command(gs1500m_t *gs, const char *text, size_t len, uint32_t now) {
    if (tx_free(gs) < len + 2u) return false;
    tx_put(gs, (const uint8_t *)text, len);
    tx_put(gs, (const uint8_t *)"\r\n", 2);
    gs->waiting = true;
    gs->since = now;
    return true;
}

static void forget_connections(gs1500m_t *gs) {
    for (int i = 0; i < GS1500M_PEERS; i++) {
        gs->peers[i].cid = -1;
        if (i > 0) gs->peers[i].used = false;
    }
    gs->server_cid = -1;
    gs->opening = -1;
}

/* Back to asking `AT` until the module answers: after a loss, an error or silence. */
static void restart(gs1500m_t *gs, uint32_t now, bool link_lost) {
    if (gs->state == GS1500M_READY && link_lost) gs->stats.link_losses++;
    gs->stats.restarts++;
    forget_connections(gs);
    gs->state = GS1500M_PROBING;
    gs->waiting = false;
    gs->step = 0;
    gs->probes = 0;
    gs->setting_baud = false;
    /* the next probe goes out one interval from now: a module that just reset is still busy */
    gs->since = now;
}

void gs1500m_init(gs1500m_t *gs, const gs1500m_config_t *config, uint32_t now_ms) {
    memset(gs, 0, sizeof *gs);
    gs->config = *config;
    gs->state = GS1500M_BOOTING;
    gs->since = now_ms;
    gs->cid = -1;
    forget_connections(gs);
    gs->peers[0].to = config->base;
    gs->peers[0].used = true;
    gs->uart_baud = config->baud;
}

uint32_t gs1500m_uart_baud(const gs1500m_t *gs) { return gs->uart_baud; }

bool gs1500m_rx_push(gs1500m_t *gs, uint8_t byte) {
    uint16_t h = gs->rx_head;
    uint16_t n = ring_next(h, GS1500M_RX_RING);
    if (n == gs->rx_tail) {
        gs->stats.rx_overruns++;
        return false;
    }
    gs->rx[h] = byte;
    RING_BARRIER();
    gs->rx_head = n;
    return true;
}

bool gs1500m_tx_pop(gs1500m_t *gs, uint8_t *byte) {
    uint16_t t = gs->tx_tail;
    const uint8_t *data = gs->tx_data;
    if (data != NULL && t == gs->tx_data_at) {
        /* the datagram sent from the caller's memory, between its header and what was queued after it */
        uint16_t pos = gs->tx_data_pos;
        *byte = data[pos++];
        gs->tx_data_pos = pos;
        if (pos == gs->tx_data_len) gs->tx_data = NULL;
        return true;
    }
    if (t == gs->tx_head) return false;
    RING_BARRIER();
    *byte = gs->tx[t];
    gs->tx_tail = ring_next(t, GS1500M_TX_RING);
    return true;
}

bool gs1500m_tx_pending(const gs1500m_t *gs) { return gs->tx_tail != gs->tx_head || gs->tx_data != NULL; }

bool gs1500m_tx_busy(const gs1500m_t *gs) { return gs->tx_data != NULL; }

bool gs1500m_rx_busy(const gs1500m_t *gs) { return gs->parse == P_PAYLOAD; }

static int parse(gs1500m_t *gs, uint32_t now, bool deliver, fr_endpoint_t *from, uint8_t *buf, size_t cap);

/* Sends the command of the current start-up step. */
static void send_step(gs1500m_t *gs, uint32_t now) {
    char text[40];
    size_t n = 0;
    switch (gs->step) {
    case STEP_ECHO_OFF: n = put_str(text, 0, "ATE0"); break;
    case STEP_BULK: n = put_str(text, 0, "AT+BDATA=1"); break;
    case STEP_CLIENT:
        n = put_str(text, 0, "AT+NCUDP=");
        n = put_endpoint(text, n, &gs->config.base);
        break;
    default:
        n = put_str(text, 0, "AT+NSUDP=");
        n = put_uint(text, n, gs->config.listen_port);
        break;
    }
    (void)command(gs, text, n, now);
}

void gs1500m_tick(gs1500m_t *gs, uint32_t now) {
    (void)parse(gs, now, false, NULL, NULL, 0);
    uint32_t waited = now - gs->since;
    switch (gs->state) {
    case GS1500M_BOOTING:
        if (waited >= gs->config.boot_ms) {
            gs->state = GS1500M_PROBING;
            gs->waiting = false;
            gs->since = now - GS1500M_PROBE_MS; /* the first probe goes at once */
        } else {
            break;
        }
        /* fall through */
    case GS1500M_PROBING:
        if (gs->setting_baud) {
            if (waited >= GS1500M_REPLY_MS) gs->setting_baud = false; /* ATB unanswered: probe again */
            break;
        }
        /* No OK yet: the module is still booting or joining, or listens at another rate; ask again, after
         * GS1500M_BAUD_PROBES silent ones at the other rate (once the last probe has left the UART). */
        if (now - gs->since >= GS1500M_PROBE_MS) {
            if (gs->config.factory_baud != 0u && gs->probes >= GS1500M_BAUD_PROBES) {
                if (gs1500m_tx_pending(gs)) break;
                gs->uart_baud = gs->uart_baud == gs->config.baud ? gs->config.factory_baud : gs->config.baud;
                gs->probes = 0;
            }
            if (command(gs, "AT", 2, now) && gs->probes < 255u) gs->probes++;
        }
        break;
    case GS1500M_CONFIGURING:
        if (gs->waiting) {
            if (waited >= GS1500M_REPLY_MS) restart(gs, now, false);
        } else {
            send_step(gs, now);
        }
        break;
    case GS1500M_READY:
        if (gs->opening >= 0 && gs->waiting && waited >= GS1500M_REPLY_MS) {
            gs->peers[gs->opening].used = false; /* no answer: the next send to it tries again */
            gs->opening = -1;
            gs->waiting = false;
        }
        break;
    }
}

static bool starts_with(const char *s, const char *prefix) {
    while (*prefix)
        if (*s++ != *prefix++) return false;
    return true;
}

static bool contains(const char *s, const char *word) {
    for (; *s; s++)
        if (starts_with(s, word)) return true;
    return false;
}

/* The connection id after "CONNECT " / "DISCONNECT ", when that is all the line holds; else -1. */
static int line_cid(const char *rest) {
    int c = rest[0];
    int v = (c >= '0' && c <= '9') ? c - '0' : (c >= 'a' && c <= 'f') ? c - 'a' + 10 : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : -1;
    return (v >= 0 && rest[1] == '\0') ? v : -1;
}

/* A text line from the module: command answers, connection ids, and the notices that end the link. */
static void on_line(gs1500m_t *gs, const char *line, uint32_t now) {
    gs->stats.status_lines++;
    if (starts_with(line, "DISASSOC") || contains(line, "Disassociat") || contains(line, "Serial2WiFi APP") ||
        starts_with(line, "APP Reset") || contains(line, "Warm Boot")) {
        /* The module left the network or restarted: everything it had open is gone. While it is still being
         * brought up there is nothing to undo. */
        if (gs->state == GS1500M_CONFIGURING || gs->state == GS1500M_READY) restart(gs, now, true);
        return;
    }
    if (starts_with(line, "DISCONNECT ")) {
        int cid = line_cid(line + 11);
        if (cid < 0) return;
        if (cid == gs->server_cid || cid == gs->peers[0].cid) {
            restart(gs, now, true);
            return;
        }
        for (int i = 1; i < GS1500M_PEERS; i++)
            if (gs->peers[i].used && gs->peers[i].cid == cid) gs->peers[i].used = false;
        return;
    }
    if (starts_with(line, "CONNECT ")) {
        int cid = line_cid(line + 8);
        if (cid < 0) return; /* a TCP server's new client: never asked for here */
        if (gs->state == GS1500M_CONFIGURING && gs->waiting && gs->step == STEP_CLIENT) gs->peers[0].cid = (int8_t)cid;
        else if (gs->state == GS1500M_CONFIGURING && gs->waiting && gs->step == STEP_SERVER) gs->server_cid = (int8_t)cid;
        else if (gs->state == GS1500M_READY && gs->opening >= 0) gs->peers[gs->opening].cid = (int8_t)cid;
        return;
    }
    bool ok = line[0] == 'O' && line[1] == 'K' && line[2] == '\0';
    bool error = starts_with(line, "ERROR");
    if (!ok && !error) return; /* echoes, banners, notices this driver has no use for */
    switch (gs->state) {
    case GS1500M_PROBING:
        if (gs->setting_baud) {
            /* ATB's answer, at the factory rate; the module runs at the new one from now on */
            gs->setting_baud = false;
            gs->waiting = false;
            if (ok) gs->uart_baud = gs->config.baud;
            gs->probes = 0;
            gs->since = now - GS1500M_PROBE_MS; /* the next probe at once, at the new rate */
        } else if (ok && gs->uart_baud != gs->config.baud) {
            /* a module at its factory rate: told the board's (not saved: a module reset brings this back) */
            char text[20];
            size_t n = put_uint(text, put_str(text, 0, "ATB="), gs->config.baud);
            if (command(gs, text, n, now)) gs->setting_baud = true;
        } else if (ok) {
            gs->state = GS1500M_CONFIGURING;
            gs->step = 0;
            gs->waiting = false;
            gs->probes = 0;
        }
        break;
    case GS1500M_CONFIGURING:
        if (!gs->waiting) break;
        gs->waiting = false;
        if (error || (gs->step == STEP_CLIENT && gs->peers[0].cid < 0) ||
            (gs->step == STEP_SERVER && gs->server_cid < 0)) {
            restart(gs, now, false);
        } else if (++gs->step == STEP_COUNT) {
            gs->state = GS1500M_READY;
        }
        break;
    case GS1500M_READY:
        if (gs->opening >= 0 && gs->waiting) {
            if (error || gs->peers[gs->opening].cid < 0) gs->peers[gs->opening].used = false;
            gs->opening = -1;
            gs->waiting = false;
        }
        break;
    default:
        break;
    }
}

/* "a.b.c.d port" (or with a colon) into an endpoint; false when it is not that. */
static bool parse_address(const char *s, fr_endpoint_t *out) {
    uint32_t part = 0;
    int digits = 0, octet = 0;
    for (;; s++) {
        char c = *s;
        if (c >= '0' && c <= '9') {
            part = part * 10u + (uint32_t)(c - '0');
            if (++digits > 5) return false;
        } else if (octet < 3 && c == '.') {
            if (digits == 0 || part > 255u) return false;
            out->ip[octet++] = (uint8_t)part;
            part = 0;
            digits = 0;
        } else if (octet == 3 && (c == ' ' || c == ':')) {
            if (digits == 0 || part > 255u) return false;
            out->ip[octet++] = (uint8_t)part;
            part = 0;
            digits = 0;
        } else if (octet == 4 && c == '\0') {
            if (digits == 0 || part > 65535u) return false;
            out->port = (uint16_t)part;
            return true;
        } else {
            return false;
        }
    }
}

static bool is_text(uint8_t b) { return (b >= 0x20 && b <= 0x7E) || b == '\t' || b == '\r'; }

static bool is_reply_letter(uint8_t b) {
    return ((b >= 'A' && b <= 'Z') || (b >= 'a' && b <= 'z')) && b != 'Z' && b != 'y';
}

static int hex_digit(uint8_t b) {
    if (b >= '0' && b <= '9') return b - '0';
    if (b >= 'a' && b <= 'f') return b - 'a' + 10;
    if (b >= 'A' && b <= 'F') return b - 'A' + 10;
    return -1;
}

static void garbage(gs1500m_t *gs, uint32_t bytes) {
    gs->stats.garbage_bytes += bytes;
    gs->garbage_run += bytes;
}

/* A header or line broke at byte `b` after `consumed` good-looking bytes. */
static void broken(gs1500m_t *gs, uint32_t consumed, uint8_t b) {
    garbage(gs, consumed);
    if (b == ESC) {
        gs->parse = P_ESC;
    } else if (b == '\n') {
        garbage(gs, 1);
        gs->parse = P_IDLE;
    } else {
        garbage(gs, 1);
        gs->parse = P_SKIP;
    }
}

static void idle_byte(gs1500m_t *gs, uint8_t b) {
    if (b == ESC) {
        gs->parse = P_ESC;
    } else if (b == '\r' || b == '\n') {
        /* the module pads its answers with empty lines */
    } else if (is_text(b)) {
        gs->line[0] = (char)b;
        gs->line_len = 1;
        gs->line_long = false;
        gs->parse = P_LINE;
    } else {
        garbage(gs, 1);
        gs->parse = P_SKIP;
    }
}

/* One byte of everything but a datagram's data. */
static void step_byte(gs1500m_t *gs, uint8_t b, uint32_t now) {
    switch (gs->parse) {
    case P_IDLE: idle_byte(gs, b); break;
    case P_SKIP:
        if (b == ESC) gs->parse = P_ESC;
        else if (b == '\n') { garbage(gs, 1); gs->parse = P_IDLE; }
        else garbage(gs, 1);
        break;
    case P_LINE:
        if (b == '\n') {
            uint8_t end = gs->line_len;
            while (end > 0 && gs->line[end - 1] == '\r') end--;
            gs->line[end] = '\0';
            gs->parse = P_IDLE;
            if (gs->line_long) garbage(gs, (uint32_t)gs->line_len + 1u);
            else if (end > 0) on_line(gs, gs->line, now);
        } else if (is_text(b)) {
            if (gs->line_len < GS1500M_LINE_MAX) gs->line[gs->line_len++] = (char)b;
            else gs->line_long = true; /* read to its end, then dropped */
        } else {
            broken(gs, gs->line_len, b);
        }
        break;
    case P_ESC:
        if (b == 'Z' || b == 'y') {
            gs->udp_server = b == 'y';
            gs->parse = P_CID;
        } else if (b == ESC) {
            garbage(gs, 1);
        } else if (is_reply_letter(b)) {
            if (b == 'O') gs->stats.acks++;
            else if (b == 'F') gs->stats.fails++;
            else gs->stats.other_replies++;
            gs->parse = P_IDLE;
        } else {
            garbage(gs, 1);
            gs->parse = P_IDLE;
            idle_byte(gs, b);
        }
        break;
    case P_CID: {
        int cid = hex_digit(b);
        if (cid < 0) {
            broken(gs, 2, b);
        } else {
            gs->cid = (int8_t)cid;
            gs->line_len = 0;
            gs->digits = 0;
            gs->length = 0;
            gs->consumed = 3;
            gs->sender_known = false;
            gs->parse = gs->udp_server ? P_ADDR : P_LEN;
        }
        break;
    }
    case P_ADDR:
        if (b == '\t') {
            gs->line[gs->line_len] = '\0';
            gs->sender_known = parse_address(gs->line, &gs->sender);
            gs->consumed = (uint16_t)(4u + gs->line_len);
            gs->parse = P_LEN;
        } else if (b >= 0x20 && b <= 0x7E && gs->line_len < 31u && gs->line_len < GS1500M_LINE_MAX) {
            gs->line[gs->line_len++] = (char)b;
        } else {
            broken(gs, 3u + gs->line_len, b);
        }
        break;
    case P_LEN:
        if (b >= '0' && b <= '9') {
            gs->length = (uint16_t)(gs->length * 10u + (uint16_t)(b - '0'));
            gs->consumed++;
            if (++gs->digits == 4) {
                if (gs->length > GS1500M_MAX_DATAGRAM) {
                    garbage(gs, gs->consumed);
                    gs->parse = P_SKIP;
                } else if (gs->length == 0) {
                    gs->parse = P_IDLE; /* an empty datagram carries nothing the library could use */
                } else {
                    gs->payload_since = now;
                    gs->got = 0;
                    gs->parse = P_PAYLOAD;
                }
            }
        } else {
            broken(gs, gs->consumed, b);
        }
        break;
    default:
        break;
    }
}

/* Copies what has arrived of the current datagram's data into `buf` (or drops it when the datagram is longer than
 * `cap`); hands the datagram out once all of it is there: its length, -1 when it was too long, 0 while more must come. */
static int take_payload(gs1500m_t *gs, fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    uint16_t n = gs->length;
    uint16_t t = gs->rx_tail;
    uint16_t avail = rx_count(gs);
    uint16_t want = (uint16_t)(n - gs->got);
    if (avail > want) avail = want;
    if (n <= cap) {
        uint16_t first = (uint16_t)(GS1500M_RX_RING - t);
        if (first > avail) first = avail;
        memcpy(buf + gs->got, &gs->rx[t], first);
        memcpy(buf + gs->got + first, &gs->rx[0], (size_t)(avail - first));
    }
    t = (uint16_t)(t + avail);
    if (t >= GS1500M_RX_RING) t = (uint16_t)(t - GS1500M_RX_RING);
    RING_BARRIER();
    gs->rx_tail = t;
    gs->got = (uint16_t)(gs->got + avail);
    if (gs->got < n) return 0;
    gs->parse = P_IDLE;
    gs->got = 0;
    if (n > cap) {
        gs->stats.too_long++;
        return -1;
    }
    if (from != NULL) {
        if (gs->udp_server && gs->sender_known) *from = gs->sender;
        else if (!gs->udp_server && gs->cid >= 0) {
            /* `ESC Z`: a reply on a client connection, from that connection's destination */
            memset(from, 0, sizeof *from);
            for (int i = 0; i < GS1500M_PEERS; i++)
                if (gs->peers[i].used && gs->peers[i].cid == gs->cid) *from = gs->peers[i].to;
        } else memset(from, 0, sizeof *from);
    }
    gs->stats.datagrams_in++;
    return (int)n;
}

/* Runs the parser over what has arrived. With `deliver` it hands out the next datagram (or reports a loss); without
 * it, it stops in front of a datagram's data and leaves it (and any loss report) for gs1500m_recv, so the module's
 * answers and notices are read even while the program is not receiving. */
static int parse(gs1500m_t *gs, uint32_t now, bool deliver, fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    /* Bounded: each turn consumes a byte or hands out a datagram, and the ring holds fewer than 2^16 bytes. */
    for (;;) {
        if (deliver && gs->garbage_run > 0 && gs->parse != P_SKIP) {
            /* A run of garbage ended where an item began: (at least) one datagram was lost there. */
            gs->garbage_run = 0;
            return -2;
        }
        if (gs->parse == P_PAYLOAD) {
            if (now - gs->payload_since >= GS1500M_PAYLOAD_MS && gs->got + rx_count(gs) < gs->length) {
                /* The data never came: the header was false. Its bytes and the data copied out so far are garbage;
                 * what is still in the ring is read anew. */
                gs->stats.payload_timeouts++;
                garbage(gs, (uint32_t)gs->consumed + gs->got);
                gs->got = 0;
                gs->parse = P_IDLE;
                continue;
            }
            /* Nothing is copied while a datagram goes out: the caller's buffer may be the one being sent. */
            if (!deliver || gs->tx_data != NULL || rx_count(gs) == 0) return 0;
            RING_BARRIER();
            int r = take_payload(gs, from, buf, cap);
            if (r == 0) return 0;
            return r;
        }
        uint16_t t = gs->rx_tail;
        if (t == gs->rx_head) return 0;
        RING_BARRIER();
        uint8_t b = gs->rx[t];
        gs->rx_tail = ring_next(t, GS1500M_RX_RING);
        step_byte(gs, b, now);
    }
}

int gs1500m_recv(gs1500m_t *gs, uint32_t now, fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    gs1500m_tick(gs, now);
    return parse(gs, now, true, from, buf, cap);
}

int gs1500m_send(gs1500m_t *gs, uint32_t now, const fr_endpoint_t *to, const uint8_t *data, size_t len) {
    gs1500m_tick(gs, now);
    if (gs->state != GS1500M_READY || len == 0 || len > GS1500M_MAX_DATAGRAM) {
        gs->stats.send_busy++;
        return -1;
    }
    int slot = -1, free_slot = -1;
    for (int i = 0; i < GS1500M_PEERS; i++) {
        gs1500m_peer_t *p = &gs->peers[i];
        if (p->used && p->to.port == to->port && memcmp(p->to.ip, to->ip, 4) == 0) slot = i;
        else if (!p->used && free_slot < 0) free_slot = i;
    }
    if (slot < 0) {
        /* A new destination: ask the module for a connection (one at a time); this datagram is not sent. With
         * every slot taken the datagram is refused: connections are closed only by a new start-up, so the module's
         * 16 are never used up. */
        if (!gs->waiting && free_slot > 0) {
            char text[40];
            size_t n = put_endpoint(text, put_str(text, 0, "AT+NCUDP="), to);
            if (command(gs, text, n, now)) {
                gs->peers[free_slot].to = *to;
                gs->peers[free_slot].used = true;
                gs->peers[free_slot].cid = -1;
                gs->opening = (int8_t)free_slot;
            }
        }
        gs->stats.send_busy++;
        return -1;
    }
    gs1500m_peer_t *p = &gs->peers[slot];
    bool copy = len <= GS1500M_TX_COPY_MAX;
    if (p->cid < 0 || (copy ? tx_free(gs) < len + 7u : tx_free(gs) < 7u || gs->tx_data != NULL)) {
        gs->stats.send_busy++;
        return -1;
    }
    uint8_t header[7];
    header[0] = ESC;
    header[1] = 'Z';
    header[2] = (uint8_t)"0123456789abcdef"[p->cid & 0xF];
    header[3] = (uint8_t)('0' + len / 1000u);
    header[4] = (uint8_t)('0' + len / 100u % 10u);
    header[5] = (uint8_t)('0' + len / 10u % 10u);
    header[6] = (uint8_t)('0' + len % 10u);
    /* Header and data as one publication, so the UART never sends a header without its data. */
    uint16_t head = tx_copy(gs, gs->tx_head, header, sizeof header);
    if (copy) {
        head = tx_copy(gs, head, data, len);
    } else {
        gs->tx_data_at = head;
        gs->tx_data_len = (uint16_t)len;
        gs->tx_data_pos = 0;
        RING_BARRIER();
        gs->tx_data = data;
    }
    RING_BARRIER();
    gs->tx_head = head;
    gs->stats.datagrams_out++;
    return 0;
}

bool gs1500m_rx_ready(const gs1500m_t *gs) {
    return rx_count(gs) > 0 && (gs->parse != P_PAYLOAD || gs->tx_data == NULL);
}

bool gs1500m_link_up(const gs1500m_t *gs) { return gs->state == GS1500M_READY; }

gs1500m_state_t gs1500m_state(const gs1500m_t *gs) { return gs->state; }

const gs1500m_stats_t *gs1500m_stats(const gs1500m_t *gs) { return &gs->stats; }
