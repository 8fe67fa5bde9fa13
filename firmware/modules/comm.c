#include "comm.h"

#include <string.h>

#include "core/data.h"
#include "drivers/uart.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"

static slip_decoder_t rx;
static uint8_t tx_seq;

/* Handlers by the index of their type in pb_packet_info (registered by the modules). */
static comm_handler_t handlers[PB_PACKET_INFO_COUNT];

/* The host session served (0: none), and the acked commands it had accepted, each by its seq and the CRC of
 * its frame (which covers type, seq, length and payload): only an identical frame is a retransmission. */
static uint32_t session;
static struct {
    uint8_t seq; /* 0: empty (acked commands never carry 0) */
    uint16_t crc;
} history[COMM_SEQ_HISTORY];
static uint8_t history_next;

/* Offers refused because a streamed frame was still being encoded, since one last went out. */
#define OFFER_PATIENCE 4u
static uint8_t offer_waits;

/* Answers under way (read_settings and read_movements can overlap). */
#define COMM_ANSWERS 2u
static comm_answer_step_t answers[COMM_ANSWERS];
static uint8_t answering; /* how many of answers[] are set */

static uint32_t host_seen_ms;
static uint32_t link_error_ms; /* when the last answer to an unreadable frame went out */
static uint8_t link_error_sent;

/* A packet sent over several ticks (comm_send_streamed()): its frame bytes are copied at once, then CRC'd
 * and SLIP-encoded into the transmit buffer COMM_STREAM_CHUNK bytes per comm_task(), each chunk published to
 * the UART interrupt as it is written. Room for the worst case was checked at the start, and nothing else is
 * written to the buffer until the frame is complete (comm_send_seq() completes it first). */
static struct {
    uint8_t active;
    uint8_t len;  /* frame bytes in buf (header and payload) */
    uint8_t done; /* bytes already encoded */
    uint16_t crc; /* CRC of buf[0..done) */
    uint8_t buf[PB_FRAME_HEADER_SIZE + sizeof(pb_robot_state_t)];
} stream;

static uint8_t on_heartbeat(const pb_frame_t *cmd, uint16_t *detail);
static uint8_t on_hello_request(const pb_frame_t *cmd, uint16_t *detail);

void comm_init(void)
{
    slip_decoder_init(&rx);
    pb_packet_lookup_init();
    memset(handlers, 0, sizeof handlers);
    memset(history, 0, sizeof history);
    history_next = 0;
    session = 0;
    tx_seq = 0;
    stream.active = 0;
    offer_waits = 0;
    memset(answers, 0, sizeof answers);
    answering = 0;
    host_seen_ms = robot_state.time.time_ms;
    link_error_sent = 0;
    comm_register(PB_PKT_HEARTBEAT, on_heartbeat);
    comm_register(PB_PKT_HELLO_REQUEST, on_hello_request);
}

