#include "l2cap.h"

#include <string.h>

#include "bluetooth/hci.h"
#include "core/data.h"

#define CID_SIGNALLING 0x0001u
#define CID_DYNAMIC 0x0040u
#define HEADER 4u /* length, channel id */

/* Signalling codes. */
#define SIG_REJECT 0x01u
#define SIG_CONNECT_REQ 0x02u
#define SIG_CONNECT_RSP 0x03u
#define SIG_CONFIG_REQ 0x04u
#define SIG_CONFIG_RSP 0x05u
#define SIG_DISCONNECT_REQ 0x06u
#define SIG_DISCONNECT_RSP 0x07u
#define SIG_ECHO_REQ 0x08u
#define SIG_ECHO_RSP 0x09u
#define SIG_INFO_REQ 0x0Au
#define SIG_INFO_RSP 0x0Bu

/* Results and reasons. */
#define CONNECT_PSM_UNSUPPORTED 0x0002u
#define CONNECT_NO_RESOURCES 0x0004u
#define CONNECT_BAD_SOURCE_CID 0x0006u
#define CONFIG_UNACCEPTABLE 0x0001u
#define CONFIG_UNKNOWN_OPTION 0x0003u
#define REJECT_NOT_UNDERSTOOD 0x0000u
#define REJECT_INVALID_CID 0x0002u

/* Configuration options. */
#define OPT_MTU 0x01u
#define OPT_MODE 0x04u
#define OPT_HINT 0x80u

enum { CH_FREE, CH_CONFIG, CH_OPEN, CH_CLOSING };
/* Configuration progress of a channel. */
#define CFG_REQ_DUE 0x01u  /* our configuration request waits for room */
#define CFG_OUT_DONE 0x02u /* the peer accepted ours */
#define CFG_IN_DONE 0x04u  /* we accepted the peer's */

typedef struct {
    uint8_t state;
    uint8_t cfg;
    uint8_t req_id; /* identifier of our configuration request */
    uint16_t rcid;  /* the peer's channel id */
    uint16_t rmtu;  /* the peer's MTU */
} chan_t;

enum { RX_IDLE, RX_ASSEMBLING, RX_PENDING };

static uint8_t waiting; /* a PDU or a configuration request waits for room: l2cap_task() has work */

typedef struct {
    uint8_t rx_state;
    uint8_t sig_done;  /* signalling commands of a pending PDU already handled */
    uint8_t next_id;   /* identifier of our next signalling request */
    uint8_t stream;    /* RFCOMM's data channel is open */
    uint16_t rx_len;
    uint16_t rx_frag;  /* bytes of the fragment being read */
    chan_t ch[L2CAP_SERVICES];
    uint8_t rx[HEADER + BT_L2CAP_MTU];
} l2cap_link_t;
static l2cap_link_t ls[BT_LINKS];

static uint16_t le16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

/* Local channel ids: one per link and service. */
static uint16_t local_cid(uint8_t link, uint8_t service)
{
    return (uint16_t)(CID_DYNAMIC + link * L2CAP_SERVICES + service);
}

/* \return the service of a local channel id of `link`, or L2CAP_SERVICES. */
static uint8_t service_of(uint8_t link, uint16_t cid)
{
    l2cap_link_t *l = &ls[link];
    uint16_t base = local_cid(link, 0);
    if (cid < base || cid >= base + L2CAP_SERVICES || l->ch[cid - base].state == CH_FREE)
        return L2CAP_SERVICES;
    return (uint8_t)(cid - base);
}

void l2cap_init(void)
{
    memset(ls, 0, sizeof ls);
    waiting = 0;
    for (uint8_t i = 0; i < BT_LINKS; i++)
        ls[i].next_id = 1;
}

/* ---- services ---- */

static void channel_opened(uint8_t link, uint8_t service)
{
    if (service == L2CAP_FRAMED)
        bt_framed_opened(link);
}

static void channel_closed(uint8_t link, uint8_t service, bool lost)
{
    l2cap_link_t *l = &ls[link];
    chan_t *c = &l->ch[service];
    uint8_t was = c->state;
    c->state = CH_FREE;
    if (was == CH_FREE)
        return;
    if (service == L2CAP_RFCOMM)
        rfcomm_channel_closed(link, lost);
    else if (service == L2CAP_FRAMED && was != CH_CONFIG)
        bt_framed_closed(link, lost);
}

