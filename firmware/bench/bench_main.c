/**
 * \file bench_main.c
 * Cycle counts of the main loop tick and of each task, on the ATmega1284 build of the portable core under
 * simavr (clk/1 Timer1 read between the tasks), as a share of the 32,000-cycle budget of a 1 ms tick at 32 MHz.
 * A tick is the time from before the first task to after the last: the tasks and the few cycles per task of
 * the timer reads, nothing of the bookkeeping.
 * Scenarios: idle; a movement; line following; teleoperation with a host packet every tick and IR payloads;
 * the track behaviour (thesis A.3) following a robot close ahead while token hand-overs and greetings arrive,
 * then driving round an obstacle; and a stress scenario (full state EVERY tick, IR and host packets every tick,
 * debug text at level 4). Output goes out on UART0 (simavr prints it).
 * The HCI build (the robot's default, -DLINK_HCI) runs its Bluetooth stack as a task of its own: a host is connected
 * over RFCOMM before the first scenario (bench_bt.c plays the controller and the host), the state goes to it and its
 * packets come in UIH frames as fast as the wire carries them; one more scenario streams full state at the rate
 * the wire can carry (every 12 ms with 27-byte ACL buffers) while the robot moves.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <string.h>

#include "app.h"
#include "bench.h"
#ifdef LINK_HCI
#include "bluetooth/bt.h"
#include "bluetooth/hci.h"
#include "bluetooth/l2cap.h"
#include "bluetooth/rfcomm.h"
#endif
#include "core/data.h"
#include "core/scheduler.h"
#include "drivers/eeprom.h"
#include "drivers/encoder.h"
#include "drivers/line_sensor.h"
#include "drivers/sensors.h"
#include "drivers/uart.h"
#include "hal/hal.h"
#include "modules/comm.h"
#include "modules/failsafe.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"
#include "modules/proximity.h"
#include "modules/reflector.h"
#include "modules/settings.h"
#include "modules/speed.h"
#include "modules/track.h"

#define BUDGET 32000ul
#ifdef LINK_HCI
#define TASKS 14
#else
#define TASKS 11
#endif

static volatile uint16_t ovf;
ISR(TIMER1_OVF_vect) { ovf++; }

static uint32_t cycles(void)
{
    uint8_t s = SREG;
    cli();
    uint16_t lo = TCNT1, hi = ovf;
    if ((TIFR1 & (1 << TOV1)) && lo < 0x8000u)
        hi++;
    SREG = s;
    return ((uint32_t)hi << 16) | lo;
}

static void out_c(char c)
{
    while (!(UCSR0A & (1 << UDRE0))) {
    }
    UDR0 = (uint8_t)c;
}

static void out_s(const char *s)
{
    while (*s)
        out_c(*s++);
}

static void out_u(uint32_t v, uint8_t width)
{
    char d[10];
    uint8_t n = 0;
    do {
        d[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v);
    while (width-- > n)
        out_c(' ');
    while (n)
        out_c(d[--n]);
}

static void out_pct(uint32_t c)
{
    uint32_t tenths = (c * 1000u + BUDGET / 2) / BUDGET;
    out_u(tenths / 10u, 4);
    out_c('.');
    out_u(tenths % 10u, 1);
    out_s(" %");
}

/* The tasks in app_tick()'s order (bt_task()'s three parts each timed), as X(name, function). */
#ifdef LINK_HCI
#define BT_TASKS(X) X("bt hci", hci_task) X("bt l2cap", l2cap_task) X("bt rfcomm", rfcomm_task)
#else
#define BT_TASKS(X)
#endif
#define TASK_LIST(X) X("speed", speed_task) X("line_sensor", line_sensor_task) X("sensors", sensors_task)          \
    X("proximity", proximity_task) BT_TASKS(X) X("comm", comm_task) X("failsafe", failsafe_task)                  \
    X("line_follower", line_follower_task) X("track", track_task) X("locomotion", locomotion_task)                \
    X("eeprom", eeprom_task) X("reflector", reflector_task)
#define NAME(name, fn) name,
static const char *const names[TASKS] = {TASK_LIST(NAME)};
static uint32_t task_max[TASKS];
static uint16_t task_in_worst[TASKS]; /* each task's share of the worst tick */
static uint32_t task_sum[TASKS];
static uint16_t task_n;
static uint32_t tick_sum;
static uint32_t tick_max, worst_tick;
static uint32_t isr_max;
static uint32_t enc_t[2];

