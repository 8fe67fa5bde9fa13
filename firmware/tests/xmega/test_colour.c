/**
 * \file test_colour.c
 * The colour sensor (TCS3472 on TWIC) on the model: what the HAL writes to it, what it reads, what the robot makes
 * of it, and a sensor that does not answer.
 */
#include <avr/io.h>

#include "core/data.h"
#include "hal/hal.h"
#include "robot.h"
#include "xm_tests.h"

/* The board's choice (hal/xmega/board.h): 4 cycles of 2.4 ms, gain 16x: full scale 4096 counts. */
#define ATIME 0xFCu
#define AGAIN 0x02u
#define FULL_SCALE 4096.0
#define GAIN 16.0
#define CYCLES 4.0

/* Light per 2.4 ms cycle at gain 1x that reads `v` of 255 on every channel. */
static uint16_t light_for(double v)
{
    return (uint16_t)(v / 255.0 * FULL_SCALE / GAIN / CYCLES + 0.5);
}

static void surface(double c, double r, double g, double b)
{
    xm_tcs_light(light_for(c), light_for(r), light_for(g), light_for(b));
}

static void the_sensor_is_configured_and_read_whole(void)
{
    robot_boot();
    surface(200, 180, 180, 180);
    robot_run_us(100000);
    bool atime = false, gain = false, enabled = false;
    uint32_t starts = 0, ends = 0, bytes = 0;
    for (uint32_t i = 0; i < xm_tcs_log_count(); i++) {
        const xm_tcs_access_t *a = xm_tcs_log(i);
        atime |= a->write && a->reg == 0x01 && a->value == ATIME;
        gain |= a->write && a->reg == 0x0F && a->value == AGAIN;
        enabled |= a->write && a->reg == 0x00 && (a->value & 0x03) == 0x03;
        starts += !a->write && a->reg == 0x14;
        ends += !a->write && a->reg == 0x1B;
        bytes += !a->write && a->reg >= 0x14 && a->reg <= 0x1B;
    }
    CHECK(enabled, "ENABLE := PON | AEN");
    CHECK(atime, "ATIME := 0x%02x (the integration time)", ATIME);
    CHECK(gain, "CONTROL := 0x%02x (the gain)", AGAIN);
    CHECK(xm_tcs_reg(0x01) == ATIME && xm_tcs_reg(0x0F) == AGAIN, "the sensor holds ATIME 0x%02x, CONTROL 0x%02x",
          xm_tcs_reg(0x01), xm_tcs_reg(0x0F));
    /* An integration is 9.6 ms: 8 or 9 in 100 ms after the configuration and the warm-up. */
    CHECK(ends >= 7 && ends <= 10 && starts - ends <= 1 && bytes - 8 * ends <= 7,
          "%u reads of the counts begun, %u ended (%u bytes): all eight bytes, once per integration", starts, ends, bytes);
    const pb_state_colour_t *k = &robot_state.colour;
    CHECK(k->clear >= 198 && k->clear <= 201 && k->red >= 178 && k->red <= 181 && k->green >= 178 && k->blue >= 178,
          "clear %u red %u green %u blue %u (light for 200, 180, 180, 180)", k->clear, k->red, k->green, k->blue);
    CHECK(xm_misuse_count() == 0, "the model saw: %s", xm_misuse_last());
}

static void surfaces_are_told_apart(void)
{
    static const struct {
        double c, r, g, b;
        uint8_t colour;
        const char *name;
    } floor[] = {
        {220, 200, 200, 200, PB_COLOUR_WHITE, "white"},
        {30, 20, 20, 20, PB_COLOUR_BLACK, "black tape"},
        {140, 200, 40, 40, PB_COLOUR_RED, "red tape"},
        {120, 40, 60, 190, PB_COLOUR_BLUE, "blue tape"},
    };
    robot_boot();
    for (unsigned i = 0; i < sizeof floor / sizeof floor[0]; i++) {
        surface(floor[i].c, floor[i].r, floor[i].g, floor[i].b);
        robot_run_us(40000); /* an integration and a read */
        CHECK(robot_state.colour.detected == floor[i].colour, "%s: detected %u (r %u g %u b %u c %u)", floor[i].name,
              robot_state.colour.detected, robot_state.colour.red, robot_state.colour.green, robot_state.colour.blue,
              robot_state.colour.clear);
    }
}

static void a_sensor_that_does_not_answer_gives_no_colour_and_is_tried_again(void)
{
    robot_boot();
    surface(220, 200, 200, 200);
    robot_run_us(50000);
    CHECK(robot_state.colour.detected == PB_COLOUR_WHITE, "white while it answers: %u", robot_state.colour.detected);
    xm_tcs_present(false); /* unplugged: every address is NACKed */
    robot_run_us(50000);
    xm_irq_clear_counts();
    uint32_t tries = xm_tcs_transactions();
    robot_run_us(1000000);
    CHECK(robot_state.colour.detected == PB_COLOUR_UNKNOWN, "no colour rather than black or white: %u",
          robot_state.colour.detected);
    CHECK(xm_tcs_transactions() - tries <= 12, "tried again %u times in a second", xm_tcs_transactions() - tries);
    CHECK(xm_irq_count(TWIC_TWIM_vect_num) <= 30, "%u TWI interrupts in a second", xm_irq_count(TWIC_TWIM_vect_num));
    CHECK((TWIC.MASTER.STATUS & TWI_MASTER_BUSSTATE_gm) == TWI_MASTER_BUSSTATE_IDLE_gc, "the bus is let go");
    xm_tcs_present(true); /* plugged in again (powered off meanwhile: not configured) */
    robot_run_us(300000);
    CHECK(robot_state.colour.detected == PB_COLOUR_WHITE, "configured again and white: %u", robot_state.colour.detected);
    CHECK(xm_misuse_count() == 0, "the model saw: %s", xm_misuse_last());
}

void suite_xm_colour(void)
{
    RUN(the_sensor_is_configured_and_read_whole);
    RUN(surfaces_are_told_apart);
    RUN(a_sensor_that_does_not_answer_gives_no_colour_and_is_tried_again);
}
