#include "rfcomm.h"

#include <string.h>

#include "bluetooth/bt_config.h"
#include "bluetooth/h4.h"
#include "bluetooth/hci.h"
#include "bluetooth/l2cap.h"
#include "core/data.h"

/* Frame types (control field without the P/F bit). */
#define SABM 0x2Fu
#define UA 0x63u
#define DM 0x0Fu
#define DISC 0x43u
#define UIH 0xEFu
#define PF 0x10u

/* Multiplexer control message types (without the EA and C/R bits). */
#define MCC_PN 0x80u
#define MCC_MSC 0xE0u
#define MCC_RPN 0x90u
#define MCC_RLS 0x50u
#define MCC_TEST 0x20u
#define MCC_FCON 0xA0u
#define MCC_FCOFF 0x60u
#define MCC_NSC 0x10u
#define MCC_COMMAND 0x02u

#define DLCI (2u * BT_RFCOMM_CHANNEL) /* the server channel of the device that did not start the multiplexer */
#define V24_READY 0x8Du /* EA, RTC, RTR, DV */
#define OVERHEAD 6u     /* address, control, two length bytes, credits, FCS */

_Static_assert(RFCOMM_TX_SIZE == 256u, "one-byte ring indices wrap by themselves");


#define MSC_DUE 0x01u /* our modem status command waits for room */
#define PAUSED 0x02u  /* the peer sent FCoff (without credit-based flow control) */

static uint8_t next_link; /* the link whose data goes first next time (turns) */

typedef struct {
    uint8_t mux;        /* DLCI 0 open */
    uint8_t dlc;        /* the data channel open */
    uint8_t cbfc;       /* credit-based flow control agreed */
    uint8_t flags;
    uint8_t tx_credits; /* frames the robot may send */
    uint8_t rx_credits; /* frames the peer may send */
    uint8_t n1;         /* the largest information field, both ways */
    uint8_t out_left;   /* information bytes of the frame being written still to write */
    uint8_t out_ctrl;   /* and its control field */
    uint8_t head, tail; /* staged bytes: [tail, head) */
    uint8_t buf[RFCOMM_TX_SIZE];
} rfcomm_link_t;
static rfcomm_link_t rs[BT_LINKS];

/* FCS of TS 07.10: CRC-8, reversed polynomial x^8 + x^2 + x + 1, over 2 or 3 bytes (bit by bit: no table). */
static uint8_t fcs(const uint8_t *p, uint8_t n)
{
    uint8_t crc = 0xFFu;
    while (n--) {
        crc ^= *p++;
        for (uint8_t i = 0; i < 8; i++)
            crc = (uint8_t)(crc & 1u ? (crc >> 1) ^ 0xE0u : crc >> 1);
    }
    return (uint8_t)(0xFFu - crc);
}

static void reset_link(uint8_t link)
{
    rfcomm_link_t *r = &rs[link];
    memset(r, 0, sizeof *r);
}

void rfcomm_init(void)
{
    for (uint8_t i = 0; i < BT_LINKS; i++)
        reset_link(i);
}

static void close_dlc(uint8_t link, bool lost)
{
    rfcomm_link_t *r = &rs[link];
    if (r->out_left) {
        hci_acl_abort(); /* the frame being written goes with the channel */
        r->out_left = 0;
    }
    if (r->dlc) {
        r->dlc = 0;
        l2cap_set_stream(link, false);
        bt_stream_closed(link, lost);
    }
}

void rfcomm_channel_closed(uint8_t link, bool lost)
{
    close_dlc(link, lost);
    reset_link(link);
}

/* ---- sending ---- */

static uint16_t frame_size(uint16_t info, bool credits)
{
    return (uint16_t)(2u + (info > 127u ? 2u : 1u) + credits + info + 1u);
}

