/**
 * \file model_tc.c
 * Timer/counters of the XMEGA model (TCC0, TCC1, TCD0, TCD1, TCE0) and what feeds their input captures: the
 * analog comparators of ACA through the event system.
 *
 * A timer counts up from the prescaled CPU clock (single-slope: normal and PWM modes) to PER and wraps to 0,
 * setting OVFIF; a compare channel sets CCxIF when the count reaches CCx. At each wrap (UPDATE) the buffered
 * registers (PERBUF, CCxBUF) take effect when their buffer-valid flag is set. In capture mode (CTRLD EVACT CAPT) an
 * event on the selected channel copies the count into CCx, or into CCxBUF when CCx still holds an unread capture
 * (a two-level FIFO), or sets ERRIF when both are full. 16-bit registers go through TEMP: reading the low byte
 * latches the high byte, writing the low byte waits in TEMP for the high byte. Not modelled: dual-slope modes,
 * counting down, event clock sources, the prescaler's phase, AWEX and Hi-Res.
 */
#include <string.h>

#include "model_internal.h"

#define CNT 0x20u
#define PER 0x26u
#define CCA 0x28u
#define PERBUF 0x36u
#define CCABUF 0x38u

typedef struct {
    xm_periph_t p;
    uint8_t channels;   /* 4 (TC0) or 2 (TC1) */
    uint8_t vec_ovf;    /* OVF; ERR, CCA, CCB, ... follow */
    char port;          /* compare outputs OCxA.. on this port */
    uint8_t pin0;       /* from this pin (TC0: 0..3, TC1: 4..5) */
    uint64_t origin;    /* the time the count was `cnt` (a count boundary) */
    uint64_t dt;        /* cycles per count, for dt_clksel at dt_hz */
    uint8_t dt_clksel;
    double dt_hz;
    uint16_t cnt;
    bool cc_full[4], buf_full[4];
} tc_t;

static tc_t tcs[5];
static uint8_t tc_count;

static uint8_t reg(const tc_t *t, uint16_t off)
{
    return xm_io[t->p.base + off];
}

static uint32_t prescale(const tc_t *t)
{
    static const uint16_t div[8] = {0, 1, 2, 4, 8, 64, 256, 1024};
    uint8_t sel = reg(t, 0x00) & TC0_CLKSEL_gm;
    return sel < 8 ? div[sel] : 0;
}

/* Time units (cycles at 32 MHz) per count. */
static uint64_t tick(tc_t *t)
{
    uint8_t sel = reg(t, 0x00) & TC0_CLKSEL_gm;
    double hz = xm_cpu_hz();
    if (sel != t->dt_clksel || hz != t->dt_hz) {
        uint32_t d = prescale(t);
        t->dt = d ? (uint64_t)((double)d * (double)XM_HZ / hz + 0.5) : 0;
        t->dt_clksel = sel;
        t->dt_hz = hz;
    }
    return t->dt;
}

static bool capturing(const tc_t *t)
{
    return (reg(t, 0x03) & TC0_EVACT_gm) == TC_EVACT_CAPT_gc;
}

/* Count boundaries past `origin` (for the running counter) are counted here: the flags they raise, the buffers that
 * take effect at a wrap. */
static void sync(tc_t *t)
{
    uint64_t dt = tick(t);
    if (!dt) {
        t->origin = xm_time;
        return;
    }
    uint64_t k = (xm_time - t->origin) / dt;
    if (k == 0)
        return;
    t->origin += k * dt;
    uint32_t top = xm_get16((uint16_t)(t->p.base + PER));
    uint32_t period = top + 1u;
    uint32_t c = t->cnt;
    if (c > top) /* set above TOP: it runs on to 0xFFFF first */
        period = 0x10000u;
    uint64_t end = (uint64_t)c + k;
    uint64_t wraps = end / period;
    uint8_t flags = 0;
    if (!capturing(t))
        for (uint8_t ch = 0; ch < t->channels; ch++) {
            uint32_t x = xm_get16((uint16_t)(t->p.base + CCA + 2u * ch));
            if (x >= period)
                continue;
            uint32_t d = (uint32_t)((x + period - c) % period);
            if (d == 0)
                d = period;
            if (d <= k)
                flags |= (uint8_t)(TC0_CCAIF_bm << ch);
        }
    if (wraps) {
        flags |= TC0_OVFIF_bm;
        uint8_t bv = reg(t, 0x0B); /* CTRLG: buffer valid flags take effect at UPDATE */
        if (bv & TC0_PERBV_bm)
            xm_set16((uint16_t)(t->p.base + PER), xm_get16((uint16_t)(t->p.base + PERBUF)));
        if (!capturing(t))
            for (uint8_t ch = 0; ch < t->channels; ch++)
                if (bv & (TC0_CCABV_bm << ch))
                    xm_set16((uint16_t)(t->p.base + CCA + 2u * ch), xm_get16((uint16_t)(t->p.base + CCABUF + 2u * ch)));
        xm_io[t->p.base + 0x0A] = xm_io[t->p.base + 0x0B] = 0;
    }
    t->cnt = (uint16_t)(end % period);
    xm_io[t->p.base + 0x0C] |= flags;
}

