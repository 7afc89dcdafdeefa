/* firmware/src/fr_gc.c: GameController control packets and the robot's return packet (docs/protocol.md
 * section 10). Versions 7 and 8 as protocol.md 10.1 and 10.2 give them; 12 (the humanoid league's
 * HL_RoboCupGameControlData.h, 2017-2019: 11 players, a 253-byte coach message), 19 (the Humanoid Soccer
 * League's RoboCupGameControlData.h of early 2026: 20 players of 4 bytes) and 20 (its GameController 7, RoboCup
 * 2026: the same 18-byte header, 20 players of 3 bytes) as their official headers lay them out, little-endian
 * and without padding beyond the headers' natural alignment. Every field is read by offset, never through a
 * C struct, so the compiler's packing cannot change what is read. */
#include <string.h>
#include "fr_internal.h"

/** One supported control-packet layout: where the fields are. */
typedef struct {
    uint8_t version;
    uint16_t size;
    uint8_t version_width;   /* bytes of the version field: 4 (v7), 2 (v12), 1 (v8, v19, v20) */
    int8_t packet_number;    /* offset, -1 when absent */
    uint8_t game_state, first_half, kick_off, secondary_state;
    uint8_t secs_remaining, secs_width; /* offset and width (2 or 4) */
    int8_t secondary_time;   /* offset of an i16, -1 when absent */
    uint8_t teams;           /* offset of team[0] */
    uint16_t team_size;
    uint8_t team_number, score; /* offsets inside a team */
    uint16_t players;        /* offset of player[0] inside a team */
    uint8_t player_size, player_count;
    uint16_t return_port;
    uint8_t return_version;
} layout_t;

static const layout_t layouts[] = {
    /* v7: protocol.md 10.2 */
    {7, 116, 4, -1, 9, 10, 11, 12, 16, 4, -1, 20, 48, 0, 3, 4, 4, 11, 3838, 2},
    /* v8: protocol.md 10.1 */
    {8, 158, 1, 5, 7, 8, 9, 10, 14, 2, 16, 18, 70, 0, 2, 48, 2, 11, 3838, 2},
    /* v12: version u16 at 4, packetNumber 6, state 9, firstHalf 10, kickOffTeam 11, secondaryState 12,
     * secsRemaining i16 20, secondaryTime i16 22, teams at 24 of 332 bytes (players of 6 bytes at 266) */
    {12, 688, 2, 6, 9, 10, 11, 12, 20, 2, 22, 24, 332, 0, 2, 266, 6, 11, 3939, 2},
    /* v19: packetNumber 5, state 10, firstHalf 12, kickingTeam 13, gamePhase 9, secsRemaining i16 14,
     * secondaryTime 16, teams at 18 of 90 bytes (20 players of 4 bytes at 10) */
    {19, 198, 1, 5, 10, 12, 13, 9, 14, 2, 16, 18, 90, 0, 4, 10, 4, 20, 3939, 4},
    /* v20 (protocol.md 10.11): v19's header; teams at 18 of 70 bytes (20 players of 3 bytes at 10) */
    {20, 158, 1, 5, 10, 12, 13, 9, 14, 2, 16, 18, 70, 0, 4, 10, 3, 20, 3939, 4},
};

/** How long a higher version, once used, keeps lower versions ignored: two GameController rounds. */
#define FR_GC_PREFERENCE_MS 1000u

static struct {
    bool heard;
    fr_endpoint_t from;
    const layout_t *layout;
    uint32_t used_at;
} gc;

void fr_gc_reset(void) { memset(&gc, 0, sizeof gc); }

/** A little-endian number of `width` bytes (GameController packets are little-endian). */
static uint32_t le(const uint8_t *p, int width) {
    uint32_t v = 0;
    for (int k = width - 1; k >= 0; k--) v = v << 8 | p[k];
    return v;
}

/** The layout a control packet has by its exact size and version, or NULL. */
static const layout_t *layout_of(const uint8_t *data, size_t len) {
    if (len < 8 || memcmp(data, "RGme", 4) != 0) return NULL;
    for (size_t k = 0; k < sizeof layouts / sizeof layouts[0]; k++) {
        const layout_t *l = &layouts[k];
        if (len == l->size && le(data + 4, l->version_width) == l->version) return l;
    }
    return NULL;
}

