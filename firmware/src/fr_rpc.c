/* firmware/src/fr_rpc.c: the RPC server (docs/protocol.md section 7): a table of handlers the program
 * registers, requests decoded field by field into one bounded call buffer, exactly one Response per Request
 * with its callId, the errors of 7.4, and calls answered later (motion.posture). */
#include <string.h>
#include "fr_internal.h"
#include "naogateway/proto/rpc.pb.h"

/** One registered method. */
typedef struct {
    const char *module;
    const char *method;
    fr_rpc_handler_t handler;
    void *ctx;
} handler_t;

/** A call answered later, with where its answer goes. */
typedef struct {
    bool used;
    bool has_call_id;
    uint32_t call_id;
    fr_route_t route;
} deferred_t;

static handler_t handlers[FR_RPC_HANDLERS_MAX];
static size_t handler_count;
static deferred_t deferred[FR_RPC_DEFERRED_MAX];

/** The call being decoded: names, parameters and the bytes of its string and binary parameters. */
static struct {
    fr_call_t call;
    char module[FR_RPC_NAME_MAX];
    char method[FR_RPC_NAME_MAX];
    bool names_truncated;
    uint8_t pool[FR_RPC_STRING_POOL];
    size_t pool_used;
    bool pool_overflow;
    fr_value_t *current; /* the parameter whose MixedValue is being decoded, NULL past FR_RPC_PARAMS_MAX */
    bool has_call_id;
    uint32_t call_id;
} in;

static char error_text[FR_RPC_ERROR_MAX];

void fr_rpc_reset(void) {
    memset(handlers, 0, sizeof handlers);
    handler_count = 0;
    memset(deferred, 0, sizeof deferred);
}

bool fr_rpc_register(const char *module, const char *method, fr_rpc_handler_t handler, void *ctx) {
    if (handler_count >= FR_RPC_HANDLERS_MAX || module == NULL || method == NULL || handler == NULL) return false;
    handlers[handler_count].module = module;
    handlers[handler_count].method = method;
    handlers[handler_count].handler = handler;
    handlers[handler_count].ctx = ctx;
    handler_count++;
    return true;
}

/* ---- decoding ------------------------------------------------------------------------------------------ */

/** Reads a name into the char array `arg` (FR_RPC_NAME_MAX), cutting it and noting so when long. */
static bool read_name(pb_istream_t *stream, void *arg) {
    char *dst = (char *)arg;
    size_t n = stream->bytes_left, keep = n < FR_RPC_NAME_MAX - 1 ? n : FR_RPC_NAME_MAX - 1;
    if (!pb_read(stream, (pb_byte_t *)dst, keep)) return false;
    dst[keep] = '\0';
    if (keep < n) {
        in.names_truncated = true;
        return pb_read(stream, NULL, n - keep);
    }
    return true;
}

/** Copies a string (`arg` non-NULL) or bytes parameter into the pool (zero-terminated) and points the current
 *  parameter at it. */
static bool read_blob(pb_istream_t *stream, void *arg) {
    bool is_string = arg != NULL;
    size_t n = stream->bytes_left;
    if (in.current == NULL || in.pool_used + n + 1 > sizeof in.pool) {
        if (in.current != NULL) in.pool_overflow = true;
        return pb_read(stream, NULL, n);
    }
    uint8_t *dst = in.pool + in.pool_used;
    if (!pb_read(stream, dst, n)) return false;
    dst[n] = 0;
    in.pool_used += n + 1;
    if (is_string) {
        in.current->kind = FR_VALUE_STRING;
        in.current->u.s = (const char *)dst;
    } else {
        in.current->kind = FR_VALUE_BINARY;
        in.current->u.bin.data = dst;
        in.current->u.bin.len = n;
    }
    return true;
}

/** A nested array parameter: its elements are read over and not kept; no method of 7.2 takes one. */
static bool read_array(pb_istream_t *stream, void *arg) {
    (void)arg;
    if (in.current != NULL && in.current->kind == FR_VALUE_NONE) in.current->kind = FR_VALUE_ARRAY;
    return pb_read(stream, NULL, stream->bytes_left);
}

/** The scalar fields of one MixedValue, the last of each kept (as nanopb's struct keeps them). */
typedef struct {
    bool has_int, has_float, has_bool;
    uint32_t int_value;
    float float_value;
    bool bool_value;
} mixed_t;

