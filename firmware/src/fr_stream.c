/* firmware/src/fr_stream.c: the robot's endpoint of the secure stream (docs/protocol.md section 11): 2-byte
 * header, cumulative ACKs, stop-and-wait at FR_STREAM_WINDOW 1 and selective repeat above it, adaptive RTO
 * (RFC 6298 with Karn's rule), fast retransmit and partial ACKs (W > 1), one idle ACK, skip notices honoured.
 * The robot's own payloads carry no deadline, so it never sends a skip notice: byte 0 of its pure ACKs is its
 * last acknowledged number. Memory: FR_STREAM_QUEUE send slots (the window and any payloads waiting for it:
 * fr_stream_send refuses a payload when all are taken) and FR_STREAM_REORDER reorder slots (W > 1), all static.
 *
 * Flow control: a data segment that would be delivered while every send slot is taken is not accepted (neither
 * delivered nor acknowledged, counted as stream_backpressure), because the program's answer to it would have
 * nowhere to go; the peer sends it again after its timeout, when a slot has been freed. */
#include <string.h>
#include "fr_internal.h"

#define M (FR_STREAM_MAX_SEQ + 1)
#define W FR_STREAM_WINDOW

/** A payload this side sent and the peer has not acknowledged yet. */
typedef struct {
    bool used;
    uint8_t seq;
    uint8_t sends;           /* transmissions so far */
    uint32_t first_sent, last_sent;
    uint32_t last_serial;    /* transmission counter at its latest transmission: orders sends within one ms */
    uint16_t len;
    uint8_t data[2 + FR_STREAM_PAYLOAD_MAX]; /* the segment: header bytes rewritten at each transmission */
} tx_slot_t;

/** Bytes of a reorder slot: none are needed at W = 1, where only the expected segment is accepted. */
#define RX_PAYLOAD (FR_STREAM_WINDOW > 1 ? FR_STREAM_PAYLOAD_MAX : 1)

/** A segment received ahead of the next expected one (W > 1). */
typedef struct {
    bool used;
    uint8_t seq;
    uint16_t len;
    uint8_t data[RX_PAYLOAD];
} rx_slot_t;

/** Reorder slots: a segment d ahead of the expected one (1 <= d <= W - 1) is kept while one is free, or in place
 *  of a kept one farther ahead (the nearest fill the gap first). */
#define RX_SLOTS (W > 1 ? FR_STREAM_REORDER : 1)
#define Q FR_STREAM_QUEUE

static tx_slot_t tx[Q];
static rx_slot_t rx[RX_SLOTS];
/** When each sequence number was last sent again (a retransmission), for the sequence-reuse rule (11.8). */
static uint32_t resent_at[M];
static bool resent[M];

static struct {
    uint8_t last_acked;     /* the peer's last ACK of our numbers */
    uint8_t next;           /* our next sequence number to transmit for the first time */
    uint8_t assign;         /* the number the next queued payload gets */
    uint8_t last_in_order;  /* the last number received in order from the peer */
    bool timer;
    uint32_t rtx_at;
    uint32_t rto, srtt, rttvar;
    bool has_sample;
    uint8_t dup_acks;
    bool recovery;
    uint8_t recover;        /* newest number sent when recovery began */
    bool fast_done;         /* fast retransmit used in this recovery */
    uint8_t ahead;          /* segments that can still cause duplicate ACKs after a resend */
    uint8_t dup_since_rtx;
    uint32_t serial;        /* transmissions so far */
    uint32_t covered_serial; /* the latest transmission among the segments the last advancing ACK covered */
    uint32_t last_transmit;
    bool idle_ack_owed;
    bool sent_data;         /* a data segment went out while a received segment was handled */
} st;

/** The distance from b forward to a, modulo M (protocol.md 11.2). */
static uint8_t dist(uint8_t a, uint8_t b) { return (uint8_t)((a + M - b) % M); }
/** The sequence number after a. */
static uint8_t inc(uint8_t a) { return (uint8_t)((a + 1) % M); }
/** Segments sent and not yet acknowledged. */
static uint8_t in_flight(void) { return dist(st.next, inc(st.last_acked)); }

void fr_stream_reset(void) {
    memset(resent, 0, sizeof resent);
    memset(tx, 0, sizeof tx);
    memset(rx, 0, sizeof rx);
    memset(&st, 0, sizeof st);
    st.last_acked = FR_STREAM_MAX_SEQ;
    st.last_in_order = FR_STREAM_MAX_SEQ;
    st.rto = FR_STREAM_RTO_INITIAL_MS;
}

