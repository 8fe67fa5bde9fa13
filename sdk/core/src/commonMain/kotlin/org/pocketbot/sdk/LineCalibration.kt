package org.pocketbot.sdk

import kotlinx.coroutines.CoroutineStart
import kotlinx.coroutines.NonCancellable
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.filter
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext
import kotlinx.coroutines.withTimeoutOrNull
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * A calibration of the eight line sensor spots: each spot's ambient-suppressed reading over the white floor
 * ([white], settings.line_sensor.cal_min) and over black tape ([black], settings.line_sensor.cal_max), in ADC counts.
 * The firmware maps a reading `raw` of spot `i` to a darkness of `(raw - white[i]) / (black[i] - white[i])`, clamped to
 * 0..1000 permille, and sees the line where that darkness exceeds settings.line_sensor.threshold.
 */
public class LineCalibration(public val white: List<Int>, public val black: List<Int>) {
    init {
        require(white.size == SPOTS && black.size == SPOTS) { "a calibration has $SPOTS white and $SPOTS black readings" }
        require((white + black).all { it in 0..MAX_ADC }) { "readings are 0..$MAX_ADC ADC counts: white $white, black $black" }
    }

    /** Black minus white reading per spot, in ADC counts: how clearly the spot tells the line from the floor. */
    public val contrast: List<Int> get() = List(SPOTS) { black[it] - white[it] }

    /**
     * The spots (0 = leftmost) whose black reading is not at least [MIN_CONTRAST] above their white one: they never
     * saw both the floor and the line, and calibrating them failed.
     */
    public val weakSpots: List<Int> get() = (0 until SPOTS).filter { contrast[it] < MIN_CONTRAST }

    /** True when every spot saw both white and black clearly: the calibration is worth writing to the robot. */
    public val isUsable: Boolean get() = weakSpots.isEmpty()

    /** The darkness of reading [raw] at [spot] with this calibration, 0 (white) .. 1000 (black), as the firmware computes it. */
    public fun darknessPermille(spot: Int, raw: Int): Int {
        val lo = white[spot]
        val hi = black[spot]
        return when {
            raw <= lo -> 0
            raw >= hi -> 1000
            else -> ((raw - lo).toLong() * 1000 / (hi - lo)).toInt()
        }
    }

    override fun equals(other: Any?): Boolean = other is LineCalibration && white == other.white && black == other.black
    override fun hashCode(): Int = white.hashCode() * 31 + black.hashCode()
    override fun toString(): String = "LineCalibration(white=$white, black=$black)"

    public companion object {
        /** Spots of the line sensor. */
        public const val SPOTS: Int = 8

        /** The largest reading of the 12-bit ADC. */
        public const val MAX_ADC: Int = 4095

        /** The least black-minus-white contrast of a usable spot, in ADC counts (the robot reads about 1900). */
        public const val MIN_CONTRAST: Int = 200

        /** The calibration [robot] runs with now (its settings as it confirmed them). */
        public fun of(robot: Robot): LineCalibration =
            LineCalibration(robot.settings.lineSensor.calMin.value, robot.settings.lineSensor.calMax.value)
    }
}

/**
 * Calibrates a robot's line sensor, in one of two ways:
 *
 * - [sweep]: the robot turns in place, left and right over the line it stands on, so every spot passes over the line
 *   and the floor (as Pololu's line sensors calibrate), and each spot's lowest and highest reading are its white and
 *   black;
 * - by hand: the user puts the robot on white and calls [sample], then on black (every spot on the tape, e.g. the
 *   robot across the line) and calls [sample] again; `LineCalibration(white, black)` is the result.
 *
 * Then [apply] writes the result (each setting acknowledged by the robot) and [save] keeps it in the robot's EEPROM.
 * Raw spot readings come only with full state packets: while it measures, the calibrator asks for full state every
 * [SAMPLE_PERIOD] and gives the robot its sync mode back afterwards.
 *
 * ```
 * val calibrator = LineCalibrator(robot)
 * val calibration = calibrator.sweep()              // the robot must stand on a line
 * if (calibration.isUsable) { calibrator.apply(calibration); calibrator.save() }
 * ```
 */
public class LineCalibrator(private val robot: Robot) {
    private val _progress = MutableStateFlow<SweepProgress?>(null)

    /** The sweep running now: the readings so far and how far it got; null while none runs. */
    public val progress: StateFlow<SweepProgress?> = _progress.asStateFlow()

