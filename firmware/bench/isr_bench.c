/**
 * \file isr_bench.c
 * Cycle counts of the robot's interrupt handlers: hal/xmega's ISRs and the firmware they call, compiled for the
 * ATmega1284 of the cycle bench with the XMEGA's register file in RAM (xmega_io/avr/io.h), each called in the
 * situations it meets on the robot: main loop ticks and line sensor phases, a beacon's messages byte by byte,
 * encoder captures, host link bytes both ways, an IR message heard byte by byte, the colour sensor configured
 * and read. A call's cycles (Timer1 at clk/1) include the handler's prologue and RETI; the XMEGA's interrupt
 * response and the vector's JMP (8 cycles) are added. Nothing acts on the registers: the register values a handler
 * reads are set here. Output: one line per vector, `BENCH: isr <vector> <name> worst <cycles> mean <cycles> calls <n>`.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <stdio.h>
#include <string.h>

#include "app.h"
#include "core/scheduler.h"
#include "drivers/ir.h"
#include "drivers/line_sensor.h"
#include "drivers/uart.h"
#include "hal/hal.h"

uint8_t bench_xmega_io[0x1000];

/* The XMEGA's registers that the handlers read (addresses of avr-libc's iox128a3.h). */
#define OSC_STATUS 0x0051u
#define TCC0_CNT 0x0820u
#define TCD0_CNT 0x0920u
#define TCD0_CCA 0x0928u
#define TCD0_CCB 0x092Au
#define USARTC0_DATA 0x08A0u
#define USARTC0_STATUS 0x08A1u
#define USARTD0_DATA 0x09A0u
#define USARTD0_STATUS 0x09A1u
#define USARTD0_CTRLB 0x09A4u
#define USARTD1_DATA 0x09B0u
#define USARTD1_STATUS 0x09B1u
#define TWIC_STATUS 0x0484u
#define TWIC_DATA 0x0487u
#define USART_RXB8 0x01u
#define USART_TXB8 0x01u
#define TWI_RIF 0x80u
#define TWI_WIF 0x40u
#define RESPONSE_CYCLES 8u

#define V(n) extern void __vector_##n(void);
V(13) V(14) V(16) V(17) V(18) V(19) V(25) V(26) V(77) V(79) V(80) V(88) V(90) V(91)
#undef V

static void set16(uint16_t a, uint16_t v)
{
    bench_xmega_io[a] = (uint8_t)v;
    bench_xmega_io[a + 1] = (uint8_t)(v >> 8);
}

/* ---- output: printf on UART0, which simavr prints ---- */

static int put(char c, FILE *f)
{
    (void)f;
    while (!(UCSR0A & (1 << UDRE0))) {
    }
    UDR0 = (uint8_t)c;
    return 0;
}

static FILE uart0 = FDEV_SETUP_STREAM(put, NULL, _FDEV_SETUP_WRITE);

/* ---- timing ---- */

typedef struct {
    uint8_t vector;
    const char *name;
    void (*isr)(void);
    uint32_t sum, worst;
    uint16_t n;
} stat_t;

static stat_t stats[] = {
    {13, "TWIC_TWIM", __vector_13, 0, 0, 0},  {14, "TCC0_OVF", __vector_14, 0, 0, 0},
    {16, "TCC0_CCA", __vector_16, 0, 0, 0},   {17, "TCC0_CCB", __vector_17, 0, 0, 0},
    {18, "TCC0_CCC", __vector_18, 0, 0, 0},   {19, "TCC0_CCD", __vector_19, 0, 0, 0},
    {25, "USARTC0_RXC", __vector_25, 0, 0, 0}, {26, "USARTC0_DRE", __vector_26, 0, 0, 0},
    {77, "TCD0_OVF", __vector_77, 0, 0, 0},   {79, "TCD0_CCA", __vector_79, 0, 0, 0},
    {80, "TCD0_CCB", __vector_80, 0, 0, 0},   {88, "USARTD0_RXC", __vector_88, 0, 0, 0},
    {90, "USARTD0_TXC", __vector_90, 0, 0, 0}, {91, "USARTD1_RXC", __vector_91, 0, 0, 0},
};

static __attribute__((noinline)) void nothing(void)
{
    __asm__ __volatile__("");
}

static uint16_t call_overhead;

/* Calls `isr` once and counts its cycles in its vector's line. */
static void call(uint8_t vector)
{
    stat_t *s = stats;
    while (s->vector != vector)
        s++;
    uint8_t sreg = SREG;
    cli();
    uint16_t t0 = TCNT1;
    s->isr();
    uint16_t t1 = TCNT1;
    SREG = sreg;
    uint32_t c = (uint16_t)(t1 - t0) - call_overhead + RESPONSE_CYCLES;
    s->sum += c;
    s->n++;
    if (c > s->worst)
        s->worst = c;
}

static uint16_t measure_overhead(void)
{
    uint16_t t0 = TCNT1;
    nothing();
    uint16_t t1 = TCNT1;
    return (uint16_t)(t1 - t0);
}

/* ---- the robot's time: TCC0 at 500 kHz, its overflow counted by the HAL's own handler ---- */

static uint32_t now_us;

static void time_to(uint32_t us)
{
    uint32_t ticks = us / 2u;
    if ((ticks >> 16) != ((now_us / 2u) >> 16)) {
        set16(TCC0_CNT, 0);
        call(14); /* the count wrapped */
    }
    set16(TCC0_CNT, (uint16_t)ticks);
    set16(TCD0_CNT, (uint16_t)(us * 4u));
    now_us = us;
}

/* ---- the situations ---- */

