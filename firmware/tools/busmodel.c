/* firmware/tools/busmodel.c: the emulated bus of busmodel.h. The AX-12A control table, status-return levels and
 * error bits follow ROBOTIS's AX-12A e-manual; the HaViMo2 answers the instructions docs/firmware.md lists (capture
 * 0x0E or a write to address 0, ping while busy unanswered, region records at 16 * (i + 1), CAP_GRID 0x15,
 * READ_GRID 0x16 with its address in 16-byte units). The return delay is kept in the table but not waited: a host's
 * scheduler is coarser than 2 microseconds. */
#include <string.h>
#include "busmodel.h"

#define ERR_RANGE 0x08u
#define ERR_CHECKSUM 0x10u
#define ERR_INSTRUCTION 0x40u

/** One AX-12A: its table and where it really is (a fraction of a unit). */
typedef struct {
    uint8_t t[BUSMODEL_TABLE];
    float pos;
    bool silent;
    bool reg_pending;
    uint8_t reg_addr, reg_len, reg_data[BUSMODEL_TABLE];
} servo_t;

static servo_t servos[BUSMODEL_SERVOS];

static struct {
    uint8_t table[256];      /* 0..15 the camera's own, 16 * (i + 1) region i */
    uint8_t grid[768];
    uint32_t busy_until;
    bool busy;
    uint8_t status_return;
} cam;

static uint8_t in_buf[300];
static size_t in_len;
static uint32_t last_ms;
static bool corrupt_next;
static size_t cut_next;
static uint8_t corrupt_id, cut_id;
static size_t babble_n;
static uint8_t babble_byte;
static busmodel_counters_t counters;

const busmodel_counters_t *busmodel_counters(void) { return &counters; }

/** The AX-12A factory table for `id`, centred. */
static void servo_defaults(servo_t *s, uint8_t id) {
    static const uint8_t rom[BUSMODEL_TABLE] = {
        12, 0, 24, 1, 1, 250, 0, 0, 0xFF, 0x03, 0, 70, 60, 140, 0xFF, 0x03, 2, 36, 36, 0,
        0, 0, 0, 0, 0, 0, 1, 1, 32, 32, 0x00, 0x02, 0, 0, 0xFF, 0x03, 0x00, 0x02, 0, 0,
        0, 0, 120, 36, 0, 0, 0, 0, 32, 0};
    memcpy(s->t, rom, sizeof rom);
    s->t[3] = id;
    s->pos = 512.0f;
    s->silent = false;
    s->reg_pending = false;
}

void busmodel_init(uint32_t now_ms) {
    for (int k = 0; k < BUSMODEL_SERVOS; k++) servo_defaults(&servos[k], (uint8_t)(k + 1));
    memset(&cam, 0, sizeof cam);
    cam.table[2] = 2;  /* firmware version */
    cam.table[3] = BUSMODEL_HAVIMO_ID;
    cam.status_return = 2;
    in_len = 0;
    memset(&counters, 0, sizeof counters);
    last_ms = now_ms;
    corrupt_next = false;
    cut_next = 0;
    babble_n = 0;
}

/** The servo with `id` on the bus, or NULL. */
static servo_t *servo_of(uint8_t id) {
    for (int k = 0; k < BUSMODEL_SERVOS; k++) if (servos[k].t[3] == id) return &servos[k];
    return NULL;
}

uint8_t *busmodel_servo(uint8_t id) {
    servo_t *s = servo_of(id);
    return s ? s->t : NULL;
}

void busmodel_silent(uint8_t id, bool silent) {
    servo_t *s = servo_of(id);
    if (s) s->silent = silent;
}
void busmodel_corrupt_next(uint8_t id) { corrupt_next = true; corrupt_id = id; }
void busmodel_cut_next(uint8_t id, size_t keep) { cut_next = keep; cut_id = id; }
void busmodel_babble(size_t n, uint8_t byte) { babble_n = n; babble_byte = byte; }

/** A little-endian 16-bit value of the table at `a`. */
static uint16_t word(const uint8_t *t, int a) { return (uint16_t)(t[a] | t[a + 1] << 8); }
/** Stores a little-endian 16-bit value at `a`. */
static void set_word(uint8_t *t, int a, uint16_t v) { t[a] = (uint8_t)v; t[a + 1] = (uint8_t)(v >> 8); }

