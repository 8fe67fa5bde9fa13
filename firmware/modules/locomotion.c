#include "locomotion.h"

#include "drivers/motors.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/fixed.h"
#include "modules/pid.h"
#include "modules/reflector.h"
#include "modules/scheduler.h"
#include "modules/settings.h"
#include "modules/speed.h"

#define DEG_TO_RAD 0.0174532925f
#define MAX_DISTANCE 100.0f
/** Longest wheel distance of one movement, m: well inside what the um arithmetic holds (FX_FRAC_MAX). */
#define MAX_WHEEL_DISTANCE 1000.0f
#define UM_PER_M 1.0e6f
/** Movements shorter than this (faster wheel, um) are done at once. */
#define MIN_MASTER_UM 10
/** Braking works on squared speeds in units of 2^BRAKE_SHIFT um/s (squares of up to 4 m/s fit 32 bits). */
#define BRAKE_SHIFT 6

/* A queued movement, converted to fixed point when it is queued (the divisions happen there, once). */
typedef struct {
    uint16_t id;
    int32_t dl, dr;   /* wheel distances, um, signed */
    int32_t v;        /* cruise speed of the faster wheel, um/s */
    int32_t master;   /* distance of the faster wheel, um */
    int16_t bl, br;   /* left:right shares dl/master, dr/master, Q14 */
    int16_t pl, pr;   /* projections: done along the faster wheel = sl * pl + sr * pr, Q14 */
} movement_t;

static movement_t queue[LOCOMOTION_QUEUE_SIZE];
static uint8_t q_head, q_count; /* the running movement stays at the head */

static struct {
    uint8_t running;
    uint8_t braking;
    int32_t sl0, sr0;      /* wheel positions at the start, um */
    int32_t vmin;          /* um/s */
    uint32_t vmin_sq;      /* (vmin >> BRAKE_SHIFT)^2 */
    int32_t accel_dt, decel_dt; /* profile slopes, um/s per tick */
    int32_t v_prof;        /* speed of the profile's rising side, um/s */
} act;

/* Coasting: after the motors are cut at the end of a movement the robot rolls on for about its speed times
 * a time constant of the drive. That time is learnt from every movement after which the robot comes to
 * rest, and later movements cut the motors that much earlier. */
#define COAST_MAX_Q14 4915 /* 0.3 s in Q14 seconds */
#define COAST_MIN_V_UMPS 5000
static struct {
    uint8_t watching;
    int32_t sl0, sr0;      /* the finished movement's frame */
    int16_t pl, pr;
    int32_t s_cut, v_cut;  /* distance done (um) and speed (um/s) when the motors were cut */
} coast;
static int16_t coast_q14; /* learnt coasting time, Q14 seconds (0 until the first observation) */
static uint8_t coast_seen;

/* Where the last movement should have ended, when the next one follows straight on. */
static uint8_t chain;
static int32_t end_l, end_r;

static pid_state_t speed_pid, balance_pid, wheel_pid[2];
static int32_t target[2]; /* um/s */

/* Controller parameters converted from the float settings when they change. */
static struct {
    uint8_t gen;
    pid_gains_t speed, wheel, balance;
    fx_gain_t accel, decel; /* m/s^2 = um/s per us */
    fx_gain_t brake;        /* 2 * decel in (2^BRAKE_SHIFT um/s)^2 per um */
    int32_t vmin;           /* profile.min_speed_mps, um/s */
} k;

static void refresh_params(void)
{
    if (k.gen == settings_generation)
        return;
    k.gen = settings_generation;
    pid_gains_convert(&k.speed, &settings.speed_pid, UM_PER_M, 1.0f);
    pid_gains_convert(&k.wheel, &settings.wheel_pid, UM_PER_M, 1.0f);
    pid_gains_convert(&k.balance, &settings.wheel_balance, UM_PER_M, 1.0f);
    const pb_settings_profile_t *p = &settings.profile;
    k.accel = fx_gain(p->accel_mps2);
    k.decel = fx_gain(p->decel_mps2);
    k.brake = fx_gain(2.0f * p->decel_mps2 * UM_PER_M / (float)(1ul << (2 * BRAKE_SHIFT)));
    k.vmin = (int32_t)(p->min_speed_mps * UM_PER_M + 0.5f);
}