/* Ticks of the main loop with a line sensor acquisition each: the tick's compare, then the 5 phases 100 us apart. */
static void ticks_and_line_phases(uint16_t n)
{
    for (uint16_t k = 0; k < n; k++) {
        uint32_t tick = now_us + 1000u - now_us % 1000u;
        time_to(tick);
        call(16);
        if (scheduler_tick_begin()) {
            line_sensor_task();
            scheduler_tick_end();
        }
        for (uint8_t phase = 1; phase <= 5; phase++) {
            time_to(tick + 100u * phase);
            call(17);
        }
    }
}

#define IR_MESSAGE_FRAMES 5u /* a message without payload: sync, sender, LED and length, power, CRC */
static uint16_t ir_frames[IR_MESSAGE_FRAMES + HAL_IR_PAYLOAD_MAX];

static uint16_t frame_written(void)
{
    return (uint16_t)(bench_xmega_io[USARTD0_DATA] | ((bench_xmega_io[USARTD0_CTRLB] & USART_TXB8) ? 0x100u : 0u));
}

/* A message's `frames` leave one TXC at a time; the TXC of the last frees the transmitter. */
static void transmit_message(uint8_t frames)
{
    ir_frames[0] = frame_written();
    for (uint8_t k = 1; k < frames; k++) {
        call(90);
        ir_frames[k] = frame_written();
    }
    call(90);
}

/* The beacon (100 ms after boot) and its messages, 24 ms apart: the scheduler's channels 3 and 2. */
static void a_beacon(void)
{
    time_to(100000u);
    call(19);
    transmit_message(IR_MESSAGE_FRAMES);
    for (uint8_t m = 1; m < 4; m++) {
        time_to(now_us + hal_ir_message_us(0) + 1000u);
        call(18);
        transmit_message(IR_MESSAGE_FRAMES);
    }
}

/* An IR message with 8 bytes of payload heard by both receivers, frame by frame. */
static void a_message_heard(void)
{
    hal_ir_msg_t m = {9, 2, 50, 8, {1, 2, 3, 0, 0xFF, 0x80, 7, 0}};
    time_to(now_us + 100000u);
    if (!hal_ir_send(&m))
        return;
    uint8_t n = (uint8_t)(IR_MESSAGE_FRAMES + m.len);
    transmit_message(n);
    for (uint8_t side = 0; side < 2; side++) {
        for (uint8_t i = 0; i < n; i++) {
            bench_xmega_io[side ? USARTD1_STATUS : USARTD0_STATUS] = (ir_frames[i] & 0x100u) ? USART_RXB8 : 0;
            bench_xmega_io[side ? USARTD1_DATA : USARTD0_DATA] = (uint8_t)ir_frames[i];
            call(side ? 91 : 88);
        }
        uint8_t s;
        while (ir_peek(&s))
            ir_pop();
    }
}

static void encoder_edges(void)
{
    uint16_t t = 1000;
    for (uint8_t k = 0; k < 40; k++, t = (uint16_t)(t + 4000u)) { /* an edge a millisecond per wheel */
        set16(TCD0_CCA, t);
        set16(TCD0_CCB, (uint16_t)(t + 2000u));
        set16(TCD0_CNT, (uint16_t)(t + 2100u));
        call(79);
        call(80);
        if (k % 8u == 0)
            call(77);
    }
}

static void host_link_bytes(void)
{
    for (uint16_t k = 0; k < 200; k++) { /* received: taken by the main loop meanwhile */
        bench_xmega_io[USARTC0_STATUS] = 0;
        bench_xmega_io[USARTC0_DATA] = (uint8_t)(k == 0 || k % 20u == 19u ? 0xC0u : k);
        call(25);
        uint8_t b;
        while (uart_getc(&b)) {
        }
    }
    for (uint8_t round = 0; round < 2; round++) { /* sent: a full buffer drained */
        uint8_t pos = uart_tx_begin();
        for (uint8_t k = 0; k < 200; k++)
            pos = uart_tx_store(pos, k);
        uart_tx_commit(pos);
        for (uint8_t k = 0; k < 201; k++)
            call(26);
    }
}

/* The colour sensor configured (7 steps), then read once per integration (10 steps each). */
static void colour_reads(void)
{
    (void)hal_sensor_read(HAL_SENSOR_COLOUR_R);
    for (uint8_t k = 0; k < 7; k++) {
        bench_xmega_io[TWIC_STATUS] = TWI_WIF;
        call(13);
    }
    for (uint8_t r = 0; r < 5; r++) {
        time_to(now_us + 10000u);
        (void)hal_sensor_read(HAL_SENSOR_COLOUR_R);
        for (uint8_t k = 0; k < 10; k++) {
            bench_xmega_io[TWIC_STATUS] = k < 2 ? TWI_WIF : TWI_RIF;
            bench_xmega_io[TWIC_DATA] = (uint8_t)(0x40u + k);
            call(13);
        }
    }
}

int main(void)
{
    UBRR0 = 0;
    UCSR0B = (1 << TXEN0);
    TCCR1A = 0;
    TCCR1B = (1 << CS10); /* clk/1 */
    bench_xmega_io[OSC_STATUS] = 0xFF; /* the oscillators are ready at once */
    app_init();
    cli();
    call_overhead = measure_overhead();
    ticks_and_line_phases(40);
    a_beacon();
    a_message_heard();
    encoder_edges();
    host_link_bytes();
    colour_reads();
    stdout = &uart0;
    for (uint8_t i = 0; i < sizeof stats / sizeof stats[0]; i++) {
        const stat_t *t = &stats[i];
        printf("BENCH: isr %u %s worst %lu mean %lu calls %u\n", t->vector, t->name, (unsigned long)t->worst,
               (unsigned long)(t->n ? t->sum / t->n : 0), t->n);
    }
    while (!(UCSR0A & (1 << UDRE0))) {
    }
    sleep_enable();
    sleep_cpu();
}
