/* firmware/tests/test_out.c: the frames the library writes by hand (src/fr_out.c) against nanopb's encoding of the
 * same messages, byte for byte: the option list, every kind of debug data, the HaViMo2 frames and every kind of RPC
 * answer, with the cases that change the bytes (strings left out, long fields with two-byte lengths, negative
 * coordinates, empty lists). The keep-alive's comparison is in test_protocol.c. */
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "../src/fr_internal.h"
#include "naogateway/proto/debugging.pb.h"
#include "naogateway/proto/havimo.pb.h"
#include "naogateway/proto/rpc.pb.h"

static const fr_endpoint_t gateway = {{192, 168, 1, 10}, 11011};

/* ---- the reference: nanopb ---------------------------------------------------------------------------- */

static bool write_str(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const char *s = (const char *)*arg;
    if (s == NULL) return true;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, (const pb_byte_t *)s, strlen(s));
}

static pb_callback_t str_cb(const char *s) {
    pb_callback_t cb;
    cb.funcs.encode = s ? write_str : NULL;
    cb.arg = (void *)(uintptr_t)s;
    return cb;
}

typedef struct {
    const void *items;
    size_t count;
} list_t;

static uint8_t expected[1400];
static size_t expected_len;

/** Encodes Message{robotID 1, ext} into `expected` (compact header form: the payload alone). */
static void reference(const pb_extension_type_t *type, void *dest) {
    pb_extension_t ext = {type, dest, NULL, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.robotID = 1;
    msg.extensions = &ext;
    pb_ostream_t o = pb_ostream_from_buffer(expected, sizeof expected);
    expected_len = pb_encode(&o, naogateway_proto_Message_fields, &msg) ? o.bytes_written : 0;
}

/** Whether the one frame sent is the reference's payload behind a legacy (12-byte) or compact header. */
static bool sent_as_reference(size_t header) {
    return expected_len > 0 && fake_sent_count == 1 && fake_sent[0].len == header + expected_len &&
           memcmp(fake_sent[0].data + header, expected, expected_len) == 0;
}

/* the option list */
typedef struct {
    const char *name, *description;
    int type;
    bool enabled;
} ref_option_t;

static bool write_options(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const ref_option_t *o = (const ref_option_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_DebuggingOption m = naogateway_proto_DebuggingOption_init_zero;
        m.name = str_cb(o[k].name);
        m.has_type = m.has_enabled = true;
        m.type = (naogateway_proto_DebuggingOptionType)o[k].type;
        m.enabled = o[k].enabled;
        m.description = str_cb(o[k].description);
        if (!pb_encode_tag_for_field(stream, field) ||
            !pb_encode_submessage(stream, naogateway_proto_DebuggingOption_fields, &m))
            return false;
    }
    return true;
}

static void reference_options(const ref_option_t *o, size_t count) {
    list_t l = {o, count};
    naogateway_proto_DebuggingCommands c = naogateway_proto_DebuggingCommands_init_zero;
    c.has_optionPush = true;
    c.optionPush.options.funcs.encode = write_options;
    c.optionPush.options.arg = &l;
    reference(&naogateway_proto_debuggingCommands, &c);
}

/* debug data */
static naogateway_proto_DebugData data_of(const char *option, uint32_t now, pb_size_t which) {
    naogateway_proto_DebugData d = naogateway_proto_DebugData_init_zero;
    d.option = str_cb(option);
    d.has_timestamp = true;
    d.timestamp = now;
    d.which_data = which;
    return d;
}

static bool write_rows(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const fr_table_row_t *r = (const fr_table_row_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_DebugTable_Row m = naogateway_proto_DebugTable_Row_init_zero;
        m.key = str_cb(r[k].key);
        m.value = str_cb(r[k].value);
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_DebugTable_Row_fields, &m))
            return false;
    }
    return true;
}

static bool write_samples(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const fr_plot_sample_t *s = (const fr_plot_sample_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_DebugPlot_Sample m = naogateway_proto_DebugPlot_Sample_init_zero;
        m.series = str_cb(s[k].series);
        m.value = s[k].value;
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_DebugPlot_Sample_fields, &m))
            return false;
    }
    return true;
}

