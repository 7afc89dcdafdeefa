/* firmware/tests/test_gamecontroller.c: GameController packets (docs/protocol.md section 10): the real packets
 * of naogateway/wire/src/test/resources/vectors/gamecontroller, versions 12 and 19 built field by field from
 * their official layouts, the gateway's version-20 vectors, the version preference and the return packets. */
#include <stdio.h>
#include <string.h>
#include "check.h"
#include "fake_port.h"
#include "fr.h"
#include "../src/fr_internal.h"

static const fr_endpoint_t gc_at = {{192, 168, 1, 50}, 3838};
static fr_game_t last_game;
static int games;

static void on_game(const fr_game_t *g, void *ctx) {
    (void)ctx;
    last_game = *g;
    games++;
}

static size_t load(const char *name, uint8_t *buf, size_t cap) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s", FR_TEST_VECTORS, name);
    FILE *f = fopen(path, "rb");
    if (!f) { printf("cannot read %s\n", path); return 0; }
    size_t n = fread(buf, 1, cap, f);
    fclose(f);
    return n;
}

static void start(uint32_t team, uint8_t player) {
    fr_settings_t s;
    memset(&s, 0, sizeof s);
    s.robot_id = 3;
    s.team_number = team;
    s.player_number = player;
    s.gateway = (fr_endpoint_t){{192, 168, 1, 10}, 11011};
    s.callbacks.game = on_game;
    s.development = true; /* unsigned keep-alives; signing has its own tests */
    fake_now = 0;
    fr_init(&s);
    fr_poll();
    fake_clear_sent();
    games = 0;
}

static void test_vectors(void) {
    uint8_t p[1024];
    fr_game_t g;
    /* v8-playing: 10.1's header, player 3 of team 12 penalised (ball manipulation, 25 s) */
    size_t n = load("v8-playing.bin", p, sizeof p);
    CHECK(n == 158);
    CHECK(fr_gc_parse(p, n, 12, 3, &g));
    CHECK(g.version == 8 && g.packet_number == 4 && g.game_state == 3 && g.first_half && g.kick_off_team == 1);
    CHECK(g.secs_remaining == 587 && g.secondary_time == 0 && g.team_index == 0 && g.score == 2 && g.opponent_score == 1);
    CHECK(g.penalty == 1 && g.secs_till_unpenalised == 25);
    CHECK(fr_gc_parse(p, n, 7, 1, &g) && g.team_index == 1 && g.score == 1 && g.penalty == 0);
    CHECK(!fr_gc_parse(p, n, 5, 1, &g)); /* neither team is ours: not used */
    CHECK(!fr_gc_parse(p, n - 1, 12, 3, &g));
    /* v7-playing: the same game in version 7 */
    n = load("v7-playing.bin", p, sizeof p);
    CHECK(n == 116);
    CHECK(fr_gc_parse(p, n, 12, 3, &g));
    CHECK(g.version == 7 && g.game_state == 3 && g.secs_remaining == 587 && g.score == 2 && g.opponent_score == 1);
    CHECK(g.penalty == 1 && g.secs_till_unpenalised == 25);
    static const struct { const char *file; uint8_t state; uint8_t packet; int secondary; } states[] = {
        {"v8-initial.bin", 0, 1, 0}, {"v8-ready.bin", 1, 2, 30}, {"v8-set.bin", 2, 3, 0}, {"v8-finished.bin", 4, 5, 0}};
    for (size_t k = 0; k < 4; k++) {
        n = load(states[k].file, p, sizeof p);
        CHECK(fr_gc_parse(p, n, 12, 1, &g) && g.game_state == states[k].state && g.packet_number == states[k].packet &&
              g.secondary_time == states[k].secondary);
    }
    n = load("v8-finished.bin", p, sizeof p);
    CHECK(fr_gc_parse(p, n, 12, 1, &g) && !g.first_half);
    n = load("v7-initial.bin", p, sizeof p);
    CHECK(fr_gc_parse(p, n, 7, 2, &g) && g.version == 7 && g.game_state == 0 && g.secs_remaining == 600);
}

