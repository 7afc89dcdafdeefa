/* firmware/src/fr_debug.c: debug options (docs/protocol.md 6.3 and section 8: pull, push, enable/disable with
 * the a.b.* rule), debug data (6.4) and HaViMo2 frames (6.5). Everything is encoded straight from the caller's
 * memory through nanopb callbacks; nothing is copied. */
#include <string.h>
#include "fr_internal.h"
#include "naogateway/proto/debugging.pb.h"
#include "naogateway/proto/havimo.pb.h"

/** One offered option. */
typedef struct {
    const char *name;
    const char *description;
    fr_option_type_t type;
    bool enabled;
    bool notify; /* switched by the frame being decoded: its callback runs after decoding */
} option_t;

static option_t options[FR_OPTIONS_MAX];
static int option_count;
/** Set by the decoder's callbacks during the applying pass: an option changed. */
static bool changed;

void fr_debug_reset(void) {
    memset(options, 0, sizeof options);
    option_count = 0;
}

int fr_option_add(const char *name, fr_option_type_t type, const char *description) {
    if (option_count >= FR_OPTIONS_MAX || name == NULL) return -1;
    options[option_count].name = name;
    options[option_count].description = description;
    options[option_count].type = type;
    options[option_count].enabled = false;
    return option_count++;
}

bool fr_option_enabled(int index) { return index >= 0 && index < option_count && options[index].enabled; }

/* ---- commands from the gateway ------------------------------------------------------------------------- */

/** Whether `pattern` names option `name`: equal, or `name` starts with `pattern` and a dot (section 8). A pattern
 *  with a zero byte in its `n` bytes names nothing (no name has one); no libc strncmp, which costs 132 B of flash. */
static bool matches(const char *pattern, size_t n, const char *name) {
    for (size_t i = 0; i < n; i++)
        if (name[i] != pattern[i] || name[i] == '\0') return false;
    return name[n] == '\0' || name[n] == '.';
}

/** Markers in the callback's arg: what a name in this list does. */
static const int mode_enable = 1, mode_disable = 0;

/** One name of an optionEnable/optionDisable; `*arg` NULL in the checking pass (the name is only read). */
static bool read_option_name(pb_istream_t *stream, const pb_field_t *field, void **arg) {
    (void)field;
    char name[FR_OPTION_NAME_MAX];
    size_t n = stream->bytes_left;
    if (n >= sizeof name || *arg == NULL) return pb_read(stream, NULL, n); /* longer than any option: no match */
    if (!pb_read(stream, (pb_byte_t *)name, n)) return false;
    name[n] = '\0';
    bool on = *(const int *)*arg == mode_enable;
    for (int k = 0; k < option_count; k++) {
        if (matches(name, n, options[k].name) && options[k].enabled != on) {
            options[k].enabled = on;
            options[k].notify = true; /* told after decoding: the callback may send, which reuses the frame buffer */
            changed = true;
        }
    }
    return true;
}

void fr_debug_prepare(void *commands_struct, bool apply) {
    naogateway_proto_DebuggingCommands *c = (naogateway_proto_DebuggingCommands *)commands_struct;
    c->optionEnable.options.funcs.decode = read_option_name;
    c->optionEnable.options.arg = apply ? (void *)(uintptr_t)&mode_enable : NULL;
    c->optionDisable.options.funcs.decode = read_option_name;
    c->optionDisable.options.arg = apply ? (void *)(uintptr_t)&mode_disable : NULL;
    changed = false;
}

/** Encodes every option of the list (DebuggingOptionList.options). */
static bool write_options(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    (void)arg;
    for (int k = 0; k < option_count; k++) {
        naogateway_proto_DebuggingOption o = naogateway_proto_DebuggingOption_init_zero;
        o.name.funcs.encode = fr_pb_write_string;
        o.name.arg = (void *)(uintptr_t)options[k].name;
        o.has_type = true;
        o.type = (naogateway_proto_DebuggingOptionType)options[k].type;
        o.has_enabled = true;
        o.enabled = options[k].enabled;
        if (options[k].description) {
            o.description.funcs.encode = fr_pb_write_string;
            o.description.arg = (void *)(uintptr_t)options[k].description;
        }
        if (!pb_encode_tag_for_field(stream, field) ||
            !pb_encode_submessage(stream, naogateway_proto_DebuggingOption_fields, &o))
            return false;
    }
    return true;
}

