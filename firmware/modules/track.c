#include "track.h"

#include <stdbool.h>
#include <stddef.h>
#include <string.h>

#include "core/data.h"
#include "modules/comm.h"
#include "modules/debug.h"
#include "modules/line_follower.h"
#include "modules/locomotion.h"
#include "modules/proximity.h"
#include "modules/speed.h"

#define UM_PER_M 1.0e6f
/** Messages go out at full power: another robot close enough to matter hears them from any LED. */
#define TRACK_MSG_POWER 100u
/** Wheel speed of turns on the spot, um/s. */
#define TURN_UMPS 60000
/** Line position (permille) within which the robot counts as lined up with the line after a turn. */
#define LINED_UP_PERMILLE 150
/** Driving on while both wheels stand still this long: something the IR does not see (a corner beside the
 *  beam) blocks the robot, ms. */
#define STALL_MS 400u
/** A robot heard ahead that is heard no more is not gone for this long, ms: it may only have turned (to drive
 *  round an obstacle) so that none of its LEDs' narrow beams points at us any more. Heard close (mid or near),
 *  it is waited for; heard far, it is approached at half speed (the token holder's boost would catch it up). */
#define VANISH_MS 1500u
/** An offer of the token not accepted within this long is withdrawn (the holder still has the token) and made
 *  again, to whichever robot is close ahead then: about ten beacons, time for an answer to come back. */
#define OFFER_TIMEOUT_MS 400u
/** Searches for the line that meet the obstacle again before giving up. */
#define MAX_RETRIES 3u
/** Rounds of a search for a lost line (sweep, back up) before the robot gives up and stands still. */
#define SEARCH_ROUNDS 4u

enum { PHASE_FOLLOW, PHASE_MANOEUVRE, PHASE_LOST };

/* A manoeuvre is a chain of steps, each a straight or a turn on the spot given by its wheel distances (mm,
 * for the PocketBot2's 26 mm wheel base: 14 mm = 62 degrees, 27 mm = 120 degrees). A step ends after its
 * distance, or earlier when its condition holds; a search that runs its whole distance has lost the line, and a
 * search for it (SEARCH) begins.
 * UNTIL_PASSED ends at its distance, or at the line (then on at DETOUR_REJOIN): on the inside of a curve the
 * line comes back across the robot's way while it passes the obstacle. UNTIL_FOUND (a search) ends at its
 * distance, or at the line: then the robot follows it again. */
enum { UNTIL_DISTANCE, UNTIL_PASSED, UNTIL_LINE, UNTIL_CENTRED, UNTIL_LINED_UP, UNTIL_FOUND };
#define STEP_DONE 0xFFu

typedef struct {
    int16_t left_mm, right_mm;
    uint8_t until;
    uint8_t next;
} step_t;

enum {
    DETOUR = 0,       /* round an obstacle on the right */
    DETOUR_REJOIN = 6, /* the line is in sight: under the sensor's middle, then line up */
    DETOUR_RETRY = 9, /* the search met the obstacle again: out a little more, and pass again */
    TURN = 10,        /* reverse: turn round to the left and line up */
    SEARCH = 12,      /* the line is lost: sweep 45 degrees either side, back up a little, again */
};

/* The detour comes back to the line from its right, heading in at an angle: the sensor first sees the line on its
 * left, then under its middle; 20 mm on, the axle is over the line, and a turn to the right lines the robot up
 * with it (turning on the spot over the line, the sensor meets it again where the robot points along it). */