static bool write_objects(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const fr_relative_t *o = (const fr_relative_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_DebugRelativePosition_RelativeObject m = naogateway_proto_DebugRelativePosition_RelativeObject_init_zero;
        m.name = str_cb(o[k].name);
        m.distance = o[k].distance;
        m.angle = o[k].angle;
        if (!pb_encode_tag_for_field(stream, field) ||
            !pb_encode_submessage(stream, naogateway_proto_DebugRelativePosition_RelativeObject_fields, &m))
            return false;
    }
    return true;
}

static bool write_shapes(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const fr_shape_t *s = (const fr_shape_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_Shape m = naogateway_proto_Shape_init_zero;
        m.kind = (naogateway_proto_Shape_Kind)s[k].kind;
        m.x1 = s[k].x1;
        m.y1 = s[k].y1;
        m.has_x2 = m.has_y2 = s[k].has_second;
        m.x2 = s[k].x2;
        m.y2 = s[k].y2;
        m.has_radius = s[k].radius > 0;
        m.radius = s[k].radius;
        m.has_colour = s[k].has_colour;
        m.colour.r = s[k].r;
        m.colour.g = s[k].g;
        m.colour.b = s[k].b;
        m.label = str_cb(s[k].label);
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_Shape_fields, &m))
            return false;
    }
    return true;
}

static bool write_bytes(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, (const pb_byte_t *)l->items, l->count);
}

/* ---- the library's frames ------------------------------------------------------------------------------ */

static fr_settings_t settings(void) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 1;
    s.team_number = 1;
    s.player_number = 1;
    s.gateway = gateway;
    s.agent = "SimAgent";
    s.role = "striker";
    s.boot_id = 1;
    s.development = true;
    s.form = FR_FORM_COMPACT;
    return s;
}

/** Delivers Message{robotID 1, debuggingCommands{optionEnable{names}}} in the legacy form and polls. */
static bool write_names(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const char *const *names = (const char *const *)*arg;
    for (; *names; names++)
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_string(stream, (const pb_byte_t *)*names, strlen(*names)))
            return false;
    return true;
}

static void enable(const char *const *names) {
    naogateway_proto_DebuggingCommands c = naogateway_proto_DebuggingCommands_init_zero;
    c.has_optionEnable = true;
    c.optionEnable.options.funcs.encode = write_names;
    c.optionEnable.options.arg = (void *)(uintptr_t)names;
    reference(&naogateway_proto_debuggingCommands, &c);
    uint8_t frame[1400] = {0, 42, 0, 0, 0, 0, 0, 0, 0, 0, 0, (uint8_t)expected_len};
    memcpy(frame + 12, expected, expected_len);
    fake_receive(&gateway, frame, 12 + expected_len);
    fake_clear_sent();
    fr_poll();
}

static char long_text[1301];
static uint8_t pixels[300];

