/**
 * \file board.h
 * Pin and clock facts of the PocketBot2 board, private to hal/xmega. Everything else includes hal/hal.h.
 */
#ifndef HAL_XMEGA_INTERNAL
#error "hal/xmega/board.h is private to the xmega HAL; include hal/hal.h instead"
#endif
#ifndef BOARD_H
#define BOARD_H

#define BOARD_F_CPU 32000000ul

#define BOARD_LED_PORT PORTF
#define BOARD_LED_MASK 0x07u              /* PF0..PF2 */

#define BOARD_MOTOR_TIMER TCE0            /* PE0..PE3: left IN1/IN2, right IN1/IN2 */
#define BOARD_MOTOR_PER 1600u             /* 32 MHz / 20 kHz PWM */

#define BOARD_HOST_USART USARTC0          /* PC2 RX, PC3 TX to the Bluetooth module */
#define BOARD_HOST_BSEL 2094u             /* 115200 Bd with BSCALE -7 */
#define BOARD_HOST_BSCALE 0x9u

/* Line sensor: detectors on PA4..PA7 (ADCA); emitters 0 on PA2, 1..3 on PB5..PB7, 4 on PA3. PB4 is the
 * accelerometer's z input (ADCB), so no emitter there: to be checked against the schematic at bring-up. */
#define BOARD_EMITTER_PA_MASK 0x0Cu       /* PA2, PA3 */
#define BOARD_EMITTER_PB_MASK 0xE0u       /* PB5..PB7 */

/* Slow analog inputs on ADCB: battery through a 1:3 divider on PB0, current sense (1 mV per mA) on PB1, a
 * ratiometric analog accelerometer on PB2..PB4 (zero g at VCC/2, 100 mV per g at 3.3 V: 99.3 counts of VCC/1.6
 * per g, so mg = (counts * 10 - 16384) * BOARD_ACCEL_MG_Q10 / 1024). VCC until ADCB has measured it. */
#define BOARD_ACCEL_MG_Q10 1031
#define BOARD_VCC_MV 3300u

#define BOARD_IR_SELECT_PORT PORTC        /* IR LED selects on PC4..PC7: front, right, rear, left */
#define BOARD_IR_CARRIER_PER 842u         /* 32 MHz / 38 kHz */
#define BOARD_IR_BSEL 832u                /* 2400 Bd */

#define BOARD_TCS3472_ADDR 0x29u          /* colour sensor on TWIC */
/* Its integration: ATIME 0xFC = 4 cycles of 2.4 ms (9.6 ms, full scale 4096 counts: 7 mm of travel at the line
 * follower's 0.7 m/s); gain 16x (AGAIN 2). Both to be tuned on the bench to the floor and the sensor's LED. */
#define BOARD_TCS_ATIME 0xFCu
#define BOARD_TCS_AGAIN 0x02u

#endif
