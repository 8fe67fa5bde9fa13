/**
 * \file hal_sim.c
 * The HAL inside the emulator (WebAssembly): the emulator drives time with sim_advance() and delivers
 * interrupts through the exports of sim_abi.h; it writes what the sensors face into `inputs` before each step, and
 * takes the IR messages sent from `ir_out` after it (sim_abi.h): the firmware makes no call out of the instance.
 *
 * Time: MCU ticks at 32 MHz (int64). hal_micros() = ticks / 32, capture timestamps = ticks / 8 (4 MHz).
 * sim_advance() fires due compare interrupts in time order, each at its own time, and after each one runs
 * the main loop until it has nothing to do (as the MCU would between interrupts); code takes no time, unless
 * a host test stretches a tick (sim_host_stretch_tick_us()).
 *
 * The EEPROM is a plain array in linear memory (sim_eeprom()), erased (0xFF) in a fresh instance and kept by
 * sim_init: the emulator power-cycles a robot by copying it into a fresh instance before sim_init.
 *
 * Host links: link 0 is the UART; the emulator's further hosts get links 1 .. COMM_LINKS-1, serial links of their
 * own (a receive and a transmit ring each, as the UART has). The board wires them into comm as they open and
 * close, as the Bluetooth stack does with its channels.
 */
#include <stddef.h>
#include <string.h>

#include "app.h"
#include "core/data.h"
#include "hal/hal.h"
#include "hal/sim/sim_abi.h"
#include "modules/comm.h"

#define TICKS_PER_US 32
#define TICKS_PER_CAPTURE 8

static int64_t now_ticks;
static int64_t deadline[HAL_SCHED_CHANNELS];
static uint8_t armed[HAL_SCHED_CHANNELS];
static uint8_t board_id;
static sim_outputs_t outputs;
static uint16_t line_result[HAL_LINE_DETECTORS];
static uint8_t eeprom[HAL_EEPROM_SIZE] = {[0 ... HAL_EEPROM_SIZE - 1] = 0xFF};
static int64_t stretch_ticks; /* how much longer than its code the next main loop tick lasts */
static uint8_t tx_out[256];
static uint8_t irq_enabled;
_Static_assert((int)SIM_SENSOR_COUNT == (int)HAL_SENSOR_COUNT, "sim_abi.h and hal.h number the sensors alike");
static sim_inputs_t inputs;
static sim_ir_out_t ir_out;

/* ---- board ---- */

void hal_init(void)
{
    memset(armed, 0, sizeof armed);
    memset(&outputs, 0, sizeof outputs);
    memset(line_result, 0, sizeof line_result);
    irq_enabled = 0;
}

void hal_irq_enable(void)
{
    irq_enabled = 1;
}

uint8_t hal_board_id(void)
{
    return board_id;
}

void hal_idle(void)
{
}

/* Interrupts are delivered only between exports, never inside the main loop: masking is a no-op. */
uint8_t hal_irq_save(void)
{
    return 0;
}

void hal_irq_restore(uint8_t saved)
{
    (void)saved;
}

/* ---- time ---- */

uint32_t hal_micros(void)
{
    return (uint32_t)(uint64_t)(now_ticks / TICKS_PER_US);
}

void hal_sched_arm(uint8_t ch, uint32_t delay_us)
{
    if (ch >= HAL_SCHED_CHANNELS)
        return;
    int64_t base = (now_ticks / TICKS_PER_US) * TICKS_PER_US; /* whole microseconds, as hal_micros() counts them */
    deadline[ch] = delay_us > 0 ? base + (int64_t)delay_us * TICKS_PER_US : now_ticks;
    armed[ch] = 1;
}

void hal_sched_disarm(uint8_t ch)
{
    if (ch < HAL_SCHED_CHANNELS)
        armed[ch] = 0;
}

uint32_t hal_capture_now(void)
{
    return (uint32_t)(uint64_t)(now_ticks / TICKS_PER_CAPTURE);
}

/* ---- outputs ---- */

void hal_motors_set(int16_t left, int16_t right)
{
    outputs.pwm_left = left;
    outputs.pwm_right = right;
}

void hal_led_set(uint8_t mask)
{
    outputs.led = mask;
}

void hal_line_emitters(uint8_t mask)
{
    outputs.line_emitters = (uint8_t)(mask & 0x1Fu);
}

/* ---- sensors: the emulator's sensor model on the values in `inputs` (sim_abi.h) ---- */