/* Host and IR traffic of a scenario: none, what the links can physically carry, or every tick (stress); or the
 * IR of the track behaviour: another robot's beacons and messages, or our own beacon reflected (an obstacle). */
enum { CHATTER_NONE, CHATTER_LINKS, CHATTER_STRESS, CHATTER_TRACK, CHATTER_OBSTACLE, CHATTER_HOST };
#define IR_MESSAGE_MS 42u

/* One tick's tasks with a timer reading between two (a 16-bit read each): called directly, in app_tick()'s order, so
 * that LTO inlines them into one function as it does into the robot's main loop (a task called through a table is a
 * function of its own: 50 to 80 cycles more each in saved registers than on the robot). The memory barriers keep
 * each task's work between its two readings. The arithmetic comes after the tick. Not inlined: the harness's cycles
 * (the worst tick includes them) would otherwise change with the register pressure of the scenarios' scripts. */
#define BARRIER() __asm__ __volatile__("" ::: "memory")
static __attribute__((noinline)) void time_tasks(uint16_t *stamp)
{
    BARRIER();
    *stamp++ = TCNT1;
    BARRIER();
#define CALL(name, fn) fn(); BARRIER(); *stamp++ = TCNT1; BARRIER();
    TASK_LIST(CALL)
#undef CALL
}

/* One millisecond: scheduler interrupts in 100 us steps, encoder edges, then the tick, each task timed. */
static void one_tick(uint8_t moving, uint8_t chatter)
{
    for (uint8_t k = 0; k < 10; k++) {
        bench_us += 100;
        uint32_t t0 = cycles();
        bench_fire_due();
        uint32_t d = cycles() - t0;
        if (d > isr_max)
            isr_max = d;
    }
    if (moving) { /* about 140 mm/s: a pulse every 5 ms per wheel */
        for (uint8_t w = 0; w < 2; w++)
            if ((bench_us / 1000u + w) % 5u == 0) {
                enc_t[w] = bench_us * 4u;
                encoder_capture_isr(w, enc_t[w]);
            }
    }
    if (chatter == CHATTER_TRACK || chatter == CHATTER_OBSTACLE) {
        /* At the IR link's rate: robot 7 close ahead (its rear LED at 50 %) handing the token to us and taking it
         * back, every message of the handshake a new step (OFFER, GIVE: we accept, take, answer; ACCEPT, TAKEN of
         * our offer: we let go, give), and robot 8 behind greeting us; or our own reflection. */
        uint32_t ms = bench_us / 1000u;
        uint8_t me = settings.identity.robot_id;
        if (chatter == CHATTER_OBSTACLE) {
            hal_ir_msg_t own = {me, 0, 100, 0, {0}};
            if (ms % IR_MESSAGE_MS == 0)
                ir_rx_isr(0, &own);
        } else if (ms % IR_MESSAGE_MS == 0) {
            hal_ir_msg_t ahead = {7, 2, 50, 0, {0}};
            if ((ms / IR_MESSAGE_MS) % 2u) {
                static const uint8_t kinds[] = {TRACK_MSG_OFFER, TRACK_MSG_GIVE, TRACK_MSG_ACCEPT, TRACK_MSG_TAKEN};
                static uint8_t step; /* from hop 1: the scenario starts without the token */
                uint8_t kind = kinds[step % 4u];
                uint8_t hop = (uint8_t)(2u * (step / 4u) + (kind == TRACK_MSG_ACCEPT || kind == TRACK_MSG_TAKEN ? 2u : 1u));
                step++;
                hal_ir_msg_t token = {7, 2, 100, TRACK_MSG_LEN, {kind, me, hop}};
                ahead = token;
            }
            ir_rx_isr(0, &ahead);
        } else if (ms % IR_MESSAGE_MS == IR_MESSAGE_MS / 2) {
            hal_ir_msg_t greet = {8, 0, 100, TRACK_MSG_LEN, {TRACK_MSG_GREET, me, 0}};
            ir_rx_isr(1, &greet);
        }
    } else if (chatter) { /* IR messages heard and a heartbeat from the host every tick */
        /* A message with a 4-byte payload is about 10 bytes at 2400 Bd (42 ms) on the IR link, so a receiver can
         * hear one every 42 ms at most; CHATTER_STRESS delivers one to each receiver every tick regardless. */
        uint32_t ms = bench_us / 1000u;
        hal_ir_msg_t m = {7, 2, 50, 4, {1, 2, 3, 4, 0, 0, 0, 0}};
        m.data[0] = (uint8_t)bench_us;
        if (chatter == CHATTER_STRESS || (chatter == CHATTER_LINKS && ms % IR_MESSAGE_MS == 0))
            ir_rx_isr(0, &m);
        m.power = 25;
        if (chatter == CHATTER_STRESS || (chatter == CHATTER_LINKS && ms % IR_MESSAGE_MS == IR_MESSAGE_MS / 2))
            ir_rx_isr(1, &m); /* CHATTER_HOST: the host's packets only */
        static const uint8_t hb[] = {0xC0, 0x11, 0x00, 0x00, 0xCF, 0xB8, 0xC0};
#ifdef LINK_HCI
        if (bench_bt_idle()) /* as fast as the wire carries them */
            bench_bt_host_packet(hb, sizeof hb);
#else
        for (uint8_t i = 0; i < sizeof hb; i++)
            uart_rx_isr(hb[i]);
#endif
    }
    if (!scheduler_tick_begin())
        return;
    robot_state.time.time_ms++;
    uint16_t stamp[TASKS + 1];
    time_tasks(stamp);
    scheduler_tick_end();
    for (uint8_t i = 0; i < TASKS; i++) {
        uint16_t d = (uint16_t)(stamp[i + 1] - stamp[i]);
        if (d > task_max[i])
            task_max[i] = d;
        task_sum[i] += d;
    }
    task_n++;
    uint16_t total = (uint16_t)(stamp[TASKS] - stamp[0]); /* a tick is far below 65536 cycles */
    if (total > tick_max) {
        tick_max = total;
        for (uint8_t i = 0; i < TASKS; i++)
            task_in_worst[i] = (uint16_t)(stamp[i + 1] - stamp[i]);
    }
    tick_sum += total;
#ifdef LINK_HCI
    bench_bt_wire(); /* the controller takes and answers the firmware's bytes, 12 per ms each way */
#else
    /* Drain the link as a 115200 Bd UART would (12 bytes per ms), keeping room for packets. */
    for (uint8_t i = 0; i < 12; i++)
        uart_tx_isr();
#endif
}

