/**
 * \file model_twi.c
 * The TWIC master of the model and a TCS3472 colour sensor on its bus (7-bit address 0x29).
 *
 * Master: writing ADDR sends a START (a repeated START while the master owns the bus) and the address byte; a
 * write address sets WIF with the slave's ACK in RXACK; a read address that is ACKed receives a byte (RIF), one
 * that is NACKed sets WIF with RXACK. Writing DATA sends a byte (WIF, RXACK); CMD RECVTRANS sends ACKACT and
 * receives the next byte; CMD STOP sends ACKACT and a STOP (the bus is idle again). Writing ADDR, DATA or a command,
 * or reading DATA, clears RIF and WIF. Bus times follow SCL = f / (2 (5 + BAUD)): 9 SCL periods a byte, one for a
 * START or STOP. Not modelled: other masters (arbitration, bus errors), timeouts, smart mode, the slave module.
 *
 * TCS3472: a command byte (CMD bit, type: repeated byte / auto-increment / special function, register address)
 * sets the register pointer; further written bytes go to registers; reads come from the pointer. After PON it
 * warms up for 2.4 ms; with AEN it integrates for (256 - ATIME) cycles of 2.4 ms, then the four counts are
 * light x gain x cycles, at most 1024 per cycle (and 65535), and STATUS.AVALID is set. Reading a channel's low
 * byte latches its high byte. ID reads 0x44.
 */
#include <string.h>

#include "model_internal.h"

#define TCS_ADDR 0x29u
#define CYCLE XM_US(2400)

enum { BUS_IDLE, BUS_ADDR, BUS_WRITE, BUS_READ, BUS_STOP };

static struct {
    xm_periph_t p;
    uint8_t busy;        /* what the bus is doing until `done_at` */
    uint64_t done_at;
    uint8_t addr_byte;   /* the last address byte sent */
    bool acked;
    bool addr_pending;   /* ADDR written during our STOP: the START follows it */
} tw;

static struct {
    bool present;
    uint16_t light[4];
    uint8_t r[0x20];
    uint8_t ptr, type;
    bool command_next;   /* the next written byte is a command */
    uint64_t cycle_end;  /* end of the current warm-up or integration cycle */
    bool integrating;    /* cycle_end ends an integration (not the warm-up) */
    uint8_t shadow;      /* latched high byte */
    xm_tcs_access_t log[4096];
    uint32_t log_n, transactions;
} tcs;

/* ---- the sensor ---- */

static void tcs_log(bool write, uint8_t reg, uint8_t value)
{
    if (tcs.log_n < sizeof tcs.log / sizeof tcs.log[0])
        tcs.log[tcs.log_n++] = (xm_tcs_access_t){.at = xm_time, .write = write, .reg = reg, .value = value};
}

static uint8_t tcs_cycles(void)
{
    return (uint8_t)(256u - tcs.r[0x01]);
}

static void tcs_integrate_end(void)
{
    static const uint8_t gain[4] = {1, 4, 16, 60};
    uint32_t max = 1024u * tcs_cycles();
    if (max > 65535u)
        max = 65535u;
    for (uint8_t c = 0; c < 4; c++) {
        uint32_t v = (uint32_t)tcs.light[c] * gain[tcs.r[0x0F] & 3u] * tcs_cycles();
        if (v > max)
            v = max;
        tcs.r[0x14 + 2 * c] = (uint8_t)v;
        tcs.r[0x15 + 2 * c] = (uint8_t)(v >> 8);
    }
    tcs.r[0x13] |= 0x01; /* AVALID */
}

static void tcs_write_reg(uint8_t reg, uint8_t v)
{
    tcs_log(true, reg, v);
    if (reg >= 0x12)
        return; /* ID, STATUS and the counts are read-only */
    uint8_t was = tcs.r[0x00];
    tcs.r[reg] = v;
    if (reg == 0x00 && (v & 0x01) && !(was & 0x01)) { /* power on: warm-up */
        tcs.cycle_end = xm_time + CYCLE;
        tcs.integrating = false;
    }
    if (reg == 0x00 && !(v & 0x01))
        tcs.cycle_end = XM_NEVER;
    if (reg == 0x00 && !(v & 0x02))
        tcs.integrating = false;
}

