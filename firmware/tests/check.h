/* firmware/tests/check.h: a minimal test harness for the C unit tests: CHECK counts, DONE prints
 * "N passed, N failed" (the line the Makefile and CI read) and returns the exit status. */
#ifndef CHECK_H
#define CHECK_H
#include <stdio.h>
#include <string.h>

static int check_passed, check_failed;

/** Counts one check; prints where it failed. */
#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (cond) check_passed++;                                                    \
        else { check_failed++; printf("FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond); } \
    } while (0)

/** Prints the summary line and gives main's return value. */
#define DONE() (printf("%d passed, %d failed\n", check_passed, check_failed), check_failed == 0 ? 0 : 1)

/** Parses "00 2A ..." hex into out; the number of bytes. */
static inline size_t hex(const char *s, unsigned char *out) {
    size_t n = 0;
    unsigned v = 0;
    int digits = 0;
    for (; *s; s++) {
        int d = *s >= '0' && *s <= '9' ? *s - '0' : *s >= 'A' && *s <= 'F' ? *s - 'A' + 10
              : *s >= 'a' && *s <= 'f' ? *s - 'a' + 10 : -1;
        if (d < 0) continue;
        v = v << 4 | (unsigned)d;
        if (++digits == 2) { out[n++] = (unsigned char)v; v = 0; digits = 0; }
    }
    return n;
}

/** Whether `got` of `got_len` bytes equals the hex `want`; prints both when not. */
static inline int same_bytes(const unsigned char *got, size_t got_len, const char *want) {
    unsigned char w[2048];
    size_t n = hex(want, w);
    if (n == got_len && memcmp(got, w, n) == 0) return 1;
    printf("  want (%zu):", n);
    for (size_t k = 0; k < n; k++) printf(" %02X", w[k]);
    printf("\n  got  (%zu):", got_len);
    for (size_t k = 0; k < got_len; k++) printf(" %02X", got[k]);
    printf("\n");
    return 0;
}
#endif
