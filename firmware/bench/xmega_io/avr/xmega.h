/** \file xmega.h  For the cycle bench: the CCP signature, then the register (two stores, as on the XMEGA). */
#ifndef BENCH_XMEGA_XMEGA_H
#define BENCH_XMEGA_XMEGA_H
#define _PROTECTED_WRITE(reg, value) do { CCP = 0xD8; (reg) = (uint8_t)(value); } while (0)
#endif
