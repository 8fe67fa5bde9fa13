/**
 * \file model.c
 * The core of the XMEGA model: the register file and its dispatch to peripherals, simulated time, the CPU's
 * interrupt flag and SLEEP, CCP, the PMIC, clocks (OSC, CLK, DFLL), the watchdog and resets.
 */
#include <string.h>

#include "model_internal.h"

uint8_t xm_io[XM_IO_SIZE];
uint64_t xm_time;

#define MAX_PERIPHS 32
#define MAX_SOURCES 64

static struct {
    xm_periph_t *periph[MAX_PERIPHS];
    uint8_t periphs;
    xm_periph_t *by_addr[XM_IO_SIZE / 8]; /* every peripheral starts on an 8-byte boundary */
    struct {
        uint8_t vector, which;
        xm_level_fn level;
        xm_ack_fn ack;
        void *ctx;
    } src[MAX_SOURCES];
    uint8_t sources;
    uint64_t horizon;
    bool fast_forward;
    /* Caches: the time of the earliest peripheral event (0: look again) and whether an interrupt may be
     * requested. A write, an event or a stimulus can change either; a read cannot make them earlier. */
    uint64_t next_at;
    bool irq_maybe;
    uint8_t ccp_window;     /* accesses left in which a protected register may be written */
    bool sei_delay;         /* the instruction after SEI runs before any interrupt */
    void (*on_restart)(uint8_t why);
    uint32_t restarts[4];
    uint64_t restart_at;
    uint16_t hook_addr; /* after the next write there, hook() runs (once) */
    void (*hook)(void);
    uint32_t irq_count[XM_VECTORS], irq_ms_count[XM_VECTORS], irq_ms_max[XM_VECTORS];
    uint64_t irq_ms; /* the millisecond irq_ms_count counts */
    uint32_t strays;
    uint32_t misuses;
    char misuse_last[160];
    /* clocks */
    uint64_t rc32m_ready_at, rc32k_ready_at;
    bool dfll_early;
    /* watchdog */
    uint64_t wdt_deadline, wdt_sync_until;
} m;

/* ---- vectors: the program's ISRs, found by name as avr-libc's vector table finds them ---- */

#define V(n) extern void __vector_##n(void) __attribute__((weak));
#define V10(t) V(t##0) V(t##1) V(t##2) V(t##3) V(t##4) V(t##5) V(t##6) V(t##7) V(t##8) V(t##9)
V(1) V(2) V(3) V(4) V(5) V(6) V(7) V(8) V(9)
V10(1) V10(2) V10(3) V10(4) V10(5) V10(6) V10(7) V10(8) V10(9) V10(10) V10(11) V(120) V(121)
#undef V
extern void __vector_default(void) __attribute__((weak));

#define V(n) __vector_##n,
static void (*const vectors[XM_VECTORS])(void) = {
    NULL, V(1) V(2) V(3) V(4) V(5) V(6) V(7) V(8) V(9)
    V10(1) V10(2) V10(3) V10(4) V10(5) V10(6) V10(7) V10(8) V10(9) V10(10) V10(11) V(120) V(121)
};
#undef V
#undef V10

/* ---- registry ---- */

void xm_attach(xm_periph_t *p)
{
    if (m.periphs == MAX_PERIPHS) {
        xm_misuse("model: too many peripherals");
        return;
    }
    m.periph[m.periphs++] = p;
    for (uint16_t a = p->base; a < p->base + p->size; a = (uint16_t)(a + 8u))
        m.by_addr[a / 8u] = p;
}

void xm_irq_source(uint8_t vector, xm_level_fn level, xm_ack_fn ack, void *ctx, uint8_t which)
{
    if (m.sources == MAX_SOURCES)
        return;
    m.src[m.sources].vector = vector;
    m.src[m.sources].which = which;
    m.src[m.sources].level = level;
    m.src[m.sources].ack = ack;
    m.src[m.sources].ctx = ctx;
    m.sources++;
}

void xm_misuse(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(m.misuse_last, sizeof m.misuse_last, fmt, ap);
    va_end(ap);
    m.misuses++;
}

uint32_t xm_misuse_count(void)
{
    return m.misuses;
}

const char *xm_misuse_last(void)
{
    return m.misuses ? m.misuse_last : "none";
}

/* ---- time ---- */

uint64_t xm_now(void)
{
    return xm_time;
}

void xm_set_horizon(uint64_t t)
{
    m.horizon = t;
}

void xm_changed(void)
{
    m.next_at = 0;
    m.irq_maybe = true;
}

