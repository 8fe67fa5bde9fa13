package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.sdk.internal.EMPTY_STATE

/**
 * The line sensor: 4 detectors x 5 emitters = 8 spots with ambient light suppression. Updated by full and reduced
 * state packets (reduced ones carry position and flags only; `raw` then keeps its last full value).
 */
public class LineSensor internal constructor() {
    private val _reading = MutableStateFlow(EMPTY_STATE.line)

    /** The last reading: `raw` per spot (adc), `position` -1000 far left .. 1000 far right (permille), `flags`. */
    public val reading: StateFlow<RobotState.Line> = _reading.asStateFlow()

    /** Line position in permille, -1000 far left .. 1000 far right. */
    public val positionPermille: Int get() = _reading.value.position

    /** True while a spot sees the line. */
    public val lineSeen: Boolean get() = LineFlag.SEEN in _reading.value.flags

    /** True after the line was lost for longer than settings.line_follow.lost_timeout_ms. */
    public val lineLost: Boolean get() = LineFlag.LOST in _reading.value.flags

    internal fun update(line: RobotState.Line) {
        _reading.value = line
    }
}

/** The colour sensor under the robot (full state only). */
public class ColourSensor internal constructor() {
    private val _reading = MutableStateFlow(EMPTY_STATE.colour)

    /** Red, green, blue and clear channels (0..255) and the classified colour code. */
    public val reading: StateFlow<RobotState.Colour> = _reading.asStateFlow()

    /** The classified surface colour, [Colour.UNKNOWN] for a code this SDK does not know. */
    public val detected: Colour get() = _reading.value.detected

    internal fun update(c: RobotState.Colour) {
        _reading.value = c
    }
}

/** The accelerometer (full state only): x forward, y left, z up, in mg. */
public class Accelerometer internal constructor() {
    private val _reading = MutableStateFlow(EMPTY_STATE.accel)

    /** The last acceleration, in mg (1 g = 1000 mg). */
    public val reading: StateFlow<RobotState.Accel> = _reading.asStateFlow()

    internal fun update(a: RobotState.Accel) {
        _reading.value = a
    }
}

/** Battery and MCU (full state only). */
public class Power internal constructor() {
    private val _reading = MutableStateFlow(EMPTY_STATE.power)

    /** Battery voltage (mV), current drawn (mA) and MCU temperature (0.1 degC). */
    public val reading: StateFlow<RobotState.Power> = _reading.asStateFlow()

    /** Battery voltage in volts. */
    public val batteryV: Double get() = _reading.value.batteryMv / 1000.0

    internal fun update(p: RobotState.Power) {
        _reading.value = p
    }
}

/** Measured wheel speeds (full and reduced state) and motor PWM (full state). */
public class Motors internal constructor() {
    private val _wheels = MutableStateFlow(EMPTY_STATE.wheels)

    /** Wheel speeds (mm/s) and motor duty (permille, -1000..1000). */
    public val wheels: StateFlow<RobotState.Wheels> = _wheels.asStateFlow()

    /** Left wheel speed in m/s. */
    public val leftMps: Double get() = _wheels.value.speedLeftMmps / 1000.0

    /** Right wheel speed in m/s. */
    public val rightMps: Double get() = _wheels.value.speedRightMmps / 1000.0

    internal fun update(w: RobotState.Wheels) {
        _wheels.value = w
    }
}