    /**
     * Turns the robot in place [passes] times by [angleDeg] to the left of the heading it started with, as far to the
     * right, and back, its wheels at [speedMps], and returns each spot's lowest (white) and highest (black) reading on
     * the way. Each turn aims at a heading measured by odometry from where the sweep began, so the robot ends facing as
     * it started (within about 2 degrees) however much a turn overshot. The robot must stand on the line, roughly
     * along it. [progress] shows the readings as they come.
     *
     * @throws RobotException when a turn did not finish (stopped, cut by the link failsafe): the result would miss
     *   part of the sweep.
     */
    public suspend fun sweep(angleDeg: Double = 40.0, speedMps: Double = 0.03, passes: Int = 2): LineCalibration {
        require(angleDeg > 0 && angleDeg <= 90) { "angleDeg must be in (0, 90], was $angleDeg" }
        require(passes >= 1) { "passes must be at least 1" }
        val targets = List(passes) { listOf(angleDeg, -angleDeg, 0.0) }.flatten()
        val low = IntArray(LineCalibration.SPOTS) { Int.MAX_VALUE }
        val high = IntArray(LineCalibration.SPOTS) { Int.MIN_VALUE }
        var done = 0
        fun publish() {
            _progress.value = SweepProgress(
                done.toDouble() / targets.size,
                low.map { it.coerceAtMost(LineCalibration.MAX_ADC) },
                high.map { it.coerceAtLeast(0) },
            )
        }
        publish()
        try {
            withFullState {
                coroutineScope {
                    // Undispatched: the collector listens before the robot moves.
                    val collector = launch(start = CoroutineStart.UNDISPATCHED) {
                        robot.stateUpdates.collect { update ->
                            if (update.kind != StateUpdate.Kind.FULL) return@collect
                            update.state.line.raw.forEachIndexed { i, raw ->
                                if (raw < low[i]) low[i] = raw
                                if (raw > high[i]) high[i] = raw
                            }
                            publish()
                        }
                    }
                    val startDeg = standStill().headingRad * DEG_PER_RAD
                    for (target in targets) {
                        turnTo(startDeg + target, speedMps)
                        done++
                        publish()
                    }
                    turnTo(startDeg, speedMps) // what the last turn overshot
                    collector.cancel()
                }
            }
        } finally {
            _progress.value = null
        }
        if (low.any { it == Int.MAX_VALUE }) throw RobotException("the robot sent no line sensor readings during the sweep")
        return LineCalibration(low.toList(), high.toList())
    }

    /** Turns in place to [headingDeg] (odometry), unless the robot already faces within [TURN_TOLERANCE_DEG] of it. */
    private suspend fun turnTo(headingDeg: Double, speedMps: Double) {
        val error = wrapAngle(headingDeg / DEG_PER_RAD - standStill().headingRad) * DEG_PER_RAD
        if (kotlin.math.abs(error) < TURN_TOLERANCE_DEG) return
        val result = robot.locomotion.enqueue(Movement.Rotate(error, speedMps)).await()
        if (result.outcome != MovementOutcome.FINISHED) throw RobotException("the calibration sweep was interrupted: $result")
    }

    /** Waits for a full state in which both wheels stand still, and returns the odometry pose of then. */
    private suspend fun standStill(): Pose {
        robot.stateUpdates.first { it.kind == StateUpdate.Kind.FULL && it.state.wheels.speedLeftMmps == 0 && it.state.wheels.speedRightMmps == 0 }
        return robot.odometry.pose.value
    }

    /**
     * The mean reading of every spot over [duration] while the robot stands still: call it with the robot on white,
     * then on black, for a calibration by hand.
     */
    public suspend fun sample(duration: Duration = 500.milliseconds): List<Int> {
        val sums = LongArray(LineCalibration.SPOTS)
        var count = 0
        fun add(update: StateUpdate) {
            update.state.line.raw.forEachIndexed { i, raw -> sums[i] += raw.toLong() }
            count++
        }
        withFullState {
            val fullStates = robot.stateUpdates.filter { it.kind == StateUpdate.Kind.FULL }
            withTimeoutOrNull(duration) { fullStates.collect { add(it) } }
            if (count == 0) add(fullStates.first()) // at least one reading, however short the duration
        }
        return sums.map { (it / count).toInt() }
    }

    /**
     * Writes [calibration] to the robot: settings.line_sensor.cal_min, then cal_max, each acknowledged. Suspends until
     * both are; the robot uses the new values at once (they last until a reset unless [save]d).
     *
     * @throws IllegalArgumentException when the calibration is not usable (see [LineCalibration.weakSpots]).
     * @throws SettingRefusedException when the robot refuses a value; nothing is changed on the robot then (a
     *   refused cal_max puts the old cal_min back).
     */
    public suspend fun apply(calibration: LineCalibration) {
        require(calibration.isUsable) { "spots ${calibration.weakSpots} saw no contrast between white and black: not written" }
        val before = LineCalibration.of(robot)
        val sensor = robot.settings.lineSensor
        sensor.calMin.set(calibration.white)
        try {
            sensor.calMax.set(calibration.black)
        } catch (e: SettingRefusedException) {
            sensor.calMin.set(before.white)
            throw e
        }
    }

    /** Saves the robot's settings, the calibration among them, to its EEPROM so it survives a reset. */
    public suspend fun save() {
        robot.settings.save()
    }

    private suspend fun <T> withFullState(block: suspend () -> T): T {
        val mode = robot.reflector.mode.value
        val period = robot.reflector.period.value
        robot.reflector.set(SyncMode.FULL, SAMPLE_PERIOD)
        try {
            return block()
        } finally {
            withContext(NonCancellable) { robot.reflector.set(mode, period) }
        }
    }

    /**
     * How far a [sweep] got: the share of its turns done ([fraction], 0..1) and each spot's lowest ([white]) and
     * highest ([black]) reading so far.
     */
    public class SweepProgress internal constructor(
        public val fraction: Double,
        public val white: List<Int>,
        public val black: List<Int>,
    ) {
        override fun toString(): String = "SweepProgress(${(fraction * 100).toInt()} %, white=$white, black=$black)"
    }

    public companion object {
        /**
         * The period of full state while calibrating: a full state frame takes about 8 ms on a 115200-baud link, so
         * 20 ms leaves room for commands and acknowledgements while the robot turns about 3 degrees between readings.
         */
        public val SAMPLE_PERIOD: Duration = 20.milliseconds

        private const val DEG_PER_RAD = 180.0 / kotlin.math.PI
        private const val TURN_TOLERANCE_DEG = 1.5
    }
}