size_t fr_stream_pending(void) {
    size_t n = 0;
    for (int k = 0; k < Q; k++) n += tx[k].used;
    return n;
}

/** The send slot holding sequence number `seq`, or NULL. */
static tx_slot_t *slot_of(uint8_t seq) {
    for (int k = 0; k < Q; k++) if (tx[k].used && tx[k].seq == seq) return &tx[k];
    return NULL;
}

/** Send slots not taken. */
static size_t free_slots(void) { return (size_t)Q - fr_stream_pending(); }

/** The sequence-reuse rule (11.8): segment m waits while m - (M - W), the last segment with the number the peer
 *  would take m + W for, was sent again within the last smoothed round trip; `*until` gets when it may go. */
static bool reuse_blocked(uint8_t seq, uint32_t now, uint32_t *until) {
    uint8_t old = (uint8_t)((seq + W) % M);
    uint32_t rtt = st.has_sample ? st.srtt : FR_STREAM_RTO_MIN_MS;
    if (!resent[old] || now - resent_at[old] >= rtt) return false;
    *until = resent_at[old] + rtt;
    return true;
}

/** Sends (or sends again) one data segment with the current ACK byte. */
static void transmit(tx_slot_t *s, uint32_t now) {
    if (s->sends >= 1) {
        resent[s->seq] = true;
        resent_at[s->seq] = now;
    }
    s->data[0] = s->seq;
    s->data[1] = st.last_in_order; /* every data segment acknowledges too */
    s->sends = (uint8_t)(s->sends < 255 ? s->sends + 1 : 255);
    if (s->sends == 1) s->first_sent = now;
    s->last_sent = now;
    s->last_serial = ++st.serial;
    st.last_transmit = now;
    st.sent_data = true;
    (void)fr_send_raw(&fr_state.gateway, s->data, (size_t)s->len + 2u);
}

/** Sends a pure ACK: byte 0 our last acknowledged number (no deadlines, so never a skip notice). */
static void pure_ack(uint32_t now) {
    uint8_t seg[2] = {st.last_acked, st.last_in_order};
    st.last_transmit = now;
    (void)fr_send_raw(&fr_state.gateway, seg, 2);
}

/** The RTO from the round-trip estimate (the initial RTO before the first sample), within its bounds. */
static uint32_t estimate_rto(void) {
    if (!st.has_sample) return FR_STREAM_RTO_INITIAL_MS;
    uint32_t var4 = 4u * st.rttvar;
    uint32_t rto = st.srtt + (var4 > 1u ? var4 : 1u);
    if (rto < FR_STREAM_RTO_MIN_MS) rto = FR_STREAM_RTO_MIN_MS;
    if (rto > FR_STREAM_RTO_MAX_MS) rto = FR_STREAM_RTO_MAX_MS;
    return rto;
}

/** Resends the oldest unacknowledged segment and starts (or continues) a recovery. */
static void resend_oldest(uint32_t now) {
    if (!fr_port_frame_free()) return; /* a segment may still go out from its slot: the timer resends it later */
    tx_slot_t *s = slot_of(inc(st.last_acked));
    uint32_t until;
    if (s == NULL) return;
    if (reuse_blocked(s->seq, now, &until)) {
        st.timer = true;
        st.rtx_at = until; /* it goes when the rule allows */
        return;
    }
    if (!st.recovery) {
        st.recovery = true;
        st.recover = (uint8_t)((st.next + M - 1) % M);
        st.fast_done = false;
    }
    /* Segments that can still cause a duplicate ACK while the peer waits for this one (11.5, lost resend): those
     * in flight sent after the latest transmission among the segments the last advancing ACK covered. */
    st.ahead = 0;
    for (int k = 0; k < Q; k++)
        if (tx[k].used && &tx[k] != s && tx[k].sends > 0 && tx[k].last_serial > st.covered_serial) st.ahead++;
    st.dup_since_rtx = 0;
    transmit(s, now);
    st.timer = true;
    st.rtx_at = now + st.rto;
}

