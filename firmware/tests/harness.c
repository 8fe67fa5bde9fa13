#include "harness.h"

#include <string.h>

int harness_failed_checks;
static int passed, failed;

void harness_run(const char *name, void (*fn)(void))
{
    int before = harness_failed_checks;
    fn();
    if (harness_failed_checks == before) {
        passed++;
    } else {
        failed++;
        printf("FAILED %s\n", name);
    }
}

int harness_report(void)
{
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}

#ifndef HARNESS_NO_MAIN
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
#endif
