/* firmware/src/fr_in.c: reading incoming messages field by field with nanopb's primitives (tags, varints, fixed32,
 * substreams, skipping), not with its descriptor-driven pb_decode: the three messages a robot reads (Message,
 * Request with its MixedValues, DebuggingCommands) are walked by hand in rpc.c, debug.c and core.c. What is taken
 * and what refused is what pb_decode takes and refuses for the same .proto (tests/test_in.c compares them on
 * mutated frames): a known field of the wrong wire type, a zero tag, a truncated value, an integer too large for its
 * field or a missing required field refuses the message; an unknown field is skipped (groups too, src/fr_pb_groups.c);
 * a string, bytes or repeated field is handed to its reader as nanopb hands a callback field: the payload of a
 * length-delimited value, the raw bytes of a scalar one. */
#include "fr_internal.h"

bool fr_pb_skip_group(pb_istream_t *stream, uint32_t tag);

bool fr_in_message(pb_istream_t *s, fr_in_field_t field, void *ctx) {
    while (s->bytes_left > 0) {
        uint32_t tag;
        pb_wire_type_t wire;
        bool eof;
        if (!pb_decode_tag(s, &wire, &tag, &eof)) {
            if (eof) break;
            return false;
        }
        if (tag == 0) return false;
        int r = field(s, tag, wire, ctx);
        if (r < 0) return false;
        if (r == 0 && !(wire == 3 ? fr_pb_skip_group(s, tag) : pb_skip_field(s, wire))) return false;
    }
    return true;
}

bool fr_in_callback(pb_istream_t *s, pb_wire_type_t wire, fr_in_reader_t reader, void *arg) {
    if (wire == PB_WT_STRING) {
        pb_istream_t sub;
        if (!pb_make_string_substream(s, &sub)) return false;
        size_t before;
        do {
            before = sub.bytes_left;
            if (reader != NULL && !reader(&sub, arg)) return false;
        } while (reader != NULL && sub.bytes_left > 0 && sub.bytes_left < before);
        return pb_close_string_substream(s, &sub);
    }
    uint8_t raw[10];
    size_t n = 0;
    switch (wire) {
    case PB_WT_VARINT:
        do {
            if (n == sizeof raw || !pb_read(s, raw + n, 1)) return false;
        } while (raw[n++] & 0x80u);
        break;
    case PB_WT_64BIT: n = 8; if (!pb_read(s, raw, 8)) return false; break;
    case PB_WT_32BIT: n = 4; if (!pb_read(s, raw, 4)) return false; break;
    default: return false;
    }
    pb_istream_t sub = pb_istream_from_buffer(raw, n);
    return reader == NULL || reader(&sub, arg);
}

bool fr_in_uint32(pb_istream_t *s, pb_wire_type_t wire, uint32_t *out) {
    uint64_t v;
    if (wire != PB_WT_VARINT || !pb_decode_varint(s, &v)) return false;
    *out = (uint32_t)v;
    return v <= UINT32_MAX; /* nanopb: "integer too large" */
}

bool fr_in_submessage(pb_istream_t *s, pb_wire_type_t wire, fr_in_field_t field, void *ctx) {
    pb_istream_t sub;
    if (wire != PB_WT_STRING || !pb_make_string_substream(s, &sub)) return false;
    return fr_in_message(&sub, field, ctx) && pb_close_string_substream(s, &sub);
}
