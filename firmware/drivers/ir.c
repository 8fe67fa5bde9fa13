#include "ir.h"

#include <string.h>

static hal_ir_msg_t rx_msg[IR_RX_QUEUE];
static uint8_t rx_side[IR_RX_QUEUE];
static volatile uint8_t rx_head, rx_count;
static uint8_t rx_tail;

void ir_init(void)
{
    rx_head = rx_tail = rx_count = 0;
}

void ir_rx_isr(uint8_t side, const hal_ir_msg_t *msg)
{
    if (rx_count >= IR_RX_QUEUE || side > 1) /* beacons repeat: a lost one is soon heard again */
        return;
    memcpy(&rx_msg[rx_head], msg, sizeof *msg);
    if (rx_msg[rx_head].len > HAL_IR_PAYLOAD_MAX)
        rx_msg[rx_head].len = HAL_IR_PAYLOAD_MAX;
    rx_side[rx_head] = side;
    rx_head = (uint8_t)((rx_head + 1u) % IR_RX_QUEUE);
    rx_count++;
}

const hal_ir_msg_t *ir_peek(uint8_t *side)
{
    if (rx_count == 0)
        return NULL;
    *side = rx_side[rx_tail];
    return &rx_msg[rx_tail]; /* the interrupt writes only the free slots */
}

void ir_pop(void)
{
    rx_tail = (uint8_t)((rx_tail + 1u) % IR_RX_QUEUE);
    uint8_t s = hal_irq_save();
    rx_count--;
    hal_irq_restore(s);
}

bool ir_transmit(const hal_ir_msg_t *msg)
{
    return hal_ir_send(msg);
}
