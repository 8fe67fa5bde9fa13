#include <string.h>

#include "core/data.h"
#include "harness.h"
#include "modules/proximity.h"
#include "world.h"

static void heard(int side, int sender, int led, int power, int len, uint32_t lo, uint32_t hi)
{
    sim_ir_rx(side, sender, led, power, len, (int32_t)lo, (int32_t)hi);
}

static void beacons_cycle_leds_and_powers(void)
{
    world_reset(9);
    world_run_ms(10 * settings.proximity.beacon_period_ms + 20);
    CHECK(world.ir_count >= 36, "%d messages in 10 beacons", world.ir_count);
    int leds[4] = {0}, powers[101] = {0};
    for (int i = 0; i < world.ir_count; i++) {
        CHECK(world.ir[i].sender == 9 && world.ir[i].len == 0, "message %d carries id 9", i);
        leds[world.ir[i].led & 3]++;
        if (world.ir[i].power >= 0 && world.ir[i].power <= 100)
            powers[world.ir[i].power]++;
    }
    CHECK(leds[0] && leds[1] && leds[2] && leds[3], "all four LEDs");
    CHECK(powers[100] && powers[50] && powers[25], "powers 100/50/25: %d %d %d", powers[100], powers[50], powers[25]);
    settings.proximity.ir_power = 0;
    int before = world.ir_count;
    world_run_ms(200);
    CHECK(world.ir_count == before, "power 0 turns the beacon off");
}

static void another_robot_is_reported_with_orientation_and_distance(void)
{
    world_reset(1);
    heard(0, 7, 2, 100, 0, 0, 0);
    world_run_ms(2);
    const pb_proximity_side_t *f = &robot_state.proximity.front;
    CHECK(f->flags == 0x02 && f->robot_id == 7 && f->robot_led == 2 && f->distance == PB_DISTANCE_CLASS_FAR,
          "far: flags %u id %u led %u dist %u", f->flags, f->robot_id, f->robot_led, f->distance);
    heard(0, 7, 1, 50, 0, 0, 0);
    world_run_ms(2);
    CHECK(f->distance == PB_DISTANCE_CLASS_MID && f->robot_led == 1, "mid via LED 1");
    heard(0, 7, 1, 25, 0, 0, 0);
    world_run_ms(2);
    CHECK(f->distance == PB_DISTANCE_CLASS_NEAR, "near");
    CHECK(robot_state.proximity.rear.flags == 0, "rear saw nothing");
    world_run_ms(settings.proximity.hold_ms + 5);
    CHECK(f->flags == 0 && f->robot_id == 0 && f->distance == PB_DISTANCE_CLASS_NONE, "forgotten after hold_ms");
}

static void own_reflection_is_an_obstacle(void)
{
    world_reset(4);
    heard(1, 4, 0, 100, 0, 0, 0);
    world_run_ms(2);
    CHECK(robot_state.proximity.rear.flags == 0x01 && robot_state.proximity.rear.robot_id == 0, "obstacle at rear");
    world_run_ms(settings.proximity.hold_ms + 5);
    CHECK(robot_state.proximity.rear.flags == 0, "cleared");
}

static void payloads_travel_both_ways(void)
{
    world_reset(3);
    uint8_t cmd[9] = {60, 'h', 'e', 'l', 'l', 'o', '!', 0xC0, 0xDB};
    host_send(PB_PKT_IR_SEND, 5, cmd, 9);
    world_run_ms(2 * settings.proximity.beacon_period_ms + 20);
    host_collect();
    CHECK(host_find(PB_PKT_ACK, 0) != NULL, "acked");
    int with_payload = 0;
    for (int i = 0; i < world.ir_count; i++)
        if (world.ir[i].len == 8) {
            with_payload++;
            CHECK(world.ir[i].power == 60 && world.ir[i].lo == 0x6C6C6568u && world.ir[i].hi == 0xDBC0216Fu,
                  "payload bytes %08x %08x", world.ir[i].lo, world.ir[i].hi);
        }
    CHECK(with_payload == 4, "sent once from each LED: %d", with_payload);
    uint8_t bad[2] = {0, 1};
    host_send(PB_PKT_IR_SEND, 6, bad, 2);
    world_run_ms(2);
    host_collect();
    CHECK(host_find(PB_PKT_ERROR, 0) && host_find(PB_PKT_ERROR, 0)->payload[0] == PB_ERROR_CODE_BAD_ARGUMENT,
          "power 0 refused");

    host_clear();
    heard(0, 8, 3, 50, 3, 0x00636261u, 0); /* "abc" from robot 8, from all LEDs of one beacon */
    heard(0, 8, 0, 50, 3, 0x00636261u, 0);
    world_run_ms(2);
    host_collect();
    CHECK(host_count(PB_PKT_IR_RECEIVED) == 1, "forwarded once: %d", host_count(PB_PKT_IR_RECEIVED));
    const host_frame_t *f = host_find(PB_PKT_IR_RECEIVED, 0);
    CHECK(f && f->len == 7 && f->payload[0] == 8 && f->payload[1] == 0 && f->payload[2] == 3 && f->payload[3] == 50 &&
              memcmp(f->payload + 4, "abc", 3) == 0, "ir_received fields");
}

void suite_proximity(void)
{
    RUN(beacons_cycle_leds_and_powers);
    RUN(another_robot_is_reported_with_orientation_and_distance);
    RUN(own_reflection_is_an_obstacle);
    RUN(payloads_travel_both_ways);
}
