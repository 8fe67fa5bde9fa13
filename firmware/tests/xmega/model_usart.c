/**
 * \file model_usart.c
 * USARTC0 (host link), USARTD0 (IR transmitter and front receiver) and USARTD1 (rear IR receiver) of the model.
 *
 * Asynchronous frames only: 1 start bit, 5..9 data bits, optional parity, 1 or 2 stop bits, at the baud rate
 * BAUDCTRLA/B and CLK2X give. Transmitter: DATA goes to the shift register when it is idle, else to the one-byte
 * buffer (DREIF clears until the buffer moves on); TXCIF when the last frame's stop bit ends and nothing waits.
 * Receiver: a two-level FIFO plus the shift register; a frame that finds all three full replaces the one in the
 * shift register and sets BUFOVF; FERR marks a frame with a bad stop bit, or one sent at a baud rate more than
 * 3 % off. RXCIF is set while the FIFO holds a frame and cleared by reading DATA. Every transmitted frame is
 * logged with its times, and the IR transmitter's LEDs and carrier (USARTD0) at its start and end.
 * Not modelled: synchronous and SPI modes, multi-processor mode, IrDA (IRCOM), receiver noise filtering.
 */
#include <stdlib.h>
#include <string.h>

#include "model_internal.h"

typedef struct {
    uint64_t at, bit_cycles;
    uint16_t data;
    bool ferr;
} arrival_t;

typedef struct {
    xm_periph_t p;
    char port;
    uint8_t rx_pin, tx_pin, vec_rxc;
    bool tx_busy, buf_full;
    uint64_t tx_start, tx_end;
    uint16_t tx_data, buf_data;
    uint8_t tx_bits;
    uint32_t tx_aux;
    struct {
        uint16_t data;
        uint8_t flags; /* FERR, BUFOVF as in STATUS */
    } fifo[3];
    uint8_t fifo_n;
    arrival_t *in;
    uint32_t in_head, in_n, in_cap;
    uint64_t send_free_at;
    int8_t echo_to[XM_USARTS]; /* USARTs whose RX also receives what this one transmits */
    xm_frame_t *log;
    uint32_t log_n, log_cap, taken;
} usart_t;

static usart_t us[XM_USARTS];

static void arrive(usart_t *u, arrival_t a);

static uint8_t reg(const usart_t *u, uint16_t off)
{
    return xm_io[u->p.base + off];
}

double xm_usart_bit_cycles(uint8_t n)
{
    if (n >= XM_USARTS)
        return 0;
    const usart_t *u = &us[n];
    uint16_t bsel = (uint16_t)(reg(u, 0x06) | (reg(u, 0x07) & 0x0Fu) << 8);
    int8_t bscale = (int8_t)(reg(u, 0x07) >> 4);
    if (bscale > 7)
        bscale = (int8_t)(bscale - 16);
    double per_bit = (reg(u, 0x04) & USART_CLK2X_bm) ? 8.0 : 16.0;
    double clocks = bscale >= 0 ? per_bit * (double)(1u << bscale) * (bsel + 1.0)
                                : per_bit * ((double)bsel / (double)(1u << -bscale) + 1.0);
    return clocks * (double)XM_HZ / xm_cpu_hz();
}

static uint8_t data_bits(const usart_t *u)
{
    uint8_t c = reg(u, 0x05) & USART_CHSIZE_gm;
    return c == USART_CHSIZE_9BIT_gc ? 9u : (uint8_t)(5u + (c & 3u));
}

static uint8_t frame_bits(const usart_t *u)
{
    uint8_t c = reg(u, 0x05);
    return (uint8_t)(1u + data_bits(u) + ((c & USART_PMODE_gm) ? 1u : 0u) + ((c & USART_SBMODE_bm) ? 2u : 1u));
}

uint32_t xm_ir_state(void)
{
    uint8_t dir = PORTC.DIR, out = PORTC.OUT;
    return (uint32_t)((dir & out) >> 4) | (uint32_t)xm_tc_carrier_duty() << 8;
}

static uint32_t aux(const usart_t *u)
{
    return u == &us[XM_USARTD0] ? xm_ir_state() : 0;
}

static void tx_start(usart_t *u, uint16_t data)
{
    u->tx_busy = true;
    u->tx_data = data;
    u->tx_bits = data_bits(u);
    u->tx_start = xm_time;
    u->tx_end = xm_time + (uint64_t)(xm_usart_bit_cycles((uint8_t)(u - us)) * frame_bits(u) + 0.5);
    u->tx_aux = aux(u);
}

