/**
 * \file uart.h
 * Host link driver: receive and transmit circular buffers filled and drained by the USART interrupts
 * (thesis 6.2.2). Nothing here blocks.
 */
#ifndef UART_H
#define UART_H

#include <stdbool.h>
#include <stdint.h>

#define UART_RX_SIZE 256u /* one-byte indices: atomic on an 8-bit MCU */
#define UART_TX_SIZE 256u

void uart_init(void);

/** Takes one received byte. \return false when none is waiting. */
bool uart_getc(uint8_t *byte);

/** \return true when received bytes wait. */
bool uart_rx_waiting(void);

/** Takes up to `max` received bytes into `dst`. \return how many. */
uint8_t uart_read(uint8_t *dst, uint8_t max);

/** \return bytes queued for transmission that the interrupt has not sent yet. */
uint8_t uart_tx_backlog(void);

/** \return the number of bytes that can be queued for transmission now. */
uint16_t uart_tx_free(void);

/** A writer for framers that produce bytes one by one: uart_tx_begin() gives the write position,
 *  uart_tx_store() appends at it, uart_tx_commit() publishes everything stored to the interrupt at once.
 *  The caller checked uart_tx_free() for all of it. */
uint8_t uart_tx_begin(void);
void uart_tx_commit(uint8_t pos);
extern uint8_t uart_tx_buf[UART_TX_SIZE];
/** \return the position after `byte` */
static inline uint8_t uart_tx_store(uint8_t pos, uint8_t byte)
{
    uart_tx_buf[pos] = byte;
    return (uint8_t)(pos + 1u);
}

/** Starts the transmitter on what was queued. */
void uart_tx_flush(void);

/** \return bytes lost on receive since reset: to a full receive buffer, or by the USART itself (an overrun, or
 *  a frame error, whose byte is dropped; each counts one though an overrun may lose more). */
uint16_t uart_rx_overflows(void);

#endif
