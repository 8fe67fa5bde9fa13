/**
 * \file bt_robot.c
 * The HCI build of the whole firmware on the host (hal/sim and the tests' world), its UART wired to a Bluetooth
 * controller reached as H4 over TCP, in real time (tests/bt_live.c): `bt_robot PORT SECONDS`. tests/bt_e2e.py --firmware runs it
 * against Bumble's virtual controllers and talks the PocketBot protocol to it over RFCOMM and the framed channel.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bt_live.h"
#include "core/data.h"
#include "world.h"

static void rx(const uint8_t *p, uint16_t n)
{
    host_send_raw(p, n);
}

static void tick(void)
{
    world_run_ms(1);
}

static int tx(uint8_t *p, int max)
{
    int32_t n = sim_uart_tx_take(max);
    memcpy(p, sim_host_tx_buffer(), (size_t)n);
    return n;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: bt_robot PORT SECONDS\n");
        return 2;
    }
    world_reset(7);
    world.link_bytes_per_ms = 0; /* the UART is the controller's, not the world's host */
    static const bt_live_robot_t robot = {rx, tick, tx};
    if (bt_live_run(atoi(argv[1]), atoi(argv[2]), &robot))
        return 1;
    printf("robot: wire %u timeouts %u resets %u dropped %u tx_dropped %u\n", robot_state.errors.bt_wire,
           robot_state.errors.bt_timeouts, robot_state.errors.bt_resets, robot_state.errors.bt_dropped,
           robot_state.errors.tx_dropped);
    return 0;
}