static uint8_t mode(void)
{
    return robot_state.locomotion.mode;
}

static void set_mode(uint8_t m)
{
    if (robot_state.locomotion.mode != m) {
        pid_reset(&wheel_pid[0]);
        pid_reset(&wheel_pid[1]);
    }
    robot_state.locomotion.mode = m;
}

/* Output clamp of the motor controllers, Q16 permille. */
static int32_t pwm_limit_q16(void)
{
    uint16_t lim = settings.motors.pwm_limit > 1000u ? 1000u : settings.motors.pwm_limit;
    return (int32_t)lim << PID_Q;
}

/* The encoders have one channel and count in the direction the motor is driven: a wheel is never driven
 * against the way it should turn (that would miscount the pulses while it still rolls forward).
 * \param duty Q16 permille */
static int16_t duty_towards(int32_t duty, int32_t direction)
{
    if ((direction > 0 && duty < 0) || (direction < 0 && duty > 0) || direction == 0)
        return 0;
    return (int16_t)fx_round_q16(fx_clamp(duty, 1000L << PID_Q));
}

static bool is_finite(float v)
{
    return v == v && v - v == 0.0f;
}

static int32_t round_to_int(float v)
{
    return (int32_t)(v >= 0.0f ? v + 0.5f : v - 0.5f);
}

static int16_t to_q14(float v)
{
    return (int16_t)round_to_int(v * (float)FX_ONE);
}

void locomotion_init(void)
{
    q_head = q_count = 0;
    act.running = 0;
    coast.watching = 0;
    coast_q14 = 0;
    coast_seen = 0;
    chain = 0;
    target[0] = target[1] = 0;
    k.gen = (uint8_t)(settings_generation - 1u);
    refresh_params();
    robot_state.locomotion.mode = PB_LOCO_MODE_IDLE;
    robot_state.locomotion.queue_length = 0;
    robot_state.locomotion.current_id = 0;
    robot_state.locomotion.finished_id = 0;
}

static uint8_t enqueue(uint16_t id, float dl, float dr, float v)
{
    if (q_count >= LOCOMOTION_QUEUE_SIZE)
        return PB_ERROR_CODE_QUEUE_FULL;
    movement_t *m = &queue[(uint8_t)(q_head + q_count) % LOCOMOTION_QUEUE_SIZE];
    m->id = id;
    m->dl = round_to_int(dl * UM_PER_M);
    m->dr = round_to_int(dr * UM_PER_M);
    m->v = round_to_int(v * UM_PER_M);
    float al = dl < 0.0f ? -dl : dl;
    float ar = dr < 0.0f ? -dr : dr;
    float master = al > ar ? al : ar;
    float inv_master = master > 0.0f ? 1.0f / master : 0.0f;
    float bl = dl * inv_master, br = dr * inv_master;
    /* (sl*dl + sr*dr) / (dl^2 + dr^2) is the fraction done; times master, the distance done. */
    float b2 = bl * bl + br * br;
    float inv_b2 = b2 > 0.0f ? 1.0f / b2 : 0.0f;
    m->master = m->dl < 0 ? -m->dl : m->dl;
    if (m->dr > m->master || -m->dr > m->master)
        m->master = m->dr < 0 ? -m->dr : m->dr;
    m->bl = to_q14(bl);
    m->br = to_q14(br);
    m->pl = to_q14(bl * inv_b2);
    m->pr = to_q14(br * inv_b2);
    q_count++;
    if (mode() != PB_LOCO_MODE_MOVEMENT) {
        set_mode(PB_LOCO_MODE_MOVEMENT);
        chain = 0;
    }
    robot_state.locomotion.queue_length = q_count;
    return PB_ERROR_CODE_NONE;
}

static bool speed_ok(float v)
{
    return is_finite(v) && v > 0.0f && v <= LOCOMOTION_MAX_SPEED;
}

