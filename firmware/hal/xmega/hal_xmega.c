/**
 * \file hal_xmega.c
 * The HAL of the PocketBot2 board: ATxmega128A3 at 32 MHz.
 *
 * Resources:
 * - TCC0 at clk/64 (500 kHz): the scheduler's four compare channels (CCA..CCD) and hal_micros(), its
 *   16-bit count extended by the overflow interrupt.
 * - Encoders: the analog comparators ACA.AC0 (left) and AC1 (right) square the reflective sensors'
 *   signals; their output toggles reach TCD0 (clk/8, 4 MHz) through event channels 0 and 1 as input
 *   captures on CCA and CCB. The capture interrupt only extends the timestamp to 32 bits and hands it on.
 * - Motors: TCE0 single-slope PWM at 20 kHz on PE0..PE3 (left IN1/IN2, right IN1/IN2 of the H-bridges).
 * - Host link: USARTC0 (PC2 RX, PC3 TX) at 115200 Bd to the Bluetooth module, RXC and DRE interrupts; receive
 *   errors (overrun, frame error) reported through uart_rx_error_isr().
 * - Recovery: a 128 ms watchdog that the main loop resets at the end of each tick; a stray interrupt resets
 *   the MCU; hal_idle() enables interrupts and sleeps in one step.
 * - Line sensor: ADCA, detectors on PA4..PA7 converted in one sweep of channels 0..3; emitters on PA2,
 *   PB5..PB7 and PA3. Slow sensors (temperature, VCC, current; battery, accelerometer) on ADCB in two sweeps
 *   that the main loop starts and reads (no interrupts); the colour sensor (TCS3472) over TWIC, read by an
 *   interrupt-driven state machine once per integration.
 * - IR: messages as 2400 Bd UART frames of 9 bits (a byte and its line code bit) on a 38 kHz carrier (TCD1 on
 *   PD5, power = carrier duty): TX from USARTD0 with the LED chosen by PC4..PC7; front receiver on USARTD0 RX
 *   (PD2), rear on USARTD1 RX (PD6).
 * - EEPROM through the NVM controller, one page write at a time; LEDs on PF0..PF2.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/pgmspace.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <stddef.h>
#include <string.h>

#include "hal/hal.h"

#define HAL_XMEGA_INTERNAL
#include "hal/xmega/board.h"

/* ---- board ---------------------------------------------------------------------------------- */

static void clock_init(void)
{
    /* The 32 MHz RC, and the 32.768 kHz RC its DFLL trims it against (the UARTs' baud rates depend on it). */
    OSC.CTRL |= OSC_RC32MEN_bm | OSC_RC32KEN_bm;
    while (!(OSC.STATUS & OSC_RC32MRDY_bm)) {
        /* boot only: the 32 MHz oscillator starts within microseconds */
    }
    _PROTECTED_WRITE(CLK_CTRL, CLK_SCLKSEL_RC32M_gc);
    while (!(OSC.STATUS & OSC_RC32KRDY_bm)) {
        /* boot only, about a millisecond: a DFLL enabled on a reference that is not running yet mistrims */
    }
    DFLLRC32M.CTRL = DFLL_ENABLE_bm;
}

/* The watchdog resets the MCU when the main loop stops ending its ticks (hal_tick_done()) for 128 ms: a hang, or
 * an interrupt storm that starves it. A reset stops the motors' PWM with every other peripheral. */
static void watchdog_init(void)
{
    while (WDT.STATUS & WDT_SYNCBUSY_bm) {
    }
    _PROTECTED_WRITE(WDT_CTRL, WDT_PER_128CLK_gc | WDT_ENABLE_bm | WDT_CEN_bm);
    while (WDT.STATUS & WDT_SYNCBUSY_bm) {
    }
}

void hal_tick_done(void)
{
    wdt_reset();
}

/* An interrupt enabled without a handler: avr-libc would jump to 0 without a reset, leaving the PMIC's level
 * active (every interrupt at it and below blocked for good). A real reset instead. */
ISR(BADISR_vect)
{
    _PROTECTED_WRITE(RST_CTRL, RST_SWRST_bm);
}

static void sched_timer_init(void);
static void encoder_init_hw(void);
static void motors_init_hw(void);
static void uart_init_hw(void);
static void adc_init_hw(void);
static void twi_init_hw(void);
static void ir_init_hw(void);

void hal_init(void)
{
    cli();
    clock_init();
    watchdog_init();
    BOARD_LED_PORT.DIRSET = BOARD_LED_MASK;
    sched_timer_init();
    encoder_init_hw();
    motors_init_hw();
    uart_init_hw();
    adc_init_hw();
    twi_init_hw();
    ir_init_hw();
    PMIC.CTRL = PMIC_LOLVLEN_bm | PMIC_MEDLVLEN_bm | PMIC_HILVLEN_bm;
}

void hal_irq_enable(void)
{
    sei();
}

uint8_t hal_board_id(void)
{
    return 0; /* a robot keeps its id in EEPROM */
}

void hal_idle(void)
{
    SLEEP.CTRL = SLEEP_SMODE_IDLE_gc | SLEEP_SEN_bm;
    sei(); /* the instruction after SEI runs before any interrupt: an interrupt pending now wakes the SLEEP at once */
    sleep_cpu();
    SLEEP.CTRL = 0;
}

uint8_t hal_irq_save(void)
{
    uint8_t s = SREG;
    cli();
    return s;
}

void hal_irq_restore(uint8_t saved)
{
    SREG = saved;
}

void hal_led_set(uint8_t mask)
{
    BOARD_LED_PORT.OUT = (uint8_t)((BOARD_LED_PORT.OUT & ~BOARD_LED_MASK) | (mask & BOARD_LED_MASK));
}

/* ---- scheduler timer: TCC0 at 500 kHz -------------------------------------------------------- */

