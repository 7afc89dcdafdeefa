/* firmware/src/fr_sha256.c: SHA-256 (FIPS 180-4), HMAC-SHA-256 (RFC 2104) and HKDF-SHA256 (RFC 5869) for signed frames
 * (docs/protocol.md 6.7). Written here rather than taken from a package: the registries' SHA-256 libraries for
 * C either allocate, pull in a whole crypto suite (mbedTLS, wolfSSL: tens of KB of flash and a configuration
 * system of their own) or come as single files meant to be copied into the tree, which this project does not do
 * with third-party source. This one is small, uses no heap and keeps its state on the caller's stack. */
#include <string.h>
#include "fr_internal.h"

static const uint32_t k256[64] = {
    0x428a2f98u, 0x71374491u, 0xb5c0fbcfu, 0xe9b5dba5u, 0x3956c25bu, 0x59f111f1u, 0x923f82a4u, 0xab1c5ed5u,
    0xd807aa98u, 0x12835b01u, 0x243185beu, 0x550c7dc3u, 0x72be5d74u, 0x80deb1feu, 0x9bdc06a7u, 0xc19bf174u,
    0xe49b69c1u, 0xefbe4786u, 0x0fc19dc6u, 0x240ca1ccu, 0x2de92c6fu, 0x4a7484aau, 0x5cb0a9dcu, 0x76f988dau,
    0x983e5152u, 0xa831c66du, 0xb00327c8u, 0xbf597fc7u, 0xc6e00bf3u, 0xd5a79147u, 0x06ca6351u, 0x14292967u,
    0x27b70a85u, 0x2e1b2138u, 0x4d2c6dfcu, 0x53380d13u, 0x650a7354u, 0x766a0abbu, 0x81c2c92eu, 0x92722c85u,
    0xa2bfe8a1u, 0xa81a664bu, 0xc24b8b70u, 0xc76c51a3u, 0xd192e819u, 0xd6990624u, 0xf40e3585u, 0x106aa070u,
    0x19a4c116u, 0x1e376c08u, 0x2748774cu, 0x34b0bcb5u, 0x391c0cb3u, 0x4ed8aa4au, 0x5b9cca4fu, 0x682e6ff3u,
    0x748f82eeu, 0x78a5636fu, 0x84c87814u, 0x8cc70208u, 0x90befffau, 0xa4506cebu, 0xbef9a3f7u, 0xc67178f2u};

/** Rotates right by n bits (one operand of the next instruction on a Cortex-M3). */
#define ROR(x, n) ((x) >> (n) | (x) << (32 - (n)))
#define S0(a) (ROR(a, 2) ^ ROR(a, 13) ^ ROR(a, 22))
#define S1(e) (ROR(e, 6) ^ ROR(e, 11) ^ ROR(e, 25))
#define CH(e, f, g) ((g) ^ ((e) & ((f) ^ (g))))
#define MAJ(a, b, c) (((a) & (b)) | ((c) & ((a) | (b))))

/** One 64-byte block into the state: one round per turn of the loop, the schedule rolled in a 16-word window, so
 *  the code and the stack stay small (a signed frame hashes three blocks; docs/firmware.md, "Footprint"). */
