/**
 * \file world.h
 * A small physical world for host tests and the fuzzer: it does the emulator's part of sim_abi.h (the sensors'
 * inputs, the IR messages sent), simulates two motors with first-order dynamics and a dead
 * band, single-channel encoders with unequal stripes, a robot pose, a line on the floor, and a host link.
 */
#ifndef WORLD_H
#define WORLD_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/sim/sim_abi.h"
#include "modules/comm.h"
#include "pb_protocol.h"
#include "protocol/slip.h"

#define WORLD_MAX_IR 64
#define WORLD_MAX_FRAMES 512

typedef struct {
    /* plant */
    double v[2];          /* wheel speeds, m/s */
    double pos[2];        /* wheel distances, m */
    double next_edge[2];  /* position of the next stripe edge ahead */
    double prev_edge[2];  /* and behind */
    int edge_index[2];
    double x, y, theta;   /* pose: metres, radians (theta 0 = +x, CCW positive) */
    double max_speed;     /* wheel speed at full duty, m/s */
    double gain[2];       /* per-wheel motor strength (1.0: as max_speed says): a disturbance */
    double tau;           /* motor time constant, s */
    int deadband;         /* duties below this do not move the wheel */
    double stripe_ratio;  /* long stripe / mean stripe */
    /* floor */
    int line_enabled;     /* a black line along y = line_y (x axis) */
    double line_y, line_width;
    int ambient;          /* ambient light reading */
    int colour[4];        /* r, g, b, clear seen by the colour sensor */
    int sensors[6];       /* battery, current, temperature, accelerometer x y z (sim_inputs_t.sensor) */
    /* IR messages the robot sent */
    struct { int sender, led, power, len; uint32_t lo, hi; } ir[WORLD_MAX_IR];
    int ir_count;
    int emitter_masks_seen; /* bit m set when the line sensor's emitters in mask m (m < 32) were seen lit */
    int64_t now;
    int link_bytes_per_ms; /* how fast the host drains the link */
    int stuck_links;       /* bit k: the host of link k reads nothing (world_run_ms leaves its bytes waiting) */
} world_t;

extern world_t world;

/* Host builds of hal_sim.c: pointers instead of the int32 linear-memory addresses. */
const sim_outputs_t *sim_host_outputs(void);
const uint8_t *sim_host_tx_buffer(void);
sim_inputs_t *sim_host_inputs(void);
sim_ir_out_t *sim_host_ir_out(void);
sim_event_t *sim_host_events(void);
void sim_host_eeprom_erase(void);
/* The next main loop tick lasts `us` longer than its code (which takes no simulated time). */
void sim_host_stretch_tick_us(uint32_t us);

/** The session and label of the test's host, which drives the robot after world_reset(). */
#define WORLD_SESSION 0x7E570001u
#define WORLD_LABEL "test@host"

/** Resets the world (robot at the origin facing +x, standing still, EEPROM erased), starts the firmware and lets
 *  the test's host (link 0) take the drive (hello_request, set_role: 1 ms); what the robot said so far is collected
 *  and cleared. */
void world_reset(int32_t robot_id);
/** As world_reset(), without any host: the robot as it comes out of reset. */
void world_power_on(int32_t robot_id);
/** Runs physics and firmware for `ms` milliseconds (0.1 ms physics steps, exact encoder edge times). */
void world_run_ms(int ms);
/** Heading change in degrees since reset. */
double world_heading_deg(void);

/* ---- host link ---- */
typedef struct {
    uint8_t type, seq, len;
    uint8_t payload[PB_MAX_PAYLOAD];
} host_frame_t;

/** Sends a packet to the robot as the host would (framed, SLIP). */
void host_send(uint8_t type, uint8_t seq, const void *payload, uint8_t len);
/** Sends raw bytes on the link. */
void host_send_raw(const uint8_t *bytes, uint16_t n);
/** Collects every frame the robot sent so far (appends to host_frames). */
void host_collect(void);
extern host_frame_t host_frames[WORLD_MAX_FRAMES];
extern int host_frame_count;
extern int host_bad_frames;
/** Forgets collected frames. */
void host_clear(void);
/** \return the n-th (0-based) collected frame of `type`, or NULL. */
const host_frame_t *host_find(uint8_t type, int n);
/** \return how many collected frames have `type`. */
int host_count(uint8_t type);
/** A host's handshake on link 0: hello_request with `session`, then set_role (PB_HOST_ROLE_*) under `label`. */
void host_handshake(uint32_t session, uint8_t role, const char *label);

/* ---- more hosts: the emulator's further links (1 .. COMM_LINKS-1), collected apart from link 0's ---- */
#define WORLD_LINK_FRAMES 128
typedef struct {
    host_frame_t frames[WORLD_LINK_FRAMES];
    int count;
    int bad;
    slip_decoder_t rx;
} link_host_t;
extern link_host_t link_hosts[COMM_LINKS];

void link_open(int link);
void link_close(int link);
void link_send(int link, uint8_t type, uint8_t seq, const void *payload, uint8_t len);
void link_send_raw(int link, const uint8_t *bytes, uint16_t n);
/** hello_request and set_role on `link`. */
void link_handshake(int link, uint32_t session, uint8_t role, const char *label);
/** Collects what the robot sent on `link` (also done by world_run_ms at the link rate). */
void link_collect(int link);
void link_clear(int link);
const host_frame_t *link_find(int link, uint8_t type, int n);
int link_count(int link, uint8_t type);

#endif
