/* firmware/src/fr_sign.c: signed frames, version 2 (docs/protocol.md 6.7): the robot key, the MAC over direction,
 * robot id, boot epoch and timestamp, signing every frame the robot sends and checking the gateway's, whose
 * timestamps must rise within the boot epoch (the window lives in RAM: a new epoch changes every MAC). */
#include <string.h>
#include "fr_internal.h"

/** Writes `v` big-endian into `out[0 .. bytes)`. */
static void big_endian(uint64_t v, uint8_t *out, int bytes) {
    for (int k = 0; k < bytes; k++) out[k] = (uint8_t)(v >> (8 * (bytes - 1 - k)));
}

void fr_sign_mac_with(const fr_hmac_key_t *key, uint8_t direction, int32_t robot_id, uint32_t epoch, uint64_t timestamp,
                      const uint8_t *bytes, size_t len, uint8_t mac[8]) {
    static const uint8_t prefix[6] = {'F', 'U', 'S', 'I', 'G', '2'};
    uint8_t head[1 + 4 + 4 + 8], full[32];
    head[0] = direction;
    big_endian((uint32_t)robot_id, head + 1, 4);
    big_endian(epoch, head + 5, 4);
    big_endian(timestamp, head + 9, 8);
    const uint8_t *parts[3] = {prefix, head, bytes};
    const size_t lens[3] = {sizeof prefix, sizeof head, len};
    fr_hmac_with(key, parts, lens, 3, full);
    memcpy(mac, full, 8);
}

void fr_sign_mac(const uint8_t *key, size_t key_len, uint8_t direction, int32_t robot_id, uint32_t epoch,
                 uint64_t timestamp, const uint8_t *bytes, size_t len, uint8_t mac[8]) {
    fr_hmac_key_t k;
    fr_hmac_key(&k, key, key_len);
    fr_sign_mac_with(&k, direction, robot_id, epoch, timestamp, bytes, len, mac);
}

void fr_robot_key(const uint8_t *team_key, size_t team_key_len, int32_t robot_id, uint8_t out[32]) {
    static const uint8_t salt[20] = {'n', 'a', 'o', 'g', 'a', 't', 'e', 'w', 'a', 'y', ' ',
                                     'r', 'o', 'b', 'o', 't', ' ', 'k', 'e', 'y'};
    uint8_t info[10] = {'F', 'U', 'S', 'I', 'G', '2'};
    big_endian((uint32_t)robot_id, info + 6, 4);
    fr_hkdf_sha256(salt, sizeof salt, team_key, team_key_len, info, sizeof info, out, 32);
}

/** The value of one hex digit, or -1. */
static int hex_digit(char c) {
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                                                                                         : -1;
}

fr_key_result_t fr_key_from_hex(const char *hex, uint8_t *out, size_t *len) {
    size_t digits = 0;
    for (const char *c = hex; *c; c++, digits++)
        if (hex_digit(*c) < 0) return FR_KEY_NOT_HEX;
    if (digits % 2 != 0) return FR_KEY_ODD_LENGTH;
    if (digits < 32) return FR_KEY_TOO_SHORT;
    if (digits > 2 * FR_SIGNING_KEY_MAX) return FR_KEY_TOO_LONG;
    for (size_t k = 0; k < digits / 2; k++) out[k] = (uint8_t)(hex_digit(hex[2 * k]) << 4 | hex_digit(hex[2 * k + 1]));
    *len = digits / 2;
    return FR_KEY_OK;
}

const char *fr_key_error_text(fr_key_result_t result) {
    switch (result) {
    case FR_KEY_OK: return "key accepted";
    case FR_KEY_TOO_SHORT: return "signing key too short: it must be 16 to 64 bytes (32 to 128 hex digits)";
    case FR_KEY_TOO_LONG: return "signing key too long: it must be 16 to 64 bytes (32 to 128 hex digits)";
    case FR_KEY_ODD_LENGTH: return "signing key has an odd number of hex digits: two digits per byte";
    case FR_KEY_NOT_HEX: return "signing key has a character that is not a hex digit (0-9, a-f)";
    }
    return "signing key refused";
}

size_t fr_sign_append(uint8_t *payload, size_t len, size_t cap) {
    if (len + FR_SIGNATURE_FIELD_SIZE > cap) return 0;
    if (fr_state.sign_counter == UINT32_MAX) { /* the next timestamp would leave this epoch: no frame at all */
        fr_state.stats.sign_exhausted++;
        return 0;
    }
    uint64_t ts = (uint64_t)fr_state.epoch << 32 | fr_state.sign_counter++;
    uint8_t *p = payload + len;
    /* key of field 7199, wire type 2 (FA C1 03), length 19, then FrameSignature: 09 + fixed64, 12 08 + mac */
    *p++ = 0xFA; *p++ = 0xC1; *p++ = 0x03; *p++ = 19;
    *p++ = 0x09;
    for (int k = 0; k < 8; k++) *p++ = (uint8_t)(ts >> (8 * k));
    *p++ = 0x12; *p++ = 8;
    fr_sign_mac_with(&fr_state.mac_key, 1, fr_state.settings.robot_id, fr_state.epoch, ts, payload, len, p);
    return len + FR_SIGNATURE_FIELD_SIZE;
}

