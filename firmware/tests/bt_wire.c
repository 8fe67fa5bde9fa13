#include "bt_wire.h"

#include <stdio.h>
#include <string.h>

#include "bluetooth/h4.h"
#include "bluetooth/hci.h"
#include "bluetooth/l2cap.h"
#include "bluetooth/rfcomm.h"
#include "core/data.h"
#include "drivers/eeprom.h"
#include "drivers/uart.h"
#include "bt_live.h"
#include "hal/hal.h"

wire_packet_t wire_out[256];
int wire_out_count;
wire_up_t wire_up;

/* ---- the HAL the stack's drivers use ---- */

static uint8_t eeprom[HAL_EEPROM_SIZE];

void hal_uart_tx_kick(void)
{
}

uint8_t hal_irq_save(void)
{
    return 0;
}

void hal_irq_restore(uint8_t saved)
{
    (void)saved;
}

void hal_eeprom_read(uint16_t addr, void *dst, uint16_t len)
{
    memcpy(dst, eeprom + addr, len);
}

bool hal_eeprom_busy(void)
{
    return false;
}

void hal_eeprom_write_page(uint16_t addr, const void *src, uint8_t len)
{
    memcpy(eeprom + addr, src, len);
}

/* ---- the robot ---- */

bool wire_echo;

void wire_reset(void)
{
    memset(eeprom, 0xFF, sizeof eeprom);
    memset(&robot_state, 0, sizeof robot_state);
    memset(&settings, 0, sizeof settings);
    memset(&wire_up, 0, sizeof wire_up);
    wire_uart_bytes_per_ms = 0;
    settings.identity.robot_id = 7;
    uart_init();
    eeprom_init();
    hci_init();
    l2cap_init();
    rfcomm_init();
    wire_clear();
}

int wire_uart_bytes_per_ms = 0;

static void parse_byte(uint8_t b);

static void tick(void)
{
    robot_state.time.time_ms++;
    hci_task();
    l2cap_task();
    rfcomm_task();
    eeprom_task();
    int16_t b;
    for (int k = 0; k < wire_uart_bytes_per_ms && (b = uart_tx_isr()) >= 0; k++)
        parse_byte((uint8_t)b);
}

void wire_run_ms(int ms)
{
    while (ms-- > 0)
        tick();
    for (int k = 0; k < 100 && h4_rx_busy(); k++) /* and until what was fed is read (HCI_RX_BUDGET a tick) */
        tick();
}

/* ---- controller to robot ---- */

void wire_feed(const uint8_t *p, uint16_t n)
{
    while (n--)
        uart_rx_isr(*p++);
}

void wire_event(uint8_t code, const uint8_t *params, uint8_t n)
{
    uint8_t h[3] = {H4_EVENT, code, n};
    wire_feed(h, 3);
    wire_feed(params, n);
}

void wire_command_complete(uint16_t opcode, const uint8_t *ret, uint8_t n)
{
    uint8_t p[64] = {1, (uint8_t)opcode, (uint8_t)(opcode >> 8), 0};
    if (n)
        memcpy(p + 4, ret, n);
    wire_event(0x0E, p, (uint8_t)(4 + n));
}

void wire_acl(uint16_t handle, uint8_t pb, const uint8_t *p, uint16_t n)
{
    uint16_t hf = (uint16_t)(handle | (pb << 12));
    uint8_t h[5] = {H4_ACL, (uint8_t)hf, (uint8_t)(hf >> 8), (uint8_t)n, (uint8_t)(n >> 8)};
    wire_feed(h, 5);
    wire_feed(p, n);
}

void wire_l2cap(uint16_t handle, uint16_t cid, const uint8_t *p, uint16_t n)
{
    uint8_t pdu[600] = {(uint8_t)n, (uint8_t)(n >> 8), (uint8_t)cid, (uint8_t)(cid >> 8)};
    memcpy(pdu + 4, p, n);
    wire_acl(handle, 2, pdu, (uint16_t)(n + 4));
}

