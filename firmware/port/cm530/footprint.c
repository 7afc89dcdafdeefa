/* firmware/port/cm530/footprint.c: the footprint stub of `make footprint` (docs/firmware.md, "Footprint"). A
 * program that does nothing but start the library and poll it, and that keeps every public function of the
 * library's headers in the image (the table build/gen/footprint_keep.c, generated from the headers by
 * tools/footprint_keep.sh), so the linker's --gc-sections drops nothing a program could use. Linked with the CM-530
 * port like the test robot, it measures the library alone: the test robot's own code (and the soft-float
 * and 64-bit division routines its number formatting pulls in) is not counted. */
#include <stddef.h>

#include "board.h"
#include "fr.h"

/** Every public function of the library (generated; see tools/footprint_keep.sh). */
extern void (*const fr_footprint_keep[])(void);
extern const size_t fr_footprint_keep_count;

/** Which kept function to call: never set, but the compiler cannot know, so the table stays referenced. */
volatile size_t fr_footprint_call = (size_t)-1;

static const uint8_t key[32] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16,
                                17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32};

int main(int argc, char **argv) {
    (void)argc;
    (void)argv;
    static fr_settings_t settings;
    settings.robot_id = 1;
    settings.gateway = (fr_endpoint_t){{192, 168, 1, 10}, 11011};
    settings.signing_key = key;
    settings.signing_key_len = sizeof key;
    (void)fr_init(&settings);
    for (;;) {
        fr_poll();
        size_t i = fr_footprint_call;
        if (i < fr_footprint_keep_count) fr_footprint_keep[i]();
        fr_port_idle();
    }
}