uint8_t locomotion_straight(uint16_t id, float distance_m, float speed_mps)
{
    if (id == 0 || !speed_ok(speed_mps) || !is_finite(distance_m) || distance_m > MAX_DISTANCE ||
        distance_m < -MAX_DISTANCE)
        return PB_ERROR_CODE_BAD_ARGUMENT;
    return enqueue(id, distance_m, distance_m, speed_mps);
}

uint8_t locomotion_rotate(uint16_t id, float angle_deg, float speed_mps)
{
    if (id == 0 || !speed_ok(speed_mps) || !is_finite(angle_deg) || angle_deg > 36000.0f || angle_deg < -36000.0f)
        return PB_ERROR_CODE_BAD_ARGUMENT;
    float half = angle_deg * DEG_TO_RAD * 0.5f * settings.geometry.wheel_base_m;
    return enqueue(id, -half, half, speed_mps);
}

uint8_t locomotion_arc(uint16_t id, float radius_m, float angle_deg, float speed_mps)
{
    if (id == 0 || !speed_ok(speed_mps) || !is_finite(angle_deg) || angle_deg > 36000.0f || angle_deg < -36000.0f ||
        !is_finite(radius_m) || radius_m <= 0.0f || radius_m > MAX_DISTANCE)
        return PB_ERROR_CODE_BAD_ARGUMENT;
    float th = angle_deg * DEG_TO_RAD;
    float ath = th < 0.0f ? -th : th;
    float half = 0.5f * settings.geometry.wheel_base_m;
    float dl = ath * radius_m - th * half;
    float dr = ath * radius_m + th * half;
    if (dl > MAX_WHEEL_DISTANCE || dl < -MAX_WHEEL_DISTANCE || dr > MAX_WHEEL_DISTANCE || dr < -MAX_WHEEL_DISTANCE)
        return PB_ERROR_CODE_BAD_ARGUMENT;
    /* The outer wheel is the faster one: scale the centre speed up to it. */
    float v = speed_mps * (radius_m + half) / radius_m;
    if (v > LOCOMOTION_MAX_SPEED)
        v = LOCOMOTION_MAX_SPEED;
    return enqueue(id, dl, dr, v);
}

static void clear_queue(void)
{
    q_count = 0;
    act.running = 0;
    act.braking = 0;
    robot_state.locomotion.queue_length = 0;
    robot_state.locomotion.current_id = 0;
}

void locomotion_stop(bool immediate)
{
    if (!immediate && mode() == PB_LOCO_MODE_MOVEMENT && act.running) {
        q_count = 1; /* keep only the running movement, and brake it */
        act.braking = 1;
        robot_state.locomotion.queue_length = 1;
        return;
    }
    clear_queue();
    set_mode(PB_LOCO_MODE_IDLE);
    motors_set(0, 0);
}

uint8_t locomotion_teleop(float left_mps, float right_mps)
{
    if (!is_finite(left_mps) || !is_finite(right_mps) || left_mps > LOCOMOTION_MAX_SPEED ||
        left_mps < -LOCOMOTION_MAX_SPEED || right_mps > LOCOMOTION_MAX_SPEED || right_mps < -LOCOMOTION_MAX_SPEED)
        return PB_ERROR_CODE_BAD_ARGUMENT;
    clear_queue();
    set_mode(PB_LOCO_MODE_TELEOP);
    locomotion_line_follow_set(round_to_int(left_mps * UM_PER_M), round_to_int(right_mps * UM_PER_M));
    return PB_ERROR_CODE_NONE;
}

void locomotion_line_follow_begin(void)
{
    clear_queue();
    set_mode(PB_LOCO_MODE_LINE_FOLLOW);
    target[0] = target[1] = 0;
}

void locomotion_line_follow_set(int32_t left_umps, int32_t right_umps)
{
    /* A wheel that reverses starts its PID afresh: the old integral pushes the wrong way. */
    if ((left_umps < 0) != (target[0] < 0))
        pid_reset(&wheel_pid[0]);
    if ((right_umps < 0) != (target[1] < 0))
        pid_reset(&wheel_pid[1]);
    target[0] = left_umps;
    target[1] = right_umps;
}