bool fr_gc_parse(const uint8_t *data, size_t len, uint32_t team, uint8_t player, fr_game_t *out) {
    const layout_t *l = layout_of(data, len);
    if (l == NULL) return false;
    int own = -1;
    for (int t = 0; t < 2; t++)
        if (data[l->teams + t * l->team_size + l->team_number] == team) own = t;
    if (own < 0 || player < 1 || player > l->player_count) return false;
    const uint8_t *mine = data + l->teams + own * l->team_size;
    const uint8_t *theirs = data + l->teams + (1 - own) * l->team_size;
    const uint8_t *me = mine + l->players + (player - 1) * l->player_size;
    memset(out, 0, sizeof *out);
    out->version = l->version;
    out->packet_number = l->packet_number >= 0 ? data[l->packet_number] : 0;
    out->game_state = data[l->game_state];
    out->first_half = data[l->first_half] != 0;
    out->kick_off_team = data[l->kick_off];
    out->secondary_state = data[l->secondary_state];
    uint32_t secs = le(data + l->secs_remaining, l->secs_width);
    out->secs_remaining = l->secs_width == 2 ? (int32_t)(int16_t)secs : (int32_t)secs;
    out->secondary_time = l->secondary_time >= 0 ? (int32_t)(int16_t)le(data + l->secondary_time, 2) : 0;
    out->team_index = (uint8_t)own;
    out->score = mine[l->score];
    out->opponent_score = theirs[l->score];
    out->penalty = l->player_size == 4 && l->version == 7 ? (uint8_t)le(me, 2) : me[0];
    out->secs_till_unpenalised = l->version == 7 ? (uint8_t)le(me + 2, 2) : me[1];
    return true;
}

/** Sends a return packet of the layout's version with `message` to the GameController last heard. */
static bool send_return(uint8_t message) {
    if (!gc.heard) return false;
    uint8_t p[32];
    size_t n;
    memset(p, 0, sizeof p);
    memcpy(p, "RGrt", 4);
    p[4] = gc.layout->return_version;
    if (gc.layout->return_version == 2) {
        /* version 2 (protocol.md 10.3): team, player, message */
        p[5] = (uint8_t)fr_state.settings.team_number;
        p[6] = fr_state.settings.player_number;
        p[7] = message;
        n = 8;
    } else {
        /* version 4 (with 19 and 20): playerNum, teamNum, fallen, pose[3], ballAge, ball[2] as floats. Alive means
         * "not fallen"; no pose or ball is known to the library: zeros and ballAge -1 (never seen). */
        static const uint8_t minus_one[4] = {0x00, 0x00, 0x80, 0xBF};
        p[5] = fr_state.settings.player_number;
        p[6] = (uint8_t)fr_state.settings.team_number;
        p[7] = message == FR_GC_ALIVE ? 0 : 1;
        memcpy(p + 20, minus_one, 4);
        n = 32;
    }
    fr_endpoint_t to = gc.from;
    to.port = gc.layout->return_port;
    return fr_send_raw(&to, p, n);
}

bool fr_gc_send(fr_gc_message_t message) { return send_return((uint8_t)message); }

void fr_gc_receive(const fr_endpoint_t *from, const uint8_t *data, size_t len) {
    if (len < 4 || memcmp(data, "RGme", 4) != 0) {
        /* RGrt of other robots, or anything else starting RG: not for us */
        fr_state.stats.gc_ignored++;
        return;
    }
    static const uint8_t any[4] = {0, 0, 0, 0};
    if (memcmp(fr_state.settings.gc_source, any, 4) != 0 && memcmp(from->ip, fr_state.settings.gc_source, 4) != 0) {
        /* on a shared WiFi anyone can broadcast RGme: only the team's GameController counts (protocol.md 10) */
        fr_state.stats.gc_ignored++;
        return;
    }
    fr_game_t game;
    const layout_t *l = layout_of(data, len);
    if (l == NULL || !fr_gc_parse(data, len, fr_state.settings.team_number, fr_state.settings.player_number, &game)) {
        fr_state.stats.gc_ignored++;
        return;
    }
    uint32_t now = fr_uptime_ms();
    /* Each round carries the same state in several versions: the newest version in use wins, the older copies
     * are neither used nor answered (protocol.md 10.3: version 8 over version 7). */
    if (gc.heard && l->version < gc.layout->version && now - gc.used_at < FR_GC_PREFERENCE_MS) {
        fr_state.stats.gc_ignored++;
        return;
    }
    gc.heard = true;
    gc.from = *from;
    gc.layout = l;
    gc.used_at = now;
    if (fr_state.settings.callbacks.game) fr_state.settings.callbacks.game(&game, fr_state.settings.callbacks.ctx);
    (void)send_return(FR_GC_ALIVE);
}
