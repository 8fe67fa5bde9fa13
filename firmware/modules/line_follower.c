#include "line_follower.h"

#include "drivers/line_sensor.h"
#include "modules/debug.h"
#include "modules/locomotion.h"
#include "modules/pid.h"
#include "modules/reflector.h"
#include "modules/settings.h"

/** Largest wheel speed difference the line PD may ask for, m/s. */
#define LINE_MAX_TURN 1.0f

static uint8_t running;
static uint8_t colour_mode;
static float speed_cmd;
static pid_state_t pid;

void line_follower_init(void)
{
    running = 0;
    robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_OFF;
    robot_state.line_follow.segment = PB_COLOUR_UNKNOWN;
}

uint8_t line_follower_command(uint8_t run, uint8_t mode, float speed_mps)
{
    if (run > 1 || mode > PB_COLOUR_MODE_SEGMENTS || !(speed_mps >= 0.0f && speed_mps <= LOCOMOTION_MAX_SPEED))
        return PB_ERROR_CODE_BAD_ARGUMENT; /* the comparison is false for NaN too */
    if (!run) {
        if (running) {
            line_follower_stop();
            locomotion_stop(true);
        }
        return PB_ERROR_CODE_NONE;
    }
    running = 1;
    colour_mode = mode;
    speed_cmd = speed_mps;
    pid_reset(&pid);
    locomotion_line_follow_begin();
    robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_FOLLOWING;
    DEBUG_PRINT(LINE, 2, "following, colour mode %u", mode);
    return PB_ERROR_CODE_NONE;
}

void line_follower_stop(void)
{
    running = 0;
    robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_OFF;
}

static float cruise_speed(void)
{
    uint8_t seg = robot_state.line_follow.segment;
    if (colour_mode == PB_COLOUR_MODE_SEGMENTS) {
        if (seg == PB_COLOUR_RED)
            return settings.line_follow.red_speed_mps;
        if (seg == PB_COLOUR_BLUE)
            return settings.line_follow.blue_speed_mps;
    }
    return speed_cmd > 0.0f ? speed_cmd : settings.line_follow.speed_mps;
}

void line_follower_task(void)
{
    /* The segment under the robot: only tape colours count, white glimpses beside the line do not. */
    uint8_t seen = robot_state.colour.detected;
    if (seen == PB_COLOUR_BLACK || seen == PB_COLOUR_RED || seen == PB_COLOUR_BLUE || seen == PB_COLOUR_GREEN)
        robot_state.line_follow.segment = seen;

    if (!running)
        return;
    if (robot_state.locomotion.mode != PB_LOCO_MODE_LINE_FOLLOW) { /* another command took the motors */
        line_follower_stop();
        return;
    }
    if (robot_state.line.flags & LINE_FLAG_LOST) {
        if (robot_state.line_follow.status != PB_LINE_FOLLOW_STATUS_LOST)
            DEBUG_PRINT(LINE, 1, "line lost");
        robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_LOST;
        pid_reset(&pid);
        locomotion_line_follow_set(0.0f, 0.0f);
        return;
    }
    robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_FOLLOWING;
    /* Positive position: the line is to the right, so the left wheel runs faster. */
    float u = pid_update(&pid, &settings.line_pid, (float)robot_state.line.position, LINE_MAX_TURN);
    float v = cruise_speed();
    locomotion_line_follow_set(v + 0.5f * u, v - 0.5f * u);
}
