#include "locomotion.h"

#include "drivers/motors.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/pid.h"
#include "modules/reflector.h"
#include "modules/scheduler.h"
#include "modules/settings.h"
#include "modules/speed.h"

#define DEG_TO_RAD 0.0174532925f
#define MAX_DISTANCE 100.0f

typedef struct {
    uint16_t id;
    float dl, dr; /* wheel distances, m, signed */
    float v;      /* cruise speed of the faster wheel, m/s */
} movement_t;

static movement_t queue[LOCOMOTION_QUEUE_SIZE];
static uint8_t q_head, q_count; /* the running movement stays at the head */

static struct {
    uint8_t running;
    uint8_t braking;
    float sl0, sr0;     /* wheel positions at the start */
    float master;       /* distance of the faster wheel, m */
    float bl, br;       /* left:right shares dl/master, dr/master */
    float pl, pr;       /* projections: done along the faster wheel = sl * pl + sr * pr */
    float vmin, vmin_sq;
    float accel_dt, decel_dt, decel2;
    float v_prof;       /* speed of the profile's rising side */
} act;

/* Coasting: after the motors are cut at the end of a movement the robot rolls on for about its speed times
 * a time constant of the drive. That time is learnt from every movement after which the robot comes to
 * rest, and later movements cut the motors that much earlier. */
#define COAST_MAX_S 0.3f
static struct {
    uint8_t watching;
    float sl0, sr0, pl, pr; /* the finished movement's frame */
    float s_cut, v_cut;     /* distance done and speed when the motors were cut */
} coast;
static float coast_s; /* learnt coasting time, s (0 until the first observation) */
static uint8_t coast_seen;

/* Where the last movement should have ended, when the next one follows straight on. */
static uint8_t chain;
static float end_l, end_r;

static pid_state_t speed_pid, balance_pid, wheel_pid[2];
static float target[2];

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

static float pwm_limit(void)
{
    static uint16_t cached_raw = 0xFFFFu;
    static float cached;
    if (settings.motors.pwm_limit != cached_raw) {
        cached_raw = settings.motors.pwm_limit;
        cached = cached_raw > 1000u ? 1000.0f : (float)cached_raw;
    }
    return cached;
}

static int16_t round_duty(float v)
{
    return (int16_t)(v >= 0.0f ? v + 0.5f : v - 0.5f);
}

/* The encoders have one channel and count in the direction the motor is driven: a wheel is never driven
 * against the way it should turn (that would miscount the pulses while it still rolls forward). */
static int16_t duty_towards(float duty, float direction)
{
    if ((direction > 0.0f && duty < 0.0f) || (direction < 0.0f && duty > 0.0f) || direction == 0.0f)
        return 0;
    return round_duty(duty);
}

static bool is_finite(float v)
{
    return v == v && v - v == 0.0f;
}

void locomotion_init(void)
{
    q_head = q_count = 0;
    act.running = 0;
    coast.watching = 0;
    coast_s = 0.0f;
    coast_seen = 0;
    chain = 0;
    target[0] = target[1] = 0.0f;
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
    m->dl = dl;
    m->dr = dr;
    m->v = v;
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
    locomotion_line_follow_set(left_mps, right_mps);
    return PB_ERROR_CODE_NONE;
}

void locomotion_line_follow_begin(void)
{
    clear_queue();
    set_mode(PB_LOCO_MODE_LINE_FOLLOW);
    target[0] = target[1] = 0.0f;
}

void locomotion_line_follow_set(float left_mps, float right_mps)
{
    /* A wheel that reverses starts its PID afresh: the old integral pushes the wrong way. */
    if ((left_mps < 0.0f) != (target[0] < 0.0f))
        pid_reset(&wheel_pid[0]);
    if ((right_mps < 0.0f) != (target[1] < 0.0f))
        pid_reset(&wheel_pid[1]);
    target[0] = left_mps;
    target[1] = right_mps;
}

void locomotion_failsafe(void)
{
    clear_queue();
    set_mode(PB_LOCO_MODE_FAILSAFE);
    motors_set(0, 0);
}

/* Per-wheel speed PIDs towards target[] (teleoperation and line following). */
static void wheel_step(void)
{
    float lim = pwm_limit();
    int16_t duty[2];
    for (uint8_t w = 0; w < 2; w++) {
        if (target[w] == 0.0f) { /* hold still without creeping on a leftover integral */
            pid_reset(&wheel_pid[w]);
            duty[w] = 0;
        } else {
            duty[w] = duty_towards(pid_update(&wheel_pid[w], &settings.wheel_pid, target[w] - speed_mps(w), lim),
                                   target[w]);
        }
    }
    motors_set(duty[0], duty[1]);
}

