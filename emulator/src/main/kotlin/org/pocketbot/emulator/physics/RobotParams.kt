package org.pocketbot.emulator.physics

import kotlin.math.PI

/**
 * The physical PocketBot2: geometry, motors, encoders and sensors. SI units (m, s, kg, N, V).
 * The defaults are the real robot's (thesis ch. 10-11) where known, and plausible values elsewhere.
 */
public class RobotParams(
    public val lengthM: Double = 0.048,
    public val widthM: Double = 0.032,
    public val massKg: Double = 0.020,
    public val wheelDiameterM: Double = 0.009,
    public val wheelBaseM: Double = 0.026,
    /** Encoder edges per wheel revolution: 20 black + 20 white stripes, one edge per stripe boundary. */
    public val pulsesPerRev: Int = 40,
    /** Share of a black+white stripe pair that is black; the black stripes are narrower (thesis 11.5). */
    public val blackStripeShare: Double = 0.42,
    /** No-load wheel speed at PWM 1000 and 3.7 V. */
    public val noLoadSpeedMps: Double = 0.6,
    public val nominalBatteryV: Double = 3.7,
    /** First-order time constant of the wheel speed (motor, gearbox and robot inertia together). */
    public val motorTauS: Double = 0.030,
    /** Force one wheel pushes with when stalled at PWM 1000 and nominal voltage. */
    public val stallForcePerWheelN: Double = 0.08,
    /** Line sensor spots: eight across the front, this far ahead of the axle, with this pitch. */
    public val lineSensorAheadM: Double = 0.020,
    public val lineSpotPitchM: Double = 0.0025,
    public val lineSpotRadiusM: Double = 0.0012,
    /** ADC counts a lit emitter adds over black tape (over white: [lineSignalWhiteAdc]). */
    public val lineSignalBlackAdc: Double = 1900.0,
    public val lineSignalWhiteAdc: Double = 110.0,
    public val lineNoiseAdc: Double = 6.0,
    public val colourSensorAheadM: Double = 0.012,
    public val colourSpotRadiusM: Double = 0.0025,
    /** IR: range at 100 % power along an LED's axis, the LED half angle, and the receivers' half angle. */
    public val irRangeM: Double = 0.150,
    public val irLedHalfAngleDeg: Double = 15.0,
    public val irReceiverHalfAngleDeg: Double = 90.0,
    /** Battery: full and empty open-circuit voltage, capacity and internal resistance. */
    public val batteryFullV: Double = 4.1,
    public val batteryEmptyV: Double = 3.4,
    public val batteryCapacityMah: Double = 150.0,
    public val batteryInternalOhm: Double = 0.4,
    public val idleCurrentMa: Double = 35.0,
    public val motorStallCurrentMa: Double = 250.0,
) {
    public val wheelPerimeterM: Double get() = PI * wheelDiameterM
    /** Length of one black + white stripe pair on the wheel's perimeter. */
    public val stripePairM: Double get() = wheelPerimeterM * 2 / pulsesPerRev
}