/* ---- robot to controller ---- */

static struct {
    uint8_t buf[400];
    uint16_t got, need;
    bool body; /* the header was read: need counts the whole packet */
} parse;

static void parsed(void)
{
    if (wire_out_count >= (int)(sizeof wire_out / sizeof wire_out[0]))
        return;
    wire_packet_t *w = &wire_out[wire_out_count++];
    const uint8_t *b = parse.buf;
    w->type = b[0];
    if (b[0] == H4_COMMAND) {
        w->opcode = (uint16_t)(b[1] | (b[2] << 8));
        w->len = b[3];
        memcpy(w->data, b + 4, w->len > sizeof w->data ? sizeof w->data : w->len);
    } else {
        w->handle = (uint16_t)(b[1] | (b[2] << 8));
        w->len = (uint16_t)(b[3] | (b[4] << 8));
        memcpy(w->data, b + 5, w->len > sizeof w->data ? sizeof w->data : w->len);
    }
}

static void parse_byte(uint8_t b)
{
    if (parse.got < sizeof parse.buf)
        parse.buf[parse.got] = b;
    parse.got++;
    if (parse.got == 1) {
        parse.need = b == H4_COMMAND ? 4 : 5;
        parse.body = false;
        return;
    }
    if (parse.got < parse.need)
        return;
    if (!parse.body) {
        uint16_t len = parse.buf[0] == H4_COMMAND ? parse.buf[3] : (uint16_t)(parse.buf[3] | (parse.buf[4] << 8));
        parse.need = (uint16_t)(parse.need + len);
        parse.body = true;
        if (len)
            return;
    }
    parsed();
    parse.got = 0;
}

int wire_collect(void)
{
    int16_t b;
    while ((b = uart_tx_isr()) >= 0)
        parse_byte((uint8_t)b);
    return wire_out_count;
}

static int answered; /* commands of wire_out answered by wire_answer_commands() */

void wire_clear(void)
{
    wire_collect();
    wire_out_count = 0;
    answered = 0;
}

const wire_packet_t *wire_find_command(uint16_t opcode, int n)
{
    wire_collect();
    for (int i = 0; i < wire_out_count; i++)
        if (wire_out[i].type == H4_COMMAND && wire_out[i].opcode == opcode && n-- == 0)
            return &wire_out[i];
    return NULL;
}

const uint8_t *wire_find_l2cap(uint16_t handle, uint16_t cid, int n, uint16_t *len)
{
    static uint8_t pdu[1024];
    uint16_t got = 0, total = 0;
    wire_collect();
    for (int i = 0; i < wire_out_count; i++) {
        const wire_packet_t *w = &wire_out[i];
        if (w->type != H4_ACL || (w->handle & 0x0FFF) != handle)
            continue;
        if (((w->handle >> 12) & 3) != 1)
            got = 0;
        memcpy(pdu + got, w->data, w->len);
        got = (uint16_t)(got + w->len);
        if (got < 4)
            continue;
        total = (uint16_t)(4 + (pdu[0] | (pdu[1] << 8)));
        if (got < total)
            continue;
        got = 0;
        if ((pdu[2] | (pdu[3] << 8)) == cid && n-- == 0) {
            *len = (uint16_t)(total - 4);
            return pdu + 4;
        }
    }
    return NULL;
}

/* ---- a controller that answers what a Bumble controller would ---- */