/** The scene at `now`: the orange ball (colour 1) rolls left to right and back, the green field (colour 2) below. */
static void scene(uint32_t now, bool grid) {
    int period = 4000, phase = (int)(now % (uint32_t)period);
    int bx = 15 + (phase < period / 2 ? phase : period - phase) * 130 / (period / 2), by = 55, r = 8;
    uint32_t bsx = 0, bsy = 0, fsx = 0, fsy = 0;
    uint16_t bn = 0, fn = 0;
    uint8_t bminx = 255, bmaxx = 0, bminy = 255, bmaxy = 0;
    uint8_t counts[768][2];
    memset(counts, 0, sizeof counts);
    for (int y = 0; y < 120; y++)
        for (int x = 0; x < 160; x++) {
            int dx = x - bx, dy = y - by, c = 0;
            if (dx * dx + dy * dy <= r * r) c = 1;
            else if (y >= 80) c = 2;
            if (c == 0) continue;
            int cell = x / 5 + 32 * (y / 5);
            if (counts[cell][c - 1] < 255) counts[cell][c - 1]++;
            if (c == 1) {
                bn++; bsx += (uint32_t)x; bsy += (uint32_t)y;
                if (x < bminx) bminx = (uint8_t)x;
                if (x > bmaxx) bmaxx = (uint8_t)x;
                if (y < bminy) bminy = (uint8_t)y;
                if (y > bmaxy) bmaxy = (uint8_t)y;
            } else {
                fn++; fsx += (uint32_t)x; fsy += (uint32_t)y;
            }
        }
    memset(cam.table + 16, 0, 240);
    const struct { uint8_t colour; uint16_t n; uint32_t sx, sy; uint8_t maxx, minx, maxy, miny; } regions[2] = {
        {1, bn, bsx, bsy, bmaxx, bminx, bmaxy, bminy}, {2, fn, fsx, fsy, 159, 0, 119, 80}};
    for (int k = 0; k < 2; k++) {
        uint8_t *rec = cam.table + 16 * (k + 1);
        rec[0] = (uint8_t)(k + 1);
        rec[1] = regions[k].colour;
        set_word(rec, 2, regions[k].n);
        for (int b = 0; b < 4; b++) { rec[4 + b] = (uint8_t)(regions[k].sx >> (8 * b)); rec[8 + b] = (uint8_t)(regions[k].sy >> (8 * b)); }
        rec[12] = regions[k].maxx; rec[13] = regions[k].minx; rec[14] = regions[k].maxy; rec[15] = regions[k].miny;
    }
    if (!grid) return;
    for (int cell = 0; cell < 768; cell++) {
        /* the lower colour index dominates a cell (HaViMo2 datasheet); at most 15 pixels are reported */
        int c = counts[cell][0] ? 1 : counts[cell][1] ? 2 : 0;
        int n = c ? counts[cell][c - 1] : 0;
        cam.grid[cell] = (uint8_t)((n > 15 ? 15 : n) << 4 | c);
    }
}

void busmodel_step(uint32_t now_ms) {
    uint32_t dt = now_ms - last_ms;
    if (dt > 1000u) dt = 1000u;
    last_ms = now_ms;
    for (int k = 0; k < BUSMODEL_SERVOS; k++) {
        servo_t *s = &servos[k];
        float goal = (float)(word(s->t, 30) & 0x3FFu);
        uint16_t speed = word(s->t, 32) & 0x3FFu;
        /* 0.111 rpm per unit, 0.29 degrees per position unit; 0 = as fast as it can (about 114 rpm) */
        float per_ms = (speed == 0 ? 114.0f : (float)speed * 0.111f) * 6.0f / 0.29f / 1000.0f;
        float step = per_ms * (float)dt, d = goal - s->pos;
        bool moving = s->t[24] && (d > 0.5f || d < -0.5f);
        if (s->t[24]) s->pos = d > step ? s->pos + step : d < -step ? s->pos - step : goal;
        uint16_t p = (uint16_t)(s->pos + 0.5f);
        set_word(s->t, 36, p);
        set_word(s->t, 38, moving ? (uint16_t)(speed == 0 ? 1023 : speed) | (d < 0 ? 0x400u : 0u) : 0);
        set_word(s->t, 40, (uint16_t)((moving ? 180u : 12u) | (d < 0 ? 0x400u : 0u)));
        s->t[42] = 120;
        s->t[43] = (uint8_t)(36 + k % 4);
        s->t[46] = moving ? 1 : 0;
    }
    if (cam.busy && (int32_t)(now_ms - cam.busy_until) >= 0) cam.busy = false;
}

