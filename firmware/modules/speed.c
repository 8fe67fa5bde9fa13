#include "speed.h"

#include <stdbool.h>

#include "core/data.h"
#include "core/fixed.h"
#include "drivers/encoder.h"
#include "hal/hal.h"

typedef struct {
    int32_t v;       /* um/s, signed */
    uint32_t v_tick; /* |v| in um per capture tick, Q32: the extrapolation's slope */
    int32_t count;   /* pulses */
    uint32_t last;   /* capture time of the last edge */
    uint8_t edges;
    int16_t mmps;    /* v for the state, updated with v */
    int32_t dist;    /* count * pulse length, um (floor), updated with the count */
    uint16_t dist_frac; /* and its fraction, 1/65536 um: a pulse more or less is an addition */
    uint32_t p2;     /* the two latest periods together, 0 unless both are known */
    uint8_t changes; /* encoder_changes() at the last snapshot */
} wheel_t;

static wheel_t wheels[2];

/* Derived from the geometry settings when they change (the only float arithmetic of this module). */
static struct {
    uint8_t gen;
    uint32_t pulse_q16;  /* pulse length, um in Q16 (up to 65535 um) */
    uint32_t k_m;        /* two pulse lengths in um * 2^32 = k_m * 2^k_s, k_m normalised to 32 bits */
    uint8_t k_s;
    uint32_t q_max;      /* the largest quotient that k_s does not shift out of 32 bits */
    uint32_t ext_cap_um; /* extrapolation stops short of the next edge */
    uint32_t timeout;    /* speed timeout in capture ticks */
    uint16_t timeout_ms;
} geo;
static uint8_t geo_changed;

/* The conversion when settings changed: float arithmetic, a call that saves every register. */
static __attribute__((noinline)) void geometry_changed(void)
{
    uint16_t ppr = settings.encoder.pulses_per_rev ? settings.encoder.pulses_per_rev : 1u;
    float pulse_um = 3.14159265e6f * settings.geometry.wheel_diameter_m / (float)ppr;
    geo.pulse_q16 = pulse_um < 65535.0f ? (uint32_t)(pulse_um * 65536.0f + 0.5f) : 0xFFFFFFFFul;
    float k = 2.0f * pulse_um * 4294967296.0f;
    uint8_t s = 0;
    while (k >= 4294967296.0f && s < 40) {
        k *= 0.5f;
        s++;
    }
    geo.k_m = (uint32_t)k;
    geo.k_s = s < 31 ? s : 31;
    geo.q_max = s < 31 ? 0xFFFFFFFFul >> s : 0;
    geo.ext_cap_um = (uint32_t)(0.95f * pulse_um);
    geo.timeout_ms = settings.encoder.speed_timeout_ms;
    geo.timeout = (uint32_t)geo.timeout_ms * (HAL_CAPTURE_HZ / 1000u);
    geo.gen = settings_generation;
    geo_changed = 1;
}

/* The test of every tick, inline: the conversion apart. */
static inline __attribute__((always_inline)) void refresh_geometry(void)
{
    if (geo.gen != settings_generation || geo.timeout_ms != settings.encoder.speed_timeout_ms)
        geometry_changed();
}

void speed_init(void)
{
    for (uint8_t w = 0; w < 2; w++) {
        wheels[w].v = 0;
        wheels[w].v_tick = 0;
        wheels[w].count = 0;
        wheels[w].last = 0;
        wheels[w].edges = 0;
        wheels[w].mmps = 0;
        wheels[w].dist = 0;
        wheels[w].dist_frac = 0;
        wheels[w].p2 = 0;
        wheels[w].changes = (uint8_t)(encoder_changes(w) - 1u);
    }
    geo.gen = (uint8_t)(settings_generation - 1u);
    refresh_geometry();
}

/* Two pulses in `ticks` capture ticks (> 0), as um per tick in Q32 (saturated at 1 um/tick = 4 m/s). */
static uint32_t two_pulses_in(uint32_t ticks)
{
    uint32_t q = fx_udiv(geo.k_m, ticks);
    return q > geo.q_max ? 0xFFFFFFFFul : fx_shl(q, geo.k_s);
}

static uint32_t tick_speed(uint32_t p0, uint32_t p1, uint32_t timeout_ticks)
{
    if (p0 == 0 || p0 > timeout_ticks)
        return 0;
    if (p1 == 0 || p1 > timeout_ticks) /* one period only: the stripe asymmetry shows, but it is a speed */
        return two_pulses_in(2u * p0);
    return two_pulses_in(p0 + p1);
}

static int32_t tick_to_umps(uint32_t v_tick)
{
    return (int32_t)fx_mulhi(v_tick, HAL_CAPTURE_HZ); /* < 4e6 */
}

int32_t speed_from_periods(uint32_t p0, uint32_t p1, uint32_t timeout_ticks)
{
    refresh_geometry();
    return tick_to_umps(tick_speed(p0, p1, timeout_ticks));
}

static __attribute__((noinline)) void speed_changed(wheel_t *wh, uint32_t v_tick, bool negative)
{
    int32_t v = tick_to_umps(v_tick);
    wh->v_tick = v_tick;
    wh->v = negative ? -v : v;
    /* round(|v| / 1000) in mm/s, from um per capture tick: v_tick * 4000 / 2^32, plus a half */
    uint32_t mm = fx_mulhi16(v_tick, (uint16_t)(HAL_CAPTURE_HZ / 1000u));
    if ((uint32_t)v - mm * 1000u >= 500u)
        mm++;
    if (mm > 32767u)
        mm = 32767u;
    wh->mmps = negative ? -(int16_t)mm : (int16_t)mm;
}