/** Sends queued payloads for the first time while the window has room. */
static void send_queued(uint32_t now) {
    while (in_flight() < W && fr_port_frame_free()) { /* a port sending from a slot takes one at a time */
        tx_slot_t *s = slot_of(st.next);
        uint32_t until;
        if (s == NULL || reuse_blocked(s->seq, now, &until)) return; /* fr_stream_poll tries again */
        st.next = inc(st.next);
        if (!st.timer) {
            st.timer = true;
            st.rtx_at = now + st.rto;
        }
        transmit(s, now);
    }
}

bool fr_stream_send(const uint8_t *data, size_t len) {
    if (!fr_state.started) return false;
    if (len < 1 || len > FR_STREAM_PAYLOAD_MAX) return false;
    tx_slot_t *s = NULL;
    for (int k = 0; k < Q && s == NULL; k++) if (!tx[k].used) s = &tx[k];
    if (s == NULL) return false;
    if (!fr_port_frame_free()) return false; /* a freed slot may still be going out as a resend */
    s->used = true;
    s->seq = st.assign;
    s->sends = 0;
    s->len = (uint16_t)len;
    memcpy(s->data + 2, data, len);
    st.assign = inc(st.assign);
    send_queued(fr_uptime_ms());
    return true;
}

/** Acts on the ACK byte `a`; false when it acknowledges something never sent (misbehaving). */
static bool on_ack(uint8_t a, bool pure, uint32_t now) {
    uint8_t d = dist(a, st.last_acked), f = in_flight();
    if (d > f) {
        return dist(st.last_acked, a) <= W; /* stale (overtaken): disregarded; else misbehaving */
    }
    if (d == 0) {
        if (pure && f > 0) {
            st.dup_acks++;
            st.dup_since_rtx++;
            if (W > 1 && !st.fast_done && st.dup_acks >= 2) {
                resend_oldest(now);
                st.fast_done = true;
            } else if (W > 1 && st.recovery && st.dup_since_rtx >= st.ahead + 2u) {
                resend_oldest(now); /* the resend itself was lost */
            }
        }
        return true;
    }
    /* d > 0: segments base .. a are acknowledged. Karn: a sample only from the newest, sent once, and only when no
     * other covered segment was sent after its first transmission. */
    tx_slot_t *newest = slot_of(a);
    bool clean = newest != NULL && newest->sends == 1;
    uint8_t old_base = inc(st.last_acked);
    for (uint8_t k = 0, seq = old_base; k < d; k++, seq = inc(seq)) {
        tx_slot_t *s = slot_of(seq);
        if (s == NULL) continue;
        if (newest && s != newest && (int32_t)(s->last_sent - newest->first_sent) > 0) clean = false;
        if (s->last_serial > st.covered_serial) st.covered_serial = s->last_serial;
        s->used = false;
    }
    if (clean) {
        uint32_t r = now - newest->first_sent;
        if (!st.has_sample) {
            st.srtt = r;
            st.rttvar = r / 2u;
            st.has_sample = true;
        } else {
            uint32_t diff = st.srtt > r ? st.srtt - r : r - st.srtt;
            st.rttvar = (3u * st.rttvar + diff) / 4u;
            st.srtt = (7u * st.srtt + r) / 8u;
        }
        st.rto = estimate_rto();
    } else {
        uint32_t twice = 2u * estimate_rto();
        if (twice > FR_STREAM_RTO_MAX_MS) twice = FR_STREAM_RTO_MAX_MS;
        if (st.rto > twice) st.rto = twice;
    }
    bool covers_recover = dist(st.recover, old_base) < d;
    st.last_acked = a;
    st.dup_acks = 0;
    if (in_flight() == 0) {
        st.timer = false;
        st.recovery = false;
    } else {
        st.timer = true;
        st.rtx_at = now + st.rto;
        if (st.recovery && !covers_recover) resend_oldest(now); /* partial ACK (NewReno) */
        else if (st.recovery) st.recovery = false;
    }
    send_queued(now);
    return true;
}

/** Hands a payload received in order to the program, or to the frame handler when it is an FU-Remote frame. */
static void deliver(const uint8_t *data, size_t len) {
    if (len >= 2 && data[0] == 0 && data[1] == 42) {
        fr_handle_frame(&fr_state.gateway, data, len, true);
    } else if (fr_state.settings.callbacks.stream) {
        fr_state.settings.callbacks.stream(data, len, fr_state.settings.callbacks.ctx);
    }
}