/** Appends a status packet from `id` with `error` and `n` parameters to out, with the test faults applied. */
static size_t status(uint8_t id, uint8_t error, const uint8_t *params, size_t n, uint8_t *out, size_t cap) {
    uint8_t p[260];
    if (n > 253) n = 253;
    p[0] = p[1] = 0xFF;
    p[2] = id;
    p[3] = (uint8_t)(n + 2);
    p[4] = error;
    if (n) memcpy(p + 5, params, n);
    uint32_t sum = 0;
    for (size_t k = 2; k < n + 5; k++) sum += p[k];
    p[n + 5] = (uint8_t)~sum;
    size_t len = n + 6;
    if (corrupt_next && corrupt_id == id) { p[n + 5] ^= 0x5A; corrupt_next = false; }
    if (cut_next && cut_id == id) { if (cut_next < len) len = cut_next; cut_next = 0; }
    if (len > cap) len = cap;
    memcpy(out, p, len);
    return len;
}

/** Whether a servo at return level `level` answers instruction `inst` (0: ping only, 1: ping and read, 2: all). */
static bool answers(uint8_t level, uint8_t inst) { return inst == 0x01 || level >= 2 || (level == 1 && inst == 0x02); }

/** Writes `n` bytes at `addr` of a servo's table; the error byte (range when read-only or beyond the table). */
static uint8_t servo_write(servo_t *s, uint8_t addr, const uint8_t *data, size_t n) {
    if (n == 0 || addr + n > BUSMODEL_TABLE) return ERR_RANGE;
    for (size_t k = 0; k < n; k++) {
        int a = addr + (int)k;
        if (a <= 2 || (a >= 36 && a <= 43) || a == 45 || a == 46) return ERR_RANGE;
    }
    memcpy(s->t + addr, data, n);
    if (addr <= 31 && addr + n > 30) s->t[24] = 1; /* a goal position switches the torque on */
    return 0;
}