/** Sends the whole option list (optionPush) on `route`. */
static void push(const fr_route_t *route) {
    naogateway_proto_DebuggingCommands c = naogateway_proto_DebuggingCommands_init_zero;
    c.has_optionPush = true;
    c.optionPush.options.funcs.encode = write_options;
    pb_extension_t ext = {&naogateway_proto_debuggingCommands, &c, NULL, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.extensions = &ext;
    (void)fr_send_message(route, &msg);
}

/* Every pull is answered with the list; so is every enable or disable, changed or not (section 8, step 5). */
void fr_debug_after(const void *commands_struct, const fr_route_t *route) {
    const naogateway_proto_DebuggingCommands *c = (const naogateway_proto_DebuggingCommands *)commands_struct;
    for (int k = 0; k < option_count; k++) {
        if (!options[k].notify) continue;
        options[k].notify = false;
        if (fr_state.settings.callbacks.option)
            fr_state.settings.callbacks.option(k, options[k].enabled, fr_state.settings.callbacks.ctx);
    }
    if ((c->has_optionPull && c->optionPull) || c->has_optionEnable || c->has_optionDisable) push(route);
}

/* ---- debug data ---------------------------------------------------------------------------------------- */

/** What the repeated-field callbacks of one DebugData encode. */
typedef struct {
    const void *items;
    size_t count;
} list_t;

/** Sends one DebugData with `d` filled except option and timestamp. */
static bool send_debug(int index, naogateway_proto_DebugData *d) {
    if (!fr_option_enabled(index)) return false;
    d->option.funcs.encode = fr_pb_write_string;
    d->option.arg = (void *)(uintptr_t)options[index].name;
    d->has_timestamp = true;
    d->timestamp = fr_uptime_ms();
    pb_extension_t ext = {&naogateway_proto_debugData, d, NULL, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.extensions = &ext;
    fr_route_t route = fr_route_gateway();
    return fr_send_message(&route, &msg);
}

bool fr_debug_text(int index, const char *text) {
    naogateway_proto_DebugData d = naogateway_proto_DebugData_init_zero;
    d.which_data = naogateway_proto_DebugData_text_tag;
    d.data.text.text.funcs.encode = fr_pb_write_string;
    d.data.text.text.arg = (void *)(uintptr_t)text;
    return send_debug(index, &d);
}

/** Encodes the rows of a DebugTable from a list_t of fr_table_row_t. */
static bool write_rows(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const fr_table_row_t *rows = (const fr_table_row_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_DebugTable_Row r = naogateway_proto_DebugTable_Row_init_zero;
        r.key.funcs.encode = r.value.funcs.encode = fr_pb_write_string;
        r.key.arg = (void *)(uintptr_t)rows[k].key;
        r.value.arg = (void *)(uintptr_t)rows[k].value;
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_DebugTable_Row_fields, &r))
            return false;
    }
    return true;
}

bool fr_debug_table(int index, const fr_table_row_t *rows, size_t count) {
    list_t l = {rows, count};
    naogateway_proto_DebugData d = naogateway_proto_DebugData_init_zero;
    d.which_data = naogateway_proto_DebugData_table_tag;
    d.data.table.rows.funcs.encode = write_rows;
    d.data.table.rows.arg = &l;
    return send_debug(index, &d);
}

/** Encodes the samples of a DebugPlot from a list_t of fr_plot_sample_t. */
static bool write_samples(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const fr_plot_sample_t *s = (const fr_plot_sample_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_DebugPlot_Sample m = naogateway_proto_DebugPlot_Sample_init_zero;
        m.series.funcs.encode = fr_pb_write_string;
        m.series.arg = (void *)(uintptr_t)s[k].series;
        m.value = s[k].value;
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_DebugPlot_Sample_fields, &m))
            return false;
    }
    return true;
}

bool fr_debug_plot(int index, const fr_plot_sample_t *samples, size_t count) {
    list_t l = {samples, count};
    naogateway_proto_DebugData d = naogateway_proto_DebugData_init_zero;
    d.which_data = naogateway_proto_DebugData_plot_tag;
    d.data.plot.samples.funcs.encode = write_samples;
    d.data.plot.samples.arg = &l;
    return send_debug(index, &d);
}

/** Encodes the objects of a DebugRelativePosition from a list_t of fr_relative_t. */
static bool write_objects(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const fr_relative_t *o = (const fr_relative_t *)l->items;
    for (size_t k = 0; k < l->count; k++) {
        naogateway_proto_DebugRelativePosition_RelativeObject m = naogateway_proto_DebugRelativePosition_RelativeObject_init_zero;
        m.name.funcs.encode = fr_pb_write_string;
        m.name.arg = (void *)(uintptr_t)o[k].name;
        m.distance = o[k].distance;
        m.angle = o[k].angle;
        if (!pb_encode_tag_for_field(stream, field) ||
            !pb_encode_submessage(stream, naogateway_proto_DebugRelativePosition_RelativeObject_fields, &m))
            return false;
    }
    return true;
}

bool fr_debug_relative(int index, const fr_relative_t *objects, size_t count) {
    list_t l = {objects, count};
    naogateway_proto_DebugData d = naogateway_proto_DebugData_init_zero;
    d.which_data = naogateway_proto_DebugData_relativePosition_tag;
    d.data.relativePosition.objects.funcs.encode = write_objects;
    d.data.relativePosition.objects.arg = &l;
    return send_debug(index, &d);
}

