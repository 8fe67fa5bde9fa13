#include "hci.h"

#include <string.h>

#include "bluetooth/h4.h"
#include "core/data.h"
#include "drivers/eeprom.h"
#include "drivers/uart.h"
#include "protocol/pb_frame.h"

/* Commands (OGF << 10 | OCF). */
#define OP_ACCEPT_CONNECTION 0x0409u
#define OP_REJECT_CONNECTION 0x040Au
#define OP_LINK_KEY_REPLY 0x040Bu
#define OP_LINK_KEY_NEGATIVE 0x040Cu
#define OP_PIN_NEGATIVE 0x040Eu
#define OP_IO_CAPABILITY_REPLY 0x042Bu
#define OP_USER_CONFIRM_REPLY 0x042Cu
#define OP_SET_EVENT_MASK 0x0C01u
#define OP_RESET 0x0C03u
#define OP_WRITE_LOCAL_NAME 0x0C13u
#define OP_READ_SCAN_ENABLE 0x0C19u
#define OP_WRITE_SCAN_ENABLE 0x0C1Au
#define OP_WRITE_CLASS_OF_DEVICE 0x0C24u
#define OP_HOST_BUFFER_SIZE 0x0C33u
#define OP_WRITE_SSP_MODE 0x0C56u
#define OP_READ_BUFFER_SIZE 0x1005u
#define OP_READ_BD_ADDR 0x1009u

/* Events. */
#define EV_CONNECTION_COMPLETE 0x03u
#define EV_CONNECTION_REQUEST 0x04u
#define EV_DISCONNECTION_COMPLETE 0x05u
#define EV_COMMAND_COMPLETE 0x0Eu
#define EV_COMMAND_STATUS 0x0Fu
#define EV_HARDWARE_ERROR 0x10u
#define EV_COMPLETED_PACKETS 0x13u
#define EV_PIN_REQUEST 0x16u
#define EV_LINK_KEY_REQUEST 0x17u
#define EV_LINK_KEY_NOTIFICATION 0x18u
#define EV_BUFFER_OVERFLOW 0x1Au
#define EV_IO_CAPABILITY_REQUEST 0x31u
#define EV_USER_CONFIRM_REQUEST 0x33u

#define NAME_LEN 248u /* Write_Local_Name's parameter, NUL-padded */
#define ACL_START 0x2000u
#define ACL_CONTINUE 0x1000u
#define FRAGMENT_HEADER 5u /* H4 type, handle and flags, length */
#define SCAN_INQUIRY_PAGE 0x03u /* Scan_Enable: inquiry and page scan */

/* The initialisation after a reset, one command at a time (only the first three must succeed): each as its
 * opcode, parameter length and parameters; the local name is made from the settings (write_local_name()). */
#define LE16(v) (uint8_t)(v), (uint8_t)((v) >> 8)
static const HAL_FLASH uint8_t init_commands[] = {
    LE16(OP_RESET), 0,
    LE16(OP_READ_BUFFER_SIZE), 0,
    LE16(OP_READ_BD_ADDR), 0,
    /* the ACL packets the robot takes; no SCO; host flow control stays off */
    LE16(OP_HOST_BUFFER_SIZE), 7, LE16(BT_ACL_RX_MAX), 0, LE16(4), LE16(0),
    /* the default events and Secure Simple Pairing's (IO capability request/response, user confirmation and
     * passkey, OOB, simple pairing complete: bits 48..53) */
    LE16(OP_SET_EVENT_MASK), 8, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x1F, 0x3F, 0x00,
    LE16(OP_WRITE_SSP_MODE), 1, 1,
    LE16(OP_WRITE_LOCAL_NAME), 0,
    LE16(OP_WRITE_CLASS_OF_DEVICE), 3, (uint8_t)BT_CLASS_OF_DEVICE, (uint8_t)(BT_CLASS_OF_DEVICE >> 8),
    (uint8_t)(BT_CLASS_OF_DEVICE >> 16),
    LE16(OP_WRITE_SCAN_ENABLE), 1, SCAN_INQUIRY_PAGE,
};
#define INIT_STEPS 9u
#define INIT_ESSENTIAL 3u