static const HAL_FLASH step_t steps[] = {
    [0] = {14, -14, UNTIL_DISTANCE, 1},        /* turn out to the right */
    [1] = {60, 60, UNTIL_DISTANCE, 2},         /* away from the line */
    [2] = {-14, 14, UNTIL_DISTANCE, 3},        /* parallel to it again */
    [3] = {140, 140, UNTIL_PASSED, 4},         /* past the obstacle, with room to turn in */
    [4] = {-14, 14, UNTIL_DISTANCE, 5},        /* turn in */
    [5] = {250, 250, UNTIL_LINE, 6},           /* until the sensor sees the line */
    [6] = {60, 60, UNTIL_CENTRED, 7},          /* until it is under the sensor's middle */
    [7] = {20, 20, UNTIL_DISTANCE, 8},         /* axle over the line */
    [8] = {23, -23, UNTIL_LINED_UP, STEP_DONE}, /* turn right (at most 100 degrees) until lined up */
    [9] = {14, -14, UNTIL_DISTANCE, 3},        /* DETOUR_RETRY */
    [10] = {-27, 27, UNTIL_DISTANCE, 11},      /* TURN: 120 degrees, the line is behind */
    [11] = {-27, 27, UNTIL_LINED_UP, STEP_DONE}, /* on until lined up (the line comes back at 180) */
    /* The sensor is 20 mm ahead of the axle: a sweep finds a line the robot has just left (it drifted off, or a
     * manoeuvre ended beside it); backing up retraces the way to where the line last was. */
    [12] = {-10, 10, UNTIL_FOUND, 13},         /* SEARCH: 45 degrees left */
    [13] = {20, -20, UNTIL_FOUND, 14},         /* 90 degrees right */
    [14] = {-10, 10, UNTIL_FOUND, 15},         /* straight again */
    [15] = {-40, -40, UNTIL_FOUND, SEARCH},    /* back up (not into a robot or obstacle behind) */
};
static struct {
    uint8_t active;     /* the behaviour runs (started, not ended by a stop or another command) */
    uint8_t phase;
    uint8_t resume;     /* after a turn: follow the line (else the behaviour stops) */
    uint8_t step;
    uint8_t settling;   /* the step waits for the wheels to stand still */
    uint32_t moving_ms; /* when the wheels last turned while driven straight on */
    uint32_t heard_ms;  /* when a robot was last heard ahead */
    uint8_t heard;      /* ... and how close, a PB_DISTANCE_CLASS_ */
    uint8_t retries;
    int32_t l0, r0;     /* wheel positions at the start of the step, um */
    uint8_t created;    /* this robot created the token already */
    uint8_t hop;        /* the token's hand-overs when it came here */
    uint8_t offer_to;   /* the robot the token is offered (then given) to, 0: none */
    uint8_t giving;     /* let go of the token to offer_to: GIVE until it answers TAKEN */
    uint16_t offer_ms;  /* when the offer began */
    uint8_t accepted_from, accepted_hop; /* the offer we accepted and have not been given yet */
    uint8_t reply, reply_to, reply_hop; /* the answer to send (ACCEPT or TAKEN), 0: none */
    uint8_t greet_to;   /* a robot close by that we have not greeted yet */
    uint8_t greet_side;
    uint8_t greeted[2]; /* per receiver: the robot greeted last while it stays in hearing */
} t;

/* From the float settings when they change. */
static struct {
    uint8_t gen;
    int32_t speed, half, boosted; /* um/s */
} k;

/* The conversion when settings changed: float arithmetic, a call that saves every register. */
static __attribute__((noinline)) void params_changed(void)
{
    k.gen = settings_generation;
    k.speed = (int32_t)(settings.track.speed_mps * UM_PER_M + 0.5f);
    k.half = k.speed / 2;
    k.boosted = k.speed + k.speed / 100 * settings.track.token_boost_percent;
}

/* The test of every tick, inline: the conversion apart. */
static inline __attribute__((always_inline)) void refresh_params(void)
{
    if (k.gen != settings_generation)
        params_changed();
}

/* The distance class of the robot heard in front, NONE if none. */
static uint8_t robot_ahead(void)
{
    const pb_proximity_side_t *f = &robot_state.proximity.front;
    return (f->flags & PB_PROXIMITY_FLAG_ROBOT) ? f->distance : PB_DISTANCE_CLASS_NONE;
}

/* Something reflects our beacon in front and it is not a robot close by (robots announce themselves). */
static bool obstacle_ahead(void)
{
    return (robot_state.proximity.front.flags & PB_PROXIMITY_FLAG_OBSTACLE) && robot_ahead() < PB_DISTANCE_CLASS_MID;
}

/* Driving straight on at `v` without the wheels turning for STALL_MS: blocked. */
static bool stalled(int32_t v)
{
    uint32_t now = robot_state.time.time_ms;
    if (v == 0 || speed_umps(0) != 0 || speed_umps(1) != 0) {
        t.moving_ms = now;
        return false;
    }
    return now - t.moving_ms >= STALL_MS;
}

static void halt(uint8_t phase, uint8_t status)
{
    t.phase = phase;
    robot_state.track.status = status;
    locomotion_wheel_setpoints(0, 0);
}