static xm_periph_t *next_event(uint64_t *at)
{
    xm_periph_t *first = NULL;
    *at = XM_NEVER;
    for (uint8_t i = 0; i < m.periphs; i++) {
        xm_periph_t *p = m.periph[i];
        if (!p->next_event)
            continue;
        uint64_t t = p->next_event(p);
        if (t < *at) {
            *at = t;
            first = p;
        }
    }
    m.next_at = *at;
    return first;
}

static void irq_check(void);

/* Runs every peripheral event due by `t`, serving interrupts as they come, then sets the time to `t`. */
static void advance_to(uint64_t t)
{
    while (m.next_at <= t) {
        uint64_t at;
        xm_periph_t *p = next_event(&at);
        if (!p || at > t)
            break;
        if (at > xm_time)
            xm_time = at;
        p->event(p);
        xm_changed();
        irq_check();
    }
    if (t > xm_time)
        xm_time = t;
}

static void access_done(void)
{
    if (m.ccp_window)
        m.ccp_window--;
    if (m.sei_delay) {
        m.sei_delay = false; /* this access was the instruction after SEI */
        return;
    }
    irq_check();
}

/* ---- the register file ---- */

uint8_t xm_read8(uint16_t addr)
{
    if (addr >= XM_IO_SIZE) {
        xm_misuse("read of 0x%04x, outside the I/O memory", addr);
        return 0;
    }
    advance_to(xm_time + XM_READ_CYCLES);
    xm_periph_t *p = m.by_addr[addr / 8u];
    uint8_t v = p && p->read && addr >= p->base && addr < p->base + p->size ? p->read(p, (uint16_t)(addr - p->base))
                                                                          : xm_io[addr];
    access_done();
    return v;
}

void xm_write8(uint16_t addr, uint8_t v)
{
    if (addr >= XM_IO_SIZE) {
        xm_misuse("write of 0x%04x, outside the I/O memory", addr);
        return;
    }
    advance_to(xm_time + XM_WRITE_CYCLES);
    xm_periph_t *p = m.by_addr[addr / 8u];
    if (p && p->write && addr >= p->base && addr < p->base + p->size)
        p->write(p, (uint16_t)(addr - p->base), v);
    else
        xm_io[addr] = v;
    xm_changed();
    if (m.hook && addr == m.hook_addr) {
        void (*hook)(void) = m.hook;
        m.hook = NULL;
        hook();
    }
    access_done();
}

/* ---- the CPU: SREG, CCP ---- */

#define SREG_ADDR 0x3Fu
#define CCP_ADDR 0x34u
#define SREG_I 0x80u

static void cpu_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    uint16_t addr = (uint16_t)(p->base + off);
    xm_io[addr] = v;
    if (addr == CCP_ADDR)
        m.ccp_window = (v == CCP_IOREG_gc) ? 5u : 0u; /* the next 4 instructions (this access counts down one) */
}

static xm_periph_t cpu = {.base = 0x30, .size = 0x10, .write = cpu_write};

bool xm_ccp_open(void)
{
    return m.ccp_window > 0;
}

void xm_sei(void)
{
    advance_to(xm_time + 1u);
    xm_io[SREG_ADDR] |= SREG_I;
    m.sei_delay = true;
    xm_changed();
}

void xm_cli(void)
{
    advance_to(xm_time + 1u);
    xm_io[SREG_ADDR] &= (uint8_t)~SREG_I;
    m.sei_delay = false;
}

/* ---- the interrupt controller ---- */

static uint8_t active_level(void)
{
    uint8_t s = PMIC.STATUS;
    return (s & PMIC_HILVLEX_bm) ? 3u : (s & PMIC_MEDLVLEX_bm) ? 2u : (s & PMIC_LOLVLEX_bm) ? 1u : 0u;
}

/* The source to serve now: enabled in the PMIC, above the level executing, the highest level first and within a
 * level the lowest vector (static priority). -1: none. */
static int pick(void)
{
    if (!(xm_io[SREG_ADDR] & SREG_I) || !m.irq_maybe)
        return -1;
    uint8_t above = active_level(), ctrl = PMIC.CTRL;
    int best = -1;
    uint8_t best_level = 0;
    for (uint8_t i = 0; i < m.sources; i++) {
        uint8_t l = m.src[i].level(m.src[i].ctx, m.src[i].which);
        if (l == 0 || l <= above || !(ctrl & (1u << (l - 1u))))
            continue;
        if (m.fast_forward && m.src[i].vector != TCC0_OVF_vect_num && m.src[i].vector != TCD0_OVF_vect_num)
            continue;
        if (l > best_level || (l == best_level && m.src[i].vector < m.src[best].vector)) {
            best = i;
            best_level = l;
        }
    }
    if (best < 0)
        m.irq_maybe = false; /* nothing to serve until something changes (a write, an event, a RETI) */
    return best;
}

