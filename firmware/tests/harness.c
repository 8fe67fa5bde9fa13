#include "harness.h"

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
