#include "line_sensor.h"

#include <stddef.h>

#include "core/data.h"
#include "core/fixed.h"
#include "core/scheduler.h"
#include "hal/hal.h"

/* Spot lit by each detector in the two lit phases: detector d sits between emitters d and d+1, spot 2d is
 * lit by emitter d and spot 2d+1 by emitter d+1. Phase A (emitters 0, 2, 4) lights spots 0, 3, 4, 7 of
 * detectors 0..3, phase B (emitters 1, 3) spots 1, 2, 5, 6 (see line_sensor_task()). */
#define EMITTERS_A 0x15u
#define EMITTERS_B 0x0Au

_Static_assert(LINE_PHASE_US <= HAL_SCHED_MAX_DELAY_US, "a phase is one compare of the scheduler's timer");

/* Spot centres in permille of the half-width, left to right. */
static const HAL_FLASH int16_t spot_x[LINE_SPOTS] = {-1000, -714, -429, -143, 143, 429, 714, 1000};

static uint16_t dark[HAL_LINE_DETECTORS], lit_a[HAL_LINE_DETECTORS], lit_b[HAL_LINE_DETECTORS];
static volatile uint8_t phase;  /* 0 idle */
static volatile uint8_t ready;
static uint32_t last_seen_ms;

/* Calibration scale per spot, (1000 << 16) / (cal_max - cal_min), and the smallest raw - cal_min whose
 * darkness exceeds the threshold, cached against settings changes. */
static uint32_t scale[LINE_SPOTS];
static uint16_t above[LINE_SPOTS];
static uint8_t scale_gen;
static uint8_t scale_dirty; /* spots whose scale waits for an update, one per call */

static uint32_t spot_scale(uint8_t i);
static uint16_t spot_above(uint8_t i);

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
    scheduler_after_short(SCHED_CH_LINE, LINE_PHASE_US, step);
}

static void start(void)
{
    /* Emitters are off between acquisitions: convert the dark reading at once. */
    phase = 1;
    hal_line_convert();
    scheduler_after_short(SCHED_CH_LINE, LINE_PHASE_US, step);
}

void line_sensor_init(void)
{
    phase = 0;
    ready = 0;
    last_seen_ms = 0;
    scale_gen = settings_generation;
    scale_dirty = 0;
    for (uint8_t i = 0; i < LINE_SPOTS; i++) {
        scale[i] = spot_scale(i);
        above[i] = spot_above(i);
    }
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

/* ((raw - lo) * scale) >> 16 > threshold  <=>  raw - lo >= ceil(((threshold + 1) << 16) / scale) */
static uint16_t spot_above(uint8_t i)
{
    uint32_t t = (uint32_t)settings.line_sensor.threshold + 1u;
    if (scale[i] == 0 || t > 1000u)
        return 0xFFFFu; /* uncalibrated, or a threshold no darkness exceeds: decided by raw >= hi */
    uint32_t x = ((t << 16) + scale[i] - 1u) / scale[i];
    return x > 0xFFFFu ? 0xFFFFu : (uint16_t)x;
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
        above[i] = spot_above(i);
        scale_dirty &= (uint8_t)~(1u << i);
    }
}

/* n / d for 0 <= n <= 1000 d (a weighted mean of |spot_x|): ten quotient bits by shift and subtract, not a
 * 32-bit division. */
#ifdef __AVR__
typedef __uint24 sum_t; /* 1000 x 8 x 1000 < 2^24: three-byte arithmetic on the AVR */
#else
typedef uint32_t sum_t;
#endif

static uint16_t mean_of(sum_t n, sum_t d)
{
#ifdef __wasm__
    /* The emulator's build divides: the same quotient (n <= 1000 d < 1024 d), and under the emulator's WebAssembly
     * runtime each unsigned comparison of the loop below is a call (Chicory's i32_ge_u): 7 % of its time. */
    return (uint16_t)(n / d);
#else
    uint16_t q = 0;
    d = (sum_t)(d << 8); /* d << 9: a byte's move and one shift (a shift by 9 is a loop on the AVR) */
    d = (sum_t)(d << 1);
    for (uint8_t i = 0; i < 10; i++) {
        q = (uint16_t)(q << 1);
        if (n >= d) {
            n -= d;
            q |= 1u;
        }
        d >>= 1;
    }
    return q;
#endif
}

/* One line under the sensor: a run of adjacent spots above the threshold. */
typedef struct {
    sum_t left, right; /* weights times |x| on each side of the centre, < 2^23 */
    uint16_t w;        /* at most 8 x 1000 */
} run_t;

