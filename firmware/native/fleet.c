/**
 * \file fleet.c
 * The emulator's benchmark fleet, natively: the same firmware (build/wasm/pocketbot.wasm, turned into C by wasm2c
 * and compiled by gcc -O2, one instance and one linear memory per robot) driven the way the emulator drives it, so
 * that `make bench-emulator` can say how far the emulator is from native code (its `native_ratio`).
 *
 * Per robot and simulated millisecond, as emulator/.../SimRobot.moveAndRun: the motors' first-order lag and the
 * battery, the pose, the encoder edges of both wheels at their interpolated times, the host's bytes at the link's
 * baud rate, all handed over in one sim_run_events call that ends with sim_advance to the step's end, the outputs
 * read from memory, the UART drained at the baud rate (every 8th step: no host attached). Before the step it writes
 * what the sensors face into the firmware's sim_inputs_t, as the emulator does: eight line sensor spots blended over
 * the tape, the slow sensors, the noise generator's state; after it, it takes the IR messages from sim_ir_out_t. At
 * the step's end the IR messages reach the robots of the same track in range and cone (the bench's tracks are 0.8 m
 * apart, beyond IR range). Single-threaded: what it measures is CPU time per robot-millisecond.
 *
 * Usage: fleet ROBOTS WARM_S MEASURE_S TILE_M CX CY RADIUS_M TAPE_W_M AMBIENT X0 Y0 H0 X1 Y1 H1 X2 Y2 H2 FRAME_HEX
 * (the round track of thesis A.3 at (CX, CY) in a TILE_M square, repeated side by side, three robots per track at
 * the given start poses in degrees, each sent the SLIP frame FRAME_HEX at the start). Prints on stdout:
 *   native robots=N cpu_us_per_robot_ms=X on_line=K/N
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "hal/sim/sim_abi.h"
#include "pocketbot.h"

/* ---- the robot and its world: emulator/.../physics/RobotParams.kt and SimRobot.kt ---------------------------- */

#define TICKS_PER_S 32000000LL
#define STEP_TICKS 32000LL
#define STEP_S 0.001
#define WHEEL_BASE 0.026
#define STRIPE_PAIR (M_PI * 0.009 * 2 / 40)
#define BLACK_SHARE 0.42
#define NO_LOAD_MPS 0.6
#define NOMINAL_V 3.7
#define MOTOR_TAU 0.030
#define LINE_AHEAD 0.020
#define SPOT_PITCH 0.0025
#define SPOT_RADIUS 0.0012
#define LINE_WHITE 110.0
#define LINE_BLACK 1900.0
#define LINE_NOISE 6.0
#define COLOUR_AHEAD 0.012
#define COLOUR_RADIUS 0.0025
#define LENGTH 0.048
#define WIDTH 0.032
#define IR_RANGE 0.150
#define IR_LED_HALF_DEG 15.0
#define IR_RX_HALF_DEG 90.0
#define BATTERY_FULL 4.1
#define BATTERY_EMPTY 3.4
#define CAPACITY_MAH 150.0
#define INTERNAL_OHM 0.4
#define IDLE_MA 35.0
#define STALL_MA 250.0
#define G 9.80665
#define BAUD 115200
#define LATENCY_TICKS (2 * TICKS_PER_S / 1000)
#define MAX_TAKE 256
#define IDLE_TX_STEPS 8
#define IR_CAP 32
#define EDGE_CAP 16

/* sim_abi.h */
#define EVENT_BYTES 16
#define EVENT_CAPACITY 64
#define EVENT_UART_RX 0
#define EVENT_ENCODER_EDGE 1

typedef struct {
    int32_t led, power, len, lo, hi, sender;
} ir_msg_t;

typedef struct {
    Z_pocketbot_instance_t fw;
    int index, track;
    double cx, cy; /* its track's centre */
    double x, y, theta, vl, vr, dist_l, dist_r, duty_l, duty_r;
    double phase_l, phase_r;
    double charge_used_mah, current_ma, prev_v, accel_x, accel_y;
    double spot_dark[8];
    uint64_t rng;
    int tx_steps;
    double tx_credit;
    const uint8_t *host_bytes; /* bytes on their way to the robot, the k-th arriving at host_t0 + (k + 1) byte times */
    int host_count, host_next;
    int64_t host_t0;
    int64_t edge_t[EDGE_CAP];
    int edge_w[EDGE_CAP];
    ir_msg_t ir_out[IR_CAP];
    int ir_out_count;
    int32_t ir_in[IR_CAP][7];
    int ir_in_count;
    uint32_t outputs, events, inputs, sent; /* addresses of sim_outputs_t, the event buffer, sim_inputs_t, sim_ir_out_t */
} robot_t;