static uint8_t tcs_read_reg(uint8_t reg)
{
    uint8_t v;
    if (reg >= 0x14 && reg <= 0x1B && (reg & 1u)) {
        v = tcs.shadow;
    } else {
        v = tcs.r[reg & 0x1Fu];
        if (reg >= 0x14 && reg <= 0x1B)
            tcs.shadow = tcs.r[reg + 1u];
    }
    tcs_log(false, reg, v);
    return v;
}

static void tcs_byte_written(uint8_t v)
{
    if (tcs.command_next) {
        tcs.command_next = false;
        if (!(v & 0x80)) {
            xm_misuse("TCS3472: a command byte without the CMD bit (0x%02x)", v);
            return;
        }
        tcs.type = (uint8_t)((v >> 5) & 3u);
        if (tcs.type == 3) { /* special function: clear the interrupt */
            tcs.r[0x13] &= (uint8_t)~0x10u;
            return;
        }
        tcs.ptr = v & 0x1Fu;
        return;
    }
    tcs_write_reg(tcs.ptr, v);
    if (tcs.type == 1)
        tcs.ptr = (uint8_t)((tcs.ptr + 1u) & 0x1Fu);
}

static uint8_t tcs_byte_read(void)
{
    uint8_t v = tcs_read_reg(tcs.ptr);
    if (tcs.type == 1)
        tcs.ptr = (uint8_t)((tcs.ptr + 1u) & 0x1Fu);
    return v;
}

/* ---- the master ---- */

static double scl_cycles(void)
{
    return 2.0 * (5.0 + TWIC.MASTER.BAUD) * (double)XM_HZ / xm_cpu_hz();
}

static void bus(uint8_t what, double scl_periods)
{
    tw.busy = what;
    tw.done_at = xm_time + (uint64_t)(scl_periods * scl_cycles() + 0.5);
}

static uint8_t bus_state(void)
{
    return TWIC.MASTER.STATUS & TWI_MASTER_BUSSTATE_gm;
}

static void set_status(uint8_t set, uint8_t clear)
{
    TWIC.MASTER.STATUS = (uint8_t)((TWIC.MASTER.STATUS & ~clear) | set);
}

static void clear_flags(void)
{
    set_status(0, TWI_MASTER_RIF_bm | TWI_MASTER_WIF_bm | TWI_MASTER_CLKHOLD_bm);
}

static bool can_act(const char *what)
{
    if (tw.busy != BUS_IDLE) {
        xm_misuse("TWI: %s while the bus is still busy with the last byte", what);
        return false;
    }
    return true;
}

static void send_address(void)
{
    uint8_t v = TWIC.MASTER.ADDR;
    if (bus_state() != TWI_MASTER_BUSSTATE_IDLE_gc && bus_state() != TWI_MASTER_BUSSTATE_OWNER_gc) {
        xm_misuse("TWI: ADDR written while the bus state is %u (not idle, not ours)", bus_state());
        return;
    }
    clear_flags();
    if (bus_state() == TWI_MASTER_BUSSTATE_IDLE_gc && (v >> 1) == TCS_ADDR)
        tcs.transactions++;
    set_status(TWI_MASTER_BUSSTATE_OWNER_gc, TWI_MASTER_BUSSTATE_gm);
    tw.addr_byte = v;
    tw.acked = tcs.present && (v >> 1) == TCS_ADDR;
    if (tw.acked && !(v & 1u))
        tcs.command_next = true;
    bus(BUS_ADDR, (tw.acked && (v & 1u)) ? 1.0 + 9.0 + 8.0 : 1.0 + 9.0);
}

