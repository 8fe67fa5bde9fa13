/** \file wdt.h  For the cycle bench. */
#ifndef BENCH_XMEGA_WDT_H
#define BENCH_XMEGA_WDT_H
#define wdt_reset() __asm__ __volatile__("wdr")
#endif
