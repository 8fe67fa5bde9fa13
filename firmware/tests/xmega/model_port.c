/**
 * \file model_port.c
 * Ports A..F of the XMEGA model: DIR and OUT with their SET/CLR/TGL strobes, IN, and a record of what each pin was
 * used for (the other parts report their uses through xm_pin_use()).
 */
#include <string.h>

#include "model_internal.h"

#define PORTS 6u /* A..F, 0x0600 + 0x20 * n */

static xm_periph_t ports;
static uint8_t uses[PORTS][8];
static uint8_t ext_level[PORTS]; /* what drives input pins from outside */

static int port_index(char port)
{
    return port >= 'A' && port < (char)('A' + PORTS) ? port - 'A' : -1;
}

void xm_pin_use(char port, uint8_t pin, uint8_t use)
{
    int i = port_index(port);
    if (i >= 0 && pin < 8)
        uses[i][pin] |= use;
}

static void note_outputs(uint8_t i)
{
    uint8_t dir = xm_io[0x600 + 0x20u * i];
    for (uint8_t pin = 0; pin < 8; pin++)
        if (dir & (1u << pin))
            uses[i][pin] |= XM_USE_GPIO_OUT;
}

static uint8_t port_read(xm_periph_t *p, uint16_t off)
{
    (void)p;
    uint8_t i = (uint8_t)(off / 0x20u), r = (uint8_t)(off % 0x20u);
    uint16_t base = (uint16_t)(0x600 + 0x20u * i);
    if (i >= PORTS)
        return xm_io[base + r];
    if (r >= 0x01 && r <= 0x03)
        return xm_io[base + 0x00]; /* the DIR strobes read DIR */
    if (r >= 0x05 && r <= 0x07)
        return xm_io[base + 0x04]; /* the OUT strobes read OUT */
    if (r == 0x08) {
        uint8_t dir = xm_io[base + 0x00];
        return (uint8_t)((xm_io[base + 0x04] & dir) | (ext_level[i] & ~dir));
    }
    return xm_io[base + r];
}

static void port_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    (void)p;
    uint8_t i = (uint8_t)(off / 0x20u), r = (uint8_t)(off % 0x20u);
    uint16_t base = (uint16_t)(0x600 + 0x20u * i);
    uint8_t *dir = &xm_io[base + 0x00], *out = &xm_io[base + 0x04];
    switch (r) {
    case 0x00: *dir = v; break;
    case 0x01: *dir |= v; break;
    case 0x02: *dir &= (uint8_t)~v; break;
    case 0x03: *dir ^= v; break;
    case 0x04: *out = v; break;
    case 0x05: *out |= v; break;
    case 0x06: *out &= (uint8_t)~v; break;
    case 0x07: *out ^= v; break;
    case 0x08: break; /* IN is read-only */
    case 0x0C: xm_io[base + r] &= (uint8_t)~v; break; /* INTFLAGS: a 1 clears */
    default: xm_io[base + r] = v; break;
    }
    if (i < PORTS)
        note_outputs(i);
}

void xm_port_power_on(void)
{
    if (xm_cold())
        memset(ext_level, 0, sizeof ext_level);
    memset(uses, 0, sizeof uses); /* a reset makes every pin an input again */
    ports = (xm_periph_t){.base = 0x600, .size = 0x20u * PORTS, .read = port_read, .write = port_write};
    xm_attach(&ports);
}

uint8_t xm_pin_uses(char port, uint8_t pin)
{
    int i = port_index(port);
    return i >= 0 && pin < 8 ? uses[i][pin] : 0;
}

const char *xm_pin_use_names(uint8_t u)
{
    static char s[96];
    static const char *const names[] = {"output", "analog input", "USART RX", "USART TX", "TWI", "timer output",
                                        "ADC reference"};
    s[0] = 0;
    for (uint8_t b = 0; b < 7; b++)
        if (u & (1u << b)) {
            if (s[0])
                strcat(s, " + ");
            strcat(s, names[b]);
        }
    return s[0] ? s : "unused";
}

void xm_pin_set(char port, uint8_t pin, bool high)
{
    int i = port_index(port);
    if (i < 0 || pin > 7)
        return;
    if (high)
        ext_level[i] |= (uint8_t)(1u << pin);
    else
        ext_level[i] &= (uint8_t)~(1u << pin);
}

bool xm_port_drives_high(char port, uint8_t pin)
{
    int i = port_index(port);
    if (i < 0 || pin > 7)
        return false;
    uint16_t base = (uint16_t)(0x600 + 0x20u * (unsigned)i);
    return (xm_io[base] & xm_io[base + 0x04] & (1u << pin)) != 0;
}

bool xm_pin_level(char port, uint8_t pin)
{
    int i = port_index(port);
    if (i < 0 || pin > 7)
        return false;
    uint16_t base = (uint16_t)(0x600 + 0x20u * (unsigned)i);
    uint8_t dir = xm_io[base];
    return ((dir & xm_io[base + 0x04]) | (~dir & ext_level[i])) & (1u << pin);
}
