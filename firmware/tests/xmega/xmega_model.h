/**
 * \file xmega_model.h
 * A host model of the ATxmega128A3 peripherals that hal/xmega uses, for testing the robot's HAL without a robot.
 *
 * What it is: the register file (I/O memory 0x0000..0x0FFF, laid out by avr-libc's device header) in host memory;
 * hal/xmega/hal_xmega.c, compiled on the host against it (hal_xmega_host.cc), reads and writes it through
 * xm_read8()/xm_write8(), which act as the hardware would: strobe registers, flags that reading or writing clears,
 * the 16-bit TEMP register, protected registers behind CCP. Simulated time (CPU cycles at 32 MHz) advances by a
 * couple of cycles per register access, while the CPU sleeps, and when a test says the CPU is busy; code between
 * register accesses takes no time. Peripherals act at their own times, and the interrupt controller calls the real
 * ISRs (functions __vector_N) by level and, within a level, by vector number.
 *
 * Modelled: the CPU's SREG I flag, SEI's one-instruction delay and SLEEP; CCP; the PMIC (levels, priority within
 * a level, nesting, a vector without a handler jumping to 0 as avr-libc's does); OSC/CLK/DFLL (start-up times,
 * the order of enabling); WDT and RST (resets); TC0/TC1 (counting from the prescaled clock, compare, overflow,
 * capture from the event system with its two-level buffer, flags, levels, TEMP, buffered compare registers);
 * the analog comparators' outputs through event channels with the digital filter; USART (baud from BSEL/BSCALE,
 * 5..9-bit frames, DRE, TXC, RXC, the two-level receive FIFO, buffer overflow and frame errors); ADC (prescaled
 * clock, pipelined conversions, signed and unsigned modes, references, internal inputs, the calibration register,
 * sampling through the source resistance, free running and sweeps); the TWI master and a TCS3472 colour sensor on
 * it; the NVM controller's EEPROM commands and the production signature row; ports (strobes, pin uses).
 *
 * Not modelled (what only a robot on the bench can tell): analog front ends (comparator hysteresis and noise,
 * detector and emitter settling, IR receivers' burst limits and AGC), oscillator accuracy and drift, the clock
 * prescaler's phase, DMA, the event system beyond AC -> TC capture, PMIC round robin, flash contents, power.
 * Instruction timing: only register accesses take time (XM_READ_CYCLES, XM_WRITE_CYCLES); interrupt entry takes
 * none. What the model does not know is reported as a misuse (xm_misuse_count()).
 */
#ifndef XMEGA_MODEL_H
#define XMEGA_MODEL_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define XM_IO_SIZE 0x1000u
#define XM_HZ 32000000ull
#define XM_US(us) ((uint64_t)(us) * (XM_HZ / 1000000u))
#define XM_MS(ms) ((uint64_t)(ms) * (XM_HZ / 1000u))
/** CPU cycles a register read (LDS) and write (STS) take; code between accesses takes none. */
#define XM_READ_CYCLES 2u
#define XM_WRITE_CYCLES 1u
#define XM_VECTORS 122u

extern uint8_t xm_io[XM_IO_SIZE];

/* ---- what the register types and the instruction shims of include/avr call ---- */
uint8_t xm_read8(uint16_t addr);
void xm_write8(uint16_t addr, uint8_t v);
void xm_sei(void);
void xm_cli(void);
void xm_sleep(void);
void xm_wdr(void);
uint8_t xm_lpm(uint16_t addr);

/* ---- power, time and the CPU ---- */

/** Everything to its power-on state: registers, peripherals, stimuli, counters; time 0. */
void xm_power_on(void);
/** Simulated time: CPU cycles since power-on. */
uint64_t xm_now(void);
/** A SLEEP returns without an interrupt when time reaches `t` (so a test's main loop can stop there). */
void xm_set_horizon(uint64_t t);
/** The CPU runs code without register accesses for `cycles`: interrupts are served as they come, or (masked)
 *  wait until it ends, as in a critical section. */
void xm_busy(uint64_t cycles, bool masked);
/** Runs `fn` (once) right after the program's next write to `addr`, before any interrupt is served: a test's way
 *  to make something happen at an exact point of the program (fn may let time pass with xm_busy()). */