static void step_begin(uint8_t i)
{
    DEBUG_PRINT(TRACK, 3, "step %u", i);
    if (i == SEARCH && t.retries++ >= SEARCH_ROUNDS) {
        halt(PHASE_LOST, PB_TRACK_STATUS_LOST); /* the line is not near: wait to be put back on it */
        return;
    }
    t.step = i;
    t.settling = 1;
}

static void manoeuvre_begin(uint8_t first, uint8_t status)
{
    t.phase = PHASE_MANOEUVRE;
    t.retries = 0;
    robot_state.track.status = status;
    step_begin(first);
}

static void follow_begin(void)
{
    t.phase = PHASE_FOLLOW;
    t.moving_ms = robot_state.time.time_ms;
    t.heard_ms = robot_state.time.time_ms - VANISH_MS;
    line_follower_steer_reset();
    robot_state.track.status = PB_TRACK_STATUS_FOLLOWING;
}

/* Ends the behaviour; `motors_off` unless another command has the motors already. */
static void end(bool motors_off)
{
    t.active = 0;
    robot_state.track.status = PB_TRACK_STATUS_OFF;
    if (motors_off)
        locomotion_stop(true);
}

static void manoeuvre_done(void)
{
    if (robot_state.track.status == PB_TRACK_STATUS_TURNING && !t.resume)
        end(true);
    else
        follow_begin();
}

/* Whether a turn on the spot has brought the line under the middle of the sensor. A lining-up turn starts with
 * the line centred already or off to the side the turn brings it from (after a detour the sensor is past the
 * line; after the first 120 degrees of a reverse the line is behind on the left). */
static bool lined_up(void)
{
    int16_t p = robot_state.line.position;
    return (robot_state.line.flags & PB_LINE_FLAG_SEEN) && p <= LINED_UP_PERMILLE && p >= -LINED_UP_PERMILLE;
}

static void manoeuvre(void)
{
    /* Each step starts at rest: the encoders count in the direction a wheel is driven, so a wheel still rolling
     * the old way would count backwards, and the turns would come out short. */
    if (t.settling) {
        locomotion_wheel_setpoints(0, 0);
        if (speed_umps(0) != 0 || speed_umps(1) != 0)
            return;
        t.settling = 0;
        t.moving_ms = robot_state.time.time_ms;
        speed_positions_um(&t.l0, &t.r0);
    }
    const HAL_FLASH step_t *s = &steps[t.step];
    int16_t l = s->left_mm, r = s->right_mm;
    uint8_t until = s->until;
    bool straight = l == r;
    if (until == UNTIL_PASSED && (robot_state.line.flags & PB_LINE_FLAG_SEEN)) {
        step_begin(DETOUR_REJOIN);
        return;
    }
    if (until == UNTIL_LINE) {
        if (robot_state.line.flags & PB_LINE_FLAG_SEEN) {
            step_begin(s->next);
            return;
        }
        if (obstacle_ahead() && t.retries < MAX_RETRIES) {
            t.retries++;
            step_begin(DETOUR_RETRY);
            return;
        }
    } else if (until == UNTIL_CENTRED) {
        if ((robot_state.line.flags & PB_LINE_FLAG_SEEN) && robot_state.line.position >= 0) {
            step_begin(s->next);
            return;
        }
    } else if (until == UNTIL_LINED_UP && lined_up()) {
        manoeuvre_done();
        return;
    } else if (until == UNTIL_FOUND && (robot_state.line.flags & PB_LINE_FLAG_SEEN)) {
        follow_begin();
        return;
    }
    int32_t pl, pr;
    speed_positions_um(&pl, &pr);
    /* Along the step's own directions: a wheel still rolling the other way at its start counts backwards. */
    pl -= t.l0;
    pr -= t.r0;
    int32_t done = ((l < 0 ? -pl : pl) + (r < 0 ? -pr : pr)) >> 1;
    if (done >= (int32_t)(l < 0 ? -l : l) * 1000) {
        if (until != UNTIL_DISTANCE && until != UNTIL_PASSED && until != UNTIL_FOUND)
            manoeuvre_begin(SEARCH, PB_TRACK_STATUS_LOST);
        else
            step_begin(s->next);
        return;
    }
    /* Straight on only while no robot is close ahead; turns on the spot need no room. Backing up (a search) is
     * left out when anything reflects our beacon behind or a robot is close there: waiting for it could be
     * waiting for a robot that waits for us. */
    int32_t v = straight ? (robot_ahead() >= PB_DISTANCE_CLASS_MID ? 0 : k.speed) : TURN_UMPS;
    if (straight && l < 0) {
        const pb_proximity_side_t *b = &robot_state.proximity.rear;
        if ((b->flags & PB_PROXIMITY_FLAG_OBSTACLE) || ((b->flags & PB_PROXIMITY_FLAG_ROBOT) && b->distance >= PB_DISTANCE_CLASS_MID)) {
            step_begin(s->next);
            return;
        }
        v = k.speed;
    } else if (straight && stalled(v) && t.retries < MAX_RETRIES) {
        /* Blocked while passing (a corner of the obstacle beside the robot): the whole way out again, further
         * from the line (a turn alone would point the pass away from it); blocked heading in: out, pass again. */
        t.retries++;
        step_begin(until == UNTIL_PASSED ? DETOUR : DETOUR_RETRY);
        return;
    }
    locomotion_wheel_setpoints(l < 0 ? -v : v, r < 0 ? -v : v);
}

