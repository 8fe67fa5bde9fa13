#include "comm.h"

#include <stddef.h>
#include <string.h>

#include "core/data.h"
#include "drivers/uart.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"

_Static_assert(COMM_LINKS >= 1u && COMM_LINKS <= 8u, "a link is one bit of a byte");
#define BIT(k) ((uint8_t)(1u << (k)))
#define LABEL_SIZE sizeof(((pb_set_role_t *)0)->label)

static uint8_t tx_seq;

/* Handlers by the index of their type in pb_packet_info (registered by the modules). */
static comm_handler_t handlers[PB_PACKET_INFO_COUNT];

/* One host link. Its host session and the acked commands that session had accepted, each by its seq and the CRC
 * of its frame (which covers type, seq, length and payload): only an identical frame is a retransmission. */
typedef struct {
    const comm_link_driver_t *drv; /* NULL while closed */
    slip_decoder_t rx;
    uint32_t session; /* 0: none */
    struct {
        uint8_t seq; /* 0: empty (acked commands never carry 0) */
        uint16_t crc;
    } history[COMM_SEQ_HISTORY];
    uint8_t history_next;
    uint8_t wants;  /* PB_HOST_ROLE_WATCH, or _DRIVE: it drives as soon as nobody does */
    uint8_t change; /* of the `driver` packet owed to this link (bit in `owed`) */
    char label[LABEL_SIZE];
} link_t;

static link_t links[COMM_LINKS];
static uint8_t open_links; /* bit k: link k has a driver */
static uint8_t framed_links;
static uint8_t polled_links; /* bit k: comm_task() takes link k's bytes with its driver's rx_take */
static uint8_t owed; /* bit k: link k is owed a `driver` packet */

/* The drive. A driver whose link is lost keeps it (link COMM_NO_LINK) until its host returns with its session, or
 * another host asks for it once the driver has been silent for the hold (`expired`, set a tick before: the failsafe
 * has stopped what the silent driver drove by then); `guarded` tells the failsafe whether motion is still the
 * driver's to guard. */
static struct {
    uint8_t taken;
    uint8_t link;
    uint8_t expired;
    uint32_t session;
    uint32_t seen_ms; /* its last sound frame */
    char label[LABEL_SIZE];
} seat;
static uint8_t guarded;

/* The link being answered: the frame's while its handler runs, the asker's while an answer goes on. */
static uint8_t reply;
static uint8_t frame_type; /* the type of the frame being handled */

/* Offers refused because a streamed frame was still being encoded, since one last went out. */
#define OFFER_PATIENCE 4u
static uint8_t offer_waits;

/* Answers under way (read_settings and read_movements can overlap), each with the link that asked. */
#define COMM_ANSWERS 2u
static struct {
    comm_answer_step_t step;
    uint8_t link;
    uint8_t type;
} answers[COMM_ANSWERS];
static uint8_t answering; /* how many of answers[] are set */

static uint32_t link_error_ms; /* when the last answer to an unreadable frame went out */
static uint8_t link_error_sent;

/* A packet sent over several ticks (comm_send_streamed()): its frame bytes are copied at once, then CRC'd and
 * SLIP-encoded COMM_STREAM_CHUNK bytes per comm_task() to the stream links in `to`, each chunk written as it is
 * encoded; the framed links in `to` get the whole frame once its CRC is known. Room for the worst case was found
 * at the start, and nothing else is written to those links until the frame is complete (frame_out() completes
 * it first). buf is also the scratch where frame_out() assembles a frame for framed links. */
static struct {
    uint8_t active;
    uint8_t to;
    uint8_t len;  /* frame bytes in buf (header and payload) */
    uint8_t done; /* bytes already encoded */
    uint16_t crc; /* CRC of buf[0..done) */
    uint8_t buf[PB_MAX_FRAME];
} stream;