/** Encodes shapes (a field drawing or an image overlay) from a list_t of fr_shape_t. */
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
        if (s[k].label) {
            m.label.funcs.encode = fr_pb_write_string;
            m.label.arg = (void *)(uintptr_t)s[k].label;
        }
        if (!pb_encode_tag_for_field(stream, field) || !pb_encode_submessage(stream, naogateway_proto_Shape_fields, &m))
            return false;
    }
    return true;
}

bool fr_debug_field(int index, const fr_shape_t *shapes, size_t count) {
    list_t l = {shapes, count};
    naogateway_proto_DebugData d = naogateway_proto_DebugData_init_zero;
    d.which_data = naogateway_proto_DebugData_fieldDrawing_tag;
    d.data.fieldDrawing.shapes.funcs.encode = write_shapes;
    d.data.fieldDrawing.shapes.arg = &l;
    return send_debug(index, &d);
}

/** Encodes a bytes field from a list_t of bytes. */
static bool write_bytes(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    return pb_encode_tag_for_field(stream, field) && pb_encode_string(stream, (const pb_byte_t *)l->items, l->count);
}

bool fr_debug_image(int index, uint32_t width, uint32_t height, uint8_t format, const uint8_t *pixels,
                    size_t pixel_len, const fr_shape_t *overlay, size_t overlay_count) {
    list_t px = {pixels, pixel_len}, ov = {overlay, overlay_count};
    naogateway_proto_DebugData d = naogateway_proto_DebugData_init_zero;
    d.which_data = naogateway_proto_DebugData_image_tag;
    d.data.image.width = width;
    d.data.image.height = height;
    d.data.image.has_format = true;
    d.data.image.format = (naogateway_proto_DebugImage_Format)format;
    if (pixels) {
        d.data.image.pixels.funcs.encode = write_bytes;
        d.data.image.pixels.arg = &px;
    }
    d.data.image.overlay.funcs.encode = write_shapes;
    d.data.image.overlay.arg = &ov;
    return send_debug(index, &d);
}

/* ---- HaViMo2 ------------------------------------------------------------------------------------------- */

/** The region records without unused slots (index byte 0), as one bytes field. */
static bool write_records(pb_ostream_t *stream, const pb_field_t *field, void *const *arg) {
    const list_t *l = (const list_t *)*arg;
    const uint8_t *r = (const uint8_t *)l->items;
    size_t used = 0;
    for (size_t k = 0; k < l->count; k++) if (r[k * FR_HAVIMO_RECORD_SIZE] != 0) used++;
    if (!pb_encode_tag_for_field(stream, field) || !pb_encode_varint(stream, used * FR_HAVIMO_RECORD_SIZE)) return false;
    for (size_t k = 0; k < l->count; k++)
        if (r[k * FR_HAVIMO_RECORD_SIZE] != 0 && !pb_write(stream, r + k * FR_HAVIMO_RECORD_SIZE, FR_HAVIMO_RECORD_SIZE))
            return false;
    return true;
}

bool fr_havimo_regions(int index, uint32_t frame, const uint8_t *records, size_t count) {
    if (!fr_option_enabled(index)) return false;
    if (count > FR_HAVIMO_REGIONS_MAX) count = FR_HAVIMO_REGIONS_MAX;
    list_t l = {records, count};
    naogateway_proto_HaViMoRegionFrame f = naogateway_proto_HaViMoRegionFrame_init_zero;
    f.frame = frame;
    f.has_timestamp = true;
    f.timestamp = fr_uptime_ms();
    f.records.funcs.encode = write_records;
    f.records.arg = &l;
    pb_extension_t ext = {&naogateway_proto_havimoRegions, &f, NULL, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.extensions = &ext;
    fr_route_t route = fr_route_gateway();
    return fr_send_message(&route, &msg);
}

bool fr_havimo_grid(int index, uint32_t frame, const uint8_t *cells) {
    if (!fr_option_enabled(index)) return false;
    list_t l = {cells, FR_HAVIMO_GRID_SIZE};
    naogateway_proto_HaViMoGridFrame f = naogateway_proto_HaViMoGridFrame_init_zero;
    f.frame = frame;
    f.has_timestamp = true;
    f.timestamp = fr_uptime_ms();
    f.cells.funcs.encode = write_bytes;
    f.cells.arg = &l;
    pb_extension_t ext = {&naogateway_proto_havimoGrid, &f, NULL, true};
    naogateway_proto_Message msg = naogateway_proto_Message_init_zero;
    msg.extensions = &ext;
    fr_route_t route = fr_route_gateway();
    return fr_send_message(&route, &msg);
}
