#include "speed.h"

#include "drivers/encoder.h"
#include "hal/hal.h"
#include "modules/pid.h"
#include "modules/reflector.h"
#include "modules/settings.h"

typedef struct {
    float v;        /* m/s, signed */
    float v_tick;   /* v per capture tick, for the extrapolation */
    int32_t count;  /* pulses */
    uint32_t last;  /* capture time of the last edge */
    uint8_t edges;
    int16_t mmps;   /* v for the state, updated with v */
    float dist;     /* count * pulse length, updated with the count */
} wheel_t;

static wheel_t wheels[2];
static uint8_t pulse_gen_seen;
static float pulse_m;
static float ext_cap; /* extrapolation stops short of the next edge */
static uint8_t pulse_gen;

float speed_pulse_m(void)
{
    if (pulse_gen != settings_generation || pulse_m <= 0.0f) {
        uint16_t ppr = settings.encoder.pulses_per_rev ? settings.encoder.pulses_per_rev : 1u;
        pulse_m = 3.14159265f * settings.geometry.wheel_diameter_m / (float)ppr;
        ext_cap = 0.95f * pulse_m;
        pulse_gen = settings_generation;
    }
    return pulse_m;
}

void speed_init(void)
{
    for (uint8_t w = 0; w < 2; w++) {
        wheels[w].v = 0.0f;
        wheels[w].v_tick = 0.0f;
        wheels[w].count = 0;
        wheels[w].last = 0;
        wheels[w].edges = 0;
        wheels[w].mmps = 0;
        wheels[w].dist = 0.0f;
    }
    pulse_gen = (uint8_t)(settings_generation - 1u);
}

float speed_from_periods(float p_m, uint32_t p0, uint32_t p1, uint32_t timeout_ticks)
{
    if (p0 == 0 || p0 > timeout_ticks)
        return 0.0f;
    if (p1 == 0 || p1 > timeout_ticks) /* one period only: the stripe asymmetry shows, but it is a speed */
        return p_m * (float)HAL_CAPTURE_HZ / (float)p0;
    return 2.0f * p_m * (float)HAL_CAPTURE_HZ / (float)(p0 + p1);
}

static int16_t to_mmps(float v)
{
    float mm = v * 1000.0f;
    if (mm > 32767.0f)
        return 32767;
    if (mm < -32767.0f)
        return -32767;
    return (int16_t)(mm >= 0 ? mm + 0.5f : mm - 0.5f);
}

static void set_speed(wheel_t *wh, float v)
{
    if (v != wh->v) {
        wh->v = v;
        wh->v_tick = v * (1.0f / (float)HAL_CAPTURE_HZ);
        wh->mmps = to_mmps(v);
    }
}

void speed_task(void)
{
    float p_m = speed_pulse_m();
    uint32_t timeout = (uint32_t)settings.encoder.speed_timeout_ms * (HAL_CAPTURE_HZ / 1000u);
    uint32_t now = hal_capture_now();
    for (uint8_t w = 0; w < 2; w++) {
        encoder_snapshot_t s;
        encoder_snapshot(w, &s);
        wheel_t *wh = &wheels[w];
        if (s.count != wh->count || pulse_gen_seen != pulse_gen) {
            wh->count = s.count;
            wh->dist = (float)s.count * p_m;
        }
        wh->last = s.last;
        uint32_t age = now - s.last;
        if (s.edges != wh->edges) { /* a new pulse: one division, the fixed delta-s speed */
            wh->edges = s.edges;
            float mag = speed_from_periods(p_m, s.periods >= 1 ? s.period[0] : 0,
                                           s.periods >= 2 ? s.period[1] : 0, timeout);
            set_speed(wh, s.dir > 0 ? mag : -mag);
        } else if (age > timeout) {
            set_speed(wh, 0.0f);
        } else if (s.periods >= 2 && wh->v != 0.0f && age > s.period[0] + s.period[1]) {
            /* The next edge is late (later than two stripes took): no stripe is longer than two mean pulses,
             * so the wheel is at most that fast now. Lets the speed fall before the timeout. */
            float bound = 2.0f * p_m * (float)HAL_CAPTURE_HZ / (float)age;
            if (wh->v > bound)
                set_speed(wh, bound);
            else if (wh->v < -bound)
                set_speed(wh, -bound);
        }
    }
    pulse_gen_seen = pulse_gen;
    robot_state.wheels.speed_left_mmps = wheels[0].mmps;
    robot_state.wheels.speed_right_mmps = wheels[1].mmps;
    robot_state.encoders.left = wheels[0].count;
    robot_state.encoders.right = wheels[1].count;
}

float speed_mps(uint8_t wheel)
{
    return wheels[wheel & 1u].v;
}

float speed_distance_m(uint8_t wheel)
{
    const wheel_t *wh = &wheels[wheel & 1u];
    if (wh->v == 0.0f)
        return wh->dist;
    /* Between edges the wheel keeps going: extrapolate, but never past the next edge. */
    float ext = wh->v_tick * (float)(hal_capture_now() - wh->last);
    return wh->dist + pid_clamp(ext, ext_cap);
}
