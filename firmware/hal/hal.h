/**
 * \file hal.h
 * The hardware abstraction layer: the only interface between the portable firmware and a target.
 * Two implementations exist: hal/xmega (the ATxmega128A3 of a PocketBot2) and hal/sim (WebAssembly inside
 * the emulator, see hal/sim/sim_abi.h). Host unit tests and the cycle bench supply their own fakes.
 *
 * Callbacks named `*_isr` are implemented above the HAL and called by it from interrupt context: they only
 * capture and flag. Everything else is called from the main loop.
 */
#ifndef HAL_H
#define HAL_H

#include <stdbool.h>
#include <stdint.h>

/** Qualifier of constant tables and strings kept in program memory. */
#ifdef __AVR__
#define HAL_FLASH __flash
#else
#define HAL_FLASH
#endif

/** Keeps a large function out of its callers on targets that need it: under the emulator each WebAssembly
 *  function becomes one JVM method, and HotSpot never compiles a method over 8000 bytecode bytes. */
#ifdef __wasm__
#define HAL_NOINLINE_SIM __attribute__((noinline))
#else
#define HAL_NOINLINE_SIM
#endif

/* ---- board ---------------------------------------------------------------------------------- */

/** Initializes clocks, pins and every peripheral; interrupts stay disabled until hal_irq_enable(). */
void hal_init(void);
/** Enables interrupts globally. */
void hal_irq_enable(void);

/** \return a robot id imposed by the board (the emulator), or 0 to use settings.identity.robot_id. */
uint8_t hal_board_id(void);

/** Sleeps until the next interrupt (sleep mode idle). Call it with interrupts masked (hal_irq_save()) after
 *  finding nothing to do: it enables them and sleeps in one step, so an interrupt that came after the check wakes
 *  it at once instead of being slept through. Returns with interrupts enabled; at once where there is nothing to
 *  wait for. */
void hal_idle(void);

/** Called at the end of every main loop tick, before the scheduler measures how long it took. The robot's HAL
 *  resets its watchdog here (a main loop that stops ending ticks resets the MCU); the emulator's (HAL_SIM) lets a
 *  test make a tick last (code takes no simulated time there: sim_host_stretch_tick_us()). */
void hal_tick_done(void);

/** Masks interrupts; \return the previous state for hal_irq_restore(). */
uint8_t hal_irq_save(void);
void hal_irq_restore(uint8_t saved);

/* ---- time and the scheduler timer ----------------------------------------------------------- */

/** Free-running microsecond clock (wraps after 71 minutes; compare with signed differences). */
uint32_t hal_micros(void);

/** Number of compare channels of the scheduler timer. */
#define HAL_SCHED_CHANNELS 4u
/** Longest delay hal_sched_arm() accepts from now; the scheduler re-arms for longer ones. */
#define HAL_SCHED_MAX_DELAY_US 60000ul

/** Arms compare channel `ch` to call scheduler_isr(ch) once, `delay_us` from now (at most
 *  HAL_SCHED_MAX_DELAY_US; 0: as soon as possible). Relative, so that the HAL needs no time of its own. */
void hal_sched_arm(uint8_t ch, uint32_t delay_us);
void hal_sched_disarm(uint8_t ch);
/** Compare interrupt of channel `ch`. */
void scheduler_isr(uint8_t ch);

/* ---- encoders: input capture ---------------------------------------------------------------- */

/** Rate of the capture timestamps. */
#define HAL_CAPTURE_HZ 4000000ul
/** The capture timer now, in the units of encoder_capture_isr() timestamps (wraps after 17 minutes). */
uint32_t hal_capture_now(void);
/** Input capture of an encoder edge of `wheel` (0 left, 1 right) at `timestamp`. */
void encoder_capture_isr(uint8_t wheel, uint32_t timestamp);

/* ---- motors --------------------------------------------------------------------------------- */

/** Sets the motor duties in permille, -1000..1000 (negative: backwards). */
void hal_motors_set(int16_t left, int16_t right);

/* ---- host link (USART) ---------------------------------------------------------------------- */

