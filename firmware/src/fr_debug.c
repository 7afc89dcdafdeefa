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

/** One name of an optionEnable/optionDisable; `arg` NULL in the checking pass (the name is only read). */
static bool read_option_name(pb_istream_t *stream, void *arg) {
    char name[FR_OPTION_NAME_MAX];
    size_t n = stream->bytes_left;
    if (n >= sizeof name || arg == NULL) return pb_read(stream, NULL, n); /* longer than any option: no match */
    if (!pb_read(stream, (pb_byte_t *)name, n)) return false;
    name[n] = '\0';
    bool on = *(const int *)arg == mode_enable;
    for (int k = 0; k < option_count; k++) {
        if (matches(name, n, options[k].name) && options[k].enabled != on) {
            options[k].enabled = on;
            options[k].notify = true; /* told after decoding: the callback may send, which reuses the frame buffer */
            changed = true;
        }
    }
    return true;
}

/** What a frame's DebuggingCommands asked for, and whether its names switch options (the second pass). */
static struct {
    bool apply;
    bool pull, push, enable, disable; /* optionPull true, and which submessages were present */
} commands;

/** The field of a DebuggingOptionNames (its names) or a DebuggingOptionList (its options, read over). */
static int names_field(pb_istream_t *s, uint32_t tag, pb_wire_type_t wire, void *ctx) {
    if (tag != 1) return 0;
    if (ctx == NULL) return fr_in_callback(s, wire, NULL, NULL) ? 1 : -1;
    return fr_in_callback(s, wire, read_option_name, commands.apply ? ctx : NULL) ? 1 : -1;
}

/** One field of a DebuggingCommands (debugging.proto). */
static int commands_field(pb_istream_t *s, uint32_t tag, pb_wire_type_t wire, void *ctx) {
    (void)ctx;
    switch (tag) {
    case naogateway_proto_DebuggingCommands_optionPull_tag:
        return wire == PB_WT_VARINT && pb_decode_bool(s, &commands.pull) ? 1 : -1;
    case naogateway_proto_DebuggingCommands_optionPush_tag:
        commands.push = true;
        return fr_in_submessage(s, wire, names_field, NULL) ? 1 : -1;
    case naogateway_proto_DebuggingCommands_optionEnable_tag:
        commands.enable = true;
        return fr_in_submessage(s, wire, names_field, (void *)(uintptr_t)&mode_enable) ? 1 : -1;
    case naogateway_proto_DebuggingCommands_optionDisable_tag:
        commands.disable = true;
        return fr_in_submessage(s, wire, names_field, (void *)(uintptr_t)&mode_disable) ? 1 : -1;
    default: return 0;
    }
}

void fr_debug_prepare(bool apply) {
    memset(&commands, 0, sizeof commands);
    commands.apply = apply;
    changed = false;
}

bool fr_debug_read(pb_istream_t *s, pb_wire_type_t wire) { return fr_in_submessage(s, wire, commands_field, NULL); }

/** Sends the whole option list (optionPush) on `route`. */
static void push(const fr_route_t *route) {
    fr_out_t w;
    if (!fr_out_begin(&w, route)) return;
    uint8_t *cmd = fr_out_open(&w, naogateway_proto_debuggingCommands_tag);
    uint8_t *list = fr_out_open(&w, naogateway_proto_DebuggingCommands_optionPush_tag);
    for (int k = 0; k < option_count; k++) {
        uint8_t *o = fr_out_open(&w, naogateway_proto_DebuggingOptionList_options_tag);
        fr_out_string(&w, naogateway_proto_DebuggingOption_name_tag, options[k].name);
        fr_out_int(&w, naogateway_proto_DebuggingOption_type_tag, (int32_t)options[k].type);
        fr_out_uint(&w, naogateway_proto_DebuggingOption_enabled_tag, options[k].enabled);
        fr_out_string(&w, naogateway_proto_DebuggingOption_description_tag, options[k].description);
        fr_out_close(&w, o);
    }
    fr_out_close(&w, list);
    fr_out_close(&w, cmd);
    (void)fr_out_send(&w, route);
}

/* Every pull is answered with the list; so is every enable or disable, changed or not (section 8, step 5). */
void fr_debug_after(const fr_route_t *route) {
    for (int k = 0; k < option_count; k++) {
        if (!options[k].notify) continue;
        options[k].notify = false;
        if (fr_state.settings.callbacks.option)
            fr_state.settings.callbacks.option(k, options[k].enabled, fr_state.settings.callbacks.ctx);
    }
    if (commands.pull || commands.enable || commands.disable) push(route);
}

