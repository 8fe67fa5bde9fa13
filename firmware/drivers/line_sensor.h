/**
 * \file line_sensor.h
 * Line sensor (thesis 11.3): four detectors and five interleaved emitters give eight spots. One
 * acquisition reads all detectors dark, then with emitters {0,2,4} lit, then with {1,3} lit; its phases
 * are spread over the line sensor scheduler channel and never wait. Lit minus dark suppresses ambient
 * light; per-spot calibration gives darkness in permille; the line position is the darkness-weighted
 * centroid of the spots above threshold, so it does not depend on the line width; of two lines (a fork), the
 * one nearest to where the line was. robot_state.line.flags
 * holds PB_LINE_FLAG_SEEN and PB_LINE_FLAG_LOST (line_flags in the schema).
 */
#ifndef LINE_SENSOR_H
#define LINE_SENSOR_H

#include <stdint.h>

#define LINE_SPOTS 8u
/** Delay between acquisition phases: emitter settling and one conversion. */
#define LINE_PHASE_US 100u

void line_sensor_init(void);
/** Evaluates the last acquisition into robot_state.line and starts the next one; once per tick. */
void line_sensor_task(void);

/**
 * The evaluation, exposed for tests: raw spot readings -> darkness (permille) and line position. When the
 * spots above the threshold form two or more separate runs (two lines: a fork), the position is that of the
 * run nearest to the previous position, so the follower keeps to one branch.
 * \param raw ambient-suppressed readings \param dark_out darkness per spot (may be NULL)
 * \param position in: the previous line position; out: the line position (permille) when the line is seen
 * \return true if seen
 */
uint8_t line_sensor_evaluate(const uint16_t raw[LINE_SPOTS], uint16_t dark_out[LINE_SPOTS], int16_t *position);

#endif