static uint8_t on_heartbeat(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_hello_request(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_set_role(const pb_frame_t *cmd, uint16_t *detail);

void comm_init(void)
{
    pb_packet_lookup_init();
    memset(handlers, 0, sizeof handlers);
    memset(links, 0, sizeof links);
    memset(&seat, 0, sizeof seat);
    memset(answers, 0, sizeof answers);
    open_links = framed_links = polled_links = owed = 0;
    seat.link = reply = COMM_NO_LINK;
    guarded = 0;
    tx_seq = 0;
    stream.active = 0;
    offer_waits = 0;
    answering = 0;
    link_error_sent = 0;
    comm_register(PB_PKT_HEARTBEAT, on_heartbeat);
    comm_register(PB_PKT_HELLO_REQUEST, on_hello_request);
    comm_register(PB_PKT_SET_ROLE, on_set_role);
}

void comm_register(uint8_t type, comm_handler_t handler)
{
    uint8_t i = pb_packet_index(type);
    if (i != PB_PACKET_NONE)
        handlers[i] = handler;
}

/* ---- output ---- */

/* SLIP-encoded bytes on their way to the stream links of `to`. When one link is the only one and has a transmit ring
 * of its own (the UART of a serial robot with one host, an RFCOMM channel) they are written straight into that ring,
 * as fast as a frame can be sent; otherwise into a chunk that is written out to each link as it fills. One at a
 * time: frames never nest. */
#define OUT_CHUNK 32u
static struct {
    uint8_t to;
    uint8_t direct; /* buf is the transmit ring of link `ring` */
    uint8_t ring;
    uint8_t pos;    /* where the next byte goes in buf */
    uint8_t *buf;
    uint8_t chunk[OUT_CHUNK + 2]; /* one more byte and its escape fit after a chunk's worth */
} out;

static inline void out_begin(uint8_t to)
{
    out.to = to;
    out.direct = 0;
    out.buf = out.chunk;
    out.pos = 0;
    if (to == 0 || (to & (uint8_t)(to - 1u)))
        return; /* no link, or several */
    uint8_t k = 0;
    while (k < COMM_LINKS - 1u && !(to & BIT(k)))
        k++;
    const comm_link_driver_t *d = links[k].drv;
    if (d != NULL && d->tx_ring != NULL) {
        out.direct = 1;
        out.ring = k;
        out.buf = d->tx_ring(k, &out.pos);
    }
}

/* Hands on what was written: published to the link's ring at once, or the chunk written to each link. */
static void out_flush(void)
{
    if (out.direct) {
        links[out.ring].drv->tx_commit(out.ring, out.pos);
        return;
    }
    uint8_t bit = 1;
    for (uint8_t k = 0; k < COMM_LINKS && bit <= out.to; k++, bit = (uint8_t)(bit << 1))
        if (out.to & bit)
            links[k].drv->tx_write(k, out.chunk, out.pos);
    out.pos = 0;
}

static void out_put(uint8_t b)
{
    if (b == SLIP_END || b == SLIP_ESC) {
        out.buf[out.pos++] = SLIP_ESC;
        b = b == SLIP_END ? SLIP_ESC_END : SLIP_ESC_ESC;
    }
    out.buf[out.pos++] = b;
}

/* The inner loop of every packet sent: CRC and SLIP-escape `n` bytes; a chunk is written out whenever it fills,
 * a link's own ring has room for all of it. */
static uint16_t out_encode(uint16_t crc, const uint8_t *p, uint8_t n)
{
    uint8_t i = out.pos;
    uint8_t *buf = out.buf;
    if (out.direct) {
        while (n--) {
            uint8_t b = *p++;
            crc = pb_crc16_byte(crc, b);
            if (b == SLIP_END || b == SLIP_ESC) {
                buf[i++] = SLIP_ESC;
                b = b == SLIP_END ? SLIP_ESC_END : SLIP_ESC_ESC;
            }
            buf[i++] = b;
        }
    } else {
        while (n--) {
            uint8_t b = *p++;
            crc = pb_crc16_byte(crc, b);
            if (b == SLIP_END || b == SLIP_ESC) {
                buf[i++] = SLIP_ESC;
                b = b == SLIP_END ? SLIP_ESC_END : SLIP_ESC_ESC;
            }
            buf[i++] = b;
            if (i >= OUT_CHUNK) {
                out.pos = i;
                out_flush();
                i = 0;
            }
        }
    }
    out.pos = i;
    return crc;
}

/* The CRC and the closing END, and everything handed on. */
static void out_end(uint16_t crc)
{
    out_put((uint8_t)crc);
    out_put((uint8_t)(crc >> 8));
    out.buf[out.pos++] = SLIP_END;
    out_flush();
}

static uint8_t slip_extra(const uint8_t *p, uint8_t n)
{
    uint8_t k = 0;
    while (n--) {
        uint8_t b = *p++;
        k += (b == SLIP_END) | (b == SLIP_ESC);
    }
    return k;
}

static uint8_t count_bits(uint8_t m)
{
    uint8_t n = 0;
    for (; m; m &= (uint8_t)(m - 1u))
        n++;
    return n;
}

/* The links of `to` with room for a frame: `framed` bytes on a framed link; on a stream link `worst` bytes (every
 * byte escaped), or the exact escaped size `exact()` counts, asked only when a link has less room than that. */
static uint8_t with_room(uint8_t to, uint16_t framed, uint16_t worst, uint16_t (*exact)(void))
{
    uint8_t ok = 0;
    uint16_t need = 0;
    uint8_t bit = 1;
    for (uint8_t k = 0; k < COMM_LINKS && bit <= to; k++, bit = (uint8_t)(bit << 1)) {
        if (!(to & bit))
            continue;
        const comm_link_driver_t *d = links[k].drv;
        uint16_t room = d == &comm_uart_link ? uart_tx_free() : d->tx_room(k);
        if (d->framed ? room >= framed
                      : room >= worst || (exact != NULL && room >= (need ? need : (need = exact()))))
            ok |= bit;
    }
    return ok;
}

/* Writes a whole frame (header, payload and CRC in buf) to the framed links of `to`. */
static void framed_out(uint8_t to, const uint8_t *buf, uint16_t n)
{
    uint8_t bit = 1;
    for (uint8_t k = 0; k < COMM_LINKS && bit <= to; k++, bit = (uint8_t)(bit << 1))
        if (to & bit)
            links[k].drv->tx_write(k, buf, n);
}

/* The snapshot of a streamed packet. On the AVR four bytes per loop step: under 5 cycles a byte against 8 for
 * memcpy(), which matters in the tick that also takes the snapshot. */
static void snapshot(uint8_t *dst, const uint8_t *src, uint8_t n)
{
#if defined(__AVR__)
    uint8_t quads = n >> 2;
    if (quads) {
        uint8_t tmp;
        __asm__ volatile("1: ld %[t], Z+"  "\n\t"
                         "st X+, %[t]"     "\n\t"
                         "ld %[t], Z+"     "\n\t"
                         "st X+, %[t]"     "\n\t"
                         "ld %[t], Z+"     "\n\t"
                         "st X+, %[t]"     "\n\t"
                         "ld %[t], Z+"     "\n\t"
                         "st X+, %[t]"     "\n\t"
                         "dec %[q]"        "\n\t"
                         "brne 1b"
                         : [t] "=&r"(tmp), [q] "+r"(quads), "+x"(dst), "+z"(src)
                         :
                         : "memory");
    }
    n &= 3u;
#endif
    while (n--)
        *dst++ = *src++;
}

/* Encodes the rest of the streamed frame, or up to `max` more bytes of it (and its end once all are done). */
static void stream_step(uint8_t max)
{
    out_begin(stream.to & (uint8_t)~framed_links);
    uint8_t i = stream.done;
    uint8_t n = (uint8_t)(stream.len - i > max ? max : stream.len - i);
    uint16_t crc = out_encode(stream.crc, stream.buf + i, n);
    stream.crc = crc;
    stream.done = (uint8_t)(i + n);
    if (stream.done < stream.len) {
        out_flush();
        return;
    }
    out_end(crc);
    stream.active = 0;
    if (stream.to & framed_links) {
        stream.buf[stream.len] = (uint8_t)crc;
        stream.buf[stream.len + 1u] = (uint8_t)(crc >> 8);
        framed_out(stream.to & framed_links, stream.buf, (uint16_t)(stream.len + PB_FRAME_CRC_SIZE));
    }
}

bool comm_send_streamed(uint8_t type, const void *payload, uint8_t len)
{
    if (stream.active)
        stream_step(0xFFu); /* the previous one first */
    if (len > sizeof stream.buf - PB_FRAME_HEADER_SIZE - PB_FRAME_CRC_SIZE)
        return comm_send(type, payload, len);
    /* The worst case on every stream link: the escapes are not known before the CRC is. A serial robot with one
     * host asks its UART alone, without the round of every link (this is the tick that takes the snapshot). */
    uint16_t framed = (uint16_t)(PB_FRAME_HEADER_SIZE + len + PB_FRAME_CRC_SIZE);
    uint16_t worst = (uint16_t)(2u * framed + 2u);
    uint8_t to = open_links == 1u && links[0].drv == &comm_uart_link ? (uart_tx_free() >= worst)
                                                                       : with_room(open_links, framed, worst, NULL);
    if (to != open_links)
        robot_state.errors.tx_dropped += count_bits(open_links & (uint8_t)~to);
    if (!to)
        return false;
    stream.buf[0] = type;
    stream.buf[1] = tx_seq++;
    stream.buf[2] = len;
    snapshot(stream.buf + PB_FRAME_HEADER_SIZE, (const uint8_t *)payload, len);
    stream.len = (uint8_t)(PB_FRAME_HEADER_SIZE + len);
    stream.done = 0;
    stream.crc = 0xFFFFu;
    stream.to = to;
    stream.active = 1;
    out_begin(to & (uint8_t)~framed_links);
    out.buf[out.pos++] = SLIP_END;
    out_flush();
    return true;
}

/* The frame being sent by frame_out(), for the exact size of its escaped form. */
static const uint8_t *out_head, *out_payload;
static uint8_t out_len;
static uint16_t frame_exact(void)
{
    /* Both ENDs, and the CRC's two bytes at their worst (it is not known yet). */
    return (uint16_t)(2u + PB_FRAME_HEADER_SIZE + slip_extra(out_head, PB_FRAME_HEADER_SIZE) + out_len +
                      slip_extra(out_payload, out_len) + 2u * PB_FRAME_CRC_SIZE);
}

/* Frames a packet to the links of `to` that have room, in one pass that SLIP-encodes and computes the CRC; framed
 * links get it whole. When a link of `must`, or every link, lacks room nothing is sent or counted (the caller
 * counts, or tries again later); else the links of `to` without room miss it (counted in tx_dropped).
 * \return false when nothing was sent. */
static bool frame_out(uint8_t to, uint8_t must, uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    const uint8_t *p = (const uint8_t *)payload;
    uint8_t head[PB_FRAME_HEADER_SIZE] = {type, seq, len};
    if (len > PB_MAX_PAYLOAD)
        return false;
    if (stream.active)
        stream_step(0xFFu); /* frames never interleave: a streamed one is completed first */
    to &= open_links;
    must &= to;
    out_head = head;
    out_payload = p;
    out_len = len;
    uint16_t framed_size = (uint16_t)(sizeof head + len + PB_FRAME_CRC_SIZE);
    uint16_t worst = (uint16_t)(2u * framed_size + 2u);
    /* A serial robot with one host asks its UART alone, as comm_send_streamed() does. */
    uint8_t ok = to == 1u && links[0].drv == &comm_uart_link && uart_tx_free() >= worst
                     ? 1u
                     : with_room(to, framed_size, worst, frame_exact);
    if (!ok || (ok & must) != must)
        return false;
    robot_state.errors.tx_dropped += count_bits(to & (uint8_t)~ok);
    out_begin(ok & (uint8_t)~framed_links);
    out.buf[out.pos++] = SLIP_END;
    uint16_t crc = out_encode(0xFFFFu, head, sizeof head);
    crc = out_encode(crc, p, len);
    if (out.to)
        out_end(crc);
    if (ok & framed_links) { /* the stream buffer is free: the streamed frame was completed above */
        memcpy(stream.buf, head, sizeof head);
        memcpy(stream.buf + sizeof head, p, len);
        stream.buf[sizeof head + len] = (uint8_t)crc;
        stream.buf[sizeof head + len + 1u] = (uint8_t)(crc >> 8);
        framed_out(ok & framed_links, stream.buf, framed_size);
    }
    return true;
}

/* The link being answered, or every link outside an answer. */
static uint8_t answered(void)
{
    return reply < COMM_LINKS ? BIT(reply) : open_links;
}

/* To the links of `to` that have room; the others are counted. \return false when none had room. */
static bool send_to(uint8_t to, uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    if (frame_out(to, 0, type, seq, payload, len))
        return true;
    robot_state.errors.tx_dropped += count_bits(to & open_links);
    return false;
}

static void send_seq(uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    send_to(answered(), type, seq, payload, len);
}

bool comm_send(uint8_t type, const void *payload, uint8_t len)
{
    return send_to(open_links, type, tx_seq++, payload, len);
}

/* Completing a streamed frame now would put its cost into the caller's tick: a frame that must not be lost waits
 * for comm_task() to finish it, unless it has already waited OFFER_PATIENCE times (a stream every tick never
 * finishes). \return true when it may go now. */
static bool stream_allows(void)
{
    if (stream.active && offer_waits < OFFER_PATIENCE) {
        offer_waits++;
        return false;
    }
    offer_waits = 0;
    return true;
}

bool comm_offer(uint8_t type, const void *payload, uint8_t len)
{
    if (!stream_allows())
        return false;
    uint8_t to = answered();
    uint8_t must = reply < COMM_LINKS ? to : seat.link < COMM_LINKS ? BIT(seat.link) : 0;
    if (!frame_out(to, must, type, tx_seq, payload, len) && (to & open_links))
        return false;
    tx_seq++;
    return true;
}

bool comm_ack(uint8_t type, uint8_t seq)
{
    pb_ack_t a = {type};
    uint8_t to = answered();
    return stream_allows() && (frame_out(to, to, PB_PKT_ACK, seq, &a, sizeof a) || !(to & open_links));
}

static void send_error(uint8_t code, uint8_t type, uint8_t seq, uint16_t detail)
{
    pb_error_t e = {code, type, seq, detail};
    send_seq(PB_PKT_ERROR, seq, &e, sizeof e);
}

/* In answer to a hello_request the hello carries its sequence number; at reset it carries 0, so a host can tell
 * the two apart. */
static void send_hello(uint8_t resumed, uint8_t seq)
{
    pb_hello_t h;
    h.robot_id = settings.identity.robot_id;
    memcpy(h.name, settings.identity.name, sizeof h.name);
    h.fw_major = PB_FW_MAJOR;
    h.fw_minor = PB_FW_MINOR;
    h.fw_patch = PB_FW_PATCH;
    h.protocol_version = PB_PROTOCOL_VERSION;
    h.layout_hash = PB_LAYOUT_HASH;
    h.settings_size = sizeof(pb_settings_t);
    h.state_size = sizeof(pb_robot_state_t);
    h.session_resumed = resumed;
    h.settings_crc = pb_crc16(0xFFFFu, (const uint8_t *)&settings, sizeof settings);
    send_seq(PB_PKT_HELLO, seq, &h, sizeof h);
}

void comm_send_hello(void)
{
    send_hello(0, 0);
}

/* ---- the drive ---- */

uint32_t comm_host_seen_ms(void)
{
    return guarded ? seat.seen_ms : robot_state.time.time_ms;
}

uint8_t comm_driver_link(void)
{
    return seat.link;
}

/* Link k is owed a `driver` packet; a change already owed to it is not overwritten by "none". */
static void owe(uint8_t k, uint8_t change)
{
    if (!(owed & BIT(k)) || change != PB_DRIVER_CHANGE_NONE)
        links[k].change = change;
    owed |= BIT(k);
}

static void announce(uint8_t change)
{
    for (uint8_t k = 0; k < COMM_LINKS; k++)
        if (open_links & BIT(k))
            owe(k, change);
}

/* Sends what is owed; what does not fit goes in a later tick. */
static void pay_debts(void)
{
    for (uint8_t k = 0; k < COMM_LINKS; k++) {
        if (!(owed & BIT(k)))
            continue;
        pb_driver_t d;
        d.role = seat.link == k ? PB_HOST_ROLE_DRIVE : PB_HOST_ROLE_WATCH;
        d.change = links[k].change;
        memcpy(d.label, seat.label, sizeof d.label);
        d.time_ms = robot_state.time.time_ms;
        if (frame_out(BIT(k), BIT(k), PB_PKT_DRIVER, tx_seq, &d, sizeof d)) {
            tx_seq++;
            owed &= (uint8_t)~BIT(k);
        }
    }
}

static void seat_take(uint8_t k, uint8_t change)
{
    seat.taken = 1;
    seat.expired = 0;
    seat.link = k;
    seat.session = links[k].session;
    memcpy(seat.label, links[k].label, sizeof seat.label);
    seat.seen_ms = robot_state.time.time_ms;
    guarded = 1;
    announce(change);
}

/* \return the first link (but `except`) whose host asked to drive and waits for it, or COMM_NO_LINK. */
static uint8_t waiting_host(uint8_t except)
{
    for (uint8_t k = 0; k < COMM_LINKS; k++)
        if ((open_links & BIT(k)) && k != except && links[k].wants == PB_HOST_ROLE_DRIVE)
            return k;
    return COMM_NO_LINK;
}

/* Nobody drives now: the driver left on purpose (goodbye, or it asked to watch), so what it queued is the robot's to
 * finish and the failsafe guards nothing; a host that asked to drive and was waiting gets the drive. */
static void seat_free(uint8_t change)
{
    guarded = 0;
    seat.taken = 0;
    seat.link = COMM_NO_LINK;
    seat.expired = 0;
    seat.session = 0;
    memset(seat.label, 0, sizeof seat.label);
    uint8_t next = waiting_host(COMM_NO_LINK);
    if (next != COMM_NO_LINK)
        seat_take(next, change);
    else
        announce(change);
}

/* A driver that has not been heard for the hold may lose the drive to a host that asks for it: marked here, at the
 * end of the tick's comm work, and handed over from the next tick on (the failsafe, which runs after comm, has
 * stopped what the silent driver drove by then, whatever the steps of the clock). Nobody waiting, it keeps it. */
static void seat_watch(void)
{
    uint8_t next = seat.expired ? waiting_host(seat.link) : COMM_NO_LINK;
    if (next != COMM_NO_LINK) {
        seat_take(next, PB_DRIVER_CHANGE_LOST);
        return;
    }
    uint16_t hold = settings.link.failsafe_timeout_ms ? settings.link.failsafe_timeout_ms : COMM_DRIVER_HOLD_MS;
    if (robot_state.time.time_ms - seat.seen_ms >= hold)
        seat.expired = 1;
}

/* The host on link k leaves the drive (`goodbye`, or `set_role` to watch): the driver's leave ends the failsafe's
 * guard (what it queued is the robot's to finish, or to drop as a goodbye's handler did). */
static void leave(uint8_t k)
{
    links[k].wants = PB_HOST_ROLE_WATCH;
    if (seat.link == k)
        seat_free(PB_DRIVER_CHANGE_LEFT);
}

/* ---- links ---- */

void comm_link_open(uint8_t link, const comm_link_driver_t *drv)
{
    if (link >= COMM_LINKS || drv == NULL)
        return;
    link_t *l = &links[link];
    l->drv = drv;
    slip_decoder_init(&l->rx);
    if (seat.link == link)
        seat.link = COMM_NO_LINK; /* a new connection: its host says who it is in its hello_request */
    l->wants = PB_HOST_ROLE_WATCH;
    open_links |= BIT(link);
    if (drv->rx_take != NULL)
        polled_links |= BIT(link);
    else
        polled_links &= (uint8_t)~BIT(link);
    if (drv->framed)
        framed_links |= BIT(link);
    else
        framed_links &= (uint8_t)~BIT(link);
    owed &= (uint8_t)~BIT(link);
}

void comm_link_close(uint8_t link, uint8_t why)
{
    (void)why; /* closed or lost: the drive waits for its host either way (comm.h) */
    if (link >= COMM_LINKS || links[link].drv == NULL)
        return;
    links[link].drv = NULL;
    links[link].wants = PB_HOST_ROLE_WATCH;
    open_links &= (uint8_t)~BIT(link);
    polled_links &= (uint8_t)~BIT(link);
    stream.to &= (uint8_t)~BIT(link);
    owed &= (uint8_t)~BIT(link);
    if (seat.link == link)
        seat.link = COMM_NO_LINK; /* the driver keeps the drive until it returns or its hold ends */
}

static uint8_t on_heartbeat(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)cmd;
    (void)detail;
    return PB_ERROR_CODE_NONE; /* its arrival is all the failsafe needs */
}

/* The session follows its host: a host that reconnects on another link brings its duplicate history along, and the
 * drive if it held it. */
static uint8_t on_hello_request(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)detail;
    pb_hello_request_t r;
    memcpy(&r, cmd->payload, sizeof r);
    link_t *l = &links[reply];
    uint8_t resumed = r.session != 0 && r.session == l->session;
    for (uint8_t k = 0; k < COMM_LINKS && r.session != 0 && !resumed; k++) {
        link_t *other = &links[k];
        if (other == l || other->session != r.session)
            continue;
        l->session = other->session;
        memcpy(l->history, other->history, sizeof l->history);
        l->history_next = other->history_next;
        other->session = 0;
        memset(other->history, 0, sizeof other->history);
        resumed = 1;
    }
    if (!resumed) { /* another host, or one that restarted: its sequence numbers owe nothing to the last one's */
        l->session = r.session;
        memset(l->history, 0, sizeof l->history);
        l->history_next = 0;
        l->wants = PB_HOST_ROLE_WATCH;
    }
    if (seat.taken && r.session != 0 && r.session == seat.session) {
        seat.link = reply;
        seat.seen_ms = robot_state.time.time_ms;
        seat.expired = 0;
    } else if (seat.link == reply) {
        seat.link = COMM_NO_LINK; /* another host on the driver's link: the driver's own link is gone */
    }
    send_hello(resumed, cmd->seq);
    return PB_ERROR_CODE_NONE;
}