static void count(uint8_t vector)
{
    uint64_t ms = xm_time / XM_MS(1);
    if (ms != m.irq_ms) {
        memset(m.irq_ms_count, 0, sizeof m.irq_ms_count);
        m.irq_ms = ms;
    }
    m.irq_count[vector]++;
    if (++m.irq_ms_count[vector] > m.irq_ms_max[vector])
        m.irq_ms_max[vector] = m.irq_ms_count[vector];
}

static void serve(int s)
{
    uint8_t level = m.src[s].level(m.src[s].ctx, m.src[s].which);
    uint8_t vector = m.src[s].vector;
    uint8_t bit = (uint8_t)(1u << (level - 1u));
    PMIC.STATUS |= bit;
    count(vector);
    if (m.src[s].ack)
        m.src[s].ack(m.src[s].ctx, m.src[s].which);
    if (vectors[vector]) {
        vectors[vector]();
    } else {
        m.strays++;
        if (__vector_default) {
            __vector_default();
        } else {
            /* avr-libc's __bad_interrupt: jmp 0. The startup code clears SREG and runs main again; no RETI ever
             * clears this level in the PMIC, so it and every level below stay blocked. */
            xm_io[SREG_ADDR] = 0;
            xm_restart(XM_RESTART_JUMP_TO_0);
            return;
        }
    }
    /* RETI: the highest level executing ends. */
    uint8_t l = active_level();
    if (l)
        PMIC.STATUS &= (uint8_t)~(1u << (l - 1u));
    xm_changed();
}

static void irq_check(void)
{
    int s;
    while ((s = pick()) >= 0)
        serve(s);
}

static void pmic_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    if (off == 0) /* STATUS is read-only */
        return;
    xm_io[p->base + off] = v;
}

static xm_periph_t pmic = {.base = 0xA0, .size = 0x10, .write = pmic_write};

uint32_t xm_irq_count(uint8_t vector)
{
    return vector < XM_VECTORS ? m.irq_count[vector] : 0;
}

uint32_t xm_irq_max_per_ms(uint8_t vector)
{
    return vector < XM_VECTORS ? m.irq_ms_max[vector] : 0;
}

void xm_irq_clear_counts(void)
{
    memset(m.irq_count, 0, sizeof m.irq_count);
    memset(m.irq_ms_count, 0, sizeof m.irq_ms_count);
    memset(m.irq_ms_max, 0, sizeof m.irq_ms_max);
}

uint32_t xm_stray_count(void)
{
    return m.strays;
}

/* ---- SLEEP and busy code ---- */

void xm_sleep(void)
{
    m.sei_delay = false; /* SLEEP was the instruction after SEI: a pending interrupt wakes it at once */
    if (!(SLEEP.CTRL & SLEEP_SEN_bm))
        return;
    if (!(xm_io[SREG_ADDR] & SREG_I)) {
        xm_misuse("SLEEP with interrupts masked at %llu: nothing but a reset wakes the CPU",
                  (unsigned long long)xm_time);
        advance_to(m.horizon);
        return;
    }
    for (;;) {
        int s = pick();
        if (s >= 0) {
            irq_check();
            return;
        }
        uint64_t at;
        xm_periph_t *p = next_event(&at);
        if (!p || at > m.horizon) {
            if (m.horizon != XM_NEVER)
                advance_to(m.horizon);
            return;
        }
        if (at > xm_time)
            xm_time = at;
        p->event(p);
        xm_changed();
    }
}

void xm_after_write(uint16_t addr, void (*fn)(void))
{
    m.hook_addr = addr;
    m.hook = fn;
}

void xm_busy(uint64_t cycles, bool masked)
{
    uint8_t i = xm_io[SREG_ADDR] & SREG_I;
    if (masked)
        xm_io[SREG_ADDR] &= (uint8_t)~SREG_I;
    advance_to(xm_time + cycles);
    xm_io[SREG_ADDR] |= i;
    xm_changed();
    irq_check();
}

void xm_fast_forward(uint64_t cycles)
{
    m.fast_forward = true;
    advance_to(xm_time + cycles);
    m.fast_forward = false;
    m.wdt_deadline = m.wdt_deadline == XM_NEVER ? XM_NEVER : m.wdt_deadline + cycles;
    xm_changed();
    irq_check();
}

/* ---- clocks: OSC, CLK, DFLL ---- */