void xm_after_write(uint16_t addr, void (*fn)(void));
/** Lets time pass quickly: only the timers' overflow interrupts are served meanwhile (the others stay pending,
 *  as behind a long critical section) and the watchdog is held. For uptime tests that skip hours. */
void xm_fast_forward(uint64_t cycles);

/** What ended a run of the firmware: a reset (registers to their reset state) or avr-libc's jump to 0 from a
 *  vector without a handler (no reset: registers keep their state and the PMIC its active level). */
enum { XM_RESTART_NONE = 0, XM_RESTART_WATCHDOG, XM_RESTART_SOFTWARE, XM_RESTART_JUMP_TO_0 };
/** Called when the CPU restarts (from inside the code that caused it); NULL: the model only counts it. */
void xm_on_restart(void (*fn)(uint8_t why));
uint32_t xm_restarts(uint8_t why);
/** When the CPU last restarted (cycles). */
uint64_t xm_last_restart_at(void);

/* ---- interrupts ---- */
/** Interrupts served per vector since power-on or xm_irq_clear_counts(). */
uint32_t xm_irq_count(uint8_t vector);
/** The most interrupts of `vector` served within one millisecond (aligned to whole milliseconds of time). */
uint32_t xm_irq_max_per_ms(uint8_t vector);
void xm_irq_clear_counts(void);
/** Interrupts that found no handler (served by __vector_default if the program has one). */
uint32_t xm_stray_count(void);

/* ---- mistakes the model saw the program make (protected write without CCP, DATA written while DRE is clear,
 *      a TWI command on a busy bus, sleeping with interrupts masked, ...) ---- */
uint32_t xm_misuse_count(void);
const char *xm_misuse_last(void);

/* ---- clocks ---- */
/** True when DFLLRC32M was enabled while its 32.768 kHz reference was not yet ready. */
bool xm_dfll_enabled_early(void);
/** The system clock source (CLK.CTRL SCLKSEL) in effect. */
uint8_t xm_sysclk(void);

/* ---- timers and the encoders' comparators ---- */
/** The time its count next becomes `count` (from the last count boundary on) for the timer at `base` (0x0900:
 *  TCD0), or XM_NEVER when it is stopped. */
uint64_t xm_tc_next_count_time(uint16_t base, uint16_t count);
/** The share of time (percent) compare output `ch` of the timer at `base` is high: 0 when the timer or its output is
 *  off (single-slope PWM only). TCE0 (0x0A00) drives the motors. */
double xm_tc_duty(uint16_t base, uint8_t ch);
/** The output of analog comparator ACA.AC0 (`ac` 0) or AC1 toggles at `at` (an encoder stripe edge). */
void xm_ac_toggle(uint8_t ac, uint64_t at);

/* ---- USART ---- */
enum { XM_USARTC0 = 0, XM_USARTD0, XM_USARTD1, XM_USARTS };
/** A frame on a USART's TX pin: start and end (cycles), data (9 bits), and what the board showed meanwhile
 *  (for USARTD0, the IR transmitter: xm_ir_state() at the start and the end of the frame). */
typedef struct {
    uint64_t start, end;
    uint16_t data;
    uint8_t bits;        /**< data bits (5..9) */
    uint32_t aux_start, aux_end;
} xm_frame_t;
uint32_t xm_usart_tx_count(uint8_t u);
const xm_frame_t *xm_usart_tx_frame(uint8_t u, uint32_t i);
/** Takes up to `max` transmitted bytes not taken yet (a byte sink: the host, or a Bluetooth controller). */
uint32_t xm_usart_take(uint8_t u, uint8_t *dst, uint32_t max);
/** A frame arriving on a USART's RX pin, its stop bit ending at `at`; `frame_error`: a bad stop bit. */
void xm_usart_rx_at(uint8_t u, uint16_t data, uint64_t at, bool frame_error);
/** Bytes sent to the MCU back to back as 8N1 frames at `baud`, the first starting at `start` or, if later, after
 *  the frames queued before it (a byte source). \return when the last stop bit ends */