static uint8_t on_set_role(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_set_role_t r;
    memcpy(&r, cmd->payload, sizeof r);
    if (r.role > PB_HOST_ROLE_TAKE_OVER) {
        *detail = offsetof(pb_set_role_t, role);
        return PB_ERROR_CODE_BAD_ARGUMENT;
    }
    uint8_t k = reply;
    link_t *l = &links[k];
    memcpy(l->label, r.label, sizeof l->label);
    if (r.role == PB_HOST_ROLE_WATCH) {
        leave(k);
    } else {
        l->wants = PB_HOST_ROLE_DRIVE;
        if (seat.link == k)
            memcpy(seat.label, l->label, sizeof seat.label);
        else if (!seat.taken)
            seat_take(k, PB_DRIVER_CHANGE_CLAIMED);
        else if (seat.expired)
            seat_take(k, PB_DRIVER_CHANGE_LOST);
        else if (r.role == PB_HOST_ROLE_TAKE_OVER)
            seat_take(k, PB_DRIVER_CHANGE_TAKEN_OVER);
        /* else another host drives: this one watches until the drive is free */
    }
    owe(k, PB_DRIVER_CHANGE_NONE); /* its answer: who drives now, before the ack */
    return PB_ERROR_CODE_NONE;
}

/* ---- input ---- */

