#include "world.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "protocol/pb_frame.h"
#include "protocol/slip.h"

world_t world;
host_frame_t host_frames[WORLD_MAX_FRAMES];
int host_frame_count;
int host_bad_frames;
static slip_decoder_t host_rx;
static void take(int32_t max);
static void sense(void);
static void advance(int64_t t);

#define TICKS_PER_S 32000000.0
#define WHEEL_D 0.009
#define PPR 40
#define BASE 0.026
#define SENSOR_AHEAD 0.020   /* line sensor ahead of the wheel axis */
#define SPOT_PITCH 0.003

static double pulse_len(void)
{
    return M_PI * WHEEL_D / PPR;
}

/* Stripe edges alternate long and short stripes. */
static double stripe(int index)
{
    double mean = pulse_len();
    return (index & 1) ? mean * (2.0 - world.stripe_ratio) : mean * world.stripe_ratio;
}

void world_power_on(int32_t robot_id)
{
    memset(&world, 0, sizeof world);
    world.max_speed = 0.5;
    world.gain[0] = world.gain[1] = 1.0;
    world.tau = 0.02;
    world.deadband = 30;
    world.stripe_ratio = 1.15;
    world.line_width = 0.015;
    world.ambient = 300;
    world.link_bytes_per_ms = 12; /* 115200 baud */
    world.colour[0] = world.colour[1] = world.colour[2] = world.colour[3] = 230;
    world.sensors[0] = 3900;
    world.sensors[1] = 120;
    world.sensors[2] = 285;
    world.sensors[5] = 1000;
    for (int w = 0; w < 2; w++) {
        world.next_edge[w] = stripe(0);
        world.prev_edge[w] = 0.0;
        world.edge_index[w] = 0;
    }
    host_clear();
    slip_decoder_init(&host_rx);
    for (int k = 0; k < (int)COMM_LINKS; k++) {
        link_clear(k);
        slip_decoder_init(&link_hosts[k].rx);
    }
    sim_host_eeprom_erase();
    sense();
    sim_init(robot_id);
}

void world_reset(int32_t robot_id)
{
    world_power_on(robot_id);
    host_handshake(WORLD_SESSION, PB_HOST_ROLE_DRIVE, WORLD_LABEL);
    world.now = (int64_t)(TICKS_PER_S / 1000); /* the robot stands still: one step of the clock does */
    sim_advance(world.now);
    while (sim_uart_tx_take(256) > 0) { /* what it said so far, unread */
    }
}

double world_heading_deg(void)
{
    return world.theta * 180.0 / M_PI;
}

static const sim_outputs_t *outputs(void)
{
    return sim_host_outputs();
}

static void step(double dt)
{
    const sim_outputs_t *o = outputs();
    int duty[2] = {o->pwm_left, o->pwm_right};
    int64_t t0 = world.now;
    for (int w = 0; w < 2; w++) {
        double goal = abs(duty[w]) < world.deadband ? 0.0 : world.max_speed * world.gain[w] * duty[w] / 1000.0;
        world.v[w] += (goal - world.v[w]) * (dt / world.tau);
        double old = world.pos[w];
        world.pos[w] += world.v[w] * dt;
        /* Edges crossed during this step, each at its interpolated time. */
        while (world.pos[w] >= world.next_edge[w]) {
            double frac = (world.next_edge[w] - old) / (world.pos[w] - old);
            int64_t t = t0 + (int64_t)(frac * dt * TICKS_PER_S);
            advance(t);
            sim_encoder_edge(w, t);
            world.prev_edge[w] = world.next_edge[w];
            world.edge_index[w]++;
            world.next_edge[w] += stripe(world.edge_index[w]);
        }
        while (world.pos[w] < world.prev_edge[w]) {
            double frac = (old - world.prev_edge[w]) / (old - world.pos[w]);
            int64_t t = t0 + (int64_t)(frac * dt * TICKS_PER_S);
            advance(t);
            sim_encoder_edge(w, t);
            world.next_edge[w] = world.prev_edge[w];
            world.edge_index[w]--;
            world.prev_edge[w] -= stripe(world.edge_index[w]);
        }
    }
    double v = (world.v[0] + world.v[1]) / 2.0;
    double om = (world.v[1] - world.v[0]) / BASE;
    world.x += v * cos(world.theta) * dt;
    world.y += v * sin(world.theta) * dt;
    world.theta += om * dt;
    world.now = t0 + (int64_t)(dt * TICKS_PER_S);
    advance(world.now);
}

