#include "core/data.h"
#include "drivers/sensors.h"
#include "harness.h"
#include "world.h"

static void colours_are_classified(void)
{
    CHECK(sensors_classify(230, 228, 225, 240) == PB_COLOUR_WHITE, "white");
    CHECK(sensors_classify(20, 22, 25, 20) == PB_COLOUR_BLACK, "black");
    CHECK(sensors_classify(200, 40, 40, 100) == PB_COLOUR_RED, "red");
    CHECK(sensors_classify(40, 60, 200, 100) == PB_COLOUR_BLUE, "blue");
    CHECK(sensors_classify(40, 180, 60, 100) == PB_COLOUR_GREEN, "green");
    CHECK(sensors_classify(110, 105, 100, 110) == PB_COLOUR_UNKNOWN, "grey");
    CHECK(sensors_classify(0, 0, 0, 0) == PB_COLOUR_BLACK && sensors_classify(255, 255, 255, 255) == PB_COLOUR_WHITE,
          "extremes");
}

static void sensor_values_reach_the_state(void)
{
    world_reset(1);
    world.sensors[SIM_SENSOR_BATTERY_MV] = 3750;
    world.sensors[SIM_SENSOR_CURRENT_MA] = 180;
    world.sensors[SIM_SENSOR_MCU_TEMP_DC] = -55;
    world.sensors[SIM_SENSOR_ACCEL_X_MG] = 100000; /* out of range: clamped by the HAL's sensor model */
    world.sensors[SIM_SENSOR_ACCEL_Y_MG] = -20;
    world.sensors[SIM_SENSOR_ACCEL_Z_MG] = 990;
    world.colour[0] = 200; world.colour[1] = 40; world.colour[2] = 40; world.colour[3] = 999;
    world_run_ms(10);
    CHECK(robot_state.power.battery_mv == 3750 && robot_state.power.current_ma == 180 &&
              robot_state.power.mcu_temp_dc == -55, "power");
    CHECK(robot_state.accel.x_mg == 16000 && robot_state.accel.y_mg == -20 && robot_state.accel.z_mg == 990,
          "accel, x clamped to the accelerometer's range: %d", robot_state.accel.x_mg);
    CHECK(robot_state.colour.red == 200 && robot_state.colour.clear == 255 &&
              robot_state.colour.detected == PB_COLOUR_RED, "colour");
}

void suite_sensors(void)
{
    RUN(colours_are_classified);
    RUN(sensor_values_reach_the_state);
}