static void test_v12_v19(void) {
    uint8_t p[688];
    fr_game_t g;
    /* version 12: 688 bytes, teams of 332 at 24, players of 6 bytes at 266 */
    memset(p, 0, sizeof p);
    memcpy(p, "RGme", 4);
    p[4] = 12; p[6] = 9; p[9] = 3; p[10] = 1; p[11] = 12; p[12] = 0;
    p[20] = 0x2C; p[21] = 0x01; /* 300 s */
    p[22] = 10;
    p[24] = 7; p[24 + 2] = 1;
    p[24 + 332] = 12; p[24 + 332 + 2] = 3;
    p[24 + 332 + 266 + 6 * 1] = 31; p[24 + 332 + 266 + 6 * 1 + 1] = 20; /* player 2 of team 12: pushing */
    CHECK(fr_gc_parse(p, 688, 12, 2, &g));
    CHECK(g.version == 12 && g.packet_number == 9 && g.game_state == 3 && g.kick_off_team == 12 && g.secs_remaining == 300);
    CHECK(g.secondary_time == 10 && g.team_index == 1 && g.score == 3 && g.opponent_score == 1);
    CHECK(g.penalty == 31 && g.secs_till_unpenalised == 20);
    CHECK(!fr_gc_parse(p, 687, 12, 2, &g));
    /* version 19: 198 bytes, teams of 90 at 18, 20 players of 4 bytes at 10 */
    memset(p, 0, sizeof p);
    memcpy(p, "RGme", 4);
    p[4] = 19; p[5] = 77; p[10] = 2; p[12] = 1; p[13] = 12;
    p[14] = 0x58; p[15] = 0x02; /* 600 s */
    p[16] = 0xFF; p[17] = 0xFF; /* -1 */
    p[18] = 12; p[18 + 4] = 2;
    p[18 + 90] = 7; p[18 + 90 + 4] = 0;
    p[18 + 10 + 4 * 19] = 5; p[18 + 10 + 4 * 19 + 1] = 30; /* player 20: pick-up */
    CHECK(fr_gc_parse(p, 198, 12, 20, &g));
    CHECK(g.version == 19 && g.packet_number == 77 && g.game_state == 2 && g.secs_remaining == 600 && g.secondary_time == -1);
    CHECK(g.team_index == 0 && g.score == 2 && g.penalty == 5 && g.secs_till_unpenalised == 30);
    CHECK(!fr_gc_parse(p, 198, 12, 21, &g));
}

/* The gateway's own version-19 and version-12 vectors (built by that side from the official layouts, see the
 * vectors' README): both halves must read the same fields from the same bytes (docs/protocol.md 10.4, 10.5). */
static void test_gateway_vectors(void) {
    uint8_t p[1024];
    fr_game_t g;
    static const struct { const char *file; uint8_t version, state, packet; int secondary; } rows[] = {
        {"v19-initial.bin", 19, 0, 1, 0}, {"v19-ready.bin", 19, 1, 2, 45}, {"v19-set.bin", 19, 2, 3, 0},
        {"v12-initial.bin", 12, 0, 1, 0}, {"v12-ready.bin", 12, 1, 2, 30}, {"v12-set.bin", 12, 2, 3, 0}};
    for (size_t k = 0; k < sizeof rows / sizeof rows[0]; k++) {
        size_t n = load(rows[k].file, p, sizeof p);
        CHECK(n == (rows[k].version == 19 ? 198u : 688u));
        CHECK(fr_gc_parse(p, n, 12, 1, &g) && g.version == rows[k].version && g.game_state == rows[k].state &&
              g.packet_number == rows[k].packet && g.secondary_time == rows[k].secondary && g.secs_remaining == 600 &&
              g.first_half && g.team_index == 0 && g.score == 0 && g.penalty == 0);
        CHECK(fr_gc_parse(p, n, 7, 2, &g) && g.team_index == 1);
    }
    /* PLAYING: score 2 : 1, player 3 of team 12 penalised for 25 s (v19 pushing 9, v12 physical contact 31) */
    size_t n = load("v19-playing.bin", p, sizeof p);
    CHECK(fr_gc_parse(p, n, 12, 3, &g) && g.version == 19 && g.game_state == 3 && g.packet_number == 4);
    CHECK(g.secs_remaining == 587 && g.secondary_time == 30 && g.score == 2 && g.opponent_score == 1);
    CHECK(g.penalty == 9 && g.secs_till_unpenalised == 25);
    CHECK(fr_gc_parse(p, n, 7, 3, &g) && g.score == 1 && g.opponent_score == 2 && g.penalty == 0);
    n = load("v12-playing.bin", p, sizeof p);
    CHECK(fr_gc_parse(p, n, 12, 3, &g) && g.version == 12 && g.game_state == 3 && g.packet_number == 4);
    CHECK(g.secs_remaining == 587 && g.score == 2 && g.opponent_score == 1);
    CHECK(g.penalty == 31 && g.secs_till_unpenalised == 25);
    n = load("v19-finished.bin", p, sizeof p);
    CHECK(fr_gc_parse(p, n, 12, 1, &g) && g.game_state == 4 && !g.first_half && g.secs_remaining == 0);
    n = load("v12-finished.bin", p, sizeof p);
    CHECK(fr_gc_parse(p, n, 12, 1, &g) && g.game_state == 4 && !g.first_half && g.secs_remaining == 0);
}

