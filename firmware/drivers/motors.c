#include "motors.h"

#include "core/data.h"
#include "drivers/encoder.h"
#include "hal/hal.h"

static int16_t clamp_duty(int16_t v)
{
    int16_t lim = (int16_t)(settings.motors.pwm_limit > 1000u ? 1000u : settings.motors.pwm_limit);
    return v > lim ? lim : v < -lim ? (int16_t)-lim : v;
}

void motors_init(void)
{
    motors_set(0, 0);
}

void motors_set(int16_t left, int16_t right)
{
    left = clamp_duty(left);
    right = clamp_duty(right);
    /* A wheel keeps its last direction while unpowered: it coasts that way. */
    if (left)
        encoder_set_direction(ENCODER_LEFT, left > 0 ? 1 : -1);
    if (right)
        encoder_set_direction(ENCODER_RIGHT, right > 0 ? 1 : -1);
    robot_state.wheels.pwm_left = left;
    robot_state.wheels.pwm_right = right;
    hal_motors_set(left, right);
}