static volatile uint16_t sched_hi;

static void sched_timer_init(void)
{
    sched_hi = 0;
    TCC0.CTRLA = TC_CLKSEL_OFF_gc;
    TCC0.CTRLB = TC_WGMODE_NORMAL_gc;
    TCC0.PER = 0xFFFF;
    TCC0.CNT = 0;
    TCC0.INTCTRLA = TC_OVFINTLVL_HI_gc;
    TCC0.INTCTRLB = 0;
    TCC0.CTRLA = TC_CLKSEL_DIV64_gc;
}

ISR(TCC0_OVF_vect)
{
    sched_hi++;
}

static uint32_t sched_ticks(void)
{
    uint8_t s = hal_irq_save();
    uint16_t hi = sched_hi;
    uint16_t lo = TCC0.CNT;
    if ((TCC0.INTFLAGS & TC0_OVFIF_bm) && lo < 0x8000u) /* wrapped, overflow interrupt still pending */
        hi++;
    hal_irq_restore(s);
    return ((uint32_t)hi << 16) | lo;
}

uint32_t hal_micros(void)
{
    return sched_ticks() << 1;
}

/* Per channel: its compare register, interrupt flag and level field (tables: on the AVR a shift by a variable count
 * is a loop, and every scheduler interrupt re-arms a channel). */
static const struct {
    register16_t *cc;
    uint8_t flag;  /* TC0_CCxIF_bm */
    uint8_t level; /* the channel's INTCTRLB field, TC0_CCxINTLVL_gm */
} sched_ch[4] = {
    {&TCC0.CCA, TC0_CCAIF_bm, TC0_CCAINTLVL_gm},
    {&TCC0.CCB, TC0_CCBIF_bm, TC0_CCBINTLVL_gm},
    {&TCC0.CCC, TC0_CCCIF_bm, TC0_CCCINTLVL_gm},
    {&TCC0.CCD, TC0_CCDIF_bm, TC0_CCDINTLVL_gm},
};
/* The medium level in every 2-bit field (TC_CCxINTLVL_MED_gc = 2 << 2x), masked to one channel's field. */
#define SCHED_LEVEL_MED 0xAAu

void hal_sched_arm(uint8_t ch, uint32_t delay_us)
{
    if (ch >= HAL_SCHED_CHANNELS)
        return;
    /* Relative to the count now: no 32-bit time here (the absolute time it compared once wrapped at another point
     * than hal_micros()). A few ticks at least, so that the count has not passed the compare value already. */
    uint16_t ticks = delay_us < 8u ? 4u : delay_us >= 2ul * 0xFFF0u ? 0xFFF0u : (uint16_t)((delay_us + 1u) >> 1);
    uint8_t level = sched_ch[ch].level;
    uint8_t s = hal_irq_save();
    *sched_ch[ch].cc = (uint16_t)(TCC0.CNT + ticks);
    TCC0.INTFLAGS = sched_ch[ch].flag;
    TCC0.INTCTRLB = (uint8_t)((TCC0.INTCTRLB & ~level) | (level & SCHED_LEVEL_MED));
    hal_irq_restore(s);
}

void hal_sched_disarm(uint8_t ch)
{
    if (ch >= HAL_SCHED_CHANNELS)
        return;
    uint8_t s = hal_irq_save();
    TCC0.INTCTRLB = (uint8_t)(TCC0.INTCTRLB & ~sched_ch[ch].level);
    hal_irq_restore(s);
}

static inline __attribute__((always_inline)) void sched_fire(uint8_t ch)
{
    TCC0.INTCTRLB = (uint8_t)(TCC0.INTCTRLB & ~sched_ch[ch].level); /* one shot */
    scheduler_isr(ch);
}

ISR(TCC0_CCA_vect) { sched_fire(0); }
ISR(TCC0_CCB_vect) { sched_fire(1); }
ISR(TCC0_CCC_vect) { sched_fire(2); }
ISR(TCC0_CCD_vect) { sched_fire(3); }

/* ---- encoders: AC -> event system -> TCD0 input capture at 4 MHz ----------------------------- */

static volatile uint16_t capture_hi;

static void encoder_init_hw(void)
{
    capture_hi = 0;
    /* Comparators against a scaled VCC threshold, high-speed mode, the large hysteresis and the event system's
     * longest filter (8 samples, 250 ns) against stripe noise; chatter that gets through anyway is rejected by the
     * encoder driver (ENCODER_MIN_EDGE_US). */
    ACA.CTRLB = 32; /* scaler: VCC * 33/64 */
    ACA.AC0MUXCTRL = AC_MUXPOS_PIN0_gc | AC_MUXNEG_SCALER_gc;
    ACA.AC1MUXCTRL = AC_MUXPOS_PIN1_gc | AC_MUXNEG_SCALER_gc;
    ACA.AC0CTRL = AC_INTMODE_BOTHEDGES_gc | AC_HSMODE_bm | AC_HYSMODE_LARGE_gc | AC_ENABLE_bm;
    ACA.AC1CTRL = AC_INTMODE_BOTHEDGES_gc | AC_HSMODE_bm | AC_HYSMODE_LARGE_gc | AC_ENABLE_bm;
    EVSYS.CH0MUX = EVSYS_CHMUX_ACA_CH0_gc;
    EVSYS.CH1MUX = EVSYS_CHMUX_ACA_CH1_gc;
    EVSYS.CH0CTRL = EVSYS_DIGFILT_8SAMPLES_gc;
    EVSYS.CH1CTRL = EVSYS_DIGFILT_8SAMPLES_gc;
    TCD0.CTRLA = TC_CLKSEL_OFF_gc;
    TCD0.PER = 0xFFFF;
    TCD0.CTRLB = TC0_CCAEN_bm | TC0_CCBEN_bm | TC_WGMODE_NORMAL_gc;
    TCD0.CTRLD = TC_EVACT_CAPT_gc | TC_EVSEL_CH0_gc; /* CCA <- event channel 0, CCB <- channel 1 */
    TCD0.INTCTRLA = TC_OVFINTLVL_HI_gc;
    TCD0.INTCTRLB = TC_CCAINTLVL_HI_gc | TC_CCBINTLVL_HI_gc;
    TCD0.CTRLA = TC_CLKSEL_DIV8_gc;
}

