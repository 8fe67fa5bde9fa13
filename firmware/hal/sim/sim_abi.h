/**
 * \file sim_abi.h
 * The contract between the firmware compiled to WebAssembly (hal/sim) and the JVM emulator: exports only, the
 * emulator hands over sensor readings and takes IR messages as data in linear memory.
 * The emulator mirrors every declaration here (emulator/.../firmware/); change both together.
 *
 * Time: the MCU clock runs at 32 MHz; `ticks` are 32 MHz clock cycles since sim_init, as int64.
 * The emulator calls sim_advance(t) with non-decreasing t; before delivering an event that happens at
 * time t (encoder edge, received byte, IR message) it first calls sim_advance(t).
 */
#ifndef SIM_ABI_H
#define SIM_ABI_H

#include <stdint.h>

#define SIM_EXPORT(name) __attribute__((export_name(#name)))

/* ---- exports: called by the emulator -------------------------------------------------------- */

/** Starts the firmware (all module inits). A non-zero robot_id overrides settings.identity.robot_id
 *  and sets the name "PocketBot-<id>" (a real robot has them in EEPROM). */
SIM_EXPORT(sim_init) void sim_init(int32_t robot_id);

/** Advances the MCU clock to `now_ticks`: fires every timer compare interrupt due, in time order, each
 *  seeing its own exact time, then runs the main loop until it has nothing left to do. */
SIM_EXPORT(sim_advance) void sim_advance(int64_t now_ticks);

/** An encoder pulse (a stripe edge) of wheel 0 (left) or 1 (right), captured at `ticks` by the timer's
 *  input capture. The encoders have one channel: the firmware signs the count by the motor direction. */
SIM_EXPORT(sim_encoder_edge) void sim_encoder_edge(int32_t wheel, int64_t ticks);

/** A byte received from the host link (USART RX complete interrupt). */
SIM_EXPORT(sim_uart_rx) void sim_uart_rx(int32_t byte);

/** An event the emulator hands over in a batch (sim_run_events), in time order. */
typedef struct __attribute__((packed)) {
    int64_t ticks; /**< when it happens */
    int32_t kind;  /**< SIM_EVENT_* */
    int32_t arg;   /**< the byte received, the wheel (0 left, 1 right), or as the kind says */
} sim_event_t;

#define SIM_EVENT_UART_RX 0
#define SIM_EVENT_ENCODER_EDGE 1
/* Host links (sim_links()): link 0 is the UART, the others further host links of the emulator. Each host the
 * emulator attaches to a robot gets a link of its own: it opens it, sends its bytes on it, and closes it when the
 * host leaves (after the host's last bytes). A fresh instance (a power cycle) starts with link 0 open only. */
#define SIM_EVENT_LINK_RX 2    /**< arg: link << 8 | byte (link 0: the UART, as SIM_EVENT_UART_RX) */
#define SIM_EVENT_LINK_OPEN 3  /**< arg: link: a host connected on it */
#define SIM_EVENT_LINK_CLOSE 4 /**< arg: link: its host left */
#define SIM_EVENT_CAPACITY 64

/** Address of the event buffer (SIM_EVENT_CAPACITY sim_event_t) that sim_run_events reads. */
SIM_EXPORT(sim_events) int32_t sim_events(void);

/** Delivers the first `count` events of the buffer in order, exactly as the single calls would: for each,
 *  sim_advance(ticks), then sim_uart_rx(arg) or sim_encoder_edge(arg, ticks); then, unless `end_ticks` is
 *  negative, sim_advance(end_ticks). One call per emulator step instead of one per event: crossing into the
 *  WebAssembly instance is the costly part of a small event. */
SIM_EXPORT(sim_run_events) void sim_run_events(int32_t count, int64_t end_ticks);

/** Takes up to `max` bytes the firmware has queued for the host link into the buffer at
 *  sim_uart_tx_buffer(); returns how many. The emulator calls it at the link's baud rate. */
SIM_EXPORT(sim_uart_tx_take) int32_t sim_uart_tx_take(int32_t max);
SIM_EXPORT(sim_uart_tx_buffer) int32_t sim_uart_tx_buffer(void);

/** How many host links the firmware serves at once (link 0 is the UART). */
SIM_EXPORT(sim_links) int32_t sim_links(void);

/** As sim_uart_tx_take, for host link `link` (0: the UART). */
SIM_EXPORT(sim_link_tx_take) int32_t sim_link_tx_take(int32_t link, int32_t max);

/** An IR message heard by receiver `side` (0 front, 1 rear). A robot hearing its own id sees an
 *  obstacle (its reflection). `len` payload bytes (0..8) are packed little-endian in lo, hi. */
SIM_EXPORT(sim_ir_rx) void sim_ir_rx(int32_t side, int32_t sender_id, int32_t sender_led, int32_t power,
                                     int32_t len, int32_t payload_lo, int32_t payload_hi);

/** Addresses in linear memory of the outputs the emulator reads after each advance (sim_outputs_t),
 *  and of the global robot_state and settings (for tests and ground-truth comparisons). */
