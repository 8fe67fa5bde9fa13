#include "movement_log.h"

#include <string.h>

#include "core/data.h"
#include "modules/comm.h"

typedef struct {
    float done;
    uint16_t id;
    uint8_t outcome;
} entry_t;

static entry_t entries[MOVEMENT_LOG_SIZE];
/* Results are numbered as recorded (mod 256): result k lives in entries[k % MOVEMENT_LOG_SIZE]. */
static uint8_t written;     /* results recorded */
static uint8_t reported;    /* results whose movement_done went out (or that were overwritten unsent) */
static uint8_t filled;      /* valid entries, up to MOVEMENT_LOG_SIZE */
static uint8_t provisional; /* 1 while result `pending_k` waits for its final done */
static uint8_t pending_k;
uint8_t movement_log_unreported;

/* The read_movements answer under way: the log, then the ack. */
static uint8_t answer_seq;
static uint8_t log_sent;

_Static_assert(256u % MOVEMENT_LOG_SIZE == 0, "result numbers wrap onto the same slots");

static bool answer_step(void);

static uint8_t on_read_movements(const pb_frame_t *cmd, uint16_t *detail)
{
    (void)detail;
    answer_seq = cmd->seq; /* a repeated request while one is under way gets the newer seq and a fresh log */
    log_sent = 0;
    if (!answer_step())
        comm_answer_later(answer_step);
    return COMM_ANSWER_LATER;
}

void movement_log_init(void)
{
    memset(entries, 0, sizeof entries);
    written = reported = filled = 0;
    provisional = 0;
    movement_log_unreported = 0;
    comm_register(PB_PKT_READ_MOVEMENTS, on_read_movements);
}

void movement_log_record(uint16_t id, uint8_t outcome, float done, bool final)
{
    /* Only one result rolls on at a time: a newer provisional one, or overwriting its slot, settles an older
     * one with what it had. */
    if (provisional && (!final || (uint8_t)(written - pending_k) >= MOVEMENT_LOG_SIZE))
        provisional = 0;
    entry_t *e = &entries[written % MOVEMENT_LOG_SIZE];
    e->id = id;
    e->outcome = outcome;
    e->done = done;
    if (!final) {
        provisional = 1;
        pending_k = written;
    }
    written++;
    movement_log_unreported = 1;
    if (filled < MOVEMENT_LOG_SIZE)
        filled++;
    if ((uint8_t)(written - reported) > MOVEMENT_LOG_SIZE) /* overwritten before its report could go out */
        reported = (uint8_t)(written - MOVEMENT_LOG_SIZE);
}

void movement_log_settle(float done)
{
    if (!provisional)
        return;
    provisional = 0;
    entries[pending_k % MOVEMENT_LOG_SIZE].done = done; /* still there: its slot was not reused meanwhile */
}

void movement_log_report(void)
{
    while (reported != written) {
        if (provisional && reported == pending_k)
            return; /* in order: what follows waits too */
        const entry_t *e = &entries[reported % MOVEMENT_LOG_SIZE];
        pb_movement_done_t d = {e->id, e->outcome, e->done};
        if (!comm_offer(PB_PKT_MOVEMENT_DONE, &d, sizeof d))
            return;
        reported++;
    }
    movement_log_unreported = 0;
}

/* The log once every result is final and reported (so it never tells less than the reports), then the ack. */
static bool answer_step(void)
{
    if (!log_sent) {
        if (movement_log_unreported)
            return false;
        pb_movement_log_t m;
        memset(&m, 0, sizeof m);
        m.current_id = robot_state.locomotion.current_id;
        m.queue_length = robot_state.locomotion.queue_length;
        m.count = filled;
        uint8_t first = (uint8_t)(written - filled);
        for (uint8_t i = 0; i < filled; i++) {
            const entry_t *e = &entries[(uint8_t)(first + i) % MOVEMENT_LOG_SIZE];
            m.ids[i] = e->id;
            m.outcomes[i] = e->outcome;
            m.done[i] = e->done;
        }
        if (!comm_offer(PB_PKT_MOVEMENT_LOG, &m, sizeof m))
            return false;
        log_sent = 1;
    }
    return comm_ack(PB_PKT_READ_MOVEMENTS, answer_seq);
}