void comm_register(uint8_t type, comm_handler_t handler)
{
    uint8_t i = pb_packet_index(type);
    if (i != PB_PACKET_NONE)
        handlers[i] = handler;
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

static inline uint8_t store_escaped(uint8_t pos, uint8_t b)
{
    if (b == SLIP_END) {
        pos = uart_tx_store(pos, SLIP_ESC);
        b = SLIP_ESC_END;
    } else if (b == SLIP_ESC) {
        pos = uart_tx_store(pos, SLIP_ESC);
        b = SLIP_ESC_ESC;
    }
    return uart_tx_store(pos, b);
}

/* The inner loop of every packet sent: CRC and SLIP-escape `n` bytes into the transmit buffer at `pos`.
 * Inlined into its two callers (a call per byte would double its cost on the AVR). */
static inline __attribute__((always_inline)) uint8_t encode(uint8_t pos, uint16_t *crc_io, const uint8_t *p,
                                                            uint8_t n)
{
    uint16_t crc = *crc_io;
    uint8_t *buf = uart_tx_buf;
    while (n--) {
        uint8_t b = *p++;
        crc = pb_crc16_byte(crc, b);
        if (b == SLIP_END || b == SLIP_ESC) {
            buf[pos++] = SLIP_ESC;
            b = b == SLIP_END ? SLIP_ESC_END : SLIP_ESC_ESC;
        }
        buf[pos++] = b;
    }
    *crc_io = crc;
    return pos;
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

/* Encodes up to `max` more bytes of the streamed frame (and its end once all are done). */
static void stream_step(uint8_t max)
{
    if (!stream.active)
        return;
    uint8_t i = stream.done;
    uint8_t n = (uint8_t)(stream.len - i > max ? max : stream.len - i);
    uint16_t crc = stream.crc;
    uint8_t pos = encode(uart_tx_begin(), &crc, stream.buf + i, n);
    stream.crc = crc;
    stream.done = (uint8_t)(i + n);
    if (stream.done == stream.len) {
        pos = store_escaped(pos, (uint8_t)crc);
        pos = store_escaped(pos, (uint8_t)(crc >> 8));
        pos = uart_tx_store(pos, SLIP_END);
        stream.active = 0;
    }
    uart_tx_commit(pos);
    uart_tx_flush();
}

bool comm_send_streamed(uint8_t type, const void *payload, uint8_t len)
{
    stream_step(0xFFu); /* the previous one first */
    uint16_t worst = (uint16_t)(2u * (PB_FRAME_HEADER_SIZE + len + PB_FRAME_CRC_SIZE) + 2u);
    if (len > sizeof stream.buf - PB_FRAME_HEADER_SIZE || worst > uart_tx_free())
        return comm_send(type, payload, len); /* at once, with the exact size check */
    stream.buf[0] = type;
    stream.buf[1] = tx_seq++;
    stream.buf[2] = len;
    snapshot(stream.buf + PB_FRAME_HEADER_SIZE, (const uint8_t *)payload, len);
    stream.len = (uint8_t)(PB_FRAME_HEADER_SIZE + len);
    stream.done = 0;
    stream.crc = 0xFFFFu;
    stream.active = 1;
    uint8_t pos = uart_tx_begin();
    uart_tx_commit(uart_tx_store(pos, SLIP_END));
    uart_tx_flush();
    return true;
}

/* Frames and SLIP-encodes straight into the transmit buffer in one pass that also computes the CRC. Only
 * when the buffer might be too small for the worst case (every byte escaped) are the escapes counted; the
 * CRC's own are known at the end, before anything is published. */
static bool frame_out(uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    const uint8_t *p = (const uint8_t *)payload;
    uint8_t head[PB_FRAME_HEADER_SIZE] = {type, seq, len};
    stream_step(0xFFu); /* frames never interleave: a streamed one is completed first */
    uint16_t free = uart_tx_free();
    uint16_t plain = (uint16_t)(2u + sizeof head + len + PB_FRAME_CRC_SIZE);
    if (len > PB_MAX_PAYLOAD || plain > free) /* too long, or no room even unescaped */
        return false;
    uint16_t need = 0; /* exact size without the CRC's escapes, when it matters */
    if ((uint16_t)(2u * plain) > free) {
        need = (uint16_t)(plain + slip_extra(head, sizeof head) + slip_extra(p, len));
        if (need > free)
            return false;
    }
    /* Written behind the published end of the buffer: nothing goes out until the commit. */
    uint8_t pos = uart_tx_begin();
    uint16_t crc = 0xFFFFu;
    pos = uart_tx_store(pos, SLIP_END);
    pos = encode(pos, &crc, head, sizeof head);
    pos = encode(pos, &crc, p, len);
    if (need && need + slip_extra((const uint8_t *)&crc, sizeof crc) > free) /* its CRC needs escapes: no room */
        return false;
    pos = store_escaped(pos, (uint8_t)crc);
    pos = store_escaped(pos, (uint8_t)(crc >> 8));
    pos = uart_tx_store(pos, SLIP_END);
    uart_tx_commit(pos);
    uart_tx_flush();
    return true;
}

bool comm_send_seq(uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    if (frame_out(type, seq, payload, len))
        return true;
    robot_state.errors.tx_dropped++;
    return false;
}

bool comm_offer(uint8_t type, const void *payload, uint8_t len)
{
    /* Completing a streamed frame now would put its cost into the caller's tick: wait for comm_task() to finish
     * it, unless offers have already waited OFFER_PATIENCE times (a stream every tick never finishes). */
    if (stream.active && offer_waits < OFFER_PATIENCE) {
        offer_waits++;
        return false;
    }
    offer_waits = 0;
    if (!frame_out(type, tx_seq, payload, len))
        return false;
    tx_seq++;
    return true;
}

bool comm_send(uint8_t type, const void *payload, uint8_t len)
{
    return comm_send_seq(type, tx_seq++, payload, len);
}

void comm_send_error(uint8_t code, uint8_t type, uint8_t seq, uint16_t detail)
{
    pb_error_t e = {code, type, seq, detail};
    comm_send_seq(PB_PKT_ERROR, seq, &e, sizeof e);
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
    comm_send_seq(PB_PKT_HELLO, seq, &h, sizeof h);
}

void comm_send_hello(void)
{
    send_hello(0, 0);
}

uint32_t comm_host_seen_ms(void)
{
    return host_seen_ms;
}

static uint8_t on_heartbeat(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)cmd;
    (void)detail;
    return PB_ERROR_CODE_NONE; /* its arrival is all the failsafe needs */
}

static uint8_t on_hello_request(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)detail;
    pb_hello_request_t r;
    memcpy(&r, cmd->payload, sizeof r);
    uint8_t resumed = r.session != 0 && r.session == session;
    if (!resumed) { /* another host, or one that restarted: its sequence numbers owe nothing to the last one's */
        session = r.session;
        memset(history, 0, sizeof history);
        history_next = 0;
    }
    send_hello(resumed, cmd->seq);
    return PB_ERROR_CODE_NONE;
}