ISR(TCD0_OVF_vect)
{
    capture_hi++;
}

/* The capture clock now, 32 bits: the 16-bit count and the overflows counted so far, plus one when the count has
 * wrapped but its overflow interrupt has not run yet. Called with interrupts masked, or from the HI-level capture
 * interrupts, which the (HI-level) overflow interrupt cannot preempt halfway. */
static uint32_t capture_clock(void)
{
    uint16_t lo = TCD0.CNT;
    uint16_t hi = capture_hi;
    if ((TCD0.INTFLAGS & TC0_OVFIF_bm) && lo < 0x8000u)
        hi++;
    return ((uint32_t)hi << 16) | lo;
}

uint32_t hal_capture_now(void)
{
    uint8_t s = hal_irq_save();
    uint32_t t = capture_clock();
    hal_irq_restore(s);
    return t;
}

/* A capture's time: the clock now, less how far the count has moved on since the capture (far less than a timer
 * period: its interrupt runs within microseconds). Right at every phase of the wrap, whether the overflow's
 * interrupt ran before the capture's or not (both are HI; the overflow's vector comes first). */
static uint32_t capture_time(uint16_t captured)
{
    uint32_t now = capture_clock();
    return now - (uint16_t)((uint16_t)now - captured);
}

ISR(TCD0_CCA_vect)
{
    encoder_capture_isr(0, capture_time(TCD0.CCA));
}

ISR(TCD0_CCB_vect)
{
    encoder_capture_isr(1, capture_time(TCD0.CCB));
}

/* ---- motors: TCE0 PWM at 20 kHz ------------------------------------------------------------- */

#define MOTOR_PER BOARD_MOTOR_PER

static void motors_init_hw(void)
{
    PORTE.DIRSET = 0x0F;
    TCE0.CTRLA = TC_CLKSEL_OFF_gc;
    TCE0.PER = MOTOR_PER;
    TCE0.CCA = TCE0.CCB = TCE0.CCC = TCE0.CCD = 0;
    TCE0.CTRLB = TC0_CCAEN_bm | TC0_CCBEN_bm | TC0_CCCEN_bm | TC0_CCDEN_bm | TC_WGMODE_SS_gc;
    TCE0.CTRLA = TC_CLKSEL_DIV1_gc;
}

static uint16_t duty_ticks(int16_t permille)
{
    uint16_t m = (uint16_t)(permille < 0 ? -permille : permille);
    if (m > 1000u)
        m = 1000u;
    return (uint16_t)(((uint32_t)m * MOTOR_PER) / 1000u);
}

void hal_motors_set(int16_t left, int16_t right)
{
    /* Buffered compare registers: the new duties start with the next PWM period, glitch-free. */
    TCE0.CCABUF = left > 0 ? duty_ticks(left) : 0;
    TCE0.CCBBUF = left < 0 ? duty_ticks(left) : 0;
    TCE0.CCCBUF = right > 0 ? duty_ticks(right) : 0;
    TCE0.CCDBUF = right < 0 ? duty_ticks(right) : 0;
}

/* ---- host link: USARTC0 at 115200 Bd -------------------------------------------------------- */

static void uart_init_hw(void)
{
    PORTC.DIRSET = PIN3_bm;
    PORTC.OUTSET = PIN3_bm;
    PORTC.DIRCLR = PIN2_bm;
    /* 115200 Bd from 32 MHz: BSEL 2094, BSCALE -7 (error 0.01 %) */
    USARTC0.BAUDCTRLA = (uint8_t)BOARD_HOST_BSEL;
    USARTC0.BAUDCTRLB = (uint8_t)((BOARD_HOST_BSCALE << 4) | (BOARD_HOST_BSEL >> 8));
    USARTC0.CTRLC = USART_CMODE_ASYNCHRONOUS_gc | USART_PMODE_DISABLED_gc | USART_CHSIZE_8BIT_gc;
    USARTC0.CTRLA = USART_RXCINTLVL_MED_gc;
    USARTC0.CTRLB = USART_RXEN_bm | USART_TXEN_bm;
}

void hal_uart_tx_kick(void)
{
    uint8_t s = hal_irq_save();
    USARTC0.CTRLA = (uint8_t)((USARTC0.CTRLA & ~USART_DREINTLVL_gm) | USART_DREINTLVL_MED_gc);
    hal_irq_restore(s);
}

ISR(USARTC0_RXC_vect)
{
    uint8_t status = USARTC0.STATUS; /* the errors belong to the byte in DATA: read first */
    uint8_t byte = USARTC0.DATA;
    uint8_t errors = (uint8_t)(((status & USART_BUFOVF_bm) ? HAL_UART_OVERRUN : 0u) |
                               ((status & USART_FERR_bm) ? HAL_UART_FRAME : 0u));
    if (errors)
        uart_rx_error_isr(errors);
    if (!(errors & HAL_UART_FRAME))
        uart_rx_isr(byte);
}

ISR(USARTC0_DRE_vect)
{
    int16_t b = uart_tx_isr();
    if (b < 0)
        USARTC0.CTRLA = (uint8_t)(USARTC0.CTRLA & ~USART_DREINTLVL_gm); /* nothing left: quiet */
    else
        USARTC0.DATA = (uint8_t)b;
}