/** One field of a MixedValue (rpc.proto). */
static int mixed_field(pb_istream_t *s, uint32_t tag, pb_wire_type_t wire, void *ctx) {
    mixed_t *v = (mixed_t *)ctx;
    switch (tag) {
    case naogateway_proto_MixedValue_string_tag: return fr_in_callback(s, wire, read_blob, (void *)1) ? 1 : -1;
    case naogateway_proto_MixedValue_int_value_tag:
        v->has_int = true;
        return fr_in_uint32(s, wire, &v->int_value) ? 1 : -1;
    case naogateway_proto_MixedValue_float_value_tag: {
        v->has_float = true;
        uint32_t bits;
        if (wire != PB_WT_32BIT || !pb_decode_fixed32(s, &bits)) return -1;
        memcpy(&v->float_value, &bits, sizeof bits);
        return 1;
    }
    case naogateway_proto_MixedValue_binary_tag: return fr_in_callback(s, wire, read_blob, NULL) ? 1 : -1;
    case naogateway_proto_MixedValue_bool_value_tag:
        v->has_bool = true;
        return wire == PB_WT_VARINT && pb_decode_bool(s, &v->bool_value) ? 1 : -1;
    case naogateway_proto_MixedValue_array_tag: return fr_in_callback(s, wire, read_array, NULL) ? 1 : -1;
    default: return 0;
    }
}

/** One MixedValue of Request.params. */
static bool read_param(pb_istream_t *stream, void *arg) {
    (void)arg;
    size_t index = in.call.count++;
    in.current = index < FR_RPC_PARAMS_MAX ? &in.call.params[index] : NULL;
    mixed_t v;
    memset(&v, 0, sizeof v);
    if (!fr_in_message(stream, mixed_field, &v)) return false;
    if (in.current != NULL && in.current->kind == FR_VALUE_NONE) {
        if (v.has_float) { in.current->kind = FR_VALUE_FLOAT; in.current->u.f = v.float_value; }
        else if (v.has_int) { in.current->kind = FR_VALUE_INT; in.current->u.i = v.int_value; }
        else if (v.has_bool) { in.current->kind = FR_VALUE_BOOL; in.current->u.b = v.bool_value; }
    }
    in.current = NULL;
    return true;
}

/** Which of a Request's required fields one occurrence had. */
typedef struct {
    bool module, method;
} request_seen_t;

/** One field of a Request (rpc.proto). */
static int request_field(pb_istream_t *s, uint32_t tag, pb_wire_type_t wire, void *ctx) {
    request_seen_t *seen = (request_seen_t *)ctx;
    switch (tag) {
    case naogateway_proto_Request_module_tag:
        seen->module = true;
        return fr_in_callback(s, wire, read_name, in.module) ? 1 : -1;
    case naogateway_proto_Request_method_tag:
        seen->method = true;
        return fr_in_callback(s, wire, read_name, in.method) ? 1 : -1;
    case naogateway_proto_Request_params_tag: return fr_in_callback(s, wire, read_param, NULL) ? 1 : -1;
    case naogateway_proto_Request_callId_tag:
        in.has_call_id = true;
        return fr_in_uint32(s, wire, &in.call_id) ? 1 : -1;
    default: return 0;
    }
}

void fr_rpc_prepare(void) { memset(&in, 0, sizeof in); }

bool fr_rpc_read(pb_istream_t *s, pb_wire_type_t wire) {
    request_seen_t seen = {false, false};
    return fr_in_submessage(s, wire, request_field, &seen) && seen.module && seen.method;
}

/* ---- answering ----------------------------------------------------------------------------------------- */

/** Sends the one Response of a call: `result` or `error` (exactly one of them). */
static void respond(const fr_route_t *route, bool has_call_id, uint32_t call_id, const fr_value_t *result,
                    const char *error) {
    fr_out_t w;
    if (!fr_out_begin(&w, route)) return;
    uint8_t *ext = fr_out_open(&w, naogateway_proto_rpcResponse_tag);
    if (error != NULL) {
        fr_out_string(&w, naogateway_proto_Response_error_tag, error);
    } else {
        uint8_t *v = fr_out_open(&w, naogateway_proto_Response_returnval_tag);
        switch (result ? result->kind : FR_VALUE_NONE) {
        case FR_VALUE_STRING: fr_out_string(&w, naogateway_proto_MixedValue_string_tag, result->u.s); break;
        case FR_VALUE_INT: fr_out_uint(&w, naogateway_proto_MixedValue_int_value_tag, result->u.i); break;
        case FR_VALUE_FLOAT: fr_out_float(&w, naogateway_proto_MixedValue_float_value_tag, result->u.f); break;
        case FR_VALUE_BOOL: fr_out_uint(&w, naogateway_proto_MixedValue_bool_value_tag, result->u.b); break;
        case FR_VALUE_BINARY:
            fr_out_bytes(&w, naogateway_proto_MixedValue_binary_tag, result->u.bin.data, result->u.bin.len);
            break;
        default: break; /* an empty MixedValue: "no value" */
        }
        fr_out_close(&w, v);
    }
    if (has_call_id) fr_out_uint(&w, naogateway_proto_Response_callId_tag, call_id);
    fr_out_close(&w, ext);
    (void)fr_out_send(&w, route);
}

