/*
 * A tiny stand-in for the firmware, used only by the emulator's own wiring tests: it implements the
 * ABI of firmware/hal/sim/sim_abi.h with trivial behaviour (echo on the link, count encoder edges,
 * beacon over IR, drive both motors at a fixed PWM, read the line sensor), so the Chicory wiring can
 * be tested without the real firmware. Build: emulator/src/test/c/build.sh (clang + wasm-ld).
 */
#include <stdint.h>

#define EXPORT(name) __attribute__((export_name(#name)))

/* sim_inputs_t and sim_ir_out_t of sim_abi.h: the sensors as the emulator writes them, the IR messages sent. */
typedef struct __attribute__((packed)) {
    uint64_t noise_state;
    int32_t noise, reserved;
    double line_ambient_adc, line_white_adc, line_span_adc, line_noise_adc;
    double line_dark[8];
    double sensor[10];
} inputs_t;

typedef struct __attribute__((packed)) {
    int32_t count, dropped;
    struct __attribute__((packed)) { int32_t sender_id, led, power, len, lo, hi; } msg[32];
} ir_out_t;

static inputs_t inputs;
static ir_out_t ir_out;

EXPORT(sim_inputs) int32_t sim_inputs(void) { return (int32_t)(uintptr_t)&inputs; }
EXPORT(sim_ir_out) int32_t sim_ir_out(void) { return (int32_t)(uintptr_t)&ir_out; }

/* Detector d with both its emitters lit, without noise. */
static int32_t detector(int d) {
    double v = inputs.line_ambient_adc;
    for (int k = 0; k < 2; k++)
        v += inputs.line_white_adc + inputs.line_span_adc * inputs.line_dark[2 * d + k];
    return (int32_t)v;
}

static void ir_send(int32_t id, int32_t led, int32_t power, int32_t len, int32_t lo, int32_t hi) {
    if (ir_out.count >= 32) { ir_out.dropped++; return; }
    ir_out.msg[ir_out.count].sender_id = id;
    ir_out.msg[ir_out.count].led = led;
    ir_out.msg[ir_out.count].power = power;
    ir_out.msg[ir_out.count].len = len;
    ir_out.msg[ir_out.count].lo = lo;
    ir_out.msg[ir_out.count].hi = hi;
    ir_out.count++;
}

typedef struct __attribute__((packed)) {
    int16_t pwm_left, pwm_right;
    uint8_t led, line_emitters;
} outputs_t;

/* The stand-in's "robot_state": what the wiring tests read back. */
typedef struct __attribute__((packed)) {
    int64_t now;
    int64_t last_edge[2];
    int32_t edges[2];
    int32_t ir_heard;
    int32_t ir_last_sender, ir_last_side, ir_last_led, ir_last_power;
    int32_t adc[4];
    int32_t battery_mv;
    int32_t id;
    int32_t rx_count;
} state_t;

static outputs_t outputs;
static state_t state;
static uint8_t tx[256];
static uint8_t txq[256];
static uint32_t txq_head, txq_tail;
static int64_t next_tick;
static int64_t next_beacon;
static uint8_t settings[4] = {1, 2, 3, 4};

EXPORT(sim_init) void sim_init(int32_t robot_id) {
    state.id = robot_id;
    outputs.pwm_left = 500;
    outputs.pwm_right = 500;
    next_tick = 32000;
    next_beacon = 32000 * 40;
}

EXPORT(sim_advance) void sim_advance(int64_t now) {
    while (next_tick <= now) {
        for (int d = 0; d < 4; d++)
            state.adc[d] = detector(d);
        state.battery_mv = (int32_t)inputs.sensor[0];
        if (next_tick >= next_beacon) {
            ir_send(state.id, 0, 100, 2, 0x1234, 0);
            next_beacon += 32000 * 40;
        }
        next_tick += 32000;
    }
    state.now = now;
}

EXPORT(sim_encoder_edge) void sim_encoder_edge(int32_t wheel, int64_t ticks) {
    state.edges[wheel & 1]++;
    state.last_edge[wheel & 1] = ticks;
}

EXPORT(sim_uart_rx) void sim_uart_rx(int32_t byte) {
    state.rx_count++;
    txq[txq_head++ & 255] = (uint8_t)byte;
}

typedef struct __attribute__((packed)) {
    int64_t ticks;
    int32_t kind, arg;
} event_t;

static event_t events[64];

EXPORT(sim_events) int32_t sim_events(void) { return (int32_t)(uintptr_t)events; }

EXPORT(sim_run_events) void sim_run_events(int32_t count, int64_t end) {
    for (int32_t i = 0; i < count && i < 64; i++) {
        sim_advance(events[i].ticks);
        if (events[i].kind == 0) sim_uart_rx(events[i].arg);
        else if (events[i].kind == 1) sim_encoder_edge(events[i].arg, events[i].ticks);
        /* a stand-in with one link: its hosts coming and going (kinds 3, 4) change nothing */
    }
    if (end >= 0) sim_advance(end);
}

EXPORT(sim_uart_tx_take) int32_t sim_uart_tx_take(int32_t max) {
    int32_t n = 0;
    while (n < max && txq_tail != txq_head) tx[n++] = txq[txq_tail++ & 255];
    return n;
}

EXPORT(sim_uart_tx_buffer) int32_t sim_uart_tx_buffer(void) { return (int32_t)(uintptr_t)tx; }

EXPORT(sim_ir_rx) void sim_ir_rx(int32_t side, int32_t sender, int32_t led, int32_t power, int32_t len,
                                 int32_t lo, int32_t hi) {
    (void)len; (void)lo; (void)hi;
    state.ir_heard++;
    state.ir_last_sender = sender;
    state.ir_last_side = side;
    state.ir_last_led = led;
    state.ir_last_power = power;
}

EXPORT(sim_outputs) int32_t sim_outputs(void) { return (int32_t)(uintptr_t)&outputs; }
EXPORT(sim_state) int32_t sim_state(void) { return (int32_t)(uintptr_t)&state; }
EXPORT(sim_settings) int32_t sim_settings(void) { return (int32_t)(uintptr_t)settings; }