/* ---- debug data ---------------------------------------------------------------------------------------- */

/** Starts a DebugData frame for option `index` to the gateway: its option name and timestamp written, the data's
 *  submessage (oneof field `data_tag`) opened at `*data`; false when the option is off or nothing may be sent. */
static bool debug_begin(fr_out_t *w, int index, uint32_t data_tag, uint8_t **ext, uint8_t **data) {
    if (!fr_option_enabled(index)) return false;
    fr_route_t route = fr_route_gateway();
    if (!fr_out_begin(w, &route)) return false;
    *ext = fr_out_open(w, naogateway_proto_debugData_tag);
    fr_out_string(w, naogateway_proto_DebugData_option_tag, options[index].name);
    fr_out_uint(w, naogateway_proto_DebugData_timestamp_tag, fr_uptime_ms());
    *data = fr_out_open(w, data_tag);
    return true;
}

/** Closes what debug_begin opened and sends the frame to the gateway. */
static bool debug_send(fr_out_t *w, uint8_t *ext, uint8_t *data) {
    fr_out_close(w, data);
    fr_out_close(w, ext);
    fr_route_t route = fr_route_gateway();
    return fr_out_send(w, &route);
}

bool fr_debug_text(int index, const char *text) {
    fr_out_t w;
    uint8_t *ext, *data;
    if (!debug_begin(&w, index, naogateway_proto_DebugData_text_tag, &ext, &data)) return false;
    fr_out_string(&w, naogateway_proto_DebugText_text_tag, text);
    return debug_send(&w, ext, data);
}

bool fr_debug_table(int index, const fr_table_row_t *rows, size_t count) {
    fr_out_t w;
    uint8_t *ext, *data;
    if (!debug_begin(&w, index, naogateway_proto_DebugData_table_tag, &ext, &data)) return false;
    for (size_t k = 0; k < count; k++) {
        uint8_t *r = fr_out_open(&w, naogateway_proto_DebugTable_rows_tag);
        fr_out_string(&w, naogateway_proto_DebugTable_Row_key_tag, rows[k].key);
        fr_out_string(&w, naogateway_proto_DebugTable_Row_value_tag, rows[k].value);
        fr_out_close(&w, r);
    }
    return debug_send(&w, ext, data);
}

bool fr_debug_plot(int index, const fr_plot_sample_t *samples, size_t count) {
    fr_out_t w;
    uint8_t *ext, *data;
    if (!debug_begin(&w, index, naogateway_proto_DebugData_plot_tag, &ext, &data)) return false;
    for (size_t k = 0; k < count; k++) {
        uint8_t *m = fr_out_open(&w, naogateway_proto_DebugPlot_samples_tag);
        fr_out_string(&w, naogateway_proto_DebugPlot_Sample_series_tag, samples[k].series);
        fr_out_float(&w, naogateway_proto_DebugPlot_Sample_value_tag, samples[k].value);
        fr_out_close(&w, m);
    }
    return debug_send(&w, ext, data);
}

bool fr_debug_relative(int index, const fr_relative_t *objects, size_t count) {
    fr_out_t w;
    uint8_t *ext, *data;
    if (!debug_begin(&w, index, naogateway_proto_DebugData_relativePosition_tag, &ext, &data)) return false;
    for (size_t k = 0; k < count; k++) {
        uint8_t *m = fr_out_open(&w, naogateway_proto_DebugRelativePosition_objects_tag);
        fr_out_string(&w, naogateway_proto_DebugRelativePosition_RelativeObject_name_tag, objects[k].name);
        fr_out_uint(&w, naogateway_proto_DebugRelativePosition_RelativeObject_distance_tag, objects[k].distance);
        fr_out_float(&w, naogateway_proto_DebugRelativePosition_RelativeObject_angle_tag, objects[k].angle);
        fr_out_close(&w, m);
    }
    return debug_send(&w, ext, data);
}

