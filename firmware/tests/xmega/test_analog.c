/**
 * \file test_analog.c
 * Pins and the ADCs on the model: no pin with two jobs, the production calibration loaded, signed conversions,
 * samples long enough for the detectors' source resistance, and the slow sensors in their physical units.
 */
#include <avr/io.h>
#include <math.h>

#include "core/data.h"
#include "hal/hal.h"
#include "robot.h"
#include "xm_tests.h"

/* Several jobs on one pin, besides a peripheral output's own direction bit. */
static bool conflict(uint8_t uses)
{
    if (uses & (XM_USE_USART_TX | XM_USE_TC_OUT))
        uses &= (uint8_t)~XM_USE_GPIO_OUT;
    return (uses & (uses - 1u)) != 0;
}

static void no_pin_is_used_twice(void)
{
    robot_boot();
    robot_run_us(300000); /* every acquisition, conversion, beacon and colour read a few times */
    hal_line_emitters(0x1F);
    hal_line_emitters(0);
    int conflicts = 0;
    for (char port = 'A'; port <= 'F'; port++)
        for (uint8_t pin = 0; pin < 8; pin++) {
            uint8_t u = xm_pin_uses(port, pin);
            if (conflict(u)) {
                conflicts++;
                printf("  P%c%u: %s\n", port, pin, xm_pin_use_names(u));
            }
        }
    CHECK(conflicts == 0, "%d pins used for two things at once", conflicts);
}

static void the_adcs_are_calibrated_and_convert_in_signed_mode(void)
{
    robot_boot();
    robot_run_us(10000);
    uint16_t cal_a = (uint16_t)(ADCA.CALL | ADCA.CALH << 8), cal_b = (uint16_t)(ADCB.CALL | ADCB.CALH << 8);
    CHECK(cal_a == XM_ADCA_CAL && cal_b == XM_ADCB_CAL, "CAL from the signature row: ADCA 0x%04x (0x%04x), ADCB 0x%04x (0x%04x)",
          cal_a, XM_ADCA_CAL, cal_b, XM_ADCB_CAL);
    CHECK((ADCA.CTRLB & ADC_CONMODE_bm) && (ADCB.CTRLB & ADC_CONMODE_bm),
          "signed mode, as the A3 errata ask even for single-ended inputs: CTRLB 0x%02x 0x%02x", ADCA.CTRLB, ADCB.CTRLB);
}

/* The line detectors are phototransistors with a high-impedance load: a sample must settle through it. */
static void line_detectors_read_their_own_voltage(void)
{
    static const double volts[4] = {0.25, 1.80, 0.40, 1.60};
    robot_boot(); /* no main loop tick yet: no acquisition of the line sensor's own */
    for (uint8_t d = 0; d < 4; d++)
        xm_analog_set('A', (uint8_t)(4 + d), volts[d], 47e3);
    hal_line_convert();
    xm_busy(XM_US(100), false); /* the line sensor reads the results 100 us after it started them */
    uint16_t res[4];
    hal_line_results(res);
    double full_scale = 3.3 / 1.6; /* the detectors' reference, VCC/1.6, is 12-bit full scale */
    for (uint8_t d = 0; d < 4; d++) {
        double expected = volts[d] / full_scale * 4096.0;
        CHECK(fabs(res[d] - expected) <= 0.005 * 4096.0, "detector %u: %u, %.0f expected (%.2f V)", d, res[d], expected,
              volts[d]);
    }
}

typedef struct {
    double vcc, battery_v, current_ma, celsius, ax_g, ay_g, az_g;
} inputs_t;

/* The board (hal/xmega/board.h): battery through a 1:3 divider on PB0, 1 mV per mA on PB1, a ratiometric
 * accelerometer on PB2..PB4 (zero g at VCC / 2, 100 mV per g at 3.3 V). */
static void apply(const inputs_t *in)
{
    xm_vcc_set(in->vcc);
    xm_temperature_set(in->celsius);
    xm_analog_set('B', 0, in->battery_v / 3.0, 33e3);
    xm_analog_set('B', 1, in->current_ma / 1000.0, 1e3);
    double zero = in->vcc / 2.0, per_g = 0.100 * in->vcc / 3.3;
    xm_analog_set('B', 2, zero + in->ax_g * per_g, 32e3);
    xm_analog_set('B', 3, zero + in->ay_g * per_g, 32e3);
    xm_analog_set('B', 4, zero + in->az_g * per_g, 32e3);
}

static void slow_sensors_read_in_their_units(void)
{
    static const inputs_t cases[] = {
        {3.30, 3.90, 120, 25.0, 0.0, 0.0, 1.0},
        {3.30, 4.15, 350, 60.0, -1.0, 0.5, 0.0},
        {3.20, 3.60, 40, -5.0, 0.2, -0.8, -1.0}, /* a lower VCC: the battery still reads right */
    };
    robot_boot();
    for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const inputs_t *c = &cases[i];
        apply(c);
        robot_run_us(20000); /* a few sweeps of ADCB and ticks of the sensors task */
        const pb_state_power_t *p = &robot_state.power;
        const pb_state_accel_t *a = &robot_state.accel;
        CHECK(fabs(p->battery_mv - c->battery_v * 1000) <= 25, "case %u: battery %u mV, %.0f mV", i, p->battery_mv,
              c->battery_v * 1000);
        CHECK(fabs(p->current_ma - c->current_ma) <= 3, "case %u: current %u mA, %.0f mA", i, p->current_ma, c->current_ma);
        CHECK(fabs(p->mcu_temp_dc - c->celsius * 10) <= 15, "case %u: MCU temperature %d dC, %.0f dC", i, p->mcu_temp_dc,
              c->celsius * 10);
        CHECK(fabs(a->x_mg - c->ax_g * 1000) <= 25 && fabs(a->y_mg - c->ay_g * 1000) <= 25 &&
                  fabs(a->z_mg - c->az_g * 1000) <= 25,
              "case %u: acceleration %d %d %d mg, %.0f %.0f %.0f mg", i, a->x_mg, a->y_mg, a->z_mg, c->ax_g * 1000,
              c->ay_g * 1000, c->az_g * 1000);
    }
    CHECK(xm_misuse_count() == 0, "the model saw: %s", xm_misuse_last());
}

void suite_xm_analog(void)
{
    RUN(no_pin_is_used_twice);
    RUN(the_adcs_are_calibrated_and_convert_in_signed_mode);
    RUN(line_detectors_read_their_own_voltage);
    RUN(slow_sensors_read_in_their_units);
}