/* Answers to the controller's requests, sent as command credits allow. */
enum { REPLY_ACCEPT, REPLY_REJECT, REPLY_LINK_KEY, REPLY_PIN_NEGATIVE, REPLY_IO_CAPABILITY, REPLY_USER_CONFIRM };
#define REPLIES 4u
static struct {
    uint8_t kind;
    uint8_t addr[6];
} replies[REPLIES];
static uint8_t reply_count;

enum { ST_QUIET, ST_INIT, ST_READY };
static uint8_t state;
static uint8_t step;          /* the init command sent or to send */
static uint8_t step_at;       /* and where it is in init_commands */
static uint8_t quiet_ticks;   /* ticks without a received byte, before the reset is sent */
static uint16_t pending_op;   /* command sent and not answered yet (0: none) */
static uint32_t pending_ms;
static uint32_t credit_ms;    /* when the stack last had a command credit or a command pending */
static uint32_t last_command_ms;
static uint8_t command_credits;
static uint8_t bd_addr[6];
static uint8_t name_id;       /* the robot id in the local name the controller has */

static uint16_t acl_mtu;      /* the controller's ACL data packet length */
static uint8_t acl_total;     /* its ACL buffers (at most 255 counted) */
static uint8_t acl_free;

enum { LINK_FREE, LINK_ACCEPTING, LINK_UP };
static struct {
    uint8_t state;
    uint16_t handle;
    uint8_t addr[6];
    uint8_t in_flight; /* our ACL packets the controller has not completed */
} links[BT_LINKS];
static uint8_t rx_link; /* link of the ACL fragment being read, 0xFF: dropped */
static uint16_t rx_lost; /* bytes the UART's receive ring had lost when last looked at */

/* ACL writer. */
static uint8_t w_open; /* a PDU is being written */
static uint8_t w_link;
static uint8_t w_unsent; /* its fragments not yet published (their controller buffers are taken) */
static uint16_t w_handle;
static uint16_t w_pdu_left;
static uint16_t w_frag_left;

/* A link key on its way to EEPROM (eeprom_write() takes one block at a time, shared with the settings). */
#define KEY_MAGIC 0xB7u
#define KEY_RECORD 28u /* magic, address, key, type, age (u16), CRC-16 */
#define KEY_SLOT 32u
_Static_assert(HCI_KEYS_EEPROM_ADDR + HCI_KEYS * KEY_SLOT <= HAL_EEPROM_SIZE, "link keys fit the EEPROM");
_Static_assert(KEY_SLOT == HAL_EEPROM_PAGE, "one key per EEPROM page");
static struct {
    uint8_t waiting;
    uint8_t slot;
    uint8_t rec[KEY_RECORD];
} key_out;

static uint32_t now_ms(void)
{
    return robot_state.time.time_ms;
}

static uint16_t le16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

/* ---- link keys in EEPROM ---- */

/* \return true when slot `i` holds a sound record, read into rec. */
static bool key_read(uint8_t i, uint8_t rec[KEY_RECORD])
{
    eeprom_read((uint16_t)(HCI_KEYS_EEPROM_ADDR + i * KEY_SLOT), rec, KEY_RECORD);
    return rec[0] == KEY_MAGIC && le16(rec + KEY_RECORD - 2) == pb_crc16(0xFFFFu, rec, KEY_RECORD - 2);
}

/* \return the slot holding the key of `addr`, or HCI_KEYS; *free_slot: the slot a new key of it would take. */
static uint8_t key_find(const uint8_t *addr, uint8_t rec[KEY_RECORD], uint8_t *free_slot, uint16_t *next_age)
{
    uint8_t oldest = 0, empty = HCI_KEYS;
    uint16_t oldest_age = 0xFFFFu, newest_age = 0;
    for (uint8_t i = 0; i < HCI_KEYS; i++) {
        if (!key_read(i, rec)) {
            if (empty == HCI_KEYS)
                empty = i;
            continue;
        }
        if (memcmp(rec + 1, addr, 6) == 0)
            return i;
        uint16_t age = le16(rec + 24);
        if (age < oldest_age) {
            oldest_age = age;
            oldest = i;
        }
        if (age >= newest_age)
            newest_age = (uint16_t)(age + 1u);
    }
    *free_slot = empty < HCI_KEYS ? empty : oldest;
    *next_age = newest_age;
    return HCI_KEYS;
}