SIM_EXPORT(sim_outputs) int32_t sim_outputs(void);
SIM_EXPORT(sim_state) int32_t sim_state(void);
SIM_EXPORT(sim_settings) int32_t sim_settings(void);

/** Address of the EEPROM (HAL_EEPROM_SIZE = 2048 bytes) in linear memory: erased (0xFF) in a fresh instance,
 *  kept by sim_init. The emulator power-cycles a robot by copying it into a fresh instance before sim_init,
 *  so saved settings survive the reset as on the robot. */
SIM_EXPORT(sim_eeprom) int32_t sim_eeprom(void);

/** What the firmware drives, little-endian in linear memory at sim_outputs(). */
typedef struct __attribute__((packed)) {
    int16_t pwm_left;      /**< motor duty, permille, -1000..1000 */
    int16_t pwm_right;
    uint8_t led;           /**< status LED bitmask */
    uint8_t line_emitters; /**< bitmask of the 5 line sensor emitters currently lit */
} sim_outputs_t;

/* ---- sensors and IR as data: the firmware imports nothing ---------------------------------------------- */

enum sim_sensor {
    SIM_SENSOR_BATTERY_MV = 0, SIM_SENSOR_CURRENT_MA = 1, SIM_SENSOR_MCU_TEMP_DC = 2,
    SIM_SENSOR_ACCEL_X_MG = 3, SIM_SENSOR_ACCEL_Y_MG = 4, SIM_SENSOR_ACCEL_Z_MG = 5,
    SIM_SENSOR_COLOUR_R = 6, SIM_SENSOR_COLOUR_G = 7, SIM_SENSOR_COLOUR_B = 8, SIM_SENSOR_COLOUR_CLEAR = 9,
    SIM_SENSOR_COUNT = 10
};

/** What the robot's sensors face during a step, little-endian in linear memory at sim_inputs(). The emulator writes
 *  it before it hands over the step's events (what changes each step) and at boot (what does not); the HAL reads
 *  it whenever the firmware converts or reads a sensor, and adds the noise itself from `noise_state`, so that a
 *  sensor read costs no call out of the instance. The HAL's readings, in the emulator's sensor model:
 *  - line sensor (hal_line_convert, lit emitters in `e`): detector d reads
 *    trunc(line_ambient_adc + sum over lit e in {d, d+1} of (line_white_adc + line_span_adc * line_dark[2d + e - d])
 *    + gauss() * line_noise_adc), within 0..4095;
 *  - sensor s (hal_sensor_read): trunc(sensor[s] + gauss() * sd(s)), sd 3 for the battery, 8 for the
 *    accelerometer, 2 for colour and none (no draw) for current and temperature; accelerometer x and y within
 *    -16000..16000, colour within 0..255;
 *  gauss() only while `noise` is set: the sum of the four 16-bit quarters of the next splitmix64 number (the
 *  generator of java.util.SplittableRandom: state += 0x9E3779B97F4A7C15, then its mix), less 131070, divided by
 *  65536 sqrt(1/3). trunc() truncates towards zero, saturating, NaN to 0 (Kotlin's Double.toInt()). */
typedef struct __attribute__((packed)) {
    uint64_t noise_state;              /**< the robot's noise generator: the emulator reads it back after the step */
    int32_t noise;                     /**< non-zero: readings are noisy (each step) */
    int32_t reserved;
    double line_ambient_adc;           /**< a detector's reading with its emitters off (at boot) */
    double line_white_adc;             /**< what a lit emitter adds over white floor (at boot) */
    double line_span_adc;              /**< and over black tape, less line_white_adc (at boot) */
    double line_noise_adc;             /**< standard deviation of a detector's noise (at boot) */
    double line_dark[8];               /**< darkness under spot j, 0 white .. 1 black, left to right (each step) */
    double sensor[SIM_SENSOR_COUNT];   /**< each sensor's true value in its unit (each step) */
} sim_inputs_t;

SIM_EXPORT(sim_inputs) int32_t sim_inputs(void);

/** An IR message the firmware sent from LED `led` (0 front, 1 right, 2 rear, 3 left) at `power` percent, `len`
 *  payload bytes (0..8) little-endian in payload_lo, payload_hi. */
typedef struct __attribute__((packed)) {
    int32_t sender_id, led, power, len, payload_lo, payload_hi;
} sim_ir_msg_t;

#define SIM_IR_OUT_CAPACITY 32

/** The IR messages sent since the emulator last emptied it (setting `count` to 0), at sim_ir_out(); the emulator
 *  delivers them (sim_ir_rx) at the step's end to every receiver in range, the sender's own receiver included when
 *  an obstacle reflects it. A message that finds the buffer full is counted in `dropped` and lost. */
typedef struct __attribute__((packed)) {
    int32_t count;
    int32_t dropped;
    sim_ir_msg_t msg[SIM_IR_OUT_CAPACITY];
} sim_ir_out_t;

SIM_EXPORT(sim_ir_out) int32_t sim_ir_out(void);

#endif
