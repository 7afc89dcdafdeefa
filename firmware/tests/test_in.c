/* firmware/tests/test_in.c: the library reads incoming frames field by field (src/fr_in.c); nanopb's pb_decode with
 * the callbacks the library had before is the reference. Valid frames (requests with every kind of parameter, debug
 * commands, unknown fields and groups) and 30,000 mutations of them (bytes flipped, inserted, removed, cut) go
 * through the library; for each, what the reference decodes predicts whether the frame is refused as bad protobuf,
 * and if not, the call the handler sees (names, every parameter, callId) and the options switched on and off. */
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "../src/fr_internal.h"
#include "naogateway/proto/debugging.pb.h"
#include "naogateway/proto/rpc.pb.h"

static const fr_endpoint_t gateway = {{192, 168, 1, 10}, 11011};

/* ---- the reference: nanopb's pb_decode with the library's former callbacks ---------------------------------- */

static struct {
    char module[FR_RPC_NAME_MAX], method[FR_RPC_NAME_MAX];
    bool names_truncated;
    fr_value_t params[FR_RPC_PARAMS_MAX];
    size_t count;
    uint8_t pool[FR_RPC_STRING_POOL];
    size_t pool_used;
    bool pool_overflow;
    fr_value_t *current;
} ref;

static bool ref_name(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field;
    char *dst = (char *)*arg;
    size_t n = stream->bytes_left, keep = n < FR_RPC_NAME_MAX - 1 ? n : FR_RPC_NAME_MAX - 1;
    if (!pb_read(stream, (pb_byte_t *)dst, keep)) return false;
    dst[keep] = '\0';
    if (keep < n) {
        ref.names_truncated = true;
        return pb_read(stream, NULL, n - keep);
    }
    return true;
}

static bool ref_blob(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field;
    bool is_string = *arg != NULL;
    size_t n = stream->bytes_left;
    if (ref.current == NULL || ref.pool_used + n + 1 > sizeof ref.pool) {
        if (ref.current != NULL) ref.pool_overflow = true;
        return pb_read(stream, NULL, n);
    }
    uint8_t *dst = ref.pool + ref.pool_used;
    if (!pb_read(stream, dst, n)) return false;
    dst[n] = 0;
    ref.pool_used += n + 1;
    if (is_string) {
        ref.current->kind = FR_VALUE_STRING;
        ref.current->u.s = (const char *)dst;
    } else {
        ref.current->kind = FR_VALUE_BINARY;
        ref.current->u.bin.data = dst;
        ref.current->u.bin.len = n;
    }
    return true;
}

static bool ref_array(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field; (void)arg;
    if (ref.current != NULL && ref.current->kind == FR_VALUE_NONE) ref.current->kind = FR_VALUE_ARRAY;
    return pb_read(stream, NULL, stream->bytes_left);
}

static bool ref_param(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field; (void)arg;
    size_t index = ref.count++;
    ref.current = index < FR_RPC_PARAMS_MAX ? &ref.params[index] : NULL;
    naogateway_proto_MixedValue v;
    memset(&v, 0, sizeof v);
    v.string.funcs.decode = ref_blob;
    v.string.arg = (void *)1;
    v.binary.funcs.decode = ref_blob;
    v.array.funcs.decode = ref_array;
    if (!pb_decode(stream, naogateway_proto_MixedValue_fields, &v)) return false;
    if (ref.current != NULL && ref.current->kind == FR_VALUE_NONE) {
        if (v.has_float_value) { ref.current->kind = FR_VALUE_FLOAT; ref.current->u.f = v.float_value; }
        else if (v.has_int_value) { ref.current->kind = FR_VALUE_INT; ref.current->u.i = v.int_value; }
        else if (v.has_bool_value) { ref.current->kind = FR_VALUE_BOOL; ref.current->u.b = v.bool_value; }
    }
    ref.current = NULL;
    return true;
}

/* the options, as the library switches them (an option named by a pattern: equal, or the pattern and a dot) */
static const char *const option_names[] = {"t.a", "t.b", "t", "x.y", "tt"};
#define OPTIONS (sizeof option_names / sizeof option_names[0])
static bool ref_enabled[OPTIONS];
static bool ref_pending[OPTIONS], ref_pending_set[OPTIONS];
static const int on = 1, off = 0;

