/* firmware/src/fr_frame.c: FU-Remote frame headers, both forms (docs/protocol.md 4.1, 4.2, 4.4). */
#include "fr_internal.h"

/** A big-endian u32 (frame headers are big-endian). */
static uint32_t be32(const uint8_t *p) {
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
}

/** Writes a big-endian u32. */
static void put_be32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

/* The checks run in the order of protocol.md 4.4, so the robot refuses what the gateway refuses. A gzip-flagged
 * frame is refused whole: an inflater needs a 32 KiB window, half the board's RAM, and the gateway never
 * compresses what it sends to a robot (4.3 says so). */
fr_frame_error_t fr_frame_parse(const uint8_t *data, size_t len, const uint8_t **payload, size_t *payload_len,
                                fr_form_t *form) {
    if (len > FR_DATAGRAM_MAX) return FR_FRAME_OVERSIZE;
    if (len < 8) return FR_FRAME_TRUNCATED;
    if (data[0] != 0 || data[1] != 42 || data[3] != 0) return FR_FRAME_WRONG_OPERATION;
    if ((data[2] & (uint8_t)~2u) != 0) return FR_FRAME_UNSUPPORTED_FLAGS;
    uint32_t word = be32(data + 4);
    size_t header = 8;
    uint32_t declared = word;
    if (word == 0) {
        if (len < 12) return FR_FRAME_TRUNCATED;
        header = 12;
        declared = be32(data + 8);
    }
    if (declared != len - header) return FR_FRAME_LENGTH_MISMATCH;
    if (data[2] & 2u) return FR_FRAME_GZIP;
    *payload = data + header;
    *payload_len = len - header;
    *form = header == 12 ? FR_FORM_LEGACY : FR_FORM_COMPACT;
    return FR_FRAME_OK;
}

uint8_t *fr_frame_header(uint8_t *payload, size_t payload_len, fr_form_t form) {
    uint8_t *frame = payload - (form == FR_FORM_LEGACY ? 12 : 8);
    frame[0] = 0;
    frame[1] = 42;
    frame[2] = 0;
    frame[3] = 0;
    if (form == FR_FORM_LEGACY) {
        put_be32(frame + 4, 0);
        put_be32(frame + 8, (uint32_t)payload_len);
    } else {
        put_be32(frame + 4, (uint32_t)payload_len);
    }
    return frame;
}