static void key_store(const uint8_t *addr, const uint8_t *key, uint8_t type)
{
    uint8_t *rec = key_out.rec;
    uint8_t slot;
    uint16_t age = 0;
    uint8_t found = key_find(addr, rec, &slot, &age);
    if (found < HCI_KEYS) {
        slot = found;
        age = le16(rec + 24);
    }
    rec[0] = KEY_MAGIC;
    memcpy(rec + 1, addr, 6);
    memcpy(rec + 7, key, 16);
    rec[23] = type;
    rec[24] = (uint8_t)age;
    rec[25] = (uint8_t)(age >> 8);
    uint16_t crc = pb_crc16(0xFFFFu, rec, KEY_RECORD - 2);
    rec[26] = (uint8_t)crc;
    rec[27] = (uint8_t)(crc >> 8);
    key_out.slot = slot;
    key_out.waiting = 1;
}

static void key_write_task(void)
{
    if (key_out.waiting &&
        eeprom_write((uint16_t)(HCI_KEYS_EEPROM_ADDR + key_out.slot * KEY_SLOT), key_out.rec, KEY_RECORD))
        key_out.waiting = 0;
}

/* ---- links ---- */

static uint8_t link_by_handle(uint16_t handle)
{
    for (uint8_t i = 0; i < BT_LINKS; i++)
        if (links[i].state == LINK_UP && links[i].handle == handle)
            return i;
    return BT_LINKS;
}

static void drop_links(uint8_t reason)
{
    for (uint8_t i = 0; i < BT_LINKS; i++) {
        uint8_t was = links[i].state;
        links[i].state = LINK_FREE;
        links[i].in_flight = 0;
        if (was == LINK_UP)
            l2cap_link_down(i, reason);
    }
}

const uint8_t *hci_link_addr(uint8_t link)
{
    return link < BT_LINKS && links[link].state == LINK_UP ? links[link].addr : NULL;
}

static void queue_reply(uint8_t kind, const uint8_t *addr)
{
    if (reply_count >= REPLIES) /* the controller asks one thing at a time per link: never full */
        return;
    replies[reply_count].kind = kind;
    memcpy(replies[reply_count].addr, addr, 6);
    reply_count++;
}

/* ---- recovery ---- */

/* The wire or the controller failed: every link is gone, and the controller is reset once the wire is quiet. */
static void recover(void)
{
    robot_state.errors.bt_resets++;
    w_open = 0; /* a PDU being written is abandoned: its unpublished bytes are never sent */
    drop_links(HCI_REASON_RESET);
    reply_count = 0;
    pending_op = 0;
    state = ST_QUIET;
    quiet_ticks = 0;
    h4_flush();
}

void hci_init(void)
{
    memset(links, 0, sizeof links);
    memset(bd_addr, 0, sizeof bd_addr);
    reply_count = 0;
    pending_op = 0;
    key_out.waiting = 0;
    w_open = 0;
    acl_mtu = 0;
    acl_total = acl_free = 0;
    rx_link = 0xFFu;
    rx_lost = uart_rx_overflows();
    state = ST_QUIET;
    quiet_ticks = 0;
    h4_init();
}

bool hci_ready(void)
{
    return state == ST_READY;
}

const uint8_t *hci_bd_addr(void)
{
    return bd_addr;
}

/* ---- commands ---- */

static bool command(uint16_t op, const uint8_t *params, uint8_t len)
{
    if (w_open || h4_tx_room() < 4u + len)
        return false;
    h4_command(op, params, len);
    pending_op = op;
    pending_ms = last_command_ms = now_ms();
    command_credits--;
    return true;
}