/* ---- ADC: line sensor on ADCA, slow sensors on ADCB ----------------------------------------- */
/* Both convert in signed mode (the A3 errata: unsigned mode's nonlinearity is not guaranteed; single-ended inputs
 * read 0..2047), with the production signature row's calibration, at a clock slow enough for the inputs' source
 * resistance: the XMEGA A samples for half an ADC clock, 4 us at 125 kHz, where the line detectors' load
 * resistors (tens of kilohms) need about 9 time constants of the 5 pF sampling capacitor to settle (2 us). */

static uint8_t prod_signature(uint8_t offset)
{
    NVM.CMD = NVM_CMD_READ_CALIB_ROW_gc;
    uint8_t b = pgm_read_byte(offset);
    NVM.CMD = NVM_CMD_NO_OPERATION_gc;
    return b;
}

/* ADCB converts the slow inputs in two sweeps, started from the main loop when hal_sensor_read() finds the last
 * one done (no interrupts): against the 1.00 V bandgap the temperature sensor, VCC/10 and the current sense;
 * against VCC/1.6 the battery divider and the ratiometric accelerometer. A reference switched settles until the
 * next call at least SLOW_SETTLE_US later. */
#define SLOW_SETTLE_US 200u
static int16_t slow_value[HAL_SENSOR_ACCEL_Z_MG + 1]; /* in hal_sensor_read()'s units */
static uint8_t slow_sweep;        /* 0: bandgap sweep, 1: VCC/1.6 sweep */
static uint8_t slow_started;      /* the sweep is converting (else its reference settles) */
static uint32_t slow_switched_us; /* when its reference was switched */
static uint16_t vcc_mv;
static uint32_t temp_k16;         /* kelvin x 10 per count, in Q16 (from TEMPSENSE) */

static void slow_configure(uint8_t sweep)
{
    slow_sweep = sweep;
    slow_started = 0;
    slow_switched_us = hal_micros();
    if (sweep == 0) {
        ADCB.REFCTRL = ADC_REFSEL_INT1V_gc | ADC_BANDGAP_bm | ADC_TEMPREF_bm;
        ADCB.CH0.CTRL = ADC_CH_INPUTMODE_INTERNAL_gc;
        ADCB.CH0.MUXCTRL = ADC_CH_MUXINT_TEMP_gc;
        ADCB.CH1.CTRL = ADC_CH_INPUTMODE_INTERNAL_gc;
        ADCB.CH1.MUXCTRL = ADC_CH_MUXINT_SCALEDVCC_gc;
        ADCB.CH2.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
        ADCB.CH2.MUXCTRL = ADC_CH_MUXPOS_PIN1_gc; /* current sense, PB1 */
    } else {
        ADCB.REFCTRL = ADC_REFSEL_VCC_gc | ADC_BANDGAP_bm | ADC_TEMPREF_bm;
        ADCB.CH0.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
        ADCB.CH0.MUXCTRL = ADC_CH_MUXPOS_PIN0_gc; /* battery divider, PB0 */
        ADCB.CH1.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
        ADCB.CH1.MUXCTRL = ADC_CH_MUXPOS_PIN2_gc; /* accelerometer x, y, z: PB2, PB3, PB4 */
        ADCB.CH2.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
        ADCB.CH2.MUXCTRL = ADC_CH_MUXPOS_PIN3_gc;
        ADCB.CH3.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
        ADCB.CH3.MUXCTRL = ADC_CH_MUXPOS_PIN4_gc;
    }
}

static int16_t count(uint8_t ch)
{
    int16_t r = (int16_t)(&ADCB.CH0RES)[ch];
    return r < 0 ? 0 : r; /* single-ended: 0..2047 */
}

/* Main loop: takes a finished sweep's results into physical units, switches to the other sweep, starts a settled
 * one. Counts of 2048 per reference to units with multiplications and shifts only: VCC/1.6 counts are
 * vcc_mv * 5 / 16384 mV each; the accelerometer is ratiometric (its counts do not depend on VCC). */
static void slow_poll(void)
{
    if (!slow_started) {
        if ((uint32_t)(hal_micros() - slow_switched_us) < SLOW_SETTLE_US)
            return;
        ADCB.INTFLAGS = ADC_CH0IF_bm | ADC_CH1IF_bm | ADC_CH2IF_bm | ADC_CH3IF_bm;
        ADCB.CTRLA = (uint8_t)(ADC_ENABLE_bm | ADC_CH0START_bm | ADC_CH1START_bm | ADC_CH2START_bm |
                               (slow_sweep ? ADC_CH3START_bm : 0u));
        slow_started = 1;
        return;
    }
    if (!(ADCB.INTFLAGS & (slow_sweep ? ADC_CH3IF_bm : ADC_CH2IF_bm)))
        return;
    if (slow_sweep == 0) {
        slow_value[HAL_SENSOR_MCU_TEMP_DC] = (int16_t)((int32_t)(((uint32_t)count(0) * temp_k16) >> 16) - 2732);
        vcc_mv = (uint16_t)(((uint32_t)count(1) * 625u) >> 7); /* VCC/10 against 1.00 V */
        slow_value[HAL_SENSOR_CURRENT_MA] = (int16_t)(((uint32_t)count(2) * 125u) >> 8); /* BOARD: 1 mV per mA */
    } else {
        slow_value[HAL_SENSOR_BATTERY_MV] = (int16_t)(((uint32_t)count(0) * vcc_mv * 15u) >> 14); /* 1:3 divider */
        for (uint8_t a = 0; a < 3; a++) /* zero g at VCC/2 = 0.8 of VCC/1.6 */
            slow_value[HAL_SENSOR_ACCEL_X_MG + a] =
                (int16_t)((((int32_t)count((uint8_t)(1 + a)) * 10 - 16384) * BOARD_ACCEL_MG_Q10) >> 10);
    }
    slow_configure((uint8_t)(slow_sweep ^ 1u));
}

