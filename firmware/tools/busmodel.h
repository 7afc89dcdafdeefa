/* firmware/tools/busmodel.h: an emulated Dynamixel bus for hosts (docs/firmware.md "The busmodel"): the 18 AX-12A
 * of a Bioloid-class humanoid (ids 1-18) and a HaViMo2 at id 100 that sees an orange ball roll across the picture.
 * Bytes in, status bytes out, as a protocol 1.0 bus does. Linked into the posix robot as its bus, into the unit
 * tests, and served on a TCP port by tools/busmodel_main.c. */
#ifndef BUSMODEL_H
#define BUSMODEL_H
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/** Servos on the model's bus: ids 1 .. BUSMODEL_SERVOS. */
#define BUSMODEL_SERVOS 18
/** The HaViMo2's id. */
#define BUSMODEL_HAVIMO_ID 100
/** Bytes of an AX-12A control table. */
#define BUSMODEL_TABLE 50
/** How long the modelled camera is busy after a capture, milliseconds (it answers nothing meanwhile). */
#define BUSMODEL_CAPTURE_MS 30u

/** Powers the bus up: every servo at its factory table, centred; the camera idle. */
void busmodel_init(uint32_t now_ms);

/** Feeds bytes the master sent (any split); writes the status bytes the bus returns into `out` (`cap` bytes) and
 *  gives their count. Time `now_ms` moves the servos and the camera first. */
size_t busmodel_feed(const uint8_t *in, size_t len, uint8_t *out, size_t cap, uint32_t now_ms);

/** Moves the servos towards their goals and ends a capture, up to `now_ms`. */
void busmodel_step(uint32_t now_ms);

/** The control table of servo `id` (NULL for another id), for tests and the camera's scene. */
uint8_t *busmodel_servo(uint8_t id);

/** Faults for tests: servo `id` answers nothing while `silent`. */
void busmodel_silent(uint8_t id, bool silent);
/** The next status packet of `id` goes out with a wrong checksum. */
void busmodel_corrupt_next(uint8_t id);
/** The next status packet of `id` goes out cut to its first `keep` bytes. */
void busmodel_cut_next(uint8_t id, size_t keep);
/** Every answer is replaced by `n` bytes of garbage (a bus stuck low reads as 0x00 bytes); 0 ends it. */
void busmodel_babble(size_t n, uint8_t byte);

/** What the bus has served since busmodel_init: instruction packets, reads answered per servo id (1..18, index
 *  id - 1), and camera captures. */
typedef struct {
    uint32_t packets;
    uint32_t servo_reads[BUSMODEL_SERVOS];
    uint32_t captures;
} busmodel_counters_t;

/** The counters. */
const busmodel_counters_t *busmodel_counters(void);

#endif