static void test_options_and_debug(void) {
    fr_settings_t s = settings();
    fake_now = 0;
    CHECK(fr_init(&s) == FR_INIT_OK);
    int text = fr_option_add("t.text", FR_OPT_TEXT, "a line of text");
    int table = fr_option_add("t.table", FR_OPT_TABLE, NULL);
    int plot = fr_option_add("t.plot", FR_OPT_PLOTTER, NULL);
    int rel = fr_option_add("t.rel", FR_OPT_DRAWING_RELATIVE, NULL);
    int field = fr_option_add("t.field", FR_OPT_DRAWING_FIELD, "shapes");
    int image = fr_option_add("t.image", FR_OPT_DRAWING_CAMERA, NULL);
    int regions = fr_option_add("h.regions", FR_OPT_HAVIMO_REGIONS, NULL);
    int grid = fr_option_add("h.grid", FR_OPT_HAVIMO_GRID, NULL);
    int off = fr_option_add("x.off", FR_OPT_TEXT, NULL);
    fr_poll();
    /* the answer to an enable is the whole list, in the request's (legacy) form */
    const char *const names[] = {"t", "h", NULL};
    enable(names);
    const ref_option_t list[] = {
        {"t.text", "a line of text", 1, true}, {"t.table", NULL, 4, true}, {"t.plot", NULL, 3, true},
        {"t.rel", NULL, 7, true}, {"t.field", "shapes", 6, true}, {"t.image", NULL, 5, true},
        {"h.regions", NULL, 100, true}, {"h.grid", NULL, 101, true}, {"x.off", NULL, 1, false}};
    reference_options(list, sizeof list / sizeof list[0]);
    CHECK(sent_as_reference(12));
    CHECK(fr_option_enabled(text) && !fr_option_enabled(off));

    fake_now = 123456;
    uint32_t now = fr_uptime_ms();
    /* text: short, long (two-byte lengths at two levels), and nothing for a disabled option */
    const char *texts[] = {"hello", long_text, ""};
    memset(long_text, 'x', sizeof long_text - 1);
    for (size_t k = 0; k < 3; k++) {
        naogateway_proto_DebugData d = data_of("t.text", now, naogateway_proto_DebugData_text_tag);
        d.data.text.text = str_cb(texts[k]);
        reference(&naogateway_proto_debugData, &d);
        fake_clear_sent();
        CHECK(fr_debug_text(text, texts[k]) && sent_as_reference(8));
    }
    fake_clear_sent();
    CHECK(!fr_debug_text(off, "no") && fake_sent_count == 0);

    const fr_table_row_t rows[] = {{"battery", "12.4 V"}, {"posture", NULL}, {NULL, "alone"}, {"", ""}};
    for (size_t n = 0; n <= 4; n += 4) {
        list_t l = {rows, n};
        naogateway_proto_DebugData d = data_of("t.table", now, naogateway_proto_DebugData_table_tag);
        d.data.table.rows.funcs.encode = write_rows;
        d.data.table.rows.arg = &l;
        reference(&naogateway_proto_debugData, &d);
        fake_clear_sent();
        CHECK(fr_debug_table(table, rows, n) && sent_as_reference(8));
    }

    const fr_plot_sample_t samples[] = {{"speed", 0.25f}, {"angle", -3.5f}, {NULL, 1e30f}};
    {
        list_t l = {samples, 3};
        naogateway_proto_DebugData d = data_of("t.plot", now, naogateway_proto_DebugData_plot_tag);
        d.data.plot.samples.funcs.encode = write_samples;
        d.data.plot.samples.arg = &l;
        reference(&naogateway_proto_debugData, &d);
        fake_clear_sent();
        CHECK(fr_debug_plot(plot, samples, 3) && sent_as_reference(8));
    }

    const fr_relative_t objects[] = {{"ball", 1234, 0.5f}, {"goal", 0, -1.25f}, {NULL, 4000000000u, 0.0f}};
    {
        list_t l = {objects, 3};
        naogateway_proto_DebugData d = data_of("t.rel", now, naogateway_proto_DebugData_relativePosition_tag);
        d.data.relativePosition.objects.funcs.encode = write_objects;
        d.data.relativePosition.objects.arg = &l;
        reference(&naogateway_proto_debugData, &d);
        fake_clear_sent();
        CHECK(fr_debug_relative(rel, objects, 3) && sent_as_reference(8));
    }

    static fr_shape_t shapes[12];
    for (size_t k = 0; k < 12; k++) {
        shapes[k].kind = (uint8_t)(k % 4);
        shapes[k].x1 = (int32_t)(k * 1000) - 4500;
        shapes[k].y1 = -(int32_t)k * 77777;
        shapes[k].has_second = k % 2 == 1;
        shapes[k].x2 = k == 3 ? -2147483647 - 1 : (int32_t)k;
        shapes[k].y2 = k == 5 ? 2147483647 : -(int32_t)k;
        shapes[k].radius = k % 3 == 0 ? 0u : (uint32_t)k * 50u;
        shapes[k].has_colour = k % 3 != 2;
        shapes[k].r = (uint8_t)(k * 20);
        shapes[k].g = 255;
        shapes[k].b = 0;
        shapes[k].label = k % 4 == 0 ? NULL : (k == 6 ? long_text + 1100 : "label");
    }
    {
        list_t l = {shapes, 12};
        naogateway_proto_DebugData d = data_of("t.field", now, naogateway_proto_DebugData_fieldDrawing_tag);
        d.data.fieldDrawing.shapes.funcs.encode = write_shapes;
        d.data.fieldDrawing.shapes.arg = &l;
        reference(&naogateway_proto_debugData, &d);
        fake_clear_sent();
        CHECK(fr_debug_field(field, shapes, 12) && sent_as_reference(8));
    }

    for (size_t k = 0; k < sizeof pixels; k++) pixels[k] = (uint8_t)(k * 13u);
    for (int with_pixels = 0; with_pixels < 2; with_pixels++) {
        list_t px = {pixels, sizeof pixels}, ov = {shapes, with_pixels ? 3u : 0u};
        naogateway_proto_DebugData d = data_of("t.image", now, naogateway_proto_DebugData_image_tag);
        d.data.image.width = 20;
        d.data.image.height = 15;
        d.data.image.has_format = true;
        d.data.image.format = (naogateway_proto_DebugImage_Format)(with_pixels ? 1 : 3);
        if (with_pixels) {
            d.data.image.pixels.funcs.encode = write_bytes;
            d.data.image.pixels.arg = &px;
        }
        d.data.image.overlay.funcs.encode = write_shapes;
        d.data.image.overlay.arg = &ov;
        reference(&naogateway_proto_debugData, &d);
        fake_clear_sent();
        CHECK(fr_debug_image(image, 20, 15, (uint8_t)(with_pixels ? 1 : 3), with_pixels ? pixels : NULL,
                             sizeof pixels, shapes, with_pixels ? 3u : 0u) &&
              sent_as_reference(8));
    }

    /* HaViMo2 regions: unused slots (index byte 0) left out; a grid */
    static uint8_t records[FR_HAVIMO_REGIONS_MAX * FR_HAVIMO_RECORD_SIZE], used[sizeof records];
    size_t used_len = 0;
    for (size_t k = 0; k < sizeof records; k++) records[k] = (uint8_t)(k * 7u + 1u);
    for (size_t r = 0; r < FR_HAVIMO_REGIONS_MAX; r += 3) records[r * FR_HAVIMO_RECORD_SIZE] = 0;
    for (size_t r = 0; r < FR_HAVIMO_REGIONS_MAX; r++)
        if (records[r * FR_HAVIMO_RECORD_SIZE] != 0) {
            memcpy(used + used_len, records + r * FR_HAVIMO_RECORD_SIZE, FR_HAVIMO_RECORD_SIZE);
            used_len += FR_HAVIMO_RECORD_SIZE;
        }
    {
        list_t l = {used, used_len};
        naogateway_proto_HaViMoRegionFrame f = naogateway_proto_HaViMoRegionFrame_init_zero;
        f.frame = 300;
        f.has_timestamp = true;
        f.timestamp = now;
        f.records.funcs.encode = write_bytes;
        f.records.arg = &l;
        reference(&naogateway_proto_havimoRegions, &f);
        fake_clear_sent();
        CHECK(fr_havimo_regions(regions, 300, records, FR_HAVIMO_REGIONS_MAX) && sent_as_reference(8));
    }
    static uint8_t cells[FR_HAVIMO_GRID_SIZE];
    for (size_t k = 0; k < sizeof cells; k++) cells[k] = (uint8_t)(k % 5u);
    {
        list_t l = {cells, sizeof cells};
        naogateway_proto_HaViMoGridFrame f = naogateway_proto_HaViMoGridFrame_init_zero;
        f.frame = 7;
        f.has_timestamp = true;
        f.timestamp = now;
        f.cells.funcs.encode = write_bytes;
        f.cells.arg = &l;
        reference(&naogateway_proto_havimoGrid, &f);
        fake_clear_sent();
        CHECK(fr_havimo_grid(grid, 7, cells) && sent_as_reference(8));
    }
    /* a frame that does not fit is not sent, and counted */
    uint32_t failed = fr_stats()->send_failed;
    static char too_long[1500];
    memset(too_long, 'y', sizeof too_long - 1);
    fake_clear_sent();
    CHECK(!fr_debug_text(text, too_long) && fake_sent_count == 0 && fr_stats()->send_failed == failed + 1);
}