void l2cap_link_up(uint8_t link)
{
    l2cap_link_t *l = &ls[link];
    l->rx_state = RX_IDLE;
    l->stream = 0;
    for (uint8_t s = 0; s < L2CAP_SERVICES; s++)
        l->ch[s].state = CH_FREE;
}

void l2cap_link_down(uint8_t link, uint8_t reason)
{
    l2cap_link_t *l = &ls[link];
    (void)reason; /* a channel still open when its link goes was lost, whatever the link's reason */
    l->rx_state = RX_IDLE;
    for (uint8_t s = 0; s < L2CAP_SERVICES; s++)
        channel_closed(link, s, true);
}

/* ---- sending ---- */

bool l2cap_can_send(uint8_t link, uint8_t service, uint16_t len, bool data)
{
    l2cap_link_t *l = &ls[link];
    const chan_t *c = &l->ch[service];
    return c->state == CH_OPEN && len <= c->rmtu && hci_acl_can_send((uint16_t)(HEADER + len), data);
}

bool l2cap_connected(uint8_t link, uint8_t service)
{
    l2cap_link_t *l = &ls[link];
    return l->ch[service].state != CH_FREE;
}

void l2cap_set_stream(uint8_t link, bool open)
{
    l2cap_link_t *l = &ls[link];
    l->stream = open;
}

uint16_t l2cap_peer_mtu(uint8_t link, uint8_t service)
{
    l2cap_link_t *l = &ls[link];
    const chan_t *c = &l->ch[service];
    return c->state == CH_OPEN ? c->rmtu : 0;
}

static void begin_cid(uint8_t link, uint16_t cid, uint16_t len)
{
    hci_acl_begin(link, (uint16_t)(HEADER + len));
    uint8_t h[HEADER] = {(uint8_t)len, (uint8_t)(len >> 8), (uint8_t)cid, (uint8_t)(cid >> 8)};
    hci_acl_put(h, HEADER); /* whole: a byte at a time was a call each through the fragmenter */
}

void l2cap_begin(uint8_t link, uint8_t service, uint16_t len)
{
    l2cap_link_t *l = &ls[link];
    begin_cid(link, l->ch[service].rcid, len);
}

/* A signalling command: code, identifier, length, then `len` bytes the caller puts. \return false without room. */
static bool signal_begin(uint8_t link, uint8_t code, uint8_t id, uint16_t len)
{
    if (!hci_acl_can_send((uint16_t)(HEADER + 4u + len), false))
        return false;
    begin_cid(link, CID_SIGNALLING, (uint16_t)(4u + len));
    hci_acl_put_byte(code);
    hci_acl_put_byte(id);
    hci_acl_put_u16(len);
    return true;
}

static bool signal_cids(uint8_t link, uint8_t code, uint8_t id, uint16_t a, uint16_t b)
{
    if (!signal_begin(link, code, id, 4))
        return false;
    hci_acl_put_u16(a);
    hci_acl_put_u16(b);
    hci_acl_end();
    return true;
}

static bool send_config_request(uint8_t link, uint8_t service)
{
    l2cap_link_t *l = &ls[link];
    chan_t *c = &l->ch[service];
    uint8_t id = l->next_id;
    if (!signal_begin(link, SIG_CONFIG_REQ, id, 8))
        return false;
    l->next_id = (uint8_t)(id == 255u ? 1u : id + 1u);
    c->req_id = id;
    c->cfg = (uint8_t)(c->cfg & ~CFG_REQ_DUE);
    hci_acl_put_u16(c->rcid);
    hci_acl_put_u16(0); /* flags: complete */
    hci_acl_put_byte(OPT_MTU);
    hci_acl_put_byte(2);
    hci_acl_put_u16(BT_L2CAP_MTU);
    hci_acl_end();
    return true;
}

/* ---- signalling ---- */

static uint8_t service_of_psm(uint16_t psm)
{
    if (psm == L2CAP_PSM_SDP)
        return L2CAP_SDP;
    if (psm == L2CAP_PSM_RFCOMM)
        return L2CAP_RFCOMM;
    if (psm == BT_PSM_FRAMED)
        return L2CAP_FRAMED;
    return L2CAP_SERVICES;
}

