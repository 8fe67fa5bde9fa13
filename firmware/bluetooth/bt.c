#include "bt.h"

#include "bluetooth/bt_config.h"
#include "bluetooth/hci.h"
#include "bluetooth/l2cap.h"
#include "bluetooth/rfcomm.h"
#include "modules/comm.h"

_Static_assert(BT_LINKS <= COMM_LINKS, "every Bluetooth link is a host link of comm");

/* RFCOMM: SLIP bytes staged by rfcomm.c. */
static uint16_t stream_room(uint8_t link)
{
    return rfcomm_tx_room(link);
}

static void stream_write(uint8_t link, const uint8_t *p, uint16_t n)
{
    rfcomm_write(link, p, n);
}

/* comm SLIP-encodes into the staging ring itself when a frame goes to this link alone (no copy through a chunk). */
static uint8_t *stream_ring(uint8_t link, uint8_t *pos)
{
    return rfcomm_tx_ring(link, pos);
}

static void stream_commit(uint8_t link, uint8_t pos)
{
    rfcomm_tx_commit(link, pos);
}

/* The framed channel: one frame per SDU, written straight into the transmit ring. Room is reported for the
 * longest frame or none (comm offers again later), which keeps the check to one. */
static uint16_t framed_room(uint8_t link)
{
    uint16_t n = l2cap_peer_mtu(link, L2CAP_FRAMED);
    if (n > PB_MAX_FRAME)
        n = PB_MAX_FRAME;
    return l2cap_can_send(link, L2CAP_FRAMED, n, true) ? n : 0;
}

static void framed_write(uint8_t link, const uint8_t *p, uint16_t n)
{
    l2cap_begin(link, L2CAP_FRAMED, n);
    hci_acl_put(p, n);
    hci_acl_end();
}

static const comm_link_driver_t stream_driver = {false, stream_room, stream_write, NULL, stream_ring, stream_commit};
static const comm_link_driver_t framed_driver = {true, framed_room, framed_write, NULL, NULL, NULL};

void bt_stream_opened(uint8_t link)
{
    comm_link_open(link, &stream_driver);
}

void bt_stream_rx(uint8_t link, const uint8_t *p, uint16_t n)
{
    comm_link_rx(link, p, n);
}

void bt_stream_closed(uint8_t link, bool lost)
{
    comm_link_close(link, lost ? COMM_LINK_LOST : COMM_LINK_CLOSED);
}

void bt_framed_opened(uint8_t link)
{
    comm_link_open(link, &framed_driver);
}

void bt_framed_rx(uint8_t link, const uint8_t *p, uint16_t n)
{
    comm_link_rx(link, p, n);
}

void bt_framed_closed(uint8_t link, bool lost)
{
    comm_link_close(link, lost ? COMM_LINK_LOST : COMM_LINK_CLOSED);
}

void bt_init(void)
{
    hci_init();
    l2cap_init();
    rfcomm_init();
}

void bt_task(void)
{
    hci_task();
    l2cap_task();
    rfcomm_task();
}