#define MAX_RUNS (LINE_SPOTS / 2u) /* runs need a spot below the threshold between them */

static int16_t centroid(const run_t *r)
{
    return r->right >= r->left ? (int16_t)mean_of(r->right - r->left, r->w) : -(int16_t)mean_of(r->left - r->right, r->w);
}

uint8_t line_sensor_evaluate(const uint16_t raw[LINE_SPOTS], uint16_t dark_out[LINE_SPOTS], int16_t *position)
{
    update_scale();
    uint16_t threshold = settings.line_sensor.threshold;
    run_t runs[MAX_RUNS];
    uint8_t n = 0;   /* runs found */
    uint8_t in_run = 0;
    for (uint8_t i = 0; i < LINE_SPOTS; i++) {
        uint16_t lo = settings.line_sensor.cal_min[i], hi = settings.line_sensor.cal_max[i];
        uint16_t d;
        if (raw[i] <= lo) {
            d = 0;
        } else if (raw[i] >= hi) { /* also an uncalibrated spot (hi <= lo): dark above cal_min */
            d = 1000;
        } else if (!dark_out && raw[i] - lo < above[i]) { /* not above the threshold: only the task asks */
            in_run = 0;
            continue;
        } else { /* (raw - lo) < (hi - lo), so the product stays below 1000 << 16 */
            uint16_t x = (uint16_t)(raw[i] - lo);
            d = (uint16_t)(fx_umul16(x, (uint16_t)(scale[i] >> 16)) + (fx_umul16(x, (uint16_t)scale[i]) >> 16));
        }
        if (dark_out)
            dark_out[i] = d;
        if (d <= threshold) {
            in_run = 0;
            continue;
        }
        if (!in_run) {
            in_run = 1;
            run_t *r = &runs[n++];
            r->left = r->right = 0;
            r->w = 0;
        }
        run_t *r = &runs[n - 1u];
        uint16_t w = (uint16_t)(d - threshold);
        int16_t x = spot_x[i];
        r->w = (uint16_t)(r->w + w);
        if (x < 0)
            r->left += fx_umul16(w, (uint16_t)-x);
        else
            r->right += fx_umul16(w, (uint16_t)x);
    }
    if (n == 0)
        return 0;
    /* Two lines (a fork, a crossing seen at an angle): follow the one nearest to where the line was, so the
     * robot commits to one branch instead of steering between them until it loses both. */
    int16_t best = centroid(&runs[0]);
    if (n > 1) {
        int16_t prev = *position;
        uint16_t best_gap = (uint16_t)(best > prev ? best - prev : prev - best);
        for (uint8_t k = 1; k < n; k++) {
            int16_t p = centroid(&runs[k]);
            uint16_t gap = (uint16_t)(p > prev ? p - prev : prev - p);
            if (gap < best_gap) {
                best = p;
                best_gap = gap;
            }
        }
    }
    *position = best;
    return 1;
}

/* A function of its own, not inlined into the main loop with the other tasks: its many live values there cost more in
 * spilled registers than the call (measured on the bench). */
__attribute__((noinline)) void line_sensor_task(void)
{
    if (ready) {
        ready = 0;
        uint16_t spot_raw[LINE_SPOTS];
        /* Each reading stored in the state as it is made (copying the 16 bytes after took 117 cycles). */
#define SPOT(i, lit, d) robot_state.line.raw[i] = spot_raw[i] = (lit[d] > dark[d] ? (uint16_t)(lit[d] - dark[d]) : 0u)
        SPOT(0, lit_a, 0);
        SPOT(1, lit_b, 0);
        SPOT(2, lit_b, 1);
        SPOT(3, lit_a, 1);
        SPOT(4, lit_a, 2);
        SPOT(5, lit_b, 2);
        SPOT(6, lit_b, 3);
        SPOT(7, lit_a, 3);
#undef SPOT
        int16_t pos = robot_state.line.position; /* where the line was: the branch to keep at a fork */
        uint8_t flags = robot_state.line.flags;
        if (line_sensor_evaluate(spot_raw, NULL, &pos)) {
            robot_state.line.position = pos;
            flags = PB_LINE_FLAG_SEEN;
            last_seen_ms = robot_state.time.time_ms;
        } else {
            flags &= (uint8_t)~PB_LINE_FLAG_SEEN;
        }
        if (!(flags & PB_LINE_FLAG_SEEN) && robot_state.time.time_ms - last_seen_ms >= settings.line_follow.lost_timeout_ms)
            flags |= PB_LINE_FLAG_LOST;
        robot_state.line.flags = flags;
    }
    if (phase == 0)
        start();
}
