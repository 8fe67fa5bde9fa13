#include "app.h"

#include <string.h>

#include "core/data.h"
#include "core/scheduler.h"
#include "drivers/eeprom.h"
#include "drivers/encoder.h"
#include "drivers/line_sensor.h"
#include "drivers/motors.h"
#include "drivers/sensors.h"
#include "drivers/uart.h"
#include "hal/hal.h"
#ifdef LINK_HCI
#include "bluetooth/bt.h"
#endif
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/failsafe.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"
#include "modules/proximity.h"
#include "modules/reflector.h"
#include "modules/settings.h"
#include "modules/speed.h"
#include "modules/track.h"

/** At most one overrun warning (debug text) per this many ms; robot_state.time counts every overrun. */
#define OVERRUN_WARNING_MS 1000u

static uint32_t last_us;
static uint16_t us_acc;
static uint32_t warned_ms;
static uint8_t warned;

static void clock_task(void)
{
    uint32_t now = hal_micros();
    uint32_t d = now - last_us;
    last_us = now;
    while (d >= 1000u) {
        d -= 1000u;
        robot_state.time.time_ms++;
    }
    us_acc = (uint16_t)(us_acc + d);
    if (us_acc >= 1000u) {
        us_acc = (uint16_t)(us_acc - 1000u);
        robot_state.time.time_ms++;
    }
}

static void led_task(void)
{
    uint8_t led = (robot_state.time.time_ms & 512u) ? PB_LED_FLAG_ALIVE : 0;
    if (robot_state.line.flags & PB_LINE_FLAG_SEEN)
        led |= PB_LED_FLAG_LINE;
    if (robot_state.locomotion.mode == PB_LOCO_MODE_FAILSAFE)
        led |= PB_LED_FLAG_FAILSAFE;
    if (robot_state.track.token)
        led |= PB_LED_FLAG_TOKEN; /* the thesis's orange light */
    if (led != robot_state.indicators.led) {
        robot_state.indicators.led = led;
        hal_led_set(led);
    }
}

/* The scheduler counts overruns; this tells the host in words, at most once a second (an overloaded loop
 * would overrun every tick, and a warning per tick would only add to the load). */
static void overrun_warning(void)
{
    if (!scheduler_overruns_pending())
        return;
    uint32_t now = robot_state.time.time_ms;
    if (warned && now - warned_ms < OVERRUN_WARNING_MS)
        return;
    uint16_t longest_us;
    uint16_t n = scheduler_take_overruns(&longest_us);
    warned = 1;
    warned_ms = now;
    DEBUG_PRINT(SCHEDULER, 1, "main loop overran %u times, longest tick %u us of %u", n, longest_us,
                scheduler_period_us());
    (void)n;
    (void)longest_us;
}

void app_init(void)
{
    memset(&robot_state, 0, sizeof robot_state);
    hal_init();
    comm_init(); /* first: the modules register their packet handlers in their inits */
    bool from_eeprom = settings_init();
    uart_init();
#ifdef LINK_HCI
    bt_init(); /* the UART carries H4 to the Bluetooth module; the stack opens comm's links as hosts connect */
#else
    comm_link_open(0, &comm_uart_link); /* a serial link is open from reset: the robot cannot see its host come */
#endif
    encoder_init();
    motors_init();
    speed_init();
    sensors_init();
    reflector_init();
    failsafe_init();
    locomotion_init();
    line_follower_init();
    scheduler_init();
    line_sensor_init();
    proximity_init();
    track_init(); /* after proximity: it listens to the payloads heard */
    last_us = hal_micros();
    us_acc = 0;
    warned = 0;
    hal_irq_enable();
    comm_send_hello();
    DEBUG_PRINT(MAIN, 2, "PocketBot %u up, settings from %s", settings.identity.robot_id,
                from_eeprom ? "EEPROM" : "defaults");
    (void)from_eeprom;
}

void app_tick(void)
{
    clock_task();
    speed_task();
    line_sensor_task();
    sensors_task();
    proximity_task();
#ifdef LINK_HCI
    bt_task();
#endif
    comm_task();
    failsafe_task();
    line_follower_task();
    track_task();
    locomotion_task();
    eeprom_task();
    led_task();
    reflector_task();
}

void app_idle(void)
{
    (void)hal_irq_save(); /* hal_idle() enables interrupts again as it sleeps */
    if (scheduler_tick_due())
        hal_irq_enable();
    else
        hal_idle();
}

bool app_poll(void)
{
    if (!scheduler_tick_begin())
        return false;
    app_tick();
    hal_tick_done();
    scheduler_tick_end();
    overrun_warning();
    return true;
}