/* The gateway's version-20 vectors (docs/protocol.md 10.11): every state in both halves, every penalty by its
 * code, and the answer: RGrt version 4 (32 bytes) to 3939, as for version 19. */
static void test_v20(void) {
    uint8_t p[1024];
    fr_game_t g;
    static const char *names[] = {"initial", "ready", "set", "playing", "finished"};
    for (uint8_t state = 0; state < 5; state++)
        for (int half = 1; half >= 0; half--) {
            char file[64];
            snprintf(file, sizeof file, "v20-%s%s.bin", names[state], half ? "" : "-second-half");
            size_t n = load(file, p, sizeof p);
            CHECK(n == 158);
            CHECK(fr_gc_parse(p, n, 12, 3, &g) && g.version == 20 && g.game_state == state && g.first_half == half &&
                  g.packet_number == state + (half ? 1 : 11) && g.team_index == 0);
            CHECK(g.secs_remaining == (state == 3 ? 587 : state == 4 ? 0 : 600));
            CHECK(g.secondary_time == (state == 1 ? 45 : state == 3 ? 30 : 0));
            CHECK(g.score == (state >= 3 ? 2 : 0) && g.opponent_score == (state >= 3 ? 1 : 0));
            /* player 3 of team 12 pushed in PLAYING: 10 in version 20, 25 s */
            CHECK(g.penalty == (state == 3 ? 10 : 0) && g.secs_till_unpenalised == (state == 3 ? 25 : 0));
            CHECK(fr_gc_parse(p, n, 7, 8, &g) && g.team_index == 1 && g.penalty == 13); /* a substitute */
            CHECK(!fr_gc_parse(p, n - 1, 12, 3, &g) && !fr_gc_parse(p, n, 12, 21, &g));
        }
    /* every penalty: player i + 1 of team 12 has code i, motion in stop (3) and cautioned (11) among them */
    size_t n = load("v20-penalties.bin", p, sizeof p);
    for (uint8_t code = 0; code <= 13; code++) {
        CHECK(fr_gc_parse(p, n, 12, (uint8_t)(code + 1), &g) && g.penalty == code);
        CHECK(g.secs_till_unpenalised == (code == 0 || code == 12 || code == 13 ? 0 : 10 + code));
    }
    /* a version-8 packet is 158 bytes too: byte 4 tells them apart */
    n = load("v8-playing.bin", p, sizeof p);
    CHECK(fr_gc_parse(p, n, 12, 3, &g) && g.version == 8);
    /* answered with RGrt version 4 at the sender's 3939 */
    n = load("v20-playing.bin", p, sizeof p);
    start(12, 3);
    fake_receive(&gc_at, p, n);
    fr_poll();
    CHECK(games == 1 && last_game.version == 20 && last_game.game_state == 3);
    CHECK(fake_sent_count == 1 && fake_sent[0].peer.port == 3939 && memcmp(fake_sent[0].peer.ip, gc_at.ip, 4) == 0);
    CHECK(same_bytes(fake_sent[0].data, fake_sent[0].len,
                     "52 47 72 74 04 03 0C 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 80 BF 00 00 00 00 00 00 00 00"));
    /* a version-19 copy of the same round is the older one: neither used nor answered */
    uint8_t v19[256];
    size_t n19 = load("v19-playing.bin", v19, sizeof v19);
    fake_clear_sent();
    fake_receive(&gc_at, v19, n19);
    fr_poll();
    CHECK(games == 1 && fake_sent_count == 0);
    /* an unknown later version is not read by the library: ignored, not answered */
    p[4] = 21;
    fake_receive(&gc_at, p, n);
    fr_poll();
    CHECK(games == 1 && fake_sent_count == 0);
}