void locomotion_failsafe(void)
{
    clear_queue();
    set_mode(PB_LOCO_MODE_FAILSAFE);
    motors_set(0, 0);
}

/* Per-wheel speed PIDs towards target[] (teleoperation and line following). */
HAL_NOINLINE_SIM static void wheel_step(void)
{
    int32_t lim = pwm_limit_q16();
    int16_t duty[2];
    for (uint8_t w = 0; w < 2; w++) {
        if (target[w] == 0) { /* hold still without creeping on a leftover integral */
            pid_reset(&wheel_pid[w]);
            duty[w] = 0;
        } else {
            duty[w] = duty_towards(pid_update(&wheel_pid[w], &k.wheel, target[w] - speed_umps(w), lim), target[w]);
        }
    }
    motors_set(duty[0], duty[1]);
}

static void start_next(void)
{
    const movement_t *m = &queue[q_head];
    act.running = 1;
    act.braking = 0;
    act.sl0 = chain ? end_l : speed_position_um(0);
    act.sr0 = chain ? end_r : speed_position_um(1);
    act.vmin = k.vmin < m->v ? k.vmin : m->v;
    uint32_t vq = (uint32_t)act.vmin >> BRAKE_SHIFT;
    act.vmin_sq = vq * vq;
    int32_t period_us = scheduler_period_us();
    act.accel_dt = fx_mul(period_us, &k.accel);
    act.decel_dt = fx_mul(period_us, &k.decel);
    act.v_prof = act.vmin;
    pid_reset(&speed_pid);
    pid_reset(&balance_pid);
    robot_state.locomotion.current_id = m->id;
    DEBUG_PRINT(LOCOMOTION, 3, "start %u", m->id);
}

static void finish(bool completed, int32_t s_done, int32_t v_now)
{
    const movement_t *m = &queue[q_head];
    coast.watching = completed && q_count == 1 && v_now > COAST_MIN_V_UMPS;
    coast.sl0 = act.sl0;
    coast.sr0 = act.sr0;
    coast.pl = m->pl;
    coast.pr = m->pr;
    coast.s_cut = s_done;
    coast.v_cut = v_now;
    if (completed) {
        robot_state.locomotion.finished_id = m->id;
        pb_movement_done_t d = {m->id};
        comm_send(PB_PKT_MOVEMENT_DONE, &d, sizeof d);
        DEBUG_PRINT(LOCOMOTION, 2, "done %u", m->id);
    }
    end_l = act.sl0 + m->dl;
    end_r = act.sr0 + m->dr;
    act.running = 0;
    q_head = (uint8_t)((q_head + 1u) % LOCOMOTION_QUEUE_SIZE);
    q_count--;
    /* Only a movement that follows at once inherits the ideal end point (coasting is corrected). */
    chain = completed && q_count > 0;
    robot_state.locomotion.queue_length = q_count;
    robot_state.locomotion.current_id = 0;
    motors_set(0, 0);
    if (q_count == 0)
        set_mode(PB_LOCO_MODE_IDLE);
}