static bool ref_option_name(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field;
    char name[FR_OPTION_NAME_MAX];
    size_t n = stream->bytes_left;
    if (n >= sizeof name || *arg == NULL) return pb_read(stream, NULL, n);
    if (!pb_read(stream, (pb_byte_t *)name, n)) return false;
    for (size_t k = 0; k < OPTIONS; k++) {
        const char *o = option_names[k];
        bool match = true;
        for (size_t i = 0; i < n && match; i++) match = o[i] == name[i] && o[i] != '\0';
        if (match && (o[n] == '\0' || o[n] == '.')) {
            ref_pending[k] = *(const int *)*arg == on;
            ref_pending_set[k] = true;
        }
    }
    return true;
}

/** Decodes `payload` as the library did with nanopb: true when it takes it; the request and commands found. */
static bool reference(const uint8_t *payload, size_t len, bool *has_request, naogateway_proto_Request *request,
                      bool *has_commands, naogateway_proto_DebuggingCommands *commands) {
    memset(&ref, 0, sizeof ref);
    memset(ref_pending_set, 0, sizeof ref_pending_set);
    memset(request, 0, sizeof *request);
    memset(commands, 0, sizeof *commands);
    request->module.funcs.decode = request->method.funcs.decode = ref_name;
    request->module.arg = ref.module;
    request->method.arg = ref.method;
    request->params.funcs.decode = ref_param;
    commands->optionEnable.options.funcs.decode = ref_option_name;
    commands->optionEnable.options.arg = (void *)(uintptr_t)&on;
    commands->optionDisable.options.funcs.decode = ref_option_name;
    commands->optionDisable.options.arg = (void *)(uintptr_t)&off;
    pb_extension_t ext_cmd = {&naogateway_proto_debuggingCommands, commands, NULL, false};
    pb_extension_t ext_req = {&naogateway_proto_rpcRequest, request, &ext_cmd, false};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.extensions = &ext_req;
    pb_istream_t in = pb_istream_from_buffer(payload, len);
    bool ok = pb_decode(&in, naogateway_proto_Message_fields, &msg);
    *has_request = ext_req.found;
    *has_commands = ext_cmd.found;
    return ok;
}

/* ---- the library's side ------------------------------------------------------------------------------------- */

static bool called;
static fr_call_t seen;
static char seen_module[FR_RPC_NAME_MAX], seen_method[FR_RPC_NAME_MAX];
static uint8_t seen_blobs[FR_RPC_PARAMS_MAX][FR_RPC_STRING_POOL];

static fr_rpc_status_t handler(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)err; (void)cap; (void)later; (void)ctx;
    called = true;
    seen = *c;
    strcpy(seen_module, c->module);
    strcpy(seen_method, c->method);
    for (size_t k = 0; k < FR_RPC_PARAMS_MAX && k < c->count; k++) {
        if (c->params[k].kind == FR_VALUE_STRING) strcpy((char *)seen_blobs[k], c->params[k].u.s);
        if (c->params[k].kind == FR_VALUE_BINARY) memcpy(seen_blobs[k], c->params[k].u.bin.data, c->params[k].u.bin.len);
    }
    r->kind = FR_VALUE_BOOL;
    r->u.b = true;
    return FR_RPC_OK;
}

/** Whether the call the handler saw is the one the reference decoded. */
static bool same_call(const naogateway_proto_Request *request) {
    if (strcmp(seen_module, ref.module) != 0 || strcmp(seen_method, ref.method) != 0) return false;
    if (seen.count != ref.count || seen.has_call_id != request->has_callId) return false;
    if (seen.has_call_id && seen.call_id != request->callId) return false;
    for (size_t k = 0; k < FR_RPC_PARAMS_MAX && k < ref.count; k++) {
        const fr_value_t *a = &seen.params[k], *b = &ref.params[k];
        if (a->kind != b->kind) return false;
        switch (a->kind) {
        case FR_VALUE_STRING: if (strcmp((const char *)seen_blobs[k], b->u.s) != 0) return false; break;
        case FR_VALUE_INT: if (a->u.i != b->u.i) return false; break;
        case FR_VALUE_FLOAT: if (memcmp(&a->u.f, &b->u.f, sizeof a->u.f) != 0) return false; break;
        case FR_VALUE_BOOL: if (a->u.b != b->u.b) return false; break;
        case FR_VALUE_BINARY:
            if (a->u.bin.len != b->u.bin.len || memcmp(seen_blobs[k], b->u.bin.data, b->u.bin.len) != 0) return false;
            break;
        default: break;
        }
    }
    return true;
}