static bool seen_before(const link_t *l, uint8_t seq, uint16_t crc)
{
    for (uint8_t i = 0; i < COMM_SEQ_HISTORY; i++)
        if (l->history[i].seq == seq && l->history[i].crc == crc)
            return true;
    return false;
}

static void remember(link_t *l, uint8_t seq, uint16_t crc)
{
    l->history[l->history_next].seq = seq;
    l->history[l->history_next].crc = crc;
    l->history_next = (uint8_t)((l->history_next + 1u) % COMM_SEQ_HISTORY);
}

/* An unreadable frame: its type and seq cannot be trusted, so the answer names neither, and at most one such
 * answer goes out per COMM_LINK_ERROR_INTERVAL_MS (the counters count every one). */
static void link_error(uint8_t code, uint16_t length)
{
    uint32_t now = robot_state.time.time_ms;
    if (link_error_sent && now - link_error_ms < COMM_LINK_ERROR_INTERVAL_MS)
        return;
    link_error_sent = 1;
    link_error_ms = now;
    send_error(code, 0, 0, length);
}

static void reject(uint8_t code, uint8_t type, uint8_t seq, uint16_t detail)
{
    robot_state.errors.rejected++;
    send_error(code, type, seq, detail);
}

static void send_ack(uint8_t type, uint8_t seq)
{
    pb_ack_t a = {type};
    send_seq(PB_PKT_ACK, seq, &a, sizeof a);
}