/* Starts a frame with `info` bytes of information (the caller puts them, then frame_end()). */
static bool frame_begin(uint8_t link, uint8_t addr, uint8_t ctrl, uint16_t info, uint8_t credits, bool data)
{
    uint16_t size = frame_size(info, credits != 0);
    if (!l2cap_can_send(link, L2CAP_RFCOMM, size, data))
        return false;
    uint8_t head[5] = {addr, ctrl, (uint8_t)(info << 1 | 1u)};
    uint8_t k = 3;
    if (info > 127u) {
        head[2] = (uint8_t)(info << 1);
        head[k++] = (uint8_t)(info >> 7);
    }
    if (credits)
        head[k++] = credits;
    l2cap_begin(link, L2CAP_RFCOMM, size);
    hci_acl_put(head, k);
    return true;
}

/* Ends a frame whose FCS covers the address, control and (not UIH) length fields. */
static void frame_end(uint8_t addr, uint8_t ctrl)
{
    uint8_t head[3] = {addr, ctrl, 1u}; /* only frames without information carry a length in their FCS */
    hci_acl_put_byte(fcs(head, (ctrl & ~PF) == UIH ? 2u : 3u));
    hci_acl_end();
}

/* A frame without information: UA or DM (responses, C/R 1 from the responder) with the final bit. */
static bool send_response(uint8_t link, uint8_t dlci, uint8_t type)
{
    uint8_t addr = (uint8_t)(dlci << 2 | 0x02u | 1u), ctrl = (uint8_t)(type | PF);
    if (!frame_begin(link, addr, ctrl, 0, 0, false))
        return false;
    frame_end(addr, ctrl);
    return true;
}

/* A multiplexer control message on DLCI 0 (UIH, a command frame of the responder: C/R 0). */
static bool send_mcc(uint8_t link, uint8_t type, const uint8_t *v, uint8_t n)
{
    if (!frame_begin(link, 0x01u, UIH, (uint16_t)(2u + n), 0, false))
        return false;
    hci_acl_put_byte((uint8_t)(type | 1u));
    hci_acl_put_byte((uint8_t)(n << 1 | 1u));
    hci_acl_put(v, n);
    frame_end(0x01u, UIH);
    return true;
}

/* ---- receiving ---- */

static bool on_pn(uint8_t link, const uint8_t *v)
{
    rfcomm_link_t *r = &rs[link];
    uint8_t a[8];
    memcpy(a, v, 8);
    bool ask_credits = (v[1] >> 4) == 0xFu;
    uint16_t n1 = (uint16_t)(v[4] | (v[5] << 8));
    if (n1 > BT_RFCOMM_N1 || n1 == 0)
        n1 = BT_RFCOMM_N1;
    a[1] = ask_credits ? 0xE0u : 0x00u;
    a[3] = 0;
    a[4] = (uint8_t)n1;
    a[5] = 0;
    a[6] = 0;
    a[7] = ask_credits ? RFCOMM_RX_CREDITS : 0;
    if (!send_mcc(link, MCC_PN, a, 8))
        return false;
    if ((v[0] & 0x3Fu) == DLCI && !r->dlc) {
        r->cbfc = ask_credits;
        r->tx_credits = ask_credits ? (uint8_t)(v[7] & 7u) : 0;
        r->rx_credits = ask_credits ? RFCOMM_RX_CREDITS : 0;
        r->n1 = (uint8_t)n1;
    }
    return true;
}