static bool write_local_name(void)
{
    /* Without its NUL: avr-gcc 5.4's LTO fails on two equal __flash strings (settings.c has this one). */
    static const HAL_FLASH char prefix[sizeof BT_NAME_PREFIX - 1u] = BT_NAME_PREFIX;
    if (w_open || h4_tx_room() < 4u + NAME_LEN)
        return false;
    uint8_t head[4 + sizeof prefix + 3] = {H4_COMMAND, (uint8_t)OP_WRITE_LOCAL_NAME, OP_WRITE_LOCAL_NAME >> 8,
                                           (uint8_t)NAME_LEN};
    uint8_t n = 4;
    for (uint8_t k = 0; k < sizeof prefix; k++)
        head[n++] = (uint8_t)prefix[k];
    uint8_t id = settings.identity.robot_id;
    name_id = id;
    for (uint8_t div = 100; div; div /= 10u) /* decimal, without leading zeros */
        if (id >= div || div == 1u || n > 4u + sizeof prefix) {
            head[n++] = (uint8_t)('0' + id / div);
            id %= div;
        }
    h4_tx_begin();
    h4_tx_bytes(head, n);
    h4_tx_zeros((uint16_t)(NAME_LEN - (n - 4u)));
    h4_tx_end();
    pending_op = OP_WRITE_LOCAL_NAME;
    pending_ms = last_command_ms = now_ms();
    command_credits--;
    return true;
}

static void send_init(void)
{
    const HAL_FLASH uint8_t *c = init_commands + step_at;
    uint16_t op = (uint16_t)(c[0] | c[1] << 8);
    uint8_t len = c[2], p[8];
    for (uint8_t i = 0; i < len; i++)
        p[i] = c[3 + i];
    if (op == OP_WRITE_LOCAL_NAME)
        write_local_name();
    else
        command(op, p, len);
}

static void send_reply(void)
{
    static const HAL_FLASH uint16_t ops[] = {OP_ACCEPT_CONNECTION, OP_REJECT_CONNECTION, OP_LINK_KEY_REPLY,
                                             OP_PIN_NEGATIVE, OP_IO_CAPABILITY_REPLY, OP_USER_CONFIRM_REPLY};
    uint8_t p[6 + 16];
    uint8_t kind = replies[0].kind;
    uint16_t op = ops[kind];
    uint8_t len = 6;
    memcpy(p, replies[0].addr, 6);
    switch (kind) {
    case REPLY_ACCEPT:
        p[6] = 0x01; /* stay peripheral: the host's piconet */
        len = 7;
        break;
    case REPLY_REJECT:
        p[6] = 0x0D; /* limited resources */
        len = 7;
        break;
    case REPLY_LINK_KEY: {
        uint8_t rec[KEY_RECORD], slot;
        uint16_t age;
        if (key_find(p, rec, &slot, &age) < HCI_KEYS) {
            memcpy(p + 6, rec + 7, 16);
            len = 22;
        } else {
            op = OP_LINK_KEY_NEGATIVE;
        }
        break;
    }
    case REPLY_IO_CAPABILITY:
        p[6] = 0x03; /* NoInputNoOutput: "just works" */
        p[7] = 0x00; /* no OOB data */
        p[8] = 0x04; /* general bonding, MITM protection not required */
        len = 9;
        break;
    default:
        break;
    }
    if (!command(op, p, len))
        return;
    reply_count--;
    memmove(&replies[0], &replies[1], reply_count * sizeof replies[0]);
}

/* ---- events ---- */

static void command_done(uint16_t op, uint8_t status, const uint8_t *ret, uint8_t len)
{
    if (op == 0)
        return; /* a NOP: credits only */
    if (op == pending_op)
        pending_op = 0;
    /* The keep-alive: scans off are a controller power-cycled behind the stack's back, its links forgotten (one
     * that refuses the command, as Bumble's did, only shows it answers). */
    if (op == OP_READ_SCAN_ENABLE && state == ST_READY && status == 0 && len && ret[0] != SCAN_INQUIRY_PAGE) {
        recover();
        return;
    }
    if (state != ST_INIT || op != (uint16_t)(init_commands[step_at] | init_commands[step_at + 1] << 8))
        return;
    if (status != 0) {
        if (step < INIT_ESSENTIAL) {
            recover();
            return;
        }
    } else if (op == OP_READ_BUFFER_SIZE && len >= 5) {
        acl_mtu = le16(ret);
        uint16_t total = le16(ret + 3);
        acl_total = acl_free = (uint8_t)(total > 255u ? 255u : total);
        if (acl_mtu == 0 || acl_total == 0) {
            recover();
            return;
        }
    } else if (op == OP_READ_BD_ADDR && len >= 6) {
        memcpy(bd_addr, ret, 6);
    }
    step_at = (uint8_t)(step_at + 3u + init_commands[step_at + 2]);
    if (++step == INIT_STEPS)
        state = ST_READY;
}

