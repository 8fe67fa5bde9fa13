#include "uart.h"

#include "hal/hal.h"

/* Single-producer single-consumer rings with one-byte indices (atomic on an 8-bit MCU): the interrupt
 * owns one index, the main loop the other, so neither side needs to mask interrupts. One slot stays free
 * to tell full from empty. */
_Static_assert(UART_RX_SIZE == 256u && UART_TX_SIZE == 256u, "indices wrap by themselves at 256");

static uint8_t rx_buf[UART_RX_SIZE];
static volatile uint8_t rx_head; /* written by the ISR */
static volatile uint8_t rx_tail;
static volatile uint16_t rx_lost;

uint8_t uart_tx_buf[UART_TX_SIZE];
#define tx_buf uart_tx_buf
static volatile uint8_t tx_head;
static volatile uint8_t tx_tail; /* written by the ISR */

void uart_init(void)
{
    rx_head = rx_tail = 0;
    rx_lost = 0;
    tx_head = tx_tail = 0;
}

void uart_rx_isr(uint8_t byte)
{
    uint8_t next = (uint8_t)(rx_head + 1u);
    if (next == rx_tail) {
        rx_lost++;
        return;
    }
    rx_buf[rx_head] = byte;
    rx_head = next;
}

void uart_rx_error_isr(uint8_t errors)
{
    (void)errors; /* an overrun lost bytes before the next one, a frame error loses that byte: one each, at least */
    rx_lost++;
}

bool uart_getc(uint8_t *byte)
{
    uint8_t t = rx_tail;
    if (t == rx_head)
        return false;
    *byte = rx_buf[t];
    rx_tail = (uint8_t)(t + 1u);
    return true;
}

bool uart_rx_waiting(void)
{
    return rx_tail != rx_head;
}

uint8_t uart_read(uint8_t *dst, uint8_t max)
{
    uint8_t t = rx_tail;
    uint8_t n = 0;
    uint8_t h = rx_head;
    while (n < max && t != h) {
        dst[n++] = rx_buf[t];
        t = (uint8_t)(t + 1u);
    }
    rx_tail = t;
    return n;
}

uint8_t uart_tx_backlog(void)
{
    return (uint8_t)(tx_head - tx_tail);
}

uint16_t uart_tx_free(void)
{
    return (uint8_t)(tx_tail - tx_head - 1u);
}

uint8_t uart_tx_begin(void)
{
    return tx_head;
}

void uart_tx_commit(uint8_t pos)
{
    tx_head = pos;
}

void uart_tx_flush(void)
{
    hal_uart_tx_kick();
}

int16_t uart_tx_isr(void)
{
    uint8_t t = tx_tail;
    if (t == tx_head)
        return -1;
    uint8_t b = tx_buf[t];
    tx_tail = (uint8_t)(t + 1u);
    return b;
}

uint16_t uart_rx_overflows(void)
{
    uint8_t s = hal_irq_save();
    uint16_t n = rx_lost;
    hal_irq_restore(s);
    return n;
}