/* A multiplexer control message. \return false when its answer found no room. */
static bool on_mcc(uint8_t link, const uint8_t *p, uint16_t n)
{
    rfcomm_link_t *r = &rs[link];
    if (n < 2)
        return true;
    uint8_t type = p[0] & 0xFCu;
    bool command = (p[0] & MCC_COMMAND) != 0;
    uint8_t len = p[1] >> 1;
    if (!(p[1] & 1u) || 2u + len > n)
        return true; /* two-byte lengths or truncated: nothing the robot would echo */
    const uint8_t *v = p + 2;
    if (!command) {
        return true; /* responses to our MSC (or NSC): nothing to do */
    }
    switch (type) {
    case MCC_PN:
        return len >= 8 ? on_pn(link, v) : true;
    case MCC_RPN:
        if (len == 1) { /* a query: 115200 Bd, 8N1, no flow control */
            uint8_t r[8] = {v[0], 0x07, 0x03, 0x00, 0x11, 0x13, 0xFF, 0x3F};
            return send_mcc(link, MCC_RPN, r, 8);
        }
        return send_mcc(link, MCC_RPN, v, len);
    case MCC_FCOFF:
    case MCC_FCON:
        if (!send_mcc(link, type, v, 0))
            return false;
        if (type == MCC_FCOFF)
            r->flags |= PAUSED;
        else
            r->flags = (uint8_t)(r->flags & ~PAUSED);
        return true;
    case MCC_MSC:
    case MCC_RLS:
    case MCC_TEST:
        return send_mcc(link, type, v, len); /* echoed as the response */
    default: {
        uint8_t t = p[0];
        return send_mcc(link, MCC_NSC, &t, 1);
    }
    }
}

bool rfcomm_on_pdu(uint8_t link, const uint8_t *p, uint16_t n)
{
    rfcomm_link_t *r = &rs[link];
    if (n < 4)
        return true;
    uint8_t addr = p[0], ctrl = p[1], type = (uint8_t)(p[1] & ~PF);
    uint8_t dlci = addr >> 2;
    uint16_t len, head;
    if (p[2] & 1u) {
        len = p[2] >> 1;
        head = 3;
    } else {
        len = (uint16_t)((p[2] >> 1) | (p[3] << 7));
        head = 4;
    }
    uint8_t credits = 0;
    if (type == UIH && (ctrl & PF) && dlci != 0 && r->cbfc)
        credits = 1;
    if ((uint32_t)head + credits + len + 1u != n || fcs(p, type == UIH ? 2u : (uint8_t)head) != p[n - 1]) {
        robot_state.errors.bt_dropped++; /* a length that disagrees with the PDU, or a bad FCS */
        return true;
    }
    const uint8_t *info = p + head + credits;
    switch (type) {
    case SABM:
        if (dlci == 0) {
            if (!send_response(link, 0, UA))
                return false;
            r->mux = 1;
            return true;
        }
        if (!r->mux || dlci != DLCI || r->dlc || l2cap_connected(link, L2CAP_FRAMED))
            return send_response(link, dlci, DM); /* one data channel per link */
        if (!send_response(link, dlci, UA))
            return false;
        if (r->n1 == 0)
            r->n1 = 127u < BT_RFCOMM_N1 ? 127u : BT_RFCOMM_N1; /* no PN: the default N1 */
        r->dlc = 1;
        r->flags = MSC_DUE;
        r->head = r->tail = 0;
        l2cap_set_stream(link, true);
        bt_stream_opened(link);
        return true;
    case DISC:
        if (dlci != 0 && (dlci != DLCI || !r->dlc))
            return send_response(link, dlci, DM);
        if (!send_response(link, dlci, UA))
            return false;
        close_dlc(link, false);
        if (dlci == 0)
            reset_link(link);
        return true;
    case UIH:
        if (dlci == 0)
            return on_mcc(link, info, len);
        if (dlci != DLCI || !r->dlc) {
            robot_state.errors.bt_dropped++;
            return true;
        }
        if (credits) {
            uint16_t c = (uint16_t)(r->tx_credits + p[head]);
            r->tx_credits = (uint8_t)(c > 255u ? 255u : c);
        }
        if (len) {
            if (r->rx_credits)
                r->rx_credits--;
            bt_stream_rx(link, info, len);
        }
        return true;
    default:
        return true; /* UA and DM: answers to nothing the robot asks */
    }
}

/* ---- staged bytes ---- */

uint16_t rfcomm_tx_room(uint8_t link)
{
    rfcomm_link_t *r = &rs[link];
    if (!r->dlc)
        return 0;
    return (uint8_t)(r->tail - r->head - 1u);
}

