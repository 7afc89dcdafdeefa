/* firmware/tests/fake_port.c: the unit tests' port (fake_port.h). */
#include <string.h>
#include "fake_port.h"

fake_datagram_t fake_sent[64];
size_t fake_sent_count;
uint32_t fake_now;
bool fake_link = true;
uint32_t fake_epoch;
bool fake_epoch_fails;
char fake_log[160];

static fake_datagram_t inbox[16];
static size_t inbox_head, inbox_count;

void fake_receive(const fr_endpoint_t *from, const uint8_t *data, size_t len) {
    if (inbox_count == 16 || len > 1400) return;
    fake_datagram_t *d = &inbox[(inbox_head + inbox_count++) % 16];
    d->peer = *from;
    d->len = len;
    memcpy(d->data, data, len);
}

void fake_clear_sent(void) { fake_sent_count = 0; }

uint32_t fr_port_millis(void) { return fake_now; }

int fr_port_send(const fr_endpoint_t *to, const uint8_t *data, size_t len) {
    if (!fake_link) return -1;
    if (fake_sent_count == 64) return -1;
    fake_sent[fake_sent_count].peer = *to;
    fake_sent[fake_sent_count].len = len;
    memcpy(fake_sent[fake_sent_count].data, data, len);
    fake_sent_count++;
    return 0;
}

int fr_port_recv(fr_endpoint_t *from, uint8_t *buf, size_t cap) {
    if (inbox_count == 0) return 0;
    fake_datagram_t *d = &inbox[inbox_head];
    inbox_head = (inbox_head + 1) % 16;
    inbox_count--;
    *from = d->peer;
    if (d->len > cap) return -1;
    memcpy(buf, d->data, d->len);
    return (int)d->len;
}

bool fr_port_link_up(void) { return fake_link; }

bool fake_frame_busy;
bool fake_board_present;
fr_board_health_t fake_board;
bool fr_port_board_health(fr_board_health_t *out) {
    *out = fake_board;
    return fake_board_present;
}

bool fr_port_frame_free(void) { return !fake_frame_busy; }

void fr_port_idle(void) {}

int fr_port_epoch_next(uint32_t *epoch) {
    if (fake_epoch_fails) return -1;
    *epoch = ++fake_epoch;
    return 0;
}

void fr_port_log(const char *text) {
    strncpy(fake_log, text, sizeof fake_log - 1);
    fake_log[sizeof fake_log - 1] = '\0';
}

bool fr_port_option(const char *arg) {
    (void)arg;
    return false;
}