/* Line following with the distance kept from the robot ahead; an obstacle starts a detour. */
static void follow(void)
{
    uint8_t line = robot_state.line.flags;
    if (line & PB_LINE_FLAG_LOST) {
        manoeuvre_begin(SEARCH, PB_TRACK_STATUS_LOST);
        return;
    }
    uint32_t now = robot_state.time.time_ms;
    uint8_t ahead = robot_ahead();
    if (ahead != PB_DISTANCE_CLASS_NONE) {
        t.heard_ms = now;
        t.heard = ahead;
    }
    int32_t v = robot_state.track.token ? k.boosted : k.speed;
    if (ahead == PB_DISTANCE_CLASS_NEAR) {
        /* Head on (its front LED faces us: one of us missed a reverse): the lower id turns round, the other
         * waits until the way is clear. */
        const pb_proximity_side_t *f = &robot_state.proximity.front;
        if (f->robot_led == PB_IR_LED_FRONT && settings.identity.robot_id < f->robot_id) {
            t.resume = 1;
            manoeuvre_begin(TURN, PB_TRACK_STATUS_TURNING);
            return;
        }
        v = 0;
    } else if (ahead == PB_DISTANCE_CLASS_NONE && now - t.heard_ms < VANISH_MS) {
        /* the robot ahead turned away (out of its LEDs' beams), it is not gone yet */
        if (t.heard >= PB_DISTANCE_CLASS_MID)
            v = 0;
        else if (v > k.half)
            v = k.half;
    } else if (ahead == PB_DISTANCE_CLASS_MID && v > k.half) {
        v = k.half;
    }
    if ((line & PB_LINE_FLAG_SEEN) && (obstacle_ahead() || stalled(v))) {
        DEBUG_PRINT(TRACK, 2, "obstacle: detour");
        manoeuvre_begin(DETOUR, PB_TRACK_STATUS_DETOUR);
        return;
    }
    if (v == 0) {
        line_follower_steer_reset();
        halt(PHASE_FOLLOW, PB_TRACK_STATUS_KEEPING_DISTANCE);
        return;
    }
    robot_state.track.status = v < k.speed ? PB_TRACK_STATUS_KEEPING_DISTANCE : PB_TRACK_STATUS_FOLLOWING;
    line_follower_steer(v);
}

/* Who to talk to: the robot ahead gets the token when it is close; robots close by that are new get a
 * greeting. */
static void listen(void)
{
    if (robot_state.track.token) {
        /* An offer stays with its robot until it is accepted or withdrawn: that robot may have answered. */
        uint16_t now = (uint16_t)robot_state.time.time_ms;
        if (t.offer_to && (uint16_t)(now - t.offer_ms) >= OFFER_TIMEOUT_MS)
            t.offer_to = 0;
        if (!t.offer_to && robot_ahead() >= PB_DISTANCE_CLASS_MID) {
            t.offer_to = robot_state.proximity.front.robot_id;
            t.offer_ms = now;
        }
    }
    const pb_proximity_side_t *side = &robot_state.proximity.front;
    for (uint8_t i = 0; i < 2; i++, side = &robot_state.proximity.rear) {
        if (!(side->flags & PB_PROXIMITY_FLAG_ROBOT))
            t.greeted[i] = 0; /* out of hearing: greeted again when met again */
        else if (side->distance >= PB_DISTANCE_CLASS_MID && side->robot_id != t.greeted[i] && !t.greet_to) {
            t.greet_to = side->robot_id;
            t.greet_side = i;
        }
    }
}