/** Executes one whole instruction packet `p` of `len` bytes whose checksum is `ok`. */
static size_t execute(const uint8_t *p, size_t len, bool ok, uint8_t *out, size_t cap, uint32_t now) {
    uint8_t id = p[2], inst = p[4];
    const uint8_t *prm = p + 5;
    size_t n = len - 6;
    counters.packets++;
    if (id == 0xFE) {
        if (!ok) return 0;
        if (inst == 0x83 && n >= 2) { /* sync write: address, length, then id and data per servo */
            uint8_t addr = prm[0], l = prm[1];
            for (size_t k = 2; l > 0 && k + 1u + l <= n; k += 1u + l) {
                servo_t *s = servo_of(prm[k]);
                if (s) (void)servo_write(s, addr, prm + k + 1, l);
            }
        } else if (inst == 0x05) {
            for (int k = 0; k < BUSMODEL_SERVOS; k++)
                if (servos[k].reg_pending) {
                    (void)servo_write(&servos[k], servos[k].reg_addr, servos[k].reg_data, servos[k].reg_len);
                    servos[k].reg_pending = false;
                }
        } else if (inst == 0x03 && n >= 2) {
            for (int k = 0; k < BUSMODEL_SERVOS; k++) (void)servo_write(&servos[k], prm[0], prm + 1, n - 1);
        }
        return 0;
    }
    if (id == BUSMODEL_HAVIMO_ID) {
        if (cam.busy) return 0; /* working: it answers nothing until the frame is processed */
        if (!ok) return status(id, ERR_CHECKSUM, NULL, 0, out, cap);
        switch (inst) {
        case 0x01: return status(id, 0, NULL, 0, out, cap);
        case 0x0E:
        case 0x15:
            counters.captures++;
            scene(now, inst == 0x15);
            cam.busy = true;
            cam.busy_until = now + BUSMODEL_CAPTURE_MS;
            return 0; /* no status packet for a capture */
        case 0x03:
            if (n >= 2 && prm[0] == 0) { /* a write to address 0 starts a capture too (public CM-5x0 examples) */
                counters.captures++;
                scene(now, false);
                cam.busy = true;
                cam.busy_until = now + BUSMODEL_CAPTURE_MS;
                return 0;
            }
            return status(id, ERR_RANGE, NULL, 0, out, cap);
        case 0x02:
            if (n != 2 || prm[0] + prm[1] > 256) return status(id, ERR_RANGE, NULL, 0, out, cap);
            return status(id, 0, cam.table + prm[0], prm[1], out, cap);
        case 0x16:
            if (n != 2 || prm[0] * 16 + prm[1] > 768) return status(id, ERR_RANGE, NULL, 0, out, cap);
            return status(id, 0, cam.grid + prm[0] * 16, prm[1], out, cap);
        default: return status(id, ERR_INSTRUCTION, NULL, 0, out, cap);
        }
    }
    servo_t *s = servo_of(id);
    if (s == NULL || s->silent) return 0;
    if (!ok) return status(id, ERR_CHECKSUM, NULL, 0, out, cap);
    uint8_t level = s->t[16];
    uint8_t err = 0;
    switch (inst) {
    case 0x01: return status(id, 0, NULL, 0, out, cap);
    case 0x02:
        if (n != 2 || prm[1] == 0 || prm[0] + prm[1] > BUSMODEL_TABLE) err = ERR_RANGE;
        else if (answers(level, inst)) {
            int index = (int)(s - servos);
            counters.servo_reads[index]++;
            return status(id, 0, s->t + prm[0], prm[1], out, cap);
        }
        else return 0;
        break;
    case 0x03: err = n >= 2 ? servo_write(s, prm[0], prm + 1, n - 1) : ERR_RANGE; break;
    case 0x04:
        if (n >= 2 && prm[0] + n - 1 <= BUSMODEL_TABLE) {
            s->reg_pending = true;
            s->reg_addr = prm[0];
            s->reg_len = (uint8_t)(n - 1);
            memcpy(s->reg_data, prm + 1, n - 1);
        } else {
            err = ERR_RANGE;
        }
        break;
    case 0x05:
        if (s->reg_pending) err = servo_write(s, s->reg_addr, s->reg_data, s->reg_len);
        s->reg_pending = false;
        break;
    case 0x06: servo_defaults(s, 1); break; /* factory reset: id 1 again, as the AX-12A does */
    default: err = ERR_INSTRUCTION; break;
    }
    return answers(level, inst) ? status(id, err, NULL, 0, out, cap) : 0;
}

size_t busmodel_feed(const uint8_t *in, size_t len, uint8_t *out, size_t cap, uint32_t now_ms) {
    size_t produced = 0;
    busmodel_step(now_ms);
    for (size_t k = 0; k < len; k++) {
        if (in_len == sizeof in_buf) in_len = 0; /* no packet is that long: start afresh */
        in_buf[in_len++] = in[k];
        for (;;) {
            size_t p = 0;
            while (p + 1 < in_len && !(in_buf[p] == 0xFF && in_buf[p + 1] == 0xFF && (p + 2 >= in_len || in_buf[p + 2] != 0xFF))) p++;
            if (p > 0) { memmove(in_buf, in_buf + p, in_len - p); in_len -= p; }
            if (in_len < 4) break;
            size_t total = (size_t)in_buf[3] + 4;
            if (in_buf[3] < 2) { memmove(in_buf, in_buf + 1, --in_len); continue; }
            if (in_len < total) break;
            uint32_t sum = 0;
            for (size_t i = 2; i + 1 < total; i++) sum += in_buf[i];
            bool ok = (uint8_t)~sum == in_buf[total - 1];
            size_t n = execute(in_buf, total, ok, out + produced, cap - produced, now_ms);
            if (babble_n > 0 && n > 0) {
                n = babble_n < cap - produced ? babble_n : cap - produced;
                memset(out + produced, babble_byte, n);
            }
            produced += n;
            memmove(in_buf, in_buf + total, in_len - total);
            in_len -= total;
        }
    }
    return produced;
}
