#include "proximity.h"

#include <stddef.h>
#include <string.h>

#include "core/data.h"
#include "core/scheduler.h"
#include "drivers/ir.h"
#include "modules/comm.h"

#define LEDS 4u
#define LEVELS 3u

typedef struct {
    uint8_t robot_id;
    uint8_t led;
    uint8_t led_class;          /* class of the message led came from */
    uint32_t class_ms[4];       /* when each distance class was last heard (index = class) */
    uint32_t robot_ms;          /* when the robot was last heard */
    uint32_t obstacle_ms;       /* when our own reflection was last heard */
    uint8_t heard_robot, heard_obstacle;
    /* What robot_state shows changes only when a message is heard or a sighting expires: publish() runs
     * then, not every tick. */
    uint8_t dirty;       /* heard something since the last publish() */
    uint8_t expiring;    /* a sighting is live: publish() again at recheck_ms */
    uint32_t recheck_ms; /* when the earliest live sighting expires */
} side_t;

static side_t sides[2];
static uint16_t hold;           /* how long a sighting is held: hold_for() */
static uint8_t hold_gen;        /* settings_generation it was computed for */
static uint16_t published_hold; /* hold at the last publish() */

/* Beacon transmission, driven from the scheduler interrupts. */
static volatile uint8_t burst_msg;    /* next message of the running beacon */
static volatile uint8_t burst_msgs;   /* messages in it */
static uint8_t level;                 /* power level of the next beacon */
static hal_ir_msg_t payload_msg;      /* pending payload, len > 0 while pending */
static volatile uint8_t payload_pending, payload_in_burst;
static proximity_payload_cb_t payload_cb;

/* Last payload forwarded, to drop the copies a beacon carries from its four LEDs; `pending` while its
 * ir_received waits for room on the link (the next payload heard replaces it). */
static struct {
    uint8_t sender, len;
    uint8_t data[HAL_IR_PAYLOAD_MAX];
    uint32_t ms;
    uint8_t pending;
    pb_ir_received_t packet;
} last_fwd;

uint8_t proximity_distance_class(uint8_t power)
{
    if (power <= 25u)
        return PB_DISTANCE_CLASS_NEAR;
    if (power <= 50u)
        return PB_DISTANCE_CLASS_MID;
    return PB_DISTANCE_CLASS_FAR;
}

/* The time from one message of a beacon to the next: the message on the IR link, then a pause. */
static uint32_t message_slot_us(uint8_t len)
{
    return hal_ir_message_us(len) + PROXIMITY_MSG_GAP_US;
}

/* hold_ms, but at least a cycle of the three beacon powers and a period: held shorter, a distance class would
 * lapse between two beacons of its power. On the robot a beacon takes 96 ms on the IR link, so at the default
 * 40 ms period beacons go every 120 ms and a cycle takes 360 ms. */
static uint16_t hold_for(void)
{
    uint16_t period = settings.proximity.beacon_period_ms < 10u ? 10u : settings.proximity.beacon_period_ms;
    uint32_t airtime_ms = LEDS * message_slot_us(0) / 1000u;
    uint32_t beacon_ms = (airtime_ms + period - 1u) / period * period; /* a beacon outlasting the period skips one */
    uint32_t least = LEVELS * beacon_ms + period;
    return settings.proximity.hold_ms > least ? settings.proximity.hold_ms : (uint16_t)least;
}

static void send_next(void)
{
    uint8_t k = burst_msg;
    if (k >= burst_msgs)
        return;
    hal_ir_msg_t m;
    uint8_t full = settings.proximity.ir_power > 100u ? 100u : settings.proximity.ir_power;
    if (k < LEDS) {
        m.sender_id = settings.identity.robot_id;
        m.led = k;
        m.power = (uint8_t)(full >> level); /* 100, 50, 25 % of the set power */
        if (m.power == 0)
            m.power = 1;
        m.len = 0;
    } else {
        memcpy(&m, &payload_msg, sizeof m);
        m.sender_id = settings.identity.robot_id;
        m.led = (uint8_t)(k - LEDS);
    }
    if (!ir_transmit(&m)) { /* transmitter still busy: try again shortly */
        scheduler_after(SCHED_CH_PROX_TX, PROXIMITY_MSG_GAP_US, send_next);
        return;
    }
    robot_state.indicators.ir_power = m.power;
    burst_msg = (uint8_t)(k + 1u);
    if (burst_msg < burst_msgs)
        scheduler_after(SCHED_CH_PROX_TX, message_slot_us(m.len), send_next);
    else if (payload_in_burst)
        payload_pending = payload_in_burst = 0;
}