/* One message per beacon, most urgent first: an answer, the hand-over, a greeting. A robot that let go of the token
 * goes on giving it after a stop: until TAKEN, the token is in its care. */
static __attribute__((noinline)) void talk(void)
{
    uint8_t msg[TRACK_MSG_LEN];
    uint8_t next = (uint8_t)(t.hop + 1u);
    if (t.reply) {
        msg[0] = t.reply;
        msg[1] = t.reply_to;
        msg[2] = t.reply_hop;
    } else if (t.giving) {
        msg[0] = TRACK_MSG_GIVE;
        msg[1] = t.offer_to;
        msg[2] = next;
    } else if (!t.active) {
        return;
    } else if (robot_state.track.token && t.offer_to) {
        msg[0] = TRACK_MSG_OFFER;
        msg[1] = t.offer_to;
        msg[2] = next;
    } else if (t.greet_to) {
        msg[0] = TRACK_MSG_GREET;
        msg[1] = t.greet_to;
        msg[2] = 0;
    } else {
        return;
    }
    if (proximity_send_payload(TRACK_MSG_POWER, msg, TRACK_MSG_LEN) != PB_ERROR_CODE_NONE)
        return; /* the previous message is still going out: again next tick */
    if (msg[0] == t.reply) {
        t.reply = 0;
    } else if (msg[0] == TRACK_MSG_GREET) {
        t.greeted[t.greet_side] = t.greet_to;
        t.greet_to = 0;
    }
}

static void answer(uint8_t kind, uint8_t to, uint8_t hop)
{
    t.reply = kind; /* one answer waits at most: the other robot asks again */
    t.reply_to = to;
    t.reply_hop = hop;
}

/* The token's hand-over is a two-phase handshake. Messages (kind, addressee, hop; hop = hand-overs so far + 1):
 * OFFER and GIVE from the holder, ACCEPT and TAKEN in answer. A robot's states, as t keeps them:
 *   holding      token 1, offer_to 0: shows the token, hurries to catch up with the robot ahead
 *   offering     token 1, offer_to X (since offer_ms): OFFER(X, hop+1) every beacon
 *   giving       token 0, giving 1, offer_to X: has let go, GIVE(X, hop+1) every beacon until X answers TAKEN
 *   accepted     accepted_from H, accepted_hop h: answered H's offer of hop h, does not hold the token yet (a
 *                robot still giving may accept: the token can come round to it before it hears the TAKEN it missed)
 *   none of these: neither holds the token nor has it in its care
 * A hand-over from H (token at hop n) to X, the robot close ahead:
 *
 *   H holding -> offering: OFFER(X, n+1) ...     X, not holding: answers each OFFER with ACCEPT(H, n+1); accepted
 *   H hears X's ACCEPT(H, n+1): token 0, giving: GIVE(X, n+1) ...
 *                                                X: the GIVE of the offer it accepted: takes the token (token 1,
 *                                                   hop n+1, a visit); answers every GIVE with TAKEN(H, n+1)
 *   H hears X's TAKEN(H, n+1): none of the states
 *
 * At most one robot holds the token at any instant: H lets go before it sends the first GIVE, and X takes the
 * token only from a GIVE. Between the two nobody holds it: it is on its way, in H's care. Each message names
 * its addressee; the other robots that hear it ignore it. An offer names one robot and stays with it until that
 * robot accepts or OFFER_TIMEOUT_MS pass (robots ahead change as they turn away, detour, overtake). Lost messages:
 *   OFFER or ACCEPT lost: H offers again; after the timeout it withdraws the offer, still holding the token, and
 *     offers to whichever robot is close ahead then. An ACCEPT that was not followed by GIVE gave X nothing.
 *   GIVE or TAKEN lost: H gives again, without a timeout (it cannot tell whether X holds the token, so it may
 *     neither take it back nor give up); X answers each GIVE with TAKEN and keeps the token it took.
 *   X hands the token on before H hears TAKEN: X still answers H's GIVE, now a repeat (it no longer matches an
 *     offer X accepted); and when the token comes back to H, H's own hand-over is over too.
 */