static int option_index[OPTIONS];
static size_t mismatches;

/** One payload through both: the same verdict, call and option changes. */
static void compare(const uint8_t *payload, size_t len) {
    int32_t id = 0;
    if (fr_message_robot_id(payload, len, &id) != 1 || id != 1) return; /* refused before decoding, both ways */
    bool has_request, has_commands;
    naogateway_proto_Request request;
    naogateway_proto_DebuggingCommands commands;
    bool ok = reference(payload, len, &has_request, &request, &has_commands, &commands);

    uint8_t frame[1400] = {0, 42, 0, 0, 0, 0, (uint8_t)(len >> 8), (uint8_t)len};
    memcpy(frame + 8, payload, len);
    uint32_t bad = fr_stats()->bad_protobuf;
    called = false;
    fake_clear_sent();
    fake_receive(&gateway, frame, 8 + len);
    fr_poll();
    bool refused = fr_stats()->bad_protobuf == bad + 1;
    bool good = refused == !ok;
    if (good && ok && has_request) {
        bool dispatched = !ref.names_truncated && !ref.pool_overflow && strcmp(ref.module, "test") == 0 &&
                          strcmp(ref.method, "m") == 0;
        good = called == dispatched && (!called || same_call(&request));
    }
    if (good && !ok) good = !called && fake_sent_count == 0;
    if (good && ok && has_commands)
        for (size_t k = 0; k < OPTIONS; k++)
            if (ref_pending_set[k]) ref_enabled[k] = ref_pending[k];
    for (size_t k = 0; k < OPTIONS; k++) good = good && fr_option_enabled(option_index[k]) == ref_enabled[k];
    if (!good) {
        if (mismatches++ < 3) {
            printf("  differs (nanopb %s, library %s):", ok ? "takes" : "refuses", refused ? "refuses" : "takes");
            for (size_t i = 0; i < len; i++) printf(" %02X", payload[i]);
            printf("\n");
        }
        for (size_t k = 0; k < OPTIONS; k++) ref_enabled[k] = fr_option_enabled(option_index[k]); /* go on in step */
    }
}

/* ---- the frames ---------------------------------------------------------------------------------------------- */

static bool write_str(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const char *s = (const char *)*arg;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, (const pb_byte_t *)s, strlen(s));
}

static bool write_params(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    (void)arg;
    static const uint8_t blob[] = {0, 1, 2, 0xFF};
    for (int k = 0; k < 8; k++) {
        naogateway_proto_MixedValue v = naogateway_proto_MixedValue_init_zero;
        switch (k) {
        case 0: v.has_float_value = true; v.float_value = 0.2f; break;
        case 1: v.has_int_value = true; v.int_value = 300; break;
        case 2: v.has_bool_value = true; v.bool_value = true; break;
        case 3: v.string.funcs.encode = write_str; v.string.arg = (void *)(uintptr_t)"hello"; break;
        case 4: v.binary.funcs.encode = write_str; v.binary.arg = (void *)(uintptr_t)blob; break;
        case 5: v.has_int_value = v.has_float_value = true; v.int_value = 7; v.float_value = -1.5f; break;
        default: break; /* empty MixedValues: no value */
        }
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_MixedValue_fields, &v))
            return false;
    }
    return true;
}

static bool write_names(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    for (const char *const *n = (const char *const *)*arg; *n; n++)
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_string(stream, (const pb_byte_t *)*n, strlen(*n)))
            return false;
    return true;
}