static void compress(uint32_t h[8], const uint8_t block[64]) {
    uint32_t w[16], a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (int i = 0; i < 64; i++) {
        uint32_t wi;
        if (i < 16) {
            const uint8_t *p = block + 4 * i;
            wi = (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
        } else {
            uint32_t w15 = w[(i - 15) & 15], w2 = w[(i - 2) & 15];
            wi = w[i & 15] + (ROR(w15, 7) ^ ROR(w15, 18) ^ (w15 >> 3)) + w[(i - 7) & 15] +
                 (ROR(w2, 17) ^ ROR(w2, 19) ^ (w2 >> 10));
        }
        w[i & 15] = wi;
        uint32_t t1 = hh + S1(e) + CH(e, f, g) + k256[i] + wi;
        uint32_t t2 = S0(a) + MAJ(a, b, c);
        hh = g; g = f; f = e; e = d + t1;
        d = c; c = b; b = a; a = t1 + t2;
    }
    h[0] += a; h[1] += b; h[2] += c; h[3] += d; h[4] += e; h[5] += f; h[6] += g; h[7] += hh;
}

void fr_sha256_init(fr_sha256_t *s) {
    static const uint32_t iv[8] = {0x6a09e667u, 0xbb67ae85u, 0x3c6ef372u, 0xa54ff53au,
                                   0x510e527fu, 0x9b05688cu, 0x1f83d9abu, 0x5be0cd19u};
    memcpy(s->h, iv, sizeof iv);
    s->used = 0;
    s->total = 0;
}

void fr_sha256_update(fr_sha256_t *s, const uint8_t *data, size_t len) {
    s->total += len;
    while (len > 0) {
        size_t n = 64 - s->used < len ? 64 - s->used : len;
        memcpy(s->block + s->used, data, n);
        s->used += n;
        data += n;
        len -= n;
        if (s->used == 64) {
            compress(s->h, s->block);
            s->used = 0;
        }
    }
}

void fr_sha256_final(fr_sha256_t *s, uint8_t out[32]) {
    uint64_t bits = s->total * 8u;
    /* Padding written into the block in place: 0x80, zeros up to byte 56 (through one more block when the
     * length no longer fits), then the length in bits, big-endian. */
    size_t used = s->used;
    s->block[used++] = 0x80;
    if (used > 56) {
        memset(s->block + used, 0, 64 - used);
        compress(s->h, s->block);
        used = 0;
    }
    memset(s->block + used, 0, 56 - used);
    for (int k = 0; k < 8; k++) s->block[56 + k] = (uint8_t)(bits >> (56 - 8 * k));
    compress(s->h, s->block);
    s->used = 0;
    for (int k = 0; k < 8; k++) {
        out[4 * k] = (uint8_t)(s->h[k] >> 24);
        out[4 * k + 1] = (uint8_t)(s->h[k] >> 16);
        out[4 * k + 2] = (uint8_t)(s->h[k] >> 8);
        out[4 * k + 3] = (uint8_t)s->h[k];
    }
}

void fr_hmac_key(fr_hmac_key_t *k, const uint8_t *key, size_t key_len) {
    uint8_t k0[64], pad[64];
    fr_sha256_t s;
    memset(k0, 0, sizeof k0);
    if (key_len > 64) {
        fr_sha256_init(&s);
        fr_sha256_update(&s, key, key_len);
        fr_sha256_final(&s, k0);
    } else {
        memcpy(k0, key, key_len);
    }
    for (int i = 0; i < 64; i++) pad[i] = (uint8_t)(k0[i] ^ 0x36);
    fr_sha256_init(&s);
    fr_sha256_update(&s, pad, 64);
    memcpy(k->inner, s.h, sizeof k->inner);
    for (int i = 0; i < 64; i++) pad[i] = (uint8_t)(k0[i] ^ 0x5c);
    fr_sha256_init(&s);
    fr_sha256_update(&s, pad, 64);
    memcpy(k->outer, s.h, sizeof k->outer);
    memset(k0, 0, sizeof k0);
    memset(pad, 0, sizeof pad);
}

/** A running hash that has taken one whole 64-byte block and ended in state `h`. */
static void resume(fr_sha256_t *s, const uint32_t h[8]) {
    memcpy(s->h, h, sizeof s->h);
    s->used = 0;
    s->total = 64;
}

void fr_hmac_with(const fr_hmac_key_t *k, const uint8_t *const *parts, const size_t *lens, size_t count,
                  uint8_t out[32]) {
    fr_sha256_t s;
    resume(&s, k->inner);
    for (size_t i = 0; i < count; i++) fr_sha256_update(&s, parts[i], lens[i]);
    fr_sha256_final(&s, out);
    resume(&s, k->outer);
    fr_sha256_update(&s, out, 32);
    fr_sha256_final(&s, out);
}

void fr_hmac_sha256(const uint8_t *key, size_t key_len, const uint8_t *const *parts, const size_t *lens, size_t count,
                    uint8_t out[32]) {
    fr_hmac_key_t k;
    fr_hmac_key(&k, key, key_len);
    fr_hmac_with(&k, parts, lens, count, out);
}

void fr_hkdf_sha256(const uint8_t *salt, size_t salt_len, const uint8_t *ikm, size_t ikm_len, const uint8_t *info,
                    size_t info_len, uint8_t *out, size_t out_len) {
    uint8_t prk[32], t[32];
    const uint8_t *extract[1] = {ikm};
    const size_t extract_len[1] = {ikm_len};
    fr_hmac_sha256(salt, salt_len, extract, extract_len, 1, prk);
    size_t done = 0, t_len = 0;
    for (uint8_t block = 1; done < out_len && block != 0; block++) {
        /* T(n) = HMAC(PRK, T(n-1) | info | n), T(0) empty */
        const uint8_t *parts[3] = {t, info, &block};
        const size_t lens[3] = {t_len, info_len, 1};
        fr_hmac_sha256(prk, sizeof prk, parts, lens, 3, t);
        t_len = sizeof t;
        size_t n = out_len - done < sizeof t ? out_len - done : sizeof t;
        memcpy(out + done, t, n);
        done += n;
    }
    memset(prk, 0, sizeof prk);
    memset(t, 0, sizeof t);
}
