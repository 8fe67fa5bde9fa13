#include "comm.h"

#include <string.h>

#include "drivers/uart.h"
#include "modules/failsafe.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"
#include "modules/proximity.h"
#include "modules/reflector.h"
#include "modules/settings.h"
#include "protocol/pb_frame.h"
#include "protocol/slip.h"

static slip_decoder_t rx;
static uint8_t tx_seq;

/* Recently accepted commands, to re-ack a retransmission without executing it twice. */
static struct {
    uint8_t type;
    uint8_t seq;
} history[COMM_SEQ_HISTORY];
static uint8_t history_next;

/* A read_settings answer in progress. */
static uint8_t reading;
static uint8_t reading_seq;
static uint16_t reading_offset;

#define SETTINGS_CHUNK 64u

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

void comm_init(void)
{
    slip_decoder_init(&rx);
    pb_packet_lookup_init();
    memset(history, 0, sizeof history);
    history_next = 0;
    reading = 0;
    tx_seq = 0;
    stream.active = 0;
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
bool comm_send_seq(uint8_t type, uint8_t seq, const void *payload, uint8_t len)
{
    const uint8_t *p = (const uint8_t *)payload;
    uint8_t head[PB_FRAME_HEADER_SIZE] = {type, seq, len};
    stream_step(0xFFu); /* frames never interleave: a streamed one is completed first */
    uint16_t free = uart_tx_free();
    uint16_t plain = (uint16_t)(2u + sizeof head + len + PB_FRAME_CRC_SIZE);
    if (len > PB_MAX_PAYLOAD || plain > free) { /* too long, or no room even unescaped */
        robot_state.errors.tx_dropped++;
        return false;
    }
    uint16_t need = 0; /* exact size without the CRC's escapes, when it matters */
    if ((uint16_t)(2u * plain) > free) {
        need = (uint16_t)(plain + slip_extra(head, sizeof head) + slip_extra(p, len));
        if (need > free) {
            robot_state.errors.tx_dropped++;
            return false;
        }
    }
    /* Written behind the published end of the buffer: nothing goes out until the commit. */
    uint8_t pos = uart_tx_begin();
    uint16_t crc = 0xFFFFu;
    pos = uart_tx_store(pos, SLIP_END);
    pos = encode(pos, &crc, head, sizeof head);
    pos = encode(pos, &crc, p, len);
    if (need && need + slip_extra((const uint8_t *)&crc, sizeof crc) > free) { /* its CRC needs escapes: no room */
        robot_state.errors.tx_dropped++;
        return false;
    }
    pos = store_escaped(pos, (uint8_t)crc);
    pos = store_escaped(pos, (uint8_t)(crc >> 8));
    pos = uart_tx_store(pos, SLIP_END);
    uart_tx_commit(pos);
    uart_tx_flush();
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

void comm_send_hello(void)
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
    comm_send(PB_PKT_HELLO, &h, sizeof h);
}

static void send_ack(uint8_t type, uint8_t seq)
{
    pb_ack_t a = {type};
    comm_send_seq(PB_PKT_ACK, seq, &a, sizeof a);
}

static bool seen_before(uint8_t type, uint8_t seq)
{
    if (seq == 0) /* hosts number acked commands from 1; 0 is never remembered */
        return false;
    for (uint8_t i = 0; i < COMM_SEQ_HISTORY; i++)
        if (history[i].seq == seq && history[i].type == type)
            return true;
    return false;
}

static void remember(uint8_t type, uint8_t seq)
{
    if (seq == 0)
        return;
    history[history_next].type = type;
    history[history_next].seq = seq;
    history_next = (uint8_t)((history_next + 1u) % COMM_SEQ_HISTORY);
}

/* Executes a packet whose type and length are valid. \return an error code, or NONE to ack. */
static uint8_t execute(uint8_t type, uint8_t seq, const uint8_t *p, uint8_t len, uint16_t *detail)
{
    switch (type) {
    case PB_PKT_HELLO_REQUEST:
        comm_send_hello();
        return PB_ERROR_CODE_NONE;
    case PB_PKT_HEARTBEAT:
        return PB_ERROR_CODE_NONE;
    case PB_PKT_SET_SYNC: {
        pb_set_sync_t c;
        memcpy(&c, p, sizeof c);
        return reflector_set_sync(c.mode, c.period_ms);
    }
    case PB_PKT_UPDATE_SETTINGS: {
        pb_update_settings_t c;
        memcpy(&c, p, len);
        if (c.length != len - PB_UPDATE_SETTINGS_MIN_SIZE) {
            *detail = c.length;
            return PB_ERROR_CODE_BAD_LENGTH;
        }
        return settings_write(c.offset, c.length, c.data, detail);
    }
    case PB_PKT_READ_SETTINGS:
        reading = 1;
        reading_seq = seq;
        reading_offset = 0;
        return PB_ERROR_CODE_NONE;
    case PB_PKT_SAVE_SETTINGS:
        return settings_save() ? PB_ERROR_CODE_NONE : PB_ERROR_CODE_BUSY;
    case PB_PKT_LOAD_DEFAULTS:
        settings_load_defaults();
        return PB_ERROR_CODE_NONE;
    case PB_PKT_MOVE_STRAIGHT: {
        pb_move_straight_t c;
        memcpy(&c, p, sizeof c);
        return locomotion_straight(c.id, c.distance_m, c.speed_mps);
    }
    case PB_PKT_MOVE_ROTATE: {
        pb_move_rotate_t c;
        memcpy(&c, p, sizeof c);
        return locomotion_rotate(c.id, c.angle_deg, c.speed_mps);
    }
    case PB_PKT_MOVE_ARC: {
        pb_move_arc_t c;
        memcpy(&c, p, sizeof c);
        return locomotion_arc(c.id, c.radius_m, c.angle_deg, c.speed_mps);
    }
    case PB_PKT_STOP: {
        pb_stop_t c;
        memcpy(&c, p, sizeof c);
        if (c.immediate > 1)
            return PB_ERROR_CODE_BAD_ARGUMENT;
        line_follower_stop();
        locomotion_stop(c.immediate != 0);
        return PB_ERROR_CODE_NONE;
    }
    case PB_PKT_WHEEL_SPEEDS: {
        pb_wheel_speeds_t c;
        memcpy(&c, p, sizeof c);
        uint8_t r = locomotion_teleop(c.left_mps, c.right_mps);
        if (r == PB_ERROR_CODE_NONE)
            line_follower_stop();
        return r;
    }
    case PB_PKT_LINE_FOLLOW: {
        pb_line_follow_t c;
        memcpy(&c, p, sizeof c);
        return line_follower_command(c.run, c.colour_mode, c.speed_mps);
    }
    case PB_PKT_IR_SEND: {
        pb_ir_send_t c;
        memcpy(&c, p, len);
        return proximity_send_payload(c.power, c.data, (uint8_t)(len - PB_IR_SEND_MIN_SIZE));
    }
    default:
        return PB_ERROR_CODE_UNKNOWN_TYPE;
    }
}

void comm_handle_frame(const uint8_t *frame, uint16_t n)
{
    pb_frame_t f = {0, 0, 0, NULL};
    uint8_t code = pb_frame_check(frame, n, &f);
    if (code == PB_ERROR_CODE_BAD_CRC) {
        robot_state.errors.crc++;
        return;
    }
    if (code == PB_ERROR_CODE_TOO_SHORT || code == PB_ERROR_CODE_TOO_LONG) {
        robot_state.errors.framing++;
        return;
    }
    if (code == PB_ERROR_CODE_BAD_LENGTH) { /* sound CRC, so type and seq can be trusted */
        robot_state.errors.framing++;
        comm_send_error(code, frame[0], frame[1], frame[2]);
        return;
    }
    failsafe_host_seen();

    const PB_FLASH pb_packet_info_t *info = pb_packet_lookup(f.type);
    if (info == NULL || info->dir != PB_DIR_H2R) {
        robot_state.errors.rejected++;
        comm_send_error(PB_ERROR_CODE_UNKNOWN_TYPE, f.type, f.seq, f.type);
        return;
    }
    if (f.len < info->min_size || f.len > info->max_size) {
        robot_state.errors.rejected++;
        comm_send_error(PB_ERROR_CODE_BAD_LENGTH, f.type, f.seq, f.len);
        return;
    }
    bool acked = info->needs_ack != 0;
    if (acked && f.type != PB_PKT_READ_SETTINGS && seen_before(f.type, f.seq)) {
        send_ack(f.type, f.seq); /* a retransmission: the first one was executed */
        return;
    }
    uint16_t detail = 0;
    code = execute(f.type, f.seq, f.payload, f.len, &detail);
    if (code != PB_ERROR_CODE_NONE) {
        robot_state.errors.rejected++;
        comm_send_error(code, f.type, f.seq, detail);
        return;
    }
    if (!acked)
        return;
    remember(f.type, f.seq);
    if (f.type != PB_PKT_READ_SETTINGS) /* its ack follows the data */
        send_ack(f.type, f.seq);
}

void comm_rx_byte(uint8_t byte)
{
    slip_result_t r = slip_decode(&rx, byte);
    if (r == SLIP_FRAME)
        comm_handle_frame(rx.buf, rx.len);
    else if (r == SLIP_ERROR)
        robot_state.errors.framing++;
}

static void continue_reading(void)
{
    while (reading) {
        if (reading_offset >= sizeof(pb_settings_t)) {
            pb_ack_t a = {PB_PKT_READ_SETTINGS};
            uint16_t before = robot_state.errors.tx_dropped;
            if (!comm_send_seq(PB_PKT_ACK, reading_seq, &a, sizeof a)) {
                robot_state.errors.tx_dropped = before; /* not lost: retried next tick */
                return;
            }
            reading = 0;
            return;
        }
        pb_settings_data_t d;
        uint16_t left = (uint16_t)(sizeof(pb_settings_t) - reading_offset);
        d.offset = reading_offset;
        d.length = (uint8_t)(left < SETTINGS_CHUNK ? left : SETTINGS_CHUNK);
        memcpy(d.data, (const uint8_t *)&settings + reading_offset, d.length);
        uint16_t before = robot_state.errors.tx_dropped;
        if (!comm_send(PB_PKT_SETTINGS_DATA, &d, (uint8_t)(PB_SETTINGS_DATA_MIN_SIZE + d.length))) {
            robot_state.errors.tx_dropped = before;
            return;
        }
        reading_offset = (uint16_t)(reading_offset + d.length);
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
    continue_reading();
}