static void on_connection_request(const uint8_t *p)
{
    uint8_t slot = BT_LINKS;
    for (uint8_t i = 0; i < BT_LINKS; i++) {
        if (links[i].state != LINK_FREE && memcmp(links[i].addr, p, 6) == 0) {
            slot = BT_LINKS; /* already connected or connecting */
            break;
        }
        if (links[i].state == LINK_FREE && slot == BT_LINKS)
            slot = i;
    }
    if (p[9] != 0x01 || slot == BT_LINKS) { /* not ACL, or no room */
        queue_reply(REPLY_REJECT, p);
        return;
    }
    links[slot].state = LINK_ACCEPTING;
    memcpy(links[slot].addr, p, 6);
    queue_reply(REPLY_ACCEPT, p);
}

static void on_connection_complete(const uint8_t *p)
{
    for (uint8_t i = 0; i < BT_LINKS; i++) {
        if (links[i].state != LINK_ACCEPTING || memcmp(links[i].addr, p + 3, 6) != 0)
            continue;
        if (p[0] != 0) {
            links[i].state = LINK_FREE;
            return;
        }
        links[i].state = LINK_UP;
        links[i].handle = le16(p + 1) & 0x0FFFu;
        links[i].in_flight = 0;
        l2cap_link_up(i);
        return;
    }
}

static void on_disconnection_complete(const uint8_t *p)
{
    if (p[0] != 0)
        return;
    uint8_t i = link_by_handle(le16(p + 1) & 0x0FFFu);
    if (i == BT_LINKS)
        return;
    if (w_open && w_link == i)
        hci_acl_abort();
    links[i].state = LINK_FREE;
    acl_free = (uint8_t)(acl_free + links[i].in_flight); /* its packets were flushed */
    links[i].in_flight = 0;
    l2cap_link_down(i, p[3]);
}

static void on_completed_packets(const uint8_t *p, uint8_t n)
{
    uint8_t k = p[0];
    if (n < 1u + 4u * k)
        return;
    for (uint8_t j = 0; j < k; j++) {
        uint8_t i = link_by_handle(le16(p + 1 + 2 * j) & 0x0FFFu);
        uint16_t c = le16(p + 1 + 2 * k + 2 * j);
        if (i == BT_LINKS)
            continue;
        if (c > links[i].in_flight)
            c = links[i].in_flight;
        links[i].in_flight = (uint8_t)(links[i].in_flight - c);
        acl_free = (uint8_t)(acl_free + c);
    }
}

/* The events the stack reads and the fewest parameter bytes each must have (the others are ignored). */
static const HAL_FLASH uint8_t event_min[][2] = {
    {EV_COMMAND_COMPLETE, 3}, {EV_COMMAND_STATUS, 4}, {EV_CONNECTION_REQUEST, 10}, {EV_CONNECTION_COMPLETE, 11},
    {EV_DISCONNECTION_COMPLETE, 4}, {EV_COMPLETED_PACKETS, 1}, {EV_LINK_KEY_NOTIFICATION, 23}, {EV_PIN_REQUEST, 6},
    {EV_LINK_KEY_REQUEST, 6}, {EV_IO_CAPABILITY_REQUEST, 6}, {EV_USER_CONFIRM_REQUEST, 6}, {EV_HARDWARE_ERROR, 0},
    {EV_BUFFER_OVERFLOW, 0},
};

static uint8_t event_min_len(uint8_t code)
{
    for (uint8_t i = 0; i < sizeof event_min / sizeof event_min[0]; i++)
        if (event_min[i][0] == code)
            return event_min[i][1];
    return 0xFFu;
}