static void test_answers(void) {
    uint8_t v8[200], v7[200];
    size_t n8 = load("v8-playing.bin", v8, sizeof v8), n7 = load("v7-playing.bin", v7, sizeof v7);
    start(12, 3);
    /* one round: v8 then v7; only v8 is used and answered, with 10.3's bytes, at the sender's 3838 */
    fake_receive(&gc_at, v8, n8);
    fake_receive(&gc_at, v7, n7);
    fr_poll();
    CHECK(games == 1 && last_game.version == 8);
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len, "52 47 72 74 02 0C 03 02"));
    CHECK(fake_sent[0].peer.port == 3838 && memcmp(fake_sent[0].peer.ip, gc_at.ip, 4) == 0);
    /* a version-7-only GameController is used once no version 8 came for two rounds */
    fake_clear_sent();
    fake_now = 1500;
    fake_receive(&gc_at, v7, n7);
    fr_poll();
    CHECK(games == 2 && last_game.version == 7 && fake_sent_count == 2); /* the answer and a keep-alive */
    /* the manual penalty button */
    fake_clear_sent();
    CHECK(fr_gc_send(FR_GC_PENALISE));
    CHECK(fake_sent_count == 1 && same_bytes(fake_sent[0].data, fake_sent[0].len, "52 47 72 74 02 0C 03 00"));
    /* another team's packet is neither used nor answered */
    start(5, 1);
    fake_receive(&gc_at, v8, n8);
    fr_poll();
    CHECK(games == 0 && fake_sent_count == 0 && fr_stats()->gc_ignored == 1);
    CHECK(!fr_gc_send(FR_GC_ALIVE));
    /* with a GameController address set, packets from elsewhere are ignored */
    fr_settings_t only;
    memset(&only, 0, sizeof only);
    only.team_number = 12;
    only.player_number = 3;
    only.gateway = (fr_endpoint_t){{192, 168, 1, 10}, 11011};
    only.callbacks.game = on_game;
    memcpy(only.gc_source, (const uint8_t[4]){192, 168, 1, 51}, 4);
    fake_now = 0;
    fr_init(&only);
    games = 0;
    fake_receive(&gc_at, v8, n8);
    fr_poll();
    CHECK(games == 0 && fr_stats()->gc_ignored == 1);
    fr_endpoint_t trusted = {{192, 168, 1, 51}, 3838};
    fake_receive(&trusted, v8, n8);
    fr_poll();
    CHECK(games == 1);
    /* version 19 is answered with return version 4 (32 bytes) at port 3939 */
    uint8_t p[198];
    memset(p, 0, sizeof p);
    memcpy(p, "RGme", 4);
    p[4] = 19; p[18] = 5;
    start(5, 2);
    fake_receive(&gc_at, p, sizeof p);
    fr_poll();
    CHECK(games == 1 && fake_sent_count == 1 && fake_sent[0].peer.port == 3939);
    CHECK(same_bytes(fake_sent[0].data, fake_sent[0].len,
                     "52 47 72 74 04 02 05 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 80 BF 00 00 00 00 00 00 00 00"));
    /* RG junk and other robots' RGrt are ignored */
    fake_clear_sent();
    fake_receive(&gc_at, (const uint8_t *)"RGrt\x02\x05\x01\x02", 8);
    fake_receive(&gc_at, (const uint8_t *)"RGxx", 4);
    fr_poll();
    CHECK(fake_sent_count == 0 && fr_stats()->gc_ignored == 2);
}

int main(void) {
    test_vectors();
    test_v12_v19();
    test_gateway_vectors();
    test_v20();
    test_answers();
    return DONE();
}