/* ---- RPC answers ---------------------------------------------------------------------------------------- */

static fr_value_t answer;
static const char *answer_error;
static fr_rpc_status_t handler(const fr_call_t *c, fr_value_t *r, char *err, size_t cap, fr_deferred_t later, void *ctx) {
    (void)c; (void)later; (void)ctx;
    if (answer_error) {
        strncpy(err, answer_error, cap - 1);
        err[cap - 1] = '\0';
        return FR_RPC_ERROR;
    }
    *r = answer;
    return FR_RPC_OK;
}

static bool write_binary(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const fr_value_t *v = (const fr_value_t *)*arg;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, v->u.bin.data, v->u.bin.len);
}

/** Calls test.m with callId `id` (none when 0) and checks its answer against nanopb's Response. */
static void call_and_compare(uint32_t id) {
    naogateway_proto_Request req = naogateway_proto_Request_init_zero;
    req.module = str_cb("test");
    req.method = str_cb("m");
    req.has_callId = id != 0;
    req.callId = id;
    reference(&naogateway_proto_rpcRequest, &req);
    uint8_t frame[1400] = {0, 42, 0, 0, 0, 0, 0, (uint8_t)expected_len};
    memcpy(frame + 8, expected, expected_len);
    fake_receive(&gateway, frame, 8 + expected_len);

    naogateway_proto_Response resp = naogateway_proto_Response_init_zero;
    resp.has_callId = id != 0;
    resp.callId = id;
    if (answer_error) {
        resp.error = str_cb(answer_error);
    } else {
        resp.has_returnval = true;
        naogateway_proto_MixedValue *v = &resp.returnval;
        switch (answer.kind) {
        case FR_VALUE_STRING: v->string = str_cb(answer.u.s); break;
        case FR_VALUE_INT: v->has_int_value = true; v->int_value = answer.u.i; break;
        case FR_VALUE_FLOAT: v->has_float_value = true; v->float_value = answer.u.f; break;
        case FR_VALUE_BOOL: v->has_bool_value = true; v->bool_value = answer.u.b; break;
        case FR_VALUE_BINARY:
            v->binary.funcs.encode = write_binary;
            v->binary.arg = &answer;
            break;
        default: break;
        }
    }
    fake_clear_sent();
    fr_poll();
    reference(&naogateway_proto_rpcResponse, &resp);
    CHECK(sent_as_reference(8));
}

