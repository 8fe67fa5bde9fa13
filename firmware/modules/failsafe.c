#include "failsafe.h"

#include "core/data.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"

/* Line following that the host keeps alive: it ends when the host goes (`autonomous` 0). */
static bool follows_for_the_host(void)
{
    return robot_state.locomotion.mode == PB_LOCO_MODE_LINE_FOLLOW && !settings.line_follow.autonomous;
}

/* The driver's goodbye (comm calls it for the driver only). */
static uint8_t on_goodbye(const pb_frame_t *cmd, uint16_t *detail)
{
    uint8_t queue = cmd->payload[0];
    if (queue > PB_LEAVE_QUEUE_DROP) {
        *detail = 0;
        return PB_ERROR_CODE_BAD_ARGUMENT;
    }
    /* Dropping is a stop; finishing keeps the movements and stops what needs a host present (teleoperation runs
     * no movement: its stop drops nothing). */
    bool host_follow = follows_for_the_host();
    if (host_follow)
        line_follower_stop();
    if (queue == PB_LEAVE_QUEUE_DROP || host_follow || robot_state.locomotion.mode == PB_LOCO_MODE_TELEOP)
        locomotion_stop(false);
    return PB_ERROR_CODE_NONE;
}

void failsafe_init(void)
{
    comm_register(PB_PKT_GOODBYE, on_goodbye);
}

void failsafe_task(void)
{
    uint16_t timeout = settings.link.failsafe_timeout_ms;
    if (timeout == 0 || robot_state.time.time_ms - comm_host_seen_ms() < timeout)
        return;
    uint8_t mode = robot_state.locomotion.mode;
    bool host_driven = mode == PB_LOCO_MODE_MOVEMENT || mode == PB_LOCO_MODE_TELEOP;
    if (follows_for_the_host()) {
        line_follower_stop();
        host_driven = true;
    }
    if (host_driven) {
        locomotion_failsafe();
        DEBUG_PRINT(MAIN, 1, "failsafe: no host packet for %u ms", timeout);
    }
}