/* Start-up times of the internal oscillators (the model's: the order of magnitude of the A3 datasheet). */
#define RC32M_STARTUP XM_US(6)
#define RC32K_STARTUP XM_MS(1)

double xm_cpu_hz(void)
{
    switch (CLK.CTRL & CLK_SCLKSEL_gm) {
    case CLK_SCLKSEL_RC32M_gc:
        return 32e6;
    case CLK_SCLKSEL_RC32K_gc:
        return 32768.0;
    default:
        return 2e6;
    }
}

uint8_t xm_sysclk(void)
{
    return CLK.CTRL & CLK_SCLKSEL_gm;
}

static void osc_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    (void)p;
    if (off == 0x00) { /* OSC.CTRL: an oscillator enabled now is ready after its start-up time */
        uint8_t was = OSC.CTRL;
        OSC.CTRL = v;
        if ((v & OSC_RC32MEN_bm) && !(was & OSC_RC32MEN_bm))
            m.rc32m_ready_at = xm_time + RC32M_STARTUP;
        if ((v & OSC_RC32KEN_bm) && !(was & OSC_RC32KEN_bm))
            m.rc32k_ready_at = xm_time + RC32K_STARTUP;
        if (!(v & OSC_RC32MEN_bm)) {
            m.rc32m_ready_at = XM_NEVER;
            OSC.STATUS &= (uint8_t)~OSC_RC32MRDY_bm;
        }
        if (!(v & OSC_RC32KEN_bm)) {
            m.rc32k_ready_at = XM_NEVER;
            OSC.STATUS &= (uint8_t)~OSC_RC32KRDY_bm;
        }
    } else if (off == 0x01) { /* STATUS is read-only */
    } else if (off == 0x10) { /* DFLLRC32M.CTRL */
        if ((v & DFLL_ENABLE_bm) && !(OSC.DFLLCTRL & OSC_RC32MCREF_bm) && !(OSC.STATUS & OSC_RC32KRDY_bm))
            m.dfll_early = true; /* the DFLL locks the 32 MHz RC to a reference that is not running yet */
        DFLLRC32M.CTRL = v;
    } else {
        xm_io[0x50 + off] = v;
    }
}

static uint64_t osc_next(xm_periph_t *p)
{
    (void)p;
    uint64_t t = XM_NEVER;
    if (!(OSC.STATUS & OSC_RC32MRDY_bm) && m.rc32m_ready_at < t)
        t = m.rc32m_ready_at;
    if (!(OSC.STATUS & OSC_RC32KRDY_bm) && m.rc32k_ready_at < t)
        t = m.rc32k_ready_at;
    return t;
}

static void osc_event(xm_periph_t *p)
{
    (void)p;
    if (xm_time >= m.rc32m_ready_at)
        OSC.STATUS |= OSC_RC32MRDY_bm;
    if (xm_time >= m.rc32k_ready_at)
        OSC.STATUS |= OSC_RC32KRDY_bm;
}

/* OSC (0x50) and DFLLRC32M (0x60) as one part. */
static xm_periph_t osc = {.base = 0x50, .size = 0x18, .write = osc_write, .next_event = osc_next, .event = osc_event};

static void clk_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    (void)p;
    if (off > 0x01) {
        xm_io[0x40 + off] = v;
        return;
    }
    if (!xm_ccp_open()) {
        xm_misuse("CLK register 0x%02x written without the CCP signature: ignored", off);
        return;
    }
    if (off == 0x00) {
        uint8_t sel = v & CLK_SCLKSEL_gm;
        bool ready = sel == CLK_SCLKSEL_RC2M_gc ? (OSC.STATUS & OSC_RC2MRDY_bm)
                     : sel == CLK_SCLKSEL_RC32M_gc ? (OSC.STATUS & OSC_RC32MRDY_bm)
                     : sel == CLK_SCLKSEL_RC32K_gc ? (OSC.STATUS & OSC_RC32KRDY_bm)
                                                   : false;
        if (!ready) {
            xm_misuse("system clock switched to source %u before it is ready: ignored", sel);
            return;
        }
    }
    xm_io[0x40 + off] = v;
}

static xm_periph_t clk = {.base = 0x40, .size = 0x08, .write = clk_write};

bool xm_dfll_enabled_early(void)
{
    return m.dfll_early;
}

/* ---- watchdog and resets ---- */

/* WDT.CTRL's period field: 8 ms << PER on the 1 kHz ULP oscillator; settings take 2-3 ULP cycles to sync. */
#define WDT_SYNC XM_MS(3)

static uint64_t wdt_period(void)
{
    return XM_MS(8) << ((WDT.CTRL & WDT_PER_gm) >> WDT_PER_gp);
}

