/**
 * \file bench_hal.c
 * A HAL for the cycle bench: the portable core runs on an ATmega1284 in simavr, fed with synthetic
 * sensor data; time is advanced by the bench, not by a timer.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <string.h>

#include "bench.h"
#include "hal/hal.h"

uint32_t bench_us;
static uint32_t sched_at[HAL_SCHED_CHANNELS];
static uint8_t sched_armed;
static uint8_t emitters;
static uint8_t eeprom[HAL_EEPROM_SIZE];
int16_t bench_line_spot = 3; /* spot under the line */

void hal_init(void) { bench_set_line_spot(bench_line_spot); }
void hal_irq_enable(void) { sei(); }
uint8_t hal_board_id(void) { return 0; }
void hal_idle(void) {}
void hal_tick_done(void) {}

uint8_t hal_irq_save(void)
{
    uint8_t s = SREG;
    cli();
    return s;
}

void hal_irq_restore(uint8_t saved)
{
    SREG = saved;
}

uint32_t hal_micros(void) { return bench_us; }
uint32_t hal_capture_now(void) { return bench_us * 4u; }

void hal_sched_arm(uint8_t ch, uint32_t delay_us)
{
    sched_at[ch] = bench_us + delay_us;
    sched_armed |= (uint8_t)(1u << ch);
}

void hal_sched_disarm(uint8_t ch)
{
    sched_armed &= (uint8_t)~(1u << ch);
}

void bench_fire_due(void)
{
    for (uint8_t ch = 0; ch < HAL_SCHED_CHANNELS; ch++)
        if ((sched_armed & (1u << ch)) && (int32_t)(bench_us - sched_at[ch]) >= 0) {
            sched_armed &= (uint8_t)~(1u << ch);
            scheduler_isr(ch);
        }
}

void hal_motors_set(int16_t left, int16_t right) { (void)left; (void)right; }
void hal_led_set(uint8_t mask) { (void)mask; }
void hal_uart_tx_kick(void) {}
void hal_line_emitters(uint8_t mask) { emitters = mask; }

/* The robot's HAL only starts the ADC sweep here: the bench looks its synthetic readings up, computed by
 * bench_set_line_spot() for each emitter pattern, so that the model of the line counts as no firmware work. */
static uint16_t line_model[3][HAL_LINE_DETECTORS];

void bench_set_line_spot(int16_t spot)
{
    static const uint8_t masks[3] = {0, 0x15u, 0x0Au};
    bench_line_spot = spot;
    for (uint8_t p = 0; p < 3; p++)
        for (uint8_t d = 0; d < HAL_LINE_DETECTORS; d++) {
            uint16_t v = 300;
            for (uint8_t k = 0; k < 2; k++)
                if (masks[p] & (1u << (d + k)))
                    v = (uint16_t)(v + ((2 * d + k) == spot || (2 * d + k) == spot + 1 ? 2000 : 100));
            line_model[p][d] = v;
        }
}

/* The robot starts a sweep with one register write: here the conversion only notes the emitters it saw, and the
 * results (read in the scheduler's interrupt, outside the tick) are looked up then. */
static uint8_t converted;

void hal_line_convert(void)
{
    converted = emitters;
}

void hal_line_results(uint16_t out[HAL_LINE_DETECTORS])
{
    uint8_t p = converted == 0x15u ? 1u : converted == 0x0Au ? 2u : 0u;
    memcpy(out, line_model[p], sizeof line_model[p]);
}

int32_t hal_sensor_read(uint8_t sensor)
{
    static const int16_t values[HAL_SENSOR_COUNT] = {3900, 120, 285, 10, -5, 1000, 200, 40, 40, 230};
    return sensor < HAL_SENSOR_COUNT ? values[sensor] : 0;
}

bool hal_ir_send(const hal_ir_msg_t *msg) { (void)msg; return true; }
uint32_t hal_ir_message_us(uint8_t len) { return (5u + len) * 11u * 1000000ul / 2400u; } /* the robot's IR link */

void hal_eeprom_read(uint16_t addr, void *dst, uint16_t len)
{
    memcpy(dst, eeprom + addr, len);
}

bool hal_eeprom_busy(void) { return false; }

void hal_eeprom_write_page(uint16_t addr, const void *src, uint8_t len)
{
    memcpy(eeprom + addr, src, len);
}