static void beacon(void)
{
    uint16_t period = settings.proximity.beacon_period_ms < 10u ? 10u : settings.proximity.beacon_period_ms;
    scheduler_again(SCHED_CH_PROX_BEACON, (uint32_t)period * 1000u, beacon);
    if (settings.proximity.ir_power == 0 || burst_msg < burst_msgs)
        return; /* off, or the previous beacon is still going out */
    level = (uint8_t)((level + 1u) % LEVELS);
    burst_msg = 0;
    payload_in_burst = payload_pending;
    burst_msgs = (uint8_t)(payload_in_burst ? 2u * LEDS : LEDS);
    send_next();
}

static uint8_t on_ir_send(const pb_frame_t *cmd, uint16_t *detail)
{
    pb_ir_send_t c;
    memcpy(&c, cmd->payload, cmd->len);
    uint8_t code = proximity_send_payload(c.power, c.data, (uint8_t)(cmd->len - PB_IR_SEND_HEAD_SIZE));
    if (code == PB_ERROR_CODE_BAD_ARGUMENT)
        *detail = offsetof(pb_ir_send_t, power); /* the size table already bounds the data */
    return code;
}

void proximity_init(void)
{
    memset(sides, 0, sizeof sides);
    sides[0].dirty = sides[1].dirty = 1;
    hold_gen = settings_generation;
    hold = hold_for();
    published_hold = hold;
    memset(&last_fwd, 0, sizeof last_fwd);
    burst_msg = burst_msgs = 0;
    level = 0;
    payload_pending = payload_in_burst = 0;
    payload_cb = NULL;
    ir_init();
    scheduler_after(SCHED_CH_PROX_BEACON, 1000u * (uint32_t)settings.proximity.beacon_period_ms, beacon);
    comm_register(PB_PKT_IR_SEND, on_ir_send);
}

void proximity_on_payload(proximity_payload_cb_t cb)
{
    payload_cb = cb;
}

uint8_t proximity_send_payload(uint8_t power, const uint8_t *data, uint8_t len)
{
    if (power < 1u || power > 100u || len > HAL_IR_PAYLOAD_MAX) /* the size table keeps len within 8 */
        return PB_ERROR_CODE_BAD_ARGUMENT;
    if (payload_pending)
        return PB_ERROR_CODE_BUSY;
    payload_msg.power = power;
    payload_msg.len = len;
    memset(payload_msg.data, 0, sizeof payload_msg.data);
    memcpy(payload_msg.data, data, len);
    payload_pending = 1;
    return PB_ERROR_CODE_NONE;
}

static void forward_payload(uint8_t side, const hal_ir_msg_t *m, uint32_t now)
{
    /* The copies of a payload from the four LEDs of one beacon come within its messages' slots. */
    uint32_t copies_ms = LEDS * (message_slot_us(HAL_IR_PAYLOAD_MAX) / 1000u + 1u);
    if (last_fwd.sender == m->sender_id && last_fwd.len == m->len && memcmp(last_fwd.data, m->data, m->len) == 0 &&
        now - last_fwd.ms < (copies_ms > settings.proximity.beacon_period_ms ? copies_ms
                                                                           : settings.proximity.beacon_period_ms))
        return;
    last_fwd.sender = m->sender_id;
    last_fwd.len = m->len;
    memcpy(last_fwd.data, m->data, m->len);
    last_fwd.ms = now;
    pb_ir_received_t *r = &last_fwd.packet;
    r->sender_id = m->sender_id;
    r->side = side;
    r->sender_led = m->led;
    r->power = m->power;
    memcpy(r->data, m->data, m->len);
    last_fwd.pending = 1;
}

static void forward_pending(void)
{
    if (comm_offer(PB_PKT_IR_RECEIVED, &last_fwd.packet, (uint8_t)(PB_IR_RECEIVED_HEAD_SIZE + last_fwd.len)))
        last_fwd.pending = 0;
}