static void test_answers(void) {
    fr_settings_t s = settings();
    fake_now = 0;
    CHECK(fr_init(&s) == FR_INIT_OK);
    CHECK(fr_rpc_register("test", "m", handler, NULL));
    fr_poll();
    static uint8_t blob[200];
    for (size_t k = 0; k < sizeof blob; k++) blob[k] = (uint8_t)(255 - k);
    fr_value_t values[8];
    memset(values, 0, sizeof values);
    values[0].kind = FR_VALUE_NONE;
    values[1].kind = FR_VALUE_STRING; values[1].u.s = "done";
    values[2].kind = FR_VALUE_STRING; values[2].u.s = long_text + 1000;
    values[3].kind = FR_VALUE_INT; values[3].u.i = 4294967295u;
    values[4].kind = FR_VALUE_FLOAT; values[4].u.f = -0.125f;
    values[5].kind = FR_VALUE_BOOL; values[5].u.b = false;
    values[6].kind = FR_VALUE_BINARY; values[6].u.bin.data = blob; values[6].u.bin.len = sizeof blob;
    values[7].kind = FR_VALUE_BINARY; values[7].u.bin.data = NULL; values[7].u.bin.len = 0;
    for (size_t k = 0; k < 8; k++) {
        answer = values[k];
        answer_error = NULL;
        call_and_compare((uint32_t)k * 1000u + 1u);
    }
    answer_error = "bad parameters: no";
    call_and_compare(0);
    call_and_compare(300);
    answer_error = NULL;
    answer = values[1];
    call_and_compare(0);
}

int main(void) {
    test_options_and_debug();
    test_answers();
    return DONE();
}
