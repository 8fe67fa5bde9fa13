/**
 * \file bt_live.h
 * A robot's UART wired to a Bluetooth controller reached as H4 over TCP on loopback, in real time: the bytes each way
 * at the 115200 Bd wire's pace (12 a millisecond) and one main loop tick a millisecond. Used by `bt_tests --live`
 * (the stack alone, tests/bt_wire.c) and by bt_robot (the whole firmware), which tests/bt_e2e.py runs.
 */
#ifndef BT_LIVE_H
#define BT_LIVE_H

#include <stdint.h>

typedef struct {
    void (*rx)(const uint8_t *p, uint16_t n); /**< bytes from the controller into the robot's UART */
    void (*tick)(void);                       /**< one millisecond of the robot */
    int (*tx)(uint8_t *p, int max);           /**< takes up to `max` bytes the robot sent; \return how many */
} bt_live_robot_t;

/** Connects to 127.0.0.1:`port` and runs the robot for `seconds` or until the controller goes away.
 *  \return 0, or 1 when the connection failed. */
int bt_live_run(int port, int seconds, const bt_live_robot_t *robot);

#endif
