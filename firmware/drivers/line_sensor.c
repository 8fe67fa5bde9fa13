#include "line_sensor.h"

#include <stddef.h>

#include "hal/hal.h"
#include "modules/reflector.h"
#include "modules/scheduler.h"
#include "modules/settings.h"

/* Spot lit by each detector in the two lit phases: detector d sits between emitters d and d+1, spot 2d is
 * lit by emitter d and spot 2d+1 by emitter d+1. */
static const HAL_FLASH uint8_t spot_a[HAL_LINE_DETECTORS] = {0, 3, 4, 7}; /* emitters 0, 2, 4 */
static const HAL_FLASH uint8_t spot_b[HAL_LINE_DETECTORS] = {1, 2, 5, 6}; /* emitters 1, 3 */
#define EMITTERS_A 0x15u
#define EMITTERS_B 0x0Au

/* Spot centres in permille of the half-width, left to right. */
static const HAL_FLASH int16_t spot_x[LINE_SPOTS] = {-1000, -714, -429, -143, 143, 429, 714, 1000};

static uint16_t dark[HAL_LINE_DETECTORS], lit_a[HAL_LINE_DETECTORS], lit_b[HAL_LINE_DETECTORS];
static volatile uint8_t phase;  /* 0 idle */
static volatile uint8_t ready;
static uint32_t last_seen_ms;

/* Calibration scale per spot, (1000 << 16) / (cal_max - cal_min), cached against settings changes. */
static uint32_t scale[LINE_SPOTS];
static uint8_t scale_gen;
static uint8_t scale_dirty; /* spots whose scale waits for an update, one per call */

static uint32_t spot_scale(uint8_t i);

static void step(void)
{
    switch (phase) {
    case 1:
        hal_line_results(dark);
        hal_line_emitters(EMITTERS_A);
        break;
    case 2:
        hal_line_convert();
        break;
    case 3:
        hal_line_results(lit_a);
        hal_line_emitters(EMITTERS_B);
        break;
    case 4:
        hal_line_convert();
        break;
    case 5:
        hal_line_results(lit_b);
        hal_line_emitters(0);
        phase = 0;
        ready = 1;
        return;
    default:
        phase = 0;
        return;
    }
    phase++;
    scheduler_after(SCHED_CH_LINE, LINE_PHASE_US, step);
}

static void start(void)
{
    /* Emitters are off between acquisitions: convert the dark reading at once. */
    phase = 1;
    hal_line_convert();
    scheduler_after(SCHED_CH_LINE, LINE_PHASE_US, step);
}

void line_sensor_init(void)
{
    phase = 0;
    ready = 0;
    last_seen_ms = 0;
    scale_gen = settings_generation;
    scale_dirty = 0;
    for (uint8_t i = 0; i < LINE_SPOTS; i++)
        scale[i] = spot_scale(i);
    hal_line_emitters(0);
    robot_state.line.position = 0;
    robot_state.line.flags = 0;
}

/* A division per spot: after a settings change they are spread over ticks, one per tick (a scale a few
 * milliseconds stale is harmless). */
static uint32_t spot_scale(uint8_t i)
{
    uint16_t lo = settings.line_sensor.cal_min[i], hi = settings.line_sensor.cal_max[i];
    return hi > lo ? (1000ul << 16) / (uint16_t)(hi - lo) : 0;
}

static void update_scale(void)
{
    if (scale_gen != settings_generation) {
        scale_gen = settings_generation;
        scale_dirty = 0xFF;
    }
    if (scale_dirty) {
        uint8_t i = 0;
        while (!(scale_dirty & (1u << i)))
            i++;
        scale[i] = spot_scale(i);
        scale_dirty &= (uint8_t)~(1u << i);
    }
}

uint8_t line_sensor_evaluate(const uint16_t raw[LINE_SPOTS], uint16_t dark_out[LINE_SPOTS], int16_t *position)
{
    update_scale();
    uint16_t threshold = settings.line_sensor.threshold;
    int32_t sum_wx = 0;
    uint32_t sum_w = 0;
    for (uint8_t i = 0; i < LINE_SPOTS; i++) {
        uint16_t lo = settings.line_sensor.cal_min[i], hi = settings.line_sensor.cal_max[i];
        uint16_t d;
        if (raw[i] <= lo)
            d = 0;
        else if (raw[i] >= hi) /* also an uncalibrated spot (hi <= lo): dark above cal_min */
            d = 1000;
        else /* (raw - lo) < (hi - lo), so the product stays below 1000 << 16 */
            d = (uint16_t)(((uint32_t)(raw[i] - lo) * scale[i]) >> 16);
        if (dark_out)
            dark_out[i] = d;
        if (d > threshold) {
            uint16_t w = (uint16_t)(d - threshold);
            sum_w += w;
            sum_wx += (int32_t)w * spot_x[i];
        }
    }
    if (sum_w == 0)
        return 0;
    *position = (int16_t)(sum_wx / (int32_t)sum_w);
    return 1;
}

void line_sensor_task(void)
{
    if (ready) {
        ready = 0;
        uint16_t spot_raw[LINE_SPOTS];
        for (uint8_t d = 0; d < HAL_LINE_DETECTORS; d++) {
            spot_raw[spot_a[d]] = lit_a[d] > dark[d] ? (uint16_t)(lit_a[d] - dark[d]) : 0;
            spot_raw[spot_b[d]] = lit_b[d] > dark[d] ? (uint16_t)(lit_b[d] - dark[d]) : 0;
        }
        for (uint8_t i = 0; i < LINE_SPOTS; i++)
            robot_state.line.raw[i] = spot_raw[i];
        int16_t pos;
        uint8_t flags = robot_state.line.flags;
        if (line_sensor_evaluate(spot_raw, NULL, &pos)) {
            robot_state.line.position = pos;
            flags = LINE_FLAG_SEEN;
            last_seen_ms = robot_state.time.time_ms;
        } else {
            flags &= (uint8_t)~LINE_FLAG_SEEN;
        }
        if (!(flags & LINE_FLAG_SEEN) && robot_state.time.time_ms - last_seen_ms >= settings.line_follow.lost_timeout_ms)
            flags |= LINE_FLAG_LOST;
        robot_state.line.flags = flags;
    }
    if (phase == 0)
        start();
}
