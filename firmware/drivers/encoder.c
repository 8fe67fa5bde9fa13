#include "encoder.h"

#include <string.h>

#include "hal/hal.h"

static volatile encoder_snapshot_t enc[2];
static volatile uint8_t have_last[2];
static volatile uint8_t changes[2];

void encoder_init(void)
{
    for (uint8_t w = 0; w < 2; w++) {
        memset((void *)&enc[w], 0, sizeof enc[w]);
        enc[w].dir = 1;
        have_last[w] = 0;
        changes[w]++;
    }
}

void encoder_capture_isr(uint8_t wheel, uint32_t timestamp)
{
    if (wheel > 1)
        return;
    volatile encoder_snapshot_t *e = &enc[wheel];
    e->count += e->dir;
    if (have_last[wheel]) {
        e->period[1] = e->period[0];
        e->period[0] = timestamp - e->last;
        if (e->periods < 2)
            e->periods++;
    }
    have_last[wheel] = 1;
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