static void take_link(int link, int32_t max);

void world_run_ms(int ms)
{
    for (int i = 0; i < ms; i++) {
        for (int k = 0; k < 10; k++)
            step(0.0001);
        if (!(world.stuck_links & 1))
            take(world.link_bytes_per_ms);
        for (int link = 1; link < (int)COMM_LINKS; link++)
            if (!(world.stuck_links & (1 << link)))
                take_link(link, world.link_bytes_per_ms);
    }
}

/* ---- sensors and IR as data (sim_abi.h) ---- */

static int spot_on_line(int spot)
{
    if (!world.line_enabled)
        return 0;
    double lateral = (3.5 - spot) * SPOT_PITCH; /* spot 0 is leftmost: +y in the robot frame */
    double sy = world.y + SENSOR_AHEAD * sin(world.theta) + lateral * cos(world.theta);
    return fabs(sy - world.line_y) <= world.line_width / 2.0;
}

/* What the sensors face now: a lit emitter adds 100 over the floor and 2000 over the line, no noise. */
static void sense(void)
{
    sim_inputs_t *in = sim_host_inputs();
    in->noise = 0;
    in->line_ambient_adc = world.ambient;
    in->line_white_adc = 100;
    in->line_span_adc = 1900;
    in->line_noise_adc = 0;
    for (int j = 0; j < 8; j++)
        in->line_dark[j] = spot_on_line(j);
    for (int s = 0; s < SIM_SENSOR_COLOUR_R; s++)
        in->sensor[s] = world.sensors[s];
    for (int c = 0; c < 4; c++)
        in->sensor[SIM_SENSOR_COLOUR_R + c] = world.colour[c];
}

/* The IR messages the firmware sent, and which emitters it lights. */
static void observe(void)
{
    sim_ir_out_t *out = sim_host_ir_out();
    for (int i = 0; i < out->count && world.ir_count < WORLD_MAX_IR; i++) {
        const sim_ir_msg_t *m = &out->msg[i];
        world.ir[world.ir_count].sender = m->sender_id;
        world.ir[world.ir_count].led = m->led;
        world.ir[world.ir_count].power = m->power;
        world.ir[world.ir_count].len = m->len;
        world.ir[world.ir_count].lo = (uint32_t)m->payload_lo;
        world.ir[world.ir_count].hi = (uint32_t)m->payload_hi;
        world.ir_count++;
    }
    out->count = 0;
    world.emitter_masks_seen |= 1 << sim_host_outputs()->line_emitters;
}

static void advance(int64_t t)
{
    sense();
    sim_advance(t);
    observe();
}

/* ---- host link ---- */

void host_send_raw(const uint8_t *bytes, uint16_t n)
{
    for (uint16_t i = 0; i < n; i++)
        sim_uart_rx(bytes[i]);
}

void host_send(uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    uint8_t frame[PB_MAX_FRAME + 8];
    uint8_t slip[2 * sizeof frame + 2];
    uint16_t n = pb_frame_encode(frame, type, seq, payload, len);
    uint16_t m = slip_encode(slip, frame, n);
    host_send_raw(slip, m);
}

/* Decodes what `link` sent (at most `max` bytes) into `frames`. */
static void take_into(int link, int32_t max, slip_decoder_t *rx, host_frame_t *frames, int capacity, int *count,
                      int *bad)
{
    while (max > 0) {
        int32_t n = sim_link_tx_take(link, max);
        if (n <= 0)
            break;
        const uint8_t *b = sim_host_tx_buffer();
        for (int32_t i = 0; i < n; i++) {
            slip_result_t r = slip_decode(rx, b[i]);
            if (r == SLIP_ERROR)
                (*bad)++;
            if (r != SLIP_FRAME)
                continue;
            pb_frame_t f;
            if (pb_frame_check(rx->buf, rx->len, &f) != PB_ERROR_CODE_NONE) {
                (*bad)++;
                continue;
            }
            if (*count < capacity) {
                host_frame_t *h = &frames[(*count)++];
                h->type = f.type;
                h->seq = f.seq;
                h->len = f.len;
                memcpy(h->payload, f.payload, f.len);
            }
        }
        max -= n;
    }
}