static void start_next(void)
{
    const movement_t *m = &queue[q_head];
    const pb_settings_profile_t *p = &settings.profile;
    act.running = 1;
    act.braking = 0;
    act.sl0 = chain ? end_l : speed_distance_m(0);
    act.sr0 = chain ? end_r : speed_distance_m(1);
    float al = m->dl < 0.0f ? -m->dl : m->dl;
    float ar = m->dr < 0.0f ? -m->dr : m->dr;
    act.master = al > ar ? al : ar;
    float inv_master = act.master > 0.0f ? 1.0f / act.master : 0.0f;
    act.bl = m->dl * inv_master;
    act.br = m->dr * inv_master;
    /* (sl*dl + sr*dr) / (dl^2 + dr^2) is the fraction done; times master, the distance done. */
    float b2 = act.bl * act.bl + act.br * act.br;
    float inv_b2 = b2 > 0.0f ? 1.0f / b2 : 0.0f;
    act.pl = act.bl * inv_b2;
    act.pr = act.br * inv_b2;
    act.vmin = p->min_speed_mps < m->v ? p->min_speed_mps : m->v;
    act.vmin_sq = act.vmin * act.vmin;
    float dt = (float)scheduler_period_us() * 1.0e-6f;
    act.accel_dt = p->accel_mps2 * dt;
    act.decel_dt = p->decel_mps2 * dt;
    act.decel2 = 2.0f * p->decel_mps2;
    act.v_prof = act.vmin;
    pid_reset(&speed_pid);
    pid_reset(&balance_pid);
    robot_state.locomotion.current_id = m->id;
    DEBUG_PRINT(LOCOMOTION, 3, "start %u", m->id);
}

static void finish(bool completed, float s_done, float v_now)
{
    const movement_t *m = &queue[q_head];
    coast.watching = completed && q_count == 1 && v_now > 0.005f;
    coast.sl0 = act.sl0;
    coast.sr0 = act.sr0;
    coast.pl = act.pl;
    coast.pr = act.pr;
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

/* One step of the two chained controllers, in as few float operations as the AVR can afford. */
static void movement_step(void)
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
    float sl = speed_distance_m(0) - act.sl0;
    float sr = speed_distance_m(1) - act.sr0;
    /* Progress: the projection of what the wheels did on what they must do. */
    float done = sl * act.pl + sr * act.pr;
    float remaining = act.master - done;
    /* Speed of the faster wheel, measured along the movement. */
    float v_meas = speed_mps(0) * act.pl + speed_mps(1) * act.pr;
    if (act.master < 1.0e-5f || remaining <= (v_meas > 0.0f ? v_meas * coast_s : 0.0f)) {
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
    /* Brake so as to reach vmin at the end: v^2 = vmin^2 + 2 a d (the square root only while braking). */
    float v_set = act.v_prof;
    float brake_sq = act.vmin_sq + act.decel2 * remaining;
    if (v_set * v_set > brake_sq)
        v_set = __builtin_sqrtf(brake_sq);

    float lim = pwm_limit();
    float base = pid_update(&speed_pid, &settings.speed_pid, v_set - v_meas, lim);
    /* Balance: zero when each wheel has done the same share of its distance. */
    float c = pid_update(&balance_pid, &settings.wheel_balance, sl * act.br - sr * act.bl, lim);
    motors_set(duty_towards(base * act.bl - c * act.br, m->dl), duty_towards(base * act.br + c * act.bl, m->dr));
}

/* Once the robot rests after a movement, how far it rolled after the cut tells the coasting time. */
static void coast_watch(void)
{
    if (mode() != PB_LOCO_MODE_IDLE) {
        coast.watching = 0;
        return;
    }
    if (speed_mps(0) != 0.0f || speed_mps(1) != 0.0f)
        return;
    coast.watching = 0;
    float done = (speed_distance_m(0) - coast.sl0) * coast.pl + (speed_distance_m(1) - coast.sr0) * coast.pr;
    float t = pid_clamp((done - coast.s_cut) / coast.v_cut, COAST_MAX_S);
    if (t < 0.0f)
        t = 0.0f;
    coast_s = coast_seen ? coast_s + 0.3f * (t - coast_s) : t;
    coast_seen = 1;
    DEBUG_PRINT(LOCOMOTION, 3, "coasting %u ms", (unsigned)(coast_s * 1000.0f));
}

float locomotion_coast_s(void)
{
    return coast_s;
}

void locomotion_task(void)
{
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