static void on_event(void)
{
    const uint8_t *p = h4_event.params;
    uint8_t n = h4_event.len;
    uint8_t code = h4_event.code;
    if (n < event_min_len(code))
        return; /* an event the stack does not use, or one too short to read */
    switch (code) {
    case EV_COMMAND_COMPLETE:
        command_credits = p[0];
        command_done(le16(p + 1), n > 3 ? p[3] : 0, p + 4, n > 4 ? (uint8_t)(n - 4) : 0);
        break;
    case EV_COMMAND_STATUS:
        command_credits = p[1];
        command_done(le16(p + 2), p[0], NULL, 0);
        break;
    case EV_HARDWARE_ERROR:
        recover();
        break;
    case EV_BUFFER_OVERFLOW:
        robot_state.errors.bt_dropped++;
        break;
    default:
        if (state != ST_READY)
            return; /* links start once the controller is ready */
        switch (code) {
        case EV_CONNECTION_REQUEST: on_connection_request(p); break;
        case EV_CONNECTION_COMPLETE: on_connection_complete(p); break;
        case EV_DISCONNECTION_COMPLETE: on_disconnection_complete(p); break;
        case EV_COMPLETED_PACKETS: on_completed_packets(p, n); break;
        case EV_LINK_KEY_REQUEST: queue_reply(REPLY_LINK_KEY, p); break;
        case EV_LINK_KEY_NOTIFICATION: key_store(p, p + 6, p[22]); break;
        case EV_PIN_REQUEST: queue_reply(REPLY_PIN_NEGATIVE, p); break;
        case EV_IO_CAPABILITY_REQUEST: queue_reply(REPLY_IO_CAPABILITY, p); break;
        case EV_USER_CONFIRM_REQUEST: queue_reply(REPLY_USER_CONFIRM, p); break;
        default: break;
        }
    }
}

static void on_acl_header(void)
{
    uint8_t i = link_by_handle(h4_acl.handle);
    uint8_t *dst = NULL;
    if (i < BT_LINKS)
        dst = l2cap_rx_fragment(i, h4_acl.pb != 1u, h4_acl.len); /* L2CAP counts what it drops */
    else
        robot_state.errors.bt_dropped++; /* no such link */
    if (dst == NULL)
        i = 0xFFu;
    rx_link = i;
    h4_acl_into(dst);
}

/* ---- the task ---- */

static void send_next(void)
{
    if (state == ST_INIT)
        send_init();
    else if (reply_count)
        send_reply();
    else if (name_id != settings.identity.robot_id)
        write_local_name();
    else if (now_ms() - last_command_ms >= HCI_KEEPALIVE_MS)
        command(OP_READ_SCAN_ENABLE, NULL, 0);
}

/* Reads a slice of the wire. \return true when the controller is being reset (nothing more this tick). */
static bool read_wire(void)
{
    uint8_t budget = HCI_RX_BUDGET;
    for (;;) {
        h4_result_t r = h4_read(&budget);
        if (r == H4_NONE)
            break;
        if (r == H4_ERROR) {
            robot_state.errors.bt_wire++;
            recover();
            return true;
        }
        if (r == H4_EVENT_READY)
            on_event();
        else if (r == H4_ACL_HEADER)
            on_acl_header();
        else if (rx_link < BT_LINKS)
            l2cap_rx_fragment_done(rx_link);
        if (state == ST_QUIET)
            return true; /* the event was a hardware error, or an essential init step failed */
    }
    if (h4_stalled(now_ms())) {
        robot_state.errors.bt_wire++;
        recover();
        return true;
    }
    return false;
}