/** Reads a varint at p (< end); its end, or NULL when truncated or longer than 10 bytes. */
static const uint8_t *varint(const uint8_t *p, const uint8_t *end, uint64_t *v) {
    *v = 0;
    for (int shift = 0; p < end && shift < 70; shift += 7) {
        uint8_t b = *p++;
        *v |= (uint64_t)(b & 0x7F) << shift;
        if (!(b & 0x80)) return p;
    }
    return NULL;
}

/** Skips one field's value of `wire` type; NULL when it does not fit (groups are walked by depth). */
static const uint8_t *skip(const uint8_t *p, const uint8_t *end, unsigned wire, uint64_t field, int depth) {
    uint64_t v;
    switch (wire) {
    case 0: return varint(p, end, &v);
    case 1: return end - p >= 8 ? p + 8 : NULL;
    case 5: return end - p >= 4 ? p + 4 : NULL;
    case 2:
        p = varint(p, end, &v);
        return p && v <= (uint64_t)(end - p) ? p + v : NULL;
    case 3:
        if (depth > FR_PB_GROUP_DEPTH) return NULL;
        while (p && p < end) {
            uint64_t key;
            p = varint(p, end, &key);
            if (!p) return NULL;
            if ((key & 7) == 4) return (key >> 3) == field ? p : NULL;
            p = skip(p, end, (unsigned)(key & 7), key >> 3, depth + 1);
        }
        return NULL;
    default: return NULL;
    }
}

int fr_message_robot_id(const uint8_t *payload, size_t len, int32_t *id) {
    const uint8_t *p = payload, *end = payload + len;
    int found = 0;
    while (p < end) {
        uint64_t key, v;
        p = varint(p, end, &key);
        if (!p) return -1;
        if (key == 0x08) {
            p = varint(p, end, &v);
            if (!p) return -1;
            *id = (int32_t)(uint32_t)v; /* an int32 on the wire: negative ones are sign-extended to 64 bits */
            found = 1;
            continue;
        }
        p = skip(p, end, (unsigned)(key & 7), key >> 3, 1);
        if (!p) return -1;
    }
    return found;
}

fr_sig_result_t fr_sign_check(const uint8_t *payload, size_t len, size_t *signed_len) {
    const uint8_t *p = payload, *end = payload + len, *sig = NULL, *sig_value = NULL;
    uint64_t sig_len = 0;
    while (p < end) {
        const uint8_t *field_start = p;
        uint64_t key;
        p = varint(p, end, &key);
        if (!p) return FR_SIG_MALFORMED;
        if (sig) return FR_SIG_NOT_LAST; /* a field after the signature */
        if ((key >> 3) == 7199) {
            if ((key & 7) != 2) return FR_SIG_MALFORMED;
            p = varint(p, end, &sig_len);
            if (!p || sig_len > (uint64_t)(end - p)) return FR_SIG_MALFORMED;
            sig = field_start;
            sig_value = p;
            p += sig_len;
            continue;
        }
        p = skip(p, end, (unsigned)(key & 7), key >> 3, 1);
        if (!p) return FR_SIG_MALFORMED;
    }
    if (!sig) return FR_SIG_UNSIGNED;
    /* FrameSignature: exactly timestamp (09 + 8 bytes) and mac (12 08 + 8 bytes), in either order */
    uint64_t ts = 0;
    const uint8_t *mac = NULL;
    bool has_ts = false;
    const uint8_t *q = sig_value, *qend = sig_value + sig_len;
    while (q < qend) {
        uint64_t key, n;
        q = varint(q, qend, &key);
        if (!q) return FR_SIG_MALFORMED;
        if (key == 0x09 && qend - q >= 8) {
            ts = 0;
            for (int k = 7; k >= 0; k--) ts = ts << 8 | q[k];
            has_ts = true;
            q += 8;
        } else if (key == 0x12 && (q = varint(q, qend, &n)) != NULL && n == 8 && qend - q >= 8) {
            mac = q;
            q += 8;
        } else {
            return FR_SIG_MALFORMED;
        }
    }
    if (!has_ts || mac == NULL) return FR_SIG_MALFORMED;
    uint8_t want[8];
    fr_sign_mac_with(&fr_state.mac_key, 2, fr_state.settings.robot_id, fr_state.epoch, ts, payload,
                     (size_t)(sig - payload), want);
    uint8_t diff = 0;
    for (int k = 0; k < 8; k++) diff |= (uint8_t)(want[k] ^ mac[k]);
    if (diff != 0) return FR_SIG_BAD;
    if (fr_state.gateway_ts_seen && ts <= fr_state.gateway_ts) return FR_SIG_REPLAYED;
    fr_state.gateway_ts_seen = true;
    fr_state.gateway_ts = ts;
    *signed_len = (size_t)(sig - payload);
    return FR_SIG_OK;
}