static void log_frame(usart_t *u)
{
    if (u->log_n == u->log_cap) {
        u->log_cap = u->log_cap ? 2u * u->log_cap : 256u;
        u->log = realloc(u->log, u->log_cap * sizeof *u->log);
    }
    u->log[u->log_n++] = (xm_frame_t){.start = u->tx_start, .end = u->tx_end, .data = u->tx_data,
                                      .bits = u->tx_bits, .aux_start = u->tx_aux, .aux_end = aux(u)};
    double bit = xm_usart_bit_cycles((uint8_t)(u - us));
    for (uint8_t n = 0; n < XM_USARTS; n++)
        if (u->echo_to[n])
            arrive(&us[n], (arrival_t){.at = u->tx_end, .bit_cycles = (uint64_t)(bit + 0.5), .data = u->tx_data});
}

static void receive(usart_t *u, const arrival_t *a)
{
    if (!(reg(u, 0x04) & USART_RXEN_bm))
        return;
    double ours = xm_usart_bit_cycles((uint8_t)(u - us));
    bool baud_off = ours <= 0 || a->bit_cycles < ours * 0.97 || a->bit_cycles > ours * 1.03;
    uint8_t flags = (a->ferr || baud_off) ? USART_FERR_bm : 0;
    uint16_t mask = (uint16_t)((1u << data_bits(u)) - 1u);
    if (u->fifo_n < 3) {
        u->fifo[u->fifo_n].data = (uint16_t)(a->data & mask);
        u->fifo[u->fifo_n++].flags = flags;
    } else { /* FIFO and shift register full: the frame in the shift register is lost */
        u->fifo[2].data = (uint16_t)(a->data & mask);
        u->fifo[2].flags = (uint8_t)(flags | USART_BUFOVF_bm);
    }
}

static uint8_t status(const usart_t *u)
{
    uint8_t s = reg(u, 0x01) & USART_TXCIF_bm;
    if (u->fifo_n) {
        s |= USART_RXCIF_bm | u->fifo[0].flags;
        if (u->fifo[0].data & 0x100u)
            s |= USART_RXB8_bm;
    }
    if (!u->buf_full)
        s |= USART_DREIF_bm;
    return s;
}

static uint8_t usart_read(xm_periph_t *p, uint16_t off)
{
    usart_t *u = (usart_t *)p;
    if (off == 0x01)
        return status(u);
    if (off != 0x00)
        return xm_io[p->base + off];
    if (!u->fifo_n)
        return xm_io[p->base]; /* an empty FIFO reads the last frame again */
    uint8_t v = (uint8_t)u->fifo[0].data;
    xm_io[p->base] = v;
    memmove(&u->fifo[0], &u->fifo[1], 2 * sizeof u->fifo[0]);
    u->fifo_n--;
    return v;
}

static void usart_write(xm_periph_t *p, uint16_t off, uint8_t v)
{
    usart_t *u = (usart_t *)p;
    switch (off) {
    case 0x00: {
        if (!(reg(u, 0x04) & USART_TXEN_bm)) {
            xm_misuse("USART at 0x%03x: DATA written with the transmitter off", p->base);
            return;
        }
        uint16_t data = (uint16_t)(v | ((reg(u, 0x04) & USART_TXB8_bm) ? 0x100u : 0u));
        if (!u->tx_busy)
            tx_start(u, data);
        else if (!u->buf_full) {
            u->buf_full = true;
            u->buf_data = data;
        } else
            xm_misuse("USART at 0x%03x: DATA written while DREIF is clear: the byte is lost", p->base);
        return;
    }
    case 0x01: /* STATUS: only TXCIF is cleared by a 1 */
        xm_io[p->base + 1] &= (uint8_t)~(v & USART_TXCIF_bm);
        return;
    default:
        xm_io[p->base + off] = v;
    }
    if (off == 0x04) {
        if (v & USART_RXEN_bm)
            xm_pin_use(u->port, u->rx_pin, XM_USE_USART_RX);
        if (v & USART_TXEN_bm)
            xm_pin_use(u->port, u->tx_pin, XM_USE_USART_TX);
    }
}

static uint64_t usart_next(xm_periph_t *p)
{
    usart_t *u = (usart_t *)p;
    uint64_t t = u->tx_busy ? u->tx_end : XM_NEVER;
    if (u->in_head < u->in_n && u->in[u->in_head].at < t)
        t = u->in[u->in_head].at;
    return t;
}

static void usart_event(xm_periph_t *p)
{
    usart_t *u = (usart_t *)p;
    if (u->tx_busy && u->tx_end <= xm_time) {
        log_frame(u);
        if (u->buf_full) {
            u->buf_full = false;
            tx_start(u, u->buf_data);
        } else {
            u->tx_busy = false;
            xm_io[p->base + 1] |= USART_TXCIF_bm;
        }
        return;
    }
    if (u->in_head < u->in_n && u->in[u->in_head].at <= xm_time) {
        receive(u, &u->in[u->in_head++]);
        if (u->in_head == u->in_n)
            u->in_head = u->in_n = 0;
    }
}