static void capture(tc_t *t, uint8_t ch)
{
    sync(t);
    uint16_t base = t->p.base;
    if (!t->cc_full[ch]) {
        xm_set16((uint16_t)(base + CCA + 2u * ch), t->cnt);
        t->cc_full[ch] = true;
        xm_io[base + 0x0C] |= (uint8_t)(TC0_CCAIF_bm << ch);
    } else if (!t->buf_full[ch]) {
        xm_set16((uint16_t)(base + CCABUF + 2u * ch), t->cnt);
        t->buf_full[ch] = true;
        xm_io[base + 0x0B] |= (uint8_t)(TC0_CCABV_bm << ch);
        xm_io[base + 0x0A] = xm_io[base + 0x0B];
    } else {
        xm_io[base + 0x0C] |= TC0_ERRIF_bm; /* both full: this capture is lost */
    }
}

/* The low byte of a 16-bit register. */
static bool is16(uint16_t off)
{
    return (off & 1u) == 0 &&
           (off == CNT || off == PER || (off >= CCA && off < CCA + 8u) || (off >= PERBUF && off < CCABUF + 8u));
}

static uint8_t tc_read(xm_periph_t *p, uint16_t off)
{
    tc_t *t = (tc_t *)p;
    sync(t);
    uint16_t base = p->base;
    if (off == CNT)
        xm_set16((uint16_t)(base + CNT), t->cnt);
    if (is16(off)) { /* low byte: the high byte goes to TEMP */
        uint8_t lo = xm_io[base + off];
        xm_io[base + 0x0F] = xm_io[base + off + 1u];
        if (capturing(t) && off >= CCA && off < CCA + 8u) {
            uint8_t ch = (uint8_t)((off - CCA) / 2u);
            if (t->buf_full[ch]) { /* the FIFO moves on: CCx holds the next capture */
                xm_set16((uint16_t)(base + off), xm_get16((uint16_t)(base + CCABUF + 2u * ch)));
                t->buf_full[ch] = false;
                xm_io[base + 0x0B] &= (uint8_t)~(TC0_CCABV_bm << ch);
                xm_io[base + 0x0A] = xm_io[base + 0x0B];
                xm_io[base + 0x0C] |= (uint8_t)(TC0_CCAIF_bm << ch);
            } else {
                t->cc_full[ch] = false;
                xm_io[base + 0x0C] &= (uint8_t)~(TC0_CCAIF_bm << ch);
            }
        }
        return lo;
    }
    if (off > 0 && is16((uint16_t)(off - 1u)))
        return xm_io[base + 0x0F]; /* high byte: TEMP */
    return xm_io[base + off];
}

