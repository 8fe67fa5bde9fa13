/** \file main.c  The robot's HAL on the XMEGA model: every suite (or those named as arguments), then
 *  "N passed, N failed". */
#include <stdbool.h>
#include <string.h>

#include "xm_tests.h"

static const struct {
    const char *name;
    void (*run)(void);
} suites[] = {
    {"time", suite_xm_time},
    {"ir", suite_xm_ir},
    {"colour", suite_xm_colour},
    {"encoder", suite_xm_encoder},
    {"analog", suite_xm_analog},
    {"recovery", suite_xm_recovery},
    {"uart", suite_xm_uart},
    {"load", suite_xm_load},
};

int main(int argc, char **argv)
{
    for (size_t i = 0; i < sizeof suites / sizeof suites[0]; i++) {
        bool named = argc < 2;
        for (int a = 1; a < argc; a++)
            named = named || strcmp(argv[a], suites[i].name) == 0;
        if (named)
            suites[i].run();
    }
    return harness_report();
}