/* Interrupt sources: which 0 RXC, 1 DRE, 2 TXC. */
static uint8_t usart_level(void *ctx, uint8_t which)
{
    usart_t *u = ctx;
    uint8_t a = reg(u, 0x03);
    if (which == 0)
        return u->fifo_n ? xm_level_at(a, 4) : 0;
    if (which == 1)
        return !u->buf_full ? xm_level_at(a, 0) : 0;
    return (reg(u, 0x01) & USART_TXCIF_bm) ? xm_level_at(a, 2) : 0;
}

static void usart_ack(void *ctx, uint8_t which)
{
    usart_t *u = ctx;
    if (which == 2)
        xm_io[u->p.base + 1] &= (uint8_t)~USART_TXCIF_bm;
}

static void arrive(usart_t *u, arrival_t a)
{
    if (u->in_n == u->in_cap) {
        u->in_cap = u->in_cap ? 2u * u->in_cap : 256u;
        u->in = realloc(u->in, u->in_cap * sizeof *u->in);
    }
    uint32_t i = u->in_n++;
    while (i > u->in_head && u->in[i - 1].at > a.at) {
        u->in[i] = u->in[i - 1];
        i--;
    }
    u->in[i] = a;
    xm_changed();
}

void xm_usart_rx_at(uint8_t n, uint16_t data, uint64_t at, bool frame_error)
{
    if (n >= XM_USARTS)
        return;
    double bit = xm_usart_bit_cycles(n);
    arrive(&us[n], (arrival_t){.at = at, .bit_cycles = (uint64_t)(bit + 0.5), .data = data, .ferr = frame_error});
}

uint64_t xm_usart_send(uint8_t n, const uint8_t *bytes, uint32_t count, uint32_t baud, uint64_t start)
{
    if (n >= XM_USARTS || baud == 0)
        return start;
    usart_t *u = &us[n];
    double bit = (double)XM_HZ / baud;
    double t = (double)(start > u->send_free_at ? start : u->send_free_at);
    for (uint32_t i = 0; i < count; i++) {
        t += 10.0 * bit;
        arrive(u, (arrival_t){.at = (uint64_t)t, .bit_cycles = (uint64_t)(bit + 0.5), .data = bytes[i]});
    }
    u->send_free_at = (uint64_t)t;
    return u->send_free_at;
}

void xm_usart_echo(uint8_t from, uint8_t to, bool on)
{
    if (from < XM_USARTS && to < XM_USARTS)
        us[from].echo_to[to] = on;
}

uint32_t xm_usart_tx_count(uint8_t n)
{
    return n < XM_USARTS ? us[n].log_n : 0;
}

const xm_frame_t *xm_usart_tx_frame(uint8_t n, uint32_t i)
{
    return n < XM_USARTS && i < us[n].log_n ? &us[n].log[i] : NULL;
}

uint32_t xm_usart_take(uint8_t n, uint8_t *dst, uint32_t max)
{
    if (n >= XM_USARTS)
        return 0;
    usart_t *u = &us[n];
    uint32_t k = 0;
    while (k < max && u->taken < u->log_n)
        dst[k++] = (uint8_t)u->log[u->taken++].data;
    return k;
}

static void usart_on(uint8_t n, uint16_t base, char port, uint8_t rx_pin, uint8_t vec_rxc)
{
    usart_t *u = &us[n];
    if (xm_cold()) {
        free(u->in);
        free(u->log);
        memset(u, 0, sizeof *u);
    }
    u->p = (xm_periph_t){.base = base, .size = 0x08, .read = usart_read, .write = usart_write,
                         .next_event = usart_next, .event = usart_event};
    u->port = port;
    u->rx_pin = rx_pin;
    u->tx_pin = (uint8_t)(rx_pin + 1u);
    u->vec_rxc = vec_rxc;
    u->tx_busy = u->buf_full = false;
    u->fifo_n = 0;
    xm_attach(&u->p);
    for (uint8_t w = 0; w < 3; w++)
        xm_irq_source((uint8_t)(vec_rxc + w), usart_level, usart_ack, u, w);
}

void xm_usart_power_on(void)
{
    usart_on(XM_USARTC0, 0x8A0, 'C', 2, USARTC0_RXC_vect_num);
    usart_on(XM_USARTD0, 0x9A0, 'D', 2, USARTD0_RXC_vect_num);
    usart_on(XM_USARTD1, 0x9B0, 'D', 6, USARTD1_RXC_vect_num);
}
