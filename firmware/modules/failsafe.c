#include "failsafe.h"

#include "core/data.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"

void failsafe_init(void)
{
}

void failsafe_task(void)
{
    uint16_t timeout = settings.link.failsafe_timeout_ms;
    if (timeout == 0 || robot_state.time.time_ms - comm_host_seen_ms() < timeout)
        return;
    uint8_t mode = robot_state.locomotion.mode;
    bool host_driven = mode == PB_LOCO_MODE_MOVEMENT || mode == PB_LOCO_MODE_TELEOP;
    if (mode == PB_LOCO_MODE_LINE_FOLLOW && !settings.line_follow.autonomous) {
        line_follower_stop();
        host_driven = true;
    }
    if (host_driven) {
        locomotion_failsafe();
        DEBUG_PRINT(MAIN, 1, "failsafe: no host packet for %u ms", timeout);
    }
}
