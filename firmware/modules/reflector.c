#include "reflector.h"

#include <stddef.h>
#include <string.h>

#include "core/data.h"
#include "modules/comm.h"

static uint32_t last_sent_ms;

static uint8_t on_set_sync(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_set_sync_t c;
    memcpy(&c, cmd->payload, sizeof c);
    if (c.mode > PB_SYNC_MODE_REDUCED) {
        *detail = offsetof(pb_set_sync_t, mode);
        return PB_ERROR_CODE_BAD_ARGUMENT;
    }
    uint8_t code = reflector_set_sync(c.mode, c.period_ms);
    if (code != PB_ERROR_CODE_NONE)
        *detail = offsetof(pb_set_sync_t, period_ms);
    return code;
}

void reflector_init(void)
{
    last_sent_ms = robot_state.time.time_ms;
    comm_register(PB_PKT_SET_SYNC, on_set_sync);
}

uint8_t reflector_set_sync(uint8_t mode, uint16_t period_ms)
{
    if (mode > PB_SYNC_MODE_REDUCED || period_ms < 1 || period_ms > 60000u)
        return PB_ERROR_CODE_BAD_ARGUMENT;
    settings.sync.mode = mode;
    settings.sync.period_ms = period_ms;
    settings_generation++;
    return PB_ERROR_CODE_NONE;
}

void reflector_task(void)
{
    uint32_t now = robot_state.time.time_ms;
    uint16_t period = settings.sync.period_ms ? settings.sync.period_ms : 1u;
    if (settings.sync.mode == PB_SYNC_MODE_NONE || now - last_sent_ms < period)
        return;
    /* Keep the cadence; after a long pause (mode change) restart from now. */
    last_sent_ms = (now - last_sent_ms < 2u * period) ? last_sent_ms + period : now;
    bool sent;
    /* Both are streamed: copied now, encoded over the next ticks at about the pace the UART sends them. */
    if (settings.sync.mode == PB_SYNC_MODE_FULL) {
        sent = comm_send_streamed(PB_PKT_STATE_FULL, &robot_state, sizeof robot_state);
    } else {
        pb_state_reduced_t r;
        r.time_ms = robot_state.time.time_ms;
        r.encoder_left = robot_state.encoders.left;
        r.encoder_right = robot_state.encoders.right;
        r.speed_left_mmps = robot_state.wheels.speed_left_mmps;
        r.speed_right_mmps = robot_state.wheels.speed_right_mmps;
        r.line_position = robot_state.line.position;
        r.line_flags = robot_state.line.flags;
        sent = comm_send_streamed(PB_PKT_STATE_REDUCED, &r, sizeof r);
    }
    if (sent)
        robot_state.time.tick_max_us = 0;
}
