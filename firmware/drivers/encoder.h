/**
 * \file encoder.h
 * Wheel encoder driver: every stripe edge is timestamped by the timer's input capture (fed by the analog
 * comparator through the event system on the robot). The interrupt only counts and stores timestamps; the
 * speed module turns them into speeds. The encoders have one channel: counts are signed by the commanded
 * motor direction (encoder_set_direction()).
 */
#ifndef ENCODER_H
#define ENCODER_H

#include <stdint.h>

#define ENCODER_LEFT 0u
#define ENCODER_RIGHT 1u

/** The shortest time between two stripe edges a wheel can make: a narrow stripe (about 0.6 mm of a 9 mm wheel's
 *  40) passing at 6 m/s, several times any speed the robot reaches. An edge sooner than this after the last one is
 *  the comparator chattering on one stripe edge: it is not counted. */
#define ENCODER_MIN_EDGE_US 100u

/** A consistent copy of what the interrupt recorded for one wheel. */
typedef struct {
    int32_t count;      /**< signed pulse count since reset */
    uint32_t last;      /**< capture time of the latest edge (HAL_CAPTURE_HZ) */
    uint32_t period[2]; /**< the two latest edge-to-edge periods, newest first */
    uint8_t periods;    /**< how many of period[] are valid (0..2) */
    uint8_t edges;      /**< rolling edge counter: tells a new edge */
    int8_t dir;         /**< direction the count moves: +1 or -1 */
} encoder_snapshot_t;

void encoder_init(void);
/** Sets the direction later edges of `wheel` count in (+1 forwards, -1 backwards). */
void encoder_set_direction(uint8_t wheel, int8_t dir);
/** Copies the state of `wheel` with interrupts masked. */
void encoder_snapshot(uint8_t wheel, encoder_snapshot_t *out);
/** \return a counter that moves whenever the snapshot of `wheel` changes (an edge, a reversal): a reader
 *  that saw it unchanged can skip the snapshot. */
uint8_t encoder_changes(uint8_t wheel);

#endif