static void report(const char *scenario)
{
    out_s("BENCH: ");
    out_s(scenario);
    out_s(": worst tick ");
    out_u(tick_max, 6);
    out_s(" cycles =");
    out_pct(tick_max);
    out_s(", mean ");
    out_u(tick_sum / task_n, 1);
    out_s(" cycles =");
    out_pct(tick_sum / task_n);
    out_s("\n");
    out_s("BENCH:   task            worst  share      mean  share   in the worst tick\n");
    for (uint8_t i = 0; i < TASKS; i++) {
        out_s("BENCH:   ");
        out_s(names[i]);
        for (uint8_t k = (uint8_t)strlen(names[i]); k < 14; k++)
            out_c(' ');
        out_u(task_max[i], 6);
        out_pct(task_max[i]);
        out_u(task_sum[i] / task_n, 9);
        out_pct(task_sum[i] / task_n);
        out_u(task_in_worst[i], 9);
        out_s("\n");
    }
    if (tick_max > worst_tick)
        worst_tick = tick_max;
    memset(task_max, 0, sizeof task_max);
    memset(task_sum, 0, sizeof task_sum);
    task_n = 0;
    tick_max = 0;
    tick_sum = 0;
}

static void run(uint16_t ticks, uint8_t moving, uint8_t chatter)
{
    for (uint16_t i = 0; i < ticks; i++)
        one_tick(moving, chatter);
}

#ifdef LINK_HCI
void bench_bt_run(uint16_t ticks)
{
    run(ticks, 0, CHATTER_NONE);
}

/* Starts the controller and connects a host over RFCOMM; none of it counts in the scenarios. */
static void bluetooth_up(void)
{
    for (uint8_t i = 0; i < 200 && !hci_ready(); i++)
        run(1, 0, CHATTER_NONE);
    bench_bt_connect();
    out_s(rfcomm_tx_room(0) ? "BENCH: a host is connected over RFCOMM.\n" : "BENCH: FAIL no host connected.\n");
    memset(task_max, 0, sizeof task_max);
    memset(task_sum, 0, sizeof task_sum);
    task_n = 0;
    tick_max = tick_sum = 0;
    isr_max = 0;
}
#endif

/* Stack painting: the RAM between the static data and the stack is filled with a pattern before anything runs,
 * and the deepest byte the stack overwrote is found at the end (the bench's own frames, the tasks and the scheduler
 * interrupts included). */
