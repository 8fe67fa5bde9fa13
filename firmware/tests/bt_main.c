/**
 * \file bt_main.c
 * The Bluetooth stack's test program: its suites (`N passed, N failed`), `--live PORT SECONDS` (bt_wire.h), or
 * `--write-corpus DIR` (seeds for fuzz_bt from the recorded session).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bt_trace.h"
#include "harness.h"

/* Seeds for fuzz_bt: each packet the controller sent in the recorded session, as a raw-bytes record. */
static void write_corpus(const char *dir)
{
    const uint8_t *p = bt_trace_in;
    for (int i = 0; i < BT_TRACE_IN_COUNT; i++) {
        int n = p[2] | p[3] << 8;
        char path[512];
        snprintf(path, sizeof path, "%s/trace-%03d", dir, i);
        FILE *f = fopen(path, "wb");
        if (f) {
            uint8_t head[2] = {0, (uint8_t)(n > 255 ? 255 : n)};
            fwrite(head, 1, 2, f);
            fwrite(p + 4, 1, head[1], f);
            fclose(f);
        }
        p += 4 + n;
    }
}

int wire_live(int port, int seconds);

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-corpus") == 0) {
        write_corpus(argv[2]);
        return 0;
    }
    if (argc == 4 && strcmp(argv[1], "--live") == 0)
        return wire_live(atoi(argv[2]), atoi(argv[3]));
    suite_bt_h4();
    suite_bt_hci();
    suite_bt_l2cap();
    suite_bt_sdp();
    suite_bt_rfcomm();
    return harness_report();
}
