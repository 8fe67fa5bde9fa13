/**
 * \file model_adc.c
 * ADCA and ADCB of the model, the analog inputs they convert, and the production signature row's calibration.
 *
 * Timing: the ADC clock is the CPU clock over PRESCALER; conversions are pipelined: one sample per ADC clock, the
 * result (CHIF) 7 ADC clocks after its sample at 12 bits (5 at 8 bits). Sampling takes half an ADC clock (the
 * XMEGA A has no SAMPCTRL): the sampling capacitor (XM_ADC_SAMPLE_PF), left at the previous sample's voltage,
 * charges through the input's source resistance, so a high-impedance input sampled too briefly reads part of the
 * previous channel. Transfer: signed mode RES = V / VREF * 2048 (single-ended: 0..2047); unsigned mode RES =
 * (V + 0.05 VREF) / VREF * 4096 with the nonlinearity the A3 errata warn of (the model: a bow of up to 12
 * counts). A CAL register that differs from the signature row's value gives a 2 % gain error (the model's stand-in
 * for an uncalibrated pipeline). References: INT1V 1.000 V, VCC/1.6, AREFA (PA0), AREFB (PB0). Internal inputs:
 * the temperature sensor (only with TEMPREF set: proportional to absolute temperature, TEMPSENSE in the signature
 * row gives its unsigned reading at 85 C), the bandgap (1.000 V), VCC/10. Free running repeats the sweep.
 * Not modelled: differential inputs, gain, compare mode, events, DMA, noise, the reference's settling.
 */
#include <math.h>
#include <string.h>

#include "model_internal.h"

#define KELVIN 273.15

typedef struct {
    xm_periph_t p;
    char port;
    uint16_t factory_cal;
    uint8_t vec_ch0;
    uint64_t next_sample;   /* the pipeline takes its next sample no earlier */
    uint64_t done_at[4];
    int16_t result[4];
    double held;            /* the sampling capacitor's voltage */
} adc_t;

static adc_t adcs[2];
static struct {
    double volts[2][8], ohms[2][8];
    double vcc, celsius;
} in;

double xm_analog_volts(char port, uint8_t pin)
{
    return (port == 'A' || port == 'B') && pin < 8 ? in.volts[port - 'A'][pin] : 0.0;
}

double xm_vcc(void)
{
    return in.vcc;
}

void xm_analog_set(char port, uint8_t pin, double volts, double source_ohm)
{
    if ((port != 'A' && port != 'B') || pin > 7)
        return;
    in.volts[port - 'A'][pin] = volts;
    in.ohms[port - 'A'][pin] = source_ohm;
}

void xm_vcc_set(double volts)
{
    in.vcc = volts;
}

void xm_temperature_set(double celsius)
{
    in.celsius = celsius;
}

static uint8_t reg(const adc_t *a, uint16_t off)
{
    return xm_io[a->p.base + off];
}

static uint64_t adc_clock(const adc_t *a)
{
    uint64_t div = 4ull << (reg(a, 0x04) & ADC_PRESCALER_gm);
    return (uint64_t)((double)div * (double)XM_HZ / xm_cpu_hz() + 0.5);
}

static double vref(const adc_t *a)
{
    switch (reg(a, 0x02) & ADC_REFSEL_gm) {
    case ADC_REFSEL_INT1V_gc:
        return 1.0;
    case ADC_REFSEL_VCC_gc:
        return in.vcc / 1.6;
    case ADC_REFSEL_AREFA_gc:
        xm_pin_use('A', 0, XM_USE_AREF);
        return in.volts[0][0];
    default:
        xm_pin_use('B', 0, XM_USE_AREF);
        return in.volts[1][0];
    }
}

/* The temperature sensor's voltage per kelvin, from the signature row's reading at 85 C. */
static double temp_volts_per_kelvin(void)
{
    return ((double)XM_TEMPSENSE / 4096.0 - 0.05) / (85.0 + KELVIN);
}