/** Delivers the kept segments that follow the last in-order one. */
static void deliver_kept(void) {
    for (bool found = true; found;) {
        found = false;
        for (int k = 0; k < RX_SLOTS; k++) {
            if (rx[k].used && rx[k].seq == inc(st.last_in_order) && free_slots() > 0) {
                st.last_in_order = rx[k].seq;
                rx[k].used = false;
                deliver(rx[k].data, rx[k].len);
                found = true;
            }
        }
    }
}

void fr_stream_receive(const uint8_t *data, size_t len) {
    uint32_t now = fr_uptime_ms();
    if (len < 2 || len > FR_DATAGRAM_MAX || data[0] > FR_STREAM_MAX_SEQ || data[1] > FR_STREAM_MAX_SEQ) {
        fr_state.stats.stream_misbehaving++;
        return;
    }
    bool pure = len == 2;
    uint8_t s = data[0];
    uint8_t expected = inc(st.last_in_order);
    uint8_t d = dist(s, expected);
    if (!pure && d > W - 1 && d < M - W) {
        fr_state.stats.stream_misbehaving++; /* data neither new nor a duplicate */
        return;
    }
    /* the ACK byte first, so answers sent while delivering see the freed window */
    uint8_t a_d = dist(data[1], st.last_acked);
    if (a_d > in_flight() && dist(st.last_acked, data[1]) > W) {
        fr_state.stats.stream_misbehaving++;
        return;
    }
    (void)on_ack(data[1], pure, now);
    st.sent_data = false;
    if (pure) {
        if (s == expected) {
            /* a skip notice (11.7): the peer gave up on `expected` */
            bool kept = false;
            for (int k = 0; k < RX_SLOTS; k++) {
                if (rx[k].used && rx[k].seq == s) {
                    kept = true;
                    st.last_in_order = s;
                    rx[k].used = false;
                    deliver(rx[k].data, rx[k].len);
                }
            }
            if (!kept) st.last_in_order = s;
            deliver_kept();
            st.idle_ack_owed = true;
            if (!st.sent_data) pure_ack(now);
        }
        return;
    }
    if (d == 0 && free_slots() == 0) {
        fr_state.stats.stream_backpressure++; /* its answer would have nowhere to go: the peer resends it */
        return;
    }
    if (d <= W - 1) {
        if (d == 0) {
            st.last_in_order = s;
            deliver(data + 2, len - 2);
            deliver_kept();
        } else {
            bool have = false;
            for (int k = 0; k < RX_SLOTS; k++) have = have || (rx[k].used && rx[k].seq == s);
            /* a free slot, else the one kept farthest ahead when this segment is nearer */
            int take = -1;
            for (int k = 0; k < RX_SLOTS && !have; k++) {
                if (!rx[k].used) { take = k; break; }
                if (take < 0 || dist(rx[k].seq, expected) > dist(rx[take].seq, expected)) take = k;
            }
            if (take >= 0 && rx[take].used && dist(rx[take].seq, expected) < d) take = -1;
            if (take >= 0 && len - 2 <= RX_PAYLOAD) {
                rx[take].used = true;
                rx[take].seq = s;
                rx[take].len = (uint16_t)(len - 2);
                memcpy(rx[take].data, data + 2, len - 2);
            }
        }
    }
    /* new or duplicate: answered at once, piggybacked if data went out meanwhile */
    st.idle_ack_owed = true;
    if (!st.sent_data) pure_ack(now);
}

void fr_stream_poll(void) {
    uint32_t now = fr_uptime_ms();
    send_queued(now);
    uint8_t before = st.last_in_order;
    deliver_kept(); /* kept segments held back while every send slot was taken */
    if (st.last_in_order != before) {
        st.idle_ack_owed = true;
        pure_ack(now);
    }
    if (st.timer && (int32_t)(now - st.rtx_at) >= 0 && fr_port_frame_free()) {
        tx_slot_t *oldest = slot_of(inc(st.last_acked));
        uint32_t until;
        if (oldest != NULL && reuse_blocked(oldest->seq, now, &until)) {
            st.rtx_at = until; /* held back by the sequence-reuse rule: no timeout yet */
        } else {
            st.rto = 2u * st.rto > FR_STREAM_RTO_MAX_MS ? FR_STREAM_RTO_MAX_MS : 2u * st.rto;
            st.recovery = false; /* a timeout starts a new recovery */
            resend_oldest(now);
        }
    }
    if (st.idle_ack_owed && in_flight() == 0 && now - st.last_transmit >= FR_STREAM_IDLE_ACK_MS) {
        st.idle_ack_owed = false;
        pure_ack(now);
    }
}
