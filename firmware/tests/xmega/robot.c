/**
 * \file robot.c
 * The robot's firmware on the XMEGA model.
 */
#include "robot.h"

#include <setjmp.h>
#include <stdbool.h>
#include <string.h>

#include "app.h"
#include "hal/hal.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"

static jmp_buf run_env;
static bool in_run;
static uint8_t restart_why;
static uint32_t ticks;
static uint64_t tick_at[ROBOT_TICK_TIMES];

static void on_restart(uint8_t why)
{
    restart_why = why;
    if (in_run)
        longjmp(run_env, 1);
}

void robot_boot(void)
{
    xm_power_on();
    xm_on_restart(on_restart);
    xm_vcc_set(3.3);
    xm_temperature_set(25.0);
    xm_analog_set('B', 0, 3.9 / 3.0, 33e3);    /* battery 3.9 V through its 1:3 divider */
    xm_analog_set('B', 1, 0.120, 1e3);         /* current sense amplifier: 120 mA */
    xm_analog_set('B', 2, 1.65, 32e3);         /* accelerometer at rest: x and y at zero g, */
    xm_analog_set('B', 3, 1.65, 32e3);
    xm_analog_set('B', 4, 1.65 + 0.33, 32e3);  /* z at +1 g */
    for (uint8_t d = 4; d < 8; d++)            /* line detectors over a white floor, emitters off */
        xm_analog_set('A', d, 0.2, 47e3);
    xm_tcs_light(200, 90, 70, 60);             /* a white floor under the colour sensor */
    ticks = 0;
    robot_frames_clear();
    app_init();
}

void robot_restart(void)
{
    app_init();
}

uint8_t robot_run_until(uint64_t t)
{
    restart_why = XM_RESTART_NONE;
    xm_set_horizon(t);
    if (setjmp(run_env)) {
        in_run = false;
        xm_set_horizon(UINT64_MAX);
        return restart_why;
    }
    in_run = true;
    while (xm_now() < t) { /* main.c's loop */
        if (app_poll()) {
            tick_at[ticks % ROBOT_TICK_TIMES] = xm_now();
            ticks++;
        } else {
            app_idle();
        }
    }
    in_run = false;
    xm_set_horizon(UINT64_MAX);
    return XM_RESTART_NONE;
}

uint8_t robot_run_us(uint64_t us)
{
    return robot_run_until(xm_now() + XM_US(us));
}

uint32_t robot_ticks(void)
{
    return ticks;
}

uint64_t robot_tick_time(uint32_t n)
{
    return n < ticks && ticks - n <= ROBOT_TICK_TIMES ? tick_at[n % ROBOT_TICK_TIMES] : 0;
}

/* ---- the host link's frames ---- */

static slip_decoder_t slip;
static uint32_t per_type[256];
static robot_frame_t kept[ROBOT_FRAMES_KEPT];
static uint32_t kept_n;

static void collect(void)
{
    uint8_t b[256];
    uint32_t n;
    while ((n = xm_usart_take(XM_USARTC0, b, sizeof b)) > 0)
        for (uint32_t i = 0; i < n; i++) {
            pb_frame_t f;
            if (slip_decode(&slip, b[i]) != SLIP_FRAME || pb_frame_check(slip.buf, slip.len, &f) != PB_ERROR_CODE_NONE)
                continue;
            per_type[f.type]++;
            if (kept_n < ROBOT_FRAMES_KEPT) {
                kept[kept_n].type = f.type;
                kept[kept_n].len = f.len;
                memcpy(kept[kept_n].payload, f.payload, f.len);
                kept_n++;
            }
        }
}

const robot_frame_t *robot_frame(uint8_t type, uint32_t n)
{
    collect();
    for (uint32_t i = 0; i < kept_n; i++)
        if (kept[i].type == type && n-- == 0)
            return &kept[i];
    return NULL;
}

uint32_t robot_frames_of_type(uint8_t type)
{
    collect();
    return per_type[type];
}

void robot_frames_clear(void)
{
    collect();
    memset(per_type, 0, sizeof per_type);
    kept_n = 0;
    slip_decoder_init(&slip);
}