static double tape_r, tape_hw, ambient;
static double alpha_lag; /* 1 - exp(-STEP_S / MOTOR_TAU) */

static uint64_t next_random(robot_t *r) /* splitmix64 */
{
    uint64_t z = (r->rng += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double uniform(robot_t *r)
{
    return (double)(next_random(r) >> 11) * (1.0 / 9007199254740992.0);
}

static double battery_loaded_v(const robot_t *r)
{
    double soc = 1 - r->charge_used_mah / CAPACITY_MAH;
    soc = soc < 0 ? 0 : soc > 1 ? 1 : soc;
    return BATTERY_EMPTY + (BATTERY_FULL - BATTERY_EMPTY) * soc - r->current_ma / 1000 * INTERNAL_OHM;
}

/* How much of a round spot of radius `sr` at (x, y) the robot's track covers (a whole circle, as Surface). */
static double coverage(const robot_t *r, double x, double y, double sr)
{
    double dx = x - r->cx, dy = y - r->cy;
    double d = fabs(sqrt(dx * dx + dy * dy) - tape_r);
    if (d >= tape_hw + sr)
        return 0.0;
    double lo = fmax(d - sr, -tape_hw), hi = fmin(d + sr, tape_hw);
    double c = (hi - lo) / (2 * sr);
    return c < 0 ? 0 : c > 1 ? 1 : c;
}

static void compute_spots(robot_t *r)
{
    double c = cos(r->theta), s = sin(r->theta);
    for (int j = 0; j < 8; j++) {
        double lat = (3.5 - j) * SPOT_PITCH; /* spot 0 is the leftmost */
        r->spot_dark[j] = coverage(r, r->x + LINE_AHEAD * c - lat * s, r->y + LINE_AHEAD * s + lat * c, SPOT_RADIUS);
    }
}

static int32_t clamp_i(int32_t v, int32_t lo, int32_t hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* ---- what the sensors face, into the firmware's sim_inputs_t; the IR it sent, out of sim_ir_out_t ------------------ */

static sim_inputs_t *inputs_of(robot_t *r)
{
    return (sim_inputs_t *)(r->fw.w2c_memory.data + r->inputs);
}

static void sense(robot_t *r)
{
    sim_inputs_t *in = inputs_of(r);
    compute_spots(r);
    double c = coverage(r, r->x + COLOUR_AHEAD * cos(r->theta), r->y + COLOUR_AHEAD * sin(r->theta), COLOUR_RADIUS);
    double rg = 235 + (18 - 235) * c, b = 235 + (20 - 235) * c; /* white floor, black tape */
    in->noise_state = r->rng;
    in->noise = 1;
    memcpy(in->line_dark, r->spot_dark, sizeof in->line_dark);
    in->sensor[SIM_SENSOR_BATTERY_MV] = battery_loaded_v(r) * 1000;
    in->sensor[SIM_SENSOR_CURRENT_MA] = r->current_ma;
    in->sensor[SIM_SENSOR_MCU_TEMP_DC] = 250 + r->current_ma / 20;
    in->sensor[SIM_SENSOR_ACCEL_X_MG] = r->accel_x;
    in->sensor[SIM_SENSOR_ACCEL_Y_MG] = r->accel_y;
    in->sensor[SIM_SENSOR_ACCEL_Z_MG] = 1000;
    in->sensor[SIM_SENSOR_COLOUR_R] = rg;
    in->sensor[SIM_SENSOR_COLOUR_G] = rg;
    in->sensor[SIM_SENSOR_COLOUR_B] = b;
    in->sensor[SIM_SENSOR_COLOUR_CLEAR] = (rg + rg + b) / 3;
}

static void take_ir(robot_t *r)
{
    sim_ir_out_t *out = (sim_ir_out_t *)(r->fw.w2c_memory.data + r->sent);
    for (int i = 0; i < out->count && r->ir_out_count < IR_CAP; i++) {
        const sim_ir_msg_t *m = &out->msg[i];
        ir_msg_t *o = &r->ir_out[r->ir_out_count++];
        o->sender = m->sender_id;
        o->led = m->led;
        o->power = clamp_i(m->power, 0, 100);
        o->len = clamp_i(m->len, 0, 8);
        o->lo = m->payload_lo;
        o->hi = m->payload_hi;
    }
    out->count = 0;
}

/* ---- one robot's millisecond ---------------------------------------------------------------------------------- */

static int64_t edge_index(double u)
{
    double k = floor(u / STRIPE_PAIR);
    return (int64_t)k * 2 + (u - k * STRIPE_PAIR >= BLACK_SHARE * STRIPE_PAIR ? 1 : 0);
}

static double edge_pos(int64_t n)
{
    int64_t pair = n >= 0 ? n / 2 : -((-n + 1) / 2);
    return (double)pair * STRIPE_PAIR + ((n - 2 * pair) == 1 ? BLACK_SHARE * STRIPE_PAIR : 0.0);
}

static int64_t edge_ticks(double part, double span)
{
    double f = part / span;
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    int64_t t = llround(f * STEP_TICKS);
    return t < 1 ? 1 : t;
}

static int collect_edges(robot_t *r, int wheel, double u0, double u1, int64_t t0, int n)
{
    if (u0 == u1)
        return n;
    int64_t e0 = edge_index(u0), e1 = edge_index(u1);
    double span = u1 - u0;
    for (int64_t k = e0 + 1; k <= e1 && n < EDGE_CAP; k++, n++) {
        r->edge_t[n] = t0 + edge_ticks(edge_pos(k) - u0, span);
        r->edge_w[n] = wheel;
    }
    for (int64_t k = e0; k > e1 && n < EDGE_CAP; k--, n++) {
        r->edge_t[n] = t0 + edge_ticks(edge_pos(k) - u0, span);
        r->edge_w[n] = wheel;
    }
    return n;
}

static void put_event(robot_t *r, int index, int64_t ticks, int32_t kind, int32_t arg)
{
    uint8_t *at = r->fw.w2c_memory.data + r->events + (uint32_t)index * EVENT_BYTES;
    memcpy(at, &ticks, 8);
    memcpy(at + 8, &kind, 4);
    memcpy(at + 12, &arg, 4);
}

static void step(robot_t *r, int64_t t0)
{
    int64_t t1 = t0 + STEP_TICKS;
    /* Motors. */
    double v_scale = battery_loaded_v(r) / NOMINAL_V;
    r->vl += (NO_LOAD_MPS * r->duty_l * v_scale - r->vl) * alpha_lag;
    r->vr += (NO_LOAD_MPS * r->duty_r * v_scale - r->vr) * alpha_lag;
    /* Pose. */
    double dl = r->vl * STEP_S, dr = r->vr * STEP_S;
    double ds = (dl + dr) / 2, dth = (dr - dl) / WHEEL_BASE, mid = r->theta + dth / 2;
    r->x += ds * cos(mid);
    r->y += ds * sin(mid);
    r->theta += dth;
    if (r->theta > M_PI)
        r->theta -= 2 * M_PI;
    else if (r->theta < -M_PI)
        r->theta += 2 * M_PI;
    double v = ds / STEP_S;
    r->accel_x = (v - r->prev_v) / STEP_S / G * 1000;
    r->accel_y = v * (dth / STEP_S) / G * 1000;
    r->prev_v = v;
    /* Encoder edges in time order. */
    int n = collect_edges(r, 0, r->dist_l + r->phase_l, r->dist_l + dl + r->phase_l, t0, 0);
    n = collect_edges(r, 1, r->dist_r + r->phase_r, r->dist_r + dr + r->phase_r, t0, n);
    r->dist_l += dl;
    r->dist_r += dr;
    for (int i = 1; i < n; i++) {
        int64_t t = r->edge_t[i];
        int w = r->edge_w[i], j = i - 1;
        for (; j >= 0 && r->edge_t[j] > t; j--) {
            r->edge_t[j + 1] = r->edge_t[j];
            r->edge_w[j + 1] = r->edge_w[j];
        }
        r->edge_t[j + 1] = t;
        r->edge_w[j + 1] = w;
    }
    sense(r);
    /* IR heard at the end of the previous step. */
    for (int k = 0; k < r->ir_in_count; k++) {
        int32_t *m = r->ir_in[k];
        Z_pocketbotZ_sim_ir_rx(&r->fw, (u32)m[0], (u32)m[1], (u32)m[2], (u32)m[3], (u32)m[4], (u32)m[5], (u32)m[6]);
    }
    r->ir_in_count = 0;
    /* Host bytes and encoder edges, merged in time order, in one call. */
    const int64_t byte_ticks = TICKS_PER_S * 10 / BAUD;
    int e = 0, queued = 0;
    for (;;) {
        int64_t te = e < n ? r->edge_t[e] : INT64_MAX;
        int64_t tr = r->host_next < r->host_count ? r->host_t0 + (r->host_next + 1) * byte_ticks : INT64_MAX;
        if (tr < t1 && tr <= te) {
            put_event(r, queued++, tr, EVENT_UART_RX, r->host_bytes[r->host_next++]);
        } else if (te <= t1) {
            put_event(r, queued++, te, EVENT_ENCODER_EDGE, r->edge_w[e]);
            e++;
        } else {
            break;
        }
        if (queued == EVENT_CAPACITY) {
            Z_pocketbotZ_sim_run_events(&r->fw, (u32)queued, (u64)-1);
            queued = 0;
        }
    }
    Z_pocketbotZ_sim_run_events(&r->fw, (u32)queued, (u64)t1);
    r->rng = inputs_of(r)->noise_state;
    take_ir(r);
    /* Outputs. */
    const uint8_t *out = r->fw.w2c_memory.data + r->outputs;
    int16_t pwm_l, pwm_r;
    memcpy(&pwm_l, out, 2);
    memcpy(&pwm_r, out + 2, 2);
    r->duty_l = clamp_i(pwm_l, -1000, 1000) / 1000.0;
    r->duty_r = clamp_i(pwm_r, -1000, 1000) / 1000.0;
    /* The UART at the baud rate; no host attached: every few steps. */
    r->tx_steps++;
    r->tx_credit = fmin(r->tx_credit + BAUD / 10.0 * STEP_S, MAX_TAKE);
    int allowance = (int)r->tx_credit;
    if (allowance > 0 && r->tx_steps >= IDLE_TX_STEPS) {
        r->tx_steps = 0;
        r->tx_credit -= (int32_t)Z_pocketbotZ_sim_uart_tx_take(&r->fw, (u32)allowance);
    }
    /* Battery. */
    double il = fmin(fabs(r->duty_l - r->vl / NO_LOAD_MPS), 1.0) * STALL_MA;
    double ir = fmin(fabs(r->duty_r - r->vr / NO_LOAD_MPS), 1.0) * STALL_MA;
    r->current_ma = IDLE_MA + il + ir;
    r->charge_used_mah += r->current_ma * STEP_S / 3600;
}

/* ---- IR between the robots of one track, at the step's end (SimWorld.exchangeIr without occlusion) ------------- */

static void exchange_ir(robot_t *group, int count)
{
    double cos_led = cos(IR_LED_HALF_DEG * M_PI / 180), cos_rx = cos(IR_RX_HALF_DEG * M_PI / 180);
    for (int si = 0; si < count; si++) {
        robot_t *s = &group[si];
        for (int k = 0; k < s->ir_out_count; k++) {
            const ir_msg_t *m = &s->ir_out[k];
            if (m->power <= 0)
                continue;
            double range = IR_RANGE * m->power / 100.0;
            double lx = m->led == 0 ? LENGTH / 2 : m->led == 2 ? -LENGTH / 2 : 0;
            double ly = m->led == 1 ? -WIDTH / 2 : m->led == 3 ? WIDTH / 2 : 0;
            double la = m->led == 0 ? 0 : m->led == 1 ? -M_PI / 2 : m->led == 2 ? M_PI : M_PI / 2;
            double c = cos(s->theta), sn = sin(s->theta);
            double ex = s->x + lx * c - ly * sn, ey = s->y + lx * sn + ly * c;
            double dx = cos(s->theta + la), dy = sin(s->theta + la);
            for (int qi = 0; qi < count; qi++) {
                robot_t *q = &group[qi];
                if (q == s || q->ir_in_count == IR_CAP)
                    continue;
                double qc = cos(q->theta), qs = sin(q->theta);
                for (int side = 0; side < 2; side++) {
                    double off = side == 0 ? LENGTH / 2 : -LENGTH / 2;
                    double vx = q->x + off * qc - ex, vy = q->y + off * qs - ey;
                    double dist = sqrt(vx * vx + vy * vy);
                    if (dist > range || dist < 1e-9 || (vx * dx + vy * dy) / dist < cos_led)
                        continue;
                    double ax = side == 0 ? qc : -qc, ay = side == 0 ? qs : -qs;
                    if ((-vx * ax - vy * ay) / dist < cos_rx || q->ir_in_count == IR_CAP)
                        continue;
                    int32_t *in = q->ir_in[q->ir_in_count++];
                    in[0] = side; in[1] = m->sender; in[2] = m->led; in[3] = m->power;
                    in[4] = m->len; in[5] = m->lo; in[6] = m->hi;
                }
            }
        }
        s->ir_out_count = 0;
    }
}

/* ---- the fleet ------------------------------------------------------------------------------------------------ */

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

int main(int argc, char **argv)
{
    if (argc != 20) {
        fprintf(stderr, "usage: %s ROBOTS WARM_S MEASURE_S TILE_M CX CY RADIUS_M TAPE_W_M AMBIENT X0 Y0 H0 X1 Y1 H1 X2 Y2 H2 FRAME_HEX\n", argv[0]);
        return 2;
    }
    int robots = atoi(argv[1]), warm_s = atoi(argv[2]), measure_s = atoi(argv[3]);
    double tile = atof(argv[4]), cx = atof(argv[5]), cy = atof(argv[6]);
    tape_r = atof(argv[7]);
    tape_hw = atof(argv[8]) / 2;
    ambient = atof(argv[9]);
    double start[3][3];
    for (int k = 0; k < 9; k++)
        start[k / 3][k % 3] = atof(argv[10 + k]);
    size_t frame_len = strlen(argv[19]) / 2;
    uint8_t *frame = malloc(frame_len + 1);
    for (size_t i = 0; i < frame_len; i++)
        sscanf(argv[19] + 2 * i, "%2hhx", &frame[i]);
    if (robots < 1 || warm_s < 0 || measure_s < 1) {
        fprintf(stderr, "bad arguments\n");
        return 2;
    }

    alpha_lag = 1 - exp(-STEP_S / MOTOR_TAU);
    wasm_rt_init();
    Z_pocketbot_init_module();
    int tracks = (robots + 2) / 3;
    int cols = (int)ceil(sqrt((double)tracks));
    robot_t *fleet = calloc((size_t)robots, sizeof *fleet);
    for (int i = 0; i < robots; i++) {
        robot_t *r = &fleet[i];
        int k = i / 3;
        r->index = i;
        r->track = k;
        r->cx = cx + tile * (k % cols);
        r->cy = cy + tile * (k / cols);
        r->x = start[i % 3][0] + tile * (k % cols);
        r->y = start[i % 3][1] + tile * (k / cols);
        r->theta = start[i % 3][2] * M_PI / 180;
        r->current_ma = IDLE_MA;
        r->rng = 42u * 0x9E3779B97F4A7C15ull + (uint64_t)i * 0x2545F491u;
        r->phase_l = uniform(r) * STRIPE_PAIR;
        r->phase_r = uniform(r) * STRIPE_PAIR;
        r->host_bytes = frame;
        r->host_count = (int)frame_len;
        r->host_t0 = LATENCY_TICKS;
        Z_pocketbot_instantiate(&r->fw);
        r->outputs = Z_pocketbotZ_sim_outputs(&r->fw);
        r->events = Z_pocketbotZ_sim_events(&r->fw);
        r->inputs = Z_pocketbotZ_sim_inputs(&r->fw);
        r->sent = Z_pocketbotZ_sim_ir_out(&r->fw);
        sim_inputs_t *in = inputs_of(r);
        in->line_ambient_adc = ambient;
        in->line_white_adc = LINE_WHITE;
        in->line_span_adc = LINE_BLACK - LINE_WHITE;
        in->line_noise_adc = LINE_NOISE;
        sense(r);
        Z_pocketbotZ_sim_init(&r->fw, (u32)(i % 254 + 1));
        Z_pocketbotZ_sim_advance(&r->fw, 0);
    }

    int64_t now = 0;
    double cpu0 = 0;
    int total_ms = (warm_s + measure_s) * 1000;
    for (int ms = 0; ms < total_ms; ms++) {
        if (ms == warm_s * 1000)
            cpu0 = cpu_seconds();
        for (int i = 0; i < robots; i++)
            step(&fleet[i], now);
        for (int i = 0; i < robots; i += 3)
            exchange_ir(&fleet[i], robots - i < 3 ? robots - i : 3);
        now += STEP_TICKS;
    }
    double cpu = cpu_seconds() - cpu0;

    int on_line = 0;
    for (int i = 0; i < robots; i++) {
        robot_t *r = &fleet[i];
        if (fabs(hypot(r->x - r->cx, r->y - r->cy) - tape_r) < 0.01 && r->dist_l > 0.2)
            on_line++;
        Z_pocketbot_free(&r->fw);
    }
    printf("native robots=%d cpu_us_per_robot_ms=%.3f on_line=%d/%d\n", robots, cpu * 1e6 / ((double)robots * measure_s * 1000),
           on_line, robots);
    free(fleet);
    free(frame);
    return 0;
}