static bool on_connect_request(uint8_t link, uint8_t id, const uint8_t *p)
{
    l2cap_link_t *l = &ls[link];
    uint16_t psm = le16(p);
    uint16_t scid = le16(p + 2);
    uint8_t s = service_of_psm(psm);
    uint16_t result = 0;
    if (s == L2CAP_SERVICES)
        result = CONNECT_PSM_UNSUPPORTED;
    else if (scid < CID_DYNAMIC)
        result = CONNECT_BAD_SOURCE_CID;
    else if (l->ch[s].state != CH_FREE || (s == L2CAP_FRAMED && l->stream))
        result = CONNECT_NO_RESOURCES; /* one channel per service, one data channel per link */
    if (!signal_begin(link, SIG_CONNECT_RSP, id, 8))
        return false;
    hci_acl_put_u16(result ? 0 : local_cid(link, s));
    hci_acl_put_u16(scid);
    hci_acl_put_u16(result);
    hci_acl_put_u16(0);
    hci_acl_end();
    if (result == 0) {
        chan_t *c = &l->ch[s];
        c->state = CH_CONFIG;
        c->cfg = CFG_REQ_DUE;
        c->rcid = scid;
        c->rmtu = L2CAP_DEFAULT_MTU;
        if (!send_config_request(link, s))
            waiting = 1; /* l2cap_task() sends it when there is room */
    }
    return true;
}

static void config_progress(uint8_t link, uint8_t s)
{
    l2cap_link_t *l = &ls[link];
    chan_t *c = &l->ch[s];
    if (c->state == CH_CONFIG && (c->cfg & (CFG_OUT_DONE | CFG_IN_DONE)) == (CFG_OUT_DONE | CFG_IN_DONE)) {
        c->state = CH_OPEN;
        channel_opened(link, s);
    }
}

static bool on_config_request(uint8_t link, uint8_t id, const uint8_t *p, uint16_t n)
{
    l2cap_link_t *l = &ls[link];
    uint16_t dcid = le16(p);
    uint16_t flags = le16(p + 2);
    uint8_t s = service_of(link, dcid);
    if (s == L2CAP_SERVICES) {
        if (!signal_begin(link, SIG_REJECT, id, 6))
            return false;
        hci_acl_put_u16(REJECT_INVALID_CID);
        hci_acl_put_u16(dcid);
        hci_acl_put_u16(0);
        hci_acl_end();
        return true;
    }
    chan_t *c = &l->ch[s];
    uint16_t mtu = c->rmtu;
    uint16_t result = 0;
    const uint8_t *bad = NULL; /* the option refused */
    for (uint16_t i = 4; i + 2u <= n;) {
        uint8_t type = p[i], len = p[i + 1];
        if (i + 2u + len > n)
            break; /* a truncated option: ignored */
        const uint8_t *v = p + i + 2;
        if (type == OPT_MTU && len == 2)
            mtu = le16(v);
        else if (type == OPT_MODE && len >= 1 && v[0] != 0 && result == 0)
            result = CONFIG_UNACCEPTABLE; /* only basic mode */
        else if (type > OPT_MODE + 1u && !(type & OPT_HINT) && !bad) {
            result = CONFIG_UNKNOWN_OPTION;
            bad = p + i;
        }
        i = (uint16_t)(i + 2u + len);
    }
    uint8_t extra = result == CONFIG_UNACCEPTABLE ? 11u : result == CONFIG_UNKNOWN_OPTION ? 1u : 0u;
    if (!signal_begin(link, SIG_CONFIG_RSP, id, (uint16_t)(6u + extra)))
        return false;
    hci_acl_put_u16(c->rcid);
    hci_acl_put_u16(flags & 1u);
    hci_acl_put_u16(result);
    if (result == CONFIG_UNKNOWN_OPTION) {
        hci_acl_put_byte(bad[0]);
    } else if (result == CONFIG_UNACCEPTABLE) { /* the mode we take: basic */
        uint8_t basic[11] = {OPT_MODE, 9};
        hci_acl_put(basic, sizeof basic);
    }
    hci_acl_end();
    if (result == 0) {
        c->rmtu = mtu < 48u ? 48u : mtu;
        if (!(flags & 1u))
            c->cfg |= CFG_IN_DONE;
        config_progress(link, s);
    }
    return true;
}