/* A function of its own, not inlined into the main loop with the other tasks: cheaper in the worst ticks (measured). */
__attribute__((noinline)) void hci_task(void)
{
    if (state == ST_QUIET) {
        /* After a failure the controller may still be sending: wait for two quiet ticks, then reset it. */
        if (h4_flush())
            quiet_ticks = 0;
        else if (++quiet_ticks >= 2u) {
            state = ST_INIT;
            step = step_at = 0;
            command_credits = 1;
        }
        return;
    }
    uint16_t lost = uart_rx_overflows();
    if (lost != rx_lost) { /* a byte lost to a full receive ring: the wire is out of step */
        rx_lost = lost;
        robot_state.errors.rx_overflow = lost;
        robot_state.errors.bt_wire++;
        recover();
        return;
    }
    if (h4_rx_busy() && read_wire())
        return;
    uint32_t now = now_ms();
    if (pending_op || command_credits)
        credit_ms = now;
    if (pending_op) {
        if (now - pending_ms > HCI_COMMAND_TIMEOUT_MS) {
            robot_state.errors.bt_timeouts++;
            recover();
        }
    } else if (command_credits) {
        send_next();
    } else if (now - credit_ms > HCI_COMMAND_TIMEOUT_MS) {
        /* No credit for a command this long (an event granted none and none came back): as good as unanswered. */
        robot_state.errors.bt_timeouts++;
        recover();
    }
    if (key_out.waiting)
        key_write_task();
}

/* ---- ACL data out ---- */

static uint8_t fragments(uint16_t len)
{
    uint8_t n = 1;
    while (len > acl_mtu) {
        len = (uint16_t)(len - acl_mtu);
        n++;
    }
    return n;
}

bool hci_acl_can_send(uint16_t len, bool data)
{
    if (state != ST_READY || w_open)
        return false;
    uint8_t frags = fragments(len);
    uint8_t spare = data && acl_total > 2u ? 1u : 0u;
    uint16_t bytes = (uint16_t)(len + FRAGMENT_HEADER * frags + (data ? HCI_TX_RESERVE : 0u));
    return (uint16_t)(frags + spare) <= acl_free && bytes <= h4_tx_room();
}

static void fragment_header(uint16_t flags)
{
    uint16_t n = w_pdu_left > acl_mtu ? acl_mtu : w_pdu_left;
    uint16_t hf = (uint16_t)(w_handle | flags);
    uint8_t h[FRAGMENT_HEADER] = {H4_ACL, (uint8_t)hf, (uint8_t)(hf >> 8), (uint8_t)n, (uint8_t)(n >> 8)};
    h4_tx_bytes(h, FRAGMENT_HEADER);
    w_frag_left = n;
}

void hci_acl_begin(uint8_t link, uint16_t len)
{
    uint8_t frags = fragments(len);
    acl_free = (uint8_t)(acl_free - frags);
    links[link].in_flight = (uint8_t)(links[link].in_flight + frags);
    w_link = link;
    w_unsent = frags;
    w_handle = links[link].handle;
    w_pdu_left = len;
    w_open = 1;
    h4_tx_begin();
    fragment_header(ACL_START);
}

/* Room in the current fragment; a full one goes to the UART and the next one starts. */
static uint16_t fragment_room(void)
{
    if (w_frag_left == 0) {
        h4_tx_end();
        w_unsent--;
        fragment_header(ACL_CONTINUE);
    }
    return w_frag_left;
}

static inline __attribute__((always_inline)) void advance(uint16_t k)
{
    w_frag_left = (uint16_t)(w_frag_left - k);
    w_pdu_left = (uint16_t)(w_pdu_left - k);
}

void hci_acl_put(const uint8_t *p, uint16_t n)
{
    if (n && n <= w_frag_left) { /* the usual case: it fits the fragment being written */
        h4_tx_bytes(p, n);
        advance(n);
        return;
    }
    while (n) {
        uint16_t k = fragment_room();
        if (k > n)
            k = n;
        h4_tx_bytes(p, k);
        p += k;
        n = (uint16_t)(n - k);
        advance(k);
    }
}

void hci_acl_put_byte(uint8_t b)
{
    fragment_room();
    h4_tx_byte(b);
    advance(1);
}

void hci_acl_put_u16(uint16_t v)
{
    hci_acl_put_byte((uint8_t)v);
    hci_acl_put_byte((uint8_t)(v >> 8));
}

void hci_acl_end(void)
{
    w_open = 0;
    h4_tx_end();
}

void hci_acl_abort(void)
{
    if (!w_open)
        return;
    w_open = 0; /* the unpublished bytes are written over by the next writer */
    acl_free = (uint8_t)(acl_free + w_unsent);
    links[w_link].in_flight = (uint8_t)(links[w_link].in_flight - w_unsent);
}