static void wdt_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    (void)p;
    if (off == 0x02) /* STATUS is read-only */
        return;
    if (!xm_ccp_open()) {
        xm_misuse("WDT register 0x%02x written without the CCP signature: ignored", off);
        return;
    }
    if (!(v & WDT_CEN_bm))
        return; /* without the change enable bit nothing changes */
    if (xm_time < m.wdt_sync_until) {
        xm_misuse("WDT written while it synchronises the previous setting: ignored");
        return;
    }
    xm_io[0x80 + off] = (uint8_t)(v & ~WDT_CEN_bm);
    m.wdt_sync_until = xm_time + WDT_SYNC;
    m.wdt_deadline = (WDT.CTRL & WDT_ENABLE_bm) ? m.wdt_sync_until + wdt_period() : XM_NEVER;
}

static uint8_t wdt_read(xm_periph_t *p, uint16_t off)
{
    (void)p;
    if (off == 0x02)
        return xm_time < m.wdt_sync_until ? WDT_SYNCBUSY_bm : 0;
    return xm_io[0x80 + off];
}

static uint64_t wdt_next(xm_periph_t *p)
{
    (void)p;
    return m.fast_forward ? XM_NEVER : m.wdt_deadline;
}

static void wdt_event(xm_periph_t *p)
{
    (void)p;
    xm_restart(XM_RESTART_WATCHDOG);
}

static xm_periph_t wdt = {.base = 0x80, .size = 0x08, .read = wdt_read, .write = wdt_write, .next_event = wdt_next,
                          .event = wdt_event};

void xm_wdr(void)
{
    advance_to(xm_time + 1u);
    if (m.wdt_deadline != XM_NEVER)
        m.wdt_deadline = xm_time + wdt_period();
    xm_changed();
}

static void rst_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    (void)p;
    if (off == 0x00) { /* STATUS: a 1 clears a flag */
        RST.STATUS &= (uint8_t)~v;
        return;
    }
    if (!xm_ccp_open()) {
        xm_misuse("RST.CTRL written without the CCP signature: ignored");
        return;
    }
    if (v & RST_SWRST_bm)
        xm_restart(XM_RESTART_SOFTWARE);
}

static xm_periph_t rst = {.base = 0x78, .size = 0x08, .write = rst_write};

/* ---- power-on and resets ---- */

static void registers_on(bool cold)
{
    uint8_t rst_status = RST.STATUS;
    memset(xm_io, 0, sizeof xm_io);
    memset(m.by_addr, 0, sizeof m.by_addr);
    m.periphs = 0;
    m.sources = 0;
    m.ccp_window = 0;
    m.sei_delay = false;
    m.rc32m_ready_at = m.rc32k_ready_at = XM_NEVER;
    m.wdt_deadline = XM_NEVER;
    m.wdt_sync_until = 0;
    OSC.CTRL = OSC_RC2MEN_bm;
    OSC.STATUS = OSC_RC2MRDY_bm;
    RST.STATUS = cold ? RST_PORF_bm : rst_status;
    xm_attach(&cpu);
    xm_attach(&clk);
    xm_attach(&osc);
    xm_attach(&rst);
    xm_attach(&wdt);
    xm_attach(&pmic);
}

static bool cold_start;

bool xm_cold(void)
{
    return cold_start;
}

static void parts_on(void)
{
    xm_port_power_on();
    xm_tc_power_on();
    xm_usart_power_on();
    xm_adc_power_on();
    xm_twi_power_on();
    xm_nvm_power_on();
}

void xm_power_on(void)
{
    memset(&m, 0, sizeof m);
    xm_changed();
    xm_time = 0;
    m.horizon = XM_NEVER;
    m.irq_ms = 0;
    cold_start = true;
    registers_on(true);
    parts_on();
    cold_start = false;
}

void xm_on_restart(void (*fn)(uint8_t why))
{
    m.on_restart = fn;
}

uint32_t xm_restarts(uint8_t why)
{
    return why < 4 ? m.restarts[why] : 0;
}

uint64_t xm_last_restart_at(void)
{
    return m.restart_at;
}

void xm_restart(uint8_t why)
{
    m.restarts[why]++;
    m.restart_at = xm_time;
    xm_changed();
    if (why != XM_RESTART_JUMP_TO_0) {
        registers_on(false);
        parts_on();
        RST.STATUS |= why == XM_RESTART_WATCHDOG ? RST_WDRF_bm : RST_SRF_bm;
    }
    if (m.on_restart)
        m.on_restart(why);
}