/* One step of the two chained controllers, in integers. */
HAL_NOINLINE_SIM static void movement_step(void)
{
    if (!act.running) {
        if (q_count == 0) {
            set_mode(PB_LOCO_MODE_IDLE);
            motors_set(0, 0);
            return;
        }
        start_next();
    }
    const movement_t *m = &queue[q_head];
    int32_t sl, sr;
    speed_positions_um(&sl, &sr);
    sl -= act.sl0;
    sr -= act.sr0;
    /* Progress: the projection of what the wheels did on what they must do. */
    int32_t done = fx_frac(sl, m->pl) + fx_frac(sr, m->pr);
    int32_t remaining = m->master - done;
    /* Speed of the faster wheel, measured along the movement. */
    int32_t v_meas = fx_frac(speed_umps(0), m->pl) + fx_frac(speed_umps(1), m->pr);
    if (m->master < MIN_MASTER_UM || remaining <= (v_meas > 0 ? fx_frac(v_meas, coast_q14) : 0)) {
        finish(true, done, v_meas);
        return;
    }
    if (act.braking) {
        act.v_prof -= act.decel_dt;
        if (act.v_prof <= act.vmin) {
            finish(false, done, v_meas);
            return;
        }
    } else if (act.v_prof < m->v) {
        act.v_prof += act.accel_dt;
        if (act.v_prof > m->v)
            act.v_prof = m->v;
    }
    /* Brake so as to reach vmin at the end: v^2 = vmin^2 + 2 a d (the square root only while braking).
     * remaining > 0 here; squares in (2^BRAKE_SHIFT um/s)^2, saturating. */
    int32_t v_set = act.v_prof;
    uint32_t decel_sq = (uint32_t)fx_mul(remaining, &k.brake);
    uint32_t brake_sq = decel_sq > 0xFFFFFFFFul - act.vmin_sq ? 0xFFFFFFFFul : act.vmin_sq + decel_sq;
    uint32_t vq = (uint32_t)v_set >> BRAKE_SHIFT;
    if (vq * vq > brake_sq)
        v_set = (int32_t)fx_isqrt(brake_sq) << BRAKE_SHIFT;

    int32_t lim = pwm_limit_q16();
    int32_t base = pid_update(&speed_pid, &k.speed, v_set - v_meas, lim);
    /* Balance: zero when each wheel has done the same share of its distance. */
    int32_t c = pid_update(&balance_pid, &k.balance, fx_frac(sl, m->br) - fx_frac(sr, m->bl), lim);
    motors_set(duty_towards(fx_frac(base, m->bl) - fx_frac(c, m->br), m->dl),
               duty_towards(fx_frac(base, m->br) + fx_frac(c, m->bl), m->dr));
}

/* Time to coast `d` um from `v` um/s, Q14 seconds, at most COAST_MAX_Q14. */
static int16_t coast_time(int32_t d, int32_t v)
{
    if (d <= 0)
        return 0;
    if (d >= v / 10 * 3 + 1) /* d / v >= 0.3 s (v / 10 * 3 <= 0.3 v: rounding keeps the cap) */
        return COAST_MAX_Q14;
    uint32_t ud = (uint32_t)d, uv = (uint32_t)v;
    while (ud >= (1ul << 17)) { /* keep ud << 14 within 32 bits */
        ud >>= 1;
        uv >>= 1;
    }
    uint32_t t = (ud << 14) / uv; /* uv > ud / 0.3 >= 1 */
    return (int16_t)(t > COAST_MAX_Q14 ? COAST_MAX_Q14 : t);
}

/* Once the robot rests after a movement, how far it rolled after the cut tells the coasting time. */
static void coast_watch(void)
{
    if (mode() != PB_LOCO_MODE_IDLE) {
        coast.watching = 0;
        return;
    }
    if (speed_umps(0) != 0 || speed_umps(1) != 0)
        return;
    coast.watching = 0;
    int32_t done = fx_frac(speed_position_um(0) - coast.sl0, coast.pl) +
                   fx_frac(speed_position_um(1) - coast.sr0, coast.pr);
    int16_t t = coast_time(done - coast.s_cut, coast.v_cut);
    /* Learn at 0.3 (19661 / 2^16) of the way towards each new observation. */
    coast_q14 = coast_seen ? (int16_t)(coast_q14 + (((int32_t)t - coast_q14) * 19661L >> 16)) : t;
    coast_seen = 1;
    DEBUG_PRINT(LOCOMOTION, 3, "coasting %u ms", (unsigned)(((uint32_t)coast_q14 * 1000u) >> 14));
}

float locomotion_coast_s(void)
{
    return (float)coast_q14 / (float)FX_ONE;
}

void locomotion_task(void)
{
    refresh_params();
    if (coast.watching)
        coast_watch();
    switch (mode()) {
    case PB_LOCO_MODE_MOVEMENT:
        movement_step();
        break;
    case PB_LOCO_MODE_TELEOP:
    case PB_LOCO_MODE_LINE_FOLLOW:
        wheel_step();
        break;
    default:
        motors_set(0, 0);
        break;
    }
}