/* A request whose answer runs for another link now: it waits (not answered, the host asks again). */
static bool answering_another(uint8_t type, uint8_t link)
{
    for (uint8_t i = 0; i < COMM_ANSWERS; i++)
        if (answers[i].step != NULL && answers[i].type == type && answers[i].link != link)
            return true;
    return false;
}

static void dispatch(uint8_t link, const uint8_t *frame, uint16_t n)
{
    pb_frame_t f = {0, 0, 0, NULL};
    uint8_t code = pb_frame_check(frame, n, &f);
    if (code == PB_ERROR_CODE_BAD_CRC) {
        robot_state.errors.crc++;
        link_error(code, n);
        return;
    }
    if (code == PB_ERROR_CODE_TOO_SHORT || code == PB_ERROR_CODE_TOO_LONG) {
        robot_state.errors.framing++;
        link_error(code, n);
        return;
    }
    bool drives = seat.link == link;
    if (drives) { /* a sound CRC: the driver is there */
        seat.seen_ms = robot_state.time.time_ms;
        seat.expired = 0;
    }
    if (code == PB_ERROR_CODE_BAD_LENGTH) { /* the header's length disagrees with the frame */
        reject(code, frame[0], frame[1], frame[2]);
        return;
    }
    uint8_t index = pb_packet_index(f.type);
    if (index == PB_PACKET_NONE || handlers[index] == NULL) { /* only host-to-robot types have handlers */
        reject(PB_ERROR_CODE_UNKNOWN_TYPE, f.type, f.seq, f.type);
        return;
    }
    comm_handler_t handler = handlers[index];
    const PB_FLASH pb_packet_info_t *info = &pb_packet_info[index];
    if (f.len < info->min_size || f.len > info->max_size) {
        reject(PB_ERROR_CODE_BAD_LENGTH, f.type, f.seq, f.len);
        return;
    }
    bool acked = info->needs_ack != 0;
    bool remembered = acked && !info->idempotent;
    uint16_t crc = (uint16_t)(frame[n - 2] | (frame[n - 1] << 8));
    if (acked && f.seq == 0) {
        reject(PB_ERROR_CODE_BAD_SEQUENCE, f.type, f.seq, 0);
        return;
    }
    link_t *l = &links[link];
    if (remembered && seen_before(l, f.seq, crc)) {
        send_ack(f.type, f.seq); /* a retransmission: the first one was executed */
        return;
    }
    if (!info->watcher_ok && !drives) {
        owe(link, PB_DRIVER_CHANGE_NONE); /* it learns who drives, before the refusal */
        pay_debts();
        reject(PB_ERROR_CODE_NOT_DRIVER, f.type, f.seq, 0);
        return;
    }
    if (answering && answering_another(f.type, link))
        return;
    uint16_t detail = 0;
    bool goodbye = f.type == PB_PKT_GOODBYE;
    frame_type = f.type;
    code = goodbye && !drives ? PB_ERROR_CODE_NONE : handler(&f, &detail); /* a watcher's goodbye moves nothing */
    if (code != PB_ERROR_CODE_NONE && code != COMM_ANSWER_LATER) {
        reject(code, f.type, f.seq, detail);
        return;
    }
    if (remembered)
        remember(l, f.seq, crc);
    if (goodbye)
        leave(link);
    if (owed)
        pay_debts(); /* a set_role's `driver` before its ack */
    if (acked && code == PB_ERROR_CODE_NONE)
        send_ack(f.type, f.seq);
}