/** Writes shapes as repeated field `field` (a field drawing's shapes or an image's overlay). */
static void write_shapes(fr_out_t *w, uint32_t field, const fr_shape_t *s, size_t count) {
    for (size_t k = 0; k < count; k++) {
        uint8_t *m = fr_out_open(w, field);
        fr_out_int(w, naogateway_proto_Shape_kind_tag, s[k].kind);
        fr_out_sint(w, naogateway_proto_Shape_x1_tag, s[k].x1);
        fr_out_sint(w, naogateway_proto_Shape_y1_tag, s[k].y1);
        if (s[k].has_second) {
            fr_out_sint(w, naogateway_proto_Shape_x2_tag, s[k].x2);
            fr_out_sint(w, naogateway_proto_Shape_y2_tag, s[k].y2);
        }
        if (s[k].radius > 0) fr_out_uint(w, naogateway_proto_Shape_radius_tag, s[k].radius);
        if (s[k].has_colour) {
            uint8_t *c = fr_out_open(w, naogateway_proto_Shape_colour_tag);
            fr_out_uint(w, naogateway_proto_Colour_r_tag, s[k].r);
            fr_out_uint(w, naogateway_proto_Colour_g_tag, s[k].g);
            fr_out_uint(w, naogateway_proto_Colour_b_tag, s[k].b);
            fr_out_close(w, c);
        }
        fr_out_string(w, naogateway_proto_Shape_label_tag, s[k].label);
        fr_out_close(w, m);
    }
}

bool fr_debug_field(int index, const fr_shape_t *shapes, size_t count) {
    fr_out_t w;
    uint8_t *ext, *data;
    if (!debug_begin(&w, index, naogateway_proto_DebugData_fieldDrawing_tag, &ext, &data)) return false;
    write_shapes(&w, naogateway_proto_DebugFieldDrawing_shapes_tag, shapes, count);
    return debug_send(&w, ext, data);
}

bool fr_debug_image(int index, uint32_t width, uint32_t height, uint8_t format, const uint8_t *pixels,
                    size_t pixel_len, const fr_shape_t *overlay, size_t overlay_count) {
    fr_out_t w;
    uint8_t *ext, *data;
    if (!debug_begin(&w, index, naogateway_proto_DebugData_image_tag, &ext, &data)) return false;
    fr_out_uint(&w, naogateway_proto_DebugImage_width_tag, width);
    fr_out_uint(&w, naogateway_proto_DebugImage_height_tag, height);
    fr_out_uint(&w, naogateway_proto_DebugImage_format_tag, format);
    if (pixels) fr_out_bytes(&w, naogateway_proto_DebugImage_pixels_tag, pixels, pixel_len);
    write_shapes(&w, naogateway_proto_DebugImage_overlay_tag, overlay, overlay_count);
    return debug_send(&w, ext, data);
}

/* ---- HaViMo2 ------------------------------------------------------------------------------------------- */

bool fr_havimo_regions(int index, uint32_t frame, const uint8_t *records, size_t count) {
    if (!fr_option_enabled(index)) return false;
    if (count > FR_HAVIMO_REGIONS_MAX) count = FR_HAVIMO_REGIONS_MAX;
    fr_route_t route = fr_route_gateway();
    fr_out_t w;
    if (!fr_out_begin(&w, &route)) return false;
    uint8_t *ext = fr_out_open(&w, naogateway_proto_havimoRegions_tag);
    fr_out_uint(&w, naogateway_proto_HaViMoRegionFrame_frame_tag, frame);
    fr_out_uint(&w, naogateway_proto_HaViMoRegionFrame_timestamp_tag, fr_uptime_ms());
    /* the region records without unused slots (index byte 0), as one bytes field */
    size_t used = 0;
    for (size_t k = 0; k < count; k++) if (records[k * FR_HAVIMO_RECORD_SIZE] != 0) used++;
    fr_out_varint(&w, naogateway_proto_HaViMoRegionFrame_records_tag << 3 | 2u);
    fr_out_varint(&w, used * FR_HAVIMO_RECORD_SIZE);
    for (size_t k = 0; k < count; k++)
        if (records[k * FR_HAVIMO_RECORD_SIZE] != 0) fr_out_raw(&w, records + k * FR_HAVIMO_RECORD_SIZE, FR_HAVIMO_RECORD_SIZE);
    fr_out_close(&w, ext);
    return fr_out_send(&w, &route);
}

bool fr_havimo_grid(int index, uint32_t frame, const uint8_t *cells) {
    if (!fr_option_enabled(index)) return false;
    fr_route_t route = fr_route_gateway();
    fr_out_t w;
    if (!fr_out_begin(&w, &route)) return false;
    uint8_t *ext = fr_out_open(&w, naogateway_proto_havimoGrid_tag);
    fr_out_uint(&w, naogateway_proto_HaViMoGridFrame_frame_tag, frame);
    fr_out_uint(&w, naogateway_proto_HaViMoGridFrame_timestamp_tag, fr_uptime_ms());
    fr_out_bytes(&w, naogateway_proto_HaViMoGridFrame_cells_tag, cells, FR_HAVIMO_GRID_SIZE);
    fr_out_close(&w, ext);
    return fr_out_send(&w, &route);
}