/* Most ticks change nothing (a wheel at rest stays at 0): that test inline, the update apart. */
static inline __attribute__((always_inline)) void set_speed(wheel_t *wh, uint32_t v_tick, bool negative)
{
    if (v_tick != wh->v_tick || (wh->v < 0) != negative)
        speed_changed(wh, v_tick, negative);
}

/* dist = count * pulse, kept exactly in Q16: one pulse forwards or back (the usual case between two ticks)
 * is an addition; a jump or new geometry multiplies (64 bits, rare). */
static void set_distance(wheel_t *wh, int32_t count)
{
    int32_t step = count - wh->count;
    uint16_t frac = (uint16_t)geo.pulse_q16;
    int32_t whole = (int32_t)(geo.pulse_q16 >> 16);
    if (step == 1 && !geo_changed) {
        uint16_t f = (uint16_t)(wh->dist_frac + frac);
        wh->dist += whole + (f < frac); /* carry */
        wh->dist_frac = f;
    } else if (step == -1 && !geo_changed) {
        wh->dist -= whole + (wh->dist_frac < frac); /* borrow */
        wh->dist_frac = (uint16_t)(wh->dist_frac - frac);
    } else if (count == 0) {
        wh->dist = 0;
        wh->dist_frac = 0;
    } else {
        int64_t q = (int64_t)count * (int64_t)geo.pulse_q16;
        wh->dist = (int32_t)(q >> 16); /* arithmetic: floor, as the steps keep it */
        wh->dist_frac = (uint16_t)q;
    }
    wh->count = count;
}

void speed_task(void)
{
    refresh_geometry();
    uint32_t timeout = geo.timeout;
    uint32_t now = hal_capture_now();
    /* The bound of a late edge (a 32-bit division, a few hundred cycles on the AVR) waits for a tick in which
     * no edge was divided: a soft bound 1 ms later changes nothing, and the worst tick has one division less. */
    bool divided = false;
    for (uint8_t w = 0; w < 2; w++) {
        wheel_t *wh = &wheels[w];
        bool edge = false;
        uint8_t changes = encoder_changes(w);
        if (changes != wh->changes || geo_changed) { /* else the snapshot would be the same as last time */
            encoder_snapshot_t s;
            encoder_snapshot(w, &s);
            wh->changes = changes;
            if (s.count != wh->count || geo_changed)
                set_distance(wh, s.count);
            wh->last = s.last;
            wh->p2 = s.periods >= 2 ? s.period[0] + s.period[1] : 0;
            if (s.edges != wh->edges) { /* a new pulse: one division, the fixed delta-s speed */
                wh->edges = s.edges;
                edge = true;
                divided = true;
                set_speed(wh, tick_speed(s.periods >= 1 ? s.period[0] : 0, s.periods >= 2 ? s.period[1] : 0, timeout),
                          s.dir < 0);
            }
        }
        if (edge)
            continue;
        uint32_t age = now - wh->last;
        if (age > timeout) {
            set_speed(wh, 0, false);
        } else if (wh->p2 != 0 && wh->v_tick != 0 && age > wh->p2 && !divided) {
            /* The next edge is late (later than two stripes took): no stripe is longer than two mean pulses,
             * so the wheel is at most that fast now. Lets the speed fall before the timeout. */
            divided = true;
            uint32_t bound = two_pulses_in(age);
            if (wh->v_tick > bound)
                set_speed(wh, bound, wh->v < 0);
        }
    }
    geo_changed = 0;
    robot_state.wheels.speed_left_mmps = wheels[0].mmps;
    robot_state.wheels.speed_right_mmps = wheels[1].mmps;
    robot_state.encoders.left = wheels[0].count;
    robot_state.encoders.right = wheels[1].count;
}

int32_t speed_umps(uint8_t wheel)
{
    return wheels[wheel & 1u].v;
}

/* Inlined for both wheels in speed_positions_um(): a call of its own saved and restored 16 registers, a third of
 * its cost. */
static inline __attribute__((always_inline)) int32_t position(const wheel_t *wh, uint32_t now)
{
    if (wh->v_tick == 0)
        return wh->dist;
    /* Between edges the wheel keeps going: extrapolate, but never past the next edge. */
    uint32_t age = now - wh->last;
    uint32_t ext = age >> 16 ? fx_mulhi(wh->v_tick, age) : fx_mulhi16(wh->v_tick, (uint16_t)age);
    if (ext > geo.ext_cap_um)
        ext = geo.ext_cap_um;
    return wh->v < 0 ? wh->dist - (int32_t)ext : wh->dist + (int32_t)ext;
}

/* Not inlined into its callers: position()'s two copies here are enough flash. */
__attribute__((noinline)) void speed_positions_um(int32_t *left, int32_t *right)
{
    uint32_t now = hal_capture_now();
    *left = position(&wheels[0], now);
    *right = position(&wheels[1], now);
}

int32_t speed_position_um(uint8_t wheel)
{
    int32_t at[2];
    speed_positions_um(&at[0], &at[1]);
    return at[wheel & 1u];
}