void rfcomm_write(uint8_t link, const uint8_t *p, uint16_t n)
{
    rfcomm_link_t *r = &rs[link];
    uint8_t h = r->head;
    uint8_t *buf = r->buf;
    while (n--) {
        buf[h++] = *p++;
    }
    r->head = h;
}

/* Writes the next slice of the frame being written (and its end). */
static void write_slice(uint8_t link)
{
    rfcomm_link_t *r = &rs[link];
    uint8_t n = r->out_left > RFCOMM_SLICE ? RFCOMM_SLICE : r->out_left;
    uint8_t t = r->tail;
    uint16_t first = (uint16_t)(RFCOMM_TX_SIZE - t);
    if (first > n)
        first = n;
    hci_acl_put(r->buf + t, first);
    hci_acl_put(r->buf, (uint16_t)(n - first));
    r->tail = (uint8_t)(t + n);
    r->out_left = (uint8_t)(r->out_left - n);
    if (r->out_left == 0)
        frame_end((uint8_t)(DLCI << 2 | 1u), r->out_ctrl);
}

/* Starts a UIH frame of `n` staged bytes (0: credits alone), giving `give` credits. */
static bool send_data(uint8_t link, uint8_t n, uint8_t give)
{
    rfcomm_link_t *r = &rs[link];
    uint8_t addr = (uint8_t)(DLCI << 2 | 1u), ctrl = (uint8_t)(give ? UIH | PF : UIH);
    if (!frame_begin(link, addr, ctrl, n, give, n != 0))
        return false;
    r->rx_credits = (uint8_t)(r->rx_credits + give);
    if (n == 0) {
        frame_end(addr, ctrl);
        return true;
    }
    if (r->cbfc)
        r->tx_credits--;
    r->out_left = n;
    r->out_ctrl = ctrl;
    write_slice(link);
    return true;
}

static void link_task(uint8_t link)
{
    rfcomm_link_t *r = &rs[link];
    if (r->out_left) {
        write_slice(link);
        return;
    }
    if (r->flags & MSC_DUE) {
        uint8_t v[2] = {(uint8_t)(DLCI << 2 | 0x02u | 1u), V24_READY};
        if (!send_mcc(link, MCC_MSC | MCC_COMMAND, v, 2))
            return;
        r->flags = (uint8_t)(r->flags & ~MSC_DUE);
    }
    uint8_t give = 0;
    if (r->cbfc && r->rx_credits <= RFCOMM_RX_CREDITS / 2u)
        give = (uint8_t)(RFCOMM_RX_CREDITS - r->rx_credits);
    uint8_t staged = (uint8_t)(r->head - r->tail);
    if (staged == 0 && give == 0)
        return;
    uint16_t max = l2cap_peer_mtu(link, L2CAP_RFCOMM);
    max = max > OVERHEAD ? (uint16_t)(max - OVERHEAD) : 0;
    if (max > r->n1)
        max = r->n1;
    bool may = (r->cbfc ? r->tx_credits != 0 : !(r->flags & PAUSED)) && max != 0;
    if (staged && may && (staged >= max || h4_tx_backlog() < RFCOMM_IDLE_BACKLOG)) {
        if (send_data(link, (uint8_t)(staged > max ? max : staged), give))
            return;
    }
    if (give)
        send_data(link, 0, give);
}

void rfcomm_task(void)
{
    for (uint8_t k = 0; k < BT_LINKS; k++) {
        uint8_t link = (uint8_t)((next_link + k) % BT_LINKS);
        if (!rs[link].dlc)
            continue;
        bool writing = rs[link].out_left != 0;
        link_task(link);
        if (writing && rs[link].out_left == 0)
            next_link = (uint8_t)((link + 1u) % BT_LINKS); /* a frame ended: the other link's turn */
        if (rs[link].out_left)
            return; /* one frame at a time in the transmit ring */
    }
}