/* Kotlin's Double.toInt(): towards zero, saturating, NaN to 0 (a plain cast would trap in WebAssembly). */
static int32_t trunc_sat(double v)
{
    if (v != v)
        return 0;
    if (v >= 2147483647.0)
        return INT32_MAX;
    if (v <= -2147483648.0)
        return INT32_MIN;
    return (int32_t)v;
}

static int32_t clamp_i32(int32_t v, int32_t lo, int32_t hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* A standard normal sample, roughly (Irwin-Hall of four 16-bit uniforms), from the robot's splitmix64 stream. */
static double gauss(void)
{
    uint64_t z = (inputs.noise_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    int64_t sum = (int64_t)((z & 0xFFFFu) + ((z >> 16) & 0xFFFFu) + ((z >> 32) & 0xFFFFu) + (z >> 48));
    return (double)(sum - 131070) * (1.0 / (65536.0 * 0.5773502691896257)); /* sqrt(4.0 / 12.0), to the last bit */
}

void hal_line_convert(void)
{
    uint8_t lit = outputs.line_emitters;
    for (uint8_t d = 0; d < HAL_LINE_DETECTORS; d++) {
        double v = inputs.line_ambient_adc;
        if (lit & (1u << d))
            v += inputs.line_white_adc + inputs.line_span_adc * inputs.line_dark[2 * d];
        if (lit & (1u << (d + 1)))
            v += inputs.line_white_adc + inputs.line_span_adc * inputs.line_dark[2 * d + 1];
        if (inputs.noise)
            v += gauss() * inputs.line_noise_adc;
        line_result[d] = (uint16_t)clamp_i32(trunc_sat(v), 0, 4095);
    }
}

void hal_line_results(uint16_t out[HAL_LINE_DETECTORS])
{
    memcpy(out, line_result, sizeof line_result);
}

int32_t hal_sensor_read(uint8_t sensor)
{
    if (sensor >= HAL_SENSOR_COUNT)
        return 0;
    static const uint8_t noise_sd[SIM_SENSOR_COUNT] = {3, 0, 0, 8, 8, 8, 2, 2, 2, 2};
    double v = inputs.sensor[sensor];
    if (inputs.noise && noise_sd[sensor])
        v += gauss() * noise_sd[sensor];
    int32_t r = trunc_sat(v);
    if (sensor == HAL_SENSOR_ACCEL_X_MG || sensor == HAL_SENSOR_ACCEL_Y_MG)
        return clamp_i32(r, -16000, 16000);
    if (sensor >= HAL_SENSOR_COLOUR_R)
        return clamp_i32(r, 0, 255);
    return r;
}

/* The emulator delivers a message the step after it is sent, without airtime (its IR link is a model of reach and
 * obstacles, not of timing): the firmware keeps the 2 ms spacing it has always had there. */
uint32_t hal_ir_message_us(uint8_t len)
{
    (void)len;
    return 1000u;
}

bool hal_ir_send(const hal_ir_msg_t *m)
{
    if (ir_out.count < 0 || ir_out.count >= SIM_IR_OUT_CAPACITY) {
        ir_out.dropped++;
        return true; /* sent into the air: nobody hears a message the emulator had no room for */
    }
    uint32_t lo = 0, hi = 0;
    uint8_t len = m->len > HAL_IR_PAYLOAD_MAX ? HAL_IR_PAYLOAD_MAX : m->len;
    for (uint8_t i = 0; i < len; i++) {
        if (i < 4)
            lo |= (uint32_t)m->data[i] << (8 * i);
        else
            hi |= (uint32_t)m->data[i] << (8 * (i - 4));
    }
    sim_ir_msg_t *o = &ir_out.msg[ir_out.count++];
    o->sender_id = m->sender_id;
    o->led = m->led;
    o->power = m->power > 100 ? 100 : m->power;
    o->len = len;
    o->payload_lo = (int32_t)lo;
    o->payload_hi = (int32_t)hi;
    return true;
}

void hal_uart_tx_kick(void)
{
    /* The emulator pulls bytes with sim_uart_tx_take() at the link's baud rate. */
}

/* ---- EEPROM: lives as long as the instance ---- */

void hal_eeprom_read(uint16_t addr, void *dst, uint16_t len)
{
    if ((uint32_t)addr + len > HAL_EEPROM_SIZE) {
        memset(dst, 0xFF, len);
        return;
    }
    memcpy(dst, eeprom + addr, len);
}

bool hal_eeprom_busy(void)
{
    return false;
}

void hal_eeprom_write_page(uint16_t addr, const void *src, uint8_t len)
{
    if ((uint32_t)addr + len <= HAL_EEPROM_SIZE)
        memcpy(eeprom + addr, src, len);
}

/* ---- exports ---- */

static void run_main_loop(void)
{
    /* Bounded: a tick is pending at most once per compare interrupt. */
    for (uint8_t i = 0; i < 8 && app_poll(); i++) {
    }
}

void sim_init(int32_t robot_id)
{
    now_ticks = 0;
    stretch_ticks = 0;
    board_id = (robot_id > 0 && robot_id < 255) ? (uint8_t)robot_id : 0;
    app_init(); /* the EEPROM keeps what it had, as on the robot */
}

/* Fires the earliest compare interrupt due by `target`, at its own time. \return false when none is due. */
static bool fire_next(int64_t target)
{
    int8_t next = -1;
    for (uint8_t ch = 0; ch < HAL_SCHED_CHANNELS; ch++)
        if (armed[ch] && deadline[ch] <= target && (next < 0 || deadline[ch] < deadline[next]))
            next = (int8_t)ch;
    if (next < 0)
        return false;
    if (deadline[next] > now_ticks)
        now_ticks = deadline[next];
    armed[next] = 0;
    if (irq_enabled)
        scheduler_isr((uint8_t)next);
    return true;
}

void sim_advance(int64_t target)
{
    while (fire_next(target))
        run_main_loop();
    if (target > now_ticks)
        now_ticks = target;
    run_main_loop();
}

/* A stretched tick: time passes inside it, and the interrupts due meanwhile fire while it still runs. */
void hal_tick_done(void)
{
    if (stretch_ticks == 0)
        return;
    int64_t end = now_ticks + stretch_ticks;
    stretch_ticks = 0;
    while (fire_next(end)) {
    }
    now_ticks = end;
}

int32_t sim_eeprom(void)
{
    return (int32_t)(uintptr_t)eeprom;
}

void sim_encoder_edge(int32_t wheel, int64_t ticks)
{
    if (wheel < 0 || wheel > 1 || !irq_enabled)
        return;
    encoder_capture_isr((uint8_t)wheel, (uint32_t)(uint64_t)(ticks / TICKS_PER_CAPTURE));
}

void sim_uart_rx(int32_t byte)
{
    if (irq_enabled)
        uart_rx_isr((uint8_t)byte);
}

/* ---- the emulator's host links beyond the UART ---- */

/* One-byte indices wrap by themselves: 255 bytes fit each way. */
static struct {
    uint8_t rx[256], tx[256];
    uint8_t rx_head, rx_tail, tx_head, tx_tail;
} sim_link[COMM_LINKS];

static uint16_t sim_link_room(uint8_t link)
{
    return (uint8_t)(sim_link[link].tx_tail - sim_link[link].tx_head - 1u);
}

static void sim_link_write(uint8_t link, const uint8_t *p, uint16_t n)
{
    uint8_t head = sim_link[link].tx_head;
    while (n--)
        sim_link[link].tx[head++] = *p++;
    sim_link[link].tx_head = head;
}

static uint8_t sim_link_take(uint8_t link, uint8_t *p, uint8_t max)
{
    uint8_t n = 0;
    while (n < max && sim_link[link].rx_tail != sim_link[link].rx_head)
        p[n++] = sim_link[link].rx[sim_link[link].rx_tail++];
    return n;
}

static const comm_link_driver_t sim_link_driver = {false, sim_link_room, sim_link_write, sim_link_take, NULL, NULL};

/* The receive interrupt of a link; a full ring loses the byte (the emulator delivers at the baud rate, and the
 * main loop empties the ring every tick, so it never fills). */
static void sim_link_rx(int32_t link, uint8_t byte)
{
    if (link == 0) {
        sim_uart_rx(byte);
    } else if (link > 0 && link < (int32_t)COMM_LINKS && irq_enabled) {
        uint8_t next = (uint8_t)(sim_link[link].rx_head + 1u);
        if (next != sim_link[link].rx_tail) {
            sim_link[link].rx[sim_link[link].rx_head] = byte;
            sim_link[link].rx_head = next;
        }
    }
}

static void sim_link_open(int32_t link, bool open)
{
#ifdef LINK_HCI
    (void)link; /* the UART is the Bluetooth module's, and comm's links are the stack's: nothing for the emulator */
    (void)open;
    return;
#endif
    if (link < 0 || link >= (int32_t)COMM_LINKS || !irq_enabled)
        return;
    sim_link[link].rx_head = sim_link[link].rx_tail = sim_link[link].tx_head = sim_link[link].tx_tail = 0;
    if (open)
        comm_link_open((uint8_t)link, link == 0 ? &comm_uart_link : &sim_link_driver);
    else
        comm_link_close((uint8_t)link, COMM_LINK_CLOSED);
}

int32_t sim_links(void)
{
    return COMM_LINKS;
}

static sim_event_t events[SIM_EVENT_CAPACITY];

int32_t sim_events(void)
{
    return (int32_t)(uintptr_t)events;
}

void sim_run_events(int32_t count, int64_t end_ticks)
{
    if (count > SIM_EVENT_CAPACITY)
        count = SIM_EVENT_CAPACITY;
    for (int32_t i = 0; i < count; i++) {
        const sim_event_t *e = &events[i];
        sim_advance(e->ticks);
        if (e->kind == SIM_EVENT_UART_RX)
            sim_uart_rx(e->arg);
        else if (e->kind == SIM_EVENT_ENCODER_EDGE)
            sim_encoder_edge(e->arg, e->ticks);
        else if (e->kind == SIM_EVENT_LINK_RX)
            sim_link_rx(e->arg >> 8, (uint8_t)e->arg);
        else if (e->kind == SIM_EVENT_LINK_OPEN || e->kind == SIM_EVENT_LINK_CLOSE)
            sim_link_open(e->arg, e->kind == SIM_EVENT_LINK_OPEN);
    }
    if (end_ticks >= 0)
        sim_advance(end_ticks);
}

int32_t sim_uart_tx_take(int32_t max)
{
    if (max > (int32_t)sizeof tx_out)
        max = (int32_t)sizeof tx_out;
    int32_t n = 0;
    while (n < max) {
        int16_t b = uart_tx_isr();
        if (b < 0)
            break;
        tx_out[n++] = (uint8_t)b;
    }
    return n;
}

int32_t sim_link_tx_take(int32_t link, int32_t max)
{
    if (link == 0)
        return sim_uart_tx_take(max);
    if (link < 0 || link >= (int32_t)COMM_LINKS)
        return 0;
    if (max > (int32_t)sizeof tx_out)
        max = (int32_t)sizeof tx_out;
    int32_t n = 0;
    while (n < max && sim_link[link].tx_tail != sim_link[link].tx_head)
        tx_out[n++] = sim_link[link].tx[sim_link[link].tx_tail++];
    return n;
}

int32_t sim_uart_tx_buffer(void)
{
    return (int32_t)(uintptr_t)tx_out;
}

void sim_ir_rx(int32_t side, int32_t sender_id, int32_t sender_led, int32_t power, int32_t len,
               int32_t payload_lo, int32_t payload_hi)
{
    if (side < 0 || side > 1 || !irq_enabled)
        return;
    hal_ir_msg_t m;
    m.sender_id = (uint8_t)sender_id;
    m.led = (uint8_t)(sender_led & 3);
    m.power = (uint8_t)(power < 0 ? 0 : power > 100 ? 100 : power);
    m.len = (uint8_t)(len < 0 ? 0 : len > (int32_t)HAL_IR_PAYLOAD_MAX ? (int32_t)HAL_IR_PAYLOAD_MAX : len);
    for (uint8_t i = 0; i < HAL_IR_PAYLOAD_MAX; i++)
        m.data[i] = (uint8_t)((i < 4 ? (uint32_t)payload_lo >> (8 * i) : (uint32_t)payload_hi >> (8 * (i - 4))) & 0xFFu);
    ir_rx_isr((uint8_t)side, &m);
}

int32_t sim_inputs(void)
{
    return (int32_t)(uintptr_t)&inputs;
}

int32_t sim_ir_out(void)
{
    return (int32_t)(uintptr_t)&ir_out;
}

int32_t sim_outputs(void)
{
    return (int32_t)(uintptr_t)&outputs;
}

int32_t sim_state(void)
{
    return (int32_t)(uintptr_t)&robot_state;
}

int32_t sim_settings(void)
{
    return (int32_t)(uintptr_t)&settings;
}

#if UINTPTR_MAX > 0xFFFFFFFFu
/* Host builds (tests, fuzzer) have 64-bit pointers that the int32 addresses above cannot carry. */
const sim_outputs_t *sim_host_outputs(void)
{
    return &outputs;
}

const uint8_t *sim_host_tx_buffer(void)
{
    return tx_out;
}

sim_inputs_t *sim_host_inputs(void)
{
    return &inputs;
}

sim_ir_out_t *sim_host_ir_out(void)
{
    return &ir_out;
}

sim_event_t *sim_host_events(void)
{
    return events;
}

void sim_host_eeprom_erase(void)
{
    memset(eeprom, 0xFF, sizeof eeprom);
}

void sim_host_stretch_tick_us(uint32_t us)
{
    stretch_ticks = (int64_t)us * TICKS_PER_US;
}
#endif
