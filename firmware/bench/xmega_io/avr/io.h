/**
 * \file io.h
 * <avr/io.h> for timing the robot's HAL on the ATmega1284 cycle bench: the ATxmega128A3's registers, as avr-libc's
 * device header lays them out (the Makefile's host copy of it), in a RAM array of the ATmega. Register accesses stay
 * LDS/STS of fixed addresses, as on the XMEGA, so an ISR's cycles are its own; nothing acts on them.
 */
#ifndef BENCH_XMEGA_IO_H
#define BENCH_XMEGA_IO_H

#include <stdint.h>

extern uint8_t bench_xmega_io[0x1000];

typedef volatile uint8_t xm_reg8;
#define XM_IO(addr) ((void *)(bench_xmega_io + (addr)))
#define _SFR_MEM8(addr) (*(volatile uint8_t *)XM_IO(addr))
#define _SFR_MEM16(addr) (*(volatile uint16_t *)XM_IO(addr))
#define _SFR_MEM32(addr) (*(volatile uint32_t *)XM_IO(addr))
#define _SFR_IO8(addr) _SFR_MEM8(addr)
#define _VECTOR(N) __vector_##N /* the ATmega1284 bench enables none of its own */
/* avr-libc's unions of a 16/32-bit register and its bytes. */
#define _WORDREGISTER(regname) _WORDREGISTER_UNION(regname)
#define _DWORDREGISTER(regname) _DWORDREGISTER_UNION(regname)
typedef volatile uint16_t xm_reg16;
typedef volatile uint32_t xm_reg32;

#define _AVR_IO_H_
#include "avr/iox128a3_host.h"
#include "avr/xmega.h"

#endif
