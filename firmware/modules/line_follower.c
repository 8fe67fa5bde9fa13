#include "line_follower.h"

#include <stddef.h>
#include <string.h>

#include "core/data.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/locomotion.h"
#include "modules/pid.h"

/** Largest wheel speed difference the line PD may ask for, m/s. */
#define LINE_MAX_TURN 1.0f
/** The PD's output: wheel speed difference in mm/s, Q16. */
#define MM_PER_M 1000.0f
#define UM_PER_M 1.0e6f

static uint8_t running;
static uint8_t colour_mode;
static int32_t speed_cmd; /* um/s */
static pid_state_t pid;

/* Converted from the float settings when they change. */
static struct {
    uint8_t gen;
    pid_gains_t pid;
    int32_t black, red, blue; /* cruise speeds, um/s */
} k;

static int32_t to_umps(float v)
{
    return (int32_t)(v * UM_PER_M + 0.5f); /* settings keep speeds in 0..1 m/s */
}

/* The conversion when settings changed: float arithmetic, a call that saves every register. */
static __attribute__((noinline)) void params_changed(void)
{
    k.gen = settings_generation;
    pid_gains_convert(&k.pid, &settings.line_pid, 1.0f, MM_PER_M);
    k.black = to_umps(settings.line_follow.speed_mps);
    k.red = to_umps(settings.line_follow.red_speed_mps);
    k.blue = to_umps(settings.line_follow.blue_speed_mps);
}

/* The test of every tick, inline: the conversion apart. */
static inline __attribute__((always_inline)) void refresh_params(void)
{
    if (k.gen != settings_generation)
        params_changed();
}

static uint8_t on_line_follow(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_line_follow_t c;
    memcpy(&c, cmd->payload, sizeof c);
    return line_follower_command(&c, detail);
}

void line_follower_init(void)
{
    running = 0;
    k.gen = (uint8_t)(settings_generation - 1u);
    refresh_params();
    robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_OFF;
    robot_state.line_follow.segment = PB_COLOUR_UNKNOWN;
    comm_register(PB_PKT_LINE_FOLLOW, on_line_follow);
}

uint8_t line_follower_command(const pb_line_follow_t *c, uint16_t *detail)
{
    uint8_t run = c->run, mode = c->colour_mode;
    float speed_mps = c->speed_mps;
    if (run > 1) {
        *detail = offsetof(pb_line_follow_t, run);
        return PB_ERROR_CODE_BAD_ARGUMENT;
    }
    if (mode > PB_COLOUR_MODE_SEGMENTS) {
        *detail = offsetof(pb_line_follow_t, colour_mode);
        return PB_ERROR_CODE_BAD_ARGUMENT;
    }
    if (!(speed_mps >= 0.0f && speed_mps <= LOCOMOTION_MAX_SPEED)) { /* false for NaN too */
        *detail = offsetof(pb_line_follow_t, speed_mps);
        return PB_ERROR_CODE_BAD_ARGUMENT;
    }
    if (!run) {
        if (running) {
            line_follower_stop();
            locomotion_stop(true);
        }
        return PB_ERROR_CODE_NONE;
    }
    running = 1;
    colour_mode = mode;
    speed_cmd = to_umps(speed_mps);
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

static int32_t cruise_speed(void)
{
    uint8_t seg = robot_state.line_follow.segment;
    if (colour_mode == PB_COLOUR_MODE_SEGMENTS) {
        if (seg == PB_COLOUR_RED)
            return k.red;
        if (seg == PB_COLOUR_BLUE)
            return k.blue;
    }
    return speed_cmd > 0 ? speed_cmd : k.black;
}

void line_follower_task(void)
{
    /* The segment under the robot: only tape colours count, white glimpses beside the line do not. */
    uint8_t seen = robot_state.colour.detected;
    if (seen == PB_COLOUR_BLACK || seen == PB_COLOUR_RED || seen == PB_COLOUR_BLUE || seen == PB_COLOUR_GREEN)
        robot_state.line_follow.segment = seen;

    if (!running)
        return;
    refresh_params();
    if (robot_state.locomotion.mode != PB_LOCO_MODE_LINE_FOLLOW) { /* another command took the motors */
        line_follower_stop();
        return;
    }
    if (robot_state.line.flags & PB_LINE_FLAG_LOST) {
        if (robot_state.line_follow.status != PB_LINE_FOLLOW_STATUS_LOST)
            DEBUG_PRINT(LINE, 1, "line lost");
        robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_LOST;
        pid_reset(&pid);
        locomotion_wheel_setpoints(0, 0);
        return;
    }
    robot_state.line_follow.status = PB_LINE_FOLLOW_STATUS_FOLLOWING;
    line_follower_steer(cruise_speed());
}

void line_follower_steer(int32_t v)
{
    refresh_params();
    /* Positive position: the line is to the right, so the left wheel runs faster. */
    int32_t u = pid_update(&pid, &k.pid, robot_state.line.position, (int32_t)(LINE_MAX_TURN * MM_PER_M) << PID_Q);
    /* Half the difference in um/s: u * 1000 / 2^16 / 2 = (u / 2^6) * 125 / 2^8 (|u / 2^6| <= 1024000). */
    int32_t half = (u >> 6) * 125 >> 8;
    locomotion_wheel_setpoints(v + half, v - half);
}

void line_follower_steer_reset(void)
{
    pid_reset(&pid);
}
