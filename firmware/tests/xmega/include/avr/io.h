/**
 * \file io.h
 * <avr/io.h> for the host model of the ATxmega128A3 (tests/xmega): the device header of avr-libc, with its
 * register file placed in host memory (xm_io[], at the device's own addresses) instead of at address 0.
 *
 * The Makefile makes avr/iox128a3_host.h from avr-libc's avr/iox128a3.h with device_header.sed: the register
 * types (register8_t, register16_t, register32_t) become the types below, and each peripheral's address
 * `(*(PORT_t *) 0x0600)` becomes `(*(PORT_t *) XM_IO(0x0600))`. Every struct, offset, bit mask and vector
 * number is avr-libc's.
 *
 * In C++ (the HAL is compiled as C++ by hal_xmega_host.cc) a register is a one-byte class whose reads and
 * writes call the model (xm_read8(), xm_write8()), so the model sees every access in program order, 16-bit
 * registers as two byte accesses, low byte first, as avr-gcc emits them (the XMEGA TEMP register depends on
 * it). In C (the model and the tests) a register is a plain byte: a view of the register file without side
 * effects.
 */
#ifndef XM_AVR_IO_H
#define XM_AVR_IO_H

#include <stdint.h>

#include "xmega_model.h"

#ifdef __cplusplus
struct xm_reg8 {
    uint8_t raw_;
    uint16_t addr() const { return (uint16_t)(&raw_ - xm_io); }
    operator uint8_t() const { return xm_read8(addr()); }
    /* An assignment's value is what was written (avr-gcc does not read a volatile register back). */
    uint8_t operator=(uint8_t v) { xm_write8(addr(), v); return v; }
    uint8_t operator=(const xm_reg8 &o) { return *this = (uint8_t)o; }
    uint8_t operator|=(uint8_t v) { return *this = (uint8_t)(*this | v); }
    uint8_t operator&=(uint8_t v) { return *this = (uint8_t)(*this & v); }
    uint8_t operator^=(uint8_t v) { return *this = (uint8_t)(*this ^ v); }
};
struct xm_reg16 {
    uint8_t raw_[2];
    uint16_t addr() const { return (uint16_t)(&raw_[0] - xm_io); }
    operator uint16_t() const
    {
        uint8_t lo = xm_read8(addr());
        return (uint16_t)(lo | xm_read8((uint16_t)(addr() + 1u)) << 8);
    }
    uint16_t operator=(uint16_t v)
    {
        xm_write8(addr(), (uint8_t)v);
        xm_write8((uint16_t)(addr() + 1u), (uint8_t)(v >> 8));
        return v;
    }
    uint16_t operator=(const xm_reg16 &o) { return *this = (uint16_t)o; }
};
struct xm_reg32 {
    uint8_t raw_[4];
    uint16_t addr() const { return (uint16_t)(&raw_[0] - xm_io); }
    operator uint32_t() const
    {
        uint32_t v = 0;
        for (uint8_t i = 0; i < 4; i++)
            v |= (uint32_t)xm_read8((uint16_t)(addr() + i)) << (8 * i);
        return v;
    }
    uint32_t operator=(uint32_t v)
    {
        for (uint8_t i = 0; i < 4; i++)
            xm_write8((uint16_t)(addr() + i), (uint8_t)(v >> (8 * i)));
        return v;
    }
};
static_assert(sizeof(xm_reg8) == 1 && sizeof(xm_reg16) == 2 && sizeof(xm_reg32) == 4, "registers keep their size");
#else
typedef uint8_t xm_reg8;
typedef struct { uint8_t b[2]; } xm_reg16;
typedef struct { uint8_t b[4]; } xm_reg32;
#endif

#define XM_IO(addr) ((void *)(xm_io + (addr)))
#define _SFR_MEM8(addr) (*(register8_t *)XM_IO(addr))
#define _SFR_MEM16(addr) (*(register16_t *)XM_IO(addr))
#define _SFR_MEM32(addr) (*(register32_t *)XM_IO(addr))
#define _SFR_IO8(addr) _SFR_MEM8(addr)
#define _SFR_IO16(addr) _SFR_MEM16(addr)
#define _VECTOR(N) __vector_##N
/* A 16/32-bit register: in C avr-libc's union with its byte halves (CNTL, CNTH); in C++ the register type alone
 * (the same layout), which reads and writes its bytes in AVR order. */
#ifdef __cplusplus
#define _WORDREGISTER(regname) register16_t regname
#define _DWORDREGISTER(regname) register32_t regname
#else
#define _WORDREGISTER(regname) _WORDREGISTER_UNION(regname)
#define _DWORDREGISTER(regname) _DWORDREGISTER_UNION(regname)
#endif

#define _AVR_IO_H_
#include "avr/iox128a3_host.h"

#include "avr/xmega.h"

#endif
