/** \file pgmspace.h  For the cycle bench: the signature row is not there; LPM reads flash instead. */
#ifndef BENCH_XMEGA_PGMSPACE_H
#define BENCH_XMEGA_PGMSPACE_H
#include <stdint.h>
#define pgm_read_byte(addr) __extension__({ uint8_t r_; uint16_t a_ = (uint16_t)(addr); \
    __asm__ __volatile__("lpm %0, Z" : "=r"(r_) : "z"(a_)); r_; })
#endif
