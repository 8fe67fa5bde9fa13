/**
 * \file model_internal.h
 * What the parts of the XMEGA model share: peripherals hook address ranges of the register file, announce their
 * next event in time and their interrupt sources; the core (model.c) runs time and the interrupt controller.
 */
#ifndef MODEL_INTERNAL_H
#define MODEL_INTERNAL_H

#include <stdarg.h>
#include <stdio.h>

#include "avr/io.h" /* C view: register names, bit masks and vector numbers over xm_io[] without side effects */
#include "xmega_model.h"

#define XM_NEVER UINT64_MAX

typedef struct xm_periph {
    uint16_t base, size;
    /* NULL: the register file is plain memory there */
    uint8_t (*read)(struct xm_periph *p, uint16_t off);
    void (*write)(struct xm_periph *p, uint16_t off, uint8_t v);
    /* when the peripheral next acts on its own (XM_NEVER: not before a register access), and that action */
    uint64_t (*next_event)(struct xm_periph *p);
    void (*event)(struct xm_periph *p);
} xm_periph_t;

/** Adds a peripheral (at power-on; it stays until the next power-on). */
void xm_attach(xm_periph_t *p);

/** An interrupt source: level() returns 0 when it does not request, else its level (1 LO, 2 MED, 3 HI);
 *  ack() is what executing its vector clears (NULL: nothing, the flag is cleared by an access). */
typedef uint8_t (*xm_level_fn)(void *ctx, uint8_t which);
typedef void (*xm_ack_fn)(void *ctx, uint8_t which);
void xm_irq_source(uint8_t vector, xm_level_fn level, xm_ack_fn ack, void *ctx, uint8_t which);

/** The level field of an INTCTRL register at bit `shift` (0 off, 1 LO, 2 MED, 3 HI). */
static inline uint8_t xm_level_at(uint8_t reg, uint8_t shift)
{
    return (uint8_t)((reg >> shift) & 3u);
}

/** Raw 16-bit register values (no side effects). */
static inline uint16_t xm_get16(uint16_t addr)
{
    return (uint16_t)(xm_io[addr] | xm_io[addr + 1u] << 8);
}
static inline void xm_set16(uint16_t addr, uint16_t v)
{
    xm_io[addr] = (uint8_t)v;
    xm_io[addr + 1u] = (uint8_t)(v >> 8);
}

/** Tells the core that a peripheral's next event or interrupt request may have moved earlier (a stimulus came;
 *  writes and events tell it themselves). */
void xm_changed(void);
/** The current time (cycles) inside the model. */
extern uint64_t xm_time;
/** True when a write to a CCP-protected register is allowed now (the CCP signature came just before). */
bool xm_ccp_open(void);
void xm_misuse(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/** A reset (registers to their reset state) or avr-libc's jump to 0; does not return when a handler takes over. */
void xm_restart(uint8_t why);
/** The CPU clock in Hz as CLK selects it (2 MHz after reset, 32 MHz once the HAL switches). */
double xm_cpu_hz(void);

/* ---- pins ---- */
void xm_pin_use(char port, uint8_t pin, uint8_t use);
/** The output level a port drives on a pin (false when it is an input). */
bool xm_port_drives_high(char port, uint8_t pin);

/* ---- the parts, powered on in this order by xm_power_on() and by every reset; xm_cold() tells them apart
 *      (a reset keeps what is outside the chip: analog inputs, the colour sensor, the EEPROM's contents) ---- */
bool xm_cold(void);
void xm_port_power_on(void);
void xm_tc_power_on(void);
void xm_usart_power_on(void);
void xm_adc_power_on(void);
void xm_twi_power_on(void);
void xm_nvm_power_on(void);
/** The production signature row (the model's calibration values), as LPM reads it. */
uint8_t xm_prod_signature(uint16_t addr);
/** The analog value of ADC inputs for other parts: volts on a pin of port A or B, the ADC's VCC. */
double xm_analog_volts(char port, uint8_t pin);
double xm_vcc(void);
/** TCD1 CCB's output as a carrier duty in percent of 50 % (0 when off), for the IR transmitter. */
uint8_t xm_tc_carrier_duty(void);

#endif
