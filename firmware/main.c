/**
 * \file main.c
 * Entry point on the robot: the main loop sleeps until an interrupt, then runs a tick when one is due.
 */
#include "app.h"

int main(void)
{
    app_init();
    for (;;) {
        if (!app_poll())
            app_idle();
    }
}