/* Samples channel `ch` now: \return its result. */
static int16_t convert(adc_t *a, uint8_t ch)
{
    uint8_t ctrl = reg(a, (uint16_t)(0x20u + 8u * ch)), mux = reg(a, (uint16_t)(0x21u + 8u * ch));
    uint8_t pos = (uint8_t)((mux & ADC_CH_MUXPOS_gm) >> ADC_CH_MUXPOS_gp);
    double v = 0.0, ohm = 0.0;
    switch (ctrl & ADC_CH_INPUTMODE_gm) {
    case ADC_CH_INPUTMODE_INTERNAL_gc:
        if (pos == 0) /* TEMP: powered by TEMPREF */
            v = (reg(a, 0x02) & ADC_TEMPREF_bm) ? temp_volts_per_kelvin() * (in.celsius + KELVIN) : 0.0;
        else if (pos == 1)
            v = 1.0;
        else if (pos == 2)
            v = in.vcc / 10.0;
        break;
    case ADC_CH_INPUTMODE_SINGLEENDED_gc:
        if (pos > 7) {
            xm_misuse("ADC%c CH%u: MUXPOS %u has no pin on the A3", a->port, ch, pos);
            break;
        }
        v = in.volts[a->port - 'A'][pos];
        ohm = in.ohms[a->port - 'A'][pos];
        xm_pin_use(a->port, pos, XM_USE_ANALOG_IN);
        break;
    default:
        xm_misuse("ADC%c CH%u: differential inputs are not modelled", a->port, ch);
    }
    double t_sample = 0.5 * (double)adc_clock(a) / (double)XM_HZ;
    double tau = ohm * XM_ADC_SAMPLE_PF * 1e-12;
    a->held = tau > 0 ? a->held + (v - a->held) * (1.0 - exp(-t_sample / tau)) : v;
    double ref = vref(a);
    bool eight = (reg(a, 0x01) & ADC_RESOLUTION_gm) == ADC_RESOLUTION_8BIT_gc;
    double res;
    if (reg(a, 0x01) & ADC_CONMODE_bm) {
        res = ref > 0 ? a->held / ref * 2048.0 : 0.0;
        res = res > 2047.0 ? 2047.0 : res < -2048.0 ? -2048.0 : res;
    } else {
        res = ref > 0 ? (a->held + 0.05 * ref) / ref * 4096.0 : 0.0;
        res += 12.0 * sin(M_PI * res / 4096.0); /* errata: INL not guaranteed in unsigned mode */
        res = res > 4095.0 ? 4095.0 : res < 0.0 ? 0.0 : res;
    }
    if (xm_get16((uint16_t)(a->p.base + 0x0C)) != a->factory_cal)
        res *= 0.98;
    if (eight)
        res /= 16.0;
    return (int16_t)lround(res);
}

static void start(adc_t *a, uint8_t ch)
{
    if (!(reg(a, 0x00) & ADC_ENABLE_bm)) {
        xm_misuse("ADC%c CH%u started while the ADC is disabled", a->port, ch);
        return;
    }
    uint64_t clk = adc_clock(a);
    uint64_t at = xm_time > a->next_sample ? xm_time : a->next_sample;
    a->next_sample = at + clk;
    bool eight = (reg(a, 0x01) & ADC_RESOLUTION_gm) == ADC_RESOLUTION_8BIT_gc;
    a->done_at[ch] = at + (eight ? 5u : 7u) * clk;
    a->result[ch] = convert(a, ch);
}

static void sweep(adc_t *a)
{
    uint8_t last = (uint8_t)((reg(a, 0x03) & ADC_SWEEP_gm) >> ADC_SWEEP_gp);
    for (uint8_t ch = 0; ch <= last; ch++)
        start(a, ch);
}

static void adc_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    adc_t *a = (adc_t *)p;
    if (off == 0x00) {
        xm_io[p->base] = (uint8_t)(v & (ADC_ENABLE_bm | ADC_DMASEL_gm));
        if (v & ADC_FLUSH_bm)
            for (uint8_t ch = 0; ch < 4; ch++)
                a->done_at[ch] = XM_NEVER;
        for (uint8_t ch = 0; ch < 4; ch++)
            if (v & (ADC_CH0START_bm << ch))
                start(a, ch);
        if ((v & ADC_ENABLE_bm) && (reg(a, 0x01) & ADC_FREERUN_bm))
            sweep(a);
        return;
    }
    if (off == 0x06) { /* INTFLAGS: a 1 clears, in the channels too */
        for (uint8_t ch = 0; ch < 4; ch++)
            if (v & (1u << ch)) {
                xm_io[p->base + 0x06] &= (uint8_t)~(1u << ch);
                xm_io[p->base + 0x23 + 8u * ch] = 0;
            }
        return;
    }
    if (off >= 0x20 && off < 0x40) {
        uint8_t ch = (uint8_t)((off - 0x20u) / 8u), r = (uint8_t)((off - 0x20u) % 8u);
        if (r == 0) {
            xm_io[p->base + off] = (uint8_t)(v & ~ADC_CH_START_bm);
            if (v & ADC_CH_START_bm)
                start(a, ch);
            return;
        }
        if (r == 3) {
            if (v & ADC_CH_CHIF_bm) {
                xm_io[p->base + off] = 0;
                xm_io[p->base + 0x06] &= (uint8_t)~(1u << ch);
            }
            return;
        }
    }
    if (off == 0x01 && (v & ADC_FREERUN_bm) && (reg(a, 0x00) & ADC_ENABLE_bm)) {
        xm_io[p->base + off] = v;
        sweep(a);
        return;
    }
    xm_io[p->base + off] = v;
}

