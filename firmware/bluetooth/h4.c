#include "h4.h"

#include "core/data.h"
#include "drivers/uart.h"

h4_event_t h4_event;
h4_acl_t h4_acl;

enum { S_TYPE, S_HEADER, S_PAYLOAD };

static struct {
    uint8_t state;
    uint8_t type;
    uint8_t got;       /* header bytes so far */
    uint8_t hdr[4];
    uint16_t need;     /* payload bytes still to come */
    uint8_t *dst;      /* where payload bytes go (NULL: skipped) */
    uint32_t last_ms;  /* when the packet in progress last got a byte */
} rd;

static uint8_t tx_pos;

void h4_init(void)
{
    rd.state = S_TYPE;
    rd.got = 0;
}

bool h4_flush(void)
{
    uint8_t b;
    bool any = false;
    while (uart_getc(&b))
        any = true;
    h4_init();
    return any;
}

bool h4_rx_busy(void)
{
    return rd.state != S_TYPE || uart_rx_waiting();
}

bool h4_stalled(uint32_t now_ms)
{
    return rd.state != S_TYPE && now_ms - rd.last_ms > H4_PACKET_TIMEOUT_MS;
}

void h4_acl_into(uint8_t *dst)
{
    rd.dst = dst;
}

/* The header is complete: how long is the payload, and is that possible? */
static h4_result_t header_done(void)
{
    rd.state = S_PAYLOAD;
    if (rd.type == H4_EVENT) {
        h4_event.code = rd.hdr[0];
        h4_event.len = rd.hdr[1] > H4_EVENT_MAX ? H4_EVENT_MAX : rd.hdr[1];
        h4_event.truncated = rd.hdr[1] > H4_EVENT_MAX;
        rd.need = rd.hdr[1];
        rd.dst = h4_event.params;
        return H4_NONE;
    }
    h4_acl.handle = (uint16_t)(rd.hdr[0] | ((rd.hdr[1] & 0x0Fu) << 8));
    h4_acl.pb = (uint8_t)((rd.hdr[1] >> 4) & 3u);
    h4_acl.len = (uint16_t)(rd.hdr[2] | (rd.hdr[3] << 8));
    if (h4_acl.len > BT_ACL_RX_MAX) {
        h4_init();
        return H4_ERROR;
    }
    rd.need = h4_acl.len;
    rd.dst = NULL;
    return H4_ACL_HEADER;
}

/* The payload is complete. */
static h4_result_t payload_done(void)
{
    rd.state = S_TYPE;
    return rd.type == H4_EVENT ? H4_EVENT_READY : H4_ACL_READY;
}

h4_result_t h4_read(uint8_t *budget)
{
    while (*budget) {
        if (rd.state == S_PAYLOAD) {
            if (rd.need == 0)
                return payload_done();
            /* Payload bytes go in bulk: straight into their buffer (events: the first H4_EVENT_MAX). */
            uint8_t room = rd.need > *budget ? *budget : (uint8_t)rd.need;
            uint8_t n;
            if (rd.type == H4_EVENT && rd.dst) {
                uint8_t space = (uint8_t)(h4_event.params + H4_EVENT_MAX - rd.dst);
                if (space == 0)
                    rd.dst = NULL; /* the rest of a long event is skipped */
                else if (room > space)
                    room = space;
            }
            uint8_t skip[8];
            uint8_t *to = rd.dst;
            if (!to) {
                to = skip;
                if (room > sizeof skip)
                    room = sizeof skip;
            }
            n = uart_read(to, room);
            if (rd.dst)
                rd.dst += n;
            if (n == 0)
                return H4_NONE;
            rd.last_ms = robot_state.time.time_ms;
            *budget = (uint8_t)(*budget - n);
            rd.need = (uint16_t)(rd.need - n);
            continue;
        }
        uint8_t b;
        if (!uart_getc(&b))
            return H4_NONE;
        (*budget)--;
        rd.last_ms = robot_state.time.time_ms;
        if (rd.state == S_TYPE) {
            if (b != H4_EVENT && b != H4_ACL)
                return H4_ERROR;
            rd.type = b;
            rd.got = 0;
            rd.state = S_HEADER;
            continue;
        }
        rd.hdr[rd.got++] = b;
        if (rd.got == (rd.type == H4_EVENT ? 2u : 4u)) {
            h4_result_t r = header_done();
            if (r != H4_NONE)
                return r;
        }
    }
    return H4_NONE;
}

/* ---- writer: behind the published end of the transmit ring, published at h4_tx_end() ---- */

uint16_t h4_tx_room(void)
{
    return uart_tx_free();
}

uint8_t h4_tx_backlog(void)
{
    return uart_tx_backlog();
}

void h4_tx_begin(void)
{
    tx_pos = uart_tx_begin();
}

void h4_tx_byte(uint8_t b)
{
    tx_pos = uart_tx_store(tx_pos, b);
}

static void h4_tx_u16(uint16_t v)
{
    tx_pos = uart_tx_store(tx_pos, (uint8_t)v);
    tx_pos = uart_tx_store(tx_pos, (uint8_t)(v >> 8));
}

/* The hot loop of everything sent: runs up to the ring's end, pointer to pointer (7 cycles a byte on the AVR,
 * against 14 indexing the ring). */
void h4_tx_bytes(const uint8_t *p, uint16_t n)
{
    uint8_t pos = tx_pos;
    tx_pos = (uint8_t)(pos + n);
    while (n) {
        uint16_t run = (uint16_t)(UART_TX_SIZE - pos);
        if (run > n)
            run = n;
        n = (uint16_t)(n - run);
        uint8_t *d = uart_tx_buf + pos;
        pos = (uint8_t)(pos + run);
        do
            *d++ = *p++;
        while (--run);
    }
}

void h4_tx_zeros(uint16_t n)
{
    uint8_t pos = tx_pos;
    while (n--)
        uart_tx_buf[pos++] = 0;
    tx_pos = pos;
}

void h4_tx_end(void)
{
    uart_tx_commit(tx_pos);
    uart_tx_flush();
}

void h4_command(uint16_t opcode, const uint8_t *params, uint8_t len)
{
    h4_tx_begin();
    h4_tx_byte(H4_COMMAND);
    h4_tx_u16(opcode);
    h4_tx_byte(len);
    h4_tx_bytes(params, len);
    h4_tx_end();
}