static void on_token_msg(uint8_t kind, uint8_t from, uint8_t hop)
{
    uint8_t next = (uint8_t)(t.hop + 1u);
    switch (kind) {
    case TRACK_MSG_OFFER:
        if (!robot_state.track.token) {
            t.accepted_from = from;
            t.accepted_hop = hop;
            answer(TRACK_MSG_ACCEPT, from, hop);
        }
        break;
    case TRACK_MSG_ACCEPT:
        if (robot_state.track.token && from == t.offer_to && hop == next) {
            robot_state.track.token = 0;
            t.giving = 1;
            DEBUG_PRINT(TRACK, 2, "token to %u, hop %u", from, hop);
        }
        break;
    case TRACK_MSG_GIVE:
        if (from == t.accepted_from && hop == t.accepted_hop) {
            t.accepted_from = 0;
            t.hop = hop;
            t.giving = 0; /* the token came back: a hand-over of ours is over too */
            t.offer_to = 0;
            robot_state.track.token = 1;
            robot_state.track.token_visits++;
            DEBUG_PRINT(TRACK, 2, "token from %u, hop %u", from, hop);
        }
        answer(TRACK_MSG_TAKEN, from, hop);
        break;
    default: /* TAKEN */
        if (t.giving && from == t.offer_to && hop == next) {
            t.giving = 0;
            t.offer_to = 0;
        }
        break;
    }
}

/* The track messages are the robots' own conversation (not forwarded to the host), whoever they are for. */
static bool on_payload(uint8_t side, const hal_ir_msg_t *m)
{
    (void)side;
    uint8_t kind = m->data[0];
    if (m->len != TRACK_MSG_LEN || kind < TRACK_MSG_GREET || kind > TRACK_MSG_TAKEN)
        return false;
    if (m->data[1] != settings.identity.robot_id)
        return true;
    if (kind == TRACK_MSG_GREET)
        robot_state.track.met_id = m->sender_id;
    else
        on_token_msg(kind, m->sender_id, m->data[2]);
    return true;
}

uint8_t track_command(uint8_t action)
{
    bool running = t.active && robot_state.locomotion.mode == PB_LOCO_MODE_TRACK;
    switch (action) {
    case PB_TRACK_ACTION_STOP:
        end(running);
        return PB_ERROR_CODE_NONE;
    case PB_TRACK_ACTION_START:
        if (!t.created && settings.track.token_origin_id == settings.identity.robot_id) {
            t.created = 1;
            t.hop = 0;
            robot_state.track.token = 1;
        }
        if (running)
            return PB_ERROR_CODE_NONE;
        refresh_params();
        locomotion_track_begin();
        t.active = 1;
        follow_begin();
        DEBUG_PRINT(TRACK, 2, "started");
        return PB_ERROR_CODE_NONE;
    case PB_TRACK_ACTION_REVERSE:
        refresh_params();
        t.resume = running;
        if (!running)
            locomotion_track_begin();
        t.active = 1;
        manoeuvre_begin(TURN, PB_TRACK_STATUS_TURNING);
        return PB_ERROR_CODE_NONE;
    default:
        return PB_ERROR_CODE_BAD_ARGUMENT;
    }
}

static uint8_t on_track(const pb_frame_t *cmd, uint16_t *detail)
{
    uint8_t code = track_command(cmd->payload[offsetof(pb_track_t, action)]);
    if (code == PB_ERROR_CODE_BAD_ARGUMENT)
        *detail = offsetof(pb_track_t, action);
    return code;
}

void track_init(void)
{
    memset(&t, 0, sizeof t);
    k.gen = (uint8_t)(settings_generation - 1u);
    refresh_params();
    robot_state.track.status = PB_TRACK_STATUS_OFF;
    comm_register(PB_PKT_TRACK, on_track);
    proximity_on_payload(on_payload);
}

/* Kept out of track_task(), so that a robot without the behaviour pays a test and no stack frame. */
static __attribute__((noinline)) void step(void)
{
    if (robot_state.locomotion.mode != PB_LOCO_MODE_TRACK) { /* another command took the motors */
        end(false);
        return;
    }
    refresh_params();
    listen();
    if (t.phase == PHASE_FOLLOW)
        follow();
    else if (t.phase == PHASE_MANOEUVRE)
        manoeuvre();
    else if (robot_state.line.flags & PB_LINE_FLAG_SEEN)
        follow_begin(); /* lost: put back on the line */
}

void track_task(void)
{
    if (t.active)
        step();
    if (t.active || t.reply || t.giving)
        talk();
}