/** Copies `a` then `b` into error_text. */
static const char *error2(const char *a, const char *b) {
    size_t n = 0;
    for (; *a && n + 1 < sizeof error_text; a++) error_text[n++] = *a;
    for (; b && *b && n + 1 < sizeof error_text; b++) error_text[n++] = *b;
    error_text[n] = '\0';
    return error_text;
}

/** Whether two zero-terminated strings are equal (a loop, not libc's strcmp: 444 B of flash for a few names). */
static bool same(const char *a, const char *b) {
    while (*a != '\0' && *a == *b) a++, b++;
    return *a == *b;
}

/** Whether `f` is neither infinite nor NaN, from its exponent bits (no soft-float comparison routines). */
static bool finite(float f) {
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    return (bits & 0x7F800000u) != 0x7F800000u;
}

void fr_rpc_dispatch(const fr_route_t *route) {
    fr_call_t *call = &in.call;
    call->module = in.module;
    call->method = in.method;
    call->has_call_id = in.has_call_id;
    call->call_id = in.call_id;
    const handler_t *h = NULL;
    for (size_t k = 0; k < handler_count && !in.names_truncated; k++)
        if (same(handlers[k].module, in.module) && same(handlers[k].method, in.method)) h = &handlers[k];
    if (h == NULL) {
        /* "unknown method: module.method", as 9.7 shows it */
        char name[2 * FR_RPC_NAME_MAX + 1];
        size_t n = strlen(in.module);
        memcpy(name, in.module, n);
        name[n] = '.';
        memcpy(name + n + 1, in.method, strlen(in.method) + 1);
        respond(route, call->has_call_id, call->call_id, NULL, error2("unknown method: ", name));
        return;
    }
    if (in.pool_overflow) {
        respond(route, call->has_call_id, call->call_id, NULL, error2("bad parameters: parameter too long", NULL));
        return;
    }
    int slot = -1;
    for (int k = 0; k < FR_RPC_DEFERRED_MAX; k++) if (!deferred[k].used) { slot = k; break; }
    fr_value_t result;
    memset(&result, 0, sizeof result);
    error_text[0] = '\0';
    fr_rpc_status_t st = h->handler(call, &result, error_text, sizeof error_text, slot, h->ctx);
    if (st == FR_RPC_LATER) {
        if (slot < 0) {
            fr_state.stats.rpc_busy++;
            respond(route, call->has_call_id, call->call_id, NULL, error2("busy: too many calls waiting", NULL));
            return;
        }
        deferred[slot].used = true;
        deferred[slot].has_call_id = call->has_call_id;
        deferred[slot].call_id = call->call_id;
        deferred[slot].route = *route;
        return;
    }
    if (st == FR_RPC_ERROR) {
        if (error_text[0] == '\0') error2("bad parameters: ", NULL);
        respond(route, call->has_call_id, call->call_id, NULL, error_text);
        return;
    }
    respond(route, call->has_call_id, call->call_id, &result, NULL);
}

void fr_rpc_answer(fr_deferred_t id, const fr_value_t *result, const char *error) {
    if (id < 0 || id >= FR_RPC_DEFERRED_MAX || !deferred[id].used) return;
    deferred_t d = deferred[id];
    deferred[id].used = false;
    respond(&d.route, d.has_call_id, d.call_id, error ? NULL : result, error);
}

/** Appends `s` to `out` (zero-terminated, `cap` bytes). */
static void add(char *out, size_t cap, const char *s) {
    size_t n = strlen(out);
    while (*s && n + 1 < cap) out[n++] = *s++;
    out[n] = '\0';
}

/** Appends the decimal `v` to `out`. */
static void add_number(char *out, size_t cap, size_t v) {
    char digits[21], rev[21];
    size_t d = 0, k = 0;
    do { rev[d++] = (char)('0' + v % 10u); v /= 10u; } while (v > 0);
    while (d > 0) digits[k++] = rev[--d];
    digits[k] = '\0';
    add(out, cap, digits);
}

bool fr_rpc_expect_floats(const fr_call_t *call, size_t count, char *error, size_t error_cap) {
    bool ok = call->count == count;
    for (size_t k = 0; ok && k < count; k++)
        ok = call->params[k].kind == FR_VALUE_FLOAT && finite(call->params[k].u.f);
    if (!ok && error_cap > 0) {
        /* "bad parameters: expected 3 numbers, got 2 parameter(s)" (protocol.md 7.4) */
        error[0] = '\0';
        add(error, error_cap, "bad parameters: expected ");
        add_number(error, error_cap, count);
        if (call->count != count) {
            add(error, error_cap, " numbers, got ");
            add_number(error, error_cap, call->count);
            add(error, error_cap, " parameter(s)");
        } else {
            add(error, error_cap, " finite numbers");
        }
    }
    return ok;
}