static void take(int32_t max)
{
    take_into(0, max, &host_rx, host_frames, WORLD_MAX_FRAMES, &host_frame_count, &host_bad_frames);
}

static void take_link(int link, int32_t max)
{
    link_host_t *h = &link_hosts[link];
    take_into(link, max, &h->rx, h->frames, WORLD_LINK_FRAMES, &h->count, &h->bad);
}

void host_collect(void)
{
    take(1 << 20);
}

void host_clear(void)
{
    host_frame_count = 0;
    host_bad_frames = 0;
}

const host_frame_t *host_find(uint8_t type, int n)
{
    for (int i = 0; i < host_frame_count; i++)
        if (host_frames[i].type == type && n-- == 0)
            return &host_frames[i];
    return NULL;
}

int host_count(uint8_t type)
{
    int c = 0;
    for (int i = 0; i < host_frame_count; i++)
        c += host_frames[i].type == type;
    return c;
}

static void role_request(uint8_t role, const char *label, pb_set_role_t *r)
{
    memset(r, 0, sizeof *r);
    r->role = role;
    strncpy(r->label, label, sizeof r->label);
}

/* Sequence numbers of the handshakes: each set_role a new command, never taken for a retransmission. */
static uint8_t handshake_seq = 200;

static uint8_t next_seq(void)
{
    handshake_seq = (uint8_t)(handshake_seq == 255 ? 200 : handshake_seq + 1);
    return handshake_seq;
}

void host_handshake(uint32_t session, uint8_t role, const char *label)
{
    pb_hello_request_t h = {PB_PROTOCOL_VERSION, session};
    pb_set_role_t r;
    role_request(role, label, &r);
    host_send(PB_PKT_HELLO_REQUEST, next_seq(), &h, sizeof h);
    host_send(PB_PKT_SET_ROLE, next_seq(), &r, sizeof r);
}

/* ---- more hosts ---- */

link_host_t link_hosts[COMM_LINKS];

static void link_event(int kind, int32_t arg)
{
    sim_event_t *e = sim_host_events();
    e->ticks = world.now;
    e->kind = kind;
    e->arg = arg;
    sim_run_events(1, -1);
}

void link_open(int link)
{
    link_event(SIM_EVENT_LINK_OPEN, link);
}

void link_close(int link)
{
    link_event(SIM_EVENT_LINK_CLOSE, link);
}

void link_send_raw(int link, const uint8_t *bytes, uint16_t n)
{
    sim_event_t *e = sim_host_events();
    while (n > 0) {
        int32_t count = 0;
        for (; count < SIM_EVENT_CAPACITY && n > 0; count++, n--) {
            e[count].ticks = world.now;
            e[count].kind = SIM_EVENT_LINK_RX;
            e[count].arg = link << 8 | *bytes++;
        }
        sim_run_events(count, -1);
    }
}

void link_send(int link, uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    uint8_t frame[PB_MAX_FRAME + 8];
    uint8_t slip[2 * sizeof frame + 2];
    uint16_t n = pb_frame_encode(frame, type, seq, payload, len);
    link_send_raw(link, slip, slip_encode(slip, frame, n));
}

void link_handshake(int link, uint32_t session, uint8_t role, const char *label)
{
    pb_hello_request_t h = {PB_PROTOCOL_VERSION, session};
    pb_set_role_t r;
    role_request(role, label, &r);
    link_send(link, PB_PKT_HELLO_REQUEST, next_seq(), &h, sizeof h);
    link_send(link, PB_PKT_SET_ROLE, next_seq(), &r, sizeof r);
}

void link_collect(int link)
{
    take_link(link, 1 << 20);
}

void link_clear(int link)
{
    link_hosts[link].count = 0;
    link_hosts[link].bad = 0;
}

const host_frame_t *link_find(int link, uint8_t type, int n)
{
    for (int i = 0; i < link_hosts[link].count; i++)
        if (link_hosts[link].frames[i].type == type && n-- == 0)
            return &link_hosts[link].frames[i];
    return NULL;
}

int link_count(int link, uint8_t type)
{
    int c = 0;
    for (int i = 0; i < link_hosts[link].count; i++)
        c += link_hosts[link].frames[i].type == type;
    return c;
}
