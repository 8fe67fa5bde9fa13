/** \file bench.h  Shared between the bench HAL and the bench driver. */
#ifndef BENCH_H
#define BENCH_H

#include <stdbool.h>
#include <stdint.h>

extern uint32_t bench_us;
extern int16_t bench_line_spot;
/** Puts the line under `spot` (0..7) for the synthetic line sensor readings. */
void bench_set_line_spot(int16_t spot);
/** Calls scheduler_isr() for every armed channel that is due at bench_us. */
void bench_fire_due(void);

/* The HCI build's controller and host (bench_bt.c). */
/** One ms of the H4 wire: the firmware's bytes taken and answered, the controller's bytes delivered. */
void bench_bt_wire(void);
/** \return true when the controller has nothing left to deliver. */
bool bench_bt_idle(void);
/** A host connects and opens RFCOMM's data channel (the bench runs meanwhile). */
void bench_bt_connect(void);
/** A host packet (SLIP bytes) in an RFCOMM data frame. */
void bench_bt_host_packet(const uint8_t *slip, uint8_t n);
/** Runs `ticks` bench ticks without timing them (bench_main.c). */
void bench_bt_run(uint16_t ticks);

#endif
