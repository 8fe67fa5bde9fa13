/**
 * \file movement_log.h
 * The results of queued movements: every movement that ends (finished, stopped, failsafe, dropped) is
 * recorded here with how much it did, reported to the host as `movement_done`, and kept among the last
 * MOVEMENT_LOG_SIZE results that `read_movements` returns as `movement_log` (for a host that was away when
 * the reports went out). Only a reset clears the log.
 *
 * A result may be recorded before its `done` is final (a movement that ends while the robot still rolls):
 * its report, and every report and log answer after it, wait for movement_log_settle().
 */
#ifndef MOVEMENT_LOG_H
#define MOVEMENT_LOG_H

#include <stdbool.h>
#include <stdint.h>

/** Results kept: as many as the queue holds, so a failsafe that clears a full queue is recorded whole. */
#define MOVEMENT_LOG_SIZE 16u

/** Clears the log and registers `read_movements` (answered once every result recorded so far is final and
 *  reported, through comm_answer_later()). */
void movement_log_init(void);

/** Records that movement `id` ended with `outcome` (PB_MOVEMENT_OUTCOME_*) after doing `done` (m or deg,
 *  signed like the request). \param final false: `done` is provisional until movement_log_settle() (at most
 *  one result is provisional; recording another provisional one settles the previous with what it had). */
void movement_log_record(uint16_t id, uint8_t outcome, float done, bool final);

/** Gives the provisional result its final `done`. */
void movement_log_settle(float done);

/** Non-zero while reports wait (the per-tick check costs a load, not a call). */
extern uint8_t movement_log_unreported;
void movement_log_report(void);

/** Sends the reports that are due, in order, as the transmit buffer has room. Once per tick. */
static inline void movement_log_task(void)
{
    if (movement_log_unreported)
        movement_log_report();
}

#endif
