/** \file main.c  The host unit tests: every suite, then "N passed, N failed". */
#include <string.h>

#include "harness.h"

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-corpus") == 0) {
        golden_write_corpus(argv[2]);
        return 0;
    }
    suite_frame();
    suite_slip();
    suite_golden();
    suite_settings();
    suite_pid();
    suite_comm();
    suite_speed();
    suite_locomotion();
    suite_line();
    suite_proximity();
    suite_sensors();
    suite_debug();
    suite_scheduler();
    suite_track();
    suite_links();
    return harness_report();
}