static void tc_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    tc_t *t = (tc_t *)p;
    sync(t);
    uint16_t base = p->base;
    if (is16(off)) {
        xm_io[base + 0x0F] = v; /* low byte: waits in TEMP */
        return;
    }
    if (off > 0 && is16((uint16_t)(off - 1u))) {
        uint16_t lo = (uint16_t)(off - 1u);
        xm_io[base + lo] = xm_io[base + 0x0F];
        xm_io[base + off] = v;
        if (lo == CNT) {
            t->cnt = xm_get16((uint16_t)(base + CNT));
            t->origin = xm_time;
        }
        if (lo >= PERBUF) { /* a buffer written: valid until the next UPDATE */
            xm_io[base + 0x0B] |= (uint8_t)(lo == PERBUF ? TC0_PERBV_bm : TC0_CCABV_bm << ((lo - CCABUF) / 2u));
            xm_io[base + 0x0A] = xm_io[base + 0x0B];
        }
        return;
    }
    switch (off) {
    case 0x00: /* CTRLA: the count goes on from now at the new rate */
        xm_io[base] = v;
        if ((v & TC0_CLKSEL_gm) >= TC_CLKSEL_EVCH0_gc)
            xm_misuse("TC at 0x%03x: event clock sources are not modelled", base);
        t->origin = xm_time;
        break;
    case 0x08: /* CTRLFCLR / CTRLFSET */
    case 0x09:
        if (v & TC0_CMD_gm)
            xm_misuse("TC at 0x%03x: commands are not modelled", base);
        break;
    case 0x0A: xm_io[base + 0x0A] = xm_io[base + 0x0B] = (uint8_t)(xm_io[base + 0x0B] & ~v); break;
    case 0x0B: xm_io[base + 0x0A] = xm_io[base + 0x0B] = (uint8_t)(xm_io[base + 0x0B] | v); break;
    case 0x0C: xm_io[base + 0x0C] &= (uint8_t)~v; break; /* INTFLAGS: a 1 clears */
    default: xm_io[base + off] = v; break;
    }
    if (off == 0x01) /* CTRLB: compare outputs on their pins */
        for (uint8_t ch = 0; ch < t->channels; ch++)
            if ((v & (TC0_CCAEN_bm << ch)) && (v & TC0_WGMODE_gm) != TC_WGMODE_NORMAL_gc)
                xm_pin_use(t->port, (uint8_t)(t->pin0 + ch), XM_USE_TC_OUT);
}

/* The next count boundary at which an enabled interrupt's flag rises. */
static uint64_t tc_next(xm_periph_t *p)
{
    tc_t *t = (tc_t *)p;
    uint64_t dt = tick(t);
    if (!dt)
        return XM_NEVER;
    uint8_t flags = reg(t, 0x0C), ia = reg(t, 0x06), ib = reg(t, 0x07);
    uint32_t top = xm_get16((uint16_t)(p->base + PER));
    uint32_t period = t->cnt <= top ? top + 1u : 0x10000u;
    uint64_t best = XM_NEVER;
    if (xm_level_at(ia, 0) && !(flags & TC0_OVFIF_bm)) {
        uint64_t at = t->origin + (uint64_t)(period - t->cnt) * dt;
        if (at < best)
            best = at;
    }
    if (!capturing(t))
        for (uint8_t ch = 0; ch < t->channels; ch++) {
            if (!xm_level_at(ib, (uint8_t)(2u * ch)) || (flags & (TC0_CCAIF_bm << ch)))
                continue;
            uint32_t x = xm_get16((uint16_t)(p->base + CCA + 2u * ch));
            if (x >= period)
                continue;
            uint32_t d = (x + period - t->cnt) % period;
            uint64_t at = t->origin + (uint64_t)(d ? d : period) * dt;
            if (at < best)
                best = at;
        }
    return best;
}

static void tc_event(xm_periph_t *p)
{
    sync((tc_t *)p);
}

/* Interrupt sources: which 0 OVF, 1 ERR, 2.. CCA.. */
/* Flags of enabled interrupts are raised by events at their time (tc_next), so no sync is needed here. */
static uint8_t tc_level(void *ctx, uint8_t which)
{
    tc_t *t = ctx;
    uint8_t flags = reg(t, 0x0C);
    if (which == 0)
        return (flags & TC0_OVFIF_bm) ? xm_level_at(reg(t, 0x06), 0) : 0;
    if (which == 1)
        return (flags & TC0_ERRIF_bm) ? xm_level_at(reg(t, 0x06), 2) : 0;
    uint8_t ch = (uint8_t)(which - 2u);
    return (flags & (TC0_CCAIF_bm << ch)) ? xm_level_at(reg(t, 0x07), (uint8_t)(2u * ch)) : 0;
}

