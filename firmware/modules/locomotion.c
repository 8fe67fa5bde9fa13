#include "locomotion.h"

#include <stddef.h>
#include <string.h>

#include "core/data.h"
#include "core/fixed.h"
#include "core/scheduler.h"
#include "drivers/motors.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/movement_log.h"
#include "modules/pid.h"
#include "modules/speed.h"

_Static_assert(MOVEMENT_LOG_SIZE >= LOCOMOTION_QUEUE_SIZE, "a failsafe that clears a full queue is logged whole");

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
    float scale;      /* request / master: the distance (m) or angle (deg) asked for per um of the faster wheel,
                       * so that `done` is reported in the request's unit and sign with one multiplication */
} movement_t;

static movement_t queue[LOCOMOTION_QUEUE_SIZE];
static uint8_t q_head, q_count; /* the running movement stays at the head */

static struct {
    uint8_t running;
    uint8_t braking;
    uint8_t stopping;      /* braking on a host's stop: it ends as stopped */
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
static int16_t coast_q14; /* learnt coasting time, Q14 seconds (0 until the first observation) */
static uint8_t coast_seen;

/* A movement that ended while the robot still rolls: its result is recorded at once with what it did so far
 * and settled when the wheels stand still (or something else drives them, or LOCOMOTION_SETTLE_MS passed),
 * with the coasting included. The same observation teaches the coasting time. */
static struct {
    uint8_t active;
    uint8_t learn;         /* a finished movement coming to rest: learn the coasting time from it */
    uint8_t finished;      /* its outcome is finished: locomotion.finished_id when settled */
    uint16_t id;
    int32_t sl0, sr0;      /* the movement's frame */
    int16_t pl, pr;
    float scale;
    int32_t s_cut, v_cut;  /* distance done (um) and speed (um/s) when the motors were cut */
    uint32_t since_ms;
} settle;

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

/* The conversion when settings changed: float arithmetic, a call that saves every register. */
static __attribute__((noinline)) void params_changed(void)
{
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

/* The test of every tick, inline: the conversion apart. */
static inline __attribute__((always_inline)) void refresh_params(void)
{
    if (k.gen != settings_generation)
        params_changed();
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

static uint8_t on_move_straight(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_move_rotate(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_move_arc(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_stop(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_wheel_speeds(const pb_frame_t *cmd, uint16_t *detail);

void locomotion_init(void)
{
    q_head = q_count = 0;
    act.running = 0;
    act.stopping = 0;
    settle.active = 0;
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
    movement_log_init();
    comm_register(PB_PKT_MOVE_STRAIGHT, on_move_straight);
    comm_register(PB_PKT_MOVE_ROTATE, on_move_rotate);
    comm_register(PB_PKT_MOVE_ARC, on_move_arc);
    comm_register(PB_PKT_STOP, on_stop);
    comm_register(PB_PKT_WHEEL_SPEEDS, on_wheel_speeds);
}

static uint8_t enqueue(uint16_t id, float dl, float dr, float v, float request)
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
    m->scale = request * inv_master * (1.0f / UM_PER_M); /* 0 for a movement of no length */
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

static bool distance_ok(float d)
{
    return is_finite(d) && d <= MAX_DISTANCE && d >= -MAX_DISTANCE;
}

static bool angle_ok(float a)
{
    return is_finite(a) && a <= 36000.0f && a >= -36000.0f;
}

/* Each refusal names the first refused field by its payload offset (error.detail). */
#define REFUSE(type, field)                                                                                \
    do {                                                                                                   \
        *detail = offsetof(type, field);                                                                   \
        return PB_ERROR_CODE_BAD_ARGUMENT;                                                                 \
    } while (0)

uint8_t locomotion_straight(const pb_move_straight_t *c, uint16_t *detail)
{
    if (c->id == 0)
        REFUSE(pb_move_straight_t, id);
    if (!distance_ok(c->distance_m))
        REFUSE(pb_move_straight_t, distance_m);
    if (!speed_ok(c->speed_mps))
        REFUSE(pb_move_straight_t, speed_mps);
    return enqueue(c->id, c->distance_m, c->distance_m, c->speed_mps, c->distance_m);
}

uint8_t locomotion_rotate(const pb_move_rotate_t *c, uint16_t *detail)
{
    if (c->id == 0)
        REFUSE(pb_move_rotate_t, id);
    if (!angle_ok(c->angle_deg))
        REFUSE(pb_move_rotate_t, angle_deg);
    if (!speed_ok(c->speed_mps))
        REFUSE(pb_move_rotate_t, speed_mps);
    float half = c->angle_deg * DEG_TO_RAD * 0.5f * settings.geometry.wheel_base_m;
    return enqueue(c->id, -half, half, c->speed_mps, c->angle_deg);
}

uint8_t locomotion_arc(const pb_move_arc_t *c, uint16_t *detail)
{
    if (c->id == 0)
        REFUSE(pb_move_arc_t, id);
    float radius_m = c->radius_m;
    if (!is_finite(radius_m) || radius_m <= 0.0f || radius_m > MAX_DISTANCE)
        REFUSE(pb_move_arc_t, radius_m);
    if (!angle_ok(c->angle_deg))
        REFUSE(pb_move_arc_t, angle_deg);
    if (!speed_ok(c->speed_mps))
        REFUSE(pb_move_arc_t, speed_mps);
    float th = c->angle_deg * DEG_TO_RAD;
    float ath = th < 0.0f ? -th : th;
    float half = 0.5f * settings.geometry.wheel_base_m;
    float dl = ath * radius_m - th * half;
    float dr = ath * radius_m + th * half;
    if (dl > MAX_WHEEL_DISTANCE || dl < -MAX_WHEEL_DISTANCE || dr > MAX_WHEEL_DISTANCE || dr < -MAX_WHEEL_DISTANCE)
        REFUSE(pb_move_arc_t, radius_m);
    /* The outer wheel is the faster one: scale the centre speed up to it. */
    float v = c->speed_mps * (radius_m + half) / radius_m;
    if (v > LOCOMOTION_MAX_SPEED)
        v = LOCOMOTION_MAX_SPEED;
    return enqueue(c->id, dl, dr, v, c->angle_deg);
}

/* What a movement did, in the unit and sign of its request. */
static float done_value(float scale, int32_t done_um)
{
    return scale * (float)done_um;
}

/* Progress of the movement with this frame along its faster wheel, um, now. */
static int32_t progress_um(int32_t sl0, int32_t sr0, int16_t pl, int16_t pr)
{
    int32_t sl, sr;
    speed_positions_um(&sl, &sr);
    return fx_frac(sl - sl0, pl) + fx_frac(sr - sr0, pr);
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

/* Records the settling result with what the wheels did by now; learns the coasting time when asked to. */
static void settle_finish(bool at_rest)
{
    settle.active = 0;
    int32_t done = progress_um(settle.sl0, settle.sr0, settle.pl, settle.pr);
    movement_log_settle(done_value(settle.scale, done));
    if (settle.finished)
        robot_state.locomotion.finished_id = settle.id;
    if (!settle.learn || !at_rest)
        return;
    int16_t t = coast_time(done - settle.s_cut, settle.v_cut);
    /* Learn at 0.3 (19661 / 2^16) of the way towards each new observation. */
    coast_q14 = coast_seen ? (int16_t)(coast_q14 + (((int32_t)t - coast_q14) * 19661L >> 16)) : t;
    coast_seen = 1;
    DEBUG_PRINT(LOCOMOTION, 3, "coasting %u ms", (unsigned)(((uint32_t)coast_q14 * 1000u) >> 14));
}

/* The running movement `m` ended with the robot still rolling: record it now, settle it at rest. */
static void settle_begin(const movement_t *m, uint8_t outcome, int32_t s_done, int32_t v_now, bool learn)
{
    if (settle.active) /* the previous one rolled into this one: it is as done as it gets */
        settle_finish(false);
    settle.active = 1;
    settle.learn = learn;
    settle.finished = outcome == PB_MOVEMENT_OUTCOME_FINISHED;
    settle.id = m->id;
    settle.sl0 = act.sl0;
    settle.sr0 = act.sr0;
    settle.pl = m->pl;
    settle.pr = m->pr;
    settle.scale = m->scale;
    settle.s_cut = s_done;
    settle.v_cut = v_now;
    settle.since_ms = robot_state.time.time_ms;
    movement_log_record(m->id, outcome, done_value(m->scale, s_done), false);
}

static void settle_step(void)
{
    uint8_t mode_now = robot_state.locomotion.mode;
    bool driven = mode_now == PB_LOCO_MODE_MOVEMENT || mode_now == PB_LOCO_MODE_TELEOP ||
                  mode_now == PB_LOCO_MODE_LINE_FOLLOW || mode_now == PB_LOCO_MODE_TRACK;
    bool at_rest = speed_umps(0) == 0 && speed_umps(1) == 0;
    if (at_rest || driven || robot_state.time.time_ms - settle.since_ms >= LOCOMOTION_SETTLE_MS)
        settle_finish(at_rest && !driven);
}

/* Ends every queued movement: the running one (settled at rest) with `running_outcome` (stopped if a host's
 * stop is braking it), the others with `queued_outcome`, in queue order. */
static void clear_queue(uint8_t running_outcome, uint8_t queued_outcome)
{
    uint8_t i = 0;
    if (q_count && act.running) {
        const movement_t *m = &queue[q_head];
        int32_t v = fx_frac(speed_umps(0), m->pl) + fx_frac(speed_umps(1), m->pr);
        settle_begin(m, act.stopping ? PB_MOVEMENT_OUTCOME_STOPPED : running_outcome,
                     progress_um(act.sl0, act.sr0, m->pl, m->pr), v, false);
        i = 1;
    }
    for (; i < q_count; i++)
        movement_log_record(queue[(uint8_t)(q_head + i) % LOCOMOTION_QUEUE_SIZE].id, queued_outcome, 0.0f, true);
    q_count = 0;
    act.running = 0;
    act.braking = 0;
    act.stopping = 0;
    robot_state.locomotion.queue_length = 0;
    robot_state.locomotion.current_id = 0;
}

void locomotion_stop(bool immediate)
{
    if (!immediate && mode() == PB_LOCO_MODE_MOVEMENT && act.running) {
        /* Keep only the running movement, and brake it; the rest never started. */
        for (uint8_t i = 1; i < q_count; i++)
            movement_log_record(queue[(uint8_t)(q_head + i) % LOCOMOTION_QUEUE_SIZE].id, PB_MOVEMENT_OUTCOME_DROPPED,
                                0.0f, true);
        q_count = 1;
        act.braking = 1;
        act.stopping = 1;
        robot_state.locomotion.queue_length = 1;
        return;
    }
    clear_queue(PB_MOVEMENT_OUTCOME_STOPPED, PB_MOVEMENT_OUTCOME_DROPPED);
    set_mode(PB_LOCO_MODE_IDLE);
    target[0] = target[1] = 0;
    motors_set(0, 0);
}

uint8_t locomotion_teleop(const pb_wheel_speeds_t *c, uint16_t *detail)
{
    float left = c->left_mps, right = c->right_mps;
    if (!is_finite(left) || left > LOCOMOTION_MAX_SPEED || left < -LOCOMOTION_MAX_SPEED)
        REFUSE(pb_wheel_speeds_t, left_mps);
    if (!is_finite(right) || right > LOCOMOTION_MAX_SPEED || right < -LOCOMOTION_MAX_SPEED)
        REFUSE(pb_wheel_speeds_t, right_mps);
    clear_queue(PB_MOVEMENT_OUTCOME_STOPPED, PB_MOVEMENT_OUTCOME_DROPPED);
    set_mode(PB_LOCO_MODE_TELEOP);
    locomotion_wheel_setpoints(round_to_int(left * UM_PER_M), round_to_int(right * UM_PER_M));
    return PB_ERROR_CODE_NONE;
}

/* A module steering the wheels by set points takes the motors. */
static void wheels_begin(uint8_t m)
{
    clear_queue(PB_MOVEMENT_OUTCOME_STOPPED, PB_MOVEMENT_OUTCOME_DROPPED);
    set_mode(m);
    target[0] = target[1] = 0;
}

void locomotion_line_follow_begin(void)
{
    wheels_begin(PB_LOCO_MODE_LINE_FOLLOW);
}

void locomotion_track_begin(void)
{
    wheels_begin(PB_LOCO_MODE_TRACK);
}

void locomotion_wheel_setpoints(int32_t left_umps, int32_t right_umps)
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
    clear_queue(PB_MOVEMENT_OUTCOME_FAILSAFE, PB_MOVEMENT_OUTCOME_FAILSAFE);
    set_mode(PB_LOCO_MODE_FAILSAFE);
    target[0] = target[1] = 0;
    motors_set(0, 0);
}

/* Per-wheel speed PIDs towards target[] (teleoperation, line following, track). */
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
    act.stopping = 0;
    if (chain) {
        act.sl0 = end_l;
        act.sr0 = end_r;
    } else {
        speed_positions_um(&act.sl0, &act.sr0);
    }
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

/* The running movement ended: at a hand-over to the next one it is recorded now, with what its wheels did
 * (the next one starts from its ideal end, so the rest is driven as part of that one); before a rest it
 * settles first. */
static void finish(bool completed, int32_t s_done, int32_t v_now)
{
    const movement_t *m = &queue[q_head];
    uint8_t outcome = completed ? PB_MOVEMENT_OUTCOME_FINISHED : PB_MOVEMENT_OUTCOME_STOPPED;
    end_l = act.sl0 + m->dl;
    end_r = act.sr0 + m->dr;
    if (completed && q_count > 1) {
        movement_log_record(m->id, outcome, done_value(m->scale, s_done), true);
        robot_state.locomotion.finished_id = m->id;
    } else {
        settle_begin(m, outcome, s_done, v_now, completed && v_now > COAST_MIN_V_UMPS);
    }
    DEBUG_PRINT(LOCOMOTION, 2, "done %u (%u)", m->id, outcome);
    act.running = 0;
    act.stopping = 0;
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

float locomotion_coast_s(void)
{
    return (float)coast_q14 / (float)FX_ONE;
}

/* ---- host commands ---- */

static uint8_t on_move_straight(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_move_straight_t c;
    memcpy(&c, cmd->payload, sizeof c);
    return locomotion_straight(&c, detail);
}

static uint8_t on_move_rotate(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_move_rotate_t c;
    memcpy(&c, cmd->payload, sizeof c);
    return locomotion_rotate(&c, detail);
}

static uint8_t on_move_arc(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_move_arc_t c;
    memcpy(&c, cmd->payload, sizeof c);
    return locomotion_arc(&c, detail);
}

static uint8_t on_stop(const pb_frame_t *cmd, uint16_t *detail)
{
    uint8_t immediate = cmd->payload[offsetof(pb_stop_t, immediate)];
    if (immediate > 1)
        REFUSE(pb_stop_t, immediate);
    locomotion_stop(immediate != 0); /* line following sees its mode gone and stops too */
    return PB_ERROR_CODE_NONE;
}

static uint8_t on_wheel_speeds(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_wheel_speeds_t c;
    memcpy(&c, cmd->payload, sizeof c);
    return locomotion_teleop(&c, detail);
}

void locomotion_task(void)
{
    refresh_params();
    if (settle.active)
        settle_step();
    switch (mode()) {
    case PB_LOCO_MODE_MOVEMENT:
        movement_step();
        break;
    case PB_LOCO_MODE_TELEOP:
    case PB_LOCO_MODE_LINE_FOLLOW:
    case PB_LOCO_MODE_TRACK:
        wheel_step();
        break;
    default:
        motors_set(0, 0);
        break;
    }
    movement_log_task();
}