uint64_t xm_usart_send(uint8_t u, const uint8_t *bytes, uint32_t n, uint32_t baud, uint64_t start);
/** Every frame USART `from` transmits also arrives at USART `to`'s RX as it ends (IR reflected by an obstacle). */
void xm_usart_echo(uint8_t from, uint8_t to, bool on);
/** The duration of one bit at the USART's configured baud rate, in cycles (0 when the baud is not set). */
double xm_usart_bit_cycles(uint8_t u);

/** The IR transmitter as the board wires it (hal/xmega/board.h): carrier from TCD1's CCB output on PD5, gated by
 *  USARTD0's TX, through the LEDs selected on PC4..PC7. bits 0..3: LEDs selected; bits 8..15: carrier duty in
 *  percent of a full 50 % square wave (0 when the carrier timer or its pin is off). */
uint32_t xm_ir_state(void);
#define XM_IR_LEDS(state) ((state) & 0x0Fu)
#define XM_IR_DUTY(state) (((state) >> 8) & 0xFFu)

/* ---- analog inputs and the ADC ---- */
/** The voltage on pin `pin` of port 'A' or 'B' and the resistance of what drives it. */
void xm_analog_set(char port, uint8_t pin, double volts, double source_ohm);
void xm_vcc_set(double volts);
void xm_temperature_set(double celsius);
/** The sampling capacitor of the ADC's input stage (the model: 5 pF). */
#define XM_ADC_SAMPLE_PF 5.0
/** Calibration values in the model's production signature row: ADCA, ADCB (CAL register) and TEMPSENSE (the
 *  unsigned 12-bit ADCA reading of the temperature sensor at 85 C, 1.00 V reference). */
#define XM_ADCA_CAL 0x0444u
#define XM_ADCB_CAL 0x0555u
#define XM_TEMPSENSE 0x0A10u

/* ---- TWI: the TCS3472 colour sensor at 0x29 ---- */
/** Light on the sensor: counts per 2.4 ms integration cycle at gain 1x, per channel (clear, red, green, blue). */
void xm_tcs_light(uint16_t clear, uint16_t red, uint16_t green, uint16_t blue);
/** Whether the sensor answers its address (false: unplugged: every transfer is NACKed, and its registers are lost). */
void xm_tcs_present(bool present);
uint8_t xm_tcs_reg(uint8_t reg);
/** Bus transactions to the sensor: register writes and reads in order. */
typedef struct {
    uint64_t at;
    bool write;
    uint8_t reg, value;
} xm_tcs_access_t;
uint32_t xm_tcs_log_count(void);
const xm_tcs_access_t *xm_tcs_log(uint32_t i);
void xm_tcs_log_clear(void);
/** TWI interrupts are counted by vector; this counts bus transactions (START ... STOP) to the sensor. */
uint32_t xm_tcs_transactions(void);

/* ---- NVM ---- */
uint8_t *xm_eeprom(void);
/** Cycles an EEPROM page erase and write keeps the NVM busy (the model: 6 ms). */
#define XM_EEPROM_WRITE_CYCLES XM_MS(6)

/* ---- ports: who uses which pin ---- */
enum {
    XM_USE_GPIO_OUT = 1u << 0, XM_USE_ANALOG_IN = 1u << 1, XM_USE_USART_RX = 1u << 2, XM_USE_USART_TX = 1u << 3,
    XM_USE_TWI = 1u << 4, XM_USE_TC_OUT = 1u << 5, XM_USE_AREF = 1u << 6
};
/** What pin `pin` of port 'A'..'F' has been used for since power-on (XM_USE_* bits, gathered over time: an ADC
 *  input counts when a conversion samples it, an output when the program drives the pin). */
uint8_t xm_pin_uses(char port, uint8_t pin);
/** A readable name for the uses, for failure messages. */
const char *xm_pin_use_names(uint8_t uses);
/** The level an input pin reads (outputs read what they drive). */
void xm_pin_set(char port, uint8_t pin, bool high);
bool xm_pin_level(char port, uint8_t pin);

#ifdef __cplusplus
}
#endif

#endif