static void tc_ack(void *ctx, uint8_t which)
{
    tc_t *t = ctx;
    uint8_t bit = which == 0 ? TC0_OVFIF_bm : which == 1 ? TC0_ERRIF_bm : (uint8_t)(TC0_CCAIF_bm << (which - 2u));
    xm_io[t->p.base + 0x0C] &= (uint8_t)~bit;
}

static tc_t *tc_add(uint16_t base, uint8_t channels, uint8_t vec_ovf, char port, uint8_t pin0)
{
    tc_t *t = &tcs[tc_count++];
    memset(t, 0, sizeof *t);
    t->p = (xm_periph_t){.base = base, .size = 0x40, .read = tc_read, .write = tc_write, .next_event = tc_next,
                         .event = tc_event};
    t->channels = channels;
    t->vec_ovf = vec_ovf;
    t->port = port;
    t->pin0 = pin0;
    t->origin = xm_time;
    xm_set16((uint16_t)(base + PER), 0xFFFF);
    xm_set16((uint16_t)(base + PERBUF), 0xFFFF);
    xm_attach(&t->p);
    for (uint8_t w = 0; w < 2u + channels; w++)
        xm_irq_source((uint8_t)(vec_ovf + w), tc_level, tc_ack, t, w);
    return t;
}

static tc_t *tc_at(uint16_t base)
{
    for (uint8_t i = 0; i < tc_count; i++)
        if (tcs[i].p.base == base)
            return &tcs[i];
    return NULL;
}

double xm_tc_duty(uint16_t base, uint8_t ch)
{
    tc_t *t = tc_at(base);
    if (!t || ch >= t->channels || !tick(t) || (reg(t, 0x01) & TC0_WGMODE_gm) != TC_WGMODE_SS_gc ||
        !(reg(t, 0x01) & (TC0_CCAEN_bm << ch)))
        return 0.0;
    sync(t);
    uint32_t per = xm_get16((uint16_t)(base + PER)) + 1u, cc = xm_get16((uint16_t)(base + CCA + 2u * ch));
    return cc >= per ? 100.0 : 100.0 * cc / per;
}

uint64_t xm_tc_next_count_time(uint16_t base, uint16_t count)
{
    tc_t *t = tc_at(base);
    if (!t || !tick(t))
        return XM_NEVER;
    sync(t);
    uint32_t top = xm_get16((uint16_t)(base + PER));
    uint32_t period = t->cnt <= top ? top + 1u : 0x10000u;
    return t->origin + (uint64_t)((count + period - t->cnt) % period) * tick(t);
}

uint8_t xm_tc_carrier_duty(void)
{
    tc_t *t = tc_at(0x940); /* TCD1, CCB on PD5 */
    if (!t || !tick(t) || !(reg(t, 0x01) & TC1_CCBEN_bm) || (reg(t, 0x01) & TC0_WGMODE_gm) != TC_WGMODE_SS_gc ||
        !(xm_io[0x660] & PIN5_bm))
        return 0;
    sync(t);
    uint32_t per = xm_get16(0x940 + PER) + 1u, ccb = xm_get16(0x940 + CCA + 2u);
    uint32_t pct = ccb >= per ? 200u : ccb * 200u / per; /* percent of a 50 % square wave */
    return (uint8_t)(pct > 200u ? 200u : pct);
}

/* ---- ACA -> event system -> capture ---- */

#define AC_QUEUE 1024u

static struct {
    uint64_t at[AC_QUEUE];
    uint8_t ac[AC_QUEUE];
    uint16_t n;
} acq;

void xm_ac_toggle(uint8_t ac, uint64_t at)
{
    if (acq.n == AC_QUEUE || ac > 1) {
        xm_misuse("model: AC toggle queue full");
        return;
    }
    uint16_t i = acq.n++;
    while (i > 0 && acq.at[i - 1] > at) { /* keep time order */
        acq.at[i] = acq.at[i - 1];
        acq.ac[i] = acq.ac[i - 1];
        i--;
    }
    acq.at[i] = at;
    acq.ac[i] = ac;
    xm_changed();
}

static void ac_pop(uint16_t i)
{
    memmove(&acq.at[i], &acq.at[i + 1], (size_t)(acq.n - i - 1u) * sizeof acq.at[0]);
    memmove(&acq.ac[i], &acq.ac[i + 1], (size_t)(acq.n - i - 1u) * sizeof acq.ac[0]);
    acq.n--;
}