void wire_answer_commands(uint16_t acl_mtu, uint16_t acl_count)
{
    wire_collect();
    for (; answered < wire_out_count; answered++) {
        const wire_packet_t *w = &wire_out[answered];
        if (w->type != H4_COMMAND)
            continue;
        if (w->opcode == 0x1005) { /* Read_Buffer_Size */
            uint8_t r[7] = {(uint8_t)acl_mtu, (uint8_t)(acl_mtu >> 8), 0, (uint8_t)acl_count,
                            (uint8_t)(acl_count >> 8), 0, 0};
            wire_command_complete(w->opcode, r, 7);
        } else if (w->opcode == 0x1009) { /* Read_BD_ADDR */
            static const uint8_t addr[6] = {0x0F, 0x0E, 0x0D, 0x0C, 0x0B, 0x0A};
            wire_command_complete(w->opcode, addr, 6);
        } else if ((w->opcode >> 10) == 0x01) { /* link control: Command Status */
            uint8_t s[4] = {0, 1, (uint8_t)w->opcode, (uint8_t)(w->opcode >> 8)};
            wire_event(0x0F, s, 4);
        } else {
            wire_command_complete(w->opcode, NULL, 0);
        }
    }
}

void wire_bring_up(uint16_t acl_mtu, uint16_t acl_count)
{
    wire_reset();
    answered = 0;
    for (int i = 0; i < 40 && !hci_ready(); i++) {
        wire_run_ms(1);
        wire_answer_commands(acl_mtu, acl_count);
    }
    wire_run_ms(1);
    wire_clear();
    answered = 0;
}

void wire_connect(const uint8_t addr[6], uint16_t handle)
{
    uint8_t req[10] = {0};
    memcpy(req, addr, 6);
    req[9] = 0x01;
    wire_event(0x04, req, 10);
    wire_run_ms(1);
    wire_collect();
    answered = wire_out_count; /* the accept is answered here */
    uint8_t st[4] = {0, 1, 0x09, 0x04};
    wire_event(0x0F, st, 4);
    uint8_t done[11] = {0, (uint8_t)handle, (uint8_t)(handle >> 8)};
    memcpy(done + 3, addr, 6);
    done[9] = 0x01;
    wire_event(0x03, done, 11);
    wire_run_ms(1);
}

uint16_t wire_open_l2cap(uint16_t handle, uint16_t psm, uint16_t scid, uint16_t mtu)
{
    static uint8_t id = 0x20;
    int before = wire_collect();
    uint8_t req[8] = {0x02, ++id, 4, 0, (uint8_t)psm, (uint8_t)(psm >> 8), (uint8_t)scid, (uint8_t)(scid >> 8)};
    wire_l2cap(handle, 1, req, sizeof req);
    wire_run_ms(1);
    uint16_t dcid = 0;
    uint8_t our_id = 0;
    const uint8_t *q;
    uint16_t n;
    for (int k = 0; (q = wire_find_l2cap(handle, 1, k, &n)); k++) {
        if (q[0] == 0x03 && q[1] == id)
            dcid = (uint16_t)(q[4] | (q[5] << 8));
        if (q[0] == 0x04)
            our_id = q[1];
    }
    (void)before;
    if (dcid == 0)
        return 0;
    uint8_t cfg[12] = {0x04, ++id, 8, 0, (uint8_t)dcid, (uint8_t)(dcid >> 8), 0, 0, 0x01, 2, (uint8_t)mtu,
                       (uint8_t)(mtu >> 8)};
    wire_l2cap(handle, 1, cfg, sizeof cfg);
    uint8_t rsp[10] = {0x05, our_id, 6, 0, (uint8_t)dcid, (uint8_t)(dcid >> 8), 0, 0, 0, 0};
    wire_l2cap(handle, 1, rsp, sizeof rsp);
    wire_run_ms(1);
    return dcid;
}

uint8_t wire_fcs(const uint8_t *p, int n)
{
    uint8_t crc = 0xFF;
    while (n--) {
        crc ^= *p++;
        for (int i = 0; i < 8; i++)
            crc = (uint8_t)(crc & 1 ? (crc >> 1) ^ 0xE0 : crc >> 1);
    }
    return (uint8_t)(0xFF - crc);
}