/** A Message with robotID 1 and the given parts; unknown fields and a group appended when `extra`. */
static size_t build(uint8_t *out, bool request, bool commands, bool extra, int variant) {
    static const char *const enable[] = {"t", "x.y", NULL}, *const disable[] = {"t.b", NULL};
    naogateway_proto_Request r = naogateway_proto_Request_init_zero;
    r.module.funcs.encode = r.method.funcs.encode = write_str;
    r.module.arg = (void *)(uintptr_t)"test";
    r.method.arg = (void *)(uintptr_t)(variant == 2 ? "other" : "m");
    if (variant != 1) r.params.funcs.encode = write_params;
    r.has_callId = variant != 3;
    r.callId = 4000000000u;
    naogateway_proto_DebuggingCommands c = naogateway_proto_DebuggingCommands_init_zero;
    c.has_optionPull = true;
    c.optionPull = variant != 0;
    c.has_optionEnable = true;
    c.optionEnable.options.funcs.encode = write_names;
    c.optionEnable.options.arg = (void *)(uintptr_t)enable;
    c.has_optionDisable = variant != 1;
    c.optionDisable.options.funcs.encode = write_names;
    c.optionDisable.options.arg = (void *)(uintptr_t)disable;
    c.has_optionPush = variant == 2;
    pb_extension_t ext_cmd = {&naogateway_proto_debuggingCommands, &c, NULL, true};
    pb_extension_t ext_req = {&naogateway_proto_rpcRequest, &r, commands ? &ext_cmd : NULL, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.robotID = 1;
    msg.extensions = request ? &ext_req : (commands ? &ext_cmd : NULL);
    pb_ostream_t o = pb_ostream_from_buffer(out, 600);
    if (!pb_encode(&o, naogateway_proto_Message_fields, &msg)) return 0;
    size_t n = o.bytes_written;
    if (extra) { /* field 50 varint, field 60 as a group holding a string, field 61 fixed32 */
        static const uint8_t more[] = {0x90, 0x03, 0x05, 0xE3, 0x03, 0x0A, 0x02, 'h', 'i', 0xE4, 0x03, 0xED, 0x03, 1, 2, 3, 4};
        memcpy(out + n, more, sizeof more);
        n += sizeof more;
    }
    return n;
}

static uint32_t rng = 12345u;
static uint32_t next(void) {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

int main(void) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.team_number = 1;
    s.gateway = gateway;
    s.development = true;
    fake_now = 0;
    CHECK(fr_init(&s) == FR_INIT_OK);
    CHECK(fr_rpc_register("test", "m", handler, NULL));
    for (size_t k = 0; k < OPTIONS; k++) option_index[k] = fr_option_add(option_names[k], FR_OPT_TEXT, NULL);
    fr_poll();

    static uint8_t bases[32][600];
    static size_t base_len[32];
    size_t nbases = 0;
    for (int variant = 0; variant < 4; variant++)
        for (int parts = 1; parts < 4; parts++)
            for (int extra = 0; extra < 2; extra++) {
                base_len[nbases] = build(bases[nbases], parts & 1, parts & 2, extra, variant);
                CHECK(base_len[nbases] > 0);
                nbases++;
            }
    /* the valid frames: each taken, the same way */
    size_t before = mismatches;
    for (size_t b = 0; b < nbases; b++) compare(bases[b], base_len[b]);
    CHECK(mismatches == before);
    /* a valid request is dispatched with all its parameters */
    called = false;
    compare(bases[1], base_len[1]);
    CHECK(called && seen.count == 8 && seen.params[0].kind == FR_VALUE_FLOAT && seen.params[5].kind == FR_VALUE_FLOAT);

    /* mutations */
    static uint8_t m[700];
    for (int round = 0; round < 30000; round++) {
        size_t b = next() % nbases, n = base_len[b];
        memcpy(m, bases[b], n);
        int edits = 1 + (int)(next() % 3);
        for (int e = 0; e < edits && n > 2; e++) {
            size_t at = 2 + next() % (n - 2); /* robotID kept, so the frame gets to the decoder */
            switch (next() % 5) {
            case 0: m[at] = (uint8_t)next(); break;
            case 1: m[at] ^= (uint8_t)(1u << (next() % 8)); break;
            case 2: memmove(m + at + 1, m + at, n - at); m[at] = (uint8_t)next(); n++; break;
            case 3: memmove(m + at, m + at + 1, n - at - 1); n--; break;
            default: n = at; break;
            }
        }
        compare(m, n);
    }
    printf("  %zu of 30000 mutated frames decoded differently\n", mismatches);
    CHECK(mismatches == 0);
    return DONE();
}