#define PAINT 0xA5u
extern uint8_t __heap_start;

static void paint_stack(void)
{
    uint8_t *p = &__heap_start;
    uint8_t *end = (uint8_t *)SP - 64; /* this function's frame and a margin */
    while (p < end)
        *p++ = PAINT;
}

static uint16_t stack_depth(void)
{
    const uint8_t *p = &__heap_start;
    while (*p == PAINT && p < (const uint8_t *)RAMEND)
        p++;
    return (uint16_t)(RAMEND - (uint16_t)p + 1u);
}

int main(void)
{
    paint_stack();
    UBRR0 = 0;
    UCSR0B = (1 << TXEN0);
    TCCR1A = 0;
    TCCR1B = (1 << CS10); /* clk/1 */
    TIMSK1 = (1 << TOIE1);
    app_init();
    sei();

    settings.link.failsafe_timeout_ms = 0;
#ifdef LINK_HCI
    bluetooth_up();
#endif
    run(50, 0, CHATTER_NONE);
    report("idle, full state every 100 ms");

    uint16_t detail;
    pb_move_straight_t move = {1, 10.0f, 0.15f};
    locomotion_straight(&move, &detail);
    run(400, 1, CHATTER_NONE);
    report("movement, full state every 100 ms");

    pb_line_follow_t follow = {1, PB_COLOUR_MODE_SEGMENTS, 0.0f};
    line_follower_command(&follow, &detail);
    bench_set_line_spot(2);
    run(400, 1, CHATTER_NONE);
    report("line following, full state every 100 ms");

    pb_wheel_speeds_t teleop = {0.1f, -0.1f};
    locomotion_teleop(&teleop, &detail);
    settings.sync.mode = PB_SYNC_MODE_REDUCED;
    settings.sync.period_ms = 5;
    run(400, 1, CHATTER_LINKS);
    report("teleoperation, reduced state every 5 ms, a host packet every tick, IR payloads at the IR link's rate");

    settings.sync.mode = PB_SYNC_MODE_FULL;
    settings.sync.period_ms = 100;
    settings.track.token_origin_id = 0;
    track_command(PB_TRACK_ACTION_START);
    bench_set_line_spot(3);
    run(400, 1, CHATTER_TRACK);
    report("track: following a robot close ahead, token hand-overs and greetings at the IR link's rate, full state every 100 ms");
    run(150, 0, CHATTER_OBSTACLE);
    run(250, 1, CHATTER_OBSTACLE);
    report("track: an obstacle ahead, the detour's steps, full state every 100 ms");
#ifdef LINK_HCI
    track_command(PB_TRACK_ACTION_STOP);
    settings.sync.mode = PB_SYNC_MODE_FULL;
    settings.sync.period_ms = 12;
    move.id = 4;
    locomotion_straight(&move, &detail);
    run(400, 1, CHATTER_HOST);
    report("Bluetooth: a movement, full state every 12 ms over RFCOMM (what the wire carries), host packets");
#endif
    uint32_t realistic = worst_tick;

    settings.debug.level = 4;
    settings.sync.mode = PB_SYNC_MODE_FULL;
    settings.sync.period_ms = 1;
    move.id = 2;
    locomotion_straight(&move, &detail);
    move.id = 3;
    locomotion_straight(&move, &detail);
    run(300, 1, CHATTER_STRESS);
    report("stress: movement start, full state EVERY tick, IR payloads and host packets every tick, debug level 4");

    out_s("BENCH: scheduler interrupts (line sensor phases, beacons), worst: ");
    out_u(isr_max, 1);
    out_s(" cycles\n");
    out_s("BENCH: stack at most ");
    out_u(stack_depth(), 1);
    out_s(" bytes deep (static RAM ends at ");
    out_u((uint16_t)&__heap_start - RAMSTART, 1);
    out_s(" bytes)\n");
    out_s("BENCH: WORST TICK (all but the stress scenario) ");
    out_u(realistic, 1);
    out_s(" cycles =");
    out_pct(realistic);
    out_s(" of the 1 ms budget (goal <= 25 %); stress scenario ");
    out_u(worst_tick, 1);
    out_s(" cycles =");
    out_pct(worst_tick);
    out_s("\n");
    while (UCSR0A & (1 << UDRE0) ? 0 : 1) {
    }
    cli();
    sleep_enable();
    sleep_cpu();
}