void wire_rfcomm(uint16_t handle, uint16_t cid, uint8_t dlci, uint8_t ctrl, const uint8_t *info, uint8_t n,
                 int credits)
{
    uint8_t f[300];
    int k = 0;
    f[k++] = (uint8_t)(dlci << 2 | 0x02 | 1); /* initiator: C/R 1 on commands */
    f[k++] = credits > 0 ? (uint8_t)(ctrl | 0x10) : ctrl;
    f[k++] = (uint8_t)(n << 1 | 1);
    if (credits > 0)
        f[k++] = (uint8_t)credits;
    if (n)
        memcpy(f + k, info, n);
    k += n;
    f[k] = wire_fcs(f, (ctrl & ~0x10) == 0xEF ? 2 : 3);
    wire_l2cap(handle, cid, f, (uint16_t)(k + 1));
}

uint16_t wire_open_rfcomm(uint16_t handle, uint8_t credits, uint16_t n1)
{
    uint16_t cid = wire_open_l2cap(handle, 3, 0x0050, 1021);
    wire_rfcomm(handle, cid, 0, 0x3F, NULL, 0, 0); /* SABM, P */
    uint8_t pn[10] = {0x83, 0x11, 2, 0xF0, 0, 0, (uint8_t)n1, (uint8_t)(n1 >> 8), 0, credits};
    wire_rfcomm(handle, cid, 0, 0xEF, pn, 10, 0);
    wire_rfcomm(handle, cid, 2, 0x3F, NULL, 0, 0);
    wire_run_ms(2);
    return cid;
}

const uint8_t *wire_find_rfcomm(uint16_t handle, int n, uint16_t *len)
{
    return wire_find_l2cap(handle, 0x0050, n, len);
}

/* ---- the stack's hooks ---- */

void bt_stream_opened(uint8_t link)
{
    wire_up.stream_opened[link]++;
}

void bt_stream_rx(uint8_t link, const uint8_t *p, uint16_t n)
{
    if (wire_echo) { /* echo */
        uint16_t room = rfcomm_tx_room(link);
        rfcomm_write(link, p, n > room ? room : n);
        return;
    }
    if (wire_up.stream_rx_len[link] + n <= (int)sizeof wire_up.stream_rx[link]) {
        memcpy(wire_up.stream_rx[link] + wire_up.stream_rx_len[link], p, n);
        wire_up.stream_rx_len[link] += n;
    }
}

void bt_stream_closed(uint8_t link, bool lost)
{
    wire_up.stream_closed[link]++;
    wire_up.stream_lost[link] += lost;
}

void bt_framed_opened(uint8_t link)
{
    wire_up.framed_opened[link]++;
}

void bt_framed_rx(uint8_t link, const uint8_t *p, uint16_t n)
{
    wire_up.framed_sdus[link]++;
    if (wire_echo) { /* echo, if there is room */
        if (l2cap_can_send(link, L2CAP_FRAMED, n, true)) {
            l2cap_begin(link, L2CAP_FRAMED, n);
            hci_acl_put(p, n);
            hci_acl_end();
        }
        return;
    }
    if (n <= sizeof wire_up.framed_rx[link]) {
        memcpy(wire_up.framed_rx[link], p, n);
        wire_up.framed_rx_len[link] = n;
    }
}

void bt_framed_closed(uint8_t link, bool lost)
{
    wire_up.framed_closed[link]++;
    wire_up.framed_lost[link] += lost;
}

/* ---- live: the stack against a controller over TCP, in real time ---- */

static void live_rx(const uint8_t *p, uint16_t n)
{
    wire_feed(p, n);
}

static int live_tx(uint8_t *p, int max)
{
    int n = 0;
    int16_t b;
    while (n < max && (b = uart_tx_isr()) >= 0)
        p[n++] = (uint8_t)b;
    return n;
}

int wire_live(int port, int seconds)
{
    static const bt_live_robot_t robot = {live_rx, tick, live_tx};
    wire_reset();
    wire_echo = true;
    if (bt_live_run(port, seconds, &robot))
        return 1;
    printf("live: wire %u timeouts %u resets %u dropped %u\n", robot_state.errors.bt_wire,
           robot_state.errors.bt_timeouts, robot_state.errors.bt_resets, robot_state.errors.bt_dropped);
    return 0;
}