/* A frame from an open link. */
static void receive(uint8_t link, const uint8_t *frame, uint16_t n)
{
    uint8_t outer = reply;
    reply = link;
    dispatch(link, frame, n);
    reply = outer;
}

void comm_handle_frame(uint8_t link, const uint8_t *frame, uint16_t n)
{
    if (link < COMM_LINKS && links[link].drv != NULL)
        receive(link, frame, n);
}

/* One received byte of stream link `link`, whose decoder is `rx`. */
static void rx_byte(uint8_t link, slip_decoder_t *rx, uint8_t b)
{
    slip_result_t r = slip_decode(rx, b);
    if (r == SLIP_FRAME) {
        receive(link, rx->buf, rx->len);
    } else if (r == SLIP_ERROR) {
        robot_state.errors.framing++;
        uint8_t outer = reply;
        reply = link;
        link_error(rx->overflow ? PB_ERROR_CODE_TOO_LONG : PB_ERROR_CODE_FRAMING, slip_seen(rx));
        reply = outer;
    }
}

void comm_link_rx(uint8_t link, const uint8_t *p, uint16_t n)
{
    if (link >= COMM_LINKS || links[link].drv == NULL)
        return;
    if (links[link].drv->framed) {
        receive(link, p, n);
        return;
    }
    slip_decoder_t *rx = &links[link].rx;
    while (n && links[link].drv != NULL) {
        uint16_t k = slip_decode_plain(rx, p, n); /* the frame's body in bulk, its ENDs and escapes one by one */
        p += k;
        n = (uint16_t)(n - k);
        if (n) {
            rx_byte(link, rx, *p++);
            n--;
        }
    }
}

