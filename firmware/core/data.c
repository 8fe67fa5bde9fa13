#include "data.h"

pb_settings_t settings;
uint8_t settings_generation;
pb_robot_state_t robot_state;
