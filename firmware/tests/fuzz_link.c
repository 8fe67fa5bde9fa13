/**
 * \file fuzz_link.c
 * libFuzzer target: arbitrary bytes on a host link go through the UART buffer (link 0, whose host drives the
 * robot) or, when the first byte is odd, an emulator link (link 1, a watcher that asked to drive), then the SLIP
 * decoder, the frame check, the driver rules and the packet dispatcher of a running firmware (hal/sim); the same
 * bytes are also handed to the frame check and dispatcher directly. After every input, every settings field must
 * still be within its range (a refused write changes nothing), and the link must still answer.
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
    int link = size > 0 && (data[0] & 1);
    if (link) {
        link_open(1);
        link_handshake(1, 0x2222, PB_HOST_ROLE_DRIVE, "fuzz");
    }
    /* Through the whole receive path, in pieces of up to 64 bytes per millisecond. */
    for (size_t i = 0; i < size; i += 64) {
        size_t n = size - i < 64 ? size - i : 64;
        if (link)
            link_send_raw(1, data + i, (uint16_t)n);
        else
            for (size_t k = 0; k < n; k++)
                sim_uart_rx(data[i + k]);
        world.now += 32000;
        sim_advance(world.now);
        while (sim_link_tx_take(link, 256) > 0) {
        }
    }
    /* Straight into the frame check and dispatcher. */
    if (size <= PB_MAX_FRAME + 8)
        comm_handle_frame((uint8_t)link, data, (uint16_t)size);
    world.now += 32000 * 5;
    sim_advance(world.now);
    check_settings();
    return 0;
}
