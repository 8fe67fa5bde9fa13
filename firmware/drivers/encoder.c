#include "encoder.h"

#include <string.h>

#include "hal/hal.h"

static volatile encoder_snapshot_t enc[2];
/* What `last` is: no edge yet, an edge in the current direction, or the last edge before a reversal. */
enum { LAST_NONE, LAST_SAME, LAST_ACROSS };
static volatile uint8_t have_last[2];
static volatile uint8_t changes[2];

void encoder_init(void)
{
    for (uint8_t w = 0; w < 2; w++) {
        memset((void *)&enc[w], 0, sizeof enc[w]);
        enc[w].dir = 1;
        have_last[w] = LAST_NONE;
        changes[w]++;
    }
}

void encoder_capture_isr(uint8_t wheel, uint32_t timestamp)
{
    if (wheel > 1)
        return;
    volatile encoder_snapshot_t *e = &enc[wheel];
    uint32_t p = timestamp - e->last;
    if (have_last[wheel] != LAST_NONE && p < ENCODER_MIN_EDGE_US * (HAL_CAPTURE_HZ / 1000000ul))
        return; /* chatter */
    e->count += e->dir;
    /* The first edge after a reversal: the wheel still rolls the old way (the time since the last edge is a
     * period of that travel), or it has turned round and crossed the stripe edge it stopped just past once more.
     * Then it comes far sooner than the last period before the reversal (a wheel slows down to turn round):
     * no travel, no period. Taken for one, it read up to 4 m/s, and the speed controller, which never drives a
     * wheel against its way, left that wheel unpowered until the speed timed out. */
    if (have_last[wheel] == LAST_SAME || (have_last[wheel] == LAST_ACROSS && p >= e->period[0] / 2u)) {
        e->period[1] = e->period[0];
        e->period[0] = p;
        if (e->periods < 2)
            e->periods++;
    }
    have_last[wheel] = LAST_SAME;
    e->last = timestamp;
    e->edges++;
    changes[wheel]++;
}

void encoder_set_direction(uint8_t wheel, int8_t dir)
{
    if (wheel > 1 || dir == 0)
        return;
    uint8_t s = hal_irq_save();
    if (enc[wheel].dir != dir) {
        enc[wheel].dir = dir;
        enc[wheel].periods = 0; /* a reversal: periods across it are no speed */
        if (have_last[wheel] != LAST_NONE)
            have_last[wheel] = LAST_ACROSS;
        changes[wheel]++;
    }
    hal_irq_restore(s);
}

uint8_t encoder_changes(uint8_t wheel)
{
    return changes[wheel & 1u];
}

void encoder_snapshot(uint8_t wheel, encoder_snapshot_t *out)
{
    uint8_t s = hal_irq_save();
    memcpy(out, (const void *)&enc[wheel], sizeof *out);
    hal_irq_restore(s);
}
