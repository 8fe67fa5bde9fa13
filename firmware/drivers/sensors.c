#include "sensors.h"

#include "core/data.h"
#include "hal/hal.h"

static uint8_t group;

void sensors_init(void)
{
    group = 0;
}

static uint8_t to_u8(int32_t v)
{
    return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
}

static int16_t to_i16(int32_t v)
{
    return (int16_t)(v < -32768 ? -32768 : v > 32767 ? 32767 : v);
}

static uint16_t to_u16(int32_t v)
{
    return (uint16_t)(v < 0 ? 0 : v > 65535 ? 65535 : v);
}

uint8_t sensors_classify(uint8_t r, uint8_t g, uint8_t b, uint8_t clear)
{
    uint8_t max = r > g ? (r > b ? r : b) : (g > b ? g : b);
    uint8_t min = r < g ? (r < b ? r : b) : (g < b ? g : b);
    uint8_t bright = max > clear ? max : clear;
    if (bright < 50)
        return PB_COLOUR_BLACK;
    if ((uint16_t)(max - min) * 4u < max) { /* saturation below 25 %: no hue */
        if (bright >= 150)
            return PB_COLOUR_WHITE;
        if (bright < 80)
            return PB_COLOUR_BLACK;
        return PB_COLOUR_UNKNOWN;
    }
    if (max == r)
        return PB_COLOUR_RED;
    if (max == g)
        return PB_COLOUR_GREEN;
    return PB_COLOUR_BLUE;
}

void sensors_task(void)
{
    switch (group) {
    case 0:
        robot_state.power.battery_mv = to_u16(hal_sensor_read(HAL_SENSOR_BATTERY_MV));
        robot_state.power.current_ma = to_u16(hal_sensor_read(HAL_SENSOR_CURRENT_MA));
        robot_state.power.mcu_temp_dc = to_i16(hal_sensor_read(HAL_SENSOR_MCU_TEMP_DC));
        break;
    case 1:
        robot_state.accel.x_mg = to_i16(hal_sensor_read(HAL_SENSOR_ACCEL_X_MG));
        robot_state.accel.y_mg = to_i16(hal_sensor_read(HAL_SENSOR_ACCEL_Y_MG));
        robot_state.accel.z_mg = to_i16(hal_sensor_read(HAL_SENSOR_ACCEL_Z_MG));
        break;
    default: {
        uint8_t r = to_u8(hal_sensor_read(HAL_SENSOR_COLOUR_R));
        uint8_t g = to_u8(hal_sensor_read(HAL_SENSOR_COLOUR_G));
        uint8_t b = to_u8(hal_sensor_read(HAL_SENSOR_COLOUR_B));
        int32_t clear = hal_sensor_read(HAL_SENSOR_COLOUR_CLEAR);
        uint8_t c = to_u8(clear);
        robot_state.colour.red = r;
        robot_state.colour.green = g;
        robot_state.colour.blue = b;
        robot_state.colour.clear = c;
        /* no reading (the sensor does not answer): no colour, rather than black */
        robot_state.colour.detected = clear < 0 ? PB_COLOUR_UNKNOWN : sensors_classify(r, g, b, c);
        break;
    }
    }
    group = group >= 2u ? 0u : (uint8_t)(group + 1u); /* not % 3: a 16-bit division, 200 cycles a tick */
}
