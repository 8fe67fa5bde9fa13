/** \file sleep.h  For the cycle bench (never sleeps). */
#ifndef BENCH_XMEGA_SLEEP_H
#define BENCH_XMEGA_SLEEP_H
#define sleep_cpu() __asm__ __volatile__("sleep")
#endif