static uint64_t ac_next(xm_periph_t *p)
{
    (void)p;
    return acq.n ? acq.at[0] : XM_NEVER;
}

/* An output toggle of ACA.ACn: each event channel that carries it passes it through its digital filter (a pulse
 * shorter than the filter's samples disappears) to the timers that capture from that channel. */
static void ac_event(xm_periph_t *p)
{
    (void)p;
    uint8_t ac = acq.ac[0];
    uint64_t at = acq.at[0];
    ac_pop(0);
    uint8_t ctrl = ac ? ACA.AC1CTRL : ACA.AC0CTRL;
    if (!(ctrl & AC_ENABLE_bm))
        return;
    for (uint8_t ch = 0; ch < 8; ch++) {
        if ((&EVSYS.CH0MUX)[ch] != (uint8_t)(EVSYS_CHMUX_ACA_CH0_gc + ac))
            continue;
        uint64_t samples = (uint64_t)((&EVSYS.CH0CTRL)[ch] & EVSYS_DIGFILT_gm) + 1u;
        uint64_t filter = (uint64_t)((double)samples * (double)XM_HZ / xm_cpu_hz());
        bool filtered = false;
        for (uint16_t i = 0; i < acq.n && acq.at[i] < at + filter; i++)
            if (acq.ac[i] == ac) { /* it toggles back within the filter: neither toggle gets through */
                ac_pop(i);
                filtered = true;
                break;
            }
        if (filtered)
            return;
        for (uint8_t k = 0; k < tc_count; k++) {
            tc_t *t = &tcs[k];
            uint8_t d = reg(t, 0x03);
            if ((d & TC0_EVACT_gm) != TC_EVACT_CAPT_gc || (d & TC0_EVSEL_gm) < TC_EVSEL_CH0_gc)
                continue;
            uint8_t first = (uint8_t)((d & TC0_EVSEL_gm) - TC_EVSEL_CH0_gc);
            if (ch < first || ch - first >= t->channels)
                continue;
            uint8_t cc = (uint8_t)(ch - first);
            if (reg(t, 0x01) & (TC0_CCAEN_bm << cc))
                capture(t, cc);
        }
    }
}

static uint8_t ac_mux_read(xm_periph_t *p, uint16_t off)
{
    return xm_io[p->base + off];
}

static void ac_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    xm_io[p->base + off] = v;
    for (uint8_t n = 0; n < 2; n++) {
        uint8_t ctrl = n ? ACA.AC1CTRL : ACA.AC0CTRL, mux = n ? ACA.AC1MUXCTRL : ACA.AC0MUXCTRL;
        if (!(ctrl & AC_ENABLE_bm))
            continue;
        uint8_t pos = (uint8_t)((mux & AC_MUXPOS_gm) >> AC_MUXPOS_gp);
        if (pos < 7) /* PIN0..PIN6 (7 is the DAC) */
            xm_pin_use('A', pos, XM_USE_ANALOG_IN);
        uint8_t neg = mux & AC_MUXNEG_gm;
        if (neg <= AC_MUXNEG_PIN7_gc) /* PIN0, 1, 3, 5, 7 */
            xm_pin_use('A', (uint8_t)(neg == 0 ? 0 : 2u * neg - 1u), XM_USE_ANALOG_IN);
    }
}

static xm_periph_t aca = {.base = 0x380, .size = 0x08, .read = ac_mux_read, .write = ac_write, .next_event = ac_next,
                          .event = ac_event};

void xm_tc_power_on(void)
{
    tc_count = 0;
    if (xm_cold())
        memset(&acq, 0, sizeof acq);
    tc_add(0x800, 4, TCC0_OVF_vect_num, 'C', 0);
    tc_add(0x840, 2, TCC1_OVF_vect_num, 'C', 4);
    tc_add(0x900, 4, TCD0_OVF_vect_num, 'D', 0);
    tc_add(0x940, 2, TCD1_OVF_vect_num, 'D', 4);
    tc_add(0xA00, 4, TCE0_OVF_vect_num, 'E', 0);
    xm_attach(&aca);
}