static void adc_init_hw(void)
{
    PORTA.DIRSET = BOARD_EMITTER_PA_MASK;
    PORTB.DIRSET = BOARD_EMITTER_PB_MASK;
    ADCA.CAL = (uint16_t)(prod_signature(offsetof(NVM_PROD_SIGNATURES_t, ADCACAL0)) |
                          (uint16_t)prod_signature(offsetof(NVM_PROD_SIGNATURES_t, ADCACAL1)) << 8);
    ADCB.CAL = (uint16_t)(prod_signature(offsetof(NVM_PROD_SIGNATURES_t, ADCBCAL0)) |
                          (uint16_t)prod_signature(offsetof(NVM_PROD_SIGNATURES_t, ADCBCAL1)) << 8);
    /* TEMPSENSE: the sensor's unsigned reading at 85 C (1.00 V reference), with that mode's offset of about 5 % of
     * the reference (205 counts); in signed mode the same voltage reads half as many counts. */
    uint16_t tempsense = (uint16_t)(prod_signature(offsetof(NVM_PROD_SIGNATURES_t, TEMPSENSE0)) |
                                    (uint16_t)prod_signature(offsetof(NVM_PROD_SIGNATURES_t, TEMPSENSE1)) << 8);
    temp_k16 = tempsense > 205u + 100u ? (2ul * 3581ul << 16) / (tempsense - 205u) : 0;
    vcc_mv = BOARD_VCC_MV;

    ADCA.CTRLB = ADC_CONMODE_bm | ADC_RESOLUTION_12BIT_gc;
    ADCA.REFCTRL = ADC_REFSEL_VCC_gc;
    ADCA.PRESCALER = ADC_PRESCALER_DIV256_gc; /* 125 kHz: 4 us samples, a 4-channel sweep in 80 us */
    ADCA.EVCTRL = ADC_SWEEP_0123_gc;
    ADCA.CH0.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
    ADCA.CH1.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
    ADCA.CH2.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
    ADCA.CH3.CTRL = ADC_CH_INPUTMODE_SINGLEENDED_gc;
    ADCA.CH0.MUXCTRL = ADC_CH_MUXPOS_PIN4_gc;
    ADCA.CH1.MUXCTRL = ADC_CH_MUXPOS_PIN5_gc;
    ADCA.CH2.MUXCTRL = ADC_CH_MUXPOS_PIN6_gc;
    ADCA.CH3.MUXCTRL = ADC_CH_MUXPOS_PIN7_gc;
    ADCA.CTRLA = ADC_ENABLE_bm;

    ADCB.CTRLB = ADC_CONMODE_bm | ADC_RESOLUTION_12BIT_gc;
    ADCB.PRESCALER = ADC_PRESCALER_DIV512_gc; /* 62.5 kHz: 8 us samples, a sweep in 160 us */
    ADCB.CTRLA = ADC_ENABLE_bm;
    memset(slow_value, 0, sizeof slow_value);
    slow_configure(0);
}

void hal_line_emitters(uint8_t mask)
{
    /* Emitter 0 on PA2, 1..3 on PB5..PB7, 4 on PA3. */
    PORTB.OUT = (uint8_t)((PORTB.OUT & ~BOARD_EMITTER_PB_MASK) | ((mask & 0x0Eu) << 4));
    PORTA.OUT = (uint8_t)((PORTA.OUT & ~BOARD_EMITTER_PA_MASK) | ((mask & 0x01u) << 2) | ((mask & 0x10u) >> 1));
}

void hal_line_convert(void)
{
    ADCA.CTRLA = ADC_ENABLE_bm | ADC_CH0START_bm | ADC_CH1START_bm | ADC_CH2START_bm | ADC_CH3START_bm;
}

/* A signed single-ended result 0..2047 as 12 bits. */
static inline __attribute__((always_inline)) uint16_t line_result(int16_t r)
{
    return r < 0 ? 0u : (uint16_t)(r << 1);
}

/* The sweep is done by then (hal.h: within 100 us). The four results in registers, not an array on the stack (a
 * scheduler interrupt's work three times a tick). */
void hal_line_results(uint16_t out[HAL_LINE_DETECTORS])
{
    uint8_t s = hal_irq_save(); /* the 16-bit reads share ADCA's TEMP register */
    int16_t r0 = (int16_t)ADCA.CH0.RES, r1 = (int16_t)ADCA.CH1.RES, r2 = (int16_t)ADCA.CH2.RES,
            r3 = (int16_t)ADCA.CH3.RES;
    hal_irq_restore(s);
    out[0] = line_result(r0);
    out[1] = line_result(r1);
    out[2] = line_result(r2);
    out[3] = line_result(r3);
}

static void colour_poll(void);
static volatile uint8_t colour[4]; /* clear, red, green, blue: 0..255 of the integration's full scale */
static volatile uint8_t colour_valid;

int32_t hal_sensor_read(uint8_t sensor)
{
    if (sensor >= HAL_SENSOR_COLOUR_R && sensor < HAL_SENSOR_COUNT) {
        colour_poll();
        uint8_t c = colour[(sensor - HAL_SENSOR_COLOUR_R + 1u) & 3u]; /* the sensor's order: clear, red, green, blue */
        return colour_valid ? c : -1;
    }
    slow_poll();
    return sensor < HAL_SENSOR_COLOUR_R ? slow_value[sensor] : 0;
}

/* ---- colour sensor: TCS3472 on TWIC, configured, then read once per integration -------------- */

