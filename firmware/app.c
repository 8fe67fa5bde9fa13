#include "app.h"

#include <string.h>

#include "drivers/eeprom.h"
#include "drivers/encoder.h"
#include "drivers/line_sensor.h"
#include "drivers/motors.h"
#include "drivers/sensors.h"
#include "drivers/uart.h"
#include "hal/hal.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/failsafe.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"
#include "modules/proximity.h"
#include "modules/reflector.h"
#include "modules/scheduler.h"
#include "modules/settings.h"
#include "modules/speed.h"

#define LED_ALIVE 0x01u
#define LED_LINE 0x02u
#define LED_FAILSAFE 0x04u

static uint32_t last_us;
static uint16_t us_acc;

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
    uint8_t led = (robot_state.time.time_ms & 512u) ? LED_ALIVE : 0;
    if (robot_state.line.flags & LINE_FLAG_SEEN)
        led |= LED_LINE;
    if (robot_state.locomotion.mode == PB_LOCO_MODE_FAILSAFE)
        led |= LED_FAILSAFE;
    if (led != robot_state.indicators.led) {
        robot_state.indicators.led = led;
        hal_led_set(led);
    }
}

void app_init(void)
{
    memset(&robot_state, 0, sizeof robot_state);
    hal_init();
    bool from_eeprom = settings_init();
    uart_init();
    encoder_init();
    motors_init();
    speed_init();
    sensors_init();
    reflector_init();
    comm_init();
    failsafe_init();
    locomotion_init();
    line_follower_init();
    scheduler_init();
    line_sensor_init();
    proximity_init();
    last_us = hal_micros();
    us_acc = 0;
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
    comm_task();
    failsafe_task();
    line_follower_task();
    locomotion_task();
    eeprom_task();
    led_task();
    reflector_task();
}

bool app_poll(void)
{
    if (!scheduler_tick_begin())
        return false;
    app_tick();
    scheduler_tick_end();
    return true;
}