/* The links whose received bytes comm_task() takes: each with rx_take, a batch at a time. */
static __attribute__((noinline)) uint8_t take_received(uint8_t budget)
{
    uint8_t bit = 1;
    for (uint8_t k = 0; k < COMM_LINKS && bit <= polled_links; k++, bit = (uint8_t)(bit << 1)) {
        if (!(polled_links & bit))
            continue;
        uint8_t buf[16], n;
        while (budget > 0 && (polled_links & bit) &&
               (n = links[k].drv->rx_take(k, buf, budget < sizeof buf ? budget : (uint8_t)sizeof buf)) > 0) {
            budget = (uint8_t)(budget - n);
            comm_link_rx(k, buf, n);
        }
    }
    return budget;
}

/* ---- answers ---- */

void comm_answer_later(comm_answer_step_t step)
{
    uint8_t free_slot = COMM_ANSWERS;
    for (uint8_t i = 0; i < COMM_ANSWERS; i++) {
        if (answers[i].step == step)
            return;
        if (answers[i].step == NULL)
            free_slot = i;
    }
    if (free_slot < COMM_ANSWERS) { /* there is one per kind of answer: never full */
        answers[free_slot].step = step;
        answers[free_slot].link = reply;
        answers[free_slot].type = frame_type;
        answering++;
    }
}

