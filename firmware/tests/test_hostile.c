/* firmware/tests/test_hostile.c: bad input from the network never stops the library. Thousands of datagrams
 * made by mutating valid frames, GameController packets and segments (seeded, so a failure can be repeated)
 * pass through fr_poll; afterwards the library still answers a valid request and still sends keep-alives. Run it
 * under -fsanitize=address,undefined to see memory errors (docs/firmware.md). */
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "../src/fr_internal.h"

static const fr_endpoint_t gateway = {{192, 168, 1, 10}, 11011};
static uint32_t rng = 12345;

static uint32_t next(void) {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

static fr_rpc_status_t ok(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)err; (void)cap; (void)ctx;
    if (c->count == 1 && c->params[0].kind == FR_VALUE_STRING && later >= 0 && c->params[0].u.s[0] == 'L') {
        fr_rpc_answer(later, NULL, "busy: never");
        return FR_RPC_LATER;
    }
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

static void on_stream(const uint8_t *data, size_t len, void *ctx) {
    (void)ctx;
    (void)fr_stream_send(data, len);
}

static const char *const seeds[] = {
    /* 9.4, 9.6, 9.8, 9.10: requests and commands */
    "00 2A 00 00 00 00 00 00 00 00 00 2B 08 01 B2 BC 03 25 0A 06 6D 6F 74 69 6F 6E 12 04 77 61 6C 6B"
    "1A 05 1D CD CC 4C 3E 1A 05 1D 00 00 00 00 1A 05 1D 00 00 00 3F 78 07",
    "00 2A 00 00 00 00 00 00 00 00 00 1A 08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 08",
    "00 2A 00 00 00 00 00 00 00 00 00 08 08 01 EA BB 03 02 08 01",
    "00 2A 00 00 00 00 00 00 00 00 00 10 08 01 EA BB 03 0A 1A 08 0A 06 68 61 76 69 6D 6F",
    /* a request with nested arrays, a string and groups */
    "00 2A 00 00 00 08 01 B2 BC 03 1F 0A 06 6D 6F 74 69 6F 6E 12 01 78 1A 0C 32 0A 32 08 32 06 0A 01 4C 28 01 1A 02"
    "22 00 C3 02 C4 02 78 05",
    /* a signed-looking frame */
    "00 2A 00 00 00 00 00 29 08 01 BA 01 0D 10 01 62 09 41 67 65 6E 74 54 65 73 74 FA C1 03 13"
    "09 05 00 00 00 03 00 00 00 12 08 01 68 92 55 59 00 26 64",
    /* segments */
    "00 14 00 2A 00 00 00 00 00 1A 08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 09",
    "01 14 41 42",
    "14 14",
    "00 14",
    /* a GameController header */
    "52 47 6D 65 08 04 06 03 01 01 00 00 FF FF 4B 02 00 00",
};

int main(void) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.development = true; /* unsigned frames: the signed path has its own tests (test_protocol, test_trust) */
    s.team_number = 12;
    s.player_number = 3;
    s.gateway = gateway;
    s.callbacks.stream = on_stream;
    fake_now = 0;
    fr_init(&s);
    fr_rpc_register("motion", "walk", ok, NULL);
    fr_rpc_register("motion", "x", ok, NULL);
    fr_rpc_register("heartbeat", "probe", ok, NULL);
    fr_option_add("havimo.regions", FR_OPT_HAVIMO_REGIONS, NULL);
    unsigned char base[1400], d[1400];
    int floods = 0;
    size_t nseeds = sizeof seeds / sizeof seeds[0];
    for (int round = 0; round < 40000; round++) {
        size_t n = hex(seeds[next() % nseeds], base);
        memcpy(d, base, n);
        if (next() % 16 == 0) {
            /* a GameController packet of a supported size, random contents */
            n = (size_t[]){116, 158, 198, 688}[next() % 4];
            for (size_t k = 0; k < n; k++) d[k] = (uint8_t)next();
            memcpy(d, "RGme", 4);
            d[4] = (uint8_t)(next() % 2 ? (n == 116 ? 7 : n == 158 ? 8 : n == 198 ? 19 : 12) : next());
        }
        int edits = 1 + (int)(next() % 4);
        for (int e = 0; e < edits; e++) {
            uint32_t kind = next() % 4;
            if (kind == 0 && n > 0) d[next() % n] = (uint8_t)next();              /* change a byte */
            else if (kind == 1 && n > 0) n = next() % n;                           /* cut */
            else if (kind == 2 && n < sizeof d - 8) {                              /* append */
                for (int k = 0; k < 8; k++) d[n++] = (uint8_t)next();
            } else if (n > 12) d[8 + next() % 4] = (uint8_t)next();                /* the length field */
        }
        fake_receive(&gateway, d, n);
        fake_now += next() % 3 == 0 ? 50 : 0;
        fake_clear_sent();
        fr_poll();
        if (fake_sent_count > 16) floods++; /* one datagram in, a bounded answer out */
    }
    CHECK(floods == 0);
    /* still alive: a valid request is answered, the keep-alive still goes out */
    fake_now += 10000;
    fake_clear_sent();
    unsigned char req[64];
    size_t n = hex(seeds[1], req);
    fake_receive(&gateway, req, n);
    fr_poll();
    int answered = 0, keepalive = 0;
    for (size_t k = 0; k < fake_sent_count; k++) {
        const unsigned char *p = fake_sent[k].data;
        if (fake_sent[k].len > 18 && p[14] == 0xBA && p[15] == 0xBC) answered = 1;
        if (fake_sent[k].len > 18 && p[14] == 0xBA && p[15] == 0x01) keepalive = 1;
    }
    CHECK(answered && keepalive);
    const fr_stats_t *st = fr_stats();
    CHECK(st->received >= 35000); /* zero-length datagrams read as "none waiting" */
    CHECK(st->bad_frame + st->bad_protobuf + st->stream_misbehaving + st->gc_ignored > 1000);
    printf("hostile: %u received, %u bad frame, %u bad protobuf, %u stream misbehaving, %u gc ignored\n", st->received,
           st->bad_frame, st->bad_protobuf, st->stream_misbehaving, st->gc_ignored);

    /* The same with signing on: mutated signed frames (and the seeds above) walk the signature parser, and a valid
     * signed request is still answered afterwards. */
    uint8_t key[32];
    for (int k = 0; k < 32; k++) key[k] = (uint8_t)(k * 7);
    s.development = false;
    s.signing_key = key;
    s.signing_key_len = sizeof key;
    fake_now = 0;
    CHECK(fr_init(&s) == FR_INIT_OK);
    fr_rpc_register("heartbeat", "probe", ok, NULL);
    uint64_t ts = 1;
    floods = 0;
    for (int round = 0; round < 20000; round++) {
        if (next() % 2 == 0) {
            /* a validly signed request for this robot, then mutated */
            n = hex("08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 08", d + 12);
            uint8_t *p = d + 12 + n;
            *p++ = 0xFA; *p++ = 0xC1; *p++ = 0x03; *p++ = 19; *p++ = 0x09;
            ts++;
            for (int k = 0; k < 8; k++) *p++ = (uint8_t)(ts >> (8 * k));
            *p++ = 0x12; *p++ = 8;
            fr_sign_mac(key, sizeof key, 2, 1, fr_epoch(), ts, d + 12, n, p);
            n += 23;
            fr_frame_header(d + 12, n, FR_FORM_LEGACY);
            n += 12;
        } else {
            n = hex(seeds[next() % nseeds], d);
        }
        int edits = (int)(next() % 3);
        for (int e = 0; e < edits; e++) {
            uint32_t kind = next() % 3;
            if (kind == 0 && n > 0) d[next() % n] = (uint8_t)next();
            else if (kind == 1 && n > 0) n = next() % n;
            else if (n < sizeof d - 8) for (int k = 0; k < 8; k++) d[n++] = (uint8_t)next();
        }
        fake_receive(&gateway, d, n);
        fake_now += next() % 3 == 0 ? 50 : 0;
        fake_clear_sent();
        fr_poll();
        if (fake_sent_count > 16) floods++;
    }
    CHECK(floods == 0);
    st = fr_stats();
    CHECK(st->bad_signature + st->malformed_signature + st->unsigned_frames + st->signature_not_last > 1000);
    /* some unmutated signed requests were answered, and one more still is */
    fake_now += 10000;
    fake_clear_sent();
    n = hex("08 01 B2 BC 03 14 0A 09 68 65 61 72 74 62 65 61 74 12 05 70 72 6F 62 65 78 08", d + 12);
    uint8_t *p = d + 12 + n;
    *p++ = 0xFA; *p++ = 0xC1; *p++ = 0x03; *p++ = 19; *p++ = 0x09;
    ts += 1000;
    for (int k = 0; k < 8; k++) *p++ = (uint8_t)(ts >> (8 * k));
    *p++ = 0x12; *p++ = 8;
    fr_sign_mac(key, sizeof key, 2, 1, fr_epoch(), ts, d + 12, n, p);
    fr_frame_header(d + 12, n + 23, FR_FORM_LEGACY);
    fake_receive(&gateway, d, n + 35);
    fr_poll();
    answered = 0;
    for (size_t k = 0; k < fake_sent_count; k++)
        if (fake_sent[k].len > 18 && fake_sent[k].data[14] == 0xBA && fake_sent[k].data[15] == 0xBC) answered = 1;
    CHECK(answered);
    printf("hostile, signed: %u bad signature, %u malformed, %u unsigned, %u not last, %u replayed, %u wrong robot\n",
           st->bad_signature, st->malformed_signature, st->unsigned_frames, st->signature_not_last, st->replayed,
           st->wrong_robot);
    return DONE();
}