/** Tells the transmitter that bytes wait (enables the data register empty interrupt). */
void hal_uart_tx_kick(void);
/** A received byte. */
void uart_rx_isr(uint8_t byte);
/** What the USART saw wrong before the byte it delivers next (or instead of it): */
#define HAL_UART_OVERRUN 0x01u /**< bytes were lost: the receiver's buffer was full (the next byte is delivered) */
#define HAL_UART_FRAME 0x02u   /**< a byte with a bad stop bit (noise, another baud rate, a break): not delivered */
/** Receive errors (HAL_UART_* bits), from the receive interrupt, just before uart_rx_isr() of the next byte. */
void uart_rx_error_isr(uint8_t errors);
/** \return the next byte to transmit, or -1 when none is queued. */
int16_t uart_tx_isr(void);

/* ---- line sensor ---------------------------------------------------------------------------- */

#define HAL_LINE_DETECTORS 4u
#define HAL_LINE_EMITTERS 5u
/** Lights the emitters in `mask` (bit e = emitter e). */
void hal_line_emitters(uint8_t mask);
/** Starts a conversion of the four detectors; results are ready for hal_line_results() within 100 us. */
void hal_line_convert(void);
/** Copies the last conversion results (12-bit) of the four detectors. */
void hal_line_results(uint16_t out[HAL_LINE_DETECTORS]);

/* ---- slow sensors --------------------------------------------------------------------------- */

enum hal_sensor {
    HAL_SENSOR_BATTERY_MV = 0, HAL_SENSOR_CURRENT_MA, HAL_SENSOR_MCU_TEMP_DC,
    HAL_SENSOR_ACCEL_X_MG, HAL_SENSOR_ACCEL_Y_MG, HAL_SENSOR_ACCEL_Z_MG,
    HAL_SENSOR_COLOUR_R, HAL_SENSOR_COLOUR_G, HAL_SENSOR_COLOUR_B, HAL_SENSOR_COLOUR_CLEAR,
    HAL_SENSOR_COUNT
};
/** \return the latest value of a sensor in its physical unit (never blocks: conversions run in the
 *  background); colour channels 0..255 of full scale, or -1 while the colour sensor gives no reading (it does not
 *  answer). */
int32_t hal_sensor_read(uint8_t sensor);

/* ---- IR proximity --------------------------------------------------------------------------- */

#define HAL_IR_PAYLOAD_MAX 8u
/** \return how long the transmitter is busy with a message of `len` payload bytes (us): hal_ir_send() refuses
 *  another one until then. On the robot, its frames on the IR link (5 + len bytes of 11 bits at 2400 Bd: 23 ms
 *  without payload); in the emulator, whose IR link delivers a message without airtime, 1 ms. */
uint32_t hal_ir_message_us(uint8_t len);
/** One IR message: who sent it, from which LED, at what power, with an optional payload. */
typedef struct {
    uint8_t sender_id;
    uint8_t led;     /**< 0 front, 1 right, 2 rear, 3 left */
    uint8_t power;   /**< percent */
    uint8_t len;     /**< payload bytes, 0..8 */
    uint8_t data[HAL_IR_PAYLOAD_MAX];
} hal_ir_msg_t;
/** Starts sending `msg`. \return false when the transmitter is still busy with the previous one. */
bool hal_ir_send(const hal_ir_msg_t *msg);
/** A message heard by receiver `side` (0 front, 1 rear). */
void ir_rx_isr(uint8_t side, const hal_ir_msg_t *msg);

/* ---- LEDs ----------------------------------------------------------------------------------- */

void hal_led_set(uint8_t mask);

/* ---- EEPROM --------------------------------------------------------------------------------- */

#define HAL_EEPROM_SIZE 2048u
#define HAL_EEPROM_PAGE 32u
void hal_eeprom_read(uint16_t addr, void *dst, uint16_t len);
/** \return true while a page write is in progress. */
bool hal_eeprom_busy(void);
/** Starts writing `len` bytes that lie within one page; returns at once. */
void hal_eeprom_write_page(uint16_t addr, const void *src, uint8_t len);

#endif