static void continue_answers(void)
{
    for (uint8_t i = 0; i < COMM_ANSWERS; i++) {
        if (answers[i].step == NULL)
            continue;
        reply = answers[i].link;
        if (answers[i].step()) {
            answers[i].step = NULL;
            answering--;
        }
    }
    reply = COMM_NO_LINK;
}

/* ---- the UART as a stream link ---- */

static uint16_t uart_room(uint8_t link)
{
    (void)link;
    return uart_tx_free();
}

static void uart_write(uint8_t link, const uint8_t *p, uint16_t n)
{
    (void)link;
    uint8_t pos = uart_tx_begin();
    while (n--)
        pos = uart_tx_store(pos, *p++);
    uart_tx_commit(pos);
    uart_tx_flush();
}

static uint8_t *uart_ring(uint8_t link, uint8_t *pos)
{
    (void)link;
    *pos = uart_tx_begin();
    return uart_tx_buf;
}

static void uart_commit(uint8_t link, uint8_t pos)
{
    (void)link;
    uart_tx_commit(pos);
    uart_tx_flush();
}

/* Its received bytes are read by comm_task() itself, while it is link 0 (rx_take NULL). */
const comm_link_driver_t comm_uart_link = {false, uart_room, uart_write, NULL, uart_ring, uart_commit};

void comm_task(void)
{
    uint8_t budget = 255; /* bytes received per tick over all links: bound the work of one tick */
    if (links[0].drv == &comm_uart_link) { /* the serial link, straight from the UART's ring */
        uint8_t b;
        while (budget && uart_getc(&b)) {
            budget--;
            if (!slip_take_plain(&links[0].rx, b)) /* a frame's body without a call a byte */
                rx_byte(0, &links[0].rx, b);
        }
    }
    if (polled_links)
        take_received(budget);
    robot_state.errors.rx_overflow = uart_rx_overflows();
    if (stream.active)
        stream_step(COMM_STREAM_CHUNK);
    if (seat.taken)
        seat_watch();
    if (owed)
        pay_debts();
    if (answering)
        continue_answers();
}
