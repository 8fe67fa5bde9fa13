/** \file bench.h  Shared between the bench HAL and the bench driver. */
#ifndef BENCH_H
#define BENCH_H

#include <stdint.h>

extern uint32_t bench_us;
extern int16_t bench_line_spot;
/** Puts the line under `spot` (0..7) for the synthetic line sensor readings. */
void bench_set_line_spot(int16_t spot);
/** Calls scheduler_isr() for every armed channel that is due at bench_us. */
void bench_fire_due(void);

#endif