#define TCS_ADDR BOARD_TCS3472_ADDR
#define TCS_CMD 0x80u
#define TCS_AUTOINC 0x20u
#define TCS_ENABLE 0x00u /* then ATIME at 0x01 */
#define TCS_CONTROL 0x0Fu
#define TCS_CDATAL 0x14u
#define TCS_PON_AEN 0x03u
/* One integration: (256 - ATIME) cycles of 2.4 ms, counts up to 1024 a cycle; one read per integration. */
#define TCS_CYCLES (256u - BOARD_TCS_ATIME)
#define TCS_INTEGRATION_US (TCS_CYCLES * 2400ul)
#define TCS_FULL_SCALE (TCS_CYCLES * 1024ul)
/* After a NACK or a bus error the sensor is configured again this much later (it may have been unplugged). */
#define TCS_RETRY_US 100000ul

/* The transfer in progress, one step per TWI interrupt. */
enum {
    TWI_IDLE,
    CONFIG_ENABLE, CONFIG_PON, CONFIG_ATIME, CONFIG_STOP, CONFIG_CONTROL, CONFIG_GAIN, CONFIG_DONE,
    READ_POINTER, READ_RESTART, READ_BYTES /* .. READ_BYTES + 7 */
};
static volatile uint8_t twi_step;
static uint8_t twi_buf[8];
static uint8_t tcs_configured;
static uint32_t twi_next_us;         /* when the main loop may start the next transfer */

static void twi_init_hw(void)
{
    twi_step = TWI_IDLE;
    colour_valid = 0;
    tcs_configured = 0;
    TWIC.MASTER.BAUD = 155; /* 100 kHz from 32 MHz */
    TWIC.MASTER.CTRLA = TWI_MASTER_INTLVL_LO_gc | TWI_MASTER_RIEN_bm | TWI_MASTER_WIEN_bm | TWI_MASTER_ENABLE_bm;
    TWIC.MASTER.STATUS = TWI_MASTER_BUSSTATE_IDLE_gc;
    twi_next_us = 0;
}

/* A NACK, a lost arbitration or a bus error: let go of the bus, forget the colour, configure again later. */
static void twi_fail(void)
{
    TWIC.MASTER.CTRLC = TWI_MASTER_CMD_STOP_gc;
    TWIC.MASTER.STATUS = TWI_MASTER_BUSSTATE_IDLE_gc;
    twi_step = TWI_IDLE;
    colour_valid = 0;
    tcs_configured = 0;
    twi_next_us = hal_micros() + TCS_RETRY_US;
}

/* Called from the main loop (hal_sensor_read()): starts the next transfer when it is due. */
static void colour_poll(void)
{
    uint8_t s = hal_irq_save();
    if (twi_step == TWI_IDLE && (int32_t)(hal_micros() - twi_next_us) >= 0) {
        twi_step = tcs_configured ? READ_POINTER : CONFIG_ENABLE;
        twi_next_us = hal_micros() + TCS_INTEGRATION_US;
        TWIC.MASTER.ADDR = (uint8_t)(TCS_ADDR << 1);
    }
    hal_irq_restore(s);
}

/* 16-bit counts to 0..255 of full scale. */
static uint8_t colour_byte(uint8_t lo, uint8_t hi)
{
    uint32_t v = ((uint32_t)((uint16_t)hi << 8 | lo) * 255u) / TCS_FULL_SCALE;
    return (uint8_t)(v > 255u ? 255u : v);
}

ISR(TWIC_TWIM_vect)
{
    uint8_t status = TWIC.MASTER.STATUS;
    if ((status & (TWI_MASTER_ARBLOST_bm | TWI_MASTER_BUSERR_bm)) ||
        ((status & TWI_MASTER_WIF_bm) && (status & TWI_MASTER_RXACK_bm))) {
        twi_fail();
        return;
    }
    uint8_t step = twi_step;
    switch (step) {
    case CONFIG_ENABLE: /* ENABLE := PON | AEN, ATIME (auto-increment), then CONTROL := gain */
        TWIC.MASTER.DATA = TCS_CMD | TCS_AUTOINC | TCS_ENABLE;
        break;
    case CONFIG_PON:
        TWIC.MASTER.DATA = TCS_PON_AEN;
        break;
    case CONFIG_ATIME:
        TWIC.MASTER.DATA = BOARD_TCS_ATIME;
        break;
    case CONFIG_STOP:
        TWIC.MASTER.CTRLC = TWI_MASTER_CMD_STOP_gc;
        TWIC.MASTER.ADDR = (uint8_t)(TCS_ADDR << 1); /* the next transfer starts after the STOP */
        break;
    case CONFIG_CONTROL:
        TWIC.MASTER.DATA = TCS_CMD | TCS_CONTROL;
        break;
    case CONFIG_GAIN:
        TWIC.MASTER.DATA = BOARD_TCS_AGAIN;
        break;
    case CONFIG_DONE:
        TWIC.MASTER.CTRLC = TWI_MASTER_CMD_STOP_gc;
        tcs_configured = 1;
        twi_step = TWI_IDLE; /* the first integration ends TCS_INTEGRATION_US after the warm-up: poll then */
        return;
    case READ_POINTER: /* point at CDATAL with auto-increment, then read clear, red, green, blue (8 bytes) */
        TWIC.MASTER.DATA = TCS_CMD | TCS_AUTOINC | TCS_CDATAL;
        break;
    case READ_RESTART:
        TWIC.MASTER.ADDR = (uint8_t)((TCS_ADDR << 1) | 1u);
        break;
    default: {
        uint8_t k = (uint8_t)(step - READ_BYTES);
        if (k > 7u) {
            twi_fail();
            return;
        }
        twi_buf[k] = TWIC.MASTER.DATA;
        if (k < 7u) {
            TWIC.MASTER.CTRLC = TWI_MASTER_CMD_RECVTRANS_gc;
            break;
        }
        TWIC.MASTER.CTRLC = TWI_MASTER_ACKACT_bm | TWI_MASTER_CMD_STOP_gc;
        for (uint8_t c = 0; c < 4; c++)
            colour[c] = colour_byte(twi_buf[2 * c], twi_buf[2 * c + 1]);
        colour_valid = 1;
        twi_step = TWI_IDLE;
        return;
    }
    }
    twi_step = (uint8_t)(step + 1u);
}