static void twi_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    (void)p;
    switch (off) {
    case 0x04: { /* MASTER.STATUS: 1s clear flags, BUSSTATE may be forced to idle */
        uint8_t keep = TWIC.MASTER.STATUS & (uint8_t)~(v & (TWI_MASTER_RIF_bm | TWI_MASTER_WIF_bm |
                                                              TWI_MASTER_ARBLOST_bm | TWI_MASTER_BUSERR_bm));
        if ((v & TWI_MASTER_BUSSTATE_gm) == TWI_MASTER_BUSSTATE_IDLE_gc)
            keep = (uint8_t)((keep & ~TWI_MASTER_BUSSTATE_gm) | TWI_MASTER_BUSSTATE_IDLE_gc);
        TWIC.MASTER.STATUS = keep;
        return;
    }
    case 0x06: /* MASTER.ADDR: START (or repeated START) and the address byte */
        TWIC.MASTER.ADDR = v;
        if (!(TWIC.MASTER.CTRLA & TWI_MASTER_ENABLE_bm))
            return;
        if (tw.busy == BUS_STOP) { /* the master waits for its STOP to end */
            tw.addr_pending = true;
            return;
        }
        if (can_act("ADDR written"))
            send_address();
        return;
    case 0x07: /* MASTER.DATA: send a byte */
        if (!can_act("DATA written"))
            return;
        if (bus_state() != TWI_MASTER_BUSSTATE_OWNER_gc || (tw.addr_byte & 1u)) {
            xm_misuse("TWI: DATA written without a write transfer of ours");
            return;
        }
        clear_flags();
        TWIC.MASTER.DATA = v;
        bus(BUS_WRITE, 9.0);
        return;
    case 0x03: { /* MASTER.CTRLC: acknowledge action and command */
        TWIC.MASTER.CTRLC = (uint8_t)(v & TWI_MASTER_ACKACT_bm);
        uint8_t cmd = v & TWI_MASTER_CMD_gm;
        if (cmd == TWI_MASTER_CMD_NOACT_gc || !can_act("a command given"))
            return;
        clear_flags();
        if (cmd == TWI_MASTER_CMD_RECVTRANS_gc) {
            if (!(tw.addr_byte & 1u) || (v & TWI_MASTER_ACKACT_bm)) {
                xm_misuse("TWI: RECVTRANS outside a read, or with a NACK");
                return;
            }
            bus(BUS_READ, 1.0 + 8.0);
        } else if (cmd == TWI_MASTER_CMD_STOP_gc) {
            bus(BUS_STOP, 2.0);
        } else {
            xm_misuse("TWI: the REPSTART command is not modelled (write ADDR instead)");
        }
        return;
    }
    default:
        xm_io[0x480 + off] = v;
    }
    if (off == 0x01 && (v & TWI_MASTER_ENABLE_bm)) {
        xm_pin_use('C', 0, XM_USE_TWI);
        xm_pin_use('C', 1, XM_USE_TWI);
    }
}

static uint8_t twi_read(xm_periph_t *p, uint16_t off)
{
    (void)p;
    if (off == 0x07) { /* reading DATA clears the flags; the clock stays held until a command */
        uint8_t v = TWIC.MASTER.DATA;
        set_status(0, TWI_MASTER_RIF_bm | TWI_MASTER_WIF_bm);
        return v;
    }
    return xm_io[0x480 + off];
}

static uint64_t twi_next(xm_periph_t *p)
{
    (void)p;
    uint64_t t = tw.busy != BUS_IDLE ? tw.done_at : XM_NEVER;
    if ((tcs.r[0x00] & 0x01) && tcs.cycle_end < t)
        t = tcs.cycle_end;
    return t;
}

