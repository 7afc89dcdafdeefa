# Turns nanopb 0.4.7's pb_decode.c into the build's modified copy (build/gen/pb_decode.c; the zlib licence
# allows altered versions that are plainly marked). The only change: an unknown field of wire type 3 (start
# group) is skipped up to its matching end-group by fr_pb_skip_group (src/fr_pb_groups.c) instead of being
# refused, as docs/protocol.md section 5 requires of every receiver. Everything else stays as released.
1i\
/* MODIFIED COPY of nanopb 0.4.7 pb_decode.c, made by the naogateway firmware build (firmware/proto/pb_decode_groups.sed):\
 * unknown groups are skipped (fr_pb_skip_group). Not the original software. */
/#include "pb_common.h"/a\
bool fr_pb_skip_group(pb_istream_t *stream, uint32_t tag);
s/if (!pb_skip_field(stream, wire_type))/if (!(wire_type == 3 ? fr_pb_skip_group(stream, tag) : pb_skip_field(stream, wire_type)))/