/* ---- IR: USARTD0 TX on a 38 kHz carrier, receivers on USARTD0 / USARTD1 RX ------------------ */

#define IR_SYNC 0xA5u
#define IR_MESSAGE_BYTES 5u /* sync, sender, LED and length, power, CRC; then the payload */
#define IR_FRAME_MAX (IR_MESSAGE_BYTES + HAL_IR_PAYLOAD_MAX)
#define IR_BAUD 2400u
#define IR_BITS_PER_BYTE 11u /* start bit, 8 data bits, the line code's bit, stop bit */
#define CARRIER_PER BOARD_IR_CARRIER_PER

/* The line code. The LEDs carry the carrier while TX is low, for the start bit and every 0 bit, so a byte with a
 * long run of 0 bits is a long burst of carrier: 0x00 alone would be 9 bits, 3.75 ms, where common IR receivers
 * take bursts up to about 70 carrier cycles (1.8 ms) before their gain control treats them as noise. Frames carry
 * 9 data bits: a byte goes out as it is (code bit 0) when its frame has no burst over 4 bits (63 cycles), else
 * rotated left by one and masked, with the code bit set, which has none either (tests/xmega checks all 256). */
#define IR_CODE_MASK 0x29u

/* True when a 9-bit frame (start bit, 9 data bits LSB first, stop bit) has no run of more than 4 zero bits. */
static bool ir_bursts_ok(uint16_t frame)
{
    uint16_t z = (uint16_t)(~((frame << 1) | 0x400u) & 0x7FFu); /* the frame's 0 bits as 1s */
    return (z & (z >> 1) & (z >> 2) & (z >> 3) & (z >> 4)) == 0;
}

static uint16_t ir_encode(uint8_t b)
{
    if (ir_bursts_ok(b))
        return b;
    return (uint16_t)(0x100u | (uint8_t)(((b << 1) | (b >> 7)) ^ IR_CODE_MASK));
}

static uint8_t ir_decode(uint16_t f)
{
    if (!(f & 0x100u))
        return (uint8_t)f;
    uint8_t r = (uint8_t)(f ^ IR_CODE_MASK);
    return (uint8_t)((r >> 1) | (r << 7));
}

static uint16_t ir_tx_buf[IR_FRAME_MAX];
/* ir_tx_len is non-zero from hal_ir_send() until the last frame's stop bit has left (its TXC). */
static volatile uint8_t ir_tx_len, ir_tx_pos;

typedef struct {
    uint8_t buf[IR_FRAME_MAX];
    uint8_t pos;
} ir_rx_t;
static ir_rx_t ir_rx[2];

/* CRC-8 (polynomial 0x07, initial 0) a nibble at a time: it runs in the transmitter's scheduler interrupt and the
 * receivers' (bit by bit it took 1000 cycles for a message). */
static const HAL_FLASH uint8_t crc8_nibble[16] = {0x00, 0x07, 0x0E, 0x09, 0x1C, 0x1B, 0x12, 0x15,
                                                  0x38, 0x3F, 0x36, 0x31, 0x24, 0x23, 0x2A, 0x2D};

static uint8_t crc8(const uint8_t *p, uint8_t n)
{
    uint8_t c = 0;
    while (n--) {
        c ^= *p++;
        c = (uint8_t)((uint8_t)(c << 4) ^ crc8_nibble[c >> 4]);
        c = (uint8_t)((uint8_t)(c << 4) ^ crc8_nibble[c >> 4]);
    }
    return c;
}

static void ir_init_hw(void)
{
    ir_tx_len = ir_tx_pos = 0;
    memset(ir_rx, 0, sizeof ir_rx);
    PORTC.DIRSET = 0xF0; /* LED selects */
    PORTD.DIRSET = PIN3_bm | PIN5_bm;
    TCD1.PER = CARRIER_PER;
    TCD1.CCB = 0;
    TCD1.CTRLB = TC1_CCBEN_bm | TC_WGMODE_SS_gc;
    TCD1.CTRLA = TC_CLKSEL_DIV1_gc;
    /* 2400 Bd: BSEL 832, BSCALE 0; 9-bit frames (the line code) */
    USARTD0.BAUDCTRLA = (uint8_t)BOARD_IR_BSEL;
    USARTD0.BAUDCTRLB = (uint8_t)(BOARD_IR_BSEL >> 8);
    USARTD1.BAUDCTRLA = (uint8_t)BOARD_IR_BSEL;
    USARTD1.BAUDCTRLB = (uint8_t)(BOARD_IR_BSEL >> 8);
    USARTD0.CTRLC = USART_CHSIZE_9BIT_gc;
    USARTD1.CTRLC = USART_CHSIZE_9BIT_gc;
    USARTD0.CTRLA = USART_RXCINTLVL_LO_gc | USART_TXCINTLVL_LO_gc;
    USARTD1.CTRLA = USART_RXCINTLVL_LO_gc;
    USARTD0.CTRLB = USART_RXEN_bm | USART_TXEN_bm;
    USARTD1.CTRLB = USART_RXEN_bm;
}

static void ir_send_frame(uint16_t f)
{
    USARTD0.CTRLB = (uint8_t)(USART_RXEN_bm | USART_TXEN_bm | ((f & 0x100u) ? USART_TXB8_bm : 0u));
    USARTD0.DATA = (uint8_t)f;
}

uint32_t hal_ir_message_us(uint8_t len)
{
    return ((uint32_t)(IR_MESSAGE_BYTES + len) * IR_BITS_PER_BYTE * 1000000ul + IR_BAUD - 1u) / IR_BAUD;
}

