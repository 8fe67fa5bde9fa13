/**
 * \file harness.h
 * A plain test harness: tests are functions run by RUN(); CHECK() records a failure with a message and
 * carries on. The last line printed is "N passed, N failed"; the exit status is non-zero on failure.
 */
#ifndef HARNESS_H
#define HARNESS_H

#include <stdio.h>

extern int harness_failed_checks;

#define CHECK(cond, ...)                                                                                \
    do {                                                                                                \
        if (!(cond)) {                                                                                  \
            harness_failed_checks++;                                                                    \
            printf("  FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);                                   \
            printf(__VA_ARGS__);                                                                        \
            printf("\n");                                                                               \
        }                                                                                               \
    } while (0)

#define RUN(fn) harness_run(#fn, fn)
void harness_run(const char *name, void (*fn)(void));
/** Prints "N passed, N failed". \return the exit status: non-zero when a test failed */
int harness_report(void);

/* The suites, one per test file. */
void suite_frame(void);
void suite_slip(void);
void suite_golden(void);
void suite_settings(void);
void suite_pid(void);
void suite_comm(void);
void suite_speed(void);
void suite_locomotion(void);
void suite_line(void);
void suite_proximity(void);
void suite_sensors(void);
void suite_debug(void);
void suite_scheduler(void);
void suite_track(void);
void suite_links(void);

/* The Bluetooth stack's suites (bt_tests: the stack below comm, with tests/bt_wire.c as its controller). */
void suite_bt_h4(void);
void suite_bt_hci(void);
void suite_bt_l2cap(void);
void suite_bt_sdp(void);
void suite_bt_rfcomm(void);

/** Writes the golden frames (SLIPped) as fuzz corpus files into `dir`. */
void golden_write_corpus(const char *dir);

#endif