static void on_config_response(uint8_t link, uint8_t id, const uint8_t *p)
{
    l2cap_link_t *l = &ls[link];
    uint8_t s = service_of(link, le16(p));
    if (s == L2CAP_SERVICES || l->ch[s].req_id != id)
        return;
    uint16_t result = le16(p + 4);
    if (result == 0) {
        l->ch[s].cfg |= CFG_OUT_DONE;
        config_progress(link, s);
    } else if (result != 0x0004u) { /* refused (not pending): the channel cannot be used */
        l->ch[s].state = CH_CLOSING;
        l->ch[s].cfg = 0;
        uint8_t req = l->next_id;
        l->next_id = (uint8_t)(req == 255u ? 1u : req + 1u);
        signal_cids(link, SIG_DISCONNECT_REQ, req, l->ch[s].rcid, local_cid(link, s));
    }
}

static bool on_disconnect_request(uint8_t link, uint8_t id, const uint8_t *p)
{
    l2cap_link_t *l = &ls[link];
    uint16_t dcid = le16(p), scid = le16(p + 2);
    uint8_t s = service_of(link, dcid);
    if (s == L2CAP_SERVICES || l->ch[s].rcid != scid) {
        if (!signal_begin(link, SIG_REJECT, id, 6))
            return false;
        hci_acl_put_u16(REJECT_INVALID_CID);
        hci_acl_put_u16(dcid);
        hci_acl_put_u16(scid);
        hci_acl_end();
        return true;
    }
    if (!signal_cids(link, SIG_DISCONNECT_RSP, id, dcid, scid))
        return false;
    channel_closed(link, s, false);
    return true;
}

static bool on_info_request(uint8_t link, uint8_t id, uint16_t type)
{
    bool features = type == 0x0002u; /* extended features: none beyond basic mode */
    if (!signal_begin(link, SIG_INFO_RSP, id, features ? 8u : 4u))
        return false;
    hci_acl_put_u16(type);
    hci_acl_put_u16(features ? 0u : 1u); /* success, or not supported */
    if (features) {
        hci_acl_put_u16(0);
        hci_acl_put_u16(0);
    }
    hci_acl_end();
    return true;
}

/* One signalling command. \return false when its answer found no room. */
static bool on_signal(uint8_t link, uint8_t code, uint8_t id, const uint8_t *p, uint16_t n)
{
    l2cap_link_t *l = &ls[link];
    switch (code) {
    case SIG_CONNECT_REQ:
        if (n >= 4)
            return on_connect_request(link, id, p);
        break;
    case SIG_CONFIG_REQ:
        if (n >= 4)
            return on_config_request(link, id, p, n);
        break;
    case SIG_CONFIG_RSP:
        if (n >= 6)
            on_config_response(link, id, p);
        return true;
    case SIG_DISCONNECT_REQ:
        if (n >= 4)
            return on_disconnect_request(link, id, p);
        break;
    case SIG_DISCONNECT_RSP:
        if (n >= 4) {
            uint8_t s = service_of(link, le16(p + 2));
            if (s < L2CAP_SERVICES && l->ch[s].state == CH_CLOSING)
                l->ch[s].state = CH_FREE;
        }
        return true;
    case SIG_ECHO_REQ:
        if (!signal_begin(link, SIG_ECHO_RSP, id, 0))
            return false;
        hci_acl_end();
        return true;
    case SIG_INFO_REQ:
        if (n >= 2)
            return on_info_request(link, id, le16(p));
        break;
    case SIG_REJECT:
    case SIG_CONNECT_RSP:
    case SIG_ECHO_RSP:
    case SIG_INFO_RSP:
        return true; /* answers to requests the robot does not make, or needs nothing from */
    default:
        break;
    }
    if (!signal_begin(link, SIG_REJECT, id, 2)) /* unknown, or too short to read */
        return false;
    hci_acl_put_u16(REJECT_NOT_UNDERSTOOD);
    hci_acl_end();
    return true;
}

