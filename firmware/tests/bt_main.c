/**
 * \file bt_main.c
 * The Bluetooth stack's test program: its suites (`N passed, N failed`), or `--live PORT SECONDS` (bt_wire.h).
 */
#include <stdlib.h>
#include <string.h>

#include "harness.h"

int wire_live(int port, int seconds);

int main(int argc, char **argv)
{
    if (argc == 4 && strcmp(argv[1], "--live") == 0)
        return wire_live(atoi(argv[2]), atoi(argv[3]));
    suite_bt_h4();
    suite_bt_hci();
    suite_bt_l2cap();
    suite_bt_sdp();
    suite_bt_rfcomm();
    return harness_report();
}
