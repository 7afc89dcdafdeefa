/* firmware/src/fr_out.c: the writer of every frame the library sends (keep-alives, answers, debug data): protobuf
 * fields written one by one into the frame buffer. nanopb's encoder walks a descriptor per field and encodes each
 * submessage twice (to size it first); this writes each once and leaves its length to fr_out_close. The bytes are
 * the ones nanopb writes for the same message (tests/test_out.c compares them): fields in field-number order, a
 * field left out where nanopb's has_ flag or string callback would be unset, minimal varints. */
#include <string.h>
#include "fr_internal.h"

void fr_out_byte(fr_out_t *w, uint8_t b) {
    if (w->p == NULL) return;
    if (w->p == w->end) { w->p = NULL; return; }
    *w->p++ = b;
}

void fr_out_varint(fr_out_t *w, uint64_t v) {
    while (v >= 0x80u) {
        fr_out_byte(w, (uint8_t)(v | 0x80u));
        v >>= 7;
    }
    fr_out_byte(w, (uint8_t)v);
}

void fr_out_uint(fr_out_t *w, uint32_t field, uint32_t v) {
    fr_out_varint(w, field << 3);
    fr_out_varint(w, v);
}

void fr_out_int(fr_out_t *w, uint32_t field, int32_t v) {
    fr_out_varint(w, field << 3);
    fr_out_varint(w, (uint64_t)(int64_t)v);
}

void fr_out_sint(fr_out_t *w, uint32_t field, int32_t v) {
    fr_out_varint(w, field << 3);
    fr_out_varint(w, ((uint32_t)v << 1) ^ (uint32_t)(v >> 31));
}

void fr_out_float(fr_out_t *w, uint32_t field, float f) {
    uint32_t bits;
    memcpy(&bits, &f, 4);
    fr_out_varint(w, field << 3 | 5u);
    for (int k = 0; k < 4; k++) fr_out_byte(w, (uint8_t)(bits >> (8 * k)));
}

void fr_out_bytes(fr_out_t *w, uint32_t field, const uint8_t *data, size_t n) {
    fr_out_varint(w, field << 3 | 2u);
    fr_out_varint(w, n);
    fr_out_raw(w, data, n);
}

void fr_out_raw(fr_out_t *w, const uint8_t *data, size_t n) {
    if (w->p == NULL || (size_t)(w->end - w->p) < n) { w->p = NULL; return; }
    if (n > 0) memcpy(w->p, data, n);
    w->p += n;
}

void fr_out_string(fr_out_t *w, uint32_t field, const char *s) {
    if (s != NULL) fr_out_bytes(w, field, (const uint8_t *)s, strlen(s));
}

/* A submessage's length is left two bytes, enough for any frame (< 16384 bytes). One that turns out shorter than 128
 * bytes (the keep-alive's, an answer's) has its bytes moved down one place, at most 127 of them; a long one (a long
 * text, a camera grid) moves nothing, however deeply it is nested. */
uint8_t *fr_out_open(fr_out_t *w, uint32_t field) {
    fr_out_varint(w, field << 3 | 2u);
    uint8_t *at = w->p;
    fr_out_byte(w, 0);
    fr_out_byte(w, 0);
    return at;
}

/* GCC would turn the move below into a call of libc's memmove (252 B of flash, for a move of at most 127 bytes). */
#if defined(__GNUC__) && !defined(__clang__)
__attribute__((optimize("no-tree-loop-distribute-patterns")))
#endif
void fr_out_close(fr_out_t *w, uint8_t *at) {
    if (w->p == NULL) return;
    size_t n = (size_t)(w->p - at - 2);
    if (n >= 0x80u) {
        at[0] = (uint8_t)(n | 0x80u);
        at[1] = (uint8_t)(n >> 7);
        return;
    }
    at[0] = (uint8_t)n;
    for (size_t k = 1; k <= n; k++) at[k] = at[k + 1];
    w->p--;
}