static void heard(uint8_t side_no, const hal_ir_msg_t *m, uint32_t now)
{
    side_t *s = &sides[side_no];
    s->dirty = 1;
    if (m->sender_id == settings.identity.robot_id) {
        s->obstacle_ms = now;
        s->heard_obstacle = 1;
        return;
    }
    if (m->len && !(payload_cb && payload_cb(side_no, m)))
        forward_payload(side_no, m, now);
    uint8_t cls = proximity_distance_class(m->power);
    bool current = s->heard_robot && now - s->robot_ms < hold;
    if (current && m->sender_id != s->robot_id) {
        /* Another robot: it takes the receiver only if at least as near as the one held. */
        uint8_t held = 0;
        for (uint8_t c = 3; c > 0 && !held; c--)
            if (s->class_ms[c] && now - s->class_ms[c] < hold)
                held = c;
        if (cls < held)
            return;
        current = false;
    }
    if (!current) {
        memset(s->class_ms, 0, sizeof s->class_ms);
        s->led_class = 0;
        s->robot_id = m->sender_id;
    }
    s->heard_robot = 1;
    s->robot_ms = now;
    s->class_ms[cls] = now ? now : 1u;
    if (cls >= s->led_class || now - s->class_ms[s->led_class] >= hold) {
        s->led = m->led; /* the LED heard at the lowest power faces us most directly */
        s->led_class = cls;
    }
}

/* Whether a sighting at `t` is live at `now`; the age of the oldest live one so far goes to *oldest (+1):
 * it is the first to expire. */
static inline __attribute__((always_inline)) bool live(uint32_t t, uint32_t now, uint16_t hold, uint16_t *oldest)
{
    uint32_t age = now - t;
    if (age >= hold)
        return false;
    if ((uint16_t)age >= *oldest)
        *oldest = (uint16_t)(age + 1u);
    return true;
}

static void publish(pb_proximity_side_t *out, side_t *s, uint32_t now)
{
    uint16_t oldest = 0;
    uint8_t flags = 0;
    if (s->heard_obstacle && live(s->obstacle_ms, now, hold, &oldest))
        flags |= PB_PROXIMITY_FLAG_OBSTACLE;
    uint8_t cls = PB_DISTANCE_CLASS_NONE;
    if (s->heard_robot && live(s->robot_ms, now, hold, &oldest)) {
        flags |= PB_PROXIMITY_FLAG_ROBOT;
        /* Lower classes that expire before this one change nothing; when it expires, this runs again. */
        for (uint8_t c = 3; c > 0 && cls == PB_DISTANCE_CLASS_NONE; c--)
            if (s->class_ms[c] && live(s->class_ms[c], now, hold, &oldest))
                cls = c;
    } else {
        s->heard_robot = 0;
    }
    s->dirty = 0;
    s->expiring = oldest != 0;
    s->recheck_ms = now + (uint16_t)(hold - (oldest - 1u)); /* when the oldest live one reaches hold */
    out->flags = flags;
    out->robot_id = (flags & PB_PROXIMITY_FLAG_ROBOT) ? s->robot_id : 0;
    out->robot_led = (flags & PB_PROXIMITY_FLAG_ROBOT) ? s->led : 0;
    out->distance = cls;
}

static void publish_if_changed(pb_proximity_side_t *out, side_t *s, uint32_t now, bool hold_changed)
{
    if (s->dirty || hold_changed || (s->expiring && (int32_t)(now - s->recheck_ms) >= 0))
        publish(out, s, now);
}

void proximity_task(void)
{
    uint32_t now = robot_state.time.time_ms;
    uint8_t side;
    const hal_ir_msg_t *m;
    /* A payload heard goes out in a later tick than the one that heard it: the two costs do not add up. */
    if (last_fwd.pending)
        forward_pending();
    while ((m = ir_peek(&side)) != NULL) {
        heard(side, m, now);
        ir_pop();
    }
    if (hold_gen != settings_generation) {
        hold_gen = settings_generation;
        hold = hold_for();
    }
    bool hold_changed = published_hold != hold;
    published_hold = hold;
    publish_if_changed(&robot_state.proximity.front, &sides[0], now, hold_changed);
    publish_if_changed(&robot_state.proximity.rear, &sides[1], now, hold_changed);
}