static void send_ack(uint8_t type, uint8_t seq)
{
    pb_ack_t a = {type};
    comm_send_seq(PB_PKT_ACK, seq, &a, sizeof a);
}

bool comm_ack(uint8_t type, uint8_t seq)
{
    pb_ack_t a = {type};
    if (stream.active && offer_waits < OFFER_PATIENCE) { /* as comm_offer() */
        offer_waits++;
        return false;
    }
    offer_waits = 0;
    return frame_out(PB_PKT_ACK, seq, &a, sizeof a);
}

static bool seen_before(uint8_t seq, uint16_t crc)
{
    for (uint8_t i = 0; i < COMM_SEQ_HISTORY; i++)
        if (history[i].seq == seq && history[i].crc == crc)
            return true;
    return false;
}

static void remember(uint8_t seq, uint16_t crc)
{
    history[history_next].seq = seq;
    history[history_next].crc = crc;
    history_next = (uint8_t)((history_next + 1u) % COMM_SEQ_HISTORY);
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
    comm_send_error(code, 0, 0, length);
}

static void reject(uint8_t code, uint8_t type, uint8_t seq, uint16_t detail)
{
    robot_state.errors.rejected++;
    comm_send_error(code, type, seq, detail);
}

void comm_handle_frame(const uint8_t *frame, uint16_t n)
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
    host_seen_ms = robot_state.time.time_ms; /* a sound CRC: the host is there */
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
    if (remembered && seen_before(f.seq, crc)) {
        send_ack(f.type, f.seq); /* a retransmission: the first one was executed */
        return;
    }
    uint16_t detail = 0;
    code = handler(&f, &detail);
    if (code != PB_ERROR_CODE_NONE && code != COMM_ANSWER_LATER) {
        reject(code, f.type, f.seq, detail);
        return;
    }
    if (remembered)
        remember(f.seq, crc);
    if (acked && code == PB_ERROR_CODE_NONE)
        send_ack(f.type, f.seq);
}

void comm_rx_byte(uint8_t byte)
{
    slip_result_t r = slip_decode(&rx, byte);
    if (r == SLIP_FRAME) {
        comm_handle_frame(rx.buf, rx.len);
    } else if (r == SLIP_ERROR) {
        robot_state.errors.framing++;
        link_error(rx.overflow ? PB_ERROR_CODE_TOO_LONG : PB_ERROR_CODE_FRAMING, slip_seen(&rx));
    }
}

void comm_answer_later(comm_answer_step_t step)
{
    uint8_t free_slot = COMM_ANSWERS;
    for (uint8_t i = 0; i < COMM_ANSWERS; i++) {
        if (answers[i] == step)
            return;
        if (answers[i] == NULL)
            free_slot = i;
    }
    if (free_slot < COMM_ANSWERS) { /* there is one per kind of answer: never full */
        answers[free_slot] = step;
        answering++;
    }
}

static void continue_answers(void)
{
    for (uint8_t i = 0; i < COMM_ANSWERS; i++)
        if (answers[i] != NULL && answers[i]()) {
            answers[i] = NULL;
            answering--;
        }
}

void comm_task(void)
{
    uint8_t b;
    uint8_t budget = 255; /* bound the work of one tick */
    while (budget-- && uart_getc(&b))
        comm_rx_byte(b);
    robot_state.errors.rx_overflow = uart_rx_overflows();
    stream_step(COMM_STREAM_CHUNK);
    if (answering)
        continue_answers();
}