static void twi_event(xm_periph_t *p)
{
    (void)p;
    if ((tcs.r[0x00] & 0x01) && tcs.cycle_end <= xm_time) { /* the sensor's warm-up or integration ended */
        if (tcs.r[0x00] & 0x02) {
            if (tcs.integrating)
                tcs_integrate_end();
            tcs.integrating = true;
            tcs.cycle_end = xm_time + (uint64_t)tcs_cycles() * CYCLE;
        } else {
            tcs.cycle_end = xm_time + CYCLE;
        }
    }
    if (tw.busy == BUS_IDLE || tw.done_at > xm_time)
        return;
    uint8_t what = tw.busy;
    tw.busy = BUS_IDLE;
    switch (what) {
    case BUS_ADDR:
        if (!tw.acked) {
            set_status(TWI_MASTER_WIF_bm | TWI_MASTER_RXACK_bm | TWI_MASTER_CLKHOLD_bm, 0);
        } else if (tw.addr_byte & 1u) {
            TWIC.MASTER.DATA = tcs_byte_read();
            set_status(TWI_MASTER_RIF_bm | TWI_MASTER_CLKHOLD_bm, TWI_MASTER_RXACK_bm);
        } else {
            set_status(TWI_MASTER_WIF_bm | TWI_MASTER_CLKHOLD_bm, TWI_MASTER_RXACK_bm);
        }
        break;
    case BUS_WRITE:
        if (tw.acked)
            tcs_byte_written(TWIC.MASTER.DATA);
        set_status(TWI_MASTER_WIF_bm | TWI_MASTER_CLKHOLD_bm | (tw.acked ? 0 : TWI_MASTER_RXACK_bm),
                   TWI_MASTER_RXACK_bm);
        break;
    case BUS_READ:
        TWIC.MASTER.DATA = tw.acked ? tcs_byte_read() : 0xFF;
        set_status(TWI_MASTER_RIF_bm | TWI_MASTER_CLKHOLD_bm, 0);
        break;
    case BUS_STOP:
        set_status(TWI_MASTER_BUSSTATE_IDLE_gc, TWI_MASTER_BUSSTATE_gm | TWI_MASTER_CLKHOLD_bm);
        if (tw.addr_pending) {
            tw.addr_pending = false;
            send_address();
        }
        break;
    }
}

static uint8_t twi_level(void *ctx, uint8_t which)
{
    (void)ctx;
    (void)which;
    uint8_t a = TWIC.MASTER.CTRLA, s = TWIC.MASTER.STATUS;
    bool want = ((s & TWI_MASTER_RIF_bm) && (a & TWI_MASTER_RIEN_bm)) || ((s & TWI_MASTER_WIF_bm) && (a & TWI_MASTER_WIEN_bm));
    return want ? xm_level_at(a, 6) : 0;
}

void xm_twi_power_on(void)
{
    memset(&tw, 0, sizeof tw);
    tw.p = (xm_periph_t){.base = 0x480, .size = 0x10, .read = twi_read, .write = twi_write, .next_event = twi_next,
                         .event = twi_event};
    xm_attach(&tw.p);
    xm_irq_source(TWIC_TWIM_vect_num, twi_level, NULL, NULL, 0);
    if (xm_cold()) {
        memset(&tcs, 0, sizeof tcs);
        tcs.present = true;
        tcs.r[0x01] = 0xFF;
        tcs.r[0x03] = 0xFF;
        tcs.r[0x12] = 0x44;
        tcs.cycle_end = XM_NEVER;
    }
}

void xm_tcs_light(uint16_t clear, uint16_t red, uint16_t green, uint16_t blue)
{
    tcs.light[0] = clear;
    tcs.light[1] = red;
    tcs.light[2] = green;
    tcs.light[3] = blue;
}

void xm_tcs_present(bool present)
{
    tcs.present = present;
    if (!present) { /* unplugged: powered off, its registers back to their reset values */
        memset(tcs.r, 0, sizeof tcs.r);
        tcs.r[0x01] = 0xFF;
        tcs.r[0x03] = 0xFF;
        tcs.r[0x12] = 0x44;
        tcs.cycle_end = XM_NEVER;
        tcs.integrating = false;
    }
}

uint8_t xm_tcs_reg(uint8_t reg)
{
    return reg < 0x20 ? tcs.r[reg] : 0;
}

uint32_t xm_tcs_log_count(void)
{
    return tcs.log_n;
}

const xm_tcs_access_t *xm_tcs_log(uint32_t i)
{
    return i < tcs.log_n ? &tcs.log[i] : NULL;
}

void xm_tcs_log_clear(void)
{
    tcs.log_n = 0;
}

uint32_t xm_tcs_transactions(void)
{
    return tcs.transactions;
}
