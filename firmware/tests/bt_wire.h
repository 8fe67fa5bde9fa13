/**
 * \file bt_wire.h
 * The controller's side of the H4 wire for the Bluetooth stack's tests (tests/test_bt_*.c, fuzz_bt.c), which
 * link the stack below comm (bluetooth/ without bt.c) with this file: a HAL for the UART driver and the EEPROM,
 * packets fed to the robot as the controller sends them, the robot's packets taken back and parsed, and the
 * stack's upward hooks recorded (what comm would receive). `bt_tests --live PORT` instead runs the stack against a
 * controller reached as H4 over TCP, echoing what each data channel receives (tests/bt_e2e.py drives it).
 */
#ifndef BT_WIRE_H
#define BT_WIRE_H

#include <stdbool.h>
#include <stdint.h>

/* ---- the robot: stack, clock ---- */

/** Erases the EEPROM, resets every counter and the stack (hci_init ...). */
void wire_reset(void);
/** Runs the stack's tasks for `ms` milliseconds of robot time (one pass per ms), and on until the bytes fed are
 *  read (a stalled packet stops that after H4_PACKET_TIMEOUT_MS). */
void wire_run_ms(int ms);
/** Bytes the UART sends (into the collected packets) per ms of wire_run_ms(); 0 (after wire_reset()): none, the
 *  test collects with wire_collect(). 12 is the 115200 Bd wire. */
extern int wire_uart_bytes_per_ms;

/* ---- controller to robot ---- */

/** Bytes as they arrive on the robot's UART. */
void wire_feed(const uint8_t *p, uint16_t n);
/** An event with its parameters. */
void wire_event(uint8_t code, const uint8_t *params, uint8_t n);
/** Command Complete for `opcode` with status 0 and `ret` return parameters after it. */
void wire_command_complete(uint16_t opcode, const uint8_t *ret, uint8_t n);
/** An ACL packet (`pb` 2: first fragment, 1: continuation) on `handle`. */
void wire_acl(uint16_t handle, uint8_t pb, const uint8_t *p, uint16_t n);
/** A whole L2CAP PDU on `handle`, channel `cid`, in one ACL packet. */
void wire_l2cap(uint16_t handle, uint16_t cid, const uint8_t *p, uint16_t n);

/* ---- robot to controller ---- */

/** One H4 packet the robot sent. */
typedef struct {
    uint8_t type;
    uint16_t opcode;   /* commands */
    uint16_t handle;   /* ACL: handle and flags (pb in bits 12..13) */
    uint16_t len;      /* parameter or payload bytes */
    uint8_t data[300];
} wire_packet_t;

/** Takes what the robot sent into a list of packets (appended); \return how many are listed. */
int wire_collect(void);
extern wire_packet_t wire_out[256];
extern int wire_out_count;
/** Forgets the packets collected. */
void wire_clear(void);
/** \return the n-th command sent with `opcode`, or NULL. */
const wire_packet_t *wire_find_command(uint16_t opcode, int n);
/** Reassembles the L2CAP PDUs the robot sent on `handle` to channel `cid`: the n-th one's payload (NULL if
 *  none); `len` set. */
const uint8_t *wire_find_l2cap(uint16_t handle, uint16_t cid, int n, uint16_t *len);

/** Answers every command the robot sent so far with success (and the return parameters of an initialisation
 *  that a Bumble controller gives: ACL buffers of `acl_mtu` bytes, `acl_count` of them). */
void wire_answer_commands(uint16_t acl_mtu, uint16_t acl_count);
/** Resets and initialises the stack to ready (a controller at 0A:0B:0C:0D:0E:0F). */
void wire_bring_up(uint16_t acl_mtu, uint16_t acl_count);
/** A peer at `addr` connects (connection request, accepted, complete) on `handle`. */
void wire_connect(const uint8_t addr[6], uint16_t handle);

/** Opens an L2CAP channel to `psm` from the peer's channel `scid` on `handle` (connection and configuration both
 *  ways, the peer's MTU `mtu`). \return the robot's channel id, 0 if it refused. */
uint16_t wire_open_l2cap(uint16_t handle, uint16_t psm, uint16_t scid, uint16_t mtu);
/** An RFCOMM frame from the peer (the initiator) on the channel `cid`: address from `dlci` (C/R as a command,
 *  or as a response when `response`), `ctrl`, information, credits when `credits` > 0 (UIH with P/F). */
void wire_rfcomm(uint16_t handle, uint16_t cid, uint8_t dlci, uint8_t ctrl, const uint8_t *info, uint8_t n,
                 int credits);
/** Opens RFCOMM from the peer: L2CAP channel (peer cid 0x0050), SABM on DLCI 0, PN with credit-based flow control
 *  (`credits` initial credits, N1 `n1`), SABM on DLCI 2. \return the robot's L2CAP channel id. */
uint16_t wire_open_rfcomm(uint16_t handle, uint8_t credits, uint16_t n1);
/** The RFCOMM frames the robot sent on the peer's channel 0x0050 of `handle`: the n-th one (NULL if none). */
const uint8_t *wire_find_rfcomm(uint16_t handle, int n, uint16_t *len);
/** TS 07.10's FCS of `n` bytes. */
uint8_t wire_fcs(const uint8_t *p, int n);

/* ---- the stack's upward hooks, recorded ---- */
typedef struct {
    int stream_opened[2], stream_closed[2], stream_lost[2];
    int framed_opened[2], framed_closed[2], framed_lost[2];
    uint8_t stream_rx[2][512];
    int stream_rx_len[2];
    uint8_t framed_rx[2][256];
    int framed_rx_len[2], framed_sdus[2];
} wire_up_t;
extern wire_up_t wire_up;
/** Echo what the data channels receive (as --live does) instead of recording it. */
extern bool wire_echo;

#endif
