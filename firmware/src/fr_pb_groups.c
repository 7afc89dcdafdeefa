/* firmware/src/fr_pb_groups.c: skipping unknown groups, which docs/protocol.md section 5 asks of every receiver
 * and nanopb 0.4.7 refuses ("invalid wire_type"). The build's copy of pb_decode.c calls this for an unknown
 * field of wire type 3 (firmware/proto/pb_decode_groups.sed); everything else is nanopb's own. */
#include "fr_internal.h"

/** Skips the rest of a group opened by field `tag`, nested groups included, up to FR_PB_GROUP_DEPTH deep. */
static bool skip_group(pb_istream_t *stream, uint32_t tag, int depth) {
    if (depth > FR_PB_GROUP_DEPTH) return false;
    for (;;) {
        pb_wire_type_t wire_type;
        uint32_t inner;
        bool eof;
        if (!pb_decode_tag(stream, &wire_type, &inner, &eof) || eof) return false; /* group never closed */
        if ((int)wire_type == 4) return inner == tag; /* an end-group of another field is malformed */
        if ((int)wire_type == 3) {
            if (!skip_group(stream, inner, depth + 1)) return false;
        } else if (!pb_skip_field(stream, wire_type)) {
            return false;
        }
    }
}

/** Called for an unknown start-group key of field `tag`: by the library's reader (fr_in.c) and by the build's
 *  pb_decode.c (the body's messages). */
bool fr_pb_skip_group(pb_istream_t *stream, uint32_t tag);
bool fr_pb_skip_group(pb_istream_t *stream, uint32_t tag) { return skip_group(stream, tag, 1); }
