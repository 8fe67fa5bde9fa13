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

/* FCS of TS 07.10: CRC-8, reversed polynomial x^8 + x^2 + x + 1, over 2 or 3 bytes of every frame sent and received;
 * by table (about 10 cycles a byte on the AVR, against 70 bit by bit). */
static const HAL_FLASH uint8_t fcs_table[256] = {
    0x00, 0x91, 0xE3, 0x72, 0x07, 0x96, 0xE4, 0x75, 0x0E, 0x9F, 0xED, 0x7C, 0x09, 0x98, 0xEA, 0x7B,
    0x1C, 0x8D, 0xFF, 0x6E, 0x1B, 0x8A, 0xF8, 0x69, 0x12, 0x83, 0xF1, 0x60, 0x15, 0x84, 0xF6, 0x67,
    0x38, 0xA9, 0xDB, 0x4A, 0x3F, 0xAE, 0xDC, 0x4D, 0x36, 0xA7, 0xD5, 0x44, 0x31, 0xA0, 0xD2, 0x43,
    0x24, 0xB5, 0xC7, 0x56, 0x23, 0xB2, 0xC0, 0x51, 0x2A, 0xBB, 0xC9, 0x58, 0x2D, 0xBC, 0xCE, 0x5F,
    0x70, 0xE1, 0x93, 0x02, 0x77, 0xE6, 0x94, 0x05, 0x7E, 0xEF, 0x9D, 0x0C, 0x79, 0xE8, 0x9A, 0x0B,
    0x6C, 0xFD, 0x8F, 0x1E, 0x6B, 0xFA, 0x88, 0x19, 0x62, 0xF3, 0x81, 0x10, 0x65, 0xF4, 0x86, 0x17,
    0x48, 0xD9, 0xAB, 0x3A, 0x4F, 0xDE, 0xAC, 0x3D, 0x46, 0xD7, 0xA5, 0x34, 0x41, 0xD0, 0xA2, 0x33,
    0x54, 0xC5, 0xB7, 0x26, 0x53, 0xC2, 0xB0, 0x21, 0x5A, 0xCB, 0xB9, 0x28, 0x5D, 0xCC, 0xBE, 0x2F,
    0xE0, 0x71, 0x03, 0x92, 0xE7, 0x76, 0x04, 0x95, 0xEE, 0x7F, 0x0D, 0x9C, 0xE9, 0x78, 0x0A, 0x9B,
    0xFC, 0x6D, 0x1F, 0x8E, 0xFB, 0x6A, 0x18, 0x89, 0xF2, 0x63, 0x11, 0x80, 0xF5, 0x64, 0x16, 0x87,
    0xD8, 0x49, 0x3B, 0xAA, 0xDF, 0x4E, 0x3C, 0xAD, 0xD6, 0x47, 0x35, 0xA4, 0xD1, 0x40, 0x32, 0xA3,
    0xC4, 0x55, 0x27, 0xB6, 0xC3, 0x52, 0x20, 0xB1, 0xCA, 0x5B, 0x29, 0xB8, 0xCD, 0x5C, 0x2E, 0xBF,
    0x90, 0x01, 0x73, 0xE2, 0x97, 0x06, 0x74, 0xE5, 0x9E, 0x0F, 0x7D, 0xEC, 0x99, 0x08, 0x7A, 0xEB,
    0x8C, 0x1D, 0x6F, 0xFE, 0x8B, 0x1A, 0x68, 0xF9, 0x82, 0x13, 0x61, 0xF0, 0x85, 0x14, 0x66, 0xF7,
    0xA8, 0x39, 0x4B, 0xDA, 0xAF, 0x3E, 0x4C, 0xDD, 0xA6, 0x37, 0x45, 0xD4, 0xA1, 0x30, 0x42, 0xD3,
    0xB4, 0x25, 0x57, 0xC6, 0xB3, 0x22, 0x50, 0xC1, 0xBA, 0x2B, 0x59, 0xC8, 0xBD, 0x2C, 0x5E, 0xCF,
};

static uint8_t fcs(const uint8_t *p, uint8_t n)
{
    uint8_t crc = 0xFFu;
    while (n--)
        crc = fcs_table[crc ^ *p++];
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

/* Up to the ring's end and from its start, pointer to pointer (as h4_tx_bytes()): the staging of every byte comm
 * sends. */
void rfcomm_write(uint8_t link, const uint8_t *p, uint16_t n)
{
    rfcomm_link_t *r = &rs[link];
    uint8_t h = r->head;
    r->head = (uint8_t)(h + n);
    while (n) {
        uint16_t run = (uint16_t)(RFCOMM_TX_SIZE - h);
        if (run > n)
            run = n;
        n = (uint16_t)(n - run);
        uint8_t *d = r->buf + h;
        h = (uint8_t)(h + run);
        do
            *d++ = *p++;
        while (--run);
    }
}

uint8_t *rfcomm_tx_ring(uint8_t link, uint8_t *pos)
{
    *pos = rs[link].head;
    return rs[link].buf;
}

void rfcomm_tx_commit(uint8_t link, uint8_t pos)
{
    rs[link].head = pos;
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
    uint8_t first = next_link; /* (not next_link in the loop: a link that ends a frame must not come round again) */
    for (uint8_t k = 0; k < BT_LINKS; k++) {
        uint8_t link = (uint8_t)((first + k) % BT_LINKS);
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