/* The commands of a signalling PDU, from the first one not handled yet. */
static bool on_signalling(uint8_t link, const uint8_t *p, uint16_t n)
{
    l2cap_link_t *l = &ls[link];
    uint8_t k = 0;
    for (uint16_t i = 0; i + 4u <= n; k++) {
        uint16_t len = le16(p + i + 2);
        if (i + 4u + len > n)
            len = (uint16_t)(n - i - 4u); /* truncated: read as far as it goes */
        if (k >= l->sig_done) {
            if (!on_signal(link, p[i], p[i + 1], p + i + 4, len))
                return false;
            l->sig_done = (uint8_t)(k + 1u);
        }
        i = (uint16_t)(i + 4u + len);
    }
    return true;
}

/* ---- receiving ---- */

/* Hands a complete PDU to its channel. \return false when an answer found no room (handle it again later). */
static bool dispatch(uint8_t link)
{
    l2cap_link_t *l = &ls[link];
    const uint8_t *p = l->rx + HEADER;
    uint16_t n = (uint16_t)(l->rx_len - HEADER);
    uint16_t cid = le16(l->rx + 2);
    if (cid == CID_SIGNALLING)
        return on_signalling(link, p, n);
    uint8_t s = service_of(link, cid);
    if (s == L2CAP_SDP)
        return sdp_on_pdu(link, p, n);
    if (s == L2CAP_RFCOMM)
        return rfcomm_on_pdu(link, p, n);
    if (s == L2CAP_FRAMED)
        bt_framed_rx(link, p, n);
    else
        robot_state.errors.bt_dropped++; /* no such channel */
    return true;
}

static void handle(uint8_t link)
{
    l2cap_link_t *l = &ls[link];
    if (dispatch(link)) {
        l->rx_state = RX_IDLE;
        l->sig_done = 0;
    } else {
        l->rx_state = RX_PENDING;
        waiting = 1;
    }
}

uint8_t *l2cap_rx_fragment(uint8_t link, bool start, uint16_t len)
{
    l2cap_link_t *l = &ls[link];
    if (l->rx_state == RX_PENDING) {
        robot_state.errors.bt_dropped++; /* the previous PDU still waits for room to answer */
        return NULL;
    }
    if (start) {
        if (l->rx_state == RX_ASSEMBLING)
            robot_state.errors.bt_dropped++; /* the last one never ended */
        l->rx_state = RX_ASSEMBLING;
        l->rx_len = 0;
    } else if (l->rx_state != RX_ASSEMBLING) {
        return NULL; /* the rest of a PDU already dropped (or counted as never started below) */
    }
    if (l->rx_len + len > sizeof l->rx) {
        robot_state.errors.bt_dropped++; /* longer than the MTU */
        l->rx_state = RX_IDLE;
        return NULL;
    }
    l->rx_frag = len;
    return l->rx + l->rx_len;
}

void l2cap_rx_fragment_done(uint8_t link)
{
    l2cap_link_t *l = &ls[link];
    uint16_t got = (uint16_t)(l->rx_len + l->rx_frag);
    l->rx_len = got;
    if (got < HEADER)
        return;
    uint16_t total = (uint16_t)(HEADER + le16(l->rx));
    if (total > sizeof l->rx) { /* longer than the MTU: its other fragments are dropped unseen */
        robot_state.errors.bt_dropped++;
        l->rx_state = RX_IDLE;
        return;
    }
    if (got < total)
        return;
    if (got > total) { /* more fragments than the length said */
        robot_state.errors.bt_dropped++;
        l->rx_state = RX_IDLE;
        return;
    }
    handle(link);
}

void l2cap_task(void)
{
    if (!waiting)
        return;
    waiting = 0;
    for (uint8_t link = 0; link < BT_LINKS; link++) {
        if (ls[link].rx_state == RX_PENDING)
            handle(link);
        for (uint8_t s = 0; s < L2CAP_SERVICES; s++)
            if (ls[link].ch[s].state == CH_CONFIG && (ls[link].ch[s].cfg & CFG_REQ_DUE))
                send_config_request(link, s);
        if (ls[link].rx_state == RX_PENDING)
            waiting = 1;
        for (uint8_t s = 0; s < L2CAP_SERVICES; s++)
            if (ls[link].ch[s].state == CH_CONFIG && (ls[link].ch[s].cfg & CFG_REQ_DUE))
                waiting = 1;
    }
}