bool hal_ir_send(const hal_ir_msg_t *m)
{
    if (ir_tx_len)
        return false;
    uint8_t len = m->len > HAL_IR_PAYLOAD_MAX ? HAL_IR_PAYLOAD_MAX : m->len;
    uint8_t raw[IR_FRAME_MAX];
    raw[0] = IR_SYNC;
    raw[1] = m->sender_id;
    raw[2] = (uint8_t)((m->led << 4) | len);
    raw[3] = m->power;
    memcpy(raw + 4, m->data, len);
    raw[4 + len] = crc8(raw + 1, (uint8_t)(3 + len));
    for (uint8_t i = 0; i < 5 + len; i++)
        ir_tx_buf[i] = ir_encode(raw[i]);
    /* The LEDs are dark while TX idles (high): the new LED and carrier duty take effect at once, from the first
     * start bit (the duty's buffer register would wait for the carrier's next period). */
    PORTC.OUT = (uint8_t)((PORTC.OUT & 0x0F) | (0x10u << (m->led & 3u)));
    TCD1.CCB = (uint16_t)((uint32_t)CARRIER_PER / 2u * (m->power > 100u ? 100u : (uint16_t)m->power) / 100u);
    ir_tx_len = (uint8_t)(5 + len);
    ir_tx_pos = 1;
    ir_send_frame(ir_tx_buf[0]);
    return true;
}

ISR(USARTD0_TXC_vect)
{
    if (ir_tx_pos < ir_tx_len) {
        ir_send_frame(ir_tx_buf[ir_tx_pos++]);
    } else { /* the last stop bit has left: LEDs off, the transmitter is free */
        PORTC.OUTCLR = 0xF0;
        ir_tx_len = ir_tx_pos = 0;
    }
}

/* A frame heard by receiver `side`: `status` read before `data`, as the USART requires. */
static void ir_frame(uint8_t side, uint8_t status, uint8_t data)
{
    ir_rx_t *r = &ir_rx[side];
    if (status & (USART_FERR_bm | USART_BUFOVF_bm)) { /* noise, a collision or a lost frame: the message is lost */
        r->pos = 0;
        return;
    }
    uint8_t b = ir_decode((uint16_t)(((status & USART_RXB8_bm) ? 0x100u : 0u) | data));
    if (r->pos == 0 && b != IR_SYNC)
        return;
    r->buf[r->pos++] = b;
    if (r->pos < 4)
        return;
    uint8_t len = r->buf[2] & 0x0Fu;
    if (len > HAL_IR_PAYLOAD_MAX) {
        r->pos = 0;
        return;
    }
    if (r->pos < 5u + len)
        return;
    r->pos = 0;
    if (crc8(r->buf + 1, (uint8_t)(3 + len)) != r->buf[4 + len])
        return;
    hal_ir_msg_t m;
    m.sender_id = r->buf[1];
    m.led = r->buf[2] >> 4;
    m.power = r->buf[3];
    m.len = len;
    memcpy(m.data, r->buf + 4, len);
    ir_rx_isr(side, &m);
}

ISR(USARTD0_RXC_vect)
{
    uint8_t status = USARTD0.STATUS;
    ir_frame(0, status, USARTD0.DATA);
}

ISR(USARTD1_RXC_vect)
{
    uint8_t status = USARTD1.STATUS;
    ir_frame(1, status, USARTD1.DATA);
}

/* ---- EEPROM through the NVM controller ------------------------------------------------------ */

static void nvm_exec(void)
{
    _PROTECTED_WRITE(NVM_CTRLA, NVM_CMDEX_bm);
}

void hal_eeprom_read(uint16_t addr, void *dst, uint16_t len)
{
    uint8_t *d = (uint8_t *)dst;
    for (uint16_t i = 0; i < len; i++) {
        uint16_t a = (uint16_t)(addr + i);
        if (a >= HAL_EEPROM_SIZE) {
            d[i] = 0xFF;
            continue;
        }
        NVM.ADDR0 = (uint8_t)a;
        NVM.ADDR1 = (uint8_t)(a >> 8);
        NVM.ADDR2 = 0;
        NVM.CMD = NVM_CMD_READ_EEPROM_gc;
        nvm_exec();
        d[i] = NVM.DATA0;
    }
    NVM.CMD = NVM_CMD_NO_OPERATION_gc;
}

bool hal_eeprom_busy(void)
{
    return (NVM.STATUS & NVM_NVMBUSY_bm) != 0;
}

void hal_eeprom_write_page(uint16_t addr, const void *src, uint8_t len)
{
    const uint8_t *s = (const uint8_t *)src;
    if (hal_eeprom_busy() || (uint32_t)addr + len > HAL_EEPROM_SIZE)
        return;
    NVM.CMD = NVM_CMD_ERASE_EEPROM_BUFFER_gc;
    nvm_exec();
    NVM.CMD = NVM_CMD_LOAD_EEPROM_BUFFER_gc;
    for (uint8_t i = 0; i < len; i++) {
        uint16_t a = (uint16_t)(addr + i);
        NVM.ADDR0 = (uint8_t)a;
        NVM.ADDR1 = (uint8_t)(a >> 8);
        NVM.ADDR2 = 0;
        NVM.DATA0 = s[i]; /* loads the page buffer */
    }
    /* Atomic erase and write of the page; the NVM controller works on while the CPU goes on. */
    NVM.ADDR0 = (uint8_t)addr;
    NVM.ADDR1 = (uint8_t)(addr >> 8);
    NVM.ADDR2 = 0;
    NVM.CMD = NVM_CMD_ERASE_WRITE_EEPROM_PAGE_gc;
    nvm_exec();
    NVM.CMD = NVM_CMD_NO_OPERATION_gc;
}