static uint64_t adc_next(xm_periph_t *p)
{
    adc_t *a = (adc_t *)p;
    uint64_t t = XM_NEVER;
    for (uint8_t ch = 0; ch < 4; ch++)
        if (a->done_at[ch] < t)
            t = a->done_at[ch];
    return t;
}

static void adc_event(xm_periph_t *p)
{
    adc_t *a = (adc_t *)p;
    bool restart = false;
    for (uint8_t ch = 0; ch < 4; ch++) {
        if (a->done_at[ch] > xm_time)
            continue;
        a->done_at[ch] = XM_NEVER;
        uint16_t r = (uint16_t)a->result[ch];
        xm_set16((uint16_t)(p->base + 0x24u + 8u * ch), r);
        xm_set16((uint16_t)(p->base + 0x10u + 2u * ch), r);
        xm_io[p->base + 0x23u + 8u * ch] = ADC_CH_CHIF_bm;
        xm_io[p->base + 0x06] |= (uint8_t)(1u << ch);
        uint8_t last = (uint8_t)((reg(a, 0x03) & ADC_SWEEP_gm) >> ADC_SWEEP_gp);
        if (ch == last && (reg(a, 0x01) & ADC_FREERUN_bm) && (reg(a, 0x00) & ADC_ENABLE_bm))
            restart = true;
    }
    if (restart)
        sweep(a);
}

static uint8_t adc_level(void *ctx, uint8_t ch)
{
    adc_t *a = ctx;
    uint8_t ic = reg(a, (uint16_t)(0x22u + 8u * ch));
    if ((ic & ADC_CH_INTMODE_gm) != 0) /* only "conversion complete" is modelled */
        return 0;
    return (reg(a, (uint16_t)(0x23u + 8u * ch)) & ADC_CH_CHIF_bm) ? xm_level_at(ic, 0) : 0;
}

static void adc_ack(void *ctx, uint8_t ch)
{
    adc_t *a = ctx;
    xm_io[a->p.base + 0x23u + 8u * ch] = 0;
    xm_io[a->p.base + 0x06] &= (uint8_t)~(1u << ch);
}

static void adc_on(adc_t *a, uint16_t base, char port, uint16_t factory_cal, uint8_t vec_ch0)
{
    memset(a, 0, sizeof *a);
    a->p = (xm_periph_t){.base = base, .size = 0x40, .write = adc_write, .next_event = adc_next, .event = adc_event};
    a->port = port;
    a->factory_cal = factory_cal;
    a->vec_ch0 = vec_ch0;
    for (uint8_t ch = 0; ch < 4; ch++)
        a->done_at[ch] = XM_NEVER;
    xm_attach(&a->p);
    for (uint8_t ch = 0; ch < 4; ch++)
        xm_irq_source((uint8_t)(vec_ch0 + ch), adc_level, adc_ack, a, ch);
}

void xm_adc_power_on(void)
{
    if (xm_cold()) {
        memset(&in, 0, sizeof in);
        in.vcc = 3.3;
        in.celsius = 25.0;
    }
    adc_on(&adcs[0], 0x200, 'A', XM_ADCA_CAL, ADCA_CH0_vect_num);
    adc_on(&adcs[1], 0x240, 'B', XM_ADCB_CAL, ADCB_CH0_vect_num);
}

/* ---- the production signature row, read with LPM while NVM.CMD is READ_CALIB_ROW ---- */

uint8_t xm_prod_signature(uint16_t addr)
{
    switch (addr) {
    case 0x20: return (uint8_t)XM_ADCA_CAL;        /* ADCACAL0 */
    case 0x21: return (uint8_t)(XM_ADCA_CAL >> 8); /* ADCACAL1 */
    case 0x24: return (uint8_t)XM_ADCB_CAL;        /* ADCBCAL0 */
    case 0x25: return (uint8_t)(XM_ADCB_CAL >> 8); /* ADCBCAL1 */
    case 0x2E: return (uint8_t)XM_TEMPSENSE;        /* TEMPSENSE0 */
    case 0x2F: return (uint8_t)(XM_TEMPSENSE >> 8); /* TEMPSENSE1 */
    default: return 0xFF;
    }
}
